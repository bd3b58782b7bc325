// Where the bytes of a written scene come from: the input buffers merged into the GLB binary chunk or kept
// as files beside a .gltf, external images embedded in the GLB or copied, and the appended vertex data.
#include "io/gltf_internal.h"

#include "io/gltf_uri.h"

#include <algorithm>
#include <cctype>
#include <map>
#include <set>

namespace specbake::io::gltf {
namespace fs = std::filesystem;

namespace {

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

Result<OutputPlan> plan_output(const SceneState& scene, const fs::path& path, bool glb) {
    const std::string stem = path.stem().string();
    const fs::path src_dir = scene.source.parent_path();
    const Payloads& payloads = scene.buffers;

    OutputPlan plan;
    plan.model = scene.model;  // the buffers hold no bytes, so this copies only the JSON side
    tinygltf::Model& m = plan.model;

    // A GLB gets one buffer, its binary chunk, holding every input buffer, the external images and the
    // appended data, so the file is self-contained. A .gltf keeps the input's buffers (written next to it)
    // and appends one buffer for the new data.
    std::vector<OutBuffer>& out_buffers = plan.buffers;
    std::vector<std::vector<uint8_t>>& embedded_images = plan.embedded_images;
    std::vector<std::pair<fs::path, fs::path>>& copies = plan.copies;
    int& target_buffer = plan.target_buffer;

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
                if (!bytes) return make_error(image_label(scene, int(i)) + ": image referenced by the scene cannot be read");
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
        if (!scene.added.empty()) {
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
    return plan;
}

}  // namespace specbake::io::gltf
