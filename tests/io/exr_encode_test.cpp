// The EXR encoder (io/image/exr_encode.h) checked by readers that share none of its code: OpenImageIO
// (through OpenEXR) reads every level of scanline and tiled mipmapped files back bit for bit, and tinyexr
// (its own ZIP decoder, Debian's libtinyexr1d, loaded when installed) reads level 0.
#include "io/image/exr_encode.h"
#include "tests/io/temp_folder.h"

#include <Imath/half.h>
#include <OpenImageIO/imageio.h>
#include <dlfcn.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

namespace specbake::io {
namespace {
namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
    return specbake::testing::fresh_test_folder("exr_encode", name);
}

void write_pieces(const fs::path& path, const std::vector<std::span<const uint8_t>>& pieces) {
    std::ofstream f(path, std::ios::binary);
    for (std::span<const uint8_t> p : pieces) f.write(reinterpret_cast<const char*>(p.data()), std::streamsize(p.size()));
}

std::vector<std::string> names_of(int channels) {
    if (channels == 1) return {"Y"};
    static const char* rgba[] = {"R", "G", "B", "A"};
    return {rgba, rgba + channels};
}

// `count` half or float samples as little-endian bytes: mostly a ramp that deflate shrinks (so chunks are
// stored compressed, not raw), one in eight random finite bits (no Inf or NaN, which compare unequal; signs,
// zeros and denormals included).
std::vector<uint8_t> random_samples(size_t count, ExrSample sample, std::mt19937& rng) {
    std::vector<uint8_t> bytes;
    for (size_t k = 0; k < count; ++k) {
        const bool noise = rng() % 8 == 0;
        const float ramp = float(k / 7 % 61) * 0.5f - 7.0f;
        if (sample == ExrSample::Half) {
            uint16_t v = noise ? uint16_t(rng()) : Imath::half(ramp).bits();
            if ((v >> 10 & 0x1f) == 0x1f) v &= 0xbfff;
            bytes.push_back(uint8_t(v)), bytes.push_back(uint8_t(v >> 8));
        } else {
            uint32_t v;
            std::memcpy(&v, &ramp, 4);
            if (noise) v = uint32_t(rng());
            if ((v >> 23 & 0xff) == 0xff) v &= 0xbfffffff;
            for (int b = 0; b < 4; ++b) bytes.push_back(uint8_t(v >> (8 * b)));
        }
    }
    return bytes;
}

float sample_value(const uint8_t* p, ExrSample sample) {
    if (sample == ExrSample::Half) {
        uint16_t bits;
        std::memcpy(&bits, p, 2);
        Imath::half h;
        h.setBits(bits);
        return float(h);
    }
    float v;
    std::memcpy(&v, p, 4);
    return v;
}

struct Written {
    std::vector<std::vector<uint8_t>> levels;  // the texels given, interleaved in names_of order
    fs::path path;
};

// Writes a random `width` x `height` image of `channels` channels (tile side 0: scanline), its rows given in
// random bands and its levels fed in reverse order (nothing depends on level 0 coming first).
Written write_random(const fs::path& dir, int width, int height, int channels, ExrSample sample, int tile_side,
                     std::mt19937& rng) {
    ExrImageDesc desc;
    desc.width = width, desc.height = height, desc.tile_side = tile_side, desc.sample = sample;
    desc.channel_names = names_of(channels);
    desc.levels = 1;
    if (tile_side)
        for (int m = std::max(width, height); m > 1; m >>= 1) ++desc.levels;
    auto encoder = ExrEncoder::create(desc, 4);
    EXPECT_TRUE(encoder.ok()) << encoder.error().message;
    Written w;
    for (int L = 0; L < desc.levels; ++L) {
        const size_t texels = size_t(std::max(1, width >> L)) * size_t(std::max(1, height >> L));
        w.levels.push_back(random_samples(texels * size_t(channels), sample, rng));
    }
    for (int L = desc.levels; L-- > 0;) {
        const int h = std::max(1, height >> L);
        const int chunk = tile_side ? tile_side : 16;
        for (int rows = 0; rows < h;) {
            rows = std::min(h, rows + 1 + int(rng() % 40));
            EXPECT_TRUE(encoder->add_rows(L, w.levels[size_t(L)].data(), rows).ok());
            const int done = encoder->rows_done(L);
            EXPECT_TRUE(done == h || (done % chunk == 0 && done <= rows && rows - done < chunk)) << done << " of " << rows;
        }
    }
    std::vector<std::pair<std::string, std::string>> strings{{"Software", "specbake"},
                                                             {"capDate", "1970:01:01 00:00:00"},
                                                             {"specbake:channels", "a,b,c,d"}};
    if (tile_side) strings.emplace_back("wrapmodes", "clamp,clamp");
    auto file = encoder->file(strings);
    EXPECT_TRUE(file.ok()) << file.error().message;
    w.path = dir / ("t_" + std::to_string(width) + "x" + std::to_string(height) + "_" + std::to_string(channels) +
                    (sample == ExrSample::Half ? "h" : "f") + (tile_side ? "_tiled" : "") + ".exr");
    if (file) write_pieces(w.path, *file);
    // Large enough to shrink: the chunks went through the predictor and deflate (small ones may be stored raw).
    size_t raw = 0;
    for (const std::vector<uint8_t>& level : w.levels) raw += level.size();
    if (width * height >= 1000) EXPECT_LT(fs::file_size(w.path), raw * 3 / 4);
    return w;
}

struct Case { int width, height, channels; ExrSample sample; int tile_side; };

std::vector<Case> round_trip_cases() {
    std::vector<Case> cases;
    for (const int tile : {0, 64})
        for (const ExrSample sample : {ExrSample::Half, ExrSample::Float})
            for (const auto& [w, h] : std::vector<std::pair<int, int>>{{200, 300}, {1, 1}, {17, 5}, {130, 64}})
                for (int c = 1; c <= 4; ++c) cases.push_back({w, h, c, sample, tile});
    cases.push_back({300, 17, 4, ExrSample::Half, 16});  // several tiles a row, each level's last ones short
    return cases;
}

std::string label(const Case& c) {
    return std::to_string(c.width) + "x" + std::to_string(c.height) + ", " + std::to_string(c.channels) + " channels, " +
           (c.sample == ExrSample::Half ? "half" : "float") + (c.tile_side ? ", tiled " + std::to_string(c.tile_side) : ", scanline");
}

// Every level of every case read back by OpenImageIO bit for bit, with the header the layout asks for.
TEST(ExrEncode, ReadsBackBitForBitThroughOpenImageIO) {
    const fs::path dir = fresh_dir("oiio");
    std::mt19937 rng(38);
    for (const Case& c : round_trip_cases()) {
        SCOPED_TRACE(label(c));
        const Written w = write_random(dir, c.width, c.height, c.channels, c.sample, c.tile_side, rng);
        auto in = OIIO::ImageInput::open(w.path.string());
        ASSERT_TRUE(in) << OIIO::geterror();
        const std::vector<std::string> names = names_of(c.channels);
        const size_t sample_bytes = c.sample == ExrSample::Half ? 2 : 4;
        const OIIO::TypeDesc type = c.sample == ExrSample::Half ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT;
        int levels = 0;
        for (int L = 0; in->seek_subimage(0, L); ++L, ++levels) {
            const OIIO::ImageSpec& spec = in->spec();
            ASSERT_LT(size_t(L), w.levels.size());
            EXPECT_EQ(spec.width, std::max(1, c.width >> L));
            EXPECT_EQ(spec.height, std::max(1, c.height >> L));
            EXPECT_EQ(spec.full_width, spec.width);
            EXPECT_EQ(spec.nchannels, c.channels);
            EXPECT_EQ(spec.format, type);
            EXPECT_EQ(spec.tile_width, c.tile_side);
            EXPECT_EQ(spec.tile_height, c.tile_side);
            EXPECT_EQ(spec.get_string_attribute("compression"), "zip");
            EXPECT_EQ(spec.get_string_attribute("Software"), "specbake");
            EXPECT_EQ(spec.get_string_attribute("DateTime"), "1970:01:01 00:00:00");
            EXPECT_EQ(spec.get_string_attribute("specbake:channels"), "a,b,c,d");
            EXPECT_EQ(spec.get_string_attribute("wrapmodes"), c.tile_side ? "clamp,clamp" : "");
            if (c.tile_side) EXPECT_EQ(spec.get_int_attribute("openexr:roundingmode", -1), 0);
            std::vector<uint8_t> got(size_t(spec.width) * size_t(spec.height) * size_t(c.channels) * sample_bytes);
            ASSERT_TRUE(in->read_image(0, L, 0, c.channels, type, got.data())) << in->geterror();
            // OpenImageIO lists EXR channels in its own order; compare each by name.
            const std::vector<uint8_t>& want = w.levels[size_t(L)];
            for (int ch = 0; ch < c.channels; ++ch) {
                const auto at = std::find(spec.channelnames.begin(), spec.channelnames.end(), names[size_t(ch)]);
                ASSERT_NE(at, spec.channelnames.end()) << names[size_t(ch)];
                const size_t column = size_t(at - spec.channelnames.begin());
                for (size_t i = 0; i < size_t(spec.width) * size_t(spec.height); ++i)
                    ASSERT_EQ(std::memcmp(&got[(i * size_t(c.channels) + column) * sample_bytes],
                                          &want[(i * size_t(c.channels) + size_t(ch)) * sample_bytes], sample_bytes), 0)
                        << "level " << L << " texel " << i << " channel " << names[size_t(ch)];
            }
        }
        EXPECT_EQ(levels, int(w.levels.size()));
    }
    fs::remove_all(dir);
}

// tinyexr's LoadEXR: level 0 as RGBA float (one channel spread over all four; A = 1 when absent). It needs
// R, G and B, so two-channel files are left to OpenImageIO.
TEST(ExrEncode, Level0ReadsBackThroughTinyexr) {
    void* lib = dlopen("libtinyexr.so.1d", RTLD_NOW | RTLD_LOCAL);
    if (!lib) GTEST_SKIP() << "tinyexr (Debian libtinyexr1d) is not installed: " << dlerror();
    using LoadExr = int (*)(float**, int*, int*, const char*, const char**);
    using FreeMessage = void (*)(const char*);
    const auto load = reinterpret_cast<LoadExr>(dlsym(lib, "LoadEXR"));
    const auto free_message = reinterpret_cast<FreeMessage>(dlsym(lib, "FreeEXRErrorMessage"));
    ASSERT_TRUE(load && free_message);
    const fs::path dir = fresh_dir("tinyexr");
    std::mt19937 rng(39);
    int files = 0;
    for (const Case& c : round_trip_cases()) {
        if (c.channels == 2) continue;
        SCOPED_TRACE(label(c));
        const Written w = write_random(dir, c.width, c.height, c.channels, c.sample, c.tile_side, rng);
        float* rgba = nullptr;
        int width = 0, height = 0;
        const char* error = nullptr;
        const int status = load(&rgba, &width, &height, w.path.string().c_str(), &error);
        const std::string message = error ? error : "";
        if (error) free_message(error);
        ASSERT_EQ(status, 0) << message;
        ++files;
        EXPECT_EQ(width, c.width);
        EXPECT_EQ(height, c.height);
        const size_t sample_bytes = c.sample == ExrSample::Half ? 2 : 4;
        const std::vector<uint8_t>& want = w.levels[0];
        for (size_t i = 0; i < size_t(width) * size_t(height); ++i)
            for (int k = 0; k < 4; ++k) {
                const int ch = c.channels == 1 ? 0 : k;
                const float expected = ch < c.channels
                                           ? sample_value(&want[(i * size_t(c.channels) + size_t(ch)) * sample_bytes], c.sample)
                                           : 1.0f;
                ASSERT_EQ(std::memcmp(&rgba[i * 4 + size_t(k)], &expected, 4), 0)
                    << "texel " << i << " channel " << k << ": " << rgba[i * 4 + size_t(k)] << " != " << expected;
            }
        std::free(rgba);
    }
    EXPECT_GT(files, 0);
    dlclose(lib);
    fs::remove_all(dir);
}

// The ZIP transform on bytes worked out by hand from its definition.
TEST(ExrEncode, ZipPredictorMatchesTheDefinition) {
    const uint8_t raw[] = {10, 20, 30, 40, 50};
    // Even-indexed 10, 30, 50, then odd-indexed 20, 40; then differences + 128 mod 256.
    const uint8_t want[] = {10, 148, 148, 98, 148};
    uint8_t out[5];
    exr_zip_predict(raw, 5, out);
    EXPECT_EQ(std::vector<uint8_t>(out, out + 5), std::vector<uint8_t>(want, want + 5));
    const uint8_t wrap[] = {200, 0, 10};  // 10 - 200 + 128 = -62 = 194 (mod 256); 0 - 10 + 128 = 118
    exr_zip_predict(wrap, 3, out);
    EXPECT_EQ(out[0], 200);
    EXPECT_EQ(out[1], 194);
    EXPECT_EQ(out[2], 118);
}

// Every length from 0 to 300 (the vector and scalar paths, odd and even counts) against the two steps as
// OpenEXR's Zip::compress writes them: interleave into a buffer, then difference it in place front to back.
TEST(ExrEncode, ZipPredictorMatchesOpenExrsTwoSteps) {
    std::mt19937 rng(40);
    for (size_t n = 0; n <= 300; ++n) {
        std::vector<uint8_t> raw(n), want(n), got(n + 1, 0xee);
        for (uint8_t& b : raw) b = uint8_t(rng());
        uint8_t* t1 = want.data();
        uint8_t* t2 = want.data() + (n + 1) / 2;
        for (size_t k = 0; k < n;) {
            *t1++ = raw[k++];
            if (k < n) *t2++ = raw[k++];
        }
        for (size_t k = 1, previous = n ? want[0] : 0; k < n; ++k) {
            const int d = int(want[k]) - int(previous) + (128 + 256);
            previous = want[k];
            want[k] = uint8_t(d);
        }
        exr_zip_predict(raw.data(), n, got.data());
        EXPECT_EQ(std::vector<uint8_t>(got.begin(), got.begin() + long(n)), want) << n << " bytes";
        EXPECT_EQ(got[n], 0xee) << n << " bytes: wrote past the end";
    }
}

TEST(ExrEncode, RefusesWhatOpenExrCannotHold) {
    ExrImageDesc desc;
    desc.width = 8, desc.height = 4, desc.channel_names = {"R", "G"};
    desc.tile_side = 64, desc.levels = 3;  // 8x4 has 4 ROUND_DOWN levels: 8x4, 4x2, 2x1, 1x1
    auto e = ExrEncoder::create(desc, 4);
    ASSERT_FALSE(e.ok());
    EXPECT_NE(e.error().message.find("4 levels"), std::string::npos) << e.error().message;
    desc.levels = 4;
    desc.channel_names = {"R", "R"};
    EXPECT_FALSE(ExrEncoder::create(desc, 4).ok());
    desc.channel_names = {"R"};
    EXPECT_FALSE(ExrEncoder::create(desc, 0).ok());
    desc.width = 0;
    EXPECT_FALSE(ExrEncoder::create(desc, 4).ok());
    desc.width = 8;
    auto ok = ExrEncoder::create(desc, 4);
    ASSERT_TRUE(ok.ok());
    const std::vector<uint8_t> texels(8 * 4 * 2, 0);
    ASSERT_TRUE(ok->add_rows(0, texels.data(), 4).ok());
    auto early = ok->file({});
    ASSERT_FALSE(early.ok());  // levels 1..3 not given
    EXPECT_NE(early.error().message.find("level 1"), std::string::npos) << early.error().message;
    for (int L = 1; L < 4; ++L) ASSERT_TRUE(ok->add_rows(L, texels.data(), 4).ok());
    EXPECT_FALSE(ok->file({{"tiles", "x"}}).ok());  // a name the layout writes
    EXPECT_TRUE(ok->file({{"note", "x"}}).ok());
}

}  // namespace
}  // namespace specbake::io
