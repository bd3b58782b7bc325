// Where options come from besides argv: response files (@list.txt) and --config files (TOML or JSON).
// Both are turned into plain data here, so the argument parser stays the single place that knows the
// options, and the command line always wins over a config file.
#pragma once

#include "core/result.h"

#include <nlohmann/json.hpp>

#include <optional>
#include <span>
#include <string>
#include <vector>

namespace specbake {

// Replaces every argument "@FILE" by the arguments FILE holds: separated by white space, grouped by
// "double" or 'single' quotes, '#' at the start of a word comments out the rest of the line, nested
// @FILE allowed (paths relative to the working folder, as compilers do). Errors name the file. Bounded,
// so that nesting cannot multiply the work: 16 levels deep, 4096 response files read in all (a file named
// twice is read twice), 64 MiB read, 2^20 arguments. The files read are appended to `files_read` when
// given, each once (they belong in a depfile).
Result<std::vector<std::string>> expand_response_files(const std::vector<std::string>& args,
                                                       std::vector<std::string>* files_read = nullptr);

// Parses a config file's text into a JSON tree: JSON when it starts with '{', TOML otherwise (values of
// TOML files stay strings; the argument parser converts them).
Result<nlohmann::json> parse_config_text(const std::string& text, const std::string& source_name);

// Per-material overrides by material name: the [materials.NAME] tables of a config file, for example
//   [materials.BrushedSteel]
//   isotropic = "max"
// Values are kept as the strings an option would receive.
class MaterialOverrides {
public:
    void set(const std::string& material, const std::string& key, std::string value);
    bool empty() const { return table_.empty(); }
    // The override of `key` for `material`, if the config file gives one.
    std::optional<std::string> find(const std::string& material, const std::string& key) const;
    // The same as a number; an error names the material and key when the text is not a number.
    Result<std::optional<double>> number(const std::string& material, const std::string& key) const;
    // Every override as {material: {key: value}}, e.g. to record in a manifest's settings.
    nlohmann::json to_json() const { return table_; }

private:
    nlohmann::json table_ = nlohmann::json::object();
};

// The overrides of the config file given with --config (empty without one). Set by run_cli().
MaterialOverrides& material_overrides();

// One option value from a config file, addressed like the argument parser addresses it: `section` empty
// for a global option, {COMMAND} for an option of that subcommand.
struct ConfigEntry {
    std::vector<std::string> section;
    std::string key;
    std::vector<std::string> values;
};

struct SplitConfig {
    std::vector<ConfigEntry> entries;
    MaterialOverrides materials;
};

// Sorts a config tree for the command being run: top-level keys that are global options stay global,
// other top-level keys belong to `command`, a table named after `command` holds its options (tables of
// other subcommands are skipped, so one file can serve several commands), and "materials" tables (top level or inside the command's table) are the per-material
// overrides. Any other table is an error naming the file.
Result<SplitConfig> split_config(const nlohmann::json& tree, const std::string& command,
                                 std::span<const std::string> global_options,
                                 std::span<const std::string> subcommands, const std::string& source_name);

}  // namespace specbake
