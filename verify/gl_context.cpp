#include "verify/gl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <system_error>

namespace specbake::verify {
namespace {

std::string egl_error_text(const char* what) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "%s failed (EGL error 0x%04x)", what, static_cast<unsigned>(eglGetError()));
    return std::string("headless OpenGL: ") + buf;
}

void default_shader_cache_dir() {
    if (std::getenv("MESA_SHADER_CACHE_DIR")) return;
    std::error_code ec;
    const auto dir = std::filesystem::temp_directory_path(ec) / "specbake-mesa-shader-cache";
    if (ec) return;
    std::filesystem::create_directories(dir, ec);
    if (!ec) setenv("MESA_SHADER_CACHE_DIR", dir.c_str(), 0);
}

// The info log of a shader or program object, through its pair of query functions.
template <class GetParameter, class GetLog>
std::string info_log(GLuint object, GetParameter get_parameter, GetLog get_log) {
    GLint length = 0;
    get_parameter(object, GL_INFO_LOG_LENGTH, &length);
    std::string log(static_cast<size_t>(std::max(length, 1)), '\0');
    get_log(object, length, nullptr, log.data());
    return log;
}

}  // namespace

Result<std::unique_ptr<GlContext>> GlContext::create() {
    default_shader_cache_dir();
    const char* extensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!extensions || !std::strstr(extensions, "EGL_MESA_platform_surfaceless"))
        return make_error("headless OpenGL: EGL_MESA_platform_surfaceless is not available "
                          "(install Mesa's EGL driver, Debian package libegl-mesa0)");
    auto get_platform_display =
        reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (!get_platform_display) return make_error("headless OpenGL: eglGetPlatformDisplayEXT is missing");
    EGLDisplay display = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (display == EGL_NO_DISPLAY) return make_error(egl_error_text("eglGetPlatformDisplayEXT"));
    EGLint major = 0, minor = 0;
    if (!eglInitialize(display, &major, &minor)) return make_error(egl_error_text("eglInitialize"));
    if (!eglBindAPI(EGL_OPENGL_API)) {
        eglTerminate(display);
        return make_error(egl_error_text("eglBindAPI(EGL_OPENGL_API)"));
    }
    const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                 EGL_NONE};
    EGLContext context = eglCreateContext(display, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attributes);
    if (context == EGL_NO_CONTEXT) {
        auto error = egl_error_text("eglCreateContext (OpenGL 4.5 core, no config)");
        eglTerminate(display);
        return make_error(error);
    }
    if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
        auto error = egl_error_text("eglMakeCurrent (surfaceless)");
        eglDestroyContext(display, context);
        eglTerminate(display);
        return make_error(error);
    }
    std::unique_ptr<GlContext> result(new GlContext());
    result->display_ = display;
    result->context_ = context;
    return result;
}

GlContext::~GlContext() {
    auto display = static_cast<EGLDisplay>(display_);
    eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display, static_cast<EGLContext>(context_));
    eglTerminate(display);
}

std::string GlContext::description() const {
    const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    return std::string(renderer ? renderer : "?") + ", " + (version ? version : "?");
}

Result<GLuint> compile_glsl_shader(GLenum stage, const std::string& source) {
    GLuint shader = glCreateShader(stage);
    const char* text = source.c_str();
    glShaderSource(shader, 1, &text, nullptr);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (ok) return shader;
    const std::string log = info_log(shader, glGetShaderiv, glGetShaderInfoLog);
    glDeleteShader(shader);
    return make_error(std::string(stage == GL_VERTEX_SHADER ? "vertex" : "fragment") +
                      " shader compilation failed: " + log);
}

Result<GLuint> link_program(GLuint vertex, GLuint fragment) {
    GLuint program = glCreateProgram();
    glAttachShader(program, vertex);
    glAttachShader(program, fragment);
    glLinkProgram(program);
    glDeleteShader(vertex);
    glDeleteShader(fragment);
    GLint ok = 0;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (ok) return program;
    const std::string log = info_log(program, glGetProgramiv, glGetProgramInfoLog);
    glDeleteProgram(program);
    return make_error("shader link failed: " + log);
}

}  // namespace specbake::verify
