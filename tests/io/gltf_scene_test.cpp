// io/gltf_scene: accessor decoding (component types, normalisation, byteStride, sparse, strips/fans),
// bad indices, and the writer's promises (appended buffer, existing bytes untouched, extension in
// extensionsUsed only, images kept as they were). The glTF files are written here by hand, byte by byte,
// so the expected values are independent of the code under test.
#include "io/gltf_scene.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstring>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;
using nlohmann::json;
using namespace specbake;
using namespace specbake::io;

namespace {

fs::path temp_dir(const std::string& name) {
    fs::path d = fs::temp_directory_path() / ("specbake_gltf_" + name + "_" + std::to_string(::getpid()));
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

template <class T>
void put(std::vector<uint8_t>& b, T v) {
    uint8_t raw[sizeof(T)];
    std::memcpy(raw, &v, sizeof(T));
    b.insert(b.end(), raw, raw + sizeof(T));
}

void pad4(std::vector<uint8_t>& b) {
    while (b.size() % 4) b.push_back(0);
}

// A quad (4 vertices) with: interleaved POSITION (float, stride 20 with 8 bytes of other data),
// NORMAL as normalised signed bytes (stride 4), TEXCOORD_0 as normalised unsigned shorts, a sparse
// override of vertex 2's position, indices as unsigned bytes; plus a second primitive as a triangle strip.
struct HandMade {
    std::vector<uint8_t> bin;
    json doc;
};

HandMade make_quad_file() {
    HandMade h;
    auto& b = h.bin;
    const float pos[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    const size_t pos_offset = b.size();
    for (int v = 0; v < 4; ++v) {
        for (int c = 0; c < 3; ++c) put<float>(b, pos[v][c]);
        put<float>(b, 99.0f);  // other interleaved data
        put<float>(b, -99.0f);
    }
    const size_t nrm_offset = b.size();
    for (int v = 0; v < 4; ++v) {
        put<int8_t>(b, 0);
        put<int8_t>(b, v == 3 ? -128 : 0);  // -128 normalises to -1 (clamped), not -1.0079
        put<int8_t>(b, 127);
        put<int8_t>(b, 0);  // padding to a 4-byte stride
    }
    const size_t uv_offset = b.size();
    const uint16_t uv[4][2] = {{0, 0}, {65535, 0}, {65535, 65535}, {0, 32768}};
    for (auto& t : uv) put<uint16_t>(b, t[0]), put<uint16_t>(b, t[1]);
    const size_t idx_offset = b.size();
    for (uint8_t i : {0, 1, 2, 0, 2, 3}) put<uint8_t>(b, i);
    pad4(b);
    const size_t sparse_idx_offset = b.size();
    put<uint16_t>(b, 2);
    pad4(b);
    const size_t sparse_val_offset = b.size();
    for (float f : {2.0f, 3.0f, 4.0f}) put<float>(b, f);
    const size_t strip_offset = b.size();
    for (uint16_t i : {0, 1, 3, 2}) put<uint16_t>(b, i);
    pad4(b);

    h.doc = {
        {"asset", {{"version", "2.0"}, {"extras", {{"note", "hand made"}}}}},
        {"extensionsUsed", {"KHR_materials_emissive_strength", "VENDOR_unknown"}},
        {"scene", 0},
        {"scenes", {{{"nodes", {0}}}}},
        {"nodes", {{{"mesh", 0}, {"scale", {2.0, 2.0, 2.0}}, {"extras", {{"id", 7}}},
                    {"extensions", {{"VENDOR_unknown", {{"payload", {1, 2, 3}}}}}}}}},
        {"materials", {{{"name", "m"},
                        {"pbrMetallicRoughness", {{"roughnessFactor", 0.25}}},
                        {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 4.0}}}}}}}},
        {"meshes",
         {{{"name", "quad"},
           {"primitives",
            {{{"attributes", {{"POSITION", 0}, {"NORMAL", 1}, {"TEXCOORD_0", 2}}}, {"indices", 3}, {"material", 0}},
             {{"attributes", {{"POSITION", 0}}}, {"indices", 4}, {"mode", 5}}}}}}},
        {"buffers", {{{"byteLength", b.size()}, {"uri", "quad.bin"}}}},
        {"bufferViews",
         {{{"buffer", 0}, {"byteOffset", pos_offset}, {"byteLength", 80}, {"byteStride", 20}},
          {{"buffer", 0}, {"byteOffset", nrm_offset}, {"byteLength", 16}, {"byteStride", 4}},
          {{"buffer", 0}, {"byteOffset", uv_offset}, {"byteLength", 16}},
          {{"buffer", 0}, {"byteOffset", idx_offset}, {"byteLength", 6}},
          {{"buffer", 0}, {"byteOffset", sparse_idx_offset}, {"byteLength", 2}},
          {{"buffer", 0}, {"byteOffset", sparse_val_offset}, {"byteLength", 12}},
          {{"buffer", 0}, {"byteOffset", strip_offset}, {"byteLength", 8}}}},
        {"accessors",
         {{{"bufferView", 0}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"},
           {"min", {0, 0, 0}}, {"max", {2, 3, 4}},
           {"sparse", {{"count", 1}, {"indices", {{"bufferView", 4}, {"componentType", 5123}}},
                       {"values", {{"bufferView", 5}}}}}},
          {{"bufferView", 1}, {"componentType", 5120}, {"normalized", true}, {"count", 4}, {"type", "VEC3"}},
          {{"bufferView", 2}, {"componentType", 5123}, {"normalized", true}, {"count", 4}, {"type", "VEC2"}},
          {{"bufferView", 3}, {"componentType", 5121}, {"count", 6}, {"type", "SCALAR"}},
          {{"bufferView", 6}, {"componentType", 5123}, {"count", 4}, {"type", "SCALAR"}}}},
    };
    return h;
}

fs::path write_hand_made(const fs::path& dir, const HandMade& h) {
    std::ofstream(dir / "quad.bin", std::ios::binary).write(reinterpret_cast<const char*>(h.bin.data()),
                                                            std::streamsize(h.bin.size()));
    std::ofstream(dir / "quad.gltf") << h.doc.dump(2);
    return dir / "quad.gltf";
}

json read_json(const fs::path& p) {
    std::ifstream in(p);
    return json::parse(in);
}

}  // namespace

TEST(GltfScene, DecodesStridedNormalizedSparseAccessors) {
    const fs::path dir = temp_dir("decode");
    auto scene = GltfScene::load(write_hand_made(dir, make_quad_file()));
    ASSERT_TRUE(scene) << scene.error().message;
    auto mesh = scene->primitive_mesh({0, 0});
    ASSERT_TRUE(mesh) << mesh.error().message;
    ASSERT_EQ(mesh->vertex_count(), 4u);
    const std::vector<float> positions = {0, 0, 0, 1, 0, 0, 2, 3, 4, 0, 1, 0};  // vertex 2 replaced (sparse)
    EXPECT_EQ(mesh->positions, positions);
    EXPECT_FLOAT_EQ(mesh->normals[2], 1.0f);     // 127 / 127
    EXPECT_FLOAT_EQ(mesh->normals[10], -1.0f);   // max(-128 / 127, -1)
    EXPECT_FLOAT_EQ(mesh->uv0[2], 1.0f);         // 65535 / 65535
    EXPECT_FLOAT_EQ(mesh->uv0[7], float(32768.0 / 65535.0));
    EXPECT_EQ(mesh->indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
    EXPECT_EQ(mesh->material, 0);

    // Triangle strip 0 1 3 2: triangles (0 1 3) and, with the winding flipped, (3 1 2).
    auto strip = scene->primitive_mesh({0, 1});
    ASSERT_TRUE(strip) << strip.error().message;
    EXPECT_EQ(strip->indices, (std::vector<uint32_t>{0, 1, 3, 3, 1, 2}));

    const auto prims = scene->primitives();
    ASSERT_EQ(prims.size(), 2u);
    EXPECT_DOUBLE_EQ(prims[0].min_instance_scale, 2.0);
    EXPECT_DOUBLE_EQ(prims[0].max_instance_scale, 2.0);
    EXPECT_EQ(prims[1].mode, 5);
    fs::remove_all(dir);
}

TEST(GltfScene, RejectsOutOfRangeIndexNamingFileAndPrimitive) {
    const fs::path dir = temp_dir("badindex");
    HandMade h = make_quad_file();
    h.bin[h.doc["bufferViews"][3]["byteOffset"].get<size_t>() + 5] = 9;  // index 9 of 4 vertices
    auto scene = GltfScene::load(write_hand_made(dir, h));
    ASSERT_TRUE(scene) << scene.error().message;
    auto mesh = scene->primitive_mesh({0, 0});
    ASSERT_FALSE(mesh);
    EXPECT_NE(mesh.error().message.find("quad.gltf"), std::string::npos) << mesh.error().message;
    EXPECT_NE(mesh.error().message.find("index 9"), std::string::npos) << mesh.error().message;
    EXPECT_EQ(mesh.error().message.find('\n'), std::string::npos);
    fs::remove_all(dir);
}

TEST(GltfScene, RejectsAccessorPastBufferEnd) {
    const fs::path dir = temp_dir("pastend");
    HandMade h = make_quad_file();
    h.doc["accessors"][2]["count"] = 40;
    auto scene = GltfScene::load(write_hand_made(dir, h));
    ASSERT_TRUE(scene) << scene.error().message;
    auto mesh = scene->primitive_mesh({0, 0});
    ASSERT_FALSE(mesh);
    EXPECT_NE(mesh.error().message.find("TEXCOORD_0"), std::string::npos) << mesh.error().message;
}

TEST(GltfScene, WriteAppendsAndKeepsEverythingElse) {
    const fs::path dir = temp_dir("write");
    const HandMade h = make_quad_file();
    auto scene = GltfScene::load(write_hand_made(dir, h));
    ASSERT_TRUE(scene) << scene.error().message;
    std::vector<float> curvature(16);
    for (size_t i = 0; i < curvature.size(); ++i) curvature[i] = float(i) * 0.5f;
    ASSERT_TRUE(scene->set_vertex_attribute({0, 0}, kCurvatureAttribute, curvature, 4));
    EXPECT_FALSE(scene->set_vertex_attribute({0, 0}, kCurvatureAttribute, std::vector<float>(12), 4));
    scene->set_material_extension(0, {{"texCoord", 0}});
    const fs::path out_dir = dir / "out";
    auto written = scene->write(out_dir / "quad.gltf");
    ASSERT_TRUE(written) << written.error().message;

    const json out = read_json(out_dir / "quad.gltf");
    // Everything of the input is still there.
    EXPECT_EQ(out["asset"]["extras"], h.doc["asset"]["extras"]);
    EXPECT_EQ(out["nodes"][0]["extras"], h.doc["nodes"][0]["extras"]);
    EXPECT_EQ(out["nodes"][0]["extensions"], h.doc["nodes"][0]["extensions"]);
    EXPECT_EQ(out["nodes"][0]["scale"], h.doc["nodes"][0]["scale"]);
    EXPECT_EQ(out["materials"][0]["extensions"]["KHR_materials_emissive_strength"],
              h.doc["materials"][0]["extensions"]["KHR_materials_emissive_strength"]);
    EXPECT_EQ(out["accessors"][0]["sparse"]["count"], 1);
    EXPECT_EQ(out["meshes"][0]["primitives"][1]["mode"], 5);
    // The extension is used, not required.
    const auto used = out["extensionsUsed"].get<std::vector<std::string>>();
    EXPECT_NE(std::find(used.begin(), used.end(), kSpecbakeExtension), used.end());
    EXPECT_NE(std::find(used.begin(), used.end(), "VENDOR_unknown"), used.end());
    EXPECT_FALSE(out.contains("extensionsRequired"));
    EXPECT_EQ(out["materials"][0]["extensions"][kSpecbakeExtension]["texCoord"], 0);
    // The original buffer is byte-identical; the curvature lives in a new buffer.
    ASSERT_EQ(out["buffers"].size(), 2u);
    EXPECT_EQ(out["buffers"][0]["uri"], "quad.bin");
    std::ifstream in(out_dir / "quad.bin", std::ios::binary);
    const std::vector<uint8_t> bin((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(bin, h.bin);
    const int acc = out["meshes"][0]["primitives"][0]["attributes"][kCurvatureAttribute];
    EXPECT_EQ(out["accessors"][acc]["type"], "VEC4");
    EXPECT_EQ(out["accessors"][acc]["componentType"], 5126);
    const int view = out["accessors"][acc]["bufferView"];
    EXPECT_EQ(out["bufferViews"][view]["buffer"], 1);
    const std::string extra_uri = out["buffers"][1]["uri"];
    std::ifstream ex(out_dir / extra_uri, std::ios::binary);
    std::vector<float> back(16);
    ex.seekg(out["bufferViews"][view].value("byteOffset", 0));
    ex.read(reinterpret_cast<char*>(back.data()), 64);
    EXPECT_EQ(back, curvature);

    // Reloading the output gives the same vertex data and the curvature attribute.
    auto again = GltfScene::load(out_dir / "quad.gltf");
    ASSERT_TRUE(again) << again.error().message;
    EXPECT_TRUE(again->primitives()[0].has_curvature);
    EXPECT_EQ(again->primitive_mesh({0, 0})->positions, scene->primitive_mesh({0, 0})->positions);
    fs::remove_all(dir);
}

TEST(GltfScene, GlbOutputIsValidContainer) {
    const fs::path dir = temp_dir("glb");
    auto scene = GltfScene::load(write_hand_made(dir, make_quad_file()));
    ASSERT_TRUE(scene) << scene.error().message;
    ASSERT_TRUE(scene->set_vertex_attribute({0, 0}, kCurvatureAttribute, std::vector<float>(16, 1.0f), 4));
    auto written = scene->write(dir / "out" / "quad.glb");
    ASSERT_TRUE(written) << written.error().message;
    std::ifstream in(dir / "out" / "quad.glb", std::ios::binary);
    const std::vector<uint8_t> glb((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_GE(glb.size(), 20u);
    uint32_t magic, version, length, json_length, json_type;
    std::memcpy(&magic, glb.data(), 4);
    std::memcpy(&version, glb.data() + 4, 4);
    std::memcpy(&length, glb.data() + 8, 4);
    std::memcpy(&json_length, glb.data() + 12, 4);
    std::memcpy(&json_type, glb.data() + 16, 4);
    EXPECT_EQ(magic, 0x46546C67u);
    EXPECT_EQ(version, 2u);
    EXPECT_EQ(length, glb.size());
    EXPECT_EQ(json_length % 4, 0u);
    EXPECT_EQ(json_type, 0x4E4F534Au);
    auto again = GltfScene::load(dir / "out" / "quad.glb");
    ASSERT_TRUE(again) << again.error().message;
    EXPECT_TRUE(again->source_is_binary());
    EXPECT_TRUE(again->primitives()[0].has_curvature);
    fs::remove_all(dir);
}

TEST(GltfScene, MissingBufferFileIsOneLineError) {
    const fs::path dir = temp_dir("missing");
    HandMade h = make_quad_file();
    h.doc["buffers"][0]["uri"] = "nowhere.bin";
    auto scene = GltfScene::load(write_hand_made(dir, h));
    ASSERT_FALSE(scene);
    EXPECT_NE(scene.error().message.find("quad.gltf"), std::string::npos) << scene.error().message;
    EXPECT_EQ(scene.error().message.find('\n'), std::string::npos);
    fs::remove_all(dir);
}
