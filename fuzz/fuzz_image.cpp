// libFuzzer target: the image-decode path of the texture bake (io/image/image_io.h) for PNG and JPEG: the PNG
// chunk and image-data checks, the JPEG marker check and the OpenImageIO module (io/image/oiio_api.h), fed in
// memory as embedded GLB images are.
#include "io/image/image_io.h"
#include "io/files/input_policy.h"

#include <cstdint>
#include <cstring>

// The texel limit is checked from the header before anything is allocated (PNG IHDR, OpenImageIO's spec),
// so a small one keeps every execution small: headers claiming more take the refusal path, which is what
// a hostile header meets in production too, and decoding stays within 256^2 texels.
static constexpr specbake::io::InputLimits kLimits{.texels = uint64_t(1) << 16};

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const bool png = size >= 8 && std::memcmp(data, "\x89PNG\r\n\x1a\n", 8) == 0;
    const bool jpeg = size >= 3 && data[0] == 0xFF && data[1] == 0xD8 && data[2] == 0xFF;
    if (!png && !jpeg) return -1;  // any other bytes would be decoded as TGA, which has no signature
    auto decoded = specbake::io::decode_image_memory({data, size}, "fuzz-input", kLimits);
    if (!decoded) return 0;
    const specbake::Image& image = decoded->image;
    // A decoded image is what its header says, within the limit, and holds exactly that many values.
    if (image.width <= 0 || image.height <= 0 || image.channels <= 0 ||
        uint64_t(image.width) * uint64_t(image.height) > kLimits.texels ||
        image.pixels.size() != size_t(image.width) * image.height * image.channels)
        __builtin_trap();
    return 0;
}
