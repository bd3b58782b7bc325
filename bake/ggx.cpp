// GGX / Beckmann NDFs with a roughness matrix and GGX masking-shadowing (TK21 Sec. 2.1, App. A).
#include "bake/ggx.h"

#include "bake/isotropic_filter.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

namespace specbake {
namespace {

// [h_x, h_y] A^-1 [h_x, h_y]^T with A^-1 = adj(A) / d, where d is the clamped determinant (App. A.4).
template <class T>
T inverse_quadratic_form(const Sym2<T>& A, T hx, T hy, T d) {
    const Sym2<T> adj{A.yy, -A.xy, A.xx};
    return quadratic_form(adj, Vec2<T>{hx, hy}) / d;
}

}  // namespace

template <class T>
T ggx_ndf(const Vec3<T>& h, const Sym2<T>& A, T tau) {
    if (!(h.z > T(0))) return T(0);  // chi+(h_z)
    const T d = std::max(det(A), tau);  // TK21 App. A.4
    const T q = inverse_quadratic_form(A, h.x, h.y, d) + h.z * h.z;
    return T(1) / (std::numbers::pi_v<T> * std::sqrt(d) * q * q);  // TK21 Eq. (1)
}

template <class T>
T beckmann_ndf(const Vec3<T>& h, const Sym2<T>& A, T tau) {
    if (!(h.z > T(0))) return T(0);
    const T d = std::max(det(A), tau);
    // TK21 Sec. 2.1: the exponent is the slope (h_x/h_z, h_y/h_z) in the quadratic form of A^-1.
    const T e = inverse_quadratic_form(A, h.x / h.z, h.y / h.z, d);
    const T hz2 = h.z * h.z;
    return std::exp(-e) / (std::numbers::pi_v<T> * std::sqrt(d) * hz2 * hz2);
}

template <class T>
T filtered_ndf(const Vec3<T>& h, const Sym2<T>& A, T alpha2) {
    const T tau = alpha2 * alpha2;
    const T d = std::max(std::max(det(A), tau), T(1e-30));
    // Tail weight along the direction u of h.xy: GGX(A) falls there as 1 / (pi sqrt(d) (u^T A^-1 u)^2 s^4)
    // at slope s, the unfiltered lobe as alpha2 / (pi s^4). At h.xy = 0 the isotropic value alpha2 / sqrt(d).
    const T r2 = h.x * h.x + h.y * h.y;
    const T q = r2 > T(0) ? (h.x * h.x * A.yy - T(2) * h.x * h.y * A.xy + h.y * h.y * A.xx) / (d * r2) : T(1) / std::sqrt(d);
    const T rho = std::clamp(alpha2 * std::sqrt(d) * q * q, T(0), T(1));
    const T ggx = ggx_ndf(h, A, tau);
    return ggx + (T(1) - rho) * (beckmann_ndf(h, A, tau) - ggx);
}

template <class T>
T filtered_ndf_isotropic(const Vec3<T>& h, T alpha2, T filtered) {
    if (!(h.z > T(0))) return T(0);
    const T f = std::max(filtered, T(1e-12));
    const T a = std::min(alpha2, f);
    const T t = std::sqrt(a * f);
    const T g = std::max(std::min(f, T(1.8) * t), T(1e-12));  // a mirror (a = 0): no GGX part
    const T fb = f + T(1.2) * t - T(0.6) * a;
    // GGX(g) and Beckmann(f_b) in forms finite as h_z -> 0: rho GGX(g) = a / (pi (g h_z^2 + |h.xy|^2)^2), and
    // Beckmann e^(-u / f_b) (1 + u)^2 / (pi f_b) with u = tan^2(theta_h) bounded where the exponential is 0.
    const T r2 = h.x * h.x + h.y * h.y, z2 = h.z * h.z;
    const T s2 = g * z2 + r2;
    const T u = std::min(r2 / z2, T(1e18));
    const T beckmann = std::exp(-u / fb) * (T(1) + u) * (T(1) + u) / (std::numbers::pi_v<T> * fb);
    return (T(1) - a / g) * beckmann + a / (std::numbers::pi_v<T> * s2 * s2);
}

// The kernel A - a I added to the material's a, projected onto the PSD cone (an anisotropic material's
// A - a I can be indefinite), by the include's formula (specaa_sym_clamp_psd).
template <class T>
Sym2<T> added_kernel(const Sym2<T>& A, T a) {
    const Sym2<T> K{A.xx - a, A.xy, A.yy - a};
    const T half_trace = T(0.5) * (K.xx + K.yy), radius = std::hypot(T(0.5) * (K.xx - K.yy), K.xy);
    const T lmax = half_trace + radius, lmin = half_trace - radius;
    if (lmax <= T(0)) return Sym2<T>{};
    if (!(lmin < T(0))) return K;
    const T f = lmax / (T(2) * radius);
    return Sym2<T>{f * (K.xx - lmin), f * K.xy, f * (K.yy - lmin)};
}

template <class T>
T convolved_ndf(const Vec3<T>& h, const Sym2<T>& A, T alpha2) {
    if (!(h.z > T(0))) return T(0);
    const T a = std::max(alpha2, T(1e-12));
    const Sym2<T> K = added_kernel(A, a);
    const T kmax = std::max(max_eigenvalue_sym2(K.xx, K.yy, K.xy), T(0));
    // No footprint to speak of: GGX(A) itself (within 0.1% of the convolution).
    if (kmax <= T(1e-3) * a) return ggx_ndf(h, Sym2<T>{A.xx + T(1e-12), A.xy, A.yy + T(1e-12)}, a * a);
    // GGX(a) = int_0^inf e^-w Beckmann(a / w I) dw (a Gaussian scale mixture), so GGX(a) convolved with
    // N(0, K / 2) is int_0^inf e^-w Beckmann(a / w I + K) dw: trapezoid rule in ln w on [w_lo, 10], steps
    // of at most 1.1 (12 to 32 nodes), the same nodes also summing the K = 0 integrand ...
    const T w_lo = T(0.05) * std::min(T(1), a / kmax);
    const T s_lo = std::log(w_lo), range = std::log(T(10)) - s_lo;
    const int nodes = int(std::clamp(std::ceil(range / T(1.1)), T(11), T(31))) + 1;
    const T ds = range / T(nodes - 1);
    const T z2 = h.z * h.z;
    const T c = (h.x * h.x + h.y * h.y) / (z2 * a);
    const T unit = T(1) / (std::numbers::pi_v<T> * a * z2 * z2);
    T sum = 0, sum_unfiltered = 0;
    for (int j = 0; j < nodes; ++j) {
        const T w = std::exp(s_lo + ds * T(j)), v = a / w;
        const T weight = (j == 0 || j == nodes - 1) ? T(0.5) : T(1);
        sum += weight * std::exp(-w) * w * beckmann_ndf(h, Sym2<T>{K.xx + v, K.xy, K.yy + v}, v * v);
        // Beckmann(a / w I) = w e^(-c w) / (pi a h_z^4).
        sum_unfiltered += weight * std::exp(-w * (T(1) + c)) * w * w * unit;
    }
    // ... and below w_lo, where a / w >= 20 k_max, in closed form with Beckmann(a / w I + K) to first order
    // in K: Beckmann(v I) (1 + q w^2 / a^2 - tr(K) w / (2 a)), q = h.xy^T K h.xy / h_z^2, v = a / w, so
    // int_0^w_lo e^-w Beckmann dw = (I1 + q I3 / a^2 - tr(K) I2 / (2 a)) / (pi a h_z^4) with
    // In = int_0^w_lo w^n e^(-w (1 + c)) dw, c = tan^2(theta_h) / a (the first-order terms matter in the
    // tails, where the lobe's mass lies below w_lo: up to 2.5% of D at K ~ a without them).
    const T c1 = T(1) + c, x = c1 * w_lo, e = std::exp(-x);
    const T below = x > T(1e-2) ? (T(1) - e * (T(1) + x)) / (c1 * c1) : w_lo * w_lo * (T(0.5) - x / T(3));
    T i2, i3;
    if (x < T(0.5)) {  // series (the closed forms cancel in float)
        i2 = std::pow(w_lo, T(3)) * (T(1) / T(3) - x / T(4) + x * x / T(10) - x * x * x / T(36));
        i3 = std::pow(w_lo, T(4)) * (T(1) / T(4) - x / T(5) + x * x / T(12) - x * x * x / T(42));
    } else {
        const T p2 = T(1) + x + T(0.5) * x * x;
        i2 = T(2) * (T(1) - e * p2) / (c1 * c1 * c1);
        i3 = T(6) * (T(1) - e * (p2 + x * x * x / T(6))) / (c1 * c1 * c1 * c1);
    }
    const T q = (h.x * h.x * K.xx + T(2) * h.x * h.y * K.xy + h.y * h.y * K.yy) / z2;
    const T first_order = q / (a * a) * i3 - T(0.5) * (K.xx + K.yy) / a * i2;
    const T direct = sum * ds + (below + first_order) * unit;
    // The trapezoid's own error (about 1% in the tails, from the node at w_lo) is larger than what a small
    // footprint changes there, so for k_max < a it is cancelled: GGX(a) + the quadrature of
    // Beckmann(a / w I + K) - Beckmann(a / w I) on the same nodes plus the first-order part below w_lo,
    // exact as K -> 0. From k_max = a / 10 to a (logarithmically) it blends into the direct sum, whose
    // relative error is the smaller one once the footprint dominates the lobe.
    const T difference =
        std::max(T(0), ggx_ndf(h, Sym2<T>{a, T(0), a}, a * a) + (sum - sum_unfiltered) * ds + first_order * unit);
    const T blend = std::clamp(std::log10(T(10) * kmax / a), T(0), T(1));
    const T D = difference + blend * (direct - difference);
    // Grazing half vectors (h_z^4 below the type's range) overflow the sums: GGX(a)'s tail there.
    const T s2 = h.x * h.x + h.y * h.y + a * z2;
    return std::isfinite(D) ? D : a / (std::numbers::pi_v<T> * s2 * s2);
}

namespace {

// Node parameters of convolved_ndf_closed_form: p = (p1, q, p2), cubic polynomials c0 + c1 z + c2 z^2 + c3 z^3
// in z = log10(k / a), one set below z = kClosedFormSwitch and one above (columns c0..c3, rows p1, q, p2).
// Fitted to the isotropic convolution (minimax relative error of D over tan^2(theta_h) / a in [0, 1e7]
// and k / a in [1e-3, 1e4]).
constexpr double kClosedFormSwitch = -0.25;
constexpr double kClosedFormSmall[3][4] = {
    {13.4053507, 18.6896586, 8.00904241, 0.357309142},
    {0.175485909, 0.837682955, -0.121406802, -0.297962248},
    {-0.78612125, 0.779175295, 1.05666563, -0.559140109}};
constexpr double kClosedFormLarge[3][4] = {
    {-0.589765801, 1.15587235, -1.77857435, 0.425394192},
    {2.49577999, 0.554438611, 0.921497471, -0.115584935},
    {-2.55947913, -0.177032328, -1.03833038, 0.133253855}};

template <class T>
T cubic(const double (&c)[4], T z) {
    return T(c[0]) + z * (T(c[1]) + z * (T(c[2]) + z * T(c[3])));
}

// The closed form's two nodes at b = k / a: weights w1, w2 and widths a e^-p1, a e^-p2 over the kernel.
template <class T>
struct ClosedFormNodes {
    T w1, w2, v1, v2;
};
template <class T>
ClosedFormNodes<T> closed_form_nodes(T b, T a) {
    const T z = std::clamp(std::log10(b), T(-3), T(4));
    const auto& c = z < T(kClosedFormSwitch) ? kClosedFormSmall : kClosedFormLarge;
    const T p1 = cubic(c[0], z), q = cubic(c[1], z), p2 = cubic(c[2], z);
    // w1 = q b / (1 + b) for small footprints (the nodes a correction of order b), e^(-1/b) / (1 + e^-q) above;
    // w2 = e^(-1/b) - w1, so the nodes carry the mass the truncated mixture leaves.
    const T rest = std::exp(-T(1) / b);
    const T w1 = z < T(kClosedFormSwitch) ? q * b / (T(1) + b) : rest / (T(1) + std::exp(-q));
    return {w1, rest - w1, a * std::exp(-p1), a * std::exp(-p2)};
}

// GGX(a)'s scale mixture over its lobes wider than k, in closed form: (1 - e^-L (1 + L)) / (b L^2) / (pi k h_z^4),
// L = (tan^2(theta_h) + a) / k, written as a (1 - e^-L (1 + L)) / (pi (|h.xy|^2 + a h_z^2)^2) (finite as
// h_z -> 0), a series where that cancels. r2 = |h.xy|^2, z2 = h_z^2 > 0.
template <class T>
T closed_form_tail(T r2, T z2, T a, T k) {
    const T pi = std::numbers::pi_v<T>;
    const T L = (r2 / z2 + a) / k;
    const T Lc = std::min(L, T(80));  // e^-L (1 + L) below float's range beyond (and no inf * 0 at h_z = 0)
    const T s2 = r2 + a * z2;
    return L > T(0.05) ? a * (T(1) - std::exp(-Lc) * (T(1) + Lc)) / (pi * s2 * s2)
                       : (T(0.5) - L / T(3) + L * L / T(8)) * a / (pi * k * k * z2 * z2);
}

// GGX(a) convolved with a small footprint to second order in K: for the isotropic slope density
// f(q) = 1 / (pi a (1 + q / a)^2), f + f' tr(K) / 2 + f'' m^T K m at the slope m, written as
// a / (pi s2^2) (1 - tr(K) h_z^2 / s2 + 6 h.xy^T K h.xy h_z^2 / s2^2), s2 = a h_z^2 + |h.xy|^2.
template <class T>
T small_footprint_ndf(T r2, T z2, T a, T trK, T hKh) {
    const T s2 = a * z2 + r2;
    return a / (std::numbers::pi_v<T> * s2 * s2) * (T(1) - trK * z2 / s2 + T(6) * hKh * z2 / (s2 * s2));
}

// Share of the fitted nodes: 0 below k = 0.03 a (the expansion alone), 1 above 0.1 a, log-linear between.
template <class T>
T closed_form_share(T b) {
    return std::clamp((std::log10(b) - std::log10(T(0.03))) / (std::log10(T(0.1)) - std::log10(T(0.03))), T(0), T(1));
}

// Beckmann(K + v I) (TK21 Sec. 2.1), 0 where its exponential underflows (h_z -> 0).
template <class T>
T beckmann_node(const Vec3<T>& h, const Sym2<T>& K, T v) {
    const Sym2<T> B{K.xx + v, K.xy, K.yy + v};
    const T d = std::max(det(B), T(1e-30)), z2 = h.z * h.z;
    const T g = std::exp(-inverse_quadratic_form(B, h.x, h.y, d) / z2);
    return g > T(0) ? g / (std::numbers::pi_v<T> * std::sqrt(d) * z2 * z2) : T(0);
}

}  // namespace

template <class T>
T convolved_ndf_closed_form(const Vec3<T>& h, const Sym2<T>& A, T alpha2) {
    if (!(h.z > T(0))) return T(0);
    const T a = std::max(alpha2, T(1e-12));
    // The added kernel projected onto the PSD cone, as in convolved_ndf.
    const Sym2<T> K = added_kernel(A, a);
    if (std::max(max_eigenvalue_sym2(K.xx, K.yy, K.xy), T(0)) <= T(1e-3) * a)
        return ggx_ndf(h, Sym2<T>{A.xx + T(1e-12), A.xy, A.yy + T(1e-12)}, a * a);
    // GGX(a) = int_0^inf e^-w Beckmann(a / w I) dw, so the convolution is int_0^inf e^-w Beckmann(a / w I + K) dw
    // (convolved_ndf). With k = tr(K) / 2 (the mean reduction, SPEC Sec. 3) and b = k / a, its lobes wider than
    // k (w < 1 / b) are taken without K (closed_form_tail: GGX(a)'s tails, mass 1 - e^(-1/b)), the rest as
    // two Beckmann nodes Beckmann(a e^(-p_i) I + K) of mass e^(-1/b).
    const T k = std::max(T(0.5) * (K.xx + K.yy), T(1e-6) * a);
    const ClosedFormNodes<T> n = closed_form_nodes(k / a, a);
    const T nodes = n.w1 * beckmann_node(h, K, n.v1) + n.w2 * beckmann_node(h, K, n.v2);
    const T r2 = h.x * h.x + h.y * h.y, z2 = h.z * h.z;
    const T fitted = closed_form_tail(r2, z2, a, k) + nodes;
    // Below k = 0.1 a the fit's error would exceed the change the footprint makes: the second-order
    // expansion there (alone below 0.03 a).
    const T hKh = h.x * h.x * K.xx + T(2) * h.x * h.y * K.xy + h.y * h.y * K.yy;
    const T small = small_footprint_ndf(r2, z2, a, K.xx + K.yy, hKh);
    const T share = closed_form_share(k / a);  // written out: the expansion is huge and wrong at large k
    return std::max(T(0), share * fitted + (T(1) - share) * small);
}

template <class T>
T convolved_ndf_isotropic(const Vec3<T>& h, T alpha2, T kernel) {
    if (!(h.z > T(0))) return T(0);
    const T a = std::max(alpha2, T(1e-12));
    const T k = std::max(kernel, T(1e-6) * a);
    const ClosedFormNodes<T> n = closed_form_nodes(k / a, a);
    const T z2 = h.z * h.z, r2 = h.x * h.x + h.y * h.y, unit = std::numbers::pi_v<T> * z2 * z2;
    // Isotropic nodes Beckmann((k + v_i) I).
    T nodes = T(0);
    for (const auto& [w, v] : {std::pair{n.w1, k + n.v1}, std::pair{n.w2, k + n.v2}}) {
        const T g = std::exp(-r2 / (z2 * v));
        if (g > T(0)) nodes += w * g / (unit * v);
    }
    const T fitted = closed_form_tail(r2, z2, a, k) + nodes;
    const T small = small_footprint_ndf(r2, z2, a, T(2) * k, k * r2);
    const T share = closed_form_share(k / a);  // written out: the expansion is huge and wrong at large k
    return std::max(T(0), share * fitted + (T(1) - share) * small);
}

template <class T>
T ggx_lambda(const Vec3<T>& o, const Sym2<T>& A) {
    if (o.z == T(0)) return std::numeric_limits<T>::infinity();
    // TK21 App. A.3.
    return T(-0.5) + std::sqrt(quadratic_form(A, Vec2<T>{o.x, o.y}) + o.z * o.z) / (T(2) * std::abs(o.z));
}

template <class T>
T ggx_g2(const Vec3<T>& i, const Vec3<T>& o, const Vec3<T>& h, const Sym2<T>& A) {
    if (!(dot(i, h) > T(0)) || !(dot(o, h) > T(0))) return T(0);
    // TK21 App. A.1; an infinite Lambda (grazing direction) gives G2 = 0.
    return T(1) / (T(1) + ggx_lambda(i, A) + ggx_lambda(o, A));
}

#define SPECBAKE_INSTANTIATE(T)                                                 \
    template T ggx_ndf<T>(const Vec3<T>&, const Sym2<T>&, T);                  \
    template T beckmann_ndf<T>(const Vec3<T>&, const Sym2<T>&, T);             \
    template T filtered_ndf<T>(const Vec3<T>&, const Sym2<T>&, T);             \
    template T filtered_ndf_isotropic<T>(const Vec3<T>&, T, T);                 \
    template T convolved_ndf<T>(const Vec3<T>&, const Sym2<T>&, T);            \
    template T convolved_ndf_closed_form<T>(const Vec3<T>&, const Sym2<T>&, T); \
    template T convolved_ndf_isotropic<T>(const Vec3<T>&, T, T);                \
    template T ggx_lambda<T>(const Vec3<T>&, const Sym2<T>&);                   \
    template T ggx_g2<T>(const Vec3<T>&, const Vec3<T>&, const Vec3<T>&, const Sym2<T>&);
SPECBAKE_INSTANTIATE(float)
SPECBAKE_INSTANTIATE(double)
#undef SPECBAKE_INSTANTIATE

}  // namespace specbake
