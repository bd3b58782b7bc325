// Texture bake (SPEC Sec. 3): the distribution of normal-map normals inside every texel footprint of every
// mip level, turned into filtered roughness, kernel, LEAN-moment and mean-normal mip chains.
//
// Footprints: level L of a W x H map is max(1, W >> L) x max(1, H >> L). Texel (i, j) of level L with size
// w x h covers the base-texel rectangle [i W/w, (i+1) W/w) x [j H/h, (j+1) H/h); every base texel weighs by
// the area it shares with that rectangle. For power-of-two sizes this is the usual 2^L x 2^L box with equal
// weights; for other sizes the boundary texels are split by area. All levels are exact area-weighted means
// over the base texels (moments are linear: a level whose footprints tile a finer level's footprints is
// summed from it exactly, any other level from the base), accumulated in double in a fixed order, so the
// output is byte-identical for any thread count. Pure computation: no file I/O.
#pragma once

#include "core/image.h"
#include "bake/isotropic_filter.h"
#include "core/result.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace specbake {

enum class RoughnessFilterMode { Projected, Approx };  // SPEC Sec. 3: TK21 Eq. (4)-(7) closed form | Eq. (9)
enum class NormalGreen { PlusY, MinusY };               // +Y: OpenGL/glTF (default), -Y: DirectX
// Auto: two channels or constant full-scale blue. Gltf: the glTF decode, n = normalize(2c - 1) with the
// stored blue channel whatever it holds (glTF 2.0 Sec. 3.9.3; what the viewer shades), z rebuilt only for
// a two-channel map (scene bakes).
enum class ReconstructZ { Auto, Always, Never, Gltf };
enum class LeanSpace { Projected, Slope };              // SPEC Sec. 3 LEAN texture: projected (default) | slope

// The CLI, config and manifest spellings, in enum order.
inline constexpr std::array<std::string_view, 2> kRoughnessFilterModeNames{"projected", "approx"};
inline constexpr std::array<std::string_view, 2> kNormalGreenNames{"+y", "-y"};
inline constexpr std::array<std::string_view, 4> kReconstructZNames{"auto", "always", "never", "gltf"};
inline constexpr std::array<std::string_view, 2> kLeanSpaceNames{"projected", "slope"};
inline std::string_view to_string(RoughnessFilterMode m) { return kRoughnessFilterModeNames[size_t(m)]; }
inline std::string_view to_string(NormalGreen g) { return kNormalGreenNames[size_t(g)]; }
inline std::string_view to_string(ReconstructZ z) { return kReconstructZNames[size_t(z)]; }
inline std::string_view to_string(LeanSpace s) { return kLeanSpaceNames[size_t(s)]; }
inline std::optional<RoughnessFilterMode> parse_roughness_filter_mode(std::string_view name) {
    return enum_from_name<RoughnessFilterMode>(kRoughnessFilterModeNames, name);
}
inline std::optional<NormalGreen> parse_normal_green(std::string_view name) {
    return enum_from_name<NormalGreen>(kNormalGreenNames, name);
}
inline std::optional<ReconstructZ> parse_reconstruct_z(std::string_view name) {
    return enum_from_name<ReconstructZ>(kReconstructZNames, name);
}
inline std::optional<LeanSpace> parse_lean_space(std::string_view name) {
    return enum_from_name<LeanSpace>(kLeanSpaceNames, name);
}

struct TextureOutputs {
    bool roughness = true;
    bool kernel = true;
    bool lean = true;
    bool normal = true;
};

// The outputs' names, in the order manifests list them.
inline constexpr std::array<std::string_view, 4> kTextureOutputNames{"roughness", "kernel", "lean", "normal"};
// The names of the outputs `outputs` selects, in kTextureOutputNames order.
std::vector<std::string_view> to_names(const TextureOutputs& outputs);
// Adds the output called `name` to `outputs`; false when no output has that name.
bool select_texture_output(TextureOutputs& outputs, std::string_view name);
// A comma list of output names ("roughness,lean"; empty: none). The error names the first unknown item:
// "'x' is not one of roughness, kernel, lean, normal".
Result<TextureOutputs> parse_texture_outputs(std::string_view list);

struct TextureBakeSettings {
    IsotropicReduction isotropic = IsotropicReduction::Mean;
    RoughnessFilterMode filter = RoughnessFilterMode::Projected;
    std::optional<double> max_kernel;     // clamp of the isotropic kernel t; none by default
    NormalGreen normal_y = NormalGreen::PlusY;
    ReconstructZ reconstruct_z = ReconstructZ::Auto;
    // Kernel output = Sigma (xx, yy, xy) (default) instead of t. The default rule needs the axes: a mip texel
    // on a bump's rim spreads along the slope only, and t = tr(Sigma) in both axes lights a crescent along
    // the rim (docs/accuracy.md#why-the-kernel-is-sigma-not-t, NormalTangentMirrorTest near).
    bool anisotropic = true;
    LeanSpace lean_space = LeanSpace::Projected;
    TextureOutputs outputs;
    int threads = 0;                      // 0: all available (TBB default); the result does not depend on it
};

// What the bake noticed about its inputs, for the user and the manifest.
struct TextureBakeNotes {
    bool z_reconstructed = false;         // z rebuilt from x, y (two channels, constant blue, or asked for)
    std::string z_reason;                 // "two-channel map", "constant full-scale blue channel", "requested"
    std::string z_decode;                 // how z was read: "rebuilt (REASON)" or "stored blue channel"
    bool looks_srgb = false;              // decoded vectors are far from unit length unless sRGB-decoded first
    bool roughness_is_orm = false;        // roughness came from a 3+ channel map; R and B carried through
    bool roughness_resampled = false;     // roughness map resolution differs from the normal map's
    long long degenerate_normals = 0;     // texels whose decoded vector had zero length (treated as +Z)
    std::vector<std::string> warnings;    // one line each, ready to print
};

// An input map as the bake reads it: `channels` interleaved values per texel, row y starting `row_stride`
// values after row y - 1. The values are floats, or 8- or 16-bit integers v standing for
// float(v) * (1.0f / 255.0f) or float(v) * (1.0f / 65535.0f), the value io/image/image_io.h decodes them to,
// so a bake of the integers equals the bake of the decoded floats while holding a quarter (8-bit) or half
// (16-bit) of the memory. Exactly one of f32, u8 and u16 is set. The memory is the caller's.
struct TextureMap {
    int width = 0, height = 0, channels = 0;
    size_t row_stride = 0;
    const float* f32 = nullptr;
    const uint8_t* u8 = nullptr;
    const uint16_t* u16 = nullptr;

    static TextureMap of(const Image& image) {
        return {image.width, image.height, image.channels, size_t(image.width) * size_t(image.channels),
                image.pixels.data(), nullptr};
    }
    bool empty() const { return width <= 0 || height <= 0 || channels <= 0; }
    float value(int x, int y, int c) const {
        const size_t i = size_t(y) * row_stride + size_t(x) * size_t(channels) + size_t(c);
        return f32 ? f32[i] : u8 ? float(u8[i]) * (1.0f / 255.0f) : float(u16[i]) * (1.0f / 65535.0f);
    }
};

// Mip chains, level 0 first, each as large as the normal map's chain. Empty when not requested.
struct TextureBakeResult {
    MipChain roughness;   // 1 channel r, or 3 channels (occlusion, r, metallic) for an ORM input
    MipChain kernel;      // 1 channel t, or 4 channels (Sigma.xx, Sigma.yy, Sigma.xy, rough share) when anisotropic
    MipChain lean;        // 5 channels (m.x, m.y, M.xx, M.yy, M.xy), projected or slope space
    MipChain normal;      // 3 channels, the normalised mean normal re-encoded as (n + 1) / 2 (green as input)
    TextureBakeNotes notes;
    // max over all texels of all levels of |r_out - r_in|, r_in = (box-filtered alpha^2)^(1/4): how much the
    // bake changes roughness beyond plain mipmapping of alpha^2 (for "would it differ visibly").
    double max_roughness_change = 0.0;
};

// Bakes `normal` (2, 3 or 4 channels; 4th ignored) with roughness from channel `roughness_channel` of
// `roughness` (any resolution; R and B carried through when it has 3+ channels and roughness_channel is 1)
// or, when `roughness` is null, the constant perceptual roughness `roughness_value` in [0, 1].
// Errors: empty maps, 1-channel normal map, NaN or infinity in a value it reads, channel out of range,
// roughness_value outside [0, 1]. Messages say "normal map: ..." / "roughness map: ..."; callers prefix the file name.
Result<TextureBakeResult> bake_texture(const Image& normal, const Image* roughness, int roughness_channel,
                                       float roughness_value, const TextureBakeSettings& settings);

// The same on maps in any TextureMap storage (integer inputs held as they were decoded).
Result<TextureBakeResult> bake_texture(const TextureMap& normal, const TextureMap* roughness, int roughness_channel,
                                       float roughness_value, const TextureBakeSettings& settings);

// The block of texels [x0, x0 + width) x [y0, y0 + rows) of mip level `level`: `rows` rows of `width`
// texels, interleaved with the channels of the matching TextureBakeResult chain; null for an output that
// was not requested. Valid during the call only. Large levels arrive in column blocks that fit the cache.
struct TextureBakeRows {
    int level = 0;
    int x0 = 0;
    int y0 = 0;
    int rows = 0;
    int width = 0;
    const float* roughness = nullptr;
    const float* kernel = nullptr;
    const float* lean = nullptr;
    const float* normal = nullptr;
};

// Receives every texel of every level exactly once, from several threads at once (disjoint blocks), in no
// particular order. The values do not depend on the thread count.
using TextureBakeRowSink = std::function<void(const TextureBakeRows&)>;

// Channel counts of the chains bake_texture() would return for these inputs (0: output not requested).
struct TextureBakeShape {
    int width = 0, height = 0, levels = 0;
    int roughness_channels = 0, kernel_channels = 0, lean_channels = 0, normal_channels = 0;
};
TextureBakeShape texture_bake_shape(const Image& normal, const Image* roughness, int roughness_channel,
                                    const TextureBakeSettings& settings);
TextureBakeShape texture_bake_shape(const TextureMap& normal, const TextureMap* roughness, int roughness_channel,
                                    const TextureBakeSettings& settings);

// bake_texture() without materialising the chains: every finished block of texels goes to `sink`, so a
// caller can encode outputs straight into their containers. The returned result has empty chains.
Result<TextureBakeResult> bake_texture_rows(const Image& normal, const Image* roughness, int roughness_channel,
                                            float roughness_value, const TextureBakeSettings& settings,
                                            const TextureBakeRowSink& sink);
// Called on the bake's calling thread, between the sink's calls, once rows [0, rows) of `level` have all
// gone to the sink; `rows` grows with each call for a level, up to the level's height. A caller can then
// finish the data of those rows (the texture job zstd-compresses them) while the bake goes on.
using TextureBakeRowsDone = std::function<void(int level, int rows)>;
// Called there too once rows [0, rows) of the normal map, and of a roughness map of the same size, will not
// be read again: a caller can release them (a roughness map of another size is read before the bands).
// Only for integer maps (float maps are read again to name a non-finite texel) baked with rows_done.
using TextureBakeInputsDone = std::function<void(int rows)>;

// The same on maps in any TextureMap storage (integer inputs held as they were decoded). With `rows_done`,
// the largest levels are baked in bands of rows from the top down (each band on all threads), reported as
// each band is done; the values are the same.
Result<TextureBakeResult> bake_texture_rows(const TextureMap& normal, const TextureMap* roughness, int roughness_channel,
                                            float roughness_value, const TextureBakeSettings& settings,
                                            const TextureBakeRowSink& sink, const TextureBakeRowsDone& rows_done = {},
                                            const TextureBakeInputsDone& inputs_done = {});

// Number of mip levels of a W x H chain: 1 + floor(log2(max(W, H))).
int mip_level_count(int width, int height);

// The first texel (x, y) holding NaN or infinity, if any: for error messages naming the texel.
std::optional<std::pair<int, int>> find_non_finite(const Image& image);

}  // namespace specbake
