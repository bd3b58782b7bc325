#include "io/image/exr_encode.h"

#include <libdeflate.h>

#include <algorithm>
#include <cstring>
#include <numeric>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace specbake::io {

namespace {

constexpr uint32_t kMagic = 20000630;
constexpr uint32_t kVersion = 2;
constexpr uint32_t kTiledFlag = 0x200;     // single-part tiled
constexpr uint32_t kLongNamesFlag = 0x400;  // some attribute, type or channel name is longer than 31 bytes
constexpr uint8_t kZipCompression = 3;      // ZIP_COMPRESSION: 16 scanlines a chunk
constexpr int kZipScanlines = 16;
constexpr uint8_t kMipmapRoundDown = 1;     // tiledesc mode: MIPMAP_LEVELS + 16 * ROUND_DOWN

void put_u32(std::vector<uint8_t>& out, uint32_t v) {
    for (int k = 0; k < 4; ++k) out.push_back(uint8_t(v >> (8 * k)));
}
void put_i32(std::vector<uint8_t>& out, int v) { put_u32(out, uint32_t(v)); }
void put_f32(std::vector<uint8_t>& out, float v) {
    uint32_t bits;
    std::memcpy(&bits, &v, 4);
    put_u32(out, bits);
}
void put_name(std::vector<uint8_t>& out, const std::string& name) {
    out.insert(out.end(), name.begin(), name.end());
    out.push_back(0);
}

int round_down_levels(int width, int height) {
    int levels = 1;
    for (int m = std::max(width, height); m > 1; m >>= 1) ++levels;
    return levels;
}

struct Attribute {
    std::string name, type;
    std::vector<uint8_t> value;
};

}  // namespace

// Both steps at once: each output byte is the difference of two input bytes (the even-indexed bytes' first,
// then the odd-indexed ones', the first odd-indexed byte against the last even-indexed one), 16 at a time
// with SSE2 where the machine has it.
void exr_zip_predict(const uint8_t* raw, size_t n, uint8_t* out) {
    if (n == 0) return;
    const size_t even = (n + 1) / 2, odd = n / 2;
    out[0] = raw[0];
    size_t i = 1, j = 1;
#if defined(__SSE2__)
    const __m128i low = _mm_set1_epi16(0x00ff), bias = _mm_set1_epi8(char(0x80));
    // The even-indexed (or, shifted, odd-indexed) bytes of the 32 bytes at `p`.
    const auto evens = [&](const uint8_t* p) {
        const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
        const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 16));
        return _mm_packus_epi16(_mm_and_si128(a, low), _mm_and_si128(b, low));
    };
    const auto odds = [&](const uint8_t* p) {
        const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
        const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 16));
        return _mm_packus_epi16(_mm_srli_epi16(a, 8), _mm_srli_epi16(b, 8));
    };
    // out[i..i+16) from raw[2i - 2 .. 2i + 32): every load stays below raw + n.
    for (; i + 16 <= even && 2 * i + 32 <= n; i += 16) {
        const __m128i d = _mm_sub_epi8(evens(raw + 2 * i), evens(raw + 2 * i - 2));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i), _mm_add_epi8(d, bias));
    }
    for (; j + 16 <= odd && 2 * j + 32 <= n; j += 16) {
        const __m128i d = _mm_sub_epi8(odds(raw + 2 * j), odds(raw + 2 * j - 2));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out + even + j), _mm_add_epi8(d, bias));
    }
#endif
    for (; i < even; ++i) out[i] = uint8_t(raw[2 * i] - raw[2 * i - 2] + 128);
    if (odd) out[even] = uint8_t(raw[1] - raw[2 * (even - 1)] + 128);
    for (; j < odd; ++j) out[even + j] = uint8_t(raw[2 * j + 1] - raw[2 * j - 1] + 128);
}

// One line of a chunk as OpenEXR lays it out: the `n` samples of each channel in turn, channel k (in the
// stored order) taken from position source[k] of the interleaved texels at `row`. One pass over the texels.
template <size_t Sample, int Channels>
void split_line(const uint8_t* row, size_t n, const int* source, uint8_t* dst) {
    for (size_t x = 0; x < n; ++x, row += Sample * Channels)
        for (int k = 0; k < Channels; ++k)
            std::memcpy(dst + (size_t(k) * n + x) * Sample, row + size_t(source[k]) * Sample, Sample);
}

struct ExrEncoder::Level {
    int width = 0, height = 0;
    int chunk_rows = 0;   // rows a chunk spans: 16 (scanline) or the tile side
    int chunk_width = 0;  // columns a chunk spans: the width (scanline) or the tile side
    int tiles_x = 1;
    int rows_done = 0;
    std::vector<std::vector<uint8_t>> chunks;  // in offset-table order, each with its chunk header
    libdeflate_compressor* deflater = nullptr;
    std::vector<uint8_t> raw, predicted, packed;  // one chunk's scratch, released with the deflater
    void release() {
        libdeflate_free_compressor(deflater);
        deflater = nullptr;
        raw = {}, predicted = {}, packed = {};
    }
    ~Level() { libdeflate_free_compressor(deflater); }
};

ExrEncoder::ExrEncoder(ExrEncoder&&) noexcept = default;
ExrEncoder& ExrEncoder::operator=(ExrEncoder&&) noexcept = default;
ExrEncoder::~ExrEncoder() = default;

Result<ExrEncoder> ExrEncoder::create(const ExrImageDesc& desc, int deflate_level) {
    if (desc.width < 1 || desc.height < 1)
        return make_error("EXR: " + std::to_string(desc.width) + "x" + std::to_string(desc.height) + " has no texels");
    if (desc.channel_names.empty()) return make_error("EXR: no channels");
    std::vector<std::string> sorted = desc.channel_names;
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end() || sorted.front().empty())
        return make_error("EXR: channel names must be distinct and not empty");
    if (desc.tile_side < 0) return make_error("EXR: negative tile side");
    const int levels = desc.tile_side ? round_down_levels(desc.width, desc.height) : 1;
    if (desc.levels != levels)
        return make_error("EXR: a " + std::string(desc.tile_side ? "mipmapped" : "scanline") + " " +
                          std::to_string(desc.width) + "x" + std::to_string(desc.height) + " image has " +
                          std::to_string(levels) + " levels, not " + std::to_string(desc.levels));
    if (deflate_level < 1 || deflate_level > 12) return make_error("EXR: deflate level out of 1..12");
    ExrEncoder e;
    e.desc_ = desc;
    e.deflate_level_ = deflate_level;
    for (int L = 0; L < levels; ++L) {
        auto level = std::make_unique<Level>();
        level->width = std::max(1, desc.width >> L);
        level->height = std::max(1, desc.height >> L);
        level->chunk_rows = desc.tile_side ? desc.tile_side : kZipScanlines;
        level->chunk_width = desc.tile_side ? desc.tile_side : level->width;
        level->tiles_x = (level->width + level->chunk_width - 1) / level->chunk_width;
        const int chunk_rows = (level->height + level->chunk_rows - 1) / level->chunk_rows;
        level->chunks.resize(size_t(chunk_rows) * size_t(level->tiles_x));
        e.levels_.push_back(std::move(level));
    }
    return e;
}

int ExrEncoder::rows_done(int level) const { return levels_[size_t(level)]->rows_done; }

Result<void> ExrEncoder::add_rows(int level, const uint8_t* texels, int rows) {
    if (level < 0 || size_t(level) >= levels_.size()) return make_error("EXR: no level " + std::to_string(level));
    Level& l = *levels_[size_t(level)];
    const int end = rows >= l.height ? l.height : rows / l.chunk_rows * l.chunk_rows;
    if (end <= l.rows_done) return {};
    const int channels = int(desc_.channel_names.size());
    const size_t sample = desc_.sample == ExrSample::Half ? 2 : 4;
    const size_t texel = size_t(channels) * sample;
    // The stored order: channels sorted by name; `source[k]` is the interleaved position of the k-th.
    std::vector<int> source(static_cast<size_t>(channels));
    std::iota(source.begin(), source.end(), 0);
    std::sort(source.begin(), source.end(),
              [&](int a, int b) { return desc_.channel_names[size_t(a)] < desc_.channel_names[size_t(b)]; });
    if (!l.deflater) {
        l.deflater = libdeflate_alloc_compressor(deflate_level_);
        if (!l.deflater) return make_error("EXR: cannot allocate a deflate compressor");
        const size_t chunk = size_t(l.chunk_rows) * size_t(l.chunk_width) * texel;
        l.raw.resize(chunk);
        l.predicted.resize(chunk);
        l.packed.resize(libdeflate_zlib_compress_bound(l.deflater, chunk));
    }
    for (int y0 = l.rows_done; y0 < end; y0 += l.chunk_rows) {
        const int y1 = std::min(y0 + l.chunk_rows, l.height);
        for (int tx = 0; tx < l.tiles_x; ++tx) {
            const int x0 = tx * l.chunk_width, x1 = std::min(x0 + l.chunk_width, l.width);
            // Each line of the chunk: every channel's samples of the line in turn (OpenEXR's layout).
            uint8_t* dst = l.raw.data();
            for (int y = y0; y < y1; ++y) {
                const uint8_t* row = texels + (size_t(y) * size_t(l.width) + size_t(x0)) * texel;
                const size_t n = size_t(x1 - x0);
                if (sample == 2 && channels == 4) split_line<2, 4>(row, n, source.data(), dst);
                else if (sample == 2 && channels == 2) split_line<2, 2>(row, n, source.data(), dst);
                else if (sample == 2 && channels == 1) split_line<2, 1>(row, n, source.data(), dst);
                else if (sample == 4 && channels == 4) split_line<4, 4>(row, n, source.data(), dst);
                else if (sample == 4 && channels == 2) split_line<4, 2>(row, n, source.data(), dst);
                else if (sample == 4 && channels == 1) split_line<4, 1>(row, n, source.data(), dst);
                else
                    for (int k = 0; k < channels; ++k) {
                        const uint8_t* src = row + size_t(source[size_t(k)]) * sample;
                        uint8_t* out = dst + size_t(k) * n * sample;
                        for (size_t x = 0; x < n; ++x, src += texel) std::memcpy(out + x * sample, src, sample);
                    }
                dst += n * texel;
            }
            const size_t raw_size = size_t(dst - l.raw.data());
            exr_zip_predict(l.raw.data(), raw_size, l.predicted.data());
            const size_t packed = libdeflate_zlib_compress(l.deflater, l.predicted.data(), raw_size, l.packed.data(),
                                                           l.packed.size());
            // A chunk that does not shrink is stored as it is; readers tell it by its size (the OpenEXR rule).
            const bool stored_raw = packed == 0 || packed >= raw_size;
            const uint8_t* data = stored_raw ? l.raw.data() : l.packed.data();
            const size_t size = stored_raw ? raw_size : packed;
            std::vector<uint8_t> chunk;
            chunk.reserve(size + 20);
            if (desc_.tile_side) {
                put_i32(chunk, tx), put_i32(chunk, y0 / l.chunk_rows), put_i32(chunk, level), put_i32(chunk, level);
            } else {
                put_i32(chunk, y0);
            }
            put_i32(chunk, int(size));
            chunk.insert(chunk.end(), data, data + size);
            l.chunks[size_t(y0 / l.chunk_rows) * size_t(l.tiles_x) + size_t(tx)] = std::move(chunk);
        }
    }
    l.rows_done = end;
    if (end == l.height) l.release();
    return {};
}

Result<std::vector<std::span<const uint8_t>>> ExrEncoder::file(
    const std::vector<std::pair<std::string, std::string>>& strings) {
    for (size_t L = 0; L < levels_.size(); ++L)
        if (levels_[L]->rows_done != levels_[L]->height)
            return make_error("EXR: level " + std::to_string(L) + " has rows not yet given");
    const int w = desc_.width, h = desc_.height;
    std::vector<Attribute> attributes;
    auto add = [&](const char* name, const char* type) -> std::vector<uint8_t>& {
        attributes.push_back({name, type, {}});
        return attributes.back().value;
    };
    {
        std::vector<std::string> sorted = desc_.channel_names;
        std::sort(sorted.begin(), sorted.end());
        std::vector<uint8_t>& v = add("channels", "chlist");
        for (const std::string& name : sorted) {
            put_name(v, name);
            put_i32(v, desc_.sample == ExrSample::Half ? 1 : 2);  // pixel type: HALF 1, FLOAT 2
            put_u32(v, 0);                                       // pLinear 0, three reserved bytes
            put_i32(v, 1), put_i32(v, 1);                        // x and y sampling
        }
        v.push_back(0);
    }
    add("compression", "compression").push_back(kZipCompression);
    for (const char* window : {"dataWindow", "displayWindow"}) {
        std::vector<uint8_t>& v = add(window, "box2i");
        put_i32(v, 0), put_i32(v, 0), put_i32(v, w - 1), put_i32(v, h - 1);
    }
    add("lineOrder", "lineOrder").push_back(0);  // INCREASING_Y
    put_f32(add("pixelAspectRatio", "float"), 1.0f);
    {
        std::vector<uint8_t>& v = add("screenWindowCenter", "v2f");
        put_f32(v, 0.0f), put_f32(v, 0.0f);
    }
    put_f32(add("screenWindowWidth", "float"), 1.0f);
    if (desc_.tile_side) {
        std::vector<uint8_t>& v = add("tiles", "tiledesc");
        put_u32(v, uint32_t(desc_.tile_side)), put_u32(v, uint32_t(desc_.tile_side));
        v.push_back(kMipmapRoundDown);
    }
    for (const auto& [name, value] : strings) {
        for (const Attribute& a : attributes)
            if (a.name == name) return make_error("EXR: attribute \"" + name + "\" given twice");
        if (name.empty() || name.find('\0') != std::string::npos || name.size() > 255)
            return make_error("EXR: attribute name \"" + name + "\" is not a name OpenEXR stores");
        std::vector<uint8_t>& v = add(name.c_str(), "string");
        v.assign(value.begin(), value.end());
    }
    std::sort(attributes.begin(), attributes.end(), [](const Attribute& a, const Attribute& b) { return a.name < b.name; });
    bool long_names = false;
    for (const Attribute& a : attributes) long_names |= a.name.size() > 31;
    for (const std::string& c : desc_.channel_names) long_names |= c.size() > 31;

    header_.clear();
    put_u32(header_, kMagic);
    put_u32(header_, kVersion | (desc_.tile_side ? kTiledFlag : 0) | (long_names ? kLongNamesFlag : 0));
    for (const Attribute& a : attributes) {
        put_name(header_, a.name);
        put_name(header_, a.type);
        put_i32(header_, int(a.value.size()));
        header_.insert(header_.end(), a.value.begin(), a.value.end());
    }
    header_.push_back(0);
    size_t chunk_count = 0;
    for (const auto& l : levels_) chunk_count += l->chunks.size();
    uint64_t offset = header_.size() + 8 * chunk_count;
    for (const auto& l : levels_)
        for (const std::vector<uint8_t>& chunk : l->chunks) {
            for (int k = 0; k < 8; ++k) header_.push_back(uint8_t(offset >> (8 * k)));
            offset += chunk.size();
        }
    std::vector<std::span<const uint8_t>> pieces{std::span<const uint8_t>(header_)};
    for (const auto& l : levels_)
        for (const std::vector<uint8_t>& chunk : l->chunks) pieces.emplace_back(chunk);
    return pieces;
}

}  // namespace specbake::io
