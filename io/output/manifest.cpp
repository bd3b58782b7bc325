#include "io/output/manifest.h"

#include "io/files/atomic_write.h"
#include "io/files/file_read.h"
#include "io/files/sha256.h"

namespace specbake::io {
namespace fs = std::filesystem;
using nlohmann::json;

json to_json(const Manifest& m) {
    json j;
    j["tool"] = m.tool;
    j["version"] = m.version;
    j["settings"] = m.settings;
    j["plan"] = m.plan;
    j["inputs"] = json::array();
    for (const ManifestInput& in : m.inputs) j["inputs"].push_back({{"path", in.path}, {"sha256", in.sha256}});
    if (!m.skipped.empty()) j["skipped"] = m.skipped;
    j["outputs"] = json::array();
    for (const ManifestOutput& o : m.outputs) {
        json e = {{"kind", o.kind},   {"path", o.path},         {"format", o.format},
                  {"width", o.width}, {"height", o.height},     {"mips", o.mips},
                  {"channels", o.channels}, {"sha256", o.sha256}};
        for (auto it = o.extra.begin(); it != o.extra.end(); ++it) e[it.key()] = it.value();
        j["outputs"].push_back(std::move(e));
    }
    return j;
}

Result<Manifest> manifest_from_json(const json& j, const std::string& source_name) {
    try {
        Manifest m;
        m.tool = j.at("tool").get<std::string>();
        m.version = j.at("version").get<std::string>();
        m.settings = j.value("settings", json::object());
        m.plan = j.value("plan", json::array());
        for (const json& in : j.at("inputs")) m.inputs.push_back({in.at("path"), in.at("sha256")});
        if (j.contains("skipped")) m.skipped = j.at("skipped").get<std::vector<std::string>>();
        for (const json& e : j.at("outputs")) {
            ManifestOutput o;
            o.kind = e.at("kind");
            o.path = e.at("path");
            o.format = e.at("format");
            o.width = e.value("width", 0);
            o.height = e.value("height", 0);
            o.mips = e.value("mips", 0);
            o.channels = e.value("channels", 0);
            o.sha256 = e.value("sha256", "");
            for (auto it = e.begin(); it != e.end(); ++it) {
                static const char* known[] = {"kind", "path", "format", "width", "height", "mips", "channels", "sha256"};
                bool is_known = false;
                for (const char* k : known) is_known |= it.key() == k;
                if (!is_known) o.extra[it.key()] = it.value();
            }
            m.outputs.push_back(std::move(o));
        }
        return m;
    } catch (const json::exception& e) {
        return make_error(source_name + ": not a specbake manifest: " + e.what());
    }
}

std::string relative_path(const fs::path& file, const fs::path& dir) {
    std::error_code ec_file, ec_dir, ec;
    const fs::path f = fs::weakly_canonical(file, ec_file), d = fs::weakly_canonical(dir, ec_dir);
    fs::path rel;
    if (!ec_file && !ec_dir) rel = fs::relative(f, d, ec);
    // No canonical path under a working folder longer than PATH_MAX: the paths as given, lexically.
    if (ec_file || ec_dir || ec || rel.empty()) rel = file.lexically_normal().lexically_relative(dir.lexically_normal());
    if (rel.empty()) rel = file;
    return rel.generic_string();
}

Result<void> write_manifest(const fs::path& dir, Manifest manifest) {
    std::vector<fs::path> unhashed;
    for (const ManifestOutput& o : manifest.outputs)
        if (o.sha256.empty()) unhashed.push_back(dir / o.path);
    auto hashes = sha256_files(unhashed);
    if (!hashes) return hashes.error();
    size_t next = 0;
    for (ManifestOutput& o : manifest.outputs)
        if (o.sha256.empty()) o.sha256 = (*hashes)[next++];
    return write_file_atomic(dir / "manifest.json", to_json(manifest).dump(2) + "\n");
}

Result<Manifest> read_manifest(const fs::path& manifest_path) {
    auto bytes = read_file(manifest_path);
    if (!bytes) return bytes.error();
    json j = json::parse(bytes->begin(), bytes->end(), nullptr, false);
    if (j.is_discarded()) return make_error(manifest_path.string() + ": not valid JSON");
    return manifest_from_json(j, manifest_path.string());
}

std::string recorded_input_path(const fs::path& file, const fs::path& output_dir) {
    std::error_code ec_in, ec_out;
    fs::path in = fs::absolute(file, ec_in).lexically_normal();
    fs::path out = fs::absolute(output_dir, ec_out).lexically_normal();
    // Under a working folder longer than PATH_MAX no absolute path exists: two relative paths are still
    // related lexically.
    if (ec_in || ec_out) in = file.lexically_normal(), out = output_dir.lexically_normal();
    const fs::path rel = in.lexically_relative(out);
    return (rel.empty() ? in : rel).generic_string();
}

}  // namespace specbake::io
