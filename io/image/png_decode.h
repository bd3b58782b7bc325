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
// keep_integers: the texels stay integers (DecodedImage::integers), `image` empty: an 8-bit file's as the
// inflated rows, each after its filter byte; a 16-bit file's as native uint16 rows, converted in the
// buffer they were inflated into.
std::optional<DecodedImage> decode_plain_png(std::span<const uint8_t> bytes, bool keep_integers = false);

}  // namespace specbake::io
