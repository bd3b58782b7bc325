// A BC1/BC3/BC4/BC5 decoder written from the Khronos Data Format Specification 1.3 Sec. 21 (independent of
// io/texture/block_compress.cpp), for the tests and the block-compression accuracy benchmark.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace bc_test {

// 16 values of one BC4 block (KDFS 21.4: red_0 > red_1 gives 6 interpolants, else 4 plus 0 and 255).
inline void decode_bc4(const uint8_t* b, float out[16]) {
    const float r0 = b[0], r1 = b[1];
    float pal[8] = {r0, r1};
    if (b[0] > b[1]) {
        for (int i = 1; i <= 6; ++i) pal[i + 1] = ((7 - i) * r0 + i * r1) / 7.0f;
    } else {
        for (int i = 1; i <= 4; ++i) pal[i + 1] = ((5 - i) * r0 + i * r1) / 5.0f;
        pal[6] = 0, pal[7] = 255;
    }
    uint64_t bits = 0;
    for (int k = 0; k < 6; ++k) bits |= uint64_t(b[2 + k]) << (8 * k);
    for (int i = 0; i < 16; ++i) out[i] = pal[(bits >> (3 * i)) & 7] / 255.0f;
}

// RGB of one BC1 block (KDFS 21.1), 4-colour mode when colour_0 > colour_1, else 3 colours and black.
inline void decode_bc1(const uint8_t* b, float out[16][3]) {
    const uint16_t c0 = uint16_t(b[0] | b[1] << 8), c1 = uint16_t(b[2] | b[3] << 8);
    auto expand = [](uint16_t c, float rgb[3]) {
        rgb[0] = float((c >> 11 & 31) * 255) / 31.0f;
        rgb[1] = float((c >> 5 & 63) * 255) / 63.0f;
        rgb[2] = float((c & 31) * 255) / 31.0f;
    };
    float pal[4][3];
    expand(c0, pal[0]);
    expand(c1, pal[1]);
    for (int c = 0; c < 3; ++c) {
        if (c0 > c1) {
            pal[2][c] = (2 * pal[0][c] + pal[1][c]) / 3;
            pal[3][c] = (pal[0][c] + 2 * pal[1][c]) / 3;
        } else {
            pal[2][c] = (pal[0][c] + pal[1][c]) / 2;
            pal[3][c] = 0;
        }
    }
    const uint32_t bits = uint32_t(b[4] | b[5] << 8 | b[6] << 16 | uint32_t(b[7]) << 24);
    for (int i = 0; i < 16; ++i)
        for (int c = 0; c < 3; ++c) out[i][c] = pal[(bits >> (2 * i)) & 3][c] / 255.0f;
}

// A whole level of `format` ("bc1", "bc3", "bc4", "bc5") as w x h texels of n channels (1, 2 or 4) in [0, 1].
inline std::vector<float> decode_level(const std::string& format, const uint8_t* data, int w, int h, int* channels) {
    const int n = format == "bc4" ? 1 : format == "bc5" ? 2 : 4;
    const size_t block = format == "bc1" || format == "bc4" ? 8 : 16;
    *channels = n;
    std::vector<float> out(size_t(w) * size_t(h) * size_t(n));
    const int bw = (w + 3) / 4, bh = (h + 3) / 4;
    for (int by = 0; by < bh; ++by)
        for (int bx = 0; bx < bw; ++bx) {
            const uint8_t* b = data + (size_t(by) * size_t(bw) + size_t(bx)) * block;
            float v[4][16] = {};
            if (format == "bc4") decode_bc4(b, v[0]);
            if (format == "bc5") decode_bc4(b, v[0]), decode_bc4(b + 8, v[1]);
            if (format == "bc1" || format == "bc3") {
                float rgb[16][3];
                decode_bc1(format == "bc3" ? b + 8 : b, rgb);
                for (int i = 0; i < 16; ++i)
                    for (int c = 0; c < 3; ++c) v[c][i] = rgb[i][c];
                if (format == "bc3") decode_bc4(b, v[3]);
                else std::fill(v[3], v[3] + 16, 1.0f);
            }
            for (int j = 0; j < 4; ++j)
                for (int i = 0; i < 4; ++i) {
                    const int x = bx * 4 + i, y = by * 4 + j;
                    if (x >= w || y >= h) continue;
                    for (int c = 0; c < n; ++c) out[(size_t(y) * size_t(w) + size_t(x)) * size_t(n) + size_t(c)] = v[c][j * 4 + i];
                }
        }
    return out;
}

}  // namespace bc_test
