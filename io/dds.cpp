#include "io/dds.h"

#include "io/texel_encoding.h"

#include <algorithm>
#include <cstring>

namespace specbake::io {
namespace {

constexpr uint32_t kMagic = 0x20534444;  // "DDS "
constexpr uint32_t kFlagsRequired = 0x1 | 0x2 | 0x4 | 0x1000;  // CAPS | HEIGHT | WIDTH | PIXELFORMAT
constexpr uint32_t kFlagPitch = 0x8, kFlagMipCount = 0x20000;
constexpr uint32_t kPixelFormatFourCC = 0x4;
constexpr uint32_t kFourCCDx10 = 0x30315844;  // "DX10"
constexpr uint32_t kCapsTexture = 0x1000, kCapsComplex = 0x8, kCapsMipmap = 0x400000;
constexpr uint32_t kDimensionTexture2D = 3;
constexpr uint32_t kAlphaModeUnknown = 0, kAlphaModeOpaque = 3;

constexpr size_t kHeaderBytes = 4 + 124 + 20;  // magic, DDS_HEADER, DDS_HEADER_DXT10

void put32(std::vector<uint8_t>& b, size_t at, uint32_t v) { std::memcpy(b.data() + at, &v, 4); }

}  // namespace

uint32_t dds_dxgi_format(TexelEncoding e, int channels, int* stored_channels) {
    // DXGI_FORMAT values: R8 61, R8G8 49, R8G8B8A8 28; R16 UNORM 56, R16G16 35, R16G16B16A16 11;
    // R16 FLOAT 54, R16G16 34, R16G16B16A16 10; R32 FLOAT 41, R32G32 16, R32G32B32 6, R32G32B32A32 2.
    int stored = channels == 3 && e != TexelEncoding::Float32 ? 4 : channels;
    if (stored_channels) *stored_channels = stored;
    static const uint32_t table[4][4] = {{61, 49, 0, 28}, {56, 35, 0, 11}, {54, 34, 0, 10}, {41, 16, 6, 2}};
    const int row = e == TexelEncoding::Unorm8 ? 0 : e == TexelEncoding::Unorm16 ? 1 : e == TexelEncoding::Float16 ? 2 : 3;
    return table[row][stored - 1];
}

ContainerLayout dds_layout(int width, int height, int levels, TexelEncoding encoding, int channels) {
    ContainerLayout layout;
    dds_dxgi_format(encoding, channels, &layout.stored_channels);
    const size_t texel_bytes = size_t(layout.stored_channels) * size_t(encoding_bytes(encoding));
    size_t at = kHeaderBytes;
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
    std::vector<uint8_t> b(kHeaderBytes, 0);
    put32(b, 0, kMagic);
    const size_t h = 4;  // DDS_HEADER
    put32(b, h + 0, 124);
    put32(b, h + 4, kFlagsRequired | kFlagPitch | kFlagMipCount);
    put32(b, h + 8, uint32_t(height));
    put32(b, h + 12, uint32_t(width));
    put32(b, h + 16, uint32_t(size_t(width) * texel_bytes));  // pitch of the top level
    put32(b, h + 24, uint32_t(layout.level_offset.size()));
    put32(b, h + 72, 32);  // DDS_PIXELFORMAT
    put32(b, h + 76, kPixelFormatFourCC);
    put32(b, h + 80, kFourCCDx10);
    put32(b, h + 104, kCapsTexture | kCapsComplex | kCapsMipmap);
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
    for (int L = 0; L < levels; ++L) {
        const Image& level = chain.levels[size_t(L)];
        encode_texels_into(level.pixels.data(), level.texel_count(), channels, 0, channels, encoding,
                           layout.stored_channels, 1.0f, b.data() + layout.level_offset[size_t(L)]);
    }
    return b;
}

}  // namespace specbake::io
