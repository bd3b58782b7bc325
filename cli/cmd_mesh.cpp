// specbake mesh: per-vertex curvature attributes alone (no texture bake, no material check), glTF out.
#include "cli/command.h"
#include "cli/pipeline_options.h"
#include "cli/scene_options.h"
#include "cli/version.h"

#include <cstdio>
#include <utility>

namespace specbake::cli {
namespace {

int run_mesh(const SceneCliOptions& o, const PipelineFlags& pipe) {
    auto made = make_scene_job(o);
    if (!made) {
        print_error(made.error().message);
        return kExitUsage;
    }
    SceneJob job = std::move(*made);
    job.plan.textures = false;
    job.plan.check_material = false;
    std::vector<std::string> scenes(job.scenes.begin(), job.scenes.end());
    if (skip_if_up_to_date({job.output_dir, scenes, scene_settings_json(job), tool_version(), {}}, pipe)) return kExitOk;
    const bool quiet = run_settings().verbosity == Verbosity::quiet;
    if (!quiet) job.progress = [](const std::string& s) { std::fprintf(stderr, "specbake: %s\n", s.c_str()); };
    auto outcome = run_scene_job(job);
    if (!outcome) {
        print_error(outcome.error().message);
        return kExitFailed;
    }
    for (const std::string& w : outcome->warnings) print_warning(w);
    for (const std::string& e : outcome->errors) print_error(e);
    for (const io::ManifestInput& in : outcome->manifest.inputs) scenes.push_back(in.path);
    if (auto d = write_manifest_depfile(pipe, job.output_dir, scenes); !d) {
        print_error(d.error().message);
        return kExitFailed;
    }
    if (!quiet) {
        for (const ScenePlan& plan : outcome->plans) {
            size_t curvature = 0;
            for (const CurvatureDecision& d : plan.primitives) curvature += d.bake;
            std::printf("%s: curvature on %zu of %zu primitives\n", plan.scene.c_str(), curvature, plan.primitives.size());
        }
    }
    return outcome->errors.empty() ? kExitOk : kExitFailed;
}

void add_mesh_command(CLI::App& app, std::function<int()>& run) {
    auto* sub = app.add_subcommand(
        "mesh", "Add per-vertex curvature (_SPECAA_CURVATURE, and TANGENT where missing) to a mesh; glTF out.");
    auto o = std::make_shared<SceneCliOptions>();
    sub->add_option("file", o->scenes, "glTF/GLB, FBX, OBJ, PLY, DAE, STL, ...")->required()->check(CLI::ExistingFile);
    sub->add_option("-o,--output", o->output_dir, "Output folder (must not hold the input)")->required();
    sub->add_option("--format", o->format, "Scene format written: same, gltf or glb")
        ->check(CLI::IsMember({"same", "gltf", "glb"}))
        ->capture_default_str();
    add_curvature_options(sub, *o);
    auto pipe = std::make_shared<PipelineFlags>();
    add_pipeline_options(*sub, *pipe);
    sub->footer(
        "Every triangle primitive with curved shading normals gets the attribute, whatever its material.\n"
        "Curvature is in object space (1/object-space length).\n"
        "\n"
        "Examples:\n"
        "  specbake mesh bunny.ply -o out/\n"
        "  specbake mesh Suzanne.gltf --estimator normal-cone --format glb -o out/\n"
        "  specbake mesh bunny.ply -o out/ --depfile out/bunny.d");
    sub->callback([&run, o, pipe] { run = [o, pipe] { return run_mesh(*o, *pipe); }; });
}

const Registration reg{"mesh", 30, &add_mesh_command};

}  // namespace
}  // namespace specbake::cli
