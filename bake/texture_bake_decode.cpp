// Decoding of the input maps into the texture bake's per-texel planes: the normals and roughness of base
// texel rows (scalar and AVX2 forms), footprint spans and the resampling of a roughness map of another size.
#include "bake/texture_bake_internal.h"
#include "bake/texture_bake_simd.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

namespace specbake::texture_bake_detail {
namespace {

#if defined(SPECBAKE_AVX2)
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

}  // namespace

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

float* scratch_floats(size_t n, int which) {
    thread_local std::vector<float> rows[2];
    std::vector<float>& r = rows[which];
    if (r.size() < n) r.resize(n);
    return r.data();
}

void Decoder::decode_normal(const float* c, double n[3], bool& degenerate, bool& non_finite) const {
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

long long Decoder::decode_normal_span(int y, int x0, int n, double* nx, double* ny, double* nz, double* xx,
                                     double* yy, double* xy) const {
    long long degenerate_count = 0;
    bool non_finite = false;
    int x = 0;
    const float* row = row_floats(normal, y, x0, n, normal.f32 ? nullptr : scratch_floats(size_t(n) * normal.channels, 0));
#if defined(SPECBAKE_AVX2)
    if (has_avx2())
        x = decode_normals_avx2(row, normal.channels, n, reconstruct, flip_y, nx, ny, nz, xx, yy, xy,
                                degenerate_count, non_finite);
#endif
    for (; x < n; ++x) {
        double v[3];
        bool degenerate = false;
        decode_normal(row + size_t(x) * size_t(normal.channels), v, degenerate, non_finite);
        degenerate_count += degenerate;
        nx[x] = v[0], ny[x] = v[1], nz[x] = v[2];
        xx[x] = v[0] * v[0], yy[x] = v[1] * v[1], xy[x] = v[0] * v[1];
    }
    if (non_finite) normal_non_finite.store(true, std::memory_order_relaxed);
    return degenerate_count;
}

long long Decoder::decode_span(int y, int x0, int W, double* v, float* r0) const {
    double* nx = plane(v, kPx, W);
    double* ny = plane(v, kPy, W);
    double* nz = plane(v, kPz, W);
    const long long degenerate = decode_normal_span(y, x0, W, nx, ny, nz, plane(v, kPxx, W), plane(v, kPyy, W),
                                                    plane(v, kPxy, W));
    double* g = plane(v, kRough, W);
    for (int x = 0; x < W; ++x) g[x] = rough_indicator(nx[x], ny[x], nz[x]);
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
        const float* t = row_floats(*roughness, y, x0, W,
                                    roughness->f32 ? nullptr : scratch_floats(size_t(W) * size_t(ch), 1));
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

// Area-weighted resampling of the roughness map onto the normal map's texel grid: each normal texel reads
// the mean alpha^2 (and ORM R, B) of the roughness texels it covers.
std::vector<double> resample_roughness(const TextureMap& rough, int channel, bool orm, int W, int H) {
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
                        const int tx = fx.first + int(i), ty = fy.first + int(j);
                        const double r = std::clamp(double(rough.value(tx, ty, channel)), 0.0, 1.0);
                        acc[0] += w * (r * r) * (r * r);
                        if (orm) acc[1] += w * rough.value(tx, ty, 0), acc[2] += w * rough.value(tx, ty, 2);
                    }
                }
                double* o = out.data() + (size_t(y) * W + x) * 3;
                for (int c = 0; c < 3; ++c) o[c] = acc[c] / area;
            }
        }
    });
    return out;
}

}  // namespace specbake::texture_bake_detail
