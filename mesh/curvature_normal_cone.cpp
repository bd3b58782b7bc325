// Cheap one-ring bound: along every edge leaving a curvature group, the normal turns by the angle between
// the two vertex normals over the edge length, an estimate of the normal curvature in that direction
// (exact on a sphere up to the chord/arc ratio). k1 is the largest such turn rate, signed positive when the
// normal turns with the edge (dn . dp > 0, convex), with d along that edge; k2 is the signed rate along the
// edge most perpendicular to d. It never underestimates the largest rate seen by the one-ring, so it is a
// conservative kernel for the run time, and it overestimates k2 on meshes whose edges do not follow the
// principal directions.
#include <tbb/parallel_for.h>

#include "mesh/curvature.h"
#include "mesh/curvature_frames.h"

namespace specbake {

VertexCurvature curvature_normal_cone(const TriMesh& mesh, const WeldedTopology& topology) {
    using detail::Shape2;
    using detail::Vec3d;
    const detail::GroupFrames frames = detail::make_group_frames(mesh, topology);
    const detail::GroupCorners lists = detail::group_corners(mesh, topology);
    std::vector<Shape2> shape(topology.group_count);

    // Edge directions (in a group's u, v frame) with their signed rates; at most a few dozen per group.
    struct EdgeRate {
        double x, y, rate;
    };
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, topology.group_count, 4096), [&](const auto& range) {
        std::vector<EdgeRate> rates;  // reused by the groups of this range
        for (uint32_t g = range.begin(); g != range.end(); ++g) {
            double best = 0.0, best_x = 1.0, best_y = 0.0;
            bool found = false;
            rates.clear();
            for (uint32_t k = lists.start[g]; k < lists.start[g + 1]; ++k) {
                const uint32_t corner = lists.order[k];
                const size_t t = corner / 3;
                if (detail::skip_triangle(mesh, topology, t)) continue;
                const uint32_t* f = &mesh.indices[3 * t];
                const uint32_t vi = f[corner % 3];
                const Vec3d pi = detail::position(mesh, vi);
                const Vec3d ni = detail::normal(mesh, vi).normalized();
                for (int o = 1; o <= 2; ++o) {
                    const uint32_t vj = f[(corner % 3 + o) % 3];
                    const Vec3d dp = detail::position(mesh, vj) - pi;
                    const Vec3d nj = detail::normal(mesh, vj).normalized();
                    const double len = dp.norm();
                    const double x = dp.dot(frames.u[g]), y = dp.dot(frames.v[g]);
                    const double planar = std::hypot(x, y);
                    if (!(len > 0.0) || !(planar > 0.0)) continue;
                    const double sign = (nj - ni).dot(dp) < 0.0 ? -1.0 : 1.0;
                    const double rate = sign * detail::angle_between(ni, nj) / len;
                    rates.push_back({x / planar, y / planar, rate});
                    if (!found || std::abs(rate) > std::abs(best)) {
                        best = rate;
                        best_x = x / planar;
                        best_y = y / planar;
                        found = true;
                    }
                }
            }
            if (!found) continue;
            double k2 = 0.0, least_alignment = 2.0;
            for (const EdgeRate& e : rates) {
                const double alignment = std::abs(e.x * best_x + e.y * best_y);
                if (alignment < least_alignment) {
                    least_alignment = alignment;
                    k2 = e.rate;
                }
            }
            // S = k1 d d^T + k2 d_perp d_perp^T in the group frame.
            const double px = -best_y, py = best_x;
            shape[g] = {best * best_x * best_x + k2 * px * px, best * best_x * best_y + k2 * px * py,
                        best * best_y * best_y + k2 * py * py};
        }
    });
    return detail::vertex_curvature_from_groups(mesh, topology, frames, shape);
}

}  // namespace specbake
