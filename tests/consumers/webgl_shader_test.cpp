// The GLSL ES 3.00 include (`specbake shader --lang glsl-es`) in Chromium's WebGL 2 (ANGLE's translator,
// then its Vulkan backend on SwiftShader): every entry point, binding and configuration macro the docs list
// (tests/gl/es_shader_source.h, the shaders glslang compiles in tests/gl/test_shader_es.cpp) compiles,
// links and draws without a GL error; deliberately broken variants of the include are rejected, so the
// check can fail. The page is browser_shaders.mjs.
#include "consumer_harness.h"

#include "gl/es_shader_source.h"

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

}  // namespace
}  // namespace specbake::consumers
