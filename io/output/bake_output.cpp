// The one-bake-per-folder rule and the staged commit of io/output/bake_output.h.
#include "io/output/bake_output.h"

#include "io/files/atomic_write.h"
#include "io/output/depfile.h"
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

// The recorded inputs as paths from the working folder (the manifest spells them from its own folder).
std::string joined(const std::vector<std::string>& names, const fs::path& dir) {
    std::string out;
    for (const std::string& n : names)
        out += (out.empty() ? "" : ", ") + (n == kDemoIdentity ? n : resolve_recorded_input(n, dir).string());
    return out.empty() ? "unknown inputs" : out;
}

}  // namespace

// The nearest folder above `dir` that holds a specbake manifest, or empty.
fs::path enclosing_bake(const fs::path& dir) {
    std::error_code ec;
    const fs::path start = fs::weakly_canonical(fs::absolute(dir, ec), ec);
    for (fs::path p = start.parent_path(); !p.empty(); p = p.parent_path()) {
        if (fs::is_regular_file(p / "manifest.json", ec) && read_manifest(p / "manifest.json")) return p;
        if (p == p.root_path()) break;
    }
    return {};
}

Result<BakeOutput> BakeOutput::open(const fs::path& dir, const OutputLock* held,
                                    const std::vector<std::string>& identity, bool replace,
                                    const std::function<void(const std::string&)>& on_wait) {
    if (const fs::path outer = enclosing_bake(dir); !outer.empty())
        return make_error(dir.string() + ": is inside " + outer.string() +
                          ", the output folder of another bake (its manifest.json); a bake there would leave "
                          "files that bake does not list: choose a folder outside it");
    BakeOutput out;
    out.replace_ = replace;
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
                return make_error(dir.string() + ": holds the bake of " + joined(before, dir) +
                                  " (manifest.json), which a bake of " + joined(identity, dir) +
                                  " would replace: choose another output folder, or pass --force to replace it");
            out.previous_files_ = bake_files(*previous);
        }
    }
    auto tx = OutputTransaction::begin(*held);
    if (!tx) return tx.error();
    out.tx_ = std::move(*tx);
    return out;
}

Result<void> BakeOutput::commit() {
    if (!replace_) {
        std::error_code ec;
        const fs::path& stage = tx_.stage();
        for (auto it = fs::recursive_directory_iterator(stage, ec); !ec && it != fs::recursive_directory_iterator();
             it.increment(ec)) {
            if (!it->is_regular_file(ec)) continue;
            const std::string rel = it->path().lexically_relative(stage).generic_string();
            if (rel == "manifest.json" || rel == kCommitRecordName) continue;
            const fs::path to = tx_.dir() / rel;
            const bool listed = std::find(previous_files_.begin(), previous_files_.end(), rel) != previous_files_.end();
            if (!listed && fs::exists(fs::symlink_status(to, ec)))
                return make_error(to.string() + ": exists and is not a file of the bake this folder holds (no "
                                  "manifest.json lists it); not replacing it: choose another output folder, or "
                                  "pass --force to replace it");
        }
    }
    return tx_.commit(previous_files_);
}

Result<void> check_depfile_path(const fs::path& depfile, const fs::path& dir, std::span<const fs::path> inputs) {
    std::error_code ec;
    const fs::path file = fs::weakly_canonical(fs::absolute(depfile, ec), ec);
    const fs::path out = fs::weakly_canonical(fs::absolute(dir, ec), ec);
    for (fs::path p = file.parent_path(); !p.empty(); p = p.parent_path()) {
        if (p == out)
            return make_error("--depfile " + depfile.string() + ": is inside the output folder " + dir.string() +
                              ", whose files a bake replaces; write it beside the folder");
        if (p == p.root_path()) break;
    }
    for (const fs::path& in : inputs) {
        if (auto spelled = escape_depfile_path(in.lexically_normal().generic_string()); !spelled)
            return make_error("--depfile " + depfile.string() + ": " + spelled.error().message);
        const bool same = fs::equivalent(depfile, in, ec) || fs::weakly_canonical(fs::absolute(in, ec), ec) == file;
        if (same)
            return make_error("--depfile " + depfile.string() + ": is the input " + in.string() +
                              "; inputs are never overwritten");
    }
    return {};
}

Result<OutputLock> lock_output_folder(const fs::path& dir, const std::string& depfile,
                                      std::span<const fs::path> inputs,
                                      const std::function<void(const std::string&)>& on_wait) {
    if (!depfile.empty())
        if (auto ok = check_depfile_path(depfile, dir, inputs); !ok) return ok.error();
    auto lock = OutputLock::acquire(dir, OutputLock::Purpose::write, on_wait);
    if (!lock) return lock.error();
    if (!depfile.empty())
        if (auto ok = check_writable(depfile); !ok) return make_error("--depfile " + ok.error().message);
    return lock;
}

}  // namespace specbake::io
