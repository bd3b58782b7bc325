#include "cli/job_texture.h"

#include "cli/version.h"
#include "io/atomic_file.h"
#include "io/image_io.h"
#include "io/sha256.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

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

io::TexelEncoding unorm_for_bits(int bits) {
    return bits <= 8 ? io::TexelEncoding::Unorm8 : io::TexelEncoding::Unorm16;
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
    j["reconstruct_z"] = s.reconstruct_z == ReconstructZ::Auto ? "auto"
                         : s.reconstruct_z == ReconstructZ::Always ? "always" : "never";
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
    int channel = in.roughness_channel;
    if (in.roughness && channel < 0) channel = in.roughness->channels >= 3 ? 1 : 0;
    if (progress)
        progress("baking " + std::to_string(in.normal->width) + "x" + std::to_string(in.normal->height) + " " +
                 in.normal_name);
    auto baked = bake_texture(*in.normal, in.roughness, channel, in.roughness_value, settings);
    if (!baked) return name_error(baked.error(), in.normal_name, in.roughness_name);
    return baked;
}

Result<TextureOutputsWritten> bake_texture_outputs(const TextureInputs& in, const TextureBakeSettings& settings,
                                                   io::TextureContainer container, const fs::path& dir,
                                                   const std::string& stem, const ProgressFn& progress) {
    auto baked = bake_texture_inputs(in, settings, progress);
    if (!baked) return baked.error();
    return write_texture_outputs(std::move(*baked), in, settings, container, dir, stem, progress);
}

Result<TextureOutputsWritten> write_texture_outputs(TextureBakeResult&& baked, const TextureInputs& in,
                                                    const TextureBakeSettings& settings,
                                                    io::TextureContainer container, const fs::path& dir,
                                                    const std::string& stem, const ProgressFn& progress) {
    TextureOutputsWritten result;
    result.notes = baked.notes;
    result.max_roughness_change = baked.max_roughness_change;
    const WrapMode wrap = settings.wrap;
    const int roughness_bits = in.roughness ? in.roughness_bits : in.normal_bits;
    auto say = [&](const std::string& what) {
        if (progress) progress("writing " + what);
    };
    if (settings.outputs.roughness) {
        say(stem + "_roughness");
        const std::vector<std::string> names =
            baked.roughness.channels() == 3 ? std::vector<std::string>{"R", "G", "B"} : std::vector<std::string>{"Y"};
        if (auto ok = append(result.outputs, io::write_texture(baked.roughness, unorm_for_bits(roughness_bits),
                                                               container, dir, stem + "_roughness", "roughness",
                                                               names, wrap));
            !ok)
            return ok.error();
        baked.roughness = MipChain{};  // written: release it before the next chain is encoded
    }
    if (settings.outputs.kernel) {
        say(stem + "_kernel");
        const std::vector<std::string> names = settings.anisotropic ? std::vector<std::string>{"xx", "yy", "xy"}
                                                                    : std::vector<std::string>{"t"};
        if (auto ok = append(result.outputs, io::write_texture(baked.kernel, io::TexelEncoding::Float16, container,
                                                               dir, stem + "_kernel", "kernel", names, wrap));
            !ok)
            return ok.error();
        baked.kernel = MipChain{};
    }
    if (settings.outputs.normal) {
        say(stem + "_normal");
        if (auto ok = append(result.outputs, io::write_texture(baked.normal, unorm_for_bits(in.normal_bits),
                                                               container, dir, stem + "_normal", "normal",
                                                               {"R", "G", "B"}, wrap));
            !ok)
            return ok.error();
        baked.normal = MipChain{};
    }
    if (settings.outputs.lean) {
        say(stem + "_lean");
        // Slope-space moments are unbounded (|s| grows as 1/n.z), so they get full float precision.
        const io::TexelEncoding enc =
            settings.lean_space == LeanSpace::Slope ? io::TexelEncoding::Float32 : io::TexelEncoding::Float16;
        const std::vector<std::string> names{"m.x", "m.y", "M.xx", "M.yy", "M.xy"};
        if (container == io::TextureContainer::Exr) {
            if (auto ok = append(result.outputs,
                                 io::write_texture(baked.lean, enc, container, dir, stem + "_lean", "lean", names, wrap));
                !ok)
                return ok.error();
        } else {
            if (auto ok = append(result.outputs, io::write_texture(channel_subset(baked.lean, 0, 4), enc, container,
                                                                   dir, stem + "_lean", "lean",
                                                                   {names.begin(), names.begin() + 4}, wrap));
                !ok)
                return ok.error();
            if (auto ok = append(result.outputs, io::write_texture(channel_subset(baked.lean, 4, 1), enc, container,
                                                                   dir, stem + "_lean_xy", "lean", {"M.xy"}, wrap));
                !ok)
                return ok.error();
        }
    }
    return result;
}

Result<TextureJobOutcome> run_texture_job(const TextureJob& job) {
    const ProgressFn& progress = job.progress;
    std::error_code ec;
    if (job.output_dir.empty()) return make_error("no output folder given");
    if (fs::exists(job.output_dir, ec) && !fs::is_directory(job.output_dir, ec))
        return make_error(job.output_dir.string() + ": exists and is not a folder");

    io::Manifest manifest;
    manifest.version = tool_version();
    manifest.settings = texture_settings_json(job.settings, job.container);

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
            const fs::path path = job.output_dir / name;
            if (auto ok = io::write_image(path, *image, 8); !ok) return ok.error();
            auto hash = io::sha256_file(path);
            if (!hash) return hash.error();
            manifest.inputs.push_back({name, *hash});
        }
    } else {
        std::vector<fs::path> inputs{job.normal};
        if (job.roughness) inputs.push_back(*job.roughness);
        if (auto ok = io::check_output_not_input(job.output_dir, inputs); !ok) return ok.error();
        if (progress) progress("reading " + job.normal.string());
        auto n = io::decode_image(job.normal);
        if (!n) return n.error();
        normal = std::move(*n);
        in.normal_name = job.normal.string();
        if (job.roughness) {
            if (progress) progress("reading " + job.roughness->string());
            auto r = io::decode_image(*job.roughness);
            if (!r) return r.error();
            roughness = std::move(*r);
            in.roughness_name = job.roughness->string();
        }
        for (const fs::path& p : inputs) {
            auto hash = io::sha256_file(p);
            if (!hash) return hash.error();
            manifest.inputs.push_back({p.string(), *hash});
        }
    }
    const bool have_roughness = job.demo || job.roughness.has_value();
    if (auto bad = find_non_finite(normal.image))
        return make_error(in.normal_name + ": NaN or infinite value at texel (" + std::to_string(bad->first) + ", " +
                          std::to_string(bad->second) + ")");
    if (have_roughness) {
        if (auto bad = find_non_finite(roughness.image))
            return make_error(in.roughness_name + ": NaN or infinite value at texel (" + std::to_string(bad->first) +
                              ", " + std::to_string(bad->second) + ")");
    }
    in.normal = &normal.image;
    in.normal_bits = normal.info.is_float ? 16 : normal.info.bits_per_channel;
    if (have_roughness) {
        in.roughness = &roughness.image;
        in.roughness_bits = roughness.info.is_float ? 16 : roughness.info.bits_per_channel;
    }
    in.roughness_channel = job.roughness_channel;
    in.roughness_value = job.roughness_value;
    if (!have_roughness) manifest.settings["roughness_value"] = job.roughness_value;
    else manifest.settings["roughness_channel"] = job.roughness_channel;

    auto written = bake_texture_outputs(in, job.settings, job.container, job.output_dir, "texture", progress);
    if (!written) return written.error();

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
    facts["looks_srgb"] = notes.looks_srgb;
    facts["roughness_is_orm"] = notes.roughness_is_orm;
    facts["roughness_resampled"] = notes.roughness_resampled;
    facts["normal_color_space_claimed"] = normal.info.color_space;
    manifest.settings["input_facts"] = facts;

    manifest.outputs = written->outputs;
    if (progress) progress("writing manifest.json");
    if (auto ok = io::write_manifest(job.output_dir, manifest); !ok) return ok.error();

    TextureJobOutcome outcome;
    outcome.manifest = std::move(manifest);
    outcome.notes = notes;
    outcome.max_roughness_change = written->max_roughness_change;
    return outcome;
}

}  // namespace specbake
