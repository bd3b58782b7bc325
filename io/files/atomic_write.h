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

// Fails when `path` exists and is not a regular file: an output replaces a regular file only, never a
// FIFO, device, socket, folder or symbolic link (the rename would swap the node or link for a file).
Result<void> check_replaceable(const std::filesystem::path& path);

// Fails, naming `path` and the system's reason, when a file could not be written there (missing folders
// are created): lets a command refuse before it works rather than after.
Result<void> check_writable(const std::filesystem::path& path);

// Writes `bytes` to `path` atomically. Creates missing parent folders.
Result<void> write_file_atomic(const std::filesystem::path& path, std::span<const uint8_t> bytes);
Result<void> write_file_atomic(const std::filesystem::path& path, const std::string& text);

}  // namespace specbake::io
