// The SPECBAKE_glints material extension (io/gltf/SPECBAKE_EXTENSION.md): a material asks for glints (C21)
// and gives their parameters; every field has a default, so {} asks for glints with the defaults.
#pragma once

#include "core/result.h"

#include <nlohmann/json.hpp>

#include <string>

namespace specbake::io {

inline constexpr const char* kGlintsExtension = "SPECBAKE_glints";

struct GlintMaterial {
    double log_density = 15.0;           // "logDensity": ln(microfacets per unit area of the scaled UV)
    double relative_area = 1.0;          // "relativeArea": fraction of cells that carry microfacets, [0, 1]
    double density_randomization = 2.0;  // "densityRandomization": std of the per-cell level jitter, >= 0
    double uv_scale = 1.0;               // "uvScale": the glint UV is uv * uvScale, > 0
    int texcoord = 0;                    // "texCoord": the TEXCOORD_n set the glints use
    std::string target = "beckmann";     // "target": NDF the glints converge to, "beckmann" or "ggx"
};

// Parses and checks the extension object; unknown keys and bad values are errors naming `where`.
Result<GlintMaterial> parse_glint_extension(const nlohmann::json& object, const std::string& where);

// The parameters as resolved, with the extension's key names.
nlohmann::json glint_material_json(const GlintMaterial& g);

}  // namespace specbake::io
