// specbake plan: what a bake of each scene would compute and why (SPEC Sec. 6), as a table or JSON.
#include "cli/command.h"
#include "cli/scene_options.h"

#include <cstdio>

namespace specbake::cli {
namespace {

int run_plan(const SceneCliOptions& o) {
    const auto made = make_scene_job(o);
    if (!made) {
        print_error(made.error().message);
        return kExitUsage;
    }
    const SceneJob& job = *made;
    nlohmann::json all = nlohmann::json::array();
    int status = kExitOk;
    for (const auto& scene : job.scenes) {
        auto plan = plan_scene(scene, job.plan);
        if (!plan) {
            print_error(plan.error().message);
            status = kExitFailed;
            continue;
        }
        if (o.json) all.push_back(plan_to_json(*plan));
        else std::fputs(plan_to_table(*plan).c_str(), stdout);
        // What would fail the bake fails the plan too.
        for (const std::string& e : plan->input_errors) print_error(e);
        if (!plan->input_errors.empty()) status = kExitFailed;
    }
    if (o.json) std::printf("%s\n", all.dump(2).c_str());
    return status;
}

}  // namespace

void add_plan_command(CLI::App& app, std::function<int()>& run) {
    auto* sub = app.add_subcommand("plan", "Show what 'bake' would compute for each material and primitive, and why.");
    auto o = std::make_shared<SceneCliOptions>();
    sub->add_option("scenes", o->scenes, "glTF/GLB scenes or other mesh files")->required();
    sub->add_flag("--json", o->json, "Print the plan as JSON (the form recorded in manifest.json)");
    add_curvature_options(sub, *o);
    add_material_options(sub, *o);
    sub->footer(
        "Texture bake: only where a normal texture exists and some texel of some mip changes roughness by at\n"
        "least half a quantisation step. Curvature: only where the largest kernel (kappa) raises the\n"
        "material's lowest roughness by --min-roughness-gain or more, and p95(|k1|) x bounding-box diagonal\n"
        "reaches --min-curvature. Each line gives the measured value and the threshold.\n"
        "\n"
        "Examples:\n"
        "  specbake plan Helmet.gltf\n"
        "  specbake plan scene.glb --json > plan.json");
    sub->callback([&run, o] { run = [o] { return run_plan(*o); }; });
}

}  // namespace specbake::cli
