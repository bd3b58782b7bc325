// Image strips of the simulator as PNG: the ground truth, then every candidate (top row, tone-mapped with
// one exposure for all), and below each candidate its error heat map |T(c) - T(g)| (black -> red -> yellow
// -> white), with a label above each tile. T(x) = x / (1 + x) after scaling the ground truth's 99th
// percentile to 1.
#pragma once

#include "core/image.h"
#include "core/result.h"
#include "verify/renderer.h"

#include <filesystem>
#include <string>
#include <vector>

namespace specbake::verify {

struct StripTile {
    std::string label;
    const SimImage* image = nullptr;
};

// The strip as an RGB image in [0, 1] (sRGB-encoded for display), each render magnified 2x to 8x (to
// about 256 pixels high) with its label above it.
Image make_strip(const SimImage& ground_truth, const std::vector<StripTile>& candidates);

// Writes `strip` as an 8-bit PNG to `path` atomically.
Result<void> write_strip_png(const Image& strip, const std::filesystem::path& path);

}  // namespace specbake::verify
