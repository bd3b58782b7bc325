// What every bake-type command shares when it runs inside a build: the run settings from the global
// flags (--jobs, --quiet, --verbose), a batch runner with progress, a summary and exit codes, the
// content-hash skip of up-to-date outputs, and the dependency list behind --depfile.
#pragma once

#include "io/up_to_date.h"

#include <functional>
#include <mutex>
#include <span>
#include <string>
#include <vector>

namespace specbake::cli {

enum class Verbosity { quiet, normal, verbose };

struct RunSettings {
    int jobs = 0;  // worker threads; 0 uses every core. Outputs do not depend on it.
    Verbosity verbosity = Verbosity::normal;
    bool progress_bar = false;  // redraw one line instead of printing one line per input
};

// The process-wide settings, filled by main() from the global flags before a command runs.
RunSettings& run_settings();

// Prints an informational line on stderr unless --quiet; `verbose_only` lines need --verbose.
void print_info(const std::string& message, bool verbose_only = false);

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

// Runs `work(i)` for every input, up to settings.jobs at a time. Shows progress (a bar on a terminal,
// plain lines otherwise, nothing with --quiet), prints one error line per failed input and a summary.
// Exceptions escaping `work` count as a failure of that input.
BatchSummary run_batch(std::span<const std::string> inputs, const std::function<ItemOutcome(size_t)>& work,
                       const RunSettings& settings = run_settings());

// Collects, from any thread, every file read, for --depfile.
class DependencyLog {
public:
    void add(const std::string& path);
    void add(std::span<const std::string> paths);
    std::vector<std::string> files() const;  // sorted, without duplicates

private:
    mutable std::mutex mutex_;
    std::vector<std::string> files_;
};

// The skip of --force's absence: when `query` finds the outputs up to date, prints
// "<output_dir>: up to date", refreshes the manifest's time stamp, logs the recorded inputs in `deps`
// and returns true. With `force`, or when stale (the reason goes to --verbose), returns false.
bool skip_if_up_to_date(const io::FreshnessQuery& query, bool force, DependencyLog* deps = nullptr);

}  // namespace specbake::cli
