// (c) The HLSL include, compiled to SPIR-V by glslangValidator (-D), validated by spirv-val and run through
// GL_ARB_gl_spirv on the same OpenGL implementation: the grids of test (a) in HLSL, compared with the
// C++ core with the same tolerance.
#include "gl/grid_cases.h"

#include <gtest/gtest.h>

namespace specbake::gltest {
namespace {

TEST(ShaderHlslSpirv, HlslGridMatchesCppCoreThroughGlSpirv) {
    SPECBAKE_REQUIRE_GL(gl);
    if (!gl->has_extension("GL_ARB_gl_spirv"))
        GTEST_SKIP() << gl->renderer() << " lacks GL_ARB_gl_spirv: HLSL is only compile-tested (ShaderCompile)";
    std::string out;
    if (run_command("command -v glslangValidator && command -v spirv-val", out) != 0)
        FAIL() << "missing shader tools (Debian glslang-tools, spirv-tools)";
    TempDir dir;
    const auto vertex = compile_vertex_spirv(grid_vertex_shader(), dir.path() / "grid.vert", out);
    ASSERT_FALSE(vertex.empty()) << out;

    size_t evaluated = 0;
    const auto failures = run_grid_groups(
        [&](const std::string& group, std::string& log) -> GLuint {
            return build_program_hlsl_spirv(vertex, grid_fragment_hlsl(group), dir.path() / group, log);
        },
        evaluated);
    for (const auto& f : failures) ADD_FAILURE() << f;
    EXPECT_GT(evaluated, 4000u);
    std::printf("%zu HLSL cases compared through GL_ARB_gl_spirv on %s\n", evaluated, gl->renderer().c_str());
}

}  // namespace
}  // namespace specbake::gltest
