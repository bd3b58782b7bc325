// Independent double-precision references for the bake tests: Eigen matrix algebra and numerical
// integration, written without calling the code under test.
#pragma once

#include "core/vec.h"

#include <Eigen/Dense>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>

namespace specbake::test {

inline constexpr double kPi = std::numbers::pi;

inline Eigen::Matrix2d to_eigen(const Sym2<double>& m) {
    Eigen::Matrix2d e;
    e << m.xx, m.xy, m.xy, m.yy;
    return e;
}

inline Sym2<double> to_sym(const Sym2<float>& m) { return {m.xx, m.xy, m.yy}; }

// Rotation by angle phi applied to diag(a, b): R diag(a, b) R^T.
inline Eigen::Matrix2d rotated_diag(double a, double b, double phi) {
    Eigen::Matrix2d R;
    R << std::cos(phi), -std::sin(phi), std::sin(phi), std::cos(phi);
    return R * Eigen::Vector2d(a, b).asDiagonal() * R.transpose();
}

// Unit vector with polar angle theta from +z and azimuth phi.
inline Vec3<double> spherical(double theta, double phi) {
    return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

// Midpoint rule over the upper hemisphere of f(m) d omega.
inline double integrate_hemisphere(const std::function<double(const Vec3<double>&)>& f, int n_theta, int n_phi) {
    double sum = 0.0;
    const double dt = 0.5 * kPi / n_theta, dp = 2.0 * kPi / n_phi;
    for (int i = 0; i < n_theta; ++i) {
        const double t = (i + 0.5) * dt;
        for (int j = 0; j < n_phi; ++j) sum += f(spherical(t, (j + 0.5) * dp)) * std::sin(t);
    }
    return sum * dt * dp;
}

// Symmetric positive semi-definite matrix with eigenvalues e1, e2 in random orientation.
inline Eigen::Matrix2d random_psd(std::mt19937_64& rng, double e1, double e2) {
    std::uniform_real_distribution<double> angle(0.0, kPi);
    return rotated_diag(e1, e2, angle(rng));
}

}  // namespace specbake::test
