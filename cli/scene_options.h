// Command-line options shared by the scene subcommands (bake, mesh, plan): the curvature estimator, the
// plan thresholds and the texture-bake settings passed through to the texture bake.
#pragma once

#include "cli/block_options.h"
#include "pipeline/config.h"
#include "pipeline/batch.h"
#include "pipeline/scene_job.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace specbake::cli {

struct SceneCliOptions {
    std::vector<std::string> scenes;
    std::string output_dir;
    std::string estimator = "shape-operator";
    std::string format = "same";
    std::string container = "ktx2";
    std::string gltf_mode = "sidecar";
    std::string basisu;
    BlockCliOptions blocks;
    std::string isotropic = "mean";
    std::string filter = "projected";
    double max_kernel = 0.0;
    std::string normal_y = "+y";
    std::string reconstruct_z = "gltf";
    bool anisotropic = true;
    std::string lean_space = "projected";
    std::vector<std::string> outputs{"roughness", "kernel", "lean", "normal"};
    double min_roughness_gain = 0.05;
    double min_relative_curvature = 0.05;
    double kappa = 0.18;
    bool json = false;
};

// Finite numbers >= 0 / > 0: CLI::NonNegativeNumber and CLI::PositiveNumber let NaN through (every
// comparison with NaN is false) and infinity too.
inline CLI::Validator finite_number(bool zero_allowed) {
    return CLI::Validator(
        [zero_allowed](std::string& text) -> std::string {
            char* end = nullptr;
            const double v = std::strtod(text.c_str(), &end);
            if (text.empty() || *end != '\0' || !std::isfinite(v) || v < 0 || (!zero_allowed && v == 0))
                return "'" + text + "' is not a finite number " + (zero_allowed ? ">= 0" : "> 0");
            return {};
        },
        zero_allowed ? "FINITE >= 0" : "FINITE > 0");
}

// Curvature options (all scene subcommands).
inline void add_curvature_options(CLI::App* sub, SceneCliOptions& o) {
    sub->add_option("--estimator", o.estimator,
                    "Curvature estimator: shape-operator (SPEC Sec. 4 per-face fit), second-order (per-vertex fit "
                    "with the curvature derivative, more accurate on irregular meshes), jet-fitting (geometric, "
                    "CGAL), normal-cone (cheap bound)")
        ->check(CLI::IsMember({"shape-operator", "second-order", "jet-fitting", "normal-cone"}))
        ->capture_default_str();
    sub->add_option("--min-curvature", o.min_relative_curvature,
                    "Bake curvature only where p95(|k1|) x bounding-box diagonal reaches this (radians of normal turn)")
        ->check(finite_number(true))
        ->capture_default_str();
}

// Material / texture options (bake and plan).
inline void add_material_options(CLI::App* sub, SceneCliOptions& o) {
    sub->add_option("--min-roughness-gain", o.min_roughness_gain,
                    "Bake curvature only for materials whose lowest roughness the largest kernel raises by this much")
        ->check(finite_number(true))
        ->capture_default_str();
    sub->add_option("--kappa", o.kappa, "Kernel clamp of the run time (SPEC Sec. 2)")
        ->check(finite_number(false))
        ->capture_default_str();
    sub->add_option("--isotropic", o.isotropic,
                    "Kernel from the footprint covariance Sigma: mean t = tr, sum t = 2 tr, max t = 2 lambda_max")
        ->check(CLI::IsMember({"mean", "sum", "max"}))
        ->capture_default_str();
    sub->add_option("--filter", o.filter, "Roughness filter: projected (TK21 Eq. 4-7) or approx (Eq. 9)")
        ->check(CLI::IsMember({"projected", "approx"}))
        ->capture_default_str();
    sub->add_option("--max-kernel", o.max_kernel, "Clamp of the baked kernel (0: none)")->check(finite_number(true));
    sub->add_option("--normal-y", o.normal_y, "Normal-map green convention: +y (OpenGL/glTF) or -y (DirectX)")
        ->check(CLI::IsMember({"+y", "-y"}))
        ->capture_default_str();
    sub->add_option("--reconstruct-z", o.reconstruct_z,
                    "Normal z: gltf (the stored blue channel, as glTF viewers shade it; rebuilt only for a "
                    "two-channel map), auto (also rebuilt where blue is constant full scale), always, never")
        ->check(CLI::IsMember({"gltf", "auto", "always", "never"}))
        ->capture_default_str();
    sub->add_flag("--anisotropic,!--isotropic-kernel", o.anisotropic,
                  "Kernel texture holds Sigma (xx, yy, xy) (default, what the default rule reads); --isotropic-kernel: t only");
    sub->add_option("--lean-space", o.lean_space, "LEAN moments in projected or slope space")
        ->check(CLI::IsMember({"projected", "slope"}))
        ->capture_default_str();
    sub->add_option("--outputs", o.outputs, "Texture outputs to write (any of roughness, kernel, lean, normal)")
        ->check(CLI::IsMember({"roughness", "kernel", "lean", "normal"}))
        ->delimiter(',')
        ->capture_default_str();
}

// Sets one texture setting from the text an option (or a [materials.NAME] key of a config file) gives:
// isotropic, filter, max-kernel (0: none), normal-y, reconstruct-z, anisotropic, lean-space, outputs.
// Returns the problem, or an empty string when `value` was applied.
inline std::string set_texture_setting(TextureBakeSettings& t, const std::string& key, const std::string& value) {
    auto one_of = [&](std::initializer_list<const char*> allowed) {
        for (const char* a : allowed)
            if (value == a) return true;
        return false;
    };
    if (key == "isotropic" && one_of({"mean", "sum", "max"})) {
        t.isotropic = value == "sum" ? IsotropicReduction::Sum : value == "max" ? IsotropicReduction::Max
                                                                                : IsotropicReduction::Mean;
    } else if (key == "filter" && one_of({"projected", "approx"})) {
        t.filter = value == "approx" ? RoughnessFilterMode::Approx : RoughnessFilterMode::Projected;
    } else if (key == "normal-y" && one_of({"+y", "-y"})) {
        t.normal_y = value == "-y" ? NormalGreen::MinusY : NormalGreen::PlusY;
    } else if (key == "reconstruct-z" && one_of({"gltf", "auto", "always", "never"})) {
        t.reconstruct_z = value == "always" ? ReconstructZ::Always
                          : value == "never" ? ReconstructZ::Never
                          : value == "gltf"  ? ReconstructZ::Gltf
                                             : ReconstructZ::Auto;
    } else if (key == "anisotropic" && one_of({"true", "false", "1", "0"})) {
        t.anisotropic = value == "true" || value == "1";
    } else if (key == "lean-space" && one_of({"projected", "slope"})) {
        t.lean_space = value == "slope" ? LeanSpace::Slope : LeanSpace::Projected;
    } else if (key == "max-kernel") {
        char* end = nullptr;
        const double v = std::strtod(value.c_str(), &end);
        if (value.empty() || *end != '\0' || !std::isfinite(v) || v < 0)
            return "'" + value + "' is not a finite number >= 0";
        t.max_kernel = v > 0 ? std::optional<double>(v) : std::nullopt;
    } else if (key == "outputs") {
        TextureOutputs out{false, false, false, false};
        std::stringstream list(value);
        std::string item;
        while (std::getline(list, item, ',')) {
            if (item == "roughness") out.roughness = true;
            else if (item == "kernel") out.kernel = true;
            else if (item == "lean") out.lean = true;
            else if (item == "normal") out.normal = true;
            else return "'" + item + "' is not one of roughness, kernel, lean, normal";
        }
        t.outputs = out;
    } else if (key == "isotropic" || key == "filter" || key == "normal-y" || key == "reconstruct-z" ||
               key == "anisotropic" || key == "lean-space") {
        return "'" + value + "' is not a valid value";
    } else {
        return "unknown key (per-material keys: isotropic, filter, max-kernel, normal-y, reconstruct-z, "
               "anisotropic, lean-space, outputs)";
    }
    return {};
}

// The job the options describe. The [materials.NAME] tables of --config give per-material texture
// settings on top of the command-line ones; a bad key or value there is an error naming it.
inline Result<SceneJob> make_scene_job(const SceneCliOptions& o) {
    SceneJob job;
    for (const std::string& s : o.scenes) job.scenes.emplace_back(s);
    job.output_dir = o.output_dir;
    job.format = o.format == "gltf" ? SceneFormat::Gltf : o.format == "glb" ? SceneFormat::Glb : SceneFormat::SameAsInput;
    job.container = io::parse_container(o.container).value_or(io::TextureContainer::Ktx2);
    job.gltf_mode = o.gltf_mode == "replace" ? GltfMode::Replace : GltfMode::Sidecar;
    job.basisu = o.basisu;
    if (auto ok = apply_block_options(o.blocks, job.container, "--container", job.supercompression); !ok)
        return ok.error();
    PlanOptions& p = job.plan;
    p.estimator = parse_curvature_estimator(o.estimator).value_or(CurvatureEstimator::ShapeOperator);
    p.min_roughness_gain = o.min_roughness_gain;
    p.min_relative_curvature = o.min_relative_curvature;
    p.kappa = o.kappa;
    p.threads = run_settings().jobs;
    TextureBakeSettings& t = p.texture_settings;
    t.isotropic = o.isotropic == "sum" ? IsotropicReduction::Sum : o.isotropic == "max" ? IsotropicReduction::Max
                                                                                        : IsotropicReduction::Mean;
    t.filter = o.filter == "approx" ? RoughnessFilterMode::Approx : RoughnessFilterMode::Projected;
    if (o.max_kernel > 0) t.max_kernel = o.max_kernel;
    t.normal_y = o.normal_y == "-y" ? NormalGreen::MinusY : NormalGreen::PlusY;
    t.reconstruct_z = o.reconstruct_z == "always" ? ReconstructZ::Always
                      : o.reconstruct_z == "never" ? ReconstructZ::Never
                      : o.reconstruct_z == "auto"  ? ReconstructZ::Auto
                                                   : ReconstructZ::Gltf;
    t.anisotropic = o.anisotropic;
    t.lean_space = o.lean_space == "slope" ? LeanSpace::Slope : LeanSpace::Projected;
    auto has = [&](const char* k) { return std::find(o.outputs.begin(), o.outputs.end(), k) != o.outputs.end(); };
    t.outputs = TextureOutputs{has("roughness"), has("kernel"), has("lean"), has("normal")};
    t.threads = run_settings().jobs;
    const nlohmann::json overrides = material_overrides().to_json();
    for (const auto& [material, keys] : overrides.items()) {
        TextureBakeSettings m = t;
        auto glints = glint_object_from_config(material, keys);
        if (!glints) return glints.error();
        if (!glints->is_null()) p.material_glints[material] = *glints;
        bool texture_keys = false;
        for (auto [key, value] : keys.items()) {
            if (is_glint_config_key(key)) continue;
            texture_keys = true;
            std::string name = key;
            std::replace(name.begin(), name.end(), '_', '-');  // max_kernel and max-kernel alike
            const std::string text = value.is_string() ? value.get<std::string>() : value.dump();
            if (std::string problem = set_texture_setting(m, name, text); !problem.empty())
                return make_error("config: materials." + material + "." + key + ": " + problem);
        }
        if (texture_keys || glints->is_null()) p.material_texture_settings[material] = m;
    }
    return job;
}

// Runs `bake` (curvature_only = false: textures and curvature, as planned) or `mesh` (curvature only) for
// parsed options: up-to-date check, the scene job, messages, depfile. Returns the process exit code.
// Defined in cmd_bake.cpp.
int run_scene_command(const SceneCliOptions& options, const PipelineFlags& pipe, bool curvature_only);

}  // namespace specbake::cli
