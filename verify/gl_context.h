// Headless OpenGL 4.5 core context on EGL's surfaceless platform (Mesa; llvmpipe without a GPU), for the
// ground-truth simulator. No window or surface: rendering goes to float framebuffer objects.
// GL entry points come from GLVND's libOpenGL, which exports every core function up to 4.6.
#pragma once

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include "core/result.h"

#include <memory>
#include <string>

namespace specbake::verify {

class GlContext {
public:
    // Creates the context and makes it current on the calling thread. Sets MESA_SHADER_CACHE_DIR to a
    // folder under the system temp directory when it is unset, so Mesa never writes into $HOME.
    static Result<std::unique_ptr<GlContext>> create();
    ~GlContext();
    GlContext(const GlContext&) = delete;
    GlContext& operator=(const GlContext&) = delete;

    // GL_RENDERER and GL_VERSION, e.g. "llvmpipe (LLVM 15.0.6, 256 bits), 4.5 (Core Profile) Mesa 22.3.6".
    std::string description() const;

private:
    GlContext() = default;
    void* display_ = nullptr;
    void* context_ = nullptr;
};

// Compiles one GLSL stage (GL_VERTEX_SHADER, GL_FRAGMENT_SHADER, ...) in the current context; the error
// carries the driver's info log.
Result<GLuint> compile_glsl_shader(GLenum stage, const std::string& source);

// Links a program from two compiled stages and deletes the stages; the error carries the link log.
Result<GLuint> link_program(GLuint vertex, GLuint fragment);

}  // namespace specbake::verify
