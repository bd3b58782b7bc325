#include "io/texture/astc_codec.h"

#include <astcenc.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <memory>
#include <string>

namespace specbake::io {
namespace {

struct ContextFree {
    void operator()(astcenc_context* c) const { astcenc_context_free(c); }
};
using Context = std::unique_ptr<astcenc_context, ContextFree>;

Result<Context> make_context(int side, unsigned flags, unsigned threads) {
    astcenc_config config;
    astcenc_error e = astcenc_config_init(ASTCENC_PRF_LDR, unsigned(side), unsigned(side), 1, ASTCENC_PRE_MEDIUM,
                                          flags, &config);
    if (e != ASTCENC_SUCCESS) return make_error(std::string("astcenc configuration: ") + astcenc_get_error_string(e));
    astcenc_context* ctx = nullptr;
    e = astcenc_context_alloc(&config, threads, &ctx);
    if (e != ASTCENC_SUCCESS) return make_error(std::string("astcenc context: ") + astcenc_get_error_string(e));
    return Context(ctx);
}

}  // namespace

bool astc_block_supported(int side) { return side == 4 || side == 6 || side == 8; }

uint32_t astc_vk_format(int side) { return side == 4 ? 157 : side == 6 ? 165 : side == 8 ? 171 : 0; }

uint64_t astc_level_bytes(int side, uint64_t w, uint64_t h) {
    const uint64_t s = uint64_t(side);
    return (w + s - 1) / s * ((h + s - 1) / s) * 16;
}

struct AstcEncoder::State {
    Context ctx;
    int side;
    unsigned threads;
};

AstcEncoder::AstcEncoder(std::unique_ptr<State> state) : state_(std::move(state)) {}
AstcEncoder::AstcEncoder(AstcEncoder&&) noexcept = default;
AstcEncoder& AstcEncoder::operator=(AstcEncoder&&) noexcept = default;
AstcEncoder::~AstcEncoder() = default;

Result<AstcEncoder> AstcEncoder::create(int side, int threads) {
    if (!astc_block_supported(side)) return make_error("ASTC footprint " + std::to_string(side) + " is not 4, 6 or 8");
    const unsigned count =
        unsigned(std::clamp(threads > 0 ? threads : tbb::this_task_arena::max_concurrency(), 1, 64));
    auto ctx = make_context(side, 0, count);
    if (!ctx) return ctx.error();
    return AstcEncoder(std::make_unique<State>(State{std::move(*ctx), side, count}));
}

Result<std::vector<uint8_t>> AstcEncoder::compress(const uint8_t* texels, int width, int height, int channels,
                                                   int used) {
    if ((used != 1 && used != 2 && used != 4) || used > channels)
        return make_error("ASTC keeps 1, 2 or 4 of the stored channels, not " + std::to_string(used) + " of " +
                          std::to_string(channels));
    if (width <= 0 || height <= 0) return make_error("ASTC level of zero size");
    // The RGBA the encoder sees (see the header): luminance, (x, y, 0, 1), or RGBA as stored.
    const size_t n = size_t(width) * size_t(height);
    std::vector<uint8_t> rgba(n * 4);
    for (size_t i = 0; i < n; ++i) {
        const uint8_t* s = texels + i * size_t(channels);
        uint8_t* d = rgba.data() + 4 * i;
        if (used == 1) d[0] = d[1] = d[2] = s[0], d[3] = 255;
        else if (used == 2) d[0] = s[0], d[1] = s[1], d[2] = 0, d[3] = 255;
        else d[0] = s[0], d[1] = s[1], d[2] = s[2], d[3] = s[3];
    }
    void* slices[1] = {rgba.data()};
    astcenc_image image{unsigned(width), unsigned(height), 1, ASTCENC_TYPE_U8, slices};
    const astcenc_swizzle identity{ASTCENC_SWZ_R, ASTCENC_SWZ_G, ASTCENC_SWZ_B, ASTCENC_SWZ_A};
    std::vector<uint8_t> out(astc_level_bytes(state_->side, uint64_t(width), uint64_t(height)));
    // Every thread index calls in; astcenc hands out blocks dynamically, each block encoded on its own, so
    // the result is the same for any count. A task that starts after the others finished finds no work.
    std::vector<astcenc_error> status(state_->threads, ASTCENC_SUCCESS);
    tbb::parallel_for(0u, state_->threads, [&](unsigned t) {
        status[t] = astcenc_compress_image(state_->ctx.get(), &image, &identity, out.data(), out.size(), t);
    });
    // Every thread has returned: the context is ready for the next image.
    const astcenc_error reset = astcenc_compress_reset(state_->ctx.get());
    for (astcenc_error e : status)
        if (e != ASTCENC_SUCCESS) return make_error(std::string("astcenc: ") + astcenc_get_error_string(e));
    if (reset != ASTCENC_SUCCESS) return make_error(std::string("astcenc: ") + astcenc_get_error_string(reset));
    return out;
}

Result<std::vector<uint8_t>> astc_compress_level(const uint8_t* texels, int width, int height, int channels, int used,
                                                 int side, int threads) {
    auto encoder = AstcEncoder::create(side, threads);
    if (!encoder) return encoder.error();
    return encoder->compress(texels, width, height, channels, used);
}

Result<std::vector<uint8_t>> astc_decompress_level(std::span<const uint8_t> blocks, int width, int height, int side) {
    if (!astc_block_supported(side)) return make_error("ASTC footprint " + std::to_string(side) + " is not 4, 6 or 8");
    if (blocks.size() != astc_level_bytes(side, uint64_t(width), uint64_t(height)))
        return make_error("ASTC level holds " + std::to_string(blocks.size()) + " bytes, expected " +
                          std::to_string(astc_level_bytes(side, uint64_t(width), uint64_t(height))));
    auto ctx = make_context(side, ASTCENC_FLG_DECOMPRESS_ONLY, 1);
    if (!ctx) return ctx.error();
    std::vector<uint8_t> rgba(size_t(width) * size_t(height) * 4);
    void* slices[1] = {rgba.data()};
    astcenc_image image{unsigned(width), unsigned(height), 1, ASTCENC_TYPE_U8, slices};
    const astcenc_swizzle identity{ASTCENC_SWZ_R, ASTCENC_SWZ_G, ASTCENC_SWZ_B, ASTCENC_SWZ_A};
    const astcenc_error e = astcenc_decompress_image(ctx->get(), blocks.data(), blocks.size(), &image, &identity, 0);
    if (e != ASTCENC_SUCCESS) return make_error(std::string("astcenc: ") + astcenc_get_error_string(e));
    return rgba;
}

}  // namespace specbake::io
