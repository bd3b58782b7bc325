#include "mesh/generate_tangents.h"

#include <tbb/parallel_for.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

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

// What a corner adds to its vertex: the corner angle in the vertex tangent plane and the triangle's dP/du
// projected into that plane (tp, length tl).
struct CornerTerm {
    double angle, tl, tp[3];
};

inline double dot3(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// One corner: p its position, p1 and p2 the next two corners' (in winding order), nv the unit vertex normal.
void corner_term(const float* p, const float* p1, const float* p2, const double* dpdu, const double* nv,
                 CornerTerm& out) {
    double e1[3], e2[3];
    for (int i = 0; i < 3; ++i) {
        e1[i] = double(p1[i]) - double(p[i]);
        e2[i] = double(p2[i]) - double(p[i]);
    }
    const double d1 = dot3(nv, e1), d2 = dot3(nv, e2), du = dot3(nv, dpdu);
    for (int i = 0; i < 3; ++i) {
        e1[i] -= d1 * nv[i];
        e2[i] -= d2 * nv[i];
        out.tp[i] = dpdu[i] - du * nv[i];
    }
    const double cross[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    // The corner angle is only a weight: a polynomial atan2 (error < 3e-11 rad) instead of libm's, about five
    // times cheaper and the same on every platform.
    out.angle = detail::corner_angle(std::sqrt(dot3(cross, cross)), dot3(e1, e2));
    out.tl = std::sqrt(dot3(out.tp, out.tp));
}

#if defined(__SSE2__)
// Two corners of one vertex at once, one per lane, with exactly the operations of corner_term and
// detail::corner_angle in the same order (so the same bits): the per-corner work is a long chain of
// dependent divisions and square roots, and two independent chains share the instructions.
void corner_terms2(const float* const p[2][3], const double* const dpdu[2], const double* nv, CornerTerm out[2]) {
    auto lanes = [](double lo, double hi) { return _mm_set_pd(hi, lo); };
    auto select = [](__m128d mask, __m128d yes, __m128d no) {
        return _mm_or_pd(_mm_and_pd(mask, yes), _mm_andnot_pd(mask, no));
    };
    const __m128d n[3] = {_mm_set1_pd(nv[0]), _mm_set1_pd(nv[1]), _mm_set1_pd(nv[2])};
    auto dot = [](const __m128d* a, const __m128d* b) {
        return _mm_add_pd(_mm_add_pd(_mm_mul_pd(a[0], b[0]), _mm_mul_pd(a[1], b[1])), _mm_mul_pd(a[2], b[2]));
    };
    __m128d e1[3], e2[3], tp[3], du[3];
    for (int i = 0; i < 3; ++i) {
        const __m128d q = lanes(p[0][0][i], p[1][0][i]);
        e1[i] = _mm_sub_pd(lanes(p[0][1][i], p[1][1][i]), q);
        e2[i] = _mm_sub_pd(lanes(p[0][2][i], p[1][2][i]), q);
        du[i] = lanes(dpdu[0][i], dpdu[1][i]);
    }
    const __m128d d1 = dot(n, e1), d2 = dot(n, e2), dn = dot(n, du);
    for (int i = 0; i < 3; ++i) {
        e1[i] = _mm_sub_pd(e1[i], _mm_mul_pd(d1, n[i]));
        e2[i] = _mm_sub_pd(e2[i], _mm_mul_pd(d2, n[i]));
        tp[i] = _mm_sub_pd(du[i], _mm_mul_pd(dn, n[i]));
    }
    const __m128d cross[3] = {_mm_sub_pd(_mm_mul_pd(e1[1], e2[2]), _mm_mul_pd(e1[2], e2[1])),
                              _mm_sub_pd(_mm_mul_pd(e1[2], e2[0]), _mm_mul_pd(e1[0], e2[2])),
                              _mm_sub_pd(_mm_mul_pd(e1[0], e2[1]), _mm_mul_pd(e1[1], e2[0]))};
    const __m128d y = _mm_sqrt_pd(dot(cross, cross)), x = dot(e1, e2);
    // detail::corner_angle, lane-wise: both branches computed, the lane's one selected.
    const __m128d zero = _mm_setzero_pd(), one = _mm_set1_pd(1.0), pi = _mm_set1_pd(detail::kAtanPi);
    const __m128d ax = _mm_andnot_pd(_mm_set1_pd(-0.0), x);
    const __m128d steep = _mm_cmpgt_pd(y, ax);
    __m128d t = _mm_div_pd(select(steep, ax, y), select(steep, y, ax));
    const __m128d high = _mm_cmpgt_pd(t, _mm_set1_pd(detail::kAtanTanPi8));
    t = select(high, _mm_div_pd(_mm_sub_pd(t, one), _mm_add_pd(t, one)), t);
    const __m128d s = _mm_mul_pd(t, t);
    __m128d poly = _mm_set1_pd(detail::kAtanFit[0]);
    for (int i = 1; i < 7; ++i) poly = _mm_add_pd(_mm_mul_pd(poly, s), _mm_set1_pd(detail::kAtanFit[i]));
    __m128d a = _mm_add_pd(_mm_mul_pd(t, poly), select(high, _mm_set1_pd(0.25 * detail::kAtanPi), zero));
    a = select(steep, _mm_sub_pd(_mm_set1_pd(0.5 * detail::kAtanPi), a), a);
    const __m128d negative = _mm_cmplt_pd(x, zero);
    a = select(negative, _mm_sub_pd(pi, a), a);
    a = select(_mm_cmpeq_pd(y, zero), select(negative, pi, zero), a);
    const __m128d tl = _mm_sqrt_pd(dot(tp, tp));
    double angle[2], length[2], tpv[3][2];
    _mm_storeu_pd(angle, a);
    _mm_storeu_pd(length, tl);
    for (int i = 0; i < 3; ++i) _mm_storeu_pd(tpv[i], tp[i]);
    for (int l = 0; l < 2; ++l) {
        out[l].angle = angle[l];
        out[l].tl = length[l];
        for (int i = 0; i < 3; ++i) out[l].tp[i] = tpv[i][l];
    }
}
#endif

}  // namespace

void generate_tangents(TriMesh& mesh) {
    using detail::Vec3d;
    const size_t n = mesh.vertex_count();
    const size_t tris = mesh.triangle_count();
    const bool with_uv = mesh.has_uv0();

    // MikkTSpace step 1, per triangle: dP/du and dP/dv from [dp1 dp2] = [dP/du dP/dv] [[du1 du2], [dv1 dv2]].
    // cross(N, dP/du) . (-dP/dv) = -|dp1 x dp2| / det, so the handedness is the sign of -det.
    detail::ScratchArray<FaceTangent> face(with_uv ? tris : 0);
    std::vector<uint32_t> start(n + 1, 0);
    detail::ScratchArray<uint32_t> order(with_uv ? mesh.indices.size() : 0);  // every slot written below
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
        std::vector<uint32_t> fill(start.begin(), start.end() - 1);
        for (size_t k = 0; k < mesh.indices.size(); ++k) order[fill[mesh.indices[k]]++] = uint32_t(k);
    }

    // MikkTSpace step 2, per vertex: each corner's dP/du projected into the vertex's tangent plane and
    // normalised, weighted by the corner angle measured in that plane; the sum normalised. The handedness is
    // the angle-weighted majority of the corners' (a vertex keeps one tangent, so corners of both
    // handednesses are not split apart as MikkTSpace would).
    // The corner terms are computed on plain doubles (in Eigen's evaluation order, so the sums are the same)
    // and, with SSE2, two corners at a time; they are added in corner order.
    mesh.tangents.clear();
    detail::reserve_huge_pages(mesh.tangents, 4 * n);
    mesh.tangents.resize(4 * n);
    const float* position = mesh.positions.data();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const auto& range) {
        for (size_t vi = range.begin(); vi != range.end(); ++vi) {
            Vec3d nrm = detail::normal(mesh, uint32_t(vi));
            const double nl = nrm.norm();
            nrm = nl > 0.0 ? Vec3d(nrm / nl) : Vec3d(0.0, 0.0, 1.0);
            const double nv[3] = {nrm[0], nrm[1], nrm[2]};
            double t_sum[3] = {0.0, 0.0, 0.0};
            double sign_sum = 0.0;
            auto add = [&](const CornerTerm& term, double sign) {
                if (!(term.angle > 0.0) || !(term.tl > 0.0) || !std::isfinite(term.tl)) return;
                const double weight = term.angle / term.tl;
                for (int i = 0; i < 3; ++i) t_sum[i] += weight * term.tp[i];
                sign_sum += term.angle * sign;
            };
            // The corners of a UV triangle: its three positions from this vertex on, and its face record.
            const float* corner_points[2][3];
            const FaceTangent* corner_face[2];
            int pending = 0;
            for (uint32_t k = with_uv ? start[vi] : 0; with_uv && k < start[vi + 1]; ++k) {
                const uint32_t corner = order[k], c = corner % 3;
                const FaceTangent& ft = face[corner / 3];
                if (ft.sign == 0.0) continue;
                const uint32_t* f = &mesh.indices[corner - c];
                corner_points[pending][0] = position + 3 * size_t(f[c]);
                corner_points[pending][1] = position + 3 * size_t(f[c == 2 ? 0 : c + 1]);
                corner_points[pending][2] = position + 3 * size_t(f[c == 0 ? 2 : c - 1]);
                corner_face[pending] = &ft;
#if defined(__SSE2__)
                if (++pending < 2) continue;
                pending = 0;
                const double* dpdu[2] = {corner_face[0]->dpdu, corner_face[1]->dpdu};
                CornerTerm terms[2];
                corner_terms2(corner_points, dpdu, nv, terms);
                add(terms[0], corner_face[0]->sign);
                add(terms[1], corner_face[1]->sign);
#else
                CornerTerm term;
                corner_term(corner_points[0][0], corner_points[0][1], corner_points[0][2], ft.dpdu, nv, term);
                add(term, ft.sign);
#endif
            }
            if (pending == 1) {
                CornerTerm term;
                corner_term(corner_points[0][0], corner_points[0][1], corner_points[0][2], corner_face[0]->dpdu, nv, term);
                add(term, corner_face[0]->sign);
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
