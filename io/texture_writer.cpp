#include "io/texture_writer.h"

#include "io/atomic_file.h"
#include "io/dds.h"
#include "io/ktx2.h"
#include "io/oiio_api.h"
#include "io/sha256.h"
#include "io/texel_encoding.h"

#include "core/huge_pages.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <memory>


namespace specbake::io {
namespace fs = std::filesystem;

const char* container_name(TextureContainer c) {
    switch (c) {
        case TextureContainer::Ktx2: return "ktx2";
        case TextureContainer::Dds: return "dds";
        case TextureContainer::Exr: return "exr";
        case TextureContainer::PngPerMip: return "png";
    }
    return "ktx2";
}

const char* encoding_name(TexelEncoding e) {
    switch (e) {
        case TexelEncoding::Unorm8: return "unorm8";
        case TexelEncoding::Unorm16: return "unorm16";
        case TexelEncoding::Float16: return "float16";
        case TexelEncoding::Float32: return "float32";
    }
    return "float32";
}

std::optional<TextureContainer> parse_container(const std::string& name) {
    for (TextureContainer c : {TextureContainer::Ktx2, TextureContainer::Dds, TextureContainer::Exr,
                               TextureContainer::PngPerMip}) {
        if (name == container_name(c)) return c;
    }
    return std::nullopt;
}

namespace {

const char* wrap_name(WrapMode w) {
    switch (w) {
        case WrapMode::Repeat: return "periodic";
        case WrapMode::Clamp: return "clamp";
        case WrapMode::Mirror: return "mirror";
    }
    return "periodic";
}

oiio::PixelType oiio_type(TexelEncoding e) {
    switch (e) {
        case TexelEncoding::Unorm8: return oiio::PixelType::Uint8;
        case TexelEncoding::Unorm16: return oiio::PixelType::Uint16;
        case TexelEncoding::Float16: return oiio::PixelType::Half;
        case TexelEncoding::Float32: return oiio::PixelType::Float;
    }
    return oiio::PixelType::Float;
}

std::vector<std::string> names_for(int channels, const std::vector<std::string>& given) {
    static const char* defaults[] = {"R", "G", "B", "A"};
    std::vector<std::string> names;
    for (int c = 0; c < channels; ++c) {
        if (size_t(c) < given.size()) names.push_back(given[size_t(c)]);
        else names.push_back(c < 4 ? defaults[c] : "C" + std::to_string(c));
    }
    return names;
}

// The DateTime written into EXR headers: SOURCE_DATE_EPOCH (the reproducible-builds convention) when it is
// set, else the epoch. OpenImageIO's EXR writer stamps the current time otherwise (its PNG writer adds none), so the same bake would give files (and
// manifest hashes) that differ from run to run and defeat build caches.
std::string reproducible_date_time() {
    std::time_t t = 0;
    if (const char* epoch = std::getenv("SOURCE_DATE_EPOCH")) {
        char* end = nullptr;
        const long long v = std::strtoll(epoch, &end, 10);
        if (end != epoch && *end == '\0' && v >= 0) t = std::time_t(v);
    }
    std::tm utc{};
    gmtime_r(&t, &utc);
    char text[32];
    std::strftime(text, sizeof text, "%Y:%m:%d %H:%M:%S", &utc);
    return text;
}

// One OpenImageIO file: all levels as a tiled MIP-mapped EXR, or a single level (PNG / EXR).
Result<void> write_oiio(const fs::path& temp, const fs::path& final_path, const std::vector<const Image*>& levels,
                        oiio::PixelType type, bool mipmapped, const std::vector<std::string>& names, WrapMode wrap) {
    auto api = oiio::api();
    if (!api) return make_error(final_path.string() + ": " + api.error().message);
    oiio::LevelsRequest request;
    request.temp_path = temp.string();
    request.name = final_path.string();
    request.levels = levels;
    request.type = type;
    request.mipmapped = mipmapped;
    request.channel_names = names;
    request.wrap = wrap_name(wrap);
    request.date_time = reproducible_date_time();
    return (*api)->write_levels(request);
}

}  // namespace

Result<std::vector<ManifestOutput>> write_texture(const MipChain& chain, TexelEncoding encoding,
                                                  TextureContainer container, const fs::path& dir,
                                                  const std::string& stem, const std::string& kind,
                                                  const std::vector<std::string>& channel_names, WrapMode wrap) {
    if (chain.levels.empty() || chain.channels() < 1) return make_error((dir / stem).string() + ": nothing to write");
    if (chain.channels() > 4 && container != TextureContainer::Exr)
        return make_error((dir / stem).string() + ": " + container_name(container) + " holds at most 4 channels");
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) return make_error(dir.string() + ": cannot create folder: " + ec.message());

    struct Pending {
        std::unique_ptr<AtomicOutput> file;
        ManifestOutput entry;
    };
    std::vector<Pending> pending;
    auto add = [&](const std::string& filename, int width, int height, int mips) -> Pending& {
        Pending p;
        p.file = std::make_unique<AtomicOutput>(dir / filename);
        p.entry.kind = kind;
        p.entry.path = filename;
        p.entry.format = container_name(container);
        p.entry.width = width;
        p.entry.height = height;
        p.entry.mips = mips;
        p.entry.channels = chain.channels();
        p.entry.extra["encoding"] = encoding_name(encoding);
        pending.push_back(std::move(p));
        return pending.back();
    };
    const std::vector<std::string> names = names_for(chain.channels(), channel_names);
    const int mips = int(chain.levels.size());

    switch (container) {
        case TextureContainer::Ktx2:
        case TextureContainer::Dds: {
            EncodedTexture t(container, encoding, chain.width(), chain.height(), mips, chain.channels());
            for (int L = 0; L < mips; ++L) {
                const Image& level = chain.levels[size_t(L)];
                t.put_block(L, 0, 0, level.width, level.height, level.pixels.data(), level.channels, 0);
            }
            const EncodedFile file{&t, stem, kind};
            return write_encoded_textures({&file, 1}, dir);
        }
        case TextureContainer::Exr: {
            Pending& p = add(stem + ".exr", chain.width(), chain.height(), mips);
            const TexelEncoding stored = encoding == TexelEncoding::Float32 ? encoding : TexelEncoding::Float16;
            p.entry.extra["encoding"] = encoding_name(stored);
            p.entry.extra["channel_names"] = names;
            std::vector<const Image*> levels;
            for (const Image& l : chain.levels) levels.push_back(&l);
            if (auto ok = write_oiio(p.file->temp_path(), p.file->final_path(), levels, oiio_type(stored), true,
                                     names, wrap);
                !ok)
                return ok.error();
            break;
        }
        case TextureContainer::PngPerMip: {
            const bool integer = encoding == TexelEncoding::Unorm8 || encoding == TexelEncoding::Unorm16;
            for (int L = 0; L < mips; ++L) {
                const Image& level = chain.levels[size_t(L)];
                const std::string filename = stem + "_mip" + std::to_string(L) + (integer ? ".png" : ".exr");
                Pending& p = add(filename, level.width, level.height, 1);
                p.entry.format = integer ? "png" : "exr";
                p.entry.extra["mip_level"] = L;
                if (auto ok = write_oiio(p.file->temp_path(), p.file->final_path(), {&level}, oiio_type(encoding),
                                         false, names, wrap);
                    !ok)
                    return ok.error();
            }
            break;
        }
    }

    std::vector<ManifestOutput> entries;
    for (Pending& p : pending) {
        auto hash = sha256_file(p.file->temp_path());
        if (!hash) return hash.error();
        p.entry.sha256 = *hash;
    }
    for (Pending& p : pending) {
        if (auto ok = p.file->commit(); !ok) return ok.error();
        entries.push_back(p.entry);
    }
    return entries;
}

bool EncodedTexture::supports(TextureContainer container) {
    return container == TextureContainer::Ktx2 || container == TextureContainer::Dds;
}

EncodedTexture::EncodedTexture(TextureContainer container, TexelEncoding encoding, int width, int height, int levels,
                               int channels)
    : container_(container), encoding_(encoding), width_(width), height_(height), channels_(channels) {
    layout_ = container == TextureContainer::Ktx2 ? ktx2_layout(width, height, levels, encoding, channels)
                                                  : dds_layout(width, height, levels, encoding, channels);
    data_.reset(new uint8_t[layout_.total]);
    // Faulted in on transparent huge pages as the rows arrive: a 4096^2 bake writes about 400 MiB of fresh
    // container bytes.
    detail::hint_huge_pages(data_.get(), layout_.total);
    if (container == TextureContainer::Ktx2) ktx2_write_header(data_.get(), layout_, width, height, encoding, channels);
    else dds_write_header(data_.get(), layout_, width, height, encoding, channels);
}

void EncodedTexture::put_block(int level, int x0, int y0, int width, int rows, const float* src, int src_channels,
                               int first) {
    const size_t w = size_t(std::max(1, width_ >> level));
    const size_t texel_bytes = size_t(layout_.stored_channels) * size_t(encoding_bytes(encoding_));
    uint8_t* dst = data_.get() + layout_.level_offset[size_t(level)] + (size_t(y0) * w + size_t(x0)) * texel_bytes;
    if (size_t(width) == w) {  // whole rows: one run
        encode_texels_into(src, w * size_t(rows), src_channels, first, channels_, encoding_, layout_.stored_channels,
                           1.0f, dst);
        return;
    }
    for (int k = 0; k < rows; ++k, src += size_t(width) * size_t(src_channels), dst += w * texel_bytes)
        encode_texels_into(src, size_t(width), src_channels, first, channels_, encoding_, layout_.stored_channels,
                           1.0f, dst);
}

ManifestOutput EncodedTexture::entry(const std::string& filename, const std::string& kind) const {
    ManifestOutput e;
    e.kind = kind;
    e.path = filename;
    e.format = container_name(container_);
    e.width = width_;
    e.height = height_;
    e.mips = int(layout_.level_offset.size());
    e.channels = channels_;
    e.extra["encoding"] = encoding_name(encoding_);
    if (container_ == TextureContainer::Ktx2) {
        e.extra["vkFormat"] = ktx2_vk_format(encoding_, channels_);
    } else {
        int stored = 0;
        e.extra["dxgiFormat"] = dds_dxgi_format(encoding_, channels_, &stored);
        e.extra["stored_channels"] = stored;
    }
    return e;
}

Result<std::vector<ManifestOutput>> write_encoded_textures(std::span<const EncodedFile> files, const fs::path& dir) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) return make_error(dir.string() + ": cannot create folder: " + ec.message());
    std::vector<std::unique_ptr<AtomicOutput>> outputs;
    std::vector<ManifestOutput> entries;
    for (const EncodedFile& f : files) {
        const std::string filename = f.stem + '.' + container_name(f.texture->container());
        outputs.push_back(std::make_unique<AtomicOutput>(dir / filename));
        entries.push_back(f.texture->entry(filename, f.kind));
    }
    // Each file is hashed from memory and written by one task; the first error in file order is reported.
    std::vector<std::optional<Error>> errors(files.size());
    tbb::parallel_for(size_t(0), files.size(), [&](size_t i) {
        entries[i].sha256 = sha256_hex(files[i].texture->bytes());
        if (auto ok = write_bytes_to(outputs[i]->temp_path(), outputs[i]->final_path(), files[i].texture->bytes()); !ok)
            errors[i] = ok.error();
    });
    for (const std::optional<Error>& e : errors)
        if (e) return *e;
    for (const auto& out : outputs)
        if (auto ok = out->commit(); !ok) return ok.error();
    return entries;
}

}  // namespace specbake::io
