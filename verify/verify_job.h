// specbake verify: renders one scene's ground truth and every candidate on the headless OpenGL context,
// and scores accuracy (sim_metrics.h) and cost (bake time, SPIR-V instructions, frame time relative to no
// filtering) per candidate (SPEC Sec. 6 and 8). Needs a current GL context (GlContext::create()).
#pragma once

#include "core/result.h"
#include "mesh/curvature.h"
#include "verify/candidates.h"
#include "verify/metrics.h"
#include "verify/scene.h"

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace specbake::verify {

struct VerifyOptions {
    std::string include_glsl;  // text of the runtime include shaders/specaa.glsl
    int width = 128;
    int height = 128;
    int spp = 256;            // ground-truth samples per pixel (rounded to a square)
    int frames = 8;           // K frames of slow camera motion for the temporal metric
    int timing_repeats = 7;   // frame-time median over this many renders; 0 skips timing
    bool spirv = true;        // count SPIR-V instructions when the tools are on PATH
    bool variants = true;     // include the bake variants
    std::vector<std::string> only;  // candidate names to keep ("none" is always kept); empty: all
    bool keep_images = true;  // keep frame 0 of every image for strips
    // Keep every candidate's per-pixel tone-mapped flicker and temporal error (CandidateReport) for the
    // harm map (strips.h, `verify --harm-map`).
    bool pixel_maps = false;
    // The glint dictionary of scenes whose materials ask for glints (shared_glint_dictionary: baked once
    // per process); the defaults are what `specbake glints` and `bake` write.
    GlintDictionarySettings glint_dictionary;
    // Also score an independent ground truth at a quarter of the samples against the full one on the same
    // frames (row "floor"): the error and flicker no candidate can be shown to beat at this sample count.
    bool floor = true;
    // A ground truth that can tell: while the floor row's RMSE or linear flicker is above `floor_goal` x no
    // filtering's, the ground-truth samples rise fourfold (at most to `max_spp`) and every frame is rendered
    // and scored again (the bakes are kept). A measure no filtering scores as 0 sets no goal. 0: never.
    int max_spp = 0;
    double floor_goal = 0.1;
    // Also score the limit row: per pixel and frame the best of kLimitKernels isotropic GGX lobes about the
    // engine's shading normal (verify_job.cpp), a lower bound for every rule that widens the lobe.
    bool limit = true;
    // Lines "#define NAME VALUE" put before every candidate's own defines, but not the baselines' (none,
    // glint-c20) or the ground truths' (`--define`).
    std::string defines;
    // Copies of the "default" candidate, each named "default:LABEL" and compiled with its own extra
    // "#define" lines (after `defines`): several variants of the rule scored against one ground truth
    // (`verify --variant`), for attributing an error to one part of the rule.
    std::vector<std::pair<std::string, std::string>> default_variants;
    // The curvature estimator (mesh/curvature.h spelling) whose per-vertex estimate the candidates made
    // with `defines` or `default_variants` read when those include SPECAA_USE_CURVATURE, on scenes without
    // exact curvature.
    std::string curvature_estimator{to_string(kDefaultCurvatureEstimator)};
    // Ground-truth samples integrate the highlight over their stratum (false: point samples).
    bool footprint_ground_truth = true;
    // Receives one line per finished stage (bakes, each ground-truth frame, timing); may be empty.
    std::function<void(const std::string&)> progress;
    // Called after each frame (ground truth and every candidate rendered) with (frames done, frames); may be empty.
    std::function<void(int, int)> frame_done;
};

struct CandidateReport {
    std::string name, family, source;
    SimMetrics metrics;
    std::optional<double> bake_ms;        // texture bake or curvature estimate; none for run-time only
    std::optional<int> spirv_instructions;
    std::optional<double> frame_ms;       // median render time on this context
    std::optional<double> frame_relative; // frame_ms / frame_ms of "none"
    SimImage image;                       // frame 0 (when keep_images)
    // With VerifyOptions::pixel_maps: per pixel T(c) - T(g)'s temporal std and Allan deviation (metrics.h).
    std::vector<float> pixel_flicker, pixel_temporal_error;
};

struct SceneReport {
    std::string scene;          // e.g. "torus"
    float roughness = 0;        // perceptual r of the scene's materials (of the first object for a file)
    bool from_file = false;     // a scene file, whose materials keep their own roughness
    int width = 0, height = 0, spp = 0, frames = 0;
    int spp_raised_from = 0;    // the first ground truth's samples when VerifyOptions::max_spp raised them; else 0
    // With VerifyOptions::max_spp, when the floor is still above its goal at the most samples: why (also a note).
    std::string floor_goal_unmet;
    double ground_truth_ms = 0; // wall time of all ground-truth frames
    SimImage ground_truth;      // frame 0 (when keep_images); empty for a glints-only scene
    // Scenes with glints (C21): the glint ground truth (renderer.h) the "glint" family is scored against.
    double glint_ground_truth_ms = 0;
    SimImage glint_ground_truth;
    std::vector<CandidateReport> candidates;
    std::vector<std::string> notes;  // skipped candidates and why
};

// Simulates `scene` and scores every candidate that applies: the specular anti-aliasing candidates against
// the GGX ground truth (not for a glints-only scene) and, for the materials that ask for glints, the glint
// candidates against the glint ground truth. Frame times are relative to "none", the glint family's to
// "glint-c20" (glints without anti-aliasing).
Result<SceneReport> run_verify(const SimScene& scene, const VerifyOptions& options);

// The row every candidate of `family` is compared with: "glint-c20" for "glint", "none" otherwise.
std::string baseline_of(const std::string& family);
Result<SceneReport> run_verify(const SimScene& scene, const VerifyOptions& options);

// The report as a Markdown table (one row per candidate).
std::string markdown_table(const SceneReport& report);

}  // namespace specbake::verify
