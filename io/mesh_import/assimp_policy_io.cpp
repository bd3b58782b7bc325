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

// A stream of the asset: counts the asset's open streams, so that an opening of the asset while one is
// open is known as a second reading (Assimp's OBJ reader keeps the OBJ open while it reads the material
// libraries it names, and the OBJ can be one of them). Assimp deletes streams with or without Close.
class CountedStream final : public Assimp::IOStream {
public:
    CountedStream(Assimp::IOStream* stream, int& open) : stream_(stream), open_(open) { ++open_; }
    ~CountedStream() override {
        --open_;
        delete stream_;
    }
    size_t Read(void* buffer, size_t size, size_t count) override { return stream_->Read(buffer, size, count); }
    size_t Write(const void* buffer, size_t size, size_t count) override { return stream_->Write(buffer, size, count); }
    aiReturn Seek(size_t offset, aiOrigin origin) override { return stream_->Seek(offset, origin); }
    size_t Tell() const override { return stream_->Tell(); }
    size_t FileSize() const override { return stream_->FileSize(); }
    void Flush() override { stream_->Flush(); }

private:
    Assimp::IOStream* stream_;
    int& open_;
};

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
        const bool is_asset_file = absolute_normal(*path) == asset_;
        const bool asset = is_asset_file && asset_streams_open_ == 0;  // else the asset read again, as a reference
        if (check_) {
            if (auto ok = check_(*path, asset); !ok) {
                if (reads_.refused.empty())
                    reads_.refused = asset ? ok.error().message : "referenced file '" + shown(*path) + "' refused: " +
                                                                     ok.error().message;
                return nullptr;
            }
        }
        Assimp::IOStream* stream = DefaultIOSystem::Open(path->c_str(), mode);
        if (stream && !is_asset_file && std::find(reads_.files.begin(), reads_.files.end(), *path) == reads_.files.end())
            reads_.files.push_back(*path);
        if (stream && is_asset_file) return new CountedStream(stream, asset_streams_open_);
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
    int asset_streams_open_ = 0;
};

}  // namespace

Assimp::IOSystem* new_policy_io_system(const fs::path& asset, const InputPolicy& policy, AssimpReads& reads,
                                       AssimpOpenCheck check) {
    return new PolicyIOSystem(asset, policy, reads, std::move(check));
}

}  // namespace specbake::io
