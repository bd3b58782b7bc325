#include "mesh/curvature_summary.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace specbake {

CurvatureSummary summarize_curvature(const TriMesh& mesh, const VertexCurvature& curvature) {
    CurvatureSummary s;
    const size_t n = mesh.vertex_count();
    if (n == 0 || curvature.values.size() != 4 * n) return s;
    float lo[3] = {mesh.positions[0], mesh.positions[1], mesh.positions[2]};
    float hi[3] = {lo[0], lo[1], lo[2]};
    for (size_t v = 0; v < n; ++v)
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], mesh.positions[3 * v + k]);
            hi[k] = std::max(hi[k], mesh.positions[3 * v + k]);
        }
    s.bbox_diagonal = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                (hi[2] - lo[2]) * (hi[2] - lo[2]));

    std::vector<char> used(n, 0);
    for (uint32_t i : mesh.indices)
        if (i < n) used[i] = 1;
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
