// specbake bake: glTF/GLB (or any Assimp format) in, glTF/GLB out with per-vertex curvature and baked
// material textures, exactly as the plan says; manifest.json records outputs, inputs, settings and plan.
#include "cli/command.h"
#include "cli/name_options.h"
#include "cli/pipeline_options.h"
#include "cli/scene_options.h"
#include "io/output/bake_output.h"
#include "cli/progress.h"
#include "pipeline/version.h"

#include <cstdio>
#include <utility>

namespace specbake::cli {

int run_scene_command(const SceneCliOptions& o, const PipelineFlags& pipe, bool curvature_only) {
    auto made = make_scene_job(o);
    if (!made) {
        print_error(made.error().message);
        return kExitUsage;
    }
    SceneJob job = std::move(*made);
    if (curvature_only) {
        job.plan.textures = false;
        job.plan.check_material = false;
    }
    std::vector<std::string> scenes;
    for (const std::filesystem::path& s : job.scenes) scenes.push_back(io::recorded_input_path(s, job.output_dir));
    job.depfile = pipe.depfile;
    auto lock = io::lock_output_folder(job.output_dir, pipe.depfile, job.scenes,
                                       [](const std::string& line) { print_info(line); });
    if (!lock) {
        print_error(lock.error().message);
        return kExitFailed;
    }
    if (skip_if_up_to_date({job.output_dir, scenes, scene_settings_json(job), tool_version(), {}}, pipe)) return kExitOk;
    job.lock = &*lock;
    job.replace = pipe.force;
    const bool quiet = run_settings().verbosity == Verbosity::quiet;
    // Assets done / total on a terminal; one line per finished scene otherwise (a single scene's steps).
    ProgressDisplay display(job.scenes.size(), progress_mode(run_settings()), "scenes");
    job.progress = [&display](const std::string& s) { display.status("", s); };
    job.scene_finished = [&display, &job](size_t i, const std::string& error) {
        display.finished(job.scenes[i].string(), error.empty() ? "done" : "FAILED");
    };
    auto outcome = run_scene_job(job);
    display.close();
    if (!outcome) {
        print_error(outcome.error().message);
        return kExitFailed;
    }
    for (const std::string& w : outcome->warnings) print_warning(w);
    for (const std::string& e : outcome->errors) print_error(e);
    for (const io::ManifestInput& in : outcome->manifest.inputs) scenes.push_back(in.path);
    // Nothing baked, nothing committed: no depfile either (the failed action reruns anyway).
    if (outcome->plans.empty()) return kExitFailed;
    if (auto d = write_manifest_depfile(pipe, job.output_dir, scenes); !d) {
        print_error(d.error().message);
        return kExitFailed;
    }
    if (!quiet) {
        for (const ScenePlan& plan : outcome->plans) {
            size_t textures = 0, curvature = 0;
            for (const TextureDecision& d : plan.textures) textures += d.bake && d.same_as < 0;
            for (const CurvatureDecision& d : plan.primitives) curvature += d.bake;
            if (curvature_only)
                std::printf("%s: curvature on %zu of %zu primitives\n", plan.scene.c_str(), curvature,
                            plan.primitives.size());
            else
                std::printf("%s: curvature on %zu of %zu primitives, %zu texture bake(s)\n", plan.scene.c_str(),
                            curvature, plan.primitives.size(), textures);
        }
        if (!outcome->plans.empty())
            std::printf("wrote %zu files and manifest.json to %s\n", outcome->manifest.outputs.size(),
                        job.output_dir.string().c_str());
    }
    return outcome->errors.empty() ? kExitOk : kExitFailed;
}

namespace {

int run_bake(const SceneCliOptions& o, const PipelineFlags& pipe) { return run_scene_command(o, pipe, false); }

}  // namespace

void add_bake_command(CLI::App& app, std::function<int()>& run) {
    auto* sub = app.add_subcommand(
        "bake", "Bake scenes: per-vertex curvature (_SPECAA_CURVATURE) and filtered material textures, glTF out.");
    auto o = std::make_shared<SceneCliOptions>();
    // A missing scene is the failure of that input (exit 1, the others baked), not a usage error.
    sub->add_option("scenes", o->scenes, "glTF/GLB scenes, or FBX, OBJ, PLY, DAE, STL, ... (read through Assimp)")
        ->required();
    sub->add_option("-o,--output", o->output_dir, "Output folder (must not hold an input); one scene is written "
                                                   "into it directly, several into one subfolder each")
        ->required();
    sub->add_option("--format", o->format, "Scene format written: same (as the input; non-glTF inputs give gltf), "
                                           "gltf or glb (self-contained: buffers and images go into the file)")
        ->check(is_member_of(kSceneFormatNames))
        ->capture_default_str();
    sub->add_option("--container", o->container, "Texture container: ktx2, dds, exr or png (one file per mip)")
        ->check(is_member_of(io::kTextureContainerNames))
        ->capture_default_str();
    sub->add_option("--gltf-mode", o->gltf_mode,
                    "sidecar: baked textures in the SPECBAKE_specular_aa extension only; replace: also put the baked "
                    "roughness and mean-normal mips into the material's metallicRoughnessTexture and normalTexture "
                    "as KTX2 (UASTC) through KHR_texture_basisu, so any glTF viewer shows them (needs basisu)")
        ->check(is_member_of(kGltfModeNames))
        ->capture_default_str();
    sub->add_option("--basisu", o->basisu,
                    "Basis Universal encoder for --gltf-mode replace (default: $SPECBAKE_BASISU, else basisu on the PATH)");
    add_block_options(*sub, o->blocks, "baked textures");
    sub->add_flag("--allow-unreadable-textures", o->allow_unreadable_textures,
                  "A normal or roughness texture that cannot be read, decoded or is over a --limit is a warning "
                  "(the layer is left unbaked) instead of failing the scene; the manifest lists it as skipped, "
                  "so the next run bakes again (for batches that must not stop on one bad asset)");
    add_curvature_options(sub, *o);
    add_material_options(sub, *o);
    auto pipe = std::make_shared<PipelineFlags>();
    add_pipeline_options(*sub, *pipe);
    sub->footer(
        "Curvature is stored in object space (1/object-space length); a node scale s divides it by s in world\n"
        "space. Baked textures are referenced from each material through the SPECBAKE_specular_aa extension\n"
        "(extensionsUsed only, so every viewer still loads the file). Run 'specbake plan' to see the decisions.\n"
        "\n"
        "Examples:\n"
        "  specbake bake Helmet.gltf -o out/\n"
        "  specbake bake scene.glb --format gltf --container png -o out/\n"
        "  specbake bake chair.fbx table.obj --estimator jet-fitting -o baked/\n"
        "  specbake bake brick.glb --normal-y -y --container dds -o out/\n"
        "  specbake bake scene.gltf --config materials.toml -o out/   ([materials.NAME] tables: per material)\n"
        "  specbake bake cloth.gltf --isotropic max --outputs roughness,kernel -o out/\n"
        "  specbake bake Helmet.gltf --gltf-mode replace --basisu /path/to/basisu -o out/\n"
        "  specbake bake Helmet.gltf --block bc -o out/   (BC4/BC5/BC1 KTX2 with every baked mip)\n"
        "  specbake bake Helmet.gltf --block astc -o out/ (ASTC 4x4 KTX2 for mobile GPUs)");
    sub->callback([&run, o, pipe] { run = [o, pipe] { return run_bake(*o, *pipe); }; });
}

}  // namespace specbake::cli
