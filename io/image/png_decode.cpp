// decode_plain_png(): chunk walk with CRC checks, inflate (libdeflate), the five PNG row filters (PNG spec
// Sec. 9), and OpenImageIO's integer-to-float conversion.
#include "io/image/png_decode.h"

#include <libdeflate.h>
#include <zlib.h>

#include <cstdlib>
#include <cstring>
#include <string_view>
#include <vector>

namespace specbake::io {

namespace {

uint32_t be32(const uint8_t* p) { return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3]; }

// Ancillary chunks that change neither the pixels nor the colour space OpenImageIO reports.
// oFFs is a page-layout position (OpenImageIO's writer adds a zero one), nothing a texture reader uses.
bool harmless_chunk(std::string_view type) {
    return type == "pHYs" || type == "oFFs" || type == "tIME" || type == "tEXt" || type == "zTXt" || type == "iTXt";
}

int paeth(int a, int b, int c) {
    const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
    return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

}  // namespace

std::optional<DecodedImage> decode_plain_png(std::span<const uint8_t> b, bool keep_integers) {
    static const uint8_t signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    if (b.size() < 8 || std::memcmp(b.data(), signature, 8) != 0) return std::nullopt;
    uint32_t width = 0, height = 0;
    int depth = 0, channels = 0;
    std::vector<uint8_t> compressed;
    bool header = false, end = false;
    for (size_t at = 8; !end;) {
        if (at + 12 > b.size()) return std::nullopt;
        const uint32_t length = be32(b.data() + at);
        if (size_t(length) + 12 > b.size() - at) return std::nullopt;
        const std::string_view type(reinterpret_cast<const char*>(b.data() + at + 4), 4);
        const uint8_t* data = b.data() + at + 8;
        const uLong crc = crc32(0L, b.data() + at + 4, uInt(length + 4));
        if (crc != be32(data + length)) return std::nullopt;
        if (type == "IHDR") {
            if (header || length != 13) return std::nullopt;
            width = be32(data), height = be32(data + 4), depth = data[8];
            const int colour = data[9];
            // Compression, filter method 0; no interlacing.
            if (data[10] != 0 || data[11] != 0 || data[12] != 0) return std::nullopt;
            channels = colour == 0 ? 1 : colour == 4 ? 2 : colour == 2 ? 3 : colour == 6 ? 4 : 0;
            if (channels == 0 || (depth != 8 && depth != 16)) return std::nullopt;
            if (width == 0 || height == 0 || width > (1u << 15) || height > (1u << 15)) return std::nullopt;
            header = true;
        } else if (!header) {
            return std::nullopt;
        } else if (type == "IDAT") {
            compressed.insert(compressed.end(), data, data + length);
        } else if (type == "IEND") {
            end = true;
        } else if (!harmless_chunk(type)) {
            return std::nullopt;
        }
        at += size_t(length) + 12;
    }
    const size_t bytes_per_pixel = size_t(channels) * size_t(depth / 8);
    const size_t stride = size_t(width) * bytes_per_pixel;
    // The rows with their filter bytes; a 16-bit file's in uint16 storage, so that its values can be made
    // native uint16 in place (the storage is accessed as bytes until then, which any object allows).
    const size_t raw_bytes = size_t(height) * (stride + 1);
    std::vector<uint8_t> raw8;
    std::vector<uint16_t> raw16;
    if (depth == 16) raw16.resize((raw_bytes + 1) / 2);
    else raw8.resize(raw_bytes);
    uint8_t* const raw = depth == 16 ? reinterpret_cast<uint8_t*>(raw16.data()) : raw8.data();
    // libdeflate inflates the whole stream at once (its size is known), 1.6-8x faster than zlib's inflate on
    // 4096^2 maps (docs/texture-bake.md). Like zlib's uncompress(), bytes after the stream's end are ignored.
    libdeflate_decompressor* inflater = libdeflate_alloc_decompressor();
    if (!inflater) return std::nullopt;
    size_t used = 0, raw_size = 0;
    const libdeflate_result inflated = libdeflate_zlib_decompress_ex(inflater, compressed.data(), compressed.size(),
                                                                     raw, raw_bytes, &used, &raw_size);
    libdeflate_free_decompressor(inflater);
    if (inflated != LIBDEFLATE_SUCCESS || raw_size != raw_bytes) return std::nullopt;

    // Unfilter in place: row y's bytes follow its filter byte; the previous row is already decoded.
    for (size_t y = 0; y < height; ++y) {
        uint8_t* row = raw + y * (stride + 1) + 1;
        const uint8_t* up = y ? row - (stride + 1) : nullptr;
        const int filter = row[-1];
        for (size_t i = 0; i < stride; ++i) {
            const int a = i >= bytes_per_pixel ? row[i - bytes_per_pixel] : 0;
            const int u = up ? up[i] : 0;
            const int c = up && i >= bytes_per_pixel ? up[i - bytes_per_pixel] : 0;
            switch (filter) {
                case 0: break;
                case 1: row[i] = uint8_t(row[i] + a); break;
                case 2: row[i] = uint8_t(row[i] + u); break;
                case 3: row[i] = uint8_t(row[i] + (a + u) / 2); break;
                case 4: row[i] = uint8_t(row[i] + paeth(a, u, c)); break;
                default: return std::nullopt;
            }
        }
    }

    DecodedImage out;
    out.info.bits_per_channel = depth;
    out.info.is_float = false;
    out.info.format = "png";
    out.info.color_space = "sRGB";  // OpenImageIO's claim for a PNG without colour chunks
    const size_t values = size_t(width) * size_t(channels);
    if (keep_integers) {
        IntegerTexels& t = out.integers;
        t.bits = depth, t.width = int(width), t.height = int(height), t.channels = channels;
        if (depth == 8) {
            t.offset = 1, t.row_stride = stride + 1;
            t.bytes = std::move(raw8);
            return out;
        }
        // Big-endian pairs after each filter byte to native values, row after row: value i of row y lands at
        // byte 2 (y values + i), before the bytes of the values not read yet (y (stride + 1) + 1 + 2 i on).
        for (size_t y = 0; y < height; ++y) {
            const uint8_t* row = raw + y * (stride + 1) + 1;
            uint16_t* dst = raw16.data() + y * values;
            for (size_t i = 0; i < values; ++i) dst[i] = uint16_t(row[2 * i] << 8 | row[2 * i + 1]);
        }
        raw16.resize(size_t(height) * values);
        t.offset = 0, t.row_stride = values;
        t.words = std::move(raw16);
        return out;
    }
    out.image = Image(int(width), int(height), channels);
    // OpenImageIO converts by multiplying with the reciprocal in float (not a division): the same bits.
    const float scale = depth == 8 ? 1.0f / 255.0f : 1.0f / 65535.0f;
    float* dst = out.image.pixels.data();
    for (size_t y = 0; y < height; ++y) {
        const uint8_t* row = raw + y * (stride + 1) + 1;
        if (depth == 8)
            for (size_t i = 0; i < values; ++i) *dst++ = float(row[i]) * scale;
        else
            for (size_t i = 0; i < values; ++i) *dst++ = float(uint32_t(row[2 * i]) << 8 | row[2 * i + 1]) * scale;
    }
    return out;
}

}  // namespace specbake::io
