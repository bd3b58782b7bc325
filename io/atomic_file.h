// Atomic file output: everything specbake writes goes to a temporary file in the destination folder and
// is renamed into place only when complete, so a failed run never leaves a half-written file.
#pragma once

#include "core/result.h"

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace specbake::io {

// A temporary path next to `final_path`; commit() renames it onto `final_path`.
// Destroying an uncommitted AtomicOutput removes the temporary file.
class AtomicOutput {
public:
    explicit AtomicOutput(std::filesystem::path final_path);
    ~AtomicOutput();
    AtomicOutput(const AtomicOutput&) = delete;
    AtomicOutput& operator=(const AtomicOutput&) = delete;

    // Where to write. The extension of the final path is kept, so format-sniffing writers still work.
    const std::filesystem::path& temp_path() const { return temp_; }
    const std::filesystem::path& final_path() const { return final_; }
    Result<void> commit();

private:
    std::filesystem::path final_;
    std::filesystem::path temp_;
    bool committed_ = false;
};

// Writes `bytes` to `file` (created or truncated); errors name `name` (the final path when `file` is a
// temporary) and give the system's reason.
Result<void> write_bytes_to(const std::filesystem::path& file, const std::filesystem::path& name,
                            std::span<const uint8_t> bytes);
// The same for a file made of `pieces` written one after the other.
Result<void> write_pieces_to(const std::filesystem::path& file, const std::filesystem::path& name,
                             std::span<const std::span<const uint8_t>> pieces);

// Fails, naming `path` and the system's reason, when a file could not be written there (missing folders
// are created): lets a command refuse before it works rather than after.
Result<void> check_writable(const std::filesystem::path& path);

// Writes `bytes` to `path` atomically. Creates missing parent folders.
Result<void> write_file_atomic(const std::filesystem::path& path, std::span<const uint8_t> bytes);
Result<void> write_file_atomic(const std::filesystem::path& path, const std::string& text);

// Reads a whole file; the error names the file.
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

// Fails when `output` is the same file as any of `inputs` (inputs are never overwritten), or when
// `output_dir` is a folder that holds one of the inputs directly.
Result<void> check_output_not_input(const std::filesystem::path& output_dir,
                                    std::span<const std::filesystem::path> inputs);

}  // namespace specbake::io
