#include "io/atomic_file.h"

#include <atomic>
#include <cstdio>
#include <fstream>
#include <system_error>
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/huge_pages.h"

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

AtomicOutput::AtomicOutput(fs::path final_path) : final_(std::move(final_path)), temp_(make_temp_path(final_)) {}

AtomicOutput::~AtomicOutput() {
    if (!committed_) {
        std::error_code ec;
        fs::remove(temp_, ec);
    }
}

Result<void> AtomicOutput::commit() {
    std::error_code ec;
    if (!fs::exists(temp_, ec)) return make_error(final_.string() + ": nothing was written");
    fs::rename(temp_, final_, ec);
    if (ec) return make_error(final_.string() + ": cannot move the finished file into place: " + ec.message());
    committed_ = true;
    return {};
}

Result<void> write_file_atomic(const fs::path& path, std::span<const uint8_t> bytes) {
    std::error_code ec;
    if (path.has_parent_path()) fs::create_directories(path.parent_path(), ec);
    if (ec) return make_error(path.parent_path().string() + ": cannot create folder: " + ec.message());
    AtomicOutput out(path);
    {
        std::ofstream f(out.temp_path(), std::ios::binary | std::ios::trunc);
        if (!f) return make_error(path.string() + ": cannot open for writing");
        f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
        f.flush();
        if (!f) return make_error(path.string() + ": write failed (disk full?)");
    }
    return out.commit();
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
    if (fd < 0) return make_error(path.string() + ": cannot open for reading");
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
