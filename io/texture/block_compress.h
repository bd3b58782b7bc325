// Block compression of baked 8-bit levels (BC1, BC3, BC4, BC5; Microsoft's D3D11 "Texture Block
// Compression" formats as the Khronos Data Format Specification 1.3 Sec. 21 describes them), deterministic,
// and the KTX2 / DDS files around the compressed levels, so the baked mips stay as they are. ASTC levels
// (io/texture/astc_codec.h) go into KTX2 files the same way.
#pragma once

#include "core/result.h"
#include "io/texture/texture_writer.h"

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace specbake::io {

// The ASTC entries are one GPU format (ASTC_NxN_UNORM_BLOCK, the footprint from Supercompression::astc_block)
// fed with 1, 2 or 4 of the stored channels (io/texture/astc_codec.h: luminance, (x, y, 0, 1), RGBA).
enum class BlockFormat { None = 0, Bc1, Bc3, Bc4, Bc5, AstcR, AstcRg, AstcRgba };

bool is_astc(BlockFormat f);
const char* block_format_name(BlockFormat f);  // "none", "bc1", "bc3", "bc4", "bc5", "astc"
size_t block_bytes(BlockFormat f);             // 8 (BC1, BC4) or 16 (BC3, BC5, ASTC)
int block_channels(BlockFormat f);             // channels taken from the texels: 4, 4, 1, 2; ASTC 1, 2, 4
// The GPU format's name: "BC1_RGB_UNORM_BLOCK", ..., "ASTC_4x4_UNORM_BLOCK".
std::string block_gpu_format_name(BlockFormat f, int astc_side = 4);

// One 4x4 block. `texels` holds 16 texels, row by row, of block_channels(format) 8-bit values each
// (BC1 ignores alpha: it stores the opaque 4-colour mode). Writes block_bytes(format) bytes to `out`.
//   BC4: endpoints the block's min and max (red_0 > red_1: the 8-value palette), each texel the nearest
//        of the 8 values the decoder derives ((7 - i) e0 + i e1) / 7;
//   BC5: two BC4 blocks, R then G;
//   BC1: endpoints from the extremes of the texels' projections on their principal axis (power iteration,
//        fixed count), rounded to RGB565, colour_0 > colour_1 (4-colour mode), nearest of the 4 colours;
//   BC3: a BC4 block of alpha, then a BC1 colour block.
void encode_block(BlockFormat format, const uint8_t* texels, uint8_t* out);

// Compresses one level of `width` x `height` texels with `channels` interleaved 8-bit values each (the
// first block_channels(format) are used); sizes that are not multiples of 4 are padded by repeating the last
// row and column (the decoder's texels past the edge are never sampled). Blocks row by row.
std::vector<uint8_t> compress_level(BlockFormat format, const uint8_t* texels, int width, int height, int channels);

// KTX2 vkFormat / DDS FourCC of each format: BC1_RGB_UNORM_BLOCK 131 / "DXT1", BC3_UNORM_BLOCK 137 / "DXT5",
// BC4_UNORM_BLOCK 139 / "ATI1", BC5_UNORM_BLOCK 141 / "ATI2"; ASTC 157 / 165 / 171 (4x4, 6x6, 8x8) and no
// FourCC (DDS has no standard ASTC format: D3D samples none).
uint32_t block_vk_format(BlockFormat f, int astc_side = 4);
const char* block_fourcc(BlockFormat f);

// A whole file (KTX2 or DDS with the legacy FourCC header) holding `levels` (level 0 first, each from
// compress_level or astc_compress_level) of a width x height texture. KTX2: descriptor with the format's
// colour model (ASTC: 162) and texel block footprint, levels aligned to the block size, smallest first;
// `zstd_level` > 0 supercompresses every level (scheme 2). ASTC is KTX2 only. Returns the file as pieces in
// file order, see Ktx2Pieces.
struct BlockFile {
    std::vector<uint8_t> header;
    std::vector<std::vector<uint8_t>> levels;  // in file order
    std::vector<std::span<const uint8_t>> pieces() const;
};
Result<BlockFile> block_file(TextureContainer container, BlockFormat format, int width, int height,
                             std::vector<std::vector<uint8_t>> levels, int zstd_level, int astc_side = 4);

}  // namespace specbake::io
