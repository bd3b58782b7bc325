// Speed of the mesh stages on a generated 1M-triangle mesh (issue 4 item 7): Assimp import of a binary PLY
// written to a temporary file, preparation (validation + tangent generation) and its OpenMesh half-edge
// build (against building the same mesh face by face with OpenMesh's add_face), and curvature per estimator
// on 1 and 2 threads, with the welding they start with on its own. Goal for the default estimator: >= 2M
// faces/s on 2 threads.
// Usage: bench_mesh [--benchmark_filter=REGEX]  (see --help of Google Benchmark)
#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "io/mesh_import/mesh_import.h"
#include "mesh/curvature.h"
#include "mesh/generate_tangents.h"
#include "mesh/halfedge_mesh.h"
#include "mesh/prepare_mesh.h"
#include "mesh/procedural_shapes.h"

using namespace specbake;

namespace {

// Jittered torus, 1000 x 500 quads = 1,000,000 triangles (irregular, with seams in u and v).
const TriMesh& million() {
    static const TriMesh mesh = make_torus(3.0f, 1.0f, 1000, 500, 0.3f, 42);
    return mesh;
}

// 100,000-triangle version for the slow jet fitting.
const TriMesh& hundred_thousand() {
    static const TriMesh mesh = make_torus(3.0f, 1.0f, 316, 158, 0.3f, 42);
    return mesh;
}

// Binary little-endian PLY with positions, normals and UVs.
const std::string& million_ply() {
    static const std::string path = [] {
        const TriMesh& m = million();
        const std::filesystem::path p = std::filesystem::temp_directory_path() / "specbake_bench_mesh_1M.ply";
        std::ofstream f(p, std::ios::binary);
        f << "ply\nformat binary_little_endian 1.0\nelement vertex " << m.vertex_count()
          << "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\n"
             "property float nz\nproperty float s\nproperty float t\nelement face "
          << m.triangle_count() << "\nproperty list uchar uint vertex_indices\nend_header\n";
        for (size_t v = 0; v < m.vertex_count(); ++v) {
            f.write(reinterpret_cast<const char*>(&m.positions[3 * v]), 12);
            f.write(reinterpret_cast<const char*>(&m.normals[3 * v]), 12);
            f.write(reinterpret_cast<const char*>(&m.uv0[2 * v]), 8);
        }
        const unsigned char three = 3;
        for (size_t t = 0; t < m.triangle_count(); ++t) {
            f.write(reinterpret_cast<const char*>(&three), 1);
            f.write(reinterpret_cast<const char*>(&m.indices[3 * t]), 12);
        }
        return p.string();
    }();
    return path;
}

void BM_ImportPly1M(benchmark::State& state) {
    const std::string& path = million_ply();
    MeshImportOptions options;
    options.join = VertexJoin::Never;  // the file is indexed already
    for (auto _ : state) {
        Result<ImportedScene> scene = import_mesh(path, options);
        if (!scene) state.SkipWithError(scene.error().message.c_str());
        benchmark::DoNotOptimize(scene);
    }
    state.counters["faces/s"] =
        benchmark::Counter(double(million().triangle_count()) * double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ImportPly1M)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

void BM_Prepare1M(benchmark::State& state) {
    for (auto _ : state) {
        state.PauseTiming();
        TriMesh m = million();
        m.tangents.clear();
        state.ResumeTiming();
        Result<MeshReport> r = prepare_mesh_for_curvature(m);
        benchmark::DoNotOptimize(r);
    }
    state.counters["faces/s"] =
        benchmark::Counter(double(million().triangle_count()) * double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Prepare1M)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

WeldedTopology million_positions() {
    WeldOptions by_position;
    by_position.split_by_normals = false;
    return weld_by_position(million(), by_position);
}

void BM_HalfEdgeMesh1M(benchmark::State& state) {
    const WeldedTopology positions = million_positions();
    for (auto _ : state) {
        HalfEdgeTopology h = build_halfedge_mesh(million(), positions);
        benchmark::DoNotOptimize(h.mesh.n_faces());
    }
    state.counters["faces/s"] =
        benchmark::Counter(double(million().triangle_count()) * double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_HalfEdgeMesh1M)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

// The same topology through OpenMesh's add_face, one face at a time (the mesh is manifold, so no face is
// refused): what build_halfedge_mesh is measured against.
void BM_HalfEdgeMeshByAddFace1M(benchmark::State& state) {
    const TriMesh& m = million();
    const WeldedTopology positions = million_positions();
    for (auto _ : state) {
        HalfEdgeMesh h;
        h.reserve(positions.position_count, 3 * m.triangle_count() / 2, m.triangle_count());
        std::vector<HalfEdgeMesh::VertexHandle> vh(positions.position_count);
        std::vector<char> made(positions.position_count, 0);
        for (size_t v = 0; v < m.vertex_count(); ++v) {
            const uint32_t p = positions.position_id[v];
            if (made[p]) continue;
            made[p] = 1;
            vh[p] = h.add_vertex(HalfEdgeMesh::Point(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]));
        }
        for (size_t t = 0; t < m.triangle_count(); ++t)
            h.add_face(vh[positions.position_id[m.indices[3 * t]]], vh[positions.position_id[m.indices[3 * t + 1]]],
                       vh[positions.position_id[m.indices[3 * t + 2]]]);
        benchmark::DoNotOptimize(h.n_faces());
    }
    state.counters["faces/s"] =
        benchmark::Counter(double(million().triangle_count()) * double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_HalfEdgeMeshByAddFace1M)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

void curvature(benchmark::State& state, const TriMesh& mesh, CurvatureEstimator estimator) {
    CurvatureOptions options;
    options.max_threads = int(state.range(0));
    for (auto _ : state) {
        Result<VertexCurvature> c = estimate_curvature(mesh, estimator, options);
        if (!c) state.SkipWithError(c.error().message.c_str());
        benchmark::DoNotOptimize(c);
    }
    state.counters["faces/s"] =
        benchmark::Counter(double(mesh.triangle_count()) * double(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_CurvatureShapeOperator1M(benchmark::State& state) { curvature(state, million(), CurvatureEstimator::ShapeOperator); }
void BM_CurvaturePatch1M(benchmark::State& state) { curvature(state, million(), CurvatureEstimator::Patch); }
void BM_CurvatureSecondOrder1M(benchmark::State& state) { curvature(state, million(), CurvatureEstimator::SecondOrder); }
void BM_CurvatureNormalCone1M(benchmark::State& state) { curvature(state, million(), CurvatureEstimator::NormalCone); }
void BM_CurvatureJetFitting100k(benchmark::State& state) {
    curvature(state, hundred_thousand(), CurvatureEstimator::JetFitting);
}
// The welding every estimator starts with (estimate_curvature includes it), on its own.
void BM_WeldForCurvature1M(benchmark::State& state) {
    tbb::task_arena arena(int(state.range(0)));
    for (auto _ : state) {
        arena.execute([&] {
            WeldedTopology w = weld_by_position(million());
            benchmark::DoNotOptimize(w.group_count);
        });
    }
    state.counters["faces/s"] =
        benchmark::Counter(double(million().triangle_count()) * double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_WeldForCurvature1M)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);
BENCHMARK(BM_CurvatureShapeOperator1M)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);
BENCHMARK(BM_CurvaturePatch1M)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);
BENCHMARK(BM_CurvatureSecondOrder1M)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);
BENCHMARK(BM_CurvatureNormalCone1M)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);
BENCHMARK(BM_CurvatureJetFitting100k)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

}  // namespace

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    std::error_code ec;
    std::filesystem::remove(std::filesystem::temp_directory_path() / "specbake_bench_mesh_1M.ply", ec);
    return 0;
}
