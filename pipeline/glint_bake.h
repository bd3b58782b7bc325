// The scene bake's glint steps: slope-space LEAN settings for the normal maps of materials that ask for
// glints, and after the texture bake the shared dictionary (once per output folder) and the material's
// "glints" entry in SPECBAKE_specular_aa (io/gltf/SPECBAKE_EXTENSION.md).
#pragma once

#include "core/result.h"
#include "io/gltf/gltf_scene.h"
#include "io/output/manifest.h"
#include "pipeline/plan.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace specbake {

// For every named material that asks for glints and has a normal texture: LEAN output in slope space
// (Olano & Baker: the base roughness folded into the second moments, so Sigma = M - m m^T is the whole
// slope covariance the glints need, C21 Eq. 16) in options.material_texture_settings.
Result<void> add_glint_lean_settings(const io::GltfScene& scene, PlanOptions& options);

// When the plan bakes glints: writes out_dir/glint_dictionary.ktx2 (appended to `written` and `outputs`;
// copied from `final_dir` when a previous bake committed the same one there, else baked once per process,
// see write_glint_dictionary; `say` tells which) and sets extension_of_material[m]["glints"] of every such
// material: its parameters, the dictionary (uri and parameters) and its slope-space LEAN outputs.
Result<void> add_glint_outputs(const ScenePlan& plan, const std::filesystem::path& out_dir,
                               const std::filesystem::path& final_dir, const std::function<void(const std::string&)>& say,
                               const std::map<std::string, std::vector<io::ManifestOutput>>& files_by_stem,
                               std::map<int, nlohmann::json>& extension_of_material,
                               std::vector<std::filesystem::path>& written, std::vector<io::ManifestOutput>& outputs);

}  // namespace specbake
