// io/gltf_scene: accessor decoding (component types, normalisation, byteStride, sparse, strips/fans),
// bad indices, and the writer's promises (appended buffer, existing bytes untouched, extension in
// extensionsUsed only, images kept as they were). The glTF files are written here by hand, byte by byte,
// so the expected values are independent of the code under test.
#include "io/gltf/gltf_scene.h"
#include "io/files/sha256.h"

#include <gtest/gtest.h>
#include <tiny_gltf.h>
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

// glTF 2.0 Sec. 3.6.2.3: sparse indices are unsigned integers. A FLOAT index (NaN, or past the end) must be
// refused, not converted to an array position.
TEST(GltfScene, SparseIndicesMustBeUnsignedIntegersInRange) {
    const fs::path dir = temp_dir("sparsefloat");
    HandMade h = make_quad_file();
    h.doc["accessors"][0]["sparse"]["indices"]["componentType"] = 5126;
    auto scene = GltfScene::load(write_hand_made(dir, h));
    ASSERT_TRUE(scene) << scene.error().message;
    auto mesh = scene->primitive_mesh({0, 0});
    ASSERT_FALSE(mesh);
    EXPECT_NE(mesh.error().message.find("sparse indices have an invalid component type"), std::string::npos)
        << mesh.error().message;
    // The fuzzer's reproducers, a GLB whose float sparse index is NaN and one whose index is far too large,
    // wrote out of bounds (the sanitizer build of this test reports that); every accessor read must stay
    // inside its array.
    for (const char* name : {"sparse-indices-float-index-nan.glb", "sparse-indices-float-index-too-large.glb"}) {
        auto glb = GltfScene::load(fs::path(SPECBAKE_SOURCE_DIR) / "fuzz/regressions/gltf" / name);
        if (!glb) continue;  // refused while reading
        for (const auto& p : glb->primitives()) {
            auto m = glb->primitive_mesh(p.ref);
            if (m) EXPECT_EQ(m->positions.size(), 3 * m->vertex_count()) << name;
        }
    }
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

namespace {

std::vector<uint8_t> file_bytes(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::vector<uint8_t>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

uint32_t u32_at(const std::vector<uint8_t>& b, size_t offset) {
    uint32_t v;
    std::memcpy(&v, b.data() + offset, 4);
    return v;
}

bool keep_encoded(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
    return true;
}

}  // namespace

// A .gltf with an external buffer and external images written as .glb: one file, every byte inside it.
// The GLB is taken apart here by its chunk layout (glTF 2.0 Sec. 4.4), independently of the writer.
TEST(GltfScene, GlbOutputEmbedsExternalBuffersAndImages) {
    const fs::path dir = temp_dir("embed");
    HandMade h = make_quad_file();
    const std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', 1, 2, 3, 4, 5};  // never decoded by the writer
    const std::vector<uint8_t> jpg = {0xFF, 0xD8, 0xFF, 9, 8, 7};
    fs::create_directories(dir / "maps");
    std::ofstream(dir / "maps" / "a b.png", std::ios::binary).write(reinterpret_cast<const char*>(png.data()), 9);
    std::ofstream(dir / "c.jpg", std::ios::binary).write(reinterpret_cast<const char*>(jpg.data()), 6);
    h.doc["images"] = {{{"uri", "maps/a%20b.png"}}, {{"uri", "c.jpg"}, {"name", "jpeg"}}, {{"uri", "maps/a%20b.png"}}};
    h.doc["textures"] = {{{"source", 0}}, {{"source", 1}}, {{"source", 2}}};
    h.doc["materials"][0]["normalTexture"] = {{"index", 0}};
    auto scene = GltfScene::load(write_hand_made(dir, h));
    ASSERT_TRUE(scene) << scene.error().message;
    std::vector<float> curvature(16);
    for (size_t i = 0; i < curvature.size(); ++i) curvature[i] = 0.25f * float(i) - 1.0f;
    ASSERT_TRUE(scene->set_vertex_attribute({0, 0}, kCurvatureAttribute, curvature, 4));
    const fs::path out_dir = dir / "out";
    auto written = scene->write(out_dir / "quad.glb");
    ASSERT_TRUE(written) << written.error().message;

    // Exactly one file, and the hash reported is the hash of its bytes (portable path, for independence).
    ASSERT_EQ(written->size(), 1u);
    size_t files = 0;
    for (const auto& e : fs::recursive_directory_iterator(out_dir)) files += e.is_regular_file();
    EXPECT_EQ(files, 1u);
    const std::vector<uint8_t> glb = file_bytes(out_dir / "quad.glb");
    EXPECT_EQ((*written)[0].sha256, sha256_hex_portable(glb));

    ASSERT_GE(glb.size(), 28u);
    EXPECT_EQ(u32_at(glb, 0), 0x46546C67u);
    EXPECT_EQ(u32_at(glb, 8), glb.size());
    const uint32_t json_length = u32_at(glb, 12);
    ASSERT_EQ(u32_at(glb, 16), 0x4E4F534Au);
    const json doc = json::parse(glb.begin() + 20, glb.begin() + 20 + json_length);
    const size_t bin_header = 20 + json_length;
    ASSERT_LE(bin_header + 8, glb.size());
    const uint32_t bin_length = u32_at(glb, bin_header);
    EXPECT_EQ(u32_at(glb, bin_header + 4), 0x004E4942u);
    EXPECT_EQ(bin_length % 4, 0u);
    EXPECT_EQ(bin_header + 8 + bin_length, glb.size());
    const uint8_t* bin = glb.data() + bin_header + 8;

    ASSERT_EQ(doc["buffers"].size(), 1u);
    EXPECT_FALSE(doc["buffers"][0].contains("uri"));
    EXPECT_LE(doc["buffers"][0]["byteLength"].get<size_t>(), bin_length);
    auto view_bytes = [&](int view) {
        const json& bv = doc["bufferViews"][size_t(view)];
        EXPECT_EQ(bv["buffer"], 0);
        const size_t offset = bv.value("byteOffset", size_t(0));
        return std::vector<uint8_t>(bin + offset, bin + offset + bv["byteLength"].get<size_t>());
    };
    // Images: no URI, a buffer view holding the file's bytes, the MIME type; one file stored once.
    ASSERT_EQ(doc["images"].size(), 3u);
    for (const json& img : doc["images"]) EXPECT_FALSE(img.contains("uri"));
    EXPECT_EQ(doc["images"][0]["mimeType"], "image/png");
    EXPECT_EQ(doc["images"][1]["mimeType"], "image/jpeg");
    EXPECT_EQ(doc["images"][1]["name"], "jpeg");
    EXPECT_EQ(view_bytes(doc["images"][0]["bufferView"]), png);
    EXPECT_EQ(view_bytes(doc["images"][1]["bufferView"]), jpg);
    EXPECT_EQ(doc["images"][2]["bufferView"], doc["images"][0]["bufferView"]);
    // The input buffer's bytes, unchanged, behind every original buffer view.
    for (size_t v = 0; v < h.doc["bufferViews"].size(); ++v) {
        const json& in = h.doc["bufferViews"][v];
        const size_t offset = in["byteOffset"];
        EXPECT_EQ(view_bytes(int(v)), std::vector<uint8_t>(h.bin.begin() + long(offset),
                                                           h.bin.begin() + long(offset + in["byteLength"].get<size_t>())))
            << "bufferView " << v;
        EXPECT_EQ(doc["bufferViews"][v].value("byteStride", 0), in.value("byteStride", 0));
    }
    const int acc = doc["meshes"][0]["primitives"][0]["attributes"][kCurvatureAttribute];
    const std::vector<uint8_t> k = view_bytes(doc["accessors"][size_t(acc)]["bufferView"]);
    ASSERT_EQ(k.size(), 64u);
    EXPECT_EQ(std::memcmp(k.data(), curvature.data(), 64), 0);

    // What a conforming reader relies on (glTF 2.0 Sec. 4.4 and 5.11), checked on the chunks parsed above
    // rather than through a third-party importer: the JSON chunk padded with spaces and the BIN chunk with
    // zeros, the buffer's length within 3 bytes of the chunk, every view inside the buffer and every
    // accessor inside its view, aligned to its component size.
    size_t json_end = bin_header;
    while (json_end > 20 && glb[json_end - 1] == ' ') --json_end;
    EXPECT_EQ(glb[json_end - 1], '}');
    EXPECT_LE(bin_header - json_end, 3u);
    const size_t buffer_length = doc["buffers"][0]["byteLength"];
    EXPECT_GE(buffer_length + 3, bin_length);
    for (size_t i = buffer_length; i < bin_length; ++i) EXPECT_EQ(bin[i], 0) << "BIN padding byte " << i;
    for (const json& bv : doc["bufferViews"])
        EXPECT_LE(bv.value("byteOffset", size_t(0)) + bv["byteLength"].get<size_t>(), buffer_length) << bv.dump();
    auto component_bytes = [](int type) { return type == 5126 || type == 5125 ? 4 : type == 5123 || type == 5122 ? 2 : 1; };
    auto components = [](const std::string& t) { return t == "SCALAR" ? 1 : t == "VEC2" ? 2 : t == "VEC3" ? 3 : t == "VEC4" ? 4 : 16; };
    for (const json& a : doc["accessors"]) {
        if (!a.contains("bufferView")) continue;
        const json& bv = doc["bufferViews"][a["bufferView"].get<size_t>()];
        const size_t size = size_t(component_bytes(a["componentType"])), element = size * size_t(components(a["type"]));
        const size_t stride = bv.value("byteStride", element), offset = a.value("byteOffset", size_t(0));
        EXPECT_EQ((bv.value("byteOffset", size_t(0)) + offset) % size, 0u) << a.dump();
        EXPECT_LE(offset + stride * (a["count"].get<size_t>() - 1) + element, bv["byteLength"].get<size_t>()) << a.dump();
    }
    // The positions decoded from the chunks alone (accessor -> view -> BIN, with its stride) are the quad's.
    {
        const json& a = doc["accessors"][doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"].get<size_t>()];
        const json& bv = doc["bufferViews"][a["bufferView"].get<size_t>()];
        const size_t stride = bv.value("byteStride", size_t(12));
        const float quad[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
        ASSERT_EQ(a["count"], 4);
        for (size_t v = 0; v < 4; ++v)
            for (size_t c = 0; c < 3; ++c) {
                float x = 0;
                std::memcpy(&x, bin + bv.value("byteOffset", size_t(0)) + a.value("byteOffset", size_t(0)) + v * stride + 4 * c, 4);
                EXPECT_EQ(x, quad[v][c]) << "vertex " << v << " component " << c;
            }
    }
    // tinygltf loads it.
    tinygltf::Model model;
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(&keep_encoded, nullptr);
    std::string err, warn;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &err, &warn, (out_dir / "quad.glb").string())) << err;
    EXPECT_EQ(model.images.size(), 3u);
    EXPECT_EQ(model.meshes[0].primitives[0].attributes.count(kCurvatureAttribute), 1u);
    auto again = GltfScene::load(out_dir / "quad.glb");
    ASSERT_TRUE(again) << again.error().message;
    EXPECT_EQ(again->primitive_mesh({0, 0})->positions, scene->primitive_mesh({0, 0})->positions);
    EXPECT_EQ(again->image_bytes(1).value(), jpg);
    fs::remove_all(dir);
}

// Hashes reported by write() for a .gltf output are those of the files written; the input hashes the
// loader computed are those of the input files.
TEST(GltfScene, WriteAndLoadReportContentHashes) {
    const fs::path dir = temp_dir("hashes");
    const fs::path input = write_hand_made(dir, make_quad_file());
    auto scene = GltfScene::load(input);
    ASSERT_TRUE(scene) << scene.error().message;
    EXPECT_EQ(scene->content_hash(input), sha256_hex_portable(file_bytes(input)));
    EXPECT_EQ(scene->content_hash(dir / "quad.bin"), sha256_hex_portable(file_bytes(dir / "quad.bin")));
    ASSERT_TRUE(scene->set_vertex_attribute({0, 0}, kCurvatureAttribute, std::vector<float>(16, 2.0f), 4));
    auto written = scene->write(dir / "out" / "quad.gltf");
    ASSERT_TRUE(written) << written.error().message;
    ASSERT_EQ(written->size(), 3u) << "scene, its buffer, the appended buffer";
    for (const GltfScene::WrittenFile& f : *written) EXPECT_EQ(f.sha256, sha256_hex_portable(file_bytes(f.path))) << f.path;
    fs::remove_all(dir);
}

// KHR_materials_clearcoat is read with the extension's defaults (factors 0, scale 1, texCoord 0).
TEST(GltfScene, ReadsClearcoatLayer) {
    const fs::path dir = temp_dir("clearcoat");
    HandMade h = make_quad_file();
    h.doc["images"] = {{{"uri", "n.png"}}, {{"uri", "r.png"}}};
    h.doc["textures"] = {{{"source", 0}}, {{"source", 1}}};
    h.doc["materials"].push_back({{"name", "coated"},
                                  {"extensions",
                                   {{"KHR_materials_clearcoat",
                                     {{"clearcoatFactor", 0.5},
                                      {"clearcoatRoughnessFactor", 0.2},
                                      {"clearcoatRoughnessTexture", {{"index", 1}, {"texCoord", 1}}},
                                      {"clearcoatNormalTexture", {{"index", 0}, {"scale", 0.75}}}}}}}});
    h.doc["materials"].push_back({{"name", "empty coat"}, {"extensions", {{"KHR_materials_clearcoat", json::object()}}}});
    auto scene = GltfScene::load(write_hand_made(dir, h));
    ASSERT_TRUE(scene) << scene.error().message;
    const auto materials = scene->materials();
    ASSERT_EQ(materials.size(), 3u);
    EXPECT_FALSE(materials[0].clearcoat.present);
    const ClearcoatInfo& c = materials[1].clearcoat;
    EXPECT_TRUE(c.present);
    EXPECT_TRUE(c.active());
    EXPECT_DOUBLE_EQ(c.factor, 0.5);
    EXPECT_DOUBLE_EQ(c.roughness_factor, 0.2);
    EXPECT_EQ(c.normal.texture, 0);
    EXPECT_EQ(c.normal.image, 0);
    EXPECT_EQ(c.normal.texcoord, 0);
    EXPECT_DOUBLE_EQ(c.normal_scale, 0.75);
    EXPECT_EQ(c.roughness.image, 1);
    EXPECT_EQ(c.roughness.texcoord, 1);
    EXPECT_EQ(c.factor_texture.texture, -1);
    const ClearcoatInfo& empty = materials[2].clearcoat;
    EXPECT_TRUE(empty.present);
    EXPECT_FALSE(empty.active()) << "clearcoatFactor defaults to 0";
    EXPECT_DOUBLE_EQ(empty.roughness_factor, 0.0);
    EXPECT_EQ(empty.normal.texture, -1);
    fs::remove_all(dir);
}
