// Stability grid (issue 2): every method over > 10^5 combinations of roughness, half-vector elevation and
// derivative magnitude returns finite, symmetric, positive semi-definite matrices that never reduce the
// roughness; non-finite inputs follow the documented policy of bake/methods.h.
#include "bake/methods.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

namespace specbake {
namespace {

// Smallest eigenvalue of a symmetric 2x2 matrix, scaled to its largest entry to avoid overflow.
double min_eigenvalue_scaled(double xx, double xy, double yy, double& scale) {
    scale = std::max({std::abs(xx), std::abs(xy), std::abs(yy)});
    if (scale == 0.0) return 0.0;
    xx /= scale, xy /= scale, yy /= scale;
    return 0.5 * (xx + yy - std::sqrt((xx - yy) * (xx - yy) + 4 * xy * xy));
}

struct GridStats {
    long combinations = 0;
    long failures = 0;
};

template <class T>
void check_grid(GridStats& stats) {
    const std::vector<double> alphas{0, 1e-7, 1e-4, 0.01, 0.1, 0.5, 0.999, 1};
    const std::vector<double> elevations{1, 0.99, 0.9, 0.5, 0.1, 1e-2, 1e-4, 1e-7, 1e-20, 0};
    const std::vector<double> azimuths{0.0, 0.8, 2.5};
    // Derivatives (neighbour minus fragment, 3D): zero, tiny, moderate, large, huge and mixed magnitudes.
    const std::vector<Vec3<double>> deltas{{0, 0, 0},         {1e-9, 0, 0},     {1e-3, -2e-3, 1e-3},
                                           {0.1, 0.05, -0.1}, {0.5, -0.7, 0.3}, {1e6, 3e5, -1e6},
                                           {1e20, -1e19, 1e20}, {1e-9, 1e6, 0}};
    const T tol = std::is_same_v<T, float> ? T(1e-4) : T(1e-9);
    for (double ax : alphas)
        for (double ay : alphas)
            for (double hz : elevations)
                for (double phi : azimuths) {
                    const double s = std::sqrt(1 - hz * hz);
                    const Vec3<T> h{T(s * std::cos(phi)), T(s * std::sin(phi)), T(hz)};
                    for (const auto& du : deltas)
                        for (const auto& dv : deltas) {
                            FilterInput<T> in;
                            in.alpha = {T(ax), T(ay)};
                            in.h = h;
                            in.h_dx = {T(h.x + du.x), T(h.y + du.y), T(h.z + du.z)};
                            in.h_dy = {T(h.x + dv.x), T(h.y + dv.y), T(h.z + dv.z)};
                            in.n = h;
                            in.n_dx = in.h_dx;
                            in.n_dy = in.h_dy;
                            in.pixel_size = T(length(du));
                            in.curvature = T(length(dv));
                            ++stats.combinations;
                            const double a_xx = double(T(ax) * T(ax)), a_yy = double(T(ay) * T(ay));
                            for (const FilterMethod& m : filter_methods()) {
                                const Sym2<T> r = evaluate(m, in);
                                const double xx = r.xx, xy = r.xy, yy = r.yy;
                                double scale = 0, escale = 0;
                                const double lmin = min_eigenvalue_scaled(xx, xy, yy, scale);
                                const double emin = min_eigenvalue_scaled(xx - a_xx, xy, yy - a_yy, escale);
                                const double det_f = xx * yy - xy * xy, det_a = a_xx * a_yy;
                                const bool ok = std::isfinite(xx) && std::isfinite(xy) && std::isfinite(yy) &&
                                                lmin >= -double(tol) &&
                                                emin * escale >= -double(tol) * std::max(scale, 1e-30) &&
                                                det_f >= det_a * (1 - double(tol)) - double(tol) * scale * scale;
                                if (!ok && ++stats.failures <= 10) {
                                    ADD_FAILURE() << m.name << (std::is_same_v<T, float> ? " float" : " double")
                                                  << " alpha " << ax << "," << ay << " h_z " << hz << " phi " << phi
                                                  << " du " << du.x << "," << du.y << "," << du.z << " dv " << dv.x
                                                  << "," << dv.y << "," << dv.z << " -> [" << xx << " " << xy << " "
                                                  << yy << "]";
                                }
                            }
                        }
                }
}

TEST(Stability, GridFloat) {
    GridStats stats;
    check_grid<float>(stats);
    EXPECT_GE(stats.combinations, 100000);
    EXPECT_EQ(stats.failures, 0);
}

TEST(Stability, GridDouble) {
    GridStats stats;
    check_grid<double>(stats);
    EXPECT_GE(stats.combinations, 100000);
    EXPECT_EQ(stats.failures, 0);
}

template <class T>
FilterInput<T> typical_input() {
    FilterInput<T> in;
    in.alpha = {T(0.2), T(0.05)};
    in.h = normalize(Vec3<T>{T(0.6), T(0.1), T(0.8)});
    in.h_dx = normalize(Vec3<T>{T(0.65), T(0.1), T(0.78)});
    in.h_dy = normalize(Vec3<T>{T(0.6), T(0.14), T(0.8)});
    in.n = normalize(Vec3<T>{T(0.1), T(0.2), T(1)});
    in.n_dx = normalize(Vec3<T>{T(0.15), T(0.2), T(1)});
    in.n_dy = normalize(Vec3<T>{T(0.1), T(0.3), T(1)});
    in.pixel_size = T(0.01);
    in.curvature = T(5);
    return in;
}

template <class T>
void expect_same(const Sym2<T>& a, const Sym2<T>& b, const std::string& what) {
    EXPECT_EQ(a.xx, b.xx) << what;
    EXPECT_EQ(a.xy, b.xy) << what;
    EXPECT_EQ(a.yy, b.yy) << what;
}

template <class T>
void check_non_finite_policy() {
    const T nan = std::numeric_limits<T>::quiet_NaN(), inf = std::numeric_limits<T>::infinity();
    for (const FilterMethod& m : filter_methods()) {
        const FilterInput<T> base = typical_input<T>();
        const Sym2<T> unfiltered = diag(base.alpha.x * base.alpha.x, base.alpha.y * base.alpha.y);
        // Kernel inputs: any non-finite value gives a zero kernel, i.e. the unfiltered A.
        T FilterInput<T>::*scalars[] = {&FilterInput<T>::sigma2, &FilterInput<T>::pixel_size,
                                        &FilterInput<T>::curvature};
        Vec3<T> FilterInput<T>::*vectors[] = {&FilterInput<T>::h,  &FilterInput<T>::h_dx, &FilterInput<T>::h_dy,
                                              &FilterInput<T>::n,  &FilterInput<T>::n_dx, &FilterInput<T>::n_dy};
        for (T bad : {nan, inf, -inf}) {
            for (auto field : scalars) {
                FilterInput<T> in = base;
                in.*field = bad;
                expect_same(evaluate(m, in), unfiltered, std::string(m.name) + " scalar");
            }
            for (auto field : vectors) {
                for (int c = 0; c < 3; ++c) {
                    FilterInput<T> in = base;
                    T* comps[] = {&(in.*field).x, &(in.*field).y, &(in.*field).z};
                    *comps[c] = bad;
                    expect_same(evaluate(m, in), unfiltered, std::string(m.name) + " vector");
                }
            }
        }
        // kappa: NaN or negative disables the kernel, +inf disables only the clamp.
        for (T bad : {nan, -inf, T(-1)}) {
            FilterInput<T> in = base;
            in.kappa = bad;
            expect_same(evaluate(m, in), unfiltered, std::string(m.name) + " kappa");
        }
        {
            FilterInput<T> in = base;
            in.kappa = inf;
            const Sym2<T> r = evaluate(m, in);
            EXPECT_TRUE(std::isfinite(r.xx) && std::isfinite(r.xy) && std::isfinite(r.yy)) << m.name;
        }
        // alpha: NaN counts as fully rough, +inf clamps to 1, -inf to 0.
        for (auto [bad, as] : {std::pair<T, T>{nan, T(1)}, {inf, T(1)}, {-inf, T(0)}}) {
            FilterInput<T> in = base, ref = base;
            in.alpha.x = bad;
            ref.alpha.x = as;
            expect_same(evaluate(m, in), evaluate(m, ref), std::string(m.name) + " alpha");
        }
    }
}

// Found by fuzz/fuzz_filter.cpp: a finite kernel whose trace overflows float (sigma2 near FLT_MAX / 4)
// made the full projected filter divide by an infinite denominator and return 0, below the material's
// roughness; the limit of an infinitely wide kernel is I.
TEST(Stability, ProjectedFilterWithOverflowingTraceIsFullyRough) {
    FilterInput<float> in;
    in.alpha = {0.1f, 0.0f};
    in.h = {1.0f, 0.5f, 0.0f};
    in.h_dx = in.h_dy = {0.0f, 1.0f, 0.0f};
    in.sigma2 = 8.457e37f;
    const Sym2<float> r = evaluate(*find_filter_method("projected"), in);
    EXPECT_EQ(r.xx, 1.0f);
    EXPECT_EQ(r.yy, 1.0f);
    EXPECT_EQ(r.xy, 0.0f);
}

TEST(Stability, NonFiniteInputsFloat) { check_non_finite_policy<float>(); }
TEST(Stability, NonFiniteInputsDouble) { check_non_finite_policy<double>(); }

}  // namespace
}  // namespace specbake
