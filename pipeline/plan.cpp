#include "pipeline/plan.h"

#include "bake/isotropic_filter.h"
#include "core/text_format.h"
#include "io/image/image_io.h"
#include "mesh/curvature_summary.h"
#include "mesh/prepare_mesh.h"
#include "pipeline/texture_job.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <tuple>

namespace specbake {
namespace {

constexpr int kModeTriangles = 4;
constexpr int kModeFan = 6;

std::string format_number(double v) { return format_double("%.4g", v); }

// Half a quantisation step of a roughness texture stored with `bits` per channel (SPEC Sec. 6).
double half_quantisation_step(int bits, bool is_float) {
    if (is_float) return std::ldexp(1.0, -11);  // half float: 10 mantissa bits, steps of 2^-10 just below 1
    return 0.5 / (std::ldexp(1.0, std::clamp(bits, 1, 16)) - 1.0);
}

// "<file>: material 2 'Name'", for notes.
std::string material_label(const io::GltfScene& scene, int material, const std::string& name) {
    return scene.source().string() + ": material " + std::to_string(material) + (name.empty() ? "" : " '" + name + "'");
}

std::string sanitize(const std::string& name) {
    std::string out;
    for (char c : name) out.push_back(std::isalnum(uint8_t(c)) || c == '-' ? c : '_');
    if (out.size() > 40) out.resize(40);
    return out;
}

}  // namespace

TextureBakeSettings layer_bake_settings(const TextureDecision& d, TextureBakeSettings s) {
    if (d.roughness_mapped_apart) s.outputs.roughness = false;  // its statistic is measured all the same
    if (!d.normal_outputs_stem.empty()) {                        // these depend on the normal map alone
        s.outputs.kernel = s.outputs.normal = false;
        if (s.lean_space != LeanSpace::Slope) s.outputs.lean = false;
    }
    return s;
}

double roughness_gain(double r, double kappa) {
    const double a = std::pow(std::clamp(r, 0.0, 1.0), 4.0);
    return std::pow(filter_projected_isotropic(a, kappa), 0.25) - std::clamp(r, 0.0, 1.0);
}

namespace {

// The scene's images, decoded on first use into plan.decoded_images or, plain 8/16-bit PNGs as their integers
// (a quarter or half of the floats' memory, what `specbake texture` holds), plan.decoded_integers (kept for
// the bake), with their bit depth in plan.image_bits; an image that cannot be read is decoded once and its
// error kept.
class ImageDecoder {
public:
    ImageDecoder(const io::GltfScene& scene, const io::InputLimits& limits, ScenePlan& plan)
        : scene_(scene), limits_(limits), plan_(plan) {}

    // The decoded image as the bake reads it, or null (negative index, or not readable: see error()).
    const TextureMap* decode(int image) {
        if (image < 0) return nullptr;
        if (auto it = maps_.find(image); it != maps_.end()) return &it->second;
        if (errors_.count(image)) return nullptr;
        return keep(image, read(image));
    }
    // Decodes the `images` not decoded yet side by side, one task each, as decode() would one by one: a
    // scene's normal and roughness maps are read at once, as `specbake texture` reads its two maps.
    void prefetch(std::vector<int> images) {
        std::sort(images.begin(), images.end());
        images.erase(std::unique(images.begin(), images.end()), images.end());
        std::erase_if(images, [&](int i) { return i < 0 || maps_.count(i) || errors_.count(i); });
        std::vector<Result<io::DecodedImage>> decoded(images.size(), make_error(""));
        tbb::parallel_for(size_t(0), images.size(), [&](size_t i) { decoded[i] = read(images[i]); });
        for (size_t i = 0; i < images.size(); ++i) keep(images[i], std::move(decoded[i]));
    }
    // The first image of the scene stored in the same file as `image` (`image` itself when none is, or when
    // it is embedded): several image entries naming one file are decoded and baked once.
    int first_of_file(int image) {
        const std::filesystem::path file = image >= 0 ? scene_.image_file(image) : std::filesystem::path();
        if (file.empty()) return image;
        std::error_code ec;
        const std::filesystem::path canonical = std::filesystem::weakly_canonical(file, ec);
        return first_by_file_.emplace(ec ? file.lexically_normal() : canonical, image).first->second;
    }
    // Why `image` could not be decoded ("" when it was).
    const std::string& error(int image) { return errors_[image]; }
    bool is_float(int image) { return is_float_[image]; }

private:
    Result<io::DecodedImage> read(int image) const {
        if (const std::filesystem::path file = scene_.image_file(image); !file.empty())
            return io::decode_image(file, limits_, true);
        auto bytes = scene_.image_bytes(image);
        if (!bytes) return bytes.error();
        return io::decode_image_memory(*bytes, scene_.image_label(image), limits_, true);
    }
    const TextureMap* keep(int image, Result<io::DecodedImage> decoded) {
        if (!decoded) {
            errors_[image] = decoded.error().message;
            return nullptr;
        }
        plan_.image_bits[image] = decoded->info.bits_per_channel;
        is_float_[image] = decoded->info.is_float;
        if (!decoded->integers.empty()) {  // integers: nothing non-finite
            const io::IntegerTexels& t = plan_.decoded_integers.emplace(image, std::move(decoded->integers)).first->second;
            return &(maps_[image] = texture_map_of(t));
        }
        if (auto bad = find_non_finite(decoded->image)) {
            errors_[image] = scene_.image_label(image) + ": non-finite value at texel (" +
                             std::to_string(bad->first) + ", " + std::to_string(bad->second) + ")";
            return nullptr;
        }
        const Image& kept = plan_.decoded_images.emplace(image, std::move(decoded->image)).first->second;
        return &(maps_[image] = TextureMap::of(kept));
    }

    const io::GltfScene& scene_;
    const io::InputLimits& limits_;
    ScenePlan& plan_;
    std::map<int, TextureMap> maps_;
    std::map<int, bool> is_float_;
    std::map<int, std::string> errors_;
    std::map<std::filesystem::path, int> first_by_file_;
};

// The layers whose normals a texture bake can filter: the base (normalTexture, roughness from
// metallicRoughness G) and, with KHR_materials_clearcoat, the coat (clearcoatNormalTexture, roughness from
// clearcoatRoughnessTexture G), each with its own roughness factor and normal scale.
struct Layer {
    const char* name;
    const io::TextureSlot* normal;
    double normal_scale;
    const io::TextureSlot* roughness;
    double roughness_factor;
};

std::vector<Layer> layers_of(const io::MaterialInfo& mat) {
    std::vector<Layer> layers{{"base", &mat.normal, mat.normal_scale, &mat.metallic_roughness, mat.roughness_factor}};
    if (mat.clearcoat.present)
        layers.push_back({"clearcoat", &mat.clearcoat.normal, mat.clearcoat.normal_scale, &mat.clearcoat.roughness,
                          mat.clearcoat.roughness_factor});
    return layers;
}

// "SCENE: material M 'NAME' (LAYER) WHAT: PROBLEM", the line of ScenePlan::input_errors.
std::string input_error(const io::GltfScene& scene, size_t material, const io::MaterialInfo& mat, const Layer& layer,
                        const std::string& what, const std::string& problem) {
    std::string line = scene.source().string() + ": material " + std::to_string(material);
    if (!mat.name.empty()) line += " '" + mat.name + "'";
    if (std::string(layer.name) != "base") line += std::string(" (") + layer.name + ")";
    return line + " " + what + ": " + problem;
}

// Lowest perceptual roughness of a layer: its roughness factor times its smallest G texel.
double lowest_roughness(const io::GltfScene& scene, size_t material, const io::MaterialInfo& mat, const Layer& layer,
                        ImageDecoder& images, ScenePlan& plan) {
    double r = layer.roughness_factor;
    if (layer.roughness->image >= 0) {
        if (const TextureMap* img = images.decode(layer.roughness->image)) {
            const int ch = img->channels >= 2 ? 1 : 0;
            float lo = 1.0f;
            for (int y = 0; y < img->height; ++y)
                for (int x = 0; x < img->width; ++x) lo = std::min(lo, img->value(x, y, ch));
            r *= std::clamp(double(lo), 0.0, 1.0);
        } else if (std::string(layer.name) == "base" || mat.clearcoat.active()) {
            // A coat with clearcoatFactor 0 does not count, so its texture is not needed.
            plan.input_errors.push_back(input_error(scene, material, mat, layer, "roughness texture",
                                                    images.error(layer.roughness->image)));
        }
    }
    return r;
}

// Lowest roughness per material and layer, and per material that of its glossiest layer: a clear coat over
// a rough base aliases as much as a glossy base.
struct MaterialRoughness {
    std::vector<std::vector<double>> per_layer;
    std::vector<std::optional<double>> lowest;
};

MaterialRoughness lowest_material_roughness(const io::GltfScene& scene, const std::vector<io::MaterialInfo>& materials,
                                            ImageDecoder& images, ScenePlan& plan) {
    MaterialRoughness out{std::vector<std::vector<double>>(materials.size()),
                          std::vector<std::optional<double>>(materials.size())};
    for (size_t m = 0; m < materials.size(); ++m) {
        for (const Layer& layer : layers_of(materials[m])) out.per_layer[m].push_back(lowest_roughness(scene, m, materials[m], layer, images, plan));
        double r = out.per_layer[m][0];
        if (materials[m].clearcoat.active()) r = std::min(r, out.per_layer[m][1]);
        out.lowest[m] = r;
    }
    return out;
}

// Why a layer has nothing a texture bake could filter, or "" when it has (a readable normal image that a
// primitive with its texture coordinates uses).
std::string texture_skip_reason(const io::MaterialInfo& mat, int material, const Layer& layer, bool coat,
                                const std::vector<io::PrimitiveInfo>& infos) {
    bool used_with_uv = false, used = false;
    for (const io::PrimitiveInfo& p : infos) {
        if (p.material != material) continue;
        used = true;
        used_with_uv |= std::find(p.texcoords.begin(), p.texcoords.end(), layer.normal->texcoord) != p.texcoords.end();
    }
    if (coat && !mat.clearcoat.active()) return "clearcoatFactor is 0: the material has no coat";
    if (layer.normal->texture < 0)
        return coat ? "no clearcoat normal texture (the coat uses the geometry normal)" : "no normal texture";
    if (layer.normal->image < 0)
        return std::string(coat ? "clearcoat normal texture" : "normal texture") + " has no image source specbake can read";
    if (!used) return "no primitive uses the material";
    if (!used_with_uv) return "no primitive using the material has TEXCOORD_" + std::to_string(layer.normal->texcoord);
    return "";
}

// The bake's inputs as the glTF material defines them: the normal map with normalTexture.scale applied
// (n = normalize((2c - 1) * (scale, scale, 1))) and the roughness map times the roughness factor, copies
// only where they differ from the decoded images.
// `map` as floats (the values TextureMap::value reads).
Image float_copy(const TextureMap& map) {
    Image image(map.width, map.height, map.channels);
    for (int y = 0; y < map.height; ++y)
        for (int x = 0; x < map.width; ++x)
            for (int c = 0; c < map.channels; ++c) image.texel(x, y)[c] = map.value(x, y, c);
    return image;
}

void set_texture_inputs(TextureWork& w, const TextureDecision& d, const Layer& layer, const TextureMap& normal,
                        const TextureMap* rough, const ScenePlan& plan) {
    w.normal = normal;
    w.roughness = rough ? *rough : TextureMap{};
    w.normal_bits = plan.image_bits.at(d.normal_image);
    w.roughness_bits = rough ? plan.image_bits.at(d.roughness_image) : w.normal_bits;
    if (layer.normal_scale != 1.0) {
        w.normal_storage = float_copy(normal);
        Image& n = w.normal_storage;
        for (size_t t = 0; t < n.texel_count(); ++t)
            for (int c = 0; c < std::min(2, n.channels); ++c) {
                float& v = n.pixels[t * size_t(n.channels) + size_t(c)];
                v = float(((2.0 * v - 1.0) * layer.normal_scale + 1.0) * 0.5);
            }
        w.normal = TextureMap::of(w.normal_storage);
    }
    w.roughness_channel = rough && rough->channels >= 2 ? 1 : 0;
    if (rough && d.roughness_factor != 1.0f) {  // glTF: r = roughness factor * G
        w.roughness_storage = float_copy(*rough);
        Image& r = w.roughness_storage;
        for (size_t t = 0; t < r.texel_count(); ++t)
            r.pixels[t * size_t(r.channels) + size_t(w.roughness_channel)] *= d.roughness_factor;
        w.roughness = TextureMap::of(w.roughness_storage);
    }
}

// Bakes one layer's texture with the settings the bake will use, so the statistic that decides comes
// from the bake itself; `reason_note` ends the decision's reason. A bake that is kept goes to the plan's
// encoder or sink right away (which write it), one that is not is dropped from plan.texture_work.
Result<void> bake_and_decide_texture(TextureDecision& d, int index, const std::string& material,
                                     const std::string& reason_note, const io::GltfScene& scene,
                                     const PlanOptions& options, ScenePlan& plan) {
    TextureWork& w = plan.texture_work.at(index);
    TextureBakeSettings s = options.texture_settings_for(material);
    if (d.roughness_mapped_apart && !s.outputs.kernel && !s.outputs.lean && !s.outputs.normal) {
        d.reason = "roughness is the only output asked for" + reason_note;
        plan.texture_work.erase(index);
        return {};
    }
    if (!options.texture_sink && !options.texture_encoder) s.outputs = TextureOutputs{true, false, false, false};
    else s = layer_bake_settings(d, s);
    Result<TextureBakeResult> baked = make_error("");
    Result<EncodedTextureBake> encoded = make_error("");
    if (options.texture_encoder) {
        encoded = options.texture_encoder(d, w, s);
        if (w.release_rows) {
            // No later layer reads these maps: they are not held while the files are written (as `specbake
            // texture` drops its maps after the bake); the decoder's views of them are not used again.
            for (int image : {d.normal_image, d.roughness_image}) {
                plan.decoded_integers.erase(image);
                plan.decoded_images.erase(image);
            }
            w.normal = w.roughness = TextureMap{};
        }
        if (encoded) {
            TextureBakeResult measure;
            measure.max_roughness_change = encoded->max_roughness_change;
            measure.notes = encoded->notes;
            baked = std::move(measure);
        } else {
            baked = encoded.error();
        }
    } else {
        baked = bake_texture(w.normal, w.roughness.empty() ? nullptr : &w.roughness, w.roughness_channel,
                             d.roughness_value, s);
    }
    if (!baked) {
        d.reason = scene.image_label(d.normal_image) + ": " + baked.error().message;
        // The texture this layer needs is not baked: as much an input failure as an unreadable image.
        plan.input_errors.push_back(scene.source().string() + ": material " + std::to_string(d.material) +
                                    (d.material_name.empty() ? "" : " '" + d.material_name + "'") +
                                    (d.layer == "base" ? "" : " (" + d.layer + ")") + " texture bake: " + d.reason);
    } else {
        d.max_roughness_change = baked->max_roughness_change;
        d.bake = baked->max_roughness_change >= d.threshold;
        d.reason = d.bake ? "the bake changes roughness by at least half a quantisation step"
                          : "the bake changes no texel of any mip by half a quantisation step";
        for (const std::string& warning : baked->notes.warnings)
            plan.notes.push_back(scene.image_label(d.normal_image) + ": " + warning);
    }
    d.reason += reason_note;
    if (!d.bake) {
        plan.texture_work.erase(index);
    } else if (options.texture_encoder) {
        if (auto ok = encoded->write(d); !ok) return ok.error();
    } else if (options.texture_sink) {
        if (auto ok = options.texture_sink(d, w, std::move(*baked)); !ok) return ok.error();
    }
    return {};
}

// The inputs a layer's texture bake is keyed by: layers with equal keys share one bake. Materials with
// their own settings share a bake only with themselves (the name is part of the key).
using TextureBakeKey = std::tuple<int, int, float, float, double, bool, std::string>;
// What the kernel, normal and projected LEAN outputs depend on: the normal map, its scale, the layer and
// the settings. Layers with equal keys and different roughness share those files.
using NormalBakeKey = std::tuple<int, double, std::string, std::string>;

// The texture decisions, one per material and layer, each bake run (and handed on) as it is decided.
Result<void> decide_textures(const io::GltfScene& scene, const PlanOptions& options,
                             const std::vector<io::MaterialInfo>& materials,
                             const std::vector<io::PrimitiveInfo>& infos, const MaterialRoughness& roughness,
                             ImageDecoder& images, ScenePlan& plan) {
    const std::string stem = scene.source().stem().string();
    std::map<TextureBakeKey, int> bakes_by_inputs;
    std::map<NormalBakeKey, int> normal_bakes;  // -> the bake that wrote those files
    // Layers still to come that may read each decoded image (every layer naming it counts, a skipped one too).
    std::map<int, int> readers_left;
    for (const io::MaterialInfo& mat : materials)
        for (const Layer& layer : layers_of(mat))
            for (int image : {layer.normal->image, layer.roughness->image})
                if (image >= 0) ++readers_left[images.first_of_file(image)];
    for (size_t m = 0; m < materials.size(); ++m) {
        const io::MaterialInfo& mat = materials[m];
        const std::vector<Layer> layers = layers_of(mat);
        for (size_t l = 0; l < layers.size(); ++l) {
            const Layer& layer = layers[l];
            const bool coat = l > 0;
            TextureDecision d;
            d.material = int(m);
            d.material_name = mat.name;
            d.layer = layer.name;
            d.roughness_factor = float(layer.roughness_factor);
            d.stem = stem + "_mat" + std::to_string(m) + (mat.name.empty() ? "" : "_" + sanitize(mat.name)) +
                     (coat ? "_clearcoat" : "");
            d.texcoord = layer.normal->texcoord;
            const std::string normal_name = coat ? "clearcoat normal texture" : "normal texture";
            for (int image : {layer.normal->image, layer.roughness->image})
                if (image >= 0) --readers_left[images.first_of_file(image)];
            if (std::string skip = texture_skip_reason(mat, int(m), layer, coat, infos); !skip.empty()) {
                d.reason = std::move(skip);
            } else if (const TextureMap* normal = images.decode(images.first_of_file(layer.normal->image)); !normal) {
                const std::string error = images.error(images.first_of_file(layer.normal->image));
                d.reason = normal_name + " cannot be decoded: " + error;
                plan.input_errors.push_back(input_error(scene, m, mat, layer, normal_name, error));
            } else {
                d.normal_image = images.first_of_file(layer.normal->image);
                const TextureMap* rough = nullptr;
                std::string mapping_note;
                if (layer.roughness->image >= 0) {
                    if (!io::same_uv_mapping(*layer.roughness, *layer.normal)) {
                        // A roughness filtered in the normal texture's UV space would move the roughness
                        // map's texels, and a constant would drop it: the material keeps its roughness.
                        d.roughness_mapped_apart = true;
                        const std::string roughness_name = coat ? "clearcoatRoughnessTexture" : "metallicRoughnessTexture";
                        plan.notes.push_back(material_label(scene, int(m), mat.name) + ": " + roughness_name + " (" +
                                             io::uv_mapping_label(*layer.roughness) + ") is mapped unlike " +
                                             (coat ? "clearcoatNormalTexture" : "normalTexture") + " (" +
                                             io::uv_mapping_label(*layer.normal) +
                                             "): its roughness is not replaced; the kernel and normal outputs are baked");
                        mapping_note = "; " + roughness_name + " is mapped unlike the " + normal_name +
                                       ": no roughness output, the decision uses the layer's lowest roughness";
                    } else if ((rough = images.decode(images.first_of_file(layer.roughness->image))) != nullptr) {
                        d.roughness_image = images.first_of_file(layer.roughness->image);
                        d.roughness_texture_used = true;
                    }
                }
                d.roughness_value = float(std::clamp(roughness.per_layer[m][l], 0.0, 1.0));
                const int bits_image = d.roughness_texture_used ? d.roughness_image : d.normal_image;
                d.threshold = half_quantisation_step(plan.image_bits[bits_image], images.is_float(bits_image));
                d.normal_scale = layer.normal_scale;
                const std::string settings_name =
                    options.material_texture_settings.count(mat.name) ? mat.name : std::string();
                // A layer mapped apart writes no roughness: its lowest roughness only feeds the statistic.
                const TextureBakeKey key(d.normal_image, d.roughness_image,
                                         d.roughness_mapped_apart      ? 0.0f
                                         : d.roughness_texture_used ? d.roughness_factor
                                                                    : d.roughness_value,
                                         d.roughness_texture_used ? 1.0f : 0.0f, layer.normal_scale,
                                         d.roughness_mapped_apart, settings_name);
                const NormalBakeKey normal_key(d.normal_image, layer.normal_scale, layer.name, settings_name);
                if (auto it = bakes_by_inputs.find(key); it != bakes_by_inputs.end()) {
                    const TextureDecision& first = plan.textures[size_t(it->second)];
                    d.same_as = it->second;
                    d.bake = first.bake;
                    d.max_roughness_change = first.max_roughness_change;
                    d.stem = first.stem;
                    d.normal_outputs_stem = first.normal_outputs_stem;
                    d.reason = "same inputs as material " + std::to_string(first.material) +
                               (first.layer == "base" ? "" : " (" + first.layer + ")") + ": " + first.reason;
                } else {
                    const int index = int(plan.textures.size());
                    if (auto n = normal_bakes.find(normal_key); n != normal_bakes.end() && !d.roughness_mapped_apart)
                        d.normal_outputs_stem = plan.textures[size_t(n->second)].stem;
                    TextureWork& w = plan.texture_work[index];
                    set_texture_inputs(w, d, layer, *normal, rough, plan);
                    w.release_rows = readers_left[d.normal_image] == 0 && (!rough || readers_left[d.roughness_image] == 0);
                    if (auto ok = bake_and_decide_texture(d, index, mat.name, mapping_note, scene, options, plan); !ok)
                        return ok;
                    bakes_by_inputs[key] = index;
                    if (d.bake && d.normal_outputs_stem.empty()) normal_bakes.emplace(normal_key, index);
                }
            }
            plan.textures.push_back(std::move(d));
        }
    }
    return {};
}

// Condition 2 for a primitive not measured before: the mesh prepared for curvature (validated, normals and
// tangents present) and its relative curvature, kept in plan.work when it bakes.
Result<void> measure_curvature(CurvatureDecision& d, size_t primitive, TriMesh mesh, const io::PrimitiveInfo& p,
                               bool roughness_known, const PlanOptions& options, ScenePlan& plan) {
    // The curvature needs the normals and tangents, not the topology report: it runs beside it.
    CurvatureOptions copts;
    copts.max_threads = options.threads;
    Result<VertexCurvature> curvature = make_error(mesh.name + ": curvature not estimated");
    PrepareOptions prepare;
    prepare.weld = copts.weld;
    prepare.with_frames = [&](const TriMesh& m, const WeldedTopology& welded) {
        curvature = estimate_curvature(m, welded, options.estimator, copts);
    };
    auto report = prepare_mesh_for_curvature(mesh, prepare);
    if (!report) return report.error();
    if (!curvature) return curvature.error();
    for (float v : curvature->values)
        if (!std::isfinite(v)) return make_error(mesh.name + ": curvature estimate is not finite");
    const CurvatureSummary summary = summarize_curvature(mesh, *curvature);
    d.relative_curvature = double(summary.relative_p95());
    d.mesh_report = report->summary();
    d.bake = *d.relative_curvature >= options.min_relative_curvature;
    const std::string material_part =
        !options.check_material ? "material not checked"
        : !roughness_known      ? "material roughness unknown (the file states none), treated as glossy"
                                : "material glossy enough to alias";
    d.reason = material_part + (d.bake ? "; shading normals curve" : "; shading normals do not curve");
    if (d.bake) {
        d.generates_tangents = !p.has_tangent;
        d.repairs_normals = report->repaired_normals > 0;
        plan.work[primitive] = PrimitiveWork{std::move(mesh), *report, std::move(*curvature)};
    }
    return {};
}

// The TEXCOORD set a primitive's generated tangents follow: its normal texture's (glTF 2.0, "the
// tangent vectors are calculated ... using the texture coordinates of the normal texture"), the base
// layer's or else the coat's of its material; 0 when it has none. When the primitive has no TANGENT and the
// normal textures of the materials it can show (its coat's, its KHR_materials_variants materials') use other
// sets, no one frame fits them all: a note names them.
int tangent_uv_set(const io::PrimitiveInfo& p, const std::vector<io::MaterialInfo>& materials,
                   std::vector<std::string>& notes) {
    struct Use {
        std::string what;
        int set;
    };
    std::vector<Use> uses;
    std::vector<int> shown{p.material};
    shown.insert(shown.end(), p.variant_materials.begin(), p.variant_materials.end());
    for (int m : shown) {
        if (m < 0 || size_t(m) >= materials.size()) continue;
        const io::MaterialInfo& mat = materials[size_t(m)];
        const std::string label = "material " + std::to_string(m) + (mat.name.empty() ? "" : " '" + mat.name + "'");
        if (mat.normal.texture >= 0) uses.push_back({label + " normalTexture", mat.normal.texcoord});
        if (mat.clearcoat.active() && mat.clearcoat.normal.texture >= 0)
            uses.push_back({label + " clearcoatNormalTexture", mat.clearcoat.normal.texcoord});
    }
    if (uses.empty()) return 0;
    const int set = uses.front().set;
    if (!p.has_tangent) {
        std::string others;
        for (const Use& u : uses)
            if (u.set != set) others += (others.empty() ? "" : ", ") + u.what + " uses TEXCOORD_" + std::to_string(u.set);
        if (!others.empty())
            notes.push_back(p.label + ": its materials' normal textures use different texture coordinates: generated "
                            "tangents follow TEXCOORD_" + std::to_string(set) + " (" + uses.front().what + "), but " +
                            others + "; author TANGENT for this primitive");
    }
    const bool present = std::find(p.texcoords.begin(), p.texcoords.end(), set) != p.texcoords.end();
    return present ? set : 0;
}

// The curvature decisions, one per primitive.
Result<void> decide_curvature(const io::GltfScene& scene, const PlanOptions& options,
                              const std::vector<io::PrimitiveInfo>& infos, const std::vector<io::MaterialInfo>& materials,
                              const MaterialRoughness& roughness, const std::vector<bool>& roughness_known,
                              ScenePlan& plan) {
    std::map<std::string, size_t> measured_geometry;  // geometry key -> first primitive measured
    for (size_t i = 0; i < infos.size(); ++i) {
        const io::PrimitiveInfo& p = infos[i];
        CurvatureDecision d;
        d.ref = p.ref;
        d.label = p.label;
        d.material = p.material;
        d.roughness_gain_threshold = options.min_roughness_gain;
        d.relative_curvature_threshold = options.min_relative_curvature;
        d.min_instance_scale = p.min_instance_scale;
        d.max_instance_scale = p.max_instance_scale;
        const bool known = p.material < 0 || size_t(p.material) >= roughness_known.size() ||
                           roughness_known[size_t(p.material)];
        if (p.material >= 0 && size_t(p.material) < roughness.lowest.size()) d.min_roughness = roughness.lowest[size_t(p.material)];
        else d.min_roughness = 1.0;  // glTF default material: roughnessFactor 1
        d.roughness_gain = roughness_gain(*d.min_roughness, options.kappa);

        const bool surface = p.mode >= kModeTriangles && p.mode <= kModeFan;
        std::optional<TriMesh> mesh;
        if (surface) d.tangent_texcoord = tangent_uv_set(p, materials, plan.notes);
        // Generated tangents, and the curvature directions in their frame, depend on the UV set too.
        const std::string geometry_key = p.geometry_key + " tangents TEXCOORD_" + std::to_string(d.tangent_texcoord);
        if (surface) {  // every surface is read, baked or not: the output must not carry invalid indices
            auto read = scene.primitive_mesh(p.ref, d.tangent_texcoord);
            if (!read) return read.error();
            mesh = std::move(*read);
        }
        if (!surface) {
            d.reason = "not a triangle surface (mode " + std::to_string(p.mode) + ")";
        } else if (!p.has_normal) {
            d.reason = "no NORMAL attribute: glTF shades the primitive flat, nothing to filter";
        } else if (options.check_material && known && *d.roughness_gain < options.min_roughness_gain) {
            d.reason = "material too rough to alias: the largest geometric kernel raises roughness " +
                       format_number(*d.min_roughness) + " by less than the threshold";
        } else if (auto same = measured_geometry.find(geometry_key); same != measured_geometry.end()) {
            // Same vertex data as an earlier primitive: same measurement, same curvature.
            const CurvatureDecision& first = plan.primitives[same->second];
            d.relative_curvature = first.relative_curvature;
            d.mesh_report = first.mesh_report;
            d.bake = first.bake;
            d.generates_tangents = first.generates_tangents;
            d.repairs_normals = first.repairs_normals;
            d.reason = first.reason + " (same vertex data as mesh " + std::to_string(first.ref.mesh) + " primitive " +
                       std::to_string(first.ref.primitive) + ")";
            if (d.bake) plan.work[i] = plan.work.at(same->second);
        } else {
            measured_geometry[geometry_key] = i;
            if (auto ok = measure_curvature(d, i, std::move(*mesh), p, known, options, plan); !ok) return ok;
        }
        plan.primitives.push_back(std::move(d));
    }
    return {};
}

}  // namespace

Result<ScenePlan> make_plan(const io::GltfScene& scene, const PlanOptions& options,
                            const std::vector<bool>& roughness_known) {
    ScenePlan plan;
    plan.scene = scene.source().string();
    const std::vector<io::PrimitiveInfo> infos = scene.primitives();
    const std::vector<io::MaterialInfo> materials = scene.materials();
    ImageDecoder images(scene, options.input_policy.limits, plan);
    if (options.textures) {
        // The maps the texture decisions read, decoded side by side before the decisions read them one by one.
        std::vector<int> wanted;
        for (size_t m = 0; m < materials.size(); ++m) {
            const std::vector<Layer> layers = layers_of(materials[m]);
            for (size_t l = 0; l < layers.size(); ++l) {
                const Layer& layer = layers[l];
                wanted.push_back(layer.roughness->image);
                if (layer.roughness->image >= 0) wanted.push_back(images.first_of_file(layer.roughness->image));
                if (layer.normal->image >= 0 && texture_skip_reason(materials[m], int(m), layer, l > 0, infos).empty())
                    wanted.push_back(images.first_of_file(layer.normal->image));
            }
        }
        images.prefetch(std::move(wanted));
    }
    const MaterialRoughness roughness = lowest_material_roughness(scene, materials, images, plan);
    // Curvature regardless of the material (`specbake mesh`) needs no roughness texture.
    if (!options.textures && !options.check_material) plan.input_errors.clear();
    if (options.textures) {
        if (auto ok = decide_textures(scene, options, materials, infos, roughness, images, plan); !ok) return ok.error();
    }
    if (auto ok = decide_curvature(scene, options, infos, materials, roughness, roughness_known, plan); !ok)
        return ok.error();
    auto glints = plan_glints(scene, options.material_glints);
    if (!glints) return glints.error();
    plan.glints = std::move(*glints);
    return plan;
}

nlohmann::json plan_to_json(const ScenePlan& plan) {
    using nlohmann::json;
    json j;
    j["scene"] = plan.scene;
    j["textures"] = json::array();
    for (const TextureDecision& d : plan.textures) {
        json e = {{"material", d.material},
                  {"material_name", d.material_name},
                  {"layer", d.layer},
                  {"decision", d.bake ? "bake" : "skip"},
                  {"reason", d.reason},
                  {"measure", "max change of perceptual roughness over all texels of all mips"},
                  {"threshold", d.threshold}};
        e["measured"] = d.max_roughness_change ? json(*d.max_roughness_change) : json(nullptr);
        if (d.normal_image >= 0) e["normal_image"] = d.normal_image;
        if (d.roughness_texture_used) e["roughness_image"] = d.roughness_image;
        else if (d.normal_image >= 0) e["roughness_value"] = d.roughness_value;
        if (d.roughness_mapped_apart) e["roughness_replaced"] = false;
        if (d.bake) e["stem"] = d.stem;
        if (d.bake && !d.normal_outputs_stem.empty()) e["normal_outputs_stem"] = d.normal_outputs_stem;
        j["textures"].push_back(std::move(e));
    }
    j["primitives"] = json::array();
    for (const CurvatureDecision& d : plan.primitives) {
        json e = {{"mesh", d.ref.mesh},
                  {"primitive", d.ref.primitive},
                  {"material", d.material},
                  {"decision", d.bake ? "curvature" : "skip"},
                  {"reason", d.reason},
                  {"roughness_gain_threshold", d.roughness_gain_threshold},
                  {"relative_curvature_threshold", d.relative_curvature_threshold},
                  {"instance_scale", {d.min_instance_scale, d.max_instance_scale}}};
        e["min_roughness"] = d.min_roughness ? json(*d.min_roughness) : json(nullptr);
        e["roughness_gain"] = d.roughness_gain ? json(*d.roughness_gain) : json(nullptr);
        e["relative_curvature"] = d.relative_curvature ? json(*d.relative_curvature) : json(nullptr);
        if (d.bake) {
            e["generated_tangents"] = d.generates_tangents;
            if (d.generates_tangents) e["tangent_texcoord"] = d.tangent_texcoord;
            e["repaired_normals"] = d.repairs_normals;
        }
        if (!d.mesh_report.empty()) e["mesh_report"] = d.mesh_report;
        j["primitives"].push_back(std::move(e));
    }
    if (!plan.glints.empty()) {
        j["glints"] = json::array();
        for (const GlintDecision& d : plan.glints) j["glints"].push_back(glint_decision_json(d));
    }
    j["notes"] = plan.notes;
    return j;
}

std::string plan_to_table(const ScenePlan& plan) {
    std::ostringstream os;
    os << plan.scene << "\n";
    auto measured = [](const std::optional<double>& v) { return v ? format_number(*v) : std::string("-"); };
    char line[512];
    std::snprintf(line, sizeof line, "  %-10s %-28s %-10s %-11s %-11s %s\n", "what", "target", "decision", "measured",
                  "threshold", "reason");
    os << line;
    for (const TextureDecision& d : plan.textures) {
        // The "what" column names the layer, so the target stays within its column.
        const std::string target = "material " + std::to_string(d.material) +
                                   (d.material_name.empty() ? "" : " '" + d.material_name.substr(0, 14) + "'");
        const std::string what = d.layer == "base" ? "texture" : d.layer;
        std::snprintf(line, sizeof line, "  %-10s %-28s %-10s %-11s %-11s %s\n", what.c_str(), target.c_str(),
                      d.bake ? "bake" : "skip", measured(d.max_roughness_change).c_str(),
                      d.threshold > 0 ? format_number(d.threshold).c_str() : "-", d.reason.c_str());
        os << line;
    }
    for (const CurvatureDecision& d : plan.primitives) {
        const std::string target = "mesh " + std::to_string(d.ref.mesh) + " primitive " + std::to_string(d.ref.primitive);
        // The measured value shown is the one that decided: curvature when it was measured, else roughness.
        const bool by_curvature = d.relative_curvature.has_value();
        std::snprintf(line, sizeof line, "  %-10s %-28s %-10s %-11s %-11s %s\n", "curvature", target.c_str(),
                      d.bake ? "bake" : "skip",
                      (by_curvature ? measured(d.relative_curvature) : measured(d.roughness_gain)).c_str(),
                      format_number(by_curvature ? d.relative_curvature_threshold : d.roughness_gain_threshold).c_str(),
                      d.reason.c_str());
        os << line;
    }
    os << glint_table_lines(plan.glints);
    for (const std::string& n : plan.notes) os << "  note: " << n << "\n";
    return os.str();
}

}  // namespace specbake
