// Packs float texels into the bytes of a texture container, and back. Little-endian, tightly packed rows.
#pragma once

#include "core/image.h"
#include "io/texture/texture_writer.h"

#include <cstdint>
#include <span>
#include <vector>

namespace specbake::io {

int encoding_bytes(TexelEncoding e);  // bytes per channel: 1, 2, 2, 4

// Encodes `count` texels of interleaved floats with `src_channels` per texel, reading channels
// [first, first + channels) and writing `out_channels` per texel to `dst`; channels past `channels` get
// `pad`. Same rounding as encode_texels.
void encode_texels_into(const float* src, size_t count, int src_channels, int first, int channels,
                        TexelEncoding encoding, int out_channels, float pad, uint8_t* dst);

// Encodes `image` with `out_channels` channels; channels beyond image.channels are filled with `pad`
// (1.0 for an opaque alpha). Unorm: round(clamp(v, 0, 1) * (2^bits - 1)); Float16: round-to-nearest half.
std::vector<uint8_t> encode_texels(const Image& image, TexelEncoding encoding, int out_channels, float pad = 1.0f);

// Inverse of encode_texels for `channels` channels of a width x height level.
Image decode_texels(std::span<const uint8_t> bytes, TexelEncoding encoding, int width, int height, int channels);

}  // namespace specbake::io
