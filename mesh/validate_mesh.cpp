#include "mesh/validate_mesh.h"

#include <algorithm>
#include <cmath>
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

}  // namespace

Result<MeshReport> validate_mesh(TriMesh& mesh) {
    Result<MeshReport> report = check_and_repair_mesh(mesh);
    if (report) add_topology_report(mesh, *report);
    return report;
}

void add_topology_report(const TriMesh& mesh, MeshReport& report) {
    WeldOptions by_position;
    by_position.split_by_normals = false;  // positions only: the normals may be written meanwhile
    const WeldedTopology topo = weld_by_position(mesh, by_position);
    report.duplicate_vertices = mesh.vertex_count() - topo.position_count;
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
    for (size_t i = 0; i < mesh.indices.size(); ++i) {
        if (mesh.indices[i] >= n)
            return make_error(name + ": triangle " + std::to_string(i / 3) + " references vertex " +
                              std::to_string(mesh.indices[i]) + " but there are only " + std::to_string(n) +
                              " vertices");
    }
    for (size_t v = 0; v < n; ++v) {
        if (!finite3(&mesh.positions[3 * v]))
            return make_error(name + ": vertex " + std::to_string(v) + " has a non-finite position");
    }

    MeshReport report;
    report.vertices = n;
    report.triangles = mesh.triangle_count();

    std::vector<char> used(n, 0);
    for (uint32_t i : mesh.indices) used[i] = 1;
    report.unreferenced_vertices = size_t(std::count(used.begin(), used.end(), 0));

    if (mesh.has_normals()) {
        std::vector<char> broken(n, 0);
        bool any_broken = false;
        for (size_t v = 0; v < n; ++v) {
            float* nv = &mesh.normals[3 * v];
            const double len = finite3(nv) ? std::sqrt(double(nv[0]) * nv[0] + double(nv[1]) * nv[1] +
                                                       double(nv[2]) * nv[2])
                                           : 0.0;
            if (!(len > 1e-12)) {
                broken[v] = 1;
                any_broken = true;
            } else if (std::abs(len - 1.0) > 1e-3) {
                for (int k = 0; k < 3; ++k) nv[k] = float(nv[k] / len);
                ++report.renormalized_normals;
            }
        }
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
        for (size_t v = 0; v < n; ++v) {
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
            report.repaired_tangents += repaired;
        }
    }

    if (mesh.has_uv0()) {
        for (size_t v = 0; v < n; ++v) {
            float* uv = &mesh.uv0[2 * v];
            if (std::isfinite(uv[0]) && std::isfinite(uv[1])) continue;
            uv[0] = uv[1] = 0.0f;
            ++report.repaired_uvs;
        }
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
