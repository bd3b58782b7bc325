// The texture bake's per-texel formulas of the levels >= 1 (SPEC Sec. 3): covariance, kernel, filtered
// roughness and mean normal from a texel's means (scalar and AVX2 forms), and the float outputs of a row.
#include "bake/texture_bake_internal.h"
#include "bake/isotropic_filter.h"
#include "bake/texture_bake_simd.h"

#include <algorithm>

namespace specbake::texture_bake_detail {
namespace {

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
                store4x4(kern + 4 * i, to_float4(f.sxx + k, 1.0, 0.0), to_float4(f.syy + k, 1.0, 0.0),
                         to_float4(f.sxy + k, 1.0, 0.0), to_float4(plane(m, kRough, w) + i, 1.0, 0.0));
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

}  // namespace

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
                    float* q = kern + 4 * size_t(i);
                    q[0] = float(f.sxx[k]), q[1] = float(f.syy[k]), q[2] = float(f.sxy[k]);
                    q[3] = float(plane(m, kRough, w)[i]);
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

}  // namespace specbake::texture_bake_detail
