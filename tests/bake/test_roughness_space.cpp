// Roughness-space mappings (TK21 Eq. 4, 5, 7) against explicit matrix inverses, and the Jacobians of
// TK21 App. C by finite differences.
#include "bake/ggx.h"
#include "bake/roughness_space.h"
#include "reference.h"

#include <gtest/gtest.h>

namespace specbake {
namespace {

using test::kPi;

Sym2<double> sym(const Eigen::Matrix2d& m) { return {m(0, 0), m(0, 1), m(1, 1)}; }

void expect_matrix_near(const Sym2<double>& got, const Eigen::Matrix2d& want, double tol) {
    EXPECT_NEAR(got.xx, want(0, 0), tol);
    EXPECT_NEAR(got.xy, want(0, 1), tol);
    EXPECT_NEAR(got.yy, want(1, 1), tol);
}

TEST(RoughnessSpace, MatchesExplicitInverses) {
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(0.001, 0.95);
    const Eigen::Matrix2d I = Eigen::Matrix2d::Identity();
    for (int k = 0; k < 1000; ++k) {
        const Eigen::Matrix2d A = test::random_psd(rng, u(rng), u(rng));
        const Eigen::Matrix2d B = (A.inverse() - I).inverse();  // TK21 Eq. (4)
        const double scale = B.norm();
        expect_matrix_near(slope_to_projected_roughness(sym(A)), B, 1e-9 * (1 + scale));
        expect_matrix_near(projected_to_slope_roughness(sym(B)), A, 1e-9);
        const Eigen::Matrix2d Bbar = B + test::random_psd(rng, u(rng), u(rng));
        expect_matrix_near(projected_to_slope_roughness(sym(Bbar)), (Bbar.inverse() + I).inverse(), 1e-9);  // Eq. (7)
    }
}

TEST(RoughnessSpace, SingularAndIsotropicEdges) {
    // alpha = 0 maps to B = 0 and back; a rank-one matrix stays rank one.
    const Sym2<double> zero{0, 0, 0};
    const Sym2<double> b0 = slope_to_projected_roughness(zero);
    EXPECT_EQ(b0.xx, 0.0);
    EXPECT_EQ(b0.yy, 0.0);
    const Sym2<double> a0 = projected_to_slope_roughness(zero);
    EXPECT_EQ(a0.xx, 0.0);
    EXPECT_EQ(a0.yy, 0.0);
    const Sym2<double> rank1{0.09, 0.12, 0.16};  // (0.3, 0.4) (0.3, 0.4)^T
    EXPECT_NEAR(det(projected_to_slope_roughness(rank1)), 0.0, 1e-15);
    // Isotropic: b = a / (1 - a), Listing 1's projRoughness2.
    for (double a : {1e-12, 1e-4, 0.3, 0.9}) {
        EXPECT_NEAR(slope_to_projected_roughness(Sym2<double>{a, 0, a}).xx, a / (1 - a), 1e-12 * (1 + a / (1 - a)));
    }
}

TEST(RoughnessSpace, GgxIsScaledDistributionOfB) {
    // TK21 Eq. (5): D(h) = sqrt(det B / det A) P(h_x, h_y, B), P the elliptical distribution of Sec. 4.2.
    const Eigen::Matrix2d A = test::rotated_diag(0.2 * 0.2, 0.5 * 0.5, 0.4);
    const Sym2<double> B = slope_to_projected_roughness(sym(A));
    const Eigen::Matrix2d Be = test::to_eigen(B);
    for (double theta : {0.0, 0.3, 0.8, 1.3}) {
        const Vec3<double> h = test::spherical(theta, 1.1);
        const Eigen::Vector2d p(h.x, h.y);
        const double q = p.dot(Be.inverse() * p) + 1.0;
        const double P = 1.0 / (kPi * std::sqrt(Be.determinant()) * q * q);
        EXPECT_NEAR(ggx_ndf(h, sym(A), 0.0), std::sqrt(Be.determinant() / A.determinant()) * P,
                    1e-9 * (1 + ggx_ndf(h, sym(A), 0.0)));
    }
}

// Point on the sphere at great-circle angles (psi_x, psi_y) around h = (theta, phi), TK21 App. C.
Vec3<double> sphere_point(double theta, double phi, double psi_x, double psi_y) {
    const double mx = std::cos(psi_y) * std::sin(psi_x), my = std::sin(psi_y), mz = std::cos(psi_y) * std::cos(psi_x);
    const double ct = std::cos(theta), st = std::sin(theta), cp = std::cos(phi), sp = std::sin(phi);
    return {ct * cp * mx - sp * my + st * cp * mz, ct * sp * mx + cp * my + st * sp * mz, -st * mx + ct * mz};
}

Vec2<double> slope(const Vec3<double>& v) { return {-v.x / v.z, -v.y / v.z}; }
Vec2<double> projected(const Vec3<double>& v) { return {v.x, v.y}; }

template <class Map>
Mat2<double> finite_difference(double theta, double phi, Map map) {
    const double e = 1e-6;
    const Vec2<double> px = map(sphere_point(theta, phi, e, 0)) - map(sphere_point(theta, phi, -e, 0));
    const Vec2<double> py = map(sphere_point(theta, phi, 0, e)) - map(sphere_point(theta, phi, 0, -e));
    return {px.x / (2 * e), py.x / (2 * e), px.y / (2 * e), py.y / (2 * e)};
}

void expect_mat_near(const Mat2<double>& a, const Mat2<double>& b, double tol) {
    EXPECT_NEAR(a.m00, b.m00, tol);
    EXPECT_NEAR(a.m01, b.m01, tol);
    EXPECT_NEAR(a.m10, b.m10, tol);
    EXPECT_NEAR(a.m11, b.m11, tol);
}

TEST(Jacobians, MatchFiniteDifferencesAndDeterminants) {
    for (double theta : {0.1, 0.5, 1.0, 1.3, 1.5}) {
        for (double phi : {0.0, 0.7, 2.0, 4.0}) {
            const Vec3<double> h = test::spherical(theta, phi);
            const double scale = 1.0 / std::pow(h.z, 3);
            const Mat2<double> js = jacobian_sphere_to_slope(h);
            expect_mat_near(js, finite_difference(theta, phi, slope), 1e-6 * scale);
            EXPECT_NEAR(det(finite_difference(theta, phi, slope)), 1.0 / std::pow(h.z, 3), 1e-5 * scale * scale);
            EXPECT_NEAR(det(js), 1.0 / std::pow(h.z, 3), 1e-9 * scale);

            const Mat2<double> jp = jacobian_sphere_to_projected(h);
            expect_mat_near(jp, finite_difference(theta, phi, projected), 1e-7);
            EXPECT_NEAR(det(finite_difference(theta, phi, projected)), h.z, 1e-7);
            EXPECT_NEAR(det(jp), h.z, 1e-12);

            // Chain rule of App. C: J(sphere -> slope) = J(projected -> slope) J(sphere -> projected).
            const Mat2<double> jps = jacobian_projected_to_slope(h);
            const Mat2<double> chain{jps.m00 * jp.m00 + jps.m01 * jp.m10, jps.m00 * jp.m01 + jps.m01 * jp.m11,
                                     jps.m10 * jp.m00 + jps.m11 * jp.m10, jps.m10 * jp.m01 + jps.m11 * jp.m11};
            expect_mat_near(chain, js, 1e-9 * scale);
            // Projected -> slope directly: d(-x / sqrt(1 - x^2 - y^2)) / d(x, y).
            const double e = 1e-6;
            auto s = [](double x, double y) { return slope(Vec3<double>{x, y, std::sqrt(1 - x * x - y * y)}); };
            const Vec2<double> dx = s(h.x + e, h.y) - s(h.x - e, h.y);
            const Vec2<double> dy = s(h.x, h.y + e) - s(h.x, h.y - e);
            expect_mat_near(jps, Mat2<double>{dx.x / (2 * e), dy.x / (2 * e), dx.y / (2 * e), dy.y / (2 * e)},
                            1e-5 * scale * scale);
        }
    }
}

}  // namespace
}  // namespace specbake
