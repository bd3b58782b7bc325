// Geometric curvature by CGAL's Monge jet fitting (Cazals & Pouget, "Estimating differential quantities
// using polynomial fitting of osculating jets", CAGD 2005): a bivariate polynomial of the given degree is
// fitted to the k-ring of welded positions around each position, and its Monge form gives the principal
// curvatures and directions. The Monge normal's sign is arbitrary, so it is flipped to agree with each
// curvature group's shading normal; CGAL's z = (k1 x^2 + k2 y^2) / 2 convention makes a sphere seen along
// its outward normal -1/R, hence the sign change to SPEC Sec. 4's +1/R.
#define CGAL_EIGEN3_ENABLED 1
#include <CGAL/Monge_via_jet_fitting.h>
#include <CGAL/Simple_cartesian.h>
#include <tbb/parallel_for.h>

#include <algorithm>

#include "mesh/curvature.h"
#include "mesh/curvature_frames.h"
#include "mesh/halfedge_mesh.h"

namespace specbake {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using MongeFit = CGAL::Monge_via_jet_fitting<Kernel>;

// Neighbouring positions of every position, sorted and unique: the one-rings of the OpenMesh half-edge mesh
// over the usable triangles (a position split into several fans, or with detached faces, gathers the rings
// of all its vertices).
void position_adjacency(const TriMesh& mesh, const WeldedTopology& topology, std::vector<uint32_t>& start,
                        std::vector<uint32_t>& neighbours) {
    const HalfEdgeTopology h = build_halfedge_mesh(mesh, topology);
    std::vector<uint32_t> first(topology.position_count + 1, 0);
    for (auto v : h.mesh.vertices()) first[h.vertex_position[v.idx()] + 1] += uint32_t(h.mesh.valence(v));
    for (uint32_t p = 0; p < topology.position_count; ++p) first[p + 1] += first[p];
    std::vector<uint32_t> all(first.back());
    {
        std::vector<uint32_t> fill(first.begin(), first.end() - 1);
        for (auto v : h.mesh.vertices()) {
            const uint32_t p = h.vertex_position[v.idx()];
            for (auto w : h.mesh.vv_range(v)) all[fill[p]++] = h.vertex_position[w.idx()];
        }
    }
    start.assign(topology.position_count + 1, 0);
    neighbours.clear();
    neighbours.reserve(all.size());
    for (uint32_t p = 0; p < topology.position_count; ++p) {
        std::sort(all.begin() + first[p], all.begin() + first[p + 1]);
        const auto end = std::unique(all.begin() + first[p], all.begin() + first[p + 1]);
        neighbours.insert(neighbours.end(), all.begin() + first[p], end);
        start[p + 1] = uint32_t(neighbours.size());
    }
}

}  // namespace

VertexCurvature curvature_jet_fitting(const TriMesh& mesh, const WeldedTopology& topology, int degree,
                                      int min_points) {
    using detail::Shape2;
    using detail::Vec3d;
    const detail::GroupFrames frames = detail::make_group_frames(mesh, topology);

    std::vector<uint32_t> start, neighbours;
    position_adjacency(mesh, topology, start, neighbours);
    std::vector<Vec3d> where(topology.position_count);
    for (size_t v = 0; v < mesh.vertex_count(); ++v) where[topology.position_id[v]] = detail::position(mesh, uint32_t(v));

    // Groups of each position, to orient one fit for all of them.
    std::vector<uint32_t> group_start(topology.position_count + 1, 0), group_list(topology.group_count);
    {
        std::vector<uint32_t> position_of_group(topology.group_count);
        for (size_t v = 0; v < mesh.vertex_count(); ++v) position_of_group[topology.group_id[v]] = topology.position_id[v];
        for (uint32_t g = 0; g < topology.group_count; ++g) ++group_start[position_of_group[g] + 1];
        for (uint32_t p = 0; p < topology.position_count; ++p) group_start[p + 1] += group_start[p];
        std::vector<uint32_t> fill(group_start.begin(), group_start.end() - 1);
        for (uint32_t g = 0; g < topology.group_count; ++g) group_list[fill[position_of_group[g]]++] = g;
    }

    const size_t needed = std::max<size_t>(size_t(min_points), size_t((degree + 1) * (degree + 2) / 2));
    constexpr int kMaxRings = 6;
    std::vector<Shape2> shape(topology.group_count);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, topology.position_count, 1024), [&](const auto& range) {
        std::vector<uint32_t> ring;
        std::vector<Kernel::Point_3> points;
        for (uint32_t p = range.begin(); p != range.end(); ++p) {
            // Breadth-first k-ring, the evaluation point first (CGAL evaluates at the first point).
            ring.assign(1, p);
            size_t frontier_begin = 0;
            for (int r = 0; r < kMaxRings && ring.size() < needed; ++r) {
                const size_t frontier_end = ring.size();
                for (size_t i = frontier_begin; i < frontier_end; ++i) {
                    for (uint32_t k = start[ring[i]]; k < start[ring[i] + 1]; ++k) {
                        const uint32_t q = neighbours[k];
                        if (std::find(ring.begin(), ring.end(), q) == ring.end()) ring.push_back(q);
                    }
                }
                if (ring.size() == frontier_end) break;
                frontier_begin = frontier_end;
            }
            if (ring.size() < needed) continue;
            points.clear();
            for (uint32_t q : ring) points.emplace_back(where[q].x(), where[q].y(), where[q].z());
            MongeFit fit;
            const MongeFit::Monge_form form = fit(points.begin(), points.end(), size_t(degree), 2);
            if (!std::isfinite(fit.condition_number())) continue;
            const Vec3d monge_n(form.normal_direction().x(), form.normal_direction().y(), form.normal_direction().z());
            const Vec3d d1(form.maximal_principal_direction().x(), form.maximal_principal_direction().y(),
                           form.maximal_principal_direction().z());
            const Vec3d d2(form.minimal_principal_direction().x(), form.minimal_principal_direction().y(),
                           form.minimal_principal_direction().z());
            const double c1 = form.principal_curvatures(0), c2 = form.principal_curvatures(1);
            if (!std::isfinite(c1) || !std::isfinite(c2)) continue;
            for (uint32_t k = group_start[p]; k < group_start[p + 1]; ++k) {
                const uint32_t g = group_list[k];
                const double sign = monge_n.dot(frames.n[g]) < 0.0 ? 1.0 : -1.0;
                const double k1 = sign * c1, k2 = sign * c2;
                const double x1 = d1.dot(frames.u[g]), y1 = d1.dot(frames.v[g]);
                const double x2 = d2.dot(frames.u[g]), y2 = d2.dot(frames.v[g]);
                shape[g] = {k1 * x1 * x1 + k2 * x2 * x2, k1 * x1 * y1 + k2 * x2 * y2, k1 * y1 * y1 + k2 * y2 * y2};
            }
        }
    });
    return detail::vertex_curvature_from_groups(mesh, topology, frames, shape);
}

}  // namespace specbake
