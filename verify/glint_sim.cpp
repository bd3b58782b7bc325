// CPU glint simulation: analytic sphere and normal-mapped plane under an orthographic camera, reference
// with Gaussian-filtered sub-pixel samples and the pixel's cell footprint, candidates at the pixel centre.
#include "verify/glint_sim.h"

#include "bake/glint_model.h"
#include "bake/pcg32.h"

#include <tbb/parallel_for.h>

#include <array>
#include <cmath>
#include <numbers>

namespace specbake::verify {
namespace {

using V3 = std::array<double, 3>;
constexpr double kPi = std::numbers::pi;
constexpr double kSigma2 = 1.0 / (2.0 * kPi);  // pixel filter variance, TK21 App. B

double dot(V3 a, V3 b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
V3 sub(V3 a, V3 b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
V3 cross(V3 a, V3 b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }
V3 normalize(V3 a) {
    const double l = std::sqrt(dot(a, a));
    return {a[0] / l, a[1] / l, a[2] / l};
}

// What the shader sees at one screen position: UV, the tangent-space half vector, view and light.
struct Shade {
    bool hit = false;
    std::array<double, 2> uv{};
    V3 h{}, o{}, i{};
};

struct Scene {
    bool plane = false;
    double shift = 0.0;  // motion of the current frame (UV units along u)
    V3 light = normalize({-0.4, 0.5, 1.0});
    V3 light_position = {0.15, 1.3, -0.75};  // the plane's point light: 1.5 along the mirror direction

    // Screen position (x, y) in [-1, 1]^2 (orthographic, looking down -z).
    Shade at(double x, double y) const {
        Shade s;
        V3 n, t, view;
        if (!plane) {
            const double r2 = x * x + y * y;
            if (r2 >= 0.98) return s;  // stay off the silhouette: the UV mapping degenerates there
            const V3 p{x, y, std::sqrt(1.0 - r2)};
            n = p;
            const double phi = std::atan2(p[0], p[2]), theta = std::acos(p[1]);
            s.uv = {phi / (2.0 * kPi) + shift, theta / kPi};
            t = {std::cos(phi), 0.0, -std::sin(phi)};
            view = {0.0, 0.0, 1.0};
        } else {
            // A plane tilted 60 degrees away from the camera: the footprint is anisotropic.
            const double tilt = kPi / 3.0;
            n = {0.0, std::sin(tilt), std::cos(tilt)};
            t = {1.0, 0.0, 0.0};
            // The ray through (x, y) hits the plane at distance y / cos(tilt) along cross(n, t).
            const double along = y / std::cos(tilt);
            s.uv = {0.5 * x + shift, 0.5 * along};
            view = {0.0, 0.0, 1.0};
        }
        const V3 b = cross(n, t);
        // The plane is lit by a point light near the mirror direction, so the half vector sweeps the slope
        // distribution across the image; the sphere by a directional light.
        const V3 l = plane ? normalize(sub(light_position, {x, y, -std::sqrt(3.0) * y})) : light;
        const V3 h = normalize({view[0] + l[0], view[1] + l[1], view[2] + l[2]});
        s.h = {dot(h, t), dot(h, b), dot(h, n)};
        s.o = {dot(view, t), dot(view, b), dot(view, n)};
        s.i = {dot(l, t), dot(l, b), dot(l, n)};
        s.hit = true;
        return s;
    }
};

// Normal map of the plane: ridges of slope amplitude 0.3 along a direction rotated by 30 degrees, 40
// ridges per UV unit: strongly anisotropic and not axis-aligned, so rho matters (C21 Fig. 7).
std::array<double, 2> normal_map_slope(std::array<double, 2> uv) {
    const double c = std::cos(kPi / 6.0), s = std::sin(kPi / 6.0);
    const double a = 0.3 * std::cos(2.0 * kPi * 40.0 * (c * uv[0] + s * uv[1]));
    return {a * c, a * s};
}

// D G2 / (4 o.z) of the glint BRDF (C21 Eq. 1 with F = 1): the specular radiance for a unit light.
double specular(double p22, const Shade& s) {
    const V3 h = s.h;
    const double ih = dot(s.i, h), oh = dot(s.o, h);
    if (s.i[2] <= 0.0 || s.o[2] <= 0.0 || ih <= 0.0 || oh <= 0.0 || h[2] <= 0.0) return 0.0;
    const double g = std::min(1.0, 2.0 * h[2] * s.o[2] / oh) * std::min(1.0, 2.0 * h[2] * s.i[2] / ih);
    return p22 / (h[2] * h[2] * h[2] * h[2]) * g / (4.0 * s.o[2]);
}

struct Candidate {
    std::string name;
    double kernel_scale;
    int lean;  // 0: normal map at the pixel centre, 1: LEAN without rho, 2: LEAN with rho, -1: smooth
};

}  // namespace

Result<GlintSimReport> run_glint_sim(const GlintDictionary& dict, const GlintSimSettings& cfg) {
    if (cfg.scene != "glitter-sphere" && cfg.scene != "glitter-plane")
        return make_error("unknown glint scene '" + cfg.scene + "' (glitter-sphere, glitter-plane)");
    if (cfg.size < 4 || cfg.size > 1024 || cfg.reference_spp < 1 || cfg.frames < 2)
        return make_error("glint simulation: size in [4, 1024], spp >= 1 and frames >= 2");
    Scene scene;
    scene.plane = cfg.scene == "glitter-plane";
    const double sigma = cfg.alpha / std::sqrt(2.0);
    std::vector<Candidate> candidates = {{"smooth", 0.0, -1}, {"c20", 0.0, 0}, {"ggaa", 0.5, 0}, {"ggaa-sk1", 1.0, 0}};
    if (scene.plane) {
        candidates.push_back({"ggaa+lean-norho", 0.5, 1});
        candidates.push_back({"ggaa+lean", 0.5, 2});
    }
    GlintParams base;
    base.log_density = cfg.log_density;
    base.relative_area = cfg.relative_area;
    const int n = cfg.size;
    const double pixel = 2.0 / n;
    const size_t count = size_t(n) * size_t(n);
    std::vector<std::vector<double>> ref(size_t(cfg.frames), std::vector<double>(count, -1.0));
    std::vector<std::vector<std::vector<double>>> img(candidates.size(), ref), cells = img, fetch = img;

    for (int frame = 0; frame < cfg.frames; ++frame) {
        scene.shift = frame * 0.25 * pixel * (scene.plane ? 0.5 : 1.0 / (2.0 * kPi));
        tbb::parallel_for(0, n, [&](int py) {
            for (int px = 0; px < n; ++px) {
                const double cx = -1.0 + (px + 0.5) * pixel, cy = -1.0 + (py + 0.5) * pixel;
                const Shade c = scene.at(cx, cy), ex = scene.at(cx + 0.5 * pixel, cy), wx = scene.at(cx - 0.5 * pixel, cy),
                            ny = scene.at(cx, cy + 0.5 * pixel), sy = scene.at(cx, cy - 0.5 * pixel);
                if (!c.hit || !ex.hit || !wx.hit || !ny.hit || !sy.hit) continue;
                // Pixel derivatives of the UV and of the projected half vector (central differences).
                const std::array<double, 4> duv = {ex.uv[0] - wx.uv[0], ex.uv[1] - wx.uv[1], ny.uv[0] - sy.uv[0], ny.uv[1] - sy.uv[1]};
                const std::array<double, 4> dh = {ex.h[0] - wx.h[0], ex.h[1] - wx.h[1], ny.h[0] - sy.h[0], ny.h[1] - sy.h[1]};
                const size_t at = size_t(py) * size_t(n) + size_t(px);
                auto slope_of = [&](const Shade& s, std::array<double, 2> offset) {
                    return std::array<double, 2>{-s.h[0] / s.h[2] - offset[0], -s.h[1] / s.h[2] - offset[1]};
                };
                const GlintSigmaRho material{sigma, sigma, 0.0};
                // Reference: Gaussian-distributed samples (stratified, Box-Muller), footprint of the pixel,
                // no GGAA, no LEAN, the normal map at full resolution.
                Pcg32 rng(uint64_t(frame) * 1000003u + at, 17u);
                const int strata = std::max(1, int(std::sqrt(double(cfg.reference_spp))));
                double sum = 0.0;
                int used = 0;
                for (int k = 0; k < strata * strata; ++k) {
                    const double u1 = (k % strata + rng.uniform()) / strata, u2 = (k / strata + rng.uniform()) / strata;
                    const double r = std::sqrt(-2.0 * kSigma2 * std::log(1.0 - u1));
                    const Shade s = scene.at(cx + r * std::cos(2 * kPi * u2) * pixel, cy + r * std::sin(2 * kPi * u2) * pixel);
                    ++used;
                    if (!s.hit) continue;
                    GlintParams g = base;
                    g.kernel_scale = 0.0;
                    const std::array<double, 2> off = scene.plane ? normal_map_slope(s.uv) : std::array<double, 2>{0, 0};
                    sum += specular(glint_p22(dict, s.uv, duv, slope_of(s, off), {0, 0, 0, 0}, material, g), s);
                }
                ref[size_t(frame)][at] = sum / used;
                // LEAN moments of the normal map over the pixel's UV footprint (ideal box-filtered mips).
                double mx = 0, my = 0, mxx = 0, myy = 0, mxy = 0;
                const int q = 8;
                for (int a = 0; a < q; ++a)
                    for (int b = 0; b < q; ++b) {
                        const double fa = (a + 0.5) / q - 0.5, fb = (b + 0.5) / q - 0.5;
                        const std::array<double, 2> sl = normal_map_slope({c.uv[0] + fa * duv[0] + fb * duv[2], c.uv[1] + fa * duv[1] + fb * duv[3]});
                        mx += sl[0] / (q * q), my += sl[1] / (q * q);
                        mxx += sl[0] * sl[0] / (q * q), myy += sl[1] * sl[1] / (q * q), mxy += sl[0] * sl[1] / (q * q);
                    }
                for (size_t ci = 0; ci < candidates.size(); ++ci) {
                    const Candidate& cand = candidates[ci];
                    GlintParams g = base;
                    g.kernel_scale = cand.kernel_scale;
                    std::array<double, 2> off = {0, 0};
                    GlintSigmaRho s = material;
                    if (scene.plane && cand.lean <= 0) off = normal_map_slope(c.uv);
                    if (scene.plane && cand.lean >= 1) {
                        off = {mx, my};
                        const double vx = mxx - mx * mx, vy = myy - my * my, cxy = cand.lean == 2 ? mxy - mx * my : 0.0;
                        s = glint_sigma_rho(sigma * sigma + vx, sigma * sigma + vy, cxy);
                    }
                    const std::array<double, 2> hs = slope_of(c, off);
                    // Eq. 21 in the normal-mapped frame: without LEAN the half vector's derivatives carry the
                    // point-sampled normal map (projected h ~ -h.z slope for the small tilts here).
                    std::array<double, 4> dhc = dh;
                    if (scene.plane && cand.lean == 0) {
                        const std::array<double, 2> e = slope_of(ex, normal_map_slope(ex.uv)), w = slope_of(wx, normal_map_slope(wx.uv));
                        const std::array<double, 2> nn = slope_of(ny, normal_map_slope(ny.uv)), ss = slope_of(sy, normal_map_slope(sy.uv));
                        dhc = {-c.h[2] * (e[0] - w[0]), -c.h[2] * (e[1] - w[1]), -c.h[2] * (nn[0] - ss[0]), -c.h[2] * (nn[1] - ss[1])};
                    }
                    GlintCost cost;
                    const double p22 = cand.lean < 0 ? glint_beckmann_p22(hs[0], hs[1], s)
                                                     : glint_p22(dict, c.uv, duv, hs, dhc, s, g, &cost);
                    cells[ci][size_t(frame)][at] = double(cost.visited);
                    fetch[ci][size_t(frame)][at] = double(cost.fetches);
                    img[ci][size_t(frame)][at] = specular(p22, c);
                }
            }
        });
    }

    GlintSimReport report;
    double ref_sum = 0.0;
    size_t covered = 0;
    for (int f = 0; f < cfg.frames; ++f)
        for (size_t p = 0; p < count; ++p)
            if (ref[size_t(f)][p] >= 0.0) ref_sum += ref[size_t(f)][p], ++covered;
    if (covered == 0 || ref_sum <= 0.0) return make_error("glint simulation: the scene shows no highlight");
    report.pixels = int(covered / size_t(cfg.frames));
    report.reference_mean = ref_sum / double(covered);
    for (size_t ci = 0; ci < candidates.size(); ++ci) {
        double se = 0.0, sum = 0.0, flicker = 0.0, row_cells = 0.0, row_fetches = 0.0;
        size_t changes = 0;
        for (int f = 0; f < cfg.frames; ++f)
            for (size_t p = 0; p < count; ++p) {
                if (ref[size_t(f)][p] < 0.0) continue;
                const double e = img[ci][size_t(f)][p] - ref[size_t(f)][p];
                se += e * e;
                sum += img[ci][size_t(f)][p];
                row_cells += cells[ci][size_t(f)][p];
                row_fetches += fetch[ci][size_t(f)][p];
                if (f > 0 && ref[size_t(f) - 1][p] >= 0.0) {
                    flicker += std::fabs(e - (img[ci][size_t(f) - 1][p] - ref[size_t(f) - 1][p]));
                    ++changes;
                }
            }
        GlintSimRow row;
        row.candidate = candidates[ci].name;
        row.rmse_percent = 100.0 * std::sqrt(se / double(covered)) / report.reference_mean;
        row.flicker = changes ? flicker / double(changes) / report.reference_mean : 0.0;
        row.energy = sum / ref_sum;
        row.cells = row_cells / double(covered);
        row.fetches = row_fetches / double(covered);
        report.rows.push_back(row);
    }
    return report;
}

}  // namespace specbake::verify
