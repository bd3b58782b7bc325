#include "mesh/validate_mesh.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>

#include "mesh/halfedge_mesh.h"
#include "mesh/mesh_math.h"
#include "mesh/weld_by_position.h"

namespace specbake {
namespace {

using detail::Vec3d;

std::string label(const TriMesh& mesh) { return mesh.name.empty() ? std::string("mesh") : mesh.name; }

bool finite3(const float* p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

// Angle-weighted normal of the triangles that use vertex v (by index, so split hard-edge vertices keep
// their own side), for the vertices in `wanted` only.
std::vector<Vec3d> corner_normals(const TriMesh& mesh, const std::vector<char>& wanted) {
    std::vector<Vec3d> sum(mesh.vertex_count(), Vec3d::Zero());
    for (size_t t = 0; t < mesh.triangle_count(); ++t) {
        const uint32_t* f = &mesh.indices[3 * t];
        if (!wanted[f[0]] && !wanted[f[1]] && !wanted[f[2]]) continue;
        const Vec3d p[3] = {detail::position(mesh, f[0]), detail::position(mesh, f[1]), detail::position(mesh, f[2])};
        if (detail::is_degenerate_triangle(p[0], p[1], p[2])) continue;
        const Vec3d n = (p[1] - p[0]).cross(p[2] - p[0]).normalized();
        for (int c = 0; c < 3; ++c)
            sum[f[c]] += detail::angle_between(p[(c + 1) % 3] - p[c], p[(c + 2) % 3] - p[c]) * n;
    }
    return sum;
}

// The smallest i < n with bad(i), or n: the same element a sequential scan would report, found in parallel.
template <class Bad>
size_t first_bad(size_t n, const Bad& bad) {
    return tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, n, 16384), n,
        [&](const tbb::blocked_range<size_t>& r, size_t found) {
            for (size_t i = r.begin(); i != r.end() && i < found; ++i)
                if (bad(i)) return i;
            return found;
        },
        [](size_t a, size_t b) { return std::min(a, b); });
}

// The sum of count(i) over i < n, in parallel (each i may repair its own element).
template <class Count>
size_t count_parallel(size_t n, const Count& count) {
    return tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, n, 16384), size_t(0),
        [&](const tbb::blocked_range<size_t>& r, size_t sum) {
            for (size_t i = r.begin(); i != r.end(); ++i) sum += count(i);
            return sum;
        },
        std::plus<size_t>());
}

}  // namespace

Result<MeshReport> validate_mesh(TriMesh& mesh) {
    Result<MeshReport> report = check_and_repair_mesh(mesh);
    if (report) add_topology_report(mesh, *report);
    return report;
}

void add_topology_report(const TriMesh& mesh, MeshReport& report) {
    WeldOptions by_position;
    by_position.split_by_normals = false;  // positions only: the normals may be written meanwhile
    add_topology_report(mesh, weld_by_position(mesh, by_position), report);
}

void add_topology_report(const TriMesh& mesh, const WeldedTopology& topo, MeshReport& report) {
    report.duplicate_vertices = mesh.vertex_count() - topo.position_count;
    std::vector<char> used(mesh.vertex_count(), 0);
    for (uint32_t i : mesh.indices) used[i] = 1;
    report.unreferenced_vertices = size_t(std::count(used.begin(), used.end(), 0));
    const HalfEdgeTopology halfedge = build_halfedge_mesh(mesh, topo);
    report.degenerate_triangles = halfedge.degenerate_triangles;
    report.boundary_edges = halfedge.boundary_edges;
    report.nonmanifold_edges = halfedge.nonmanifold_edges;
    report.nonmanifold_vertices = halfedge.nonmanifold_vertices;
    report.detached_faces = halfedge.detached_faces;
    report.split_vertices = halfedge.split_vertices;
}

Result<MeshReport> check_and_repair_mesh(TriMesh& mesh) {
    const std::string name = label(mesh);
    if (mesh.positions.size() % 3 != 0)
        return make_error(name + ": position array length " + std::to_string(mesh.positions.size()) +
                          " is not a multiple of 3");
    const size_t n = mesh.vertex_count();
    if (n == 0 || mesh.indices.empty()) return make_error(name + ": no triangles");
    if (mesh.indices.size() % 3 != 0)
        return make_error(name + ": index count " + std::to_string(mesh.indices.size()) + " is not a multiple of 3");
    if (!mesh.normals.empty() && mesh.normals.size() != 3 * n)
        return make_error(name + ": " + std::to_string(mesh.normals.size() / 3) + " normals for " + std::to_string(n) +
                          " vertices");
    if (!mesh.tangents.empty() && mesh.tangents.size() != 4 * n)
        return make_error(name + ": " + std::to_string(mesh.tangents.size() / 4) + " tangents for " +
                          std::to_string(n) + " vertices");
    if (!mesh.uv0.empty() && mesh.uv0.size() != 2 * n)
        return make_error(name + ": " + std::to_string(mesh.uv0.size() / 2) + " texture coordinates for " +
                          std::to_string(n) + " vertices");
    if (const size_t i = first_bad(mesh.indices.size(), [&](size_t i) { return mesh.indices[i] >= n; });
        i < mesh.indices.size())
        return make_error(name + ": triangle " + std::to_string(i / 3) + " references vertex " +
                          std::to_string(mesh.indices[i]) + " but there are only " + std::to_string(n) + " vertices");
    if (const size_t v = first_bad(n, [&](size_t v) { return !finite3(&mesh.positions[3 * v]); }); v < n)
        return make_error(name + ": vertex " + std::to_string(v) + " has a non-finite position");

    MeshReport report;
    report.vertices = n;
    report.triangles = mesh.triangle_count();

    if (mesh.has_normals()) {
        std::vector<char> broken(n, 0);
        report.renormalized_normals = count_parallel(n, [&](size_t v) -> size_t {
            float* nv = &mesh.normals[3 * v];
            const double len = finite3(nv) ? std::sqrt(double(nv[0]) * nv[0] + double(nv[1]) * nv[1] +
                                                       double(nv[2]) * nv[2])
                                           : 0.0;
            if (!(len > 1e-12)) {
                broken[v] = 1;
                return 0;
            }
            if (!(std::abs(len - 1.0) > 1e-3)) return 0;
            for (int k = 0; k < 3; ++k) nv[k] = float(nv[k] / len);
            return 1;
        });
        const bool any_broken = std::find(broken.begin(), broken.end(), 1) != broken.end();
        if (any_broken) {
            const std::vector<Vec3d> sum = corner_normals(mesh, broken);
            for (size_t v = 0; v < n; ++v) {
                if (!broken[v]) continue;
                const double len = sum[v].norm();
                const Vec3d nv = len > 0.0 ? Vec3d(sum[v] / len) : Vec3d(0.0, 0.0, 1.0);
                for (int k = 0; k < 3; ++k) mesh.normals[3 * v + k] = float(nv[k]);
                ++report.repaired_normals;
            }
        }
    }

    if (mesh.has_tangents()) {
        report.repaired_tangents = count_parallel(n, [&](size_t v) -> size_t {
            float* tv = &mesh.tangents[4 * v];
            bool repaired = false;
            const Vec3d nv = mesh.has_normals() ? detail::normal(mesh, uint32_t(v)) : Vec3d(0.0, 0.0, 1.0);
            const Vec3d t(tv[0], tv[1], tv[2]);
            const double perpendicular = (t - nv.dot(t) * nv).norm();
            if (!finite3(tv) || !(perpendicular > 1e-6 * std::max(1.0, t.norm()))) {
                Vec3d tt, bb;
                detail::orthonormal_basis(nv, tt, bb);
                for (int k = 0; k < 3; ++k) tv[k] = float(tt[k]);
                repaired = true;
            }
            if (tv[3] != 1.0f && tv[3] != -1.0f) {
                tv[3] = tv[3] < 0.0f ? -1.0f : 1.0f;
                repaired = true;
            }
            return size_t(repaired);
        });
    }

    if (mesh.has_uv0()) {
        report.repaired_uvs = count_parallel(n, [&](size_t v) -> size_t {
            float* uv = &mesh.uv0[2 * v];
            if (std::isfinite(uv[0]) && std::isfinite(uv[1])) return 0;
            uv[0] = uv[1] = 0.0f;
            return 1;
        });
    }
    return report;
}

std::string MeshReport::summary() const {
    std::ostringstream s;
    s << vertices << " vertices, " << triangles << " triangles";
    auto item = [&](size_t count, const char* what) {
        if (count) s << ", " << count << ' ' << what;
    };
    item(degenerate_triangles, "degenerate triangles (skipped)");
    item(duplicate_vertices, "duplicate vertices (welded)");
    item(unreferenced_vertices, "unreferenced vertices");
    item(boundary_edges, "boundary edges");
    item(nonmanifold_edges, "non-manifold edges");
    item(nonmanifold_vertices, "non-manifold vertices");
    item(detached_faces, "faces detached from a non-manifold or misoriented edge");
    item(split_vertices, "vertices split into separate fans");
    item(repaired_normals, "zero or non-finite normals regenerated");
    item(renormalized_normals, "non-unit normals renormalised");
    item(repaired_tangents, "tangents repaired");
    item(repaired_uvs, "non-finite UVs zeroed");
    if (generated_normals) s << ", normals generated";
    if (generated_tangents) s << ", tangents generated";
    return s.str();
}

}  // namespace specbake
