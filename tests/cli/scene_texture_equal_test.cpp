// The scene bake's texture files (KTX2 and DDS, plain and block-compressed: BC, ASTC) are the bytes `specbake texture`
// writes for the same normal and ORM maps: the scene bake streams its rows the way the texture job does.
#include "tests/cli/scene_test_util.h"

#include "io/image/image_io.h"

#include <gtest/gtest.h>

namespace {
using namespace scene_test;

TEST(SceneTextureEqual, SceneTexturesAreTheTextureJobsBytes) {
    const fs::path src = fs::path(SPECBAKE_ASSETS_DIR) / "gltf" / "NormalTangentMirrorTest";
    const fs::path scene = src / "NormalTangentMirrorTest.gltf";
    if (!fs::exists(scene)) GTEST_SKIP() << "shared asset missing: " << scene;
    const fs::path dir = temp_dir("scene_texture_equal");
    // The material: normalTexture and metallicRoughnessTexture on TEXCOORD_0, normal scale and roughness
    // factor 1, so the texture job's G roughness channel reads the same values.
    const std::string normal = (src / "NormalTangentTest_Normal.png").string();
    const std::string orm = (src / "NormalTangentMirrorTest_OcclusionRoughnessMetallic.png").string();
    struct Case {
        std::string name, container;
        std::vector<std::string> extra;
    };
    for (const Case& c : {Case{"ktx2", "ktx2", {}}, Case{"ktx2_bc", "ktx2", {"--block", "bc"}},
                          Case{"dds_bc", "dds", {"--block", "bc"}}, Case{"ktx2_astc", "ktx2", {"--block", "astc"}}}) {
        SCOPED_TRACE(c.name);
        std::vector<std::string> bake{"-q", "bake", scene.string(), "--container", c.container, "-o",
                                      (dir / ("bake_" + c.name)).string()};
        std::vector<std::string> texture{"-q",   "texture", "--normal", normal, "--roughness", orm, "--format",
                                         c.container, "-o", (dir / ("texture_" + c.name)).string()};
        bake.insert(bake.end(), c.extra.begin(), c.extra.end());
        texture.insert(texture.end(), c.extra.begin(), c.extra.end());
        const RunResult b = run_specbake(bake, dir);
        ASSERT_EQ(b.exit_code, 0) << b.err;
        const RunResult t = run_specbake(texture, dir);
        ASSERT_EQ(t.exit_code, 0) << t.err;
        for (const char* kind : {"roughness", "kernel", "normal", "lean", "lean_xy"}) {
            const fs::path from_scene =
                dir / ("bake_" + c.name) / ("NormalTangentMirrorTest_mat0_Material_" + std::string(kind) + "." + c.container);
            const fs::path from_texture = dir / ("texture_" + c.name) / ("texture_" + std::string(kind) + "." + c.container);
            ASSERT_TRUE(fs::exists(from_scene)) << from_scene;
            ASSERT_TRUE(fs::exists(from_texture)) << from_texture;
            EXPECT_TRUE(slurp(from_scene) == slurp(from_texture)) << kind;
        }
    }
}

// Two materials read the same 16-bit normal map (held as integers): the first with the ORM map, the second,
// the normal map's last reader, with a constant roughness; only the last reader's bake may return the map's
// rows to the system as it passes them. Each bake reads the whole map: the files are the texture job's bytes.
TEST(SceneTextureEqual, MapsSharedByMaterialsAreReadWholeByEachBake) {
    const fs::path dir = temp_dir("scene_texture_shared_maps");
    constexpr int kSize = 256;  // levels that tile: the bake reports the input rows it has passed
    specbake::Image normal(kSize, kSize, 3), orm(kSize, kSize, 3);
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            const double sx = 0.5 * std::sin(0.11 * x + 0.05 * y), sy = 0.4 * std::cos(0.07 * y - 0.13 * x);
            const double len = std::sqrt(sx * sx + sy * sy + 1.0);
            const float n[3] = {float(-sx / len), float(-sy / len), float(1.0 / len)};
            for (int c = 0; c < 3; ++c) normal.texel(x, y)[c] = 0.5f * n[c] + 0.5f;
            const float o[3] = {0.8f, 0.25f + 0.5f * float((x * 7 + y * 3) % 97) / 97.0f, 0.1f};
            for (int c = 0; c < 3; ++c) orm.texel(x, y)[c] = o[c];
        }
    ASSERT_TRUE(specbake::io::write_image(dir / "n.png", normal, 16).ok());
    ASSERT_TRUE(specbake::io::write_image(dir / "orm.png", orm, 16).ok());
    // One quad per material: POSITION, NORMAL, TANGENT, TEXCOORD_0 and six indices.
    std::string bin;
    auto put = [&](std::initializer_list<float> v) {
        for (float f : v) bin.append(reinterpret_cast<const char*>(&f), 4);
    };
    put({-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0});
    put({0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1});
    put({1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1});
    put({0, 1, 1, 1, 1, 0, 0, 0});
    for (uint16_t i : {0, 1, 2, 0, 2, 3}) bin.append(reinterpret_cast<const char*>(&i), 2);
    write_bytes(dir / "cards.bin", bin);
    const std::string first = "{\"name\": \"first\", \"normalTexture\": {\"index\": 0}, \"pbrMetallicRoughness\": "
                              "{\"metallicRoughnessTexture\": {\"index\": 1}}}";
    const std::string second = "{\"name\": \"second\", \"normalTexture\": {\"index\": 0}, \"pbrMetallicRoughness\": "
                               "{\"roughnessFactor\": 0.6}}";
    const std::string primitive =
        "\"attributes\": {\"POSITION\": 0, \"NORMAL\": 1, \"TANGENT\": 2, \"TEXCOORD_0\": 3}, \"indices\": 4";
    write_bytes(dir / "cards.gltf",
                "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": [0]}], "
                "\"nodes\": [{\"mesh\": 0}], \"meshes\": [{\"primitives\": [{" + primitive + ", \"material\": 0}, {" +
                primitive + ", \"material\": 1}]}], \"materials\": [" + first + ", " + second + "], \"textures\": [{\"source\": 0}, {\"source\": 1}], "
                "\"images\": [{\"uri\": \"n.png\"}, {\"uri\": \"orm.png\"}], "
                "\"buffers\": [{\"uri\": \"cards.bin\", \"byteLength\": " + std::to_string(bin.size()) + "}], "
                "\"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 48}, "
                "{\"buffer\": 0, \"byteOffset\": 48, \"byteLength\": 48}, {\"buffer\": 0, \"byteOffset\": 96, "
                "\"byteLength\": 64}, {\"buffer\": 0, \"byteOffset\": 160, \"byteLength\": 32}, "
                "{\"buffer\": 0, \"byteOffset\": 192, \"byteLength\": 12}], "
                "\"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC3\", "
                "\"min\": [-1, -1, 0], \"max\": [1, 1, 0]}, {\"bufferView\": 1, \"componentType\": 5126, "
                "\"count\": 4, \"type\": \"VEC3\"}, {\"bufferView\": 2, \"componentType\": 5126, \"count\": 4, "
                "\"type\": \"VEC4\"}, {\"bufferView\": 3, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC2\"}, "
                "{\"bufferView\": 4, \"componentType\": 5123, \"count\": 6, \"type\": \"SCALAR\"}]}");
    for (const std::string container : {"ktx2", "dds"}) {
        SCOPED_TRACE(container);
        const RunResult b = run_specbake({"-q", "bake", (dir / "cards.gltf").string(), "--container", container, "-o",
                                          (dir / ("bake_" + container)).string()}, dir);
        ASSERT_EQ(b.exit_code, 0) << b.err;
        const RunResult t = run_specbake({"-q", "texture", "--normal", (dir / "n.png").string(), "--roughness",
                                          (dir / "orm.png").string(), "--reconstruct-z", "gltf", "--format", container,
                                          "-o", (dir / ("texture_" + container)).string()}, dir);
        ASSERT_EQ(t.exit_code, 0) << t.err;
        const RunResult c = run_specbake({"-q", "texture", "--normal", (dir / "n.png").string(), "--roughness-value",
                                          "0.6", "--reconstruct-z", "gltf", "--format", container, "-o",
                                          (dir / ("constant_" + container)).string()}, dir);
        ASSERT_EQ(c.exit_code, 0) << c.err;
        // The second material's roughness; the normal-map outputs are the first's, shared by both.
        const std::vector<std::pair<std::string, std::string>> pairs = {
            {"cards_mat0_first_roughness", "texture_/texture_roughness"}, {"cards_mat0_first_kernel", "texture_/texture_kernel"},
            {"cards_mat0_first_normal", "texture_/texture_normal"}, {"cards_mat0_first_lean", "texture_/texture_lean"},
            {"cards_mat1_second_roughness", "constant_/texture_roughness"}};
        for (const auto& [scene_stem, texture_file] : pairs) {
            const fs::path from_scene = dir / ("bake_" + container) / (scene_stem + "." + container);
            const std::string folder = texture_file.substr(0, texture_file.find('/'));
            const fs::path from_texture =
                dir / (folder + container) / (texture_file.substr(texture_file.find('/') + 1) + "." + container);
            ASSERT_TRUE(fs::exists(from_scene)) << from_scene;
            ASSERT_TRUE(fs::exists(from_texture)) << from_texture;
            EXPECT_TRUE(slurp(from_scene) == slurp(from_texture)) << scene_stem;
        }
    }
}

}  // namespace
