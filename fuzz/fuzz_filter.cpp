// libFuzzer target: the filter core (bake/methods.h) on raw bit patterns, NaN, infinities and denormals
// included, in float and double. Every method must return what methods.h promises for any input: a
// finite, symmetric, positive semi-definite A_bar that does not reduce the material's roughness
// (A_bar - A positive semi-definite, det(A_bar) >= det(A)), A = diag(alpha^2) after the alpha policy.
#include "bake/methods.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <type_traits>

namespace {

using specbake::FilterInput;
using specbake::Sym2;
using specbake::Vec3;

// Smallest eigenvalue of [[xx, xy], [xy, yy]], computed on the matrix scaled to its largest entry so
// that neither huge nor subnormal entries overflow or underflow.
double min_eigenvalue(double xx, double xy, double yy) {
    const double scale = std::max({std::abs(xx), std::abs(xy), std::abs(yy)});
    if (scale == 0.0) return 0.0;
    xx /= scale, xy /= scale, yy /= scale;
    return scale * 0.5 * (xx + yy - std::sqrt((xx - yy) * (xx - yy) + 4 * xy * xy));
}

template <class T>
T take(const uint8_t*& p) {
    T v;
    std::memcpy(&v, p, sizeof(T));
    p += sizeof(T);
    return v;
}

template <class T>
Vec3<T> take3(const uint8_t*& p, bool unit) {
    Vec3<T> v{take<T>(p), take<T>(p), take<T>(p)};
    if (unit) {
        // The documented domain: unit vectors (a zero or non-finite one stays as it is).
        const T len = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
        if (std::isfinite(len) && len > T(0)) v = {v.x / len, v.y / len, v.z / len};
    }
    return v;
}

// Layout: flags, then alpha (2), h, h_dx, h_dy, n, n_dx, n_dy (3 each), sigma2, kappa, pixel_size,
// curvature. Flag bits: 1 = unit vectors, 2 = default sigma2 and kappa.
template <class T>
constexpr size_t kInputBytes = 1 + 24 * sizeof(T);

template <class T>
void run(const uint8_t* p) {
    const uint8_t flags = *p++;
    const bool unit = flags & 1;
    FilterInput<T> in;
    in.alpha = {take<T>(p), take<T>(p)};
    in.h = take3<T>(p, unit);
    in.h_dx = take3<T>(p, unit);
    in.h_dy = take3<T>(p, unit);
    in.n = take3<T>(p, unit);
    in.n_dx = take3<T>(p, unit);
    in.n_dy = take3<T>(p, unit);
    const T sigma2 = take<T>(p), kappa = take<T>(p);
    if (!(flags & 2)) in.sigma2 = sigma2, in.kappa = kappa;
    in.pixel_size = take<T>(p);
    in.curvature = take<T>(p);

    auto policy_alpha = [](T a) { return std::isnan(a) ? T(1) : std::min(std::max(a, T(0)), T(1)); };
    const T ax = policy_alpha(in.alpha.x), ay = policy_alpha(in.alpha.y);
    const double a_xx = double(ax * ax), a_yy = double(ay * ay);
    const double tol = std::is_same_v<T, float> ? 1e-4 : 1e-9;
    // Results in the subnormal range keep only a few digits: their rounding is absolute, about
    // denorm_min per operation, and that slack is allowed on top of the relative tolerance.
    const double slack = 64 * double(std::numeric_limits<T>::denorm_min());
    for (const specbake::FilterMethod& m : specbake::filter_methods()) {
        const Sym2<T> r = specbake::evaluate(m, in);
        const double xx = r.xx, xy = r.xy, yy = r.yy;
        const char* broken = nullptr;
        const double scale = std::max({std::abs(xx), std::abs(xy), std::abs(yy), 1e-30});
        if (!std::isfinite(xx) || !std::isfinite(xy) || !std::isfinite(yy))
            broken = "not finite";
        else if (min_eigenvalue(xx, xy, yy) < -tol * scale - slack)
            broken = "not positive semi-definite";
        else if (min_eigenvalue(xx - a_xx, xy, yy - a_yy) < -tol * scale - slack)
            broken = "reduces the roughness (A_bar - A not PSD)";
        else if (xx * yy - xy * xy < a_xx * a_yy * (1 - tol) - (tol * scale + 2 * slack) * scale)
            broken = "det(A_bar) < det(A)";
        if (broken) {
            std::fprintf(stderr, "%s (%s): %s: A_bar = [%.9g %.9g %.9g], A = diag(%.9g, %.9g)\n",
                         std::string(m.name).c_str(), std::is_same_v<T, float> ? "float" : "double", broken, xx,
                         xy, yy, a_xx, a_yy);
            std::abort();
        }
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size >= kInputBytes<float>) run<float>(data);
    if (size >= kInputBytes<float> + kInputBytes<double>) run<double>(data + kInputBytes<float>);
    return 0;
}
