// The settings of this run from the global flags (--jobs, --quiet, --verbose, --limit, --allow-root, the
// option files read), and the informational messages they govern. The command line's process-wide state:
// the libraries below receive what they need of it as parameters.
#pragma once

#include "io/files/input_policy.h"

#include <string>
#include <vector>

namespace specbake {

enum class Verbosity { quiet, normal, verbose };

struct RunSettings {
    int jobs = 0;  // worker threads; 0 uses every core. Outputs do not depend on it.
    Verbosity verbosity = Verbosity::normal;
    bool progress_bar = false;  // redraw one line instead of printing one line per input
    std::vector<std::string> option_files;  // response and config files the command line was read from
    io::InputPolicy input_policy;  // --limit and --allow-root, passed to every job that reads inputs
};

// The process-wide settings, filled by run_cli() from the global flags before a command runs.
RunSettings& run_settings();

// Prints an informational line on stderr unless --quiet; `verbose_only` lines need --verbose.
void print_info(const std::string& message, bool verbose_only = false);

}  // namespace specbake
