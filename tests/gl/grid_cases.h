// Input grids for the include's functions and their C++ references (the filtering core of bake/ in
// double, or independent double computations where the core has no counterpart). Shared by the GLSL
// run (test_shader_functions.cpp) and the HLSL-through-SPIR-V run (test_shader_hlsl_spirv.cpp).
#pragma once

#include "gl/gl_harness.h"

#include <functional>
#include <string>
#include <vector>

namespace specbake::gltest {

// Float tolerance of a GPU value against the double reference: |gpu - ref| <= kRelTol |ref| + kAbsTol.
// The include evaluates each function in at most ~30 single-precision operations without catastrophic
// cancellation (GLSL allows 2.5 ulp per division, sqrt is exact or ~3 ulp); 4e-5 covers ~300 ulp of
// accumulated rounding. kAbsTol only admits rounding of results that are exactly 0 in double.
inline constexpr double kRelTol = 4e-5;
inline constexpr double kAbsTol = 1e-12;

struct GridGroup {
    std::string name;  // SPECAA_TEST_<name> in grid_eval.inc
    std::vector<GridCase> cases;
    // Empty when the GPU result matches the reference, else a description of the mismatch.
    std::function<std::string(const GridCase&, const GridResult&)> check;
};

// Every group: KERNELS, ISOTROPIC, GGX, BAKED, NORMAL, MATRIX, CURVATURE.
std::vector<GridGroup> grid_groups();

// Runs every group with programs from `build` (GLSL or SPIR-V) and returns the failures (at most a few
// per group, with the case count) or an empty list. `evaluated` counts the compared cases.
std::vector<std::string> run_grid_groups(const std::function<GLuint(const std::string& group, std::string& log)>& build,
                                         size_t& evaluated);

}  // namespace specbake::gltest
