// Engines' offline roughness mips (bake/peer_roughness_bake.h) against values worked from their formulas
// on maps whose mean normals are known in closed form; tests/cli/peer_bake_binary_test.cpp holds the
// Filament path to Debian's roughness-prefilter binary.
#include "bake/peer_roughness_bake.h"

#include <gtest/gtest.h>

#include <cmath>

namespace specbake {
namespace {

// n x n map of two unit normals tilted by +-t about y in a checker: every 2x2 box averages to (0, 0, cos t).
Image checker(int n, double t, double blue_override = -1) {
    Image im(n, n, 3);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const double s = (x + y) % 2 == 0 ? 1.0 : -1.0;
            float* c = im.texel(x, y);
            c[0] = float((std::sin(s * t) + 1) / 2);
            c[1] = 0.5f;
            c[2] = float(blue_override >= 0 ? blue_override : (std::cos(t) + 1) / 2);
        }
    return im;
}

double kappa_of(double r) { return (3 * r - r * r * r) / (1 - r * r); }

TEST(PeerRoughnessBake, FilamentWidensByTwoOverKappaOfTheMeanNormal) {
    const double t = 0.4;
    const Image map = checker(8, t);
    auto chain = bake_peer_roughness(map, nullptr, 0.3f, PeerRoughnessBake::Filament);
    ASSERT_TRUE(chain) << chain.error().message;
    ASSERT_EQ(chain->levels.size(), 4u);  // 8, 4, 2, 1
    EXPECT_EQ(chain->levels[3].width, 1);
    // Level 0 is the roughness as authored; from level 1 on, every box holds both normals equally.
    // The stored 8-bit-free floats give r_bar = cos t up to float rounding of the encoded values.
    EXPECT_FLOAT_EQ(chain->levels[0].texel(3, 5)[0], 0.3f);
    const double expected = std::sqrt(0.09 + 2.0 / kappa_of(std::cos(t)));  // 0.49299
    for (int k = 1; k < 4; ++k) EXPECT_NEAR(chain->levels[size_t(k)].texel(0, 0)[0], expected, 2e-6) << k;
    // Debian's build: a quarter of the spread, 1 / (2 kappa).
    auto debian = bake_peer_roughness(map, nullptr, 0.3f, PeerRoughnessBake::FilamentDebian);
    EXPECT_NEAR(debian->levels[1].texel(1, 1)[0], std::sqrt(0.09 + 0.5 / kappa_of(std::cos(t))), 2e-6);
}

TEST(PeerRoughnessBake, GodotRebuildsZAndLimitsTheVariance) {
    const double t = 0.4;
    // The stored blue channel says z = 1; Godot rebuilds z = sqrt(1 - x^2), so r_bar = cos t as above.
    const Image map = checker(4, t, 1.0);
    auto chain = bake_peer_roughness(map, nullptr, 0.3f, PeerRoughnessBake::Godot);
    ASSERT_TRUE(chain) << chain.error().message;
    const double variance = 0.25 / kappa_of(std::cos(t));  // 0.0192
    EXPECT_NEAR(chain->levels[1].texel(0, 1)[0], std::sqrt(0.09 + 3 * variance), 2e-6);
    // Filament normalises the stored vector (x, 0, 1): a different tilt, atan(sin t) = 0.3709.
    auto filament = bake_peer_roughness(map, nullptr, 0.3f, PeerRoughnessBake::Filament);
    const double r_bar = 1.0 / std::sqrt(1.0 + std::sin(t) * std::sin(t));
    EXPECT_NEAR(filament->levels[1].texel(0, 1)[0], std::sqrt(0.09 + 2.0 / kappa_of(r_bar)), 2e-6);
    // Steep enough and Godot's 0.4^2 cap binds: t = 1.2 gives 3 variance = 0.45 > 0.16.
    auto steep = bake_peer_roughness(checker(4, 1.2, 1.0), nullptr, 0.3f, PeerRoughnessBake::Godot);
    EXPECT_NEAR(steep->levels[1].texel(0, 0)[0], std::sqrt(0.09 + 0.16), 2e-6);
}

TEST(PeerRoughnessBake, FlatMapsKeepTheRoughnessMapsBoxAverage) {
    // A flat normal map (r_bar = 1, kappa = 10^4): Filament adds 2e-4 to r^2, Godot nothing. The roughness
    // map (2x the normal map's size) is box-averaged over the same uv rectangle.
    Image flat(4, 4, 3);
    for (size_t i = 0; i < flat.texel_count(); ++i) flat.pixels[3 * i] = flat.pixels[3 * i + 1] = 0.5f, flat.pixels[3 * i + 2] = 1.0f;
    Image rough(8, 8, 1);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) rough.texel(x, y)[0] = x < 4 ? 0.2f : 0.6f;
    auto godot = bake_peer_roughness(flat, &rough, 0.0f, PeerRoughnessBake::Godot);
    ASSERT_TRUE(godot);
    EXPECT_NEAR(godot->levels[0].texel(0, 0)[0], 0.2, 1e-6);  // 2x2 roughness texels, all 0.2
    EXPECT_NEAR(godot->levels[2].texel(0, 0)[0], 0.4, 1e-6);  // the whole map
    auto filament = bake_peer_roughness(flat, &rough, 0.0f, PeerRoughnessBake::Filament);
    EXPECT_NEAR(filament->levels[1].texel(1, 0)[0], std::sqrt(0.36 + 2e-4), 1e-6);
    // Errors name the map.
    EXPECT_FALSE(bake_peer_roughness(Image(4, 4, 1), nullptr, 0.5f, PeerRoughnessBake::Godot));
}

TEST(PeerRoughnessBake, UnityHdrpAddsTwiceTheCappedVarianceToAlphaSquared) {
    const double t = 0.4;
    auto chain = bake_peer_roughness(checker(8, t), nullptr, 0.3f, PeerRoughnessBake::UnityHdrp);
    ASSERT_TRUE(chain) << chain.error().message;
    EXPECT_FLOAT_EQ(chain->levels[0].texel(2, 3)[0], 0.3f);  // level 0 as authored
    // var = 1 / (4 kappa) = 0.01913, under the 0.03125 cap; 2 var = 0.0383, under threshold^2 = 0.04.
    const double variance = 1.0 / (4.0 * kappa_of(std::cos(t)));
    for (int k = 1; k < 4; ++k)
        EXPECT_NEAR(chain->levels[size_t(k)].texel(0, 0)[0], std::pow(0.0081 + 2.0 * variance, 0.25), 2e-6) << k;
    // Steep: var = 1 / (4 kappa(cos 1.2)) = 0.30 is capped at 0.03125, and 2 x 0.03125 at 0.2^2.
    auto steep = bake_peer_roughness(checker(4, 1.2), nullptr, 0.3f, PeerRoughnessBake::UnityHdrp);
    EXPECT_NEAR(steep->levels[1].texel(1, 0)[0], std::pow(0.0081 + 0.04, 0.25), 2e-6);
}

TEST(PeerRoughnessBake, UnrealTakesTheUnnormalisedMeanAndWidensEveryLevel) {
    const double t = 0.4;
    // Unit normals whose 2x2 boxes average to (0, 0, cos t): L = cos t from level 1 on.
    auto chain = bake_peer_roughness(checker(8, t), nullptr, 0.3f, PeerRoughnessBake::Unreal);
    ASSERT_TRUE(chain) << chain.error().message;
    const auto toksvig = [](double length, double r) {
        const double v = std::max(0.0, (1 - length) / length - 4e-5), a = r * r * r * r, b = 2 * v * (a - 1);
        return std::pow((b - a) / (b - 1), 0.25);
    };
    EXPECT_NEAR(chain->levels[0].texel(1, 1)[0], 0.3, 2e-6);  // unit normals: variance 1e-7 - 4e-5 -> 0
    // var = (1 - cos t) / cos t - 4e-5 = 0.08566: a' = (B - a) / (B - 1) = 0.1522 with a = 0.0081, r' = 0.6246.
    EXPECT_NEAR(chain->levels[1].texel(0, 0)[0], toksvig(std::cos(t), 0.3), 2e-6);
    EXPECT_NEAR(chain->levels[1].texel(0, 0)[0], 0.6246, 1e-4);
    // A stored normal of length 0.8 (blue 0.9, not renormalised) widens level 0 as well: var = 0.25 - 4e-5.
    Image short_normals(2, 2, 3);
    for (size_t i = 0; i < short_normals.texel_count(); ++i)
        short_normals.pixels[3 * i] = short_normals.pixels[3 * i + 1] = 0.5f, short_normals.pixels[3 * i + 2] = 0.9f;
    auto shortened = bake_peer_roughness(short_normals, nullptr, 0.3f, PeerRoughnessBake::Unreal);
    ASSERT_TRUE(shortened);
    EXPECT_NEAR(shortened->levels[0].texel(0, 0)[0], toksvig(0.8, 0.3), 2e-6);
    // Filament normalises the same texels: nothing to widen at level 1 but its 2e-4 floor.
    auto filament = bake_peer_roughness(short_normals, nullptr, 0.3f, PeerRoughnessBake::Filament);
    EXPECT_NEAR(filament->levels[1].texel(0, 0)[0], std::sqrt(0.09 + 2e-4), 2e-6);
}

}  // namespace
}  // namespace specbake
