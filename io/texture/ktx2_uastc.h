// KTX2 files of UASTC blocks (vkFormat 0, KHR_DF_MODEL_UASTC) for glTF's KHR_texture_basisu: the level of a
// one-level file an encoder wrote, and a full mip chain assembled from one such file per level, so the
// baked levels are kept instead of mips the encoder would regenerate.
#pragma once

#include "core/result.h"

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace specbake::io {

// One level of UASTC data: ceil(w / 4) x ceil(h / 4) blocks of 16 bytes.
size_t uastc_level_bytes(int width, int height);
struct UastcLevel {
    int width = 0, height = 0;
    std::vector<uint8_t> blocks;
};

// A one-level UASTC KTX2 file (no supercompression), as `basisu -uastc -ktx2 -ktx2_no_zstandard` writes it:
// its level and its data format descriptor (kept verbatim for the assembled file). Errors name `name`.
struct UastcFile {
    UastcLevel level;
    std::vector<uint8_t> dfd;  // the whole DFD (dfdTotalSize first)
};
Result<UastcFile> read_uastc_ktx2(std::span<const uint8_t> bytes, const std::string& name);

// A KTX2 file of `levels` (level 0 first, each half the previous size, down to 1x1), the descriptor `dfd`
// (kept as it is: bytesPlane0 stays 16 under zstd, KHR DataFormat #27), KTXwriter `writer`; level data
// smallest level first, KTX 2.0 Sec. 3. `zstd_level` 0: no supercompression, each level aligned to 16 bytes
// (lcm of the 16-byte block and 4); 1-22: every level a zstd frame of that level (scheme 2, which
// KHR_texture_basisu allows for UASTC), unaligned.
std::vector<uint8_t> assemble_uastc_ktx2(const std::vector<UastcLevel>& levels, std::span<const uint8_t> dfd,
                                         const std::string& writer, int zstd_level = 0);

}  // namespace specbake::io
