// The output-folder lock, staging, commit and recovery of io/output/output_folder.h.
#include "io/output/output_folder.h"

#include "io/files/atomic_write.h"
#include "io/files/file_read.h"
#include "io/files/cleanup_registry.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <regex>
#include <set>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

namespace specbake::io {
namespace fs = std::filesystem;

namespace {

std::string os_error(int err) { return std::strerror(err); }

bool is_stage_name(const std::string& name) { return name.rfind(kStagePrefix, 0) == 0; }

// The temporaries AtomicOutput names .<stem>.tmp<pid>-<n><ext>.
bool is_temp_name(const std::string& name) {
    static const std::regex pattern(R"(\..*\.tmp[0-9]+-[0-9]+(\.[^/]*)?)");
    return std::regex_match(name, pattern);
}

// A manifest path that stays inside the folder: relative, no "..", not one of specbake's own names.
bool is_inside(const std::string& rel) {
    const fs::path p = fs::path(rel).lexically_normal();
    if (rel.empty() || p.is_absolute() || p.empty() || *p.begin() == "..") return false;
    const std::string first = p.begin()->string();
    return first != "." && first != kLockFileName && !is_stage_name(first);
}

// Regular files under `stage` (relative, '/'), without the commit record.
std::vector<std::string> staged_files(const fs::path& stage) {
    std::vector<std::string> files;
    std::error_code ec;
    for (auto it = fs::recursive_directory_iterator(stage, ec); !ec && it != fs::recursive_directory_iterator();
         it.increment(ec)) {
        if (!it->is_regular_file(ec)) continue;
        const std::string rel = it->path().lexically_relative(stage).generic_string();
        if (rel != kCommitRecordName) files.push_back(rel);
    }
    std::sort(files.begin(), files.end());
    return files;
}

// Removes `file`'s empty parent folders up to (not including) `dir`.
void remove_empty_parents(const fs::path& dir, fs::path file) {
    std::error_code ec;
    for (fs::path p = file.parent_path(); p != dir && p.string().size() > dir.string().size(); p = p.parent_path())
        if (!fs::remove(p, ec)) break;  // fails (and stops) when not empty
}

Result<void> rename_into(const fs::path& from, const fs::path& to) {
    std::error_code ec;
    fs::create_directories(to.parent_path(), ec);
    if (::rename(from.c_str(), to.c_str()) != 0)
        return make_error(to.string() + ": cannot move the finished file into place: " + os_error(errno));
    return {};
}

Result<void> write_record(const fs::path& stage, const std::vector<std::string>& remove) {
    const fs::path temp = stage / (std::string(kCommitRecordName) + ".tmp");
    const std::string text = nlohmann::json{{"remove", remove}}.dump() + "\n";
    if (auto ok = write_bytes_to(temp, stage.parent_path(),
                                 {reinterpret_cast<const uint8_t*>(text.data()), text.size()});
        !ok)
        return ok;
    if (::rename(temp.c_str(), (stage / kCommitRecordName).c_str()) != 0)
        return make_error(stage.parent_path().string() + ": cannot record the commit: " + os_error(errno));
    return {};
}

}  // namespace

FolderLeftovers find_leftovers(const fs::path& dir) {
    FolderLeftovers out;
    std::error_code ec;
    for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::recursive_directory_iterator();
         it.increment(ec)) {
        const std::string name = it->path().filename().string();
        // Stages sit at the top; temporaries at most one folder down (several scenes: OUT/<scene>/).
        if (it.depth() >= 1 && it->is_directory(ec)) it.disable_recursion_pending();
        if (is_stage_name(name) && it->is_directory(ec)) {
            if (fs::exists(it->path() / kCommitRecordName, ec)) out.pending_commits.push_back(it->path());
            else out.stale.push_back(it->path());
            it.disable_recursion_pending();
        } else if (is_temp_name(name) && !it->is_directory(ec)) {
            out.stale.push_back(it->path());
        }
    }
    std::sort(out.stale.begin(), out.stale.end());
    return out;
}

Result<void> finish_commit(const fs::path& dir, const fs::path& stage) {
    std::vector<std::string> remove;
    if (auto record = read_file(stage / kCommitRecordName); record) {
        const auto j = nlohmann::json::parse(record->begin(), record->end(), nullptr, false);
        if (j.is_object() && j.contains("remove") && j["remove"].is_array())
            for (const auto& r : j["remove"])
                if (r.is_string()) remove.push_back(r.get<std::string>());
    }
    // 1. Every staged file but the manifest; 2. the previous bake's files not written again; 3. the
    // manifest; 4. the stage. Each step only finds what an interrupted pass left, so repeating is safe.
    for (const std::string& rel : staged_files(stage))
        if (rel != "manifest.json")
            if (auto ok = rename_into(stage / rel, dir / rel); !ok) return ok;
    std::error_code ec;
    for (const std::string& rel : remove) {
        if (!is_inside(rel)) continue;
        fs::remove(dir / rel, ec);
        remove_empty_parents(dir, dir / rel);
    }
    if (fs::exists(stage / "manifest.json", ec))
        if (auto ok = rename_into(stage / "manifest.json", dir / "manifest.json"); !ok) return ok;
    fs::remove_all(stage, ec);
    if (ec) return make_error(stage.string() + ": cannot remove the staging folder: " + ec.message());
    return {};
}

Result<OutputLock> OutputLock::acquire(const fs::path& dir, Purpose purpose,
                                       const std::function<void(const std::string&)>& on_wait) {
    std::error_code ec;
    OutputLock lock;
    lock.dir_ = dir;
    if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
        return make_error(dir.string() + ": exists and is not a folder");
    const fs::path file = dir / kLockFileName;
    bool told = false;
    int vanished = 0;
    for (;;) {
        // (Again on every pass: a holder that made the folder removes it when it stays empty.)
        if (purpose == Purpose::write && !fs::exists(dir, ec)) {
            lock.created_dir_ = fs::create_directories(dir, ec);
            if (ec) return make_error(dir.string() + ": cannot create folder: " + ec.message());
        }
        int fd = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        // The holder that made the folder may have removed it, empty, between our look and the open.
        if (fd < 0 && errno == ENOENT && purpose == Purpose::write && ++vanished < 64) continue;
        if (fd < 0 && purpose == Purpose::check) return lock;  // a folder nobody can write into
        if (fd < 0) return make_error(dir.string() + ": cannot create the lock file " + kLockFileName + ": " + os_error(errno));
        if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
            if (on_wait && !told) {
                char pid[32] = {};
                const ssize_t n = ::pread(fd, pid, sizeof pid - 1, 0);
                const std::string holder = n > 0 ? std::string(pid, size_t(n)) : std::string("?");
                on_wait(dir.string() + ": waiting for specbake process " + holder +
                        ", which is writing this folder");
                told = true;
            }
            while (::flock(fd, LOCK_EX) != 0 && errno == EINTR) {
            }
        }
        // The holder before us may have removed the file: then this lock is on a dead inode; take a new one.
        struct stat held {}, now {};
        if (::fstat(fd, &held) == 0 && ::stat(file.c_str(), &now) == 0 && held.st_ino == now.st_ino &&
            held.st_dev == now.st_dev) {
            const std::string pid = std::to_string(::getpid());
            if (::ftruncate(fd, 0) == 0 && ::pwrite(fd, pid.data(), pid.size(), 0) < 0) {
                // the holder's number is only for the waiting message
            }
            lock.fd_ = fd;
            break;
        }
        ::close(fd);
    }
    register_cleanup(file);

    // Recovery: roll an interrupted commit forward; remove (write) or report (check) the leftovers.
    const FolderLeftovers found = find_leftovers(dir);
    for (const fs::path& stage : found.pending_commits) {
        if (auto ok = finish_commit(dir, stage); !ok)
            return make_error(dir.string() + ": cannot finish the interrupted commit of an earlier run: " +
                              ok.error().message);
        lock.recovery_.finished_commit = true;
    }
    lock.recovery_.leftovers = found.stale;
    if (purpose == Purpose::write) {
        for (const fs::path& p : found.stale) fs::remove_all(p, ec);
        lock.recovery_.leftovers_removed = true;
    }
    return lock;
}

OutputLock::OutputLock(OutputLock&& other) noexcept
    : fd_(other.fd_), dir_(std::move(other.dir_)), created_dir_(other.created_dir_),
      recovery_(std::move(other.recovery_)) {
    other.fd_ = -1;
}

OutputLock& OutputLock::operator=(OutputLock&& other) noexcept {
    if (this != &other) {
        release();
        fd_ = other.fd_;
        dir_ = std::move(other.dir_);
        created_dir_ = other.created_dir_;
        recovery_ = std::move(other.recovery_);
        other.fd_ = -1;
    }
    return *this;
}

OutputLock::~OutputLock() { release(); }

void OutputLock::release() {
    if (fd_ < 0) return;
    // Removed while held: a process waiting on the old file sees it gone and takes a new one.
    const fs::path file = dir_ / kLockFileName;
    ::unlink(file.c_str());
    unregister_cleanup(file);
    ::close(fd_);
    fd_ = -1;
    std::error_code ec;
    if (created_dir_ && fs::is_empty(dir_, ec)) fs::remove(dir_, ec);
}

Result<OutputTransaction> OutputTransaction::begin(const OutputLock& lock) {
    OutputTransaction tx;
    tx.dir_ = lock.dir();
    tx.stage_ = tx.dir_ / (kStagePrefix + std::to_string(::getpid()));
    std::error_code ec;
    fs::remove_all(tx.stage_, ec);  // a stage of an earlier process with the same number
    register_cleanup(tx.stage_);
    if (::mkdir(tx.stage_.c_str(), 0755) != 0) {
        const int err = errno;
        unregister_cleanup(tx.stage_);
        return make_error(tx.dir_.string() + ": cannot create the staging folder " + tx.stage_.filename().string() +
                          ": " + os_error(err));
    }
    tx.done_ = false;
    return tx;
}

OutputTransaction::OutputTransaction(OutputTransaction&& other) noexcept
    : dir_(std::move(other.dir_)), stage_(std::move(other.stage_)), done_(other.done_) {
    other.done_ = true;
}

OutputTransaction& OutputTransaction::operator=(OutputTransaction&& other) noexcept {
    if (this != &other) {
        this->~OutputTransaction();
        dir_ = std::move(other.dir_);
        stage_ = std::move(other.stage_);
        done_ = other.done_;
        other.done_ = true;
    }
    return *this;
}

OutputTransaction::~OutputTransaction() {
    if (done_) return;
    std::error_code ec;
    fs::remove_all(stage_, ec);
    unregister_cleanup(stage_);
    done_ = true;
}

std::string OutputTransaction::final_names(const std::string& message) const {
    std::string out = message;
    const std::string from = stage_.string(), to = dir_.string();
    if (from.empty()) return out;
    for (size_t at = out.find(from); at != std::string::npos; at = out.find(from, at + to.size()))
        out.replace(at, from.size(), to);
    return out;
}

Result<void> OutputTransaction::record(const std::vector<std::string>& previous_files) {
    if (done_) return make_error(dir_.string() + ": nothing staged to commit");
    const std::vector<std::string> staged = staged_files(stage_);
    const std::set<std::string> written(staged.begin(), staged.end());
    std::vector<std::string> remove;
    std::error_code ec;
    for (const std::string& rel : previous_files) {
        const std::string norm = fs::path(rel).lexically_normal().generic_string();
        if (is_inside(rel) && !written.count(norm) && fs::exists(fs::symlink_status(dir_ / norm, ec))) remove.push_back(norm);
    }
    // Everything that could stop a staged file from going into place is checked before the commit point.
    for (const std::string& rel : staged) {
        const fs::path to = dir_ / rel;
        if (fs::is_directory(fs::symlink_status(to, ec)))
            return make_error(to.string() + ": is a folder; cannot replace it with a file");
        if (auto ok = check_replaceable(to); !ok) return ok;
        for (fs::path p = to.parent_path(); p != dir_ && p.string().size() > dir_.string().size(); p = p.parent_path())
            if (fs::exists(fs::symlink_status(p, ec)) && !fs::is_directory(p, ec))
                return make_error(p.string() + ": is a file; cannot put " + to.string() + " into it");
    }
    if (auto ok = write_record(stage_, remove); !ok) return make_error(final_names(ok.error().message));
    // Recorded: from here on the stage is the commit, finished by this run or the next one, never removed.
    done_ = true;
    unregister_cleanup(stage_);
    return {};
}

Result<void> OutputTransaction::commit(const std::vector<std::string>& previous_files) {
    std::unique_lock hold = hold_commit();
    if (auto ok = record(previous_files); !ok) return ok;
    if (auto ok = finish_commit(dir_, stage_); !ok)
        return make_error(final_names(ok.error().message) + " (the next specbake run into " + dir_.string() +
                          " finishes the commit)");
    return {};
}

}  // namespace specbake::io
