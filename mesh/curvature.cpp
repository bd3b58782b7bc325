#include "mesh/curvature.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace specbake {
namespace {

std::string label(const TriMesh& mesh) { return mesh.name.empty() ? std::string("mesh") : mesh.name; }

bool all_finite(const std::vector<float>& values) {
    for (float x : values)
        if (!std::isfinite(x)) return false;
    return true;
}

}  // namespace

std::string_view to_string(CurvatureEstimator estimator) {
    switch (estimator) {
        case CurvatureEstimator::ShapeOperator: return "shape-operator";
        case CurvatureEstimator::JetFitting: return "jet-fitting";
        case CurvatureEstimator::NormalCone: return "normal-cone";
    }
    return "unknown";
}

std::optional<CurvatureEstimator> parse_curvature_estimator(std::string_view name) {
    for (CurvatureEstimator e :
         {CurvatureEstimator::ShapeOperator, CurvatureEstimator::JetFitting, CurvatureEstimator::NormalCone}) {
        if (name == to_string(e)) return e;
    }
    return std::nullopt;
}

Result<VertexCurvature> estimate_curvature(const TriMesh& mesh, CurvatureEstimator estimator,
                                           const CurvatureOptions& options) {
    const std::string name = label(mesh);
    const size_t n = mesh.vertex_count();
    if (mesh.positions.size() % 3 != 0 || n == 0 || mesh.indices.empty() || mesh.indices.size() % 3 != 0)
        return make_error(name + ": no triangles (or malformed position/index arrays)");
    if (!mesh.has_normals()) return make_error(name + ": curvature needs vertex normals (see prepare_mesh.h)");
    if (!mesh.has_tangents()) return make_error(name + ": curvature needs vertex tangents (see prepare_mesh.h)");
    for (uint32_t i : mesh.indices)
        if (i >= n) return make_error(name + ": index " + std::to_string(i) + " out of range");
    if (!all_finite(mesh.positions) || !all_finite(mesh.normals) || !all_finite(mesh.tangents))
        return make_error(name + ": non-finite position, normal or tangent (run validate_mesh first)");
    if (options.jet_degree < 2 || options.jet_degree > 4)
        return make_error(name + ": jet fitting degree must be 2..4, got " + std::to_string(options.jet_degree));

    const int threads = options.max_threads > 0 ? options.max_threads : tbb::this_task_arena::max_concurrency();
    tbb::task_arena arena(threads);
    VertexCurvature out;
    arena.execute([&] {
        const WeldedTopology topology = weld_by_position(mesh, options.weld);
        switch (estimator) {
            case CurvatureEstimator::ShapeOperator: out = curvature_shape_operator(mesh, topology); break;
            case CurvatureEstimator::JetFitting:
                out = curvature_jet_fitting(mesh, topology, options.jet_degree, std::max(options.jet_min_points, 6));
                break;
            case CurvatureEstimator::NormalCone: out = curvature_normal_cone(mesh, topology); break;
        }
    });
    for (size_t v = 0; v < n; ++v) {
        const float* c = &out.values[4 * v];
        if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || !std::isfinite(c[2]) || !std::isfinite(c[3]))
            return make_error(name + ": " + std::string(to_string(estimator)) +
                              " produced a non-finite curvature at vertex " + std::to_string(v));
    }
    return out;
}

}  // namespace specbake
