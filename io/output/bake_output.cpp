// The one-bake-per-folder rule and the staged commit of io/output/bake_output.h.
#include "io/output/bake_output.h"

#include "io/files/atomic_write.h"
#include "io/output/up_to_date.h"

#include <algorithm>

namespace specbake::io {
namespace fs = std::filesystem;

std::vector<std::string> bake_identity(const Manifest& m) {
    if (m.settings.is_object() && m.settings.value("demo", false)) return {kDemoIdentity};
    std::vector<std::string> ids;
    if (!m.plan.is_array()) return ids;
    for (const nlohmann::json& p : m.plan) {
        if (!p.is_object()) continue;
        for (const char* key : {"scene", "target"})
            if (p.contains(key) && p[key].is_string()) ids.push_back(p[key].get<std::string>());
    }
    return ids;
}

std::vector<std::string> bake_files(const Manifest& m) {
    std::vector<std::string> files;
    for (const ManifestOutput& o : m.outputs) files.push_back(o.path);
    if (m.settings.is_object() && m.settings.value("demo", false))
        for (const ManifestInput& in : m.inputs) files.push_back(in.path);
    return files;
}

namespace {

// Spellings of one file compare equal: relative to the working folder, or recorded relative to `dir`.
std::string canonical_input(const std::string& recorded, const fs::path& dir) {
    if (recorded == kDemoIdentity) return recorded;
    std::error_code ec;
    const fs::path p = fs::weakly_canonical(resolve_recorded_input(recorded, dir), ec);
    return ec ? recorded : p.string();
}

std::string joined(const std::vector<std::string>& names) {
    std::string out;
    for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
    return out.empty() ? "unknown inputs" : out;
}

}  // namespace

Result<BakeOutput> BakeOutput::open(const fs::path& dir, const OutputLock* held,
                                    const std::vector<std::string>& identity, bool replace,
                                    const std::function<void(const std::string&)>& on_wait) {
    BakeOutput out;
    if (!held) {
        auto lock = OutputLock::acquire(dir, OutputLock::Purpose::write, on_wait);
        if (!lock) return lock.error();
        out.own_lock_ = std::move(*lock);
        held = &*out.own_lock_;
    }
    const fs::path manifest_path = dir / "manifest.json";
    std::error_code ec;
    if (fs::exists(manifest_path, ec)) {
        auto previous = read_manifest(manifest_path);
        if (!previous && !replace)
            return make_error(previous.error().message +
                              "; not replacing it: choose another output folder, or pass --force to replace it");
        if (previous) {
            const std::vector<std::string> before = bake_identity(*previous);
            std::vector<std::string> now;
            for (const std::string& id : identity) now.push_back(canonical_input(id, dir));
            std::vector<std::string> others;
            for (const std::string& id : before)
                if (std::find(now.begin(), now.end(), canonical_input(id, dir)) == now.end()) others.push_back(id);
            if ((!others.empty() || before.empty()) && !replace)
                return make_error(dir.string() + ": holds the bake of " + joined(before) +
                                  " (manifest.json), which a bake of " + joined(identity) +
                                  " would replace: choose another output folder, or pass --force to replace it");
            out.previous_files_ = bake_files(*previous);
        }
    }
    auto tx = OutputTransaction::begin(*held);
    if (!tx) return tx.error();
    out.tx_ = std::move(*tx);
    return out;
}

Result<OutputLock> lock_output_folder(const fs::path& dir, const std::string& depfile,
                                      const std::function<void(const std::string&)>& on_wait) {
    auto lock = OutputLock::acquire(dir, OutputLock::Purpose::write, on_wait);
    if (!lock) return lock.error();
    if (!depfile.empty())
        if (auto ok = check_writable(depfile); !ok) return make_error("--depfile " + ok.error().message);
    return lock;
}

}  // namespace specbake::io
