// File-name tests shared by the readers and writers that pick a format by extension.
#pragma once

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

namespace specbake::io {

// The extension of `path` with its dot, lower-cased (".GLB" -> ".glb"); "" when it has none.
inline std::string lower_extension(const std::filesystem::path& path) {
    std::string e = path.extension().string();
    std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return e;
}

}  // namespace specbake::io
