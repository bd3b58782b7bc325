// Writes the seed corpora of the fuzz targets, each made here from the project's own writers or from
// text built in this file (no third-party files): make_seeds OUT_DIR creates OUT_DIR/<target>/seed-N.
#include "bake/constants.h"
#include "io/files/file_read.h"
#include "io/gltf/gltf_scene.h"
#include "io/image/image_io.h"
#include "io/texture/texture_writer.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace specbake;

namespace {

fs::path g_out;

void put(const std::string& target, const std::string& name, const std::vector<uint8_t>& bytes) {
    const fs::path dir = g_out / target;
    fs::create_directories(dir);
    std::ofstream(dir / name, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), bytes.size());
}
void put_text(const std::string& target, const std::string& name, const std::string& text) {
    put(target, name, std::vector<uint8_t>(text.begin(), text.end()));
}
std::vector<uint8_t> slurp(const fs::path& path) {
    auto bytes = io::read_file(path);
    if (!bytes) {
        std::fprintf(stderr, "make_seeds: %s\n", bytes.error().message.c_str());
        std::exit(1);
    }
    return *bytes;
}
void need(bool ok, const std::string& what) {
    if (!ok) {
        std::fprintf(stderr, "make_seeds: %s failed\n", what.c_str());
        std::exit(1);
    }
}

// A small image with a gradient in every channel (normal-map-like values).
Image gradient(int w, int h, int c) {
    Image img(w, h, c);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int k = 0; k < c; ++k)
                img.pixels[(size_t(y) * w + x) * c + k] = float((x * (k + 1) + y * 3) % 17) / 16.0f;
    return img;
}

std::string base64(const std::vector<uint8_t>& in) {
    static const char* tab = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < in.size(); i += 3) {
        const uint32_t v = (uint32_t(in[i]) << 16) | (i + 1 < in.size() ? uint32_t(in[i + 1]) << 8 : 0) |
                           (i + 2 < in.size() ? uint32_t(in[i + 2]) : 0);
        out += tab[(v >> 18) & 63];
        out += tab[(v >> 12) & 63];
        out += i + 1 < in.size() ? tab[(v >> 6) & 63] : '=';
        out += i + 2 < in.size() ? tab[v & 63] : '=';
    }
    return out;
}

void images(const fs::path& tmp, std::vector<uint8_t>& small_png) {
    int n = 0;
    struct Kind { const char* ext; int w, h, c, bits; };
    for (const Kind& k : {Kind{"png", 4, 4, 3, 8}, Kind{"png", 3, 5, 4, 16}, Kind{"png", 8, 2, 1, 8},
                          Kind{"png", 2, 2, 2, 16}, Kind{"jpg", 8, 8, 3, 8}, Kind{"jpg", 16, 9, 1, 8}}) {
        const fs::path file = tmp / ("img." + std::string(k.ext));
        need(bool(io::write_image(file, gradient(k.w, k.h, k.c), k.bits)), file.string());
        const auto bytes = slurp(file);
        if (n == 0) small_png = bytes;
        put("image", "seed-" + std::to_string(n++) + "." + k.ext, bytes);
    }
}

void containers(const fs::path& tmp) {
    int n = 0;
    for (auto container : {io::TextureContainer::Ktx2, io::TextureContainer::Dds})
        for (auto encoding : {io::TexelEncoding::Unorm8, io::TexelEncoding::Unorm16, io::TexelEncoding::Float16,
                              io::TexelEncoding::Float32})
            for (int channels : {1, 2, 4}) {
                if ((n++ % 2) && channels == 2) continue;  // keep the corpus small
                MipChain chain;
                for (int size = 4; size >= 1; size /= 2) chain.levels.push_back(gradient(size, size, channels));
                auto written =
                    io::write_texture(chain, encoding, io::TextureFileFormat(container), tmp, "tex", "roughness");
                need(bool(written), "write_texture");
                put("container", "seed-" + std::to_string(n) + "." + io::container_name(container),
                    slurp(tmp / written->front().path));
            }
}

// glTF scenes: one quad in many encodings (indexed or not, strips and fans, strides, normalised and
// sparse accessors), materials with textures, transforms, clearcoat, nodes in hierarchies.
void gltf_scenes(const fs::path& tmp, const std::vector<uint8_t>& png) {
    using nlohmann::json;
    std::vector<uint8_t> bin;
    auto append = [&](const void* p, size_t n) {
        while (bin.size() % 4) bin.push_back(0);
        const size_t off = bin.size();
        bin.insert(bin.end(), static_cast<const uint8_t*>(p), static_cast<const uint8_t*>(p) + n);
        return off;
    };
    const float pos[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    const float nrm[] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    const float tan[] = {1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1};
    const uint16_t uv16[] = {0, 0, 65535, 0, 65535, 65535, 0, 65535};
    const uint16_t idx16[] = {0, 1, 2, 0, 2, 3};
    const uint8_t idx8[] = {0, 1, 2, 0, 2, 3};
    const uint32_t strip[] = {0, 1, 3, 2};
    const uint32_t sparse_idx[] = {2};
    const float sparse_val[] = {1, 1, 0.5f};
    const size_t o_pos = append(pos, sizeof pos), o_nrm = append(nrm, sizeof nrm), o_tan = append(tan, sizeof tan);
    const size_t o_uv = append(uv16, sizeof uv16), o_i16 = append(idx16, sizeof idx16), o_i8 = append(idx8, sizeof idx8);
    const size_t o_strip = append(strip, sizeof strip), o_si = append(sparse_idx, sizeof sparse_idx);
    const size_t o_sv = append(sparse_val, sizeof sparse_val), o_png = append(png.data(), png.size());
    json views = json::array();
    auto view = [&](size_t off, size_t len, int target = 0) {
        json v{{"buffer", 0}, {"byteOffset", off}, {"byteLength", len}};
        if (target) v["target"] = target;
        views.push_back(v);
        return int(views.size() - 1);
    };
    const int v_pos = view(o_pos, sizeof pos, 34962), v_nrm = view(o_nrm, sizeof nrm, 34962);
    const int v_tan = view(o_tan, sizeof tan, 34962), v_uv = view(o_uv, sizeof uv16, 34962);
    const int v_i16 = view(o_i16, sizeof idx16, 34963), v_i8 = view(o_i8, sizeof idx8, 34963);
    const int v_strip = view(o_strip, sizeof strip, 34963), v_si = view(o_si, sizeof sparse_idx);
    const int v_sv = view(o_sv, sizeof sparse_val), v_png = view(o_png, png.size());
    json accessors = json::array({
        {{"bufferView", v_pos}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}, {"min", {0, 0, 0}}, {"max", {1, 1, 0}}},
        {{"bufferView", v_nrm}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}},
        {{"bufferView", v_tan}, {"componentType", 5126}, {"count", 4}, {"type", "VEC4"}},
        {{"bufferView", v_uv}, {"componentType", 5123}, {"normalized", true}, {"count", 4}, {"type", "VEC2"}},
        {{"bufferView", v_i16}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}},
        {{"bufferView", v_i8}, {"componentType", 5121}, {"count", 6}, {"type", "SCALAR"}},
        {{"bufferView", v_strip}, {"componentType", 5125}, {"count", 4}, {"type", "SCALAR"}},
        {{"bufferView", v_pos}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"},
         {"sparse", {{"count", 1}, {"indices", {{"bufferView", v_si}, {"componentType", 5125}}},
                     {"values", {{"bufferView", v_sv}}}}}},
        {{"componentType", 5126}, {"count", 4}, {"type", "VEC3"},
         {"sparse", {{"count", 1}, {"indices", {{"bufferView", v_si}, {"componentType", 5125}}},
                     {"values", {{"bufferView", v_sv}}}}}},
    });
    const std::string data_uri = "data:application/octet-stream;base64," + base64(bin);
    const json attrs{{"POSITION", 0}, {"NORMAL", 1}, {"TANGENT", 2}, {"TEXCOORD_0", 3}};
    const json materials = json::array({
        {{"name", "Rough"}, {"pbrMetallicRoughness", {{"roughnessFactor", 0.4}, {"metallicFactor", 0.0},
                                                       {"metallicRoughnessTexture", {{"index", 0}}}}},
         {"normalTexture", {{"index", 1}, {"scale", 0.8},
                            {"extensions", {{"KHR_texture_transform", {{"scale", {2, 2}}, {"texCoord", 0}}}}}}}},
        {{"name", "Coat"}, {"extensions", {{"KHR_materials_clearcoat", {{"clearcoatFactor", 1.0},
                                            {"clearcoatRoughnessFactor", 0.1},
                                            {"clearcoatNormalTexture", {{"index", 1}}}}}}}},
    });
    auto scene_with = [&](json primitives, bool embed_image_in_view) {
        json g{{"asset", {{"version", "2.0"}}}, {"scene", 0}, {"scenes", {{{"nodes", {0}}}}},
               {"nodes", {{{"name", "root"}, {"children", {1}}, {"translation", {1, 2, 3}}},
                          {{"mesh", 0}, {"scale", {2, 2, 2}}, {"rotation", {0, 0, 0.7071068, 0.7071068}}}}},
               {"meshes", {{{"name", "Quad"}, {"primitives", primitives}}}},
               {"buffers", {{{"byteLength", bin.size()}, {"uri", data_uri}}}},
               {"bufferViews", views}, {"accessors", accessors}, {"materials", materials},
               {"samplers", {{{"wrapS", 33071}, {"wrapT", 10497}}}},
               {"textures", {{{"source", 0}, {"sampler", 0}}, {{"source", embed_image_in_view ? 1 : 0}}}},
               {"extensionsUsed", {"KHR_texture_transform", "KHR_materials_clearcoat"}}};
        g["images"] = json::array({{{"uri", "data:image/png;base64," + base64(png)}},
                                   {{"bufferView", v_png}, {"mimeType", "image/png"}}});
        return g;
    };
    std::vector<json> scenes{
        scene_with({{{"attributes", attrs}, {"indices", 4}, {"material", 0}}}, false),
        scene_with({{{"attributes", attrs}, {"indices", 5}, {"material", 1}},
                    {{"attributes", {{"POSITION", 7}}}, {"indices", 6}, {"mode", 5}}}, true),
        scene_with({{{"attributes", {{"POSITION", 8}, {"TEXCOORD_0", 3}}}, {"indices", 6}, {"mode", 6}}}, false),
        scene_with({{{"attributes", {{"POSITION", 0}}}, {"mode", 4}}, {{"attributes", attrs}, {"mode", 0}}}, true),
    };
    int n = 0;
    for (const json& g : scenes) {
        const std::string text = g.dump();
        put_text("gltf", "seed-" + std::to_string(n) + ".gltf", text);
        // The same scene as GLB, written by the scene writer (buffers and images in the binary chunk).
        const fs::path in = tmp / "in.gltf", out = tmp / "out.glb";
        std::ofstream(in) << text;
        auto scene = io::GltfScene::load(in);
        need(bool(scene), "glTF seed " + std::to_string(n) + (scene ? "" : ": " + scene.error().message));
        need(bool(scene->write(out)), "GLB seed");
        put("gltf", "seed-" + std::to_string(n) + ".glb", slurp(out));
        ++n;
    }
}

void meshes() {
    put_text("mesh", "seed-0.obj",
             "# quad\nmtllib none.mtl\no Quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
             "vn 0 0 1\nusemtl Steel\nf 1/1/1 2/2/1 3/3/1 4/4/1\n");
    put_text("mesh", "seed-1.obj",
             "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\nf -1 -2 -3\nl 1 2\np 3\ng second\nf 2 3 4\n");
    put_text("mesh", "seed-2.ply",
             "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
             "property float nx\nproperty float ny\nproperty float nz\nproperty float s\nproperty float t\n"
             "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
             "0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n1 1 0 0 0 1 1 1\n0 1 0 0 0 1 0 1\n3 0 1 2\n4 0 2 3 1\n");
    std::string bin = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                      "property float z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n";
    const float v[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    bin.append(reinterpret_cast<const char*>(v), sizeof v);
    const uint8_t count = 3;
    const uint32_t f[] = {0, 1, 2};
    bin.append(reinterpret_cast<const char*>(&count), 1);
    bin.append(reinterpret_cast<const char*>(f), sizeof f);
    put_text("mesh", "seed-3.ply", bin);
}

void configs() {
    // First byte 0: config text; 1: response file.
    put_text("config", "seed-0", std::string(1, '\0') +
             "quiet = true\njobs = 2\n[texture]\nfilter = \"projected\"\nmips = [\"8\", \"4\"]\n"
             "[materials.Steel]\nisotropic = \"max\"\n[scene]\ncontainer = 'ktx2'\n");
    put_text("config", "seed-1", std::string(1, '\0') +
             R"({"quiet": false, "texture": {"sigma2": 0.16, "materials": {"A": {"kappa": 0.2}}}, "scene": {"x": [1, 2]}})");
    put_text("config", "seed-2", std::string(1, '\0') + "# comment\n[bake]\n\"quoted key\" = \"v # not a comment\"\n");
    put_text("config", "seed-3", "\x01" "texture in.png -o 'out dir' --filter \"projected aa\" # rest\n--quiet\n");
    put_text("config", "seed-4", "\x01" "@args.rsp --jobs 2");  // names itself: the depth limit
    put_text("config", "seed-5", "\x01" "'unterminated");
}

// Filter inputs in the layout of fuzz_filter.cpp: stability-grid corners in float, then in double.
void filter_inputs() {
    int n = 0;
    const double alphas[] = {0, 1e-7, 0.1, 1};
    const double hz[] = {1, 0.5, 1e-7, 0};
    const double deltas[] = {0, 1e-9, 0.1, 1e20};
    for (double a : alphas)
        for (double z : hz)
            for (double d : deltas) {
                std::vector<uint8_t> bytes;
                auto push = [&](auto value) {
                    const auto* p = reinterpret_cast<const uint8_t*>(&value);
                    bytes.insert(bytes.end(), p, p + sizeof value);
                };
                auto fields = [&](auto zero) {
                    using T = decltype(zero);
                    const double s = std::sqrt(1 - z * z);
                    bytes.push_back(uint8_t(n % 4));
                    push(T(a)), push(T(a * 0.5));
                    const double h[3] = {s, 0, z};
                    for (int v = 0; v < 6; ++v)
                        for (int c = 0; c < 3; ++c) push(T(h[c] + ((v % 3) == 1 && c == 0 ? d : 0) + ((v % 3) == 2 && c == 1 ? d : 0)));
                    push(T(kDefaultSigma2)), push(T(kDefaultKappa)), push(T(d)), push(T(1 / (d + 1)));
                };
                fields(0.0f);
                fields(0.0);
                put("filter", "seed-" + std::to_string(n++), bytes);
            }
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: make_seeds OUT_DIR\n");
        return 2;
    }
    g_out = argv[1];
    const fs::path tmp = g_out / ".work";
    fs::create_directories(tmp);
    std::vector<uint8_t> png;
    images(tmp, png);
    containers(tmp);
    gltf_scenes(tmp, png);
    meshes();
    configs();
    filter_inputs();
    fs::remove_all(tmp);
    return 0;
}
