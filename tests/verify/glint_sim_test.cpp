// The glint simulation (verify/glint_sim.h) on small images: the candidates the scene calls for, finite
// metrics, and the orderings C21 reports that hold at this size (GGAA below C20 on the sphere, LEAN
// with rho below LEAN without rho and below no LEAN on the plane).
#include "verify/glint_sim.h"

#include <gtest/gtest.h>

#include <cmath>

namespace specbake::verify {
namespace {

const GlintDictionary& dictionary() {
    static const GlintDictionary d = [] {
        GlintDictionarySettings s;
        s.count = 32;
        return *bake_glint_dictionary(s);
    }();
    return d;
}

TEST(GlintSim, SphereGgaaBeatsC20) {
    GlintSimSettings s;
    s.size = 24;
    s.reference_spp = 64;
    s.frames = 2;
    auto report = run_glint_sim(dictionary(), s);
    ASSERT_TRUE(report.ok()) << report.error().message;
    ASSERT_EQ(report->rows.size(), 4u);
    EXPECT_GT(report->pixels, 300);
    for (const GlintSimRow& r : report->rows) {
        EXPECT_TRUE(std::isfinite(r.rmse_percent) && std::isfinite(r.flicker) && std::isfinite(r.energy)) << r.candidate;
        EXPECT_GT(r.energy, 0.5) << r.candidate;
        EXPECT_LT(r.energy, 1.5) << r.candidate;
    }
    EXPECT_LT(report->rows[2].rmse_percent, report->rows[1].rmse_percent);  // ggaa < c20
    EXPECT_LT(report->rows[2].flicker, report->rows[1].flicker);
}

TEST(GlintSim, PlaneHasTheLeanCandidatesAndBadScenesFail) {
    GlintSimSettings s;
    s.scene = "glitter-plane";
    s.size = 24;
    s.reference_spp = 64;
    s.frames = 2;
    auto report = run_glint_sim(dictionary(), s);
    ASSERT_TRUE(report.ok()) << report.error().message;
    ASSERT_EQ(report->rows.size(), 6u);
    EXPECT_EQ(report->rows[5].candidate, "ggaa+lean");
    for (const GlintSimRow& r : report->rows) EXPECT_TRUE(std::isfinite(r.rmse_percent)) << r.candidate;
    // C21 Fig. 7: LEAN with rho below LEAN without rho and below no LEAN (rows +lean, +lean-norho, ggaa).
    EXPECT_LT(report->rows[5].rmse_percent, report->rows[4].rmse_percent);
    EXPECT_LT(report->rows[5].rmse_percent, report->rows[2].rmse_percent);
    s.scene = "teapot";
    EXPECT_FALSE(run_glint_sim(dictionary(), s).ok());
}

}  // namespace
}  // namespace specbake::verify
