// Closed-form principal curvatures of the test surfaces (outward normals, convex positive), and the error
// statistics the accuracy tests and the accuracy benchmark report. Independent of the estimators.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "core/trimesh.h"

namespace specbake::testing {

struct Principal {
    double k1 = 0.0, k2 = 0.0;     // |k1| >= |k2|
    double dir[3] = {0, 0, 0};     // unit k1 direction; zero when k1 == k2 (umbilic)
    bool use = true;               // false: leave this vertex out of the statistics (open boundary)
};

inline Principal sorted(double ka, const double da[3], double kb, const double db[3]) {
    Principal p;
    const bool a_first = std::abs(ka) >= std::abs(kb);
    p.k1 = a_first ? ka : kb;
    p.k2 = a_first ? kb : ka;
    const double* d = a_first ? da : db;
    if (std::abs(std::abs(ka) - std::abs(kb)) > 1e-9 * std::max(std::abs(ka), std::abs(kb)))
        for (int i = 0; i < 3; ++i) p.dir[i] = d[i];
    return p;
}

inline Principal sphere_curvature(double radius, const float*) {
    Principal p;
    p.k1 = p.k2 = 1.0 / radius;
    return p;
}

// Cylinder around Z: 1/R around the axis, 0 along it. Vertices on the open rims are not scored.
inline Principal cylinder_curvature(double radius, double height, const float* x) {
    const double phi = std::atan2(x[1], x[0]);
    const double around[3] = {-std::sin(phi), std::cos(phi), 0.0}, along[3] = {0, 0, 1};
    Principal p = sorted(1.0 / radius, around, 0.0, along);
    p.use = std::abs(std::abs(x[2]) - 0.5 * height) > 1e-4 * height;
    return p;
}

// Torus around Z (do Carmo Sec. 3-3): along the tube's meridian 1/r, along the parallel
// cos(psi) / (R + r cos(psi)), with psi the angle around the tube from the outer equator.
inline Principal torus_curvature(double major, double minor, const float* x) {
    const double phi = std::atan2(x[1], x[0]);
    const double rho = std::hypot(x[0], x[1]);
    const double psi = std::atan2(x[2], rho - major);
    const double meridian[3] = {-std::sin(psi) * std::cos(phi), -std::sin(psi) * std::sin(phi), std::cos(psi)};
    const double parallel[3] = {-std::sin(phi), std::cos(phi), 0.0};
    return sorted(1.0 / minor, meridian, std::cos(psi) / (major + minor * std::cos(psi)), parallel);
}

// Ellipsoid x^2/a^2 + y^2/b^2 + z^2/c^2 = 1: Gaussian curvature K = 1 / (a^2 b^2 c^2 h^4) and mean curvature
// H = (a^2 + b^2 + c^2 - |x|^2) / (2 a^2 b^2 c^2 h^3), h^2 = x^2/a^4 + y^2/b^4 + z^2/c^4; k = H -+ sqrt(H^2 - K).
// Directions are not scored (left zero).
inline Principal ellipsoid_curvature(double a, double b, double c, const float* x) {
    // Project the (float) vertex back onto the surface along the ray from the centre.
    const double s = 1.0 / std::sqrt(x[0] * x[0] / (a * a) + x[1] * x[1] / (b * b) + x[2] * x[2] / (c * c));
    const double X = s * x[0], Y = s * x[1], Z = s * x[2];
    const double h2 = X * X / (a * a * a * a) + Y * Y / (b * b * b * b) + Z * Z / (c * c * c * c);
    const double abc2 = a * a * b * b * c * c;
    const double K = 1.0 / (abc2 * h2 * h2);
    const double H = (a * a + b * b + c * c - (X * X + Y * Y + Z * Z)) / (2.0 * abc2 * h2 * std::sqrt(h2));
    const double root = std::sqrt(std::max(0.0, H * H - K));
    Principal p;
    p.k1 = H + root;
    p.k2 = H - root;
    return p;
}

struct CurvatureErrors {
    double rms_k1 = 0.0, rms_k2 = 0.0;  // RMS of |k - k_true| / |k1_true|
    double max_k1 = 0.0, max_k2 = 0.0;
    double rms_angle_deg = 0.0;         // RMS angle between estimated and true k1 directions (as lines)
    size_t scored = 0, scored_directions = 0;
};

// Compares an estimate with the closed form at every referenced, scored vertex. The estimated direction is
// rebuilt in 3D from the vertex's own frame exactly as SPEC Sec. 4 defines it: d.x T + d.y B, with
// T orthogonalised against N and B = cross(N, T) * w.
inline CurvatureErrors compare(const TriMesh& mesh, const VertexCurvature& est,
                               const std::function<Principal(const float*)>& truth,
                               double min_anisotropy = 0.05) {
    CurvatureErrors e;
    std::vector<char> used(mesh.vertex_count(), 0);
    for (uint32_t i : mesh.indices) used[i] = 1;
    double s1 = 0, s2 = 0, sa = 0;
    for (size_t v = 0; v < mesh.vertex_count(); ++v) {
        if (!used[v]) continue;
        const Principal p = truth(&mesh.positions[3 * v]);
        if (!p.use) continue;
        const float* c = &est.values[4 * v];
        const double scale = std::abs(p.k1);
        const double e1 = std::abs(c[0] - p.k1) / scale, e2 = std::abs(c[1] - p.k2) / scale;
        s1 += e1 * e1;
        s2 += e2 * e2;
        e.max_k1 = std::max(e.max_k1, e1);
        e.max_k2 = std::max(e.max_k2, e2);
        ++e.scored;
        const bool has_dir = p.dir[0] != 0.0 || p.dir[1] != 0.0 || p.dir[2] != 0.0;
        if (!has_dir || std::abs(p.k1 - p.k2) < min_anisotropy * std::abs(p.k1)) continue;
        const float* n = &mesh.normals[3 * v];
        const float* t = &mesh.tangents[4 * v];
        double N[3] = {n[0], n[1], n[2]};
        const double nl = std::sqrt(N[0] * N[0] + N[1] * N[1] + N[2] * N[2]);
        for (double& x : N) x /= nl;
        double T[3] = {t[0], t[1], t[2]};
        const double tn = T[0] * N[0] + T[1] * N[1] + T[2] * N[2];
        for (int i = 0; i < 3; ++i) T[i] -= tn * N[i];
        const double tl = std::sqrt(T[0] * T[0] + T[1] * T[1] + T[2] * T[2]);
        for (double& x : T) x /= tl;
        const double B[3] = {t[3] * (N[1] * T[2] - N[2] * T[1]), t[3] * (N[2] * T[0] - N[0] * T[2]),
                             t[3] * (N[0] * T[1] - N[1] * T[0])};
        double D[3], dot = 0, dl = 0;
        for (int i = 0; i < 3; ++i) {
            D[i] = c[2] * T[i] + c[3] * B[i];
            dl += D[i] * D[i];
            dot += D[i] * p.dir[i];
        }
        const double angle = std::acos(std::min(1.0, std::abs(dot) / std::sqrt(dl))) * 180.0 / M_PI;
        sa += angle * angle;
        ++e.scored_directions;
    }
    if (e.scored) {
        e.rms_k1 = std::sqrt(s1 / double(e.scored));
        e.rms_k2 = std::sqrt(s2 / double(e.scored));
    }
    if (e.scored_directions) e.rms_angle_deg = std::sqrt(sa / double(e.scored_directions));
    return e;
}

}  // namespace specbake::testing
