// C++ evaluation of the include's glint path (specaa_glint_*), formula by formula, in double precision
// except the integer hash.
#include "bake/glint_model.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace specbake {
namespace {

constexpr double kPi = std::numbers::pi;

double texel_row_lookup(const GlintDictionary& d, int level, int marginal, int mip, double u) {
    const int w = d.settings.width >> mip;
    const double t = u * w - 0.5;
    const int x0 = int(std::floor(t));
    const double f = t - x0;
    const auto at = [&](int x) { return double(glint_texel(d, level, marginal, mip, std::clamp(x, 0, w - 1))); };
    return (1.0 - f) * at(x0) + f * at(x0 + 1);
}

struct Footprint {
    std::array<double, 4> axes;  // major.xy, minor.xy
    double level;
};

Footprint footprint(const std::array<double, 4>& duv, double max_anisotropy, int levels) {
    const double lx = std::hypot(duv[0], duv[1]), ly = std::hypot(duv[2], duv[3]);
    std::array<double, 2> major = lx >= ly ? std::array<double, 2>{duv[0], duv[1]} : std::array<double, 2>{duv[2], duv[3]};
    std::array<double, 2> minor = lx >= ly ? std::array<double, 2>{duv[2], duv[3]} : std::array<double, 2>{duv[0], duv[1]};
    const double major_length = std::max(lx, ly);
    double minor_length = std::min(lx, ly);
    const double floor_length = major_length / max_anisotropy;
    if (minor_length < floor_length) {
        const std::array<double, 2> dir = minor_length > 0.0
                                              ? std::array<double, 2>{minor[0] / minor_length, minor[1] / minor_length}
                                              : std::array<double, 2>{-major[1] / major_length, major[0] / major_length};
        minor = {dir[0] * floor_length, dir[1] * floor_length};
        minor_length = floor_length;
    }
    const double l = std::clamp(levels - 1 + std::log2(std::max(minor_length, 1e-30)), 0.0, double(levels - 1));
    return {{major[0], major[1], minor[0], minor[1]}, l};
}

double cell(const GlintDictionary& d, int s, int t, int level, double level_dist, std::array<double, 2> hs,
            const std::array<double, 4>& dh, const std::array<double, 4>& minv, double beckmann, const GlintParams& g,
            GlintCost* cost) {
    const int L = d.settings.levels, N = d.settings.count;
    const double sigma_o = glint_sigma_o(d.settings);
    const std::array<uint32_t, 6> r = glint_cell_draws(s, t, level);
    if (glint_unit(r[0]) >= g.relative_area) return 0.0;
    const double n = std::sqrt(-2.0 * std::log(1.0 - glint_unit(r[1]))) * std::cos(2.0 * kPi * glint_unit(r[2]));
    const int k = int(std::clamp(std::floor(level_dist + g.density_randomization * n + 0.5), 0.0, double(L)));
    if (k >= L) return beckmann;
    const double e = g.ggx ? glint_cell_scale(r) : 1.0;  // E of the GGX scale mixture
    const double theta = 2.0 * kPi * glint_unit(r[3]);
    const double ct = std::cos(theta), st = std::sin(theta);
    const double se = std::sqrt(e);
    const std::array<double, 4> m = {se * (ct * minv[0] + st * minv[2]), se * (ct * minv[1] + st * minv[3]),
                                     se * (-st * minv[0] + ct * minv[2]), se * (-st * minv[1] + ct * minv[3])};
    const double hox = m[0] * hs[0] + m[1] * hs[1], hoy = m[2] * hs[0] + m[3] * hs[1];
    if (std::fabs(hox) > 4.0 * sigma_o || std::fabs(hoy) > 4.0 * sigma_o) return 0.0;
    const int i = std::min(int(glint_unit(r[4]) * N), N - 1), j = std::min(int(glint_unit(r[5]) * N), N - 1);
    if (cost) cost->fetches += 2;
    const double scale = g.kernel_scale * 0.25 / sigma_o;
    const double gxx = scale * (m[0] * dh[0] + m[1] * dh[1]), gxy = scale * (m[2] * dh[0] + m[3] * dh[1]);
    const double gyx = scale * (m[0] * dh[2] + m[1] * dh[3]), gyy = scale * (m[2] * dh[2] + m[3] * dh[3]);
    return glint_marginal_grad(d, k, i, hox, gxx, gyx) * glint_marginal_grad(d, k, j, hoy, gxy, gyy) *
           (minv[0] * minv[3] - minv[1] * minv[2]) * e;
}

double level_sdf(const GlintDictionary& d, std::array<double, 2> uv, const std::array<double, 4>& axes, int level,
                 std::array<double, 2> hs, const std::array<double, 4>& dh, const std::array<double, 4>& minv,
                 double beckmann, const GlintParams& g, int max_cells, GlintCost* cost) {
    const int L = d.settings.levels;
    const double level_dist = (level - (L - 1)) + g.log_density / (2.0 * std::numbers::ln2);
    if (g.relative_area > 0.99 && std::floor(level_dist + 0.5) >= L) return beckmann;
    const double scale = std::exp2(L - 1 - level);
    const double px = uv[0] * scale - 0.5, py = uv[1] * scale - 0.5;
    const double d0x = axes[0] * scale, d0y = axes[1] * scale, d1x = axes[2] * scale, d1y = axes[3] * scale;
    double A = d0y * d0y + d1y * d1y + 1.0, B = -2.0 * (d0x * d0y + d1x * d1y), C = d0x * d0x + d1x * d1x + 1.0;
    const double F = A * C - 0.25 * B * B;
    A /= F;
    B /= F;
    C /= F;
    const double det = 4.0 * A * C - B * B;
    const double half_u = 2.0 * std::sqrt(det * C) / det, half_v = 2.0 * std::sqrt(A * det) / det;
    const int s0 = int(std::ceil(px - half_u)), s1 = int(std::floor(px + half_u));
    const int t0 = int(std::ceil(py - half_v)), t1 = int(std::floor(py + half_v));
    double sum = 0.0, weights = 0.0;
    int visited = 0;
    for (int t = t0; t <= t1 && visited < max_cells; ++t)
        for (int s = s0; s <= s1 && visited < max_cells; ++s) {
            ++visited;
            if (cost) ++cost->visited;
            const double ds = s - px, dt = t - py;
            const double r2 = A * ds * ds + B * ds * dt + C * dt * dt;
            if (r2 < 1.0) {
                const double w = std::exp(-2.0 * r2) - std::exp(-2.0);
                if (cost) ++cost->weighted;
                sum += w * cell(d, s, t, level, level_dist, hs, dh, minv, beckmann, g, cost);
                weights += w;
            }
        }
    return weights > 1e-6 ? sum / weights : 0.0;
}

}  // namespace

std::array<uint32_t, 3> glint_pcg3d(std::array<uint32_t, 3> v) {
    for (uint32_t& c : v) c = c * 1664525u + 1013904223u;
    v[0] += v[1] * v[2];
    v[1] += v[2] * v[0];
    v[2] += v[0] * v[1];
    for (uint32_t& c : v) c ^= c >> 16u;
    v[0] += v[1] * v[2];
    v[1] += v[2] * v[0];
    v[2] += v[0] * v[1];
    return v;
}

std::array<uint32_t, 6> glint_cell_draws(int32_t s, int32_t t, int level) {
    const std::array<uint32_t, 3> r1 = glint_pcg3d({uint32_t(s) << uint32_t(level), uint32_t(t) << uint32_t(level), 0x2545F491u});
    const std::array<uint32_t, 3> r2 = glint_pcg3d({r1[0] ^ 0x9E3779B9u, r1[1] ^ 0x85EBCA6Bu, r1[2] ^ 0xC2B2AE35u});
    return {r1[0], r1[1], r1[2], r2[0], r2[1], r2[2]};
}

double glint_unit(uint32_t x) { return double(x >> 8u) / 16777216.0; }

GlintSigmaRho glint_sigma_rho(double xx, double yy, double xy) {
    const double sx = std::clamp(std::sqrt(std::max(xx, 0.0)), 0.01, 1.0);
    const double sy = std::clamp(std::sqrt(std::max(yy, 0.0)), 0.01, 1.0);
    return {sx, sy, std::clamp(xy / (sx * sy), -0.99, 0.99)};
}

std::array<double, 4> glint_inverse_transform(const GlintSigmaRho& s, double sigma_o) {
    const double c = std::sqrt(1.0 - s.rho * s.rho);
    return {sigma_o / (s.sx * c), -sigma_o * s.rho / (s.sy * c), 0.0, sigma_o / s.sy};
}

double glint_beckmann_p22(double mx, double my, const GlintSigmaRho& s) {
    const double c2 = 1.0 - s.rho * s.rho;
    const double x = mx / s.sx, y = my / s.sy;
    return std::exp(-0.5 * (x * x - 2.0 * s.rho * x * y + y * y) / c2) / (2.0 * kPi * s.sx * s.sy * std::sqrt(c2));
}

double glint_ggx_p22(double mx, double my, const GlintSigmaRho& s) {
    // A = 2 Sigma; m^T A^-1 m = q / 2 with q the Beckmann exponent's quadratic form.
    const double c2 = 1.0 - s.rho * s.rho;
    const double x = mx / s.sx, y = my / s.sy;
    const double q = (x * x - 2.0 * s.rho * x * y + y * y) / c2;
    const double t = 1.0 + 0.5 * q;
    return 1.0 / (2.0 * kPi * s.sx * s.sy * std::sqrt(c2) * t * t);
}

double glint_cell_scale(const std::array<uint32_t, 6>& r) {
    const std::array<uint32_t, 3> r3 = glint_pcg3d({r[3] ^ 0x27D4EB2Fu, r[4] ^ 0x165667B1u, r[5] ^ 0xD3A2646Cu});
    return std::max(-std::log(1.0 - glint_unit(r3[0])), 1.0 / 64.0);
}

double glint_marginal_grad(const GlintDictionary& d, int level, int marginal, double x, double gx, double gy) {
    const double u = std::fabs(x) * 0.25 / glint_sigma_o(d.settings);
    const double rho = std::max(std::fabs(gx), std::fabs(gy)) * d.settings.width;
    const double lambda = rho > 0.0 ? std::log2(rho) : -1.0;
    if (lambda <= 0.0) return texel_row_lookup(d, level, marginal, 0, u);
    const int q = d.mip_count - 1;
    if (lambda >= q) return texel_row_lookup(d, level, marginal, q, u);
    const int m = int(std::floor(lambda));
    const double f = lambda - m;
    return (1.0 - f) * texel_row_lookup(d, level, marginal, m, u) + f * texel_row_lookup(d, level, marginal, m + 1, u);
}

double glint_p22(const GlintDictionary& d, std::array<double, 2> uv, std::array<double, 4> duv,
                 std::array<double, 2> hs, std::array<double, 4> dh, const GlintSigmaRho& s, const GlintParams& g,
                 GlintCost* cost) {
    const Footprint f = footprint(duv, g.max_anisotropy, d.settings.levels);
    const int il = int(std::floor(f.level));
    const double w = f.level - il;
    const std::array<double, 4> minv = glint_inverse_transform(s, glint_sigma_o(d.settings));
    const double beckmann = g.ggx ? glint_ggx_p22(hs[0], hs[1], s) : glint_beckmann_p22(hs[0], hs[1], s);
    constexpr int kMaxCells = 64;  // SPECAA_GLINT_MAX_CELLS
    double p = (1.0 - w) * level_sdf(d, uv, f.axes, il, hs, dh, minv, beckmann, g, kMaxCells, cost);
    if (w > 0.0) p += w * level_sdf(d, uv, f.axes, il + 1, hs, dh, minv, beckmann, g, kMaxCells, cost);
    return p;
}

}  // namespace specbake
