// The include's glint path (specaa_glint_*) on a real OpenGL implementation against the C++ evaluation
// of the same formulas (bake/glint_model.h) reading the same baked dictionary as a 2D array texture;
// hard cases finite; the HLSL glint path compiled to SPIR-V; no derivative inside a conditional block.
#include "gl/gl_harness.h"

#include "bake/glint_dictionary.h"
#include "bake/glint_model.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>

namespace specbake::gltest {
namespace {

constexpr int kCount = 16;

const GlintDictionary& dictionary() {
    static const GlintDictionary d = [] {
        GlintDictionarySettings s;
        s.count = kCount;
        return *bake_glint_dictionary(s);
    }();
    return d;
}

// in0 = (uv, hs), in1 = ddx/ddy(uv), in2 = ddx/ddy(h.xy), in3 = (sx, sy, rho, logDensity),
// in4 = (relativeArea, zeta, maxAnisotropy, kernelScale), in5 = (cell s, cell t, level).
std::string glint_fragment(bool ggx) {
    return "#version 450\n#define SPECAA_GLINT_COUNT " + std::to_string(kCount) + "\n" +
           (ggx ? "#define SPECAA_GLINT_GGX\n" : "") +
           read_source_file("shaders/specaa.glsl") + R"(
layout(binding = 3) uniform sampler2DArray uDict;
)" + glsl_fragment_wrapper(6, 4, R"(
    SpecaaGlintParams g;
    g.logDensity = vIn3.w;
    g.relativeArea = vIn4.x;
    g.densityRandomization = vIn4.y;
    g.maxAnisotropy = vIn4.z;
    g.kernelScale = vIn4.w;
    o0 = vec4(specaa_glint_P22(uDict, vIn0.xy, vIn1, vIn0.zw, vIn2, vIn3.xyz, g),
              specaa_glint_beckmann_P22(vIn0.zw, vIn3.xyz), 0.0, 0.0);
    int level = int(vIn5.z);
    uvec3 r1 = specaa_glint_pcg3d(uvec3(uint(int(vIn5.x)) << uint(level), uint(int(vIn5.y)) << uint(level), 0x2545F491u));
    uvec3 r2 = specaa_glint_pcg3d(r1 ^ uvec3(0x9E3779B9u, 0x85EBCA6Bu, 0xC2B2AE35u));
    o1 = vec4(specaa_glint_unit(r1.x), specaa_glint_unit(r1.y), specaa_glint_unit(r1.z), specaa_glint_unit(r2.x));
    o2 = specaa_glint_inverse_transform(vIn3.xyz);
    o3 = vec4(specaa_glint_sigma_rho(vIn1.xyz), 0.0);)");
}

GLuint upload_dictionary(const GlintDictionary& d) {
    GLuint tex = 0;
    glActiveTexture(GL_TEXTURE3);
    glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D_ARRAY, tex);
    for (int m = 0; m < d.mip_count; ++m)
        glTexImage3D(GL_TEXTURE_2D_ARRAY, m, GL_RGBA16F, d.settings.width >> m, 1, d.layers, 0, GL_RGBA, GL_FLOAT,
                     d.mips[size_t(m)].pixels.data());
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAX_LEVEL, d.mip_count - 1);
    glActiveTexture(GL_TEXTURE0);
    return tex;
}

struct Case {
    GridCase grid;
    std::array<double, 2> uv, hs;
    std::array<double, 4> duv, dh;
    GlintSigmaRho s;
    GlintParams g;
    int cs, ct, level;
};

Case make_case(std::array<double, 2> uv, std::array<double, 4> duv, std::array<double, 2> hs, std::array<double, 4> dh,
               GlintSigmaRho s, GlintParams g, int cs, int ct, int level) {
    Case c{{}, uv, hs, duv, dh, s, g, cs, ct, level};
    auto f = [](double v) { return float(v); };
    c.grid.in[0] = {f(uv[0]), f(uv[1]), f(hs[0]), f(hs[1])};
    c.grid.in[1] = {f(duv[0]), f(duv[1]), f(duv[2]), f(duv[3])};
    c.grid.in[2] = {f(dh[0]), f(dh[1]), f(dh[2]), f(dh[3])};
    c.grid.in[3] = {f(s.sx), f(s.sy), f(s.rho), f(g.log_density)};
    c.grid.in[4] = {f(g.relative_area), f(g.density_randomization), f(g.max_anisotropy), f(g.kernel_scale)};
    c.grid.in[5] = {float(cs), float(ct), float(level), 0.0f};
    // The C++ side reads the float inputs the GPU reads.
    c.uv = {c.grid.in[0][0], c.grid.in[0][1]};
    c.hs = {c.grid.in[0][2], c.grid.in[0][3]};
    for (int i = 0; i < 4; ++i) c.duv[size_t(i)] = c.grid.in[1][size_t(i)], c.dh[size_t(i)] = c.grid.in[2][size_t(i)];
    c.s = {c.grid.in[3][0], c.grid.in[3][1], c.grid.in[3][2]};
    c.g = {c.grid.in[3][3], c.grid.in[4][0], c.grid.in[4][1], c.grid.in[4][2], c.grid.in[4][3]};
    return c;
}

std::vector<Case> random_cases(int n) {
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<Case> cases;
    for (int i = 0; i < n; ++i) {
        const double scale = std::exp2(-20.0 + 14.0 * u(rng)), aniso = 1.0 + 6.0 * u(rng), a = 2 * M_PI * u(rng);
        const std::array<double, 4> duv = {scale * std::cos(a), scale * std::sin(a), -scale / aniso * std::sin(a),
                                           scale / aniso * std::cos(a)};
        const double hscale = std::exp2(-14.0 + 10.0 * u(rng));
        const std::array<double, 4> dh = {hscale * (u(rng) - 0.5), hscale * (u(rng) - 0.5), hscale * (u(rng) - 0.5),
                                          hscale * (u(rng) - 0.5)};
        const GlintSigmaRho s{0.03 + 0.4 * u(rng), 0.03 + 0.4 * u(rng), -0.9 + 1.8 * u(rng)};
        const std::array<double, 2> hs = {s.sx * 3.0 * (u(rng) - 0.5), s.sy * 3.0 * (u(rng) - 0.5)};
        GlintParams g;
        g.log_density = 4.0 + 30.0 * u(rng);
        g.relative_area = i % 3 == 0 ? 1.0 : 0.2 + 0.8 * u(rng);
        g.density_randomization = i % 4 == 0 ? 0.0 : 2.0;
        g.kernel_scale = i % 2 == 0 ? 0.0 : 0.5;
        cases.push_back(make_case({4.0 * u(rng), 4.0 * u(rng)}, duv, hs, dh, s, g, int(u(rng) * 60000) - 30000,
                                  int(u(rng) * 60000) - 30000, i % 16));
    }
    return cases;
}

std::vector<GridResult> run(const std::vector<Case>& cases, std::string& log, bool ggx = false) {
    const GLuint program = build_program_glsl(grid_vertex_shader(), glint_fragment(ggx), log);
    if (!program) return {};
    const GLuint tex = upload_dictionary(dictionary());
    std::vector<GridCase> grid;
    for (const Case& c : cases) grid.push_back(c.grid);
    std::vector<GridResult> out = evaluate_grid(program, grid, log);
    glDeleteTextures(1, &tex);
    glDeleteProgram(program);
    return out;
}

void compare_with_cpp(bool ggx) {
    SPECBAKE_REQUIRE_GL(gl);
    std::vector<Case> cases = random_cases(2000);
    for (Case& c : cases) c.g.ggx = ggx;
    std::string log;
    const std::vector<GridResult> out = run(cases, log, ggx);
    ASSERT_EQ(out.size(), cases.size()) << log;
    const GlintDictionary& d = dictionary();
    int nonzero = 0, off_c20 = 0, off_ggaa = 0, ggaa = 0, c20 = 0;
    std::vector<double> errors;
    for (size_t i = 0; i < cases.size(); ++i) {
        const Case& c = cases[i];
        const double expected = glint_p22(d, c.uv, c.duv, c.hs, c.dh, c.s, c.g);
        const double got = out[i].out[0][0];
        ASSERT_TRUE(std::isfinite(got)) << "case " << i;
        EXPECT_NEAR(out[i].out[0][1], glint_beckmann_p22(c.hs[0], c.hs[1], c.s), 1e-4 * out[i].out[0][1] + 1e-6);
        const std::array<uint32_t, 6> r = glint_cell_draws(c.cs, c.ct, c.level);
        for (int k = 0; k < 4; ++k) EXPECT_EQ(double(out[i].out[1][size_t(k)]), glint_unit(r[size_t(k)])) << "case " << i;
        const std::array<double, 4> minv = glint_inverse_transform(c.s, glint_sigma_o(d.settings));
        for (int k = 0; k < 4; ++k) EXPECT_NEAR(out[i].out[2][size_t(k)], minv[size_t(k)], 1e-5 * std::fabs(minv[size_t(k)]) + 1e-6);
        nonzero += expected > 0.0;
        // Relative to the Beckmann peak of the case: the scale of the SDF.
        const double scale = std::max(std::fabs(expected), ggx ? glint_ggx_p22(0, 0, c.s) : glint_beckmann_p22(0, 0, c.s));
        const double error = std::fabs(got - expected) / scale;
        errors.push_back(error);
        if (c.g.kernel_scale == 0.0) {
            ++c20;
            off_c20 += error > 1e-3;
        } else {
            ++ggaa;
            off_ggaa += error > 2e-2;
        }
    }
    std::sort(errors.begin(), errors.end());
    std::printf("glint P22 (%s): %d cases, %d nonzero, median error %.2e, p99 %.2e; C20 off %d/%d, GGAA off %d/%d (%s)\n",
                ggx ? "GGX" : "Beckmann", int(cases.size()), nonzero, errors[errors.size() / 2], errors[errors.size() * 99 / 100], off_c20, c20,
                off_ggaa, ggaa, gl->renderer().c_str());
    EXPECT_GT(nonzero, int(cases.size()) / 2);
    // A handful may flip a rounded jittered level or a cell at the ellipse edge between float and double.
    EXPECT_LE(off_c20, c20 / 100);
    EXPECT_LE(off_ggaa, ggaa / 100);
}

TEST(ShaderGlints, GlslGlintPathMatchesTheCppEvaluation) { compare_with_cpp(false); }
TEST(ShaderGlints, GlslGgxGlintPathMatchesTheCppEvaluation) { compare_with_cpp(true); }

// alpha near 0 and 1, grazing half vectors, zero derivatives, densities e^0 and e^50, relative areas 0
// and 1, rho at the clamps, large UVs: finite and non-negative on the GPU and in C++.
TEST(ShaderGlints, HardCasesAreFinite) {
    SPECBAKE_REQUIRE_GL(gl);
    std::vector<Case> cases;
    const std::array<double, 4> zero{0, 0, 0, 0}, small{1e-5, 0, 0, 1e-5}, huge{3.0, 0.0, 0.0, 5.0};
    const GlintSigmaRho sigmas[] = {glint_sigma_rho(0.0, 0.0, 0.0), glint_sigma_rho(1e-8, 1e-8, 0.0),
                                    glint_sigma_rho(0.5, 0.5, 0.0), glint_sigma_rho(4.0, 4.0, 3.99),
                                    glint_sigma_rho(0.02, 0.01, 0.0141), glint_sigma_rho(0.02, 0.01, -0.0141)};
    const std::array<double, 2> slopes[] = {{0.0, 0.0}, {1e3, -2e3}, {0.01, 0.02}, {-40.0, 0.0}};
    int n = 0;
    for (const GlintSigmaRho& sr : sigmas)
        for (const std::array<double, 2>& hs : slopes)
            for (const std::array<double, 4>& duv : {zero, small, huge})
                for (const std::array<double, 4>& dh : {zero, small, huge})
                    for (double density : {0.0, 50.0, 12.0})
                        for (double area : {0.0, 1.0, 0.3}) {
                            GlintParams g;
                            g.log_density = density;
                            g.relative_area = area;
                            g.kernel_scale = n % 2 ? 0.5 : 0.0;
                            const std::array<double, 2> uv = n % 3 == 0 ? std::array<double, 2>{1000.25, -999.5}
                                                                        : std::array<double, 2>{0.3, 0.7};
                            cases.push_back(make_case(uv, duv, hs, dh, sr, g, -n, n, n % 16));
                            ++n;
                        }
    std::string log;
    const std::vector<GridResult> out = run(cases, log);
    ASSERT_EQ(out.size(), cases.size()) << log;
    const GlintDictionary& d = dictionary();
    int equal_beckmann = 0, density50 = 0;
    for (size_t i = 0; i < cases.size(); ++i) {
        const Case& c = cases[i];
        const double expected = glint_p22(d, c.uv, c.duv, c.hs, c.dh, c.s, c.g);
        ASSERT_TRUE(std::isfinite(expected)) << "C++ case " << i;
        ASSERT_TRUE(std::isfinite(out[i].out[0][0]) && out[i].out[0][0] >= 0.0f) << "GL case " << i;
        for (int k = 0; k < 4; ++k) ASSERT_TRUE(std::isfinite(out[i].out[2][size_t(k)])) << "GL case " << i;
        if (c.g.log_density == 50.0 && c.g.relative_area == 1.0) {
            // C21 Fig. 10: at e^50 every cell is past the last level: the smooth Beckmann SDF.
            ++density50;
            equal_beckmann += std::fabs(out[i].out[0][0] - out[i].out[0][1]) <= 1e-5 * out[i].out[0][1] + 1e-30;
        }
    }
    EXPECT_EQ(equal_beckmann, density50);
}

// Disassembled, optimised (inlined) SPIR-V of `source`; empty on a compile failure (in `log`).
std::string compile_spirv(const std::string& source, bool hlsl, std::string& log) {
    TempDir dir;
    const std::string src = (dir.path() / (hlsl ? "glint.hlsl" : "glint.frag")).string();
    const std::string spv = (dir.path() / "glint.spv").string(), opt = (dir.path() / "opt.spv").string();
    std::ofstream(src) << source;
    const std::string compile = hlsl ? "glslangValidator -V -D -e main -S frag '" + src + "' -o '" + spv + "'"
                                     : "glslangValidator -G -S frag '" + src + "' -o '" + spv + "'";
    std::string out;
    if (run_command(compile + " && spirv-opt -O '" + spv + "' -o '" + opt + "' && spirv-val --target-env " +
                        (hlsl ? "vulkan1.0" : "opengl4.5") + " '" + opt + "'",
                    out) != 0) {
        log = out;
        return {};
    }
    std::string dis;
    run_command("spirv-dis --no-header '" + opt + "'", dis);
    return dis;
}

// True when every derivative (OpDPdx/OpDPdy and variants, OpFwidth, implicit-LOD samples) of the
// optimised shader sits before its first branch or merge instruction: in the entry block, which every
// invocation of the quad executes.
bool derivatives_in_uniform_flow(const std::string& dis, int& derivatives) {
    std::istringstream in(dis);
    std::string line;
    bool branched = false, ok = true;
    derivatives = 0;
    while (std::getline(in, line)) {
        if (line.find("OpSelectionMerge") != std::string::npos || line.find("OpLoopMerge") != std::string::npos ||
            line.find("OpBranchConditional") != std::string::npos || line.find("OpSwitch") != std::string::npos)
            branched = true;
        const bool derivative = line.find("OpDPd") != std::string::npos || line.find("OpFwidth") != std::string::npos ||
                                line.find("ImplicitLod") != std::string::npos;
        if (derivative) {
            ++derivatives;
            ok = ok && !branched;
        }
    }
    return ok;
}

std::string glint_program_glsl(bool derivative_in_branch) {
    return std::string("#version 450\n") + read_source_file("shaders/specaa.glsl") + R"(
layout(binding = 0) uniform sampler2DArray uDict;
layout(location = 0) in vec2 vUv;
layout(location = 1) in vec3 vI;
layout(location = 2) in vec3 vO;
layout(location = 3) in vec3 vSigma;
layout(location = 0) out vec4 fragColor;
void main() {
    vec3 h = normalize(vI + vO);
    vec4 duv = specaa_glint_derivatives(vUv);
)" + (derivative_in_branch ? "    vec4 dh = vec4(0.0);\n    if (vI.z > 0.0) dh = specaa_glint_derivatives(h.xy);\n"
                            : "    vec4 dh = specaa_glint_derivatives(h.xy);\n") + R"(
    SpecaaGlintParams g = specaa_glint_default_params();
    fragColor = vec4(specaa_glint_specular(uDict, vUv, duv, vI, vO, dh, specaa_glint_sigma_rho(vSigma), g));
}
)";
}

TEST(ShaderGlints, DerivativesSitOutsideConditionalBlocks) {
    std::string log;
    int derivatives = 0;
    const std::string good = compile_spirv(glint_program_glsl(false), false, log);
    ASSERT_FALSE(good.empty()) << log;
    EXPECT_TRUE(derivatives_in_uniform_flow(good, derivatives));
    EXPECT_EQ(derivatives, 4);  // ddx/ddy of the UV and of h.xy; the glint functions take none
    EXPECT_NE(good.find("OpImageSampleExplicitLod"), std::string::npos);  // textureGrad
    // The check sees a derivative inside a branch (as in C21's public shader).
    const std::string bad = compile_spirv(glint_program_glsl(true), false, log);
    ASSERT_FALSE(bad.empty()) << log;
    EXPECT_FALSE(derivatives_in_uniform_flow(bad, derivatives));

    const std::string hlsl = read_source_file("shaders/specaa.hlsl") + R"(
Texture2DArray uDict : register(t0);
SamplerState uSampler : register(s0);
float4 main(float2 uv : TEXCOORD0, float3 i : TEXCOORD1, float3 o : TEXCOORD2, float3 sigma : TEXCOORD3) : SV_Target0 {
    float3 h = normalize(i + o);
    float4 duv = specaa_glint_derivatives(uv);
    float4 dh = specaa_glint_derivatives(h.xy);
    SpecaaGlintParams g = specaa_glint_default_params();
    return specaa_glint_specular(uDict, uSampler, uv, duv, i, o, dh, specaa_glint_sigma_rho(sigma), g).xxxx;
}
)";
    const std::string hlsl_dis = compile_spirv(hlsl, true, log);
    ASSERT_FALSE(hlsl_dis.empty()) << log;
    EXPECT_TRUE(derivatives_in_uniform_flow(hlsl_dis, derivatives));
    EXPECT_EQ(derivatives, 4);
}

}  // namespace
}  // namespace specbake::gltest
