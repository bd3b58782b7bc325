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

Result<std::vector<uint8_t>> read_file(const fs::path& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) return make_error(path.string() + ": no such file");
    if (fs::is_directory(path, ec)) return make_error(path.string() + ": is a folder, not a file");
    std::ifstream f(path, std::ios::binary);
    if (!f) return make_error(path.string() + ": cannot open for reading");
    f.seekg(0, std::ios::end);
    const std::streamoff size = f.tellg();
    if (size < 0) return make_error(path.string() + ": cannot determine the file size");
    f.seekg(0, std::ios::beg);
    // Scene files are tens of MB: the buffer is faulted in as huge pages where the kernel has them.
    std::vector<uint8_t> bytes;
    detail::reserve_huge_pages(bytes, static_cast<size_t>(size));
    bytes.resize(static_cast<size_t>(size));
    f.read(reinterpret_cast<char*>(bytes.data()), size);
    if (!f) return make_error(path.string() + ": read failed");
    return bytes;
}

Result<MappedFile> MappedFile::open(const fs::path& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) return make_error(path.string() + ": no such file");
    if (fs::is_directory(path, ec)) return make_error(path.string() + ": is a folder, not a file");
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return make_error(path.string() + ": cannot open for reading: " + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd, &st) != 0 || st.st_size < 0) {
        ::close(fd);
        return make_error(path.string() + ": cannot determine the file size");
    }
    MappedFile file;
    if (st.st_size > 0) {
        void* p = S_ISREG(st.st_mode) ? ::mmap(nullptr, size_t(st.st_size), PROT_READ, MAP_PRIVATE, fd, 0) : MAP_FAILED;
        if (p != MAP_FAILED) {
            file.data_ = static_cast<const uint8_t*>(p);
            file.size_ = size_t(st.st_size);
        }
    }
    ::close(fd);  // a mapping stays valid
    if (!file.data_ && st.st_size > 0) {
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
