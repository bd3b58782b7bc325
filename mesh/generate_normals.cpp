#include "mesh/generate_normals.h"

#include "mesh/mesh_math.h"
#include "mesh/weld_by_position.h"

namespace specbake {

void generate_normals(TriMesh& mesh, NormalWeighting weighting) {
    using detail::Vec3d;
    WeldOptions by_position;  // weld by position alone, whatever normals are present
    by_position.split_by_normals = false;
    const WeldedTopology topo = weld_by_position(mesh, by_position);

    std::vector<Vec3d> sum(topo.position_count, Vec3d::Zero());
    const size_t tris = mesh.triangle_count();
    for (size_t t = 0; t < tris; ++t) {
        const uint32_t* f = &mesh.indices[3 * t];
        const Vec3d p[3] = {detail::position(mesh, f[0]), detail::position(mesh, f[1]), detail::position(mesh, f[2])};
        const Vec3d cross = (p[1] - p[0]).cross(p[2] - p[0]);
        const double len = cross.norm();
        if (!(len > 0.0) || !std::isfinite(len)) continue;
        for (int c = 0; c < 3; ++c) {
            const Vec3d e1 = p[(c + 1) % 3] - p[c], e2 = p[(c + 2) % 3] - p[c];
            double w = 1.0;
            if (weighting == NormalWeighting::Angle) w = detail::angle_between(e1, e2) / len;
            if (weighting == NormalWeighting::Max) w = 1.0 / (e1.squaredNorm() * e2.squaredNorm());
            if (std::isfinite(w)) sum[topo.position_id[f[c]]] += w * cross;
        }
    }

    const size_t n = mesh.vertex_count();
    mesh.normals.resize(3 * n);
    for (size_t v = 0; v < n; ++v) {
        Vec3d s = sum[topo.position_id[v]];
        const double len = s.norm();
        s = len > 0.0 ? Vec3d(s / len) : Vec3d(0.0, 0.0, 1.0);
        for (int k = 0; k < 3; ++k) mesh.normals[3 * v + k] = float(s[k]);
    }
}

}  // namespace specbake
