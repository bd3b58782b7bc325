// Default parameters of the derivative-based NDF filters (SPEC Sec. 2). Every function takes them as
// parameters; these are the values used when the caller does not choose.
#pragma once

namespace specbake {

// Variance of the Gaussian pixel filter in pixels^2, TK21 App. B: 1/(2 pi), a Gaussian whose peak is 1.
inline constexpr double kDefaultSigma2 = 0.15915494309189535;

// Upper bound of the kernel squared roughness for the clamped kernels, TK21 Listing 3 / Eq. (10) (from K16).
inline constexpr double kDefaultKappa = 0.18;

// Slope |n.xy| / n.z below which a normal-map texel counts as flat for the Sigma kernel's rough share
// (docs/texture-bake.md#output-layouts): 2.5 steps of an 8-bit map, so quantisation noise on a flat field
// stays flat.
inline constexpr double kFlatSlope = 0.02;

}  // namespace specbake
