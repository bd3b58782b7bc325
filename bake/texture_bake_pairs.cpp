// The texture bake's AVX2 register pass: levels 0 and 1 of two base rows decoded, written and pair-summed
// in registers, for a level 1 of 2 x 2 footprints, the base planes never stored.
#include "bake/texture_bake_internal.h"
#include "bake/texture_bake_simd.h"

#include <algorithm>

#if defined(SPECBAKE_AVX2)
namespace specbake::texture_bake_detail {
namespace {

// One row's quantities of four texels of a half group: the unit normal, its products, and the roughness.
struct PairTexels4 {
    __m256d x, y, z, xx, yy, xy, a, g;
    __m128 r, occlusion, metallic;
};

// The base level's outputs of four texels from `o` on in `out` (each output that was requested);
// `rough_in`: the roughness texels as read, for ORM from a three-channel map.
template <bool kOrm, bool kRgb>
SPECBAKE_AVX2_INLINE void store_base_outputs4(const BaseRow& out, const PairTexels4& q, const float* rough_in, size_t o,
                                              bool clamped, int kern_ch, __m256d half, __m256d half_y) {
    if (out.rough) {
        if constexpr (kOrm && kRgb) {
            // The texels as read unless G was clamped: R and B pass through.
            const float* in = rough_in;
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
    if (out.kern) {  // Sigma = 0 at the base, the rough share the texel's indicator
        float* k = out.kern + size_t(kern_ch) * o;
        const __m128 zero = _mm_setzero_ps();
        if (kern_ch == 4)
            store4x4(k, zero, zero, zero, _mm256_cvtpd_ps(q.g));
        else
            _mm_storeu_ps(k, zero);
    }
    if (out.lean)
        store5x4(out.lean + 5 * o, _mm256_cvtpd_ps(q.x), _mm256_cvtpd_ps(q.y), _mm256_cvtpd_ps(q.xx),
                 _mm256_cvtpd_ps(q.yy), _mm256_cvtpd_ps(q.xy));
    if (out.nrm)
        store3x4(out.nrm + 3 * o, _mm256_cvtpd_ps(_mm256_add_pd(_mm256_mul_pd(half, q.x), half)),
                 _mm256_cvtpd_ps(_mm256_add_pd(_mm256_mul_pd(half_y, q.y), half)),
                 _mm256_cvtpd_ps(_mm256_add_pd(_mm256_mul_pd(half, q.z), half)));
}

// The column sums of the group's half `sum` (per quantity, four columns): row y plus row y + 1.
template <bool kOrm>
SPECBAKE_AVX2_INLINE void add_column_sums4(const PairTexels4 (&t)[2], double (*sum)[4]) {
    _mm256_store_pd(sum[kPx], _mm256_add_pd(t[0].x, t[1].x));
    _mm256_store_pd(sum[kPy], _mm256_add_pd(t[0].y, t[1].y));
    _mm256_store_pd(sum[kPz], _mm256_add_pd(t[0].z, t[1].z));
    _mm256_store_pd(sum[kPxx], _mm256_add_pd(t[0].xx, t[1].xx));
    _mm256_store_pd(sum[kPyy], _mm256_add_pd(t[0].yy, t[1].yy));
    _mm256_store_pd(sum[kPxy], _mm256_add_pd(t[0].xy, t[1].xy));
    _mm256_store_pd(sum[kA], _mm256_add_pd(t[0].a, t[1].a));
    _mm256_store_pd(sum[kRough], _mm256_add_pd(t[0].g, t[1].g));
    if constexpr (kOrm) {
        _mm256_store_pd(sum[kCore], _mm256_add_pd(_mm256_cvtps_pd(t[0].occlusion), _mm256_cvtps_pd(t[1].occlusion)));
        _mm256_store_pd(sum[kCore + 1], _mm256_add_pd(_mm256_cvtps_pd(t[0].metallic), _mm256_cvtps_pd(t[1].metallic)));
    }
}

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
    n = std::min(n, kTileTexels / 2);  // a column tile's (the rest goes through the planes)
    // Integer maps are converted for the 2 n texels read, in scratch rows of the thread.
    const size_t span = 2 * size_t(n);
    float* const normal_scratch = dec.normal.f32 ? nullptr : scratch_floats(2 * span * normal_stride, 0);
    float* const rough_scratch = kMap && !dec.roughness->f32 ? scratch_floats(2 * span * rough_stride, 1) : nullptr;
    const float* normal_row[2] = {
        row_floats(dec.normal, y, bx, int(span), normal_scratch),
        row_floats(dec.normal, y + 1, bx, int(span), normal_scratch ? normal_scratch + span * normal_stride : nullptr)};
    const float* rough_row[2] = {
        kMap ? row_floats(*dec.roughness, y, bx, int(span), rough_scratch) : nullptr,
        kMap ? row_floats(*dec.roughness, y + 1, bx, int(span), rough_scratch ? rough_scratch + span * rough_stride : nullptr)
             : nullptr};
    const bool reconstruct = !kRgb && dec.reconstruct, flip_y = dec.flip_y;
    const __m256d y_sign = _mm256_set1_pd(flip_y ? -0.0 : 0.0);
    const int channel = kOrm ? 1 : dec.roughness_channel;  // ORM: roughness is G
    long long zero_length = 0;
    const __m256d half = _mm256_set1_pd(0.5), half_y = _mm256_set1_pd(flip_y ? -0.5 : 0.5);
    const __m256d quarter = _mm256_set1_pd(0.25);
    const __m256d flat2 = _mm256_set1_pd(kFlatSlope * kFlatSlope), one = _mm256_set1_pd(1.0);
    const __m128 constant_r = _mm_set1_ps(dec.constant_r);
    const __m256d constant_a = _mm256_set1_pd(dec.constant_a);
    __m256d normal_finite = _mm256_setzero_pd();
    __m128 rough_finite = _mm_setzero_ps();
    alignas(32) double sums[2][C][4];  // column sums of the group's two halves, per quantity
    // The unit normals first, in a loop of their own: the float root, division and Newton step of their
    // inverse lengths are one long chain of latency, which the out-of-order core overlaps across iterations
    // of a short loop but not across the long one below.
    alignas(32) double unit[2][3][kTileTexels];
    const int n4 = n & ~3;
    for (int r = 0; r < 2; ++r)
        for (int x = 0; x < 2 * n4; x += 4) {
            const RawNormal4 v = raw_normal4(normal_row[r] + size_t(x) * normal_stride, normal_stride, reconstruct, y_sign);
            const Normal4 u = unit_normal4(v, inverse_length4(v.len2), normal_finite, zero_length);
            _mm256_store_pd(unit[r][0] + x, u.x);
            _mm256_store_pd(unit[r][1] + x, u.y);
            _mm256_store_pd(unit[r][2] + x, u.z);
        }
    int i = 0;
    for (; i + 4 <= n; i += 4) {
#pragma GCC unroll 2
        for (int h = 0; h < 2; ++h) {
            const size_t o = size_t(2 * i + 4 * h);  // the half's first texel in the rows
            PairTexels4 t[2];
#pragma GCC unroll 2
            for (int r = 0; r < 2; ++r) {
                PairTexels4& q = t[r];
                q.x = _mm256_load_pd(unit[r][0] + o), q.y = _mm256_load_pd(unit[r][1] + o);
                q.z = _mm256_load_pd(unit[r][2] + o);
                q.xx = _mm256_mul_pd(q.x, q.x), q.yy = _mm256_mul_pd(q.y, q.y), q.xy = _mm256_mul_pd(q.x, q.y);
                // rough_indicator: x^2 + y^2 > kFlatSlope^2 z^2
                q.g = _mm256_and_pd(_mm256_cmp_pd(_mm256_add_pd(q.xx, q.yy),
                                                  _mm256_mul_pd(flat2, _mm256_mul_pd(q.z, q.z)), _CMP_GT_OQ),
                                    one);
                q.r = q.occlusion = q.metallic = constant_r, q.a = constant_a;
                bool clamped = false;
                if constexpr (kMap) {
                    const Roughness4 g = decode_roughness4(rough_row[r] + o * rough_stride, rough_stride, channel,
                                                           kOrm, rough_finite);
                    q.r = g.r, q.occlusion = g.occlusion, q.metallic = g.metallic, q.a = g.a, clamped = g.clamped;
                }
                store_base_outputs4<kOrm, kRgb>(rows[r], q, kOrm && kRgb ? rough_row[r] + 3 * o : nullptr, o, clamped,
                                                kern_ch, half, half_y);
            }
            add_column_sums4<kOrm>(t, sums[h]);
        }
#pragma GCC unroll 10
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

}  // namespace

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

}  // namespace specbake::texture_bake_detail
#endif
