// What a build farm needs from `bake` and its siblings, each reproduced here from inputs built on the spot:
// every input failure fails the build and nothing skipped is recorded as up to date (issue 37, item 1);
// only regular files are read or replaced, and a depfile never lands on an input or inside the output
// folder (item 2). Every run is under `timeout`, so a hang fails the test instead of stalling it.
#include "scene_test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <OpenImageIO/imageio.h>

#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdlib>
#include <set>

using namespace scene_test;
using nlohmann::json;

namespace {

// An 8x8 RGB normal map whose normals tilt in a checkerboard: on a glossy material its filtered roughness
// differs from the material's, so the bake writes textures. Written by OpenImageIO, as PNG or JPEG by the
// extension of `p`.
void write_bumpy_normals(const fs::path& p) {
    fs::create_directories(p.parent_path());
    std::vector<uint8_t> px(8 * 8 * 3);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            uint8_t* t = &px[size_t(y * 8 + x) * 3];
            t[0] = (x + y) % 2 ? 200 : 56;
            t[1] = y % 2 ? 190 : 66;
            t[2] = 200;
        }
    const std::string tmp = (p.parent_path() / ("tmp_" + std::to_string(::getpid()) + p.extension().string())).string();
    auto out = OIIO::ImageOutput::create(tmp);
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(8, 8, 3, OIIO::TypeDesc::UINT8);
    ASSERT_TRUE(out->open(tmp, spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, px.data()));
    out->close();
    fs::rename(tmp, p);
}

// A size x size RGB PNG of pseudo-random normals: enough texels that the bake's parallel loops use every
// thread they are given.
void write_noisy_normals(const fs::path& p, int size) {
    std::vector<uint8_t> px(size_t(size) * size_t(size) * 3);
    uint32_t state = 12345;
    for (size_t i = 0; i < px.size(); i += 3) {
        state = state * 1664525u + 1013904223u;
        px[i] = uint8_t(40 + (state >> 24) % 176);
        px[i + 1] = uint8_t(40 + (state >> 16 & 0xFF) % 176);
        px[i + 2] = 200;
    }
    const std::string tmp = (p.parent_path() / "tmp_noisy.png").string();
    auto out = OIIO::ImageOutput::create(tmp);
    ASSERT_TRUE(out);
    ASSERT_TRUE(out->open(tmp, OIIO::ImageSpec(size, size, 3, OIIO::TypeDesc::UINT8)));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, px.data()));
    out->close();
    fs::rename(tmp, p);
}

// One triangle (positions, normals, UVs in t.bin beside it) whose glossy material has the normal texture
// `image_uri`.
void write_triangle_scene(const fs::path& gltf, const std::string& image_uri) {
    const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const float nrm[9] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    const float uv[6] = {0, 0, 1, 0, 0, 1};
    std::string data(reinterpret_cast<const char*>(pos), 36);
    data += std::string(reinterpret_cast<const char*>(nrm), 36);
    data += std::string(reinterpret_cast<const char*>(uv), 24);
    write_bytes(gltf.parent_path() / (gltf.stem().string() + ".bin"), data);
    json j = {
        {"asset", {{"version", "2.0"}}},
        {"scene", 0},
        {"scenes", json::array({{{"nodes", {0}}}})},
        {"nodes", json::array({{{"mesh", 0}}})},
        {"buffers", json::array({{{"byteLength", data.size()}, {"uri", gltf.stem().string() + ".bin"}}})},
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
        {"materials", json::array({{{"name", "Glossy"},
                                    {"pbrMetallicRoughness", {{"roughnessFactor", 0.05}, {"metallicFactor", 0.0}}},
                                    {"normalTexture", {{"index", 0}}}}})},
        {"images", json::array({{{"uri", image_uri}}})},
        {"textures", json::array({{{"source", 0}}})},
    };
    write_bytes(gltf, j.dump(1));
}

// Runs `[env] specbake <args>` under `timeout` (a hang is killed after 60 s and reported as exit 124/137).
RunResult run_bounded(const std::vector<std::string>& args, const fs::path& dir, const std::string& env = "") {
    std::string cmd = env + (env.empty() ? "" : " ") + "timeout -k 5 60 " + quote(SPECBAKE_EXE);
    for (const std::string& a : args) cmd += " " + quote(a);
    const fs::path out = dir / "stdout.txt", err = dir / "stderr.txt";
    cmd += " < /dev/null > " + quote(out.string()) + " 2> " + quote(err.string());
    const int status = std::system(cmd.c_str());
    RunResult r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.signaled = WIFSIGNALED(status) || r.exit_code == 124 || r.exit_code == 137 || r.exit_code > 128;
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
}

std::vector<std::string> lines_of(const std::string& text) {
    std::vector<std::string> lines;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
}

// The one line of `err` naming all of `words`, or "".
std::string line_naming(const std::string& err, const std::vector<std::string>& words) {
    for (const std::string& line : lines_of(err)) {
        bool all = true;
        for (const std::string& w : words) all = all && line.find(w) != std::string::npos;
        if (all) return line;
    }
    return {};
}

json read_json(const fs::path& p) { return json::parse(slurp(p)); }

// Kinds of the outputs a manifest lists.
std::set<std::string> output_kinds(const fs::path& manifest) {
    std::set<std::string> kinds;
    const json m = read_json(manifest);
    for (const json& o : m["outputs"]) kinds.insert(o["kind"].get<std::string>());
    return kinds;
}

bool is_named_pipe(const fs::path& p) {
    struct stat st {};
    return ::lstat(p.c_str(), &st) == 0 && S_ISFIFO(st.st_mode);
}

}  // namespace

// The reference: the bumpy normal map bakes textures, so the failures below are failures of the input.
TEST(FarmInputFailures, AReadableNormalMapBakesTextures) {
    const fs::path dir = temp_dir("farm_ok");
    write_bumpy_normals(dir / "n.png");
    write_triangle_scene(dir / "s.gltf", "n.png");
    const RunResult r = run_bounded({"bake", (dir / "s.gltf").string(), "-o", (dir / "out").string()}, dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(output_kinds(dir / "out" / "manifest.json").count("roughness")) << slurp(dir / "out" / "manifest.json");
    fs::remove_all(dir);
}

// An image the material needs that cannot be read fails the bake with one line naming the scene, the
// material and the file; no manifest is written, and once the cause is fixed the next run bakes.
TEST(FarmInputFailures, EveryUnreadableNormalMapFailsTheBakeAndTheFixedRunBakes) {
    struct Case {
        const char* name;
        std::function<void(const fs::path&)> make_bad;
        std::vector<std::string> extra_args;
        std::string env;
    };
    const std::vector<Case> cases = {
        {"lfs", [](const fs::path& p) {
             write_bytes(p, "version https://git-lfs.github.com/spec/v1\noid sha256:"
                            "4d7a214614ab2935c943f9e0ff69d22eadbb8f32b1258daaa5e2ca24d17e2393\nsize 12345\n");
         }, {}, ""},
        {"truncated", [](const fs::path& p) {
             write_bumpy_normals(p);
             const std::string png = slurp(p);
             write_bytes(p, png.substr(0, png.size() / 2));
         }, {}, ""},
        {"empty", [](const fs::path& p) { write_bytes(p, ""); }, {}, ""},
        {"limit", [](const fs::path& p) { write_bumpy_normals(p); }, {"--limit", "texels=16"}, ""},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const fs::path dir = temp_dir(std::string("farm_bad_") + c.name);
        c.make_bad(dir / "n.png");
        write_triangle_scene(dir / "s.gltf", "n.png");
        std::vector<std::string> args{"bake", (dir / "s.gltf").string(), "-o", (dir / "out").string()};
        args.insert(args.end(), c.extra_args.begin(), c.extra_args.end());
        const RunResult bad = run_bounded(args, dir, c.env);
        EXPECT_FALSE(bad.signaled) << bad.err;
        EXPECT_EQ(bad.exit_code, 1) << bad.err;
        EXPECT_NE(line_naming(bad.err, {"error", "s.gltf", "material 0 'Glossy'", "n.png"}), "") << bad.err;
        EXPECT_FALSE(fs::exists(dir / "out" / "manifest.json")) << "a failed scene records nothing";
        // Fixed: a readable image, no lowered limit.
        write_bumpy_normals(dir / "n.png");
        const RunResult fixed = run_bounded({"bake", (dir / "s.gltf").string(), "-o", (dir / "out").string()}, dir);
        EXPECT_EQ(fixed.exit_code, 0) << fixed.err;
        EXPECT_EQ(fixed.out.find("up to date"), std::string::npos) << fixed.out;
        ASSERT_TRUE(fs::exists(dir / "out" / "manifest.json"));
        EXPECT_TRUE(output_kinds(dir / "out" / "manifest.json").count("roughness"));
        fs::remove_all(dir);
    }
}

// A JPEG normal map with the OpenImageIO module missing: the JPEG cannot be decoded, so the bake fails;
// with the module found again the same, unchanged inputs bake.
TEST(FarmInputFailures, JpegWithoutTheImageModuleFailsAndBakesOnceItIsFound) {
    const fs::path dir = temp_dir("farm_jpeg");
    write_bumpy_normals(dir / "n.jpg");
    write_triangle_scene(dir / "s.gltf", "n.jpg");
    const std::vector<std::string> args{"bake", (dir / "s.gltf").string(), "-o", (dir / "out").string()};
    const RunResult bad = run_bounded(args, dir, "SPECBAKE_OIIO_MODULE=" + quote((dir / "no_such_module.so").string()));
    EXPECT_EQ(bad.exit_code, 1) << bad.err;
    EXPECT_NE(line_naming(bad.err, {"error", "s.gltf", "material 0 'Glossy'", "n.jpg"}), "") << bad.err;
    EXPECT_FALSE(fs::exists(dir / "out" / "manifest.json"));
    const RunResult fixed = run_bounded(args, dir);
    EXPECT_EQ(fixed.exit_code, 0) << fixed.err;
    EXPECT_EQ(fixed.out.find("up to date"), std::string::npos) << fixed.out;
    EXPECT_TRUE(output_kinds(dir / "out" / "manifest.json").count("roughness"));
    fs::remove_all(dir);
}

// Opting in turns the failure into a warning for a batch; the manifest says what was skipped, so the next
// run is never "up to date" and bakes once the image is readable.
TEST(FarmInputFailures, AllowingUnreadableTexturesWarnsAndNeverRecordsUpToDate) {
    const fs::path dir = temp_dir("farm_allow");
    write_bytes(dir / "n.png", "");
    write_triangle_scene(dir / "s.gltf", "n.png");
    std::vector<std::string> args{"bake", (dir / "s.gltf").string(), "-o", (dir / "out").string(),
                                  "--allow-unreadable-textures"};
    const RunResult warned = run_bounded(args, dir);
    EXPECT_EQ(warned.exit_code, 0) << warned.err;
    EXPECT_NE(line_naming(warned.err, {"warning", "s.gltf", "material 0 'Glossy'", "n.png"}), "") << warned.err;
    const json manifest = read_json(dir / "out" / "manifest.json");
    ASSERT_TRUE(manifest.contains("skipped"));
    EXPECT_EQ(manifest["skipped"].size(), 1u);
    const RunResult again = run_bounded(args, dir);
    EXPECT_EQ(again.exit_code, 0) << again.err;
    EXPECT_EQ(again.out.find("up to date"), std::string::npos) << "a bake that skipped an input is never up to date";
    write_bumpy_normals(dir / "n.png");
    const RunResult fixed = run_bounded(args, dir);
    EXPECT_EQ(fixed.exit_code, 0) << fixed.err;
    EXPECT_FALSE(read_json(dir / "out" / "manifest.json").contains("skipped"));
    EXPECT_TRUE(output_kinds(dir / "out" / "manifest.json").count("roughness"));
    // Now complete: the next run is up to date.
    const RunResult fresh = run_bounded(args, dir);
    EXPECT_NE(fresh.out.find("up to date"), std::string::npos) << fresh.out << fresh.err;
    fs::remove_all(dir);
}

// FIFOs, character devices and sockets are refused by every reader with an error saying what they are,
// instead of blocking on them.
TEST(FarmSpecialFiles, FifosDevicesAndSocketsAreRefusedWithoutHanging) {
    const fs::path dir = temp_dir("farm_fifo");
    ASSERT_EQ(::mkfifo((dir / "n.png").c_str(), 0644), 0);
    write_triangle_scene(dir / "s.gltf", "n.png");
    for (const char* command : {"bake", "plan"}) {
        SCOPED_TRACE(command);
        std::vector<std::string> args{command, (dir / "s.gltf").string()};
        if (std::string(command) == "bake") args.insert(args.end(), {"-o", (dir / "out").string()});
        const RunResult r = run_bounded(args, dir);
        EXPECT_FALSE(r.signaled) << "hung or crashed: " << r.err;
        EXPECT_NE(r.exit_code, 0);
        EXPECT_NE(line_naming(r.err, {"n.png", "FIFO"}), "") << r.err;
    }
    const RunResult t = run_bounded({"texture", "--normal", (dir / "n.png").string(), "-o", (dir / "t").string()}, dir);
    EXPECT_FALSE(t.signaled) << t.err;
    EXPECT_NE(t.exit_code, 0);
    EXPECT_NE(line_naming(t.err, {"n.png", "FIFO"}), "") << t.err;
    const RunResult i = run_bounded({"inspect", (dir / "n.png").string()}, dir);
    EXPECT_FALSE(i.signaled) << i.err;
    EXPECT_NE(i.exit_code, 0);
    EXPECT_NE(line_naming(i.err, {"n.png", "FIFO"}), "") << i.err;

    // A Unix socket in place of the normal map.
    const fs::path sock = dir / "sock.png";
    const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
    ASSERT_GE(fd, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    ASSERT_LT(sock.string().size(), sizeof addr.sun_path);
    std::strcpy(addr.sun_path, sock.c_str());
    ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
    const RunResult s = run_bounded({"texture", "--normal", sock.string(), "-o", (dir / "t").string()}, dir);
    ::close(fd);
    EXPECT_NE(s.exit_code, 0);
    EXPECT_NE(line_naming(s.err, {"sock.png", "socket"}), "") << s.err;

    // A character device inside the scene folder (mknod needs the privilege; skipped without it).
    write_triangle_scene(dir / "d.gltf", "dev.png");
    if (::mknod((dir / "dev.png").c_str(), S_IFCHR | 0644, makedev(1, 5)) == 0) {  // /dev/zero: never ends
        const RunResult d = run_bounded({"plan", (dir / "d.gltf").string()}, dir);
        EXPECT_FALSE(d.signaled) << d.err;
        EXPECT_NE(line_naming(d.err, {"dev.png", "character device"}), "") << d.err;
    }
    fs::remove_all(dir);
}

// `inspect --check` of a folder where a FIFO stands in place of an output reports it, without hanging.
TEST(FarmSpecialFiles, InspectCheckReportsAFifoInPlaceOfAnOutput) {
    const fs::path dir = temp_dir("farm_check_fifo");
    write_bumpy_normals(dir / "n.png");
    write_triangle_scene(dir / "s.gltf", "n.png");
    ASSERT_EQ(run_bounded({"bake", (dir / "s.gltf").string(), "-o", (dir / "out").string()}, dir).exit_code, 0);
    std::string texture;
    const json m = read_json(dir / "out" / "manifest.json");
    for (const json& o : m["outputs"])
        if (o["kind"] == "roughness") texture = o["path"];
    ASSERT_FALSE(texture.empty());
    fs::remove(dir / "out" / texture);
    ASSERT_EQ(::mkfifo((dir / "out" / texture).c_str(), 0644), 0);
    const RunResult c = run_bounded({"inspect", "--check", (dir / "out").string()}, dir);
    EXPECT_FALSE(c.signaled) << c.err;
    EXPECT_NE(c.exit_code, 0);
    EXPECT_NE((c.out + c.err).find("FIFO"), std::string::npos) << c.out << c.err;
    const RunResult i = run_bounded({"inspect", (dir / "out" / texture).string()}, dir);
    EXPECT_FALSE(i.signaled) << i.err;
    EXPECT_NE(i.exit_code, 0);
    fs::remove_all(dir);
}

// Outputs, depfiles and `shader -o` replace regular files only: a FIFO, device or symbolic link there is
// an error and stays as it was.
TEST(FarmSpecialFiles, OnlyRegularFilesAreReplaced) {
    const fs::path dir = temp_dir("farm_replace");
    write_bumpy_normals(dir / "n.png");
    write_triangle_scene(dir / "s.gltf", "n.png");
    ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0644), 0);
    const RunResult shader = run_bounded({"shader", "--lang", "glsl", "-o", (dir / "fifo").string()}, dir);
    EXPECT_NE(shader.exit_code, 0);
    EXPECT_NE(line_naming(shader.err, {"fifo", "FIFO"}), "") << shader.err;
    EXPECT_TRUE(is_named_pipe(dir / "fifo"));

    const RunResult dep = run_bounded(
        {"bake", (dir / "s.gltf").string(), "-o", (dir / "out").string(), "--depfile", (dir / "fifo").string()}, dir);
    EXPECT_NE(dep.exit_code, 0);
    EXPECT_NE(line_naming(dep.err, {"fifo", "FIFO"}), "") << dep.err;
    EXPECT_TRUE(is_named_pipe(dir / "fifo"));
    EXPECT_FALSE(fs::exists(dir / "out" / "manifest.json")) << "refused before anything runs";

    write_bytes(dir / "target.d", "kept");
    fs::create_symlink(dir / "target.d", dir / "link.d");
    const RunResult link = run_bounded(
        {"bake", (dir / "s.gltf").string(), "-o", (dir / "out").string(), "--depfile", (dir / "link.d").string()}, dir);
    EXPECT_NE(link.exit_code, 0);
    EXPECT_NE(line_naming(link.err, {"link.d", "symbolic link"}), "") << link.err;
    EXPECT_TRUE(fs::is_symlink(dir / "link.d"));
    EXPECT_EQ(slurp(dir / "target.d"), "kept");

    // A FIFO where the bake would put its scene, in a folder without a manifest: even --force, which
    // replaces files no manifest lists, replaces regular files only.
    fs::create_directories(dir / "out2");
    ASSERT_EQ(::mkfifo((dir / "out2" / "s.gltf").c_str(), 0644), 0);
    const RunResult out =
        run_bounded({"bake", (dir / "s.gltf").string(), "-o", (dir / "out2").string(), "--force"}, dir);
    EXPECT_FALSE(out.signaled) << out.err;
    EXPECT_NE(out.exit_code, 0);
    EXPECT_NE(line_naming(out.err, {"s.gltf", "FIFO"}), "") << out.err;
    EXPECT_TRUE(is_named_pipe(dir / "out2" / "s.gltf"));
    fs::remove_all(dir);
}

// A depfile path that is an input (given, or found in the scene) or lies inside the output folder is
// refused before anything is baked; the input and the folder stay as they were.
TEST(FarmSpecialFiles, DepfileOnAnInputOrInsideTheOutputFolderIsRefused) {
    const fs::path dir = temp_dir("farm_depfile_input");
    write_bumpy_normals(dir / "n.png");
    write_triangle_scene(dir / "s.gltf", "n.png");
    const std::string texture = slurp(dir / "n.png"), scene = slurp(dir / "s.gltf");
    for (const fs::path& depfile : {dir / "n.png", dir / "s.gltf", dir / "." / "n.png"}) {
        SCOPED_TRACE(depfile.string());
        const RunResult r = run_bounded(
            {"bake", (dir / "s.gltf").string(), "-o", (dir / "out").string(), "--depfile", depfile.string()}, dir);
        EXPECT_EQ(r.exit_code, 1) << r.err;
        EXPECT_NE(line_naming(r.err, {"--depfile", "input"}), "") << r.err;
        EXPECT_EQ(slurp(dir / "n.png"), texture);
        EXPECT_EQ(slurp(dir / "s.gltf"), scene);
        EXPECT_FALSE(fs::exists(dir / "out" / "manifest.json"));
    }
    ASSERT_EQ(run_bounded({"bake", (dir / "s.gltf").string(), "-o", (dir / "out").string()}, dir).exit_code, 0);
    const std::string manifest = slurp(dir / "out" / "manifest.json");
    for (const fs::path& depfile : {dir / "out" / "manifest.json", dir / "out" / "sub" / "x.d"}) {
        const RunResult r = run_bounded({"bake", (dir / "s.gltf").string(), "-o", (dir / "out").string(), "--force",
                                         "--depfile", depfile.string()},
                                        dir);
        EXPECT_EQ(r.exit_code, 1) << r.err;
        EXPECT_NE(line_naming(r.err, {"--depfile", "inside the output folder"}), "") << r.err;
        EXPECT_EQ(slurp(dir / "out" / "manifest.json"), manifest);
    }
    // The folder is still usable.
    const RunResult again = run_bounded({"bake", (dir / "s.gltf").string(), "-o", (dir / "out").string()}, dir);
    EXPECT_EQ(again.exit_code, 0) << again.err;
    fs::remove_all(dir);
}

// The manifest records inputs relative to the output folder: the same bake from another working folder,
// with ./, without it or with absolute paths gives byte for byte the same manifest and is up to date.
TEST(FarmManifestPaths, TheSameBakeFromAnyWorkingFolderOrSpellingGivesTheSameManifest) {
    const fs::path dir = temp_dir("farm_paths");
    write_bumpy_normals(dir / "a" / "n.png");
    write_triangle_scene(dir / "a" / "x.gltf", "n.png");
    const std::string in_dir = "cd " + quote(dir.string()) + " &&";
    const std::string in_a = "cd " + quote((dir / "a").string()) + " &&";
    const RunResult first = run_bounded({"bake", "a/x.gltf", "-o", "out"}, dir, in_dir);
    ASSERT_EQ(first.exit_code, 0) << first.err;
    const std::string manifest = slurp(dir / "out" / "manifest.json");
    EXPECT_EQ(manifest.find(dir.string()), std::string::npos) << "no absolute path: " << manifest;
    const json m = json::parse(manifest);
    std::set<std::string> inputs;
    for (const json& in : m["inputs"]) inputs.insert(in["path"].get<std::string>());
    EXPECT_EQ(inputs, (std::set<std::string>{"../a/x.gltf", "../a/x.bin", "../a/n.png"})) << m["inputs"].dump();

    // Other spellings, other working folders: up to date, nothing rewritten.
    const std::vector<std::pair<std::vector<std::string>, std::string>> runs = {
        {{"bake", "./a/x.gltf", "-o", "./out/"}, in_dir},
        {{"bake", "x.gltf", "-o", "../out"}, in_a},
        {{"bake", "./x.gltf", "-o", (dir / "out").string()}, in_a},
        {{"bake", (dir / "a" / "x.gltf").string(), "-o", (dir / "out").string()}, "cd / &&"},
    };
    for (const auto& [args, where] : runs) {
        SCOPED_TRACE(args[1] + " from " + where);
        const RunResult r = run_bounded(args, dir, where);
        EXPECT_EQ(r.exit_code, 0) << r.err;
        EXPECT_NE(r.out.find("up to date"), std::string::npos) << r.out << r.err;
        EXPECT_EQ(slurp(dir / "out" / "manifest.json"), manifest);
    }
    // Baked again (forced, or into an empty folder) under each spelling: the same bytes.
    for (const auto& [args, where] : runs) {
        SCOPED_TRACE(args[1] + " from " + where + ", forced");
        std::vector<std::string> forced = args;
        forced.push_back("--force");
        const RunResult r = run_bounded(forced, dir, where);
        EXPECT_EQ(r.exit_code, 0) << r.err;
        EXPECT_EQ(slurp(dir / "out" / "manifest.json"), manifest);
    }
    fs::remove_all(dir / "out");
    const RunResult absolute = run_bounded({"bake", (dir / "a" / "x.gltf").string(), "-o", (dir / "out").string()}, dir, "cd / &&");
    EXPECT_EQ(absolute.exit_code, 0) << absolute.err;
    EXPECT_EQ(slurp(dir / "out" / "manifest.json"), manifest);
    fs::remove_all(dir);
}

namespace {

// Runs a shell command line (specbake as $SPECBAKE) with stderr captured; the exit code.
int run_shell(const std::string& line, const fs::path& dir, std::string* err = nullptr) {
    const fs::path e = dir / "shell_err.txt";
    const std::string cmd = "export SPECBAKE=" + quote(SPECBAKE_EXE) + "; cd " + quote(dir.string()) + " && timeout -k 5 60 " +
                            line + " 2> " + quote(e.string());
    const int status = std::system(("bash -c " + quote(cmd)).c_str());
    if (err) *err = slurp(e);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

// One exit-code table for every command: 1 for an input that cannot be read (missing included), 2 for a
// bad command line.
TEST(FarmExitCodes, AMissingInputIsOneAndABadOptionTwoForEveryCommand) {
    const fs::path dir = temp_dir("farm_exit");
    const std::string missing = (dir / "missing.gltf").string();
    const std::vector<std::vector<std::string>> missing_runs = {
        {"bake", missing, "-o", (dir / "o1").string()},
        {"mesh", missing, "-o", (dir / "o2").string()},
        {"plan", missing},
        {"texture", "--normal", (dir / "missing.png").string(), "-o", (dir / "o3").string()},
        {"inspect", (dir / "missing.png").string()},
        {"inspect", "--check", (dir / "missing.png").string()},
        {"verify", missing},
        {"bench", "--no-builtin", "--no-corpus", missing},
        {"view", missing, "--port", "0"},
    };
    for (const auto& args : missing_runs) {
        SCOPED_TRACE(args[0] + " " + args[1]);
        const RunResult r = run_bounded(args, dir);
        EXPECT_EQ(r.exit_code, 1) << r.err;
        EXPECT_NE(line_naming(r.err, {"error", "missing.", "no such file"}), "") << r.err;
    }
    for (const char* command :
         {"bake", "mesh", "plan", "texture", "inspect", "shader", "filter", "glints", "verify", "bench", "view"}) {
        SCOPED_TRACE(command);
        const RunResult r = run_bounded({command, "--no-such-option"}, dir);
        EXPECT_EQ(r.exit_code, 2) << r.err;
    }
    fs::remove_all(dir);
}

// What a command prints must arrive: standard output on a full device fails the run.
TEST(FarmExitCodes, WriteErrorsOnStandardOutputFailTheRun) {
    const fs::path dir = temp_dir("farm_full");
    if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
    write_bumpy_normals(dir / "n.png");
    write_triangle_scene(dir / "s.gltf", "n.png");
    for (const std::string& line : {std::string("\"$SPECBAKE\" plan s.gltf"), std::string("\"$SPECBAKE\" plan --json s.gltf"),
                                    std::string("\"$SPECBAKE\" inspect --json n.png"), std::string("\"$SPECBAKE\" filter --json"),
                                    std::string("\"$SPECBAKE\" shader --lang glsl")}) {
        SCOPED_TRACE(line);
        std::string err;
        ASSERT_EQ(run_shell(line + " > /dev/null", dir, &err), 0) << err;
        EXPECT_EQ(run_shell(line + " > /dev/full", dir, &err), 1) << err;
        EXPECT_NE(err.find("standard output"), std::string::npos) << err;
    }
    fs::remove_all(dir);
}

// A thread count the system cannot give falls back to the threads it can: no abort, outputs as usual.
TEST(FarmExitCodes, ThreadsThatCannotBeCreatedFallBack) {
    if (kAddressSanitizer) GTEST_SKIP() << "AddressSanitizer reserves more address space than the limit below";
    const fs::path dir = temp_dir("farm_threads");
    write_bumpy_normals(dir / "n.png");
    write_triangle_scene(dir / "s.gltf", "n.png");
    const RunResult many = run_bounded({"bake", "-j", "20000", (dir / "s.gltf").string(), "-o", (dir / "a").string()}, dir);
    EXPECT_FALSE(many.signaled) << many.err;
    EXPECT_EQ(many.exit_code, 0) << many.err;
    EXPECT_TRUE(fs::exists(dir / "a" / "manifest.json"));
    // Under an address-space limit each thread's stack must fit: only some of the 200 can start, and a
    // 512^2 map keeps them all busy (the pool used to abort on the first it could not create).
    write_noisy_normals(dir / "big.png", 512);
    write_triangle_scene(dir / "big.gltf", "big.png");
    std::string err;
    const int limited =
        run_shell("bash -c 'ulimit -v 600000; exec \"$0\" \"$@\"' \"$SPECBAKE\" bake -j 200 big.gltf -o b", dir, &err);
    EXPECT_EQ(limited, 0) << err;
    EXPECT_TRUE(fs::exists(dir / "b" / "manifest.json")) << err;
    for (const auto& e : fs::directory_iterator(dir / "b"))
        EXPECT_EQ(e.path().filename().string().rfind(".specbake", 0), std::string::npos) << "left behind: " << e.path();
    fs::remove_all(dir);
}

// A batch reports a missing scene and bakes the others; a scene listed twice (any spelling) is baked once.
TEST(FarmBatches, AMissingSceneFailsAloneAndADuplicateIsBakedOnce) {
    const fs::path dir = temp_dir("farm_batch");
    write_bumpy_normals(dir / "n.png");
    write_triangle_scene(dir / "a.gltf", "n.png");
    write_triangle_scene(dir / "b.gltf", "n.png");
    const RunResult r = run_bounded({"bake", (dir / "a.gltf").string(), (dir / "missing.gltf").string(),
                                     (dir / "b.gltf").string(), "-o", (dir / "out").string()},
                                    dir);
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(line_naming(r.err, {"error", "missing.gltf", "no such file"}), "") << r.err;
    EXPECT_TRUE(fs::exists(dir / "out" / "a" / "a.gltf"));
    EXPECT_TRUE(fs::exists(dir / "out" / "b" / "b.gltf"));
    const RunResult twice = run_bounded({"bake", (dir / "a.gltf").string(), (dir / "." / "a.gltf").string(),
                                         (dir / "a.gltf").string(), "-o", (dir / "twice").string()},
                                        dir);
    EXPECT_EQ(twice.exit_code, 0) << twice.err;
    const json m = read_json(dir / "twice" / "manifest.json");
    EXPECT_EQ(m["plan"].size(), 1u) << m["plan"].dump();
    EXPECT_TRUE(fs::exists(dir / "twice" / "a.gltf")) << "one scene: written directly into the folder";
    fs::remove_all(dir);
}

// A symbolic link loop is reported as one, not as a missing file.
TEST(FarmSpecialFiles, SymlinkLoopsAreReportedAsSuch) {
    const fs::path dir = temp_dir("farm_loop");
    fs::create_symlink(dir / "loop_b.gltf", dir / "loop_a.gltf");
    fs::create_symlink(dir / "loop_a.gltf", dir / "loop_b.gltf");
    fs::create_symlink(dir / "loop_a.gltf", dir / "loop.png");
    const RunResult b = run_bounded({"bake", (dir / "loop_a.gltf").string(), "-o", (dir / "out").string()}, dir);
    EXPECT_EQ(b.exit_code, 1) << b.err;
    EXPECT_NE(line_naming(b.err, {"loop_a.gltf", "symbolic link loop"}), "") << b.err;
    const RunResult t = run_bounded({"texture", "--normal", (dir / "loop.png").string(), "-o", (dir / "t").string()}, dir);
    EXPECT_EQ(t.exit_code, 1) << t.err;
    EXPECT_NE(line_naming(t.err, {"loop.png", "symbolic link loop"}), "") << t.err;
    fs::remove_all(dir);
}

// `inspect --check -q` prints nothing when the folder is sound (the exit code says it).
TEST(FarmExitCodes, InspectCheckQuietIsSilent) {
    const fs::path dir = temp_dir("farm_quiet");
    write_bumpy_normals(dir / "n.png");
    write_triangle_scene(dir / "s.gltf", "n.png");
    ASSERT_EQ(run_bounded({"bake", (dir / "s.gltf").string(), "-o", (dir / "out").string()}, dir).exit_code, 0);
    const RunResult q = run_bounded({"inspect", "--check", "-q", (dir / "out").string()}, dir);
    EXPECT_EQ(q.exit_code, 0) << q.err;
    EXPECT_EQ(q.out, "");
    EXPECT_EQ(q.err, "");
    fs::remove_all(dir);
}

// A JSON config with a key twice is refused as TOML refuses it; a [materials.NAME] table for a material no
// baked scene has is reported.
TEST(FarmConfig, DuplicateJsonKeysAreRefusedAndUnknownMaterialsReported) {
    const fs::path dir = temp_dir("farm_config");
    write_bumpy_normals(dir / "n.png");
    write_triangle_scene(dir / "s.gltf", "n.png");
    write_bytes(dir / "dup.json", "{\"materials\": {\"Glossy\": {\"isotropic\": \"max\", \"isotropic\": \"sum\"}}}");
    const RunResult dup = run_bounded({"bake", "--config", (dir / "dup.json").string(), (dir / "s.gltf").string(), "-o",
                                       (dir / "out").string()},
                                      dir);
    EXPECT_EQ(dup.exit_code, 2) << dup.err;
    EXPECT_NE(line_naming(dup.err, {"dup.json", "isotropic", "twice"}), "") << dup.err;
    write_bytes(dir / "typo.toml", "[materials.Glosy]\nisotropic = \"max\"\n");
    const RunResult typo = run_bounded({"bake", "--config", (dir / "typo.toml").string(), (dir / "s.gltf").string(),
                                        "-o", (dir / "out").string()},
                                       dir);
    EXPECT_EQ(typo.exit_code, 0) << typo.err;
    EXPECT_NE(line_naming(typo.err, {"warning", "materials.Glosy", "no material"}), "") << typo.err;
    fs::remove_all(dir);
}

// A folder without a manifest that holds files with the names of outputs: refused, naming the file, and the
// file kept (--force replaces it). A bake into a folder inside another bake's output folder is refused, so
// the outer folder's check keeps passing.
TEST(FarmOutputFolders, ForeignFilesAndNestedOutputFoldersAreRefused) {
    const fs::path dir = temp_dir("farm_foreign");
    write_bumpy_normals(dir / "n.png");
    write_triangle_scene(dir / "s.gltf", "n.png");
    write_bytes(dir / "out" / "s.gltf", "the user's own file");
    const RunResult r = run_bounded({"bake", (dir / "s.gltf").string(), "-o", (dir / "out").string()}, dir);
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(line_naming(r.err, {"s.gltf", "no manifest.json lists it"}), "") << r.err;
    EXPECT_EQ(slurp(dir / "out" / "s.gltf"), "the user's own file");
    EXPECT_FALSE(fs::exists(dir / "out" / "manifest.json"));
    const RunResult forced = run_bounded({"bake", (dir / "s.gltf").string(), "-o", (dir / "out").string(), "--force"}, dir);
    EXPECT_EQ(forced.exit_code, 0) << forced.err;
    EXPECT_NE(slurp(dir / "out" / "s.gltf"), "the user's own file");

    const RunResult nested = run_bounded({"bake", (dir / "s.gltf").string(), "-o", (dir / "out" / "inner").string()}, dir);
    EXPECT_EQ(nested.exit_code, 1) << nested.err;
    EXPECT_NE(line_naming(nested.err, {"inner", "output folder of another bake"}), "") << nested.err;
    EXPECT_FALSE(fs::exists(dir / "out" / "inner"));
    const RunResult check = run_bounded({"inspect", "--check", (dir / "out").string()}, dir);
    EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
    fs::remove_all(dir);
}

// A working folder longer than PATH_MAX (no absolute path can be formed for it): the bake works with the
// relative paths it was given.
TEST(FarmOutputFolders, WorkingFolderLongerThanPathMax) {
    const fs::path dir = temp_dir("farm_long");
    write_bumpy_normals(dir / "n.png");
    write_triangle_scene(dir / "s.gltf", "n.png");
    // 20 levels of 240 characters, entered one at a time (mkdir and chdir take a relative name).
    const std::string level(240, 'd');
    std::string script = "cd " + quote(dir.string());
    for (int i = 0; i < 20; ++i) script += " && mkdir " + level + " && cd " + level;
    script += " && cp " + quote((dir / "n.png").string()) + " " + quote((dir / "s.gltf").string()) + " " +
              quote((dir / "s.bin").string()) + " . && \"$SPECBAKE\" bake s.gltf -o out && test -f out/manifest.json" +
              " && \"$SPECBAKE\" bake s.gltf -o out";
    std::string err;
    const int code = run_shell("bash -c " + quote(script), dir, &err);
    EXPECT_EQ(code, 0) << err;
    EXPECT_EQ(err.find("the output is an input"), std::string::npos) << err;
    // rm -rf copes with the depth; std::filesystem::remove_all may not.
    EXPECT_EQ(std::system(("rm -rf " + quote(dir.string())).c_str()), 0);
}

// `inspect --check` checks the textures a .glb carries against their manifest entries: a changed hash or
// width in the manifest is found although the .glb itself is intact.
TEST(FarmExitCodes, InspectCheckVerifiesTexturesEmbeddedInAGlb) {
    const fs::path dir = temp_dir("farm_glb_check");
    write_bumpy_normals(dir / "n.png");
    write_triangle_scene(dir / "s.gltf", "n.png");
    ASSERT_EQ(run_bounded({"bake", (dir / "s.gltf").string(), "--format", "glb", "-o", (dir / "out").string()}, dir).exit_code, 0);
    const fs::path manifest = dir / "out" / "manifest.json";
    const std::string original = slurp(manifest);
    const RunResult sound = run_bounded({"inspect", "--check", (dir / "out").string()}, dir);
    ASSERT_EQ(sound.exit_code, 0) << sound.out << sound.err;
    auto edit = [&](const std::function<void(json&)>& change) {
        json m = json::parse(original);
        bool found = false;
        for (json& o : m["outputs"])
            if (o.contains("embedded_images") && !o["embedded_images"].empty()) {
                change(o["embedded_images"][0]);
                found = true;
            }
        ASSERT_TRUE(found) << original;
        write_bytes(manifest, m.dump(1));
    };
    edit([](json& e) { e["sha256"] = std::string(64, '0'); });
    const RunResult hash = run_bounded({"inspect", "--check", (dir / "out").string()}, dir);
    EXPECT_EQ(hash.exit_code, 1) << hash.out << hash.err;
    EXPECT_NE(line_naming(hash.err, {"s.glb", "embedded image", "hash"}), "") << hash.err;
    edit([](json& e) { e["width"] = e["width"].get<int>() * 2; });
    const RunResult width = run_bounded({"inspect", "--check", (dir / "out").string()}, dir);
    EXPECT_EQ(width.exit_code, 1) << width.out << width.err;
    EXPECT_NE(line_naming(width.err, {"s.glb", "embedded image", "size"}), "") << width.err;
    fs::remove_all(dir);
}
