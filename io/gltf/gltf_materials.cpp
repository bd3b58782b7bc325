// The materials of a scene as the bake reads them: normal and metallic-roughness texture slots (with
// KHR_texture_transform), their factors, and KHR_materials_clearcoat.
#include "io/gltf/gltf_internal.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace specbake::io {
using gltf::from_value;
using gltf::to_value;
using nlohmann::json;

std::vector<MaterialInfo> GltfScene::materials() const {
    const tinygltf::Model& m = impl_->model;
    auto slot = [&](int texture, int texcoord, const tinygltf::ExtensionMap& ext) {
        TextureSlot s;
        if (texture < 0 || size_t(texture) >= m.textures.size()) return s;
        s.texture = texture;
        const int src = m.textures[size_t(texture)].source;
        s.image = src >= 0 && size_t(src) < m.images.size() ? src : -1;
        s.texcoord = texcoord;
        auto it = ext.find("KHR_texture_transform");
        s.transformed = it != ext.end();
        if (s.transformed) {
            s.transform = from_value(it->second);
            const json& t = s.transform;
            if (t.contains("texCoord") && t["texCoord"].is_number_integer()) s.texcoord = t["texCoord"].get<int>();
            auto pair = [&](const char* key, std::array<double, 2>& v) {
                if (t.contains(key) && t[key].is_array() && t[key].size() == 2 && t[key][0].is_number() && t[key][1].is_number())
                    v = {t[key][0].get<double>(), t[key][1].get<double>()};
            };
            pair("offset", s.offset);
            pair("scale", s.scale);
            if (t.contains("rotation") && t["rotation"].is_number()) s.rotation = t["rotation"].get<double>();
        }
        return s;
    };
    // A textureInfo object inside an extension (tinygltf leaves those as JSON values).
    auto slot_json = [&](const json& info) {
        if (!info.is_object() || !info.contains("index") || !info["index"].is_number_integer()) return TextureSlot();
        tinygltf::ExtensionMap ext;
        if (info.contains("extensions") && info["extensions"].is_object())
            for (auto it = info["extensions"].begin(); it != info["extensions"].end(); ++it) ext[it.key()] = to_value(it.value());
        const int texcoord = info.contains("texCoord") && info["texCoord"].is_number_integer() ? info["texCoord"].get<int>() : 0;
        return slot(info["index"].get<int>(), texcoord, ext);
    };
    std::vector<MaterialInfo> out;
    out.reserve(m.materials.size());
    for (const tinygltf::Material& mat : m.materials) {
        MaterialInfo info;
        info.name = mat.name;
        info.normal = slot(mat.normalTexture.index, mat.normalTexture.texCoord, mat.normalTexture.extensions);
        info.normal_scale = mat.normalTexture.scale;
        const auto& pbr = mat.pbrMetallicRoughness;
        info.metallic_roughness = slot(pbr.metallicRoughnessTexture.index, pbr.metallicRoughnessTexture.texCoord,
                                       pbr.metallicRoughnessTexture.extensions);
        info.roughness_factor = pbr.roughnessFactor;
        info.metallic_factor = pbr.metallicFactor;
        if (auto it = mat.extensions.find("KHR_materials_clearcoat"); it != mat.extensions.end()) {
            const json cc = from_value(it->second);
            ClearcoatInfo& c = info.clearcoat;
            c.present = true;
            auto number = [&](const char* key, double fallback) {
                return cc.contains(key) && cc[key].is_number() ? cc[key].get<double>() : fallback;
            };
            // Defaults of KHR_materials_clearcoat: factors 0, normal scale 1, texCoord 0.
            c.factor = number("clearcoatFactor", 0.0);
            c.roughness_factor = number("clearcoatRoughnessFactor", 0.0);
            c.factor_texture = slot_json(cc.value("clearcoatTexture", json()));
            c.roughness = slot_json(cc.value("clearcoatRoughnessTexture", json()));
            const json normal = cc.value("clearcoatNormalTexture", json());
            c.normal = slot_json(normal);
            if (normal.is_object() && normal.contains("scale") && normal["scale"].is_number())
                c.normal_scale = normal["scale"].get<double>();
        }
        // SPECBAKE_glints (io/gltf/glint_extension.h): kept as JSON, parsed by the plan.
        if (auto it = mat.extensions.find("SPECBAKE_glints"); it != mat.extensions.end()) info.glints = from_value(it->second);
        out.push_back(std::move(info));
    }
    return out;
}

namespace {

bool nearly_equal(double a, double b) { return std::abs(a - b) <= 1e-6 * std::max({1.0, std::abs(a), std::abs(b)}); }

bool identity_transform(const TextureSlot& s) {
    return nearly_equal(s.offset[0], 0) && nearly_equal(s.offset[1], 0) && nearly_equal(s.rotation, 0) &&
           nearly_equal(s.scale[0], 1) && nearly_equal(s.scale[1], 1);
}

std::string number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

}  // namespace

bool same_uv_mapping(const TextureSlot& a, const TextureSlot& b) {
    return a.texcoord == b.texcoord && nearly_equal(a.offset[0], b.offset[0]) && nearly_equal(a.offset[1], b.offset[1]) &&
           nearly_equal(a.rotation, b.rotation) && nearly_equal(a.scale[0], b.scale[0]) &&
           nearly_equal(a.scale[1], b.scale[1]);
}

std::string uv_mapping_label(const TextureSlot& s) {
    std::string label = "TEXCOORD_" + std::to_string(s.texcoord);
    if (!identity_transform(s))
        label += " offset (" + number(s.offset[0]) + ", " + number(s.offset[1]) + ") rotation " + number(s.rotation) +
                 " scale (" + number(s.scale[0]) + ", " + number(s.scale[1]) + ")";
    return label;
}

json uv_transform_json(const TextureSlot& s) {
    if (identity_transform(s)) return nullptr;
    return {{"offset", {s.offset[0], s.offset[1]}}, {"rotation", s.rotation}, {"scale", {s.scale[0], s.scale[1]}}};
}

}  // namespace specbake::io
