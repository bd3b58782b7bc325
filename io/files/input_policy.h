// What an input may make specbake read and allocate: the folders a scene's URIs may resolve into (the
// scene's own folder and the roots named with --allow-root) and the limits checked before allocating.
#pragma once

#include "core/result.h"

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace specbake::io {

// Every limit has a name, used by `--limit NAME=VALUE` and in the message of the error it raises.
struct InputLimits {
    uint64_t texels = uint64_t(1) << 28;             // per image, from its header (16384 x 16384)
    uint64_t json_depth = 512;                       // nesting of objects and arrays in a glTF's JSON
    uint64_t json_bytes = uint64_t(1) << 28;         // size of a glTF's JSON (256 MiB)
    uint64_t nodes = uint64_t(1) << 20;              // nodes of one scene
    uint64_t primitives = uint64_t(1) << 16;         // primitives of one scene
    uint64_t accessor_elements = uint64_t(1) << 26;  // elements of an accessor without a bufferView
    uint64_t texture_bytes = uint64_t(1) << 32;      // one level of a KTX2/DDS file (4 GiB)
    // A scene read through Assimp (OBJ, FBX, PLY, ...): vertices and faces of all its meshes together
    // (a glTF's are bounded by its accessors and their buffers instead).
    uint64_t vertices = uint64_t(1) << 26;
    uint64_t faces = uint64_t(1) << 26;
};

// Passed to every reader that opens inputs (the command line builds one from --limit and --allow-root); a
// default-constructed policy has the default limits and no roots besides the scene's own folder.
struct InputPolicy {
    InputLimits limits;
    // Folders besides a scene's own that its URIs may resolve into (absolute, lexically normal).
    std::vector<std::filesystem::path> allowed_roots;
};

// Applies "NAME=VALUE" (VALUE a whole number, optionally with a K, M or G suffix for 2^10, 2^20, 2^30).
// The error lists the names.
Result<void> set_limit(InputLimits& limits, const std::string& assignment);
// Adds a folder to the allowed roots; the error says why it cannot be one (missing, not a folder).
Result<void> add_allowed_root(InputPolicy& policy, const std::filesystem::path& folder);

// "... exceeds the limit of N (--limit NAME=N raises it)", the tail of every limit error.
std::string over_limit(const char* name, uint64_t value, uint64_t limit);

// The path as UTF-8 text, or an error naming it: manifests and plans record paths as JSON strings, which
// must be valid UTF-8 (checked before any work, instead of failing when the manifest is written).
Result<void> check_utf8_path(const std::filesystem::path& path);
bool is_valid_utf8(const std::string& text);
// The text with each byte that starts no well-formed UTF-8 sequence replaced by U+FFFD, for names a file
// carries that are written again as JSON text (glTF names); valid text comes back unchanged.
std::string to_valid_utf8(const std::string& text);
// The text with each such byte written as \xHH, for messages that quote it.
std::string escape_invalid_utf8(const std::string& text);

// Resolves a decoded URI of a file in `folder` to the path that is read, hashed, copied and listed: the
// folder joined with the decoded text, lexically normal. Refused (the reason, without the scene's name):
// NUL bytes, invalid UTF-8, absolute paths, and paths that leave `folder`, lexically or through a symbolic link, unless
// they lie in one of the allowed roots.
Result<std::filesystem::path> resolve_in_folder(const std::filesystem::path& folder, const std::string& decoded,
                                                const InputPolicy& policy);

// Fails when `output` is the same file as any of `inputs` (inputs are never overwritten), or when
// `output_dir` is a folder that holds one of the inputs directly.
Result<void> check_output_not_input(const std::filesystem::path& output_dir,
                                    std::span<const std::filesystem::path> inputs);

}  // namespace specbake::io
