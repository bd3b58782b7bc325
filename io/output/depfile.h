// Dependency files in the Make/Ninja syntax that compilers write with -MD: "target...: dep...".
// Build systems (Make, Ninja, CMake's add_custom_command DEPFILE) read them to learn every file an
// action read, including files it discovered itself (textures a glTF references).
#pragma once

#include "core/result.h"

#include <filesystem>
#include <span>
#include <string>

namespace specbake::io {

// Escapes one path for a depfile: a space becomes "\ " (backslashes right before it doubled), '#'
// becomes "\#", '$' becomes "$$". Paths holding a newline cannot be written and give an error.
Result<std::string> escape_depfile_path(const std::string& path);

// The depfile text: targets in the given order (Ninja matches the first against the action's first
// output), dependencies sorted and without duplicates, one per line, so equal sets give equal bytes.
Result<std::string> format_depfile(std::span<const std::string> targets, std::span<const std::string> deps);

// Writes format_depfile(...) to `file` atomically.
Result<void> write_depfile(const std::filesystem::path& file, std::span<const std::string> targets,
                           std::span<const std::string> deps);

}  // namespace specbake::io
