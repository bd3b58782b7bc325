#include "bake/peer_roughness_bake.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

namespace specbake {
namespace {

// Summed-area table of `channels` values per texel, (w + 1) x (h + 1) with a zero first row and column.
struct SummedArea {
    int w = 0, h = 0, channels = 0;
    std::vector<double> sums;
    double box(int x0, int y0, int x1, int y1, int c) const {  // sum over [x0, x1) x [y0, y1)
        const auto at = [&](int x, int y) { return sums[(size_t(y) * size_t(w + 1) + size_t(x)) * size_t(channels) + size_t(c)]; };
        return at(x1, y1) - at(x0, y1) - at(x1, y0) + at(x0, y0);
    }
};

template <class F>
SummedArea summed_area(int w, int h, int channels, F value) {
    SummedArea s{w, h, channels, std::vector<double>(size_t(w + 1) * size_t(h + 1) * size_t(channels), 0.0)};
    std::vector<double> v(static_cast<size_t>(channels), 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            value(x, y, v.data());
            for (int c = 0; c < channels; ++c) {
                const size_t i = (size_t(y + 1) * size_t(w + 1) + size_t(x + 1)) * size_t(channels) + size_t(c);
                const size_t left = i - size_t(channels), up = i - size_t(w + 1) * size_t(channels);
                s.sums[i] = v[size_t(c)] + s.sums[left] + s.sums[up] - s.sums[up - size_t(channels)];
            }
        }
    return s;
}

// The texels [first, last) of a map `full` texels wide under texel `i` of a level `n` texels wide (at least one).
std::pair<int, int> under(int i, int n, int full) {
    const int first = int(int64_t(i) * full / n);
    return {first, std::max(first + 1, int(int64_t(i + 1) * full / n))};
}

}  // namespace

double peer_widened_roughness(double r_bar, double r, PeerRoughnessBake peer) {
    const double kappa = r_bar < 1.0 ? (3.0 * r_bar - r_bar * r_bar * r_bar) / (1.0 - r_bar * r_bar) : 1.0e4;
    double widened = r;
    switch (peer) {
        case PeerRoughnessBake::Filament: widened = std::sqrt(r * r + 2.0 / kappa); break;
        case PeerRoughnessBake::FilamentDebian: widened = std::sqrt(r * r + 1.0 / (2.0 * kappa)); break;
        case PeerRoughnessBake::Godot:
            widened = std::sqrt(r * r + std::min(3.0 * (r_bar < 1.0 ? 0.25 / kappa : 0.0), 0.4 * 0.4));
            break;
        case PeerRoughnessBake::UnityHdrp: {
            const double variance = r_bar < 1.0 ? std::min(1.0 / (4.0 * kappa), 0.03125) : 0.0;
            widened = std::pow(r * r * r * r + std::min(2.0 * variance, 0.2 * 0.2), 0.25);
            break;
        }
        case PeerRoughnessBake::Unreal: {
            const double length = std::clamp(r_bar, 1.0e-6, 1.0);
            const double variance = std::max(0.0, (1.0 - length) / length - 4.0e-5);
            const double a = r * r * r * r, b = 2.0 * variance * (a - 1.0);
            widened = std::pow(std::max(0.0, (b - a) / (b - 1.0)), 0.25);
            break;
        }
    }
    return std::clamp(widened, 0.0, 1.0);
}

Result<MipChain> bake_peer_roughness(const Image& normal, const Image* roughness, float roughness_value,
                                     PeerRoughnessBake peer) {
    if (normal.empty() || normal.channels < 3) return make_error("normal map: needs 3 channels");
    if (roughness && roughness->empty()) return make_error("roughness map: empty");
    const int W = normal.width, H = normal.height;
    const SummedArea normals = summed_area(W, H, 3, [&](int x, int y, double* out) {
        const float* c = normal.texel(x, y);
        double n[3] = {2.0 * c[0] - 1.0, 2.0 * c[1] - 1.0, 2.0 * c[2] - 1.0};
        if (peer == PeerRoughnessBake::Godot) {
            n[2] = std::sqrt(std::max(0.0, 1.0 - (n[0] * n[0] + n[1] * n[1])));
        } else if (peer != PeerRoughnessBake::Unreal) {
            const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            for (double& v : n) v = len > 0 ? v / len : 0.0;
        }
        std::copy_n(n, 3, out);
    });
    SummedArea rough;
    if (roughness)
        rough = summed_area(roughness->width, roughness->height, 1,
                            [&](int x, int y, double* out) { *out = double(roughness->texel(x, y)[0]); });
    MipChain chain;
    for (int k = 0;; ++k) {
        const int w = std::max(1, W >> k), h = std::max(1, H >> k);
        Image level(w, h, 1);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                double r = roughness_value;
                if (roughness) {
                    // The roughness map's own texels under the same uv rectangle (at least one).
                    const auto [x0, x1] = under(x, w, roughness->width);
                    const auto [y0, y1] = under(y, h, roughness->height);
                    r = rough.box(x0, y0, x1, y1, 0) / double((x1 - x0) * (y1 - y0));
                }
                if (k > 0 || peer == PeerRoughnessBake::Unreal) {
                    const auto [x0, x1] = under(x, w, W);
                    const auto [y0, y1] = under(y, h, H);
                    const double count = double((x1 - x0) * (y1 - y0));
                    double m[3];
                    for (int c = 0; c < 3; ++c) m[c] = normals.box(x0, y0, x1, y1, c) / count;
                    r = peer_widened_roughness(std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]), r, peer);
                }
                level.texel(x, y)[0] = float(std::clamp(r, 0.0, 1.0));
            }
        chain.levels.push_back(std::move(level));
        if (w == 1 && h == 1) break;
    }
    return chain;
}

}  // namespace specbake
