// The include's hard cases (issue 18): the stability grid of the C++ core (tests/bake/test_stability.cpp:
// alpha 0 ... 1 per axis, h_z from 1 to exactly 0, zero, tiny, huge and mixed derivatives) plus NaN and
// infinities in every input, through every derivative-based method and the default entry points of the
// include, in GLSL and in HLSL (glslangValidator -D -> SPIR-V -> GL_ARB_gl_spirv) on the GL
// implementation (llvmpipe in CI), float32, the default entry points once per SPECAA_QUALITY tier (with the
// tier's default NDF at h). One draw per program: each case is one 2x2 quad of a large
// float framebuffer (tests/gl/shaders/stability_eval.inc). Every output must be finite, a symmetric
// PSD matrix that never reduces the input roughness, and follow the edge policy of the C++ core
// (bake/methods.h), which the core itself is evaluated on for the same float inputs.
#include "gl/gl_harness.h"

#include "bake/methods.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace specbake::gltest {
namespace {

constexpr int kWidth = 1024;  // pixels; 512 quads (cases) per row of quads
constexpr double kTol = 1e-4;  // float32 rounding relative to the matrix scale (as the C++ float grid)
constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

using V3 = Vec3<float>;

struct Case {
    float alpha[2];   // the C++ core's alpha (slope-space roughness)
    float alpha2[2];  // the include's input alpha^2 (NaN and +-inf passed as they are)
    float r;          // perceptual roughness of the default entry point
    float k1;         // curvature of the SPECAA_USE_CURVATURE run
    V3 h, h_dx, h_dy, n, n_dx, n_dy;
};

bool finite3(const V3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// The stability grid of the C++ core (122,880 cases), then NaN/+inf/-inf in each component of each
// input on a smaller base grid.
std::vector<Case> make_cases() {
    const double alphas[] = {0, 1e-7, 1e-4, 0.01, 0.1, 0.5, 0.999, 1};
    const double elevations[] = {1, 0.99, 0.9, 0.5, 0.1, 1e-2, 1e-4, 1e-7, 1e-20, 0};
    const double azimuths[] = {0.0, 0.8, 2.5};
    const Vec3<double> deltas[] = {{0, 0, 0},         {1e-9, 0, 0},     {1e-3, -2e-3, 1e-3}, {0.1, 0.05, -0.1},
                                   {0.5, -0.7, 0.3}, {1e6, 3e5, -1e6}, {1e20, -1e19, 1e20}, {1e-9, 1e6, 0}};
    auto make = [](double ax, double ay, double hz, double phi, const Vec3<double>& du, const Vec3<double>& dv) {
        Case c{};
        c.alpha[0] = float(ax), c.alpha[1] = float(ay);
        c.alpha2[0] = c.alpha[0] * c.alpha[0], c.alpha2[1] = c.alpha[1] * c.alpha[1];
        c.r = std::sqrt(float(ax));
        c.k1 = float(10.0 * length(dv));
        const double s = std::sqrt(1 - hz * hz);
        c.h = {float(s * std::cos(phi)), float(s * std::sin(phi)), float(hz)};
        c.h_dx = {float(c.h.x + du.x), float(c.h.y + du.y), float(c.h.z + du.z)};
        c.h_dy = {float(c.h.x + dv.x), float(c.h.y + dv.y), float(c.h.z + dv.z)};
        c.n = c.h, c.n_dx = c.h_dx, c.n_dy = c.h_dy;
        return c;
    };
    std::vector<Case> cases;
    for (double ax : alphas)
        for (double ay : alphas)
            for (double hz : elevations)
                for (double phi : azimuths)
                    for (const auto& du : deltas)
                        for (const auto& dv : deltas) cases.push_back(make(ax, ay, hz, phi, du, dv));
    for (double ax : alphas)
        for (double ay : {0.01, 0.5})
            for (double hz : {1.0, 0.5, 1e-4})
                for (int d = 0; d < 2; ++d) {
                    const Case base = make(ax, ay, hz, 0.8, deltas[d ? 3 : 0], deltas[d ? 2 : 0]);
                    for (float bad : {kNan, kInf, -kInf}) {
                        for (int field = 0; field < 6; ++field)
                            for (int comp = 0; comp < 3; ++comp) {
                                Case c = base;
                                V3* v[] = {&c.h, &c.h_dx, &c.h_dy, &c.n, &c.n_dx, &c.n_dy};
                                float* x[] = {&v[field]->x, &v[field]->y, &v[field]->z};
                                *x[comp] = bad;
                                cases.push_back(c);
                            }
                        for (int axis = 0; axis < 2; ++axis) {
                            Case c = base;
                            c.alpha[axis] = c.alpha2[axis] = bad;
                            cases.push_back(c);
                        }
                        Case c = base;
                        c.r = bad;
                        cases.push_back(c);
                        c = base;
                        c.k1 = bad;
                        cases.push_back(c);
                    }
                }
    return cases;
}

std::string vertex_shader() { return pass_through_vertex_shader(7, 2); }

// Groups: METHODS, or DEFAULT / CURVATURE with the tier's SPECAA_QUALITY after a slash (e.g. "DEFAULT/1").
std::string defines(const std::string& group) {
    if (group == "METHODS") return "#define SPECAA_TEST_METHODS\n";
    const size_t slash = group.find('/');
    const std::string tier = "#define SPECAA_QUALITY " + group.substr(slash + 1) + "\n";
    return group.substr(0, slash) == "DEFAULT" ? tier + "#define SPECAA_TEST_DEFAULT\n"
                                               : tier + "#define SPECAA_TEST_DEFAULT\n#define SPECAA_USE_CURVATURE\n";
}

std::string fragment_glsl(const std::string& group) {
    return "#version 450\n" + defines(group) + read_source_file("shaders/specaa.glsl") +
           read_source_file("tests/gl/shaders/stability_eval.inc") +
           glsl_fragment_wrapper(7, 5,
                                 "specaa_test_stability(gl_FragCoord.xy, vIn0, vIn1, vIn2, vIn3, vIn4, vIn5, vIn6, "
                                 "o0, o1, o2, o3, o4);");
}

// HLSL's SV_Position has y down: the wrapper turns it back into GL window coordinates.
std::string fragment_hlsl(const std::string& group, int height) {
    return defines(group) + read_source_file("shaders/specaa.hlsl") +
           read_source_file("tests/gl/shaders/stability_eval.inc") +
           hlsl_fragment_wrapper(7, 5, "float4 position : SV_Position, ",
                                 "    specaa_test_stability(float2(position.x, " + std::to_string(height) +
                                     ".0 - position.y), in0, in1, in2, in3, in4, in5, in6, r.o0, r.o1, r.o2, r.o3, r.o4);");
}

constexpr PointGrid kGrid{7, 5, kWidth, 2};

// Draws every case as one 2x2 point and returns, per case, the 20 outputs of its lower-left pixel.
std::vector<std::array<float, 20>> render(GLuint program, const std::vector<Case>& cases, std::string& log) {
    std::vector<float> inputs;
    inputs.reserve(cases.size() * 28);
    for (const Case& c : cases) {
        const float in[28] = {c.alpha2[0], c.alpha2[1], c.r,      c.k1,     c.h.x,    c.h.y,    c.h.z,
                              0,           c.h_dx.x,    c.h_dx.y, c.h_dx.z, 0,        c.h_dy.x, c.h_dy.y,
                              c.h_dy.z,    0,           c.n.x,    c.n.y,    c.n.z,    0,        c.n_dx.x,
                              c.n_dx.y,    c.n_dx.z,    0,        c.n_dy.x, c.n_dy.y, c.n_dy.z, 0};
        inputs.insert(inputs.end(), in, in + 28);
    }
    const std::vector<float> values = evaluate_points(program, inputs, kGrid, log);
    std::vector<std::array<float, 20>> results(values.size() / 20);
    for (size_t i = 0; i < results.size(); ++i) std::copy_n(values.begin() + std::ptrdiff_t(i * 20), 20, results[i].begin());
    return results;
}

// Smallest eigenvalue of a symmetric 2x2 matrix divided by its largest entry's magnitude.
double min_eigenvalue_relative(double xx, double xy, double yy) {
    const double scale = std::max({std::abs(xx), std::abs(xy), std::abs(yy)});
    if (scale == 0.0) return 0.0;
    xx /= scale, xy /= scale, yy /= scale;
    return 0.5 * (xx + yy - std::sqrt((xx - yy) * (xx - yy) + 4 * xy * xy));
}

// Finite, PSD, A_bar - A PSD and det(A_bar) >= det(A) for A = diag(a_xx, a_yy); empty when all hold.
std::string check_matrix(double xx, double xy, double yy, double a_xx, double a_yy) {
    if (!std::isfinite(xx) || !std::isfinite(xy) || !std::isfinite(yy)) return "not finite";
    const double scale = std::max({std::abs(xx), std::abs(xy), std::abs(yy), 1e-30});
    if (min_eigenvalue_relative(xx, xy, yy) < -kTol) return "not positive semi-definite";
    const double escale = std::max({std::abs(xx - a_xx), std::abs(xy), std::abs(yy - a_yy)});
    if (min_eigenvalue_relative(xx - a_xx, xy, yy - a_yy) * escale < -kTol * scale)
        return "below the input roughness (A_bar - A not PSD)";
    if (xx * yy - xy * xy < a_xx * a_yy * (1 - kTol) - kTol * scale * scale) return "det(A_bar) < det(A)";
    return {};
}

std::string describe(const Case& c) {
    std::ostringstream s;
    s.precision(9);
    auto v = [&](const V3& x) { s << "(" << x.x << ", " << x.y << ", " << x.z << ") "; };
    s << "alpha " << c.alpha[0] << "," << c.alpha[1] << " r " << c.r << " k1 " << c.k1 << " h ";
    v(c.h), s << "h_dx ", v(c.h_dx), s << "h_dy ", v(c.h_dy), s << "n ", v(c.n), s << "n_dx ", v(c.n_dx);
    s << "n_dy ", v(c.n_dy);
    return s.str();
}

struct Failures {
    size_t count = 0;
    std::vector<std::string> shown;
    void add(const std::string& what) {
        if (++count <= 12) shown.push_back(what);
    }
};

// The methods, in the order of filter_methods(), and where the include's outputs hold them.
struct MethodSlot {
    const char* name;
    int xx, yy, xy;     // output indices (xy -1: axis-aligned)
    bool uses_normals;  // iso-*: the normal field, else the half-vector field
};
const MethodSlot kSlots[] = {{"slope", 0, 1, 2, false},         {"slope-aa", 3, 4, -1, false},
                             {"projected-approx", 5, 6, 7, false}, {"projected-aa", 8, 9, -1, false},
                             {"projected", 10, 11, 12, false},     {"iso-max", 13, 14, -1, true},
                             {"iso-sum", 15, 16, -1, true},        {"iso-mean", 17, 18, -1, true}};

void check_methods(const std::vector<Case>& cases, const std::vector<std::array<float, 20>>& out, Failures& f) {
    for (size_t i = 0; i < cases.size(); ++i) {
        const Case& c = cases[i];
        for (const MethodSlot& slot : kSlots) {
            const FilterMethod* m = find_filter_method(slot.name);
            // The C++ core on the inputs this entry point takes (the others set to a finite normal).
            FilterInput<float> in;
            in.alpha = {c.alpha[0], c.alpha[1]};
            if (slot.uses_normals) {
                in.n = c.n, in.n_dx = c.n_dx, in.n_dy = c.n_dy;
            } else {
                in.h = c.h, in.h_dx = c.h_dx, in.h_dy = c.h_dy;
            }
            const Sym2<float> core = evaluate(*m, in);
            const double xx = out[i][size_t(slot.xx)], yy = out[i][size_t(slot.yy)];
            const double xy = slot.xy < 0 ? 0.0 : out[i][size_t(slot.xy)];
            auto policy_alpha = [](float a) { return std::isnan(a) ? 1.0f : std::min(std::max(a, 0.0f), 1.0f); };
            const float ax = policy_alpha(c.alpha[0]), ay = policy_alpha(c.alpha[1]);
            std::string e = check_matrix(xx, xy, yy, double(ax * ax), double(ay * ay));
            const bool inputs_finite = slot.uses_normals ? finite3(c.n) && finite3(c.n_dx) && finite3(c.n_dy)
                                                         : finite3(c.h) && finite3(c.h_dx) && finite3(c.h_dy);
            if (e.empty() && !inputs_finite && (xx != core.xx || yy != core.yy || xy != core.xy))
                e = "non-finite input: not the core's unfiltered result";
            if (e.empty() && inputs_finite && !(std::isfinite(c.alpha[0]) && std::isfinite(c.alpha[1]))) {
                const double scale = std::abs(core.xx) + std::abs(core.yy);
                if (std::abs(xx - core.xx) > 1e-3 * scale || std::abs(yy - core.yy) > 1e-3 * scale ||
                    std::abs(xy - core.xy) > 1e-3 * scale)
                    e = "non-finite alpha: differs from the core";
            }
            // Overflow: the core saturates the unclamped methods to I (or, for the full projected filter, reaches
            // I within float rounding); so must the include.
            if (e.empty() && inputs_finite && core.xx == 1 && core.yy == 1 && core.xy == 0 && slot.xy >= 0 &&
                (std::abs(xx - 1) > kTol || std::abs(yy - 1) > kTol || std::abs(xy) > kTol))
                e = "overflow: the core gives I";
            if (!e.empty()) {
                std::ostringstream s;
                s.precision(9);
                s << slot.name << ": " << e << ": [" << xx << " " << xy << " " << yy << "], core [" << core.xx << " "
                  << core.xy << " " << core.yy << "] for " << describe(c);
                f.add(s.str());
            }
        }
    }
}

void check_default(const std::vector<Case>& cases, const std::vector<std::array<float, 20>>& out, bool curvature,
                   Failures& f) {
    for (size_t i = 0; i < cases.size(); ++i) {
        const Case& c = cases[i];
        const float r4 = (c.r * c.r) * (c.r * c.r);
        const float a = std::isnan(r4) ? 1.0f : std::min(std::max(r4, 0.0f), 1.0f);
        const double alpha2 = out[i][0], rough = out[i][1], xx = out[i][2], yy = out[i][3], xy = out[i][4];
        const double D = out[i][5];
        std::string e;
        if (!std::isfinite(alpha2) || alpha2 < a * (1 - kTol) || alpha2 > 1 + kTol)
            e = "filtered a not finite, below the input or above 1";
        else if (!std::isfinite(rough) || std::abs(rough - std::pow(alpha2, 0.25)) > kTol)
            e = "filtered r is not a^(1/4)";
        else
            e = check_matrix(xx, xy, yy, a, a);
        // Non-finite kernel inputs: zero kernel, the unfiltered a (edge policy).
        bool usable;
        if (curvature) {
            const V3 dx = c.h_dx - c.h, dy = c.h_dy - c.h;
            usable = finite3(c.h) && finite3(dx) && finite3(dy) && std::isfinite(c.k1) && std::isfinite(c.n.x) &&
                     std::isfinite(c.n.y);
        } else {
            usable = finite3(c.n) && finite3(c.n_dx - c.n) && finite3(c.n_dy - c.n);
        }
        if (e.empty() && !usable &&
            (std::abs(alpha2 - a) > 1e-6 || std::abs(xx - a) > 1e-6 || std::abs(yy - a) > 1e-6 || xy != 0))
            e = "non-finite input: not the unfiltered a";
        // The NDF takes a unit half vector (its domain): finite and non-negative there, 0 below the horizon.
        if (e.empty() && finite3(c.h) && (!std::isfinite(D) || D < 0 || (c.h.z <= 0 && D != 0)))
            e = "default NDF not finite, negative, or not 0 below the horizon";
        if (!e.empty()) {
            std::ostringstream s;
            s.precision(9);
            s << (curvature ? "default+curvature" : "default") << ": " << e << ": a " << alpha2 << " r " << rough
              << " matrix [" << xx << " " << xy << " " << yy << "] D " << D << " for " << describe(c);
            f.add(s.str());
        }
    }
}

// Runs the three programs built by `build` over the grid and checks every case.
void run_grid(const std::string& language, const std::function<GLuint(const std::string&, int, std::string&)>& build) {
    const std::vector<Case> cases = make_cases();
    ASSERT_GE(cases.size(), 100000u);
    const int height = point_grid_height(kGrid, cases.size());
    // The default entry points once per SPECAA_QUALITY tier (fast 0, balanced 1, reference 2).
    for (const std::string group : {"METHODS", "DEFAULT/0", "DEFAULT/1", "DEFAULT/2", "CURVATURE/0", "CURVATURE/1",
                                    "CURVATURE/2"}) {
        std::string log;
        const GLuint program = build(group, height, log);
        ASSERT_NE(program, 0u) << group << ": " << log;
        const auto out = render(program, cases, log);
        glDeleteProgram(program);
        ASSERT_EQ(out.size(), cases.size()) << group << ": " << log;
        Failures f;
        if (group == "METHODS")
            check_methods(cases, out, f);
        else
            check_default(cases, out, group.rfind("CURVATURE", 0) == 0, f);
        for (const auto& s : f.shown) ADD_FAILURE() << language << " " << s;
        EXPECT_EQ(f.count, 0u) << language << " " << group << ": " << f.count << " failures";
        std::printf("%s %s: %zu cases checked\n", language.c_str(), group.c_str(), cases.size());
    }
}

TEST(ShaderStability, GlslGridFiniteSymmetricPsdAndPolicy) {
    SPECBAKE_REQUIRE_GL(gl);
    run_grid("GLSL", [](const std::string& group, int, std::string& log) {
        return build_program_glsl(vertex_shader(), fragment_glsl(group), log);
    });
}

TEST(ShaderStability, HlslGridThroughGlSpirvFiniteSymmetricPsdAndPolicy) {
    SPECBAKE_REQUIRE_GL(gl);
    if (!gl->has_extension("GL_ARB_gl_spirv"))
        GTEST_SKIP() << gl->renderer() << " lacks GL_ARB_gl_spirv: HLSL is only compile-tested (ShaderCompile)";
    TempDir dir;
    std::string out;
    const auto vertex = compile_vertex_spirv(vertex_shader(), dir.path() / "stability.vert", out);
    ASSERT_FALSE(vertex.empty()) << out;
    run_grid("HLSL", [&](const std::string& group, int height, std::string& log) -> GLuint {
        std::string file = group;
        std::replace(file.begin(), file.end(), '/', '_');
        return build_program_hlsl_spirv(vertex, fragment_hlsl(group, height), dir.path() / file, log);
    });
}

}  // namespace
}  // namespace specbake::gltest
