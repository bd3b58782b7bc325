// BC1/BC3/BC4/BC5 block encoders and the KTX2 / legacy-DDS files around block-compressed mip levels.
// Block layouts: Khronos Data Format Specification 1.3 Sec. 21.1 (BC1), 21.3 (BC3), 21.4 (BC4), 21.5 (BC5).
#include "io/texture/block_compress.h"
#include "io/texture/astc_codec.h"

#include <tbb/parallel_for.h>
#include <zstd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

namespace specbake::io {
namespace {

void put32(uint8_t* b, uint32_t v) { std::memcpy(b, &v, 4); }
void put64(uint8_t* b, uint64_t v) { std::memcpy(b, &v, 8); }

// BC4 (KDFS Sec. 21.4): red_0, red_1, then 16 3-bit indices, texel 0 in the lowest bits.
void bc4_block(const uint8_t* v, int stride, uint8_t* out) {
    int lo = 255, hi = 0;
    for (int i = 0; i < 16; ++i) lo = std::min(lo, int(v[i * stride])), hi = std::max(hi, int(v[i * stride]));
    out[0] = uint8_t(hi);
    out[1] = uint8_t(lo);
    uint64_t bits = 0;
    if (hi > lo) {
        // red_0 > red_1: value i = ((7 - i) red_0 + i red_1) / 7 for i = 0..7 in palette order 0, 1 = the ends,
        // 2..7 the interpolants from red_0 towards red_1. Nearest by |7 v - (7 - t) hi - t lo| over t = 0..7.
        static constexpr int kIndexOfStep[8] = {0, 2, 3, 4, 5, 6, 7, 1};  // t steps from red_0 to red_1
        for (int i = 0; i < 16; ++i) {
            const int x = 7 * int(v[i * stride]);
            int best = 0, best_err = 1 << 30;
            for (int t = 0; t < 8; ++t) {
                const int err = std::abs(x - ((7 - t) * hi + t * lo));
                if (err < best_err) best_err = err, best = t;
            }
            bits |= uint64_t(kIndexOfStep[best]) << (3 * i);
        }
    }
    for (int k = 0; k < 6; ++k) out[2 + k] = uint8_t(bits >> (8 * k));
}

uint16_t to565(const float c[3]) {
    const int r = std::clamp(int(std::lround(c[0] * 31.0f / 255.0f)), 0, 31);
    const int g = std::clamp(int(std::lround(c[1] * 63.0f / 255.0f)), 0, 63);
    const int b = std::clamp(int(std::lround(c[2] * 31.0f / 255.0f)), 0, 31);
    return uint16_t(r << 11 | g << 5 | b);
}

// The 8-bit colour a decoder expands RGB565 to (bit replication).
std::array<int, 3> from565(uint16_t c) {
    const int r = c >> 11 & 31, g = c >> 5 & 63, b = c & 31;
    return {r << 3 | r >> 2, g << 2 | g >> 4, b << 3 | b >> 2};
}

// BC1 colour block in its 4-colour mode (KDFS Sec. 21.1): colour_0 > colour_1 as 16-bit numbers, palette
// c0, c1, (2 c0 + c1) / 3, (c0 + 2 c1) / 3; 2-bit indices, texel 0 lowest.
void bc1_block(const uint8_t* t, int stride, uint8_t* out) {
    float mean[3] = {0, 0, 0};
    for (int i = 0; i < 16; ++i)
        for (int c = 0; c < 3; ++c) mean[c] += float(t[i * stride + c]) / 16.0f;
    float cov[6] = {0, 0, 0, 0, 0, 0};  // xx, xy, xz, yy, yz, zz
    for (int i = 0; i < 16; ++i) {
        const float d[3] = {t[i * stride] - mean[0], t[i * stride + 1] - mean[1], t[i * stride + 2] - mean[2]};
        cov[0] += d[0] * d[0], cov[1] += d[0] * d[1], cov[2] += d[0] * d[2];
        cov[3] += d[1] * d[1], cov[4] += d[1] * d[2], cov[5] += d[2] * d[2];
    }
    // Power iteration towards the principal axis, from the axis of the channel with the largest variance
    // (a start orthogonal to the principal axis, as (1, 1, 1) is for anti-correlated channels, would stall).
    const int start = cov[0] >= cov[3] && cov[0] >= cov[5] ? 0 : cov[3] >= cov[5] ? 1 : 2;
    float axis[3] = {start == 0 ? 1.0f : 0.0f, start == 1 ? 1.0f : 0.0f, start == 2 ? 1.0f : 0.0f};
    for (int it = 0; it < 8; ++it) {
        const float n[3] = {cov[0] * axis[0] + cov[1] * axis[1] + cov[2] * axis[2],
                            cov[1] * axis[0] + cov[3] * axis[1] + cov[4] * axis[2],
                            cov[2] * axis[0] + cov[4] * axis[1] + cov[5] * axis[2]};
        const float len = std::max({std::fabs(n[0]), std::fabs(n[1]), std::fabs(n[2])});
        if (len < 1e-6f) break;
        for (int c = 0; c < 3; ++c) axis[c] = n[c] / len;
    }
    float lo = 1e30f, hi = -1e30f;
    for (int i = 0; i < 16; ++i) {
        const float p = (t[i * stride] - mean[0]) * axis[0] + (t[i * stride + 1] - mean[1]) * axis[1] +
                        (t[i * stride + 2] - mean[2]) * axis[2];
        lo = std::min(lo, p), hi = std::max(hi, p);
    }
    const float norm2 = axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2];
    float e0[3], e1[3];
    for (int c = 0; c < 3; ++c) {
        e0[c] = mean[c] + axis[c] * hi / norm2;
        e1[c] = mean[c] + axis[c] * lo / norm2;
    }
    uint16_t c0 = to565(e0), c1 = to565(e1);
    if (c0 < c1) std::swap(c0, c1);
    uint32_t bits = 0;
    if (c0 != c1) {
        const std::array<int, 3> a = from565(c0), b = from565(c1);
        std::array<std::array<int, 3>, 4> palette{a, b, {}, {}};
        for (int c = 0; c < 3; ++c) {
            palette[2][size_t(c)] = (2 * a[size_t(c)] + b[size_t(c)]) / 3;
            palette[3][size_t(c)] = (a[size_t(c)] + 2 * b[size_t(c)]) / 3;
        }
        for (int i = 0; i < 16; ++i) {
            int best = 0, best_err = 1 << 30;
            for (int k = 0; k < 4; ++k) {
                int err = 0;
                for (int c = 0; c < 3; ++c) {
                    const int d = int(t[i * stride + c]) - palette[size_t(k)][size_t(c)];
                    err += d * d;
                }
                if (err < best_err) best_err = err, best = k;
            }
            bits |= uint32_t(best) << (2 * i);
        }
    }
    // c0 == c1 (a flat block): every index 0 selects colour_0 in either mode.
    out[0] = uint8_t(c0), out[1] = uint8_t(c0 >> 8), out[2] = uint8_t(c1), out[3] = uint8_t(c1 >> 8);
    put32(out + 4, bits);
}

}  // namespace

const char* block_format_name(BlockFormat f) {
    switch (f) {
        case BlockFormat::None: return "none";
        case BlockFormat::Bc1: return "bc1";
        case BlockFormat::Bc3: return "bc3";
        case BlockFormat::Bc4: return "bc4";
        case BlockFormat::Bc5: return "bc5";
        case BlockFormat::AstcR:
        case BlockFormat::AstcRg:
        case BlockFormat::AstcRgba: return "astc";
    }
    return "none";
}

bool is_astc(BlockFormat f) {
    return f == BlockFormat::AstcR || f == BlockFormat::AstcRg || f == BlockFormat::AstcRgba;
}

size_t block_bytes(BlockFormat f) { return f == BlockFormat::Bc1 || f == BlockFormat::Bc4 ? 8 : 16; }

int block_channels(BlockFormat f) {
    switch (f) {
        case BlockFormat::Bc4:
        case BlockFormat::AstcR: return 1;
        case BlockFormat::Bc5:
        case BlockFormat::AstcRg: return 2;
        default: return 4;
    }
}

std::string block_gpu_format_name(BlockFormat f, int astc_side) {
    switch (f) {
        case BlockFormat::Bc1: return "BC1_RGB_UNORM_BLOCK";
        case BlockFormat::Bc3: return "BC3_UNORM_BLOCK";
        case BlockFormat::Bc4: return "BC4_UNORM_BLOCK";
        case BlockFormat::Bc5: return "BC5_UNORM_BLOCK";
        case BlockFormat::AstcR:
        case BlockFormat::AstcRg:
        case BlockFormat::AstcRgba: {
            const std::string side = std::to_string(astc_side);
            return "ASTC_" + side + "x" + side + "_UNORM_BLOCK";
        }
        case BlockFormat::None: break;
    }
    return "";
}

uint32_t block_vk_format(BlockFormat f, int astc_side) {
    switch (f) {
        case BlockFormat::Bc1: return 131;
        case BlockFormat::Bc3: return 137;
        case BlockFormat::Bc4: return 139;
        case BlockFormat::Bc5: return 141;
        case BlockFormat::AstcR:
        case BlockFormat::AstcRg:
        case BlockFormat::AstcRgba: return astc_vk_format(astc_side);
        case BlockFormat::None: break;
    }
    return 0;
}

const char* block_fourcc(BlockFormat f) {
    switch (f) {
        case BlockFormat::Bc1: return "DXT1";
        case BlockFormat::Bc3: return "DXT5";
        case BlockFormat::Bc4: return "ATI1";
        case BlockFormat::Bc5: return "ATI2";
        default: break;
    }
    return "";
}

void encode_block(BlockFormat format, const uint8_t* texels, uint8_t* out) {
    switch (format) {
        case BlockFormat::Bc4: bc4_block(texels, 1, out); return;
        case BlockFormat::Bc5:
            bc4_block(texels, 2, out);
            bc4_block(texels + 1, 2, out + 8);
            return;
        case BlockFormat::Bc1: bc1_block(texels, 4, out); return;
        case BlockFormat::Bc3:
            bc4_block(texels + 3, 4, out);
            bc1_block(texels, 4, out + 8);
            return;
        default: return;  // None; ASTC levels are encoded whole (astc_compress_level)
    }
}

std::vector<uint8_t> compress_level(BlockFormat format, const uint8_t* texels, int width, int height, int channels) {
    const int bw = (width + 3) / 4, bh = (height + 3) / 4, n = block_channels(format);
    const size_t bytes = block_bytes(format);
    std::vector<uint8_t> out(size_t(bw) * size_t(bh) * bytes);
    tbb::parallel_for(0, bh, [&](int by) {
        uint8_t block[16 * 4];
        for (int bx = 0; bx < bw; ++bx) {
            for (int j = 0; j < 4; ++j)
                for (int i = 0; i < 4; ++i) {
                    const int x = std::min(bx * 4 + i, width - 1), y = std::min(by * 4 + j, height - 1);
                    const uint8_t* src = texels + (size_t(y) * size_t(width) + size_t(x)) * size_t(channels);
                    for (int c = 0; c < n; ++c) block[(j * 4 + i) * n + c] = c < channels ? src[c] : 255;
                }
            encode_block(format, block, out.data() + (size_t(by) * size_t(bw) + size_t(bx)) * bytes);
        }
    });
    return out;
}

std::vector<std::span<const uint8_t>> BlockFile::pieces() const {
    std::vector<std::span<const uint8_t>> p{std::span<const uint8_t>(header)};
    for (const std::vector<uint8_t>& l : levels) p.emplace_back(l);
    return p;
}

namespace {

// Basic descriptor of a block-compressed format (KDFS 1.3 Sec. 5, 21 and 23): colour model BC1A 128, BC3
// 130, BC4 131, BC5 132, ASTC 162; 4x4 texel blocks (ASTC: its footprint); one 64-bit sample per 8 bytes of
// BC block, one 128-bit sample of channel 0 (ASTC data) for ASTC.
std::vector<uint8_t> block_dfd(BlockFormat f, int astc_side) {
    if (is_astc(f)) {
        std::vector<uint8_t> d(4 + 24 + 16, 0);
        put32(d.data(), uint32_t(d.size()));
        put32(d.data() + 8, 2u | (40u << 16));
        put32(d.data() + 12, 162u | (1u << 8) | (1u << 16));  // ASTC, BT.709 primaries, linear transfer
        const uint32_t side = uint32_t(astc_side - 1);
        put32(d.data() + 16, side | side << 8);  // footprint NxNx1x1 (stored minus one)
        put32(d.data() + 20, 16);               // bytesPlane0
        put32(d.data() + 28, 127u << 16);       // bit offset 0, 128 bits, channel 0 (ASTC data)
        put32(d.data() + 40, 0xFFFFFFFFu);      // sampleUpper
        return d;
    }
    const int samples = f == BlockFormat::Bc3 || f == BlockFormat::Bc5 ? 2 : 1;
    const uint32_t block_size = 24 + 16 * uint32_t(samples);
    std::vector<uint8_t> d(4 + block_size, 0);
    const uint32_t model = f == BlockFormat::Bc1 ? 128 : f == BlockFormat::Bc3 ? 130 : f == BlockFormat::Bc4 ? 131 : 132;
    put32(d.data(), uint32_t(d.size()));
    put32(d.data() + 4, 0);
    put32(d.data() + 8, 2u | (block_size << 16));
    put32(d.data() + 12, model | (1u << 8) | (1u << 16));  // BT.709 primaries, linear transfer, straight alpha
    put32(d.data() + 16, 3u | 3u << 8);                    // texel block 4x4x1x1 (stored minus one)
    put32(d.data() + 20, uint32_t(block_bytes(f)));        // bytesPlane0
    for (int s = 0; s < samples; ++s) {
        // BC3: alpha (channel 15) in the first 64 bits, colour (0) after; BC5: red (0) then green (1).
        const uint32_t channel = f == BlockFormat::Bc3 ? (s == 0 ? 15u : 0u) : uint32_t(s);
        uint8_t* at = d.data() + 28 + 16 * s;
        put32(at, uint32_t(64 * s) | (63u << 16) | (channel << 24));
        put32(at + 4, 0);
        put32(at + 8, 0);
        put32(at + 12, 0xFFFFFFFFu);
    }
    return d;
}

}  // namespace

Result<BlockFile> block_file(TextureContainer container, BlockFormat format, int width, int height,
                             std::vector<std::vector<uint8_t>> levels, int zstd_level, int astc_side) {
    if (format == BlockFormat::None || levels.empty()) return make_error("no block format or no levels");
    if (is_astc(format) && container != TextureContainer::Ktx2) return make_error("ASTC is written to KTX2 only");
    if (is_astc(format) && !astc_block_supported(astc_side))
        return make_error("ASTC footprint " + std::to_string(astc_side) + " is not 4, 6 or 8");
    const size_t count = levels.size();
    BlockFile file;
    if (container == TextureContainer::Dds) {
        // Legacy header with a FourCC (DDPF_FOURCC) and the top level's size (DDSD_LINEARSIZE).
        file.header.assign(128, 0);
        uint8_t* h = file.header.data();
        std::memcpy(h, "DDS ", 4);
        put32(h + 4, 124);
        put32(h + 8, 0x1 | 0x2 | 0x4 | 0x1000 | 0x20000 | 0x80000);
        put32(h + 12, uint32_t(height));
        put32(h + 16, uint32_t(width));
        put32(h + 20, uint32_t(levels[0].size()));
        put32(h + 28, uint32_t(count));
        put32(h + 76, 32);
        put32(h + 80, 0x4);
        std::memcpy(h + 84, block_fourcc(format), 4);
        put32(h + 108, 0x1000 | 0x8 | 0x400000);  // TEXTURE | COMPLEX | MIPMAP
        file.levels = std::move(levels);
        return file;
    }
    if (container != TextureContainer::Ktx2) return make_error("block compression is written to KTX2 and DDS only");
    // Supercompress each level independently (deterministic whatever the thread count).
    std::vector<size_t> raw_size(count);
    for (size_t i = 0; i < count; ++i) raw_size[i] = levels[i].size();
    if (zstd_level > 0) {
        std::vector<std::string> errors(count);
        tbb::parallel_for(size_t(0), count, [&](size_t i) {
            std::vector<uint8_t> packed(ZSTD_compressBound(levels[i].size()));
            const size_t n = ZSTD_compress(packed.data(), packed.size(), levels[i].data(), levels[i].size(), zstd_level);
            if (ZSTD_isError(n)) errors[i] = ZSTD_getErrorName(n);
            packed.resize(ZSTD_isError(n) ? 0 : n);
            levels[i] = std::move(packed);
        });
        for (const std::string& e : errors)
            if (!e.empty()) return make_error("zstd: " + e);
    }
    const std::vector<uint8_t> dfd = block_dfd(format, astc_side);
    static const char key[] = "KTXwriter", value[] = "specbake";
    const uint32_t kv_length = uint32_t(sizeof(key) + sizeof(value));
    const size_t kvd_bytes = (4 + kv_length + 3) / 4 * 4;
    const size_t dfd_offset = 80 + 24 * count, kvd_offset = dfd_offset + dfd.size();
    size_t at = kvd_offset + kvd_bytes;
    // Levels smallest first; uncompressed levels aligned to lcm(block bytes, 4), zstd ones to 1.
    const size_t alignment = zstd_level > 0 ? 1 : block_bytes(format);
    std::vector<size_t> offset(count);
    for (size_t i = count; i-- > 0;) {
        at = (at + alignment - 1) / alignment * alignment;
        offset[i] = at;
        at += levels[i].size();
    }
    file.header.assign(offset[count - 1], 0);
    uint8_t* b = file.header.data();
    static const uint8_t kId[12] = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n'};
    std::memcpy(b, kId, 12);
    put32(b + 12, block_vk_format(format, astc_side));
    put32(b + 16, 1);  // typeSize of block formats
    put32(b + 20, uint32_t(width));
    put32(b + 24, uint32_t(height));
    put32(b + 36, 1);  // faceCount
    put32(b + 40, uint32_t(count));
    put32(b + 44, zstd_level > 0 ? 2 : 0);
    put32(b + 48, uint32_t(dfd_offset));
    put32(b + 52, uint32_t(dfd.size()));
    put32(b + 56, uint32_t(kvd_offset));
    put32(b + 60, uint32_t(kvd_bytes));
    for (size_t i = 0; i < count; ++i) {
        put64(b + 80 + 24 * i, offset[i]);
        put64(b + 80 + 24 * i + 8, levels[i].size());
        put64(b + 80 + 24 * i + 16, raw_size[i]);
    }
    std::memcpy(b + dfd_offset, dfd.data(), dfd.size());
    put32(b + kvd_offset, kv_length);
    std::memcpy(b + kvd_offset + 4, key, sizeof(key));
    std::memcpy(b + kvd_offset + 4 + sizeof(key), value, sizeof(value));
    // Header (up to the smallest level), then the levels smallest first, each after its alignment padding.
    std::vector<std::vector<uint8_t>> ordered;
    size_t end = offset[count - 1];
    for (size_t i = count; i-- > 0;) {
        const size_t stored = levels[i].size();
        std::vector<uint8_t> piece(offset[i] - end, 0);
        if (piece.empty()) piece = std::move(levels[i]);
        else piece.insert(piece.end(), levels[i].begin(), levels[i].end());
        ordered.push_back(std::move(piece));
        end = offset[i] + stored;
    }
    file.levels = std::move(ordered);
    return file;
}

}  // namespace specbake::io
