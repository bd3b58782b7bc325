#include "io/texture/texel_encoding.h"

#include <Imath/half.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#if defined(__x86_64__)
#include <cpuid.h>
#include <immintrin.h>
#endif

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

// round(clamp(v, 0, 1) * scale), rounding halves away from zero as std::lround does: v * scale is a float
// below 2^16, so adding 0.5 in double is exact and truncation is the floor.
inline uint32_t unorm(float v, float scale) {
    return uint32_t(double(std::clamp(v, 0.0f, 1.0f) * scale) + 0.5);
}

// IEEE half of n floats, round to nearest even: F16C (four per instruction) where the CPU has it, else
// Imath's bit arithmetic, which rounds the same way (Imath itself uses F16C when compiled for it).
#if defined(__x86_64__)
__attribute__((target("f16c"))) void halves_f16c(const float* src, size_t n, uint8_t* dst) {
    size_t i = 0;
    for (; i + 4 <= n; i += 4) {
        const __m128i h = _mm_cvtps_ph(_mm_loadu_ps(src + i), _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
        _mm_storel_epi64(reinterpret_cast<__m128i*>(dst + 2 * i), h);
    }
    for (; i < n; ++i) put<uint16_t>(dst + 2 * i, _cvtss_sh(src[i], _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC));
}

// CPUID leaf 1, ECX bit 29 (F16C): read directly, as clang 14's __builtin_cpu_supports has no "f16c".
bool f16c_supported() {
    static const bool yes = [] {
        unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
        return __get_cpuid(1, &eax, &ebx, &ecx, &edx) && (ecx & bit_F16C) != 0;
    }();
    return yes;
}

// Halves of the first four of every texel's src_channels (>= 4) floats: one conversion per texel.
__attribute__((target("f16c"))) void halves4_strided_f16c(const float* src, size_t count, int src_channels,
                                                         uint8_t* dst) {
    for (size_t i = 0; i < count; ++i, src += src_channels, dst += 8)
        _mm_storel_epi64(reinterpret_cast<__m128i*>(dst),
                         _mm_cvtps_ph(_mm_loadu_ps(src), _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC));
}
#endif

void halves(const float* src, size_t n, uint8_t* dst) {
#if defined(__x86_64__)
    if (f16c_supported()) return halves_f16c(src, n, dst);
#endif
    for (size_t i = 0; i < n; ++i) put<uint16_t>(dst + 2 * i, Imath::half(src[i]).bits());
}

// Float16: the texels' values are gathered into a small buffer and converted in one run.
void encode_halves(const float* src, size_t count, int src_channels, int channels, int out_channels, float pad,
                   uint8_t* dst) {
    constexpr size_t kChunk = 1024;
    float buffer[kChunk];
    const size_t per_chunk = std::max<size_t>(1, kChunk / size_t(out_channels));
    for (size_t begin = 0; begin < count; begin += per_chunk) {
        const size_t n = std::min(per_chunk, count - begin);
        const float* s = src + begin * size_t(src_channels);
        float* b = buffer;
        for (size_t i = 0; i < n; ++i, s += src_channels)
            for (int c = 0; c < out_channels; ++c) *b++ = c < channels ? s[c] : pad;
        halves(buffer, n * size_t(out_channels), dst + begin * size_t(out_channels) * 2);
    }
}

template <TexelEncoding E>
void encode_run(const float* src, size_t count, int src_channels, int channels, int out_channels, float pad,
                uint8_t* dst) {
    constexpr int bytes = E == TexelEncoding::Unorm8 ? 1 : E == TexelEncoding::Unorm16 ? 2 : 4;
    for (size_t i = 0; i < count; ++i, src += src_channels) {
        for (int c = 0; c < out_channels; ++c, dst += bytes) {
            const float v = c < channels ? src[c] : pad;
            if constexpr (E == TexelEncoding::Unorm8) *dst = uint8_t(unorm(v, 255.0f));
            else if constexpr (E == TexelEncoding::Unorm16) put<uint16_t>(dst, uint16_t(unorm(v, 65535.0f)));
            else put<float>(dst, v);
        }
    }
}

#if defined(__x86_64__)
// unorm(v, 255) of the first multiple of eight of n floats, eight per AVX2 instruction, in float: x =
// clamp(v) * 255 is the same float product as the scalar form; the conversion rounds half to even, so a
// tie x = k + 1/2 with k even comes out as k and is bumped to k + 1 (std::lround rounds halves up). The
// difference x - round(x) is exact (both lie within 256 and within 1/2 of each other). max/min stand in
// for the clamp: they differ only in the sign of a zero, which rounds to the same byte, and a NaN gives 0
// as the scalar clamp does. Returns how many it did.
__attribute__((target("avx2"))) size_t unorm8_avx2(const float* src, size_t n, uint8_t* dst) {
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f), scale = _mm256_set1_ps(255.0f);
    const __m256 half = _mm256_set1_ps(0.5f);
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        const __m256 x = _mm256_mul_ps(_mm256_min_ps(_mm256_max_ps(_mm256_loadu_ps(src + i), zero), one), scale);
        __m256i r = _mm256_cvtps_epi32(x);
        const __m256 tie = _mm256_cmp_ps(_mm256_sub_ps(x, _mm256_cvtepi32_ps(r)), half, _CMP_EQ_OQ);
        r = _mm256_sub_epi32(r, _mm256_castps_si256(tie));  // the mask is -1 on a tie
        const __m128i words = _mm_packs_epi32(_mm256_castsi256_si128(r), _mm256_extracti128_si256(r, 1));
        _mm_storel_epi64(reinterpret_cast<__m128i*>(dst + i), _mm_packus_epi16(words, words));
    }
    return i;
}
#endif

// Unorm8 of n contiguous floats, as unorm(v, 255).
void unorm8_flat(const float* src, size_t n, uint8_t* dst) {
    size_t i = 0;
#if defined(__x86_64__)
    static const bool avx2 = (__builtin_cpu_init(), __builtin_cpu_supports("avx2"));
    if (avx2) i = unorm8_avx2(src, n, dst);
#endif
    for (; i < n; ++i) dst[i] = uint8_t(unorm(src[i], 255.0f));
}

// The common case without padding (channels == out_channels), with the channel count N known at compile
// time so the per-texel loop unrolls; same rounding as encode_run.
template <int N>
void encode_fixed(const float* src, size_t count, int src_channels, TexelEncoding encoding, uint8_t* dst) {
    switch (encoding) {
        case TexelEncoding::Unorm8:
            if (src_channels == N) return unorm8_flat(src, count * N, dst);
            for (size_t i = 0; i < count; ++i, src += src_channels, dst += N)
                for (int c = 0; c < N; ++c) dst[c] = uint8_t(unorm(src[c], 255.0f));
            break;
        case TexelEncoding::Unorm16:
            for (size_t i = 0; i < count; ++i, src += src_channels, dst += 2 * N)
                for (int c = 0; c < N; ++c) put<uint16_t>(dst + 2 * c, uint16_t(unorm(src[c], 65535.0f)));
            break;
        case TexelEncoding::Float16: {
            if (src_channels == N) return halves(src, count * N, dst);
#if defined(__x86_64__)
            if (N == 4 && f16c_supported()) return halves4_strided_f16c(src, count, src_channels, dst);
#endif
            constexpr size_t kTexels = 256;
            float buffer[kTexels * N];
            for (size_t begin = 0; begin < count; begin += kTexels) {
                const size_t n = std::min(kTexels, count - begin);
                const float* s = src + begin * size_t(src_channels);
                for (size_t i = 0; i < n; ++i, s += src_channels)
                    for (int c = 0; c < N; ++c) buffer[i * N + c] = s[c];
                halves(buffer, n * N, dst + begin * 2 * N);
            }
            break;
        }
        case TexelEncoding::Float32:
            for (size_t i = 0; i < count; ++i, src += src_channels, dst += 4 * N) std::memcpy(dst, src, 4 * N);
            break;
    }
}

}  // namespace

void encode_texels_into(const float* src, size_t count, int src_channels, int first, int channels,
                        TexelEncoding encoding, int out_channels, float pad, uint8_t* dst) {
    src += first;
    if (channels == out_channels) {
        switch (channels) {
            case 1: return encode_fixed<1>(src, count, src_channels, encoding, dst);
            case 2: return encode_fixed<2>(src, count, src_channels, encoding, dst);
            case 3: return encode_fixed<3>(src, count, src_channels, encoding, dst);
            case 4: return encode_fixed<4>(src, count, src_channels, encoding, dst);
            default: break;
        }
    }
    switch (encoding) {
        case TexelEncoding::Unorm8:
            encode_run<TexelEncoding::Unorm8>(src, count, src_channels, channels, out_channels, pad, dst);
            break;
        case TexelEncoding::Unorm16:
            encode_run<TexelEncoding::Unorm16>(src, count, src_channels, channels, out_channels, pad, dst);
            break;
        case TexelEncoding::Float16: encode_halves(src, count, src_channels, channels, out_channels, pad, dst); break;
        case TexelEncoding::Float32:
            encode_run<TexelEncoding::Float32>(src, count, src_channels, channels, out_channels, pad, dst);
            break;
    }
}

std::vector<uint8_t> encode_texels(const Image& image, TexelEncoding encoding, int out_channels, float pad) {
    std::vector<uint8_t> out(image.texel_count() * size_t(out_channels) * size_t(encoding_bytes(encoding)));
    encode_texels_into(image.pixels.data(), image.texel_count(), image.channels, 0, image.channels, encoding,
                       out_channels, pad, out.data());
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
