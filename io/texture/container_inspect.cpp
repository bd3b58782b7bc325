#include "io/texture/container_inspect.h"
#include "io/files/input_policy.h"

#include "io/texture/astc_codec.h"
#include "io/files/atomic_write.h"
#include "io/files/file_read.h"
#include "io/texture/bc_decode.h"
#include "io/texture/byte_order.h"
#include "io/image/image_io.h"
#include "io/image/oiio_api.h"


#include <zstd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numeric>
#include <optional>

namespace specbake::io {
namespace {

enum class Numeric { unorm, srgb, sfloat };

// Formats a bake can produce, by the KTX2 vkFormat (Vulkan) and DDS DXGI_FORMAT values: uncompressed, the
// block-compressed BC1 (RGB, opaque), BC3, BC4 and BC5 UNORM of `--block bc` (io/texture/bc_decode.h), and the ASTC
// 4x4, 6x6 and 8x8 UNORM of `--block astc` (KTX2 only; decoded by astcenc, io/texture/astc_codec.h).
struct FormatInfo {
    uint32_t vk;
    uint32_t dxgi;  // 0: no DXGI equivalent
    const char* name;
    int channels;
    int bytes;  // per channel (1 for block formats: typeSize, and 8-bit endpoints)
    Numeric numeric;
    bool block = false;
    BcFormat bc = BcFormat::Bc1;
    uint8_t colour_model = 1;  // KDFS 1.3 Sec. 5.6: RGBSDA 1, BC1A 128, BC3 130, BC4 131, BC5 132, ASTC 162
    int astc = 0;              // ASTC footprint side; 0 for the others
};

constexpr std::array<FormatInfo, 25> kFormats{{
    {9, 61, "R8_UNORM", 1, 1, Numeric::unorm},
    {16, 49, "R8G8_UNORM", 2, 1, Numeric::unorm},
    {23, 0, "R8G8B8_UNORM", 3, 1, Numeric::unorm},
    {37, 28, "R8G8B8A8_UNORM", 4, 1, Numeric::unorm},
    {43, 29, "R8G8B8A8_SRGB", 4, 1, Numeric::srgb},
    {70, 56, "R16_UNORM", 1, 2, Numeric::unorm},
    {77, 35, "R16G16_UNORM", 2, 2, Numeric::unorm},
    {84, 0, "R16G16B16_UNORM", 3, 2, Numeric::unorm},
    {91, 11, "R16G16B16A16_UNORM", 4, 2, Numeric::unorm},
    {76, 54, "R16_SFLOAT", 1, 2, Numeric::sfloat},
    {83, 34, "R16G16_SFLOAT", 2, 2, Numeric::sfloat},
    {90, 0, "R16G16B16_SFLOAT", 3, 2, Numeric::sfloat},
    {97, 10, "R16G16B16A16_SFLOAT", 4, 2, Numeric::sfloat},
    {100, 41, "R32_SFLOAT", 1, 4, Numeric::sfloat},
    {103, 16, "R32G32_SFLOAT", 2, 4, Numeric::sfloat},
    {106, 6, "R32G32B32_SFLOAT", 3, 4, Numeric::sfloat},
    {109, 2, "R32G32B32A32_SFLOAT", 4, 4, Numeric::sfloat},
    {131, 71, "BC1_RGB_UNORM_BLOCK", 4, 1, Numeric::unorm, true, BcFormat::Bc1, 128},
    {137, 77, "BC3_UNORM_BLOCK", 4, 1, Numeric::unorm, true, BcFormat::Bc3, 130},
    {139, 80, "BC4_UNORM_BLOCK", 1, 1, Numeric::unorm, true, BcFormat::Bc4, 131},
    {141, 83, "BC5_UNORM_BLOCK", 2, 1, Numeric::unorm, true, BcFormat::Bc5, 132},
    {157, 0, "ASTC_4x4_UNORM_BLOCK", 4, 1, Numeric::unorm, true, BcFormat::Bc1, 162, 4},
    {165, 0, "ASTC_6x6_UNORM_BLOCK", 4, 1, Numeric::unorm, true, BcFormat::Bc1, 162, 6},
    {171, 0, "ASTC_8x8_UNORM_BLOCK", 4, 1, Numeric::unorm, true, BcFormat::Bc1, 162, 8},
    {0, 0, "", 0, 0, Numeric::unorm},
}};

const FormatInfo* format_by_vk(uint32_t vk) {
    for (const FormatInfo& f : kFormats)
        if (f.channels && f.vk == vk) return &f;
    return nullptr;
}

const FormatInfo* format_by_dxgi(uint32_t dxgi) {
    for (const FormatInfo& f : kFormats)
        if (f.channels && f.dxgi && f.dxgi == dxgi) return &f;
    return nullptr;
}

// Texels a side of one block (1 for plain formats) and bytes a block (plain: a texel).
int block_side(const FormatInfo& f) { return f.astc ? f.astc : f.block ? 4 : 1; }
uint32_t block_size_bytes(const FormatInfo& f) {
    return f.astc ? 16u : f.block ? uint32_t(bc_block_bytes(f.bc)) : uint32_t(f.channels * f.bytes);
}

uint32_t u32(std::span<const uint8_t> b, size_t at) {
    return uint32_t(b[at]) | uint32_t(b[at + 1]) << 8 | uint32_t(b[at + 2]) << 16 | uint32_t(b[at + 3]) << 24;
}
uint64_t u64(std::span<const uint8_t> b, size_t at) { return uint64_t(u32(b, at)) | uint64_t(u32(b, at + 4)) << 32; }

float half_to_float(uint16_t h) {
    const int sign = h >> 15;
    const int exponent = (h >> 10) & 0x1f;
    const int mantissa = h & 0x3ff;
    float v;
    if (exponent == 0) {
        v = std::ldexp(float(mantissa), -24);  // subnormal
    } else if (exponent == 31) {
        v = mantissa ? std::nanf("") : INFINITY;
    } else {
        v = std::ldexp(float(mantissa + 1024), exponent - 25);
    }
    return sign ? -v : v;
}

float decode_channel(const uint8_t* p, const FormatInfo& f) {
    if (f.numeric == Numeric::sfloat) {
        if (f.bytes == 2) return half_to_float(uint16_t(p[0] | p[1] << 8));
        float v;
        std::memcpy(&v, p, 4);  // little-endian hosts only, as every target of specbake
        return v;
    }
    if (f.bytes == 1) return float(p[0]) / 255.0f;
    return float(p[0] | p[1] << 8) / 65535.0f;
}

int full_chain_levels(uint32_t w, uint32_t h) {
    int n = 1;
    for (uint32_t m = std::max(w, h); m > 1; m >>= 1) ++n;
    return n;
}

uint64_t level_bytes(uint32_t w, uint32_t h, int level, const FormatInfo& f) {
    // A 2^32-wide chain has 33 levels: level 32 is 1x1 (and a shift by 32 would be undefined).
    const uint64_t lw = level >= 32 ? 1 : std::max<uint32_t>(1, w >> level);
    const uint64_t lh = level >= 32 ? 1 : std::max<uint32_t>(1, h >> level);
    if (f.astc) return astc_level_bytes(f.astc, lw, lh);
    if (f.block) return bc_level_bytes(f.bc, lw, lh);
    return lw * lh * uint64_t(f.channels * f.bytes);
}

Result<Image> decode_level(const uint8_t* data, int w, int h, const FormatInfo& f) {
    if (f.astc) {
        auto rgba = astc_decompress_level({data, size_t(astc_level_bytes(f.astc, uint64_t(w), uint64_t(h)))}, w, h, f.astc);
        if (!rgba) return rgba.error();
        Image img(w, h, 4);
        for (size_t i = 0; i < rgba->size(); ++i) img.pixels[i] = float((*rgba)[i]) / 255.0f;
        return img;
    }
    if (f.block) return decode_bc_level(f.bc, data, w, h);
    Image img(w, h, f.channels);
    const size_t texel = size_t(f.channels * f.bytes);
    for (size_t i = 0; i < img.texel_count(); ++i)
        for (int c = 0; c < f.channels; ++c)
            img.pixels[i * f.channels + c] = decode_channel(data + i * texel + size_t(c) * f.bytes, f);
    return img;
}

constexpr size_t kKtx2HeaderBytes = 80;
constexpr size_t kKtx2LevelEntryBytes = 24;

// Level 0 against the limits (io/files/input_policy.h) before it is decoded to float texels: its texel count
// and its bytes in the file (over all `layers` of an array; 1 for a single image).
Result<void> check_size(uint32_t w, uint32_t h, const FormatInfo& f, const InputLimits& limits, uint32_t layers = 1) {
    const uint64_t texels = uint64_t(w) * h * layers;
    if (texels > limits.texels)
        return make_error("image is " + std::to_string(w) + "x" + std::to_string(h) +
                          (layers > 1 ? " x " + std::to_string(layers) + " layers" : std::string()) +
                          ", its texel count " + over_limit("texels", texels, limits.texels));
    if (const uint64_t bytes = level_bytes(w, h, 0, f) * layers; bytes > limits.texture_bytes)
        return make_error("level 0 of " + over_limit("texture-bytes", bytes, limits.texture_bytes) + " bytes");
    return {};
}

struct Ktx2Layout {
    const FormatInfo* format = nullptr;
    uint32_t width = 0, height = 0, levels = 0;
    uint32_t layers = 0;  // KTX2 layerCount: 0 for a single image, else a 2D array of that many layers
    std::vector<uint64_t> offsets;
    uint32_t transfer = 0;
    std::vector<std::vector<uint8_t>> inflated;  // zstd: every level decompressed (and checked)
};

Error ktx2_error(const std::string& name, const std::string& what) { return make_error(name + ": KTX2: " + what); }

// What the header says about the rest of the file: how the levels are stored and where the metadata lies.
struct Ktx2Sections {
    bool zstd = false;
    uint32_t stored_layers = 1;  // layers of every level: 1 for a single image
    uint64_t index_end = 0;      // end of the level index
    uint32_t dfd_offset = 0, dfd_length = 0, kvd_offset = 0, kvd_length = 0;
};

// The header (KTX 2.0 Sec. 3.1): format, size, layers and levels of `L`, checked against what specbake reads
// and the input limits, and the metadata's place in the file.
Result<Ktx2Sections> read_ktx2_header(std::span<const uint8_t> b, const std::string& name, const InputLimits& limits,
                                      Ktx2Layout& L) {
    auto fail = [&](const std::string& what) { return ktx2_error(name, what); };
    if (b.size() < kKtx2HeaderBytes) return fail("truncated header (" + std::to_string(b.size()) + " bytes)");
    if (std::memcmp(b.data(), kKtx2Identifier, 12) != 0) return fail("bad identifier");
    const uint32_t vk = u32(b, 12), type_size = u32(b, 16);
    L.width = u32(b, 20);
    L.height = u32(b, 24);
    const uint32_t depth = u32(b, 28), layers = u32(b, 32), faces = u32(b, 36);
    L.levels = std::max<uint32_t>(1, u32(b, 40));
    const uint32_t supercompression = u32(b, 44);
    L.format = format_by_vk(vk);
    if (!L.format) return fail("vkFormat " + std::to_string(vk) + " is not a format specbake reads");
    const FormatInfo& f = *L.format;
    if (type_size != uint32_t(f.bytes))
        return fail("typeSize " + std::to_string(type_size) + " does not match " + f.name);
    if (L.width == 0 || L.height == 0) return fail("zero width or height");
    // Single 2D images and 2D arrays (the glint dictionary); no volumes, cube maps or 1D textures.
    if (depth != 0 || faces != 1) return fail("only 2D images and 2D arrays are supported");
    L.layers = layers;
    if (f.block && layers != 0) return fail("block-compressed 2D arrays are not supported");
    Ktx2Sections s;
    s.stored_layers = std::max<uint32_t>(1, layers);
    // Scheme 2 is Zstandard (KTX 2.0 Sec. 3.9.2); BasisLZ (1) and ZLIB (3) are not written by specbake.
    if (supercompression != 0 && supercompression != 2)
        return fail("supercompression scheme " + std::to_string(supercompression) + " (specbake reads none and zstd)");
    s.zstd = supercompression == 2;
    if (auto r = check_size(L.width, L.height, f, limits, s.stored_layers); !r) return fail(r.error().message);
    if (L.levels > uint32_t(full_chain_levels(L.width, L.height)))
        return fail("levelCount " + std::to_string(L.levels) + " exceeds the full chain of " +
                    std::to_string(full_chain_levels(L.width, L.height)));

    s.index_end = kKtx2HeaderBytes + kKtx2LevelEntryBytes * uint64_t(L.levels);
    if (b.size() < s.index_end) return fail("truncated level index");
    s.dfd_offset = u32(b, 48), s.dfd_length = u32(b, 52);
    s.kvd_offset = u32(b, 56), s.kvd_length = u32(b, 60);
    const uint64_t sgd_offset = u64(b, 64), sgd_length = u64(b, 72);
    if (s.dfd_length == 0) return fail("no data format descriptor");
    if (s.dfd_offset < s.index_end || uint64_t(s.dfd_offset) + s.dfd_length > b.size())
        return fail("data format descriptor at " + std::to_string(s.dfd_offset) + "+" + std::to_string(s.dfd_length) +
                    " lies outside the file");
    if (s.dfd_offset % 4) return fail("data format descriptor is not 4-byte aligned");
    if (s.kvd_length && (s.kvd_offset < s.index_end || uint64_t(s.kvd_offset) + s.kvd_length > b.size()))
        return fail("key/value data lies outside the file");
    if (sgd_offset != 0 || sgd_length != 0) return fail("supercompression global data, which zstd does not use");
    return s;
}

// Key/value entries (KTX 2.0 Sec. 3.11): each a 4-byte length, that many bytes, padding to 4; every entry
// inside the block.
Result<void> check_ktx2_key_values(std::span<const uint8_t> b, const Ktx2Sections& s, const std::string& name) {
    for (uint64_t at = s.kvd_offset, end = uint64_t(s.kvd_offset) + s.kvd_length; s.kvd_length && at < end;) {
        if (end - at < 4) return ktx2_error(name, "key/value data ends inside an entry's length");
        const uint64_t entry = u32(b, size_t(at));
        if (entry > end - at - 4)
            return ktx2_error(name, "key/value entry at " + std::to_string(at) + " of length " +
                                        std::to_string(entry) + " runs past the key/value data");
        at += 4 + (entry + 3) / 4 * 4;
    }
    return {};
}

// The samples of the basic descriptor block starting at `blk` (KDFS 1.3 Sec. 5.18) against format `f`.
Result<void> check_dfd_samples(std::span<const uint8_t> b, size_t blk, uint32_t samples, const FormatInfo& f,
                               const std::string& name) {
    auto fail = [&](const std::string& what) { return ktx2_error(name, what); };
    if (f.astc) {
        // One 128-bit sample of channel 0 (ASTC data, KDFS 1.3 Sec. 5.18).
        if (samples != 1 || (b[blk + 24] | b[blk + 25] << 8) != 0 || b[blk + 26] != 127 || (b[blk + 27] & 0x0f) != 0)
            return fail(std::string("DFD samples do not describe ") + f.name);
    } else if (f.block) {
        // One 64-bit sample per 8 bytes of block (KDFS 1.3 Sec. 5.18): BC3 alpha (15) then colour (0), BC5
        // red (0) then green (1), BC1 and BC4 one sample of channel 0.
        const uint32_t want = uint32_t(bc_block_bytes(f.bc) / 8);
        if (samples != want)
            return fail(std::to_string(samples) + " DFD samples for " + f.name + " (expected " + std::to_string(want) + ")");
        for (uint32_t s = 0; s < samples; ++s) {
            const size_t at = blk + 24 + 16 * s;
            const uint32_t channel = b[at + 3] & 0x0f;
            const uint32_t expected = f.bc == BcFormat::Bc3 ? (s == 0 ? 15u : 0u) : s;
            if (uint32_t(b[at] | b[at + 1] << 8) != 64 * s || b[at + 2] != 63 || channel != expected)
                return fail("DFD sample " + std::to_string(s) + " does not describe " + f.name);
        }
    } else if (samples != uint32_t(f.channels))
        return fail(std::to_string(samples) + " DFD samples for " + std::to_string(f.channels) + " channels");
    for (uint32_t s = 0; s < samples && !f.block; ++s) {
        const size_t at = blk + 24 + 16 * s;
        const uint32_t bit_offset = b[at] | b[at + 1] << 8;
        const uint32_t bit_length = b[at + 2] + 1u;
        const uint8_t channel_type = b[at + 3];
        const uint32_t channel_id = channel_type & 0x0f;
        const uint32_t expected_id = s == 3 ? 15 : s;  // R, G, B, then A = 15
        const bool is_float = channel_type & 0x80;
        if (bit_offset != s * 8u * f.bytes || bit_length != 8u * f.bytes || channel_id != expected_id ||
            is_float != (f.numeric == Numeric::sfloat))
            return fail("DFD sample " + std::to_string(s) + " does not describe channel " + std::to_string(s) +
                        " of " + f.name);
    }
    return {};
}

// Data format descriptor: the basic block (Khronos Data Format Specification 1.3, Sec. 5) against the
// format of `L`, whose transfer function it fills.
Result<void> check_ktx2_dfd(std::span<const uint8_t> b, const Ktx2Sections& s, const std::string& name,
                            Ktx2Layout& L) {
    auto fail = [&](const std::string& what) { return ktx2_error(name, what); };
    const FormatInfo& f = *L.format;
    if (s.dfd_length < 4 + 24) return fail("data format descriptor too short");
    if (u32(b, s.dfd_offset) != s.dfd_length) return fail("dfdTotalSize does not match dfdByteLength");
    const size_t blk = s.dfd_offset + 4;
    const uint32_t w0 = u32(b, blk), w1 = u32(b, blk + 4);
    const uint32_t vendor = w0 & 0x1ffff, type = w0 >> 17, version = w1 & 0xffff, block_size = w1 >> 16;
    if (vendor != 0 || type != 0) return fail("first descriptor block is not the Khronos basic block");
    if (version != 2) return fail("descriptor version " + std::to_string(version) + " (expected 2)");
    const uint32_t samples = (block_size - 24) / 16;
    if (block_size < 24 || (block_size - 24) % 16 || 4 + block_size > s.dfd_length)
        return fail("descriptor block size " + std::to_string(block_size) + " is inconsistent");
    const uint8_t color_model = b[blk + 8];
    L.transfer = b[blk + 10];
    if (color_model != f.colour_model)
        return fail("colour model " + std::to_string(color_model) + " does not match " + f.name + " (expected " +
                    std::to_string(f.colour_model) + ")");
    // Texel block dimensions are stored minus one: 1x1x1x1 for plain texels, 4x4x1x1 for BC blocks, the
    // footprint for ASTC.
    const int side = block_side(f);
    if (b[blk + 12] != side - 1 || b[blk + 13] != side - 1 || b[blk + 14] | b[blk + 15])
        return fail("texel block dimensions are not " + std::to_string(side) + "x" + std::to_string(side) + "x1x1");
    const uint32_t plane_bytes = block_size_bytes(f);
    if (b[blk + 16] != plane_bytes)
        return fail("bytesPlane0 " + std::to_string(b[blk + 16]) + " does not match " + f.name);
    const uint32_t expected_transfer = f.numeric == Numeric::srgb ? 2 : 1;
    if (L.transfer != expected_transfer)
        return fail("transfer function " + std::to_string(L.transfer) + " does not match " + f.name);
    return check_dfd_samples(b, blk, samples, f, name);
}

// Level index: sizes exact, aligned, inside the file, clear of the metadata, smallest level first.
// Supercompressed levels have no alignment (mipPadding is align(1)) and any byteLength; they must
// inflate to exactly uncompressedByteLength. Fills the offsets (and, with `inflate`, the inflated levels) of `L`.
Result<void> read_ktx2_levels(std::span<const uint8_t> b, const Ktx2Sections& s, const std::string& name,
                              bool inflate, Ktx2Layout& L) {
    auto fail = [&](const std::string& what) { return ktx2_error(name, what); };
    const FormatInfo& f = *L.format;
    const bool zstd = s.zstd;
    const uint64_t alignment =
        zstd ? 1 : std::lcm(uint64_t(block_size_bytes(f)), uint64_t(4));
    const uint64_t metadata_end = std::max<uint64_t>(uint64_t(s.dfd_offset) + s.dfd_length,
                                                     s.kvd_length ? uint64_t(s.kvd_offset) + s.kvd_length : 0);
    for (uint32_t level = 0; level < L.levels; ++level) {
        const size_t at = kKtx2HeaderBytes + kKtx2LevelEntryBytes * level;
        const uint64_t offset = u64(b, at), length = u64(b, at + 8), uncompressed = u64(b, at + 16);
        const std::string lv = "level " + std::to_string(level);
        // An array level holds its layers one after another (KTX 2.0 Sec. 3.9.7).
        const uint64_t expected = level_bytes(L.width, L.height, int(level), f) * s.stored_layers;
        if ((!zstd && length != expected) || uncompressed != expected)
            return fail(lv + " holds " + std::to_string(zstd ? uncompressed : length) + " bytes, expected " +
                        std::to_string(expected));
        if (zstd && length == 0) return fail(lv + " has no compressed data");
        if (offset % alignment) return fail(lv + " offset " + std::to_string(offset) + " is not aligned");
        if (offset < metadata_end) return fail(lv + " offset " + std::to_string(offset) + " overlaps the metadata");
        if (offset > b.size() || length > b.size() - offset)
            return fail(lv + " at " + std::to_string(offset) + "+" + std::to_string(length) +
                        " runs past the end of the file (" + std::to_string(b.size()) + " bytes)");
        if (level > 0 && offset + length > L.offsets.back())
            return fail(lv + " is not stored before level " + std::to_string(level - 1) +
                        " (levels are stored smallest first, without overlap)");
        L.offsets.push_back(offset);
        if (zstd && !inflate) {
            const unsigned long long content = ZSTD_getFrameContentSize(b.data() + offset, length);
            if (content == ZSTD_CONTENTSIZE_ERROR) return fail(lv + " is not a zstd frame");
            if (content != ZSTD_CONTENTSIZE_UNKNOWN && content != expected)
                return fail(lv + " declares " + std::to_string(content) + " bytes, expected " + std::to_string(expected));
        } else if (zstd) {
            std::vector<uint8_t> level_bytes_out(expected);
            const size_t n = ZSTD_decompress(level_bytes_out.data(), level_bytes_out.size(), b.data() + offset, length);
            if (ZSTD_isError(n)) return fail(lv + ": zstd: " + ZSTD_getErrorName(n));
            if (n != expected)
                return fail(lv + " inflates to " + std::to_string(n) + " bytes, expected " + std::to_string(expected));
            L.inflated.push_back(std::move(level_bytes_out));
        }
    }
    return {};
}

// `inflate`: zstd levels are decompressed (and kept for decoding); otherwise only each level's zstd frame
// header is read, whose content size must equal uncompressedByteLength (the check reads headers alone).
Result<Ktx2Layout> parse_ktx2(std::span<const uint8_t> b, const std::string& name, const InputLimits& limits,
                              bool inflate = true) {
    Ktx2Layout L;
    auto sections = read_ktx2_header(b, name, limits, L);
    if (!sections) return sections.error();
    if (auto ok = check_ktx2_key_values(b, *sections, name); !ok) return ok.error();
    if (auto ok = check_ktx2_dfd(b, *sections, name, L); !ok) return ok.error();
    if (auto ok = read_ktx2_levels(b, *sections, name, inflate, L); !ok) return ok.error();
    return L;
}

constexpr size_t kDdsHeaderBytes = 4 + 124;
constexpr size_t kDx10HeaderBytes = 20;

struct DdsLayout {
    const FormatInfo* format = nullptr;
    bool bgra = false;  // A8R8G8B8: RGBA8 texels stored B, G, R, A
    uint32_t width = 0, height = 0, levels = 0;
    size_t data_start = 0;  // after the legacy header, or after the DX10 header
};

Result<DdsLayout> parse_dds(std::span<const uint8_t> b, const std::string& name, const InputLimits& limits) {
    auto fail = [&](const std::string& what) { return make_error(name + ": DDS: " + what); };
    if (b.size() < kDdsHeaderBytes) return fail("truncated header");
    if (std::memcmp(b.data(), "DDS ", 4) != 0) return fail("bad magic");
    if (u32(b, 4) != 124) return fail("header size is not 124");
    const uint32_t flags = u32(b, 8);
    constexpr uint32_t kRequired = 0x1 | 0x2 | 0x4 | 0x1000;  // CAPS, HEIGHT, WIDTH, PIXELFORMAT
    if ((flags & kRequired) != kRequired) return fail("header flags lack CAPS/HEIGHT/WIDTH/PIXELFORMAT");
    DdsLayout L;
    L.height = u32(b, 12);
    L.width = u32(b, 16);
    const uint32_t depth = u32(b, 24);
    L.levels = (flags & 0x20000) ? std::max<uint32_t>(1, u32(b, 28)) : 1;  // DDSD_MIPMAPCOUNT
    if (L.width == 0 || L.height == 0) return fail("zero width or height");
    if ((flags & 0x800000) && depth > 1) return fail("volume textures are not supported");
    if (L.levels > uint32_t(full_chain_levels(L.width, L.height)))
        return fail("mip count " + std::to_string(L.levels) + " exceeds the full chain");
    if (u32(b, 76) != 32) return fail("pixel format size is not 32");
    const uint32_t pf_flags = u32(b, 80);
    L.data_start = kDdsHeaderBytes;
    if ((pf_flags & 0x4) && std::memcmp(b.data() + 84, "DX10", 4) == 0) {
        if (b.size() < kDdsHeaderBytes + kDx10HeaderBytes) return fail("truncated DX10 header");
        L.data_start += kDx10HeaderBytes;
        const uint32_t dxgi = u32(b, 128), dimension = u32(b, 132), misc = u32(b, 136), array = u32(b, 140);
        L.format = format_by_dxgi(dxgi);
        if (!L.format)
            return fail("DXGI format " + std::to_string(dxgi) + " is not a format specbake reads");
        if (dimension != 3) return fail("resource dimension " + std::to_string(dimension) + " is not TEXTURE2D");
        if (misc & 0x4) return fail("cube maps are not supported");
        if (array != 1) return fail("array size " + std::to_string(array) + " (expected 1)");
    } else {
        // Legacy pixel formats, mapped to DXGI as Microsoft's DDS reference does (L8, A8L8, A8B8G8R8,
        // A8R8G8B8 = B8G8R8A8, L16, G16R16, FourCC 36 = A16B16G16R16; the FourCCs DXT1 = BC1, DXT5 = BC3,
        // ATI1 / BC4U = BC4, ATI2 / BC5U = BC5).
        const uint32_t fourcc = u32(b, 84), bits = u32(b, 88);
        const std::array<uint32_t, 4> m{u32(b, 92), u32(b, 96), u32(b, 100), u32(b, 104)};
        auto masks = [&](uint32_t r, uint32_t g, uint32_t bl, uint32_t a) { return m == std::array{r, g, bl, a}; };
        uint32_t dxgi = 0;
        auto is = [&](const char* code) { return std::memcmp(b.data() + 84, code, 4) == 0; };
        if (pf_flags & 0x4) {
            dxgi = fourcc == 36 ? 11 : is("DXT1") ? 71 : is("DXT5") ? 77 : is("ATI1") || is("BC4U") ? 80
                 : is("ATI2") || is("BC5U") ? 83 : 0;
        }
        else if ((pf_flags & 0x20000) && bits == 8 && masks(0xFF, 0, 0, 0)) dxgi = 61;
        else if ((pf_flags & 0x20000) && bits == 16 && masks(0xFF, 0, 0, 0xFF00)) dxgi = 49;
        else if ((pf_flags & 0x20000) && bits == 16 && masks(0xFFFF, 0, 0, 0)) dxgi = 56;
        else if ((pf_flags & 0x40) && bits == 32 && masks(0xFF, 0xFF00, 0xFF0000, 0xFF000000u)) dxgi = 28;
        else if ((pf_flags & 0x40) && bits == 32 && masks(0xFF0000, 0xFF00, 0xFF, 0xFF000000u)) dxgi = 28, L.bgra = true;
        else if ((pf_flags & 0x40) && bits == 32 && masks(0xFFFF, 0xFFFF0000u, 0, 0)) dxgi = 35;
        L.format = format_by_dxgi(dxgi);
        if (!L.format) return fail("legacy pixel format is not one specbake reads");
    }
    if (auto r = check_size(L.width, L.height, *L.format, limits); !r) return fail(r.error().message);
    uint64_t expected = L.data_start;
    for (uint32_t level = 0; level < L.levels; ++level) expected += level_bytes(L.width, L.height, int(level), *L.format);
    if (b.size() != expected)
        return fail("file holds " + std::to_string(b.size()) + " bytes, header implies " + std::to_string(expected));
    return L;
}

bool has_prefix(std::span<const uint8_t> b, const void* magic, size_t n) {
    return b.size() >= n && std::memcmp(b.data(), magic, n) == 0;
}

Result<InspectedTexture> read_with_oiio(const std::filesystem::path& path, const InputLimits& limits) {
    auto api = oiio::api();
    if (!api) return make_error(path.string() + ": " + api.error().message);
    return (*api)->read_levels(path.string(), limits.texels);
}

}  // namespace

Result<void> check_ktx2_structure(std::span<const uint8_t> bytes, const std::string& name,
                                  const InputLimits& limits) {
    auto r = parse_ktx2(bytes, name, limits);
    if (!r) return r.error();
    return {};
}

Result<void> check_dds_structure(std::span<const uint8_t> bytes, const std::string& name,
                                 const InputLimits& limits) {
    auto r = parse_dds(bytes, name, limits);
    if (!r) return r.error();
    return {};
}

Result<InspectedTexture> decode_ktx2_for_inspection(std::span<const uint8_t> bytes, const std::string& name,
                                                    const InputLimits& limits) {
    auto layout = parse_ktx2(bytes, name, limits);
    if (!layout) return layout.error();
    InspectedTexture t;
    t.format = "ktx2";
    t.pixel_format = layout->format->name;
    t.transfer = layout->transfer == 2 ? "sRGB" : "linear";
    t.channel_names.assign({"R", "G", "B", "A"});
    t.channel_names.resize(size_t(layout->format->channels));
    t.layers = int(layout->layers);
    t.channel_bytes = layout->format->bytes;
    if (layout->format->block) t.block_bytes = int(block_size_bytes(*layout->format));
    const int stored_layers = std::max(1, t.layers);
    // An array's layers are decoded one below the other: each level is width x (height x layers).
    for (uint32_t level = 0; level < layout->levels; ++level) {
        auto img = decode_level(layout->inflated.empty() ? bytes.data() + layout->offsets[level]
                                                         : layout->inflated[level].data(),
                                int(std::max<uint32_t>(1, layout->width >> level)),
                                int(std::max<uint32_t>(1, layout->height >> level)) * stored_layers, *layout->format);
        if (!img) return make_error(name + ": KTX2: level " + std::to_string(level) + ": " + img.error().message);
        t.mips.levels.push_back(std::move(*img));
    }
    return t;
}

Result<InspectedTexture> decode_dds_for_inspection(std::span<const uint8_t> bytes, const std::string& name,
                                                   const InputLimits& limits) {
    auto layout = parse_dds(bytes, name, limits);
    if (!layout) return layout.error();
    InspectedTexture t;
    t.format = "dds";
    t.pixel_format = layout->format->name;
    t.channel_bytes = layout->format->bytes;
    if (layout->format->block) t.block_bytes = int(bc_block_bytes(layout->format->bc));
    t.transfer = layout->format->numeric == Numeric::srgb ? "sRGB" : "linear";
    t.channel_names.assign({"R", "G", "B", "A"});
    t.channel_names.resize(size_t(layout->format->channels));
    size_t at = layout->data_start;
    for (uint32_t level = 0; level < layout->levels; ++level) {
        const int w = int(std::max<uint32_t>(1, layout->width >> level));
        const int h = int(std::max<uint32_t>(1, layout->height >> level));
        auto img = decode_level(bytes.data() + at, w, h, *layout->format);
        if (!img) return make_error(name + ": DDS: level " + std::to_string(level) + ": " + img.error().message);
        t.mips.levels.push_back(std::move(*img));
        if (layout->bgra)
            for (size_t i = 0; i < t.mips.levels.back().texel_count(); ++i)
                std::swap(t.mips.levels.back().pixels[4 * i], t.mips.levels.back().pixels[4 * i + 2]);
        at += level_bytes(layout->width, layout->height, int(level), *layout->format);
    }
    return t;
}

Result<InspectedTexture> read_texture_for_inspection(const std::filesystem::path& path, const InputLimits& limits) {
    auto bytes = read_file(path);
    if (!bytes) return bytes.error();
    if (has_prefix(*bytes, kKtx2Identifier, 12)) return decode_ktx2_for_inspection(*bytes, path.string(), limits);
    if (has_prefix(*bytes, "DDS ", 4)) return decode_dds_for_inspection(*bytes, path.string(), limits);
    if (auto r = check_png_structure(*bytes, path.string(), limits); !r) return r.error();  // before OpenImageIO loads
    return read_with_oiio(path, limits);
}

Result<void> check_texture_file(const std::filesystem::path& path, const InputLimits& limits) {
    auto bytes = read_file(path);
    if (!bytes) return bytes.error();
    if (has_prefix(*bytes, kKtx2Identifier, 12)) return check_ktx2_structure(*bytes, path.string(), limits);
    if (has_prefix(*bytes, "DDS ", 4)) return check_dds_structure(*bytes, path.string(), limits);
    if (auto r = check_png_structure(*bytes, path.string(), limits); !r) return r.error();
    auto t = read_with_oiio(path, limits);
    if (!t) return t.error();
    return {};
}

Result<TextureShape> check_container_shape(std::span<const uint8_t> bytes, const std::string& name,
                                           const InputLimits& limits) {
    if (has_prefix(bytes, kKtx2Identifier, 12)) {
        auto l = parse_ktx2(bytes, name, limits, false);
        if (!l) return l.error();
        return TextureShape{"ktx2", int(l->width), int(l->height), int(l->levels), l->format->channels, int(l->layers)};
    }
    if (has_prefix(bytes, "DDS ", 4)) {
        auto l = parse_dds(bytes, name, limits);
        if (!l) return l.error();
        return TextureShape{"dds", int(l->width), int(l->height), int(l->levels), l->format->channels};
    }
    return make_error(name + ": neither KTX2 nor DDS");
}

Result<TextureShape> read_image_shape(const std::filesystem::path& path) {
    if (auto ok = check_regular_input(path); !ok) return ok.error();
    auto api = oiio::api();
    if (!api) return make_error(path.string() + ": " + api.error().message);
    return (*api)->read_shape(path.string());
}

Result<void> write_png_rgb8(const std::filesystem::path& path, int width, int height, std::span<const uint8_t> rgb) {
    if (rgb.size() != size_t(width) * height * 3) return make_error(path.string() + ": image size mismatch");
    AtomicOutput out(path);
    std::error_code ec;
    if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path(), ec);
    auto api = oiio::api();
    if (!api) return make_error(path.string() + ": " + api.error().message);
    if (auto ok = (*api)->write_rgb8(out.temp_path().string(), path.string(), width, height, rgb.data()); !ok)
        return ok.error();
    return out.commit();
}

}  // namespace specbake::io
