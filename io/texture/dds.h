// DirectDraw Surface, uncompressed 2D texture with a full mip chain. 8- and 16-bit unorm data use the
// legacy header alone (a DDS_PIXELFORMAT with luminance / RGB bit masks or a FourCC), which common DDS
// readers load (Pillow, OpenImageIO; three.js DDSLoader the RGBA8 form, A8R8G8B8, the only uncompressed
// one it implements); float data, which has no legacy form
// common readers accept, uses the DX10 extension header (DDS_HEADER + DDS_HEADER_DXT10). 3-channel data is stored as RGBA with alpha = 1 (DXGI has no 3-channel
// 8/16-bit formats; float32 follows the same rule so every container has the same layout).
#pragma once

#include "core/image.h"
#include "io/texture/texel_encoding.h"
#include "io/texture/texture_writer.h"

#include <cstdint>
#include <optional>
#include <vector>

namespace specbake::io {

// The legacy DDS_PIXELFORMAT of `channels` (1-4, stored as gpu_channels) as `encoding`, if there is one.
struct DdsLegacyPixelFormat {
    uint32_t flags, fourcc, rgb_bit_count, r_mask, g_mask, b_mask, a_mask;
    const char* name;  // D3D9 name: "L8", "A8L8", "A8R8G8B8", "L16", "A16B16G16R16"
    bool bgra = false;  // texels stored B, G, R, A (A8R8G8B8): the writer swaps R and B of each texel
};
std::optional<DdsLegacyPixelFormat> dds_legacy_pixel_format(TexelEncoding encoding, int channels);

// Swaps the first and third byte of each of `count` 4-byte texels (RGBA8 <-> BGRA8, A8R8G8B8 order).
void dds_swap_red_blue(uint8_t* texels, size_t count);

// DXGI_FORMAT for `channels` (1-4) as `encoding` (the DX10 header's, or the legacy form's equivalent); `stored_channels` receives the channel count in the file.
uint32_t dds_dxgi_format(TexelEncoding encoding, int channels, int* stored_channels);

// The whole file.
std::vector<uint8_t> encode_dds(const MipChain& chain, TexelEncoding encoding);

// Layout of the file encode_dds writes for a width x height chain of `levels` levels of `channels`.
ContainerLayout dds_layout(int width, int height, int levels, TexelEncoding encoding, int channels);

// Writes the DDS header (and the DX10 header where there is no legacy form) of that file into `file`
// (layout.total bytes); level data untouched.
void dds_write_header(uint8_t* file, const ContainerLayout& layout, int width, int height, TexelEncoding encoding,
                      int channels);

}  // namespace specbake::io
