// libspecbake_oiio.so: every call specbake makes into OpenImageIO (io/image/oiio_api.h says why this is a
// module loaded on demand). Only specbake_oiio_api() is exported.
#include "io/image/oiio_api.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <memory>
#include <vector>

namespace specbake::io::oiio {
namespace {

// Largest side accepted: bigger files are almost certainly corrupt headers, and would not fit in memory.
constexpr int kMaxSide = 1 << 15;

std::string one_line(std::string s, const char* if_empty) {
    std::replace(s.begin(), s.end(), '\n', ' ');
    while (!s.empty() && (s.back() == ' ' || s.back() == '\r')) s.pop_back();
    return s.empty() ? std::string(if_empty) : s;
}

// A writer's failure with the operating system's reason: OpenImageIO's message rarely carries it, but the
// failing call (fopen, fwrite, fclose through libpng or OpenEXR) leaves it in errno, which is cleared before
// each write sequence. The reason is added unless the message already says it.
std::string write_failure(const std::string& message, int err) {
    std::string text = one_line(message, "unknown writer error");
    if (err != 0) {
        const std::string reason = std::strerror(err);
        if (text.find(reason) == std::string::npos) text += " (" + reason + ")";
    }
    return text;
}

// OpenImageIO's PNG and OpenEXR writers do not report every failed write (a full disk leaves a short file
// after a "successful" close), so where the format takes an IOProxy the bytes go through this one: a
// descriptor of its own, writes gathered into 64 KiB runs, every call checked, and the first failure's
// errno kept for the message. Formats without proxy support write the file themselves.
class CheckedFile final : public OIIO::Filesystem::IOProxy {
public:
    explicit CheckedFile(const std::string& path) : IOProxy(path, Write) {
        fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
        if (fd_ < 0) err_ = errno, m_mode = Closed;
    }
    ~CheckedFile() override { close(); }
    const char* proxytype() const override { return "specbake-checked"; }
    size_t write(const void* buf, size_t size) override {
        if (!run_.empty() && m_pos != run_start_ + int64_t(run_.size())) flush_run();
        if (run_.empty()) run_start_ = m_pos;
        const auto* p = static_cast<const unsigned char*>(buf);
        run_.insert(run_.end(), p, p + size);
        m_pos += int64_t(size);
        if (run_.size() >= (size_t(1) << 16)) flush_run();
        return err_ ? 0 : size;
    }
    size_t pwrite(const void* buf, size_t size, int64_t offset) override {
        flush_run();
        return put(static_cast<const unsigned char*>(buf), size, offset) ? size : 0;
    }
    size_t size() const override {
        const_cast<CheckedFile*>(this)->flush_run();
        struct stat st {};
        return fd_ >= 0 && ::fstat(fd_, &st) == 0 ? size_t(st.st_size) : 0;
    }
    void flush() const override { const_cast<CheckedFile*>(this)->flush_run(); }
    void close() override {
        if (fd_ < 0) return;
        flush_run();
        if (::close(fd_) != 0 && !err_) err_ = errno;
        fd_ = -1;
        m_mode = Closed;
    }
    int error_number() const { return err_; }

private:
    bool put(const unsigned char* p, size_t n, int64_t offset) {
        while (n > 0 && !err_ && fd_ >= 0) {
            const ssize_t w = ::pwrite(fd_, p, n, offset);
            if (w < 0 && errno == EINTR) continue;
            if (w <= 0) {
                err_ = w < 0 ? errno : ENOSPC;
                break;
            }
            p += w, n -= size_t(w), offset += w;
        }
        return !err_ && fd_ >= 0;
    }
    void flush_run() {
        if (run_.empty()) return;
        put(run_.data(), run_.size(), run_start_);
        run_.clear();
    }
    int fd_ = -1;
    int err_ = 0;
    std::vector<unsigned char> run_;
    int64_t run_start_ = 0;
};

// Sets a CheckedFile on an output whose format takes one; finish() then closes it and reports its failure.
// Declared before the ImageOutput, so that the writer (whose destructor may still write) goes first.
class CheckedTarget {
public:
    void attach(OIIO::ImageOutput& out, const std::string& path) {
        if (out.supports("ioproxy")) {
            file_ = std::make_unique<CheckedFile>(path);
            if (!out.set_ioproxy(file_.get())) file_.reset();
        }
    }
    Result<void> finish(const std::string& name) {
        if (!file_) return {};
        file_->close();
        if (const int err = file_->error_number(); err != 0)
            return make_error(name + ": cannot write: " + std::strerror(err));
        return {};
    }
    int error_number() const { return file_ ? file_->error_number() : 0; }

private:
    std::unique_ptr<CheckedFile> file_;
};

OIIO::TypeDesc type_of(PixelType t) {
    switch (t) {
        case PixelType::Uint8: return OIIO::TypeDesc::UINT8;
        case PixelType::Uint16: return OIIO::TypeDesc::UINT16;
        case PixelType::Half: return OIIO::TypeDesc::HALF;
        case PixelType::Float: return OIIO::TypeDesc::FLOAT;
    }
    return OIIO::TypeDesc::FLOAT;
}

OIIO::ImageSpec reader_config() {
    OIIO::ImageSpec config;
    // Data maps: keep alpha unassociated (no premultiplication of RGB by A on read).
    config.attribute("oiio:UnassociatedAlpha", 1);
    return config;
}

// The texel count of the header against the limit, before any pixel is allocated (the header alone says
// 32768 x 32768 in 74 bytes). The wording matches io/files/input_policy.h's over_limit().
Result<void> check_texels(const OIIO::ImageSpec& spec, uint64_t max_texels, const std::string& name) {
    const uint64_t texels = uint64_t(std::max(spec.width, 0)) * uint64_t(std::max(spec.height, 0)) *
                            uint64_t(std::max(spec.depth, 1));
    if (texels > max_texels)
        return make_error(name + ": image is " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                          ", its texel count " + std::to_string(texels) + " exceeds the limit of " +
                          std::to_string(max_texels) + " (--limit texels=N raises it)");
    return {};
}

Result<DecodedImage> decode(OIIO::ImageInput& in, const std::string& name, uint64_t max_texels) {
    const OIIO::ImageSpec& spec = in.spec();
    if (auto r = check_texels(spec, max_texels, name); !r) return r.error();
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
        return make_error(name + ": cannot decode: " + one_line(in.geterror(), "unknown decoder error"));
    const OIIO::TypeDesc::BASETYPE base = OIIO::TypeDesc::BASETYPE(spec.format.basetype);
    out.info.is_float = base == OIIO::TypeDesc::HALF || base == OIIO::TypeDesc::FLOAT || base == OIIO::TypeDesc::DOUBLE;
    out.info.bits_per_channel = int(spec.format.size()) * 8;
    if (!out.info.is_float && out.info.bits_per_channel > 16) out.info.bits_per_channel = 16;
    out.info.format = in.format_name();
    out.info.color_space = spec.get_string_attribute("oiio:ColorSpace");
    return out;
}

Result<DecodedImage> decode_file(const std::string& name, uint64_t max_texels) {
    const OIIO::ImageSpec config = reader_config();
    auto in = OIIO::ImageInput::open(name, &config);
    if (!in) return make_error(name + ": cannot read as an image: " + one_line(OIIO::geterror(), "unknown decoder error"));
    auto result = decode(*in, name, max_texels);
    in->close();
    return result;
}

Result<DecodedImage> decode_memory(std::span<const uint8_t> bytes, const std::string& probe, const std::string& name,
                                   uint64_t max_texels) {
    OIIO::Filesystem::IOMemReader reader(const_cast<uint8_t*>(bytes.data()), bytes.size());
    OIIO::ImageSpec config = reader_config();
    void* proxy = &reader;
    config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
    // A format recognised by its signature (every probe but TGA's, which has none) is opened by its own
    // reader only: ImageInput::open() would try every other reader on a damaged file (LibRaw's among them,
    // which zeroes about a megabyte to start), and their messages are not about this file's format.
    std::unique_ptr<OIIO::ImageInput> in;
    if (probe != "image.tga") {
        in = OIIO::ImageInput::create(probe, false, &config, &reader);
        OIIO::ImageSpec spec;
        if (in && !in->open(probe, spec, config))
            return make_error(name + ": cannot read as an image: " + one_line(in->geterror(), "unknown decoder error"));
    } else {
        in = OIIO::ImageInput::open(probe, &config, &reader);
    }
    if (!in) return make_error(name + ": cannot read as an image: " + one_line(OIIO::geterror(), "unknown decoder error"));
    auto result = decode(*in, name, max_texels);
    in->close();
    return result;
}

Result<void> write_image(const std::string& temp_path, const std::string& name, const Image& image, PixelType type) {
    CheckedTarget target;
    auto out = OIIO::ImageOutput::create(name);
    if (!out) return make_error(name + ": no writer for this extension: " + one_line(OIIO::geterror(), "unknown format"));
    OIIO::ImageSpec spec(image.width, image.height, image.channels, type_of(type));
    spec.attribute("oiio:UnassociatedAlpha", 1);  // data, not premultiplied colour: store as given
    target.attach(*out, temp_path);
    errno = 0;
    if (!out->open(temp_path, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data()) || !out->close()) {
        const int err = target.error_number() ? target.error_number() : errno;
        return make_error(name + ": cannot write: " + write_failure(out->geterror(), err));
    }
    out.reset();
    return target.finish(name);
}

Result<InspectedTexture> read_levels(const std::string& name, uint64_t max_texels) {
    auto in = OIIO::ImageInput::open(name);
    if (!in) return make_error(name + ": cannot read image: " + one_line(OIIO::geterror(), "unknown format"));
    InspectedTexture t;
    const std::string fmt = in->format_name();
    t.format = fmt == "openexr" ? "exr" : fmt;
    OIIO::ImageSpec spec = in->spec();
    t.pixel_format = spec.format.c_str();
    t.transfer = spec.get_string_attribute("oiio:ColorSpace", "linear");
    t.channel_names = spec.channelnames;
    // The meaning recorded by the writer, when it matches the channel count.
    if (const std::string meaning = spec.get_string_attribute("specbake:channels"); !meaning.empty()) {
        std::vector<std::string> names;
        for (size_t at = 0; at <= meaning.size();) {
            const size_t comma = std::min(meaning.find(',', at), meaning.size());
            names.push_back(meaning.substr(at, comma - at));
            at = comma + 1;
        }
        if (int(names.size()) == spec.nchannels) t.channel_names = names;
    }
    for (int level = 0; in->seek_subimage(0, level); ++level) {
        spec = in->spec();
        if (auto r = check_texels(spec, max_texels, name); !r) return r.error();
        Image img(spec.width, spec.height, spec.nchannels);
        if (!in->read_image(0, level, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, img.pixels.data()))
            return make_error(name + ": mip " + std::to_string(level) + ": " + one_line(in->geterror(), "unreadable"));
        t.mips.levels.push_back(std::move(img));
    }
    if (t.mips.levels.empty()) return make_error(name + ": no image data");
    return t;
}

Result<void> write_rgb8(const std::string& temp_path, const std::string& name, int width, int height,
                        const uint8_t* rgb) {
    CheckedTarget target;
    auto file = OIIO::ImageOutput::create(temp_path);
    if (!file) return make_error(name + ": cannot write PNG: " + one_line(OIIO::geterror(), "no PNG writer"));
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    target.attach(*file, temp_path);
    errno = 0;
    if (!file->open(temp_path, spec) || !file->write_image(OIIO::TypeDesc::UINT8, rgb) || !file->close()) {
        const int err = target.error_number() ? target.error_number() : errno;
        return make_error(name + ": cannot write PNG: " + write_failure(file->geterror(), err));
    }
    file.reset();
    return target.finish(name);
}

Result<TextureShape> read_shape(const std::string& name) {
    auto in = OIIO::ImageInput::open(name);
    if (!in) return make_error(name + ": cannot read image: " + one_line(OIIO::geterror(), "unknown format"));
    TextureShape shape;
    const std::string fmt = in->format_name();
    shape.format = fmt == "openexr" ? "exr" : fmt;
    shape.width = in->spec().width;
    shape.height = in->spec().height;
    shape.channels = in->spec().nchannels;
    while (in->seek_subimage(0, shape.mips)) ++shape.mips;
    if (shape.mips == 0) return make_error(name + ": no image data");
    return shape;
}

const Api kApi{sizeof(Api), SPECBAKE_OIIO_API_TAG, decode_file, decode_memory, write_image,
               read_levels, write_rgb8, read_shape};

}  // namespace
}  // namespace specbake::io::oiio

extern "C" __attribute__((visibility("default"))) const specbake::io::oiio::Api* specbake_oiio_api() {
    return &specbake::io::oiio::kApi;
}
