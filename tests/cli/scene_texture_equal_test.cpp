// The scene bake's texture files (KTX2 and DDS, plain and block-compressed: BC, ASTC) are the bytes `specbake texture`
// writes for the same normal and ORM maps: the scene bake streams its rows the way the texture job does.
#include "tests/cli/scene_test_util.h"

#include <gtest/gtest.h>

namespace {
using namespace scene_test;

TEST(SceneTextureEqual, SceneTexturesAreTheTextureJobsBytes) {
    const fs::path src = fs::path(SPECBAKE_ASSETS_DIR) / "gltf" / "NormalTangentMirrorTest";
    const fs::path scene = src / "NormalTangentMirrorTest.gltf";
    if (!fs::exists(scene)) GTEST_SKIP() << "shared asset missing: " << scene;
    const fs::path dir = temp_dir("scene_texture_equal");
    // The material: normalTexture and metallicRoughnessTexture on TEXCOORD_0, normal scale and roughness
    // factor 1, so the texture job's G roughness channel reads the same values.
    const std::string normal = (src / "NormalTangentTest_Normal.png").string();
    const std::string orm = (src / "NormalTangentMirrorTest_OcclusionRoughnessMetallic.png").string();
    struct Case {
        std::string name, container;
        std::vector<std::string> extra;
    };
    for (const Case& c : {Case{"ktx2", "ktx2", {}}, Case{"ktx2_bc", "ktx2", {"--block", "bc"}},
                          Case{"dds_bc", "dds", {"--block", "bc"}}, Case{"ktx2_astc", "ktx2", {"--block", "astc"}}}) {
        SCOPED_TRACE(c.name);
        std::vector<std::string> bake{"-q", "bake", scene.string(), "--container", c.container, "-o",
                                      (dir / ("bake_" + c.name)).string()};
        std::vector<std::string> texture{"-q",   "texture", "--normal", normal, "--roughness", orm, "--format",
                                         c.container, "-o", (dir / ("texture_" + c.name)).string()};
        bake.insert(bake.end(), c.extra.begin(), c.extra.end());
        texture.insert(texture.end(), c.extra.begin(), c.extra.end());
        const RunResult b = run_specbake(bake, dir);
        ASSERT_EQ(b.exit_code, 0) << b.err;
        const RunResult t = run_specbake(texture, dir);
        ASSERT_EQ(t.exit_code, 0) << t.err;
        for (const char* kind : {"roughness", "kernel", "normal", "lean", "lean_xy"}) {
            const fs::path from_scene =
                dir / ("bake_" + c.name) / ("NormalTangentMirrorTest_mat0_Material_" + std::string(kind) + "." + c.container);
            const fs::path from_texture = dir / ("texture_" + c.name) / ("texture_" + std::string(kind) + "." + c.container);
            ASSERT_TRUE(fs::exists(from_scene)) << from_scene;
            ASSERT_TRUE(fs::exists(from_texture)) << from_texture;
            EXPECT_TRUE(slurp(from_scene) == slurp(from_texture)) << kind;
        }
    }
}

}  // namespace
