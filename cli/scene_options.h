// Command-line options shared by the scene subcommands (bake, mesh, plan): the curvature estimator, the
// plan thresholds and the texture-bake settings passed through to the texture bake.
#pragma once

#include "cli/block_options.h"
#include "cli/name_options.h"
#include "cli/config.h"
#include "cli/batch.h"
#include "pipeline/scene_job.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace specbake::cli {

struct SceneCliOptions {
    std::vector<std::string> scenes;
    std::string output_dir;
    std::string estimator{to_string(kDefaultCurvatureEstimator)};
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
    bool allow_unreadable_textures = false;  // `bake --allow-unreadable-textures`
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
                    "Curvature estimator: patch (the default: SPEC Sec. 4's per-face fit averaged over each vertex's "
                    "smooth patch, so that faces much steeper than most of the one-ring, a lip or a bevel, count "
                    "little), shape-operator (the per-face fit averaged over the whole one-ring), second-order "
                    "(per-vertex fit with the curvature derivative, more accurate on irregular meshes), jet-fitting "
                    "(geometric, CGAL), normal-cone (cheap bound)")
        ->check(CLI::IsMember({"shape-operator", "second-order", "jet-fitting", "normal-cone", "patch"}))
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
        ->check(is_member_of(kIsotropicReductionNames))
        ->capture_default_str();
    sub->add_option("--filter", o.filter, "Roughness filter: projected (TK21 Eq. 4-7) or approx (Eq. 9)")
        ->check(is_member_of(kRoughnessFilterModeNames))
        ->capture_default_str();
    sub->add_option("--max-kernel", o.max_kernel, "Clamp of the baked kernel (0: none)")->check(finite_number(true));
    sub->add_option("--normal-y", o.normal_y, "Normal-map green convention: +y (OpenGL/glTF) or -y (DirectX)")
        ->check(is_member_of(kNormalGreenNames))
        ->capture_default_str();
    sub->add_option("--reconstruct-z", o.reconstruct_z,
                    "Normal z: gltf (the stored blue channel, as glTF viewers shade it; rebuilt only for a "
                    "two-channel map), auto (also rebuilt where blue is constant full scale), always, never")
        ->check(is_member_of(kReconstructZNames))
        ->capture_default_str();
    sub->add_flag("--anisotropic,!--isotropic-kernel", o.anisotropic,
                  "Kernel texture holds Sigma (xx, yy, xy) (default, what the default rule reads); --isotropic-kernel: t only");
    sub->add_option("--lean-space", o.lean_space, "LEAN moments in projected or slope space")
        ->check(is_member_of(kLeanSpaceNames))
        ->capture_default_str();
    sub->add_option("--outputs", o.outputs, "Texture outputs to write (any of roughness, kernel, lean, normal)")
        ->check(is_member_of(kTextureOutputNames))
        ->delimiter(',')
        ->capture_default_str();
}

// Sets one texture setting from the text an option (or a [materials.NAME] key of a config file) gives:
// isotropic, filter, max-kernel (0: none), normal-y, reconstruct-z, anisotropic, lean-space, outputs.
// Returns the problem, or an empty string when `value` was applied.
inline std::string set_texture_setting(TextureBakeSettings& t, const std::string& key, const std::string& value) {
    // Sets `field` to the enumerator `value` names, or says it names none.
    auto set = [&value](auto& field, auto parsed) -> std::string {
        if (!parsed) return "'" + value + "' is not a valid value";
        field = *parsed;
        return {};
    };
    if (key == "isotropic") return set(t.isotropic, parse_isotropic_reduction(value));
    if (key == "filter") return set(t.filter, parse_roughness_filter_mode(value));
    if (key == "normal-y") return set(t.normal_y, parse_normal_green(value));
    if (key == "reconstruct-z") return set(t.reconstruct_z, parse_reconstruct_z(value));
    if (key == "lean-space") return set(t.lean_space, parse_lean_space(value));
    if (key == "anisotropic") {
        if (value != "true" && value != "false" && value != "1" && value != "0")
            return "'" + value + "' is not a valid value";
        t.anisotropic = value == "true" || value == "1";
    } else if (key == "max-kernel") {
        char* end = nullptr;
        const double v = std::strtod(value.c_str(), &end);
        if (value.empty() || *end != '\0' || !std::isfinite(v) || v < 0)
            return "'" + value + "' is not a finite number >= 0";
        t.max_kernel = v > 0 ? std::optional<double>(v) : std::nullopt;
    } else if (key == "outputs") {
        auto outputs = parse_texture_outputs(value);
        if (!outputs) return outputs.error().message;
        t.outputs = *outputs;
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
    // A scene listed twice (however spelled) is baked once.
    std::vector<std::filesystem::path> seen;
    for (const std::string& s : o.scenes) {
        std::error_code ec;
        const std::filesystem::path key = std::filesystem::weakly_canonical(std::filesystem::absolute(s, ec), ec);
        if (std::find(seen.begin(), seen.end(), key) != seen.end()) continue;
        seen.push_back(key);
        job.scenes.emplace_back(s);
    }
    job.output_dir = o.output_dir;
    job.format = *parse_scene_format(o.format);
    job.texture_format.container = io::parse_container(o.container).value_or(io::TextureContainer::Ktx2);
    job.gltf_mode = *parse_gltf_mode(o.gltf_mode);
    job.basisu = o.basisu;
    job.unreadable_textures_are_warnings = o.allow_unreadable_textures;
    if (auto ok = apply_block_options(o.blocks, "--container", job.texture_format); !ok)
        return ok.error();
    PlanOptions& p = job.plan;
    p.estimator = parse_curvature_estimator(o.estimator).value_or(kDefaultCurvatureEstimator);
    p.min_roughness_gain = o.min_roughness_gain;
    p.min_relative_curvature = o.min_relative_curvature;
    p.kappa = o.kappa;
    p.threads = run_settings().jobs;
    p.input_policy = run_settings().input_policy;
    // The options' checks accept only the enums' names.
    TextureBakeSettings& t = p.texture_settings;
    t.isotropic = *parse_isotropic_reduction(o.isotropic);
    t.filter = *parse_roughness_filter_mode(o.filter);
    if (o.max_kernel > 0) t.max_kernel = o.max_kernel;
    t.normal_y = *parse_normal_green(o.normal_y);
    t.reconstruct_z = *parse_reconstruct_z(o.reconstruct_z);
    t.anisotropic = o.anisotropic;
    t.lean_space = *parse_lean_space(o.lean_space);
    t.outputs = TextureOutputs{false, false, false, false};
    for (const std::string& name : o.outputs) select_texture_output(t.outputs, name);
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
