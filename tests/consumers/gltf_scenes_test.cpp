// `specbake bake` outputs in third-party consumers: Khronos glTF-Validator must report no error or warning
// the input did not have (per issue code), three.js GLTFLoader (headless Chromium) must load every baked
// .gltf/.glb with the input's meshes and materials, and the baked textures the SPECBAKE_specular_aa
// extension references must load in the matching three.js loader with the extension's size and level
// count, texels read back from the GPU matching specbake's spec-based reader (io/container_inspect.h).
// Scenes: a generated quad with the demo normal map, and the shared glTF models where present.
#include "consumer_harness.h"
#include "three_js_support.h"

#include "io/container_inspect.h"

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

struct Mode {
    const char* label;
    const char* args;
    bool all_scenes;  // else the quad only: the texture test covers the containers on every map already
};
const Mode kModes[] = {{"gltf, KTX2", "--format gltf", true},
                       {"glb, KTX2", "--format glb", true},
                       {"gltf, DDS", "--format gltf --container dds", false},
                       {"gltf, EXR", "--format gltf --container exr", false}};

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
};

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
    for (size_t m = 0; m < std::size(kModes); ++m)
        for (const fs::path& in : inputs) {
            if (!kModes[m].all_scenes && in != inputs.front()) continue;
            const fs::path out = data / std::to_string(m) / in.stem();
            specbake("bake -q " + std::string(kModes[m].args) + " " + quote(in) + " -o " + quote(out));
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
        auto counts = [](const nlohmann::json& r) {
            std::map<std::string, int> c;
            for (const auto& i : r["issues"])
                if (i["severity"].get<int>() <= 1) ++c[i["code"].get<std::string>()];
            return c;
        };
        for (const SceneFile& s : scenes) {
            const nlohmann::json& in = reports[s.input.string()];
            const nlohmann::json& o = reports[(data / s.output).string()];
            ASSERT_TRUE(in.value("ok", false)) << s.input << ": validator failed: " << in.dump();
            ASSERT_TRUE(o.value("ok", false)) << s.output << ": validator failed: " << o.dump();
            const auto before = counts(in), after = counts(o);
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
        std::printf("glTF-Validator %s: %zu baked scenes, no new error or warning checked\n",
                    reports.begin()->second.value("validator", "?").c_str(), scenes.size());
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
                if (!o.contains("uri") || o["format"] == "png") continue;
                TextureFile t;
                t.id = (s.output.parent_path() / o["uri"].get<std::string>()).string();
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
    nlohmann::json result;
    if (!run_browser(job, data, &result)) return;
    std::map<std::string, const nlohmann::json*> by_id;
    for (const auto& r : result["results"]) by_id[r["id"]] = &r;

    std::map<std::pair<std::string, std::string>, std::pair<int, int>> table;  // (row, consumer) -> (ok, files)
    std::map<std::pair<std::string, std::string>, std::string> notes;
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
                const double tol = tolerance(enc, want);
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
    std::printf("%s", md.c_str());
    std::ofstream("consumer_results_scenes.md") << md;
}

}  // namespace
}  // namespace specbake::consumers
