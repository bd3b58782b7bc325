// Simulator building blocks against independent computations: metrics on synthetic images, the ground
// truth's sample layout, the camera motion, and the built-in scenes' analytic geometry.
#include "verify/bench_job.h"
#include "verify/metrics.h"
#include "verify/renderer.h"
#include "verify/scene.h"

#include <gtest/gtest.h>

#include <array>

#include <cmath>
#include <numbers>

namespace specbake::verify {
namespace {

SimImage constant_image(int w, int h, float value, float coverage) {
    SimImage im(w, h, 2);
    for (size_t i = 0; i < im.texel_count(); ++i) {
        im.pixels[2 * i] = value;
        im.pixels[2 * i + 1] = coverage;
    }
    return im;
}

TEST(VerifyMetrics, ConstantOffsetGivesClosedFormErrors) {
    // Ground truth 1 everywhere, candidate 1.5: linear RMSE = MAE = 0.5 / mean(1); tone-mapped error
    // 1.5/2.5 - 1/2 = 0.1; no temporal change, so no flicker; energy ratio 1.5.
    SimMetricsAccumulator acc;
    for (int f = 0; f < 3; ++f) acc.add_frame(constant_image(4, 3, 1.0f, 1.0f), constant_image(4, 3, 1.5f, 1.0f));
    const SimMetrics m = acc.finish();
    EXPECT_NEAR(m.rmse, 0.5, 1e-9);
    EXPECT_NEAR(m.mae, 0.5, 1e-9);
    EXPECT_NEAR(m.rmse_tonemapped, 0.1, 1e-7);
    EXPECT_NEAR(m.mae_tonemapped, 0.1, 1e-7);
    EXPECT_NEAR(m.flicker, 0.0, 1e-9);
    EXPECT_NEAR(m.energy_ratio, 1.5, 1e-9);
    EXPECT_NEAR(m.peak_ratio, 1.5, 1e-6);
    EXPECT_EQ(m.pixels, 36);
}

TEST(VerifyMetrics, FlickerIsTheTemporalStandardDeviation) {
    // Candidate alternates between 0 and 1 over a ground truth of 0: tone-mapped error alternates 0 and 1/2,
    // population std over 4 frames = 1/4 at every pixel.
    SimMetricsAccumulator acc;
    for (int f = 0; f < 4; ++f)
        acc.add_frame(constant_image(2, 2, 0.0f, 1.0f), constant_image(2, 2, f % 2 ? 1.0f : 0.0f, 1.0f));
    EXPECT_NEAR(acc.finish().flicker, 0.25, 1e-9);
}

TEST(VerifyMetrics, TemporalErrorEqualsTheFlickerForAnAlternatingError) {
    // The alternating error above changes by 1/2 (tone-mapped) and 1 (linear) between every pair of frames:
    // sqrt(d^2 / 2) = 1/(2 sqrt 2) and 1/sqrt 2. A ground truth of 0 gives no normalisation: use g = 1 and
    // c alternating 1 and 2 (linear error 0, 1: flicker 1/2, temporal error 1/sqrt 2, both / mean(g) = 1).
    SimMetricsAccumulator acc;
    for (int f = 0; f < 4; ++f)
        acc.add_frame(constant_image(2, 2, 1.0f, 1.0f), constant_image(2, 2, f % 2 ? 2.0f : 1.0f, 1.0f));
    const SimMetrics m = acc.finish();
    EXPECT_NEAR(m.flicker_linear, 0.5, 1e-9);
    EXPECT_NEAR(m.temporal_error_linear, 1.0 / std::sqrt(2.0), 1e-9);
    EXPECT_NEAR(m.temporal_error, (2.0 / 3.0 - 0.5) / std::sqrt(2.0), 1e-7);
}

// A highlight (one bright pixel) at `centre` of a row over a dark surface.
SimImage highlight_row(int width, int centre, float peak) {
    SimImage im = constant_image(width, 1, 0.01f, 1.0f);
    im.texel(centre, 0)[0] += peak;
    return im;
}

TEST(VerifyMetrics, TemporalErrorOfAFrozenCandidateIsTheGroundTruthsOwnChange) {
    // A candidate that shows frame 0 in every frame: its error changes exactly as the ground truth does,
    // (c1 - c0) - (g1 - g0) = -(g1 - g0). With the highlight moving one pixel per frame over 6 pixels and
    // 4 frames, pixels 1 and 2 change by the peak in two of three pairs, pixels 0 and 3 in one.
    SimMetricsAccumulator acc;
    const SimImage first = highlight_row(6, 0, 1.0f);
    double sum_g = 0;
    for (int f = 0; f < 4; ++f) {
        const SimImage g = highlight_row(6, f, 1.0f);
        for (int x = 0; x < 6; ++x) sum_g += g.texel(x, 0)[0];
        acc.add_frame(g, first);
    }
    const double mean_g = sum_g / 24.0;
    const double expected = (2 * std::sqrt(1.0 / 6.0) + 2 * std::sqrt(2.0 / 6.0)) / 6.0 / mean_g;
    EXPECT_NEAR(acc.finish().temporal_error_linear, expected, 1e-6);
}

TEST(VerifyMetrics, TemporalErrorScoresPixelsTheObjectLeaves) {
    // Pixel 1 carries the error and is covered in frames 0-2 but not in frame 3: the flicker, which keeps
    // only pixels scored in every frame, does not see it; the temporal error scores its two frame pairs.
    SimMetricsAccumulator acc;
    for (int f = 0; f < 4; ++f) {
        SimImage g = constant_image(2, 1, 1.0f, 1.0f), c = constant_image(2, 1, 1.0f, 1.0f);
        c.texel(1, 0)[0] = f % 2 ? 3.0f : 1.0f;
        if (f == 3) g.texel(1, 0)[1] = 0.0f;
        acc.add_frame(g, c);
    }
    const SimMetrics m = acc.finish();
    EXPECT_NEAR(m.flicker_linear, 0.0, 1e-12);
    // Pixel 0: no change; pixel 1: changes of 2 in both pairs -> sqrt(8 / 4) = sqrt 2; mean over 2 pixels.
    EXPECT_NEAR(m.temporal_error_linear, std::sqrt(2.0) / 2.0, 1e-9);
}

TEST(VerifyMetrics, PartiallyCoveredPixelsAreNotScored) {
    SimImage gt = constant_image(2, 1, 1.0f, 1.0f);
    SimImage c = constant_image(2, 1, 1.0f, 1.0f);
    gt.texel(1, 0)[1] = 0.5f;  // silhouette pixel in the ground truth
    c.texel(1, 0)[0] = 100.0f;
    SimMetricsAccumulator acc;
    acc.add_frame(gt, c);
    const SimMetrics m = acc.finish();
    EXPECT_EQ(m.pixels, 1);
    EXPECT_NEAR(m.rmse, 0.0, 1e-12);
}

TEST(VerifyMetrics, EmptyMaskGivesZeroPixels) {
    SimMetricsAccumulator acc;
    acc.add_frame(constant_image(2, 2, 1.0f, 0.0f), constant_image(2, 2, 1.0f, 1.0f));
    EXPECT_EQ(acc.finish().pixels, 0);
}

TEST(VerifyGroundTruth, SampleLayoutCoversTheRequestedCount) {
    EXPECT_EQ(ground_truth_layout(256, 128, 128).samples(), 256);
    EXPECT_EQ(ground_truth_layout(256, 128, 128).scale, 16);
    EXPECT_EQ(ground_truth_layout(1, 64, 64).samples(), 1);
    EXPECT_EQ(ground_truth_layout(9, 64, 64).samples(), 9);   // 3 per axis: scale 3, one pass
    EXPECT_EQ(ground_truth_layout(25, 64, 64).samples(), 25);  // 5 per axis: scale 5, one pass
    // Large images keep the supersampled target within 8192 texels.
    EXPECT_LE(ground_truth_layout(256, 4096, 4096).scale * 4096, 8192);
    EXPECT_EQ(ground_truth_layout(256, 4096, 4096).samples(), 256);
}

TEST(VerifyScenes, CameraOrbitMovesAboutTheRequestedPixels) {
    auto scene = make_builtin_scene("sphere", 0.3f);
    ASSERT_TRUE(scene.ok());
    const int height = 128;
    const SimCamera a = camera_at_frame(*scene, 0, height), b = camera_at_frame(*scene, 1, height);
    // Orbiting by an angle moves the sphere's front point (radius 1 from the target) sideways by angle * 1
    // world units relative to the view axis; in pixels at its distance d - 1, whose pixel size is
    // 2 (d - 1) tan(fov/2) / height.
    const double d = std::hypot(a.position[0], a.position[1], a.position[2]);
    const double cosang = (a.position[0] * b.position[0] + a.position[1] * b.position[1] + a.position[2] * b.position[2]) /
                          (d * d);
    const double angle = std::acos(std::min(1.0, cosang));
    const double pixel = 2.0 * (d - 1.0) * std::tan(20.0 * std::numbers::pi / 180.0) / height;
    const double moved = angle * 1.0 / pixel;
    EXPECT_GT(moved, 0.1);
    EXPECT_LT(moved, 1.0);  // sub-pixel motion
    EXPECT_EQ(camera_at_frame(*scene, 0, height).position, scene->camera.position);
}

TEST(VerifyScenes, AnalyticGeometryIsConsistent) {
    for (auto name : builtin_scene_names()) {
        auto scene = make_builtin_scene(name, 0.3f);
        ASSERT_TRUE(scene.ok()) << name;
        for (const SimObject& o : scene->objects) {
            const TriMesh& m = o.mesh;
            ASSERT_TRUE(m.has_normals() && m.has_tangents() && m.has_uv0()) << name;
            ASSERT_EQ(o.exact_curvature.values.size(), 4 * m.vertex_count());
            for (size_t v = 0; v < m.vertex_count(); v += 97) {
                const float* n = &m.normals[3 * v];
                const float* t = &m.tangents[4 * v];
                EXPECT_NEAR(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0, 1e-5) << name;
                EXPECT_NEAR(n[0] * t[0] + n[1] * t[1] + n[2] * t[2], 0.0, 1e-5) << name;
                const float* k = &o.exact_curvature.values[4 * v];
                EXPECT_GE(std::abs(k[0]), std::abs(k[1]) - 1e-6f) << name;  // |k1| >= |k2|
            }
        }
    }
    // Sphere of radius 1: every vertex at distance 1 with curvature +1 (SPEC Sec. 4 sign convention).
    auto sphere = make_builtin_scene("sphere", 0.3f);
    const SimObject& s = sphere->objects[0];
    for (size_t v = 0; v < s.mesh.vertex_count(); v += 31) {
        const float* p = &s.mesh.positions[3 * v];
        EXPECT_NEAR(std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]), 1.0, 1e-5);
        EXPECT_FLOAT_EQ(s.exact_curvature.values[4 * v], 1.0f);
    }
    EXPECT_FALSE(make_builtin_scene("teapot", 0.3f).ok());
    EXPECT_FALSE(make_builtin_scene("sphere", 1.5f).ok());
}


// The bench's do-no-harm table names, per scene, every measure whose ratio to no filtering exceeds its goal
// (RMSE 1.02x, the others 1.00x), gives the default's energy and the floor's ratios, and counts the scenes
// that hold. Ratios computed by hand from the rows below.
TEST(VerifyBenchSummary, DoNoHarmTableNamesEveryFailingMeasureWithItsFloor) {
    const auto row = [](const char* name, double rmse, double flicker_linear, double flicker, double terr_linear,
                        double terr, double energy) {
        CandidateReport c;
        c.name = c.family = name;
        c.metrics.rmse = rmse;
        c.metrics.flicker_linear = flicker_linear;
        c.metrics.flicker = flicker;
        c.metrics.temporal_error_linear = terr_linear;
        c.metrics.temporal_error = terr;
        c.metrics.energy_ratio = energy;
        return c;
    };
    BenchReport report;
    SceneReport harmed;
    harmed.scene = "lamp@far";
    harmed.from_file = true;
    harmed.candidates = {row("none", 1.0, 0.2, 0.1, 0.4, 0.01, 1.3), row("default", 1.021, 0.1, 0.11, 0.2, 0.0125, 0.8),
                         row("floor", 0.05, 0.02, 0.01, 0.1, 0.004, 1.0)};
    SceneReport holding;
    holding.scene = "box@near";
    holding.from_file = true;
    holding.candidates = {row("none", 2.0, 0.2, 0.1, 0.4, 0.02, 1.0), row("default", 1.0, 0.1, 0.05, 0.2, 0.02, 1.0)};
    report.scenes = {harmed, holding};
    const std::string md = bench_summary_markdown(report);
    EXPECT_NE(md.find("| lamp@far | 1.021 | 0.500 | 1.100 | 0.500 | 1.250 | 0.80 | **RMSE, flicker (tm), t-err (tm)** "
                      "| 0.050 | 0.100 | 0.100 | 0.250 | 0.400 |"),
              std::string::npos)
        << md;
    EXPECT_NE(md.find("| box@near | 0.500 | 0.500 | 0.500 | 0.500 | 1.000 | 1.00 | holds | - | - | - | - | - |"),
              std::string::npos)
        << md;
    EXPECT_NE(md.find("The default holds on 1 of 2 scenes."), std::string::npos) << md;
}

// Each engine's row is held against specbake's row of equal or lower cost on the scenes both ran on; where
// no specbake row is that cheap on all of them, against the cheapest (its extra SPIR-V in brackets).
// Geometric means and do-no-harm counts computed by hand from the rows below.
TEST(VerifyBenchSummary, EnginesAreHeldAgainstTheTierOfEqualOrLowerCost) {
    const auto row = [](const char* name, const char* family, int spirv, std::array<double, 6> m) {
        CandidateReport c;
        c.name = name;
        c.family = family;
        c.spirv_instructions = spirv;
        c.metrics.rmse = m[0];
        c.metrics.rmse_tonemapped = m[1];
        c.metrics.flicker_linear = m[2];
        c.metrics.flicker = m[3];
        c.metrics.temporal_error_linear = m[4];
        c.metrics.temporal_error = m[5];
        return c;
    };
    SceneReport plain;  // no normal map: no baked rows
    plain.scene = "sphere";
    plain.candidates = {row("none", "none", 254, {1, 1, 1, 1, 1, 1}),
                        row("godot", "peer", 266, {0.5, 1.2, 0.8, 1.1, 0.9, 1.05}),
                        row("fast", "tier", 363, {0.4, 0.8, 0.7, 0.9, 0.8, 0.95}),
                        row("default", "default", 877, {0.3, 0.5, 0.5, 0.5, 0.5, 0.5})};
    SceneReport mapped;
    mapped.scene = "tiles";
    mapped.from_file = true;
    mapped.candidates = {row("none", "none", 254, {2, 2, 2, 2, 2, 2}),
                         row("godot", "peer", 266, {2, 2, 2, 2, 2, 2}),
                         row("filament-prefilter", "peer", 269, {4, 4, 4, 4, 4, 4}),
                         row("baked-texture", "baked", 269, {1, 1, 1, 1, 1, 1}),
                         row("fast", "tier", 363, {0.5, 1, 1, 1, 1, 1}),
                         row("default", "default", 877, {0.5, 0.5, 0.5, 0.5, 0.5, 0.5})};
    BenchReport report;
    report.scenes = {plain, mapped};
    const std::string md = bench_summary_markdown(report);
    // godot: sqrt(0.5 x 1), sqrt(1.2 x 1), ...; fast: sqrt(0.4 x 0.25), sqrt(0.8 x 0.5), ...; godot fails
    // flicker (tm) on the sphere, fast holds both.
    EXPECT_NE(md.find("| godot | 266 | fast | 363 (+97) | 2 | 0.707 / 0.316 | 1.095 / 0.632 | 0.894 / 0.592 | "
                      "1.049 / 0.671 | 0.949 / 0.632 | 1.025 / 0.689 | 1 / 2 | 6 of 6 |"),
              std::string::npos)
        << md;
    // The engine's offline bake against the baked roughness alone, at the same cost, on the one mapped scene.
    EXPECT_NE(md.find("| filament-prefilter | 269 | baked-texture | 269 | 1 | 2.000 / 0.500 | 2.000 / 0.500 | "
                      "2.000 / 0.500 | 2.000 / 0.500 | 2.000 / 0.500 | 2.000 / 0.500 | 0 / 1 | 6 of 6 |"),
              std::string::npos)
        << md;
}

// The plot draws every aggregated row at its SPIR-V count, the tiers in their own colour beside the peers.
TEST(VerifyBenchSummary, PlotDrawsTiersAndPeersInTheirColours) {
    const auto row = [](const char* name, const char* family, int spirv, double rmse) {
        CandidateReport c;
        c.name = name;
        c.family = family;
        c.spirv_instructions = spirv;
        c.metrics.rmse = c.metrics.rmse_tonemapped = rmse;
        c.metrics.flicker_linear = c.metrics.flicker = 1.0;
        return c;
    };
    SceneReport s;
    s.scene = "sphere";
    s.candidates = {row("none", "none", 254, 1.0), row("godot", "peer", 266, 0.8), row("fast", "tier", 363, 0.5)};
    BenchReport report;
    report.scenes = {s};
    const std::string svg = bench_svg(report);
    EXPECT_NE(svg.find("fill=\"#e377c2\">fast</text>"), std::string::npos) << svg;
    EXPECT_NE(svg.find("fill=\"#d62728\">godot</text>"), std::string::npos) << svg;
    EXPECT_NE(svg.find("pink tiers"), std::string::npos) << svg;
}

// Twelve rows that land on almost the same spot of both panels (the engines' run-time filters do, at
// 264-272 instructions and 0.6-1.1x): every label is drawn, none overlaps another label or a dot, each
// stays inside the canvas, and a label moved off its dot is tied to it by a line. Text boxes are bounded
// here by 6.5 px a character at the plot's 10 px font (wider than any glyph's advance in common sans
// fonts but W and M), not by the plot's own figure.
TEST(VerifyBenchSummary, PlotLabelsOfACrowdedClusterDoNotOverlap) {
    SceneReport s;
    s.scene = "sphere";
    const auto row = [](std::string name, const char* family, int spirv, double v) {
        CandidateReport c;
        c.name = std::move(name);
        c.family = family;
        c.spirv_instructions = spirv;
        c.metrics.rmse = c.metrics.rmse_tonemapped = v;
        c.metrics.flicker_linear = c.metrics.flicker = v;
        return c;
    };
    s.candidates.push_back(row("none", "none", 254, 1.0));
    const char* names[] = {"filament", "godot", "unity-hdrp", "threejs", "babylon", "filament-prefilter",
                           "godot-importer", "unity-hdrp-nf", "unreal-toksvig", "baked-texture", "fast", "limit"};
    for (int i = 0; i < 12; ++i) s.candidates.push_back(row(names[i], "peer", 264 + i % 4, 0.80 + 0.01 * (i % 5)));
    BenchReport report;
    report.scenes = {s};
    const std::string svg = bench_svg(report);
    struct Box {
        double l, t, r, b;
        std::string text;
    };
    std::vector<Box> texts, dots;
    std::vector<std::array<double, 4>> lines;
    const auto attr = [](const std::string& el, const std::string& name) {
        const size_t at = el.find(" " + name + "=\"");
        return at == std::string::npos ? NAN : std::stod(el.substr(at + name.size() + 3));
    };
    for (size_t at = svg.find('<'); at != std::string::npos; at = svg.find('<', at + 1)) {
        const size_t end = svg.find('>', at);
        const std::string el = svg.substr(at, end - at);
        if (el.rfind("<circle", 0) == 0) {
            const double x = attr(el, "cx"), y = attr(el, "cy");
            dots.push_back({x - 3.5, y - 3.5, x + 3.5, y + 3.5, ""});
        } else if (el.rfind("<line", 0) == 0 && el.find("stroke-width=\"0.5\"") != std::string::npos) {
            lines.push_back({attr(el, "x1"), attr(el, "y1"), attr(el, "x2"), attr(el, "y2")});
        } else if (el.rfind("<text", 0) == 0 && el.find("text-anchor") == std::string::npos &&
                   el.find("font-size") == std::string::npos) {
            const std::string text = svg.substr(end + 1, svg.find('<', end) - end - 1);
            if (text.find(' ') != std::string::npos) continue;  // the captions below the panels
            const double x = attr(el, "x"), y = attr(el, "y");
            texts.push_back({x, y - 8, x + 6.5 * double(text.size()), y + 1, text});
        }
    }
    ASSERT_EQ(texts.size(), 2u * 13u) << svg;  // every row's label in both panels
    ASSERT_EQ(dots.size(), 2u * 13u);
    const auto overlap = [](const Box& a, const Box& b) {
        return a.l < b.r && b.l < a.r && a.t < b.b && b.t < a.b;
    };
    for (size_t i = 0; i < texts.size(); ++i) {
        EXPECT_GE(texts[i].l, 0.0) << texts[i].text;
        EXPECT_LE(texts[i].r, 1030.0) << texts[i].text;
        for (size_t j = i + 1; j < texts.size(); ++j)
            EXPECT_FALSE(overlap(texts[i], texts[j])) << texts[i].text << " and " << texts[j].text << "\n" << svg;
        for (const Box& d : dots) EXPECT_FALSE(overlap(texts[i], d)) << texts[i].text << "\n" << svg;
    }
    // A label away from its dot has a line from the dot: some labels in the cluster must have moved.
    EXPECT_GE(lines.size(), 4u) << svg;
}

}  // namespace
}  // namespace specbake::verify
