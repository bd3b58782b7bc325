// Texture bake (SPEC Sec. 3). See texture_bake.h for the footprint convention.
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
#include "bake/texture_bake.h"

#include "core/huge_pages.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

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

namespace specbake {
namespace {

#if defined(SPECBAKE_AVX2)
bool has_avx2() {
    static const bool yes = (__builtin_cpu_init(), __builtin_cpu_supports("avx2"));
    return yes;
}

// Channels 0, 1, 2 of the four texels at c, c + stride, c + 2 stride, c + 3 stride. Three-channel rows
// (the usual RGB map) are split with three loads and shuffles instead of twelve scalar loads.
struct Channels4 {
    __m128 x, y, z;
};
SPECBAKE_AVX2_INLINE Channels4 load_channels4(const float* c, size_t stride) {
    if (stride == 3) {
        const __m128 a = _mm_loadu_ps(c), b = _mm_loadu_ps(c + 4), d = _mm_loadu_ps(c + 8);  // x0 y0 z0 x1 | y1 ..
        const __m128 x = _mm_blend_ps(_mm_blend_ps(a, b, 0x4), d, 0x2);                      // x0 x3 x2 x1 (lanes)
        const __m128 y = _mm_blend_ps(_mm_blend_ps(a, b, 0x9), d, 0x4);                      // y1 y0 y3 y2
        const __m128 z = _mm_blend_ps(_mm_blend_ps(a, b, 0x2), d, 0x9);                      // z2 z1 z0 z3
        return {_mm_shuffle_ps(x, x, _MM_SHUFFLE(1, 2, 3, 0)), _mm_shuffle_ps(y, y, _MM_SHUFFLE(2, 3, 0, 1)),
                _mm_shuffle_ps(z, z, _MM_SHUFFLE(3, 0, 1, 2))};
    }
    auto channel = [&](int k) {
        return _mm_set_ps(c[3 * stride + k], c[2 * stride + k], c[stride + k], c[k]);
    };
    return {channel(0), channel(1), stride > 2 ? channel(2) : _mm_setzero_ps()};
}

// (mask ? a : b) per lane.
SPECBAKE_AVX2_INLINE __m256d select4(__m256d mask, __m256d a, __m256d b) { return _mm256_blendv_pd(b, a, mask); }

// inverse_length of four values.
SPECBAKE_AVX2_INLINE __m256d inverse_length4(__m256d x) {
    const __m256d one = _mm256_set1_pd(1.0);
    const __m256d y = _mm256_cvtps_pd(_mm_div_ps(_mm_set1_ps(1.0f), _mm_sqrt_ps(_mm256_cvtpd_ps(x))));
    const __m256d r = _mm256_mul_pd(
        y, _mm256_sub_pd(_mm256_set1_pd(1.5), _mm256_mul_pd(_mm256_mul_pd(_mm256_set1_pd(0.5), x), _mm256_mul_pd(y, y))));
    const __m256d seeded = _mm256_and_pd(_mm256_cmp_pd(x, _mm256_set1_pd(kMinSeed), _CMP_GE_OQ),
                                         _mm256_cmp_pd(x, _mm256_set1_pd(kMaxSeed), _CMP_LE_OQ));
    if (_mm256_movemask_pd(seeded) == 0xF) return r;
    return select4(seeded, r, _mm256_div_pd(one, _mm256_sqrt_pd(x)));
}

// Unit normals of four texels (Decoder::decode_normal) and their squares.
struct Normal4 {
    __m256d x, y, z, xx, yy;
};

// The four texels at c, c + stride, .. decoded to vectors (Decoder::decode_normal before normalising): v, its
// squared length, and the sum of the values read (NaN if one is not finite).
struct RawNormal4 {
    __m256d x, y, z, len2, read;
};
// y_sign is -0.0 in every lane to flip green (-Y maps), +0.0 otherwise.
SPECBAKE_AVX2_INLINE RawNormal4 raw_normal4(const float* c, size_t stride, bool reconstruct, __m256d y_sign) {
    const __m256d one = _mm256_set1_pd(1.0), two = _mm256_set1_pd(2.0), zero = _mm256_setzero_pd();
    const Channels4 in = load_channels4(c, stride);
    const __m256d vx = _mm256_sub_pd(_mm256_mul_pd(two, _mm256_cvtps_pd(in.x)), one);
    const __m256d vy = _mm256_xor_pd(_mm256_sub_pd(_mm256_mul_pd(two, _mm256_cvtps_pd(in.y)), one), y_sign);
    const __m256d xx = _mm256_mul_pd(vx, vx), yy = _mm256_mul_pd(vy, vy);
    const __m256d vz = reconstruct ? _mm256_sqrt_pd(_mm256_max_pd(_mm256_sub_pd(_mm256_sub_pd(one, xx), yy), zero))
                                   : _mm256_sub_pd(_mm256_mul_pd(two, _mm256_cvtps_pd(in.z)), one);
    const __m256d read = reconstruct ? _mm256_add_pd(vx, vy) : _mm256_add_pd(_mm256_add_pd(vx, vy), vz);
    return {vx, vy, vz, _mm256_add_pd(_mm256_add_pd(xx, yy), _mm256_mul_pd(vz, vz)), read};
}

// The unit normals of `v` given inv = inverse_length4(v.len2); `finite` gathers (read - read) (0 while the
// values are finite, NaN for good once one is not) and `degenerate` counts zero-length vectors (+Z).
SPECBAKE_AVX2_INLINE Normal4 unit_normal4(const RawNormal4& v, __m256d inv, __m256d& finite, long long& degenerate) {
    finite = _mm256_add_pd(finite, _mm256_sub_pd(v.read, v.read));
    const __m256d ok = _mm256_cmp_pd(v.len2, _mm256_set1_pd(1e-20), _CMP_GT_OQ);
    degenerate += 4 - __builtin_popcount(unsigned(_mm256_movemask_pd(ok)));
    const __m256d ux = _mm256_and_pd(ok, _mm256_mul_pd(v.x, inv));
    const __m256d uy = _mm256_and_pd(ok, _mm256_mul_pd(v.y, inv));
    return {ux, uy, select4(ok, _mm256_mul_pd(v.z, inv), _mm256_set1_pd(1.0)), _mm256_mul_pd(ux, ux),
            _mm256_mul_pd(uy, uy)};
}

SPECBAKE_AVX2_INLINE Normal4 decode_normal4(const float* c, size_t stride, bool reconstruct, bool flip_y,
                                            __m256d& finite, long long& degenerate) {
    const RawNormal4 v = raw_normal4(c, stride, reconstruct, _mm256_set1_pd(flip_y ? -0.0 : 0.0));
    return unit_normal4(v, inverse_length4(v.len2), finite, degenerate);
}

// Unit normals and their products of the first multiple of four of the n texels at `row` (`ch` floats each);
// returns how many texels it did.
SPECBAKE_AVX2 int decode_normals_avx2(const float* row, int ch, int n, bool reconstruct, bool flip_y, double* nx,
                                      double* ny, double* nz, double* pxx, double* pyy, double* pxy,
                                      long long& degenerate, bool& non_finite) {
    const size_t stride = size_t(ch);
    __m256d finite = _mm256_setzero_pd();
    int x = 0;
    for (; x + 4 <= n; x += 4) {
        const Normal4 u = decode_normal4(row + size_t(x) * stride, stride, reconstruct, flip_y, finite, degenerate);
        _mm256_storeu_pd(nx + x, u.x);
        _mm256_storeu_pd(ny + x, u.y);
        _mm256_storeu_pd(nz + x, u.z);
        _mm256_storeu_pd(pxx + x, u.xx);
        _mm256_storeu_pd(pyy + x, u.yy);
        _mm256_storeu_pd(pxy + x, _mm256_mul_pd(u.x, u.y));
    }
    if (_mm256_movemask_pd(_mm256_cmp_pd(finite, finite, _CMP_UNORD_Q))) non_finite = true;
    return x;
}

// Roughness of four texels of a same-size map (Decoder::decode_span): r = clamp(t[channel]), a = (r^2)^2 in
// double, and for an ORM map (3+ channels, `orm`) R and B as read; `finite` as in decode_normal4.
struct Roughness4 {
    __m128 r, occlusion, metallic;
    __m256d a;
    bool clamped = false;  // r differs from the value read (or it is NaN)
};
SPECBAKE_AVX2_INLINE Roughness4 decode_roughness4(const float* c, size_t stride, int channel, bool orm,
                                                  __m128& finite) {
    const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
    const Channels4 in = stride >= 3 ? load_channels4(c, stride) : Channels4{};
    const __m128 v = stride >= 3 && channel < 3
                         ? (channel == 0 ? in.x : channel == 1 ? in.y : in.z)
                         : _mm_set_ps(c[3 * stride + channel], c[2 * stride + channel], c[stride + channel], c[channel]);
    finite = _mm_add_ps(finite, _mm_sub_ps(v, v));
    if (orm) finite = _mm_add_ps(finite, _mm_add_ps(_mm_sub_ps(in.x, in.x), _mm_sub_ps(in.z, in.z)));
    // std::clamp(v, 0, 1): v < 0 ? 0 : (1 < v ? 1 : v)
    const __m128 r = _mm_blendv_ps(_mm_blendv_ps(v, one, _mm_cmplt_ps(one, v)), zero, _mm_cmplt_ps(v, zero));
    const __m256d rd = _mm256_cvtps_pd(r);
    const __m256d r2 = _mm256_mul_pd(rd, rd);
    return {r, in.x, in.z, _mm256_mul_pd(r2, r2), _mm_movemask_ps(_mm_cmpneq_ps(r, v)) != 0};
}

// decode_roughness4 over the first multiple of four of the n texels at t into a and r0 (and, when
// `occlusion` is given, ORM R and B); returns how many texels it did.
SPECBAKE_AVX2 int decode_roughness_avx2(const float* t, int ch, int channel, int n, double* a, float* r0,
                                        double* occlusion, double* metallic, bool& non_finite) {
    const size_t stride = size_t(ch);
    __m128 finite = _mm_setzero_ps();
    int x = 0;
    for (; x + 4 <= n; x += 4) {
        const Roughness4 q = decode_roughness4(t + size_t(x) * stride, stride, channel, occlusion != nullptr, finite);
        _mm256_storeu_pd(a + x, q.a);
        _mm_storeu_ps(r0 + x, q.r);
        if (occlusion) {
            _mm256_storeu_pd(occlusion + x, _mm256_cvtps_pd(q.occlusion));
            _mm256_storeu_pd(metallic + x, _mm256_cvtps_pd(q.metallic));
        }
    }
    if (_mm_movemask_ps(_mm_cmpunord_ps(finite, finite))) non_finite = true;
    return x;
}
#endif

// The fused pass over the largest levels (see bake_validated): width in base texels of its column tiles,
// and how many levels above the base it covers at most.
constexpr int kTileTexels = 512;
constexpr int kMaxFusedLevels = 4;

// Per-texel linear quantities, in this order; the ORM and slope groups are present only when needed.
enum Channel : int { kPx, kPy, kPz, kPxx, kPyy, kPxy, kA, kCore };

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
std::vector<Span1D> footprint_spans(int src, int n) {
    std::vector<Span1D> spans(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
        const double x0 = double(i) * src / n;
        const double x1 = double(i + 1) * src / n;
        const int k0 = int(std::floor(x0));
        const int k1 = std::min(src, int(std::ceil(x1)));
        Span1D& s = spans[size_t(i)];
        s.first = k0;
        for (int k = k0; k < k1; ++k) {
            const double w = std::min(double(k + 1), x1) - std::max(double(k), x0);
            s.weight.push_back(std::max(0.0, w));
        }
    }
    return spans;
}

// Plane c of a row of `width` texels stored as consecutive planes.
inline double* plane(double* row, int c, int width) { return row + size_t(c) * size_t(width); }
inline const double* plane(const double* row, int c, int width) { return row + size_t(c) * size_t(width); }

struct Decoder {
    explicit Decoder(const Image& n) : normal(n) {}
    const Image& normal;
    bool reconstruct = false;
    bool flip_y = false;
    // Roughness: either read per texel from a same-size map, or from a resampled array (a, R, B).
    const Image* roughness = nullptr;
    int roughness_channel = 0;
    bool orm = false;
    std::vector<double> resampled;  // a, R, B per normal-map texel when the sizes differ
    double constant_a = 0.0;
    float constant_r = 0.0f;  // (constant_a)^(1/4) as written at mip 0
    Layout layout;
    // Set when a value the bake reads is NaN or infinite (checked as the texels are decoded; the bake
    // fails afterwards, naming the texel).
    mutable std::atomic<bool> normal_non_finite{false}, roughness_non_finite{false};

    // Unit normal of base texel (x, y) in the +Y tangent frame; zero-length vectors decode to +Z.
    void decode_normal(int x, int y, double n[3], bool& degenerate, bool& non_finite) const {
        const float* c = normal.texel(x, y);
        if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || (!reconstruct && !std::isfinite(c[2]))) non_finite = true;
        double nx = 2.0 * c[0] - 1.0;
        double ny = 2.0 * c[1] - 1.0;
        if (flip_y) ny = -ny;
        double nz;
        if (reconstruct) {
            nz = std::sqrt(std::max(0.0, 1.0 - nx * nx - ny * ny));
        } else {
            nz = 2.0 * c[2] - 1.0;
        }
        const double len2 = nx * nx + ny * ny + nz * nz;
        degenerate = !(len2 > 1e-20);
        if (degenerate) {
            n[0] = 0.0, n[1] = 0.0, n[2] = 1.0;
            return;
        }
        const double inv = inverse_length(len2);
        n[0] = nx * inv, n[1] = ny * inv, n[2] = nz * inv;
    }

    // Unit normals of base texels [x0, x0 + n) of row y into nx, ny, nz and their products into xx, yy,
    // xy; returns the degenerate count.
    long long decode_normal_span(int y, int x0, int n, double* nx, double* ny, double* nz, double* xx, double* yy,
                                 double* xy) const {
        long long degenerate_count = 0;
        bool non_finite = false;
        int x = 0;
#if defined(SPECBAKE_AVX2)
        if (has_avx2())
            x = decode_normals_avx2(normal.texel(x0, y), normal.channels, n, reconstruct, flip_y, nx, ny, nz, xx, yy,
                                    xy, degenerate_count, non_finite);
#endif
        for (; x < n; ++x) {
            double v[3];
            bool degenerate = false;
            decode_normal(x0 + x, y, v, degenerate, non_finite);
            degenerate_count += degenerate;
            nx[x] = v[0], ny[x] = v[1], nz[x] = v[2];
            xx[x] = v[0] * v[0], yy[x] = v[1] * v[1], xy[x] = v[0] * v[1];
        }
        if (non_finite) normal_non_finite.store(true, std::memory_order_relaxed);
        return degenerate_count;
    }

    // The layout.count quantities of base texels [x0, x0 + W) of row y as planes of W doubles in `v`, and
    // the mip-0 output roughness of every texel in `r0`; returns the number of degenerate normals. The mip-0
    // roughness is (a)^(1/4); for a same-size map that is the clamped input value itself (the double round
    // trip r -> r^4 -> r rounds back to the same float), so the roots are taken only for resampled maps.
    long long decode_span(int y, int x0, int W, double* v, float* r0) const {
        double* nx = plane(v, kPx, W);
        double* ny = plane(v, kPy, W);
        double* nz = plane(v, kPz, W);
        const long long degenerate = decode_normal_span(y, x0, W, nx, ny, nz, plane(v, kPxx, W), plane(v, kPyy, W),
                                                        plane(v, kPxy, W));
        double* a = plane(v, kA, W);
        double* occlusion = layout.occlusion >= 0 ? plane(v, layout.occlusion, W) : nullptr;
        double* metallic = layout.occlusion >= 0 ? plane(v, layout.metallic, W) : nullptr;
        if (!resampled.empty()) {
            const double* r = resampled.data() + (size_t(y) * size_t(normal.width) + size_t(x0)) * 3;
            for (int x = 0; x < W; ++x) {
                a[x] = r[3 * size_t(x)];
                r0[x] = float(std::sqrt(std::sqrt(std::clamp(a[x], 0.0, 1.0))));
            }
            if (occlusion)
                for (int x = 0; x < W; ++x) occlusion[x] = r[3 * size_t(x) + 1], metallic[x] = r[3 * size_t(x) + 2];
        } else if (roughness) {
            const int ch = roughness->channels;
            const float* t = roughness->texel(x0, y);
            int done = 0;
            bool non_finite = false;
#if defined(SPECBAKE_AVX2)
            if (has_avx2())
                done = decode_roughness_avx2(t, ch, roughness_channel, W, a, r0, occlusion, metallic, non_finite);
#endif
            for (int x = done; x < W; ++x) {
                const float* c = t + size_t(x) * ch;
                if (!std::isfinite(c[roughness_channel]) || (occlusion && !(std::isfinite(c[0]) && std::isfinite(c[2]))))
                    non_finite = true;
                const float r = std::clamp(c[roughness_channel], 0.0f, 1.0f);
                const double r2 = double(r) * double(r);
                a[x] = r2 * r2;  // a = alpha^2 = r^4 (SPEC Sec. 2)
                r0[x] = r;
            }
            if (occlusion)
                for (int x = done; x < W; ++x) occlusion[x] = t[size_t(x) * ch], metallic[x] = t[size_t(x) * ch + 2];
            if (non_finite) roughness_non_finite.store(true, std::memory_order_relaxed);
        } else {
            std::fill(a, a + W, constant_a);
            std::fill(r0, r0 + W, constant_r);
        }
        if (layout.slope >= 0) {
            double* s[5];
            for (int k = 0; k < 5; ++k) s[k] = plane(v, layout.slope + k, W);
            for (int x = 0; x < W; ++x) {
                const double z = std::max(nz[x], kMinSlopeZ);
                const double sx = -nx[x] / z, sy = -ny[x] / z;  // slope space (SPEC Sec. 2)
                s[0][x] = sx, s[1][x] = sy, s[2][x] = sx * sx, s[3][x] = sy * sy, s[4][x] = sx * sy;
            }
        }
        return degenerate;
    }
};

// Area-weighted resampling of the roughness map onto the normal map's texel grid: each normal texel reads
// the mean alpha^2 (and ORM R, B) of the roughness texels it covers.
std::vector<double> resample_roughness(const Image& rough, int channel, bool orm, int W, int H) {
    const std::vector<Span1D> sx = footprint_spans(rough.width, W);
    const std::vector<Span1D> sy = footprint_spans(rough.height, H);
    const double area = (double(rough.width) / W) * (double(rough.height) / H);
    std::vector<double> out(size_t(W) * H * 3);
    tbb::parallel_for(tbb::blocked_range<int>(0, H), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y < rows.end(); ++y) {
            const Span1D& fy = sy[size_t(y)];
            for (int x = 0; x < W; ++x) {
                const Span1D& fx = sx[size_t(x)];
                double acc[3] = {0, 0, 0};
                for (size_t j = 0; j < fy.weight.size(); ++j) {
                    for (size_t i = 0; i < fx.weight.size(); ++i) {
                        const double w = fy.weight[j] * fx.weight[i];
                        const float* t = rough.texel(fx.first + int(i), fy.first + int(j));
                        const double r = std::clamp(double(t[channel]), 0.0, 1.0);
                        acc[0] += w * (r * r) * (r * r);
                        if (orm) acc[1] += w * t[0], acc[2] += w * t[2];
                    }
                }
                double* o = out.data() + (size_t(y) * W + x) * 3;
                for (int c = 0; c < 3; ++c) o[c] = acc[c] / area;
            }
        }
    });
    return out;
}

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

// Float output rows of one block of rows of one level, interleaved as the chains; null for an
// output that was not requested.
struct RowBlock {
    int width = 0;
    int rough_ch = 0, kern_ch = 0, lean_ch = 0, nrm_ch = 0;
    // Not zero-filled: every texel of a block is written before it is emitted.
    std::unique_ptr<float[]> rough, kern, lean, nrm;

    RowBlock(const TextureBakeShape& shape, int w, int rows)
        : width(w),
          rough_ch(shape.roughness_channels),
          kern_ch(shape.kernel_channels),
          lean_ch(shape.lean_channels),
          nrm_ch(shape.normal_channels),
          rough(uninitialized<float>(size_t(w) * rows * size_t(rough_ch))),
          kern(uninitialized<float>(size_t(w) * rows * size_t(kern_ch))),
          lean(uninitialized<float>(size_t(w) * rows * size_t(lean_ch))),
          nrm(uninitialized<float>(size_t(w) * rows * size_t(nrm_ch))) {}

    static float* row(const std::unique_ptr<float[]>& v, int ch, int width, int k) {
        return v ? v.get() + size_t(k) * size_t(width) * size_t(ch) : nullptr;
    }
    float* rough_row(int k) { return row(rough, rough_ch, width, k); }
    float* kern_row(int k) { return row(kern, kern_ch, width, k); }
    float* lean_row(int k) { return row(lean, lean_ch, width, k); }
    float* nrm_row(int k) { return row(nrm, nrm_ch, width, k); }
    // The rows of row k from texel `offset` on.
    BaseRow base_row(int k, int offset) {
        auto from = [&](float* r, int ch) { return r ? r + size_t(offset) * size_t(ch) : nullptr; };
        return {from(rough_row(k), rough_ch), from(kern_row(k), kern_ch), from(lean_row(k), lean_ch),
                from(nrm_row(k), nrm_ch)};
    }

    void emit(const TextureBakeRowSink& sink, int level, int x0, int y0, int rows) const {
        TextureBakeRows r;
        r.level = level, r.x0 = x0, r.y0 = y0, r.rows = rows, r.width = width;
        r.roughness = rough.get();
        r.kernel = kern.get();
        r.lean = lean.get();
        r.normal = nrm.get();
        sink(r);
    }
};

#if defined(SPECBAKE_AVX2)
// Four floats float(scale * src[i] + offset), the product and sum in double as in the scalar form.
SPECBAKE_AVX2_INLINE __m128 to_float4(const double* src, double scale, double offset) {
    if (scale == 1.0 && offset == 0.0) return _mm256_cvtpd_ps(_mm256_loadu_pd(src));  // keeps the sign of a zero
    return _mm256_cvtpd_ps(_mm256_add_pd(_mm256_mul_pd(_mm256_set1_pd(scale), _mm256_loadu_pd(src)),
                                         _mm256_set1_pd(offset)));
}

// Four texels of three channels a, b, c interleaved into out[0 .. 12).
SPECBAKE_AVX2_INLINE void store3x4(float* out, __m128 a, __m128 b, __m128 c) {
    const __m128 ab_lo = _mm_unpacklo_ps(a, b), ab_hi = _mm_unpackhi_ps(a, b);  // a0 b0 a1 b1, a2 b2 a3 b3
    _mm_storeu_ps(out, _mm_blend_ps(_mm_shuffle_ps(ab_lo, ab_lo, _MM_SHUFFLE(2, 0, 1, 0)),
                                    _mm_shuffle_ps(c, c, _MM_SHUFFLE(0, 0, 0, 0)), 0x4));  // a0 b0 c0 a1
    _mm_storeu_ps(out + 4, _mm_blend_ps(_mm_shuffle_ps(ab_lo, ab_hi, _MM_SHUFFLE(1, 0, 3, 3)),
                                        _mm_shuffle_ps(c, c, _MM_SHUFFLE(1, 1, 1, 1)), 0x2));  // b1 c1 a2 b2
    _mm_storeu_ps(out + 8, _mm_blend_ps(_mm_shuffle_ps(ab_hi, ab_hi, _MM_SHUFFLE(3, 3, 2, 3)),
                                        _mm_shuffle_ps(c, c, _MM_SHUFFLE(3, 3, 3, 2)), 0x9));  // c2 a3 b3 c3
}

// Four texels of five channels m0[k] .. m4[k] interleaved into out[0 .. 20): texel k's first four are row k
// of the transposed 4 x 4 block, the fifth follows it.
SPECBAKE_AVX2_INLINE void store5x4(float* out, __m128 m0, __m128 m1, __m128 m2, __m128 m3, __m128 m4) {
    alignas(16) float fifth[4];
    _mm_store_ps(fifth, m4);
    _MM_TRANSPOSE4_PS(m0, m1, m2, m3);
    _mm_storeu_ps(out, m0), out[4] = fifth[0];
    _mm_storeu_ps(out + 5, m1), out[9] = fifth[1];
    _mm_storeu_ps(out + 10, m2), out[14] = fifth[2];
    _mm_storeu_ps(out + 15, m3), out[19] = fifth[3];
}

// The same with float(p0[k]) .. float(p4[k]).
SPECBAKE_AVX2_INLINE void store5x4(float* out, const double* p0, const double* p1, const double* p2, const double* p3,
                                   const double* p4) {
    store5x4(out, to_float4(p0, 1.0, 0.0), to_float4(p1, 1.0, 0.0), to_float4(p2, 1.0, 0.0), to_float4(p3, 1.0, 0.0),
             to_float4(p4, 1.0, 0.0));
}

// The mip-0 outputs (see write_base_row) of the first multiple of four of the W texels; returns how many.
SPECBAKE_AVX2 int write_base_avx2(const double* v, const float* r0, int W, const Layout& layout, bool flip_y,
                                  float* rough, float* lean, float* nrm) {
    const double* px = plane(v, kPx, W);
    const double* py = plane(v, kPy, W);
    const double* pz = plane(v, kPz, W);
    int x = 0;
    for (; x + 4 <= W; x += 4) {
        if (rough && layout.occlusion >= 0)
            store3x4(rough + 3 * size_t(x), to_float4(plane(v, layout.occlusion, W) + x, 1.0, 0.0),
                     _mm_loadu_ps(r0 + x), to_float4(plane(v, layout.metallic, W) + x, 1.0, 0.0));
        if (lean)
            store5x4(lean + 5 * size_t(x), px + x, py + x, plane(v, kPxx, W) + x, plane(v, kPyy, W) + x,
                     plane(v, kPxy, W) + x);
        if (nrm)  // (n + 1) / 2 as 0.5 n + 0.5, green with the input's sign convention
            store3x4(nrm + 3 * size_t(x), to_float4(px + x, 0.5, 0.5), to_float4(py + x, flip_y ? -0.5 : 0.5, 0.5),
                     to_float4(pz + x, 0.5, 0.5));
    }
    return x;
}
#endif

// Mip-0 outputs of one base row from its planes `v` and output roughness `r0`. Every footprint is one
// base texel, so Sigma = 0, t = 0 and a = a_base exactly (SPEC Sec. 3: the input roughness passes
// through), and the decoded normal is already unit length: no divisions or roots.
void write_base_row(const double* v, const float* r0, int W, const Layout& layout, bool flip_y, const BaseRow& out,
                    int kern_ch) {
    float* const rough = out.rough;
    float* const kern = out.kern;
    float* const lean = out.lean;
    float* const nrm = out.nrm;
    const bool slope = layout.slope >= 0;
    int x0 = 0;  // texels [0, x0) done by the vector form (projected-space LEAN only)
#if defined(SPECBAKE_AVX2)
    if (has_avx2() && !slope) x0 = write_base_avx2(v, r0, W, layout, flip_y, rough, lean, nrm);
#endif
    const double* px = plane(v, kPx, W);
    const double* py = plane(v, kPy, W);
    const double* pz = plane(v, kPz, W);
    if (rough) {
        if (layout.occlusion >= 0) {
            const double* o = plane(v, layout.occlusion, W);
            const double* m = plane(v, layout.metallic, W);
            for (int x = x0; x < W; ++x)
                rough[3 * size_t(x)] = float(o[x]), rough[3 * size_t(x) + 1] = r0[x], rough[3 * size_t(x) + 2] = float(m[x]);
        } else {
            std::memcpy(rough, r0, size_t(W) * sizeof(float));
        }
    }
    if (kern) std::fill(kern, kern + size_t(W) * size_t(kern_ch), 0.0f);
    if (lean) {
        if (slope) {
            // Olano & Baker LEAN: the base lobe's slope covariance alpha^2 / 2 folded into the second moments.
            const double* a = plane(v, kA, W);
            const double* sl[5];
            for (int k = 0; k < 5; ++k) sl[k] = plane(v, layout.slope + k, W);
            for (int x = x0; x < W; ++x) {
                float* l = lean + 5 * size_t(x);
                l[0] = float(sl[0][x]), l[1] = float(sl[1][x]);
                l[2] = float(sl[2][x] + 0.5 * a[x]), l[3] = float(sl[3][x] + 0.5 * a[x]);
                l[4] = float(sl[4][x]);
            }
        } else {
            const double* xx = plane(v, kPxx, W);
            const double* yy = plane(v, kPyy, W);
            const double* xy = plane(v, kPxy, W);
            for (int x = x0; x < W; ++x) {
                float* l = lean + 5 * size_t(x);
                l[0] = float(px[x]), l[1] = float(py[x]), l[2] = float(xx[x]), l[3] = float(yy[x]), l[4] = float(xy[x]);
            }
        }
    }
    if (nrm) {
        const double sign = flip_y ? -1.0 : 1.0;
        for (int x = x0; x < W; ++x) {
            float* n = nrm + 3 * size_t(x);
            n[0] = float(0.5 * px[x] + 0.5), n[1] = float(0.5 * (sign * py[x]) + 0.5), n[2] = float(0.5 * pz[x] + 0.5);
        }
    }
}

#if defined(SPECBAKE_AVX2)
// Levels 0 and 1 of base rows y and y + 1 over base texels [bx, bx + 2 n) in one pass, for a level 1 whose
// footprints are 2 x 2 blocks of the base: each 4 x 2 group of texels is decoded in registers, written as
// level 0 into rows[0] and rows[1], and its column sums kept; the pair sums of two groups give four level-1
// means, stored into the C planes of `m` (w doubles each). These are the operations of decode_span,
// write_base_row and block_means, in the same order, so the results are identical; the base planes are
// never stored. Projected-space LEAN, with ORM R and B (kOrm) or not, roughness from a same-size map (kMap)
// or a constant. Does the first multiple of four of the n means; returns how many.
// kRgb: three-channel normal map with z read, and a three-channel roughness map if any (the usual case,
// with strides and the decode known at compile time).
template <bool kOrm, bool kMap, bool kRgb>
SPECBAKE_AVX2 int base_and_pairs_avx2(const Decoder& dec, int y, int bx, int n, const BaseRow rows[2], int kern_ch,
                                      double* m, int w, long long& degenerate) {
    constexpr int C = kOrm ? kCore + 2 : kCore;
    const size_t normal_stride = kRgb ? 3 : size_t(dec.normal.channels);
    const size_t rough_stride = !kMap ? 0 : kRgb ? 3 : size_t(dec.roughness->channels);
    const float* normal_row[2] = {dec.normal.texel(bx, y), dec.normal.texel(bx, y + 1)};
    const float* rough_row[2] = {kMap ? dec.roughness->texel(bx, y) : nullptr,
                                 kMap ? dec.roughness->texel(bx, y + 1) : nullptr};
    const bool reconstruct = !kRgb && dec.reconstruct, flip_y = dec.flip_y;
    const __m256d y_sign = _mm256_set1_pd(flip_y ? -0.0 : 0.0);
    const int channel = kOrm ? 1 : dec.roughness_channel;  // ORM: roughness is G
    long long zero_length = 0;
    const __m256d half = _mm256_set1_pd(0.5), half_y = _mm256_set1_pd(flip_y ? -0.5 : 0.5);
    const __m256d quarter = _mm256_set1_pd(0.25);
    const __m128 constant_r = _mm_set1_ps(dec.constant_r);
    const __m256d constant_a = _mm256_set1_pd(dec.constant_a);
    __m256d normal_finite = _mm256_setzero_pd();
    __m128 rough_finite = _mm_setzero_ps();
    alignas(32) double sums[2][C][4];  // column sums of the group's two halves, per quantity
    // The unit normals first, in a loop of their own: the float root, division and Newton step of their
    // inverse lengths are one long chain of latency, which the out-of-order core overlaps across iterations
    // of a short loop but not across the long one below.
    alignas(32) double unit[2][3][kTileTexels];
    n = std::min(n, kTileTexels / 2);  // a column tile's (the rest goes through the planes)
    const int n4 = n & ~3;
    for (int r = 0; r < 2; ++r)
        for (int x = 0; x < 2 * n4; x += 4) {
            const RawNormal4 v = raw_normal4(normal_row[r] + size_t(x) * normal_stride, normal_stride, reconstruct, y_sign);
            const Normal4 u = unit_normal4(v, inverse_length4(v.len2), normal_finite, zero_length);
            _mm256_store_pd(unit[r][0] + x, u.x);
            _mm256_store_pd(unit[r][1] + x, u.y);
            _mm256_store_pd(unit[r][2] + x, u.z);
        }
    // One row's quantities of a half group: the unit normal, its products, and the roughness.
    struct Texels {
        __m256d x, y, z, xx, yy, xy, a;
        __m128 r, occlusion, metallic;
    };
    int i = 0;
    for (; i + 4 <= n; i += 4) {
#pragma GCC unroll 2
        for (int h = 0; h < 2; ++h) {
            const size_t o = size_t(2 * i + 4 * h);  // the half's first texel in the rows
            Texels t[2];
#pragma GCC unroll 2
            for (int r = 0; r < 2; ++r) {
                Texels& q = t[r];
                q.x = _mm256_load_pd(unit[r][0] + o), q.y = _mm256_load_pd(unit[r][1] + o);
                q.z = _mm256_load_pd(unit[r][2] + o);
                q.xx = _mm256_mul_pd(q.x, q.x), q.yy = _mm256_mul_pd(q.y, q.y), q.xy = _mm256_mul_pd(q.x, q.y);
                q.r = q.occlusion = q.metallic = constant_r, q.a = constant_a;
                bool clamped = false;
                if constexpr (kMap) {
                    const Roughness4 g = decode_roughness4(rough_row[r] + o * rough_stride, rough_stride, channel,
                                                           kOrm, rough_finite);
                    q.r = g.r, q.occlusion = g.occlusion, q.metallic = g.metallic, q.a = g.a, clamped = g.clamped;
                }
                const BaseRow& out = rows[r];
                if (out.rough) {
                    if constexpr (kOrm && kRgb) {
                        // The texels as read unless G was clamped: R and B pass through.
                        const float* in = rough_row[r] + 3 * o;
                        if (!clamped) {
                            _mm_storeu_ps(out.rough + 3 * o, _mm_loadu_ps(in));
                            _mm_storeu_ps(out.rough + 3 * o + 4, _mm_loadu_ps(in + 4));
                            _mm_storeu_ps(out.rough + 3 * o + 8, _mm_loadu_ps(in + 8));
                        } else {
                            store3x4(out.rough + 3 * o, q.occlusion, q.r, q.metallic);
                        }
                    } else if constexpr (kOrm) {
                        store3x4(out.rough + 3 * o, q.occlusion, q.r, q.metallic);
                    } else {
                        _mm_storeu_ps(out.rough + o, q.r);
                    }
                }
                if (out.kern) {  // Sigma = 0 at the base
                    float* k = out.kern + size_t(kern_ch) * o;
                    _mm_storeu_ps(k, _mm_setzero_ps());
                    if (kern_ch == 3) _mm_storeu_ps(k + 4, _mm_setzero_ps()), _mm_storeu_ps(k + 8, _mm_setzero_ps());
                }
                if (out.lean)
                    store5x4(out.lean + 5 * o, _mm256_cvtpd_ps(q.x), _mm256_cvtpd_ps(q.y), _mm256_cvtpd_ps(q.xx),
                             _mm256_cvtpd_ps(q.yy), _mm256_cvtpd_ps(q.xy));
                if (out.nrm)
                    store3x4(out.nrm + 3 * o, _mm256_cvtpd_ps(_mm256_add_pd(_mm256_mul_pd(half, q.x), half)),
                             _mm256_cvtpd_ps(_mm256_add_pd(_mm256_mul_pd(half_y, q.y), half)),
                             _mm256_cvtpd_ps(_mm256_add_pd(_mm256_mul_pd(half, q.z), half)));
            }
            // Column sums: row y plus row y + 1.
            double(*sum)[4] = sums[h];
            _mm256_store_pd(sum[kPx], _mm256_add_pd(t[0].x, t[1].x));
            _mm256_store_pd(sum[kPy], _mm256_add_pd(t[0].y, t[1].y));
            _mm256_store_pd(sum[kPz], _mm256_add_pd(t[0].z, t[1].z));
            _mm256_store_pd(sum[kPxx], _mm256_add_pd(t[0].xx, t[1].xx));
            _mm256_store_pd(sum[kPyy], _mm256_add_pd(t[0].yy, t[1].yy));
            _mm256_store_pd(sum[kPxy], _mm256_add_pd(t[0].xy, t[1].xy));
            _mm256_store_pd(sum[kA], _mm256_add_pd(t[0].a, t[1].a));
            if constexpr (kOrm) {
                _mm256_store_pd(sum[kCore], _mm256_add_pd(_mm256_cvtps_pd(t[0].occlusion), _mm256_cvtps_pd(t[1].occlusion)));
                _mm256_store_pd(sum[kCore + 1], _mm256_add_pd(_mm256_cvtps_pd(t[0].metallic), _mm256_cvtps_pd(t[1].metallic)));
            }
        }
#pragma GCC unroll 9
        for (int c = 0; c < C; ++c) {  // as pair_means_avx2
            const __m256d pairs = _mm256_hadd_pd(_mm256_load_pd(sums[0][c]), _mm256_load_pd(sums[1][c]));
            _mm256_storeu_pd(plane(m, c, w) + i, _mm256_mul_pd(_mm256_permute4x64_pd(pairs, 0xD8), quarter));
        }
    }
    degenerate += zero_length;
    if (_mm256_movemask_pd(_mm256_cmp_pd(normal_finite, normal_finite, _CMP_UNORD_Q)))
        dec.normal_non_finite.store(true, std::memory_order_relaxed);
    if (_mm_movemask_ps(_mm_cmpunord_ps(rough_finite, rough_finite)))
        dec.roughness_non_finite.store(true, std::memory_order_relaxed);
    return i;
}

// base_and_pairs_avx2 for the decoder's roughness source and layout.
int base_and_pairs(const Decoder& dec, int y, int bx, int n, const BaseRow rows[2], int kern_ch, double* m, int w,
                   long long& degenerate) {
    const bool orm = dec.layout.occlusion >= 0;
    const bool rgb = dec.normal.channels == 3 && !dec.reconstruct && (!dec.roughness || dec.roughness->channels == 3);
    if (dec.roughness) {
        if (orm)  // an ORM map has 3+ channels
            return rgb ? base_and_pairs_avx2<true, true, true>(dec, y, bx, n, rows, kern_ch, m, w, degenerate)
                       : base_and_pairs_avx2<true, true, false>(dec, y, bx, n, rows, kern_ch, m, w, degenerate);
        return rgb ? base_and_pairs_avx2<false, true, true>(dec, y, bx, n, rows, kern_ch, m, w, degenerate)
                   : base_and_pairs_avx2<false, true, false>(dec, y, bx, n, rows, kern_ch, m, w, degenerate);
    }
    return rgb ? base_and_pairs_avx2<false, false, true>(dec, y, bx, n, rows, kern_ch, m, w, degenerate)
               : base_and_pairs_avx2<false, false, false>(dec, y, bx, n, rows, kern_ch, m, w, degenerate);
}
#endif

// The SPEC Sec. 3 formulas for `n` texels of a level >= 1, before they are stored as floats.
constexpr int kChunk = 64;

struct Finalized {
    double r[kChunk], t[kChunk], sxx[kChunk], syy[kChunk], sxy[kChunk], nx[kChunk], ny[kChunk], nz[kChunk];
    double change = 0.0;  // largest |r - r_in| so far, r_in = (mean alpha^2)^(1/4)
};

// Texel k of the chunk from its means; the scalar definition the AVX2 path below reproduces bit for bit.
inline void finalize_one(double mx, double my, double mz, double mxx, double myy, double mxy, double ma,
                         const TextureBakeSettings& s, bool flip_y, Finalized& f, int k) {
    // Sigma = M - m m^T, clamped to positive semi-definite.
    const double sxx = std::max(0.0, mxx - mx * mx);
    const double syy = std::max(0.0, myy - my * my);
    const double bound = std::sqrt(sxx * syy);
    const double sxy = std::clamp(mxy - mx * my, -bound, bound);
    double t = reduce_covariance(s.isotropic, sxx, syy, sxy);
    if (s.max_kernel) t = std::min(t, *s.max_kernel);
    const double a_base = std::clamp(ma, 0.0, 1.0);
    const double a = s.filter == RoughnessFilterMode::Projected ? filter_projected_isotropic(a_base, t)
                                                                : filter_approx_isotropic(a_base, t);
    const double r = std::sqrt(std::sqrt(a));  // r = a^(1/4)
    f.change = std::max(f.change, std::abs(r - std::sqrt(std::sqrt(a_base))));
    f.r[k] = r, f.t[k] = t, f.sxx[k] = sxx, f.syy[k] = syy, f.sxy[k] = sxy;
    double nx = mx, ny = my, nz = mz;
    const double len2 = nx * nx + ny * ny + nz * nz;
    if (len2 > 1e-24) {
        const double inv = inverse_length(len2);
        nx *= inv, ny *= inv, nz *= inv;
    } else {
        nx = 0.0, ny = 0.0, nz = 1.0;
    }
    if (flip_y) ny = -ny;
    f.nx[k] = nx, f.ny[k] = ny, f.nz[k] = nz;
}

#if defined(SPECBAKE_AVX2)
// Texels k .. k + 3 of the chunk: finalize_one four at a time. Every step is the same IEEE operation in the
// same order (std::max / std::min / std::clamp as their comparisons and selects), so results are identical.
SPECBAKE_AVX2_INLINE void finalize_four(const double* mx_, const double* my_, const double* mz_, const double* mxx_,
                                        const double* myy_, const double* mxy_, const double* ma_,
                                        const TextureBakeSettings& s, bool flip_y, Finalized& f, int k,
                                        __m256d& change) {
    const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0), half = _mm256_set1_pd(0.5);
    const __m256d two = _mm256_set1_pd(2.0), sign = _mm256_set1_pd(-0.0);
    const __m256d mx = _mm256_loadu_pd(mx_), my = _mm256_loadu_pd(my_), mz = _mm256_loadu_pd(mz_);
    const __m256d sxx = _mm256_max_pd(_mm256_sub_pd(_mm256_loadu_pd(mxx_), _mm256_mul_pd(mx, mx)), zero);
    const __m256d syy = _mm256_max_pd(_mm256_sub_pd(_mm256_loadu_pd(myy_), _mm256_mul_pd(my, my)), zero);
    const __m256d dxy = _mm256_sub_pd(_mm256_loadu_pd(mxy_), _mm256_mul_pd(mx, my));
    // The clamp to +-sqrt(sxx syy) changes nothing where dxy^2 < sxx syy (1 - 1e-9): then |dxy| < sqrt(sxx syy)
    // exactly, and the rounded root, rounding monotonically, is still >= |dxy|. The root is taken otherwise.
    const __m256d p = _mm256_mul_pd(sxx, syy);
    __m256d sxy = dxy;
    if (_mm256_movemask_pd(_mm256_cmp_pd(_mm256_mul_pd(dxy, dxy), _mm256_mul_pd(p, _mm256_set1_pd(1.0 - 1e-9)),
                                         _CMP_LT_OQ)) != 0xF) {
        const __m256d bound = _mm256_sqrt_pd(p);
        const __m256d neg_bound = _mm256_xor_pd(bound, sign);
        sxy = select4(_mm256_cmp_pd(dxy, neg_bound, _CMP_LT_OQ), neg_bound,
                      select4(_mm256_cmp_pd(bound, dxy, _CMP_LT_OQ), bound, dxy));
    }
    __m256d t = _mm256_add_pd(sxx, syy);  // mean
    switch (s.isotropic) {
        case IsotropicReduction::Mean: break;
        case IsotropicReduction::Sum: t = _mm256_mul_pd(two, t); break;
        case IsotropicReduction::Max: {
            const __m256d half_tr = _mm256_mul_pd(half, _mm256_add_pd(sxx, syy));
            const __m256d d = _mm256_mul_pd(half, _mm256_sub_pd(sxx, syy));
            const __m256d root = _mm256_sqrt_pd(_mm256_add_pd(_mm256_mul_pd(d, d), _mm256_mul_pd(sxy, sxy)));
            t = _mm256_mul_pd(two, _mm256_add_pd(half_tr, root));
            break;
        }
    }
    if (s.max_kernel) {
        const __m256d K = _mm256_set1_pd(*s.max_kernel);
        t = select4(_mm256_cmp_pd(K, t, _CMP_LT_OQ), K, t);
    }
    const __m256d ma = _mm256_loadu_pd(ma_);
    const __m256d a_base = select4(_mm256_cmp_pd(ma, zero, _CMP_LT_OQ), zero,
                                   select4(_mm256_cmp_pd(one, ma, _CMP_LT_OQ), one, ma));
    __m256d a;
    if (s.filter == RoughnessFilterMode::Projected) {
        const __m256d kk = _mm256_mul_pd(t, _mm256_sub_pd(one, a_base));
        a = _mm256_div_pd(_mm256_add_pd(a_base, kk), _mm256_add_pd(one, kk));
    } else {
        const __m256d sum = _mm256_add_pd(a_base, t);
        a = select4(_mm256_cmp_pd(sum, one, _CMP_LT_OQ), sum, one);
    }
    const __m256d r = _mm256_sqrt_pd(_mm256_sqrt_pd(a));
    // |r - r_in| only counts where it can raise the lane's largest change. As r^4 - r_in^4 = a - a_base >= 0,
    // r - r_in = (a - a_base) / ((r + r_in)(r^2 + r_in^2)) <= (a - a_base) / r^3: texels where that bound
    // stays below the change so far minus 1e-15 (far above the roundings of both roots) are ruled out
    // without their roots; the result is the same as with every root taken.
    const __m256d r3 = _mm256_mul_pd(_mm256_mul_pd(r, r), r);
    const __m256d gap = _mm256_mul_pd(_mm256_sub_pd(a, a_base), _mm256_set1_pd(1.0 + 1e-9));
    const __m256d reach = _mm256_mul_pd(_mm256_sub_pd(change, _mm256_set1_pd(1e-15)), r3);
    if (_mm256_movemask_pd(_mm256_cmp_pd(reach, gap, _CMP_LE_OQ))) {
        const __m256d r_in = _mm256_sqrt_pd(_mm256_sqrt_pd(a_base));
        const __m256d diff = _mm256_andnot_pd(sign, _mm256_sub_pd(r, r_in));
        change = select4(_mm256_cmp_pd(change, diff, _CMP_LT_OQ), diff, change);
    }
    _mm256_storeu_pd(f.r + k, r);
    _mm256_storeu_pd(f.t + k, t);
    _mm256_storeu_pd(f.sxx + k, sxx);
    _mm256_storeu_pd(f.syy + k, syy);
    _mm256_storeu_pd(f.sxy + k, sxy);
    const __m256d len2 =
        _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(mx, mx), _mm256_mul_pd(my, my)), _mm256_mul_pd(mz, mz));
    const __m256d ok = _mm256_cmp_pd(len2, _mm256_set1_pd(1e-24), _CMP_GT_OQ);
    const __m256d inv = inverse_length4(len2);
    __m256d ny = select4(ok, _mm256_mul_pd(my, inv), zero);
    if (flip_y) ny = _mm256_xor_pd(ny, sign);
    _mm256_storeu_pd(f.nx + k, select4(ok, _mm256_mul_pd(mx, inv), zero));
    _mm256_storeu_pd(f.ny + k, ny);
    _mm256_storeu_pd(f.nz + k, select4(ok, _mm256_mul_pd(mz, inv), one));
}

// The stores of finalize_row (projected-space LEAN) for the first multiple of four of the chunk's n texels
// at i0, from its means m (planes of w) and the chunk's results f; returns how many texels it did.
SPECBAKE_AVX2 int store_finalized_avx2(const double* m, int w, const Layout& layout, bool anisotropic,
                                       const Finalized& f, int i0, int n, float* rough, float* kern, float* lean,
                                       float* nrm) {
    int k = 0;
    for (; k + 4 <= n; k += 4) {
        const size_t i = size_t(i0 + k);
        if (rough) {
            if (layout.occlusion >= 0)
                store3x4(rough + 3 * i, to_float4(plane(m, layout.occlusion, w) + i, 1.0, 0.0),
                         to_float4(f.r + k, 1.0, 0.0), to_float4(plane(m, layout.metallic, w) + i, 1.0, 0.0));
            else
                _mm_storeu_ps(rough + i, to_float4(f.r + k, 1.0, 0.0));
        }
        if (kern) {
            if (anisotropic)
                store3x4(kern + 3 * i, to_float4(f.sxx + k, 1.0, 0.0), to_float4(f.syy + k, 1.0, 0.0),
                         to_float4(f.sxy + k, 1.0, 0.0));
            else
                _mm_storeu_ps(kern + i, to_float4(f.t + k, 1.0, 0.0));
        }
        if (lean)
            store5x4(lean + 5 * i, plane(m, kPx, w) + i, plane(m, kPy, w) + i, plane(m, kPxx, w) + i,
                     plane(m, kPyy, w) + i, plane(m, kPxy, w) + i);
        if (nrm)
            store3x4(nrm + 3 * i, to_float4(f.nx + k, 0.5, 0.5), to_float4(f.ny + k, 0.5, 0.5),
                     to_float4(f.nz + k, 0.5, 0.5));
    }
    return k;
}

// finalize_four over the first multiple of four of the chunk's n texels at i0; returns how many it did.
SPECBAKE_AVX2 int finalize_chunk_avx2(const double* pmx, const double* pmy, const double* pmz, const double* pxx,
                                      const double* pyy, const double* pxy, const double* pa, int i0, int n,
                                      const TextureBakeSettings& s, bool flip_y, Finalized& f) {
    __m256d lanes = _mm256_set1_pd(f.change);
    int k = 0;
    for (; k + 4 <= n; k += 4) {
        const int i = i0 + k;
        finalize_four(pmx + i, pmy + i, pmz + i, pxx + i, pyy + i, pxy + i, pa + i, s, flip_y, f, k, lanes);
    }
    double four[4];
    _mm256_storeu_pd(four, lanes);
    f.change = std::max(f.change, std::max(std::max(four[0], four[1]), std::max(four[2], four[3])));
    return k;
}
#endif

// Outputs of one row of a level >= 1 from its means `m` (planes of w doubles), SPEC Sec. 3; returns the
// row's largest |r_out - r_in|, r_in = (mean alpha^2)^(1/4).
double finalize_row(const double* m, int w, const Layout& layout, const TextureBakeSettings& s, bool flip_y,
                    float* rough, float* kern, float* lean, float* nrm) {
    const double* pmx = plane(m, kPx, w);
    const double* pmy = plane(m, kPy, w);
    const double* pmz = plane(m, kPz, w);
    const double* pxx = plane(m, kPxx, w);
    const double* pyy = plane(m, kPyy, w);
    const double* pxy = plane(m, kPxy, w);
    const double* pa = plane(m, kA, w);
    Finalized f;
    for (int i0 = 0; i0 < w; i0 += kChunk) {
        const int n = std::min(kChunk, w - i0);
        int k = 0;
#if defined(SPECBAKE_AVX2)
        if (has_avx2()) k = finalize_chunk_avx2(pmx, pmy, pmz, pxx, pyy, pxy, pa, i0, n, s, flip_y, f);
#endif
        for (; k < n; ++k) {
            const int i = i0 + k;
            finalize_one(pmx[i], pmy[i], pmz[i], pxx[i], pyy[i], pxy[i], pa[i], s, flip_y, f, k);
        }
        k = 0;
#if defined(SPECBAKE_AVX2)
        if (has_avx2() && layout.slope < 0)
            k = store_finalized_avx2(m, w, layout, s.anisotropic, f, i0, n, rough, kern, lean, nrm);
#endif
        for (; k < n; ++k) {
            const int i = i0 + k;
            if (rough) {
                if (layout.occlusion >= 0) {
                    float* o = rough + 3 * size_t(i);
                    o[0] = float(plane(m, layout.occlusion, w)[i]);
                    o[1] = float(f.r[k]);
                    o[2] = float(plane(m, layout.metallic, w)[i]);
                } else {
                    rough[i] = float(f.r[k]);
                }
            }
            if (kern) {
                if (s.anisotropic) {
                    float* q = kern + 3 * size_t(i);
                    q[0] = float(f.sxx[k]), q[1] = float(f.syy[k]), q[2] = float(f.sxy[k]);
                } else {
                    kern[i] = float(f.t[k]);
                }
            }
            if (lean) {
                float* l = lean + 5 * size_t(i);
                if (layout.slope >= 0) {
                    // Olano & Baker LEAN: first and second slope moments with the base lobe's slope covariance
                    // A / 2 = (alpha^2 / 2) I folded into the second moments (A = 2 x slope covariance, TK21 Sec. 2.1).
                    const double* sl = m + size_t(layout.slope) * w + i;
                    l[0] = float(sl[0]), l[1] = float(sl[size_t(w)]);
                    l[2] = float(sl[2 * size_t(w)] + 0.5 * pa[i]), l[3] = float(sl[3 * size_t(w)] + 0.5 * pa[i]);
                    l[4] = float(sl[4 * size_t(w)]);
                } else {
                    l[0] = float(pmx[i]), l[1] = float(pmy[i]), l[2] = float(pxx[i]), l[3] = float(pyy[i]);
                    l[4] = float(pxy[i]);
                }
            }
            if (nrm) {
                float* q = nrm + 3 * size_t(i);
                q[0] = float(0.5 * f.nx[k] + 0.5), q[1] = float(0.5 * f.ny[k] + 0.5), q[2] = float(0.5 * f.nz[k] + 0.5);
            }
        }
    }
    return f.change;
}

#if defined(SPECBAKE_AVX2)
// block_means with fx = 2 for one plane, four means per instruction: the column sums of the fy rows `src`
// (added row by row, as in the scalar loop), then each mean's even column plus its odd one (hadd gives
// means i, i + 2, i + 1, i + 3; the permute puts them in order), times `inv`. Does the first multiple of four
// of the w means; returns how many.
SPECBAKE_AVX2 int pair_means_avx2(const double* const* src, int fy, int w, double inv, double* o) {
    const __m256d scale = _mm256_set1_pd(inv);
    int i = 0;
    for (; i + 4 <= w; i += 4) {
        const size_t k = 2 * size_t(i);
        __m256d lo = _mm256_loadu_pd(src[0] + k), hi = _mm256_loadu_pd(src[0] + k + 4);
        for (int dy = 1; dy < fy; ++dy) {
            lo = _mm256_add_pd(lo, _mm256_loadu_pd(src[dy] + k));
            hi = _mm256_add_pd(hi, _mm256_loadu_pd(src[dy] + k + 4));
        }
        const __m256d sums = _mm256_permute4x64_pd(_mm256_hadd_pd(lo, hi), 0xD8);
        _mm256_storeu_pd(o + i, _mm256_mul_pd(sums, scale));
    }
    return i;
}
#endif

// Means of one row of a level whose footprints are fx x fy blocks of the finer level: `fine` holds the
// fy finer rows (each C planes of pw doubles), `out` receives C planes of w means. Each mean adds the
// columns of its block, each column summed over its rows first ((a + c) + (b + d) for a 2 x 2 block with
// rows a b and c d: pairwise, and the order vector forms add in), and is multiplied by 1 / (fx fy).
void block_means(const double* fine, int pw, int fx, int fy, int C, int w, double* out) {
    const double inv = 1.0 / double(fx * fy);
    for (int c = 0; c < C; ++c) {
        double* o = plane(out, c, w);
        // Level sizes are max(1, n >> L), so a block spans at most 3 finer rows (3 -> 1).
        const double* src[3];
        for (int dy = 0; dy < fy; ++dy) src[dy] = plane(fine + size_t(dy) * size_t(C) * size_t(pw), c, pw);
        int i = 0;
#if defined(SPECBAKE_AVX2)
        if (fx == 2 && has_avx2()) i = pair_means_avx2(src, fy, w, inv, o);
#endif
        for (; i < w; ++i) {
            double acc = 0.0;
            for (int dx = 0; dx < fx; ++dx) {
                const size_t k = size_t(i) * fx + dx;
                double column = src[0][k];
                for (int dy = 1; dy < fy; ++dy) column += src[dy][k];
                acc = dx == 0 ? column : acc + column;
            }
            o[i] = acc * inv;
        }
    }
}

bool blue_is_constant_full_scale(const Image& n) {
    if (n.channels < 3) return false;
    const float first = n.pixels[2];
    if (!(first >= 1.0f - 1.0f / 512.0f)) return false;
    const size_t count = n.texel_count();
    for (size_t i = 0; i < count; ++i) {
        if (n.pixels[i * n.channels + 2] != first) return false;
    }
    return true;
}

double srgb_to_linear(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

// A tangent-space normal map stored through an sRGB encode decodes to vectors far from unit length
// (flat (0.5, 0.5, 1) becomes (0.735, 0.735, 1)); decoding the sRGB curve first brings them back.
bool looks_srgb_encoded(const Image& n) {
    if (n.channels < 3) return false;
    // Values of 8-bit inputs (most maps; within float rounding of a code k / 255) take the curve from a
    // table of the 256 codes instead of a pow() per value: this only decides a warning.
    static const std::array<double, 256> table = [] {
        std::array<double, 256> t{};
        for (int k = 0; k < 256; ++k) t[size_t(k)] = srgb_to_linear(k / 255.0);
        return t;
    }();
    auto linear = [](double c) {
        const double code = c * 255.0;
        const long k = long(code + 0.5);  // code >= 0: the values are clamped to [0, 1]
        return k >= 0 && k <= 255 && std::abs(code - double(k)) < 1e-4 ? table[size_t(k)] : srgb_to_linear(c);
    };
    double dev_linear = 0.0, dev_srgb = 0.0;
    size_t samples = 0;
    auto sample = [&](size_t i) {
        const float* c = n.pixels.data() + i * n.channels;
        double l2 = 0.0, s2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double a = 2.0 * c[k] - 1.0;
            const double b = 2.0 * linear(std::clamp(double(c[k]), 0.0, 1.0)) - 1.0;
            l2 += a * a;
            s2 += b * b;
        }
        dev_linear += std::abs(std::sqrt(l2) - 1.0);
        dev_srgb += std::abs(std::sqrt(s2) - 1.0);
        ++samples;
    };
    // At most 16384 texels, as 256 runs of 64 consecutive texels spread over the map: runs are read at the
    // speed of memory, where single texels spread as widely each cost a cache miss.
    const size_t count = n.texel_count();
    constexpr size_t kRuns = 256, kRun = 64;
    if (count <= kRuns * kRun) {
        for (size_t i = 0; i < count; ++i) sample(i);
    } else {
        for (size_t run = 0; run < kRuns; ++run)
            for (size_t i = run * (count / kRuns), end = i + kRun; i < end; ++i) sample(i);
    }
    dev_linear /= double(samples);
    dev_srgb /= double(samples);
    return dev_linear > 0.08 && dev_srgb < 0.5 * dev_linear;
}

// "<what>: NaN or infinite value at texel (x, y)" for the first such texel of `image`.
Error non_finite_error(const std::string& what, const Image& image) {
    const auto bad = find_non_finite(image);
    return Error{what + ": NaN or infinite value" +
                 (bad ? " at texel (" + std::to_string(bad->first) + ", " + std::to_string(bad->second) + ")" : "")};
}

// Checks of the inputs' shapes and of the parts that are not read texel by texel in the decode (which
// checks every value it reads for NaN and infinity itself).
Result<void> validate(const Image& normal, const Image* roughness, int channel, float value) {
    if (normal.empty()) return make_error("normal map: empty image (0x0)");
    if (normal.channels < 2)
        return make_error("normal map: has " + std::to_string(normal.channels) +
                          " channel; a normal map needs 2 (x, y) or 3+ (x, y, z) channels");
    if (normal.pixels.size() != normal.texel_count() * size_t(normal.channels))
        return make_error("normal map: pixel buffer does not match its size");
    if (roughness) {
        if (roughness->empty()) return make_error("roughness map: empty image (0x0)");
        if (roughness->pixels.size() != roughness->texel_count() * size_t(roughness->channels))
            return make_error("roughness map: pixel buffer does not match its size");
        if (channel < 0 || channel >= roughness->channels)
            return make_error("roughness map: channel " + std::to_string(channel) + " does not exist (the map has " +
                              std::to_string(roughness->channels) + ")");
        const bool resampled = roughness->width != normal.width || roughness->height != normal.height;
        if (resampled && find_non_finite(*roughness)) return non_finite_error("roughness map", *roughness);
    } else if (!(value >= 0.0f && value <= 1.0f)) {
        return make_error("roughness value " + std::to_string(value) + " is outside [0, 1]");
    }
    return {};
}

// A zero-filled w x h image. Large buffers are reserved first and marked for transparent huge pages before
// they are touched: a 4096^2 bake writes about 1 GiB of fresh outputs, and faulting it in 4 KiB pages costs
// more CPU time than the arithmetic.
Image make_output_image(int w, int h, int channels) {
    Image image;
    image.width = w, image.height = h, image.channels = channels;
    const size_t n = size_t(w) * size_t(h) * size_t(channels);
    detail::reserve_huge_pages(image.pixels, n);
    image.pixels.resize(n);
    return image;
}

// Levels 0 .. levels-1 of a W x H chain; none when channels is 0 (output not requested).
void allocate_chain(MipChain& chain, int W, int H, int levels, int channels) {
    chain.levels.clear();
    if (channels <= 0) return;
    for (int L = 0; L < levels; ++L)
        chain.levels.push_back(make_output_image(std::max(1, W >> L), std::max(1, H >> L), channels));
}

}  // namespace

int mip_level_count(int width, int height) {
    int n = 1;
    for (int s = std::max(width, height); s > 1; s >>= 1) ++n;
    return n;
}

std::optional<std::pair<int, int>> find_non_finite(const Image& image) {
    const size_t n = image.pixels.size();
    const float* p = image.pixels.data();
    // Blocks are screened on the exponent bits (all ones: NaN or infinity), four floats per SSE2
    // instruction; only a block that holds one is searched element by element.
    constexpr size_t kBlock = 4096;
    size_t first = 0;
    for (; first < n; first += kBlock) {
        const size_t end = std::min(n, first + kBlock);
        size_t i = first;
        uint32_t bad = 0;
#if defined(__SSE2__)
        const __m128i exponent = _mm_set1_epi32(0x7f800000);
        __m128i any = _mm_setzero_si128();
        for (; i + 4 <= end; i += 4) {
            const __m128i bits = _mm_and_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p + i)), exponent);
            any = _mm_or_si128(any, _mm_cmpeq_epi32(bits, exponent));
        }
        bad = uint32_t(_mm_movemask_epi8(any));
#endif
        for (; i < end; ++i) {
            uint32_t bits;
            std::memcpy(&bits, p + i, sizeof bits);
            bad |= uint32_t((bits & 0x7f800000u) == 0x7f800000u);
        }
        if (bad) break;
    }
    for (size_t i = first; i < n; ++i) {
        if (!std::isfinite(p[i])) {
            const size_t texel = i / size_t(std::max(1, image.channels));
            return std::pair<int, int>(int(texel % size_t(image.width)), int(texel / size_t(image.width)));
        }
    }
    return std::nullopt;
}

TextureBakeShape texture_bake_shape(const Image& normal, const Image* roughness, int roughness_channel,
                                    const TextureBakeSettings& settings) {
    TextureBakeShape shape;
    shape.width = normal.width, shape.height = normal.height;
    shape.levels = normal.empty() ? 0 : mip_level_count(normal.width, normal.height);
    const bool orm = roughness && roughness->channels >= 3 && roughness_channel == 1;
    const TextureOutputs& want = settings.outputs;
    shape.roughness_channels = want.roughness ? (orm ? 3 : 1) : 0;
    shape.kernel_channels = want.kernel ? (settings.anisotropic ? 3 : 1) : 0;
    shape.lean_channels = want.lean ? 5 : 0;
    shape.normal_channels = want.normal ? 3 : 0;
    return shape;
}

namespace {

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

// The bake proper, on validated inputs.
Result<TextureBakeResult> bake_validated(const Image& normal, const Image* roughness, int roughness_channel,
                                         float roughness_value, const TextureBakeSettings& settings,
                                         const TextureBakeRowSink& sink) {
    TextureBakeResult result;
    TextureBakeNotes& notes = result.notes;
    const int W = normal.width, H = normal.height;

    Decoder dec(normal);
    dec.flip_y = settings.normal_y == NormalGreen::MinusY;
    if (normal.channels == 2) {
        if (settings.reconstruct_z == ReconstructZ::Never)
            return make_error("normal map: has two channels, so z must be reconstructed (reconstruct-z is 'never')");
        dec.reconstruct = true;
        notes.z_reason = "two-channel map";
    } else if (settings.reconstruct_z == ReconstructZ::Always) {
        dec.reconstruct = true;
        notes.z_reason = "requested";
    } else if (settings.reconstruct_z == ReconstructZ::Auto && blue_is_constant_full_scale(normal)) {
        dec.reconstruct = true;
        notes.z_reason = "constant full-scale blue channel";
    }
    notes.z_reconstructed = dec.reconstruct;
    if (!dec.reconstruct && looks_srgb_encoded(normal)) {
        notes.looks_srgb = true;
        notes.warnings.push_back(
            "normal map: values look sRGB-encoded (decoded vectors are far from unit length unless the sRGB curve "
            "is removed first); data maps are never colour-converted, so re-export it as linear data");
    }

    Layout& layout = dec.layout;
    if (roughness) {
        dec.roughness = roughness;
        dec.roughness_channel = roughness_channel;
        dec.orm = roughness->channels >= 3 && roughness_channel == 1;
        notes.roughness_is_orm = dec.orm;
        if (dec.orm) {
            layout.occlusion = layout.count++;
            layout.metallic = layout.count++;
        }
        if (roughness->width != W || roughness->height != H) {
            notes.roughness_resampled = true;
            dec.resampled = resample_roughness(*roughness, roughness_channel, dec.orm, W, H);
        }
    } else {
        const double r = roughness_value;
        dec.constant_a = r * r * r * r;
        dec.constant_r = float(std::sqrt(std::sqrt(std::clamp(dec.constant_a, 0.0, 1.0))));
    }
    const bool slope = settings.outputs.lean && settings.lean_space == LeanSpace::Slope;
    if (slope) {
        layout.slope = layout.count;
        layout.count += 5;
    }
    const int C = layout.count;


    const TextureBakeShape shape = texture_bake_shape(normal, roughness, roughness_channel, settings);
    const int levels = shape.levels;
    auto level_w = [&](int L) { return std::max(1, W >> L); };
    auto level_h = [&](int L) { return std::max(1, H >> L); };
    // Level L is the mean of blocks of level L-1 when both of its sizes divide level L-1's.
    auto tiles_previous = [&](int L) {
        return L >= 2 && level_w(L - 1) % level_w(L) == 0 && level_h(L - 1) % level_h(L) == 0;
    };

    // Means of the previous / current level, kept when the next level tiles it: row j is C planes of w.
    // Not zero-filled: every mean of a kept level is written before the next level reads it.
    std::unique_ptr<double[]> previous, current;
    std::vector<double> level_change(size_t(levels), 0.0);
    std::atomic<long long> degenerate{0};
    const size_t row_doubles = size_t(C) * size_t(W);

    // Writes the outputs of rows of level L into `block` row k from their means.
    auto finalize_into = [&](RowBlock& block, int k, const double* means, int w) {
        return finalize_row(means, w, layout, settings, dec.flip_y, block.rough_row(k), block.kern_row(k),
                            block.lean_row(k), block.nrm_row(k));
    };
    auto base_into = [&](RowBlock& block, int k, const double* v, const float* r0, int n, int offset = 0) {
        write_base_row(v, r0, n, layout, dec.flip_y, block.base_row(k, offset), block.kern_ch);
    };
    auto reduce_changes = [](const std::vector<double>& rows) {
        double m = 0.0;
        for (double c : rows) m = std::max(m, c);
        return m;
    };

    // Levels 0 .. F in one pass when each of levels 1 .. F has footprints that are whole blocks of the level
    // before (all even sizes, up to kMaxFusedLevels): every base row is decoded once, written as level 0
    // and summed upwards. Each task owns whole rows of level F, so the finer rows under them never leave
    // the task, and only level-F means (a 4^F-th of the base) are kept for level F + 1. Column tiles of
    // about kTileTexels base texels keep a task's planes and float rows in the L2 cache; every output texel
    // still sums its own footprint in the same order.
    const bool fused = levels >= 2 && W % level_w(1) == 0 && H % level_h(1) == 0;
    auto run_fused = [&] {
        int F = 1;
        while (F < kMaxFusedLevels && F + 1 < levels && tiles_previous(F + 1)) ++F;
        std::vector<int> fx(size_t(F) + 1, 1), fy(size_t(F) + 1, 1), tile(size_t(F) + 1, 1);
        for (int L = 1; L <= F; ++L)
            fx[size_t(L)] = level_w(L - 1) / level_w(L), fy[size_t(L)] = level_h(L - 1) / level_h(L);
        int span = 1;  // base texels per level-F texel along x
        for (int L = 1; L <= F; ++L) span *= fx[size_t(L)];
        tile[size_t(F)] = std::clamp(kTileTexels / span, 1, level_w(F));
        for (int L = F; L >= 1; --L) tile[size_t(L) - 1] = tile[size_t(L)] * fx[size_t(L)];
        const int wF = level_w(F), hF = level_h(F);
        // Levels 0 and 1 straight from the decoded registers (base_and_pairs_avx2) where it applies.
        bool pairs_in_registers = false;
#if defined(SPECBAKE_AVX2)
        pairs_in_registers = has_avx2() && fx[1] == 2 && fy[1] == 2 && layout.slope < 0 && dec.resampled.empty();
#endif
        const bool keep = F + 1 < levels && tiles_previous(F + 1);
        current = uninitialized<double>(keep ? size_t(wF) * hF * C : 0);
        std::vector<std::vector<double>> change(size_t(F) + 1);
        for (int L = 1; L <= F; ++L) change[size_t(L)].assign(size_t(level_h(L)), 0.0);

        tbb::parallel_for(tbb::blocked_range<int>(0, hF), [&](const tbb::blocked_range<int>& rows) {
            // Per level: the finer rows under one row of it; its output rows are held until the rows under
            // one row of the next level are done, and go to the sink as one block.
            std::vector<std::unique_ptr<double[]>> fine(size_t(F) + 1);
            std::vector<RowBlock> out;
            for (int L = 0; L <= F; ++L) {
                if (L >= 1) fine[size_t(L)] = uninitialized<double>(size_t(C) * tile[size_t(L) - 1] * fy[size_t(L)]);
                out.emplace_back(shape, tile[size_t(L)], L < F ? fy[size_t(L) + 1] : 1);
            }
            const auto top = uninitialized<double>(size_t(C) * tile[size_t(F)]);  // means of level F
            const auto r0 = uninitialized<float>(size_t(tile[0]));
            long long task_degenerate = 0;
            // Levels 0 and 1 of texels [x, x + n) of row j of level 1 (2 x 2 footprints) from registers, the
            // last means (n not a multiple of four) through the planes in `f`.
            auto levels_0_1 = [&](int j, int x, int n, double* m, double* f) {
                RowBlock& base = out[0];
                int done = 0;
#if defined(SPECBAKE_AVX2)
                const BaseRow rows[2] = {base.base_row(0, 0), base.base_row(1, 0)};
                done = base_and_pairs(dec, 2 * j, 2 * x, n, rows, base.kern_ch, m, n, task_degenerate);
#endif
                if (done == n) return;
                const int rest = n - done, nr = 2 * rest;
                for (int dy = 0; dy < 2; ++dy) {
                    double* v = f + size_t(dy) * C * nr;
                    task_degenerate += dec.decode_span(2 * j + dy, 2 * (x + done), nr, v, r0.get());
                    base_into(base, dy, v, r0.get(), nr, 2 * done);
                }
                std::array<double, 4 * 16> tail;  // C (<= 14) planes of rest (< 4) means
                block_means(f, nr, 2, 2, C, rest, tail.data());
                for (int c = 0; c < C; ++c) std::copy_n(tail.data() + size_t(c) * rest, rest, plane(m, c, n) + done);
            };
            // Means of texels [x, x + n) of row j of level L into m (C planes of n) and its outputs into row k
            // of out[L], after the outputs of every finer level under them went to the sink.
            std::function<void(int, int, int, int, double*, int)> block = [&](int L, int j, int x, int n, double* m,
                                                                              int k) {
                RowBlock& o = out[size_t(L)];
                if (L == 0) {
                    task_degenerate += dec.decode_span(j, x, n, m, r0.get());
                    base_into(o, k, m, r0.get(), n);
                    return;
                }
                const int fxL = fx[size_t(L)], fyL = fy[size_t(L)], nf = n * fxL;
                double* f = fine[size_t(L)].get();
                out[size_t(L) - 1].width = nf;
                if (L == 1 && pairs_in_registers) {
                    levels_0_1(j, x, n, m, f);
                } else {
                    for (int dy = 0; dy < fyL; ++dy)
                        block(L - 1, j * fyL + dy, x * fxL, nf, f + size_t(dy) * C * nf, dy);
                    block_means(f, nf, fxL, fyL, C, n, m);
                }
                out[size_t(L) - 1].emit(sink, L - 1, x * fxL, j * fyL, fyL);
                double& c = change[size_t(L)][size_t(j)];
                c = std::max(c, finalize_into(o, k, m, n));
            };
            for (int j = rows.begin(); j < rows.end(); ++j) {
                for (int x = 0; x < wF; x += tile[size_t(F)]) {
                    const int n = std::min(tile[size_t(F)], wF - x);
                    double* m = top.get();
                    out[size_t(F)].width = n;
                    block(F, j, x, n, m, 0);
                    out[size_t(F)].emit(sink, F, x, j, 1);
                    if (keep)
                        for (int c = 0; c < C; ++c)
                            std::copy_n(m + size_t(c) * n, n, current.get() + (size_t(j) * C + c) * wF + x);
                }
            }
            degenerate += task_degenerate;
        });
        for (int L = 1; L <= F; ++L) level_change[size_t(L)] = reduce_changes(change[size_t(L)]);
        previous.swap(current);
        return F + 1;
    };

    auto run = [&] {
        const int first_level = fused ? run_fused() : 0;
        for (int L = first_level; L < levels; ++L) {
            const int w = level_w(L), h = level_h(L);
            const bool from_previous = tiles_previous(L);
            const bool keep = L >= 1 && L + 1 < levels && tiles_previous(L + 1);
            current = uninitialized<double>(keep ? size_t(w) * h * C : 0);
            std::vector<double> row_change(size_t(h), 0.0);
            const std::vector<Span1D> spans_x = from_previous || L == 0 ? std::vector<Span1D>{} : footprint_spans(W, w);
            const std::vector<Span1D> spans_y = from_previous || L == 0 ? std::vector<Span1D>{} : footprint_spans(H, h);
            const double area = (double(W) / w) * (double(H) / h);
            const int pw = L >= 1 ? level_w(L - 1) : 0;
            const int fx = from_previous ? pw / w : 0;
            const int fy = from_previous ? level_h(L - 1) / h : 0;

            tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
                std::vector<double> base(from_previous ? 0 : row_doubles);
                std::vector<float> r0(from_previous ? 0 : size_t(W));
                std::vector<double> means(size_t(C) * w);
                RowBlock out(shape, w, 1);
                long long task_degenerate = 0;
                for (int j = rows.begin(); j < rows.end(); ++j) {
                    if (L == 0) {
                        task_degenerate += dec.decode_span(j, 0, W, base.data(), r0.data());
                        base_into(out, 0, base.data(), r0.data(), W);
                        out.emit(sink, 0, 0, j, 1);
                        continue;
                    }
                    if (from_previous) {
                        block_means(previous.get() + size_t(j) * fy * C * pw, pw, fx, fy, C, w, means.data());
                    } else {
                        std::fill(means.begin(), means.end(), 0.0);
                        const Span1D& sy = spans_y[size_t(j)];
                        for (size_t k = 0; k < sy.weight.size(); ++k) {
                            const double wy = sy.weight[k];
                            if (wy <= 0.0) continue;
                            dec.decode_span(sy.first + int(k), 0, W, base.data(), r0.data());
                            for (int c = 0; c < C; ++c) {
                                double* m = plane(means.data(), c, w);
                                const double* v = plane(base.data(), c, W);
                                for (int i = 0; i < w; ++i) {
                                    const Span1D& sx = spans_x[size_t(i)];
                                    for (size_t q = 0; q < sx.weight.size(); ++q)
                                        m[i] += wy * sx.weight[q] * v[sx.first + int(q)];
                                }
                            }
                        }
                        const double inv = 1.0 / area;
                        for (double& m : means) m *= inv;
                    }
                    row_change[size_t(j)] = finalize_into(out, 0, means.data(), w);
                    out.emit(sink, L, 0, j, 1);
                    if (keep) std::copy(means.begin(), means.end(), current.get() + size_t(j) * w * C);
                }
                degenerate += task_degenerate;
            });
            level_change[size_t(L)] = reduce_changes(row_change);
            previous.swap(current);
        }
        result.max_roughness_change = reduce_changes(level_change);
    };
    run_with_threads(settings.threads, run);

    if (dec.normal_non_finite) return non_finite_error("normal map", normal);
    if (dec.roughness_non_finite) return non_finite_error("roughness map", *roughness);
    notes.degenerate_normals = degenerate;
    if (notes.degenerate_normals > 0)
        notes.warnings.push_back("normal map: " + std::to_string(notes.degenerate_normals) +
                                 " texels decode to a zero-length vector; treated as +Z");
    if (notes.roughness_resampled)
        notes.warnings.push_back("roughness map is " + std::to_string(roughness->width) + "x" +
                                 std::to_string(roughness->height) + ", the normal map " + std::to_string(W) + "x" +
                                 std::to_string(H) +
                                 "; outputs have the normal map's size, each texel reading the roughness it covers");
    return result;
}

}  // namespace

Result<TextureBakeResult> bake_texture_rows(const Image& normal, const Image* roughness, int roughness_channel,
                                            float roughness_value, const TextureBakeSettings& settings,
                                            const TextureBakeRowSink& sink) {
    if (auto ok = validate(normal, roughness, roughness_channel, roughness_value); !ok) return ok.error();
    return bake_validated(normal, roughness, roughness_channel, roughness_value, settings, sink);
}

Result<TextureBakeResult> bake_texture(const Image& normal, const Image* roughness, int roughness_channel,
                                       float roughness_value, const TextureBakeSettings& settings) {
    if (auto ok = validate(normal, roughness, roughness_channel, roughness_value); !ok) return ok.error();
    const TextureBakeShape shape = texture_bake_shape(normal, roughness, roughness_channel, settings);
    MipChain rough, kern, lean, nrm;
    // The chains are allocated (and zero-filled) on two threads: LEAN, the widest, against the other three.
    run_with_threads(settings.threads, [&] {
        tbb::parallel_invoke(
            [&] { allocate_chain(lean, shape.width, shape.height, shape.levels, shape.lean_channels); },
            [&] {
                allocate_chain(rough, shape.width, shape.height, shape.levels, shape.roughness_channels);
                allocate_chain(kern, shape.width, shape.height, shape.levels, shape.kernel_channels);
                allocate_chain(nrm, shape.width, shape.height, shape.levels, shape.normal_channels);
            });
    });
    auto copy_rows = [](MipChain& chain, const TextureBakeRows& r, const float* src) {
        if (!src) return;
        Image& level = chain.levels[size_t(r.level)];
        const size_t row_floats = size_t(r.width) * size_t(level.channels);
        for (int k = 0; k < r.rows; ++k)
            std::memcpy(level.texel(r.x0, r.y0 + k), src + size_t(k) * row_floats, row_floats * sizeof(float));
    };
    auto baked = bake_validated(normal, roughness, roughness_channel, roughness_value, settings,
                                [&](const TextureBakeRows& r) {
                                    copy_rows(rough, r, r.roughness);
                                    copy_rows(kern, r, r.kernel);
                                    copy_rows(lean, r, r.lean);
                                    copy_rows(nrm, r, r.normal);
                                });
    if (!baked) return baked;
    baked->roughness = std::move(rough);
    baked->kernel = std::move(kern);
    baked->lean = std::move(lean);
    baked->normal = std::move(nrm);
    return baked;
}

}  // namespace specbake
