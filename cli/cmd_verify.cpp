// specbake verify: scores every specular anti-aliasing candidate against the ground truth on one scene.
#include "cli/command.h"
#include "verify/gl_context.h"
#include "cli/batch.h"
#include "cli/progress.h"
#include "verify/verify_job.h"
#include "cli/verify_options.h"
#include "verify/scene_file.h"
#include "verify/strips.h"
#include "verify/bench_job.h"
#include "core/text_format.h"
#include "io/files/file_read.h"

#include "io/files/atomic_write.h"

#include <nlohmann/json.hpp>

#include <cctype>
#include <cstring>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

namespace specbake::cli {

namespace {

using namespace specbake::verify;

struct VerifyCommandOptions {
    std::string scene_file;
    std::string builtin;
    float alpha = 0.05f;
    SimCommandOptions sim;
    std::string strip;
    std::string harm_map;
    std::string images;
    std::string frame_data;
    float distance = 1.0f;
    int lights = 0;  // 0: the scene's own
};

// `image` (channel 0 radiance, 1 coverage; row 0 the top) as a Portable Float Map: "PF", RGB = radiance,
// coverage, 0, little-endian, rows bottom to top.
Result<void> write_pfm(const SimImage& image, const std::filesystem::path& path) {
    std::string bytes = "PF\n" + std::to_string(image.width) + " " + std::to_string(image.height) + "\n-1.0\n";
    const size_t header = bytes.size();
    bytes.resize(header + size_t(image.width) * size_t(image.height) * 12);
    char* out = bytes.data() + header;
    for (int y = image.height - 1; y >= 0; --y)
        for (int x = 0; x < image.width; ++x) {
            const float* p = &image.pixels[(size_t(y) * size_t(image.width) + size_t(x)) * size_t(image.channels)];
            const float rgb[3] = {p[0], image.channels > 1 ? p[1] : 1.0f, 0.0f};
            std::memcpy(out, rgb, 12);
            out += 12;
        }
    return io::write_file_atomic(path, bytes);
}

// --frame-data DIR: frame 0 of the ground truth and of every candidate as DIR/NAME.pfm, and DIR/frame.json
// with the camera, lights and size they were rendered with, so another renderer can draw the same frame.
Result<void> write_frame_data(const SimScene& scene, const SceneReport& report, const std::filesystem::path& dir) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) return make_error(dir.string() + ": cannot create the folder: " + ec.message());
    const SimCamera cam = camera_at_frame(scene, 0, report.height);
    nlohmann::json j = {{"scene", report.scene}, {"width", report.width}, {"height", report.height},
                        {"camera", {{"position", cam.position}, {"target", cam.target}, {"up", cam.up},
                                    {"fovYDegrees", cam.fov_y_degrees}}},
                        {"lights", nlohmann::json::array()}, {"images", nlohmann::json::object()},
                        {"radiance", "specular only: sum over lights of D G2 / (4 n.v) E, F = 1; E the irradiance on a surface facing the light"}};
    for (size_t i = 0; i < std::min(scene.lights.size(), kMaxSimLights); ++i) {
        const SimLight& l = scene.lights[i];
        j["lights"].push_back({{"type", l.type == SimLight::Type::Directional ? "directional"
                                        : l.type == SimLight::Type::Point     ? "point" : "spot"},
                               {"direction", l.direction}, {"position", l.position}, {"radiance", l.radiance},
                               {"range", l.range}, {"innerCone", l.inner_cone}, {"outerCone", l.outer_cone}});
    }
    const auto write = [&](const std::string& name, const SimImage& image) -> Result<void> {
        if (image.empty()) return {};
        j["images"][name] = name + ".pfm";
        return write_pfm(image, dir / (name + ".pfm"));
    };
    if (auto w = write("ground-truth", report.ground_truth); !w) return w;
    for (const CandidateReport& c : report.candidates) {
        std::string name = c.name;
        for (char& ch : name)
            if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '-' && ch != '_' && ch != '.') ch = '_';
        if (auto w = write(name, c.image); !w) return w;
    }
    return io::write_file_atomic(dir / "frame.json", j.dump(1));
}

int run_verify_command(const VerifyCommandOptions& o) {
    VerifyOptions options;
    if (!apply_sim_command_options(o.sim, options)) return kExitUsage;
    options.pixel_maps = !o.harm_map.empty() || !o.strip.empty();
    // Frames done / total on a terminal; the stage lines as plain lines otherwise.
    ProgressDisplay display(size_t(options.frames), progress_mode(run_settings()), "frames",
                            ProgressDisplay::Lines::activity);
    const std::string item = o.scene_file.empty() ? o.builtin : o.scene_file;
    options.progress = [&display, &item](const std::string& line) { display.status(item, line); };
    options.frame_done = [&display, &item](int, int) { display.finished(item, "done"); };
    if (o.scene_file.empty() == o.builtin.empty()) {
        print_error("give either a scene file or --builtin NAME (see specbake verify --help)");
        return kExitUsage;
    }
    // A missing or unreadable scene is a failed input (exit 1), as for every command, not a usage error.
    if (!o.scene_file.empty()) {
        if (auto regular = io::check_regular_input(o.scene_file); !regular) {
            print_error(regular.error().message);
            return kExitFailed;
        }
    }
    auto scene = o.builtin.empty() ? load_sim_scene(o.scene_file, run_settings().input_policy)
                                   : make_builtin_scene(o.builtin, std::sqrt(o.alpha));
    if (!scene) {
        print_error(scene.error().message);
        return o.builtin.empty() ? kExitFailed : kExitUsage;
    }
    if (o.distance != 1.0f) *scene = at_distance(*scene, format_double("x%g", double(o.distance)), o.distance);
    if (o.lights > 0) *scene = with_cost_lights(*scene, o.lights);
    if (!o.scene_file.empty() && run_settings().verbosity != Verbosity::quiet)
        print_line(stderr, "specbake: " + o.scene_file + ": " + std::to_string(scene->objects.size()) + " objects, " +
                               std::to_string(scene->normal_maps.size()) + " normal maps, " +
                               std::to_string(scene->roughness_maps.size()) + " roughness maps, " +
                               std::to_string(scene->lights.size()) + " lights");
    auto context = GlContext::create();
    if (!context) {
        print_error(context.error().message);
        return kExitFailed;
    }
    auto report = run_verify(*scene, options);
    display.close();
    if (!report) {
        print_error(report.error().message);
        return kExitFailed;
    }
    char material[96];
    if (report->from_file) std::snprintf(material, sizeof material, "its own materials");
    else
        std::snprintf(material, sizeof material, "roughness %.3g (alpha %.3g)", double(report->roughness),
                      double(report->roughness * report->roughness));
    std::printf("Scene %s, %s, %dx%d, ground truth %d spp (%.1f s), %d frames; %s\n\n", report->scene.c_str(),
                material, report->width, report->height, report->spp,
                (report->ground_truth_ms + report->glint_ground_truth_ms) / 1000.0, report->frames,
                (*context)->description().c_str());
    if (!options.defines.empty()) {
        std::string shown = options.defines;
        std::replace(shown.begin(), shown.end(), '\n', ';');
        std::printf("Candidates but the baseline compiled with: %s\n\n", shown.c_str());
    }
    std::fputs(markdown_table(*report).c_str(), stdout);
    if (!report->glint_ground_truth.empty() || report->glint_ground_truth_ms > 0)
        std::printf("\nglint-* rows: the materials with SPECBAKE_glints only, against the glint ground truth (the "
                    "include's glint SDF without GGAA or LEAN, full-resolution maps, the cell footprint of the output "
                    "pixel; C21 Sec. 6); their frame x is relative to glint-c20.\n");
    for (const std::string& note : report->notes) print_warning(note);
    if (!o.strip.empty()) {
        // One strip per ground truth: the GGX candidates', and the glint candidates' (NAME-glints.png when
        // the scene has both).
        const std::vector<StripTile> tiles = strip_tiles(report->candidates, false);
        const std::vector<StripTile> glint_tiles = strip_tiles(report->candidates, true);
        const StripHarm harm = default_strip_harm(report->candidates);
        std::filesystem::path glint_strip = o.strip;
        if (!tiles.empty()) {
            glint_strip.replace_filename(glint_strip.stem().string() + "-glints" + glint_strip.extension().string());
            if (auto written = write_strip_png(make_strip(report->ground_truth, tiles, &harm), o.strip); !written) {
                print_error(written.error().message);
                return kExitFailed;
            }
        }
        if (!glint_tiles.empty()) {
            if (auto written = write_strip_png(make_strip(report->glint_ground_truth, glint_tiles), glint_strip); !written) {
                print_error(written.error().message);
                return kExitFailed;
            }
        }
    }
    if (!o.images.empty()) {
        // One picture per candidate: the ground truth beside it, its error below.
        for (const bool glint : {false, true}) {
            const SimImage& gt = glint ? report->glint_ground_truth : report->ground_truth;
            if (gt.empty()) continue;
            for (const StripTile& tile : strip_tiles(report->candidates, glint, 0, true)) {
                std::string name = tile.label;
                for (char& ch : name)
                    if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '-' && ch != '_' && ch != '.') ch = '_';
                const std::filesystem::path path = std::filesystem::path(o.images) / (name + ".png");
                if (auto written = write_strip_png(make_strip(gt, {tile}), path); !written) {
                    print_error(written.error().message);
                    return kExitFailed;
                }
            }
        }
    }
    if (!o.frame_data.empty()) {
        if (auto written = write_frame_data(*scene, *report, o.frame_data); !written) {
            print_error(written.error().message);
            return kExitFailed;
        }
    }
    if (!o.harm_map.empty()) {
        const CandidateReport* none = nullptr;
        std::vector<HarmTile> tiles;
        for (const CandidateReport& c : report->candidates) {
            if (c.family == "glint" || c.family == "limit" || c.pixel_flicker.empty()) continue;
            if (c.name == "none") none = &c;
            else tiles.push_back({c.name, &c.pixel_flicker, &c.pixel_temporal_error});
        }
        if (none && !tiles.empty()) {
            std::vector<HarmReport> summaries;
            const Image map = make_harm_map(report->ground_truth, {"none", &none->pixel_flicker, &none->pixel_temporal_error},
                                            tiles, &summaries);
            if (auto written = write_strip_png(map, o.harm_map); !written) {
                print_error(written.error().message);
                return kExitFailed;
            }
            std::printf("\nHarm map %s: per pixel, candidate minus none (tone-mapped), as fractions of none's sum: "
                        "excess (of it within 2 px of the silhouette) / relief\n\n",
                        o.harm_map.c_str());
            std::printf("| candidate | flicker excess | at silhouette | flicker relief | t-err excess | at silhouette | t-err relief |\n");
            std::printf("|---|---:|---:|---:|---:|---:|---:|\n");
            for (const HarmReport& h : summaries)
                std::printf("| %s | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f |\n", h.label.c_str(), h.flicker.excess,
                            h.flicker.edge_excess, h.flicker.relief, h.temporal_error.excess,
                            h.temporal_error.edge_excess, h.temporal_error.relief);
        }
    }
    return kExitOk;
}

}  // namespace

void add_verify_command(CLI::App& app, std::function<int()>& run) {
    auto* sub = app.add_subcommand("verify",
                                   "Render a scene's ground truth and every anti-aliasing candidate on headless "
                                   "OpenGL and print accuracy and cost");
    auto o = std::make_shared<VerifyCommandOptions>();
    auto* file = sub->add_option("scene", o->scene_file,
                                 "Scene file: glTF/GLB (its KHR_lights_punctual lights, first perspective camera, "
                                 "roughness and normal textures) or any mesh Assimp reads");
    sub->add_option("--builtin", o->builtin, "Built-in analytic scene: sphere, cylinder, torus, bumpy-sphere, scratched-sphere; glints (C21): "
                    "glitter-sphere, glitter-plane")
        ->excludes(file);
    sub->add_option("--alpha", o->alpha, "GGX alpha of a built-in scene's material (the papers' roughness; glTF r = sqrt(alpha))")
        ->capture_default_str()
        ->check(CLI::Range(0.0001f, 1.0f));
    add_sim_command_options(sub, o->sim);
    sub->add_option("--distance", o->distance,
                    "Camera distance as a factor of the scene's own (bench: near 0.55, mid 1, far 3)")
        ->capture_default_str()
        ->check(CLI::Range(0.05f, 100.0f));
    sub->add_option("--lights", o->lights,
                    "Shade under N directional lights instead of the scene's own (for run-time cost: 35 degrees off "
                    "the view, spread about it, irradiance 1/N each; frame x then counts N lights per pixel)")
        ->check(CLI::Range(1, int(kMaxSimLights)));
    sub->add_option("--strip", o->strip,
                    "Also write the strip to this PNG file: a labelled grid (frame 0, cropped to the object) of the "
                    "ground truth, no filtering, the default and its variants, and the three best other candidates, "
                    "each over its error map and captioned with its ratios to no filtering, plus where the "
                    "default's temporal error exceeds no filtering's");
    sub->add_option("--images", o->images,
                    "Also write one PNG per candidate into this folder (NAME.png: the ground truth, the candidate and "
                    "its error map)");
    sub->add_option("--frame-data", o->frame_data,
                    "Also write frame 0 of the ground truth and of every candidate as float images into this folder "
                    "(NAME.pfm: radiance, coverage) with frame.json, the camera, lights and size they were rendered "
                    "with: the same frame drawn elsewhere (e.g. three.js) can be compared with them");
    sub->add_option("--harm-map", o->harm_map,
                    "Also write the harm map to this PNG file: per pixel, where each candidate's tone-mapped flicker "
                    "and temporal error exceed no filtering's (red) or fall below it (blue), and print where the "
                    "excess lies");
    sub->footer("Examples:\n"
                "  specbake verify scene.glb --strip scene.png\n"
                "  specbake verify scene.glb --strip scene.png --images scene-candidates/\n"
                "  specbake verify --builtin torus --alpha 0.01 --strip torus.png\n"
                "  specbake verify --builtin cylinder --alpha 0.01 --spp 1024 --frames 16 --size 256x256\n"
                "  specbake verify --builtin bumpy-sphere --only baked-texture,default\n"
                "  specbake verify --builtin glitter-plane --alpha 0.1 --size 64x64 --spp 1024 --frames 4\n"
                "  specbake verify scene.gltf --distance 3 --only default,default-two-lobes --define SPECAA_KAPPA=1.0\n"
                "  specbake verify scene.gltf --only default --frames 1 --repeats 0 --frame-data frame/\n"
                "  specbake verify --builtin bumpy-sphere --size 1920x1080 --distance 0.4 --lights 4 --frames 1 --spp 1 "
                "--no-floor --no-limit --repeats 5   (frame time of each candidate; bench/frame_cost.sh runs the tiers and peers)\n"
                "  specbake verify glittery.gltf   (materials with \"SPECBAKE_glints\" also get the glint candidates)");
    sub->callback([&run, o] { run = [o] { return run_verify_command(*o); }; });
}

}  // namespace specbake::cli
