// Shared pieces of the scene tests: temporary folders, running the specbake executable, reading glTF
// accessors with tinygltf directly (independent of io/gltf_scene), and the procedural sphere/plane models.
#pragma once

#include "tests/io/procedural_gltf.h"

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

// Whether these tests (and so the specbake they run, built with the same flags) use AddressSanitizer: GCC
// defines __SANITIZE_ADDRESS__, clang answers __has_feature.
#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kAddressSanitizer = true;
#else
inline constexpr bool kAddressSanitizer = false;
#endif
#else
inline constexpr bool kAddressSanitizer = false;
#endif

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

// Writes `bytes` to `p`, creating its folder.
inline void write_bytes(const fs::path& p, const std::string& bytes) {
    fs::create_directories(p.parent_path());
    std::ofstream(p, std::ios::binary) << bytes;
}

inline std::string slurp(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

// Little-endian 32- and 64-bit values at byte `at` of a file's bytes (KTX2, DDS and GLB headers).
inline uint32_t le32(const std::string& b, size_t at) {
    uint32_t v = 0;
    for (int i = 3; i >= 0; --i) v = v << 8 | uint8_t(b[at + size_t(i)]);
    return v;
}
inline uint64_t le64(const std::string& b, size_t at) { return uint64_t(le32(b, at)) | uint64_t(le32(b, at + 4)) << 32; }

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
// one material of the given roughness (tests/io/procedural_gltf.h).
inline void write_test_model(const fs::path& path, bool sphere, double radius, double roughness, int rings = 48,
                             int segments = 96) {
    specbake::testing::write_procedural_model(
        path, {.sphere = sphere, .size = radius, .rings = rings, .segments = segments, .roughness = roughness});
}

// SPECBAKE_NO_GL=1 turns the tests that render (verify, bench) into skips.
inline bool gl_disabled() {
    const char* v = std::getenv("SPECBAKE_NO_GL");
    return v && std::string(v) == "1";
}

}  // namespace scene_test
