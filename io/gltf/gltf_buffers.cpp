// Where the bytes of a written scene come from: the input buffers merged into the GLB binary chunk or kept
// as files beside a .gltf, external images embedded in the GLB or copied, and the appended vertex data.
#include "io/gltf/gltf_internal.h"

#include "core/assert.h"
#include "io/files/file_name.h"
#include "io/gltf/gltf_uri.h"

#include <algorithm>
#include <cctype>
#include <map>
#include <set>

namespace specbake::io::gltf {
namespace fs = std::filesystem;

namespace {

std::string mime_type_of(const fs::path& file) {
    const std::string e = lower_extension(file);
    if (e == ".png") return "image/png";
    if (e == ".jpg" || e == ".jpeg") return "image/jpeg";
    if (e == ".ktx2") return "image/ktx2";  // KHR_texture_basisu
    if (e == ".webp") return "image/webp";  // EXT_texture_webp
    if (e == ".dds") return "image/vnd-ms.dds";  // MSFT_texture_dds
    return {};
}

// Where the copy of an image file goes, relative to the output folder: its path relative to the scene's
// folder, or its file name when it lies outside (in an allowed root).
fs::path copy_name(const fs::path& file, const fs::path& src_dir) {
    const fs::path rel = file.lexically_relative(src_dir.empty() ? fs::path(".") : src_dir);
    if (rel.empty() || *rel.begin() == ".." || rel.is_absolute()) return file.filename();
    return rel;
}

// `wanted`, or, when the bake writes a file of that name or another file was copied there, the first of
// NAME_1.EXT, NAME_2.EXT ... that is free (deterministic: the images are taken in their glTF order).
fs::path free_name(const fs::path& wanted, const std::set<std::string>& used) {
    if (!used.count(wanted.generic_string())) return wanted;
    for (int k = 1;; ++k) {
        fs::path candidate = wanted.parent_path() / (wanted.stem().string() + "_" + std::to_string(k) +
                                                     wanted.extension().string());
        if (!used.count(candidate.generic_string())) return candidate;
    }
}

// Names in the output folder already taken (the files the caller writes, the scene, then the buffers and
// copies as they are planned) and the copies of external image files planned so far.
class OutputNames {
public:
    OutputNames(const std::vector<std::string>& reserved, const fs::path& scene_file, const fs::path& src_dir)
        : used_(reserved.begin(), reserved.end()), src_dir_(src_dir) {
        used_.insert(scene_file.filename().generic_string());
    }
    bool taken(const std::string& name) const { return used_.count(name) > 0; }
    void take(const std::string& name) { used_.insert(name); }

    // `img` (an external file `from`) copied into the output folder; an image file used twice is copied
    // once. The URI changes only where the file's place does.
    void plan_copy(OutputPlan& plan, tinygltf::Image& img, const fs::path& from) {
        auto [it, is_new] = copy_of_file_.try_emplace(from);
        if (is_new) {
            const fs::path wanted = copy_name(from, src_dir_);
            it->second = free_name(wanted, used_);
            used_.insert(it->second.generic_string());
            plan.copies.push_back({from, it->second, it->second == wanted ? std::string() : wanted.generic_string()});
        }
        const std::string uri = percent_encode(it->second.generic_string());
        if (fs::path(percent_decode(img.uri)).lexically_normal() != it->second) img.uri = uri;
    }

private:
    std::set<std::string> used_;
    fs::path src_dir_;
    std::map<fs::path, fs::path> copy_of_file_;
};

// Appends `bytes` (kept in plan.embedded_images) to the GLB's binary chunk on a new buffer view named
// `name`; returns the view's index. The vector's heap block does not move when embedded_images grows, so
// the chunk's span of it stays valid.
int append_embedded_view(OutputPlan& plan, std::vector<uint8_t>&& bytes, const std::string& name) {
    SPECBAKE_ASSERT(!plan.buffers.empty());
    plan.embedded_images.push_back(std::move(bytes));
    tinygltf::BufferView bv;
    bv.buffer = 0;
    bv.byteLength = plan.embedded_images.back().size();
    bv.byteOffset = plan.buffers[0].bytes.append(plan.embedded_images.back());
    bv.name = name;
    plan.model.bufferViews.push_back(bv);
    return int(plan.model.bufferViews.size() - 1);
}

// A GLB gets one buffer, its binary chunk, holding every input buffer, the external images (those with a
// MIME type glTF can name; the others stay external files next to it) and the bake's own textures, so the
// file is self-contained.
Result<void> plan_glb_chunk(const SceneState& scene, OutputPlan& plan, OutputNames& names) {
    const Payloads& payloads = scene.buffers;
    tinygltf::Model& m = plan.model;
    plan.buffers.emplace_back();
    plan.buffers[0].source = payloads.size() == 1 ? 0 : -1;
    std::vector<size_t> shift(payloads.size());
    for (size_t i = 0; i < payloads.size(); ++i) shift[i] = plan.buffers[0].bytes.append(payloads[i]);
    for (tinygltf::BufferView& bv : m.bufferViews) {
        if (bv.buffer < 0 || size_t(bv.buffer) >= payloads.size()) continue;
        bv.byteOffset += shift[size_t(bv.buffer)];
        bv.buffer = 0;
    }
    std::map<fs::path, int> view_of_file;  // an image file used twice is stored once
    for (size_t i = 0; i < m.images.size(); ++i) {
        tinygltf::Image& img = m.images[i];
        if (i >= scene.image_paths.size() || scene.image_paths[i].empty()) continue;
        const fs::path& from = scene.image_paths[i];
        const std::string mime = mime_type_of(from);
        if (mime.empty()) {
            names.plan_copy(plan, img, from);
            continue;
        }
        auto [it, is_new] = view_of_file.try_emplace(from, -1);
        if (is_new) {
            auto bytes = read_file(from);
            if (!bytes) return make_error(image_label(scene, int(i)) + ": image referenced by the scene cannot be read");
            it->second = append_embedded_view(plan, std::move(*bytes), std::string());
        }
        img.bufferView = it->second;
        img.mimeType = mime;
        img.uri.clear();
    }
    // The bake's own textures, each on a buffer view after those of the input's images.
    for (const SceneState::BakedImage& b : scene.baked_images) {
        auto bytes = read_file(b.file);
        if (!bytes) return bytes.error();
        plan.baked_views.push_back(append_embedded_view(plan, std::move(*bytes), b.name));
    }
    plan.target_buffer = 0;
    return {};
}

// A .gltf keeps the input's buffers (written next to it, data URIs kept as they were) and appends one
// buffer for the new data; external images are copied next to the scene, at the same relative path when
// it stays inside the output folder, else under their file name (and the URI follows).
void plan_gltf_files(const SceneState& scene, const std::string& stem, OutputPlan& plan, OutputNames& names) {
    const Payloads& payloads = scene.buffers;
    const fs::path src_dir = scene.source.parent_path();
    tinygltf::Model& m = plan.model;
    for (size_t i = 0; i < payloads.size(); ++i) {
        OutBuffer b;
        b.source = int(i);
        b.bytes.append(payloads[i]);
        const std::string& uri = m.buffers[i].uri;
        if (is_data_uri(uri)) {
            b.uri = uri;
            plan.buffers.push_back(std::move(b));
            continue;
        }
        std::string rel;
        if (i < scene.buffer_paths.size() && !scene.buffer_paths[i].empty())
            rel = copy_name(scene.buffer_paths[i], src_dir).generic_string();
        if (rel.empty() || names.taken(rel)) {
            const std::string base = stem + (i == 0 ? "" : "_" + std::to_string(i));
            rel = base + ".bin";
            for (int k = 1; names.taken(rel); ++k) rel = base + "_" + std::to_string(k) + ".bin";
        }
        names.take(rel);
        b.uri = percent_encode(rel);
        b.file = rel;
        plan.buffers.push_back(std::move(b));
    }
    if (!scene.added.empty()) {
        OutBuffer b;
        std::string rel = stem + "_specaa.bin";
        for (int k = 1; names.taken(rel); ++k) rel = stem + "_specaa_" + std::to_string(k) + ".bin";
        names.take(rel);
        b.uri = percent_encode(rel);
        b.file = rel;
        plan.buffers.push_back(std::move(b));
        plan.target_buffer = int(plan.buffers.size() - 1);
    }
    for (size_t i = 0; i < m.images.size(); ++i)
        if (i < scene.image_paths.size() && !scene.image_paths[i].empty()) names.plan_copy(plan, m.images[i], scene.image_paths[i]);
}

// Appended vertex data, on the target buffer. Primitives that share vertex data get equal values; they
// share one accessor too.
void append_added_attributes(const SceneState& scene, OutputPlan& plan) {
    tinygltf::Model& m = plan.model;
    std::vector<std::pair<const AddedAttribute*, int>> accessor_of_values;
    for (const AddedAttribute& a : scene.added) {
        int shared = -1;
        for (const auto& [previous, accessor] : accessor_of_values)
            if (previous->attribute == a.attribute && previous->components == a.components && previous->values == a.values)
                shared = accessor;
        if (shared >= 0) {
            m.meshes[size_t(a.ref.mesh)].primitives[size_t(a.ref.primitive)].attributes[a.attribute] = shared;
            continue;
        }
        SPECBAKE_ASSERT(plan.target_buffer >= 0 && size_t(plan.target_buffer) < plan.buffers.size());
        SPECBAKE_ASSERT(a.components >= 1 && a.components <= 4 && a.values.size() % size_t(a.components) == 0);
        tinygltf::BufferView bv;
        bv.buffer = plan.target_buffer;
        bv.byteLength = a.values.size() * sizeof(float);
        bv.byteOffset = plan.buffers[size_t(plan.target_buffer)].bytes.append(
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
}

}  // namespace

Result<OutputPlan> plan_output(const SceneState& scene, const fs::path& path, bool glb,
                               const std::vector<std::string>& reserved) {
    OutputPlan plan;
    plan.model = scene.model;  // the buffers hold no bytes, so this copies only the JSON side
    OutputNames names(reserved, path, scene.source.parent_path());
    if (glb) {
        if (auto ok = plan_glb_chunk(scene, plan, names); !ok) return ok.error();
    } else {
        plan_gltf_files(scene, path.stem().string(), plan, names);
    }
    for (const ImageCopy& c : plan.copies) {
        std::error_code ec;
        if (!fs::is_regular_file(c.from, ec))
            return make_error(c.from.string() + ": image referenced by the scene does not exist");
    }
    append_added_attributes(scene, plan);
    if (glb && plan.buffers[0].bytes.size == 0) plan.buffers.clear();
    return plan;
}

}  // namespace specbake::io::gltf
