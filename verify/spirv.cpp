#include "verify/spirv.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <random>
#include <sstream>
#include <unistd.h>

namespace specbake::verify {
namespace {

bool on_path(const std::string& tool) {
    const char* path = std::getenv("PATH");
    if (!path) return false;
    std::stringstream dirs(path);
    std::string dir;
    while (std::getline(dirs, dir, ':')) {
        if (!dir.empty() && ::access((std::filesystem::path(dir) / tool).c_str(), X_OK) == 0) return true;
    }
    return false;
}

// Runs `command` through the shell, returning its exit status and combined output.
std::pair<int, std::string> run(const std::string& command) {
    std::string output;
    FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
    if (!pipe) return {-1, "cannot start: " + command};
    char buffer[4096];
    while (size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) output.append(buffer, n);
    const int status = ::pclose(pipe);
    return {status, output};
}

// Removes a scratch folder on every exit path.
struct ScratchDir {
    std::filesystem::path path;
    ~ScratchDir() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
};

Result<int> count_uncached(const std::string& source);

}  // namespace

bool spirv_tools_available() {
    return on_path("glslangValidator") && on_path("spirv-opt") && on_path("spirv-dis");
}

Result<int> spirv_instruction_count(const std::string& source) {
    // Candidates repeat across scenes with identical text; the count depends on the text only.
    static std::mutex mutex;
    static std::map<std::string, int> counted;
    {
        std::lock_guard lock(mutex);
        if (auto it = counted.find(source); it != counted.end()) return it->second;
    }
    auto count = count_uncached(source);
    if (count) {
        std::lock_guard lock(mutex);
        counted[source] = *count;
    }
    return count;
}

namespace {

Result<int> count_uncached(const std::string& source) {
    std::error_code ec;
    std::random_device rd;
    ScratchDir dir{std::filesystem::temp_directory_path(ec) / ("specbake-spirv-" + std::to_string(rd()))};
    std::filesystem::create_directories(dir.path, ec);
    if (ec) return make_error("cannot create a scratch folder for SPIR-V: " + ec.message());
    const auto frag = dir.path / "candidate.frag";
    {
        std::ofstream out(frag);
        out << source;
        if (!out) return make_error("cannot write " + frag.string());
    }
    const std::string q = "'", spv = (dir.path / "a.spv").string(), opt = (dir.path / "b.spv").string();
    auto [s1, o1] = run("glslangValidator -G --auto-map-locations --auto-map-bindings -o " + q + spv + q + " " + q +
                        frag.string() + q);
    if (s1 != 0) return make_error("glslangValidator failed: " + o1.substr(0, 2000));
    auto [s2, o2] = run("spirv-opt -O " + q + spv + q + " -o " + q + opt + q);
    if (s2 != 0) return make_error("spirv-opt failed: " + o2.substr(0, 2000));
    auto [s3, text] = run("spirv-dis --no-header " + q + opt + q);
    if (s3 != 0) return make_error("spirv-dis failed: " + text.substr(0, 2000));
    int count = 0;
    bool inside = false;
    std::stringstream lines(text);
    std::string line;
    while (std::getline(lines, line)) {
        if (line.find("OpFunction ") != std::string::npos || line.ends_with("OpFunction")) inside = true;
        if (inside && line.find("Op") != std::string::npos) ++count;
        if (line.find("OpFunctionEnd") != std::string::npos) inside = false;
    }
    return count;
}

}  // namespace

}  // namespace specbake::verify
