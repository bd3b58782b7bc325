// Incremental builds by content: outputs are up to date when the manifest in their folder records the
// same tool version, the same settings, the same inputs with unchanged SHA-256, and every output is
// present with the hash the manifest recorded, and the bake skipped nothing (Manifest::skipped).
// Timestamps play no part, so a fresh checkout or a restored cache is recognised as up to date as well.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace specbake::io {

struct FreshnessQuery {
    std::filesystem::path output_dir;  // folder holding manifest.json
    std::vector<std::string> inputs;   // the inputs the command was given, as recorded_input_path() spells them
    nlohmann::json settings;           // exactly what the command would write as the manifest's "settings"
    std::string tool_version;
    // Settings keys the command derives from the inputs while baking (facts about the input files); they
    // are left out of the comparison because the input hashes already cover them.
    std::vector<std::string> derived_setting_keys;
};

struct Freshness {
    bool up_to_date = false;
    std::string reason;                       // why a rebake is needed (empty when up to date)
    std::vector<std::string> recorded_inputs;  // every input the manifest lists, for the depfile of a skipped run
};

// Compares the query with `output_dir/manifest.json`. A relative recorded input is looked up from the
// manifest folder (io/output/manifest.h, recorded_input_path). Inputs the manifest adds to the given ones (textures a
// scene references) must still hash the same.
Freshness check_up_to_date(const FreshnessQuery& query);

// Where a path recorded in a manifest of `output_dir` is found: as given when absolute, else relative to
// the manifest folder (lexically normal, so "out/../a/x.png" reads "a/x.png").
std::filesystem::path resolve_recorded_input(const std::string& recorded, const std::filesystem::path& output_dir);

// Sets the manifest's modification time to now, so timestamp-based tools (Make, Ninja) see the skipped
// action as done; file contents are untouched.
void mark_manifest_fresh(const std::filesystem::path& output_dir);

}  // namespace specbake::io
