#include "verify/strips.h"

#include "io/texture/texture_writer.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <random>

namespace specbake::verify {
namespace {

// The 99th percentile of the ground truth's radiance over the pixels the object covers (1 when it covers
// none): the white point of the strips' and harm maps' tone mapping.
float covered_p99(const SimImage& gt) {
    std::vector<float> values;
    for (size_t i = 0; i < gt.texel_count(); ++i)
        if (gt.pixels[2 * i + 1] > 0.0f) values.push_back(gt.pixels[2 * i]);
    if (values.empty()) return 1.0f;
    const size_t k = size_t(0.99 * double(values.size() - 1));
    std::nth_element(values.begin(), values.begin() + long(k), values.end());
    return std::max(values[k], 1e-6f);
}


// 3 x 5 pixel glyphs, one row per 3-bit value (bit 2 = left column).
struct Glyph {
    char c;
    unsigned char rows[5];
};
constexpr Glyph kFont[] = {
    {'a', {2, 5, 7, 5, 5}}, {'b', {6, 5, 6, 5, 6}}, {'c', {3, 4, 4, 4, 3}}, {'d', {6, 5, 5, 5, 6}},
    {'e', {7, 4, 6, 4, 7}}, {'f', {7, 4, 6, 4, 4}}, {'g', {3, 4, 5, 5, 3}}, {'h', {5, 5, 7, 5, 5}},
    {'i', {7, 2, 2, 2, 7}}, {'j', {1, 1, 1, 5, 2}}, {'k', {5, 5, 6, 5, 5}}, {'l', {4, 4, 4, 4, 7}},
    {'m', {5, 7, 7, 5, 5}}, {'n', {6, 5, 5, 5, 5}}, {'o', {2, 5, 5, 5, 2}}, {'p', {6, 5, 6, 4, 4}},
    {'q', {2, 5, 5, 6, 3}}, {'r', {6, 5, 6, 5, 5}}, {'s', {3, 4, 2, 1, 6}}, {'t', {7, 2, 2, 2, 2}},
    {'u', {5, 5, 5, 5, 7}}, {'v', {5, 5, 5, 5, 2}}, {'w', {5, 5, 7, 7, 5}}, {'x', {5, 5, 2, 5, 5}},
    {'y', {5, 5, 2, 2, 2}}, {'z', {7, 1, 2, 4, 7}}, {'0', {7, 5, 5, 5, 7}}, {'1', {2, 6, 2, 2, 7}},
    {'2', {6, 1, 2, 4, 7}}, {'3', {6, 1, 2, 1, 6}}, {'4', {5, 5, 7, 1, 1}}, {'5', {7, 4, 6, 1, 6}},
    {'6', {3, 4, 7, 5, 7}}, {'7', {7, 1, 2, 2, 2}}, {'8', {7, 5, 7, 5, 7}}, {'9', {7, 5, 7, 1, 6}},
    {'-', {0, 0, 7, 0, 0}}, {'+', {0, 2, 7, 2, 0}}, {'/', {1, 1, 2, 4, 4}}, {'.', {0, 0, 0, 0, 2}},
    {'_', {0, 0, 0, 0, 7}}, {'|', {2, 2, 2, 2, 2}},
};
constexpr int kScale = 2;
constexpr int kLineHeight = 5 * kScale + 3;
constexpr int kLabelHeight = 2 * kLineHeight + 4;  // two lines of text above each tile

// `label` in at most two lines of `width` characters, broken after a '/', '-' or '+' where one fits.
std::pair<std::string, std::string> wrap_label(const std::string& label, size_t width) {
    if (label.size() <= width) return {label, ""};
    size_t cut = label.find_last_of("/-+", width - 1);
    cut = cut == std::string::npos || cut == 0 ? width : cut + 1;
    return {label.substr(0, cut), label.substr(cut, width)};
}

void draw_text(Image& im, int x0, int y0, const std::string& text) {
    int x = x0;
    for (char ch : text) {
        const char c = char(std::tolower(static_cast<unsigned char>(ch)));
        const Glyph* g = std::find_if(std::begin(kFont), std::end(kFont), [c](const Glyph& f) { return f.c == c; });
        if (g != std::end(kFont)) {
            for (int r = 0; r < 5; ++r)
                for (int col = 0; col < 3; ++col)
                    if (g->rows[r] & (4 >> col))
                        for (int sy = 0; sy < kScale; ++sy)
                            for (int sx = 0; sx < kScale; ++sx) {
                                const int px = x + col * kScale + sx, py = y0 + r * kScale + sy;
                                if (px < im.width && py < im.height)
                                    std::fill_n(im.texel(px, py), 3, 1.0f);
                            }
        }
        x += 4 * kScale;
    }
}

float srgb(float linear) {
    linear = std::clamp(linear, 0.0f, 1.0f);
    return linear <= 0.0031308f ? 12.92f * linear : 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
}

// Black -> red -> yellow -> white over [0, 1].
void heat(float v, float* rgb) {
    v = std::clamp(v, 0.0f, 1.0f) * 3.0f;
    rgb[0] = std::min(v, 1.0f);
    rgb[1] = std::clamp(v - 1.0f, 0.0f, 1.0f);
    rgb[2] = std::clamp(v - 2.0f, 0.0f, 1.0f);
}

double finite_mean(const std::vector<float>& v) {
    double sum = 0;
    long long n = 0;
    for (float x : v)
        if (std::isfinite(x)) sum += x, ++n;
    return n > 0 ? sum / double(n) : 0.0;
}

// A harm-map pixel: the candidate's per-pixel measure `c` minus the baseline's `b`, divided by `scale`,
// over `dim` (a dim copy of the ground truth's display value): red where larger, blue where smaller. Pixels
// either does not score stay black.
void harm_pixel(float c, float b, double scale, float dim, float* rgb) {
    if (!std::isfinite(c) || !std::isfinite(b)) {
        std::fill_n(rgb, 3, 0.0f);
        return;
    }
    const float d = float((double(c) - double(b)) / scale);
    rgb[0] = std::clamp(dim + std::max(d, 0.0f) * (1.0f - dim), 0.0f, 1.0f);
    rgb[1] = dim;
    rgb[2] = std::clamp(dim + std::max(-d, 0.0f) * (1.0f - dim), 0.0f, 1.0f);
}

}  // namespace

namespace {

// The pixels the ground truth covers, with 4 pixels of margin (the whole image when it covers none): at
// the far distance a model is a few dozen pixels of the render.
struct Crop {
    int x0 = 0, y0 = 0, w = 0, h = 0;
};
Crop object_crop(const SimImage& gt) {
    int x_lo = gt.width, x_hi = -1, y_lo = gt.height, y_hi = -1;
    for (int y = 0; y < gt.height; ++y)
        for (int x = 0; x < gt.width; ++x)
            if (gt.texel(x, y)[1] > 0.0f) x_lo = std::min(x_lo, x), x_hi = std::max(x_hi, x), y_lo = std::min(y_lo, y), y_hi = std::max(y_hi, y);
    if (x_hi < 0) x_lo = 0, x_hi = gt.width - 1, y_lo = 0, y_hi = gt.height - 1;
    x_lo = std::max(0, x_lo - 4), y_lo = std::max(0, y_lo - 4);
    x_hi = std::min(gt.width - 1, x_hi + 4), y_hi = std::min(gt.height - 1, y_hi + 4);
    return {x_lo, y_lo, x_hi - x_lo + 1, y_hi - y_lo + 1};
}

std::string ratio_caption(const SimMetrics& m, const SimMetrics& none) {
    const auto r = [](double c, double b) {
        if (!(b > 0)) return std::string("-");
        char text[32];
        std::snprintf(text, sizeof text, "%.2fx", c / b);
        return std::string(text);
    };
    return "rmse " + r(m.rmse, none.rmse) + " flicker " + r(m.flicker, none.flicker) + " t-err " +
           r(m.temporal_error, none.temporal_error);
}

}  // namespace

std::vector<StripTile> strip_tiles(const std::vector<CandidateReport>& candidates, bool glint, int best, bool all) {
    std::vector<StripTile> tiles;
    const auto in_family = [glint](const CandidateReport& c) {
        return !c.image.empty() && (c.family == "glint") == glint;
    };
    const CandidateReport* none = nullptr;
    for (const CandidateReport& c : candidates)
        if (in_family(c) && c.name == (glint ? "glint-c20" : "none")) none = &c;
    const auto tile = [none](const CandidateReport& c) {
        return StripTile{c.name, &c.image, none && &c != none ? ratio_caption(c.metrics, none->metrics) : ""};
    };
    if (glint || all) {
        for (const CandidateReport& c : candidates)
            if (in_family(c)) tiles.push_back(tile(c));
        return tiles;
    }
    std::vector<const CandidateReport*> others;
    if (none) tiles.push_back(tile(*none));
    for (const CandidateReport& c : candidates) {
        if (!in_family(c) || &c == none) continue;
        if (c.name == "default" || c.name.rfind("default:", 0) == 0) tiles.push_back(tile(c));
        else if (c.family != "limit" && c.name != "limit" && c.name != "floor") others.push_back(&c);
    }
    // Rank sum over RMSE and tone-mapped flicker; ties keep the report's order.
    std::vector<double> score(others.size(), 0.0);
    for (const auto key : {&SimMetrics::rmse, &SimMetrics::flicker}) {
        std::vector<size_t> order(others.size());
        for (size_t i = 0; i < order.size(); ++i) order[i] = i;
        std::stable_sort(order.begin(), order.end(),
                         [&](size_t a, size_t b) { return others[a]->metrics.*key < others[b]->metrics.*key; });
        for (size_t r = 0; r < order.size(); ++r) score[order[r]] += double(r);
    }
    std::vector<size_t> order(others.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return score[a] < score[b]; });
    for (size_t i = 0; i < order.size() && int(i) < best; ++i) tiles.push_back(tile(*others[order[i]]));
    return tiles;
}

StripHarm default_strip_harm(const std::vector<CandidateReport>& candidates) {
    const CandidateReport* none = nullptr;
    const CandidateReport* fallback = nullptr;
    for (const CandidateReport& c : candidates) {
        if (c.name == "none") none = &c;
        if (c.name == "default") fallback = &c;
    }
    if (!none || !fallback) return {};
    return {"default - none", &fallback->pixel_temporal_error, &none->pixel_temporal_error};
}

Image make_strip(const SimImage& gt, const std::vector<StripTile>& candidates, const StripHarm* harm) {
    const Crop crop = object_crop(gt);
    // Every image pixel drawn as a zoom x zoom block, the crop about 320 pixels across, so single-pixel
    // highlights and their errors stay visible and labels of 40 characters fit.
    const int zoom = std::clamp(320 / std::max(crop.w, crop.h), 1, 12);
    const int w = crop.w * zoom, h = crop.h * zoom, gap = 6;
    const bool with_harm = harm && harm->candidate && harm->baseline && !harm->candidate->empty() &&
                           harm->candidate->size() == gt.texel_count() && harm->baseline->size() == gt.texel_count();
    const int cells = 1 + int(candidates.size()) + (with_harm ? 1 : 0);
    const int columns = std::min(cells, 4), rows = (cells + columns - 1) / columns;
    const int cell_w = std::max(w, 40 * 4 * kScale) + gap, cell_h = kLabelHeight + 2 * h + gap + gap;
    Image strip(columns * cell_w, rows * cell_h, 3);
    const float p99 = covered_p99(gt);
    const auto tone = [p99](float x) { return (x / p99) / (1.0f + x / p99); };
    const auto sample = [&](const SimImage& im, int x, int y) { return im.texel(crop.x0 + x / zoom, crop.y0 + y / zoom)[0]; };
    const auto origin = [&](int cell) { return std::pair<int, int>((cell % columns) * cell_w, (cell / columns) * cell_h); };
    const auto label = [&](int cell, const std::string& name, const std::string& caption) {
        const auto [x0, y0] = origin(cell);
        const size_t width = size_t(std::max(1, (cell_w - gap) / (4 * kScale)));
        draw_text(strip, x0 + 2, y0 + 3, wrap_label(name, width).first);
        draw_text(strip, x0 + 2, y0 + 3 + kLineHeight, caption.substr(0, width));
    };
    const auto put_image = [&](const SimImage& im, int cell) {
        const auto [x0, y0] = origin(cell);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                std::fill_n(strip.texel(x0 + x, y0 + kLabelHeight + y), 3, srgb(tone(sample(im, x, y))));
    };
    put_image(gt, 0);
    label(0, "ground truth", "error x4 below; ratios to none");
    for (size_t c = 0; c < candidates.size(); ++c) {
        const int cell = int(c) + 1;
        put_image(*candidates[c].image, cell);
        label(cell, candidates[c].label, candidates[c].caption);
        const auto [x0, y0] = origin(cell);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const float err = std::abs(tone(sample(*candidates[c].image, x, y)) - tone(sample(gt, x, y)));
                heat(4.0f * err, strip.texel(x0 + x, y0 + kLabelHeight + h + gap + y));
            }
    }
    if (with_harm) {
        // The harm map's temporal-error tile over a dim copy of the ground truth.
        const int cell = cells - 1;
        const auto [x0, y0] = origin(cell);
        label(cell, harm->label + " t-err tm", "red: more than it, blue: less");
        const double scale = 2.0 * std::max(finite_mean(*harm->baseline), 1e-9);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const int px = crop.x0 + x / zoom, py = crop.y0 + y / zoom;
                const size_t i = size_t(py) * size_t(gt.width) + size_t(px);
                harm_pixel((*harm->candidate)[i], (*harm->baseline)[i], scale, 0.3f * srgb(tone(gt.texel(px, py)[0])),
                           strip.texel(x0 + x, y0 + kLabelHeight + y));
            }
    }
    return strip;
}

namespace {

HarmSummary harm_summary(const std::vector<float>& c, const std::vector<float>& b, const std::vector<bool>& edge) {
    HarmSummary h;
    double base = 0;
    for (size_t i = 0; i < c.size() && i < b.size(); ++i) {
        if (!std::isfinite(c[i]) || !std::isfinite(b[i])) continue;
        base += b[i];
        const double d = double(c[i]) - double(b[i]);
        if (d > 0) {
            h.excess += d;
            if (edge[i]) h.edge_excess += d;
        } else {
            h.relief -= d;
        }
        ++h.pixels;
    }
    if (base > 0) {
        h.excess /= base;
        h.relief /= base;
        h.edge_excess /= base;
    }
    return h;
}

}  // namespace

Image make_harm_map(const SimImage& gt, const HarmTile& baseline, const std::vector<HarmTile>& candidates,
                    std::vector<HarmReport>* summaries) {
    // Cropped to the object (object_crop), magnified to about 384 pixels.
    const Crop crop = object_crop(gt);
    const int x_lo = crop.x0, y_lo = crop.y0, crop_w = crop.w, crop_h = crop.h;
    const int zoom = std::clamp(384 / std::max(crop_w, crop_h), 1, 12);
    const int w = crop_w * zoom, h = crop_h * zoom, gap = 4;
    const int tile_w = std::max(w, 64 * 4 * kScale) + gap, tile_h = h + kLabelHeight;  // room for 64 characters
    Image map(3 * tile_w, std::max<int>(1, int(candidates.size())) * tile_h, 3);
    // Silhouette band: within 2 pixels of a pixel the ground truth does not fully cover.
    std::vector<bool> edge(gt.texel_count(), false);
    for (int y = 0; y < gt.height; ++y)
        for (int x = 0; x < gt.width; ++x)
            for (int dy = -2; dy <= 2 && !edge[size_t(y) * gt.width + x]; ++dy)
                for (int dx = -2; dx <= 2; ++dx) {
                    const int u = std::clamp(x + dx, 0, gt.width - 1), v = std::clamp(y + dy, 0, gt.height - 1);
                    if (gt.texel(u, v)[1] < 0.999f) {
                        edge[size_t(y) * gt.width + x] = true;
                        break;
                    }
                }
    const float p99 = covered_p99(gt);
    const auto tone = [p99](float x) { return (x / p99) / (1.0f + x / p99); };
    const double scale_flicker = 2.0 * std::max(finite_mean(*baseline.flicker), 1e-9);
    const double scale_terr = 2.0 * std::max(finite_mean(*baseline.temporal_error), 1e-9);
    for (size_t c = 0; c < candidates.size(); ++c) {
        const int row = int(c) * tile_h;
        // Column 0: the ground truth; columns 1, 2: flicker and temporal error against the baseline.
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                std::fill_n(map.texel(x, row + kLabelHeight + y), 3, srgb(tone(gt.texel(x_lo + x / zoom, y_lo + y / zoom)[0])));
        draw_text(map, 2, row + 3, "ground truth");
        const std::vector<float>* mine[2] = {candidates[c].flicker, candidates[c].temporal_error};
        const std::vector<float>* base[2] = {baseline.flicker, baseline.temporal_error};
        const double scale[2] = {scale_flicker, scale_terr};
        const char* what[2] = {"flicker tm", "t-err tm"};
        for (int m = 0; m < 2; ++m) {
            const int x0 = (m + 1) * tile_w;
            const auto [first, second] = wrap_label(candidates[c].label + " - " + baseline.label, size_t(std::max(1, (tile_w - gap) / (4 * kScale))));
            draw_text(map, x0 + 2, row + 3, first + " " + what[m]);
            draw_text(map, x0 + 2, row + 3 + kLineHeight, second);
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    const int px = x_lo + x / zoom, py = y_lo + y / zoom;
                    const size_t i = size_t(py) * gt.width + size_t(px);
                    harm_pixel((*mine[m])[i], (*base[m])[i], scale[m], 0.3f * srgb(tone(gt.texel(px, py)[0])),
                               map.texel(x0 + x, row + kLabelHeight + y));
                }
        }
        if (summaries)
            summaries->push_back({candidates[c].label, harm_summary(*candidates[c].flicker, *baseline.flicker, edge),
                                  harm_summary(*candidates[c].temporal_error, *baseline.temporal_error, edge)});
    }
    return map;
}

Result<void> write_strip_png(const Image& strip, const std::filesystem::path& path) {
    // io::write_texture writes `<stem>_mip0.png` atomically into a folder; a private folder next to the
    // destination keeps that name out of sight, and the rename onto `path` is atomic too.
    std::error_code ec;
    const auto parent = path.parent_path().empty() ? std::filesystem::path(".") : path.parent_path();
    std::filesystem::create_directories(parent, ec);
    if (ec) return make_error(parent.string() + ": cannot create folder: " + ec.message());
    std::random_device rd;
    const auto scratch = parent / (".specbake-strip-" + std::to_string(rd()));
    MipChain chain;
    chain.levels.push_back(strip);
    const io::TextureFileFormat png(io::TextureContainer::PngPerMip);
    auto written = io::write_texture(chain, io::TexelEncoding::Unorm8, png, scratch, "strip", "strip");
    Result<void> result;
    if (!written) {
        result = make_error(path.string() + ": " + written.error().message);
    } else {
        std::filesystem::rename(scratch / "strip_mip0.png", path, ec);
        if (ec) result = make_error(path.string() + ": cannot write: " + ec.message());
    }
    std::filesystem::remove_all(scratch, ec);
    return result;
}

}  // namespace specbake::verify
