// The WGSL include (`specbake shader --lang wgsl`, shaders/specaa.wgsl translated from the shared body by
// shaders/to_wgsl.py) in Chromium's WebGPU (Tint, then Dawn on SwiftShader's Vulkan), run in headless
// Chromium by tests/consumers/browser_check.mjs with the page browser_wgsl.mjs:
// - the include alone compiles with no error (getCompilationInfo); a compute pipeline calling the
//   derivative-free entry points and a render pipeline whose fragment stage calls the default entry points
//   (derivatives, a baked kernel texture) are created; the GLSL ES include given as WGSL, and the default
//   called in non-uniform control flow, are rejected (so the check can fail);
// - every group of the GLSL grid (tests/gl/grid_cases.h: the filters, reductions, NDFs, G2, the convolved
//   NDF, the curvature kernels) evaluated by the WGSL include in a compute shader, the evaluation being
//   tests/gl/shaders/grid_eval.inc translated by the same shaders/to_wgsl.py, and checked against the same
//   C++ references with the same tolerances as the GLSL on OpenGL; plus the default's derivative-free
//   entry points (specaa_widened_matrix, specaa_default_D without baked data) against the bake's matrix
//   filter and convolved NDF;
// - the default with the baked Sigma kernel (the _kernel functions) drawn in a fragment shader over a
//   1 x 1 kernel texture (constant normal: no per-pixel kernel), at a footprint under one texel (the
//   convolved NDF) and of four texels (LOD 2: the blend toward GGX(A)), against the same core: the texel's
//   single lobe K = 2 Sigma sqrt(g), the gate, the matrix filter, and the blend of GGX(A) and the convolution.
// Skips when node or Chromium is missing (as the consumer tests do).
#include "gl/grid_cases.h"

#include "bake/ggx.h"
#include "bake/roughness_space.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <string>

namespace specbake::gltest {
namespace {

const std::string kSource = SPECBAKE_SOURCE_DIR;

std::string slurp(const std::filesystem::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
}

std::string wgsl_include() {
    TempDir dir;
    const auto file = dir.path() / "specaa.wgsl";
    std::string out;
    if (run_command(std::string("'") + SPECBAKE_EXE + "' shader --lang wgsl -o '" + file.string() + "'", out) != 0)
        return {};
    return slurp(file);
}

// tests/gl/shaders/grid_eval.inc for one group, translated to WGSL as the include is.
std::string wgsl_grid_eval(const std::string& group, std::string& log) {
    std::string out;
    const int rc = run_command("python3 '" + kSource + "/shaders/to_wgsl.py' -DSPECAA_TEST_" + group + " --macros '" +
                                   kSource + "/shaders/src/macros_wgsl.inc' '" + kSource + "/tests/gl/shaders/grid_eval.inc'",
                               out);
    if (rc != 0) {
        log = out;
        return {};
    }
    return out;
}

// The compute entry point of a grid: case i reads six vec4 at 6i and writes four at 4i.
const char* kGridMain = R"(
@group(0) @binding(0) var<storage, read> specaa_test_in: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> specaa_test_out: array<vec4<f32>>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= arrayLength(&specaa_test_out) / 4u) { return; }
    var o0: vec4<f32>;
    var o1: vec4<f32>;
    var o2: vec4<f32>;
    var o3: vec4<f32>;
    specaa_test_eval(specaa_test_in[6u * i], specaa_test_in[6u * i + 1u], specaa_test_in[6u * i + 2u],
                     specaa_test_in[6u * i + 3u], specaa_test_in[6u * i + 4u], specaa_test_in[6u * i + 5u],
                     &o0, &o1, &o2, &o3);
    specaa_test_out[4u * i] = o0;
    specaa_test_out[4u * i + 1u] = o1;
    specaa_test_out[4u * i + 2u] = o2;
    specaa_test_out[4u * i + 3u] = o3;
}
)";

// The default's entry points that need no derivatives, in the grid's calling convention:
// in0 = (h, perceptual roughness r), in1.xyz = kernel matrix K; o0 = specaa_widened_matrix(r^4, K),
// o1.x = specaa_default_D(h, o0, surface of roughness r) (no baked data: GGX convolved with the footprint).
const char* kDefaultEval = R"(
fn specaa_test_eval(in0: vec4<f32>, in1: vec4<f32>, in2: vec4<f32>, in3: vec4<f32>, in4: vec4<f32>,
                    in5: vec4<f32>, o0: ptr<function, vec4<f32>>, o1: ptr<function, vec4<f32>>,
                    o2: ptr<function, vec4<f32>>, o3: ptr<function, vec4<f32>>) {
    var s: SpecaaSurface;
    s.roughness = in0.w;
    let A = specaa_widened_matrix(specaa_base_alpha2(s), in1.xyz);
    *o0 = vec4<f32>(A, 0.0);
    *o1 = vec4<f32>(specaa_default_D(in0.xyz, A, s), 0.0, 0.0, 0.0);
    *o2 = vec4<f32>(0.0);
    *o3 = vec4<f32>(0.0);
}
)";

nlohmann::json encode(float v) {
    if (std::isnan(v)) return "nan";
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    return static_cast<double>(v);
}
float decode(const nlohmann::json& v) {
    if (v.is_number()) return v.get<float>();
    const std::string s = v.get<std::string>();
    return s == "nan" ? NAN : s == "inf" ? INFINITY : -INFINITY;
}

// Runs browser_wgsl.html on `job`; false with the reason in `skip` when node or Chromium is missing.
bool run_webgpu(nlohmann::json job, nlohmann::json& result, std::string& skip) {
    std::string out;
    if (run_command("command -v node", out) != 0) {
        skip = "node is not installed (Debian package nodejs; .ci/setup installs it)";
        return false;
    }
    TempDir dir;
    job["page"] = "browser_wgsl.html";
    job["webgpu"] = true;
    std::ofstream(dir.path() / "job.json") << job.dump();
    const int rc = run_command("timeout 170 node '" + kSource + "/tests/consumers/browser_check.mjs' '" +
                                   (dir.path() / "job.json").string() + "' '" + dir.path().string() + "' '" +
                                   (dir.path() / "result.json").string() + "' 150",
                               out);
    if (rc == 3) {
        skip = out;
        return false;
    }
    EXPECT_EQ(rc, 0) << "headless Chromium run failed: " << out;
    if (rc != 0) return false;
    result = nlohmann::json::parse(slurp(dir.path() / "result.json"));
    EXPECT_FALSE(result.contains("fatal")) << result["fatal"];
    return !result.contains("fatal");
}

std::string messages(const nlohmann::json& r) {
    std::string s;
    for (const auto& m : r["messages"])
        s += m.value("type", "") + " " + std::to_string(m.value("line", 0)) + ":" + std::to_string(m.value("column", 0)) +
             ": " + m.value("message", "") + "\n";
    return s + r.value("pipelineError", "") + r.value("validationError", "");
}

// A fragment stage calling the default entry points, without and with the baked Sigma kernel (in uniform
// control flow unless `guard` puts one in a branch on a varying).
std::string render_module(const std::string& include, bool guard) {
    std::string fs = R"(
struct VsOut {
    @builtin(position) position: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) uv: vec2<f32>,
    @location(2) tangent: vec4<f32>,
}
@vertex fn vs(@builtin(vertex_index) i: u32) -> VsOut {
    let p = vec2<f32>(f32(i & 1u) * 4.0 - 1.0, f32(i >> 1u) * 4.0 - 1.0);
    return VsOut(vec4<f32>(p, 0.0, 1.0), normalize(vec3<f32>(p, 1.0)), p * 0.5 + 0.5, vec4<f32>(1.0, 0.0, 0.0, 1.0));
}
@group(0) @binding(0) var kernelTexture: texture_2d<f32>;
@group(0) @binding(1) var kernelSampler: sampler;
@fragment fn fs(v: VsOut) -> @location(0) vec4<f32> {
    var s: SpecaaSurface;
    s.roughness = 0.3;
    s.uv = v.uv;
    s.normal = normalize(v.normal);
    s.tangent = v.tangent.xyz;
    s.bitangent = cross(s.normal, v.tangent.xyz) * v.tangent.w;
    s.view = normalize(vec3<f32>(v.uv, 1.0));
    let h = normalize(vec3<f32>(0.1, 0.2, 1.0));
    var r = 0.0;
)";
    fs += guard ? "    if (v.uv.x > 0.5) { r = specaa_filtered_roughness(s); }\n"
                : "    r = specaa_filtered_roughness(s);\n";
    fs += R"(
    let A = specaa_filtered_alpha2_matrix(s);
    let d = specaa_default_D(h, A, s) * specaa_ggx_G2(h, h, h, A);
    let baked = specaa_filtered_alpha2_matrix_kernel(s, kernelTexture, kernelSampler);
    let bakedD = specaa_default_D_kernel(h, baked, s, kernelTexture, kernelSampler) * specaa_ggx_G2(h, h, h, baked);
    let bakedR = specaa_filtered_roughness_kernel(s, kernelTexture, kernelSampler);
    return vec4<f32>(d + bakedD, r + bakedR, specaa_filtered_alpha2(s), specaa_filtered_alpha2_kernel(s, kernelTexture, kernelSampler));
}
)";
    return include + fs;
}

TEST(ShaderWgsl, IncludeCompilesAndBuildsPipelinesInChromiumWebGpu) {
    const std::string include = wgsl_include();
    ASSERT_FALSE(include.empty()) << "specbake shader --lang wgsl wrote nothing";
    EXPECT_EQ(include, read_source_file("shaders/specaa.wgsl"));
    const std::string compute = include + kDefaultEval + kGridMain;
    nlohmann::json job = {{"modules", nlohmann::json::array()}};
    job["modules"].push_back({{"id", "include"}, {"code", include}});
    job["modules"].push_back({{"id", "compute"}, {"code", compute}, {"entryPoint", "main"}});
    job["modules"].push_back(
        {{"id", "fragment"}, {"code", render_module(include, false)}, {"render", {{"vertex", "vs"}, {"fragment", "fs"}}}});
    job["modules"].push_back({{"id", "broken: the GLSL ES include"}, {"code", read_source_file("shaders/specaa_es.glsl")}});
    job["modules"].push_back({{"id", "broken: the default in non-uniform control flow"},
                              {"code", render_module(include, true)},
                              {"render", {{"vertex", "vs"}, {"fragment", "fs"}}}});
    nlohmann::json result;
    std::string skip;
    if (!run_webgpu(job, result, skip)) {
        if (!skip.empty()) GTEST_SKIP() << skip;
        return;
    }
    std::printf("WebGPU adapter: %s\n", result.value("adapter", "").c_str());
    const auto& r = result["results"];
    ASSERT_EQ(r.size(), 5u);
    for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(r[i].value("errors", -1), 0) << r[i].value("id", "") << "\n" << messages(r[i]);
        EXPECT_FALSE(r[i].contains("validationError")) << r[i].value("id", "") << "\n" << messages(r[i]);
    }
    EXPECT_TRUE(r[1].value("pipeline", false)) << messages(r[1]);
    EXPECT_TRUE(r[2].value("pipeline", false)) << messages(r[2]);
    EXPECT_GT(r[3].value("errors", 0), 0) << "the GLSL ES include compiled as WGSL";
    EXPECT_GT(r[4].value("errors", 0), 0) << "dpdx in non-uniform control flow was accepted";
    EXPECT_NE(messages(r[4]).find("uniform"), std::string::npos) << messages(r[4]);
}

// Reference of the DEFAULT evaluation: the bake's projected-space matrix filter (TK21 Eq. 4-7) and
// convolved NDF, tolerances as the grid's MATRIX (4e-5 relative) and convolved-D (1e-3 relative) checks.
GridGroup default_group() {
    GridGroup g{"DEFAULT", {}, {}};
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (double r : {0.05, 0.2, 0.5, 0.8})
        for (double scale : {0.0, 1e-3, 0.03, 0.3, 3.0})
            for (double hz : {1.0, 0.8, 0.4, 0.1})
                for (int rep = 0; rep < 3; ++rep) {
                    const double phi = 3.14159265358979 * u(rng), s = std::sqrt(1.0 - hz * hz);
                    const double dx = scale * u(rng), dy = scale * u(rng), ex = scale * u(rng), ey = scale * u(rng);
                    GridCase c;
                    c.in[0] = {float(s * std::cos(phi)), float(s * std::sin(phi)), float(hz), float(r)};
                    c.in[1] = {float(dx * dx + ex * ex), float(dy * dy + ey * ey), float(dx * dy + ex * ey), 0.0f};
                    g.cases.push_back(c);
                }
    g.check = [](const GridCase& c, const GridResult& res) -> std::string {
        const double r = c.in[0][3], a = r * r * r * r;
        const Sym2<double> K{c.in[1][0], c.in[1][2], c.in[1][1]};
        const Sym2<double> A = projected_to_slope_roughness(slope_to_projected_roughness(diag(a, a)) + K);
        const auto close = [](double gpu, double ref, double rel) { return std::abs(gpu - ref) <= rel * std::abs(ref) + kAbsTol; };
        const double scale = std::abs(A.xx) + std::abs(A.yy);
        std::string e;
        char buf[400];
        if (!close(res.out[0][0], A.xx, kRelTol) || !close(res.out[0][1], A.yy, kRelTol) ||
            !(std::abs(res.out[0][2] - A.xy) <= kRelTol * scale + kAbsTol)) {
            std::snprintf(buf, sizeof buf, "specaa_widened_matrix(%g, (%g, %g, %g)): gpu (%g, %g, %g), reference (%g, %g, %g)", a,
                          K.xx, K.yy, K.xy, res.out[0][0], res.out[0][1], res.out[0][2], A.xx, A.yy, A.xy);
            return buf;
        }
        // D from the GPU's A (its rounding is checked above), as specaa_default_D receives it.
        const Sym2<double> Agpu{res.out[0][0], res.out[0][2], res.out[0][1]};
        const Vec3<double> h{c.in[0][0], c.in[0][1], c.in[0][2]};
        const double cond = std::max(1.0, std::abs(Agpu.xx * Agpu.yy) / std::max(det(Agpu), a * a));
        const double ref = convolved_ndf(h, Agpu, a);
        if (!(std::abs(res.out[1][0] - ref) <= 1e-3 * cond * ref + kAbsTol)) {
            std::snprintf(buf, sizeof buf, "specaa_default_D(h = (%g, %g, %g), r = %g, K = (%g, %g, %g)): gpu %.8g, reference %.8g",
                          h.x, h.y, h.z, r, K.xx, K.yy, K.xy, res.out[1][0], ref);
            return buf;
        }
        return {};
    };
    return g;
}

TEST(ShaderWgsl, GridMatchesCppCoreInWebGpuComputeShader) {
    const std::string include = wgsl_include();
    ASSERT_FALSE(include.empty()) << "specbake shader --lang wgsl wrote nothing";
    std::vector<GridGroup> groups = grid_groups();
    groups.push_back(default_group());
    nlohmann::json job = {{"modules", nlohmann::json::array()}};
    for (const GridGroup& group : groups) {
        std::string log;
        const std::string eval = group.name == "DEFAULT" ? kDefaultEval : wgsl_grid_eval(group.name, log);
        ASSERT_FALSE(eval.empty()) << group.name << ": shaders/to_wgsl.py failed on grid_eval.inc: " << log;
        nlohmann::json inputs = nlohmann::json::array();
        for (const GridCase& c : group.cases)
            for (const Vec4& v : c.in)
                for (float x : v) inputs.push_back(encode(x));
        job["modules"].push_back({{"id", group.name}, {"code", include + eval + kGridMain}, {"entryPoint", "main"},
                                  {"inputs", inputs}, {"outputCount", 16 * group.cases.size()}});
    }
    nlohmann::json result;
    std::string skip;
    if (!run_webgpu(job, result, skip)) {
        if (!skip.empty()) GTEST_SKIP() << skip;
        return;
    }
    const auto& results = result["results"];
    ASSERT_EQ(results.size(), groups.size());
    size_t evaluated = 0;
    for (size_t g = 0; g < groups.size(); ++g) {
        const auto& r = results[g];
        const GridGroup& group = groups[g];
        ASSERT_EQ(r.value("errors", -1), 0) << group.name << "\n" << messages(r);
        ASSERT_TRUE(r.value("pipeline", false)) << group.name << "\n" << messages(r);
        const auto& out = r["outputs"];
        ASSERT_EQ(out.size(), 16 * group.cases.size()) << group.name;
        size_t failed = 0;
        for (size_t i = 0; i < group.cases.size(); ++i) {
            GridResult res;
            for (int k = 0; k < 16; ++k) res.out[k / 4][k % 4] = decode(out[16 * i + k]);
            const std::string e = group.check(group.cases[i], res);
            if (!e.empty() && ++failed <= 3) ADD_FAILURE() << group.name << " case " << i << ": " << e;
        }
        EXPECT_EQ(failed, 0u) << group.name << ": " << failed << " of " << group.cases.size() << " cases differ";
        evaluated += group.cases.size();
    }
    EXPECT_GT(evaluated, 4000u);
    std::printf("%zu cases compared on WebGPU (%s)\n", evaluated, result.value("adapter", "").c_str());
}

// The fragment shader of the baked-kernel check: pixel (x, y) of a 16 x 16 target has roughness
// r = 0.05 + 0.9 (y + 0.5) / 16 and h = normalize(0.06 (x mod 8), 0.03, 1); uv spans 0.01 texel per pixel
// left of x = 8 and 4 texels right of it (the texture is 1 x 1: LOD -6.6 and 2).
const char* kKernelDraw = R"(
@group(0) @binding(0) var kernelTexture: texture_2d<f32>;
@group(0) @binding(1) var kernelSampler: sampler;
@vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    return vec4<f32>(f32(i & 1u) * 4.0 - 1.0, f32(i >> 1u) * 4.0 - 1.0, 0.0, 1.0);
}
@fragment fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    var s: SpecaaSurface;
    s.roughness = 0.05 + 0.9 * p.y / 16.0;
    s.uv = p.xy * select(0.01, 4.0, p.x > 8.0);
    s.normal = vec3<f32>(0.0, 0.0, 1.0);
    s.view = vec3<f32>(0.0, 0.0, 1.0);
    s.tangent = vec3<f32>(1.0, 0.0, 0.0);
    s.bitangent = vec3<f32>(0.0, 1.0, 0.0);
    let h = normalize(vec3<f32>(0.06 * f32(u32(p.x) % 8u), 0.03, 1.0));
    let A = specaa_filtered_alpha2_matrix_kernel(s, kernelTexture, kernelSampler);
    return vec4<f32>(A, specaa_default_D_kernel(h, A, s, kernelTexture, kernelSampler));
}
)";

TEST(ShaderWgsl, DefaultWithBakedKernelMatchesCppCoreInAFragmentShader) {
    const std::string include = wgsl_include();
    ASSERT_FALSE(include.empty()) << "specbake shader --lang wgsl wrote nothing";
    const int size = 16;
    const int texel[4] = {12, 6, 3, 128};  // Sigma (xx, yy, xy) and g, as RGBA8 k / 255: w inside (0, 1) on most pixels
    nlohmann::json job = {{"modules", nlohmann::json::array()}};
    job["modules"].push_back({{"id", "kernel"}, {"code", include + kKernelDraw},
                              {"draw", {{"size", size}, {"texel", {texel[0], texel[1], texel[2], texel[3]}}}}});
    nlohmann::json result;
    std::string skip;
    if (!run_webgpu(job, result, skip)) {
        if (!skip.empty()) GTEST_SKIP() << skip;
        return;
    }
    const auto& r = result["results"][0];
    ASSERT_EQ(r.value("errors", -1), 0) << messages(r);
    ASSERT_FALSE(r.contains("drawError")) << r.value("drawError", "");
    const auto& px = r["pixels"];
    ASSERT_EQ(px.size(), size_t(4 * size * size));
    const double sxx = texel[0] / 255.0, syy = texel[1] / 255.0, sxy = texel[2] / 255.0, g = texel[3] / 255.0;
    int blended = 0;
    double worst_a = 0, worst_d = 0;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const double rough = double(0.05f + 0.9f * (float(y) + 0.5f) / 16.0f), a = std::pow(rough, 4.0);
            // K = 2 Sigma sqrt(g), gated: K f^2, f = saturate(lambda_max(K) / (0.5 a)).
            Sym2<double> K{2.0 * std::sqrt(g) * sxx, 2.0 * std::sqrt(g) * sxy, 2.0 * std::sqrt(g) * syy};
            const double lmax = 0.5 * (K.xx + K.yy) + std::hypot(0.5 * (K.xx - K.yy), K.xy);
            const double f = std::min(1.0, lmax / (0.5 * a));
            K = (f * f) * K;
            const Sym2<double> A = projected_to_slope_roughness(slope_to_projected_roughness(diag(a, a)) + K);
            const size_t i = 4 * size_t(y * size + x);
            const double scale = A.xx + A.yy;
            const double ea = std::max({std::abs(decode(px[i]) - A.xx) / A.xx, std::abs(decode(px[i + 1]) - A.yy) / A.yy,
                                        std::abs(decode(px[i + 2]) - A.xy) / scale});
            worst_a = std::max(worst_a, ea);
            EXPECT_LE(ea, kRelTol) << "A at pixel (" << x << ", " << y << "): gpu (" << decode(px[i]) << ", "
                                   << decode(px[i + 1]) << ", " << decode(px[i + 2]) << "), reference (" << A.xx << ", "
                                   << A.yy << ", " << A.xy << ")";
            // D: the blend weight w = saturate(LOD) max((1 - g) saturate(8 lambda_max(baked spread)),
            // saturate(8 lambda_min(rest of A - a I))), LOD 2 right of x = 8 (the spread's size, its heavy tail
            // 1 - g and the rest's shape).
            const Vec3<double> h = normalize(Vec3<double>{0.06 * (x % 8), 0.03, 1.0});
            const Sym2<double> rest{A.xx - a - K.xx, A.xy - K.xy, A.yy - a - K.yy};
            const double rest_minor = 0.5 * (rest.xx + rest.yy) - std::hypot(0.5 * (rest.xx - rest.yy), rest.xy);
            const double baked_max = 0.5 * (K.xx + K.yy) + std::hypot(0.5 * (K.xx - K.yy), K.xy);
            const double w = x >= 8 ? std::max((1.0 - g) * std::clamp(8.0 * baked_max, 0.0, 1.0),
                                               std::clamp(8.0 * rest_minor, 0.0, 1.0))
                                    : 0.0;
            blended += w > 0.0 && w < 1.0;
            const double ggx = ggx_ndf(h, A, a * a), d = ggx + (1.0 - w) * (convolved_ndf(h, A, a) - ggx);
            const double cond = std::max(1.0, A.xx * A.yy / std::max(det(A), a * a));
            worst_d = std::max(worst_d, std::abs(decode(px[i + 3]) - d) / (cond * d));
            EXPECT_LE(std::abs(decode(px[i + 3]) - d), 1e-3 * cond * d + kAbsTol)
                << "D at pixel (" << x << ", " << y << "), w " << w << ": gpu " << decode(px[i + 3]) << ", reference " << d;
        }
    EXPECT_GT(blended, 8) << "too few pixels between the convolution and GGX(A)";
    std::printf("baked kernel: %d pixels, worst relative error A %.2e, D %.2e (%d blended)\n", size * size, worst_a,
                worst_d, blended);
}

}  // namespace
}  // namespace specbake::gltest
