#include "mesh/curvature_summary.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <vector>

namespace specbake {
namespace {

struct Box {
    float lo[3], hi[3];
};

}  // namespace

CurvatureSummary summarize_curvature(const TriMesh& mesh, const VertexCurvature& curvature) {
    CurvatureSummary s;
    const size_t n = mesh.vertex_count();
    if (n == 0 || curvature.values.size() != 4 * n) return s;
    // Bounding box, used vertices and the |k1| list in parallel: minima, maxima and flags do not depend on
    // the order they are gathered in, and the list keeps vertex order.
    const float* p = mesh.positions.data();
    const Box first{{p[0], p[1], p[2]}, {p[0], p[1], p[2]}};
    const Box box = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, n, 16384), first,
        [&](const tbb::blocked_range<size_t>& r, Box b) {
            for (size_t v = r.begin(); v != r.end(); ++v)
                for (int k = 0; k < 3; ++k) {
                    b.lo[k] = std::min(b.lo[k], p[3 * v + k]);
                    b.hi[k] = std::max(b.hi[k], p[3 * v + k]);
                }
            return b;
        },
        [](Box a, const Box& b) {
            for (int k = 0; k < 3; ++k) {
                a.lo[k] = std::min(a.lo[k], b.lo[k]);
                a.hi[k] = std::max(a.hi[k], b.hi[k]);
            }
            return a;
        });
    const float d[3] = {box.hi[0] - box.lo[0], box.hi[1] - box.lo[1], box.hi[2] - box.lo[2]};
    s.bbox_diagonal = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);

    // Several corners may mark one vertex at once: relaxed atomic stores of the same value.
    std::vector<char> used(n, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.indices.size(), 65536), [&](const auto& r) {
        for (size_t k = r.begin(); k != r.end(); ++k)
            if (const uint32_t i = mesh.indices[k]; i < n)
                std::atomic_ref<char>(used[i]).store(1, std::memory_order_relaxed);
    });
    std::vector<float> k1;
    k1.reserve(n);
    for (size_t v = 0; v < n; ++v)
        if (used[v]) k1.push_back(std::abs(curvature.values[4 * v]));
    if (k1.empty()) return s;
    s.max_abs_k1 = *std::max_element(k1.begin(), k1.end());
    const size_t rank = std::min(k1.size() - 1, size_t(std::ceil(0.95 * double(k1.size()))) - 1);
    std::nth_element(k1.begin(), k1.begin() + rank, k1.end());
    s.p95_abs_k1 = k1[rank];
    return s;
}

}  // namespace specbake
