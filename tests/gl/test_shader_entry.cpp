// The default entry points (specaa_filtered_alpha2 / _roughness / _alpha2_matrix) on llvmpipe with each
// kind of baked data bound as a real mipmapped texture: every mip level holds its own constant, the
// texture coordinates are scaled so that the hardware selects level L, and the result must be the
// SPEC Sec. 3 composition of level L's data with the per-pixel kernel of a known normal or curvature
// field, computed in double with the C++ core (bake/isotropic_filter.h, bake/roughness_space.h). The
// default NDF (specaa_default_D) at a fixed half vector with that matrix is checked against the blend of
// the C++ GGX and convolved NDFs (bake/ggx.h) by the level of detail and the spread.
#include "gl/gl_harness.h"

#include "bake/constants.h"
#include "bake/ggx.h"
#include "bake/isotropic_filter.h"
#include "bake/roughness_space.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace specbake::gltest {
namespace {

constexpr int kTexSize = 64;
constexpr int kLevels = 7;
constexpr int kView = 16;
constexpr double kSigma2 = kDefaultSigma2;
constexpr double kKappa = kDefaultKappa;
constexpr double kRoughness = 0.3;    // material r when no roughness texture is bound
constexpr double kNormalSlope = 0.02;  // n = normalize(kNormalSlope * x, 0, 1) at window x
constexpr double kViewSlope = 0.03;    // v = normalize(0, kViewSlope * y, 1) at window y: the view turns along y
constexpr double kWorldPerPixel = 0.01;
constexpr double kK1 = 3.0, kK2 = -1.0, kDirAngle = 0.4;  // _SPECAA_CURVATURE
constexpr double kGate = 0.5;  // SPECAA_KERNEL_GATE
constexpr double kTol = 4e-5;  // single-precision evaluation of a few closed forms (see grid_cases.h)

// Per-level baked data.
Sym2<double> level_sigma(int L) { return {0.002 * (L + 1), 0.0005 * (L + 1), 0.001 * (L + 1) * (L + 1)}; }
double level_kernel(int L) { return 0.003 * (L + 1) * (L + 1); }
double level_roughness(int L) { return 0.1 + 0.1 * L; }
Vec2<double> level_mean(int L) { return {0.1 * L, -0.05 * L}; }
// Rough share g of the Sigma kernel texels (alpha): both ends and between.
double level_share(int L) { static constexpr double g[kLevels] = {1.0, 0.3, 0.6, 0.0, 0.85, 0.45, 1.0}; return g[L]; }

enum class Baked { None, Kernel, KernelAnisotropic, Lean, Roughness };

struct Config {
    const char* name;
    Baked baked;
    bool curvature;
    bool pixel_kernel;
    double world_per_pixel = kWorldPerPixel;  // footprint of the curvature kernel
    bool two_lobes = false;                    // SPECAA_KERNEL_TWO_LOBES
    double roughness = kRoughness;             // material r (no roughness texture)
    int quality = 2;                           // SPECAA_QUALITY
};

GLuint make_texture(int channels, const std::function<std::array<float, 4>(int)>& level_value) {
    GLuint tex = 0;
    glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexStorage2D(GL_TEXTURE_2D, kLevels, channels == 1 ? GL_R32F : GL_RGBA32F, kTexSize, kTexSize);
    for (int L = 0; L < kLevels; ++L) {
        const int size = kTexSize >> L;
        const auto v = level_value(L);
        std::vector<float> texels;
        for (int i = 0; i < size * size; ++i) texels.insert(texels.end(), v.begin(), v.begin() + channels);
        glTexSubImage2D(GL_TEXTURE_2D, L, 0, 0, size, size, channels == 1 ? GL_RED : GL_RGBA, GL_FLOAT, texels.data());
    }
    // Nearest level, nearest texel: the expected value is exactly level L's constant.
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST_MIPMAP_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    return tex;
}

std::string fragment_source(const Config& c) {
    std::string defines = "#version 450\nlayout(binding = 0) uniform sampler2D uTex0;\nlayout(binding = 1) uniform sampler2D uTex1;\n";
    switch (c.baked) {
        case Baked::None: break;
        case Baked::Kernel: defines += "#define SPECAA_KERNEL_TEXTURE uTex0\n"; break;
        case Baked::KernelAnisotropic: defines += "#define SPECAA_KERNEL_TEXTURE uTex0\n#define SPECAA_KERNEL_ANISOTROPIC\n"; break;
        case Baked::Lean: defines += "#define SPECAA_LEAN_TEXTURE0 uTex0\n#define SPECAA_LEAN_TEXTURE1 uTex1\n"; break;
        case Baked::Roughness: defines += "#define SPECAA_ROUGHNESS_TEXTURE uTex0\n"; break;
    }
    if (c.curvature) defines += "#define SPECAA_USE_CURVATURE\n";
    if (!c.pixel_kernel) defines += "#define SPECAA_NO_PIXEL_KERNEL\n";
    if (c.two_lobes) defines += "#define SPECAA_KERNEL_TWO_LOBES\n";
    defines += "#define SPECAA_QUALITY " + std::to_string(c.quality) + "\n";
    return defines + read_source_file("shaders/specaa.glsl") + R"(
uniform float uUvPerPixel;
uniform float uNormalSlope;
uniform float uViewSlope;
uniform float uWorldPerPixel;
uniform vec4 uCurvature;
uniform float uRoughness;
uniform vec3 uH;
layout(location = 0) out vec4 o0;
layout(location = 1) out vec4 o1;
layout(location = 2) out vec4 o2;
void main() {
    SpecaaSurface s;
    s.roughness = uRoughness;
    s.uv = gl_FragCoord.xy * uUvPerPixel;
    s.normal = normalize(vec3(uNormalSlope * gl_FragCoord.x, 0.0, 1.0));
    s.position = vec3(gl_FragCoord.xy * uWorldPerPixel, 0.0);
    s.tangent = vec3(1.0, 0.0, 0.0);
    s.bitangent = vec3(0.0, 1.0, 0.0);
    s.curvature = uCurvature;
    s.view = normalize(vec3(0.0, uViewSlope * gl_FragCoord.y, 1.0));
    o0 = vec4(specaa_filtered_alpha2(s), specaa_filtered_roughness(s), 0.0, 0.0);
    vec3 A = specaa_filtered_alpha2_matrix(s);
    o1 = vec4(A, 0.0);
    o2 = vec4(specaa_default_D(normalize(uH), A, s), 0.0, 0.0, 0.0);
}
)";
}

// Each eigenvalue clamped to at most kappa, eigenvectors kept (the per-pixel clamp of the matrix form,
// TK21 Sec. 4), by an explicit eigendecomposition: angle of the major axis, then V diag(min) V^T.
Sym2<double> clamp_kernel(Sym2<double> k) {
    const double phi = 0.5 * std::atan2(2.0 * k.xy, k.xx - k.yy);
    const double c = std::cos(phi), s = std::sin(phi);
    const double l1 = c * c * k.xx + 2.0 * c * s * k.xy + s * s * k.yy;  // along (c, s)
    const double l2 = s * s * k.xx - 2.0 * c * s * k.xy + c * c * k.yy;  // along (-s, c)
    const double m1 = std::min(l1, kKappa), m2 = std::min(l2, kKappa);
    return {m1 * c * c + m2 * s * s, (m1 - m2) * c * s, m1 * s * s + m2 * c * c};
}

// The gate: a baked kernel narrower than SPECAA_KERNEL_GATE times a is scaled by (lambda_max / (gate a))^2
// (lambda_max in double by the C++ core, as for the blend's k_max below).
double gate_factor(Sym2<double> k, double a) {
    const double f = std::clamp(max_eigenvalue_sym2(k.xx, k.yy, k.xy) / (kGate * a), 0.0, 1.0);
    return f * f;
}

void run_config(const Config& c) {
    SPECBAKE_REQUIRE_GL(gl);
    std::string log;
    const std::string vertex = "#version 450\nvoid main() { vec2 q = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);"
                               " gl_Position = vec4(q * 2.0 - 1.0, 0.0, 1.0); }\n";
    GLuint program = build_program_glsl(vertex, fragment_source(c), log);
    ASSERT_NE(program, 0u) << log;

    GLuint tex0 = 0, tex1 = 0;
    switch (c.baked) {
        case Baked::None: break;
        case Baked::Kernel: tex0 = make_texture(1, [](int L) { return std::array<float, 4>{float(level_kernel(L))}; }); break;
        case Baked::KernelAnisotropic:
            tex0 = make_texture(4, [](int L) {
                const auto s = level_sigma(L);
                return std::array<float, 4>{float(s.xx), float(s.yy), float(s.xy), float(level_share(L))};
            });
            break;
        case Baked::Lean:
            tex0 = make_texture(4, [](int L) {
                const auto s = level_sigma(L);
                const auto m = level_mean(L);
                return std::array<float, 4>{float(m.x), float(m.y), float(s.xx + m.x * m.x), float(s.yy + m.y * m.y)};
            });
            tex1 = make_texture(1, [](int L) {
                const auto s = level_sigma(L);
                const auto m = level_mean(L);
                return std::array<float, 4>{float(s.xy + m.x * m.y)};
            });
            break;
        case Baked::Roughness:
            tex0 = make_texture(4, [](int L) { return std::array<float, 4>{0.7f, float(level_roughness(L)), 0.3f, 1.0f}; });
            break;
    }
    GLuint vao = 0, fbo = 0, targets[3] = {};
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    fbo = create_float_targets(3, kView, kView, targets);
    ASSERT_EQ(glCheckFramebufferStatus(GL_FRAMEBUFFER), static_cast<GLenum>(GL_FRAMEBUFFER_COMPLETE));
    // Bound after the render targets: creating them rebinds GL_TEXTURE_2D on the active unit.
    glBindTextureUnit(0, tex0);
    glBindTextureUnit(1, tex1);
    glViewport(0, 0, kView, kView);
    glUseProgram(program);
    const double dir = kDirAngle;
    glUniform1f(glGetUniformLocation(program, "uNormalSlope"), float(kNormalSlope));
    glUniform1f(glGetUniformLocation(program, "uViewSlope"), float(kViewSlope));
    glUniform1f(glGetUniformLocation(program, "uWorldPerPixel"), float(c.world_per_pixel));
    glUniform4f(glGetUniformLocation(program, "uCurvature"), float(kK1), float(kK2), float(2 * std::cos(dir)), float(2 * std::sin(dir)));
    glUniform1f(glGetUniformLocation(program, "uRoughness"), float(c.roughness));
    const Vec3<double> h = normalize(Vec3<double>{0.12, -0.07, 1.0});
    glUniform3f(glGetUniformLocation(program, "uH"), float(h.x), float(h.y), float(h.z));
    int blends = 0;  // pixels where the default NDF is strictly between the convolution and GGX(A)
    int faded = 0;   // pixels where the gate scales the baked kernel strictly between 0 and 1

    int failures = 0;
    for (int L = 0; L < (c.baked == Baked::None ? 1 : kLevels - 1); ++L) {
        // One pixel spans 2^L texels: the hardware's level of detail is L.
        glUniform1f(glGetUniformLocation(program, "uUvPerPixel"), float(std::ldexp(1.0, L) / kTexSize));
        glDrawArrays(GL_TRIANGLES, 0, 3);
        std::vector<float> out0(kView * kView * 4), out1(kView * kView * 4), out2(kView * kView * 4);
        glReadBuffer(GL_COLOR_ATTACHMENT0);
        glReadPixels(0, 0, kView, kView, GL_RGBA, GL_FLOAT, out0.data());
        glReadBuffer(GL_COLOR_ATTACHMENT1);
        glReadPixels(0, 0, kView, kView, GL_RGBA, GL_FLOAT, out1.data());
        glReadBuffer(GL_COLOR_ATTACHMENT2);
        glReadPixels(0, 0, kView, kView, GL_RGBA, GL_FLOAT, out2.data());
        ASSERT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));

        for (int y = 0; y < kView; ++y)
            for (int x = 0; x < kView; ++x) {
                // Baked data of level L as the kernel matrix K = 2 Sigma (isotropic t: K = t I).
                double a0 = std::pow(double(float(c.roughness)), 4);
                // The Sigma kernel's single lobe: K = 2 Sigma sqrt(g), g the texel's rough share (alpha);
                // k_sigma = 2 Sigma itself, which the two lobes split.
                Sym2<double> k_tex{}, k_sigma{};
                switch (c.baked) {
                    case Baked::None: break;
                    case Baked::Kernel: k_tex = diag(level_kernel(L), level_kernel(L)); break;
                    case Baked::KernelAnisotropic:
                        k_sigma = 2.0 * level_sigma(L);
                        k_tex = std::sqrt(level_share(L)) * k_sigma;
                        break;
                    case Baked::Lean: k_tex = 2.0 * level_sigma(L); break;
                    case Baked::Roughness: a0 = std::pow(double(float(level_roughness(L))), 4); break;
                }
                if (c.baked != Baked::None && c.baked != Baked::Roughness) {
                    const double fade = gate_factor(k_tex, a0);
                    if (fade > 0.05 && fade < 0.95) ++faded;
                    k_tex = fade * k_tex;
                }
                // Per-pixel kernel: normal differences across the quad (x&~1 -> x|1), or the curvature
                // kernel of the footprint (w, 0), (0, w) in the (T, B) frame; each less the half vector's
                // turn with the view across the quad (y&~1 -> y|1), tangential to the fragment's normal,
                // over 2 n.v (the view does not change along x). The fast and balanced tiers leave the turn out.
                auto normal_x = [](int px) { const double t = double(float(kNormalSlope)) * (px + 0.5); return Vec3<double>{t / std::hypot(t, 1.0), 0.0, 1.0 / std::hypot(t, 1.0)}; };
                auto view_y = [](int py) { const double t = double(float(kViewSlope)) * (py + 0.5); return Vec3<double>{0.0, t / std::hypot(t, 1.0), 1.0 / std::hypot(t, 1.0)}; };
                const Vec3<double> n_px = normal_x(x), v_px = view_y(y), dview = view_y(y | 1) - view_y(y & ~1);
                const double turn_scale = c.quality != 2 ? 0.0 : 0.5 / std::max(dot(n_px, v_px), 1e-3);
                const Vec3<double> turn = turn_scale * (dview - dot(n_px, dview) * n_px);
                Sym2<double> k_px{};
                double want_iso = 0.0;  // specaa_filtered_alpha2
                if (c.pixel_kernel && c.curvature) {
                    const double cx = std::cos(dir), cy = std::sin(dir);
                    const Sym2<double> S{kK1 * cx * cx + kK2 * cy * cy, (kK1 - kK2) * cx * cy, kK1 * cy * cy + kK2 * cx * cx};
                    const double w = c.world_per_pixel;
                    const double du_x = S.xx * w, du_y = S.xy * w, dv_x = S.xy * w - turn.x, dv_y = S.yy * w - turn.y;
                    k_px = (2 * kSigma2) * Sym2<double>{du_x * du_x + dv_x * dv_x, du_x * du_y + dv_x * dv_y, du_y * du_y + dv_y * dv_y};
                } else if (c.pixel_kernel) {
                    const auto dn = normal_x(x | 1) - normal_x(x & ~1);
                    // Isotropic path: sigma^2 (|dn_x|^2 + |dn_y - turn|^2) (TK21 Eq. 14); matrix path: projected
                    // onto T = x and B = y.
                    k_px = (2 * kSigma2) * Sym2<double>{dn.x * dn.x + turn.x * turn.x, turn.x * turn.y, turn.y * turn.y};
                    const double t_iso = std::min(kSigma2 * (dot(dn, dn) + dot(turn, turn)), kKappa);
                    const double t = 0.5 * (k_tex.xx + k_tex.yy) + t_iso;
                    const double want = filter_projected_isotropic(a0, t);
                    want_iso = want;
                    const size_t i = static_cast<size_t>(y * kView + x) * 4;
                    if (std::abs(out0[i] - want) > kTol * want && ++failures <= 5)
                        ADD_FAILURE() << c.name << " level " << L << " pixel " << x << "," << y << ": a " << out0[i] << " want " << want;
                }
                const size_t i = static_cast<size_t>(y * kView + x) * 4;
                if (!(c.pixel_kernel && !c.curvature)) {
                    const double t = 0.5 * (k_tex.xx + k_tex.yy) + std::min(0.5 * (k_px.xx + k_px.yy), kKappa);
                    const double want = filter_projected_isotropic(a0, t);
                    want_iso = want;
                    if (std::abs(out0[i] - want) > kTol * want && ++failures <= 5)
                        ADD_FAILURE() << c.name << " level " << L << " pixel " << x << "," << y << ": a " << out0[i] << " want " << want;
                }
                if (std::abs(out0[i + 1] - std::pow(double(out0[i]), 0.25)) > kTol && ++failures <= 5)
                    ADD_FAILURE() << c.name << ": r != a^(1/4)";
                if (c.quality != 2) {
                    // The fast and balanced tiers: the isotropic form as their matrix; the fast tier's NDF
                    // specaa_filtered_D_isotropic on it (filtered_ndf_isotropic: two lobes with the material's tails),
                    // the balanced tier's GGX(a) convolved with the footprint a' - a in closed form.
                    if ((std::abs(out1[i] - want_iso) > kTol * want_iso || std::abs(out1[i + 1] - want_iso) > kTol * want_iso ||
                         out1[i + 2] != 0.0f) && ++failures <= 5)
                        ADD_FAILURE() << c.name << " level " << L << " pixel " << x << "," << y << ": fast matrix " << out1[i]
                                      << " " << out1[i + 1] << " " << out1[i + 2] << " want " << want_iso;
                    if (c.quality == 1) {
                        // The closed form's float evaluation (its cubic fits, exp) against double: 2e-3.
                        const double balanced_d = convolved_ndf_closed_form(h, Sym2<double>{want_iso, 0.0, want_iso}, a0);
                        if (std::abs(out2[i] - balanced_d) > 2e-3 * balanced_d && ++failures <= 5)
                            ADD_FAILURE() << c.name << " level " << L << " pixel " << x << "," << y << ": balanced D "
                                          << out2[i] << " want " << balanced_d;
                        continue;
                    }
                    const double fast_d = filtered_ndf_isotropic(h, a0, want_iso);
                    if (std::abs(out2[i] - fast_d) > 1e-4 * fast_d && ++failures <= 5)
                        ADD_FAILURE() << c.name << " level " << L << " pixel " << x << "," << y << ": fast D " << out2[i]
                                      << " want " << fast_d << " (GGX(a') " << ggx_ndf(h, diag(want_iso, want_iso), a0 * a0) << ")";
                    continue;
                }
                const Sym2<double> A = projected_to_slope_roughness(slope_to_projected_roughness(diag(a0, a0)) + k_tex + clamp_kernel(k_px));
                const double scale = A.xx + A.yy;
                if ((std::abs(out1[i] - A.xx) > kTol * scale || std::abs(out1[i + 1] - A.yy) > kTol * scale ||
                     std::abs(out1[i + 2] - A.xy) > kTol * scale) && ++failures <= 5)
                    ADD_FAILURE() << c.name << " level " << L << " pixel " << x << "," << y << ": matrix " << out1[i] << " "
                                  << out1[i + 1] << " " << out1[i + 2] << " want " << A.xx << " " << A.yy << " " << A.xy;
                // The default NDF: GGX(A) + (1 - w) (convolution - GGX(A)). w = 0 without baked data; the level
                // of detail L (saturated) with the baked roughness; with kernel or LEAN mips (SPECAA_GGX_SPREAD 8)
                // L times the larger of saturate(8 lambda_max(baked spread)) and saturate(8 lambda_min(rest of
                // A - a I)), the baked spread's part times 1 - g (its heavy tail) where the Sigma kernel's texel
                // holds the rough share g of a single lobe.
                const auto blend_share = [a0](const Sym2<double>& matrix, const Sym2<double>& baked, double heavy) {
                    const double rxx = matrix.xx - a0 - baked.xx, ryy = matrix.yy - a0 - baked.yy, rxy = matrix.xy - baked.xy;
                    const double rest_minor = 0.5 * (rxx + ryy) - std::hypot(0.5 * (rxx - ryy), rxy);
                    return std::max(heavy * std::clamp(8.0 * max_eigenvalue_sym2(baked.xx, baked.yy, baked.xy), 0.0, 1.0),
                                    std::clamp(8.0 * rest_minor, 0.0, 1.0));
                };
                const double heavy = c.baked == Baked::KernelAnisotropic && !c.two_lobes ? 1.0 - level_share(L) : 1.0;
                double w = 0.0;
                if (c.baked == Baked::Roughness) w = std::min(1.0, double(L));
                else if (c.baked != Baked::None) w = std::min(1.0, double(L)) * blend_share(A, k_tex, heavy);
                // The Sigma kernel's two lobes: the rough share g with K = 2 Sigma / g (gated), the flat share
                // with the pixel kernel alone, convolved.
                const double g = c.baked == Baked::KernelAnisotropic && c.two_lobes ? level_share(L) : 1.0;
                const Sym2<double> k_rough = (1.0 / std::max(g, 1e-3)) * k_sigma;
                const Sym2<double> rough_A =
                    g < 1.0 ? projected_to_slope_roughness(slope_to_projected_roughness(diag(a0, a0)) +
                                                           gate_factor(k_rough, a0) * k_rough + clamp_kernel(k_px))
                            : A;
                const Sym2<double> flat_A = projected_to_slope_roughness(slope_to_projected_roughness(diag(a0, a0)) + clamp_kernel(k_px));
                if (g < 1.0)
                    w = std::min(1.0, double(L)) * blend_share(rough_A, gate_factor(k_rough, a0) * k_rough, 1.0);
                const double ggx = ggx_ndf(h, rough_A, a0 * a0), conv = convolved_ndf(h, rough_A, a0);
                const double flat = g < 1.0 ? convolved_ndf(h, flat_A, a0) : 0.0;
                const double want_d = g * (ggx + (1.0 - w) * (conv - ggx)) + (1.0 - g) * flat;
                // The convolution's quadrature in float and the matrix's rounding: 3e-3 of the larger NDF.
                if (std::abs(out2[i] - want_d) > 3e-3 * std::max({ggx, conv, flat}) && ++failures <= 5)
                    ADD_FAILURE() << c.name << " level " << L << " pixel " << x << "," << y << ": default D " << out2[i]
                                  << " want " << want_d << " (GGX " << ggx << ", convolution " << conv << ", w " << w << ")";
                if (w > 0.05 && w < 0.95 && std::abs(conv - ggx) > 0.05 * ggx) ++blends;
            }
    }
    EXPECT_EQ(failures, 0) << c.name;
    if (c.roughness != kRoughness) EXPECT_GT(faded, 0) << c.name << ": no pixel where the gate fades the baked kernel";
    // The kernel cases reach the blend itself, not only its ends.
    // The rough material's cases are there for the gate (with the Sigma kernel at r = 0.6 no pixel is both
    // in the blend and 5% apart).
    if ((c.baked == Baked::Kernel || c.baked == Baked::KernelAnisotropic || c.baked == Baked::Lean) && c.roughness == kRoughness &&
        c.quality == 2)
        EXPECT_GT(blends, 0) << c.name << ": no pixel between the convolution and GGX(A)";
    glDeleteTextures(3, targets);
    glDeleteTextures(1, &tex0);
    glDeleteTextures(1, &tex1);
    glDeleteFramebuffers(1, &fbo);
    glDeleteVertexArrays(1, &vao);
    glDeleteProgram(program);
}

// The fast tier (SPECAA_QUALITY 0) with each binding: its Sigma kernel mean from the texel's eigenvalues
// (specaa_baked_kernel_mean), gated, and its NDF against the C++ composition.
TEST(ShaderEntry, FastTierDerivativesOnly) { run_config({"fast, derivatives", Baked::None, false, true, kWorldPerPixel, false, kRoughness, 0}); }
TEST(ShaderEntry, FastTierRoughnessTexturePlusDerivatives) {
    run_config({"fast, roughness+derivatives", Baked::Roughness, false, true, kWorldPerPixel, false, kRoughness, 0});
}
TEST(ShaderEntry, FastTierAnisotropicKernelPlusDerivatives) {
    run_config({"fast, anisotropic kernel+derivatives", Baked::KernelAnisotropic, false, true, kWorldPerPixel, false, kRoughness, 0});
}
TEST(ShaderEntry, FastTierAnisotropicKernelGatedUnderARoughMaterial) {
    run_config({"fast, anisotropic kernel, r 0.6", Baked::KernelAnisotropic, false, false, kWorldPerPixel, false, 0.6, 0});
}
TEST(ShaderEntry, FastTierLeanPlusCurvature) {
    run_config({"fast, LEAN+curvature", Baked::Lean, true, true, kWorldPerPixel, false, kRoughness, 0});
}

// The balanced tier (SPECAA_QUALITY 1): the fast tier's matrix, the closed-form convolution as its NDF.
TEST(ShaderEntry, BalancedTierDerivativesOnly) { run_config({"balanced, derivatives", Baked::None, false, true, kWorldPerPixel, false, kRoughness, 1}); }
TEST(ShaderEntry, BalancedTierRoughnessTexturePlusDerivatives) {
    run_config({"balanced, roughness+derivatives", Baked::Roughness, false, true, kWorldPerPixel, false, kRoughness, 1});
}
TEST(ShaderEntry, BalancedTierAnisotropicKernelPlusDerivatives) {
    run_config({"balanced, anisotropic kernel+derivatives", Baked::KernelAnisotropic, false, true, kWorldPerPixel, false, kRoughness, 1});
}
TEST(ShaderEntry, BalancedTierLeanPlusCurvature) {
    run_config({"balanced, LEAN+curvature", Baked::Lean, true, true, kWorldPerPixel, false, kRoughness, 1});
}

TEST(ShaderEntry, DerivativesOnly) { run_config({"derivatives", Baked::None, false, true}); }
TEST(ShaderEntry, KernelTexturePlusDerivatives) { run_config({"kernel+derivatives", Baked::Kernel, false, true}); }
TEST(ShaderEntry, AnisotropicKernelTextureOnly) { run_config({"anisotropic kernel", Baked::KernelAnisotropic, false, false}); }
// SPECAA_KERNEL_TWO_LOBES: the rough share in alpha splits the texel; the flat share's lobe carries the
// pixel kernel (and only it). Without the define the single lobe scales Sigma by sqrt(g) (the cases above).
TEST(ShaderEntry, AnisotropicKernelTwoLobes) {
    run_config({"anisotropic kernel, two lobes", Baked::KernelAnisotropic, false, false, kWorldPerPixel, true});
}
TEST(ShaderEntry, AnisotropicKernelTwoLobesPlusDerivatives) {
    run_config({"anisotropic kernel+derivatives, two lobes", Baked::KernelAnisotropic, false, true, kWorldPerPixel, true});
}
// A rough material (r = 0.6, a = 0.13): the baked kernels of the lower levels are narrower than a and the
// gate (SPECAA_KERNEL_GATE) fades them, the upper levels' pass whole.
TEST(ShaderEntry, AnisotropicKernelGatedUnderARoughMaterial) {
    run_config({"anisotropic kernel+derivatives, rough material", Baked::KernelAnisotropic, false, true, kWorldPerPixel, false, 0.6});
}
TEST(ShaderEntry, AnisotropicKernelTwoLobesGatedUnderARoughMaterial) {
    run_config({"anisotropic kernel+derivatives, two lobes, rough material", Baked::KernelAnisotropic, false, true, kWorldPerPixel, true, 0.6});
}
TEST(ShaderEntry, KernelTextureGatedUnderARoughMaterial) {
    run_config({"kernel, rough material", Baked::Kernel, false, false, kWorldPerPixel, false, 0.6});
}
TEST(ShaderEntry, LeanPlusCurvature) { run_config({"LEAN+curvature", Baked::Lean, true, true}); }
// A footprint of 0.4 makes the curvature kernel's major eigenvalue exceed kappa and its minor one stay
// below: the clamp must cap the first and keep the second (TK21 Sec. 4), not scale the matrix.
TEST(ShaderEntry, CurvatureKernelClampedPerEigenvalue) {
    run_config({"curvature, clamped", Baked::None, true, true, 0.4});
}
TEST(ShaderEntry, RoughnessTexturePlusDerivatives) { run_config({"roughness+derivatives", Baked::Roughness, false, true}); }

}  // namespace
}  // namespace specbake::gltest
