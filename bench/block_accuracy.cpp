// Block compression against the uncompressed bake (issue 16, item 3): the shared NormalTangentTest normal
// and ORM maps baked once, every level of the 8-bit outputs compressed by io/block_compress and decoded by
// the spec-written decoder of tests/io/bc_decode.h (ASTC: compressed and decoded by astcenc,
// io/texture/astc_codec.h). Prints, per format: roughness error in r units (RMS and
// max, worst level and level 0), mean-normal angle error (BC5, z rebuilt from x, y), size against the
// uncompressed level data (and both after zstd -3), encode throughput.
// Run: build/bench/block_accuracy [normal.png orm.png]
#include "bake/texture_bake.h"
#include "io/texture/astc_codec.h"
#include "io/texture/block_compress.h"
#include "io/image/image_io.h"
#include "tests/io/bc_decode.h"

#include <zstd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {
using namespace specbake;

std::vector<uint8_t> to8(const Image& level, int stored) {
    std::vector<uint8_t> out(level.texel_count() * size_t(stored));
    for (size_t i = 0; i < level.texel_count(); ++i)
        for (int c = 0; c < stored; ++c)
            out[i * size_t(stored) + size_t(c)] =
                c < level.channels ? uint8_t(std::lround(std::clamp(level.pixels[i * size_t(level.channels) + size_t(c)], 0.0f, 1.0f) * 255.0f)) : 255;
    return out;
}

size_t zstd_size(const std::vector<uint8_t>& b) {
    std::vector<uint8_t> out(ZSTD_compressBound(b.size()));
    return ZSTD_compress(out.data(), out.size(), b.data(), b.size(), 3);
}

struct Row {
    std::string name;
    double rms0 = 0, max0 = 0, rms_worst = 0, max_worst = 0, angle_mean0 = 0, angle_max = 0;
    size_t raw = 0, packed = 0, raw_z = 0, packed_z = 0;
    double seconds = 0, texels = 0;
};

// `channel` of `stored`-channel 8-bit levels vs the decoded blocks (roughness rows), or the normal angle.
Row measure(const std::string& name, io::BlockFormat format, const MipChain& chain, int stored, int channel, bool normal,
            int astc_side = 4) {
    Row row;
    row.name = name;
    for (size_t L = 0; L < chain.levels.size(); ++L) {
        const Image& level = chain.levels[L];
        const std::vector<uint8_t> ref = to8(level, stored);
        const auto t0 = std::chrono::steady_clock::now();
        std::vector<uint8_t> blocks;
        if (io::is_astc(format)) {
            auto b = io::astc_compress_level(ref.data(), level.width, level.height, stored, io::block_channels(format),
                                             astc_side);
            if (!b) {
                std::fprintf(stderr, "%s\n", b.error().message.c_str());
                std::exit(1);
            }
            blocks = std::move(*b);
        } else {
            blocks = io::compress_level(format, ref.data(), level.width, level.height, stored);
        }
        row.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        row.texels += double(level.texel_count());
        row.raw += ref.size(), row.packed += blocks.size();
        row.raw_z += zstd_size(ref), row.packed_z += zstd_size(blocks);
        int n = 0;
        std::vector<float> dec;
        if (io::is_astc(format)) {
            auto rgba = io::astc_decompress_level(blocks, level.width, level.height, astc_side);
            if (!rgba) {
                std::fprintf(stderr, "%s\n", rgba.error().message.c_str());
                std::exit(1);
            }
            n = 4;
            for (uint8_t v : *rgba) dec.push_back(float(v) / 255.0f);
        } else {
            dec = bc_test::decode_level(io::block_format_name(format), blocks.data(), level.width, level.height, &n);
        }
        double sum = 0, worst = 0, angle_sum = 0;
        for (size_t i = 0; i < level.texel_count(); ++i) {
            if (normal) {
                double a[3], b[3];
                for (int c = 0; c < 3; ++c) a[c] = ref[i * size_t(stored) + size_t(c)] / 127.5 - 1.0;
                b[0] = dec[i * size_t(n)] * 2.0 - 1.0, b[1] = dec[i * size_t(n) + 1] * 2.0 - 1.0;
                b[2] = std::sqrt(std::max(0.0, 1.0 - b[0] * b[0] - b[1] * b[1]));
                const double la = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]), lb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
                const double cosine = std::clamp((a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (la * lb), -1.0, 1.0);
                const double deg = std::acos(cosine) * 180.0 / M_PI;
                angle_sum += deg, row.angle_max = std::max(row.angle_max, deg);
                continue;
            }
            const double d = dec[i * size_t(n) + size_t(channel)] - ref[i * size_t(stored) + size_t(channel)] / 255.0;
            sum += d * d, worst = std::max(worst, std::fabs(d));
        }
        const double rms = std::sqrt(sum / double(level.texel_count()));
        if (L == 0) row.rms0 = rms, row.max0 = worst, row.angle_mean0 = angle_sum / double(level.texel_count());
        row.rms_worst = std::max(row.rms_worst, rms), row.max_worst = std::max(row.max_worst, worst);
    }
    return row;
}

}  // namespace

int main(int argc, char** argv) {
    const std::string dir = std::string(SPECBAKE_ASSETS_DIR) + "/gltf/NormalTangentTest/";
    const std::string normal_path = argc > 2 ? argv[1] : dir + "NormalTangentTest_Normal.png";
    const std::string orm_path = argc > 2 ? argv[2] : dir + "NormalTangentTest_OcclusionRoughnessMetallic.png";
    auto n = io::decode_image(normal_path);
    auto m = io::decode_image(orm_path);
    if (!n || !m) {
        std::fprintf(stderr, "%s\n", (!n ? n.error() : m.error()).message.c_str());
        return 1;
    }
    TextureBakeSettings s;
    s.outputs.kernel = s.outputs.lean = false;
    auto orm = bake_texture(n->image, &m->image, 1, 0.0f, s);
    auto alone = bake_texture(n->image, nullptr, -1, 0.5f, s);  // one-channel roughness (constant input 0.5)
    if (!orm || !alone) {
        std::fprintf(stderr, "bake failed\n");
        return 1;
    }
    std::vector<Row> rows;
    rows.push_back(measure("BC4 roughness (R8, normal map only)", io::BlockFormat::Bc4, alone->roughness, 1, 0, false));
    rows.push_back(measure("BC1 ORM roughness (RGBA8, r in G)", io::BlockFormat::Bc1, orm->roughness, 4, 1, false));
    rows.push_back(measure("BC3 ORM roughness (RGBA8, r in G)", io::BlockFormat::Bc3, orm->roughness, 4, 1, false));
    rows.push_back(measure("BC5 mean normal (x, y of RGBA8)", io::BlockFormat::Bc5, orm->normal, 4, 0, true));
    for (int side : {4, 6, 8}) {
        const std::string a = "ASTC " + std::to_string(side) + "x" + std::to_string(side);
        rows.push_back(measure(a + " roughness (R8, normal map only)", io::BlockFormat::AstcR, alone->roughness, 1, 0,
                               false, side));
        rows.push_back(measure(a + " ORM roughness (RGBA8, r in G)", io::BlockFormat::AstcRgba, orm->roughness, 4, 1,
                               false, side));
        rows.push_back(measure(a + " mean normal (x, y of RGBA8)", io::BlockFormat::AstcRg, orm->normal, 4, 0, true, side));
    }
    std::printf("%dx%d %s + %s, %zu levels\n\n", n->image.width, n->image.height, normal_path.c_str(), orm_path.c_str(),
                orm->roughness.levels.size());
    std::printf("| format | r error level 0 RMS / max | r error worst level RMS / max | normal angle level 0 mean / all max | "
                "size vs uncompressed | both after zstd -3 | encode Mtexel/s |\n|---|---|---|---|---|---|---|\n");
    for (const Row& r : rows) {
        const bool normal = r.name.find("normal (") != std::string::npos;
        std::printf("| %s | %s | %s | %s | %.3f | %.2f MB vs %.2f MB | %.1f |\n", r.name.c_str(),
                    normal ? "-" : (std::to_string(r.rms0).substr(0, 7) + " / " + std::to_string(r.max0).substr(0, 7)).c_str(),
                    normal ? "-" : (std::to_string(r.rms_worst).substr(0, 7) + " / " + std::to_string(r.max_worst).substr(0, 7)).c_str(),
                    normal ? (std::to_string(r.angle_mean0).substr(0, 5) + " / " + std::to_string(r.angle_max).substr(0, 5) + " deg").c_str() : "-",
                    double(r.packed) / double(r.raw), r.packed_z / 1e6, r.raw_z / 1e6, r.texels / r.seconds * 1e-6);
    }
    return 0;
}
