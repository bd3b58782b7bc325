// Default estimator (CurvatureEstimator::ShapeOperator), the method SPEC Sec. 4 names: Rusinkiewicz,
// "Estimating Curvatures and Their Derivatives on Triangle Meshes", 3DPVT 2004. Per face, the 2x2 shape
// operator S (second fundamental form) is the least-squares solution of S * e_i = dn_i for the three edges
// e_i and the differences dn_i of the vertex normals along them, both in the face's (u, v) frame (Sec. 3,
// Eq. 2-3). S is symmetric, so the unknowns are (a, b, c) of [[a, b], [b, c]] and the normal equations form
// a full 3x3 system that is solved as such (in closed form, below). Each face's S is rotated into the frame
// of each corner's curvature group and accumulated with the corner's mixed-Voronoi area (Sec. 4-5), then
// normalised by the summed area. Exact for spherical and cylindrical normals; on irregular triangulations
// its error is first order in the edge length (curvature_second_order.cpp explains why and offers a
// second-order fit).
//
// Layout for speed: four passes, over the vertices (unit normals, double), the groups (the unit normal of
// each group's frame), the faces and the vertices again, each taking four items at a time, one per lane of a
// 4-wide double vector (GCC/Clang vector extension: one AVX2 register, two SSE2 registers). They are compiled
// for AVX2 and for the baseline instruction set and chosen at load time (function multiversioning). Every
// lane performs the IEEE operations of the scalar formulas in the same order, and fused multiply-adds are
// off, so both versions give the same bits. A group's tangent basis (u, v) is derived from its normal where
// it is needed, which costs less than writing and reading back 48 more bytes a group. The face pass computes
// a weighted operator per corner as four floats and adds it to its group's sums (double) in corner order, so
// the result does not depend on the thread count; the last pass eigen-decomposes each vertex's group sum and
// writes the vertex's output. On several threads the faces are cut into chunks of a fixed size, processed in
// parallel: a chunk adds a corner straight into its group's sums when the group's first corner lies in that
// chunk (no other chunk adds to them before it), and otherwise keeps the corner in a list that is added
// afterwards, chunk by chunk, in corner order. Each group's sum thus runs over its corners in increasing
// order as one sequential pass would (which is what one thread runs), without a per-corner array or a sort of
// corners by group; meshes in a spatially coherent order (as exported) defer few corners.
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "mesh/curvature.h"
#include "mesh/curvature_frames.h"
#include "mesh/lanes.h"
#include "mesh/scratch_array.h"

namespace specbake {
namespace {

using detail::Shape2;
using detail::Vec3d;

// A curvature group's unit normal, the n of its frame (detail::group_frame); the basis (u, v) is derived
// from it where needed, which is cheaper than storing and reading it back.
struct GroupNormal {
    double n[3];
};

inline void load3(const float* x, double out[3]) {
    out[0] = x[0];
    out[1] = x[1];
    out[2] = x[2];
}
inline double dot3(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// The passes over the mesh are compiled for AVX2 and for the baseline instruction set (mesh/lanes.h).
using namespace lanes;
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

// Everything the face pass reads, as flat arrays.
struct FaceInput {
    const uint32_t* indices;
    const uint32_t* position_id;
    const uint32_t* group_id;
    const float* positions;
    const double* unit_normals;  // per vertex
    const GroupNormal* group_normals;
};

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

// Weighted operators of the corners of faces t .. t + 3 (lane l: face t + l; lanes at or past `lanes`
// repeat the last face): shape[i][l] is (a, b, c, weight) of corner i of lane l, all zero for a face that
// carries no information; group[i][l] is that corner's curvature group.
SPECBAKE_INLINE void face_shapes(const FaceInput& in, size_t t, int lanes, uint32_t (&group)[3][kLanes],
                                 v4f (&shape)[3][kLanes]) {
    const uint32_t* f[kLanes];
    v4l distinct;
#pragma GCC unroll 4
    for (int l = 0; l < kLanes; ++l) {
        f[l] = &in.indices[3 * (t + size_t(std::min(l, lanes - 1)))];
        const uint32_t a = in.position_id[f[l][0]], b = in.position_id[f[l][1]], c = in.position_id[f[l][2]];
        distinct[l] = a != b && b != c && a != c ? -1 : 0;
        for (int i = 0; i < 3; ++i) group[i][l] = in.group_id[f[l][i]];
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
    v4l usable = distinct & (twice_area > 1e-10 * lsum);

    // The divisions first, so their latency overlaps the rest.
    const v4d area = 0.5 * twice_area;
    const v4d inv_area = 1.0 / (4.0 * area);
    const v4d inv_cr = 1.0 / twice_area, inv_l0 = 1.0 / sqrt4(l[0]);
    const v4d G = 3.0 * cr2;
    const v4d inv_det = 1.0 / (lsum * G);

    // Face frame: u along e_0, normal from the winding, v = n x u.
    v4d fn[3], fu[3], fv[3];
#pragma GCC unroll 4
    for (int k = 0; k < 3; ++k) {
        fn[k] = cr[k] * inv_cr;
        fu[k] = e[0][k] * inv_l0;
    }
    cross4(fn, fu, fv);

    // The groups' frames and the rotation factor 1 / (1 + n . ng) of each corner.
    v4d ng[3][3], ug[3][3], vg[3][3], ndot[3], inv_turn[3];
#pragma GCC unroll 3
    for (int i = 0; i < 3; ++i) {
        const double* const group_normal[kLanes] = {
            in.group_normals[group[i][0]].n, in.group_normals[group[i][1]].n, in.group_normals[group[i][2]].n,
            in.group_normals[group[i][3]].n};
#pragma GCC unroll 3
        for (int k = 0; k < 3; ++k) ng[i][k] = gather(group_normal, k);
        orthonormal_basis4(ng[i], ug[i], vg[i]);
        ndot[i] = dot4(fn, ng[i]);
        inv_turn[i] = 1.0 / (1.0 + ndot[i]);
    }

    v4d w[3];
    mixed_voronoi_weights4(l, area, inv_area, w);
    v4d sa, sb, sc;
    solve_face_operator4(e, n, fu, fv, G, inv_det, sa, sb, sc);
    usable &= is_finite(sa) & is_finite(sb) & is_finite(sc);

#pragma GCC unroll 3
    for (int i = 0; i < 3; ++i) {
        // Rotate the face frame about fn x ng into the group's tangent plane (Rusinkiewicz 2004 Sec. 4); for
        // opposite normals, the half turn.
        const v4l opposite = ndot[i] <= -1.0;
        v4d perp[3], dperp[3];
#pragma GCC unroll 4
        for (int k = 0; k < 3; ++k) {
            perp[k] = ng[i][k] - ndot[i] * fn[k];
            dperp[k] = (fn[k] + ng[i][k]) * inv_turn[i];
        }
        const v4d su = dot4(fu, perp), sv = dot4(fv, perp);
        v4d ru[3], rv[3];
#pragma GCC unroll 4
        for (int k = 0; k < 3; ++k) {
            ru[k] = opposite ? -fu[k] : fu[k] - dperp[k] * su;
            rv[k] = opposite ? -fv[k] : fv[k] - dperp[k] * sv;
        }
        // Coordinates of the group basis vectors in the rotated face frame: S_group = P^T S_face P.
        const v4d p00 = dot4(ug[i], ru), p10 = dot4(ug[i], rv), p01 = dot4(vg[i], ru), p11 = dot4(vg[i], rv);
        const v4d s0 = sa * p00 + sb * p10, s1 = sb * p00 + sc * p10;  // S (p00, p10)
        const v4d t0 = sa * p01 + sb * p11, t1 = sb * p01 + sc * p11;  // S (p01, p11)
        const v4d zero = splat(0.0);
        const v4d record[4] = {usable ? w[i] * (p00 * s0 + p10 * s1) : zero,
                               usable ? w[i] * (p00 * t0 + p10 * t1) : zero,
                               usable ? w[i] * (p01 * t0 + p11 * t1) : zero, usable ? w[i] : zero};
        lane_records(record, shape[i]);
    }
}

// A group's running sums of its corners' weighted operators and weights: a, b, c, weight.
struct GroupSum {
    double s[4];
};

// A corner whose group's first corner lies in an earlier chunk: added to the sums after all chunks.
struct DeferredCorner {
    uint32_t group;
    v4f shape;  // (a, b, c, weight) of the corner, weighted by its mixed-Voronoi area, in the group's frame
};

constexpr uint32_t kNoChunk = 0xffffffffu;
constexpr size_t kChunkFaces = 16384;  // fixed, so which corners are deferred does not depend on the threads

// The four sums in one vector addition (each component its own sequential sum). ScratchArray aligns small
// arrays to 16 bytes only, hence the unaligned loads.
SPECBAKE_INLINE void add_corner(GroupSum& sum, v4f shape) {
    v4d x;
    std::memcpy(&x, sum.s, sizeof x);
    x += __builtin_convertvector(shape, v4d);
    std::memcpy(sum.s, &x, sizeof x);
}

// The face pass over chunk `chunk` (triangles [begin, end)), four faces at a time, adding each corner in
// corner order to its group's sums or to the chunk's deferred list; without first_chunk (one pass over all
// faces) every corner is added to the sums.
SPECBAKE_AVX2_CLONES void shape_faces(const FaceInput& in, const uint32_t* first_chunk, uint32_t chunk,
                                      size_t begin, size_t end, GroupSum* sums,
                                      std::vector<DeferredCorner>& deferred) {
    for (size_t t = begin; t < end; t += kLanes) {
        const int lanes = int(std::min<size_t>(kLanes, end - t));
        uint32_t group[3][kLanes];
        v4f shape[3][kLanes];
        face_shapes(in, t, lanes, group, shape);
        for (int l = 0; l < lanes; ++l)
            for (int i = 0; i < 3; ++i) {
                const uint32_t g = group[i][l];
                if (!first_chunk || first_chunk[g] == chunk) add_corner(sums[g], shape[i][l]);
                else deferred.push_back({g, shape[i][l]});
            }
    }
}

// Unit normals (double) of vertices [begin, end): each normal times the reciprocal of its length. Four
// vertices per vector, read and written as three vectors of consecutive components.
SPECBAKE_AVX2_CLONES void normalise_normals(const float* normals, size_t begin, size_t end, double* out) {
    size_t v = begin;
    for (; v + kLanes <= end; v += kLanes) {
        v4f f[3];
        std::memcpy(f, &normals[3 * v], sizeof f);
        const v4d a = __builtin_convertvector(f[0], v4d), b = __builtin_convertvector(f[1], v4d),
                  c = __builtin_convertvector(f[2], v4d);  // x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3
        const v4d x = v4d{a[0], a[3], b[2], c[1]}, y = v4d{a[1], b[0], b[3], c[2]}, z = v4d{a[2], b[1], c[0], c[3]};
        const v4d inv = 1.0 / sqrt4(x * x + y * y + z * z);
        const v4d scaled[3] = {a * v4d{inv[0], inv[0], inv[0], inv[1]}, b * v4d{inv[1], inv[1], inv[2], inv[2]},
                               c * v4d{inv[2], inv[3], inv[3], inv[3]}};
        std::memcpy(&out[3 * v], scaled, sizeof scaled);
    }
    for (; v < end; ++v) {
        double n[3];
        load3(&normals[3 * v], n);
        const double inv = 1.0 / std::sqrt(dot3(n, n));
        for (int k = 0; k < 3; ++k) out[3 * v + k] = n[k] * inv;
    }
}

// Unit normals of groups [begin, end) (detail::group_frame's n, its operations lane by lane): the first
// vertex's normal divided by its length, +z for a zero normal.
SPECBAKE_AVX2_CLONES void group_normals(const float* normals, const uint32_t* group_vertex, uint32_t begin,
                                        uint32_t end, GroupNormal* out) {
    for (uint32_t first = begin; first < end; first += kLanes) {
        const int lanes = int(std::min<uint32_t>(kLanes, end - first));
        const float* normal[kLanes];
#pragma GCC unroll 4
        for (int l = 0; l < kLanes; ++l)
            normal[l] = &normals[3 * size_t(group_vertex[first + uint32_t(std::min(l, lanes - 1))])];
        const v4d x = gather(normal, 0), y = gather(normal, 1), z = gather(normal, 2);
        const v4d len = sqrt4(x * x + y * y + z * z);
        const v4l nonzero = len > 0.0;
        const v4d n[3] = {nonzero ? x / len : splat(0.0), nonzero ? y / len : splat(0.0),
                          nonzero ? z / len : splat(1.0)};
        for (int l = 0; l < lanes; ++l) out[first + uint32_t(l)] = {{n[0][l], n[1][l], n[2][l]}};
    }
}

// Everything the vertex pass reads and writes.
struct VertexInput {
    const TriMesh* mesh;
    const WeldedTopology* topology;
    const GroupSum* sums;  // per group
    const GroupNormal* group_normals;
    float* out;  // 4 per vertex
};

// Output (k1, k2, d.x, d.y) of vertices [begin, end), four at a time (lane l: vertex first + l): the group's
// summed operator normalised by its weight, detail::principal_curvatures of it and detail::vertex_curvature_at,
// their operations lane by lane. A vertex whose normal is zero or whose tangent is along its normal takes
// the scalar functions, which handle those cases.
SPECBAKE_AVX2_CLONES void vertex_outputs(const VertexInput& in, size_t begin, size_t end) {
    const uint32_t* group_id = in.topology->group_id.data();
    const float* normals = in.mesh->normals.data();
    const float* tangents = in.mesh->tangents.data();
    for (size_t first = begin; first < end; first += kLanes) {
        const int lanes = int(std::min<size_t>(kLanes, end - first));
        size_t vertex[kLanes];
        const double* sum[kLanes];
        const double* group_normal[kLanes];
        const float *vn[kLanes], *vt[kLanes];
#pragma GCC unroll 4
        for (int l = 0; l < kLanes; ++l) {
            vertex[l] = first + size_t(std::min(l, lanes - 1));
            const uint32_t g = group_id[vertex[l]];
            sum[l] = in.sums[g].s;
            group_normal[l] = in.group_normals[g].n;
            vn[l] = &normals[3 * vertex[l]];
            vt[l] = &tangents[4 * vertex[l]];
        }
        // The vertex's tangent frame: N normalised, T orthogonalised against N and normalised (B = N x T * w
        // below); first, so that its divisions overlap the group's.
        v4d n[3] = {gather(vn, 0), gather(vn, 1), gather(vn, 2)};
        const v4d n2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
        v4l scalar = !(n2 > 0.0);
        const v4d n_len = sqrt4(n2);
#pragma GCC unroll 3
        for (int k = 0; k < 3; ++k) n[k] = n[k] / n_len;
        v4d t[3] = {gather(vt, 0), gather(vt, 1), gather(vt, 2)};
        const v4d nt = n[0] * t[0] + n[1] * t[1] + n[2] * t[2];
#pragma GCC unroll 3
        for (int k = 0; k < 3; ++k) t[k] = t[k] - nt * n[k];
        const v4d t_len = sqrt4(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
        scalar |= !(t_len > 1e-12);
#pragma GCC unroll 3
        for (int k = 0; k < 3; ++k) t[k] = t[k] / t_len;

        // The group's operator (no data: zero).
        const v4d weight = gather(sum, 3);
        const v4l weighted = weight > 0.0;
        const v4d a = weighted ? gather(sum, 0) / weight : splat(0.0);
        const v4d b = weighted ? gather(sum, 1) / weight : splat(0.0);
        const v4d c = weighted ? gather(sum, 2) / weight : splat(0.0);

        // Principal curvatures, |k1| >= |k2|, and the k1 eigenvector from the better conditioned row of S - k1 I.
        const v4d mean = 0.5 * (a + c), half_diff = 0.5 * (a - c);
        const v4d radius = sqrt4(half_diff * half_diff + b * b);
        const v4d hi = mean + radius, lo = mean - radius;
        const v4l hi_first = abs4(hi) >= abs4(lo);
        const v4d k1 = hi_first ? hi : lo, k2 = hi_first ? lo : hi;
        const v4d x1 = b, y1 = k1 - a, x2 = k1 - c, y2 = b;
        const v4l row2 = x2 * x2 + y2 * y2 > x1 * x1 + y1 * y1;
        v4d x = row2 ? x2 : x1, y = row2 ? y2 : y1;
        const v4d len = sqrt4(x * x + y * y);
        const v4d abs_k1 = abs4(k1);
        const v4l directed = len > 1e-12 * (abs_k1 < 1e-300 ? splat(1e-300) : abs_k1);
        x = directed ? x / len : splat(1.0);
        y = directed ? y / len : splat(0.0);
        const v4d ng[3] = {gather(group_normal, 0), gather(group_normal, 1), gather(group_normal, 2)};
        v4d u[3], v[3], dir[3];
        orthonormal_basis4(ng, u, v);
#pragma GCC unroll 3
        for (int k = 0; k < 3; ++k) dir[k] = x * u[k] + y * v[k];

        const v4d sign = gather(vt, 3) < 0.0 ? splat(-1.0) : splat(1.0);
        const v4d bt[3] = {sign * (n[1] * t[2] - n[2] * t[1]), sign * (n[2] * t[0] - n[0] * t[2]),
                           sign * (n[0] * t[1] - n[1] * t[0])};
        v4d dx = dir[0] * t[0] + dir[1] * t[1] + dir[2] * t[2];
        v4d dy = dir[0] * bt[0] + dir[1] * bt[1] + dir[2] * bt[2];
        const v4d d_len = sqrt4(dx * dx + dy * dy);
        const v4l unit = d_len > 1e-12;
        dx = unit ? dx / d_len : splat(1.0);
        dy = unit ? dy / d_len : splat(0.0);

        v4f value[kLanes];
        lane_records({k1, k2, dx, dy}, value);
        for (int l = 0; l < lanes; ++l) {
            float* out = &in.out[4 * vertex[l]];
            if (!scalar[l]) {
                std::memcpy(out, &value[l], sizeof value[l]);
                continue;
            }
            Shape2 shape;
            if (weight[l] > 0.0) shape = {a[l], b[l], c[l]};
            const detail::GroupPrincipal principal = detail::principal_curvatures(
                shape, Vec3d(u[0][l], u[1][l], u[2][l]), Vec3d(v[0][l], v[1][l], v[2][l]));
            detail::vertex_curvature_at(*in.mesh, *in.topology, vertex[l], principal, out);
        }
    }
}

}  // namespace

VertexCurvature curvature_shape_operator(const TriMesh& mesh, const WeldedTopology& topology) {
    const size_t verts = mesh.vertex_count(), tris = mesh.triangle_count();
    const uint32_t groups = topology.group_count;
    // Unit normals in double, each normalised once rather than once per triangle (same values); a zero normal
    // gives non-finite components, and its triangles are then skipped by the finiteness check of the fit.
    detail::ScratchArray<double> unit_normal(3 * verts);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, verts, 8192), [&](const auto& range) {
        normalise_normals(mesh.normals.data(), range.begin(), range.end(), unit_normal.data());
    });
    detail::ScratchArray<GroupNormal> normals(groups);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, groups, 4096), [&](const auto& range) {
        group_normals(mesh.normals.data(), topology.group_vertex.data(), range.begin(), range.end(),
                      normals.data());
    });

    detail::ScratchArray<GroupSum> sums(groups);
    const FaceInput input{mesh.indices.data(),      topology.position_id.data(), topology.group_id.data(),
                          mesh.positions.data(),    unit_normal.data(),          normals.data()};
    if (tbb::this_task_arena::max_concurrency() == 1) {
        // One thread: a single pass in corner order needs neither the chunks' first corners nor deferral.
        std::fill(sums.data(), sums.data() + groups, GroupSum{});
        std::vector<DeferredCorner> none;
        shape_faces(input, nullptr, 0, 0, tris, sums.data(), none);
    } else {
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
                while (uint32_t(c) < seen &&
                       !first.compare_exchange_weak(seen, uint32_t(c), std::memory_order_relaxed)) {
                }
            }
        });
        std::vector<std::vector<DeferredCorner>> deferred(chunks);
        tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
            shape_faces(input, first_chunk.data(), uint32_t(c), c * kChunkFaces,
                        std::min(tris, (c + 1) * kChunkFaces), sums.data(), deferred[c]);
        });
        for (const std::vector<DeferredCorner>& list : deferred)
            for (const DeferredCorner& d : list) add_corner(sums[d.group], d.shape);
    }

    // Each vertex eigen-decomposes its group's sums itself (a group has one vertex, or a few along seams): no
    // per-group array of principal curvatures to fill and read back.
    VertexCurvature out;
    detail::reserve_huge_pages(out.values, 4 * verts);
    out.values.resize(4 * verts);
    const VertexInput vertex_input{&mesh, &topology, sums.data(), normals.data(), out.values.data()};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, verts, 8192),
                      [&](const auto& range) { vertex_outputs(vertex_input, range.begin(), range.end()); });
    return out;
}

}  // namespace specbake
