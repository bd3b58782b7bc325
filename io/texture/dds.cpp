#include "io/texture/dds.h"

#include "core/assert.h"
#include "io/texture/byte_order.h"
#include "io/texture/texel_encoding.h"

#include <algorithm>
#include <cstring>

namespace specbake::io {
namespace {

constexpr uint32_t kMagic = 0x20534444;  // "DDS "
constexpr uint32_t kFlagsRequired = 0x1 | 0x2 | 0x4 | 0x1000;  // CAPS | HEIGHT | WIDTH | PIXELFORMAT
constexpr uint32_t kFlagPitch = 0x8, kFlagMipCount = 0x20000;
constexpr uint32_t kPixelFormatFourCC = 0x4, kPixelFormatAlpha = 0x1, kPixelFormatRgb = 0x40;
constexpr uint32_t kPixelFormatLuminance = 0x20000;
constexpr uint32_t kFourCCDx10 = 0x30315844;  // "DX10"
constexpr uint32_t kCapsTexture = 0x1000, kCapsComplex = 0x8, kCapsMipmap = 0x400000;
constexpr uint32_t kDimensionTexture2D = 3;
constexpr uint32_t kAlphaModeUnknown = 0, kAlphaModeOpaque = 3;

constexpr size_t kLegacyHeaderBytes = 4 + 124;          // magic, DDS_HEADER
constexpr size_t kDx10HeaderBytes = kLegacyHeaderBytes + 20;  // + DDS_HEADER_DXT10


size_t header_bytes(TexelEncoding e, int channels) {
    return dds_legacy_pixel_format(e, channels) ? kLegacyHeaderBytes : kDx10HeaderBytes;
}

}  // namespace

std::optional<DdsLegacyPixelFormat> dds_legacy_pixel_format(TexelEncoding e, int channels) {
    // The D3D9 forms Microsoft's DDS reference (and DirectXTex's DDSTextureLoader) map to these DXGI
    // formats: L8 -> R8_UNORM, A8L8 -> R8G8_UNORM, A8R8G8B8 masks -> B8G8R8A8_UNORM (the same RGBA8 data
    // in B, G, R, A byte order), L16 -> R16_UNORM, FourCC 36 (D3DFMT_A16B16G16R16) -> R16G16B16A16_UNORM.
    // RGBA8 is stored as A8R8G8B8 rather than A8B8G8R8 because three.js DDSLoader reads only that order
    // (its uncompressed case requires red in 0x00FF0000); Pillow and OpenImageIO read both. Float formats
    // have only numeric FourCCs (111-116) that common readers reject, so they keep the DX10 header.
    const int stored = gpu_channels(channels);
    if (e == TexelEncoding::Unorm8) {
        if (stored == 1) return DdsLegacyPixelFormat{kPixelFormatLuminance, 0, 8, 0xFF, 0, 0, 0, "L8"};
        if (stored == 2)
            return DdsLegacyPixelFormat{kPixelFormatLuminance | kPixelFormatAlpha, 0, 16, 0xFF, 0, 0, 0xFF00, "A8L8"};
        return DdsLegacyPixelFormat{kPixelFormatRgb | kPixelFormatAlpha, 0, 32, 0xFF0000, 0xFF00, 0xFF, 0xFF000000u,
                                    "A8R8G8B8", true};
    }
    if (e == TexelEncoding::Unorm16) {
        if (stored == 1) return DdsLegacyPixelFormat{kPixelFormatLuminance, 0, 16, 0xFFFF, 0, 0, 0, "L16"};
        // G16R16 (RGB bit masks 0xFFFF, 0xFFFF0000) exists, but OpenImageIO 2.4 takes it for 8-bit RGB and
        // hangs reading it: R16G16 keeps the DX10 header.
        if (stored == 2) return std::nullopt;
        return DdsLegacyPixelFormat{kPixelFormatFourCC, 36, 0, 0, 0, 0, 0, "A16B16G16R16"};
    }
    return std::nullopt;
}

void dds_swap_red_blue(uint8_t* texels, size_t count) {
    for (size_t i = 0; i < count; ++i, texels += 4) std::swap(texels[0], texels[2]);
}

uint32_t dds_dxgi_format(TexelEncoding e, int channels, int* stored_channels) {
    // DXGI_FORMAT values: R8 61, R8G8 49, R8G8B8A8 28 (written as the legacy A8R8G8B8, whose DXGI
    // equivalent is B8G8R8A8 87); R16 UNORM 56, R16G16 35, R16G16B16A16 11; R16 FLOAT 54, R16G16 34, R16G16B16A16 10; R32 FLOAT 41, R32G32 16, R32G32B32A32 2.
    const int stored = gpu_channels(channels);
    if (stored_channels) *stored_channels = stored;
    static const uint32_t table[4][4] = {{61, 49, 0, 87}, {56, 35, 0, 11}, {54, 34, 0, 10}, {41, 16, 0, 2}};
    const int row = e == TexelEncoding::Unorm8 ? 0 : e == TexelEncoding::Unorm16 ? 1 : e == TexelEncoding::Float16 ? 2 : 3;
    return table[row][stored - 1];
}

ContainerLayout dds_layout(int width, int height, int levels, TexelEncoding encoding, int channels) {
    ContainerLayout layout;
    dds_dxgi_format(encoding, channels, &layout.stored_channels);
    const size_t texel_bytes = size_t(layout.stored_channels) * size_t(encoding_bytes(encoding));
    size_t at = header_bytes(encoding, channels);
    for (int L = 0; L < levels; ++L) {
        layout.level_offset.push_back(at);
        at += size_t(std::max(1, width >> L)) * size_t(std::max(1, height >> L)) * texel_bytes;
    }
    layout.total = at;
    return layout;
}

void dds_write_header(uint8_t* file, const ContainerLayout& layout, int width, int height, TexelEncoding encoding,
                      int channels) {
    int stored = 0;
    const uint32_t format = dds_dxgi_format(encoding, channels, &stored);
    const size_t texel_bytes = size_t(stored) * size_t(encoding_bytes(encoding));
    const std::optional<DdsLegacyPixelFormat> legacy = dds_legacy_pixel_format(encoding, channels);
    std::vector<uint8_t> b(legacy ? kLegacyHeaderBytes : kDx10HeaderBytes, 0);
    put32(b, 0, kMagic);
    const size_t h = 4;  // DDS_HEADER
    put32(b, h + 0, 124);
    put32(b, h + 4, kFlagsRequired | kFlagPitch | kFlagMipCount);
    put32(b, h + 8, uint32_t(height));
    put32(b, h + 12, uint32_t(width));
    put32(b, h + 16, uint32_t(size_t(width) * texel_bytes));  // pitch of the top level
    put32(b, h + 24, uint32_t(layout.level_offset.size()));
    put32(b, h + 72, 32);  // DDS_PIXELFORMAT
    put32(b, h + 104, kCapsTexture | kCapsComplex | kCapsMipmap);
    if (legacy) {
        put32(b, h + 76, legacy->flags);
        put32(b, h + 80, legacy->fourcc);
        put32(b, h + 84, legacy->rgb_bit_count);
        put32(b, h + 88, legacy->r_mask);
        put32(b, h + 92, legacy->g_mask);
        put32(b, h + 96, legacy->b_mask);
        put32(b, h + 100, legacy->a_mask);
        std::memcpy(file, b.data(), b.size());
        return;
    }
    put32(b, h + 76, kPixelFormatFourCC);
    put32(b, h + 80, kFourCCDx10);
    const size_t x = h + 124;  // DDS_HEADER_DXT10
    put32(b, x + 0, format);
    put32(b, x + 4, kDimensionTexture2D);
    put32(b, x + 8, 0);
    put32(b, x + 12, 1);  // arraySize
    put32(b, x + 16, stored != channels ? kAlphaModeOpaque : kAlphaModeUnknown);
    std::memcpy(file, b.data(), b.size());
}

std::vector<uint8_t> encode_dds(const MipChain& chain, TexelEncoding encoding) {
    const int channels = chain.channels();
    const int levels = int(chain.levels.size());
    const ContainerLayout layout = dds_layout(chain.width(), chain.height(), levels, encoding, channels);
    std::vector<uint8_t> b(layout.total);
    dds_write_header(b.data(), layout, chain.width(), chain.height(), encoding, channels);
    SPECBAKE_ASSERT(layout.level_offset.size() == size_t(levels));
    for (int L = 0; L < levels; ++L) {
        const Image& level = chain.levels[size_t(L)];
        SPECBAKE_ASSERT(level.channels == channels && level.width == std::max(1, chain.width() >> L) &&
                        level.height == std::max(1, chain.height() >> L) && layout.level_offset[size_t(L)] < b.size());
        uint8_t* dst = b.data() + layout.level_offset[size_t(L)];
        encode_texels_into(level.pixels.data(), level.texel_count(), channels, 0, channels, encoding,
                           layout.stored_channels, 1.0f, dst);
        if (const auto legacy = dds_legacy_pixel_format(encoding, channels); legacy && legacy->bgra)
            dds_swap_red_blue(dst, level.texel_count());
    }
    return b;
}

}  // namespace specbake::io
