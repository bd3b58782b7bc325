#!/usr/bin/env python3
"""Translates the include's shared body (shaders/src/, written in the SPECAA_* macro dialect) to WGSL.

WGSL has no preprocessor, so the body is first run through the C preprocessor (`cpp`, GCC's) with the
WGSL macro set (shaders/src/macros_wgsl.inc) and the configuration's defines, which resolves every
#if and expands SPECAA_FLOAT3 to vec3<f32>, SPECAA_DDX to dpdx, ...; comments are kept. What is left is
C-like declarations around WGSL expressions, which this script rewrites statement by statement:

  float f(SPECAA_FLOAT3 a, out SPECAA_FLOAT4 b) {
                                     ->  fn f(a: vec3<f32>, b: ptr<function, vec4<f32>>) -> f32 {
  float x = e1, y = e2;              ->  let x: f32 = e1; var y: f32 = e2;  (var where assigned later)
  return c ? a : b;                  ->  return select(b, a, c);  (only a whole initializer, return value
                                         or right-hand side; select evaluates both sides)
  if (c) stmt;                       ->  if (c) { stmt; }
  for (int j = 0; j < n; ++j)        ->  for (var j: i32 = 0; j < n; j++)
  struct S { float a; };             ->  struct S { a: f32, }
  b = v; (b an out parameter)        ->  (*b) = v;   and f(x, y) -> f(x, &y) at the call sites
  float(x), int(x), uint(x)          ->  f32(x), i32(x), u32(x)

Anything else (a ternary inside a larger expression, an assignment to a parameter, an unknown top-level
construct) stops with an error naming the line: the body must stay in the subset this translates.

A second configuration can follow in the same module (WGSL has no overloads): the body translated again
with more defines, each function that differs from the first translation (or calls one that does) renamed
with a suffix, and the names the configuration binds (a texture, its sampler) made trailing parameters of
every function that uses them or calls one that does (--variant-*, --texture-parameter).

Usage: to_wgsl.py [-D NAME[=VALUE]]... [--macros MACROS_FILE] [--variant-suffix S --variant-define NAME[=VALUE]...
         --texture-parameter NAME=TYPE... --variant-header COMMENT_FILE] FILE...
  The files are concatenated (the macro file without its // comment lines), then translated; WGSL on stdout.
"""
import re
import subprocess
import sys

TYPE_WORDS = {'float': 'f32', 'int': 'i32', 'uint': 'u32'}
SCALAR_TYPES = {'f32', 'i32', 'u32', 'bool'}
ASSIGN_OPS = {'=', '+=', '-=', '*=', '/='}

_TOKEN = re.compile(r'''
    (?P<comment>//[^\n]*|/\*.*?\*/)
  | (?P<space>[ \t\r\n]+)
  | (?P<number>0[xX][0-9a-fA-F]+[uUiI]?|(?:\d+\.\d*|\.\d+|\d+)(?:[eE][+-]?\d+)?[uUfFiIhH]?)
  | (?P<ident>[A-Za-z_]\w*)
  | (?P<punct>&&|\|\||==|!=|<=|>=|\+=|-=|\*=|/=|\+\+|--|->|[-+*/%<>=!&|^~?:;,.(){}\[\]])
''', re.VERBOSE | re.DOTALL)


class TranslateError(Exception):
    pass


class Tok:
    __slots__ = ('kind', 'text', 'line')

    def __init__(self, kind, text, line):
        self.kind, self.text, self.line = kind, text, line

    @property
    def code(self):
        return self.kind not in ('comment', 'space')


def tokenize(text):
    out, pos, line = [], 0, 1
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if not m:
            raise TranslateError(f'line {line}: unexpected character {text[pos]!r}')
        kind = m.lastgroup
        word = m.group()
        if kind == 'ident' and word in TYPE_WORDS:
            word = TYPE_WORDS[word]
        out.append(Tok(kind, word, line))
        line += word.count('\n')
        pos = m.end()
    return out


def text_of(toks):
    return ''.join(t.text for t in toks)


def next_code(toks, i):
    while i < len(toks) and not toks[i].code:
        i += 1
    return i


def matching(toks, i, open_, close):
    """Index of the token closing the bracket at toks[i]."""
    depth = 0
    for j in range(i, len(toks)):
        if toks[j].text == open_:
            depth += 1
        elif toks[j].text == close:
            depth -= 1
            if depth == 0:
                return j
    raise TranslateError(f'line {toks[i].line}: unbalanced {open_!r}')


def split_top(toks, sep):
    """Splits a token list at `sep` tokens outside brackets."""
    parts, depth, start = [], 0, 0
    for j, t in enumerate(toks):
        if t.text in '([{':
            depth += 1
        elif t.text in ')]}':
            depth -= 1
        elif t.text == sep and depth == 0:
            parts.append(toks[start:j])
            start = j + 1
    parts.append(toks[start:])
    return parts


def strip(toks):
    a, b = 0, len(toks)
    while a < b and not toks[a].code:
        a += 1
    while b > a and not toks[b - 1].code:
        b -= 1
    return toks[:a], toks[a:b], toks[b:]


def is_type_start(toks, i, structs):
    t = toks[i]
    return t.kind == 'ident' and (t.text in SCALAR_TYPES or t.text in structs or
                                  re.fullmatch(r'vec[234]', t.text) is not None)


def read_type(toks, i):
    """A type at toks[i] (f32, vec3<f32>, texture_2d<f32>, SpecaaSurface): (type text, next index)."""
    j = i + 1
    k = next_code(toks, j)
    if k < len(toks) and toks[k].text == '<':
        end = matching(toks, k, '<', '>')
        return text_of([t for t in toks[i:end + 1] if t.code]), end + 1
    return toks[i].text, j


class Translator:
    def __init__(self):
        self.structs = set()
        self.out_params = {}  # function name -> indices of its out parameters

    # ----- expressions -----------------------------------------------------------------------------

    def expression(self, toks, derefs):
        """Rewrites an expression: out parameters dereferenced, & added for out arguments, the ternary."""
        toks = self.ternary(toks)
        result = []
        i = 0
        while i < len(toks):
            t = toks[i]
            prev = next((p for p in reversed(result) if p.code), None)
            after_dot = prev is not None and prev.text == '.'
            if t.kind == 'ident' and t.text in derefs and not after_dot:
                result.append(Tok('ident', f'(*{t.text})', t.line))
                i += 1
                continue
            if t.kind == 'ident' and t.text in self.out_params and not after_dot:
                k = next_code(toks, i + 1)
                if k < len(toks) and toks[k].text == '(':
                    end = matching(toks, k, '(', ')')
                    args = split_top(toks[k + 1:end], ',')
                    rewritten = []
                    for n, arg in enumerate(args):
                        arg_toks = self.expression(arg, derefs)
                        if n in self.out_params[t.text]:
                            lead, core, trail = strip(arg_toks)
                            if len(core) != 1 or core[0].kind != 'ident':
                                raise TranslateError(f'line {t.line}: the out argument of {t.text} must be a variable')
                            arg_toks = lead + [Tok('punct', '&', t.line)] + core + trail
                        rewritten.append(text_of(arg_toks))
                    result.append(Tok('expr', t.text + '(' + ','.join(rewritten) + ')', t.line))
                    i = end + 1
                    continue
            if t.text == '?':
                raise TranslateError(f'line {t.line}: a ?: inside a larger expression (only a whole initializer, '
                                     'return value or right-hand side becomes select)')
            result.append(t)
            i += 1
        return result

    def ternary(self, toks):
        depth, q = 0, None
        for j, t in enumerate(toks):
            if t.text in '([{':
                depth += 1
            elif t.text in ')]}':
                depth -= 1
            elif t.text == '?' and depth == 0:
                q = j
                break
        if q is None:
            return toks
        depth, nested, colon = 0, 0, None
        for j in range(q + 1, len(toks)):
            t = toks[j]
            if t.text in '([{':
                depth += 1
            elif t.text in ')]}':
                depth -= 1
            elif depth == 0 and t.text == '?':
                nested += 1
            elif depth == 0 and t.text == ':':
                if nested == 0:
                    colon = j
                    break
                nested -= 1
        if colon is None:
            raise TranslateError(f'line {toks[q].line}: ?: without its :')
        lead, cond, _ = strip(toks[:q])
        when_true = text_of(self.ternary(strip(toks[q + 1:colon])[1]))
        _, when_false, trail = strip(toks[colon + 1:])
        when_false = text_of(self.ternary(when_false))
        # select(value if false, value if true, condition)
        return lead + [Tok('expr', f'select({when_false}, {when_true}, {text_of(cond)})', toks[q].line)] + trail

    # ----- statements ------------------------------------------------------------------------------

    def assigned_names(self, toks):
        """Names assigned anywhere in a function body (name, name.x, name[i] before = or +=, ++, --)."""
        code = [t for t in toks if t.code]
        names = set()
        for j, t in enumerate(code):
            if t.text == '=' and j >= 2 and code[j - 1].kind == 'ident' and (
                    code[j - 2].text in (',', '>') or code[j - 2].text in SCALAR_TYPES or code[j - 2].text in self.structs
                    or re.fullmatch(r'vec[234]', code[j - 2].text)):
                continue  # the initializer of a declaration
            if t.text in ASSIGN_OPS or t.text in ('++', '--'):
                k = j - 1
                while k >= 0 and (code[k].kind == 'ident' or code[k].text in '.]' or code[k].kind == 'number' or code[k].text == '['):
                    if code[k].kind == 'ident' and (k == 0 or code[k - 1].text != '.'):
                        names.add(code[k].text)
                        break
                    k -= 1
                if t.text in ('++', '--') and j + 1 < len(code) and code[j + 1].kind == 'ident':
                    names.add(code[j + 1].text)
            if t.kind == 'ident' and t.text in self.out_params and j + 1 < len(code) and code[j + 1].text == '(':
                depth = 0
                args, cur = [], []
                for m in range(j + 1, len(code)):
                    if code[m].text in '([{':
                        depth += 1
                        if depth == 1:
                            continue
                    elif code[m].text in ')]}':
                        depth -= 1
                        if depth == 0:
                            args.append(cur)
                            break
                    if depth == 1 and code[m].text == ',':
                        args.append(cur)
                        cur = []
                    else:
                        cur.append(code[m])
                for n in self.out_params[t.text]:
                    if n < len(args) and len(args[n]) == 1:
                        names.add(args[n][0].text)
        return names

    def declaration(self, toks, i, end, mutable, derefs, in_for=False, indent=''):
        """`TYPE a = e, b;` from toks[i] to the ';' at toks[end] (exclusive)."""
        ty, j = read_type(toks, i)
        parts = []
        for declarator in split_top(toks[j:end], ','):
            lead, core, _ = strip(declarator)
            if not core or core[0].kind != 'ident':
                raise TranslateError(f'line {toks[i].line}: cannot read the declaration')
            name = core[0].text
            keyword = 'var' if (name in mutable or in_for) else 'let'
            k = next_code(core, 1)
            if k < len(core) and core[k].text == '=':
                init = text_of(strip(self.expression(core[k + 1:], derefs))[1])
                parts.append(f'{keyword} {name}: {ty} = {init}')
            elif k >= len(core):
                parts.append(f'var {name}: {ty}')
            else:
                raise TranslateError(f'line {toks[i].line}: cannot read the declaration of {name}')
        if in_for:
            return parts[0]
        sep = ';\n' + indent
        return sep.join(parts)

    def statement_end(self, toks, i):
        depth = 0
        for j in range(i, len(toks)):
            t = toks[j]
            if t.text in '([{':
                depth += 1
            elif t.text in ')]}':
                depth -= 1
            elif t.text == ';' and depth == 0:
                return j
        raise TranslateError(f'line {toks[i].line}: statement without ;')

    def block(self, toks, mutable, derefs, params):
        """Translates the statements of a block body (toks without the braces)."""
        out = []
        i = 0
        while i < len(toks):
            t = toks[i]
            if not t.code:
                out.append(t.text)
                i += 1
                continue
            if t.text == '{':
                end = matching(toks, i, '{', '}')
                out.append('{' + self.block(toks[i + 1:end], mutable, derefs, params) + '}')
                i = end + 1
            elif t.text == 'if' or t.text == 'for' or t.text == 'while':
                k = next_code(toks, i + 1)
                close = matching(toks, k, '(', ')')
                if t.text == 'for':
                    init, cond, step = split_top(toks[k + 1:close], ';')
                    ii = next_code(init, 0)
                    if ii < len(init) and is_type_start(init, ii, self.structs):
                        init_text = self.declaration(init, ii, len(init), mutable, derefs, in_for=True)
                    else:
                        init_text = text_of(self.expression(init, derefs)).strip()
                    step_core = [x for x in step if x.code]
                    if len(step_core) == 2 and step_core[0].text in ('++', '--'):
                        step_text = step_core[1].text + step_core[0].text
                    else:
                        step_text = text_of(self.expression(step, derefs)).strip()
                    head = f'for ({init_text};{text_of(self.expression(cond, derefs))}; {step_text})'
                else:
                    head = t.text + ' ' + text_of(self.expression(toks[k:close + 1], derefs))
                out.append(head)
                i, body = self.branch(toks, close + 1, mutable, derefs, params)
                out.append(body)
                j = next_code(toks, i)
                if t.text == 'if' and j < len(toks) and toks[j].text == 'else':
                    out.append(text_of(toks[i:j]) + 'else')
                    i, body = self.branch(toks, j + 1, mutable, derefs, params)
                    out.append(body)
            elif t.text in ('return', 'break', 'continue', 'discard'):
                end = self.statement_end(toks, i)
                out.append(t.text + text_of(self.expression(toks[i + 1:end], derefs)) + ';')
                i = end + 1
            elif is_type_start(toks, i, self.structs) and self.is_declaration(toks, i):
                end = self.statement_end(toks, i)
                indent = ''.join(out).rsplit('\n', 1)[-1]
                out.append(self.declaration(toks, i, end, mutable, derefs, indent=indent if indent.isspace() else '') + ';')
                i = end + 1
            else:
                end = self.statement_end(toks, i)
                stmt = toks[i:end]
                parts = None
                for n, s in enumerate(stmt):
                    if s.text in ASSIGN_OPS:
                        parts = (stmt[:n + 1], stmt[n + 1:])
                        break
                if parts:
                    target = [x for x in parts[0] if x.code]
                    if target and target[0].kind == 'ident' and target[0].text in params:
                        raise TranslateError(f'line {target[0].line}: assignment to the parameter {target[0].text} '
                                             '(WGSL parameters are immutable: assign a local copy)')
                    out.append(text_of(self.expression(parts[0], derefs)) + text_of(self.expression(parts[1], derefs)) + ';')
                else:
                    code = [x for x in stmt if x.code]
                    if len(code) == 2 and code[0].text in ('++', '--'):
                        out.append(code[1].text + code[0].text + ';')
                    else:
                        out.append(text_of(self.expression(stmt, derefs)) + ';')
                i = end + 1
        return ''.join(out)

    def is_declaration(self, toks, i):
        _, j = read_type(toks, i)
        k = next_code(toks, j)
        return k < len(toks) and toks[k].kind == 'ident'

    def branch(self, toks, i, mutable, derefs, params):
        """The body of an if/else/for at toks[i]: a block, or one statement wrapped in braces."""
        j = next_code(toks, i)
        lead = text_of(toks[i:j])
        if toks[j].text == '{':
            end = matching(toks, j, '{', '}')
            return end + 1, lead + '{' + self.block(toks[j + 1:end], mutable, derefs, params) + '}'
        end = self.statement_end(toks, j)
        return end + 1, ' { ' + self.block(toks[j:end + 1], mutable, derefs, params).strip() + ' }'

    # ----- top level -------------------------------------------------------------------------------

    def struct(self, toks, i):
        k = next_code(toks, i + 1)
        name = toks[k].text
        self.structs.add(name)
        open_ = next_code(toks, k + 1)
        close = matching(toks, open_, '{', '}')
        body = toks[open_ + 1:close]
        out, j = [], 0
        while j < len(body):
            if not body[j].code:
                out.append(body[j].text)
                j += 1
                continue
            end = self.statement_end(body, j)
            ty, n = read_type(body, j)
            field = [x for x in body[n:end] if x.code]
            if len(field) != 1:
                raise TranslateError(f'line {body[j].line}: one field per declaration in struct {name}')
            out.append(f'{field[0].text}: {ty},')
            j = end + 1
        semi = next_code(toks, close + 1)
        if semi >= len(toks) or toks[semi].text != ';':
            raise TranslateError(f'line {toks[close].line}: struct {name} without its ;')
        return semi + 1, f'struct {name} {{' + ''.join(out) + '}'

    def function(self, toks, i):
        paren = i
        while toks[paren].text != '(':
            if toks[paren].text in ';{}=':
                raise TranslateError(f'line {toks[i].line}: unsupported top-level construct: '
                                     + text_of(toks[i:paren + 1]).strip())
            paren += 1
        sig = [t for t in toks[i:paren] if t.code]
        name = sig[-1].text
        ret = text_of(sig[:-1])
        close = matching(toks, paren, '(', ')')
        params, derefs, outs = [], set(), []
        for n, p in enumerate(split_top(toks[paren + 1:close], ',')):
            lead, core, _ = strip(p)
            if not core:
                continue
            is_out = core[0].text == 'out'
            if core[0].text == 'inout':
                raise TranslateError(f'line {core[0].line}: inout parameters are not translated')
            start = 1 if is_out else 0
            start = next_code(core, start)
            ty, j = read_type(core, start)
            pname = [x for x in core[j:] if x.code]
            if len(pname) != 1:
                raise TranslateError(f'line {core[0].line}: cannot read a parameter of {name}')
            pname = pname[0].text
            if is_out:
                derefs.add(pname)
                outs.append(n)
                ty = f'ptr<function, {ty}>'
            params.append(text_of(lead) + f'{pname}: {ty}')
        if outs:
            self.out_params[name] = set(outs)
        open_ = next_code(toks, close + 1)
        if toks[open_].text != '{':
            raise TranslateError(f'line {toks[open_].line}: {name}: a declaration without a body')
        end = matching(toks, open_, '{', '}')
        body = toks[open_ + 1:end]
        mutable = self.assigned_names(body)
        plain_params = {p.split(':')[0].strip() for p in params} - derefs
        head = f'fn {name}(' + ','.join(params).lstrip() + ')'
        if ret != 'void':
            head += f' -> {ret}'
        return end + 1, head + ' {' + self.block(body, mutable, derefs, plain_params) + '}'

    def translate(self, text):
        toks = tokenize(text)
        out, i = [], 0
        while i < len(toks):
            t = toks[i]
            if not t.code:
                out.append(t.text)
                i += 1
            elif t.text == 'struct':
                i, s = self.struct(toks, i)
                out.append(s)
            else:
                i, f = self.function(toks, i)
                out.append(f)
        return ''.join(out)


# ----- a second configuration in the same module ----------------------------------------------------

def top_level_items(text):
    """Splits translated WGSL into (name, kind, tokens) items; comments and blank lines before an item
    belong to it (kind None for trailing text)."""
    toks = tokenize(text)
    items, start, i = [], 0, 0
    while i < len(toks):
        t = toks[i]
        if not t.code:
            i += 1
            continue
        if t.text in ('fn', 'struct'):
            name = toks[next_code(toks, i + 1)].text
            brace = i
            while toks[brace].text != '{':
                brace += 1
            end = matching(toks, brace, '{', '}')
        else:  # const, ...: up to its ;
            name = toks[next_code(toks, i + 1)].text
            end = i
            while toks[end].text != ';':
                end += 1
        items.append((name, t.text, toks[start:end + 1]))
        start = i = end + 1
    items.append((None, None, toks[start:]))
    return items


def calls(toks, names):
    """Indices of the '(' of calls to `names` in toks."""
    out = []
    code = [j for j, t in enumerate(toks) if t.code]
    previous = {j: toks[code[n - 1]].text if n else '' for n, j in enumerate(code)}
    for j, t in enumerate(toks):
        if t.kind == 'ident' and t.text in names and t.code and previous[j] not in ('.', 'fn'):
            k = next_code(toks, j + 1)
            if k < len(toks) and toks[k].text == '(':
                out.append(k)
    return out


def with_callers(items, names):
    """`names` and every function that calls one of them, directly or through others."""
    names = set(names)
    changed = True
    while changed:
        changed = False
        for name, kind, toks in items:
            if kind == 'fn' and name not in names and calls(toks, names):
                names.add(name)
                changed = True
    return names


def add_texture_parameters(items, params):
    """Functions using the free names of `params` ([(name, type)]), and the functions calling them, take
    them as trailing parameters; their calls pass them on."""
    names = {n for n, _ in params}
    needs = with_callers(items, {name for name, kind, toks in items
                                 if kind == 'fn' and any(t.kind == 'ident' and t.text in names for t in toks)})
    declared = ', '.join(f'{n}: {ty}' for n, ty in params)
    passed = ', '.join(n for n, _ in params)
    result = []
    for name, kind, toks in items:
        toks = list(toks)
        for k in reversed(calls(toks, needs)):
            close = matching(toks, k, '(', ')')
            empty = next_code(toks, k + 1) == close
            toks.insert(close, Tok('expr', passed if empty else ', ' + passed, toks[k].line))
        if kind == 'fn' and name in needs:
            k = next_code(toks, [j for j, t in enumerate(toks) if t.text == name][0] + 1)
            close = matching(toks, k, '(', ')')
            empty = next_code(toks, k + 1) == close
            toks.insert(close, Tok('expr', declared if empty else ', ' + declared, toks[k].line))
        result.append((name, kind, toks))
    return result


def variant_functions(base_text, variant_text, params, suffix, header):
    """The functions of `variant_text` (the body in another configuration) that differ from those of
    `base_text`, or call one that does, renamed with `suffix` and with the texture parameters added; one
    comment line each instead of the repeated documentation."""
    base = {name: text_of([t for t in toks if t.code]) for name, kind, toks in top_level_items(base_text) if name}
    items = add_texture_parameters(top_level_items(variant_text), params)
    code = {name: text_of([t for t in toks if t.code]) for name, kind, toks in items if name}
    differ = with_callers(items, {name for name, kind, toks in items if kind == 'fn' and base.get(name) != code[name]})
    out = [header]
    for name, kind, toks in items:
        if name not in differ:
            continue
        body = [t for t in toks]
        first = next_code(body, 0)
        body = body[first:]
        renamed = ''.join(t.text + suffix if (t.kind == 'ident' and t.text in differ and
                                              (j == 0 or body[j - 1].text != '.')) else t.text
                          for j, t in enumerate(body))
        out.append(f'\n// {name} with the baked texture.\n{renamed}\n')
    return ''.join(out)


def preprocess(sources, defines):
    args = ['cpp', '-P', '-C', '-undef', '-nostdinc', '-std=c99']
    for d in defines:
        args.append('-D' + d)
    try:
        run = subprocess.run(args, input=''.join(sources), capture_output=True, text=True)
    except FileNotFoundError:
        raise TranslateError('the C preprocessor `cpp` is not installed (Debian package cpp)')
    if run.returncode != 0:
        raise TranslateError('cpp failed: ' + run.stderr.strip())
    return run.stdout


def tidy(text):
    text = re.sub(r'[ \t]+\n', '\n', text)
    text = re.sub(r'\n{3,}', '\n\n', text)
    return text.lstrip('\n')


def translate(sources, defines=()):
    return tidy(Translator().translate(preprocess(sources, defines)))


def main(argv):
    defines, files = [], []
    variant = {'suffix': None, 'defines': [], 'params': [], 'header': ''}
    it = iter(argv)
    for a in it:
        if a == '-D':
            defines.append(next(it))
        elif a.startswith('-D'):
            defines.append(a[2:])
        elif a == '--macros':
            files.append((next(it), True))
        elif a == '--variant-suffix':
            variant['suffix'] = next(it)
        elif a == '--variant-define':
            variant['defines'].append(next(it))
        elif a == '--texture-parameter':
            name, _, ty = next(it).partition('=')
            variant['params'].append((name, ty))
        elif a == '--variant-header':
            with open(next(it), encoding='utf-8') as fh:
                variant['header'] = fh.read()
        else:
            files.append((a, False))
    if not files:
        sys.stderr.write('\n'.join(__doc__.strip().splitlines()[-3:]) + '\n')
        return 2
    sources = []
    for f, macros_only in files:
        with open(f, encoding='utf-8') as fh:
            text = fh.read()
        if macros_only:  # its comments describe the macros, not the WGSL
            text = ''.join(line for line in text.splitlines(True) if not line.lstrip().startswith('//'))
        sources.append(text)
    try:
        text = translate(sources, defines)
        if variant['suffix']:
            text += variant_functions(text, translate(sources, defines + variant['defines']), variant['params'],
                                      variant['suffix'], '\n' + variant['header'])
        sys.stdout.write(text)
    except TranslateError as e:
        sys.stderr.write(f'to_wgsl.py: {e}\n')
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
