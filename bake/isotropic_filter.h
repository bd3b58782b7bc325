// Isotropic projected-space NDF filtering of a squared roughness `a = alpha^2` by a kernel variance `t`,
// and the reductions of a 2x2 projected-space normal covariance Sigma to `t` (SPEC Sec. 3).
// Domain: a in [0, 1], t >= 0. NaN inputs propagate as NaN (callers validate data before filtering).
#pragma once

#include "core/enum_names.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <optional>
#include <string_view>

namespace specbake {

// How a 2x2 covariance is reduced to an isotropic kernel variance.
enum class IsotropicReduction { Mean, Sum, Max };

// "mean", "sum", "max" (the CLI and manifest spellings), in enum order.
inline constexpr std::array<std::string_view, 3> kIsotropicReductionNames{"mean", "sum", "max"};
inline std::string_view to_string(IsotropicReduction r) { return kIsotropicReductionNames[size_t(r)]; }
inline std::optional<IsotropicReduction> parse_isotropic_reduction(std::string_view name) {
    return enum_from_name<IsotropicReduction>(kIsotropicReductionNames, name);
}

// Full projected-space filtering, isotropic closed form of TK21 Eq. (4)-(7):
// a' = (a + t (1 - a)) / (1 + t (1 - a)). Stays in [a, 1]; a = 1 stays 1, t = 0 leaves a unchanged.
template <class T>
inline T filter_projected_isotropic(T a, T t) {
    const T k = t * (T(1) - a);
    return (a + k) / (T(1) + k);
}

// Approximate projected-space filtering, TK21 Eq. (9): a' = min(1, a + t).
template <class T>
inline T filter_approx_isotropic(T a, T t) {
    return std::min(T(1), a + t);
}

// Largest eigenvalue of the symmetric 2x2 matrix [[xx, xy], [xy, yy]].
template <class T>
inline T max_eigenvalue_sym2(T xx, T yy, T xy) {
    const T half_tr = T(0.5) * (xx + yy);
    const T d = T(0.5) * (xx - yy);
    return half_tr + std::sqrt(d * d + xy * xy);
}

// Kernel variance t from Sigma = [[xx, xy], [xy, yy]] (Sigma positive semi-definite):
// Mean t = tr(Sigma) (TK21 Eq. 14 analogue), Sum t = 2 tr(Sigma) (Eq. 13), Max t = 2 lambda_max (Eq. 10).
template <class T>
inline T reduce_covariance(IsotropicReduction r, T xx, T yy, T xy) {
    switch (r) {
        case IsotropicReduction::Mean: return xx + yy;
        case IsotropicReduction::Sum: return T(2) * (xx + yy);
        case IsotropicReduction::Max: return T(2) * max_eigenvalue_sym2(xx, yy, xy);
    }
    return xx + yy;
}

}  // namespace specbake
