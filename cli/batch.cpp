#include "cli/batch.h"

#include "cli/progress.h"
#include "io/output/bake_output.h"
#include "io/output/depfile.h"
#include "pipeline/concurrency.h"

#include <tbb/task_arena.h>

#include <chrono>
#include <cstdio>
#include <exception>

namespace specbake {

int BatchSummary::exit_code() const { return failed > 0 ? 1 : 0; }

std::string error_line(const std::string& input, const std::string& message) {
    const bool names_input = message.rfind(input, 0) == 0;
    return "specbake: error: " + (names_input ? std::string() : input + ": ") + message;
}

BatchSummary run_batch(std::span<const std::string> inputs, const std::function<ItemOutcome(size_t)>& work,
                       const RunSettings& settings) {
    const auto start = std::chrono::steady_clock::now();
    ProgressDisplay progress(inputs.size(), progress_mode(settings), "inputs");
    std::vector<ItemStatus> status(inputs.size(), ItemStatus::failed);
    static const char* words[] = {"done", "up to date", "FAILED"};
    auto run_one = [&](size_t i) {
        progress.status(inputs[i], "");
        ItemOutcome outcome;
        try {
            outcome = work(i);
        } catch (const std::exception& e) {
            outcome = {ItemStatus::failed, inputs[i] + ": internal error: " + e.what()};
        }
        status[i] = outcome.status;
        if (outcome.status == ItemStatus::failed) print_line(stderr, error_line(inputs[i], outcome.message));
        progress.finished(inputs[i], words[int(outcome.status)]);
    };
    tbb::task_arena arena(settings.jobs > 0 ? settings.jobs : tbb::task_arena::automatic);
    arena.execute([&] { for_each_concurrently(inputs.size(), run_one); });
    progress.close();

    BatchSummary summary;
    for (ItemStatus s : status) {
        summary.done += s == ItemStatus::done;
        summary.up_to_date += s == ItemStatus::up_to_date;
        summary.failed += s == ItemStatus::failed;
    }
    if (inputs.size() > 1 || summary.failed > 0 || settings.verbosity == Verbosity::verbose) {
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (settings.verbosity != Verbosity::quiet) {
            char line[160];
            std::snprintf(line, sizeof line, "specbake: %d done, %d up to date, %d failed (%.2f s)", summary.done,
                          summary.up_to_date, summary.failed, seconds);
            print_line(stderr, line);
        }
    }
    return summary;
}

Result<void> write_manifest_depfile(const PipelineFlags& flags, const std::filesystem::path& output_dir,
                                    const std::vector<std::string>& recorded_inputs) {
    if (flags.depfile.empty()) return {};
    std::vector<std::string> deps = run_settings().option_files;
    for (const std::string& in : recorded_inputs)
        deps.push_back(io::resolve_recorded_input(in, output_dir).lexically_normal().generic_string());
    const std::vector<std::string> targets{(output_dir / "manifest.json").lexically_normal().generic_string()};
    // Inputs found while baking (a scene's textures) are checked here as well: never overwritten.
    const std::vector<std::filesystem::path> dep_paths(deps.begin(), deps.end());
    if (auto ok = io::check_depfile_path(flags.depfile, output_dir, dep_paths); !ok) return ok.error();
    return io::write_depfile(flags.depfile, targets, deps);
}

bool skip_if_up_to_date(const io::FreshnessQuery& query, const PipelineFlags& flags) {
    if (flags.force) return false;
    const io::Freshness f = io::check_up_to_date(query);
    if (!f.up_to_date) {
        print_info(query.output_dir.string() + ": baking (" + f.reason + ")", true);
        return false;
    }
    if (auto written = write_manifest_depfile(flags, query.output_dir, f.recorded_inputs); !written) {
        print_line(stderr, "specbake: error: " + written.error().message);
        return false;
    }
    io::mark_manifest_fresh(query.output_dir);
    if (run_settings().verbosity != Verbosity::quiet) print_line(stdout, query.output_dir.string() + ": up to date");
    return true;
}

}  // namespace specbake
