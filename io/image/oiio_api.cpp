#include "io/image/oiio_api.h"

#include <dlfcn.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>

namespace specbake::io::oiio {
namespace {
namespace fs = std::filesystem;

constexpr const char* kModuleFile = "libspecbake_oiio.so";

std::vector<fs::path> candidates() {
    if (const char* forced = std::getenv("SPECBAKE_OIIO_MODULE"); forced && *forced) return {fs::path(forced)};
    std::vector<fs::path> paths;
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec) {
        paths.push_back(exe.parent_path() / kModuleFile);
        paths.push_back((exe.parent_path() / SPECBAKE_OIIO_MODULE_FROM_BINDIR / kModuleFile).lexically_normal());
    }
    paths.push_back(fs::path(SPECBAKE_OIIO_MODULE_INSTALLED));
    paths.push_back(fs::path(SPECBAKE_OIIO_MODULE_BUILT));
    return paths;
}

Result<const Api*> load() {
    std::string problems;
    auto note = [&](const fs::path& p, const std::string& why) {
        problems += (problems.empty() ? "" : "; ") + p.string() + ": " + why;
    };
    for (const fs::path& path : candidates()) {
        std::error_code ec;
        if (!fs::is_regular_file(path, ec)) {
            note(path, "not found");
            continue;
        }
        // RTLD_LOCAL: OpenImageIO's own dependencies stay out of the global symbol scope.
        void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!handle) {
            const char* why = dlerror();
            note(path, why ? why : "cannot be loaded");
            continue;
        }
        using Entry = const Api* (*)();
        const auto entry = reinterpret_cast<Entry>(dlsym(handle, "specbake_oiio_api"));
        const Api* found = entry ? entry() : nullptr;
        if (!found) {
            note(path, "not a specbake image module");
            dlclose(handle);
            continue;
        }
        if (found->size != sizeof(Api) || std::strcmp(found->tag, SPECBAKE_OIIO_API_TAG) != 0) {
            note(path, std::string("belongs to specbake ") + found->tag + ", this is " + SPECBAKE_OIIO_API_TAG);
            dlclose(handle);
            continue;
        }
        return found;  // stays loaded for the life of the process
    }
    return make_error("image support (OpenImageIO) is unavailable: " + problems +
                      " (set SPECBAKE_OIIO_MODULE to the path of " + kModuleFile + ")");
}

}  // namespace

Result<const Api*> api() {
    static const Result<const Api*> loaded = load();
    return loaded;
}

}  // namespace specbake::io::oiio
