// The specbake command line: expands response files, reads --config, parses the global flags and
// dispatches to one subcommand.
#include "cli/app.h"

#include "cli/command.h"
#include "cli/config.h"
#include "cli/progress.h"
#include "cli/run_settings.h"
#include "io/files/cleanup_registry.h"
#include "io/files/input_policy.h"
#include "pipeline/version.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <cerrno>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <system_error>
#include <thread>
#include <exception>
#include <iterator>
#include <memory>
#include <optional>
#include <sstream>
#include <unistd.h>
#include <vector>

namespace specbake::cli {
namespace {

struct Command {
    const char* name;
    AddCommand add;
};

// In the order of --help.
constexpr Command kCommands[] = {
    {"bake", &add_bake_command},       {"texture", &add_texture_command}, {"mesh", &add_mesh_command},
    {"plan", &add_plan_command},       {"glints", &add_glints_command},   {"inspect", &add_inspect_command},
    {"shader", &add_shader_command},   {"verify", &add_verify_command},   {"bench", &add_bench_command},
    {"filter", &add_filter_command},   {"view", &add_view_command},
};

// Reads --config files (TOML or JSON) into the parser's items. Top-level keys go to the command being
// run, so one flat file configures it; [materials.NAME] tables become material_overrides().
class ConfigFile : public CLI::Config {
public:
    ConfigFile(std::string command, std::vector<std::string> globals, std::vector<std::string> subcommands)
        : command_(std::move(command)), globals_(std::move(globals)), subcommands_(std::move(subcommands)) {}

    void set_option(const CLI::Option* option) { option_ = option; }
    void set_app(const CLI::App* app) { app_ = app; }
    // The config file and the keys it gave, to name the file when the parser refuses one of them.
    const std::string& source() const { return source_; }
    bool gave(const std::string& message) const {
        for (const std::string& k : keys_)
            if (message.find(k) != std::string::npos) return true;
        return false;
    }

    std::string to_config(const CLI::App* app, bool defaults, bool descriptions, std::string prefix) const override {
        return CLI::ConfigTOML().to_config(app, defaults, descriptions, std::move(prefix));
    }

    std::vector<CLI::ConfigItem> from_config(std::istream& input) const override {
        const std::string text{std::istreambuf_iterator<char>(input), std::istreambuf_iterator<char>()};
        const std::string name = option_ && option_->count() ? option_->results().back() : "config file";
        source_ = name;
        auto tree = parse_config_text(text, name);
        if (!tree) throw CLI::ConfigError(tree.error().message, CLI::ExitCodes::ConfigError);
        auto split = split_config(*tree, command_, globals_, subcommands_, name);
        if (!split) throw CLI::ConfigError(split.error().message, CLI::ExitCodes::ConfigError);
        material_overrides() = split->materials;
        std::vector<CLI::ConfigItem> items;
        for (ConfigEntry& e : split->entries) {
            keys_.push_back(e.key);
            if (auto problem = flag_problem(e); !problem.empty())
                throw CLI::ConfigError(name + ": " + e.key + ": " + problem, CLI::ExitCodes::ConfigError);
            items.push_back({e.section, e.key, e.values});
        }
        return items;
    }

private:
    // A flag given a value other than true or false ("yes" is a string in TOML, not a boolean).
    std::string flag_problem(const ConfigEntry& e) const {
        if (!app_) return {};
        const CLI::App* scope = app_;
        for (const std::string& s : e.section) {
            try {
                scope = app_->get_subcommand(s);
            } catch (const CLI::Error&) {
                return {};
            }
        }
        const CLI::Option* opt = nullptr;
        try {
            opt = scope->get_option("--" + e.key);
        } catch (const CLI::Error&) {
            return {};
        }
        if (opt->get_expected_min() != 0) return {};
        for (const std::string& v : e.values)
            if (v != "true" && v != "false") return "'" + v + "' is not true or false";
        return {};
    }

    std::string command_;
    const CLI::App* app_ = nullptr;
    mutable std::string source_;
    mutable std::vector<std::string> keys_;
    std::vector<std::string> globals_;
    std::vector<std::string> subcommands_;
    const CLI::Option* option_ = nullptr;
};

// The global flags as parsed, before they are checked and applied to the run settings.
struct GlobalFlags {
    bool quiet = false;
    bool verbose = false;
    std::vector<std::string> limits, roots;
    CLI::Option* config = nullptr;
};

// -j, -q, -v, --limit, --allow-root and --config; --jobs goes straight into `settings`.
void add_global_options(CLI::App& app, RunSettings& settings, GlobalFlags& flags) {
    app.add_option("-j,--jobs", settings.jobs, "Worker threads (default: all cores); outputs do not depend on it")
        ->check(CLI::NonNegativeNumber);
    app.add_flag("-q,--quiet", flags.quiet, "Print errors only");
    app.add_flag("-v,--verbose", flags.verbose, "Print what is done and why (for example why an output is rebaked)");
    app.add_option("--limit", flags.limits,
                   "NAME=VALUE: raise (or lower) a limit checked before allocating: texels (per image, default "
                   "2^28), json-depth (512), json-bytes (256M), nodes (1M), primitives (65536), "
                   "accessor-elements (64M, accessors without a bufferView), texture-bytes (4G, one KTX2/DDS "
                   "level), vertices and faces (64M each, a scene read through Assimp); K, M, G suffixes. "
                   "Repeatable")
        ->expected(1)
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    app.add_option("--allow-root", flags.roots,
                   "A folder that scene URIs may also resolve into (by default only the scene's own folder; "
                   "absolute paths and ../ leaving it are refused). Repeatable")
        ->expected(1)
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    flags.config =
        app.set_config("--config", "", "Read options from a TOML or JSON file; options on the command line win");
}

void add_commands(CLI::App& app, std::function<int()>& run) {
    for (const Command& c : kCommands) c.add(app, run);
    for (CLI::App* sub : app.get_subcommands({}))
        sub->footer(sub->get_footer() +
                    "\n\nGlobal options (before or after the command): -j/--jobs N, -q/--quiet, -v/--verbose,\n"
                    "--config FILE, and @FILE response files. See 'specbake --help'.");
}

// The reader of --config files, told the command being run (the first argument naming one) and the global
// options, so that top-level keys go where they belong.
std::shared_ptr<ConfigFile> add_config_reader(CLI::App& app, const std::vector<std::string>& args,
                                              const CLI::Option* config_option) {
    std::vector<std::string> subcommands;
    for (const Command& c : kCommands) subcommands.emplace_back(c.name);
    std::vector<std::string> globals;
    for (const CLI::Option* opt : app.get_options())
        for (const std::string& name : opt->get_lnames()) globals.push_back(name);
    const auto command = std::find_first_of(args.begin(), args.end(), subcommands.begin(), subcommands.end());
    auto formatter = std::make_shared<ConfigFile>(command == args.end() ? std::string() : *command, globals,
                                                  subcommands);
    formatter->set_option(config_option);
    formatter->set_app(&app);
    app.config_formatter(formatter);
    app.allow_config_extras(CLI::config_extras_mode::error);  // a misspelt key is an error, not ignored
    return formatter;
}

// Checks the global flags and applies them to `settings`; the exit code of a usage error, if any.
std::optional<int> apply_global_flags(const GlobalFlags& flags, const ConfigFile& formatter, RunSettings& settings) {
    if (flags.quiet && flags.verbose) {
        print_error("--quiet and --verbose exclude each other");
        return kExitUsage;
    }
    for (const std::string& file : flags.config->results()) settings.option_files.push_back(file);
    io::InputPolicy& policy = settings.input_policy;
    const std::string from_config = flags.config->count() ? " (" + formatter.source() + " or the command line)" : "";
    for (const std::string& l : flags.limits)
        if (auto r = io::set_limit(policy.limits, l); !r) {
            print_error(r.error().message + from_config);
            return kExitUsage;
        }
    for (const std::string& root : flags.roots)
        if (auto r = io::add_allowed_root(policy, root); !r) {
            print_error(r.error().message + from_config);
            return kExitUsage;
        }
    settings.verbosity = flags.quiet ? Verbosity::quiet : flags.verbose ? Verbosity::verbose : Verbosity::normal;
    settings.progress_bar = !flags.quiet && isatty(fileno(stderr));
    return std::nullopt;
}

// How many threads this process can run at once, up to `wanted` (itself included): starts wanted - 1
// threads that wait, and stops at the first that cannot be created (a process or memory limit). The thread
// pool then never tries to start a thread the system refuses, which would end the process.
int startable_threads(int wanted) {
    std::vector<std::thread> started;
    std::mutex m;
    std::condition_variable cv;
    bool go = false;
    for (int i = 1; i < wanted; ++i) {
        try {
            started.emplace_back([&] {
                std::unique_lock<std::mutex> lock(m);
                cv.wait(lock, [&] { return go; });
            });
        } catch (const std::system_error&) {
            break;
        }
    }
    {
        std::lock_guard<std::mutex> lock(m);
        go = true;
    }
    cv.notify_all();
    for (std::thread& t : started) t.join();
    return int(started.size()) + 1;
}

// More threads than this never make a bake faster and only cost memory for their stacks.
constexpr int kMaxJobs = 256;

// The thread count of the run: -j (capped at kMaxJobs) or every core, lowered to what the system lets the
// process start, with a warning when -j asked for more than that.
int usable_jobs(int asked) {
    const int cores = std::max(1, int(std::thread::hardware_concurrency()));
    const int wanted = asked > 0 ? std::min(asked, kMaxJobs) : cores;
    const int startable = startable_threads(wanted);
    if (startable < wanted && asked > 0)
        print_warning("-j " + std::to_string(asked) + ": only " + std::to_string(startable) +
                      " threads can be started (process or memory limit); using " + std::to_string(startable));
    return startable < wanted || asked > 0 ? startable : 0;
}

}  // namespace

void print_error(const std::string& message) { print_line(stderr, "specbake: error: " + message); }
void print_warning(const std::string& message) { print_line(stderr, "specbake: warning: " + message); }

int run_cli(int argc, char** argv) {
    // Before any thread starts: SIGINT, SIGTERM and SIGHUP remove this run's temporaries and staging folders.
    io::install_interrupt_cleanup();
    RunSettings& settings = run_settings();
    auto expanded = expand_response_files(std::vector<std::string>(argv + 1, argv + argc), &settings.option_files);
    if (!expanded) {
        print_error(expanded.error().message);
        return kExitUsage;
    }
    std::vector<std::string> args = std::move(*expanded);

    CLI::App app{"specbake: bakes specular anti-aliasing data (filtered roughness, kernel and LEAN mips,\n"
                 "per-vertex curvature) and ships the runtime shader include that uses it.",
                 "specbake"};
    app.set_version_flag("--version", std::string("specbake ") + specbake::tool_version());
    app.require_subcommand(1);
    app.fallthrough();  // global flags may follow the command name: specbake bake -j 4 scene.gltf
    GlobalFlags flags;
    add_global_options(app, settings, flags);
    app.footer("Arguments @FILE are replaced by the arguments listed in FILE (response file).\n"
               "Exit codes: 0 success, 1 some inputs failed (the others completed), 2 usage error.\n"
               "Run 'specbake <command> --help' for the options and examples of each command.");
    std::function<int()> run;
    add_commands(app, run);
    const std::shared_ptr<ConfigFile> formatter = add_config_reader(app, args, flags.config);

    try {
        std::vector<std::string> reversed(args.rbegin(), args.rend());
        app.parse(reversed);
    } catch (const CLI::ParseError& e) {
        // A value from the config file the parser refused: say which file it came from.
        const std::string what = e.what();
        if (!formatter->source().empty() && what.find(formatter->source()) == std::string::npos &&
            formatter->gave(what)) {
            print_error(formatter->source() + ": " + what);
            return kExitUsage;
        }
        const int code = app.exit(e);
        return code == 0 ? kExitOk : kExitUsage;
    }
    if (!run) {
        print_error("no command given; see 'specbake --help'");
        return kExitUsage;
    }
    if (auto usage = apply_global_flags(flags, *formatter, settings)) return *usage;
    settings.jobs = usable_jobs(settings.jobs);
    std::optional<tbb::global_control> thread_limit;
    if (settings.jobs > 0) thread_limit.emplace(tbb::global_control::max_allowed_parallelism, size_t(settings.jobs));

    int code = kExitFailed;
    try {
        code = run();
    } catch (const std::exception& e) {
        print_error(std::string("internal error: ") + e.what());
        code = kExitFailed;
    }
    // What was printed must have arrived: a full disk or closed pipe behind stdout fails the run.
    if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
        const int err = errno;
        print_error(std::string("standard output: cannot write: ") + std::strerror(err ? err : EIO));
        if (code == kExitOk) code = kExitFailed;
    }
    return code;
}

}  // namespace specbake::cli
