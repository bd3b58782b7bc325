// Shared by the libFuzzer targets: a per-process scratch folder (on tmpfs where there is one) for the
// readers that take a path, so each input is a real file with the extension that selects the reader.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace specbake::fuzz {

inline const std::filesystem::path& scratch_dir() {
    static const std::filesystem::path dir = [] {
        namespace fs = std::filesystem;
        // The fuzz scripts name a folder they remove afterwards (a crash skips the atexit clean-up).
        const char* env = std::getenv("SPECBAKE_FUZZ_SCRATCH");
        const fs::path base = env && *env                         ? fs::path(env)
                              : fs::is_directory("/dev/shm") ? fs::path("/dev/shm")
                                                             : fs::temp_directory_path();
        const fs::path d = base / ("specbake-fuzz-" + std::to_string(::getpid()));
        fs::create_directories(d);
        std::atexit([] { std::error_code ec; std::filesystem::remove_all(scratch_dir(), ec); });
        return d;
    }();
    return dir;
}

// Writes the input to scratch_dir()/name (replacing the previous input) and returns its path.
inline std::filesystem::path write_scratch(const std::string& name, const uint8_t* data, size_t size) {
    const std::filesystem::path path = scratch_dir() / name;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    if (!out) {
        std::fprintf(stderr, "cannot write %s\n", path.c_str());
        std::abort();
    }
    return path;
}

}  // namespace specbake::fuzz
