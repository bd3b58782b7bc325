// ASTC LDR 2D blocks (Khronos Data Format Specification 1.3 Sec. 23) through ARM's astcenc 4 (Debian's
// libastcenc): the block format of `--block astc`, for mobile GPUs. One format carries 1, 2 or 4 channels;
// every block is 16 bytes whatever its footprint (4x4: 8 bits a texel, 6x6: 3.56, 8x8: 2).
#pragma once

#include "core/result.h"

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace specbake::io {

// Square footprints specbake writes: 4, 6 or 8 texels a side.
bool astc_block_supported(int side);
// VK_FORMAT_ASTC_{4x4,6x6,8x8}_UNORM_BLOCK: 157, 165, 171; 0 for other sides.
uint32_t astc_vk_format(int side);
// Bytes of a w x h level: 16 per block, blocks covering the level (edges padded).
uint64_t astc_level_bytes(int side, uint64_t w, uint64_t h);

// How the stored channels of a level become the RGBA the encoder sees, so that a texture samples as
// the uncompressed format would: one channel as luminance (r, r, r, 1: ASTC's luminance endpoint modes,
// sampled .r), two channels (the mean normal's x, y) as (x, y, 0, 1), four as they are.
//
// Compresses one level of `width` x `height` texels with `channels` interleaved 8-bit values each, of which
// the first `used` (1, 2 or 4) are kept, astcenc's medium effort, LDR profile, linear data (no sRGB, no perceptual weighting), on up to
// `threads` threads (0: the machine's). The bytes do not depend on the thread count.
Result<std::vector<uint8_t>> astc_compress_level(const uint8_t* texels, int width, int height, int channels, int used,
                                                 int side, int threads = 0);

// The same for many levels: the encoder's set-up (about 4 ms of tables per footprint) is done once and
// reused, level after level. compress() gives the bytes astc_compress_level gives.
class AstcEncoder {
public:
    static Result<AstcEncoder> create(int side, int threads = 0);
    Result<std::vector<uint8_t>> compress(const uint8_t* texels, int width, int height, int channels, int used);
    AstcEncoder(AstcEncoder&&) noexcept;
    AstcEncoder& operator=(AstcEncoder&&) noexcept;
    ~AstcEncoder();

private:
    struct State;
    explicit AstcEncoder(std::unique_ptr<State> state);
    std::unique_ptr<State> state_;
};

// Decodes one level of blocks to width x height RGBA8 texels (the LDR decode of the specification).
Result<std::vector<uint8_t>> astc_decompress_level(std::span<const uint8_t> blocks, int width, int height, int side);

}  // namespace specbake::io
