// C++ evaluation of the include's glint functions (shaders/src/specaa_glints.inc: C21 Eq. 3-6, 15, 18,
// 19, 21 on the C20 cell pyramid), reading the dictionary as the GPU does: the reference for the GL tests.
#pragma once

#include "bake/glint_dictionary.h"

#include <array>
#include <cstdint>

namespace specbake {

struct GlintParams {
    double log_density = 15.0;
    double relative_area = 1.0;
    double density_randomization = 2.0;
    double max_anisotropy = 4.0;
    double kernel_scale = 0.5;
    // Target NDF: Beckmann (C20/C21), or GGX (SPECAA_GLINT_GGX): each cell's transform is divided by
    // sqrt(E), E ~ Exp(1) from the cell hash (clamped at 1/64), because GGX slopes are the scale mixture
    // N(0, Sigma / E) (a bivariate Student t with 2 degrees of freedom); the analytic fallback is GGX.
    bool ggx = false;
};

// pcg3d (Jarzynski & Olano 2020), as in the include.
std::array<uint32_t, 3> glint_pcg3d(std::array<uint32_t, 3> v);
// The draws of a cell (s, t) at spatial level `level`: (r1, r2) of specaa_glint_cell.
std::array<uint32_t, 6> glint_cell_draws(int32_t s, int32_t t, int level);
double glint_unit(uint32_t x);  // top 24 bits / 2^24

struct GlintSigmaRho {
    double sx, sy, rho;
};
GlintSigmaRho glint_sigma_rho(double xx, double yy, double xy);                    // with the include's clamps
std::array<double, 4> glint_inverse_transform(const GlintSigmaRho& s, double sigma_o);  // Eq. 18 inverse
double glint_beckmann_p22(double mx, double my, const GlintSigmaRho& s);
// GGX slope distribution with A = 2 Sigma: 1 / (pi sqrt(det A) (1 + m^T A^-1 m)^2).
double glint_ggx_p22(double mx, double my, const GlintSigmaRho& s);
// The GGX scale E of a cell from its third draw set (specaa_glint_cell with SPECAA_GLINT_GGX).
double glint_cell_scale(const std::array<uint32_t, 6>& draws);

// Trilinear read of marginal i at level k with explicit u-gradients (gx, gy), OpenGL 4.6 Sec. 8.14:
// lambda = log2(max(|gx|, |gy|) width), magnification (linear, mip 0) for lambda <= 0, else linear
// between mips floor(lambda) and floor(lambda) + 1; linear filtering through texel centres, clamp to edge.
double glint_marginal_grad(const GlintDictionary& d, int level, int marginal, double x, double gx, double gy);

// What one evaluation did (the run-time cost): bounding-box cells visited, cells inside the ellipse,
// dictionary fetches.
struct GlintCost {
    long visited = 0, weighted = 0, fetches = 0;
};

// The include's specaa_glint_P22 (uv, duv = (ddx uv, ddy uv), hs, dh = (ddx h.xy, ddy h.xy)); adds its
// cost to `cost` when given.
double glint_p22(const GlintDictionary& d, std::array<double, 2> uv, std::array<double, 4> duv,
                 std::array<double, 2> hs, std::array<double, 4> dh, const GlintSigmaRho& s, const GlintParams& g,
                 GlintCost* cost = nullptr);

}  // namespace specbake
