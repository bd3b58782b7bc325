// Test harness for the runtime shader include on a real OpenGL implementation: a headless OpenGL 4.5
// core context (EGL surfaceless platform; Mesa llvmpipe in CI), program building from GLSL source or
// SPIR-V, and a grid evaluator that runs one fragment per input case and reads float results back.
#pragma once

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include "verify/gl_context.h"

#include <array>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace specbake::gltest {

// Per-test context. `open()` returns null and sets `reason` when no context can be made; tests call
// SPECBAKE_REQUIRE_GL, which skips when SPECBAKE_NO_GL=1 and fails otherwise.
class GlContext {
public:
    static std::unique_ptr<GlContext> open(std::string& reason);
    ~GlContext();
    GlContext(const GlContext&) = delete;
    GlContext& operator=(const GlContext&) = delete;

    bool has_extension(const char* name) const;
    std::string renderer() const;

private:
    GlContext() = default;
    std::unique_ptr<verify::GlContext> context_;
};

// True when SPECBAKE_NO_GL=1 (GL tests skip instead of failing).
bool gl_disabled();

// Reads a file of the source tree (SPECBAKE_SOURCE_DIR); empty string when missing.
std::string read_source_file(const std::string& relative_path);

// A fresh temporary folder removed with the object.
class TempDir {
public:
    TempDir();
    ~TempDir();
    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
};

// Runs a shell command, returns its exit status and stores stdout+stderr in `output`.
int run_command(const std::string& command, std::string& output);

// Creates and binds a framebuffer with `count` (1-8) RGBA32F colour attachments of `width` x `height`,
// written to `textures`, all set as draw buffers. Returns the framebuffer; the caller deletes both.
GLuint create_float_targets(int count, int width, int height, GLuint* textures);

// Linked program from GLSL sources; 0 and a log on failure.
GLuint build_program_glsl(const std::string& vertex, const std::string& fragment, std::string& log);
// Linked program from SPIR-V binaries (GL_ARB_gl_spirv), entry point "main" in both; 0 and a log on failure.
GLuint build_program_spirv(const std::vector<char>& vertex, const std::vector<char>& fragment, std::string& log);

// Reads a whole binary file (a SPIR-V module); empty when missing.
std::vector<char> read_binary(const std::filesystem::path& path);

// GLSL vertex shader of a point grid: `inputs` vec4 attributes (locations 0 .. inputs-1) forwarded as flat
// varyings vIn0 ..., the cell centre in clip space at location `inputs`, drawn as a `point_size` pixel point.
std::string pass_through_vertex_shader(int inputs, int point_size);
// GLSL fragment interface of a point grid: flat vec4 vIn0 ... (`inputs`), vec4 outputs o0 ... (`outputs`),
// then `void main() { body }`. The caller puts the version, defines and include before it.
std::string glsl_fragment_wrapper(int inputs, int outputs, const std::string& body);
// HLSL counterpart: a struct FragmentOutput of `outputs` float4 SV_Target fields and
// `FragmentOutput main(leading nointerpolation float4 in0 : TEXCOORD0, ...) { FragmentOutput r; body return r; }`;
// `leading` is empty or a parameter followed by ", ".
std::string hlsl_fragment_wrapper(int inputs, int outputs, const std::string& leading, const std::string& body);

// GLSL vertex source compiled to SPIR-V by glslangValidator (-G) at `path` + ".spv"; empty and a log on failure.
std::vector<char> compile_vertex_spirv(const std::string& source, const std::filesystem::path& path, std::string& log);
// HLSL fragment source written to `stem` + ".hlsl", compiled to SPIR-V (glslangValidator -D, spirv-val) and linked
// with `vertex` through GL_ARB_gl_spirv; 0 and a log on failure.
GLuint build_program_hlsl_spirv(const std::vector<char>& vertex, const std::string& source,
                                const std::filesystem::path& stem, std::string& log);

// A grid of point cells: each case is one `cell` x `cell` point with `inputs` vec4 attributes, in rows of
// width / cell cells, writing `outputs` (1-8) vec4 targets read back from RGBA32F attachments.
struct PointGrid {
    int inputs = 6;
    int outputs = 4;
    int width = 256;  // pixels
    int cell = 1;     // pixels per side of a case
};
// Framebuffer height in pixels for `count` cases.
int point_grid_height(const PointGrid& grid, size_t count);
// Draws `inputs.size() / (4 * grid.inputs)` cases with `program` (pass_through_vertex_shader(grid.inputs, grid.cell))
// and returns, per case, the `4 * grid.outputs` values of its lower-left pixel. Empty on a GL error (message in `log`).
std::vector<float> evaluate_points(GLuint program, const std::vector<float>& inputs, const PointGrid& grid, std::string& log);

// Grid evaluation: case i is one point-sized fragment at pixel i with six flat vec4 inputs
// (locations 0-5) and four vec4 outputs (locations 0-3) read back from RGBA32F attachments.
using Vec4 = std::array<float, 4>;
struct GridCase {
    std::array<Vec4, 6> in{};
};
struct GridResult {
    std::array<Vec4, 4> out{};
};

// The GLSL vertex shader that places case i at pixel i and forwards its inputs as flat varyings.
std::string grid_vertex_shader();
// The GLSL fragment wrapper around `specaa.glsl` + `tests/gl/shaders/grid_eval.inc` for one test case.
std::string grid_fragment_glsl(const std::string& test_case);
// Same for HLSL (glslangValidator -D input).
std::string grid_fragment_hlsl(const std::string& test_case);

// Draws all cases with `program` and returns their outputs. Empty on a GL error (message in `log`).
std::vector<GridResult> evaluate_grid(GLuint program, const std::vector<GridCase>& cases, std::string& log);

}  // namespace specbake::gltest

// Skips (SPECBAKE_NO_GL=1) or fails with the reason when no OpenGL context can be created.
#define SPECBAKE_REQUIRE_GL(ctx)                                                                           \
    if (::specbake::gltest::gl_disabled()) GTEST_SKIP() << "SPECBAKE_NO_GL=1: OpenGL tests disabled";      \
    std::string gl_reason_;                                                                                \
    auto ctx = ::specbake::gltest::GlContext::open(gl_reason_);                                            \
    if (!ctx) FAIL() << "no headless OpenGL 4.5 context (set SPECBAKE_NO_GL=1 to skip): " << gl_reason_
