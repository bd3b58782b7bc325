#include "pipeline/batch.h"

#include "io/depfile.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <exception>
#include <mutex>

namespace specbake {

RunSettings& run_settings() {
    static RunSettings settings;
    return settings;
}

namespace {
std::mutex& output_mutex() {
    static std::mutex m;
    return m;
}
}  // namespace

void print_info(const std::string& message, bool verbose_only) {
    const Verbosity v = run_settings().verbosity;
    if (v == Verbosity::quiet || (verbose_only && v != Verbosity::verbose)) return;
    std::lock_guard lock(output_mutex());
    std::fprintf(stderr, "%s\n", message.c_str());
}

int BatchSummary::exit_code() const { return failed > 0 ? 1 : 0; }

namespace {

// Progress display; every call holds output_mutex(), so lines from parallel inputs never interleave.
class Progress {
public:
    Progress(size_t total, const RunSettings& s) : total_(total), settings_(s) {}

    void finished(const std::string& input, const ItemOutcome& outcome) {
        std::lock_guard lock(output_mutex());
        ++count_;
        if (outcome.status == ItemStatus::failed) {
            clear_bar();
            const bool names_input = outcome.message.rfind(input, 0) == 0;
            std::fprintf(stderr, "specbake: error: %s%s\n", names_input ? "" : (input + ": ").c_str(),
                         outcome.message.c_str());
        }
        if (settings_.verbosity == Verbosity::quiet) return;
        if (settings_.progress_bar) {
            draw_bar(input);
        } else if (total_ > 1 || settings_.verbosity == Verbosity::verbose) {
            static const char* words[] = {"done", "up to date", "FAILED"};
            std::fprintf(stderr, "[%zu/%zu] %s %s\n", count_, total_, words[int(outcome.status)], input.c_str());
        }
    }

    void close() {
        std::lock_guard lock(output_mutex());
        clear_bar();
    }

private:
    void draw_bar(const std::string& input) {
        constexpr size_t kWidth = 30;
        const size_t filled = total_ ? kWidth * count_ / total_ : kWidth;
        std::string bar(filled, '=');
        bar.resize(kWidth, ' ');
        std::string name = input.size() > 40 ? "..." + input.substr(input.size() - 37) : input;
        std::fprintf(stderr, "\r[%s] %zu/%zu %-40s", bar.c_str(), count_, total_, name.c_str());
        std::fflush(stderr);
        bar_drawn_ = true;
    }
    void clear_bar() {
        if (!bar_drawn_) return;
        std::fprintf(stderr, "\r%*s\r", 80, "");
        bar_drawn_ = false;
    }

    size_t total_;
    size_t count_ = 0;
    const RunSettings& settings_;
    bool bar_drawn_ = false;
};

}  // namespace

BatchSummary run_batch(std::span<const std::string> inputs, const std::function<ItemOutcome(size_t)>& work,
                       const RunSettings& settings) {
    const auto start = std::chrono::steady_clock::now();
    Progress progress(inputs.size(), settings);
    std::vector<ItemStatus> status(inputs.size(), ItemStatus::failed);
    auto run_one = [&](size_t i) {
        ItemOutcome outcome;
        try {
            outcome = work(i);
        } catch (const std::exception& e) {
            outcome = {ItemStatus::failed, inputs[i] + ": internal error: " + e.what()};
        }
        status[i] = outcome.status;
        progress.finished(inputs[i], outcome);
    };
    tbb::task_arena arena(settings.jobs > 0 ? settings.jobs : tbb::task_arena::automatic);
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, inputs.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i != r.end(); ++i) run_one(i);
        });
    });
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
            std::lock_guard lock(output_mutex());
            std::fprintf(stderr, "specbake: %d done, %d up to date, %d failed (%.2f s)\n", summary.done,
                         summary.up_to_date, summary.failed, seconds);
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
        std::lock_guard lock(output_mutex());
        std::fprintf(stderr, "specbake: error: %s\n", written.error().message.c_str());
        return false;
    }
    io::mark_manifest_fresh(query.output_dir);
    if (run_settings().verbosity != Verbosity::quiet) {
        std::lock_guard lock(output_mutex());
        std::printf("%s: up to date\n", query.output_dir.string().c_str());
        std::fflush(stdout);
    }
    return true;
}

}  // namespace specbake
