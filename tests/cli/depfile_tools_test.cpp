// `bake --depfile` read by the real build tools, GNU Make and Ninja, over file names with the characters
// that break dependency files: a second build does nothing, and a newer texture (the only changed input)
// rebuilds. Names neither tool can read back give one clear error before anything is baked. Skipped when
// the tool is not installed. File times are set explicitly, so nothing depends on the clock.
#include "scene_test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <OpenImageIO/imageio.h>

#include <sys/stat.h>

#include <chrono>
#include <cstdlib>

using namespace scene_test;
using nlohmann::json;

namespace {

void write_normals_png(const fs::path& p) {
    fs::create_directories(p.parent_path());
    std::vector<uint8_t> px(4 * 4 * 3);
    for (size_t i = 0; i < px.size(); i += 3) px[i] = uint8_t(100 + i), px[i + 1] = 128, px[i + 2] = 230;
    const std::string tmp = (p.parent_path() / "tmp_normals.png").string();
    auto out = OIIO::ImageOutput::create(tmp);
    ASSERT_TRUE(out);
    ASSERT_TRUE(out->open(tmp, OIIO::ImageSpec(4, 4, 3, OIIO::TypeDesc::UINT8)));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, px.data()));
    out->close();
    fs::rename(tmp, p);
}

// A triangle scene (buffer embedded) whose material's normal texture is `image_uri`.
void write_scene(const fs::path& gltf, const std::string& image_uri) {
    const float data[24] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    const std::string bin(reinterpret_cast<const char*>(data), sizeof data);
    write_bytes(gltf.parent_path() / "tri.bin", bin);
    json j = {
        {"asset", {{"version", "2.0"}}},
        {"scene", 0},
        {"scenes", json::array({{{"nodes", {0}}}})},
        {"nodes", json::array({{{"mesh", 0}}})},
        {"buffers", json::array({{{"byteLength", bin.size()}, {"uri", "tri.bin"}}})},
        {"bufferViews", json::array({{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}},
                                     {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 36}},
                                     {{"buffer", 0}, {"byteOffset", 72}, {"byteLength", 24}}})},
        {"accessors", json::array({{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"},
                                    {"min", {0, 0, 0}}, {"max", {1, 1, 0}}},
                                   {{"bufferView", 1}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}},
                                   {{"bufferView", 2}, {"componentType", 5126}, {"count", 3}, {"type", "VEC2"}}})},
        {"meshes", json::array({{{"primitives", json::array({{{"attributes",
                                                                {{"POSITION", 0}, {"NORMAL", 1}, {"TEXCOORD_0", 2}}},
                                                               {"material", 0}}})}}})},
        {"materials", json::array({{{"pbrMetallicRoughness", {{"roughnessFactor", 0.4}, {"metallicFactor", 0.0}}},
                                    {"normalTexture", {{"index", 0}}}}})},
        {"images", json::array({{{"uri", image_uri}}})},
        {"textures", json::array({{{"source", 0}}})},
    };
    write_bytes(gltf, j.dump(1));
}

// A glTF URI for a file name: every byte outside the unreserved set percent-encoded (RFC 3986).
std::string uri_of(const std::string& name) {
    std::string out;
    for (unsigned char c : name) {
        if (std::isalnum(c) || c == '-' || c == '.' || c == '_' || c == '~') {
            out += char(c);
        } else {
            char hex[4];
            std::snprintf(hex, sizeof hex, "%%%02X", c);
            out += hex;
        }
    }
    return out;
}

bool have(const char* tool) { return std::system((std::string("command -v ") + tool + " > /dev/null 2>&1").c_str()) == 0; }

// Runs a shell command in `dir`; its exit code, and its output in `out`.
int run_in(const fs::path& dir, const std::string& command, std::string* out = nullptr) {
    const fs::path log = dir / "tool.log";
    const int status = std::system(("cd " + quote(dir.string()) + " && " + command + " > " + quote(log.string()) + " 2>&1").c_str());
    if (out) *out = slurp(log);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

void set_mtime(const fs::path& p, fs::file_time_type t) { fs::last_write_time(p, t); }

// Every input a minute old, the manifest half a minute old, then the texture alone made newer than it.
void make_texture_newer(const fs::path& dir, const std::string& texture) {
    const auto base = fs::last_write_time(dir / "out" / "manifest.json") - std::chrono::minutes(1);
    for (const char* input : {"scene.gltf", "tri.bin"}) set_mtime(dir / input, base);
    set_mtime(dir / texture, base);
    set_mtime(dir / "out" / "manifest.json", base + std::chrono::seconds(30));
    set_mtime(dir / texture, base + std::chrono::seconds(45));
}

// Names with every character the issue lists that both tools can read back once escaped.
const std::vector<std::string> kNames = {
    "sp ace.png", "dol$lar.png", "ha#sh.png", "co:lon.png", "back\\slash.png", "n\xc3\xa4me.png",
    "all of $ # : \\ % ( ) ~ ! @ , + { } \xe2\x82\xac.png", "~tilde.png", "two  spaces\\ .png"};

}  // namespace

TEST(DepfileTools, MakeReadsTheDepfileOfEveryExpressibleName) {
    if (!have("make")) GTEST_SKIP() << "GNU Make is not installed";
    for (const std::string& name : kNames) {
        SCOPED_TRACE(name);
        const fs::path dir = temp_dir("depfile_make");
        write_normals_png(dir / name);
        write_scene(dir / "scene.gltf", uri_of(name));
        write_bytes(dir / "Makefile", "out/manifest.json: scene.gltf\n\t" + quote(SPECBAKE_EXE) +
                                          " bake scene.gltf -o out --depfile scene.d\n-include scene.d\n");
        std::string log;
        ASSERT_EQ(run_in(dir, "make", &log), 0) << log;
        ASSERT_TRUE(fs::exists(dir / "scene.d"));
        // A second build has nothing to do.
        EXPECT_EQ(run_in(dir, "make -q", &log), 0) << log << slurp(dir / "scene.d");
        // The texture alone newer than the manifest: Make must know it as a dependency.
        make_texture_newer(dir, name);
        EXPECT_EQ(run_in(dir, "make -q", &log), 1) << "Make did not see the texture: " << log << slurp(dir / "scene.d");
        ASSERT_EQ(run_in(dir, "make", &log), 0) << log;
        EXPECT_EQ(run_in(dir, "make -q", &log), 0) << log;
        fs::remove_all(dir);
    }
}

TEST(DepfileTools, NinjaReadsTheDepfileOfEveryExpressibleName) {
    if (!have("ninja")) GTEST_SKIP() << "Ninja is not installed";
    for (const std::string& name : kNames) {
        SCOPED_TRACE(name);
        const fs::path dir = temp_dir("depfile_ninja");
        write_normals_png(dir / name);
        write_scene(dir / "scene.gltf", uri_of(name));
        std::string exe = SPECBAKE_EXE;
        // The depfile beside the output folder: inside it, it would be refused.
        write_bytes(dir / "build.ninja", "rule bake\n  command = " + exe +
                                             " bake $in -o $outdir --depfile $outdir.d\n  depfile = $outdir.d\n"
                                             "  deps = gcc\nbuild out/manifest.json: bake scene.gltf\n  outdir = out\n");
        std::string log;
        ASSERT_EQ(run_in(dir, "ninja", &log), 0) << log;
        // Ninja read the name back exactly.
        ASSERT_EQ(run_in(dir, "ninja -t deps out/manifest.json", &log), 0) << log;
        EXPECT_NE(log.find("    " + name + "\n"), std::string::npos) << log;
        EXPECT_EQ(log.find("VALID"), log.rfind("VALID")) << log;
        ASSERT_EQ(run_in(dir, "ninja", &log), 0) << log;
        EXPECT_NE(log.find("no work to do"), std::string::npos) << "a second build reruns: " << log;
        make_texture_newer(dir, name);
        ASSERT_EQ(run_in(dir, "ninja -d explain", &log), 0) << log;
        EXPECT_EQ(log.find("no work to do"), std::string::npos) << "Ninja did not see the texture: " << log;
        ASSERT_EQ(run_in(dir, "ninja", &log), 0) << log;
        EXPECT_NE(log.find("no work to do"), std::string::npos) << log;
        fs::remove_all(dir);
    }
}

// Names Ninja ends at (it has no escape for them), that Make reads as syntax, or a line break: one line
// naming the file, exit 1, nothing baked and no depfile.
TEST(DepfileTools, NamesNoDepfileCanHoldAreRefusedBeforeBaking) {
    for (const std::string& name :
         {std::string("se;mi.png"), std::string("pi|pe.png"), std::string("am&p.png"), std::string("quo'te.png"),
          std::string("dq\"te.png"), std::string("st*ar.png"), std::string("qu?es.png"), std::string("ta\tb.png"),
          std::string("new\nline.png"), std::string("eq=x.png"), std::string("br[1].png")}) {
        SCOPED_TRACE(name);
        const fs::path dir = temp_dir("depfile_refused");
        write_normals_png(dir / name);
        write_scene(dir / "scene.gltf", uri_of(name));
        const RunResult r =
            run_specbake({"bake", (dir / "scene.gltf").string(), "-o", (dir / "out").string(), "--depfile",
                          (dir / "scene.d").string()},
                         dir);
        EXPECT_EQ(r.exit_code, 1) << r.err;
        EXPECT_NE(r.err.find("cannot write the path"), std::string::npos) << r.err;
        size_t error_lines = 0;
        for (size_t at = r.err.find("specbake: error:"); at != std::string::npos; at = r.err.find("specbake: error:", at + 1))
            ++error_lines;
        EXPECT_EQ(error_lines, 1u) << r.err;
        EXPECT_EQ(r.err.find("\n", r.err.find("specbake: error:")), r.err.size() - 1) << "the error is one line: " << r.err;
        EXPECT_FALSE(fs::exists(dir / "scene.d"));
        EXPECT_FALSE(fs::exists(dir / "out" / "manifest.json"));
        fs::remove_all(dir);
    }
}
