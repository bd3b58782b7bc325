// Layout for speed. The corners are not sorted by vertex: a pass over the triangles in index order computes
// each triangle's dP/du once and its three corners' terms, and adds every corner term to its vertex's sums
// (4 doubles: weighted tangent xyz, signed angle), so each vertex adds its corners in corner order. Four
// triangles run at once, one per lane of a 4-wide double vector (AVX2 where the CPU has it). The vertices
// are split into chunks of consecutive indices, parallel tasks sharing one small set of arrays per thread;
// a chunk's pass visits only the blocks of triangles whose vertex-index bounds meet the chunk and adds only
// its own vertices' corners, so every sum runs in the same order for any split and any thread count. The
// results are those of the scalar formulation (detail::corner_angle, Eigen's evaluation order) bit for bit:
// the lanes do the same IEEE operations in the same order.
#include "mesh/generate_tangents.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "mesh/mesh_math.h"
#include "mesh/lanes.h"
#include "mesh/scratch_array.h"

namespace specbake {
namespace {

// The passes are compiled for AVX2 and for the baseline instruction set (mesh/lanes.h). The corner pass
// differs between the two beyond the instructions (see less()) and is chosen explicitly, once per chunk.
// Clang builds (the sanitizer and fuzz builds) keep the baseline only, as mesh/lanes.h says why.
#if defined(__x86_64__) && defined(__linux__) && !defined(__clang__)
#define SPECBAKE_X86_VERSIONS
#endif
#define SPECBAKE_INLINE_LAMBDA __attribute__((always_inline))
using namespace lanes;

SPECBAKE_INLINE v4d select(v4l mask, v4d yes, v4d no) { return mask ? yes : no; }  // yes where mask is set

// The corner pass comes in two versions: kAvx2, two groups of four triangles side by side in sixteen 256-bit
// registers; otherwise one group, with the comparisons made on SSE2 halves (the baseline version would
// otherwise compare element by element) and fewer values spilled from its sixteen 128-bit registers.
// A lane-wise comparison; `sse2` is its SSE2 intrinsic, `op` the same comparison on whole vectors.
template <bool kAvx2, class Sse2, class Op>
SPECBAKE_INLINE v4l compare(v4d a, v4d b, Sse2 sse2, Op op) {
#if defined(__SSE2__)
    if constexpr (!kAvx2) {
        const __m128d lo = sse2(__m128d{a[0], a[1]}, __m128d{b[0], b[1]});
        const __m128d hi = sse2(__m128d{a[2], a[3]}, __m128d{b[2], b[3]});
        return (v4l)v4d{lo[0], lo[1], hi[0], hi[1]};
    }
#endif
    return op(a, b);
}
template <bool kAvx2>
SPECBAKE_INLINE v4l less(v4d a, v4d b) {
    return compare<kAvx2>(a, b, [](__m128d x, __m128d y) SPECBAKE_INLINE_LAMBDA { return _mm_cmplt_pd(x, y); },
                          [](v4d x, v4d y) SPECBAKE_INLINE_LAMBDA { return x < y; });
}
template <bool kAvx2>
SPECBAKE_INLINE v4l equal(v4d a, v4d b) {
    return compare<kAvx2>(a, b, [](__m128d x, __m128d y) SPECBAKE_INLINE_LAMBDA { return _mm_cmpeq_pd(x, y); },
                          [](v4d x, v4d y) SPECBAKE_INLINE_LAMBDA { return x == y; });
}
template <bool kAvx2>
SPECBAKE_INLINE v4d choose(v4l mask, v4d yes, v4d no) {
    if constexpr (!kAvx2) return (v4d)(((v4l)yes & mask) | ((v4l)no & ~mask));
    return mask ? yes : no;
}


// detail::corner_angle lane-wise, with its operations in its order (so the same bits): both branches are
// computed and each lane's one selected. N vectors at once, step by step: each is a long chain of dependent
// divisions and multiply-adds, and independent chains side by side keep the units busy.
#define SPECBAKE_EACH _Pragma("GCC unroll 8") for (int c = 0; c < N; ++c)
template <bool kAvx2, int N>
SPECBAKE_INLINE void corner_angles(const v4d (&y)[N], const v4d (&x)[N], v4d (&a)[N]) {
    const v4d zero = splat(0.0), one = splat(1.0);
    v4d t[N], s[N], poly[N];
    v4l steep[N], high[N];
    SPECBAKE_EACH {
        const v4d ax = (v4d)((v4l)x[c] & ~(v4l)splat(-0.0));
        steep[c] = less<kAvx2>(ax, y[c]);
        t[c] = choose<kAvx2>(steep[c], ax, y[c]) / choose<kAvx2>(steep[c], y[c], ax);
    }
    SPECBAKE_EACH {
        high[c] = less<kAvx2>(splat(detail::kAtanTanPi8), t[c]);
        t[c] = choose<kAvx2>(high[c], (t[c] - one) / (t[c] + one), t[c]);
        s[c] = t[c] * t[c];
        poly[c] = splat(detail::kAtanFit[0]);
    }
#pragma GCC unroll 6
    for (int i = 1; i < 7; ++i) SPECBAKE_EACH poly[c] = poly[c] * s[c] + splat(detail::kAtanFit[i]);
    SPECBAKE_EACH {
        a[c] = t[c] * poly[c] + choose<kAvx2>(high[c], splat(0.25 * detail::kAtanPi), zero);
        a[c] = choose<kAvx2>(steep[c], splat(0.5 * detail::kAtanPi) - a[c], a[c]);
        const v4l negative = less<kAvx2>(x[c], zero);
        a[c] = choose<kAvx2>(negative, splat(detail::kAtanPi) - a[c], a[c]);
        a[c] = choose<kAvx2>(equal<kAvx2>(y[c], zero), choose<kAvx2>(negative, splat(detail::kAtanPi), zero), a[c]);
    }
}

// One bit per lane of a lane mask (bit j set when lane j is true).
SPECBAKE_INLINE int lane_bits(v4l mask) {
#if defined(__SSE2__)
    const v4d m = (v4d)mask;
    return _mm_movemask_pd(__m128d{m[0], m[1]}) | _mm_movemask_pd(__m128d{m[2], m[3]}) << 2;
#else
    return (mask[0] ? 1 : 0) | (mask[1] ? 2 : 0) | (mask[2] ? 4 : 0) | (mask[3] ? 8 : 0);
#endif
}

// Rows (x, y, z, w) of four lanes to the four lanes' (x, y, z, w).
SPECBAKE_INLINE void transpose4(const v4d (&in)[4], v4d (&out)[4]) {
    const v4d t0 = __builtin_shufflevector(in[0], in[1], 0, 4, 2, 6), t1 = __builtin_shufflevector(in[0], in[1], 1, 5, 3, 7);
    const v4d t2 = __builtin_shufflevector(in[2], in[3], 0, 4, 2, 6), t3 = __builtin_shufflevector(in[2], in[3], 1, 5, 3, 7);
    out[0] = __builtin_shufflevector(t0, t2, 0, 1, 4, 5);
    out[1] = __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
    out[2] = __builtin_shufflevector(t0, t2, 2, 3, 6, 7);
    out[3] = __builtin_shufflevector(t1, t3, 2, 3, 6, 7);
}

// Element k of the records (stride floats each) of the four lanes' vertices.
SPECBAKE_INLINE v4d gather4(const float* a, const uint32_t (&v)[kLanes], size_t stride, size_t k) {
    return v4d{a[stride * v[0] + k], a[stride * v[1] + k], a[stride * v[2] + k], a[stride * v[3] + k]};
}

// x, y, z of the four lanes' vertices, as x, y and z vectors, from double xyz records that can be read four
// doubles at a time (one spare double at the end).
SPECBAKE_INLINE void gather_xyz(const double* a, const uint32_t (&v)[kLanes], v4d (&out)[3]) {
    v4d rows[4], columns[4];
#pragma GCC unroll 4
    for (int j = 0; j < kLanes; ++j) std::memcpy(&rows[j], a + 3 * size_t(v[j]), sizeof rows[j]);
    transpose4(rows, columns);
    for (int k = 0; k < 3; ++k) out[k] = columns[k];
}

// Triangles per block of the vertex-index bounds that let a chunk skip the triangles it has no vertex in.
constexpr size_t kBlock = 1024;

// Everything the passes read, as flat arrays.
struct TangentInput {
    const float* positions;
    const float* normals;
    const float* uv;  // null without UVs
    const uint32_t* indices;
    size_t triangles;
    const uint32_t* block_bounds;  // smallest and largest vertex index per block of triangles (none without UVs)
};

// The vertices [first, last) with their working arrays, indexed from first.
struct Chunk {
    size_t first, last;
    double* unit_normals;  // 3 per vertex and one spare, so any vertex's can be read as 4 doubles
    double* sums;          // 4 per vertex: sum of the weighted projected dP/du (xyz), of the signed angles
};

// Unit normal of one vertex, (0, 0, 1) for a zero or NaN one.
SPECBAKE_INLINE void unit_normal(const float* n, double* out) {
    const double x = n[0], y = n[1], z = n[2];
    const double l = std::sqrt(x * x + y * y + z * z);
    const bool ok = l > 0.0;
    out[0] = ok ? x / l : 0.0;
    out[1] = ok ? y / l : 0.0;
    out[2] = ok ? z / l : 1.0;
}

// Unit normals of the chunk's vertices, and their sums cleared (when there are sums).
SPECBAKE_AVX2_CLONES void start_chunk(const TangentInput& in, const Chunk& chunk) {
    const size_t count = chunk.last - chunk.first;
    const float* normals = in.normals + 3 * chunk.first;
    size_t v = 0;
    for (; v + kLanes <= count; v += kLanes) {
        const float* n = normals + 3 * v;
        const v4d x{n[0], n[3], n[6], n[9]}, y{n[1], n[4], n[7], n[10]}, z{n[2], n[5], n[8], n[11]};
        const v4d l = sqrt4(x * x + y * y + z * z);
        const v4l ok = l > splat(0.0);
        const v4d ux = select(ok, x / l, splat(0.0)), uy = select(ok, y / l, splat(0.0)), uz = select(ok, z / l, splat(1.0));
        double* out = chunk.unit_normals + 3 * v;
        for (int j = 0; j < kLanes; ++j) {
            out[3 * j] = ux[j];
            out[3 * j + 1] = uy[j];
            out[3 * j + 2] = uz[j];
        }
    }
    for (; v < count; ++v) unit_normal(normals + 3 * v, chunk.unit_normals + 3 * v);
    if (chunk.sums) std::memset(chunk.sums, 0, 4 * count * sizeof(double));
}

// Triangles per batch: kGroups groups of four, one triangle per lane, computed side by side (independent
// chains of divisions and multiply-adds keep the units busy).
template <bool kAvx2>
constexpr int kGroupsOf = kAvx2 ? 2 : 1;

// MikkTSpace step 1 and the corner terms of step 2 for the triangles [t, t + count) (count <= kBatch), added
// to the sums of the chunk's vertices; kInside: every vertex of the triangles is in the chunk.
template <bool kAvx2, bool kInside>
SPECBAKE_INLINE void add_batch(const TangentInput& in, const Chunk& chunk, size_t t, int count) {
    constexpr int kGroups = kGroupsOf<kAvx2>, kBatch = kGroups * kLanes;
    const size_t owned = chunk.last - chunk.first;
    uint32_t f[3 * kBatch];  // the batch's triangles; a short last batch repeats its last one
    if (count == kBatch) {
        std::memcpy(f, in.indices + 3 * t, sizeof f);
    } else {
        for (int j = 0; j < kBatch; ++j) std::memcpy(f + 3 * j, in.indices + 3 * (t + std::min(j, count - 1)), 3 * sizeof *f);
    }
    if (!kInside) {
        bool any = false;
        for (int i = 0; i < 3 * kBatch; ++i) any |= size_t(f[i]) - chunk.first < owned;
        if (!any) return;
    }
    // Corner i % 3 of group i / 3, lane j: its vertex, and the vertex's place in the chunk (0 for the
    // vertices of other chunks, whose corners are computed but not added).
    constexpr int N = 3 * kGroups;
    uint32_t vi[N][kLanes], local[N][kLanes];
#pragma GCC unroll 8
    for (int i = 0; i < N; ++i)
#pragma GCC unroll 4
        for (int j = 0; j < kLanes; ++j) {
            vi[i][j] = f[3 * (kLanes * (i / 3) + j) + i % 3];
            const size_t l = vi[i][j] - chunk.first;
            local[i][j] = uint32_t(kInside || l < owned ? l : 0);
        }
    v4d p[N][3], u[N], v[N];  // p[corner][axis]
#pragma GCC unroll 8
    for (int i = 0; i < N; ++i) {
        for (int k = 0; k < 3; ++k) p[i][k] = gather4(in.positions, vi[i], 3, k);
        u[i] = gather4(in.uv, vi[i], 2, 0);
        v[i] = gather4(in.uv, vi[i], 2, 1);
    }
    // MikkTSpace step 1: dP/du from [dp1 dp2] = [dP/du dP/dv] [[du1 du2], [dv1 dv2]];
    // cross(N, dP/du) . (-dP/dv) = -|dp1 x dp2| / det, so the handedness is the sign of -det.
    v4d dp1[kGroups][3], dp2[kGroups][3], dp12[kGroups][3], dpdu[kGroups][3];
    v4l uv_ok[kGroups], negative_det[kGroups];
#pragma GCC unroll 4
    for (int g = 0; g < kGroups; ++g) {
        const int c0 = 3 * g, c1 = c0 + 1, c2 = c0 + 2;
        const v4d du1 = u[c1] - u[c0], dv1 = v[c1] - v[c0], du2 = u[c2] - u[c0], dv2 = v[c2] - v[c0];
        const v4d det = du1 * dv2 - du2 * dv1;  // twice the signed UV area
        const v4d adet = (v4d)((v4l)det & ~(v4l)splat(-0.0));
        uv_ok[g] = less<kAvx2>(splat(0.0), adet) & less<kAvx2>(adet, splat(INFINITY));
        negative_det[g] = less<kAvx2>(det, splat(0.0));
#pragma GCC unroll 3
        for (int k = 0; k < 3; ++k) {
            dp1[g][k] = p[c1][k] - p[c0][k];
            dp2[g][k] = p[c2][k] - p[c0][k];
            dp12[g][k] = p[c2][k] - p[c1][k];
            dpdu[g][k] = (dp1[g][k] * dv2 - dp2[g][k] * dv1) / det;
        }
    }
    // Step 2, per corner: the edges to the next and the previous corner (a - b = -(b - a) exactly),
    // dP/du projected into the vertex's tangent plane, the corner angle measured in that plane.
    v4d tp[N][3], y[N], x[N], tl[N];
    SPECBAKE_EACH {
        const int g = c / 3, corner = c % 3;
        v4d e1[3], e2[3], n[3];
        gather_xyz(chunk.unit_normals, local[c], n);
#pragma GCC unroll 3
        for (int k = 0; k < 3; ++k) {
            e1[k] = corner == 0 ? dp1[g][k] : corner == 1 ? dp12[g][k] : -dp2[g][k];
            e2[k] = corner == 0 ? dp2[g][k] : corner == 1 ? -dp1[g][k] : -dp12[g][k];
        }
        const v4d d1 = dot4(n, e1), d2 = dot4(n, e2), dn = dot4(n, dpdu[g]);
#pragma GCC unroll 3
        for (int k = 0; k < 3; ++k) {
            e1[k] = e1[k] - d1 * n[k];
            e2[k] = e2[k] - d2 * n[k];
            tp[c][k] = dpdu[g][k] - dn * n[k];
        }
        const v4d cross[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                              e1[0] * e2[1] - e1[1] * e2[0]};
        y[c] = sqrt4(dot4(cross, cross));
        x[c] = dot4(e1, e2);
        tl[c] = sqrt4(dot4(tp[c], tp[c]));
    }
    // The corner angle is only a weight: a polynomial atan2 (detail::corner_angle) instead of libm's.
    v4d angle[N], rows[N][4], terms[N][4];
    int add[N];  // lanes whose corner counts, one bit each
    corner_angles<kAvx2>(y, x, angle);
    SPECBAKE_EACH {
        const v4l ok = uv_ok[c / 3] & less<kAvx2>(splat(0.0), angle[c]) & less<kAvx2>(splat(0.0), tl[c]) &
                       less<kAvx2>(tl[c], splat(INFINITY));
        add[c] = lane_bits(ok);
        const v4d weight = angle[c] / tl[c];
        rows[c][0] = weight * tp[c][0];
        rows[c][1] = weight * tp[c][1];
        rows[c][2] = weight * tp[c][2];
        rows[c][3] = choose<kAvx2>(negative_det[c / 3], angle[c], -angle[c]);
        transpose4(rows[c], terms[c]);
    }
    auto add_term = [&](int c, int j) SPECBAKE_INLINE_LAMBDA {
        double* sum = chunk.sums + 4 * size_t(local[c][j]);
        v4d s;
        std::memcpy(&s, sum, sizeof s);
        s += terms[c][j];
        std::memcpy(sum, &s, sizeof s);
    };
    // The common case first: every corner of a full batch inside the chunk counts.
    bool every = kInside && count == kBatch;
    for (int c = 0; c < N; ++c) every = every && add[c] == (1 << kLanes) - 1;
    if (every) {
#pragma GCC unroll 2
        for (int g = 0; g < kGroups; ++g)
#pragma GCC unroll 4
            for (int j = 0; j < kLanes; ++j)
#pragma GCC unroll 3
                for (int corner = 0; corner < 3; ++corner) add_term(3 * g + corner, j);
        return;
    }
    for (int g = 0; g < kGroups; ++g)
        for (int j = 0; j < std::min(kLanes, count - kLanes * g); ++j)
#pragma GCC unroll 3
            for (int corner = 0; corner < 3; ++corner) {
                const int c = 3 * g + corner;
                if ((add[c] >> j & 1) && (kInside || size_t(vi[c][j]) - chunk.first < owned)) add_term(c, j);
            }
}

// The corners of the triangles that reference the chunk's vertices, added to those vertices' sums in corner
// order.
template <bool kAvx2>
SPECBAKE_INLINE void sum_corners_with(const TangentInput& in, const Chunk& chunk) {
    constexpr size_t kBatch = kGroupsOf<kAvx2> * kLanes;
    const size_t blocks = (in.triangles + kBlock - 1) / kBlock;
    for (size_t b = 0; b < blocks; ++b) {
        const size_t low = in.block_bounds[2 * b], high = in.block_bounds[2 * b + 1];
        if (high < chunk.first || low >= chunk.last) continue;
        const size_t end = std::min(in.triangles, (b + 1) * kBlock);
        if (low >= chunk.first && high < chunk.last) {
            for (size_t t = b * kBlock; t < end; t += kBatch) add_batch<kAvx2, true>(in, chunk, t, int(std::min(kBatch, end - t)));
        } else {
            for (size_t t = b * kBlock; t < end; t += kBatch) add_batch<kAvx2, false>(in, chunk, t, int(std::min(kBatch, end - t)));
        }
    }
}

#if defined(SPECBAKE_X86_VERSIONS)
__attribute__((target("arch=x86-64-v3"))) void sum_corners_avx2(const TangentInput& in, const Chunk& chunk) {
    sum_corners_with<true>(in, chunk);
}
#endif

void sum_corners(const TangentInput& in, const Chunk& chunk) {
#if defined(SPECBAKE_X86_VERSIONS)
    static const bool avx2 = __builtin_cpu_supports("x86-64-v3");
    if (avx2) return sum_corners_avx2(in, chunk);
#endif
    sum_corners_with<false>(in, chunk);
}

// Smallest and largest vertex index of the blocks [first, last) of triangles, eight indices at a time.
SPECBAKE_AVX2_CLONES void block_bounds_of(const uint32_t* indices, size_t triangles, size_t first, size_t last,
                                          uint32_t* bounds) {
    typedef uint32_t v8u __attribute__((vector_size(32)));
    for (size_t b = first; b < last; ++b) {
        const uint32_t* i = indices + 3 * b * kBlock;
        const uint32_t* end = indices + 3 * std::min(triangles, (b + 1) * kBlock);
        v8u low = ~v8u{}, high = v8u{};
        for (; i + 8 <= end; i += 8) {
            v8u x;
            std::memcpy(&x, i, sizeof x);
            low = x < low ? x : low;
            high = x > high ? x : high;
        }
        uint32_t lo = low[0], hi = high[0];
        for (int k = 1; k < 8; ++k) {
            lo = std::min(lo, low[k]);
            hi = std::max(hi, high[k]);
        }
        for (; i < end; ++i) {
            lo = std::min(lo, *i);
            hi = std::max(hi, *i);
        }
        bounds[2 * b] = lo;
        bounds[2 * b + 1] = hi;
    }
}

// One vertex's tangent from its unit normal and its sums (none without UVs): the sum projected into the
// tangent plane and normalised, w the sign of the signed angle sum; Frisvad's basis where the sum vanishes.
void finish_vertex(const double* un, const double* s, float* out) {
    using detail::Vec3d;
    const Vec3d nrm(un[0], un[1], un[2]);
    const Vec3d sum = s ? Vec3d(s[0], s[1], s[2]) : Vec3d(0.0, 0.0, 0.0);
    Vec3d t = sum - nrm.dot(sum) * nrm;
    double w = 1.0;
    const double tl = t.norm();
    if (tl > 1e-12 && std::isfinite(tl)) {
        t /= tl;
        w = s[3] < 0.0 ? -1.0 : 1.0;
    } else {
        Vec3d b;
        detail::orthonormal_basis(nrm, t, b);
    }
    for (int k = 0; k < 3; ++k) out[k] = float(t[k]);
    out[3] = float(w);
}

// finish_vertex for the chunk's vertices, four at a time with its operations in its order; lanes whose sum
// vanishes, and the last few vertices, take finish_vertex itself.
SPECBAKE_AVX2_CLONES void finish_chunk(const Chunk& chunk, float* tangents) {
    typedef float v4f __attribute__((vector_size(16)));
    const size_t count = chunk.last - chunk.first;
    float* out = tangents + 4 * chunk.first;
    size_t i = 0;
    if (chunk.sums) {
        const uint32_t lanes[kLanes] = {0, 1, 2, 3};
        for (; i + kLanes <= count; i += kLanes) {
            v4d n[3], rows[4], s[4];
            gather_xyz(chunk.unit_normals + 3 * i, lanes, n);
#pragma GCC unroll 4
            for (int j = 0; j < kLanes; ++j) std::memcpy(&rows[j], chunk.sums + 4 * (i + j), sizeof rows[j]);
            transpose4(rows, s);
            const v4d d = n[0] * s[0] + n[1] * s[1] + n[2] * s[2];
            v4d t[4];
#pragma GCC unroll 3
            for (int k = 0; k < 3; ++k) t[k] = s[k] - d * n[k];
            const v4d tl = sqrt4(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
            const int good = lane_bits((tl > splat(1e-12)) & (tl < splat(INFINITY)));
#pragma GCC unroll 3
            for (int k = 0; k < 3; ++k) t[k] = t[k] / tl;
            t[3] = select(s[3] < splat(0.0), splat(-1.0), splat(1.0));
            transpose4(t, rows);
#pragma GCC unroll 4
            for (int j = 0; j < kLanes; ++j) {
                const v4f f = __builtin_convertvector(rows[j], v4f);
                std::memcpy(out + 4 * (i + j), &f, sizeof f);
            }
            if (good != (1 << kLanes) - 1)
                for (int j = 0; j < kLanes; ++j)
                    if (!(good >> j & 1)) finish_vertex(chunk.unit_normals + 3 * (i + j), chunk.sums + 4 * (i + j), out + 4 * (i + j));
        }
    }
    for (; i < count; ++i) finish_vertex(chunk.unit_normals + 3 * i, chunk.sums ? chunk.sums + 4 * i : nullptr, out + 4 * i);
}

}  // namespace

void generate_tangents(TriMesh& mesh) {
    const size_t n = mesh.vertex_count();
    const size_t tris = mesh.triangle_count();
    const bool with_uv = mesh.has_uv0();

    // Vertex-index bounds of each block of triangles.
    const size_t blocks = with_uv ? (tris + kBlock - 1) / kBlock : 0;
    detail::ScratchArray<uint32_t> block_bounds(2 * blocks);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks, 16), [&](const auto& range) {
        block_bounds_of(mesh.indices.data(), tris, range.begin(), range.end(), block_bounds.data());
    });
    size_t span = 0;  // mean vertex-index span of a block
    for (size_t b = 0; b < blocks; ++b) span += block_bounds[2 * b + 1] - block_bounds[2 * b] + 1;
    span = blocks ? span / blocks : 0;

    // Chunks of consecutive vertices, each a task with its thread's set of arrays (4 MiB, instead of 56 bytes
    // per vertex of fresh memory): at most kChunk vertices or 16 block spans, so the triangles two chunks
    // share, computed by both, stay about a percent (a mesh without index locality gets one chunk per thread),
    // at least one chunk per thread, and a multiple of the thread count. The split does not change the result.
    constexpr size_t kMinChunk = 16384;
    constexpr size_t kChunk = ((size_t(4) << 20) / sizeof(double) - 1) / 7;
    const size_t threads = std::min<size_t>(size_t(std::max(1, tbb::this_task_arena::max_concurrency())),
                                            tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
    const size_t chunk_size = std::max(kChunk, 16 * span);
    size_t chunks = std::max({size_t(1), (n + chunk_size - 1) / chunk_size, std::min(threads, n / kMinChunk)});
    if (chunks > threads) chunks = (chunks + threads - 1) / threads * threads;
    const size_t length = (n + chunks - 1) / chunks;

    const TangentInput in{mesh.positions.data(), mesh.normals.data(), with_uv ? mesh.uv0.data() : nullptr,
                          mesh.indices.data(), tris, block_bounds.data()};
    mesh.tangents.clear();
    detail::reserve_huge_pages(mesh.tangents, 4 * n);
    mesh.tangents.resize(4 * n);
    float* tangents = mesh.tangents.data();
    tbb::enumerable_thread_specific<detail::ScratchArray<double>> arrays([&] {
        detail::ScratchArray<double> a((with_uv ? 7 : 3) * length + 1);
        a[3 * length] = 0.0;  // the spare double after the unit normals
        return a;
    });
    tbb::parallel_for(tbb::blocked_range<size_t>(0, chunks, 1), [&](const auto& range) {
        double* a = arrays.local().data();
        for (size_t p = range.begin(); p != range.end(); ++p) {
            const Chunk chunk{std::min(n, p * length), std::min(n, (p + 1) * length), a, with_uv ? a + 3 * length + 1 : nullptr};
            start_chunk(in, chunk);
            if (with_uv) sum_corners(in, chunk);
            finish_chunk(chunk, tangents);
        }
    });
}

}  // namespace specbake
