// The glTF-valid replacement mode's edit of a material: its normal and metallic-roughness slots refer to
// new textures carrying the baked chains through KHR_texture_basisu (KTX2, UASTC), each with a fallback
// image so viewers without the extension still load the file (the extension stays out of
// extensionsRequired, KHR_texture_basisu Sec. "Using Without a Fallback").
#include "io/gltf/gltf_internal.h"

#include <algorithm>

namespace specbake::io {
namespace {

constexpr const char* kBasisu = "KHR_texture_basisu";
constexpr int kLinear = 9729, kLinearMipmapLinear = 9987, kRepeat = 10497;

void add_used(tinygltf::Model& m, const std::string& name) {
    if (std::find(m.extensionsUsed.begin(), m.extensionsUsed.end(), name) == m.extensionsUsed.end())
        m.extensionsUsed.push_back(name);
}

// The image for the file `uri` (one per file: a second call returns the first); with `embed_from` set it is
// recorded as that folder's file, so a GLB carries it on a buffer view (io/gltf/gltf_buffers.cpp) like the
// input's external images.
int add_image(gltf::SceneState& scene, const std::string& uri, const std::string& mime,
              const std::filesystem::path& embed_from) {
    if (auto it = scene.basisu_images.find(uri); it != scene.basisu_images.end()) return it->second;
    tinygltf::Model& m = scene.model;
    tinygltf::Image img;
    img.uri = uri;
    img.mimeType = mime;
    m.images.push_back(std::move(img));
    scene.image_paths.resize(m.images.size());
    if (!embed_from.empty()) scene.image_paths.back() = embed_from / uri;
    scene.basisu_images[uri] = int(m.images.size()) - 1;
    return int(m.images.size()) - 1;
}

// A new texture for the KTX2 file `uri`, replacing texture `old` (-1: none) of a slot; its fallback
// source is the PNG `fallback_uri`, or the old texture's image when that is empty.
int add_basisu_texture(gltf::SceneState& scene, int old, const std::string& uri, const std::string& fallback_uri,
                       const std::filesystem::path& embed_from) {
    tinygltf::Model& m = scene.model;
    const int old_source = old >= 0 && size_t(old) < m.textures.size() ? m.textures[size_t(old)].source : -1;
    const std::pair<std::string, std::string> key{uri, fallback_uri.empty() ? "image " + std::to_string(old_source) : fallback_uri};
    if (auto it = scene.basisu_textures.find(key); it != scene.basisu_textures.end()) return it->second;
    tinygltf::Sampler sampler;
    sampler.magFilter = kLinear;
    sampler.minFilter = kLinearMipmapLinear;  // the baked levels are what must be sampled
    sampler.wrapS = sampler.wrapT = kRepeat;
    int fallback = -1;
    if (old >= 0 && size_t(old) < m.textures.size()) {
        const tinygltf::Texture& t = m.textures[size_t(old)];
        if (t.sampler >= 0 && size_t(t.sampler) < m.samplers.size()) {
            sampler.wrapS = m.samplers[size_t(t.sampler)].wrapS;
            sampler.wrapT = m.samplers[size_t(t.sampler)].wrapT;
        }
        fallback = t.source;
    }
    if (!fallback_uri.empty()) fallback = add_image(scene, fallback_uri, "image/png", embed_from);
    m.samplers.push_back(sampler);
    tinygltf::Texture tex;
    tex.sampler = int(m.samplers.size()) - 1;
    tex.source = fallback;
    tinygltf::Value::Object ext;
    ext["source"] = tinygltf::Value(add_image(scene, uri, "image/ktx2", embed_from));
    tex.extensions[kBasisu] = tinygltf::Value(std::move(ext));
    m.textures.push_back(std::move(tex));
    scene.basisu_textures[key] = int(m.textures.size()) - 1;
    return int(m.textures.size()) - 1;
}

template <class Info>
void point_slot(Info& info, int texture, const GltfScene::BasisuTextures& t) {
    info.index = texture;
    info.texCoord = t.texcoord;
    if (t.transform.is_null()) info.extensions.erase("KHR_texture_transform");
    else info.extensions["KHR_texture_transform"] = gltf::to_value(t.transform);
}

}  // namespace

void GltfScene::use_basisu_textures(int material, const BasisuTextures& t) {
    tinygltf::Model& m = impl_->model;
    if (material < 0 || size_t(material) >= m.materials.size()) return;
    tinygltf::Material& mat = m.materials[size_t(material)];
    if (!t.normal_uri.empty()) {
        const int tex = add_basisu_texture(*impl_, mat.normalTexture.index, t.normal_uri, t.normal_fallback_uri,
                                             t.embed_from);
        point_slot(mat.normalTexture, tex, t);
        mat.normalTexture.scale = 1.0;  // the bake applied it (glTF: n = normalize((2c - 1) * (s, s, 1)))
    }
    if (!t.roughness_uri.empty()) {
        auto& pbr = mat.pbrMetallicRoughness;
        const int tex = add_basisu_texture(*impl_, pbr.metallicRoughnessTexture.index, t.roughness_uri,
                                             t.roughness_fallback_uri, t.embed_from);
        point_slot(pbr.metallicRoughnessTexture, tex, t);
        pbr.roughnessFactor = 1.0;  // the baked r already holds the factor
    }
    if (!t.transform.is_null()) add_used(m, "KHR_texture_transform");
    add_used(m, kBasisu);
}

}  // namespace specbake::io
