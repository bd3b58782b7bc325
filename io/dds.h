// DirectDraw Surface with the DX10 extension header (DDS_HEADER + DDS_HEADER_DXT10), uncompressed 2D
// texture with a full mip chain. DXGI has no 3-channel 8/16-bit formats: RGB data is stored as RGBA
// with alpha = 1 (RGB float32 uses DXGI_FORMAT_R32G32B32_FLOAT).
#pragma once

#include "core/image.h"
#include "io/texel_encoding.h"
#include "io/texture_writer.h"

#include <cstdint>
#include <vector>

namespace specbake::io {

// DXGI_FORMAT for `channels` (1-4) as `encoding`; `stored_channels` receives the channel count in the file.
uint32_t dds_dxgi_format(TexelEncoding encoding, int channels, int* stored_channels);

// The whole file.
std::vector<uint8_t> encode_dds(const MipChain& chain, TexelEncoding encoding);

// Layout of the file encode_dds writes for a width x height chain of `levels` levels of `channels`.
ContainerLayout dds_layout(int width, int height, int levels, TexelEncoding encoding, int channels);

// Writes the DDS and DX10 headers of that file into `file` (layout.total bytes); level data untouched.
void dds_write_header(uint8_t* file, const ContainerLayout& layout, int width, int height, TexelEncoding encoding,
                      int channels);

}  // namespace specbake::io
