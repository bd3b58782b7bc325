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
// Layout for speed: the vertices' unit normals (double) and the groups' frames are computed once up front;
// one pass over the faces computes a weighted operator per corner as four floats and adds it to its group's
// sums (double) in corner order, so the result does not depend on the thread count; a last pass over the
// vertices eigen-decomposes each vertex's group sum and writes the vertex's output. The faces are cut into
// chunks of a fixed size, processed in parallel: a chunk adds a corner straight into its group's sums when
// the group's first corner lies in that chunk (no other chunk adds to them before it), and otherwise keeps
// the corner in a list that is added afterwards, chunk by chunk, in corner order. Each group's sum thus
// runs over its corners in increasing order as one sequential pass would, without a per-corner array or a
// sort of corners by group; meshes in a spatially coherent order (as exported) defer few corners.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <vector>

#include "mesh/curvature.h"
#include "mesh/curvature_frames.h"
#include "mesh/scratch_array.h"

namespace specbake {
namespace {

using detail::Shape2;
using detail::Vec3d;

// A curvature group's frame (detail::group_frame), stored together because each corner reads all three.
struct Frame {
    double n[3], u[3], v[3];
};

// Weighted operator of one corner in its group's (u, v) frame, and the weight (mixed-Voronoi area).
struct CornerShape {
    float a, b, c, weight;
};

inline void load3(const float* x, double out[3]) {
    out[0] = x[0];
    out[1] = x[1];
    out[2] = x[2];
}
inline double dot3(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline void cross3(const double* a, const double* b, double* out) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

// The three weighted corner operators of triangle t; zero weights when it carries no information.
__attribute__((always_inline)) inline void face_shape(const TriMesh& mesh, const WeldedTopology& topology,
                                                     const double* unit_normals, const Frame* frames, size_t t,
                                                     CornerShape out[3]) {
    const uint32_t* f = &mesh.indices[3 * t];
    for (int i = 0; i < 3; ++i) out[i] = {0.0f, 0.0f, 0.0f, 0.0f};
    const uint32_t* pid = topology.position_id.data();
    if (pid[f[0]] == pid[f[1]] || pid[f[1]] == pid[f[2]] || pid[f[0]] == pid[f[2]]) return;

    double p[3][3], e[3][3];
    for (int i = 0; i < 3; ++i) load3(&mesh.positions[3 * size_t(f[i])], p[i]);
    for (int k = 0; k < 3; ++k) {
        e[0][k] = p[2][k] - p[1][k];  // e_i opposite corner i
        e[1][k] = p[0][k] - p[2][k];
        e[2][k] = p[1][k] - p[0][k];
    }
    double cr[3];
    cross3(e[0], e[1], cr);  // twice the area along the face normal (winding order)
    const double cr2 = dot3(cr, cr);
    const double l[3] = {dot3(e[0], e[0]), dot3(e[1], e[1]), dot3(e[2], e[2])};
    const double lsum = l[0] + l[1] + l[2];
    const double twice_area = std::sqrt(cr2);
    // Same test as detail::is_degenerate_triangle: smallest angle under ~1e-10 rad.
    if (!(twice_area > 1e-10 * lsum)) return;

    double w[3];
    detail::mixed_voronoi_areas(l[0], l[1], l[2], 0.5 * twice_area, w);

    const double* n[3];
    for (int i = 0; i < 3; ++i) n[i] = &unit_normals[3 * size_t(f[i])];

    // Face frame: u along e_0, normal from the winding, v = n x u.
    double fn[3], fu[3], fv[3];
    const double inv_cr = 1.0 / twice_area, inv_l0 = 1.0 / std::sqrt(l[0]);
    for (int k = 0; k < 3; ++k) {
        fn[k] = cr[k] * inv_cr;
        fu[k] = e[0][k] * inv_l0;
    }
    cross3(fn, fu, fv);

    // Normal equations of the six equations [eu ev 0; 0 eu ev] (a b c)^T = (dn.u, dn.v):
    // M = [[A, B, 0], [B, A + C, B], [0, B, C]] with A = sum eu^2, B = sum eu ev, C = sum ev^2.
    double A = 0.0, B = 0.0, C = 0.0, r0 = 0.0, r1 = 0.0, r2 = 0.0;
    for (int i = 0; i < 3; ++i) {
        const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
        const double dn[3] = {n[i2][0] - n[i1][0], n[i2][1] - n[i1][1], n[i2][2] - n[i1][2]};
        const double eu = dot3(e[i], fu), ev = dot3(e[i], fv);
        const double dnu = dot3(dn, fu), dnv = dot3(dn, fv);
        A += eu * eu;
        B += eu * ev;
        C += ev * ev;
        r0 += dnu * eu;
        r1 += dnu * ev + dnv * eu;
        r2 += dnv * ev;
    }
    // det M = (A + C)(AC - B^2), and AC - B^2 = sum over edge pairs of (e_i x e_j)^2 (Cauchy-Binet) = 3 |cr|^2,
    // which keeps the solve accurate on thin triangles; A + C is the summed squared edge length.
    const double G = 3.0 * cr2;
    const double inv_det = 1.0 / (lsum * G);
    const double c00 = G + C * C, c11 = A * C, c22 = G + A * A, c01 = -B * C, c02 = B * B, c12 = -A * B;
    const double sa = (c00 * r0 + c01 * r1 + c02 * r2) * inv_det;
    const double sb = (c01 * r0 + c11 * r1 + c12 * r2) * inv_det;
    const double sc = (c02 * r0 + c12 * r1 + c22 * r2) * inv_det;
    if (!std::isfinite(sa) || !std::isfinite(sb) || !std::isfinite(sc)) return;

    for (int i = 0; i < 3; ++i) {
        const uint32_t g = topology.group_id[f[i]];
        const Frame& frame = frames[g];
        const double* ng = frame.n;
        // Rotate the face frame about fn x ng into the group's tangent plane (Rusinkiewicz 2004 Sec. 4).
        double ru[3] = {fu[0], fu[1], fu[2]}, rv[3] = {fv[0], fv[1], fv[2]};
        const double ndot = dot3(fn, ng);
        if (ndot <= -1.0) {
            for (int k = 0; k < 3; ++k) {
                ru[k] = -ru[k];
                rv[k] = -rv[k];
            }
        } else {
            double perp[3], dperp[3];
            const double inv = 1.0 / (1.0 + ndot);
            for (int k = 0; k < 3; ++k) {
                perp[k] = ng[k] - ndot * fn[k];
                dperp[k] = (fn[k] + ng[k]) * inv;
            }
            const double su = dot3(fu, perp), sv = dot3(fv, perp);
            for (int k = 0; k < 3; ++k) {
                ru[k] -= dperp[k] * su;
                rv[k] -= dperp[k] * sv;
            }
        }
        // Coordinates of the group basis vectors in the rotated face frame: S_group = P^T S_face P.
        const double* ug = frame.u;
        const double* vg = frame.v;
        const double p00 = dot3(ug, ru), p10 = dot3(ug, rv), p01 = dot3(vg, ru), p11 = dot3(vg, rv);
        const double s0 = sa * p00 + sb * p10, s1 = sb * p00 + sc * p10;  // S (p00, p10)
        const double t0 = sa * p01 + sb * p11, t1 = sb * p01 + sc * p11;  // S (p01, p11)
        out[i] = {float(w[i] * (p00 * s0 + p10 * s1)), float(w[i] * (p00 * t0 + p10 * t1)),
                  float(w[i] * (p01 * t0 + p11 * t1)), float(w[i])};
    }
}

// A group's running sums of its corners' weighted operators and weights.
struct GroupSum {
    double a, b, c, weight;
};

// A corner whose group's first corner lies in an earlier chunk: added to the sums after all chunks.
struct DeferredCorner {
    uint32_t group;
    CornerShape shape;
};

constexpr uint32_t kNoChunk = 0xffffffffu;
constexpr size_t kChunkFaces = 16384;  // fixed, so which corners are deferred does not depend on the threads

inline void add_corner(GroupSum& sum, const CornerShape& s) {
    sum.a += s.a;
    sum.b += s.b;
    sum.c += s.c;
    sum.weight += s.weight;
}

// The face pass over chunk `chunk` (triangles [begin, end)), compiled for AVX2 and for the baseline
// instruction set and chosen at load time (GCC/Clang function multiversioning). Floating-point contraction
// is off (ISO C++ mode), so both versions compute the same bits.
#if defined(__x86_64__) && defined(__linux__)
__attribute__((target_clones("arch=x86-64-v3", "default")))
#endif
void shape_faces(const TriMesh& mesh, const WeldedTopology& topology, const double* unit_normals,
                 const Frame* frames, const uint32_t* first_chunk, uint32_t chunk, size_t begin, size_t end,
                 GroupSum* sums, std::vector<DeferredCorner>& deferred) {
    for (size_t t = begin; t != end; ++t) {
        CornerShape corner[3];
        face_shape(mesh, topology, unit_normals, frames, t, corner);
        for (int i = 0; i < 3; ++i) {
            const uint32_t g = topology.group_id[mesh.indices[3 * t + i]];
            if (first_chunk[g] == chunk) add_corner(sums[g], corner[i]);
            else deferred.push_back({g, corner[i]});
        }
    }
}

}  // namespace

VertexCurvature curvature_shape_operator(const TriMesh& mesh, const WeldedTopology& topology) {
    const size_t verts = mesh.vertex_count(), tris = mesh.triangle_count();
    const uint32_t groups = topology.group_count;
    // Unit normals in double, each normalised once rather than once per triangle (same values); a zero normal
    // gives non-finite components, and its triangles are then skipped by the finiteness check of the fit.
    detail::ScratchArray<double> unit_normals(3 * verts);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, verts, 8192), [&](const auto& range) {
        for (size_t v = range.begin(); v != range.end(); ++v) {
            double* n = &unit_normals[3 * v];
            load3(&mesh.normals[3 * v], n);
            const double inv = 1.0 / std::sqrt(dot3(n, n));
            for (int k = 0; k < 3; ++k) n[k] *= inv;
        }
    });
    detail::ScratchArray<Frame> frames(groups);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, groups, 4096), [&](const auto& range) {
        for (uint32_t g = range.begin(); g != range.end(); ++g) {
            Vec3d n, u, v;
            detail::group_frame(&mesh.normals[3 * size_t(topology.group_vertex[g])], n, u, v);
            for (int k = 0; k < 3; ++k) {
                frames[g].n[k] = n[k];
                frames[g].u[k] = u[k];
                frames[g].v[k] = v[k];
            }
        }
    });

    // The chunk of each group's first corner: the smallest chunk that has one of its corners (an atomic
    // minimum, the same whatever the order the chunks run in).
    const size_t chunks = (tris + kChunkFaces - 1) / kChunkFaces;
    detail::ScratchArray<uint32_t> first_chunk(groups);
    detail::ScratchArray<GroupSum> sums(groups);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, groups, 16384), [&](const auto& range) {
        for (uint32_t g = range.begin(); g != range.end(); ++g) {
            first_chunk[g] = kNoChunk;
            sums[g] = {0.0, 0.0, 0.0, 0.0};
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

    std::vector<std::vector<DeferredCorner>> deferred(chunks);
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
        shape_faces(mesh, topology, unit_normals.data(), frames.data(), first_chunk.data(), uint32_t(c),
                    c * kChunkFaces, std::min(tris, (c + 1) * kChunkFaces), sums.data(), deferred[c]);
    });
    for (const std::vector<DeferredCorner>& list : deferred)
        for (const DeferredCorner& d : list) add_corner(sums[d.group], d.shape);

    // Each vertex eigen-decomposes its group's sums itself (a group has one vertex, or a few along seams): no
    // per-group array of principal curvatures to fill and read back.
    VertexCurvature out;
    detail::reserve_huge_pages(out.values, 4 * verts);
    out.values.resize(4 * verts);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, verts, 8192), [&](const auto& range) {
        for (size_t v = range.begin(); v != range.end(); ++v) {
            const uint32_t g = topology.group_id[v];
            const GroupSum& sum = sums[g];
            Shape2 shape;
            if (sum.weight > 0.0) shape = {sum.a / sum.weight, sum.b / sum.weight, sum.c / sum.weight};
            const Frame& f = frames[g];
            const detail::GroupPrincipal principal = detail::principal_curvatures(
                shape, Vec3d(f.u[0], f.u[1], f.u[2]), Vec3d(f.v[0], f.v[1], f.v[2]));
            detail::vertex_curvature_at(mesh, topology, v, principal, &out.values[4 * v]);
        }
    });
    return out;
}

}  // namespace specbake
