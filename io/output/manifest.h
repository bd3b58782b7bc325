// manifest.json (SPEC Sec. 7): written into every output folder. Records the tool version, the settings,
// the plan with its reasons, and every input and output with content hashes. Paths are relative to the
// manifest's folder and use '/'. Keys are written sorted, so equal content gives byte-identical files.
#pragma once

#include "core/result.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace specbake::io {

struct ManifestInput {
    std::string path;    // recorded_input_path(): relative to the manifest's folder
    std::string sha256;
};

struct ManifestOutput {
    std::string kind;    // "roughness", "kernel", "lean", "normal", "mesh", "scene", ...
    std::string path;    // relative to the manifest folder
    std::string format;  // "ktx2", "dds", "exr", "png", "gltf", "glb", ...
    int width = 0;
    int height = 0;
    int mips = 0;
    int channels = 0;
    std::string sha256;
    nlohmann::json extra = nlohmann::json::object();  // kind-specific facts (vkFormat, vertex count, ...)
};

struct Manifest {
    std::string tool = "specbake";
    std::string version;
    nlohmann::json settings = nlohmann::json::object();
    nlohmann::json plan = nlohmann::json::array();
    std::vector<ManifestInput> inputs;
    std::vector<ManifestOutput> outputs;
    // Input failures a bake was told to take as warnings (`bake --allow-unreadable-textures`): what the
    // folder lacks. Written only when not empty; a manifest that lists any is never up to date.
    std::vector<std::string> skipped;
};

nlohmann::json to_json(const Manifest& m);
Result<Manifest> manifest_from_json(const nlohmann::json& j, const std::string& source_name);

// Fills the sha256 of every output that has none by hashing its file (path relative to `dir`; files are
// hashed in parallel), then writes `dir/manifest.json` atomically. A hash already set is the writer's hash
// of the bytes it wrote and is kept.
Result<void> write_manifest(const std::filesystem::path& dir, Manifest manifest);
Result<Manifest> read_manifest(const std::filesystem::path& manifest_path);

// How a manifest in `output_dir` records the input `file` (docs/build-pipelines.md#manifest-paths): its
// path relative to the output folder, with '/' separators, both made absolute from the working folder and
// lexically normal (symbolic links are not resolved). So the same bake gives the same text from any working
// folder and any spelling of the paths (./a/x.gltf, a/x.gltf, /abs/a/x.gltf), and a tree moved as a whole
// (a sandbox, a cache restored elsewhere) keeps its manifests valid.
std::string recorded_input_path(const std::filesystem::path& file, const std::filesystem::path& output_dir);

// Path of `file` relative to `dir`, with '/' separators.
std::string relative_path(const std::filesystem::path& file, const std::filesystem::path& dir);

}  // namespace specbake::io
