#include "verify/candidates.h"

#include "verify/engine_peers.h"

#include <algorithm>
#include <tuple>

namespace specbake::verify {
namespace {

// Bodies set `vec3 A` (xx, yy, xy) from: float a (material alpha^2), float alpha, vec3 hTS, vec3 n (world
// shading normal), vec3 nGeo (world vertex normal), SpecaaSurface s, float viewDepth.
SimCandidate derivative(const char* name, const char* source, const char* body) {
    return {name, "derivative", source, {"", body, "exact", ""}, "", ""};
}

const char* kBakedRoughnessDefines =
    "#define SPECAA_ROUGHNESS_TEXTURE uBakedRoughness\n#define SPECAA_ROUGHNESS_CHANNEL r\n";
// The bake's default kernel mips hold Sigma (xx, yy, xy); "-isotropic-kernel" bakes hold t = tr(Sigma).
const char* kBakedKernelDefines = "#define SPECAA_KERNEL_TEXTURE uBakedKernel\n#define SPECAA_KERNEL_ANISOTROPIC\n";
const char* kBakedIsotropicKernelDefines = "#define SPECAA_KERNEL_TEXTURE uBakedKernel\n";
const char* kIsotropicKernelBake = "mean-projected-isotropic-kernel";
const char* kIsotropicDefault = "float f = specaa_filtered_alpha2(s); A = vec3(f, f, 0.0);";
const char* kMatrixDefault = "A = specaa_filtered_alpha2_matrix(s);";
// The default NDF: GGX of the material (or baked) roughness convolved with the footprint (the include's
// specaa_convolved_D), in place of GGX of the widened matrix.
const char* kConvolvedNdf = "#define SIM_NDF(h, A, a) specaa_convolved_D(h, A, specaa_base_alpha2(s))\n";
const char* kDefaultNdf = "#define SIM_NDF(h, A, a) specaa_default_D(h, A, s)\n";

void add_variants(std::vector<SimCandidate>& c, bool normal_mapped);

// The unfiltered baseline, the derivative-based rules of K16 and TK21, and the peers' rules (VAREF,
// Filament).
void add_derivative_and_peer_candidates(std::vector<SimCandidate>& c) {
    c.push_back({"none", "none", "unfiltered GGX", {"", "A = vec3(a, a, 0.0);", "exact", ""}, "", ""});
    c.push_back(derivative("slope", "K16, TK21 Eq. (2)", "A = specaa_slope(vec2(a), hTS);"));
    c.push_back(derivative("slope-aa", "K16, TK21 Listing 3 in slope space",
                           "A = vec3(specaa_slope_aa(vec2(a), hTS), 0.0);"));
    c.push_back(derivative("projected-approx", "TK21 Eq. (9), Listing 2",
                           "A = specaa_projected_approx(vec2(a), hTS);"));
    c.push_back(derivative("projected-aa", "TK21 Listing 3", "A = vec3(specaa_projected_aa(vec2(a), hTS), 0.0);"));
    c.push_back(derivative("projected", "TK21 Eq. (4)-(8), Listing 1", "A = specaa_projected(vec2(a), hTS);"));
    c.push_back(derivative("iso-max", "TK21 Eq. (10)", "float f = specaa_iso_max(a, n); A = vec3(f, f, 0.0);"));
    c.push_back(derivative("iso-sum", "TK21 Eq. (13), Listing 5", "float f = specaa_iso_sum(a, n); A = vec3(f, f, 0.0);"));
    c.push_back(derivative("iso-mean", "TK21 Eq. (14)", "float f = specaa_iso_mean(a, n); A = vec3(f, f, 0.0);"));
    // VAREF Sec. 2-4: alpha' = alpha + sigma_g^2, r' = sqrt(alpha') clamped to [0.04, 1], SCALE 50, cap 0.1.
    c.push_back({"varef-screen", "peer", "VAREF Sec. 3A",
                 {"",
                  "vec3 dnx = dFdx(n); vec3 dny = dFdy(n);\n"
                  "        float var = min(50.0 * max(dot(dnx, dnx), dot(dny, dny)), 0.1);\n"
                  "        float r = clamp(sqrt(alpha + var), 0.04, 1.0); float f = r * r * r * r;\n"
                  "        A = vec3(f, f, 0.0);",
                  "exact", ""},
                 "", ""});
    c.push_back({"varef-curvature", "peer", "VAREF Sec. 3B",
                 {"",
                  "float px = specaa_pixel_footprint_from_depth(viewDepth, uTanHalfFovY, uViewportHeight);\n"
                  "        float var = min(50.0 * (px * abs(vCurvature.x)) * (px * abs(vCurvature.x)), 0.1);\n"
                  "        float r = clamp(sqrt(alpha + var), 0.04, 1.0); float f = r * r * r * r;\n"
                  "        A = vec3(f, f, 0.0);",
                  "exact", ""},
                 "", "exact"});
    // Filament's geometric specular AA (normalFiltering in its shading code): variance
    // 0.15 (|dN/dx|^2 + |dN/dy|^2) of the geometric normal, kernel min(2 variance, 0.2) added to alpha^2.
    c.push_back({"filament", "peer", "Filament normalFiltering (variance 0.15, threshold 0.2)",
                 {"",
                  "vec3 dnx = dFdx(nGeo); vec3 dny = dFdy(nGeo);\n"
                  "        float f = clamp(a + min(2.0 * 0.15 * (dot(dnx, dnx) + dot(dny, dny)), 0.2), 0.0, 1.0);\n"
                  "        A = vec3(f, f, 0.0);",
                  "exact", ""},
                 "", ""});
    // Engines' run-time filters (bake/peers.h, verify/engine_peers.h), each on the normal it uses: the
    // shading normal n (Godot, Babylon.js) or the interpolated vertex normal nGeo (Unity HDRP, three.js).
    const auto engine = [&](const char* name, const char* source, const char* call) {
        c.push_back({name, "peer", source,
                     {kEnginePeersGlsl, std::string("float f = ") + call + "; A = vec3(f, f, 0.0);", "exact", ""},
                     "", ""});
    };
    engine("godot", "Godot 4 roughness limiter (amount 0.25, limit 0.18; on r^2, shading normal)",
           "peer_godot_alpha2(sqrt(alpha), dFdx(n), dFdy(n))");
    engine("unity-hdrp", "Unity HDRP geometric specular AA (screen-space variance 0.1, threshold 0.2)",
           "peer_unity_alpha2(a, dFdx(nGeo), dFdy(nGeo))");
    engine("threejs", "three.js geometryRoughness (added to r, floor 0.0525)",
           "peer_threejs_alpha2(sqrt(alpha), dFdx(nGeo), dFdy(nGeo))");
    engine("babylon", "Babylon.js SPECULARAA, analytic lights (r = max(r, slope^(2/3)); shading normal)",
           "peer_babylon_alpha2(sqrt(alpha), dFdx(n), dFdy(n))");
}

// The rules that read baked data: curvature, and where the scene is normal-mapped the roughness mips.
void add_baked_candidates(std::vector<SimCandidate>& c, bool normal_mapped) {
    c.push_back({"baked-curvature", "baked", "SPEC Sec. 4-5: _SPECAA_CURVATURE kernel, TK21 Eq. (3)",
                 {"#define SPECAA_USE_CURVATURE\n", kIsotropicDefault, "exact", ""}, "", "exact"});
    c.push_back({"baked-curvature-matrix", "baked", "SPEC Sec. 4-5: anisotropic _SPECAA_CURVATURE kernel, TK21 Eq. (3)",
                 {"#define SPECAA_USE_CURVATURE\n", "A = specaa_filtered_alpha2_matrix(s);", "exact", ""}, "", "exact"});
    if (normal_mapped) {
        c.push_back({"baked-texture", "baked", "SPEC Sec. 3 filtered roughness mips",
                     {std::string(kBakedRoughnessDefines) + "#define SPECAA_NO_PIXEL_KERNEL\n", kIsotropicDefault,
                      "exact", "mean-projected"},
                     "mean-projected", ""});
        // Engines' offline roughness mips (bake/peer_roughness_bake.h), shaded as the engine does: the baked
        // roughness alone.
        for (const auto& [name, source, bake] :
             {std::tuple{"filament-prefilter", "Filament roughness-prefilter (vMF, r' = sqrt(r^2 + 2 / kappa))", "peer-filament"},
              std::tuple{"godot-importer", "Godot 4 importer roughness mips (r' = sqrt(r^2 + min(0.75 / kappa, 0.16)))", "peer-godot"},
              std::tuple{"unity-hdrp-nf", "Unity HDRP NormalMapFilteringTexturePostprocessor (var = min(1 / (4 kappa), 0.03125), a' = a + min(2 var, 0.2^2))", "peer-unity"},
              std::tuple{"unreal-toksvig", "Unreal 5 composite texture, Toksvig (var = (1 - |N|) / |N| - 4e-5, a' = (B - a) / (B - 1), B = 2 var (a - 1))", "peer-unreal"}})
            c.push_back({name, "peer", source,
                         {std::string(kBakedRoughnessDefines) + "#define SPECAA_NO_PIXEL_KERNEL\n", kIsotropicDefault,
                          "exact", bake},
                         bake, ""});
    }
}

// The default rule (the matrix form) with its NDFs and baked inputs, and its isotropic, curvature, tails
// and clamped forms.
void add_default_candidates(std::vector<SimCandidate>& c, bool normal_mapped) {
    // The matrix form with the NDF `ndf` defines; where the scene is normal-mapped, with the baked data
    // `baked` binds: the Sigma kernel mips or t mips with the material's roughness, or the baked roughness.
    enum class Baked { Kernel, IsotropicKernel, Roughness };
    const auto matrix_default = [&](const char* name, const char* source, const std::string& ndf, Baked baked) {
        const char* defines = !normal_mapped                   ? ""
                              : baked == Baked::Kernel          ? kBakedKernelDefines
                              : baked == Baked::IsotropicKernel ? kBakedIsotropicKernelDefines
                                                                : kBakedRoughnessDefines;
        const std::string bake = !normal_mapped ? "" : baked == Baked::IsotropicKernel ? kIsotropicKernelBake : "mean-projected";
        c.push_back({name, "default", source, {defines + ndf, kMatrixDefault, "exact", bake}, bake, ""});
    };
    // The default reads the per-vertex curvature the scene bake writes (_SPECAA_CURVATURE, SPECAA_USE_CURVATURE):
    // a pixel kernel continuous across triangle edges (docs/accuracy.md#the-default-rule-and-the-curvature-it-reads).
    matrix_default("default",
                   "specaa_filtered_alpha2_matrix with specaa_default_D (baked Sigma kernel mips + anisotropic "
                   "per-pixel kernel from the baked curvature; GGX convolved with the footprint, GGX of the matrix "
                   "where the spread is broad in every direction)",
                   std::string("#define SPECAA_USE_CURVATURE\n") + kDefaultNdf, Baked::Kernel);
    c.back().curvature_bake = c.back().shader.curvature_source = "exact";
    // The same without the curvature attribute: the per-pixel kernel from the quad derivatives of the normal.
    matrix_default("default-derivatives",
                   "specaa_filtered_alpha2_matrix with specaa_default_D, the per-pixel kernel from quad derivatives "
                   "(no curvature attribute bound)",
                   kDefaultNdf, Baked::Kernel);
    // The include's cheaper quality tiers (SPECAA_QUALITY; the default above is the reference tier), each on
    // the baked data it is meant for: the rows an engine's own filter is held against (bench summary).
    const auto tier = [&](const char* name, const char* source, const char* quality, Baked baked) {
        matrix_default(name, source, std::string("#define SPECAA_QUALITY ") + quality + "\n" + kDefaultNdf, baked);
        c.back().family = "tier";
    };
    tier("fast",
         "SPECAA_QUALITY_FAST on the baked roughness: the isotropic filtered roughness, two lobes fitted to the "
         "convolution with the material's tails kept (TK21 Sec. 7)",
         "0", Baked::Roughness);
    tier("balanced",
         "SPECAA_QUALITY_BALANCED on the baked roughness: the fast tier's isotropic filtered roughness, GGX convolved "
         "with the footprint in closed form",
         "1", Baked::Roughness);
    if (normal_mapped)
        matrix_default("default-isotropic-kernel",
                       "specaa_filtered_alpha2_matrix with specaa_default_D on the isotropic kernel mips (t = tr Sigma; "
                       "--isotropic-kernel)",
                       kDefaultNdf, Baked::IsotropicKernel);
    if (normal_mapped)
        matrix_default("default-two-lobes",
                       "specaa_filtered_alpha2_matrix with specaa_default_D, SPECAA_KERNEL_TWO_LOBES (the Sigma kernel "
                       "texel as its flat share's lobe and its rough share's, alpha = rough share)",
                       std::string("#define SPECAA_KERNEL_TWO_LOBES\n") + kDefaultNdf, Baked::Kernel);
    matrix_default("default-roughness",
                   "specaa_filtered_alpha2_matrix on the baked roughness with specaa_default_D (convolution under "
                   "magnification, GGX of the matrix from mip 1)",
                   kDefaultNdf, Baked::Roughness);
    matrix_default("default-ggx", "specaa_filtered_alpha2_matrix on the baked roughness with specaa_ggx_D (GGX of the widened matrix)", "", Baked::Roughness);
    matrix_default("default-convolved",
                   "specaa_filtered_alpha2_matrix on the baked roughness with specaa_convolved_D everywhere (GGX of "
                   "the baked roughness convolved with the footprint)",
                   kConvolvedNdf, Baked::Roughness);
    if (normal_mapped)
        matrix_default("default-kernel-convolved",
                       "specaa_filtered_alpha2_matrix on the baked kernel mips with specaa_convolved_D everywhere (the "
                       "texel's and the pixel's spread convolved as one Gaussian)",
                       kConvolvedNdf, Baked::Kernel);
    c.push_back({"default-isotropic", "default", "specaa_filtered_alpha2 (isotropic form of the default)",
                 {normal_mapped ? kBakedRoughnessDefines : "", kIsotropicDefault, "exact", "mean-projected"},
                 normal_mapped ? "mean-projected" : "", ""});
    c.push_back({"default+curvature", "default", "specaa_filtered_alpha2_matrix with SPECAA_USE_CURVATURE",
                 {std::string(normal_mapped ? kBakedRoughnessDefines : "") + "#define SPECAA_USE_CURVATURE\n",
                  kMatrixDefault, "exact", "mean-projected"},
                 normal_mapped ? "mean-projected" : "", "exact"});
    matrix_default("default-tails",
                   "specaa_filtered_alpha2_matrix with specaa_filtered_D (tail weight of the baked roughness along the "
                   "half vector, TK21 Sec. 7)",
                   "#define SIM_NDF(h, A, a) specaa_filtered_D(h, A, specaa_base_alpha2(s))\n", Baked::Roughness);
    // The matrix form with each eigenvalue of A clamped to the isotropic form's a: the matrix's shape where
    // the footprint is round, the isotropic width along an axis the matrix widens beyond it
    // (docs/accuracy.md#other-rules-measured-and-not-kept: where the matrix over-blurs, its tails along the
    // widened axis).
    c.push_back({"default-clamped", "default",
                 "specaa_filtered_alpha2_matrix, eigenvalues clamped to specaa_filtered_alpha2",
                 {normal_mapped ? kBakedRoughnessDefines : "",
                  "vec3 Am = specaa_filtered_alpha2_matrix(s); float fi = specaa_filtered_alpha2(s);\n"
                  "        float hm = 0.5 * (Am.x + Am.y), dm = sqrt(0.25 * (Am.x - Am.y) * (Am.x - Am.y) + Am.z * Am.z);\n"
                  "        float l1 = hm + dm, l2 = hm - dm;\n"
                  "        vec2 v = abs(Am.z) > 1.0e-20 ? normalize(vec2(Am.z, l1 - Am.x)) : (Am.x >= Am.y ? vec2(1.0, 0.0) : vec2(0.0, 1.0));\n"
                  "        float m1 = min(l1, fi), m2 = min(l2, fi);\n"
                  "        A = vec3(m1 * v.x * v.x + m2 * v.y * v.y, m1 * v.y * v.y + m2 * v.x * v.x, (m1 - m2) * v.x * v.y);",
                  "exact", "mean-projected"},
                 normal_mapped ? "mean-projected" : "", ""});
}

// Scene files: curvature comes from the given estimator (`specbake bake` writes the default one), and is
// timed as the candidates' bake; its own variant row would repeat "baked-curvature".
void use_estimated_curvature(std::vector<SimCandidate>& c, const std::string& estimator) {
    std::erase_if(c, [&](const SimCandidate& x) { return x.name == "baked-curvature/" + estimator; });
    for (SimCandidate& x : c) {
        if (x.curvature_bake != "exact") continue;
        x.curvature_bake = estimator;
        x.shader.curvature_source = estimator;
    }
}

}  // namespace

std::vector<SimCandidate> simulator_candidates(const SimScene& scene, bool variants, const std::string& estimator) {
    const bool normal_mapped = std::any_of(scene.objects.begin(), scene.objects.end(),
                                           [](const SimObject& o) { return o.material.normal_map >= 0; });
    std::vector<SimCandidate> c;
    add_derivative_and_peer_candidates(c);
    add_baked_candidates(c, normal_mapped);
    add_default_candidates(c, normal_mapped);
    if (variants) add_variants(c, normal_mapped);
    if (!has_exact_curvature(scene)) use_estimated_curvature(c, estimator);
    return c;
}

namespace {

// The bake's own variants (sim_candidates.h).
void add_variants(std::vector<SimCandidate>& c, bool normal_mapped) {
    if (normal_mapped) {
        const std::pair<const char*, const char*> texture_variants[] = {
            {"baked-texture/approx", "mean-approx"}, {"baked-texture/sum", "sum-projected"},
            {"baked-texture/max", "max-projected"}};
        for (const auto& [name, key] : texture_variants)
            c.push_back({name, "variant", "SPEC Sec. 3 bake variant",
                         {std::string(kBakedRoughnessDefines) + "#define SPECAA_NO_PIXEL_KERNEL\n",
                          kIsotropicDefault, "exact", key},
                         key, ""});
        c.push_back({"baked-kernel", "variant", "SPEC Sec. 3 kernel mips (t, mean), added at run time",
                     {std::string(kBakedIsotropicKernelDefines) + "#define SPECAA_NO_PIXEL_KERNEL\n",
                      kIsotropicDefault, "exact", kIsotropicKernelBake},
                     kIsotropicKernelBake, ""});
        c.push_back({"baked-lean", "variant", "SPEC Sec. 3 LEAN moments (C21 Eq. 16)",
                     {"#define SPECAA_LEAN_TEXTURE0 uBakedLean0\n#define SPECAA_LEAN_TEXTURE1 uBakedLean1\n"
                      "#define SPECAA_NO_PIXEL_KERNEL\n",
                      kIsotropicDefault, "exact", "mean-projected"},
                     "mean-projected", ""});
    }
    for (const char* estimator : {"shape-operator", "patch", "second-order", "jet-fitting", "normal-cone"}) {
        c.push_back({std::string("baked-curvature/") + estimator, "variant", "SPEC Sec. 4 estimator",
                     {"#define SPECAA_USE_CURVATURE\n", kIsotropicDefault, estimator, ""}, "", estimator});
    }
}

}  // namespace

std::vector<SimCandidate> glint_candidates(const SimScene& scene) {
    std::vector<SimCandidate> c;
    if (!has_glints(scene)) return c;
    const bool normal_mapped = std::any_of(scene.objects.begin(), scene.objects.end(), [](const SimObject& o) {
        return o.material.glints.enabled && o.material.normal_map >= 0;
    });
    const auto glint = [](const char* name, const char* source, std::string defines, const char* bake) {
        SimShaderSpec spec;
        spec.defines = std::move(defines);
        spec.glint = true;
        spec.baked_source = bake;
        return SimCandidate{name, "glint", source, spec, bake, ""};
    };
    c.push_back(glint("glint-smooth", "C20/C21 smooth BRDF: analytic SDF, V-cavity", "#define SIM_GLINT_SMOOTH\n", ""));
    c.push_back(glint("glint-c20", "C20: glints without anti-aliasing", "#define SIM_GLINT_KERNEL_SCALE 0.0\n", ""));
    c.push_back(glint("glint-ggaa", "C21 Eq. 15, 19, 21 (s_K = 0.5)", "#define SIM_GLINT_KERNEL_SCALE 0.5\n", ""));
    if (normal_mapped) {
        c.push_back(glint("glint-ggaa+lean-norho", "C21 Sec. 5, LEAN with rho = 0",
                          "#define SIM_GLINT_KERNEL_SCALE 0.5\n#define SIM_GLINT_LEAN 1\n", "slope-lean"));
        c.push_back(glint("glint-ggaa+lean", "C21 Sec. 5, Eq. 16, 18: slope-space LEAN with rho",
                          "#define SIM_GLINT_KERNEL_SCALE 0.5\n#define SIM_GLINT_LEAN 2\n", "slope-lean"));
    }
    return c;
}

std::vector<SimTextureBake> texture_bakes_for(const std::vector<SimCandidate>& candidates) {
    std::vector<SimTextureBake> bakes;
    for (const SimCandidate& c : candidates) {
        if (c.texture_bake.empty()) continue;
        if (std::any_of(bakes.begin(), bakes.end(), [&](const SimTextureBake& b) { return b.key == c.texture_bake; }))
            continue;
        TextureBakeSettings s;
        const std::string& k = c.texture_bake;
        s.isotropic = k.starts_with("sum") ? IsotropicReduction::Sum
                      : k.starts_with("max") ? IsotropicReduction::Max
                                             : IsotropicReduction::Mean;
        s.filter = k.ends_with("approx") ? RoughnessFilterMode::Approx : RoughnessFilterMode::Projected;
        s.outputs.normal = false;
        // The simulator shades the glTF decode (scene_file.cpp: the stored blue channel), so the bake reads
        // the same normals.
        s.reconstruct_z = ReconstructZ::Gltf;
        // The glint materials' LEAN (pipeline/glint_bake.h): slope space, the base roughness folded in.
        if (k == "slope-lean") s.lean_space = LeanSpace::Slope;
        s.anisotropic = !k.ends_with("isotropic-kernel");
        std::optional<PeerRoughnessBake> peer;
        if (k == "peer-filament") peer = PeerRoughnessBake::Filament;
        if (k == "peer-godot") peer = PeerRoughnessBake::Godot;
        if (k == "peer-unity") peer = PeerRoughnessBake::UnityHdrp;
        if (k == "peer-unreal") peer = PeerRoughnessBake::Unreal;
        bakes.push_back({k, s, peer});
    }
    return bakes;
}

std::vector<SimCurvatureBake> curvature_bakes_for(const std::vector<SimCandidate>& candidates) {
    std::vector<SimCurvatureBake> bakes;
    for (const SimCandidate& c : candidates) {
        const std::string& k = c.shader.curvature_source;
        if (k == "exact" ||
            std::any_of(bakes.begin(), bakes.end(), [&](const SimCurvatureBake& b) { return b.key == k; }))
            continue;
        bakes.push_back({k, parse_curvature_estimator(k)});
    }
    return bakes;
}

}  // namespace specbake::verify
