// A .glb bake carries its baked textures: the file is parsed here from the GLB chunk layout (glTF 2.0
// Sec. 4.4: header, JSON chunk, BIN chunk) without tinygltf or specbake's reader, and every texture the
// vendor extension names must be a buffer view whose bytes equal the file a .gltf bake writes beside it.
#include "tests/cli/scene_test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstring>

namespace {
using namespace scene_test;
using nlohmann::json;

struct Glb {
    json doc;
    std::string bin;
};

// GLB 2.0: magic "glTF", version 2, total length; chunk 0 JSON (0x4E4F534A), chunk 1 BIN (0x004E4942),
// each chunk length a multiple of 4.
Glb parse_glb(const std::string& b) {
    Glb g;
    EXPECT_GE(b.size(), 20u);
    EXPECT_EQ(b.substr(0, 4), "glTF");
    EXPECT_EQ(le32(b, 4), 2u);
    EXPECT_EQ(le32(b, 8), b.size());
    const uint32_t json_length = le32(b, 12);
    EXPECT_EQ(le32(b, 16), 0x4E4F534Au);
    EXPECT_EQ(json_length % 4, 0u);
    g.doc = json::parse(b.substr(20, json_length));
    const size_t bin_at = 20 + size_t(json_length);
    if (bin_at < b.size()) {
        const uint32_t bin_length = le32(b, bin_at);
        EXPECT_EQ(le32(b, bin_at + 4), 0x004E4942u);
        EXPECT_EQ(bin_length % 4, 0u);
        EXPECT_EQ(bin_at + 8 + bin_length, b.size());
        g.bin = b.substr(bin_at + 8, bin_length);
    }
    return g;
}

TEST(SceneGlbTextures, GlbCarriesEveryBakedTexture) {
    const fs::path scene = fs::path(SPECBAKE_ASSETS_DIR) / "gltf" / "NormalTangentTest" / "NormalTangentTest.gltf";
    if (!fs::exists(scene)) GTEST_SKIP() << "shared asset missing: " << scene;
    const fs::path dir = temp_dir("glb_textures");
    const RunResult glb = run_specbake({"-q", "bake", scene.string(), "--format", "glb", "-o", (dir / "glb").string()}, dir);
    ASSERT_EQ(glb.exit_code, 0) << glb.err;
    const RunResult gltf =
        run_specbake({"-q", "bake", scene.string(), "--format", "gltf", "-o", (dir / "gltf").string()}, dir);
    ASSERT_EQ(gltf.exit_code, 0) << gltf.err;

    // The .glb folder holds the scene and the manifest only.
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir / "glb")) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    EXPECT_EQ(names, (std::vector<std::string>{"NormalTangentTest.glb", "manifest.json"}));

    const Glb g = parse_glb(slurp(dir / "glb" / "NormalTangentTest.glb"));
    ASSERT_EQ(g.doc["buffers"].size(), 1u);
    EXPECT_FALSE(g.doc["buffers"][0].contains("uri"));
    const json beside = json::parse(slurp(dir / "gltf" / "NormalTangentTest.gltf"));
    size_t textures = 0;
    for (size_t m = 0; m < g.doc["materials"].size(); ++m) {
        const json& mat = g.doc["materials"][m];
        if (!mat.contains("extensions") || !mat["extensions"].contains("SPECBAKE_specular_aa")) continue;
        const json& outs = mat["extensions"]["SPECBAKE_specular_aa"]["outputs"];
        const json& file_outs = beside["materials"][m]["extensions"]["SPECBAKE_specular_aa"]["outputs"];
        ASSERT_EQ(outs.size(), file_outs.size());
        for (size_t i = 0; i < outs.size(); ++i) {
            const json& o = outs[i];
            SCOPED_TRACE(o.dump());
            EXPECT_FALSE(o.contains("uri"));
            EXPECT_FALSE(o.contains("embedded"));
            EXPECT_EQ(o["mimeType"], "image/ktx2");
            EXPECT_EQ(o["kind"], file_outs[i]["kind"]);
            const json& view = g.doc["bufferViews"][o["bufferView"].get<size_t>()];
            EXPECT_EQ(view["buffer"], 0);
            const size_t offset = view.value("byteOffset", size_t(0)), length = view["byteLength"].get<size_t>();
            ASSERT_LE(offset + length, g.bin.size());
            const std::string bytes = g.bin.substr(offset, length);
            EXPECT_EQ(bytes.substr(0, 12), std::string("\xABKTX 20\xBB\r\n\x1A\n", 12));
            EXPECT_EQ(bytes, slurp(dir / "gltf" / file_outs[i]["uri"].get<std::string>()));
            ++textures;
        }
    }
    EXPECT_GT(textures, 0u);

    // The manifest lists the carried textures under the scene, with the hash of their bytes.
    const json manifest = json::parse(slurp(dir / "glb" / "manifest.json"));
    ASSERT_EQ(manifest["outputs"].size(), 1u);
    EXPECT_EQ(manifest["outputs"][0]["embedded_images"].size(), textures);
    const RunResult check = run_specbake({"inspect", "--check", (dir / "glb").string()}, dir);
    EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
    fs::remove_all(dir);
}

}  // namespace
