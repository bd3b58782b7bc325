// Glint dictionary of C21 Sec. 3/6.1: N multiscale 1D slope marginals P_o(x) over L distribution levels,
// each with its texture mip chain baked here (not by glGenerateMipmap), stored 4 marginals per RGBA texel.
#pragma once

#include "core/image.h"
#include "core/result.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace specbake {

// Parameters of the dictionary; the defaults are C21's (N = 192, L = 16, 64 texels, alpha_dict = 0.5 so
// sigma_o = alpha_dict / sqrt 2 = 0.354, lobe std 0.02).
struct GlintDictionarySettings {
    int count = 192;          // N marginals, a multiple of 4 (4 per RGBA texel)
    int levels = 16;          // L distribution levels; level k holds 2^k mirrored pairs of lobes
    int width = 64;           // texels per marginal at mip 0, a power of two; they cover |slope| in [0, 4 sigma_o]
    double alpha_dict = 0.5;  // Beckmann roughness of the coarsest level
    double lobe_std = 0.02;   // slope standard deviation of one lobe
    uint64_t seed = 1;
    friend bool operator==(const GlintDictionarySettings&, const GlintDictionarySettings&) = default;
};

// Validates the settings; the error names the offending parameter.
Result<void> check_glint_dictionary_settings(const GlintDictionarySettings& s);

// sigma_o = alpha_dict / sqrt 2: the per-axis Beckmann slope standard deviation (C21 Sec. 3).
double glint_sigma_o(const GlintDictionarySettings& s);
// Standard deviation of the lobe means: sqrt(sigma_o^2 - lobe_std^2), so that a lobe mean plus its lobe
// has variance sigma_o^2 and the coarsest level converges to the Beckmann marginal exactly (C21 drew the
// means with sigma_o, which makes the level variance sigma_o^2 + lobe_std^2).
double glint_mean_std(const GlintDictionarySettings& s);

struct GlintDictionary {
    GlintDictionarySettings settings;
    int layers = 0;            // levels * count / 4
    int mip_count = 0;         // 1 + log2(width)
    // mips[m]: (width >> m) x layers, 4 channels, every value a 16-bit float stored exactly in a float.
    // Row = layer = k * (count / 4) + i / 4 for level k and marginal i; channel i % 4.
    std::vector<Image> mips;
};

// Layer and channel of marginal i at distribution level k.
inline int glint_layer(const GlintDictionarySettings& s, int level, int marginal) {
    return level * (s.count / 4) + marginal / 4;
}

// Bakes the dictionary. Deterministic: a PCG32 stream per marginal, Marsaglia's polar method, and
// exp/log/erf built from IEEE +,-,*,/ only, so the bytes do not depend on the standard library, the
// thread count or the order of work.
//
// Texel x of mip m holds the mean density over |slope| in [x D_m, (x+1) D_m], D_m = 4 sigma_o 2^m / W,
// exact from erf differences, rescaled so that 2 D_m sum_x v_x = 1. That sum is the integral over
// [-4 sigma_o, 4 sigma_o] of what the GPU reconstructs with linear filtering through texel centres
// (x + 1/2) / w, clamp-to-edge or mirrored addressing, at u = |slope| / (4 sigma_o): each marginal
// integrates to 1 at every level and every mip. Mips are pairwise means, which keep that sum. Each row is
// rounded to half precision with the rounding error carried to the next texel, so the stored halves keep
// the sum to the last texel's rounding.
Result<GlintDictionary> bake_glint_dictionary(const GlintDictionarySettings& settings);

// The dictionary of `settings`, baked once per process and then shared: it depends on nothing but its
// settings (deterministic, see above), so `bake` over many folders, `verify` and `bench` bake it once
// per parameter set. Thread-safe; concurrent first calls with the same settings bake it once.
Result<std::shared_ptr<const GlintDictionary>> shared_glint_dictionary(const GlintDictionarySettings& settings);

// Value of marginal i at level k, mip m, texel x.
inline float glint_texel(const GlintDictionary& d, int level, int marginal, int mip, int x) {
    return d.mips[size_t(mip)].texel(x, glint_layer(d.settings, level, marginal))[marginal % 4];
}

// The exactly rounded IEEE half nearest to v (ties to even), as a double; v in [0, 65504].
double round_to_half(double v);

// Deterministic elementary functions (IEEE +,-,*,/ only; compiled without contraction), shared with the
// glint CPU model of the tests and the simulator so both see the same numbers.
double det_exp(double x);
double det_log(double x);   // x > 0
double det_erf(double x);

}  // namespace specbake
