// Small geometry routines shared by the mesh/ algorithms (internal to specbake_mesh): vertex access as
// Eigen vectors, corner angles, mixed-Voronoi corner areas and a branch-free orthonormal basis.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>

#include "core/trimesh.h"

namespace specbake::detail {

using Vec3d = Eigen::Vector3d;

inline Vec3d position(const TriMesh& m, uint32_t v) {
    return {m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]};
}
inline Vec3d normal(const TriMesh& m, uint32_t v) {
    return {m.normals[3 * v], m.normals[3 * v + 1], m.normals[3 * v + 2]};
}
inline Vec3d tangent(const TriMesh& m, uint32_t v) {
    return {m.tangents[4 * v], m.tangents[4 * v + 1], m.tangents[4 * v + 2]};
}

// Angle between two edge vectors, robust for small and near-pi angles (atan2 of |cross| and dot).
inline double angle_between(const Vec3d& a, const Vec3d& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

// atan2(y, x) for y >= 0 (an angle in [0, pi] from its unnormalised sine and cosine, e.g. |a x b| and a.b),
// without a libm call: the ratio of the smaller to the larger magnitude is reduced to |t| <= tan(pi/8) by
// atan(t) = pi/4 + atan((t - 1) / (t + 1)), and atan(t) = t P(t^2) with P the degree-6 Chebyshev fit of
// atan(t)/t on that range (fitted for this function; error below 3e-11 rad, see the Tangents tests). y = 0
// gives 0 or pi by the sign of x (0 for x = 0, as atan2); NaN in gives NaN out.
inline constexpr double kAtanFit[7] = {0.047073481419680201663,  -0.084561928869404960153, 0.11040489227218240327,
                                       -0.14281588772654124125,  0.19999883856551302778,   -0.33333332097609385878,
                                       0.99999999997839877638};  // highest power of t^2 first
inline constexpr double kAtanPi = 3.14159265358979323846, kAtanTanPi8 = 0.41421356237309504880;
inline double corner_angle(double y, double x) {
    if (y == 0.0) return x < 0.0 ? kAtanPi : 0.0;
    const double ax = std::abs(x);
    const bool steep = y > ax;  // beyond pi/4: pi/2 - atan(ax / y)
    double t = steep ? ax / y : y / ax;
    const bool high = t > kAtanTanPi8;
    if (high) t = (t - 1.0) / (t + 1.0);
    const double s = t * t;
    double p = kAtanFit[0];
    for (int i = 1; i < 7; ++i) p = p * s + kAtanFit[i];
    double a = t * p + (high ? 0.25 * kAtanPi : 0.0);
    if (steep) a = 0.5 * kAtanPi - a;
    return x < 0.0 ? kAtanPi - a : a;
}

// Orthonormal basis (t, b) with n = t x b for unit n (Duff et al., "Building an Orthonormal Basis,
// Revisited", JCGT 2017): continuous except across n.z = 0, deterministic.
inline void orthonormal_basis(const Vec3d& n, Vec3d& t, Vec3d& b) {
    const double sign = std::copysign(1.0, n.z());
    const double a = -1.0 / (sign + n.z());
    const double bb = n.x() * n.y() * a;
    t = Vec3d(1.0 + sign * n.x() * n.x() * a, sign * bb, -sign * n.x());
    b = Vec3d(bb, sign + n.y() * n.y() * a, -n.y());
}

// Mixed-Voronoi areas of the three corners of a triangle (Meyer, Desbrun, Schroder & Barr 2003, Fig. 4),
// from its squared edge lengths l_i (edge i opposite corner i) and its area (> 0): the Voronoi region when
// no angle is obtuse, else half the area at the obtuse corner and a quarter at the two others. Sum = area.
inline void mixed_voronoi_areas(double l0, double l1, double l2, double area, double w[3]) {
    // Corner i is obtuse when the opposite squared edge exceeds the sum of the two others.
    if (l0 > l1 + l2) {
        w[0] = 0.5 * area; w[1] = w[2] = 0.25 * area;
    } else if (l1 > l0 + l2) {
        w[1] = 0.5 * area; w[0] = w[2] = 0.25 * area;
    } else if (l2 > l0 + l1) {
        w[2] = 0.5 * area; w[0] = w[1] = 0.25 * area;
    } else {
        // Voronoi area of corner i = (|e_j|^2 cot(angle k) + |e_k|^2 cot(angle j)) / 8, with
        // cot(angle i) = (l_j + l_k - l_i) / (4 area).
        const double inv = 1.0 / (4.0 * area);
        const double c0 = (l1 + l2 - l0) * inv, c1 = (l0 + l2 - l1) * inv, c2 = (l0 + l1 - l2) * inv;
        w[0] = (l1 * c1 + l2 * c2) / 8.0;
        w[1] = (l0 * c0 + l2 * c2) / 8.0;
        w[2] = (l0 * c0 + l1 * c1) / 8.0;
    }
}

}  // namespace specbake::detail

namespace specbake::detail {

// A triangle is degenerate when two corners share a position or it is (numerically) a line: twice its area
// below 1e-10 of its summed squared edge lengths, i.e. its smallest angle under ~1e-10 rad. Such triangles
// carry no usable normal or curvature information.
inline bool is_degenerate_triangle(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2) {
    const Vec3d e0 = p1 - p0, e1 = p2 - p0, e2 = p2 - p1;
    const double twice_area = e0.cross(e1).norm();
    const double scale = e0.squaredNorm() + e1.squaredNorm() + e2.squaredNorm();
    return !(twice_area > 1e-10 * scale);
}

}  // namespace specbake::detail
