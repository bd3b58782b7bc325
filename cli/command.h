// Subcommand registry. Each cmd_*.cpp registers one subcommand at static-initialisation time:
//
//   namespace {
//   void add_texture_command(CLI::App& app, std::function<int()>& run) {
//       auto* sub = app.add_subcommand("texture", "Bake a normal map ...");
//       auto opts = std::make_shared<TextureOptions>();
//       sub->add_option("--normal", opts->normal, "...")->required();
//       sub->footer("Examples:\n  specbake texture --normal n.png -o out/");
//       sub->callback([&run, opts] { run = [opts] { return run_texture(*opts); }; });
//   }
//   const specbake::cli::Registration reg{"texture", 20, &add_texture_command};
//   }  // namespace
//
// The order value sorts the subcommands in --help. A subcommand's callback returns the process exit code.
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

struct Registration {
    Registration(const char* name, int order, AddCommand add);
};

// Prints "specbake: error: <message>" on stderr.
void print_error(const std::string& message);
void print_warning(const std::string& message);

}  // namespace specbake::cli
