// One headless GL context and the runtime include text for every simulator test of this executable, and
// the options of a small simulation.
// SPECBAKE_REQUIRE_GL() skips the test when SPECBAKE_NO_GL=1 (as the GL suite does) and fails with the
// reason when no context can be created.
#pragma once

#include "verify/gl_context.h"
#include "verify/verify_job.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <unistd.h>

namespace specbake::verify::test {

// A fresh folder under the system's temporary folder, removed with the object.
class TempDir {
public:
    TempDir() {
        path_ = std::filesystem::temp_directory_path() /
                ("specbake-verify-" + std::to_string(::getpid()) + "-" + std::to_string(counter_++));
        std::filesystem::create_directories(path_);
    }
    ~TempDir() { std::filesystem::remove_all(path_); }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
    static inline int counter_ = 0;
};

struct SimTestEnvironment {
    std::unique_ptr<GlContext> context;
    std::string error;    // why there is no context (reported by the tests, never skipped)
    std::string include;  // shaders/specaa.glsl
};

inline bool gl_disabled() {
    const char* v = std::getenv("SPECBAKE_NO_GL");
    return v && std::string(v) == "1";
}

inline SimTestEnvironment& sim_environment() {
    static SimTestEnvironment env = [] {
        SimTestEnvironment e;
        auto context = GlContext::create();
        if (!context) {
            e.error = context.error().message;
            return e;
        }
        e.context = std::move(*context);
        std::ifstream in(std::string(SPECBAKE_SOURCE_DIR) + "/shaders/specaa.glsl");
        std::stringstream text;
        text << in.rdbuf();
        e.include = text.str();
        if (e.include.empty()) e.error = "cannot read shaders/specaa.glsl";
        return e;
    }();
    return env;
}

// Options for a small, quick simulation: no timing, no SPIR-V counts, no bake variants, no images.
inline VerifyOptions small_verify(int width, int height, int spp, int frames) {
    VerifyOptions options;
    options.include_glsl = sim_environment().include;
    options.width = width;
    options.height = height;
    options.spp = spp;
    options.frames = frames;
    options.timing_repeats = 0;
    options.spirv = false;
    options.variants = false;
    options.keep_images = false;
    options.floor = false;
    options.limit = false;
    return options;
}

}  // namespace specbake::verify::test

#define SPECBAKE_REQUIRE_GL()                                                                           \
    do {                                                                                                \
        if (::specbake::verify::test::gl_disabled()) GTEST_SKIP() << "SPECBAKE_NO_GL=1: OpenGL tests disabled"; \
        ASSERT_TRUE(::specbake::verify::test::sim_environment().error.empty())                             \
            << "no headless OpenGL context (set SPECBAKE_NO_GL=1 to skip): "                           \
            << ::specbake::verify::test::sim_environment().error;                                          \
    } while (false)
