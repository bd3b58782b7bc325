// What every bake-type command shares when it runs inside a build: a batch runner with progress, a
// summary and exit codes, the content-hash skip of up-to-date outputs, and --depfile.
#pragma once

#include "cli/run_settings.h"
#include "core/result.h"
#include "io/output/up_to_date.h"

#include <filesystem>

#include <functional>
#include <span>
#include <string>
#include <vector>

namespace specbake {

enum class ItemStatus { done, up_to_date, failed };

struct ItemOutcome {
    ItemStatus status = ItemStatus::done;
    std::string message;  // the error for a failed input; names the file
};

struct BatchSummary {
    int done = 0;
    int up_to_date = 0;
    int failed = 0;
    // 0 when nothing failed, 1 when some input failed (the others completed).
    int exit_code() const;
};

// "specbake: error: INPUT: MESSAGE", without repeating INPUT when the message already starts with it.
std::string error_line(const std::string& input, const std::string& message);

// Runs `work(i)` for every input, up to settings.jobs at a time. Shows progress (a bar on a terminal,
// plain lines otherwise, nothing with --quiet), prints one error line per failed input and a summary.
// Exceptions escaping `work` count as a failure of that input.
BatchSummary run_batch(std::span<const std::string> inputs, const std::function<ItemOutcome(size_t)>& work,
                       const RunSettings& settings = run_settings());

// The flags of a command whose outputs go into one folder with one manifest.json (see
// cli/pipeline_options.h for the command-line side).
struct PipelineFlags {
    std::string depfile;  // write a Make/Ninja dependency file here
    bool force = false;   // bake even when the manifest shows the outputs are up to date
};

// When `query` finds the outputs up to date (and not flags.force): prints "<output_dir>: up to date",
// refreshes the manifest's time stamp, writes the depfile from the manifest's inputs and returns true.
// Otherwise returns false (the reason is printed with --verbose). A depfile write error is printed and
// counts as not up to date, so the bake runs and reports normally.
bool skip_if_up_to_date(const io::FreshnessQuery& query, const PipelineFlags& flags);

// Writes flags.depfile (when set) after a bake: target `output_dir/manifest.json`, dependencies every input
// the manifest records (textures a scene references included) plus the response and config files read.
Result<void> write_manifest_depfile(const PipelineFlags& flags, const std::filesystem::path& output_dir,
                                    const std::vector<std::string>& recorded_inputs);

}  // namespace specbake
