// Nanoseconds per evaluation of every filtering method (float) from bake/methods.h, of the bare kernels
// of bake/kernels.h, and of GGX D and G2. Inputs cycle through 1024 random fragments so nothing folds.
#include "bake/ggx.h"
#include "bake/kernels.h"
#include "bake/methods.h"
#include "bake/peers.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace {

using namespace specbake;

constexpr size_t kInputs = 1024;

Vec3<float> random_unit(std::mt19937& rng, float min_z) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const float z = min_z + (1.0f - min_z) * u(rng), phi = 6.2831853f * u(rng), s = std::sqrt(1 - z * z);
    return {s * std::cos(phi), s * std::sin(phi), z};
}

Vec3<float> nudged(std::mt19937& rng, const Vec3<float>& v) {
    std::normal_distribution<float> g(0.0f, 0.02f);
    return normalize(Vec3<float>{v.x + g(rng), v.y + g(rng), v.z + g(rng)});
}

const std::vector<FilterInput<float>>& inputs() {
    static const std::vector<FilterInput<float>> data = [] {
        std::mt19937 rng(42);
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        std::vector<FilterInput<float>> v(kInputs);
        for (FilterInput<float>& in : v) {
            in.alpha = {0.01f + 0.5f * u(rng), 0.01f + 0.5f * u(rng)};
            in.h = random_unit(rng, 0.1f);
            in.h_dx = nudged(rng, in.h);
            in.h_dy = nudged(rng, in.h);
            in.n = random_unit(rng, -1.0f);
            in.n_dx = nudged(rng, in.n);
            in.n_dy = nudged(rng, in.n);
            in.pixel_size = 0.01f * u(rng);
            in.curvature = 10.0f * u(rng);
        }
        return v;
    }();
    return data;
}

void bm_method(benchmark::State& state, const FilterMethod* method) {
    const auto& in = inputs();
    size_t i = 0;
    for (auto _ : state) {
        benchmark::DoNotOptimize(evaluate(*method, in[i]));
        i = (i + 1) % kInputs;
    }
}

// The bare projected-space kernels on precomputed derivatives (what a shader executes after ddx/ddy).
template <class F>
void bm_kernel(benchmark::State& state, F kernel) {
    const auto& in = inputs();
    size_t i = 0;
    for (auto _ : state) {
        const FilterInput<float>& f = in[i];
        const Vec2<float> r2{f.alpha.x * f.alpha.x, f.alpha.y * f.alpha.y};
        const Vec2<float> du{f.h_dx.x - f.h.x, f.h_dx.y - f.h.y}, dv{f.h_dy.x - f.h.x, f.h_dy.y - f.h.y};
        benchmark::DoNotOptimize(kernel(r2, du, dv, f.sigma2, f.kappa));
        i = (i + 1) % kInputs;
    }
}

void bm_ggx_d(benchmark::State& state) {
    const auto& in = inputs();
    size_t i = 0;
    for (auto _ : state) {
        const FilterInput<float>& f = in[i];
        const Sym2<float> A{f.alpha.x * f.alpha.x, 0.1f * f.alpha.x * f.alpha.y, f.alpha.y * f.alpha.y};
        benchmark::DoNotOptimize(ggx_ndf(f.h, A, f.alpha.x * f.alpha.x * f.alpha.y * f.alpha.y));
        i = (i + 1) % kInputs;
    }
}

void bm_ggx_g2(benchmark::State& state) {
    const auto& in = inputs();
    size_t i = 0;
    for (auto _ : state) {
        const FilterInput<float>& f = in[i];
        const Sym2<float> A{f.alpha.x * f.alpha.x, 0.1f * f.alpha.x * f.alpha.y, f.alpha.y * f.alpha.y};
        benchmark::DoNotOptimize(ggx_g2(f.n, f.h_dx, f.h, A));
        i = (i + 1) % kInputs;
    }
}

void bm_k16_rect(benchmark::State& state) {
    const auto& in = inputs();
    size_t i = 0;
    for (auto _ : state) {
        const FilterInput<float>& f = in[i];
        const Vec2<float> hpp{f.h.x / f.h.z, f.h.y / f.h.z};
        const Vec2<float> fp = k16_ggx_rect_footprint(Vec2<float>{0.01f, 0.02f}, Vec2<float>{0.005f, 0.0f}, f.alpha, 1.0f);
        benchmark::DoNotOptimize(k16_ggx_rect_ndf(hpp, f.h, f.alpha, fp));
        i = (i + 1) % kInputs;
    }
}

const bool registered = [] {
    for (const FilterMethod& m : filter_methods())
        benchmark::RegisterBenchmark(("method/" + std::string(m.name)).c_str(), bm_method, &m);
    benchmark::RegisterBenchmark("kernel/non_axis_aligned", [](benchmark::State& s) {
        bm_kernel(s, [](auto r2, auto du, auto dv, float sigma2, float) {
            return filter_non_axis_aligned(r2, du, dv, sigma2);
        });
    });
    benchmark::RegisterBenchmark("kernel/axis_aligned", [](benchmark::State& s) {
        bm_kernel(s, [](auto r2, auto du, auto dv, float sigma2, float kappa) {
            return filter_axis_aligned(r2, du, dv, sigma2, kappa);
        });
    });
    benchmark::RegisterBenchmark("kernel/projected_full", [](benchmark::State& s) {
        bm_kernel(s, [](auto r2, auto du, auto dv, float sigma2, float) { return filter_projected(r2, du, dv, sigma2); });
    });
    benchmark::RegisterBenchmark("ggx/D", bm_ggx_d);
    benchmark::RegisterBenchmark("ggx/G2", bm_ggx_g2);
    benchmark::RegisterBenchmark("peer/k16_ggx_rect_ndf", bm_k16_rect);
    return true;
}();

}  // namespace

BENCHMARK_MAIN();
