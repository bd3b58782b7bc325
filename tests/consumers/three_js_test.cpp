// three.js r187 in headless Chromium (WebGL 2, SwiftShader) on `specbake texture` outputs: KTX2Loader (zstd
// and plain), DDSLoader, EXRLoader and TextureLoader (PNG per mip) must load every file whose format the
// loader implements with the right size and level count, and texels read back from the GPU texture at
// several mips (textureLod into an RGBA32F target) must match the library's bake of the same inputs
// within the stored format's tolerance. Block-compressed outputs (`--block bc`, KTX2 and DDS) are checked
// against their own blocks decoded by the spec-written decoder of tests/io/bc_decode.h; ASTC outputs
// (`--block astc`, KTX2) against their blocks decoded by astcenc, which the GPU's own ASTC decoder must
// reproduce. Files a loader does
// not implement are reported, with its reason, in the results table (consumer_results.md in the test's
// working folder, and stdout).
#include "consumer_harness.h"
#include "three_js_support.h"
#include "tests/io/bc_decode.h"

#include "bake/texture_bake.h"
#include "io/texture/astc_codec.h"
#include "io/image/image_io.h"

#include <array>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <vector>

#include <zstd.h>

namespace specbake::consumers {
namespace {

// The block format of a `--block bc` or `--block astc` output from its manifest entry: "bc1" .. "bc5",
// "astc4", "astc6", "astc8" ("" when not block-compressed).
std::string block_format_of(const nlohmann::json& o) {
    const std::string g = o.value("gpu_format", "");
    if (g.rfind("ASTC_", 0) == 0 && g.size() > 5) return "astc" + g.substr(5, 1);
    if (g.rfind("BC1", 0) == 0) return "bc1";
    if (g.rfind("BC3", 0) == 0) return "bc3";
    if (g.rfind("BC4", 0) == 0) return "bc4";
    if (g.rfind("BC5", 0) == 0) return "bc5";
    return "";
}

// The blocks of every level of a block-compressed KTX2 (KTX 2.0 Sec. 3.9, zstd levels inflated) or legacy
// FourCC DDS file, level 0 first, read from the file alone.
std::vector<std::string> block_levels(const std::string& b, const std::string& format, int width, int height,
                                      int levels) {
    const size_t block = format == "bc1" || format == "bc4" ? 8 : 16;
    const size_t side = format.rfind("astc", 0) == 0 ? size_t(format[4] - '0') : 4;
    auto bytes_of = [&](int L) {
        const size_t w = size_t(std::max(1, width >> L)), h = size_t(std::max(1, height >> L));
        return (w + side - 1) / side * ((h + side - 1) / side) * block;
    };
    std::vector<std::string> out;
    if (b.compare(0, 4, "DDS ") == 0) {
        size_t at = 128;
        for (int L = 0; L < levels; ++L) out.push_back(b.substr(at, bytes_of(L))), at += bytes_of(L);
        return out;
    }
    const bool zstd = le32(b, 44) == 2;
    for (int L = 0; L < levels; ++L) {
        uint64_t offset = 0, length = 0;
        std::memcpy(&offset, b.data() + 80 + 24 * L, 8);
        std::memcpy(&length, b.data() + 80 + 24 * L + 8, 8);
        std::string level = b.substr(size_t(offset), size_t(length));
        if (zstd) {
            std::string raw(bytes_of(L), '\0');
            const size_t n = ZSTD_decompress(raw.data(), raw.size(), level.data(), level.size());
            EXPECT_FALSE(ZSTD_isError(n)) << "level " << L;
            level = raw;
        }
        EXPECT_EQ(level.size(), bytes_of(L)) << "level " << L;
        out.push_back(level);
    }
    return out;
}

struct FileCheck {
    std::string id;           // path relative to the data folder
    std::string loader;
    std::string row;          // results-table row: container, kind, format
    std::string encoding;     // manifest "encoding"
    int width = 0, height = 0, mips = 0, channels = 0;
    int mip_level = -1;       // one-file-per-mip outputs: the level this file holds
    Support support;
    std::string stem;         // output stem without _mipN ("texture_roughness")
    const TextureBakeResult* reference = nullptr;
    std::vector<Sample> samples;
    // Block-compressed files: every level decoded from the file's blocks (tests/io/bc_decode.h), the texels
    // the GPU must return; `decoded_channels` values per texel.
    std::string block;
    std::vector<std::vector<float>> decoded;
    int decoded_channels = 0;
};

struct Container {
    const char* label;
    const char* args;
};
const Container kContainers[] = {{"KTX2 (zstd)", "--format ktx2"},
                                 {"KTX2 (none)", "--format ktx2 --supercompression none"},
                                 {"DDS", "--format dds"},
                                 {"EXR", "--format exr"},
                                 {"PNG/EXR per mip", "--format png"}};

struct BakeCase {
    std::string name;       // folder name
    std::string args;       // `specbake texture` arguments before --format / -o
    std::unique_ptr<TextureBakeResult> reference;
    bool block = false;     // `--block bc`: KTX2 and DDS only (the containers that hold blocks)
    bool ktx2_only = false; // `--block astc`: KTX2 only
};

const char* loader_for(const std::string& ext) {
    if (ext == ".ktx2") return "KTX2Loader";
    if (ext == ".dds") return "DDSLoader";
    if (ext == ".exr") return "EXRLoader";
    return "TextureLoader";
}

class ThreeJs : public ConsumerTest {
protected:
    // Bakes `c` in every container into data/<case>/<container>, and lists its files.
    void add_case(BakeCase& c, const fs::path& data, std::vector<FileCheck>& checks) {
        for (size_t k = 0; k < std::size(kContainers); ++k) {
            if (c.block && std::string(kContainers[k].args).find("exr") != std::string::npos) continue;
            if (c.block && std::string(kContainers[k].args).find("png") != std::string::npos) continue;
            if (c.ktx2_only && std::string(kContainers[k].args).find("ktx2") == std::string::npos) continue;
            const std::string folder = c.name + "/" + std::to_string(k);
            const fs::path out = data / folder;
            specbake("texture -q " + c.args + " " + kContainers[k].args + " -o " + quote(out));
            const nlohmann::json manifest = nlohmann::json::parse(slurp(out / "manifest.json"));
            for (const auto& o : manifest["outputs"]) {
                const std::string path = o["path"];
                const std::string ext = fs::path(path).extension().string();
                if (ext != ".ktx2" && ext != ".dds" && ext != ".exr" && ext != ".png") continue;
                FileCheck f;
                f.id = folder + "/" + path;
                f.loader = loader_for(ext);
                f.encoding = o.value("encoding", "");
                f.width = o["width"];
                f.height = o["height"];
                f.mips = o["mips"];
                f.channels = o["channels"];
                f.mip_level = o.value("mip_level", -1);
                f.stem = fs::path(path).stem().string();
                if (f.mip_level >= 0) f.stem = f.stem.substr(0, f.stem.rfind("_mip"));
                const std::string kind = f.stem.substr(f.stem.find('_') + 1);
                f.row = std::string(kContainers[k].label) + " | " + kind + " | " + o.value("gpu_format", "?");
                f.support = loader_supports(f.loader, slurp(out / path));
                f.reference = c.reference.get();
                f.block = block_format_of(o);
                if (!f.block.empty()) {
                    for (const std::string& level : block_levels(slurp(out / path), f.block, f.width, f.height, f.mips)) {
                        const int L = int(f.decoded.size());
                        const int lw = std::max(1, f.width >> L), lh = std::max(1, f.height >> L);
                        const auto* blocks = reinterpret_cast<const uint8_t*>(level.data());
                        if (f.block.rfind("astc", 0) == 0) {
                            auto rgba = io::astc_decompress_level({blocks, level.size()}, lw, lh, f.block[4] - '0');
                            ASSERT_TRUE(rgba.ok()) << f.id << ": " << (rgba.ok() ? "" : rgba.error().message);
                            f.decoded.emplace_back(rgba->begin(), rgba->end());
                            for (float& v : f.decoded.back()) v /= 255.0f;
                            f.decoded_channels = 4;
                        } else {
                            f.decoded.push_back(bc_test::decode_level(f.block, blocks, lw, lh, &f.decoded_channels));
                        }
                    }
                }
                if (f.mip_level >= 0) {
                    // One file per mip: the file's level 0 against the reference's level mip_level.
                    const int lw = f.width, lh = f.height;
                    for (Sample s : pick_samples(lw, lh, 1, false)) {
                        s.level = f.mip_level;
                        if (f.loader == "EXRLoader") s.read_y = lh - 1 - s.y;
                        f.samples.push_back(s);
                    }
                } else {
                    // EXRLoader reads level 0 only and returns it bottom-up.
                    const bool exr = f.loader == "EXRLoader";
                    for (Sample s : pick_samples(f.width, f.height, f.mips, !exr)) {
                        if (exr) s.read_y = f.height - 1 - s.y;
                        f.samples.push_back(s);
                    }
                }
                checks.push_back(std::move(f));
            }
        }
    }
};

std::string fmt(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.6g", v);
    return b;
}

TEST_F(ThreeJs, LoadersDecodeEveryTextureOutputWithItsMipsAndTexels) {
    if (const std::string why = missing_node_packages({"three"}); !why.empty()) GTEST_SKIP() << why;
    if (!have("chromium") && !have("chromium-browser") && !have("google-chrome"))
        GTEST_SKIP() << "no Chromium installed (Debian package chromium; .ci/setup installs it)";

    // Inputs the test makes: the built-in demo maps (ORM roughness, 512x384), the demo normal map as an 8-
    // and a 16-bit PNG with constant roughness (R8 / R16 roughness, the isotropic R16F kernel, slope-space LEAN;
    // the other bakes write the default Sigma kernel).
    const fs::path in = root_ / "inputs";
    fs::create_directories(in);
    const Image demo_normal = demo_normal_map(), demo_orm = demo_orm_map();
    ASSERT_TRUE(io::write_image(in / "normal8.png", demo_normal, 8).ok());
    ASSERT_TRUE(io::write_image(in / "normal16.png", demo_normal, 16).ok());
    auto bake = [](const Image& normal, const Image* rough, float value, const TextureBakeSettings& s) {
        auto r = bake_texture(normal, rough, 1, value, s);
        EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
        return std::make_unique<TextureBakeResult>(r.ok() ? std::move(*r) : TextureBakeResult{});
    };
    std::vector<BakeCase> cases;
    cases.push_back({"demo_orm", "--demo", bake(demo_normal, &demo_orm, 0.5f, {})});
    // Block compression: BC1 (and BC3) ORM roughness and BC5 normal of the demo, BC4 of a one-channel roughness.
    // The float outputs of these bakes stay float and are checked against the reference bake.
    cases.push_back({"demo_bc", "--demo --block bc", bake(demo_normal, &demo_orm, 0.5f, {}), true});
    cases.push_back({"demo_bc3", "--demo --block bc --block-rgba bc3", bake(demo_normal, &demo_orm, 0.5f, {}), true});
    // ASTC (KTX2 only; the DDS container is skipped for these): 4x4 of the demo, 6x6 of a one-channel
    // roughness, 8x8 (which KTX2Loader r187 does not map: reported, not failed).
    cases.push_back({"demo_astc", "--demo --block astc", bake(demo_normal, &demo_orm, 0.5f, {}), true, true});
    cases.push_back({"demo_astc8", "--demo --block astc --astc-block 8x8", bake(demo_normal, &demo_orm, 0.5f, {}), true,
                     true});
    {
        TextureBakeSettings s;
        s.anisotropic = false;
        s.lean_space = LeanSpace::Slope;
        auto n8 = io::read_image(in / "normal8.png");
        ASSERT_TRUE(n8.ok());
        cases.push_back({"iso_slope", "--normal " + quote(in / "normal8.png") +
                                          " --roughness-value 0.3 --isotropic-kernel --lean-space slope",
                         bake(*n8, nullptr, 0.3f, s)});
        cases.push_back({"normal_bc", "--normal " + quote(in / "normal8.png") + " --roughness-value 0.3 --block bc",
                         bake(*n8, nullptr, 0.3f, {}), true});
        cases.push_back({"normal_astc6", "--normal " + quote(in / "normal8.png") +
                                             " --roughness-value 0.3 --block astc --astc-block 6x6",
                         bake(*n8, nullptr, 0.3f, {}), true, true});
        auto n16 = io::read_image(in / "normal16.png");
        ASSERT_TRUE(n16.ok());
        // 16-bit input: half-float roughness and normal (R16_SFLOAT, RGBA16F), 16-bit UNORM PNGs per mip.
        cases.push_back({"input16", "--normal " + quote(in / "normal16.png") + " --roughness-value 0.3",
                         bake(*n16, nullptr, 0.3f, {})});
    }
    // The shared normal maps, where present.
    const fs::path maps = fs::path(SPECBAKE_ASSETS_DIR) / "normalmaps";
    if (fs::exists(maps)) {
        std::vector<fs::path> files;
        for (const auto& e : fs::recursive_directory_iterator(maps))
            if (e.path().extension() == ".png" || e.path().extension() == ".jpg") files.push_back(e.path());
        std::sort(files.begin(), files.end());
        for (const fs::path& p : files) {
            auto img = io::read_image(p);
            ASSERT_TRUE(img.ok()) << p;
            cases.push_back({"shared_" + p.stem().string(), "--normal " + quote(p), bake(*img, nullptr, 0.5f, {})});
        }
    } else {
        std::printf("note: %s is absent; the shared normal maps are not baked\n", maps.c_str());
    }

    const fs::path data = root_ / "data";
    std::vector<FileCheck> checks;
    for (BakeCase& c : cases) add_case(c, data, checks);
    ASSERT_FALSE(::testing::Test::HasFatalFailure());

    nlohmann::json job = {{"entries", nlohmann::json::array()}};
    for (const FileCheck& f : checks) {
        nlohmann::json samples = nlohmann::json::array();
        for (const Sample& s : f.samples) samples.push_back({{"level", s.read_level}, {"x", s.x}, {"y", s.read_y}});
        job["entries"].push_back({{"id", f.id}, {"path", f.id}, {"loader", f.loader}, {"samples", samples}});
    }
    nlohmann::json result;
    if (!run_browser(job, data, &result)) return;
    std::printf("three.js r%s on %s, %s\n", result.value("three", "?").c_str(), result.value("webgl", "?").c_str(),
                result.value("renderer", "?").c_str());
    // WebGL 2 samples 16-bit unorm textures only through EXT_texture_norm16, which Chromium does not offer
    // on every backend (SwiftShader has none).
    bool norm16 = false;
    for (const auto& e : result.value("extensions", nlohmann::json::array())) norm16 |= e == "EXT_texture_norm16";
    for (FileCheck& f : checks)
        if (!norm16 && f.loader == "KTX2Loader" && f.encoding == "unorm16" && f.support.supported)
            f.support = {false, "this WebGL 2 has no EXT_texture_norm16"};
    std::map<std::string, const nlohmann::json*> by_id;
    for (const auto& r : result["results"]) by_id[r["id"]] = &r;

    struct Cell { int files = 0, loaded = 0, rejected_unsupported = 0, all_levels = 0, texels_ok = 0, texels_checked = 0;
                  int levels_seen = 0, levels_want = 0; double worst = 0; std::set<std::string> reasons; };
    std::map<std::pair<std::string, std::string>, Cell> table;  // (row, loader)
    for (const FileCheck& f : checks) {
        SCOPED_TRACE(f.id + " (" + f.loader + ")");
        Cell& cell = table[{f.row, f.loader}];
        ++cell.files;
        ASSERT_TRUE(by_id.count(f.id)) << "no result for " << f.id;
        const nlohmann::json& r = *by_id[f.id];
        if (!r["ok"].get<bool>()) {
            const std::string why = r.value("error", "");
            if (!f.support.supported) {
                ++cell.rejected_unsupported;
                cell.reasons.insert(f.support.reason);
                continue;
            }
            ADD_FAILURE() << f.loader << " rejected " << f.id << " (" << f.row << "): " << why;
            continue;
        }
        ++cell.loaded;
        EXPECT_EQ(r["width"], f.width) << f.id;
        EXPECT_EQ(r["height"], f.height) << f.id;
        const int levels = r["levels"];
        const int want_levels = f.mip_level >= 0 ? 1 : f.loader == "EXRLoader" ? 1 : f.mips;
        EXPECT_EQ(levels, want_levels) << f.id << ": level count";
        cell.levels_seen = levels;
        cell.levels_want = f.mip_level >= 0 ? f.mips : f.mips;
        if (f.mip_level >= 0 || levels == f.mips) ++cell.all_levels;
        // docs/consumers.md#filtering-in-threejs: KTX2Loader hands out uncompressed textures with nearest
        // filtering, block-compressed ones with trilinear filtering.
        if (f.loader == "KTX2Loader")
            EXPECT_NE(r.value("minFilter", "").find(f.block.empty() ? "Nearest" : "LinearMip"), std::string::npos)
                << f.id << ": KTX2Loader's minFilter is now " << r.value("minFilter", "")
                << "; update docs/consumers.md#filtering-in-threejs";
        const auto& values = r["values"];
        ASSERT_EQ(values.size(), f.samples.size()) << f.id;
        bool all = true;
        for (size_t i = 0; i < f.samples.size(); ++i) {
            const Sample& s = f.samples[i];
            if (values[i].is_null()) {
                ADD_FAILURE() << f.id << ": level " << s.read_level << " was not read back";
                all = false;
                continue;
            }
            for (int c = 0; c < f.channels; ++c) {
                // Block-compressed: the file's own blocks as decoded from the specification; the GPU's
                // decoder may round the interpolated palette entries to 8 bits (and BC1's RGB565 endpoints
                // widen by bit replication rather than by value), so one step of 8 bits is allowed.
                const bool blocks = !f.block.empty();
                const double want =
                    blocks ? f.decoded[size_t(s.level)][(size_t(s.y) * size_t(std::max(1, f.width >> s.level)) + size_t(s.x)) *
                                                            size_t(f.decoded_channels) + size_t(c)]
                           : reference_value(*f.reference, f.stem, s.level, s.x, s.y, c);
                const double got = values[i][size_t(c)].get<double>();
                // Browsers decode 16-bit PNG to 8 bits.
                const std::string enc = f.loader == "TextureLoader" && f.encoding == "unorm16" ? "unorm8" : f.encoding;
                const double tol = blocks ? 1.0 / 255 + 1e-6 : tolerance(enc, want) + (enc != f.encoding ? 0.5 / 255 : 0.0);
                cell.worst = std::max(cell.worst, std::abs(got - want) / tol);
                if (std::abs(got - want) > tol) {
                    all = false;
                    ADD_FAILURE() << f.id << " (" << f.loader << "): level " << s.level << " texel (" << s.x << ", "
                                  << s.y << ") channel " << c << ": GPU read-back " << fmt(got) << ", specbake "
                                  << fmt(want) << " (tolerance " << fmt(tol) << ")";
                }
            }
        }
        ++cell.texels_checked;
        if (all) ++cell.texels_ok;
    }

    // The table of docs/consumers.md#results-per-loader.
    std::string md = "| container | kind | stored format | consumer | loads | levels | texels match |\n"
                     "|---|---|---|---|---|---|---|\n";
    for (const auto& [key, cell] : table) {
        std::string loads = cell.loaded == cell.files ? "yes" : cell.loaded == 0 ? "no" : std::to_string(cell.loaded) + "/" + std::to_string(cell.files);
        for (const std::string& reason : cell.reasons)
            if (cell.loaded < cell.files) loads += " (" + reason + ")";
        std::string levels = cell.loaded == 0 ? "-" : key.first.rfind("PNG", 0) == 0 ? "all (one file each)"
                             : cell.all_levels == cell.loaded ? "all" : std::to_string(cell.levels_seen) + " of " + std::to_string(cell.levels_want);
        if (cell.loaded > 0 && key.second == "EXRLoader" && key.first.rfind("PNG", 0) != 0)
            levels += " (EXRLoader reads level 0 only)";
        const std::string texels = cell.texels_checked == 0 ? "-" : cell.texels_ok == cell.texels_checked ? "yes" : "NO";
        md += "| " + key.first + " | " + key.second + " | " + loads + " | " + levels + " | " + texels + " |\n";
    }
    std::printf("%s", md.c_str());
    std::ofstream("consumer_results.md") << md;
}

}  // namespace
}  // namespace specbake::consumers
