// (0) The include compiles in both languages through glslangValidator to SPIR-V that spirv-val accepts:
// every cost entry point (each method and each baked-data configuration of the default entry point), the
// minimal examples, and GLSL 3.30. Also checks that the committed specaa.glsl/.hlsl are what the shared
// sources generate, and prints the instruction-count table.
#include "gl/gl_harness.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

namespace specbake::gltest {
namespace {

const std::string kShaders = std::string(SPECBAKE_SOURCE_DIR) + "/shaders";

bool have_tools(std::string& missing) {
    std::string out;
    for (const char* tool : {"glslangValidator", "spirv-val", "spirv-opt", "spirv-dis"})
        if (run_command(std::string("command -v ") + tool, out) != 0) missing += std::string(" ") + tool;
    return missing.empty();
}

#define SPECBAKE_REQUIRE_TOOLS()                                                                          \
    std::string missing_;                                                                                \
    if (!have_tools(missing_)) FAIL() << "missing shader tools (Debian glslang-tools, spirv-tools):" << missing_

TEST(ShaderCompile, GeneratedIncludesMatchSources) {
    std::string out;
    const int status = run_command(std::string("'") + SPECBAKE_CMAKE_COMMAND + "' -DCHECK=ON -P '" + kShaders +
                                       "/generate.cmake'", out);
    EXPECT_EQ(status, 0) << out;
    // All three share the body (the filters, then the glints) byte for byte after their prologues, and both
    // GLSL variants the GLSL macros before it.
    const std::string glsl = read_source_file("shaders/specaa.glsl"), hlsl = read_source_file("shaders/specaa.hlsl"),
                      glsl_es = read_source_file("shaders/specaa_es.glsl");
    const std::string body =
        read_source_file("shaders/src/specaa_body.inc") + read_source_file("shaders/src/specaa_glints.inc");
    const std::string glsl_tail = read_source_file("shaders/src/macros_glsl.inc") + body;
    ASSERT_FALSE(body.empty());
    EXPECT_EQ(glsl.substr(glsl.size() - glsl_tail.size()), glsl_tail);
    EXPECT_EQ(glsl_es.substr(glsl_es.size() - glsl_tail.size()), glsl_tail);
    EXPECT_EQ(hlsl.substr(hlsl.size() - body.size()), body);
}

TEST(ShaderCompile, MinimalExamplesCompileToValidSpirv) {
    SPECBAKE_REQUIRE_TOOLS();
    TempDir dir;
    std::string out;
    const std::string spv = (dir.path() / "x.spv").string();
    EXPECT_EQ(run_command("glslangValidator -G -S frag -I'" + kShaders + "' '" + kShaders +
                              "/examples/minimal.frag' -o '" + spv + "' && spirv-val --target-env opengl4.5 '" + spv + "'",
                          out), 0) << out;
    EXPECT_EQ(run_command("glslangValidator -V -D -e main -S frag -I'" + kShaders + "' '" + kShaders +
                              "/examples/minimal.hlsl' -o '" + spv + "' && spirv-val '" + spv + "'",
                          out), 0) << out;
}

TEST(ShaderCompile, GlslIncludeCompilesAsVersion330) {
    SPECBAKE_REQUIRE_TOOLS();
    TempDir dir;
    const auto path = dir.path() / "v330.frag";
    std::ofstream(path) << "#version 330 core\nuniform sampler2D uKernel;\n#define SPECAA_KERNEL_TEXTURE uKernel\n"
                        << read_source_file("shaders/specaa.glsl")
                        << "in vec3 vNormal;\nin vec2 vUv;\nin vec3 vView;\nout vec4 color;\nvoid main() {\n"
                           "    SpecaaSurface s;\n    s.roughness = 0.2;\n    s.uv = vUv;\n    s.normal = normalize(vNormal);\n"
                           "    s.view = normalize(vView);\n"
                           "    color = vec4(specaa_filtered_roughness(s));\n}\n";
    std::string out;
    EXPECT_EQ(run_command("glslangValidator -S frag '" + path.string() + "'", out), 0) << out;
}

// The diagnostic switches of the default (verify --variant) compile in both languages with the minimal
// examples' bindings, each on its own.
TEST(ShaderCompile, DiagnosticSwitchesCompileToValidSpirvInBothLanguages) {
    SPECBAKE_REQUIRE_TOOLS();
    TempDir dir;
    const std::string spv = (dir.path() / "x.spv").string();
    for (const char* define : {"SPECAA_NO_BAKED_KERNEL", "SPECAA_DEFAULT_D_WEIGHT=0.0", "SPECAA_KERNEL_LOD_BIAS=-1.0",
                               "SPECAA_GATE_PIXEL_KERNEL", "SPECAA_BLEND_FROM_BAKED_SPREAD", "SPECAA_KERNEL_AREA_LOD",
                               "SPECAA_USE_CURVATURE -DSPECAA_PIXEL_KERNEL_MIN", "SPECAA_USE_CURVATURE -DSPECAA_PIXEL_KERNEL_MAX",
                               "SPECAA_USE_CURVATURE -DSPECAA_PIXEL_KERNEL_MEAN", "SPECAA_USE_CURVATURE -DSPECAA_PIXEL_KERNEL_EDGE=0.01",
                               "SPECAA_BLEND_FROM_LARGEST_AXIS", "SPECAA_BLEND_FROM_SPREAD_SIZE",
                               "SPECAA_QUALITY=0 -DSPECAA_TIER_VIEW_TURN", "SPECAA_QUALITY=1 -DSPECAA_TIER_VIEW_TURN"}) {
        std::string out;
        EXPECT_EQ(run_command(std::string("glslangValidator -G -S frag -D") + define + " -I'" + kShaders + "' '" +
                                  kShaders + "/examples/minimal.frag' -o '" + spv +
                                  "' && spirv-val --target-env opengl4.5 '" + spv + "'",
                              out), 0) << define << "\n" << out;
        EXPECT_EQ(run_command(std::string("glslangValidator -V -D -e main -S frag -D") + define + " -I'" + kShaders +
                                  "' '" + kShaders + "/examples/minimal.hlsl' -o '" + spv + "' && spirv-val '" + spv + "'",
                              out), 0) << define << "\n" << out;
    }
}

// With the baked roughness bound the default NDF samples its level of detail (textureQueryLod is GLSL
// 4.00): the include must still compile as GLSL 3.30 with the driver itself, which (unlike
// glslangValidator) holds to the version, and as 4.50; with the kernel mips as well.
TEST(ShaderCompile, DefaultNdfCompilesWithTheDriverAsVersion330And450) {
    SPECBAKE_REQUIRE_GL(ctx);
    for (const char* version : {"#version 330 core\n", "#version 450 core\n"})
        for (const char* binding : {"uniform sampler2D uKernel;\n#define SPECAA_KERNEL_TEXTURE uKernel\n",
                                    "uniform sampler2D uRough;\n#define SPECAA_ROUGHNESS_TEXTURE uRough\n"}) {
        const std::string source =
            std::string(version) + binding +
            read_source_file("shaders/specaa.glsl") +
            "in vec3 vNormal;\nin vec4 vTangent;\nin vec2 vUv;\nin vec3 vH;\nin vec3 vView;\nout vec4 color;\nvoid main() {\n"
            "    SpecaaSurface s;\n    s.roughness = 0.2;\n    s.uv = vUv;\n    s.normal = normalize(vNormal);\n"
            "    s.view = normalize(vView);\n"
            "    s.tangent = vTangent.xyz;\n    s.bitangent = cross(s.normal, vTangent.xyz) * vTangent.w;\n"
            "    vec3 A = specaa_filtered_alpha2_matrix(s);\n"
            "    color = vec4(specaa_default_D(normalize(vH), A, s));\n}\n";
        auto shader = verify::compile_glsl_shader(GL_FRAGMENT_SHADER, source);
        EXPECT_TRUE(shader.ok()) << version << binding << (shader.ok() ? "" : shader.error().message);
    }
}

TEST(ShaderCompile, EveryEntryPointCompilesToValidSpirvInBothLanguages) {
    SPECBAKE_REQUIRE_TOOLS();
    // The script compiles every entry of shaders/cost/ in GLSL and HLSL, optimises with spirv-opt -O,
    // validates with spirv-val and counts instructions; it fails on any error.
    std::string out;
    const int status = run_command("bash '" + kShaders + "/count_instructions.sh'", out);
    EXPECT_EQ(status, 0) << out;
    std::printf("SPIR-V instructions per entry point after spirv-opt -O:\n%s", out.c_str());
    EXPECT_NE(out.find("projected"), std::string::npos) << out;
}

// Instructions inside the functions of the optimised SPIR-V of shaders/cost/entries.frag (GLSL) or
// entries.hlsl (HLSL) compiled with `defines`, counted as shaders/count_instructions.sh counts them; -1 on
// a tool error (the output in `log`).
int cost_entry_instructions(bool hlsl, const std::string& defines, const TempDir& dir, std::string& log) {
    const std::string in = (dir.path() / "in.spv").string(), opt = (dir.path() / "opt.spv").string();
    const std::string compile =
        hlsl ? "glslangValidator -V -D -e main -S frag -I'" + kShaders + "' " + defines + " '" + kShaders + "/cost/entries.hlsl'"
             : "glslangValidator -G -S frag -I'" + kShaders + "' " + defines + " '" + kShaders + "/cost/entries.frag'";
    if (run_command(compile + " -o '" + in + "' && spirv-opt -O '" + in + "' -o '" + opt + "'", log) != 0) return -1;
    std::string text;
    if (run_command("spirv-dis --no-header --raw-id '" + opt + "'", text) != 0) {
        log = text;
        return -1;
    }
    int count = 0;
    bool inside = false;
    std::istringstream lines(text);
    std::string line;
    while (std::getline(lines, line)) {
        if (line.find("OpFunction ") != std::string::npos) inside = true;
        if (inside && line.find("Op") != std::string::npos) ++count;
        if (line.find("OpFunctionEnd") != std::string::npos) inside = false;
    }
    return count;
}

// The fast tier's budget (issue 35): its matrix and NDF (the edge policy included) cost at most 50 SPIR-V
// instructions over an unfiltered shader's GGX(a), with derivatives only and with the baked roughness, in
// both languages.
TEST(ShaderCompile, FastAndBalancedTiersCostAtMost50And150InstructionsOverUnfilteredGgx) {
    SPECBAKE_REQUIRE_TOOLS();
    TempDir dir;
    for (bool hlsl : {false, true}) {
        const char* language = hlsl ? "HLSL" : "GLSL";
        std::string log;
        const int none = cost_entry_instructions(hlsl, "-DSPECAA_COST_NONE_NDF", dir, log);
        ASSERT_GT(none, 0) << language << " unfiltered GGX D: " << log;
        for (const char* binding : {"", "-DSPECAA_COST_TEXTURES -DSPECAA_ROUGHNESS_TEXTURE=uBaked0"}) {
            const int fast = cost_entry_instructions(
                hlsl, std::string("-DSPECAA_COST_DEFAULT_NDF -DSPECAA_QUALITY=0 ") + binding, dir, log);
            ASSERT_GT(fast, 0) << language << " fast tier " << binding << ": " << log;
            EXPECT_LE(fast - none, 50) << language << " fast tier " << binding << ": " << fast << " against " << none;
            const int balanced = cost_entry_instructions(
                hlsl, std::string("-DSPECAA_COST_DEFAULT_NDF -DSPECAA_QUALITY=1 ") + binding, dir, log);
            ASSERT_GT(balanced, 0) << language << " balanced tier " << binding << ": " << log;
            EXPECT_LE(balanced - none, 150) << language << " balanced tier " << binding << ": " << balanced << " against " << none;
            // The reference tier of the same entry costs far more: the count sees the filtering at all.
            const int reference = cost_entry_instructions(
                hlsl, std::string("-DSPECAA_COST_DEFAULT_NDF -DSPECAA_QUALITY=2 ") + binding, dir, log);
            EXPECT_GT(reference - none, 200) << language << " reference tier " << binding << ": " << log;
            std::printf("%s %s: fast tier %d instructions, +%d over GGX(a); balanced tier %d, +%d\n", language,
                        *binding ? "+ baked roughness" : "(derivatives only)", fast, fast - none, balanced, balanced - none);
        }
    }
}

TEST(ShaderCompile, RoughnessTextureWithKernelIsRejected) {
    SPECBAKE_REQUIRE_TOOLS();
    // Binding the baked roughness together with the kernel would count the normal-map variance twice.
    TempDir dir;
    const auto path = dir.path() / "both.frag";
    std::ofstream(path) << "#version 450\nlayout(binding=0) uniform sampler2D a;\nlayout(binding=1) uniform sampler2D b;\n"
                        << "#define SPECAA_ROUGHNESS_TEXTURE a\n#define SPECAA_KERNEL_TEXTURE b\n"
                        << read_source_file("shaders/specaa.glsl") << "void main() {}\n";
    std::string out;
    EXPECT_NE(run_command("glslangValidator -G -S frag '" + path.string() + "' -o '" + (dir.path() / "x.spv").string() + "'", out), 0);
    EXPECT_NE(out.find("bind either the roughness or the kernel"), std::string::npos) << out;
}

// A shader that does not compile and a program that does not link come back as errors carrying the
// driver's log, naming the stage.
TEST(ShaderCompile, CompileAndLinkErrorsCarryTheDriversLog) {
    SPECBAKE_REQUIRE_GL(ctx);
    auto bad = verify::compile_glsl_shader(GL_FRAGMENT_SHADER,
                                        "#version 450 core\nvoid main() { undeclared_name = 1.0; }\n");
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.error().message.find("fragment shader compilation failed: "), std::string::npos);
    EXPECT_NE(bad.error().message.find("undeclared_name"), std::string::npos) << bad.error().message;

    // The fragment shader reads an input the vertex shader never writes: both compile, the link fails.
    auto vertex = verify::compile_glsl_shader(GL_VERTEX_SHADER,
                                           "#version 450 core\nvoid main() { gl_Position = vec4(0.0); }\n");
    auto fragment = verify::compile_glsl_shader(
        GL_FRAGMENT_SHADER,
        "#version 450 core\nlayout(location = 0) in vec4 never_written;\nout vec4 color;\n"
        "void main() { color = never_written; }\n");
    ASSERT_TRUE(vertex.ok()) << vertex.error().message;
    ASSERT_TRUE(fragment.ok()) << fragment.error().message;
    auto linked = verify::link_program(*vertex, *fragment);
    if (linked.ok()) GTEST_SKIP() << "this driver links an unwritten varying; the link-error path is not reached";
    EXPECT_EQ(linked.error().message.rfind("shader link failed: ", 0), 0u) << linked.error().message;
    EXPECT_GT(linked.error().message.size(), std::string("shader link failed: ").size());
}

}  // namespace
}  // namespace specbake::gltest
