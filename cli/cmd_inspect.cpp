// `specbake inspect`: statistics, histograms, differences, structural checks and a contact sheet of baked
// textures and manifests.
#include "cli/command.h"
#include "cli/run_settings.h"
#include "pipeline/inspect.h"

#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>

namespace specbake::cli {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

struct InspectOptions {
    std::vector<std::string> files;
    bool json = false;
    bool check = false;
    bool all = false;
    std::string kind;
    std::string sheet;
};

// A folder stands for the manifest in it.
fs::path resolve(const std::string& file) {
    std::error_code ec;
    return fs::is_directory(file, ec) ? fs::path(file) / "manifest.json" : fs::path(file);
}

bool is_manifest(const fs::path& p) { return p.extension() == ".json"; }

int run_check(const InspectOptions& o) {
    const io::InputLimits& limits = run_settings().input_policy.limits;
    // -q: the errors alone (and the exit code); -v adds nothing here.
    const bool quiet = run_settings().verbosity == Verbosity::quiet;
    int failed = 0;
    for (const std::string& f : o.files) {
        const fs::path p = resolve(f);
        std::vector<std::string> problems;
        if (is_manifest(p)) {
            FolderCheck c = check_manifest_folder(p, limits, [&](const std::string& line) {
                if (!o.json && !quiet) std::fprintf(stderr, "specbake: %s\n", line.c_str());
            });
            for (const std::string& note : c.notes)
                if (!o.json && !quiet) std::fprintf(stderr, "specbake: note: %s\n", note.c_str());
            problems = std::move(c.problems);
        } else {
            auto r = io::check_texture_file(p, limits);
            if (!r) problems.push_back(r.error().message);
        }
        for (const std::string& problem : problems) print_error(problem);
        failed += !problems.empty();
        if (problems.empty() && !o.json && !quiet) std::printf("%s: ok\n", p.string().c_str());
    }
    if (o.json) std::printf("%s\n", json{{"checked", o.files.size()}, {"malformed", failed}}.dump(2).c_str());
    return failed ? kExitFailed : kExitOk;
}

// Pairs the textures of two manifests by their path inside the output folder.
Result<json> diff_manifests(const ManifestReport& a, const ManifestReport& b, const fs::path& dir_a,
                            const fs::path& dir_b) {
    std::map<std::string, const TextureReport*> in_b;
    for (const TextureReport& t : b.textures) in_b[fs::relative(t.path, dir_b).generic_string()] = &t;
    json diffs = json::array();
    for (const TextureReport& t : a.textures) {
        const std::string rel = fs::relative(t.path, dir_a).generic_string();
        auto it = in_b.find(rel);
        if (it == in_b.end()) {
            diffs.push_back({{"a", t.path}, {"missing_in_b", true}});
            continue;
        }
        auto d = diff_textures(t, *it->second);
        if (!d) return d.error();
        diffs.push_back(*d);
        in_b.erase(it);
    }
    for (const auto& [rel, t] : in_b) diffs.push_back({{"b", t->path}, {"missing_in_a", true}});
    return diffs;
}

int run_diff(const InspectOptions& o) {
    const io::InputLimits& limits = run_settings().input_policy.limits;
    const fs::path pa = resolve(o.files[0]), pb = resolve(o.files[1]);
    json diffs = json::array();
    if (is_manifest(pa) != is_manifest(pb)) {
        print_error(pa.string() + " and " + pb.string() + ": compare two textures or two manifests");
        return kExitUsage;
    }
    if (is_manifest(pa)) {
        auto a = inspect_manifest(pa, false, limits);
        auto b = inspect_manifest(pb, false, limits);
        if (!a || !b) {
            print_error((!a ? a.error() : b.error()).message);
            return kExitFailed;
        }
        auto d = diff_manifests(*a, *b, pa.parent_path(), pb.parent_path());
        if (!d) {
            print_error(d.error().message);
            return kExitFailed;
        }
        diffs = std::move(*d);
    } else {
        auto a = inspect_texture(pa, o.kind, limits);
        auto b = inspect_texture(pb, o.kind, limits);
        if (!a || !b) {
            print_error((!a ? a.error() : b.error()).message);
            return kExitFailed;
        }
        auto d = diff_textures(*a, *b);
        if (!d) {
            print_error(d.error().message);
            return kExitFailed;
        }
        diffs.push_back(std::move(*d));
    }
    if (o.json) {
        std::printf("%s\n", json{{"diff", diffs}}.dump(2).c_str());
    } else {
        for (const json& d : diffs) {
            if (d.contains("missing_in_b")) {
                std::printf("%s: not in the second bake\n", d["a"].get<std::string>().c_str());
            } else if (d.contains("missing_in_a")) {
                std::printf("%s: not in the first bake\n", d["b"].get<std::string>().c_str());
            } else {
                std::printf("%s", diff_text(d).c_str());
            }
        }
    }
    return kExitOk;
}

int run_inspect(const InspectOptions& o) {
    const io::InputLimits& limits = run_settings().input_policy.limits;
    if (o.check) return run_check(o);
    if (o.files.size() == 2 && o.sheet.empty()) return run_diff(o);
    std::vector<TextureReport> textures;
    json out = {{"files", json::array()}, {"manifests", json::array()}};
    int failed = 0;
    for (const std::string& f : o.files) {
        const fs::path p = resolve(f);
        if (is_manifest(p)) {
            auto m = inspect_manifest(p, false, limits);
            if (!m) {
                print_error(m.error().message);
                ++failed;
                continue;
            }
            for (const std::string& problem : m->problems) print_error(problem);
            failed += !m->problems.empty();
            json mj = {{"path", p.string()}, {"manifest", m->manifest}, {"textures", json::array()}};
            if (!o.json) {
                const json& man = m->manifest;
                std::printf("%s: specbake %s, %zu inputs, %zu outputs\n", p.string().c_str(),
                            man["version"].get<std::string>().c_str(), man["inputs"].size(), man["outputs"].size());
                for (const json& e : man["outputs"])
                    std::printf("  %-10s %-5s %s\n", e["kind"].get<std::string>().c_str(),
                                e["format"].get<std::string>().c_str(), e["path"].get<std::string>().c_str());
            }
            for (TextureReport& t : m->textures) {
                if (o.json) {
                    mj["textures"].push_back(report_json(t));
                } else {
                    std::printf("%s", report_text(t, o.all).c_str());
                }
                textures.push_back(std::move(t));
            }
            out["manifests"].push_back(std::move(mj));
            continue;
        }
        auto t = inspect_texture(p, o.kind, limits);
        if (!t) {
            print_error(t.error().message);
            ++failed;
            continue;
        }
        if (o.json) {
            out["files"].push_back(report_json(*t));
        } else {
            std::printf("%s", report_text(*t, o.all).c_str());
        }
        textures.push_back(std::move(*t));
    }
    if (o.json) std::printf("%s\n", out.dump(2).c_str());
    if (!o.sheet.empty() && !textures.empty()) {
        auto r = write_contact_sheet(textures, o.sheet);
        if (!r) {
            print_error(r.error().message);
            return kExitFailed;
        }
    }
    return failed ? kExitFailed : kExitOk;
}

}  // namespace

void add_inspect_command(CLI::App& app, std::function<int()>& run) {
    auto* sub = app.add_subcommand(
        "inspect", "Show what a bake wrote: per-mip statistics and histograms, differences, structure checks");
    auto o = std::make_shared<InspectOptions>();
    sub->add_option("files", o->files,
                    "KTX2, DDS, EXR or PNG files, manifest.json files or output folders. Two files: their "
                    "per-mip differences")
        ->required();
    sub->add_flag("--json", o->json, "Print JSON instead of tables");
    sub->add_flag("--check", o->check,
                  "Validate the container structure (KTX2 level index, DFD, sizes; DDS header) and, for a "
                  "manifest, every output's hash; exit 1 when anything is malformed");
    sub->add_flag("--all", o->all, "Also list the raw channels when derived quantities are shown");
    sub->add_option("--kind", o->kind, "What the files hold, when their names do not say it")
        ->check(CLI::IsMember({"roughness", "kernel", "lean", "lean_xy", "normal"}));
    sub->add_option("--sheet", o->sheet, "Write a false-colour contact sheet of all mips (PNG)");
    sub->footer(
        "Derived quantities: roughness (r), kernel (t or tr(Sigma)), LEAN variance tr(Sigma) and\n"
        "lambda_max with Sigma = M - m m^T. Percentiles are nearest-rank.\n"
        "Examples:\n"
        "  specbake inspect out/rock_roughness.ktx2\n"
        "  specbake inspect out/ --json\n"
        "  specbake inspect out/rock_lean.ktx2 --sheet lean.png\n"
        "  specbake inspect old/ new/              (per-mip differences of two bakes)\n"
        "  specbake inspect --check out/*.ktx2 out/*.dds");
    sub->callback([&run, o] { run = [o] { return run_inspect(*o); }; });
}

}  // namespace specbake::cli
