// The GLSL ES 3.00 include (`specbake shader --lang glsl-es`) in Chromium's WebGL 2 (ANGLE's translator,
// then its Vulkan backend on SwiftShader): every entry point, binding and configuration macro the docs list
// (tests/gl/es_shader_source.h, the shaders glslang compiles in tests/gl/test_shader_es.cpp) compiles,
// links and draws without a GL error; deliberately broken variants of the include are rejected, so the
// check can fail. The page is browser_shaders.mjs.
#include "consumer_harness.h"

#include "gl/es_shader_source.h"

#include <algorithm>
#include <cmath>

namespace specbake::consumers {
namespace {

class WebGlShaders : public ConsumerTest {};

TEST_F(WebGlShaders, EsIncludeCompilesLinksAndDrawsForEveryEntryPointAndBinding) {
    if (!have("node")) GTEST_SKIP() << "node is not installed (Debian package nodejs; .ci/setup installs it)";
    specbake("shader --lang glsl-es -o " + quote(root_ / "specaa_es.glsl"));
    const std::string include = slurp(root_ / "specaa_es.glsl");
    ASSERT_FALSE(include.empty());
    const std::string source_dir = SPECBAKE_SOURCE_DIR;
    const std::string entries = es_shaders::read_text(source_dir + "/shaders/cost/entries.inc");
    const auto variants = es_shaders::all_variants(source_dir);
    const auto broken = es_shaders::broken_variants(include, es_shaders::read_text(source_dir + "/shaders/specaa.glsl"));
    ASSERT_GE(variants.size(), 34u + 16u);
    ASSERT_EQ(broken.size(), 2u);
    ASSERT_NE(broken[1].include, include) << "the LOD guard the broken variant replaces is gone";

    nlohmann::json job = {{"page", "browser_shaders.html"}, {"shaders", nlohmann::json::array()}};
    for (const auto& v : variants)
        job["shaders"].push_back({{"id", v.name}, {"vertex", es_shaders::vertex_source()},
                                  {"fragment", es_shaders::fragment_source(include, entries, v)}});
    for (const auto& b : broken)
        job["shaders"].push_back({{"id", "broken: " + b.name}, {"vertex", es_shaders::vertex_source()},
                                  {"fragment", es_shaders::fragment_source(b.include, entries, b.variant)}});
    nlohmann::json result;
    if (!run_browser(job, root_, &result)) return;
    std::printf("%s; %s; %s\n", result.value("webgl", "").c_str(), result.value("glsl", "").c_str(),
                result.value("renderer", "").c_str());
    const auto& results = result["results"];
    ASSERT_EQ(results.size(), variants.size() + broken.size());
    for (size_t i = 0; i < variants.size(); ++i) {
        const auto& r = results[i];
        EXPECT_TRUE(r.value("compiled", false) && r.value("linked", false))
            << variants[i].name << "\n" << r["logs"].dump(1);
        EXPECT_EQ(r.value("glError", -1), 0) << variants[i].name << ": GL error drawing with the program";
    }
    // The desktop include stops at the sampler2DArray parameter, the textureQueryLod path at the call.
    const char* expected[] = {"sampler2DArray", "textureQueryLod"};
    for (size_t i = 0; i < broken.size(); ++i) {
        const auto& r = results[variants.size() + i];
        EXPECT_FALSE(r.value("compiled", true)) << broken[i].name << " compiled";
        const std::string log = r["logs"].value("fragment", "");
        EXPECT_NE(log.find(expected[i]), std::string::npos) << broken[i].name << ": " << log;
    }
}

// The ES include's level of detail (derivatives x textureSize, GLSL ES having no textureQueryLod) against
// the mip the sampler itself picks: a 256 x 256 texture whose level k holds k, NEAREST_MIPMAP_NEAREST, which
// the GL ES spec (Sec. 8.14.3) reads at level ceil(lambda + 1/2) - 1 (0 for lambda <= 1/2). Isotropic
// footprints in bands of lambda from -1.1 to 7.15, and a receding plane, rotated 30 degrees, with
// anisotropic footprints (the spec's lambda is of the major axis; a GPU may approximate it, SwiftShader
// does not). Pixels within 0.05 of a rounding boundary are not counted.
TEST_F(WebGlShaders, EsLevelOfDetailMatchesTheSamplersMipSelection) {
    if (!have("node")) GTEST_SKIP() << "node is not installed (Debian package nodejs; .ci/setup installs it)";
    specbake("shader --lang glsl-es -o " + quote(root_ / "specaa_es.glsl"));
    const std::string include = slurp(root_ / "specaa_es.glsl");
    const int viewport = 128, levels = 9;
    const char* footprints[][2] = {
        {"isotropic", "vec2 uv = gl_FragCoord.xy * exp2(floor(p.y * 12.0) * 0.75 - 1.1) / 256.0;\n"},
        {"perspective", "float z = 1.0 / (0.04 + 0.96 * p.y);\n"
                        "vec2 uv = mat2(0.866, 0.5, -0.5, 0.866) * vec2((p.x - 0.5) * z, z) * 0.3;\n"}};
    nlohmann::json job = {{"page", "browser_shaders.html"}, {"shaders", nlohmann::json::array()}};
    for (const auto& f : footprints)
        job["shaders"].push_back(
            {{"id", f[0]}, {"vertex", es_shaders::vertex_source()},
             {"lod", {{"size", 256}, {"levels", levels}, {"viewport", viewport}}},
             {"fragment", std::string("#version 300 es\nuniform highp sampler2D uLevels;\n") + include +
                              "out vec4 color;\nvoid main() {\n    vec2 p = gl_FragCoord.xy / " + std::to_string(viewport) +
                              ".0;\n    " + f[1] +
                              "    color = vec4(specaa_texture_lod(uLevels, uv), texture(uLevels, uv).r, 0.0, 1.0);\n}\n"}});
    nlohmann::json result;
    if (!run_browser(job, root_, &result)) return;
    ASSERT_EQ(result["results"].size(), 2u);
    for (const auto& r : result["results"]) {
        const std::string id = r.value("id", "");
        ASSERT_TRUE(r.value("compiled", false) && r.value("linked", false)) << id << "\n" << r["logs"].dump(1);
        ASSERT_EQ(r.value("glError", -1), 0) << id;
        const auto& computed = r["computed"];
        const auto& sampled = r["sampled"];
        ASSERT_EQ(computed.size(), size_t(viewport * viewport));
        int counted = 0, agree = 0, off_by_more = 0;
        double lo = 1e9, hi = -1e9;
        for (size_t i = 0; i < computed.size(); ++i) {
            const double lambda = computed[i].get<double>();
            lo = std::min(lo, lambda), hi = std::max(hi, lambda);
            const double to_boundary = std::abs(lambda - 0.5 - std::round(lambda - 0.5));
            if (to_boundary < 0.05 && lambda > 0.45) continue;
            const int expected = lambda <= 0.5 ? 0 : std::min(levels - 1, int(std::ceil(lambda + 0.5)) - 1);
            ++counted;
            agree += sampled[i].get<int>() == expected;
            off_by_more += std::abs(sampled[i].get<int>() - expected) > 1;
        }
        std::printf("%s: lambda %.2f .. %.2f; the sampler read the level of the include's LOD at %d of %d pixels (%.2f%%)\n",
                    id.c_str(), lo, hi, agree, counted, 100.0 * agree / counted);
        EXPECT_GT(hi - lo, 5.0) << id << ": the footprints do not span the mips";
        EXPECT_EQ(off_by_more, 0) << id;
        EXPECT_EQ(agree, counted) << id;
    }
}

}  // namespace
}  // namespace specbake::consumers
