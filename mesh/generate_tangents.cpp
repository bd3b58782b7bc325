#include "mesh/generate_tangents.h"

#include <tbb/parallel_for.h>

#include "mesh/mesh_math.h"

namespace specbake {

void generate_tangents(TriMesh& mesh) {
    using detail::Vec3d;
    const size_t n = mesh.vertex_count();
    const bool with_uv = mesh.has_uv0();

    // Corners of each vertex in triangle order (a counting sort), so each vertex sums its corners itself, in
    // the same order for any thread count.
    std::vector<uint32_t> start(n + 1, 0), order;
    if (with_uv) {
        for (uint32_t i : mesh.indices) ++start[i + 1];
        for (size_t v = 0; v < n; ++v) start[v + 1] += start[v];
        order.resize(mesh.indices.size());
        std::vector<uint32_t> fill(start.begin(), start.end() - 1);
        for (size_t k = 0; k < mesh.indices.size(); ++k) order[fill[mesh.indices[k]]++] = uint32_t(k);
    }

    mesh.tangents.resize(4 * n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const auto& range) {
        for (size_t vi = range.begin(); vi != range.end(); ++vi) {
            const Vec3d nrm = detail::normal(mesh, uint32_t(vi));
            Vec3d t_sum = Vec3d::Zero(), b_sum = Vec3d::Zero();
            for (uint32_t k = with_uv ? start[vi] : 0; with_uv && k < start[vi + 1]; ++k) {
                const uint32_t corner = order[k], c = corner % 3;
                const uint32_t* f = &mesh.indices[corner - c];
                const Vec3d p[3] = {detail::position(mesh, f[0]), detail::position(mesh, f[1]),
                                    detail::position(mesh, f[2])};
                const double u[3] = {mesh.uv0[2 * f[0]], mesh.uv0[2 * f[1]], mesh.uv0[2 * f[2]]};
                const double v[3] = {mesh.uv0[2 * f[0] + 1], mesh.uv0[2 * f[1] + 1], mesh.uv0[2 * f[2] + 1]};
                const Vec3d dp1 = p[1] - p[0], dp2 = p[2] - p[0];
                const double du1 = u[1] - u[0], dv1 = v[1] - v[0], du2 = u[2] - u[0], dv2 = v[2] - v[0];
                const double det = du1 * dv2 - du2 * dv1;  // twice the signed UV area
                if (!(std::abs(det) > 0.0) || !std::isfinite(det)) continue;
                // dP/du and dP/dv from the 2x2 system [dp1 dp2] = [dP/du dP/dv] [[du1 du2], [dv1 dv2]].
                const Vec3d dpdu = (dp1 * dv2 - dp2 * dv1) / det;
                const Vec3d dpdv = (dp2 * du1 - dp1 * du2) / det;
                // glTF v grows downwards in the image; the normal map's +Y (and B) points up, along -dP/dv.
                const Vec3d up = -dpdv;
                const double angle = detail::angle_between(p[(c + 1) % 3] - p[c], p[(c + 2) % 3] - p[c]);
                if (!(angle > 0.0)) continue;
                // MikkTSpace projects the face's directions into the vertex's tangent plane and normalises
                // them before the angle-weighted sum.
                const Vec3d tp = dpdu - nrm.dot(dpdu) * nrm;
                const Vec3d bp = up - nrm.dot(up) * nrm;
                const double tl = tp.norm(), bl = bp.norm();
                if (tl > 0.0 && std::isfinite(tl)) t_sum += (angle / tl) * tp;
                if (bl > 0.0 && std::isfinite(bl)) b_sum += (angle / bl) * bp;
            }
            Vec3d t = t_sum - nrm.dot(t_sum) * nrm;
            double w = 1.0;
            const double tl = t.norm();
            if (tl > 1e-12 && std::isfinite(tl)) {
                t /= tl;
                w = nrm.cross(t).dot(b_sum) < 0.0 ? -1.0 : 1.0;
            } else {
                Vec3d b;
                detail::orthonormal_basis(nrm, t, b);
            }
            for (int k = 0; k < 3; ++k) mesh.tangents[4 * vi + k] = float(t[k]);
            mesh.tangents[4 * vi + 3] = float(w);
        }
    });
}

}  // namespace specbake
