// The texture bake's input checks and analysis: shapes and channels, the first non-finite texel, and the
// hints read from the normal map (constant full-scale blue, sRGB-encoded values).
#include "bake/texture_bake_internal.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace specbake {
namespace texture_bake_detail {
namespace {

double srgb_to_linear(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

}  // namespace

bool blue_is_constant_full_scale(const TextureMap& n) {
    if (n.channels < 3) return false;
    const float first = n.value(0, 0, 2);
    if (!(first >= 1.0f - 1.0f / 512.0f)) return false;
    const size_t ch = size_t(n.channels);
    for (int y = 0; y < n.height; ++y) {
        const size_t row = size_t(y) * n.row_stride + 2;
        // One integer code stands for one float value, so the codes of integer maps are compared.
        auto same = [&](const auto* v) {
            for (size_t i = 0; i < size_t(n.width); ++i)
                if (v[row + i * ch] != v[2]) return false;
            return true;
        };
        if (!(n.f32 ? same(n.f32) : n.u8 ? same(n.u8) : same(n.u16))) return false;
    }
    return true;
}

// A tangent-space normal map stored through an sRGB encode decodes to vectors far from unit length
// (flat (0.5, 0.5, 1) becomes (0.735, 0.735, 1)); decoding the sRGB curve first brings them back.
bool looks_srgb_encoded(const TextureMap& n) {
    if (n.channels < 3) return false;
    // Values of 8-bit inputs (most maps; within float rounding of a code k / 255) take the curve from a
    // table of the 256 codes instead of a pow() per value: this only decides a warning.
    static const std::array<double, 256> table = [] {
        std::array<double, 256> t{};
        for (int k = 0; k < 256; ++k) t[size_t(k)] = srgb_to_linear(k / 255.0);
        return t;
    }();
    auto linear = [](double c) {
        if (!(c >= 0.0)) c = 0.0;  // NaN: the non-finite check reports the texel; this only decides a warning
        const double code = c * 255.0;
        const long k = long(code + 0.5);  // code >= 0: the values are clamped to [0, 1]
        return k >= 0 && k <= 255 && std::abs(code - double(k)) < 1e-4 ? table[size_t(k)] : srgb_to_linear(c);
    };
    double dev_linear = 0.0, dev_srgb = 0.0;
    size_t samples = 0;
    auto sample = [&](size_t i) {
        const int x = int(i % size_t(n.width)), y = int(i / size_t(n.width));
        double l2 = 0.0, s2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            const float c = n.value(x, y, k);
            const double a = 2.0 * c - 1.0;
            const double b = 2.0 * linear(std::clamp(double(c), 0.0, 1.0)) - 1.0;
            l2 += a * a;
            s2 += b * b;
        }
        dev_linear += std::abs(std::sqrt(l2) - 1.0);
        dev_srgb += std::abs(std::sqrt(s2) - 1.0);
        ++samples;
    };
    // At most 16384 texels, as 256 runs of 64 consecutive texels spread over the map: runs are read at the
    // speed of memory, where single texels spread as widely each cost a cache miss.
    const size_t count = size_t(n.width) * size_t(n.height);
    constexpr size_t kRuns = 256, kRun = 64;
    if (count <= kRuns * kRun) {
        for (size_t i = 0; i < count; ++i) sample(i);
    } else {
        for (size_t run = 0; run < kRuns; ++run)
            for (size_t i = run * (count / kRuns), end = i + kRun; i < end; ++i) sample(i);
    }
    dev_linear /= double(samples);
    dev_srgb /= double(samples);
    return dev_linear > 0.08 && dev_srgb < 0.5 * dev_linear;
}

// "<what>: NaN or infinite value at texel (x, y)" for the first such texel of `image`.
Error non_finite_error(const std::string& what, const TextureMap& image) {
    std::optional<std::pair<int, int>> bad;
    for (int y = 0; y < image.height && image.f32 && !bad; ++y) {
        Image row(image.width, 1, image.channels);
        std::copy_n(image.f32 + size_t(y) * image.row_stride, row.pixels.size(), row.pixels.begin());
        if (auto at = find_non_finite(row)) bad = std::pair<int, int>(at->first, y);
    }
    return Error{what + ": NaN or infinite value" +
                 (bad ? " at texel (" + std::to_string(bad->first) + ", " + std::to_string(bad->second) + ")" : "")};
}

// Checks of the inputs' shapes and of the parts that are not read texel by texel in the decode (which
// checks every value it reads for NaN and infinity itself).
Result<void> validate_buffers(const Image& normal, const Image* roughness) {
    if (!normal.empty() && normal.pixels.size() != normal.texel_count() * size_t(normal.channels))
        return make_error("normal map: pixel buffer does not match its size");
    if (roughness && !roughness->empty() && roughness->pixels.size() != roughness->texel_count() * size_t(roughness->channels))
        return make_error("roughness map: pixel buffer does not match its size");
    return {};
}

// Checks of the inputs' shapes and of the parts that are not read texel by texel in the decode (which
// checks every value it reads for NaN and infinity itself).
Result<void> validate(const TextureMap& normal, const TextureMap* roughness, int channel, float value) {
    if (normal.empty()) return make_error("normal map: empty image (0x0)");
    if (normal.channels < 2)
        return make_error("normal map: has " + std::to_string(normal.channels) +
                          " channel; a normal map needs 2 (x, y) or 3+ (x, y, z) channels");
    if (roughness) {
        if (roughness->empty()) return make_error("roughness map: empty image (0x0)");
        if (channel < 0 || channel >= roughness->channels)
            return make_error("roughness map: channel " + std::to_string(channel) + " does not exist (the map has " +
                              std::to_string(roughness->channels) + ")");
        const bool resampled = roughness->width != normal.width || roughness->height != normal.height;
        if (resampled && roughness->f32) {  // integers are always finite
            for (int y = 0; y < roughness->height; ++y) {
                const float* r = roughness->f32 + size_t(y) * roughness->row_stride;
                for (size_t i = 0; i < size_t(roughness->width) * size_t(roughness->channels); ++i)
                    if (!std::isfinite(r[i])) return non_finite_error("roughness map", *roughness);
            }
        }
    } else if (!(value >= 0.0f && value <= 1.0f)) {
        return make_error("roughness value " + std::to_string(value) + " is outside [0, 1]");
    }
    return {};
}

}  // namespace texture_bake_detail

std::optional<std::pair<int, int>> find_non_finite(const Image& image) {
    const size_t n = image.pixels.size();
    const float* p = image.pixels.data();
    // Blocks are screened on the exponent bits (all ones: NaN or infinity), four floats per SSE2
    // instruction; only a block that holds one is searched element by element.
    constexpr size_t kBlock = 4096;
    size_t first = 0;
    for (; first < n; first += kBlock) {
        const size_t end = std::min(n, first + kBlock);
        size_t i = first;
        uint32_t bad = 0;
#if defined(__SSE2__)
        const __m128i exponent = _mm_set1_epi32(0x7f800000);
        __m128i any = _mm_setzero_si128();
        for (; i + 4 <= end; i += 4) {
            const __m128i bits = _mm_and_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p + i)), exponent);
            any = _mm_or_si128(any, _mm_cmpeq_epi32(bits, exponent));
        }
        bad = uint32_t(_mm_movemask_epi8(any));
#endif
        for (; i < end; ++i) {
            uint32_t bits;
            std::memcpy(&bits, p + i, sizeof bits);
            bad |= uint32_t((bits & 0x7f800000u) == 0x7f800000u);
        }
        if (bad) break;
    }
    for (size_t i = first; i < n; ++i) {
        if (!std::isfinite(p[i])) {
            const size_t texel = i / size_t(std::max(1, image.channels));
            return std::pair<int, int>(int(texel % size_t(image.width)), int(texel / size_t(image.width)));
        }
    }
    return std::nullopt;
}

}  // namespace specbake
