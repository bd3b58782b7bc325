// Incremental builds by content: outputs are up to date when the manifest in their folder records the
// same tool version, the same settings, the same inputs with unchanged SHA-256, and every output is
// present with the hash the manifest recorded. Timestamps play no part, so a fresh checkout or a
// restored cache is recognised as up to date as well.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace specbake::io {

struct FreshnessQuery {
    std::filesystem::path output_dir;  // folder holding manifest.json
    std::vector<std::string> inputs;   // the inputs the command was given, spelled as the manifest records them
    nlohmann::json settings;           // exactly what the command would write as the manifest's "settings"
    std::string tool_version;
};

struct Freshness {
    bool up_to_date = false;
    std::string reason;                       // why a rebake is needed (empty when up to date)
    std::vector<std::string> recorded_inputs;  // every input the manifest lists, for the depfile of a skipped run
};

// Compares the query with `output_dir/manifest.json`. A relative recorded input is looked up from the
// working folder, then from the manifest folder. Inputs the manifest adds to the given ones (textures a
// scene references) must still hash the same.
Freshness check_up_to_date(const FreshnessQuery& query);

// Sets the manifest's modification time to now, so timestamp-based tools (Make, Ninja) see the skipped
// action as done; file contents are untouched.
void mark_manifest_fresh(const std::filesystem::path& output_dir);

}  // namespace specbake::io
