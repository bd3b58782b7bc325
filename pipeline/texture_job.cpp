#include "pipeline/texture_job.h"

#include "io/output/bake_output.h"
#include "pipeline/version.h"
#include "io/texture/block_compress.h"
#include "io/files/input_policy.h"
#include "io/image/image_io.h"
#include "io/files/sha256.h"
#include "core/huge_pages.h"

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
io::TexelEncoding encoding_for_bits(int bits, const io::TextureFileFormat& format) {
    if (bits <= 8) return io::TexelEncoding::Unorm8;
    if (format.container == io::TextureContainer::PngPerMip || format.supercompression.block != io::BlockFamily::None)
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
// channels, the same in every container; docs/texture-bake.md#output-layouts): `<stem>_roughness` (Y = r, or the ORM
// map as RGBA with G = r and A = 1), `_kernel` (Y = t, or RGBA = xx, yy, xy, rough share), `_normal` (RGBA = normalised
// mean normal as (n + 1) / 2, A = 1: a drop-in for glTF normalTexture and engine shaders that read .xyz;
// zstd removes the constant A almost entirely, and the two-channel form belongs to BC5),
// `_lean` (RGBA = m.x, m.y, M.xx, M.yy) plus `_lean_xy` (Y = M.xy). `names` are the channels' meanings.
std::vector<OutputFile> output_files(const TextureBakeShape& shape, const TextureInputs& in,
                                     const TextureBakeSettings& settings, const std::string& stem,
                                     const io::TextureFileFormat& format) {
    std::vector<OutputFile> files;
    const bool have_roughness = in.roughness || in.roughness_map.channels > 0;
    const int roughness_bits = have_roughness ? in.roughness_bits : in.normal_bits;
    if (settings.outputs.roughness) {
        files.push_back({Chain::Roughness, "roughness", stem + "_roughness",
                         encoding_for_bits(roughness_bits, format), 0,
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
                         encoding_for_bits(in.normal_bits, format), 0, 3,
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

// The block format of `f` when block compression is asked (io/texture/block_compress.h): unorm data only, one
// channel BC4, the mean normal BC5 (x, y; z = sqrt(1 - x^2 - y^2) at run time), four channels BC1 or BC3;
// ASTC keeps the same channels (io/texture/astc_codec.h).
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
    detail::advise_whole_pages(p, bytes, uintptr_t(sysconf(_SC_PAGESIZE)), MADV_DONTNEED);
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
// The demo maps as written beside its outputs.
constexpr const char* kDemoNormalName = "demo_normal.png";
constexpr const char* kDemoOrmName = "demo_orm.png";
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

nlohmann::json texture_settings_json(const TextureBakeSettings& s, const io::TextureFileFormat& format) {
    nlohmann::json j;
    j["format"] = io::container_name(format.container);
    j["isotropic"] = std::string(to_string(s.isotropic));
    j["filter"] = std::string(to_string(s.filter));
    j["max_kernel"] = s.max_kernel ? nlohmann::json(*s.max_kernel) : nlohmann::json(nullptr);
    j["normal_y"] = std::string(to_string(s.normal_y));
    j["reconstruct_z"] = std::string(to_string(s.reconstruct_z));
    j["wrap"] = std::string(to_string(format.wrap));
    j["anisotropic"] = s.anisotropic;
    j["lean_space"] = std::string(to_string(s.lean_space));
    nlohmann::json outs = nlohmann::json::array();
    for (std::string_view name : to_names(s.outputs)) outs.push_back(std::string(name));
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

TextureJobRecord texture_job_record(const TextureJob& job) {
    TextureJobRecord record;
    const io::TextureFileFormat& format = job.texture_format;
    record.settings = texture_settings_json(job.settings, format);
    if (format.container == io::TextureContainer::Ktx2 || format.supercompression.block != io::BlockFamily::None)
        record.settings["supercompression"] = supercompression_json(format.supercompression);
    if (job.demo) {
        record.settings["demo"] = true;
        record.inputs = {kDemoNormalName, kDemoOrmName};
    } else {
        record.inputs.push_back(io::recorded_input_path(job.normal, job.output_dir));
        if (job.roughness) record.inputs.push_back(io::recorded_input_path(*job.roughness, job.output_dir));
    }
    if (job.demo || job.roughness) record.settings["roughness_channel"] = job.roughness_channel;
    else record.settings["roughness_value"] = job.roughness_value;
    return record;
}

Result<TextureOutputsWritten> bake_texture_outputs(const TextureInputs& in, const TextureBakeSettings& settings,
                                                   const io::TextureFileFormat& format, const fs::path& dir,
                                                   const std::string& stem, const ProgressFn& progress,
                                                   const FractionFn& fraction) {
    auto encoded = bake_texture_encoded(in, settings, format, stem, progress, fraction, dir);
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
                                                   const io::TextureFileFormat& format, const std::string& stem,
                                                   const ProgressFn& progress, const FractionFn& fraction,
                                                   const fs::path& stream_dir) {
    const io::TextureContainer container = format.container;
    const io::Supercompression& supercompression = format.supercompression;
    const InputMaps maps = maps_of(in);
    if (maps.normal.channels == 0) return make_error(in.normal_name + ": no normal map given");
    const int channel = roughness_channel_of(in);
    const TextureBakeShape shape = texture_bake_shape(maps.normal, maps.roughness, channel, settings);
    const std::vector<OutputFile> files = output_files(shape, in, settings, stem, format);
    EncodedTextureOutputs out;
    for (const OutputFile& f : files) {
        out.textures.push_back(std::make_unique<io::EncodedTexture>(container, f.encoding, shape.width, shape.height,
                                                                    shape.levels, f.channels, supercompression,
                                                                    format.wrap));
        out.textures.back()->set_channel_meaning(f.names);
        out.files.push_back({out.textures.back().get(), f.stem, f.kind, f.names, block_format_of(f, supercompression)});
        // Block-compressed levels (BC, ASTC) are made as the rows finish.
        if (out.files.back().block != io::BlockFormat::None) out.textures.back()->set_block_format(out.files.back().block);
        // Uncompressed DDS goes to its file as the rows finish (level 0 first in the file, as baked).
        if (!stream_dir.empty() && container == io::TextureContainer::Dds && out.files.back().block == io::BlockFormat::None)
            if (auto ok = out.textures.back()->stream_to(stream_dir / (f.stem + ".dds")); !ok) return ok.error();
    }
    if (progress)
        progress("baking " + std::to_string(maps.normal.width) + "x" + std::to_string(maps.normal.height) + " " +
                 in.normal_name);
    // Texels of every level, for the fraction done; the rows arrive from several threads.
    double total_texels = 0;
    for (int L = 0; L < shape.levels; ++L)
        total_texels += double(std::max(1, shape.width >> L)) * double(std::max(1, shape.height >> L));
    std::atomic<size_t> texels_done{0};
    // zstd-supercompressed KTX2 files, per-mip PNGs and EXRs compress their levels' rows as the bake
    // finishes them, top down, and DDS files given `stream_dir` write them to the file, so neither a whole
    // level's raw bytes nor the raw file are held (a mipmapped EXR holds its levels >= 1 until level 0 is
    // written; io::EncodedTexture::compress_rows).
    std::vector<size_t> streamed;
    for (size_t i = 0; i < files.size(); ++i)
        if (out.textures[i]->streams() && out.files[i].block == out.textures[i]->block_format()) streamed.push_back(i);
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
    // The integer maps' rows are returned to the system once the bake is past them (the job's own buffers).
    const TextureBakeInputsDone release_inputs = [&](int rows) {
        if (!in.release_rows) return;
        for (const TextureMap* m : {&maps.normal, maps.roughness}) {
            if (!m || m->f32 || m->height != maps.normal.height) continue;
            const size_t values = size_t(rows) * m->row_stride;
            if (m->u8) release_pages(m->u8, values);
            else release_pages(reinterpret_cast<const uint8_t*>(m->u16), values * sizeof(uint16_t));
        }
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
                                                    const io::TextureFileFormat& format, const fs::path& dir,
                                                    const std::string& stem, const ProgressFn& progress) {
    TextureOutputsWritten result;
    result.notes = baked.notes;
    result.max_roughness_change = baked.max_roughness_change;
    TextureBakeShape shape;
    shape.roughness_channels = baked.roughness.channels();
    shape.kernel_channels = baked.kernel.channels();
    shape.lean_channels = baked.lean.channels();
    shape.normal_channels = baked.normal.channels();
    const std::vector<OutputFile> files = output_files(shape, in, settings, stem, format);
    for (size_t i = 0; i < files.size(); ++i) {
        const OutputFile& f = files[i];
        if (progress) progress("writing " + f.stem);
        MipChain& chain = chain_of(baked, f.chain);
        const bool whole = f.first == 0 && f.channels == chain.channels();
        if (auto ok = append(result.outputs,
                             io::write_texture(whole ? chain : channel_subset(chain, f.first, f.channels), f.encoding,
                                               format, dir, f.stem, f.kind, f.names,
                                               block_format_of(f, format.supercompression)));
            !ok)
            return ok.error();
        // Written: release the chain before the next one is encoded, unless a later file reads it too.
        if (i + 1 == files.size() || files[i + 1].chain != f.chain) chain = MipChain{};
    }
    return result;
}

TextureMap texture_map_of(const io::IntegerTexels& t) {
    TextureMap m{t.width, t.height, t.channels, t.row_stride};
    if (t.bits == 8) m.u8 = t.bytes.data() + t.offset;
    else m.u16 = t.words.data() + t.offset;
    return m;
}

namespace {

// The job's checks before anything is read: an output folder that can be one, no input inside it, block
// formats its container holds, UTF-8 paths.
Result<void> check_texture_job(const TextureJob& job) {
    std::error_code ec;
    if (job.output_dir.empty()) return make_error("no output folder given");
    const io::TextureFileFormat& format = job.texture_format;
    if (const std::string p = io::block_container_problem(format.container, format.supercompression.block); !p.empty())
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
    return {};
}

// The job's decoded maps, named as the manifest and error messages name them, with their manifest entries.
struct JobMaps {
    io::DecodedImage normal, roughness;
    std::string normal_name, roughness_name;
    bool have_roughness = false;
    std::vector<io::ManifestInput> entries;
};

// The demo maps, written into `out`'s staging folder beside the outputs, so the bake can be inspected and
// repeated with --normal/--roughness.
Result<void> make_demo_maps(const io::BakeOutput& out, JobMaps& maps) {
    maps.normal.image = demo_normal_map();
    maps.roughness.image = demo_orm_map();
    maps.normal_name = kDemoNormalName;
    maps.roughness_name = kDemoOrmName;
    maps.have_roughness = true;
    for (const auto& [image, name] : {std::pair{&maps.normal.image, maps.normal_name},
                                      std::pair{&maps.roughness.image, maps.roughness_name}}) {
        const fs::path path = out.stage() / name;
        if (auto ok = io::write_image(path, *image, 8); !ok) return out.final_names(ok.error());
        auto hash = io::sha256_file(path);
        if (!hash) return hash.error();
        maps.entries.push_back({name, *hash});
    }
    return {};
}

// The job's map files, decoded and hashed side by side, each file by one task. The row-streaming bake
// reads plain PNG maps as their 8- or 16-bit integers, a quarter or half of the float images' memory.
Result<void> read_job_maps(const TextureJob& job, JobMaps& maps) {
    if (job.progress) job.progress("reading " + job.normal.string());
    if (job.roughness && job.progress) job.progress("reading " + job.roughness->string());
    Result<io::DecodedImage> n = make_error(""), r = make_error("");
    Result<std::string> n_hash = make_error(""), r_hash = make_error("");
    tbb::parallel_invoke(
        [&] {
            n = io::decode_image(job.normal, job.limits, true);
            if (n) n_hash = io::sha256_file(job.normal);
        },
        [&] {
            if (!job.roughness) return;
            r = io::decode_image(*job.roughness, job.limits, true);
            if (r) r_hash = io::sha256_file(*job.roughness);
        });
    if (!n) return n.error();
    if (!n_hash) return n_hash.error();
    maps.normal = std::move(*n);
    maps.normal_name = job.normal.string();
    maps.entries.push_back({io::recorded_input_path(job.normal, job.output_dir), *n_hash});
    if (job.roughness) {
        if (!r) return r.error();
        if (!r_hash) return r_hash.error();
        maps.roughness = std::move(*r);
        maps.roughness_name = job.roughness->string();
        maps.have_roughness = true;
        maps.entries.push_back({io::recorded_input_path(*job.roughness, job.output_dir), *r_hash});
    }
    return {};
}

// The bake's view of `maps` (which must stay where they are while it is used): the integer texels where the
// decoder kept them, else the float images. Non-finite texels are reported by the bake's validation.
TextureInputs texture_inputs_of(const JobMaps& maps, const TextureJob& job) {
    TextureInputs in;
    in.normal_name = maps.normal_name;
    in.roughness_name = maps.roughness_name;
    in.normal = &maps.normal.image;
    if (!maps.normal.integers.empty()) in.normal = nullptr, in.normal_map = texture_map_of(maps.normal.integers);
    in.release_rows = true;  // the job's own buffers, dropped after the bake
    in.normal_bits = maps.normal.info.is_float ? 16 : maps.normal.info.bits_per_channel;
    if (maps.have_roughness) {
        in.roughness = &maps.roughness.image;
        if (!maps.roughness.integers.empty())
            in.roughness = nullptr, in.roughness_map = texture_map_of(maps.roughness.integers);
        in.roughness_bits = maps.roughness.info.is_float ? 16 : maps.roughness.info.bits_per_channel;
    }
    in.roughness_channel = job.roughness_channel;
    in.roughness_value = job.roughness_value;
    return in;
}

// Bakes `in` and writes the outputs into `out`'s staging folder. The decoded maps are
// released once baked, before the files are packed and written, so the inputs, the encoded files and the
// packed files are never all held at once. Errors name the final files.
Result<TextureOutputsWritten> bake_job_outputs(const TextureJob& job, const TextureInputs& in, JobMaps& maps,
                                               const io::BakeOutput& out) {
    auto encoded = bake_texture_encoded(in, job.settings, job.texture_format, "texture", job.progress, job.fraction,
                                        out.stage());
    if (!encoded) return out.final_names(encoded.error());
    maps.normal.image = Image{}, maps.normal.integers = io::IntegerTexels{};
    maps.roughness.image = Image{}, maps.roughness.integers = io::IntegerTexels{};
    if (job.progress)
        for (const io::EncodedFile& f : encoded->files) job.progress("writing " + f.stem);
    auto files = io::write_encoded_textures(encoded->files, out.stage());
    if (!files) return out.final_names(files.error());
    return TextureOutputsWritten{std::move(*files), encoded->notes, encoded->max_roughness_change};
}

// The plan's entry (SPEC Sec. 6): would the bake change roughness visibly, i.e. by half a quantisation step?
nlohmann::json texture_decision(const TextureInputs& in, bool have_roughness, double max_roughness_change) {
    const int bits = (have_roughness ? in.roughness_bits : in.normal_bits) <= 8 ? 8 : 16;
    const double half_step = 0.5 / double((1 << bits) - 1);
    const bool visible = max_roughness_change >= half_step;
    nlohmann::json decision;
    decision["target"] = in.normal_name;
    decision["action"] = "texture bake";
    decision["max_roughness_change"] = max_roughness_change;
    decision["half_quantisation_step"] = half_step;
    decision["reason"] = visible ? "requested; the bake changes roughness by more than half a quantisation step"
                                 : "requested; the bake changes roughness by less than half a quantisation step "
                                   "(the outputs equal plain mipmapping of alpha^2 after quantisation)";
    return decision;
}

// The manifest's "input_facts": what the bake noticed about its inputs.
nlohmann::json input_facts(const TextureBakeNotes& notes, const std::string& normal_color_space) {
    nlohmann::json facts;
    facts["z_reconstructed"] = notes.z_reconstructed;
    if (notes.z_reconstructed) facts["z_reason"] = notes.z_reason;
    facts["z_decode"] = notes.z_decode;
    facts["looks_srgb"] = notes.looks_srgb;
    facts["roughness_is_orm"] = notes.roughness_is_orm;
    facts["roughness_resampled"] = notes.roughness_resampled;
    facts["normal_color_space_claimed"] = normal_color_space;
    return facts;
}

}  // namespace

Result<TextureJobOutcome> run_texture_job(const TextureJob& job) {
    if (auto ok = check_texture_job(job); !ok) return ok.error();
    auto out = io::BakeOutput::open(job.output_dir, job.lock,
                                    {job.demo ? std::string(io::kDemoIdentity)
                                              : io::recorded_input_path(job.normal, job.output_dir)},
                                    job.replace,
                                    job.progress);
    if (!out) return out.error();

    io::Manifest manifest;
    manifest.version = tool_version();
    manifest.settings = texture_job_record(job).settings;
    JobMaps maps;
    if (auto ok = job.demo ? make_demo_maps(*out, maps) : read_job_maps(job, maps); !ok) return ok.error();
    manifest.inputs = maps.entries;
    const TextureInputs in = texture_inputs_of(maps, job);
    auto written = bake_job_outputs(job, in, maps, *out);
    if (!written) return written.error();

    manifest.plan.push_back(texture_decision(in, maps.have_roughness, written->max_roughness_change));
    if (!job.demo) manifest.plan.back()["target"] = io::recorded_input_path(job.normal, job.output_dir);
    manifest.settings["input_facts"] = input_facts(written->notes, maps.normal.info.color_space);
    manifest.outputs = written->outputs;
    if (job.progress) job.progress("writing manifest.json");
    if (auto ok = io::write_manifest(out->stage(), manifest); !ok) return out->final_names(ok.error());
    if (auto ok = out->commit(); !ok) return ok.error();

    TextureJobOutcome outcome;
    outcome.manifest = std::move(manifest);
    outcome.notes = written->notes;
    outcome.max_roughness_change = written->max_roughness_change;
    return outcome;
}

}  // namespace specbake
