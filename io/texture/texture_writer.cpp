#include "io/texture/texture_writer.h"

#include "io/texture/astc_codec.h"
#include "io/files/atomic_write.h"
#include "io/texture/block_compress.h"
#include "io/texture/dds.h"
#include "io/texture/ktx2.h"
#include "io/texture/png_stream.h"
#include "io/image/exr_encode.h"
#include "io/files/sha256.h"
#include "io/texture/texel_encoding.h"

#include "core/huge_pages.h"

#include <tbb/parallel_for.h>

#define ZSTD_STATIC_LINKING_ONLY  // ZSTD_getCParams: the window the stream reads back
#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <memory>


namespace specbake::io {
namespace fs = std::filesystem;

int gpu_channels(int channels) { return channels == 3 ? 4 : channels; }

std::string gpu_format_name(TexelEncoding encoding, int channels) {
    static const char* rgba[] = {"R", "G", "B", "A"};
    const char* bits = encoding == TexelEncoding::Unorm8 ? "8" : encoding == TexelEncoding::Float32 ? "32" : "16";
    std::string name;
    for (int c = 0; c < channels && c < 4; ++c) name += std::string(rgba[c]) + bits;
    const bool is_float = encoding == TexelEncoding::Float16 || encoding == TexelEncoding::Float32;
    return name + (is_float ? "_SFLOAT" : "_UNORM");
}

// The names are string literals, so their data() is null-terminated.
const char* container_name(TextureContainer c) { return kTextureContainerNames[size_t(c)].data(); }

std::optional<TextureContainer> parse_container(std::string_view name) {
    return enum_from_name<TextureContainer>(kTextureContainerNames, name);
}

const char* encoding_name(TexelEncoding e) {
    switch (e) {
        case TexelEncoding::Unorm8: return "unorm8";
        case TexelEncoding::Unorm16: return "unorm16";
        case TexelEncoding::Float16: return "float16";
        case TexelEncoding::Float32: return "float32";
    }
    return "float32";
}

const char* block_family_name(BlockFamily f) { return kBlockFamilyNames[size_t(f)].data(); }

std::optional<BlockFamily> parse_block_family(std::string_view name) {
    return enum_from_name<BlockFamily>(kBlockFamilyNames, name);
}

std::string block_container_problem(TextureContainer container, BlockFamily family) {
    if (family == BlockFamily::None || container == TextureContainer::Ktx2) return {};
    if (container == TextureContainer::Dds && family == BlockFamily::Bc) return {};
    if (container == TextureContainer::Dds)
        return "ASTC is written to KTX2 only: DDS has no standard ASTC format (D3D samples none)";
    return std::string(block_family_name(family)) + " block compression needs a ktx2 or dds container; " +
           container_name(container) + " writes its levels uncompressed";
}

namespace {

// The zlib level of per-mip PNGs: on 4096^2 ORM roughness and mean-normal levels (filter Up, one thread),
// level 2 deflated at 118 / 182 MB/s to 0.079 / 0.025 of the filtered bytes, level 1 at 116 / 204 MB/s to
// 0.091 / 0.026, level 3 up to 20% slower, level 6 (OpenImageIO's) 4x slower on the roughness for 1.5x smaller.
constexpr int kPngZlibLevel = 2;

// The tile side of mipmapped EXRs, as OpenImageIO's texture writer (maketx) chooses.
constexpr int kExrTileSide = 64;

const char* wrap_name(WrapMode w) {
    switch (w) {
        case WrapMode::Repeat: return "periodic";
        case WrapMode::Clamp: return "clamp";
        case WrapMode::Mirror: return "mirror";
    }
    return "periodic";
}

// EXR channel names common readers load (three.js EXRLoader, OpenImageIO, Pillow-free tools): Y alone,
// else R, G, B, A in the KTX2/DDS order. What the channels mean goes into "specbake:channels".
std::vector<std::string> exr_names(int channels) {
    if (channels == 1) return {"Y"};
    static const char* rgba[] = {"R", "G", "B", "A"};
    return {rgba, rgba + channels};
}

// `given` meanings, padded with the defaults (R, G, B; "1" for the A = 1 of padded 3-channel data).
std::vector<std::string> meaning_for(int data_channels, int stored, const std::vector<std::string>& given) {
    std::vector<std::string> names = exr_names(stored);
    for (int c = 0; c < stored; ++c) {
        if (size_t(c) < given.size()) names[size_t(c)] = given[size_t(c)];
        else if (c >= data_channels) names[size_t(c)] = "1";
    }
    return names;
}

std::string joined(const std::vector<std::string>& names) {
    std::string s;
    for (const std::string& n : names) s += (s.empty() ? "" : ",") + n;
    return s;
}

// The DateTime written into EXR headers (OpenEXR's "capDate" attribute): SOURCE_DATE_EPOCH (the
// reproducible-builds convention) when it is set, else the epoch, never the current time, so the same bake
// gives the same files (and manifest hashes) from run to run and build caches hold.
std::string reproducible_date_time() {
    std::time_t t = 0;
    if (const char* epoch = std::getenv("SOURCE_DATE_EPOCH")) {
        char* end = nullptr;
        const long long v = std::strtoll(epoch, &end, 10);
        if (end != epoch && *end == '\0' && v >= 0) t = std::time_t(v);
    }
    std::tm utc{};
    gmtime_r(&t, &utc);
    char text[32];
    std::strftime(text, sizeof text, "%Y:%m:%d %H:%M:%S", &utc);
    return text;
}

// EXR and per-mip files: levels tightly packed from offset 0, level 0 first, no header.
ContainerLayout plain_layout(int width, int height, int levels, TexelEncoding encoding, int data_channels) {
    ContainerLayout layout;
    layout.stored_channels = gpu_channels(data_channels);
    const size_t texel_bytes = size_t(layout.stored_channels) * size_t(encoding_bytes(encoding));
    for (int L = 0; L < levels; ++L) {
        layout.level_offset.push_back(layout.total);
        layout.total += size_t(std::max(1, width >> L)) * size_t(std::max(1, height >> L)) * texel_bytes;
    }
    return layout;
}

// What an EXR stores of `encoding`: float32 as float32, everything else as half.
TexelEncoding exr_encoding(TexelEncoding encoding) {
    return encoding == TexelEncoding::Float32 ? encoding : TexelEncoding::Float16;
}

}  // namespace

Result<std::vector<ManifestOutput>> write_texture(const MipChain& data, TexelEncoding encoding,
                                                  const TextureFileFormat& format, const fs::path& dir,
                                                  const std::string& stem, const std::string& kind,
                                                  const std::vector<std::string>& channel_names, BlockFormat block) {
    if (data.levels.empty() || data.channels() < 1) return make_error((dir / stem).string() + ": nothing to write");
    if (data.channels() > 4)
        return make_error((dir / stem).string() + ": " + std::to_string(data.channels()) +
                          " channels; a texture holds at most 4");
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) return make_error(dir.string() + ": cannot create folder: " + ec.message());

    const int mips = int(data.levels.size());
    const std::vector<std::string> names = meaning_for(data.channels(), gpu_channels(data.channels()), channel_names);
    EncodedTexture t(format.container, encoding, data.width(), data.height(), mips, data.channels(),
                     format.supercompression, format.wrap);
    for (int L = 0; L < mips; ++L) {
        const Image& level = data.levels[size_t(L)];
        t.put_block(L, 0, 0, level.width, level.height, level.pixels.data(), level.channels, 0);
    }
    const EncodedFile file{&t, stem, kind, names, block};
    return write_encoded_textures({&file, 1}, dir);
}

EncodedTexture::EncodedTexture(TextureContainer container, TexelEncoding encoding, int width, int height, int levels,
                               int channels, const Supercompression& supercompression, WrapMode wrap)
    : container_(container), encoding_(container == TextureContainer::Exr ? exr_encoding(encoding) : encoding),
      width_(width), height_(height), channels_(channels), supercompression_(supercompression), wrap_(wrap) {
    if (container == TextureContainer::Ktx2) layout_ = ktx2_layout(width, height, levels, encoding_, channels);
    else if (container == TextureContainer::Dds) layout_ = dds_layout(width, height, levels, encoding_, channels);
    else layout_ = plain_layout(width, height, levels, encoding_, channels);
    data_.reset(new uint8_t[layout_.total]);
    if (png()) png_.resize(layout_.level_offset.size());  // one stream a level, each made by its level's feeder
    if (exr()) {  // every file's encoder made here, so levels fed on several threads share no set-up
        const bool mipmapped = container == TextureContainer::Exr;
        for (size_t L = 0; L < (mipmapped ? 1 : layout_.level_offset.size()); ++L) {
            ExrImageDesc desc;
            desc.width = std::max(1, width >> L);
            desc.height = std::max(1, height >> L);
            desc.levels = mipmapped ? int(layout_.level_offset.size()) : 1;
            desc.tile_side = mipmapped ? kExrTileSide : 0;
            desc.sample = encoding_ == TexelEncoding::Float32 ? ExrSample::Float : ExrSample::Half;
            desc.channel_names = exr_names(layout_.stored_channels);
            auto encoder = ExrEncoder::create(desc, kExrDeflateLevel);
            if (encoder) exr_.push_back(std::make_unique<ExrStream>(std::move(*encoder)));
            else exr_problem_ = encoder.error().message, exr_.emplace_back();
        }
    }
    // Faulted in on transparent huge pages as the rows arrive: a 4096^2 bake writes about 400 MiB of fresh
    // container bytes.
    detail::hint_huge_pages(data_.get(), layout_.total);
    if (container == TextureContainer::Ktx2) ktx2_write_header(data_.get(), layout_, width, height, encoding, channels);
    if (container == TextureContainer::Dds) dds_write_header(data_.get(), layout_, width, height, encoding, channels);
    if (container == TextureContainer::Dds)
        if (const auto legacy = dds_legacy_pixel_format(encoding, channels); legacy && legacy->bgra) bgra_ = true;
}

void EncodedTexture::put_block(int level, int x0, int y0, int width, int rows, const float* src, int src_channels,
                               int first) {
    const size_t w = size_t(std::max(1, width_ >> level));
    const size_t texel_bytes = size_t(layout_.stored_channels) * size_t(encoding_bytes(encoding_));
    uint8_t* dst = data_.get() + layout_.level_offset[size_t(level)] + (size_t(y0) * w + size_t(x0)) * texel_bytes;
    if (size_t(width) == w) {  // whole rows: one run
        encode_texels_into(src, w * size_t(rows), src_channels, first, channels_, encoding_, layout_.stored_channels,
                           1.0f, dst);
        if (bgra_) dds_swap_red_blue(dst, w * size_t(rows));
        return;
    }
    for (int k = 0; k < rows; ++k, src += size_t(width) * size_t(src_channels), dst += w * texel_bytes) {
        encode_texels_into(src, size_t(width), src_channels, first, channels_, encoding_, layout_.stored_channels,
                           1.0f, dst);
        if (bgra_) dds_swap_red_blue(dst, size_t(width));
    }
}

// The zstd stream of one level (compress_rows).
struct EncodedTexture::LevelStream {
    ZSTD_CCtx* cctx = nullptr;
    std::unique_ptr<uint8_t[]> out;  // compressBound bytes, touched only as far as zstd writes
    size_t capacity = 0, in_pos = 0, out_pos = 0;
    size_t released = 0;             // bytes from the level's start whose pages were returned
    size_t window = 0;               // how far back zstd reads, plus a block
    bool done = false;
    ~LevelStream() { ZSTD_freeCCtx(cctx); }
};

// The EXR encoder of one file (compress_rows, exr_file).
struct EncodedTexture::ExrStream {
    explicit ExrStream(ExrEncoder encoder) : encoder(std::move(encoder)) {}
    ExrEncoder encoder;
    std::vector<std::string> meaning;              // what the file's "specbake:channels" says, once done
    std::vector<std::span<const uint8_t>> file;    // once done: pieces of the encoder's bytes
    bool done = false;
};

namespace {

// `texels` texels of `channels` stored channels at `src` as 8-bit texels in stored channel order (DDS
// A8R8G8B8 back to RGBA; 16-bit unorm rounded to 8 bits: BC endpoints and the ASTC LDR decode hold 8
// bits), in `scratch` when they are not `src` itself.
const uint8_t* as_unorm8(const uint8_t* src, size_t texels, int channels, TexelEncoding encoding, bool bgra,
                         std::vector<uint8_t>& scratch) {
    if (bgra) {  // the DDS A8R8G8B8 byte order back to RGBA for the block encoder
        scratch.assign(src, src + texels * 4);
        dds_swap_red_blue(scratch.data(), texels);
        src = scratch.data();
    }
    if (encoding == TexelEncoding::Unorm16) {
        std::vector<uint8_t> narrowed(texels * size_t(channels));
        for (size_t k = 0; k < narrowed.size(); ++k) {
            uint16_t v;
            std::memcpy(&v, src + 2 * k, 2);
            narrowed[k] = uint8_t((uint32_t(v) * 255u + 32767u) / 65535u);
        }
        scratch = std::move(narrowed);
        src = scratch.data();
    }
    return src;
}

// `height` rows of `width` 8-bit texels (`channels` stored) as blocks of `format`: BC by compress_level,
// ASTC by `astc`, whose set-up (footprint `side`) is made on first use and kept for the next call.
Result<std::vector<uint8_t>> encode_blocks(BlockFormat format, int side, std::unique_ptr<AstcEncoder>& astc,
                                           const uint8_t* texels, int width, int height, int channels) {
    if (!is_astc(format)) return compress_level(format, texels, width, height, channels);
    if (!astc) {
        auto encoder = AstcEncoder::create(side);
        if (!encoder) return encoder.error();
        astc = std::make_unique<AstcEncoder>(std::move(*encoder));
    }
    return astc->compress(texels, width, height, channels, block_channels(format));
}

}  // namespace

void EncodedTexture::set_block_format(BlockFormat format) {
    if (!is_container_file(container_) || format == BlockFormat::None ||
        (encoding_ != TexelEncoding::Unorm8 && encoding_ != TexelEncoding::Unorm16) ||
        (is_astc(format) && !astc_block_supported(supercompression_.astc_block)))
        return;
    block_ = format;
    block_levels_.assign(layout_.level_offset.size(), {});
    block_done_.assign(layout_.level_offset.size(), 0);
}

// Blocks of the whole block rows that rows [0, rows) of `level` complete (the rest with the level's last
// row): 4-row strips for BC, footprint-high strips for ASTC. Each block is encoded from its own texels alone
// (BC's compress_level; astcenc hands out blocks one by one), a strip's last block row is padded from the
// level's last row as the whole level's is, and the strips start on block rows: the blocks are those of the
// whole level, in its order. The whole 2 MiB pages (the huge pages the buffer was hinted for) of the rows
// compressed go back to the system.
Result<void> EncodedTexture::block_rows(int level, int rows) {
    const int w = std::max(1, width_ >> level), h = std::max(1, height_ >> level);
    int& done = block_done_[size_t(level)];
    const int unit = is_astc(block_) ? supercompression_.astc_block : 4;
    const int upto = rows >= h ? h : rows / unit * unit;
    if (upto <= done) return {};
    const int channels = layout_.stored_channels;
    const size_t row_bytes = size_t(w) * size_t(channels) * size_t(encoding_bytes(encoding_));
    const uint8_t* start = data_.get() + layout_.level_offset[size_t(level)];
    std::vector<uint8_t> scratch;
    const uint8_t* src = as_unorm8(start + size_t(done) * row_bytes, size_t(w) * size_t(upto - done), channels,
                                   encoding_, bgra_, scratch);
    auto blocks = encode_blocks(block_, unit, astc_, src, w, upto - done, channels);
    if (!blocks) return blocks.error();
    std::vector<uint8_t>& out = block_levels_[size_t(level)];
    out.insert(out.end(), blocks->begin(), blocks->end());
    done = upto;
    detail::advise_whole_pages(start, size_t(upto) * row_bytes, uintptr_t(2) << 20, MADV_DONTNEED);
    return {};
}

Result<std::vector<std::vector<uint8_t>>> EncodedTexture::take_block_levels() {
    if (block_ == BlockFormat::None) return std::vector<std::vector<uint8_t>>{};
    for (int L = 0; L < int(block_done_.size()); ++L)  // rows never reported: still held, compressed now
        if (auto ok = block_rows(L, std::max(1, height_ >> L)); !ok) return ok.error();
    return std::move(block_levels_);
}

EncodedTexture::~EncodedTexture() {
    if (fd_ >= 0) ::close(fd_);
}

namespace {

// Writes [p, p + n) at `offset` of `fd`; the error names `name` and gives the system's reason.
Result<void> write_at(int fd, const uint8_t* p, size_t n, size_t offset, const fs::path& name) {
    while (n > 0) {
        const ssize_t k = ::pwrite(fd, p, std::min<size_t>(n, size_t(1) << 30), off_t(offset));
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) return make_error(name.string() + ": cannot write: " + std::strerror(k < 0 ? errno : ENOSPC));
        p += k, n -= size_t(k), offset += size_t(k);
    }
    return {};
}

}  // namespace

Result<void> EncodedTexture::stream_to(const fs::path& final_path) {
    if (container_ != TextureContainer::Dds) return make_error(final_path.string() + ": only DDS files are written as they are baked");
    if (file_) return make_error(final_path.string() + ": the file is already being written");
    std::error_code ec;
    if (final_path.has_parent_path()) fs::create_directories(final_path.parent_path(), ec);
    if (ec) return make_error(final_path.parent_path().string() + ": cannot create folder: " + ec.message());
    auto out = std::make_unique<AtomicOutput>(final_path);
    fd_ = ::open(out->temp_path().c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd_ < 0) return make_error(final_path.string() + ": cannot open for writing: " + std::strerror(errno));
    file_ = std::move(out);
    rows_written_.assign(layout_.level_offset.size(), 0);
    // The header: every byte before level 0.
    return write_at(fd_, data_.get(), layout_.level_offset[0], 0, final_path);
}

// Rows [written, rows) of `level` to the file at their offset; the whole 2 MiB pages (the huge pages the
// buffer was hinted for) of the level's rows in the file go back to the system.
Result<void> EncodedTexture::write_rows(int level, int rows) {
    int& written = rows_written_[size_t(level)];
    const int upto = std::min(rows, std::max(1, height_ >> level));
    if (upto <= written) return {};
    const size_t row_bytes =
        size_t(std::max(1, width_ >> level)) * size_t(layout_.stored_channels) * size_t(encoding_bytes(encoding_));
    const size_t at = layout_.level_offset[size_t(level)];
    const uint8_t* start = data_.get() + at;
    const size_t from = size_t(written) * row_bytes, to = size_t(upto) * row_bytes;
    if (auto ok = write_at(fd_, start + from, to - from, at + from, file_->final_path()); !ok) return ok;
    written = upto;
    detail::advise_whole_pages(start, to, uintptr_t(2) << 20, MADV_DONTNEED);
    return {};
}

Result<std::string> EncodedTexture::finish_file(const fs::path& final_path, std::unique_ptr<AtomicOutput>& out) {
    if (!file_) return make_error(final_path.string() + ": the file was not written as it was baked");
    if (file_->final_path() != final_path)
        return make_error(final_path.string() + ": the texture was written as " + file_->final_path().string());
    for (int L = 0; L < int(rows_written_.size()); ++L)
        if (auto ok = write_rows(L, std::max(1, height_ >> L)); !ok) return ok.error();
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) return make_error(final_path.string() + ": cannot write: " + std::strerror(errno));
    out = std::move(file_);
    // Hashed as written: read back in windows from the page cache, the raw rows being gone.
    auto hash = sha256_file(out->temp_path());
    if (!hash) return make_error(final_path.string() + ": " + hash.error().message);
    return *hash;
}

// Compresses the EXR chunks that rows up to `rows` of `level` complete (whole 64-row tile rows of a
// mipmapped file's level, whole 16-row blocks of a per-mip file; the rest with the level's last row) and
// returns the raw pages compressed to the system.
Result<void> EncodedTexture::feed_exr(int level, int rows) {
    const bool mipmapped = container_ == TextureContainer::Exr;
    const auto& slot = exr_[mipmapped ? 0 : size_t(level)];
    if (!slot) return make_error(exr_problem_);
    const int encoder_level = mipmapped ? level : 0;
    const size_t row_bytes =
        size_t(std::max(1, width_ >> level)) * size_t(layout_.stored_channels) * size_t(encoding_bytes(encoding_));
    const uint8_t* start = data_.get() + layout_.level_offset[size_t(level)];
    const int before = slot->encoder.rows_done(encoder_level);
    if (auto ok = slot->encoder.add_rows(encoder_level, start, rows); !ok) return ok;
    const int done = slot->encoder.rows_done(encoder_level);
    // Whole 2 MiB pages (the huge pages the buffer was hinted for) of the rows compressed.
    if (done > before) detail::advise_whole_pages(start, size_t(done) * row_bytes, uintptr_t(2) << 20, MADV_DONTNEED);
    return {};
}

Result<std::vector<std::span<const uint8_t>>> EncodedTexture::exr_file(int level, const std::vector<std::string>& meaning) {
    if (!exr()) return make_error("EXR files are for the exr container and per-mip float data");
    const bool mipmapped = container_ == TextureContainer::Exr;
    if (mipmapped != (level < 0)) return make_error("a mipmapped EXR is one file; per-mip EXRs are one a level");
    const int first = std::max(level, 0);
    if (!exr_[size_t(first)]) return make_error(exr_problem_);
    ExrStream& x = *exr_[size_t(first)];
    const std::vector<std::string> stored_meaning = meaning_for(channels_, layout_.stored_channels, meaning);
    if (!x.done) {
        const int levels = mipmapped ? int(layout_.level_offset.size()) : 1;
        bool streamed = false;
        for (int L = 0; L < levels; ++L) streamed |= x.encoder.rows_done(L) > 0;
        if (streamed && stored_meaning != meaning_for(channels_, layout_.stored_channels, meaning_))
            return make_error("the channel meaning differs from the one the EXR file was streamed with");
        for (int L = first; L < first + levels; ++L)
            if (auto ok = feed_exr(L, std::max(1, height_ >> L)); !ok) return ok.error();
        // The attributes OpenImageIO's EXR writer stored before (its DateTime is OpenEXR's capDate).
        std::vector<std::pair<std::string, std::string>> strings{
            {"Software", "specbake"}, {"capDate", reproducible_date_time()}, {"specbake:channels", joined(stored_meaning)}};
        if (mipmapped) {
            strings.emplace_back("textureformat", "Plain Texture");
            strings.emplace_back("wrapmodes", std::string(wrap_name(wrap_)) + "," + wrap_name(wrap_));
        }
        auto file = x.encoder.file(strings);
        if (!file) return file.error();
        x.file = std::move(*file);
        x.meaning = stored_meaning;
        x.done = true;
    }
    if (x.meaning != stored_meaning)
        return make_error("the channel meaning differs from the one the EXR file was written with");
    return x.file;
}

Result<void> EncodedTexture::compress_rows(int level, int rows) {
    if (block_ != BlockFormat::None) return block_rows(level, rows);
    if (file_) return write_rows(level, rows);
    if (exr()) return feed_exr(level, rows);
    if (png()) {
        auto& stream = png_[size_t(level)];
        const int w = std::max(1, width_ >> level), h = std::max(1, height_ >> level);
        if (!stream) stream = std::make_unique<PngLevelStream>(w, h, layout_.stored_channels,
                                                               8 * encoding_bytes(encoding_), kPngZlibLevel);
        const uint8_t* start = data_.get() + layout_.level_offset[size_t(level)];
        if (auto ok = stream->add_rows(start, rows); !ok) return ok;
        // Whole 2 MiB pages (the huge pages the buffer was hinted for) of rows no strip reads again.
        if (stream->done()) {
            const size_t level_bytes = size_t(h) * stream->row_bytes();
            detail::advise_whole_pages(start, level_bytes, uintptr_t(2) << 20, MADV_DONTNEED);
        } else {
            detail::advise_whole_pages(start, size_t(stream->rows_read()) * stream->row_bytes(), uintptr_t(2) << 20,
                                       MADV_DONTNEED);
        }
        return {};
    }
    if (!supercompressed()) return make_error("zstd streams are for zstd-supercompressed KTX2 files");
    if (streams_.empty()) streams_.resize(layout_.level_offset.size());
    auto& slot = streams_[size_t(level)];
    const size_t w = size_t(std::max(1, width_ >> level)), h = size_t(std::max(1, height_ >> level));
    const size_t row_bytes = w * size_t(layout_.stored_channels) * size_t(encoding_bytes(encoding_));
    const size_t length = h * row_bytes;
    if (!slot) {
        slot = std::make_unique<LevelStream>();
        slot->cctx = ZSTD_createCCtx();
        if (!slot->cctx) return make_error("zstd: cannot create a compression context");
        const int zl = supercompression_.zstd_level;
        ZSTD_CCtx_setParameter(slot->cctx, ZSTD_c_compressionLevel, zl);
        ZSTD_CCtx_setParameter(slot->cctx, ZSTD_c_stableInBuffer, 1);
        ZSTD_CCtx_setParameter(slot->cctx, ZSTD_c_stableOutBuffer, 1);
        ZSTD_CCtx_setPledgedSrcSize(slot->cctx, length);
        slot->capacity = ZSTD_compressBound(length);
        slot->out.reset(new uint8_t[slot->capacity]);
        slot->window = (size_t(1) << ZSTD_getCParams(zl, length, 0).windowLog) + ZSTD_BLOCKSIZE_MAX;
    }
    LevelStream& z = *slot;
    if (z.done) return {};
    uint8_t* const start = data_.get() + layout_.level_offset[size_t(level)];
    const size_t available = std::min(length, size_t(rows) * row_bytes);
    const ZSTD_EndDirective mode = available == length ? ZSTD_e_end : ZSTD_e_continue;
    ZSTD_inBuffer in{start, available, z.in_pos};
    ZSTD_outBuffer out{z.out.get(), z.capacity, z.out_pos};
    for (;;) {
        const size_t left = ZSTD_compressStream2(z.cctx, &out, &in, mode);
        if (ZSTD_isError(left)) return make_error(std::string("zstd: ") + ZSTD_getErrorName(left));
        if (mode == ZSTD_e_continue || left == 0) break;
    }
    z.in_pos = in.pos, z.out_pos = out.pos;
    if (mode == ZSTD_e_end) {
        z.done = true;
        ZSTD_freeCCtx(z.cctx);
        z.cctx = nullptr;
        return {};
    }
    // Whole 2 MiB pages (the huge pages the buffer was hinted for) wholly behind the window.
    if (z.in_pos > z.window + z.released) {
        const void* to = detail::advise_whole_pages(start + z.released, z.in_pos - z.window - z.released,
                                                    uintptr_t(2) << 20, MADV_DONTNEED);
        if (to) z.released = size_t(static_cast<const uint8_t*>(to) - start);
    }
    return {};
}

Result<std::vector<std::span<const uint8_t>>> EncodedTexture::png_level(int level) {
    if (!png()) return make_error("per-mip PNG levels are for integer data in the png container");
    if (!png_[size_t(level)] || !png_[size_t(level)]->done())
        if (auto ok = compress_rows(level, std::max(1, height_ >> level)); !ok) return ok.error();
    return png_[size_t(level)]->pieces();
}

std::vector<std::span<const uint8_t>> EncodedTexture::streamed_levels() const {
    std::vector<std::span<const uint8_t>> levels;
    if (streams_.size() != layout_.level_offset.size()) return {};
    for (const auto& z : streams_) {
        if (!z || !z->done) return {};
        levels.emplace_back(z->out.get(), z->out_pos);
    }
    return levels;
}

ManifestOutput EncodedTexture::entry(const std::string& filename, const std::string& kind) const {
    ManifestOutput e;
    e.kind = kind;
    e.path = filename;
    e.format = container_name(container_);
    e.width = width_;
    e.height = height_;
    e.mips = int(layout_.level_offset.size());
    e.channels = layout_.stored_channels;
    e.extra["encoding"] = encoding_name(encoding_);
    e.extra["gpu_format"] = gpu_format_name(encoding_, layout_.stored_channels);
    if (container_ == TextureContainer::Ktx2) e.extra["vkFormat"] = ktx2_vk_format(encoding_, layout_.stored_channels);
    else {
        e.extra["dxgiFormat"] = dds_dxgi_format(encoding_, channels_, nullptr);
        const auto legacy = dds_legacy_pixel_format(encoding_, channels_);
        e.extra["dds_header"] = legacy ? std::string("legacy ") + legacy->name : std::string("dx10");
    }
    return e;
}

namespace {

// The level `L` of `t` as 8-bit texels in stored channel order (DDS A8R8G8B8 back to RGBA; 16-bit unorm
// rounded to 8 bits: BC endpoints and the ASTC LDR decode hold 8 bits). `scratch` holds them when
// they are not the level's own bytes.
const uint8_t* level_as_unorm8(const EncodedTexture& t, size_t L, std::vector<uint8_t>& scratch) {
    const ContainerLayout& layout = t.layout();
    const int w = std::max(1, t.width() >> L), h = std::max(1, t.height() >> L);
    return as_unorm8(t.bytes().data() + layout.level_offset[L], size_t(w) * size_t(h), layout.stored_channels,
                     t.encoding(), t.bgra(), scratch);
}

// The file of `t` with every level block-compressed as `format`, zstd-supercompressed when `t` asks for it
// (KTX2). BC levels are encoded in parallel; ASTC levels one after another, each on every thread.
Result<BlockFile> block_compressed(const EncodedTexture& t, BlockFormat format) {
    if (t.encoding() != TexelEncoding::Unorm8 && t.encoding() != TexelEncoding::Unorm16)
        return make_error("block compression takes 8- or 16-bit unorm data");
    const ContainerLayout& layout = t.layout();
    const int channels = layout.stored_channels;
    const int astc_side = t.supercompression().astc_block;
    std::vector<std::vector<uint8_t>> levels(layout.level_offset.size());
    if (is_astc(format)) {
        std::unique_ptr<AstcEncoder> astc;
        for (size_t L = 0; L < levels.size(); ++L) {
            std::vector<uint8_t> scratch;
            const uint8_t* src = level_as_unorm8(t, L, scratch);
            auto blocks = encode_blocks(format, astc_side, astc, src, std::max(1, t.width() >> L),
                                        std::max(1, t.height() >> L), channels);
            if (!blocks) return blocks.error();
            levels[L] = std::move(*blocks);
        }
    } else {
        tbb::parallel_for(size_t(0), levels.size(), [&](size_t L) {
            std::vector<uint8_t> scratch;
            const uint8_t* src = level_as_unorm8(t, L, scratch);
            levels[L] = compress_level(format, src, std::max(1, t.width() >> L), std::max(1, t.height() >> L), channels);
        });
    }
    return block_file(t.container(), format, t.width(), t.height(), std::move(levels),
                      t.supercompressed() ? t.supercompression().zstd_level : 0, astc_side);
}

// The manifest entry of a block-compressed file: its format names and the channels the blocks hold.
void describe_blocks(ManifestOutput& e, const EncodedTexture& t, const EncodedFile& f) {
    const int side = t.supercompression().astc_block;
    e.extra["gpu_format"] = block_gpu_format_name(f.block, side);
    e.extra["encoding"] = "unorm8";
    if (t.container() == TextureContainer::Ktx2) e.extra["vkFormat"] = block_vk_format(f.block, side);
    else {
        e.extra.erase("dxgiFormat");
        e.extra["dds_header"] = std::string("legacy FourCC ") + block_fourcc(f.block);
    }
    if (is_astc(f.block)) {
        e.extra["astc_block"] = std::to_string(side) + "x" + std::to_string(side);
        // What the decoded RGBA holds beyond the kept channels (io/texture/astc_codec.h).
        e.extra["astc_decoded_as"] = f.block == BlockFormat::AstcR ? "r, r, r, 1" : f.block == BlockFormat::AstcRg
                                                                                      ? "x, y, 0, 1" : "r, g, b, a";
    }
    if (block_channels(f.block) < 4) {
        e.channels = block_channels(f.block);
        std::vector<std::string> meaning = e.extra["channel_meaning"];
        meaning.resize(size_t(e.channels));
        e.extra["channel_meaning"] = meaning;
    }
}

}  // namespace

namespace {

// One file of write_encoded_textures: a whole texture (KTX2, DDS, EXR), or level `level` of a per-mip one.
struct TargetFile {
    size_t file = 0;
    int level = -1;
    std::unique_ptr<AtomicOutput> out;
    ManifestOutput entry;
};

// The manifest entry of an EXR or per-mip file of `t`: the stored format and what each channel means.
ManifestOutput level_file_entry(const EncodedTexture& t, const EncodedFile& f, const std::string& filename,
                                int level) {
    const int channels = t.layout().stored_channels;
    ManifestOutput e;
    e.kind = f.kind;
    e.path = filename;
    e.format = t.png() ? "png" : "exr";
    e.width = level < 0 ? t.width() : std::max(1, t.width() >> level);
    e.height = level < 0 ? t.height() : std::max(1, t.height() >> level);
    e.mips = level < 0 ? int(t.layout().level_offset.size()) : 1;
    e.channels = channels;
    e.extra["encoding"] = encoding_name(t.encoding());
    e.extra["gpu_format"] = gpu_format_name(t.encoding(), channels);
    e.extra["channel_meaning"] = meaning_for(t.channels(), channels, f.channel_meaning);
    e.extra["channel_names"] = exr_names(channels);
    if (level >= 0) e.extra["mip_level"] = level;
    return e;
}

// Writes a KTX2 or DDS file: supercompressed (its levels in parallel) or block-compressed where asked,
// hashed from memory.
Result<void> write_container(const EncodedFile& f, TargetFile& target) {
    const EncodedTexture& t = *f.texture;
    ManifestOutput& entry = target.entry;
    if (t.streams_to_file()) {  // DDS written as it was baked (stream_to): the rest of its rows, the hash
        if (f.block != BlockFormat::None)
            return make_error(target.out->final_path().string() + ": a file written as it was baked cannot be block-compressed");
        const fs::path final_path = target.out->final_path();
        auto hash = f.texture->finish_file(final_path, target.out);
        if (!hash) return hash.error();
        entry.sha256 = *hash;
        entry.extra["bytes"] = t.bytes().size();
        entry.extra["uncompressed_bytes"] = t.bytes().size();
        entry.extra["block_compression"] = block_format_name(f.block);
        entry.extra["supercompression"] = "none";
        return {};
    }
    Ktx2Pieces packed;
    BlockFile blocks;
    std::vector<std::span<const uint8_t>> pieces{t.bytes()};
    if (f.block != BlockFormat::None) {
        // Blocks made as the rows arrived (set_block_format), else from the whole levels now.
        std::vector<std::vector<uint8_t>> streamed;
        if (t.block_format() == f.block) {
            auto levels = f.texture->take_block_levels();
            if (!levels) return make_error(target.out->final_path().string() + ": " + levels.error().message);
            streamed = std::move(*levels);
        }
        auto b = !streamed.empty() ? block_file(t.container(), f.block, t.width(), t.height(), std::move(streamed),
                                                t.supercompressed() ? t.supercompression().zstd_level : 0,
                                                t.supercompression().astc_block)
                                   : block_compressed(t, f.block);
        if (!b) return make_error(target.out->final_path().string() + ": " + b.error().message);
        blocks = std::move(*b);
        pieces = blocks.pieces();
        describe_blocks(entry, t, f);
    } else if (const auto streamed = t.streamed_levels(); t.supercompressed() && !streamed.empty()) {
        // Compressed while the bake ran (compress_rows): the header, then the levels smallest first.
        std::vector<size_t> sizes;
        for (std::span<const uint8_t> l : streamed) sizes.push_back(l.size());
        packed.header = ktx2_zstd_header(t.bytes(), sizes);
        pieces = {std::span<const uint8_t>(packed.header)};
        for (size_t L = streamed.size(); L-- > 0;) pieces.push_back(streamed[L]);
    } else if (t.supercompressed()) {
        auto z = ktx2_zstd_pieces(t.bytes(), t.layout(), t.supercompression().zstd_level);
        if (!z) return make_error(target.out->final_path().string() + ": " + z.error().message);
        packed = std::move(*z);
        pieces = packed.pieces();
    }
    Sha256 hash;
    size_t size = 0;
    for (std::span<const uint8_t> p : pieces) hash.update(p), size += p.size();
    entry.sha256 = hash.hex();
    entry.extra["bytes"] = size;
    entry.extra["uncompressed_bytes"] = t.bytes().size();
    entry.extra["block_compression"] = block_format_name(f.block);
    entry.extra["supercompression"] = t.supercompressed() ? "zstd" : "none";
    if (t.supercompressed()) entry.extra["zstd_level"] = t.supercompression().zstd_level;
    return write_pieces_to(target.out->temp_path(), target.out->final_path(), pieces);
}

// Writes an EXR file (every level, tiled) or one level of a per-mip output (PNG, or EXR for float data).
Result<void> write_level_file(const EncodedFile& f, TargetFile& target) {
    EncodedTexture& t = *f.texture;
    ManifestOutput& entry = target.entry;
    if (t.png()) {
        auto pieces = t.png_level(target.level);
        if (!pieces) return make_error(target.out->final_path().string() + ": " + pieces.error().message);
        Sha256 hash;
        for (std::span<const uint8_t> p : *pieces) hash.update(p);
        entry.sha256 = hash.hex();
        return write_pieces_to(target.out->temp_path(), target.out->final_path(), *pieces);
    }
    auto pieces = t.exr_file(target.level, f.channel_meaning);
    if (!pieces) return make_error(target.out->final_path().string() + ": " + pieces.error().message);
    Sha256 hash;
    for (std::span<const uint8_t> p : *pieces) hash.update(p);
    entry.sha256 = hash.hex();
    return write_pieces_to(target.out->temp_path(), target.out->final_path(), *pieces);
}

}  // namespace

Result<std::vector<ManifestOutput>> write_encoded_textures(std::span<const EncodedFile> files, const fs::path& dir) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) return make_error(dir.string() + ": cannot create folder: " + ec.message());
    std::vector<TargetFile> targets;
    for (size_t i = 0; i < files.size(); ++i) {
        const EncodedFile& f = files[i];
        const EncodedTexture& t = *f.texture;
        auto add = [&](const std::string& filename, int level) {
            TargetFile target{i, level, std::make_unique<AtomicOutput>(dir / filename), {}};
            if (EncodedTexture::is_container_file(t.container())) {
                target.entry = t.entry(filename, f.kind);
                target.entry.extra["channel_meaning"] = meaning_for(t.channels(), gpu_channels(t.channels()), f.channel_meaning);
            } else {
                target.entry = level_file_entry(t, f, filename, level);
            }
            targets.push_back(std::move(target));
        };
        if (t.container() != TextureContainer::PngPerMip) {
            add(f.stem + '.' + container_name(t.container()), -1);
            continue;
        }
        for (int L = 0; L < int(t.layout().level_offset.size()); ++L)
            add(f.stem + "_mip" + std::to_string(L) + (t.png() ? ".png" : ".exr"), L);
    }
    // Each file is encoded, hashed and written by one task; the first error in file order is reported.
    std::vector<std::optional<Error>> errors(targets.size());
    tbb::parallel_for(size_t(0), targets.size(), [&](size_t k) {
        TargetFile& target = targets[k];
        const EncodedFile& f = files[target.file];
        auto ok = EncodedTexture::is_container_file(f.texture->container()) ? write_container(f, target)
                                                                            : write_level_file(f, target);
        if (!ok) errors[k] = ok.error();
    });
    for (const std::optional<Error>& e : errors)
        if (e) return *e;
    std::vector<ManifestOutput> entries;
    for (TargetFile& target : targets) {
        if (auto ok = target.out->commit(); !ok) return ok.error();
        entries.push_back(std::move(target.entry));
    }
    return entries;
}

}  // namespace specbake::io
