// Derivative-based NDF filter kernels: K16 slope space, TK21 projected space (Listings 1-3, Eq. 9, 10,
// 13, 14).
#include "bake/kernels.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace specbake {
namespace {

// HLSL saturate; a NaN maps to 0 as on GPUs.
template <class T>
T saturate(T x) {
    return x > T(0) ? (x < T(1) ? x : T(1)) : T(0);
}

// min(k, kappa) written so that a NaN kernel (undefined derivative) selects kappa.
template <class T>
T clamp_kernel(T k, T kappa) {
    return k < kappa ? k : kappa;
}

}  // namespace

template <class T>
Vec2<T> slope_half_vector(const Vec3<T>& h) {
    const T inv = -T(1) / std::abs(h.z);  // TK21 Listing 2, the division removed for projected space
    return {h.x * inv, h.y * inv};
}

template <class T>
Vec2<T> projected_half_vector(const Vec3<T>& h) {
    return {h.x, h.y};
}

template <class T>
Sym2<T> kernel_roughness(const Vec2<T>& du, const Vec2<T>& dv, T sigma2) {
    // TK21 Eq. (3): Sigma = sigma^2 [du; dv]^T [du; dv]; the roughness matrix of a Gaussian is 2 Sigma.
    // The derivatives are scaled by sqrt(2 sigma^2) before the products, so that tiny derivatives under a
    // large sigma^2 do not lose their digits in subnormal squares (a float kernel came out indefinite:
    // fuzz/regressions/filter); the off-diagonal is then kept within sqrt(xx yy), which the Gram matrix of
    // exact arithmetic satisfies, so the kernel is positive semi-definite after rounding too.
    const T r = std::sqrt(T(2) * sigma2);
    const Vec2<T> u{r * du.x, r * du.y}, v{r * dv.x, r * dv.y};
    const T xx = u.x * u.x + v.x * v.x, yy = u.y * u.y + v.y * v.y;
    const T bound = std::sqrt(xx) * std::sqrt(yy);
    const T xy = std::clamp(u.x * u.y + v.x * v.y, -bound, bound);
    return {xx, xy, yy};
}

template <class T>
Sym2<T> filter_non_axis_aligned(const Vec2<T>& roughness2, const Vec2<T>& du, const Vec2<T>& dv, T sigma2) {
    return diag(roughness2.x, roughness2.y) + kernel_roughness(du, dv, sigma2);  // TK21 Eq. (2) / (9)
}

template <class T>
Vec2<T> filter_axis_aligned(const Vec2<T>& roughness2, const Vec2<T>& du, const Vec2<T>& dv, T sigma2, T kappa) {
    // TK21 Listing 3: fwidth bounding rectangle, clamped kernel, saturated sum.
    const T bx = std::abs(du.x) + std::abs(dv.x);
    const T by = std::abs(du.y) + std::abs(dv.y);
    const T s = T(2) * sigma2;
    return {saturate(roughness2.x + clamp_kernel(s * bx * bx, kappa)),
            saturate(roughness2.y + clamp_kernel(s * by * by, kappa))};
}

template <class T>
Sym2<T> filter_projected(const Vec2<T>& roughness2, const Vec2<T>& du, const Vec2<T>& dv, T sigma2) {
    const Sym2<T> K = kernel_roughness(du, dv, sigma2);
    const bool rough_x = !(roughness2.x < T(1));
    const bool rough_y = !(roughness2.y < T(1));
    // alpha = 1 maps to an infinite B (Eq. 4); the limit of Eq. (7) keeps that axis at 1 and decouples it.
    if (rough_x && rough_y) return diag(T(1), T(1));
    if (rough_x) {
        const T byy = roughness2.y / (T(1) - roughness2.y) + K.yy;
        return diag(T(1), byy / (T(1) + byy));
    }
    if (rough_y) {
        const T bxx = roughness2.x / (T(1) - roughness2.x) + K.xx;
        return diag(bxx / (T(1) + bxx), T(1));
    }
    // TK21 Eq. (4): projected-space roughness, Listing 1 (axis-aligned material).
    const T bx = roughness2.x / (T(1) - roughness2.x);
    const T by = roughness2.y / (T(1) - roughness2.y);
    const Sym2<T> Bbar = diag(bx, by) + K;  // TK21 Eq. (6)
    // det(Bbar) expanded as det(B) + b_x K_yy + b_y K_xx + det(K) with det(K) = (2 sigma^2 det[du; dv])^2:
    // every term is non-negative, so a long thin kernel (rank one up to rounding) cannot cancel to garbage.
    const T cross = T(2) * sigma2 * (du.x * dv.y - du.y * dv.x);
    const T e = bx * by + bx * K.yy + by * K.xx + cross * cross;
    // TK21 Eq. (7) via App. D with Listing 1's clamps det >= det(B) and det(m) >= 1, where
    // m = Bbar/d + I and det(m) = e/d^2 + tr/d + 1; numerator and denominator are multiplied by d.
    const T d = std::max(e, bx * by);
    const T e_over_d = d > T(0) ? e / d : T(1);  // e = d = 0: singular Bbar, the ratio's limit is 1
    const T denom = std::max(e_over_d + trace(Bbar) + d, d);
    // A finite kernel whose trace or determinant overflows is infinitely wide within the type's range:
    // the limit is I (dividing by the infinite denominator would give 0 instead).
    if (!(denom <= std::numeric_limits<T>::max())) return diag(T(1), T(1));
    return {(Bbar.xx + d) / denom, Bbar.xy / denom, (Bbar.yy + d) / denom};
}

template <class T>
T isotropic_kernel_roughness(IsotropicReduction reduction, const Vec3<T>& dn_u, const Vec3<T>& dn_v, T sigma2) {
    // Sigma = sigma^2 G; its eigenvalues equal those of the projected-space covariance (TK21 Eq. 11-12).
    return reduce_covariance(reduction, sigma2 * dot(dn_u, dn_u), sigma2 * dot(dn_v, dn_v), sigma2 * dot(dn_u, dn_v));
}

template <class T>
T filter_isotropic(T roughness2, T kernel, T kappa) {
    return saturate(roughness2 + clamp_kernel(kernel, kappa));  // TK21 Listing 5
}

#define SPECBAKE_INSTANTIATE(T)                                                                              \
    template Vec2<T> slope_half_vector<T>(const Vec3<T>&);                                                  \
    template Vec2<T> projected_half_vector<T>(const Vec3<T>&);                                              \
    template Sym2<T> kernel_roughness<T>(const Vec2<T>&, const Vec2<T>&, T);                                \
    template Sym2<T> filter_non_axis_aligned<T>(const Vec2<T>&, const Vec2<T>&, const Vec2<T>&, T);         \
    template Vec2<T> filter_axis_aligned<T>(const Vec2<T>&, const Vec2<T>&, const Vec2<T>&, T, T);          \
    template Sym2<T> filter_projected<T>(const Vec2<T>&, const Vec2<T>&, const Vec2<T>&, T);                \
    template T isotropic_kernel_roughness<T>(IsotropicReduction, const Vec3<T>&, const Vec3<T>&, T);        \
    template T filter_isotropic<T>(T, T, T);
SPECBAKE_INSTANTIATE(float)
SPECBAKE_INSTANTIATE(double)
#undef SPECBAKE_INSTANTIATE

}  // namespace specbake
