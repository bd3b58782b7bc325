// `specbake inspect`: what a bake wrote, per mip level. Reads KTX2/DDS/EXR/PNG outputs and manifests,
// derives the quantities an artist asks about (perceptual roughness, kernel, the variance that the LEAN
// moments imply: Sigma = M - m m^T, SPEC Sec. 3), and reports statistics, histograms, differences between
// two bakes, structural checks and a false-colour contact sheet.
#pragma once

#include "core/image.h"
#include "core/result.h"
#include "io/texture/container_inspect.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace specbake {

inline constexpr int kHistogramBins = 16;

// Statistics of the finite values of one quantity on one mip level. Percentiles are nearest-rank:
// p_q is the ceil(q/100 * n)-th smallest value. The histogram has kHistogramBins equal bins over
// [hist_lo, hist_hi] (shared by all levels of a quantity, so levels compare); the top bin is closed.
struct QuantityStats {
    long long count = 0;      // finite values
    long long nonfinite = 0;  // NaN and infinities, left out of everything else
    double min = 0, max = 0, mean = 0;
    double p01 = 0, p05 = 0, p50 = 0, p95 = 0, p99 = 0;
    double hist_lo = 0, hist_hi = 0;
    std::vector<long long> histogram;
};

// Statistics of `values`; the histogram spans [lo, hi] (values outside are clamped into the end bins).
QuantityStats compute_stats(std::span<const float> values, double lo, double hi);

// One per-texel quantity across the mip chain: a raw channel ("R") or a derived one ("roughness",
// "kernel t", "variance tr(Sigma)", "variance lambda_max").
struct Quantity {
    std::string name;
    bool derived = false;
    std::vector<std::vector<float>> levels;  // texel values of each mip level
    std::vector<QuantityStats> stats;        // per mip level
};

// What a file is, from the manifest "kind" or else from the file name (..._roughness, _kernel, _lean,
// _lean_xy, _normal, optionally followed by _mip<L>): "roughness", "kernel", "lean", "lean_xy", "normal"
// or "" when unknown.
std::string kind_from_name(const std::filesystem::path& path);

// The raw channels and the quantities derived for `kind` (layouts of SPEC Sec. 3 and io/texture/texture_writer.h:
// roughness 1 channel r or 3 channels ORM with r in G; kernel t or (Sigma.xx, Sigma.yy, Sigma.xy);
// LEAN (m.x, m.y, M.xx, M.yy[, M.xy])). Variance is clamped at zero (Sigma is positive semi-definite).
std::vector<Quantity> quantities_of(const MipChain& mips, const std::string& kind,
                                    const std::vector<std::string>& channel_names);

struct TextureReport {
    std::string path;
    std::string kind;
    io::InspectedTexture texture;
    std::vector<Quantity> quantities;  // stats filled
};

// Reads and analyses one texture file (its size held to `limits`); `kind` empty: guessed from the file name.
Result<TextureReport> inspect_texture(const std::filesystem::path& path, std::string kind = "",
                                      const io::InputLimits& limits = {});

nlohmann::json report_json(const TextureReport& report);
// A per-mip table of the derived quantities (all raw channels when none is derived, or with `all`).
std::string report_text(const TextureReport& report, bool all);

// Per mip level and channel: max and mean absolute difference and RMSE between two bakes of equal shape.
// A difference in shape (size, mips, channels) is an error naming both files.
Result<nlohmann::json> diff_textures(const TextureReport& a, const TextureReport& b);
std::string diff_text(const nlohmann::json& diff);

// Every texture a manifest lists, with the manifest's kind, and the manifest facts themselves.
struct ManifestReport {
    nlohmann::json manifest;
    std::vector<TextureReport> textures;
    std::vector<std::string> problems;  // missing files, hash mismatches, structure errors
};
Result<ManifestReport> inspect_manifest(const std::filesystem::path& manifest_path, bool check_hashes,
                                        const io::InputLimits& limits = {});

// `inspect --check` of a manifest: every output hashed (in parallel, from read-only mappings streamed in
// windows, never copied) and compared with the manifest; KTX2/DDS structure checked and their declared
// shape, and EXR/PNG headers, compared with the manifest entry. Takes the folder's lock (waiting for a run
// that writes it; `on_wait` says so), rolls an interrupted commit forward when the folder is writable
// (io/output/output_folder.h; said in `notes`), and reports leftovers of interrupted runs as problems.
struct FolderCheck {
    std::vector<std::string> problems;
    std::vector<std::string> notes;
    uint64_t bytes_hashed = 0;
};
FolderCheck check_manifest_folder(const std::filesystem::path& manifest_path, const io::InputLimits& limits,
                                  const std::function<void(const std::string&)>& on_wait = {});

// One row per report: every mip level of the first derived quantity (else channel R) in false colour
// (viridis; magenta for NaN/inf), scaled by nearest neighbour so small mips stay visible, the mip index
// under each, and a colour bar with its minimum, middle and maximum value drawn in a built-in bitmap font.
Result<void> write_contact_sheet(std::span<const TextureReport> reports, const std::filesystem::path& png);

}  // namespace specbake
