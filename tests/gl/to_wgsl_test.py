"""Unit tests of shaders/to_wgsl.py, the rewrite of the include's macro dialect to WGSL: each construct the
body uses, translated exactly, and the constructs outside the subset refused with the line named. (Whether
the result is valid WGSL is checked by Chromium's WebGPU in tests/gl/test_shader_wgsl.cpp.)
Run: python3 -m unittest discover -s tests/gl -p 'to_wgsl_test.py'   (ctest: shader_to_wgsl)
"""
import os
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'shaders'))
import to_wgsl  # noqa: E402

MACROS = '#define SPECAA_FLOAT2 vec2<f32>\n#define SPECAA_FLOAT3 vec3<f32>\n#define SPECAA_SELECT(c, a, b) select(b, a, c)\n'


def wgsl(source, defines=()):
    return to_wgsl.translate([MACROS, source], defines).strip()


class Declarations(unittest.TestCase):
    def test_function_signature_and_return_type(self):
        self.assertEqual(wgsl('float f(SPECAA_FLOAT2 a, float b) { return a.x * b; }'),
                         'fn f(a: vec2<f32>, b: f32) -> f32 { return a.x * b; }')

    def test_void_function_has_no_arrow(self):
        self.assertEqual(wgsl('void g(float x) { }'), 'fn g(x: f32) { }')

    def test_let_for_constants_var_for_assigned_locals(self):
        self.assertEqual(wgsl('float f(float x) {\n    float a = x;\n    float b = 1.0;\n    b += a;\n    return b;\n}'),
                         'fn f(x: f32) -> f32 {\n    let a: f32 = x;\n    var b: f32 = 1.0;\n    b += a;\n    return b;\n}')

    def test_a_component_assignment_makes_a_var(self):
        self.assertIn('var v: vec3<f32> = x;', wgsl('SPECAA_FLOAT3 f(SPECAA_FLOAT3 x) { SPECAA_FLOAT3 v = x; v.y = 0.0; return v; }'))

    def test_several_declarators_become_several_declarations_on_the_same_indent(self):
        self.assertEqual(wgsl('float f(float x) {\n    float a = x, b = 2.0 * x;\n    return a + b;\n}'),
                         'fn f(x: f32) -> f32 {\n    let a: f32 = x;\n    let b: f32 = 2.0 * x;\n    return a + b;\n}')

    def test_conversions_and_scalar_type_names(self):
        self.assertEqual(wgsl('float f(int n) { uint u = uint(n); return float(n - 1) + float(u); }'),
                         'fn f(n: i32) -> f32 { let u: u32 = u32(n); return f32(n - 1) + f32(u); }')

    def test_comments_are_kept_and_not_rewritten(self):
        self.assertEqual(wgsl('// a float in a comment\nfloat f(float x) { return x; }  // int stays'),
                         '// a float in a comment\nfn f(x: f32) -> f32 { return x; } // int stays')

    def test_struct_fields(self):
        self.assertEqual(wgsl('struct S {\n    float r;  // roughness\n    SPECAA_FLOAT2 uv;\n};'),
                         'struct S {\n    r: f32, // roughness\n    uv: vec2<f32>,\n}')

    def test_struct_parameters_and_locals(self):
        self.assertEqual(wgsl('struct S { float r; };\nfloat f(S s) { S t = s; return t.r; }'),
                         'struct S { r: f32, }\nfn f(s: S) -> f32 { let t: S = s; return t.r; }')


class Statements(unittest.TestCase):
    def test_ternary_initializer_return_and_assignment_become_select(self):
        out = wgsl('float f(float x) {\n    float a = x > 0.0 ? x : -x;\n    float b = 0.0;\n'
                   '    b = a < 1.0 ? 1.0 : a;\n    return b > 2.0 ? 2.0 : b;\n}')
        self.assertIn('let a: f32 = select(-x, x, x > 0.0);', out)
        self.assertIn('b = select(a, 1.0, a < 1.0);', out)
        self.assertIn('return select(b, 2.0, b > 2.0);', out)

    def test_ternary_with_parentheses_and_a_nested_false_branch(self):
        self.assertIn('select(select(3.0, 2.0, x < 2.0), (x + 1.0) * 2.0, (x < 1.0 || x > 5.0))',
                      wgsl('float f(float x) { return (x < 1.0 || x > 5.0) ? (x + 1.0) * 2.0 : x < 2.0 ? 2.0 : 3.0; }'))

    def test_ternary_inside_a_larger_expression_is_refused(self):
        with self.assertRaisesRegex(to_wgsl.TranslateError, r'line 1: a \?: inside a larger expression'):
            wgsl('float f(float x) { return 1.0 + (x > 0.0 ? x : 0.0); }')

    def test_if_without_braces_gets_braces(self):
        self.assertEqual(wgsl('float f(float x) { if (x < 0.0) return 0.0; return x; }'),
                         'fn f(x: f32) -> f32 { if (x < 0.0) { return 0.0; } return x; }')

    def test_else_branches(self):
        self.assertEqual(wgsl('float f(float x) { float y = 0.0; if (x < 0.0) y = 1.0; else y = 2.0; return y; }'),
                         'fn f(x: f32) -> f32 { var y: f32 = 0.0; if (x < 0.0) { y = 1.0; } else { y = 2.0; } return y; }')

    def test_for_loop_with_prefix_increment_and_break(self):
        self.assertEqual(wgsl('float f(int n) { float s = 0.0; for (int j = 0; j < 32; ++j) { if (j >= n) break; s += 1.0; } return s; }'),
                         'fn f(n: i32) -> f32 { var s: f32 = 0.0; for (var j: i32 = 0; j < 32; j++) '
                         '{ if (j >= n) { break; } s += 1.0; } return s; }')

    def test_assignment_to_a_parameter_is_refused(self):
        with self.assertRaisesRegex(to_wgsl.TranslateError, r'line 1: assignment to the parameter x'):
            wgsl('float f(float x) { x *= 2.0; return x; }')

    def test_out_parameters_become_pointers_and_their_arguments_references(self):
        out = wgsl('bool g(float x, out SPECAA_FLOAT2 r) { r = SPECAA_FLOAT2(x, x); r.y = 0.0; return r.x > 0.0; }\n'
                   'float f(float x) { SPECAA_FLOAT2 v; bool ok = g(x, v); return v.x; }')
        self.assertIn('fn g(x: f32, r: ptr<function, vec2<f32>>) -> bool { (*r) = vec2<f32>(x, x); (*r).y = 0.0; return (*r).x > 0.0; }', out)
        self.assertIn('var v: vec2<f32>; let ok: bool = g(x, &v);', out)

    def test_inout_is_refused(self):
        with self.assertRaisesRegex(to_wgsl.TranslateError, 'inout'):
            wgsl('void g(inout float x) { }')


class SecondConfiguration(unittest.TestCase):
    SOURCE = ('float texel(float x) { return x; }\n'
              '#if defined(TEX)\nfloat baked(float x) { return texel(TEX); }\n#else\nfloat baked(float x) { return 0.0; }\n#endif\n'
              'float total(float x) { return baked(x) + x; }\n'
              'float unrelated(float x) { return 2.0 * x; }\n')

    def test_differing_functions_and_their_callers_are_renamed_and_take_the_texture(self):
        base = wgsl(self.SOURCE)
        variant = wgsl(self.SOURCE, ['TEX=tex'])
        out = to_wgsl.variant_functions(base, variant, [('tex', 'texture_2d<f32>'), ('smp', 'sampler')], '_t', '// header\n')
        self.assertEqual(out, '// header\n'
                              '\n// baked with the baked texture.\n'
                              'fn baked_t(x: f32, tex: texture_2d<f32>, smp: sampler) -> f32 { return texel(tex); }\n'
                              '\n// total with the baked texture.\n'
                              'fn total_t(x: f32, tex: texture_2d<f32>, smp: sampler) -> f32 { return baked_t(x, tex, smp) + x; }\n')


class Preprocessing(unittest.TestCase):
    def test_macros_and_defines_select_the_configuration(self):
        source = '#if defined(USE_B)\nfloat f(float x) { return SPECAA_SELECT(x > 0.0, x, 0.0); }\n#else\nfloat f(float x) { return x; }\n#endif\n'
        self.assertEqual(wgsl(source), 'fn f(x: f32) -> f32 { return x; }')
        self.assertEqual(wgsl(source, ['USE_B']), 'fn f(x: f32) -> f32 { return select(0.0, x, x > 0.0); }')

    def test_an_unknown_top_level_construct_is_refused(self):
        with self.assertRaisesRegex(to_wgsl.TranslateError, 'unsupported top-level construct'):
            wgsl('float x = 1.0;')

    def test_the_shipped_include_is_the_translation_of_the_body(self):
        root = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..')
        def read(p):
            with open(os.path.join(root, p), encoding="utf-8") as f:
                return f.read()
        macros = ''.join(l for l in read('shaders/src/macros_wgsl.inc').splitlines(True) if not l.lstrip().startswith('//'))
        body = to_wgsl.translate([macros, read('shaders/src/specaa_body.inc')])
        shipped = read('shaders/specaa.wgsl')
        self.assertTrue(shipped.startswith(read('shaders/src/prologue_wgsl.inc') + body))
        self.assertIn('fn specaa_default_D_kernel(h: vec3<f32>, filteredA: vec3<f32>, s: SpecaaSurface, '
                      'kernelTexture: texture_2d<f32>, kernelSampler: sampler) -> f32 {', shipped)
        for line in body.splitlines():
            self.assertFalse(line.lstrip().startswith('#'), line)
            self.assertNotRegex(line.split('//')[0], r'\b(float|int|uint|SPECAA_FLOAT\d|SPECAA_DD[XY])\b', line)


if __name__ == '__main__':
    unittest.main()
