#include "mesh/generate_tangents.h"

#include "mesh/mesh_math.h"

namespace specbake {

void generate_tangents(TriMesh& mesh) {
    using detail::Vec3d;
    const size_t n = mesh.vertex_count();
    std::vector<Vec3d> t_sum(n, Vec3d::Zero());
    std::vector<Vec3d> b_sum(n, Vec3d::Zero());

    if (mesh.has_uv0()) {
        const size_t tris = mesh.triangle_count();
        for (size_t t = 0; t < tris; ++t) {
            const uint32_t* f = &mesh.indices[3 * t];
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
            for (int c = 0; c < 3; ++c) {
                const uint32_t vi = f[c];
                const double angle = detail::angle_between(p[(c + 1) % 3] - p[c], p[(c + 2) % 3] - p[c]);
                if (!(angle > 0.0)) continue;
                const Vec3d nrm = detail::normal(mesh, vi);
                // MikkTSpace projects the face's directions into the vertex's tangent plane and normalises
                // them before the angle-weighted sum.
                Vec3d tp = dpdu - nrm.dot(dpdu) * nrm;
                Vec3d bp = up - nrm.dot(up) * nrm;
                const double tl = tp.norm(), bl = bp.norm();
                if (tl > 0.0 && std::isfinite(tl)) t_sum[vi] += (angle / tl) * tp;
                if (bl > 0.0 && std::isfinite(bl)) b_sum[vi] += (angle / bl) * bp;
            }
        }
    }

    mesh.tangents.resize(4 * n);
    for (size_t v = 0; v < n; ++v) {
        const Vec3d nrm = detail::normal(mesh, uint32_t(v));
        Vec3d t = t_sum[v] - nrm.dot(t_sum[v]) * nrm;
        double w = 1.0;
        const double tl = t.norm();
        if (tl > 1e-12 && std::isfinite(tl)) {
            t /= tl;
            w = nrm.cross(t).dot(b_sum[v]) < 0.0 ? -1.0 : 1.0;
        } else {
            Vec3d b;
            detail::orthonormal_basis(nrm, t, b);
        }
        for (int k = 0; k < 3; ++k) mesh.tangents[4 * v + k] = float(t[k]);
        mesh.tangents[4 * v + 3] = float(w);
    }
}

}  // namespace specbake
