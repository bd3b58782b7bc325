// Second-order estimator (CurvatureEstimator::SecondOrder), after Rusinkiewicz, "Estimating Curvatures and
// Their Derivatives on Triangle Meshes", 3DPVT 2004. The 2x2 shape operator S (second fundamental form) is
// the least-squares solution of S * e = dn for the edges e of the triangles around a vertex and the
// differences dn of the vertex normals along them, both in a (u, v) tangent frame (Sec. 3, Eq. 2-3); S is
// symmetric, so the unknowns are (a, b, c) of [[a, b], [b, c]], and each triangle counts with its corner's
// mixed-Voronoi area (Sec. 4-5). Unlike the default estimator (curvature_shape_operator.cpp, the per-face
// fit of SPEC Sec. 4), the fit also models the curvature derivative of Sec. 6.
//
// Second order on irregular meshes. Rusinkiewicz (and the default estimator) fits S per face and averages
// the face operators at the vertices. A face's fit is the gradient of the linear interpolant of the
// normals: it is exact at the face's centroid only up to O(h) terms in the normals' second derivatives, and
// the averaged centroids sit O(h) away from the vertex on an irregular mesh. On regular grids both cancel
// between mirrored triangles; on a jittered torus or ellipsoid they leave a first-order error (3% at 32
// segments, 0.7% at 128). Here the fit is made per vertex over its triangles' edges from the vertex (the
// one-ring spokes), with the normal field modelled to second order: in the vertex's tangent frame, with x
// the projected offset of a neighbour, the tangential part of its unit normal is
//     n_t(x) = S x + 1/2 C(x, x) + O(|x|^3)
// (Monge patch z = -1/2 x^T S x - 1/6 C(x, x, x): n_t = -grad z to third order), where C is the fully
// symmetric curvature-derivative tensor of Sec. 6, [[[alpha, beta], [beta, gamma]], [[beta, gamma],
// [gamma, delta]]]. Fitting (a, b, c, alpha, beta, gamma, delta) jointly leaves S with an O(h^2) error on any
// triangulation. No rotation of face frames is needed: positions and normals are projected straight into
// the vertex frame, which is exact for the model. Spheres and cylinders with exact normals are reproduced
// to float rounding (n_t = x / R).
//
// Edges at the limits: with fewer than four distinct spokes (valence-3 vertices, corners of open meshes) C is
// not determined; a small ridge on C (relative to its own diagonal, so scale free) then selects C = 0 along
// the undetermined directions and S reduces to the first-order fit. Degenerate triangles are skipped; a
// vertex whose spokes do not span the plane gets no curvature.
//
// Layout for speed: one pass over the curvature groups (parallel, four groups per 4-wide double vector, one
// group per lane). Each group's corners are gathered in corner order into a small structure-of-arrays
// block; the corner weights, the spokes' moments and the 7x7 LDL^T solve then run lane-parallel. Every
// sum runs in a fixed order, so the result does not depend on the thread count.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>

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

// The hot loops are compiled for AVX2 and for the baseline instruction set (mesh/lanes.h).
using namespace lanes;

constexpr int kUnknowns = 7;  // a, b, c, alpha, beta, gamma, delta

// Ridge on the C block, relative to the mean of its diagonal: negligible where the spokes determine C
// (it shifts C by 1e-6 of itself), decisive only along directions the spokes do not see.
constexpr double kRidge = 1e-6;

// Moments of one group's spoke equations, the sums its normal equations are made of:
// m_pq = sum w x^p y^q (p + q = 2..4) of the projected offsets, and mu_pq, mv_pq = sum w n_t.u x^p y^q,
// sum w n_t.v x^p y^q (p + q = 1..2) of the normals' tangential differences, in this order.
enum Moment { m20, m11, m02, m30, m21, m12, m03, m40, m31, m22, m13, m04,
              mu10, mu01, mu20, mu11, mu02, mv10, mv01, mv20, mv11, mv02, kMoments };

// Everything the vertex pass reads, as flat arrays.
struct GatherInput {
    const uint32_t* indices;
    const float* positions;
    const float* unit_normals;
    const uint32_t* start;
    const uint32_t* order;
    const uint32_t* group_vertex;
    const float* normals;  // as authored: the group frame is built from the first vertex's normal
    detail::GroupPrincipal* principal;
};

// Corners of four groups, one group per vector lane: corner c of lane l at [4 c + l], as stored (float
// positions and unit normals of the next and the previous vertex of the triangle, and the corner's own
// unit normal). Groups with more corners than a block holds are summed over several rounds.
constexpr int kSlots = 8;
struct CornerBlock {
    alignas(32) float pa[3][kSlots * kLanes], pb[3][kSlots * kLanes], na[3][kSlots * kLanes],
        nb[3][kSlots * kLanes], n0[3][kSlots * kLanes];
};

typedef float v4f __attribute__((vector_size(16)));
SPECBAKE_INLINE v4d load4(const float* p) {
    v4f f;
    std::memcpy(&f, p, sizeof f);
    return __builtin_convertvector(f, v4d);
}

// Adds one spoke (offset d, normal difference dn, weight w) per lane to the lanes' moments.
SPECBAKE_INLINE void add_spoke(const v4d (&d)[3], const v4d (&dn)[3], v4d w, const v4d (&u)[3], const v4d (&v)[3],
                               v4d (&acc)[kMoments]) {
    const v4d x = d[0] * u[0] + d[1] * u[1] + d[2] * u[2], y = d[0] * v[0] + d[1] * v[1] + d[2] * v[2];
    const v4d du = dn[0] * u[0] + dn[1] * u[1] + dn[2] * u[2], dv = dn[0] * v[0] + dn[1] * v[1] + dn[2] * v[2];
    const v4d wx = w * x, wy = w * y;
    const v4d wx2 = wx * x, wxy = wx * y, wy2 = wy * y;
    acc[m20] += wx2;
    acc[m11] += wxy;
    acc[m02] += wy2;
    acc[m30] += wx2 * x;
    acc[m21] += wx2 * y;
    acc[m12] += wy2 * x;
    acc[m03] += wy2 * y;
    acc[m40] += wx2 * x * x;
    acc[m31] += wx2 * x * y;
    acc[m22] += wx2 * y * y;
    acc[m13] += wy2 * y * x;
    acc[m04] += wy2 * y * y;
    acc[mu10] += wx * du;
    acc[mu01] += wy * du;
    acc[mu20] += wx2 * du;
    acc[mu11] += wxy * du;
    acc[mu02] += wy2 * du;
    acc[mv10] += wx * dv;
    acc[mv01] += wy * dv;
    acc[mv20] += wx2 * dv;
    acc[mv11] += wxy * dv;
    acc[mv02] += wy2 * dv;
}

// Adds the first `slots` corners of every lane to the lanes' moments: each corner's two spokes with the
// corner's mixed-Voronoi area (the branch-free form of detail::mixed_voronoi_areas), zero when the triangle
// carries no information (corners not three distinct positions, or smallest angle under ~1e-10 rad, as
// detail::is_degenerate_triangle). Float differences of nearby values are exact in double, so the fit sees
// the mesh as stored.
SPECBAKE_INLINE void sum_block(const CornerBlock& b, int slots, const v4d (&p0)[3], const v4d (&u)[3],
                               const v4d (&v)[3], v4d (&acc)[kMoments]) {
    for (int s = 0; s < slots * kLanes; s += kLanes) {
        v4d da[3], db[3], dna[3], dnb[3];
        for (int c = 0; c < 3; ++c) {
            const v4d n0 = load4(&b.n0[c][s]);
            da[c] = load4(&b.pa[c][s]) - p0[c];
            db[c] = load4(&b.pb[c][s]) - p0[c];
            dna[c] = load4(&b.na[c][s]) - n0;
            dnb[c] = load4(&b.nb[c][s]) - n0;
        }
        // Squared edges opposite this corner (lo), the next (la) and the previous vertex (lb); twice the area.
        const v4d e[3] = {da[0] - db[0], da[1] - db[1], da[2] - db[2]};
        const v4d lo = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
        const v4d la = db[0] * db[0] + db[1] * db[1] + db[2] * db[2];
        const v4d lb = da[0] * da[0] + da[1] * da[1] + da[2] * da[2];
        const v4d cx = da[1] * db[2] - da[2] * db[1], cy = da[2] * db[0] - da[0] * db[2],
                  cz = da[0] * db[1] - da[1] * db[0];
        const v4d twice_area = sqrt4(cx * cx + cy * cy + cz * cz);
        const v4l usable = twice_area > 1e-10 * (lo + la + lb);
        // Voronoi area (lb cot(angle at b) + la cot(angle at a)) / 8, cot(angle at m) = (sum of the other two
        // squared edges - l_m) / (4 area) = (...) / (2 twice_area); an obtuse corner here takes half the area,
        // an obtuse corner elsewhere leaves a quarter.
        const v4d inv = usable ? 0.5 / twice_area : splat(0.0);
        const v4d cot_a = (lo + lb - la) * inv, cot_b = (lo + la - lb) * inv;
        const v4d voronoi = (lb * cot_b + la * cot_a) / 8.0;
        const v4l obtuse_here = lo > la + lb, obtuse_elsewhere = (la > lo + lb) | (lb > lo + la);
        v4d w = obtuse_here ? 0.25 * twice_area : (obtuse_elsewhere ? 0.125 * twice_area : voronoi);
        w = usable ? w : splat(0.0);
        add_spoke(da, dna, w, u, v, acc);
        add_spoke(db, dnb, w, u, v, acc);
    }
}

// Frames (u, v) and moments of groups first .. first + 3 (lane l: group first + l, lanes past `lanes`
// empty).
SPECBAKE_INLINE void group_moments(const GatherInput& in, uint32_t first, int lanes, CornerBlock& b,
                                   v4d (&u)[3], v4d (&v)[3], v4d (&acc)[kMoments]) {
    v4d p0[3];
    float p0f[3][kLanes];
    uint32_t cursor[kLanes], stop[kLanes];
    for (int l = 0; l < kLanes; ++l) {
        const uint32_t g = first + uint32_t(std::min(l, lanes - 1));
        const size_t first_vertex = in.group_vertex[g];
        const float* p = &in.positions[3 * first_vertex];
        detail::Vec3d n, fu, fv;
        detail::group_frame(&in.normals[3 * first_vertex], n, fu, fv);
        for (int c = 0; c < 3; ++c) {
            p0f[c][l] = p[c];
            p0[c][l] = p[c];
            u[c][l] = fu[c];
            v[c][l] = fv[c];
        }
        cursor[l] = in.start[g];
        stop[l] = l < lanes ? in.start[g + 1] : in.start[g];
    }
    for (int q = 0; q < kMoments; ++q) acc[q] = splat(0.0);
    for (;;) {
        int filled[kLanes], most = 0;
        for (int l = 0; l < kLanes; ++l) {
            int s = 0;
            for (; cursor[l] < stop[l] && s < kSlots; ++s) {
                const uint32_t corner = in.order[cursor[l]++];
                const uint32_t t = corner / 3, i = corner - 3 * t;
                const uint32_t* f = &in.indices[3 * size_t(t)];
                const size_t a = 3 * size_t(f[i == 2 ? 0 : i + 1]), bv = 3 * size_t(f[i == 0 ? 2 : i - 1]),
                             o = 3 * size_t(f[i]);
                const float *pa = &in.positions[a], *pb = &in.positions[bv];
                const float *na = &in.unit_normals[a], *nb = &in.unit_normals[bv], *n0 = &in.unit_normals[o];
                const int at = s * kLanes + l;
                b.pa[0][at] = pa[0], b.pa[1][at] = pa[1], b.pa[2][at] = pa[2];
                b.pb[0][at] = pb[0], b.pb[1][at] = pb[1], b.pb[2][at] = pb[2];
                b.na[0][at] = na[0], b.na[1][at] = na[1], b.na[2][at] = na[2];
                b.nb[0][at] = nb[0], b.nb[1][at] = nb[1], b.nb[2][at] = nb[2];
                b.n0[0][at] = n0[0], b.n0[1][at] = n0[1], b.n0[2][at] = n0[2];
            }
            filled[l] = s;
            most = std::max(most, s);
        }
        if (most == 0) break;
        for (int l = 0; l < kLanes; ++l)
            for (int pad = filled[l]; pad < most; ++pad) {  // a degenerate corner at the group's position: weight 0
                const int at = pad * kLanes + l;
                for (int c = 0; c < 3; ++c) {
                    b.pa[c][at] = b.pb[c][at] = p0f[c][l];
                    b.na[c][at] = b.nb[c][at] = b.n0[c][at] = 0.0f;
                }
            }
        sum_block(b, most, p0, u, v, acc);
    }
}

// Normal equations of the model rows r_u = (x, y, 0, x^2/2, xy, y^2/2, 0) and r_v = (0, x, y, 0, x^2/2, xy,
// y^2/2) for the unknowns z = (a, b, c, alpha, beta, gamma, delta): M = sum w (r_u r_u^T + r_v r_v^T)
// (lower triangle) and r = sum w (r_u du + r_v dv), from the moments s (a vector of lanes or one double).
template <class T>
SPECBAKE_INLINE void normal_equations(const T (&s)[kMoments], T (&M)[kUnknowns][kUnknowns], T (&r)[kUnknowns]) {
    const T zero = s[m20] * 0.0;
    M[0][0] = s[m20];
    M[1][0] = s[m11];
    M[1][1] = s[m02] + s[m20];
    M[2][0] = zero;
    M[2][1] = s[m11];
    M[2][2] = s[m02];
    M[3][0] = 0.5 * s[m30];
    M[3][1] = 0.5 * s[m21];
    M[3][2] = zero;
    M[3][3] = 0.25 * s[m40];
    M[4][0] = s[m21];
    M[4][1] = s[m12] + 0.5 * s[m30];
    M[4][2] = 0.5 * s[m21];
    M[4][3] = 0.5 * s[m31];
    M[4][4] = s[m22] + 0.25 * s[m40];
    M[5][0] = 0.5 * s[m12];
    M[5][1] = 0.5 * s[m03] + s[m21];
    M[5][2] = s[m12];
    M[5][3] = 0.25 * s[m22];
    M[5][4] = 0.5 * (s[m13] + s[m31]);
    M[5][5] = 0.25 * s[m04] + s[m22];
    M[6][0] = zero;
    M[6][1] = 0.5 * s[m12];
    M[6][2] = 0.5 * s[m03];
    M[6][3] = zero;
    M[6][4] = 0.25 * s[m22];
    M[6][5] = 0.5 * s[m13];
    M[6][6] = 0.25 * s[m04];
    r[0] = s[mu10];
    r[1] = s[mu01] + s[mv10];
    r[2] = s[mv01];
    r[3] = 0.5 * s[mu20];
    r[4] = s[mu11] + 0.5 * s[mv20];
    r[5] = 0.5 * s[mu02] + s[mv11];
    r[6] = 0.5 * s[mv02];
}

// LDL^T solve of the first n unknowns of M z = r (lower triangle of M; z holds r on entry), lane-parallel,
// fully unrolled; ok keeps the lanes whose pivots all exceed 1e-12 of their diagonal entries (the others'
// results are meaningless).
template <int n, class T, class Mask>
SPECBAKE_INLINE void ldlt_solve(const T (&M)[kUnknowns][kUnknowns], T (&z)[kUnknowns], Mask& ok) {
    T L[kUnknowns][kUnknowns], d[kUnknowns], inv_d[kUnknowns];
#pragma GCC unroll 7
    for (int j = 0; j < n; ++j) {
        T dj = M[j][j];
#pragma GCC unroll 7
        for (int k = 0; k < j; ++k) dj -= L[j][k] * L[j][k] * d[k];
        const auto pivot = dj > 1e-12 * M[j][j];
        ok = ok & pivot;
        d[j] = dj;
        inv_d[j] = pivot ? 1.0 / dj : dj * 0.0;
#pragma GCC unroll 7
        for (int i = j + 1; i < n; ++i) {
            T x = M[i][j];
#pragma GCC unroll 7
            for (int k = 0; k < j; ++k) x -= L[i][k] * L[j][k] * d[k];
            L[i][j] = x * inv_d[j];
        }
    }
#pragma GCC unroll 7
    for (int i = 0; i < n; ++i) {
#pragma GCC unroll 7
        for (int k = 0; k < i; ++k) z[i] -= L[i][k] * z[k];
    }
#pragma GCC unroll 7
    for (int i = 0; i < n; ++i) z[i] *= inv_d[i];
#pragma GCC unroll 7
    for (int i = n - 1; i >= 0; --i) {
#pragma GCC unroll 7
        for (int k = i + 1; k < n; ++k) z[i] -= L[k][i] * z[k];
    }
}

// S of `lanes` groups from their moments (lane l): the full model with the ridge on the C block;
// a lane whose system is not numerically positive definite falls back to the linear model (S alone), and
// to no curvature when even that fails (the spokes do not span the plane).
SPECBAKE_INLINE void solve_shapes(const v4d (&s)[kMoments], int lanes, Shape2* out) {
    v4d M[kUnknowns][kUnknowns], z[kUnknowns];
    normal_equations(s, M, z);
    const v4d ridge = kRidge * (M[3][3] + M[4][4] + M[5][5] + M[6][6]) / double(kUnknowns - 3);
    for (int i = 3; i < kUnknowns; ++i) M[i][i] += ridge;
    v4l ok = {-1, -1, -1, -1};
    ldlt_solve<kUnknowns>(M, z, ok);

    for (int l = 0; l < lanes; ++l) {
        out[l] = {};
        double S[3] = {z[0][l], z[1][l], z[2][l]};
        if (!ok[l]) {
            double sl[kMoments], Ml[kUnknowns][kUnknowns], zl[kUnknowns];
            for (int q = 0; q < kMoments; ++q) sl[q] = s[q][l];
            normal_equations(sl, Ml, zl);
            bool fine = true;
            ldlt_solve<3>(Ml, zl, fine);
            if (!fine) continue;
            for (int i = 0; i < 3; ++i) S[i] = zl[i];
        }
        if (std::isfinite(S[0]) && std::isfinite(S[1]) && std::isfinite(S[2])) out[l] = {S[0], S[1], S[2]};
    }
}

// The fit of groups [begin, end), four at a time, and their principal curvatures.
SPECBAKE_AVX2_CLONES void fit_groups(const GatherInput& in, uint32_t begin, uint32_t end) {
    CornerBlock block;
    for (uint32_t first = begin; first < end; first += kLanes) {
        const int lanes = int(std::min<uint32_t>(kLanes, end - first));
        v4d u[3], v[3], moments[kMoments];
        group_moments(in, first, lanes, block, u, v, moments);
        Shape2 shape[kLanes];
        solve_shapes(moments, lanes, shape);
        for (int l = 0; l < lanes; ++l)
            in.principal[first + uint32_t(l)] = detail::principal_curvatures(
                shape[l], detail::Vec3d(u[0][l], u[1][l], u[2][l]), detail::Vec3d(v[0][l], v[1][l], v[2][l]));
    }
}

}  // namespace

VertexCurvature curvature_second_order(const TriMesh& mesh, const WeldedTopology& topology) {
    const size_t verts = mesh.vertex_count();
    detail::ScratchArray<float> unit_normals(3 * verts);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, verts, 8192), [&](const auto& range) {
        for (size_t v = range.begin(); v != range.end(); ++v) {
            const float* n = &mesh.normals[3 * v];
            const double len = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
            const double inv = len > 0.0 ? 1.0 / len : 0.0;
            for (int k = 0; k < 3; ++k) unit_normals[3 * v + k] = float(n[k] * inv);
        }
    });

    const uint32_t groups = topology.group_count;
    const detail::GroupCorners lists = detail::group_corners(mesh, topology);
    detail::ScratchArray<detail::GroupPrincipal> principal(groups);
    const GatherInput input{mesh.indices.data(), mesh.positions.data(), unit_normals.data(), lists.start.data(),
                            lists.order.data(), topology.group_vertex.data(), mesh.normals.data(),
                            principal.data()};
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, groups, 2048),
                      [&](const auto& range) { fit_groups(input, range.begin(), range.end()); });
    return detail::vertex_curvature_from_principal(mesh, topology, principal.data());
}

}  // namespace specbake
