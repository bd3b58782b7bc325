// Default estimator: Rusinkiewicz, "Estimating Curvatures and Their Derivatives on Triangle Meshes",
// 3DPVT 2004. Per face, the 2x2 shape operator S (second fundamental form) is the least-squares solution of
// S * e_i = dn_i for the three edges e_i and the differences dn_i of the vertex normals along them, both in
// the face's (u, v) frame (Sec. 3, Eq. 2-3). S is symmetric, so the unknowns are (a, b, c) of [[a, b], [b, c]]
// and the normal equations form a full 3x3 system that is solved as such. Each face's S is rotated into the
// frame of each corner's curvature group and accumulated with the corner's mixed-Voronoi area (Sec. 4-5),
// then normalised by the summed area.
#include <tbb/parallel_for.h>

#include <Eigen/Cholesky>

#include "mesh/curvature.h"
#include "mesh/curvature_frames.h"

namespace specbake {
namespace {

using detail::Shape2;
using detail::Vec3d;

// Rotates the frame (u, v) of a plane with normal n_from about n_from x n_to so that it lies in the plane of
// n_to (Rusinkiewicz 2004 Sec. 4; both normals unit length).
void rotate_frame(Vec3d& u, Vec3d& v, const Vec3d& n_from, const Vec3d& n_to) {
    const double ndot = n_from.dot(n_to);
    if (ndot <= -1.0) {
        u = -u;
        v = -v;
        return;
    }
    const Vec3d perp_from = n_to - ndot * n_from;
    const Vec3d dperp = (n_from + n_to) / (1.0 + ndot);
    u -= dperp * u.dot(perp_from);
    v -= dperp * v.dot(perp_from);
}

// Weighted operator of one corner, expressed in its group's (u, v) frame.
struct CornerShape {
    double a = 0.0, b = 0.0, c = 0.0, weight = 0.0;
};

}  // namespace

VertexCurvature curvature_shape_operator(const TriMesh& mesh, const WeldedTopology& topology) {
    const detail::GroupFrames frames = detail::make_group_frames(mesh, topology);
    const size_t tris = mesh.triangle_count();
    std::vector<CornerShape> corner(3 * tris);

    tbb::parallel_for(tbb::blocked_range<size_t>(0, tris, 2048), [&](const auto& range) {
        for (size_t t = range.begin(); t != range.end(); ++t) {
            if (detail::skip_triangle(mesh, topology, t)) continue;
            const uint32_t* f = &mesh.indices[3 * t];
            const Vec3d p[3] = {detail::position(mesh, f[0]), detail::position(mesh, f[1]),
                                detail::position(mesh, f[2])};
            double area_weight[3];
            if (!detail::mixed_voronoi_areas(p[0], p[1], p[2], area_weight)) continue;
            Vec3d n[3];
            for (int i = 0; i < 3; ++i) n[i] = detail::normal(mesh, f[i]).normalized();

            // Face frame: u along edge 0, face normal from the winding.
            const Vec3d e[3] = {p[2] - p[1], p[0] - p[2], p[1] - p[0]};
            const Vec3d fn = e[0].cross(e[1]).normalized();
            const Vec3d fu = e[0].normalized();
            const Vec3d fv = fn.cross(fu);

            // Normal equations of the 6 equations [eu ev 0; 0 eu ev] (a b c)^T = (dn.u, dn.v).
            Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
            Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
            for (int i = 0; i < 3; ++i) {
                const Vec3d dn = n[(i + 2) % 3] - n[(i + 1) % 3];
                const double eu = e[i].dot(fu), ev = e[i].dot(fv);
                const double dnu = dn.dot(fu), dnv = dn.dot(fv);
                m(0, 0) += eu * eu;
                m(0, 1) += eu * ev;
                m(1, 1) += eu * eu + ev * ev;
                m(1, 2) += eu * ev;
                m(2, 2) += ev * ev;
                rhs(0) += dnu * eu;
                rhs(1) += dnu * ev + dnv * eu;
                rhs(2) += dnv * ev;
            }
            m(1, 0) = m(0, 1);
            m(2, 1) = m(1, 2);
            const Eigen::Vector3d abc = m.ldlt().solve(rhs);
            if (!abc.allFinite()) continue;

            for (int i = 0; i < 3; ++i) {
                const uint32_t g = topology.group_id[f[i]];
                Vec3d ru = fu, rv = fv;
                rotate_frame(ru, rv, fn, frames.n[g]);
                // Coordinates of the group basis vectors in the rotated face frame: S_group = P^T S_face P.
                const double p00 = frames.u[g].dot(ru), p10 = frames.u[g].dot(rv);
                const double p01 = frames.v[g].dot(ru), p11 = frames.v[g].dot(rv);
                auto form = [&](double x0, double x1, double y0, double y1) {
                    return x0 * (abc(0) * y0 + abc(1) * y1) + x1 * (abc(1) * y0 + abc(2) * y1);
                };
                const double w = area_weight[i];
                corner[3 * t + i] = {w * form(p00, p10, p00, p10), w * form(p00, p10, p01, p11),
                                     w * form(p01, p11, p01, p11), w};
            }
        }
    });

    // Gather corners per group in corner order, so sums do not depend on scheduling.
    const uint32_t groups = topology.group_count;
    const detail::GroupCorners lists = detail::group_corners(mesh, topology);
    std::vector<Shape2> shape(groups);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, groups, 4096), [&](const auto& range) {
        for (uint32_t g = range.begin(); g != range.end(); ++g) {
            double a = 0.0, b = 0.0, c = 0.0, w = 0.0;
            for (uint32_t k = lists.start[g]; k < lists.start[g + 1]; ++k) {
                const CornerShape& s = corner[lists.order[k]];
                a += s.a;
                b += s.b;
                c += s.c;
                w += s.weight;
            }
            if (w > 0.0) shape[g] = {a / w, b / w, c / w};
        }
    });
    return detail::vertex_curvature_from_groups(mesh, topology, frames, shape);
}

}  // namespace specbake
