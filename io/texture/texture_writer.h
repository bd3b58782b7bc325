// Writes a MipChain with its full mip chain to a texture container, atomically (temporary file + rename),
// and describes what it wrote as manifest entries (SPEC Sec. 7). Containers: KTX2 (io/texture/ktx2.h), DDS
// (io/texture/dds.h), tiled mipmapped OpenEXR (io/image/exr_encode.h, "Plain Texture"), or one PNG (integer encodings) / EXR
// (float encodings) file per mip level. Every container stores 1, 2 or 4 channels (formats GPUs sample:
// D3D has no 3-channel 8/16-bit formats and Vulkan makes them optional): 3-channel data gets A = 1.
#pragma once

#include "core/enum_names.h"
#include "core/image.h"
#include "core/result.h"
#include "io/output/manifest.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace specbake::io {

class PngLevelStream;
class AtomicOutput;
class AstcEncoder;

enum class TextureContainer { Ktx2, Dds, Exr, PngPerMip };

// How texel values are stored. Unorm: round(clamp(v, 0, 1) * (2^bits - 1)); Float16: IEEE half.
enum class TexelEncoding { Unorm8, Unorm16, Float16, Float32 };

// Where the level data of a container file lies: total file size and the byte offset of every level's
// texels (level 0 first), each level tightly packed with `stored_channels` channels per texel.
struct ContainerLayout {
    size_t total = 0;
    std::vector<size_t> level_offset;
    int stored_channels = 0;
};

// Channels a container stores for `channels` of data: 3 becomes 4 (RGBA, A = 1), the others stay.
int gpu_channels(int channels);

// The GPU format name of `channels` stored channels as `encoding`: "R8_UNORM", "R16G16_SFLOAT",
// "R8G8B8A8_UNORM", ... (Vulkan / DXGI spelling without the prefix).
std::string gpu_format_name(TexelEncoding encoding, int channels);

// How KTX2/DDS level data is compressed. zstd: KTX2 supercompression (io/texture/ktx2.h, ktx2_zstd), scheme 2, on
// by default; other containers ignore it. block: 8-bit outputs block-compressed (io/texture/block_compress.h).
// Bc: one channel BC4, the mean normal BC5 (x, y), four channels `rgba_block` (BC1 by default: the ORM
// map's A is 1, which BC1's opaque mode stores exactly; BC3 adds an alpha block). Astc: every 8-bit
// output ASTC with an `astc_block` x `astc_block` footprint (io/texture/astc_codec.h; the mean normal keeps x, y
// as BC5 does), KTX2 only. Float data stays float16/32 either way.
enum class BlockFormat;
enum class BlockFamily { None, Bc, Astc };
struct Supercompression {
    bool zstd = true;
    int zstd_level = 3;  // 1 (fastest) .. 22; 3 is zstd's own default
    BlockFamily block = BlockFamily::None;
    int rgba_block = 1;  // 1: BC1, 3: BC3
    int astc_block = 4;  // 4, 6 or 8 texels a side
};

// "none", "bc", "astc" (the CLI spellings), in enum order.
inline constexpr std::array<std::string_view, 3> kBlockFamilyNames{"none", "bc", "astc"};
// How a texture's files are stored: the parameters that travel together from the command line through the
// jobs to the writers.
struct TextureFileFormat {
    TextureFileFormat() = default;
    explicit TextureFileFormat(TextureContainer container, const Supercompression& supercompression = {},
                               WrapMode wrap = WrapMode::Repeat)
        : container(container), supercompression(supercompression), wrap(wrap) {}

    TextureContainer container = TextureContainer::Ktx2;
    Supercompression supercompression;  // KTX2 zstd, KTX2/DDS block compression
    // The addressing the textures are sampled with, recorded where the container has a place for it (EXR
    // "wrapmodes") and in manifests. Box footprints lie inside the map, so it does not change baked values.
    WrapMode wrap = WrapMode::Repeat;
};

const char* block_family_name(BlockFamily f);
std::optional<BlockFamily> parse_block_family(std::string_view name);
// Why `container` cannot hold the block formats of `family` (BC: KTX2 and DDS; ASTC: KTX2 only, as DDS
// has no standard ASTC format), or empty when it can.
std::string block_container_problem(TextureContainer container, BlockFamily family);

// "ktx2", "dds", "exr", "png" (the CLI and manifest spellings), in enum order.
inline constexpr std::array<std::string_view, 4> kTextureContainerNames{"ktx2", "dds", "exr", "png"};
const char* container_name(TextureContainer c);
std::optional<TextureContainer> parse_container(std::string_view name);
const char* encoding_name(TexelEncoding e);          // "unorm8", "unorm16", "float16", "float32"

// Writes `chain` (1-4 channels) as `dir/<stem>.<ext>` (per-mip: `dir/<stem>_mip<L>.<ext>`), 3 channels
// stored as RGBA with A = 1. `channel_names` say what each stored channel means (e.g. "m.x"); they go to
// the manifest ("channel_meaning") and to the EXR header attribute "specbake:channels", while EXR
// channels are named as common readers expect: Y for one channel, R, G (, B, A) otherwise, in the same
// order as the KTX2/DDS channels. Returns one entry per file, `path` relative to `dir`,
// kind `kind`, sha256 filled. Creates `dir` when missing; the error names the file. All files of the call
// are written to temporary names first and renamed only when every one succeeded. `block` other than
// BlockFormat::None block-compresses a KTX2/DDS file's levels (io/texture/block_compress.h); EXR and PNG ignore it.
Result<std::vector<ManifestOutput>> write_texture(const MipChain& chain, TexelEncoding encoding,
                                                  const TextureFileFormat& format, const std::filesystem::path& dir,
                                                  const std::string& stem, const std::string& kind,
                                                  const std::vector<std::string>& channel_names = {},
                                                  BlockFormat block = {});

// A texture file (KTX2, DDS, mipmapped EXR) or the files of a per-mip output (one PNG or EXR a level)
// assembled in memory, level by level and row by row, so a producer can encode rows as it finishes them
// instead of holding float chains. put_block() may run on several threads at once for disjoint blocks; the
// file is complete once every texel of every level was put. bytes() is the KTX2/DDS file without
// supercompression (for EXR and per-mip files: the stored levels, tightly packed, no header);
// write_encoded_textures applies `supercompression` to KTX2 files and encodes PNG and EXR as it writes.
// EXR stores half floats (float32 data as float32), as does a per-mip level of float data.
class EncodedTexture {
public:
    // KTX2 and DDS: one file whose bytes() are the file's (before supercompression or block compression).
    static bool is_container_file(TextureContainer container) {
        return container == TextureContainer::Ktx2 || container == TextureContainer::Dds;
    }
    // `wrap` is recorded in EXR files ("wrapmodes").
    EncodedTexture(TextureContainer container, TexelEncoding encoding, int width, int height, int levels,
                   int channels, const Supercompression& supercompression = {}, WrapMode wrap = WrapMode::Repeat);

    // Encodes the texels [x0, x0 + width) x [y0, y0 + rows) of `level` from `rows` rows of `width`
    // interleaved floats with `src_channels` per texel, taking channels [first, first + channels()).
    void put_block(int level, int x0, int y0, int width, int rows, const float* src, int src_channels, int first);

    std::span<const uint8_t> bytes() const { return {data_.get(), layout_.total}; }
    int channels() const { return channels_; }
    int width() const { return width_; }
    int height() const { return height_; }
    TexelEncoding encoding() const { return encoding_; }
    TextureContainer container() const { return container_; }
    const ContainerLayout& layout() const { return layout_; }
    // True when the written file is supercompressed (KTX2 with zstd on).
    bool supercompressed() const { return container_ == TextureContainer::Ktx2 && supercompression_.zstd; }
    // True when compress_rows() encodes the rows as they arrive: zstd-supercompressed KTX2, per-mip PNG
    // and EXR files, and DDS files given a path by stream_to().
    bool streams() const { return supercompressed() || png() || exr() || streams_to_file() || block_ != BlockFormat{}; }
    // KTX2 and DDS of 8/16-bit unorm data: the levels are block-compressed as `format` by compress_rows,
    // whole block rows as they arrive (4 rows for BC, the footprint's side for ASTC), the raw pages returned;
    // the file is written from the blocks (write_encoded_textures, when its EncodedFile asks for the same
    // format). Call before any compress_rows().
    void set_block_format(BlockFormat format);
    BlockFormat block_format() const { return block_; }
    // The blocks of every level (moved out; rows compress_rows was not told of are compressed now), or empty
    // when no block format was set; an error if the encoder failed on the rows still held.
    Result<std::vector<std::vector<uint8_t>>> take_block_levels();
    // DDS: the file is written to a temporary name next to `final_path` while the bake runs: the header now,
    // then every row compress_rows() is told of at its place in the file, after which the raw pages those rows
    // filled are returned to the system (they read as zeroes in bytes() afterwards), so the raw file is never
    // all held. write_encoded_textures writes the rows never reported, hashes the file as written and renames
    // it to `final_path` (it must write the texture to that path). Call before any compress_rows(); the file
    // is removed unless written. Not for block-compressed files, whose blocks are made from the whole level.
    Result<void> stream_to(const std::filesystem::path& final_path);
    bool streams_to_file() const { return file_ != nullptr; }
    // A file stream_to() began: writes the rows not yet written, closes it and returns its SHA-256 (hex) read
    // back from the file; the temporary output moves to `out` (renamed by the caller once every file is done).
    Result<std::string> finish_file(const std::filesystem::path& final_path, std::unique_ptr<AtomicOutput>& out);
    // True for per-mip PNG files (integer data in the PngPerMip container).
    bool png() const {
        return container_ == TextureContainer::PngPerMip &&
               (encoding_ == TexelEncoding::Unorm8 || encoding_ == TexelEncoding::Unorm16);
    }
    // True for EXR files: the mipmapped EXR container, or per-mip files of float data.
    bool exr() const { return container_ == TextureContainer::Exr || (container_ == TextureContainer::PngPerMip && !png()); }
    // What each stored channel of an EXR means (its "specbake:channels" attribute), given before the first
    // compress_rows() call opens the file; write_encoded_textures checks it against the EncodedFile's.
    void set_channel_meaning(const std::vector<std::string>& meaning) { meaning_ = meaning; }
    const Supercompression& supercompression() const { return supercompression_; }
    WrapMode wrap() const { return wrap_; }
    // True when the level bytes hold RGBA8 texels in B, G, R, A order (DDS A8R8G8B8, io/texture/dds.h).
    bool bgra() const { return bgra_; }
    // The manifest entry of this file as `filename` (sha256 left empty; the writer fills it).
    ManifestOutput entry(const std::string& filename, const std::string& kind) const;

    // Per-mip PNG: filters and deflates the strips that rows [0, rows) of `level` complete
    // (io/texture/png_stream.h) and returns the raw pages no strip reads again to the system.
    // EXR: ZIP-compresses the chunks rows [0, rows) of `level` complete (io/image/exr_encode.h: whole 64-row
    // tile rows of a mipmapped file's level, whole 16-row blocks of a per-mip file) and returns the raw
    // pages compressed to the system; only compressed chunks are held.
    // DDS given a path by stream_to(): writes rows [0, rows) of `level` not yet written to the file and
    // returns the whole 2 MiB pages they fill to the system.
    // KTX2 with zstd: zstd-compresses rows [0, rows) of `level`, put before the call, as a stream of the
    // level (whole zstd blocks; the rest once rows is the level's height), and returns the raw pages zstd
    // no longer reads (older than its window) to the system, so a level's raw bytes are never all held.
    // `rows` grows from call to call; rows below it are not put again. A level is fed by one thread at a
    // time. The compressed levels are the bytes of ktx2_zstd's one-shot compression: zstd compresses the
    // same blocks from the same contiguous buffer (ZSTD_c_stableInBuffer). write_encoded_textures uses them
    // once every level was fed to its end.
    Result<void> compress_rows(int level, int rows);
    // The compressed bytes of every level when all were fed to their end by compress_rows, else empty.
    std::vector<std::span<const uint8_t>> streamed_levels() const;

    // Per-mip PNG: the file of `level`, every level fed to its end first (by compress_rows, or here).
    Result<std::vector<std::span<const uint8_t>>> png_level(int level);
    // EXR: the file (`level` -1: the mipmapped file; else that level of a per-mip output), every row fed
    // first (by compress_rows, or here); its pieces live as long as the texture. `meaning` must be that of
    // set_channel_meaning when rows were streamed, and the same at every call.
    Result<std::vector<std::span<const uint8_t>>> exr_file(int level, const std::vector<std::string>& meaning);
    ~EncodedTexture();

private:
    struct LevelStream;
    struct ExrStream;
    Result<void> feed_exr(int level, int rows);
    Result<void> write_rows(int level, int rows);
    Result<void> block_rows(int level, int rows);
    BlockFormat block_{};                           // BC levels made as the rows arrive
    std::vector<std::vector<uint8_t>> block_levels_;
    std::vector<int> block_done_;                   // per level, rows [0, n) are in block_levels_
    std::unique_ptr<AstcEncoder> astc_;             // the ASTC encoder's set-up, reused strip after strip
    std::unique_ptr<AtomicOutput> file_;  // DDS written as the bake runs (stream_to)
    int fd_ = -1;
    std::vector<int> rows_written_;       // per level, rows [0, n) are in the file
    std::vector<std::unique_ptr<LevelStream>> streams_;
    std::vector<std::unique_ptr<ExrStream>> exr_;  // one a level (per-mip) or one (mipmapped)
    std::string exr_problem_;                      // why an EXR encoder could not be made
    std::vector<std::string> meaning_;
    std::vector<std::unique_ptr<PngLevelStream>> png_;
    TextureContainer container_;
    TexelEncoding encoding_;
    int width_, height_, channels_;
    Supercompression supercompression_;
    WrapMode wrap_;
    ContainerLayout layout_;
    bool bgra_ = false;
    std::unique_ptr<uint8_t[]> data_;  // not zero-filled: every byte is written by the header or a row
};

// Writes `files` (each `dir/<stem>.<ext>`, `kind` as given) atomically: all are supercompressed where
// asked, hashed and written to temporary names in parallel, and renamed only when every one succeeded.
// Returns their manifest entries, with "bytes" (file size), "uncompressed_bytes" and "supercompression".
struct EncodedFile {
    EncodedTexture* texture = nullptr;  // non-const: per-mip PNG levels not yet fed are encoded by the write
    std::string stem;
    std::string kind;
    std::vector<std::string> channel_meaning;  // what each stored channel holds (manifest), may be empty
    BlockFormat block{};                       // BlockFormat::None: the texels as they are
};
Result<std::vector<ManifestOutput>> write_encoded_textures(std::span<const EncodedFile> files,
                                                           const std::filesystem::path& dir);

}  // namespace specbake::io
