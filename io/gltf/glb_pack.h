// Private to io/gltf_*.cpp: the bytes of an output file as a list of pieces (no copies of the buffers),
// written to a temporary while hashed, and the GLB container around a JSON text and a binary chunk.
#pragma once

#include "core/result.h"
#include "io/files/atomic_write.h"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace specbake::io::gltf {

// The bytes of one output file (or of the GLB binary chunk) as a list of pieces, each starting at a
// multiple of 4 (glTF 2.0 Sec. 3.6.2.4 aligns accessors to their component size, at most 4 for vertex data).
struct PieceList {
    std::vector<std::span<const uint8_t>> pieces;
    size_t size = 0;

    // Appends `bytes` (which must outlive the list) after zero padding to a multiple of 4; returns their offset.
    size_t append(std::span<const uint8_t> bytes);
};

// Writes the pieces to the temporary file of `out` and returns their SHA-256, hashed on a TBB worker while
// this thread writes. Nothing is renamed into place here.
Result<std::string> write_pieces(AtomicOutput& out, const std::vector<std::span<const uint8_t>>& pieces);

// A GLB file (glTF 2.0 Sec. 4.4): 12-byte header, JSON chunk padded with spaces, BIN chunk padded with zeros.
struct GlbFile {
    std::vector<uint8_t> head;      // file header, JSON chunk header and the padded JSON
    std::vector<uint8_t> bin_head;  // BIN chunk header; empty when there is no binary chunk
    const PieceList* bin = nullptr;
    size_t bin_padding = 0;
    // The file's pieces, pointing into this object and into `bin`.
    std::vector<std::span<const uint8_t>> pieces() const;
};
// The GLB around `json_text` and the binary chunk `bin` (null: none); the error names `path` when the file
// would exceed the 4 GiB the container can address.
Result<GlbFile> pack_glb(const std::filesystem::path& path, const std::string& json_text, const PieceList* bin);

}  // namespace specbake::io::gltf
