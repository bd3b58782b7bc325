#include "gl/gl_harness.h"

#include <EGL/egl.h>

#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

namespace specbake::gltest {
namespace {

constexpr int kGridWidth = 256;

// Mesa's shader cache goes to a folder of this process, removed at exit, so tests never touch $HOME.
void private_shader_cache() {
    static TempDir cache;
    setenv("MESA_SHADER_CACHE_DIR", cache.path().c_str(), 1);
}

std::string shader_log(GLuint shader) {
    GLint length = 0;
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
    std::string log(static_cast<size_t>(std::max(length, 1)), '\0');
    glGetShaderInfoLog(shader, length, nullptr, log.data());
    return log;
}

GLuint link(GLuint vs, GLuint fs, std::string& log) {
    auto program = verify::link_program(vs, fs);
    if (!program) {
        log += program.error().message;
        return 0;
    }
    return *program;
}

GLuint compile_glsl(GLenum stage, const std::string& source, std::string& log) {
    auto shader = verify::compile_glsl_shader(stage, source);
    if (!shader) {
        log += shader.error().message;
        return 0;
    }
    return *shader;
}

GLuint load_spirv(GLenum stage, const std::vector<char>& binary, std::string& log) {
    // glSpecializeShader is core in 4.6; on a 4.5 context it is the ARB_gl_spirv entry point.
    static auto specialize =
        reinterpret_cast<PFNGLSPECIALIZESHADERPROC>(eglGetProcAddress("glSpecializeShaderARB"));
    if (!specialize) {
        log += "glSpecializeShaderARB is missing";
        return 0;
    }
    GLuint shader = glCreateShader(stage);
    glShaderBinary(1, &shader, GL_SHADER_BINARY_FORMAT_SPIR_V_ARB, binary.data(), static_cast<GLsizei>(binary.size()));
    specialize(shader, "main", 0, nullptr, nullptr);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        log += (stage == GL_VERTEX_SHADER ? "vertex SPIR-V: " : "fragment SPIR-V: ") + shader_log(shader);
        glDeleteShader(shader);
        return 0;
    }
    return shader;
}

// Links the two stages when both exist; otherwise deletes whichever does and returns 0 (the log already
// says why).
GLuint link_both(GLuint vs, GLuint fs, std::string& log) {
    if (!vs || !fs) {
        glDeleteShader(vs);
        glDeleteShader(fs);
        return 0;
    }
    return link(vs, fs, log);
}

}  // namespace

bool gl_disabled() {
    const char* v = std::getenv("SPECBAKE_NO_GL");
    return v && std::strcmp(v, "1") == 0;
}

std::unique_ptr<GlContext> GlContext::open(std::string& reason) {
    private_shader_cache();
    auto context = verify::GlContext::create();
    if (!context) {
        reason = context.error().message;
        return nullptr;
    }
    std::unique_ptr<GlContext> result(new GlContext());
    result->context_ = std::move(context.value());
    return result;
}

GlContext::~GlContext() = default;

bool GlContext::has_extension(const char* name) const {
    GLint count = 0;
    glGetIntegerv(GL_NUM_EXTENSIONS, &count);
    for (GLint i = 0; i < count; ++i)
        if (std::strcmp(reinterpret_cast<const char*>(glGetStringi(GL_EXTENSIONS, static_cast<GLuint>(i))), name) == 0)
            return true;
    return false;
}

std::string GlContext::renderer() const {
    return std::string(reinterpret_cast<const char*>(glGetString(GL_RENDERER))) + ", " +
           reinterpret_cast<const char*>(glGetString(GL_VERSION));
}

std::string read_source_file(const std::string& relative_path) {
    std::ifstream in(std::filesystem::path(SPECBAKE_SOURCE_DIR) / relative_path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

TempDir::TempDir() {
    std::random_device rd;
    const auto base = std::filesystem::temp_directory_path();
    do {
        path_ = base / ("specbake-gl-" + std::to_string(rd()));
    } while (!std::filesystem::create_directory(path_));
}

TempDir::~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
}

int run_command(const std::string& command, std::string& output) {
    output.clear();
    FILE* pipe = popen((command + " 2>&1").c_str(), "r");
    if (!pipe) return -1;
    std::array<char, 4096> buf{};
    size_t n = 0;
    while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) output.append(buf.data(), n);
    const int status = pclose(pipe);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

GLuint create_float_targets(int count, int width, int height, GLuint* textures) {
    const GLenum attachments[8] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2, GL_COLOR_ATTACHMENT3,
                                   GL_COLOR_ATTACHMENT4, GL_COLOR_ATTACHMENT5, GL_COLOR_ATTACHMENT6, GL_COLOR_ATTACHMENT7};
    GLuint fbo = 0;
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glGenTextures(count, textures);
    for (int i = 0; i < count; ++i) {
        glBindTexture(GL_TEXTURE_2D, textures[i]);
        glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA32F, width, height);
        glFramebufferTexture2D(GL_FRAMEBUFFER, attachments[i], GL_TEXTURE_2D, textures[i], 0);
    }
    glDrawBuffers(count, attachments);
    return fbo;
}

GLuint build_program_glsl(const std::string& vertex, const std::string& fragment, std::string& log) {
    const GLuint vs = compile_glsl(GL_VERTEX_SHADER, vertex, log);
    const GLuint fs = compile_glsl(GL_FRAGMENT_SHADER, fragment, log);
    return link_both(vs, fs, log);
}

GLuint build_program_spirv(const std::vector<char>& vertex, const std::vector<char>& fragment, std::string& log) {
    const GLuint vs = load_spirv(GL_VERTEX_SHADER, vertex, log);
    const GLuint fs = load_spirv(GL_FRAGMENT_SHADER, fragment, log);
    return link_both(vs, fs, log);
}

std::string grid_vertex_shader() {
    return R"(#version 450
layout(location = 0) in vec4 aIn0;
layout(location = 1) in vec4 aIn1;
layout(location = 2) in vec4 aIn2;
layout(location = 3) in vec4 aIn3;
layout(location = 4) in vec4 aIn4;
layout(location = 5) in vec4 aIn5;
layout(location = 6) in vec2 aPixel;   // pixel centre in clip space
layout(location = 0) flat out vec4 vIn0;
layout(location = 1) flat out vec4 vIn1;
layout(location = 2) flat out vec4 vIn2;
layout(location = 3) flat out vec4 vIn3;
layout(location = 4) flat out vec4 vIn4;
layout(location = 5) flat out vec4 vIn5;
void main() {
    vIn0 = aIn0; vIn1 = aIn1; vIn2 = aIn2; vIn3 = aIn3; vIn4 = aIn4; vIn5 = aIn5;
    gl_Position = vec4(aPixel, 0.0, 1.0);
    gl_PointSize = 1.0;
}
)";
}

std::string grid_fragment_glsl(const std::string& test_case) {
    return "#version 450\n#define SPECAA_TEST_" + test_case + "\n" + read_source_file("shaders/specaa.glsl") +
           read_source_file("tests/gl/shaders/grid_eval.inc") + R"(
layout(location = 0) flat in vec4 vIn0;
layout(location = 1) flat in vec4 vIn1;
layout(location = 2) flat in vec4 vIn2;
layout(location = 3) flat in vec4 vIn3;
layout(location = 4) flat in vec4 vIn4;
layout(location = 5) flat in vec4 vIn5;
layout(location = 0) out vec4 o0;
layout(location = 1) out vec4 o1;
layout(location = 2) out vec4 o2;
layout(location = 3) out vec4 o3;
void main() { specaa_test_eval(vIn0, vIn1, vIn2, vIn3, vIn4, vIn5, o0, o1, o2, o3); }
)";
}

std::string grid_fragment_hlsl(const std::string& test_case) {
    return "#define SPECAA_TEST_" + test_case + "\n" + read_source_file("shaders/specaa.hlsl") +
           read_source_file("tests/gl/shaders/grid_eval.inc") + R"(
struct GridOutput {
    float4 o0 : SV_Target0;
    float4 o1 : SV_Target1;
    float4 o2 : SV_Target2;
    float4 o3 : SV_Target3;
};
GridOutput main(nointerpolation float4 in0 : TEXCOORD0, nointerpolation float4 in1 : TEXCOORD1,
                nointerpolation float4 in2 : TEXCOORD2, nointerpolation float4 in3 : TEXCOORD3,
                nointerpolation float4 in4 : TEXCOORD4, nointerpolation float4 in5 : TEXCOORD5) {
    GridOutput r;
    specaa_test_eval(in0, in1, in2, in3, in4, in5, r.o0, r.o1, r.o2, r.o3);
    return r;
}
)";
}

std::vector<GridResult> evaluate_grid(GLuint program, const std::vector<GridCase>& cases, std::string& log) {
    const int count = static_cast<int>(cases.size());
    const int width = kGridWidth;
    const int height = (count + width - 1) / width;

    // Interleaved vertices: six vec4 inputs and the pixel centre.
    std::vector<float> vertices;
    vertices.reserve(cases.size() * 26);
    for (int i = 0; i < count; ++i) {
        for (const Vec4& v : cases[static_cast<size_t>(i)].in) vertices.insert(vertices.end(), v.begin(), v.end());
        vertices.push_back((static_cast<float>(i % width) + 0.5f) / static_cast<float>(width) * 2.0f - 1.0f);
        vertices.push_back((static_cast<float>(i / width) + 0.5f) / static_cast<float>(height) * 2.0f - 1.0f);
    }
    GLuint vao = 0, vbo = 0, fbo = 0;
    std::array<GLuint, 4> targets{};
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    glGenBuffers(1, &vbo);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(float)), vertices.data(), GL_STATIC_DRAW);
    const GLsizei stride = 26 * sizeof(float);
    for (GLuint a = 0; a < 7; ++a) {
        glEnableVertexAttribArray(a);
        glVertexAttribPointer(a, a < 6 ? 4 : 2, GL_FLOAT, GL_FALSE, stride,
                              reinterpret_cast<const void*>(static_cast<uintptr_t>(a * 4 * sizeof(float))));
    }
    fbo = create_float_targets(4, width, height, targets.data());
    std::vector<GridResult> results;
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        log += "float framebuffer incomplete";
    } else {
        glViewport(0, 0, width, height);
        const float nan = std::numeric_limits<float>::quiet_NaN();
        const float clear[4] = {nan, nan, nan, nan};
        for (int t = 0; t < 4; ++t) glClearBufferfv(GL_COLOR, t, clear);
        glUseProgram(program);
        glDrawArrays(GL_POINTS, 0, count);
        std::vector<float> pixels(static_cast<size_t>(width * height * 4));
        results.resize(cases.size());
        for (int t = 0; t < 4; ++t) {
            glReadBuffer(GL_COLOR_ATTACHMENT0 + GLenum(t));
            glReadPixels(0, 0, width, height, GL_RGBA, GL_FLOAT, pixels.data());
            for (int i = 0; i < count; ++i)
                for (int c = 0; c < 4; ++c)
                    results[static_cast<size_t>(i)].out[static_cast<size_t>(t)][static_cast<size_t>(c)] =
                        pixels[static_cast<size_t>(i * 4 + c)];
        }
        if (GLenum error = glGetError(); error != GL_NO_ERROR) {
            log += "GL error " + std::to_string(error);
            results.clear();
        }
    }
    glDeleteTextures(4, targets.data());
    glDeleteFramebuffers(1, &fbo);
    glDeleteBuffers(1, &vbo);
    glDeleteVertexArrays(1, &vao);
    return results;
}

}  // namespace specbake::gltest
