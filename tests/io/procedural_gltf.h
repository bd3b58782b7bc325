// Procedural glTF models written with tinygltf directly, independently of specbake's writer: a UV sphere or
// a flat grid with one material, for the scene tests and as the scene benchmark's input.
#pragma once

#include <tiny_gltf.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <vector>

namespace specbake::testing {

// Appends `bytes` from `src` to buffer 0 of `m` as a new buffer view (bufferView.target `target`, 0 for
// none) with an accessor over it; returns the accessor's index.
inline int append_accessor(tinygltf::Model& m, const void* src, size_t bytes, int type, int component_type,
                           size_t count, int target = 0) {
    std::vector<unsigned char>& data = m.buffers[0].data;
    tinygltf::BufferView bv;
    bv.buffer = 0;
    bv.byteOffset = data.size();
    bv.byteLength = bytes;
    bv.target = target;
    const auto* b = static_cast<const uint8_t*>(src);
    data.insert(data.end(), b, b + bytes);
    m.bufferViews.push_back(bv);
    tinygltf::Accessor a;
    a.bufferView = int(m.bufferViews.size() - 1);
    a.componentType = component_type;
    a.type = type;
    a.count = count;
    m.accessors.push_back(a);
    return int(m.accessors.size() - 1);
}

struct ProceduralModel {
    // A UV sphere of radius `size` (outward normals, poles on y), else a `size` x `size` grid in the plane
    // y = 0 facing +y; (rings + 1) x (segments + 1) vertices with UVs, no tangents, one material.
    bool sphere = true;
    double size = 1.0;
    int rings = 48, segments = 96;
    double roughness = 0.5, metallic = 0.0;
    // Only what glTF requires: no names, no bufferView targets, no default scene.
    bool minimal = false;
};

// A .gltf path gets pretty-printed JSON and its buffer as <stem>.bin beside it; a .glb path one
// self-contained binary file. Returns false when tinygltf cannot write.
inline bool write_procedural_model(const std::filesystem::path& path, const ProceduralModel& spec) {
    const double radius = spec.size;
    const int rings = spec.rings, segments = spec.segments;
    std::vector<float> pos, nrm, uv;
    std::vector<uint32_t> idx;
    for (int r = 0; r <= rings; ++r) {
        for (int s = 0; s <= segments; ++s) {
            const double u = double(s) / segments, v = double(r) / rings;
            if (spec.sphere) {
                const double theta = v * M_PI, phi = u * 2 * M_PI;
                const double n[3] = {std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)};
                for (int k = 0; k < 3; ++k) pos.push_back(float(radius * n[k])), nrm.push_back(float(n[k]));
            } else {
                pos.insert(pos.end(), {float(u * radius), 0.0f, float(v * radius)});
                nrm.insert(nrm.end(), {0.0f, 1.0f, 0.0f});
            }
            uv.insert(uv.end(), {float(u), float(v)});
        }
    }
    for (int r = 0; r < rings; ++r)
        for (int s = 0; s < segments; ++s) {
            const uint32_t a = uint32_t(r * (segments + 1) + s), b = a + 1, c = a + uint32_t(segments + 1), d = c + 1;
            idx.insert(idx.end(), {a, c, b, b, c, d});
        }
    const bool glb = path.extension() == ".glb";
    tinygltf::Model m;
    m.asset.version = "2.0";
    m.buffers.emplace_back();
    if (!glb) m.buffers[0].uri = path.stem().string() + ".bin";
    const int vertex_target = spec.minimal ? 0 : TINYGLTF_TARGET_ARRAY_BUFFER;
    const int index_target = spec.minimal ? 0 : TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER;
    const size_t nv = pos.size() / 3;
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    prim.attributes["POSITION"] = append_accessor(m, pos.data(), pos.size() * 4, TINYGLTF_TYPE_VEC3,
                                                  TINYGLTF_COMPONENT_TYPE_FLOAT, nv, vertex_target);
    m.accessors.back().minValues = {-radius, -radius, -radius};
    m.accessors.back().maxValues = {radius, radius, radius};
    prim.attributes["NORMAL"] = append_accessor(m, nrm.data(), nrm.size() * 4, TINYGLTF_TYPE_VEC3,
                                                TINYGLTF_COMPONENT_TYPE_FLOAT, nv, vertex_target);
    prim.attributes["TEXCOORD_0"] = append_accessor(m, uv.data(), uv.size() * 4, TINYGLTF_TYPE_VEC2,
                                                    TINYGLTF_COMPONENT_TYPE_FLOAT, nv, vertex_target);
    prim.indices = append_accessor(m, idx.data(), idx.size() * 4, TINYGLTF_TYPE_SCALAR,
                                   TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, idx.size(), index_target);
    prim.material = 0;
    tinygltf::Material mat;
    if (!spec.minimal) mat.name = "test";
    mat.pbrMetallicRoughness.roughnessFactor = spec.roughness;
    mat.pbrMetallicRoughness.metallicFactor = spec.metallic;
    m.materials.push_back(mat);
    tinygltf::Mesh mesh;
    if (!spec.minimal) mesh.name = spec.sphere ? "sphere" : "plane";
    mesh.primitives.push_back(prim);
    m.meshes.push_back(mesh);
    tinygltf::Node node;
    node.mesh = 0;
    m.nodes.push_back(node);
    tinygltf::Scene scene;
    scene.nodes = {0};
    m.scenes.push_back(scene);
    if (!spec.minimal) m.defaultScene = 0;
    tinygltf::TinyGLTF writer;
    return glb ? writer.WriteGltfSceneToFile(&m, path.string(), true, true, false, true)
               : writer.WriteGltfSceneToFile(&m, path.string(), false, false, true, false);
}

}  // namespace specbake::testing
