#include "mesh/curvature.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

namespace specbake {
namespace {

std::string label(const TriMesh& mesh) { return mesh.name.empty() ? std::string("mesh") : mesh.name; }

// Smallest i in [0, n) with bad(i), or n: in parallel, the same answer for any thread count.
template <class Bad>
size_t first_bad(size_t n, const Bad& bad) {
    return tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, n, 1 << 16), n,
        [&](const tbb::blocked_range<size_t>& r, size_t found) {
            for (size_t i = r.begin(); i != r.end() && i < found; ++i)
                if (bad(i)) return i;
            return found;
        },
        [](size_t a, size_t b) { return std::min(a, b); });
}

bool all_finite(const std::vector<float>& values) {
    return first_bad(values.size(), [&](size_t i) { return !std::isfinite(values[i]); }) == values.size();
}

// Checks the inputs, welds unless `shared` is given and runs the estimator, on options.max_threads threads.
Result<VertexCurvature> estimate(const TriMesh& mesh, const WeldedTopology* shared, CurvatureEstimator estimator,
                                 const CurvatureOptions& options) {
    const std::string name = label(mesh);
    const size_t n = mesh.vertex_count();
    if (mesh.positions.size() % 3 != 0 || n == 0 || mesh.indices.empty() || mesh.indices.size() % 3 != 0)
        return make_error(name + ": no triangles (or malformed position/index arrays)");
    if (!mesh.has_normals()) return make_error(name + ": curvature needs vertex normals (see prepare_mesh.h)");
    if (!mesh.has_tangents()) return make_error(name + ": curvature needs vertex tangents (see prepare_mesh.h)");
    if (options.jet_degree < 2 || options.jet_degree > 4)
        return make_error(name + ": jet fitting degree must be 2..4, got " + std::to_string(options.jet_degree));
    if (shared && (shared->position_id.size() != n || shared->group_id.size() != n))
        return make_error(name + ": the welded topology given is not of this mesh");

    // An arena of its own only for a thread count other than the caller's: work in a new arena reaches the
    // workers only as they migrate into it, so a worker finishing the caller's other work (the topology
    // report beside this estimate) may sit idle while this thread runs the face pass alone.
    const int threads = options.max_threads > 0 ? options.max_threads : tbb::this_task_arena::max_concurrency();
    std::optional<tbb::task_arena> own_arena;
    if (threads != tbb::this_task_arena::max_concurrency()) own_arena.emplace(threads);
    auto in_arena = [&](const auto& work) {
        if (own_arena) own_arena->execute(work);
        else work();
    };
    size_t bad_index = 0;
    bool finite = true;
    in_arena([&] {
        bad_index = first_bad(mesh.indices.size(), [&](size_t k) { return mesh.indices[k] >= n; });
        finite = all_finite(mesh.positions) && all_finite(mesh.normals) && all_finite(mesh.tangents);
    });
    if (bad_index < mesh.indices.size())
        return make_error(name + ": index " + std::to_string(mesh.indices[bad_index]) + " out of range");
    if (!finite) return make_error(name + ": non-finite position, normal or tangent (run validate_mesh first)");

    VertexCurvature out;
    size_t bad_vertex = n;
    in_arena([&] {
        WeldedTopology own;
        if (!shared) own = weld_by_position(mesh, options.weld);
        const WeldedTopology& topology = shared ? *shared : own;
        switch (estimator) {
            case CurvatureEstimator::ShapeOperator: out = curvature_shape_operator(mesh, topology); break;
            case CurvatureEstimator::JetFitting:
                out = curvature_jet_fitting(mesh, topology, options.jet_degree, std::max(options.jet_min_points, 6));
                break;
            case CurvatureEstimator::NormalCone: out = curvature_normal_cone(mesh, topology); break;
            case CurvatureEstimator::SecondOrder: out = curvature_second_order(mesh, topology); break;
            case CurvatureEstimator::Patch: out = curvature_patch(mesh, topology); break;
        }
        bad_vertex = first_bad(4 * n, [&](size_t k) { return !std::isfinite(out.values[k]); }) / 4;
    });
    if (bad_vertex < n)
        return make_error(name + ": " + std::string(to_string(estimator)) +
                          " produced a non-finite curvature at vertex " + std::to_string(bad_vertex));
    return out;
}

}  // namespace

std::string_view to_string(CurvatureEstimator estimator) {
    switch (estimator) {
        case CurvatureEstimator::ShapeOperator: return "shape-operator";
        case CurvatureEstimator::JetFitting: return "jet-fitting";
        case CurvatureEstimator::NormalCone: return "normal-cone";
        case CurvatureEstimator::SecondOrder: return "second-order";
        case CurvatureEstimator::Patch: return "patch";
    }
    return "unknown";
}

std::optional<CurvatureEstimator> parse_curvature_estimator(std::string_view name) {
    for (CurvatureEstimator e : {CurvatureEstimator::ShapeOperator, CurvatureEstimator::JetFitting,
                                 CurvatureEstimator::NormalCone, CurvatureEstimator::SecondOrder,
                                 CurvatureEstimator::Patch}) {
        if (name == to_string(e)) return e;
    }
    return std::nullopt;
}

Result<VertexCurvature> estimate_curvature(const TriMesh& mesh, CurvatureEstimator estimator,
                                           const CurvatureOptions& options) {
    return estimate(mesh, nullptr, estimator, options);
}

Result<VertexCurvature> estimate_curvature(const TriMesh& mesh, const WeldedTopology& topology,
                                           CurvatureEstimator estimator, const CurvatureOptions& options) {
    return estimate(mesh, &topology, estimator, options);
}

}  // namespace specbake
