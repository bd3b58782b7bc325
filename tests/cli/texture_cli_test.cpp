// `specbake texture` end to end: the demo, the shared normal maps, and bad inputs (one error line naming
// the file, exit code 1, nothing half-written).
#include "io/image/image_io.h"
#include "io/texture/ktx2.h"
#include "io/output/manifest.h"
#include "io/files/sha256.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

namespace specbake {
namespace {
namespace fs = std::filesystem;

struct RunResult {
    int code = -1;
    std::string out, err;
};

std::string read_text(const fs::path& p) {
    std::ifstream f(p);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

RunResult run(const std::string& args, const fs::path& scratch) {
    const fs::path out = scratch / "stdout.txt", err = scratch / "stderr.txt";
    const std::string cmd = std::string("'") + SPECBAKE_EXE + "' " + args + " >'" + out.string() + "' 2>'" + err.string() + "'";
    const int status = std::system(cmd.c_str());
    RunResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = read_text(out);
    r.err = read_text(err);
    return r;
}

class TextureCli : public ::testing::Test {
protected:
    void SetUp() override {
        root_ = fs::temp_directory_path() /
                ("specbake_texture_cli_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) +
                 "_" + std::to_string(::getpid()));
        fs::remove_all(root_);
        fs::create_directories(root_ / "scratch");
    }
    void TearDown() override { fs::remove_all(root_); }

    // Expects a failed run with exactly one "specbake: error: ..." line that names `file`.
    void expect_one_error_line(const RunResult& r, const std::string& file) {
        EXPECT_EQ(r.code, 1) << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_EQ(r.err.rfind("specbake: error: ", 0), 0u) << r.err;
        EXPECT_NE(r.err.find(file), std::string::npos) << r.err;
    }

    // The folder holds nothing (or does not exist): no partial or temporary file.
    void expect_empty_or_missing(const fs::path& dir) {
        if (!fs::exists(dir)) return;
        for (const auto& e : fs::directory_iterator(dir)) ADD_FAILURE() << "left behind: " << e.path();
    }

    fs::path root_;
};

TEST_F(TextureCli, HelpHasExamples) {
    const RunResult r = run("texture --help", root_ / "scratch");
    EXPECT_EQ(r.code, 0);
    EXPECT_NE(r.out.find("Examples:"), std::string::npos);
    EXPECT_NE(r.out.find("--demo"), std::string::npos);
    EXPECT_NE(r.out.find("--roughness-value"), std::string::npos);
}

TEST_F(TextureCli, DemoWritesContainersAndManifestDeterministically) {
    const fs::path a = root_ / "a", b = root_ / "b";
    const RunResult r1 = run("texture --demo -q -j 1 -o '" + a.string() + "'", root_ / "scratch");
    ASSERT_EQ(r1.code, 0) << r1.err;
    const RunResult r2 = run("texture --demo -q -j 2 -o '" + b.string() + "'", root_ / "scratch");
    ASSERT_EQ(r2.code, 0) << r2.err;
    auto m = io::read_manifest(a / "manifest.json");
    ASSERT_TRUE(m.ok()) << m.error().message;
    EXPECT_EQ(m->tool, "specbake");
    ASSERT_EQ(m->outputs.size(), 5u);  // roughness, kernel, lean, lean_xy, normal
    ASSERT_EQ(m->inputs.size(), 2u);
    for (const io::ManifestOutput& o : m->outputs) {
        EXPECT_EQ(o.format, "ktx2");
        EXPECT_EQ(o.width, 512);
        EXPECT_EQ(o.height, 384);
        EXPECT_EQ(o.mips, 10);
        auto hash = io::sha256_file(a / o.path);
        ASSERT_TRUE(hash.ok());
        EXPECT_EQ(*hash, o.sha256);
        // Any thread count gives the same bytes.
        auto other = io::sha256_file(b / o.path);
        ASSERT_TRUE(other.ok());
        EXPECT_EQ(*other, o.sha256) << o.path;
        std::ifstream f(a / o.path, std::ios::binary);
        const std::vector<uint8_t> bytes{std::istreambuf_iterator<char>(f), {}};
        auto t = io::read_ktx2_texture(bytes, o.path);
        ASSERT_TRUE(t.ok()) << t.error().message;
        EXPECT_EQ(int(t->chain.levels.size()), o.mips);
    }
    // Mip 0 of the roughness output is the ORM input's G channel, unchanged.
    auto orm = io::read_image(a / "demo_orm.png");
    ASSERT_TRUE(orm.ok());
    std::ifstream f(a / "texture_roughness.ktx2", std::ios::binary);
    const std::vector<uint8_t> bytes{std::istreambuf_iterator<char>(f), {}};
    auto rough = io::read_ktx2_texture(bytes, "r");
    ASSERT_TRUE(rough.ok());
    // The ORM roughness is stored as RGBA with A = 1 (docs/texture-bake.md#output-layouts).
    ASSERT_EQ(rough->chain.channels(), 4);
    ASSERT_EQ(rough->chain.levels[0].texel_count(), orm->texel_count());
    for (size_t i = 0; i < orm->texel_count(); ++i) {
        for (int c = 0; c < 3; ++c)
            ASSERT_NEAR(rough->chain.levels[0].pixels[i * 4 + size_t(c)], orm->pixels[i * 3 + size_t(c)], 1e-6);
        ASSERT_EQ(rough->chain.levels[0].pixels[i * 4 + 3], 1.0f);
    }
}

// EXR outputs (the mipmapped file, and the per-mip float files beside per-mip PNGs) are written by the tree's
// own encoders: with the OpenImageIO module made unfindable, a bake of plain PNG inputs still writes them,
// and OpenImageIO reads every level back.
TEST_F(TextureCli, ExrAndPngOutputsNeedNoImageModule) {
    const fs::path demo = root_ / "demo";
    const RunResult d = run("texture --demo -q -o '" + demo.string() + "'", root_ / "scratch");
    ASSERT_EQ(d.code, 0) << d.err;
    const std::string inputs =
        "--normal '" + (demo / "demo_normal.png").string() + "' --roughness '" + (demo / "demo_orm.png").string() + "'";
    const std::string missing = "SPECBAKE_OIIO_MODULE='" + (root_ / "absent" / "libspecbake_oiio.so").string() + "' ";
    for (const char* format : {"exr", "png"}) {
        SCOPED_TRACE(format);
        const fs::path out = root_ / format;
        const std::string cmd = std::string("'") + SPECBAKE_EXE + "' texture -q " + inputs + " --format " + format +
                                " -o '" + out.string() + "' 2>'" + (root_ / "scratch" / "err.txt").string() + "'";
        ASSERT_EQ(std::system((missing + cmd).c_str()), 0) << read_text(root_ / "scratch" / "err.txt");
        auto m = io::read_manifest(out / "manifest.json");
        ASSERT_TRUE(m.ok());
        int exr_files = 0;
        for (const io::ManifestOutput& o : m->outputs) {
            if (o.format != "exr") continue;
            ++exr_files;
            auto in = OIIO::ImageInput::open((out / o.path).string());
            ASSERT_TRUE(in) << o.path << ": " << OIIO::geterror();
            int levels = 0;
            while (in->seek_subimage(0, levels)) ++levels;
            EXPECT_EQ(levels, o.mips) << o.path;
            std::vector<float> texels(size_t(o.width) * size_t(o.height) * size_t(o.channels));
            EXPECT_TRUE(in->read_image(0, 0, 0, o.channels, OIIO::TypeDesc::FLOAT, texels.data())) << in->geterror();
        }
        EXPECT_GT(exr_files, 0);
    }
}

TEST_F(TextureCli, EveryFormatFromTheCommandLine) {
    for (const char* format : {"dds", "exr", "png"}) {
        const fs::path out = root_ / format;
        const RunResult r = run(std::string("texture --demo -q --format ") + format + " --anisotropic --outputs roughness,kernel -o '" +
                              out.string() + "'",
                          root_ / "scratch");
        ASSERT_EQ(r.code, 0) << r.err;
        auto m = io::read_manifest(out / "manifest.json");
        ASSERT_TRUE(m.ok());
        for (const io::ManifestOutput& o : m->outputs) EXPECT_TRUE(fs::exists(out / o.path)) << o.path;
        if (std::string(format) == "png") EXPECT_EQ(m->outputs.size(), 20u);  // 2 outputs x 10 mips
        else EXPECT_EQ(m->outputs.size(), 2u);
    }
}

TEST_F(TextureCli, TwoChannelSixteenBitMapIsReconstructedAndSaid) {
    Image n(8, 6, 2);
    for (size_t i = 0; i < n.pixels.size(); ++i) n.pixels[i] = 0.5f + 0.01f * float(i % 7);
    const fs::path in = root_ / "in" / "n16.png";
    ASSERT_TRUE(io::write_image(in, n, 16).ok());
    const RunResult r = run("texture --normal '" + in.string() + "' --roughness-value 0.3 -o '" + (root_ / "out").string() + "'",
                      root_ / "scratch");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("z reconstructed"), std::string::npos) << r.err;
    auto m = io::read_manifest(root_ / "out" / "manifest.json");
    ASSERT_TRUE(m.ok());
    // A 16-bit input gives half-float roughness and normal outputs in KTX2 (R16_SFLOAT: 11 significant bits,
    // and a format WebGL 2 samples, which it does not do for 16-bit UNORM without EXT_texture_norm16).
    EXPECT_EQ(m->outputs[0].extra["encoding"], "float16");
    EXPECT_EQ(m->outputs[0].extra["gpu_format"], "R16_SFLOAT");
    // Per-mip PNGs keep 16-bit UNORM (PNG has no float).
    const RunResult p = run("texture --normal '" + in.string() + "' --roughness-value 0.3 --format png -o '" +
                                (root_ / "png").string() + "'",
                            root_ / "scratch");
    ASSERT_EQ(p.code, 0) << p.err;
    auto mp = io::read_manifest(root_ / "png" / "manifest.json");
    ASSERT_TRUE(mp.ok());
    EXPECT_EQ(mp->outputs[0].extra["encoding"], "unorm16");
}

TEST_F(TextureCli, BadInputsGiveOneErrorLineAndNoOutput) {
    const fs::path in = root_ / "in";
    fs::create_directories(in);
    Image good(16, 16, 3);
    for (float& v : good.pixels) v = 0.5f;
    ASSERT_TRUE(io::write_image(in / "good.png", good, 8).ok());
    {
        std::ifstream f(in / "good.png", std::ios::binary);
        const std::string bytes{std::istreambuf_iterator<char>(f), {}};
        std::ofstream t(in / "truncated.png", std::ios::binary);
        t << bytes.substr(0, bytes.size() / 2);
    }
    ASSERT_TRUE(io::write_image(in / "gray.png", Image(16, 16, 1), 8).ok());
    {
        Image nan_map(4, 4, 3);
        nan_map.pixels[7] = std::numeric_limits<float>::quiet_NaN();
        auto out = OIIO::ImageOutput::create((in / "nan.exr").string());
        ASSERT_TRUE(out);
        ASSERT_TRUE(out->open((in / "nan.exr").string(), OIIO::ImageSpec(4, 4, 3, OIIO::TypeDesc::FLOAT)));
        ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, nan_map.pixels.data()));
        out->close();
    }
    const fs::path out = root_ / "out";
    struct Case { std::string args, names; };
    for (const Case& c : {Case{"--normal '" + (in / "truncated.png").string() + "'", "truncated.png"},
                          Case{"--normal '" + (in / "gray.png").string() + "'", "gray.png"},
                          Case{"--normal '" + (in / "nan.exr").string() + "'", "nan.exr"},
                          Case{"--normal '" + (in / "missing.png").string() + "'", "missing.png"},
                          Case{"--normal '" + (in / "good.png").string() + "' --roughness '" +
                                   (in / "truncated.png").string() + "'",
                               "truncated.png"}}) {
        SCOPED_TRACE(c.args);
        const RunResult r = run("texture " + c.args + " -o '" + out.string() + "'", root_ / "scratch");
        expect_one_error_line(r, c.names);
        expect_empty_or_missing(out);
    }
    // Output folder = the input's folder: refused, the input untouched, nothing written.
    const auto before = fs::last_write_time(in / "good.png");
    const size_t files_before = size_t(std::distance(fs::directory_iterator(in), fs::directory_iterator{}));
    const RunResult r = run("texture --normal '" + (in / "good.png").string() + "' -o '" + in.string() + "'", root_ / "scratch");
    expect_one_error_line(r, in.string());
    EXPECT_EQ(fs::last_write_time(in / "good.png"), before);
    EXPECT_EQ(size_t(std::distance(fs::directory_iterator(in), fs::directory_iterator{})), files_before);
    // Usage errors exit with 2.
    EXPECT_EQ(run("texture -o '" + out.string() + "'", root_ / "scratch").code, 2);
    EXPECT_EQ(run("texture --demo --format bmp -o '" + out.string() + "'", root_ / "scratch").code, 2);
}

TEST_F(TextureCli, SharedNormalMaps) {
    const fs::path assets = SPECBAKE_ASSETS_DIR;
    const fs::path ribs = assets / "gltf" / "ClearCoatTest" / "RibsNormal.png";
    const fs::path stripes = assets / "gltf" / "ClearCoatTest" / "RoughnessStripes.png";
    const fs::path wrap = assets / "gltf" / "ClearCoatTest" / "PlasticWrap_normals.jpg";
    const fs::path tangent = assets / "gltf" / "NormalTangentTest" / "NormalTangentTest_Normal.png";
    const fs::path tangent_orm = assets / "gltf" / "NormalTangentTest" / "NormalTangentTest_OcclusionRoughnessMetallic.png";
    if (!fs::exists(ribs) || !fs::exists(wrap) || !fs::exists(tangent))
        GTEST_SKIP() << "shared assets not found under " << assets << " (set SPECBAKE_SHARED_ASSETS)";
    {
        const RunResult r = run("texture -q --normal '" + ribs.string() + "' --roughness '" + stripes.string() +
                              "' --anisotropic -o '" + (root_ / "ribs").string() + "'",
                          root_ / "scratch");
        ASSERT_EQ(r.code, 0) << r.err;
        // Ribs vary along x only: the anisotropic kernel has Sigma.yy = 0 at every level.
        std::ifstream f(root_ / "ribs" / "texture_kernel.ktx2", std::ios::binary);
        const std::vector<uint8_t> bytes{std::istreambuf_iterator<char>(f), {}};
        auto k = io::read_ktx2_texture(bytes, "kernel");
        ASSERT_TRUE(k.ok());
        float max_xx = 0, max_yy = 0;
        for (const Image& L : k->chain.levels)
            for (size_t i = 0; i < L.texel_count(); ++i) max_xx = std::max(max_xx, L.pixels[4 * i]), max_yy = std::max(max_yy, L.pixels[4 * i + 1]);
        EXPECT_GT(max_xx, 0.01f);
        EXPECT_LT(max_yy, 1e-4f);
    }
    {
        const RunResult r = run("texture -q --normal '" + wrap.string() + "' --roughness-value 0.2 --format exr -o '" +
                              (root_ / "wrap").string() + "'",
                          root_ / "scratch");
        ASSERT_EQ(r.code, 0) << r.err;
        EXPECT_TRUE(fs::exists(root_ / "wrap" / "texture_lean.exr"));
        EXPECT_TRUE(fs::exists(root_ / "wrap" / "texture_lean_xy.exr"));
    }
    {
        const RunResult r = run("texture -q --normal '" + tangent.string() + "' --roughness '" + tangent_orm.string() +
                              "' --format dds -o '" + (root_ / "tangent").string() + "'",
                          root_ / "scratch");
        ASSERT_EQ(r.code, 0) << r.err;
        auto m = io::read_manifest(root_ / "tangent" / "manifest.json");
        ASSERT_TRUE(m.ok());
        EXPECT_EQ(m->outputs[0].channels, 4);  // ORM carried through, as RGBA with A = 1
        EXPECT_EQ(m->outputs[0].mips, 12);
    }
}

}  // namespace
}  // namespace specbake
