// The specbake command line as a function: cli/main.cpp calls it, tests can too.
#pragma once

namespace specbake::cli {

// Expands response files, reads --config, parses the global flags into run_settings() and runs the one
// subcommand given. Returns the process exit code (cli/command.h).
int run_cli(int argc, char** argv);

}  // namespace specbake::cli
