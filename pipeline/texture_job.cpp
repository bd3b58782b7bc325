#include "pipeline/texture_job.h"

#include "pipeline/bake_output.h"
#include "pipeline/version.h"
#include "io/atomic_file.h"
#include "io/block_compress.h"
#include "io/input_policy.h"
#include "io/image_io.h"
#include "io/sha256.h"

#include <tbb/parallel_for.h>
#include <sys/mman.h>
#include <unistd.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <memory>
#include <mutex>
#include <optional>

namespace specbake {
namespace fs = std::filesystem;

namespace {

const char* reduction_name(IsotropicReduction r) {
    switch (r) {
        case IsotropicReduction::Mean: return "mean";
        case IsotropicReduction::Sum: return "sum";
        case IsotropicReduction::Max: return "max";
    }
    return "mean";
}

const char* wrap_name(WrapMode w) {
    switch (w) {
        case WrapMode::Repeat: return "repeat";
        case WrapMode::Clamp: return "clamp";
        case WrapMode::Mirror: return "mirror";
    }
    return "repeat";
}

// Replaces the bake's "normal map: " / "roughness map: " prefix by the file's name.
Error name_error(const Error& e, const std::string& normal_name, const std::string& roughness_name) {
    const std::string& m = e.message;
    if (m.rfind("normal map: ", 0) == 0) return make_error(normal_name + ": " + m.substr(12));
    if (m.rfind("roughness map: ", 0) == 0) return make_error(roughness_name + ": " + m.substr(15));
    return e;
}

// The encoding of the roughness and mean-normal outputs of `bits`-bit inputs: 8 bits as R8/RGBA8 UNORM;
// deeper inputs as half floats (R16_SFLOAT, R16G16B16A16_SFLOAT: formats every GPU samples and filters,
// 11 significant bits, which three.js and WebGL 2 load where they have no 16-bit UNORM), except as 16-bit
// UNORM in per-mip PNGs (PNG has no float) and where block compression narrows them to 8 bits anyway.
io::TexelEncoding encoding_for_bits(int bits, io::TextureContainer container, const io::Supercompression& s) {
    if (bits <= 8) return io::TexelEncoding::Unorm8;
    if (container == io::TextureContainer::PngPerMip || s.block != io::BlockFamily::None)
        return io::TexelEncoding::Unorm16;
    return io::TexelEncoding::Float16;
}

// Channels [first, first + count) of every level.
MipChain channel_subset(const MipChain& chain, int first, int count) {
    MipChain out;
    for (const Image& level : chain.levels) {
        Image sub(level.width, level.height, count);
        const size_t n = level.texel_count();
        for (size_t i = 0; i < n; ++i)
            for (int c = 0; c < count; ++c) sub.pixels[i * count + c] = level.pixels[i * level.channels + first + c];
        out.levels.push_back(std::move(sub));
    }
    return out;
}

enum class Chain { Roughness, Kernel, Normal, Lean };

// One output file: channels [first, first + channels) of one baked chain, stored as `encoding`.
struct OutputFile {
    Chain chain;
    std::string kind, stem;
    io::TexelEncoding encoding;
    int first = 0, channels = 0;
    std::vector<std::string> names;
};

// The files of settings.outputs, in the order they are written, each in a layout GPUs sample (1, 2 or 4
// channels, the same in every container; README "Output layouts"): `<stem>_roughness` (Y = r, or the ORM
// map as RGBA with G = r and A = 1), `_kernel` (Y = t, or RGBA = xx, yy, xy, rough share), `_normal` (RGBA = normalised
// mean normal as (n + 1) / 2, A = 1: a drop-in for glTF normalTexture and engine shaders that read .xyz;
// zstd removes the constant A almost entirely, and the two-channel form belongs to BC5),
// `_lean` (RGBA = m.x, m.y, M.xx, M.yy) plus `_lean_xy` (Y = M.xy). `names` are the channels' meanings.
std::vector<OutputFile> output_files(const TextureBakeShape& shape, const TextureInputs& in,
                                     const TextureBakeSettings& settings, const std::string& stem,
                                     io::TextureContainer container, const io::Supercompression& supercompression) {
    std::vector<OutputFile> files;
    const bool have_roughness = in.roughness || in.roughness_map.channels > 0;
    const int roughness_bits = have_roughness ? in.roughness_bits : in.normal_bits;
    if (settings.outputs.roughness) {
        files.push_back({Chain::Roughness, "roughness", stem + "_roughness",
                         encoding_for_bits(roughness_bits, container, supercompression), 0,
                         shape.roughness_channels,
                         shape.roughness_channels == 3 ? std::vector<std::string>{"input.r", "r", "input.b", "1"}
                                                       : std::vector<std::string>{"r"}});
    }
    if (settings.outputs.kernel) {
        files.push_back({Chain::Kernel, "kernel", stem + "_kernel", io::TexelEncoding::Float16, 0, shape.kernel_channels,
                         settings.anisotropic ? std::vector<std::string>{"xx", "yy", "xy", "rough"}
                                              : std::vector<std::string>{"t"}});
    }
    if (settings.outputs.normal) {
        files.push_back({Chain::Normal, "normal", stem + "_normal",
                         encoding_for_bits(in.normal_bits, container, supercompression), 0, 3,
                         {"n.x", "n.y", "n.z", "1"}});
    }
    if (settings.outputs.lean) {
        // Slope-space moments are unbounded (|s| grows as 1/n.z), so they get full float precision.
        const io::TexelEncoding enc =
            settings.lean_space == LeanSpace::Slope ? io::TexelEncoding::Float32 : io::TexelEncoding::Float16;
        files.push_back({Chain::Lean, "lean", stem + "_lean", enc, 0, 4, {"m.x", "m.y", "M.xx", "M.yy"}});
        files.push_back({Chain::Lean, "lean", stem + "_lean_xy", enc, 4, 1, {"M.xy"}});
    }
    return files;
}

// The block format of `f` when block compression is asked (io/block_compress.h): unorm data only, one
// channel BC4, the mean normal BC5 (x, y; z = sqrt(1 - x^2 - y^2) at run time), four channels BC1 or BC3;
// ASTC keeps the same channels (io/astc_codec.h).
io::BlockFormat block_format_of(const OutputFile& f, const io::Supercompression& s) {
    if (s.block == io::BlockFamily::None ||
        (f.encoding != io::TexelEncoding::Unorm8 && f.encoding != io::TexelEncoding::Unorm16))
        return io::BlockFormat::None;
    const bool astc = s.block == io::BlockFamily::Astc;
    if (f.chain == Chain::Normal) return astc ? io::BlockFormat::AstcRg : io::BlockFormat::Bc5;
    if (f.channels == 1) return astc ? io::BlockFormat::AstcR : io::BlockFormat::Bc4;
    if (astc) return io::BlockFormat::AstcRgba;
    return s.rgba_block == 3 ? io::BlockFormat::Bc3 : io::BlockFormat::Bc1;
}

MipChain& chain_of(TextureBakeResult& baked, Chain c) {
    switch (c) {
        case Chain::Roughness: return baked.roughness;
        case Chain::Kernel: return baked.kernel;
        case Chain::Normal: return baked.normal;
        case Chain::Lean: return baked.lean;
    }
    return baked.roughness;
}

const float* rows_of(const TextureBakeRows& r, Chain c) {
    switch (c) {
        case Chain::Roughness: return r.roughness;
        case Chain::Kernel: return r.kernel;
        case Chain::Normal: return r.normal;
        case Chain::Lean: return r.lean;
    }
    return r.roughness;
}

int chain_channels(const TextureBakeShape& shape, Chain c) {
    switch (c) {
        case Chain::Roughness: return shape.roughness_channels;
        case Chain::Kernel: return shape.kernel_channels;
        case Chain::Normal: return shape.normal_channels;
        case Chain::Lean: return shape.lean_channels;
    }
    return 0;
}

// Returns the whole pages of [p, p + bytes) to the system (they read as zeroes afterwards).
void release_pages(const uint8_t* p, size_t bytes) {
    const uintptr_t page = uintptr_t(sysconf(_SC_PAGESIZE));
    const uintptr_t from = (reinterpret_cast<uintptr_t>(p) + page - 1) & ~(page - 1);
    const uintptr_t to = (reinterpret_cast<uintptr_t>(p) + bytes) & ~(page - 1);
    if (to > from) madvise(reinterpret_cast<void*>(from), to - from, MADV_DONTNEED);
}

// The maps of `in` as the bake reads them: the 8-bit views where set, else the float images.
struct InputMaps {
    TextureMap normal, roughness_storage;
    const TextureMap* roughness = nullptr;
};
InputMaps maps_of(const TextureInputs& in) {
    InputMaps m;
    m.normal = in.normal_map.channels > 0 ? in.normal_map : in.normal ? TextureMap::of(*in.normal) : TextureMap{};
    if (in.roughness_map.channels > 0) m.roughness_storage = in.roughness_map;
    else if (in.roughness) m.roughness_storage = TextureMap::of(*in.roughness);
    if (m.roughness_storage.channels > 0 || in.roughness) m.roughness = &m.roughness_storage;
    return m;
}

int roughness_channel_of(const TextureInputs& in) {
    const bool have = in.roughness || in.roughness_map.channels > 0;
    const int channels = in.roughness_map.channels > 0 ? in.roughness_map.channels : in.roughness ? in.roughness->channels : 0;
    if (have && in.roughness_channel < 0) return channels >= 3 ? 1 : 0;
    return in.roughness_channel;
}

Result<void> append(std::vector<io::ManifestOutput>& all, Result<std::vector<io::ManifestOutput>> written) {
    if (!written) return written.error();
    for (io::ManifestOutput& o : *written) all.push_back(std::move(o));
    return {};
}

// 8-bit quantisation, as the demo maps would be stored in a PNG.
float quantise8(double v) { return float(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)) / 255.0f; }

// Deterministic per-texel hash in [0, 1).
double hash01(int x, int y, uint32_t seed) {
    uint32_t h = uint32_t(x) * 0x8da6b343u ^ uint32_t(y) * 0xd8163841u ^ seed * 0xcb1ab31fu;
    h ^= h >> 16;
    h *= 0x7feb352du;
    h ^= h >> 15;
    h *= 0x846ca68bu;
    h ^= h >> 16;
    return double(h) / 4294967296.0;
}

constexpr int kDemoWidth = 512, kDemoHeight = 384;
constexpr double kPi = 3.14159265358979323846;

// Height-field gradient of the demo surface: bumps on the left third, ribs along x in the middle,
// fine noise on the right.
void demo_gradient(int x, int y, double& gx, double& gy) {
    const double u = (x + 0.5), v = (y + 0.5);
    if (x < kDemoWidth / 3) {
        const double k = 2.0 * kPi / 16.0, amp = 1.2;  // 16-texel period bumps
        gx = amp * k * std::cos(k * u) * std::sin(k * v);
        gy = amp * k * std::sin(k * u) * std::cos(k * v);
    } else if (x < 2 * kDemoWidth / 3) {
        const double k = 2.0 * kPi / 6.0, amp = 0.6;  // 6-texel ribs: all variance in x
        gx = amp * k * std::cos(k * u);
        gy = 0.0;
    } else {
        gx = 0.35 * (hash01(x, y, 1) - 0.5);
        gy = 0.35 * (hash01(x, y, 2) - 0.5);
    }
}

}  // namespace

Image demo_normal_map() {
    Image n(kDemoWidth, kDemoHeight, 3);
    for (int y = 0; y < kDemoHeight; ++y) {
        for (int x = 0; x < kDemoWidth; ++x) {
            double gx, gy;
            demo_gradient(x, y, gx, gy);
            const double len = std::sqrt(gx * gx + gy * gy + 1.0);
            float* t = n.texel(x, y);
            t[0] = quantise8(0.5 - 0.5 * gx / len);
            t[1] = quantise8(0.5 - 0.5 * gy / len);
            t[2] = quantise8(0.5 + 0.5 / len);
        }
    }
    return n;
}

Image demo_orm_map() {
    Image m(kDemoWidth, kDemoHeight, 3);
    for (int y = 0; y < kDemoHeight; ++y) {
        for (int x = 0; x < kDemoWidth; ++x) {
            float* t = m.texel(x, y);
            t[0] = quantise8(1.0 - 0.3 * double(y) / kDemoHeight);                  // occlusion
            t[1] = quantise8(0.05 + 0.45 * double(y) / (kDemoHeight - 1));          // roughness 0.05 .. 0.5
            t[2] = ((x / 32) % 2 == 0) ? 1.0f : 0.0f;                               // metallic stripes
        }
    }
    return m;
}

nlohmann::json texture_settings_json(const TextureBakeSettings& s, io::TextureContainer container) {
    nlohmann::json j;
    j["format"] = io::container_name(container);
    j["isotropic"] = reduction_name(s.isotropic);
    j["filter"] = s.filter == RoughnessFilterMode::Projected ? "projected" : "approx";
    j["max_kernel"] = s.max_kernel ? nlohmann::json(*s.max_kernel) : nlohmann::json(nullptr);
    j["normal_y"] = s.normal_y == NormalGreen::PlusY ? "+y" : "-y";
    j["reconstruct_z"] = s.reconstruct_z == ReconstructZ::Auto     ? "auto"
                         : s.reconstruct_z == ReconstructZ::Always ? "always"
                         : s.reconstruct_z == ReconstructZ::Gltf   ? "gltf"
                                                                   : "never";
    j["wrap"] = wrap_name(s.wrap);
    j["anisotropic"] = s.anisotropic;
    j["lean_space"] = s.lean_space == LeanSpace::Projected ? "projected" : "slope";
    nlohmann::json outs = nlohmann::json::array();
    if (s.outputs.roughness) outs.push_back("roughness");
    if (s.outputs.kernel) outs.push_back("kernel");
    if (s.outputs.lean) outs.push_back("lean");
    if (s.outputs.normal) outs.push_back("normal");
    j["outputs"] = outs;
    return j;
}

Result<TextureBakeResult> bake_texture_inputs(const TextureInputs& in, const TextureBakeSettings& settings,
                                              const ProgressFn& progress) {
    if (!in.normal) return make_error(in.normal_name + ": no normal map given");
    if (progress)
        progress("baking " + std::to_string(in.normal->width) + "x" + std::to_string(in.normal->height) + " " +
                 in.normal_name);
    auto baked = bake_texture(*in.normal, in.roughness, roughness_channel_of(in), in.roughness_value, settings);
    if (!baked) return name_error(baked.error(), in.normal_name, in.roughness_name);
    return baked;
}

nlohmann::json supercompression_json(const io::Supercompression& s) {
    nlohmann::json j = s.zstd ? nlohmann::json{{"scheme", "zstd"}, {"zstd_level", s.zstd_level}}
                              : nlohmann::json{{"scheme", "none"}};
    if (s.block == io::BlockFamily::Bc)
        j["block"] = {{"one_channel", "bc4"}, {"normal", "bc5"}, {"rgba", s.rgba_block == 3 ? "bc3" : "bc1"}};
    if (s.block == io::BlockFamily::Astc) {
        const std::string astc = "astc" + std::to_string(s.astc_block) + "x" + std::to_string(s.astc_block);
        j["block"] = {{"one_channel", astc}, {"normal", astc}, {"rgba", astc}};
    }
    return j;
}

Result<TextureOutputsWritten> bake_texture_outputs(const TextureInputs& in, const TextureBakeSettings& settings,
                                                   io::TextureContainer container, const fs::path& dir,
                                                   const std::string& stem, const ProgressFn& progress,
                                                   const FractionFn& fraction,
                                                   const io::Supercompression& supercompression) {
    if (!io::EncodedTexture::supports(container)) {
        auto baked = bake_texture_inputs(in, settings, progress);
        if (!baked) return baked.error();
        return write_texture_outputs(std::move(*baked), in, settings, container, dir, stem, progress,
                                     supercompression);
    }
    auto encoded = bake_texture_encoded(in, settings, container, stem, progress, fraction, supercompression);
    if (!encoded) return encoded.error();
    TextureOutputsWritten result;
    result.notes = encoded->notes;
    result.max_roughness_change = encoded->max_roughness_change;
    if (progress)
        for (const io::EncodedFile& f : encoded->files) progress("writing " + f.stem);
    auto written = io::write_encoded_textures(encoded->files, dir);
    if (!written) return written.error();
    result.outputs = std::move(*written);
    return result;
}

Result<EncodedTextureOutputs> bake_texture_encoded(const TextureInputs& in, const TextureBakeSettings& settings,
                                                   io::TextureContainer container, const std::string& stem,
                                                   const ProgressFn& progress, const FractionFn& fraction,
                                                   const io::Supercompression& supercompression) {
    const InputMaps maps = maps_of(in);
    if (maps.normal.channels == 0) return make_error(in.normal_name + ": no normal map given");
    if (!io::EncodedTexture::supports(container))
        return make_error(std::string("cannot encode ") + io::container_name(container) + " in memory");
    const int channel = roughness_channel_of(in);
    const TextureBakeShape shape = texture_bake_shape(maps.normal, maps.roughness, channel, settings);
    const std::vector<OutputFile> files = output_files(shape, in, settings, stem, container, supercompression);
    EncodedTextureOutputs out;
    for (const OutputFile& f : files) {
        out.textures.push_back(std::make_unique<io::EncodedTexture>(container, f.encoding, shape.width, shape.height,
                                                                    shape.levels, f.channels, supercompression));
        out.files.push_back({out.textures.back().get(), f.stem, f.kind, f.names, block_format_of(f, supercompression)});
    }
    if (progress)
        progress("baking " + std::to_string(maps.normal.width) + "x" + std::to_string(maps.normal.height) + " " +
                 in.normal_name);
    // Texels of every level, for the fraction done; the rows arrive from several threads.
    double total_texels = 0;
    for (int L = 0; L < shape.levels; ++L)
        total_texels += double(std::max(1, shape.width >> L)) * double(std::max(1, shape.height >> L));
    std::atomic<size_t> texels_done{0};
    // zstd-supercompressed KTX2 files compress their levels' rows as the bake finishes them, top down, so
    // neither a whole level's raw bytes nor the raw file are held (io::EncodedTexture::compress_rows).
    std::vector<size_t> streamed;
    for (size_t i = 0; i < files.size(); ++i)
        if (out.textures[i]->supercompressed() && out.files[i].block == io::BlockFormat::None) streamed.push_back(i);
    std::optional<Error> stream_error;
    std::mutex stream_error_lock;
    const TextureBakeRowsDone rows_done = [&](int level, int rows) {
        tbb::parallel_for(size_t(0), streamed.size(), [&](size_t k) {
            if (auto ok = out.textures[streamed[k]]->compress_rows(level, rows); !ok) {
                std::lock_guard<std::mutex> lock(stream_error_lock);
                if (!stream_error) stream_error = make_error(files[streamed[k]].stem + ": " + ok.error().message);
            }
        });
    };
    // The 8-bit maps' rows are returned to the system once the bake is past them (the job's own buffers).
    const TextureBakeInputsDone release_inputs = [&](int rows) {
        if (!in.release_rows) return;
        for (const TextureMap* m : {&maps.normal, maps.roughness})
            if (m && m->u8 && m->height == maps.normal.height) release_pages(m->u8, size_t(rows) * m->row_stride);
    };
    auto baked = bake_texture_rows(maps.normal, maps.roughness, channel, in.roughness_value, settings,
                                   [&](const TextureBakeRows& r) {
                                       if (fraction)
                                           fraction(double(texels_done += size_t(r.width) * size_t(r.rows)) /
                                                    total_texels);
                                       for (size_t i = 0; i < files.size(); ++i)
                                           out.textures[i]->put_block(r.level, r.x0, r.y0, r.width, r.rows,
                                                                      rows_of(r, files[i].chain),
                                                                     chain_channels(shape, files[i].chain),
                                                                     files[i].first);
                                   },
                                   streamed.empty() ? TextureBakeRowsDone{} : rows_done, release_inputs);
    if (!baked) return name_error(baked.error(), in.normal_name, in.roughness_name);
    if (stream_error) return *stream_error;
    out.notes = baked->notes;
    out.max_roughness_change = baked->max_roughness_change;
    return out;
}

Result<TextureOutputsWritten> write_texture_outputs(TextureBakeResult&& baked, const TextureInputs& in,
                                                    const TextureBakeSettings& settings,
                                                    io::TextureContainer container, const fs::path& dir,
                                                    const std::string& stem, const ProgressFn& progress,
                                                    const io::Supercompression& supercompression) {
    TextureOutputsWritten result;
    result.notes = baked.notes;
    result.max_roughness_change = baked.max_roughness_change;
    TextureBakeShape shape;
    shape.roughness_channels = baked.roughness.channels();
    shape.kernel_channels = baked.kernel.channels();
    shape.lean_channels = baked.lean.channels();
    shape.normal_channels = baked.normal.channels();
    const std::vector<OutputFile> files = output_files(shape, in, settings, stem, container, supercompression);
    for (size_t i = 0; i < files.size(); ++i) {
        const OutputFile& f = files[i];
        if (progress) progress("writing " + f.stem);
        MipChain& chain = chain_of(baked, f.chain);
        const bool whole = f.first == 0 && f.channels == chain.channels();
        if (auto ok = append(result.outputs,
                             io::write_texture(whole ? chain : channel_subset(chain, f.first, f.channels), f.encoding,
                                               container, dir, f.stem, f.kind, f.names, settings.wrap,
                                               supercompression, block_format_of(f, supercompression)));
            !ok)
            return ok.error();
        // Written: release the chain before the next one is encoded, unless a later file reads it too.
        if (i + 1 == files.size() || files[i + 1].chain != f.chain) chain = MipChain{};
    }
    return result;
}

Result<TextureJobOutcome> run_texture_job(const TextureJob& job) {
    const ProgressFn& progress = job.progress;
    std::error_code ec;
    if (job.output_dir.empty()) return make_error("no output folder given");
    if (const std::string p = io::block_container_problem(job.container, job.supercompression.block); !p.empty())
        return make_error(p);
    for (const fs::path& p : {job.output_dir, job.demo ? fs::path() : job.normal, job.roughness.value_or(fs::path())})
        if (auto r = io::check_utf8_path(p); !r) return r.error();
    if (fs::exists(job.output_dir, ec) && !fs::is_directory(job.output_dir, ec))
        return make_error(job.output_dir.string() + ": exists and is not a folder");

    if (!job.demo) {
        std::vector<fs::path> inputs{job.normal};
        if (job.roughness) inputs.push_back(*job.roughness);
        if (auto ok = io::check_output_not_input(job.output_dir, inputs); !ok) return ok.error();
    }
    auto out = BakeOutput::open(job.output_dir, job.lock,
                                {job.demo ? std::string(kDemoIdentity) : job.normal.string()}, job.replace,
                                progress);
    if (!out) return out.error();
    const fs::path& stage = out->stage();

    io::Manifest manifest;
    manifest.version = tool_version();
    manifest.settings = texture_settings_json(job.settings, job.container);
    if (job.container == io::TextureContainer::Ktx2 || job.supercompression.block != io::BlockFamily::None)
        manifest.settings["supercompression"] = supercompression_json(job.supercompression);

    TextureInputs in;
    io::DecodedImage normal, roughness;
    if (job.demo) {
        normal.image = demo_normal_map();
        roughness.image = demo_orm_map();
        in.normal_name = "demo_normal.png";
        in.roughness_name = "demo_orm.png";
        manifest.settings["demo"] = true;
        // The generated inputs are written beside the outputs, so the bake can be inspected and repeated
        // with --normal/--roughness.
        for (const auto& [image, name] : {std::pair{&normal.image, in.normal_name},
                                          std::pair{&roughness.image, in.roughness_name}}) {
            const fs::path path = stage / name;
            if (auto ok = io::write_image(path, *image, 8); !ok) return out->final_names(ok.error());
            auto hash = io::sha256_file(path);
            if (!hash) return hash.error();
            manifest.inputs.push_back({name, *hash});
        }
    } else {
        if (progress) progress("reading " + job.normal.string());
        if (job.roughness && progress) progress("reading " + job.roughness->string());
        // The two maps are decoded and hashed side by side, each file by one task. The row-streaming bake
        // (KTX2, DDS) reads 8-bit maps as bytes, a quarter of the float images' memory.
        const bool keep_8bit = io::EncodedTexture::supports(job.container);
        Result<io::DecodedImage> n = make_error(""), r = make_error("");
        Result<std::string> n_hash = make_error(""), r_hash = make_error("");
        tbb::parallel_invoke(
            [&] {
                n = io::decode_image(job.normal, keep_8bit);
                if (n) n_hash = io::sha256_file(job.normal);
            },
            [&] {
                if (!job.roughness) return;
                r = io::decode_image(*job.roughness, keep_8bit);
                if (r) r_hash = io::sha256_file(*job.roughness);
            });
        if (!n) return n.error();
        if (!n_hash) return n_hash.error();
        normal = std::move(*n);
        in.normal_name = job.normal.string();
        manifest.inputs.push_back({job.normal.string(), *n_hash});
        if (job.roughness) {
            if (!r) return r.error();
            if (!r_hash) return r_hash.error();
            roughness = std::move(*r);
            in.roughness_name = job.roughness->string();
            manifest.inputs.push_back({job.roughness->string(), *r_hash});
        }
    }
    const bool have_roughness = job.demo || job.roughness.has_value();
    // Non-finite texels are reported by the bake's validation, with the file's name.
    auto bytes_map = [](const io::Bytes8& b) {
        return TextureMap{b.width, b.height, b.channels, b.row_bytes, nullptr, b.data.data() + b.offset};
    };
    in.normal = &normal.image;
    if (!normal.bytes8.empty()) in.normal = nullptr, in.normal_map = bytes_map(normal.bytes8);
    in.release_rows = true;  // the job's own buffers, dropped after the bake
    in.normal_bits = normal.info.is_float ? 16 : normal.info.bits_per_channel;
    if (have_roughness) {
        in.roughness = &roughness.image;
        if (!roughness.bytes8.empty()) in.roughness = nullptr, in.roughness_map = bytes_map(roughness.bytes8);
        in.roughness_bits = roughness.info.is_float ? 16 : roughness.info.bits_per_channel;
    }
    in.roughness_channel = job.roughness_channel;
    in.roughness_value = job.roughness_value;
    if (!have_roughness) manifest.settings["roughness_value"] = job.roughness_value;
    else manifest.settings["roughness_channel"] = job.roughness_channel;

    Result<TextureOutputsWritten> written = make_error("");
    if (io::EncodedTexture::supports(job.container)) {
        // KTX2 and DDS: the decoded inputs are released once baked, before the files are packed and written,
        // so the inputs, the encoded files and the packed files are never all held at once.
        auto encoded = bake_texture_encoded(in, job.settings, job.container, "texture", progress, job.fraction,
                                            job.supercompression);
        if (!encoded) return out->final_names(encoded.error());
        normal.image = Image{}, normal.bytes8 = io::Bytes8{};
        roughness.image = Image{}, roughness.bytes8 = io::Bytes8{};
        if (progress)
            for (const io::EncodedFile& f : encoded->files) progress("writing " + f.stem);
        auto files = io::write_encoded_textures(encoded->files, stage);
        if (!files) return out->final_names(files.error());
        written = TextureOutputsWritten{std::move(*files), encoded->notes, encoded->max_roughness_change};
    } else {
        written = bake_texture_outputs(in, job.settings, job.container, stage, "texture", progress, job.fraction,
                                       job.supercompression);
    }
    if (!written) return out->final_names(written.error());

    // The plan (SPEC Sec. 6): would the bake change roughness visibly, i.e. by half a quantisation step?
    const int bits = (have_roughness ? in.roughness_bits : in.normal_bits) <= 8 ? 8 : 16;
    const double half_step = 0.5 / double((1 << bits) - 1);
    const bool visible = written->max_roughness_change >= half_step;
    nlohmann::json decision;
    decision["target"] = in.normal_name;
    decision["action"] = "texture bake";
    decision["max_roughness_change"] = written->max_roughness_change;
    decision["half_quantisation_step"] = half_step;
    decision["reason"] = visible ? "requested; the bake changes roughness by more than half a quantisation step"
                                 : "requested; the bake changes roughness by less than half a quantisation step "
                                   "(the outputs equal plain mipmapping of alpha^2 after quantisation)";
    manifest.plan.push_back(decision);
    const TextureBakeNotes& notes = written->notes;
    nlohmann::json facts;
    facts["z_reconstructed"] = notes.z_reconstructed;
    if (notes.z_reconstructed) facts["z_reason"] = notes.z_reason;
    facts["z_decode"] = notes.z_decode;
    facts["looks_srgb"] = notes.looks_srgb;
    facts["roughness_is_orm"] = notes.roughness_is_orm;
    facts["roughness_resampled"] = notes.roughness_resampled;
    facts["normal_color_space_claimed"] = normal.info.color_space;
    manifest.settings["input_facts"] = facts;

    manifest.outputs = written->outputs;
    if (progress) progress("writing manifest.json");
    if (auto ok = io::write_manifest(stage, manifest); !ok) return out->final_names(ok.error());
    if (auto ok = out->commit(); !ok) return ok.error();

    TextureJobOutcome outcome;
    outcome.manifest = std::move(manifest);
    outcome.notes = notes;
    outcome.max_roughness_change = written->max_roughness_change;
    return outcome;
}

}  // namespace specbake
