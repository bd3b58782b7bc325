// Accuracy metrics of one candidate against the ground truth over K frames (SPEC Sec. 8): RMSE and MAE
// on linear radiance normalised by the ground truth's mean and on tone-mapped values x / (1 + x),
// temporal instability (per-pixel standard deviation over the frames of candidate minus ground truth,
// averaged), temporal error (per-pixel frame-to-frame change of the candidate minus that of the ground
// truth, over consecutive frames that both score the pixel), and over-blur (ratios of total energy and of
// the 99th-percentile highlight).
// Only pixels fully covered in the ground truth and covered by the candidate count, so silhouette
// (geometric) aliasing, which no NDF filter addresses, does not enter the scores.
#pragma once

#include "verify/renderer.h"

#include <vector>

namespace specbake::verify {

struct SimMetrics {
    double rmse = 0;            // sqrt(mean (c - g)^2) / mean(g), linear radiance
    double mae = 0;             // mean |c - g| / mean(g)
    double rmse_tonemapped = 0; // on x / (1 + x)
    double mae_tonemapped = 0;
    double flicker = 0;         // mean over pixels of the temporal std of T(c) - T(g), T(x) = x / (1 + x)
    double flicker_linear = 0;  // mean over pixels of the temporal std of c - g, divided by mean(g)
    // Temporal error: per pixel sqrt(sum over consecutive scored frame pairs of ((c1 - c0) - (g1 - g0))^2 /
    // (2 pairs)) (the Allan deviation of the error), averaged over pixels with at least one pair. Equal to
    // the flicker for an error independent from frame to frame; unlike it, near zero for a temporally
    // stable error that moves with the image, and it scores pixels the object leaves or enters during the
    // path (the flicker keeps only pixels scored in every frame, which can exclude the highlight).
    double temporal_error = 0;         // on T(x) = x / (1 + x)
    double temporal_error_linear = 0;  // linear radiance, divided by mean(g)
    double energy_ratio = 1;    // sum(c) / sum(g): < 1 lost highlight energy, > 1 over-bright
    double peak_ratio = 1;      // 99th percentile of c / 99th percentile of g: < 1 means over-blurred peaks
    long long pixels = 0;       // pixel-frames scored
};

// Accumulates frames (same size, channel 0 radiance, channel 1 coverage) and computes SimMetrics.
class SimMetricsAccumulator {
public:
    void add_frame(const SimImage& ground_truth, const SimImage& candidate);
    SimMetrics finish() const;
    // Per pixel (row-major, width x height of the frames): the temporal standard deviation of T(c) - T(g)
    // (the flicker's pixel term; NaN where a frame did not score the pixel) and the Allan deviation of
    // T(c) - T(g) over consecutive frame pairs (the temporal error's pixel term; NaN without a pair).
    std::vector<float> pixel_flicker() const;
    std::vector<float> pixel_temporal_error() const;

private:
    struct PixelHistory {
        double sum = 0, sum_sq = 0, sum_lin = 0, sum_sq_lin = 0;
        int count = 0;
        // Temporal error: the previous frame's errors when it scored this pixel, and the pair sums.
        double last_lin = 0, last_tm = 0, pair_sq_lin = 0, pair_sq_tm = 0;
        int last_frame = -2, pairs = 0;
    };
    std::vector<PixelHistory> history_;
    std::vector<float> gt_values_, candidate_values_;
    double sum_sq_ = 0, sum_abs_ = 0, sum_sq_tm_ = 0, sum_abs_tm_ = 0, sum_gt_ = 0, sum_c_ = 0;
    long long n_ = 0;
    int frames_ = 0;
};

// True where the metrics score a pixel: ground-truth coverage >= 0.999 and candidate coverage > 0.5.
bool scored_pixel(const SimImage& ground_truth, const SimImage& candidate, int x, int y);

}  // namespace specbake::verify
