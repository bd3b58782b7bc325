// The verify strip: which candidates it shows (ranks computed here by hand) and where each tile, error map
// and harm cell lands, pixel for pixel against values this test computes from the definitions (crop to the
// object with 4 pixels of margin, magnification to about 320 pixels, T(x) = x / (1 + x) at the ground
// truth's 99th percentile, sRGB encoding, the heat ramp).
#include "verify/strips.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace specbake::verify {
namespace {

CandidateReport candidate(const std::string& name, const std::string& family, double rmse, double flicker) {
    CandidateReport c;
    c.name = name;
    c.family = family;
    c.metrics.rmse = rmse;
    c.metrics.flicker = flicker;
    c.metrics.temporal_error = flicker;
    c.image = SimImage(4, 4, 2);
    return c;
}

std::vector<std::string> labels(const std::vector<StripTile>& tiles) {
    std::vector<std::string> out;
    for (const StripTile& t : tiles) out.push_back(t.label);
    return out;
}

TEST(VerifyStrip, ShowsNoFilteringTheDefaultItsVariantsAndTheBestThreeByRankSum) {
    std::vector<CandidateReport> c;
    c.push_back(candidate("none", "none", 1.0, 1.0));
    c.push_back(candidate("default", "default", 0.4, 0.5));
    c.push_back(candidate("limit", "limit", 0.01, 0.01));   // a reference row, never a candidate
    c.push_back(candidate("floor", "floor", 0.01, 0.01));
    c.push_back(candidate("a", "derivative", 0.2, 0.9));    // RMSE rank 0, flicker rank 4: sum 4
    c.push_back(candidate("b", "derivative", 0.3, 0.3));    // 1 + 1 = 2
    c.push_back(candidate("c", "peer", 0.5, 0.2));          // 3 + 0 = 3
    c.push_back(candidate("d", "peer", 0.6, 0.6));          // 4 + 3 = 7
    c.push_back(candidate("e", "variant", 0.45, 0.35));     // 2 + 2 = 4, after a in report order
    c.push_back(candidate("default:nopix", "default", 0.9, 0.9));
    c.push_back(candidate("glint-c20", "glint", 1.0, 1.0));
    c.push_back(candidate("glint-ggaa", "glint", 0.5, 0.5));
    c.push_back(candidate("empty", "derivative", 0.0, 0.0));
    c.back().image = SimImage();  // no image kept: never shown

    EXPECT_EQ(labels(strip_tiles(c, false)),
              (std::vector<std::string>{"none", "default", "default:nopix", "b", "c", "a"}));
    EXPECT_EQ(labels(strip_tiles(c, false, 1)), (std::vector<std::string>{"none", "default", "default:nopix", "b"}));
    EXPECT_EQ(labels(strip_tiles(c, true)), (std::vector<std::string>{"glint-c20", "glint-ggaa"}));
    EXPECT_EQ(strip_tiles(c, false, 0, true).size(), 10u);  // every GGX candidate with an image, rows included
    // Captions: ratios to no filtering's RMSE, tone-mapped flicker and temporal error.
    const auto tiles = strip_tiles(c, false);
    EXPECT_EQ(tiles[0].caption, "");
    EXPECT_EQ(tiles[1].caption, "rmse 0.40x flicker 0.50x t-err 0.50x");
}

float srgb(float x) {
    x = std::clamp(x, 0.0f, 1.0f);
    return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

TEST(VerifyStrip, GridCropsToTheObjectAndPlacesRendersErrorsAndTheHarmCell) {
    // 40 x 30 render; the object covers x 10..15, y 5..9, radiance 2 except one pixel of 8 at (12, 7).
    const int W = 40, H = 30;
    SimImage gt(W, H, 2);
    for (int y = 5; y <= 9; ++y)
        for (int x = 10; x <= 15; ++x) gt.texel(x, y)[0] = 2.0f, gt.texel(x, y)[1] = 1.0f;
    gt.texel(12, 7)[0] = 8.0f;
    SimImage same = gt, brighter = gt;
    brighter.texel(13, 8)[0] = 4.0f;
    std::vector<float> base(size_t(W) * H, 1.0f), mine(size_t(W) * H, 1.0f);
    mine[size_t(6) * W + 11] = 2.0f;  // more temporal error than the baseline at (11, 6)
    mine[size_t(8) * W + 14] = 0.0f;  // less at (14, 8)
    const StripHarm harm{"default - none", &mine, &base};
    const Image strip = make_strip(gt, {{"same", &same, ""}, {"brighter", &brighter, ""}}, &harm);

    // Crop x 6..19, y 1..13 (14 x 13); zoom min(12, 320 / 14) = 12: tiles 168 x 156 pixels. Cells are
    // max(168, 40 characters of 8 pixels) + 6 = 326 wide and 30 (two label lines) + 2 x 156 + 12 = 354 high;
    // four cells in one row.
    ASSERT_EQ(strip.width, 4 * 326);
    ASSERT_EQ(strip.height, 354);
    const int label = 30, tile = 156, cell_w = 326;
    // The ground truth's 99th percentile over the 30 covered pixels: sorted, index floor(0.99 x 29) = 28, so 2.
    const auto tone = [](float x) { return srgb((x / 2.0f) / (1.0f + x / 2.0f)); };
    const auto at = [&](int cell, int px, int py, bool error_row) {
        // Centre of render pixel (px, py)'s 12 x 12 block.
        const int x = cell * cell_w + (px - 6) * 12 + 6;
        const int y = label + (error_row ? tile + 6 : 0) + (py - 1) * 12 + 6;
        return strip.texel(x, y);
    };
    EXPECT_NEAR(at(0, 12, 7, false)[0], tone(8.0f), 1e-6);
    EXPECT_NEAR(at(0, 11, 7, false)[0], tone(2.0f), 1e-6);
    EXPECT_NEAR(at(0, 6, 1, false)[0], 0.0f, 1e-6);
    EXPECT_NEAR(at(1, 12, 7, false)[1], tone(8.0f), 1e-6);
    // Error maps: none for the identical render; 4 |T(4/2) - T(2/2)| = 4 (2/3 - 1/2) = 2/3 for the
    // brighter pixel: the ramp's red 1, green 3 x 2/3 - 1 = 1, blue 0 (yellow).
    for (int py = 1; py <= 13; ++py)
        for (int px = 6; px <= 19; ++px) ASSERT_EQ(at(1, px, py, true)[0], 0.0f) << px << "," << py;
    EXPECT_NEAR(at(2, 13, 8, true)[0], 1.0f, 1e-5);
    EXPECT_NEAR(at(2, 13, 8, true)[1], 1.0f, 1e-5);
    EXPECT_NEAR(at(2, 13, 8, true)[2], 0.0f, 1e-5);
    EXPECT_NEAR(at(2, 12, 8, true)[0], 0.0f, 1e-6);
    // Harm cell: over 0.3 x the ground truth's display value, red by (2 - 1) / (2 x mean 1) = 0.5 of the
    // rest at (11, 6), blue by 0.5 at (14, 8), grey where equal.
    const float g = 0.3f * tone(2.0f);
    EXPECT_NEAR(at(3, 11, 6, false)[0], g + 0.5f * (1.0f - g), 1e-5);
    EXPECT_NEAR(at(3, 11, 6, false)[2], g, 1e-5);
    EXPECT_NEAR(at(3, 14, 8, false)[2], g + 0.5f * (1.0f - g), 1e-5);
    EXPECT_NEAR(at(3, 14, 8, false)[0], g, 1e-5);
    EXPECT_NEAR(at(3, 10, 5, false)[1], g, 1e-5);

    // Without the harm maps (or with maps of another size) there is no harm cell.
    std::vector<float> wrong(7, 1.0f);
    const StripHarm mismatched{"x", &wrong, &base};
    EXPECT_EQ(make_strip(gt, {{"same", &same, ""}}, &mismatched).width, 2 * 326);
    EXPECT_EQ(make_strip(gt, {{"same", &same, ""}}).width, 2 * 326);
    // Five cells wrap onto a second row.
    const Image five = make_strip(gt, {{"a", &same, ""}, {"b", &same, ""}, {"c", &same, ""}, {"d", &same, ""}});
    EXPECT_EQ(five.width, 4 * 326);
    EXPECT_EQ(five.height, 2 * 354);
}

}  // namespace
}  // namespace specbake::verify
