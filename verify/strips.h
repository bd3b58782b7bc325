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

// The harm map (`verify --harm-map`): where a candidate's temporal error exceeds the baseline's. One row
// per candidate, two tiles: the per-pixel tone-mapped flicker and the per-pixel tone-mapped temporal error
// (metrics.h), each as the candidate's minus the baseline's over a dim copy of the ground truth: red where
// the candidate's is larger (full red at twice the baseline's mean over the image), blue where smaller;
// pixels the metric does not score are black.
struct HarmTile {
    std::string label;
    const std::vector<float>* flicker = nullptr;
    const std::vector<float>* temporal_error = nullptr;
};

// Where the excess lies, per candidate and measure: sums over the pixels both score of max(c - b, 0)
// (excess) and max(b - c, 0) (relief), as fractions of the baseline's sum; `edge_excess`: the part of the
// excess within 2 pixels of the ground truth's silhouette (a pixel whose coverage is below 0.999).
struct HarmSummary {
    double excess = 0, relief = 0, edge_excess = 0;
    long long pixels = 0;
};
struct HarmReport {
    std::string label;
    HarmSummary flicker, temporal_error;
};

Image make_harm_map(const SimImage& ground_truth, const HarmTile& baseline, const std::vector<HarmTile>& candidates,
                    std::vector<HarmReport>* summaries = nullptr);

// Writes `strip` as an 8-bit PNG to `path` atomically.
Result<void> write_strip_png(const Image& strip, const std::filesystem::path& path);

}  // namespace specbake::verify
