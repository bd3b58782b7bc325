// Minimal 2D/3D vector and 2x2 matrix types for the filtering core, templated on the scalar (float or
// double). Sym2 is the symmetric 2x2 roughness/covariance matrix [[xx, xy], [xy, yy]]; Mat2 is a general
// 2x2 matrix (Jacobians). Only the operations the formulas need; no allocation, no I/O.
#pragma once

#include <cmath>

namespace specbake {

template <class T>
struct Vec2 {
    T x = 0, y = 0;
};

template <class T>
struct Vec3 {
    T x = 0, y = 0, z = 0;
};

// Symmetric 2x2 matrix [[xx, xy], [xy, yy]].
template <class T>
struct Sym2 {
    T xx = 0, xy = 0, yy = 0;
};

// General 2x2 matrix [[m00, m01], [m10, m11]] (row, column).
template <class T>
struct Mat2 {
    T m00 = 0, m01 = 0, m10 = 0, m11 = 0;
};

template <class T> inline Vec2<T> operator+(Vec2<T> a, Vec2<T> b) { return {a.x + b.x, a.y + b.y}; }
template <class T> inline Vec2<T> operator-(Vec2<T> a, Vec2<T> b) { return {a.x - b.x, a.y - b.y}; }
template <class T> inline Vec2<T> operator*(T s, Vec2<T> a) { return {s * a.x, s * a.y}; }
template <class T> inline T dot(Vec2<T> a, Vec2<T> b) { return a.x * b.x + a.y * b.y; }

template <class T> inline Vec3<T> operator+(Vec3<T> a, Vec3<T> b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
template <class T> inline Vec3<T> operator-(Vec3<T> a, Vec3<T> b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
template <class T> inline Vec3<T> operator*(T s, Vec3<T> a) { return {s * a.x, s * a.y, s * a.z}; }
template <class T> inline T dot(Vec3<T> a, Vec3<T> b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <class T> inline T length(Vec3<T> a) { return std::sqrt(dot(a, a)); }
template <class T> inline Vec3<T> normalize(Vec3<T> a) { return (T(1) / length(a)) * a; }

template <class T> inline Sym2<T> operator+(Sym2<T> a, Sym2<T> b) { return {a.xx + b.xx, a.xy + b.xy, a.yy + b.yy}; }
template <class T> inline Sym2<T> operator*(T s, Sym2<T> a) { return {s * a.xx, s * a.xy, s * a.yy}; }
template <class T> inline T det(Sym2<T> a) { return a.xx * a.yy - a.xy * a.xy; }
template <class T> inline T trace(Sym2<T> a) { return a.xx + a.yy; }
template <class T> inline Sym2<T> diag(T x, T y) { return {x, T(0), y}; }
// Quadratic form v^T M v.
template <class T> inline T quadratic_form(Sym2<T> m, Vec2<T> v) {
    return m.xx * v.x * v.x + T(2) * m.xy * v.x * v.y + m.yy * v.y * v.y;
}

template <class T> inline T det(Mat2<T> a) { return a.m00 * a.m11 - a.m01 * a.m10; }

}  // namespace specbake
