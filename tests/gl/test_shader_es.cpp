// The GLSL ES 3.00 (WebGL 2) include, as `specbake shader --lang glsl-es` writes it, compiles and links
// with glslang in its ES profile for every entry point, binding and configuration macro the docs list
// (tests/gl/es_shader_source.h), and with the OpenGL driver's own ES 3.00 compiler; deliberately broken
// variants (the desktop include, a textureQueryLod LOD path) are rejected. Chromium's WebGL 2 compiles
// the same shaders in tests/consumers/webgl_shader_test.cpp.
#include "gl/es_shader_source.h"
#include "gl/gl_harness.h"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

namespace specbake::gltest {
namespace {

std::string es_include() {
    TempDir dir;
    const auto file = dir.path() / "specaa_es.glsl";
    std::string out;
    if (run_command(std::string("'") + SPECBAKE_EXE + "' shader --lang glsl-es -o '" + file.string() + "'", out) != 0)
        return {};
    return es_shaders::read_text(file.string());
}

// glslangValidator's verdict on a vertex + fragment pair, linked (-l); the stage comes from the extension.
int glslang_link(const TempDir& dir, const std::string& fragment, std::string& log) {
    const auto vert = dir.path() / "es.vert", frag = dir.path() / "es.frag";
    std::ofstream(vert) << es_shaders::vertex_source();
    std::ofstream(frag) << fragment;
    return run_command("glslangValidator -l '" + vert.string() + "' '" + frag.string() + "'", log);
}

TEST(ShaderEs, EveryEntryPointAndBindingCompilesAndLinksWithGlslangAsEs) {
    std::string out;
    if (run_command("command -v glslangValidator", out) != 0) FAIL() << "glslangValidator is missing (Debian glslang-tools)";
    const std::string include = es_include();
    ASSERT_FALSE(include.empty()) << "specbake shader --lang glsl-es wrote nothing";
    EXPECT_EQ(include, read_source_file("shaders/specaa_es.glsl"));
    const std::string entries = read_source_file("shaders/cost/entries.inc");
    const auto variants = es_shaders::all_variants(SPECBAKE_SOURCE_DIR);
    ASSERT_GE(variants.size(), 34u + 16u);
    TempDir dir;
    for (const auto& v : variants) {
        std::string log;
        EXPECT_EQ(glslang_link(dir, es_shaders::fragment_source(include, entries, v), log), 0) << v.name << "\n" << log;
    }
}

TEST(ShaderEs, BrokenVariantsAreRejectedByGlslang) {
    std::string out;
    if (run_command("command -v glslangValidator", out) != 0) FAIL() << "glslangValidator is missing (Debian glslang-tools)";
    const std::string include = es_include();
    ASSERT_FALSE(include.empty());
    const std::string entries = read_source_file("shaders/cost/entries.inc");
    const auto broken = es_shaders::broken_variants(include, read_source_file("shaders/specaa.glsl"));
    ASSERT_EQ(broken.size(), 2u);
    TempDir dir;
    std::string log;
    ASSERT_NE(broken[1].include, include) << "the LOD guard the broken variant replaces is gone";
    EXPECT_NE(glslang_link(dir, es_shaders::fragment_source(broken[0].include, entries, broken[0].variant), log), 0);
    EXPECT_NE(log.find("default precision"), std::string::npos) << log;
    EXPECT_NE(glslang_link(dir, es_shaders::fragment_source(broken[1].include, entries, broken[1].variant), log), 0);
    EXPECT_NE(log.find("textureQueryLod"), std::string::npos) << log;
}

// The driver's ES 3.00 compiler (ARB_ES3_compatibility; Mesa in CI) on the same shaders: a second,
// independent front end.
TEST(ShaderEs, EveryEntryPointAndBindingCompilesWithTheDriverAsEs300) {
    SPECBAKE_REQUIRE_GL(ctx);
    if (!ctx->has_extension("GL_ARB_ES3_compatibility"))
        GTEST_SKIP() << "the driver has no GL_ARB_ES3_compatibility (" << ctx->renderer() << ")";
    const std::string include = es_include();
    ASSERT_FALSE(include.empty());
    const std::string entries = read_source_file("shaders/cost/entries.inc");
    auto vertex = verify::compile_glsl_shader(GL_VERTEX_SHADER, es_shaders::vertex_source());
    ASSERT_TRUE(vertex.ok()) << vertex.error().message;
    for (const auto& v : es_shaders::all_variants(SPECBAKE_SOURCE_DIR)) {
        auto fragment = verify::compile_glsl_shader(GL_FRAGMENT_SHADER, es_shaders::fragment_source(include, entries, v));
        ASSERT_TRUE(fragment.ok()) << v.name << "\n" << fragment.error().message;
        auto linked = verify::link_program(*vertex, *fragment);
        EXPECT_TRUE(linked.ok()) << v.name << "\n" << (linked.ok() ? "" : linked.error().message);
        if (linked.ok()) glDeleteProgram(*linked);
        glDeleteShader(*fragment);
    }
    glDeleteShader(*vertex);
    for (const auto& b : es_shaders::broken_variants(include, read_source_file("shaders/specaa.glsl"))) {
        auto fragment = verify::compile_glsl_shader(GL_FRAGMENT_SHADER, es_shaders::fragment_source(b.include, entries, b.variant));
        EXPECT_FALSE(fragment.ok()) << b.name;
        if (fragment.ok()) glDeleteShader(*fragment);
    }
}

}  // namespace
}  // namespace specbake::gltest
