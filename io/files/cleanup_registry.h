// Paths to remove when the process is interrupted: temporaries of atomic writes, staging folders and the lock
// files of output folders. install_interrupt_cleanup() makes SIGINT, SIGTERM and SIGHUP remove them before
// the process ends by the signal, so an interrupted run leaves nothing behind
// (docs/build-pipelines.md#output-folders-are-transactional).
#pragma once

#include <filesystem>
#include <mutex>

namespace specbake::io {

// Adds / drops a file or folder (removed with everything in it) to remove on interruption.
void register_cleanup(const std::filesystem::path& path);
void unregister_cleanup(const std::filesystem::path& path);

// Held while an output folder commits: the interrupt cleanup waits for the commit to finish, so a signal
// never cuts a commit in half.
std::unique_lock<std::mutex> hold_commit();

// Removes every registered path now. Called by the interrupt handler; usable by tests.
void remove_registered_paths();

// Blocks SIGINT, SIGTERM and SIGHUP in the calling thread (and every thread it starts later) and starts a
// thread that waits for them, removes the registered paths and then ends the process by the same signal
// (its exit status tells the parent which). Call once, at the start of main, before other threads exist.
void install_interrupt_cleanup();

}  // namespace specbake::io
