// Roughness mips baked from a normal map the way engines bake them offline, written from their published
// formulas (docs/accuracy.md#engine-peers), for the simulator's peer rows. Each level-k texel averages
// the unit normals of level 0 under it (the texels [x W / w_k, (x + 1) W / w_k) of the normal map, a
// 2^k box for power-of-two sizes), takes the mean's length r, the von Mises-Fisher concentration
// kappa = (3 r - r^3) / (1 - r^2) (Banerjee et al. 2005's approximation; kappa = 10^4 where r >= 1), and
// widens the box-filtered roughness of the same texels:
// - Filament `roughness-prefilter` (tools/roughness-prefilter, Karis 2018's correction of Neubelt 2013):
//   normals decoded as normalize(2c - 1) with the stored blue channel; r' = sqrt(r^2 + 2 / kappa).
//   FilamentDebian is the formula of the `roughness-prefilter` that Debian 12 ships (Filament 1.9.25):
//   r' = sqrt(r^2 + 1 / (2 kappa)), four times less spread, measured against that binary in the tests.
// - Godot 4 importer (core/io/image.cpp `generate_mipmap_roughness`): z rebuilt as
//   sqrt(max(0, 1 - x^2 - y^2)) from x, y = 2c - 1; r' = sqrt(r^2 + min(3 (0.25 / kappa), 0.4^2)).
// - Unity HDRP `NormalMapFilteringTexturePostprocessor` (files named `_NF`): normals decoded as
//   normalize(2c - 1) with the stored blue channel; var = min(1 / (4 kappa), 0.03125) (0 where r_bar >= 1,
//   the cap being what its 8-bit encoding holds), applied by its shader's NormalFiltering as
//   a' = a + min(2 var, threshold^2) on a = r^4, threshold 0.2 (HDRP's default specular AA threshold).
// - Unreal 5 composite texture (`ApplyCompositeTexture`, Toksvig, CompositePower 1): the mean of the decoded
//   2c - 1 vectors, not normalised per texel (the normal map's own box-filtered mip), L = min(|mean|, 1),
//   var = max(0, (1 - L) / L - 4e-5); with a = r^4, B = 2 var (a - 1), a' = (B - a) / (B - 1). It is applied
//   to every level, level 0 included (a stored normal shorter than 1 widens there too).
// Level 0 is the roughness as authored in the others. The result is clamped to [0, 1] (the engines store it
// in unsigned normalised formats).
#pragma once

#include "core/image.h"
#include "core/result.h"

namespace specbake {

enum class PeerRoughnessBake { Filament, FilamentDebian, Godot, UnityHdrp, Unreal };

// `normal`: 3+ channels encoded (n + 1) / 2, +Y green; `roughness`: 1+ channels (channel 0: perceptual
// roughness r) of any size, or null for the constant `roughness_value`. Returns levels down to 1 x 1 of
// the normal map's size, one channel of perceptual roughness.
Result<MipChain> bake_peer_roughness(const Image& normal, const Image* roughness, float roughness_value,
                                     PeerRoughnessBake peer);

// The widened roughness of one texel from its mean normal length r_bar (Unreal: L, the length of the mean
// of the decoded vectors) and box-filtered roughness r.
double peer_widened_roughness(double r_bar, double r, PeerRoughnessBake peer);

}  // namespace specbake
