// The subcommands. Each cmd_*.cpp defines one add_*_command function, which cli/app.cpp calls in the
// order of --help:
//
//   void add_texture_command(CLI::App& app, std::function<int()>& run) {
//       auto* sub = app.add_subcommand("texture", "Bake a normal map ...");
//       auto opts = std::make_shared<TextureOptions>();
//       sub->add_option("--normal", opts->normal, "...")->required();
//       sub->footer("Examples:\n  specbake texture --normal n.png -o out/");
//       sub->callback([&run, opts] { run = [opts] { return run_texture(*opts); }; });
//   }
//
// A subcommand's callback returns the process exit code.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <string>

namespace specbake::cli {

// Exit codes documented in docs/build-pipelines.md#exit-codes.
enum ExitCode : int {
    kExitOk = 0,
    kExitFailed = 1,  // an input failed (the others, if any, completed)
    kExitUsage = 2,   // bad command line
};

// Adds the subcommand to `app` and sets `run` to the function that executes it after parsing.
using AddCommand = void (*)(CLI::App& app, std::function<int()>& run);

void add_bake_command(CLI::App& app, std::function<int()>& run);
void add_texture_command(CLI::App& app, std::function<int()>& run);
void add_mesh_command(CLI::App& app, std::function<int()>& run);
void add_plan_command(CLI::App& app, std::function<int()>& run);
void add_glints_command(CLI::App& app, std::function<int()>& run);
void add_inspect_command(CLI::App& app, std::function<int()>& run);
void add_shader_command(CLI::App& app, std::function<int()>& run);
void add_verify_command(CLI::App& app, std::function<int()>& run);
void add_bench_command(CLI::App& app, std::function<int()>& run);
void add_filter_command(CLI::App& app, std::function<int()>& run);
void add_view_command(CLI::App& app, std::function<int()>& run);

// Prints "specbake: error: <message>" on stderr.
void print_error(const std::string& message);
void print_warning(const std::string& message);

}  // namespace specbake::cli
