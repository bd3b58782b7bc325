// Glint dictionary job: bake, encode as a KTX2 2D array (io/texture/ktx2.h), hash, write atomically, and the
// manifest with every parameter of the dictionary (SPEC Sec. 7).
#include "pipeline/glint_job.h"

#include "io/files/atomic_write.h"
#include "io/files/file_read.h"
#include "io/texture/ktx2.h"
#include "io/files/sha256.h"
#include "pipeline/version.h"

#include "io/output/manifest.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace specbake {
namespace fs = std::filesystem;
using nlohmann::json;

json glint_dictionary_parameters(const GlintDictionarySettings& s) {
    const double sigma_o = glint_sigma_o(s);
    json p;
    p["count"] = s.count;
    p["levels"] = s.levels;
    p["width"] = s.width;
    p["mips"] = int(std::log2(double(s.width))) + 1;
    p["alpha_dict"] = s.alpha_dict;
    p["sigma_o"] = sigma_o;
    p["lobe_std"] = s.lobe_std;
    p["lobe_mean_std"] = glint_mean_std(s);
    p["seed"] = s.seed;
    p["generator"] = "pcg32 stream per marginal, Marsaglia polar normals";
    p["target"] = "beckmann";
    p["slope_range"] = json::array({0.0, 4.0 * sigma_o});
    json layout;
    layout["texture"] = "2d_array";
    layout["vk_format"] = "R16G16B16A16_SFLOAT";
    layout["layers"] = s.levels * (s.count / 4);
    layout["layer"] = "level * count / 4 + marginal / 4";
    layout["channel"] = "marginal % 4";
    layout["u"] = "|slope| / (4 sigma_o), texel x centred at (x + 0.5) / width";
    layout["v"] = 0.5;
    layout["addressing"] = "clamp_to_edge (or mirrored_repeat) in u";
    layout["filter"] = "linear, linear between mips";
    layout["texel"] = "mean density over |slope| in [x, x + 1] texel widths, 2 * texel width * sum = 1";
    layout["level_lobes"] = "level k: 2^k mirrored pairs, nested (level k is a prefix of level k + 1)";
    p["layout"] = layout;
    return p;
}

double glint_dictionary_max_integral_error(const GlintDictionary& d) {
    const GlintDictionarySettings& s = d.settings;
    const double range = 4.0 * glint_sigma_o(s);
    double worst = 0.0;
    for (int m = 0; m < d.mip_count; ++m) {
        const Image& mip = d.mips[size_t(m)];
        for (int layer = 0; layer < d.layers; ++layer)
            for (int c = 0; c < 4; ++c) {
                double sum = 0.0;
                for (int x = 0; x < mip.width; ++x) sum += mip.texel(x, layer)[c];
                worst = std::max(worst, std::fabs(2.0 * range / mip.width * sum - 1.0));
            }
    }
    return worst;
}

namespace {

// The dictionary a previous bake committed in `committed_dir` for the settings `s`, when it can be trusted
// to be byte for byte what `s` bakes: listed in the folder's manifest (committed_dir/manifest.json, or a
// batch manifest one folder up, whose paths carry the scene's folder) written by this tool version, with
// the same parameters, and its file hashing to the listed sha256. Fills `bytes` and returns the entry.
std::optional<io::ManifestOutput> committed_dictionary(const GlintDictionarySettings& s, const fs::path& committed_dir,
                                                       std::vector<uint8_t>& bytes) {
    const std::pair<fs::path, std::string> places[] = {
        {committed_dir / "manifest.json", kGlintDictionaryFile},
        {committed_dir.parent_path() / "manifest.json", committed_dir.filename().string() + "/" + kGlintDictionaryFile}};
    const json parameters = glint_dictionary_parameters(s);
    for (const auto& [manifest_path, listed] : places) {
        std::error_code ec;
        if (!fs::is_regular_file(manifest_path, ec)) continue;
        auto manifest = io::read_manifest(manifest_path);
        if (!manifest || manifest->version != tool_version()) continue;
        for (const io::ManifestOutput& o : manifest->outputs) {
            if (o.kind != "glint_dictionary" || o.path != listed || !o.extra.contains("parameters") ||
                o.extra["parameters"] != parameters)
                continue;
            auto file = io::read_file(committed_dir / kGlintDictionaryFile);
            if (!file || io::sha256_hex(*file) != o.sha256) return std::nullopt;
            bytes = std::move(*file);
            io::ManifestOutput entry = o;
            entry.path = kGlintDictionaryFile;
            return entry;
        }
    }
    return std::nullopt;
}

}  // namespace

Result<io::ManifestOutput> write_glint_dictionary(const GlintDictionarySettings& s, const fs::path& dir,
                                                  const fs::path& committed_dir, bool* reused) {
    if (reused) *reused = false;
    std::vector<uint8_t> bytes;
    if (!committed_dir.empty()) {
        if (auto entry = committed_dictionary(s, committed_dir, bytes)) {
            if (auto ok = io::write_file_atomic(dir / kGlintDictionaryFile, bytes); !ok) return ok.error();
            if (reused) *reused = true;
            return *entry;
        }
    }
    auto dict = shared_glint_dictionary(s);
    if (!dict) return dict.error();
    const GlintDictionary& d = **dict;
    MipChain stacked;
    stacked.levels = d.mips;
    bytes = io::encode_ktx2_array(stacked, d.layers, io::TexelEncoding::Float16);
    if (auto ok = io::write_file_atomic(dir / kGlintDictionaryFile, bytes); !ok) return ok.error();
    io::ManifestOutput out;
    out.kind = "glint_dictionary";
    out.path = kGlintDictionaryFile;
    out.format = "ktx2";
    out.width = s.width;
    out.height = 1;
    out.mips = d.mip_count;
    out.channels = 4;
    out.sha256 = io::sha256_hex(bytes);
    out.extra["layers"] = d.layers;
    out.extra["vkFormat"] = io::ktx2_vk_format(io::TexelEncoding::Float16, 4);
    out.extra["bytes"] = bytes.size();
    out.extra["max_integral_error"] = glint_dictionary_max_integral_error(d);
    out.extra["parameters"] = glint_dictionary_parameters(s);
    return out;
}

Result<io::Manifest> run_glint_job(const GlintDictionarySettings& s, const fs::path& dir) {
    if (auto ok = check_glint_dictionary_settings(s); !ok) return ok.error();
    auto entry = write_glint_dictionary(s, dir);
    if (!entry) return entry.error();
    io::Manifest manifest;
    manifest.version = tool_version();
    manifest.settings["glint_dictionary"] = glint_dictionary_parameters(s);
    json decision;
    decision["target"] = kGlintDictionaryFile;
    decision["action"] = "glint dictionary bake";
    decision["reason"] = "requested (specbake glints)";
    manifest.plan.push_back(decision);
    manifest.outputs.push_back(*entry);
    if (auto ok = io::write_manifest(dir, manifest); !ok) return ok.error();
    return manifest;
}

}  // namespace specbake
