#include "mesh/generate_tangents.h"

#include <tbb/parallel_for.h>

#include "mesh/mesh_math.h"
#include "mesh/scratch_array.h"

namespace specbake {
namespace {

// Per triangle: dP/du, and the handedness its UV mapping gives (+1: B = cross(N, T) points along -dP/dv,
// i.e. up the glTF image), 0 when the UV triangle is degenerate.
struct FaceTangent {
    double dpdu[3];
    double sign;
};

}  // namespace

void generate_tangents(TriMesh& mesh) {
    using detail::Vec3d;
    const size_t n = mesh.vertex_count();
    const size_t tris = mesh.triangle_count();
    const bool with_uv = mesh.has_uv0();

    // MikkTSpace step 1, per triangle: dP/du and dP/dv from [dp1 dp2] = [dP/du dP/dv] [[du1 du2], [dv1 dv2]].
    // cross(N, dP/du) . (-dP/dv) = -|dp1 x dp2| / det, so the handedness is the sign of -det.
    detail::ScratchArray<FaceTangent> face(with_uv ? tris : 0);
    std::vector<uint32_t> start(n + 1, 0), order;
    if (with_uv) {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, tris, 8192), [&](const auto& range) {
            for (size_t t = range.begin(); t != range.end(); ++t) {
                const uint32_t* f = &mesh.indices[3 * t];
                const Vec3d p0 = detail::position(mesh, f[0]);
                const Vec3d dp1 = detail::position(mesh, f[1]) - p0, dp2 = detail::position(mesh, f[2]) - p0;
                const double u0 = mesh.uv0[2 * f[0]], v0 = mesh.uv0[2 * f[0] + 1];
                const double du1 = mesh.uv0[2 * f[1]] - u0, dv1 = mesh.uv0[2 * f[1] + 1] - v0;
                const double du2 = mesh.uv0[2 * f[2]] - u0, dv2 = mesh.uv0[2 * f[2] + 1] - v0;
                const double det = du1 * dv2 - du2 * dv1;  // twice the signed UV area
                FaceTangent& ft = face[t];
                ft.sign = 0.0;
                if (!(std::abs(det) > 0.0) || !std::isfinite(det)) continue;
                const Vec3d dpdu = (dp1 * dv2 - dp2 * dv1) / det;
                for (int k = 0; k < 3; ++k) ft.dpdu[k] = dpdu[k];
                ft.sign = det < 0.0 ? 1.0 : -1.0;
            }
        });
        // Corners of each vertex in triangle order (a counting sort), so each vertex sums its own corners in
        // the same order for any thread count.
        for (uint32_t i : mesh.indices) ++start[i + 1];
        for (size_t v = 0; v < n; ++v) start[v + 1] += start[v];
        order.resize(mesh.indices.size());
        std::vector<uint32_t> fill(start.begin(), start.end() - 1);
        for (size_t k = 0; k < mesh.indices.size(); ++k) order[fill[mesh.indices[k]]++] = uint32_t(k);
    }

    // MikkTSpace step 2, per vertex: each corner's dP/du projected into the vertex's tangent plane and
    // normalised, weighted by the corner angle measured in that plane; the sum normalised. The handedness is
    // the angle-weighted majority of the corners' (a vertex keeps one tangent, so corners of both
    // handednesses are not split apart as MikkTSpace would).
    // The corner loop is written out on plain doubles (in Eigen's evaluation order, so the sums are the
    // same): it avoids the stores and reloads of small vector temporaries on this latency-bound path.
    mesh.tangents.resize(4 * n);
    const float* position = mesh.positions.data();
    auto dot = [](const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const auto& range) {
        for (size_t vi = range.begin(); vi != range.end(); ++vi) {
            Vec3d nrm = detail::normal(mesh, uint32_t(vi));
            const double nl = nrm.norm();
            nrm = nl > 0.0 ? Vec3d(nrm / nl) : Vec3d(0.0, 0.0, 1.0);
            const double nv[3] = {nrm[0], nrm[1], nrm[2]};
            double t_sum[3] = {0.0, 0.0, 0.0};
            double sign_sum = 0.0;
            for (uint32_t k = with_uv ? start[vi] : 0; with_uv && k < start[vi + 1]; ++k) {
                const uint32_t corner = order[k], c = corner % 3;
                const FaceTangent& ft = face[corner / 3];
                if (ft.sign == 0.0) continue;
                const uint32_t* f = &mesh.indices[corner - c];
                const float* p = position + 3 * size_t(f[c]);
                const float* p1 = position + 3 * size_t(f[c == 2 ? 0 : c + 1]);
                const float* p2 = position + 3 * size_t(f[c == 0 ? 2 : c - 1]);
                double e1[3], e2[3], tp[3];
                for (int i = 0; i < 3; ++i) {
                    e1[i] = double(p1[i]) - double(p[i]);
                    e2[i] = double(p2[i]) - double(p[i]);
                }
                const double d1 = dot(nv, e1), d2 = dot(nv, e2), du = dot(nv, ft.dpdu);
                for (int i = 0; i < 3; ++i) {
                    e1[i] -= d1 * nv[i];
                    e2[i] -= d2 * nv[i];
                    tp[i] = ft.dpdu[i] - du * nv[i];
                }
                const double cross[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                                         e1[0] * e2[1] - e1[1] * e2[0]};
                // The corner angle is only a weight: a polynomial atan2 (error < 3e-11 rad) instead of libm's,
                // about five times cheaper and the same on every platform.
                const double angle = detail::corner_angle(std::sqrt(dot(cross, cross)), dot(e1, e2));
                const double tl = std::sqrt(dot(tp, tp));
                if (!(angle > 0.0) || !(tl > 0.0) || !std::isfinite(tl)) continue;
                const double weight = angle / tl;
                for (int i = 0; i < 3; ++i) t_sum[i] += weight * tp[i];
                sign_sum += angle * ft.sign;
            }
            const Vec3d sum(t_sum[0], t_sum[1], t_sum[2]);
            Vec3d t = sum - nrm.dot(sum) * nrm;
            double w = 1.0;
            const double tl = t.norm();
            if (tl > 1e-12 && std::isfinite(tl)) {
                t /= tl;
                w = sign_sum < 0.0 ? -1.0 : 1.0;
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
