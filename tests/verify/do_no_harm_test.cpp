// Do no harm (issue 15, item 4): at the bench's far distance, where the object covers few pixels and
// normal-map aliasing is strongest, the default rule's error must not exceed no filtering's, on shared
// sample models (skipped when ../shared/assets is absent) and on the project's own normal-mapped scene.
#include "sim_test_environment.h"

#include "verify/bench_job.h"
#include "verify/scene_file.h"

#include <gtest/gtest.h>

#include <filesystem>

namespace specbake::verify {
namespace {

namespace fs = std::filesystem;

// The bench's factor of distance `label` ("near", "far"), so the test pins the distance the bench reports.
float distance_factor(const std::string& label) {
    for (const auto& [name, factor] : BenchOptions{}.distances)
        if (name == label) return factor;
    ADD_FAILURE() << "BenchOptions has no " << label << " distance";
    return 1.0f;
}

// The metrics of candidate `name` in `report`, or null.
const SimMetrics* metrics_of(const SceneReport& report, const std::string& name) {
    for (const CandidateReport& c : report.candidates)
        if (c.name == name) return &c.metrics;
    return nullptr;
}

// `distance`: a bench distance label, or empty for the scene's own framing (the analytic scenes' bench view).
void expect_default_no_worse(const SimScene& scene, int size = 64, bool tone_mapped = false,
                             const std::string& distance = "far", int spp = 64, int frames = 3) {
    VerifyOptions options = test::small_verify(size, size, spp, frames);
    options.only = {"default"};
    auto report = run_verify(distance.empty() ? scene : at_distance(scene, distance, distance_factor(distance)), options);
    ASSERT_TRUE(report.ok()) << report.error().message;
    const SimMetrics* none = metrics_of(*report, "none");
    const SimMetrics* def = metrics_of(*report, "default");
    ASSERT_TRUE(none && def);
    ASSERT_GT(none->pixels, 0) << scene.name << ": no pixel scored at the " << (distance.empty() ? "bench" : distance) << " distance";
    EXPECT_LE(def->rmse, none->rmse) << scene.name;
    EXPECT_LE(def->flicker_linear, none->flicker_linear) << scene.name;
    // The temporal error (frame pairs, so pixels the object enters or leaves count too) as well.
    EXPECT_LE(def->temporal_error_linear, none->temporal_error_linear) << scene.name;
    // Tone-mapped flicker and temporal error, where the default NDF is GGX convolved with the footprint
    // (no baked normal-map data): the over-bright tails of GGX(A) around a highlight used to raise them.
    if (tone_mapped) {
        EXPECT_LE(def->flicker, none->flicker) << scene.name;
        EXPECT_LE(def->temporal_error, none->temporal_error) << scene.name;
    }
}

// Settings of the field models' checks (the issue's: 256x256, 256 spp, 8 frames).
constexpr int kFieldSize = 256, kFieldSpp = 256, kFieldFrames = 8;

void shared_model(const char* name, int size = 64, bool tone_mapped = false, const std::string& distance = "far",
                  int spp = 64, int frames = 3) {
    const fs::path file = fs::path(SPECBAKE_ASSETS_DIR) / "gltf" / name / (std::string(name) + ".gltf");
    if (!fs::exists(file)) GTEST_SKIP() << file << " not found: shared assets absent, do-no-harm not checked on it";
    auto scene = load_sim_scene(file);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    expect_default_no_worse(*scene, size, tone_mapped, distance, spp, frames);
}

TEST(VerifyDoNoHarm, DefaultNoWorseThanNoneOnSuzanneFar) {
    SPECBAKE_REQUIRE_GL();
    shared_model("Suzanne", 64, true);
}

TEST(VerifyDoNoHarm, DefaultNoWorseThanNoneOnSheenClothFar) {
    SPECBAKE_REQUIRE_GL();
    shared_model("SheenCloth");
}

// ORM + normal map (the case where filtering lost against a point-sampled ground truth). Its tiles need
// 128 pixels at the far distance for pixels the pixel filter sees fully covered.
TEST(VerifyDoNoHarm, DefaultNoWorseThanNoneOnNormalTangentTestFar) {
    SPECBAKE_REQUIRE_GL();
    shared_model("NormalTangentTest", 128);
}

TEST(VerifyDoNoHarm, DefaultNoWorseThanNoneOnTheNormalMappedSphereFar) {
    SPECBAKE_REQUIRE_GL();
    for (float alpha : {0.01f, 0.05f}) {
        auto scene = make_builtin_scene("bumpy-sphere", std::sqrt(alpha));
        ASSERT_TRUE(scene.ok());
        expect_default_no_worse(*scene);
    }
}

// Smooth curved mirrors at the bench's own framing of the analytic scenes, the case the tone-mapped metrics
// failed on (sphere 3.8x, torus 2.9x no filtering's tone-mapped flicker at alpha 0.01 with GGX(A)).
TEST(VerifyDoNoHarm, DefaultNoWorseThanNoneOnSmoothCurvedMirrorsToneMapped) {
    SPECBAKE_REQUIRE_GL();
    for (const char* name : {"sphere", "torus"})
        for (float alpha : {0.01f, 0.05f}) {
            auto scene = make_builtin_scene(name, std::sqrt(alpha));
            ASSERT_TRUE(scene.ok());
            expect_default_no_worse(*scene, 64, true, "");
        }
}

// The per-pixel kernel is the spread of the half vector relative to the normal over the footprint: on a
// smooth sphere the normal turns one way across the pixel and the direction to the eye the other, and both
// move the highlight (specaa_view_turn_axis). The ground truth integrates the pixel, so it sees both; a kernel
// of the normal's turn alone (SPECAA_NO_VIEW_TURN) leaves the highlight too narrow: at 64x64, 64 spp,
// 3 frames its RMSE is 0.14x / 0.27x no filtering's at alpha 0.01 / 0.05 against the default's 0.020x / 0.035x.
TEST(VerifyAccuracy, DefaultKernelFollowsTheHalfVectorNotTheNormalAlone) {
    SPECBAKE_REQUIRE_GL();
    for (float alpha : {0.01f, 0.05f}) {
        auto scene = make_builtin_scene("sphere", std::sqrt(alpha));
        ASSERT_TRUE(scene.ok());
        VerifyOptions options = test::small_verify(64, 64, 64, 3);
        options.only = {"default"};
        options.default_variants = {{"noturn", "#define SPECAA_NO_VIEW_TURN\n"}};
        auto report = run_verify(*scene, options);
        ASSERT_TRUE(report.ok()) << report.error().message;
        const SimMetrics* none = metrics_of(*report, "none");
        const SimMetrics* def = metrics_of(*report, "default");
        const SimMetrics* noturn = metrics_of(*report, "default:noturn");
        ASSERT_TRUE(none && def && noturn);
        EXPECT_LT(def->rmse, 0.06 * none->rmse) << "alpha " << alpha;
        EXPECT_GT(noturn->rmse, 0.1 * none->rmse) << "alpha " << alpha << ": the normal's turn alone fits too: the test pins nothing";
        EXPECT_LT(def->flicker_linear, noturn->flicker_linear) << "alpha " << alpha;
    }
}

// A rough smooth sphere (alpha 0.2): the footprint changes its lobe by a fraction of a percent, less than the
// error the convolution's quadrature had in the tails before it cancelled that error against the same
// quadrature of GGX(a) (bake/ggx.cpp convolved_ndf). With the plain sum the tails near the silhouette came
// out over-bright and moved with the image: at 128x128, 64 spp, 4 frames 1.075x no filtering's tone-mapped
// flicker and 1.064x its temporal error (fails here); now 0.93x and 0.99x.
TEST(VerifyDoNoHarm, DefaultNoWorseThanNoneOnARoughSphereToneMapped) {
    SPECBAKE_REQUIRE_GL();
    auto scene = make_builtin_scene("sphere", std::sqrt(0.2f));
    ASSERT_TRUE(scene.ok());
    expect_default_no_worse(*scene, 128, true, "", 64, 4);
}

// The normal-mapped sphere at the bench's framing, tone-mapped: its bump map's slopes are a sum of many
// waves, a Gaussian-like spread the convolution models and GGX(A)'s tails over-brighten. At 128x128,
// 256 spp, 4 frames the earlier rule (GGX(A) on the baked roughness, `default-roughness`) gives 1.23x no
// filtering's tone-mapped flicker at alpha 0.01 and fails here; the default 0.83x.
TEST(VerifyDoNoHarm, DefaultNoWorseThanNoneOnTheNormalMappedSphereToneMapped) {
    SPECBAKE_REQUIRE_GL();
    auto scene = make_builtin_scene("bumpy-sphere", std::sqrt(0.01f));
    ASSERT_TRUE(scene.ok());
    expect_default_no_worse(*scene, 128, true, "", 256, 4);
}

// A smooth bump map under a rough material (the normal-mapped sphere at alpha 0.2, the bench's settings:
// 128x128, 256 spp, 8 frames): no filtering's flicker there is the engine's trilinear sampling of the mean
// normal, and the baked kernel, a fraction of a, only added to it. The gate (SPECAA_KERNEL_GATE) fades
// kernels below a / 2. With every kernel whole (gate 0) this scene fails: 1.0025x no filtering's
// tone-mapped flicker, 1.019x its linear temporal error; with the gate every metric is below 1.
TEST(VerifyDoNoHarm, DefaultNoWorseThanNoneOnARoughBumpMappedSphere) {
    SPECBAKE_REQUIRE_GL();
    auto scene = make_builtin_scene("bumpy-sphere", std::sqrt(0.2f));
    ASSERT_TRUE(scene.ok());
    expect_default_no_worse(*scene, 128, true, "", 256, 8);
    // The same check must fail without the gate, or it would not pin it.
    VerifyOptions options = test::small_verify(128, 128, 256, 8);
    options.only = {"default"};
    options.defines = "#define SPECAA_KERNEL_GATE 0.0\n";
    auto whole = run_verify(*scene, options);
    ASSERT_TRUE(whole.ok()) << whole.error().message;
    const SimMetrics* none = metrics_of(*whole, "none");
    const SimMetrics* def = metrics_of(*whole, "default");
    ASSERT_TRUE(none && def);
    EXPECT_GT(def->flicker, none->flicker) << "the ungated kernel no longer raises the flicker: the test pins nothing";
}

// Domes on a flat field, magnified (the bench's near distance), tone-mapped: a mip texel on a dome's rim
// spreads along the slope only. The default's Sigma kernel mips follow that; the isotropic t = tr(Sigma)
// (`--isotropic-kernel`, row `default-isotropic-kernel`) widens the lobe across the slope too and lights a
// crescent along every rim: at 128x128, 64 spp, 4 frames 1.07x no filtering's tone-mapped flicker (fails
// here), the default 0.77x.
TEST(VerifyDoNoHarm, DefaultNoWorseThanNoneOnNormalTangentMirrorTestNearToneMapped) {
    SPECBAKE_REQUIRE_GL();
    shared_model("NormalTangentMirrorTest", 128, true, "near", 64, 4);
}

// Models outside the corpus the rule was first tuned on (docs/accuracy.md#do-no-harm-in-the-field), at the
// distances where the earlier default did harm, at the bench's settings (128x128, 256 spp, 8 frames). The
// earlier default (the per-pixel kernel from quad derivatives, the GGX(A) share judged on the largest
// eigenvalue of all of K: row `default-derivatives` with SPECAA_BLEND_FROM_LARGEST_AXIS) gave strongly curved
// parts (the lamp's twisted stem, the olives' rims, the helmet's visor) GGX(A)'s heavy tails, a halo that
// moves with the image, and its quad kernel jumps where triangle edges cross a pixel. The default reads the
// baked curvature (`patch`) and judges the share on the spread's shape. Each test runs both: the earlier rule
// must fail a do-no-harm measure there (so the check can fail on these settings), the default must hold
// every one.
void expect_default_holds_where_the_earlier_rule_failed(const char* name, const std::string& distance,
                                                       const char* earlier_candidate = "default-derivatives",
                                                       const char* earlier_defines = "#define SPECAA_BLEND_FROM_LARGEST_AXIS\n") {
    const fs::path file = fs::path(SPECBAKE_ASSETS_DIR) / "gltf" / name / (std::string(name) + ".gltf");
    if (!fs::exists(file)) GTEST_SKIP() << file << " not found: shared assets absent, do-no-harm not checked on it";
    auto scene = load_sim_scene(file);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    const SimScene at = at_distance(*scene, distance, distance_factor(distance));
    for (const bool earlier : {false, true}) {
        VerifyOptions options = test::small_verify(128, 128, 256, 8);
        options.only = {earlier ? earlier_candidate : "default"};
        if (earlier) options.defines = earlier_defines;
        auto report = run_verify(at, options);
        ASSERT_TRUE(report.ok()) << report.error().message;
        const SimMetrics* none = metrics_of(*report, "none");
        const SimMetrics* def = metrics_of(*report, options.only[0]);
        ASSERT_TRUE(none && def);
        const bool holds = def->rmse <= 1.02 * none->rmse && def->flicker_linear <= none->flicker_linear &&
                           def->flicker <= none->flicker && def->temporal_error_linear <= none->temporal_error_linear &&
                           def->temporal_error <= none->temporal_error;
        const std::string ratios = "RMSE " + std::to_string(def->rmse / none->rmse) + ", flicker " +
                                   std::to_string(def->flicker_linear / none->flicker_linear) + ", tm flicker " +
                                   std::to_string(def->flicker / none->flicker) + ", t-err " +
                                   std::to_string(def->temporal_error_linear / none->temporal_error_linear) +
                                   ", tm t-err " + std::to_string(def->temporal_error / none->temporal_error);
        if (earlier)
            EXPECT_FALSE(holds) << name << " " << distance << ": the earlier rule holds here (" << ratios
                                << "); the check no longer shows the harm it guards against";
        else
            EXPECT_TRUE(holds) << name << " " << distance << ": the default does harm (" << ratios << " x none)";
    }
}

TEST(VerifyDoNoHarmField, DefaultHoldsOnLightsPunctualLampMid) {
    SPECBAKE_REQUIRE_GL();
    expect_default_holds_where_the_earlier_rule_failed("LightsPunctualLamp", "mid");
}

TEST(VerifyDoNoHarmField, DefaultHoldsOnIridescentDishWithOlivesNear) {
    SPECBAKE_REQUIRE_GL();
    expect_default_holds_where_the_earlier_rule_failed("IridescentDishWithOlives", "near");
}

TEST(VerifyDoNoHarmField, DefaultHoldsOnDamagedHelmetFar) {
    SPECBAKE_REQUIRE_GL();
    expect_default_holds_where_the_earlier_rule_failed("DamagedHelmet", "far");
}

TEST(VerifyDoNoHarmField, DefaultHoldsOnClearCoatTestMid) {
    SPECBAKE_REQUIRE_GL();
    expect_default_holds_where_the_earlier_rule_failed("ClearCoatTest", "mid");
}

// The lamp's stem near: a broad baked spread (rough share g 0.6-0.95: its normals all on the slope) above the
// blend's size threshold. Judged on the size alone (SPECAA_BLEND_FROM_SPREAD_SIZE, the rule before) it took
// GGX(A), whose tails draw a halo that moves with the image (tone-mapped temporal error 1.11x); weighed by its
// heavy tail 1 - g it keeps the convolution.
TEST(VerifyDoNoHarmField, DefaultHoldsOnLightsPunctualLampNear) {
    SPECBAKE_REQUIRE_GL();
    expect_default_holds_where_the_earlier_rule_failed("LightsPunctualLamp", "near", "default",
                                                       "#define SPECAA_BLEND_FROM_SPREAD_SIZE\n");
}

// Mixed texels: sparse grooves on a flat field (the built-in scratched sphere), alpha 0.05, 128x128, 64 spp,
// 4 frames. The Gaussian of a Sigma kernel texel's covariance (SPECAA_KERNEL_COVARIANCE, the earlier
// default) spreads the flat field's highlight over the grooves' slopes; the default's single lobe narrows
// it by sqrt(g), g the texel's rough share in the kernel's alpha, and SPECAA_KERNEL_TWO_LOBES keeps the
// flat share's lobe sharp. Fails if the rough share is not baked, or if the include ignores it (the rows
// would equal the covariance lobe's).
TEST(VerifyMixedTexels, RoughShareNarrowsTheSingleLobeAndTwoLobesKeepTheFlatHighlight) {
    SPECBAKE_REQUIRE_GL();
    auto scene = make_builtin_scene("scratched-sphere", std::sqrt(0.05f));
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    VerifyOptions options = test::small_verify(128, 128, 64, 4);
    options.only = {"default", "default-two-lobes"};
    auto report = run_verify(*scene, options);
    options.only = {"default"};
    options.defines = "#define SPECAA_KERNEL_COVARIANCE\n";
    auto covariance_report = run_verify(*scene, options);
    ASSERT_TRUE(report.ok()) << report.error().message;
    ASSERT_TRUE(covariance_report.ok()) << covariance_report.error().message;
    const SimMetrics* one = metrics_of(*report, "default");
    const SimMetrics* two = metrics_of(*report, "default-two-lobes");
    const SimMetrics* covariance = metrics_of(*covariance_report, "default");
    ASSERT_TRUE(one && two && covariance);
    EXPECT_LE(one->rmse_tonemapped, 0.9 * covariance->rmse_tonemapped);
    EXPECT_LE(one->flicker, covariance->flicker);
    EXPECT_LE(two->rmse_tonemapped, 0.8 * covariance->rmse_tonemapped);
    EXPECT_LE(two->temporal_error, covariance->temporal_error);
}

}  // namespace
}  // namespace specbake::verify
