// SPECBAKE_glints: parsing with defaults and range checks.
#include "io/gltf/glint_extension.h"

#include <cmath>

namespace specbake::io {

Result<GlintMaterial> parse_glint_extension(const nlohmann::json& object, const std::string& where) {
    if (!object.is_object()) return make_error(where + ": " + kGlintsExtension + " must be an object");
    GlintMaterial g;
    for (auto it = object.begin(); it != object.end(); ++it) {
        const std::string& key = it.key();
        const nlohmann::json& v = it.value();
        if (key == "extensions" || key == "extras") continue;
        if (key == "target") {
            if (!v.is_string() || (v.get<std::string>() != "beckmann" && v.get<std::string>() != "ggx"))
                return make_error(where + ": target must be \"beckmann\" or \"ggx\"");
            g.target = v.get<std::string>();
            continue;
        }
        if (key == "texCoord") {
            if (!v.is_number_integer() || v.get<int>() < 0) return make_error(where + ": texCoord must be an integer >= 0");
            g.texcoord = v.get<int>();
            continue;
        }
        double* target = key == "logDensity"             ? &g.log_density
                         : key == "relativeArea"         ? &g.relative_area
                         : key == "densityRandomization" ? &g.density_randomization
                         : key == "uvScale"              ? &g.uv_scale
                                                         : nullptr;
        if (!target) return make_error(where + ": " + kGlintsExtension + " has no field '" + key + "'");
        if (!v.is_number() || !std::isfinite(v.get<double>()))
            return make_error(where + ": " + key + " must be a finite number");
        *target = v.get<double>();
    }
    if (g.log_density < 0.0 || g.log_density > 60.0) return make_error(where + ": logDensity must be in [0, 60]");
    if (g.relative_area < 0.0 || g.relative_area > 1.0) return make_error(where + ": relativeArea must be in [0, 1]");
    if (g.density_randomization < 0.0 || g.density_randomization > 16.0)
        return make_error(where + ": densityRandomization must be in [0, 16]");
    if (!(g.uv_scale > 0.0) || g.uv_scale > 1e4) return make_error(where + ": uvScale must be in (0, 10000]");
    return g;
}

nlohmann::json glint_material_json(const GlintMaterial& g) {
    return {{"logDensity", g.log_density},
            {"relativeArea", g.relative_area},
            {"densityRandomization", g.density_randomization},
            {"uvScale", g.uv_scale},
            {"texCoord", g.texcoord},
            {"target", g.target}};
}

}  // namespace specbake::io
