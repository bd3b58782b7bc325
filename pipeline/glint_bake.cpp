// Glint steps of the scene bake: LEAN settings before planning, dictionary and extension entries after.
#include "pipeline/glint_bake.h"

#include "pipeline/glint_job.h"

namespace specbake {
using nlohmann::json;

Result<void> add_glint_lean_settings(const io::GltfScene& scene, PlanOptions& options) {
    auto asked = plan_glints(scene, options.material_glints);
    if (!asked) return asked.error();
    for (const GlintDecision& g : *asked) {
        if (!g.bake || !g.normal_map || g.material_name.empty()) continue;
        TextureBakeSettings t = options.texture_settings_for(g.material_name);
        t.outputs.lean = true;
        t.lean_space = LeanSpace::Slope;
        options.material_texture_settings[g.material_name] = t;
    }
    return {};
}

Result<void> add_glint_outputs(const ScenePlan& plan, const std::filesystem::path& out_dir,
                               const std::filesystem::path& final_dir, const std::function<void(const std::string&)>& say,
                               const std::map<std::string, std::vector<io::ManifestOutput>>& files_by_stem,
                               std::map<int, json>& extension_of_material, std::vector<std::filesystem::path>& written,
                               std::vector<io::ManifestOutput>& outputs) {
    const GlintDictionarySettings settings;
    bool dictionary = false;
    for (const GlintDecision& g : plan.glints) {
        if (!g.bake) continue;
        if (!dictionary) {
            bool reused = false;
            auto entry = write_glint_dictionary(settings, out_dir, final_dir, &reused);
            if (!entry) return entry.error();
            if (say)
                say(std::string(reused ? "glint dictionary: the committed one is reused (same parameters and hash)"
                                       : "glint dictionary: baked") +
                    " for " + final_dir.string());
            written.push_back(out_dir / entry->path);
            outputs.push_back(*entry);
            dictionary = true;
        }
        json glints = io::glint_material_json(g.params);
        glints["dictionary"] = {{"uri", kGlintDictionaryFile}, {"parameters", glint_dictionary_parameters(settings)}};
        glints["lean"] = json::array();
        for (const TextureDecision& d : plan.textures) {
            if (d.material != g.material || d.layer != "base" || !d.bake) continue;
            const TextureDecision& owner = d.same_as >= 0 ? plan.textures[size_t(d.same_as)] : d;
            auto files = files_by_stem.find(owner.stem);
            if (files == files_by_stem.end()) continue;
            for (const io::ManifestOutput& o : files->second)
                if (o.kind == "lean") glints["lean"].push_back(o.path);
        }
        if (!glints["lean"].empty()) glints["leanSpace"] = "slope";
        json& target = extension_of_material[g.material];
        if (target.is_null()) target = json::object();
        target["glints"] = std::move(glints);
    }
    return {};
}

}  // namespace specbake
