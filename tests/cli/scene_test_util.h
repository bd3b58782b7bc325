// Shared pieces of the scene tests: temporary folders, running the specbake executable, reading glTF
// accessors with tinygltf directly (independent of io/gltf_scene), and a procedural sphere/plane writer.
#pragma once

#include <tiny_gltf.h>

#include <sys/wait.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace scene_test {

namespace fs = std::filesystem;

inline fs::path temp_dir(const std::string& name) {
    fs::path d = fs::temp_directory_path() / ("specbake_scene_" + name + "_" + std::to_string(::getpid()));
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

struct RunResult {
    int exit_code = -1;
    bool signaled = false;
    std::string out, err;
};

inline std::string slurp(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

inline std::string quote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

// Runs `specbake <args>`; stdout and stderr are captured into files in `dir`.
inline RunResult run_specbake(const std::vector<std::string>& args, const fs::path& dir) {
    std::string cmd = quote(SPECBAKE_EXE);
    for (const std::string& a : args) cmd += " " + quote(a);
    const fs::path out = dir / "stdout.txt", err = dir / "stderr.txt";
    cmd += " > " + quote(out.string()) + " 2> " + quote(err.string());
    const int status = std::system(cmd.c_str());
    RunResult r;
    r.signaled = WIFSIGNALED(status) || (WIFEXITED(status) && WEXITSTATUS(status) > 128);
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
}

inline bool no_decode(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                      void*) {
    return true;
}

// Loads with tinygltf, images not decoded.
inline bool load_model(const fs::path& path, tinygltf::Model& model, std::string& err) {
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(&no_decode, nullptr);
    std::string warn;
    const bool glb = path.extension() == ".glb";
    return glb ? loader.LoadBinaryFromFile(&model, &err, &warn, path.string())
               : loader.LoadASCIIFromFile(&model, &err, &warn, path.string());
}

// The bytes of every element of an accessor (stride removed), for byte-exact comparisons.
inline std::vector<uint8_t> accessor_bytes(const tinygltf::Model& m, int index) {
    const tinygltf::Accessor& a = m.accessors.at(size_t(index));
    std::vector<uint8_t> out;
    if (a.bufferView < 0) return out;
    const tinygltf::BufferView& bv = m.bufferViews.at(size_t(a.bufferView));
    const size_t elem = size_t(tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType)) *
                               tinygltf::GetNumComponentsInType(uint32_t(a.type)));
    const size_t stride = bv.byteStride ? bv.byteStride : elem;
    const uint8_t* base = m.buffers.at(size_t(bv.buffer)).data.data() + bv.byteOffset + a.byteOffset;
    for (size_t i = 0; i < a.count; ++i) out.insert(out.end(), base + i * stride, base + i * stride + elem);
    return out;
}

inline std::vector<float> float_accessor(const tinygltf::Model& m, int index) {
    const std::vector<uint8_t> bytes = accessor_bytes(m, index);
    std::vector<float> out(bytes.size() / 4);
    if (!out.empty()) std::memcpy(out.data(), bytes.data(), out.size() * 4);
    return out;
}

// Writes a UV sphere (radius R, outward normals, UVs, no tangents) or a flat grid as a .gltf + .bin with
// one material of the given roughness. Written with tinygltf, independently of specbake's writer.
inline void write_test_model(const fs::path& path, bool sphere, double radius, double roughness, int rings = 48,
                             int segments = 96) {
    std::vector<float> pos, nrm, uv;
    std::vector<uint32_t> idx;
    for (int r = 0; r <= rings; ++r) {
        for (int s = 0; s <= segments; ++s) {
            const double u = double(s) / segments, v = double(r) / rings;
            if (sphere) {
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
    tinygltf::Model m;
    m.asset.version = "2.0";
    tinygltf::Buffer buf;
    auto add = [&](const void* p, size_t n, int type, int ctype, size_t count, int target) {
        tinygltf::BufferView bv;
        bv.buffer = 0;
        bv.byteOffset = buf.data.size();
        bv.byteLength = n;
        bv.target = target;
        buf.data.insert(buf.data.end(), static_cast<const uint8_t*>(p), static_cast<const uint8_t*>(p) + n);
        m.bufferViews.push_back(bv);
        tinygltf::Accessor a;
        a.bufferView = int(m.bufferViews.size() - 1);
        a.componentType = ctype;
        a.count = count;
        a.type = type;
        m.accessors.push_back(a);
        return int(m.accessors.size() - 1);
    };
    const size_t nv = pos.size() / 3;
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    prim.attributes["POSITION"] = add(pos.data(), pos.size() * 4, TINYGLTF_TYPE_VEC3, TINYGLTF_COMPONENT_TYPE_FLOAT, nv,
                                      TINYGLTF_TARGET_ARRAY_BUFFER);
    m.accessors.back().minValues = {-radius, -radius, -radius};
    m.accessors.back().maxValues = {radius, radius, radius};
    prim.attributes["NORMAL"] = add(nrm.data(), nrm.size() * 4, TINYGLTF_TYPE_VEC3, TINYGLTF_COMPONENT_TYPE_FLOAT, nv,
                                    TINYGLTF_TARGET_ARRAY_BUFFER);
    prim.attributes["TEXCOORD_0"] = add(uv.data(), uv.size() * 4, TINYGLTF_TYPE_VEC2, TINYGLTF_COMPONENT_TYPE_FLOAT,
                                        nv, TINYGLTF_TARGET_ARRAY_BUFFER);
    prim.indices = add(idx.data(), idx.size() * 4, TINYGLTF_TYPE_SCALAR, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT,
                       idx.size(), TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    prim.material = 0;
    buf.uri = path.stem().string() + ".bin";
    m.buffers.push_back(buf);
    tinygltf::Material mat;
    mat.name = "test";
    mat.pbrMetallicRoughness.roughnessFactor = roughness;
    mat.pbrMetallicRoughness.metallicFactor = 0.0;
    m.materials.push_back(mat);
    tinygltf::Mesh mesh;
    mesh.name = sphere ? "sphere" : "plane";
    mesh.primitives.push_back(prim);
    m.meshes.push_back(mesh);
    tinygltf::Node node;
    node.mesh = 0;
    m.nodes.push_back(node);
    tinygltf::Scene scene;
    scene.nodes = {0};
    m.scenes.push_back(scene);
    m.defaultScene = 0;
    tinygltf::TinyGLTF writer;
    writer.WriteGltfSceneToFile(&m, path.string(), false, false, true, false);
}

}  // namespace scene_test
