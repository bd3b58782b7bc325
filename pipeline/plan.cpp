#include "pipeline/plan.h"

#include "core/text_format.h"
#include "io/image/image_io.h"
#include "mesh/curvature_summary.h"
#include "mesh/prepare_mesh.h"

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

std::string sanitize(const std::string& name) {
    std::string out;
    for (char c : name) out.push_back(std::isalnum(uint8_t(c)) || c == '-' ? c : '_');
    if (out.size() > 40) out.resize(40);
    return out;
}

}  // namespace

double roughness_gain(double r, double kappa) {
    const double a = std::pow(std::clamp(r, 0.0, 1.0), 4.0);
    const double tk = kappa * (1.0 - a);
    const double filtered = (a + tk) / (1.0 + tk);  // SPEC Sec. 3, TK21 Eq. (4)-(7) isotropic closed form
    return std::pow(filtered, 0.25) - std::clamp(r, 0.0, 1.0);
}

Result<ScenePlan> make_plan(const io::GltfScene& scene, const PlanOptions& options,
                            const std::vector<bool>& roughness_known) {
    ScenePlan plan;
    plan.scene = scene.source().string();
    const std::vector<io::PrimitiveInfo> infos = scene.primitives();
    const std::vector<io::MaterialInfo> materials = scene.materials();
    const std::string stem = scene.source().stem().string();

    std::map<int, bool> image_is_float;
    std::map<int, std::string> decode_errors;
    auto decode = [&](int image) -> const Image* {
        if (image < 0) return nullptr;
        if (auto it = plan.decoded_images.find(image); it != plan.decoded_images.end()) return &it->second;
        if (decode_errors.count(image)) return nullptr;
        Result<io::DecodedImage> decoded = make_error(scene.image_label(image) + ": not read");
        if (const std::filesystem::path file = scene.image_file(image); !file.empty()) {
            decoded = io::decode_image(file, options.input_policy.limits);
        } else {
            auto bytes = scene.image_bytes(image);
            if (!bytes) {
                decode_errors[image] = bytes.error().message;
                return nullptr;
            }
            decoded = io::decode_image_memory(*bytes, scene.image_label(image), options.input_policy.limits);
        }
        if (!decoded) {
            decode_errors[image] = decoded.error().message;
            return nullptr;
        }
        if (auto bad = find_non_finite(decoded->image)) {
            decode_errors[image] = scene.image_label(image) + ": non-finite value at texel (" +
                                   std::to_string(bad->first) + ", " + std::to_string(bad->second) + ")";
            return nullptr;
        }
        plan.image_bits[image] = decoded->info.bits_per_channel;
        image_is_float[image] = decoded->info.is_float;
        return &plan.decoded_images.emplace(image, std::move(decoded->image)).first->second;
    };

    // The layers whose normals a texture bake can filter: the base (normalTexture, roughness from
    // metallicRoughness G) and, with KHR_materials_clearcoat, the coat (clearcoatNormalTexture, roughness
    // from clearcoatRoughnessTexture G), each with its own roughness factor and normal scale.
    struct Layer {
        const char* name;
        const io::TextureSlot* normal;
        double normal_scale;
        const io::TextureSlot* roughness;
        double roughness_factor;
    };
    auto layers_of = [](const io::MaterialInfo& mat) {
        std::vector<Layer> layers{{"base", &mat.normal, mat.normal_scale, &mat.metallic_roughness, mat.roughness_factor}};
        if (mat.clearcoat.present)
            layers.push_back({"clearcoat", &mat.clearcoat.normal, mat.clearcoat.normal_scale, &mat.clearcoat.roughness,
                              mat.clearcoat.roughness_factor});
        return layers;
    };

    // Lowest perceptual roughness of a layer: its roughness factor times its smallest G texel.
    auto lowest_roughness = [&](const Layer& layer) {
        double r = layer.roughness_factor;
        if (layer.roughness->image >= 0) {
            if (const Image* img = decode(layer.roughness->image)) {
                const int ch = img->channels >= 2 ? 1 : 0;
                float lo = 1.0f;
                for (size_t i = 0; i < img->texel_count(); ++i)
                    lo = std::min(lo, img->pixels[i * size_t(img->channels) + size_t(ch)]);
                r *= std::clamp(double(lo), 0.0, 1.0);
            } else {
                plan.notes.push_back(decode_errors[layer.roughness->image] + " (" + layer.name +
                                     " roughness texture not read; its roughness factor used alone)");
            }
        }
        return r;
    };
    // A material's lowest roughness is that of its glossiest layer: a clear coat over a rough base aliases
    // as much as a glossy base.
    std::vector<std::vector<double>> layer_min_roughness(materials.size());
    std::vector<std::optional<double>> min_roughness(materials.size());
    for (size_t m = 0; m < materials.size(); ++m) {
        for (const Layer& layer : layers_of(materials[m])) layer_min_roughness[m].push_back(lowest_roughness(layer));
        double r = layer_min_roughness[m][0];
        if (materials[m].clearcoat.active()) r = std::min(r, layer_min_roughness[m][1]);
        min_roughness[m] = r;
    }

    // Texture decisions, one per material and layer.
    // Materials with their own settings share a bake only with themselves (the name is part of the key).
    std::map<std::tuple<int, int, float, float, double, std::string>, int> bakes_by_inputs;
    for (size_t m = 0; m < materials.size() && options.textures; ++m) {
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
            bool used_with_uv = false, used = false;
            for (const io::PrimitiveInfo& p : infos) {
                if (p.material != int(m)) continue;
                used = true;
                used_with_uv |=
                    std::find(p.texcoords.begin(), p.texcoords.end(), layer.normal->texcoord) != p.texcoords.end();
            }
            const std::string normal_name = coat ? "clearcoat normal texture" : "normal texture";
            if (coat && !mat.clearcoat.active()) {
                d.reason = "clearcoatFactor is 0: the material has no coat";
            } else if (layer.normal->texture < 0) {
                d.reason = coat ? "no clearcoat normal texture (the coat uses the geometry normal)" : "no normal texture";
            } else if (layer.normal->image < 0) {
                d.reason = normal_name + " has no image source specbake can read";
            } else if (!used) {
                d.reason = "no primitive uses the material";
            } else if (!used_with_uv) {
                d.reason = "no primitive using the material has TEXCOORD_" + std::to_string(layer.normal->texcoord);
            } else if (const Image* normal = decode(layer.normal->image); !normal) {
                d.reason = normal_name + " cannot be decoded: " + decode_errors[layer.normal->image];
                plan.notes.push_back(decode_errors[layer.normal->image]);
            } else {
                d.normal_image = layer.normal->image;
                const Image* rough = nullptr;
                std::string mapping_note;
                if (layer.roughness->image >= 0) {
                    const bool same_mapping = layer.roughness->texcoord == layer.normal->texcoord &&
                                              !layer.roughness->transformed && !layer.normal->transformed;
                    if (!same_mapping) {
                        mapping_note = "; roughness texture is mapped differently from the " + normal_name +
                                       ", so the layer's lowest roughness is used as a constant";
                    } else if ((rough = decode(layer.roughness->image)) != nullptr) {
                        d.roughness_image = layer.roughness->image;
                        d.roughness_texture_used = true;
                    }
                }
                d.roughness_value = float(std::clamp(layer_min_roughness[m][l], 0.0, 1.0));
                const int bits_image = d.roughness_texture_used ? d.roughness_image : d.normal_image;
                d.threshold = half_quantisation_step(plan.image_bits[bits_image], image_is_float[bits_image]);
                const auto key = std::make_tuple(d.normal_image, d.roughness_image,
                                                 d.roughness_texture_used ? d.roughness_factor : d.roughness_value,
                                                 d.roughness_texture_used ? 1.0f : 0.0f, layer.normal_scale,
                                                 options.material_texture_settings.count(mat.name) ? mat.name
                                                                                                   : std::string());
                if (auto it = bakes_by_inputs.find(key); it != bakes_by_inputs.end()) {
                    const TextureDecision& first = plan.textures[size_t(it->second)];
                    d.same_as = it->second;
                    d.bake = first.bake;
                    d.max_roughness_change = first.max_roughness_change;
                    d.stem = first.stem;
                    d.reason = "same inputs as material " + std::to_string(first.material) +
                               (first.layer == "base" ? "" : " (" + first.layer + ")") + ": " + first.reason;
                } else {
                    // The statistic comes from the bake itself, with the settings the bake will use.
                    const int index = int(plan.textures.size());
                    TextureWork& w = plan.texture_work[index];
                    w.normal = normal;
                    w.roughness = rough;
                    w.normal_bits = plan.image_bits[d.normal_image];
                    w.roughness_bits = rough ? plan.image_bits[d.roughness_image] : w.normal_bits;
                    if (layer.normal_scale != 1.0) {  // glTF: n = normalize((2c - 1) * (scale, scale, 1))
                        w.normal_storage = *normal;
                        Image& n = w.normal_storage;
                        for (size_t t = 0; t < n.texel_count(); ++t)
                            for (int c = 0; c < std::min(2, n.channels); ++c) {
                                float& v = n.pixels[t * size_t(n.channels) + size_t(c)];
                                v = float(((2.0 * v - 1.0) * layer.normal_scale + 1.0) * 0.5);
                            }
                        w.normal = &w.normal_storage;
                    }
                    w.roughness_channel = rough && rough->channels >= 2 ? 1 : 0;
                    if (rough && d.roughness_factor != 1.0f) {  // glTF: r = roughness factor * G
                        w.roughness_storage = *rough;
                        Image& r = w.roughness_storage;
                        for (size_t t = 0; t < r.texel_count(); ++t)
                            r.pixels[t * size_t(r.channels) + size_t(w.roughness_channel)] *= d.roughness_factor;
                        w.roughness = &w.roughness_storage;
                    }
                    TextureBakeSettings s = options.texture_settings_for(mat.name);
                    if (!options.texture_sink && !options.texture_encoder)
                        s.outputs = TextureOutputs{true, false, false, false};
                    Result<TextureBakeResult> baked = make_error("");
                    Result<EncodedTextureBake> encoded = make_error("");
                    if (options.texture_encoder) {
                        encoded = options.texture_encoder(d, w, s);
                        if (encoded) {
                            TextureBakeResult measure;
                            measure.max_roughness_change = encoded->max_roughness_change;
                            measure.notes = encoded->notes;
                            baked = std::move(measure);
                        } else {
                            baked = encoded.error();
                        }
                    } else {
                        baked = bake_texture(*w.normal, w.roughness, w.roughness_channel, d.roughness_value, s);
                    }
                    if (!baked) {
                        d.reason = scene.image_label(d.normal_image) + ": " + baked.error().message;
                        plan.notes.push_back(d.reason);
                    } else {
                        d.max_roughness_change = baked->max_roughness_change;
                        d.bake = baked->max_roughness_change >= d.threshold;
                        d.reason = d.bake ? "the bake changes roughness by at least half a quantisation step"
                                          : "the bake changes no texel of any mip by half a quantisation step";
                        for (const std::string& warning : baked->notes.warnings)
                            plan.notes.push_back(scene.image_label(d.normal_image) + ": " + warning);
                    }
                    d.reason += mapping_note;
                    if (!d.bake) {
                        plan.texture_work.erase(index);
                    } else if (options.texture_encoder) {
                        if (auto ok = encoded->write(d); !ok) return ok.error();
                    } else if (options.texture_sink) {
                        if (auto ok = options.texture_sink(d, w, std::move(*baked)); !ok) return ok.error();
                    }
                    bakes_by_inputs[key] = index;
                }
            }
            plan.textures.push_back(std::move(d));
        }
    }

    // Curvature decisions, one per primitive.
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
        if (p.material >= 0 && size_t(p.material) < materials.size()) d.min_roughness = min_roughness[size_t(p.material)];
        else d.min_roughness = 1.0;  // glTF default material: roughnessFactor 1
        d.roughness_gain = roughness_gain(*d.min_roughness, options.kappa);

        const bool surface = p.mode >= kModeTriangles && p.mode <= kModeFan;
        std::optional<TriMesh> mesh;
        if (surface) {  // every surface is read, baked or not: the output must not carry invalid indices
            auto read = scene.primitive_mesh(p.ref);
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
        } else if (auto same = measured_geometry.find(p.geometry_key); same != measured_geometry.end()) {
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
            measured_geometry[p.geometry_key] = i;
            // The curvature needs the normals and tangents, not the topology report: it runs beside it.
            CurvatureOptions copts;
            copts.max_threads = options.threads;
            Result<VertexCurvature> curvature = make_error(mesh->name + ": curvature not estimated");
            PrepareOptions prepare;
            prepare.weld = copts.weld;
            prepare.with_frames = [&](const TriMesh& m, const WeldedTopology& welded) {
                curvature = estimate_curvature(m, welded, options.estimator, copts);
            };
            auto report = prepare_mesh_for_curvature(*mesh, prepare);
            if (!report) return report.error();
            if (!curvature) return curvature.error();
            for (float v : curvature->values)
                if (!std::isfinite(v)) return make_error(mesh->name + ": curvature estimate is not finite");
            const CurvatureSummary summary = summarize_curvature(*mesh, *curvature);
            d.relative_curvature = double(summary.relative_p95());
            d.mesh_report = report->summary();
            d.bake = *d.relative_curvature >= options.min_relative_curvature;
            const std::string material_part =
                !options.check_material ? "material not checked"
                : !known                ? "material roughness unknown (the file states none), treated as glossy"
                                        : "material glossy enough to alias";
            d.reason = material_part + (d.bake ? "; shading normals curve" : "; shading normals do not curve");
            if (d.bake) {
                d.generates_tangents = !p.has_tangent;
                d.repairs_normals = report->repaired_normals > 0;
                plan.work[i] = PrimitiveWork{std::move(*mesh), *report, std::move(*curvature)};
            }
        }
        plan.primitives.push_back(std::move(d));
    }
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
        if (d.bake) e["stem"] = d.stem;
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
