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
#include <iterator>
#include <limits>
#include <random>
#include <sstream>

namespace specbake::gltest {
namespace {

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

std::vector<char> read_binary(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string pass_through_vertex_shader(int inputs, int point_size) {
    std::string decl, out, copy;
    for (int i = 0; i < inputs; ++i) {
        const std::string n = std::to_string(i);
        decl += "layout(location = " + n + ") in vec4 aIn" + n + ";\n";
        out += "layout(location = " + n + ") flat out vec4 vIn" + n + ";\n";
        copy += "    vIn" + n + " = aIn" + n + ";\n";
    }
    return "#version 450\n" + decl + "layout(location = " + std::to_string(inputs) +
           ") in vec2 aCell;   // cell centre in clip space\n" + out + "void main() {\n" + copy +
           "    gl_Position = vec4(aCell, 0.0, 1.0);\n    gl_PointSize = " + std::to_string(point_size) + ".0;\n}\n";
}

std::string glsl_fragment_wrapper(int inputs, int outputs, const std::string& body) {
    std::string s = "\n";
    for (int i = 0; i < inputs; ++i)
        s += "layout(location = " + std::to_string(i) + ") flat in vec4 vIn" + std::to_string(i) + ";\n";
    for (int i = 0; i < outputs; ++i)
        s += "layout(location = " + std::to_string(i) + ") out vec4 o" + std::to_string(i) + ";\n";
    return s + "void main() {\n" + body + "\n}\n";
}

std::string hlsl_fragment_wrapper(int inputs, int outputs, const std::string& leading, const std::string& body) {
    std::string s = "\nstruct FragmentOutput {\n";
    for (int i = 0; i < outputs; ++i) s += "    float4 o" + std::to_string(i) + " : SV_Target" + std::to_string(i) + ";\n";
    s += "};\nFragmentOutput main(" + leading;
    for (int i = 0; i < inputs; ++i)
        s += (i ? ", " : "") + std::string("nointerpolation float4 in") + std::to_string(i) + " : TEXCOORD" +
             std::to_string(i);
    return s + ") {\n    FragmentOutput r;\n" + body + "\n    return r;\n}\n";
}

std::vector<char> compile_vertex_spirv(const std::string& source, const std::filesystem::path& path, std::string& log) {
    std::ofstream(path) << source;
    const std::string spv = path.string() + ".spv";
    std::string out;
    if (run_command("glslangValidator -G -S vert '" + path.string() + "' -o '" + spv + "'", out) != 0) {
        log += "glslangValidator: " + out;
        return {};
    }
    return read_binary(spv);
}

GLuint build_program_hlsl_spirv(const std::vector<char>& vertex, const std::string& source,
                                const std::filesystem::path& stem, std::string& log) {
    const std::string src = stem.string() + ".hlsl", spv = stem.string() + ".spv";
    std::ofstream(src) << source;
    std::string text;
    if (run_command("glslangValidator -V -D -e main -S frag '" + src + "' -o '" + spv + "' && spirv-val '" + spv + "'",
                    text) != 0) {
        log += "glslangValidator/spirv-val: " + text;
        return 0;
    }
    return build_program_spirv(vertex, read_binary(spv), log);
}

int point_grid_height(const PointGrid& grid, size_t count) {
    const size_t per_row = size_t(grid.width / grid.cell);
    return grid.cell * int((count + per_row - 1) / per_row);
}

std::vector<float> evaluate_points(GLuint program, const std::vector<float>& inputs, const PointGrid& grid, std::string& log) {
    const size_t floats_in = size_t(4 * grid.inputs), floats_out = size_t(4 * grid.outputs);
    const size_t count = inputs.size() / floats_in;
    const size_t per_row = size_t(grid.width / grid.cell);
    const int width = grid.width, height = point_grid_height(grid, count);

    // Interleaved vertices: the vec4 inputs and the cell centre.
    std::vector<float> vertices;
    vertices.reserve(count * (floats_in + 2));
    for (size_t i = 0; i < count; ++i) {
        vertices.insert(vertices.end(), inputs.begin() + std::ptrdiff_t(i * floats_in),
                        inputs.begin() + std::ptrdiff_t((i + 1) * floats_in));
        const int qx = int(i % per_row), qy = int(i / per_row);
        vertices.push_back((float(grid.cell * qx) + 0.5f * float(grid.cell)) / float(width) * 2.0f - 1.0f);
        vertices.push_back((float(grid.cell * qy) + 0.5f * float(grid.cell)) / float(height) * 2.0f - 1.0f);
    }
    GLuint vao = 0, vbo = 0;
    std::array<GLuint, 8> targets{};
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    glGenBuffers(1, &vbo);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(vertices.size() * sizeof(float)), vertices.data(), GL_STATIC_DRAW);
    const GLsizei stride = GLsizei((floats_in + 2) * sizeof(float));
    for (GLuint a = 0; a <= GLuint(grid.inputs); ++a) {
        glEnableVertexAttribArray(a);
        glVertexAttribPointer(a, a < GLuint(grid.inputs) ? 4 : 2, GL_FLOAT, GL_FALSE, stride,
                              reinterpret_cast<const void*>(uintptr_t(a * 4 * sizeof(float))));
    }
    const GLuint fbo = create_float_targets(grid.outputs, width, height, targets.data());
    std::vector<float> results;
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        log += "float framebuffer incomplete";
    } else {
        glViewport(0, 0, width, height);
        const float nan = std::numeric_limits<float>::quiet_NaN();
        const float clear[4] = {nan, nan, nan, nan};
        for (int t = 0; t < grid.outputs; ++t) glClearBufferfv(GL_COLOR, t, clear);
        glEnable(GL_PROGRAM_POINT_SIZE);
        glUseProgram(program);
        glDrawArrays(GL_POINTS, 0, GLsizei(count));
        results.resize(count * floats_out);
        std::vector<float> pixels(size_t(width) * size_t(height) * 4);
        for (int t = 0; t < grid.outputs; ++t) {
            glReadBuffer(GL_COLOR_ATTACHMENT0 + GLenum(t));
            glReadPixels(0, 0, width, height, GL_RGBA, GL_FLOAT, pixels.data());
            for (size_t i = 0; i < count; ++i) {
                const size_t qx = i % per_row, qy = i / per_row;
                const float* p = &pixels[(size_t(grid.cell) * (qy * size_t(width) + qx)) * 4];
                std::copy(p, p + 4, results.begin() + std::ptrdiff_t(i * floats_out + 4 * size_t(t)));
            }
        }
        if (GLenum error = glGetError(); error != GL_NO_ERROR) {
            log += "GL error " + std::to_string(error);
            results.clear();
        }
    }
    glDeleteTextures(grid.outputs, targets.data());
    glDeleteFramebuffers(1, &fbo);
    glDeleteBuffers(1, &vbo);
    glDeleteVertexArrays(1, &vao);
    return results;
}

std::string grid_vertex_shader() { return pass_through_vertex_shader(6, 1); }

std::string grid_fragment_glsl(const std::string& test_case) {
    return "#version 450\n#define SPECAA_TEST_" + test_case + "\n" + read_source_file("shaders/specaa.glsl") +
           read_source_file("tests/gl/shaders/grid_eval.inc") +
           glsl_fragment_wrapper(6, 4, "specaa_test_eval(vIn0, vIn1, vIn2, vIn3, vIn4, vIn5, o0, o1, o2, o3);");
}

std::string grid_fragment_hlsl(const std::string& test_case) {
    return "#define SPECAA_TEST_" + test_case + "\n" + read_source_file("shaders/specaa.hlsl") +
           read_source_file("tests/gl/shaders/grid_eval.inc") +
           hlsl_fragment_wrapper(6, 4, "", "specaa_test_eval(in0, in1, in2, in3, in4, in5, r.o0, r.o1, r.o2, r.o3);");
}

std::vector<GridResult> evaluate_grid(GLuint program, const std::vector<GridCase>& cases, std::string& log) {
    std::vector<float> inputs;
    inputs.reserve(cases.size() * 24);
    for (const GridCase& c : cases)
        for (const Vec4& v : c.in) inputs.insert(inputs.end(), v.begin(), v.end());
    const std::vector<float> values = evaluate_points(program, inputs, PointGrid{}, log);
    std::vector<GridResult> results(values.size() / 16);
    for (size_t i = 0; i < results.size(); ++i)
        for (size_t t = 0; t < 4; ++t)
            std::copy_n(values.begin() + std::ptrdiff_t(i * 16 + t * 4), 4, results[i].out[t].begin());
    return results;
}

}  // namespace specbake::gltest
