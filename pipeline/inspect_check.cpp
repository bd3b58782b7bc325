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
#include <optional>

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
    });
    for (const FileCheck& c : checks) {
        if (c.problem) out.problems.push_back(*c.problem);
        out.bytes_hashed += c.bytes;
    }
    return out;
}

}  // namespace specbake
