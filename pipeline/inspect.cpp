#include "pipeline/inspect.h"

#include "core/text_format.h"
#include "io/output/manifest.h"
#include "io/files/sha256.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <regex>

namespace specbake {
namespace fs = std::filesystem;
using nlohmann::json;

QuantityStats compute_stats(std::span<const float> values, double lo, double hi) {
    QuantityStats s;
    std::vector<float> finite;
    finite.reserve(values.size());
    for (float v : values) {
        if (std::isfinite(v)) {
            finite.push_back(v);
        } else {
            ++s.nonfinite;
        }
    }
    s.count = (long long)finite.size();
    s.hist_lo = lo;
    s.hist_hi = hi;
    s.histogram.assign(kHistogramBins, 0);
    if (finite.empty()) return s;
    double sum = 0;  // in texel order: the same value whatever the thread count
    for (float v : finite) sum += v;
    s.mean = sum / double(finite.size());
    std::sort(finite.begin(), finite.end());
    s.min = finite.front();
    s.max = finite.back();
    auto rank = [&](double q) {
        const size_t k = size_t(std::ceil(q / 100.0 * double(finite.size())));
        return double(finite[std::clamp<size_t>(k, 1, finite.size()) - 1]);
    };
    s.p01 = rank(1);
    s.p05 = rank(5);
    s.p50 = rank(50);
    s.p95 = rank(95);
    s.p99 = rank(99);
    const double width = hi - lo;
    for (float v : finite) {
        int bin = width > 0 ? int(std::floor((v - lo) / width * kHistogramBins)) : 0;
        ++s.histogram[size_t(std::clamp(bin, 0, kHistogramBins - 1))];
    }
    return s;
}

std::string kind_from_name(const fs::path& path) {
    static const std::regex pattern(R"(.*_(roughness|kernel|lean_xy|lean|normal)(_mip[0-9]+)?)");
    std::smatch m;
    const std::string stem = path.stem().string();
    return std::regex_match(stem, m, pattern) ? m[1].str() : std::string();
}

namespace {

Quantity derive(const MipChain& mips, std::string name, bool derived, const std::function<float(const float*)>& f) {
    Quantity q;
    q.name = std::move(name);
    q.derived = derived;
    for (const Image& level : mips.levels) {
        std::vector<float> values(level.texel_count());
        for (size_t i = 0; i < values.size(); ++i) values[i] = f(level.pixels.data() + i * level.channels);
        q.levels.push_back(std::move(values));
    }
    return q;
}

std::array<int, 5> lean_channels(const std::vector<std::string>& names, int channels) {
    static const std::array<const char*, 5> expected{"m.x", "m.y", "M.xx", "M.yy", "M.xy"};
    std::array<int, 5> at{0, 1, 2, 3, 4};
    for (size_t k = 0; k < expected.size(); ++k) {
        auto it = std::find(names.begin(), names.end(), expected[k]);
        if (it == names.end()) {
            if (k < 4) return {0, 1, 2, 3, std::min(4, channels - 1)};
            continue;
        }
        at[k] = int(it - names.begin());
    }
    return at;
}

void fill_stats(Quantity& q) {
    double lo = INFINITY, hi = -INFINITY;
    for (const auto& level : q.levels)
        for (float v : level)
            if (std::isfinite(v)) {
                lo = std::min(lo, double(v));
                hi = std::max(hi, double(v));
            }
    if (!(lo <= hi)) lo = hi = 0;
    q.stats.clear();
    for (const auto& level : q.levels) q.stats.push_back(compute_stats(level, lo, hi));
}

}  // namespace

std::vector<Quantity> quantities_of(const MipChain& mips, const std::string& kind,
                                    const std::vector<std::string>& channel_names) {
    std::vector<Quantity> out;
    const int c = mips.channels();
    // Derived quantities first: they are what the report and the contact sheet show.
    if (kind == "roughness") {
        const int r = c >= 3 ? 1 : 0;
        out.push_back(derive(mips, "roughness", true, [r](const float* t) { return t[r]; }));
    } else if (kind == "kernel") {
        if (c >= 3) {
            out.push_back(derive(mips, "kernel tr(Sigma)", true, [](const float* t) { return t[0] + t[1]; }));
            // Alpha: the share of the texel's base normals steeper than slope 0.02 (SPECAA_KERNEL_TWO_LOBES).
            if (c >= 4) out.push_back(derive(mips, "rough share", true, [](const float* t) { return t[3]; }));
        } else {
            out.push_back(derive(mips, "kernel t", true, [](const float* t) { return t[0]; }));
        }
    } else if (kind == "lean" && c >= 4) {
        // Channels (m.x, m.y, M.xx, M.yy, M.xy); EXR files name them and store them sorted by name.
        const std::array<int, 5> at = lean_channels(channel_names, c);
        // SPEC Sec. 3: Sigma = M - m m^T, clamped to positive semi-definite.
        out.push_back(derive(mips, "variance tr(Sigma)", true, [at](const float* t) {
            return std::max(0.0f, t[at[2]] - t[at[0]] * t[at[0]]) + std::max(0.0f, t[at[3]] - t[at[1]] * t[at[1]]);
        }));
        if (c >= 5) {
            out.push_back(derive(mips, "variance lambda_max", true, [at](const float* t) {
                const double mx = t[at[0]], my = t[at[1]];
                const double xx = std::max(0.0, double(t[at[2]]) - mx * mx);
                const double yy = std::max(0.0, double(t[at[3]]) - my * my);
                const double xy = double(t[at[4]]) - mx * my;
                const double half_diff = 0.5 * (xx - yy);
                return float(std::max(0.0, 0.5 * (xx + yy) + std::sqrt(half_diff * half_diff + xy * xy)));
            }));
        }
    }
    for (int ch = 0; ch < c; ++ch) {
        const std::string name = ch < int(channel_names.size()) ? channel_names[size_t(ch)] : "C" + std::to_string(ch);
        out.push_back(derive(mips, name, false, [ch](const float* t) { return t[ch]; }));
    }
    for (Quantity& q : out) fill_stats(q);
    return out;
}

Result<TextureReport> inspect_texture(const fs::path& path, std::string kind, const io::InputLimits& limits) {
    auto texture = io::read_texture_for_inspection(path, limits);
    if (!texture) return texture.error();
    TextureReport r;
    r.path = path.string();
    r.kind = kind.empty() ? kind_from_name(path) : std::move(kind);
    if (r.kind == "lean" && texture->mips.channels() == 1) r.kind = "lean_xy";
    r.texture = std::move(*texture);
    r.quantities = quantities_of(r.texture.mips, r.kind, r.texture.channel_names);
    return r;
}

namespace {

json stats_json(const QuantityStats& s) {
    return {{"count", s.count}, {"nonfinite", s.nonfinite}, {"min", s.min},  {"max", s.max},
            {"mean", s.mean},   {"p01", s.p01},             {"p05", s.p05},  {"p50", s.p50},
            {"p95", s.p95},     {"p99", s.p99},
            {"histogram", {{"lo", s.hist_lo}, {"hi", s.hist_hi}, {"counts", s.histogram}}}};
}

std::string sparkline(const std::vector<long long>& counts) {
    static const char ramp[] = " .:-=+*#%@";
    const long long top = counts.empty() ? 0 : *std::max_element(counts.begin(), counts.end());
    std::string out;
    for (long long c : counts) {
        const int k = top ? int(std::ceil(double(c) / double(top) * 9.0)) : 0;
        out += ramp[std::clamp(k, 0, 9)];
    }
    return out;
}

// Bytes level L takes in its container (every layer), 0 when the container's sizes are not known.
size_t level_bytes(const io::InspectedTexture& t, size_t level) {
    const Image& l = t.mips.levels[level];
    if (t.block_bytes > 0) return size_t((l.width + 3) / 4) * size_t((l.height + 3) / 4) * size_t(t.block_bytes);
    return t.mips.levels[level].texel_count() * size_t(t.mips.levels[level].channels) * size_t(t.channel_bytes);
}

}  // namespace

json report_json(const TextureReport& r) {
    const MipChain& m = r.texture.mips;
    json j = {{"path", r.path},
              {"kind", r.kind},
              {"format", r.texture.format},
              {"pixel_format", r.texture.pixel_format},
              {"transfer", r.texture.transfer},
              {"width", m.width()},
              {"height", m.levels.empty() ? 0 : r.texture.layer_height(0)},
              {"mips", m.levels.size()},
              {"channels", m.channels()},
              {"channel_names", r.texture.channel_names}};
    // A 2D array (KTX2): sizes are one layer's; the statistics cover every layer of the level.
    if (r.texture.layers > 0) j["layers"] = r.texture.layers;
    json levels = json::array();
    for (size_t L = 0; L < m.levels.size(); ++L) {
        json q = json::object();
        for (const Quantity& quantity : r.quantities) q[quantity.name] = stats_json(quantity.stats[L]);
        json level = {{"level", L}, {"width", m.levels[L].width}, {"height", r.texture.layer_height(L)}};
        if (r.texture.channel_bytes > 0) level["bytes"] = level_bytes(r.texture, L);
        if (r.texture.layers > 0) level["layers"] = r.texture.layers;
        level["quantities"] = std::move(q);
        levels.push_back(std::move(level));
    }
    j["levels"] = std::move(levels);
    return j;
}

std::string report_text(const TextureReport& r, bool all) {
    const MipChain& m = r.texture.mips;
    const int layers = r.texture.layers;
    const std::string layer_text = layers > 0 ? " x " + std::to_string(layers) + " layers (2D array)" : "";
    std::string out = r.path + ": " + r.texture.format + " " + r.texture.pixel_format + " (" + r.texture.transfer +
                      "), " + std::to_string(m.width()) + "x" + std::to_string(m.levels.empty() ? 0 : r.texture.layer_height(0)) +
                      layer_text + ", " + std::to_string(m.levels.size()) + " mips, " + std::to_string(m.channels()) +
                      " channels" + (r.kind.empty() ? "" : ", kind " + r.kind) + "\n";
    if (layers > 0) {
        // Per-level sizes of the array: one layer's size and the level's bytes over all layers.
        out += "  levels:";
        for (size_t L = 0; L < m.levels.size(); ++L)
            out += " " + std::to_string(L) + ": " + std::to_string(m.levels[L].width) + "x" +
                   std::to_string(r.texture.layer_height(L)) + " (" +
                   std::to_string(level_bytes(r.texture, L)) + " B)" + (L + 1 < m.levels.size() ? "," : "");
        out += "\n";
    }
    const bool any_derived = std::any_of(r.quantities.begin(), r.quantities.end(), [](auto& q) { return q.derived; });
    for (const Quantity& q : r.quantities) {
        if (any_derived && !q.derived && !all) continue;
        out += "  " + q.name + "   (histogram over [" + format_double("%.4g", q.stats[0].hist_lo) + ", " +
               format_double("%.4g", q.stats[0].hist_hi) + "])\n";
        out += "    mip  size          min        p5       p50       p95       max      mean  histogram\n";
        for (size_t L = 0; L < q.stats.size(); ++L) {
            const QuantityStats& s = q.stats[L];
            char line[256];
            const std::string size = std::to_string(m.levels[L].width) + "x" + std::to_string(r.texture.layer_height(L)) +
                                     (layers > 0 ? "x" + std::to_string(layers) : "");
            std::snprintf(line, sizeof line, "    %3zu  %-11s %9.4g %9.4g %9.4g %9.4g %9.4g %9.4g  |%s|%s\n", L,
                          size.c_str(), s.min, s.p05, s.p50, s.p95, s.max, s.mean, sparkline(s.histogram).c_str(),
                          s.nonfinite ? (" " + std::to_string(s.nonfinite) + " non-finite").c_str() : "");
            out += line;
        }
    }
    return out;
}

Result<json> diff_textures(const TextureReport& a, const TextureReport& b) {
    const MipChain& ma = a.texture.mips;
    const MipChain& mb = b.texture.mips;
    if (ma.width() != mb.width() || ma.height() != mb.height() || ma.levels.size() != mb.levels.size() ||
        ma.channels() != mb.channels())
        return make_error(a.path + " and " + b.path + " differ in shape: " + std::to_string(ma.width()) + "x" +
                          std::to_string(ma.height()) + "x" + std::to_string(ma.channels()) + ", " +
                          std::to_string(ma.levels.size()) + " mips vs " + std::to_string(mb.width()) + "x" +
                          std::to_string(mb.height()) + "x" + std::to_string(mb.channels()) + ", " +
                          std::to_string(mb.levels.size()) + " mips");
    json levels = json::array();
    bool identical = true;
    for (size_t L = 0; L < ma.levels.size(); ++L) {
        json channels = json::object();
        for (size_t qi = 0; qi < a.quantities.size(); ++qi) {
            const std::vector<float>& va = a.quantities[qi].levels[L];
            const std::vector<float>& vb = b.quantities[qi].levels[L];
            double max_abs = 0, sum_abs = 0, sum_sq = 0;
            long long differing = 0;
            for (size_t i = 0; i < va.size(); ++i) {
                const double d = double(va[i]) - double(vb[i]);
                const bool same = va[i] == vb[i] || (std::isnan(va[i]) && std::isnan(vb[i]));
                if (same) continue;
                ++differing;
                const double ad = std::isfinite(d) ? std::abs(d) : INFINITY;
                max_abs = std::max(max_abs, ad);
                sum_abs += ad;
                sum_sq += ad * ad;
            }
            identical &= differing == 0;
            const double n = double(std::max<size_t>(1, va.size()));
            channels[a.quantities[qi].name] = {{"max_abs", max_abs},
                                               {"mean_abs", sum_abs / n},
                                               {"rmse", std::sqrt(sum_sq / n)},
                                               {"differing_texels", differing}};
        }
        levels.push_back({{"level", L}, {"quantities", channels}});
    }
    return json{{"a", a.path}, {"b", b.path}, {"identical", identical}, {"levels", levels}};
}

std::string diff_text(const json& d) {
    std::string out = d["a"].get<std::string>() + " vs " + d["b"].get<std::string>() + ": " +
                      (d["identical"].get<bool>() ? "identical texel values\n" : "differences per mip\n");
    if (d["identical"].get<bool>()) return out;
    out += "    mip  quantity                   max |a-b|  mean |a-b|        rmse  differing texels\n";
    for (const json& level : d["levels"]) {
        for (auto it = level["quantities"].begin(); it != level["quantities"].end(); ++it) {
            char line[256];
            std::snprintf(line, sizeof line, "    %3d  %-24s %11.4g %11.4g %11.4g  %lld\n", level["level"].get<int>(),
                          it.key().c_str(), it.value()["max_abs"].get<double>(), it.value()["mean_abs"].get<double>(),
                          it.value()["rmse"].get<double>(), it.value()["differing_texels"].get<long long>());
            out += line;
        }
    }
    return out;
}

Result<ManifestReport> inspect_manifest(const fs::path& manifest_path, bool check_hashes,
                                        const io::InputLimits& limits) {
    auto manifest = io::read_manifest(manifest_path);
    if (!manifest) return manifest.error();
    ManifestReport r;
    r.manifest = io::to_json(*manifest);
    const fs::path dir = manifest_path.parent_path();
    for (const io::ManifestOutput& o : manifest->outputs) {
        const fs::path file = dir / o.path;
        if (check_hashes) {
            auto hash = io::sha256_file(file);
            if (!hash) {
                r.problems.push_back(hash.error().message);
                continue;
            }
            if (*hash != o.sha256) r.problems.push_back(file.string() + ": content differs from the manifest's hash");
        }
        if (o.format != "ktx2" && o.format != "dds" && o.format != "exr" && o.format != "png") continue;
        auto t = inspect_texture(file, o.kind, limits);
        if (!t) {
            r.problems.push_back(t.error().message);
            continue;
        }
        const MipChain& m = t->texture.mips;
        const int layers = o.extra.contains("layers") && o.extra["layers"].is_number_integer() ? o.extra["layers"].get<int>() : 0;
        if (layers != t->texture.layers)
            r.problems.push_back(file.string() + ": " + std::to_string(t->texture.layers) + " layers, the manifest entry says " +
                                 std::to_string(layers));
        if ((o.width && o.width != m.width()) || (o.height && !m.levels.empty() && o.height != t->texture.layer_height(0)) ||
            (o.channels && o.channels > m.channels()) ||  // DDS pads 3 channels to 4
            (o.mips && o.format != "png" && size_t(o.mips) != m.levels.size()))
            r.problems.push_back(file.string() + ": size, channels or mips differ from the manifest entry");
        r.textures.push_back(std::move(*t));
    }
    return r;
}

namespace {

struct Rgb {
    uint8_t r, g, b;
};

// Viridis at five evenly spaced stops, interpolated linearly.
Rgb false_colour(double t) {
    static const std::array<std::array<double, 3>, 5> stops{
        {{68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}}};
    t = std::clamp(t, 0.0, 1.0) * 4.0;
    const int i = std::min(3, int(t));
    const double f = t - i;
    auto mix = [&](int c) { return uint8_t(std::lround(stops[i][c] + f * (stops[i + 1][c] - stops[i][c]))); };
    return {mix(0), mix(1), mix(2)};
}

// 3x5 glyphs, one string of 15 '#'/'.' per character, rows top to bottom.
const char* glyph(char c) {
    switch (c) {
        case '0': return "####.##.##.####";
        case '1': return ".#.##..#..#.###";
        case '2': return "###..#####..###";
        case '3': return "###..####..####";
        case '4': return "#.##.####..#..#";
        case '5': return "####..###..####";
        case '6': return "####..####.####";
        case '7': return "###..#..#..#..#";
        case '8': return "####.#####.####";
        case '9': return "####.####..####";
        case '.': return ".............#.";
        case '-': return "......###......";
        case '+': return "....#.###.#....";
        case 'e': return "......#####..##";
        default: return "...............";
    }
}

class Canvas {
public:
    Canvas(int w, int h) : w_(w), h_(h), rgb_(size_t(w) * h * 3, 24) {}
    void put(int x, int y, Rgb c) {
        if (x < 0 || y < 0 || x >= w_ || y >= h_) return;
        uint8_t* p = rgb_.data() + (size_t(y) * w_ + x) * 3;
        p[0] = c.r;
        p[1] = c.g;
        p[2] = c.b;
    }
    // Text at scale 2 (6x10 pixels per glyph plus 2 spacing).
    void text(int x, int y, const std::string& s) {
        for (char ch : s) {
            const char* g = glyph(ch);
            for (int gy = 0; gy < 5; ++gy)
                for (int gx = 0; gx < 3; ++gx)
                    if (g[gy * 3 + gx] == '#')
                        for (int k = 0; k < 4; ++k) put(x + gx * 2 + k % 2, y + gy * 2 + k / 2, {235, 235, 235});
            x += 8;
        }
    }
    static int text_width(const std::string& s) { return int(s.size()) * 8; }
    int width() const { return w_; }
    int height() const { return h_; }
    const std::vector<uint8_t>& pixels() const { return rgb_; }

private:
    int w_, h_;
    std::vector<uint8_t> rgb_;
};

constexpr int kMargin = 8;
constexpr int kGap = 6;
constexpr int kLabel = 14;
constexpr int kBarHeight = 12;
constexpr int kMinCell = 16;

struct CellSize {
    int w, h;
};

std::vector<CellSize> cell_sizes(const MipChain& m) {
    const int base_h = std::clamp(m.height(), 64, 256);
    std::vector<CellSize> cells;
    for (size_t L = 0; L < m.levels.size(); ++L) {
        const int h = std::max(kMinCell, base_h >> L);
        const int w = std::max(1, int(std::lround(double(h) * m.levels[L].width / m.levels[L].height)));
        cells.push_back({w, h});
    }
    return cells;
}

const Quantity& sheet_quantity(const TextureReport& r) { return r.quantities.front(); }

}  // namespace

Result<void> write_contact_sheet(std::span<const TextureReport> reports, const fs::path& png) {
    if (reports.empty()) return make_error(png.string() + ": nothing to draw");
    int width = 0, height = kMargin;
    std::vector<int> row_heights;
    for (const TextureReport& r : reports) {
        if (r.quantities.empty()) return make_error(r.path + ": no data to draw");
        int w = kMargin;
        int h = 0;
        for (const CellSize& c : cell_sizes(r.texture.mips)) {
            w += c.w + kGap;
            h = std::max(h, c.h);
        }
        width = std::max({width, w + kMargin, 300});
        row_heights.push_back(h);
        height += h + kLabel + kBarHeight + kLabel + kMargin * 2;
    }
    Canvas canvas(width, height);
    int y = kMargin;
    for (size_t ri = 0; ri < reports.size(); ++ri) {
        const TextureReport& r = reports[ri];
        const Quantity& q = sheet_quantity(r);
        const double lo = q.stats[0].hist_lo, hi = q.stats[0].hist_hi;
        const std::vector<CellSize> cells = cell_sizes(r.texture.mips);
        int x = kMargin;
        for (size_t L = 0; L < cells.size(); ++L) {
            const Image& level = r.texture.mips.levels[L];
            for (int dy = 0; dy < cells[L].h; ++dy)
                for (int dx = 0; dx < cells[L].w; ++dx) {
                    const int sx = std::min(level.width - 1, dx * level.width / cells[L].w);
                    const int sy = std::min(level.height - 1, dy * level.height / cells[L].h);
                    const float v = q.levels[L][size_t(sy) * level.width + sx];
                    canvas.put(x + dx, y + dy,
                               std::isfinite(v) ? false_colour(hi > lo ? (v - lo) / (hi - lo) : 0.5) : Rgb{255, 0, 255});
                }
            canvas.text(x, y + row_heights[ri] + 2, std::to_string(L));
            x += cells[L].w + kGap;
        }
        // Legend: the colour bar over [lo, hi] with its end and middle values.
        const int bar_y = y + row_heights[ri] + kLabel + 2;
        const int bar_w = std::min(256, width - 2 * kMargin);
        for (int bx = 0; bx < bar_w; ++bx)
            for (int by = 0; by < kBarHeight; ++by)
                canvas.put(kMargin + bx, bar_y + by, false_colour(double(bx) / std::max(1, bar_w - 1)));
        const std::string lo_text = format_double("%.3g", lo), mid_text = format_double("%.3g", 0.5 * (lo + hi)), hi_text = format_double("%.3g", hi);
        const int text_y = bar_y + kBarHeight + 2;
        canvas.text(kMargin, text_y, lo_text);
        canvas.text(kMargin + bar_w / 2 - Canvas::text_width(mid_text) / 2, text_y, mid_text);
        canvas.text(kMargin + bar_w - Canvas::text_width(hi_text), text_y, hi_text);
        y += row_heights[ri] + kLabel + kBarHeight + kLabel + kMargin * 2;
    }
    return io::write_png_rgb8(png, canvas.width(), canvas.height(), canvas.pixels());
}

}  // namespace specbake
