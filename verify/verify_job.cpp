#include "verify/verify_job.h"

#include "verify/renderer.h"
#include "verify/spirv.h"
#include "core/text_format.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>

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

}  // namespace

Result<SceneReport> run_verify(const SimScene& scene, const VerifyOptions& options) {
    if (options.frames < 1 || options.frames > 1024) return make_error("--frames must be in [1, 1024]");
    if (options.spp < 1 || options.spp > 65536) return make_error("--spp must be in [1, 65536]");
    auto renderer_result = SimRenderer::create(scene, options.width, options.height, options.include_glsl);
    if (!renderer_result) return renderer_result.error();
    SimRenderer& renderer = **renderer_result;
    renderer.set_ground_truth_footprint(options.footprint_ground_truth);

    SceneReport report;
    report.scene = scene.name;
    report.roughness = scene.objects.empty() ? 0.0f : scene.objects[0].material.roughness;
    report.from_file = scene.from_file;
    report.notes = scene.notes;
    report.width = options.width;
    report.height = options.height;
    report.spp = ground_truth_layout(options.spp, options.width, options.height).samples();
    report.frames = options.frames;

    std::vector<SimCandidate> candidates;
    if (!scene.glints_only) candidates = simulator_candidates(scene, options.variants);
    // Glints only where a material asks for them (SPEC Sec. 6).
    for (SimCandidate& c : glint_candidates(scene)) candidates.push_back(std::move(c));
    if (!options.only.empty()) {
        for (const std::string& name : options.only) {
            if (std::none_of(candidates.begin(), candidates.end(), [&](const SimCandidate& c) { return c.name == name; }))
                report.notes.push_back("candidate '" + name + "' does not apply to " + scene.name);
        }
        std::erase_if(candidates, [&](const SimCandidate& c) {
            return c.name != baseline_of(c.family) &&
                   std::find(options.only.begin(), options.only.end(), c.name) == options.only.end();
        });
    }
    if (!options.defines.empty()) {
        // With SPECAA_USE_CURVATURE every candidate reads _SPECAA_CURVATURE: the analytic one, or for a scene
        // file the default estimator's, as for the candidates that ask for curvature themselves.
        const bool curvature = options.defines.find("#define SPECAA_USE_CURVATURE\n") != std::string::npos ||
                               options.defines.find("#define SPECAA_USE_CURVATURE ") != std::string::npos;
        const std::string estimator = has_exact_curvature(scene) ? "exact" : "shape-operator";
        for (SimCandidate& c : candidates) {
            if (c.name == baseline_of(c.family)) continue;
            c.shader.defines = options.defines + c.shader.defines;
            if (curvature && c.curvature_bake.empty()) c.curvature_bake = c.shader.curvature_source = estimator;
        }
    }
    if (!options.default_variants.empty()) {
        const auto base = std::find_if(candidates.begin(), candidates.end(), [](const SimCandidate& c) { return c.name == "default"; });
        if (base == candidates.end()) report.notes.push_back("--variant: no default candidate on " + scene.name + ", variants skipped");
        const SimCandidate copy = base == candidates.end() ? SimCandidate{} : *base;
        for (const auto& [label, lines] : base == candidates.end() ? decltype(options.default_variants){} : options.default_variants) {
            SimCandidate v = copy;
            v.name = "default:" + label;
            v.shader.defines = lines + v.shader.defines;
            candidates.push_back(std::move(v));
        }
    }
    const bool any_glint = std::any_of(candidates.begin(), candidates.end(), [](const SimCandidate& c) { return c.shader.glint; });
    const bool any_ggx = std::any_of(candidates.begin(), candidates.end(), [](const SimCandidate& c) { return !c.shader.glint; });
    if (any_glint) {
        auto dictionary = shared_glint_dictionary(options.glint_dictionary);
        if (!dictionary) return make_error(scene.name + ": glint dictionary: " + dictionary.error().message);
        // One target per scene: the first glint material's (the include selects it at compile time).
        bool ggx = false, first = true, mixed = false;
        for (const SimObject& o : scene.objects) {
            if (!o.material.glints.enabled) continue;
            if (first) ggx = o.material.glints.ggx;
            else mixed |= o.material.glints.ggx != ggx;
            first = false;
        }
        if (mixed)
            report.notes.push_back(std::string("glint materials with both targets: all simulated with the ") +
                                   (ggx ? "GGX" : "Beckmann") + " target of the first");
        if (auto set = renderer.set_glint_dictionary(**dictionary, ggx); !set) return set.error();
    }

    // Bakes (timed): texture bakes per texture set, curvature estimates per object.
    std::map<std::string, double> bake_ms;
    const std::vector<SimTextureSet> sets = texture_sets(scene);
    for (const SimTextureBake& bake : texture_bakes_for(candidates)) {
        double total = 0;
        for (size_t set = 0; set < sets.size(); ++set) {
            const SimTextureSet& t = sets[set];
            const Image* roughness_map = t.roughness_map >= 0 ? &scene.roughness_maps[size_t(t.roughness_map)] : nullptr;
            const auto start = std::chrono::steady_clock::now();
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

    const auto say = [&](const std::string& line) {
        if (options.progress) options.progress(scene.name + ": " + line);
    };
    if (!bake_ms.empty()) {
        std::string done;
        for (const auto& [key, ms] : bake_ms) done += (done.empty() ? "" : ", ") + key + format_double(" %.0f ms", ms);
        say("baked " + done);
    }

    // Compile every candidate before rendering so a shader error fails fast.
    std::vector<int> ids;
    for (const SimCandidate& c : candidates) {
        auto id = renderer.compile_candidate(c.shader);
        if (!id) return make_error("candidate '" + c.name + "': " + id.error().message);
        ids.push_back(*id);
    }

    std::optional<int> limit_id;
    if (options.limit) {
        auto id = renderer.compile_candidate(limit_shader());
        if (!id) return make_error("limit row: " + id.error().message);
        limit_id = *id;
    }
    SimMetricsAccumulator limit_accumulator;
    SimImage limit_image;

    std::vector<SimMetricsAccumulator> accumulators(candidates.size());
    SimMetricsAccumulator floor_accumulator;
    SimImage floor_image;
    const int floor_spp = std::max(1, report.spp / 4);
    report.candidates.resize(candidates.size());
    double gt_total = 0, glint_total = 0, glint_radiance = 0;
    for (int frame = 0; frame < options.frames; ++frame) {
        auto frame_start = std::chrono::steady_clock::now();
        SimImage gt, glint_gt;
        if (any_ggx) gt = renderer.render_ground_truth(frame, report.spp);
        gt_total += ms_since(frame_start);
        frame_start = std::chrono::steady_clock::now();
        if (any_glint) glint_gt = renderer.render_glint_ground_truth(frame, report.spp);
        glint_total += ms_since(frame_start);
        for (size_t k = 0; k < glint_gt.texel_count(); ++k) glint_radiance += glint_gt.pixels[2 * k];
        for (size_t i = 0; i < candidates.size(); ++i) {
            SimImage image = renderer.render_candidate(ids[i], frame);
            accumulators[i].add_frame(candidates[i].shader.glint ? glint_gt : gt, image);
            if (frame == 0 && options.keep_images) report.candidates[i].image = std::move(image);
        }
        if (limit_id && any_ggx) {
            SimImage best;
            for (int k = 0; k < kLimitKernels; ++k) {
                renderer.set_candidate_uniform(*limit_id, "uLimitKernel", limit_kernel(k));
                keep_nearest(gt, renderer.render_candidate(*limit_id, frame), best, k == 0);
            }
            limit_accumulator.add_frame(gt, best);
            if (frame == 0 && options.keep_images) limit_image = std::move(best);
        }
        if (options.floor && any_ggx) {
            const auto floor_start = std::chrono::steady_clock::now();
            SimImage quarter = renderer.render_ground_truth(frame, floor_spp, 1);
            floor_accumulator.add_frame(gt, quarter);
            if (frame == 0 && options.keep_images) floor_image = std::move(quarter);
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
    if (any_glint && !(glint_radiance > 0))
        report.notes.push_back("the glint ground truth is black (no glint material reflects a light towards the camera): "
                               "the glint rows score nothing");
    report.ground_truth_ms = gt_total;
    report.glint_ground_truth_ms = glint_total;

    const bool spirv = options.spirv && spirv_tools_available();
    if (options.spirv && !spirv)
        report.notes.push_back("SPIR-V counts skipped: glslangValidator, spirv-opt or spirv-dis not on PATH");
    std::map<std::string, double> baseline_ms;
    for (size_t i = 0; i < candidates.size(); ++i) {
        const SimCandidate& c = candidates[i];
        CandidateReport& row = report.candidates[i];
        row.name = c.name;
        row.family = c.family;
        row.source = c.source;
        row.metrics = accumulators[i].finish();
        if (options.pixel_maps) {
            row.pixel_flicker = accumulators[i].pixel_flicker();
            row.pixel_temporal_error = accumulators[i].pixel_temporal_error();
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
    if (options.timing_repeats > 0) {
        say("timing " + std::to_string(candidates.size()) + " candidates x " + std::to_string(options.timing_repeats));
        // Round robin over the candidates, so load changes on a shared machine hit all of them alike;
        // each sample is 4 back-to-back frames, the reported time the median sample per frame.
        constexpr int kDrawsPerSample = 4;
        std::vector<std::vector<double>> samples(candidates.size());
        for (int rep = 0; rep < options.timing_repeats; ++rep)
            for (size_t i = 0; i < candidates.size(); ++i)
                samples[i].push_back(renderer.time_candidate(ids[i], kDrawsPerSample) / kDrawsPerSample);
        for (size_t i = 0; i < candidates.size(); ++i) {
            auto& v = samples[i];
            std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
            report.candidates[i].frame_ms = v[v.size() / 2];
            baseline_ms[candidates[i].name] = v[v.size() / 2];
        }
    }
    if (limit_id && any_ggx) {
        CandidateReport row;
        row.name = "limit";
        row.family = "limit";
        row.source = "best of " + std::to_string(kLimitKernels) +
                     " isotropic GGX lobes about the shading normal per pixel and frame (a lower bound, verify_job.cpp)";
        row.metrics = limit_accumulator.finish();
        row.image = std::move(limit_image);
        report.candidates.push_back(std::move(row));
    }
    if (options.floor && any_ggx) {
        CandidateReport row;
        row.name = "floor";
        row.family = "floor";
        row.source = "ground truth at " + std::to_string(ground_truth_layout(floor_spp, options.width, options.height).samples()) +
                     " spp (independent jitter) against the full one";
        row.metrics = floor_accumulator.finish();
        if (options.pixel_maps) {
            row.pixel_flicker = floor_accumulator.pixel_flicker();
            row.pixel_temporal_error = floor_accumulator.pixel_temporal_error();
        }
        row.image = std::move(floor_image);
        report.candidates.push_back(std::move(row));
    }
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
