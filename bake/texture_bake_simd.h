// The AVX2 building blocks of the texture bake's vector loops, inlined into them: loads and decodes of
// four texels, inverse lengths, selects, and the interleaving stores of four output texels.
//
// Each performs the same IEEE operations in the same order as the scalar form it stands for (see
// texture_bake_internal.h), so the vector loops built from them give bit-identical results.
#pragma once

#include "bake/texture_bake_internal.h"

#if defined(SPECBAKE_AVX2)
#include <immintrin.h>

namespace specbake::texture_bake_detail {

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

// Four texels of four channels a, b, c, d interleaved into out[0 .. 16).
SPECBAKE_AVX2_INLINE void store4x4(float* out, __m128 a, __m128 b, __m128 c, __m128 d) {
    _MM_TRANSPOSE4_PS(a, b, c, d);
    _mm_storeu_ps(out, a), _mm_storeu_ps(out + 4, b), _mm_storeu_ps(out + 8, c), _mm_storeu_ps(out + 12, d);
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

}  // namespace specbake::texture_bake_detail
#endif
