// Glint decisions of the plan: who asks (extension or config), the resolved parameters, and whether a
// primitive of the material has the texture coordinates the glints need.
#include "pipeline/glint_plan.h"

#include <algorithm>
#include <cstdio>
#include <set>

namespace specbake {
using nlohmann::json;

namespace {

struct ConfigKey {
    const char* config;
    const char* extension;
};
constexpr ConfigKey kKeys[] = {{"glints_log_density", "logDensity"},
                               {"glints_relative_area", "relativeArea"},
                               {"glints_density_randomization", "densityRandomization"},
                               {"glints_uv_scale", "uvScale"},
                               {"glints_texcoord", "texCoord"}};

std::string normalised(std::string key) {
    std::replace(key.begin(), key.end(), '-', '_');
    return key;
}

}  // namespace

bool is_glint_config_key(const std::string& key) { return normalised(key).rfind("glints", 0) == 0; }

Result<json> glint_object_from_config(const std::string& material, const json& keys) {
    json object = json::object();
    bool asked = false;
    for (auto it = keys.begin(); it != keys.end(); ++it) {
        const std::string key = normalised(it.key());
        if (!is_glint_config_key(key)) continue;
        const std::string text = it.value().is_string() ? it.value().get<std::string>() : it.value().dump();
        const std::string where = "config: materials." + material + "." + it.key();
        if (key == "glints_target") {
            object["target"] = text;
            continue;
        }
        if (key == "glints") {
            if (text != "true" && text != "false") return make_error(where + ": must be true or false");
            asked = text == "true";
            continue;
        }
        const ConfigKey* found = nullptr;
        for (const ConfigKey& k : kKeys)
            if (key == k.config) found = &k;
        if (!found) return make_error(where + ": unknown glint key");
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (text.empty() || *end != '\0') return make_error(where + ": '" + text + "' is not a number");
        object[found->extension] = key == "glints_texcoord" ? json(int(v)) : json(v);
    }
    if (!asked) return json();
    return object;
}

Result<std::vector<GlintDecision>> plan_glints(const io::GltfScene& scene,
                                               const std::map<std::string, json>& config_glints) {
    const std::vector<io::MaterialInfo> materials = scene.materials();
    std::vector<GlintDecision> out;
    const std::string file = scene.source().filename().string();
    for (size_t m = 0; m < materials.size(); ++m) {
        const io::MaterialInfo& mat = materials[m];
        auto config = config_glints.find(mat.name);
        const bool by_config = !mat.name.empty() && config != config_glints.end() && !config->second.is_null();
        if (mat.glints.is_null() && !by_config) continue;  // no ask: nothing planned, nothing printed
        json object = mat.glints.is_object() ? mat.glints : json::object();
        if (!mat.glints.is_null() && !mat.glints.is_object())
            return make_error(file + ": material " + std::to_string(m) + ": " + io::kGlintsExtension + " must be an object");
        if (by_config) object.update(config->second);
        const std::string where = file + ": material " + std::to_string(m) + (mat.name.empty() ? "" : " '" + mat.name + "'");
        auto params = io::parse_glint_extension(object, where);
        if (!params) return params.error();
        GlintDecision d;
        d.material = int(m);
        d.material_name = mat.name;
        d.params = *params;
        d.asked_by = mat.glints.is_null() ? "config" : by_config ? "SPECBAKE_glints and config" : io::kGlintsExtension;
        bool has_uv = false;
        for (const io::PrimitiveInfo& p : scene.primitives())
            if (p.material == int(m) && std::count(p.texcoords.begin(), p.texcoords.end(), params->texcoord)) has_uv = true;
        d.normal_map = mat.normal.image >= 0;
        d.bake = has_uv;
        d.reason = has_uv ? "asked by " + d.asked_by + (d.normal_map ? "; slope-space LEAN of the normal map" : "")
                          : "asked by " + d.asked_by + ", but no primitive of it has TEXCOORD_" +
                                std::to_string(params->texcoord);
        out.push_back(std::move(d));
    }
    return out;
}

json glint_decision_json(const GlintDecision& d) {
    return {{"material", d.material},     {"material_name", d.material_name}, {"decision", d.bake ? "bake" : "skip"},
            {"asked_by", d.asked_by},     {"reason", d.reason},               {"parameters", io::glint_material_json(d.params)},
            {"normal_map_lean", d.normal_map && d.bake}};
}

std::string glint_table_lines(const std::vector<GlintDecision>& decisions) {
    std::string out;
    char line[512];
    for (const GlintDecision& d : decisions) {
        const std::string target = "material " + std::to_string(d.material) +
                                   (d.material_name.empty() ? "" : " '" + d.material_name.substr(0, 14) + "'");
        char measured[32];
        std::snprintf(measured, sizeof measured, "ln %.4g", d.params.log_density);
        std::snprintf(line, sizeof line, "  %-10s %-28s %-10s %-11s %-11s %s\n", "glints", target.c_str(),
                      d.bake ? "bake" : "skip", measured, "-", d.reason.c_str());
        out += line;
    }
    return out;
}

}  // namespace specbake
