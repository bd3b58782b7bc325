// SHA-256 (FIPS 180-4) of byte buffers and files, as lowercase hex: the content hashes in manifests.
// On x86-64 CPUs with the SHA extensions (SHA-NI, checked at run time) blocks are compressed with them,
// about 2 GB/s per core; elsewhere a portable implementation runs. Both give the same digest.
#pragma once

#include "core/result.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace specbake::io {

// Incremental hasher: update() any number of times, then hex() once.
class Sha256 {
public:
    Sha256();
    void update(std::span<const uint8_t> bytes);
    void update(const std::string& text);
    std::string hex();

private:
    std::array<uint32_t, 8> h_;
    std::array<uint8_t, 64> buffer_{};
    size_t buffered_ = 0;
    uint64_t total_bytes_ = 0;
};

std::string sha256_hex(std::span<const uint8_t> bytes);
// Hashes a file in chunks; the error names the file.
Result<std::string> sha256_file(const std::filesystem::path& path);
// Hashes several files at once (on TBB workers, each file by one task); results in the order given.
Result<std::vector<std::string>> sha256_files(std::span<const std::filesystem::path> paths);

// True when this CPU compresses blocks with the SHA extensions.
bool sha256_uses_cpu_extensions();
// The digest computed by the portable compression function alone, whatever the CPU offers: lets tests
// compare the two implementations on the same data.
std::string sha256_hex_portable(std::span<const uint8_t> bytes);

}  // namespace specbake::io
