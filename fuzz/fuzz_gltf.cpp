// libFuzzer target: the glTF/GLB reader (io/gltf/gltf_scene.h). An input starting with "glTF" is a .glb, any
// other a .gltf; the scene is loaded, and every primitive, material and image is read back as a bake does.
#include "fuzz/fuzz_common.h"
#include "io/gltf/gltf_scene.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstring>

// JSON nested deeper than ~10,000 levels overflows the stack inside tinygltf's recursive JSON conversion
// (a known problem of the reader, refused by its own depth limit once that exists): inputs are kept
// below that size so the target explores everything else.
static constexpr size_t kMaxInput = 8192;

// The JSON of a .gltf, or of a .glb's first chunk; null when it does not parse (the loader says why).
static nlohmann::json scene_json(const uint8_t* data, size_t size, bool binary) {
    if (!binary) return nlohmann::json::parse(data, data + size, nullptr, false);
    if (size < 20) return nullptr;
    uint32_t length = 0;
    std::memcpy(&length, data + 12, 4);
    if (length > size - 20) return nullptr;
    return nlohmann::json::parse(data + 20, data + 20 + length, nullptr, false);
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size > kMaxInput) return -1;
    const bool binary = size >= 4 && std::memcmp(data, "glTF", 4) == 0;
    const auto path = specbake::fuzz::write_scratch(binary ? "scene.glb" : "scene.gltf", data, size);
    auto scene = specbake::io::GltfScene::load(path);
    if (!scene) return 0;
    for (const auto& p : scene->primitives()) {
        auto mesh = scene->primitive_mesh(p.ref);
        if (mesh && mesh->indices.size() % 3 != 0) __builtin_trap();  // read_mesh promises triangle lists
    }
    const auto materials = scene->materials();
    for (const auto& m : materials) {
        for (int image : {m.normal.image, m.metallic_roughness.image, m.clearcoat.normal.image,
                          m.clearcoat.roughness.image})
            if (image >= 0) {
                (void)scene->image_bytes(image);
                (void)scene->image_label(image);
            }
    }
    (void)scene->resource_files();
    (void)scene->content_hash(path);
    return 0;
}
