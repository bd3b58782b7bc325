// The simulator's Filament peer (bake/peer_roughness_bake.h) against Filament's own roughness-prefilter
// (Debian 12's libfilament-tools, Filament 1.9.25) on a generated normal map: the same box of level-0
// normals, decode and kappa, with that build's 1 / (2 kappa) in place of the current 2 / kappa
// (PeerRoughnessBake::FilamentDebian). Levels 0 and 1 agree to the 8-bit step; from level 2 on that build
// widens some texels less than the 2^k box this bake averages (on this map 33 of 85 texels of levels 2-5,
// by up to 14/255), which no shifted box reproduces: the difference is printed, not asserted, and
// docs/accuracy.md#engine-peers states it. Skips with a message where the binary is not installed.
#include "bake/peer_roughness_bake.h"
#include "scene_test_util.h"

#include <OpenImageIO/imageio.h>

#include <gtest/gtest.h>

#include <cmath>

namespace {

using namespace scene_test;

TEST(PeerBakeBinary, FilamentFormulaMatchesRoughnessPrefilter) {
    if (std::system("command -v roughness-prefilter > /dev/null 2>&1") != 0)
        GTEST_SKIP() << "roughness-prefilter (Debian package libfilament-tools) not installed";
    const fs::path dir = temp_dir("peer_bake_binary");
    // 32 x 32 bumps of several frequencies, 8-bit RGB with the stored blue channel.
    const int n = 32;
    std::vector<uint8_t> pixels(size_t(n) * n * 3);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const double sx = 0.8 * std::sin(2 * M_PI * x * 3 / n) + 0.3 * std::sin(2 * M_PI * (x + 2 * y) * 5 / n);
            const double sy = 0.5 * std::cos(2 * M_PI * y * 2 / n);
            const double len = std::sqrt(sx * sx + sy * sy + 1.0);
            const double v[3] = {-sx / len, -sy / len, 1.0 / len};
            for (int c = 0; c < 3; ++c) pixels[(size_t(y) * n + x) * 3 + c] = uint8_t(std::lround((v[c] * 0.5 + 0.5) * 255));
        }
    const fs::path in = dir / "n.png";
    auto out = OIIO::ImageOutput::create(in.string());
    ASSERT_TRUE(out && out->open(in.string(), OIIO::ImageSpec(n, n, 3, OIIO::TypeDesc::UINT8)));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, pixels.data()));
    out->close();
    const std::string cmd = "cd '" + dir.string() + "' && roughness-prefilter -r 0.3 -f png n.png r.png > log.txt 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << slurp(dir / "log.txt");

    specbake::Image normal(n, n, 3);
    for (size_t i = 0; i < pixels.size(); ++i) normal.pixels[i] = float(pixels[i]) / 255.0f;
    auto chain = specbake::bake_peer_roughness(normal, nullptr, 0.3f, specbake::PeerRoughnessBake::FilamentDebian);
    ASSERT_TRUE(chain) << chain.error().message;
    ASSERT_EQ(chain->levels.size(), 6u);
    int compared = 0, widened = 0, deeper_differ = 0;
    double deeper_max = 0;
    for (size_t k = 0; k < chain->levels.size(); ++k) {
        const fs::path level = dir / ("r_" + std::to_string(k) + ".png");
        auto input = OIIO::ImageInput::open(level.string());
        ASSERT_TRUE(input) << level << ": " << OIIO::geterror();
        const OIIO::ImageSpec spec = input->spec();
        ASSERT_EQ(spec.width, chain->levels[k].width) << level;
        std::vector<uint8_t> theirs(size_t(spec.width) * spec.height * spec.nchannels);
        ASSERT_TRUE(input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT8, theirs.data()));
        input->close();
        for (int y = 0; y < spec.height; ++y)
            for (int x = 0; x < spec.width; ++x) {
                const double mine = 255.0 * chain->levels[k].texel(x, y)[0];
                const int value = theirs[(size_t(y) * spec.width + x) * size_t(spec.nchannels)];
                if (k <= 1) {
                    EXPECT_LE(std::abs(mine - value), 1.0) << "level " << k << " texel " << x << "," << y << ": " << mine
                                                           << " against " << value;
                    ++compared;
                } else if (std::abs(mine - value) > 1.0) {
                    ++deeper_differ;
                    deeper_max = std::max(deeper_max, std::abs(mine - value));
                }
                if (k == 1 && value > 77) ++widened;  // above 0.3
            }
    }
    EXPECT_EQ(compared, 32 * 32 + 16 * 16);
    std::printf("levels 2-5: %d of 85 texels differ by more than one 8-bit step (at most %.1f)\n", deeper_differ, deeper_max);
    EXPECT_GT(widened, 100);  // the map's spread does widen level 1
    fs::remove_all(dir);
}

}  // namespace
