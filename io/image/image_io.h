// Image decoding for the texture bake (OpenImageIO): PNG 8/16, JPEG, TGA, TIFF, EXR, and anything else
// OpenImageIO reads. Values come back exactly as stored, with no colour conversion and no alpha
// premultiplication (normal and roughness maps are data); 8/16-bit integers are normalised to [0, 1].
#pragma once

#include "core/image.h"
#include "core/result.h"
#include "io/files/input_policy.h"

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace specbake::io {

// What the file said about itself, beside the pixels.
struct ImageInfo {
    int bits_per_channel = 8;   // 8, 16 for integer files; 16 or 32 for half/float files
    bool is_float = false;      // stored as half or float (EXR, float TIFF, HDR)
    std::string format;         // OpenImageIO format name: "png", "jpeg", "openexr", ...
    std::string color_space;    // the colour space the file claims ("sRGB", "Linear", or empty); never applied
};

// 8- or 16-bit integer texels as stored, for callers that convert values as they read them: width x height
// texels of `channels` values each, row y starting offset + y * row_stride values into `bytes` (8-bit) or
// `words` (16-bit, native byte order); value v stands for float(v) * (1.0f / (2^bits - 1)), what `image`
// would hold. A quarter (8-bit) or half (16-bit) of the float image's memory.
struct IntegerTexels {
    std::vector<uint8_t> bytes;    // 8-bit
    std::vector<uint16_t> words;   // 16-bit
    int bits = 8;
    int width = 0, height = 0, channels = 0;
    size_t offset = 0, row_stride = 0;  // in values
    bool empty() const { return bytes.empty() && words.empty(); }
};

struct DecodedImage {
    Image image;               // empty when `integers` holds the texels
    ImageInfo info;
    IntegerTexels integers;    // only when asked for (keep_integers) and the file is a plain 8/16-bit PNG
};

// Reads the first subimage, level 0. Errors name the file ("<path>: <problem>"): missing, unreadable,
// unknown format, truncated, 0x0, more than 2^15 texels per side, more texels than limits.texels.
// Non-finite values are returned as is (callers validate; see has_non_finite()). keep_integers: a plain
// 8- or 16-bit PNG (io/image/png_decode.h) comes back in `integers` (8-bit: its rows as they were inflated,
// no copy; 16-bit: the inflated rows turned into native uint16 in place), `image` empty; every other file as
// `image`.
Result<DecodedImage> decode_image(const std::filesystem::path& path, const InputLimits& limits = {},
                                  bool keep_integers = false);

// Same, from bytes in memory (embedded GLB images); `name_for_errors` is used in place of a path.
Result<DecodedImage> decode_image_memory(std::span<const uint8_t> bytes, const std::string& name_for_errors,
                                         const InputLimits& limits = {}, bool keep_integers = false);

// The chunk structure of a PNG (lengths, CRCs, IHDR fields) and its size against the texel limit
// (io/files/input_policy.h), from the bytes alone; anything that is not a PNG passes.
Result<void> check_png_structure(std::span<const uint8_t> bytes, const std::string& name, const InputLimits& limits);
// The image data of a PNG whose structure passed check_png_structure: its IDAT chunks inflate without a
// zlib error to at least the bytes the header's size, depth, colour type and interlacing need (PNG spec
// Sec. 10, Sec. 8.2), so that libpng never has to report a broken stream itself (on stderr, without the
// file's name). Inflates into a small buffer; anything that is not a PNG passes.
Result<void> check_png_image_data(std::span<const uint8_t> bytes, const std::string& name);
// The metadata segments of a JPEG that OpenImageIO reads (APP1 Exif/XMP, APP2 ICC, APP13 Photoshop), found
// by walking the markers as libjpeg does (io/image/jpeg_markers.cpp says how): each identifier NUL-terminated
// inside its segment, each segment whole and each header as long as it says, since OpenImageIO compares
// them with strcmp and reads the headers' fields without checking the length. Anything that is not a
// JPEG passes, and so does one that libjpeg itself stops reading before such a segment.
Result<void> check_jpeg_markers(std::span<const uint8_t> bytes, const std::string& name);

// Convenience forms that drop the metadata.
Result<Image> read_image(const std::filesystem::path& path, const InputLimits& limits = {});
Result<Image> read_image_memory(std::span<const uint8_t> bytes, const std::string& name_for_errors,
                                const InputLimits& limits = {});

// Writes `image` atomically as an 8- or 16-bit integer file (format from the extension: .png, .tif, ...),
// values clamped to [0, 1], no colour conversion. The error names the file.
Result<void> write_image(const std::filesystem::path& path, const Image& image, int bits);

}  // namespace specbake::io
