// `specbake inspect` on files this test writes byte by byte from the KTX 2.0 / DDS specifications, so
// neither the reader nor the statistics are checked against code that shares their assumptions.
#include "pipeline/inspect.h"
#include "io/texture/container_inspect.h"
#include "io/texture/texture_writer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace specbake;

namespace {

struct Bytes {
    std::vector<uint8_t> b;
    void u8(uint8_t v) { b.push_back(v); }
    void u16(uint16_t v) { u8(uint8_t(v)), u8(uint8_t(v >> 8)); }
    void u32(uint32_t v) { u16(uint16_t(v)), u16(uint16_t(v >> 16)); }
    void u64(uint64_t v) { u32(uint32_t(v)), u32(uint32_t(v >> 32)); }
    void f32(float v) {
        uint32_t u;
        std::memcpy(&u, &v, 4);
        u32(u);
    }
    void pad_to(size_t n) { b.resize(std::max(b.size(), n), 0); }
    void put32(size_t at, uint32_t v) {
        for (int i = 0; i < 4; ++i) b[at + i] = uint8_t(v >> (8 * i));
    }
    void put64(size_t at, uint64_t v) { put32(at, uint32_t(v)), put32(at + 4, uint32_t(v >> 32)); }
};

// A KTX2 file of 32-bit float texels, `channels` channels, levels[L] the texel values of level L
// (level L is max(1, w >> L) x max(1, h >> L)). Layout: header, level index, DFD, then the level data
// smallest level first, each aligned to lcm(texel size, 4) (KTX 2.0 Sec. 3).
// `layers` > 0 makes it a 2D array (layerCount): each level then holds its layers one after another.
std::vector<uint8_t> make_ktx2_f32(uint32_t w, uint32_t h, int channels, const std::vector<std::vector<float>>& levels,
                                   uint32_t layers = 0) {
    static const uint32_t vk[] = {100, 103, 106, 109};  // R32_SFLOAT .. R32G32B32A32_SFLOAT
    Bytes f;
    const uint8_t id[12] = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n'};
    for (uint8_t c : id) f.u8(c);
    f.u32(vk[channels - 1]);
    f.u32(4);  // typeSize
    f.u32(w);
    f.u32(h);
    f.u32(0);  // depth
    f.u32(layers);
    f.u32(1);  // faces
    f.u32(uint32_t(levels.size()));
    f.u32(0);  // supercompression
    const uint32_t dfd_offset = 80 + 24 * uint32_t(levels.size());
    const uint32_t dfd_length = 4 + 24 + 16 * uint32_t(channels);
    f.u32(dfd_offset);
    f.u32(dfd_length);
    f.u32(0), f.u32(0);  // kvd
    f.u64(0), f.u64(0);  // sgd
    const size_t level_index = f.b.size();
    f.pad_to(dfd_offset);
    f.u32(dfd_length);                               // dfdTotalSize
    f.u32(0);                                        // vendorId 0, descriptorType 0
    f.u32(2u | (24u + 16u * uint32_t(channels)) << 16);  // version 2, block size
    f.u8(1), f.u8(1), f.u8(1), f.u8(0);              // RGBSDA, BT.709, linear, straight alpha
    f.u32(0);                                        // texel block 1x1x1x1
    f.u32(uint32_t(4 * channels)), f.u32(0);         // bytesPlane0..7
    for (int c = 0; c < channels; ++c) {
        f.u16(uint16_t(32 * c));
        f.u8(31);
        f.u8(uint8_t((c == 3 ? 15 : c) | 0x80 | 0x40));  // float, signed
        f.u32(0);
        f.f32(-1.0f);
        f.f32(1.0f);
    }
    for (size_t L = levels.size(); L-- > 0;) {
        const size_t align = std::lcm(size_t(4 * channels), size_t(4));
        f.pad_to((f.b.size() + align - 1) / align * align);
        const size_t offset = f.b.size();
        for (float v : levels[L]) f.f32(v);
        f.put64(level_index + 24 * L, offset);
        f.put64(level_index + 24 * L + 8, levels[L].size() * 4);
        f.put64(level_index + 24 * L + 16, levels[L].size() * 4);
    }
    return f.b;
}

// A DDS file with the DX10 header, R8_UNORM, mips largest first.
std::vector<uint8_t> make_dds_r8(uint32_t w, uint32_t h, const std::vector<std::vector<uint8_t>>& levels) {
    Bytes f;
    f.u8('D'), f.u8('D'), f.u8('S'), f.u8(' ');
    f.u32(124);
    f.u32(0x1 | 0x2 | 0x4 | 0x1000 | 0x20000);  // CAPS HEIGHT WIDTH PIXELFORMAT MIPMAPCOUNT
    f.u32(h);
    f.u32(w);
    f.u32(w);  // pitch
    f.u32(0);  // depth
    f.u32(uint32_t(levels.size()));
    for (int i = 0; i < 11; ++i) f.u32(0);
    f.u32(32);
    f.u32(0x4);  // DDPF_FOURCC
    f.u8('D'), f.u8('X'), f.u8('1'), f.u8('0');
    for (int i = 0; i < 5; ++i) f.u32(0);
    f.u32(0x1000 | 0x400000 | 0x8);  // TEXTURE | MIPMAP | COMPLEX
    for (int i = 0; i < 4; ++i) f.u32(0);
    f.u32(61);  // DXGI_FORMAT_R8_UNORM
    f.u32(3);   // TEXTURE2D
    f.u32(0);
    f.u32(1);
    f.u32(0);
    for (const auto& level : levels)
        for (uint8_t v : level) f.u8(v);
    return f.b;
}

class Files {
public:
    Files() : dir_(fs::temp_directory_path() / ("specbake_inspect_" + std::to_string(::getpid()))) {
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    ~Files() { fs::remove_all(dir_); }
    fs::path write(const std::string& name, const std::vector<uint8_t>& bytes) const {
        std::ofstream(dir_ / name, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), bytes.size());
        return dir_ / name;
    }
    const fs::path& dir() const { return dir_; }

private:
    fs::path dir_;
};

// 4x2 roughness, 3 levels; level 0 holds eight distinct values so every percentile rank is visible.
const std::vector<std::vector<float>> kRoughness{{0.8f, 0.1f, 0.7f, 0.2f, 0.6f, 0.3f, 0.5f, 0.4f},
                                                 {0.25f, 0.75f},
                                                 {0.5f}};

}  // namespace

TEST(InspectKtx2, DecodesLevelsWrittenByHand) {
    const auto bytes = make_ktx2_f32(4, 2, 1, kRoughness);
    ASSERT_TRUE(io::check_ktx2_structure(bytes, "r.ktx2").ok());
    auto t = io::decode_ktx2_for_inspection(bytes, "r.ktx2");
    ASSERT_TRUE(t.ok()) << t.error().message;
    EXPECT_EQ(t->pixel_format, "R32_SFLOAT");
    ASSERT_EQ(t->mips.levels.size(), 3u);
    EXPECT_EQ(t->mips.levels[1].width, 2);
    EXPECT_EQ(t->mips.levels[1].height, 1);
    EXPECT_EQ(t->mips.levels[0].pixels, kRoughness[0]);
    EXPECT_EQ(t->mips.levels[1].pixels, kRoughness[1]);
    EXPECT_EQ(t->mips.levels[2].pixels, kRoughness[2]);
}

TEST(InspectKtx2, RoughnessStatisticsPerMip) {
    Files files;
    const fs::path p = files.write("rock_roughness.ktx2", make_ktx2_f32(4, 2, 1, kRoughness));
    auto r = inspect_texture(p);
    ASSERT_TRUE(r.ok()) << r.error().message;
    EXPECT_EQ(r->kind, "roughness");
    const Quantity& q = r->quantities.front();
    EXPECT_EQ(q.name, "roughness");
    const QuantityStats& s = q.stats[0];
    // Sorted level 0: 0.1 .. 0.8. Nearest rank k = ceil(q n / 100) with n = 8: p1, p5 -> 1st; p50 -> 4th;
    // p95, p99 -> 8th.
    EXPECT_EQ(s.count, 8);
    EXPECT_FLOAT_EQ(s.min, 0.1f);
    EXPECT_FLOAT_EQ(s.max, 0.8f);
    EXPECT_NEAR(s.mean, 0.45, 1e-7);
    EXPECT_FLOAT_EQ(s.p01, 0.1f);
    EXPECT_FLOAT_EQ(s.p05, 0.1f);
    EXPECT_FLOAT_EQ(s.p50, 0.4f);
    EXPECT_FLOAT_EQ(s.p95, 0.8f);
    EXPECT_FLOAT_EQ(s.p99, 0.8f);
    // Histogram over [0.1, 0.8] shared by all levels, 16 bins of width 0.04375: 0.1 -> bin 0, 0.2 -> 2,
    // 0.3 -> 4, 0.4 -> 6, 0.5 -> 9, 0.6 -> 11, 0.7 -> 13, 0.8 -> the closed top bin 15.
    EXPECT_DOUBLE_EQ(s.hist_lo, double(0.1f));
    EXPECT_DOUBLE_EQ(s.hist_hi, double(0.8f));
    const std::vector<long long> expected{1, 0, 1, 0, 1, 0, 1, 0, 0, 1, 0, 1, 0, 1, 0, 1};
    EXPECT_EQ(s.histogram, expected);
    EXPECT_FLOAT_EQ(q.stats[1].p50, 0.25f);
    EXPECT_NEAR(q.stats[1].mean, 0.5, 1e-7);
    EXPECT_FLOAT_EQ(q.stats[2].min, 0.5f);
}

TEST(InspectKtx2, LeanVarianceFromMoments) {
    Files files;
    // Two texels of (m.x, m.y, M.xx, M.yy); tr(Sigma) = M.xx - m.x^2 + M.yy - m.y^2, each term >= 0.
    const std::vector<std::vector<float>> lean{{0.5f, -0.25f, 0.5f, 0.25f, 0.0f, 0.0f, 0.1f, 0.2f}, {}};
    std::vector<std::vector<float>> levels{lean[0], {0.25f, -0.125f, 0.3f, 0.15f}};
    const fs::path p = files.write("rock_lean.ktx2", make_ktx2_f32(2, 1, 4, levels));
    auto r = inspect_texture(p);
    ASSERT_TRUE(r.ok()) << r.error().message;
    const Quantity& q = r->quantities.front();
    EXPECT_EQ(q.name, "variance tr(Sigma)");
    ASSERT_EQ(q.levels[0].size(), 2u);
    EXPECT_NEAR(q.levels[0][0], (0.5 - 0.25) + (0.25 - 0.0625), 1e-6);
    EXPECT_NEAR(q.levels[0][1], 0.1 + 0.2, 1e-6);
    EXPECT_NEAR(q.levels[1][0], (0.3 - 0.0625) + (0.15 - 0.015625), 1e-6);
    EXPECT_NEAR(q.stats[0].mean, (0.4375 + 0.3) / 2, 1e-6);
}

TEST(InspectKtx2, LeanVarianceClampsAtZero) {
    Files files;
    // M.xx < m.x^2 happens after quantisation; Sigma is clamped to positive semi-definite.
    const fs::path p = files.write("a_lean.ktx2", make_ktx2_f32(1, 1, 4, {{0.5f, 0.5f, 0.2f, 0.3f}}));
    auto r = inspect_texture(p);
    ASSERT_TRUE(r.ok());
    EXPECT_NEAR(r->quantities.front().levels[0][0], 0.3 - 0.25, 1e-7);
}

TEST(InspectKtx2, NonFiniteValuesAreCountedNotAveraged) {
    const std::vector<float> v{1.0f, NAN, 3.0f, INFINITY};
    const QuantityStats s = compute_stats(v, 1.0, 3.0);
    EXPECT_EQ(s.count, 2);
    EXPECT_EQ(s.nonfinite, 2);
    EXPECT_DOUBLE_EQ(s.mean, 2.0);
}

TEST(InspectKtx2, CheckRejectsCorruptedFiles) {
    const auto good = make_ktx2_f32(4, 2, 1, kRoughness);
    ASSERT_TRUE(io::check_ktx2_structure(good, "g").ok());
    // Each corruption must be rejected for its own reason: `what` appears in the message.
    auto expect_rejected = [](std::vector<uint8_t> bytes, const std::string& what) {
        auto r = io::check_ktx2_structure(bytes, "bad.ktx2");
        ASSERT_FALSE(r.ok()) << what;
        EXPECT_EQ(r.error().message.rfind("bad.ktx2: KTX2: ", 0), 0u) << r.error().message;
        EXPECT_NE(r.error().message.find(what), std::string::npos) << r.error().message;
    };
    const uint64_t level0_offset = uint64_t(good[80]) | uint64_t(good[81]) << 8;
    auto truncated = good;
    truncated.resize(good.size() - 4);
    expect_rejected(truncated, "runs past the end");
    expect_rejected(std::vector<uint8_t>(good.begin(), good.begin() + 60), "truncated header");

    Bytes wrong_offset{good};
    wrong_offset.put64(80, wrong_offset.b.size() - 16);  // level 0 runs past the end
    expect_rejected(wrong_offset.b, "runs past the end");
    Bytes misaligned{good};
    misaligned.put64(80, level0_offset + 2);
    expect_rejected(misaligned.b, "not aligned");
    Bytes into_dfd{good};
    into_dfd.put64(80 + 24 * 2, 80 + 24 * 3);  // level 2 inside the DFD
    expect_rejected(into_dfd.b, "overlaps the metadata");
    Bytes swapped{good};
    swapped.put64(80, 80 + 24 * 3 + 44);  // level 0 right after the DFD, before the smaller levels
    expect_rejected(swapped.b, "smallest first");
    Bytes wrong_length{good};
    wrong_length.put64(80 + 8, 28);
    expect_rejected(wrong_length.b, "expected 32");
    Bytes too_many_levels{good};
    too_many_levels.put32(40, 4);  // a 4x2 chain has 3 levels
    expect_rejected(too_many_levels.b, "levelCount 4");
    Bytes dfd_bytes_plane{good};
    dfd_bytes_plane.b[80 + 24 * 3 + 4 + 16] = 8;
    expect_rejected(dfd_bytes_plane.b, "bytesPlane0");
    Bytes dfd_sample{good};
    dfd_sample.b[80 + 24 * 3 + 4 + 24 + 3] = 0x00;  // sample 0 no longer float
    expect_rejected(dfd_sample.b, "DFD sample 0");
    Bytes dfd_outside{good};
    dfd_outside.put32(48, uint32_t(good.size()));
    expect_rejected(dfd_outside.b, "outside the file");
    Bytes bad_magic{good};
    bad_magic.b[1] = 'X';
    expect_rejected(bad_magic.b, "bad identifier");
}

// A 2D array (the glint dictionary's container): 4x1 texels, 3 layers, 3 levels, every value distinct.
TEST(InspectKtx2, ArrayLayersLevelsAndSizes) {
    Files files;
    std::vector<std::vector<float>> levels(3);
    for (int L = 0; L < 3; ++L)
        for (int layer = 0; layer < 3; ++layer)
            for (int x = 0; x < (4 >> L); ++x) levels[size_t(L)].push_back(float(100 * L + 10 * layer + x));
    const std::vector<uint8_t> bytes = make_ktx2_f32(4, 1, 1, levels, 3);
    const fs::path path = files.write("array.ktx2", bytes);
    auto shape = io::check_container_shape(bytes, "array.ktx2");
    ASSERT_TRUE(shape.ok()) << shape.error().message;
    EXPECT_EQ(shape->layers, 3);
    EXPECT_EQ(shape->width, 4);
    EXPECT_EQ(shape->height, 1);
    EXPECT_EQ(shape->mips, 3);
    auto r = inspect_texture(path);
    ASSERT_TRUE(r.ok()) << r.error().message;
    EXPECT_EQ(r->texture.layers, 3);
    ASSERT_EQ(r->texture.mips.levels.size(), 3u);
    for (int L = 0; L < 3; ++L) {
        const Image& level = r->texture.mips.levels[size_t(L)];
        EXPECT_EQ(level.width, 4 >> L);
        EXPECT_EQ(r->texture.layer_height(size_t(L)), 1);
        for (int layer = 0; layer < 3; ++layer)
            for (int x = 0; x < (4 >> L); ++x) EXPECT_EQ(level.texel(x, layer)[0], float(100 * L + 10 * layer + x));
    }
    const nlohmann::json j = report_json(*r);
    EXPECT_EQ(j["layers"], 3);
    EXPECT_EQ(j["height"], 1);
    EXPECT_EQ(j["levels"][1]["bytes"], 2 * 3 * 4);  // 2 texels x 3 layers x 4 bytes
    const std::string text = report_text(*r, true);
    EXPECT_NE(text.find("4x1 x 3 layers (2D array), 3 mips"), std::string::npos) << text;
    EXPECT_NE(text.find("1: 2x1 (24 B)"), std::string::npos) << text;
    // A layer count that does not match the level sizes is refused, naming the level.
    std::vector<uint8_t> wrong = bytes;
    wrong[32] = 2;
    auto bad = io::check_ktx2_structure(wrong, "wrong.ktx2");
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.error().message.find("wrong.ktx2: KTX2: level 0 holds 48 bytes, expected 32"), std::string::npos)
        << bad.error().message;
    std::vector<uint8_t> cube = bytes;
    cube[36] = 6;
    EXPECT_FALSE(io::check_ktx2_structure(cube, "cube.ktx2").ok());
}

TEST(InspectDds, DecodesAndChecks) {
    const std::vector<std::vector<uint8_t>> levels{{0, 51, 102, 255, 204, 153, 10, 20}, {255, 0}, {128}};
    const auto good = make_dds_r8(4, 2, levels);
    ASSERT_TRUE(io::check_dds_structure(good, "k.dds").ok());
    auto t = io::decode_dds_for_inspection(good, "k.dds");
    ASSERT_TRUE(t.ok()) << t.error().message;
    EXPECT_EQ(t->pixel_format, "R8_UNORM");
    ASSERT_EQ(t->mips.levels.size(), 3u);
    EXPECT_FLOAT_EQ(t->mips.levels[0].pixels[1], 51.0f / 255.0f);
    EXPECT_FLOAT_EQ(t->mips.levels[1].pixels[0], 1.0f);
    EXPECT_FLOAT_EQ(t->mips.levels[2].pixels[0], 128.0f / 255.0f);

    auto truncated = good;
    truncated.pop_back();
    EXPECT_FALSE(io::check_dds_structure(truncated, "t.dds").ok());
    auto trailing = good;
    trailing.push_back(0);
    EXPECT_FALSE(io::check_dds_structure(trailing, "t.dds").ok());
    Bytes header_size{good};
    header_size.put32(4, 120);
    EXPECT_FALSE(io::check_dds_structure(header_size.b, "t.dds").ok());
    Bytes no_dx10{good};
    no_dx10.b[84] = 'D', no_dx10.b[85] = 'X', no_dx10.b[86] = 'T', no_dx10.b[87] = '5';
    EXPECT_FALSE(io::check_dds_structure(no_dx10.b, "t.dds").ok());
    Bytes mips{good};
    mips.put32(28, 5);
    EXPECT_FALSE(io::check_dds_structure(mips.b, "t.dds").ok());
}

// Level counts from hostile headers (found by fuzz/fuzz_container.cpp): a count of 0xFFFFFFFF is
// refused by the count check, where it once turned negative (DDS: the size check then walked four
// billion levels for seconds; KTX2: the level index was reported truncated instead).
TEST(InspectHostile, LevelCountOfAllOnesIsRefusedAsExceedingTheChain) {
    Bytes dds{make_dds_r8(4, 2, {{0, 51, 102, 255, 204, 153, 10, 20}, {255, 0}, {128}})};
    dds.put32(28, 0xFFFFFFFFu);
    auto d = io::check_dds_structure(dds.b, "m.dds");
    ASSERT_FALSE(d.ok());
    EXPECT_NE(d.error().message.find("mip count 4294967295 exceeds the full chain"), std::string::npos)
        << d.error().message;
    Bytes ktx{make_ktx2_f32(4, 2, 1, kRoughness)};
    ktx.put32(40, 0xFFFFFFFFu);
    auto k = io::check_ktx2_structure(ktx.b, "m.ktx2");
    ASSERT_FALSE(k.ok());
    EXPECT_NE(k.error().message.find("levelCount 4294967295 exceeds the full chain"), std::string::npos)
        << k.error().message;
}

TEST(InspectDiff, PerMipDifferences) {
    Files files;
    auto changed = kRoughness;
    changed[0][3] += 0.25f;
    changed[0][5] -= 0.125f;
    const fs::path a = files.write("a_roughness.ktx2", make_ktx2_f32(4, 2, 1, kRoughness));
    const fs::path b = files.write("b_roughness.ktx2", make_ktx2_f32(4, 2, 1, changed));
    auto ra = inspect_texture(a);
    auto rb = inspect_texture(b);
    ASSERT_TRUE(ra.ok() && rb.ok());
    auto d = diff_textures(*ra, *rb);
    ASSERT_TRUE(d.ok());
    EXPECT_FALSE((*d)["identical"].get<bool>());
    const auto& l0 = (*d)["levels"][0]["quantities"]["roughness"];
    EXPECT_NEAR(l0["max_abs"].get<double>(), 0.25, 1e-6);
    EXPECT_NEAR(l0["mean_abs"].get<double>(), 0.375 / 8, 1e-6);
    EXPECT_NEAR(l0["rmse"].get<double>(), std::sqrt((0.0625 + 0.015625) / 8), 1e-6);
    EXPECT_EQ(l0["differing_texels"].get<long long>(), 2);
    EXPECT_EQ((*d)["levels"][1]["quantities"]["roughness"]["differing_texels"].get<long long>(), 0);

    auto same = diff_textures(*ra, *ra);
    ASSERT_TRUE(same.ok());
    EXPECT_TRUE((*same)["identical"].get<bool>());
    const fs::path c = files.write("c_roughness.ktx2", make_ktx2_f32(2, 1, 1, {{0.f, 1.f}, {0.5f}}));
    auto rc = inspect_texture(c);
    ASSERT_TRUE(rc.ok());
    EXPECT_FALSE(diff_textures(*ra, *rc).ok());
}

TEST(InspectWriterCrossCheck, TextureWriterOutputReadsBackExactly) {
    Files files;
    MipChain chain;
    for (int L = 0; L < 4; ++L) {
        Image img(8 >> L, 4 >> L ? 4 >> L : 1, 4);
        for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = float((i * 7 + L * 3) % 17) / 16.0f - 0.25f;
        chain.levels.push_back(std::move(img));
    }
    for (io::TextureContainer container : {io::TextureContainer::Ktx2, io::TextureContainer::Dds}) {
        auto written = io::write_texture(chain, io::TexelEncoding::Float32, io::TextureFileFormat(container),
                                         files.dir(), "x", "lean");
        ASSERT_TRUE(written.ok()) << written.error().message;
        const fs::path p = files.dir() / written->front().path;
        EXPECT_TRUE(io::check_texture_file(p).ok()) << io::check_texture_file(p).error().message;
        auto t = io::read_texture_for_inspection(p);
        ASSERT_TRUE(t.ok()) << t.error().message;
        EXPECT_EQ(t->pixel_format, "R32G32B32A32_SFLOAT");
        ASSERT_EQ(t->mips.levels.size(), chain.levels.size());
        for (size_t L = 0; L < chain.levels.size(); ++L) EXPECT_EQ(t->mips.levels[L].pixels, chain.levels[L].pixels);
    }
}

TEST(InspectSheet, DrawsEveryMipInFalseColour) {
    Files files;
    const fs::path p = files.write("flat_roughness.ktx2", make_ktx2_f32(4, 2, 1, {std::vector<float>(8, 0.5f), {0.5f, 0.5f}, {0.5f}}));
    auto r = inspect_texture(p);
    ASSERT_TRUE(r.ok());
    const fs::path sheet = files.dir() / "sheet.png";
    ASSERT_TRUE(write_contact_sheet(std::span(&*r, 1), sheet).ok());
    auto png = io::read_texture_for_inspection(sheet);
    ASSERT_TRUE(png.ok()) << png.error().message;
    const Image& img = png->mips.levels[0];
    EXPECT_EQ(img.channels, 3);
    // A constant image maps to the middle of the colour bar: viridis stop 2 = (33, 145, 140).
    const float* texel = img.texel(10, 10);
    EXPECT_NEAR(texel[0] * 255.0f, 33.0f, 0.5f);
    EXPECT_NEAR(texel[1] * 255.0f, 145.0f, 0.5f);
    EXPECT_NEAR(texel[2] * 255.0f, 140.0f, 0.5f);
}
