// specbake bench: the accuracy/cost table of every candidate on the built-in scenes and given scene files
// (SPEC Sec. 8).
#include "cli/command.h"
#include "io/files/file_read.h"
#include "verify/gl_context.h"
#include "verify/bench_job.h"
#include "verify/scene.h"
#include "cli/batch.h"
#include "cli/progress.h"
#include "cli/verify_options.h"

#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

namespace specbake::cli {

namespace {

using namespace specbake::verify;

// The most ground-truth samples the full bench raises a pair to (--max-spp).
constexpr int kBenchMaxSpp = 1024;

// The shared sample models next to a checkout (issue 15: the real-asset corpus).
constexpr std::string_view kDefaultCorpus = "../shared/assets/gltf";

struct BenchCommandOptions {
    std::vector<std::string> files;
    bool no_builtin = false;
    std::vector<std::string> scenes;
    std::vector<float> alpha{0.01f, 0.05f, 0.2f};
    float glint_alpha = 0.1f;
    SimCommandOptions sim;
    std::string corpus = std::string(kDefaultCorpus);
    bool no_corpus = false;
    bool quick = false;
    std::string output;
    std::string command_line;
};

int run_bench_command(const BenchCommandOptions& given) {
    BenchCommandOptions o = given;
    if (o.quick) {
        // CI size: every scene and distance, at a quarter of the pixels, samples and frames.
        o.sim.size = "64x64";
        o.sim.spp = 64;
        o.sim.frames = 4;
        o.sim.repeats = 0;
        o.sim.no_variants = true;
        o.alpha = {0.01f, 0.05f};
    }
    // Samples where they matter: a pair whose floor is above 10% of no filtering's RMSE or flicker is run
    // again at 4x the samples, up to 1024 (not in the CI-sized run).
    if (o.sim.max_spp < 0) o.sim.max_spp = o.quick ? 0 : kBenchMaxSpp;
    BenchOptions options;
    options.input_policy = run_settings().input_policy;
    VerifyOptions& v = options.verify;
    if (!apply_sim_command_options(o.sim, v)) return kExitUsage;
    if (!o.no_corpus) {
        std::error_code ec;
        if (std::filesystem::is_directory(o.corpus, ec)) {
            auto files = corpus_files(o.corpus);
            if (!files) {
                print_error(files.error().message);
                return kExitFailed;
            }
            options.scene_files.insert(options.scene_files.end(), files->begin(), files->end());
        } else if (o.corpus != kDefaultCorpus) {
            print_error(o.corpus + ": corpus folder not found");
            return kExitUsage;
        } else {
            print_warning(o.corpus + ": no real-asset corpus here (give --corpus DIR), analytic scenes and given files only");
        }
    }
    for (const std::string& name : o.scenes) {
        if (auto scene = make_builtin_scene(name, 0.5f); !scene) {
            print_error(scene.error().message);
            return kExitUsage;
        }
    }
    v.keep_images = !o.output.empty();
    v.pixel_maps = v.keep_images;  // the strips' harm cell
    options.scenes = o.scenes;
    options.no_builtin = o.no_builtin;
    // A missing or unreadable scene file fails before the long run starts (exit 1, as for every command).
    for (const std::string& f : o.files) {
        if (auto regular = io::check_regular_input(f); !regular) {
            print_error(regular.error().message);
            return kExitFailed;
        }
        options.scene_files.emplace_back(f);
    }
    const size_t file_runs = options.scene_files.size() * options.distances.size();
    options.alpha = o.alpha;
    options.glint_alpha = o.glint_alpha;
    options.command_line = o.command_line;
    auto context = GlContext::create();
    if (!context) {
        print_error(context.error().message);
        return kExitFailed;
    }
    options.renderer = (*context)->description();
    // Scenes done / total (each built-in scene once per alpha, then the files) on a terminal, with the frames
    // of the scene in work as the fraction; one line per finished scene otherwise.
    size_t builtin = 0;
    if (o.scenes.empty() && !o.no_builtin)
        builtin = builtin_scene_names().size() * o.alpha.size() + builtin_glint_scene_names().size();
    for (const std::string& name : o.scenes) builtin += name.starts_with("glitter-") ? 1 : o.alpha.size();
    ProgressDisplay display(builtin + file_runs, progress_mode(run_settings()), "scenes",
                            ProgressDisplay::Lines::activity);
    // The frame timing after the last frame takes about one frame's time: leave it its share.
    v.frame_done = [&display](int done, int frames) { display.fraction(double(done) / double(frames + 1)); };
    auto report = run_bench(options, [&display](const std::string& line) {
        display.status("", line);
        display.finished(line, "done");
    });
    display.close();
    if (!report) {
        print_error(report.error().message);
        return kExitFailed;
    }
    std::fputs(bench_summary_markdown(*report).c_str(), stdout);
    if (!o.output.empty()) {
        if (auto written = write_bench_outputs(*report, o.output); !written) {
            print_error(written.error().message);
            return kExitFailed;
        }
        std::printf("\nWrote %s/bench.md, bench.csv, bench.svg and strips/*.png\n", o.output.c_str());
    }
    return kExitOk;
}

}  // namespace

void add_bench_command(CLI::App& app, std::function<int()>& run) {
    auto* sub = app.add_subcommand("bench",
                                   "Accuracy against cost of every anti-aliasing candidate on the built-in scenes "
                                   "and any given scene files: Markdown table, CSV, SVG plot, PNG image strips");
    auto o = std::make_shared<BenchCommandOptions>();
    sub->add_option("files", o->files,
                    "Scene files (glTF/GLB or any mesh Assimp reads), each simulated with its own materials, "
                    "lights and camera");
    sub->add_flag("--no-builtin", o->no_builtin, "Only the given scene files, no built-in scenes");
    sub->add_option("--scenes", o->scenes,
                    "Built-in scenes (default: sphere,cylinder,torus,bumpy-sphere and the glint scenes "
                    "glitter-sphere,glitter-plane)")
        ->delimiter(',');
    sub->add_option("--alpha", o->alpha, "GGX alpha (= r^2) values of the materials")
        ->delimiter(',')
        ->capture_default_str()
        ->check(CLI::Range(0.0001f, 1.0f));
    sub->add_option("--glint-alpha", o->glint_alpha, "Alpha of the glint scenes (each runs once)")
        ->capture_default_str()
        ->check(CLI::Range(0.0001f, 1.0f));
    add_sim_command_options(sub, o->sim);
    sub->add_option("--corpus", o->corpus,
                    "Real-asset corpus: every .gltf/.glb in the subfolders of this folder, each at near, mid and far "
                    "camera distances (skipped with a warning when the default folder is absent)")
        ->capture_default_str();
    sub->add_flag("--no-corpus", o->no_corpus, "Leave out the real-asset corpus");
    sub->add_flag("--quick", o->quick,
                  "Smaller run for CI: 64x64, 64 spp, 4 frames, no timing, no bake variants, alpha 0.01 and 0.05");
    sub->add_option("-o,--output", o->output, "Folder for bench.md, bench.csv, bench.svg and strips/");
    sub->footer("Examples:\n"
                "  specbake bench -o bench-out\n"
                "  specbake bench --no-builtin helmet.glb -o helmet-bench\n"
                "  specbake bench --scenes glitter-sphere,glitter-plane --size 64x64 --spp 1024 --frames 4 -o glints\n"
                "  specbake bench --quick --scenes glitter-sphere,glitter-plane\n"
                "  specbake bench --scenes torus,cylinder --alpha 0.01 --size 256x256 --spp 1024 --frames 16 -o big\n");
    sub->callback([&run, o, sub] {
        o->command_line = "specbake bench";
        // As it can be run again: flags alone, comma-separated lists joined, other repeated options repeated.
        for (CLI::Option* opt : sub->get_options()) {
            if (opt->count() == 0 || opt->get_name() == "--help") continue;
            const bool positional = opt->get_name() == "files";
            if (opt->get_items_expected_max() == 0) {
                o->command_line += " " + opt->get_name();
            } else if (positional || opt->get_delimiter() == ',') {
                std::string joined;
                for (const std::string& r : opt->results()) joined += (joined.empty() ? "" : ",") + r;
                o->command_line += (positional ? " " : " " + opt->get_name() + " ") + joined;
            } else {
                for (const std::string& r : opt->results()) o->command_line += " " + opt->get_name() + " " + r;
            }
        }
        run = [o] { return run_bench_command(*o); };
    });
}

}  // namespace specbake::cli
