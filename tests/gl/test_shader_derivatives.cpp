// (b) The derivative paths of the GLSL include on rendered analytic surfaces: a sphere and a cylinder are
// ray cast per pixel in a fragment shader (exact normals, no tessellation), the include's derivative-based
// methods run on the 2x2 quads, and the results are compared with the kernels built in double from the
// closed-form surface at the pixel centres of the same quad (llvmpipe: ddx = f(x|1, y) - f(x&~1, y),
// coarse equals fine), including pixels at grazing view and half-vector angles near the silhouettes.
// Runs the GLSL include and, through glslangValidator -D and GL_ARB_gl_spirv, the HLSL include.
#include "gl/gl_harness.h"

#include "bake/constants.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>

namespace specbake::gltest {
namespace {

constexpr int kSize = 128;
constexpr double kTanHalfFov = 0.45;
constexpr double kCenterZ = -4.0;
constexpr double kSphereRadius = 1.5;
constexpr double kCylinderRadius = 1.0;
constexpr double kSigma2 = kDefaultSigma2;
constexpr double kKappa = kDefaultKappa;
// Float ray casting and 1-pixel differences: ~1e-5 relative noise on the normals' differences, amplified
// near the silhouette; 1e-3 leaves margin while a wrong factor, space or derivative axis is far outside.
constexpr double kTol = 1e-3;

struct D3 {
    double x, y, z;
};
D3 operator+(D3 a, D3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
D3 operator-(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
D3 operator*(double s, D3 a) { return {s * a.x, s * a.y, s * a.z}; }
double dot(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
D3 cross(D3 a, D3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
D3 normalize(D3 a) { return (1.0 / std::sqrt(dot(a, a))) * a; }

const D3 kLight = normalize(D3{0.8, 0.3, 0.6});

// Closed-form surface sample at the centre of pixel (x, y) (window coordinates, y up).
struct Sample {
    D3 p, n, t, b;  // hit point, outward normal, tangent frame (T, B)
    D3 h;           // tangent-space half vector (h.T, h.B, h.n)
    D3 v;           // direction to the eye
    D3 r;           // mirror direction of the view, 2 (n.v) n - v
    double n_dot_v;
};

std::optional<Sample> trace(int surface, int x, int y) {
    const D3 d = normalize({((x + 0.5) / kSize * 2.0 - 1.0) * kTanHalfFov, ((y + 0.5) / kSize * 2.0 - 1.0) * kTanHalfFov, -1.0});
    const D3 c{0.0, 0.0, kCenterZ};
    Sample s{};
    if (surface == 0) {
        // |t d - c|^2 = R^2
        const double bq = dot(d, c), cq = dot(c, c) - kSphereRadius * kSphereRadius, disc = bq * bq - cq;
        if (disc < 0) return std::nullopt;
        s.p = (bq - std::sqrt(disc)) * d;
        s.n = (1.0 / kSphereRadius) * (s.p - c);
        s.t = normalize(cross(D3{0, 1, 0}, s.n));
        s.b = cross(s.n, s.t);
    } else {
        // Cylinder along y: (t d - c) projected on xz has length R.
        const double a = d.x * d.x + d.z * d.z, bq = d.x * c.x + d.z * c.z;
        const double cq = c.x * c.x + c.z * c.z - kCylinderRadius * kCylinderRadius, disc = bq * bq - a * cq;
        if (disc < 0) return std::nullopt;
        s.p = ((bq - std::sqrt(disc)) / a) * d;
        s.n = (1.0 / kCylinderRadius) * D3{s.p.x - c.x, 0.0, s.p.z - c.z};
        s.b = {0, 1, 0};
        s.t = cross(s.b, s.n);
    }
    const D3 v = -1.0 * d;
    const D3 hw = normalize(v + kLight);
    s.h = {dot(hw, s.t), dot(hw, s.b), dot(hw, s.n)};
    s.v = v;
    s.n_dot_v = dot(s.n, v);
    s.r = 2.0 * s.n_dot_v * s.n - v;
    return s;
}

// The surface shader (tests/gl/shaders/surface_eval.inc) wrapped for GLSL and for HLSL. HLSL's
// SV_Position has y down (Vulkan origin), so its wrapper flips y back to the GL window convention.
std::string surface_glsl(int surface, bool environment = false) {
    return "#version 450\n#define SPECAA_TEST_SURFACE " + std::to_string(surface) + "\n" +
           (environment ? "#define SPECAA_TEST_ENVIRONMENT\n" : "") +
           read_source_file("shaders/specaa.glsl") + read_source_file("tests/gl/shaders/surface_eval.inc") + R"(
layout(location = 0) out vec4 o0;
layout(location = 1) out vec4 o1;
layout(location = 2) out vec4 o2;
layout(location = 3) out vec4 o3;
void main() { specaa_test_surface(gl_FragCoord.xy, o0, o1, o2, o3); }
)";
}

std::string surface_hlsl(int surface) {
    return "#define SPECAA_TEST_SURFACE " + std::to_string(surface) + "\n" + read_source_file("shaders/specaa.hlsl") +
           read_source_file("tests/gl/shaders/surface_eval.inc") + R"(
struct SurfaceOutput {
    float4 o0 : SV_Target0;
    float4 o1 : SV_Target1;
    float4 o2 : SV_Target2;
    float4 o3 : SV_Target3;
};
SurfaceOutput main(float4 position : SV_Position) {
    SurfaceOutput r;
    specaa_test_surface(float2(position.x, 128.0 - position.y), r.o0, r.o1, r.o2, r.o3);
    return r;
}
)";
}

const char* kFullscreenVertex = "#version 450\nvoid main() { vec2 q = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);"
                                " gl_Position = vec4(q * 2.0 - 1.0, 0.0, 1.0); }\n";

struct Kernel2 {
    double xx, yy, xy;
};
Kernel2 kernel(double ux, double uy, double vx, double vy) {
    return {2 * kSigma2 * (ux * ux + vx * vx), 2 * kSigma2 * (uy * uy + vy * vy), 2 * kSigma2 * (ux * uy + vx * vy)};
}

bool near(double gpu, double ref, double scale) { return std::abs(gpu - ref) <= kTol * scale + 1e-9; }
bool near_sym(const float* gpu, const Kernel2& k) {
    const double s = std::abs(k.xx) + std::abs(k.yy);
    return near(gpu[0], k.xx, s) && near(gpu[1], k.yy, s) && near(gpu[2], k.xy, s);
}

// The closed-form samples of pixel (x, y) and of the quad pixels its ddx / ddy difference, or nothing where one
// misses the surface or lies within a hair of the silhouette (float ray casting is ill-conditioned there).
struct QuadSamples {
    Sample s0x, s1x, s0y, s1y, s;
};
std::optional<QuadSamples> quad_samples(int surface, int x, int y) {
    const auto s0x = trace(surface, x & ~1, y), s1x = trace(surface, x | 1, y);
    const auto s0y = trace(surface, x, y & ~1), s1y = trace(surface, x, y | 1);
    const auto s = trace(surface, x, y);
    if (!s0x || !s1x || !s0y || !s1y || !s) return std::nullopt;
    if (std::min({s0x->n_dot_v, s1x->n_dot_v, s0y->n_dot_v, s1y->n_dot_v}) < 0.02) return std::nullopt;
    return QuadSamples{*s0x, *s1x, *s0y, *s1y, *s};
}

// Draws one viewport-covering triangle with `program` (already linked; deleted afterwards) into four float
// targets and reads them back (RGBA per pixel, rows bottom to top).
std::array<std::vector<float>, 4> render_targets(GLuint program) {
    std::array<std::vector<float>, 4> out;
    GLuint vao = 0, targets[4] = {};
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    const GLuint fbo = create_float_targets(4, kSize, kSize, targets);
    EXPECT_EQ(glCheckFramebufferStatus(GL_FRAMEBUFFER), static_cast<GLenum>(GL_FRAMEBUFFER_COMPLETE));
    glViewport(0, 0, kSize, kSize);
    glUseProgram(program);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    for (int i = 0; i < 4; ++i) {
        out[size_t(i)].resize(kSize * kSize * 4);
        glReadBuffer(GL_COLOR_ATTACHMENT0 + GLenum(i));
        glReadPixels(0, 0, kSize, kSize, GL_RGBA, GL_FLOAT, out[size_t(i)].data());
    }
    EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
    glDeleteTextures(4, targets);
    glDeleteFramebuffers(1, &fbo);
    glDeleteVertexArrays(1, &vao);
    glDeleteProgram(program);
    return out;
}

// Renders `surface` with `program` (already linked) and compares every pixel with the closed form.
void render_and_compare(GLuint program, int surface, const char* name) {
    const auto out = render_targets(program);

    int compared = 0, grazing = 0, failures = 0, curvature_checked = 0, slope_skipped = 0;
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            // The quad differences this pixel's ddx/ddy use.
            const auto q = quad_samples(surface, x, y);
            if (!q) continue;
            const Sample *s0x = &q->s0x, *s1x = &q->s1x, *s0y = &q->s0y, *s1y = &q->s1y, *s = &q->s;
            const size_t i = static_cast<size_t>(y * kSize + x) * 4;
            if (out[0][i + 3] != 1.0f) {
                if (++failures <= 5) ADD_FAILURE() << name << " (" << x << ", " << y << "): GPU missed a closed-form hit";
                continue;
            }
            const D3 dnu = s1x->n - s0x->n, dnv = s1y->n - s0y->n;
            const double g11 = dot(dnu, dnu), g22 = dot(dnv, dnv), g12 = dot(dnu, dnv);
            const double mean = kSigma2 * (g11 + g22), sum = 2 * mean;
            const double lmax = 0.5 * (g11 + g22) + std::hypot(0.5 * (g11 - g22), g12);
            const double iso[3] = {std::min(mean, kKappa), std::min(sum, kKappa), std::min(2 * kSigma2 * lmax, kKappa)};
            // Half-vector derivatives in the (moving) tangent frame of each pixel, projected and slope space.
            const D3 hu = s1x->h - s0x->h, hv = s1y->h - s0y->h;
            const Kernel2 proj = kernel(hu.x, hu.y, hv.x, hv.y);
            auto slope = [](const D3& h) { return std::pair{h.x / -std::abs(h.z), h.y / -std::abs(h.z)}; };
            const auto [a0x, a0y] = slope(s0x->h);
            const auto [a1x, a1y] = slope(s1x->h);
            const auto [b0x, b0y] = slope(s0y->h);
            const auto [b1x, b1y] = slope(s1y->h);
            const Kernel2 slp = kernel(a1x - a0x, a1y - a0y, b1x - b0x, b1y - b0y);
            const double bx = std::abs(hu.x) + std::abs(hv.x), by = std::abs(hu.y) + std::abs(hv.y);
            const double paa[2] = {std::min(2 * kSigma2 * bx * bx, kKappa), std::min(2 * kSigma2 * by * by, kKappa)};
            // Curvature kernel: footprint = position differences in this pixel's (T, B); S from the closed form.
            const D3 pu = s1x->p - s0x->p, pv = s1y->p - s0y->p;
            const double ut = dot(pu, s->t), ub = dot(pu, s->b), vt = dot(pv, s->t), vb = dot(pv, s->b);
            const double k1 = surface == 0 ? 1 / kSphereRadius : 1 / kCylinderRadius, k2 = surface == 0 ? k1 : 0.0;
            const Kernel2 curv = kernel(k1 * ut, k2 * ub, k1 * vt, k2 * vb);

            bool ok = true;
            for (int m = 0; m < 3; ++m) ok &= near(out[0][i + m], iso[m], iso[m]);
            ok &= near_sym(&out[1][i], proj);
            // Slope space amplifies the float noise of h by det J = 1/h_z^3 (TK21 Sec. 3): compared only
            // where the quad's half vectors are at least ~87 degrees from grazing, projected space everywhere.
            const double hz_min = std::min({std::abs(s0x->h.z), std::abs(s1x->h.z), std::abs(s0y->h.z), std::abs(s1y->h.z)});
            if (hz_min >= 0.05) ok &= near_sym(&out[2][i], slp);
            else ++slope_skipped;
            ok &= near(out[1][i + 3], paa[0], paa[0]) && near(out[2][i + 3], paa[1], paa[1]);
            ok &= near_sym(&out[3][i], curv);
            if (!ok && ++failures <= 5)
                ADD_FAILURE() << name << " pixel (" << x << ", " << y << ") n.v " << s->n_dot_v << ": iso gpu "
                              << out[0][i] << " " << out[0][i + 1] << " " << out[0][i + 2] << " ref " << iso[0] << " "
                              << iso[1] << " " << iso[2] << "; projected gpu " << out[1][i] << " " << out[1][i + 1]
                              << " " << out[1][i + 2] << " ref " << proj.xx << " " << proj.yy << " " << proj.xy
                              << "; slope gpu " << out[2][i] << " " << out[2][i + 1] << " " << out[2][i + 2] << " ref "
                              << slp.xx << " " << slp.yy << " " << slp.xy << "; curvature gpu " << out[3][i] << " "
                              << out[3][i + 1] << " " << out[3][i + 2] << " ref " << curv.xx << " " << curv.yy << " "
                              << curv.xy;
            ++compared;
            if (s->n_dot_v < 0.3) ++grazing;
            // Where the footprint is small against the radius, the curvature kernel and the normal-difference
            // kernel describe the same normal spread: tr(K_curv) / 2 = sigma^2 (|dn_u|^2 + |dn_v|^2)
            // (first order; the chord's normal component makes the difference second order).
            const double reach = std::sqrt(std::max(dot(pu, pu), dot(pv, pv))) * k1;
            if (reach < 0.05) {
                const double tr = 0.5 * (out[3][i] + out[3][i + 1]);
                if (std::abs(tr - mean) > 4.0 * reach * reach * mean + 1e-9 && ++failures <= 5)
                    ADD_FAILURE() << name << " pixel (" << x << ", " << y << "): curvature kernel trace/2 " << tr
                                  << " vs normal-difference kernel " << mean;
                ++curvature_checked;
            }
        }
    EXPECT_EQ(failures, 0) << name << ": " << failures << " of " << compared << " pixels differ";
    EXPECT_GT(compared, kSize * kSize / 8) << name;
    EXPECT_GT(grazing, 100) << name << ": too few grazing pixels";
    EXPECT_GT(curvature_checked, 100) << name;
    std::printf("%s: %d pixels compared, %d at n.v < 0.3, %d curvature/derivative cross-checks, slope space "
                "skipped at %d pixels with h.z < 0.05\n", name, compared, grazing, curvature_checked, slope_skipped);
}

// specaa_environment_kernel on the ray-cast surfaces against the closed-form mirror direction r = 2 (n.v) n - v
// at the pixel centres of the quad: per screen axis half the quad's difference of r, less its part along this
// pixel's r, kernel sigma^2 (|e_x|^2 + |e_y|^2) clamped to kappa; a = 1/16 widened by it in projected space
// (TK21 Eq. 6-7: (a + k (1 - a)) / (1 + k (1 - a))); with s.view zero, the normal's kernel (iso-mean).
void environment_compare(int surface, const char* name) {
    SPECBAKE_REQUIRE_GL(gl);
    std::string log;
    const GLuint program = build_program_glsl(kFullscreenVertex, surface_glsl(surface, true), log);
    ASSERT_NE(program, 0u) << log;
    const std::vector<float> out = render_targets(program)[0];
    int compared = 0, grazing = 0, failures = 0, clamped = 0;
    double widest_ratio = 0;  // the highlight's kernel (with the half vector's turn) over the environment's
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            const auto q = quad_samples(surface, x, y);
            if (!q) continue;
            const size_t i = static_cast<size_t>(y * kSize + x) * 4;
            D3 ex = 0.5 * (q->s1x.r - q->s0x.r), ey = 0.5 * (q->s1y.r - q->s0y.r);
            ex = ex - dot(ex, q->s.r) * q->s.r;
            ey = ey - dot(ey, q->s.r) * q->s.r;
            const double k = std::min(kSigma2 * (dot(ex, ex) + dot(ey, ey)), kKappa);
            const double a = 1.0 / 16.0, kk = k * (1.0 - a), alpha2 = (a + kk) / (1.0 + kk);
            const D3 dnu = q->s1x.n - q->s0x.n, dnv = q->s1y.n - q->s0y.n;
            const double normal_kernel = std::min(kSigma2 * (dot(dnu, dnu) + dot(dnv, dnv)), kKappa);
            const bool ok = near(out[i], k, k) && near(out[i + 1], alpha2, alpha2) && near(out[i + 2], normal_kernel, normal_kernel);
            if (!ok && ++failures <= 5)
                ADD_FAILURE() << name << " pixel (" << x << ", " << y << ") n.v " << q->s.n_dot_v << ": environment kernel gpu "
                              << out[i] << " ref " << k << ", a gpu " << out[i + 1] << " ref " << alpha2
                              << ", with no view gpu " << out[i + 2] << " ref " << normal_kernel;
            ++compared;
            if (q->s.n_dot_v < 0.3) ++grazing;
            if (k >= kKappa) ++clamped;
            // The highlight's kernel with the half vector's turn, tangential dv / (2 n.v) taken off dn (the default's).
            const auto turn = [&](const Sample& s0, const Sample& s1) {
                const D3 dv = s1.v - s0.v;
                return (0.5 / q->s.n_dot_v) * (dv - dot(dv, q->s.n) * q->s.n);
            };
            const D3 hx = dnu - turn(q->s0x, q->s1x), hy = dnv - turn(q->s0y, q->s1y);
            const double highlight = kSigma2 * (dot(hx, hx) + dot(hy, hy));
            if (k > 0 && k < kKappa) widest_ratio = std::max(widest_ratio, highlight / k);
        }
    EXPECT_EQ(failures, 0) << name << ": " << failures << " of " << compared << " pixels differ";
    EXPECT_GT(compared, kSize * kSize / 8) << name;
    EXPECT_GT(grazing, 100) << name;
    std::printf("%s: environment kernel at %d pixels (%d at n.v < 0.3, %d clamped to kappa); the highlight's kernel is "
                "up to %.1fx the environment's\n", name, compared, grazing, clamped, widest_ratio);
}

void run_glsl(int surface, const char* name) {
    SPECBAKE_REQUIRE_GL(gl);
    std::string log;
    const GLuint program = build_program_glsl(kFullscreenVertex, surface_glsl(surface), log);
    ASSERT_NE(program, 0u) << log;
    render_and_compare(program, surface, name);
}

// (c) The same through HLSL -> SPIR-V -> GL_ARB_gl_spirv: the HLSL derivative paths (ddx/ddy).
void run_hlsl(int surface, const char* name) {
    SPECBAKE_REQUIRE_GL(gl);
    if (!gl->has_extension("GL_ARB_gl_spirv"))
        GTEST_SKIP() << gl->renderer() << " lacks GL_ARB_gl_spirv: HLSL is only compile-tested (ShaderCompile)";
    TempDir dir;
    const auto vs = dir.path() / "v.vert", fs = dir.path() / "f.hlsl";
    std::ofstream(vs) << kFullscreenVertex;
    std::ofstream(fs) << surface_hlsl(surface);
    std::string out;
    ASSERT_EQ(run_command("glslangValidator -G -S vert '" + vs.string() + "' -o '" + vs.string() + ".spv' && "
                          "glslangValidator -V -D -e main -S frag '" + fs.string() + "' -o '" + fs.string() + ".spv' && "
                          "spirv-val '" + fs.string() + ".spv'", out), 0) << out;
    auto read = [](const std::filesystem::path& p) {
        std::ifstream in(p, std::ios::binary);
        return std::vector<char>{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    };
    std::string log;
    const GLuint program = build_program_spirv(read(vs.string() + ".spv"), read(fs.string() + ".spv"), log);
    ASSERT_NE(program, 0u) << log;
    render_and_compare(program, surface, name);
}

TEST(ShaderDerivatives, SphereMatchesClosedForm) { run_glsl(0, "sphere"); }
TEST(ShaderDerivatives, CylinderAtGrazingAnglesMatchesClosedForm) { run_glsl(1, "cylinder"); }
TEST(ShaderDerivatives, HlslSphereThroughGlSpirvMatchesClosedForm) { run_hlsl(0, "HLSL sphere"); }
TEST(ShaderDerivatives, HlslCylinderThroughGlSpirvMatchesClosedForm) { run_hlsl(1, "HLSL cylinder"); }
TEST(ShaderDerivatives, EnvironmentKernelOnTheSphereMatchesTheMirrorDirectionsSpread) { environment_compare(0, "sphere"); }
TEST(ShaderDerivatives, EnvironmentKernelOnTheCylinderMatchesTheMirrorDirectionsSpread) { environment_compare(1, "cylinder"); }

}  // namespace
}  // namespace specbake::gltest
