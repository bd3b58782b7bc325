#include "io/texture/png_stream.h"

#include <tbb/parallel_for.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

namespace specbake::io {

namespace {

// Rows a strip holds: about this many raw bytes, enough for deflate to find its matches and few enough
// that a 4096-wide level gives both threads strips to compress in every band the bake finishes.
constexpr size_t kStripBytes = size_t(256) << 10;

void put_u32(std::vector<uint8_t>& out, uint32_t v) {
    for (int s = 24; s >= 0; s -= 8) out.push_back(uint8_t(v >> s));
}

// Appends a chunk (length, type, data, CRC over type and data; PNG 1.2 Sec. 3.2).
void put_chunk(std::vector<uint8_t>& out, const char* type, const uint8_t* data, size_t size) {
    put_u32(out, uint32_t(size));
    const size_t at = out.size();
    out.insert(out.end(), type, type + 4);
    if (size) out.insert(out.end(), data, data + size);
    put_u32(out, uint32_t(crc32(0, out.data() + at, uInt(out.size() - at))));
}

void put_text(std::vector<uint8_t>& out, const std::string& key, const std::string& value) {
    std::string text = key;
    text.push_back('\0');
    text += value;
    put_chunk(out, "tEXt", reinterpret_cast<const uint8_t*>(text.data()), text.size());
}

// PNG filter type 2, Up (PNG 1.2 Sec. 6.3): each byte less the byte above (zero above the first row). On
// 4096^2 ORM roughness and mean-normal levels it compressed as well as libpng's per-row choice among all
// five filters (0.079 and 0.025 of the filtered bytes at zlib level 2 either way; no filter: 0.079 and
// 0.043) in a seventh of the filtering time.
void filter_up(const uint8_t* row, const uint8_t* prev, size_t n, uint8_t* out) {
    out[0] = 2;
    if (!prev) {
        std::memcpy(out + 1, row, n);
        return;
    }
    for (size_t i = 0; i < n; ++i) out[i + 1] = uint8_t(row[i] - prev[i]);
}

// 16-bit levels whose filtered bytes carry at least this order-0 entropy (bits a byte) are deflated with
// Huffman codes alone (Z_HUFFMAN_ONLY): their low bytes are noise, where zlib's match search at level 2
// found almost nothing. On the strips of a 2048^2 16-bit mean-normal level (entropy 6.3-6.5) Huffman
// alone gave 0.800 of the filtered bytes at 125 MB/s against level 2's 0.826 at 47 MB/s; ORM roughness
// levels (entropy 0.5-1.0) keep level 2 (0.006 against Huffman's 0.14). Data repeating exactly within the
// 32 KiB window (a map tiled every few hundred texels) would lose its matches above the threshold.
constexpr double kHuffmanOnlyEntropy = 6.0;

// Order-0 entropy of `n` bytes, bits a byte.
double byte_entropy(const uint8_t* p, size_t n) {
    if (n == 0) return 0.0;
    uint32_t count[4][256] = {};
    size_t i = 0;
    for (; i + 4 <= n; i += 4) ++count[0][p[i]], ++count[1][p[i + 1]], ++count[2][p[i + 2]], ++count[3][p[i + 3]];
    for (; i < n; ++i) ++count[0][p[i]];
    double h = 0.0;
    for (int v = 0; v < 256; ++v) {
        const double c = double(count[0][v]) + count[1][v] + count[2][v] + count[3][v];
        if (c > 0) h -= c * std::log2(c / double(n));
    }
    return h / double(n);
}

// Row `y` of the level in PNG byte order (16-bit values big-endian), in `scratch` when it needs a swap.
const uint8_t* png_row(const uint8_t* texels, size_t row_bytes, int bits, int y, std::vector<uint8_t>& scratch) {
    const uint8_t* src = texels + size_t(y) * row_bytes;
    if (bits == 8) return src;
    scratch.resize(row_bytes);
    for (size_t i = 0; i + 1 < row_bytes; i += 2) scratch[i] = src[i + 1], scratch[i + 1] = src[i];
    return scratch.data();
}

}  // namespace

PngLevelStream::PngLevelStream(int width, int height, int channels, int bits, int zlib_level)
    : width_(width), height_(height), channels_(channels), bits_(bits), level_(zlib_level),
      row_bytes_(size_t(width) * size_t(channels) * size_t(bits / 8)) {
    strip_rows_ = int(std::clamp<size_t>(kStripBytes / std::max<size_t>(1, row_bytes_), 1, size_t(height)));
    const size_t strips = (size_t(height) + size_t(strip_rows_) - 1) / size_t(strip_rows_);
    strips_.resize(strips);
    adler_.resize(strips);

    static const uint8_t signature[8] = {137, 80, 78, 71, 13, 10, 26, 10};
    head_.assign(signature, signature + 8);
    std::vector<uint8_t> ihdr;
    put_u32(ihdr, uint32_t(width));
    put_u32(ihdr, uint32_t(height));
    const uint8_t colour_type = channels == 1 ? 0 : channels == 2 ? 4 : 6;  // grey, grey + alpha, RGBA
    ihdr.insert(ihdr.end(), {uint8_t(bits), colour_type, 0, 0, 0});
    put_chunk(head_, "IHDR", ihdr.data(), ihdr.size());
    // The ancillary chunks the OpenImageIO writer gave these files: linear data (gamma 1.0), no offset.
    std::vector<uint8_t> gama;
    put_u32(gama, 100000);
    put_chunk(head_, "gAMA", gama.data(), gama.size());
    const uint8_t offsets[9] = {};
    put_chunk(head_, "oFFs", offsets, sizeof offsets);
    put_text(head_, "oiio:ColorSpace", "Linear");
    put_text(head_, "Software", "specbake");
    put_chunk(tail_, "IEND", nullptr, 0);
}

Result<void> PngLevelStream::add_rows(const uint8_t* texels, int rows) {
    rows = std::min(rows, height_);
    size_t end = next_strip_;
    while (end < strips_.size() && std::min(height_, int(end + 1) * strip_rows_) <= rows) ++end;
    if (end == next_strip_) return {};
    std::vector<std::string> errors(end - next_strip_);
    tbb::parallel_for(next_strip_, end, [&](size_t s) {
        const int y0 = int(s) * strip_rows_, y1 = std::min(height_, y0 + strip_rows_);
        std::vector<uint8_t> filtered(size_t(y1 - y0) * (row_bytes_ + 1)), row_scratch, prev_scratch;
        for (int y = y0; y < y1; ++y) {
            const uint8_t* prev = y > 0 ? png_row(texels, row_bytes_, bits_, y - 1, prev_scratch) : nullptr;
            const uint8_t* row = png_row(texels, row_bytes_, bits_, y, row_scratch);
            filter_up(row, prev, row_bytes_, filtered.data() + size_t(y - y0) * (row_bytes_ + 1));
        }
        adler_[s] = uint32_t(adler32(adler32(0, nullptr, 0), filtered.data(), uInt(filtered.size())));
        z_stream z{};
        const bool noise = bits_ == 16 && byte_entropy(filtered.data(), filtered.size()) >= kHuffmanOnlyEntropy;
        if (deflateInit2(&z, level_, Z_DEFLATED, -15, 8, noise ? Z_HUFFMAN_ONLY : Z_DEFAULT_STRATEGY) != Z_OK) {
            errors[s - next_strip_] = "zlib: cannot start a deflate stream";
            return;
        }
        std::vector<uint8_t> deflated(deflateBound(&z, uLong(filtered.size())) + 16);
        z.next_in = filtered.data();
        z.avail_in = uInt(filtered.size());
        z.next_out = deflated.data();
        z.avail_out = uInt(deflated.size());
        const bool last = s + 1 == strips_.size();
        const int rc = deflate(&z, last ? Z_FINISH : Z_SYNC_FLUSH);
        const size_t size = deflated.size() - z.avail_out;
        deflateEnd(&z);
        if (rc != (last ? Z_STREAM_END : Z_OK) || z.avail_in != 0) {
            errors[s - next_strip_] = "zlib: deflate failed";
            return;
        }
        std::vector<uint8_t> data;
        data.reserve(size + 6);
        // The zlib header (RFC 1950: deflate, 32 KiB window, check bits) before the first strip.
        if (s == 0) data.insert(data.end(), {0x78, uint8_t(level_ <= 1 ? 0x01 : level_ <= 5 ? 0x5e : level_ == 6 ? 0x9c : 0xda)});
        data.insert(data.end(), deflated.begin(), deflated.begin() + std::ptrdiff_t(size));
        std::vector<uint8_t>& chunk = strips_[s];
        put_chunk(chunk, "IDAT", data.data(), data.size());
    });
    for (const std::string& e : errors)
        if (!e.empty()) return make_error(e);
    for (size_t s = next_strip_; s < end; ++s) {
        // The stream's adler32 over all filtered bytes, combined strip by strip, ends the last strip.
        if (s > 0) {
            const int y0 = int(s) * strip_rows_, y1 = std::min(height_, y0 + strip_rows_);
            adler_[s] = uint32_t(adler32_combine(adler_[s - 1], adler_[s], z_off_t(size_t(y1 - y0) * (row_bytes_ + 1))));
        }
    }
    next_strip_ = end;
    rows_read_ = std::max(0, std::min(height_, int(end) * strip_rows_) - 1);
    if (done()) {
        std::vector<uint8_t> check;
        put_u32(check, adler_.back());
        std::vector<uint8_t> last;
        put_chunk(last, "IDAT", check.data(), check.size());
        tail_.insert(tail_.begin(), last.begin(), last.end());
    }
    return {};
}

std::vector<std::span<const uint8_t>> PngLevelStream::pieces() const {
    std::vector<std::span<const uint8_t>> pieces{head_};
    for (const std::vector<uint8_t>& s : strips_) pieces.emplace_back(s);
    pieces.emplace_back(tail_);
    return pieces;
}

size_t PngLevelStream::bytes() const {
    size_t n = head_.size() + tail_.size();
    for (const std::vector<uint8_t>& s : strips_) n += s.size();
    return n;
}

}  // namespace specbake::io
