// CurvatureEstimator::Patch: the shape operator of the shading-normal field (Rusinkiewicz 2004, as the
// shape-operator estimator computes per face), aggregated at each curvature group over the faces of the
// smooth patch the group belongs to rather than over all of its one-ring.
//
// Why: the run-time kernel interpolates the per-vertex operator across each face, so a vertex value has to
// describe the faces that interpolate it. Where a one-ring holds faces of very different gradient (a lip of
// a few steep faces beside a gently curved dome), the area average carries the steep faces into every
// dome face touching that vertex and widens their highlight by the square of the ratio (measured on
// IridescentDishWithOlives' glass cover: vertex |k1| median 24/m against its faces' 15.8/m; docs/accuracy.md).
// Here each face's weight is its mixed-Voronoi area times min(1, m_med / m_f)^2, where m_f is the face
// operator's Frobenius norm (rotation invariant) and m_med the area-weighted median of m over the group's
// faces: faces steeper than the one-ring's majority count as little as their share of the squared gradient
// the majority would give them (a Cauchy-type robust weight with the median as its scale, no constant of
// its own), faces at or below the median keep their full weight. Where the one-ring is one smooth patch
// (every m_f near m_med) this is shape-operator's average; where it is two, the vertex takes the
// majority's. The faces of the minority then interpolate a smaller kernel than their own gradient, which
// filters less there (never more than the majority patch's gradient warrants).
//
// Each face operator is expressed in the group frame after rotating the face's frame into the group's
// tangent plane (Rusinkiewicz 2004 Sec. 4), as shape-operator does.
//
// Layout for speed: the per-face least squares is shape-operator's, four faces at a time
// (curvature_face_fit.h). m_med needs all of a group's faces before any can be weighted, so the faces are
// fitted twice: a first pass keeps each face's m_f and corner areas, a pass over the groups (their corners
// listed by detail::group_corners) takes each group's median, four groups at a time through a sorting
// network on (m_f, area) without branches, and a second pass over the faces fits them again (cheaper than
// storing every corner's operator), weighs each corner and adds it to its group's sums in corner order as
// shape-operator does, so the result does not depend on the thread count.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "mesh/curvature.h"
#include "mesh/curvature_face_fit.h"
#include "mesh/curvature_frames.h"
#include "mesh/scratch_array.h"

namespace specbake {

namespace {

using namespace lanes;

// A face's operator norm m_f = sqrt(a^2 + 2 b^2 + c^2) (-1 for a face that carries no information) and the
// mixed-Voronoi areas of its corners.
struct FaceMagnitude {
    double m, w[3];
};

SPECBAKE_INLINE v4d magnitude4(const FaceFit4& fit) {
    return sqrt4(fit.sa * fit.sa + 2.0 * fit.sb * fit.sb + fit.sc * fit.sc);
}

// The faces [begin, end), four at a time (curvature_face_fit.h): m_f and the corner areas of each.
SPECBAKE_AVX2_CLONES void face_magnitudes(const FaceInput& in, size_t begin, size_t end, FaceMagnitude* out) {
    for (size_t t = begin; t < end; t += kLanes) {
        const int lanes = int(std::min<size_t>(kLanes, end - t));
        FaceFit4 fit;
        fit_faces4(in, t, lanes, fit);
        const v4d m = fit.usable ? magnitude4(fit) : splat(-1.0);
        for (int l = 0; l < lanes; ++l) out[t + size_t(l)] = {m[l], {fit.w[0][l], fit.w[1][l], fit.w[2][l]}};
    }
}

// A group's faces (m_f, corner area).
struct Entry {
    double m, w;
};

// The area-weighted median m_med of a group's entries: the first m, in increasing order of (m, w) (as
// std::sort orders the pairs), at which the areas accumulated in that order reach half the total (the
// areas summed in corner order).
double weighted_median(Entry* x, size_t n, double total) {
    std::sort(x, x + n, [](const Entry& p, const Entry& q) { return p.m < q.m || (p.m == q.m && p.w < q.w); });
    double acc = 0.0;
    for (size_t i = 0; i < n; ++i) {
        acc += x[i].w;
        if (acc >= 0.5 * total) return x[i].m;
    }
    return x[n - 1].m;
}

// weighted_median of four groups at once, one per lane, each of up to kSorted entries (m[k], w[k]: entry k
// of each lane; lanes with fewer entries padded with m = +inf, w = 0, which sort last and add nothing): a
// sorting network on (m, w), then the accumulation in that order, without branches.
constexpr int kSorted = 8;
SPECBAKE_INLINE v4d weighted_median4(v4d (&m)[kSorted], v4d (&w)[kSorted], v4d total) {
    static constexpr int kNetwork[19][2] = {{0, 2}, {1, 3}, {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6},
                                            {3, 7}, {0, 1}, {2, 3}, {4, 5}, {6, 7}, {2, 4}, {3, 5},
                                            {1, 4}, {3, 6}, {1, 2}, {3, 4}, {5, 6}};
#pragma GCC unroll 19
    for (int c = 0; c < 19; ++c) {
        const int i = kNetwork[c][0], j = kNetwork[c][1];
        const v4l swap = (m[j] < m[i]) | ((m[j] == m[i]) & (w[j] < w[i]));
        const v4d mi = m[i], wi = w[i];
        m[i] = swap ? m[j] : mi;
        w[i] = swap ? w[j] : wi;
        m[j] = swap ? mi : m[j];
        w[j] = swap ? wi : w[j];
    }
    const v4d half = 0.5 * total;
    v4d acc = splat(0.0), median = splat(0.0), largest = splat(0.0);
    v4l reached = acc != acc;  // all false
#pragma GCC unroll 8
    for (int k = 0; k < kSorted; ++k) {
        acc += w[k];
        const v4l here = ~reached & (acc >= half);
        median = here ? m[k] : median;
        reached |= here;
        largest = m[k] < HUGE_VAL ? m[k] : largest;
    }
    return reached ? median : largest;  // as weighted_median, should the accumulated areas stop short of half
}

// m_med of groups [begin, end) from their faces' m_f and corner areas (0 for a group without area), four
// groups at a time; a group of more than kSorted usable faces on its own.
SPECBAKE_AVX2_CLONES void group_medians(const detail::GroupCorners& lists, const FaceMagnitude* faces,
                                        uint32_t begin, uint32_t end, double* median) {
    std::vector<Entry> many;
    for (uint32_t g0 = begin; g0 < end; g0 += kLanes) {
        const int lanes = int(std::min<uint32_t>(kLanes, end - g0));
        double m[kSorted][kLanes], w[kSorted][kLanes], total[kLanes];
        bool large[kLanes] = {false, false, false, false};
        for (int l = 0; l < kLanes; ++l) {
            for (int k = 0; k < kSorted; ++k) {
                m[k][l] = HUGE_VAL;
                w[k][l] = 0.0;
            }
            total[l] = 0.0;
            if (l >= lanes) continue;
            const uint32_t g = g0 + uint32_t(l), first = lists.start[g], last = lists.start[g + 1];
            int n = 0;
            for (uint32_t k = first; k < last; ++k) {
                const uint32_t corner = lists.order[k];
                const FaceMagnitude& face = faces[corner / 3];
                if (face.m < 0.0) continue;
                if (n < kSorted) {
                    m[n][l] = face.m;
                    w[n][l] = face.w[corner % 3];
                }
                ++n;
                total[l] += face.w[corner % 3];
            }
            large[l] = n > kSorted;
        }
        v4d mv[kSorted], wv[kSorted];
        for (int k = 0; k < kSorted; ++k) {
            std::memcpy(&mv[k], m[k], sizeof mv[k]);
            std::memcpy(&wv[k], w[k], sizeof wv[k]);
        }
        v4d t;
        std::memcpy(&t, total, sizeof t);
        const v4d med = weighted_median4(mv, wv, t);
        for (int l = 0; l < lanes; ++l) {
            const uint32_t g = g0 + uint32_t(l);
            if (!(total[l] > 0.0)) {
                median[g] = 0.0;
            } else if (!large[l]) {
                median[g] = med[l];
            } else {
                many.clear();
                for (uint32_t k = lists.start[g]; k < lists.start[g + 1]; ++k) {
                    const uint32_t corner = lists.order[k];
                    const FaceMagnitude& face = faces[corner / 3];
                    if (face.m >= 0.0) many.push_back({face.m, face.w[corner % 3]});
                }
                median[g] = weighted_median(many.data(), many.size(), total[l]);
            }
        }
    }
}

// The face pass over faces [begin, end), four at a time: each corner's operator in its group's frame
// (Rusinkiewicz 2004 Sec. 4), weighted by its area times min(1, m_med / m_f)^2, and that weight, added in
// corner order to its group's sums (add_corners).
SPECBAKE_AVX2_CLONES void weigh_faces(const FaceInput& in, const double* median, const uint32_t* first_chunk,
                                      uint32_t chunk, size_t begin, size_t end, detail::GroupSum* sums,
                                      std::vector<DeferredCorner<detail::GroupSum>>& deferred) {
    for (size_t t = begin; t < end; t += kLanes) {
        const int lanes = int(std::min<size_t>(kLanes, end - t));
        FaceFit4 fit;
        fit_faces4(in, t, lanes, fit);
        corner_groups4(in, fit);
        const v4d m = magnitude4(fit), zero = splat(0.0);
        detail::GroupSum shape[3][kLanes];  // (a, b, c, weight) of corner i of lane l
#pragma GCC unroll 3
        for (int i = 0; i < 3; ++i) {
            const v4d med = {median[fit.group[i][0]], median[fit.group[i][1]], median[fit.group[i][2]],
                             median[fit.group[i][3]]};
            const v4d q = med / m;
            const v4l steeper = (m > med) & (m > 0.0);
            const v4d w = steeper ? fit.w[i] * (q * q) : fit.w[i];
            v4d a, b, c;
            operator_in_group4(fit, i, a, b, c);
            const v4d wa = fit.usable ? w * a : zero, wb = fit.usable ? w * b : zero,
                      wc = fit.usable ? w * c : zero, wu = fit.usable ? w : zero;
#pragma GCC unroll 4
            for (int l = 0; l < kLanes; ++l) shape[i][l] = {{wa[l], wb[l], wc[l], wu[l]}};
        }
        add_corners(fit.group, shape, lanes, first_chunk, chunk, sums, deferred);
    }
}

}  // namespace

VertexCurvature curvature_patch(const TriMesh& mesh, const WeldedTopology& topology) {
    // A zero normal stays zero here: its faces are fitted with it.
    const detail::FitNormals normals = detail::fit_normals(mesh, topology, true);
    const FaceInput input{mesh.indices.data(),   topology.position_id.data(), topology.group_id.data(),
                          mesh.positions.data(), normals.unit.data(),         normals.group.data()};
    const size_t faces = mesh.triangle_count();
    const uint32_t groups = topology.group_count;

    // m_med of each group, from m_f and the corner areas of its faces.
    detail::ScratchArray<double> median(groups);
    {
        const detail::GroupCorners lists = detail::group_corners(mesh, topology);
        detail::ScratchArray<FaceMagnitude> magnitude(faces);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, faces, 4096), [&](const auto& range) {
            face_magnitudes(input, range.begin(), range.end(), magnitude.data());
        });
        tbb::parallel_for(tbb::blocked_range<uint32_t>(0, groups, 4096), [&](const auto& range) {
            group_medians(lists, magnitude.data(), range.begin(), range.end(), median.data());
        });
    }

    // The faces fitted again (cheaper than keeping each corner's operator), weighted and summed per group.
    detail::ScratchArray<detail::GroupSum> sums(groups);
    sum_corners_in_order<detail::GroupSum>(
        mesh, topology, sums.data(),
        [&](const uint32_t* first_chunk, uint32_t chunk, size_t begin, size_t end,
            std::vector<DeferredCorner<detail::GroupSum>>& deferred) {
            weigh_faces(input, median.data(), first_chunk, chunk, begin, end, sums.data(), deferred);
        });
    return detail::vertex_curvature_from_sums(mesh, topology, sums.data(), normals.group.data());
}

}  // namespace specbake
