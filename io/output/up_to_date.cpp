#include "io/output/up_to_date.h"

#include "io/output/manifest.h"
#include "io/files/sha256.h"

#include <tbb/parallel_for.h>

#include <algorithm>

namespace specbake::io {
namespace fs = std::filesystem;

namespace {

Freshness stale(std::string reason) {
    Freshness f;
    f.reason = std::move(reason);
    return f;
}

nlohmann::json without_keys(nlohmann::json settings, const std::vector<std::string>& keys) {
    if (settings.is_object())
        for (const std::string& k : keys) settings.erase(k);
    return settings;
}

}  // namespace

fs::path resolve_recorded_input(const std::string& recorded, const fs::path& output_dir) {
    const fs::path p(recorded);
    if (p.is_absolute()) return p;
    return (output_dir / p).lexically_normal();
}

Freshness check_up_to_date(const FreshnessQuery& query) {
    const fs::path manifest_path = query.output_dir / "manifest.json";
    std::error_code ec;
    if (!fs::exists(manifest_path, ec)) return stale("no manifest in " + query.output_dir.string());
    auto manifest = read_manifest(manifest_path);
    if (!manifest) return stale(manifest.error().message);
    if (manifest->version != query.tool_version)
        return stale("made by specbake " + manifest->version + ", this is " + query.tool_version);
    if (without_keys(manifest->settings, query.derived_setting_keys) !=
        without_keys(query.settings, query.derived_setting_keys))
        return stale("settings changed");

    for (const std::string& given : query.inputs) {
        const bool recorded = std::any_of(manifest->inputs.begin(), manifest->inputs.end(),
                                          [&](const ManifestInput& in) { return in.path == given; });
        if (!recorded) return stale("input " + given + " is not in the manifest");
    }
    if (manifest->inputs.empty()) return stale("the manifest lists no inputs");
    if (!manifest->skipped.empty())
        return stale("the last bake skipped " + std::to_string(manifest->skipped.size()) + " input(s): " +
                     manifest->skipped.front());

    // Every input and output hashed at once (in parallel); the first difference in manifest order is reported.
    const size_t n_in = manifest->inputs.size(), n_out = manifest->outputs.size();
    std::vector<Result<std::string>> hashes(n_in + n_out, Result<std::string>(std::string()));
    tbb::parallel_for(size_t(0), n_in + n_out, [&](size_t i) {
        hashes[i] = sha256_file(i < n_in ? resolve_recorded_input(manifest->inputs[i].path, query.output_dir)
                                         : query.output_dir / manifest->outputs[i - n_in].path);
    });
    Freshness fresh;
    for (size_t i = 0; i < n_in; ++i) {
        const ManifestInput& in = manifest->inputs[i];
        if (!hashes[i]) return stale("input " + in.path + " is missing");
        if (*hashes[i] != in.sha256) return stale("input " + in.path + " changed");
        fresh.recorded_inputs.push_back(in.path);
    }
    for (size_t i = 0; i < n_out; ++i) {
        const ManifestOutput& out = manifest->outputs[i];
        if (!hashes[n_in + i]) return stale("output " + out.path + " is missing");
        if (*hashes[n_in + i] != out.sha256) return stale("output " + out.path + " was modified");
    }
    fresh.up_to_date = true;
    return fresh;
}

void mark_manifest_fresh(const fs::path& output_dir) {
    std::error_code ec;
    fs::last_write_time(output_dir / "manifest.json", fs::file_time_type::clock::now(), ec);
}

}  // namespace specbake::io
