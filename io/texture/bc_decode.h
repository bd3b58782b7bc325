// Decoding of the block-compressed levels specbake writes (BC1, BC3, BC4, BC5 UNORM; Khronos Data Format
// Specification 1.3 Sec. 21, D3D11 "Texture Block Compression"), so `inspect` reads them like plain levels.
#pragma once

#include "core/image.h"

#include <cstddef>
#include <cstdint>

namespace specbake::io {

enum class BcFormat { Bc1, Bc3, Bc4, Bc5 };

// Bytes of one 4x4 block (8 for BC1 and BC4, 16 for BC3 and BC5) and the channels a decoded texel has:
// BC1 and BC3 RGBA (BC1 opaque: A = 1), BC4 one (R), BC5 two (R, G).
size_t bc_block_bytes(BcFormat f);
int bc_channels(BcFormat f);

// Bytes of a width x height level: ceil(width / 4) * ceil(height / 4) blocks.
uint64_t bc_level_bytes(BcFormat f, uint64_t width, uint64_t height);

// Decodes a width x height level (bc_level_bytes bytes, blocks row by row) to unorm values in [0, 1];
// texels of edge blocks past the level's size are dropped.
Image decode_bc_level(BcFormat f, const uint8_t* data, int width, int height);

}  // namespace specbake::io
