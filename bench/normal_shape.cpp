// Shape of a normal map's spread per mip texel, and what a one-lobe model of it gets wrong
// (docs/accuracy.md#mixed-texels): for every shared normal map and mip levels 2, 4 and 6,
// - the kurtosis E|d|^4 / (E|d|^2)^2 of the slopes d about the texel's mean slope (2 for a 2D Gaussian,
//   below 2 for a compact band, above 2 for a spike with tails), weighted by the texel's variance, and
// - the density of the map's normals in slope space at half vectors h tilted 5-60 degrees from the
//   surface normal (mean over 8 azimuths): the true one (the fraction of full-resolution texels whose
//   slope lies within a disk of radius 0.02 about h's slope, per area) against the model every one-lobe
//   filter shares, one Gaussian per mip texel with the texel's mean and covariance of slopes (LEAN,
//   LEADR), averaged over the texels and widened by the disk's own variance (0.02^2 / 4 per axis).
// A ratio above 1 is light the filtered material reflects at h that the full-resolution map does not:
// where texels mix a flat field with steep bumps, each texel's Gaussian fills the gap between them.
// Second model, from the same moments plus one number per texel: the flat fraction f (the share of the
// texel whose slope is below kFlat, the unperturbed normal) as a spike at slope 0, and the rest as one
// Gaussian whose moments follow from the texel's: mean m / (1 - f), second moment E[d d^T] / (1 - f).
// f is linear in the base texels, so its mips are plain box filters of a 0/1 mask.
//
// Run: build/bench/normal_shape [assets folder]   (seconds)
#include "io/image/image_io.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

namespace {
using namespace specbake;
namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;
constexpr double kDisk = 0.02;  // slope-space radius of the true density's histogram disk
constexpr double kFlat = 0.02;  // slope below which a base texel counts as flat (8-bit encoding: 1/127 steps)
constexpr double kTilts[] = {5, 10, 20, 30, 45, 60};
constexpr int kAzimuths = 8;

struct Slopes {
    int width = 0, height = 0;
    std::vector<double> x, y;
};

// Slopes (-n_x / n_z, -n_y / n_z in the map's tangent frame; the sign does not matter here) of every
// texel, from the encoded (n + 1) / 2, renormalised; normals within 3 degrees of the horizon are clamped there.
Slopes decode_slopes(const Image& n) {
    Slopes s;
    s.width = n.width, s.height = n.height;
    s.x.resize(n.texel_count()), s.y.resize(n.texel_count());
    for (int j = 0; j < n.height; ++j)
        for (int i = 0; i < n.width; ++i) {
            const float* c = n.texel(i, j);
            double v[3] = {2.0 * c[0] - 1.0, 2.0 * c[1] - 1.0, n.channels >= 3 ? 2.0 * c[2] - 1.0 : 0.0};
            if (n.channels == 2) v[2] = std::sqrt(std::max(0.0, 1.0 - v[0] * v[0] - v[1] * v[1]));
            double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            if (len < 1e-12) v[0] = 0, v[1] = 0, v[2] = 1, len = 1;
            // Slope = (x / len) / (z / len), with z / len clamped at 0.05.
            const double z = std::max(v[2], 0.05 * len);
            const size_t k = size_t(j) * n.width + i;
            s.x[k] = v[0] / z;
            s.y[k] = v[1] / z;
        }
    return s;
}

struct Gaussian {
    double mx, my, cxx, cyy, cxy;
};

struct Texel {
    Gaussian all;   // every base texel
    double flat;    // flat fraction f
    Gaussian rest;  // the base texels that are not flat (moments derived from `all` and f)
};

// Mean and covariance of the slopes of each texel of level L (box of 2^L x 2^L base texels) and the
// variance-weighted kurtosis over the level.
std::vector<Texel> level_moments(const Slopes& s, int L, double& kurtosis) {
    const int b = 1 << L, w = s.width / b, h = s.height / b;
    std::vector<Texel> t(size_t(w) * h);
    double kurt_sum = 0, var_sum = 0;
    for (int ty = 0; ty < h; ++ty)
        for (int tx = 0; tx < w; ++tx) {
            double sx = 0, sy = 0;
            for (int y = ty * b; y < ty * b + b; ++y)
                for (int x = tx * b; x < tx * b + b; ++x) sx += s.x[size_t(y) * s.width + x], sy += s.y[size_t(y) * s.width + x];
            const double n = double(b) * b, mx = sx / n, my = sy / n;
            double xx = 0, yy = 0, xy = 0, m4 = 0, flat = 0;
            for (int y = ty * b; y < ty * b + b; ++y)
                for (int x = tx * b; x < tx * b + b; ++x) {
                    const double sx0 = s.x[size_t(y) * s.width + x], sy0 = s.y[size_t(y) * s.width + x];
                    const double dx = sx0 - mx, dy = sy0 - my;
                    xx += dx * dx, yy += dy * dy, xy += dx * dy, m4 += (dx * dx + dy * dy) * (dx * dx + dy * dy);
                    flat += sx0 * sx0 + sy0 * sy0 < kFlat * kFlat;
                }
            Texel& texel = t[size_t(ty) * w + tx];
            texel.all = {mx, my, xx / n, yy / n, xy / n};
            texel.flat = flat / n;
            // The rest from the texel's moments (the flat texels taken as slope 0): mean m / (1 - f), second
            // moment (Sigma + m m^T) / (1 - f), its covariance clamped to positive semi-definite.
            const double r = 1.0 - texel.flat;
            if (r > 1e-3) {
                const double rx = mx / r, ry = my / r;
                double rxx = std::max((xx / n + mx * mx) / r - rx * rx, 0.0), ryy = std::max((yy / n + my * my) / r - ry * ry, 0.0);
                const double lim = std::sqrt(rxx * ryy);
                const double rxy = std::clamp((xy / n + mx * my) / r - rx * ry, -lim, lim);
                texel.rest = {rx, ry, rxx, ryy, rxy};
            } else {
                texel.rest = {0, 0, 0, 0, 0};
            }
            const double m2 = (xx + yy) / n;
            if (m2 > 1e-8) kurt_sum += m2 * (m4 / n) / (m2 * m2), var_sum += m2;
        }
    kurtosis = var_sum > 0 ? kurt_sum / var_sum : 0.0;
    return t;
}

double true_density(const Slopes& s, double hx, double hy) {
    long long count = 0;
    for (size_t k = 0; k < s.x.size(); ++k) {
        const double dx = s.x[k] - hx, dy = s.y[k] - hy;
        count += dx * dx + dy * dy < kDisk * kDisk;
    }
    return double(count) / double(s.x.size()) / (kPi * kDisk * kDisk);
}

// A Gaussian's density at (hx, hy), widened by the histogram disk's variance (0.02^2 / 4 per axis).
double gaussian_density(const Gaussian& g, double hx, double hy) {
    const double widen = 0.25 * kDisk * kDisk;
    const double xx = g.cxx + widen, yy = g.cyy + widen, xy = g.cxy, det = std::max(xx * yy - xy * xy, widen * widen);
    const double dx = hx - g.mx, dy = hy - g.my;
    const double q = (yy * dx * dx - 2.0 * xy * dx * dy + xx * dy * dy) / det;
    return std::exp(-0.5 * q) / (2.0 * kPi * std::sqrt(det));
}

// Mean over the texels of the one-Gaussian model (first) and of the flat-fraction model (second).
std::pair<double, double> model_density(const std::vector<Texel>& texels, double hx, double hy) {
    const double spike = gaussian_density(Gaussian{0, 0, 0, 0, 0}, hx, hy);  // the flat part, the same for every texel
    double one = 0, split = 0;
    for (const Texel& t : texels) {
        one += gaussian_density(t.all, hx, hy);
        split += t.flat * spike;
        if (t.flat < 1.0 - 1e-3) split += (1.0 - t.flat) * gaussian_density(t.rest, hx, hy);
    }
    return {one / double(texels.size()), split / double(texels.size())};
}

// Half-vector slopes: kAzimuths per tilt of kTilts, tilt-major.
std::vector<std::array<double, 2>> half_vector_slopes() {
    std::vector<std::array<double, 2>> h;
    for (double tilt : kTilts)
        for (int a = 0; a < kAzimuths; ++a) {
            const double m = std::tan(tilt * kPi / 180.0), phi = 2.0 * kPi * a / kAzimuths;
            h.push_back({m * std::cos(phi), m * std::sin(phi)});
        }
    return h;
}

// A normal map by its name: a word of the stem (split at '_', '-', '.', ' ') that ends in "normal" or
// "normals" or is "normal" followed by digits ("RibsNormal", "rock_normal_1k", "ldr-xy-normal1"; not
// "NormalTangentTest_BaseColor").
bool is_normal_map_name(const fs::path& path) {
    std::string stem = path.stem().string();
    std::transform(stem.begin(), stem.end(), stem.begin(), [](unsigned char c) {
        return c == '-' || c == '.' || c == ' ' ? '_' : char(std::tolower(c));
    });
    std::stringstream words(stem);
    for (std::string w; std::getline(words, w, '_');) {
        if (w.ends_with("normal") || w.ends_with("normals")) return true;
        if (w.starts_with("normal") && w.size() > 6 &&
            std::all_of(w.begin() + 6, w.end(), [](unsigned char c) { return std::isdigit(c); }))
            return true;
    }
    return false;
}

}  // namespace

int main(int argc, char** argv) {
    const fs::path assets = argc > 1 ? fs::path(argv[1]) : fs::path(SPECBAKE_ASSETS_DIR);
    std::vector<fs::path> maps;
    std::error_code ec;
    if (fs::is_directory(assets, ec))
        for (const auto& e : fs::recursive_directory_iterator(assets)) {
            std::string ext = e.path().extension().string();
            std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
            if (e.is_regular_file() && (ext == ".png" || ext == ".jpg" || ext == ".exr") && is_normal_map_name(e.path()))
                maps.push_back(e.path());
        }
    std::sort(maps.begin(), maps.end());
    if (maps.empty()) {
        std::fprintf(stderr, "normal_shape: no normal maps found under %s (give the assets folder)\n", assets.string().c_str());
        return 1;
    }
    std::printf("Density of normals at h, model / true: one Gaussian per texel, then flat fraction + one Gaussian\n\n");
    std::printf("| map | level | texel | kurtosis | flat fraction");
    for (double t : kTilts) std::printf(" | %.0f deg", t);
    std::printf(" |\n|---|---:|---:|---:|---:");
    for (size_t i = 0; i < std::size(kTilts); ++i) std::printf("|---:");
    std::printf("|\n");
    const std::vector<std::array<double, 2>> halves = half_vector_slopes();
    for (const fs::path& path : maps) {
        auto image = io::read_image(path);
        if (!image) {
            std::fprintf(stderr, "normal_shape: %s\n", image.error().message.c_str());
            return 1;
        }
        const Slopes s = decode_slopes(*image);
        std::vector<double> truth;
        for (const auto& [hx, hy] : halves) truth.push_back(true_density(s, hx, hy));
        for (int L : {2, 4, 6}) {
            if ((s.width >> L) < 4 || (s.height >> L) < 4) continue;
            double kurtosis = 0;
            const std::vector<Texel> texels = level_moments(s, L, kurtosis);
            double flat = 0;
            for (const Texel& t : texels) flat += t.flat;
            std::printf("| %s | %d | %dx%d | %.2f | %.2f ", fs::relative(path, assets).generic_string().c_str(), L, 1 << L,
                        1 << L, kurtosis, flat / double(texels.size()));
            for (size_t k = 0; k < halves.size();) {
                double t = 0, one = 0, split = 0;
                for (int a = 0; a < kAzimuths; ++a, ++k) {
                    t += truth[k];
                    const auto [o, sp] = model_density(texels, halves[k][0], halves[k][1]);
                    one += o, split += sp;
                }
                if (t > 0) std::printf("| %.2f / %.2f ", one / t, split / t);
                else std::printf("| - ");
            }
            std::printf("|\n");
        }
    }
    return 0;
}
