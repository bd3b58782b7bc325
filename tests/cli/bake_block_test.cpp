// `specbake bake --block bc`: the scene bake's textures block-compressed exactly as `specbake texture
// --block bc` compresses the same inputs (byte for byte), recorded in the manifest and the vendor
// extension, re-baked when the option changes, and plain without it.
#include "tests/cli/scene_test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstring>
#include <map>

namespace {
using namespace scene_test;

class BakeBlock : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = temp_dir("bake_block");
        // The quad of tests/consumer (roughnessFactor 0.3) with the demo normal map beside it.
        fs::copy_file(fs::path(SPECBAKE_SOURCE_DIR) / "tests/consumer/quad.gltf", dir_ / "quad.gltf");
        ASSERT_EQ(run({"-q", "texture", "--demo", "-o", (dir_ / "demo").string()}), 0);
    }
    void TearDown() override { fs::remove_all(dir_); }
    int run(const std::vector<std::string>& args) {
        const RunResult r = run_specbake(args, dir_);
        if (r.exit_code != 0) ADD_FAILURE() << r.err;
        return r.exit_code;
    }
    nlohmann::json json_of(const fs::path& p) { return nlohmann::json::parse(slurp(p)); }
    fs::path dir_;
};

TEST_F(BakeBlock, SceneTexturesAreCompressedAsTheTextureCommandDoes) {
    for (const char* container : {"ktx2", "dds"}) {
        SCOPED_TRACE(container);
        const fs::path scene = dir_ / (std::string("scene_") + container), tex = dir_ / (std::string("tex_") + container);
        ASSERT_EQ(run({"-q", "bake", (dir_ / "quad.gltf").string(), "--container", container, "--block", "bc", "-o",
                       scene.string()}),
                  0);
        ASSERT_EQ(run({"-q", "texture", "--normal", (dir_ / "demo" / "demo_normal.png").string(), "--roughness-value",
                       "0.3", "--format", container, "--block", "bc", "-o", tex.string()}),
                  0);
        for (const char* kind : {"roughness", "normal", "kernel"}) {
            const std::string a = slurp(scene / (std::string("quad_mat0_Bumpy_") + kind + "." + container));
            const std::string b = slurp(tex / (std::string("texture_") + kind + "." + container));
            ASSERT_FALSE(a.empty()) << kind;
            EXPECT_TRUE(a == b) << kind << ": the scene bake's file differs from texture --block bc's";
        }
        const nlohmann::json m = json_of(scene / "manifest.json");
        EXPECT_EQ(m["settings"]["supercompression"]["block"],
                  (nlohmann::json{{"one_channel", "bc4"}, {"normal", "bc5"}, {"rgba", "bc1"}}));
        std::map<std::string, std::string> gpu;
        for (const auto& o : m["outputs"])
            if (o.contains("gpu_format")) gpu[o["kind"].get<std::string>() + ":" + o["path"].get<std::string>()] = o["gpu_format"];
        EXPECT_EQ(gpu["roughness:quad_mat0_Bumpy_roughness." + std::string(container)], "BC4_UNORM_BLOCK");
        EXPECT_EQ(gpu["normal:quad_mat0_Bumpy_normal." + std::string(container)], "BC5_UNORM_BLOCK");
        EXPECT_EQ(gpu["kernel:quad_mat0_Bumpy_kernel." + std::string(container)], "R16G16B16A16_SFLOAT");
        // The extension says what the blocks hold: BC5 is the normal's x, y only.
        const nlohmann::json g = json_of(scene / "quad.gltf");
        const nlohmann::json& outs = g["materials"][0]["extensions"]["SPECBAKE_specular_aa"]["outputs"];
        int checked = 0;
        for (const auto& o : outs) {
            if (o["kind"] == "normal") {
                EXPECT_EQ(o["gpuFormat"], "BC5_UNORM_BLOCK");
                EXPECT_EQ(o["channels"], 2);
                ++checked;
            }
            if (o["kind"] == "kernel") {
                EXPECT_FALSE(o.contains("gpuFormat"));
                ++checked;
            }
        }
        EXPECT_EQ(checked, 2);
        const RunResult check = run_specbake({"inspect", "--check", (scene / "manifest.json").string()}, dir_);
        EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
    }
}

// Without --block the bake is as before (no "supercompression" setting, no gpuFormat); changing --block
// re-bakes instead of reporting the folder up to date.
TEST_F(BakeBlock, OffByDefaultAndAChangeRebakes) {
    const fs::path out = dir_ / "out";
    ASSERT_EQ(run({"-q", "bake", (dir_ / "quad.gltf").string(), "-o", out.string()}), 0);
    EXPECT_FALSE(json_of(out / "manifest.json")["settings"].contains("supercompression"));
    EXPECT_EQ(slurp(out / "quad.gltf").find("gpuFormat"), std::string::npos);
    const std::string plain = slurp(out / "quad_mat0_Bumpy_normal.ktx2");
    ASSERT_EQ(run({"-q", "bake", (dir_ / "quad.gltf").string(), "--block", "bc", "--block-rgba", "bc3", "-o",
                   out.string()}),
              0);
    const nlohmann::json m = json_of(out / "manifest.json");
    EXPECT_EQ(m["settings"]["supercompression"]["block"]["rgba"], "bc3");
    const std::string blocks = slurp(out / "quad_mat0_Bumpy_normal.ktx2");
    EXPECT_NE(plain, blocks);
    uint32_t vk = 0;
    std::memcpy(&vk, blocks.data() + 12, 4);
    EXPECT_EQ(vk, 141u);  // VK_FORMAT_BC5_UNORM_BLOCK
    const RunResult bad = run_specbake({"bake", (dir_ / "quad.gltf").string(), "--block", "bc7", "-o", out.string()}, dir_);
    EXPECT_NE(bad.exit_code, 0);
    EXPECT_NE(bad.err.find("--block"), std::string::npos) << bad.err;
}

}  // namespace
