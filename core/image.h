// Image: a plain interleaved float image, the in-memory currency between io/ and bake/.
// Values are stored as decoded from the file (no colour conversion); 8/16-bit data is normalised to [0,1].
#pragma once

#include "core/enum_names.h"

#include <array>
#include <cstddef>
#include <optional>
#include <string_view>
#include <vector>

namespace specbake {

struct Image {
    int width = 0;
    int height = 0;
    int channels = 0;
    std::vector<float> pixels;  // row-major, width * height * channels, row 0 is the top of the file

    Image() = default;
    Image(int w, int h, int c) : width(w), height(h), channels(c), pixels(size_t(w) * h * c, 0.0f) {}

    bool empty() const { return width <= 0 || height <= 0 || channels <= 0; }
    size_t texel_count() const { return size_t(width) * size_t(height); }
    float* texel(int x, int y) { return pixels.data() + (size_t(y) * width + x) * channels; }
    const float* texel(int x, int y) const { return pixels.data() + (size_t(y) * width + x) * channels; }
};

// How a texture is addressed outside [0, 1]: recorded with baked outputs so the run time samples them the
// way the bake assumed (EXR "wrapmodes", the manifest).
enum class WrapMode { Repeat, Clamp, Mirror };

// "repeat", "clamp", "mirror" (the CLI and manifest spellings), in enum order.
inline constexpr std::array<std::string_view, 3> kWrapModeNames{"repeat", "clamp", "mirror"};
inline std::string_view to_string(WrapMode wrap) { return kWrapModeNames[size_t(wrap)]; }
inline std::optional<WrapMode> parse_wrap_mode(std::string_view name) {
    return enum_from_name<WrapMode>(kWrapModeNames, name);
}

// A full mip chain, level 0 first; level L is max(1, W >> L) x max(1, H >> L).
struct MipChain {
    std::vector<Image> levels;
    int width() const { return levels.empty() ? 0 : levels[0].width; }
    int height() const { return levels.empty() ? 0 : levels[0].height; }
    int channels() const { return levels.empty() ? 0 : levels[0].channels; }
};

}  // namespace specbake
