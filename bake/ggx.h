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

// GGX Smith Lambda for a non-axis-aligned roughness matrix, TK21 App. A.3:
// Lambda(o) = -1/2 + sqrt(o_xy^T A o_xy + o_z^2) / (2 |o_z|). Returns +inf for o_z = 0.
template <class T>
T ggx_lambda(const Vec3<T>& o, const Sym2<T>& A);

// Height-correlated masking-shadowing, TK21 App. A.1 (Heitz 2014):
// G2 = chi+(i.h) chi+(o.h) / (1 + Lambda(i) + Lambda(o)). In [0, 1].
template <class T>
T ggx_g2(const Vec3<T>& i, const Vec3<T>& o, const Vec3<T>& h, const Sym2<T>& A);

}  // namespace specbake
