// Options `specbake verify` and `specbake bench` share: image size, ground-truth samples, frames, timing
// repeats and the bake variants, registered once and turned into verify::VerifyOptions once.
#pragma once

#include "cli/command.h"
#include "verify/verify_job.h"

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <string>
#include <vector>

namespace specbake::cli {

// Defined in the build-generated shader_embed.cpp (shaders/embed.cmake).
extern const unsigned char kSpecaaGlsl[];
extern const std::size_t kSpecaaGlslSize;

struct SimCommandOptions {
    std::string size = "128x128";
    int spp = 256;
    int frames = 8;
    int repeats = 7;
    bool no_variants = false;
    std::string ground_truth = "footprint";
    bool no_floor = false;
    bool no_limit = false;
    int max_spp = -1;          // -1: the command's default (verify: never raise; bench: 1024, --quick: never)
    double floor_goal = 0.1;
    std::vector<std::string> defines;  // NAME or NAME=VALUE
    std::vector<std::string> variants;  // LABEL:NAME[=VALUE][+NAME[=VALUE]...]
    std::vector<std::string> only;      // candidate names to keep besides the baselines; empty: all
    std::string curvature_estimator{to_string(kDefaultCurvatureEstimator)};
};

inline void add_sim_command_options(CLI::App* sub, SimCommandOptions& o) {
    sub->add_option("--size", o.size, "Image size WxH")->capture_default_str();
    sub->add_option("--spp", o.spp, "Ground-truth samples per pixel (rounded to a square)")
        ->capture_default_str()
        ->check(CLI::Range(1, 65536));
    sub->add_option("--frames", o.frames, "Frames of slow sub-pixel camera motion (temporal instability)")
        ->capture_default_str()
        ->check(CLI::Range(1, 1024));
    sub->add_option("--repeats", o.repeats, "Renders per candidate for the median frame time (0: no timing)")
        ->capture_default_str()
        ->check(CLI::Range(0, 1000));
    sub->add_flag("--no-variants", o.no_variants, "Leave out the bake variants");
    sub->add_option("--ground-truth", o.ground_truth,
                    "Ground-truth estimator: footprint (each sample integrates the highlight over its stratum) or "
                    "point (point samples)")
        ->capture_default_str()
        ->check(CLI::IsMember({"footprint", "point"}));
    sub->add_flag("--no-limit", o.no_limit,
                  "Skip the limit row (per pixel the best of 32 isotropic GGX lobes about the shading normal)");
    sub->add_flag("--no-floor", o.no_floor,
                  "Skip the floor row (a second ground truth at a quarter of the samples scored against the first)");
    sub->add_option("--max-spp", o.max_spp,
                    "Raise the ground truth's samples fourfold at a time, up to this many, while the floor is above "
                    "--floor-goal x no filtering's RMSE or flicker, and score every frame again (0: never; "
                    "default: never for verify, 1024 for bench, never for bench --quick)")
        ->check(CLI::Range(0, 65536));
    sub->add_option("--floor-goal", o.floor_goal,
                    "The floor (a quarter-sample ground truth against the full one) --max-spp aims at, as a fraction "
                    "of no filtering's RMSE and flicker")
        ->capture_default_str()
        ->check(CLI::Range(1e-3, 10.0));
    sub->add_option("--define", o.defines,
                    "Compile every candidate but the baseline with '#define NAME VALUE' (repeatable): try the "
                    "include's settings on a scene, e.g. --define SPECAA_KERNEL_TWO_LOBES --define SPECAA_KAPPA=1.0")
        ->type_name("NAME[=VALUE]");
    sub->add_option("--only", o.only, "Only these candidates (plus 'none'), e.g. --only projected,default")
        ->delimiter(',');
    sub->add_option("--variant", o.variants,
                    "Also score a copy of the default named default:LABEL compiled with these defines (repeatable; "
                    "'+' separates defines), e.g. --variant nopix:SPECAA_NO_PIXEL_KERNEL --variant g1:SPECAA_KERNEL_GATE=1; "
                    "a variant that defines SPECAA_ROUGHNESS_TEXTURE=uBakedRoughness shades with the baked roughness in "
                    "place of the kernel mips, e.g. --variant fast:SPECAA_QUALITY=0+SPECAA_ROUGHNESS_TEXTURE=uBakedRoughness"
                    "+SPECAA_ROUGHNESS_CHANNEL=r")
        ->type_name("LABEL:NAME[=VALUE][+NAME[=VALUE]]");
    sub->add_option("--curvature-estimator", o.curvature_estimator,
                    "On scene files, the per-vertex curvature that --define and --variant candidates with "
                    "SPECAA_USE_CURVATURE read (the default among them): patch (what bake writes by default), "
                    "shape-operator, second-order, jet-fitting or normal-cone (analytic scenes use their exact curvature)")
        ->capture_default_str()
        ->check(CLI::IsMember({"shape-operator", "patch", "second-order", "jet-fitting", "normal-cone"}));
}

// "NAME" or "NAME=VALUE" as the line "#define NAME VALUE"; an error message for anything else (NAME a C
// identifier, VALUE one line).
inline bool define_line(const std::string& d, std::string& line, std::string& error) {
    const size_t eq = d.find('=');
    const std::string name = d.substr(0, eq), value = eq == std::string::npos ? "" : d.substr(eq + 1);
    const auto ident = [](char c, bool first) {
        return c == '_' || (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (!first && c >= '0' && c <= '9');
    };
    bool ok = !name.empty();
    for (size_t i = 0; ok && i < name.size(); ++i) ok = ident(name[i], i == 0);
    if (!ok) {
        error = "--define '" + d + "': expected NAME or NAME=VALUE with NAME a C identifier";
        return false;
    }
    if (value.find_first_of("\n\r\\") != std::string::npos) {
        error = "--define '" + d + "': the value must be one line without backslashes";
        return false;
    }
    line = "#define " + name + (value.empty() ? "" : " " + value) + "\n";
    return true;
}

// Fills `v` from `o` and the embedded runtime include. Prints the error and returns false for a bad --size.
inline bool apply_sim_command_options(const SimCommandOptions& o, verify::VerifyOptions& v) {
    if (std::sscanf(o.size.c_str(), "%dx%d", &v.width, &v.height) != 2 || v.width < 2 || v.height < 2 ||
        v.width > 8192 || v.height > 8192) {
        print_error("--size: expected WxH between 2x2 and 8192x8192, got '" + o.size + "'");
        return false;
    }
    v.include_glsl.assign(reinterpret_cast<const char*>(kSpecaaGlsl), kSpecaaGlslSize);
    v.spp = o.spp;
    v.frames = o.frames;
    v.timing_repeats = o.repeats;
    v.variants = !o.no_variants;
    v.footprint_ground_truth = o.ground_truth == "footprint";
    v.floor = !o.no_floor;
    v.max_spp = std::max(o.max_spp, 0);
    v.floor_goal = o.floor_goal;
    v.limit = !o.no_limit;
    v.only = o.only;
    v.curvature_estimator = o.curvature_estimator;
    v.defines.clear();
    for (const std::string& d : o.defines) {
        std::string line, error;
        if (!define_line(d, line, error)) {
            print_error(error);
            return false;
        }
        v.defines += line;
    }
    v.default_variants.clear();
    for (const std::string& spec : o.variants) {
        const size_t colon = spec.find(':');
        if (colon == std::string::npos || colon == 0) {
            print_error("--variant '" + spec + "': expected LABEL:NAME[=VALUE][+NAME[=VALUE]]");
            return false;
        }
        std::string lines, rest = spec.substr(colon + 1);
        while (!rest.empty()) {
            const size_t plus = rest.find('+');
            std::string line, error;
            if (!define_line(rest.substr(0, plus), line, error)) {
                print_error(error);
                return false;
            }
            lines += line;
            rest = plus == std::string::npos ? "" : rest.substr(plus + 1);
        }
        v.default_variants.emplace_back(spec.substr(0, colon), lines);
    }
    return true;
}

}  // namespace specbake::cli
