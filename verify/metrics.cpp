#include "verify/metrics.h"

#include <algorithm>
#include <cmath>

namespace specbake::verify {
namespace {

double tonemap(double x) { return x / (1.0 + x); }

double percentile(std::vector<float> values, double q) {
    if (values.empty()) return 0.0;
    const size_t k = std::min(values.size() - 1, size_t(q * double(values.size() - 1) + 0.5));
    std::nth_element(values.begin(), values.begin() + long(k), values.end());
    return values[k];
}

}  // namespace

bool scored_pixel(const SimImage& ground_truth, const SimImage& candidate, int x, int y) {
    return ground_truth.texel(x, y)[1] >= 0.999f && candidate.texel(x, y)[1] > 0.5f;
}

void SimMetricsAccumulator::add_frame(const SimImage& gt, const SimImage& c) {
    if (history_.empty()) history_.resize(gt.texel_count());
    ++frames_;
    for (int y = 0; y < gt.height; ++y) {
        for (int x = 0; x < gt.width; ++x) {
            if (!scored_pixel(gt, c, x, y)) continue;
            const double g = gt.texel(x, y)[0], v = c.texel(x, y)[0];
            const double d = v - g, dt = tonemap(v) - tonemap(g);
            sum_sq_ += d * d;
            sum_abs_ += std::abs(d);
            sum_sq_tm_ += dt * dt;
            sum_abs_tm_ += std::abs(dt);
            sum_gt_ += g;
            sum_c_ += v;
            ++n_;
            gt_values_.push_back(float(g));
            candidate_values_.push_back(float(v));
            PixelHistory& h = history_[size_t(y) * gt.width + x];
            h.sum += dt;
            h.sum_sq += dt * dt;
            h.sum_lin += d;
            h.sum_sq_lin += d * d;
            ++h.count;
            if (h.last_frame == frames_ - 2) {
                h.pair_sq_lin += (d - h.last_lin) * (d - h.last_lin);
                h.pair_sq_tm += (dt - h.last_tm) * (dt - h.last_tm);
                ++h.pairs;
            }
            h.last_frame = frames_ - 1;
            h.last_lin = d;
            h.last_tm = dt;
        }
    }
}

SimMetrics SimMetricsAccumulator::finish() const {
    SimMetrics m;
    m.pixels = n_;
    if (n_ == 0) return m;
    const double mean_gt = sum_gt_ / double(n_);
    const double norm = mean_gt > 0 ? 1.0 / mean_gt : 0.0;
    m.rmse = std::sqrt(sum_sq_ / double(n_)) * norm;
    m.mae = sum_abs_ / double(n_) * norm;
    m.rmse_tonemapped = std::sqrt(sum_sq_tm_ / double(n_));
    m.mae_tonemapped = sum_abs_tm_ / double(n_);
    m.energy_ratio = sum_gt_ > 0 ? sum_c_ / sum_gt_ : 1.0;
    const double p_gt = percentile(gt_values_, 0.99);
    m.peak_ratio = p_gt > 0 ? percentile(candidate_values_, 0.99) / p_gt : 1.0;
    // Temporal instability over pixels scored in every frame (population std over the K frames).
    double flicker = 0, flicker_lin = 0, terr = 0, terr_lin = 0;
    long long stable = 0, paired = 0;
    for (const PixelHistory& h : history_) {
        if (h.pairs > 0) {
            terr += std::sqrt(h.pair_sq_tm / (2.0 * h.pairs));
            terr_lin += std::sqrt(h.pair_sq_lin / (2.0 * h.pairs));
            ++paired;
        }
        if (h.count != frames_ || frames_ < 2) continue;
        const double k = double(h.count);
        const double var = std::max(0.0, h.sum_sq / k - (h.sum / k) * (h.sum / k));
        const double var_lin = std::max(0.0, h.sum_sq_lin / k - (h.sum_lin / k) * (h.sum_lin / k));
        flicker += std::sqrt(var);
        flicker_lin += std::sqrt(var_lin);
        ++stable;
    }
    if (stable > 0) {
        m.flicker = flicker / double(stable);
        m.flicker_linear = flicker_lin / double(stable) * norm;
    }
    if (paired > 0) {
        m.temporal_error = terr / double(paired);
        m.temporal_error_linear = terr_lin / double(paired) * norm;
    }
    return m;
}

std::vector<float> SimMetricsAccumulator::pixel_flicker() const {
    std::vector<float> out(history_.size(), std::nanf(""));
    for (size_t i = 0; i < history_.size(); ++i) {
        const PixelHistory& h = history_[i];
        if (h.count != frames_ || frames_ < 2) continue;
        const double k = double(h.count);
        out[i] = float(std::sqrt(std::max(0.0, h.sum_sq / k - (h.sum / k) * (h.sum / k))));
    }
    return out;
}

std::vector<float> SimMetricsAccumulator::pixel_temporal_error() const {
    std::vector<float> out(history_.size(), std::nanf(""));
    for (size_t i = 0; i < history_.size(); ++i)
        if (history_[i].pairs > 0) out[i] = float(std::sqrt(history_[i].pair_sq_tm / (2.0 * history_[i].pairs)));
    return out;
}

}  // namespace specbake::verify
