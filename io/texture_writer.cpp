#include "io/texture_writer.h"

#include "io/atomic_file.h"
#include "io/dds.h"
#include "io/ktx2.h"
#include "io/sha256.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <fstream>
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

std::string one_line(std::string s) {
    std::replace(s.begin(), s.end(), '\n', ' ');
    return s;
}

const char* wrap_name(WrapMode w) {
    switch (w) {
        case WrapMode::Repeat: return "periodic";
        case WrapMode::Clamp: return "clamp";
        case WrapMode::Mirror: return "mirror";
    }
    return "periodic";
}

Result<void> write_bytes(const fs::path& path, const std::vector<uint8_t>& bytes) {
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    if (!f) return make_error(path.string() + ": cannot open for writing");
    f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    f.flush();
    if (!f) return make_error(path.string() + ": write failed (disk full?)");
    return {};
}

OIIO::TypeDesc oiio_type(TexelEncoding e) {
    switch (e) {
        case TexelEncoding::Unorm8: return OIIO::TypeDesc::UINT8;
        case TexelEncoding::Unorm16: return OIIO::TypeDesc::UINT16;
        case TexelEncoding::Float16: return OIIO::TypeDesc::HALF;
        case TexelEncoding::Float32: return OIIO::TypeDesc::FLOAT;
    }
    return OIIO::TypeDesc::FLOAT;
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

// One OpenImageIO file: all levels as a tiled MIP-mapped EXR, or a single level (PNG / EXR).
Result<void> write_oiio(const fs::path& temp, const fs::path& final_path, const std::vector<const Image*>& levels,
                        OIIO::TypeDesc type, bool mipmapped, const std::vector<std::string>& names, WrapMode wrap) {
    auto out = OIIO::ImageOutput::create(temp.string());
    if (!out) return make_error(final_path.string() + ": no writer: " + one_line(OIIO::geterror()));
    if (mipmapped && !out->supports("mipmap"))
        return make_error(final_path.string() + ": the format cannot hold MIP levels");
    for (size_t i = 0; i < levels.size(); ++i) {
        const Image& level = *levels[i];
        OIIO::ImageSpec spec(level.width, level.height, level.channels, type);
        spec.channelnames = names;
        spec.attribute("oiio:UnassociatedAlpha", 1);  // data, not premultiplied colour: store as given
        if (mipmapped) {
            spec.tile_width = 64;
            spec.tile_height = 64;
            spec.attribute("textureformat", "Plain Texture");
            spec.attribute("wrapmodes", std::string(wrap_name(wrap)) + "," + wrap_name(wrap));
        }
        if (type == OIIO::TypeDesc::HALF || type == OIIO::TypeDesc::FLOAT) spec.attribute("compression", "zip");
        spec.attribute("oiio:ColorSpace", "Linear");
        spec.attribute("Software", "specbake");
        const auto mode = i == 0 ? OIIO::ImageOutput::Create : OIIO::ImageOutput::AppendMIPLevel;
        if (!out->open(temp.string(), spec, mode))
            return make_error(final_path.string() + ": cannot write: " + one_line(out->geterror()));
        if (!out->write_image(OIIO::TypeDesc::FLOAT, level.pixels.data()))
            return make_error(final_path.string() + ": cannot write: " + one_line(out->geterror()));
    }
    if (!out->close()) return make_error(final_path.string() + ": cannot write: " + one_line(out->geterror()));
    return {};
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
        case TextureContainer::Ktx2: {
            Pending& p = add(stem + ".ktx2", chain.width(), chain.height(), mips);
            const std::vector<uint8_t> bytes = encode_ktx2(chain, encoding);
            p.entry.extra["vkFormat"] = ktx2_vk_format(encoding, chain.channels());
            if (auto ok = write_bytes(p.file->temp_path(), bytes); !ok) return ok.error();
            break;
        }
        case TextureContainer::Dds: {
            Pending& p = add(stem + ".dds", chain.width(), chain.height(), mips);
            int stored = 0;
            p.entry.extra["dxgiFormat"] = dds_dxgi_format(encoding, chain.channels(), &stored);
            p.entry.extra["stored_channels"] = stored;
            if (auto ok = write_bytes(p.file->temp_path(), encode_dds(chain, encoding)); !ok) return ok.error();
            break;
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

}  // namespace specbake::io
