// `specbake texture --block astc`: ASTC LDR levels in KTX2 (plain and zstd), checked against what the
// specification fixes independently of the encoder: the file structure (KTX 2.0 Sec. 3, KDFS 1.3 Sec. 5.6
// colour model ASTC = 162, the footprint in texelBlockDimension), level sizes (16 bytes a block, edges
// padded, the demo's 4x3, 2x1 and 1x1 levels included), and the bit layout of the void-extent block
// (constant-colour block, KDFS 1.3 Sec. 23.12) an encoder must write for a constant block; every level
// decodes close to the uncompressed bake of the same input. The GPU decode of the same files is checked
// in tests/consumers/three_js_test.cpp (three.js KTX2Loader in Chromium).
#include "tests/cli/scene_test_util.h"

#include "io/texture/astc_codec.h"
#include "io/texture/container_inspect.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <zstd.h>

#include <cmath>
#include <random>
#include <unistd.h>

namespace {
using namespace scene_test;
using namespace specbake;

// Level L of a KTX2 file, zstd inflated to `raw` bytes when the file is supercompressed.
std::string ktx2_level(const std::string& b, uint32_t L, size_t raw) {
    const uint64_t off = le64(b, 80 + 24 * L), len = le64(b, 80 + 24 * L + 8);
    std::string level = b.substr(off, len);
    if (le32(b, 44) != 2) return level;
    std::string out(raw, '\0');
    const size_t n = ZSTD_decompress(out.data(), out.size(), level.data(), level.size());
    EXPECT_FALSE(ZSTD_isError(n));
    out.resize(ZSTD_isError(n) ? 0 : n);
    return out;
}

size_t blocks_bytes(int side, int w, int h) { return size_t((w + side - 1) / side) * size_t((h + side - 1) / side) * 16; }

// The codec on its own.
TEST(AstcCodec, ConstantBlocksAreVoidExtentBlocksOfTheSpecification) {
    // A constant 8x8 image of one value per channel: every 4x4 block is the void-extent block of KDFS 1.3
    // Sec. 23.12: bits 0-8 = 0x1FC, bit 9 = 0 (LDR), bits 10-11 reserved 1, the four 13-bit extent
    // coordinates all ones ("no extent"), then R, G, B, A as UNORM16 (v * 257 for the 8-bit value v).
    const uint8_t rgba[4] = {10, 200, 77, 255};
    std::vector<uint8_t> img(8 * 8 * 4);
    for (size_t i = 0; i < img.size(); ++i) img[i] = rgba[i % 4];
    auto blocks = io::astc_compress_level(img.data(), 8, 8, 4, 4, 4);
    ASSERT_TRUE(blocks.ok()) << blocks.error().message;
    ASSERT_EQ(blocks->size(), 4u * 16u);
    for (size_t b = 0; b < 4; ++b) {
        const uint8_t* p = blocks->data() + 16 * b;
        uint64_t lo = 0;
        for (int i = 7; i >= 0; --i) lo = lo << 8 | p[i];
        EXPECT_EQ(lo & 0x1FF, 0x1FCu) << "block " << b;
        EXPECT_EQ((lo >> 9) & 1, 0u) << "LDR";
        EXPECT_EQ((lo >> 12), (uint64_t(1) << 52) - 1) << "extent coordinates";
        for (int c = 0; c < 4; ++c)
            EXPECT_EQ(uint32_t(p[8 + 2 * c] | p[9 + 2 * c] << 8), uint32_t(rgba[c]) * 257u) << "channel " << c;
    }
    // Decoded: the value again.
    auto back = io::astc_decompress_level(*blocks, 8, 8, 4);
    ASSERT_TRUE(back.ok());
    for (size_t i = 0; i < back->size(); ++i) EXPECT_EQ((*back)[i], rgba[i % 4]);
}

TEST(AstcCodec, ChannelMappingSizesAndThreadCountIndependence) {
    // A smooth two-channel field with noise, 37x23 (not multiples of any footprint).
    const int w = 37, h = 23;
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> noise(-3, 3);
    std::vector<uint8_t> two(size_t(w) * h * 2);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            two[(size_t(y) * w + x) * 2] = uint8_t(std::clamp(40 + 4 * x + noise(rng), 0, 255));
            two[(size_t(y) * w + x) * 2 + 1] = uint8_t(std::clamp(220 - 7 * y + noise(rng), 0, 255));
        }
    for (int side : {4, 6, 8}) {
        SCOPED_TRACE("side " + std::to_string(side));
        auto one_thread = io::astc_compress_level(two.data(), w, h, 2, 2, side, 1);
        auto two_threads = io::astc_compress_level(two.data(), w, h, 2, 2, side, 2);
        ASSERT_TRUE(one_thread.ok() && two_threads.ok());
        EXPECT_EQ(one_thread->size(), blocks_bytes(side, w, h));
        EXPECT_EQ(io::astc_level_bytes(side, w, h), blocks_bytes(side, w, h));
        EXPECT_EQ(*one_thread, *two_threads) << "the bytes depend on the thread count";
        auto rgba = io::astc_decompress_level(*one_thread, w, h, side);
        ASSERT_TRUE(rgba.ok());
        double sum = 0;
        for (size_t i = 0; i < size_t(w) * h; ++i) {
            // Two channels decode as (x, y, 0, 1), as an R8G8 texture samples.
            EXPECT_EQ((*rgba)[4 * i + 2], 0) << "texel " << i;
            EXPECT_EQ((*rgba)[4 * i + 3], 255) << "texel " << i;
            for (int c = 0; c < 2; ++c) {
                const double d = (*rgba)[4 * i + size_t(c)] - two[2 * i + size_t(c)];
                sum += d * d;
            }
        }
        // Gradients of 4-7 steps a texel with +-3 noise: measured RMS 1.4 (4x4), 2.1 (6x6), 2.6 (8x8) steps.
        EXPECT_LT(std::sqrt(sum / (2.0 * w * h)), side == 4 ? 2.5 : 4.0);
    }
    // One channel decodes as luminance (r, r, r, 1).
    std::vector<uint8_t> one(size_t(w) * h);
    for (size_t i = 0; i < one.size(); ++i) one[i] = uint8_t(i * 7 % 251);
    auto blocks = io::astc_compress_level(one.data(), w, h, 1, 1, 4);
    ASSERT_TRUE(blocks.ok());
    auto rgba = io::astc_decompress_level(*blocks, w, h, 4);
    ASSERT_TRUE(rgba.ok());
    for (size_t i = 0; i < one.size(); ++i) {
        EXPECT_EQ((*rgba)[4 * i], (*rgba)[4 * i + 1]);
        EXPECT_EQ((*rgba)[4 * i], (*rgba)[4 * i + 2]);
        EXPECT_EQ((*rgba)[4 * i + 3], 255);
    }
    // Bad arguments are errors, not crashes.
    EXPECT_FALSE(io::astc_compress_level(one.data(), w, h, 1, 1, 5).ok());
    EXPECT_FALSE(io::astc_compress_level(one.data(), w, h, 1, 3, 4).ok());
    EXPECT_FALSE(io::astc_compress_level(one.data(), 0, h, 1, 1, 4).ok());
    EXPECT_FALSE(io::astc_decompress_level({blocks->data(), blocks->size() - 1}, w, h, 4).ok());
}

class AstcTexture : public ::testing::Test {
protected:
    void SetUp() override { dir_ = temp_dir("astc"); }
    void TearDown() override { fs::remove_all(dir_); }
    void bake(const std::string& name, std::vector<std::string> extra) {
        std::vector<std::string> args{"-q", "texture", "--demo", "-o", (dir_ / name).string()};
        args.insert(args.end(), extra.begin(), extra.end());
        const RunResult r = run_specbake(args, dir_);
        ASSERT_EQ(r.exit_code, 0) << r.err;
    }
    fs::path dir_;
};

// Every 8-bit output of the demo (ORM roughness RGBA8, mean normal) as ASTC 4x4 / 6x6 / 8x8, plain and
// zstd: the KTX2 structure, the level sizes, the manifest, and every level close to the uncompressed bake.
TEST_F(AstcTexture, EveryLevelOfTheDemoIsAstcAndCloseToTheUncompressedBake) {
    bake("ref", {"--supercompression", "none"});
    const auto ref_rough = io::read_texture_for_inspection(dir_ / "ref" / "texture_roughness.ktx2");
    const auto ref_normal = io::read_texture_for_inspection(dir_ / "ref" / "texture_normal.ktx2");
    ASSERT_TRUE(ref_rough.ok() && ref_normal.ok());
    for (const char* block : {"4x4", "6x6", "8x8"}) {
        const int side = block[0] - '0';
        for (const char* sc : {"none", "zstd"}) {
            const std::string name = std::string("astc") + block + sc;
            SCOPED_TRACE(name);
            bake(name, {"--block", "astc", "--astc-block", block, "--supercompression", sc});
            for (const char* file : {"texture_roughness.ktx2", "texture_normal.ktx2"}) {
                SCOPED_TRACE(file);
                const std::string f = slurp(dir_ / name / file);
                EXPECT_EQ(le32(f, 12), io::astc_vk_format(side));  // VK_FORMAT_ASTC_NxN_UNORM_BLOCK
                EXPECT_EQ(le32(f, 16), 1u);                         // typeSize of block formats
                EXPECT_EQ(le32(f, 44), std::string(sc) == "zstd" ? 2u : 0u);
                const uint32_t dfd = le32(f, 48);
                EXPECT_EQ(uint8_t(f[dfd + 12]), 162);  // KHR_DF_MODEL_ASTC
                EXPECT_EQ(uint8_t(f[dfd + 14]), 1);    // linear transfer
                EXPECT_EQ(le32(f, dfd + 16), uint32_t((side - 1) | (side - 1) << 8));
                EXPECT_EQ(uint8_t(f[dfd + 20]), 16);   // bytesPlane0
                const uint32_t w = le32(f, 20), h = le32(f, 24), levels = le32(f, 40);
                EXPECT_EQ(levels, 10u);  // 512x384: the full chain
                for (uint32_t L = 0; L < levels; ++L) {
                    const int lw = int(std::max(1u, w >> L)), lh = int(std::max(1u, h >> L));
                    EXPECT_EQ(le64(f, 80 + 24 * L + 16), blocks_bytes(side, lw, lh)) << "level " << L;
                    EXPECT_EQ(ktx2_level(f, L, blocks_bytes(side, lw, lh)).size(), blocks_bytes(side, lw, lh));
                }
            }
            // Decoded (inspect's reader) against the uncompressed bake, level by level.
            const auto rough = io::read_texture_for_inspection(dir_ / name / "texture_roughness.ktx2");
            const auto normal = io::read_texture_for_inspection(dir_ / name / "texture_normal.ktx2");
            ASSERT_TRUE(rough.ok()) << rough.error().message;
            ASSERT_TRUE(normal.ok()) << normal.error().message;
            EXPECT_EQ(rough->pixel_format, "ASTC_" + std::string(block) + "_UNORM_BLOCK");
            ASSERT_EQ(rough->mips.levels.size(), ref_rough->mips.levels.size());
            for (size_t L = 0; L < rough->mips.levels.size(); ++L) {
                const Image& a = rough->mips.levels[L];
                const Image& r = ref_rough->mips.levels[L];
                const Image& na = normal->mips.levels[L];
                const Image& nr = ref_normal->mips.levels[L];
                ASSERT_EQ(a.texel_count(), r.texel_count());
                double sum = 0, angle_sum = 0;
                for (size_t i = 0; i < a.texel_count(); ++i) {
                    const double d = a.pixels[4 * i + 1] - r.pixels[4 * i + 1];  // G = r
                    sum += d * d;
                    EXPECT_EQ(a.pixels[4 * i + 3], 1.0f);
                    // Normal: x, y kept, (B, A) = (0, 1); z rebuilt as the include does.
                    EXPECT_EQ(na.pixels[4 * i + 2], 0.0f);
                    double u[3], v[3];
                    for (int c = 0; c < 3; ++c) u[c] = nr.pixels[4 * i + size_t(c)] * 2.0 - 1.0;
                    v[0] = na.pixels[4 * i] * 2.0 - 1.0, v[1] = na.pixels[4 * i + 1] * 2.0 - 1.0;
                    v[2] = std::sqrt(std::max(0.0, 1.0 - v[0] * v[0] - v[1] * v[1]));
                    const double lu = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
                    const double lv = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
                    angle_sum += std::acos(std::clamp((u[0] * v[0] + u[1] * v[1] + u[2] * v[2]) / (lu * lv), -1.0, 1.0));
                }
                const double rms = std::sqrt(sum / double(a.texel_count()));
                const double mean_deg = angle_sum / double(a.texel_count()) * 180.0 / M_PI;
                // The demo's metallic stripes switch inside blocks, and its bumps are a few texels wide; bounds
                // above what was measured (4x4: mean angle 0.72, 1.71, 1.62 deg on levels 0-2; 8x8 up to 4.1),
                // looser for the larger footprints; the smallest levels hold a block or less.
                EXPECT_LT(rms, side == 4 ? 0.04 : 0.08) << "level " << L;
                if (L < 6) EXPECT_LT(mean_deg, side == 4 ? 2.5 : 6.0) << "level " << L;
            }
            // The manifest says what the blocks hold.
            const nlohmann::json m = nlohmann::json::parse(slurp(dir_ / name / "manifest.json"));
            for (const nlohmann::json& o : m["outputs"]) {
                if (o["kind"] == "normal") {
                    EXPECT_EQ(o["gpu_format"], "ASTC_" + std::string(block) + "_UNORM_BLOCK");
                    EXPECT_EQ(o["channel_meaning"], (std::vector<std::string>{"n.x", "n.y"}));
                    EXPECT_EQ(o["astc_decoded_as"], "x, y, 0, 1");
                    EXPECT_EQ(o["block_compression"], "astc");
                }
                if (o["kind"] == "kernel") EXPECT_EQ(o["gpu_format"], "R16G16B16A16_SFLOAT");  // float Sigma stays float
            }
            EXPECT_EQ(m["settings"]["supercompression"]["block"]["normal"], std::string("astc") + block);
        }
    }
}

// A one-channel roughness (normal map alone) is luminance ASTC; --check of the folder passes.
TEST_F(AstcTexture, OneChannelRoughnessAndInspectCheck) {
    bake("ref", {"--supercompression", "none"});
    const std::string normal = (dir_ / "ref" / "demo_normal.png").string();
    const RunResult r = run_specbake({"-q", "texture", "--normal", normal, "--block", "astc", "-o", (dir_ / "one").string()}, dir_);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto t = io::read_texture_for_inspection(dir_ / "one" / "texture_roughness.ktx2");
    ASSERT_TRUE(t.ok()) << t.error().message;
    for (const Image& level : t->mips.levels)
        for (size_t i = 0; i < level.texel_count(); ++i) {
            ASSERT_EQ(level.pixels[4 * i], level.pixels[4 * i + 1]);
            ASSERT_EQ(level.pixels[4 * i + 3], 1.0f);
        }
    const nlohmann::json m = nlohmann::json::parse(slurp(dir_ / "one" / "manifest.json"));
    for (const nlohmann::json& o : m["outputs"])
        if (o["kind"] == "roughness") {
            EXPECT_EQ(o["channels"], 1);
            EXPECT_EQ(o["astc_decoded_as"], "r, r, r, 1");
        }
    const RunResult check = run_specbake({"inspect", "--check", (dir_ / "one").string()}, dir_);
    EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
}

// ASTC has no DDS form: a usage error naming both options, nothing written; EXR and PNG likewise.
TEST(AstcUsage, DdsExrAndPngContainersRefuseAstc) {
    const fs::path dir = fs::temp_directory_path() / ("specbake_astc_usage_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    for (const char* format : {"dds", "exr", "png"}) {
        SCOPED_TRACE(format);
        const fs::path out = dir / format;
        const RunResult t = run_specbake({"texture", "--demo", "--block", "astc", "--format", format, "-o", out.string()}, dir);
        EXPECT_EQ(t.exit_code, 2) << t.err;
        EXPECT_NE(t.err.find(std::string("--block astc with --format ") + format), std::string::npos) << t.err;
        EXPECT_FALSE(fs::exists(out / "manifest.json"));
    }
    const RunResult d = run_specbake({"texture", "--demo", "--block", "astc", "--format", "dds", "-o", (dir / "d").string()}, dir);
    EXPECT_NE(d.err.find("DDS has no standard ASTC format"), std::string::npos) << d.err;
    fs::remove_all(dir);
}

}  // namespace
