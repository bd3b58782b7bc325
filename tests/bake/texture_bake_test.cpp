// Texture bake (SPEC Sec. 3) against closed forms and an independent brute-force reference.
#include "bake/texture_bake.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <mutex>
#include <random>
#include <tuple>

namespace specbake {
namespace {

// Stored value c of a normal component n: c = (n + 1) / 2.
float encode(double n) { return float(0.5 * n + 0.5); }

// Decoded unit normal of a stored texel, in double, as SPEC Sec. 2 states it.
void decode(const float* c, int channels, bool flip_y, bool reconstruct, double n[3]) {
    double x = 2.0 * c[0] - 1.0, y = 2.0 * c[1] - 1.0;
    if (flip_y) y = -y;
    double z = reconstruct || channels == 2 ? std::sqrt(std::max(0.0, 1.0 - x * x - y * y)) : 2.0 * c[2] - 1.0;
    const double len = std::sqrt(x * x + y * y + z * z);
    n[0] = x / len, n[1] = y / len, n[2] = z / len;
}

// SPEC Sec. 3 formulas written out independently of the implementation.
double filtered_a(double a, double t, RoughnessFilterMode mode) {
    if (mode == RoughnessFilterMode::Approx) return std::min(1.0, a + t);
    return (a + t * (1.0 - a)) / (1.0 + t * (1.0 - a));
}

double kernel_t(IsotropicReduction red, double xx, double yy, double xy) {
    if (red == IsotropicReduction::Mean) return xx + yy;
    if (red == IsotropicReduction::Sum) return 2.0 * (xx + yy);
    const double l = 0.5 * (xx + yy) + std::sqrt(0.25 * (xx - yy) * (xx - yy) + xy * xy);
    return 2.0 * l;
}

struct RefTexel {
    double r = 0, occlusion = 0, metallic = 0, t = 0, sxx = 0, syy = 0, sxy = 0, a_base = 0;
    double lean[5] = {};
    double normal[3] = {};
};

// Brute force: loops over every base texel and every roughness texel overlapping the footprint of
// texel (i, j) of level L in the continuous [0, 1]^2 texture domain.
RefTexel reference(const Image& nm, const Image* rough, int channel, double rvalue, const TextureBakeSettings& s,
                   int L, int i, int j) {
    const int W = nm.width, H = nm.height;
    const int w = std::max(1, W >> L), h = std::max(1, H >> L);
    const double u0 = double(i) / w, u1 = double(i + 1) / w, v0 = double(j) / h, v1 = double(j + 1) / h;
    auto overlap = [](double a0, double a1, double b0, double b1) { return std::max(0.0, std::min(a1, b1) - std::max(a0, b0)); };
    const bool flip = s.normal_y == NormalGreen::MinusY;
    const bool recon = s.reconstruct_z == ReconstructZ::Always || nm.channels == 2;
    double wsum = 0, m[3] = {}, M[3] = {};
    for (int y = 0; y < H; ++y) {
        const double wy = overlap(v0, v1, double(y) / H, double(y + 1) / H);
        if (wy <= 0) continue;
        for (int x = 0; x < W; ++x) {
            const double wx = overlap(u0, u1, double(x) / W, double(x + 1) / W);
            if (wx <= 0) continue;
            double n[3];
            decode(nm.texel(x, y), nm.channels, flip, recon, n);
            const double wgt = wx * wy;
            wsum += wgt;
            for (int c = 0; c < 3; ++c) m[c] += wgt * n[c];
            M[0] += wgt * n[0] * n[0], M[1] += wgt * n[1] * n[1], M[2] += wgt * n[0] * n[1];
        }
    }
    for (double& v : m) v /= wsum;
    for (double& v : M) v /= wsum;
    RefTexel out;
    if (rough) {
        double rs = 0, a = 0, o = 0, met = 0;
        for (int y = 0; y < rough->height; ++y) {
            const double wy = overlap(v0, v1, double(y) / rough->height, double(y + 1) / rough->height);
            if (wy <= 0) continue;
            for (int x = 0; x < rough->width; ++x) {
                const double wx = overlap(u0, u1, double(x) / rough->width, double(x + 1) / rough->width);
                if (wx <= 0) continue;
                const float* t = rough->texel(x, y);
                const double r = t[channel];
                rs += wx * wy;
                a += wx * wy * r * r * r * r;
                if (rough->channels >= 3) o += wx * wy * t[0], met += wx * wy * t[2];
            }
        }
        out.a_base = a / rs, out.occlusion = o / rs, out.metallic = met / rs;
    } else {
        out.a_base = rvalue * rvalue * rvalue * rvalue;
    }
    out.sxx = std::max(0.0, M[0] - m[0] * m[0]);
    out.syy = std::max(0.0, M[1] - m[1] * m[1]);
    out.sxy = M[2] - m[0] * m[1];
    out.t = kernel_t(s.isotropic, out.sxx, out.syy, out.sxy);
    if (s.max_kernel) out.t = std::min(out.t, *s.max_kernel);
    out.r = std::pow(filtered_a(out.a_base, out.t, s.filter), 0.25);
    out.lean[0] = m[0], out.lean[1] = m[1], out.lean[2] = M[0], out.lean[3] = M[1], out.lean[4] = M[2];
    const double len = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    out.normal[0] = 0.5 * m[0] / len + 0.5;
    out.normal[1] = 0.5 * (flip ? -m[1] : m[1]) / len + 0.5;
    out.normal[2] = 0.5 * m[2] / len + 0.5;
    return out;
}

Image random_normal_map(int W, int H, unsigned seed, double spread) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> g(0.0, spread);
    Image n(W, H, 3);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            double v[3] = {g(rng), g(rng), 1.0};
            const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            for (int c = 0; c < 3; ++c) n.texel(x, y)[c] = encode(v[c] / len);
        }
    return n;
}

Image random_orm(int W, int H, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    Image r(W, H, 3);
    for (float& v : r.pixels) v = u(rng);
    return r;
}

void expect_matches_reference(const Image& nm, const Image* rough, int channel, double rvalue,
                              const TextureBakeSettings& s) {
    auto res = bake_texture(nm, rough, channel, float(rvalue), s);
    ASSERT_TRUE(res.ok()) << res.error().message;
    const int levels = mip_level_count(nm.width, nm.height);
    ASSERT_EQ(int(res->roughness.levels.size()), levels);
    const bool orm = rough && rough->channels >= 3 && channel == 1;
    double max_change = 0.0;
    for (int L = 0; L < levels; ++L) {
        const Image& R = res->roughness.levels[size_t(L)];
        ASSERT_EQ(R.width, std::max(1, nm.width >> L));
        ASSERT_EQ(R.height, std::max(1, nm.height >> L));
        for (int j = 0; j < R.height; ++j) {
            for (int i = 0; i < R.width; ++i) {
                const RefTexel ref = reference(nm, rough, channel, double(float(rvalue)), s, L, i, j);
                max_change = std::max(max_change, std::abs(ref.r - std::pow(ref.a_base, 0.25)));
                const float* r = R.texel(i, j);
                SCOPED_TRACE("level " + std::to_string(L) + " texel " + std::to_string(i) + "," + std::to_string(j));
                if (orm) {
                    EXPECT_NEAR(r[0], ref.occlusion, 2e-6);
                    EXPECT_NEAR(r[1], ref.r, 2e-6);
                    EXPECT_NEAR(r[2], ref.metallic, 2e-6);
                } else {
                    EXPECT_NEAR(r[0], ref.r, 2e-6);
                }
                const float* k = res->kernel.levels[size_t(L)].texel(i, j);
                if (s.anisotropic) {
                    EXPECT_NEAR(k[0], ref.sxx, 2e-6);
                    EXPECT_NEAR(k[1], ref.syy, 2e-6);
                    EXPECT_NEAR(k[2], ref.sxy, 2e-6);
                } else {
                    EXPECT_NEAR(k[0], ref.t, 2e-6);
                }
                const float* l = res->lean.levels[size_t(L)].texel(i, j);
                for (int c = 0; c < 5; ++c) EXPECT_NEAR(l[c], ref.lean[c], 2e-6);
                const float* n = res->normal.levels[size_t(L)].texel(i, j);
                for (int c = 0; c < 3; ++c) EXPECT_NEAR(n[c], ref.normal[c], 2e-6);
            }
        }
    }
    EXPECT_NEAR(res->max_roughness_change, max_change, 1e-9);
}

TEST(TextureBake, BruteForceRandomNpotSameSizeOrm) {
    const Image nm = random_normal_map(37, 23, 1, 0.3);
    const Image orm = random_orm(37, 23, 2);
    TextureBakeSettings s;
    expect_matches_reference(nm, &orm, 1, 0.0, s);
}

TEST(TextureBake, BruteForceRoughnessOfOtherResolution) {
    const Image nm = random_normal_map(48, 20, 3, 0.2);
    const Image small = random_orm(13, 29, 4);  // neither size divides the normal map's
    TextureBakeSettings s;
    s.anisotropic = true;
    expect_matches_reference(nm, &small, 1, 0.0, s);
    const Image large = random_orm(101, 40, 5);
    s.isotropic = IsotropicReduction::Max;
    expect_matches_reference(nm, &large, 0, 0.0, s);
}

TEST(TextureBake, BruteForceEveryReductionAndFilter) {
    const Image nm = random_normal_map(20, 33, 6, 0.4);
    for (IsotropicReduction red : {IsotropicReduction::Mean, IsotropicReduction::Sum, IsotropicReduction::Max}) {
        for (RoughnessFilterMode f : {RoughnessFilterMode::Projected, RoughnessFilterMode::Approx}) {
            TextureBakeSettings s;
            s.isotropic = red;
            s.filter = f;
            expect_matches_reference(nm, nullptr, 0, 0.3, s);
        }
    }
}

TEST(TextureBake, BruteForcePowerOfTwoNonSquareMinusYAndClamp) {
    const Image nm = random_normal_map(64, 8, 7, 0.5);
    TextureBakeSettings s;
    s.normal_y = NormalGreen::MinusY;
    s.max_kernel = 0.05;
    expect_matches_reference(nm, nullptr, 0, 0.1, s);
}

// Even sizes take the pass that builds levels 0 and 1 from registers; 78 = 2 (4 * 9 + 3) leaves a tail of
// three level-1 texels per row to the planes.
TEST(TextureBake, BruteForceEvenSizesWithOrmAndTail) {
    const Image nm = random_normal_map(78, 40, 11, 0.4);
    const Image orm = random_orm(78, 40, 12);
    TextureBakeSettings s;
    s.anisotropic = true;
    expect_matches_reference(nm, &orm, 1, 0.0, s);
}

// The register pass's other forms: a four-channel normal map (alpha unread) with -Y, and a one-channel
// roughness map of the same size; then z reconstructed from a three-channel map.
TEST(TextureBake, BruteForceEvenSizesRgbaNormalsOneChannelRoughness) {
    const Image rgb = random_normal_map(40, 24, 15, 0.35);
    Image rgba(rgb.width, rgb.height, 4);
    for (size_t i = 0; i < rgb.texel_count(); ++i) {
        for (int c = 0; c < 3; ++c) rgba.pixels[4 * i + size_t(c)] = rgb.pixels[3 * i + size_t(c)];
        rgba.pixels[4 * i + 3] = 0.25f;
    }
    const Image orm = random_orm(40, 24, 16);
    Image rough(orm.width, orm.height, 1);
    for (size_t i = 0; i < orm.texel_count(); ++i) rough.pixels[i] = orm.pixels[3 * i + 1];
    TextureBakeSettings s;
    s.normal_y = NormalGreen::MinusY;
    expect_matches_reference(rgba, &rough, 0, 0.0, s);
    TextureBakeSettings z;
    z.reconstruct_z = ReconstructZ::Always;
    expect_matches_reference(rgb, &rough, 0, 0.0, z);
}

TEST(TextureBake, BruteForceTwoChannelMap) {
    const Image full = random_normal_map(24, 17, 8, 0.3);
    Image two(full.width, full.height, 2);
    for (size_t i = 0; i < full.texel_count(); ++i)
        two.pixels[2 * i] = full.pixels[3 * i], two.pixels[2 * i + 1] = full.pixels[3 * i + 1];
    TextureBakeSettings s;
    expect_matches_reference(two, nullptr, 0, 0.4, s);
    auto res = bake_texture(two, nullptr, 0, 0.4f, s);
    ASSERT_TRUE(res.ok());
    EXPECT_TRUE(res->notes.z_reconstructed);
    EXPECT_EQ(res->notes.z_reason, "two-channel map");
}

// Two normals alternating texel by texel: every footprint of level >= 1 holds both equally often, so
// m = (p1 + p2) / 2 and Sigma = d d^T / 4 with d = p1 - p2, in closed form.
TEST(TextureBake, CheckerboardClosedFormEveryLevel) {
    const double n1[3] = {0.6, 0.0, 0.8}, n2[3] = {-0.28, 0.96 * 0.6, 0.96 * 0.8};
    const int size = 32;
    Image nm(size, size, 3);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x)
            for (int c = 0; c < 3; ++c) nm.texel(x, y)[c] = encode(((x + y) % 2 ? n2 : n1)[c]);
    // The decoded normals are the stored values' (not exactly n1, n2).
    double p1[3], p2[3];
    decode(nm.texel(0, 0), 3, false, false, p1);
    decode(nm.texel(1, 0), 3, false, false, p2);
    const double dx = p1[0] - p2[0], dy = p1[1] - p2[1];
    const double sxx = dx * dx / 4, syy = dy * dy / 4, sxy = dx * dy / 4;
    const double r_in = double(0.2f), a_in = std::pow(r_in, 4.0);
    for (IsotropicReduction red : {IsotropicReduction::Mean, IsotropicReduction::Sum, IsotropicReduction::Max}) {
        TextureBakeSettings s;
        s.isotropic = red;
        s.anisotropic = false;  // the kernel output as t
        auto res = bake_texture(nm, nullptr, 0, float(r_in), s);
        ASSERT_TRUE(res.ok());
        // tr(Sigma) = |d|^2 / 4; lambda_max = |d|^2 / 4 too (Sigma has rank one).
        const double d2 = dx * dx + dy * dy;
        const double t = red == IsotropicReduction::Mean ? d2 / 4 : d2 / 2;
        const double r_expect = std::pow((a_in + t * (1 - a_in)) / (1 + t * (1 - a_in)), 0.25);
        EXPECT_NEAR(res->roughness.levels[0].pixels[0], r_in, 1e-7);  // mip 0 passes through
        EXPECT_EQ(res->kernel.levels[0].pixels[0], 0.0f);
        for (size_t L = 1; L < res->roughness.levels.size(); ++L) {
            const Image& R = res->roughness.levels[L];
            for (float v : R.pixels) ASSERT_NEAR(v, r_expect, 1e-6) << "level " << L;
            for (float v : res->kernel.levels[L].pixels) ASSERT_NEAR(v, t, 1e-6) << "level " << L;
            const float* l = res->lean.levels[L].texel(0, 0);
            EXPECT_NEAR(l[0], (p1[0] + p2[0]) / 2, 1e-6);
            EXPECT_NEAR(l[1], (p1[1] + p2[1]) / 2, 1e-6);
            EXPECT_NEAR(l[2] - l[0] * l[0], sxx, 1e-6);
            EXPECT_NEAR(l[3] - l[1] * l[1], syy, 1e-6);
            EXPECT_NEAR(l[4] - l[0] * l[1], sxy, 1e-6);
        }
        EXPECT_NEAR(res->max_roughness_change, r_expect - r_in, 1e-9);
    }
}

// Ribs p.x = s sin(2 pi (x + 1/2) / P): over any whole number of periods (P >= 3) the discrete mean
// of sin is 0 and of sin^2 is 1/2, so Sigma = diag(s^2 / 2, 0) at every level whose footprint is a
// multiple of P, and LEAN holds m = 0, M.xx = s^2 / 2.
TEST(TextureBake, SinusoidalRibsClosedForm) {
    const int period = 4, W = 64, H = 16;
    const double amp = 0.5;
    Image nm(W, H, 3);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const double px = amp * std::sin(2 * M_PI * (x + 0.5) / period);
            float* t = nm.texel(x, y);
            t[0] = encode(px), t[1] = encode(0.0), t[2] = encode(std::sqrt(1 - px * px));
        }
    TextureBakeSettings s;
    s.anisotropic = true;
    auto res = bake_texture(nm, nullptr, 0, 0.05f, s);
    ASSERT_TRUE(res.ok());
    for (size_t L = 2; L < res->kernel.levels.size(); ++L) {
        const Image& K = res->kernel.levels[L];
        for (int j = 0; j < K.height; ++j)
            for (int i = 0; i < K.width; ++i) {
                EXPECT_NEAR(K.texel(i, j)[0], amp * amp / 2, 2e-6) << "level " << L;
                EXPECT_NEAR(K.texel(i, j)[1], 0.0, 1e-9);
                EXPECT_NEAR(K.texel(i, j)[2], 0.0, 1e-6);
                EXPECT_NEAR(res->lean.levels[L].texel(i, j)[0], 0.0, 2e-6);
            }
    }
}

// The Sigma kernel's alpha channel is the rough share: at every level, the fraction of the footprint's
// base texels whose slope |n.xy| / n.z exceeds 0.02. Texels with slope 0.019 (flat) and 0.021 (rough) at
// angles of their own, and steep ones, in a hashed pattern; the expected share is counted from the
// pattern itself. Both bake paths: the register pass (projected LEAN) and the planes (slope-space LEAN).
TEST(TextureBake, RoughShareCountsTheSteepTexelsOfEachFootprint) {
    const int W = 64, H = 32;
    auto kind = [](int x, int y) { return (unsigned(x) * 73856093u ^ unsigned(y) * 19349663u) % 5u; };
    auto slope_of = [](unsigned k) { return k == 0 ? 0.0 : k == 1 ? 0.019 : k == 2 ? 0.021 : k == 3 ? 0.4 : 1.5; };
    Image nm(W, H, 3);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const double t = slope_of(kind(x, y)), phi = 0.37 * x + 1.1 * y, len = std::hypot(t, 1.0);
            const double n[3] = {t * std::cos(phi) / len, t * std::sin(phi) / len, 1.0 / len};
            for (int c = 0; c < 3; ++c) nm.texel(x, y)[c] = encode(n[c]);
        }
    for (LeanSpace space : {LeanSpace::Projected, LeanSpace::Slope}) {
        TextureBakeSettings s;
        s.anisotropic = true;
        s.lean_space = space;
        auto res = bake_texture(nm, nullptr, 0, 0.3f, s);
        ASSERT_TRUE(res.ok());
        ASSERT_EQ(res->kernel.channels(), 4);
        for (size_t L = 0; L < res->kernel.levels.size(); ++L) {
            const Image& K = res->kernel.levels[L];
            const int fx = W / K.width, fy = H / K.height;  // the last levels' footprints are 2:1
            for (int j = 0; j < K.height; ++j)
                for (int i = 0; i < K.width; ++i) {
                    int rough = 0;
                    for (int y = j * fy; y < (j + 1) * fy; ++y)
                        for (int x = i * fx; x < (i + 1) * fx; ++x) rough += kind(x, y) >= 2 ? 1 : 0;
                    ASSERT_NEAR(K.texel(i, j)[3], double(rough) / double(fx * fy), 1e-6)
                        << "level " << L << " texel " << i << "," << j << (space == LeanSpace::Slope ? " (slope LEAN)" : "");
                }
        }
    }
}

TEST(TextureBake, OutputsAreIdenticalForAnyThreadCount) {
    const Image nm = random_normal_map(257, 129, 9, 0.3);
    const Image orm = random_orm(100, 300, 10);
    TextureBakeSettings s;
    s.threads = 1;
    auto one = bake_texture(nm, &orm, 1, 0, s);
    s.threads = 2;
    auto two = bake_texture(nm, &orm, 1, 0, s);
    ASSERT_TRUE(one.ok() && two.ok());
    for (size_t L = 0; L < one->roughness.levels.size(); ++L) {
        for (const auto& [a, b] : {std::pair{&one->roughness, &two->roughness}, std::pair{&one->kernel, &two->kernel},
                                   std::pair{&one->lean, &two->lean}, std::pair{&one->normal, &two->normal}}) {
            const auto& x = a->levels[L].pixels;
            const auto& y = b->levels[L].pixels;
            ASSERT_EQ(x.size(), y.size());
            EXPECT_EQ(std::memcmp(x.data(), y.data(), x.size() * sizeof(float)), 0) << "level " << L;
        }
    }
}

// The same bake through the register pass (roughness map of the normal map's size) and through the planes
// (the same roughness at twice the resolution, resampled first) is bit for bit the same: the roughness
// values are chosen so that the resampled means are exact (r in quarters, R and B in eighths).
TEST(TextureBake, RegisterAndPlanePassesAgreeBitForBit) {
    const int W = 78, H = 40;
    std::mt19937 rng(13);
    std::uniform_int_distribution<int> quarter(0, 4), eighth(0, 8);
    Image orm(W, H, 3), orm2(2 * W, 2 * H, 3);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const float v[3] = {float(eighth(rng)) / 8.0f, float(quarter(rng)) / 4.0f, float(eighth(rng)) / 8.0f};
            for (int c = 0; c < 3; ++c) {
                orm.texel(x, y)[c] = v[c];
                for (int k = 0; k < 4; ++k) orm2.texel(2 * x + k % 2, 2 * y + k / 2)[c] = v[c];
            }
        }
    const Image rgb = random_normal_map(W, H, 14, 0.5);
    Image two(W, H, 2);
    for (size_t i = 0; i < rgb.texel_count(); ++i)
        two.pixels[2 * i] = rgb.pixels[3 * i], two.pixels[2 * i + 1] = rgb.pixels[3 * i + 1];
    for (const Image* nm : {&rgb, static_cast<const Image*>(&two)}) {
        for (const NormalGreen green : {NormalGreen::PlusY, NormalGreen::MinusY}) {
            TextureBakeSettings s;
            s.normal_y = green;
            auto direct = bake_texture(*nm, &orm, 1, 0.0f, s);
            auto resampled = bake_texture(*nm, &orm2, 1, 0.0f, s);
            ASSERT_TRUE(direct.ok() && resampled.ok());
            EXPECT_FALSE(direct->notes.roughness_resampled);
            EXPECT_TRUE(resampled->notes.roughness_resampled);
            EXPECT_EQ(direct->max_roughness_change, resampled->max_roughness_change);
            for (size_t L = 0; L < direct->roughness.levels.size(); ++L) {
                for (const auto& [a, b] :
                     {std::pair{&direct->roughness, &resampled->roughness}, std::pair{&direct->kernel, &resampled->kernel},
                      std::pair{&direct->lean, &resampled->lean}, std::pair{&direct->normal, &resampled->normal}}) {
                    const auto& x = a->levels[L].pixels;
                    const auto& y = b->levels[L].pixels;
                    ASSERT_EQ(x.size(), y.size());
                    EXPECT_EQ(std::memcmp(x.data(), y.data(), x.size() * sizeof(float)), 0)
                        << nm->channels << " channels, level " << L;
                }
            }
        }
    }
}

// The streamed bake hands every texel of every level over exactly once, with the values bake_texture()
// returns, for fused (even), odd and non-square sizes, and for maps wide enough to arrive in column blocks.
TEST(TextureBake, BlocksStreamEveryTexelOnceWithTheChainValues) {
    for (const auto& [W, H] : {std::pair{64, 32}, std::pair{37, 23}, std::pair{16, 1}, std::pair{6, 12},
                               std::pair{600, 20}, std::pair{1030, 6}}) {
        SCOPED_TRACE(std::to_string(W) + "x" + std::to_string(H));
        const Image nm = random_normal_map(W, H, 16, 0.3);
        const Image orm = random_orm(W, H, 17);
        TextureBakeSettings s;
        s.threads = 2;
        auto chains = bake_texture(nm, &orm, 1, 0, s);
        ASSERT_TRUE(chains.ok());
        const TextureBakeShape shape = texture_bake_shape(nm, &orm, 1, s);
        ASSERT_EQ(shape.levels, mip_level_count(W, H));
        EXPECT_EQ(shape.roughness_channels, 3);
        EXPECT_EQ(shape.lean_channels, 5);
        std::vector<std::vector<int>> seen(size_t(shape.levels));
        for (size_t L = 0; L < seen.size(); ++L) seen[L].assign(chains->roughness.levels[L].texel_count(), 0);
        std::mutex m;
        bool equal = true, inside = true;
        auto same = [](const float* block, const Image& level, const TextureBakeRows& r) {
            const size_t row_floats = size_t(r.width) * size_t(level.channels);
            for (int k = 0; k < r.rows; ++k)
                if (std::memcmp(block + size_t(k) * row_floats, level.texel(r.x0, r.y0 + k), row_floats * sizeof(float)))
                    return false;
            return true;
        };
        auto streamed = bake_texture_rows(nm, &orm, 1, 0, s, [&](const TextureBakeRows& r) {
            std::lock_guard<std::mutex> lock(m);
            const size_t L = size_t(r.level);
            const Image& level = chains->roughness.levels[L];
            if (r.x0 < 0 || r.y0 < 0 || r.x0 + r.width > level.width || r.y0 + r.rows > level.height) {
                inside = false;
                return;
            }
            for (int y = r.y0; y < r.y0 + r.rows; ++y)
                for (int x = r.x0; x < r.x0 + r.width; ++x) ++seen[L][size_t(y) * level.width + x];
            equal = equal && same(r.roughness, chains->roughness.levels[L], r) &&
                    same(r.kernel, chains->kernel.levels[L], r) && same(r.lean, chains->lean.levels[L], r) &&
                    same(r.normal, chains->normal.levels[L], r);
        });
        ASSERT_TRUE(streamed.ok());
        EXPECT_TRUE(inside);
        EXPECT_TRUE(equal);
        for (size_t L = 0; L < seen.size(); ++L)
            EXPECT_EQ(seen[L], std::vector<int>(seen[L].size(), 1)) << "level " << L;
        EXPECT_EQ(streamed->max_roughness_change, chains->max_roughness_change);
        EXPECT_TRUE(streamed->roughness.levels.empty());
    }
}

// `bits`-bit codes of `image` (values rounded to k / (2^bits - 1)), and the float image those codes decode to
// (float(k) * (1.0f / (2^bits - 1)), as io/ decodes integer files). 8-bit rows are padded like a PNG's
// inflated data (one filter byte before each row), 16-bit rows by three values after each row.
struct IntegerMap {
    std::vector<uint8_t> bytes;
    std::vector<uint16_t> words;
    TextureMap map;
    Image decoded;
};
IntegerMap as_integers(const Image& image, int bits) {
    IntegerMap b;
    const size_t row = size_t(image.width) * size_t(image.channels);
    const size_t stride = bits == 8 ? row + 1 : row + 3, first = bits == 8 ? 1 : 0;
    const double top = bits == 8 ? 255.0 : 65535.0;
    const float scale = bits == 8 ? 1.0f / 255.0f : 1.0f / 65535.0f;
    if (bits == 8) b.bytes.assign(size_t(image.height) * stride, 0xEE);
    else b.words.assign(size_t(image.height) * stride, 0xEEEE);
    b.decoded = Image(image.width, image.height, image.channels);
    for (int y = 0; y < image.height; ++y)
        for (size_t i = 0; i < row; ++i) {
            const long k = std::lround(std::clamp(double(image.pixels[size_t(y) * row + i]), 0.0, 1.0) * top);
            if (bits == 8) b.bytes[size_t(y) * stride + first + i] = uint8_t(k);
            else b.words[size_t(y) * stride + first + i] = uint16_t(k);
            b.decoded.pixels[size_t(y) * row + i] = float(k) * scale;
        }
    b.map = TextureMap{image.width, image.height, image.channels, stride};
    if (bits == 8) b.map.u8 = b.bytes.data() + first;
    else b.map.u16 = b.words.data() + first;
    return b;
}

TEST(TextureBake, IntegerMapsBakeAsTheirDecodedFloats) {
    for (const int bits : {8, 16}) {
        SCOPED_TRACE(std::to_string(bits) + "-bit");
        struct Case {
            int W, H, normal_channels, rough_w, rough_h, rough_channels, channel;
        };
        for (const Case& c : {Case{64, 32, 3, 64, 32, 3, 1}, Case{37, 23, 3, 37, 23, 1, 0}, Case{40, 24, 2, 40, 24, 3, 1},
                              Case{48, 16, 4, 24, 8, 3, 1}, Case{1030, 6, 3, 1030, 6, 3, 1}, Case{9, 5, 3, 0, 0, 0, 0}}) {
            SCOPED_TRACE(std::to_string(c.W) + "x" + std::to_string(c.H) + " normal channels " +
                         std::to_string(c.normal_channels));
            Image nm = random_normal_map(c.W, c.H, 21, 0.3);
            if (c.normal_channels != 3) {
                Image n(c.W, c.H, c.normal_channels);
                for (size_t t = 0; t < n.texel_count(); ++t)
                    for (int k = 0; k < c.normal_channels; ++k)
                        n.pixels[t * size_t(c.normal_channels) + size_t(k)] = k < 3 ? nm.pixels[t * 3 + size_t(k)] : 0.25f;
                nm = n;
            }
            Image rough = c.rough_channels ? random_orm(c.rough_w, c.rough_h, 22) : Image{};
            if (c.rough_channels == 1) {
                Image r(c.rough_w, c.rough_h, 1);
                for (size_t t = 0; t < r.texel_count(); ++t) r.pixels[t] = rough.pixels[t * 3 + 1];
                rough = r;
            }
            const IntegerMap ni = as_integers(nm, bits);
            const IntegerMap ri = c.rough_channels ? as_integers(rough, bits) : IntegerMap{};
            for (int threads : {1, 2}) {
                TextureBakeSettings s;
                s.threads = threads;
                auto floats = bake_texture(ni.decoded, c.rough_channels ? &ri.decoded : nullptr, c.channel, 0.4f, s);
                ASSERT_TRUE(floats.ok()) << floats.error().message;
                std::mutex m;
                bool equal = true;
                auto same = [](const float* block, const MipChain& chain, const TextureBakeRows& r) {
                    if (!block) return chain.levels.empty();
                    const Image& level = chain.levels[size_t(r.level)];
                    const size_t row_floats = size_t(r.width) * size_t(level.channels);
                    for (int k = 0; k < r.rows; ++k)
                        if (std::memcmp(block + size_t(k) * row_floats, level.texel(r.x0, r.y0 + k), row_floats * sizeof(float)))
                            return false;
                    return true;
                };
                auto bytes = bake_texture_rows(ni.map, c.rough_channels ? &ri.map : nullptr, c.channel, 0.4f, s,
                                               [&](const TextureBakeRows& r) {
                                                   std::lock_guard<std::mutex> lock(m);
                                                   equal = equal && same(r.roughness, floats->roughness, r) &&
                                                           same(r.kernel, floats->kernel, r) &&
                                                           same(r.lean, floats->lean, r) && same(r.normal, floats->normal, r);
                                               });
                ASSERT_TRUE(bytes.ok()) << bytes.error().message;
                EXPECT_TRUE(equal);
                EXPECT_EQ(bytes->max_roughness_change, floats->max_roughness_change);
                EXPECT_EQ(bytes->notes.z_reconstructed, floats->notes.z_reconstructed);
                EXPECT_EQ(bytes->notes.looks_srgb, floats->notes.looks_srgb);
                EXPECT_EQ(bytes->notes.roughness_resampled, floats->notes.roughness_resampled);
                EXPECT_EQ(bytes->notes.warnings, floats->notes.warnings);
            }
        }
        // The notes read from the codes: a constant full-scale blue channel, and sRGB-looking values.
        Image flat(8, 8, 3);
        for (size_t t = 0; t < flat.texel_count(); ++t)
            flat.pixels[t * 3] = 0.5f + 0.3f * float(t % 3) / 3.0f, flat.pixels[t * 3 + 1] = 0.5f, flat.pixels[t * 3 + 2] = 1.0f;
        const IntegerMap fi = as_integers(flat, bits);
        auto rows = bake_texture_rows(fi.map, nullptr, 0, 0.5f, {}, [](const TextureBakeRows&) {});
        ASSERT_TRUE(rows.ok());
        EXPECT_TRUE(rows->notes.z_reconstructed);
        Image srgb = random_normal_map(32, 32, 13, 0.2);  // pushed through the sRGB encode curve
        for (float& v : srgb.pixels) v = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1 / 2.4f) - 0.055f;
        const IntegerMap si = as_integers(srgb, bits);
        auto warned = bake_texture_rows(si.map, nullptr, 0, 0.5f, {}, [](const TextureBakeRows&) {});
        ASSERT_TRUE(warned.ok());
        EXPECT_TRUE(warned->notes.looks_srgb);
    }
}

// Input rows reported as no longer read can be overwritten (a caller releases them) without changing any
// output: here they are poisoned as soon as they are reported.
TEST(TextureBake, InputRowsReportedDoneAreNotReadAgain) {
    for (const auto& [W, H, bits] : {std::tuple{256, 512, 8}, std::tuple{512, 96, 8}, std::tuple{256, 512, 16}, std::tuple{512, 96, 16}}) {
        SCOPED_TRACE(std::to_string(W) + "x" + std::to_string(H) + " " + std::to_string(bits) + "-bit");
        const int depth = bits;  // a lambda cannot capture a structured binding before C++20 in every compiler
        IntegerMap ni = as_integers(random_normal_map(W, H, 41, 0.3), bits);
        IntegerMap ri = as_integers(random_orm(W, H, 42), bits);
        TextureBakeSettings s;
        s.threads = 2;
        auto reference = bake_texture(ni.decoded, &ri.decoded, 1, 0, s);
        ASSERT_TRUE(reference.ok());
        std::mutex m;
        bool equal = true;
        int released = 0;
        auto rows = bake_texture_rows(
            ni.map, &ri.map, 1, 0, s,
            [&](const TextureBakeRows& b) {
                std::lock_guard<std::mutex> lock(m);
                const Image& level = reference->lean.levels[size_t(b.level)];
                for (int k = 0; k < b.rows; ++k)
                    equal = equal && !std::memcmp(b.lean + size_t(k) * b.width * 5, level.texel(b.x0, b.y0 + k),
                                                  size_t(b.width) * 5 * sizeof(float));
            },
            [](int, int) {},
            [&](int upto) {
                EXPECT_GE(upto, released);
                for (IntegerMap* b : {&ni, &ri}) {
                    if (depth == 8) std::fill_n(b->bytes.begin(), size_t(upto) * b->map.row_stride, uint8_t(0x5A));
                    else std::fill_n(b->words.begin(), size_t(upto) * b->map.row_stride, uint16_t(0x5A5A));
                }
                released = upto;
            });
        ASSERT_TRUE(rows.ok());
        EXPECT_TRUE(equal);
        EXPECT_EQ(released, H);
        EXPECT_EQ(rows->max_roughness_change, reference->max_roughness_change);
    }
}

// With a rows-done callback the rows reported done for a level have all reached the sink, the reports grow
// to the level's height, and the values are those of the bake without it.
TEST(TextureBake, RowsDoneFollowTheSinkTopDown) {
    for (const auto& [W, H] : {std::pair{512, 512}, std::pair{96, 1040}, std::pair{37, 23}}) {
        SCOPED_TRACE(std::to_string(W) + "x" + std::to_string(H));
        const Image nm = random_normal_map(W, H, 31, 0.3);
        const Image orm = random_orm(W, H, 32);
        TextureBakeSettings s;
        s.threads = 2;
        auto chains = bake_texture(nm, &orm, 1, 0, s);
        ASSERT_TRUE(chains.ok());
        const int levels = mip_level_count(W, H);
        std::mutex m;
        auto sunk = std::vector<std::vector<char>>(size_t(levels));
        for (int L = 0; L < levels; ++L) sunk[size_t(L)].assign(chains->roughness.levels[size_t(L)].texel_count(), 0);
        std::vector<int> done(size_t(levels), 0);
        bool in_order = true, complete = true, equal = true;
        int reports = 0;
        const TextureMap n = TextureMap::of(nm), r = TextureMap::of(orm);
        auto rows = bake_texture_rows(
            n, &r, 1, 0, s,
            [&](const TextureBakeRows& b) {
                std::lock_guard<std::mutex> lock(m);
                const Image& level = chains->roughness.levels[size_t(b.level)];
                for (int y = b.y0; y < b.y0 + b.rows; ++y)
                    for (int x = b.x0; x < b.x0 + b.width; ++x) sunk[size_t(b.level)][size_t(y) * level.width + x] = 1;
                for (int k = 0; k < b.rows; ++k)
                    equal = equal && !std::memcmp(b.roughness + size_t(k) * b.width * 3, level.texel(b.x0, b.y0 + k),
                                                  size_t(b.width) * 3 * sizeof(float));
            },
            [&](int level, int upto) {
                ++reports;
                in_order = in_order && upto >= done[size_t(level)];
                done[size_t(level)] = upto;
                const Image& l = chains->roughness.levels[size_t(level)];
                for (size_t i = 0; i < size_t(upto) * size_t(l.width); ++i) complete = complete && sunk[size_t(level)][i];
            });
        ASSERT_TRUE(rows.ok());
        EXPECT_TRUE(in_order);
        EXPECT_TRUE(complete) << "a row was reported done before it reached the sink";
        EXPECT_TRUE(equal);
        for (int L = 0; L < levels; ++L) EXPECT_EQ(done[size_t(L)], std::max(1, H >> L)) << "level " << L;
        if (H >= 512) EXPECT_GT(reports, levels) << "the largest levels come in bands";
        EXPECT_EQ(rows->max_roughness_change, chains->max_roughness_change);
    }
}

TEST(TextureBake, SlopeSpaceLeanFoldsBaseRoughness) {
    // Flat normals: s = 0, so the second moments are the base lobe's slope variance alpha^2 / 2.
    Image nm(8, 8, 3);
    for (size_t i = 0; i < nm.texel_count(); ++i) nm.pixels[3 * i] = 0.5f, nm.pixels[3 * i + 1] = 0.5f, nm.pixels[3 * i + 2] = 1.0f;
    TextureBakeSettings s;
    s.lean_space = LeanSpace::Slope;
    s.reconstruct_z = ReconstructZ::Never;
    auto res = bake_texture(nm, nullptr, 0, 0.5f, s);
    ASSERT_TRUE(res.ok());
    const float* l = res->lean.levels[2].texel(0, 0);
    EXPECT_NEAR(l[0], 0.0, 1e-9);
    EXPECT_NEAR(l[2], std::pow(0.5, 4) / 2, 1e-7);
    EXPECT_NEAR(l[3], std::pow(0.5, 4) / 2, 1e-7);
    EXPECT_NEAR(l[4], 0.0, 1e-9);
}

TEST(TextureBake, EdgeRoughnessZeroAndOne) {
    const Image nm = random_normal_map(16, 16, 11, 0.3);
    TextureBakeSettings s;
    s.anisotropic = false;  // the kernel output as t
    auto one = bake_texture(nm, nullptr, 0, 1.0f, s);
    ASSERT_TRUE(one.ok());
    for (const Image& L : one->roughness.levels)
        for (float v : L.pixels) EXPECT_EQ(v, 1.0f);  // a = 1 stays 1
    EXPECT_EQ(one->max_roughness_change, 0.0);
    auto zero = bake_texture(nm, nullptr, 0, 0.0f, s);
    ASSERT_TRUE(zero.ok());
    EXPECT_EQ(zero->roughness.levels[0].pixels[0], 0.0f);  // mip 0: Sigma = 0
    const double t = zero->kernel.levels[4].pixels[0];
    EXPECT_NEAR(zero->roughness.levels[4].pixels[0], std::pow(t / (1 + t), 0.25), 1e-6);  // a = t / (1 + t)
}

TEST(TextureBake, OneByOneMap) {
    Image nm(1, 1, 3);
    nm.pixels = {0.7f, 0.4f, 0.9f};
    auto res = bake_texture(nm, nullptr, 0, 0.3f, TextureBakeSettings{});
    ASSERT_TRUE(res.ok());
    ASSERT_EQ(res->roughness.levels.size(), 1u);
    EXPECT_NEAR(res->roughness.levels[0].pixels[0], 0.3f, 1e-7);
}

TEST(TextureBake, ConstantBlueIsReconstructedAndReported) {
    Image nm = random_normal_map(16, 8, 12, 0.3);
    for (size_t i = 0; i < nm.texel_count(); ++i) nm.pixels[3 * i + 2] = 1.0f;
    auto res = bake_texture(nm, nullptr, 0, 0.5f, TextureBakeSettings{});
    ASSERT_TRUE(res.ok());
    EXPECT_TRUE(res->notes.z_reconstructed);
    EXPECT_EQ(res->notes.z_reason, "constant full-scale blue channel");
    TextureBakeSettings never;
    never.reconstruct_z = ReconstructZ::Never;
    auto kept = bake_texture(nm, nullptr, 0, 0.5f, never);
    ASSERT_TRUE(kept.ok());
    EXPECT_FALSE(kept->notes.z_reconstructed);
}

TEST(TextureBake, SrgbLookingMapIsWarnedAbout) {
    Image linear = random_normal_map(32, 32, 13, 0.2);
    auto plain = bake_texture(linear, nullptr, 0, 0.5f, TextureBakeSettings{});
    ASSERT_TRUE(plain.ok());
    EXPECT_FALSE(plain->notes.looks_srgb);
    Image srgb = linear;  // the same data pushed through the sRGB encode curve
    for (float& v : srgb.pixels) v = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1 / 2.4f) - 0.055f;
    auto warned = bake_texture(srgb, nullptr, 0, 0.5f, TextureBakeSettings{});
    ASSERT_TRUE(warned.ok());
    EXPECT_TRUE(warned->notes.looks_srgb);
    EXPECT_FALSE(warned->notes.warnings.empty());
}

// NaN and infinity are caught wherever the decode meets them (vector body and scalar tail, normal and ORM
// channels, a roughness map of another size), each error naming the texel; a channel the bake never reads
// (the alpha of an RGBA normal map, B of a roughness map read from R) does not stop it.
TEST(TextureBake, NonFiniteValuesThatAreReadAreErrors) {
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    const Image nm = random_normal_map(11, 6, 31, 0.2);
    const Image orm = random_orm(11, 6, 32);
    struct Case { bool in_normal; int x, y, channel; float value; };
    // 11 x 6 goes through the planes; 12 x 8 (every level tiles the one below, so no level reads the base
    // again) through the register pass for levels 0-1 (x < 8) and the planes for the last texels of a row.
    for (const bool even : {false, true}) {
        const Image nm_s = even ? random_normal_map(12, 8, 33, 0.2) : nm;
        const Image orm_s = even ? random_orm(12, 8, 34) : orm;
        for (const Case& c : {Case{true, 1, 2, 0, nan}, Case{true, 9, 4, 2, -inf}, Case{true, 10, 5, 1, inf},
                              Case{false, 2, 1, 1, nan}, Case{false, 10, 0, 0, inf}, Case{false, 5, 5, 2, nan},
                              Case{true, 6, 3, 0, nan}, Case{false, 7, 4, 1, -inf}}) {
            SCOPED_TRACE(std::to_string(nm_s.width) + "x" + std::to_string(nm_s.height) + ", " +
                         (c.in_normal ? "normal" : "orm") + " texel " + std::to_string(c.x) + "," +
                         std::to_string(c.y) + " channel " + std::to_string(c.channel));
            Image n = nm_s, r = orm_s;
            (c.in_normal ? n : r).texel(c.x, c.y)[c.channel] = c.value;
            auto res = bake_texture(n, &r, 1, 0.0f, TextureBakeSettings{});
            ASSERT_FALSE(res.ok());
            const std::string where = std::string(c.in_normal ? "normal map" : "roughness map") +
                                      ": NaN or infinite value at texel (" + std::to_string(c.x) + ", " +
                                      std::to_string(c.y) + ")";
            EXPECT_EQ(res.error().message, where);
        }
    }
    Image small(3, 2, 1);
    small.pixels.assign(6, 0.5f);
    small.texel(2, 1)[0] = nan;
    auto resampled = bake_texture(nm, &small, 0, 0.0f, TextureBakeSettings{});
    ASSERT_FALSE(resampled.ok());
    EXPECT_EQ(resampled.error().message, "roughness map: NaN or infinite value at texel (2, 1)");

    Image rgba(8, 4, 4);
    for (size_t i = 0; i < rgba.texel_count(); ++i) {
        float* t = rgba.pixels.data() + 4 * i;
        t[0] = 0.5f, t[1] = 0.5f, t[2] = 1.0f, t[3] = nan;  // alpha unused
    }
    EXPECT_TRUE(bake_texture(rgba, nullptr, 0, 0.5f, TextureBakeSettings{}).ok());
    Image r_unused = orm;
    r_unused.texel(3, 3)[2] = nan;  // roughness from R: not an ORM map, so B is not read
    EXPECT_TRUE(bake_texture(nm, &r_unused, 0, 0.0f, TextureBakeSettings{}).ok());
}

TEST(TextureBake, BadInputsAreErrors) {
    Image one_channel(4, 4, 1);
    auto e1 = bake_texture(one_channel, nullptr, 0, 0.5f, TextureBakeSettings{});
    ASSERT_FALSE(e1.ok());
    EXPECT_NE(e1.error().message.find("normal map: has 1 channel"), std::string::npos);

    auto e2 = bake_texture(Image{}, nullptr, 0, 0.5f, TextureBakeSettings{});
    ASSERT_FALSE(e2.ok());
    EXPECT_NE(e2.error().message.find("empty"), std::string::npos);

    Image nan_map = random_normal_map(4, 4, 14, 0.1);
    nan_map.texel(2, 3)[1] = std::numeric_limits<float>::quiet_NaN();
    auto e3 = bake_texture(nan_map, nullptr, 0, 0.5f, TextureBakeSettings{});
    ASSERT_FALSE(e3.ok());
    EXPECT_NE(e3.error().message.find("texel (2, 3)"), std::string::npos);

    const Image nm = random_normal_map(4, 4, 15, 0.1);
    Image rough(4, 4, 1);
    auto e4 = bake_texture(nm, &rough, 2, 0.5f, TextureBakeSettings{});
    ASSERT_FALSE(e4.ok());
    EXPECT_NE(e4.error().message.find("roughness map: channel 2"), std::string::npos);
    rough.pixels[5] = std::numeric_limits<float>::infinity();
    EXPECT_FALSE(bake_texture(nm, &rough, 0, 0.5f, TextureBakeSettings{}).ok());
    EXPECT_FALSE(bake_texture(nm, nullptr, 0, 1.5f, TextureBakeSettings{}).ok());

    Image two(4, 4, 2);
    TextureBakeSettings never;
    never.reconstruct_z = ReconstructZ::Never;
    EXPECT_FALSE(bake_texture(two, nullptr, 0, 0.5f, never).ok());
}

TEST(TextureBake, DegenerateTexelsDecodeToPlusZ) {
    Image nm(2, 2, 3);
    for (float& v : nm.pixels) v = 0.5f;  // (0, 0, 0) after decoding
    auto res = bake_texture(nm, nullptr, 0, 0.5f, TextureBakeSettings{});
    ASSERT_TRUE(res.ok());
    EXPECT_EQ(res->notes.degenerate_normals, 4);
    const float* n = res->normal.levels[1].texel(0, 0);
    EXPECT_FLOAT_EQ(n[2], 1.0f);
    EXPECT_EQ(res->kernel.levels[1].pixels[0], 0.0f);
}

TEST(TextureBake, MipLevelCount) {
    EXPECT_EQ(mip_level_count(1, 1), 1);
    EXPECT_EQ(mip_level_count(4096, 4096), 13);
    EXPECT_EQ(mip_level_count(37, 23), 6);
    EXPECT_EQ(mip_level_count(64, 8), 7);
}

}  // namespace
}  // namespace specbake
