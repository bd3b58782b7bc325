// The scene jobs (`specbake bake`, `specbake mesh`, `specbake plan`): read a scene (glTF/GLB through
// tinygltf, every other format through Assimp), plan it (pipeline/plan.h), bake what the plan says
// (per-vertex curvature, the material textures), write glTF/GLB with everything of the input kept and a
// manifest.json that lists every output with its kind, the inputs with their hashes, the settings and the
// plan. Curvature is stored in object space (a node scale s divides it by s in world space).
#pragma once

#include "core/enum_names.h"
#include "pipeline/plan.h"
#include "pipeline/texture_job.h"
#include "io/gltf/gltf_scene.h"
#include "io/output/manifest.h"
#include "io/output/output_folder.h"
#include "io/texture/texture_writer.h"

#include <array>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace specbake {

enum class SceneFormat { SameAsInput, Gltf, Glb };
enum class GltfMode { Sidecar, Replace };  // `bake --gltf-mode`

// The CLI spellings (`--format`, `--gltf-mode`), in enum order.
inline constexpr std::array<std::string_view, 3> kSceneFormatNames{"same", "gltf", "glb"};
inline constexpr std::array<std::string_view, 2> kGltfModeNames{"sidecar", "replace"};
inline std::string_view to_string(SceneFormat f) { return kSceneFormatNames[size_t(f)]; }
inline std::string_view to_string(GltfMode m) { return kGltfModeNames[size_t(m)]; }
inline std::optional<SceneFormat> parse_scene_format(std::string_view name) {
    return enum_from_name<SceneFormat>(kSceneFormatNames, name);
}
inline std::optional<GltfMode> parse_gltf_mode(std::string_view name) {
    return enum_from_name<GltfMode>(kGltfModeNames, name);
}

struct SceneJob {
    std::vector<std::filesystem::path> scenes;
    std::filesystem::path output_dir;      // one scene: written directly into it; several: into <dir>/<stem>/
    // Non-glTF inputs: .gltf unless Glb is asked for. A .glb holds the input's buffers and images itself.
    SceneFormat format = SceneFormat::SameAsInput;
    PlanOptions plan;
    // The baked textures' container (KTX2 by default), KTX2 zstd (on, level 3) and `bake --block bc`
    // (block-compressed 8/16-bit outputs in KTX2 and DDS, as `texture --block`: BC4 one channel, BC5 the
    // mean normal, BC1/BC3 four channels; float stays float).
    io::TextureFileFormat texture_format;
    // Sidecar: baked textures in the SPECBAKE_specular_aa extension only. Replace: also the material's
    // normalTexture and metallicRoughnessTexture carry the baked chains as KTX2 (UASTC) through
    // KHR_texture_basisu (pipeline/gltf_replace.h), encoded by `basisu` (find_basisu()).
    GltfMode gltf_mode = GltfMode::Sidecar;
    std::filesystem::path basisu;          // empty: $SPECBAKE_BASISU or basisu on the PATH
    ProgressFn progress;                   // called from the threads baking the scenes
    // The output folder's lock when the caller already holds it (else the job takes it, io/output/bake_output.h).
    const io::OutputLock* lock = nullptr;
    // The dependency file the command writes afterwards (empty: none): a scene whose inputs include it
    // fails before anything is baked, since writing it would overwrite that input.
    std::filesystem::path depfile;
    // Replace a bake of other scenes that output_dir holds (refused otherwise).
    bool replace = false;
    // An image a material needs that cannot be read, decoded or is over a limit fails its scene (one line
    // naming the scene, the material and the file). True (`--allow-unreadable-textures`): a warning, the
    // layer is left unbaked, and the manifest records it as skipped, so the next run bakes again.
    bool unreadable_textures_are_warnings = false;
    // Called from the baking thread when scene i is finished (error empty on success).
    std::function<void(size_t scene, const std::string& error)> scene_finished;
};

// A scene read from any supported file, with what the plan needs to know about its materials.
struct LoadedScene {
    io::GltfScene scene;
    bool is_gltf = true;                   // false: imported through Assimp (a new glTF is written)
    std::vector<bool> roughness_known;     // per material; false where the file states no roughness
    std::vector<std::string> notes;        // import notes (dropped primitives, generated normals, ...)
};

// glTF/GLB (detected by content) through tinygltf; everything else through Assimp, both under `policy`.
// Imported meshes without normals get generated normals (Max weights, noted), which are written into the
// output.
Result<LoadedScene> load_scene(const std::filesystem::path& path, const io::InputPolicy& policy);

struct SceneJobOutcome {
    io::Manifest manifest;                 // as written (empty outputs when every scene failed)
    std::vector<ScenePlan> plans;
    std::vector<std::string> errors;       // one line per scene that failed (the others completed)
    std::vector<std::string> warnings;
};

// Runs the bake of every scene, several at a time (for_each_concurrently, pipeline/concurrency.h). A scene that
// fails leaves none of its files behind; the manifest lists the scenes that completed. The plans returned
// hold the decisions only (work, texture_work and decoded_images are released once written). Fails as a
// whole (Error) only for problems that stop every scene: the output folder is (or holds) an input or holds
// a bake of other scenes, or the commit fails. Everything is staged and committed with the manifest
// (io/output/bake_output.h); when every scene fails the folder is unchanged.
Result<SceneJobOutcome> run_scene_job(const SceneJob& job);

// The plan of one scene, as `specbake plan` prints it (the scene read under options.input_policy). Images
// a material needs that cannot be read are in its input_errors, which a bake fails on.
Result<ScenePlan> plan_scene(const std::filesystem::path& path, const PlanOptions& options);

// The settings block of the manifest.
nlohmann::json scene_settings_json(const SceneJob& job);

}  // namespace specbake
