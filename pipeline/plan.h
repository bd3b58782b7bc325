// The bake plan (SPEC Sec. 6): per material and per primitive, what a scene bake computes and why, with the
// threshold and the measured value behind each decision. `specbake plan` prints it, `specbake bake` does
// exactly what it says and records it in the manifest.
//
// Texture bake of a material layer (the base, and the clear coat of KHR_materials_clearcoat, each with its
// own normal texture and roughness): only when it has a normal texture that can be decoded, some primitive
// samples it with texture coordinates, and the bake changes the output visibly: the largest change of
// perceptual roughness r over every texel of every mip level (TextureBakeResult::max_roughness_change) is
// at least half a quantisation step of the roughness output (0.5 / 255 for 8-bit roughness, 0.5 / 65535
// for 16-bit, 2^-11 for half/float).
//
// Curvature of a primitive: only when
//  1. its material is glossy enough to alias: the largest geometric kernel the run time applies (the
//     clamp kappa = 0.18, SPEC Sec. 2) raises the material's lowest roughness r_min by at least
//     `min_roughness_gain` (0.05 by default). The filtered roughness is the projected-space closed form of
//     SPEC Sec. 3, a' = (a + kappa (1 - a)) / (1 + kappa (1 - a)), a = r^4, so the measured value is
//     a'^(1/4) - r_min. 0.05 is reached at r_min ~ 0.74; a material with r_min = 0.9 gains 0.007 and is
//     left alone. r_min = roughnessFactor times the smallest roughness texel (G channel) when the material
//     has a metallicRoughness texture; with a clear coat (clearcoatFactor > 0 or a clearcoatTexture) the
//     smaller of that and the coat's clearcoatRoughnessFactor times its smallest texel; no material means
//     the glTF default, r = 1.
//  2. its shading normals actually curve: p95(|k1|) times the bounding-box diagonal (the normal's turn, in
//     radians, across the primitive at the 95th percentile of vertices; ~2 for a sphere, 0 for a plane or
//     a faceted box) is at least `min_relative_curvature` (0.05 by default).
//  3. it is a triangle surface (mode 4, 5 or 6) with normals (without NORMAL, glTF shades it flat).
// Curvature is in object space: a node scale s divides it by s in world space (the run time applies the
// node transform); the plan records each primitive's instance scales.
//
// Glints: only for materials that ask (pipeline/glint_plan.h); other scenes' plans have no glint entry.
#pragma once

#include "core/result.h"
#include "bake/texture_bake.h"
#include "io/files/input_policy.h"
#include "io/gltf/gltf_scene.h"
#include "io/image/image_io.h"
#include "mesh/curvature.h"
#include "core/trimesh.h"
#include "mesh/validate_mesh.h"
#include "pipeline/glint_plan.h"

#include <nlohmann/json.hpp>

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace specbake {

struct TextureDecision;
struct TextureWork;

// Receives a texture bake the plan decided to keep, with its decision and inputs (see PlanOptions).
using TextureBakeSink = std::function<Result<void>(const TextureDecision&, const TextureWork&, TextureBakeResult&&)>;

// A texture bake held encoded (the row-streaming bake of pipeline/texture_job.h, no float chains): the
// statistic and notes the plan decides on, and `write`, called once if the plan keeps the bake.
struct EncodedTextureBake {
    double max_roughness_change = 0.0;
    TextureBakeNotes notes;
    std::function<Result<void>(const TextureDecision&)> write;
};
// Bakes one texture's inputs with `settings`; errors are the bake's own ("normal map: ...").
using TextureBakeEncoder =
    std::function<Result<EncodedTextureBake>(const TextureDecision&, const TextureWork&, const TextureBakeSettings&)>;

// TextureBakeSettings with the glTF normal decode (scene bakes: what a glTF viewer shades).
inline TextureBakeSettings gltf_texture_settings() {
    TextureBakeSettings s;
    s.reconstruct_z = ReconstructZ::Gltf;
    return s;
}

struct PlanOptions {
    bool textures = true;                 // false: curvature only (`specbake mesh`)
    bool check_material = true;           // false: curvature regardless of material roughness (`specbake mesh`)
    double kappa = 0.18;                  // kernel clamp, SPEC Sec. 2
    double min_roughness_gain = 0.05;
    double min_relative_curvature = 0.05;
    CurvatureEstimator estimator = kDefaultCurvatureEstimator;
    int threads = 0;
    // What the scene may make the job read and allocate: the scene is loaded and its images decoded under it.
    io::InputPolicy input_policy;
    // The statistic is measured with the settings the bake uses. Scene bakes decode normal textures as glTF
    // does (the stored blue channel, ReconstructZ::Gltf) unless told otherwise.
    TextureBakeSettings texture_settings = gltf_texture_settings();
    // Settings of the materials named here (config [materials.NAME]); every other material uses
    // texture_settings.
    std::map<std::string, TextureBakeSettings> material_texture_settings;

    // The texture-bake settings of the material called `material`.
    const TextureBakeSettings& texture_settings_for(const std::string& material) const {
        auto it = material_texture_settings.find(material);
        return it == material_texture_settings.end() ? texture_settings : it->second;
    }

    // Set by `specbake bake`: the plan bakes each material with all its outputs and passes every bake it
    // keeps to this function right after the decision (which writes it), so each texture is baked once and
    // only one material's chains are held at a time. Empty (`specbake plan`): roughness only, nothing kept.
    // An error from it ends the plan.
    TextureBakeSink texture_sink;
    // In place of texture_sink when set (`specbake bake` without --gltf-mode replace): each
    // texture is baked straight into its files' bytes, a fraction of the float chains' memory.
    TextureBakeEncoder texture_encoder;

    // Materials that ask for glints through the config ([materials.NAME] glints = true ...), by name, as
    // SPECBAKE_glints objects (pipeline/glint_plan.h).
    std::map<std::string, nlohmann::json> material_glints;
};

struct TextureDecision {
    int material = -1;
    std::string material_name;
    // "base": normalTexture, roughness from metallicRoughness G and roughnessFactor. "clearcoat"
    // (KHR_materials_clearcoat): clearcoatNormalTexture, roughness from clearcoatRoughnessTexture G and
    // clearcoatRoughnessFactor. A material with the extension gets one decision per layer.
    std::string layer = "base";
    bool bake = false;
    std::string reason;
    std::optional<double> max_roughness_change;  // measured (r units)
    double threshold = 0.0;                      // half a quantisation step of the roughness output
    int normal_image = -1;
    int roughness_image = -1;                    // -1: constant roughness (factor)
    bool roughness_texture_used = false;         // false when the roughness map is absent or mapped differently
    // The roughness texture's UV mapping differs from the normal texture's (io::same_uv_mapping): no roughness
    // output is written (the material keeps its own roughness); roughness_value, the layer's lowest
    // roughness, only stands in for the decision's statistic.
    bool roughness_mapped_apart = false;
    float roughness_value = 1.0f;                // constant roughness when no roughness map is used
    float roughness_factor = 1.0f;
    double normal_scale = 1.0;                   // normalTexture.scale (the coat's for the coat), applied to the map
    int texcoord = 0;
    std::string stem;                            // output file stem
    int same_as = -1;                            // index in ScenePlan::textures of the identical bake reused
    // The stem of an earlier bake of the same normal map (same scale, layer and settings) whose kernel,
    // normal and projected LEAN files this layer uses: its own bake then writes its roughness (and a
    // slope-space LEAN) only. Empty when the layer writes them itself.
    std::string normal_outputs_stem;
};

struct CurvatureDecision {
    io::PrimitiveRef ref;
    std::string label;
    int material = -1;
    bool bake = false;
    std::string reason;
    std::optional<double> min_roughness;          // r_min of the material
    std::optional<double> roughness_gain;         // measured for condition 1
    double roughness_gain_threshold = 0.0;
    std::optional<double> relative_curvature;     // measured for condition 2
    double relative_curvature_threshold = 0.0;
    double min_instance_scale = 1.0, max_instance_scale = 1.0;
    bool generates_tangents = false;
    int tangent_texcoord = 0;                     // TEXCOORD set tangents are generated from (the normal texture's)
    bool repairs_normals = false;                 // zero / non-finite authored normals replaced in the output
    std::string mesh_report;
};

// The computed data a bake reuses (the plan had to compute it to decide).
struct PrimitiveWork {
    TriMesh mesh;                                 // validated, normals and tangents present
    MeshReport report;
    VertexCurvature curvature;
};

// The inputs of one texture bake: the decoded maps (plain PNGs as their integers, others as floats), or
// adjusted float copies when the material scales them (normalTexture.scale, roughnessFactor).
struct TextureWork {
    TextureMap normal;
    TextureMap roughness;              // empty (no channels): constant TextureDecision::roughness_value
    int roughness_channel = 0;
    int normal_bits = 8, roughness_bits = 8;
    Image normal_storage, roughness_storage;
    // No later layer of the plan reads the decoded maps this bake reads: the bake may return their rows to
    // the system as it passes them (TextureInputs::release_rows), as `specbake texture` does.
    bool release_rows = false;
};

struct ScenePlan {
    std::string scene;                            // source file
    std::vector<TextureDecision> textures;        // per material: base layer, then clear coat if it has one
    std::vector<CurvatureDecision> primitives;    // one per primitive
    std::vector<std::string> notes;               // import notes, warnings
    // Images a material needs (normal or roughness texture of a layer the plan considers) that could not be
    // read, decoded or are over a limit: one line each naming the scene, the material and the file. A bake
    // fails on them (the texture would silently be missing) unless told to take them as warnings.
    std::vector<std::string> input_errors;
    std::map<size_t, PrimitiveWork> work;         // by index into `primitives`, for the ones to bake
    std::vector<GlintDecision> glints;            // only the materials that ask for glints
    std::map<int, TextureWork> texture_work;      // by index in `textures`, for the texture bakes to run
    std::map<int, Image> decoded_images;          // image index -> decoded image (as floats)
    std::map<int, io::IntegerTexels> decoded_integers;  // image index -> decoded plain 8/16-bit PNG, as integers
    std::map<int, int> image_bits;                // image index -> bits per channel of the file
};

// Builds the plan for a loaded scene. `roughness_known` is false for imported formats whose materials
// state no roughness: condition 1 is then taken as met and the reason says so. Errors (a primitive that
// cannot be read or is rejected by validation) name the file, mesh and primitive.
Result<ScenePlan> make_plan(const io::GltfScene& scene, const PlanOptions& options,
                            const std::vector<bool>& roughness_known = {});

// The plan as recorded in manifests and printed by `specbake plan --json`.
nlohmann::json plan_to_json(const ScenePlan& plan);
// A human-readable table (one line per decision).
std::string plan_to_table(const ScenePlan& plan);

// The settings a kept layer's own bake writes with: `s` less the roughness output when its roughness texture
// is mapped apart, less the kernel, normal and projected LEAN when it shares them (normal_outputs_stem).
TextureBakeSettings layer_bake_settings(const TextureDecision& d, TextureBakeSettings s);

// r' - r for the clamped kernel kappa at roughness r (condition 1 above).
double roughness_gain(double r, double kappa);

}  // namespace specbake
