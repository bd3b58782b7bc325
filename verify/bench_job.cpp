#include "verify/bench_job.h"

#include "verify/float3_math_internal.h"

#include "verify/scene_file.h"
#include "verify/strips.h"
#include "core/text_format.h"
#include "io/files/atomic_write.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <set>

namespace specbake::verify {
namespace {

std::string scene_label(const SceneReport& s) {
    if (s.from_file) return s.scene;
    return s.scene + " a=" + format_double("%.3g", double(s.roughness) * double(s.roughness));
}

const CandidateReport* find_row(const SceneReport& s, const std::string& name) {
    for (const CandidateReport& c : s.candidates)
        if (c.name == name) return &c;
    return nullptr;
}

constexpr double kFloor = 1e-9;  // keeps the logarithm finite for a candidate identical to none

// Geometric mean of candidate / none over the scenes where none's value is above the floor (a scene where
// none does not flicker at all says nothing about a candidate's flicker relative to it).
struct RatioMean {
    double log_sum = 0;
    int n = 0;
    void add(double candidate, double none) {
        if (none <= kFloor) return;
        log_sum += std::log(std::max(candidate, kFloor) / none);
        ++n;
    }
    // Counted whatever none's value: both sides floored (RMSE, where none is zero only if it equals the
    // ground truth).
    void add_floored(double candidate, double none) {
        log_sum += std::log(std::max(candidate, kFloor) / std::max(none, kFloor));
        ++n;
    }
    double value() const { return n ? std::exp(log_sum / n) : 1.0; }
};

// The six summary measures of a candidate against its baseline over a set of scenes: geometric means of
// RMSE, RMSE (tm), flicker, flicker (tm), t-err and t-err (tm) as ratios to the baseline's.
struct RatioMeans {
    RatioMean rmse, rmse_tm, flicker, flicker_tm, terr, terr_tm;
    void add(const SimMetrics& m, const SimMetrics& base) {
        rmse.add_floored(m.rmse, base.rmse);
        rmse_tm.add_floored(m.rmse_tonemapped, base.rmse_tonemapped);
        flicker.add(m.flicker_linear, base.flicker_linear);
        flicker_tm.add(m.flicker, base.flicker);
        terr.add(m.temporal_error_linear, base.temporal_error_linear);
        terr_tm.add(m.temporal_error, base.temporal_error);
    }
    std::array<double, 6> values() const {
        return {rmse.value(), rmse_tm.value(), flicker.value(), flicker_tm.value(), terr.value(), terr_tm.value()};
    }
};

// Per candidate, aggregated over the scenes it ran on.
struct Aggregate {
    std::string name, family;
    RatioMeans ratios;
    double energy = 0, peak = 0;
    int n = 0;
    std::optional<int> spirv;
    std::vector<double> frame_rel, bake_ms;
    double rel_error() const { return ratios.rmse_tm.value(); }
    double rel_error_linear() const { return ratios.rmse.value(); }
    double rel_flicker() const { return ratios.flicker.value(); }
    double rel_flicker_tm() const { return ratios.flicker_tm.value(); }
    double rel_terr() const { return ratios.terr.value(); }
    double rel_terr_tm() const { return ratios.terr_tm.value(); }
};

enum class Family { All, Analytic, Real };
bool in_family(const SceneReport& s, Family f) {
    return f == Family::All || (f == Family::Real) == s.from_file;
}

double median(std::vector<double> v) {
    if (v.empty()) return NAN;
    std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
    return v[v.size() / 2];
}

std::vector<Aggregate> aggregate(const BenchReport& r, Family family = Family::All) {
    std::vector<Aggregate> out;
    std::map<std::string, size_t> index;
    for (const SceneReport& s : r.scenes) {
        if (!in_family(s, family)) continue;
        for (const CandidateReport& c : s.candidates) {
            const CandidateReport* none = find_row(s, baseline_of(c.family));
            if (!none) continue;
            auto [it, fresh] = index.try_emplace(c.name, out.size());
            if (fresh) {
                out.emplace_back();
                out.back().name = c.name;
                out.back().family = c.family;
            }
            Aggregate& a = out[it->second];
            a.ratios.add(c.metrics, none->metrics);
            a.energy += c.metrics.energy_ratio;
            a.peak += c.metrics.peak_ratio;
            ++a.n;
            if (c.spirv_instructions) a.spirv = std::max(a.spirv.value_or(0), *c.spirv_instructions);
            if (c.frame_relative) a.frame_rel.push_back(*c.frame_relative);
            if (c.bake_ms) a.bake_ms.push_back(*c.bake_ms);
        }
    }
    return out;
}

std::string csv_escape(const std::string& s) {
    return s.find_first_of(",\"") == std::string::npos ? s : "\"" + s + "\"";
}

std::string opt(const std::optional<double>& v, const char* f) { return v ? format_double(f, *v) : ""; }

}  // namespace

Result<BenchReport> run_bench(const BenchOptions& options, const std::function<void(const std::string&)>& progress) {
    BenchReport report;
    report.renderer = options.renderer;
    report.command_line = options.command_line;
    std::vector<std::string> scenes = options.scenes;
    if (scenes.empty() && !options.no_builtin) {
        for (auto n : builtin_scene_names()) scenes.emplace_back(n);
        for (auto n : builtin_glint_scene_names()) scenes.emplace_back(n);
    }
    for (const std::string& name : scenes) {
        const bool glint = name.starts_with("glitter-");
        for (float alpha : glint ? std::vector<float>{options.glint_alpha} : options.alpha) {
            if (!(alpha > 0.0f && alpha <= 1.0f)) return make_error("--alpha values must be in (0, 1]");
            auto scene = make_builtin_scene(name, std::sqrt(alpha));
            if (!scene) return scene.error();
            auto result = run_verify(*scene, options.verify);
            if (!result) return make_error(name + ": " + result.error().message);
            report.scenes.push_back(std::move(*result));
            if (progress)
                progress(scene_label(report.scenes.back()) + ": ground truth " +
                         format_double("%.1f s", (report.scenes.back().ground_truth_ms + report.scenes.back().glint_ground_truth_ms) / 1000.0));
        }
    }
    std::vector<std::filesystem::path> files = options.scene_files;
    if (!options.corpus_dir.empty()) {
        auto corpus = corpus_files(options.corpus_dir);
        if (!corpus) return corpus.error();
        files.insert(files.end(), corpus->begin(), corpus->end());
    }
    for (const std::filesystem::path& file : files) {
        auto scene = load_sim_scene(file, options.input_policy);
        if (!scene) return scene.error();
        for (const auto& [label, factor] : options.distances) {
            auto result = run_verify(at_distance(*scene, label, factor), options.verify);
            if (!result) return make_error(file.string() + " (" + label + "): " + result.error().message);
            report.scenes.push_back(std::move(*result));
            if (progress)
                progress(scene_label(report.scenes.back()) + ": ground truth " +
                         format_double("%.1f s", (report.scenes.back().ground_truth_ms +
                                                    report.scenes.back().glint_ground_truth_ms) / 1000.0));
        }
    }
    return report;
}

Result<std::vector<std::filesystem::path>> corpus_files(const std::filesystem::path& dir) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) return make_error(dir.string() + ": corpus folder not found");
    std::vector<fs::path> out;
    for (const auto& model : fs::directory_iterator(dir, ec)) {
        if (!model.is_directory()) continue;
        for (const auto& file : fs::directory_iterator(model.path(), ec)) {
            const std::string ext = file.path().extension().string();
            if (file.is_regular_file() && (ext == ".gltf" || ext == ".glb")) out.push_back(file.path());
        }
    }
    if (ec) return make_error(dir.string() + ": " + ec.message());
    if (out.empty()) return make_error(dir.string() + ": no .gltf or .glb file in its subfolders");
    std::sort(out.begin(), out.end());
    return out;
}

SimScene at_distance(const SimScene& scene, const std::string& label, float factor) {
    SimScene out = scene;
    out.name = scene.name + "@" + label;
    SimCamera& c = out.camera;
    for (int i = 0; i < 3; ++i) c.position[i] = c.target[i] + factor * (c.position[i] - c.target[i]);
    return out;
}

SimScene with_cost_lights(const SimScene& scene, int count) {
    SimScene out = scene;
    out.name = scene.name + "+" + std::to_string(count) + "L";
    const SimCamera& c = scene.camera;
    const Float3 view = unit(sub(c.position, c.target));
    const Float3 right = unit(cross3(c.up, view));
    const Float3 up = cross3(view, right);
    constexpr float kTilt = 35.0f * std::numbers::pi_v<float> / 180.0f;
    out.lights.clear();
    for (int k = 0; k < count; ++k) {
        const float turn = 2.0f * std::numbers::pi_v<float> * float(k) / float(count);
        const float su = std::sin(kTilt) * std::cos(turn), sr = std::sin(kTilt) * std::sin(turn);
        SimLight light;
        light.type = SimLight::Type::Directional;
        for (int i = 0; i < 3; ++i) light.direction[i] = std::cos(kTilt) * view[i] + su * up[i] + sr * right[i];
        light.direction = unit(light.direction);
        light.radiance = 1.0f / float(count);
        out.lights.push_back(light);
    }
    return out;
}

namespace {

std::string aggregate_table(const BenchReport& r, Family family) {
    std::string out;
    out += "| candidate | family | RMSE vs base | RMSE (tm) vs base | flicker vs base | flicker (tm) vs base | t-err vs base "
           "| t-err (tm) vs base | energy | p99 | SPIR-V | frame x | bake ms |\n";
    out += "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const Aggregate& a : aggregate(r, family)) {
        const double frame = median(a.frame_rel), bake = median(a.bake_ms);
        out += "| " + a.name + " | " + a.family + " | " + format_double("%.3f", a.rel_error_linear()) + " | " +
               format_double("%.3f", a.rel_error()) + " | " + format_double("%.3f", a.rel_flicker()) + " | " +
               format_double("%.3f", a.rel_flicker_tm()) + " | " + format_double("%.3f", a.rel_terr()) + " | " +
               format_double("%.3f", a.rel_terr_tm()) + " | " + format_double("%.2f", a.energy / a.n) + " | " +
               format_double("%.2f", a.peak / a.n) + " | " + (a.spirv ? std::to_string(*a.spirv) : "-") + " | " +
               (std::isnan(frame) ? "-" : format_double("%.2f", frame)) + " | " +
               (std::isnan(bake) ? "-" : format_double("%.1f", bake)) + " |\n";
    }
    return out;
}


// The do-no-harm measures of a candidate against no filtering (candidate / none): RMSE, linear and
// tone-mapped flicker, linear and tone-mapped temporal error, and their goals.
constexpr const char* kHarmNames[5] = {"RMSE", "flicker", "flicker (tm)", "t-err", "t-err (tm)"};
constexpr double kHarmGoal[5] = {1.02, 1.0, 1.0, 1.0, 1.0};
std::array<double, 5> harm_measures(const SimMetrics& m, const SimMetrics& none) {
    const auto ratio = [](double a, double b) { return b > 0 ? a / b : (a > 0 ? INFINITY : 1.0); };
    return {ratio(m.rmse, none.rmse), ratio(m.flicker_linear, none.flicker_linear), ratio(m.flicker, none.flicker),
            ratio(m.temporal_error_linear, none.temporal_error_linear), ratio(m.temporal_error, none.temporal_error)};
}
bool does_no_harm(const SimMetrics& m, const SimMetrics& none) {
    const std::array<double, 5> x = harm_measures(m, none);
    for (int i = 0; i < 5; ++i)
        if (!(x[i] <= kHarmGoal[i])) return false;
    return true;
}

// The do-no-harm check of the default per scene: each measure as default / none, the measures that exceed
// their goal (RMSE <= 1.02x, linear and tone-mapped flicker and temporal error <= 1.00x), the default's
// energy, and the floor (ground truth at 1/4 of the samples against the full one, / none) of each measure:
// a ratio whose excess over its goal is below the floor's is not decided by this ground truth.
std::string do_no_harm_table(const BenchReport& r) {
    std::string out =
        "\nDo no harm (default / none per scene; goal RMSE <= 1.02x, linear and tone-mapped flicker and temporal "
        "error <= 1.00x; flicker over the pixels scored in every frame, t-err over frame pairs), the default's "
        "energy / the ground truth's, and the floor of each measure (ground truth at 1/4 of the samples against "
        "the full one, / none) at the ground truth's samples per pixel (raised fourfold at a time, up to --max-spp, "
        "where the floor's RMSE or flicker was above --floor-goal x none's):\n\n";
    out += "| scene | default RMSE x | flicker x | flicker (tm) x | t-err x | t-err (tm) x | energy | fails by "
           "| floor RMSE x | floor flicker x | floor flicker (tm) x | floor t-err x | floor t-err (tm) x | spp |\n"
           "|---|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|\n";
    int pairs = 0, holding = 0;
    for (const SceneReport& s : r.scenes) {
        const CandidateReport* none = find_row(s, "none");
        const CandidateReport* def = find_row(s, "default");
        const CandidateReport* floor = find_row(s, "floor");
        if (!none || !def) continue;
        const std::array<double, 5> x = harm_measures(def->metrics, none->metrics);
        std::string fails;
        for (int i = 0; i < 5; ++i)
            if (!(x[i] <= kHarmGoal[i])) fails += (fails.empty() ? "" : ", ") + std::string(kHarmNames[i]);
        ++pairs;
        holding += fails.empty() ? 1 : 0;
        out += "| " + scene_label(s);
        for (double v : x) out += " | " + format_double("%.3f", v);
        out += " | " + format_double("%.2f", def->metrics.energy_ratio) + " | " +
               (fails.empty() ? std::string("holds") : "**" + fails + "**");
        if (floor) {
            for (double v : harm_measures(floor->metrics, none->metrics)) out += " | " + format_double("%.3f", v);
        } else {
            out += " | - | - | - | - | -";
        }
        out += " | " + std::to_string(s.spp) +
               (s.spp_raised_from > 0 ? " (from " + std::to_string(s.spp_raised_from) + ")" : std::string()) + " |\n";
    }
    out += "\nThe default holds on " + std::to_string(holding) + " of " + std::to_string(pairs) + " scenes.\n";
    std::string above;
    for (const SceneReport& s : r.scenes)
        if (!s.floor_goal_unmet.empty()) above += "\n- " + scene_label(s) + ": " + s.floor_goal_unmet;
    if (!above.empty()) out += "\nFloors still above their goal at the most samples --max-spp allows:\n" + above + "\n";
    return out;
}

// A candidate over a set of scenes: geometric means of its ratio to no filtering (RMSE, RMSE (tm), flicker,
// flicker (tm), t-err, t-err (tm)) and the scenes where it does no harm.
struct OverScenes {
    std::array<double, 6> means{};
    int holds = 0, n = 0;
};
OverScenes over_scenes(const BenchReport& r, const std::string& name, const std::vector<size_t>& scenes) {
    RatioMeans ratios;
    OverScenes o;
    for (size_t i : scenes) {
        const CandidateReport* none = find_row(r.scenes[i], "none");
        const CandidateReport* c = find_row(r.scenes[i], name);
        if (!none || !c) continue;
        ratios.add(c->metrics, none->metrics);
        o.holds += does_no_harm(c->metrics, none->metrics) ? 1 : 0;
        ++o.n;
    }
    o.means = ratios.values();
    return o;
}

// Each engine's filter (the "peer" rows) against specbake's row of equal or lower cost, on the scenes both
// ran on: the most expensive of the baked roughness alone and the three quality tiers whose SPIR-V count is
// at most the engine's, or, where none is that cheap, the cheapest of them, with its extra cost.
std::string engines_against_tiers(const BenchReport& r) {
    static const char* const kOurs[] = {"baked-texture", "fast", "balanced", "default"};
    std::vector<std::string> peers;
    std::map<std::string, int> spirv;
    for (const SceneReport& s : r.scenes)
        for (const CandidateReport& c : s.candidates) {
            if (c.spirv_instructions) spirv[c.name] = std::max(spirv[c.name], *c.spirv_instructions);
            if (c.family == "peer" && std::find(peers.begin(), peers.end(), c.name) == peers.end())
                peers.push_back(c.name);
        }
    std::string rows;
    for (const std::string& peer : peers) {
        std::vector<size_t> scenes;
        for (size_t i = 0; i < r.scenes.size(); ++i)
            if (find_row(r.scenes[i], peer) && find_row(r.scenes[i], "none")) scenes.push_back(i);
        if (scenes.empty() || !spirv.count(peer)) continue;
        std::string match;  // the most expensive row within the engine's cost, else the cheapest
        std::string cheapest;
        for (const char* ours : kOurs) {
            const bool everywhere = std::all_of(scenes.begin(), scenes.end(),
                                                [&](size_t i) { return find_row(r.scenes[i], ours) != nullptr; });
            if (!everywhere || !spirv.count(ours)) continue;
            if (spirv[ours] <= spirv[peer] && (match.empty() || spirv[ours] > spirv[match])) match = ours;
            if (cheapest.empty() || spirv[ours] < spirv[cheapest]) cheapest = ours;
        }
        if (match.empty()) match = cheapest;
        if (match.empty()) continue;
        const OverScenes e = over_scenes(r, peer, scenes), o = over_scenes(r, match, scenes);
        int lower = 0;
        rows += "| " + peer + " | " + std::to_string(spirv[peer]) + " | " + (match == "default" ? "reference" : match) +
                " | " + std::to_string(spirv[match]) +
                (spirv[match] > spirv[peer] ? " (+" + std::to_string(spirv[match] - spirv[peer]) + ")" : "") + " | " +
                std::to_string(e.n);
        for (int k = 0; k < 6; ++k) {
            rows += " | " + format_double("%.3f", e.means[k]) + " / " + format_double("%.3f", o.means[k]);
            lower += o.means[k] < e.means[k] ? 1 : 0;
        }
        rows += " | " + std::to_string(e.holds) + " / " + std::to_string(o.holds) + " | " + std::to_string(lower) +
                " of 6 |\n";
    }
    if (rows.empty()) return "";
    return "\nThe peers' filters (engines' run-time filters and offline bakes, VAREF's) against specbake's row of "
           "equal or lower cost (on the scenes both ran on): the "
           "most expensive of baked-texture (the baked roughness alone) and the tiers fast, balanced and reference "
           "(the default) whose SPIR-V count is at most the engine's, else the cheapest of them (its extra "
           "instructions in brackets). Cells are peer / specbake, geometric means of the ratio to no "
           "filtering; do no harm counts the scenes where every measure holds its goal:\n\n"
           "| peer | SPIR-V | specbake | SPIR-V | scenes | RMSE | RMSE (tm) | flicker | flicker (tm) | t-err "
           "| t-err (tm) | do no harm | specbake lower on |\n"
           "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n" +
           rows;
}
}  // namespace

std::string bench_summary_markdown(const BenchReport& r) {
    size_t real = 0;
    for (const SceneReport& s : r.scenes) real += s.from_file ? 1 : 0;
    const size_t analytic = r.scenes.size() - real;
    std::string out = "All " + std::to_string(r.scenes.size()) + " scenes:\n\n" + aggregate_table(r, Family::All);
    if (real > 0 && analytic > 0) {
        out += "\nAnalytic (" + std::to_string(analytic) + " scene/roughness pairs):\n\n" + aggregate_table(r, Family::Analytic);
        out += "\nReal assets (" + std::to_string(real) + " scene/distance pairs):\n\n" + aggregate_table(r, Family::Real);
    }
    out += "\nBase: none (no filtering); for the glint family glint-c20 (glints without anti-aliasing, C20), on the "
           "glint ground truth.\n";
    out += do_no_harm_table(r);
    out += engines_against_tiers(r);
    out += "\nBest per scene (lowest linear RMSE / lowest flicker among filtering candidates):\n\n";
    out += "| scene | base RMSE | best RMSE | base flicker | best flicker |\n|---|---:|---|---:|---|\n";
    for (const SceneReport& s : r.scenes) {
        const bool glints_only = std::none_of(s.candidates.begin(), s.candidates.end(),
                                              [](const CandidateReport& c) { return c.family != "glint"; });
        const std::string base = glints_only ? "glint-c20" : "none";
        const CandidateReport* none = find_row(s, base);
        const CandidateReport *best_e = nullptr, *best_f = nullptr;
        for (const CandidateReport& c : s.candidates) {
            if (c.name == base || c.family == "floor" || c.family == "limit" || (c.family == "glint") != glints_only)
                continue;
            if (!best_e || c.metrics.rmse < best_e->metrics.rmse) best_e = &c;
            if (!best_f || c.metrics.flicker_linear < best_f->metrics.flicker_linear) best_f = &c;
        }
        if (!none || !best_e) continue;
        out += "| " + scene_label(s) + " | " + format_double("%.3f", none->metrics.rmse) + " | " + best_e->name + " " +
               format_double("%.3f", best_e->metrics.rmse) + " | " + format_double("%.3f", none->metrics.flicker_linear) + " | " +
               best_f->name + " " + format_double("%.3f", best_f->metrics.flicker_linear) + " |\n";
    }
    return out;
}

std::string bench_full_markdown(const BenchReport& r) {
    std::string out = "# specbake bench\n\n";
    out += "Command: `" + r.command_line + "`\n\nRenderer: " + r.renderer + "\n\n";
    if (!r.scenes.empty())
        out += "Images " + std::to_string(r.scenes[0].width) + "x" + std::to_string(r.scenes[0].height) +
               ", ground truth " + std::to_string(r.scenes[0].spp) + " spp (Gaussian pixel filter, sigma^2 = 1/(2 pi)), " +
               std::to_string(r.scenes[0].frames) + " frames of camera motion.\n\n";
    out += "## Summary (geometric mean over scenes of the ratio to no filtering; lower is better; linear "
           "radiance unless marked tm)\n\n";
    out += bench_summary_markdown(r);
    for (const SceneReport& s : r.scenes) {
        out += "\n## " + scene_label(s) +
               (s.from_file ? std::string(" (scene file, its own materials)") : " (r = " + format_double("%.3g", s.roughness) + ")") +
               "\n\n";
        out += markdown_table(s);
        for (const std::string& note : s.notes) out += "\n- " + note;
        if (!s.notes.empty()) out += "\n";
    }
    out += "\nColumns: RMSE and MAE of linear radiance divided by the ground truth's mean; (tm) on x/(1+x); "
           "flicker = mean over pixels of the temporal standard deviation of the error, divided by the ground "
           "truth's mean, over the pixels scored in every frame; t-err (temporal error) = mean over pixels of "
           "sqrt(sum over consecutive frames both scoring the pixel of ((c1 - c0) - (g1 - g0))^2 / (2 pairs)), "
           "divided by the ground truth's mean (equal to the flicker for an error independent from frame to "
           "frame, near zero for a stable error moving with the image); (tm) the same on x/(1+x); energy and "
           "p99 = candidate/ground-truth ratios of total radiance and of the 99th percentile (< 1: over-blur); "
           "SPIR-V = instructions in functions after spirv-opt -O; frame x = median frame time relative to no "
           "filtering on this renderer; bake ms = texture bake or curvature estimate.\n";
    return out;
}

std::string bench_csv(const BenchReport& r) {
    std::string out =
        "scene,alpha,roughness,width,height,spp,frames,candidate,family,source,rmse,mae,rmse_tonemapped,"
        "mae_tonemapped,flicker,flicker_linear,energy_ratio,peak_ratio,pixels,bake_ms,spirv_instructions,frame_ms,"
        "frame_relative,temporal_error,temporal_error_linear\n";
    for (const SceneReport& s : r.scenes) {
        for (const CandidateReport& c : s.candidates) {
            const SimMetrics& m = c.metrics;
            // A scene file's materials have their own roughness: alpha and roughness stay empty.
            out += s.scene + "," + (s.from_file ? "," : format_double("%.6g", double(s.roughness) * s.roughness) + "," + format_double("%.6g", s.roughness)) +
                   "," + std::to_string(s.width) + "," + std::to_string(s.height) + "," + std::to_string(s.spp) +
                   "," + std::to_string(s.frames) + "," + csv_escape(c.name) + "," + c.family + "," +
                   csv_escape(c.source) + "," + format_double("%.6g", m.rmse) + "," + format_double("%.6g", m.mae) + "," +
                   format_double("%.6g", m.rmse_tonemapped) + "," + format_double("%.6g", m.mae_tonemapped) + "," +
                   format_double("%.6g", m.flicker) + "," + format_double("%.6g", m.flicker_linear) + "," +
                   format_double("%.6g", m.energy_ratio) + "," + format_double("%.6g", m.peak_ratio) + "," + std::to_string(m.pixels) +
                   "," + opt(c.bake_ms, "%.3f") + "," +
                   (c.spirv_instructions ? std::to_string(*c.spirv_instructions) : "") + "," +
                   opt(c.frame_ms, "%.4f") + "," + opt(c.frame_relative, "%.4f") + "," +
                   format_double("%.6g", m.temporal_error) + "," + format_double("%.6g", m.temporal_error_linear) + "\n";
        }
    }
    return out;
}

// A labelled dot of the plot and where its label went: the text's left end and baseline, its width, and
// whether it sits far enough from its dot to need a leader line.
struct PlotPoint {
    double x, y;
    std::string name, colour;
};
struct PlacedLabel {
    double x, y, width;
    bool leader;
};
struct PlotBox {
    double left, top, right, bottom;
};

// Width of a label at the plot's 10 px sans-serif: 6.5 px a character bounds the glyphs' advance
// (0.5-0.6 em for lower case and digits; W and M aside).
constexpr double kLabelCharWidth = 6.5, kLabelHeight = 11.0;

// Labels placed so that none overlaps another label or a dot: beside its dot, right then left, at the
// dot's height or shifted up or down in steps of a line, the nearest free place inside `area` first, then
// the same further out to the sides; the dots are placed from the top of the panel down. A label that
// finds no free place stays beside its dot.
std::vector<PlacedLabel> place_labels(const std::vector<PlotPoint>& points, const PlotBox& area) {
    std::vector<PlotBox> taken;
    for (const PlotPoint& p : points) taken.push_back({p.x - 4, p.y - 4, p.x + 4, p.y + 4});
    const auto free = [&](const PlotBox& b) {
        if (b.left < area.left || b.right > area.right || b.top < area.top || b.bottom > area.bottom) return false;
        for (const PlotBox& t : taken)
            if (b.left < t.right && t.left < b.right && b.top < t.bottom && t.top < b.bottom) return false;
        return true;
    };
    std::vector<size_t> order(points.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return points[a].y < points[b].y; });
    std::vector<PlacedLabel> out(points.size());
    for (size_t i : order) {
        const PlotPoint& p = points[i];
        const double w = kLabelCharWidth * double(p.name.size());
        PlacedLabel chosen{p.x + 6, p.y - 4, w, false};
        bool found = false;
        for (int shift = 0; shift < 4 && !found; ++shift) {
            for (int step = 0; step <= 40 && !found; ++step) {
                const double dy = (step % 2 ? -1.0 : 1.0) * double((step + 1) / 2) * kLabelHeight;
                for (int side = 0; side < 2 && !found; ++side) {
                    const double dx = 6 + 45.0 * shift;
                    const double x = side == 0 ? p.x + dx : p.x - dx - w, baseline = p.y + 3 + dy;
                    const PlotBox box{x, baseline - 9, x + w, baseline + 2};
                    if (free(box)) {
                        chosen = {x, baseline, w, std::abs(dy) > 0 || shift > 0};
                        taken.push_back(box);
                        found = true;
                    }
                }
            }
        }
        out[i] = chosen;
    }
    return out;
}

std::string bench_svg(const BenchReport& r) {
    const std::vector<Aggregate> rows = aggregate(r);
    const int panel_w = 460, panel_h = 360, margin = 60, width = 2 * panel_w + 110, height = panel_h + 105;
    int x_min = 1 << 30, x_max = 0;
    for (const Aggregate& a : rows)
        if (a.spirv) {
            x_min = std::min(x_min, *a.spirv);
            x_max = std::max(x_max, *a.spirv);
        }
    const bool have_x = x_max > 0;
    if (!have_x) {
        x_min = 0;
        x_max = int(rows.size());
    }
    x_min -= 10;
    x_max += 10;
    const std::map<std::string, std::string> colours = {{"none", "#000000"},   {"derivative", "#1f77b4"},
                                                        {"peer", "#d62728"},   {"baked", "#2ca02c"},
                                                        {"default", "#9467bd"}, {"variant", "#8c564b"},
                                                        {"glint", "#ff7f0e"},   {"tier", "#e377c2"}};
    std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(width) + "\" height=\"" +
                      std::to_string(height) + "\" font-family=\"sans-serif\" font-size=\"10\">\n";
    svg += "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
    for (int panel = 0; panel < 2; ++panel) {
        const int ox = panel * (panel_w + 40) + margin, oy = 40, pw = panel_w - margin, ph = panel_h - 40;
        double y_max = 1.2;
        for (const Aggregate& a : rows) y_max = std::max(y_max, panel ? a.rel_flicker() : a.rel_error_linear());
        y_max = std::min(y_max * 1.05, 20.0);
        const auto px = [&](double x) { return ox + (x - x_min) / double(x_max - x_min) * pw; };
        const auto py = [&](double y) { return oy + ph - std::min(y, y_max) / y_max * ph; };
        svg += "<text x=\"" + std::to_string(ox) + "\" y=\"24\" font-size=\"13\">" +
               std::string(panel ? "flicker relative to no filtering" : "RMSE relative to no filtering") +
               "</text>\n";
        svg += "<rect x=\"" + std::to_string(ox) + "\" y=\"" + std::to_string(oy) + "\" width=\"" +
               std::to_string(pw) + "\" height=\"" + std::to_string(ph) + "\" fill=\"none\" stroke=\"#888\"/>\n";
        for (double t = 0; t <= y_max; t += y_max > 4 ? 1.0 : 0.25) {
            svg += "<line x1=\"" + format_double("%.1f", double(ox)) + "\" x2=\"" + format_double("%.1f", double(ox + pw)) + "\" y1=\"" +
                   format_double("%.1f", py(t)) + "\" y2=\"" + format_double("%.1f", py(t)) + "\" stroke=\"" +
                   (std::abs(t - 1.0) < 1e-9 ? "#444" : "#ddd") + "\"/>\n";
            svg += "<text x=\"" + std::to_string(ox - 6) + "\" y=\"" + format_double("%.1f", py(t) + 3) +
                   "\" text-anchor=\"end\">" + format_double("%.2f", t) + "</text>\n";
        }
        svg += "<text x=\"" + format_double("%.1f", ox + pw / 2.0) + "\" y=\"" + std::to_string(oy + ph + 30) +
               "\" text-anchor=\"middle\">" +
               std::string(have_x ? "SPIR-V instructions (spirv-opt -O)" : "candidate") + "</text>\n";
        for (int t = 0; t < 5; ++t) {
            const double x = x_min + (x_max - x_min) * t / 4.0;
            svg += "<text x=\"" + format_double("%.1f", px(x)) + "\" y=\"" + std::to_string(oy + ph + 14) +
                   "\" text-anchor=\"middle\">" + format_double("%.0f", x) + "</text>\n";
        }
        std::vector<PlotPoint> points;
        for (size_t i = 0; i < rows.size(); ++i) {
            const Aggregate& a = rows[i];
            const double x = have_x ? (a.spirv ? double(*a.spirv) : double(x_min)) : double(i);
            const double y = panel ? a.rel_flicker() : a.rel_error_linear();
            points.push_back({px(x), py(y), a.name, colours.count(a.family) ? colours.at(a.family) : "#555"});
        }
        const std::vector<PlacedLabel> labels =
            place_labels(points, {double(ox), double(oy), double(ox + pw + (panel ? margin + 10 : 38)), double(oy + ph)});
        for (size_t i = 0; i < points.size(); ++i) {
            const PlotPoint& p = points[i];
            const PlacedLabel& l = labels[i];
            svg += "<circle cx=\"" + format_double("%.1f", p.x) + "\" cy=\"" + format_double("%.1f", p.y) + "\" r=\"3.5\" fill=\"" +
                   p.colour + "\"/>\n";
            if (l.leader)
                svg += "<line x1=\"" + format_double("%.1f", p.x) + "\" y1=\"" + format_double("%.1f", p.y) + "\" x2=\"" +
                       format_double("%.1f", l.x < p.x ? l.x + l.width : l.x) + "\" y2=\"" + format_double("%.1f", l.y - 3) +
                       "\" stroke=\"" + p.colour + "\" stroke-width=\"0.5\"/>\n";
            svg += "<text x=\"" + format_double("%.1f", l.x) + "\" y=\"" + format_double("%.1f", l.y) + "\" fill=\"" +
                   p.colour + "\">" + p.name + "</text>\n";
        }
    }
    svg += "<text x=\"" + std::to_string(margin) + "\" y=\"" + std::to_string(height - 26) +
           "\">Geometric mean over " + std::to_string(r.scenes.size()) +
           " scene/roughness pairs; below the dark line = better than no filtering.</text>\n";
    svg += "<text x=\"" + std::to_string(margin) + "\" y=\"" + std::to_string(height - 10) +
           "\">Colours: black none, blue derivative, red peers (engines, VAREF), green baked, purple default, pink "
           "tiers, brown bake variants, orange glints (relative to glint-c20).</text>\n";
    svg += "</svg>\n";
    return svg;
}

Result<void> write_bench_outputs(const BenchReport& r, const std::filesystem::path& dir) {
    if (auto w = io::write_file_atomic(dir / "bench.md", bench_full_markdown(r)); !w) return w;
    if (auto w = io::write_file_atomic(dir / "bench.csv", bench_csv(r)); !w) return w;
    if (auto w = io::write_file_atomic(dir / "bench.svg", bench_svg(r)); !w) return w;
    for (const SceneReport& s : r.scenes) {
        const std::string stem = s.from_file ? s.scene : s.scene + "-a" + format_double("%.3g", double(s.roughness) * s.roughness);
        // One strip per ground truth: the GGX candidates' and the glint candidates' (NAME-glints.png).
        for (const bool glint : {false, true}) {
            const SimImage& gt = glint ? s.glint_ground_truth : s.ground_truth;
            if (gt.empty()) continue;
            const StripHarm harm = glint ? StripHarm{} : default_strip_harm(s.candidates);
            const auto path = dir / "strips" / (stem + (glint ? "-glints.png" : ".png"));
            if (auto w = write_strip_png(make_strip(gt, strip_tiles(s.candidates, glint), &harm), path); !w) return w;
        }
    }
    return {};
}

}  // namespace specbake::verify
