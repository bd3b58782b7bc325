// `verify --strip` and `--images`: the pictures a person looks at, read back with OpenImageIO. Which
// candidates the strip holds and where its pixels land is pinned in tests/verify/strips_test.cpp; here the
// command writes them, names them and sizes them as its help says.
#include "scene_test_util.h"

#include <OpenImageIO/imageio.h>

#include <gtest/gtest.h>

namespace {

using namespace scene_test;

std::pair<int, int> png_size(const fs::path& path) {
    auto in = OIIO::ImageInput::open(path.string());
    if (!in) return {0, 0};
    const OIIO::ImageSpec spec = in->spec();
    in->close();
    return {spec.width, spec.height};
}

TEST(VerifyPictures, StripIsAGridWithTheHarmCellAndImagesAreOnePerCandidate) {
    if (gl_disabled()) GTEST_SKIP() << "SPECBAKE_NO_GL=1: OpenGL tests disabled";
    const fs::path dir = temp_dir("verify_pictures");
    const RunResult r = run_specbake({"verify", "--builtin", "sphere", "--size", "24x24", "--spp", "16", "--frames", "2",
                                      "--repeats", "0", "--no-variants", "--no-limit", "--no-floor", "--only",
                                      "default,projected", "--variant", "nopix:SPECAA_NO_PIXEL_KERNEL", "--strip",
                                      (dir / "s.png").string(), "--images", (dir / "each").string()},
                                     dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    // Cells: ground truth, none, default, default:nopix, projected (the best of the rest) and the harm
    // cell: six, four to a row, each 326 pixels wide (at least 40 label characters) and 30 + 2 x tile + 12
    // high.
    const auto [w, h] = png_size(dir / "s.png");
    EXPECT_EQ(w, 4 * 326);
    EXPECT_GT(h, 2 * (30 + 12));
    EXPECT_EQ((h / 2 - 42) % 2, 0) << h;
    // One picture per candidate (the ground truth beside it): ':' is not kept in a file name.
    for (const char* name : {"none.png", "default.png", "default_nopix.png", "projected.png"}) {
        const auto [iw, ih] = png_size(dir / "each" / name);
        EXPECT_EQ(iw, 2 * 326) << name;
        EXPECT_EQ(ih, h / 2) << name;
    }
    fs::remove_all(dir);
}

}  // namespace
