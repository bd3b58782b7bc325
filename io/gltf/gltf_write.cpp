// Writing a scene: the output plan (io/gltf/gltf_buffers.cpp) serialised to glTF JSON by tinygltf, the buffers
// array set from the plan, and every file (scene, buffers, image copies) written atomically together.
#include "io/gltf/gltf_internal.h"

#include "io/files/file_name.h"

#include <algorithm>
#include <cctype>
#include <set>
#include <sstream>

namespace specbake::io {
namespace fs = std::filesystem;
using gltf::OutBuffer;
using nlohmann::json;

Result<std::vector<GltfScene::WrittenFile>> GltfScene::write(const fs::path& path,
                                                             const std::vector<std::string>& reserved) const {
    const std::string ext = lower_extension(path);
    if (ext != ".gltf" && ext != ".glb") return make_error(path.string() + ": output must end in .gltf or .glb");
    const bool glb = ext == ".glb";
    const fs::path out_dir = path.parent_path().empty() ? fs::path(".") : path.parent_path();

    auto planned = gltf::plan_output(*impl_, path, glb, reserved);
    if (!planned) return planned.error();
    tinygltf::Model& m = planned->model;
    const std::vector<OutBuffer>& out_buffers = planned->buffers;
    const int target_buffer = planned->target_buffer;

    // The JSON, serialised by tinygltf without buffer payloads; then each buffer's length, URI, name and
    // extensions are set from the output plan (tinygltf 2.7 drops buffer extensions when serialising).
    std::vector<tinygltf::Buffer> input_buffers = std::move(m.buffers);
    m.buffers.assign(out_buffers.size(), tinygltf::Buffer());
    std::string json_text;
    try {
        tinygltf::TinyGLTF writer;
        writer.SetImageWriter(&gltf::keep_image_uri, nullptr);
        writer.SetFsCallbacks(gltf::fs_callbacks(nullptr));
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
                if (in.extras.Type() != tinygltf::NULL_TYPE) e["extras"] = gltf::from_value(in.extras);
                for (const auto& [name, value] : in.extensions) e["extensions"][name] = gltf::from_value(value);
            } else if (int(&b - out_buffers.data()) == target_buffer && !glb) {
                e["name"] = "specbake";
            }
            doc["buffers"].push_back(std::move(e));
        }
    }

    // Baked textures carried in the GLB: "embedded": k in the vendor extension's outputs becomes the view.
    if (glb && !planned->baked_views.empty() && doc.contains("materials")) {
        auto resolve = [&](json& outputs) -> Result<void> {
            if (!outputs.is_array()) return {};
            for (json& o : outputs) {
                if (!o.is_object() || !o.contains("embedded")) continue;
                const int k = o["embedded"].get<int>();
                if (k < 0 || size_t(k) >= planned->baked_views.size())
                    return make_error(path.string() + ": embedded texture " + std::to_string(k) + " was not planned");
                o.erase("embedded");
                o["bufferView"] = planned->baked_views[size_t(k)];
            }
            return {};
        };
        for (json& mat : doc["materials"]) {
            if (!mat.contains("extensions") || !mat["extensions"].contains(kSpecbakeExtension)) continue;
            json& e = mat["extensions"][kSpecbakeExtension];
            if (e.contains("outputs"))
                if (auto r = resolve(e["outputs"]); !r) return r.error();
            if (e.contains("clearcoat") && e["clearcoat"].contains("outputs"))
                if (auto r = resolve(e["clearcoat"]["outputs"]); !r) return r.error();
        }
    }

    // Every file goes to a temporary first; all are renamed into place once all are written.
    std::vector<std::unique_ptr<AtomicOutput>> outputs;
    std::vector<WrittenFile> written;
    auto emit = [&](const fs::path& file, const std::vector<std::span<const uint8_t>>& pieces,
                    std::string renamed_from = {}) -> Result<void> {
        outputs.push_back(std::make_unique<AtomicOutput>(file));
        auto hash = gltf::write_pieces(*outputs.back(), pieces);
        if (!hash) return hash.error();
        written.push_back({file, std::move(*hash), std::move(renamed_from)});
        return {};
    };
    const std::string text = doc.dump(glb ? -1 : 2);
    if (glb) {
        auto container = gltf::pack_glb(path, text, out_buffers.empty() ? nullptr : &out_buffers[0].bytes);
        if (!container) return container.error();
        if (auto r = emit(path, container->pieces()); !r) return r.error();
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
    for (const gltf::ImageCopy& c : planned->copies) {
        const fs::path dst = out_dir / c.to;
        if (!copied.insert(dst).second) continue;
        std::error_code ec;
        if (fs::exists(dst, ec) && fs::equivalent(c.from, dst, ec)) continue;
        auto bytes = read_file(c.from);
        if (!bytes) return bytes.error();
        if (auto r = emit(dst, {std::span<const uint8_t>(*bytes)}, c.renamed_from); !r) return r.error();
    }
    for (const auto& out : outputs)
        if (auto r = out->commit(); !r) return r.error();
    return written;
}

}  // namespace specbake::io
