#include "mesh/validate_mesh.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

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

// Counts vertices whose incident triangles do not form one fan: the link (the edges opposite the vertex)
// must be a single path or cycle.
size_t count_nonmanifold_vertices(const std::vector<uint32_t>& tri_pos, uint32_t position_count) {
    const size_t tris = tri_pos.size() / 3;
    std::vector<uint32_t> start(position_count + 1, 0);
    for (uint32_t p : tri_pos) ++start[p + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    std::vector<uint32_t> incident(tri_pos.size());
    for (size_t t = 0; t < tris; ++t)
        for (int c = 0; c < 3; ++c) incident[fill[tri_pos[3 * t + c]]++] = uint32_t(3 * t + c);

    size_t bad = 0;
    std::vector<uint32_t> local, parent, degree;
    for (uint32_t v = 0; v < position_count; ++v) {
        const uint32_t b = start[v], e = start[v + 1];
        if (e - b < 2) continue;
        local.clear();
        for (uint32_t k = b; k < e; ++k) {
            const uint32_t corner = incident[k], t = corner / 3, c = corner % 3;
            local.push_back(tri_pos[3 * t + (c + 1) % 3]);
            local.push_back(tri_pos[3 * t + (c + 2) % 3]);
        }
        std::vector<uint32_t> ids(local);
        std::sort(ids.begin(), ids.end());
        ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
        parent.resize(ids.size());
        std::iota(parent.begin(), parent.end(), 0u);
        degree.assign(ids.size(), 0);
        auto find = [&](uint32_t x) {
            while (parent[x] != x) x = parent[x] = parent[parent[x]];
            return x;
        };
        size_t components = ids.size();
        bool branching = false;
        for (size_t k = 0; k < local.size(); k += 2) {
            const uint32_t a = uint32_t(std::lower_bound(ids.begin(), ids.end(), local[k]) - ids.begin());
            const uint32_t c = uint32_t(std::lower_bound(ids.begin(), ids.end(), local[k + 1]) - ids.begin());
            if (++degree[a] > 2 || ++degree[c] > 2) branching = true;
            const uint32_t ra = find(a), rc = find(c);
            if (ra != rc) {
                parent[ra] = rc;
                --components;
            }
        }
        if (branching || components > 1) ++bad;
    }
    return bad;
}

}  // namespace

Result<MeshReport> validate_mesh(TriMesh& mesh) {
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

    TriMesh positions_only;
    positions_only.positions = mesh.positions;
    const WeldedTopology topo = weld_by_position(positions_only);
    report.duplicate_vertices = n - topo.position_count;

    std::vector<char> used(n, 0);
    for (uint32_t i : mesh.indices) used[i] = 1;
    report.unreferenced_vertices = size_t(std::count(used.begin(), used.end(), 0));

    // Topology on welded positions, over the non-degenerate triangles.
    std::vector<uint32_t> tri_pos;
    tri_pos.reserve(mesh.indices.size());
    for (size_t t = 0; t < report.triangles; ++t) {
        const uint32_t* f = &mesh.indices[3 * t];
        const uint32_t a = topo.position_id[f[0]], b = topo.position_id[f[1]], c = topo.position_id[f[2]];
        if (a == b || b == c || a == c ||
            detail::is_degenerate_triangle(detail::position(mesh, f[0]), detail::position(mesh, f[1]),
                                           detail::position(mesh, f[2]))) {
            ++report.degenerate_triangles;
            continue;
        }
        tri_pos.insert(tri_pos.end(), {a, b, c});
    }
    std::vector<uint64_t> edges;
    edges.reserve(tri_pos.size());
    for (size_t k = 0; k < tri_pos.size(); k += 3) {
        for (int c = 0; c < 3; ++c) {
            const uint64_t a = tri_pos[k + c], b = tri_pos[k + (c + 1) % 3];
            edges.push_back(std::min(a, b) << 32 | std::max(a, b));
        }
    }
    std::sort(edges.begin(), edges.end());
    for (size_t i = 0; i < edges.size();) {
        size_t j = i;
        while (j < edges.size() && edges[j] == edges[i]) ++j;
        if (j - i == 1) ++report.boundary_edges;
        if (j - i >= 3) ++report.nonmanifold_edges;
        i = j;
    }
    report.nonmanifold_vertices = count_nonmanifold_vertices(tri_pos, topo.position_count);

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
    item(repaired_normals, "zero or non-finite normals regenerated");
    item(renormalized_normals, "non-unit normals renormalised");
    item(repaired_tangents, "tangents repaired");
    item(repaired_uvs, "non-finite UVs zeroed");
    if (generated_normals) s << ", normals generated";
    if (generated_tangents) s << ", tangents generated";
    return s.str();
}

}  // namespace specbake
