// The texture job (`specbake texture`): read the normal and roughness maps, bake them (bake/texture_bake.h),
// write the requested mip chains into one folder and record them in manifest.json. The lower-level
// bake_texture_outputs() is the same pipeline for images already in memory; the scene bake runs its two
// steps apart (the plan bakes, then write_texture_outputs()) and writes one combined manifest itself.
#pragma once

#include "bake/texture_bake.h"
#include "io/files/input_policy.h"
#include "io/image/image_io.h"
#include "io/output/manifest.h"
#include "io/output/output_folder.h"
#include "io/texture/texture_writer.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace specbake {

// Called with short progress lines ("reading ...", "baking 4096x4096 ...", "writing ..."); may be empty.
using ProgressFn = std::function<void(const std::string&)>;
// Called with the fraction [0, 1] of the bake's texels done (all mips), from the baking threads; may be empty.
using FractionFn = std::function<void(double)>;

struct TextureJob {
    std::filesystem::path normal;                  // ignored when demo is set
    std::optional<std::filesystem::path> roughness;
    int roughness_channel = -1;                    // -1: G (index 1) for 3+ channel files, else channel 0
    float roughness_value = 0.5f;                  // used when no roughness file is given
    bool demo = false;                             // bake the built-in procedural normal + ORM maps instead
    std::filesystem::path output_dir;
    io::TextureFileFormat texture_format;          // KTX2 with zstd by default
    TextureBakeSettings settings;
    io::InputLimits limits;                        // the maps' texel counts are checked against them
    ProgressFn progress;
    // The output folder's lock when the caller already holds it (else the job takes it, io/output/bake_output.h).
    const io::OutputLock* lock = nullptr;
    // Replace a bake of another normal map that output_dir holds (refused otherwise).
    bool replace = false;
    FractionFn fraction;                           // the bake runs row by row, every container
};

// The manifest's "supercompression" setting: {"scheme": "zstd", "zstd_level": N} or {"scheme": "none"}.
nlohmann::json supercompression_json(const io::Supercompression& s);

// What a texture job records about how it was asked to bake: the manifest's settings (texture_settings_json
// plus "supercompression", "demo", and "roughness_channel" or "roughness_value"; the job adds "input_facts",
// which the inputs' hashes cover) and the input files as the manifest names them (the demo's: the maps it
// writes). run_texture_job records it and the up-to-date check compares it, so the two cannot disagree.
struct TextureJobRecord {
    nlohmann::json settings;
    std::vector<std::string> inputs;
};
TextureJobRecord texture_job_record(const TextureJob& job);

struct TextureJobOutcome {
    io::Manifest manifest;                         // as written to output_dir/manifest.json
    TextureBakeNotes notes;                        // warnings to print, z reconstruction, ...
    double max_roughness_change = 0.0;             // see TextureBakeResult
};

// Whole pipeline. Errors are one line naming the file: unreadable or invalid input, output folder equal
// to (or holding) an input, a bake of other inputs in it, write failure. Every file is staged and
// committed together with the manifest: on any failure the folder keeps the bake it held.
Result<TextureJobOutcome> run_texture_job(const TextureJob& job);

// Already-decoded inputs for bake_texture_outputs().
struct TextureInputs {
    const Image* normal = nullptr;
    std::string normal_name;                       // for error messages ("<name>: ...")
    const Image* roughness = nullptr;              // null: constant roughness_value
    std::string roughness_name;
    int roughness_channel = -1;                    // as in TextureJob
    float roughness_value = 0.5f;
    int normal_bits = 8;                           // 8 or 16 (integer files), 16/32 float: output encodings
    int roughness_bits = 8;
    // The maps held as 8- or 16-bit texels instead (the texture job's plain PNG inputs, a quarter or half of
    // the float images' memory): used by bake_texture_encoded in place of `normal` / `roughness` when their
    // channels are set. The float-chain path (bake_texture_inputs) reads only the images.
    TextureMap normal_map, roughness_map;
    // The caller drops the integer maps after the bake: their rows may be returned to the system (read as
    // zeroes) once the bake is past them.
    bool release_rows = false;
};

// The bake's view of decoded integer texels (a TextureInputs map, a scene's image); they must stay where
// they are while it is used.
TextureMap texture_map_of(const io::IntegerTexels& texels);

struct TextureOutputsWritten {
    std::vector<io::ManifestOutput> outputs;       // paths relative to the output folder, hashes filled
    TextureBakeNotes notes;
    double max_roughness_change = 0.0;
};

// Bakes and writes `dir/<stem>_roughness.<ext>`, `_kernel`, `_lean` (RGBA = (m.x, m.y, M.xx, M.yy)
// plus `_lean_xy` Y = M.xy), `_normal`, as selected in settings.outputs, 1, 2 or 4 channels each, the
// same layout in every container (docs/texture-bake.md#output-layouts). Does not write a manifest.
Result<TextureOutputsWritten> bake_texture_outputs(const TextureInputs& inputs, const TextureBakeSettings& settings,
                                                   const io::TextureFileFormat& format,
                                                   const std::filesystem::path& dir, const std::string& stem,
                                                   const ProgressFn& progress = {}, const FractionFn& fraction = {});

// bake_texture_outputs() up to the write: the bake encodes every finished row straight
// into the files' bytes (no float chain of the whole map is held). files[i] refers to textures[i].
// `stream_dir`, when given, is the folder write_encoded_textures will write the files to: uncompressed DDS
// files are written there (under temporary names) as their rows finish (io::EncodedTexture::stream_to).
struct EncodedTextureOutputs {
    std::vector<std::unique_ptr<io::EncodedTexture>> textures;
    std::vector<io::EncodedFile> files;
    TextureBakeNotes notes;
    double max_roughness_change = 0.0;
};
Result<EncodedTextureOutputs> bake_texture_encoded(const TextureInputs& inputs, const TextureBakeSettings& settings,
                                                   const io::TextureFileFormat& format, const std::string& stem,
                                                   const ProgressFn& progress = {}, const FractionFn& fraction = {},
                                                   const std::filesystem::path& stream_dir = {});

// The two steps of bake_texture_outputs(), for a caller that needs the bake before deciding to write it
// (`specbake bake` measures the plan's statistic on the bake it writes). Errors name the input files.
Result<TextureBakeResult> bake_texture_inputs(const TextureInputs& inputs, const TextureBakeSettings& settings,
                                              const ProgressFn& progress = {});

// Writes the chains of `baked` selected in settings.outputs, as bake_texture_outputs() does; `inputs`
// gives the output encodings. Each chain is released once written, so peak memory stays one encoding.
Result<TextureOutputsWritten> write_texture_outputs(TextureBakeResult&& baked, const TextureInputs& inputs,
                                                    const TextureBakeSettings& settings,
                                                    const io::TextureFileFormat& format,
                                                    const std::filesystem::path& dir, const std::string& stem,
                                                    const ProgressFn& progress = {});

// The settings as recorded in manifests, with the container and wrap of `format`.
nlohmann::json texture_settings_json(const TextureBakeSettings& settings, const io::TextureFileFormat& format);

// The built-in demo inputs: a 512x384 (deliberately non-power-of-two) RGB normal map of bumps, ribs
// and a flat area, and a matching ORM map, both as 8-bit-quantised values.
Image demo_normal_map();
Image demo_orm_map();

}  // namespace specbake
