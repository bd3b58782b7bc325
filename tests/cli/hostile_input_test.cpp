// Hostile inputs built here byte by byte: deep JSON, URIs that leave the scene's folder, copies named like
// outputs, headers claiming huge images or accessors, cyclic node graphs, bad config values. Each must
// end in one clear line naming the file, a non-zero exit, no crash, and bounded memory (peak RSS of the
// child process, from getrusage).
#include "scene_test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <OpenImageIO/imageio.h>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <functional>
#include <set>

using namespace scene_test;
using nlohmann::json;

namespace {

std::string le32(uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); }
std::string be32(uint32_t v) {
    const char b[4] = {char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
    return std::string(b, 4);
}

// A PNG chunk with its CRC (PNG spec Sec. 5.3).
std::string png_chunk(const std::string& type, const std::string& data) {
    const std::string td = type + data;
    return be32(uint32_t(data.size())) + td +
           be32(uint32_t(crc32(0, reinterpret_cast<const Bytef*>(td.data()), uInt(td.size()))));
}

// A PNG whose header claims width x height RGB8 but whose image data is a few bytes: 74 bytes for 32768^2.
std::string png_claiming(uint32_t width, uint32_t height) {
    const std::string ihdr = be32(width) + be32(height) + std::string("\x08\x02\x00\x00\x00", 5);
    // Never inflated: the header alone must stop the decode.
    const std::string idat = std::string("\x78\x9c\x63\x00\x00\x00\x01\x00\x01", 9) + std::string(8, '\0');
    return std::string("\x89PNG\r\n\x1a\n", 8) + png_chunk("IHDR", ihdr) + png_chunk("IDAT", idat) +
           png_chunk("IEND", "");
}

// A valid 4x4 RGB8 PNG (a flat normal map), written with OpenImageIO.
void write_normal_png(const fs::path& p) {
    fs::create_directories(p.parent_path());
    std::vector<uint8_t> px(4 * 4 * 3);
    for (size_t i = 0; i < px.size(); i += 3) px[i] = 128, px[i + 1] = 128, px[i + 2] = 255;
    const std::string png = p.string() + ".tmp.png";  // the writer is chosen by the extension
    auto out = OIIO::ImageOutput::create(png);
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(4, 4, 3, OIIO::TypeDesc::UINT8);
    ASSERT_TRUE(out->open(png, spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, px.data()));
    out->close();
    fs::rename(png, p);
}

std::string base64(const std::string& in) {
    static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < in.size(); i += 3) {
        uint32_t v = uint8_t(in[i]) << 16;
        if (i + 1 < in.size()) v |= uint8_t(in[i + 1]) << 8;
        if (i + 2 < in.size()) v |= uint8_t(in[i + 2]);
        out += t[(v >> 18) & 63];
        out += t[(v >> 12) & 63];
        out += i + 1 < in.size() ? t[(v >> 6) & 63] : '=';
        out += i + 2 < in.size() ? t[v & 63] : '=';
    }
    return out;
}

// One triangle with positions, normals and UVs in an embedded buffer, one material whose normal texture
// is the image at `image_uri` (none when empty).
json triangle_scene(const std::string& image_uri) {
    const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const float nrm[9] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    const float uv[6] = {0, 0, 1, 0, 0, 1};
    std::string data(reinterpret_cast<const char*>(pos), 36);
    data += std::string(reinterpret_cast<const char*>(nrm), 36);
    data += std::string(reinterpret_cast<const char*>(uv), 24);
    json j = {
        {"asset", {{"version", "2.0"}}},
        {"scene", 0},
        {"scenes", json::array({{{"nodes", {0}}}})},
        {"nodes", json::array({{{"mesh", 0}}})},
        {"buffers", json::array({{{"byteLength", data.size()},
                                  {"uri", "data:application/octet-stream;base64," + base64(data)}}})},
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
        {"materials", json::array({{{"pbrMetallicRoughness", {{"roughnessFactor", 0.05}, {"metallicFactor", 0.0}}}}})},
    };
    if (!image_uri.empty()) {
        j["images"] = json::array({{{"uri", image_uri}}});
        j["textures"] = json::array({{{"source", 0}}});
        j["materials"][0]["normalTexture"] = {{"index", 0}};
    }
    return j;
}

void write_json(const fs::path& p, const json& j) { write_bytes(p, j.dump(1)); }

// A GLB holding `json_text` (and no binary chunk).
std::string glb_of(std::string json_text) {
    while (json_text.size() % 4) json_text += ' ';
    return std::string("glTF") + le32(2) + le32(uint32_t(12 + 8 + json_text.size())) + le32(uint32_t(json_text.size())) +
           std::string("JSON") + json_text;
}

// Under AddressSanitizer the executable reserves terabytes of shadow address space (so no RLIMIT_AS) and
// its resident set carries the shadow and the allocator's quarantine: the peak bound is wider there, still
// far below the gigabytes the findings reached.
constexpr long kPeakRssLimitKb = (kAddressSanitizer ? 1024 : 200) * 1024;

struct Measured {
    RunResult run;
    long peak_rss_kb = 0;
};

// Runs specbake in a child and reports its peak resident set (getrusage of that child alone).
Measured run_measured(const std::vector<std::string>& args, const fs::path& dir) {
    const fs::path out = dir / "stdout.txt", err = dir / "stderr.txt";
    const pid_t pid = fork();
    if (pid == 0) {
        std::vector<char*> argv{const_cast<char*>(SPECBAKE_EXE)};
        for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
        argv.push_back(nullptr);
        if (!freopen(out.c_str(), "w", stdout) || !freopen(err.c_str(), "w", stderr)) _exit(127);
        // A runaway allocation fails here instead of taking the test machine with it.
        const rlimit as{size_t(6) << 30, size_t(6) << 30};
        if (!kAddressSanitizer) setrlimit(RLIMIT_AS, &as);
        execv(SPECBAKE_EXE, argv.data());
        _exit(127);
    }
    int status = 0;
    rusage usage{};
    wait4(pid, &status, 0, &usage);
    Measured m;
    m.run.signaled = WIFSIGNALED(status);
    m.run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    m.run.out = slurp(out);
    m.run.err = slurp(err);
    m.peak_rss_kb = usage.ru_maxrss;
    return m;
}

// A clean refusal: exit 1 or 2, no signal, no internal error, one line naming `file`.
void expect_clean_error(const RunResult& r, const std::string& file, const std::string& words) {
    EXPECT_FALSE(r.signaled) << r.err;
    EXPECT_TRUE(r.exit_code == 1 || r.exit_code == 2) << "exit " << r.exit_code << ": " << r.err;
    EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(file), std::string::npos) << "names " << file << ": " << r.err;
    EXPECT_NE(r.err.find(words), std::string::npos) << "says '" << words << "': " << r.err;
}

}  // namespace

TEST(HostileInput, DeeplyNestedJsonIsRefusedWithoutCrash) {
    const fs::path dir = temp_dir("deep_json");
    json j = triangle_scene("");
    std::string text = j.dump();
    const std::string deep = std::string(30000, '[') + std::string(30000, ']');
    text.insert(text.find('{') + 1, "\"extras\":" + deep + ",");
    write_bytes(dir / "deep.gltf", text);
    write_bytes(dir / "deep.glb", glb_of(text));
    for (const char* name : {"deep.gltf", "deep.glb"}) {
        const RunResult r = run_specbake({"bake", (dir / name).string(), "-o", (dir / "out").string()}, dir);
        expect_clean_error(r, name, "nesting depth");
        EXPECT_NE(r.err.find("--limit json-depth"), std::string::npos) << r.err;
    }
    // The limit can be raised; 300 levels are within the default.
    text = j.dump();
    text.insert(text.find('{') + 1, "\"extras\":" + std::string(300, '[') + std::string(300, ']') + ",");
    write_bytes(dir / "ok.gltf", text);
    EXPECT_EQ(run_specbake({"bake", (dir / "ok.gltf").string(), "-o", (dir / "out_ok").string()}, dir).exit_code, 0);
    const RunResult tight = run_specbake(
        {"--limit", "json-depth=100", "bake", (dir / "ok.gltf").string(), "-o", (dir / "out_tight").string()}, dir);
    expect_clean_error(tight, "ok.gltf", "nesting depth");
    fs::remove_all(dir);
}

TEST(HostileInput, UrisLeavingTheSceneFolderAreRefused) {
    const fs::path dir = temp_dir("uri_escape");
    write_normal_png(dir / "outside" / "secret.png");
    write_bytes(dir / "outside" / "secret.bin", std::string(96, '\0'));
    write_normal_png(dir / "scene" / "real.png");
    const std::string abs = (dir / "outside" / "secret.png").string();
    const std::vector<std::string> image_uris = {abs, "../outside/secret.png", "%2e%2e/outside/secret.png",
                                                 "%2E%2E%2Foutside%2Fsecret.png", "file://" + abs,
                                                 "real.png%00.txt"};
    int n = 0;
    for (const std::string& uri : image_uris) {
        const std::string name = "s" + std::to_string(n++) + ".gltf";
        write_json(dir / "scene" / name, triangle_scene(uri));
        const fs::path out = dir / ("out" + std::to_string(n));
        const RunResult r = run_specbake({"bake", (dir / "scene" / name).string(), "-o", out.string()}, dir);
        expect_clean_error(r, name, "refused");
        EXPECT_FALSE(fs::exists(out / "secret.png")) << uri;
        EXPECT_FALSE(fs::exists(out / "passwd")) << uri;
    }
    // A buffer URI leaving the folder, relative or absolute: refused, saying why (not "File not found").
    for (const std::string& uri : {std::string("../outside/secret.bin"), (dir / "outside" / "secret.bin").string()}) {
        json j = triangle_scene("");
        j["buffers"][0]["uri"] = uri;
        write_json(dir / "scene" / "buf.gltf", j);
        const RunResult r = run_specbake({"bake", (dir / "scene" / "buf.gltf").string(), "-o", (dir / "outb").string()}, dir);
        expect_clean_error(r, "buf.gltf", "refused");
        EXPECT_EQ(r.err.find("File not found"), std::string::npos) << r.err;
    }
    // --allow-root names a folder that may be read; the copy then lands under its file name.
    write_json(dir / "scene" / "lib.gltf", triangle_scene("../outside/secret.png"));
    const RunResult ok = run_specbake({"--allow-root", (dir / "outside").string(), "bake",
                                       (dir / "scene" / "lib.gltf").string(), "-o", (dir / "outlib").string()},
                                      dir);
    EXPECT_EQ(ok.exit_code, 0) << ok.err;
    EXPECT_EQ(slurp(dir / "outlib" / "secret.png"), slurp(dir / "outside" / "secret.png"));
    fs::remove_all(dir);
}

TEST(HostileInput, OneResolvedPathIsReadCopiedAndListed) {
    const fs::path dir = temp_dir("uri_once");
    write_normal_png(dir / "scene" / "real.png");
    write_json(dir / "scene" / "s.gltf", triangle_scene("nosuch/../real.png"));
    const RunResult r = run_specbake({"bake", (dir / "scene" / "s.gltf").string(), "-o", (dir / "out").string()}, dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(slurp(dir / "out" / "real.png"), slurp(dir / "scene" / "real.png"));
    const json manifest = json::parse(slurp(dir / "out" / "manifest.json"));
    bool listed = false;
    for (const json& in : manifest["inputs"])
        listed |= fs::path(in["path"].get<std::string>()).filename() == "real.png";
    EXPECT_TRUE(listed) << manifest["inputs"].dump();
    fs::remove_all(dir);
}

TEST(HostileInput, CopiesNeverTakeTheNameOfAnOutputOrAnotherCopy) {
    const fs::path dir = temp_dir("collide");
    // Image files named like the outputs of the bake (a PNG under each name) and two images called tex.png
    // from two allowed roots.
    for (const char* name : {"scene.gltf", "scene_specaa.bin", "manifest.json"}) write_normal_png(dir / "in" / name);
    write_normal_png(dir / "a" / "tex.png");
    write_normal_png(dir / "b" / "tex.png");
    {
        // b's tex.png differs from a's, so a clobbered copy would show.
        std::string b = slurp(dir / "b" / "tex.png");
        b += std::string(16, '\0');
        write_bytes(dir / "b" / "tex.png", b);
    }
    json j = triangle_scene("");
    j["images"] = json::array();
    j["textures"] = json::array();
    int k = 0;
    for (const char* name : {"scene.gltf", "scene_specaa.bin", "manifest.json"}) {
        j["images"].push_back({{"uri", name}, {"mimeType", "image/png"}});
        j["textures"].push_back({{"source", k++}});
    }
    j["images"].push_back({{"uri", (dir / "a" / "tex.png").string()}});
    j["images"].push_back({{"uri", (dir / "b" / "tex.png").string()}});
    j["textures"].push_back({{"source", 3}});
    j["textures"].push_back({{"source", 4}});
    j["materials"][0]["occlusionTexture"] = {{"index", 4}};
    j["materials"][0]["emissiveTexture"] = {{"index", 3}};
    write_bytes(dir / "in" / "scene.glb", glb_of(j.dump()));
    const RunResult r = run_specbake({"--allow-root", (dir / "a").string(), "--allow-root", (dir / "b").string(), "bake",
                                      (dir / "in" / "scene.glb").string(), "--format", "gltf", "-o",
                                      (dir / "out").string()},
                                     dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    tinygltf::Model out;
    std::string err;
    ASSERT_TRUE(load_model(dir / "out" / "scene.gltf", out, err)) << err;
    ASSERT_EQ(out.images.size(), 5u);
    const std::vector<fs::path> sources = {dir / "in" / "scene.gltf", dir / "in" / "scene_specaa.bin",
                                           dir / "in" / "manifest.json", dir / "a" / "tex.png", dir / "b" / "tex.png"};
    std::set<std::string> names;
    for (size_t i = 0; i < 5; ++i) {
        EXPECT_EQ(slurp(dir / "out" / out.images[i].uri), slurp(sources[i])) << out.images[i].uri;
        names.insert(out.images[i].uri);
    }
    EXPECT_EQ(names.size(), 5u);
    const json manifest = json::parse(slurp(dir / "out" / "manifest.json"));
    int renamed = 0;
    for (const json& o : manifest["outputs"]) {
        EXPECT_TRUE(fs::exists(dir / "out" / o["path"].get<std::string>())) << o.dump();
        if (o.contains("renamed_from")) ++renamed;
    }
    EXPECT_EQ(renamed, 3) << manifest["outputs"].dump(1);

    // With curvature baked, the scene's own appended buffer keeps its name and its data; the image named
    // like it is renamed.
    fs::create_directories(dir / "sph");
    write_test_model(dir / "sph" / "sphere.gltf", true, 1.0, 0.2, 12, 24);
    write_normal_png(dir / "sph" / "sphere_specaa.bin");
    json s = json::parse(slurp(dir / "sph" / "sphere.gltf"));
    s["images"] = json::array({{{"uri", "sphere_specaa.bin"}, {"mimeType", "image/png"}}});
    s["textures"] = json::array({{{"source", 0}}});
    s["materials"][0]["emissiveTexture"] = {{"index", 0}};
    write_json(dir / "sph" / "sphere.gltf", s);
    const RunResult c = run_specbake({"bake", (dir / "sph" / "sphere.gltf").string(), "-o", (dir / "outc").string()}, dir);
    ASSERT_EQ(c.exit_code, 0) << c.err;
    tinygltf::Model baked;
    ASSERT_TRUE(load_model(dir / "outc" / "sphere.gltf", baked, err)) << err;
    const auto& attrs = baked.meshes[0].primitives[0].attributes;
    ASSERT_TRUE(attrs.count("_SPECAA_CURVATURE"));
    EXPECT_EQ(float_accessor(baked, attrs.at("_SPECAA_CURVATURE")).size(), 4u * 13 * 25);
    EXPECT_NE(baked.images[0].uri, "sphere_specaa.bin");
    EXPECT_EQ(slurp(dir / "outc" / baked.images[0].uri), slurp(dir / "sph" / "sphere_specaa.bin"));
    fs::remove_all(dir);
}

TEST(HostileInput, ImageHeaderClaimingHugeSizeIsRefusedBeforeDecoding) {
    const fs::path dir = temp_dir("huge_png");
    const std::string png = png_claiming(32768, 32768);
    ASSERT_EQ(png.size(), 74u);
    write_bytes(dir / "huge.png", png);
    const Measured t = run_measured({"texture", "--normal", (dir / "huge.png").string(), "-o", (dir / "out").string()}, dir);
    expect_clean_error(t.run, "huge.png", "--limit texels");
    EXPECT_LT(t.peak_rss_kb, kPeakRssLimitKb) << "peak RSS in KiB";
    write_bytes(dir / "wide.png", png_claiming(60000, 60000));
    const Measured i = run_measured({"inspect", (dir / "wide.png").string()}, dir);
    expect_clean_error(i.run, "wide.png", "--limit texels");
    EXPECT_LT(i.peak_rss_kb, kPeakRssLimitKb) << "peak RSS in KiB";
    // The same image inside a scene.
    write_json(dir / "s.gltf", triangle_scene("huge.png"));
    const Measured s = run_measured({"bake", (dir / "s.gltf").string(), "-o", (dir / "outs").string()}, dir);
    EXPECT_FALSE(s.run.signaled);
    EXPECT_NE(s.run.err.find("huge.png"), std::string::npos) << s.run.err;
    EXPECT_LT(s.peak_rss_kb, kPeakRssLimitKb) << "peak RSS in KiB";
    fs::remove_all(dir);
}

TEST(HostileInput, AccessorCountsAreCheckedBeforeAllocating) {
    const fs::path dir = temp_dir("accessors");
    struct Case {
        const char* name;
        std::function<void(json&)> edit;
    };
    const std::vector<Case> cases = {
        {"noview.gltf", [](json& j) { j["accessors"][0] = {{"componentType", 5126}, {"count", uint64_t(1) << 32}, {"type", "VEC3"}}; }},
        {"index31.gltf", [](json& j) {
             j["accessors"].push_back({{"bufferView", 0}, {"componentType", 5125}, {"count", uint64_t(1) << 31}, {"type", "SCALAR"}});
             j["meshes"][0]["primitives"][0]["indices"] = 3;
         }},
        {"count62.gltf", [](json& j) { j["accessors"][1]["count"] = uint64_t(1) << 62; }},
        {"count62noview.gltf", [](json& j) { j["accessors"][1] = {{"componentType", 5126}, {"count", uint64_t(1) << 62}, {"type", "VEC3"}}; }},
    };
    for (const Case& c : cases) {
        json j = triangle_scene("");
        c.edit(j);
        write_json(dir / c.name, j);
        const Measured m = run_measured({"bake", (dir / c.name).string(), "-o", (dir / "out").string()}, dir);
        expect_clean_error(m.run, c.name, "accessor");
        EXPECT_LT(m.peak_rss_kb, kPeakRssLimitKb) << c.name << ": peak RSS in KiB";
    }
    fs::remove_all(dir);
}

TEST(HostileInput, NodeAndPrimitiveCountsAreLimited) {
    const fs::path dir = temp_dir("counts");
    json j = triangle_scene("");
    j["materials"] = json::array();
    json prim = j["meshes"][0]["primitives"][0];
    prim.erase("material");
    for (int i = 0; i < 40; ++i) j["meshes"][0]["primitives"].push_back(prim);
    write_json(dir / "many.gltf", j);
    const RunResult r = run_specbake({"--limit", "primitives=16", "bake", (dir / "many.gltf").string(), "-o",
                                      (dir / "out").string()},
                                     dir);
    expect_clean_error(r, "many.gltf", "--limit primitives");
    for (int i = 0; i < 40; ++i) j["nodes"].push_back({{"mesh", 0}});
    write_json(dir / "nodes.gltf", j);
    const RunResult n = run_specbake({"--limit", "nodes=8", "bake", (dir / "nodes.gltf").string(), "-o",
                                      (dir / "out").string()},
                                     dir);
    expect_clean_error(n, "nodes.gltf", "--limit nodes");
    const RunResult bad = run_specbake({"--limit", "primitives=lots", "bake", (dir / "many.gltf").string(), "-o",
                                        (dir / "out").string()},
                                       dir);
    EXPECT_EQ(bad.exit_code, 2) << bad.err;
    fs::remove_all(dir);
}

TEST(HostileInput, CyclicNodeGraphIsRefused) {
    const fs::path dir = temp_dir("cycle");
    json j = triangle_scene("");
    j["nodes"] = json::array({{{"mesh", 0}, {"children", {1}}}, {{"children", {2}}}, {{"children", {0}}}});
    write_json(dir / "cycle.gltf", j);
    expect_clean_error(run_specbake({"bake", (dir / "cycle.gltf").string(), "-o", (dir / "out").string()}, dir),
                       "cycle.gltf", "cycle");
    fs::remove_all(dir);
}

TEST(HostileInput, CorruptPngErrorsNameTheFile) {
    const fs::path dir = temp_dir("png_crc");
    write_normal_png(dir / "good.png");
    std::string png = slurp(dir / "good.png");
    // Flip one byte inside the IDAT chunk's data: its CRC no longer matches.
    const size_t idat = png.find("IDAT");
    ASSERT_NE(idat, std::string::npos);
    png[idat + 6] = char(png[idat + 6] ^ 0x5a);
    write_bytes(dir / "bad.png", png);
    // And an IHDR with a bit depth PNG does not have, its CRC correct.
    std::string header = slurp(dir / "good.png");
    const size_t ihdr = header.find("IHDR");
    header[ihdr + 4 + 8] = 3;
    const std::string crc = be32(uint32_t(crc32(0, reinterpret_cast<const Bytef*>(header.data() + ihdr), 17)));
    header.replace(ihdr + 17, 4, crc);
    write_bytes(dir / "depth.png", header);
    for (const char* name : {"bad.png", "depth.png"}) {
        const RunResult r = run_specbake({"texture", "--normal", (dir / name).string(), "-o", (dir / "out").string()}, dir);
        expect_clean_error(r, name, name);
        std::istringstream lines(r.err);
        for (std::string line; std::getline(lines, line);)
            EXPECT_NE(line.find(name), std::string::npos) << "every line names the file: " << line;
    }
    fs::remove_all(dir);
}

TEST(HostileInput, InvalidUtf8PathsAreReportedWithTheFile) {
    const fs::path dir = temp_dir("utf8");
    // A scene and a normal map whose names are not UTF-8, and a URI that is not once percent-decoded.
    const fs::path scene = dir / "scene\xff.gltf";
    write_json(scene, triangle_scene(""));
    RunResult r = run_specbake({"bake", scene.string(), "-o", (dir / "out").string()}, dir);
    expect_clean_error(r, scene.string(), "UTF-8");
    const fs::path normal = dir / "normal\xfe.png";
    write_normal_png(normal);
    r = run_specbake({"texture", "--normal", normal.string(), "-o", (dir / "out").string()}, dir);
    expect_clean_error(r, normal.string(), "UTF-8");
    fs::copy_file(normal, dir / "n.png");
    write_json(dir / "uri.gltf", triangle_scene("%ffn.png"));
    r = run_specbake({"bake", (dir / "uri.gltf").string(), "-o", (dir / "out").string()}, dir);
    expect_clean_error(r, "uri.gltf", "UTF-8");
    fs::remove_all(dir);
}

TEST(HostileInput, BadOptionAndConfigValuesAreRefused) {
    const fs::path dir = temp_dir("options");
    write_json(dir / "s.gltf", triangle_scene(""));
    const std::string scene = (dir / "s.gltf").string(), out = (dir / "out").string();
    EXPECT_EQ(run_specbake({"bake", scene, "-o", out, "--max-kernel", "nan"}, dir).exit_code, 2);
    EXPECT_EQ(run_specbake({"bake", scene, "-o", out, "--max-kernel", "inf"}, dir).exit_code, 2);
    write_bytes(dir / "quiet.toml", "quiet = \"yes\"\n");
    const RunResult q = run_specbake({"--config", (dir / "quiet.toml").string(), "bake", scene, "-o", out}, dir);
    EXPECT_EQ(q.exit_code, 2) << q.err;
    EXPECT_NE(q.err.find("quiet.toml"), std::string::npos) << q.err;
    write_bytes(dir / "typo.toml", "frobnicate = 3\n");
    const RunResult t = run_specbake({"--config", (dir / "typo.toml").string(), "bake", scene, "-o", out}, dir);
    EXPECT_EQ(t.exit_code, 2) << t.err;
    EXPECT_NE(t.err.find("typo.toml"), std::string::npos) << t.err;
    write_bytes(dir / "limits.toml", "limit = [\"primitives=0\"]\n");
    const RunResult l = run_specbake({"--config", (dir / "limits.toml").string(), "bake", scene, "-o", out}, dir);
    EXPECT_EQ(l.exit_code, 2) << l.err;
    EXPECT_NE(l.err.find("limits.toml"), std::string::npos) << l.err;
    fs::remove_all(dir);
}

TEST(HostileInput, Ktx2KeyValueEntryRunningPastItsBlockFailsCheck) {
    const fs::path dir = temp_dir("ktx2_kv");
    ASSERT_EQ(run_specbake({"texture", "--demo", "-o", (dir / "out").string()}, dir).exit_code, 0);
    fs::path ktx;
    for (const auto& e : fs::directory_iterator(dir / "out"))
        if (e.path().extension() == ".ktx2") ktx = e.path();
    ASSERT_FALSE(ktx.empty());
    EXPECT_EQ(run_specbake({"inspect", "--check", (dir / "out").string()}, dir).exit_code, 0);
    std::string bytes = slurp(ktx);
    uint32_t kvd_offset = 0, kvd_length = 0;
    std::memcpy(&kvd_offset, bytes.data() + 56, 4);
    std::memcpy(&kvd_length, bytes.data() + 60, 4);
    ASSERT_GT(kvd_length, 4u) << "the writer stores key/value data";
    bytes.replace(kvd_offset, 4, le32(0xFFFFFFFFu));
    write_bytes(ktx, bytes);
    const RunResult r = run_specbake({"inspect", ktx.string()}, dir);
    EXPECT_NE(r.exit_code, 0) << r.out << r.err;
    EXPECT_NE((r.out + r.err).find("key/value"), std::string::npos) << r.out << r.err;
    fs::remove_all(dir);
}

TEST(HostileInput, DdsWithHugeMipCountIsRefusedAtOnce) {
    const fs::path dir = temp_dir("dds_mips");
    // DDS_HEADER (124 bytes after the magic) + DDS_HEADER_DXT10, 512x512 RGBA8, mip count 0xFFFFFFFF,
    // padded to 1 MiB.
    std::string dds = "DDS " + le32(124) + le32(0x1 | 0x2 | 0x4 | 0x1000 | 0x20000) + le32(512) + le32(512) +
                      le32(0) + le32(0) + le32(0xFFFFFFFFu) + std::string(44, '\0') + le32(32) + le32(0x4) + "DX10" +
                      std::string(20, '\0') + le32(0) + le32(0) + le32(0) + le32(0) + le32(0);
    ASSERT_EQ(dds.size(), 128u);
    dds += le32(28) + le32(3) + le32(0) + le32(1) + le32(0);  // DXGI_FORMAT_R8G8B8A8_UNORM, TEXTURE2D
    dds.resize(1 << 20, '\0');
    write_bytes(dir / "mips.dds", dds);
    const Measured m = run_measured({"inspect", (dir / "mips.dds").string()}, dir);
    expect_clean_error(m.run, "mips.dds", "mip count");
    EXPECT_LT(m.peak_rss_kb, kPeakRssLimitKb);
    // And a header claiming 65536^2 texels.
    std::string big = dds;
    big.replace(12, 8, le32(65536) + le32(65536));
    big.replace(28, 4, le32(1));
    write_bytes(dir / "big.dds", big);
    const Measured b = run_measured({"inspect", (dir / "big.dds").string()}, dir);
    expect_clean_error(b.run, "big.dds", "--limit texels");
    EXPECT_LT(b.peak_rss_kb, kPeakRssLimitKb);
    fs::remove_all(dir);
}

namespace {

// One triangle as an OBJ that names `mtllib` (none when empty) and uses its material "m".
std::string obj_triangle(const std::string& mtllib) {
    std::string obj = mtllib.empty() ? "" : "mtllib " + mtllib + "\nusemtl m\n";
    return obj + "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n";
}

bool manifest_lists_input(const fs::path& manifest, const std::string& file_name) {
    const json doc = json::parse(slurp(manifest));
    for (const json& in : doc["inputs"])
        if (fs::path(in["path"].get<std::string>()).filename() == file_name) return true;
    return false;
}

}  // namespace

TEST(HostileInput, MeshFilesReadThroughAssimpFollowThePathPolicy) {
    const fs::path dir = temp_dir("assimp_policy");
    write_bytes(dir / "outside" / "secret.mtl", "newmtl m\nNs 30\n");
    write_bytes(dir / "scene" / "inside.mtl", "newmtl m\nNs 30\n");
    // An .mtl outside the scene's folder, relative or through a symbolic link: refused, naming the reference.
    write_bytes(dir / "scene" / "rel.obj", obj_triangle("../outside/secret.mtl"));
    fs::create_symlink(dir / "outside" / "secret.mtl", dir / "scene" / "link.mtl");
    write_bytes(dir / "scene" / "link.obj", obj_triangle("link.mtl"));
    for (const auto& [name, ref] : {std::pair<std::string, std::string>{"rel.obj", "../outside/secret.mtl"},
                                    {"link.obj", "link.mtl"}}) {
        const RunResult r = run_specbake({"bake", (dir / "scene" / name).string(), "-o", (dir / "out").string()}, dir);
        expect_clean_error(r, name, "refused");
        EXPECT_NE(r.err.find("'" + ref + "'"), std::string::npos) << r.err;
        EXPECT_FALSE(fs::exists(dir / "out" / "manifest.json"));
    }
    // A texture reference leaving the folder, in an .mtl inside it: refused too.
    write_bytes(dir / "scene" / "tex.mtl", "newmtl m\nNs 30\nmap_Bump ../outside/normal.png\n");
    write_normal_png(dir / "outside" / "normal.png");
    write_bytes(dir / "scene" / "tex.obj", obj_triangle("tex.mtl"));
    const RunResult t = run_specbake({"bake", (dir / "scene" / "tex.obj").string(), "-o", (dir / "outt").string()}, dir);
    expect_clean_error(t, "tex.obj", "refused");
    EXPECT_NE(t.err.find("../outside/normal.png"), std::string::npos) << t.err;
    // --allow-root permits the folder; the .mtl read is listed among the manifest's inputs.
    const RunResult ok = run_specbake({"--allow-root", (dir / "outside").string(), "bake",
                                       (dir / "scene" / "rel.obj").string(), "-o", (dir / "outok").string()},
                                      dir);
    ASSERT_EQ(ok.exit_code, 0) << ok.err;
    EXPECT_TRUE(manifest_lists_input(dir / "outok" / "manifest.json", "secret.mtl"));
    // An .mtl beside the scene is read and listed as well.
    write_bytes(dir / "scene" / "plain.obj", obj_triangle("inside.mtl"));
    const RunResult plain =
        run_specbake({"bake", (dir / "scene" / "plain.obj").string(), "-o", (dir / "outplain").string()}, dir);
    ASSERT_EQ(plain.exit_code, 0) << plain.err;
    EXPECT_TRUE(manifest_lists_input(dir / "outplain" / "manifest.json", "inside.mtl"));
    fs::remove_all(dir);
}

// An OBJ exported with Latin-1 names (one of the mesh fuzz target's saved inputs had 0xFF in its usemtl
// name): the glTF written names them as UTF-8 text (each invalid byte U+FFFD), where the JSON writer
// failed at the very end before; what was changed is said, with the bytes as read.
TEST(HostileInput, MeshNamesThatAreNotUtf8AreWrittenAsUtf8WithANote) {
    const fs::path dir = temp_dir("latin1_names");
    write_bytes(dir / "scene" / "latin1.mtl", "newmtl M\xE9tal\xFF\nNs 30\n");
    write_bytes(dir / "scene" / "latin1.obj", "mtllib latin1.mtl\no Pi\xE8""ce\nusemtl M\xE9tal\xFF\n"
                                              "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n");
    const RunResult r =
        run_specbake({"mesh", (dir / "scene" / "latin1.obj").string(), "-o", (dir / "out").string()}, dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE((r.out + r.err).find("M\\xE9tal\\xFF"), std::string::npos) << r.out << r.err;
    const fs::path written = dir / "out" / "latin1.gltf";
    ASSERT_TRUE(fs::exists(written));
    const json doc = json::parse(slurp(written));  // throws on invalid UTF-8
    bool found = false;
    for (const json& m : doc["materials"]) found = found || m.value("name", "") == "M\xEF\xBF\xBDtal\xEF\xBF\xBD";
    EXPECT_TRUE(found) << doc["materials"].dump();
    EXPECT_TRUE(fs::exists(dir / "scene" / "latin1.obj"));
    fs::remove_all(dir);
}

TEST(HostileInput, MeshFilesReadThroughAssimpAreLimited) {
    const fs::path dir = temp_dir("assimp_limits");
    // Two triangles (4 vertices) as OBJ: the vertex, face and primitive limits apply after import.
    write_bytes(dir / "quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n");
    const std::string quad = (dir / "quad.obj").string();
    expect_clean_error(run_specbake({"--limit", "vertices=3", "bake", quad, "-o", (dir / "o1").string()}, dir),
                       "quad.obj", "--limit vertices");
    expect_clean_error(run_specbake({"--limit", "faces=1", "bake", quad, "-o", (dir / "o2").string()}, dir),
                       "quad.obj", "--limit faces");
    EXPECT_EQ(run_specbake({"bake", quad, "-o", (dir / "o3").string()}, dir).exit_code, 0);
    // A PLY header claiming 2^31 vertices in a few bytes: refused from the header, before Assimp allocates.
    const std::string ply_head = "ply\nformat binary_little_endian 1.0\nelement vertex 2147483648\n"
                                 "property float x\nproperty float y\nproperty float z\n"
                                 "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    write_bytes(dir / "huge.ply", ply_head + std::string(64, '\0'));
    const Measured h = run_measured({"bake", (dir / "huge.ply").string(), "-o", (dir / "o4").string()}, dir);
    expect_clean_error(h.run, "huge.ply", "--limit vertices");
    EXPECT_LT(h.peak_rss_kb, kPeakRssLimitKb) << "peak RSS in KiB";
    // Within the limit but more instances than bytes after the header: refused the same way.
    write_bytes(dir / "short.ply", "ply\nformat ascii 1.0\nelement vertex 1000000\nproperty float x\n"
                                   "property float y\nproperty float z\nend_header\n0 0 0\n");
    const Measured s = run_measured({"bake", (dir / "short.ply").string(), "-o", (dir / "o5").string()}, dir);
    expect_clean_error(s.run, "short.ply", "bytes follow");
    fs::remove_all(dir);
}

TEST(HostileInput, CorruptPngImageDataIsOneLineNamingTheFile) {
    const fs::path dir = temp_dir("png_zlib");
    // 8x8 RGB8 rows whose zlib stream is broken while every CRC is right: a stored block whose length
    // and its complement disagree, garbage after a valid header, and a stream that ends too early.
    const std::string ihdr = be32(8) + be32(8) + std::string("\x08\x02\x00\x00\x00", 5);
    const std::string ihdr_interlaced = be32(8) + be32(8) + std::string("\x08\x02\x00\x00\x01", 5);
    std::string rows(8 * (1 + 8 * 3), '\x40');
    for (size_t y = 0; y < 8; ++y) rows[y * 25] = 0;
    std::string deflated(compressBound(uLong(rows.size())), '\0');
    uLongf size = uLongf(deflated.size());
    ASSERT_EQ(compress(reinterpret_cast<Bytef*>(deflated.data()), &size, reinterpret_cast<const Bytef*>(rows.data()),
                       uLong(rows.size())),
              Z_OK);
    deflated.resize(size);
    const std::string garbage = std::string("\x78\x9c", 2) + std::string(40, '\xff');
    const std::string short_stream = [&] {
        std::string half(rows.substr(0, rows.size() / 2)), out(compressBound(uLong(half.size())), '\0');
        uLongf n = uLongf(out.size());
        compress(reinterpret_cast<Bytef*>(out.data()), &n, reinterpret_cast<const Bytef*>(half.data()), uLong(half.size()));
        return out.substr(0, n);
    }();
    auto png = [&](const std::string& header, const std::string& idat) {
        return std::string("\x89PNG\r\n\x1a\n", 8) + png_chunk("IHDR", header) + png_chunk("IDAT", idat) +
               png_chunk("IEND", "");
    };
    write_bytes(dir / "garbage.png", png(ihdr, garbage));
    write_bytes(dir / "garbage_interlaced.png", png(ihdr_interlaced, garbage));
    write_bytes(dir / "short.png", png(ihdr, short_stream));
    write_bytes(dir / "good.png", png(ihdr, deflated));
    for (const char* name : {"garbage.png", "garbage_interlaced.png", "short.png"}) {
        const RunResult r = run_specbake({"texture", "--normal", (dir / name).string(), "-o", (dir / "out").string()}, dir);
        expect_clean_error(r, name, "PNG image data");
        EXPECT_EQ(r.err.find("libpng"), std::string::npos) << r.err;
        std::istringstream lines(r.err);
        int n = 0;
        for (std::string line; std::getline(lines, line); ++n)
            EXPECT_NE(line.find(name), std::string::npos) << "every line names the file: " << line;
        EXPECT_EQ(n, 1) << r.err;
    }
    // The intact stream decodes (the check measures the inflated size the header asks for).
    EXPECT_EQ(run_specbake({"texture", "--normal", (dir / "good.png").string(), "-o", (dir / "og").string()}, dir).exit_code, 0);
    fs::remove_all(dir);
}

namespace {

// Runs specbake in a child whose files may not grow past `max_bytes` (RLIMIT_FSIZE; SIGXFSZ ignored, so
// the write fails with EFBIG): a full disk without privileges (a read-only folder does not stop root, and
// /dev/full cannot be an output: outputs are renamed into place). Its stdout and stderr, together, in err.
RunResult run_with_file_size_limit(const std::vector<std::string>& args, rlim_t max_bytes) {
    // The messages go through a pipe: a file would be cut at the limit too.
    int fds[2];
    if (pipe(fds) != 0) return {};
    const pid_t pid = fork();
    if (pid == 0) {
        std::vector<char*> argv{const_cast<char*>(SPECBAKE_EXE)};
        for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
        argv.push_back(nullptr);
        close(fds[0]);
        if (dup2(fds[1], 1) < 0 || dup2(fds[1], 2) < 0) _exit(127);
        signal(SIGXFSZ, SIG_IGN);
        const rlimit fsize{max_bytes, max_bytes};
        setrlimit(RLIMIT_FSIZE, &fsize);
        execv(SPECBAKE_EXE, argv.data());
        _exit(127);
    }
    close(fds[1]);
    RunResult r;
    char buffer[4096];
    for (ssize_t n; (n = read(fds[0], buffer, sizeof buffer)) > 0;) r.err.append(buffer, size_t(n));
    close(fds[0]);
    int status = 0;
    waitpid(pid, &status, 0);
    r.signaled = WIFSIGNALED(status);
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

}  // namespace

TEST(HostileInput, WriteErrorsGiveTheFileAndTheOsReason) {
    const fs::path dir = temp_dir("write_errors");
    write_json(dir / "tri.gltf", triangle_scene(""));
    write_normal_png(dir / "n.png");
    const std::string reason = std::strerror(EFBIG);
    struct Case {
        std::vector<std::string> args;
        std::string file;  // the output the error names
    };
    const std::vector<Case> cases = {
        {{"bake", (dir / "tri.gltf").string(), "-o", (dir / "o1").string()}, (dir / "o1" / "tri").string()},
        {{"bake", (dir / "tri.gltf").string(), "--format", "glb", "-o", (dir / "o2").string()}, (dir / "o2" / "tri").string()},
        {{"texture", "--normal", (dir / "n.png").string(), "--format", "ktx2", "-o", (dir / "o3").string()}, ".ktx2"},
        {{"texture", "--normal", (dir / "n.png").string(), "--format", "png", "-o", (dir / "o4").string()}, ".png"},
        {{"texture", "--normal", (dir / "n.png").string(), "--format", "exr", "-o", (dir / "o5").string()}, ".exr"},
    };
    for (const Case& c : cases) {
        const RunResult r = run_with_file_size_limit(c.args, 64);
        expect_clean_error(r, c.file, reason);
        EXPECT_EQ(r.err.find("disk full?"), std::string::npos) << r.err;
        EXPECT_EQ(r.err.find(".tmp"), std::string::npos) << "names the output, not its temporary: " << r.err;
    }
    fs::remove_all(dir);
}

TEST(HostileInput, JpegMetadataSegmentsAreCheckedBeforeTheDecoder) {
    const fs::path dir = temp_dir("jpeg_markers");
    // A valid 8x8 JPEG from OpenImageIO, then APP segments inserted after its SOI marker.
    const fs::path good = dir / "good.jpg";
    {
        fs::create_directories(dir);
        std::vector<uint8_t> px(8 * 8 * 3, 128);
        auto out = OIIO::ImageOutput::create(good.string());
        ASSERT_TRUE(out);
        ASSERT_TRUE(out->open(good.string(), OIIO::ImageSpec(8, 8, 3, OIIO::TypeDesc::UINT8)));
        ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, px.data()));
        out->close();
    }
    const std::string jpeg = slurp(good);
    auto with_segment = [&](uint8_t marker, const std::string& data) {
        const uint16_t n = uint16_t(data.size() + 2);
        return jpeg.substr(0, 2) + std::string{char(0xFF), char(marker), char(n >> 8), char(n & 0xFF)} + data +
               jpeg.substr(2);
    };
    // An APP1 whose identifier has no NUL (OpenImageIO strcmp()s it), an Exif header shorter than its
    // 6 bytes (OpenImageIO takes length - 6), an ICC header without its sequence bytes.
    write_bytes(dir / "app1.jpg", with_segment(0xE1, "\x04\x04"));
    write_bytes(dir / "exif.jpg", with_segment(0xE1, std::string("Exif\0", 5)));
    write_bytes(dir / "icc.jpg", with_segment(0xE2, std::string("ICC_PROFILE\0", 12)));
    // The same APP1 after stray bytes, which libjpeg skips to reach it.
    const std::string app1 = with_segment(0xE1, "\x04\x04");
    write_bytes(dir / "stray.jpg", app1.substr(0, 2) + "\x01\x02" + app1.substr(2));
    for (const char* name : {"app1.jpg", "exif.jpg", "icc.jpg", "stray.jpg"}) {
        const RunResult r = run_specbake({"texture", "--normal", (dir / name).string(), "-o", (dir / "out").string()}, dir);
        expect_clean_error(r, name, "corrupt JPEG");
    }
    // A well-formed Exif segment (header only) is fine.
    write_bytes(dir / "ok.jpg", with_segment(0xE1, std::string("Exif\0\0", 6)));
    EXPECT_EQ(run_specbake({"texture", "--normal", (dir / "ok.jpg").string(), "-o", (dir / "ok").string()}, dir).exit_code, 0);
    fs::remove_all(dir);
}

TEST(HostileInput, PlyFaceListWithoutIndicesIsRefusedWithoutAbort) {
    const fs::path dir = temp_dir("ply_faces");
    // A misspelt face property makes Assimp's PLY reader produce faces with no indices; its triangulation
    // then aborted the process on an assertion.
    write_bytes(dir / "faces.ply", "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                                   "property float z\nelement face 2\nproperty list uchar int vertex_indices\n"
                                   "end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\nx 4\nprope 0 2 3 1\n");
    const RunResult r = run_specbake({"bake", (dir / "faces.ply").string(), "-o", (dir / "out").string()}, dir);
    expect_clean_error(r, "faces.ply", "no vertex indices");
    fs::remove_all(dir);
}
