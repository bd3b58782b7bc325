// Extension objects, which tinygltf keeps as tinygltf::Value and the API passes as nlohmann::json, converted
// both ways; and the setters of the vendor extension SPECBAKE_specular_aa (io/gltf/SPECBAKE_EXTENSION.md).
#include "io/gltf/gltf_internal.h"

#include <algorithm>

namespace specbake::io {
using nlohmann::json;

namespace gltf {

tinygltf::Value to_value(const json& j) {
    switch (j.type()) {
        case json::value_t::null: return tinygltf::Value();
        case json::value_t::boolean: return tinygltf::Value(j.get<bool>());
        case json::value_t::number_integer:
        case json::value_t::number_unsigned: return tinygltf::Value(j.get<int>());
        case json::value_t::number_float: return tinygltf::Value(j.get<double>());
        case json::value_t::string: return tinygltf::Value(j.get<std::string>());
        case json::value_t::array: {
            tinygltf::Value::Array a;
            for (const json& e : j) a.push_back(to_value(e));
            return tinygltf::Value(std::move(a));
        }
        case json::value_t::object: {
            tinygltf::Value::Object o;
            for (auto it = j.begin(); it != j.end(); ++it) o[it.key()] = to_value(it.value());
            return tinygltf::Value(std::move(o));
        }
        default: return tinygltf::Value();
    }
}

json from_value(const tinygltf::Value& v) {
    switch (v.Type()) {
        case tinygltf::BOOL_TYPE: return v.Get<bool>();
        case tinygltf::INT_TYPE: return v.Get<int>();
        case tinygltf::REAL_TYPE: return v.Get<double>();
        case tinygltf::STRING_TYPE: return v.Get<std::string>();
        case tinygltf::ARRAY_TYPE: {
            json a = json::array();
            for (size_t i = 0; i < v.ArrayLen(); ++i) a.push_back(from_value(v.Get(int(i))));
            return a;
        }
        case tinygltf::OBJECT_TYPE: {
            json o = json::object();
            for (const std::string& k : v.Keys()) o[k] = from_value(v.Get(k));
            return o;
        }
        default: return nullptr;
    }
}

}  // namespace gltf

namespace {
void add_extension_used(tinygltf::Model& m) {
    if (std::find(m.extensionsUsed.begin(), m.extensionsUsed.end(), kSpecbakeExtension) == m.extensionsUsed.end())
        m.extensionsUsed.push_back(kSpecbakeExtension);
}
}  // namespace

void GltfScene::set_material_extension(int material, const json& extension) {
    tinygltf::Model& m = impl_->model;
    if (material < 0 || size_t(material) >= m.materials.size()) return;
    m.materials[size_t(material)].extensions[kSpecbakeExtension] = gltf::to_value(extension);
    add_extension_used(m);
}

void GltfScene::set_root_extension(const json& extension) {
    impl_->model.extensions[kSpecbakeExtension] = gltf::to_value(extension);
    add_extension_used(impl_->model);
}

int GltfScene::embed_baked_image(const std::filesystem::path& file, const std::string& mime_type,
                                 const std::string& name) {
    std::vector<gltf::SceneState::BakedImage>& baked = impl_->baked_images;
    for (size_t k = 0; k < baked.size(); ++k)
        if (baked[k].file == file) return int(k);
    baked.push_back({file, mime_type, name});
    return int(baked.size() - 1);
}

}  // namespace specbake::io
