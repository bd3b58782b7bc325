// Speed of the texture bake (issue 3, item 8) on a 4096 x 4096 RGB8 normal map plus an RGB8 ORM map,
// all default outputs, against the issue's goals:
//  (a) compute-only throughput in Mtexel/s of the base map on 1 and 2 threads (goal: >= 200 on 2):
//      `encoded` is what the texture job computes (bake_texture_encoded: the bake with every row encoded
//      into the in-memory KTX2 files, whose fresh pages the kernel zeroes), `values` is the bake alone
//      (bake_texture_rows with a sink that keeps nothing: every output value of every level computed,
//      nothing encoded or stored), `float chains` is the library call bake_texture() that returns float32
//      mip chains (about 1 GiB of fresh memory at 4096^2, so it is bound by memory traffic);
// (--end-to-end-only skips (a); --keep DIR leaves the inputs and outputs in DIR.)
//  (b) end-to-end wall and CPU time of the texture job (PNG decode, bake, KTX2 writes, hashes, manifest) in
//      a child process, timed from outside like the oiiotool commands, against the I/O floor measured in the
//      same run: oiiotool decoding and re-encoding
//      the same two PNGs (oiiotool's own defaults: PNG output at zlib level 6), one after the other as
//      two commands, and both at once (the job decodes its two inputs side by side) (goal: <= 1.0x, issue 16);
//  (c) peak resident memory of that child (getrusage) over the decoded inputs (8-bit) plus the outputs
//      written (goal: <= 1.5x, issue 16), and of one oiiotool run for comparison;
//  (d) the floor of each output container, in the same run, from 8-bit and from 16-bit PNG inputs: the
//      texture job (a child, as in (b)) writing the roughness and mean-normal outputs as KTX2 (zstd level 3),
//      DDS (uncompressed), EXR (tiled mipmapped half, zip) and per-mip PNG (filter Up, zlib level 2),
//      against (1) decoding its two inputs with the fastest decoder here (io/image/png_decode: libdeflate
//      inflate; 8-bit kept as bytes, 16-bit as uint16, as the job keeps them) and (2) that plus compressing
//      the same raw output levels with the same codec and level, in this process (one thread; EXR: the
//      tree's encoder, io/image/exr_encode.h, on the unorm levels as half, untimed conversion); CPU seconds,
//      and peak RSS against decoded inputs + written files.
//
// Run: build/bench/bench_texture [--size N] [--compute-only] [--floor-only] [google-benchmark flags]
// (--compute-only skips (b), (c) and (d), which take about 15 s at 4096^2; --floor-only runs (d) alone;
// `--floor-only --size 1024` is the quick form.)
#include "pipeline/texture_job.h"
#include "io/image/image_io.h"
#include "io/image/exr_encode.h"
#include "io/texture/png_stream.h"
#include "io/texture/texel_encoding.h"

#include <benchmark/benchmark.h>
#include <zstd.h>

#include <sys/resource.h>
#include <tbb/task_arena.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <vector>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

namespace {
using namespace specbake;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

float q8(double v) { return float(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)) / 255.0f; }
float q16(double v) { return float(std::lround(std::clamp(v, 0.0, 1.0) * 65535.0)) / 65535.0f; }

uint32_t hash(uint32_t x, uint32_t y) {
    uint32_t h = x * 0x8da6b343u ^ y * 0xd8163841u;
    h ^= h >> 15;
    h *= 0x2c1b3c6du;
    h ^= h >> 12;
    return h;
}

// Bumps at three scales plus per-texel noise, quantised to `bits` (8 or 16).
Image make_normal(int size, int bits = 8) {
    const auto q = bits == 16 ? q16 : q8;
    Image n(size, size, 3);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            double gx = 0, gy = 0;
            for (double period : {256.0, 37.0, 7.0}) {
                const double k = 2 * M_PI / period, a = 0.4;
                gx += a * std::cos(k * x) * std::sin(k * y);
                gy += a * std::sin(k * x) * std::cos(k * y);
            }
            gx += 0.2 * (double(hash(uint32_t(x), uint32_t(y)) & 1023) / 1023.0 - 0.5);
            const double len = std::sqrt(gx * gx + gy * gy + 1);
            float* t = n.texel(x, y);
            t[0] = q(0.5 - 0.5 * gx / len), t[1] = q(0.5 - 0.5 * gy / len), t[2] = q(0.5 + 0.5 / len);
        }
    return n;
}

Image make_orm(int size, int bits = 8) {
    const auto q = bits == 16 ? q16 : q8;
    Image m(size, size, 3);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            float* t = m.texel(x, y);
            t[0] = q(1.0 - 0.25 * y / size), t[1] = q(0.1 + 0.6 * x / size), t[2] = ((x / 64 + y / 64) % 2) ? 1.0f : 0.0f;
        }
    return m;
}

// User + system CPU seconds of this process, all threads.
double process_cpu_seconds() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The outputs of (d): the two integer outputs, which both KTX2 and per-mip PNG hold.
TextureOutputs floor_outputs() { return TextureOutputs{true, false, false, true}; }

// Child mode: run the texture job once, print "<wall seconds> <peak RSS KiB> <CPU seconds>". `container`
// "ktx2-all": all default outputs as KTX2; "ktx2", "dds", "exr", "png": the outputs of (d).
int end_to_end_child(const char* normal, const char* orm, const char* out, const std::string& container) {
    TextureJob job;
    job.normal = normal;
    job.roughness = fs::path(orm);
    job.output_dir = out;
    if (container != "ktx2-all") job.settings.outputs = floor_outputs();
    if (container != "ktx2-all") job.texture_format = io::TextureFileFormat(*io::parse_container(container));
    const auto t0 = Clock::now();
    auto r = run_texture_job(job);
    const double wall = seconds_since(t0);
    if (!r) {
        std::fprintf(stderr, "%s\n", r.error().message.c_str());
        return 1;
    }
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    const double cpu = double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
    std::printf("%.3f %ld %.3f\n", wall, long(u.ru_maxrss), cpu);
    return 0;
}

// CPU seconds (user + system) of the waited-for children of this process so far.
double children_cpu_seconds() {
    rusage u{};
    getrusage(RUSAGE_CHILDREN, &u);
    return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct Timed {
    double wall = -1.0;
    double cpu = -1.0;
};

// Wall Mtexel/s and CPU ns/texel of every repetition of every compute benchmark, by name.
std::map<std::string, std::vector<double>> g_rates, g_cpu_ns;

double median(std::vector<double> v) {
    if (v.empty()) return -1.0;
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

Timed time_command(const std::string& cmd) {
    const auto t0 = Clock::now();
    const double c0 = children_cpu_seconds();
    if (std::system(cmd.c_str()) != 0) return {};
    return {seconds_since(t0), children_cpu_seconds() - c0};
}

// One job run in a child process: wall and CPU from outside, peak RSS from inside, bytes written.
struct ChildRun {
    Timed time;
    long rss_kib = 0;
    uintmax_t output_bytes = 0;
};
ChildRun run_child(const std::string& self, const fs::path& normal, const fs::path& orm, const fs::path& out,
                   const std::string& container) {
    ChildRun run;
    fs::remove_all(out);
    const fs::path report = out.string() + ".txt";
    const Timed t = time_command("'" + self + "' --end-to-end-child '" + normal.string() + "' '" + orm.string() + "' '" +
                                 out.string() + "' " + container + " > '" + report.string() + "'");
    double wall_inside = 0, cpu_inside = 0;
    FILE* f = t.wall >= 0 ? std::fopen(report.string().c_str(), "r") : nullptr;
    if (f && std::fscanf(f, "%lf %ld %lf", &wall_inside, &run.rss_kib, &cpu_inside) == 3) run.time = t;
    if (f) std::fclose(f);
    std::error_code none;
    for (const auto& e : fs::directory_iterator(out, none))
        if (e.path().filename() != "manifest.json") run.output_bytes += e.file_size();
    return run;
}

// The two inputs of (d) at `bits` (8 or 16) as PNGs in `dir`, and the images they hold.
struct FloorInputs {
    fs::path normal_png, orm_png;
    Image normal, orm;
};

// (d): the job against its floor for every container, from `bits`-bit inputs, the median of `repeats` runs.
void print_floor(const std::string& self, const fs::path& dir, const FloorInputs& in, int bits, int size,
                 int repeats) {
    // (1) Decoding the inputs as the job does (plain PNGs kept as 8- or 16-bit integers), one after the other.
    std::vector<double> decode_cpu;
    size_t decoded_bytes = 0;
    for (int r = 0; r < repeats; ++r) {
        const double c0 = process_cpu_seconds();
        auto n = io::decode_image(in.normal_png, {}, true);
        auto m = io::decode_image(in.orm_png, {}, true);
        decode_cpu.push_back(process_cpu_seconds() - c0);
        if (!n || !m) {
            std::fprintf(stderr, "floor: cannot decode the inputs\n");
            return;
        }
        auto integer_bytes = [](const io::IntegerTexels& t) { return t.bytes.size() + t.words.size() * sizeof(uint16_t); };
        decoded_bytes = integer_bytes(n->integers) + integer_bytes(m->integers) +
                        (n->image.pixels.size() + m->image.pixels.size()) * sizeof(float);
    }
    // The raw output levels (uncompressed KTX2 files, untimed): what every container compresses.
    TextureInputs inputs;
    inputs.normal = &in.normal;
    inputs.roughness = &in.orm;
    inputs.normal_bits = inputs.roughness_bits = bits;
    TextureBakeSettings settings;
    settings.outputs = floor_outputs();
    io::Supercompression none;
    none.zstd = false;
    auto raw = bake_texture_encoded(inputs, settings, io::TextureFileFormat(io::TextureContainer::Ktx2, none), "t");
    if (!raw) {
        std::fprintf(stderr, "floor: %s\n", raw.error().message.c_str());
        return;
    }
    // The same levels as EXR stores them (half), untimed.
    std::vector<std::vector<std::vector<uint8_t>>> halves;
    for (const auto& t : raw->textures) {
        const io::ContainerLayout& layout = t->layout();
        halves.emplace_back();
        for (size_t L = 0; L < layout.level_offset.size(); ++L) {
            const int w = std::max(1, t->width() >> L), h = std::max(1, t->height() >> L);
            const size_t bytes = size_t(w) * size_t(h) * size_t(layout.stored_channels) * size_t(io::encoding_bytes(t->encoding()));
            const Image level = io::decode_texels(t->bytes().subspan(layout.level_offset[L], bytes), t->encoding(), w, h,
                                                  layout.stored_channels);
            halves.back().push_back(io::encode_texels(level, io::TexelEncoding::Float16, layout.stored_channels));
        }
    }
    // (2) Compressing every level with the job's codec and level, one level after another.
    auto compress_cpu = [&](io::TextureContainer container) {
        const double c0 = process_cpu_seconds();
        for (size_t k = 0; k < raw->textures.size(); ++k) {
            const io::EncodedTexture& t = *raw->textures[k];
            const io::ContainerLayout& layout = t.layout();
            if (container == io::TextureContainer::Exr) {
                io::ExrImageDesc desc;
                desc.width = t.width(), desc.height = t.height();
                desc.levels = int(layout.level_offset.size());
                desc.tile_side = 64;
                desc.channel_names = layout.stored_channels == 1 ? std::vector<std::string>{"Y"}
                                                                 : std::vector<std::string>{"R", "G", "B", "A"};
                auto encoder = io::ExrEncoder::create(desc, io::kExrDeflateLevel);
                if (!encoder) return -1.0;
                for (size_t L = 0; L < layout.level_offset.size(); ++L)
                    if (!encoder->add_rows(int(L), halves[k][L].data(), std::max(1, t.height() >> L))) return -1.0;
                auto file = encoder->file({});
                if (!file) return -1.0;
                benchmark::DoNotOptimize(file->size());
                continue;
            }
            for (size_t L = 0; L < layout.level_offset.size(); ++L) {
                const int w = std::max(1, t.width() >> L), h = std::max(1, t.height() >> L);
                const uint8_t* level = t.bytes().data() + layout.level_offset[L];
                const int channel_bytes = io::encoding_bytes(t.encoding());
                const size_t bytes = size_t(w) * size_t(h) * size_t(layout.stored_channels) * size_t(channel_bytes);
                if (container == io::TextureContainer::PngPerMip) {
                    io::PngLevelStream stream(w, h, layout.stored_channels, 8 * channel_bytes, 2);
                    if (!stream.add_rows(level, h)) return -1.0;
                    benchmark::DoNotOptimize(stream.bytes());
                } else if (container == io::TextureContainer::Ktx2) {
                    std::vector<uint8_t> out(ZSTD_compressBound(bytes));
                    benchmark::DoNotOptimize(ZSTD_compress(out.data(), out.size(), level, bytes, 3));
                }  // DDS stores its levels as they are
            }
        }
        return process_cpu_seconds() - c0;
    };
    const double mib = 1024.0 * 1024.0;
    std::printf("(d) floor, %dx%d %d-bit inputs, roughness + mean normal, CPU s (user + sys), median of %d\n", size, size,
                bits, repeats);
    std::printf("  container  job CPU   decode   (ratio)   decode + compress   (ratio)   job peak MiB   decoded + files MiB   (ratio)\n");
    const double decode = median(decode_cpu);
    for (const io::TextureContainer container : {io::TextureContainer::Ktx2, io::TextureContainer::Dds,
                                                 io::TextureContainer::Exr, io::TextureContainer::PngPerMip}) {
        const std::string name = io::container_name(container);
        std::vector<double> job_cpu, compress, rss;
        uintmax_t files = 0;
        tbb::task_arena one_thread(1);
        for (int r = 0; r < repeats; ++r) {
            const ChildRun run = run_child(self, in.normal_png, in.orm_png, dir / "floor_out", name);
            if (run.time.cpu < 0) {
                std::fprintf(stderr, "floor: the %s job failed\n", name.c_str());
                return;
            }
            job_cpu.push_back(run.time.cpu);
            rss.push_back(double(run.rss_kib) / 1024.0);
            files = run.output_bytes;
            one_thread.execute([&] { compress.push_back(compress_cpu(container)); });
        }
        const double job = median(job_cpu), floor = decode + median(compress);
        const double held = (double(decoded_bytes) + double(files)) / mib;
        std::printf("  %-9s %8.2f %8.2f %8.2fx %13.2f %13.2fx %14.1f %21.1f %8.2fx\n", name.c_str(), job, decode,
                    job / decode, floor, job / floor, median(rss), held, median(rss) / held);
    }
}

// Writes the inputs of (d) at `bits` to `dir`; empty paths on failure.
FloorInputs floor_inputs(const fs::path& dir, int size, int bits) {
    FloorInputs in{dir / ("normal" + std::to_string(bits) + ".png"), dir / ("orm" + std::to_string(bits) + ".png"),
                   make_normal(size, bits), make_orm(size, bits)};
    if (!io::write_image(in.normal_png, in.normal, bits) || !io::write_image(in.orm_png, in.orm, bits)) return {};
    return in;
}

// (d) for 8- and 16-bit inputs.
void print_floors(const std::string& self, const fs::path& dir, int size, int repeats) {
    for (const int bits : {8, 16}) {
        const FloorInputs in = floor_inputs(dir, size, bits);
        if (in.normal_png.empty()) {
            std::fprintf(stderr, "floor: cannot write the %d-bit inputs to %s\n", bits, dir.string().c_str());
            return;
        }
        print_floor(self, dir, in, bits, size, repeats);
    }
}

}  // namespace

int main(int argc, char** argv) {
    if (argc == 6 && std::strcmp(argv[1], "--end-to-end-child") == 0)
        return end_to_end_child(argv[2], argv[3], argv[4], argv[5]);
    int size = 4096;
    bool compute_only = false, end_to_end_only = false, floor_only = false;
    fs::path keep;  // --keep DIR: inputs and outputs go to DIR and stay there
    for (int i = 1; i < argc; ++i) {
        if (i + 1 < argc && std::strcmp(argv[i], "--size") == 0) size = std::atoi(argv[i + 1]);
        if (std::strcmp(argv[i], "--compute-only") == 0) compute_only = true;
        if (std::strcmp(argv[i], "--end-to-end-only") == 0) end_to_end_only = true;
        if (std::strcmp(argv[i], "--floor-only") == 0) floor_only = true;
        if (i + 1 < argc && std::strcmp(argv[i], "--keep") == 0) keep = argv[i + 1];
    }

    // (b), (c) first, before this process holds large images.
    const fs::path dir =
        keep.empty() ? fs::temp_directory_path() / ("specbake_bench_texture_" + std::to_string(::getpid())) : keep;
    fs::create_directories(dir);
    const fs::path normal_png = dir / "normal.png", orm_png = dir / "orm.png";
    if (!compute_only && !floor_only) {
        const Image n = make_normal(size), m = make_orm(size);
        if (!io::write_image(normal_png, n, 8) || !io::write_image(orm_png, m, 8)) {
            std::fprintf(stderr, "cannot write the benchmark inputs to %s\n", dir.string().c_str());
            return 1;
        }
    }
    const std::string self = fs::read_symlink("/proc/self/exe").string();
    if (floor_only) {
        print_floors(self, dir, size, 3);
        if (keep.empty()) fs::remove_all(dir);
        return 0;
    }
    const fs::path out = dir / "out";
    const std::string child = "'" + self + "' --end-to-end-child '" + normal_png.string() + "' '" + orm_png.string() +
                              "' '" + out.string() + "' ktx2-all > '" + (dir / "child.txt").string() + "'";
    // Wall and CPU time of the job are taken from outside its process, as for oiiotool below (process start
    // and exit included, CPU of the waited-for child); its peak RSS is its own ru_maxrss, the counter GNU
    // time's %M reports for oiiotool.
    double e2e = -1, e2e_cpu = -1, e2e_inside = -1, cpu_inside = -1;
    long rss_kib = 0;
    if (!compute_only) {
        const Timed job = time_command(child);
        FILE* f = job.wall >= 0 ? std::fopen((dir / "child.txt").string().c_str(), "r") : nullptr;
        if (f && std::fscanf(f, "%lf %ld %lf", &e2e_inside, &rss_kib, &cpu_inside) == 3) e2e = job.wall, e2e_cpu = job.cpu;
        if (f) std::fclose(f);
    }
    const Timed floor_png = compute_only ? Timed{} : time_command("oiiotool '" + normal_png.string() + "' -o '" + (dir / "n2.png").string() + "' && oiiotool '" +
                             orm_png.string() + "' -o '" + (dir / "o2.png").string() + "'");
    const Timed floor_png_parallel = compute_only ? Timed{} :
        time_command("oiiotool '" + normal_png.string() + "' -o '" + (dir / "n3.png").string() + "' & p=$!; oiiotool '" +
                     orm_png.string() + "' -o '" + (dir / "o3.png").string() + "'; r=$?; wait $p && [ $r -eq 0 ]");
    const Timed floor_tif = compute_only ? Timed{} : time_command("oiiotool '" + normal_png.string() + "' --compression none -o '" + (dir / "n2.tif").string() +
                             "' && oiiotool '" + orm_png.string() + "' --compression none -o '" +
                             (dir / "o2.tif").string() + "'");
    // Peak memory of one oiiotool decode + re-encode (GNU time's %M: max RSS in KiB).
    long oiio_rss_kib = 0;
    if (!compute_only &&
        std::system(("/usr/bin/time -f %M -o '" + (dir / "oiio_rss.txt").string() + "' oiiotool '" +
                     normal_png.string() + "' -o '" + (dir / "n4.png").string() + "'")
                        .c_str()) == 0) {
        if (FILE* f = std::fopen((dir / "oiio_rss.txt").string().c_str(), "r")) {
            if (std::fscanf(f, "%ld", &oiio_rss_kib) != 1) oiio_rss_kib = 0;
            std::fclose(f);
        }
    }
    uintmax_t output_bytes = 0;
    std::error_code no_output;  // --compute-only: no end-to-end run, no output folder
    for (const auto& e : fs::directory_iterator(out, no_output))
        if (e.path().extension() == ".ktx2") output_bytes += e.file_size();

    // (a) compute only.
    if (!end_to_end_only) {
        const Image normal = make_normal(size), orm = make_orm(size);
        TextureInputs inputs;
        inputs.normal = &normal;
        inputs.roughness = &orm;
        enum class Kind { Encoded, Values, FloatChains };
        const std::map<Kind, std::string> kind_names{{Kind::Encoded, "bake_texture_encoded/"},
                                                     {Kind::Values, "bake_texture_values/"},
                                                     {Kind::FloatChains, "bake_texture_float_chains/"}};
        for (const Kind kind : {Kind::Encoded, Kind::Values, Kind::FloatChains}) {
            for (int threads : {1, 2}) {
                const std::string name = kind_names.at(kind) + std::to_string(size) + "/threads:" + std::to_string(threads);
                benchmark::RegisterBenchmark(name.c_str(), [&, threads, kind, name](benchmark::State& state) {
                    TextureBakeSettings s;
                    s.threads = threads;
                    const double cpu0 = process_cpu_seconds();
                    const auto t0 = Clock::now();
                    for (auto _ : state) {
                        if (kind == Kind::Encoded) {
                            const io::TextureFileFormat ktx2(io::TextureContainer::Ktx2);
                            auto r = bake_texture_encoded(inputs, s, ktx2, "texture");
                            benchmark::DoNotOptimize(r);
                        } else if (kind == Kind::Values) {
                            auto r = bake_texture_rows(normal, &orm, 1, 0.0f, s, [](const TextureBakeRows& rows) {
                                benchmark::DoNotOptimize(rows.roughness);
                            });
                            benchmark::DoNotOptimize(r);
                        } else {
                            auto r = bake_texture(normal, &orm, 1, 0.0f, s);
                            benchmark::DoNotOptimize(r);
                        }
                    }
                    const double wall = seconds_since(t0);
                    const double cpu = process_cpu_seconds() - cpu0;
                    const double texels = double(state.iterations()) * double(size) * size;
                    state.counters["Mtexel/s"] = benchmark::Counter(double(size) * size * 1e-6,
                                                                    benchmark::Counter::kIsIterationInvariantRate);
                    // CPU time of all threads (user + system): on a loaded machine the wall-time rate drops,
                    // this one much less.
                    state.counters["cpu_ns/texel"] = cpu * 1e9 / texels;
                    g_rates[name].push_back(texels * 1e-6 / wall);
                    g_cpu_ns[name].push_back(cpu * 1e9 / texels);
                })
                    ->Unit(benchmark::kMillisecond)
                    ->UseRealTime()
                    ->MeasureProcessCPUTime()
                    ->MinTime(2.0);
            }
        }
        benchmark::Initialize(&argc, argv);
        benchmark::RunSpecifiedBenchmarks();
        benchmark::Shutdown();
    }

    const double mib = 1024.0 * 1024.0;
    const double decoded_u8 = 2.0 * size * size * 3;  // both inputs, 8-bit RGB
    const double decoded_f32 = decoded_u8 * 4;        // as the float images specbake holds
    const double memory_ratio = rss_kib * 1024.0 / (decoded_u8 + double(output_bytes));
    std::printf("\nsummary, %dx%d RGB8 normal + ORM, all default outputs (KTX2)\n", size, size);
    if (!end_to_end_only) {
        std::printf("(a) compute only, median over all timed runs  wall Mtexel/s   CPU ns/texel (all threads)\n");
        for (const char* kind : {"bake_texture_encoded/", "bake_texture_values/", "bake_texture_float_chains/"}) {
            for (int threads : {1, 2}) {
                const std::string name = kind + std::to_string(size) + "/threads:" + std::to_string(threads);
                std::printf("  %-28s %d thread%s %21.1f %14.1f\n", kind, threads, threads > 1 ? "s" : " ",
                            median(g_rates[name]), median(g_cpu_ns[name]));
            }
        }
        const double encoded2 = median(g_rates["bake_texture_encoded/" + std::to_string(size) + "/threads:2"]);
        const double values2 = median(g_rates["bake_texture_values/" + std::to_string(size) + "/threads:2"]);
        std::printf("  goal >= 200 Mtexel/s on 2 threads: bake + encode (as the job runs it) %s (%.1f), bake alone %s (%.1f)\n",
                    encoded2 >= 200.0 ? "met" : "NOT met", encoded2, values2 >= 200.0 ? "met" : "NOT met", values2);
    }
    if (compute_only) {
        if (keep.empty()) fs::remove_all(dir);
        return 0;
    }
    std::printf("(b) end to end                       wall            CPU (user + sys)\n");
    std::printf("  specbake texture:                 %8.2f s        %8.2f s   (inside the job: %.2f s wall)\n", e2e,
                e2e_cpu, e2e_inside);
    std::printf("  oiiotool PNG->PNG, one by one:    %8.2f s (%.2fx) %8.2f s (%.2fx)\n", floor_png.wall,
                e2e / floor_png.wall, floor_png.cpu, e2e_cpu / floor_png.cpu);
    std::printf("  oiiotool PNG->PNG, both at once:  %8.2f s (%.2fx) %8.2f s (%.2fx)\n", floor_png_parallel.wall,
                e2e / floor_png_parallel.wall, floor_png_parallel.cpu, e2e_cpu / floor_png_parallel.cpu);
    std::printf("  oiiotool PNG->TIFF (no compression), one by one: %6.2f s (%.2fx) %6.2f s (%.2fx)\n",
                floor_tif.wall, e2e / floor_tif.wall, floor_tif.cpu, e2e_cpu / floor_tif.cpu);
    std::printf("  goal <= 1.0x the PNG->PNG floor (wall, issue 16 item 7): %s one by one (%.2fx), %s both at once (%.2fx)\n",
                e2e / floor_png.wall <= 1.0 ? "met" : "NOT met", e2e / floor_png.wall,
                e2e / floor_png_parallel.wall <= 1.0 ? "met" : "NOT met", e2e / floor_png_parallel.wall);
    std::printf("(c) peak memory (max RSS of the job): %8.1f MiB\n", rss_kib / 1024.0);
    std::printf("  decoded inputs: %.1f MiB as 8-bit, %.1f MiB as float; outputs written: %.1f MiB\n", decoded_u8 / mib,
                decoded_f32 / mib, double(output_bytes) / mib);
    std::printf("  ratio to (decoded 8-bit inputs + outputs): %.2fx; goal <= 1.5x (issue 16 item 7): %s\n", memory_ratio,
                memory_ratio <= 1.5 ? "met" : "NOT met");
    std::printf("  oiiotool PNG->PNG of the normal map alone: %.1f MiB\n", oiio_rss_kib / 1024.0);
    print_floors(self, dir, size, 3);
    if (keep.empty()) fs::remove_all(dir);
    return 0;
}
