// Pictures of the simulator as PNG: the strip, a labelled grid of the ground truth and the candidates that
// matter (tone-mapped with one exposure for all, each above its error heat map |T(c) - T(g)|, black -> red
// -> yellow -> white), and the harm map. T(x) = x / (1 + x) after scaling the ground truth's 99th
// percentile to 1.
#pragma once

#include "core/image.h"
#include "core/result.h"
#include "verify/renderer.h"
#include "verify/verify_job.h"

#include <filesystem>
#include <string>
#include <vector>

namespace specbake::verify {

struct StripTile {
    std::string label;
    const SimImage* image = nullptr;
    std::string caption;  // a second line under the label, e.g. the ratios to no filtering
};

// Where one candidate's per-pixel tone-mapped temporal error exceeds the baseline's (the harm map's
// measure), drawn as the strip's last cell.
struct StripHarm {
    std::string label;                                // e.g. "default - none"
    const std::vector<float>* candidate = nullptr;    // CandidateReport::pixel_temporal_error
    const std::vector<float>* baseline = nullptr;
};

// The strip's tiles from a scene's candidates. The GGX strip (glint = false): no filtering, the default and
// its variants (`--variant`: default:LABEL), then the `best` other candidates with the lowest
// sum of ranks over RMSE and tone-mapped flicker (the limit and floor rows are not candidates); each
// captioned with its RMSE (linear) and tone-mapped flicker and temporal error as ratios to no filtering's. The glint
// strip: every glint candidate. `all`: every candidate of the family.
std::vector<StripTile> strip_tiles(const std::vector<CandidateReport>& candidates, bool glint, int best = 3,
                                   bool all = false);

// The default's harm against no filtering from a scene's candidates (empty when either is missing or kept
// no per-pixel maps: VerifyOptions::pixel_maps).
StripHarm default_strip_harm(const std::vector<CandidateReport>& candidates);

// The strip as an RGB image in [0, 1] (sRGB-encoded for display): a grid of at most four columns, the
// ground truth first, each tile cropped to the object (4 pixels of margin) and magnified to about 320
// pixels, its label and caption above it and its error map below; with `harm`, a last cell with the
// harm map of that candidate against the baseline (red where its temporal error is larger, blue where
// smaller, full at twice the baseline's mean).
Image make_strip(const SimImage& ground_truth, const std::vector<StripTile>& candidates,
                 const StripHarm* harm = nullptr);

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
