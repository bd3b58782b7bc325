// specbake texture: bakes one normal map (+ roughness) into filtered roughness, kernel, LEAN and
// mean-normal mip chains (SPEC Sec. 3, 7). Only argument parsing and printing live here; the pipeline
// is pipeline/texture_job.h.
#include "cli/block_options.h"
#include "cli/command.h"
#include "cli/name_options.h"
#include "io/output/bake_output.h"
#include "pipeline/texture_job.h"
#include "cli/pipeline_options.h"
#include "cli/progress.h"
#include "pipeline/version.h"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

namespace specbake::cli {
namespace {
namespace fs = std::filesystem;

struct TextureOptions {
    std::string normal;
    std::string roughness;
    std::optional<float> roughness_value;
    std::string output;
    std::string format = "ktx2";
    std::string supercompression = "zstd";
    int zstd_level = 3;
    BlockCliOptions blocks;
    std::string isotropic = "mean";
    std::string filter = "projected";
    std::optional<double> max_kernel;
    std::string normal_y = "+y";
    std::string reconstruct_z = "auto";
    std::string wrap = "repeat";
    bool anisotropic = true;
    std::string lean_space = "projected";
    std::string outputs = "roughness,kernel,lean,normal";
    bool demo = false;
};

// "FILE[:channel]" with channel 0-3 or r/g/b/a. A path that exists as given is never split.
bool parse_roughness(const std::string& arg, fs::path& file, int& channel) {
    std::error_code ec;
    channel = -1;
    file = arg;
    const size_t colon = arg.rfind(':');
    if (colon == std::string::npos || fs::exists(arg, ec)) return true;
    const std::string ch = arg.substr(colon + 1);
    static const std::string letters = "rgba";
    if (ch.size() == 1 && ch[0] >= '0' && ch[0] <= '3') channel = ch[0] - '0';
    else if (ch.size() == 1 && letters.find(char(std::tolower(ch[0]))) != std::string::npos)
        channel = int(letters.find(char(std::tolower(ch[0]))));
    else return false;
    file = arg.substr(0, colon);
    return true;
}

int run_texture(const TextureOptions& o, const PipelineFlags& pipe) {
    TextureJob job;
    job.demo = o.demo;
    if (!o.demo) {
        if (o.normal.empty()) {
            print_error("texture: --normal FILE (or --demo) is required");
            return kExitUsage;
        }
        job.normal = o.normal;
    }
    if (!o.roughness.empty()) {
        if (o.demo) {
            print_error("texture: --demo brings its own roughness; do not combine it with --roughness");
            return kExitUsage;
        }
        fs::path file;
        int channel = -1;
        if (!parse_roughness(o.roughness, file, channel)) {
            print_error("texture: --roughness " + o.roughness + ": the channel after ':' must be 0-3 or r, g, b, a");
            return kExitUsage;
        }
        job.roughness = file;
        job.roughness_channel = channel;
    }
    if (o.roughness_value) job.roughness_value = *o.roughness_value;
    job.output_dir = o.output;
    job.texture_format.container = *io::parse_container(o.format);
    job.limits = run_settings().input_policy.limits;
    job.texture_format.supercompression.zstd = o.supercompression == "zstd";
    job.texture_format.supercompression.zstd_level = o.zstd_level;
    job.texture_format.wrap = *parse_wrap_mode(o.wrap);
    if (auto ok = apply_block_options(o.blocks, "--format", job.texture_format); !ok) {
        print_error("texture: " + ok.error().message);
        return kExitUsage;
    }
    // The options' checks accept only the enums' names.
    TextureBakeSettings& s = job.settings;
    s.isotropic = *parse_isotropic_reduction(o.isotropic);
    s.filter = *parse_roughness_filter_mode(o.filter);
    s.max_kernel = o.max_kernel;
    s.normal_y = *parse_normal_green(o.normal_y);
    s.reconstruct_z = *parse_reconstruct_z(o.reconstruct_z);
    s.anisotropic = o.anisotropic;
    s.lean_space = *parse_lean_space(o.lean_space);
    s.threads = run_settings().jobs;
    auto outputs = parse_texture_outputs(o.outputs);
    if (!outputs || to_names(*outputs).empty()) {
        print_error("texture: --outputs " + o.outputs + ": expected a comma list of roughness, kernel, lean, normal");
        return kExitUsage;
    }
    s.outputs = *outputs;
    TextureJobRecord record = texture_job_record(job);
    std::vector<std::string>& inputs = record.inputs;
    std::vector<fs::path> input_files;
    if (!job.demo) input_files.push_back(job.normal);
    if (job.roughness) input_files.push_back(*job.roughness);
    auto lock = io::lock_output_folder(job.output_dir, pipe.depfile, input_files,
                                       [](const std::string& line) { print_info(line); });
    if (!lock) {
        print_error(lock.error().message);
        return kExitFailed;
    }
    if (skip_if_up_to_date({job.output_dir, inputs, record.settings, tool_version(), {"input_facts"}}, pipe))
        return kExitOk;
    job.lock = &*lock;
    job.replace = pipe.force;
    const bool quiet = run_settings().verbosity == Verbosity::quiet;
    // A bar with the fraction of texels baked on a terminal. Elsewhere the steps are printed with
    // --verbose only, so a failed run's stderr stays its one error line.
    ProgressMode mode = progress_mode(run_settings());
    if (mode == ProgressMode::lines && run_settings().verbosity != Verbosity::verbose) mode = ProgressMode::off;
    ProgressDisplay display(1, mode, "maps");
    const std::string item = job.demo ? std::string("demo") : job.normal.string();
    job.progress = [&display, &item](const std::string& line) { display.status(item, line); };
    job.fraction = [&display](double f) { display.fraction(f); };

    auto outcome = run_texture_job(job);
    display.finished(item, outcome ? "done" : "FAILED");
    display.close();
    if (!outcome) {
        print_error(outcome.error().message);
        return kExitFailed;
    }
    for (const std::string& w : outcome->notes.warnings) print_warning(w);
    for (const io::ManifestInput& in : outcome->manifest.inputs) inputs.push_back(in.path);
    if (auto d = write_manifest_depfile(pipe, job.output_dir, inputs); !d) {
        print_error(d.error().message);
        return kExitFailed;
    }
    if (outcome->notes.z_reconstructed)
        std::fprintf(stderr, "specbake: note: z reconstructed from x and y (%s); a glTF viewer shades the stored "
                     "blue channel (--reconstruct-z gltf)\n", outcome->notes.z_reason.c_str());
    if (!quiet) {
        for (const io::ManifestOutput& out : outcome->manifest.outputs)
            std::printf("%-9s %s  %dx%d, %d mips, %d channels\n", out.kind.c_str(),
                        (fs::path(o.output) / out.path).string().c_str(), out.width, out.height, out.mips,
                        out.channels);
        std::printf("manifest  %s\n", (fs::path(o.output) / "manifest.json").string().c_str());
        std::printf("max roughness change over plain mipmapping: %.5f\n", outcome->max_roughness_change);
    }
    return kExitOk;
}

}  // namespace

void add_texture_command(CLI::App& app, std::function<int()>& run) {
    auto* sub = app.add_subcommand(
        "texture",
        "Bake a normal map (and roughness) into filtered roughness, kernel, LEAN and mean-normal mips.");
    auto o = std::make_shared<TextureOptions>();
    sub->add_option("--normal", o->normal,
                    "Tangent-space normal map: PNG (8/16-bit), JPEG, TGA, TIFF, EXR, ... 2, 3 or 4 channels");
    sub->add_option("--roughness", o->roughness,
                    "Roughness map FILE[:channel] (channel 0-3 or r/g/b/a). Default channel: G for 3+ channel "
                    "files (glTF ORM: R and B are carried through), else the first. Any resolution.");
    auto* value = sub->add_option("--roughness-value", o->roughness_value,
                                  "Constant perceptual roughness in [0, 1] when there is no roughness map (default 0.5)")
                      ->check(CLI::Range(0.0f, 1.0f));
    sub->get_option("--roughness")->excludes(value);
    sub->add_option("-o,--output", o->output, "Output folder (created; must not hold an input)")->required();
    sub->add_option("--format", o->format, "Container: ktx2 (default), dds, exr (tiled, mipmapped) or png "
                                           "(one file per mip; float data as EXR)")
        ->check(is_member_of(io::kTextureContainerNames));
    sub->add_option("--supercompression", o->supercompression,
                    "KTX2 level compression: zstd (default; KTX2 supercompression scheme 2) or none")
        ->check(CLI::IsMember({"zstd", "none"}));
    add_block_options(*sub, o->blocks, "outputs");
    sub->add_option("--zstd-level", o->zstd_level, "Zstandard level for KTX2, 1 (fastest) to 22 (default 3)")
        ->check(CLI::Range(1, 22));
    sub->add_option("--isotropic", o->isotropic,
                    "Kernel from the footprint covariance Sigma: mean t = tr (default), sum t = 2 tr, "
                    "max t = 2 lambda_max")
        ->check(is_member_of(kIsotropicReductionNames));
    sub->add_option("--filter", o->filter,
                    "projected: a' = (a + t(1-a)) / (1 + t(1-a)) (default, exact for GGX); approx: a' = min(1, a + t)")
        ->check(is_member_of(kRoughnessFilterModeNames));
    sub->add_option("--max-kernel", o->max_kernel, "Clamp of the kernel t (none by default)")
        ->check(CLI::Range(0.0, 1e9));
    sub->add_option("--normal-y", o->normal_y, "Green channel convention: +y (OpenGL/glTF, default) or -y (DirectX)")
        ->check(is_member_of(kNormalGreenNames));
    sub->add_option("--reconstruct-z", o->reconstruct_z,
                    "auto (default: for 2-channel maps and maps whose blue is constant at full scale), always, never, "
                    "gltf (the stored blue channel, as glTF viewers and scene bakes decode it; rebuilt only for "
                    "2-channel maps)")
        ->check(is_member_of(kReconstructZNames));
    sub->add_option("--wrap", o->wrap,
                    "Addressing the textures are sampled with: repeat (default), clamp, mirror. Footprints lie "
                    "inside the map, so it does not change values; it is recorded in the manifest and EXR files")
        ->check(is_member_of(kWrapModeNames));
    sub->add_flag("--anisotropic,!--isotropic-kernel", o->anisotropic,
                  "Kernel output holds Sigma (xx, yy, xy) (default, what the default rule reads); --isotropic-kernel: "
                  "t only, a quarter of the memory");
    sub->add_option("--lean-space", o->lean_space,
                    "LEAN moments in projected space (default) or slope space (Olano & Baker, base roughness folded in)")
        ->check(is_member_of(kLeanSpaceNames));
    sub->add_option("--outputs", o->outputs, "Comma list of roughness, kernel, lean, normal (default: all)");
    sub->add_flag("--demo", o->demo,
                  "Bake the built-in 512x384 procedural normal map (bumps, ribs, noise) and ORM map; they are "
                  "written to the output folder as demo_normal.png and demo_orm.png");
    sub->footer(
        "Outputs (in the output folder): texture_roughness, texture_kernel, texture_lean + texture_lean_xy,\n"
        "texture_normal (1, 2 or 4 channels each, the same layout in every format), and manifest.json.\n"
        "\nExamples:\n"
        "  specbake texture --demo -o out/demo\n"
        "  specbake texture --normal rock_n.png --roughness rock_orm.png -o out/rock\n"
        "  specbake texture --normal n.tga --roughness-value 0.3 --format dds --normal-y -y -o out/n\n"
        "  specbake texture --normal n.png --roughness r.png:0 --isotropic max --isotropic-kernel --format exr -o out/n");
    auto pipe = std::make_shared<PipelineFlags>();
    add_pipeline_options(*sub, *pipe);
    sub->callback([&run, o, pipe] { run = [o, pipe] { return run_texture(*o, *pipe); }; });
}

}  // namespace specbake::cli
