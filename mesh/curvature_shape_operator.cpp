// Default estimator, after Rusinkiewicz, "Estimating Curvatures and Their Derivatives on Triangle Meshes",
// 3DPVT 2004. The 2x2 shape operator S (second fundamental form) is the least-squares solution of
// S * e = dn for the edges e of the triangles around a vertex and the differences dn of the vertex normals
// along them, both in a (u, v) tangent frame (Sec. 3, Eq. 2-3); S is symmetric, so the unknowns are (a, b, c)
// of [[a, b], [b, c]], and each triangle counts with its corner's mixed-Voronoi area (Sec. 4-5).
//
// Second order on irregular meshes. Rusinkiewicz fits S per face and averages the face operators at the
// vertices. A face's fit is the gradient of the linear interpolant of the normals: it is exact at the
// face's centroid only up to O(h) terms in the normals' second derivatives, and the averaged centroids sit
// O(h) away from the vertex on an irregular mesh. On regular grids both cancel between mirrored triangles;
// on a jittered torus or ellipsoid they leave a first-order error (3% at 32 segments, 0.7% at 128). Here the
// fit is made per vertex over its triangles' edges from the vertex (the one-ring spokes), with the normal
// field modelled to second order: in the vertex's tangent frame, with x the projected offset of a
// neighbour, the tangential part of its unit normal is
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
// Layout for speed: a face pass (parallel, no allocation) writes the mixed-Voronoi weight of every corner,
// zero for skipped triangles; a vertex pass gathers each curvature group's corners in corner order, so the
// sums and the result do not depend on the thread count.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "mesh/curvature.h"
#include "mesh/curvature_frames.h"
#include "mesh/scratch_array.h"

namespace specbake {
namespace {

using detail::Shape2;

// The hot functions are compiled twice, for AVX2 + FMA and for the baseline instruction set, and chosen once
// at load time (GCC/Clang function multiversioning); their helpers are inlined into each version.
#if defined(__GNUC__) && defined(__x86_64__) && defined(__linux__)
#define SPECBAKE_AVX2_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#define SPECBAKE_INLINE __attribute__((always_inline)) inline
#else
#define SPECBAKE_AVX2_CLONES
#define SPECBAKE_INLINE inline
#endif

constexpr int kUnknowns = 7;  // a, b, c, alpha, beta, gamma, delta

// Ridge on the C block, relative to the mean of its diagonal: negligible where the spokes determine C
// (it shifts C by 1e-6 of itself), decisive only along directions the spokes do not see.
constexpr double kRidge = 1e-6;

// Mixed-Voronoi weights of the corners of triangle t; zeros when it carries no information (corners not
// three distinct positions, or smallest angle under ~1e-10 rad, as detail::is_degenerate_triangle).
SPECBAKE_AVX2_CLONES void corner_weights(const TriMesh& mesh, const WeldedTopology& topology, size_t t, float out[3]) {
    const uint32_t* f = &mesh.indices[3 * t];
    out[0] = out[1] = out[2] = 0.0f;
    const uint32_t* pid = topology.position_id.data();
    if (pid[f[0]] == pid[f[1]] || pid[f[1]] == pid[f[2]] || pid[f[0]] == pid[f[2]]) return;
    double p[3][3];
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) p[i][k] = mesh.positions[3 * size_t(f[i]) + k];
    double e[3][3];
    for (int k = 0; k < 3; ++k) {
        e[0][k] = p[2][k] - p[1][k];  // e_i opposite corner i
        e[1][k] = p[0][k] - p[2][k];
        e[2][k] = p[1][k] - p[0][k];
    }
    const double cr[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                          e[0][0] * e[1][1] - e[0][1] * e[1][0]};
    double l[3];
    for (int i = 0; i < 3; ++i) l[i] = e[i][0] * e[i][0] + e[i][1] * e[i][1] + e[i][2] * e[i][2];
    const double twice_area = std::sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
    if (!(twice_area > 1e-10 * (l[0] + l[1] + l[2]))) return;
    double w[3];
    detail::mixed_voronoi_areas(l[0], l[1], l[2], 0.5 * twice_area, w);
    for (int i = 0; i < 3; ++i) out[i] = float(w[i]);
}

// Weighted sums of one vertex's spoke equations, the moments the normal equations are made of:
// m_pq = sum w x^p y^q (p + q = 2..4) of the projected offsets, and mu_pq, mv_pq = sum w n_t.u x^p y^q,
// sum w n_t.v x^p y^q (p + q = 1..2) of the normals' tangential differences.
struct SpokeMoments {
    double m20, m11, m02, m30, m21, m12, m03, m40, m31, m22, m13, m04;
    double mu10, mu01, mu20, mu11, mu02, mv10, mv01, mv20, mv11, mv02;
};

// In-place Cholesky solve of the symmetric positive definite system M z = r (lower triangle of M used);
// false when a pivot falls below 1e-12 of its diagonal entry.
template <int N>
bool cholesky_solve(double (&M)[kUnknowns][kUnknowns], double (&r)[kUnknowns]) {
#pragma GCC unroll 7
    for (int j = 0; j < N; ++j) {
        double d = M[j][j];
        for (int k = 0; k < j; ++k) d -= M[j][k] * M[j][k];
        if (!(d > 1e-12 * M[j][j])) return false;
        const double s = std::sqrt(d), inv = 1.0 / s;
        M[j][j] = s;
#pragma GCC unroll 7
        for (int i = j + 1; i < N; ++i) {
            double v = M[i][j];
            for (int k = 0; k < j; ++k) v -= M[i][k] * M[j][k];
            M[i][j] = v * inv;
        }
    }
#pragma GCC unroll 7
    for (int i = 0; i < N; ++i) {
        double v = r[i];
        for (int k = 0; k < i; ++k) v -= M[i][k] * r[k];
        r[i] = v / M[i][i];
    }
#pragma GCC unroll 7
    for (int i = N - 1; i >= 0; --i) {
        double v = r[i];
        for (int k = i + 1; k < N; ++k) v -= M[k][i] * r[k];
        r[i] = v / M[i][i];
    }
    return true;
}

// Normal equations of the model rows r_u = (x, y, 0, x^2/2, xy, y^2/2, 0) and r_v = (0, x, y, 0, x^2/2, xy,
// y^2/2) for the unknowns z = (a, b, c, alpha, beta, gamma, delta): M = sum w (r_u r_u^T + r_v r_v^T)
// and r = sum w (r_u du + r_v dv), from the moments; lower triangle of M in lane l.
template <int Lanes>
SPECBAKE_INLINE void normal_equations(const SpokeMoments& s, double (&M)[7][7][Lanes], double (&r)[7][Lanes], int l) {
    M[0][0][l] = s.m20;
    M[1][0][l] = s.m11;
    M[1][1][l] = s.m02 + s.m20;
    M[2][0][l] = 0.0;
    M[2][1][l] = s.m11;
    M[2][2][l] = s.m02;
    M[3][0][l] = 0.5 * s.m30;
    M[3][1][l] = 0.5 * s.m21;
    M[3][2][l] = 0.0;
    M[3][3][l] = 0.25 * s.m40;
    M[4][0][l] = s.m21;
    M[4][1][l] = s.m12 + 0.5 * s.m30;
    M[4][2][l] = 0.5 * s.m21;
    M[4][3][l] = 0.5 * s.m31;
    M[4][4][l] = s.m22 + 0.25 * s.m40;
    M[5][0][l] = 0.5 * s.m12;
    M[5][1][l] = 0.5 * s.m03 + s.m21;
    M[5][2][l] = s.m12;
    M[5][3][l] = 0.25 * s.m22;
    M[5][4][l] = 0.5 * (s.m13 + s.m31);
    M[5][5][l] = 0.25 * s.m04 + s.m22;
    M[6][0][l] = 0.0;
    M[6][1][l] = 0.5 * s.m12;
    M[6][2][l] = 0.5 * s.m03;
    M[6][3][l] = 0.0;
    M[6][4][l] = 0.25 * s.m22;
    M[6][5][l] = 0.5 * s.m13;
    M[6][6][l] = 0.25 * s.m04;
    r[0][l] = s.mu10;
    r[1][l] = s.mu01 + s.mv10;
    r[2][l] = s.mv01;
    r[3][l] = 0.5 * s.mu20;
    r[4][l] = s.mu11 + 0.5 * s.mv20;
    r[5][l] = 0.5 * s.mu02 + s.mv11;
    r[6][l] = 0.5 * s.mv02;
}

// Groups are solved in batches, lane by lane in lockstep, so the divisions of the factorisations overlap
// (and vectorise) instead of forming one long dependency chain per group.
constexpr int kBatch = 4;

// S of up to kBatch groups: LDL^T solve of the normal equations with the ridge on the C block; a lane whose
// system is not numerically positive definite falls back to the linear model (S alone), and to no
// curvature when even that fails (the spokes do not span the plane).
SPECBAKE_INLINE void solve_shapes(const SpokeMoments (&s)[kBatch], const bool (&any)[kBatch], int lanes, Shape2* out) {
    double M[kUnknowns][kUnknowns][kBatch], r[kUnknowns][kBatch];
    for (int l = 0; l < kBatch; ++l) {
        normal_equations(s[l], M, r, l);
        const double ridge = kRidge * (M[3][3][l] + M[4][4][l] + M[5][5][l] + M[6][6][l]) / (kUnknowns - 3);
        for (int i = 3; i < kUnknowns; ++i) M[i][i][l] += ridge;
    }

    double L[kUnknowns][kUnknowns][kBatch], inv_d[kUnknowns][kBatch], d[kUnknowns][kBatch];
    bool ok[kBatch] = {true, true, true, true};
    for (int j = 0; j < kUnknowns; ++j) {
        for (int l = 0; l < kBatch; ++l) {
            double dj = M[j][j][l];
            for (int k = 0; k < j; ++k) dj -= L[j][k][l] * L[j][k][l] * d[k][l];
            const bool pivot = dj > 1e-12 * M[j][j][l];
            ok[l] = ok[l] && pivot;
            d[j][l] = dj;
            inv_d[j][l] = pivot ? 1.0 / dj : 0.0;
        }
        for (int i = j + 1; i < kUnknowns; ++i)
            for (int l = 0; l < kBatch; ++l) {
                double v = M[i][j][l];
                for (int k = 0; k < j; ++k) v -= L[i][k][l] * L[j][k][l] * d[k][l];
                L[i][j][l] = v * inv_d[j][l];
            }
    }
    double z[kUnknowns][kBatch];
    for (int i = 0; i < kUnknowns; ++i)
        for (int l = 0; l < kBatch; ++l) {
            double v = r[i][l];
            for (int k = 0; k < i; ++k) v -= L[i][k][l] * z[k][l];
            z[i][l] = v;
        }
    for (int i = 0; i < kUnknowns; ++i)
        for (int l = 0; l < kBatch; ++l) z[i][l] *= inv_d[i][l];
    for (int i = kUnknowns - 1; i >= 0; --i)
        for (int l = 0; l < kBatch; ++l) {
            double v = z[i][l];
            for (int k = i + 1; k < kUnknowns; ++k) v -= L[k][i][l] * z[k][l];
            z[i][l] = v;
        }

    for (int l = 0; l < lanes; ++l) {
        out[l] = {};
        if (!any[l]) continue;
        double S[3] = {z[0][l], z[1][l], z[2][l]};
        if (!ok[l]) {
            double Ml[kUnknowns][kUnknowns][1], rl[kUnknowns][1];
            normal_equations(s[l], Ml, rl, 0);
            double M3[kUnknowns][kUnknowns], r3[kUnknowns];
            for (int i = 0; i < 3; ++i) {
                for (int j = 0; j <= i; ++j) M3[i][j] = Ml[i][j][0];
                r3[i] = rl[i][0];
            }
            if (!cholesky_solve<3>(M3, r3)) continue;
            for (int i = 0; i < 3; ++i) S[i] = r3[i];
        }
        if (std::isfinite(S[0]) && std::isfinite(S[1]) && std::isfinite(S[2])) out[l] = {S[0], S[1], S[2]};
    }
}

// Everything one curvature group's fit reads, as flat arrays.
struct GatherInput {
    const uint32_t* indices;
    const float* positions;
    const float* unit_normals;
    const float* weight;  // per corner
    const uint32_t* start;
    const uint32_t* order;
    const detail::GroupFrames* frames;
    Shape2* shape;
};

// A group's spokes in structure-of-arrays form, summed four at a time in four independent lanes (each lane
// in a fixed order, then the lanes in a fixed order: the same sums for any thread count), which the
// compiler turns into one 4-wide vector operation per moment.
constexpr int kLanes = 4;
constexpr int kSpokeBlock = 64;
struct SpokeBlock {
    alignas(32) double x[kSpokeBlock], y[kSpokeBlock], du[kSpokeBlock], dv[kSpokeBlock], w[kSpokeBlock];
    int n = 0;
};
constexpr int kMoments = 22;

SPECBAKE_INLINE void sum_block(SpokeBlock& b, double (&acc)[kMoments][kLanes]) {
    while (b.n % kLanes != 0) {
        b.x[b.n] = b.y[b.n] = b.du[b.n] = b.dv[b.n] = b.w[b.n] = 0.0;
        ++b.n;
    }
    for (int s = 0; s < b.n; s += kLanes) {
        for (int l = 0; l < kLanes; ++l) {
            const double x = b.x[s + l], y = b.y[s + l], du = b.du[s + l], dv = b.dv[s + l];
            const double wx = b.w[s + l] * x, wy = b.w[s + l] * y;
            const double wx2 = wx * x, wxy = wx * y, wy2 = wy * y;
            acc[0][l] += wx2;
            acc[1][l] += wxy;
            acc[2][l] += wy2;
            acc[3][l] += wx2 * x;
            acc[4][l] += wx2 * y;
            acc[5][l] += wy2 * x;
            acc[6][l] += wy2 * y;
            acc[7][l] += wx2 * x * x;
            acc[8][l] += wx2 * x * y;
            acc[9][l] += wx2 * y * y;
            acc[10][l] += wy2 * y * x;
            acc[11][l] += wy2 * y * y;
            acc[12][l] += wx * du;
            acc[13][l] += wy * du;
            acc[14][l] += wx2 * du;
            acc[15][l] += wxy * du;
            acc[16][l] += wy2 * du;
            acc[17][l] += wx * dv;
            acc[18][l] += wy * dv;
            acc[19][l] += wx2 * dv;
            acc[20][l] += wxy * dv;
            acc[21][l] += wy2 * dv;
        }
    }
    b.n = 0;
}

// The moments of group g's spokes; false when it has no usable triangle.
SPECBAKE_INLINE bool group_moments(const GatherInput& in, uint32_t g, SpokeBlock& b, SpokeMoments& out) {
    const double* u = in.frames->u[g].data();
    const double* v = in.frames->v[g].data();
    double acc[kMoments][kLanes] = {};
    bool any = false;
    for (uint32_t k = in.start[g]; k < in.start[g + 1]; ++k) {
        const uint32_t corner = in.order[k];
        const double w = in.weight[corner];
        if (!(w > 0.0)) continue;
        any = true;
        const uint32_t* f = &in.indices[corner - corner % 3];
        const int i = int(corner % 3);
        const float* p0 = &in.positions[3 * size_t(f[i])];
        const float* n0 = &in.unit_normals[3 * size_t(f[i])];
        const double nu0 = n0[0] * u[0] + n0[1] * u[1] + n0[2] * u[2];
        const double nv0 = n0[0] * v[0] + n0[1] * v[1] + n0[2] * v[2];
        if (b.n + 2 > kSpokeBlock) sum_block(b, acc);
        for (int o = 1; o <= 2; ++o) {
            const size_t j = f[(i + o) % 3];
            const float* pj = &in.positions[3 * j];
            const float* nj = &in.unit_normals[3 * j];
            // Float differences of nearby positions are exact in double: the fit sees the mesh as stored.
            const double d[3] = {double(pj[0]) - p0[0], double(pj[1]) - p0[1], double(pj[2]) - p0[2]};
            b.x[b.n] = d[0] * u[0] + d[1] * u[1] + d[2] * u[2];
            b.y[b.n] = d[0] * v[0] + d[1] * v[1] + d[2] * v[2];
            b.du[b.n] = nj[0] * u[0] + nj[1] * u[1] + nj[2] * u[2] - nu0;
            b.dv[b.n] = nj[0] * v[0] + nj[1] * v[1] + nj[2] * v[2] - nv0;
            b.w[b.n] = w;
            ++b.n;
        }
    }
    sum_block(b, acc);
    double m[kMoments];
    for (int q = 0; q < kMoments; ++q) m[q] = (acc[q][0] + acc[q][1]) + (acc[q][2] + acc[q][3]);
    out = {m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8], m[9], m[10], m[11],
           m[12], m[13], m[14], m[15], m[16], m[17], m[18], m[19], m[20], m[21]};
    return any;
}

// The fit of groups [begin, end).
SPECBAKE_AVX2_CLONES void fit_groups(const GatherInput& in, uint32_t begin, uint32_t end) {
    SpokeBlock block;
    for (uint32_t first = begin; first < end; first += kBatch) {
        const int lanes = int(std::min<uint32_t>(kBatch, end - first));
        SpokeMoments moments[kBatch];
        bool any[kBatch] = {};  // lanes past `lanes` repeat the first group's (valid) system, unused
        for (int l = 0; l < lanes; ++l) any[l] = group_moments(in, first + uint32_t(l), block, moments[l]);
        for (int l = lanes; l < kBatch; ++l) moments[l] = moments[0];
        solve_shapes(moments, any, lanes, &in.shape[first]);
    }
}

}  // namespace

VertexCurvature curvature_shape_operator(const TriMesh& mesh, const WeldedTopology& topology) {
    const detail::GroupFrames frames = detail::make_group_frames(mesh, topology);
    const size_t tris = mesh.triangle_count(), verts = mesh.vertex_count();
    detail::ScratchArray<float> weight(3 * tris), unit_normals(3 * verts);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, tris, 8192), [&](const auto& range) {
        for (size_t t = range.begin(); t != range.end(); ++t) corner_weights(mesh, topology, t, &weight[3 * t]);
    });
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
    std::vector<Shape2> shape(groups);
    const GatherInput input{mesh.indices.data(), mesh.positions.data(), unit_normals.data(), weight.data(),
                            lists.start.data(), lists.order.data(), &frames, shape.data()};
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, groups, 2048),
                      [&](const auto& range) { fit_groups(input, range.begin(), range.end()); });
    return detail::vertex_curvature_from_groups(mesh, topology, frames, shape);
}

}  // namespace specbake
