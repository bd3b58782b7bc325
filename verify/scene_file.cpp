#include "verify/scene_file.h"

#include "verify/float3_math_internal.h"

#include "io/files/file_name.h"
#include "io/gltf/glint_extension.h"
#include "io/gltf/gltf_scene.h"
#include "io/image/image_io.h"
#include "io/mesh_import/mesh_import.h"
#include "mesh/prepare_mesh.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <numbers>
#include <optional>

namespace specbake::verify {
namespace {

namespace fs = std::filesystem;
using Mat4 = std::array<double, 16>;  // column-major, glTF "matrix" layout

constexpr Mat4 kIdentity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

// Smallest perceptual roughness simulated. A perfect mirror lit by a punctual light reflects a Dirac
// delta that no pixel filter resolves; real-time renderers clamp r likewise (Filament's
// MIN_PERCEPTUAL_ROUGHNESS is 0.045). Clamped materials and texels are noted.
constexpr float kMinRoughness = 0.045f;

Mat4 multiply(const Mat4& a, const Mat4& b) {
    Mat4 m{};
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            for (int k = 0; k < 4; ++k) m[c * 4 + r] += a[k * 4 + r] * b[c * 4 + k];
    return m;
}

// glTF node transform: "matrix", or T * R * S from "translation", "rotation" (x, y, z, w), "scale".
Mat4 local_transform(const nlohmann::json& node) {
    if (node.contains("matrix") && node["matrix"].is_array() && node["matrix"].size() == 16) {
        Mat4 m;
        for (int i = 0; i < 16; ++i) m[i] = node["matrix"][i].get<double>();
        return m;
    }
    std::array<double, 3> t{0, 0, 0}, s{1, 1, 1};
    std::array<double, 4> q{0, 0, 0, 1};
    if (node.contains("translation")) for (int i = 0; i < 3; ++i) t[i] = node["translation"][i].get<double>();
    if (node.contains("scale")) for (int i = 0; i < 3; ++i) s[i] = node["scale"][i].get<double>();
    if (node.contains("rotation")) for (int i = 0; i < 4; ++i) q[i] = node["rotation"][i].get<double>();
    const double qn = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (qn > 0) for (double& v : q) v /= qn;
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    const double r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                            {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                            {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
    Mat4 m{};
    for (int c = 0; c < 3; ++c)
        for (int row = 0; row < 3; ++row) m[c * 4 + row] = r[row][c] * s[c];
    m[12] = t[0];
    m[13] = t[1];
    m[14] = t[2];
    m[15] = 1;
    return m;
}

Float3 column(const Mat4& m, int c) { return {float(m[c * 4]), float(m[c * 4 + 1]), float(m[c * 4 + 2])}; }


// Positions by M, normals by the inverse transpose of its 3x3 part, tangents by the 3x3 part with the
// handedness flipped when M mirrors. Fails when the 3x3 part is singular.
bool transform_mesh(TriMesh& mesh, const Mat4& m) {
    double a[3][3];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) a[r][c] = m[c * 4 + r];
    const double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                       a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                       a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    if (!(std::abs(det) > 1e-30) || !std::isfinite(det)) return false;
    // Cofactor matrix = det * inverse transpose; its direction is what normals need.
    double n[3][3];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            const int r1 = (r + 1) % 3, r2 = (r + 2) % 3, c1 = (c + 1) % 3, c2 = (c + 2) % 3;
            n[r][c] = (a[r1][c1] * a[r2][c2] - a[r1][c2] * a[r2][c1]) * (det < 0 ? -1.0 : 1.0);
        }
    const auto apply = [](const double (&mat)[3][3], const float* v, float* out, bool normalise) {
        double o[3];
        for (int r = 0; r < 3; ++r) o[r] = mat[r][0] * v[0] + mat[r][1] * v[1] + mat[r][2] * v[2];
        double l = normalise ? std::sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]) : 1.0;
        if (!(l > 0)) l = 1.0;
        for (int r = 0; r < 3; ++r) out[r] = float(o[r] / l);
    };
    for (size_t v = 0; v < mesh.vertex_count(); ++v) {
        float* p = &mesh.positions[3 * v];
        const float x[3] = {p[0], p[1], p[2]};
        apply(a, x, p, false);
        for (int r = 0; r < 3; ++r) p[r] += float(m[12 + r]);
    }
    for (size_t v = 0; v < mesh.normals.size() / 3; ++v) {
        const float x[3] = {mesh.normals[3 * v], mesh.normals[3 * v + 1], mesh.normals[3 * v + 2]};
        apply(n, x, &mesh.normals[3 * v], true);
    }
    for (size_t v = 0; v < mesh.tangents.size() / 4; ++v) {
        float* t = &mesh.tangents[4 * v];
        const float x[3] = {t[0], t[1], t[2]};
        apply(a, x, t, true);
        if (det < 0) t[3] = -t[3];
    }
    return true;
}

// A mesh in object space with the world transform of one node that instances it.
struct Instance {
    TriMesh mesh;
    Mat4 world;
    std::string label;
};

struct LoadedMaterial {
    float roughness = 1.0f;
    int normal_map = -1;
    int roughness_map = -1;
    SimGlints glints;
};

// Decoded maps, shared by every material that references the same image.
class MapCache {
public:
    MapCache(SimScene& scene) : scene_(scene) {}

    // Normal map from encoded pixels: glTF normalTexture scale applied to x and y (glTF 2.0 Sec. 3.9.3),
    // z rebuilt for two-channel maps, re-encoded as (n + 1) / 2 in 3 channels.
    Result<int> normal_map(const std::string& key, const Image& decoded, double scale) {
        const std::string k = key + "#" + std::to_string(scale);
        if (auto it = normal_.find(k); it != normal_.end()) return it->second;
        if (decoded.channels < 2) return make_error("a normal map needs 2 or more channels, it has 1");
        Image out(decoded.width, decoded.height, 3);
        for (size_t i = 0; i < decoded.texel_count(); ++i) {
            const float* c = &decoded.pixels[i * size_t(decoded.channels)];
            const double x = (2.0 * c[0] - 1.0) * scale, y = (2.0 * c[1] - 1.0) * scale;
            const double z = decoded.channels >= 3 ? 2.0 * c[2] - 1.0 : std::sqrt(std::max(0.0, 1.0 - x * x - y * y));
            double l = std::sqrt(x * x + y * y + z * z);
            const bool ok = std::isfinite(l) && l > 0;
            if (!ok) l = 1.0;
            float* o = &out.pixels[i * 3];
            o[0] = ok ? float(0.5 * (x / l + 1.0)) : 0.5f;
            o[1] = ok ? float(0.5 * (y / l + 1.0)) : 0.5f;
            o[2] = ok ? float(0.5 * (z / l + 1.0)) : 1.0f;
        }
        scene_.normal_maps.push_back(std::move(out));
        return normal_[k] = int(scene_.normal_maps.size() - 1);
    }

    // Roughness map: `channel` of the decoded image times `factor` (glTF metallicRoughness: G).
    int roughness_map(const std::string& key, const Image& decoded, int channel, float factor) {
        const std::string k = key + "#" + std::to_string(channel) + "#" + std::to_string(factor);
        if (auto it = roughness_.find(k); it != roughness_.end()) return it->second;
        Image out(decoded.width, decoded.height, 1);
        const int c = std::min(channel, decoded.channels - 1);
        for (size_t i = 0; i < decoded.texel_count(); ++i) {
            const float v = decoded.pixels[i * size_t(decoded.channels) + size_t(c)] * factor;
            out.pixels[i] = std::isfinite(v) ? std::clamp(v, kMinRoughness, 1.0f) : 1.0f;
            if (v < kMinRoughness) ++clamped_texels;
        }
        scene_.roughness_maps.push_back(std::move(out));
        return roughness_[k] = int(scene_.roughness_maps.size() - 1);
    }

    long long clamped_texels = 0;  // roughness texels raised to kMinRoughness

private:
    SimScene& scene_;
    std::map<std::string, int> normal_, roughness_;
};

void note_clamps(SimScene& scene, const std::string& file, int materials, long long texels) {
    if (materials == 0 && texels == 0) return;
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.3g", double(kMinRoughness));
    scene.notes.push_back(file + ": roughness below " + buf + " raised to " + buf + " (" + std::to_string(materials) +
                          " materials, " + std::to_string(texels) + " texels): a mirror under a punctual light "
                          "has no finite ground truth");
}

Result<nlohmann::json> read_gltf_json(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return make_error(path.string() + ": cannot open");
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::string text = bytes;
    if (bytes.size() >= 20 && std::memcmp(bytes.data(), "glTF", 4) == 0) {
        uint32_t length = 0, type = 0;
        std::memcpy(&length, bytes.data() + 12, 4);
        std::memcpy(&type, bytes.data() + 16, 4);
        if (type != 0x4E4F534Au || size_t(length) > bytes.size() - 20)
            return make_error(path.string() + ": GLB without a JSON chunk");
        text = bytes.substr(20, length);
    }
    auto json = nlohmann::json::parse(text, nullptr, false);
    if (json.is_discarded() || !json.is_object()) return make_error(path.string() + ": not valid glTF JSON");
    return json;
}

double number_or(const nlohmann::json& j, const char* key, double fallback) {
    return j.contains(key) && j[key].is_number() ? j[key].get<double>() : fallback;
}

// Reads one texture slot's map; a note instead when the simulator cannot sample it as the file means.
std::optional<Image> slot_image(const io::GltfScene& gltf, const io::TextureSlot& slot, const char* what,
                                const io::InputLimits& limits, std::map<int, Image>& decoded,
                                std::vector<std::string>& notes, std::string& error) {
    if (slot.texture < 0) return std::nullopt;
    if (slot.image < 0) {
        notes.push_back(std::string(what) + " texture " + std::to_string(slot.texture) + " has no image: not simulated");
        return std::nullopt;
    }
    if (slot.texcoord != 0 || slot.transformed) {
        notes.push_back(std::string(what) + " texture " + std::to_string(slot.texture) +
                        (slot.texcoord != 0 ? " uses TEXCOORD_" + std::to_string(slot.texcoord)
                                            : std::string(" has KHR_texture_transform")) +
                        ": not simulated");
        return std::nullopt;
    }
    if (auto it = decoded.find(slot.image); it != decoded.end()) return it->second;
    auto bytes = gltf.image_bytes(slot.image);
    if (!bytes) {
        error = bytes.error().message;
        return std::nullopt;
    }
    auto image = io::read_image_memory(*bytes, gltf.image_label(slot.image), limits);
    if (!image) {
        error = image.error().message;
        return std::nullopt;
    }
    return decoded[slot.image] = std::move(*image);
}

struct FileCamera {
    Mat4 world;
    double yfov = 0.0;
};

struct GltfContents {
    std::vector<Instance> instances;
    std::vector<LoadedMaterial> materials;
    std::optional<FileCamera> camera;
};

// The scene's materials into out.materials: roughness (clamped to the simulator's minimum), normal and
// roughness maps through the cache, and the glints of the materials that ask for them (SPECBAKE_glints,
// io/gltf/SPECBAKE_EXTENSION.md).
Result<void> load_gltf_materials(const io::GltfScene& loaded, const fs::path& path, const io::InputLimits& limits,
                                 SimScene& scene, GltfContents& out) {
    MapCache cache(scene);
    std::map<int, Image> decoded;
    int clamped_materials = 0;
    for (const io::MaterialInfo& m : loaded.materials()) {
        LoadedMaterial mat;
        mat.roughness = float(std::clamp(m.roughness_factor, 0.0, 1.0));
        if (mat.roughness < kMinRoughness) ++clamped_materials;
        std::string error;
        if (auto image = slot_image(loaded, m.normal, "normal", limits, decoded, scene.notes, error)) {
            auto index = cache.normal_map("image" + std::to_string(m.normal.image), *image, m.normal_scale);
            if (!index) return make_error(loaded.image_label(m.normal.image) + ": " + index.error().message);
            mat.normal_map = *index;
        }
        if (!error.empty()) return make_error(error);
        if (auto image = slot_image(loaded, m.metallic_roughness, "metallicRoughness", limits, decoded, scene.notes,
                                    error))
            mat.roughness_map = cache.roughness_map("image" + std::to_string(m.metallic_roughness.image), *image,
                                                    image->channels >= 2 ? 1 : 0, mat.roughness);
        if (!error.empty()) return make_error(error);
        mat.roughness = std::max(mat.roughness, kMinRoughness);
        if (!m.glints.is_null()) {
            const std::string where = path.string() + ": material " + std::to_string(out.materials.size());
            auto g = io::parse_glint_extension(m.glints, where);
            if (!g) return g.error();
            if (g->texcoord != 0) {
                scene.notes.push_back(where + ": glints on TEXCOORD_" + std::to_string(g->texcoord) + ": not simulated");
            } else {
                mat.glints = {true, float(g->log_density), float(g->relative_area), float(g->density_randomization),
                              float(g->uv_scale), g->target == "ggx"};
            }
        }
        out.materials.push_back(mat);
    }
    note_clamps(scene, path.filename().string(), clamped_materials, cache.clamped_texels);
    return {};
}

// The nodes a walk of the glTF's node graph starts from: the default scene's (or the first's), or without
// scenes every node that is no node's child.
std::vector<int> root_nodes(const nlohmann::json& j, const nlohmann::json& nodes) {
    std::vector<int> roots;
    if (j.contains("scenes") && j["scenes"].is_array() && !j["scenes"].empty()) {
        const int s = int(number_or(j, "scene", 0));
        const nlohmann::json& sc = j["scenes"][size_t(std::clamp(s, 0, int(j["scenes"].size()) - 1))];
        if (sc.contains("nodes")) for (const auto& n : sc["nodes"]) roots.push_back(n.get<int>());
    } else {
        std::vector<bool> child(nodes.size(), false);
        for (const auto& n : nodes)
            if (n.contains("children")) for (const auto& c : n["children"]) child[size_t(c.get<int>())] = true;
        for (size_t n = 0; n < nodes.size(); ++n) if (!child[n]) roots.push_back(int(n));
    }
    return roots;
}

// A KHR_lights_punctual light `def` placed by a node with world transform `world`.
SimLight punctual_light(const nlohmann::json& def, const Mat4& world) {
    SimLight light;
    const std::string type = def.value("type", "");
    light.type = type == "point" ? SimLight::Type::Point
                 : type == "spot" ? SimLight::Type::Spot
                                  : SimLight::Type::Directional;
    double rgb[3] = {1, 1, 1};
    if (def.contains("color")) for (int i = 0; i < 3; ++i) rgb[i] = def["color"][i].get<double>();
    // Luminance of the light colour (Rec. 709 weights) times its intensity.
    light.radiance = float(number_or(def, "intensity", 1.0) * (0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]));
    light.range = float(number_or(def, "range", 0.0));
    const Float3 minus_z = unit(column(world, 2));
    light.position = column(world, 3);
    if (light.type == SimLight::Type::Directional) light.direction = minus_z;  // towards the light
    else light.direction = {-minus_z[0], -minus_z[1], -minus_z[2]};            // spot axis
    if (def.contains("spot")) {
        light.inner_cone = float(number_or(def["spot"], "innerConeAngle", 0.0));
        light.outer_cone = float(number_or(def["spot"], "outerConeAngle", std::numbers::pi / 4));
    }
    return light;
}

// The first perspective camera a node references becomes the scene's camera (an orthographic one is
// noted and skipped).
void read_node_camera(const nlohmann::json& j, const nlohmann::json& node, const Mat4& world, const std::string& file,
                      SimScene& scene, GltfContents& out) {
    const int c = node["camera"].get<int>();
    if (!j.contains("cameras") || c < 0 || size_t(c) >= j["cameras"].size()) return;
    const nlohmann::json& cam = j["cameras"][size_t(c)];
    if (cam.value("type", "") == "perspective" && cam.contains("perspective"))
        out.camera = FileCamera{world, number_or(cam["perspective"], "yfov", 0.7)};
    else
        scene.notes.push_back(file + ": camera " + std::to_string(c) +
                              " is orthographic, not simulated (automatic orbit instead)");
}

Result<void> load_gltf(const fs::path& path, const io::InputPolicy& policy, SimScene& scene, GltfContents& out) {
    auto loaded = io::GltfScene::load(path, policy);
    if (!loaded) return loaded.error();
    // io::GltfScene reads primitives, materials and images; the node graph, cameras and lights, which only
    // the simulator needs, are read from the same JSON here.
    auto json = read_gltf_json(path);
    if (!json) return json.error();
    const nlohmann::json& j = *json;
    const std::string file = path.filename().string();
    if (auto materials = load_gltf_materials(*loaded, path, policy.limits, scene, out); !materials) return materials;

    // Lights of KHR_lights_punctual, placed by the nodes that reference them.
    const nlohmann::json* light_defs = nullptr;
    if (j.contains("extensions") && j["extensions"].contains("KHR_lights_punctual") &&
        j["extensions"]["KHR_lights_punctual"].contains("lights"))
        light_defs = &j["extensions"]["KHR_lights_punctual"]["lights"];

    const nlohmann::json empty = nlohmann::json::array();
    const nlohmann::json& nodes = j.contains("nodes") ? j["nodes"] : empty;
    const std::vector<int> roots = root_nodes(j, nodes);
    const auto primitives = loaded->primitives();
    bool skinned_or_animated = j.contains("animations") && !j["animations"].empty();
    std::vector<std::pair<int, Mat4>> stack;
    for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.push_back({*it, kIdentity});
    size_t visited = 0;
    while (!stack.empty()) {
        auto [index, parent] = stack.back();
        stack.pop_back();
        // glTF nodes have at most one parent, so a walk longer than the node count has met a cycle.
        if (index < 0 || size_t(index) >= nodes.size() || ++visited > nodes.size())
            return make_error(path.string() + ": node hierarchy is broken (bad index or a cycle)");
        const nlohmann::json& node = nodes[size_t(index)];
        const Mat4 world = multiply(parent, local_transform(node));
        if (node.contains("skin")) skinned_or_animated = true;
        if (node.contains("mesh")) {
            const int mesh = node["mesh"].get<int>();
            for (const io::PrimitiveInfo& p : primitives) {
                if (p.ref.mesh != mesh) continue;
                if (p.mode != 4 && p.mode != 5 && p.mode != 6) {
                    scene.notes.push_back(p.label + ": points or lines, not simulated");
                    continue;
                }
                auto tri = loaded->primitive_mesh(p.ref);
                if (!tri) return tri.error();
                tri->material = p.material;
                out.instances.push_back({std::move(*tri), world, p.label});
            }
        }
        if (node.contains("camera") && !out.camera) read_node_camera(j, node, world, file, scene, out);
        if (light_defs && node.contains("extensions") && node["extensions"].contains("KHR_lights_punctual")) {
            const int l = node["extensions"]["KHR_lights_punctual"].value("light", -1);
            if (l >= 0 && size_t(l) < light_defs->size()) scene.lights.push_back(punctual_light((*light_defs)[size_t(l)], world));
        }
        if (node.contains("children"))
            for (auto c = node["children"].rbegin(); c != node["children"].rend(); ++c)
                stack.push_back({c->get<int>(), world});
    }
    if (skinned_or_animated) scene.notes.push_back(file + ": animations and skins are not simulated (rest pose)");
    return {};
}

Result<void> load_imported(const fs::path& path, const io::InputPolicy& policy, SimScene& scene,
                           GltfContents& out) {
    auto imported = import_mesh(path.string(), {}, policy);
    if (!imported) return imported.error();
    for (const std::string& note : imported->notes) scene.notes.push_back(note);
    MapCache cache(scene);
    int clamped_materials = 0;
    for (const ImportedMaterial& m : imported->materials) {
        LoadedMaterial mat;
        mat.roughness = std::clamp(m.roughness_factor, 0.0f, 1.0f);
        if (mat.roughness < kMinRoughness) ++clamped_materials;
        mat.roughness = std::max(mat.roughness, kMinRoughness);
        // The files were resolved by the path policy at import (io/mesh_import/mesh_import.h).
        const auto read = [&](const std::string& ref, const fs::path& file) -> Result<Image> {
            if (file.empty()) return make_error("embedded texture " + ref);
            return io::read_image(file, policy.limits);
        };
        if (m.has_normal_texture) {
            auto image = read(m.normal_texture, m.normal_texture_file);
            if (!image) {
                scene.notes.push_back(m.name + ": normal texture not simulated (" + image.error().message + ")");
            } else {
                auto index = cache.normal_map(m.normal_texture, *image, 1.0);
                if (!index) return make_error(m.normal_texture + ": " + index.error().message);
                mat.normal_map = *index;
            }
        }
        if (m.has_roughness_texture) {
            auto image = read(m.roughness_texture, m.roughness_texture_file);
            if (!image) scene.notes.push_back(m.name + ": roughness texture not simulated (" + image.error().message + ")");
            else mat.roughness_map = cache.roughness_map(m.roughness_texture, *image, image->channels >= 2 ? 1 : 0, mat.roughness);
        }
        out.materials.push_back(mat);
    }
    note_clamps(scene, path.filename().string(), clamped_materials, cache.clamped_texels);
    std::vector<Mat4> world(imported->nodes.size(), kIdentity);
    for (size_t n = 0; n < imported->nodes.size(); ++n) {
        const ImportedNode& node = imported->nodes[n];
        Mat4 local;
        for (int i = 0; i < 16; ++i) local[i] = node.local_transform[i];
        // Assimp lists parents before their children.
        world[n] = node.parent >= 0 && size_t(node.parent) < n ? multiply(world[size_t(node.parent)], local) : local;
        for (int m : node.meshes)
            out.instances.push_back({imported->meshes[size_t(m)], world[n], imported->meshes[size_t(m)].name});
    }
    return {};
}

}  // namespace

Result<SimScene> load_sim_scene(const fs::path& path, const io::InputPolicy& policy) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) return make_error(path.string() + ": no such file");
    SimScene scene;
    scene.name = path.stem().string();
    scene.from_file = true;
    GltfContents contents;
    const std::string ext = io::lower_extension(path);
    auto loaded = ext == ".gltf" || ext == ".glb" ? load_gltf(path, policy, scene, contents)
                                                  : load_imported(path, policy, scene, contents);
    if (!loaded) return loaded.error();

    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (Instance& instance : contents.instances) {
        TriMesh& mesh = instance.mesh;
        const int material = mesh.material;
        auto report = prepare_mesh_for_curvature(mesh);
        if (!report) return report.error();
        if (!mesh.has_uv0()) mesh.uv0.assign(mesh.vertex_count() * 2, 0.0f);
        if (!transform_mesh(mesh, instance.world)) {
            scene.notes.push_back(instance.label + ": singular node transform, not simulated");
            continue;
        }
        for (size_t v = 0; v < mesh.vertex_count(); ++v)
            for (int a = 0; a < 3; ++a) {
                lo[a] = std::min(lo[a], double(mesh.positions[3 * v + a]));
                hi[a] = std::max(hi[a], double(mesh.positions[3 * v + a]));
            }
        SimObject object;
        object.mesh = std::move(mesh);
        if (material >= 0 && size_t(material) < contents.materials.size()) {
            const LoadedMaterial& m = contents.materials[size_t(material)];
            object.material.roughness = m.roughness;
            object.material.normal_map = object.mesh.has_uv0() ? m.normal_map : -1;
            object.material.roughness_map = m.roughness_map;
            object.material.glints = m.glints;
        } else {
            object.material.roughness = 1.0f;  // glTF default material: roughnessFactor 1
        }
        scene.objects.push_back(std::move(object));
    }
    if (scene.objects.empty()) return make_error(path.string() + ": no triangles to simulate");

    const Float3 centre{float(0.5 * (lo[0] + hi[0])), float(0.5 * (lo[1] + hi[1])), float(0.5 * (lo[2] + hi[2]))};
    float radius = 0;
    for (const SimObject& o : scene.objects)
        for (size_t v = 0; v < o.mesh.vertex_count(); ++v) {
            const float* p = &o.mesh.positions[3 * v];
            const Float3 d{p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]};
            radius = std::max(radius, std::sqrt(dot3(d, d)));
        }
    scene.object_radius = std::max(radius, 1e-6f);

    if (contents.camera) {
        const Mat4& w = contents.camera->world;
        SimCamera& cam = scene.camera;
        cam.position = column(w, 3);
        const Float3 z = unit(column(w, 2));
        const Float3 forward{-z[0], -z[1], -z[2]};
        cam.up = unit(column(w, 1));
        cam.fov_y_degrees = float(contents.camera->yfov * 180.0 / std::numbers::pi);
        // Orbit (for the temporal metric) about the point straight ahead at the depth of the scene centre.
        const Float3 to_centre{centre[0] - cam.position[0], centre[1] - cam.position[1], centre[2] - cam.position[2]};
        const float depth = std::max(dot3(to_centre, forward), 0.1f * scene.object_radius);
        cam.target = {cam.position[0] + forward[0] * depth, cam.position[1] + forward[1] * depth,
                      cam.position[2] + forward[2] * depth};
    } else {
        // Automatic orbit: the bounding sphere fills about 5/6 of the view height (its silhouette stays
        // clear of the border and the pixel filter), seen from the front (+Z, glTF's front), slightly from above.
        SimCamera& cam = scene.camera;
        cam.fov_y_degrees = 40.0f;
        cam.target = centre;
        cam.up = {0, 1, 0};
        const Float3 dir = unit({0.0f, 0.35f, 1.0f});
        const float distance = 1.2f * scene.object_radius / std::sin(0.5f * cam.fov_y_degrees * std::numbers::pi_v<float> / 180.0f);
        cam.position = {centre[0] + dir[0] * distance, centre[1] + dir[1] * distance, centre[2] + dir[2] * distance};
    }
    if (scene.lights.empty()) {
        // One directional key light from the upper left of the camera, like the built-in scenes.
        const Float3 back = unit({scene.camera.position[0] - scene.camera.target[0],
                                  scene.camera.position[1] - scene.camera.target[1],
                                  scene.camera.position[2] - scene.camera.target[2]});
        const Float3 right = unit(cross3(scene.camera.up, back));
        const Float3 up = cross3(back, right);
        SimLight light;
        for (int i = 0; i < 3; ++i) light.direction[i] = -0.45f * right[i] + 0.65f * up[i] + 0.6f * back[i];
        light.direction = unit(light.direction);
        scene.lights.push_back(light);
        scene.notes.push_back(path.filename().string() + ": no KHR_lights_punctual lights, one default directional light");
    }
    if (scene.lights.size() > kMaxSimLights) {
        scene.notes.push_back(path.filename().string() + ": " + std::to_string(scene.lights.size()) +
                              " lights, the first " + std::to_string(kMaxSimLights) + " simulated");
        scene.lights.resize(kMaxSimLights);
    }
    return scene;
}

}  // namespace specbake::verify
