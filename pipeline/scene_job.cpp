#include "pipeline/scene_job.h"

#include "pipeline/gltf_replace.h"
#include "pipeline/uastc_encode.h"

#include "core/assert.h"
#include "io/output/bake_output.h"
#include "pipeline/concurrency.h"
#include "pipeline/glint_bake.h"
#include "pipeline/version.h"
#include "io/files/file_name.h"
#include "io/files/input_policy.h"
#include "io/mesh_import/mesh_import.h"
#include "io/files/sha256.h"
#include "mesh/generate_normals.h"

#include <algorithm>
#include <set>

namespace specbake {
namespace fs = std::filesystem;
using io::lower_extension;
using nlohmann::json;

namespace {

const char* format_of(const fs::path& p) {
    const std::string e = lower_extension(p);
    if (e == ".gltf") return "gltf";
    if (e == ".glb") return "glb";
    if (e == ".bin") return "bin";
    if (e == ".png") return "png";
    if (e == ".jpg" || e == ".jpeg") return "jpeg";
    if (e == ".ktx2") return "ktx2";
    if (e == ".webp") return "webp";
    return "file";
}

// Removes the files a failed scene wrote, so a failure leaves nothing half done.
void remove_files(const std::vector<fs::path>& files) {
    std::error_code ec;
    for (const fs::path& f : files) fs::remove(f, ec);
}

json root_extension(const SceneJob& job, bool textures) {
    json ext = {{"version", 1},
                {"generator", std::string("specbake ") + tool_version()},
                {"curvature",
                 {{"attribute", io::kCurvatureAttribute},
                  {"layout", "k1, k2, d.x, d.y"},
                  {"units", "1 / object-space length"},
                  {"space", "object"},
                  {"estimator", std::string(to_string(job.plan.estimator))}}}};
    if (textures) ext["textures"] = texture_settings_json(job.plan.texture_settings, job.texture_format);
    return ext;
}

struct SceneResult {
    std::vector<io::ManifestOutput> outputs;  // paths relative to the scene's output folder
    std::vector<io::ManifestInput> inputs;    // hashed
    std::vector<std::string> skipped;         // input failures taken as warnings
    std::vector<std::string> material_names;  // of the scene, for the check of config [materials.NAME]
    ScenePlan plan;
};

// One scene's bake in progress: where it writes (out_dir, staged, for final_dir), what it has written
// (removed if it fails) and what the manifest will list, each texture stem's files for the material
// extensions, and the outputs that move inside a .glb.
struct SceneBake {
    SceneBake(const SceneJob& scene_job, const fs::path& input_file, const fs::path& staged_dir,
              const fs::path& final_folder, std::vector<fs::path>& written_files, std::vector<std::string>& notes)
        : job(scene_job), input(input_file), out_dir(staged_dir), final_dir(final_folder), written(written_files),
          warnings(notes), say([&job = scene_job](const std::string& s) {
              if (job.progress) job.progress(s);
          }) {}

    const SceneJob& job;
    const fs::path& input;
    const fs::path& out_dir;
    const fs::path& final_dir;
    std::vector<fs::path>& written;
    std::vector<std::string>& warnings;
    std::function<void(const std::string&)> say;
    SceneResult result;
    // Layers with identical inputs share one set of files (the first one's, by its stem).
    std::map<std::string, std::vector<io::ManifestOutput>> files_by_stem;
    std::map<std::string, ReplaceLayer> replace_by_stem;  // --gltf-mode replace: the chains it encodes
    std::map<std::string, int> embedded;  // output path -> its number among the scene's embedded files
    // The materials each texture file serves (manifest "materials": one entry per file, every user listed).
    std::map<std::string, std::vector<int>> materials_of_file;
    void used_by(const std::string& path, int material) {
        std::vector<int>& m = materials_of_file[path];
        if (std::find(m.begin(), m.end(), material) == m.end()) m.push_back(material);
    }
};

// Each texture file's manifest entry lists the materials that use it.
void record_material_users(SceneBake& bake) {
    for (io::ManifestOutput& o : bake.result.outputs)
        if (auto it = bake.materials_of_file.find(o.path); it != bake.materials_of_file.end()) o.extra["materials"] = it->second;
}

// The plan's texture sink: the plan measures its statistic on the full bake and this writes each kept bake
// right away (and keeps, for --gltf-mode replace, the chains the replacement encodes).
TextureBakeSink texture_sink(SceneBake& bake, const io::GltfScene& scene, const PlanOptions& options) {
    return [&bake, &scene, &options](const TextureDecision& d, const TextureWork& w,
                                     TextureBakeResult&& baked) -> Result<void> {
        const SceneJob& job = bake.job;
        bake.say("writing " + (d.layer == "base" ? std::string() : d.layer + " ") + "textures of material " +
                 std::to_string(d.material) + " of " + bake.input.string());
        TextureInputs in;
        in.normal_map = w.normal;
        in.normal_name = scene.image_label(d.normal_image);
        in.roughness_map = w.roughness;
        in.roughness_name = w.roughness.empty() ? std::string() : scene.image_label(d.roughness_image);
        in.roughness_channel = w.roughness.empty() ? -1 : w.roughness_channel;
        in.roughness_value = d.roughness_value;
        in.normal_bits = w.normal_bits;
        in.roughness_bits = w.roughness_bits;
        // The replacement needs the mean normal (normalTexture); without it the layer keeps its slots.
        if (job.gltf_mode == GltfMode::Replace && d.layer == "base" && options.texture_settings_for(d.material_name).outputs.normal) {
            ReplaceLayer& r = bake.replace_by_stem[d.stem];
            r.stem = d.stem;
            r.roughness = baked.roughness;
            r.normal = baked.normal;
            if (!d.normal_outputs_stem.empty()) {  // baked once, with the earlier layer of the same normal map
                auto first = bake.replace_by_stem.find(d.normal_outputs_stem);
                if (first != bake.replace_by_stem.end()) r.normal = first->second.normal;
            }
            r.normal_bits = w.normal_bits;
            r.roughness_bits = w.roughness_bits;
        }
        const TextureBakeSettings settings = layer_bake_settings(d, options.texture_settings_for(d.material_name));
        auto out = write_texture_outputs(std::move(baked), in, settings, job.texture_format, bake.out_dir, d.stem,
                                         job.progress);
        if (!out) return out.error();
        for (const io::ManifestOutput& o : out->outputs) bake.written.push_back(bake.out_dir / o.path);
        bake.result.outputs.insert(bake.result.outputs.end(), out->outputs.begin(), out->outputs.end());
        bake.files_by_stem[d.stem] = std::move(out->outputs);
        return {};
    };
}

// Without replacement the files are all the bake needs: they are baked row by row straight into their
// bytes (KTX2 zstd and per-mip PNG streamed per level), as `specbake texture` does, so no float chain is
// held. The replacement encodes the float roughness and normal chains.
TextureBakeEncoder texture_encoder(SceneBake& bake) {
    return [&bake](const TextureDecision& d, const TextureWork& w,
                   const TextureBakeSettings& settings) -> Result<EncodedTextureBake> {
        const SceneJob& job = bake.job;
        TextureInputs in;
        in.normal_map = w.normal;
        // The plan names the image in its note; these keep the bake's own prefixes (name_error).
        in.normal_name = "normal map";
        in.roughness_map = w.roughness;
        in.roughness_name = "roughness map";
        in.roughness_channel = w.roughness_channel;
        in.roughness_value = d.roughness_value;
        in.normal_bits = w.normal_bits;
        in.roughness_bits = w.roughness_bits;
        in.release_rows = w.release_rows;
        auto encoded = std::make_shared<EncodedTextureOutputs>();
        auto baked = bake_texture_encoded(in, settings, job.texture_format, d.stem, {}, {}, bake.out_dir);
        if (!baked) return baked.error();
        *encoded = std::move(*baked);
        EncodedTextureBake out{encoded->max_roughness_change, encoded->notes, {}};
        out.write = [&bake, encoded](const TextureDecision& kept) -> Result<void> {
            bake.say("writing " + (kept.layer == "base" ? std::string() : kept.layer + " ") + "textures of material " +
                     std::to_string(kept.material) + " of " + bake.input.string());
            for (const io::EncodedFile& f : encoded->files) bake.say("writing " + f.stem);
            auto files = io::write_encoded_textures(encoded->files, bake.out_dir);
            if (!files) return files.error();
            for (const io::ManifestOutput& o : *files) bake.written.push_back(bake.out_dir / o.path);
            bake.result.outputs.insert(bake.result.outputs.end(), files->begin(), files->end());
            bake.files_by_stem[kept.stem] = std::move(*files);
            *encoded = EncodedTextureOutputs{};  // written: the next material's bake needs the memory
            return {};
        };
        return out;
    };
}

// Curvature, and the frame it refers to, set on the scene's primitives; returns how many were baked. The
// vectors move into the scene (the plan keeps the meshes' positions, which is all the manifest needs).
Result<size_t> move_curvature_into_scene(ScenePlan& plan, io::GltfScene& scene) {
    size_t baked_primitives = 0;
    for (auto& [index, work] : plan.work) {
        SPECBAKE_ASSERT(index < plan.primitives.size());
        const CurvatureDecision& d = plan.primitives[index];
        if (auto r = scene.set_vertex_attribute(d.ref, io::kCurvatureAttribute, std::move(work.curvature.values), 4); !r)
            return r.error();
        if (d.generates_tangents || work.report.repaired_tangents > 0)
            if (auto r = scene.set_vertex_attribute(d.ref, "TANGENT", std::move(work.mesh.tangents), 4); !r) return r.error();
        if (d.repairs_normals)
            if (auto r = scene.set_vertex_attribute(d.ref, "NORMAL", std::move(work.mesh.normals), 3); !r) return r.error();
        ++baked_primitives;
    }
    return baked_primitives;
}

// The MIME type under which a .glb carries a baked texture of `format` on a buffer view (KTX2, DDS, PNG);
// "" for the formats that stay beside it (EXR).
std::string embedded_mime_type(const std::string& format) {
    if (format == "ktx2") return "image/ktx2";
    if (format == "png") return "image/png";
    if (format == "dds") return "image/vnd-ms.dds";
    return {};
}

// Material extensions pointing at the files written during planning: the base layer's properties at the
// top of the object, the clear coat's in "clearcoat" (io/gltf/SPECBAKE_EXTENSION.md). In a .glb the
// textures with a MIME type go on buffer views, so it is self-contained (recorded in bake.embedded).
std::map<int, json> material_texture_extensions(SceneBake& bake, io::GltfScene& scene, const ScenePlan& plan,
                                                const PlanOptions& options, bool glb) {
    const std::vector<io::MaterialInfo> materials = scene.materials();
    std::map<int, json> extension_of_material;
    for (size_t i = 0; i < plan.textures.size(); ++i) {
        const TextureDecision& d = plan.textures[i];
        if (!d.bake) continue;
        const size_t owner = d.same_as >= 0 ? size_t(d.same_as) : i;
        SPECBAKE_ASSERT(d.material >= 0 && size_t(d.material) < materials.size() && owner < plan.textures.size());
        const io::MaterialInfo& mat = materials[size_t(d.material)];
        const bool coat = d.layer == "clearcoat";
        const io::TextureSlot& normal = coat ? mat.clearcoat.normal : mat.normal;
        // What the baked textures hold and where they lie (io/gltf/SPECBAKE_EXTENSION.md): the factors folded
        // into them, their UV mapping (the normal texture's), and whether a roughness output replaces the
        // material's roughness.
        json ext = {{"texCoord", d.texcoord}, {"roughnessReplaced", !d.roughness_mapped_apart},
                    {"source", {{coat ? "clearcoatNormalTexture" : "normalTexture", normal.texture}}}};
        json folded = {{"normalScale", d.normal_scale}};
        if (!d.roughness_mapped_apart) {
            ext["roughnessChannel"] = d.roughness_texture_used ? 1 : 0;
            folded["roughnessFactor"] = d.roughness_factor;
        }
        ext["folded"] = std::move(folded);
        if (d.roughness_texture_used)
            ext["source"][coat ? "clearcoatRoughnessTexture" : "metallicRoughnessTexture"] =
                coat ? mat.clearcoat.roughness.texture : mat.metallic_roughness.texture;
        else if (!d.roughness_mapped_apart)
            ext["source"]["roughness"] = d.roughness_value;
        if (const json t = io::uv_transform_json(normal); !t.is_null()) ext["KHR_texture_transform"] = t;
        const std::string& owner_name = plan.textures[owner].material_name;
        if (options.material_texture_settings.count(owner_name))  // differs from the root's "textures"
            ext["settings"] = texture_settings_json(options.texture_settings_for(owner_name), bake.job.texture_format);
        ext["outputs"] = json::array();
        // Its own files, then those it shares with an earlier bake of the same normal map (the kinds it
        // did not write itself).
        std::vector<io::ManifestOutput> files = bake.files_by_stem.at(d.stem);
        if (!d.normal_outputs_stem.empty()) {
            std::set<std::string> own;
            for (const io::ManifestOutput& o : files) own.insert(o.kind);
            for (const io::ManifestOutput& o : bake.files_by_stem.at(d.normal_outputs_stem))
                if (!own.count(o.kind)) files.push_back(o);
        }
        for (const io::ManifestOutput& o : files) {
            bake.used_by(o.path, d.material);
            json entry = {{"kind", o.kind}, {"uri", o.path}, {"format", o.format}, {"width", o.width},
                          {"height", o.height}, {"mips", o.mips}, {"channels", o.channels}};
            // Block-compressed (`--block bc`, `--block astc`): the GPU format, since BC5 / ASTC hold the normal's x, y only.
            if (o.extra.value("block_compression", "none") != "none") entry["gpuFormat"] = o.extra["gpu_format"];
            if (const std::string mime = embedded_mime_type(o.format); glb && !mime.empty()) {
                const int k = scene.embed_baked_image(bake.out_dir / o.path, mime, o.path);
                bake.embedded[o.path] = k;
                entry.erase("uri");
                entry["embedded"] = k;  // the scene writer puts the buffer view's index here
                entry["mimeType"] = mime;
            }
            ext["outputs"].push_back(std::move(entry));
        }
        json& target = extension_of_material[d.material];
        if (target.is_null()) target = json::object();
        if (coat) target["clearcoat"] = std::move(ext);
        else target.update(ext);
    }
    return extension_of_material;
}

// --gltf-mode replace: each baked base layer's textures encoded as UASTC KTX2 by basisu and put in the
// material's own slots.
Result<void> replace_with_uastc(SceneBake& bake, io::GltfScene& scene, const ScenePlan& plan, bool glb) {
    const SceneJob& job = bake.job;
    auto basisu = find_basisu(job.basisu);
    if (!basisu) return basisu.error();
    const std::vector<io::MaterialInfo> materials = scene.materials();
    std::vector<io::ManifestOutput>& outputs = bake.result.outputs;
    std::map<std::string, io::GltfScene::BasisuTextures> encoded_by_stem;  // one encode per shared bake
    std::map<std::string, std::vector<std::string>> files_of_stem;
    for (const TextureDecision& d : plan.textures) {
        if (!d.bake || d.layer != "base" || !bake.replace_by_stem.count(d.stem)) continue;
        const io::TextureSlot& normal = materials[size_t(d.material)].normal;
        if (auto it = encoded_by_stem.find(d.stem); it != encoded_by_stem.end()) {
            io::GltfScene::BasisuTextures t = it->second;
            t.texcoord = d.texcoord;
            t.transform = io::uv_transform_json(normal);
            scene.use_basisu_textures(d.material, t);
            for (const std::string& f : files_of_stem[d.stem]) bake.used_by(f, d.material);
            continue;
        }
        ReplaceLayer layer = bake.replace_by_stem.at(d.stem);
        layer.material = d.material;
        layer.roughness_from_texture = d.roughness_texture_used;
        layer.texcoord = d.texcoord;
        layer.transform = io::uv_transform_json(normal);
        layer.normal_scale = d.normal_scale;
        layer.roughness_factor = d.roughness_factor;
        if (auto first = encoded_by_stem.find(d.normal_outputs_stem); first != encoded_by_stem.end()) {
            layer.normal_from = &first->second;  // the same mean-normal chain, encoded once
            for (const std::string& uri : {first->second.normal_uri, first->second.normal_fallback_uri})
                if (!uri.empty()) bake.used_by(uri, d.material);
        }
        bake.say("encoding UASTC textures of material " + std::to_string(d.material) + " of " + bake.input.string());
        const size_t before = outputs.size();
        const io::Supercompression& supercompression = job.texture_format.supercompression;
        const int zstd = supercompression.zstd ? supercompression.zstd_level : 0;
        auto used = replace_with_basisu(scene, layer, *basisu, bake.out_dir, glb, outputs, bake.warnings, zstd);
        if (!used) return used.error();
        if (!used->normal_uri.empty()) encoded_by_stem[d.stem] = *used;
        for (size_t k = before; k < outputs.size(); ++k) {
            files_of_stem[d.stem].push_back(outputs[k].path);
            bake.used_by(outputs[k].path, d.material);
            bake.written.push_back(bake.out_dir / outputs[k].path);
            if (glb) bake.embedded[outputs[k].path] = -1;  // on a buffer view as a glTF image
        }
    }
    return {};
}

// Hashes of the inputs, asked for only now: the scene file's is computed in the background since the load,
// the other files the loader read come hashed with the scene, the rest (images, files read through
// Assimp) are hashed together here.
Result<std::vector<io::ManifestInput>> hash_inputs(const io::GltfScene& scene, const std::vector<fs::path>& inputs,
                                                   const fs::path& output_dir) {
    std::vector<fs::path> unhashed;
    for (const fs::path& in : inputs)
        if (scene.content_hash(in).empty()) unhashed.push_back(in);
    auto hashes = io::sha256_files(unhashed);
    if (!hashes) return hashes.error();
    std::vector<io::ManifestInput> hashed;
    for (size_t i = 0, next = 0; i < inputs.size(); ++i) {
        std::string hash = scene.content_hash(inputs[i]);
        SPECBAKE_ASSERT(!hash.empty() || next < hashes->size());
        hashed.push_back({io::recorded_input_path(inputs[i], output_dir), hash.empty() ? (*hashes)[next++] : std::move(hash)});
    }
    return hashed;
}

// The textures now inside the GLB leave the folder and the outputs; returns their manifest entries, which
// the manifest lists under the scene's entry.
Result<json> take_embedded_outputs(SceneBake& bake) {
    json inside = json::array();
    if (bake.embedded.empty()) return inside;
    std::vector<io::ManifestOutput> kept;
    for (io::ManifestOutput& o : bake.result.outputs) {
        const auto it = bake.embedded.find(o.path);
        if (it == bake.embedded.end()) {
            kept.push_back(std::move(o));
            continue;
        }
        std::error_code ec;
        fs::remove(bake.out_dir / o.path, ec);
        if (ec) return make_error((bake.out_dir / o.path).string() + ": cannot remove: " + ec.message());
        bake.written.erase(std::remove(bake.written.begin(), bake.written.end(), bake.out_dir / o.path), bake.written.end());
        json e = {{"name", o.path}, {"mimeType", embedded_mime_type(o.format)}, {"kind", o.kind},
                  {"format", o.format}, {"width", o.width}, {"height", o.height}, {"mips", o.mips},
                  {"channels", o.channels}, {"sha256", o.sha256}};
        for (const auto& [key, value] : o.extra.items()) e[key] = value;
        inside.push_back(std::move(e));
    }
    bake.result.outputs = std::move(kept);
    return inside;
}

// The manifest entries of the files the scene writer wrote: the scene first (its entry's extra is
// `scene_extra`), then its buffers and copied images.
void add_scene_file_outputs(SceneBake& bake, const std::vector<io::GltfScene::WrittenFile>& files,
                            const json& scene_extra) {
    for (const io::GltfScene::WrittenFile& f : files) bake.written.push_back(f.path);
    for (size_t i = 0; i < files.size(); ++i) {
        const fs::path& f = files[i].path;
        io::ManifestOutput o;
        o.sha256 = files[i].sha256;
        o.kind = i == 0 ? "scene" : (std::string(format_of(f)) == "bin" ? "buffer" : "image");
        o.path = io::relative_path(f, bake.out_dir);
        o.format = format_of(f);
        if (!files[i].renamed_from.empty()) o.extra = {{"renamed_from", files[i].renamed_from}};
        if (i == 0) o.extra = scene_extra;
        bake.result.outputs.push_back(std::move(o));
    }
}

// Writes into `out_dir` (staged) what belongs in `final_dir`.
Result<SceneResult> bake_one_scene(const SceneJob& job, const fs::path& input, const fs::path& out_dir,
                                   const fs::path& final_dir, std::vector<fs::path>& written,
                                   std::vector<std::string>& warnings) {
    SceneBake bake(job, input, out_dir, final_dir, written, warnings);
    bake.say("reading " + input.string());
    auto loaded = load_scene(input, job.plan.input_policy);
    if (!loaded) return loaded.error();
    for (const std::string& n : loaded->notes) warnings.push_back(n);
    io::GltfScene& scene = loaded->scene;

    std::vector<fs::path> inputs{input};
    for (const fs::path& r : scene.resource_files()) inputs.push_back(r);
    if (auto r = io::check_output_not_input(final_dir, inputs); !r) return r.error();
    if (!job.depfile.empty())
        if (auto r = io::check_depfile_path(job.depfile, job.output_dir, inputs); !r) return r.error();

    PlanOptions options = job.plan;
    options.texture_sink = texture_sink(bake, scene, options);
    if (job.gltf_mode != GltfMode::Replace)
        options.texture_encoder = texture_encoder(bake);
    // Materials that ask for glints get slope-space LEAN moments of their normal map (C21 Eq. 16).
    if (auto r = add_glint_lean_settings(scene, options); !r) return r.error();
    bake.say("planning " + input.string());
    auto plan = make_plan(scene, options, loaded->roughness_known);
    if (!plan) return plan.error();
    for (const std::string& n : plan->notes) warnings.push_back(n);
    if (!plan->input_errors.empty()) {
        if (!job.unreadable_textures_are_warnings) {
            // The first names the scene, the material and the file; the rest follow as warnings.
            for (size_t i = 1; i < plan->input_errors.size(); ++i) warnings.push_back(plan->input_errors[i]);
            return make_error(plan->input_errors.front() +
                              (plan->input_errors.size() > 1
                                   ? " (and " + std::to_string(plan->input_errors.size() - 1) + " more)"
                                   : std::string()));
        }
        for (const std::string& e : plan->input_errors) warnings.push_back(e);
        bake.result.skipped = plan->input_errors;
    }
    auto baked_primitives = move_curvature_into_scene(*plan, scene);
    if (!baked_primitives) return baked_primitives.error();

    std::string ext = loaded->is_gltf && scene.source_is_binary() ? ".glb" : ".gltf";
    if (job.format == SceneFormat::Gltf) ext = ".gltf";
    if (job.format == SceneFormat::Glb) ext = ".glb";
    const bool glb = ext == ".glb";
    std::map<int, json> extension_of_material = material_texture_extensions(bake, scene, *plan, options, glb);
    if (auto r = add_glint_outputs(*plan, out_dir, final_dir, bake.say, bake.files_by_stem, extension_of_material,
                                   written, bake.result.outputs);
        !r)
        return r.error();
    if (job.gltf_mode == GltfMode::Replace)
        if (auto r = replace_with_uastc(bake, scene, *plan, glb); !r) return r.error();
    for (const auto& [material, ext] : extension_of_material) scene.set_material_extension(material, ext);
    record_material_users(bake);
    const bool any_texture = !extension_of_material.empty();
    if (*baked_primitives > 0 || any_texture) scene.set_root_extension(root_extension(job, any_texture));
    auto hashed = hash_inputs(scene, inputs, job.output_dir);
    if (!hashed) return hashed.error();
    bake.result.inputs = std::move(*hashed);

    const fs::path out_file = out_dir / (input.stem().string() + ext);
    bake.say("writing " + (final_dir / out_file.filename()).string());
    // Copied images never take the name of a file this bake writes: the textures, the manifest.
    std::vector<std::string> reserved{"manifest.json"};
    for (const io::ManifestOutput& o : bake.result.outputs) reserved.push_back(o.path);
    auto files = scene.write(out_file, reserved);
    if (!files) return files.error();
    auto inside = take_embedded_outputs(bake);
    if (!inside) return inside.error();
    size_t vertices = 0;
    for (const auto& [index, work] : plan->work) vertices += work.mesh.vertex_count();
    json scene_extra = {{"curvature_primitives", *baked_primitives},
                        {"curvature_vertices", vertices},
                        {"curvature_space",
                         "object: _SPECAA_CURVATURE is in 1/object-space length; a node scale s divides it by s "
                         "in world space"},
                        {"source_format", loaded->is_gltf ? (scene.source_is_binary() ? "glb" : "gltf")
                                                          : lower_extension(input).substr(1)}};
    if (!inside->empty()) scene_extra["embedded_images"] = *inside;
    add_scene_file_outputs(bake, *files, scene_extra);
    for (const io::MaterialInfo& m : scene.materials()) bake.result.material_names.push_back(m.name);
    bake.result.plan = std::move(*plan);
    return std::move(bake.result);
}

}  // namespace

Result<LoadedScene> load_scene(const fs::path& path, const io::InputPolicy& policy) {
    if (auto r = io::check_utf8_path(path); !r) return r.error();
    LoadedScene out;
    const std::string ext = lower_extension(path);
    if (ext == ".gltf" || ext == ".glb") {
        auto scene = io::GltfScene::load(path, policy);
        if (!scene) return scene.error();
        out.scene = std::move(*scene);
        out.roughness_known.assign(out.scene.materials().size(), true);
        return out;
    }
    auto imported = import_mesh(path.string(), {}, policy);
    if (!imported) return imported.error();
    out.is_gltf = false;
    out.notes = imported->notes;
    size_t generated = 0;
    for (TriMesh& m : imported->meshes) {
        if (m.has_normals()) continue;
        generate_normals(m);  // Max (1999) weights, as for glTF primitives without normals
        ++generated;
    }
    if (generated > 0)
        out.notes.push_back(path.string() + ": " + std::to_string(generated) +
                            " mesh(es) without normals: normals generated (Max weights) and written");
    for (const ImportedMaterial& m : imported->materials)
        out.roughness_known.push_back(m.roughness_from_file || m.roughness_factor != 1.0f);
    auto scene = io::GltfScene::from_imported(*imported);
    if (!scene) return scene.error();
    out.scene = std::move(*scene);
    return out;
}

Result<ScenePlan> plan_scene(const fs::path& path, const PlanOptions& options) {
    auto loaded = load_scene(path, options.input_policy);
    if (!loaded) return loaded.error();
    auto plan = make_plan(loaded->scene, options, loaded->roughness_known);
    if (!plan) return plan.error();
    plan->notes.insert(plan->notes.begin(), loaded->notes.begin(), loaded->notes.end());
    return plan;
}

json scene_settings_json(const SceneJob& job) {
    json s = {{"estimator", std::string(to_string(job.plan.estimator))},
              {"format", job.format == SceneFormat::SameAsInput ? "same as input" : std::string(to_string(job.format))},
              {"textures", job.plan.textures},
              {"check_material", job.plan.check_material},
              {"kappa", job.plan.kappa},
              {"min_roughness_gain", job.plan.min_roughness_gain},
              {"min_relative_curvature", job.plan.min_relative_curvature},
              {"curvature_space", "object (1/object-space length; node scale s divides it by s in world space)"}};
    // Glints asked through the config, so the up-to-date check sees a changed value (absent otherwise).
    if (!job.plan.material_glints.empty()) {
        json glints = json::object();
        for (const auto& [name, object] : job.plan.material_glints) glints[name] = object;
        s["material_glints"] = glints;
    }
    if (job.gltf_mode != GltfMode::Sidecar) s["gltf_mode"] = std::string(to_string(job.gltf_mode));
    // Recorded only when asked, so manifests of bakes without it stay as they were.
    const io::Supercompression& supercompression = job.texture_format.supercompression;
    if (supercompression.block != io::BlockFamily::None)
        s["supercompression"] = supercompression_json(supercompression);
    if (job.plan.textures) {
        s["texture"] = texture_settings_json(job.plan.texture_settings, job.texture_format);
        // Per-material settings as applied, so the up-to-date check sees a changed override.
        if (!job.plan.material_texture_settings.empty()) {
            json materials = json::object();
            for (const auto& [name, settings] : job.plan.material_texture_settings)
                materials[name] = texture_settings_json(settings, job.texture_format);
            s["materials"] = materials;
        }
    }
    return s;
}

Result<SceneJobOutcome> run_scene_job(const SceneJob& job) {
    if (job.scenes.empty()) return make_error("no scene given");
    if (auto r = io::check_utf8_path(job.output_dir); !r) return r.error();
    const io::TextureFileFormat& format = job.texture_format;
    if (const std::string p = io::block_container_problem(format.container, format.supercompression.block); !p.empty())
        return make_error(p);
    SceneJobOutcome outcome;
    outcome.manifest.version = tool_version();
    outcome.manifest.settings = scene_settings_json(job);

    std::vector<fs::path> all_inputs(job.scenes.begin(), job.scenes.end());
    if (auto r = io::check_output_not_input(job.output_dir, all_inputs); !r) return r.error();
    std::set<std::string> stems;
    for (const fs::path& s : job.scenes)
        if (!stems.insert(s.stem().string()).second && job.scenes.size() > 1)
            return make_error(s.string() + ": another scene has the same name '" + s.stem().string() +
                              "'; each scene gets its own folder named after it, so names must differ");

    std::vector<std::string> identity;
    for (const fs::path& s : job.scenes) identity.push_back(io::recorded_input_path(s, job.output_dir));
    auto out = io::BakeOutput::open(job.output_dir, job.lock, identity, job.replace, job.progress);
    if (!out) return out.error();
    // The scenes are baked side by side (each one's own parallel loops still use every thread) into the
    // staging folder and merged in input order, so the manifest and the messages do not depend on the
    // thread count.
    struct Baked {
        Result<SceneResult> result = make_error("");
        std::vector<std::string> warnings;
    };
    std::vector<Baked> baked(job.scenes.size());
    for_each_concurrently(job.scenes.size(), [&](size_t i) {
        const fs::path& input = job.scenes[i];
        const bool one = job.scenes.size() == 1;
        const fs::path out_dir = one ? out->stage() : out->stage() / input.stem();
        const fs::path final_dir = one ? job.output_dir : job.output_dir / input.stem();
        std::vector<fs::path> written;
        Baked& b = baked[i];
        b.result = bake_one_scene(job, input, out_dir, final_dir, written, b.warnings);
        if (b.result) {
            // What the bake computed is written; the plan keeps its decisions only, so a batch of many
            // scenes holds the data of the scenes in work, not of every scene baked so far.
            b.result->plan.work.clear();
            b.result->plan.texture_work.clear();
            b.result->plan.decoded_images.clear();
            b.result->plan.decoded_integers.clear();
        } else {
            remove_files(written);
        }
        if (job.scene_finished) job.scene_finished(i, b.result ? std::string() : b.result.error().message);
    });
    for (size_t i = 0; i < job.scenes.size(); ++i) {
        const fs::path& input = job.scenes[i];
        Baked& b = baked[i];
        outcome.warnings.insert(outcome.warnings.end(), b.warnings.begin(), b.warnings.end());
        if (!b.result) {
            outcome.errors.push_back(out->final_names(b.result.error()).message);
            continue;
        }
        SceneResult& result = *b.result;
        const std::string prefix = job.scenes.size() == 1 ? "" : input.stem().string() + "/";
        for (io::ManifestOutput o : result.outputs) {
            o.path = prefix + o.path;
            outcome.manifest.outputs.push_back(std::move(o));
        }
        outcome.manifest.inputs.insert(outcome.manifest.inputs.end(), result.inputs.begin(), result.inputs.end());
        outcome.manifest.skipped.insert(outcome.manifest.skipped.end(), result.skipped.begin(), result.skipped.end());
        outcome.manifest.plan.push_back(plan_to_json(result.plan));
        outcome.manifest.plan.back()["scene"] = io::recorded_input_path(input, job.output_dir);
        outcome.plans.push_back(std::move(result.plan));
    }
    if (outcome.plans.empty()) return outcome;
    // A config table for a material no baked scene has is most likely a misspelt name.
    std::set<std::string> names;
    for (const Baked& b : baked)
        if (b.result) names.insert(b.result->material_names.begin(), b.result->material_names.end());
    std::set<std::string> configured;
    for (const auto& [name, settings] : job.plan.material_texture_settings) configured.insert(name);
    for (const auto& [name, glints] : job.plan.material_glints) configured.insert(name);
    for (const std::string& name : configured)
        if (!names.count(name))
            outcome.warnings.push_back("config: [materials." + name + "]: no material of the baked scene" +
                                       (job.scenes.size() > 1 ? "s" : "") + " is called '" + name + "'");
    if (auto r = io::write_manifest(out->stage(), outcome.manifest); !r) return out->final_names(r.error());
    if (auto r = out->commit(); !r) return r.error();
    return outcome;
}

}  // namespace specbake
