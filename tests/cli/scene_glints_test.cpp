// Scenes that ask for glints: SPECBAKE_glints on a material, or glints keys in a config's
// [materials.NAME]; `plan` lists glints only for them, `bake` writes the dictionary once and the slope-space
// LEAN moments of the material's normal map, referenced from SPECBAKE_specular_aa. Checked with tinygltf
// and nlohmann::json reading the outputs directly.
#include "scene_test_util.h"

#include <OpenImageIO/imageio.h>
#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <cmath>

namespace {

using namespace scene_test;
using nlohmann::json;

// A plane whose material has an anisotropic bump normal map (ridges along u) and, when `ask`, the
// glint extension object `glints`.
fs::path write_glint_plane(const fs::path& dir, bool ask, const json& glints) {
    const fs::path gltf = dir / "plane.gltf";
    write_test_model(gltf, false, 2.0, 0.2, 8, 8);
    const int n = 64;
    std::vector<uint8_t> pixels(size_t(n) * n * 3);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const double sx = 0.6 * std::sin(2 * M_PI * x * 5 / n), sy = 0.1 * std::cos(2 * M_PI * y * 3 / n);
            const double len = std::sqrt(sx * sx + sy * sy + 1.0);
            const double v[3] = {-sx / len, -sy / len, 1.0 / len};
            for (int c = 0; c < 3; ++c) pixels[(size_t(y) * n + x) * 3 + c] = uint8_t(std::lround((v[c] * 0.5 + 0.5) * 255));
        }
    auto out = OIIO::ImageOutput::create((dir / "normal.png").string());
    out->open((dir / "normal.png").string(), OIIO::ImageSpec(n, n, 3, OIIO::TypeDesc::UINT8));
    out->write_image(OIIO::TypeDesc::UINT8, pixels.data());
    out->close();
    json j = json::parse(slurp(gltf));
    j["images"] = json::array({{{"uri", "normal.png"}}});
    j["textures"] = json::array({{{"source", 0}}});
    j["materials"][0]["normalTexture"] = {{"index", 0}};
    if (ask) {
        j["materials"][0]["extensions"]["SPECBAKE_glints"] = glints;
        j["extensionsUsed"] = json::array({"SPECBAKE_glints"});
    }
    std::ofstream(gltf) << j.dump(2);
    return gltf;
}

TEST(SceneGlints, ExtensionAsksPlanAndBakeFollow) {
    const fs::path dir = temp_dir("glints_ext");
    const fs::path gltf = write_glint_plane(dir, true, json::object({{"logDensity", 18.5}}));
    const RunResult plan = run_specbake({"plan", gltf.string()}, dir);
    ASSERT_EQ(plan.exit_code, 0) << plan.err;
    EXPECT_NE(plan.out.find("glints     material 0 'test'"), std::string::npos) << plan.out;
    EXPECT_NE(plan.out.find("asked by SPECBAKE_glints; slope-space LEAN"), std::string::npos) << plan.out;
    EXPECT_NE(plan.out.find("ln 18.5"), std::string::npos) << plan.out;

    const RunResult bake = run_specbake({"bake", gltf.string(), "-o", (dir / "out").string()}, dir);
    ASSERT_EQ(bake.exit_code, 0) << bake.err;
    ASSERT_TRUE(fs::exists(dir / "out" / "glint_dictionary.ktx2"));
    const json out = json::parse(slurp(dir / "out" / "plane.gltf"));
    const json& ext = out["materials"][0]["extensions"]["SPECBAKE_specular_aa"];
    ASSERT_TRUE(ext.contains("glints")) << ext.dump(2);
    const json& g = ext["glints"];
    EXPECT_EQ(g["logDensity"], 18.5);
    EXPECT_EQ(g["relativeArea"], 1.0);
    EXPECT_EQ(g["densityRandomization"], 2.0);
    EXPECT_EQ(g["dictionary"]["uri"], "glint_dictionary.ktx2");
    EXPECT_EQ(g["dictionary"]["parameters"]["count"], 192);
    EXPECT_EQ(g["leanSpace"], "slope");
    ASSERT_FALSE(g["lean"].empty());
    for (const json& uri : g["lean"]) EXPECT_TRUE(fs::exists(dir / "out" / uri.get<std::string>())) << uri;
    // The input's ask is kept.
    EXPECT_TRUE(out["materials"][0]["extensions"].contains("SPECBAKE_glints"));
    const json manifest = json::parse(slurp(dir / "out" / "manifest.json"));
    int dictionaries = 0;
    for (const json& o : manifest["outputs"]) dictionaries += o["kind"] == "glint_dictionary";
    EXPECT_EQ(dictionaries, 1);
    EXPECT_EQ(manifest["plan"][0]["glints"][0]["decision"], "bake");
    fs::remove_all(dir);
}

// The dictionary depends on its parameters only: a rebake into the same folder copies the committed one
// when the manifest vouches for it (same parameters and tool version, matching hash), and bakes it again
// when the committed file was altered; both give the bytes of the first bake.
TEST(SceneGlints, RebakeReusesTheCommittedDictionary) {
    const fs::path dir = temp_dir("glints_reuse");
    const fs::path gltf = write_glint_plane(dir, true, json::object());
    const fs::path out = dir / "out";
    ASSERT_EQ(run_specbake({"bake", gltf.string(), "-o", out.string()}, dir).exit_code, 0);
    const std::string first = slurp(out / "glint_dictionary.ktx2");
    const auto entry_of = [&] {
        const json manifest = json::parse(slurp(out / "manifest.json"));
        for (const json& o : manifest["outputs"])
            if (o["kind"] == "glint_dictionary") return o;
        return json();
    };
    const json first_entry = entry_of();
    ASSERT_FALSE(first_entry.is_null());
    const auto change_roughness = [&](double r) {
        json j = json::parse(slurp(gltf));
        j["materials"][0]["pbrMetallicRoughness"]["roughnessFactor"] = r;
        std::ofstream(gltf) << j.dump(2);
    };

    change_roughness(0.3);  // the textures change, the dictionary does not
    const RunResult again = run_specbake({"-v", "bake", gltf.string(), "-o", out.string()}, dir);
    ASSERT_EQ(again.exit_code, 0) << again.err;
    EXPECT_NE(again.err.find("glint dictionary: the committed one is reused"), std::string::npos) << again.err;
    EXPECT_EQ(slurp(out / "glint_dictionary.ktx2"), first);
    EXPECT_EQ(entry_of(), first_entry);

    std::string altered = first;
    altered[altered.size() - 3] ^= 0x10;
    std::ofstream(out / "glint_dictionary.ktx2", std::ios::binary) << altered;
    change_roughness(0.35);
    const RunResult rebaked = run_specbake({"-v", "bake", gltf.string(), "-o", out.string()}, dir);
    ASSERT_EQ(rebaked.exit_code, 0) << rebaked.err;
    EXPECT_NE(rebaked.err.find("glint dictionary: baked"), std::string::npos) << rebaked.err;
    EXPECT_EQ(slurp(out / "glint_dictionary.ktx2"), first);
    EXPECT_EQ(entry_of(), first_entry);
    fs::remove_all(dir);
}

// The same glTF that plans and bakes above also verifies: its normal-mapped glint material gets every
// glint candidate, LEAN rows included, next to the specular AA rows.
TEST(SceneGlints, ExtensionAsksVerifyFollows) {
    if (gl_disabled()) GTEST_SKIP() << "SPECBAKE_NO_GL=1: OpenGL tests disabled";
    const fs::path dir = temp_dir("glints_verify");
    const fs::path gltf = write_glint_plane(dir, true, json::object());
    // Rough enough that the default key light's highlight reaches the camera (a Beckmann lobe has no tail).
    json j = json::parse(slurp(gltf));
    j["materials"][0]["pbrMetallicRoughness"]["roughnessFactor"] = 0.6;
    std::ofstream(gltf) << j.dump(2);
    const RunResult r = run_specbake({"verify", gltf.string(), "--size", "24x24", "--spp", "16", "--frames", "2",
                                      "--repeats", "0", "--no-variants", "--only",
                                      "none,glint-smooth,glint-ggaa,glint-ggaa+lean-norho,glint-ggaa+lean", "--strip",
                                      (dir / "strip.png").string()},
                                     dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    for (const char* name : {"| none |", "| glint-smooth |", "| glint-c20 |", "| glint-ggaa |",
                             "| glint-ggaa+lean-norho |", "| glint-ggaa+lean |"})
        EXPECT_NE(r.out.find(name), std::string::npos) << name << "\n" << r.out;
    EXPECT_EQ(r.err.find("glint ground truth is black"), std::string::npos) << r.err;
    EXPECT_TRUE(fs::exists(dir / "strip.png"));
    EXPECT_TRUE(fs::exists(dir / "strip-glints.png"));
    fs::remove_all(dir);
}

// `bench --quick` runs the glint scenes: their rows, the glint family in the summary, their strips.
TEST(SceneGlints, BenchQuickRunsTheGlintScenes) {
    if (gl_disabled()) GTEST_SKIP() << "SPECBAKE_NO_GL=1: OpenGL tests disabled";
    const fs::path dir = temp_dir("glints_bench");
    const RunResult r =
        run_specbake({"bench", "--quick", "--scenes", "glitter-sphere,glitter-plane", "-o", (dir / "b").string()}, dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("| glint-ggaa | glint |"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("| glint-c20 | glint | 1.000 |"), std::string::npos) << r.out;  // the family's base
    const std::string csv = slurp(dir / "b" / "bench.csv");
    EXPECT_NE(csv.find("glitter-plane,0.1,"), std::string::npos) << csv;
    EXPECT_NE(csv.find(",glint-ggaa+lean,glint,"), std::string::npos) << csv;
    EXPECT_TRUE(fs::exists(dir / "b" / "strips" / "glitter-sphere-a0.1-glints.png"));
    EXPECT_TRUE(fs::exists(dir / "b" / "strips" / "glitter-plane-a0.1-glints.png"));
    fs::remove_all(dir);
}

TEST(SceneGlints, NoAskNoGlints) {
    const fs::path dir = temp_dir("plain_noask");
    const fs::path gltf = write_glint_plane(dir, false, json());
    const RunResult plan = run_specbake({"plan", gltf.string()}, dir);
    ASSERT_EQ(plan.exit_code, 0) << plan.err;
    EXPECT_EQ(plan.out.find("glints"), std::string::npos) << plan.out;
    const RunResult bake = run_specbake({"bake", gltf.string(), "-o", (dir / "out").string()}, dir);
    ASSERT_EQ(bake.exit_code, 0) << bake.err;
    EXPECT_FALSE(fs::exists(dir / "out" / "glint_dictionary.ktx2"));
    EXPECT_EQ(slurp(dir / "out" / "manifest.json").find("glint"), std::string::npos);
    fs::remove_all(dir);
}

TEST(SceneGlints, ConfigAsksAndBadValuesFail) {
    const fs::path dir = temp_dir("glints_config");
    const fs::path gltf = dir / "sphere.gltf";
    write_test_model(gltf, true, 1.0, 0.3, 16, 32);
    std::ofstream(dir / "glints.toml") << "[materials.test]\nglints = true\nglints_log_density = 20\nglints_relative_area = 0.5\n";
    const RunResult plan = run_specbake({"--config", (dir / "glints.toml").string(), "plan", gltf.string()}, dir);
    ASSERT_EQ(plan.exit_code, 0) << plan.err;
    EXPECT_NE(plan.out.find("asked by config"), std::string::npos) << plan.out;
    EXPECT_NE(plan.out.find("ln 20"), std::string::npos) << plan.out;

    std::ofstream(dir / "bad.toml") << "[materials.test]\nglints = true\nglints_relative_area = 2\n";
    const RunResult bad = run_specbake({"--config", (dir / "bad.toml").string(), "plan", gltf.string()}, dir);
    EXPECT_NE(bad.exit_code, 0);
    EXPECT_NE(bad.err.find("relativeArea must be in [0, 1]"), std::string::npos) << bad.err;

    const fs::path ext = write_glint_plane(dir, true, json::object({{"density", 3}}));
    const RunResult unknown = run_specbake({"plan", ext.string()}, dir);
    EXPECT_NE(unknown.exit_code, 0);
    EXPECT_NE(unknown.err.find("SPECBAKE_glints has no field 'density'"), std::string::npos) << unknown.err;
    fs::remove_all(dir);
}

}  // namespace
