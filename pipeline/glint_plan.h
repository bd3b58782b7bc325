// Glints in the plan (SPEC Sec. 6): only materials that ask for them, through the SPECBAKE_glints
// material extension or the same keys in a config's [materials.NAME] (glints = true, glints_log_density,
// glints_relative_area, glints_density_randomization, glints_uv_scale, glints_texcoord, glints_target). A material
// without the asked TEXCOORD_n on any primitive is skipped with the reason.
#pragma once

#include "core/result.h"
#include "io/gltf/gltf_scene.h"
#include "io/gltf/glint_extension.h"

#include <nlohmann/json.hpp>

#include <map>
#include <string>
#include <vector>

namespace specbake {

struct GlintDecision {
    int material = -1;
    std::string material_name;
    bool bake = false;
    std::string asked_by;        // "SPECBAKE_glints" or "config"
    std::string reason;
    io::GlintMaterial params;
    bool normal_map = false;     // the material's normal texture gets slope-space LEAN moments
};

// The config's glint keys of one material as a SPECBAKE_glints object; null when the keys do not ask
// for glints (no "glints" key, or glints = false). Errors name the material and key.
Result<nlohmann::json> glint_object_from_config(const std::string& material, const nlohmann::json& keys);

// True for the config keys glint_object_from_config reads.
bool is_glint_config_key(const std::string& key);

// One decision per material that asks (extension first, the config's keys override it field by field).
Result<std::vector<GlintDecision>> plan_glints(const io::GltfScene& scene,
                                               const std::map<std::string, nlohmann::json>& config_glints);

nlohmann::json glint_decision_json(const GlintDecision& d);
// One line per decision in the `specbake plan` table layout.
std::string glint_table_lines(const std::vector<GlintDecision>& decisions);

}  // namespace specbake
