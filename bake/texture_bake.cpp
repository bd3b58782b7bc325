// Texture bake (SPEC Sec. 3). See texture_bake.h for the footprint convention.
//
// Every level is a set of area-weighted means over base texels of the linear per-texel quantities
// (normal, p p^T, alpha^2, occlusion, metallic, slope moments). A level whose footprints tile the previous
// level's footprints exactly (both sizes divide) is the plain mean of the previous level's blocks, kept in
// double; every other level is reduced from the base texels directly. Each output texel is summed by one
// thread in a fixed order, so results do not depend on the thread count.
#include "bake/texture_bake.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace specbake {
namespace {

// Per-texel linear quantities, in this order; the ORM and slope groups are present only when needed.
enum Channel : int { kPx, kPy, kPz, kPxx, kPyy, kPxy, kA, kCore };

struct Layout {
    int count = kCore;
    int occlusion = -1, metallic = -1;  // ORM R and B
    int slope = -1;                     // s.x, s.y, s.x^2, s.y^2, s.x s.y
};

// Smallest |n.z| used for slope space s = -(n.x, n.y) / n.z: keeps grazing normals finite (|s| <= 1e4).
constexpr double kMinSlopeZ = 1e-4;

struct Span1D {
    int first = 0;              // first source index
    std::vector<double> weight; // weight of source index first + k (the overlap length)
};

// Source intervals of the `n` output cells on an axis of `src` source cells: cell i covers
// [i src / n, (i+1) src / n); each source cell weighs by its overlap with that interval.
std::vector<Span1D> footprint_spans(int src, int n) {
    std::vector<Span1D> spans(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
        const double x0 = double(i) * src / n;
        const double x1 = double(i + 1) * src / n;
        const int k0 = int(std::floor(x0));
        const int k1 = std::min(src, int(std::ceil(x1)));
        Span1D& s = spans[size_t(i)];
        s.first = k0;
        for (int k = k0; k < k1; ++k) {
            const double w = std::min(double(k + 1), x1) - std::max(double(k), x0);
            s.weight.push_back(std::max(0.0, w));
        }
    }
    return spans;
}

struct Decoder {
    explicit Decoder(const Image& n) : normal(n) {}
    const Image& normal;
    bool reconstruct = false;
    bool flip_y = false;
    // Roughness: either read per texel from a same-size map, or from a resampled array (a, R, B).
    const Image* roughness = nullptr;
    int roughness_channel = 0;
    bool orm = false;
    std::vector<double> resampled;  // a, R, B per normal-map texel when the sizes differ
    double constant_a = 0.0;
    Layout layout;

    // Unit normal of base texel (x, y) in the +Y tangent frame; zero-length vectors decode to +Z.
    void decode_normal(int x, int y, double n[3], bool& degenerate) const {
        const float* c = normal.texel(x, y);
        double nx = 2.0 * c[0] - 1.0;
        double ny = 2.0 * c[1] - 1.0;
        if (flip_y) ny = -ny;
        double nz;
        if (reconstruct) {
            nz = std::sqrt(std::max(0.0, 1.0 - nx * nx - ny * ny));
        } else {
            nz = 2.0 * c[2] - 1.0;
        }
        const double len2 = nx * nx + ny * ny + nz * nz;
        degenerate = !(len2 > 1e-20);
        if (degenerate) {
            n[0] = 0.0, n[1] = 0.0, n[2] = 1.0;
            return;
        }
        const double inv = 1.0 / std::sqrt(len2);
        n[0] = nx * inv, n[1] = ny * inv, n[2] = nz * inv;
    }

    // Fills the layout.count quantities of base row y into row[x * count + c]; returns degenerate count.
    long long decode_row(int y, double* row) const {
        long long degenerate_count = 0;
        const int C = layout.count;
        for (int x = 0; x < normal.width; ++x) {
            double* v = row + size_t(x) * C;
            double n[3];
            bool degenerate = false;
            decode_normal(x, y, n, degenerate);
            degenerate_count += degenerate;
            v[kPx] = n[0];
            v[kPy] = n[1];
            v[kPz] = n[2];
            v[kPxx] = n[0] * n[0];
            v[kPyy] = n[1] * n[1];
            v[kPxy] = n[0] * n[1];
            double occlusion = 0.0, metallic = 0.0;
            if (!resampled.empty()) {
                const double* r = resampled.data() + (size_t(y) * normal.width + x) * 3;
                v[kA] = r[0];
                occlusion = r[1];
                metallic = r[2];
            } else if (roughness) {
                const float* t = roughness->texel(x, y);
                const double r = std::clamp(double(t[roughness_channel]), 0.0, 1.0);
                const double r2 = r * r;
                v[kA] = r2 * r2;  // a = alpha^2 = r^4 (SPEC Sec. 2)
                if (orm) occlusion = t[0], metallic = t[2];
            } else {
                v[kA] = constant_a;
            }
            if (layout.occlusion >= 0) v[layout.occlusion] = occlusion, v[layout.metallic] = metallic;
            if (layout.slope >= 0) {
                const double z = std::max(n[2], kMinSlopeZ);
                const double sx = -n[0] / z, sy = -n[1] / z;  // slope space (SPEC Sec. 2)
                double* s = v + layout.slope;
                s[0] = sx, s[1] = sy, s[2] = sx * sx, s[3] = sy * sy, s[4] = sx * sy;
            }
        }
        return degenerate_count;
    }
};

// Area-weighted resampling of the roughness map onto the normal map's texel grid: each normal texel reads
// the mean alpha^2 (and ORM R, B) of the roughness texels it covers.
std::vector<double> resample_roughness(const Image& rough, int channel, bool orm, int W, int H) {
    const std::vector<Span1D> sx = footprint_spans(rough.width, W);
    const std::vector<Span1D> sy = footprint_spans(rough.height, H);
    const double area = (double(rough.width) / W) * (double(rough.height) / H);
    std::vector<double> out(size_t(W) * H * 3);
    tbb::parallel_for(tbb::blocked_range<int>(0, H), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y < rows.end(); ++y) {
            const Span1D& fy = sy[size_t(y)];
            for (int x = 0; x < W; ++x) {
                const Span1D& fx = sx[size_t(x)];
                double acc[3] = {0, 0, 0};
                for (size_t j = 0; j < fy.weight.size(); ++j) {
                    for (size_t i = 0; i < fx.weight.size(); ++i) {
                        const double w = fy.weight[j] * fx.weight[i];
                        const float* t = rough.texel(fx.first + int(i), fy.first + int(j));
                        const double r = std::clamp(double(t[channel]), 0.0, 1.0);
                        acc[0] += w * (r * r) * (r * r);
                        if (orm) acc[1] += w * t[0], acc[2] += w * t[2];
                    }
                }
                double* o = out.data() + (size_t(y) * W + x) * 3;
                for (int c = 0; c < 3; ++c) o[c] = acc[c] / area;
            }
        }
    });
    return out;
}

// Turns the means of one texel into its output values (SPEC Sec. 3); returns |r_out - r_in|.
double finalize_texel(const double* v, const Layout& layout, const TextureBakeSettings& s, bool flip_y,
                      float* rough, float* kern, float* lean, float* nrm) {
    const double mx = v[kPx], my = v[kPy];
    // Sigma = M - m m^T, clamped to positive semi-definite.
    double sxx = std::max(0.0, v[kPxx] - mx * mx);
    double syy = std::max(0.0, v[kPyy] - my * my);
    const double bound = std::sqrt(sxx * syy);
    double sxy = std::clamp(v[kPxy] - mx * my, -bound, bound);
    double t = reduce_covariance(s.isotropic, sxx, syy, sxy);
    if (s.max_kernel) t = std::min(t, *s.max_kernel);
    const double a_base = std::clamp(v[kA], 0.0, 1.0);
    const double a = s.filter == RoughnessFilterMode::Projected ? filter_projected_isotropic(a_base, t)
                                                                : filter_approx_isotropic(a_base, t);
    const double r = std::sqrt(std::sqrt(a));  // r = a^(1/4)
    const double r_in = std::sqrt(std::sqrt(a_base));
    if (rough) {
        if (layout.occlusion >= 0) {
            rough[0] = float(v[layout.occlusion]);
            rough[1] = float(r);
            rough[2] = float(v[layout.metallic]);
        } else {
            rough[0] = float(r);
        }
    }
    if (kern) {
        if (s.anisotropic) {
            kern[0] = float(sxx), kern[1] = float(syy), kern[2] = float(sxy);
        } else {
            kern[0] = float(t);
        }
    }
    if (lean) {
        if (layout.slope >= 0) {
            // Olano & Baker LEAN: first and second slope moments with the base lobe's slope covariance
            // A / 2 = (alpha^2 / 2) I folded into the second moments (A = 2 x slope covariance, TK21 Sec. 2.1).
            const double* sl = v + layout.slope;
            lean[0] = float(sl[0]), lean[1] = float(sl[1]);
            lean[2] = float(sl[2] + 0.5 * v[kA]), lean[3] = float(sl[3] + 0.5 * v[kA]);
            lean[4] = float(sl[4]);
        } else {
            lean[0] = float(mx), lean[1] = float(my);
            lean[2] = float(v[kPxx]), lean[3] = float(v[kPyy]), lean[4] = float(v[kPxy]);
        }
    }
    if (nrm) {
        double nx = v[kPx], ny = v[kPy], nz = v[kPz];
        const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
        if (len > 1e-12) {
            nx /= len, ny /= len, nz /= len;
        } else {
            nx = 0.0, ny = 0.0, nz = 1.0;
        }
        if (flip_y) ny = -ny;
        nrm[0] = float(0.5 * nx + 0.5), nrm[1] = float(0.5 * ny + 0.5), nrm[2] = float(0.5 * nz + 0.5);
    }
    return std::abs(r - r_in);
}

// Mip 0: every footprint is one base texel, so Sigma = 0, t = 0 and a = a_base exactly (SPEC Sec. 3:
// the input roughness passes through). Same outputs as finalize_texel without its divisions and roots;
// the decoded normal is already unit length.
void finalize_base_texel(const double* v, const Layout& layout, const TextureBakeSettings& s, bool flip_y,
                         float* rough, float* kern, float* lean, float* nrm) {
    if (rough) {
        const float r = float(std::sqrt(std::sqrt(std::clamp(v[kA], 0.0, 1.0))));
        if (layout.occlusion >= 0) {
            rough[0] = float(v[layout.occlusion]), rough[1] = r, rough[2] = float(v[layout.metallic]);
        } else {
            rough[0] = r;
        }
    }
    if (kern) {
        kern[0] = 0.0f;
        if (s.anisotropic) kern[1] = 0.0f, kern[2] = 0.0f;
    }
    if (lean) {
        if (layout.slope >= 0) {
            const double* sl = v + layout.slope;
            lean[0] = float(sl[0]), lean[1] = float(sl[1]);
            lean[2] = float(sl[2] + 0.5 * v[kA]), lean[3] = float(sl[3] + 0.5 * v[kA]);
            lean[4] = float(sl[4]);
        } else {
            lean[0] = float(v[kPx]), lean[1] = float(v[kPy]);
            lean[2] = float(v[kPxx]), lean[3] = float(v[kPyy]), lean[4] = float(v[kPxy]);
        }
    }
    if (nrm) {
        nrm[0] = float(0.5 * v[kPx] + 0.5);
        nrm[1] = float(0.5 * (flip_y ? -v[kPy] : v[kPy]) + 0.5);
        nrm[2] = float(0.5 * v[kPz] + 0.5);
    }
}

bool blue_is_constant_full_scale(const Image& n) {
    if (n.channels < 3) return false;
    const float first = n.pixels[2];
    if (!(first >= 1.0f - 1.0f / 512.0f)) return false;
    const size_t count = n.texel_count();
    for (size_t i = 0; i < count; ++i) {
        if (n.pixels[i * n.channels + 2] != first) return false;
    }
    return true;
}

double srgb_to_linear(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

// A tangent-space normal map stored through an sRGB encode decodes to vectors far from unit length
// (flat (0.5, 0.5, 1) becomes (0.735, 0.735, 1)); decoding the sRGB curve first brings them back.
bool looks_srgb_encoded(const Image& n) {
    if (n.channels < 3) return false;
    const size_t count = n.texel_count();
    const size_t stride = std::max<size_t>(1, count / 65536);
    double dev_linear = 0.0, dev_srgb = 0.0;
    size_t samples = 0;
    for (size_t i = 0; i < count; i += stride) {
        const float* c = n.pixels.data() + i * n.channels;
        double l2 = 0.0, s2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double a = 2.0 * c[k] - 1.0;
            const double b = 2.0 * srgb_to_linear(std::clamp(double(c[k]), 0.0, 1.0)) - 1.0;
            l2 += a * a;
            s2 += b * b;
        }
        dev_linear += std::abs(std::sqrt(l2) - 1.0);
        dev_srgb += std::abs(std::sqrt(s2) - 1.0);
        ++samples;
    }
    dev_linear /= double(samples);
    dev_srgb /= double(samples);
    return dev_linear > 0.08 && dev_srgb < 0.5 * dev_linear;
}

Result<void> validate(const Image& normal, const Image* roughness, int channel, float value) {
    if (normal.empty()) return make_error("normal map: empty image (0x0)");
    if (normal.channels < 2)
        return make_error("normal map: has " + std::to_string(normal.channels) +
                          " channel; a normal map needs 2 (x, y) or 3+ (x, y, z) channels");
    if (normal.pixels.size() != normal.texel_count() * size_t(normal.channels))
        return make_error("normal map: pixel buffer does not match its size");
    if (auto bad = find_non_finite(normal))
        return make_error("normal map: NaN or infinite value at texel (" + std::to_string(bad->first) + ", " +
                          std::to_string(bad->second) + ")");
    if (roughness) {
        if (roughness->empty()) return make_error("roughness map: empty image (0x0)");
        if (roughness->pixels.size() != roughness->texel_count() * size_t(roughness->channels))
            return make_error("roughness map: pixel buffer does not match its size");
        if (channel < 0 || channel >= roughness->channels)
            return make_error("roughness map: channel " + std::to_string(channel) + " does not exist (the map has " +
                              std::to_string(roughness->channels) + ")");
        if (auto bad = find_non_finite(*roughness))
            return make_error("roughness map: NaN or infinite value at texel (" + std::to_string(bad->first) +
                              ", " + std::to_string(bad->second) + ")");
    } else if (!(value >= 0.0f && value <= 1.0f)) {
        return make_error("roughness value " + std::to_string(value) + " is outside [0, 1]");
    }
    return {};
}

void allocate_chain(MipChain& chain, int W, int H, int levels, int channels) {
    chain.levels.clear();
    for (int L = 0; L < levels; ++L) chain.levels.emplace_back(std::max(1, W >> L), std::max(1, H >> L), channels);
}

}  // namespace

int mip_level_count(int width, int height) {
    int n = 1;
    for (int s = std::max(width, height); s > 1; s >>= 1) ++n;
    return n;
}

std::optional<std::pair<int, int>> find_non_finite(const Image& image) {
    const size_t n = image.pixels.size();
    for (size_t i = 0; i < n; ++i) {
        if (!std::isfinite(image.pixels[i])) {
            const size_t texel = i / size_t(std::max(1, image.channels));
            return std::pair<int, int>(int(texel % size_t(image.width)), int(texel / size_t(image.width)));
        }
    }
    return std::nullopt;
}

Result<TextureBakeResult> bake_texture(const Image& normal, const Image* roughness, int roughness_channel,
                                       float roughness_value, const TextureBakeSettings& settings) {
    if (auto ok = validate(normal, roughness, roughness_channel, roughness_value); !ok) return ok.error();

    TextureBakeResult result;
    TextureBakeNotes& notes = result.notes;
    const int W = normal.width, H = normal.height;

    Decoder dec(normal);
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
        if (roughness->width != W || roughness->height != H) {
            notes.roughness_resampled = true;
            dec.resampled = resample_roughness(*roughness, roughness_channel, dec.orm, W, H);
        }
    } else {
        const double r = roughness_value;
        dec.constant_a = r * r * r * r;
    }
    const bool slope = settings.outputs.lean && settings.lean_space == LeanSpace::Slope;
    if (slope) {
        layout.slope = layout.count;
        layout.count += 5;
    }
    const int C = layout.count;

    const int levels = mip_level_count(W, H);
    const TextureOutputs& want = settings.outputs;
    if (want.roughness) allocate_chain(result.roughness, W, H, levels, dec.orm ? 3 : 1);
    if (want.kernel) allocate_chain(result.kernel, W, H, levels, settings.anisotropic ? 3 : 1);
    if (want.lean) allocate_chain(result.lean, W, H, levels, 5);
    if (want.normal) allocate_chain(result.normal, W, H, levels, 3);

    auto level_w = [&](int L) { return std::max(1, W >> L); };
    auto level_h = [&](int L) { return std::max(1, H >> L); };
    // Level L is the mean of blocks of level L-1 when both of its sizes divide level L-1's.
    auto tiles_previous = [&](int L) {
        return L >= 2 && level_w(L - 1) % level_w(L) == 0 && level_h(L - 1) % level_h(L) == 0;
    };

    std::vector<double> previous, current;  // means of the previous / current level, C per texel
    std::vector<double> level_change(size_t(levels), 0.0);
    long long degenerate = 0;

    // Writes the outputs of row j of level L from its means (C per texel); returns the row's max change.
    auto finalize_row = [&](int L, int j, const double* means) {
        const int w = level_w(L);
        Image* R = want.roughness ? &result.roughness.levels[size_t(L)] : nullptr;
        Image* K = want.kernel ? &result.kernel.levels[size_t(L)] : nullptr;
        Image* E = want.lean ? &result.lean.levels[size_t(L)] : nullptr;
        Image* N = want.normal ? &result.normal.levels[size_t(L)] : nullptr;
        if (L == 0) {
            for (int i = 0; i < w; ++i)
                finalize_base_texel(means + size_t(i) * C, layout, settings, dec.flip_y, R ? R->texel(i, j) : nullptr,
                                    K ? K->texel(i, j) : nullptr, E ? E->texel(i, j) : nullptr,
                                    N ? N->texel(i, j) : nullptr);
            return 0.0;
        }
        double change = 0.0;
        for (int i = 0; i < w; ++i) {
            change = std::max(change, finalize_texel(means + size_t(i) * C, layout, settings, dec.flip_y,
                                                     R ? R->texel(i, j) : nullptr, K ? K->texel(i, j) : nullptr,
                                                     E ? E->texel(i, j) : nullptr, N ? N->texel(i, j) : nullptr));
        }
        return change;
    };
    auto reduce_changes = [](const std::vector<double>& rows) {
        double m = 0.0;
        for (double c : rows) m = std::max(m, c);
        return m;
    };

    // Levels 0 and 1 in one pass when level 1's footprints are whole blocks of base texels (all even
    // sizes): every base row is decoded once, written as level 0 and summed into its level-1 row.
    const bool fused = levels >= 2 && W % level_w(1) == 0 && H % level_h(1) == 0;
    auto run_fused = [&] {
        const int w1 = level_w(1), h1 = level_h(1), fx = W / w1, fy = H / h1;
        const bool keep = levels > 2 && tiles_previous(2);
        current.assign(keep ? size_t(w1) * h1 * C : 0, 0.0);
        std::vector<double> change0(size_t(H), 0.0), change1(size_t(h1), 0.0);
        std::vector<long long> row_degenerate(size_t(h1), 0);
        tbb::parallel_for(tbb::blocked_range<int>(0, h1), [&](const tbb::blocked_range<int>& rows) {
            std::vector<double> base_row(size_t(W) * C), means(size_t(w1) * C);
            for (int j = rows.begin(); j < rows.end(); ++j) {
                std::fill(means.begin(), means.end(), 0.0);
                for (int dy = 0; dy < fy; ++dy) {
                    const int y = j * fy + dy;
                    row_degenerate[size_t(j)] += dec.decode_row(y, base_row.data());
                    change0[size_t(y)] = finalize_row(0, y, base_row.data());
                    for (int i = 0; i < w1; ++i) {
                        double* m = means.data() + size_t(i) * C;
                        for (int dx = 0; dx < fx; ++dx) {
                            const double* v = base_row.data() + size_t(i * fx + dx) * C;
                            for (int c = 0; c < C; ++c) m[c] += v[c];
                        }
                    }
                }
                const double inv = 1.0 / double(fx * fy);
                for (double& m : means) m *= inv;
                change1[size_t(j)] = finalize_row(1, j, means.data());
                if (keep) std::copy(means.begin(), means.end(), current.begin() + ptrdiff_t(size_t(j) * w1 * C));
            }
        });
        level_change[0] = reduce_changes(change0);
        level_change[1] = reduce_changes(change1);
        for (long long d : row_degenerate) degenerate += d;
        previous.swap(current);
    };

    auto run = [&] {
        if (fused) run_fused();
        for (int L = fused ? 2 : 0; L < levels; ++L) {
            const int w = level_w(L), h = level_h(L);
            const bool from_previous = tiles_previous(L);
            const bool keep = L >= 1 && L + 1 < levels && tiles_previous(L + 1);
            current.assign(keep ? size_t(w) * h * C : 0, 0.0);
            std::vector<double> row_change(size_t(h), 0.0);
            std::vector<long long> row_degenerate(size_t(h), 0);
            const std::vector<Span1D> spans_x = from_previous ? std::vector<Span1D>{} : footprint_spans(W, w);
            const std::vector<Span1D> spans_y = from_previous ? std::vector<Span1D>{} : footprint_spans(H, h);
            const double area = (double(W) / w) * (double(H) / h);
            const int pw = L >= 1 ? level_w(L - 1) : 0;
            const int fx = from_previous ? pw / w : 0;
            const int fy = from_previous ? level_h(L - 1) / h : 0;

            tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
                std::vector<double> base_row(from_previous ? 0 : size_t(W) * C);
                std::vector<double> means(size_t(w) * C);
                for (int j = rows.begin(); j < rows.end(); ++j) {
                    std::fill(means.begin(), means.end(), 0.0);
                    if (from_previous) {
                        const double inv = 1.0 / double(fx * fy);
                        for (int i = 0; i < w; ++i) {
                            double* m = means.data() + size_t(i) * C;
                            for (int dy = 0; dy < fy; ++dy) {
                                const double* src =
                                    previous.data() + (size_t(j * fy + dy) * pw + size_t(i) * fx) * C;
                                for (int dx = 0; dx < fx; ++dx)
                                    for (int c = 0; c < C; ++c) m[c] += src[size_t(dx) * C + c];
                            }
                            for (int c = 0; c < C; ++c) m[c] *= inv;
                        }
                    } else {
                        const Span1D& sy = spans_y[size_t(j)];
                        for (size_t k = 0; k < sy.weight.size(); ++k) {
                            const double wy = sy.weight[k];
                            if (wy <= 0.0) continue;
                            row_degenerate[size_t(j)] += dec.decode_row(sy.first + int(k), base_row.data());
                            for (int i = 0; i < w; ++i) {
                                const Span1D& sx = spans_x[size_t(i)];
                                double* m = means.data() + size_t(i) * C;
                                for (size_t q = 0; q < sx.weight.size(); ++q) {
                                    const double wxy = wy * sx.weight[q];
                                    const double* v = base_row.data() + size_t(sx.first + int(q)) * C;
                                    for (int c = 0; c < C; ++c) m[c] += wxy * v[c];
                                }
                            }
                        }
                        const double inv = 1.0 / area;
                        for (double& m : means) m *= inv;
                    }
                    row_change[size_t(j)] = finalize_row(L, j, means.data());
                    if (keep) std::copy(means.begin(), means.end(), current.begin() + ptrdiff_t(size_t(j) * w * C));
                }
            });
            level_change[size_t(L)] = reduce_changes(row_change);
            if (L == 0)
                for (long long d : row_degenerate) degenerate += d;
            previous.swap(current);
        }
        result.max_roughness_change = reduce_changes(level_change);
    };
    if (settings.threads > 0) {
        tbb::task_arena arena(settings.threads);
        arena.execute(run);
    } else {
        run();
    }

    notes.degenerate_normals = degenerate;
    if (degenerate > 0)
        notes.warnings.push_back("normal map: " + std::to_string(degenerate) +
                                 " texels decode to a zero-length vector; treated as +Z");
    if (notes.roughness_resampled)
        notes.warnings.push_back("roughness map is " + std::to_string(roughness->width) + "x" +
                                 std::to_string(roughness->height) + ", the normal map " + std::to_string(W) + "x" +
                                 std::to_string(H) +
                                 "; outputs have the normal map's size, each texel reading the roughness it covers");
    return result;
}

}  // namespace specbake
