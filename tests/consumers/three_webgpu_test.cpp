// The WGSL include in three.js r187's WebGPURenderer (headless Chromium, WebGPU on SwiftShader), wired as
// docs/shader-include.md#webgpu-wgsl shows: `wgsl(source)` as an include of TSL `wgslFn` functions. The page
// is browser_three_webgpu.mjs.
// - The renderer runs on WebGPU (not its WebGL 2 fallback) and logs no error or warning.
// - A full-screen quad evaluates specaa_widened_matrix and specaa_default_D (no baked data) at each pixel's
//   uv; both match the bake's projected-space filter and convolved NDF (4e-5 and 1e-3 relative, the
//   tolerances of the grid in tests/gl/grid_cases.h).
// - A MeshStandardNodeMaterial sphere with roughnessNode = specaa_filtered_roughness of the vertex normal
//   draws lit pixels, and that roughness read back matches the closed form of the per-pixel kernel on an
//   orthographic sphere, t = sigma^2 (|dn/dx|^2 + |dn/dy|^2), |dn/dx|^2 = (p / R)^2 (1 + x^2 / z^2) for pixel
//   width p (TK21 Eq. 14, clamped to kappa), within 3% of r on the pixels whose 2x2 quad lies inside
//   0.8 R (the quad's finite differences of a 64 x 32 tessellation against the smooth sphere); with a
//   one-texel kernel texture passed from TSL's texture()/sampler() nodes, specaa_filtered_roughness_kernel
//   matches the same closed form plus the texel's gated kernel, within the same 3%.
#include "consumer_harness.h"

#include "bake/constants.h"
#include "bake/ggx.h"
#include "bake/roughness_space.h"

#include <cmath>

namespace specbake::consumers {
namespace {

class ThreeWebGpu : public ConsumerTest {};

TEST_F(ThreeWebGpu, WgslIncludeInWgslFnMatchesTheCoreAndShadesASphere) {
    if (auto why = missing_node_packages({"three"}); !why.empty()) GTEST_SKIP() << why;
    const int size = 32;
    const double roughness = 0.2, radius = 0.9;
    const int texel[4] = {40, 20, 10, 128};  // the baked kernel: Sigma (xx, yy, xy) and g as RGBA8 k / 255
    const nlohmann::json job = {{"page", "browser_three_webgpu.html"}, {"webgpu", true}, {"size", size},
                                {"roughness", roughness}, {"radius", radius},
                                {"texel", {texel[0], texel[1], texel[2], texel[3]}}};
    nlohmann::json result;
    if (!run_browser(job, root_, &result)) return;
    std::printf("three.js backend: %s\n", result.value("backend", "").c_str());
    ASSERT_EQ(result.value("backend", ""), "WebGPU");
    EXPECT_TRUE(result["errors"].empty()) << result["errors"].dump(1);

    // The quad: (u, v, A.xx, D) per pixel.
    const auto& grid = result["grid"];
    ASSERT_EQ(grid.size(), size_t(4 * size * size));
    const double hx = 0.3, hy = 0.2, hz = double(0.932737905308881f);
    int checked = 0;
    double worst_a = 0, worst_d = 0;
    for (int i = 0; i < size * size; ++i) {
        const double u = grid[4 * i].get<double>(), v = grid[4 * i + 1].get<double>();
        const double r = 0.1 + 0.8 * u, a = r * r * r * r, t = 2.0 * v * v;
        const Sym2<double> K{t, 0.25 * t, 0.5 * t};
        const Sym2<double> A = projected_to_slope_roughness(slope_to_projected_roughness(diag(a, a)) + K);
        const double gpu_a = grid[4 * i + 2].get<double>(), gpu_d = grid[4 * i + 3].get<double>();
        const double d = convolved_ndf(Vec3<double>{double(float(hx)), double(float(hy)), hz}, A, a);
        const double cond = std::max(1.0, A.xx * A.yy / std::max(det(A), a * a));
        worst_a = std::max(worst_a, std::abs(gpu_a - A.xx) / A.xx);
        worst_d = std::max(worst_d, std::abs(gpu_d - d) / (cond * d));
        EXPECT_LE(std::abs(gpu_a - A.xx), 4e-5 * A.xx) << "A.xx at u " << u << ", v " << v;
        EXPECT_LE(std::abs(gpu_d - d), 1e-3 * cond * d) << "D at u " << u << ", v " << v;
        ++checked;
    }
    std::printf("quad: %d pixels, worst relative error A.xx %.2e, D %.2e\n", checked, worst_a, worst_d);

    // The sphere: lit pixels, and the filtered roughness against the closed form.
    const auto& shaded = result["shaded"];
    const auto& rough = result["roughness"];
    const auto& kernel_rough = result["kernelRoughness"];
    ASSERT_EQ(shaded.size(), size_t(4 * size * size));
    ASSERT_EQ(rough.size(), size_t(4 * size * size));
    ASSERT_EQ(kernel_rough.size(), size_t(4 * size * size));
    const double p = 2.0 / size, a = std::pow(roughness, 4.0);
    // The texel's isotropic kernel: half the trace of K = 2 Sigma sqrt(g), gated by
    // f = saturate(lambda_max(K) / (0.5 a)) (f = 1 here: the kernel is far wider than a).
    const double root_g = std::sqrt(texel[3] / 255.0);
    const double kxx = 2.0 * root_g * texel[0] / 255.0, kyy = 2.0 * root_g * texel[1] / 255.0,
                 kxy = 2.0 * root_g * texel[2] / 255.0;
    const double kmax = 0.5 * (kxx + kyy) + std::hypot(0.5 * (kxx - kyy), kxy);
    const double gate = std::min(1.0, kmax / (0.5 * a));
    const double baked_t = 0.5 * (kxx + kyy) * gate * gate;
    int lit = 0, compared = 0;
    double worst = 0, worst_kernel = 0;
    for (int row = 0; row < size; ++row)
        for (int col = 0; col < size; ++col) {
            const int i = row * size + col;
            if (rough[4 * i + 3].get<double>() == 0.0) continue;  // background
            const double value = shaded[4 * i].get<double>();
            EXPECT_TRUE(std::isfinite(value));
            lit += value > 0.01;
            // Pixel centre in view units; the read-back's row order does not matter (the sphere is symmetric).
            const double x = -1.0 + (col + 0.5) * p, y = -1.0 + (row + 0.5) * p;
            const double quad_x = std::abs(x) + p, quad_y = std::abs(y) + p;  // farthest pixel of its quad
            if (quad_x * quad_x + quad_y * quad_y > 0.64 * radius * radius) continue;
            const double z2 = radius * radius - x * x - y * y;
            const double dn2 = (p / radius) * (p / radius) * ((1.0 + x * x / z2) + (1.0 + y * y / z2));
            const double t = std::min(kDefaultSigma2 * dn2, kDefaultKappa);
            const double filtered = std::pow((a + t * (1.0 - a)) / (1.0 + t * (1.0 - a)), 0.25);
            const double gpu = rough[4 * i].get<double>();
            worst = std::max(worst, std::abs(gpu - filtered) / filtered);
            EXPECT_LE(std::abs(gpu - filtered), 0.03 * filtered) << "pixel (" << col << ", " << row << ")";
            EXPECT_GE(gpu, roughness * (1.0 - 1e-5)) << "pixel (" << col << ", " << row << ")";
            const double tk = t + baked_t;
            const double with_kernel = std::pow((a + tk * (1.0 - a)) / (1.0 + tk * (1.0 - a)), 0.25);
            const double gpu_kernel = kernel_rough[4 * i].get<double>();
            worst_kernel = std::max(worst_kernel, std::abs(gpu_kernel - with_kernel) / with_kernel);
            EXPECT_LE(std::abs(gpu_kernel - with_kernel), 0.03 * with_kernel)
                << "with the kernel texture, pixel (" << col << ", " << row << ")";
            ++compared;
        }
    std::printf("sphere: %d lit pixels; filtered roughness at %d inner pixels within %.2f%% of the closed form, "
                "with the kernel texture within %.2f%%\n",
                lit, compared, 100.0 * worst, 100.0 * worst_kernel);
    EXPECT_GT(lit, size * size / 4);
    EXPECT_GT(compared, 100);
}

}  // namespace
}  // namespace specbake::consumers
