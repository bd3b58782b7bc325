// Every shared glTF model through the scene bake: node/material/texture/extension counts and the bytes of
// every input attribute and index buffer are equal before and after, the output loads in tinygltf and in
// Assimp, and every added float is finite. Every file of assets/nasty through `specbake bake`: a clear
// one-line error naming the file or a bake whose outputs hold no NaN/Inf, never a crash.
#include "pipeline/scene_job.h"
#include "scene_test_util.h"

#include <assimp/Importer.hpp>
#include <assimp/scene.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

using namespace specbake;
using namespace scene_test;

namespace {

std::vector<fs::path> shared_scenes() {
    std::vector<fs::path> out;
    const fs::path assets = SPECBAKE_ASSETS_DIR;
    for (const char* folder : {"gltf", "meshes"}) {
        if (!fs::exists(assets / folder)) continue;
        for (const auto& e : fs::recursive_directory_iterator(assets / folder)) {
            const std::string ext = e.path().extension().string();
            if (e.is_regular_file() && (ext == ".gltf" || ext == ".glb")) out.push_back(e.path());
        }
    }
    std::sort(out.begin(), out.end());
    return out;
}

std::set<std::string> keys(const tinygltf::ExtensionMap& m) {
    std::set<std::string> k;
    for (const auto& [name, value] : m) k.insert(name);
    return k;
}

// `same_image_uris`: false for a GLB output, whose images are embedded (checked byte for byte instead).
void expect_preserved(const tinygltf::Model& in, const tinygltf::Model& out, const ScenePlan& plan,
                      const std::string& name, bool same_image_uris = true) {
    EXPECT_EQ(in.nodes.size(), out.nodes.size()) << name;
    EXPECT_EQ(in.materials.size(), out.materials.size()) << name;
    EXPECT_EQ(in.textures.size(), out.textures.size()) << name;
    EXPECT_EQ(in.images.size(), out.images.size()) << name;
    EXPECT_EQ(in.samplers.size(), out.samplers.size()) << name;
    EXPECT_EQ(in.meshes.size(), out.meshes.size()) << name;
    EXPECT_EQ(in.animations.size(), out.animations.size()) << name;
    EXPECT_EQ(in.skins.size(), out.skins.size()) << name;
    EXPECT_EQ(in.cameras.size(), out.cameras.size()) << name;
    EXPECT_EQ(in.extensionsRequired, out.extensionsRequired) << name;
    for (const std::string& e : in.extensionsUsed)
        EXPECT_NE(std::find(out.extensionsUsed.begin(), out.extensionsUsed.end(), e), out.extensionsUsed.end())
            << name << ": " << e;
    EXPECT_EQ(keys(in.extensions), [&] {
        auto k = keys(out.extensions);
        k.erase("SPECBAKE_specular_aa");
        return k;
    }()) << name;
    for (size_t i = 0; i < std::min(in.nodes.size(), out.nodes.size()); ++i) {
        EXPECT_EQ(in.nodes[i].matrix, out.nodes[i].matrix) << name;
        EXPECT_EQ(in.nodes[i].translation, out.nodes[i].translation) << name;
        EXPECT_EQ(in.nodes[i].rotation, out.nodes[i].rotation) << name;
        EXPECT_EQ(in.nodes[i].scale, out.nodes[i].scale) << name;
        EXPECT_EQ(in.nodes[i].children, out.nodes[i].children) << name;
        EXPECT_EQ(in.nodes[i].mesh, out.nodes[i].mesh) << name;
    }
    for (size_t i = 0; i < std::min(in.materials.size(), out.materials.size()); ++i) {
        auto k = keys(out.materials[i].extensions);
        k.erase("SPECBAKE_specular_aa");
        EXPECT_EQ(keys(in.materials[i].extensions), k) << name << " material " << i;
        EXPECT_EQ(in.materials[i].normalTexture.index, out.materials[i].normalTexture.index);
        EXPECT_EQ(keys(in.materials[i].normalTexture.extensions), keys(out.materials[i].normalTexture.extensions));
        EXPECT_EQ(in.materials[i].pbrMetallicRoughness.roughnessFactor,
                  out.materials[i].pbrMetallicRoughness.roughnessFactor);
    }
    for (size_t i = 0; i < std::min(in.images.size(), out.images.size()) && same_image_uris; ++i)
        EXPECT_EQ(in.images[i].uri, out.images[i].uri);

    std::set<std::pair<int, int>> repaired_normals;
    for (const CurvatureDecision& d : plan.primitives)
        if (d.repairs_normals) repaired_normals.insert({d.ref.mesh, d.ref.primitive});
    for (size_t m = 0; m < std::min(in.meshes.size(), out.meshes.size()); ++m) {
        ASSERT_EQ(in.meshes[m].primitives.size(), out.meshes[m].primitives.size()) << name;
        for (size_t p = 0; p < in.meshes[m].primitives.size(); ++p) {
            const tinygltf::Primitive& a = in.meshes[m].primitives[p];
            const tinygltf::Primitive& b = out.meshes[m].primitives[p];
            for (const auto& [attr, acc] : a.attributes) {
                if (attr == "NORMAL" && repaired_normals.count({int(m), int(p)})) continue;
                ASSERT_TRUE(b.attributes.count(attr)) << name << ": " << attr;
                EXPECT_EQ(accessor_bytes(in, acc), accessor_bytes(out, b.attributes.at(attr)))
                    << name << " mesh " << m << " primitive " << p << " " << attr;
            }
            if (a.indices >= 0) EXPECT_EQ(accessor_bytes(in, a.indices), accessor_bytes(out, b.indices)) << name;
            for (const char* added : {"_SPECAA_CURVATURE", "TANGENT", "NORMAL"}) {
                auto it = b.attributes.find(added);
                if (it == b.attributes.end()) continue;
                for (float v : float_accessor(out, it->second)) ASSERT_TRUE(std::isfinite(v)) << name << " " << added;
            }
        }
    }
}

}  // namespace

TEST(SceneRoundTrip, EverySharedModel) {
    const std::vector<fs::path> scenes = shared_scenes();
    if (scenes.empty()) GTEST_SKIP() << "no shared glTF models under " << SPECBAKE_ASSETS_DIR;
    for (const fs::path& scene : scenes) {
        SCOPED_TRACE(scene.string());
        const fs::path out_dir = temp_dir("roundtrip_" + scene.stem().string());
        SceneJob job;
        job.scenes = {scene};
        job.output_dir = out_dir;
        job.texture_format.container = io::TextureContainer::Ktx2;
        auto outcome = run_scene_job(job);
        ASSERT_TRUE(outcome) << outcome.error().message;
        ASSERT_TRUE(outcome->errors.empty()) << outcome->errors[0];
        ASSERT_EQ(outcome->plans.size(), 1u);

        tinygltf::Model in, out;
        std::string err;
        ASSERT_TRUE(load_model(scene, in, err)) << err;
        const fs::path out_file = out_dir / scene.filename();
        ASSERT_TRUE(load_model(out_file, out, err)) << err;
        expect_preserved(in, out, outcome->plans[0], scene.filename().string());

        // Every file the scene references is in the output folder.
        for (const tinygltf::Image& img : out.images)
            if (!img.uri.empty() && img.uri.rfind("data:", 0) != 0) EXPECT_TRUE(fs::exists(out_dir / img.uri)) << img.uri;
        for (const tinygltf::Buffer& b : out.buffers)
            if (!b.uri.empty() && b.uri.rfind("data:", 0) != 0) EXPECT_TRUE(fs::exists(out_dir / b.uri)) << b.uri;

        Assimp::Importer importer;
        const aiScene* ai = importer.ReadFile(out_file.string(), 0);
        ASSERT_NE(ai, nullptr) << importer.GetErrorString();
        EXPECT_GT(ai->mNumMeshes, 0u);
        fs::remove_all(out_dir);
    }
}

// Every shared .gltf (external buffers and images) written as .glb: a single self-contained file with no
// external URI, every image's bytes equal to its input file, everything else preserved, loadable in both
// tinygltf and Assimp. Curvature only, so the test stays quick; embedding does not depend on the textures.
TEST(SceneRoundTrip, SharedGltfAsSelfContainedGlb) {
    std::vector<fs::path> scenes;
    for (const fs::path& s : shared_scenes())
        if (s.extension() == ".gltf") scenes.push_back(s);
    if (scenes.empty()) GTEST_SKIP() << "no shared .gltf models under " << SPECBAKE_ASSETS_DIR;
    for (const fs::path& scene : scenes) {
        SCOPED_TRACE(scene.string());
        const fs::path out_dir = temp_dir("glb_" + scene.stem().string());
        SceneJob job;
        job.scenes = {scene};
        job.output_dir = out_dir;
        job.format = SceneFormat::Glb;
        job.plan.textures = false;
        auto outcome = run_scene_job(job);
        ASSERT_TRUE(outcome) << outcome.error().message;
        ASSERT_TRUE(outcome->errors.empty()) << outcome->errors[0];

        tinygltf::Model in, out;
        std::string err;
        ASSERT_TRUE(load_model(scene, in, err)) << err;
        const fs::path out_file = out_dir / (scene.stem().string() + ".glb");
        ASSERT_TRUE(load_model(out_file, out, err)) << err;
        expect_preserved(in, out, outcome->plans[0], scene.filename().string(), false);
        ASSERT_LE(out.buffers.size(), 1u);
        for (const tinygltf::Buffer& b : out.buffers) EXPECT_TRUE(b.uri.empty()) << b.uri;
        ASSERT_EQ(in.images.size(), out.images.size());
        for (size_t i = 0; i < out.images.size(); ++i) {
            const tinygltf::Image& img = out.images[i];
            if (in.images[i].uri.rfind("data:", 0) == 0) continue;
            EXPECT_TRUE(img.uri.empty()) << img.uri;
            ASSERT_GE(img.bufferView, 0);
            EXPECT_FALSE(img.mimeType.empty());
            const tinygltf::BufferView& bv = out.bufferViews[size_t(img.bufferView)];
            const auto& data = out.buffers[size_t(bv.buffer)].data;
            const std::string embedded(data.begin() + long(bv.byteOffset), data.begin() + long(bv.byteOffset + bv.byteLength));
            EXPECT_EQ(embedded, slurp(scene.parent_path() / in.images[i].uri)) << in.images[i].uri;
        }
        // Nothing but the GLB and the manifest in the folder.
        for (const auto& e : fs::directory_iterator(out_dir)) {
            const std::string name = e.path().filename().string();
            EXPECT_TRUE(name == out_file.filename().string() || name == "manifest.json" || name == "stdout.txt" ||
                        name == "stderr.txt")
                << name;
        }
        Assimp::Importer importer;
        const aiScene* ai = importer.ReadFile(out_file.string(), 0);
        ASSERT_NE(ai, nullptr) << importer.GetErrorString();
        EXPECT_GT(ai->mNumMeshes, 0u);
        fs::remove_all(out_dir);
    }
}

TEST(SceneNasty, EveryFileGivesCleanErrorOrFiniteOutput) {
    const fs::path nasty = fs::path(SPECBAKE_ASSETS_DIR) / "nasty";
    if (!fs::exists(nasty)) GTEST_SKIP() << "shared nasty assets not found at " << nasty;
    std::vector<fs::path> files;
    for (const auto& e : fs::recursive_directory_iterator(nasty))
        if (e.is_regular_file()) files.push_back(e.path());
    std::sort(files.begin(), files.end());
    ASSERT_FALSE(files.empty());
    for (const fs::path& file : files) {
        SCOPED_TRACE(file.string());
        const fs::path dir = temp_dir("nasty_" + file.stem().string());
        const RunResult r = run_specbake({"bake", file.string(), "-o", (dir / "out").string(), "-q"}, dir);
        ASSERT_FALSE(r.signaled) << "crashed: " << r.err;
        ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 1) << "exit " << r.exit_code << ": " << r.err;
        if (r.exit_code != 0) {
            // One error line, naming the file.
            size_t errors = 0, pos = 0;
            while ((pos = r.err.find("specbake: error:", pos)) != std::string::npos) ++errors, ++pos;
            EXPECT_EQ(errors, 1u) << r.err;
            EXPECT_NE(r.err.find(file.filename().string()), std::string::npos) << r.err;
            EXPECT_FALSE(fs::exists(dir / "out" / (file.stem().string() + ".gltf"))) << "no half-written scene";
        } else {
            fs::path out_file;
            for (const auto& e : fs::directory_iterator(dir / "out"))
                if (e.path().extension() == ".gltf" || e.path().extension() == ".glb") out_file = e.path();
            ASSERT_FALSE(out_file.empty()) << r.err;
            tinygltf::Model out;
            std::string err;
            ASSERT_TRUE(load_model(out_file, out, err)) << err;
            for (const tinygltf::Mesh& m : out.meshes)
                for (const tinygltf::Primitive& p : m.primitives)
                    for (const auto& [attr, acc] : p.attributes) {
                        if (out.accessors[size_t(acc)].componentType != TINYGLTF_COMPONENT_TYPE_FLOAT) continue;
                        if (attr != "_SPECAA_CURVATURE" && attr != "TANGENT" && attr != "NORMAL") continue;
                        for (float v : float_accessor(out, acc)) ASSERT_TRUE(std::isfinite(v)) << attr;
                    }
            EXPECT_TRUE(fs::exists(dir / "out" / "manifest.json"));
        }
        fs::remove_all(dir);
    }
}
