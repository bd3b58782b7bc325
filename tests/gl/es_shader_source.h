// The GLSL ES 3.00 (WebGL 2) shaders the tests compile with glslang (tests/gl/test_shader_es.cpp) and with
// Chromium's WebGL 2 (tests/consumers/webgl_shader_test.cpp): one fragment shader per entry point and binding
// of shaders/cost/entries.list (the rows of the cost table in docs/shader-include.md), one per configuration
// macro of that page's table, and the minimal example's use. Each is assembled as a WebGL 2 application
// would (no #include there): #version, the #defines, highp sampler uniforms, the include's text
// (`specbake shader --lang glsl-es`), shaders/cost/entries.inc and a main(); a vertex shader writes every
// input, so the pair links.
#pragma once

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace specbake::es_shaders {

struct Variant {
    std::string name;
    std::vector<std::string> defines;  // NAME or NAME=VALUE
};

inline std::vector<std::string> split_words(const std::string& text) {
    std::istringstream in(text);
    std::vector<std::string> words;
    for (std::string w; in >> w;) words.push_back(w);
    return words;
}

inline std::string read_text(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

// The configuration macros of docs/shader-include.md#configuration-macros (and the glint cap of
// docs/glints.md), each on top of the entry point and binding it changes.
inline std::vector<Variant> configuration_variants() {
    const std::string ndf = "SPECAA_COST_DEFAULT_NDF SPECAA_COST_TEXTURES ";
    const std::string sigma = ndf + "SPECAA_KERNEL_TEXTURE=uBaked0 SPECAA_KERNEL_ANISOTROPIC ";
    const std::vector<std::pair<std::string, std::string>> rows = {
        {"default + Sigma kernel, SPECAA_KERNEL_COVARIANCE", sigma + "SPECAA_KERNEL_COVARIANCE"},
        {"default + Sigma kernel, SPECAA_KERNEL_GATE 0", sigma + "SPECAA_KERNEL_GATE=0.0"},
        {"default + Sigma kernel, SPECAA_NO_BAKED_KERNEL", sigma + "SPECAA_NO_BAKED_KERNEL"},
        {"default + Sigma kernel, SPECAA_DEFAULT_D_WEIGHT 0", sigma + "SPECAA_DEFAULT_D_WEIGHT=0.0"},
        {"default + Sigma kernel, SPECAA_KERNEL_LOD_BIAS -1", sigma + "SPECAA_KERNEL_LOD_BIAS=-1.0"},
        {"default + Sigma kernel, SPECAA_KERNEL_AREA_LOD", sigma + "SPECAA_KERNEL_AREA_LOD"},
        {"default + Sigma kernel, SPECAA_GATE_PIXEL_KERNEL", sigma + "SPECAA_GATE_PIXEL_KERNEL"},
        {"default + Sigma kernel, SPECAA_BLEND_FROM_BAKED_SPREAD", sigma + "SPECAA_BLEND_FROM_BAKED_SPREAD"},
        {"default + Sigma kernel, two lobes, SPECAA_BLEND_FROM_BAKED_SPREAD",
         sigma + "SPECAA_KERNEL_TWO_LOBES SPECAA_BLEND_FROM_BAKED_SPREAD"},
        {"default + Sigma kernel, SPECAA_USE_CURVATURE", sigma + "SPECAA_USE_CURVATURE"},
        {"default + Sigma kernel, SPECAA_NO_PIXEL_KERNEL", sigma + "SPECAA_NO_PIXEL_KERNEL"},
        {"default + Sigma kernel, SPECAA_SIGMA2 SPECAA_KAPPA SPECAA_GGX_SPREAD",
         sigma + "SPECAA_SIGMA2=0.1 SPECAA_KAPPA=0.3 SPECAA_GGX_SPREAD=4.0"},
        {"default + LEAN", ndf + "SPECAA_LEAN_TEXTURE0=uBaked0 SPECAA_LEAN_TEXTURE1=uBaked1"},
        {"default + roughness texture, SPECAA_ROUGHNESS_CHANNEL r",
         ndf + "SPECAA_ROUGHNESS_TEXTURE=uBaked0 SPECAA_ROUGHNESS_CHANNEL=r"},
        {"default, derivatives only, SPECAA_USE_CURVATURE", "SPECAA_COST_DEFAULT_NDF SPECAA_USE_CURVATURE"},
        {"glints, SPECAA_GLINT_MAX_CELLS 16", "SPECAA_COST_GLINT SPECAA_GLINT_MAX_CELLS=16"},
    };
    std::vector<Variant> out;
    for (const auto& [name, defines] : rows) out.push_back({name, split_words(defines)});
    return out;
}

// Every row of shaders/cost/entries.list, then the configuration variants.
inline std::vector<Variant> all_variants(const std::string& source_dir) {
    std::istringstream list(read_text(source_dir + "/shaders/cost/entries.list"));
    std::vector<Variant> out;
    for (std::string line; std::getline(list, line);) {
        if (line.empty() || line[0] == '#') continue;
        const auto bar = line.find('|');
        out.push_back({line.substr(0, bar), split_words(bar == std::string::npos ? "" : line.substr(bar + 1))});
    }
    for (auto& v : configuration_variants()) out.push_back(std::move(v));
    return out;
}

inline std::string fragment_source(const std::string& include, const std::string& entries_inc, const Variant& v) {
    std::string s = "#version 300 es\n";
    for (const auto& d : v.defines) {
        const auto eq = d.find('=');
        s += "#define " + (eq == std::string::npos ? d : d.substr(0, eq) + " " + d.substr(eq + 1)) + "\n";
    }
    s += "#if defined(SPECAA_COST_TEXTURES)\n"
         "uniform highp sampler2D uBaked0;\n"
         "uniform highp sampler2D uBaked1;\n"
         "#endif\n"
         "#if defined(SPECAA_COST_GLINT)\n"
         "uniform highp sampler2DArray uGlintDictionary;\n"
         "#define SPECAA_COST_GLINT_DICTIONARY uGlintDictionary\n"
         "#endif\n";
    s += include;
    s += entries_inc;
    s += "in vec3 vHalfVector;\nin vec3 vNormal;\nin vec3 vPosition;\nin vec4 vTangent;\nin vec4 vCurvature;\n"
         "in vec2 vUv;\nin float vRoughness;\nin vec3 vView;\nout vec4 fragColor;\n"
         "void main() {\n"
         "    fragColor = specaa_cost_eval(vHalfVector, vNormal, vPosition, vTangent, vCurvature, vUv, vRoughness, vView);\n"
         "}\n";
    return s;
}

inline std::string vertex_source() {
    return "#version 300 es\n"
           "in vec4 aPosition;\n"
           "out vec3 vHalfVector;\nout vec3 vNormal;\nout vec3 vPosition;\nout vec4 vTangent;\nout vec4 vCurvature;\n"
           "out vec2 vUv;\nout float vRoughness;\nout vec3 vView;\n"
           "void main() {\n"
           "    vHalfVector = normalize(aPosition.xyz + vec3(0.0, 0.0, 2.0));\n"
           "    vNormal = vec3(0.0, 0.0, 1.0);\n"
           "    vPosition = aPosition.xyz;\n"
           "    vTangent = vec4(1.0, 0.0, 0.0, 1.0);\n"
           "    vCurvature = vec4(0.5, 0.25, 1.0, 0.0);\n"
           "    vUv = aPosition.xy * 0.5 + 0.5;\n"
           "    vRoughness = 0.3;\n"
           "    vView = normalize(vec3(0.0, 0.0, 3.0) - aPosition.xyz);\n"
           "    gl_Position = aPosition;\n"
           "}\n";
}

// Deliberately broken variants of the include that a real ES compiler must reject, and a line of its
// expected message; they show that the checks above can fail.
struct Broken {
    std::string name;
    std::string include;
    Variant variant;
};

inline std::vector<Broken> broken_variants(const std::string& es_include, const std::string& desktop_include) {
    std::vector<Broken> out;
    // The desktop include with only float and int given a precision, as the issue that asked for the ES
    // variant found it: GLSL ES has no default precision for the glints' sampler2DArray parameter.
    out.push_back({"desktop include with float and int precision, glints",
                   "precision highp float;\nprecision highp int;\n" + desktop_include,
                   {"glints", {"SPECAA_COST_GLINT"}}});
    // The ES include with its LOD path switched to textureQueryLod, which GLSL ES does not have.
    std::string query_lod = es_include;
    const std::string guard = "#if __VERSION__ >= 400 && !defined(GL_ES)";
    if (const auto at = query_lod.find(guard); at != std::string::npos) query_lod.replace(at, guard.size(), "#if 1");
    out.push_back({"textureQueryLod in the LOD path, default + kernel", query_lod,
                   {"default + kernel", split_words("SPECAA_COST_DEFAULT_NDF SPECAA_COST_TEXTURES SPECAA_KERNEL_TEXTURE=uBaked0")}});
    return out;
}

}  // namespace specbake::es_shaders
