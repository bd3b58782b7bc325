#include "io/image/image_io.h"

#include "io/files/atomic_write.h"
#include "io/files/file_read.h"
#include "io/files/input_policy.h"
#include "io/image/oiio_api.h"
#include "io/image/png_decode.h"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <initializer_list>
#include <fstream>
#include <memory>
#include <string_view>
#include <system_error>
#include <vector>

namespace specbake::io {
namespace fs = std::filesystem;

namespace {

// A file checked into Git LFS but not fetched holds this text instead of the image.
constexpr char kLfsPointerPrefix[] = "version https://git-lfs.github.com/spec/";
constexpr const char* kLfsPointerProblem = "is a Git LFS pointer file, not the image (fetch it: git lfs pull)";

bool is_lfs_pointer(std::span<const uint8_t> bytes) {
    const size_t n = sizeof kLfsPointerPrefix - 1;
    return bytes.size() >= n && std::equal(bytes.begin(), bytes.begin() + n, kLfsPointerPrefix);
}

uint32_t be32(const uint8_t* p) { return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3]; }

// CRC-32 of ISO 3309 / PNG Annex D, table-driven.
uint32_t crc32(std::span<const uint8_t> bytes) {
    static const auto table = [] {
        std::array<uint32_t, 256> t{};
        for (uint32_t n = 0; n < 256; ++n) {
            uint32_t c = n;
            for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
            t[n] = c;
        }
        return t;
    }();
    uint32_t c = 0xFFFFFFFFu;
    for (uint8_t byte : bytes) c = table[(c ^ byte) & 0xFF] ^ (c >> 8);
    return c ^ 0xFFFFFFFFu;
}

// The IHDR fields libpng checks (PNG spec Sec. 11.2.2), checked first so that its complaint comes as one
// line naming the file.
Result<void> check_ihdr(const uint8_t* d, const std::string& name) {
    const uint32_t w = be32(d), h = be32(d + 4);
    const int depth = d[8], colour = d[9];
    auto depth_in = [&](std::initializer_list<int> allowed) {
        return std::find(allowed.begin(), allowed.end(), depth) != allowed.end();
    };
    const bool depth_ok = colour == 0   ? depth_in({1, 2, 4, 8, 16})
                          : colour == 3 ? depth_in({1, 2, 4, 8})
                          : (colour == 2 || colour == 4 || colour == 6) && depth_in({8, 16});
    if (w > 0x7FFFFFFFu || h > 0x7FFFFFFFu || !depth_ok || d[10] != 0 || d[11] != 0 || d[12] > 1)
        return make_error(name + ": invalid PNG header (IHDR: " + std::to_string(w) + "x" + std::to_string(h) +
                          ", bit depth " + std::to_string(depth) + ", colour type " + std::to_string(colour) +
                          ", compression " + std::to_string(d[10]) + ", filter " + std::to_string(d[11]) +
                          ", interlace " + std::to_string(d[12]) + ")");
    return {};
}

// Walks the chunks of a PNG before libpng sees it: libpng reports truncation, empty headers and CRC
// mismatches on stderr by itself, without the file's name, and the error should be one line from
// specbake instead. The header's size is checked against the texel limit here too, before OpenImageIO
// is even loaded.
}  // namespace

Result<void> check_png_structure(std::span<const uint8_t> b, const std::string& name, const InputLimits& limits) {
    static const uint8_t signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    if (b.size() < 8 || !std::equal(signature, signature + 8, b.begin())) return {};
    size_t at = 8;
    bool first = true;
    while (true) {
        if (at + 12 > b.size()) return make_error(name + ": truncated PNG (ends before the IEND chunk)");
        const uint32_t length = be32(b.data() + at);
        const std::string type(reinterpret_cast<const char*>(b.data() + at + 4), 4);
        if (size_t(length) + 12 > b.size() - at)
            return make_error(name + ": truncated PNG (ends inside the " + type + " chunk)");
        if (first) {
            if (type != "IHDR" || length < 8) return make_error(name + ": invalid PNG (no IHDR chunk)");
            const uint32_t w = be32(b.data() + at + 8), h = be32(b.data() + at + 12);
            if (w == 0 || h == 0)
                return make_error(name + ": empty image (" + std::to_string(w) + "x" + std::to_string(h) + ")");
            if (auto r = check_ihdr(b.data() + at + 8, name); !r) return r.error();
            if (uint64_t(w) * h > limits.texels)
                return make_error(name + ": image is " + std::to_string(w) + "x" + std::to_string(h) +
                                  ", its texel count " + over_limit("texels", uint64_t(w) * h, limits.texels));
            first = false;
        }
        // PNG spec Sec. 5.3: the CRC covers the chunk type and data.
        if (crc32(b.subspan(at + 4, size_t(length) + 4)) != be32(b.data() + at + 8 + length))
            return make_error(name + ": corrupt PNG (CRC mismatch in the " + type + " chunk)");
        at += size_t(length) + 12;
        if (type == "IEND") return {};
    }
}

Result<void> check_png_image_data(std::span<const uint8_t> b, const std::string& name) {
    static const uint8_t signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    if (b.size() < 33 || !std::equal(signature, signature + 8, b.begin())) return {};
    const uint8_t* ihdr = b.data() + 16;
    const uint64_t w = be32(ihdr), h = be32(ihdr + 4);
    const int depth = ihdr[8], colour = ihdr[9];
    const uint64_t samples = colour == 2 ? 3 : colour == 4 ? 2 : colour == 6 ? 4 : 1;
    // One filter byte per row of each (non-empty) pass; Adam7's passes start at (x0, y0) with steps (dx, dy).
    auto pass_bytes = [&](uint64_t x0, uint64_t y0, uint64_t dx, uint64_t dy) -> uint64_t {
        const uint64_t pw = w > x0 ? (w - x0 + dx - 1) / dx : 0, ph = h > y0 ? (h - y0 + dy - 1) / dy : 0;
        return pw == 0 || ph == 0 ? 0 : ph * (1 + (pw * samples * uint64_t(depth) + 7) / 8);
    };
    uint64_t expected = 0;
    if (ihdr[12] == 0) {
        expected = pass_bytes(0, 0, 1, 1);
    } else {
        static const uint64_t adam7[7][4] = {{0, 0, 8, 8}, {4, 0, 8, 8}, {0, 4, 4, 8}, {2, 0, 4, 4},
                                             {0, 2, 2, 4}, {1, 0, 2, 2}, {0, 1, 1, 2}};
        for (const auto& p : adam7) expected += pass_bytes(p[0], p[1], p[2], p[3]);
    }
    z_stream z{};
    if (inflateInit(&z) != Z_OK) return make_error(name + ": cannot check the PNG image data (zlib)");
    std::vector<uint8_t> scratch(size_t(1) << 16);
    uint64_t produced = 0;
    int status = Z_OK;
    for (size_t at = 8; at + 12 <= b.size() && status == Z_OK && produced < expected;) {
        const uint32_t length = be32(b.data() + at);
        const std::string_view type(reinterpret_cast<const char*>(b.data() + at + 4), 4);
        if (type == "IEND") break;
        if (type == "IDAT") {
            z.next_in = const_cast<Bytef*>(b.data() + at + 8);
            z.avail_in = length;
            while (status == Z_OK && z.avail_in > 0 && produced < expected) {
                z.next_out = scratch.data();
                z.avail_out = uInt(scratch.size());
                status = inflate(&z, Z_NO_FLUSH);
                produced += scratch.size() - z.avail_out;
                if (status == Z_BUF_ERROR) status = Z_OK;  // no progress possible yet: the next chunk goes on
            }
        }
        at += size_t(length) + 12;
    }
    const std::string why = z.msg ? z.msg : "";
    inflateEnd(&z);
    if (status != Z_OK && status != Z_STREAM_END)
        return make_error(name + ": corrupt PNG image data (zlib: " + (why.empty() ? "error " + std::to_string(status) : why) + ")");
    if (produced < expected)
        return make_error(name + ": PNG image data ends early (" + std::to_string(produced) + " of " +
                          std::to_string(expected) + " bytes once inflated)");
    return {};
}

Result<DecodedImage> decode_image(const fs::path& path, const InputLimits& limits, bool keep_integers) {
    const std::string name = path.string();
    std::error_code ec;
    if (fs::is_directory(path, ec)) return make_error(name + ": is a folder, not an image");
    if (auto ok = check_regular_input(path); !ok) return ok.error();
    {
        std::ifstream f(path, std::ios::binary);
        char head[sizeof kLfsPointerPrefix] = {};
        // PNG and JPEG are checked from their bytes before a decoder sees them (check_png_structure,
        // check_jpeg_markers), so they are decoded from memory like embedded images.
        const bool read = bool(f.read(head, 8));
        f.read(head + 8, sizeof head - 9);
        if (is_lfs_pointer(std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(head), sizeof head - 1)))
            return make_error(name + ": " + kLfsPointerProblem);
        if (!read) return make_error(name + (fs::file_size(path, ec) == 0 ? ": is empty (0 bytes)" : ": is too short to be an image"));
        const bool png = static_cast<uint8_t>(head[0]) == 0x89 && head[1] == 'P';
        const bool jpeg = static_cast<uint8_t>(head[0]) == 0xFF && static_cast<uint8_t>(head[1]) == 0xD8;
        if (png || jpeg) {
            f.close();
            auto bytes = MappedFile::open(path);
            if (!bytes) return bytes.error();
            return decode_image_memory(bytes->bytes(), name, limits, keep_integers);
        }
    }
    auto oiio = oiio::api();
    if (!oiio) return make_error(name + ": " + oiio.error().message);
    return (*oiio)->decode_file(name, limits.texels);
}

Result<DecodedImage> decode_image_memory(std::span<const uint8_t> bytes, const std::string& name_for_errors,
                                         const InputLimits& limits, bool keep_integers) {
    if (bytes.empty()) return make_error(name_for_errors + ": no image data");
    if (is_lfs_pointer(bytes)) return make_error(name_for_errors + ": " + kLfsPointerProblem);
    if (auto ok = check_png_structure(bytes, name_for_errors, limits); !ok) return ok.error();
    // Plain PNGs (most texture libraries) without loading OpenImageIO; the same values and facts.
    if (auto png = decode_plain_png(bytes, keep_integers)) return std::move(*png);
    if (auto ok = check_png_image_data(bytes, name_for_errors); !ok) return ok.error();
    if (auto ok = check_jpeg_markers(bytes, name_for_errors); !ok) return ok.error();
    // OpenImageIO picks the decoder from the name's extension; take it from the leading bytes instead.
    std::string probe = "image.tga";  // the one common format without a signature
    if (bytes.size() >= 4 && bytes[0] == 0x89 && bytes[1] == 'P' && bytes[2] == 'N' && bytes[3] == 'G')
        probe = "image.png";
    else if (bytes.size() >= 2 && bytes[0] == 0xFF && bytes[1] == 0xD8) probe = "image.jpg";
    else if (bytes.size() >= 4 && bytes[0] == 0x76 && bytes[1] == 0x2F && bytes[2] == 0x31 && bytes[3] == 0x01)
        probe = "image.exr";
    else if (bytes.size() >= 4 && ((bytes[0] == 'I' && bytes[1] == 'I') || (bytes[0] == 'M' && bytes[1] == 'M')))
        probe = "image.tif";
    else if (bytes.size() >= 4 && bytes[0] == 'R' && bytes[1] == 'I' && bytes[2] == 'F' && bytes[3] == 'F')
        probe = "image.webp";
    auto oiio = oiio::api();
    if (!oiio) return make_error(name_for_errors + ": " + oiio.error().message);
    return (*oiio)->decode_memory(bytes, probe, name_for_errors, limits.texels);
}

Result<Image> read_image(const fs::path& path, const InputLimits& limits) {
    auto d = decode_image(path, limits);
    if (!d) return d.error();
    return std::move(d->image);
}

Result<Image> read_image_memory(std::span<const uint8_t> bytes, const std::string& name_for_errors,
                                const InputLimits& limits) {
    auto d = decode_image_memory(bytes, name_for_errors, limits);
    if (!d) return d.error();
    return std::move(d->image);
}

Result<void> write_image(const fs::path& path, const Image& image, int bits) {
    const std::string name = path.string();
    if (image.empty()) return make_error(name + ": empty image");
    std::error_code ec;
    if (path.has_parent_path()) fs::create_directories(path.parent_path(), ec);
    if (ec) return make_error(path.parent_path().string() + ": cannot create folder: " + ec.message());
    auto oiio = oiio::api();
    if (!oiio) return make_error(name + ": " + oiio.error().message);
    AtomicOutput file(path);
    if (auto ok = (*oiio)->write_image(file.temp_path().string(), name, image,
                                       bits <= 8 ? oiio::PixelType::Uint8 : oiio::PixelType::Uint16);
        !ok)
        return ok.error();
    return file.commit();
}

}  // namespace specbake::io
