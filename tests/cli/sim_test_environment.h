// One headless GL context and the runtime include text for every simulator test of this executable.
// SPECBAKE_REQUIRE_GL() skips the test when SPECBAKE_NO_GL=1 (as the GL suite does) and fails with the
// reason when no context can be created.
#pragma once

#include "cli/gl_context.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

namespace specbake::cli::test {

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

}  // namespace specbake::cli::test

#define SPECBAKE_REQUIRE_GL()                                                                           \
    do {                                                                                                \
        if (::specbake::cli::test::gl_disabled()) GTEST_SKIP() << "SPECBAKE_NO_GL=1: OpenGL tests disabled"; \
        ASSERT_TRUE(::specbake::cli::test::sim_environment().error.empty())                             \
            << "no headless OpenGL context (set SPECBAKE_NO_GL=1 to skip): "                           \
            << ::specbake::cli::test::sim_environment().error;                                          \
    } while (false)
