// specbake glints: bakes the glint dictionary of C21 (MIP-mapped 1D slope marginals, KTX2 2D array) and
// its manifest into a folder.
#include "cli/command.h"

#include "cli/batch.h"
#include "pipeline/glint_job.h"

#include <cstdio>
#include <memory>
#include <string>

namespace specbake::cli {
namespace {

struct GlintsOptions {
    std::string output_dir;
    GlintDictionarySettings settings;
};

int run_glints(const GlintsOptions& o) {
    auto manifest = run_glint_job(o.settings, o.output_dir);
    if (!manifest) {
        print_error(manifest.error().message);
        return kExitFailed;
    }
    if (run_settings().verbosity != Verbosity::quiet) {
        const io::ManifestOutput& out = manifest->outputs.front();
        std::printf("%s/%s: %d marginals x %d levels, %d texels, %d mips, %d layers, %zu bytes; "
                    "max |integral - 1| %.2e\n",
                    o.output_dir.c_str(), out.path.c_str(), o.settings.count, o.settings.levels, o.settings.width,
                    out.mips, out.extra["layers"].get<int>(), out.extra["bytes"].get<size_t>(),
                    out.extra["max_integral_error"].get<double>());
    }
    return kExitOk;
}

}  // namespace

void add_glints_command(CLI::App& app, std::function<int()>& run) {
    auto* sub = app.add_subcommand(
        "glints", "Bake the glint dictionary (C21: MIP-mapped 1D slope distributions) as a KTX2 2D array.");
    auto o = std::make_shared<GlintsOptions>();
    GlintDictionarySettings& s = o->settings;
    sub->add_option("-o,--output", o->output_dir, "Output folder: glint_dictionary.ktx2 and manifest.json")
        ->required();
    sub->add_option("--count", s.count, "Number of 1D marginals N (a multiple of 4)")->capture_default_str();
    sub->add_option("--levels", s.levels, "Distribution levels L (level k holds 2^k mirrored lobe pairs)")
        ->capture_default_str();
    sub->add_option("--width", s.width, "Texels per marginal at mip 0 (a power of two)")->capture_default_str();
    sub->add_option("--alpha-dict", s.alpha_dict, "Beckmann roughness of the coarsest level (sigma_o = alpha/sqrt 2)")
        ->capture_default_str();
    sub->add_option("--lobe-std", s.lobe_std, "Slope standard deviation of one lobe")->capture_default_str();
    sub->add_option("--seed", s.seed, "Seed of the generator; equal seeds give byte-identical files")
        ->capture_default_str();
    sub->footer(
        "The dictionary does not depend on any asset; 'bake' writes it once per output folder for the\n"
        "materials that ask for glints (SPECBAKE_glints). The defaults are the paper's.\n"
        "\n"
        "Examples:\n"
        "  specbake glints -o out/\n"
        "  specbake glints -o out/ --count 256 --seed 7");
    sub->callback([&run, o] { run = [o] { return run_glints(*o); }; });
}

}  // namespace specbake::cli
