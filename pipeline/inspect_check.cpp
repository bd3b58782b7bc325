// `inspect --check` of a manifest folder (pipeline/inspect.h): hashes at disk speed, header checks, and the
// folder's transactional state (io/output/output_folder.h).
#include "pipeline/inspect.h"

#include "io/files/file_read.h"
#include "io/texture/container_inspect.h"
#include "io/output/manifest.h"
#include "io/output/output_folder.h"
#include "io/files/sha256.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <optional>
#include <span>

namespace specbake {
namespace fs = std::filesystem;

namespace {

struct FileCheck {
    std::optional<std::string> problem;
    uint64_t bytes = 0;
    io::MappedFile mapped;
    std::optional<io::TextureShape> shape;
};

// One output before hashing: mapped read-only (no copy), KTX2/DDS headers parsed from the mapping.
void open_output(const fs::path& file, const io::ManifestOutput& o, const io::InputLimits& limits, FileCheck& r) {
    auto mapped = io::MappedFile::open(file);
    if (!mapped) {
        r.problem = mapped.error().message;
        return;
    }
    r.mapped = std::move(*mapped);
    if (o.format == "ktx2" || o.format == "dds") {
        auto s = io::check_container_shape(r.mapped.bytes(), file.string(), limits);
        if (!s) {
            r.problem = s.error().message;
            return;
        }
        r.shape = *s;
    }
}

// One output after hashing: the digest against the manifest's, EXR/PNG headers through OpenImageIO, the
// shape against the manifest entry.
void finish_output(const fs::path& file, const io::ManifestOutput& o, const std::string& digest, FileCheck& r) {
    r.bytes = r.mapped.bytes().size();
    if (digest != o.sha256) {
        r.problem = file.string() + ": content differs from the manifest's hash";
        return;
    }
    std::optional<io::TextureShape>& shape = r.shape;
    if (!shape && (o.format == "exr" || o.format == "png")) {
        auto s = io::read_image_shape(file);
        if (!s) {
            r.problem = s.error().message;
            return;
        }
        shape = *s;
    }
    if (shape && ((o.width && o.width != shape->width) || (o.height && o.height != shape->height) ||
                  (o.channels && o.channels > shape->channels) ||  // DDS pads 3 channels to 4
                  (o.mips && o.format != "png" && o.mips != shape->mips)))
        r.problem = file.string() + ": size, channels or mips differ from the manifest entry";
    // A 2D array (the glint dictionary) records its layer count as an extra fact.
    const int layers = o.extra.contains("layers") && o.extra["layers"].is_number_integer() ? o.extra["layers"].get<int>() : 0;
    if (shape && !r.problem && layers != shape->layers)
        r.problem = file.string() + ": " + std::to_string(shape->layers) + " layers, the manifest entry says " +
                    std::to_string(layers);
}

uint32_t le32(std::span<const uint8_t> b, size_t at) {
    return uint32_t(b[at]) | uint32_t(b[at + 1]) << 8 | uint32_t(b[at + 2]) << 16 | uint32_t(b[at + 3]) << 24;
}

// The textures a .glb carries on its buffer views (the scene entry's "embedded_images", each on the view
// named like it): their bytes against the entry's hash, and KTX2/DDS headers against its size and mips. The
// GLB's own hash covers its bytes, not what the manifest says about the textures inside it.
std::optional<std::string> check_embedded_images(const fs::path& file, std::span<const uint8_t> glb,
                                                 const nlohmann::json& entries, const io::InputLimits& limits) {
    const std::string name = file.string();
    if (glb.size() < 20 || le32(glb, 0) != 0x46546C67u) return name + ": embedded images listed, but not a GLB";
    const uint64_t json_length = le32(glb, 12);
    if (le32(glb, 16) != 0x4E4F534Au || 20 + json_length > glb.size()) return name + ": GLB JSON chunk out of bounds";
    const size_t bin_at = size_t(20 + json_length);
    std::span<const uint8_t> bin;
    if (bin_at + 8 <= glb.size() && le32(glb, bin_at + 4) == 0x004E4942u) {
        const uint64_t bin_length = le32(glb, bin_at);
        if (bin_at + 8 + bin_length > glb.size()) return name + ": GLB BIN chunk out of bounds";
        bin = glb.subspan(bin_at + 8, size_t(bin_length));
    }
    const nlohmann::json doc = nlohmann::json::parse(glb.begin() + 20, glb.begin() + 20 + std::ptrdiff_t(json_length), nullptr, false);
    if (doc.is_discarded() || !doc.is_object()) return name + ": GLB JSON chunk is not valid JSON";
    const nlohmann::json views = doc.value("bufferViews", nlohmann::json::array());
    if (!entries.is_array()) return name + ": embedded_images is not a list";
    for (const nlohmann::json& e : entries) {
        const std::string image = e.is_object() ? e.value("name", "") : "";
        const nlohmann::json* view = nullptr;
        for (const nlohmann::json& v : views)
            if (v.is_object() && v.value("name", "") == image && v.value("buffer", -1) == 0) view = &v;
        if (image.empty() || !view) return name + ": embedded image '" + image + "' has no buffer view of that name";
        const uint64_t offset = view->value("byteOffset", uint64_t(0)), length = view->value("byteLength", uint64_t(0));
        if (length > bin.size() || offset > bin.size() - length) return name + ": embedded image '" + image + "' lies outside the BIN chunk";
        const std::span<const uint8_t> bytes = bin.subspan(size_t(offset), size_t(length));
        if (io::sha256_hex(bytes) != e.value("sha256", ""))
            return name + ": embedded image '" + image + "': content differs from the manifest's hash";
        const std::string format = e.value("format", "");
        if (format != "ktx2" && format != "dds") continue;
        auto shape = io::check_container_shape(bytes, name + ": embedded image '" + image + "'", limits);
        if (!shape) return shape.error().message;
        const int width = e.value("width", 0), height = e.value("height", 0), mips = e.value("mips", 0),
                  channels = e.value("channels", 0);
        if ((width && width != shape->width) || (height && height != shape->height) || (mips && mips != shape->mips) ||
            (channels && channels > shape->channels))
            return name + ": embedded image '" + image + "': size, channels or mips differ from the manifest entry";
    }
    return std::nullopt;
}

}  // namespace

FolderCheck check_manifest_folder(const fs::path& manifest_path, const io::InputLimits& limits,
                                  const std::function<void(const std::string&)>& on_wait) {
    FolderCheck out;
    const fs::path dir = manifest_path.parent_path().empty() ? fs::path(".") : manifest_path.parent_path();
    auto lock = io::OutputLock::acquire(dir, io::OutputLock::Purpose::check, on_wait);
    if (!lock) {
        out.problems.push_back(lock.error().message);
        return out;
    }
    if (lock->recovery().finished_commit)
        out.notes.push_back(dir.string() + ": finished the commit of an interrupted run");
    const io::FolderLeftovers left = io::find_leftovers(dir);
    for (const fs::path& p : left.pending_commits)
        out.problems.push_back(p.string() + ": commit of an interrupted run not finished (the folder is not "
                               "writable here); the next bake into " + dir.string() + " finishes it");
    for (const fs::path& p : left.stale)
        out.problems.push_back(p.string() + ": left by an interrupted run; the next bake into " + dir.string() +
                               " removes it");

    auto manifest = io::read_manifest(manifest_path);
    if (!manifest) {
        out.problems.push_back(manifest.error().message);
        return out;
    }
    const std::vector<io::ManifestOutput>& outputs = manifest->outputs;
    std::vector<FileCheck> checks(outputs.size());
    std::vector<fs::path> files(outputs.size());
    tbb::parallel_for(size_t(0), outputs.size(), [&](size_t i) {
        const io::ManifestOutput& o = outputs[i];
        if (fs::path(o.path).is_absolute() || fs::path(o.path).lexically_normal().string().rfind("..", 0) == 0) {
            checks[i].problem = manifest_path.string() + ": output path " + o.path + " leaves the folder";
            return;
        }
        files[i] = dir / o.path;
        open_output(files[i], o, limits, checks[i]);
    });
    // All outputs hashed together, several interleaved on each core (io::sha256_ranges), from the mappings
    // in windows: the window after next is read from disk while one is hashed (cold page cache), and each
    // window's pages are dropped from the mapping once hashed, so memory stays at a few windows per core.
    std::vector<size_t> hashed;
    std::vector<std::span<const uint8_t>> ranges;
    for (size_t i = 0; i < checks.size(); ++i)
        if (!checks[i].problem) {
            hashed.push_back(i);
            ranges.push_back(checks[i].mapped.bytes());
        }
    constexpr size_t kWindow = size_t(4) << 20;
    const std::vector<std::string> digests = io::sha256_ranges(
        ranges,
        [&](size_t r, size_t offset, size_t) {
            const io::MappedFile& m = checks[hashed[r]].mapped;
            if (offset == 0) m.prefetch(0, 2 * kWindow);
            m.prefetch(offset + 2 * kWindow, kWindow);
        },
        [&](size_t r, size_t offset, size_t size) { checks[hashed[r]].mapped.release_pages(offset, size); });
    tbb::parallel_for(size_t(0), hashed.size(), [&](size_t k) {
        const size_t i = hashed[k];
        finish_output(files[i], outputs[i], digests[k], checks[i]);
        if (!checks[i].problem && outputs[i].extra.contains("embedded_images")) {
            try {
                checks[i].problem = check_embedded_images(files[i], checks[i].mapped.bytes(),
                                                          outputs[i].extra["embedded_images"], limits);
            } catch (const nlohmann::json::exception& e) {
                checks[i].problem = files[i].string() + ": embedded images: " + e.what();
            }
        }
    });
    for (const FileCheck& c : checks) {
        if (c.problem) out.problems.push_back(*c.problem);
        out.bytes_hashed += c.bytes;
    }
    return out;
}

}  // namespace specbake
