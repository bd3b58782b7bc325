// SHA-256 (FIPS 180-4) of byte buffers and files, as lowercase hex: the content hashes in manifests.
// On x86-64 CPUs with the SHA extensions (SHA-NI, checked at run time) blocks are compressed with them,
// about 2 GB/s per core; elsewhere a portable implementation runs. Both give the same digest.
#pragma once

#include "core/result.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
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

// Hashes several byte ranges at once; results in the order given. The ranges are spread over as many TBB
// workers as there are idle cores, at least one (longest first, each to the worker with the fewest bytes
// so far), and a worker compresses up to
// three of its ranges in lockstep: with the SHA extensions one range alone waits on the latency of every
// pair of rounds, three interleaved keep the unit busy (about 1.8x the bytes per CPU second). Each range
// is hashed in windows of at most 4 MiB; `before(range, offset, size)` is called before a window is
// hashed and `after` once it has been (to read ahead, or drop the pages of a mapping); either may be null.
using HashWindowFn = std::function<void(size_t range, size_t offset, size_t size)>;
std::vector<std::string> sha256_ranges(std::span<const std::span<const uint8_t>> ranges, const HashWindowFn& before = {},
                                       const HashWindowFn& after = {});

// True when this CPU compresses blocks with the SHA extensions.
bool sha256_uses_cpu_extensions();
// The digest computed by the portable compression function alone, whatever the CPU offers: lets tests
// compare the two implementations on the same data.
std::string sha256_hex_portable(std::span<const uint8_t> bytes);

}  // namespace specbake::io
