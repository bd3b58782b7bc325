// Output bytes as piece lists: 4-byte aligned appends, the write of a list to a temporary file with its
// SHA-256 computed alongside, and the GLB container (glTF 2.0 Sec. 4.4).
#include "io/gltf/glb_pack.h"

#include "io/files/sha256.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <limits>

#include <tbb/task_group.h>

namespace specbake::io::gltf {
namespace fs = std::filesystem;

namespace {
const uint8_t kZeros[4] = {};
}  // namespace

size_t PieceList::append(std::span<const uint8_t> bytes) {
    if (size % 4) {
        const size_t pad = 4 - size % 4;
        pieces.emplace_back(kZeros, pad);
        size += pad;
    }
    const size_t offset = size;
    if (!bytes.empty()) pieces.push_back(bytes);
    size += bytes.size();
    return offset;
}

Result<std::string> write_pieces(AtomicOutput& out, const std::vector<std::span<const uint8_t>>& pieces) {
    std::error_code ec;
    const fs::path& final_path = out.final_path();
    if (final_path.has_parent_path()) fs::create_directories(final_path.parent_path(), ec);
    if (ec) return make_error(final_path.parent_path().string() + ": cannot create folder: " + ec.message());
    std::FILE* f = std::fopen(out.temp_path().c_str(), "wb");
    if (!f) return make_error(final_path.string() + ": cannot open for writing: " + std::strerror(errno));
    std::string hash;
    tbb::task_group hashing;
    hashing.run([&] {
        Sha256 sha;
        for (std::span<const uint8_t> p : pieces) sha.update(p);
        hash = sha.hex();
    });
    // The first failing call's errno is the reason (ENOSPC, EFBIG, EIO ...); fclose reports a delayed one.
    int err = 0;
    for (std::span<const uint8_t> p : pieces)
        if (!err && std::fwrite(p.data(), 1, p.size(), f) != p.size()) err = errno ? errno : EIO;
    if (std::fflush(f) != 0 && !err) err = errno ? errno : EIO;
    if (std::fclose(f) != 0 && !err) err = errno ? errno : EIO;
    hashing.wait();
    if (err) return make_error(final_path.string() + ": cannot write: " + std::strerror(err));
    return hash;
}

Result<GlbFile> pack_glb(const fs::path& path, const std::string& json_text, const PieceList* bin) {
    GlbFile glb;
    std::string json_chunk = json_text;
    while (json_chunk.size() % 4) json_chunk.push_back(' ');
    const size_t bin_size = bin ? bin->size : 0;
    const size_t bin_padded = (bin_size + 3) / 4 * 4;
    const uint64_t total = 12 + 8 + json_chunk.size() + (bin ? 8 + bin_padded : 0);
    if (total > std::numeric_limits<uint32_t>::max()) return make_error(path.string() + ": GLB would exceed 4 GiB");
    auto put32 = [](std::vector<uint8_t>& to, uint32_t v) {
        for (int k = 0; k < 4; ++k) to.push_back(uint8_t(v >> (8 * k)));
    };
    put32(glb.head, 0x46546C67);  // "glTF"
    put32(glb.head, 2);
    put32(glb.head, uint32_t(total));
    put32(glb.head, uint32_t(json_chunk.size()));
    put32(glb.head, 0x4E4F534A);  // "JSON"
    glb.head.insert(glb.head.end(), json_chunk.begin(), json_chunk.end());
    if (bin) {
        put32(glb.bin_head, uint32_t(bin_padded));
        put32(glb.bin_head, 0x004E4942);  // "BIN"
        glb.bin = bin;
        glb.bin_padding = bin_padded - bin_size;
    }
    return glb;
}

std::vector<std::span<const uint8_t>> GlbFile::pieces() const {
    std::vector<std::span<const uint8_t>> out{head};
    if (bin) {
        out.push_back(bin_head);
        out.insert(out.end(), bin->pieces.begin(), bin->pieces.end());
        if (bin_padding > 0) out.emplace_back(kZeros, bin_padding);
    }
    return out;
}

}  // namespace specbake::io::gltf
