#include "verify/strips.h"

#include "io/texture/texture_writer.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <random>

namespace specbake::verify {
namespace {

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

}  // namespace

Image make_strip(const SimImage& gt, const std::vector<StripTile>& candidates) {
    // Every image pixel drawn as a zoom x zoom block: at least 2x, and about 256 pixels high for small
    // renders, so single-pixel highlights and their errors stay visible.
    const int zoom = std::clamp(256 / std::max(gt.height, 1), 2, 8);
    const int w = gt.width * zoom, h = gt.height * zoom, gap = 4;
    const int columns = 1 + int(candidates.size());
    const int tile_w = w + gap, tile_h = h + kLabelHeight;
    Image strip(columns * tile_w, 2 * tile_h, 3);
    std::vector<float> values;
    for (size_t i = 0; i < gt.texel_count(); ++i)
        if (gt.pixels[2 * i + 1] > 0.0f) values.push_back(gt.pixels[2 * i]);
    float p99 = 1.0f;
    if (!values.empty()) {
        const size_t k = size_t(0.99 * double(values.size() - 1));
        std::nth_element(values.begin(), values.begin() + long(k), values.end());
        p99 = std::max(values[k], 1e-6f);
    }
    const auto tone = [p99](float x) { return (x / p99) / (1.0f + x / p99); };
    const auto put_image = [&](const SimImage& im, int column) {
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                std::fill_n(strip.texel(column * tile_w + x, kLabelHeight + y), 3, srgb(tone(im.texel(x / zoom, y / zoom)[0])));
    };
    put_image(gt, 0);
    draw_text(strip, 2, 3, "ground truth");
    draw_text(strip, 2, tile_h + 3, "error x4");
    for (size_t c = 0; c < candidates.size(); ++c) {
        const int column = int(c) + 1;
        put_image(*candidates[c].image, column);
        const auto [first, second] = wrap_label(candidates[c].label, size_t(std::max(1, w / (4 * kScale))));
        draw_text(strip, column * tile_w + 2, 3, first);
        draw_text(strip, column * tile_w + 2, 3 + kLineHeight, second);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const float err = std::abs(tone(candidates[c].image->texel(x / zoom, y / zoom)[0]) -
                                           tone(gt.texel(x / zoom, y / zoom)[0]));
                heat(4.0f * err, strip.texel(column * tile_w + x, tile_h + kLabelHeight + y));
            }
    }
    return strip;
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
