#include "io/gltf_scene.h"

#include "io/atomic_file.h"
#include "io/sha256.h"
#include "core/huge_pages.h"

// The tinygltf implementation is compiled here, from the installed header, instead of being taken from
// Debian's libtinygltf.so: that library's TinyGLTF class does not match the layout its header declares
// (the loader sees the filesystem callbacks as null, and destroying a TinyGLTF frees a bad pointer).
// specbake decodes images itself (io/image_io.h) and never lets tinygltf read image files.
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include <tbb/task_group.h>

namespace specbake::io {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr int kModeTriangles = 4;
constexpr int kModeStrip = 5;
constexpr int kModeFan = 6;

std::string first_line(const std::string& text) {
    std::string line = text.substr(0, text.find('\n'));
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    return line;
}

bool is_data_uri(const std::string& uri) { return uri.rfind("data:", 0) == 0; }
bool is_remote_uri(const std::string& uri) {
    const size_t colon = uri.find(':');
    const size_t slash = uri.find('/');
    return colon != std::string::npos && colon > 1 && (slash == std::string::npos || colon < slash);
}

// RFC 3986 percent-decoding of a relative URI into a file path.
std::string percent_decode(const std::string& uri) {
    std::string out;
    out.reserve(uri.size());
    for (size_t i = 0; i < uri.size(); ++i) {
        if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(uint8_t(uri[i + 1])) &&
            std::isxdigit(uint8_t(uri[i + 2]))) {
            out.push_back(char(std::stoi(uri.substr(i + 1, 2), nullptr, 16)));
            i += 2;
        } else {
            out.push_back(uri[i]);
        }
    }
    return out;
}

std::string percent_encode(const std::string& path) {
    static const char* hex = "0123456789ABCDEF";
    std::string out;
    for (unsigned char c : path) {
        if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~' || c == '/') {
            out.push_back(char(c));
        } else {
            out.push_back('%');
            out.push_back(hex[c >> 4]);
            out.push_back(hex[c & 15]);
        }
    }
    return out;
}

std::string base64_encode(const uint8_t* data, size_t size) {
    static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    out.reserve((size + 2) / 3 * 4);
    for (size_t i = 0; i < size; i += 3) {
        const uint32_t b0 = data[i];
        const uint32_t b1 = i + 1 < size ? data[i + 1] : 0;
        const uint32_t b2 = i + 2 < size ? data[i + 2] : 0;
        const uint32_t triple = (b0 << 16) | (b1 << 8) | b2;
        out.push_back(table[(triple >> 18) & 63]);
        out.push_back(table[(triple >> 12) & 63]);
        out.push_back(i + 1 < size ? table[(triple >> 6) & 63] : '=');
        out.push_back(i + 2 < size ? table[triple & 63] : '=');
    }
    return out;
}

std::vector<uint8_t> base64_decode(const std::string& text) {
    std::array<int, 256> value;
    value.fill(-1);
    const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    for (int i = 0; i < 64; ++i) value[uint8_t(table[i])] = i;
    std::vector<uint8_t> out;
    uint32_t acc = 0;
    int bits = 0;
    for (char c : text) {
        const int v = value[uint8_t(c)];
        if (v < 0) continue;
        acc = (acc << 6) | uint32_t(v);
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            out.push_back(uint8_t((acc >> bits) & 0xFF));
        }
    }
    return out;
}

// Image callbacks: images stay encoded. An embedded data-URI image keeps its bytes as a data URI so the
// writer emits it unchanged; external and buffer-view images keep their reference.
bool keep_image_encoded(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                        const unsigned char* bytes, int size, void*) {
    image->as_is = true;
    if (image->uri.empty() && image->bufferView < 0 && bytes && size > 0) {
        const std::string mime = image->mimeType.empty() ? "application/octet-stream" : image->mimeType;
        image->uri = "data:" + mime + ";base64," + base64_encode(bytes, size_t(size));
    }
    return true;
}

// File access for tinygltf through std::filesystem (external buffers and images relative to the scene).
bool fs_file_exists(const std::string& path, void*) {
    std::error_code ec;
    return fs::is_regular_file(path, ec);
}
std::string fs_expand_path(const std::string& path, void*) { return path; }
// Files read while loading are hashed on the way (the manifest records every input's hash), into the
// map passed as user data.
bool fs_read_whole_file(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* hashes) {
    auto bytes = read_file(path);
    if (!bytes) {
        if (err) *err += bytes.error().message + "\n";
        return false;
    }
    if (hashes) (*static_cast<std::map<fs::path, std::string>*>(hashes))[fs::path(path).lexically_normal()] =
        sha256_hex(*bytes);
    *out = std::move(*bytes);
    return true;
}
bool fs_refuse_write(std::string* err, const std::string& path, const std::vector<unsigned char>&, void*) {
    if (err) *err += path + ": specbake writes glTF files itself\n";
    return false;
}

tinygltf::FsCallbacks fs_callbacks(std::map<fs::path, std::string>* hashes) {
    return tinygltf::FsCallbacks{&fs_file_exists, &fs_expand_path, &fs_read_whole_file, &fs_refuse_write, hashes};
}

bool keep_image_uri(const std::string*, const std::string*, const tinygltf::Image*, bool, std::string*, void*) {
    return false;
}

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

size_t component_size(int component_type) {
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_BYTE:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
        case TINYGLTF_COMPONENT_TYPE_SHORT:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
        case TINYGLTF_COMPONENT_TYPE_INT:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
        case TINYGLTF_COMPONENT_TYPE_DOUBLE: return 8;
        default: return 0;
    }
}

int component_count(int type) {
    switch (type) {
        case TINYGLTF_TYPE_SCALAR: return 1;
        case TINYGLTF_TYPE_VEC2: return 2;
        case TINYGLTF_TYPE_VEC3: return 3;
        case TINYGLTF_TYPE_VEC4: return 4;
        default: return 0;  // matrices are never vertex attributes specbake reads
    }
}

// One component as double. Normalised integers map to [0,1] / [-1,1] as the glTF spec defines
// (signed: max(c / (2^(n-1) - 1), -1)).
double decode_component(const uint8_t* p, int component_type, bool normalized) {
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_BYTE: {
            int8_t v;
            std::memcpy(&v, p, 1);
            return normalized ? std::max(v / 127.0, -1.0) : double(v);
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[0] / 255.0 : double(p[0]);
        case TINYGLTF_COMPONENT_TYPE_SHORT: {
            int16_t v;
            std::memcpy(&v, p, 2);
            return normalized ? std::max(v / 32767.0, -1.0) : double(v);
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
            uint16_t v;
            std::memcpy(&v, p, 2);
            return normalized ? v / 65535.0 : double(v);
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
            uint32_t v;
            std::memcpy(&v, p, 4);
            return normalized ? v / 4294967295.0 : double(v);
        }
        case TINYGLTF_COMPONENT_TYPE_INT: {
            int32_t v;
            std::memcpy(&v, p, 4);
            return double(v);
        }
        case TINYGLTF_COMPONENT_TYPE_FLOAT: {
            float v;
            std::memcpy(&v, p, 4);
            return double(v);
        }
        default: {
            double v;
            std::memcpy(&v, p, 8);
            return v;
        }
    }
}

// A strided view into a buffer, range-checked once.
struct StridedView {
    const uint8_t* base = nullptr;
    size_t stride = 0;
};

// The bytes of every buffer, held apart from the tinygltf model so that copying the model for a write
// never copies them.
using Payloads = std::vector<std::vector<unsigned char>>;

Result<StridedView> view_of(const tinygltf::Model& m, const Payloads& payloads, int buffer_view, size_t byte_offset,
                            size_t count, size_t element_size, size_t element_stride_default,
                            const std::string& what) {
    if (buffer_view < 0 || size_t(buffer_view) >= m.bufferViews.size())
        return make_error(what + ": bufferView " + std::to_string(buffer_view) + " does not exist");
    const tinygltf::BufferView& bv = m.bufferViews[size_t(buffer_view)];
    if (bv.buffer < 0 || size_t(bv.buffer) >= payloads.size())
        return make_error(what + ": buffer " + std::to_string(bv.buffer) + " does not exist");
    const std::vector<unsigned char>& data = payloads[size_t(bv.buffer)];
    if (bv.byteOffset > data.size() || bv.byteLength > data.size() - bv.byteOffset)
        return make_error(what + ": bufferView " + std::to_string(buffer_view) + " lies outside its buffer");
    const size_t stride = bv.byteStride ? bv.byteStride : element_stride_default;
    if (count > 0) {
        const size_t last = byte_offset + stride * (count - 1) + element_size;
        if (byte_offset > bv.byteLength || last > bv.byteLength || last < byte_offset)
            return make_error(what + ": data runs past the end of bufferView " + std::to_string(buffer_view));
    }
    return StridedView{data.data() + bv.byteOffset + byte_offset, stride};
}

// Dense copy of an accessor's values as doubles (count * components), sparse substitution applied.
Result<std::vector<double>> read_accessor(const tinygltf::Model& m, const Payloads& payloads, int index,
                                          const std::string& what) {
    if (index < 0 || size_t(index) >= m.accessors.size())
        return make_error(what + ": accessor " + std::to_string(index) + " does not exist");
    const tinygltf::Accessor& a = m.accessors[size_t(index)];
    const int nc = component_count(a.type);
    const size_t cs = component_size(a.componentType);
    if (nc == 0 || cs == 0) return make_error(what + ": accessor " + std::to_string(index) + " has an unsupported type");
    std::vector<double> out(a.count * size_t(nc), 0.0);
    if (a.bufferView >= 0) {
        auto view = view_of(m, payloads, a.bufferView, a.byteOffset, a.count, cs * size_t(nc), cs * size_t(nc), what);
        if (!view) return view.error();
        if (view->stride % cs != 0) return make_error(what + ": byteStride is not a multiple of the component size");
        if (a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT) {  // the common case, without per-component dispatch
            float f[4];
            for (size_t i = 0; i < a.count; ++i) {
                std::memcpy(f, view->base + i * view->stride, 4 * size_t(nc));
                for (int c = 0; c < nc; ++c) out[i * nc + c] = f[c];
            }
        } else if (a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT && nc == 1) {
            for (size_t i = 0; i < a.count; ++i) {
                uint32_t v;
                std::memcpy(&v, view->base + i * view->stride, 4);
                out[i] = a.normalized ? v / 4294967295.0 : double(v);
            }
        } else {
            for (size_t i = 0; i < a.count; ++i) {
                const uint8_t* p = view->base + i * view->stride;
                for (int c = 0; c < nc; ++c)
                    out[i * nc + c] = decode_component(p + c * cs, a.componentType, a.normalized);
            }
        }
    }
    if (a.sparse.isSparse) {
        const size_t n = size_t(std::max(a.sparse.count, 0));
        const int ict = a.sparse.indices.componentType;
        const size_t ics = component_size(ict);
        if (ics == 0 || ics > 4 || ict == TINYGLTF_COMPONENT_TYPE_BYTE || ict == TINYGLTF_COMPONENT_TYPE_SHORT)
            return make_error(what + ": sparse indices have an invalid component type");
        auto iv = view_of(m, payloads, a.sparse.indices.bufferView, size_t(std::max(a.sparse.indices.byteOffset, 0)), n, ics, ics, what);
        if (!iv) return iv.error();
        auto vv = view_of(m, payloads, a.sparse.values.bufferView, size_t(std::max(a.sparse.values.byteOffset, 0)), n,
                          cs * size_t(nc), cs * size_t(nc), what);
        if (!vv) return vv.error();
        for (size_t s = 0; s < n; ++s) {
            // Sparse index and value arrays are tightly packed (glTF 2.0 Sec. 3.6.2.3).
            const double target = decode_component(iv->base + s * ics, ict, false);
            if (target < 0 || target >= double(a.count))
                return make_error(what + ": sparse index " + std::to_string(size_t(target)) + " out of range");
            const uint8_t* p = vv->base + s * cs * size_t(nc);
            for (int c = 0; c < nc; ++c)
                out[size_t(target) * nc + c] = decode_component(p + c * cs, a.componentType, a.normalized);
        }
    }
    return out;
}

// Float attribute with exactly `components` per element (TEXCOORD/NORMAL/...).
Result<std::vector<float>> read_attribute(const tinygltf::Model& m, const Payloads& payloads, int index,
                                          int components, const std::string& what) {
    const tinygltf::Accessor& a = m.accessors.at(size_t(index));
    if (component_count(a.type) != components)
        return make_error(what + ": expected " + std::to_string(components) + " components per element");
    if (a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT && !a.sparse.isSparse && a.bufferView >= 0) {
        // The common case, copied without the detour through doubles.
        const size_t element = 4 * size_t(components);
        auto view = view_of(m, payloads, a.bufferView, a.byteOffset, a.count, element, element, what);
        if (!view) return view.error();
        // A mesh's attribute arrays are tens of MB: faulted in as huge pages where the kernel has them.
        std::vector<float> out;
        detail::reserve_huge_pages(out, a.count * size_t(components));
        out.resize(a.count * size_t(components));
        if (view->stride == element) {
            if (!out.empty()) std::memcpy(out.data(), view->base, out.size() * sizeof(float));
        } else {
            for (size_t i = 0; i < a.count; ++i) std::memcpy(&out[i * size_t(components)], view->base + i * view->stride, element);
        }
        return out;
    }
    auto values = read_accessor(m, payloads, index, what);
    if (!values) return values.error();
    std::vector<float> out(values->size());
    for (size_t i = 0; i < out.size(); ++i) out[i] = float((*values)[i]);
    return out;
}

// An index accessor (unsigned byte, short or int scalars) as uint32, read directly when not sparse.
Result<std::vector<uint32_t>> read_indices(const tinygltf::Model& m, const Payloads& payloads, int index,
                                           const std::string& what) {
    const tinygltf::Accessor& a = m.accessors.at(size_t(index));
    const size_t cs = component_size(a.componentType);
    std::vector<uint32_t> out;
    detail::reserve_huge_pages(out, a.count);
    out.resize(a.count);
    if (!a.sparse.isSparse && a.bufferView >= 0 && cs > 0) {
        auto view = view_of(m, payloads, a.bufferView, a.byteOffset, a.count, cs, cs, what);
        if (!view) return view.error();
        if (cs == 4 && view->stride == 4) {
            if (!out.empty()) std::memcpy(out.data(), view->base, out.size() * 4);
        } else {
            for (size_t i = 0; i < a.count; ++i) {
                const uint8_t* p = view->base + i * view->stride;
                if (cs == 1) {
                    out[i] = p[0];
                } else if (cs == 2) {
                    uint16_t v;
                    std::memcpy(&v, p, 2);
                    out[i] = v;
                } else {
                    std::memcpy(&out[i], p, 4);
                }
            }
        }
        return out;
    }
    auto values = read_accessor(m, payloads, index, what);
    if (!values) return values.error();
    for (size_t i = 0; i < out.size(); ++i) out[i] = uint32_t((*values)[i]);
    return out;
}

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

struct GltfScene::Impl {
    tinygltf::Model model;  // its buffers hold no data: the bytes are in `buffers`
    Payloads buffers;
    fs::path source;
    bool binary = false;
    std::map<fs::path, std::string> content_hashes;  // of the files read at load
    // The scene file's own hash is computed in the background from its bytes (mapped until then) while the
    // caller plans and bakes; content_hash() collects it.
    MappedFile source_bytes;
    std::unique_ptr<tbb::task_group> source_hashing;
    std::string source_hash;
    void finish_source_hash() {
        if (!source_hashing) return;
        source_hashing->wait();
        source_hashing.reset();
        content_hashes[source.lexically_normal()] = std::move(source_hash);
        source_bytes = {};
    }
    ~Impl() {
        if (source_hashing) source_hashing->wait();
    }
    struct Added {
        PrimitiveRef ref;
        std::string attribute;
        std::vector<float> values;
        int components = 4;
    };
    std::vector<Added> added;
};

GltfScene::GltfScene() : impl_(std::make_unique<Impl>()) {}
GltfScene::~GltfScene() = default;
GltfScene::GltfScene(GltfScene&&) noexcept = default;
GltfScene& GltfScene::operator=(GltfScene&&) noexcept = default;

const fs::path& GltfScene::source() const { return impl_->source; }
bool GltfScene::source_is_binary() const { return impl_->binary; }

Result<GltfScene> GltfScene::load(const fs::path& path) {
    auto read = MappedFile::open(path);
    if (!read) return read.error();
    GltfScene scene;
    Impl& impl = *scene.impl_;
    impl.source = path;
    impl.source_bytes = std::move(*read);
    const std::span<const uint8_t> source_bytes = impl.source_bytes.bytes();
    const std::span<const uint8_t>* bytes = &source_bytes;
    impl.binary = bytes->size() >= 4 && std::memcmp(bytes->data(), "glTF", 4) == 0;
    // The manifest records the hash of every input; it is computed from the bytes already in memory instead
    // of reading the file again later, on another thread, beside the parse and whatever the caller does next.
    impl.source_hashing = std::make_unique<tbb::task_group>();
    impl.source_hashing->run([&impl] { impl.source_hash = sha256_hex(impl.source_bytes.bytes()); });
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(&keep_image_encoded, nullptr);
    loader.SetImageWriter(&keep_image_uri, nullptr);
    loader.SetFsCallbacks(fs_callbacks(&impl.content_hashes));
    std::string err, warn;
    std::string base_dir = path.parent_path().string();
    if (base_dir.empty()) base_dir = ".";
    bool ok = false;
    try {
        if (impl.binary) {
            if (bytes->size() > std::numeric_limits<unsigned int>::max())
                return make_error(path.string() + ": GLB larger than 4 GiB");
            ok = loader.LoadBinaryFromMemory(&impl.model, &err, &warn, bytes->data(),
                                             static_cast<unsigned int>(bytes->size()), base_dir);
        } else {
            ok = loader.LoadASCIIFromString(&impl.model, &err, &warn, reinterpret_cast<const char*>(bytes->data()),
                                            static_cast<unsigned int>(bytes->size()), base_dir);
        }
    } catch (const std::exception& e) {
        return make_error(path.string() + ": not a valid glTF file: " + e.what());
    }
    if (!ok) {
        const std::string reason = first_line(err.empty() ? warn : err);
        return make_error(path.string() + ": not a valid glTF file: " + (reason.empty() ? "parse error" : reason));
    }
    impl.buffers.resize(impl.model.buffers.size());
    for (size_t i = 0; i < impl.buffers.size(); ++i) impl.buffers[i].swap(impl.model.buffers[i].data);
    return scene;
}

std::string GltfScene::content_hash(const fs::path& file) const {
    impl_->finish_source_hash();
    auto it = impl_->content_hashes.find(file.lexically_normal());
    return it == impl_->content_hashes.end() ? std::string() : it->second;
}

Result<GltfScene> GltfScene::from_imported(const ImportedScene& imported) {
    GltfScene scene;
    scene.impl_->source = imported.path;
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

    // Node hierarchy: one glTF node per imported node; a node with several meshes gets one child per mesh
    // (a glTF node holds at most one mesh).
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
    m.scenes.push_back(root);
    m.defaultScene = 0;
    return scene;
}

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
                if (name == "POSITION" || name == "NORMAL" || name == "TANGENT" || name == "TEXCOORD_0")
                    info.geometry_key += " " + name + " " + std::to_string(acc);
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
        // SPECBAKE_glints (io/glint_extension.h): kept as JSON, parsed by the plan.
        if (auto it = mat.extensions.find("SPECBAKE_glints"); it != mat.extensions.end()) info.glints = from_value(it->second);
        out.push_back(std::move(info));
    }
    return out;
}

Result<TriMesh> GltfScene::primitive_mesh(PrimitiveRef ref) const {
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
        auto v = read_attribute(m, impl_->buffers, it->second, nc, t.name + ": " + name);
        if (!v) return v.error();
        dst = std::move(*v);
        return {};
    };
    if (auto r = read("POSITION", 3, t.positions); !r) return r.error();
    if (auto r = read("NORMAL", 3, t.normals); !r) return r.error();
    if (auto r = read("TANGENT", 4, t.tangents); !r) return r.error();
    if (auto r = read("TEXCOORD_0", 2, t.uv0); !r) return r.error();
    const size_t n = t.vertex_count();
    if (!t.normals.empty() && t.normals.size() != n * 3) return make_error(t.name + ": NORMAL count differs from POSITION count");
    if (!t.tangents.empty() && t.tangents.size() != n * 4) return make_error(t.name + ": TANGENT count differs from POSITION count");
    if (!t.uv0.empty() && t.uv0.size() != n * 2) return make_error(t.name + ": TEXCOORD_0 count differs from POSITION count");

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
        auto v = read_indices(m, impl_->buffers, p.indices, t.name + ": indices");
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

std::string GltfScene::image_label(int image) const {
    const tinygltf::Model& m = impl_->model;
    const std::string file = impl_->source.string();
    if (image < 0 || size_t(image) >= m.images.size()) return file + ": image " + std::to_string(image);
    const tinygltf::Image& img = m.images[size_t(image)];
    if (!img.uri.empty() && !is_data_uri(img.uri))
        return (impl_->source.parent_path() / percent_decode(img.uri)).string();
    return file + ": image " + std::to_string(image) + (img.name.empty() ? "" : " '" + img.name + "'");
}

fs::path GltfScene::image_file(int image) const {
    const tinygltf::Model& m = impl_->model;
    if (image < 0 || size_t(image) >= m.images.size()) return {};
    const tinygltf::Image& img = m.images[size_t(image)];
    if (img.bufferView >= 0 || img.uri.empty() || is_data_uri(img.uri) || is_remote_uri(img.uri)) return {};
    return impl_->source.parent_path() / percent_decode(img.uri);
}

Result<std::vector<uint8_t>> GltfScene::image_bytes(int image) const {
    const tinygltf::Model& m = impl_->model;
    if (image < 0 || size_t(image) >= m.images.size()) return make_error(image_label(image) + ": does not exist");
    const tinygltf::Image& img = m.images[size_t(image)];
    if (img.bufferView >= 0) {
        auto view = view_of(m, impl_->buffers, img.bufferView, 0, 1, 0, 0, image_label(image));
        if (!view) return view.error();
        const tinygltf::BufferView& bv = m.bufferViews[size_t(img.bufferView)];
        return std::vector<uint8_t>(view->base, view->base + bv.byteLength);
    }
    if (is_data_uri(img.uri)) {
        const size_t comma = img.uri.find(',');
        if (comma == std::string::npos || img.uri.find(";base64") > comma)
            return make_error(image_label(image) + ": data URI is not base64");
        return base64_decode(img.uri.substr(comma + 1));
    }
    if (img.uri.empty() || is_remote_uri(img.uri)) return make_error(image_label(image) + ": not a local file");
    return read_file(impl_->source.parent_path() / percent_decode(img.uri));
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
    for (Impl::Added& a : impl_->added) {
        if (a.ref == ref && a.attribute == attribute) {
            a.values = std::move(values);
            a.components = components;
            return {};
        }
    }
    impl_->added.push_back({ref, attribute, std::move(values), components});
    return {};
}

std::vector<fs::path> GltfScene::resource_files() const {
    std::vector<fs::path> out;
    const fs::path dir = impl_->source.parent_path();
    auto add = [&](const std::string& uri) {
        if (uri.empty() || is_data_uri(uri) || is_remote_uri(uri)) return;
        const fs::path p = dir / percent_decode(uri);
        std::error_code ec;
        if (fs::is_regular_file(p, ec) && std::find(out.begin(), out.end(), p) == out.end()) out.push_back(p);
    };
    for (const tinygltf::Buffer& b : impl_->model.buffers) add(b.uri);
    for (const tinygltf::Image& i : impl_->model.images) add(i.uri);
    return out;
}

namespace {
void add_extension_used(tinygltf::Model& m) {
    if (std::find(m.extensionsUsed.begin(), m.extensionsUsed.end(), kSpecbakeExtension) == m.extensionsUsed.end())
        m.extensionsUsed.push_back(kSpecbakeExtension);
}
}  // namespace

void GltfScene::set_material_extension(int material, const json& extension) {
    tinygltf::Model& m = impl_->model;
    if (material < 0 || size_t(material) >= m.materials.size()) return;
    m.materials[size_t(material)].extensions[kSpecbakeExtension] = to_value(extension);
    add_extension_used(m);
}

void GltfScene::set_root_extension(const json& extension) {
    impl_->model.extensions[kSpecbakeExtension] = to_value(extension);
    add_extension_used(impl_->model);
}

namespace {

// The bytes of one output file (or of the GLB binary chunk) as a list of pieces, each starting at a
// multiple of 4 (glTF 2.0 Sec. 3.6.2.4 aligns accessors to their component size, at most 4 for vertex data).
struct PieceList {
    std::vector<std::span<const uint8_t>> pieces;
    size_t size = 0;

    size_t append(std::span<const uint8_t> bytes) {
        static const uint8_t zeros[4] = {};
        if (size % 4) {
            const size_t pad = 4 - size % 4;
            pieces.emplace_back(zeros, pad);
            size += pad;
        }
        const size_t offset = size;
        if (!bytes.empty()) pieces.push_back(bytes);
        size += bytes.size();
        return offset;
    }
};

// Writes the pieces to the temporary file of `out` and returns their SHA-256, hashed on a TBB worker while
// this thread writes. Nothing is renamed into place here.
Result<std::string> write_pieces(AtomicOutput& out, const std::vector<std::span<const uint8_t>>& pieces) {
    std::error_code ec;
    const fs::path& final_path = out.final_path();
    if (final_path.has_parent_path()) fs::create_directories(final_path.parent_path(), ec);
    if (ec) return make_error(final_path.parent_path().string() + ": cannot create folder: " + ec.message());
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(out.temp_path().c_str(), "wb"), &std::fclose);
    if (!f) return make_error(final_path.string() + ": cannot open for writing");
    std::string hash;
    tbb::task_group hashing;
    hashing.run([&] {
        Sha256 sha;
        for (std::span<const uint8_t> p : pieces) sha.update(p);
        hash = sha.hex();
    });
    bool ok = true;
    for (std::span<const uint8_t> p : pieces) ok = ok && std::fwrite(p.data(), 1, p.size(), f.get()) == p.size();
    ok = std::fflush(f.get()) == 0 && ok;
    hashing.wait();
    if (!ok) return make_error(final_path.string() + ": write failed (disk full?)");
    return hash;
}

std::string mime_type_of(const fs::path& file) {
    std::string e = file.extension().string();
    std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (e == ".png") return "image/png";
    if (e == ".jpg" || e == ".jpeg") return "image/jpeg";
    if (e == ".ktx2") return "image/ktx2";  // KHR_texture_basisu
    if (e == ".webp") return "image/webp";  // EXT_texture_webp
    if (e == ".dds") return "image/vnd-ms.dds";  // MSFT_texture_dds
    return {};
}

bool inside_folder(const fs::path& relative) {
    return relative.is_relative() && !relative.empty() && *relative.begin() != "..";
}

}  // namespace

Result<std::vector<GltfScene::WrittenFile>> GltfScene::write(const fs::path& path) const {
    const std::string ext = [&] {
        std::string e = path.extension().string();
        std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
        return e;
    }();
    if (ext != ".gltf" && ext != ".glb") return make_error(path.string() + ": output must end in .gltf or .glb");
    const bool glb = ext == ".glb";
    const fs::path out_dir = path.parent_path().empty() ? fs::path(".") : path.parent_path();
    const std::string stem = path.stem().string();
    const fs::path src_dir = impl_->source.parent_path();
    const Payloads& payloads = impl_->buffers;

    tinygltf::Model m = impl_->model;  // the buffers hold no bytes, so this copies only the JSON side

    // Where every output buffer's bytes come from. A GLB gets one buffer, its binary chunk, holding every
    // input buffer, the external images and the appended data, so the file is self-contained. A .gltf
    // keeps the input's buffers (written next to it) and appends one buffer for the new data.
    struct OutBuffer {
        PieceList bytes;
        std::string uri;  // empty for the GLB binary chunk; a data URI is kept as it was
        fs::path file;    // relative to out_dir; empty when nothing is written for it
        int source = -1;  // input buffer written 1:1 (name, extensions kept), -1 for a merged or new one
    };
    std::vector<OutBuffer> out_buffers;
    std::vector<std::vector<uint8_t>> embedded_images;  // file bytes of images moved into the GLB
    std::vector<std::pair<fs::path, fs::path>> copies;   // images copied next to a .gltf: from, relative to
    int target_buffer = -1;                              // receives the appended vertex data

    if (glb) {
        out_buffers.emplace_back();
        out_buffers[0].source = payloads.size() == 1 ? 0 : -1;
        std::vector<size_t> shift(payloads.size());
        for (size_t i = 0; i < payloads.size(); ++i) shift[i] = out_buffers[0].bytes.append(payloads[i]);
        for (tinygltf::BufferView& bv : m.bufferViews) {
            if (bv.buffer < 0 || size_t(bv.buffer) >= payloads.size()) continue;
            bv.byteOffset += shift[size_t(bv.buffer)];
            bv.buffer = 0;
        }
        std::map<fs::path, int> view_of_file;  // an image file used twice is stored once
        for (size_t i = 0; i < m.images.size(); ++i) {
            tinygltf::Image& img = m.images[i];
            if (img.uri.empty() || is_data_uri(img.uri) || is_remote_uri(img.uri)) continue;
            const fs::path decoded = fs::path(percent_decode(img.uri)).lexically_normal();
            const fs::path from = src_dir / decoded;
            const std::string mime = mime_type_of(from);
            if (mime.empty()) {
                // Not a type glTF can name in a bufferView: it stays an external file next to the GLB.
                const fs::path rel = inside_folder(decoded) ? decoded : decoded.filename();
                if (!inside_folder(decoded)) img.uri = percent_encode(rel.generic_string());
                copies.push_back({from, rel});
                continue;
            }
            auto [it, is_new] = view_of_file.try_emplace(from, -1);
            if (is_new) {
                auto bytes = read_file(from);
                if (!bytes) return make_error(image_label(int(i)) + ": image referenced by the scene cannot be read");
                // The vector's heap block does not move when embedded_images grows, so the span stays valid.
                embedded_images.push_back(std::move(*bytes));
                tinygltf::BufferView bv;
                bv.buffer = 0;
                bv.byteLength = embedded_images.back().size();
                bv.byteOffset = out_buffers[0].bytes.append(embedded_images.back());
                m.bufferViews.push_back(bv);
                it->second = int(m.bufferViews.size() - 1);
            }
            img.bufferView = it->second;
            img.mimeType = mime;
            img.uri.clear();
        }
        target_buffer = 0;
    } else {
        std::set<std::string> used_names;
        for (size_t i = 0; i < payloads.size(); ++i) {
            OutBuffer b;
            b.source = int(i);
            b.bytes.append(payloads[i]);
            const std::string& uri = m.buffers[i].uri;
            if (is_data_uri(uri)) {
                b.uri = uri;
                out_buffers.push_back(std::move(b));
                continue;
            }
            std::string rel;
            if (!uri.empty() && !is_remote_uri(uri)) {
                const fs::path decoded = fs::path(percent_decode(uri)).lexically_normal();
                rel = inside_folder(decoded) ? decoded.generic_string() : decoded.filename().string();
            }
            if (rel.empty() || used_names.count(rel)) {
                const std::string base = stem + (i == 0 ? "" : "_" + std::to_string(i));
                rel = base + ".bin";
                for (int k = 1; used_names.count(rel); ++k) rel = base + "_" + std::to_string(k) + ".bin";
            }
            used_names.insert(rel);
            b.uri = percent_encode(rel);
            b.file = rel;
            out_buffers.push_back(std::move(b));
        }
        if (!impl_->added.empty()) {
            OutBuffer b;
            std::string rel = stem + "_specaa.bin";
            for (int k = 1; used_names.count(rel); ++k) rel = stem + "_specaa_" + std::to_string(k) + ".bin";
            b.uri = percent_encode(rel);
            b.file = rel;
            out_buffers.push_back(std::move(b));
            target_buffer = int(out_buffers.size() - 1);
        }
        // External images are copied next to the scene, at the same relative path when it stays inside the
        // output folder, else under their file name (and the URI follows).
        for (tinygltf::Image& img : m.images) {
            if (img.uri.empty() || is_data_uri(img.uri) || is_remote_uri(img.uri)) continue;
            const fs::path decoded = fs::path(percent_decode(img.uri)).lexically_normal();
            const fs::path rel = inside_folder(decoded) ? decoded : decoded.filename();
            if (!inside_folder(decoded)) img.uri = percent_encode(rel.generic_string());
            copies.push_back({src_dir / decoded, rel});
        }
    }
    for (const auto& [from, rel] : copies) {
        std::error_code ec;
        if (!fs::is_regular_file(from, ec)) return make_error(from.string() + ": image referenced by the scene does not exist");
    }

    // Appended vertex data. Primitives that share vertex data get equal values; they share one accessor too.
    std::vector<std::pair<const Impl::Added*, int>> accessor_of_values;
    for (const Impl::Added& a : impl_->added) {
        int shared = -1;
        for (const auto& [previous, accessor] : accessor_of_values)
            if (previous->attribute == a.attribute && previous->components == a.components && previous->values == a.values)
                shared = accessor;
        if (shared >= 0) {
            m.meshes[size_t(a.ref.mesh)].primitives[size_t(a.ref.primitive)].attributes[a.attribute] = shared;
            continue;
        }
        tinygltf::BufferView bv;
        bv.buffer = target_buffer;
        bv.byteLength = a.values.size() * sizeof(float);
        bv.byteOffset = out_buffers[size_t(target_buffer)].bytes.append(
            std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(a.values.data()), bv.byteLength));
        bv.target = TINYGLTF_TARGET_ARRAY_BUFFER;
        bv.name = a.attribute;
        m.bufferViews.push_back(bv);
        tinygltf::Accessor acc;
        acc.bufferView = int(m.bufferViews.size() - 1);
        acc.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
        acc.type = a.components == 1   ? TINYGLTF_TYPE_SCALAR
                   : a.components == 2 ? TINYGLTF_TYPE_VEC2
                   : a.components == 3 ? TINYGLTF_TYPE_VEC3
                                       : TINYGLTF_TYPE_VEC4;
        acc.count = a.values.size() / size_t(a.components);
        m.accessors.push_back(acc);
        m.meshes[size_t(a.ref.mesh)].primitives[size_t(a.ref.primitive)].attributes[a.attribute] =
            int(m.accessors.size() - 1);
        accessor_of_values.push_back({&a, int(m.accessors.size() - 1)});
    }

    if (glb && out_buffers[0].bytes.size == 0) out_buffers.clear();

    // The JSON, serialised by tinygltf without buffer payloads; then each buffer's length, URI, name and
    // extensions are set from the output plan (tinygltf 2.7 drops buffer extensions when serialising).
    std::vector<tinygltf::Buffer> input_buffers = std::move(m.buffers);
    m.buffers.assign(out_buffers.size(), tinygltf::Buffer());
    std::string json_text;
    try {
        tinygltf::TinyGLTF writer;
        writer.SetImageWriter(&keep_image_uri, nullptr);
        writer.SetFsCallbacks(fs_callbacks(nullptr));
        std::ostringstream os;
        if (!writer.WriteGltfSceneToStream(&m, os, false, false))
            return make_error(path.string() + ": could not serialise the glTF");
        json_text = os.str();
    } catch (const std::exception& e) {
        return make_error(path.string() + ": could not serialise the glTF: " + e.what());
    }
    json doc = json::parse(json_text, nullptr, false);
    if (doc.is_discarded()) return make_error(path.string() + ": could not serialise the glTF");
    if (!out_buffers.empty()) {
        doc["buffers"] = json::array();
        for (const OutBuffer& b : out_buffers) {
            json e = {{"byteLength", b.bytes.size}};
            if (!b.uri.empty()) e["uri"] = b.uri;
            if (b.source >= 0) {
                const tinygltf::Buffer& in = input_buffers[size_t(b.source)];
                if (!in.name.empty()) e["name"] = in.name;
                if (in.extras.Type() != tinygltf::NULL_TYPE) e["extras"] = from_value(in.extras);
                for (const auto& [name, value] : in.extensions) e["extensions"][name] = from_value(value);
            } else if (int(&b - out_buffers.data()) == target_buffer && !glb) {
                e["name"] = "specbake";
            }
            doc["buffers"].push_back(std::move(e));
        }
    }

    // Every file goes to a temporary first; all are renamed into place once all are written.
    std::vector<std::unique_ptr<AtomicOutput>> outputs;
    std::vector<WrittenFile> written;
    auto emit = [&](const fs::path& file, const std::vector<std::span<const uint8_t>>& pieces) -> Result<void> {
        outputs.push_back(std::make_unique<AtomicOutput>(file));
        auto hash = write_pieces(*outputs.back(), pieces);
        if (!hash) return hash.error();
        written.push_back({file, std::move(*hash)});
        return {};
    };
    const std::string text = doc.dump(glb ? -1 : 2);
    std::vector<uint8_t> header;
    auto put32 = [&](uint32_t v) {
        for (int k = 0; k < 4; ++k) header.push_back(uint8_t(v >> (8 * k)));
    };
    if (glb) {
        // GLB container (glTF 2.0 Sec. 4.4): 12-byte header, JSON chunk padded with spaces, BIN chunk with zeros.
        std::string json_chunk = text;
        while (json_chunk.size() % 4) json_chunk.push_back(' ');
        const bool has_bin = !out_buffers.empty();
        const size_t bin_size = has_bin ? out_buffers[0].bytes.size : 0;
        const size_t bin_padded = (bin_size + 3) / 4 * 4;
        const uint64_t total = 12 + 8 + json_chunk.size() + (has_bin ? 8 + bin_padded : 0);
        if (total > std::numeric_limits<uint32_t>::max()) return make_error(path.string() + ": GLB would exceed 4 GiB");
        put32(0x46546C67);
        put32(2);
        put32(uint32_t(total));
        put32(uint32_t(json_chunk.size()));
        put32(0x4E4F534A);
        header.insert(header.end(), json_chunk.begin(), json_chunk.end());
        std::vector<std::span<const uint8_t>> pieces{header};
        std::vector<uint8_t> bin_header;
        static const uint8_t zeros[4] = {};
        if (has_bin) {
            for (uint32_t v : {uint32_t(bin_padded), uint32_t(0x004E4942)})
                for (int k = 0; k < 4; ++k) bin_header.push_back(uint8_t(v >> (8 * k)));
            pieces.push_back(bin_header);
            pieces.insert(pieces.end(), out_buffers[0].bytes.pieces.begin(), out_buffers[0].bytes.pieces.end());
            if (bin_padded > bin_size) pieces.emplace_back(zeros, bin_padded - bin_size);
        }
        if (auto r = emit(path, pieces); !r) return r.error();
    } else {
        const std::string with_newline = text + "\n";
        const std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(with_newline.data()), with_newline.size());
        if (auto r = emit(path, {bytes}); !r) return r.error();
    }
    for (const OutBuffer& b : out_buffers) {
        if (b.file.empty()) continue;
        if (auto r = emit(out_dir / b.file, b.bytes.pieces); !r) return r.error();
    }
    std::set<fs::path> copied;
    for (const auto& [from, rel] : copies) {
        const fs::path dst = out_dir / rel;
        if (!copied.insert(dst).second) continue;
        std::error_code ec;
        if (fs::exists(dst, ec) && fs::equivalent(from, dst, ec)) continue;
        auto bytes = read_file(from);
        if (!bytes) return bytes.error();
        if (auto r = emit(dst, {std::span<const uint8_t>(*bytes)}); !r) return r.error();
    }
    for (const auto& out : outputs)
        if (auto r = out->commit(); !r) return r.error();
    return written;
}

}  // namespace specbake::io
