// KTX 2.0 (Khronos Texture 2.0 specification) for uncompressed 2D textures and 2D texture arrays with a full mip chain:
// vkFormat R8/R16 UNORM, R16/R32 SFLOAT with 1, 2 or 4 channels (3-channel data stored as RGBA, A = 1), a basic data format descriptor
// (KHR_DF_MODEL_RGBSDA, BT.709 primaries, KHR_DF_TRANSFER_LINEAR), a KTXwriter key/value entry,
// and level data stored smallest level first, each level aligned to lcm(texel size, 4).
#pragma once

#include "core/image.h"
#include "core/result.h"
#include "io/texture/texel_encoding.h"
#include "io/texture/texture_writer.h"

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace specbake::io {

// vkFormat of `channels` channels (1-4) stored as `encoding`.
uint32_t ktx2_vk_format(TexelEncoding encoding, int channels);

// The whole file.
std::vector<uint8_t> encode_ktx2(const MipChain& chain, TexelEncoding encoding);

// Layout of the file encode_ktx2 writes for a width x height chain of `levels` levels of `channels` of data
// (stored_channels = gpu_channels(channels)). `layers` > 0 makes it an array texture of that many layers
// (KTX2 layerCount), each width x height.
ContainerLayout ktx2_layout(int width, int height, int levels, TexelEncoding encoding, int channels, int layers = 0);

// Writes everything of that file except the level data into `file` (layout.total bytes): header, level
// index, data format descriptor, key/value data, and zeroes for the alignment padding.
void ktx2_write_header(uint8_t* file, const ContainerLayout& layout, int width, int height, TexelEncoding encoding,
                       int channels, int layers = 0);

// A 2D array texture of `layers` layers: every level of `stacked` holds its layers one below the other
// (height = layers x layer height, layer 0 at the top), as KTX2 stores them.
std::vector<uint8_t> encode_ktx2_array(const MipChain& stacked, int layers, TexelEncoding encoding);

// The file `raw` (header and levels as ktx2_write_header and the texels wrote them, `layout`) with every
// level compressed by Zstandard at `zstd_level` (supercompressionScheme 2, KTX 2.0 Sec. 3.9.2): the level
// index holds each level's compressed byteLength and its uncompressedByteLength, levels follow each other
// without padding (mipPadding is align(1) when supercompressed), the descriptor is unchanged (bytesPlane0
// keeps the texel size, KDFS issue 27). Levels are compressed in parallel, each by one single-threaded
// zstd call, so the bytes do not depend on the thread count.
Result<std::vector<uint8_t>> ktx2_zstd(std::span<const uint8_t> raw, const ContainerLayout& layout, int zstd_level);

// The same file as ktx2_zstd, as pieces in file order (header through key/value data, then the compressed
// levels smallest first) that are written one after the other: nothing is copied into one buffer, and the
// compressed levels' buffers are not zero-filled (only the pages zstd writes are touched).
struct Ktx2Pieces {
    std::vector<uint8_t> header;
    std::vector<std::unique_ptr<uint8_t[]>> level_data;  // level i's compressed bytes
    std::vector<size_t> level_size;
    std::vector<std::span<const uint8_t>> pieces() const;
    size_t size() const;
};
Result<Ktx2Pieces> ktx2_zstd_pieces(std::span<const uint8_t> raw, const ContainerLayout& layout, int zstd_level);
// The first piece of that file (header through key/value data) for levels compressed to `level_size` bytes
// each (level 0 first); `raw` needs to hold only its header through the key/value data.
std::vector<uint8_t> ktx2_zstd_header(std::span<const uint8_t> raw, const std::vector<size_t>& level_size);

// What a KTX2 file holds, as parsed and checked by read_ktx2_texture.
struct Ktx2Info {
    uint32_t vk_format = 0;
    uint32_t type_size = 0;
    uint32_t level_count = 0;
    uint32_t layer_count = 0;  // 0: not an array
    uint32_t supercompression = 0;
    // Data format descriptor, basic block.
    uint32_t color_model = 0, color_primaries = 0, transfer = 0, flags = 0;
    uint32_t bytes_plane0 = 0;
    std::vector<uint32_t> sample_bit_lengths;  // bitLength + 1 of each sample
    std::vector<uint32_t> sample_channel_ids;
    std::vector<uint32_t> sample_qualifiers;   // high nibble of channelType (0x80 float, 0x40 signed, ...)
    std::vector<uint64_t> level_offsets, level_lengths;
    std::string writer;                        // KTXwriter value
};

struct Ktx2Texture {
    Ktx2Info info;
    TexelEncoding encoding = TexelEncoding::Unorm8;
    MipChain chain;  // decoded to float; an array's layers one below the other (height x layers rows)
};

// Parses and validates a KTX2 file written by encode_ktx2 or ktx2_zstd (uncompressed formats, optionally
// zstd-supercompressed): identifier, header, index, level sizes and alignment, descriptor consistency
// with vkFormat; zstd levels are decompressed and must inflate to exactly their uncompressedByteLength.
// Errors name `name`.
Result<Ktx2Texture> read_ktx2_texture(std::span<const uint8_t> bytes, const std::string& name);

}  // namespace specbake::io
