// Mappings between the slope-space roughness matrix A and the projected-space ([h_x, h_y]) roughness
// matrix B of the GGX NDF (TK21 Eq. 4 and 7), and the Jacobians of TK21 App. C / Sec. 3-4.1.
#pragma once

#include "core/vec.h"

namespace specbake {

// B = (A^-1 - I)^-1, TK21 Eq. (4), evaluated without inverses as (A - det(A) I) / det(I - A).
// Domain: A symmetric positive semi-definite with eigenvalues < 1 (alpha < 1); singular A is fine
// (alpha = 0 maps to B = 0). An eigenvalue >= 1 has no finite B: the result is not finite.
template <class T>
Sym2<T> slope_to_projected_roughness(const Sym2<T>& A);

// A = (B^-1 + I)^-1, TK21 Eq. (7), in the adjugate-free form of App. D multiplied through by det(B):
// A = (B + det(B) I) / (1 + tr(B) + det(B)). Defined for every positive semi-definite B (also singular).
template <class T>
Sym2<T> projected_to_slope_roughness(const Sym2<T>& B);

// Jacobian from the sphere (angles on the two great circles through h, TK21 App. C) to slope space
// (-h_x/h_z, -h_y/h_z): -1 / (h_z^2 sqrt(1 - h_z^2)) [[h_x, -h_y h_z], [h_y, h_x h_z]]; det = 1/h_z^3.
// Domain 0 < h_z < 1.
template <class T>
Mat2<T> jacobian_sphere_to_slope(const Vec3<T>& h);

// Jacobian from the sphere to the projected plane (h_x, h_y), TK21 Sec. 4.1 / App. C:
// 1 / sqrt(1 - h_z^2) [[h_x h_z, -h_y], [h_y h_z, h_x]]; det = h_z. Domain 0 <= h_z < 1.
template <class T>
Mat2<T> jacobian_sphere_to_projected(const Vec3<T>& h);

// Jacobian from the projected plane to slope space, TK21 App. C:
// -1 / h_z^3 [[1 - h_y^2, h_x h_y], [h_x h_y, 1 - h_x^2]]. Domain h_z > 0.
template <class T>
Mat2<T> jacobian_projected_to_slope(const Vec3<T>& h);

}  // namespace specbake
