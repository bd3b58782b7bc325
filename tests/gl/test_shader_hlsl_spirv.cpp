// (c) The HLSL include, compiled to SPIR-V by glslangValidator (-D), validated by spirv-val and run through
// GL_ARB_gl_spirv on the same OpenGL implementation: the grids of test (a) in HLSL, compared with the
// C++ core with the same tolerance.
#include "gl/grid_cases.h"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

namespace specbake::gltest {
namespace {

std::vector<char> read_binary(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(ShaderHlslSpirv, HlslGridMatchesCppCoreThroughGlSpirv) {
    SPECBAKE_REQUIRE_GL(gl);
    if (!gl->has_extension("GL_ARB_gl_spirv"))
        GTEST_SKIP() << gl->renderer() << " lacks GL_ARB_gl_spirv: HLSL is only compile-tested (ShaderCompile)";
    std::string out;
    if (run_command("command -v glslangValidator && command -v spirv-val", out) != 0)
        FAIL() << "missing shader tools (Debian glslang-tools, spirv-tools)";
    TempDir dir;
    const auto vert_src = dir.path() / "grid.vert", vert_spv = dir.path() / "grid.vert.spv";
    std::ofstream(vert_src) << grid_vertex_shader();
    ASSERT_EQ(run_command("glslangValidator -G -S vert '" + vert_src.string() + "' -o '" + vert_spv.string() + "'", out), 0)
        << out;
    const auto vertex = read_binary(vert_spv);

    size_t evaluated = 0;
    const auto failures = run_grid_groups(
        [&](const std::string& group, std::string& log) -> GLuint {
            const auto src = dir.path() / (group + ".hlsl"), spv = dir.path() / (group + ".spv");
            std::ofstream(src) << grid_fragment_hlsl(group);
            std::string text;
            if (run_command("glslangValidator -V -D -e main -S frag '" + src.string() + "' -o '" + spv.string() +
                                "' && spirv-val '" + spv.string() + "'",
                            text) != 0) {
                log += "glslangValidator/spirv-val: " + text;
                return 0;
            }
            return build_program_spirv(vertex, read_binary(spv), log);
        },
        evaluated);
    for (const auto& f : failures) ADD_FAILURE() << f;
    EXPECT_GT(evaluated, 4000u);
    std::printf("%zu HLSL cases compared through GL_ARB_gl_spirv on %s\n", evaluated, gl->renderer().c_str());
}

}  // namespace
}  // namespace specbake::gltest
