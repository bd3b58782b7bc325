#include "io/texture/ktx2.h"

#include "core/assert.h"
#include "io/texture/byte_order.h"
#include "io/texture/texel_encoding.h"

#include <tbb/parallel_for.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>
#include <numeric>

namespace specbake::io {
namespace {

constexpr size_t kHeaderBytes = 80;        // identifier + 9 header words + index (4 x u32, 2 x u64)
constexpr size_t kLevelIndexEntry = 24;    // byteOffset, byteLength, uncompressedByteLength (u64 each)
constexpr uint32_t kModelRgbsda = 1;       // KHR_DF_MODEL_RGBSDA
constexpr uint32_t kPrimariesBt709 = 1;    // KHR_DF_PRIMARIES_BT709
constexpr uint32_t kTransferLinear = 1;    // KHR_DF_TRANSFER_LINEAR
constexpr uint32_t kQualifierSigned = 0x40, kQualifierFloat = 0x80;  // KHR_DF_SAMPLE_DATATYPE_*
constexpr uint32_t kChannelAlpha = 15;     // KHR_DF_CHANNEL_RGBSDA_ALPHA
constexpr uint32_t kFloatMinusOne = 0xBF800000u, kFloatOne = 0x3F800000u;

size_t align_up(size_t v, size_t a) { return (v + a - 1) / a * a; }

bool is_float(TexelEncoding e) { return e == TexelEncoding::Float16 || e == TexelEncoding::Float32; }

// Channel ids of 1-4 channel RGBA data: R, G, B, then alpha.
uint32_t channel_id(int c) { return c == 3 ? kChannelAlpha : uint32_t(c); }

// Basic data format descriptor (Khronos Data Format Specification 1.3, Sec. 5), one sample per channel.
std::vector<uint8_t> make_dfd(TexelEncoding e, int channels) {
    const uint32_t bits = uint32_t(encoding_bytes(e)) * 8;
    const uint32_t block_size = 24 + 16 * uint32_t(channels);
    std::vector<uint8_t> d(4 + block_size, 0);
    put32(d, 0, uint32_t(d.size()));                  // dfdTotalSize
    put32(d, 4, 0);                                   // vendorId 0 (Khronos), descriptorType 0 (basic)
    put32(d, 8, 2u | (block_size << 16));             // versionNumber 2 (KDFS 1.3), descriptorBlockSize
    put32(d, 12, kModelRgbsda | (kPrimariesBt709 << 8) | (kTransferLinear << 16));  // flags 0: straight alpha
    put32(d, 16, 0);                                  // texel block 1x1x1x1 (dimensions stored minus one)
    put32(d, 20, uint32_t(channels) * bits / 8);      // bytesPlane0
    put32(d, 24, 0);
    for (int c = 0; c < channels; ++c) {
        const size_t at = 28 + size_t(c) * 16;
        const uint32_t qualifiers = is_float(e) ? (kQualifierFloat | kQualifierSigned) : 0;
        const uint32_t channel_type = channel_id(c) | qualifiers;
        put32(d, at, uint32_t(c) * bits | ((bits - 1) << 16) | (channel_type << 24));
        put32(d, at + 4, 0);  // sample position 0
        put32(d, at + 8, is_float(e) ? kFloatMinusOne : 0u);
        put32(d, at + 12, is_float(e) ? kFloatOne : uint32_t((uint64_t(1) << bits) - 1));
    }
    return d;
}

std::vector<uint8_t> make_kvd() {
    static const char key[] = "KTXwriter";
    static const char value[] = "specbake";
    const uint32_t length = uint32_t(sizeof(key) + sizeof(value));  // both with their NUL terminator
    std::vector<uint8_t> k(align_up(4 + length, 4), 0);
    put32(k, 0, length);
    std::memcpy(k.data() + 4, key, sizeof(key));
    std::memcpy(k.data() + 4 + sizeof(key), value, sizeof(value));
    return k;
}

}  // namespace

uint32_t ktx2_vk_format(TexelEncoding e, int channels) {
    // VkFormat values (Vulkan 1.0 core): R8 UNORM 9/16/23/37, R16 UNORM 70/77/84/91,
    // R16 SFLOAT 76/83/90/97, R32 SFLOAT 100/103/106/109 for 1/2/3/4 channels.
    static const uint32_t table[4][4] = {
        {9, 16, 23, 37}, {70, 77, 84, 91}, {76, 83, 90, 97}, {100, 103, 106, 109}};
    const int row = e == TexelEncoding::Unorm8 ? 0 : e == TexelEncoding::Unorm16 ? 1 : e == TexelEncoding::Float16 ? 2 : 3;
    return table[row][std::clamp(channels, 1, 4) - 1];
}

namespace {

// Byte offsets of the parts before the level data.
struct Ktx2Parts {
    size_t dfd_offset = 0, kvd_offset = 0, data_start = 0;
};

Ktx2Parts ktx2_parts(int levels, const std::vector<uint8_t>& dfd, const std::vector<uint8_t>& kvd) {
    Ktx2Parts p;
    p.dfd_offset = kHeaderBytes + kLevelIndexEntry * size_t(levels);
    p.kvd_offset = p.dfd_offset + dfd.size();
    p.data_start = p.kvd_offset + kvd.size();
    return p;
}

}  // namespace

ContainerLayout ktx2_layout(int width, int height, int levels, TexelEncoding encoding, int data_channels, int layers) {
    const int channels = gpu_channels(data_channels);
    const size_t texel_bytes = size_t(channels) * size_t(encoding_bytes(encoding));
    const size_t alignment = std::lcm(texel_bytes, size_t(4));
    const Ktx2Parts parts = ktx2_parts(levels, make_dfd(encoding, channels), make_kvd());
    ContainerLayout layout;
    layout.stored_channels = channels;
    layout.level_offset.resize(size_t(levels));
    // Level data: smallest level first, each aligned.
    size_t offset = parts.data_start;
    for (int i = levels; i-- > 0;) {
        offset = align_up(offset, alignment);
        layout.level_offset[size_t(i)] = offset;
        offset += size_t(std::max(1, width >> i)) * size_t(std::max(1, height >> i)) * texel_bytes *
                  size_t(std::max(1, layers));
    }
    layout.total = offset;
    return layout;
}

void ktx2_write_header(uint8_t* file, const ContainerLayout& layout, int width, int height, TexelEncoding encoding,
                       int data_channels, int layers) {
    const int channels = gpu_channels(data_channels);
    const uint32_t levels = uint32_t(layout.level_offset.size());
    const size_t texel_bytes = size_t(channels) * size_t(encoding_bytes(encoding));
    const std::vector<uint8_t> dfd = make_dfd(encoding, channels);
    const std::vector<uint8_t> kvd = make_kvd();
    const Ktx2Parts parts = ktx2_parts(int(levels), dfd, kvd);

    std::vector<uint8_t> b(parts.data_start, 0);
    std::memcpy(b.data(), kKtx2Identifier, sizeof(kKtx2Identifier));
    put32(b, 12, ktx2_vk_format(encoding, channels));
    put32(b, 16, uint32_t(encoding_bytes(encoding)));  // typeSize
    put32(b, 20, uint32_t(width));
    put32(b, 24, uint32_t(height));
    put32(b, 28, 0);       // pixelDepth: 2D
    put32(b, 32, uint32_t(std::max(0, layers)));  // layerCount: 0 when not an array
    put32(b, 36, 1);       // faceCount
    put32(b, 40, levels);  // levelCount
    put32(b, 44, 0);       // supercompressionScheme: none
    put32(b, 48, uint32_t(parts.dfd_offset));
    put32(b, 52, uint32_t(dfd.size()));
    put32(b, 56, uint32_t(parts.kvd_offset));
    put32(b, 60, uint32_t(kvd.size()));
    put64(b, 64, 0);       // no supercompression global data
    put64(b, 72, 0);
    for (uint32_t i = 0; i < levels; ++i) {
        const size_t at = kHeaderBytes + kLevelIndexEntry * i;
        const size_t length = size_t(std::max(1, width >> i)) * size_t(std::max(1, height >> i)) * texel_bytes *
                              size_t(std::max(1, layers));
        put64(b, at, layout.level_offset[i]);
        put64(b, at + 8, length);
        put64(b, at + 16, length);
    }
    std::memcpy(b.data() + parts.dfd_offset, dfd.data(), dfd.size());
    std::memcpy(b.data() + parts.kvd_offset, kvd.data(), kvd.size());
    std::memcpy(file, b.data(), b.size());
    // Alignment padding before each level (levels are stored smallest first).
    size_t end = b.size();
    for (uint32_t i = levels; i-- > 0;) {
        std::memset(file + end, 0, layout.level_offset[i] - end);
        end = layout.level_offset[i] + size_t(std::max(1, width >> i)) * size_t(std::max(1, height >> i)) * texel_bytes *
                                           size_t(std::max(1, layers));
    }
}

std::vector<std::span<const uint8_t>> Ktx2Pieces::pieces() const {
    std::vector<std::span<const uint8_t>> p{std::span<const uint8_t>(header)};
    for (size_t i = level_size.size(); i-- > 0;) p.emplace_back(level_data[i].get(), level_size[i]);
    return p;
}

size_t Ktx2Pieces::size() const {
    size_t n = header.size();
    for (size_t s : level_size) n += s;
    return n;
}

Result<Ktx2Pieces> ktx2_zstd_pieces(std::span<const uint8_t> raw, const ContainerLayout& layout, int zstd_level) {
    const size_t levels = layout.level_offset.size();
    Ktx2Pieces out;
    out.level_data.resize(levels);
    out.level_size.resize(levels);
    std::vector<size_t> raw_length(levels);
    std::vector<std::string> errors(levels);
    for (size_t i = 0; i < levels; ++i) raw_length[i] = size_t(get64(raw, kHeaderBytes + kLevelIndexEntry * i + 8));
    tbb::parallel_for(size_t(0), levels, [&](size_t i) {
        const size_t bound = ZSTD_compressBound(raw_length[i]);
        out.level_data[i].reset(new uint8_t[bound]);
        const size_t n = ZSTD_compress(out.level_data[i].get(), bound, raw.data() + layout.level_offset[i],
                                       raw_length[i], zstd_level);
        if (ZSTD_isError(n)) errors[i] = ZSTD_getErrorName(n);
        else out.level_size[i] = n;
    });
    for (const std::string& e : errors)
        if (!e.empty()) return make_error("zstd: " + e);
    out.header = ktx2_zstd_header(raw, out.level_size);
    return out;
}

std::vector<uint8_t> ktx2_zstd_header(std::span<const uint8_t> raw, const std::vector<size_t>& level_size) {
    // Header, index, descriptor and key/value data (the last part before the levels; no global data);
    // the alignment padding of the uncompressed layout is dropped.
    const size_t header_end = size_t(get32(raw, 56)) + get32(raw, 60);
    std::vector<uint8_t> header(raw.begin(), raw.begin() + long(header_end));
    put32(header, 44, 2);  // supercompressionScheme: Zstandard
    size_t at = header_end;
    for (size_t i = level_size.size(); i-- > 0;) {
        const size_t entry = kHeaderBytes + kLevelIndexEntry * i;
        const uint64_t raw_length = get64(raw, entry + 8);
        put64(header, entry, at);
        put64(header, entry + 8, level_size[i]);
        put64(header, entry + 16, raw_length);
        at += level_size[i];
    }
    return header;
}

Result<std::vector<uint8_t>> ktx2_zstd(std::span<const uint8_t> raw, const ContainerLayout& layout, int zstd_level) {
    auto packed = ktx2_zstd_pieces(raw, layout, zstd_level);
    if (!packed) return packed.error();
    std::vector<uint8_t> file;
    file.reserve(packed->size());
    for (std::span<const uint8_t> p : packed->pieces()) file.insert(file.end(), p.begin(), p.end());
    return file;
}

std::vector<uint8_t> encode_ktx2(const MipChain& chain, TexelEncoding encoding) {
    const int channels = chain.channels();
    const int levels = int(chain.levels.size());
    const ContainerLayout layout = ktx2_layout(chain.width(), chain.height(), levels, encoding, channels);
    std::vector<uint8_t> b(layout.total);
    ktx2_write_header(b.data(), layout, chain.width(), chain.height(), encoding, channels);
    SPECBAKE_ASSERT(layout.level_offset.size() == size_t(levels));
    for (int i = 0; i < levels; ++i) {
        const Image& level = chain.levels[size_t(i)];
        SPECBAKE_ASSERT(level.channels == channels && level.width == std::max(1, chain.width() >> i) &&
                        level.height == std::max(1, chain.height() >> i) && layout.level_offset[size_t(i)] < b.size());
        encode_texels_into(level.pixels.data(), level.texel_count(), channels, 0, channels, encoding,
                           layout.stored_channels, 1.0f, b.data() + layout.level_offset[size_t(i)]);
    }
    return b;
}

std::vector<uint8_t> encode_ktx2_array(const MipChain& stacked, int layers, TexelEncoding encoding) {
    const int channels = stacked.channels();
    const int levels = int(stacked.levels.size());
    const int height = stacked.height() / layers;
    const ContainerLayout layout = ktx2_layout(stacked.width(), height, levels, encoding, channels, layers);
    std::vector<uint8_t> b(layout.total);
    ktx2_write_header(b.data(), layout, stacked.width(), height, encoding, channels, layers);
    SPECBAKE_ASSERT(layout.level_offset.size() == size_t(levels) && stacked.height() % layers == 0);
    for (int i = 0; i < levels; ++i) {
        // KTX2 Sec. 3.9: within a level, layer after layer, each row after row: the stacked image as it is.
        const Image& level = stacked.levels[size_t(i)];
        encode_texels_into(level.pixels.data(), level.texel_count(), channels, 0, channels, encoding,
                           layout.stored_channels, 1.0f, b.data() + layout.level_offset[size_t(i)]);
    }
    return b;
}

Result<Ktx2Texture> read_ktx2_texture(std::span<const uint8_t> b, const std::string& name) {
    auto fail = [&](const std::string& what) -> Result<Ktx2Texture> { return make_error(name + ": " + what); };
    if (b.size() < kHeaderBytes || std::memcmp(b.data(), kKtx2Identifier, sizeof(kKtx2Identifier)) != 0)
        return fail("not a KTX2 file");
    Ktx2Texture t;
    Ktx2Info& info = t.info;
    info.vk_format = get32(b, 12);
    info.type_size = get32(b, 16);
    const uint32_t width = get32(b, 20), height = get32(b, 24);
    if (get32(b, 28) != 0 || get32(b, 36) != 1) return fail("not a plain 2D texture or 2D array");
    info.layer_count = get32(b, 32);
    if (info.layer_count > 65535) return fail("bad layer count");
    const uint32_t layers = std::max(1u, info.layer_count);
    info.level_count = get32(b, 40);
    info.supercompression = get32(b, 44);
    if (info.supercompression != 0 && info.supercompression != 2)
        return fail("supercompression scheme " + std::to_string(info.supercompression) + " is not supported (only zstd)");
    if (width == 0 || height == 0 || width > (1u << 15) || height > (1u << 15)) return fail("bad size");
    if (info.level_count == 0 || info.level_count > 16) return fail("bad level count");

    // Format from vkFormat.
    int channels = 0;
    bool found = false;
    for (TexelEncoding e : {TexelEncoding::Unorm8, TexelEncoding::Unorm16, TexelEncoding::Float16, TexelEncoding::Float32}) {
        for (int c = 1; c <= 4; ++c) {
            if (ktx2_vk_format(e, c) == info.vk_format) t.encoding = e, channels = c, found = true;
        }
    }
    if (!found) return fail("unsupported vkFormat " + std::to_string(info.vk_format));
    if (info.type_size != uint32_t(encoding_bytes(t.encoding))) return fail("typeSize does not match vkFormat");

    // Data format descriptor.
    const uint32_t dfd_offset = get32(b, 48), dfd_length = get32(b, 52);
    if (dfd_offset % 4 != 0 || size_t(dfd_offset) + dfd_length > b.size() || dfd_length < 28)
        return fail("bad data format descriptor location");
    if (get32(b, dfd_offset) != dfd_length) return fail("dfdTotalSize does not match dfdByteLength");
    const uint32_t block_size = get32(b, dfd_offset + 8) >> 16;
    if (4 + block_size != dfd_length || (block_size - 24) % 16 != 0) return fail("bad descriptor block size");
    const uint32_t model_word = get32(b, dfd_offset + 12);
    info.color_model = model_word & 0xFF;
    info.color_primaries = (model_word >> 8) & 0xFF;
    info.transfer = (model_word >> 16) & 0xFF;
    info.flags = model_word >> 24;
    info.bytes_plane0 = get32(b, dfd_offset + 20) & 0xFF;
    const uint32_t samples = (block_size - 24) / 16;
    for (uint32_t s = 0; s < samples; ++s) {
        const uint32_t w = get32(b, dfd_offset + 28 + 16 * s);
        info.sample_bit_lengths.push_back(((w >> 16) & 0xFF) + 1);
        info.sample_channel_ids.push_back((w >> 24) & 0x0F);
        info.sample_qualifiers.push_back((w >> 24) & 0xF0);
    }
    const size_t texel_bytes = size_t(channels) * info.type_size;
    if (samples != uint32_t(channels) || info.bytes_plane0 != texel_bytes)
        return fail("data format descriptor does not match vkFormat");

    // Key/value data.
    const uint32_t kvd_offset = get32(b, 56), kvd_length = get32(b, 60);
    if (size_t(kvd_offset) + kvd_length > b.size()) return fail("bad key/value data location");
    for (size_t at = kvd_offset; at + 4 <= size_t(kvd_offset) + kvd_length;) {
        const uint32_t len = get32(b, at);
        if (at + 4 + len > size_t(kvd_offset) + kvd_length) return fail("bad key/value entry");
        const std::string entry(reinterpret_cast<const char*>(b.data() + at + 4), len);
        const size_t nul = entry.find('\0');
        if (nul != std::string::npos && entry.substr(0, nul) == "KTXwriter") {
            info.writer = entry.substr(nul + 1);
            while (!info.writer.empty() && info.writer.back() == '\0') info.writer.pop_back();
        }
        at = align_up(at + 4 + len, 4);
    }

    // Levels.
    if (kHeaderBytes + kLevelIndexEntry * info.level_count > b.size()) return fail("truncated level index");
    const bool zstd = info.supercompression == 2;
    const size_t alignment = zstd ? 1 : std::lcm(texel_bytes, size_t(4));
    for (uint32_t i = 0; i < info.level_count; ++i) {
        const size_t at = kHeaderBytes + kLevelIndexEntry * i;
        const uint64_t off = get64(b, at), len = get64(b, at + 8), ulen = get64(b, at + 16);
        const int w = std::max(1, int(width >> i)), h = std::max(1, int(height >> i));
        const std::string level = "level " + std::to_string(i);
        const uint64_t level_bytes = uint64_t(w) * uint64_t(h) * texel_bytes * layers;
        if (ulen != level_bytes || (!zstd && len != ulen)) return fail(level + " has the wrong size");
        if (off % alignment != 0) return fail(level + " is not aligned");
        if (off > b.size() || len > b.size() - off) return fail("truncated " + level);
        info.level_offsets.push_back(off);
        info.level_lengths.push_back(len);
        if (!zstd) {
            t.chain.levels.push_back(decode_texels(b.subspan(off, len), t.encoding, w, h * int(layers), channels));
            continue;
        }
        std::vector<uint8_t> inflated(ulen);
        const size_t n = ZSTD_decompress(inflated.data(), inflated.size(), b.data() + off, len);
        if (ZSTD_isError(n)) return fail(level + ": zstd: " + ZSTD_getErrorName(n));
        if (n != ulen) return fail(level + " inflates to " + std::to_string(n) + " bytes, not " + std::to_string(ulen));
        t.chain.levels.push_back(decode_texels(inflated, t.encoding, w, h * int(layers), channels));
    }
    return t;
}

}  // namespace specbake::io
