#include "cli/run_settings.h"

#include "cli/progress.h"

namespace specbake {

RunSettings& run_settings() {
    static RunSettings settings;
    return settings;
}

void print_info(const std::string& message, bool verbose_only) {
    const Verbosity v = run_settings().verbosity;
    if (v == Verbosity::quiet || (verbose_only && v != Verbosity::verbose)) return;
    print_line(stderr, message);
}

}  // namespace specbake
