// The texture bake's level scheduling and row streaming: the decoder set up from the settings, the fused
// pass over the largest levels in column tiles, the remaining levels row by row, finished rows to the sink.
#include "bake/texture_bake_internal.h"

#include "core/assert.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>

namespace specbake::texture_bake_detail {
namespace {

// Float output rows of one block of rows of one level, interleaved as the chains; null for an
// output that was not requested.
struct RowBlock {
    int width = 0;
    int rough_ch = 0, kern_ch = 0, lean_ch = 0, nrm_ch = 0;
    // Not zero-filled: every texel of a block is written before it is emitted.
    std::unique_ptr<float[]> rough, kern, lean, nrm;

    RowBlock(const TextureBakeShape& shape, int w, int rows)
        : width(w),
          rough_ch(shape.roughness_channels),
          kern_ch(shape.kernel_channels),
          lean_ch(shape.lean_channels),
          nrm_ch(shape.normal_channels),
          rough(uninitialized<float>(size_t(w) * rows * size_t(rough_ch))),
          kern(uninitialized<float>(size_t(w) * rows * size_t(kern_ch))),
          lean(uninitialized<float>(size_t(w) * rows * size_t(lean_ch))),
          nrm(uninitialized<float>(size_t(w) * rows * size_t(nrm_ch))) {}

    static float* row(const std::unique_ptr<float[]>& v, int ch, int width, int k) {
        return v ? v.get() + size_t(k) * size_t(width) * size_t(ch) : nullptr;
    }
    float* rough_row(int k) { return row(rough, rough_ch, width, k); }
    float* kern_row(int k) { return row(kern, kern_ch, width, k); }
    float* lean_row(int k) { return row(lean, lean_ch, width, k); }
    float* nrm_row(int k) { return row(nrm, nrm_ch, width, k); }
    // The rows of row k from texel `offset` on.
    BaseRow base_row(int k, int offset) {
        auto from = [&](float* r, int ch) { return r ? r + size_t(offset) * size_t(ch) : nullptr; };
        return {from(rough_row(k), rough_ch), from(kern_row(k), kern_ch), from(lean_row(k), lean_ch),
                from(nrm_row(k), nrm_ch)};
    }

    void emit(const TextureBakeRowSink& sink, int level, int x0, int y0, int rows) const {
        TextureBakeRows r;
        r.level = level, r.x0 = x0, r.y0 = y0, r.rows = rows, r.width = width;
        r.roughness = rough.get();
        r.kernel = kern.get();
        r.lean = lean.get();
        r.normal = nrm.get();
        sink(r);
    }
};

// Sets the decoder up from the settings: the normal map's y and z conventions, the roughness source (a map,
// resampled when its size differs from the normal map's, or a constant) and the planes the means carry.
// Records in `notes` what it chose and why.
Result<void> set_up_decoder(Decoder& dec, const BakeInputs& in, const TextureBakeSettings& settings,
                            TextureBakeNotes& notes) {
    const TextureMap& normal = in.normal;
    const TextureMap* const roughness = in.roughness;
    const int roughness_channel = in.roughness_channel;
    dec.flip_y = settings.normal_y == NormalGreen::MinusY;
    if (normal.channels == 2) {
        if (settings.reconstruct_z == ReconstructZ::Never)
            return make_error("normal map: has two channels, so z must be reconstructed (reconstruct-z is 'never')");
        dec.reconstruct = true;
        notes.z_reason = "two-channel map";
    } else if (settings.reconstruct_z == ReconstructZ::Always) {
        dec.reconstruct = true;
        notes.z_reason = "requested";
    } else if (settings.reconstruct_z == ReconstructZ::Auto && blue_is_constant_full_scale(normal)) {
        dec.reconstruct = true;
        notes.z_reason = "constant full-scale blue channel";
    }
    notes.z_reconstructed = dec.reconstruct;
    notes.z_decode = dec.reconstruct ? "rebuilt from x and y (" + notes.z_reason + ")" : "stored blue channel";
    if (!dec.reconstruct && looks_srgb_encoded(normal)) {
        notes.looks_srgb = true;
        notes.warnings.push_back(
            "normal map: values look sRGB-encoded (decoded vectors are far from unit length unless the sRGB curve "
            "is removed first); data maps are never colour-converted, so re-export it as linear data");
    }

    Layout& layout = dec.layout;
    if (roughness) {
        dec.roughness = roughness;
        dec.roughness_channel = roughness_channel;
        dec.orm = roughness->channels >= 3 && roughness_channel == 1;
        notes.roughness_is_orm = dec.orm;
        if (dec.orm) {
            layout.occlusion = layout.count++;
            layout.metallic = layout.count++;
        }
        if (roughness->width != normal.width || roughness->height != normal.height) {
            notes.roughness_resampled = true;
            dec.resampled = resample_roughness(*roughness, roughness_channel, dec.orm, normal.width, normal.height);
        }
    } else {
        const double r = in.roughness_value;
        dec.constant_a = r * r * r * r;
        dec.constant_r = float(std::sqrt(std::sqrt(std::clamp(dec.constant_a, 0.0, 1.0))));
    }
    if (settings.outputs.lean && settings.lean_space == LeanSpace::Slope) {
        layout.slope = layout.count;
        layout.count += 5;
    }
    return {};
}

// The mip levels of one bake from the decoder's base rows, each finished block of output rows to the
// sink: the fused pass over the largest levels, then every remaining level from the means of the level
// before (when its footprints tile that level) or from its footprints in the base.
struct LevelPass {
    LevelPass(Decoder& decoder, const TextureBakeSettings& bake_settings, const TextureBakeShape& bake_shape,
              const BakeRowTargets& targets)
        : dec(decoder),
          layout(decoder.layout),
          settings(bake_settings),
          shape(bake_shape),
          to(targets),
          W(decoder.normal.width),
          H(decoder.normal.height),
          C(decoder.layout.count),
          levels(bake_shape.levels) {}

    Decoder& dec;
    const Layout& layout;
    const TextureBakeSettings& settings;
    const TextureBakeShape& shape;
    const BakeRowTargets& to;
    const int W, H, C, levels;
    // Means of the previous / current level, kept when the next level tiles it: row j is C planes of w.
    // Not zero-filled: every mean of a kept level is written before the next level reads it.
    std::unique_ptr<double[]> previous, current;
    std::vector<double> level_change = std::vector<double>(size_t(levels), 0.0);
    std::atomic<long long> degenerate{0};

    // Levels 0 .. F of the fused pass: per level its footprint (fx x fy texels of the level before) and the
    // width of its column tiles.
    struct FusedLevels {
        int F = 1;
        std::vector<int> fx, fy, tile;
        bool pairs_in_registers = false;  // levels 0 and 1 straight from the decoded registers
        bool keep = false;                // level F's means kept for level F + 1
    };

    int level_w(int L) const { return std::max(1, W >> L); }
    int level_h(int L) const { return std::max(1, H >> L); }
    // Level L is the mean of blocks of level L-1 when both of its sizes divide level L-1's.
    bool tiles_previous(int L) const {
        return L >= 2 && level_w(L - 1) % level_w(L) == 0 && level_h(L - 1) % level_h(L) == 0;
    }
    // Writes the outputs of rows of level L into `block` row k from their means.
    double finalize_into(RowBlock& block, int k, const double* means, int w) const {
        return finalize_row(means, w, layout, settings, dec.flip_y, block.rough_row(k), block.kern_row(k),
                            block.lean_row(k), block.nrm_row(k));
    }
    void base_into(RowBlock& block, int k, const double* v, const float* r0, int n, int offset = 0) const {
        write_base_row(v, r0, n, layout, dec.flip_y, block.base_row(k, offset), block.kern_ch);
    }
    static double reduce_changes(const std::vector<double>& rows) {
        double m = 0.0;
        for (double c : rows) m = std::max(m, c);
        return m;
    }

    // Runs every level; returns the largest roughness change of any output texel.
    double run() {
        const bool fused = levels >= 2 && W % level_w(1) == 0 && H % level_h(1) == 0;
        const int first_level = fused ? run_fused() : 0;
        for (int L = first_level; L < levels; ++L) run_level(L);
        return reduce_changes(level_change);
    }

    FusedLevels plan_fused() const;
    void fused_band(const FusedLevels& fused, std::vector<std::vector<double>>& change, const tbb::blocked_range<int>& rows);
    int run_fused();
    void run_level(int L);
};

// Levels 0 .. F in one pass when each of levels 1 .. F has footprints that are whole blocks of the level
// before (all even sizes, up to kMaxFusedLevels): every base row is decoded once, written as level 0 and
// summed upwards. Each task owns whole rows of level F, so the finer rows under them never leave the task,
// and only level-F means (a 4^F-th of the base) are kept for level F + 1. Column tiles of about
// kTileTexels base texels keep a task's planes and float rows in the L2 cache; every output texel still
// sums its own footprint in the same order.
LevelPass::FusedLevels LevelPass::plan_fused() const {
    FusedLevels f;
    int& F = f.F;
    while (F < kMaxFusedLevels && F + 1 < levels && tiles_previous(F + 1)) ++F;
    f.fx.assign(size_t(F) + 1, 1), f.fy.assign(size_t(F) + 1, 1), f.tile.assign(size_t(F) + 1, 1);
    for (int L = 1; L <= F; ++L)
        f.fx[size_t(L)] = level_w(L - 1) / level_w(L), f.fy[size_t(L)] = level_h(L - 1) / level_h(L);
    int span = 1;  // base texels per level-F texel along x
    for (int L = 1; L <= F; ++L) span *= f.fx[size_t(L)];
    f.tile[size_t(F)] = std::clamp(kTileTexels / span, 1, level_w(F));
    for (int L = F; L >= 1; --L) f.tile[size_t(L) - 1] = f.tile[size_t(L)] * f.fx[size_t(L)];
#if defined(SPECBAKE_AVX2)
    f.pairs_in_registers = has_avx2() && f.fx[1] == 2 && f.fy[1] == 2 && layout.slope < 0 && dec.resampled.empty();
#endif
    f.keep = F + 1 < levels && tiles_previous(F + 1);
    return f;
}

// The rows `rows` of level F of the fused pass, in column tiles, with every finer level under them.
void LevelPass::fused_band(const FusedLevels& fused, std::vector<std::vector<double>>& change,
                           const tbb::blocked_range<int>& rows) {
    const int F = fused.F, wF = level_w(F);
    const std::vector<int>&fx = fused.fx, &fy = fused.fy, &tile = fused.tile;
    const TextureBakeRowSink& sink = to.sink;
    // Per level: the finer rows under one row of it; its output rows are held until the rows under one row
    // of the next level are done, and go to the sink as one block.
    std::vector<std::unique_ptr<double[]>> fine(size_t(F) + 1);
    std::vector<RowBlock> out;
    for (int L = 0; L <= F; ++L) {
        if (L >= 1) fine[size_t(L)] = uninitialized<double>(size_t(C) * tile[size_t(L) - 1] * fy[size_t(L)]);
        out.emplace_back(shape, tile[size_t(L)], L < F ? fy[size_t(L) + 1] : 1);
    }
    const auto top = uninitialized<double>(size_t(C) * tile[size_t(F)]);  // means of level F
    const auto r0 = uninitialized<float>(size_t(tile[0]));
    long long task_degenerate = 0;
    // Levels 0 and 1 of texels [x, x + n) of row j of level 1 (2 x 2 footprints) from registers, the last
    // means (n not a multiple of four) through the planes in `f`.
    auto levels_0_1 = [&](int j, int x, int n, double* m, double* f) {
        RowBlock& base = out[0];
        int done = 0;
#if defined(SPECBAKE_AVX2)
        const BaseRow rows[2] = {base.base_row(0, 0), base.base_row(1, 0)};
        done = base_and_pairs(dec, 2 * j, 2 * x, n, rows, base.kern_ch, m, n, task_degenerate);
#endif
        if (done == n) return;
        const int rest = n - done, nr = 2 * rest;
        for (int dy = 0; dy < 2; ++dy) {
            double* v = f + size_t(dy) * C * nr;
            task_degenerate += dec.decode_span(2 * j + dy, 2 * (x + done), nr, v, r0.get());
            base_into(base, dy, v, r0.get(), nr, 2 * done);
        }
        std::array<double, 4 * 16> tail;  // C (<= 14) planes of rest (< 4) means
        block_means(f, nr, 2, 2, C, rest, tail.data());
        for (int c = 0; c < C; ++c) std::copy_n(tail.data() + size_t(c) * rest, rest, plane(m, c, n) + done);
    };
    // Means of texels [x, x + n) of row j of level L into m (C planes of n) and its outputs into row k of
    // out[L], after the outputs of every finer level under them went to the sink.
    std::function<void(int, int, int, int, double*, int)> block = [&](int L, int j, int x, int n, double* m, int k) {
        RowBlock& o = out[size_t(L)];
        if (L == 0) {
            task_degenerate += dec.decode_span(j, x, n, m, r0.get());
            base_into(o, k, m, r0.get(), n);
            return;
        }
        const int fxL = fx[size_t(L)], fyL = fy[size_t(L)], nf = n * fxL;
        double* f = fine[size_t(L)].get();
        out[size_t(L) - 1].width = nf;
        if (L == 1 && fused.pairs_in_registers) {
            levels_0_1(j, x, n, m, f);
        } else {
            for (int dy = 0; dy < fyL; ++dy) block(L - 1, j * fyL + dy, x * fxL, nf, f + size_t(dy) * C * nf, dy);
            block_means(f, nf, fxL, fyL, C, n, m);
        }
        out[size_t(L) - 1].emit(sink, L - 1, x * fxL, j * fyL, fyL);
        double& c = change[size_t(L)][size_t(j)];
        c = std::max(c, finalize_into(o, k, m, n));
    };
    for (int j = rows.begin(); j < rows.end(); ++j) {
        for (int x = 0; x < wF; x += tile[size_t(F)]) {
            const int n = std::min(tile[size_t(F)], wF - x);
            double* m = top.get();
            out[size_t(F)].width = n;
            block(F, j, x, n, m, 0);
            out[size_t(F)].emit(sink, F, x, j, 1);
            if (fused.keep)
                for (int c = 0; c < C; ++c) std::copy_n(m + size_t(c) * n, n, current.get() + (size_t(j) * C + c) * wF + x);
        }
    }
    degenerate += task_degenerate;
}

// The fused pass (plan_fused); returns the first level it did not compute.
int LevelPass::run_fused() {
    const FusedLevels fused = plan_fused();
    const int F = fused.F, wF = level_w(F), hF = level_h(F);
    current = uninitialized<double>(fused.keep ? size_t(wF) * hF * C : 0);
    std::vector<std::vector<double>> change(size_t(F) + 1);
    for (int L = 1; L <= F; ++L) change[size_t(L)].assign(size_t(level_h(L)), 0.0);
    auto band = [&](const tbb::blocked_range<int>& rows) { fused_band(fused, change, rows); };
    if (!to.rows_done) {
        tbb::parallel_for(tbb::blocked_range<int>(0, hF), band);
    } else {
        // Bands of about kBandBaseRows base rows, top down; the rows of every fused level under them are done.
        // Base rows are read again after the pass only by a later level that does not tile the one before.
        // Float maps are read again to name a non-finite texel; integer maps hold none.
        const TextureMap* const roughness = dec.roughness;
        bool base_read_later = dec.normal.f32 || (roughness && roughness->f32 && dec.resampled.empty());
        for (int L = F + 1; L < levels; ++L) base_read_later = base_read_later || !tiles_previous(L);
        const int step = std::max(1, kBandBaseRows / std::max(1, H / hF));
        for (int b0 = 0; b0 < hF; b0 += step) {
            const int b1 = std::min(hF, b0 + step);
            tbb::parallel_for(tbb::blocked_range<int>(b0, b1, 1), band);
            for (int L = 0; L <= F; ++L) to.rows_done(L, int(int64_t(b1) * level_h(L) / hF));
            if (to.inputs_done && !base_read_later) to.inputs_done(int(int64_t(b1) * H / hF));
        }
    }
    for (int L = 1; L <= F; ++L) level_change[size_t(L)] = reduce_changes(change[size_t(L)]);
    previous.swap(current);
    return F + 1;
}

// Level L on its own: level 0 from the decoded base rows; a level that tiles the one before from its
// means; any other from its footprints in the base (weighted where they straddle texels).
void LevelPass::run_level(int L) {
    const int w = level_w(L), h = level_h(L);
    const bool from_previous = tiles_previous(L);
    const bool keep = L >= 1 && L + 1 < levels && tiles_previous(L + 1);
    current = uninitialized<double>(keep ? size_t(w) * h * C : 0);
    std::vector<double> row_change(size_t(h), 0.0);
    const std::vector<Span1D> spans_x = from_previous || L == 0 ? std::vector<Span1D>{} : footprint_spans(W, w);
    const std::vector<Span1D> spans_y = from_previous || L == 0 ? std::vector<Span1D>{} : footprint_spans(H, h);
    const double area = (double(W) / w) * (double(H) / h);
    const int pw = L >= 1 ? level_w(L - 1) : 0;
    const int fx = from_previous ? pw / w : 0;
    const int fy = from_previous ? level_h(L - 1) / h : 0;
    const size_t row_doubles = size_t(C) * size_t(W);
    const TextureBakeRowSink& sink = to.sink;
    SPECBAKE_ASSERT(!from_previous || previous);

    tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
        std::vector<double> base(from_previous ? 0 : row_doubles);
        std::vector<float> r0(from_previous ? 0 : size_t(W));
        std::vector<double> means(size_t(C) * w);
        RowBlock out(shape, w, 1);
        long long task_degenerate = 0;
        for (int j = rows.begin(); j < rows.end(); ++j) {
            if (L == 0) {
                task_degenerate += dec.decode_span(j, 0, W, base.data(), r0.data());
                base_into(out, 0, base.data(), r0.data(), W);
                out.emit(sink, 0, 0, j, 1);
                continue;
            }
            if (from_previous) {
                block_means(previous.get() + size_t(j) * fy * C * pw, pw, fx, fy, C, w, means.data());
            } else {
                std::fill(means.begin(), means.end(), 0.0);
                const Span1D& sy = spans_y[size_t(j)];
                for (size_t k = 0; k < sy.weight.size(); ++k) {
                    const double wy = sy.weight[k];
                    if (wy <= 0.0) continue;
                    dec.decode_span(sy.first + int(k), 0, W, base.data(), r0.data());
                    for (int c = 0; c < C; ++c) {
                        double* m = plane(means.data(), c, w);
                        const double* v = plane(base.data(), c, W);
                        for (int i = 0; i < w; ++i) {
                            const Span1D& sx = spans_x[size_t(i)];
                            for (size_t q = 0; q < sx.weight.size(); ++q) m[i] += wy * sx.weight[q] * v[sx.first + int(q)];
                        }
                    }
                }
                const double inv = 1.0 / area;
                for (double& m : means) m *= inv;
            }
            row_change[size_t(j)] = finalize_into(out, 0, means.data(), w);
            out.emit(sink, L, 0, j, 1);
            if (keep) std::copy(means.begin(), means.end(), current.get() + size_t(j) * w * C);
        }
        degenerate += task_degenerate;
    });
    level_change[size_t(L)] = reduce_changes(row_change);
    previous.swap(current);
    if (to.rows_done) to.rows_done(L, h);
}

}  // namespace

// The bake proper, on validated inputs.
Result<TextureBakeResult> bake_validated(const BakeInputs& in, const TextureBakeSettings& settings,
                                         const BakeRowTargets& to) {
    TextureBakeResult result;
    TextureBakeNotes& notes = result.notes;
    const TextureMap& normal = in.normal;
    const int W = normal.width, H = normal.height;
    Decoder dec(normal);
    if (auto ok = set_up_decoder(dec, in, settings, notes); !ok) return ok.error();
    const TextureBakeShape shape = texture_bake_shape(normal, in.roughness, in.roughness_channel, settings);
    SPECBAKE_ASSERT(shape.levels == mip_level_count(W, H));

    LevelPass pass(dec, settings, shape, to);
    run_with_threads(settings.threads, [&] { result.max_roughness_change = pass.run(); });

    if (dec.normal_non_finite) return non_finite_error("normal map", normal);
    if (dec.roughness_non_finite) return non_finite_error("roughness map", *in.roughness);
    notes.degenerate_normals = pass.degenerate;
    if (notes.degenerate_normals > 0)
        notes.warnings.push_back("normal map: " + std::to_string(notes.degenerate_normals) +
                                 " texels decode to a zero-length vector; treated as +Z");
    if (notes.roughness_resampled)
        notes.warnings.push_back("roughness map is " + std::to_string(in.roughness->width) + "x" +
                                 std::to_string(in.roughness->height) + ", the normal map " + std::to_string(W) + "x" +
                                 std::to_string(H) +
                                 "; outputs have the normal map's size, each texel reading the roughness it covers");
    return result;
}

}  // namespace specbake::texture_bake_detail
