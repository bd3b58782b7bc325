// Subcommand registry. Each cmd_*.cpp registers one subcommand at static-initialisation time:
//
//   static specbake::cli::Registration reg{"texture", 20, &add_texture_command};
//
// The order value sorts the subcommands in --help. A subcommand's callback returns the process exit code.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <string>

namespace specbake::cli {

// Exit codes documented in the README.
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
