// The table of every roughness-filtering method specbake implements: name, source and evaluation from one
// fragment and its right (dx) and down (dy) neighbours. The CLI, benchmarks, shader tests and simulator
// iterate over filter_methods(); each entry wraps a function of bake/kernels.h or bake/peers.h.
#pragma once

#include "bake/constants.h"
#include "core/result.h"
#include "core/vec.h"

#include <span>
#include <string_view>

namespace specbake {

// One shading fragment and its neighbours. Derivatives are formed as neighbour minus fragment
// (ddx_fine / ddy_fine) in the space each method filters in.
template <class T>
struct FilterInput {
    Vec2<T> alpha{T(0.1), T(0.1)};  // slope-space roughness (alpha_x, alpha_y), alpha = r^2, in [0, 1]
    Vec3<T> h{0, 0, 1};             // tangent-space unit half vector at the fragment
    Vec3<T> h_dx{0, 0, 1};          // ... at the right neighbour (screen x + 1)
    Vec3<T> h_dy{0, 0, 1};          // ... at the down neighbour (screen y + 1)
    Vec3<T> n{0, 0, 1};             // world-space unit shading normal at the fragment (isotropic methods)
    Vec3<T> n_dx{0, 0, 1};          // ... at the right neighbour
    Vec3<T> n_dy{0, 0, 1};          // ... at the down neighbour
    T sigma2 = T(kDefaultSigma2);   // pixel-filter variance in pixels^2 (TK21 App. B)
    T kappa = T(kDefaultKappa);     // kernel clamp of the clamped methods; +inf disables it
    T pixel_size = 0;               // world-space pixel footprint size (VAREF curvature mode)
    T curvature = 0;                // 1 / radius in 1/world length (VAREF curvature mode)
};

// A filtering method. Both evaluators compute the same formula in float and double.
struct FilterMethod {
    std::string_view name;     // command-line name, e.g. "projected"
    std::string_view source;   // citation, e.g. "TK21 Listing 1"
    std::string_view summary;  // one line for tables and --help
    bool isotropic;            // adds the same kernel to both axes (normal-based methods)
    Sym2<float> (*evaluate_float)(const FilterInput<float>&);
    Sym2<double> (*evaluate_double)(const FilterInput<double>&);
};

// All methods in a fixed order: slope, slope-aa, projected-approx, projected-aa, projected, iso-max,
// iso-sum, iso-mean, varef-screen, varef-curvature.
std::span<const FilterMethod> filter_methods();

// The method called `name`, or nullptr.
const FilterMethod* find_filter_method(std::string_view name);

// Filtered roughness matrix A_bar (squared-roughness units; isotropic methods add the same kernel to
// alpha_x^2 and alpha_y^2, so an isotropic material gives a I). Edge policy, identical for every method:
//  - alpha is clamped to [0, 1]; a NaN alpha component counts as 1 (fully rough).
//  - A non-finite value in h, the neighbours, the normals, sigma2, pixel_size or curvature, a negative
//    sigma2, or a NaN or negative kappa gives a zero kernel: the result is diag(alpha_x^2, alpha_y^2).
//  - A kernel that is unbounded (slope space at h.z = 0) or overflows is infinitely wide: the clamped
//    methods add kappa, the others saturate to the fully rough matrix I.
// The result is always finite, symmetric and positive semi-definite, with det(A_bar) >= det(A).
template <class T>
Sym2<T> evaluate(const FilterMethod& method, const FilterInput<T>& input);

// evaluate() by name; an unknown name is an error listing the valid names.
template <class T>
Result<Sym2<T>> evaluate_method(std::string_view name, const FilterInput<T>& input);

}  // namespace specbake
