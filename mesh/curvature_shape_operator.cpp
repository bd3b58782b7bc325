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

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "mesh/curvature.h"
#include "mesh/curvature_frames.h"
#include "mesh/curvature_face_fit.h"
#include "mesh/scratch_array.h"

namespace specbake {
namespace {

using detail::Shape2;
using detail::Vec3d;

inline void load3(const float* x, double out[3]) {
    out[0] = x[0];
    out[1] = x[1];
    out[2] = x[2];
}
inline double dot3(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// The passes over the mesh are compiled for AVX2 and for the baseline instruction set (mesh/lanes.h); the
// face fit is shared with the patch estimator (mesh/curvature_face_fit.h).
using namespace lanes;
using detail::GroupNormal;
using detail::GroupSum;

// Weighted operators of the corners of faces t .. t + 3 (lane l: face t + l; lanes at or past `lanes`
// repeat the last face): shape[i][l] is (a, b, c, weight) of corner i of lane l, all zero for a face that
// carries no information; group[i][l] is that corner's curvature group.
SPECBAKE_INLINE void face_shapes(const FaceInput& in, size_t t, int lanes, uint32_t (&group)[3][kLanes],
                                 v4f (&shape)[3][kLanes]) {
    FaceFit4 fit;
    fit_faces4(in, t, lanes, fit);
    corner_groups4(in, fit);
    std::memcpy(group, fit.group, sizeof group);
#pragma GCC unroll 3
    for (int i = 0; i < 3; ++i) {
        v4d a, b, c;
        operator_in_group4(fit, i, a, b, c);
        const v4d zero = splat(0.0);
        const v4d record[4] = {fit.usable ? fit.w[i] * a : zero, fit.usable ? fit.w[i] * b : zero,
                               fit.usable ? fit.w[i] * c : zero, fit.usable ? fit.w[i] : zero};
        lane_records(record, shape[i]);
    }
}

// The face pass over chunk `chunk` (triangles [begin, end)), four faces at a time, adding each corner in
// corner order to its group's sums or to the chunk's deferred list; without first_chunk (one pass over all
// faces) every corner is added to the sums.
SPECBAKE_AVX2_CLONES void shape_faces(const FaceInput& in, const uint32_t* first_chunk, uint32_t chunk,
                                      size_t begin, size_t end, GroupSum* sums,
                                      std::vector<DeferredCorner<v4f>>& deferred) {
    for (size_t t = begin; t < end; t += kLanes) {
        const int lanes = int(std::min<size_t>(kLanes, end - t));
        uint32_t group[3][kLanes];
        v4f shape[3][kLanes];
        face_shapes(in, t, lanes, group, shape);
        add_corners(group, shape, lanes, first_chunk, chunk, sums, deferred);
    }
}

// Unit normals (double) of vertices [begin, end): each normal times the reciprocal of its length (a zero
// normal: non-finite components, or zeros with zero_stays_zero). Four vertices per vector, read and written
// as three vectors of consecutive components.
SPECBAKE_AVX2_CLONES void normalise_normals(const float* normals, size_t begin, size_t end, double* out,
                                            bool zero_stays_zero) {
    size_t v = begin;
    for (; v + kLanes <= end; v += kLanes) {
        v4f f[3];
        std::memcpy(f, &normals[3 * v], sizeof f);
        const v4d a = __builtin_convertvector(f[0], v4d), b = __builtin_convertvector(f[1], v4d),
                  c = __builtin_convertvector(f[2], v4d);  // x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3
        const v4d x = v4d{a[0], a[3], b[2], c[1]}, y = v4d{a[1], b[0], b[3], c[2]}, z = v4d{a[2], b[1], c[0], c[3]};
        const v4d len2 = x * x + y * y + z * z;
        v4d inv = 1.0 / sqrt4(len2);
        if (zero_stays_zero) inv = len2 > 0.0 ? inv : splat(0.0);
        const v4d scaled[3] = {a * v4d{inv[0], inv[0], inv[0], inv[1]}, b * v4d{inv[1], inv[1], inv[2], inv[2]},
                               c * v4d{inv[2], inv[3], inv[3], inv[3]}};
        std::memcpy(&out[3 * v], scaled, sizeof scaled);
    }
    for (; v < end; ++v) {
        double n[3];
        load3(&normals[3 * v], n);
        const double len2 = dot3(n, n);
        const double inv = zero_stays_zero && !(len2 > 0.0) ? 0.0 : 1.0 / std::sqrt(len2);
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

namespace detail {

FitNormals fit_normals(const TriMesh& mesh, const WeldedTopology& topology, bool zero_stays_zero) {
    const size_t verts = mesh.vertex_count();
    const uint32_t groups = topology.group_count;
    FitNormals out{ScratchArray<double>(3 * verts), ScratchArray<GroupNormal>(groups)};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, verts, 8192), [&](const auto& range) {
        normalise_normals(mesh.normals.data(), range.begin(), range.end(), out.unit.data(), zero_stays_zero);
    });
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, groups, 4096), [&](const auto& range) {
        group_normals(mesh.normals.data(), topology.group_vertex.data(), range.begin(), range.end(),
                      out.group.data());
    });
    return out;
}

VertexCurvature vertex_curvature_from_sums(const TriMesh& mesh, const WeldedTopology& topology,
                                           const GroupSum* sums, const GroupNormal* group_normals) {
    // Each vertex eigen-decomposes its group's sums itself (a group has one vertex, or a few along seams): no
    // per-group array of principal curvatures to fill and read back.
    const size_t verts = mesh.vertex_count();
    VertexCurvature out;
    reserve_huge_pages(out.values, 4 * verts);
    out.values.resize(4 * verts);
    const VertexInput vertex_input{&mesh, &topology, sums, group_normals, out.values.data()};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, verts, 8192),
                      [&](const auto& range) { vertex_outputs(vertex_input, range.begin(), range.end()); });
    return out;
}

}  // namespace detail

VertexCurvature curvature_shape_operator(const TriMesh& mesh, const WeldedTopology& topology) {
    const detail::FitNormals normals = detail::fit_normals(mesh, topology, false);
    detail::ScratchArray<GroupSum> sums(topology.group_count);
    const FaceInput input{mesh.indices.data(),   topology.position_id.data(), topology.group_id.data(),
                          mesh.positions.data(), normals.unit.data(),         normals.group.data()};
    sum_corners_in_order<v4f>(mesh, topology, sums.data(),
                              [&](const uint32_t* first_chunk, uint32_t chunk, size_t begin, size_t end,
                                  std::vector<DeferredCorner<v4f>>& deferred) {
                                  shape_faces(input, first_chunk, chunk, begin, end, sums.data(), deferred);
                              });
    return detail::vertex_curvature_from_sums(mesh, topology, sums.data(), normals.group.data());
}

}  // namespace specbake
