#include "gl/grid_cases.h"

#include "bake/constants.h"
#include "bake/ggx.h"
#include "bake/isotropic_filter.h"
#include "bake/kernels.h"
#include "bake/roughness_space.h"

#include <cmath>
#include <random>
#include <sstream>

namespace specbake::gltest {
namespace {

constexpr double kSigma2 = kDefaultSigma2;
constexpr double kKappa = kDefaultKappa;

// Squared roughness values of the stability grid (issue 2): smooth, tiny, nearly and fully rough.
const double kAlpha2[] = {0.0, 1e-7, 1e-4, 0.01, 0.1, 0.5, 0.999, 1.0};

Vec4 v4(double x, double y, double z = 0, double w = 0) {
    return {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z), static_cast<float>(w)};
}

// The float value the GPU saw, back in double, so references start from identical inputs.
double f(float x) { return static_cast<double>(x); }

bool close(double gpu, double ref) {
    if (std::isinf(ref)) return gpu == ref;
    return std::isfinite(gpu) && std::abs(gpu - ref) <= kRelTol * std::abs(ref) + kAbsTol;
}

std::string describe(const char* what, const GridCase& c, const std::vector<double>& gpu, const std::vector<double>& ref) {
    std::ostringstream s;
    s.precision(9);
    s << what << ": inputs";
    for (const Vec4& v : c.in) s << " (" << v[0] << ", " << v[1] << ", " << v[2] << ", " << v[3] << ")";
    s << "; gpu";
    for (double g : gpu) s << " " << g;
    s << "; reference";
    for (double r : ref) s << " " << r;
    return s.str();
}

std::string compare(const char* what, const GridCase& c, const std::vector<double>& gpu, const std::vector<double>& ref) {
    for (size_t i = 0; i < gpu.size(); ++i)
        if (!close(gpu[i], ref[i])) return describe(what, c, gpu, ref);
    return {};
}

std::vector<double> sym(const Sym2<double>& m) { return {m.xx, m.yy, m.xy}; }

// Symmetric matrices (xx, yy, xy): the off-diagonal term is a sum of products that can cancel, so its
// rounding is relative to the matrix scale |xx| + |yy| (>= 2 |xy| for PSD matrices), not to itself.
std::string compare_sym(const char* what, const GridCase& c, const std::vector<double>& gpu, const Sym2<double>& ref) {
    const double scale = std::abs(ref.xx) + std::abs(ref.yy);
    if (!close(gpu[0], ref.xx) || !close(gpu[1], ref.yy) ||
        !(std::abs(gpu[2] - ref.xy) <= kRelTol * scale + kAbsTol))
        return describe(what, c, gpu, sym(ref));
    return {};
}
std::vector<double> out3(const Vec4& v) { return {v[0], v[1], v[2]}; }

// Random 2D derivative of magnitude `scale` (deterministic stream).
Vec2<double> random_delta(std::mt19937& rng, double scale) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    return {scale * u(rng), scale * u(rng)};
}

Vec3<double> random_unit(std::mt19937& rng, bool upper) {
    std::normal_distribution<double> g;
    Vec3<double> v{g(rng), g(rng), g(rng)};
    if (upper) v.z = std::abs(v.z);
    return normalize(v);
}

GridGroup kernels_group() {
    GridGroup g{"KERNELS", {}, {}};
    std::mt19937 rng(1);
    const double scales[] = {0.0, 1e-6, 1e-3, 0.05, 0.5, 10.0, 1e3};
    for (double ax : kAlpha2)
        for (double ay : {ax, 0.01, 0.5})
            for (double su : scales)
                for (double sv : scales)
                    for (int rep = 0; rep < 2; ++rep) {
                        GridCase c;
                        const auto dus = random_delta(rng, su), dvs = random_delta(rng, sv);
                        const auto dup = random_delta(rng, su), dvp = random_delta(rng, sv);
                        c.in[0] = v4(dus.x, dus.y, dvs.x, dvs.y);
                        c.in[1] = v4(dup.x, dup.y, dvp.x, dvp.y);
                        c.in[2] = v4(ax, ay);
                        g.cases.push_back(c);
                    }
    g.check = [](const GridCase& c, const GridResult& r) -> std::string {
        const Vec2<double> a2{f(c.in[2][0]), f(c.in[2][1])};
        const Vec2<double> dus{f(c.in[0][0]), f(c.in[0][1])}, dvs{f(c.in[0][2]), f(c.in[0][3])};
        const Vec2<double> dup{f(c.in[1][0]), f(c.in[1][1])}, dvp{f(c.in[1][2]), f(c.in[1][3])};
        std::string e = compare_sym("slope (K16, TK21 Eq. 2)", c, out3(r.out[0]), filter_non_axis_aligned(a2, dus, dvs, kSigma2));
        if (e.empty()) e = compare_sym("projected-approx (TK21 Listing 2)", c, out3(r.out[1]), filter_non_axis_aligned(a2, dup, dvp, kSigma2));
        if (e.empty()) e = compare_sym("projected (TK21 Listing 1)", c, out3(r.out[2]), filter_projected(a2, dup, dvp, kSigma2));
        if (e.empty()) {
            const auto s = filter_axis_aligned(a2, dus, dvs, kSigma2, kKappa);
            const auto p = filter_axis_aligned(a2, dup, dvp, kSigma2, kKappa);
            e = compare("slope-aa / projected-aa (TK21 Listing 3)", c,
                        {r.out[3][0], r.out[3][1], r.out[3][2], r.out[3][3]}, {s.x, s.y, p.x, p.y});
        }
        return e;
    };
    return g;
}

GridGroup isotropic_group() {
    GridGroup g{"ISOTROPIC", {}, {}};
    std::mt19937 rng(2);
    const double angles[] = {0.0, 1e-4, 0.01, 0.1, 0.5, 1.0, 2.0};
    for (double a : kAlpha2)
        for (double tu : angles)
            for (double tv : angles)
                for (int rep = 0; rep < 3; ++rep) {
                    // Normals of neighbouring pixels turned by tu, tv: dn = n' - n of unit normals.
                    const auto n = random_unit(rng, false);
                    auto turned = [&](double angle) {
                        const auto axis = random_unit(rng, false);
                        const Vec3<double> t = normalize(Vec3<double>{axis.y * n.z - axis.z * n.y, axis.z * n.x - axis.x * n.z,
                                                                      axis.x * n.y - axis.y * n.x});
                        return (std::cos(angle) - 1.0) * n + std::sin(angle) * t;
                    };
                    const auto du = turned(tu), dv = turned(tv);
                    GridCase c;
                    c.in[0] = v4(du.x, du.y, du.z, a);
                    c.in[1] = v4(dv.x, dv.y, dv.z);
                    g.cases.push_back(c);
                }
    g.check = [](const GridCase& c, const GridResult& r) -> std::string {
        const Vec3<double> du{f(c.in[0][0]), f(c.in[0][1]), f(c.in[0][2])}, dv{f(c.in[1][0]), f(c.in[1][1]), f(c.in[1][2])};
        const double a = f(c.in[0][3]);
        const double kmax = isotropic_kernel_roughness(IsotropicReduction::Max, du, dv, kSigma2);
        const double ksum = isotropic_kernel_roughness(IsotropicReduction::Sum, du, dv, kSigma2);
        const double kmean = isotropic_kernel_roughness(IsotropicReduction::Mean, du, dv, kSigma2);
        std::string e = compare("iso kernels max/sum/mean (TK21 Eq. 10, 13, 14)", c, {r.out[0][0], r.out[0][1], r.out[0][2]},
                                {kmax, ksum, kmean});
        if (e.empty())
            e = compare("iso filters max/sum/mean (TK21 Listing 5)", c, {r.out[1][0], r.out[1][1], r.out[1][2]},
                        {filter_isotropic(a, kmax, kKappa), filter_isotropic(a, ksum, kKappa), filter_isotropic(a, kmean, kKappa)});
        return e;
    };
    return g;
}

GridGroup ggx_group() {
    GridGroup g{"GGX", {}, {}};
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    // Half vectors from normal incidence to grazing (h.z = 0 exactly) and below the horizon.
    const double hz_values[] = {1.0, 0.9, 0.5, 0.1, 1e-3, 0.0, -0.3};
    for (double ax : {1e-4, 0.01, 0.1, 0.5, 1.0})
        for (double ay : {ax, 0.05})
            for (double hz : hz_values)
                for (int rep = 0; rep < 6; ++rep) {
                    const double phi = 6.283185307179586 * (u(rng) * 0.5 + 0.5);
                    const double s = std::sqrt(1.0 - hz * hz);
                    const Vec3<double> h{s * std::cos(phi), s * std::sin(phi), hz};
                    // A filtered, non-axis-aligned matrix: diag + a PSD kernel.
                    const auto d = random_delta(rng, 0.3 * rep);
                    const double kxx = d.x * d.x, kyy = d.y * d.y, kxy = d.x * d.y;
                    auto i = random_unit(rng, true);
                    auto o = random_unit(rng, true);
                    if (rep == 5) o = {std::sqrt(0.5), std::sqrt(0.5), 0.0};  // grazing outgoing direction
                    GridCase c;
                    c.in[0] = v4(h.x, h.y, h.z, ax * ay);
                    c.in[1] = v4(ax + kxx, ay + kyy, kxy);
                    c.in[2] = v4(i.x, i.y, i.z);
                    c.in[3] = v4(o.x, o.y, o.z);
                    g.cases.push_back(c);
                }
    g.check = [](const GridCase& c, const GridResult& r) -> std::string {
        const Vec3<double> h{f(c.in[0][0]), f(c.in[0][1]), f(c.in[0][2])};
        const double tau = f(c.in[0][3]);
        const Sym2<double> A{f(c.in[1][0]), f(c.in[1][2]), f(c.in[1][1])};
        const Vec3<double> i{f(c.in[2][0]), f(c.in[2][1]), f(c.in[2][2])}, o{f(c.in[3][0]), f(c.in[3][1]), f(c.in[3][2])};
        std::string e = compare("Lambda, G2 (TK21 App. A.1, A.3)", c, {r.out[0][2], r.out[0][3]},
                                {ggx_lambda(o, A), ggx_g2(i, o, h, A)});
        if (!e.empty()) return e;
        // D depends on det(A) = xx yy - xy^2, which float rounds with relative error ~ eps xx yy / det
        // (the precision problem of TK21 App. A.4): scale the tolerance by that condition number, and for
        // Beckmann also by its exponent, whose absolute error becomes the relative error of exp().
        const double det_clamped = std::max(det(A), tau);
        const double cond = std::max(1.0, std::abs(A.xx * A.yy) / det_clamped);
        const double exponent = h.z > 0 ? quadratic_form(Sym2<double>{A.yy, -A.xy, A.xx}, Vec2<double>{h.x, h.y}) /
                                              det_clamped / (h.z * h.z) : 0.0;
        const double ggx = ggx_ndf(h, A, tau), beckmann = beckmann_ndf(h, A, tau);
        if (std::abs(r.out[0][0] - ggx) > kRelTol * cond * ggx + kAbsTol ||
            std::abs(r.out[0][1] - beckmann) > kRelTol * cond * (1.0 + exponent) * beckmann + kAbsTol)
            return describe("GGX D, Beckmann D (TK21 Eq. 1, Sec. 2.1, App. A.4)", c, {r.out[0][0], r.out[0][1]},
                            {ggx, beckmann});
        // The tail-weighted mixture (TK21 Sec. 7) of the two, with Beckmann's tolerance.
        const double filtered = filtered_ndf(h, A, std::sqrt(tau));
        if (std::abs(r.out[1][0] - filtered) > kRelTol * cond * (1.0 + exponent) * filtered + kAbsTol)
            return describe("filtered D (TK21 Sec. 7)", c, {r.out[1][0]}, {filtered});
        // GGX convolved with the footprint: a sum of up to 32 Beckmann lobes in float, each with its own
        // exponent; 1e-3 relative (the quadrature itself is checked against a brute-force convolution in
        // tests/bake/test_ggx.cpp).
        const double convolved = convolved_ndf(h, A, std::sqrt(tau));
        if (!(std::abs(r.out[1][1] - convolved) <= 1e-3 * cond * convolved + kAbsTol))
            return describe("convolved D (GGX through the footprint)", c, {r.out[1][1]}, {convolved});
        // Its closed form (the balanced tier's NDF) against its C++ twin: three exponentials and two Beckmann
        // lobes in float, 1e-3 relative like the quadrature.
        const double closed_form = convolved_ndf_closed_form(h, A, std::sqrt(tau));
        if (!(std::abs(r.out[1][2] - closed_form) <= 1e-3 * cond * (1.0 + exponent) * closed_form + kAbsTol))
            return describe("convolved D in closed form", c, {r.out[1][2]}, {closed_form});
        // The isotropic closed form (the balanced tier's NDF) on the mean of the kernel.
        const double a = std::sqrt(tau);
        const double isotropic = convolved_ndf_isotropic(h, a, std::max(0.5 * (A.xx + A.yy) - a, 0.0));
        if (!(std::abs(r.out[1][3] - isotropic) <= 1e-3 * (1.0 + exponent) * isotropic + kAbsTol))
            return describe("convolved D in closed form, isotropic (balanced tier)", c, {r.out[1][3]}, {isotropic});
        // The fast tier's two-lobe NDF on the isotropic A = f I, f = tr(A) / 2 >= a, against
        // filtered_ndf_isotropic, with Beckmann's tolerance for its exponent (at most tan^2(theta_h) / f).
        const double fi = 0.5 * (A.xx + A.yy);
        const double fast = filtered_ndf_isotropic(h, a, fi);
        const double fast_exponent = h.z > 0 ? (h.x * h.x + h.y * h.y) / (h.z * h.z * fi) : 0.0;
        if (!(std::abs(r.out[2][0] - fast) <= kRelTol * (1.0 + fast_exponent) * fast + kAbsTol))
            return describe("filtered D on an isotropic A (fast tier)", c, {r.out[2][0]}, {fast});
        return {};
    };
    return g;
}

// Nearest PSD matrix by eigen decomposition in double (independent of the include's projector form).
Sym2<double> reference_clamp_psd(const Sym2<double>& m) {
    const double half_tr = 0.5 * (m.xx + m.yy), r = std::hypot(0.5 * (m.xx - m.yy), m.xy);
    const double l1 = half_tr + r, l2 = half_tr - r;
    const double angle = 0.5 * std::atan2(2.0 * m.xy, m.xx - m.yy);  // eigenvector of l1
    const double cx = std::cos(angle), cy = std::sin(angle);
    const double p1 = std::max(l1, 0.0), p2 = std::max(l2, 0.0);
    return {p1 * cx * cx + p2 * cy * cy, (p1 - p2) * cx * cy, p1 * cy * cy + p2 * cx * cx};
}

GridGroup baked_group() {
    GridGroup g{"BAKED", {}, {}};
    std::mt19937 rng(4);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const double kernels[] = {0.0, 1e-6, 1e-3, 0.05, 0.5, 3.0, 1e4};
    for (double a : kAlpha2)
        for (double t : kernels)
            for (int rep = 0; rep < 4; ++rep) {
                // Sigma: PSD, or indefinite (rounded moments) for the clamp.
                const double sx = t * (0.5 + 0.5 * u(rng)), sy = t * (0.5 + 0.5 * u(rng));
                const double sxy = (rep == 3 ? 1.5 : 0.9) * std::sqrt(sx * sy) * u(rng);
                // LEAN moments of a normal spread around a mean m: M = Sigma + m m^T.
                const double mx = 0.6 * u(rng), my = 0.6 * u(rng);
                GridCase c;
                c.in[0] = v4(a, t);
                c.in[1] = v4(sx, sy, sxy);
                c.in[2] = v4(mx, my, sx + mx * mx, sy + my * my);
                c.in[3] = v4(sxy + mx * my, 0.0);
                g.cases.push_back(c);
            }
    g.check = [](const GridCase& c, const GridResult& r) -> std::string {
        const double a = f(c.in[0][0]), t = f(c.in[0][1]);
        const Sym2<double> s{f(c.in[1][0]), f(c.in[1][2]), f(c.in[1][1])};
        std::string e = compare("SPEC Sec. 3 filters and reductions", c,
                                {r.out[0][0], r.out[0][1], r.out[0][2], r.out[0][3], r.out[1][0]},
                                {filter_projected_isotropic(a, t), filter_approx_isotropic(a, t),
                                 reduce_covariance(IsotropicReduction::Mean, s.xx, s.yy, s.xy),
                                 reduce_covariance(IsotropicReduction::Sum, s.xx, s.yy, s.xy),
                                 reduce_covariance(IsotropicReduction::Max, s.xx, s.yy, s.xy)});
        if (e.empty())
            e = compare("roughness mappings r = a^(1/4), a = r^4", c, {r.out[1][1], r.out[1][2]},
                        {std::pow(a, 0.25), a * a * a * a});
        if (e.empty()) {
            const double mx = f(c.in[2][0]), my = f(c.in[2][1]);
            const Sym2<double> cov{f(c.in[2][2]) - mx * mx, f(c.in[3][0]) - mx * my, f(c.in[2][3]) - my * my};
            const auto ref = reference_clamp_psd(cov);
            // The moments are rounded to float before the subtraction: allow that rounding of M.
            const std::vector<double> gpu = out3(r.out[2]), want = sym(ref);
            for (size_t k = 0; k < 3; ++k)
                if (std::abs(gpu[k] - want[k]) > kRelTol * (std::abs(want[k]) + 1.0))
                    return describe("LEAN covariance M - m m^T (SPEC Sec. 3)", c, gpu, want);
        }
        if (e.empty())
            e = compare("PSD clamp and lambda_max", c, {r.out[3][0], r.out[3][1], r.out[3][2], r.out[3][3]},
                        {reference_clamp_psd(s).xx, reference_clamp_psd(s).yy, reference_clamp_psd(s).xy,
                         0.5 * (s.xx + s.yy) + std::hypot(0.5 * (s.xx - s.yy), s.xy)});
        return e;
    };
    return g;
}

// Mean-normal decoding: two-channel (BC5) texels with z rebuilt, RGB texels renormalised. Reference in
// double from the texel as the GPU saw it. Near the rim of the unit disc 1 - x^2 - y^2 cancels in float and
// the square root amplifies that to about sqrt(float epsilon), so the bound is absolute (unit vectors).
GridGroup normal_group() {
    GridGroup g{"NORMAL", {}, {}};
    std::mt19937 rng(6);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const int bytes[] = {0, 1, 37, 64, 127, 128, 129, 200, 230, 254, 255};
    for (int x : bytes)
        for (int y : bytes) {
            GridCase c;
            c.in[0] = v4(x / 255.0, y / 255.0);
            c.in[1] = v4(x / 255.0, y / 255.0, bytes[size_t(x + y) % std::size(bytes)] / 255.0);
            g.cases.push_back(c);
        }
    for (int k = 0; k < 200; ++k) {
        GridCase c;
        c.in[0] = v4(u(rng), u(rng));
        c.in[1] = v4(u(rng), u(rng), u(rng));
        g.cases.push_back(c);
    }
    GridCase gray;  // the zero vector of the RGB form
    gray.in[1] = v4(0.5, 0.5, 0.5);
    g.cases.push_back(gray);
    g.check = [](const GridCase& c, const GridResult& r) -> std::string {
        const double x = 2 * f(c.in[0][0]) - 1, y = 2 * f(c.in[0][1]) - 1;
        const double z = std::sqrt(std::max(0.0, 1 - x * x - y * y));
        const double l = std::sqrt(x * x + y * y + z * z);
        const std::vector<double> xy_ref{x / l, y / l, z / l}, xy_gpu = {r.out[0][0], r.out[0][1], r.out[0][2]};
        for (size_t k = 0; k < 3; ++k)
            if (!(std::abs(xy_gpu[k] - xy_ref[k]) <= 1e-3))
                return describe("two-channel normal, z = sqrt(max(0, 1 - x^2 - y^2))", c, xy_gpu, xy_ref);
        const double n[3] = {2 * f(c.in[1][0]) - 1, 2 * f(c.in[1][1]) - 1, 2 * f(c.in[1][2]) - 1};
        const double ln = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        const std::vector<double> rgb_ref = ln > 0 ? std::vector<double>{n[0] / ln, n[1] / ln, n[2] / ln}
                                                   : std::vector<double>{0.0, 0.0, 1.0};
        const std::vector<double> rgb_gpu = {r.out[1][0], r.out[1][1], r.out[1][2]};
        for (size_t k = 0; k < 3; ++k)
            if (!(std::abs(rgb_gpu[k] - rgb_ref[k]) <= 1e-5))
                return describe("RGB normal (n + 1) / 2, renormalised", c, rgb_gpu, rgb_ref);
        return {};
    };
    return g;
}

GridGroup matrix_group() {
    GridGroup g{"MATRIX", {}, {}};
    std::mt19937 rng(5);
    const double scales[] = {0.0, 1e-5, 1e-2, 0.3, 3.0, 1e3};
    for (double ax : kAlpha2)
        for (double ay : kAlpha2)
            for (double s : scales) {
                if (ax >= 1.0 || ay >= 1.0) continue;  // the reference mapping needs finite B (a < 1)
                const auto d1 = random_delta(rng, s), d2 = random_delta(rng, s);
                GridCase c;
                c.in[0] = v4(ax, ay);
                c.in[1] = v4(d1.x * d1.x + d2.x * d2.x, d1.y * d1.y + d2.y * d2.y, d1.x * d1.y + d2.x * d2.y);
                g.cases.push_back(c);
            }
    g.check = [](const GridCase& c, const GridResult& r) -> std::string {
        // Independent path: B = (A^-1 - I)^-1 (Eq. 4), B + K (Eq. 6), back with Eq. 7, each its own function.
        const Sym2<double> A = diag(f(c.in[0][0]), f(c.in[0][1]));
        const Sym2<double> K{f(c.in[1][0]), f(c.in[1][2]), f(c.in[1][1])};
        return compare("projected-space matrix filter (TK21 Eq. 4-8)", c, out3(r.out[0]),
                       sym(projected_to_slope_roughness(slope_to_projected_roughness(A) + K)));
    };
    return g;
}

GridGroup curvature_group() {
    GridGroup g{"CURVATURE", {}, {}};
    std::mt19937 rng(6);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const double curvatures[] = {0.0, 0.01, 1.0, 100.0};
    for (double k1 : curvatures)
        for (double k2_ratio : {1.0, 0.3, 0.0, -1.0})
            for (double step : {0.0, 1e-4, 1e-2, 1.0})
                for (int rep = 0; rep < 4; ++rep) {
                    const double angle = 3.141592653589793 * u(rng);
                    const double dlen = rep == 3 ? 0.0 : 1.0 + 0.5 * u(rng);  // unnormalised, or umbilic (0)
                    GridCase c;
                    c.in[0] = v4(k1, k2_ratio * k1, dlen * std::cos(angle), dlen * std::sin(angle));
                    c.in[1] = v4(step * u(rng), step * u(rng), step * u(rng), step * u(rng));
                    c.in[2] = v4(step, 10.0 * (1.0 + u(rng)), 0.5 + 0.4 * u(rng), 1080.0);
                    g.cases.push_back(c);
                }
    g.check = [](const GridCase& c, const GridResult& r) -> std::string {
        const double k1 = f(c.in[0][0]), k2 = f(c.in[0][1]);
        double dx = f(c.in[0][2]), dy = f(c.in[0][3]);
        const double len = std::hypot(dx, dy);
        // Shape operator R diag(k1, k2) R^T with R = [d, d_perp]; an umbilic (d = 0) uses k1 on both axes.
        double e1 = k1, e2 = k2;
        if (len < 1e-6) {
            dx = 1.0, dy = 0.0, e2 = k1;
        } else {
            dx /= len, dy /= len;
        }
        const double sxx = e1 * dx * dx + e2 * dy * dy, syy = e1 * dy * dy + e2 * dx * dx, sxy = (e1 - e2) * dx * dy;
        const double ux = f(c.in[1][0]), uy = f(c.in[1][1]), vx = f(c.in[1][2]), vy = f(c.in[1][3]);
        // Normal derivatives along the two footprint vectors, then K = 2 sigma^2 (du du^T + dv dv^T).
        const double dux = sxx * ux + sxy * uy, duy = sxy * ux + syy * uy;
        const double dvx = sxx * vx + sxy * vy, dvy = sxy * vx + syy * vy;
        const double kxx = 2 * kSigma2 * (dux * dux + dvx * dvx), kyy = 2 * kSigma2 * (duy * duy + dvy * dvy);
        const double kxy = 2 * kSigma2 * (dux * duy + dvx * dvy);
        const double w = f(c.in[2][0]);
        return compare("curvature kernel, shape operator, footprint (SPEC Sec. 4)", c,
                       {r.out[0][0], r.out[0][1], r.out[0][2], r.out[0][3], r.out[1][0], r.out[1][1], r.out[1][2], r.out[1][3]},
                       {kxx, kyy, kxy, kSigma2 * w * w * (k1 * k1 + k2 * k2), sxx, syy, sxy,
                        2.0 * f(c.in[2][1]) * f(c.in[2][2]) / f(c.in[2][3])});
    };
    return g;
}

}  // namespace

std::vector<GridGroup> grid_groups() {
    return {kernels_group(), isotropic_group(), ggx_group(), baked_group(), normal_group(), matrix_group(),
            curvature_group()};
}

std::vector<std::string> run_grid_groups(const std::function<GLuint(const std::string&, std::string&)>& build,
                                         size_t& evaluated) {
    std::vector<std::string> failures;
    evaluated = 0;
    for (const GridGroup& group : grid_groups()) {
        std::string log;
        const GLuint program = build(group.name, log);
        if (!program) {
            failures.push_back(group.name + ": program failed to build: " + log);
            continue;
        }
        const auto results = evaluate_grid(program, group.cases, log);
        glDeleteProgram(program);
        if (results.size() != group.cases.size()) {
            failures.push_back(group.name + ": evaluation failed: " + log);
            continue;
        }
        size_t failed = 0;
        for (size_t i = 0; i < results.size(); ++i) {
            std::string e = group.check(group.cases[i], results[i]);
            if (e.empty()) continue;
            if (++failed <= 3) failures.push_back(group.name + " case " + std::to_string(i) + ": " + e);
        }
        if (failed > 3) failures.push_back(group.name + ": " + std::to_string(failed) + " of " +
                                           std::to_string(results.size()) + " cases differ");
        evaluated += results.size();
    }
    return failures;
}

}  // namespace specbake::gltest
