// SHA-256 (FIPS 180-4) of byte buffers and files, as lowercase hex: the content hashes in manifests.
#pragma once

#include "bake/result.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

namespace specbake::io {

// Incremental hasher: update() any number of times, then hex() once.
class Sha256 {
public:
    Sha256();
    void update(std::span<const uint8_t> bytes);
    void update(const std::string& text);
    std::string hex();

private:
    void compress(const uint8_t* block);
    std::array<uint32_t, 8> h_;
    std::array<uint8_t, 64> buffer_{};
    size_t buffered_ = 0;
    uint64_t total_bytes_ = 0;
};

std::string sha256_hex(std::span<const uint8_t> bytes);
// Hashes a file in chunks; the error names the file.
Result<std::string> sha256_file(const std::filesystem::path& path);

}  // namespace specbake::io
