// The texture bake's plane path: mip-0 outputs of a decoded base row and the block means of a level that
// tiles the finer one, each read from / written to planes of doubles (scalar and AVX2 forms).
#include "bake/texture_bake_internal.h"
#include "bake/texture_bake_simd.h"

#include <algorithm>
#include <cstring>

namespace specbake::texture_bake_detail {
namespace {

#if defined(SPECBAKE_AVX2)
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

}  // namespace

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
    if (kern) {
        std::fill(kern, kern + size_t(W) * size_t(kern_ch), 0.0f);
        if (kern_ch == 4) {  // Sigma = 0, the rough share the texel's own indicator
            const double* g = plane(v, kRough, W);
            for (int x = 0; x < W; ++x) kern[4 * size_t(x) + 3] = float(g[x]);
        }
    }
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

}  // namespace specbake::texture_bake_detail
