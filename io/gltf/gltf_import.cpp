// A new glTF scene built from an Assimp import (io/mesh_import/mesh_import.h): one triangle primitive per imported
// mesh, the node hierarchy with its matrices, and one material per imported material.
#include "io/gltf/gltf_internal.h"

#include <algorithm>
#include <array>
#include <limits>

namespace specbake::io {
using gltf::kModeTriangles;

namespace {

// The scene of the imported node hierarchy, its nodes appended to m.nodes: one glTF node per imported node;
// a node with several meshes gets one child per mesh (a glTF node holds at most one mesh); a mesh no node
// places gets a root node of its own.
tinygltf::Scene node_hierarchy(const ImportedScene& imported, tinygltf::Model& m) {
    const std::array<float, 16> identity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    tinygltf::Scene root;
    std::vector<int> node_index(imported.nodes.size(), -1);
    for (size_t i = 0; i < imported.nodes.size(); ++i) {
        const ImportedNode& in = imported.nodes[i];
        tinygltf::Node node;
        node.name = in.name;
        if (in.local_transform != identity) node.matrix.assign(in.local_transform.begin(), in.local_transform.end());
        m.nodes.push_back(node);
        node_index[i] = int(m.nodes.size() - 1);
    }
    std::vector<bool> placed(imported.meshes.size(), false);
    for (size_t i = 0; i < imported.nodes.size(); ++i) {
        const ImportedNode& in = imported.nodes[i];
        const int self = node_index[i];
        std::vector<int> meshes;
        for (int mi : in.meshes)
            if (mi >= 0 && size_t(mi) < imported.meshes.size()) meshes.push_back(mi);
        if (meshes.size() == 1) {
            m.nodes[size_t(self)].mesh = meshes[0];
        } else {
            for (int mi : meshes) {
                tinygltf::Node child;
                child.name = m.meshes[size_t(mi)].name;
                child.mesh = mi;
                m.nodes.push_back(child);
                m.nodes[size_t(self)].children.push_back(int(m.nodes.size() - 1));
            }
        }
        for (int mi : meshes) placed[size_t(mi)] = true;
        if (in.parent >= 0 && size_t(in.parent) < imported.nodes.size() && size_t(in.parent) != i)
            m.nodes[size_t(node_index[size_t(in.parent)])].children.push_back(self);
        else
            root.nodes.push_back(self);
    }
    for (size_t mi = 0; mi < placed.size(); ++mi) {
        if (placed[mi]) continue;
        tinygltf::Node node;
        node.name = m.meshes[mi].name;
        node.mesh = int(mi);
        m.nodes.push_back(node);
        root.nodes.push_back(int(m.nodes.size() - 1));
    }
    return root;
}

}  // namespace

Result<GltfScene> GltfScene::from_imported(const ImportedScene& imported) {
    GltfScene scene;
    scene.impl_->source = imported.path;
    scene.impl_->other_files = imported.files;
    tinygltf::Model& m = scene.impl_->model;
    m.asset.version = "2.0";
    m.asset.generator = "specbake (imported through Assimp)";
    m.buffers.emplace_back();
    scene.impl_->buffers.emplace_back();
    std::vector<unsigned char>& data = scene.impl_->buffers[0];

    auto add_view = [&](const void* src, size_t bytes, int target) {
        while (data.size() % 4) data.push_back(0);
        tinygltf::BufferView bv;
        bv.buffer = 0;
        bv.byteOffset = data.size();
        bv.byteLength = bytes;
        bv.target = target;
        const auto* p = static_cast<const uint8_t*>(src);
        data.insert(data.end(), p, p + bytes);
        m.bufferViews.push_back(bv);
        return int(m.bufferViews.size() - 1);
    };
    auto add_accessor = [&](const std::vector<float>& v, int nc, int type, bool bounds) {
        tinygltf::Accessor a;
        a.bufferView = add_view(v.data(), v.size() * sizeof(float), TINYGLTF_TARGET_ARRAY_BUFFER);
        a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
        a.count = v.size() / size_t(nc);
        a.type = type;
        if (bounds) {  // POSITION requires min and max (glTF 2.0 Sec. 5.1.1)
            a.minValues.assign(size_t(nc), std::numeric_limits<double>::infinity());
            a.maxValues.assign(size_t(nc), -std::numeric_limits<double>::infinity());
            for (size_t i = 0; i < v.size(); ++i) {
                a.minValues[i % nc] = std::min(a.minValues[i % nc], double(v[i]));
                a.maxValues[i % nc] = std::max(a.maxValues[i % nc], double(v[i]));
            }
        }
        m.accessors.push_back(a);
        return int(m.accessors.size() - 1);
    };

    for (const ImportedMaterial& im : imported.materials) {
        tinygltf::Material mat;
        mat.name = im.name;
        mat.pbrMetallicRoughness.metallicFactor = 0.0;
        mat.pbrMetallicRoughness.roughnessFactor = im.roughness_factor;
        m.materials.push_back(mat);
    }
    for (size_t i = 0; i < imported.meshes.size(); ++i) {
        const TriMesh& t = imported.meshes[i];
        tinygltf::Mesh mesh;
        mesh.name = t.name;
        if (t.vertex_count() == 0 || t.triangle_count() == 0) return make_error(t.name + ": has no triangles");
        tinygltf::Primitive prim;
        prim.mode = kModeTriangles;
        if (t.material >= 0 && size_t(t.material) < m.materials.size()) prim.material = t.material;
        {
            prim.attributes["POSITION"] = add_accessor(t.positions, 3, TINYGLTF_TYPE_VEC3, true);
            if (t.has_normals()) prim.attributes["NORMAL"] = add_accessor(t.normals, 3, TINYGLTF_TYPE_VEC3, false);
            if (t.has_tangents()) prim.attributes["TANGENT"] = add_accessor(t.tangents, 4, TINYGLTF_TYPE_VEC4, false);
            if (t.has_uv0()) prim.attributes["TEXCOORD_0"] = add_accessor(t.uv0, 2, TINYGLTF_TYPE_VEC2, false);
            tinygltf::Accessor idx;
            idx.bufferView = add_view(t.indices.data(), t.indices.size() * sizeof(uint32_t),
                                      TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
            idx.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
            idx.count = t.indices.size();
            idx.type = TINYGLTF_TYPE_SCALAR;
            m.accessors.push_back(idx);
            prim.indices = int(m.accessors.size() - 1);
        }
        mesh.primitives.push_back(prim);
        m.meshes.push_back(mesh);
    }
    if (m.meshes.empty()) return make_error(imported.path + ": contains no triangle meshes");

    m.scenes.push_back(node_hierarchy(imported, m));
    m.defaultScene = 0;
    return scene;
}

}  // namespace specbake::io
