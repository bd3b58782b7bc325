// The deflate level of EXR ZIP chunks (io/image/exr_encode.h): every level of the given EXR files (a
// texture bake's outputs) cut into the chunks a mipmapped file of 64x64 tiles and a per-mip file of 16-row
// blocks hold, run through the ZIP predictor, then deflated by libdeflate at levels 1, 2, 4, 6, 9 and by zlib
// at levels 1 and 6 (its default, which OpenEXR's own writer uses). Prints, per compressor and level, the
// compressed size against the raw texels and the deflate CPU time (one thread, the best of `repeats`).
// Run: build/bench/exr_deflate [--repeats N] a.exr b.exr ...
#include "io/image/exr_encode.h"
#include "io/image/oiio_api.h"
#include "io/texture/texel_encoding.h"

#include <libdeflate.h>
#include <sys/resource.h>
#include <zlib.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {
using namespace specbake;

double process_cpu_seconds() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// The chunks of one level (`texels`: half samples, `channels` interleaved), each laid out as OpenEXR stores
// it (a line's samples channel by channel) and predicted; `tile` 0: 16-row scanline blocks.
void add_chunks(const std::vector<uint8_t>& texels, int width, int height, int channels, int tile,
                std::vector<std::vector<uint8_t>>& chunks) {
    const int rows = tile ? tile : 16, cols = tile ? tile : width;
    for (int y0 = 0; y0 < height; y0 += rows)
        for (int x0 = 0; x0 < width; x0 += cols) {
            std::vector<uint8_t> raw;
            for (int y = y0; y < std::min(height, y0 + rows); ++y)
                for (int c = 0; c < channels; ++c)
                    for (int x = x0; x < std::min(width, x0 + cols); ++x) {
                        const size_t at = (size_t(y) * size_t(width) + size_t(x)) * size_t(channels) + size_t(c);
                        raw.push_back(texels[2 * at]), raw.push_back(texels[2 * at + 1]);
                    }
            std::vector<uint8_t> predicted(raw.size());
            io::exr_zip_predict(raw.data(), raw.size(), predicted.data());
            chunks.push_back(std::move(predicted));
        }
}

}  // namespace

int main(int argc, char** argv) {
    int repeats = 3;
    std::vector<std::string> files;
    for (int k = 1; k < argc; ++k) {
        if (std::strcmp(argv[k], "--repeats") == 0 && k + 1 < argc) repeats = std::max(1, std::atoi(argv[++k]));
        else files.emplace_back(argv[k]);
    }
    if (files.empty()) {
        std::fprintf(stderr, "usage: exr_deflate [--repeats N] a.exr b.exr ...\n");
        return 2;
    }
    auto oiio = io::oiio::api();
    if (!oiio) {
        std::fprintf(stderr, "exr_deflate: %s\n", oiio.error().message.c_str());
        return 1;
    }
    for (const int tile : {64, 0}) {
        std::vector<std::vector<uint8_t>> chunks;
        size_t raw_bytes = 0;
        for (const std::string& name : files) {
            auto t = (*oiio)->read_levels(name, uint64_t(1) << 30);
            if (!t) {
                std::fprintf(stderr, "exr_deflate: %s\n", t.error().message.c_str());
                return 1;
            }
            for (const Image& level : t->mips.levels) {
                const std::vector<uint8_t> half = io::encode_texels(level, io::TexelEncoding::Float16, level.channels);
                raw_bytes += half.size();
                add_chunks(half, level.width, level.height, level.channels, tile, chunks);
            }
        }
        std::printf("%s chunks: %zu, raw %.1f MiB\n", tile ? "64x64 tile" : "16-row scanline", chunks.size(),
                    double(raw_bytes) / (1024.0 * 1024.0));
        std::printf("  compressor  level   size/raw   CPU s   MB/s\n");
        struct Run { const char* name; int level; };
        for (const Run run : {Run{"libdeflate", 1}, Run{"libdeflate", 2}, Run{"libdeflate", 4}, Run{"libdeflate", 6},
                              Run{"libdeflate", 9}, Run{"zlib", 1}, Run{"zlib", 6}}) {
            const bool zlib = run.name[0] == 'z';
            double best = 1e30;
            size_t packed = 0;
            for (int r = 0; r < repeats; ++r) {
                packed = 0;
                libdeflate_compressor* deflater = zlib ? nullptr : libdeflate_alloc_compressor(run.level);
                std::vector<uint8_t> out;
                const double c0 = process_cpu_seconds();
                for (const std::vector<uint8_t>& chunk : chunks) {
                    size_t size;
                    if (zlib) {
                        uLongf n = compressBound(uLong(chunk.size()));
                        out.resize(n);
                        compress2(out.data(), &n, chunk.data(), uLong(chunk.size()), run.level);
                        size = n;
                    } else {
                        out.resize(libdeflate_zlib_compress_bound(deflater, chunk.size()));
                        size = libdeflate_zlib_compress(deflater, chunk.data(), chunk.size(), out.data(), out.size());
                    }
                    packed += std::min(size, chunk.size());  // a chunk that does not shrink is stored raw
                }
                best = std::min(best, process_cpu_seconds() - c0);
                libdeflate_free_compressor(deflater);
            }
            std::printf("  %-10s  %5d   %8.4f   %5.2f   %4.0f\n", run.name, run.level, double(packed) / double(raw_bytes),
                        best, double(raw_bytes) / best / 1e6);
        }
    }
    return 0;
}
