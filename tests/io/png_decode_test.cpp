// decode_plain_png() against OpenImageIO (libpng) on PNGs written here with every row filter, every plain
// colour type and both bit depths; files it must leave to OpenImageIO (palette, interlaced, gAMA, bad CRC).
#include "io/image/png_decode.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace specbake::io {
namespace {

void put32(std::vector<uint8_t>& out, uint32_t v) {
    for (int s = 24; s >= 0; s -= 8) out.push_back(uint8_t(v >> s));
}

void chunk(std::vector<uint8_t>& out, const char* type, const std::vector<uint8_t>& data) {
    put32(out, uint32_t(data.size()));
    std::vector<uint8_t> body(type, type + 4);
    body.insert(body.end(), data.begin(), data.end());
    out.insert(out.end(), body.begin(), body.end());
    put32(out, uint32_t(crc32(0L, body.data(), uInt(body.size()))));
}

int paeth(int a, int b, int c) {
    const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
    return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

// A PNG of random samples; row y uses filter y % 5 (the encoder side of PNG spec Sec. 9).
// `level`, `strategy`: zlib's (stored, fixed or dynamic Huffman blocks, RLE); `noise` bits of noise on a
// ramp (8: random bytes); `trailing` bytes after the zlib stream.
std::vector<uint8_t> make_png(int w, int h, int colour, int depth, uint32_t seed, const char* extra_chunk = nullptr,
                              int interlace = 0, int level = Z_DEFAULT_COMPRESSION, int strategy = Z_DEFAULT_STRATEGY,
                              int noise = 8, size_t trailing = 0) {
    const int channels = colour == 0 ? 1 : colour == 4 ? 2 : colour == 2 ? 3 : colour == 6 ? 4 : 1;
    const size_t bpp = size_t(channels * depth / 8), stride = size_t(w) * bpp;
    std::mt19937 rng(seed);
    std::vector<std::vector<uint8_t>> rows(size_t(h), std::vector<uint8_t>(stride, 0));
    for (auto& r : rows)
        for (size_t i = 0; i < r.size(); ++i) r[i] = uint8_t((noise >= 8 ? 0 : i / 5) + (rng() >> (32 - noise)));
    std::vector<uint8_t> raw;
    for (size_t y = 0; y < size_t(h); ++y) {
        const int filter = int(y % 5);
        raw.push_back(uint8_t(filter));
        for (size_t i = 0; i < stride; ++i) {
            const int x = rows[y][i];
            const int a = i >= bpp ? rows[y][i - bpp] : 0, b = y ? rows[y - 1][i] : 0;
            const int c = y && i >= bpp ? rows[y - 1][i - bpp] : 0;
            const int pred = filter == 0 ? 0 : filter == 1 ? a : filter == 2 ? b : filter == 3 ? (a + b) / 2 : paeth(a, b, c);
            raw.push_back(uint8_t(x - pred));
        }
    }
    std::vector<uint8_t> z(compressBound(uLong(raw.size())) + trailing);
    z_stream zs{};
    EXPECT_EQ(deflateInit2(&zs, level, Z_DEFLATED, 15, 8, strategy), Z_OK);
    zs.next_in = raw.data(), zs.avail_in = uInt(raw.size());
    zs.next_out = z.data(), zs.avail_out = uInt(z.size());
    EXPECT_EQ(deflate(&zs, Z_FINISH), Z_STREAM_END);
    z.resize(zs.total_out);
    deflateEnd(&zs);
    for (size_t k = 0; k < trailing; ++k) z.push_back(uint8_t(k * 37));
    std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    std::vector<uint8_t> ihdr;
    put32(ihdr, uint32_t(w));
    put32(ihdr, uint32_t(h));
    ihdr.insert(ihdr.end(), {uint8_t(depth), uint8_t(colour), 0, 0, uint8_t(interlace)});
    chunk(png, "IHDR", ihdr);
    chunk(png, "tEXt", {'C', 'o', 'm', 'm', 'e', 'n', 't', 0, 'x'});
    if (extra_chunk && std::string(extra_chunk) == "gAMA") chunk(png, "gAMA", {0, 0, 0xB1, 0x8F});
    if (colour == 3) {
        std::vector<uint8_t> palette;
        for (int i = 0; i < 256; ++i) palette.insert(palette.end(), {uint8_t(i), uint8_t(255 - i), uint8_t(i / 2)});
        chunk(png, "PLTE", palette);
    }
    // Split into two IDAT chunks: decoders must concatenate them.
    const size_t half = z.size() / 2;
    chunk(png, "IDAT", std::vector<uint8_t>(z.begin(), z.begin() + long(half)));
    chunk(png, "IDAT", std::vector<uint8_t>(z.begin() + long(half), z.end()));
    chunk(png, "IEND", {});
    return png;
}

// OpenImageIO's decode of the bytes, configured as specbake's image module reads data maps.
std::vector<float> oiio_decode(std::vector<uint8_t>& png, int& channels, std::string& colour_space) {
    OIIO::Filesystem::IOMemReader reader(png.data(), png.size());
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    void* proxy = &reader;
    config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
    auto in = OIIO::ImageInput::open("image.png", &config);
    if (!in) return {};
    const OIIO::ImageSpec& s = in->spec();
    channels = s.nchannels;
    colour_space = s.get_string_attribute("oiio:ColorSpace");
    std::vector<float> px(size_t(s.width) * size_t(s.height) * size_t(s.nchannels));
    if (!in->read_image(0, 0, 0, s.nchannels, OIIO::TypeDesc::FLOAT, px.data())) return {};
    return px;
}

TEST(PlainPng, SameValuesAndFactsAsOpenImageIO) {
    for (int colour : {0, 4, 2, 6}) {
        for (int depth : {8, 16}) {
            SCOPED_TRACE("colour type " + std::to_string(colour) + ", " + std::to_string(depth) + " bits");
            std::vector<uint8_t> png = make_png(37, 23, colour, depth, uint32_t(colour * 100 + depth));
            auto mine = decode_plain_png(png);
            ASSERT_TRUE(mine.has_value());
            int channels = 0;
            std::string colour_space;
            const std::vector<float> ref = oiio_decode(png, channels, colour_space);
            ASSERT_EQ(mine->image.width, 37);
            ASSERT_EQ(mine->image.height, 23);
            ASSERT_EQ(mine->image.channels, channels);
            ASSERT_EQ(mine->image.pixels.size(), ref.size());
            EXPECT_EQ(std::memcmp(mine->image.pixels.data(), ref.data(), ref.size() * sizeof(float)), 0)
                << "the float bits differ from OpenImageIO's";
            EXPECT_EQ(mine->info.color_space, colour_space);
            EXPECT_EQ(mine->info.bits_per_channel, depth);
            EXPECT_FALSE(mine->info.is_float);
            EXPECT_EQ(mine->info.format, "png");
        }
    }
}

// The inflate takes every kind of deflate block zlib writes (stored, fixed and dynamic Huffman, RLE matches)
// on larger, compressible rows, and ignores bytes after the stream's end as zlib's uncompress() did: the
// texels are OpenImageIO's (libpng's inflate), bit for bit. A stream cut short is refused.
TEST(PlainPng, EveryDeflateBlockKindInflatesAsOpenImageIOReadsIt) {
    struct Case { int level, strategy, noise; size_t trailing; };
    for (const Case c : {Case{0, Z_DEFAULT_STRATEGY, 8, 0}, Case{1, Z_DEFAULT_STRATEGY, 2, 0}, Case{9, Z_FIXED, 3, 0},
                         Case{6, Z_RLE, 1, 0}, Case{6, Z_HUFFMAN_ONLY, 4, 0}, Case{9, Z_DEFAULT_STRATEGY, 0, 0},
                         Case{6, Z_DEFAULT_STRATEGY, 3, 5}}) {
        for (int depth : {8, 16}) {
            SCOPED_TRACE("zlib level " + std::to_string(c.level) + ", strategy " + std::to_string(c.strategy) +
                         ", noise bits " + std::to_string(c.noise) + ", " + std::to_string(depth) + " bits");
            std::vector<uint8_t> png = make_png(301, 170, 6, depth, uint32_t(c.level * 10 + depth), nullptr, 0, c.level,
                                                c.strategy, c.noise, c.trailing);
            auto mine = decode_plain_png(png);
            ASSERT_TRUE(mine.has_value());
            int channels = 0;
            std::string colour_space;
            const std::vector<float> ref = oiio_decode(png, channels, colour_space);
            ASSERT_EQ(mine->image.pixels.size(), ref.size());
            EXPECT_EQ(std::memcmp(mine->image.pixels.data(), ref.data(), ref.size() * sizeof(float)), 0)
                << "the float bits differ from OpenImageIO's";
        }
    }
    // The stream without its last 9 bytes (adler32 and the end of the data), its IDAT's CRC made right.
    std::vector<uint8_t> png = make_png(64, 64, 2, 8, 5, nullptr, 0, 6, Z_DEFAULT_STRATEGY, 3);
    const size_t iend = png.size() - 12, crc_at = iend - 4;
    size_t idat = 8;  // the last IDAT chunk's start
    for (size_t at = 8; at < iend;) {
        const uint32_t length = uint32_t(png[at]) << 24 | uint32_t(png[at + 1]) << 16 | uint32_t(png[at + 2]) << 8 | png[at + 3];
        idat = at;
        at += length + 12;
    }
    std::vector<uint8_t> body(png.begin() + long(idat) + 4, png.begin() + long(crc_at) - 9);
    std::vector<uint8_t> cut(png.begin(), png.begin() + long(idat));
    chunk(cut, "IDAT", std::vector<uint8_t>(body.begin() + 4, body.end()));
    cut.insert(cut.end(), png.begin() + long(iend), png.end());
    EXPECT_FALSE(decode_plain_png(cut).has_value()) << "a stream cut short";
}

TEST(PlainPng, IntegerTexelsStandForOpenImageIOsFloats) {
    for (int depth : {8, 16}) {
        for (int colour : {0, 4, 2, 6}) {
            SCOPED_TRACE("colour type " + std::to_string(colour) + ", " + std::to_string(depth) + " bits");
            std::vector<uint8_t> png = make_png(37, 23, colour, depth, uint32_t(colour * 7 + depth));
            auto mine = decode_plain_png(png, true);
            ASSERT_TRUE(mine.has_value());
            EXPECT_TRUE(mine->image.pixels.empty());
            int channels = 0;
            std::string colour_space;
            const std::vector<float> ref = oiio_decode(png, channels, colour_space);
            const IntegerTexels& t = mine->integers;
            ASSERT_EQ(t.bits, depth);
            ASSERT_EQ(t.width, 37);
            ASSERT_EQ(t.height, 23);
            ASSERT_EQ(t.channels, channels);
            ASSERT_GE(depth == 8 ? t.bytes.size() : t.words.size(), t.offset + 22 * t.row_stride + 37 * size_t(channels));
            EXPECT_TRUE(depth == 8 ? t.words.empty() : t.bytes.empty());
            const float scale = depth == 8 ? 1.0f / 255.0f : 1.0f / 65535.0f;
            bool same = true;
            for (int y = 0; y < 23; ++y)
                for (size_t i = 0; i < 37 * size_t(channels); ++i) {
                    const size_t at = t.offset + size_t(y) * t.row_stride + i;
                    const float v = float(depth == 8 ? t.bytes[at] : t.words[at]) * scale;
                    same = same && v == ref[size_t(y) * 37 * size_t(channels) + i];
                }
            EXPECT_TRUE(same) << "an integer does not stand for OpenImageIO's float";
            EXPECT_EQ(mine->info.bits_per_channel, depth);
            EXPECT_EQ(mine->info.color_space, colour_space);
        }
    }
}

// 16-bit samples are big-endian (PNG spec Sec. 7.1): a hand-made 3 x 2 gray file of known values, one row
// stored plain (filter 0) and one with filter Sub, whose sums carry from the low byte into the high one.
TEST(PlainPng, SixteenBitValuesAreBigEndianSamples) {
    const std::vector<uint16_t> values = {0x0000, 0x0102, 0xFFFF, 0x00FF, 0x0100, 0x8001};
    std::vector<uint8_t> raw = {0, 0x00, 0x00, 0x01, 0x02, 0xFF, 0xFF};
    // Row 1 with Sub: each byte minus the byte two before it (one sample back), modulo 256.
    const uint8_t row1[6] = {0x00, 0xFF, 0x01, 0x00, 0x80, 0x01};
    raw.push_back(1);
    for (int i = 0; i < 6; ++i) raw.push_back(uint8_t(row1[i] - (i >= 2 ? row1[i - 2] : 0)));
    std::vector<uint8_t> z(compressBound(uLong(raw.size())));
    uLongf size = z.size();
    ASSERT_EQ(compress(z.data(), &size, raw.data(), uLong(raw.size())), Z_OK);
    z.resize(size);
    std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    std::vector<uint8_t> ihdr;
    put32(ihdr, 3);
    put32(ihdr, 2);
    ihdr.insert(ihdr.end(), {16, 0, 0, 0, 0});
    chunk(png, "IHDR", ihdr);
    chunk(png, "IDAT", z);
    chunk(png, "IEND", {});
    auto kept = decode_plain_png(png, true);
    ASSERT_TRUE(kept.has_value());
    ASSERT_EQ(kept->integers.bits, 16);
    ASSERT_EQ(kept->integers.row_stride, 3u);
    EXPECT_EQ(std::vector<uint16_t>(kept->integers.words.begin(), kept->integers.words.begin() + 6), values);
    int channels = 0;
    std::string colour_space;
    const std::vector<float> ref = oiio_decode(png, channels, colour_space);
    ASSERT_EQ(ref.size(), 6u);
    auto floats = decode_plain_png(png);
    ASSERT_TRUE(floats.has_value());
    EXPECT_EQ(floats->image.pixels, ref);
    for (size_t i = 0; i < 6; ++i) {
        EXPECT_NEAR(ref[i], values[i] / 65535.0, 1e-7) << "sample " << i;
        EXPECT_EQ(float(values[i]) * (1.0f / 65535.0f), ref[i]) << "sample " << i;
    }
}

TEST(PlainPng, EverythingElseIsLeftToOpenImageIO) {
    EXPECT_FALSE(decode_plain_png(make_png(8, 8, 3, 8, 1)).has_value()) << "palette";
    EXPECT_FALSE(decode_plain_png(make_png(8, 8, 2, 8, 2, "gAMA")).has_value()) << "gAMA changes the colour space";
    EXPECT_FALSE(decode_plain_png(make_png(8, 8, 2, 8, 3, nullptr, 1)).has_value()) << "interlaced";
    std::vector<uint8_t> bad_crc = make_png(8, 8, 2, 8, 4);
    bad_crc[bad_crc.size() - 20] ^= 0x40;  // inside the last IDAT
    EXPECT_FALSE(decode_plain_png(bad_crc).has_value());
    std::vector<uint8_t> truncated = make_png(8, 8, 2, 8, 5);
    truncated.resize(truncated.size() - 30);
    EXPECT_FALSE(decode_plain_png(truncated).has_value());
    const std::vector<uint8_t> not_png = {'G', 'I', 'F', '8', '9', 'a', 0, 0, 0, 0, 0, 0};
    EXPECT_FALSE(decode_plain_png(not_png).has_value());
    // The public decoder still reads those through OpenImageIO.
    std::vector<uint8_t> palette = make_png(8, 8, 3, 8, 6);
    auto decoded = decode_image_memory(palette, "palette.png");
    ASSERT_TRUE(decoded.ok()) << decoded.error().message;
    EXPECT_EQ(decoded->image.channels, 3);
}

}  // namespace
}  // namespace specbake::io
