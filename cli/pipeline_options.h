// The command-line side of cli/batch.h: the flags every bake-type command offers. The global flags
// (--jobs, --quiet, --verbose, --config) are parsed by run_cli() for every command.
#pragma once

#include "cli/batch.h"

#include <CLI/CLI.hpp>

namespace specbake::cli {

// Adds --depfile and --force to `sub`, filling `flags`.
inline void add_pipeline_options(CLI::App& sub, PipelineFlags& flags) {
    sub.add_option("--depfile", flags.depfile,
                   "Write a Make/Ninja dependency file: target OUTPUT/manifest.json, every file read "
                   "(scenes, the textures they reference, response and config files)");
    sub.add_flag("--force", flags.force,
                 "Bake even when manifest.json shows the outputs are up to date (same inputs by SHA-256, "
                 "same settings and tool version, outputs unchanged), and replace a bake of other inputs "
                 "that the output folder holds (refused otherwise)");
}

}  // namespace specbake::cli
