// CurvatureEstimator::Patch: the shape operator of the shading-normal field (Rusinkiewicz 2004, as the
// default estimator computes per face), aggregated at each curvature group over the faces of the smooth
// patch the group belongs to rather than over all of its one-ring.
//
// Why: the run-time kernel interpolates the per-vertex operator across each face, so a vertex value has to
// describe the faces that interpolate it. Where a one-ring holds faces of very different gradient (a lip of
// a few steep faces beside a gently curved dome), the area average carries the steep faces into every
// dome face touching that vertex and widens their highlight by the square of the ratio (measured on
// IridescentDishWithOlives' glass cover: vertex |k1| median 24/m against its faces' 15.8/m; docs/accuracy.md).
// Here each face's weight is its mixed-Voronoi area times min(1, m_med / m_f)^2, where m_f is the face
// operator's Frobenius norm (rotation invariant) and m_med the area-weighted median of m over the group's
// faces: faces steeper than the one-ring's majority count as little as their share of the squared gradient
// the majority would give them (a Cauchy-type robust weight with the median as its scale, no constant of
// its own), faces at or below the median keep their full weight. Where the one-ring is one smooth patch
// (every m_f near m_med) this is the default estimator's average; where it is two, the vertex takes the
// majority's. The faces of the minority then interpolate a smaller kernel than their own gradient, which
// filters less there (never more than the majority patch's gradient warrants).
//
// Each face operator is expressed in the group frame after rotating that frame into the face's plane
// (Rusinkiewicz 2004 Sec. 4), as the default estimator does.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "mesh/curvature.h"
#include "mesh/curvature_frames.h"

namespace specbake {

namespace {

struct FaceOperator {
    detail::Vec3d fu, fv;  // the face's frame
    double a = 0, b = 0, c = 0;
    double magnitude = 0;  // Frobenius norm sqrt(a^2 + 2 b^2 + c^2)
    double w[3] = {0, 0, 0};  // mixed-Voronoi area of each corner
    bool valid = false;
};

FaceOperator face_operator(const TriMesh& mesh, const WeldedTopology& topology, size_t t) {
    using detail::Vec3d;
    FaceOperator out;
    if (detail::skip_triangle(mesh, topology, t)) return out;
    const uint32_t* f = &mesh.indices[3 * t];
    Vec3d p[3], n[3];
    for (int i = 0; i < 3; ++i) {
        p[i] = detail::position(mesh, f[i]);
        n[i] = detail::normal(mesh, f[i]).normalized();
    }
    const Vec3d cr = (p[1] - p[0]).cross(p[2] - p[0]);
    const double twice_area = cr.norm();
    if (!(twice_area > 0.0)) return out;
    const Vec3d nf = cr / twice_area;
    out.fu = (p[1] - p[0]).normalized();
    out.fv = nf.cross(out.fu);
    // Least squares of S e_i = dn_i over the three edges (Rusinkiewicz 2004 Sec. 3).
    Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
    Eigen::Vector3d r = Eigen::Vector3d::Zero();
    double l[3];
    for (int i = 0; i < 3; ++i) {
        const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
        const Vec3d e = p[i2] - p[i1], dn = n[i2] - n[i1];
        l[i] = e.squaredNorm();
        const double eu = e.dot(out.fu), ev = e.dot(out.fv), dnu = dn.dot(out.fu), dnv = dn.dot(out.fv);
        const Eigen::Vector3d row0(eu, ev, 0.0), row1(0.0, eu, ev);
        M += row0 * row0.transpose() + row1 * row1.transpose();
        r += row0 * dnu + row1 * dnv;
    }
    const Eigen::Vector3d s = M.ldlt().solve(r);
    if (!s.allFinite()) return out;
    out.a = s[0];
    out.b = s[1];
    out.c = s[2];
    out.magnitude = std::sqrt(s[0] * s[0] + 2.0 * s[1] * s[1] + s[2] * s[2]);
    detail::mixed_voronoi_areas(l[0], l[1], l[2], 0.5 * twice_area, out.w);
    out.valid = true;
    return out;
}

}  // namespace

VertexCurvature curvature_patch(const TriMesh& mesh, const WeldedTopology& topology) {
    using detail::Shape2;
    using detail::Vec3d;
    const detail::GroupFrames frames = detail::make_group_frames(mesh, topology);
    const detail::GroupCorners lists = detail::group_corners(mesh, topology);
    const size_t faces = mesh.indices.size() / 3;
    std::vector<FaceOperator> ops(faces);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, faces, 4096), [&](const auto& range) {
        for (size_t t = range.begin(); t != range.end(); ++t) ops[t] = face_operator(mesh, topology, t);
    });
    std::vector<Shape2> shape(topology.group_count);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, topology.group_count, 4096), [&](const auto& range) {
        std::vector<std::pair<double, double>> by_magnitude;  // (m_f, weight), reused
        for (uint32_t g = range.begin(); g != range.end(); ++g) {
            by_magnitude.clear();
            double total = 0.0;
            for (uint32_t k = lists.start[g]; k < lists.start[g + 1]; ++k) {
                const uint32_t corner = lists.order[k];
                const FaceOperator& op = ops[corner / 3];
                if (!op.valid) continue;
                by_magnitude.push_back({op.magnitude, op.w[corner % 3]});
                total += op.w[corner % 3];
            }
            if (!(total > 0.0)) continue;
            std::sort(by_magnitude.begin(), by_magnitude.end());
            double median = by_magnitude.back().first, acc = 0.0;
            for (const auto& [m, w] : by_magnitude) {
                acc += w;
                if (acc >= 0.5 * total) {
                    median = m;
                    break;
                }
            }
            const Vec3d& u = frames.u[g];
            const Vec3d& v = frames.v[g];
            double sa = 0, sb = 0, sc = 0, sw = 0;
            for (uint32_t k = lists.start[g]; k < lists.start[g + 1]; ++k) {
                const uint32_t corner = lists.order[k];
                const FaceOperator& op = ops[corner / 3];
                if (!op.valid) continue;
                double w = op.w[corner % 3];
                if (op.magnitude > median && op.magnitude > 0.0) {
                    const double q = median / op.magnitude;
                    w *= q * q;
                }
                // The group's (u, v) rotated about nf x ng into the face's plane (Rusinkiewicz 2004 Sec. 4),
                // then the face operator in that basis: exact for spherical normals whatever the angle
                // between face and group normal.
                const Vec3d nf = op.fu.cross(op.fv);
                const Vec3d ng = u.cross(v);
                const double ndot = ng.dot(nf);
                Vec3d ru = u, rv = v;
                if (ndot <= -1.0) {
                    ru = -u;
                    rv = -v;
                } else {
                    const Vec3d perp = nf - ndot * ng;
                    const Vec3d dperp = (ng + nf) / (1.0 + ndot);
                    ru -= dperp * ru.dot(perp);
                    rv -= dperp * rv.dot(perp);
                }
                const double u1 = ru.dot(op.fu), v1 = ru.dot(op.fv), u2 = rv.dot(op.fu), v2 = rv.dot(op.fv);
                sa += w * (op.a * u1 * u1 + op.b * 2.0 * u1 * v1 + op.c * v1 * v1);
                sb += w * (op.a * u1 * u2 + op.b * (u1 * v2 + u2 * v1) + op.c * v1 * v2);
                sc += w * (op.a * u2 * u2 + op.b * 2.0 * u2 * v2 + op.c * v2 * v2);
                sw += w;
            }
            if (sw > 0.0) shape[g] = Shape2{sa / sw, sb / sw, sc / sw};
        }
    });
    return detail::vertex_curvature_from_groups(mesh, topology, frames, shape);
}

}  // namespace specbake
