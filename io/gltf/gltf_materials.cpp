// The materials of a scene as the bake reads them: normal and metallic-roughness texture slots (with
// KHR_texture_transform), their factors, and KHR_materials_clearcoat.
#include "io/gltf/gltf_internal.h"

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
            if (it->second.Has("texCoord")) s.texcoord = it->second.Get("texCoord").GetNumberAsInt();
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

}  // namespace specbake::io
