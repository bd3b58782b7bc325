// specbake bench: runs `verify` on the built-in scenes (each at several roughness values) and on any given
// scene files (with their own materials), then prints a
// Markdown summary and writes, into one output folder, the full per-scene tables (bench.md), every number
// as CSV (bench.csv), error against cost as an SVG plot (bench.svg) and one PNG image strip per scene
// (strips/<scene>-r<roughness>.png). All files are written atomically (SPEC Sec. 7-8).
#pragma once

#include "core/result.h"
#include "io/files/input_policy.h"
#include "verify/verify_job.h"

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace specbake::verify {

struct BenchOptions {
    VerifyOptions verify;
    std::vector<std::string> scenes;   // built-in scene names (glint scenes too); empty: all (none with `no_builtin`)
    bool no_builtin = false;           // only the scene files
    std::vector<std::filesystem::path> scene_files;  // glTF/GLB or other mesh files, each at every distance
    io::InputPolicy input_policy;                    // what the scene files may make the bench read and allocate
    // Real-asset corpus: every .gltf/.glb directly inside each subfolder of this folder (the layout of the
    // glTF sample models, e.g. ../shared/assets/gltf), added to `scene_files`; empty: none.
    std::filesystem::path corpus_dir;
    // Camera distances a scene file is simulated at, as factors of its own framing distance (the orbit
    // that fits the object, or its camera) with a label: near shows part of the object magnified, far
    // leaves it a few dozen pixels wide, where normal-map aliasing is strongest.
    std::vector<std::pair<std::string, float>> distances{{"near", 0.55f}, {"mid", 1.0f}, {"far", 3.0f}};
    // GGX alpha (= r^2) of the materials, the papers' "roughness"; r = sqrt(alpha) is what glTF stores.
    std::vector<float> alpha{0.01f, 0.05f, 0.2f};
    // The glint scenes (builtin_glint_scene_names) run once each, at this alpha (C21's sphere and plane
    // scenes are glossy: Beckmann alpha 0.05-0.16).
    float glint_alpha = 0.1f;
    std::filesystem::path output_dir;  // empty: print only
    std::string renderer;              // GL_RENDERER/GL_VERSION, recorded in the outputs
    std::string command_line;          // recorded in bench.md so the table can be regenerated
};

struct BenchReport {
    std::vector<SceneReport> scenes;
    std::string renderer;
    std::string command_line;
};

// Runs every scene x roughness; `progress` receives one line per finished scene.
Result<BenchReport> run_bench(const BenchOptions& options, const std::function<void(const std::string&)>& progress);

// The glTF/GLB files of a corpus folder (see BenchOptions::corpus_dir), sorted; an error when it has none.
Result<std::vector<std::filesystem::path>> corpus_files(const std::filesystem::path& dir);

// `scene` seen from `factor` times its camera's distance to the target, named "<name>@<label>".
SimScene at_distance(const SimScene& scene, const std::string& label, float factor);

// `scene` under `count` (1 to kMaxSimLights) directional lights instead of its own, for run-time cost: each
// 35 degrees off the direction from the target to the camera, spread evenly about it (the first towards the
// camera's up), irradiance 1 / count each, so every light puts a highlight in view and the image keeps its
// exposure. Named "<name>+<count>L".
SimScene with_cost_lights(const SimScene& scene, int count);

// Summary: per candidate the geometric means (over scenes) of its RMSE (linear and tone-mapped) and
// flicker (linear and tone-mapped) relative to its family's baseline (baseline_of: no filtering, or for the glint
// family glints without anti-aliasing), the mean energy and peak ratios, and its
// costs; one table over all scenes, then one per family (analytic, real assets) when both ran, then the
// do-no-harm check of the default per scene.
std::string bench_summary_markdown(const BenchReport& report);
// One table per scene (markdown_table) with a heading, plus the summary and the command line.
std::string bench_full_markdown(const BenchReport& report);
std::string bench_csv(const BenchReport& report);
// Two panels: relative linear RMSE and relative flicker against SPIR-V instructions, one point per candidate.
std::string bench_svg(const BenchReport& report);

// Writes bench.md, bench.csv, bench.svg and strips/*.png into `dir` (created when missing).
Result<void> write_bench_outputs(const BenchReport& report, const std::filesystem::path& dir);

}  // namespace specbake::verify
