#include "verify/verify_job.h"

#include "verify/renderer.h"
#include "verify/spirv.h"
#include "core/assert.h"
#include "core/text_format.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <optional>
#include <sstream>

namespace specbake::verify {
namespace {

double ms_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

SimBakedTextures to_textures(TextureBakeResult&& result) {
    SimBakedTextures t;
    t.roughness = std::move(result.roughness);
    t.kernel = std::move(result.kernel);
    t.lean = std::move(result.lean);
    return t;
}

// The limit row (issue 15, item 5). A rule that keeps one isotropic GGX lobe about the shading normal the
// engine computes (mipped normal map, interpolated vertex normal) can only choose its roughness per pixel;
// the best it can do is the roughness whose 1-spp radiance is closest to the ground truth. The row renders
// the projected-space filter (TK21 Eq. 7) of the material's a with each kernel of a logarithmic grid,
// 0 and 1e-6 .. 1, and keeps per pixel and frame the one nearest the ground truth. It bounds the isotropic
// rules (and the matrix form where its anisotropy does not matter) from below on these frames; a lobe
// with its own mean direction or anisotropy, or several lobes, could do better.
constexpr int kLimitKernels = 32;

float limit_kernel(int k) { return k == 0 ? 0.0f : float(std::pow(10.0, -6.0 + 6.0 * (k - 1) / (kLimitKernels - 2))); }

SimShaderSpec limit_shader() {
    SimShaderSpec spec;
    spec.defines = "uniform float uLimitKernel;\n";
    spec.body = "float f = specaa_filter_projected_isotropic(a, uLimitKernel); A = vec3(f, f, 0.0);";
    return spec;
}

// Per pixel, the radiance of `candidate` nearest to `gt` (coverage from the first).
void keep_nearest(const SimImage& gt, const SimImage& candidate, SimImage& best, bool first) {
    if (first) {
        best = candidate;
        return;
    }
    for (size_t i = 0; i < gt.texel_count(); ++i) {
        const float g = gt.pixels[2 * i];
        if (std::abs(candidate.pixels[2 * i] - g) < std::abs(best.pixels[2 * i] - g)) best.pixels[2 * i] = candidate.pixels[2 * i];
    }
}

SceneReport empty_report(const SimScene& scene, const VerifyOptions& options) {
    SceneReport report;
    report.scene = scene.name;
    report.roughness = scene.objects.empty() ? 0.0f : scene.objects[0].material.roughness;
    report.from_file = scene.from_file;
    report.notes = scene.notes;
    report.width = options.width;
    report.height = options.height;
    report.spp = ground_truth_layout(options.spp, options.width, options.height).samples();
    report.frames = options.frames;
    return report;
}

// A --variant that binds the baked roughness (SPECAA_ROUGHNESS_TEXTURE) shades with the roughness mips of the
// default's bake in place of its kernel mips (the include takes one or the other); where the default binds
// no baked data (no normal map) the material's roughness is the baked one and the binding is dropped.
// Returns the variant's lines.
std::string with_baked_roughness(const std::string& lines, SimCandidate& v) {
    static const std::string kRoughness = "#define SPECAA_ROUGHNESS_TEXTURE ";
    if (lines.find(kRoughness) == std::string::npos) return lines;
    static const std::string kKernel = "#define SPECAA_KERNEL_TEXTURE uBakedKernel\n";
    static const std::string kAnisotropic = "#define SPECAA_KERNEL_ANISOTROPIC\n";
    if (!v.shader.baked_source.empty()) {
        for (const std::string& line : {kKernel, kAnisotropic})
            if (auto at = v.shader.defines.find(line); at != std::string::npos) v.shader.defines.erase(at, line.size());
        return lines;
    }
    std::string kept, line;
    std::istringstream in(lines);
    while (std::getline(in, line))
        if (!line.starts_with(kRoughness) && !line.starts_with("#define SPECAA_ROUGHNESS_CHANNEL ")) kept += line + "\n";
    return kept;
}

// The candidates the scene gets: the simulator's (unless it simulates glints only) and the glint ones where
// a material asks for them (SPEC Sec. 6), narrowed to --only (plus the baselines), with --define's lines
// in front of every non-baseline shader. Notes the --only names that do not apply.
std::vector<SimCandidate> select_candidates(const SimScene& scene, const VerifyOptions& options,
                                            std::vector<std::string>& notes) {
    std::vector<SimCandidate> candidates;
    if (!scene.glints_only) candidates = simulator_candidates(scene, options.variants, options.curvature_estimator);
    for (SimCandidate& c : glint_candidates(scene)) candidates.push_back(std::move(c));
    if (!options.only.empty()) {
        for (const std::string& name : options.only) {
            if (std::none_of(candidates.begin(), candidates.end(), [&](const SimCandidate& c) { return c.name == name; }))
                notes.push_back("candidate '" + name + "' does not apply to " + scene.name);
        }
        std::erase_if(candidates, [&](const SimCandidate& c) {
            return c.name != baseline_of(c.family) &&
                   std::find(options.only.begin(), options.only.end(), c.name) == options.only.end();
        });
    }
    // With SPECAA_USE_CURVATURE a candidate reads _SPECAA_CURVATURE: the analytic one, or for a scene file the
    // default estimator's, as for the candidates that ask for curvature themselves.
    const auto uses_curvature = [](const std::string& lines) {
        return lines.find("#define SPECAA_USE_CURVATURE\n") != std::string::npos ||
               lines.find("#define SPECAA_USE_CURVATURE ") != std::string::npos;
    };
    const std::string estimator = has_exact_curvature(scene) ? "exact" : options.curvature_estimator;
    if (!options.defines.empty()) {
        const bool curvature = uses_curvature(options.defines);
        for (SimCandidate& c : candidates) {
            if (c.name == baseline_of(c.family)) continue;
            c.shader.defines = options.defines + c.shader.defines;
            if (curvature && c.curvature_bake.empty()) c.curvature_bake = c.shader.curvature_source = estimator;
        }
    }
    if (!options.default_variants.empty()) {
        const auto base = std::find_if(candidates.begin(), candidates.end(),
                                       [](const SimCandidate& c) { return c.name == "default"; });
        if (base == candidates.end()) {
            notes.push_back("--variant: no default candidate on " + scene.name + ", variants skipped");
        } else {
            const SimCandidate copy = *base;
            for (const auto& [label, lines] : options.default_variants) {
                SimCandidate v = copy;
                v.name = "default:" + label;
                v.shader.defines = with_baked_roughness(lines, v) + v.shader.defines;
                if (uses_curvature(lines) && v.curvature_bake.empty()) v.curvature_bake = v.shader.curvature_source = estimator;
                candidates.push_back(std::move(v));
            }
        }
    }
    return candidates;
}

// The glint dictionary and target for the renderer. One target per scene: the first glint material's (the
// include selects it at compile time); a note when materials ask for both.
Result<void> set_glint_target(SimRenderer& renderer, const SimScene& scene, const VerifyOptions& options,
                              std::vector<std::string>& notes) {
    auto dictionary = shared_glint_dictionary(options.glint_dictionary);
    if (!dictionary) return make_error(scene.name + ": glint dictionary: " + dictionary.error().message);
    bool ggx = false, first = true, mixed = false;
    for (const SimObject& o : scene.objects) {
        if (!o.material.glints.enabled) continue;
        if (first) ggx = o.material.glints.ggx;
        else mixed |= o.material.glints.ggx != ggx;
        first = false;
    }
    if (mixed)
        notes.push_back(std::string("glint materials with both targets: all simulated with the ") +
                        (ggx ? "GGX" : "Beckmann") + " target of the first");
    return renderer.set_glint_dictionary(**dictionary, ggx);
}

// The bakes the candidates read, handed to the renderer and timed: texture bakes per texture set,
// curvature estimates per object. Returns the milliseconds per bake key ("curvature:" + estimator for
// the curvature ones).
Result<std::map<std::string, double>> run_bakes(const SimScene& scene, const std::vector<SimCandidate>& candidates,
                                                SimRenderer& renderer) {
    std::map<std::string, double> bake_ms;
    const std::vector<SimTextureSet> sets = texture_sets(scene);
    for (const SimTextureBake& bake : texture_bakes_for(candidates)) {
        double total = 0;
        for (size_t set = 0; set < sets.size(); ++set) {
            const SimTextureSet& t = sets[set];
            const Image* roughness_map = t.roughness_map >= 0 ? &scene.roughness_maps[size_t(t.roughness_map)] : nullptr;
            const auto start = std::chrono::steady_clock::now();
            if (bake.peer) {
                auto chain = bake_peer_roughness(scene.normal_maps[size_t(t.normal_map)], roughness_map, t.roughness, *bake.peer);
                total += ms_since(start);
                if (!chain) return make_error(scene.name + ": texture bake failed: " + chain.error().message);
                SimBakedTextures textures;
                textures.roughness = std::move(*chain);
                renderer.set_baked(bake.key, int(set), textures);
                continue;
            }
            auto baked = bake_texture(scene.normal_maps[size_t(t.normal_map)], roughness_map, 0, t.roughness, bake.settings);
            total += ms_since(start);
            if (!baked) return make_error(scene.name + ": texture bake failed: " + baked.error().message);
            renderer.set_baked(bake.key, int(set), to_textures(std::move(*baked)));
        }
        bake_ms[bake.key] = total;
    }
    for (const SimCurvatureBake& bake : curvature_bakes_for(candidates)) {
        double total = 0;
        for (size_t o = 0; o < scene.objects.size(); ++o) {
            const auto start = std::chrono::steady_clock::now();
            auto curvature = estimate_curvature(scene.objects[o].mesh, *bake.estimator);
            total += ms_since(start);
            if (!curvature) return make_error(scene.name + ": curvature estimate failed: " + curvature.error().message);
            renderer.set_curvature(bake.key, int(o), *curvature);
        }
        bake_ms["curvature:" + bake.key] = total;
    }
    return bake_ms;
}

// Every candidate's program, compiled before rendering so a shader error fails fast.
Result<std::vector<int>> compile_candidates(SimRenderer& renderer, const std::vector<SimCandidate>& candidates) {
    std::vector<int> ids;
    for (const SimCandidate& c : candidates) {
        auto id = renderer.compile_candidate(c.shader);
        if (!id) return make_error("candidate '" + c.name + "': " + id.error().message);
        ids.push_back(*id);
    }
    return ids;
}

// The scores gathered over the frames: per candidate, and for the limit and floor rows.
struct FrameScores {
    std::vector<SimMetricsAccumulator> candidates;
    SimMetricsAccumulator limit, floor;
    SimImage limit_image, floor_image;  // frame 0's, with --keep-images
    int floor_spp = 1;
    double glint_radiance = 0;          // summed over the glint ground truth of every frame
};

// What to render per frame: the candidates' programs, and which ground truths and reference rows.
struct FramePrograms {
    const std::vector<SimCandidate>& candidates;
    const std::vector<int>& ids;
    std::optional<int> limit_id;
    bool any_ggx = false, any_glint = false;
};

// Renders every frame: the ground truths (timed into the report), every candidate against its ground
// truth, the limit row's grid of kernels and the floor's quarter-sample ground truth.
FrameScores render_frames(SimRenderer& renderer, const FramePrograms& programs, const VerifyOptions& options,
                          const std::function<void(const std::string&)>& say, SceneReport& report) {
    const std::vector<SimCandidate>& candidates = programs.candidates;
    FrameScores scores;
    scores.candidates.resize(candidates.size());
    scores.floor_spp = std::max(1, report.spp / 4);
    double gt_total = 0, glint_total = 0;
    for (int frame = 0; frame < options.frames; ++frame) {
        auto frame_start = std::chrono::steady_clock::now();
        SimImage gt, glint_gt;
        if (programs.any_ggx) gt = renderer.render_ground_truth(frame, report.spp);
        gt_total += ms_since(frame_start);
        frame_start = std::chrono::steady_clock::now();
        if (programs.any_glint) glint_gt = renderer.render_glint_ground_truth(frame, report.spp);
        glint_total += ms_since(frame_start);
        for (size_t k = 0; k < glint_gt.texel_count(); ++k) scores.glint_radiance += glint_gt.pixels[2 * k];
        for (size_t i = 0; i < candidates.size(); ++i) {
            SimImage image = renderer.render_candidate(programs.ids[i], frame);
            scores.candidates[i].add_frame(candidates[i].shader.glint ? glint_gt : gt, image);
            if (frame == 0 && options.keep_images) report.candidates[i].image = std::move(image);
        }
        if (programs.limit_id && programs.any_ggx) {
            SimImage best;
            for (int k = 0; k < kLimitKernels; ++k) {
                renderer.set_candidate_uniform(*programs.limit_id, "uLimitKernel", limit_kernel(k));
                keep_nearest(gt, renderer.render_candidate(*programs.limit_id, frame), best, k == 0);
            }
            scores.limit.add_frame(gt, best);
            if (frame == 0 && options.keep_images) scores.limit_image = std::move(best);
        }
        if (options.floor && programs.any_ggx) {
            const auto floor_start = std::chrono::steady_clock::now();
            SimImage quarter = renderer.render_ground_truth(frame, scores.floor_spp, 1);
            scores.floor.add_frame(gt, quarter);
            if (frame == 0 && options.keep_images) scores.floor_image = std::move(quarter);
            gt_total += ms_since(floor_start);
        }
        if (frame == 0 && options.keep_images) {
            report.ground_truth = std::move(gt);
            report.glint_ground_truth = std::move(glint_gt);
        }
        say("frame " + std::to_string(frame + 1) + "/" + std::to_string(options.frames) + ": ground truth and " +
            std::to_string(candidates.size()) + " candidates rendered");
        if (options.frame_done) options.frame_done(frame + 1, options.frames);
    }
    report.ground_truth_ms += gt_total;  // summed over every pass of the frames (VerifyOptions::max_spp)
    report.glint_ground_truth_ms += glint_total;
    return scores;
}

// With VerifyOptions::max_spp: which of the floor's RMSE and linear flicker, as ratios to no filtering's, is
// above VerifyOptions::floor_goal ("RMSE 0.134x, flicker 0.223x none's"); nothing when both are at most the
// goal, or without a floor row or no filtering.
std::optional<std::string> floor_above_goal(const std::vector<SimCandidate>& candidates, const FrameScores& scores,
                                            const VerifyOptions& options) {
    if (options.max_spp <= 0 || !options.floor) return std::nullopt;
    const auto none = std::find_if(candidates.begin(), candidates.end(), [](const SimCandidate& c) { return c.name == "none"; });
    if (none == candidates.end()) return std::nullopt;
    const SimMetrics n = scores.candidates[size_t(none - candidates.begin())].finish(), f = scores.floor.finish();
    // A measure no filtering scores as 0 (nothing moves) has no ratio to reach.
    const double rmse = n.rmse > 0 ? f.rmse / n.rmse : 0.0;
    const double flicker = n.flicker_linear > 0 ? f.flicker_linear / n.flicker_linear : 0.0;
    if (rmse <= options.floor_goal && flicker <= options.floor_goal) return std::nullopt;
    return "floor RMSE " + format_double("%.3f", rmse) + "x, flicker " + format_double("%.3f", flicker) + "x none's";
}

// Each candidate's row: its metrics, its bakes' time and (with --spirv and the tools on PATH) its
// SPIR-V instruction count.
void fill_candidate_rows(const std::vector<SimCandidate>& candidates, std::vector<SimMetricsAccumulator>& scores,
                         std::map<std::string, double>& bake_ms, SimRenderer& renderer, const VerifyOptions& options,
                         SceneReport& report) {
    const bool spirv = options.spirv && spirv_tools_available();
    if (options.spirv && !spirv)
        report.notes.push_back("SPIR-V counts skipped: glslangValidator, spirv-opt or spirv-dis not on PATH");
    SPECBAKE_ASSERT(report.candidates.size() == candidates.size() && scores.size() == candidates.size());
    for (size_t i = 0; i < candidates.size(); ++i) {
        const SimCandidate& c = candidates[i];
        CandidateReport& row = report.candidates[i];
        row.name = c.name;
        row.family = c.family;
        row.source = c.source;
        row.metrics = scores[i].finish();
        if (options.pixel_maps) {
            row.pixel_flicker = scores[i].pixel_flicker();
            row.pixel_temporal_error = scores[i].pixel_temporal_error();
        }
        if (!c.texture_bake.empty()) row.bake_ms = bake_ms[c.texture_bake];
        if (!c.curvature_bake.empty() && c.curvature_bake != "exact")
            row.bake_ms = row.bake_ms.value_or(0.0) + bake_ms["curvature:" + c.curvature_bake];
        if (spirv) {
            auto count = spirv_instruction_count(renderer.candidate_source(c.shader));
            if (count) row.spirv_instructions = *count;
            else report.notes.push_back(c.name + ": " + count.error().message);
        }
    }
}

// Frame times per candidate, into its row; returns them by candidate name. Round robin over the
// candidates, so load changes on a shared machine hit all of them alike; each sample is 4 back-to-back
// frames, the reported time the median sample per frame.
std::map<std::string, double> time_candidates(SimRenderer& renderer, const FramePrograms& programs, int repeats,
                                              SceneReport& report) {
    const std::vector<SimCandidate>& candidates = programs.candidates;
    std::map<std::string, double> frame_ms;
    constexpr int kDrawsPerSample = 4;
    std::vector<std::vector<double>> samples(candidates.size());
    for (int rep = 0; rep < repeats; ++rep)
        for (size_t i = 0; i < candidates.size(); ++i)
            samples[i].push_back(renderer.time_candidate(programs.ids[i], kDrawsPerSample) / kDrawsPerSample);
    for (size_t i = 0; i < candidates.size(); ++i) {
        auto& v = samples[i];
        std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
        report.candidates[i].frame_ms = v[v.size() / 2];
        frame_ms[candidates[i].name] = v[v.size() / 2];
    }
    return frame_ms;
}

// The limit and floor rows, after the candidates'.
void add_reference_rows(FrameScores& scores, const FramePrograms& programs, const VerifyOptions& options,
                        SceneReport& report) {
    if (programs.limit_id && programs.any_ggx) {
        CandidateReport row;
        row.name = "limit";
        row.family = "limit";
        row.source = "best of " + std::to_string(kLimitKernels) +
                     " isotropic GGX lobes about the shading normal per pixel and frame (a lower bound, verify_job.cpp)";
        row.metrics = scores.limit.finish();
        row.image = std::move(scores.limit_image);
        report.candidates.push_back(std::move(row));
    }
    if (options.floor && programs.any_ggx) {
        CandidateReport row;
        row.name = "floor";
        row.family = "floor";
        row.source = "ground truth at " +
                     std::to_string(ground_truth_layout(scores.floor_spp, options.width, options.height).samples()) +
                     " spp (independent jitter) against the full one";
        row.metrics = scores.floor.finish();
        if (options.pixel_maps) {
            row.pixel_flicker = scores.floor.pixel_flicker();
            row.pixel_temporal_error = scores.floor.pixel_temporal_error();
        }
        row.image = std::move(scores.floor_image);
        report.candidates.push_back(std::move(row));
    }
}

}  // namespace

Result<SceneReport> run_verify(const SimScene& scene, const VerifyOptions& options) {
    if (options.frames < 1 || options.frames > 1024) return make_error("--frames must be in [1, 1024]");
    if (options.spp < 1 || options.spp > 65536) return make_error("--spp must be in [1, 65536]");
    if (options.max_spp < 0 || options.max_spp > 65536) return make_error("--max-spp must be in [0, 65536]");
    if (!(options.floor_goal > 0)) return make_error("--floor-goal must be above 0");
    auto renderer_result = SimRenderer::create(scene, options.width, options.height, options.include_glsl);
    if (!renderer_result) return renderer_result.error();
    SimRenderer& renderer = **renderer_result;
    renderer.set_ground_truth_footprint(options.footprint_ground_truth);

    SceneReport report = empty_report(scene, options);
    const std::vector<SimCandidate> candidates = select_candidates(scene, options, report.notes);
    const bool any_glint = std::any_of(candidates.begin(), candidates.end(), [](const SimCandidate& c) { return c.shader.glint; });
    const bool any_ggx = std::any_of(candidates.begin(), candidates.end(), [](const SimCandidate& c) { return !c.shader.glint; });
    if (any_glint)
        if (auto set = set_glint_target(renderer, scene, options, report.notes); !set) return set.error();
    auto bake_ms = run_bakes(scene, candidates, renderer);
    if (!bake_ms) return bake_ms.error();

    const std::function<void(const std::string&)> say = [&](const std::string& line) {
        if (options.progress) options.progress(scene.name + ": " + line);
    };
    if (!bake_ms->empty()) {
        std::string done;
        for (const auto& [key, ms] : *bake_ms) done += (done.empty() ? "" : ", ") + key + format_double(" %.0f ms", ms);
        say("baked " + done);
    }
    auto ids = compile_candidates(renderer, candidates);
    if (!ids) return ids.error();
    FramePrograms programs{candidates, *ids, std::nullopt, any_ggx, any_glint};
    if (options.limit) {
        auto id = renderer.compile_candidate(limit_shader());
        if (!id) return make_error("limit row: " + id.error().message);
        programs.limit_id = *id;
    }

    report.candidates.resize(candidates.size());
    FrameScores scores = render_frames(renderer, programs, options, say, report);
    for (;;) {
        const std::optional<std::string> why = floor_above_goal(candidates, scores, options);
        if (!why || !any_ggx) break;
        const int next = ground_truth_layout(report.spp * 4, options.width, options.height).samples();
        if (next <= report.spp || next > options.max_spp) {
            report.floor_goal_unmet = "the floor stays above " + format_double("%g", options.floor_goal) +
                                      "x no filtering's at " + std::to_string(report.spp) + " spp (" + *why +
                                      "): more samples than --max-spp " + std::to_string(options.max_spp) +
                                      " would be needed";
            report.notes.push_back(report.floor_goal_unmet);
            break;
        }
        report.notes.push_back("ground truth raised from " + std::to_string(report.spp) + " to " +
                               std::to_string(next) + " spp: " + *why);
        say("floor " + *why + ": ground truth again at " + std::to_string(next) + " spp");
        if (report.spp_raised_from == 0) report.spp_raised_from = report.spp;
        report.spp = next;
        scores = render_frames(renderer, programs, options, say, report);
    }
    if (any_glint && !(scores.glint_radiance > 0))
        report.notes.push_back("the glint ground truth is black (no glint material reflects a light towards the camera): "
                               "the glint rows score nothing");
    fill_candidate_rows(candidates, scores.candidates, *bake_ms, renderer, options, report);
    std::map<std::string, double> baseline_ms;
    if (options.timing_repeats > 0) {
        say("timing " + std::to_string(candidates.size()) + " candidates x " + std::to_string(options.timing_repeats));
        baseline_ms = time_candidates(renderer, programs, options.timing_repeats, report);
    }
    add_reference_rows(scores, programs, options, report);
    for (CandidateReport& row : report.candidates) {
        auto base = baseline_ms.find(baseline_of(row.family));
        if (row.frame_ms && base != baseline_ms.end() && base->second > 0) row.frame_relative = *row.frame_ms / base->second;
    }
    return report;
}

std::string baseline_of(const std::string& family) { return family == "glint" ? "glint-c20" : "none"; }

std::string markdown_table(const SceneReport& r) {
    std::string out;
    out += "| candidate | RMSE | MAE | RMSE (tm) | flicker | flicker (tm) | t-err | t-err (tm) | energy | p99 | bake ms | SPIR-V | frame x |\n";
    out += "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const CandidateReport& c : r.candidates) {
        const SimMetrics& m = c.metrics;
        out += "| " + c.name + " | " + format_double("%.3f", m.rmse) + " | " + format_double("%.3f", m.mae) + " | " +
               format_double("%.4f", m.rmse_tonemapped) + " | " + format_double("%.3g", m.flicker_linear) + " | " +
               format_double("%.3g", m.flicker) + " | " + format_double("%.3g", m.temporal_error_linear) + " | " +
               format_double("%.3g", m.temporal_error) + " | " +
               format_double("%.2f", m.energy_ratio) + " | " + format_double("%.2f", m.peak_ratio) + " | " +
               (c.bake_ms ? format_double("%.1f", *c.bake_ms) : "-") + " | " +
               (c.spirv_instructions ? std::to_string(*c.spirv_instructions) : "-") + " | " +
               (c.frame_relative ? format_double("%.2f", *c.frame_relative) : "-") + " |\n";
    }
    return out;
}

}  // namespace specbake::verify
