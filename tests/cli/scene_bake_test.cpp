// Scene bake end to end: curvature of a procedural sphere read back from the output (closed form +1/R),
// the plan's decisions (no normal map -> curvature only, rough -> none, flat -> none), the manifest, and
// refusing to write into the input's folder.
#include "pipeline/scene_job.h"
#include "io/output/manifest.h"
#include "scene_test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace specbake;
using namespace scene_test;

namespace {

int find_material_decision(const ScenePlan& plan, int material) {
    for (size_t i = 0; i < plan.textures.size(); ++i)
        if (plan.textures[i].material == material) return int(i);
    return -1;
}

}  // namespace

TEST(SceneBake, SphereCurvatureIsOneOverRadiusInOutput) {
    const fs::path dir = temp_dir("sphere");
    const double radius = 2.0;
    fs::create_directories(dir / "in");
    write_test_model(dir / "in" / "sphere.gltf", true, radius, 0.2);
    SceneJob job;
    job.scenes = {dir / "in" / "sphere.gltf"};
    job.output_dir = dir / "out";
    auto outcome = run_scene_job(job);
    ASSERT_TRUE(outcome) << outcome.error().message;
    ASSERT_TRUE(outcome->errors.empty()) << outcome->errors[0];

    tinygltf::Model in, out;
    std::string err;
    ASSERT_TRUE(load_model(dir / "in" / "sphere.gltf", in, err)) << err;
    ASSERT_TRUE(load_model(dir / "out" / "sphere.gltf", out, err)) << err;
    const tinygltf::Primitive& p = out.meshes[0].primitives[0];
    ASSERT_TRUE(p.attributes.count("_SPECAA_CURVATURE"));
    ASSERT_TRUE(p.attributes.count("TANGENT")) << "tangents are generated where missing";
    const std::vector<float> k = float_accessor(out, p.attributes.at("_SPECAA_CURVATURE"));
    const std::vector<float> pos = float_accessor(out, p.attributes.at("POSITION"));
    const std::vector<float> tan = float_accessor(out, p.attributes.at("TANGENT"));
    ASSERT_EQ(k.size() / 4, pos.size() / 3);
    double sum_sq = 0;
    size_t n = 0;
    for (size_t v = 0; v < pos.size() / 3; ++v) {
        for (int c = 0; c < 4; ++c) ASSERT_TRUE(std::isfinite(k[4 * v + c]));
        if (std::abs(pos[3 * v + 1]) > 0.9 * radius) continue;  // the poles' fans are a different tessellation
        const double expected = 1.0 / radius;  // closed form, outward normals: +1/R
        sum_sq += std::pow((k[4 * v] - expected) / expected, 2) + std::pow((k[4 * v + 1] - expected) / expected, 2);
        n += 2;
        EXPECT_NEAR(std::hypot(k[4 * v + 2], k[4 * v + 3]), 1.0, 1e-3);
        EXPECT_NEAR(std::abs(tan[4 * v + 3]), 1.0f, 1e-6f);
    }
    EXPECT_LT(std::sqrt(sum_sq / double(n)), 0.01) << "RMS relative error of k1, k2";
    // The input's attribute bytes are untouched in the output.
    for (const char* name : {"POSITION", "NORMAL", "TEXCOORD_0"})
        EXPECT_EQ(accessor_bytes(in, in.meshes[0].primitives[0].attributes.at(name)),
                  accessor_bytes(out, p.attributes.at(name)))
            << name;

    auto manifest = io::read_manifest(dir / "out" / "manifest.json");
    ASSERT_TRUE(manifest) << manifest.error().message;
    bool has_scene = false, has_buffer = false;
    for (const io::ManifestOutput& o : manifest->outputs) {
        has_scene |= o.kind == "scene" && o.path == "sphere.gltf";
        has_buffer |= o.kind == "buffer";
        EXPECT_EQ(o.sha256.size(), 64u);
    }
    EXPECT_TRUE(has_scene);
    EXPECT_TRUE(has_buffer);
    ASSERT_EQ(manifest->inputs.size(), 2u) << "the .gltf and its .bin";
    ASSERT_EQ(manifest->plan.size(), 1u);
    EXPECT_EQ(manifest->plan[0]["primitives"][0]["decision"], "curvature");
    EXPECT_NE(manifest->settings.dump().find("object"), std::string::npos) << "curvature space is stated";
    fs::remove_all(dir);
}

TEST(ScenePlan, NoNormalMapMeansCurvatureOnly) {
    const fs::path dir = temp_dir("plan_glossy");
    write_test_model(dir / "sphere.gltf", true, 1.0, 0.3, 24, 48);
    auto plan = plan_scene(dir / "sphere.gltf", PlanOptions{});
    ASSERT_TRUE(plan) << plan.error().message;
    ASSERT_EQ(plan->textures.size(), 1u);
    EXPECT_FALSE(plan->textures[0].bake);
    EXPECT_NE(plan->textures[0].reason.find("no normal texture"), std::string::npos);
    ASSERT_EQ(plan->primitives.size(), 1u);
    EXPECT_TRUE(plan->primitives[0].bake) << plan->primitives[0].reason;
    // Measured value of a sphere: p95 |k1| * diagonal = (1/R) * 2 sqrt(3) R = 3.46.
    ASSERT_TRUE(plan->primitives[0].relative_curvature);
    EXPECT_NEAR(*plan->primitives[0].relative_curvature, 2.0 * std::sqrt(3.0), 0.1);
    fs::remove_all(dir);
}

TEST(ScenePlan, RoughMaterialGetsNoCurvature) {
    const fs::path dir = temp_dir("plan_rough");
    write_test_model(dir / "sphere.gltf", true, 1.0, 0.95, 24, 48);
    auto plan = plan_scene(dir / "sphere.gltf", PlanOptions{});
    ASSERT_TRUE(plan) << plan.error().message;
    ASSERT_EQ(plan->primitives.size(), 1u);
    const CurvatureDecision& d = plan->primitives[0];
    EXPECT_FALSE(d.bake);
    EXPECT_NE(d.reason.find("too rough"), std::string::npos) << d.reason;
    // Independent evaluation of the measured value: a = 0.95^4, a' = (a + k(1-a)) / (1 + k(1-a)), k = 0.18.
    const double a = std::pow(0.95, 4), ap = (a + 0.18 * (1 - a)) / (1 + 0.18 * (1 - a));
    ASSERT_TRUE(d.roughness_gain);
    EXPECT_NEAR(*d.roughness_gain, std::pow(ap, 0.25) - 0.95, 1e-9);
    EXPECT_LT(*d.roughness_gain, d.roughness_gain_threshold);
    // `specbake mesh` does not look at the material.
    PlanOptions mesh_only;
    mesh_only.textures = false;
    mesh_only.check_material = false;
    auto forced = plan_scene(dir / "sphere.gltf", mesh_only);
    ASSERT_TRUE(forced) << forced.error().message;
    EXPECT_TRUE(forced->primitives[0].bake);
    fs::remove_all(dir);
}

TEST(ScenePlan, FlatPlaneGetsNoCurvature) {
    const fs::path dir = temp_dir("plan_flat");
    write_test_model(dir / "plane.gltf", false, 3.0, 0.1, 8, 8);
    auto plan = plan_scene(dir / "plane.gltf", PlanOptions{});
    ASSERT_TRUE(plan) << plan.error().message;
    const CurvatureDecision& d = plan->primitives[0];
    EXPECT_FALSE(d.bake);
    ASSERT_TRUE(d.relative_curvature);
    EXPECT_LT(*d.relative_curvature, 1e-6);
    EXPECT_NE(d.reason.find("do not curve"), std::string::npos) << d.reason;
    fs::remove_all(dir);
}

TEST(ScenePlan, SharedModelsDecisions) {
    const fs::path assets = SPECBAKE_ASSETS_DIR;
    if (!fs::exists(assets / "gltf")) GTEST_SKIP() << "shared assets not found at " << assets;
    {  // Suzanne: metallicRoughness texture but no normal map -> curvature only.
        auto plan = plan_scene(assets / "gltf/Suzanne/Suzanne.gltf", PlanOptions{});
        ASSERT_TRUE(plan) << plan.error().message;
        for (const TextureDecision& d : plan->textures) EXPECT_FALSE(d.bake) << d.reason;
        ASSERT_EQ(plan->primitives.size(), 1u);
        EXPECT_TRUE(plan->primitives[0].bake) << plan->primitives[0].reason;
    }
    {  // NormalTangentTest: a normal map on a glossy material -> texture bake and curvature on the bumps.
        auto plan = plan_scene(assets / "gltf/NormalTangentTest/NormalTangentTest.gltf", PlanOptions{});
        ASSERT_TRUE(plan) << plan.error().message;
        const int t = find_material_decision(*plan, 0);
        ASSERT_GE(t, 0);
        EXPECT_TRUE(plan->textures[size_t(t)].bake) << plan->textures[size_t(t)].reason;
        ASSERT_TRUE(plan->textures[size_t(t)].max_roughness_change);
        EXPECT_GE(*plan->textures[size_t(t)].max_roughness_change, plan->textures[size_t(t)].threshold);
    }
    {  // MetalRoughSpheresNoTextures: spheres (p95 |k1| x diagonal = 2 sqrt(3)) in a grid of roughness
       // values, and flat label glyphs without a material (glTF default roughness 1).
        const fs::path file = assets / "meshes/MetalRoughSpheresNoTextures/MetalRoughSpheresNoTextures.gltf";
        auto plan = plan_scene(file, PlanOptions{});
        ASSERT_TRUE(plan) << plan.error().message;
        for (const TextureDecision& d : plan->textures) EXPECT_FALSE(d.bake);
        size_t curved = 0, rough = 0;
        for (const CurvatureDecision& d : plan->primitives) {
            if (d.bake) {
                ++curved;
                EXPECT_NEAR(*d.relative_curvature, 2.0 * std::sqrt(3.0), 0.1) << d.label;
            } else if (d.reason.find("too rough") != std::string::npos) {
                ++rough;
                EXPECT_LT(*d.roughness_gain, d.roughness_gain_threshold);
            }
        }
        EXPECT_GT(curved, 0u);
        EXPECT_GT(rough, 0u);
        // Without the material check the glyphs are measured: flat, no curvature.
        PlanOptions mesh_only;
        mesh_only.textures = false;
        mesh_only.check_material = false;
        auto geometric = plan_scene(file, mesh_only);
        ASSERT_TRUE(geometric) << geometric.error().message;
        size_t flat = 0;
        for (const CurvatureDecision& d : geometric->primitives) {
            ASSERT_TRUE(d.relative_curvature) << d.label;
            if (!d.bake) {
                ++flat;
                EXPECT_LT(*d.relative_curvature, 1e-3) << d.label;
            }
        }
        EXPECT_GT(flat, 0u);
    }
}

TEST(SceneBakeCli, RefusesOutputFolderOfTheInput) {
    const fs::path dir = temp_dir("same_dir");
    write_test_model(dir / "sphere.gltf", true, 1.0, 0.2, 8, 16);
    const std::string before = slurp(dir / "sphere.gltf");
    const fs::path logs = temp_dir("same_dir_logs");
    const RunResult r = run_specbake({"bake", (dir / "sphere.gltf").string(), "-o", dir.string()}, logs);
    EXPECT_FALSE(r.signaled);
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.err.find("specbake: error:"), std::string::npos) << r.err;
    EXPECT_EQ(slurp(dir / "sphere.gltf"), before);
    EXPECT_FALSE(fs::exists(dir / "manifest.json"));
    fs::remove_all(dir);
    fs::remove_all(logs);
}

TEST(SceneBakeCli, PlanPrintsJsonWithReasonsAndHelpHasExamples) {
    const fs::path dir = temp_dir("plan_cli");
    write_test_model(dir / "plane.gltf", false, 1.0, 0.2, 4, 4);
    const RunResult r = run_specbake({"plan", (dir / "plane.gltf").string(), "--json"}, dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json j = nlohmann::json::parse(r.out);
    ASSERT_EQ(j.size(), 1u);
    EXPECT_EQ(j[0]["primitives"][0]["decision"], "skip");
    EXPECT_TRUE(j[0]["primitives"][0].contains("relative_curvature"));
    EXPECT_TRUE(j[0]["primitives"][0].contains("relative_curvature_threshold"));
    for (const char* cmd : {"bake", "mesh", "plan"}) {
        const RunResult h = run_specbake({cmd, "--help"}, dir);
        EXPECT_EQ(h.exit_code, 0);
        EXPECT_NE(h.out.find("Examples:"), std::string::npos) << cmd;
    }
    fs::remove_all(dir);
}

// OpenImageIO is a module loaded on first use (io/image/oiio_api.h). With the module made unfindable, commands
// that pass no image through it still work, and one that does fails with a clear error.
TEST(SceneBakeCli, OnlyImageWorkLoadsTheImageModule) {
    const fs::path dir = temp_dir("no_image_module");
    write_test_model(dir / "sphere.gltf", true, 1.0, 0.2, 8, 16);
    const fs::path missing = dir / "absent" / "libspecbake_oiio.so";
    ASSERT_EQ(::setenv("SPECBAKE_OIIO_MODULE", missing.c_str(), 1), 0);
    const RunResult bake = run_specbake({"bake", (dir / "sphere.gltf").string(), "-o", (dir / "out").string()}, dir);
    const RunResult plan = run_specbake({"plan", (dir / "sphere.gltf").string()}, dir);
    const RunResult shader = run_specbake({"shader", "--lang", "hlsl", "-o", (dir / "specaa.hlsl").string()}, dir);
    const RunResult inspect = run_specbake({"inspect", (dir / "out" / "manifest.json").string()}, dir);
    const RunResult texture = run_specbake({"texture", "--demo", "-o", (dir / "demo").string()}, dir);
    ::unsetenv("SPECBAKE_OIIO_MODULE");
    // The executable itself must not bring OpenImageIO in: the dynamic loader lists every library it maps.
    ASSERT_EQ(::setenv("LD_DEBUG", "files", 1), 0);
    const RunResult loaded = run_specbake({"--version"}, dir);
    ::unsetenv("LD_DEBUG");
    EXPECT_EQ(loaded.exit_code, 0) << loaded.err;
    EXPECT_NE(loaded.err.find("libtbb"), std::string::npos) << "the loader listed no libraries";
    EXPECT_EQ(loaded.err.find("libOpenImageIO"), std::string::npos) << "OpenImageIO is loaded at start-up";
    EXPECT_EQ(bake.exit_code, 0) << bake.err;
    EXPECT_TRUE(fs::exists(dir / "out" / "sphere.gltf"));
    EXPECT_EQ(plan.exit_code, 0) << plan.err;
    EXPECT_EQ(shader.exit_code, 0) << shader.err;
    EXPECT_EQ(inspect.exit_code, 0) << inspect.err;
    // The demo writes its input maps as PNG: that needs the module. Nothing is written.
    EXPECT_FALSE(texture.signaled);
    EXPECT_NE(texture.exit_code, 0);
    EXPECT_NE(texture.err.find("image support (OpenImageIO) is unavailable"), std::string::npos) << texture.err;
    EXPECT_NE(texture.err.find(missing.string()), std::string::npos) << texture.err;
    EXPECT_NE(texture.err.find("SPECBAKE_OIIO_MODULE"), std::string::npos) << texture.err;
    EXPECT_TRUE(!fs::exists(dir / "demo") || fs::is_empty(dir / "demo"));
    fs::remove_all(dir);
}
