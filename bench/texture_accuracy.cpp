// Accuracy of the texture bake (issue 3, item 7): for every shared normal map and several base
// roughnesses, the footprint-NDF error of baked mip texels, per method.
//
// Error of one footprint: E = integral over the hemisphere of |D_exact(h) - D_lobe(h)| (h.z) d omega_h,
// with D_exact the mean of the base GGX lobes tilted to every base texel's normal (area weights as in
// the bake) and D_lobe one GGX lobe about the normalised mean normal with the method's roughness. With
// the projected-disk parameterisation h = (x, y, sqrt(1 - x^2 - y^2)), (h.z) d omega = dx dy, so E is a
// plain integral over the unit disk, evaluated on a regular grid. E = 0 is a perfect lobe; 2 is disjoint.
//
// Methods: the bake (projected filtering with the mean, sum and max reductions; approx filtering with
// mean), plain mipmapping (alpha^2 box-filtered, no variance), Filament's roughness prefilter
// (r' = sqrt(r^2 + min(2 * 0.25 / k, 0.04)), k = (3l - l^3) / (1 - l^2), l = |mean normal|) and
// Toksvig (Blinn-Phong exponent s = 2 / alpha^2 - 2 scaled by l / (l + s (1 - l)), back to alpha).
//
// Run: build/bench/texture_accuracy [assets folder]   (a few minutes on 2 cores)
#include "bake/texture_bake.h"
#include "io/image/image_io.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace {
using namespace specbake;
namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;
constexpr int kGrid = 256;            // grid points per side of [-1, 1]^2
constexpr int kSamplesPerLevel = 6;   // footprints per level and map
constexpr int kMaxLevel = 5;          // footprints up to 32 x 32 base texels

// Isotropic GGX NDF about a unit normal, as a function of cos = n.h (TK21 Eq. 1 with A = alpha^2 I).
double ggx(double cos_nh, double alpha2) {
    if (cos_nh <= 0.0) return 0.0;
    const double d = cos_nh * cos_nh * (alpha2 - 1.0) + 1.0;
    return alpha2 / (kPi * d * d);
}

struct Grid {
    std::vector<double> hx, hy, hz;
    double cell = 0.0;
};

Grid make_grid() {
    Grid g;
    g.cell = (2.0 / kGrid) * (2.0 / kGrid);
    for (int j = 0; j < kGrid; ++j)
        for (int i = 0; i < kGrid; ++i) {
            const double x = -1.0 + (i + 0.5) * 2.0 / kGrid, y = -1.0 + (j + 0.5) * 2.0 / kGrid;
            const double r2 = x * x + y * y;
            if (r2 >= 1.0) continue;
            g.hx.push_back(x), g.hy.push_back(y), g.hz.push_back(std::sqrt(1.0 - r2));
        }
    return g;
}

void decode(const Image& n, int x, int y, double out[3]) {
    const float* c = n.texel(x, y);
    double v[3] = {2.0 * c[0] - 1.0, 2.0 * c[1] - 1.0, n.channels >= 3 ? 2.0 * c[2] - 1.0 : 0.0};
    if (n.channels == 2) v[2] = std::sqrt(std::max(0.0, 1.0 - v[0] * v[0] - v[1] * v[1]));
    const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (len < 1e-12) v[0] = 0, v[1] = 0, v[2] = 1;
    else
        for (double& c2 : v) c2 /= len;
    for (int k = 0; k < 3; ++k) out[k] = v[k];
}

struct Footprint {
    std::vector<double> normals;  // 3 per base texel
    std::vector<double> weights;
    double mean[3] = {0, 0, 0};
};

// Base texels of texel (i, j) of level L with their area weights (as in bake/texture_bake.h).
Footprint footprint(const Image& n, int L, int i, int j) {
    const int W = n.width, H = n.height, w = std::max(1, W >> L), h = std::max(1, H >> L);
    const double x0 = double(i) * W / w, x1 = double(i + 1) * W / w, y0 = double(j) * H / h, y1 = double(j + 1) * H / h;
    Footprint f;
    double total = 0.0;
    for (int y = int(std::floor(y0)); y < std::min(H, int(std::ceil(y1))); ++y)
        for (int x = int(std::floor(x0)); x < std::min(W, int(std::ceil(x1))); ++x) {
            const double wx = std::min(x + 1.0, x1) - std::max(double(x), x0);
            const double wy = std::min(y + 1.0, y1) - std::max(double(y), y0);
            if (wx <= 0 || wy <= 0) continue;
            double v[3];
            decode(n, x, y, v);
            f.normals.insert(f.normals.end(), v, v + 3);
            f.weights.push_back(wx * wy);
            total += wx * wy;
            for (int k = 0; k < 3; ++k) f.mean[k] += wx * wy * v[k];
        }
    for (double& wgt : f.weights) wgt /= total;
    for (double& m : f.mean) m /= total;
    return f;
}

enum Method { kProjMean, kProjSum, kProjMax, kApproxMean, kNone, kFilament, kToksvig, kMethodCount };
const char* kMethodNames[kMethodCount] = {"proj-mean", "proj-sum", "proj-max", "approx", "mipmap", "filament", "toksvig"};

double filament_alpha2(double r, double l) {
    if (l >= 1.0) return r * r * r * r;
    const double k = (3.0 * l - l * l * l) / (1.0 - l * l);
    const double rp = std::sqrt(r * r + std::min(2.0 * 0.25 / k, 0.04));
    return std::pow(std::min(1.0, rp), 4.0);
}

double toksvig_alpha2(double r, double l) {
    const double alpha2 = std::max(1e-8, r * r * r * r);
    const double s = 2.0 / alpha2 - 2.0;
    const double ft = l / (l + s * (1.0 - l));
    return std::min(1.0, 2.0 / (ft * s + 2.0));
}

}  // namespace

int main(int argc, char** argv) {
    const fs::path assets = argc > 1 ? fs::path(argv[1]) : fs::path(SPECBAKE_ASSETS_DIR);
    std::vector<fs::path> maps;
    if (fs::exists(assets)) {
        for (const auto& e : fs::recursive_directory_iterator(assets)) {
            const std::string name = e.path().filename().string();
            std::string lower = name;
            std::transform(lower.begin(), lower.end(), lower.begin(), ::tolower);
            if (lower.find("normal") == std::string::npos) continue;
            if (lower.find("basecolor") != std::string::npos || lower.find("occlusion") != std::string::npos) continue;
            if (!(lower.ends_with(".png") || lower.ends_with(".jpg"))) continue;
            if (e.path().parent_path().filename() == "NormalTangentMirrorTest") continue;  // same file as NormalTangentTest
            maps.push_back(e.path());
        }
    }
    std::sort(maps.begin(), maps.end());
    if (maps.empty()) {
        std::fprintf(stderr, "no normal maps found under %s\n", assets.string().c_str());
        return 1;
    }
    const Grid grid = make_grid();
    const double roughnesses[] = {0.2, 0.4, 0.7};

    std::printf("Footprint-NDF error E (L1 over the hemisphere, projected-area weighted; 0 = exact, 2 = disjoint)\n");
    std::printf("mean over %d footprints per level, levels 1-%d, grid %d^2\n\n", kSamplesPerLevel, kMaxLevel, kGrid);
    std::printf("%-40s %4s", "normal map", "r");
    for (const char* m : kMethodNames) std::printf(" %9s", m);
    std::printf("\n");
    double grand[kMethodCount] = {};
    int grand_rows = 0;
    for (const fs::path& path : maps) {
        auto img = io::read_image(path);
        if (!img) {
            std::fprintf(stderr, "%s\n", img.error().message.c_str());
            continue;
        }
        const Image& n = *img;
        for (double r : roughnesses) {
            // The bake's outputs for each reduction / filter.
            TextureBakeResult bakes[4];
            const IsotropicReduction reds[4] = {IsotropicReduction::Mean, IsotropicReduction::Sum, IsotropicReduction::Max,
                                                IsotropicReduction::Mean};
            bool ok = true;
            for (int b = 0; b < 4; ++b) {
                TextureBakeSettings s;
                s.isotropic = reds[b];
                s.filter = b == 3 ? RoughnessFilterMode::Approx : RoughnessFilterMode::Projected;
                s.outputs.lean = false;
                auto res = bake_texture(n, nullptr, 0, float(r), s);
                if (!res) {
                    std::fprintf(stderr, "%s: %s\n", path.string().c_str(), res.error().message.c_str());
                    ok = false;
                    break;
                }
                bakes[b] = std::move(*res);
            }
            if (!ok) continue;
            const double rr = double(float(r));
            const double a_base = rr * rr * rr * rr;
            double sum[kMethodCount] = {};
            int count = 0;
            const int levels = std::min(kMaxLevel, mip_level_count(n.width, n.height) - 1);
            for (int L = 1; L <= levels; ++L) {
                const int w = std::max(1, n.width >> L), h = std::max(1, n.height >> L);
                for (int s = 0; s < kSamplesPerLevel; ++s) {
                    // Fixed, spread-out texels: a low-discrepancy walk over the level.
                    const int i = int(std::fmod((s + 0.5) * 0.6180339887498949, 1.0) * w);
                    const int j = int(std::fmod((s + 0.5) * 0.7548776662466927 + 0.31, 1.0) * h);
                    const Footprint f = footprint(n, L, i, j);
                    const size_t count_texels = f.weights.size();
                    const double ml = std::sqrt(f.mean[0] * f.mean[0] + f.mean[1] * f.mean[1] + f.mean[2] * f.mean[2]);
                    const double axis[3] = {f.mean[0] / ml, f.mean[1] / ml, f.mean[2] / ml};
                    double a_out[kMethodCount];
                    for (int b = 0; b < 4; ++b) {
                        const double rb = bakes[b].roughness.levels[size_t(L)].texel(i, j)[0];
                        a_out[b] = rb * rb * rb * rb;
                    }
                    a_out[kNone] = a_base;
                    a_out[kFilament] = filament_alpha2(rr, std::min(1.0, ml));
                    a_out[kToksvig] = toksvig_alpha2(rr, std::min(1.0, ml));
                    std::vector<double> err(grid.hx.size() * kMethodCount);
                    tbb::parallel_for(size_t(0), grid.hx.size(), [&](size_t g) {
                        const double hx = grid.hx[g], hy = grid.hy[g], hz = grid.hz[g];
                        double exact = 0.0;
                        for (size_t t = 0; t < count_texels; ++t) {
                            const double* nn = &f.normals[3 * t];
                            exact += f.weights[t] * ggx(nn[0] * hx + nn[1] * hy + nn[2] * hz, a_base);
                        }
                        const double c = axis[0] * hx + axis[1] * hy + axis[2] * hz;
                        for (int m = 0; m < kMethodCount; ++m)
                            err[g * kMethodCount + size_t(m)] = std::abs(exact - ggx(c, a_out[m]));
                    });
                    for (int m = 0; m < kMethodCount; ++m) {
                        double e = 0.0;
                        for (size_t g = 0; g < grid.hx.size(); ++g) e += err[g * kMethodCount + size_t(m)];
                        sum[m] += e * grid.cell;
                    }
                    ++count;
                }
            }
            std::string label = path.parent_path().filename().string() + "/" + path.filename().string();
            if (label.size() > 40) label = "..." + label.substr(label.size() - 37);
            std::printf("%-40s %4.1f", label.c_str(), r);
            for (int m = 0; m < kMethodCount; ++m) {
                std::printf(" %9.4f", sum[m] / count);
                grand[m] += sum[m] / count;
            }
            std::printf("\n");
            std::fflush(stdout);
            ++grand_rows;
        }
    }
    std::printf("%-40s %4s", "mean of all rows", "");
    for (int m = 0; m < kMethodCount; ++m) std::printf(" %9.4f", grand[m] / grand_rows);
    std::printf("\n");
    return 0;
}
