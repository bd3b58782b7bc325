// Run-time cost of the include's glint path per pixel and light, counted with its C++ twin
// (bake/glint_model.h, checked against the GLSL on llvmpipe): bounding-box cells visited, cells inside the
// footprint ellipse, dictionary fetches, over random pixel footprints at the glitter scenes' pixel scale.
#include "bake/glint_model.h"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

using namespace specbake;

int main() {
    auto dict = shared_glint_dictionary(GlintDictionarySettings{});
    if (!dict) {
        std::fprintf(stderr, "glint_cost: %s\n", dict.error().message.c_str());
        return 1;
    }
    const double sigma = 0.1 / std::sqrt(2.0);  // alpha 0.1, as `verify --builtin glitter-* --alpha 0.1`
    const GlintSigmaRho s{sigma, sigma, 0.0};
    std::printf("Per pixel and light, logDensity 15, alpha 0.1, half vectors from the Beckmann lobe (where the\n"
                "highlight is), footprints of 2^-7.5 UV (about one 64 x 64 pixel on the glitter sphere) times\n"
                "2^[-1, 1], random orientation; 20000 pixels per row. C20 (s_K = 0) and GGAA (s_K = 0.5) visit\n"
                "and fetch alike: GGAA reads with textureGrad where C20 reads mip 0.\n\n");
    std::printf("| eccentricity | cells visited | cells in ellipse | dictionary fetches |\n|---:|---:|---:|---:|\n");
    for (const double eccentricity : {1.0, 2.0, 4.0, 8.0}) {
        std::mt19937_64 rng(7);
        std::uniform_real_distribution<double> u(0.0, 1.0);
        std::normal_distribution<double> n(0.0, 1.0);
        GlintCost cost;
        const int pixels = 20000;
        for (int p = 0; p < pixels; ++p) {
            const double len = std::exp2(-7.5 + 2.0 * (u(rng) - 0.5)), a = 2.0 * std::numbers::pi * u(rng);
            const std::array<double, 4> duv = {len * std::cos(a), len * std::sin(a), -len / eccentricity * std::sin(a),
                                               len / eccentricity * std::cos(a)};
            const std::array<double, 2> hs = {sigma * n(rng), sigma * n(rng)};
            const std::array<double, 4> dh = {0.01 * n(rng), 0.01 * n(rng), 0.01 * n(rng), 0.01 * n(rng)};
            glint_p22(**dict, {4.0 * u(rng), 4.0 * u(rng)}, duv, hs, dh, s, GlintParams{}, &cost);
        }
        std::printf("| %.0f:1 | %.1f | %.1f | %.1f |\n", eccentricity, double(cost.visited) / pixels,
                    double(cost.weighted) / pixels, double(cost.fetches) / pixels);
    }
    return 0;
}
