// The triangle primitives of a scene: what each one is (mode, attributes, geometry key, the scale of the
// nodes that instance it), its vertex data as TriMesh, and the baked vertex attributes set on it.
#include "io/gltf/gltf_internal.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace specbake::io {
using gltf::kModeFan;
using gltf::kModeStrip;
using gltf::kModeTriangles;

namespace {

std::array<double, 16> node_local_matrix(const tinygltf::Node& n) {
    std::array<double, 16> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};  // column-major
    if (n.matrix.size() == 16) {
        std::copy(n.matrix.begin(), n.matrix.end(), m.begin());
        return m;
    }
    double qx = 0, qy = 0, qz = 0, qw = 1;
    if (n.rotation.size() == 4) qx = n.rotation[0], qy = n.rotation[1], qz = n.rotation[2], qw = n.rotation[3];
    const double sx = n.scale.size() == 3 ? n.scale[0] : 1, sy = n.scale.size() == 3 ? n.scale[1] : 1,
                 sz = n.scale.size() == 3 ? n.scale[2] : 1;
    const double r[9] = {1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy + qz * qw), 2 * (qx * qz - qy * qw),
                         2 * (qx * qy - qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz + qx * qw),
                         2 * (qx * qz + qy * qw), 2 * (qy * qz - qx * qw), 1 - 2 * (qx * qx + qy * qy)};
    const double s[3] = {sx, sy, sz};
    for (int c = 0; c < 3; ++c)
        for (int row = 0; row < 3; ++row) m[c * 4 + row] = r[c * 3 + row] * s[c];
    if (n.translation.size() == 3) m[12] = n.translation[0], m[13] = n.translation[1], m[14] = n.translation[2];
    return m;
}

std::array<double, 16> multiply(const std::array<double, 16>& a, const std::array<double, 16>& b) {
    std::array<double, 16> r{};
    for (int c = 0; c < 4; ++c)
        for (int row = 0; row < 4; ++row)
            for (int k = 0; k < 4; ++k) r[c * 4 + row] += a[k * 4 + row] * b[c * 4 + k];
    return r;
}

}  // namespace

std::vector<PrimitiveInfo> GltfScene::primitives() const {
    const tinygltf::Model& m = impl_->model;
    // Instance scales: walk every scene graph from its roots (a node may be reached from several scenes).
    std::vector<std::pair<double, double>> scale(m.meshes.size(), {std::numeric_limits<double>::infinity(), 0.0});
    std::vector<int> instances(m.meshes.size(), 0);
    std::vector<int> roots;
    for (const tinygltf::Scene& s : m.scenes) roots.insert(roots.end(), s.nodes.begin(), s.nodes.end());
    const std::array<double, 16> identity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    std::vector<std::pair<int, std::array<double, 16>>> stack;
    for (int r : roots) stack.push_back({r, identity});
    size_t visits = 0;
    while (!stack.empty() && visits < 4 * m.nodes.size() * std::max<size_t>(1, m.scenes.size()) + 16) {
        auto [ni, parent] = stack.back();
        stack.pop_back();
        ++visits;
        if (ni < 0 || size_t(ni) >= m.nodes.size()) continue;
        const tinygltf::Node& n = m.nodes[size_t(ni)];
        const std::array<double, 16> world = multiply(parent, node_local_matrix(n));
        if (n.mesh >= 0 && size_t(n.mesh) < m.meshes.size()) {
            for (int c = 0; c < 3; ++c) {
                const double len = std::sqrt(world[c * 4] * world[c * 4] + world[c * 4 + 1] * world[c * 4 + 1] +
                                             world[c * 4 + 2] * world[c * 4 + 2]);
                scale[size_t(n.mesh)].first = std::min(scale[size_t(n.mesh)].first, len);
                scale[size_t(n.mesh)].second = std::max(scale[size_t(n.mesh)].second, len);
            }
            ++instances[size_t(n.mesh)];
        }
        for (int c : n.children) stack.push_back({c, world});
    }

    std::vector<PrimitiveInfo> out;
    const std::string file = impl_->source.string();
    for (size_t mi = 0; mi < m.meshes.size(); ++mi) {
        const tinygltf::Mesh& mesh = m.meshes[mi];
        for (size_t pi = 0; pi < mesh.primitives.size(); ++pi) {
            const tinygltf::Primitive& p = mesh.primitives[pi];
            PrimitiveInfo info;
            info.ref = {int(mi), int(pi)};
            info.label = file + ": mesh " + std::to_string(mi) + (mesh.name.empty() ? "" : " '" + mesh.name + "'") +
                         " primitive " + std::to_string(pi);
            info.mode = p.mode < 0 ? kModeTriangles : p.mode;
            info.material = p.material;
            info.has_normal = p.attributes.count("NORMAL") > 0;
            info.has_tangent = p.attributes.count("TANGENT") > 0;
            info.has_curvature = p.attributes.count(kCurvatureAttribute) > 0;
            info.geometry_key = "mode " + std::to_string(info.mode) + " indices " + std::to_string(p.indices);
            for (const auto& [name, acc] : p.attributes) {
                if (name.rfind("TEXCOORD_", 0) == 0) info.texcoords.push_back(std::atoi(name.c_str() + 9));
                // Every UV set: generated tangents follow the normal texture's, which may be any of them.
                if (name == "POSITION" || name == "NORMAL" || name == "TANGENT" || name.rfind("TEXCOORD_", 0) == 0)
                    info.geometry_key += " " + name + " " + std::to_string(acc);
            }
            if (auto it = p.extensions.find("KHR_materials_variants"); it != p.extensions.end() && it->second.Has("mappings")) {
                const tinygltf::Value& mappings = it->second.Get("mappings");
                for (size_t k = 0; mappings.IsArray() && k < mappings.ArrayLen(); ++k)
                    if (mappings.Get(int(k)).Has("material"))
                        info.variant_materials.push_back(mappings.Get(int(k)).Get("material").GetNumberAsInt());
            }
            std::sort(info.texcoords.begin(), info.texcoords.end());
            info.instances = instances[mi];
            if (instances[mi] > 0) {
                info.min_instance_scale = scale[mi].first;
                info.max_instance_scale = scale[mi].second;
            }
            out.push_back(std::move(info));
        }
    }
    return out;
}

Result<TriMesh> GltfScene::primitive_mesh(PrimitiveRef ref, int uv_set) const {
    const tinygltf::Model& m = impl_->model;
    if (ref.mesh < 0 || size_t(ref.mesh) >= m.meshes.size() || ref.primitive < 0 ||
        size_t(ref.primitive) >= m.meshes[size_t(ref.mesh)].primitives.size())
        return make_error(impl_->source.string() + ": no primitive " + std::to_string(ref.primitive) + " in mesh " +
                          std::to_string(ref.mesh));
    const tinygltf::Mesh& mesh = m.meshes[size_t(ref.mesh)];
    const tinygltf::Primitive& p = mesh.primitives[size_t(ref.primitive)];
    TriMesh t;
    t.name = impl_->source.string() + ": mesh " + std::to_string(ref.mesh) +
             (mesh.name.empty() ? "" : " '" + mesh.name + "'") + " primitive " + std::to_string(ref.primitive);
    t.material = p.material;
    const int mode = p.mode < 0 ? kModeTriangles : p.mode;
    if (mode != kModeTriangles && mode != kModeStrip && mode != kModeFan)
        return make_error(t.name + ": mode " + std::to_string(mode) + " is not a triangle surface");
    auto pos_it = p.attributes.find("POSITION");
    if (pos_it == p.attributes.end()) return make_error(t.name + ": has no POSITION attribute");
    auto read = [&](const char* name, int nc, std::vector<float>& dst) -> Result<void> {
        auto it = p.attributes.find(name);
        if (it == p.attributes.end()) return {};
        if (it->second < 0 || size_t(it->second) >= m.accessors.size())
            return make_error(t.name + ": " + name + " accessor " + std::to_string(it->second) + " does not exist");
        auto v = gltf::read_attribute(m, impl_->buffers, it->second, nc, t.name + ": " + name, impl_->limits);
        if (!v) return v.error();
        dst = std::move(*v);
        return {};
    };
    if (auto r = read("POSITION", 3, t.positions); !r) return r.error();
    if (auto r = read("NORMAL", 3, t.normals); !r) return r.error();
    if (auto r = read("TANGENT", 4, t.tangents); !r) return r.error();
    const std::string uv_name = "TEXCOORD_" + std::to_string(std::max(0, uv_set));
    if (auto r = read(uv_name.c_str(), 2, t.uv0); !r) return r.error();
    const size_t n = t.vertex_count();
    if (!t.normals.empty() && t.normals.size() != n * 3) return make_error(t.name + ": NORMAL count differs from POSITION count");
    if (!t.tangents.empty() && t.tangents.size() != n * 4) return make_error(t.name + ": TANGENT count differs from POSITION count");
    if (!t.uv0.empty() && t.uv0.size() != n * 2) return make_error(t.name + ": " + uv_name + " count differs from POSITION count");

    std::vector<uint32_t> order;
    if (p.indices >= 0) {
        if (size_t(p.indices) >= m.accessors.size())
            return make_error(t.name + ": indices accessor " + std::to_string(p.indices) + " does not exist");
        const tinygltf::Accessor& ia = m.accessors[size_t(p.indices)];
        if (ia.type != TINYGLTF_TYPE_SCALAR ||
            (ia.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
             ia.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
             ia.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
            return make_error(t.name + ": indices are not unsigned integer scalars");
        auto v = gltf::read_indices(m, impl_->buffers, p.indices, t.name + ": indices", impl_->limits);
        if (!v) return v.error();
        order = std::move(*v);
        for (size_t i = 0; i < order.size(); ++i) {
            if (order[i] >= n)
                return make_error(t.name + ": index " + std::to_string(order[i]) + " at position " +
                                  std::to_string(i) + " is out of range (" + std::to_string(n) + " vertices)");
        }
    } else {
        order.resize(n);
        for (size_t i = 0; i < n; ++i) order[i] = uint32_t(i);
    }
    if (mode == kModeTriangles) {
        order.resize(order.size() / 3 * 3);
        t.indices = std::move(order);
    } else {
        for (size_t i = 2; i < order.size(); ++i) {
            if (mode == kModeFan) {
                t.indices.insert(t.indices.end(), {order[0], order[i - 1], order[i]});
            } else if (i % 2 == 0) {  // strips alternate winding (glTF 2.0 Sec. 3.7.2.1)
                t.indices.insert(t.indices.end(), {order[i - 2], order[i - 1], order[i]});
            } else {
                t.indices.insert(t.indices.end(), {order[i - 1], order[i - 2], order[i]});
            }
        }
    }
    return t;
}

Result<void> GltfScene::set_vertex_attribute(PrimitiveRef ref, const std::string& attribute,
                                            std::vector<float> values, int components) {
    if (components < 1 || components > 4) return make_error(attribute + ": 1 to 4 components per vertex");
    const tinygltf::Model& m = impl_->model;
    const std::string label = impl_->source.string() + ": mesh " + std::to_string(ref.mesh) + " primitive " +
                              std::to_string(ref.primitive);
    if (ref.mesh < 0 || size_t(ref.mesh) >= m.meshes.size() || ref.primitive < 0 ||
        size_t(ref.primitive) >= m.meshes[size_t(ref.mesh)].primitives.size())
        return make_error(label + ": does not exist");
    const auto& attributes = m.meshes[size_t(ref.mesh)].primitives[size_t(ref.primitive)].attributes;
    auto pos = attributes.find("POSITION");
    if (pos == attributes.end() || pos->second < 0 || size_t(pos->second) >= m.accessors.size())
        return make_error(label + ": has no POSITION attribute");
    const size_t vertices = m.accessors[size_t(pos->second)].count;
    if (values.size() != vertices * size_t(components))
        return make_error(label + ": " + attribute + " has " + std::to_string(values.size() / size_t(components)) +
                          " entries for " + std::to_string(vertices) + " vertices");
    for (gltf::AddedAttribute& a : impl_->added) {
        if (a.ref == ref && a.attribute == attribute) {
            a.values = std::move(values);
            a.components = components;
            return {};
        }
    }
    impl_->added.push_back({ref, attribute, std::move(values), components});
    return {};
}

}  // namespace specbake::io
