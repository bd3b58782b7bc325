// Glint dictionary (C21 Sec. 3, 6.1) against independent computations: integrals under an emulated GPU
// lookup, the authors' left-edge convention failing that test, texel values recomputed with std::erf,
// convergence of many random cells to the non-axis-aligned Beckmann SDF, determinism.
#include "bake/glint_dictionary.h"
#include "bake/pcg32.h"
#include "reference.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace specbake {
namespace {

using test::kPi;

// GPU texture read of a 1D row of texels at u in [0, 1]: texel x centred at (x + 0.5) / w, linear
// filtering, clamp-to-edge or mirrored-repeat addressing (OpenGL 4.6 Sec. 8.14.2, 8.14.4).
double gpu_lookup(const std::vector<double>& v, double u, bool mirror) {
    const int w = int(v.size());
    const double t = u * w - 0.5;
    const int x0 = int(std::floor(t));
    const double f = t - x0;
    auto at = [&](int x) {
        if (mirror) {
            if (x < 0) x = -1 - x;
            if (x >= w) x = 2 * w - 1 - x;
        }
        return v[size_t(std::clamp(x, 0, w - 1))];
    };
    return (1.0 - f) * at(x0) + f * at(x0 + 1);
}

// Integral over [-range, range] of the lookup at u = |s| / range (the C21 shader's read), midpoint rule.
double lookup_integral(const std::vector<double>& v, double range, bool mirror) {
    const int n = 4096;
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
        const double s = -range + (i + 0.5) * 2.0 * range / n;
        sum += gpu_lookup(v, std::fabs(s) / range, mirror);
    }
    return sum * 2.0 * range / n;
}

std::vector<double> row(const GlintDictionary& d, int level, int marginal, int mip) {
    std::vector<double> v(static_cast<size_t>(d.settings.width >> mip));
    for (size_t x = 0; x < v.size(); ++x) v[x] = glint_texel(d, level, marginal, mip, int(x));
    return v;
}

const GlintDictionary& default_dictionary() {
    static const GlintDictionary d = *bake_glint_dictionary(GlintDictionarySettings{});
    return d;
}

TEST(GlintDictionary, Pcg32MatchesTheReferenceSequence) {
    // pcg32-demo of the PCG C reference (pcg32_srandom_r(&rng, 42u, 54u)): its first six outputs.
    Pcg32 rng(42u, 54u);
    const uint32_t expected[] = {0xa15c02b7u, 0x7b47f409u, 0xba1d3330u, 0x83d2f293u, 0xbfa4784bu, 0xcbed606eu};
    for (uint32_t e : expected) EXPECT_EQ(rng.next(), e);
}

TEST(GlintDictionary, ElementaryFunctionsMatchTheLibrary) {
    for (double x = -7.0; x < 7.0; x += 1e-3) EXPECT_NEAR(det_erf(x), std::erf(x), 2e-14) << x;
    for (double x = 1e-300; x < 1e300; x *= 1.37) EXPECT_NEAR(det_log(x), std::log(x), 1e-15 * std::fabs(std::log(x)) + 1e-300);
    for (double x = -700.0; x < 700.0; x += 0.37) EXPECT_NEAR(det_exp(x) / std::exp(x), 1.0, 2e-15) << x;
    EXPECT_EQ(round_to_half(1.0 / 3.0), 0.333251953125);  // 0x3555
    EXPECT_EQ(round_to_half(1.0 + 1.0 / 2048.0), 1.0);    // a tie rounds to even
    EXPECT_EQ(round_to_half(1.0 + 3.0 / 2048.0), 1.0 + 2.0 / 1024.0);
    EXPECT_EQ(round_to_half(3e-8), std::ldexp(1.0, -24));  // subnormal
}

TEST(GlintDictionary, EveryMarginalIntegratesToOneUnderTheGpuLookup) {
    const GlintDictionary& d = default_dictionary();
    const double range = 4.0 * glint_sigma_o(d.settings);
    EXPECT_EQ(d.mip_count, 7);
    EXPECT_EQ(d.layers, 16 * 48);
    double worst = 0.0;
    for (int k = 0; k < d.settings.levels; ++k)
        for (int i = 0; i < d.settings.count; i += (k % 3 == 0 ? 1 : 7))  // every marginal on every third level
            for (int m = 0; m < d.mip_count; ++m) {
                const std::vector<double> v = row(d, k, i, m);
                for (bool mirror : {false, true}) {
                    const double integral = lookup_integral(v, range, mirror);
                    worst = std::max(worst, std::fabs(integral - 1.0));
                    ASSERT_NEAR(integral, 1.0, 1e-3) << "level " << k << " marginal " << i << " mip " << m;
                }
            }
    RecordProperty("worst_integral_error", std::to_string(worst));
}

// The authors' generator (RD in the design notes) stores the density at texel left edges x D and
// normalises the linear interpolant through those points; the GPU reads the texels at their centres.
TEST(GlintDictionary, LeftEdgeConventionFailsTheGpuIntegral) {
    const double sigma_o = 0.5 / std::sqrt(2.0), lobe = 0.02, range = 4.0 * sigma_o;
    const int w = 64;
    const double delta = range / w;
    std::mt19937_64 rng(7);
    std::normal_distribution<double> normal(0.0, sigma_o);
    double mean_error = 0.0;
    const int marginals = 64;
    for (int i = 0; i < marginals; ++i) {
        const int lobes = 2;  // level 0: one mirrored pair
        std::vector<double> mu(static_cast<size_t>(lobes / 2));
        for (double& m : mu) m = normal(rng);
        std::vector<double> v(static_cast<size_t>(w));
        for (int x = 0; x < w; ++x)
            for (double m : mu)
                for (double s : {x * delta, -x * delta})
                    v[size_t(x)] += std::exp(-0.5 * (s - m) * (s - m) / (lobe * lobe)) / (lobe * std::sqrt(2 * kPi));
        // Normalise the left-edge interpolant (texel x at slope x D, clamped past the last point) over the range.
        double area = 0.0;
        for (int x = 0; x + 1 < w; ++x) area += 0.5 * (v[size_t(x)] + v[size_t(x) + 1]) * delta;
        area += v[size_t(w) - 1] * delta;
        for (double& e : v) e /= 2.0 * area;
        mean_error += std::fabs(lookup_integral(v, range, true) - 1.0) / marginals;
    }
    EXPECT_GT(mean_error, 0.01) << "the left-edge table integrates to 1 under a texel-centre read";
}

// Texel values recomputed independently: the same PCG32 streams, the polar method with std::log, and
// the box averages with std::erf, normalised to 2 D sum v = 1; equal to half precision.
TEST(GlintDictionary, TexelsAreBoxAveragesOfTheLobes) {
    GlintDictionarySettings s;
    s.count = 8;
    s.levels = 6;
    s.seed = 11;
    const GlintDictionary d = *bake_glint_dictionary(s);
    const double sigma_o = s.alpha_dict / std::sqrt(2.0);
    const double mean_std = std::sqrt(sigma_o * sigma_o - s.lobe_std * s.lobe_std);
    const double delta = 4.0 * sigma_o / s.width;
    for (int i = 0; i < s.count; ++i) {
        Pcg32 rng(s.seed, uint64_t(i));
        std::vector<double> mu;
        for (int k = 0; k < s.levels; ++k) {
            while (int(mu.size()) < (1 << k)) {
                double u, v, q;
                do {
                    u = 2.0 * rng.uniform() - 1.0;
                    v = 2.0 * rng.uniform() - 1.0;
                    q = u * u + v * v;
                } while (!(q > 0.0 && q < 1.0));
                mu.push_back(std::fabs(u * std::sqrt(-2.0 * std::log(q) / q) * mean_std));
            }
            std::vector<double> mass(static_cast<size_t>(s.width));
            double total = 0.0;
            for (int x = 0; x < s.width; ++x) {
                for (double m : mu)
                    for (double c : {m, -m}) {
                        const double z = 1.0 / (s.lobe_std * std::sqrt(2.0));
                        mass[size_t(x)] += 0.5 * (std::erf(((x + 1) * delta - c) * z) - std::erf((x * delta - c) * z));
                    }
                total += mass[size_t(x)];
            }
            // Half rounding, plus the rounding error carried from the previous texel.
            for (int x = 0; x < s.width; ++x) {
                const double expected = mass[size_t(x)] / (2.0 * delta * total);
                const double previous = x > 0 ? mass[size_t(x) - 1] / (2.0 * delta * total) : 0.0;
                EXPECT_NEAR(glint_texel(d, k, i, 0, x), expected, 1e-3 * std::max(expected, previous) + 1e-7)
                    << "marginal " << i << " level " << k << " texel " << x;
            }
        }
    }
}

// Mean over random cells of P22_M (C21 Eq. 4-6 and 15 without a kernel): the two marginals read at
// ho = R(-theta) M^-1 m, M from Eq. 18, times det(R(-theta) M^-1); compared with the correlated Beckmann SDF.
TEST(GlintDictionary, ManyCellsConvergeToTheCorrelatedBeckmannSdf) {
    const GlintDictionary& d = default_dictionary();
    const double sigma_o = glint_sigma_o(d.settings), range = 4.0 * sigma_o;
    const double sx = 0.2, sy = 0.1, rho = 0.5;
    // Eq. 18: M = (1/sigma_o) [[sx sqrt(1 - rho^2), rho sx], [0, sy]].
    Eigen::Matrix2d M;
    M << sx * std::sqrt(1.0 - rho * rho), rho * sx, 0.0, sy;
    M /= sigma_o;
    const Eigen::Matrix2d Minv = M.inverse();
    Eigen::Matrix2d sigma;
    sigma << sx * sx, rho * sx * sy, rho * sx * sy, sy * sy;
    ASSERT_LT((M * (sigma_o * sigma_o * Eigen::Matrix2d::Identity()) * M.transpose() - sigma).norm(), 1e-12);
    const Eigen::Matrix2d sigma_inv = sigma.inverse();
    const double norm = 1.0 / (2.0 * kPi * std::sqrt(sigma.determinant()));

    const int grid = 48;
    const double extent = 4.0 * sx;  // slopes in [-4 sx, 4 sx]^2 hold all but 1e-6 of the mass
    auto error_after = [&](int level, int cells, uint64_t seed) {
        std::vector<std::vector<double>> rows(size_t(d.settings.count));
        for (int i = 0; i < d.settings.count; ++i) rows[size_t(i)] = row(d, level, i, 0);
        std::mt19937_64 rng(seed);
        std::uniform_int_distribution<int> pick(0, d.settings.count - 1);
        std::uniform_real_distribution<double> angle(0.0, 2.0 * kPi);
        std::vector<double> mean(size_t(grid * grid), 0.0);
        for (int c = 0; c < cells; ++c) {
            const int i = pick(rng), j = pick(rng);
            const double t = angle(rng);
            Eigen::Matrix2d R;
            R << std::cos(t), std::sin(t), -std::sin(t), std::cos(t);  // R(-theta)
            const Eigen::Matrix2d Mc = R * Minv;
            const double det = Mc.determinant();
            for (int y = 0; y < grid; ++y)
                for (int x = 0; x < grid; ++x) {
                    const Eigen::Vector2d m(-extent + (x + 0.5) * 2 * extent / grid, -extent + (y + 0.5) * 2 * extent / grid);
                    const Eigen::Vector2d ho = Mc * m;
                    if (std::fabs(ho.x()) > range || std::fabs(ho.y()) > range) continue;
                    mean[size_t(y * grid + x)] += gpu_lookup(rows[size_t(i)], std::fabs(ho.x()) / range, true) *
                                                  gpu_lookup(rows[size_t(j)], std::fabs(ho.y()) / range, true) * det / cells;
                }
        }
        double l1 = 0.0, total = 0.0;
        for (int y = 0; y < grid; ++y)
            for (int x = 0; x < grid; ++x) {
                const Eigen::Vector2d m(-extent + (x + 0.5) * 2 * extent / grid, -extent + (y + 0.5) * 2 * extent / grid);
                const double target = norm * std::exp(-0.5 * m.dot(sigma_inv * m));
                l1 += std::fabs(mean[size_t(y * grid + x)] - target);
                total += target;
            }
        return l1 / total;
    };
    const double coarse = error_after(15, 20000, 1), mid = error_after(6, 20000, 2);
    RecordProperty("l1_level15", std::to_string(coarse));
    RecordProperty("l1_level6", std::to_string(mid));
    EXPECT_LT(coarse, 0.01);
    EXPECT_LT(mid, 0.025);
    // More cells under the footprint: the mean approaches the target.
    const double few = error_after(15, 64, 3), more = error_after(15, 1024, 3);
    EXPECT_GT(few, more);
    EXPECT_GT(more, coarse);
}

TEST(GlintDictionary, CoarsestLevelHasTheBeckmannVariance) {
    const GlintDictionary& d = default_dictionary();
    const double sigma_o = glint_sigma_o(d.settings), range = 4.0 * sigma_o;
    double variance = 0.0;
    const int n = 8000;
    for (int i = 0; i < d.settings.count; ++i) {
        const std::vector<double> v = row(d, d.settings.levels - 1, i, 0);
        for (int s = 0; s < n; ++s) {
            const double slope = -range + (s + 0.5) * 2 * range / n;
            variance += slope * slope * gpu_lookup(v, std::fabs(slope) / range, true) * 2 * range / n / d.settings.count;
        }
    }
    // Truncation at 4 sigma_o removes 0.3% of a Gaussian's variance.
    EXPECT_NEAR(variance, sigma_o * sigma_o, 0.02 * sigma_o * sigma_o);
}

TEST(GlintDictionary, SameBytesOnAnyThreadCount) {
    GlintDictionarySettings s;
    s.count = 16;
    s.levels = 12;
    auto bake_with = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
        return *bake_glint_dictionary(s);
    };
    const GlintDictionary a = bake_with(1), b = bake_with(2);
    for (int m = 0; m < a.mip_count; ++m) EXPECT_EQ(a.mips[size_t(m)].pixels, b.mips[size_t(m)].pixels);
    s.seed = 2;
    const GlintDictionary c = *bake_glint_dictionary(s);
    EXPECT_NE(a.mips[0].pixels, c.mips[0].pixels);
}

TEST(GlintDictionary, BadSettingsAreErrors) {
    for (auto change : std::vector<void (*)(GlintDictionarySettings&)>{
             [](GlintDictionarySettings& s) { s.count = 6; }, [](GlintDictionarySettings& s) { s.width = 48; },
             [](GlintDictionarySettings& s) { s.levels = 0; }, [](GlintDictionarySettings& s) { s.lobe_std = 0.5; },
             [](GlintDictionarySettings& s) { s.alpha_dict = -1.0; }}) {
        GlintDictionarySettings s;
        change(s);
        auto d = bake_glint_dictionary(s);
        ASSERT_FALSE(d.ok());
        EXPECT_NE(d.error().message.find("glint dictionary"), std::string::npos);
    }
}

}  // namespace
}  // namespace specbake
