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
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace specbake {
namespace {

// Per-texel linear quantities, in this order; the ORM and slope groups are present only when needed.
enum Channel : int { kPx, kPy, kPz, kPxx, kPyy, kPxy, kA, kCore };

struct Layout {
    int count = kCore;
    int occlusion = -1, metallic = -1;  // ORM R and B
    int slope = -1;                     // s.x, s.y, s.x^2, s.y^2, s.x s.y
};

// Largest number of per-texel quantities: the core group, ORM R and B, and five slope moments.
constexpr int kMaxChannels = kCore + 2 + 5;

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
    float constant_r = 0.0f;  // (constant_a)^(1/4) as written at mip 0
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

    // Unit normals of base row y into nx, ny, nz (same arithmetic as decode_normal, two texels per SSE2
    // instruction: packed sqrt and division round exactly like the scalar ones); returns the degenerate count.
    long long decode_normal_row(int y, double* nx, double* ny, double* nz) const {
        long long degenerate_count = 0;
        int x = 0;
#if defined(__SSE2__)
        const int ch = normal.channels;
        const float* row = normal.texel(0, y);
        const __m128d one = _mm_set1_pd(1.0), two = _mm_set1_pd(2.0), zero = _mm_setzero_pd();
        const __m128d tiny = _mm_set1_pd(1e-20);
        for (; x + 2 <= normal.width; x += 2) {
            const float* c0 = row + size_t(x) * ch;
            const float* c1 = c0 + ch;
            const __m128d vx = _mm_sub_pd(_mm_mul_pd(two, _mm_set_pd(c1[0], c0[0])), one);
            __m128d vy = _mm_sub_pd(_mm_mul_pd(two, _mm_set_pd(c1[1], c0[1])), one);
            if (flip_y) vy = _mm_xor_pd(vy, _mm_set1_pd(-0.0));
            const __m128d xx = _mm_mul_pd(vx, vx), yy = _mm_mul_pd(vy, vy);
            const __m128d vz = reconstruct ? _mm_sqrt_pd(_mm_max_pd(_mm_sub_pd(_mm_sub_pd(one, xx), yy), zero))
                                           : _mm_sub_pd(_mm_mul_pd(two, _mm_set_pd(c1[2], c0[2])), one);
            const __m128d len2 = _mm_add_pd(_mm_add_pd(xx, yy), _mm_mul_pd(vz, vz));
            const __m128d inv = _mm_div_pd(one, _mm_sqrt_pd(len2));
            const __m128d ok = _mm_cmpgt_pd(len2, tiny);
            const int ok_bits = _mm_movemask_pd(ok);
            degenerate_count += 2 - ((ok_bits & 1) + (ok_bits >> 1));
            _mm_storeu_pd(nx + x, _mm_and_pd(ok, _mm_mul_pd(vx, inv)));
            _mm_storeu_pd(ny + x, _mm_and_pd(ok, _mm_mul_pd(vy, inv)));
            _mm_storeu_pd(nz + x, _mm_or_pd(_mm_and_pd(ok, _mm_mul_pd(vz, inv)), _mm_andnot_pd(ok, one)));
        }
#endif
        for (; x < normal.width; ++x) {
            double n[3];
            bool degenerate = false;
            decode_normal(x, y, n, degenerate);
            degenerate_count += degenerate;
            nx[x] = n[0], ny[x] = n[1], nz[x] = n[2];
        }
        return degenerate_count;
    }

    // Output roughness of base texel (x, y) whose mean alpha^2 is a: (a)^(1/4). For a same-size map that is
    // the clamped input value itself (the double round trip r -> r^4 -> r rounds back to the same float),
    // so the two roots are taken only for resampled maps.
    float base_roughness(int x, int y, double a) const {
        if (!resampled.empty()) return float(std::sqrt(std::sqrt(std::clamp(a, 0.0, 1.0))));
        if (roughness) return std::clamp(roughness->texel(x, y)[roughness_channel], 0.0f, 1.0f);
        return constant_r;
    }

    // Fills the layout.count quantities of base texel (x, y) into v; returns whether it was degenerate.
    bool texel_values(int x, int y, double* v) const {
        double n[3];
        bool degenerate = false;
        decode_normal(x, y, n, degenerate);
        texel_values_from_normal(x, y, n, v);
        return degenerate;
    }

    // The layout.count quantities of base texel (x, y) whose unit normal is n.
    void texel_values_from_normal(int x, int y, const double n[3], double* v) const {
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

    // Fills the layout.count quantities of base row y into row[x * count + c]; returns degenerate count.
    long long decode_row(int y, double* row) const {
        long long degenerate_count = 0;
        const int C = layout.count;
        for (int x = 0; x < normal.width; ++x) degenerate_count += texel_values(x, y, row + size_t(x) * C);
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
// the input roughness passes through). Same outputs as finalize_texel without its divisions and roots (r is
// the base roughness, Decoder::base_roughness);
// the decoded normal is already unit length.
inline void finalize_base_texel(const double* v, float r, const Layout& layout, const TextureBakeSettings& s,
                                bool flip_y, float* rough, float* kern, float* lean, float* nrm) {
    if (rough) {
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

// A zero-filled w x h image. Large buffers are reserved first and marked for transparent huge pages before
// they are touched: a 4096^2 bake writes about 1 GiB of fresh outputs, and faulting it in 4 KiB pages costs
// more CPU time than the arithmetic.
Image make_output_image(int w, int h, int channels) {
    Image image;
    image.width = w, image.height = h, image.channels = channels;
    const size_t n = size_t(w) * size_t(h) * size_t(channels);
    image.pixels.reserve(n);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    constexpr uintptr_t kHuge = uintptr_t(2) << 20;
    const uintptr_t begin = (reinterpret_cast<uintptr_t>(image.pixels.data()) + kHuge - 1) & ~(kHuge - 1);
    const uintptr_t end = (reinterpret_cast<uintptr_t>(image.pixels.data() + n)) & ~(kHuge - 1);
    if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);  // a hint; failure is harmless
#endif
    image.pixels.resize(n);
    return image;
}

void allocate_chain(MipChain& chain, int W, int H, int levels, int channels) {
    chain.levels.clear();
    for (int L = 0; L < levels; ++L)
        chain.levels.push_back(make_output_image(std::max(1, W >> L), std::max(1, H >> L), channels));
}

}  // namespace

int mip_level_count(int width, int height) {
    int n = 1;
    for (int s = std::max(width, height); s > 1; s >>= 1) ++n;
    return n;
}

std::optional<std::pair<int, int>> find_non_finite(const Image& image) {
    const size_t n = image.pixels.size();
    // Blocks are screened branch-free on the exponent bits (all ones: NaN or infinity), which vectorises;
    // only a block that holds one is searched element by element.
    constexpr size_t kBlock = 4096;
    size_t first = 0;
    for (; first < n; first += kBlock) {
        const size_t end = std::min(n, first + kBlock);
        uint32_t bad = 0;
        for (size_t i = first; i < end; ++i) {
            uint32_t bits;
            std::memcpy(&bits, &image.pixels[i], sizeof bits);
            bad |= uint32_t((bits & 0x7f800000u) == 0x7f800000u);
        }
        if (bad) break;
    }
    for (size_t i = first; i < n; ++i) {
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
        dec.constant_r = float(std::sqrt(std::sqrt(std::clamp(dec.constant_a, 0.0, 1.0))));
    }
    const bool slope = settings.outputs.lean && settings.lean_space == LeanSpace::Slope;
    if (slope) {
        layout.slope = layout.count;
        layout.count += 5;
    }
    const int C = layout.count;

    const int levels = mip_level_count(W, H);
    const TextureOutputs& want = settings.outputs;
    // Zero-filling the outputs is a large part of the bake's memory traffic: the chains are allocated on
    // two threads (LEAN, the widest, against the other three).
    auto allocate_outputs = [&] {
        tbb::parallel_invoke(
            [&] {
                if (want.lean) allocate_chain(result.lean, W, H, levels, 5);
            },
            [&] {
                if (want.roughness) allocate_chain(result.roughness, W, H, levels, dec.orm ? 3 : 1);
                if (want.kernel) allocate_chain(result.kernel, W, H, levels, settings.anisotropic ? 3 : 1);
                if (want.normal) allocate_chain(result.normal, W, H, levels, 3);
            });
    };

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
                finalize_base_texel(means + size_t(i) * C, dec.base_roughness(i, j, means[size_t(i) * C + kA]), layout,
                                    settings, dec.flip_y, R ? R->texel(i, j) : nullptr,
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
    // When level 2 tiles level 1 as well, each task also owns whole level-2 rows: the level-1 rows of one
    // level-2 row stay in the task, and only level-2 means (a sixteenth of the base) are kept for level 3.
    auto run_fused = [&] {
        const int w1 = level_w(1), h1 = level_h(1), fx = W / w1, fy = H / h1;
        const bool with2 = levels > 2 && tiles_previous(2);
        const int w2 = with2 ? level_w(2) : w1, h2 = with2 ? level_h(2) : h1;
        const int fx2 = w1 / w2, fy2 = h1 / h2;  // 1 x 1 when level 2 is not part of this pass
        const int next = with2 ? 3 : 2;
        const bool keep = next < levels && tiles_previous(next);
        current.assign(keep ? size_t(w2) * h2 * C : 0, 0.0);
        std::vector<double> change1(size_t(h1), 0.0), change2(size_t(h2), 0.0);
        std::vector<long long> row_degenerate(size_t(h2), 0);
        Image* R0 = want.roughness ? &result.roughness.levels[0] : nullptr;
        Image* K0 = want.kernel ? &result.kernel.levels[0] : nullptr;
        Image* E0 = want.lean ? &result.lean.levels[0] : nullptr;
        Image* N0 = want.normal ? &result.normal.levels[0] : nullptr;
        const double inv = 1.0 / double(fx * fy);
        const double inv2 = 1.0 / double(fx2 * fy2);
        // Each base texel is decoded once, written as level 0 and added to its level-1 block mean in the
        // fixed order (dy, dx), so no decoded base row is stored; level 2 sums level-1 means in the same
        // order as the level loop below would.
        tbb::parallel_for(tbb::blocked_range<int>(0, h2, with2 ? 1 : 4), [&](const tbb::blocked_range<int>& rows) {
            std::vector<double> means1(size_t(w1) * C * size_t(fy2)), means2(size_t(w2) * C);
            std::vector<double> normals(size_t(W) * 3 * size_t(fy));  // rows of nx, ny, nz per dy
            for (int j2 = rows.begin(); j2 < rows.end(); ++j2) {
                long long row_deg = 0;
                for (int dy2 = 0; dy2 < fy2; ++dy2) {
                    const int j = j2 * fy2 + dy2;
                    double* means = means1.data() + size_t(dy2) * w1 * C;
                    for (int dy = 0; dy < fy; ++dy) {
                        double* nx = normals.data() + size_t(dy) * 3 * W;
                        row_deg += dec.decode_normal_row(j * fy + dy, nx, nx + W, nx + 2 * size_t(W));
                    }
                    for (int i = 0; i < w1; ++i) {
                        double m[kMaxChannels];
                        for (int c = 0; c < C; ++c) m[c] = 0.0;
                        for (int dy = 0; dy < fy; ++dy) {
                            const int y = j * fy + dy;
                            const double* nx = normals.data() + size_t(dy) * 3 * W;
                            for (int dx = 0; dx < fx; ++dx) {
                                const int x = i * fx + dx;
                                const double n[3] = {nx[x], nx[W + x], nx[2 * size_t(W) + x]};
                                double v[kMaxChannels];
                                dec.texel_values_from_normal(x, y, n, v);
                                finalize_base_texel(v, dec.base_roughness(x, y, v[kA]), layout, settings, dec.flip_y,
                                                    R0 ? R0->texel(x, y) : nullptr,
                                                    K0 ? K0->texel(x, y) : nullptr, E0 ? E0->texel(x, y) : nullptr,
                                                    N0 ? N0->texel(x, y) : nullptr);
                                for (int c = 0; c < C; ++c) m[c] += v[c];
                            }
                        }
                        double* out = means + size_t(i) * C;
                        for (int c = 0; c < C; ++c) out[c] = m[c] * inv;
                    }
                    change1[size_t(j)] = finalize_row(1, j, means);
                }
                row_degenerate[size_t(j2)] = row_deg;
                const double* kept = means1.data();
                if (with2) {
                    for (int i = 0; i < w2; ++i) {
                        double* m = means2.data() + size_t(i) * C;
                        for (int c = 0; c < C; ++c) m[c] = 0.0;
                        for (int dy = 0; dy < fy2; ++dy) {
                            const double* src = means1.data() + (size_t(dy) * w1 + size_t(i) * fx2) * C;
                            for (int dx = 0; dx < fx2; ++dx)
                                for (int c = 0; c < C; ++c) m[c] += src[size_t(dx) * C + c];
                        }
                        for (int c = 0; c < C; ++c) m[c] *= inv2;
                    }
                    change2[size_t(j2)] = finalize_row(2, j2, means2.data());
                    kept = means2.data();
                }
                if (keep) std::copy(kept, kept + size_t(w2) * C, current.begin() + ptrdiff_t(size_t(j2) * w2 * C));
            }
        });
        level_change[0] = 0.0;  // mip 0 passes the input roughness through
        level_change[1] = reduce_changes(change1);
        if (with2) level_change[2] = reduce_changes(change2);
        for (long long d : row_degenerate) degenerate += d;
        previous.swap(current);
        return next;
    };

    auto run = [&] {
        allocate_outputs();
        const int first_level = fused ? run_fused() : 0;
        for (int L = first_level; L < levels; ++L) {
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
