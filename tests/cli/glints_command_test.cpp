// specbake glints: the KTX2 2D array read back by a parser written here from the KTX 2.0 specification
// (not io/ktx2), every stored marginal integrated under an emulated GPU lookup, the manifest's
// parameters, determinism across runs and thread counts, and bad options.
#include "scene_test_util.h"

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace {

using namespace scene_test;

uint32_t u32(const std::string& b, size_t at) {
    uint32_t v;
    std::memcpy(&v, b.data() + at, 4);
    return v;
}
uint64_t u64(const std::string& b, size_t at) {
    uint64_t v;
    std::memcpy(&v, b.data() + at, 8);
    return v;
}

// IEEE 754 binary16 to double.
double half_to_double(uint16_t h) {
    const int sign = h >> 15, exponent = (h >> 10) & 31, mantissa = h & 1023;
    const double magnitude = exponent == 0 ? std::ldexp(mantissa, -24)
                                           : std::ldexp(1024 + mantissa, exponent - 25);
    return sign ? -magnitude : magnitude;
}

TEST(GlintsCommand, WritesAnArrayWhoseMarginalsIntegrateToOne) {
    const fs::path dir = temp_dir("glints");
    const RunResult r = run_specbake({"glints", "-o", (dir / "out").string(), "--count", "16", "--levels", "8"}, dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string b = slurp(dir / "out" / "glint_dictionary.ktx2");
    ASSERT_GT(b.size(), 80u);
    const unsigned char id[12] = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n'};
    ASSERT_EQ(std::memcmp(b.data(), id, 12), 0);
    EXPECT_EQ(u32(b, 12), 97u);  // VK_FORMAT_R16G16B16A16_SFLOAT
    EXPECT_EQ(u32(b, 16), 2u);   // typeSize
    EXPECT_EQ(u32(b, 20), 64u);  // pixelWidth
    EXPECT_EQ(u32(b, 24), 1u);   // pixelHeight: a 2D array, not 1D (OpenGL ES, WebGL, Metal)
    EXPECT_EQ(u32(b, 28), 0u);   // pixelDepth
    const uint32_t layers = u32(b, 32), levels = u32(b, 40);
    EXPECT_EQ(layers, 8u * 16u / 4u);
    EXPECT_EQ(u32(b, 36), 1u);
    EXPECT_EQ(levels, 7u);
    EXPECT_EQ(u32(b, 44), 0u);

    const double sigma_o = 0.5 / std::sqrt(2.0), range = 4.0 * sigma_o;
    double worst = 0.0;
    for (uint32_t m = 0; m < levels; ++m) {
        const uint64_t offset = u64(b, 80 + 24 * m), length = u64(b, 80 + 24 * m + 8);
        const int w = 64 >> m;
        ASSERT_EQ(length, uint64_t(w) * layers * 8);
        ASSERT_LE(offset + length, b.size());
        ASSERT_EQ(offset % 8, 0u);
        for (uint32_t layer = 0; layer < layers; ++layer)
            for (int c = 0; c < 4; ++c) {
                std::vector<double> v(static_cast<size_t>(w));
                for (int x = 0; x < w; ++x) {
                    uint16_t h;
                    std::memcpy(&h, b.data() + offset + (size_t(layer) * w + x) * 8 + size_t(c) * 2, 2);
                    v[size_t(x)] = half_to_double(h);
                    ASSERT_GE(v[size_t(x)], 0.0);
                }
                // Linear filter through texel centres, clamp to edge, u = |s| / range, midpoint rule.
                const int n = 2048;
                double integral = 0.0;
                for (int i = 0; i < n; ++i) {
                    const double t = std::fabs(-range + (i + 0.5) * 2 * range / n) / range * w - 0.5;
                    const int x0 = int(std::floor(t));
                    const double f = t - x0;
                    integral += ((1 - f) * v[size_t(std::clamp(x0, 0, w - 1))] + f * v[size_t(std::clamp(x0 + 1, 0, w - 1))]) *
                                2 * range / n;
                }
                worst = std::max(worst, std::fabs(integral - 1.0));
            }
    }
    EXPECT_LT(worst, 1e-3);

    const nlohmann::json manifest = nlohmann::json::parse(slurp(dir / "out" / "manifest.json"));
    const nlohmann::json& p = manifest["settings"]["glint_dictionary"];
    EXPECT_EQ(p["count"], 16);
    EXPECT_EQ(p["levels"], 8);
    EXPECT_EQ(p["width"], 64);
    EXPECT_EQ(p["seed"], 1);
    EXPECT_EQ(p["target"], "beckmann");
    EXPECT_NEAR(p["sigma_o"].get<double>(), sigma_o, 1e-12);
    EXPECT_NEAR(p["slope_range"][1].get<double>(), range, 1e-12);
    EXPECT_EQ(p["layout"]["layers"], 32);
    const nlohmann::json& out = manifest["outputs"][0];
    EXPECT_EQ(out["kind"], "glint_dictionary");
    EXPECT_EQ(out["mips"], 7);
    EXPECT_EQ(out["bytes"], b.size());
    EXPECT_EQ(out["sha256"].get<std::string>().size(), 64u);

    // Same bytes on a second run with one thread.
    const RunResult again =
        run_specbake({"-j", "1", "glints", "-o", (dir / "again").string(), "--count", "16", "--levels", "8"}, dir);
    ASSERT_EQ(again.exit_code, 0) << again.err;
    EXPECT_EQ(slurp(dir / "again" / "glint_dictionary.ktx2"), b);
    EXPECT_EQ(slurp(dir / "again" / "manifest.json"), slurp(dir / "out" / "manifest.json"));
    fs::remove_all(dir);
}

// inspect reads the dictionary's 2D array: layers, levels, format and per-level sizes as the command's
// parameters imply them (levels x count / 4 layers of (64 >> L) x 1 RGBA16F texels); inspect --check
// passes on the folder and fails, naming the layers, when the manifest's layer count is wrong.
TEST(GlintsCommand, InspectReadsTheArray) {
    const fs::path dir = temp_dir("glints_inspect");
    const fs::path out = dir / "out";
    ASSERT_EQ(run_specbake({"glints", "-o", out.string(), "--count", "16", "--levels", "8"}, dir).exit_code, 0);
    const RunResult r = run_specbake({"inspect", "--json", (out / "glint_dictionary.ktx2").string()}, dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    nlohmann::json j = nlohmann::json::parse(r.out);
    j = j["files"][0];
    EXPECT_EQ(j["format"], "ktx2");
    EXPECT_EQ(j["pixel_format"], "R16G16B16A16_SFLOAT");
    EXPECT_EQ(j["layers"], 8 * 16 / 4);
    EXPECT_EQ(j["width"], 64);
    EXPECT_EQ(j["height"], 1);
    ASSERT_EQ(j["mips"], 7);
    for (int L = 0; L < 7; ++L) {
        EXPECT_EQ(j["levels"][L]["width"], 64 >> L) << L;
        EXPECT_EQ(j["levels"][L]["bytes"], (64 >> L) * 32 * 8) << L;  // 32 layers, 4 halves per texel
    }
    const RunResult text = run_specbake({"inspect", (out / "glint_dictionary.ktx2").string()}, dir);
    EXPECT_NE(text.out.find("64x1 x 32 layers (2D array), 7 mips, 4 channels"), std::string::npos) << text.out;
    const RunResult check = run_specbake({"inspect", "--check", (out / "manifest.json").string()}, dir);
    EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
    nlohmann::json manifest = nlohmann::json::parse(slurp(out / "manifest.json"));
    manifest["outputs"][0]["layers"] = 31;
    std::ofstream(out / "manifest.json") << manifest.dump(2);
    const RunResult bad = run_specbake({"inspect", "--check", (out / "manifest.json").string()}, dir);
    EXPECT_NE(bad.exit_code, 0);
    EXPECT_NE((bad.out + bad.err).find("32 layers, the manifest entry says 31"), std::string::npos) << bad.out << bad.err;
    fs::remove_all(dir);
}

TEST(GlintsCommand, BadParametersFailWithOneLine) {
    const fs::path dir = temp_dir("glints_bad");
    const RunResult r = run_specbake({"glints", "-o", (dir / "out").string(), "--count", "6"}, dir);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("count 6 must be a multiple of 4"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1);
    EXPECT_FALSE(fs::exists(dir / "out" / "glint_dictionary.ktx2"));
    const RunResult missing = run_specbake({"glints"}, dir);
    EXPECT_EQ(missing.exit_code, 2);
    fs::remove_all(dir);
}

}  // namespace
