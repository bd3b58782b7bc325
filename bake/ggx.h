// GGX and Beckmann microfacet distributions with a full (non-axis-aligned) 2x2 roughness matrix A
// (= 2 x slope covariance, TK21 Sec. 2.1), GGX Smith Lambda and height-correlated G2 (TK21 App. A).
// Vectors are unit vectors in tangent space (z along the shading normal). A is in squared-roughness units:
// the axis-aligned case is A = diag(alpha_x^2, alpha_y^2).
#pragma once

#include "core/vec.h"

namespace specbake {

// GGX NDF, TK21 Eq. (1) with the determinant clamp of App. A.4: det(A) is replaced by max(det(A), tau)
// both in the normalisation and in A^-1 = adj(A) / max(det(A), tau). Use tau = alpha_x^2 alpha_y^2 of the
// unfiltered material (App. A.4). Returns 0 for h_z <= 0. Requires max(det(A), tau) > 0 (else: a Dirac
// delta, the result is not finite).
template <class T>
T ggx_ndf(const Vec3<T>& h, const Sym2<T>& A, T tau);

// Beckmann NDF with a roughness matrix, TK21 Sec. 2.1 (generalised Beckmann), same clamp as ggx_ndf.
template <class T>
T beckmann_ndf(const Vec3<T>& h, const Sym2<T>& A, T tau);

// NDF of a filtered lobe with the tail weight of the unfiltered material (TK21 Sec. 7; the include's
// specaa_filtered_D): rho GGX(A) + (1 - rho) Beckmann(A), alpha2 = a of the unfiltered material, with the
// tail weight rho = clamp(alpha2 sqrt(d) (u^T A^-1 u)^2, 0, 1) along the direction u of h.xy
// (d = max(det A, alpha2^2)). Far from the peak GGX(A) falls along u as 1 / (pi sqrt(d) (u^T A^-1 u)^2
// theta^4), the mixture as alpha2 / (pi theta^4), the unfiltered lobe's tail, in every direction (a weight
// from det A alone leaves the tail along the widened axis of an anisotropic A heavier by its anisotropy).
// Integrates to one (projected) like both parts: both are functions of the slope's A^-1 quadratic form, so
// along every ray of slopes their difference integrates to zero, whatever weight the ray carries.
// rho = alpha2 / sqrt(d) at h.xy = 0 and for isotropic A.
template <class T>
T filtered_ndf(const Vec3<T>& h, const Sym2<T>& A, T alpha2);

// The fast tier's NDF for an isotropic filtered a' = filtered (the include's specaa_filtered_D_isotropic): a
// two-lobe stand-in for GGX(alpha2) convolved with the footprint k = a' - a, rho GGX(g) + (1 - rho) Beckmann(f_b)
// with g = min(a', 1.8 sqrt(a a')), rho = a / g (so the tail is GGX(a)'s, a / (pi tan^4)) and
// f_b = a' + 1.2 sqrt(a a') - 0.6 a; integrates to one; GGX(a) at a' = a. The minimax fit of that form to the
// convolution: 30% largest relative error of D (the plain mixture g = f_b = a', 51%).
template <class T>
T filtered_ndf_isotropic(const Vec3<T>& h, T alpha2, T filtered);

// NDF of GGX(alpha2) seen through a Gaussian footprint (the include's specaa_convolved_D): GGX(alpha2 I)
// convolved with the footprint's slope distribution N(0, K / 2), K = A - alpha2 I (TK21 Eq. 3). GGX is a
// Gaussian scale mixture, GGX(a) = int_0^inf e^-w Beckmann(a / w I) dw, so the convolution is exactly
// int_0^inf e^-w Beckmann(a / w I + K) dw: evaluated by the trapezoid rule in ln w (steps <= 1.1, 12 to 32
// nodes) over [w_lo, 10], w_lo = 0.05 min(1, a / k_max), plus the part below w_lo in closed form (K neglected there);
// GGX(A) when k_max <= 1e-3 a. Keeps the unfiltered lobe's tails and a core as wide as the footprint.
template <class T>
T convolved_ndf(const Vec3<T>& h, const Sym2<T>& A, T alpha2);

// convolved_ndf without the quadrature (the include's specaa_convolved_D_closed_form, its C++ twin): the
// lobes of GGX(a)'s scale mixture wider than the footprint's mean kernel k = tr(K) / 2 in closed form (they
// carry GGX(a)'s tails), the rest as two Beckmann lobes of a e^-p_i I + K whose widths p_i and weights are
// fitted functions of k / a; integrates to one; GGX(A) below k_max = 1e-3 a, as convolved_ndf. Largest
// relative error of D against the convolution: 9.5% for an isotropic K (the fit), up to 70% for a strongly
// anisotropic one (k_max / k_min = 40; tests/bake/test_ggx.cpp, docs/accuracy.md).
template <class T>
T convolved_ndf_closed_form(const Vec3<T>& h, const Sym2<T>& A, T alpha2);

// The same closed form for an isotropic footprint K = kernel I (the include's specaa_convolved_D_isotropic,
// the balanced tier's NDF); kernel = 0 is GGX(alpha2).
template <class T>
T convolved_ndf_isotropic(const Vec3<T>& h, T alpha2, T kernel);

// GGX Smith Lambda for a non-axis-aligned roughness matrix, TK21 App. A.3:
// Lambda(o) = -1/2 + sqrt(o_xy^T A o_xy + o_z^2) / (2 |o_z|). Returns +inf for o_z = 0.
template <class T>
T ggx_lambda(const Vec3<T>& o, const Sym2<T>& A);

// Height-correlated masking-shadowing, TK21 App. A.1 (Heitz 2014):
// G2 = chi+(i.h) chi+(o.h) / (1 + Lambda(i) + Lambda(o)). In [0, 1].
template <class T>
T ggx_g2(const Vec3<T>& i, const Vec3<T>& o, const Vec3<T>& h, const Sym2<T>& A);

}  // namespace specbake
