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

#include <cmath>

#include "mesh/curvature.h"
#include "mesh/curvature_frames.h"
#include "mesh/scratch_array.h"

namespace specbake {
namespace {

using detail::Shape2;

constexpr int kUnknowns = 7;  // a, b, c, alpha, beta, gamma, delta

// Ridge on the C block, relative to the mean of its diagonal: negligible where the spokes determine C
// (it shifts C by 1e-6 of itself), decisive only along directions the spokes do not see.
constexpr double kRidge = 1e-6;

// Mixed-Voronoi weights of the corners of triangle t; zeros when it carries no information (corners not
// three distinct positions, or smallest angle under ~1e-10 rad, as detail::is_degenerate_triangle).
void corner_weights(const TriMesh& mesh, const WeldedTopology& topology, size_t t, float out[3]) {
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

// Weighted sums of one vertex's spoke equations: moments m[p][q] = sum w x^p y^q (p + q = 2..4) of the
// projected offsets and mu/mv[p][q] = sum w n_t.u x^p y^q, sum w n_t.v x^p y^q (p + q = 1..2).
struct SpokeMoments {
    double m[5][5] = {};
    double mu[3][3] = {};
    double mv[3][3] = {};

    void add(double w, double x, double y, double du, double dv) {
        const double x2 = x * x, xy = x * y, y2 = y * y;
        m[2][0] += w * x2;
        m[1][1] += w * xy;
        m[0][2] += w * y2;
        m[3][0] += w * x2 * x;
        m[2][1] += w * x2 * y;
        m[1][2] += w * x * y2;
        m[0][3] += w * y2 * y;
        m[4][0] += w * x2 * x2;
        m[3][1] += w * x2 * xy;
        m[2][2] += w * x2 * y2;
        m[1][3] += w * xy * y2;
        m[0][4] += w * y2 * y2;
        const double wu = w * du, wv = w * dv;
        mu[1][0] += wu * x;
        mu[0][1] += wu * y;
        mu[2][0] += wu * x2;
        mu[1][1] += wu * xy;
        mu[0][2] += wu * y2;
        mv[1][0] += wv * x;
        mv[0][1] += wv * y;
        mv[2][0] += wv * x2;
        mv[1][1] += wv * xy;
        mv[0][2] += wv * y2;
    }
};

// Row of the model for the u and the v component of n_t: coefficient times x^px y^py per unknown.
struct Term {
    double coef;
    int px, py;
};
constexpr Term kRowU[kUnknowns] = {{1, 1, 0}, {1, 0, 1}, {0, 0, 0}, {0.5, 2, 0}, {1, 1, 1}, {0.5, 0, 2}, {0, 0, 0}};
constexpr Term kRowV[kUnknowns] = {{0, 0, 0}, {1, 1, 0}, {1, 0, 1}, {0, 0, 0}, {0.5, 2, 0}, {1, 1, 1}, {0.5, 0, 2}};

// In-place Cholesky solve of the symmetric system M z = r of size n; false when M is not numerically
// positive definite (a pivot below 1e-12 of its diagonal entry).
bool cholesky_solve(double M[kUnknowns][kUnknowns], double r[kUnknowns], int n) {
    for (int j = 0; j < n; ++j) {
        double d = M[j][j];
        for (int k = 0; k < j; ++k) d -= M[j][k] * M[j][k];
        if (!(d > 1e-12 * M[j][j])) return false;
        const double s = std::sqrt(d);
        M[j][j] = s;
        for (int i = j + 1; i < n; ++i) {
            double v = M[i][j];
            for (int k = 0; k < j; ++k) v -= M[i][k] * M[j][k];
            M[i][j] = v / s;
        }
    }
    for (int i = 0; i < n; ++i) {
        double v = r[i];
        for (int k = 0; k < i; ++k) v -= M[i][k] * r[k];
        r[i] = v / M[i][i];
    }
    for (int i = n - 1; i >= 0; --i) {
        double v = r[i];
        for (int k = i + 1; k < n; ++k) v -= M[k][i] * r[k];
        r[i] = v / M[i][i];
    }
    return true;
}

// S from the moments: the normal equations of the model, with the ridge on the C block; falls back to the
// linear model (S alone) when even that fails, and to no curvature when the spokes do not span the plane.
bool solve_shape(const SpokeMoments& s, Shape2& out) {
    double M[kUnknowns][kUnknowns], r[kUnknowns];
    for (int i = 0; i < kUnknowns; ++i) {
        r[i] = kRowU[i].coef * s.mu[kRowU[i].px][kRowU[i].py] + kRowV[i].coef * s.mv[kRowV[i].px][kRowV[i].py];
        for (int j = 0; j < kUnknowns; ++j)
            M[i][j] = kRowU[i].coef * kRowU[j].coef * s.m[kRowU[i].px + kRowU[j].px][kRowU[i].py + kRowU[j].py] +
                      kRowV[i].coef * kRowV[j].coef * s.m[kRowV[i].px + kRowV[j].px][kRowV[i].py + kRowV[j].py];
    }
    double diag = 0.0;
    for (int i = 3; i < kUnknowns; ++i) diag += M[i][i];
    const double ridge = kRidge * diag / (kUnknowns - 3);
    for (int i = 3; i < kUnknowns; ++i) M[i][i] += ridge;
    double L[kUnknowns][kUnknowns], z[kUnknowns];
    std::copy(&M[0][0], &M[0][0] + kUnknowns * kUnknowns, &L[0][0]);
    std::copy(r, r + kUnknowns, z);
    if (!cholesky_solve(L, z, kUnknowns)) {
        std::copy(r, r + 3, z);
        if (!cholesky_solve(M, z, 3)) return false;
    }
    out = {z[0], z[1], z[2]};
    return std::isfinite(z[0]) && std::isfinite(z[1]) && std::isfinite(z[2]);
}

}  // namespace

VertexCurvature curvature_shape_operator(const TriMesh& mesh, const WeldedTopology& topology) {
    const detail::GroupFrames frames = detail::make_group_frames(mesh, topology);
    const size_t tris = mesh.triangle_count();
    detail::ScratchArray<float> weight(3 * tris);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, tris, 4096), [&](const auto& range) {
        for (size_t t = range.begin(); t != range.end(); ++t) corner_weights(mesh, topology, t, &weight[3 * t]);
    });

    const uint32_t groups = topology.group_count;
    const detail::GroupCorners lists = detail::group_corners(mesh, topology);
    std::vector<Shape2> shape(groups);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, groups, 1024), [&](const auto& range) {
        for (uint32_t g = range.begin(); g != range.end(); ++g) {
            const double* u = frames.u[g].data();
            const double* v = frames.v[g].data();
            SpokeMoments moments;
            bool any = false;
            for (uint32_t k = lists.start[g]; k < lists.start[g + 1]; ++k) {
                const uint32_t corner = lists.order[k];
                const double w = weight[corner];
                if (!(w > 0.0)) continue;
                any = true;
                const uint32_t* f = &mesh.indices[corner - corner % 3];
                const int i = int(corner % 3);
                const float* p0 = &mesh.positions[3 * size_t(f[i])];
                const Eigen::Vector3d n0 = detail::normal(mesh, f[i]).normalized();
                for (int o = 1; o <= 2; ++o) {
                    const uint32_t j = f[(i + o) % 3];
                    const float* pj = &mesh.positions[3 * size_t(j)];
                    const double d[3] = {double(pj[0]) - p0[0], double(pj[1]) - p0[1], double(pj[2]) - p0[2]};
                    const Eigen::Vector3d dn = detail::normal(mesh, j).normalized() - n0;
                    moments.add(w, d[0] * u[0] + d[1] * u[1] + d[2] * u[2], d[0] * v[0] + d[1] * v[1] + d[2] * v[2],
                                dn[0] * u[0] + dn[1] * u[1] + dn[2] * u[2], dn[0] * v[0] + dn[1] * v[1] + dn[2] * v[2]);
                }
            }
            if (any && !solve_shape(moments, shape[g])) shape[g] = {};
        }
    });
    return detail::vertex_curvature_from_groups(mesh, topology, frames, shape);
}

}  // namespace specbake
