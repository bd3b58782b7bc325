// Texture bake (SPEC Sec. 3), the public entry points: the chains' shape, the mip level count, and the
// bake into float chains or to a row sink. See texture_bake.h for the footprint convention.
//
// The bake itself is spread over the bake/texture_bake_*.cpp files (texture_bake_internal.h describes the
// scheme): texture_bake_levels.cpp schedules the levels and streams the rows, texture_bake_decode.cpp reads
// the input maps, texture_bake_planes.cpp and texture_bake_pairs.cpp reduce the base rows (plane path and
// AVX2 register pass), texture_bake_texel.cpp holds the per-texel formulas, texture_bake_inputs.cpp the
// input checks.
#include "bake/texture_bake.h"

#include "bake/texture_bake_internal.h"
#include "core/assert.h"
#include "core/huge_pages.h"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cstring>

namespace specbake {
namespace {

// A zero-filled w x h image. Large buffers are reserved first and marked for transparent huge pages before
// they are touched: a 4096^2 bake writes about 1 GiB of fresh outputs, and faulting it in 4 KiB pages costs
// more CPU time than the arithmetic.
Image make_output_image(int w, int h, int channels) {
    Image image;
    image.width = w, image.height = h, image.channels = channels;
    const size_t n = size_t(w) * size_t(h) * size_t(channels);
    detail::reserve_huge_pages(image.pixels, n);
    image.pixels.resize(n);
    return image;
}

// Levels 0 .. levels-1 of a W x H chain; none when channels is 0 (output not requested).
void allocate_chain(MipChain& chain, int W, int H, int levels, int channels) {
    chain.levels.clear();
    if (channels <= 0) return;
    for (int L = 0; L < levels; ++L)
        chain.levels.push_back(make_output_image(std::max(1, W >> L), std::max(1, H >> L), channels));
}

}  // namespace

using texture_bake_detail::bake_validated;
using texture_bake_detail::run_with_threads;
using texture_bake_detail::validate;
using texture_bake_detail::validate_buffers;

int mip_level_count(int width, int height) {
    int n = 1;
    for (int s = std::max(width, height); s > 1; s >>= 1) ++n;
    return n;
}

TextureBakeShape texture_bake_shape(const TextureMap& normal, const TextureMap* roughness, int roughness_channel,
                                    const TextureBakeSettings& settings) {
    TextureBakeShape shape;
    shape.width = normal.width, shape.height = normal.height;
    shape.levels = normal.empty() ? 0 : mip_level_count(normal.width, normal.height);
    const bool orm = roughness && roughness->channels >= 3 && roughness_channel == 1;
    const TextureOutputs& want = settings.outputs;
    shape.roughness_channels = want.roughness ? (orm ? 3 : 1) : 0;
    shape.kernel_channels = want.kernel ? (settings.anisotropic ? 4 : 1) : 0;
    shape.lean_channels = want.lean ? 5 : 0;
    shape.normal_channels = want.normal ? 3 : 0;
    return shape;
}

TextureBakeShape texture_bake_shape(const Image& normal, const Image* roughness, int roughness_channel,
                                    const TextureBakeSettings& settings) {
    const TextureMap r = roughness ? TextureMap::of(*roughness) : TextureMap{};
    return texture_bake_shape(TextureMap::of(normal), roughness ? &r : nullptr, roughness_channel, settings);
}

Result<TextureBakeResult> bake_texture_rows(const TextureMap& normal, const TextureMap* roughness, int roughness_channel,
                                            float roughness_value, const TextureBakeSettings& settings,
                                            const TextureBakeRowSink& sink, const TextureBakeRowsDone& rows_done,
                                            const TextureBakeInputsDone& inputs_done) {
    if (auto ok = validate(normal, roughness, roughness_channel, roughness_value); !ok) return ok.error();
    return bake_validated({normal, roughness, roughness_channel, roughness_value}, settings,
                          {sink, rows_done, inputs_done});
}

Result<TextureBakeResult> bake_texture_rows(const Image& normal, const Image* roughness, int roughness_channel,
                                            float roughness_value, const TextureBakeSettings& settings,
                                            const TextureBakeRowSink& sink) {
    if (auto ok = validate_buffers(normal, roughness); !ok) return ok.error();
    const TextureMap r = roughness ? TextureMap::of(*roughness) : TextureMap{};
    return bake_texture_rows(TextureMap::of(normal), roughness ? &r : nullptr, roughness_channel, roughness_value,
                             settings, sink);
}

Result<TextureBakeResult> bake_texture(const Image& normal, const Image* roughness, int roughness_channel,
                                       float roughness_value, const TextureBakeSettings& settings) {
    if (auto ok = validate_buffers(normal, roughness); !ok) return ok.error();
    const TextureMap roughness_map = roughness ? TextureMap::of(*roughness) : TextureMap{};
    return bake_texture(TextureMap::of(normal), roughness ? &roughness_map : nullptr, roughness_channel,
                        roughness_value, settings);
}

Result<TextureBakeResult> bake_texture(const TextureMap& normal_map, const TextureMap* rough, int roughness_channel,
                                       float roughness_value, const TextureBakeSettings& settings) {
    if (auto ok = validate(normal_map, rough, roughness_channel, roughness_value); !ok) return ok.error();
    const TextureBakeShape shape = texture_bake_shape(normal_map, rough, roughness_channel, settings);
    MipChain rough_chain, kern, lean, nrm;
    // The chains are allocated (and zero-filled) on two threads: LEAN, the widest, against the other three.
    run_with_threads(settings.threads, [&] {
        tbb::parallel_invoke(
            [&] { allocate_chain(lean, shape.width, shape.height, shape.levels, shape.lean_channels); },
            [&] {
                allocate_chain(rough_chain, shape.width, shape.height, shape.levels, shape.roughness_channels);
                allocate_chain(kern, shape.width, shape.height, shape.levels, shape.kernel_channels);
                allocate_chain(nrm, shape.width, shape.height, shape.levels, shape.normal_channels);
            });
    });
    auto copy_rows = [](MipChain& chain, const TextureBakeRows& r, const float* src) {
        if (!src) return;
        SPECBAKE_ASSERT(r.level >= 0 && size_t(r.level) < chain.levels.size());
        Image& level = chain.levels[size_t(r.level)];
        SPECBAKE_ASSERT(r.x0 >= 0 && r.y0 >= 0 && r.x0 + r.width <= level.width && r.y0 + r.rows <= level.height);
        const size_t row_floats = size_t(r.width) * size_t(level.channels);
        for (int k = 0; k < r.rows; ++k)
            std::memcpy(level.texel(r.x0, r.y0 + k), src + size_t(k) * row_floats, row_floats * sizeof(float));
    };
    const TextureBakeRowSink sink = [&](const TextureBakeRows& r) {
        copy_rows(rough_chain, r, r.roughness);
        copy_rows(kern, r, r.kernel);
        copy_rows(lean, r, r.lean);
        copy_rows(nrm, r, r.normal);
    };
    auto baked = bake_validated({normal_map, rough, roughness_channel, roughness_value}, settings, {sink, {}, {}});
    if (!baked) return baked;
    baked->roughness = std::move(rough_chain);
    baked->kernel = std::move(kern);
    baked->lean = std::move(lean);
    baked->normal = std::move(nrm);
    return baked;
}

std::vector<std::string_view> to_names(const TextureOutputs& outputs) {
    const bool selected[] = {outputs.roughness, outputs.kernel, outputs.lean, outputs.normal};
    std::vector<std::string_view> names;
    for (size_t i = 0; i < kTextureOutputNames.size(); ++i)
        if (selected[i]) names.push_back(kTextureOutputNames[i]);
    return names;
}

bool select_texture_output(TextureOutputs& outputs, std::string_view name) {
    bool* const flags[] = {&outputs.roughness, &outputs.kernel, &outputs.lean, &outputs.normal};
    for (size_t i = 0; i < kTextureOutputNames.size(); ++i)
        if (kTextureOutputNames[i] == name) return *flags[i] = true;
    return false;
}

Result<TextureOutputs> parse_texture_outputs(std::string_view list) {
    TextureOutputs outputs{false, false, false, false};
    // As std::getline splits: items between commas, a trailing empty item dropped.
    while (!list.empty()) {
        const size_t comma = list.find(',');
        const std::string_view item = list.substr(0, comma);
        if (!select_texture_output(outputs, item))
            return make_error("'" + std::string(item) + "' is not one of roughness, kernel, lean, normal");
        list = comma == std::string_view::npos ? std::string_view() : list.substr(comma + 1);
    }
    return outputs;
}

}  // namespace specbake
