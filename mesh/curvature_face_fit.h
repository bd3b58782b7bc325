// The per-face shape-operator fit of Rusinkiewicz 2004 four faces at a time (mesh/lanes.h), and the
// vectorised passes around it, shared by the estimators built on it (internal to specbake_mesh):
// curvature_shape_operator.cpp, which explains the layout, and curvature_patch.cpp. Include it only from
// translation units that may take lanes.h (which turns off floating-point contraction for them).
#pragma once

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "core/trimesh.h"
#include "mesh/lanes.h"
#include "mesh/scratch_array.h"
#include "mesh/weld_by_position.h"

namespace specbake::detail {

// A curvature group's unit normal, the n of its frame (detail::group_frame); the basis (u, v) is derived
// from it where needed, which is cheaper than storing and reading it back.
struct GroupNormal {
    double n[3];
};

// A group's running sums of its corners' weighted operators (in the group's frame) and weights: a, b, c,
// weight.
struct GroupSum {
    double s[4];
};

// What the face fits read besides the mesh: the vertices' unit normals (double, each normalised once rather
// than once per triangle) and the groups' unit normals (detail::group_frame's n: the first vertex's normal
// divided by its length, +z for a zero normal). A zero vertex normal gives non-finite components, so that its
// triangles are skipped by the finiteness check of the fit, or zeros with zero_stays_zero.
struct FitNormals {
    ScratchArray<double> unit;  // 3 per vertex
    ScratchArray<GroupNormal> group;
};
FitNormals fit_normals(const TriMesh& mesh, const WeldedTopology& topology, bool zero_stays_zero);

// Output (k1, k2, d.x, d.y) of every vertex from its group's sums: the operator sums / weight (zero without
// weight), detail::principal_curvatures of it in the group's frame and detail::vertex_curvature_at, with the
// same results.
VertexCurvature vertex_curvature_from_sums(const TriMesh& mesh, const WeldedTopology& topology,
                                           const GroupSum* sums, const GroupNormal* group_normals);

}  // namespace specbake::detail

namespace specbake::lanes {

typedef float v4f __attribute__((vector_size(16)));

SPECBAKE_INLINE void cross4(const v4d (&a)[3], const v4d (&b)[3], v4d (&out)[3]) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

SPECBAKE_INLINE v4d abs4(v4d x) {
    constexpr long kMagnitude = 0x7fffffffffffffffL;  // all bits but the sign
    return (v4d)((v4l)x & v4l{kMagnitude, kMagnitude, kMagnitude, kMagnitude});
}
SPECBAKE_INLINE v4l is_finite(v4d x) { return x - x == 0.0; }  // inf - inf and NaN - NaN are NaN

// The four lanes of four quantities (q[j][l]) as four 4-float records, one per lane (out[l][j]), each
// converted to float.
SPECBAKE_INLINE void lane_records(const v4d (&q)[4], v4f (&out)[kLanes]) {
    const v4f a = __builtin_convertvector(q[0], v4f), b = __builtin_convertvector(q[1], v4f);
    const v4f c = __builtin_convertvector(q[2], v4f), d = __builtin_convertvector(q[3], v4f);
    const v4f ab_lo = __builtin_shufflevector(a, b, 0, 4, 1, 5), ab_hi = __builtin_shufflevector(a, b, 2, 6, 3, 7);
    const v4f cd_lo = __builtin_shufflevector(c, d, 0, 4, 1, 5), cd_hi = __builtin_shufflevector(c, d, 2, 6, 3, 7);
    out[0] = __builtin_shufflevector(ab_lo, cd_lo, 0, 1, 4, 5);
    out[1] = __builtin_shufflevector(ab_lo, cd_lo, 2, 3, 6, 7);
    out[2] = __builtin_shufflevector(ab_hi, cd_hi, 0, 1, 4, 5);
    out[3] = __builtin_shufflevector(ab_hi, cd_hi, 2, 3, 6, 7);
}

// detail::orthonormal_basis (Duff et al. 2017), its operations lane by lane: u and v of the group frame
// with normal n.
SPECBAKE_INLINE void orthonormal_basis4(const v4d (&n)[3], v4d (&u)[3], v4d (&v)[3]) {
    const v4l sign_bit = (v4l)splat(-0.0);
    const v4d sign = (v4d)(((v4l)n[2] & sign_bit) | (v4l)splat(1.0));  // copysign(1, n.z)
    const v4d a = -1.0 / (sign + n[2]);
    const v4d b = n[0] * n[1] * a;
    u[0] = 1.0 + sign * n[0] * n[0] * a;
    u[1] = sign * b;
    u[2] = -sign * n[0];
    v[0] = b;
    v[1] = sign + n[1] * n[1] * a;
    v[2] = -n[1];
}

// Component k of four lanes' 3-vectors.
SPECBAKE_INLINE v4d gather(const double* const (&x)[kLanes], int k) {
    return v4d{x[0][k], x[1][k], x[2][k], x[3][k]};
}
SPECBAKE_INLINE v4d gather(const float* const (&x)[kLanes], int k) {
    return __builtin_convertvector((v4f{x[0][k], x[1][k], x[2][k], x[3][k]}), v4d);
}

// Mixed-Voronoi areas of the corners of four faces with squared edge lengths l (l[i] opposite corner i)
// and areas `area` (detail::mixed_voronoi_areas, its operations lane by lane): the Voronoi region when no
// angle is obtuse, else half the area at the obtuse corner and a quarter at the two others. inv_area is
// 1 / (4 area).
SPECBAKE_INLINE void mixed_voronoi_weights4(const v4d (&l)[3], v4d area, v4d inv_area, v4d (&w)[3]) {
    const v4d cot[3] = {(l[1] + l[2] - l[0]) * inv_area, (l[0] + l[2] - l[1]) * inv_area,
                        (l[0] + l[1] - l[2]) * inv_area};
    const v4d voronoi[3] = {(l[1] * cot[1] + l[2] * cot[2]) / 8.0, (l[0] * cot[0] + l[2] * cot[2]) / 8.0,
                            (l[0] * cot[0] + l[1] * cot[1]) / 8.0};
    const v4l obtuse[3] = {l[0] > l[1] + l[2], l[1] > l[0] + l[2], l[2] > l[0] + l[1]};
    const v4l any_obtuse = obtuse[0] | obtuse[1] | obtuse[2];
#pragma GCC unroll 4
    for (int i = 0; i < 3; ++i) w[i] = obtuse[i] ? 0.5 * area : (any_obtuse ? 0.25 * area : voronoi[i]);
}

// The face's shape operator (a, b, c) = S in its frame (fu, fv), least squares over its three edges e_i
// (opposite corner i) of S e = dn, dn the change of the corner normals n along the edge (Rusinkiewicz 2004
// Sec. 3). G = 3 |cr|^2 and inv_det = 1 / ((A + C) G), cr twice the face's area vector.
SPECBAKE_INLINE void solve_face_operator4(const v4d (&e)[3][3], const v4d (&n)[3][3], const v4d (&fu)[3],
                                          const v4d (&fv)[3], v4d G, v4d inv_det, v4d& sa, v4d& sb, v4d& sc) {
    // Normal equations of the six equations [eu ev 0; 0 eu ev] (a b c)^T = (dn.u, dn.v):
    // M = [[A, B, 0], [B, A + C, B], [0, B, C]] with A = sum eu^2, B = sum eu ev, C = sum ev^2.
    v4d A = splat(0.0), B = A, C = A, r0 = A, r1 = A, r2 = A;
#pragma GCC unroll 4
    for (int i = 0; i < 3; ++i) {
        const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
        const v4d dn[3] = {n[i2][0] - n[i1][0], n[i2][1] - n[i1][1], n[i2][2] - n[i1][2]};
        const v4d eu = dot4(e[i], fu), ev = dot4(e[i], fv);
        const v4d dnu = dot4(dn, fu), dnv = dot4(dn, fv);
        A += eu * eu;
        B += eu * ev;
        C += ev * ev;
        r0 += dnu * eu;
        r1 += dnu * ev + dnv * eu;
        r2 += dnv * ev;
    }
    // det M = (A + C)(AC - B^2), and AC - B^2 = sum over edge pairs of (e_i x e_j)^2 (Cauchy-Binet) = 3 |cr|^2,
    // which keeps the solve accurate on thin triangles; A + C is the summed squared edge length.
    const v4d c00 = G + C * C, c11 = A * C, c22 = G + A * A, c01 = -B * C, c02 = B * B, c12 = -A * B;
    sa = (c00 * r0 + c01 * r1 + c02 * r2) * inv_det;
    sb = (c01 * r0 + c11 * r1 + c12 * r2) * inv_det;
    sc = (c02 * r0 + c12 * r1 + c22 * r2) * inv_det;
}

// Everything the face fit reads, as flat arrays.
struct FaceInput {
    const uint32_t* indices;
    const uint32_t* position_id;
    const uint32_t* group_id;
    const float* positions;
    const double* unit_normals;  // per vertex
    const detail::GroupNormal* group_normals;
};

// Four faces' fits (lane l: face t + l; lanes at or past `lanes` repeat the last face).
struct FaceFit4 {
    uint32_t group[3][kLanes];  // curvature group of each corner
    v4d fn[3], fu[3], fv[3];    // face frame: u along e_0, normal from the winding, v = n x u
    v4d w[3];                   // mixed-Voronoi area of each corner
    v4d sa, sb, sc;             // the operator [[sa, sb], [sb, sc]] in (fu, fv)
    v4l usable;                 // three distinct positions, not numerically a line, a finite operator
    v4d ng[3][3], ndot[3], inv_turn[3];  // per corner (corner_groups4): its group's normal, fn . ng and
                                         // 1 / (1 + fn . ng)
};

SPECBAKE_INLINE void fit_faces4(const FaceInput& in, size_t t, int lanes, FaceFit4& fit) {
    const uint32_t* f[kLanes];
    v4l distinct;
#pragma GCC unroll 4
    for (int l = 0; l < kLanes; ++l) {
        f[l] = &in.indices[3 * (t + size_t(std::min(l, lanes - 1)))];
        const uint32_t a = in.position_id[f[l][0]], b = in.position_id[f[l][1]], c = in.position_id[f[l][2]];
        distinct[l] = a != b && b != c && a != c ? -1 : 0;
        for (int i = 0; i < 3; ++i) fit.group[i][l] = in.group_id[f[l][i]];
    }
    v4d p[3][3], n[3][3];
#pragma GCC unroll 3
    for (int i = 0; i < 3; ++i) {
        const float* const pi[kLanes] = {&in.positions[3 * size_t(f[0][i])], &in.positions[3 * size_t(f[1][i])],
                                         &in.positions[3 * size_t(f[2][i])], &in.positions[3 * size_t(f[3][i])]};
        const double* const ni[kLanes] = {
            &in.unit_normals[3 * size_t(f[0][i])], &in.unit_normals[3 * size_t(f[1][i])],
            &in.unit_normals[3 * size_t(f[2][i])], &in.unit_normals[3 * size_t(f[3][i])]};
#pragma GCC unroll 4
        for (int k = 0; k < 3; ++k) {
            p[i][k] = gather(pi, k);
            n[i][k] = gather(ni, k);
        }
    }

    v4d e[3][3];
#pragma GCC unroll 4
    for (int k = 0; k < 3; ++k) {
        e[0][k] = p[2][k] - p[1][k];  // e_i opposite corner i
        e[1][k] = p[0][k] - p[2][k];
        e[2][k] = p[1][k] - p[0][k];
    }
    v4d cr[3];
    cross4(e[0], e[1], cr);  // twice the area along the face normal (winding order)
    const v4d cr2 = dot4(cr, cr);
    const v4d l[3] = {dot4(e[0], e[0]), dot4(e[1], e[1]), dot4(e[2], e[2])};
    const v4d lsum = l[0] + l[1] + l[2];
    const v4d twice_area = sqrt4(cr2);
    // Same test as detail::is_degenerate_triangle: smallest angle under ~1e-10 rad.
    fit.usable = distinct & (twice_area > 1e-10 * lsum);

    // The divisions first, so their latency overlaps the rest.
    const v4d area = 0.5 * twice_area;
    const v4d inv_area = 1.0 / (4.0 * area);
    const v4d inv_cr = 1.0 / twice_area, inv_l0 = 1.0 / sqrt4(l[0]);
    const v4d G = 3.0 * cr2;
    const v4d inv_det = 1.0 / (lsum * G);

#pragma GCC unroll 4
    for (int k = 0; k < 3; ++k) {
        fit.fn[k] = cr[k] * inv_cr;
        fit.fu[k] = e[0][k] * inv_l0;
    }
    cross4(fit.fn, fit.fu, fit.fv);

    mixed_voronoi_weights4(l, area, inv_area, fit.w);
    solve_face_operator4(e, n, fit.fu, fit.fv, G, inv_det, fit.sa, fit.sb, fit.sc);
    fit.usable &= is_finite(fit.sa) & is_finite(fit.sb) & is_finite(fit.sc);
}

// The corners' groups' normals and the rotation factors of each corner, for operator_in_group4.
SPECBAKE_INLINE void corner_groups4(const FaceInput& in, FaceFit4& fit) {
#pragma GCC unroll 3
    for (int i = 0; i < 3; ++i) {
        const double* const group_normal[kLanes] = {
            in.group_normals[fit.group[i][0]].n, in.group_normals[fit.group[i][1]].n,
            in.group_normals[fit.group[i][2]].n, in.group_normals[fit.group[i][3]].n};
#pragma GCC unroll 3
        for (int k = 0; k < 3; ++k) fit.ng[i][k] = gather(group_normal, k);
        fit.ndot[i] = dot4(fit.fn, fit.ng[i]);
        fit.inv_turn[i] = 1.0 / (1.0 + fit.ndot[i]);
    }
}

// The face operator of corner i (after corner_groups4) expressed in its group's frame (u, v)
// (orthonormal_basis4 of the group's normal): [[a, b], [b, c]].
SPECBAKE_INLINE void operator_in_group4(const FaceFit4& fit, int i, v4d& a, v4d& b, v4d& c) {
    // Rotate the face frame about fn x ng into the group's tangent plane (Rusinkiewicz 2004 Sec. 4); for
    // opposite normals, the half turn.
    const v4l opposite = fit.ndot[i] <= -1.0;
    v4d perp[3], dperp[3];
#pragma GCC unroll 4
    for (int k = 0; k < 3; ++k) {
        perp[k] = fit.ng[i][k] - fit.ndot[i] * fit.fn[k];
        dperp[k] = (fit.fn[k] + fit.ng[i][k]) * fit.inv_turn[i];
    }
    const v4d su = dot4(fit.fu, perp), sv = dot4(fit.fv, perp);
    v4d ru[3], rv[3];
#pragma GCC unroll 4
    for (int k = 0; k < 3; ++k) {
        ru[k] = opposite ? -fit.fu[k] : fit.fu[k] - dperp[k] * su;
        rv[k] = opposite ? -fit.fv[k] : fit.fv[k] - dperp[k] * sv;
    }
    v4d ug[3], vg[3];
    orthonormal_basis4(fit.ng[i], ug, vg);
    // Coordinates of the group basis vectors in the rotated face frame: S_group = P^T S_face P.
    const v4d p00 = dot4(ug, ru), p10 = dot4(ug, rv), p01 = dot4(vg, ru), p11 = dot4(vg, rv);
    const v4d s0 = fit.sa * p00 + fit.sb * p10, s1 = fit.sb * p00 + fit.sc * p10;  // S (p00, p10)
    const v4d t0 = fit.sa * p01 + fit.sb * p11, t1 = fit.sb * p01 + fit.sc * p11;  // S (p01, p11)
    a = p00 * s0 + p10 * s1;
    b = p00 * t0 + p10 * t1;
    c = p01 * t0 + p11 * t1;
}


// Corner order: the estimators add each corner's record (a, b, c, weight) to its group's sums with the
// corners of each group in increasing order, as one sequential pass over the faces would, on any number of
// threads (curvature_shape_operator.cpp explains the chunks).

// A corner whose group's first corner lies in an earlier chunk: added to the sums after all chunks.
template <class Record>
struct DeferredCorner {
    static_assert(alignof(Record) <= alignof(std::max_align_t), "kept in std::vector: no over-aligned records");
    uint32_t group;
    Record shape;
};

constexpr uint32_t kNoChunk = 0xffffffffu;
constexpr size_t kChunkFaces = 16384;  // fixed, so which corners are deferred does not depend on the threads

// The four sums in one vector addition (each component its own sequential sum). ScratchArray aligns small
// arrays to 16 bytes only, hence the unaligned loads.
SPECBAKE_INLINE void add_corner(detail::GroupSum& sum, v4d shape) {
    v4d x;
    std::memcpy(&x, sum.s, sizeof x);
    x += shape;
    std::memcpy(sum.s, &x, sizeof x);
}
SPECBAKE_INLINE void add_corner(detail::GroupSum& sum, v4f shape) {
    add_corner(sum, __builtin_convertvector(shape, v4d));
}
SPECBAKE_INLINE void add_corner(detail::GroupSum& sum, const detail::GroupSum& shape) {
    v4d x;
    std::memcpy(&x, shape.s, sizeof x);
    add_corner(sum, x);
}

// The records of the corners of `lanes` faces (shape[i][l]: corner i of lane l, in group group[i][l]), in
// corner order, each to its group's sums or, when the group's first corner lies in a chunk before `chunk`,
// to the chunk's deferred list; without first_chunk (one pass over all faces) every corner to the sums.
template <class Record>
SPECBAKE_INLINE void add_corners(const uint32_t (&group)[3][kLanes], const Record (&shape)[3][kLanes], int lanes,
                                 const uint32_t* first_chunk, uint32_t chunk, detail::GroupSum* sums,
                                 std::vector<DeferredCorner<Record>>& deferred) {
    for (int l = 0; l < lanes; ++l)
        for (int i = 0; i < 3; ++i) {
            const uint32_t g = group[i][l];
            if (!first_chunk || first_chunk[g] == chunk) add_corner(sums[g], shape[i][l]);
            else deferred.push_back({g, shape[i][l]});
        }
}

// sums[g] = the sum over group g's corners in corner order of their records. face_pass(first_chunk, chunk,
// begin, end, deferred) computes the records of faces [begin, end) and passes them to add_corners.
template <class Record, class FacePass>
void sum_corners_in_order(const TriMesh& mesh, const WeldedTopology& topology, detail::GroupSum* sums,
                          FacePass face_pass) {
    const size_t tris = mesh.triangle_count();
    const uint32_t groups = topology.group_count;
    if (tbb::this_task_arena::max_concurrency() == 1) {
        // One thread: a single pass in corner order needs neither the chunks' first corners nor deferral.
        std::fill(sums, sums + groups, detail::GroupSum{});
        std::vector<DeferredCorner<Record>> none;
        face_pass(nullptr, 0, 0, tris, none);
        return;
    }
    // The chunk of each group's first corner: the smallest chunk that has one of its corners (an atomic
    // minimum, the same whatever the order the chunks run in).
    const size_t chunks = (tris + kChunkFaces - 1) / kChunkFaces;
    detail::ScratchArray<uint32_t> first_chunk(groups);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, groups, 16384), [&](const auto& range) {
        for (uint32_t g = range.begin(); g != range.end(); ++g) {
            first_chunk[g] = kNoChunk;
            sums[g] = {};
        }
    });
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
        const size_t end = std::min(tris, (c + 1) * kChunkFaces);
        for (size_t k = 3 * c * kChunkFaces; k < 3 * end; ++k) {
            std::atomic_ref<uint32_t> first(first_chunk[topology.group_id[mesh.indices[k]]]);
            uint32_t seen = first.load(std::memory_order_relaxed);
            while (uint32_t(c) < seen && !first.compare_exchange_weak(seen, uint32_t(c), std::memory_order_relaxed)) {
            }
        }
    });
    std::vector<std::vector<DeferredCorner<Record>>> deferred(chunks);
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
        face_pass(first_chunk.data(), uint32_t(c), c * kChunkFaces, std::min(tris, (c + 1) * kChunkFaces), deferred[c]);
    });
    for (const std::vector<DeferredCorner<Record>>& list : deferred)
        for (const DeferredCorner<Record>& d : list) add_corner(sums[d.group], d.shape);
}

}  // namespace specbake::lanes
