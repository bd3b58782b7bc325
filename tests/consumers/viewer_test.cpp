// `specbake view` (cli/cmd_view.cpp, web/three/viewer/) in headless Chromium with the pinned three r187
// (viewer_check.mjs): specbake serves a baked UV sphere with the demo normal map, the page renders it
// with filtering off and on side by side and posts what it drew; each half must show the sphere (lit
// pixels read back from the canvas), the two halves must differ (the patch is on in one only) and both
// must report a frame time. Also the command's errors: no scene in the folder, --three naming no three.js.
#include "consumer_harness.h"
#include "tests/io/procedural_gltf.h"

namespace specbake::consumers {
namespace {

class Viewer : public ConsumerTest {
protected:
    // A UV sphere with the demo normal map (the quad's material), baked into root_/baked.
    void bake_sphere() {
        const fs::path inputs = root_ / "inputs";
        fs::create_directories(inputs);
        fs::copy_file(fs::path(SPECBAKE_SOURCE_DIR) / "tests/consumer/quad.gltf", inputs / "quad.gltf");
        specbake("texture --demo -q -o " + quote(inputs / "demo"));
        testing::ProceduralModel sphere;
        sphere.rings = 32, sphere.segments = 64;
        ASSERT_TRUE(testing::write_procedural_model(inputs / "sphere.gltf", sphere));
        const nlohmann::json q = nlohmann::json::parse(slurp(inputs / "quad.gltf"));
        nlohmann::json g = nlohmann::json::parse(slurp(inputs / "sphere.gltf"));
        g["images"] = q["images"];
        g["textures"] = q["textures"];
        if (q.contains("samplers")) g["samplers"] = q["samplers"];
        g["materials"][0] = q["materials"][0];
        std::ofstream(inputs / "sphere.gltf") << g.dump(1);
        specbake("bake -q " + quote(inputs / "sphere.gltf") + " -o " + quote(root_ / "baked"));
    }
};

TEST_F(Viewer, DrawsBothHalvesAndReportsFrameTimes) {
    if (const std::string why = missing_node_packages({"three"}); !why.empty()) GTEST_SKIP() << why;
    bake_sphere();
    std::string err;
    const int rc = shell("timeout 170 node " + quote(consumers_dir() / "viewer_check.mjs") + " " + quote(SPECBAKE_EXE) +
                             " " + quote(root_ / "baked") + " " + quote(root_ / "report.json") + " 40 800x500 150",
                         root_ / "scratch", nullptr, &err);
    if (rc == 3) GTEST_SKIP() << err;
    ASSERT_EQ(rc, 0) << "viewer run failed: " << err;
    const nlohmann::json r = nlohmann::json::parse(slurp(root_ / "report.json"));
    ASSERT_FALSE(r.contains("fatal")) << r["fatal"];
    EXPECT_EQ(r.value("three", ""), "187");
    EXPECT_EQ(r.value("scene", ""), "sphere.gltf");
    for (const auto& e : r["errors"]) ADD_FAILURE() << "page console " << e.value("level", "") << ": " << e.value("text", "");
    EXPECT_EQ(r["plugin"]["patched"].size(), 1u) << r["plugin"].dump();
    EXPECT_NE(r.value("status", "").find("three.js r187 from the copy tests/consumers/package-lock.json pins"),
              std::string::npos) << r.value("status", "");
    const auto& halves = r["halves"];
    ASSERT_EQ(halves.size(), 2u);
    double mean[2] = {0, 0};
    for (int i = 0; i < 2; ++i) {
        const auto& h = halves[size_t(i)];
        SCOPED_TRACE(h.value("name", ""));
        // The sphere fills about a fifth of each half at the default distance.
        EXPECT_GT(h.value("litFraction", 0.0), 0.05) << "the half shows no sphere";
        EXPECT_LT(h.value("litFraction", 1.0), 0.6);
        EXPECT_GT(h.value("frameMs", 0.0), 0.0);
        EXPECT_GE(h.value("samples", 0), 30);
        for (int c = 0; c < 3; ++c) mean[i] += h["mean"][size_t(c)].get<double>();
        // The label shows the same median, rounded to 0.1 ms, in the page itself.
        EXPECT_NE(r["labels"][size_t(i)].get<std::string>().find(" ms"), std::string::npos) << r["labels"][size_t(i)];
    }
    // Same geometry and camera on both halves; specbake's filtering changes the shading of the right one.
    EXPECT_NEAR(halves[0].value("litFraction", 0.0), halves[1].value("litFraction", 1.0), 0.01);
    EXPECT_GT(std::abs(mean[0] - mean[1]), 0.05) << "the halves are the same image: the patch is not on in one";
    std::printf("viewer %dx%d: off %.1f ms, on %.1f ms (median of %d frames, SwiftShader); mean colour sum off %.2f, on %.2f\n",
                r["size"][0].get<int>(), r["size"][1].get<int>(), halves[0].value("frameMs", 0.0),
                halves[1].value("frameMs", 0.0), halves[1].value("samples", 0), mean[0], mean[1]);
}

TEST_F(Viewer, ErrorsNameTheProblem) {
    fs::create_directories(root_ / "empty");
    std::string err;
    EXPECT_EQ(shell(quote(SPECBAKE_EXE) + " view " + quote(root_ / "empty") + " --port 0", root_ / "scratch", nullptr, &err), 1);
    EXPECT_NE(err.find("no .gltf or .glb files in it"), std::string::npos) << err;
    EXPECT_EQ(shell(quote(SPECBAKE_EXE) + " view " + quote(root_ / "missing") + " --port 0", root_ / "scratch", nullptr, &err), 1);
    EXPECT_NE(err.find("no such file or folder"), std::string::npos) << err;
    std::ofstream(root_ / "empty/a.gltf") << "{}";
    EXPECT_EQ(shell(quote(SPECBAKE_EXE) + " view " + quote(root_ / "empty") + " --port 0 --three " + quote(root_ / "empty"),
                    root_ / "scratch", nullptr, &err), 1);
    EXPECT_NE(err.find("no three.js package there"), std::string::npos) << err;
}

}  // namespace
}  // namespace specbake::consumers
