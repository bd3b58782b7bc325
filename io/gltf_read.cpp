// Loading a .gltf or .glb through tinygltf with images left encoded and every file read hashed; the
// scene's source and resources, and the bytes, files and labels of its images.
#include "io/gltf_internal.h"

#include "io/gltf_uri.h"
#include "io/sha256.h"

#include <algorithm>
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

}  // namespace

tinygltf::FsCallbacks fs_callbacks(std::map<fs::path, std::string>* hashes) {
    return tinygltf::FsCallbacks{&fs_file_exists, &fs_expand_path, &fs_read_whole_file, &fs_refuse_write, hashes};
}

bool keep_image_uri(const std::string*, const std::string*, const tinygltf::Image*, bool, std::string*, void*) {
    return false;
}

std::string image_label(const SceneState& scene, int image) {
    const tinygltf::Model& m = scene.model;
    const std::string file = scene.source.string();
    if (image < 0 || size_t(image) >= m.images.size()) return file + ": image " + std::to_string(image);
    const tinygltf::Image& img = m.images[size_t(image)];
    if (!img.uri.empty() && !is_data_uri(img.uri))
        return (scene.source.parent_path() / percent_decode(img.uri)).string();
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

std::string GltfScene::image_label(int image) const { return gltf::image_label(*impl_, image); }

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

}  // namespace specbake::io
