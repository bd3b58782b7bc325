// specbake shader: writes the runtime shader include (GLSL, GLSL ES, HLSL or WGSL) that is embedded in the
// executable, byte for byte identical to shaders/specaa.glsl, specaa_es.glsl, specaa.hlsl and specaa.wgsl of the
// source tree.
#include "cli/command.h"

#include "io/files/atomic_write.h"

#include <cstddef>
#include <cstdio>
#include <memory>
#include <string>

namespace specbake::cli {

// Defined in the build-generated shader_embed.cpp (shaders/embed.cmake).
extern const unsigned char kSpecaaGlsl[];
extern const std::size_t kSpecaaGlslSize;
extern const unsigned char kSpecaaGlslEs[];
extern const std::size_t kSpecaaGlslEsSize;
extern const unsigned char kSpecaaHlsl[];
extern const std::size_t kSpecaaHlslSize;
extern const unsigned char kSpecaaWgsl[];
extern const std::size_t kSpecaaWgslSize;

namespace {

struct ShaderOptions {
    std::string lang;
    std::string output;
};

int run_shader(const ShaderOptions& opts) {
    const auto embedded = [](const unsigned char* bytes, std::size_t size) {
        return std::string(reinterpret_cast<const char*>(bytes), size);
    };
    const std::string text = opts.lang == "glsl"      ? embedded(kSpecaaGlsl, kSpecaaGlslSize)
                             : opts.lang == "glsl-es" ? embedded(kSpecaaGlslEs, kSpecaaGlslEsSize)
                             : opts.lang == "wgsl"    ? embedded(kSpecaaWgsl, kSpecaaWgslSize)
                                                      : embedded(kSpecaaHlsl, kSpecaaHlslSize);
    if (opts.output.empty()) {
        if (std::fwrite(text.data(), 1, text.size(), stdout) != text.size() || std::fflush(stdout) != 0) {
            print_error("could not write the shader include to standard output");
            return kExitFailed;
        }
        return kExitOk;
    }
    if (auto written = io::write_file_atomic(opts.output, text); !written) {
        print_error(written.error().message);
        return kExitFailed;
    }
    return kExitOk;
}

}  // namespace

void add_shader_command(CLI::App& app, std::function<int()>& run) {
    auto* sub = app.add_subcommand(
        "shader",
        "Write the runtime shader include (GLSL, GLSL ES, HLSL or WGSL) for specular anti-aliasing in an engine.");
    auto opts = std::make_shared<ShaderOptions>();
    sub->add_option("--lang", opts->lang,
                    "Shading language of the include: glsl (GLSL 3.30+), glsl-es (GLSL ES 3.00+: WebGL 2, "
                    "OpenGL ES 3), hlsl (Shader Model 5+), wgsl (WebGPU: three.js WebGPURenderer, Bevy)")
        ->required()
        ->check(CLI::IsMember({"glsl", "glsl-es", "hlsl", "wgsl"}));
    sub->add_option("-o,--output", opts->output,
                    "Write to FILE (atomically: a temporary file renamed into place) instead of standard output");
    sub->footer(
        "Examples:\n"
        "  specbake shader --lang glsl -o shaders/specaa.glsl\n"
        "  specbake shader --lang hlsl > specaa.hlsl\n"
        "  specbake shader --lang glsl-es -o web/specaa_es.glsl\n"
        "    WebGL 2: no #include there, so concatenate '#version 300 es', your #defines and highp sampler\n"
        "    uniforms, the include's text, then your shader (docs/shader-include.md#webgl-2-and-opengl-es).\n"
        "  specbake shader --lang wgsl -o assets/shaders/specaa.wgsl\n"
        "    WebGPU: the default entry points without baked data and, suffixed _kernel, with the baked Sigma\n"
        "    kernel; to prepend to a WGSL module or give to three.js TSL's wgsl()/wgslFn\n"
        "    (docs/shader-include.md#webgpu-wgsl).\n"
        "\n"
        "Cost tier: #define SPECAA_QUALITY before the include to pick what the default entry points\n"
        "(specaa_filtered_alpha2_matrix, specaa_default_D) cost per light:\n"
        "  SPECAA_QUALITY_FAST (0)       isotropic filtered roughness and two lobes fitted to the footprint's\n"
        "                                convolved NDF with the material's tails: the cheapest; bind the baked\n"
        "                                roughness\n"
        "  SPECAA_QUALITY_BALANCED (1)   the same filtered roughness and the footprint's convolved NDF in closed\n"
        "                                form (no loop); bind the baked roughness\n"
        "  SPECAA_QUALITY_REFERENCE (2)  the default: the anisotropic matrix form and the convolution by quadrature\n"
        "  SPIR-V instructions and accuracy per tier: docs/shader-include.md#quality-tiers.\n"
        "\n"
        "Curvature: where 'specbake bake' wrote the _SPECAA_CURVATURE vertex attribute, #define SPECAA_USE_CURVATURE\n"
        "and pass it: the default rule takes its per-pixel kernel from it (continuous across triangle edges)\n"
        "instead of quad derivatives (docs/shader-include.md#the-default-entry-point).");
    sub->callback([&run, opts] { run = [opts] { return run_shader(*opts); }; });
}

}  // namespace specbake::cli
