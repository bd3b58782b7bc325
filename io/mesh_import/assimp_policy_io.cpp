// new_policy_io_system(): Assimp's default file access behind the path policy.
#include "io/mesh_import/assimp_policy_io_internal.h"
#include "io/files/file_read.h"

#include <assimp/DefaultIOSystem.h>
#include <assimp/IOStream.hpp>

#include <algorithm>
#include <cstring>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>

namespace specbake::io {
namespace fs = std::filesystem;

namespace {

class PolicyIOSystem final : public Assimp::DefaultIOSystem {
public:
    PolicyIOSystem(const fs::path& asset, const InputPolicy& policy, AssimpReads& reads, AssimpOpenCheck check)
        : asset_(absolute_normal(asset)), folder_(asset_.parent_path()), given_folder_(asset.parent_path()),
          policy_(policy), reads_(reads), check_(std::move(check)) {}

    bool Exists(const char* file) const override {
        const std::optional<fs::path> path = resolve(file);
        return path && DefaultIOSystem::Exists(path->c_str());
    }

    Assimp::IOStream* Open(const char* file, const char* mode) override {
        // Assimp's importers only read; a write would be a bug, and is refused like a path outside.
        if (!mode || std::strchr(mode, 'w') || std::strchr(mode, 'a') || std::strchr(mode, '+')) return nullptr;
        const std::optional<fs::path> path = resolve(file);
        if (!path) return nullptr;
        // A FIFO or device would block the importer (or never end): only regular files are opened.
        if (!check_regular_input(*path)) return nullptr;
        const bool asset = absolute_normal(*path) == asset_;
        if (check_) {
            if (auto ok = check_(*path, asset); !ok) {
                if (reads_.refused.empty())
                    reads_.refused = asset ? ok.error().message : "referenced file '" + shown(*path) + "' refused: " +
                                                                     ok.error().message;
                return nullptr;
            }
        }
        Assimp::IOStream* stream = DefaultIOSystem::Open(path->c_str(), mode);
        if (stream && !asset && std::find(reads_.files.begin(), reads_.files.end(), *path) == reads_.files.end())
            reads_.files.push_back(*path);
        return stream;
    }

private:
    // A referenced file as named in a refusal: relative to the asset's folder.
    std::string shown(const fs::path& p) const {
        const fs::path rel = p.lexically_relative(given_folder_);
        return (rel.empty() ? p : rel).generic_string();
    }

    static fs::path absolute_normal(const fs::path& p) {
        std::error_code ec;
        const fs::path a = fs::absolute(p, ec);
        return (ec ? p : a).lexically_normal();
    }

    // Assimp names a referenced file by joining the asset's folder with the reference as written (an OBJ's
    // "mtllib ../x.mtl" arrives as "FOLDER/../x.mtl"), or by the reference alone; either way the name is
    // taken relative to the asset's folder and resolved once. Each name's answer is kept for the import:
    // Assimp's FileSystemFilter asks Exists and Open for a dozen names derived from every reference, the
    // same ones again for a reference repeated in the file.
    std::optional<fs::path> resolve(const char* file) const {
        if (!file || !*file) return std::nullopt;
        const auto [known, added] = resolved_.try_emplace(file);
        if (added) known->second = resolve_once(file);
        return known->second;
    }

    std::optional<fs::path> resolve_once(const char* file) const {
        const fs::path full = absolute_normal(file);
        if (full == asset_) return fs::path(file);
        fs::path rel = full.lexically_relative(folder_);
        const std::string reference = rel.empty() ? full.string() : rel.generic_string();
        // Resolved against the folder as the asset was named, so the path read and listed has the same form.
        auto resolved = resolve_in_folder(given_folder_, reference, policy_);
        if (resolved) return *resolved;
        if (reads_.refused.empty())
            reads_.refused = "referenced file '" + reference + "' refused: " + resolved.error().message;
        return std::nullopt;
    }

    mutable std::unordered_map<std::string, std::optional<fs::path>> resolved_;
    fs::path asset_, folder_, given_folder_;
    const InputPolicy& policy_;
    AssimpReads& reads_;
    AssimpOpenCheck check_;
};

}  // namespace

Assimp::IOSystem* new_policy_io_system(const fs::path& asset, const InputPolicy& policy, AssimpReads& reads,
                                       AssimpOpenCheck check) {
    return new PolicyIOSystem(asset, policy, reads, std::move(check));
}

}  // namespace specbake::io
