// The glint evaluation (bake/glint_model.h, the C++ twin of specaa_glint_*) against independent
// computations: Eq. 18 reproducing Sigma, the cell hash without repeats (and C20's seed with them), the
// filtered mass of a textureGrad read, and the coarse level / high density matching the smooth SDF.
#include "bake/glint_model.h"
#include "reference.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace specbake {
namespace {

using test::kPi;

const GlintDictionary& small_dictionary() {
    static const GlintDictionary d = [] {
        GlintDictionarySettings s;
        s.count = 32;
        return *bake_glint_dictionary(s);
    }();
    return d;
}

TEST(GlintModel, Eq18InverseReproducesTheCovariance) {
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double sigma_o = 0.5 / std::sqrt(2.0);
    for (int k = 0; k < 1000; ++k) {
        const GlintSigmaRho s{0.01 + 0.99 * u(rng), 0.01 + 0.99 * u(rng), -0.99 + 1.98 * u(rng)};
        const std::array<double, 4> mi = glint_inverse_transform(s, sigma_o);
        Eigen::Matrix2d Minv;
        Minv << mi[0], mi[1], mi[2], mi[3];
        const Eigen::Matrix2d M = Minv.inverse();
        Eigen::Matrix2d sigma;
        sigma << s.sx * s.sx, s.rho * s.sx * s.sy, s.rho * s.sx * s.sy, s.sy * s.sy;
        // M Sigma_o M^T = Sigma (C21 Eq. 16-17) for the isotropic Sigma_o = sigma_o^2 I, also after a rotation.
        const double t = 2 * kPi * u(rng);
        Eigen::Matrix2d R;
        R << std::cos(t), -std::sin(t), std::sin(t), std::cos(t);
        const Eigen::Matrix2d Mc = M * R;
        EXPECT_LT((Mc * Mc.transpose() * sigma_o * sigma_o - sigma).norm(), 1e-9 * sigma.norm());
    }
}

TEST(GlintModel, CellDrawsNeverRepeatAndC20SeedsDo) {
    // All cells of a 2048 x 2048 block (signed indices) at spatial levels 0 and 7: the 96 bits of r1
    // and the first word of r2 of each cell are distinct.
    for (int level : {0, 7}) {
        std::vector<std::array<uint32_t, 4>> keys;
        keys.reserve(2048 * 2048);
        for (int t = -1024; t < 1024; ++t)
            for (int s = -1024; s < 1024; ++s) {
                const std::array<uint32_t, 6> r = glint_cell_draws(s, t, level);
                keys.push_back({r[0], r[1], r[2], r[3]});
            }
        std::sort(keys.begin(), keys.end());
        EXPECT_EQ(std::adjacent_find(keys.begin(), keys.end()), keys.end()) << "level " << level;
    }
    // C20's seed s + 1549 t over the same block: cells (s, t) and (s + 1549, t - 1) share every draw.
    std::vector<uint32_t> seeds;
    for (int t = 0; t < 2048; ++t)
        for (int s = 0; s < 2048; ++s) seeds.push_back(uint32_t(s) + 1549u * uint32_t(t));
    std::sort(seeds.begin(), seeds.end());
    const size_t distinct = size_t(std::unique(seeds.begin(), seeds.end()) - seeds.begin());
    EXPECT_LT(distinct, seeds.size() * 8 / 10);
}

TEST(GlintModel, UniformDrawsAreUniform) {
    // Mean and variance of each draw over 2^20 cells: 1/2 and 1/12 within 5 standard errors.
    std::array<double, 6> mean{}, square{};
    const int n = 1 << 20;
    for (int c = 0; c < n; ++c) {
        const std::array<uint32_t, 6> r = glint_cell_draws(c % 1024, c / 1024, 3);
        for (int k = 0; k < 6; ++k) {
            const double v = glint_unit(r[size_t(k)]);
            mean[size_t(k)] += v / n;
            square[size_t(k)] += v * v / n;
        }
    }
    for (int k = 0; k < 6; ++k) {
        EXPECT_NEAR(mean[size_t(k)], 0.5, 5 * std::sqrt(1.0 / 12 / n));
        EXPECT_NEAR(square[size_t(k)] - mean[size_t(k)] * mean[size_t(k)], 1.0 / 12, 5 * std::sqrt(1.0 / 180 / n));
    }
}

// The integral over slopes of a marginal read with textureGrad at any kernel size is 1: every mip and
// every blend of two mips integrates to 1 (C21 Eq. 15 keeps the SDF normalised).
TEST(GlintModel, FilteredMarginalsKeepUnitMass) {
    const GlintDictionary& d = small_dictionary();
    const double range = 4.0 * glint_sigma_o(d.settings);
    std::mt19937_64 rng(9);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int k = 0; k < 300; ++k) {
        const int level = int(u(rng) * d.settings.levels), marginal = int(u(rng) * d.settings.count);
        const double g = std::exp2(-10.0 + 12.0 * u(rng));
        const int n = 4096;
        double mass = 0.0;
        for (int i = 0; i < n; ++i) {
            const double x = -range + (i + 0.5) * 2 * range / n;
            mass += glint_marginal_grad(d, level, marginal, x, g, 0.3 * g) * 2 * range / n;
        }
        EXPECT_NEAR(mass, 1.0, 1e-3) << "level " << level << " marginal " << marginal << " gradient " << g;
    }
}

// P22 over the slope plane of one pixel: the patch SDF integrates to the kept fraction of the mass
// (C21 Sec. 7 conjectures energy conservation; the cut at 4 sigma_o in dictionary space loses < 1e-3).
TEST(GlintModel, PatchSdfIntegratesToOne) {
    const GlintDictionary& d = small_dictionary();
    const GlintSigmaRho s{0.15, 0.1, 0.4};
    GlintParams g;
    g.log_density = 12.0;
    for (const std::array<double, 4>& duv : {std::array<double, 4>{2e-4, 0, 0, 2e-4}, std::array<double, 4>{3e-3, 1e-3, -5e-4, 1e-3}}) {
        const int n = 160;
        const double extent = 6.0 * 0.15;
        double mass = 0.0;
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const std::array<double, 2> hs = {-extent + (x + 0.5) * 2 * extent / n, -extent + (y + 0.5) * 2 * extent / n};
                mass += glint_p22(d, {0.37, 0.61}, duv, hs, {0, 0, 0, 0}, s, g) * (2 * extent / n) * (2 * extent / n);
            }
        EXPECT_NEAR(mass, 1.0, 0.02);
    }
}

// At a coarse level the mean of P22 over many pixels is the correlated Beckmann SDF (C21 Sec. 3), and at
// density e^50 every pixel returns it exactly (C21 Fig. 10).
TEST(GlintModel, ManyPixelsAndHighDensityMatchTheSmoothSdf) {
    const GlintDictionary& d = small_dictionary();
    const GlintSigmaRho s{0.2, 0.1, 0.5};
    GlintParams g;
    // Spatial level 5 and distribution level 12.4 (jittered by zeta = 2): coarse, below the analytic cut.
    // (At fine levels the mean over the dictionary's finite set of marginals carries a sampling error.)
    g.log_density = 31.0;
    const std::array<double, 4> duv = {1e-3, 0, 0, 1e-3};
    std::mt19937_64 rng(4);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const std::array<double, 2> probes[] = {{0.0, 0.0}, {0.15, 0.05}, {-0.1, 0.08}, {0.25, 0.15}};
    for (const std::array<double, 2>& hs : probes) {
        double mean = 0.0;
        const int pixels = 3000;
        for (int p = 0; p < pixels; ++p) mean += glint_p22(d, {100 * u(rng), 100 * u(rng)}, duv, hs, {0, 0, 0, 0}, s, g) / pixels;
        const double target = glint_beckmann_p22(hs[0], hs[1], s);
        EXPECT_NEAR(mean, target, 0.03 * target) << hs[0] << " " << hs[1];
        GlintParams dense = g;
        dense.log_density = 50.0;
        EXPECT_DOUBLE_EQ(glint_p22(d, {0.3, 0.4}, duv, hs, {0, 0, 0, 0}, s, dense), target);
    }
}

// GGX target: the per-cell scale mixture (E ~ Exp(1), Sigma / E) averages to the GGX slope distribution,
// heavy tail included, and e^50 returns it exactly.
TEST(GlintModel, GgxTargetConvergesToGgx) {
    const GlintDictionary& d = small_dictionary();
    const GlintSigmaRho s{0.2, 0.1, 0.5};
    GlintParams g;
    g.log_density = 31.0;
    g.ggx = true;
    const std::array<double, 4> duv = {1e-3, 0, 0, 1e-3};
    std::mt19937_64 rng(8);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    // Independent check of the closed form: GGX with A = 2 Sigma, written from TK21 Eq. (1) in slopes.
    Eigen::Matrix2d A;
    A << 2 * s.sx * s.sx, 2 * s.rho * s.sx * s.sy, 2 * s.rho * s.sx * s.sy, 2 * s.sy * s.sy;
    const std::array<double, 2> probes[] = {{0.0, 0.0}, {0.15, 0.05}, {-0.1, 0.08}, {0.3, 0.12}, {0.6, 0.3}};
    for (const std::array<double, 2>& hs : probes) {
        const Eigen::Vector2d m(hs[0], hs[1]);
        const double q = m.dot(A.inverse() * m);
        const double target = 1.0 / (kPi * std::sqrt(A.determinant()) * (1 + q) * (1 + q));
        EXPECT_NEAR(glint_ggx_p22(hs[0], hs[1], s), target, 1e-12 * target);
        double mean = 0.0;
        const int pixels = 20000;
        for (int p = 0; p < pixels; ++p) mean += glint_p22(d, {100 * u(rng), 100 * u(rng)}, duv, hs, {0, 0, 0, 0}, s, g) / pixels;
        EXPECT_NEAR(mean, target, 0.03 * target) << hs[0] << " " << hs[1];
        GlintParams dense = g;
        dense.log_density = 50.0;
        EXPECT_DOUBLE_EQ(glint_p22(d, {0.3, 0.4}, duv, hs, {0, 0, 0, 0}, s, dense), glint_ggx_p22(hs[0], hs[1], s));
    }
    // The tail probe is far above Beckmann's: the mixture is not a Gaussian.
    EXPECT_GT(glint_ggx_p22(0.6, 0.3, s), 5.0 * glint_beckmann_p22(0.6, 0.3, s));
}

}  // namespace
}  // namespace specbake
