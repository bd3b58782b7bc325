// Texture bake internals shared by the bake/texture_bake*.cpp files: the per-texel layout of the linear
// quantities, the decoder of the input maps, the row kernels' declarations and the AVX2 selection.
//
// Every level is a set of area-weighted means over base texels of the linear per-texel quantities
// (normal, p p^T, alpha^2, occlusion, metallic, slope moments), accumulated in double. Rows are held
// structure-of-arrays (one plane of doubles per quantity), so block sums and outputs are plain loops over
// contiguous arrays. A level whose footprints tile the previous level's footprints exactly (both sizes
// divide) is the plain mean of the previous level's blocks, 2 x 2 blocks summed pairwise ((a + c) + (b + d));
// every other level is reduced from the base texels directly. Levels 0 to 4, where they tile, come out of
// one pass over the base rows in column tiles (bake_validated); levels 0 and 1 are computed from registers
// there (base_and_pairs_avx2), the base planes never stored. Each output texel is summed by one thread in
// a fixed order, so results do not depend on the thread count, nor on the CPU: the vector forms perform
// the scalar forms' IEEE operations in the same order. Finished rows go to a sink (bake_texture_rows) or
// into float chains (bake_texture).
#pragma once

#include "bake/constants.h"
#include "bake/texture_bake.h"

#include <tbb/task_arena.h>

#include <atomic>
#include <cmath>
#include <memory>
#include <vector>

namespace specbake::texture_bake_detail {

// Lengths outside [kMinSeed, kMaxSeed] (squared) are out of float range for the estimate of inverse_length.
constexpr double kMinSeed = 1e-30, kMaxSeed = 1e30;

// 1 / sqrt(x): a float estimate refined by one Newton step in double (relative error below 2e-14, against
// 1e-7 for the float estimate), exact division and root outside [kMinSeed, kMaxSeed]. A double square root
// and division cost several times more than the whole rest of a texel's decode; the vector forms perform the
// same IEEE operations, so results do not depend on the CPU.
inline double inverse_length(double x) {
    if (!(x >= kMinSeed && x <= kMaxSeed)) return 1.0 / std::sqrt(x);
    const double y = double(1.0f / std::sqrt(float(x)));
    return y * (1.5 - (0.5 * x) * (y * y));
}

// The inner loops have AVX2 forms (four doubles per instruction), chosen at run time; each performs the
// same IEEE operations in the same order as the scalar form it stands for, so results are bit-identical
// on every CPU. Only "avx2" is enabled for them, not "fma": a fused multiply-add would round differently.
#if defined(__x86_64__)
#define SPECBAKE_AVX2 __attribute__((target("avx2")))
// For the small pieces the loops are built from: vectors passed in registers, not through memory.
#define SPECBAKE_AVX2_INLINE __attribute__((target("avx2"), always_inline)) inline
#endif

#if defined(SPECBAKE_AVX2)
inline bool has_avx2() {
    static const bool yes = (__builtin_cpu_init(), __builtin_cpu_supports("avx2"));
    return yes;
}
#endif

// The fused pass over the largest levels (see bake_validated): width in base texels of its column tiles,
// and how many levels above the base it covers at most.
constexpr int kTileTexels = 512;
constexpr int kMaxFusedLevels = 4;
// Base rows per band of that pass when the caller follows the rows done (TextureBakeRowsDone).
constexpr int kBandBaseRows = 128;

// Per-texel linear quantities, in this order; the ORM and slope groups are present only when needed.
// kRough: 1 where the base texel's normal is steeper than kFlatSlope, else 0 (its mean is the rough share).
enum Channel : int { kPx, kPy, kPz, kPxx, kPyy, kPxy, kA, kRough, kCore };

// 1 for a unit normal (x, y, z) steeper than kFlatSlope (x^2 + y^2 > kFlatSlope^2 z^2), else 0.
inline double rough_indicator(double x, double y, double z) {
    return x * x + y * y > kFlatSlope * kFlatSlope * z * z ? 1.0 : 0.0;
}

struct Layout {
    int count = kCore;
    int occlusion = -1, metallic = -1;  // ORM R and B
    int slope = -1;                     // s.x, s.y, s.x^2, s.y^2, s.x s.y
};

// Smallest |n.z| used for slope space s = -(n.x, n.y) / n.z: keeps grazing normals finite (|s| <= 1e4).
constexpr double kMinSlopeZ = 1e-4;

struct Span1D {
    int first = 0;              // first source index
    std::vector<double> weight; // weight of source index first + k (the overlap length)
};

// Source intervals of the `n` output cells on an axis of `src` source cells: cell i covers
// [i src / n, (i+1) src / n); each source cell weighs by its overlap with that interval.
std::vector<Span1D> footprint_spans(int src, int n);

// Plane c of a row of `width` texels stored as consecutive planes.
inline double* plane(double* row, int c, int width) { return row + size_t(c) * size_t(width); }
inline const double* plane(const double* row, int c, int width) { return row + size_t(c) * size_t(width); }

// The values of `count` integers of a map: float(v) * scale, scale = 1 / (2^bits - 1) (TextureMap).
template <class Integer>
void integers_to_floats(const Integer* s, size_t count, float scale, float* out) {
    for (size_t i = 0; i < count; ++i) out[i] = float(s[i]) * scale;
}

// Floats of texels [x0, x0 + n) of row y of `m`: the map's own memory for a float map, else `scratch`
// (n * channels floats) filled with the integers' values (TextureMap).
inline const float* row_floats(const TextureMap& m, int y, int x0, int n, float* scratch) {
    const size_t at = size_t(y) * m.row_stride + size_t(x0) * size_t(m.channels);
    if (m.f32) return m.f32 + at;
    const size_t count = size_t(n) * size_t(m.channels);
    if (m.u8) integers_to_floats(m.u8 + at, count, 1.0f / 255.0f, scratch);
    else integers_to_floats(m.u16 + at, count, 1.0f / 65535.0f, scratch);
    return scratch;
}

// A per-thread scratch row of at least n floats, for row_floats.
float* scratch_floats(size_t n, int which);

struct Decoder {
    explicit Decoder(const TextureMap& n) : normal(n) {}
    TextureMap normal;
    bool reconstruct = false;
    bool flip_y = false;
    // Roughness: either read per texel from a same-size map, or from a resampled array (a, R, B).
    const TextureMap* roughness = nullptr;
    int roughness_channel = 0;
    bool orm = false;
    std::vector<double> resampled;  // a, R, B per normal-map texel when the sizes differ
    double constant_a = 0.0;
    float constant_r = 0.0f;  // (constant_a)^(1/4) as written at mip 0
    Layout layout;
    // Set when a value the bake reads is NaN or infinite (checked as the texels are decoded; the bake
    // fails afterwards, naming the texel).
    mutable std::atomic<bool> normal_non_finite{false}, roughness_non_finite{false};

    // Unit normal of the base texel whose channels are at c, in the +Y tangent frame; zero-length vectors
    // decode to +Z.
    void decode_normal(const float* c, double n[3], bool& degenerate, bool& non_finite) const;

    // Unit normals of base texels [x0, x0 + n) of row y into nx, ny, nz and their products into xx, yy,
    // xy; returns the degenerate count.
    long long decode_normal_span(int y, int x0, int n, double* nx, double* ny, double* nz, double* xx, double* yy,
                                 double* xy) const;

    // The layout.count quantities of base texels [x0, x0 + W) of row y as planes of W doubles in `v`, and
    // the mip-0 output roughness of every texel in `r0`; returns the number of degenerate normals. The mip-0
    // roughness is (a)^(1/4); for a same-size map that is the clamped input value itself (the double round
    // trip r -> r^4 -> r rounds back to the same float), so the roots are taken only for resampled maps.
    long long decode_span(int y, int x0, int W, double* v, float* r0) const;
};

// Area-weighted resampling of the roughness map onto the normal map's texel grid: each normal texel reads
// the mean alpha^2 (and ORM R, B) of the roughness texels it covers.
std::vector<double> resample_roughness(const TextureMap& rough, int channel, bool orm, int W, int H);

// An array of n values left uninitialised (scratch that is written before it is read).
template <class T>
std::unique_ptr<T[]> uninitialized(size_t n) {
    return n ? std::unique_ptr<T[]>(new T[n]) : nullptr;
}

// Output rows of one base row; null for an output that was not requested.
struct BaseRow {
    float* rough = nullptr;
    float* kern = nullptr;
    float* lean = nullptr;
    float* nrm = nullptr;
};

// Mip-0 outputs of one base row from its planes `v` and output roughness `r0` (texture_bake_planes.cpp).
void write_base_row(const double* v, const float* r0, int W, const Layout& layout, bool flip_y, const BaseRow& out,
                    int kern_ch);

// Means of one row of a level whose footprints are fx x fy blocks of the finer level: `fine` holds the
// fy finer rows (each C planes of pw doubles), `out` receives C planes of w means (texture_bake_planes.cpp).
void block_means(const double* fine, int pw, int fx, int fy, int C, int w, double* out);

// Outputs of one row of a level >= 1 from its means `m` (planes of w doubles), SPEC Sec. 3; returns the
// row's largest |r_out - r_in|, r_in = (mean alpha^2)^(1/4) (texture_bake_texel.cpp).
double finalize_row(const double* m, int w, const Layout& layout, const TextureBakeSettings& s, bool flip_y,
                    float* rough, float* kern, float* lean, float* nrm);

#if defined(SPECBAKE_AVX2)
// Levels 0 and 1 of base rows y and y + 1 over base texels [bx, bx + 2 n) from registers, for a level 1
// whose footprints are 2 x 2 blocks of the base; returns how many means it did (texture_bake_pairs.cpp).
int base_and_pairs(const Decoder& dec, int y, int bx, int n, const BaseRow rows[2], int kern_ch, double* m, int w,
                   long long& degenerate);
#endif

// "<what>: NaN or infinite value at texel (x, y)" for the first such texel of `image` (texture_bake_inputs.cpp).
Error non_finite_error(const std::string& what, const TextureMap& image);

// Input analysis (texture_bake_inputs.cpp): a constant blue channel at full scale (z to reconstruct), and
// values that look sRGB-encoded.
bool blue_is_constant_full_scale(const TextureMap& n);
bool looks_srgb_encoded(const TextureMap& n);

// Checks of the inputs' shapes and of the parts that are not read texel by texel in the decode (which
// checks every value it reads for NaN and infinity itself).
Result<void> validate(const TextureMap& normal, const TextureMap* roughness, int channel, float value);
// The float images' own check: a pixel buffer as large as their size says.
Result<void> validate_buffers(const Image& normal, const Image* roughness);

// Runs `fn` on `threads` threads (0: the calling arena, all available).
template <class Fn>
void run_with_threads(int threads, Fn&& fn) {
    if (threads > 0) {
        tbb::task_arena arena(threads);
        arena.execute(fn);
    } else {
        fn();
    }
}

// The maps a bake reads: the normal map, and the roughness as a channel of a map or, without one, the
// constant perceptual roughness roughness_value.
struct BakeInputs {
    const TextureMap& normal;
    const TextureMap* roughness = nullptr;
    int roughness_channel = 0;
    float roughness_value = 1.0f;
};

// Where a bake's rows go: every finished block of output rows to the sink; rows_done (optional) hears of the
// levels whose rows are all out, inputs_done (optional) of the base rows of the inputs no longer read.
struct BakeRowTargets {
    const TextureBakeRowSink& sink;
    const TextureBakeRowsDone& rows_done;
    const TextureBakeInputsDone& inputs_done;
};

// The bake proper, on validated inputs (texture_bake_levels.cpp).
Result<TextureBakeResult> bake_validated(const BakeInputs& in, const TextureBakeSettings& settings,
                                         const BakeRowTargets& to);

}  // namespace specbake::texture_bake_detail
