// Derivative-based NDF filter kernels (K16, T19, TK21). Every function takes the screen-space
// derivatives of a 2D quantity (neighbour minus fragment, as ddx_fine/ddy_fine) and the material's
// squared roughness roughness2 = (alpha_x^2, alpha_y^2), and returns the filtered roughness in
// squared-roughness units, following the listings' arithmetic with their clamps.
#pragma once

#include "bake/isotropic_filter.h"
#include "core/vec.h"

namespace specbake {

// Slope-space half vector as in K16 / TK21 Listings 2-3: h.xy / -|h.z|. Not finite for h.z = 0.
template <class T>
Vec2<T> slope_half_vector(const Vec3<T>& h);

// Orthographically projected half vector, TK21 Sec. 4.1: (h.x, h.y).
template <class T>
Vec2<T> projected_half_vector(const Vec3<T>& h);

// Kernel roughness matrix 2 Sigma = 2 sigma^2 [du; dv]^T [du; dv], TK21 Eq. (3) (and K16 "C = U U^T"
// for slope-space derivatives). du, dv: derivatives along the screen x and y axes.
template <class T>
Sym2<T> kernel_roughness(const Vec2<T>& du, const Vec2<T>& dv, T sigma2);

// Non-axis-aligned filtering diag(roughness2) + 2 Sigma, TK21 Listing 2. With slope-space derivatives
// this is K16's R' = R + 2C (TK21 Eq. 2); with projected derivatives it is TK21 Eq. (9). No clamp.
template <class T>
Sym2<T> filter_non_axis_aligned(const Vec2<T>& roughness2, const Vec2<T>& du, const Vec2<T>& dv, T sigma2);

// Axis-aligned filtering with the kappa clamp, TK21 Listing 3 (K16 bounding rectangle):
// bounds = |du| + |dv| (fwidth), result = saturate(roughness2 + min(2 sigma^2 bounds^2, kappa)).
// A NaN kernel component (0/0 at h.z = 0 in slope space) compares false and is clamped to kappa.
template <class T>
Vec2<T> filter_axis_aligned(const Vec2<T>& roughness2, const Vec2<T>& du, const Vec2<T>& dv, T sigma2, T kappa);

// Full projected-space filtering, TK21 Eq. (4)-(8), Listing 1 with App. D and its determinant clamp
// det(B_bar) >= det(B) and det(m) >= 1. Computed as (B_bar + d I) / max(det(B_bar)/d + tr(B_bar) + d, d)
// with d the clamped determinant: Listing 1 multiplied through by d, so alpha = 0 with a zero kernel
// (singular B_bar) gives A_bar = 0 instead of 0/0. det(B_bar) is expanded into non-negative terms so that
// elongated kernels do not lose it to cancellation. roughness2 >= 1 on an axis (B infinite) gives the limit
// A_bar = 1 on that axis (both axes: I). du, dv are derivatives of (h.x, h.y).
template <class T>
Sym2<T> filter_projected(const Vec2<T>& roughness2, const Vec2<T>& du, const Vec2<T>& dv, T sigma2);

// Isotropic kernel squared roughness from world-space normal differences dn_u, dn_v (TK21 Sec. 5,
// Eq. 12: ||dn|| equals the projected derivative of the averaged normal). Sigma = sigma^2 G with G the
// 2x2 Gram matrix of dn_u, dn_v; Max: 2 lambda_max(Sigma) (Eq. 10), Sum: 2 tr(Sigma) (Eq. 13, Listing 5),
// Mean: tr(Sigma) (Eq. 14).
template <class T>
T isotropic_kernel_roughness(IsotropicReduction reduction, const Vec3<T>& dn_u, const Vec3<T>& dn_v, T sigma2);

// Isotropic filtering of one squared roughness, TK21 Eq. (10)/(13)/(14) as in Listing 5:
// saturate(roughness2 + min(kernel, kappa)). A NaN kernel is clamped to kappa.
template <class T>
T filter_isotropic(T roughness2, T kernel, T kappa);

}  // namespace specbake
