#include "io/image_io.h"

#include "io/atomic_file.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <fstream>
#include <memory>
#include <system_error>

namespace specbake::io {
namespace fs = std::filesystem;

namespace {

// Largest side accepted: bigger files are almost certainly corrupt headers, and would not fit in memory.
constexpr int kMaxSide = 1 << 15;

std::string one_line(std::string s) {
    std::replace(s.begin(), s.end(), '\n', ' ');
    while (!s.empty() && (s.back() == ' ' || s.back() == '\r')) s.pop_back();
    return s.empty() ? std::string("unknown decoder error") : s;
}

OIIO::ImageSpec reader_config() {
    OIIO::ImageSpec config;
    // Data maps: keep alpha unassociated (no premultiplication of RGB by A on read).
    config.attribute("oiio:UnassociatedAlpha", 1);
    return config;
}

Result<DecodedImage> decode(OIIO::ImageInput& in, const std::string& name) {
    const OIIO::ImageSpec& spec = in.spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
        return make_error(name + ": empty image (" + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                          ")");
    if (spec.width > kMaxSide || spec.height > kMaxSide)
        return make_error(name + ": image is " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                          ", larger than " + std::to_string(kMaxSide) + " per side");
    if (spec.depth > 1) return make_error(name + ": volume images are not supported");
    DecodedImage out;
    out.image = Image(spec.width, spec.height, spec.nchannels);
    if (!in.read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, out.image.pixels.data()))
        return make_error(name + ": cannot decode: " + one_line(in.geterror()));
    const OIIO::TypeDesc::BASETYPE base = OIIO::TypeDesc::BASETYPE(spec.format.basetype);
    out.info.is_float = base == OIIO::TypeDesc::HALF || base == OIIO::TypeDesc::FLOAT || base == OIIO::TypeDesc::DOUBLE;
    out.info.bits_per_channel = int(spec.format.size()) * 8;
    if (!out.info.is_float && out.info.bits_per_channel > 16) out.info.bits_per_channel = 16;
    out.info.format = in.format_name();
    out.info.color_space = spec.get_string_attribute("oiio:ColorSpace");
    return out;
}

uint32_t be32(const uint8_t* p) { return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3]; }

// Walks the chunks of a PNG before libpng sees it: libpng reports truncation and empty headers on
// stderr by itself, and the error should be one line from specbake instead.
Result<void> check_png_structure(std::span<const uint8_t> b, const std::string& name) {
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
            first = false;
        }
        at += size_t(length) + 12;
        if (type == "IEND") return {};
    }
}

}  // namespace

Result<DecodedImage> decode_image(const fs::path& path) {
    const std::string name = path.string();
    std::error_code ec;
    if (!fs::exists(path, ec)) return make_error(name + ": no such file");
    if (fs::is_directory(path, ec)) return make_error(name + ": is a folder, not an image");
    {
        std::ifstream f(path, std::ios::binary);
        char head[8] = {};
        if (f.read(head, 8) && static_cast<uint8_t>(head[0]) == 0x89 && head[1] == 'P') {
            f.close();
            auto bytes = read_file(path);
            if (!bytes) return bytes.error();
            return decode_image_memory(*bytes, name);  // checks the chunk structure first
        }
    }
    const OIIO::ImageSpec config = reader_config();
    auto in = OIIO::ImageInput::open(name, &config);
    if (!in) return make_error(name + ": cannot read as an image: " + one_line(OIIO::geterror()));
    auto result = decode(*in, name);
    in->close();
    return result;
}

Result<DecodedImage> decode_image_memory(std::span<const uint8_t> bytes, const std::string& name_for_errors) {
    if (bytes.empty()) return make_error(name_for_errors + ": no image data");
    if (auto ok = check_png_structure(bytes, name_for_errors); !ok) return ok.error();
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
    OIIO::Filesystem::IOMemReader reader(const_cast<uint8_t*>(bytes.data()), bytes.size());
    OIIO::ImageSpec config = reader_config();
    void* proxy = &reader;
    config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
    auto in = OIIO::ImageInput::open(probe, &config, &reader);
    if (!in) return make_error(name_for_errors + ": cannot read as an image: " + one_line(OIIO::geterror()));
    auto result = decode(*in, name_for_errors);
    in->close();
    return result;
}

Result<Image> read_image(const fs::path& path) {
    auto d = decode_image(path);
    if (!d) return d.error();
    return std::move(d->image);
}

Result<Image> read_image_memory(std::span<const uint8_t> bytes, const std::string& name_for_errors) {
    auto d = decode_image_memory(bytes, name_for_errors);
    if (!d) return d.error();
    return std::move(d->image);
}

Result<void> write_image(const fs::path& path, const Image& image, int bits) {
    const std::string name = path.string();
    if (image.empty()) return make_error(name + ": empty image");
    std::error_code ec;
    if (path.has_parent_path()) fs::create_directories(path.parent_path(), ec);
    if (ec) return make_error(path.parent_path().string() + ": cannot create folder: " + ec.message());
    AtomicOutput file(path);
    auto out = OIIO::ImageOutput::create(name);
    if (!out) return make_error(name + ": no writer for this extension: " + one_line(OIIO::geterror()));
    OIIO::ImageSpec spec(image.width, image.height, image.channels,
                         bits <= 8 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::UINT16);
    spec.attribute("oiio:UnassociatedAlpha", 1);  // data, not premultiplied colour: store as given
    if (!out->open(file.temp_path().string(), spec) ||
        !out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data()) || !out->close())
        return make_error(name + ": cannot write: " + one_line(out->geterror()));
    return file.commit();
}

}  // namespace specbake::io
