// UASTC KTX2 assembly (io/texture/ktx2_uastc.h): header, level index and level placement read back by hand from
// the KTX 2.0 layout, and the one-level reader's refusals.
#include "io/texture/ktx2_uastc.h"

#include <gtest/gtest.h>
#include <zstd.h>

#include <cstring>

namespace specbake::io {
namespace {

uint32_t u32(const std::vector<uint8_t>& b, size_t at) {
    uint32_t v;
    std::memcpy(&v, b.data() + at, 4);
    return v;
}
uint64_t u64(const std::vector<uint8_t>& b, size_t at) {
    uint64_t v;
    std::memcpy(&v, b.data() + at, 8);
    return v;
}

// A UASTC descriptor as basisu writes it: dfdTotalSize, then a basic block with colorModel 166.
std::vector<uint8_t> uastc_dfd() {
    std::vector<uint8_t> d(44, 0);
    const uint32_t total = 44, block_size = 40u << 16 | 2u;
    std::memcpy(d.data(), &total, 4);
    std::memcpy(d.data() + 8, &block_size, 4);
    d[12] = 166;  // KHR_DF_MODEL_UASTC
    d[14] = 1;    // linear
    return d;
}

UastcLevel level(int w, int h, uint8_t fill) {
    return {w, h, std::vector<uint8_t>(size_t((w + 3) / 4) * size_t((h + 3) / 4) * 16, fill)};
}

TEST(Ktx2Uastc, AssemblesEveryLevelSmallestFirstAligned) {
    const std::vector<UastcLevel> levels = {level(12, 8, 1), level(6, 4, 2), level(3, 2, 3), level(1, 1, 4)};
    const std::vector<uint8_t> dfd = uastc_dfd();
    const std::vector<uint8_t> f = assemble_uastc_ktx2(levels, dfd, "test");
    EXPECT_EQ(f[0], 0xAB);
    EXPECT_EQ(std::memcmp(f.data() + 1, "KTX 20", 6), 0);
    EXPECT_EQ(u32(f, 12), 0u);   // vkFormat undefined
    EXPECT_EQ(u32(f, 16), 1u);   // typeSize
    EXPECT_EQ(u32(f, 20), 12u);  // pixelWidth
    EXPECT_EQ(u32(f, 24), 8u);
    EXPECT_EQ(u32(f, 40), 4u);   // levelCount
    EXPECT_EQ(u32(f, 44), 0u);   // no supercompression
    ASSERT_EQ(u32(f, 52), dfd.size());
    EXPECT_EQ(std::memcmp(f.data() + u32(f, 48), dfd.data(), dfd.size()), 0);
    const std::string kvd(reinterpret_cast<const char*>(f.data()) + u32(f, 56) + 4, 14);
    EXPECT_EQ(kvd, std::string("KTXwriter\0test", 14));
    uint64_t previous = ~0ull;
    for (size_t i = 0; i < levels.size(); ++i) {
        const uint64_t offset = u64(f, 80 + 24 * i), length = u64(f, 88 + 24 * i);
        EXPECT_EQ(length, levels[i].blocks.size()) << i;
        EXPECT_EQ(u64(f, 96 + 24 * i), length) << i;
        EXPECT_EQ(offset % 16, 0u) << i;
        EXPECT_LT(offset, previous) << "level " << i << " must come before the larger ones";
        previous = offset;
        ASSERT_LE(offset + length, f.size());
        for (uint64_t k = 0; k < length; ++k) ASSERT_EQ(f[offset + k], levels[i].blocks[0]) << i;
    }
    EXPECT_EQ(u64(f, 80) + u64(f, 88), f.size());  // level 0 is last
}

// zstd (scheme 2): every level one zstd frame that inflates (by libzstd's own decoder) to exactly the
// level's blocks, uncompressedByteLength the block bytes, the descriptor unchanged, levels packed
// smallest first without padding; the same bytes as a plain file once inflated.
TEST(Ktx2Uastc, ZstdLevelsInflateToTheBlocks) {
    std::vector<UastcLevel> levels = {level(12, 8, 1), level(6, 4, 2), level(3, 2, 3), level(1, 1, 4)};
    for (size_t k = 0; k < levels[0].blocks.size(); ++k) levels[0].blocks[k] = uint8_t(k * 37 % 11);
    const std::vector<uint8_t> dfd = uastc_dfd();
    const std::vector<uint8_t> f = assemble_uastc_ktx2(levels, dfd, "test", 3);
    EXPECT_EQ(u32(f, 44), 2u);  // Zstandard
    ASSERT_EQ(u32(f, 52), dfd.size());
    EXPECT_EQ(std::memcmp(f.data() + u32(f, 48), dfd.data(), dfd.size()), 0);
    uint64_t end = f.size();
    for (size_t i = 0; i < levels.size(); ++i) {
        const uint64_t offset = u64(f, 80 + 24 * i), length = u64(f, 88 + 24 * i);
        EXPECT_EQ(u64(f, 96 + 24 * i), levels[i].blocks.size()) << i;
        EXPECT_EQ(offset + length, end) << "level " << i << " must end where the next larger one starts";
        end = offset;
        std::vector<uint8_t> raw(levels[i].blocks.size() + 1);
        const size_t n = ZSTD_decompress(raw.data(), raw.size(), f.data() + offset, length);
        ASSERT_FALSE(ZSTD_isError(n)) << i;
        raw.resize(n);
        EXPECT_EQ(raw, levels[i].blocks) << i;
    }
    EXPECT_LT(f.size(), assemble_uastc_ktx2(levels, dfd, "test").size());
}

TEST(Ktx2Uastc, ReadsOneLevelFileAndRefusesOthers) {
    const std::vector<uint8_t> one = assemble_uastc_ktx2({level(5, 3, 7)}, uastc_dfd(), "x");
    auto r = read_uastc_ktx2(one, "one.ktx2");
    ASSERT_TRUE(r.ok()) << r.error().message;
    EXPECT_EQ(r->level.width, 5);
    EXPECT_EQ(r->level.height, 3);
    EXPECT_EQ(r->level.blocks.size(), 2u * 1u * 16u);
    EXPECT_EQ(r->dfd, uastc_dfd());

    std::vector<uint8_t> rgba = one;
    rgba[12] = 37;  // vkFormat R8G8B8A8_UNORM
    auto bad = read_uastc_ktx2(rgba, "rgba.ktx2");
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.error().message.find("rgba.ktx2: vkFormat 37"), std::string::npos) << bad.error().message;

    std::vector<uint8_t> model = one;
    model[u32(one, 48) + 12] = 1;  // RGBSDA
    EXPECT_FALSE(read_uastc_ktx2(model, "m.ktx2").ok());
    EXPECT_FALSE(read_uastc_ktx2(std::vector<uint8_t>(one.begin(), one.begin() + 60), "short.ktx2").ok());
}

}  // namespace
}  // namespace specbake::io
