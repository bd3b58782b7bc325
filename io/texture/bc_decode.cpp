// BC1/BC3/BC4/BC5 block decoding after KDFS 1.3 Sec. 21.1 (BC1), 21.3 (BC3) and 21.4-21.5 (BC4, BC5).
#include "io/texture/bc_decode.h"

namespace specbake::io {
namespace {

// Eight 8-bit-unit values of a BC4 channel block and its 16 3-bit indices (KDFS 21.4): red_0 > red_1 gives
// six interpolants (7 - i) r0 + i r1 over 7, otherwise four over 5 followed by 0 and 255.
void bc4_channel(const uint8_t* block, float* out, int stride) {
    const float r0 = block[0], r1 = block[1];
    float palette[8] = {r0, r1};
    if (block[0] > block[1]) {
        for (int i = 1; i < 7; ++i) palette[1 + i] = (float(7 - i) * r0 + float(i) * r1) / 7.0f;
    } else {
        for (int i = 1; i < 5; ++i) palette[1 + i] = (float(5 - i) * r0 + float(i) * r1) / 5.0f;
        palette[6] = 0.0f;
        palette[7] = 255.0f;
    }
    uint64_t indices = 0;
    for (int k = 0; k < 6; ++k) indices |= uint64_t(block[2 + k]) << (8 * k);
    for (int t = 0; t < 16; ++t) out[t * stride] = palette[(indices >> (3 * t)) & 7u] / 255.0f;
}

// RGB of a BC1 colour block (KDFS 21.1): RGB565 endpoints widened to 8 bits by value (c * 255 / 31, 63);
// colour_0 > colour_1 or `always_four` (the colour block of BC2/BC3, KDFS 21.3) selects the four-colour
// palette (2 c0 + c1) / 3, (c0 + 2 c1) / 3, else (c0 + c1) / 2 and black (A = 0 for BC1 with alpha; the
// RGB formats written here ignore it).
void bc1_colour(const uint8_t* block, bool always_four, float* out, int stride) {
    const uint32_t c0 = uint32_t(block[0]) | uint32_t(block[1]) << 8;
    const uint32_t c1 = uint32_t(block[2]) | uint32_t(block[3]) << 8;
    float palette[4][3];
    for (int e = 0; e < 2; ++e) {
        const uint32_t c = e == 0 ? c0 : c1;
        palette[e][0] = float((c >> 11) & 31u) * 255.0f / 31.0f;
        palette[e][1] = float((c >> 5) & 63u) * 255.0f / 63.0f;
        palette[e][2] = float(c & 31u) * 255.0f / 31.0f;
    }
    const bool four = always_four || c0 > c1;
    for (int k = 0; k < 3; ++k) {
        palette[2][k] = four ? (2.0f * palette[0][k] + palette[1][k]) / 3.0f : (palette[0][k] + palette[1][k]) / 2.0f;
        palette[3][k] = four ? (palette[0][k] + 2.0f * palette[1][k]) / 3.0f : 0.0f;
    }
    const uint32_t indices = uint32_t(block[4]) | uint32_t(block[5]) << 8 | uint32_t(block[6]) << 16 |
                             uint32_t(block[7]) << 24;
    for (int t = 0; t < 16; ++t) {
        const uint32_t i = (indices >> (2 * t)) & 3u;
        for (int k = 0; k < 3; ++k) out[t * stride + k] = palette[i][k] / 255.0f;
    }
}

}  // namespace

size_t bc_block_bytes(BcFormat f) { return f == BcFormat::Bc1 || f == BcFormat::Bc4 ? 8 : 16; }

int bc_channels(BcFormat f) { return f == BcFormat::Bc4 ? 1 : f == BcFormat::Bc5 ? 2 : 4; }

uint64_t bc_level_bytes(BcFormat f, uint64_t width, uint64_t height) {
    return (width + 3) / 4 * ((height + 3) / 4) * bc_block_bytes(f);
}

Image decode_bc_level(BcFormat f, const uint8_t* data, int width, int height) {
    const int n = bc_channels(f);
    Image img(width, height, n);
    const int blocks_x = (width + 3) / 4, blocks_y = (height + 3) / 4;
    float texels[16 * 4];
    for (int by = 0; by < blocks_y; ++by) {
        for (int bx = 0; bx < blocks_x; ++bx, data += bc_block_bytes(f)) {
            switch (f) {
                case BcFormat::Bc1:
                    bc1_colour(data, false, texels, 4);
                    for (int t = 0; t < 16; ++t) texels[t * 4 + 3] = 1.0f;
                    break;
                case BcFormat::Bc3:  // alpha block (BC4-coded), then the colour block
                    bc4_channel(data, texels + 3, 4);
                    bc1_colour(data + 8, true, texels, 4);
                    break;
                case BcFormat::Bc4: bc4_channel(data, texels, 1); break;
                case BcFormat::Bc5:  // red block, then green
                    bc4_channel(data, texels, 2);
                    bc4_channel(data + 8, texels + 1, 2);
                    break;
            }
            for (int j = 0; j < 4; ++j) {
                const int y = by * 4 + j;
                if (y >= height) break;
                for (int i = 0; i < 4; ++i) {
                    const int x = bx * 4 + i;
                    if (x >= width) break;
                    float* dst = img.pixels.data() + (size_t(y) * size_t(width) + size_t(x)) * size_t(n);
                    for (int c = 0; c < n; ++c) dst[c] = texels[(j * 4 + i) * n + c];
                }
            }
        }
    }
    return img;
}

}  // namespace specbake::io
