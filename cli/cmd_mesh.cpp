// specbake mesh: per-vertex curvature attributes alone (no texture bake, no material check), glTF out.
#include "cli/command.h"
#include "cli/name_options.h"
#include "cli/pipeline_options.h"
#include "cli/scene_options.h"

#include <utility>

namespace specbake::cli {
namespace {

int run_mesh(const SceneCliOptions& o, const PipelineFlags& pipe) { return run_scene_command(o, pipe, true); }

}  // namespace

void add_mesh_command(CLI::App& app, std::function<int()>& run) {
    auto* sub = app.add_subcommand(
        "mesh", "Add per-vertex curvature (_SPECAA_CURVATURE, and TANGENT where missing) to a mesh; glTF out.");
    auto o = std::make_shared<SceneCliOptions>();
    sub->add_option("file", o->scenes, "glTF/GLB, FBX, OBJ, PLY, DAE, STL, ...")->required();
    sub->add_option("-o,--output", o->output_dir, "Output folder (must not hold the input)")->required();
    sub->add_option("--format", o->format, "Scene format written: same, gltf or glb")
        ->check(is_member_of(kSceneFormatNames))
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

}  // namespace specbake::cli
