// Links the installed specbake library: checks the baked manifest's hashes with the library's own reader.
#include "pipeline/version.h"
#include "io/output/manifest.h"
#include "io/files/sha256.h"

#include <cstdio>
#include <filesystem>

int main() {
    namespace fs = std::filesystem;
    auto manifest = specbake::io::read_manifest(MANIFEST);
    if (!manifest) {
        std::fprintf(stderr, "%s\n", manifest.error().message.c_str());
        return 1;
    }
    if (manifest->version != specbake::tool_version()) {
        std::fprintf(stderr, "manifest version %s, library %s\n", manifest->version.c_str(), specbake::tool_version());
        return 1;
    }
    const fs::path dir = fs::path(MANIFEST).parent_path();
    for (const auto& out : manifest->outputs) {
        auto hash = specbake::io::sha256_file(dir / out.path);
        if (!hash || *hash != out.sha256) {
            std::fprintf(stderr, "%s: hash mismatch\n", out.path.c_str());
            return 1;
        }
    }
    if (!fs::exists(fs::path(SHADER_DIR) / "specaa.glsl")) {
        std::fprintf(stderr, "no shader include in %s\n", SHADER_DIR);
        return 1;
    }
    std::printf("specbake %s: %zu outputs verified\n", specbake::tool_version(), manifest->outputs.size());
    return 0;
}
