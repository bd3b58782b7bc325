// A PNG decoder for the plain files texture libraries are made of (8/16-bit gray, gray+alpha, RGB, RGBA,
// not interlaced, no colour chunks), so a bake of such maps does not load OpenImageIO (~0.3 s per process).
#pragma once

#include "io/image/image_io.h"

#include <cstdint>
#include <optional>
#include <span>

namespace specbake::io {

// The image exactly as OpenImageIO decodes it (values v / (2^bits - 1) rounded as float(v) * (1.0f / max),
// alpha unassociated, colour space "sRGB", format "png"), or nothing when the file is anything else:
// palette, interlaced, a gAMA/sRGB/iCCP/cHRM/sBIT/tRNS or unknown chunk, a CRC or zlib error, a size
// outside 1..2^15. The caller then decodes it through OpenImageIO, which also words the errors.
// keep_8bit: an 8-bit file's texels stay bytes (DecodedImage::bytes8: the inflated rows, each after its
// filter byte), `image` empty.
std::optional<DecodedImage> decode_plain_png(std::span<const uint8_t> bytes, bool keep_8bit = false);

}  // namespace specbake::io
