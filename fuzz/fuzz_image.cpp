// libFuzzer target: the image-decode path of the texture bake (io/image_io.h) for PNG and JPEG: the PNG
// chunk check and the OpenImageIO module (io/oiio_api.h), fed in memory as embedded GLB images are.
#include "io/image_io.h"

#include <cstdint>
#include <cstring>

namespace {

// Texels the header claims (PNG IHDR, JPEG SOFn), 0 when it cannot be read. The decoder allocates for
// the claimed size before reading pixel data (no texel limit is checked from the header yet), so inputs
// claiming more than kMaxTexels would only find that again, as out-of-memory or timeout.
constexpr uint64_t kMaxTexels = uint64_t(1) << 22;

uint64_t claimed_texels(const uint8_t* d, size_t n) {
    auto be16 = [&](size_t i) { return uint32_t(d[i]) << 8 | d[i + 1]; };
    auto be32 = [&](size_t i) { return be16(i) << 16 | be16(i + 2); };
    if (n >= 24 && d[0] == 0x89 && std::memcmp(d + 12, "IHDR", 4) == 0) return uint64_t(be32(16)) * be32(20);
    uint64_t most = 0;  // JPEG: the largest frame header found
    for (size_t i = 2; i + 9 <= n; ++i)
        if (d[i] == 0xFF && d[i + 1] >= 0xC0 && d[i + 1] <= 0xCF && d[i + 1] != 0xC4 && d[i + 1] != 0xC8 &&
            d[i + 1] != 0xCC) {
            const uint64_t t = uint64_t(be16(i + 5)) * be16(i + 7);
            most = t > most ? t : most;
        }
    return most;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const bool png = size >= 8 && std::memcmp(data, "\x89PNG\r\n\x1a\n", 8) == 0;
    const bool jpeg = size >= 3 && data[0] == 0xFF && data[1] == 0xD8 && data[2] == 0xFF;
    if (!png && !jpeg) return -1;  // any other bytes would be decoded as TGA, which has no signature
    if (claimed_texels(data, size) > kMaxTexels) return -1;
    auto decoded = specbake::io::decode_image_memory({data, size}, "fuzz-input");
    if (!decoded) return 0;
    const specbake::Image& image = decoded->image;
    // A decoded image is what its header says, and holds exactly that many values.
    if (image.width <= 0 || image.height <= 0 || image.channels <= 0 ||
        image.pixels.size() != size_t(image.width) * image.height * image.channels)
        __builtin_trap();
    return 0;
}
