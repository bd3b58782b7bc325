#include "io/texel_encoding.h"

#include <Imath/half.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace specbake::io {

int encoding_bytes(TexelEncoding e) {
    switch (e) {
        case TexelEncoding::Unorm8: return 1;
        case TexelEncoding::Unorm16: return 2;
        case TexelEncoding::Float16: return 2;
        case TexelEncoding::Float32: return 4;
    }
    return 4;
}

namespace {

template <class T>
void put(uint8_t* dst, T v) {
    std::memcpy(dst, &v, sizeof(T));  // host is little-endian (x86-64, ARM64), as the containers are
}

template <class T>
T get(const uint8_t* src) {
    T v;
    std::memcpy(&v, src, sizeof(T));
    return v;
}

}  // namespace

std::vector<uint8_t> encode_texels(const Image& image, TexelEncoding encoding, int out_channels, float pad) {
    const int bytes = encoding_bytes(encoding);
    const size_t count = image.texel_count();
    std::vector<uint8_t> out(count * size_t(out_channels) * size_t(bytes));
    uint8_t* dst = out.data();
    for (size_t i = 0; i < count; ++i) {
        const float* src = image.pixels.data() + i * size_t(image.channels);
        for (int c = 0; c < out_channels; ++c, dst += bytes) {
            const float v = c < image.channels ? src[c] : pad;
            switch (encoding) {
                case TexelEncoding::Unorm8:
                    *dst = uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
                    break;
                case TexelEncoding::Unorm16:
                    put<uint16_t>(dst, uint16_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 65535.0f)));
                    break;
                case TexelEncoding::Float16: put<uint16_t>(dst, Imath::half(v).bits()); break;
                case TexelEncoding::Float32: put<float>(dst, v); break;
            }
        }
    }
    return out;
}

Image decode_texels(std::span<const uint8_t> bytes, TexelEncoding encoding, int width, int height, int channels) {
    Image image(width, height, channels);
    const int size = encoding_bytes(encoding);
    const size_t n = image.pixels.size();
    for (size_t i = 0; i < n && (i + 1) * size_t(size) <= bytes.size(); ++i) {
        const uint8_t* src = bytes.data() + i * size_t(size);
        switch (encoding) {
            case TexelEncoding::Unorm8: image.pixels[i] = float(*src) / 255.0f; break;
            case TexelEncoding::Unorm16: image.pixels[i] = float(get<uint16_t>(src)) / 65535.0f; break;
            case TexelEncoding::Float16: {
                Imath::half h;
                h.setBits(get<uint16_t>(src));
                image.pixels[i] = float(h);
                break;
            }
            case TexelEncoding::Float32: image.pixels[i] = get<float>(src); break;
        }
    }
    return image;
}

}  // namespace specbake::io
