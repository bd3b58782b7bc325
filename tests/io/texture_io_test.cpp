// Image decoding and texture containers: round trips through independent readers (OpenImageIO for
// EXR/PNG, a DDS parse written here from the DDS/DX10 layout, byte-level KTX2 structure checks).
#include "io/files/sha256.h"
#include "io/image/image_io.h"
#include "io/texture/block_compress.h"
#include "io/texture/dds.h"
#include "io/texture/ktx2.h"
#include "io/texture/png_stream.h"
#include "io/texture/texel_encoding.h"
#include "io/texture/texture_writer.h"
#include "tests/io/temp_folder.h"

#include <Imath/half.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <zstd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <thread>

namespace specbake::io {
namespace {
namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
    return specbake::testing::fresh_test_folder("texture_io", name);
}

std::vector<uint8_t> slurp(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(f), {}};
}

uint32_t u32(const std::vector<uint8_t>& b, size_t at) {
    return uint32_t(b[at]) | uint32_t(b[at + 1]) << 8 | uint32_t(b[at + 2]) << 16 | uint32_t(b[at + 3]) << 24;
}
uint64_t u64(const std::vector<uint8_t>& b, size_t at) { return uint64_t(u32(b, at)) | uint64_t(u32(b, at + 4)) << 32; }

MipChain random_chain(int W, int H, int channels, unsigned seed, float lo = 0.0f, float hi = 1.0f) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(lo, hi);
    MipChain c;
    for (int L = 0;; ++L) {
        Image im(std::max(1, W >> L), std::max(1, H >> L), channels);
        for (float& v : im.pixels) v = u(rng);
        c.levels.push_back(std::move(im));
        if ((W >> L) <= 1 && (H >> L) <= 1) break;
    }
    return c;
}

// Puts every level of `chain` into `t` in bands of 1 to `max_rows` rows (drawn from `rng`), each band
// reported with compress_rows as the bake reports finished rows; `after_band(level, rows_done, band)` runs
// after each report. False (with the failing level and row) when compress_rows fails.
::testing::AssertionResult put_in_bands(EncodedTexture& t, const MipChain& chain, std::mt19937& rng, int max_rows,
                                        const std::function<void(int, int, int)>& after_band = {}) {
    for (int L = 0; L < int(chain.levels.size()); ++L) {
        const Image& level = chain.levels[size_t(L)];
        for (int y = 0; y < level.height;) {
            const int rows = std::min(level.height - y, 1 + int(rng() % unsigned(max_rows)));
            t.put_block(L, 0, y, level.width, rows,
                        level.pixels.data() + size_t(y) * size_t(level.width) * size_t(level.channels), level.channels, 0);
            y += rows;
            if (auto ok = t.compress_rows(L, y); !ok)
                return ::testing::AssertionFailure() << "compress_rows(" << L << ", " << y << "): " << ok.error().message;
            if (after_band) after_band(L, y, rows);
        }
    }
    return ::testing::AssertionSuccess();
}

double tolerance(TexelEncoding e) {
    switch (e) {
        case TexelEncoding::Unorm8: return 0.5 / 255 + 1e-6;
        case TexelEncoding::Unorm16: return 0.5 / 65535 + 1e-7;
        case TexelEncoding::Float16: return 1e-3;
        case TexelEncoding::Float32: return 0.0;
    }
    return 0.0;
}

void expect_chain_near(const MipChain& got, const MipChain& want, int channels, double tol) {
    ASSERT_EQ(got.levels.size(), want.levels.size());
    for (size_t L = 0; L < want.levels.size(); ++L) {
        const Image& g = got.levels[L];
        const Image& w = want.levels[L];
        ASSERT_EQ(g.width, w.width);
        ASSERT_EQ(g.height, w.height);
        for (size_t i = 0; i < w.texel_count(); ++i)
            for (int c = 0; c < channels; ++c)
                ASSERT_NEAR(g.pixels[i * g.channels + c], w.pixels[i * w.channels + c], tol) << "level " << L;
    }
}

// Expected vkFormat from the Vulkan enum, written out here as a table of names to values.
uint32_t expected_vk(TexelEncoding e, int c) {
    if (e == TexelEncoding::Unorm8) return c == 1 ? 9 : c == 2 ? 16 : c == 3 ? 23 : 37;     // VK_FORMAT_R8*_UNORM
    if (e == TexelEncoding::Unorm16) return c == 1 ? 70 : c == 2 ? 77 : c == 3 ? 84 : 91;   // R16*_UNORM
    if (e == TexelEncoding::Float16) return c == 1 ? 76 : c == 2 ? 83 : c == 3 ? 90 : 97;   // R16*_SFLOAT
    return c == 1 ? 100 : c == 2 ? 103 : c == 3 ? 106 : 109;                                // R32*_SFLOAT
}

TEST(Ktx2, RoundTripAndStructureEveryFormat) {
    const fs::path dir = fresh_dir("ktx2");
    for (TexelEncoding e : {TexelEncoding::Unorm8, TexelEncoding::Unorm16, TexelEncoding::Float16, TexelEncoding::Float32}) {
        for (int channels = 1; channels <= 4; ++channels) {
            SCOPED_TRACE(std::string(encoding_name(e)) + " x" + std::to_string(channels));
            const MipChain chain = random_chain(13, 6, channels, unsigned(channels) * 7 + unsigned(e));
            const TextureFileFormat plain(TextureContainer::Ktx2, Supercompression{false, 3});
            auto written = write_texture(chain, e, plain, dir, "t", "kernel");
            ASSERT_TRUE(written.ok()) << written.error().message;
            ASSERT_EQ(written->size(), 1u);
            const std::vector<uint8_t> b = slurp(dir / "t.ktx2");
            // Header (KTX 2.0 Sec. 3).
            const uint8_t id[12] = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n'};
            ASSERT_EQ(std::memcmp(b.data(), id, 12), 0);
            const int bytes = e == TexelEncoding::Unorm8 ? 1 : e == TexelEncoding::Float32 ? 4 : 2;
            // Formats GPUs sample: three channels are stored as RGBA with A = 1.
            const int stored = channels == 3 ? 4 : channels;
            EXPECT_EQ(u32(b, 12), expected_vk(e, stored));
            EXPECT_EQ(u32(b, 16), uint32_t(bytes));  // typeSize
            EXPECT_EQ(u32(b, 20), 13u);
            EXPECT_EQ(u32(b, 24), 6u);
            EXPECT_EQ(u32(b, 28), 0u);
            EXPECT_EQ(u32(b, 32), 0u);
            EXPECT_EQ(u32(b, 36), 1u);
            EXPECT_EQ(u32(b, 40), 4u);  // 13x6 -> 6x3 -> 3x1 -> 1x1
            EXPECT_EQ(u32(b, 44), 0u);
            // Level index: sizes, alignment to lcm(texel size, 4), smallest level stored first, no overlap.
            const size_t texel = size_t(bytes) * stored;
            const size_t align = std::lcm(texel, size_t(4));
            uint64_t previous_offset = 0;
            for (int L = 3; L >= 0; --L) {
                const size_t at = 80 + 24 * size_t(L);
                const uint64_t off = u64(b, at), len = u64(b, at + 8);
                const int w = std::max(1, 13 >> L), h = std::max(1, 6 >> L);
                EXPECT_EQ(len, uint64_t(w) * h * texel);
                EXPECT_EQ(u64(b, at + 16), len);
                EXPECT_EQ(off % align, 0u);
                EXPECT_GE(off, previous_offset);
                previous_offset = off + len;
                EXPECT_LE(off + len, b.size());
            }
            EXPECT_EQ(previous_offset, b.size());
            // DFD: basic block, RGBSDA, linear transfer, one sample per channel.
            const uint32_t dfd = u32(b, 48), dfd_len = u32(b, 52);
            EXPECT_EQ(u32(b, dfd), dfd_len);
            EXPECT_EQ(dfd_len, 4u + 24u + 16u * uint32_t(stored));
            EXPECT_EQ(u32(b, dfd + 4), 0u);
            EXPECT_EQ(u32(b, dfd + 8) >> 16, 24u + 16u * uint32_t(stored));
            EXPECT_EQ(b[dfd + 12], 1u);      // KHR_DF_MODEL_RGBSDA
            EXPECT_EQ(b[dfd + 12 + 2], 1u);  // KHR_DF_TRANSFER_LINEAR
            EXPECT_EQ(b[dfd + 20], texel);   // bytesPlane0
            for (int c = 0; c < stored; ++c) {
                const size_t s = dfd + 28 + 16 * size_t(c);
                EXPECT_EQ(u32(b, s) & 0xFFFF, uint32_t(c * bytes * 8));      // bitOffset
                EXPECT_EQ(b[s + 2], uint32_t(bytes * 8 - 1));                  // bitLength - 1
                EXPECT_EQ(b[s + 3] & 0x0F, c == 3 ? 15u : uint32_t(c));        // channel id (alpha = 15)
                const bool is_float = e == TexelEncoding::Float16 || e == TexelEncoding::Float32;
                EXPECT_EQ(b[s + 3] & 0xF0, is_float ? 0xC0u : 0u);             // FLOAT | SIGNED
            }
            // Values through the reader.
            auto back = read_ktx2_texture(b, "t.ktx2");
            ASSERT_TRUE(back.ok()) << back.error().message;
            EXPECT_EQ(back->info.writer, "specbake");
            EXPECT_EQ(back->info.transfer, 1u);
            expect_chain_near(back->chain, chain, channels, tolerance(e));
            ASSERT_EQ(back->chain.channels(), stored);
            if (stored != channels)
                for (const Image& level : back->chain.levels)
                    for (size_t i = 0; i < level.texel_count(); ++i) ASSERT_EQ(level.pixels[i * 4 + 3], 1.0f);
            EXPECT_EQ((*written)[0].extra["vkFormat"], expected_vk(e, stored));
            EXPECT_EQ((*written)[0].channels, stored);
        }
    }
    fs::remove_all(dir);
}

TEST(Ktx2, ReaderRejectsDamage) {
    const MipChain chain = random_chain(8, 8, 1, 3);
    std::vector<uint8_t> b = encode_ktx2(chain, TexelEncoding::Unorm8);
    EXPECT_TRUE(read_ktx2_texture(b, "x").ok());
    std::vector<uint8_t> truncated(b.begin(), b.begin() + long(b.size() - 10));
    auto r = read_ktx2_texture(truncated, "x.ktx2");
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("x.ktx2"), std::string::npos);
    std::vector<uint8_t> bad_format = b;
    bad_format[12] = 200;
    EXPECT_FALSE(read_ktx2_texture(bad_format, "x").ok());
}

// DDS parsed here from the documented layout: "DDS ", DDS_HEADER (124 bytes), DDS_HEADER_DXT10.
struct ParsedDds {
    uint32_t width, height, mips, dxgi, dimension, array_size, flags, caps, fourcc;
    uint32_t pf_flags, bit_count, masks[4];
    size_t data_offset;
};
ParsedDds parse_dds(const std::vector<uint8_t>& b) {
    ParsedDds p{};
    EXPECT_EQ(u32(b, 0), 0x20534444u);
    EXPECT_EQ(u32(b, 4), 124u);
    p.flags = u32(b, 8);
    p.height = u32(b, 12);
    p.width = u32(b, 16);
    p.mips = u32(b, 28);
    EXPECT_EQ(u32(b, 76), 32u);
    p.pf_flags = u32(b, 80);
    p.fourcc = u32(b, 84);
    p.bit_count = u32(b, 88);
    for (int k = 0; k < 4; ++k) p.masks[k] = u32(b, 92 + 4 * size_t(k));
    p.caps = u32(b, 108);
    p.data_offset = 128;
    if (p.fourcc == 0x30315844u) {  // "DX10"
        p.dxgi = u32(b, 128);
        p.dimension = u32(b, 132);
        p.array_size = u32(b, 140);
        p.data_offset = 148;
    }
    return p;
}

// Float16 encoding (hardware conversion where the CPU has it) rounds exactly as Imath's portable
// conversion: ties to even, subnormals, the largest half and overflow to infinity.
TEST(TexelEncoding, HalfMatchesImathBitForBit) {
    std::vector<float> values{0.0f, -0.0f, 1.0f, -2.5f, 65504.0f, 65519.0f, 65520.0f, 1e6f, 5.96e-8f, 2.98e-8f,
                              1e-10f, 6.1e-5f, 1.0f + 1.0f / 2048.0f, 1.0f + 3.0f / 2048.0f, 0.1f, 1.0f / 3.0f};
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-4.0f, 4.0f);
    std::uniform_int_distribution<int> e(-30, 16);
    while (values.size() < 4099) values.push_back(std::ldexp(u(rng), e(rng)));
    Image im(int(values.size()), 1, 1);
    im.pixels = values;
    const std::vector<uint8_t> h = encode_texels(im, TexelEncoding::Float16, 1);
    for (size_t i = 0; i < values.size(); ++i)
        ASSERT_EQ(uint16_t(h[2 * i] | h[2 * i + 1] << 8), Imath::half(values[i]).bits()) << values[i];
}

// Unorm rounding is round-half-away-from-zero of clamp(v, 0, 1) * (2^bits - 1), as std::lround computes
// it, including values right at and next to the halfway points.
TEST(TexelEncoding, UnormRoundingMatchesLround) {
    Image im(64, 1, 1);
    std::vector<float> values{-1.0f, 0.0f, 1.0f, 2.0f, 0.5f / 255.0f, 0.49999997f / 255.0f, 127.5f / 255.0f,
                              254.5f / 255.0f, 0.5f / 65535.0f, 32767.5f / 65535.0f};
    for (float v : std::vector<float>(values)) {
        values.push_back(std::nextafter(v, 2.0f));
        values.push_back(std::nextafter(v, -2.0f));
    }
    values.resize(64, 0.25f);
    im.pixels = values;
    const std::vector<uint8_t> u8 = encode_texels(im, TexelEncoding::Unorm8, 1);
    const std::vector<uint8_t> u16 = encode_texels(im, TexelEncoding::Unorm16, 1);
    for (size_t i = 0; i < values.size(); ++i) {
        const float c = std::clamp(values[i], 0.0f, 1.0f);
        EXPECT_EQ(u8[i], uint8_t(std::lround(c * 255.0f))) << values[i];
        EXPECT_EQ(uint32_t(u16[2 * i] | u16[2 * i + 1] << 8), uint32_t(std::lround(c * 65535.0f))) << values[i];
    }
}

// zstd supercompression (KTX 2.0 Sec. 3.9.2, scheme 2): every level inflates, by the zstd library
// directly, to exactly the bytes of the uncompressed file's level; the index holds byteLength and
// uncompressedByteLength; levels follow each other smallest first without padding; the header, DFD and
// key/value data are those of the uncompressed file apart from the scheme.
TEST(Ktx2, ZstdLevelsInflateToTheUncompressedFile) {
    const fs::path dir = fresh_dir("ktx2_zstd");
    for (TexelEncoding e : {TexelEncoding::Unorm8, TexelEncoding::Unorm16, TexelEncoding::Float16}) {
        for (int channels = 1; channels <= 4; ++channels) {
            SCOPED_TRACE(std::string(encoding_name(e)) + " x" + std::to_string(channels));
            const MipChain chain = random_chain(37, 21, channels, unsigned(channels) * 3 + unsigned(e));
            const std::vector<uint8_t> plain = encode_ktx2(chain, e);
            const TextureFileFormat zstd(TextureContainer::Ktx2, Supercompression{true, 5});
            auto written = write_texture(chain, e, zstd, dir, "z", "kernel");
            ASSERT_TRUE(written.ok()) << written.error().message;
            const std::vector<uint8_t> z = slurp(dir / "z.ktx2");
            EXPECT_EQ(u32(z, 44), 2u);
            EXPECT_EQ(u32(plain, 44), 0u);
            EXPECT_TRUE(std::equal(z.begin(), z.begin() + 44, plain.begin()));
            const size_t meta_end = size_t(u32(plain, 56)) + u32(plain, 60);
            const size_t index_end = 80 + 24 * size_t(u32(plain, 40));
            EXPECT_TRUE(std::equal(z.begin() + 48, z.begin() + 80, plain.begin() + 48));
            EXPECT_TRUE(std::equal(z.begin() + long(index_end), z.begin() + long(meta_end),
                                   plain.begin() + long(index_end)));
            size_t expected_offset = meta_end;
            for (int L = int(u32(z, 40)) - 1; L >= 0; --L) {
                const size_t at = 80 + 24 * size_t(L);
                const uint64_t off = u64(z, at), len = u64(z, at + 8), ulen = u64(z, at + 16);
                EXPECT_EQ(off, expected_offset) << "level " << L;
                EXPECT_EQ(ulen, u64(plain, at + 8));
                std::vector<uint8_t> inflated(ulen + 1);
                const size_t n = ZSTD_decompress(inflated.data(), inflated.size(), z.data() + off, len);
                ASSERT_FALSE(ZSTD_isError(n)) << ZSTD_getErrorName(n);
                ASSERT_EQ(n, ulen);
                EXPECT_TRUE(std::equal(inflated.begin(), inflated.begin() + long(n), plain.begin() + long(u64(plain, at))));
                expected_offset = off + len;
            }
            EXPECT_EQ(expected_offset, z.size());
            const ManifestOutput& entry = (*written)[0];
            EXPECT_EQ(entry.extra["supercompression"], "zstd");
            EXPECT_EQ(entry.extra["zstd_level"], 5);
            EXPECT_EQ(entry.extra["bytes"], z.size());
            EXPECT_EQ(entry.extra["uncompressed_bytes"], plain.size());
            auto back = read_ktx2_texture(z, "z.ktx2");
            ASSERT_TRUE(back.ok()) << back.error().message;
            expect_chain_near(back->chain, chain, channels, tolerance(e));
            // A level that claims another uncompressed size is refused.
            std::vector<uint8_t> bad = z;
            const uint64_t wrong = u64(z, 80 + 16) + 4;
            std::memcpy(bad.data() + 80 + 16, &wrong, 8);
            EXPECT_FALSE(read_ktx2_texture(bad, "bad.ktx2").ok());
        }
    }
    // The same chain gives the same bytes every time (levels are compressed independently).
    const MipChain chain = random_chain(300, 200, 4, 77);
    std::vector<std::vector<uint8_t>> runs;
    for (int run = 0; run < 2; ++run) {
        const TextureFileFormat ktx2(TextureContainer::Ktx2);
        ASSERT_TRUE(write_texture(chain, TexelEncoding::Float16, ktx2, dir, "d", "lean").ok());
        runs.push_back(slurp(dir / "d.ktx2"));
    }
    EXPECT_EQ(runs[0], runs[1]);
    EXPECT_EQ(u32(runs[0], 44), 2u);  // zstd is the default
    fs::remove_all(dir);
}

// A KTX2 file whose levels were zstd-compressed band by band as their rows arrived (compress_rows, with
// the raw pages behind zstd's window returned) is byte for byte the file of the one-shot compression of
// the whole raw file (ktx2_zstd), at several zstd levels; and zstd decompresses it to the raw levels.
TEST(EncodedTexture, LevelsCompressedAsTheirRowsArriveGiveTheOneShotFile) {
    const int W = 2048, H = 1280;  // level 0: 10 MiB of RGBA8, well past a level-3 window of 2 MiB
    const int levels = 12;
    std::mt19937 rng(5);
    std::vector<std::vector<float>> data(levels);
    for (int L = 0; L < levels; ++L) {
        const size_t n = size_t(std::max(1, W >> L)) * size_t(std::max(1, H >> L)) * 3;
        data[size_t(L)].resize(n);
        // Smooth ramps with noise in the low bits: compressible, but not trivially.
        for (size_t i = 0; i < n; ++i) data[size_t(L)][i] = float((i / 3 % 4096) / 4096.0 + (rng() % 8) / 2048.0);
    }
    for (int zstd_level : {1, 3, 9}) {
        SCOPED_TRACE("zstd level " + std::to_string(zstd_level));
        Supercompression z;
        z.zstd_level = zstd_level;
        EncodedTexture one_shot(TextureContainer::Ktx2, TexelEncoding::Unorm8, W, H, levels, 3, z);
        EncodedTexture streamed(TextureContainer::Ktx2, TexelEncoding::Unorm8, W, H, levels, 3, z);
        for (int L = 0; L < levels; ++L) {
            const int w = std::max(1, W >> L), h = std::max(1, H >> L);
            one_shot.put_block(L, 0, 0, w, h, data[size_t(L)].data(), 3, 0);
            const int band = std::max(1, 97 >> L);  // not a multiple of anything zstd uses
            for (int y = 0; y < h; y += band) {
                const int rows = std::min(band, h - y);
                streamed.put_block(L, 0, y, w, rows, data[size_t(L)].data() + size_t(y) * size_t(w) * 3, 3, 0);
                ASSERT_TRUE(streamed.compress_rows(L, y + rows).ok());
            }
        }
        auto expected = ktx2_zstd(one_shot.bytes(), one_shot.layout(), zstd_level);
        ASSERT_TRUE(expected.ok());
        const fs::path dir = fresh_dir("streamed_zstd");
        const EncodedFile file{&streamed, "t", "roughness", {}};
        ASSERT_TRUE(write_encoded_textures({&file, 1}, dir).ok());
        const std::vector<uint8_t> written = slurp(dir / "t.ktx2");
        EXPECT_EQ(written.size(), expected->size());
        EXPECT_TRUE(written == *expected) << "the streamed levels differ from the one-shot compression";
        auto back = read_ktx2_texture(written, "t.ktx2");
        ASSERT_TRUE(back.ok()) << back.error().message;
        for (int L = 0; L < levels; ++L) {
            const size_t at = one_shot.layout().level_offset[size_t(L)];
            const size_t n = size_t(std::max(1, W >> L)) * size_t(std::max(1, H >> L)) * 4;
            std::vector<uint8_t> level(n);
            const size_t got = ZSTD_decompress(level.data(), n, written.data() + size_t(back->info.level_offsets[size_t(L)]),
                                               size_t(back->info.level_lengths[size_t(L)]));
            ASSERT_EQ(got, n) << "level " << L;
            EXPECT_TRUE(std::equal(level.begin(), level.end(), one_shot.bytes().begin() + long(at))) << "level " << L;
        }
        fs::remove_all(dir);
    }
}

// A container filled block by block (whole rows and column blocks), in scrambled order and with channels
// taken from a wider interleaved source, is byte for byte the file encode_ktx2 / encode_dds make from the
// whole chain.
TEST(EncodedTexture, BlocksInAnyOrderGiveTheWholeChainFile) {
    const MipChain wide = random_chain(13, 6, 5, 21);
    for (TextureContainer container : {TextureContainer::Ktx2, TextureContainer::Dds}) {
        for (TexelEncoding e : {TexelEncoding::Unorm8, TexelEncoding::Unorm16, TexelEncoding::Float16,
                                TexelEncoding::Float32}) {
            SCOPED_TRACE(std::string(container_name(container)) + " " + encoding_name(e));
            const int first = 1, channels = 3;
            MipChain sub;
            for (const Image& l : wide.levels) {
                Image s(l.width, l.height, channels);
                for (size_t i = 0; i < l.texel_count(); ++i)
                    for (int c = 0; c < channels; ++c) s.pixels[i * channels + c] = l.pixels[i * 5 + first + c];
                sub.levels.push_back(std::move(s));
            }
            EncodedTexture t(container, e, 13, 6, int(wide.levels.size()), channels);
            for (int L = int(wide.levels.size()) - 1; L >= 0; --L) {
                const Image& l = wide.levels[size_t(L)];
                for (int y = l.height - 1; y >= 0; y -= 2) {
                    const int y0 = std::max(0, y - 1), rows = y - y0 + 1;
                    if (L % 2 == 0) {
                        t.put_block(L, 0, y0, l.width, rows, l.texel(0, y0), 5, first);
                        continue;
                    }
                    // Odd levels: column blocks of up to 4 texels, right to left, copied out of the level.
                    for (int x1 = l.width; x1 > 0; x1 -= 4) {
                        const int x0 = std::max(0, x1 - 4), w = x1 - x0;
                        std::vector<float> block;
                        for (int k = 0; k < rows; ++k)
                            block.insert(block.end(), l.texel(x0, y0 + k), l.texel(x0, y0 + k) + size_t(w) * 5);
                        t.put_block(L, x0, y0, w, rows, block.data(), 5, first);
                    }
                }
            }
            const std::vector<uint8_t> whole =
                container == TextureContainer::Ktx2 ? encode_ktx2(sub, e) : encode_dds(sub, e);
            ASSERT_EQ(t.bytes().size(), whole.size());
            EXPECT_TRUE(std::equal(whole.begin(), whole.end(), t.bytes().begin()));
        }
    }
}

// BC levels made as the rows arrive (set_block_format, compress_rows in bands that cut 4-row block rows)
// give the file made from the whole levels at the write, for KTX2 (plain and zstd) and DDS, 8- and 16-bit
// data, sizes whose levels end in partial block rows (the whole-level encoder is checked against a BC
// decoder written from the spec in tests/cli/block_compress_test.cpp).
TEST(EncodedTexture, BlocksMadeAsTheRowsArriveGiveTheWholeLevelFile) {
    struct Case {
        TextureContainer container;
        bool zstd;
        TexelEncoding e;
        int width, height, channels;
        BlockFormat block;
        int astc_side = 4;
    };
    std::mt19937 rng(21);
    // ASTC strips are footprint-high (6 and 8 rows here, sizes that leave partial blocks at both edges).
    for (const Case& c : {Case{TextureContainer::Ktx2, true, TexelEncoding::Unorm8, 300, 203, 1, BlockFormat::Bc4},
                          Case{TextureContainer::Ktx2, false, TexelEncoding::Unorm16, 130, 77, 3, BlockFormat::Bc1},
                          Case{TextureContainer::Dds, false, TexelEncoding::Unorm8, 257, 130, 3, BlockFormat::Bc1},
                          Case{TextureContainer::Dds, false, TexelEncoding::Unorm8, 64, 37, 3, BlockFormat::Bc3},
                          Case{TextureContainer::Ktx2, true, TexelEncoding::Unorm8, 90, 61, 1, BlockFormat::Bc4},
                          Case{TextureContainer::Ktx2, true, TexelEncoding::Unorm8, 100, 75, 1, BlockFormat::AstcR, 6},
                          Case{TextureContainer::Ktx2, false, TexelEncoding::Unorm16, 70, 45, 2, BlockFormat::AstcRg, 8},
                          Case{TextureContainer::Ktx2, true, TexelEncoding::Unorm8, 33, 29, 4, BlockFormat::AstcRgba, 4}}) {
        SCOPED_TRACE(std::string(container_name(c.container)) + " " + encoding_name(c.e) + " " +
                     std::to_string(c.width) + "x" + std::to_string(c.height) + " " + block_format_name(c.block) +
                     " " + std::to_string(c.astc_side));
        const MipChain chain = random_chain(c.width, c.height, c.channels, unsigned(c.height));
        const int levels = int(chain.levels.size());
        Supercompression s;
        s.zstd = c.zstd;
        s.astc_block = c.astc_side;
        EncodedTexture banded(c.container, c.e, c.width, c.height, levels, c.channels, s);
        banded.set_block_format(c.block);
        ASSERT_EQ(banded.block_format(), c.block);
        ASSERT_TRUE(banded.streams());
        ASSERT_TRUE(put_in_bands(banded, chain, rng, 23));
        const fs::path dir = fresh_dir("bc_bands");
        const EncodedFile file{&banded, "b", "roughness", {}, c.block};
        auto written = write_encoded_textures({&file, 1}, dir);
        ASSERT_TRUE(written.ok()) << written.error().message;
        auto whole = write_texture(chain, c.e, TextureFileFormat(c.container, s), dir, "w", "roughness", {}, c.block);
        ASSERT_TRUE(whole.ok()) << whole.error().message;
        const std::string ext = std::string(".") + container_name(c.container);
        const std::vector<uint8_t> got = slurp(dir / ("b" + ext)), want = slurp(dir / ("w" + ext));
        EXPECT_EQ(got.size(), want.size());
        EXPECT_TRUE(got == want) << "the blocks made as the rows arrived differ from those of the whole levels";
        fs::remove_all(dir);
    }
}

// 8/16-bit unorm data get the legacy header (the D3D9 pixel formats Microsoft's DDS reference maps to
// DXGI: L8, A8L8, A8R8G8B8 masks with the texels in B, G, R, A order, L16, FourCC 36); R16G16 and float
// data the DX10 header.
TEST(Dds, LegacyHeaderWhereOneExistsElseDx10) {
    const fs::path dir = fresh_dir("dds");
    struct Case { TexelEncoding e; int channels; uint32_t dxgi; int stored; uint32_t pf_flags, fourcc, bits, m[4]; };
    constexpr uint32_t lum = 0x20000, alpha = 0x1, rgb = 0x40, four = 0x4;
    // DXGI_FORMAT_R16G16B16A16_FLOAT 10, R32G32B32A32_FLOAT 2 (three channels stored as four, A = 1).
    for (const Case& c : {Case{TexelEncoding::Unorm8, 1, 0, 1, lum, 0, 8, {0xFF, 0, 0, 0}},
                          Case{TexelEncoding::Unorm8, 2, 0, 2, lum | alpha, 0, 16, {0xFF, 0, 0, 0xFF00}},
                          Case{TexelEncoding::Unorm8, 3, 0, 4, rgb | alpha, 0, 32, {0xFF0000, 0xFF00, 0xFF, 0xFF000000u}},
                          Case{TexelEncoding::Unorm16, 1, 0, 1, lum, 0, 16, {0xFFFF, 0, 0, 0}},
                          Case{TexelEncoding::Unorm16, 2, 35, 2, four, 0x30315844u, 0, {0, 0, 0, 0}},
                          Case{TexelEncoding::Unorm16, 4, 0, 4, four, 36, 0, {0, 0, 0, 0}},
                          Case{TexelEncoding::Float16, 4, 10, 4, four, 0x30315844u, 0, {0, 0, 0, 0}},
                          Case{TexelEncoding::Float32, 3, 2, 4, four, 0x30315844u, 0, {0, 0, 0, 0}}}) {
        SCOPED_TRACE(std::string(encoding_name(c.e)) + " x" + std::to_string(c.channels));
        const MipChain chain = random_chain(10, 4, c.channels, 5);
        auto written = write_texture(chain, c.e, TextureFileFormat(TextureContainer::Dds), dir, "t", "roughness");
        ASSERT_TRUE(written.ok()) << written.error().message;
        const std::vector<uint8_t> b = slurp(dir / "t.dds");
        const ParsedDds p = parse_dds(b);
        EXPECT_EQ(p.width, 10u);
        EXPECT_EQ(p.height, 4u);
        EXPECT_EQ(p.mips, 4u);
        EXPECT_EQ(p.pf_flags, c.pf_flags);
        EXPECT_EQ(p.fourcc, c.fourcc);
        EXPECT_EQ(p.bit_count, c.bits);
        for (int k = 0; k < 4; ++k) EXPECT_EQ(p.masks[k], c.m[k]) << "mask " << k;
        EXPECT_NE(p.flags & 0x20000u, 0u);  // DDSD_MIPMAPCOUNT
        EXPECT_NE(p.caps & 0x400000u, 0u);  // DDSCAPS_MIPMAP
        if (c.dxgi) {
            EXPECT_EQ(p.dxgi, c.dxgi);
            EXPECT_EQ(p.dimension, 3u);
            EXPECT_EQ(p.array_size, 1u);
        }
        const int bytes = c.e == TexelEncoding::Unorm8 ? 1 : c.e == TexelEncoding::Float32 ? 4 : 2;
        size_t at = p.data_offset;
        for (const Image& level : chain.levels) {
            for (size_t i = 0; i < level.texel_count(); ++i) {
                for (int k = 0; k < c.stored; ++k, at += size_t(bytes)) {
                    // The masks give each byte's channel: A8R8G8B8 holds B, G, R, A.
                    const bool bgra = c.bits == 32 && c.m[0] == 0xFF0000u;
                    const int ch = bgra && k != 3 ? 2 - k : k;
                    const float want = ch < c.channels ? level.pixels[i * c.channels + ch] : 1.0f;
                    float got;
                    if (bytes == 1) got = b[at] / 255.0f;
                    else if (c.e == TexelEncoding::Unorm16) got = float(b[at] | b[at + 1] << 8) / 65535.0f;
                    else if (bytes == 4) std::memcpy(&got, &b[at], 4);
                    else {
                        // IEEE half, decoded by hand.
                        const uint16_t h = uint16_t(b[at] | b[at + 1] << 8);
                        const int ex = (h >> 10) & 31, man = h & 1023;
                        got = ex == 0 ? std::ldexp(float(man), -24) : std::ldexp(1.0f + man / 1024.0f, ex - 15);
                        if (h & 0x8000) got = -got;
                    }
                    ASSERT_NEAR(got, want, tolerance(c.e));
                }
            }
        }
        EXPECT_EQ(at, b.size());
        // OpenImageIO reads the legacy forms (and DX10 files from 2.5 on); where it can, it must agree.
        // OpenImageIO 2.4 returns 16-bit legacy data at 8-bit precision.
        auto in = OIIO::ImageInput::open((dir / "t.dds").string());
        if (in) {
            std::vector<float> px(size_t(10) * 4 * size_t(in->spec().nchannels));
            ASSERT_TRUE(in->read_image(0, 0, 0, in->spec().nchannels, OIIO::TypeDesc::FLOAT, px.data()));
            EXPECT_NEAR(px[0], chain.levels[0].pixels[0], c.e == TexelEncoding::Unorm16 ? 1.0 / 255 : tolerance(c.e));
            if (c.bits == 32 && c.channels >= 3)  // A8R8G8B8: red and blue where the masks put them
                EXPECT_NEAR(px[2], chain.levels[0].pixels[2], tolerance(c.e));
        } else {
            (void)OIIO::geterror();
        }
    }
    fs::remove_all(dir);
}

// A DDS file as the documented layout and the encoding rules give it, worked out here: "DDS ", DDS_HEADER
// (flags CAPS | HEIGHT | WIDTH | PITCH | PIXELFORMAT | MIPMAPCOUNT, the top level's pitch, the mip count,
// a DDS_PIXELFORMAT of its own), DDS_HEADER_DXT10 where the format has no legacy form, then every level top
// down, tightly packed: unorm as std::lround(clamp(v, 0, 1) * max), half as Imath rounds it, three
// channels stored as four with A = 1, A8R8G8B8 texels as B, G, R, A.
struct HandDdsFormat { uint32_t pf_flags, fourcc, bits, masks[4], dxgi; };
std::vector<uint8_t> hand_dds(const MipChain& chain, TexelEncoding e, const HandDdsFormat& f) {
    const int channels = chain.channels(), stored = channels == 3 ? 4 : channels;
    const int bytes = e == TexelEncoding::Unorm8 ? 1 : e == TexelEncoding::Float32 ? 4 : 2;
    std::vector<uint8_t> b;
    auto put = [&](uint32_t v) {
        for (int k = 0; k < 4; ++k) b.push_back(uint8_t(v >> (8 * k)));
    };
    put(0x20534444u);
    put(124);
    put(0x1u | 0x2u | 0x4u | 0x8u | 0x1000u | 0x20000u);
    put(uint32_t(chain.height()));
    put(uint32_t(chain.width()));
    put(uint32_t(chain.width() * stored * bytes));
    put(0);  // depth
    put(uint32_t(chain.levels.size()));
    for (int k = 0; k < 11; ++k) put(0);  // reserved
    put(32);
    put(f.pf_flags);
    put(f.fourcc);
    put(f.bits);
    for (uint32_t m : f.masks) put(m);
    put(0x1000u | 0x8u | 0x400000u);  // TEXTURE | COMPLEX | MIPMAP
    for (int k = 0; k < 4; ++k) put(0);  // caps2-4, reserved
    if (f.fourcc == 0x30315844u) {        // DDS_HEADER_DXT10
        put(f.dxgi);
        put(3);  // TEXTURE2D
        put(0);
        put(1);
        put(stored != channels ? 3 : 0);  // alpha mode: opaque for the padded A
    }
    EXPECT_EQ(b.size(), f.fourcc == 0x30315844u ? 148u : 128u);
    const bool bgra = f.bits == 32 && f.masks[0] == 0xFF0000u;
    for (const Image& level : chain.levels) {
        for (size_t i = 0; i < level.texel_count(); ++i) {
            for (int k = 0; k < stored; ++k) {
                const int ch = bgra && k != 3 ? 2 - k : k;
                const float v = ch < channels ? level.pixels[i * size_t(channels) + size_t(ch)] : 1.0f;
                const float c = std::clamp(v, 0.0f, 1.0f);
                if (e == TexelEncoding::Unorm8) {
                    b.push_back(uint8_t(std::lround(c * 255.0f)));
                } else if (e == TexelEncoding::Unorm16) {
                    const uint32_t u = uint32_t(std::lround(c * 65535.0f));
                    b.push_back(uint8_t(u)), b.push_back(uint8_t(u >> 8));
                } else if (e == TexelEncoding::Float16) {
                    const uint16_t h = Imath::half(v).bits();
                    b.push_back(uint8_t(h)), b.push_back(uint8_t(h >> 8));
                } else {
                    uint32_t u;
                    std::memcpy(&u, &v, 4);
                    put(u);
                }
            }
        }
    }
    return b;
}

// The temporary files next to `dir`/`stem`.* (AtomicOutput names them ".<stem>.tmp<pid>-<n><ext>").
std::vector<fs::path> temporaries(const fs::path& dir, const std::string& stem) {
    std::vector<fs::path> found;
    for (const auto& entry : fs::directory_iterator(dir))
        if (entry.path().filename().string().rfind("." + stem + ".tmp", 0) == 0) found.push_back(entry.path());
    return found;
}

// A DDS file written to its file as its rows arrive (stream_to, compress_rows band by band, the raw pages
// behind them returned) is, byte for byte, the file worked out by hand from the layout, as is the file
// written whole; the rows reported are in the (temporary) file before the texture is finished, and no
// temporary is left once it is written.
TEST(Dds, WrittenAsItsRowsArriveIsTheHandWorkedFile) {
    constexpr uint32_t lum = 0x20000, alpha = 0x1, rgb = 0x40, four = 0x4, dx10 = 0x30315844u;
    struct Case { TexelEncoding e; int width, height, channels; HandDdsFormat f; };
    std::mt19937 rng(12);
    for (const Case& c : {Case{TexelEncoding::Unorm8, 1100, 700, 3, {rgb | alpha, 0, 32, {0xFF0000, 0xFF00, 0xFF, 0xFF000000u}, 0}},
                          Case{TexelEncoding::Unorm8, 37, 23, 1, {lum, 0, 8, {0xFF, 0, 0, 0}, 0}},
                          Case{TexelEncoding::Unorm8, 64, 32, 2, {lum | alpha, 0, 16, {0xFF, 0, 0, 0xFF00}, 0}},
                          Case{TexelEncoding::Unorm16, 300, 200, 3, {four, 36, 0, {0, 0, 0, 0}, 0}},
                          Case{TexelEncoding::Unorm16, 41, 9, 1, {lum, 0, 16, {0xFFFF, 0, 0, 0}, 0}},
                          Case{TexelEncoding::Unorm16, 20, 12, 2, {four, dx10, 0, {0, 0, 0, 0}, 35}},
                          Case{TexelEncoding::Float16, 600, 520, 4, {four, dx10, 0, {0, 0, 0, 0}, 10}},
                          Case{TexelEncoding::Float16, 33, 70, 3, {four, dx10, 0, {0, 0, 0, 0}, 10}},
                          Case{TexelEncoding::Float32, 17, 30, 1, {four, dx10, 0, {0, 0, 0, 0}, 41}}}) {
        SCOPED_TRACE(std::string(encoding_name(c.e)) + " " + std::to_string(c.width) + "x" + std::to_string(c.height) +
                     "x" + std::to_string(c.channels));
        const fs::path dir = fresh_dir("dds_streamed");
        const MipChain chain = random_chain(c.width, c.height, c.channels, unsigned(c.width), -0.1f, 1.1f);
        const std::vector<uint8_t> want = hand_dds(chain, c.e, c.f);
        const int levels = int(chain.levels.size());
        EncodedTexture t(TextureContainer::Dds, c.e, c.width, c.height, levels, c.channels);
        ASSERT_TRUE(t.stream_to(dir / "t.dds").ok());
        ASSERT_TRUE(t.streams() && t.streams_to_file());
        const size_t header = c.f.fourcc == dx10 ? 148 : 128;
        const size_t row_bytes = size_t(c.width) * size_t(c.channels == 3 ? 4 : c.channels) *
                                 size_t(c.e == TexelEncoding::Unorm8 ? 1 : c.e == TexelEncoding::Float32 ? 4 : 2);
        bool first_band_checked = false;
        ASSERT_TRUE(put_in_bands(t, chain, rng, 40, [&](int L, int y, int rows) {
            if (L != 0 || y != rows) return;
            // The first band: already in the file, which is not yet in place.
            first_band_checked = true;
            EXPECT_FALSE(fs::exists(dir / "t.dds"));
            const std::vector<fs::path> temp = temporaries(dir, "t");
            ASSERT_EQ(temp.size(), 1u);
            const std::vector<uint8_t> early = slurp(temp[0]);
            const size_t n = header + size_t(rows) * row_bytes;
            ASSERT_GE(early.size(), n);
            EXPECT_TRUE(std::equal(want.begin(), want.begin() + long(n), early.begin()))
                << "the header and the first rows are not in the file as they arrived";
        }));
        EXPECT_TRUE(first_band_checked);
        const EncodedFile file{&t, "t", "roughness", {}};
        auto written = write_encoded_textures({&file, 1}, dir);
        ASSERT_TRUE(written.ok()) << written.error().message;
        const std::vector<uint8_t> got = slurp(dir / "t.dds");
        EXPECT_EQ(got.size(), want.size());
        EXPECT_TRUE(got == want) << "the streamed file differs from the hand-worked one";
        ASSERT_EQ(written->size(), 1u);
        EXPECT_EQ((*written)[0].sha256, sha256_hex(got));
        EXPECT_EQ((*written)[0].extra["bytes"], want.size());
        EXPECT_TRUE(temporaries(dir, "t").empty());
        // The same file written whole (no stream_to) as before.
        auto whole = write_texture(chain, c.e, TextureFileFormat(TextureContainer::Dds), dir, "w", "roughness");
        ASSERT_TRUE(whole.ok()) << whole.error().message;
        EXPECT_TRUE(slurp(dir / "w.dds") == want) << "the file written whole differs from the hand-worked one";
        EXPECT_EQ((*whole)[0].sha256, (*written)[0].sha256);
        fs::remove_all(dir);
    }
}

// A DDS file begun by stream_to and never written leaves nothing behind; one written to another path than
// the one it was begun for is refused.
TEST(Dds, UnfinishedStreamLeavesNoFile) {
    const fs::path dir = fresh_dir("dds_unfinished");
    const MipChain chain = random_chain(16, 8, 1, 3);
    {
        EncodedTexture t(TextureContainer::Dds, TexelEncoding::Unorm8, 16, 8, int(chain.levels.size()), 1);
        ASSERT_TRUE(t.stream_to(dir / "t.dds").ok());
        t.put_block(0, 0, 0, 16, 8, chain.levels[0].pixels.data(), 1, 0);
        ASSERT_TRUE(t.compress_rows(0, 8).ok());
        EXPECT_EQ(temporaries(dir, "t").size(), 1u);
        for (int L = 1; L < int(chain.levels.size()); ++L) {
            const Image& l = chain.levels[size_t(L)];
            t.put_block(L, 0, 0, l.width, l.height, l.pixels.data(), 1, 0);
        }
        const EncodedFile file{&t, "other", "roughness", {}};
        EXPECT_FALSE(write_encoded_textures({&file, 1}, dir).ok());
        EXPECT_FALSE(fs::exists(dir / "other.dds"));
    }
    EXPECT_TRUE(temporaries(dir, "t").empty());
    EXPECT_FALSE(fs::exists(dir / "t.dds"));
    EncodedTexture ktx2(TextureContainer::Ktx2, TexelEncoding::Unorm8, 16, 8, int(chain.levels.size()), 1);
    EXPECT_FALSE(ktx2.stream_to(dir / "t.ktx2").ok());
    fs::remove_all(dir);
}

// The same chain written twice, a second apart, gives the same bytes: the header's DateTime is not the
// clock's (SOURCE_DATE_EPOCH when set, else the epoch), so build caches and manifest hashes stay valid.
TEST(Exr, SameChainSameBytesAtAnyTime) {
    const fs::path dir = fresh_dir("exr_reproducible");
    const MipChain chain = random_chain(20, 12, 1, 3, 0.0f, 1.0f);
    auto bytes = [&](const std::string& stem) {
        const TextureFileFormat exr(TextureContainer::Exr, {}, WrapMode::Repeat);
        auto written = write_texture(chain, TexelEncoding::Float16, exr, dir, stem, "kernel", {"t"});
        EXPECT_TRUE(written.ok()) << written.error().message;
        std::ifstream f(dir / (stem + ".exr"), std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(f), {});
    };
    const std::string first = bytes("a");
    std::this_thread::sleep_for(std::chrono::milliseconds(1100));
    const std::string second = bytes("b");
    ASSERT_FALSE(first.empty());
    EXPECT_TRUE(first == second);
    auto in = OIIO::ImageInput::open((dir / "a.exr").string());
    ASSERT_TRUE(in);
    const std::string stamp = in->spec().get_string_attribute("DateTime");
    const char* epoch = std::getenv("SOURCE_DATE_EPOCH");
    if (!epoch) EXPECT_EQ(stamp, "1970:01:01 00:00:00");
    fs::remove_all(dir);
}

// EXR channels carry the names common readers load (R, G, B, A in the KTX2/DDS order) and their meaning
// in the "specbake:channels" header attribute; more than four channels are refused (every container has
// the same 1, 2 or 4 channel layout).
TEST(Exr, MipmappedTiledPlainTextureThroughOpenImageIO) {
    const fs::path dir = fresh_dir("exr");
    const MipChain chain = random_chain(70, 33, 4, 9, -2.0f, 2.0f);
    const TextureFileFormat exr(TextureContainer::Exr, {}, WrapMode::Clamp);
    auto written =
        write_texture(chain, TexelEncoding::Float32, exr, dir, "lean", "lean", {"m.x", "m.y", "M.xx", "M.yy"});
    ASSERT_TRUE(written.ok()) << written.error().message;
    EXPECT_EQ((*written)[0].extra["channel_meaning"], (std::vector<std::string>{"m.x", "m.y", "M.xx", "M.yy"}));
    EXPECT_EQ((*written)[0].extra["gpu_format"], "R32G32B32A32_SFLOAT");
    auto in = OIIO::ImageInput::open((dir / "lean.exr").string());
    ASSERT_TRUE(in);
    const OIIO::ImageSpec spec0 = in->spec(0, 0);
    EXPECT_EQ(spec0.get_string_attribute("textureformat"), "Plain Texture");
    EXPECT_EQ(spec0.get_string_attribute("wrapmodes"), "clamp,clamp");
    EXPECT_EQ(spec0.get_string_attribute("specbake:channels"), "m.x,m.y,M.xx,M.yy");
    EXPECT_GT(spec0.tile_width, 0);
    // OpenEXR stores channels sorted by name; find each by its name.
    const std::vector<std::string> names{"R", "G", "B", "A"};
    ASSERT_EQ(spec0.nchannels, 4);
    std::vector<int> column(4, -1);
    for (int c = 0; c < 4; ++c)
        for (int k = 0; k < spec0.nchannels; ++k)
            if (spec0.channelnames[size_t(k)] == names[size_t(c)]) column[size_t(c)] = k;
    for (int c = 0; c < 4; ++c) ASSERT_GE(column[size_t(c)], 0) << names[size_t(c)];
    int levels = 0;
    for (int L = 0;; ++L) {
        OIIO::ImageSpec spec = in->spec_dimensions(0, L);
        if (spec.width == 0) break;
        ++levels;
        const Image& want = chain.levels[size_t(L)];
        ASSERT_EQ(spec.width, want.width);
        ASSERT_EQ(spec.height, want.height);
        std::vector<float> px(want.pixels.size());
        ASSERT_TRUE(in->read_image(0, L, 0, 4, OIIO::TypeDesc::FLOAT, px.data()));
        for (size_t i = 0; i < want.texel_count(); ++i)
            for (int c = 0; c < 4; ++c) ASSERT_EQ(px[i * 4 + size_t(column[size_t(c)])], want.pixels[i * 4 + size_t(c)]);
    }
    EXPECT_EQ(levels, int(chain.levels.size()));
    // One channel is Y; five channels are refused with the file's name.
    const TextureFileFormat exr_repeat(TextureContainer::Exr);
    auto one = write_texture(random_chain(8, 8, 1, 2), TexelEncoding::Float16, exr_repeat, dir, "t", "kernel", {"t"});
    ASSERT_TRUE(one.ok()) << one.error().message;
    auto in1 = OIIO::ImageInput::open((dir / "t.exr").string());
    ASSERT_TRUE(in1);
    EXPECT_EQ(in1->spec().channelnames, std::vector<std::string>{"Y"});
    auto five = write_texture(random_chain(8, 8, 5, 2), TexelEncoding::Float16, exr_repeat, dir, "five", "lean");
    ASSERT_FALSE(five.ok());
    EXPECT_NE(five.error().message.find("five"), std::string::npos);
    EXPECT_FALSE(fs::exists(dir / "five.exr"));
    fs::remove_all(dir);
}

// EXR files (the mipmapped container, and per-mip files of float data) written band by band as their rows
// arrive, in scrambled band sizes and sizes that do not tile, read back through OpenImageIO as the files
// OpenImageIO writes from each whole level (write_image, the header specbake's files had when OpenImageIO
// wrote them): the same header attributes and the same stored texels at every level, and the texels given.
TEST(Exr, StreamedInBandsEqualsWrittenWhole) {
    struct Case { TextureContainer container; TexelEncoding encoding; int width, height, channels; };
    std::mt19937 rng(8);
    for (const Case c : {Case{TextureContainer::Exr, TexelEncoding::Float16, 300, 200, 4},
                         Case{TextureContainer::Exr, TexelEncoding::Float32, 130, 64, 1},
                         Case{TextureContainer::Exr, TexelEncoding::Float16, 64, 257, 3},
                         Case{TextureContainer::PngPerMip, TexelEncoding::Float16, 301, 77, 4},
                         Case{TextureContainer::PngPerMip, TexelEncoding::Float32, 40, 130, 1}}) {
        SCOPED_TRACE(std::string(container_name(c.container)) + " " + encoding_name(c.encoding) + " " +
                     std::to_string(c.width) + "x" + std::to_string(c.height) + "x" + std::to_string(c.channels));
        const MipChain chain = random_chain(c.width, c.height, c.channels, unsigned(c.width), -2.0f, 2.0f);
        const int levels = int(chain.levels.size());
        const std::vector<std::string> meaning{"a", "b", "c", "d"};
        const std::vector<std::string> given(meaning.begin(), meaning.begin() + std::min(c.channels, 4));
        EncodedTexture whole(c.container, c.encoding, c.width, c.height, levels, c.channels, {}, WrapMode::Mirror);
        EncodedTexture banded(c.container, c.encoding, c.width, c.height, levels, c.channels, {}, WrapMode::Mirror);
        banded.set_channel_meaning(given);
        ASSERT_TRUE(banded.exr() && banded.streams());
        for (int L = 0; L < levels; ++L) {
            const Image& level = chain.levels[size_t(L)];
            whole.put_block(L, 0, 0, level.width, level.height, level.pixels.data(), c.channels, 0);
        }
        ASSERT_TRUE(put_in_bands(banded, chain, rng, 40));
        const fs::path dir = fresh_dir("exr_bands");
        const EncodedFile file{&banded, "t", "kernel", given};
        auto written = write_encoded_textures({&file, 1}, dir);
        ASSERT_TRUE(written.ok()) << written.error().message;
        // The reference: each file written whole by OpenImageIO from the stored levels, as before streaming.
        const bool mipmapped = c.container == TextureContainer::Exr;
        const int stored = whole.layout().stored_channels;
        const OIIO::TypeDesc type = whole.encoding() == TexelEncoding::Float32 ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::HALF;
        std::vector<std::string> names = stored == 1 ? std::vector<std::string>{"Y"}
                                                     : std::vector<std::string>{"R", "G", "B", "A"};
        names.resize(size_t(stored));
        std::string stored_meaning;
        for (int k = 0; k < stored; ++k) stored_meaning += (k ? "," : "") + (k < c.channels ? meaning[size_t(k)] : std::string("1"));
        const char* epoch = std::getenv("SOURCE_DATE_EPOCH");
        auto reference = [&](const fs::path& path, int first, int count) {
            auto out = OIIO::ImageOutput::create(path.string());
            ASSERT_TRUE(out);
            for (int L = first; L < first + count; ++L) {
                OIIO::ImageSpec spec(std::max(1, c.width >> L), std::max(1, c.height >> L), stored, type);
                spec.channelnames = names;
                spec.attribute("oiio:UnassociatedAlpha", 1);
                if (mipmapped) {
                    spec.tile_width = spec.tile_height = 64;
                    spec.attribute("textureformat", "Plain Texture");
                    spec.attribute("wrapmodes", "mirror,mirror");
                }
                spec.attribute("compression", "zip");
                spec.attribute("oiio:ColorSpace", "Linear");
                spec.attribute("Software", "specbake");
                spec.attribute("DateTime", "1970:01:01 00:00:00");
                spec.attribute("specbake:channels", stored_meaning);
                ASSERT_TRUE(out->open(path.string(), spec, L == first ? OIIO::ImageOutput::Create
                                                                      : OIIO::ImageOutput::AppendMIPLevel));
                ASSERT_TRUE(out->write_image(type, whole.bytes().data() + whole.layout().level_offset[size_t(L)]));
            }
            ASSERT_TRUE(out->close());
        };
        const int files = mipmapped ? 1 : levels;
        ASSERT_EQ(written->size(), size_t(files));
        for (int k = 0; k < files; ++k) {
            const std::string name = mipmapped ? "t.exr" : "t_mip" + std::to_string(k) + ".exr";
            EXPECT_EQ((*written)[size_t(k)].path, name);
            reference(dir / ("ref_" + name), mipmapped ? 0 : k, mipmapped ? levels : 1);
            auto in = OIIO::ImageInput::open((dir / name).string());
            ASSERT_TRUE(in);
            auto ref = OIIO::ImageInput::open((dir / ("ref_" + name)).string());
            ASSERT_TRUE(ref);
            for (int L = 0; ref->seek_subimage(0, L); ++L) {
                ASSERT_TRUE(in->seek_subimage(0, L)) << name << ": no level " << L;
                // Every attribute as OpenImageIO reports it (the DateTime differs only when SOURCE_DATE_EPOCH
                // is set, as the reference stamps the epoch).
                OIIO::ImageSpec ours = in->spec(), theirs = ref->spec();
                if (epoch) ours.erase_attribute("DateTime"), theirs.erase_attribute("DateTime");
                EXPECT_EQ(ours.serialize(OIIO::ImageSpec::SerialText, OIIO::ImageSpec::SerialDetailed),
                          theirs.serialize(OIIO::ImageSpec::SerialText, OIIO::ImageSpec::SerialDetailed))
                    << name << " level " << L;
                std::vector<uint8_t> got(theirs.image_bytes()), want(theirs.image_bytes());
                ASSERT_EQ(ours.image_bytes(), theirs.image_bytes());
                ASSERT_TRUE(in->read_image(0, L, 0, stored, type, got.data())) << in->geterror();
                ASSERT_TRUE(ref->read_image(0, L, 0, stored, type, want.data())) << ref->geterror();
                EXPECT_TRUE(got == want) << name << " level " << L << ": other texels";
            }
            int read = 0;
            for (int L = 0; in->seek_subimage(0, L); ++L, ++read) {
                const OIIO::ImageSpec& spec = in->spec();
                Image level(spec.width, spec.height, stored), got(spec.width, spec.height, c.channels);
                ASSERT_TRUE(in->read_image(0, L, 0, stored, OIIO::TypeDesc::FLOAT, level.pixels.data()));
                for (int ch = 0; ch < c.channels; ++ch) {  // OpenEXR stores channels sorted by name
                    const long column = std::find(spec.channelnames.begin(), spec.channelnames.end(),
                                                  names[size_t(ch)]) - spec.channelnames.begin();
                    ASSERT_LT(column, stored);
                    for (size_t i = 0; i < level.texel_count(); ++i)
                        got.pixels[i * size_t(c.channels) + size_t(ch)] = level.pixels[i * size_t(stored) + size_t(column)];
                }
                MipChain one, want;
                one.levels.push_back(got);
                want.levels.push_back(chain.levels[size_t(L + (mipmapped ? 0 : k))]);
                expect_chain_near(one, want, c.channels, tolerance(c.encoding));
            }
            EXPECT_EQ(read, mipmapped ? levels : 1);
        }
        fs::remove_all(dir);
    }
}

TEST(PngPerMip, OneFilePerLevel) {
    const fs::path dir = fresh_dir("png");
    const MipChain chain = random_chain(9, 5, 3, 11);
    const TextureFileFormat png(TextureContainer::PngPerMip);
    auto written = write_texture(chain, TexelEncoding::Unorm16, png, dir, "n", "normal");
    ASSERT_TRUE(written.ok()) << written.error().message;
    ASSERT_EQ(written->size(), chain.levels.size());
    for (size_t L = 0; L < chain.levels.size(); ++L) {
        const fs::path p = dir / ("n_mip" + std::to_string(L) + ".png");
        auto d = decode_image(p);
        ASSERT_TRUE(d.ok()) << d.error().message;
        EXPECT_EQ(d->info.bits_per_channel, 16);
        ASSERT_EQ(d->image.channels, 4);  // RGB data as RGBA, A = 1
        for (size_t i = 0; i < d->image.texel_count(); ++i) ASSERT_EQ(d->image.pixels[i * 4 + 3], 1.0f);
        MipChain one, want;
        one.levels.push_back(d->image);
        want.levels.push_back(chain.levels[L]);
        expect_chain_near(one, want, 3, tolerance(TexelEncoding::Unorm16));
    }
    auto floats = write_texture(chain, TexelEncoding::Float16, png, dir, "k", "kernel");
    ASSERT_TRUE(floats.ok());
    EXPECT_EQ((*floats)[0].path, "k_mip0.exr");
    fs::remove_all(dir);
}

// A per-mip PNG deflated strip by strip as its rows arrive: the same bytes however the rows arrive, and
// OpenImageIO (libpng) reads back exactly the texels given, for every channel count and depth, sizes of
// one strip and of several, the last one short.
TEST(PngLevelStream, StreamedInBandsReadsBackExactlyThroughOpenImageIO) {
    // noisy_top: the upper half uniform noise (16-bit strips of it are Huffman-coded alone), the rest ramps.
    struct Case { int width, height, channels, bits; bool noisy_top = false; };
    std::mt19937 rng(5);
    for (const Case c : {Case{1, 1, 1, 8}, Case{7, 3, 4, 16}, Case{300, 1000, 2, 8}, Case{2100, 70, 4, 8},
                         Case{513, 400, 1, 16}, Case{1030, 300, 4, 16, true}, Case{700, 90, 2, 8, true}}) {
        SCOPED_TRACE(std::to_string(c.width) + "x" + std::to_string(c.height) + " " + std::to_string(c.channels) +
                     " channels, " + std::to_string(c.bits) + " bits");
        const size_t row_bytes = size_t(c.width) * size_t(c.channels) * size_t(c.bits / 8);
        std::vector<uint8_t> texels(row_bytes * size_t(c.height));
        // Smooth ramps with noise: compressible, but not trivially.
        for (size_t i = 0; i < texels.size(); ++i) texels[i] = uint8_t(i / 7 + rng() % 5);
        if (c.noisy_top)
            for (size_t i = 0; i < row_bytes * size_t(c.height / 2); ++i) texels[i] = uint8_t(rng());
        PngLevelStream whole(c.width, c.height, c.channels, c.bits, 2);
        ASSERT_TRUE(whole.add_rows(texels.data(), c.height).ok());
        ASSERT_TRUE(whole.done());
        PngLevelStream banded(c.width, c.height, c.channels, c.bits, 2);
        for (int rows = 0; rows < c.height;) {
            rows = std::min(c.height, rows + 1 + int(rng() % 97));
            ASSERT_TRUE(banded.add_rows(texels.data(), rows).ok());
            EXPECT_LT(banded.rows_read(), std::max(1, rows));
        }
        ASSERT_TRUE(banded.done());
        std::vector<uint8_t> a, b;
        for (std::span<const uint8_t> p : whole.pieces()) a.insert(a.end(), p.begin(), p.end());
        for (std::span<const uint8_t> p : banded.pieces()) b.insert(b.end(), p.begin(), p.end());
        EXPECT_TRUE(a == b) << "the file depends on how its rows arrived";
        EXPECT_EQ(a.size(), whole.bytes());
        const fs::path dir = fresh_dir("png_stream");
        const fs::path file = dir / "level.png";
        std::ofstream(file, std::ios::binary).write(reinterpret_cast<const char*>(a.data()), std::streamsize(a.size()));
        OIIO::ImageSpec config;
        config.attribute("oiio:UnassociatedAlpha", 1);  // alpha as stored (data), not premultiplied
        auto in = OIIO::ImageInput::open(file.string(), &config);
        ASSERT_TRUE(in) << OIIO::geterror();
        const OIIO::ImageSpec& spec = in->spec();
        EXPECT_EQ(spec.width, c.width);
        EXPECT_EQ(spec.height, c.height);
        EXPECT_EQ(spec.nchannels, c.channels);
        const OIIO::TypeDesc type = c.bits == 8 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::UINT16;
        std::vector<uint8_t> back(texels.size());
        ASSERT_TRUE(in->read_image(0, 0, 0, c.channels, type, back.data())) << in->geterror();
        EXPECT_TRUE(back == texels) << "OpenImageIO decodes other texels than were written";
        in->close();
        fs::remove_all(dir);
    }
}

TEST(ImageIo, DecodesEveryInputFormatWithoutConversion) {
    const fs::path dir = fresh_dir("decode");
    Image src(6, 5, 3);
    for (size_t i = 0; i < src.pixels.size(); ++i) src.pixels[i] = float(i % 256) / 255.0f;
    struct Case { const char* name; OIIO::TypeDesc type; int bits; double tol; };
    for (const Case& c : {Case{"a.png", OIIO::TypeDesc::UINT8, 8, 1e-6}, Case{"b.png", OIIO::TypeDesc::UINT16, 16, 1e-6},
                          Case{"c.tga", OIIO::TypeDesc::UINT8, 8, 1e-6}, Case{"d.tif", OIIO::TypeDesc::UINT16, 16, 1e-6},
                          Case{"e.exr", OIIO::TypeDesc::HALF, 16, 1e-3}, Case{"f.jpg", OIIO::TypeDesc::UINT8, 8, 0.1}}) {
        SCOPED_TRACE(c.name);
        const fs::path p = dir / c.name;
        {
            auto out = OIIO::ImageOutput::create(p.string());
            ASSERT_TRUE(out);
            OIIO::ImageSpec spec(src.width, src.height, 3, c.type);
            if (std::string(c.name).ends_with(".png")) spec.attribute("oiio:ColorSpace", "sRGB");
            ASSERT_TRUE(out->open(p.string(), spec));
            ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, src.pixels.data()));
            out->close();
        }
        auto d = decode_image(p);
        ASSERT_TRUE(d.ok()) << d.error().message;
        EXPECT_EQ(d->info.bits_per_channel, c.bits);
        ASSERT_EQ(d->image.width, 6);
        ASSERT_EQ(d->image.channels, 3);
        for (size_t i = 0; i < src.pixels.size(); ++i) ASSERT_NEAR(d->image.pixels[i], src.pixels[i], c.tol);
        // The same bytes from memory (embedded images).
        const std::vector<uint8_t> bytes = slurp(p);
        auto m = read_image_memory(bytes, "embedded");
        ASSERT_TRUE(m.ok()) << m.error().message;
        EXPECT_EQ(m->pixels, d->image.pixels);
    }
    fs::remove_all(dir);
}

TEST(ImageIo, RgbaPngIsNotPremultiplied) {
    const fs::path dir = fresh_dir("alpha");
    const fs::path p = dir / "orm.png";
    Image src(2, 1, 4);
    src.pixels = {1.0f, 0.6f, 0.2f, 0.0f, 0.4f, 0.8f, 1.0f, 0.5f};
    ASSERT_TRUE(write_image(p, src, 8).ok());
    auto d = read_image(p);
    ASSERT_TRUE(d.ok());
    for (size_t i = 0; i < src.pixels.size(); ++i) EXPECT_NEAR(d->pixels[i], src.pixels[i], 0.5 / 255 + 1e-6);
    fs::remove_all(dir);
}

TEST(ImageIo, BadFilesGiveOneLineNamingTheFile) {
    const fs::path dir = fresh_dir("bad");
    Image src(16, 16, 3);
    ASSERT_TRUE(write_image(dir / "good.png", src, 8).ok());
    std::vector<uint8_t> bytes = slurp(dir / "good.png");
    {
        std::ofstream f(dir / "truncated.png", std::ios::binary);
        f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size() / 2));
    }
    // A PNG signature and IHDR claiming 0 x 0.
    const uint8_t zero[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R',
                            0, 0, 0, 0, 0, 0, 0, 0, 8, 2, 0, 0, 0, 0x0, 0x0, 0x0, 0x0};
    {
        std::ofstream f(dir / "zero.png", std::ios::binary);
        f.write(reinterpret_cast<const char*>(zero), sizeof(zero));
    }
    {
        std::ofstream f(dir / "garbage.png", std::ios::binary);
        f << "this is not an image";
    }
    for (const char* name : {"truncated.png", "zero.png", "garbage.png", "missing.png"}) {
        SCOPED_TRACE(name);
        auto d = decode_image(dir / name);
        ASSERT_FALSE(d.ok());
        EXPECT_NE(d.error().message.find((dir / name).string()), std::string::npos) << d.error().message;
        EXPECT_EQ(d.error().message.find('\n'), std::string::npos);
    }
    auto folder = decode_image(dir);
    ASSERT_FALSE(folder.ok());
    EXPECT_NE(folder.error().message.find("folder"), std::string::npos);
    fs::remove_all(dir);
}

}  // namespace
}  // namespace specbake::io
