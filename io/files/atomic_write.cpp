#include "io/files/atomic_write.h"

#include <atomic>
#include <cstdio>
#include <algorithm>
#include <fstream>
#include <system_error>
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/huge_pages.h"
#include "io/files/cleanup_registry.h"

#include <cerrno>
#include <cstring>

namespace specbake::io {
namespace fs = std::filesystem;

namespace {

fs::path make_temp_path(const fs::path& final_path) {
    static std::atomic<unsigned> counter{0};
    // Name: .<stem>.tmp<pid>-<n><ext> in the same folder, so the rename stays on one file system.
    const std::string name = "." + final_path.stem().string() + ".tmp" + std::to_string(::getpid()) + "-" +
                             std::to_string(counter.fetch_add(1)) + final_path.extension().string();
    return final_path.parent_path() / name;
}

}  // namespace

// The temporary is registered for removal on interruption (io/files/cleanup_registry.h) while it may exist.
AtomicOutput::AtomicOutput(fs::path final_path) : final_(std::move(final_path)), temp_(make_temp_path(final_)) {
    register_cleanup(temp_);
}

AtomicOutput::~AtomicOutput() {
    if (!committed_) {
        std::error_code ec;
        fs::remove(temp_, ec);
    }
    unregister_cleanup(temp_);
}

Result<void> check_replaceable(const fs::path& path) {
    struct stat st {};
    if (::lstat(path.c_str(), &st) != 0) return {};  // nothing there (or nothing reachable): created
    if (S_ISREG(st.st_mode)) return {};
    const char* what = S_ISLNK(st.st_mode)    ? "a symbolic link"
                       : S_ISDIR(st.st_mode)  ? "a folder"
                       : S_ISFIFO(st.st_mode) ? "a FIFO (named pipe)"
                       : S_ISCHR(st.st_mode)  ? "a character device"
                       : S_ISBLK(st.st_mode)  ? "a block device"
                       : S_ISSOCK(st.st_mode) ? "a socket"
                                              : "not a regular file";
    return make_error(path.string() + ": is " + what + "; specbake replaces only regular files");
}

Result<void> AtomicOutput::commit() {
    if (auto ok = check_replaceable(final_); !ok) return ok;
    std::error_code ec;
    if (!fs::exists(temp_, ec)) return make_error(final_.string() + ": nothing was written");
    fs::rename(temp_, final_, ec);
    if (ec) return make_error(final_.string() + ": cannot move the finished file into place: " + ec.message());
    committed_ = true;
    return {};
}

Result<void> write_pieces_to(const fs::path& file, const fs::path& name,
                             std::span<const std::span<const uint8_t>> pieces) {
    const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) return make_error(name.string() + ": cannot open for writing: " + std::strerror(errno));
    for (std::span<const uint8_t> bytes : pieces) {
        size_t done = 0;
        while (done < bytes.size()) {
            const ssize_t n = ::write(fd, bytes.data() + done, std::min<size_t>(bytes.size() - done, size_t(1) << 30));
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) {
                const int err = n < 0 ? errno : ENOSPC;
                ::close(fd);
                return make_error(name.string() + ": cannot write: " + std::strerror(err));
            }
            done += size_t(n);
        }
    }
    if (::close(fd) != 0) return make_error(name.string() + ": cannot write: " + std::strerror(errno));
    return {};
}

Result<void> write_bytes_to(const fs::path& file, const fs::path& name, std::span<const uint8_t> bytes) {
    const std::span<const uint8_t> one[] = {bytes};
    return write_pieces_to(file, name, one);
}

Result<void> write_file_atomic(const fs::path& path, std::span<const uint8_t> bytes) {
    std::error_code ec;
    if (path.has_parent_path()) fs::create_directories(path.parent_path(), ec);
    if (ec) return make_error(path.parent_path().string() + ": cannot create folder: " + ec.message());
    AtomicOutput out(path);
    if (auto ok = write_bytes_to(out.temp_path(), path, bytes); !ok) return ok;
    return out.commit();
}

Result<void> check_writable(const fs::path& path) {
    std::error_code ec;
    if (path.has_parent_path()) fs::create_directories(path.parent_path(), ec);
    if (ec) return make_error(path.string() + ": cannot create its folder: " + ec.message());
    if (auto ok = check_replaceable(path); !ok) return ok;
    AtomicOutput probe(path);
    const int fd = ::open(probe.temp_path().c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0) return make_error(path.string() + ": cannot be written: " + std::strerror(errno));
    ::close(fd);
    return {};
}

Result<void> write_file_atomic(const fs::path& path, const std::string& text) {
    return write_file_atomic(path, std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
}

}  // namespace specbake::io
