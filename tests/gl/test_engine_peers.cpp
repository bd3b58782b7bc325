// The simulator's engine peer rows (verify/engine_peers.h) against their C++ twins (bake/peers.h): the same
// GLSL the candidates compile, evaluated on a grid of roughness and normal derivatives on a real OpenGL
// implementation, read back and compared in double. Cases cover every branch: below and at each limit,
// the floors and the caps.
#include "bake/peers.h"
#include "gl/gl_harness.h"
#include "verify/engine_peers.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace specbake::gltest {
namespace {

TEST(EnginePeersGlsl, MatchTheirCppTwins) {
    SPECBAKE_REQUIRE_GL(gl);
    struct Case {
        double r;
        Vec3<double> dx, dy;
    };
    std::vector<Case> cases;
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (double r : {0.0, 0.01, 0.0525, 0.1, 0.3, 0.7, 0.95, 1.0})
        for (double scale : {0.0, 1e-3, 0.05, 0.2, 0.6, 1.5})
            for (int k = 0; k < 8; ++k) {
                const auto v = [&] { return Vec3<double>{scale * (2 * unit(rng) - 1), scale * (2 * unit(rng) - 1), scale * (2 * unit(rng) - 1)}; };
                cases.push_back({r, v(), v()});
            }
    const PointGrid grid{3, 1, 64, 1};
    std::vector<float> inputs;
    for (const Case& c : cases) {
        const float in[12] = {float(c.r), float(c.r * c.r * c.r * c.r), 0, 0, float(c.dx.x), float(c.dx.y),
                              float(c.dx.z), 0, float(c.dy.x), float(c.dy.y), float(c.dy.z), 0};
        inputs.insert(inputs.end(), in, in + 12);
    }
    const std::string fragment =
        std::string("#version 450 core\n") + verify::kEnginePeersGlsl +
        glsl_fragment_wrapper(3, 1,
                              "    o0 = vec4(peer_godot_alpha2(vIn0.x, vIn1.xyz, vIn2.xyz),\n"
                              "              peer_unity_alpha2(vIn0.y, vIn1.xyz, vIn2.xyz),\n"
                              "              peer_threejs_alpha2(vIn0.x, vIn1.xyz, vIn2.xyz),\n"
                              "              peer_babylon_alpha2(vIn0.x, vIn1.xyz, vIn2.xyz));");
    std::string log;
    const GLuint program = build_program_glsl(pass_through_vertex_shader(3, 1), fragment, log);
    ASSERT_NE(program, 0u) << log;
    const std::vector<float> out = evaluate_points(program, inputs, grid, log);
    glDeleteProgram(program);
    ASSERT_EQ(out.size(), cases.size() * 4) << log;
    for (size_t i = 0; i < cases.size(); ++i) {
        // The twins in double from the same float inputs the shader saw.
        const double r = double(float(cases[i].r)), a = double(float(cases[i].r * cases[i].r * cases[i].r * cases[i].r));
        const Vec3<double> dx{double(float(cases[i].dx.x)), double(float(cases[i].dx.y)), double(float(cases[i].dx.z))};
        const Vec3<double> dy{double(float(cases[i].dy.x)), double(float(cases[i].dy.y)), double(float(cases[i].dy.z))};
        const double expected[4] = {godot_limiter_alpha2(r, dx, dy), unity_geometric_aa_alpha2(a, dx, dy),
                                    threejs_geometry_roughness_alpha2(r, dx, dy), babylon_specular_aa_alpha2(r, dx, dy)};
        for (int k = 0; k < 4; ++k)
            EXPECT_NEAR(out[4 * i + k], expected[k], 2e-6 + 2e-5 * std::abs(expected[k]))
                << "peer " << k << " case " << i << " r " << r;
    }
}

}  // namespace
}  // namespace specbake::gltest
