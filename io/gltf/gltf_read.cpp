// Loading a .gltf or .glb through tinygltf with images left encoded and every file read hashed; the
// scene's source and resources, and the bytes, files and labels of its images.
#include "io/gltf/gltf_internal.h"

#include "io/gltf/gltf_uri.h"
#include "io/files/sha256.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <limits>

namespace specbake::io {
namespace fs = std::filesystem;

namespace gltf {
namespace {

std::string first_line(const std::string& text) {
    std::string line = text.substr(0, text.find('\n'));
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    return line;
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

// File access for tinygltf: external buffers only (images are never read by it, io/gltf/tinygltf_internal.h).
// tinygltf joins the decoded URI to the base folder it is given, which is kMarker: the part after it is
// resolved by the path policy (io/files/input_policy.h), and anything else (tinygltf's fallback to the working
// folder) is not found. A refusal is kept for the error message, which then says why instead of
// "File not found".
constexpr const char* kMarker = "\x01specbake-scene-folder";

std::string shown(const std::string& decoded) {
    std::string out;
    for (char c : decoded) out += c == '\0' ? std::string("%00") : std::string(1, c);
    return out;
}

std::string fs_expand_path(const std::string& path, void* user) {
    if (!user) return path;
    auto& ctx = *static_cast<LoadContext*>(user);
    const std::string prefix = std::string(kMarker) + "/";
    if (path.compare(0, prefix.size(), prefix) != 0) return {};
    const std::string decoded = path.substr(prefix.size());
    auto resolved = resolve_in_folder(ctx.folder, decoded, *ctx.policy);
    if (!resolved) {
        if (ctx.refusal.empty())
            ctx.refusal = ctx.scene + ": URI '" + shown(decoded) + "' refused: " + resolved.error().message;
        return {};
    }
    return resolved->string();
}
bool fs_file_exists(const std::string& path, void*) {
    std::error_code ec;
    return !path.empty() && fs::is_regular_file(path, ec);
}
// Files read while loading are hashed on the way (the manifest records every input's hash).
bool fs_read_whole_file(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
    auto bytes = read_file(path);
    if (!bytes) {
        if (err) *err += bytes.error().message + "\n";
        return false;
    }
    auto* ctx = static_cast<LoadContext*>(user);
    if (ctx) ctx->read.push_back(fs::path(path));
    if (ctx && ctx->hashes) (*ctx->hashes)[fs::path(path).lexically_normal()] = sha256_hex(*bytes);
    *out = std::move(*bytes);
    return true;
}
bool fs_refuse_write(std::string* err, const std::string& path, const std::vector<unsigned char>&, void*) {
    if (err) *err += path + ": specbake writes glTF files itself\n";
    return false;
}

// The JSON's size and nesting depth, checked before tinygltf parses it: its conversion of the parsed
// JSON recurses once per level, and some 20,000 levels overflow the stack. One pass over the bytes,
// brackets inside strings skipped.
Result<void> check_json_shape(std::span<const uint8_t> json, const std::string& name, const InputLimits& limits) {
    if (json.size() > limits.json_bytes)
        return make_error(name + ": JSON of " + over_limit("json-bytes", json.size(), limits.json_bytes) + " bytes");
    uint64_t depth = 0;
    bool in_string = false;
    for (size_t i = 0; i < json.size(); ++i) {
        const uint8_t c = json[i];
        if (in_string) {
            if (c == '\\') ++i;
            else if (c == '"') in_string = false;
        } else if (c == '"') {
            in_string = true;
        } else if (c == '{' || c == '[') {
            if (++depth > limits.json_depth)
                return make_error(name + ": JSON nesting depth " + over_limit("json-depth", depth, limits.json_depth));
        } else if ((c == '}' || c == ']') && depth > 0) {
            --depth;
        }
    }
    return {};
}

// The JSON chunk of a GLB (glTF 2.0 Sec. 4.4), or all of a .gltf; a malformed GLB is left to tinygltf.
std::span<const uint8_t> json_of(std::span<const uint8_t> bytes, bool binary) {
    if (!binary) return bytes;
    if (bytes.size() < 20) return {};
    uint32_t length = 0;
    std::memcpy(&length, bytes.data() + 12, 4);
    return bytes.subspan(20, std::min<size_t>(length, bytes.size() - 20));
}

bool is_file_uri(const std::string& uri) {
    return uri.size() >= 5 && std::tolower(uint8_t(uri[0])) == 'f' && std::tolower(uint8_t(uri[1])) == 'i' &&
           std::tolower(uint8_t(uri[2])) == 'l' && std::tolower(uint8_t(uri[3])) == 'e' && uri[4] == ':';
}

// Every external image and buffer resolved once by the path policy; a refusal names the scene and the URI.
Result<void> resolve_files(SceneState& scene, const LoadContext& ctx) {
    const tinygltf::Model& m = scene.model;
    auto resolve = [&](const std::string& uri, const char* what) -> Result<fs::path> {
        if (uri.empty() || is_data_uri(uri)) return fs::path();
        const std::string refused = ctx.scene + ": " + what + " URI '" + shown(uri) + "' refused: ";
        if (is_file_uri(uri)) return make_error(refused + "file: URIs are not read (use a relative path)");
        if (is_remote_uri(uri)) return fs::path();
        auto path = resolve_in_folder(ctx.folder, percent_decode(uri), *ctx.policy);
        if (!path) return make_error(refused + path.error().message);
        return *path;
    };
    scene.image_paths.resize(m.images.size());
    for (size_t i = 0; i < m.images.size(); ++i) {
        auto p = resolve(m.images[i].uri, "image");
        if (!p) return p.error();
        scene.image_paths[i] = std::move(*p);
    }
    scene.buffer_paths.resize(m.buffers.size());
    for (size_t i = 0; i < m.buffers.size(); ++i) {
        auto p = resolve(m.buffers[i].uri, "buffer");
        if (!p) return p.error();
        // tinygltf decodes buffer URIs itself; a URI it decodes differently ('+', malformed escapes)
        // would make the bytes read differ from the file hashed and listed.
        if (!p->empty() && std::find(ctx.read.begin(), ctx.read.end(), *p) == ctx.read.end())
            return make_error(ctx.scene + ": buffer URI '" + shown(m.buffers[i].uri) +
                              "' is ambiguous ('+' and malformed %-escapes are not supported in buffer URIs)");
        scene.buffer_paths[i] = std::move(*p);
    }
    return {};
}

// Node and primitive counts against the limits, and the node hierarchy a forest (glTF 2.0 Sec. 3.5.3:
// no node is its own ancestor), checked by an iterative depth-first walk.
Result<void> check_structure(const tinygltf::Model& m, const std::string& name, const InputLimits& limits) {
    if (m.nodes.size() > limits.nodes)
        return make_error(name + ": node count " + over_limit("nodes", m.nodes.size(), limits.nodes));
    uint64_t primitives = 0;
    for (const tinygltf::Mesh& mesh : m.meshes) primitives += mesh.primitives.size();
    if (primitives > limits.primitives)
        return make_error(name + ": primitive count " + over_limit("primitives", primitives, limits.primitives));
    enum : uint8_t { unseen, open, done };
    std::vector<uint8_t> state(m.nodes.size(), unseen);
    std::vector<std::pair<size_t, size_t>> stack;  // node, next child
    for (size_t root = 0; root < m.nodes.size(); ++root) {
        if (state[root] != unseen) continue;
        stack.push_back({root, 0});
        state[root] = open;
        while (!stack.empty()) {
            auto& [node, next] = stack.back();
            const std::vector<int>& children = m.nodes[node].children;
            if (next == children.size()) {
                state[node] = done;
                stack.pop_back();
                continue;
            }
            const int child = children[next++];
            if (child < 0 || size_t(child) >= m.nodes.size())
                return make_error(name + ": node " + std::to_string(node) + " has child " + std::to_string(child) +
                                  ", which does not exist");
            if (state[size_t(child)] == open)
                return make_error(name + ": node " + std::to_string(child) +
                                  " is its own ancestor (the node hierarchy has a cycle)");
            if (state[size_t(child)] == unseen) {
                state[size_t(child)] = open;
                stack.push_back({size_t(child), 0});
            }
        }
    }
    return {};
}

}  // namespace

tinygltf::FsCallbacks fs_callbacks(LoadContext* context) {
    return tinygltf::FsCallbacks{&fs_file_exists, &fs_expand_path, &fs_read_whole_file, &fs_refuse_write, context};
}

bool keep_image_uri(const std::string*, const std::string*, const tinygltf::Image*, bool, std::string*, void*) {
    return false;
}

std::string image_label(const SceneState& scene, int image) {
    const tinygltf::Model& m = scene.model;
    const std::string file = scene.source.string();
    if (image < 0 || size_t(image) >= m.images.size()) return file + ": image " + std::to_string(image);
    const tinygltf::Image& img = m.images[size_t(image)];
    if (size_t(image) < scene.image_paths.size() && !scene.image_paths[size_t(image)].empty())
        return scene.image_paths[size_t(image)].string();
    return file + ": image " + std::to_string(image) + (img.name.empty() ? "" : " '" + img.name + "'");
}

}  // namespace gltf

using namespace gltf;

GltfScene::GltfScene() : impl_(std::make_unique<Impl>()) {}
GltfScene::~GltfScene() = default;
GltfScene::GltfScene(GltfScene&&) noexcept = default;
GltfScene& GltfScene::operator=(GltfScene&&) noexcept = default;

const fs::path& GltfScene::source() const { return impl_->source; }
bool GltfScene::source_is_binary() const { return impl_->binary; }

Result<GltfScene> GltfScene::load(const fs::path& path, const InputPolicy& policy) {
    auto read = MappedFile::open(path);
    if (!read) return read.error();
    GltfScene scene;
    Impl& impl = *scene.impl_;
    impl.source = path;
    impl.limits = policy.limits;
    impl.source_bytes = std::move(*read);
    const std::span<const uint8_t> source_bytes = impl.source_bytes.bytes();
    const std::span<const uint8_t>* bytes = &source_bytes;
    impl.binary = bytes->size() >= 4 && std::memcmp(bytes->data(), "glTF", 4) == 0;
    // The manifest records the hash of every input; it is computed from the bytes already in memory instead
    // of reading the file again later, on another thread, beside the parse and whatever the caller does next.
    impl.source_hashing = std::make_unique<tbb::task_group>();
    impl.source_hashing->run([&impl] { impl.source_hash = sha256_hex(impl.source_bytes.bytes()); });
    if (auto shape = check_json_shape(json_of(*bytes, impl.binary), path.string(), policy.limits); !shape)
        return shape.error();
    LoadContext ctx;
    ctx.scene = path.string();
    ctx.folder = path.parent_path();
    ctx.policy = &policy;
    ctx.hashes = &impl.content_hashes;
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(&keep_image_encoded, nullptr);
    loader.SetImageWriter(&keep_image_uri, nullptr);
    loader.SetFsCallbacks(fs_callbacks(&ctx));
    std::string err, warn;
    const std::string base_dir = kMarker;
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
    if (!ok && !ctx.refusal.empty()) return make_error(ctx.refusal);
    if (!ok) {
        const std::string reason = first_line(err.empty() ? warn : err);
        return make_error(path.string() + ": not a valid glTF file: " + (reason.empty() ? "parse error" : reason));
    }
    if (auto r = check_structure(impl.model, path.string(), policy.limits); !r) return r.error();
    if (auto r = resolve_files(impl, ctx); !r) return r.error();
    impl.buffers.resize(impl.model.buffers.size());
    for (size_t i = 0; i < impl.buffers.size(); ++i) impl.buffers[i].swap(impl.model.buffers[i].data);
    return scene;
}

std::string GltfScene::content_hash(const fs::path& file) const {
    impl_->finish_source_hash();
    auto it = impl_->content_hashes.find(file.lexically_normal());
    return it == impl_->content_hashes.end() ? std::string() : it->second;
}

std::vector<fs::path> GltfScene::resource_files() const {
    std::vector<fs::path> out;
    auto add = [&](const fs::path& p) {
        std::error_code ec;
        if (!p.empty() && fs::is_regular_file(p, ec) && std::find(out.begin(), out.end(), p) == out.end())
            out.push_back(p);
    };
    for (const fs::path& p : impl_->buffer_paths) add(p);
    for (const fs::path& p : impl_->image_paths) add(p);
    for (const fs::path& p : impl_->other_files) add(p);
    return out;
}

std::string GltfScene::image_label(int image) const { return gltf::image_label(*impl_, image); }

fs::path GltfScene::image_file(int image) const {
    const tinygltf::Model& m = impl_->model;
    if (image < 0 || size_t(image) >= m.images.size()) return {};
    const tinygltf::Image& img = m.images[size_t(image)];
    if (img.bufferView >= 0 || size_t(image) >= impl_->image_paths.size()) return {};
    return impl_->image_paths[size_t(image)];
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
    if (size_t(image) >= impl_->image_paths.size() || impl_->image_paths[size_t(image)].empty())
        return make_error(image_label(image) + ": not a local file");
    return read_file(impl_->image_paths[size_t(image)]);
}

}  // namespace specbake::io
