// An empty folder of its own for a test: <temp>/specbake_<area>_<name>_<pid>, removed first if a previous
// run left it.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>

namespace specbake::testing {

inline std::filesystem::path fresh_test_folder(const std::string& area, const std::string& name) {
    const std::filesystem::path d =
        std::filesystem::temp_directory_path() / ("specbake_" + area + "_" + name + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(d);
    std::filesystem::create_directories(d);
    return d;
}

}  // namespace specbake::testing
