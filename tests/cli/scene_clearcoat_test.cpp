// KHR_materials_clearcoat through the plan and the bake: the coat's normal texture is baked with the
// coat's roughness (SPEC Sec. 6 rules, one decision per layer), referenced from the vendor extension's
// "clearcoat" object; a glossy coat over a rough base makes the primitive glossy for the curvature rule.
// Checked on a generated sphere (the coarsest roughness mip against the closed form of SPEC Sec. 3 computed
// here from the normal map's texels) and on the shared ClearCoatTest model.
#include "pipeline/scene_job.h"
#include "io/image/image_io.h"
#include "io/output/manifest.h"
#include "scene_test_util.h"
#include "tests/io/procedural_images.h"

#include <assimp/Importer.hpp>
#include <assimp/scene.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>

using namespace specbake;
using namespace scene_test;
using nlohmann::json;

namespace {

constexpr int kMapSize = 64;

// Ripples along x and y: the normal map whose statistics the test computes independently.
Image ripple_normal_map() { return specbake::testing::sine_normal_map(kMapSize, 0.6, 0.3); }

// A glossy-coated sphere: base roughness 0.9 without a normal map, a coat of roughness `coat_roughness`
// with the ripple map as clearcoatNormalTexture.
fs::path write_coated_sphere(const fs::path& dir, double coat_factor, double coat_roughness) {
    const fs::path path = dir / "coated.gltf";
    write_test_model(path, true, 1.0, 0.9, 24, 48);
    EXPECT_TRUE(io::write_image(dir / "coat_normal.png", ripple_normal_map(), 8));
    std::ifstream in(path);
    json doc = json::parse(in);
    doc["images"] = {{{"uri", "coat_normal.png"}}};
    doc["textures"] = {{{"source", 0}}};
    doc["materials"][0]["extensions"]["KHR_materials_clearcoat"] = {
        {"clearcoatFactor", coat_factor},
        {"clearcoatRoughnessFactor", coat_roughness},
        {"clearcoatNormalTexture", {{"index", 0}}}};
    doc["extensionsUsed"] = {"KHR_materials_clearcoat"};
    std::ofstream(path) << doc.dump(2);
    return path;
}

const TextureDecision* decision(const ScenePlan& plan, int material, const std::string& layer) {
    for (const TextureDecision& d : plan.textures)
        if (d.material == material && d.layer == layer) return &d;
    return nullptr;
}

}  // namespace

TEST(SceneClearcoat, CoatNormalTextureIsPlannedWithCoatRoughness) {
    const fs::path dir = temp_dir("clearcoat_plan");
    auto plan = plan_scene(write_coated_sphere(dir, 1.0, 0.1), PlanOptions{});
    ASSERT_TRUE(plan) << plan.error().message;
    ASSERT_EQ(plan->textures.size(), 2u) << "base and clear coat";
    const TextureDecision* base = decision(*plan, 0, "base");
    const TextureDecision* coat = decision(*plan, 0, "clearcoat");
    ASSERT_TRUE(base && coat);
    EXPECT_FALSE(base->bake);
    EXPECT_NE(base->reason.find("no normal texture"), std::string::npos) << base->reason;
    EXPECT_TRUE(coat->bake) << coat->reason;
    EXPECT_EQ(coat->normal_image, 0);
    EXPECT_FALSE(coat->roughness_texture_used);
    EXPECT_FLOAT_EQ(coat->roughness_value, 0.1f);
    // Curvature: the base alone (r = 0.9) is too rough to alias, the coat (r = 0.1) is not.
    ASSERT_EQ(plan->primitives.size(), 1u);
    const CurvatureDecision& p = plan->primitives[0];
    EXPECT_TRUE(p.bake) << p.reason;
    ASSERT_TRUE(p.min_roughness);
    EXPECT_NEAR(*p.min_roughness, 0.1, 1e-9);
    fs::remove_all(dir);
}

TEST(SceneClearcoat, NoCoatWhenFactorIsZero) {
    const fs::path dir = temp_dir("clearcoat_zero");
    auto plan = plan_scene(write_coated_sphere(dir, 0.0, 0.1), PlanOptions{});
    ASSERT_TRUE(plan) << plan.error().message;
    const TextureDecision* coat = decision(*plan, 0, "clearcoat");
    ASSERT_TRUE(coat);
    EXPECT_FALSE(coat->bake);
    EXPECT_NE(coat->reason.find("no coat"), std::string::npos) << coat->reason;
    EXPECT_FALSE(plan->primitives[0].bake);
    EXPECT_NE(plan->primitives[0].reason.find("too rough"), std::string::npos) << plan->primitives[0].reason;
    fs::remove_all(dir);
}

TEST(SceneClearcoat, BakedCoatIsReferencedAndFiltered) {
    const fs::path dir = temp_dir("clearcoat_bake");
    const double coat_roughness = 0.1;
    SceneJob job;
    job.scenes = {write_coated_sphere(dir, 1.0, coat_roughness)};
    job.output_dir = dir / "out";
    job.texture_format.container = io::TextureContainer::PngPerMip;
    auto outcome = run_scene_job(job);
    ASSERT_TRUE(outcome) << outcome.error().message;
    ASSERT_TRUE(outcome->errors.empty()) << outcome->errors[0];

    std::ifstream in(dir / "out" / "coated.gltf");
    const json doc = json::parse(in);
    const json& ext = doc["materials"][0]["extensions"]["SPECBAKE_specular_aa"];
    EXPECT_FALSE(ext.contains("outputs")) << "the base layer was not baked";
    ASSERT_TRUE(ext.contains("clearcoat")) << ext.dump();
    const json& coat = ext["clearcoat"];
    EXPECT_EQ(coat["source"]["clearcoatNormalTexture"], 0);
    EXPECT_NEAR(coat["source"]["roughness"].get<double>(), coat_roughness, 1e-6);
    EXPECT_EQ(coat["roughnessChannel"], 0);
    EXPECT_EQ(coat["texCoord"], 0);
    ASSERT_FALSE(coat["outputs"].empty());
    for (const json& o : coat["outputs"]) EXPECT_TRUE(fs::exists(dir / "out" / o["uri"].get<std::string>())) << o;
    EXPECT_EQ(doc["materials"][0]["extensions"]["KHR_materials_clearcoat"]["clearcoatRoughnessFactor"], coat_roughness)
        << "the input's extension is kept";

    // Coarsest roughness mip (1x1, the whole map) against SPEC Sec. 3 evaluated here: projected normals of
    // the 8-bit texels as stored, Sigma = M - m m^T, t = tr(Sigma), a = (a_b + t(1 - a_b)) / (1 + t(1 - a_b)).
    auto stored = io::decode_image(dir / "coat_normal.png");
    ASSERT_TRUE(stored) << stored.error().message;
    double mx = 0, my = 0, mxx = 0, myy = 0;
    const size_t n = stored->image.texel_count();
    for (size_t i = 0; i < n; ++i) {
        const float* c = stored->image.pixels.data() + 3 * i;
        double v[3] = {2.0 * c[0] - 1.0, 2.0 * c[1] - 1.0, 2.0 * c[2] - 1.0};
        const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        mx += v[0] / len, my += v[1] / len, mxx += v[0] * v[0] / (len * len), myy += v[1] * v[1] / (len * len);
    }
    mx /= double(n), my /= double(n), mxx /= double(n), myy /= double(n);
    const double t = (mxx - mx * mx) + (myy - my * my);
    const double ab = std::pow(coat_roughness, 4.0);
    const double expected = std::pow((ab + t * (1 - ab)) / (1 + t * (1 - ab)), 0.25);

    auto manifest = io::read_manifest(dir / "out" / "manifest.json");
    ASSERT_TRUE(manifest) << manifest.error().message;
    const int last_mip = int(std::log2(kMapSize));
    std::string coarsest, finest;
    for (const io::ManifestOutput& o : manifest->outputs) {
        if (o.kind != "roughness" || o.path.find("clearcoat") == std::string::npos) continue;
        if (o.extra.value("mip_level", -1) == last_mip) coarsest = o.path;
        if (o.extra.value("mip_level", -1) == 0) finest = o.path;
    }
    ASSERT_FALSE(coarsest.empty()) << "the manifest lists the coat's roughness mips";
    auto top = io::decode_image(dir / "out" / coarsest);
    ASSERT_TRUE(top) << top.error().message;
    ASSERT_EQ(top->image.texel_count(), 1u);
    EXPECT_NEAR(top->image.pixels[0], expected, 1.5 / 255.0);
    EXPECT_GT(expected, coat_roughness + 0.1) << "the ripples must filter visibly for this test to mean anything";
    auto base_level = io::decode_image(dir / "out" / finest);
    ASSERT_TRUE(base_level) << base_level.error().message;
    EXPECT_NEAR(base_level->image.pixels[0], coat_roughness, 0.5 / 255.0 + 1e-6) << "mip 0 passes the coat roughness through";
    fs::remove_all(dir);
}

TEST(SceneClearcoat, SharedClearCoatTestModel) {
    const fs::path file = fs::path(SPECBAKE_ASSETS_DIR) / "gltf/ClearCoatTest/ClearCoatTest.gltf";
    if (!fs::exists(file)) GTEST_SKIP() << "shared asset not found: " << file;
    std::ifstream in(file);
    const json doc = json::parse(in);
    auto plan = plan_scene(file, PlanOptions{});
    ASSERT_TRUE(plan) << plan.error().message;
    size_t coats = 0, baked = 0;
    for (size_t m = 0; m < doc["materials"].size(); ++m) {
        const json& mat = doc["materials"][m];
        const TextureDecision* coat = decision(*plan, int(m), "clearcoat");
        if (!mat.contains("extensions") || !mat["extensions"].contains("KHR_materials_clearcoat")) {
            EXPECT_EQ(coat, nullptr) << "material " << m << " has no coat";
            continue;
        }
        ++coats;
        ASSERT_NE(coat, nullptr) << "material " << m;
        const json& cc = mat["extensions"]["KHR_materials_clearcoat"];
        if (!cc.contains("clearcoatNormalTexture")) {
            EXPECT_FALSE(coat->bake);
            EXPECT_NE(coat->reason.find("no clearcoat normal texture"), std::string::npos) << coat->reason;
            continue;
        }
        // A normal map under a coat of roughness 0.03 changes the filtered roughness far beyond half a step.
        const int texture = cc["clearcoatNormalTexture"]["index"];
        EXPECT_EQ(coat->normal_image, doc["textures"][size_t(texture)]["source"].get<int>()) << "material " << m;
        EXPECT_TRUE(coat->bake) << "material " << m << ": " << coat->reason;
        EXPECT_FLOAT_EQ(coat->roughness_value, cc.value("clearcoatRoughnessFactor", 0.0f));
        ++baked;
    }
    EXPECT_EQ(coats, 6u);
    EXPECT_EQ(baked, 2u) << "CoatNorm_Coated and SharedNorm_Coated";

    const fs::path out_dir = temp_dir("clearcoat_asset");
    SceneJob job;
    job.scenes = {file};
    job.output_dir = out_dir;
    auto outcome = run_scene_job(job);
    ASSERT_TRUE(outcome) << outcome.error().message;
    ASSERT_TRUE(outcome->errors.empty()) << outcome->errors[0];
    std::ifstream out_in(out_dir / "ClearCoatTest.gltf");
    const json out = json::parse(out_in);
    size_t referenced = 0;
    for (const json& mat : out["materials"]) {
        if (!mat.contains("extensions") || !mat["extensions"].contains("SPECBAKE_specular_aa")) continue;
        const json& ext = mat["extensions"]["SPECBAKE_specular_aa"];
        if (!ext.contains("clearcoat")) continue;
        ++referenced;
        EXPECT_TRUE(ext["clearcoat"]["source"].contains("clearcoatNormalTexture"));
        for (const json& o : ext["clearcoat"]["outputs"])
            EXPECT_TRUE(fs::exists(out_dir / o["uri"].get<std::string>())) << o;
    }
    EXPECT_EQ(referenced, 2u);
    Assimp::Importer importer;
    ASSERT_NE(importer.ReadFile((out_dir / "ClearCoatTest.gltf").string(), 0), nullptr) << importer.GetErrorString();
    fs::remove_all(out_dir);
}
