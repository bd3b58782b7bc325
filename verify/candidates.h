// The candidates the simulator scores against the ground truth (issue: verify/bench): no filtering, every
// derivative-based method of the runtime include, the VAREF and Filament-style peers, baked texture only,
// baked curvature only, the include's default entry point, and the bake's own variants. Each is a small
// GLSL body on top of shaders/specaa.glsl plus the baked data it samples.
#pragma once

#include "bake/peer_roughness_bake.h"
#include "bake/texture_bake.h"
#include "verify/renderer.h"
#include "verify/scene.h"
#include "mesh/curvature.h"

#include <optional>
#include <string>
#include <vector>

namespace specbake::verify {

// A texture bake a candidate depends on (run once per normal map, timed as the candidate's bake cost).
struct SimTextureBake {
    std::string key;  // "mean-projected", "mean-approx", "sum-projected", "max-projected", "peer-filament", ...
    TextureBakeSettings settings;
    std::optional<PeerRoughnessBake> peer;  // an engine's offline roughness bake instead of specbake's
};

// A curvature estimate a candidate depends on ("exact" is the analytic curvature: no bake).
struct SimCurvatureBake {
    std::string key;  // "exact", "shape-operator", "second-order", "jet-fitting", "normal-cone"
    std::optional<CurvatureEstimator> estimator;
};

struct SimCandidate {
    std::string name;    // table row, e.g. "projected-approx", "baked-texture", "default+curvature"
    std::string family;  // "none", "derivative", "peer", "baked", "default", "tier", "variant"
    std::string source;  // citation of the formula
    SimShaderSpec shader;
    std::string texture_bake;    // key of a SimTextureBake, empty when none
    std::string curvature_bake;  // key of a SimCurvatureBake, empty when the candidate ignores curvature
};

// Candidates that apply to `scene` (baked-texture ones only when it has a normal map). With `variants`,
// also the bake variants (approx filter, sum/max reductions, kernel and LEAN textures, curvature
// estimators).
std::vector<SimCandidate> simulator_candidates(const SimScene& scene, bool variants,
                                              const std::string& estimator = std::string(to_string(kDefaultCurvatureEstimator)));

// The glint candidates (C21) of a scene whose materials ask for glints (family "glint"): the smooth BRDF
// (analytic SDF), glints without anti-aliasing (C20: s_K = 0), GGAA (C21 Eq. 15, 19, 21, s_K = 0.5) and,
// when a glint material has a normal map, GGAA with slope-space LEAN without and with rho (Eq. 16, 18).
// Empty for a scene without glints.
std::vector<SimCandidate> glint_candidates(const SimScene& scene);

// The texture bakes and curvature estimates the given candidates need.
std::vector<SimTextureBake> texture_bakes_for(const std::vector<SimCandidate>& candidates);
std::vector<SimCurvatureBake> curvature_bakes_for(const std::vector<SimCandidate>& candidates);

}  // namespace specbake::verify
