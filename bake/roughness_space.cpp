// Slope <-> projected roughness matrices (TK21 Eq. 4, 7, App. D) and the Jacobians of TK21 App. C.
#include "bake/roughness_space.h"

#include <cmath>

namespace specbake {

template <class T>
Sym2<T> slope_to_projected_roughness(const Sym2<T>& A) {
    // (A^-1 - I)^-1 = A (I - A)^-1 = (A - det(A) I) / det(I - A), the inverse of the map below.
    const T dA = det(A);
    const T denom = T(1) - trace(A) + dA;  // det(I - A)
    return {(A.xx - dA) / denom, A.xy / denom, (A.yy - dA) / denom};
}

template <class T>
Sym2<T> projected_to_slope_roughness(const Sym2<T>& B) {
    // TK21 App. D: A = (B/det(B) + I) / det(B/det(B) + I); multiplied through by det(B).
    const T dB = det(B);
    const T denom = T(1) + trace(B) + dB;
    return {(B.xx + dB) / denom, B.xy / denom, (B.yy + dB) / denom};
}

template <class T>
Mat2<T> jacobian_sphere_to_slope(const Vec3<T>& h) {
    const T s = -T(1) / (h.z * h.z * std::sqrt(T(1) - h.z * h.z));  // TK21 Sec. 3 / App. C
    return {s * h.x, -s * h.y * h.z, s * h.y, s * h.x * h.z};
}

template <class T>
Mat2<T> jacobian_sphere_to_projected(const Vec3<T>& h) {
    const T s = T(1) / std::sqrt(T(1) - h.z * h.z);  // TK21 Sec. 4.1 / App. C
    return {s * h.x * h.z, -s * h.y, s * h.y * h.z, s * h.x};
}

template <class T>
Mat2<T> jacobian_projected_to_slope(const Vec3<T>& h) {
    const T s = -T(1) / (h.z * h.z * h.z);  // TK21 App. C
    return {s * (T(1) - h.y * h.y), s * h.x * h.y, s * h.x * h.y, s * (T(1) - h.x * h.x)};
}

#define SPECBAKE_INSTANTIATE(T)                                               \
    template Sym2<T> slope_to_projected_roughness<T>(const Sym2<T>&);        \
    template Sym2<T> projected_to_slope_roughness<T>(const Sym2<T>&);        \
    template Mat2<T> jacobian_sphere_to_slope<T>(const Vec3<T>&);            \
    template Mat2<T> jacobian_sphere_to_projected<T>(const Vec3<T>&);        \
    template Mat2<T> jacobian_projected_to_slope<T>(const Vec3<T>&);
SPECBAKE_INSTANTIATE(float)
SPECBAKE_INSTANTIATE(double)
#undef SPECBAKE_INSTANTIATE

}  // namespace specbake
