// The process-wide cleanup list of io/files/cleanup_registry.h and the thread that handles interrupts.
#include "io/files/cleanup_registry.h"

#include <csignal>
#include <map>
#include <string>
#include <thread>
#include <pthread.h>
#include <unistd.h>

namespace specbake::io {
namespace fs = std::filesystem;

namespace {

std::mutex& registry_mutex() {
    static std::mutex m;
    return m;
}

std::mutex& commit_mutex() {
    static std::mutex m;
    return m;
}

// Path -> how many registrations (two writers may register the same folder).
std::map<std::string, int>& registry() {
    static std::map<std::string, int> paths;
    return paths;
}

}  // namespace

void register_cleanup(const fs::path& path) {
    std::lock_guard lock(registry_mutex());
    ++registry()[path.string()];
}

void unregister_cleanup(const fs::path& path) {
    std::lock_guard lock(registry_mutex());
    auto it = registry().find(path.string());
    if (it != registry().end() && --it->second <= 0) registry().erase(it);
}

std::unique_lock<std::mutex> hold_commit() { return std::unique_lock<std::mutex>(commit_mutex()); }

void remove_registered_paths() {
    std::lock_guard lock(registry_mutex());
    for (const auto& [path, count] : registry()) {
        // A writer still running may add a file to a folder while it is removed; a few passes catch it.
        for (int pass = 0; pass < 4; ++pass) {
            std::error_code ec;
            fs::remove_all(path, ec);
            if (!ec && !fs::exists(fs::symlink_status(path, ec))) break;
        }
    }
    registry().clear();
}

void install_interrupt_cleanup() {
    sigset_t set;
    sigemptyset(&set);
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&set, sig);
    if (pthread_sigmask(SIG_BLOCK, &set, nullptr) != 0) return;
    std::thread([set] {
        int sig = 0;
        while (sigwait(&set, &sig) != 0) {
        }
        // A commit in progress finishes first; none starts afterwards (the lock is never released).
        std::unique_lock commit = hold_commit();
        remove_registered_paths();
        std::signal(sig, SIG_DFL);
        pthread_sigmask(SIG_UNBLOCK, &set, nullptr);
        std::raise(sig);
        ::_exit(128 + sig);
    }).detach();
}

}  // namespace specbake::io
