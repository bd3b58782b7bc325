// A texture file read back as stored, for inspection: what the container says of its texels and the levels
// themselves. Filled by io/texture/container_inspect.h (KTX2, DDS) and the image module (EXR, PNG).
#pragma once

#include "core/image.h"

#include <string>
#include <vector>

namespace specbake::io {

struct InspectedTexture {
    std::string format;        // "ktx2", "dds", "exr", "png"
    std::string pixel_format;  // "R16G16B16A16_SFLOAT" (KTX2 vkFormat / DDS DXGI format name), "half", "uint8", ...
    std::string transfer;      // "linear" or "sRGB" (as the container states)
    std::vector<std::string> channel_names;  // from the file where it has them (EXR), else R, G, B, A
    // Values as stored: unorm normalised to [0, 1], floats as they are, no conversion. A 2D array's layers
    // (KTX2) sit one below the other: level L is (width >> L) x ((height >> L) x layers).
    MipChain mips;
    int layers = 0;            // 0: a single image; else the array's layer count
    int channel_bytes = 0;     // bytes per stored channel (KTX2, DDS); 0 when not known (EXR, PNG)
    int block_bytes = 0;       // block-compressed (BC1/3/4/5): bytes per 4x4 block, decoded to `mips`; else 0
    // Height of one layer at level L (the level's height for a single image).
    int layer_height(size_t level) const { return layers > 0 ? mips.levels[level].height / layers : mips.levels[level].height; }
};

// The shape of a texture file, without its texels.
struct TextureShape {
    std::string format;
    int width = 0, height = 0, mips = 0, channels = 0;
    int layers = 0;  // KTX2 2D arrays: the layer count (0 for a single image); width and height are a layer's
};

}  // namespace specbake::io
