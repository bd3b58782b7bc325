// Command-line options shared by the scene subcommands (bake, mesh, plan): the curvature estimator, the
// plan thresholds and the texture-bake settings passed through to the texture bake.
#pragma once

#include "cli/job_scene.h"

#include <CLI/CLI.hpp>

#include <memory>
#include <string>
#include <vector>

namespace specbake::cli {

struct SceneCliOptions {
    std::vector<std::string> scenes;
    std::string output_dir;
    std::string estimator = "shape-operator";
    std::string format = "same";
    std::string container = "ktx2";
    std::string kernel = "mean";
    std::string filter = "projected";
    double max_kernel = 0.0;
    std::string green = "+y";
    std::string reconstruct_z = "auto";
    bool anisotropic = false;
    std::string lean_space = "projected";
    std::vector<std::string> outputs{"roughness", "kernel", "lean", "normal"};
    double min_roughness_gain = 0.05;
    double min_relative_curvature = 0.05;
    double kappa = 0.18;
    int threads = 0;
    bool json = false;
    bool quiet = false;
};

// Curvature options (all scene subcommands).
inline void add_curvature_options(CLI::App* sub, SceneCliOptions& o) {
    sub->add_option("--estimator", o.estimator, "Curvature estimator")
        ->check(CLI::IsMember({"shape-operator", "jet-fitting", "normal-cone"}))
        ->capture_default_str();
    sub->add_option("--min-curvature", o.min_relative_curvature,
                    "Bake curvature only where p95(|k1|) x bounding-box diagonal reaches this (radians of normal turn)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    sub->add_option("--threads", o.threads, "Worker threads (0: all cores)")->check(CLI::NonNegativeNumber);
}

// Material / texture options (bake and plan).
inline void add_material_options(CLI::App* sub, SceneCliOptions& o) {
    sub->add_option("--min-roughness-gain", o.min_roughness_gain,
                    "Bake curvature only for materials whose lowest roughness the largest kernel raises by this much")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    sub->add_option("--kappa", o.kappa, "Kernel clamp of the run time (SPEC Sec. 2)")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    sub->add_option("--kernel", o.kernel, "Isotropic kernel of the texture bake (TK21 Eq. 14, 13, 10)")
        ->check(CLI::IsMember({"mean", "sum", "max"}))
        ->capture_default_str();
    sub->add_option("--filter", o.filter, "Roughness filter: projected (TK21 Eq. 4-7) or approx (Eq. 9)")
        ->check(CLI::IsMember({"projected", "approx"}))
        ->capture_default_str();
    sub->add_option("--max-kernel", o.max_kernel, "Clamp of the baked kernel (0: none)")->check(CLI::NonNegativeNumber);
    sub->add_option("--green", o.green, "Normal-map green convention: +y (OpenGL/glTF) or -y (DirectX)")
        ->check(CLI::IsMember({"+y", "-y"}))
        ->capture_default_str();
    sub->add_option("--reconstruct-z", o.reconstruct_z, "Rebuild normal z from x, y")
        ->check(CLI::IsMember({"auto", "always", "never"}))
        ->capture_default_str();
    sub->add_flag("--anisotropic", o.anisotropic, "Kernel texture holds Sigma (xx, yy, xy) instead of t");
    sub->add_option("--lean-space", o.lean_space, "LEAN moments in projected or slope space")
        ->check(CLI::IsMember({"projected", "slope"}))
        ->capture_default_str();
    sub->add_option("--outputs", o.outputs, "Texture outputs to write (any of roughness, kernel, lean, normal)")
        ->check(CLI::IsMember({"roughness", "kernel", "lean", "normal"}))
        ->delimiter(',')
        ->capture_default_str();
}

inline SceneJob make_scene_job(const SceneCliOptions& o) {
    SceneJob job;
    for (const std::string& s : o.scenes) job.scenes.emplace_back(s);
    job.output_dir = o.output_dir;
    job.format = o.format == "gltf" ? SceneFormat::Gltf : o.format == "glb" ? SceneFormat::Glb : SceneFormat::SameAsInput;
    job.container = io::parse_container(o.container).value_or(io::TextureContainer::Ktx2);
    PlanOptions& p = job.plan;
    p.estimator = parse_curvature_estimator(o.estimator).value_or(CurvatureEstimator::ShapeOperator);
    p.min_roughness_gain = o.min_roughness_gain;
    p.min_relative_curvature = o.min_relative_curvature;
    p.kappa = o.kappa;
    p.threads = o.threads;
    TextureBakeSettings& t = p.texture_settings;
    t.isotropic = o.kernel == "sum" ? IsotropicReduction::Sum : o.kernel == "max" ? IsotropicReduction::Max
                                                                                  : IsotropicReduction::Mean;
    t.filter = o.filter == "approx" ? RoughnessFilterMode::Approx : RoughnessFilterMode::Projected;
    if (o.max_kernel > 0) t.max_kernel = o.max_kernel;
    t.normal_y = o.green == "-y" ? NormalGreen::MinusY : NormalGreen::PlusY;
    t.reconstruct_z = o.reconstruct_z == "always" ? ReconstructZ::Always
                      : o.reconstruct_z == "never" ? ReconstructZ::Never
                                                   : ReconstructZ::Auto;
    t.anisotropic = o.anisotropic;
    t.lean_space = o.lean_space == "slope" ? LeanSpace::Slope : LeanSpace::Projected;
    auto has = [&](const char* k) { return std::find(o.outputs.begin(), o.outputs.end(), k) != o.outputs.end(); };
    t.outputs = TextureOutputs{has("roughness"), has("kernel"), has("lean"), has("normal")};
    t.threads = o.threads;
    return job;
}

}  // namespace specbake::cli
