// The glint dictionary job (`specbake glints`, and `bake` for materials that ask for glints): bakes the
// C21 dictionary (bake/glint_dictionary.h) and writes it as a KTX2 2D array with its manifest entry.
#pragma once

#include "bake/glint_dictionary.h"
#include "io/output/manifest.h"

#include <nlohmann/json.hpp>

#include <filesystem>

namespace specbake {

inline constexpr const char* kGlintDictionaryFile = "glint_dictionary.ktx2";

// Every parameter a run time needs to read the dictionary (and to rebuild it): sizes, the slope range,
// the target, the seed, the texture layout and addressing.
nlohmann::json glint_dictionary_parameters(const GlintDictionarySettings& s);

// Largest |integral - 1| over every marginal, level and mip of the stored (half) values, under the GPU
// lookup of the layout (2 D_m sum_x v_x, see bake_glint_dictionary).
double glint_dictionary_max_integral_error(const GlintDictionary& d);

// Writes dir/glint_dictionary.ktx2 atomically (R16G16B16A16_SFLOAT, 2D array of levels x count / 4 layers
// of width x 1 texels, full mip chain). Returns its manifest entry (sha256 of the written bytes, the
// parameters and the measured integral error as extra facts). The dictionary depends on its settings
// only, so it is baked once per process and settings (shared_glint_dictionary); with `committed_dir`
// (the folder a staged bake commits to) a dictionary already committed there is copied instead of baked
// when the folder's manifest lists it from this tool version with the same parameters and its bytes
// hash to the listed sha256 (`*reused` then says so). Either way the bytes and the entry are the same.
Result<io::ManifestOutput> write_glint_dictionary(const GlintDictionarySettings& s, const std::filesystem::path& dir,
                                                  const std::filesystem::path& committed_dir = {},
                                                  bool* reused = nullptr);

// `specbake glints -o DIR`: the dictionary and DIR/manifest.json.
Result<io::Manifest> run_glint_job(const GlintDictionarySettings& s, const std::filesystem::path& dir);

}  // namespace specbake
