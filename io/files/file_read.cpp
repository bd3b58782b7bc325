#include "io/files/file_read.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "core/huge_pages.h"

namespace specbake::io {
namespace fs = std::filesystem;

namespace {

std::string not_regular(const fs::path& path, mode_t mode) {
    const char* what = S_ISDIR(mode)    ? "is a folder, not a file"
                       : S_ISFIFO(mode) ? "is a FIFO (named pipe), not a regular file"
                       : S_ISCHR(mode)  ? "is a character device, not a regular file"
                       : S_ISBLK(mode)  ? "is a block device, not a regular file"
                       : S_ISSOCK(mode) ? "is a socket, not a regular file"
                                        : "is not a regular file";
    return path.string() + ": " + what;
}

std::string open_problem(const fs::path& path, int err) {
    if (err == ENOENT) return path.string() + ": no such file";
    if (err == ELOOP) return path.string() + ": symbolic link loop (too many levels of symbolic links)";
    if (err == ENAMETOOLONG) return path.string() + ": path too long";
    return path.string() + ": cannot open for reading: " + std::strerror(err);
}

}  // namespace

Result<void> check_regular_input(const fs::path& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) return make_error(open_problem(path, errno));
    if (!S_ISREG(st.st_mode)) return make_error(not_regular(path, st.st_mode));
    return {};
}

Result<int> open_regular_input(const fs::path& path) {
    if (auto ok = check_regular_input(path); !ok) return ok.error();
    // Checked again on the descriptor: the name may have been replaced in between.
    const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
    if (fd < 0) return make_error(open_problem(path, errno));
    struct stat st {};
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        const mode_t mode = st.st_mode;
        ::close(fd);
        return make_error(not_regular(path, mode));
    }
    ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
    return fd;
}

namespace {

// A regular file opened for reading (open_regular_input) and its size in bytes.
struct OpenedFile {
    int fd = -1;
    size_t size = 0;
};

Result<OpenedFile> open_regular_input_with_size(const fs::path& path) {
    auto opened = open_regular_input(path);
    if (!opened) return opened.error();
    struct stat st {};
    if (::fstat(*opened, &st) != 0 || st.st_size < 0) {
        ::close(*opened);
        return make_error(path.string() + ": cannot determine the file size");
    }
    return OpenedFile{*opened, static_cast<size_t>(st.st_size)};
}

}  // namespace

Result<std::vector<uint8_t>> read_file(const fs::path& path) {
    auto opened = open_regular_input_with_size(path);
    if (!opened) return opened.error();
    const int fd = opened->fd;
    // Scene files are tens of MB: the buffer is faulted in as huge pages where the kernel has them.
    std::vector<uint8_t> bytes;
    detail::reserve_huge_pages(bytes, opened->size);
    bytes.resize(opened->size);
    size_t done = 0;
    while (done < bytes.size()) {
        const ssize_t n = ::read(fd, bytes.data() + done, bytes.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            ::close(fd);
            return make_error(path.string() + ": read failed" + (n < 0 ? std::string(": ") + std::strerror(errno) : " (file shrank)"));
        }
        done += size_t(n);
    }
    ::close(fd);
    return bytes;
}

Result<MappedFile> MappedFile::open(const fs::path& path) {
    auto opened = open_regular_input_with_size(path);
    if (!opened) return opened.error();
    const int fd = opened->fd;
    MappedFile file;
    if (opened->size > 0) {
        void* p = ::mmap(nullptr, opened->size, PROT_READ, MAP_PRIVATE, fd, 0);
        if (p != MAP_FAILED) {
            file.data_ = static_cast<const uint8_t*>(p);
            file.size_ = opened->size;
        }
    }
    ::close(fd);  // a mapping stays valid
    if (!file.data_ && opened->size > 0) {
        auto read = read_file(path);
        if (!read) return read.error();
        file.read_ = std::move(*read);
    }
    return file;
}

MappedFile::MappedFile(MappedFile&& other) noexcept
    : data_(other.data_), size_(other.size_), read_(std::move(other.read_)) {
    other.data_ = nullptr;
    other.size_ = 0;
}

MappedFile& MappedFile::operator=(MappedFile&& other) noexcept {
    if (this != &other) {
        if (data_) ::munmap(const_cast<uint8_t*>(data_), size_);
        data_ = other.data_;
        size_ = other.size_;
        read_ = std::move(other.read_);
        other.data_ = nullptr;
        other.size_ = 0;
    }
    return *this;
}

void MappedFile::release_pages(size_t offset, size_t size) const {
    if (!data_ || offset >= size_) return;
    // The mapping starts on a page, so the whole pages of the range are those of its offsets.
    detail::advise_whole_pages(data_ + offset, std::min(size_ - offset, size), uintptr_t(::sysconf(_SC_PAGESIZE)),
                               MADV_DONTNEED);
}

void MappedFile::prefetch(size_t offset, size_t size) const {
    if (!data_ || offset >= size_) return;
    const size_t page = size_t(::sysconf(_SC_PAGESIZE));
    const size_t begin = offset / page * page;
    const size_t end = std::min(size_, offset + size);
    ::madvise(const_cast<uint8_t*>(data_) + begin, end - begin, MADV_WILLNEED);
}

MappedFile::~MappedFile() {
    if (data_) ::munmap(const_cast<uint8_t*>(data_), size_);
}

}  // namespace specbake::io
