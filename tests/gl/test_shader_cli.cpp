// specbake shader: the embedded include is byte-identical to shaders/specaa.glsl, specaa_es.glsl,
// specaa.hlsl and specaa.wgsl, on stdout and with -o (atomic); bad arguments give one error line and a
// non-zero exit without touching files; the help names the cost tiers (SPECAA_QUALITY).
#include "gl/gl_harness.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <iterator>

namespace specbake::gltest {
namespace {

std::string read_all(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(ShaderCli, WritesTheIncludesByteForByte) {
    TempDir dir;
    for (const std::string lang : {"glsl", "glsl-es", "hlsl", "wgsl"}) {
        const std::string expected = read_source_file(lang == "glsl-es" ? "shaders/specaa_es.glsl" : "shaders/specaa." + lang);
        ASSERT_FALSE(expected.empty());
        const auto file = dir.path() / ("specaa." + lang);
        std::string out;
        ASSERT_EQ(run_command(std::string("'") + SPECBAKE_EXE + "' shader --lang " + lang + " -o '" + file.string() + "'", out), 0)
            << out;
        EXPECT_EQ(read_all(file), expected) << lang;
        const auto piped = dir.path() / ("stdout." + lang);
        ASSERT_EQ(run_command(std::string("'") + SPECBAKE_EXE + "' shader --lang " + lang + " > '" + piped.string() + "'", out), 0);
        EXPECT_EQ(read_all(piped), expected) << lang;
    }
    // Only the requested files exist: no temporary file left behind.
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), std::filesystem::directory_iterator()), 8);
}

TEST(ShaderCli, ReplacesAnExistingFileCompletely) {
    TempDir dir;
    const auto file = dir.path() / "specaa.glsl";
    std::ofstream(file) << std::string(200000, 'x');
    std::string out;
    ASSERT_EQ(run_command(std::string("'") + SPECBAKE_EXE + "' shader --lang glsl -o '" + file.string() + "'", out), 0) << out;
    EXPECT_EQ(read_all(file), read_source_file("shaders/specaa.glsl"));
}

// The help says how to pick a cost tier, with the macro names the include defines.
TEST(ShaderCli, HelpNamesTheQualityTiers) {
    std::string out;
    ASSERT_EQ(run_command(std::string("'") + SPECBAKE_EXE + "' shader --help", out), 0) << out;
    const std::string include = read_source_file("shaders/specaa.glsl");
    for (const char* tier : {"SPECAA_QUALITY_FAST (0)", "SPECAA_QUALITY_BALANCED (1)", "SPECAA_QUALITY_REFERENCE (2)"}) {
        EXPECT_NE(out.find(tier), std::string::npos) << tier << "\n" << out;
        EXPECT_NE(include.find(tier), std::string::npos) << tier;
    }
}

TEST(ShaderCli, BadArgumentsFailWithOneLine) {
    TempDir dir;
    std::string out;
    EXPECT_EQ(run_command(std::string("'") + SPECBAKE_EXE + "' shader --lang metal", out), 2) << out;
    EXPECT_NE(out.find("metal"), std::string::npos) << out;
    EXPECT_EQ(run_command(std::string("'") + SPECBAKE_EXE + "' shader", out), 2) << out;
    // The output is an existing folder: an error naming it, exit 1, the folder untouched.
    const auto folder = dir.path() / "out";
    std::filesystem::create_directory(folder);
    EXPECT_EQ(run_command(std::string("'") + SPECBAKE_EXE + "' shader --lang hlsl -o '" + folder.string() + "'", out), 1) << out;
    EXPECT_NE(out.find(folder.string()), std::string::npos) << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
    EXPECT_TRUE(std::filesystem::is_directory(folder));
    EXPECT_TRUE(std::filesystem::is_empty(folder));
}

}  // namespace
}  // namespace specbake::gltest
