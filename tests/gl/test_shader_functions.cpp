// (a) Every function of the GLSL include evaluated on grids of inputs (edge cases included) in fragment
// shaders on a real OpenGL 4.5 implementation, read back and compared with the C++ core in double
// (tolerance: grid_cases.h).
#include "gl/grid_cases.h"

#include <gtest/gtest.h>

namespace specbake::gltest {
namespace {

TEST(ShaderFunctions, GlslGridMatchesCppCore) {
    SPECBAKE_REQUIRE_GL(gl);
    size_t evaluated = 0;
    const auto failures = run_grid_groups(
        [](const std::string& group, std::string& log) {
            return build_program_glsl(grid_vertex_shader(), grid_fragment_glsl(group), log);
        },
        evaluated);
    for (const auto& f : failures) ADD_FAILURE() << f;
    EXPECT_GT(evaluated, 4000u);
    std::printf("%zu cases compared on %s\n", evaluated, gl->renderer().c_str());
}

}  // namespace
}  // namespace specbake::gltest
