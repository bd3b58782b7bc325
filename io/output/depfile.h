// Dependency files in the Make/Ninja syntax that compilers write with -MD: "target...: dep...".
// Build systems (Make, Ninja, CMake's add_custom_command DEPFILE) read them to learn every file an
// action read, including files it discovered itself (textures a glTF references).
#pragma once

#include "core/result.h"

#include <filesystem>
#include <span>
#include <string>

namespace specbake::io {

// Escapes one path for a depfile that GNU Make (4.3) and Ninja (1.11) both read back as that path: a
// space becomes "\ " (backslashes right before it doubled), '#' "\#", ':' "\:", '$' "$$", a leading '~'
// "./~"; every other byte, UTF-8 included, is written as it is. A path neither tool can read back the same
// (a line break, tab, ; | = [ * ? & ' " < > ^ `, a trailing backslash or ':', a backslash before '#' or
// ':', a trailing "(...)") gives an error naming the path and the character (docs/build-pipelines.md#depfiles).
Result<std::string> escape_depfile_path(const std::string& path);

// The depfile text: targets in the given order (Ninja matches the first against the action's first
// output), dependencies sorted and without duplicates, one per line, so equal sets give equal bytes.
Result<std::string> format_depfile(std::span<const std::string> targets, std::span<const std::string> deps);

// Writes format_depfile(...) to `file` atomically.
Result<void> write_depfile(const std::filesystem::path& file, std::span<const std::string> targets,
                           std::span<const std::string> deps);

}  // namespace specbake::io
