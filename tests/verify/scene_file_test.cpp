// `specbake verify SCENE`: scene files become simulator scenes with their own transforms, cameras, lights
// and materials. Each test writes a small glTF with known content and checks the loaded scene or its
// ground truth against an independent construction: the same sphere transformed by hand and rendered as
// a built-in-style scene, far point and spot lights against a directional light of equal irradiance,
// texture values decoded and scaled by hand.
#include "verify/verify_job.h"
#include "verify/bench_job.h"
#include "bake/texture_bake.h"
#include "verify/renderer.h"
#include "verify/scene.h"
#include "verify/scene_file.h"
#include "io/image/image_io.h"

#include "tests/verify/sim_test_environment.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <vector>

namespace specbake::verify {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

test::SimTestEnvironment& environment() { return test::sim_environment(); }

using test::TempDir;

constexpr double kPi = std::numbers::pi;
constexpr float kSphereRadius = 0.5f;
const Float3 kCentre{2.0f, -1.0f, 0.5f};
constexpr double kYaw = 30.0 * kPi / 180.0;  // node rotation about +Y

// The unit sphere of the built-in scenes, object space.
TriMesh unit_sphere() {
    auto scene = make_builtin_scene("sphere", 0.3f, 0.25f);
    return scene->objects[0].mesh;
}

// Appends `values` to the binary buffer as a float accessor of `type` ("VEC3", ...) and returns its index.
int add_accessor(json& gltf, std::string& bin, const std::vector<float>& values, int components, const char* type,
                 bool bounds = false) {
    const size_t offset = bin.size();
    bin.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(float));
    gltf["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", values.size() * 4}});
    json accessor = {{"bufferView", gltf["bufferViews"].size() - 1},
                     {"componentType", 5126},
                     {"count", values.size() / size_t(components)},
                     {"type", type}};
    if (bounds) {
        std::vector<float> lo(size_t(components), 1e30f), hi(size_t(components), -1e30f);
        for (size_t i = 0; i < values.size(); ++i) {
            lo[i % size_t(components)] = std::min(lo[i % size_t(components)], values[i]);
            hi[i % size_t(components)] = std::max(hi[i % size_t(components)], values[i]);
        }
        accessor["min"] = lo;
        accessor["max"] = hi;
    }
    gltf["accessors"].push_back(accessor);
    return int(gltf["accessors"].size() - 1);
}

// A glTF with the unit sphere under a node at kCentre, scaled to kSphereRadius and turned by kYaw, a
// perspective camera 1.8 in front of it looking down -Z, and the given lights (KHR_lights_punctual
// definitions with their node's translation and rotation). Returns the .gltf path.
fs::path write_sphere_gltf(const fs::path& dir, const std::vector<std::pair<json, json>>& lights,
                           const json& material = json::object(), bool camera = true) {
    const TriMesh m = unit_sphere();
    json gltf = {{"asset", {{"version", "2.0"}}}, {"bufferViews", json::array()}, {"accessors", json::array()}};
    std::string bin;
    const int pos = add_accessor(gltf, bin, m.positions, 3, "VEC3", true);
    const int nrm = add_accessor(gltf, bin, m.normals, 3, "VEC3");
    const int tan = add_accessor(gltf, bin, m.tangents, 4, "VEC4");
    const int uv = add_accessor(gltf, bin, m.uv0, 2, "VEC2");
    const size_t index_offset = bin.size();
    bin.append(reinterpret_cast<const char*>(m.indices.data()), m.indices.size() * 4);
    gltf["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", index_offset}, {"byteLength", m.indices.size() * 4}});
    gltf["accessors"].push_back({{"bufferView", gltf["bufferViews"].size() - 1},
                                 {"componentType", 5125},
                                 {"count", m.indices.size()},
                                 {"type", "SCALAR"}});
    const int idx = int(gltf["accessors"].size() - 1);
    json primitive = {{"attributes", {{"POSITION", pos}, {"NORMAL", nrm}, {"TANGENT", tan}, {"TEXCOORD_0", uv}}},
                      {"indices", idx}};
    if (!material.empty()) {
        gltf["materials"] = json::array({material});
        primitive["material"] = 0;
    }
    gltf["meshes"] = json::array({{{"primitives", json::array({primitive})}}});
    gltf["buffers"] = json::array({{{"uri", "sphere.bin"}, {"byteLength", bin.size()}}});
    const double s = std::sin(0.5 * kYaw), c = std::cos(0.5 * kYaw);
    gltf["nodes"] = json::array({{{"mesh", 0},
                                  {"translation", {kCentre[0], kCentre[1], kCentre[2]}},
                                  {"rotation", {0.0, s, 0.0, c}},
                                  {"scale", {kSphereRadius, kSphereRadius, kSphereRadius}}}});
    json roots = {0};
    if (camera) {
        gltf["cameras"] = json::array({{{"type", "perspective"},
                                        {"perspective", {{"yfov", 40.0 * kPi / 180.0}, {"znear", 0.01}}}}});
        // Parent with a translation, child with the rest: the camera's world transform is their product.
        gltf["nodes"].push_back({{"translation", {kCentre[0], 0.0, 0.0}}, {"children", {2}}});
        gltf["nodes"].push_back({{"camera", 0}, {"translation", {0.0, kCentre[1], kCentre[2] + 1.8}}});
        roots.push_back(1);
    }
    if (!lights.empty()) {
        gltf["extensionsUsed"] = {"KHR_lights_punctual"};
        json defs = json::array();
        for (const auto& [def, node] : lights) {
            defs.push_back(def);
            json n = node;
            n["extensions"] = {{"KHR_lights_punctual", {{"light", defs.size() - 1}}}};
            gltf["nodes"].push_back(n);
            roots.push_back(gltf["nodes"].size() - 1);
        }
        gltf["extensions"] = {{"KHR_lights_punctual", {{"lights", defs}}}};
    }
    gltf["scenes"] = json::array({{{"nodes", roots}}});
    gltf["scene"] = 0;
    std::ofstream(dir / "sphere.bin", std::ios::binary) << bin;
    std::ofstream(dir / "sphere.gltf") << gltf.dump(1);
    return dir / "sphere.gltf";
}

// Quaternion (x, y, z, w) turning -Z into the unit vector `d` (a light or spot pointing along d).
json rotation_pointing(Float3 d) {
    // Axis -Z x d, angle acos(-d.z).
    const double ax = d[1], ay = -d[0];
    const double angle = std::acos(std::clamp(-double(d[2]), -1.0, 1.0));
    const double len = std::sqrt(ax * ax + ay * ay);
    if (len < 1e-12) return {0.0, 0.0, 0.0, 1.0};
    const double s = std::sin(0.5 * angle) / len;
    return {ax * s, ay * s, 0.0, std::cos(0.5 * angle)};
}

// The same sphere transformed by hand, with the camera and one directional light of irradiance E from
// `towards_light`: the independent construction the loaded scenes are compared with.
SimScene reference_scene(Float3 towards_light, float irradiance, float roughness) {
    SimScene scene;
    scene.name = "reference";
    SimObject object;
    object.mesh = unit_sphere();
    const float c = float(std::cos(kYaw)), s = float(std::sin(kYaw));
    const auto rotate = [&](float* v) {
        const float x = v[0], z = v[2];
        v[0] = c * x + s * z;
        v[2] = -s * x + c * z;
    };
    for (size_t v = 0; v < object.mesh.vertex_count(); ++v) {
        float* p = &object.mesh.positions[3 * v];
        rotate(p);
        for (int a = 0; a < 3; ++a) p[a] = kCentre[a] + kSphereRadius * p[a];
        rotate(&object.mesh.normals[3 * v]);
        rotate(&object.mesh.tangents[4 * v]);
    }
    object.material.roughness = roughness;
    scene.objects.push_back(std::move(object));
    scene.camera = {{kCentre[0], kCentre[1], kCentre[2] + 1.8f}, kCentre, {0, 1, 0}, 40.0f};
    scene.object_radius = kSphereRadius;
    SimLight light;
    light.direction = towards_light;
    light.radiance = irradiance;
    scene.lights.push_back(light);
    return scene;
}

SimImage ground_truth(const SimScene& scene, int size = 48, int spp = 16) {
    auto renderer = SimRenderer::create(scene, size, size, environment().include);
    EXPECT_TRUE(renderer.ok()) << (renderer.ok() ? "" : renderer.error().message);
    return renderer.ok() ? (*renderer)->render_ground_truth(0, spp) : SimImage(size, size, 2);
}

// RMSE of the radiance divided by the reference's mean radiance.
double relative_rmse(const SimImage& a, const SimImage& reference) {
    double sum = 0, mean = 0;
    for (size_t i = 0; i < reference.texel_count(); ++i) {
        const double d = a.pixels[2 * i] - reference.pixels[2 * i];
        sum += d * d;
        mean += reference.pixels[2 * i];
    }
    const double n = double(reference.texel_count());
    return std::sqrt(sum / n) / std::max(mean / n, 1e-12);
}

double total_radiance(const SimImage& image) {
    double sum = 0;
    for (size_t i = 0; i < image.texel_count(); ++i) sum += image.pixels[2 * i];
    return sum;
}

const Float3 kTowardsLight{0.0f, 0.5f, 0.8660254f};

TEST(VerifySceneFile, NodeTransformsCameraAndDirectionalLightMatchAHandBuiltScene) {
    SPECBAKE_REQUIRE_GL();
    TempDir dir;
    const json light = {{"type", "directional"}, {"intensity", 4.0}, {"color", {0.5, 0.5, 0.5}}};
    auto scene = load_sim_scene(write_sphere_gltf(dir.path(), {{light, {{"rotation", rotation_pointing({-kTowardsLight[0], -kTowardsLight[1], -kTowardsLight[2]})}}}},
                                                  {{"pbrMetallicRoughness", {{"roughnessFactor", 0.3}}}}));
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    ASSERT_EQ(scene->objects.size(), 1u);
    ASSERT_EQ(scene->lights.size(), 1u);
    EXPECT_EQ(scene->lights[0].type, SimLight::Type::Directional);
    EXPECT_NEAR(scene->lights[0].radiance, 2.0f, 1e-6f);  // intensity x luminance of the grey colour
    for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(scene->lights[0].direction[a], kTowardsLight[a], 1e-5f);
        EXPECT_NEAR(scene->camera.position[a], (Float3{kCentre[0], kCentre[1], kCentre[2] + 1.8f})[a], 1e-5f);
        EXPECT_NEAR(scene->camera.target[a], kCentre[a], 1e-4f);
    }
    EXPECT_NEAR(scene->camera.fov_y_degrees, 40.0f, 1e-4f);
    EXPECT_NEAR(scene->objects[0].material.roughness, 0.3f, 1e-6f);
    EXPECT_NEAR(scene->object_radius, kSphereRadius, 1e-3f);

    const SimImage loaded = ground_truth(*scene);
    const SimImage reference = ground_truth(reference_scene(kTowardsLight, 2.0f, 0.3f));
    EXPECT_GT(total_radiance(reference), 0.0);
    EXPECT_LT(relative_rmse(loaded, reference), 1e-3);
}

TEST(VerifySceneFile, FarPointAndSpotLightsGiveTheIrradianceOfADirectionalLight) {
    SPECBAKE_REQUIRE_GL();
    // At distance D an intensity of E D^2 gives irradiance E; the sphere (radius 0.5) is so small against D
    // that direction and falloff vary by under 0.1% across it.
    constexpr double D = 2000.0;
    const json position = {kCentre[0] + D * kTowardsLight[0], kCentre[1] + D * kTowardsLight[1],
                           kCentre[2] + D * kTowardsLight[2]};
    const SimImage reference = ground_truth(reference_scene(kTowardsLight, 1.5f, 0.3f));
    const json material = {{"pbrMetallicRoughness", {{"roughnessFactor", 0.3}}}};
    {
        TempDir dir;
        const json point = {{"type", "point"}, {"intensity", 1.5 * D * D}, {"range", 100.0 * D}};
        auto scene = load_sim_scene(write_sphere_gltf(dir.path(), {{point, {{"translation", position}}}}, material));
        ASSERT_TRUE(scene.ok()) << scene.error().message;
        EXPECT_EQ(scene->lights[0].type, SimLight::Type::Point);
        EXPECT_LT(relative_rmse(ground_truth(*scene), reference), 5e-3);
    }
    const json spot_towards = rotation_pointing({-kTowardsLight[0], -kTowardsLight[1], -kTowardsLight[2]});
    {
        TempDir dir;
        const json spot = {{"type", "spot"}, {"intensity", 1.5 * D * D}, {"spot", {{"innerConeAngle", 0.2}, {"outerConeAngle", 0.4}}}};
        auto scene = load_sim_scene(
            write_sphere_gltf(dir.path(), {{spot, {{"translation", position}, {"rotation", spot_towards}}}}, material));
        ASSERT_TRUE(scene.ok()) << scene.error().message;
        EXPECT_EQ(scene->lights[0].type, SimLight::Type::Spot);
        EXPECT_LT(relative_rmse(ground_truth(*scene), reference), 5e-3);
    }
    {
        // The same spot turned away from the sphere lights nothing.
        TempDir dir;
        const json spot = {{"type", "spot"}, {"intensity", 1.5 * D * D}, {"spot", {{"innerConeAngle", 0.2}, {"outerConeAngle", 0.4}}}};
        auto scene = load_sim_scene(write_sphere_gltf(
            dir.path(), {{spot, {{"translation", position}, {"rotation", rotation_pointing(kTowardsLight)}}}}, material));
        ASSERT_TRUE(scene.ok()) << scene.error().message;
        EXPECT_EQ(total_radiance(ground_truth(*scene)), 0.0);
    }
}

TEST(VerifySceneFile, WithoutLightsAndCameraTheSceneGetsADefaultLightAndAFramingOrbit) {
    SPECBAKE_REQUIRE_GL();
    TempDir dir;
    auto scene = load_sim_scene(write_sphere_gltf(dir.path(), {}, json::object(), false));
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    ASSERT_EQ(scene->lights.size(), 1u);
    EXPECT_EQ(scene->lights[0].type, SimLight::Type::Directional);
    EXPECT_FALSE(scene->notes.empty());
    EXPECT_EQ(scene->objects[0].material.roughness, 1.0f);  // glTF default material
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(scene->camera.target[a], kCentre[a], 1e-3f);
    // The whole sphere is in view and fills a good part of it: coverage reaches the middle, not the border.
    const SimImage gt = ground_truth(*scene, 32, 4);
    double border = 0, covered = 0;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
            const float c = gt.texel(x, y)[1];
            covered += c;
            if (x == 0 || y == 0 || x == 31 || y == 31) border += c;
        }
    EXPECT_EQ(border, 0.0);
    EXPECT_GT(covered, 0.3 * 32 * 32);
}

TEST(VerifySceneFile, MaterialTexturesAreDecodedWithTheirFactorAndScale) {
    TempDir dir;
    // 4 x 4 metallicRoughness map with G = x / 3 and a normal map tilted along +x by 0.6 (encoded).
    Image orm(4, 4, 3), normal(4, 4, 3);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) {
            orm.texel(x, y)[1] = float(x) / 3.0f;
            const double nx = 0.6, nz = 0.8;
            normal.texel(x, y)[0] = float(0.5 * (nx + 1));
            normal.texel(x, y)[1] = 0.5f;
            normal.texel(x, y)[2] = float(0.5 * (nz + 1));
        }
    ASSERT_TRUE(io::write_image(dir.path() / "orm.png", orm, 16).ok());
    ASSERT_TRUE(io::write_image(dir.path() / "normal.png", normal, 16).ok());
    json material = {{"pbrMetallicRoughness",
                      {{"roughnessFactor", 0.5}, {"metallicRoughnessTexture", {{"index", 0}}}}},
                     {"normalTexture", {{"index", 1}, {"scale", 0.5}}}};
    const fs::path path = write_sphere_gltf(dir.path(), {}, material);
    {
        std::ifstream in(path);
        json gltf = json::parse(in);
        gltf["images"] = json::array({{{"uri", "orm.png"}}, {{"uri", "normal.png"}}});
        gltf["textures"] = json::array({{{"source", 0}}, {{"source", 1}}});
        std::ofstream(path) << gltf.dump(1);
    }
    auto scene = load_sim_scene(path);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    ASSERT_EQ(scene->roughness_maps.size(), 1u);
    ASSERT_EQ(scene->normal_maps.size(), 1u);
    // Texels below the simulator's smallest roughness (0.045) are raised to it.
    for (int x = 0; x < 4; ++x)
        EXPECT_NEAR(scene->roughness_maps[0].texel(x, 2)[0], std::max(0.045, 0.5 * x / 3.0), 1e-4);
    // glTF normalTexture scale multiplies x and y before normalising: (0.3, 0, 0.8) / |.|.
    const double l = std::sqrt(0.3 * 0.3 + 0.8 * 0.8);
    const float* n = scene->normal_maps[0].texel(1, 1);
    EXPECT_NEAR(2.0 * n[0] - 1.0, 0.3 / l, 1e-3);
    EXPECT_NEAR(2.0 * n[1] - 1.0, 0.0, 1e-3);
    EXPECT_NEAR(2.0 * n[2] - 1.0, 0.8 / l, 1e-3);
    EXPECT_EQ(scene->objects[0].material.normal_map, 0);
    EXPECT_EQ(scene->objects[0].material.roughness_map, 0);
}

// A normal map whose blue channel is constant 255 (an embossed map written with z = 1): glTF viewers and
// the simulator shade normalize(2c - 1) with that stored blue (glTF 2.0 Sec. 3.9.3), not z rebuilt from x
// and y. The bake with the glTF decode (what scene bakes use) must give the same kernel mips as a bake of
// the simulator's own decoded map; rebuilding z (`--reconstruct-z auto`) gives a larger spread.
TEST(VerifySceneFile, SceneBakesDecodeNormalMapsAsTheSimulatorDoes) {
    TempDir dir;
    constexpr int kSize = 32;
    Image normal(kSize, kSize, 3);
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            // Embossed bumps: slopes up to ~0.6 in x and y, 8-bit codes, blue fixed at 255.
            const double sx = 0.6 * std::sin(2.0 * kPi * x / 8.0), sy = 0.5 * std::cos(2.0 * kPi * y / 6.0);
            normal.texel(x, y)[0] = float(std::round(255.0 * 0.5 * (sx + 1.0)) / 255.0);
            normal.texel(x, y)[1] = float(std::round(255.0 * 0.5 * (sy + 1.0)) / 255.0);
            normal.texel(x, y)[2] = 1.0f;
        }
    ASSERT_TRUE(io::write_image(dir.path() / "normal.png", normal, 8).ok());
    const fs::path path = write_sphere_gltf(dir.path(), {}, {{"normalTexture", {{"index", 0}}}});
    {
        std::ifstream in(path);
        json gltf = json::parse(in);
        gltf["images"] = json::array({{{"uri", "normal.png"}}});
        gltf["textures"] = json::array({{{"source", 0}}});
        std::ofstream(path) << gltf.dump(1);
    }
    auto scene = load_sim_scene(path);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    ASSERT_EQ(scene->normal_maps.size(), 1u);
    auto decoded = io::read_image(dir.path() / "normal.png");
    ASSERT_TRUE(decoded.ok()) << decoded.error().message;

    TextureBakeSettings gltf_decode;
    gltf_decode.reconstruct_z = ReconstructZ::Gltf;
    TextureBakeSettings auto_decode = gltf_decode;
    auto_decode.reconstruct_z = ReconstructZ::Auto;
    auto from_file = bake_texture(*decoded, nullptr, 0, 0.2f, gltf_decode);
    auto from_simulator = bake_texture(scene->normal_maps[0], nullptr, 0, 0.2f, gltf_decode);
    auto rebuilt = bake_texture(*decoded, nullptr, 0, 0.2f, auto_decode);
    ASSERT_TRUE(from_file.ok() && from_simulator.ok() && rebuilt.ok());
    EXPECT_FALSE(from_file->notes.z_reconstructed);
    EXPECT_EQ(from_file->notes.z_decode, "stored blue channel");
    EXPECT_TRUE(rebuilt->notes.z_reconstructed);
    EXPECT_EQ(rebuilt->notes.z_reason, "constant full-scale blue channel");
    ASSERT_EQ(from_file->kernel.levels.size(), from_simulator->kernel.levels.size());
    double trace_file = 0, trace_rebuilt = 0;
    for (size_t level = 1; level < from_file->kernel.levels.size(); ++level) {
        const Image& a = from_file->kernel.levels[level];
        const Image& b = from_simulator->kernel.levels[level];
        const Image& c = rebuilt->kernel.levels[level];
        ASSERT_EQ(a.pixels.size(), b.pixels.size());
        for (size_t t = 0; t < a.texel_count(); ++t) {
            // Sigma (xx, yy, xy): the simulator's map holds the same unit normals, re-encoded as floats.
            for (int ch = 0; ch < 3; ++ch)
                EXPECT_NEAR(a.pixels[4 * t + size_t(ch)], b.pixels[4 * t + size_t(ch)], 2e-5) << level << " " << t;
            trace_file += a.pixels[4 * t] + a.pixels[4 * t + 1];
            trace_rebuilt += c.pixels[4 * t] + c.pixels[4 * t + 1];
        }
    }
    // Rebuilding z tilts every normal further than (2c - 1) normalised does (z = sqrt(1 - x^2 - y^2) < 1):
    // the projected spread grows.
    EXPECT_GT(trace_rebuilt, 1.05 * trace_file);
}

TEST(VerifySceneFile, EveryCandidateRunsOnASceneFileWithEstimatedCurvature) {
    SPECBAKE_REQUIRE_GL();
    TempDir dir;
    Image normal(64, 64, 3);
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) {
            // Ribs along x: n = (-h', 0, 1) / |.|, h' = 0.4 cos(2 pi 8 x / 64).
            const double g = 0.4 * std::cos(2 * kPi * 8 * x / 64.0), l = std::sqrt(1 + g * g);
            normal.texel(x, y)[0] = float(0.5 * (-g / l + 1));
            normal.texel(x, y)[1] = 0.5f;
            normal.texel(x, y)[2] = float(0.5 * (1 / l + 1));
        }
    ASSERT_TRUE(io::write_image(dir.path() / "normal.png", normal, 16).ok());
    const fs::path path = write_sphere_gltf(dir.path(), {}, {{"pbrMetallicRoughness", {{"roughnessFactor", 0.25}}},
                                                             {"normalTexture", {{"index", 0}}}});
    {
        std::ifstream in(path);
        json gltf = json::parse(in);
        gltf["images"] = json::array({{{"uri", "normal.png"}}});
        gltf["textures"] = json::array({{{"source", 0}}});
        std::ofstream(path) << gltf.dump(1);
    }
    auto scene = load_sim_scene(path);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    EXPECT_FALSE(has_exact_curvature(*scene));
    VerifyOptions options = test::small_verify(32, 32, 16, 2);
    options.variants = true;
    auto report = run_verify(*scene, options);
    ASSERT_TRUE(report.ok()) << report.error().message;
    EXPECT_TRUE(report->from_file);
    bool baked_texture = false, baked_curvature = false;
    for (const CandidateReport& c : report->candidates) {
        EXPECT_TRUE(std::isfinite(c.metrics.rmse) && std::isfinite(c.metrics.flicker_linear)) << c.name;
        EXPECT_NE(c.name, "baked-curvature/patch");
        if (c.name == "baked-texture") baked_texture = c.bake_ms.has_value();
        // Curvature comes from the default estimator, timed as a bake.
        if (c.name == "baked-curvature") baked_curvature = c.bake_ms.has_value();
    }
    EXPECT_TRUE(baked_texture);
    EXPECT_TRUE(baked_curvature);
}

// A --variant whose defines ask for SPECAA_USE_CURVATURE gets the estimated curvature bound, as --define does:
// on a glossy sphere from a file its per-pixel kernel then removes most of no filtering's error (unbound, the
// attribute reads as zero curvature and the row equals none's).
TEST(VerifySceneFile, VariantAskingForCurvatureReadsTheEstimatedCurvature) {
    SPECBAKE_REQUIRE_GL();
    TempDir dir;
    const fs::path path = write_sphere_gltf(dir.path(), {}, {{"pbrMetallicRoughness", {{"roughnessFactor", 0.1}}}});
    auto scene = load_sim_scene(path);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    ASSERT_FALSE(has_exact_curvature(*scene));
    VerifyOptions options = test::small_verify(64, 64, 64, 2);
    options.only = {"default"};
    options.default_variants = {{"curv", "#define SPECAA_USE_CURVATURE\n"}};
    auto report = run_verify(*scene, options);
    ASSERT_TRUE(report.ok()) << report.error().message;
    const SimMetrics *none = nullptr, *curv = nullptr;
    for (const CandidateReport& c : report->candidates) {
        if (c.name == "none") none = &c.metrics;
        if (c.name == "default:curv") curv = &c.metrics;
    }
    ASSERT_TRUE(none && curv);
    EXPECT_LT(curv->rmse, 0.6 * none->rmse);
}

// A --variant that binds the baked roughness shades with the default's roughness mips in place of its kernel
// mips (the include rejects both at once): on a normal-mapped scene it is the default-roughness row to the
// last bit; where nothing is baked (no normal map) the binding is dropped and it is the default row.
TEST(VerifySceneFile, VariantBindingTheBakedRoughnessReplacesTheKernelMips) {
    SPECBAKE_REQUIRE_GL();
    const std::string rough = "#define SPECAA_ROUGHNESS_TEXTURE uBakedRoughness\n#define SPECAA_ROUGHNESS_CHANNEL r\n";
    for (const char* name : {"bumpy-sphere", "sphere"}) {
        auto scene = make_builtin_scene(name, 0.3f, 0.5f);
        ASSERT_TRUE(scene.ok()) << scene.error().message;
        const bool normal_mapped = std::string(name) == "bumpy-sphere";
        VerifyOptions options = test::small_verify(32, 32, 4, 1);
        options.only = {"default", "default-roughness"};
        options.default_variants = {{"rough", rough}};
        // The default reads the curvature attribute; default-roughness then does too.
        options.defines = "#define SPECAA_USE_CURVATURE\n";
        auto report = run_verify(*scene, options);
        ASSERT_TRUE(report.ok()) << name << ": " << report.error().message;
        const SimMetrics *variant = nullptr, *twin = nullptr, *kernel = nullptr;
        for (const CandidateReport& c : report->candidates) {
            if (c.name == "default:rough") variant = &c.metrics;
            if (c.name == (normal_mapped ? "default-roughness" : "default")) twin = &c.metrics;
            if (c.name == "default") kernel = &c.metrics;
        }
        ASSERT_TRUE(variant && twin && kernel) << name;
        EXPECT_EQ(variant->rmse, twin->rmse) << name;
        EXPECT_EQ(variant->flicker_linear, twin->flicker_linear) << name;
        // The kernel mips shade the normal-mapped sphere differently: the binding did change.
        if (normal_mapped) EXPECT_NE(variant->rmse, kernel->rmse);
    }
}

TEST(VerifySceneFile, MaterialsWithoutANormalMapKeepTheirRoughnessInBakedCandidates) {
    SPECBAKE_REQUIRE_GL();
    // Two spheres side by side, only the right one normal-mapped: nothing is baked for the left one, so the
    // baked-texture candidate must shade it exactly like no filtering (its own roughness, no kernel).
    auto bumpy = make_builtin_scene("bumpy-sphere", 0.3f, 0.5f);
    ASSERT_TRUE(bumpy.ok());
    SimScene scene = *bumpy;
    scene.objects.push_back(scene.objects[0]);
    for (size_t o = 0; o < 2; ++o) {
        TriMesh& m = scene.objects[o].mesh;
        for (size_t v = 0; v < m.vertex_count(); ++v) m.positions[3 * v] += o == 0 ? -1.2f : 1.2f;
    }
    scene.objects[0].material.normal_map = -1;
    scene.camera = {{0.0f, 0.0f, 6.0f}, {0, 0, 0}, {0, 1, 0}, 40.0f};
    VerifyOptions options = test::small_verify(64, 32, 4, 1);
    options.keep_images = true;
    options.only = {"baked-texture"};
    auto report = run_verify(scene, options);
    ASSERT_TRUE(report.ok()) << report.error().message;
    ASSERT_EQ(report->candidates.size(), 2u);
    const SimImage& none = report->candidates[0].image;
    const SimImage& baked = report->candidates[1].image;
    double left = 0, right = 0, difference_left = 0, difference_right = 0;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 64; ++x) {
            const double d = std::abs(double(baked.texel(x, y)[0]) - none.texel(x, y)[0]);
            (x < 32 ? left : right) += none.texel(x, y)[0];
            (x < 32 ? difference_left : difference_right) += d;
        }
    ASSERT_GT(left, 0.0);
    EXPECT_LT(difference_left, 1e-4 * left);
    EXPECT_GT(difference_right, 1e-3 * right);  // the normal-mapped sphere does change
}

TEST(VerifySceneFile, EverySharedGltfModelIsSimulated) {
    SPECBAKE_REQUIRE_GL();
    const fs::path assets = SPECBAKE_ASSETS_DIR;
    std::vector<fs::path> scenes;
    for (const char* folder : {"gltf", "meshes"}) {
        std::error_code ec;
        for (fs::recursive_directory_iterator it(assets / folder, ec), end; !ec && it != end; it.increment(ec))
            if (it->path().extension() == ".gltf" || it->path().extension() == ".glb") scenes.push_back(it->path());
    }
    if (scenes.empty()) GTEST_SKIP() << "no shared glTF models under " << assets;
    for (const fs::path& path : scenes) {
        auto scene = load_sim_scene(path);
        ASSERT_TRUE(scene.ok()) << scene.error().message;
        // Large enough that the models' many small glossy parts cover whole pixels, so the ground truth
        // resolves their highlights.
        VerifyOptions options = test::small_verify(48, 48, 16, 1);
        options.only = {"default", "baked-texture", "baked-curvature"};
        auto report = run_verify(*scene, options);
        ASSERT_TRUE(report.ok()) << path << ": " << report.error().message;
        for (const CandidateReport& c : report->candidates) {
            EXPECT_TRUE(std::isfinite(c.metrics.rmse) && std::isfinite(c.metrics.flicker_linear) &&
                        std::isfinite(c.metrics.energy_ratio))
                << path << " " << c.name;
            // No candidate may blow up against the ground truth (an unbound texture or a mirror did, by
            // factors of 1e5 and more); filtering spreads highlights, it does not multiply their energy.
            EXPECT_LT(c.metrics.energy_ratio, 4.0) << path << " " << c.name;
        }
    }
}

TEST(VerifySceneFile, BadFilesGiveAnErrorNamingTheFile) {
    TempDir dir;
    auto missing = load_sim_scene(dir.path() / "nope.gltf");
    ASSERT_FALSE(missing.ok());
    EXPECT_NE(missing.error().message.find("nope.gltf"), std::string::npos);
    std::ofstream(dir.path() / "broken.gltf") << "{ not json";
    auto broken = load_sim_scene(dir.path() / "broken.gltf");
    ASSERT_FALSE(broken.ok());
    EXPECT_NE(broken.error().message.find("broken.gltf"), std::string::npos);
    // A node hierarchy with a cycle must not hang.
    const fs::path path = write_sphere_gltf(dir.path(), {}, json::object(), false);
    std::ifstream in(path);
    json gltf = json::parse(in);
    in.close();
    gltf["nodes"][0]["children"] = {0};
    std::ofstream(path) << gltf.dump();
    auto cyclic = load_sim_scene(path);
    ASSERT_FALSE(cyclic.ok());
    EXPECT_NE(cyclic.error().message.find("sphere.gltf"), std::string::npos);
}

// `verify --lights N` (bench/frame_cost.sh): N directional lights, each 35 degrees off the view direction,
// their projections across the view spread evenly (360 / N degrees apart, the first along the camera's up),
// irradiance summing to 1. Checked with the angles computed here in double precision.
TEST(VerifyScene, CostLightsAreSpreadEvenlyAroundTheView) {
    auto scene = make_builtin_scene("bumpy-sphere", 0.2f);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    for (int n : {1, 2, 3, 4, 8}) {
        const SimScene lit = with_cost_lights(*scene, n);
        ASSERT_EQ(lit.lights.size(), size_t(n));
        EXPECT_EQ(lit.name, scene->name + "+" + std::to_string(n) + "L");
        const SimCamera& c = lit.camera;
        double view[3], up[3];
        double len = 0.0;
        for (int i = 0; i < 3; ++i) len += double(c.position[i] - c.target[i]) * double(c.position[i] - c.target[i]);
        for (int i = 0; i < 3; ++i) view[i] = double(c.position[i] - c.target[i]) / std::sqrt(len);
        // The camera's up made orthogonal to the view.
        double d = 0.0;
        for (int i = 0; i < 3; ++i) d += double(c.up[i]) * view[i];
        double ul = 0.0;
        for (int i = 0; i < 3; ++i) ul += (double(c.up[i]) - d * view[i]) * (double(c.up[i]) - d * view[i]);
        for (int i = 0; i < 3; ++i) up[i] = (double(c.up[i]) - d * view[i]) / std::sqrt(ul);
        double total = 0.0;
        std::vector<double> azimuth;
        for (const SimLight& l : lit.lights) {
            EXPECT_EQ(l.type, SimLight::Type::Directional);
            total += l.radiance;
            double norm = 0.0, cos_view = 0.0, along_up = 0.0;
            for (int i = 0; i < 3; ++i) {
                norm += double(l.direction[i]) * double(l.direction[i]);
                cos_view += double(l.direction[i]) * view[i];
                along_up += double(l.direction[i]) * up[i];
            }
            EXPECT_NEAR(norm, 1.0, 1e-5);
            EXPECT_NEAR(std::acos(std::clamp(cos_view, -1.0, 1.0)) * 180.0 / std::numbers::pi, 35.0, 1e-3);
            // Angle of the projection across the view, measured from up.
            const double across = std::sqrt(std::max(0.0, 1.0 - cos_view * cos_view));
            azimuth.push_back(std::acos(std::clamp(along_up / across, -1.0, 1.0)));
        }
        EXPECT_NEAR(total, 1.0, 1e-5);
        EXPECT_NEAR(azimuth[0], 0.0, 1e-3);  // the first towards the camera's up
        // Pairwise: the light directions sit on a cone, so their spread is even when every pair's angle
        // matches the cone's chord for its index difference.
        for (int a = 0; a < n; ++a)
            for (int b = a + 1; b < n; ++b) {
                double dab = 0.0;
                for (int i = 0; i < 3; ++i) dab += double(lit.lights[a].direction[i]) * double(lit.lights[b].direction[i]);
                const double s = std::sin(35.0 * std::numbers::pi / 180.0), cv = std::cos(35.0 * std::numbers::pi / 180.0);
                const double expected = cv * cv + s * s * std::cos(2.0 * std::numbers::pi * double(b - a) / double(n));
                EXPECT_NEAR(dab, expected, 1e-5) << n << " lights, " << a << " and " << b;
            }
    }
}

// Each vertex's mean incident edge length (the simulator's vEdge): two triangles sharing the diagonal of a
// 3 x 4 rectangle, counted by hand (a corner on one triangle sees its two edges; a diagonal end sees 3, 4 or
// 5 once per triangle), and a vertex on no triangle 0.
TEST(VerifyScene, MeanEdgeLengthsAreEachVertexsIncidentEdgesAveraged) {
    TriMesh m;
    m.positions = {0, 0, 0, 3, 0, 0, 3, 4, 0, 0, 4, 0, 9, 9, 9};
    m.indices = {0, 1, 2, 0, 2, 3};
    const std::vector<float> e = mean_edge_lengths(m);
    ASSERT_EQ(e.size(), size_t(5));
    EXPECT_FLOAT_EQ(e[0], (3.0f + 5.0f + 5.0f + 4.0f) / 4.0f);  // (0,1), (2,0) of the first; (0,2), (3,0) of the second
    EXPECT_FLOAT_EQ(e[1], (3.0f + 4.0f) / 2.0f);
    EXPECT_FLOAT_EQ(e[2], (4.0f + 5.0f + 5.0f + 3.0f) / 4.0f);
    EXPECT_FLOAT_EQ(e[3], (3.0f + 4.0f) / 2.0f);
    EXPECT_EQ(e[4], 0.0f);
}

}  // namespace
}  // namespace specbake::verify
