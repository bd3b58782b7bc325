// OpenEXR 2 files written by specbake itself (no OpenImageIO): single-part scanline images and tiled
// MIPMAP_LEVELS images (ROUND_DOWN, square tiles), HALF or FLOAT channels, ZIP compression (16 scanlines a
// chunk; one tile a chunk), INCREASING_Y line order. The chunks are compressed as the rows that complete
// them arrive, so a producer never needs a whole uncompressed level; only compressed chunks are held.
// The layout follows the OpenEXR file-layout document (openexr.com, "OpenEXR File Layout"): magic and
// version, the header's attributes sorted by name, the offset table, the chunks in table order.
#pragma once

#include "core/result.h"

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace specbake::io {

enum class ExrSample { Half, Float };

// The libdeflate level specbake's EXR files are written with. On the chunks of a 4096^2 texture bake's five
// half outputs (NormalTangentTest maps tiled 2x2, 725 MiB of levels; bench/exr_deflate, one thread), 64x64
// tiles deflated to 0.0512 of the raw bytes at level 1 in 2.45 s, 0.0499 at level 4 in 2.76 s, 0.0484 at
// level 6 in 3.71 s; zlib's default (level 6, OpenEXR's own) gave 0.0496 in 6.79 s and zlib level 1 0.0585
// in 2.28 s. Level 1: the fastest libdeflate level, files within 3% of zlib's default and as large as the
// ones OpenImageIO wrote before (39.9 MB against 40.0 MB for the bake), 2.8x faster than zlib's default.
inline constexpr int kExrDeflateLevel = 1;

struct ExrImageDesc {
    int width = 0, height = 0;  // level 0
    int levels = 1;             // tiled: floor(log2(max(width, height))) + 1 (ROUND_DOWN); scanline: 1
    int tile_side = 0;          // 0: a scanline image; else a tiled MIPMAP_LEVELS image of tile_side^2 tiles
    ExrSample sample = ExrSample::Half;
    // The channels in the order the texels given to add_rows interleave them. The file lists (and stores)
    // them sorted by name, as OpenEXR requires.
    std::vector<std::string> channel_names;
};

// The texel rows of one image's levels in, its file out. add_rows() may run on several threads at once for
// different levels; one level is fed by one thread at a time.
class ExrEncoder {
public:
    // `deflate_level`: libdeflate's compression level (1..12) of the ZIP chunks.
    static Result<ExrEncoder> create(const ExrImageDesc& desc, int deflate_level);
    ExrEncoder(ExrEncoder&&) noexcept;
    ExrEncoder& operator=(ExrEncoder&&) noexcept;
    ~ExrEncoder();

    // Rows [0, rows) of `level` lie at `texels` (the level's first row; rows tightly packed, every texel's
    // channels interleaved in channel_names order, samples little-endian half or float). Compresses every
    // chunk those rows complete that was not compressed before (scanline: whole 16-row blocks, tiled: whole
    // rows of tiles; the rest once `rows` reaches the level's height). `rows` grows from call to call.
    Result<void> add_rows(int level, const uint8_t* texels, int rows);
    // The rows of `level` compressed so far: the rows no later call reads again.
    int rows_done(int level) const;
    // The file, once every level was fed to its end: the header (the layout's attributes plus `strings`,
    // each a (name, value) attribute of type "string"), the offset table and every chunk. The spans point
    // into the encoder and live as long as it does.
    Result<std::vector<std::span<const uint8_t>>> file(const std::vector<std::pair<std::string, std::string>>& strings);

private:
    struct Level;
    ExrEncoder() = default;
    ExrImageDesc desc_;
    int deflate_level_ = 1;
    std::vector<std::unique_ptr<Level>> levels_;
    std::vector<uint8_t> header_;
};

// The transform OpenEXR's ZIP compressor applies to a chunk before deflate (ImfZip.cpp, Zip::compress): the
// n bytes of `raw` split into the even-indexed ones followed by the odd-indexed ones, then every byte after
// the first replaced by (byte - the byte before it + 128) mod 256. `out` holds n bytes.
void exr_zip_predict(const uint8_t* raw, size_t n, uint8_t* out);

}  // namespace specbake::io
