// Transactional output folders (docs/build-pipelines.md#output-folders-are-transactional): one run at a time
// per folder (an advisory lock), every file of a run staged in a hidden folder inside it, and a commit whose
// record makes the folder hold either the previous complete bake or the new one, whenever the process dies.
//
// Commit protocol. The run writes everything, manifest.json included, into OUT/.specbake-stage-PID/. The
// commit point is the atomic rename of the stage's commit record (.specbake-commit, listing the previous
// bake's files that the new one does not write again). Then every staged file is renamed into place,
// the listed files are removed, manifest.json is renamed last and the stage is removed. A run killed
// before the commit point leaves the previous bake untouched (plus its stage, removed by the next run);
// one killed after it is rolled forward, by the next run or `inspect --check`, when they take the lock.
#pragma once

#include "core/result.h"

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace specbake::io {

inline constexpr const char* kLockFileName = ".specbake.lock";
inline constexpr const char* kStagePrefix = ".specbake-stage-";
inline constexpr const char* kCommitRecordName = ".specbake-commit";

// What a run finds in an output folder when it takes the lock.
struct FolderRecovery {
    bool finished_commit = false;                 // an interrupted commit was rolled forward
    std::vector<std::filesystem::path> leftovers;  // stages and temporaries of interrupted runs
    bool leftovers_removed = false;
};

// The exclusive advisory lock on OUT/.specbake.lock (flock), held for a whole run.
class OutputLock {
public:
    enum class Purpose {
        write,  // creates the folder; rolls an interrupted commit forward and removes leftovers
        check,  // rolls an interrupted commit forward when the folder is writable; only reports leftovers
    };
    // Waits while another process holds the lock; `on_wait` gets one line saying which process (may be
    // empty). A folder that cannot hold a lock file (read-only, check only) is read without one.
    static Result<OutputLock> acquire(const std::filesystem::path& dir, Purpose purpose,
                                      const std::function<void(const std::string&)>& on_wait = {});
    OutputLock() = default;
    OutputLock(OutputLock&& other) noexcept;
    OutputLock& operator=(OutputLock&& other) noexcept;
    OutputLock(const OutputLock&) = delete;
    OutputLock& operator=(const OutputLock&) = delete;
    ~OutputLock();  // removes the lock file and releases it; removes the folder when it made it and it is empty

    const std::filesystem::path& dir() const { return dir_; }
    const FolderRecovery& recovery() const { return recovery_; }
    bool held() const { return fd_ >= 0; }

private:
    void release();
    int fd_ = -1;
    std::filesystem::path dir_;
    bool created_dir_ = false;
    FolderRecovery recovery_;
};

// One run's staged output, under a lock the caller holds. Destroying it uncommitted removes the stage.
class OutputTransaction {
public:
    static Result<OutputTransaction> begin(const OutputLock& lock);
    OutputTransaction() = default;
    OutputTransaction(OutputTransaction&& other) noexcept;
    OutputTransaction& operator=(OutputTransaction&& other) noexcept;
    OutputTransaction(const OutputTransaction&) = delete;
    OutputTransaction& operator=(const OutputTransaction&) = delete;
    ~OutputTransaction();

    // Where the run writes what belongs at the same relative path in dir().
    const std::filesystem::path& stage() const { return stage_; }
    const std::filesystem::path& dir() const { return dir_; }
    // `message` with the stage folder replaced by the output folder, so errors name the final files.
    std::string final_names(const std::string& message) const;

    // Commits everything staged. `previous_files` (paths relative to dir(), '/'-separated) are the files
    // of the bake the folder held; those the stage does not hold again are removed. Paths that leave the
    // folder are ignored. Fails without changing the folder when a staged file cannot go into place.
    Result<void> commit(const std::vector<std::string>& previous_files);
    // The commit point alone (after the checks commit() makes): commit() is record() then finish_commit().
    // Once recorded, the stage is kept for roll-forward whatever happens to this object.
    Result<void> record(const std::vector<std::string>& previous_files);

private:
    std::filesystem::path dir_, stage_;
    bool done_ = true;
};

// Leftovers of interrupted runs in `dir` (stages without a commit record, `.NAME.tmpPID-N.EXT` files) and
// whether a stage holds a commit record (a commit to roll forward). Reads only.
struct FolderLeftovers {
    std::vector<std::filesystem::path> stale;
    std::vector<std::filesystem::path> pending_commits;
};
FolderLeftovers find_leftovers(const std::filesystem::path& dir);

// Rolls forward the commit recorded in `stage` (idempotent; the caller holds the folder's lock).
Result<void> finish_commit(const std::filesystem::path& dir, const std::filesystem::path& stage);

}  // namespace specbake::io
