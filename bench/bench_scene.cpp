// End-to-end scene bake speed on a generated 1M-triangle mesh (a UV sphere, 500 x 1000 quads, as GLB):
// the whole `bake` (read, plan, curvature, tangents, write, manifest) against the floor of what any
// pipeline has to do with the same data, Assimp import plus tinygltf write, and the stages of the bake
// (import, preparation, preparation with the curvature beside it, curvature, write, hashing), at 1 and 2
// threads. Goal: whole bake within 2x of import + write. A second reference adds what the bake's output
// holds beyond the input: Assimp's own tangent step and an output GLB of the bake's size.
//
//   cmake --build build --target bench_scene && build/bench/bench_scene --benchmark_min_time=0.01 --benchmark_repetitions=3
#include "pipeline/scene_job.h"
#include "io/gltf/gltf_scene.h"
#include "io/files/sha256.h"
#include "mesh/curvature.h"
#include "mesh/generate_tangents.h"
#include "mesh/prepare_mesh.h"
#include "tests/io/procedural_gltf.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>
#include <tiny_gltf.h>

#include <filesystem>

namespace fs = std::filesystem;
using namespace specbake;

namespace {

constexpr int kRings = 500, kSegments = 1000;  // 2 * 500 * 1000 = 1M triangles

const fs::path& bench_dir() {
    static const fs::path dir = [] {
        fs::path d = fs::temp_directory_path() / "specbake_bench_scene";
        fs::create_directories(d / "in");
        return d;
    }();
    return dir;
}

using testing::append_accessor;

// Writes the sphere once (tinygltf), glossy metallic material, no tangents (the bake generates them).
const fs::path& sphere_glb() {
    static const fs::path path = [] {
        const fs::path p = bench_dir() / "in" / "sphere1m.glb";
        if (fs::exists(p)) return p;
        testing::write_procedural_model(p, {.sphere = true, .size = 1.0, .rings = kRings, .segments = kSegments,
                                            .roughness = 0.3, .metallic = 1.0, .minimal = true});
        return p;
    }();
    return path;
}

void BM_WholeBake(benchmark::State& state) {
    SceneJob job;
    job.scenes = {sphere_glb()};
    job.output_dir = bench_dir() / "out_bake";
    job.plan.threads = int(state.range(0));
    // As `specbake -j N` does: every TBB task (curvature, hashing beside the parse and the write) on N threads.
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, size_t(state.range(0)));
    for (auto _ : state) {
        auto outcome = run_scene_job(job);
        if (!outcome || !outcome->errors.empty() || outcome->manifest.outputs.empty() ||
            outcome->manifest.outputs[0].extra.value("curvature_primitives", 0) == 0) {
            state.SkipWithError("bake failed");
            return;
        }
    }
    state.counters["faces/s"] = benchmark::Counter(2.0 * kRings * kSegments, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_WholeBake)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// The reference: Assimp reads the same GLB, tinygltf writes its vertex data (positions, normals, uvs,
// indices) as a GLB. No analysis at all.
// With `output_sized`, Assimp also runs its tangent-space step (which SPEC Sec. 4 accepts for the tangents
// the bake generates) and the GLB written is as large as the bake's: the tangents, and one more VEC4 float
// attribute where the bake writes _SPECAA_CURVATURE (zeros here: Assimp computes no curvature).
void reference_import_and_write(benchmark::State& state, bool output_sized) {
    const fs::path out = bench_dir() / (output_sized ? "out_ref_sized" : "out_ref") / "sphere1m.glb";
    fs::create_directories(out.parent_path());
    for (auto _ : state) {
        Assimp::Importer importer;
        const unsigned steps = aiProcess_Triangulate | (output_sized ? aiProcess_CalcTangentSpace : 0u);
        const aiScene* ai = importer.ReadFile(sphere_glb().string(), steps);
        if (!ai || ai->mNumMeshes == 0 || (output_sized && !ai->mMeshes[0]->mTangents)) {
            state.SkipWithError("assimp failed");
            return;
        }
        const aiMesh* am = ai->mMeshes[0];
        const size_t nv = am->mNumVertices;
        tinygltf::Model m;
        m.asset.version = "2.0";
        m.buffers.emplace_back();
        std::vector<float> uv(nv * 2);
        for (size_t v = 0; v < nv; ++v) uv[2 * v] = am->mTextureCoords[0][v].x, uv[2 * v + 1] = am->mTextureCoords[0][v].y;
        std::vector<uint32_t> idx(size_t(am->mNumFaces) * 3);
        for (unsigned f = 0; f < am->mNumFaces; ++f)
            for (int k = 0; k < 3; ++k) idx[3 * f + k] = am->mFaces[f].mIndices[k];
        tinygltf::Primitive prim;
        prim.attributes["POSITION"] = append_accessor(m, am->mVertices, nv * 12, TINYGLTF_TYPE_VEC3,
                                          TINYGLTF_COMPONENT_TYPE_FLOAT, nv);
        prim.attributes["NORMAL"] = append_accessor(m, am->mNormals, nv * 12, TINYGLTF_TYPE_VEC3,
                                        TINYGLTF_COMPONENT_TYPE_FLOAT, nv);
        prim.attributes["TEXCOORD_0"] = append_accessor(m, uv.data(), uv.size() * 4, TINYGLTF_TYPE_VEC2, TINYGLTF_COMPONENT_TYPE_FLOAT,
                                            nv);
        if (output_sized) {
            // glTF TANGENT: xyz and the handedness w of the bitangent Assimp computed.
            std::vector<float> tangent(nv * 4);
            for (size_t v = 0; v < nv; ++v) {
                const aiVector3D& t = am->mTangents[v];
                const aiVector3D nb = am->mNormals[v] ^ t;
                const float w = nb * am->mBitangents[v] < 0.0f ? -1.0f : 1.0f;
                tangent[4 * v] = t.x, tangent[4 * v + 1] = t.y, tangent[4 * v + 2] = t.z, tangent[4 * v + 3] = w;
            }
            prim.attributes["TANGENT"] = append_accessor(m, tangent.data(), tangent.size() * 4, TINYGLTF_TYPE_VEC4,
                                             TINYGLTF_COMPONENT_TYPE_FLOAT, nv);
            const std::vector<float> same_size(nv * 4, 0.0f);
            prim.attributes["_SPECAA_CURVATURE"] = append_accessor(m, same_size.data(), same_size.size() * 4,
                                                       TINYGLTF_TYPE_VEC4, TINYGLTF_COMPONENT_TYPE_FLOAT, nv);
        }
        prim.indices = append_accessor(m, idx.data(), idx.size() * 4, TINYGLTF_TYPE_SCALAR, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, idx.size());
        tinygltf::Mesh mesh;
        mesh.primitives.push_back(prim);
        m.meshes.push_back(mesh);
        tinygltf::TinyGLTF writer;
        if (!writer.WriteGltfSceneToFile(&m, out.string(), true, true, false, true)) {
            state.SkipWithError("tinygltf write failed");
            return;
        }
    }
}
void BM_AssimpImportTinygltfWrite(benchmark::State& state) { reference_import_and_write(state, false); }
BENCHMARK(BM_AssimpImportTinygltfWrite)->Unit(benchmark::kMillisecond)->UseRealTime();
void BM_AssimpImportTangentsTinygltfWriteOutputSized(benchmark::State& state) { reference_import_and_write(state, true); }
BENCHMARK(BM_AssimpImportTangentsTinygltfWriteOutputSized)->Unit(benchmark::kMillisecond)->UseRealTime();

// Stages of the bake.
void BM_StageImport(benchmark::State& state) {
    for (auto _ : state) {
        auto scene = io::GltfScene::load(sphere_glb());
        auto mesh = scene->primitive_mesh({0, 0});
        benchmark::DoNotOptimize(mesh->positions.data());
    }
}
BENCHMARK(BM_StageImport)->Unit(benchmark::kMillisecond)->UseRealTime();

// Runs `step` (returning false on failure) on a fresh copy of the sphere's mesh per iteration, the copy
// untimed, at the benchmark's thread count.
template <class Step>
void on_fresh_meshes(benchmark::State& state, Step step) {
    auto scene = io::GltfScene::load(sphere_glb());
    const TriMesh source = std::move(*scene->primitive_mesh({0, 0}));
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, size_t(state.range(0)));
    for (auto _ : state) {
        state.PauseTiming();
        TriMesh mesh = source;
        state.ResumeTiming();
        if (!step(mesh)) {
            state.SkipWithError("stage failed");
            return;
        }
        benchmark::DoNotOptimize(mesh.tangents.data());
    }
    state.counters["faces/s"] = benchmark::Counter(double(source.triangle_count()), benchmark::Counter::kIsIterationInvariantRate);
}

// Validation with the topology report (weld + OpenMesh half-edge mesh) beside the tangent generation, as
// the bake runs it before the curvature.
void BM_StagePrepare(benchmark::State& state) {
    on_fresh_meshes(state, [](TriMesh& mesh) { return bool(prepare_mesh_for_curvature(mesh)); });
}
BENCHMARK(BM_StagePrepare)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// Tangent generation alone (MikkTSpace-style; the sphere has none).
void BM_StageTangents(benchmark::State& state) {
    on_fresh_meshes(state, [](TriMesh& mesh) {
        generate_tangents(mesh);
        return true;
    });
}
BENCHMARK(BM_StageTangents)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// Preparation and curvature as the bake runs them: one weld shared by the topology report and the estimate,
// the estimate beside the report.
void BM_StagePrepareAndCurvature(benchmark::State& state) {
    CurvatureOptions options;
    options.max_threads = int(state.range(0));
    on_fresh_meshes(state, [&](TriMesh& mesh) {
        Result<VertexCurvature> curvature = make_error("not estimated");
        PrepareOptions prepare;
        prepare.weld = options.weld;
        prepare.with_frames = [&](const TriMesh& m, const WeldedTopology& welded) {
            curvature = estimate_curvature(m, welded, CurvatureEstimator::ShapeOperator, options);
        };
        return prepare_mesh_for_curvature(mesh, prepare) && curvature;
    });
}
BENCHMARK(BM_StagePrepareAndCurvature)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_StageCurvature(benchmark::State& state) {
    auto scene = io::GltfScene::load(sphere_glb());
    TriMesh mesh = std::move(*scene->primitive_mesh({0, 0}));
    if (!prepare_mesh_for_curvature(mesh)) {
        state.SkipWithError("prepare failed");
        return;
    }
    CurvatureOptions options;
    options.max_threads = int(state.range(0));
    for (auto _ : state) {
        auto k = estimate_curvature(mesh, CurvatureEstimator::ShapeOperator, options);
        benchmark::DoNotOptimize(k->values.data());
    }
    state.counters["faces/s"] = benchmark::Counter(double(mesh.triangle_count()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_StageCurvature)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_StageWrite(benchmark::State& state) {
    auto scene = io::GltfScene::load(sphere_glb());
    const size_t n = scene->primitive_mesh({0, 0})->vertex_count();
    (void)scene->set_vertex_attribute({0, 0}, io::kCurvatureAttribute, std::vector<float>(4 * n, 1.0f), 4);
    (void)scene->set_vertex_attribute({0, 0}, "TANGENT", std::vector<float>(4 * n, 1.0f), 4);
    for (auto _ : state) {
        auto written = scene->write(bench_dir() / "out_write" / "sphere1m.glb");
        if (!written) {
            state.SkipWithError(written.error().message.c_str());
            return;
        }
    }
}
BENCHMARK(BM_StageWrite)->Unit(benchmark::kMillisecond)->UseRealTime();

// The content hashes the manifest needs, of the input GLB and the written output, on their own.
void BM_StageHash(benchmark::State& state) {
    const fs::path written = bench_dir() / "out_bake" / "sphere1m.glb";
    if (!fs::exists(written)) {
        state.SkipWithError("run BM_WholeBake first");
        return;
    }
    const std::vector<fs::path> files{sphere_glb(), written};
    for (auto _ : state) {
        auto hashes = io::sha256_files(files);
        benchmark::DoNotOptimize(hashes->data());
    }
    state.counters["bytes/s"] = benchmark::Counter(double(fs::file_size(files[0]) + fs::file_size(files[1])),
                                                   benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_StageHash)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
