#include "io/atomic_file.h"

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
#include "io/cleanup_registry.h"

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

// The temporary is registered for removal on interruption (io/cleanup_registry.h) while it may exist.
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

Result<void> AtomicOutput::commit() {
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
    if (fs::is_directory(path, ec)) return make_error(path.string() + ": is a folder, not a file");
    AtomicOutput probe(path);
    const int fd = ::open(probe.temp_path().c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0) return make_error(path.string() + ": cannot be written: " + std::strerror(errno));
    ::close(fd);
    return {};
}

Result<void> write_file_atomic(const fs::path& path, const std::string& text) {
    return write_file_atomic(path, std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
}

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
    const size_t page = size_t(::sysconf(_SC_PAGESIZE));
    const size_t begin = (offset + page - 1) / page * page;  // whole pages inside the range only
    const size_t end = std::min(size_, offset + size) / page * page;
    if (end > begin) ::madvise(const_cast<uint8_t*>(data_) + begin, end - begin, MADV_DONTNEED);
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

Result<void> check_output_not_input(const fs::path& output_dir, std::span<const fs::path> inputs) {
    std::error_code ec;
    const fs::path out = fs::weakly_canonical(output_dir, ec);
    for (const fs::path& in : inputs) {
        const fs::path inc = fs::weakly_canonical(in, ec);
        if (inc == out)
            return make_error(output_dir.string() + ": the output is an input file; inputs are never overwritten");
        if (inc.parent_path() == out)
            return make_error(output_dir.string() + ": the output folder holds the input " + in.string() +
                              "; choose another folder so inputs are never overwritten");
    }
    return {};
}

}  // namespace specbake::io
