// Private to io/gltf_*.cpp: the state behind GltfScene (the tinygltf model, the buffer bytes kept apart
// from it, the attributes to append) and the tinygltf-side helpers the reading and writing files share.
#pragma once

#include "io/files/file_read.h"
#include "io/gltf/glb_pack.h"
#include "io/gltf/gltf_scene.h"
#include "io/files/input_policy.h"

// Declarations only: the implementation is compiled once, in io/gltf/tinygltf_impl.cpp.
#include "io/gltf/tinygltf_internal.h"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <tbb/task_group.h>

namespace specbake::io {
namespace gltf {

inline constexpr int kModeTriangles = 4;
inline constexpr int kModeStrip = 5;
inline constexpr int kModeFan = 6;

// The bytes of every buffer, held apart from the tinygltf model so that copying the model for a write
// never copies them.
using Payloads = std::vector<std::vector<unsigned char>>;

// A float vertex attribute set by set_vertex_attribute(), appended by write().
struct AddedAttribute {
    PrimitiveRef ref;
    std::string attribute;
    std::vector<float> values;
    int components = 4;
};

struct SceneState {
    tinygltf::Model model;  // its buffers hold no data: the bytes are in `buffers`
    Payloads buffers;
    std::filesystem::path source;
    bool binary = false;
    InputLimits limits;  // of the policy the scene was loaded with; accessors are read against them
    std::map<std::filesystem::path, std::string> content_hashes;  // of the files read at load
    // The file of every image and buffer stored as an external file, resolved once by the path policy
    // (io/files/input_policy.h) at load; empty for embedded and remote ones. Everything reads these.
    std::vector<std::filesystem::path> image_paths, buffer_paths;
    // Other files the scene was read from: what Assimp opened besides the asset (an OBJ's .mtl).
    std::vector<std::filesystem::path> other_files;
    // Files the bake wrote that a GLB output carries as images (GltfScene::embed_baked_image).
    struct BakedImage {
        std::filesystem::path file;
        std::string mime_type, name;  // the name goes on the buffer view
    };
    std::vector<BakedImage> baked_images;
    // The textures use_basisu_textures made, by KTX2 file and fallback: materials sharing one bake share one
    // texture and one image per file.
    std::map<std::pair<std::string, std::string>, int> basisu_textures;
    std::map<std::string, int> basisu_images;  // by URI: one image per file
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
    ~SceneState() {
        if (source_hashing) source_hashing->wait();
    }
    std::vector<AddedAttribute> added;
};

// What tinygltf's file access needs while a scene loads: the scene (for messages) and its folder, the
// path policy, where to put the hashes of the files read (null: no hashing), the files read, and the
// first URI the policy refused.
struct LoadContext {
    std::string scene;
    std::filesystem::path folder;
    const InputPolicy* policy = nullptr;
    std::map<std::filesystem::path, std::string>* hashes = nullptr;
    std::vector<std::filesystem::path> read;
    std::string refusal;
};
// io/gltf/gltf_read.cpp: tinygltf's file access through std::filesystem and the path policy (`context` null:
// paths used as given, nothing hashed), refusing to write; and the image writer that leaves every image
// as it is.
tinygltf::FsCallbacks fs_callbacks(LoadContext* context);
bool keep_image_uri(const std::string*, const std::string*, const tinygltf::Image*, bool, std::string*, void*);
// URI or "<file>: image N", for messages.
std::string image_label(const SceneState& scene, int image);

// io/gltf/gltf_extension.cpp: extension objects between nlohmann::json and tinygltf::Value.
tinygltf::Value to_value(const nlohmann::json& j);
nlohmann::json from_value(const tinygltf::Value& v);

// io/gltf/gltf_accessors.cpp: a strided view into a buffer, range-checked once.
struct StridedView {
    const uint8_t* base = nullptr;
    size_t stride = 0;
};
Result<StridedView> view_of(const tinygltf::Model& m, const Payloads& payloads, int buffer_view, size_t byte_offset,
                            size_t count, size_t element_size, size_t element_stride_default,
                            const std::string& what);
// Float attribute with exactly `components` per element (TEXCOORD/NORMAL/...). An accessor without a
// bufferView is held to limits.accessor_elements before it is allocated.
Result<std::vector<float>> read_attribute(const tinygltf::Model& m, const Payloads& payloads, int index,
                                          int components, const std::string& what, const InputLimits& limits);
// An index accessor (unsigned byte, short or int scalars) as uint32.
Result<std::vector<uint32_t>> read_indices(const tinygltf::Model& m, const Payloads& payloads, int index,
                                           const std::string& what, const InputLimits& limits);

// io/gltf/gltf_buffers.cpp: where every byte of a written scene comes from.
struct OutBuffer {
    PieceList bytes;
    std::string uri;             // empty for the GLB binary chunk; a data URI is kept as it was
    std::filesystem::path file;  // relative to the output folder; empty when nothing is written for it
    int source = -1;             // input buffer written 1:1 (name, extensions kept), -1 for a merged or new one
};
struct ImageCopy {
    std::filesystem::path from;  // the resolved input file
    std::filesystem::path to;    // relative to the output folder
    std::string renamed_from;    // the name it would have had when that was taken; empty when not renamed
};
struct OutputPlan {
    tinygltf::Model model;  // the input's JSON side, with views, images and accessors set for the output
    std::vector<OutBuffer> buffers;
    std::vector<std::vector<uint8_t>> embedded_images;  // file bytes of images moved into the GLB
    std::vector<ImageCopy> copies;
    std::vector<int> baked_views;  // GLB: the buffer view of every SceneState::baked_images entry
    int target_buffer = -1;                                                        // holds the appended data
};
// The plan for writing `scene` to `path` (a .glb when `glb`, else a .gltf); its pieces point into `scene`
// and into the plan's own embedded images. `reserved`: names (relative to the output folder) the caller
// writes there itself, which no buffer or copied image may take.
Result<OutputPlan> plan_output(const SceneState& scene, const std::filesystem::path& path, bool glb,
                               const std::vector<std::string>& reserved);

}  // namespace gltf

struct GltfScene::Impl : gltf::SceneState {};

}  // namespace specbake::io
