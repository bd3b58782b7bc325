// A scene bake bakes what a glTF viewer shades (issue 34), on generated spheres with a bumpy normal map
// and an ORM texture: textures whose UV mappings (texCoord and KHR_texture_transform) agree bake as one
// and keep the ORM; truly misaligned maps write no roughness replacement and `bake` says so as `plan` does;
// generated tangents follow the normal texture's texCoord (checked against the sphere's analytic
// derivatives); layers with the same inputs (also through two image entries naming one file) bake once and
// the manifest lists each file once with its materials; the extension records what it folded in.
#include "io/image/image_io.h"
#include "io/output/manifest.h"
#include "pipeline/scene_job.h"
#include "scene_test_util.h"
#include "tests/io/procedural_images.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <map>
#include <set>

using namespace specbake;
using namespace scene_test;
using nlohmann::json;

namespace {

constexpr int kMap = 64;

// Bumps of period 8 and 16 texels: a map whose bake changes roughness everywhere.
Image bumpy_normal_map() { return specbake::testing::sine_normal_map(kMap, 0.5, 0.4); }

// R = occlusion, G = roughness from 0.1 to 0.9 across x, B = metallic.
Image orm_map() {
    Image img(kMap, kMap, 3);
    for (int y = 0; y < kMap; ++y)
        for (int x = 0; x < kMap; ++x) {
            float* t = img.texel(x, y);
            t[0] = 1.0f;
            t[1] = float(0.1 + 0.8 * x / (kMap - 1));
            t[2] = float(y % 2);
        }
    return img;
}

// A UV sphere (radius 1, poles on y) with TEXCOORD_0 = (u, v) = (phi / 2pi, theta / pi) and TEXCOORD_1 =
// (v, u), no tangents; `materials` glossy materials, the primitive using material 0. normal.png and
// orm.png beside it; the materials are filled in by the caller.
fs::path write_sphere(const fs::path& dir, const std::string& name, int materials = 1) {
    const int rings = 24, segments = 48;
    std::vector<float> pos, nrm, uv0, uv1;
    std::vector<uint32_t> idx;
    for (int r = 0; r <= rings; ++r)
        for (int s = 0; s <= segments; ++s) {
            const double u = double(s) / segments, v = double(r) / rings;
            const double theta = v * M_PI, phi = u * 2 * M_PI;
            const double n[3] = {std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)};
            for (int k = 0; k < 3; ++k) pos.push_back(float(n[k])), nrm.push_back(float(n[k]));
            uv0.insert(uv0.end(), {float(u), float(v)});
            uv1.insert(uv1.end(), {float(v), float(u)});
        }
    for (int r = 0; r < rings; ++r)
        for (int s = 0; s < segments; ++s) {
            const uint32_t a = uint32_t(r * (segments + 1) + s), b = a + 1, c = a + uint32_t(segments + 1), d = c + 1;
            idx.insert(idx.end(), {a, b, c, b, d, c});  // counter-clockwise seen from outside
        }
    tinygltf::Model m;
    m.asset.version = "2.0";
    m.buffers.emplace_back();
    m.buffers[0].uri = name + ".bin";
    using specbake::testing::append_accessor;
    const size_t nv = pos.size() / 3;
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    prim.attributes["POSITION"] =
        append_accessor(m, pos.data(), pos.size() * 4, TINYGLTF_TYPE_VEC3, TINYGLTF_COMPONENT_TYPE_FLOAT, nv);
    m.accessors.back().minValues = {-1, -1, -1};
    m.accessors.back().maxValues = {1, 1, 1};
    prim.attributes["NORMAL"] =
        append_accessor(m, nrm.data(), nrm.size() * 4, TINYGLTF_TYPE_VEC3, TINYGLTF_COMPONENT_TYPE_FLOAT, nv);
    prim.attributes["TEXCOORD_0"] =
        append_accessor(m, uv0.data(), uv0.size() * 4, TINYGLTF_TYPE_VEC2, TINYGLTF_COMPONENT_TYPE_FLOAT, nv);
    prim.attributes["TEXCOORD_1"] =
        append_accessor(m, uv1.data(), uv1.size() * 4, TINYGLTF_TYPE_VEC2, TINYGLTF_COMPONENT_TYPE_FLOAT, nv);
    prim.indices = append_accessor(m, idx.data(), idx.size() * 4, TINYGLTF_TYPE_SCALAR,
                                   TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, idx.size());
    prim.material = 0;
    for (int k = 0; k < materials; ++k) {
        tinygltf::Material mat;
        mat.name = "m" + std::to_string(k);
        mat.pbrMetallicRoughness.roughnessFactor = 0.5;
        m.materials.push_back(mat);
    }
    tinygltf::Mesh mesh;
    mesh.primitives.push_back(prim);
    m.meshes.push_back(mesh);
    tinygltf::Node node;
    node.mesh = 0;
    m.nodes.push_back(node);
    tinygltf::Scene scene;
    scene.nodes = {0};
    m.scenes.push_back(scene);
    m.defaultScene = 0;
    const fs::path path = dir / (name + ".gltf");
    tinygltf::TinyGLTF writer;
    EXPECT_TRUE(writer.WriteGltfSceneToFile(&m, path.string(), false, false, true, false));
    EXPECT_TRUE(io::write_image(dir / "normal.png", bumpy_normal_map(), 8));
    EXPECT_TRUE(io::write_image(dir / "orm.png", orm_map(), 8));
    return path;
}

json read_json(const fs::path& p) {
    std::ifstream in(p);
    return json::parse(in);
}

void write_json(const fs::path& p, const json& j) { std::ofstream(p) << j.dump(2); }

// Images 0 = normal.png, 1 = orm.png; textures 0 and 1 on them.
void add_images(json& g) {
    g["images"] = {{{"uri", "normal.png"}}, {{"uri", "orm.png"}}};
    g["textures"] = {{{"source", 0}}, {{"source", 1}}};
}

json transform(double s, double ox = 0.0) { return {{"KHR_texture_transform", {{"scale", {s, s}}, {"offset", {ox, 0.0}}}}}; }

const json& extension_of(const json& g, int material) {
    return g["materials"][size_t(material)]["extensions"]["SPECBAKE_specular_aa"];
}

std::set<std::string> output_kinds(const json& ext) {
    std::set<std::string> kinds;
    for (const json& o : ext["outputs"]) kinds.insert(o["kind"].get<std::string>());
    return kinds;
}

// Level 0 of the baked roughness (PNG per mip) named by the extension.
std::string roughness_level0(const json& ext) {
    for (const json& o : ext["outputs"])
        if (o["kind"] == "roughness") return o["uri"];
    return {};
}

}  // namespace

// A tiling transform applied identically to the normal and ORM textures (spelled differently: one with
// its defaults written out) is one mapping: the ORM is filtered, not replaced by a constant. Level 0 of the
// baked roughness is roughnessFactor x G texel for texel (the ORM as a viewer reads it).
TEST(SceneSemantics, SameTransformOnBothTexturesKeepsTheOrm) {
    const fs::path dir = temp_dir("sem_same_transform");
    const fs::path in = write_sphere(dir, "tiled");
    json g = read_json(in);
    add_images(g);
    g["extensionsUsed"] = {"KHR_texture_transform"};
    json mat = g["materials"][0];
    mat["normalTexture"] = {{"index", 0}, {"extensions", transform(4.0)}};
    json orm_transform = transform(4.0);
    orm_transform["KHR_texture_transform"]["rotation"] = 0.0;
    orm_transform["KHR_texture_transform"]["texCoord"] = 0;
    mat["pbrMetallicRoughness"]["metallicRoughnessTexture"] = {{"index", 1}, {"extensions", orm_transform}};
    g["materials"][0] = mat;
    write_json(in, g);

    const RunResult plan = run_specbake({"plan", in.string()}, dir);
    ASSERT_EQ(plan.exit_code, 0) << plan.err;
    EXPECT_EQ(plan.out.find("mapped unlike"), std::string::npos) << plan.out;

    const RunResult bake = run_specbake({"bake", "--container", "png", in.string(), "-o", (dir / "out").string()}, dir);
    ASSERT_EQ(bake.exit_code, 0) << bake.err;
    EXPECT_EQ(bake.err.find("mapped unlike"), std::string::npos) << bake.err;
    const json out = read_json(dir / "out/tiled.gltf");
    const json& ext = extension_of(out, 0);
    EXPECT_EQ(ext["source"].value("metallicRoughnessTexture", -1), 1) << ext.dump();
    EXPECT_FALSE(ext["source"].contains("roughness")) << ext.dump();
    EXPECT_EQ(ext["roughnessReplaced"], true);
    EXPECT_EQ(ext["roughnessChannel"], 1);
    EXPECT_EQ(ext["KHR_texture_transform"]["scale"], json({4.0, 4.0}));

    const std::string level0 = roughness_level0(ext);
    ASSERT_FALSE(level0.empty()) << ext.dump();
    auto baked = io::decode_image(dir / "out" / level0);
    auto orm = io::decode_image(dir / "orm.png");
    ASSERT_TRUE(baked && orm);
    ASSERT_EQ(baked->image.width, kMap);
    double worst = 0.0;
    for (int y = 0; y < kMap; ++y)
        for (int x = 0; x < kMap; ++x)
            worst = std::max(worst, std::abs(double(baked->image.texel(x, y)[1]) - 0.5 * orm->image.texel(x, y)[1]));
    EXPECT_LE(worst, 1.0 / 255.0 + 1e-6) << "level 0 of the baked roughness is 0.5 x the ORM's G";
    fs::remove_all(dir);
}

// Normal texture on TEXCOORD_1 (ORM on 0), and a transform on the normal texture only: no roughness output
// replaces the material's roughness (the kernel and normal outputs are still baked), and `bake` prints the
// one-line warning `plan` prints, naming the material and both mappings.
TEST(SceneSemantics, MisalignedMapsKeepTheMaterialRoughnessAndBakeSaysSo) {
    struct Case {
        const char* name;
        json normal_info, orm_info;
        const char* normal_mapping;
        const char* orm_mapping;
    };
    const std::vector<Case> cases = {
        {"texcoord1", {{"index", 0}, {"texCoord", 1}}, {{"index", 1}}, "(TEXCOORD_1)", "(TEXCOORD_0)"},
        {"transform_on_normal", {{"index", 0}, {"extensions", transform(2.0, 0.25)}}, {{"index", 1}},
         "(TEXCOORD_0 offset (0.25, 0) rotation 0 scale (2, 2))", "(TEXCOORD_0)"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const fs::path dir = temp_dir(std::string("sem_misaligned_") + c.name);
        const fs::path in = write_sphere(dir, c.name);
        json g = read_json(in);
        add_images(g);
        g["extensionsUsed"] = {"KHR_texture_transform"};
        g["materials"][0]["normalTexture"] = c.normal_info;
        g["materials"][0]["pbrMetallicRoughness"]["metallicRoughnessTexture"] = c.orm_info;
        write_json(in, g);

        const RunResult plan = run_specbake({"plan", in.string()}, dir);
        ASSERT_EQ(plan.exit_code, 0) << plan.err;
        const RunResult bake = run_specbake({"bake", "--container", "png", in.string(), "-o", (dir / "out").string()}, dir);
        ASSERT_EQ(bake.exit_code, 0) << bake.err;
        // The line names the material and both mappings, the same in plan and bake.
        std::string line;
        std::istringstream lines(bake.err);
        for (std::string l; std::getline(lines, l);)
            if (l.find("is mapped unlike") != std::string::npos) line = l;
        ASSERT_FALSE(line.empty()) << "bake printed no warning: " << bake.err;
        EXPECT_NE(line.find("material 0 'm0'"), std::string::npos) << line;
        EXPECT_NE(line.find(std::string("metallicRoughnessTexture ") + c.orm_mapping), std::string::npos) << line;
        EXPECT_NE(line.find(std::string("normalTexture ") + c.normal_mapping), std::string::npos) << line;
        const std::string message = line.substr(line.find(in.string()));
        EXPECT_NE(plan.out.find(message), std::string::npos) << "plan says the same: " << plan.out;

        const json out = read_json(dir / "out" / (std::string(c.name) + ".gltf"));
        const json& ext = extension_of(out, 0);
        EXPECT_EQ(ext["roughnessReplaced"], false) << ext.dump();
        EXPECT_EQ(output_kinds(ext).count("roughness"), 0u) << "no constant replaces the ORM: " << ext.dump();
        EXPECT_EQ(output_kinds(ext).count("kernel"), 1u) << ext.dump();
        EXPECT_FALSE(ext["source"].contains("roughness")) << ext.dump();
        EXPECT_FALSE(ext["folded"].contains("roughnessFactor")) << ext.dump();
        for (const auto& e : fs::directory_iterator(dir / "out"))
            EXPECT_EQ(e.path().filename().string().find("_roughness"), std::string::npos) << e.path();
        fs::remove_all(dir);
    }
}

// Generated TANGENT follows the normal texture's texCoord: on TEXCOORD_1 = (v, u) of the sphere, T is the
// meridian direction dP/dtheta (independent computation from the parametrisation), and B = cross(N, T) w
// points along decreasing TEXCOORD_1 v (= -dP/dphi).
TEST(SceneSemantics, GeneratedTangentsFollowTheNormalTexturesTexCoord) {
    const fs::path dir = temp_dir("sem_tangents");
    const fs::path in = write_sphere(dir, "uv1");
    json g = read_json(in);
    add_images(g);
    g["materials"][0]["normalTexture"] = {{"index", 0}, {"texCoord", 1}};
    g["materials"][0]["pbrMetallicRoughness"]["roughnessFactor"] = 0.1;
    write_json(in, g);
    const RunResult bake = run_specbake({"bake", "-q", in.string(), "-o", (dir / "out").string()}, dir);
    ASSERT_EQ(bake.exit_code, 0) << bake.err;

    tinygltf::Model m;
    std::string err;
    ASSERT_TRUE(load_model(dir / "out/uv1.gltf", m, err)) << err;
    const auto& attrs = m.meshes[0].primitives[0].attributes;
    ASSERT_TRUE(attrs.count("TANGENT")) << "tangents are generated with the curvature";
    const std::vector<float> t = float_accessor(m, attrs.at("TANGENT"));
    const std::vector<float> p = float_accessor(m, attrs.at("POSITION"));
    const std::vector<float> n = float_accessor(m, attrs.at("NORMAL"));
    const std::vector<float> uv1 = float_accessor(m, attrs.at("TEXCOORD_1"));
    size_t checked = 0;
    double worst = 1.0;
    for (size_t v = 0; v < p.size() / 3; ++v) {
        const double theta = uv1[2 * v] * M_PI, phi = uv1[2 * v + 1] * 2 * M_PI;
        if (theta < 0.15 * M_PI || theta > 0.85 * M_PI) continue;  // the poles, where the frame turns
        const double meridian[3] = {std::cos(theta) * std::cos(phi), -std::sin(theta), std::cos(theta) * std::sin(phi)};
        const double along[3] = {-std::sin(phi), 0.0, std::cos(phi)};  // dP/dphi, unit
        const double T[3] = {t[4 * v], t[4 * v + 1], t[4 * v + 2]}, w = t[4 * v + 3];
        const double N[3] = {n[3 * v], n[3 * v + 1], n[3 * v + 2]};
        const double B[3] = {(N[1] * T[2] - N[2] * T[1]) * w, (N[2] * T[0] - N[0] * T[2]) * w,
                             (N[0] * T[1] - N[1] * T[0]) * w};
        const double align = T[0] * meridian[0] + T[1] * meridian[1] + T[2] * meridian[2];
        worst = std::min(worst, align);
        EXPECT_LT(B[0] * along[0] + B[1] * along[1] + B[2] * along[2], -0.9) << "vertex " << v;
        ++checked;
    }
    EXPECT_GT(checked, 500u);
    EXPECT_GT(worst, 0.99) << "T follows dP/du of TEXCOORD_1 (before: TEXCOORD_0's, alignment near 0)";
    fs::remove_all(dir);
}

// A primitive whose materials (here through KHR_materials_variants) use different texCoords for their
// normal textures is reported: no one generated frame fits both.
TEST(SceneSemantics, MaterialsDisagreeingOnTheNormalTexCoordAreReported) {
    const fs::path dir = temp_dir("sem_variants");
    const fs::path in = write_sphere(dir, "variants", 2);
    json g = read_json(in);
    add_images(g);
    g["materials"][0]["normalTexture"] = {{"index", 0}, {"texCoord", 1}};
    g["materials"][1]["normalTexture"] = {{"index", 0}};
    g["materials"][0]["pbrMetallicRoughness"]["roughnessFactor"] = 0.1;
    g["extensionsUsed"] = {"KHR_materials_variants"};
    g["extensions"]["KHR_materials_variants"] = {{"variants", {{{"name", "a"}}, {{"name", "b"}}}}};
    g["meshes"][0]["primitives"][0]["extensions"]["KHR_materials_variants"] = {
        {"mappings", {{{"material", 0}, {"variants", {0}}}, {{"material", 1}, {"variants", {1}}}}}};
    write_json(in, g);
    const RunResult plan = run_specbake({"plan", in.string()}, dir);
    ASSERT_EQ(plan.exit_code, 0) << plan.err;
    EXPECT_NE(plan.out.find("generated tangents follow TEXCOORD_1 (material 0 'm0' normalTexture), but material 1 "
                            "'m1' normalTexture uses TEXCOORD_0"),
              std::string::npos)
        << plan.out;
    fs::remove_all(dir);
}

// Three materials with the same inputs, the third through a second image entry naming the same PNG: one
// bake, one set of files, each listed once in the manifest with every material that uses it.
TEST(SceneSemantics, IdenticalInputsBakeOnceAndTheManifestListsEveryUser) {
    const fs::path dir = temp_dir("sem_shared");
    const fs::path in = write_sphere(dir, "shared", 3);
    json g = read_json(in);
    add_images(g);
    g["images"].push_back({{"uri", "./normal.png"}});
    g["textures"].push_back({{"source", 2}});
    for (int k = 0; k < 3; ++k) {
        g["materials"][size_t(k)]["normalTexture"] = {{"index", k == 2 ? 2 : 0}};
        g["materials"][size_t(k)]["pbrMetallicRoughness"]["metallicRoughnessTexture"] = {{"index", 1}};
    }
    // Every material is used by a primitive of its own on the same vertex data.
    json prim = g["meshes"][0]["primitives"][0];
    for (int k = 1; k < 3; ++k) {
        prim["material"] = k;
        g["meshes"][0]["primitives"].push_back(prim);
    }
    write_json(in, g);
    const RunResult bake = run_specbake({"bake", "-q", in.string(), "-o", (dir / "out").string()}, dir);
    ASSERT_EQ(bake.exit_code, 0) << bake.err;
    const json out = read_json(dir / "out/shared.gltf");
    const json uris = extension_of(out, 0)["outputs"];
    ASSERT_FALSE(uris.empty());
    for (int k = 1; k < 3; ++k) EXPECT_EQ(extension_of(out, k)["outputs"], uris) << "material " << k;

    auto manifest = io::read_manifest(dir / "out/manifest.json");
    ASSERT_TRUE(manifest) << manifest.error().message;
    std::map<std::string, int> listed;
    size_t textures = 0;
    for (const io::ManifestOutput& o : manifest->outputs) {
        ++listed[o.path];
        if (o.kind == "scene" || o.kind == "buffer" || o.kind == "image") continue;
        ++textures;
        EXPECT_EQ(o.extra.value("materials", json()), json({0, 1, 2})) << o.path;
    }
    for (const auto& [path, count] : listed) EXPECT_EQ(count, 1) << path;
    EXPECT_EQ(textures, uris.size()) << "one bake's files";
    fs::remove_all(dir);
}

// The extension says what the baked textures hold: normalTexture.scale and roughnessFactor folded in, the
// texCoord and transform they use.
TEST(SceneSemantics, ExtensionRecordsFoldedFactorsAndMapping) {
    const fs::path dir = temp_dir("sem_folded");
    const fs::path in = write_sphere(dir, "folded");
    json g = read_json(in);
    add_images(g);
    g["extensionsUsed"] = {"KHR_texture_transform"};
    g["materials"][0]["normalTexture"] = {{"index", 0}, {"scale", 0.3}, {"texCoord", 1}, {"extensions", transform(3.0)}};
    g["materials"][0]["pbrMetallicRoughness"]["metallicRoughnessTexture"] = {
        {"index", 1}, {"texCoord", 1}, {"extensions", transform(3.0)}};
    write_json(in, g);
    const RunResult bake = run_specbake({"bake", "-q", in.string(), "-o", (dir / "out").string()}, dir);
    ASSERT_EQ(bake.exit_code, 0) << bake.err;
    const json out = read_json(dir / "out/folded.gltf");
    const json& ext = extension_of(out, 0);
    EXPECT_EQ(ext["texCoord"], 1);
    EXPECT_NEAR(ext["folded"]["normalScale"].get<double>(), 0.3, 1e-9);
    EXPECT_NEAR(ext["folded"]["roughnessFactor"].get<double>(), 0.5, 1e-6);
    EXPECT_EQ(ext["roughnessReplaced"], true);
    EXPECT_EQ(ext["KHR_texture_transform"], json({{"offset", {0.0, 0.0}}, {"rotation", 0.0}, {"scale", {3.0, 3.0}}}));
    fs::remove_all(dir);
}

// One normal map under two materials with different roughness: each gets its own roughness, and the
// kernel and mean-normal files (which depend on the normal map alone) are written once and named by both.
TEST(SceneSemantics, NormalOnlyOutputsAreWrittenOnceForDifferentRoughness) {
    const fs::path dir = temp_dir("sem_normal_shared");
    const fs::path in = write_sphere(dir, "two", 2);
    json g = read_json(in);
    add_images(g);
    for (int k = 0; k < 2; ++k) {
        g["materials"][size_t(k)]["normalTexture"] = {{"index", 0}};
        g["materials"][size_t(k)]["pbrMetallicRoughness"]["metallicRoughnessTexture"] = {{"index", 1}};
        g["materials"][size_t(k)]["pbrMetallicRoughness"]["roughnessFactor"] = k == 0 ? 0.5 : 0.8;
    }
    json prim = g["meshes"][0]["primitives"][0];
    prim["material"] = 1;
    g["meshes"][0]["primitives"].push_back(prim);
    write_json(in, g);
    const RunResult bake = run_specbake({"bake", "-q", in.string(), "-o", (dir / "out").string()}, dir);
    ASSERT_EQ(bake.exit_code, 0) << bake.err;
    const json out = read_json(dir / "out/two.gltf");
    std::map<std::string, std::string> uri[2];
    for (int k = 0; k < 2; ++k)
        for (const json& o : extension_of(out, k)["outputs"]) uri[k][o["kind"]] = o["uri"];
    ASSERT_TRUE(uri[0].count("roughness") && uri[1].count("roughness"));
    EXPECT_NE(uri[0]["roughness"], uri[1]["roughness"]);
    for (const char* kind : {"kernel", "normal", "lean"}) {
        ASSERT_TRUE(uri[0].count(kind) && uri[1].count(kind)) << kind;
        EXPECT_EQ(uri[0][kind], uri[1][kind]) << kind;
    }
    size_t kernels = 0;
    for (const auto& e : fs::directory_iterator(dir / "out"))
        kernels += e.path().filename().string().find("_kernel") != std::string::npos;
    EXPECT_EQ(kernels, 1u);
    auto manifest = io::read_manifest(dir / "out/manifest.json");
    ASSERT_TRUE(manifest) << manifest.error().message;
    for (const io::ManifestOutput& o : manifest->outputs) {
        if (o.kind == "kernel") {
            EXPECT_EQ(o.extra.value("materials", json()), json({0, 1}));
        }
    }
    fs::remove_all(dir);
}
