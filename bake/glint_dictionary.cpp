// Glint dictionary bake (C21 Sec. 3 and 6.1): lobe means from a seeded PCG32, exact box averages of the
// mirrored Gaussian lobes per texel, normalisation under the GPU's texel-centre lookup, baked mips.
#include "bake/glint_dictionary.h"

#include "bake/pcg32.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <utility>

namespace specbake {
namespace {

constexpr double kLn2Hi = 6.93147180369123816490e-01;  // fdlibm's split of ln 2: k * kLn2Hi is exact
constexpr double kLn2Lo = 1.90821492927058770002e-10;
constexpr double kLn2 = 0.69314718055994530942;
constexpr double kSqrtPi = 1.77245385090551602730;
constexpr double kSqrt2 = 1.41421356237309504880;

// A standard normal from Marsaglia's polar method (no trigonometry; det_log for the logarithm).
double normal(Pcg32& rng) {
    for (;;) {
        const double u = 2.0 * rng.uniform() - 1.0, v = 2.0 * rng.uniform() - 1.0;
        const double s = u * u + v * v;
        if (s > 0.0 && s < 1.0) return u * std::sqrt(-2.0 * det_log(s) / s);
    }
}

// Adds the masses of the lobe N(mu, sd^2) over the texels [x D, (x+1) D] to acc. Beyond 7 sd the lobe's
// mass (2.6e-12) is far below the smallest half (6e-8) even as a density over one texel.
void add_lobe(std::vector<double>& acc, double delta, double mu, double sd) {
    const int w = int(acc.size());
    const int first = std::max(0, int(std::floor((mu - 7.0 * sd) / delta)));
    const int last = std::min(w - 1, int(std::floor((mu + 7.0 * sd) / delta)));
    if (last < first) return;
    const double k = 1.0 / (sd * kSqrt2);
    double below = det_erf((first * delta - mu) * k);
    for (int x = first; x <= last; ++x) {
        const double above = det_erf(((x + 1) * delta - mu) * k);
        acc[size_t(x)] += 0.5 * (above - below);
        below = above;
    }
}

// Rounds a row of non-negative values to halves, carrying each rounding error to the next texel, so the
// sum of the row is kept to the rounding of its last texel.
void quantise_row(const std::vector<double>& v, float* dst, int stride) {
    double carry = 0.0;
    for (size_t x = 0; x < v.size(); ++x) {
        const double target = v[x] + carry;
        const double q = round_to_half(std::max(0.0, target));
        carry = target - q;
        dst[x * size_t(stride)] = float(q);
    }
}

// 1 / n, computed once (IEEE division, the same on every platform).
const struct Reciprocals {
    double values[128];
    Reciprocals() {
        values[0] = 0.0;
        for (int n = 1; n < 128; ++n) values[n] = 1.0 / n;
    }
    double operator[](int n) const { return values[n]; }
} kReciprocal;

}  // namespace

double det_exp(double x) {
    if (x < -745.0) return 0.0;
    if (x > 709.0) return HUGE_VAL;
    // x = k ln 2 + r, |r| <= ln2 / 2; exp(r) by its Taylor series (r^24 / 24! < 1e-30).
    const double k = std::nearbyint(x / kLn2);
    const double r = (x - k * kLn2Hi) - k * kLn2Lo;
    double term = 1.0, sum = 1.0;
    for (int n = 1; n < 24; ++n) {
        term *= r / n;
        sum += term;
    }
    return std::ldexp(sum, int(k));
}

double det_log(double x) {
    int e = 0;
    double m = std::frexp(x, &e);  // x = m 2^e, m in [0.5, 1)
    if (m < 0.70710678118654752440) {
        m *= 2.0;
        --e;
    }
    // log m = 2 atanh z, z = (m - 1) / (m + 1), |z| <= 0.1716: 2 sum z^(2n+1) / (2n+1) to n = 14.
    const double z = (m - 1.0) / (m + 1.0), z2 = z * z;
    double power = z, sum = 0.0;
    for (int n = 0; n < 15; ++n) {
        sum += power / (2 * n + 1);
        power *= z2;
    }
    return 2.0 * sum + e * kLn2;
}

double det_erf(double x) {
    if (x < 0.0) return -det_erf(-x);
    if (x >= 6.0) return 1.0;  // erfc(6) = 2e-17
    if (x < 2.5) {
        // Maclaurin series: erf x = 2/sqrt(pi) sum (-1)^n x^(2n+1) / (n! (2n+1)); 60 terms reach 1e-17 at 2.5.
        const double x2 = x * x;
        double term = x, sum = x;
        for (int n = 1; n < 60; ++n) {
            term *= -x2 * kReciprocal[n];
            const double add = term * kReciprocal[2 * n + 1];
            sum += add;
            if (std::fabs(add) < 1e-17 * sum) break;
        }
        return 2.0 / kSqrtPi * sum;
    }
    // erfc x = exp(-x^2) / sqrt(pi) / (x + (1/2) / (x + 1 / (x + (3/2) / (x + ...)))), evaluated backward;
    // 40 terms reach 1e-16 at x = 2.5.
    double f = x;
    for (int n = 40; n >= 1; --n) f = x + (0.5 * n) / f;
    return 1.0 - det_exp(-x * x) / (kSqrtPi * f);
}

double round_to_half(double v) {
    if (v <= 0.0) return 0.0;
    int e = 0;
    std::frexp(v, &e);                                  // v in [2^(e-1), 2^e)
    const double ulp = std::ldexp(1.0, std::max(e - 1, -14) - 10);  // subnormal halves below 2^-14
    return std::nearbyint(v / ulp) * ulp;
}

double glint_sigma_o(const GlintDictionarySettings& s) { return s.alpha_dict / kSqrt2; }

double glint_mean_std(const GlintDictionarySettings& s) {
    const double so = glint_sigma_o(s);
    return std::sqrt(so * so - s.lobe_std * s.lobe_std);
}

Result<void> check_glint_dictionary_settings(const GlintDictionarySettings& s) {
    if (s.count < 4 || s.count > 4096 || s.count % 4 != 0)
        return make_error("glint dictionary: count " + std::to_string(s.count) + " must be a multiple of 4 in [4, 4096]");
    if (s.levels < 1 || s.levels > 20)
        return make_error("glint dictionary: levels " + std::to_string(s.levels) + " must be in [1, 20]");
    if (s.width < 2 || s.width > 4096 || (s.width & (s.width - 1)) != 0)
        return make_error("glint dictionary: width " + std::to_string(s.width) + " must be a power of two in [2, 4096]");
    if (!(s.alpha_dict > 0.0 && s.alpha_dict <= 2.0))
        return make_error("glint dictionary: alpha-dict must be in (0, 2]");
    if (!(s.lobe_std > 0.0 && s.lobe_std < glint_sigma_o(s)))
        return make_error("glint dictionary: lobe-std must be in (0, alpha-dict / sqrt 2)");
    if (size_t(s.levels) * size_t(s.count / 4) > 65535)
        return make_error("glint dictionary: levels x count / 4 exceeds 65535 texture layers");
    return {};
}

Result<GlintDictionary> bake_glint_dictionary(const GlintDictionarySettings& settings) {
    if (auto ok = check_glint_dictionary_settings(settings); !ok) return ok.error();
    GlintDictionary d;
    d.settings = settings;
    d.layers = settings.levels * (settings.count / 4);
    d.mip_count = 1;
    while ((settings.width >> d.mip_count) > 0) ++d.mip_count;
    for (int m = 0; m < d.mip_count; ++m) d.mips.emplace_back(settings.width >> m, d.layers, 4);

    const double sigma_o = glint_sigma_o(settings);
    const double delta = 4.0 * sigma_o / settings.width;
    const double mean_std = glint_mean_std(settings);
    const int W = settings.width;
    tbb::parallel_for(0, settings.count, [&](int i) {
        Pcg32 rng(settings.seed, uint64_t(i));  // stream i: marginal i
        std::vector<double> acc(static_cast<size_t>(W), 0.0);
        int drawn = 0;
        for (int k = 0; k < settings.levels; ++k) {
            // Level k holds the first 2^k means (nested, C21 Fig. 3): a lobe at +mu and its twin at -mu.
            for (; drawn < (1 << k); ++drawn) {
                const double mu = std::fabs(normal(rng) * mean_std);
                add_lobe(acc, delta, mu, settings.lobe_std);
                add_lobe(acc, delta, -mu, settings.lobe_std);
            }
            double total = 0.0;
            for (double a : acc) total += a;
            // Mean density per texel, scaled so that 2 delta sum v = 1: v_x = acc_x / (2 delta total).
            std::vector<double> v(static_cast<size_t>(W));
            for (int x = 0; x < W; ++x) v[size_t(x)] = acc[size_t(x)] / (2.0 * delta * total);
            const int layer = glint_layer(settings, k, i);
            for (int m = 0; m < d.mip_count; ++m) {
                if (m > 0) {
                    for (size_t x = 0; x < v.size() / 2; ++x) v[x] = 0.5 * (v[2 * x] + v[2 * x + 1]);
                    v.resize(v.size() / 2);
                }
                quantise_row(v, d.mips[size_t(m)].texel(0, layer) + i % 4, 4);
            }
        }
    });
    return d;
}

Result<std::shared_ptr<const GlintDictionary>> shared_glint_dictionary(const GlintDictionarySettings& settings) {
    static std::mutex mutex;
    static std::vector<std::pair<GlintDictionarySettings, std::shared_ptr<const GlintDictionary>>> baked;
    // Held over the bake: a second caller with the same settings waits for it instead of baking again.
    const std::lock_guard lock(mutex);
    for (const auto& [s, d] : baked)
        if (s == settings) return d;
    auto d = bake_glint_dictionary(settings);
    if (!d) return d.error();
    auto shared = std::make_shared<const GlintDictionary>(std::move(*d));
    baked.emplace_back(settings, shared);
    return shared;
}

}  // namespace specbake
