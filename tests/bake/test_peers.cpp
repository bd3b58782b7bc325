// VAREF variance formulas and the K16 GGX rectangle integral against direct algebra and quadrature.
#include "bake/ggx.h"
#include "bake/peers.h"
#include "reference.h"

#include <gtest/gtest.h>

namespace specbake {
namespace {

using test::kPi;

TEST(Varef, ScreenSpaceVarianceAndCap) {
    // SCALE * max(|dN/dx|^2, |dN/dy|^2) = 50 * max(1e-4, 4e-4) = 0.02.
    EXPECT_NEAR(varef_screen_space_variance(Vec3<double>{0.01, 0, 0}, Vec3<double>{0, 0.02, 0}), 0.02, 1e-15);
    EXPECT_EQ(varef_screen_space_variance(Vec3<double>{0.5, 0, 0}, Vec3<double>{0, 0, 0}), 0.1);  // MAX_VARIANCE
    EXPECT_EQ(varef_screen_space_variance(Vec3<double>{0, 0, 0}, Vec3<double>{0, 0, 0}), 0.0);
}

TEST(Varef, CurvatureVarianceAndAlpha) {
    // 50 * (0.01 / 0.5)^2 = 0.02 for a sphere of radius 0.5 and 1 cm pixels.
    EXPECT_NEAR(varef_curvature_variance(0.01, 2.0), 0.02, 1e-15);
    EXPECT_EQ(varef_curvature_variance(1.0, 1.0), 0.1);
    // roughness' = sqrt(r^2 + sigma_g^2) with alpha = r^2: alpha' = alpha + variance.
    EXPECT_NEAR(varef_filter_alpha(0.25, 0.02), 0.27, 1e-15);
    EXPECT_NEAR(varef_filter_alpha(0.0, 0.0), 0.04 * 0.04, 1e-18);  // MIN_ROUGHNESS floor
    EXPECT_EQ(varef_filter_alpha(1.0, 0.1), 1.0);
}

// GGX slope distribution of K16 / TK21 Sec. 4.2, P(x, y) = 1 / (pi a b (1 + x^2/a^2 + y^2/b^2)^2).
double slope_pdf(double x, double y, double a, double b) {
    const double q = 1 + x * x / (a * a) + y * y / (b * b);
    return 1 / (kPi * a * b * q * q);
}

TEST(K16Rect, MatchesQuadratureOfTheSlopeDistribution) {
    struct Case {
        double hx, hy, a, b, fx, fy, hz;
    };
    for (const Case& c : {Case{0.1, -0.05, 0.1, 0.2, 0.05, 0.02, 0.9}, Case{0.0, 0.0, 0.02, 0.02, 0.1, 0.1, 1.0},
                          Case{1.5, 0.3, 0.3, 0.1, 0.4, 0.01, 0.5}, Case{-0.2, 0.4, 0.5, 0.5, 0.3, 0.3, 0.3}}) {
        const int n = 1000;
        double sum = 0;
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j)
                sum += slope_pdf(c.hx - c.fx + (i + 0.5) * 2 * c.fx / n, c.hy - c.fy + (j + 0.5) * 2 * c.fy / n, c.a, c.b);
        const double mean = sum / (double(n) * n);
        const double expected = mean / std::max(1e-3, std::pow(c.hz, 4));
        const double got = k16_ggx_rect_ndf(Vec2<double>{c.hx, c.hy}, Vec3<double>{0, 0, c.hz},
                                            Vec2<double>{c.a, c.b}, Vec2<double>{c.fx, c.fy});
        EXPECT_NEAR(got, expected, 1e-4 * expected);
    }
}

TEST(K16Rect, SmallFootprintIsTheGgxNdf) {
    for (double theta : {0.0, 0.4, 1.0}) {
        const Vec3<double> h = test::spherical(theta, 0.6);
        const Vec2<double> hpp{h.x / h.z, h.y / h.z};
        const Vec2<double> alpha{0.3, 0.15};
        const double d = ggx_ndf(h, Sym2<double>{0.09, 0, 0.0225}, 0.0);
        EXPECT_NEAR(k16_ggx_rect_ndf(hpp, h, alpha, Vec2<double>{1e-3, 1e-3}), d, 1e-4 * d);
    }
}

TEST(K16Rect, FootprintClamps) {
    const Vec2<double> alpha{0.05, 0.3};
    // (|dx| + |dy|) / 2, floored at min(alpha, 0.1), capped at footprint_max.
    const Vec2<double> fp = k16_ggx_rect_footprint(Vec2<double>{0.2, 0.0}, Vec2<double>{-0.1, 0.01}, alpha, 1.0);
    EXPECT_NEAR(fp.x, 0.15, 1e-15);
    EXPECT_NEAR(fp.y, 0.1, 1e-15);
    const Vec2<double> big = k16_ggx_rect_footprint(Vec2<double>{5, 5}, Vec2<double>{5, 5}, alpha, 1.0);
    EXPECT_EQ(big.x, 1.0);
    EXPECT_EQ(big.y, 1.0);
}

// Engines' run-time filters against values worked by hand from their formulas (bake/peers.h).
TEST(EnginePeers, GodotLimiterAddsToRSquaredAndClampsAtTheLimit) {
    const Vec3<double> dx{0.1, 0, 0}, dy{0, 0.2, 0};
    // variance 0.25 (0.01 + 0.04) = 0.0125; r'^2 = 0.09 + 0.025 = 0.115; a = 0.115^2.
    EXPECT_NEAR(godot_limiter_alpha2(0.3, dx, dy), 0.115 * 0.115, 1e-15);
    // 2 variance = 0.5 is limited to 0.18: r'^2 = 0.27.
    EXPECT_NEAR(godot_limiter_alpha2(0.3, Vec3<double>{1, 0, 0}, Vec3<double>{0, 0, 0}), 0.27 * 0.27, 1e-15);
    EXPECT_EQ(godot_limiter_alpha2(0.95, Vec3<double>{1, 0, 0}, Vec3<double>{0, 0, 0}), 1.0);
    EXPECT_NEAR(godot_limiter_alpha2(0.3, Vec3<double>{}, Vec3<double>{}), 0.0081, 1e-15);
}

TEST(EnginePeers, UnityGeometricAaAddsToASquaredWithTheThresholdSquared) {
    const Vec3<double> dx{0.1, 0, 0}, dy{0, 0.2, 0};
    // variance 0.1 x 0.05 = 0.005: a + 0.01.
    EXPECT_NEAR(unity_geometric_aa_alpha2(0.01, dx, dy), 0.02, 1e-15);
    // 2 variance = 0.2 is limited to 0.2^2 = 0.04.
    EXPECT_NEAR(unity_geometric_aa_alpha2(0.01, Vec3<double>{1, 0, 0}, Vec3<double>{0, 0, 0}), 0.05, 1e-15);
    EXPECT_EQ(unity_geometric_aa_alpha2(0.99, Vec3<double>{1, 0, 0}, Vec3<double>{0, 0, 0}), 1.0);
}

TEST(EnginePeers, ThreeJsAddsTheLargestDerivativeComponentToR) {
    // max(|dx|, |dy|) = (0.1, 0.25, 0.05): 0.25 added to r = 0.3.
    EXPECT_NEAR(threejs_geometry_roughness_alpha2(0.3, Vec3<double>{0.1, -0.25, 0}, Vec3<double>{0, 0.2, 0.05}),
                0.55 * 0.55 * 0.55 * 0.55, 1e-15);
    EXPECT_NEAR(threejs_geometry_roughness_alpha2(0.01, Vec3<double>{}, Vec3<double>{}), 7.5969140625e-06, 1e-18);
    EXPECT_EQ(threejs_geometry_roughness_alpha2(0.9, Vec3<double>{0.25, 0, 0}, Vec3<double>{}), 1.0);
}

TEST(EnginePeers, BabylonRaisesRToTheSlopesCubeRoot) {
    // max(|dx|^2, |dy|^2) = 0.04; 0.04^0.333 = 0.34238 > 0.3 (worked in double: a = 0.0137386452129849).
    EXPECT_NEAR(babylon_specular_aa_alpha2(0.3, Vec3<double>{0.1, 0, 0}, Vec3<double>{0, 0.2, 0}), 0.013738645212984884,
                1e-15);
    EXPECT_NEAR(babylon_specular_aa_alpha2(0.5, Vec3<double>{0.1, 0, 0}, Vec3<double>{0, 0.2, 0}), 0.0625, 1e-15);
    EXPECT_EQ(babylon_specular_aa_alpha2(0.3, Vec3<double>{2, 0, 0}, Vec3<double>{}), 1.0);
}

}  // namespace
}  // namespace specbake
