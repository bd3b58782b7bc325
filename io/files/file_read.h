// Reading whole files: into memory, or mapped read-only without a copy. Errors name the file.
#pragma once

#include "core/result.h"

#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

namespace specbake::io {

// Fails unless `path` names a regular file (symbolic links followed): a FIFO, device or socket would
// block a reader or never end, and a folder is not a file. The error names the file and says what it is
// ("is a FIFO (named pipe), not a regular file", "symbolic link loop", "no such file", ...).
Result<void> check_regular_input(const std::filesystem::path& path);

// Opens `path` for reading without blocking on a FIFO (O_NONBLOCK) and checks, on the descriptor, that it
// is a regular file; the descriptor (blocking again) or the error of check_regular_input.
Result<int> open_regular_input(const std::filesystem::path& path);

// Reads a whole regular file; the error names the file.
Result<std::vector<uint8_t>> read_file(const std::filesystem::path& path);

// A whole file mapped read-only: its bytes without a copy into fresh memory (a 28 MB scene is otherwise
// copied out of the page cache and faulted in page by page before anything parses it). Files that cannot
// be mapped are read instead. Move-only; the bytes last as long as the object. The error names the file.
class MappedFile {
public:
    static Result<MappedFile> open(const std::filesystem::path& path);
    MappedFile() = default;
    MappedFile(MappedFile&& other) noexcept;
    MappedFile& operator=(MappedFile&& other) noexcept;
    MappedFile(const MappedFile&) = delete;
    MappedFile& operator=(const MappedFile&) = delete;
    ~MappedFile();
    std::span<const uint8_t> bytes() const { return data_ ? std::span<const uint8_t>(data_, size_) : std::span<const uint8_t>(read_); }
    // Drops the pages of bytes [offset, offset + size) from this process (the page cache keeps them; a
    // later access faults them in again): lets a reader stream through a huge file in bounded memory.
    void release_pages(size_t offset, size_t size) const;
    // Asks the kernel to start reading [offset, offset + size) of a mapping now (MADV_WILLNEED), so that a
    // reader hashing one window while the next is read keeps the disk busy; no-op for a file read into memory.
    void prefetch(size_t offset, size_t size) const;

private:
    const uint8_t* data_ = nullptr;  // the mapping, or null
    size_t size_ = 0;
    std::vector<uint8_t> read_;      // the bytes when the file could not be mapped
};

}  // namespace specbake::io
