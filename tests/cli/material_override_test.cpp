// Per-material texture settings from --config [materials.NAME]: applied to that material's bake only,
// recorded in the manifest and noticed by the up-to-date check. The reference for the overridden
// material is a plain bake with the same setting given for every material on the command line.
#include "scene_test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>

namespace {

using scene_test::fs::path;
using scene_test::run_specbake;
using scene_test::slurp;
using nlohmann::json;

class MaterialOverride : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = scene_test::temp_dir("material_override");
        scene_test::fs::create_directories(dir_ / "scene");
        ASSERT_EQ(run_specbake({"texture", "--demo", "-q", "-o", (dir_ / "scene/demo").string()}, dir_).exit_code, 0);
        // The quad twice: one primitive per material, both materials with the same normal texture and
        // roughness, so without an override they share one bake.
        json g = json::parse(slurp(path(SPECBAKE_SOURCE_DIR) / "tests/consumer/quad.gltf"));
        json second = g["materials"][0];
        second["name"] = "Plain";
        g["materials"].push_back(second);
        json prim = g["meshes"][0]["primitives"][0];
        prim["material"] = 1;
        g["meshes"][0]["primitives"].push_back(prim);
        std::ofstream(dir_ / "scene/two.gltf") << g.dump(1);
    }
    void TearDown() override { scene_test::fs::remove_all(dir_); }

    json manifest(const path& out) const { return json::parse(slurp(out / "manifest.json")); }
    // sha256 of the output of `kind` whose file name contains `stem_part`.
    static std::string hash_of(const json& m, const std::string& kind, const std::string& stem_part) {
        for (const json& o : m["outputs"])
            if (o["kind"] == kind && o["path"].get<std::string>().find(stem_part) != std::string::npos)
                return o["sha256"];
        return {};
    }
    scene_test::RunResult bake(const path& out, std::vector<std::string> extra) {
        std::vector<std::string> args{"bake", (dir_ / "scene/two.gltf").string(), "-o", out.string()};
        args.insert(args.end(), extra.begin(), extra.end());
        return run_specbake(args, dir_);
    }

    path dir_;
};

TEST_F(MaterialOverride, AppliesToTheNamedMaterialOnly) {
    std::ofstream(dir_ / "max.toml") << "[materials.Bumpy]\nisotropic = \"max\"\n";
    const path over = dir_ / "over", all_max = dir_ / "all_max", plain = dir_ / "plain";
    auto r = bake(over, {"--config", (dir_ / "max.toml").string(), "-q"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    ASSERT_EQ(bake(all_max, {"--isotropic", "max", "-q"}).exit_code, 0);
    ASSERT_EQ(bake(plain, {"-q"}).exit_code, 0);

    const json m = manifest(over);
    EXPECT_EQ(m["settings"]["texture"]["isotropic"], "mean");
    EXPECT_EQ(m["settings"]["materials"]["Bumpy"]["isotropic"], "max");
    EXPECT_FALSE(m["settings"]["materials"].contains("Plain"));
    // The plan bakes the two materials separately now.
    int own_bakes = 0;
    for (const json& t : m["plan"][0]["textures"]) own_bakes += t.dump().find("same inputs") == std::string::npos;
    EXPECT_EQ(own_bakes, 2) << m["plan"].dump(1);

    // The isotropic reduction changes the filtered roughness (the default kernel output is Sigma, which it
    // does not touch).
    const std::string bumpy = hash_of(m, "roughness", "_Bumpy"), other = hash_of(m, "roughness", "_Plain");
    ASSERT_FALSE(bumpy.empty());
    ASSERT_FALSE(other.empty());
    EXPECT_EQ(bumpy, hash_of(manifest(all_max), "roughness", "_Bumpy"));
    EXPECT_EQ(other, hash_of(manifest(plain), "roughness", "_Bumpy")) << "Plain is baked with the defaults";
    EXPECT_NE(bumpy, other);
}

TEST_F(MaterialOverride, ChangedOverrideRebakes) {
    std::ofstream(dir_ / "a.toml") << "[materials.Plain]\nisotropic = \"sum\"\n";
    const path out = dir_ / "out";
    ASSERT_EQ(bake(out, {"--config", (dir_ / "a.toml").string(), "-q"}).exit_code, 0);
    auto same = bake(out, {"--config", (dir_ / "a.toml").string()});
    ASSERT_EQ(same.exit_code, 0) << same.err;
    EXPECT_NE(same.out.find("up to date"), std::string::npos) << same.out << same.err;
    auto quiet = bake(out, {"--config", (dir_ / "a.toml").string(), "-q"});
    ASSERT_EQ(quiet.exit_code, 0) << quiet.err;
    EXPECT_EQ(quiet.out + quiet.err, "") << "the global --quiet silences the up-to-date line";
    std::ofstream(dir_ / "a.toml") << "[materials.Plain]\nisotropic = \"max\"\n";
    auto changed = bake(out, {"--config", (dir_ / "a.toml").string()});
    ASSERT_EQ(changed.exit_code, 0) << changed.err;
    EXPECT_EQ(changed.out.find("up to date"), std::string::npos) << changed.out;
    EXPECT_EQ(manifest(out)["settings"]["materials"]["Plain"]["isotropic"], "max");
}

TEST_F(MaterialOverride, BadKeyOrValueIsAUsageError) {
    std::ofstream(dir_ / "bad.toml") << "[materials.Bumpy]\nisotropic = \"median\"\n";
    auto r = bake(dir_ / "bad", {"--config", (dir_ / "bad.toml").string()});
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("materials.Bumpy.isotropic"), std::string::npos) << r.err;
    std::ofstream(dir_ / "typo.toml") << "[materials.Bumpy]\nisotropik = \"max\"\n";
    r = bake(dir_ / "typo", {"--config", (dir_ / "typo.toml").string()});
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("materials.Bumpy.isotropik"), std::string::npos) << r.err;
}

}  // namespace
