// specbake mesh: per-vertex curvature attributes alone (no texture bake, no material check), glTF out.
#include "cli/command.h"
#include "cli/scene_options.h"

#include <cstdio>

namespace specbake::cli {
namespace {

int run_mesh(const SceneCliOptions& o) {
    SceneJob job = make_scene_job(o);
    job.plan.textures = false;
    job.plan.check_material = false;
    if (!o.quiet) job.progress = [](const std::string& s) { std::fprintf(stderr, "specbake: %s\n", s.c_str()); };
    auto outcome = run_scene_job(job);
    if (!outcome) {
        print_error(outcome.error().message);
        return kExitFailed;
    }
    for (const std::string& w : outcome->warnings) print_warning(w);
    for (const std::string& e : outcome->errors) print_error(e);
    if (!o.quiet) {
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
    sub->add_flag("-q,--quiet", o->quiet, "Print errors and warnings only");
    sub->footer(
        "Every triangle primitive with curved shading normals gets the attribute, whatever its material.\n"
        "Curvature is in object space (1/object-space length).\n"
        "\n"
        "Examples:\n"
        "  specbake mesh bunny.ply -o out/\n"
        "  specbake mesh Suzanne.gltf --estimator normal-cone --format glb -o out/");
    sub->callback([&run, o] { run = [o] { return run_mesh(*o); }; });
}

const Registration reg{"mesh", 30, &add_mesh_command};

}  // namespace
}  // namespace specbake::cli
