// The method table: each entry forms its derivatives from the fragment and its neighbours and calls one
// kernel of bake/kernels.h or bake/peers.h, inside the common edge policy documented in methods.h.
#include "bake/methods.h"

#include "bake/kernels.h"
#include "bake/peers.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <type_traits>

namespace specbake {
namespace {

template <class T>
bool finite(const Vec3<T>& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

template <class T>
bool finite(const Sym2<T>& m) {
    return std::isfinite(m.xx) && std::isfinite(m.xy) && std::isfinite(m.yy);
}

template <class T>
Vec2<T> slope_du(const FilterInput<T>& in) { return slope_half_vector(in.h_dx) - slope_half_vector(in.h); }
template <class T>
Vec2<T> slope_dv(const FilterInput<T>& in) { return slope_half_vector(in.h_dy) - slope_half_vector(in.h); }
template <class T>
Vec2<T> proj_du(const FilterInput<T>& in) { return projected_half_vector(in.h_dx) - projected_half_vector(in.h); }
template <class T>
Vec2<T> proj_dv(const FilterInput<T>& in) { return projected_half_vector(in.h_dy) - projected_half_vector(in.h); }

template <class T>
Sym2<T> from_axes(const Vec2<T>& r2) { return diag(r2.x, r2.y); }

// Each method maps the sanitised squared roughness r2 and the input to A_bar.
struct Slope {
    template <class T>
    static Sym2<T> apply(const Vec2<T>& r2, const FilterInput<T>& in) {
        return filter_non_axis_aligned(r2, slope_du(in), slope_dv(in), in.sigma2);
    }
};
struct SlopeAxisAligned {
    template <class T>
    static Sym2<T> apply(const Vec2<T>& r2, const FilterInput<T>& in) {
        return from_axes(filter_axis_aligned(r2, slope_du(in), slope_dv(in), in.sigma2, in.kappa));
    }
};
struct ProjectedApprox {
    template <class T>
    static Sym2<T> apply(const Vec2<T>& r2, const FilterInput<T>& in) {
        return filter_non_axis_aligned(r2, proj_du(in), proj_dv(in), in.sigma2);
    }
};
struct ProjectedAxisAligned {
    template <class T>
    static Sym2<T> apply(const Vec2<T>& r2, const FilterInput<T>& in) {
        return from_axes(filter_axis_aligned(r2, proj_du(in), proj_dv(in), in.sigma2, in.kappa));
    }
};
struct Projected {
    template <class T>
    static Sym2<T> apply(const Vec2<T>& r2, const FilterInput<T>& in) {
        return filter_projected(r2, proj_du(in), proj_dv(in), in.sigma2);
    }
};
template <IsotropicReduction R>
struct Isotropic {
    template <class T>
    static Sym2<T> apply(const Vec2<T>& r2, const FilterInput<T>& in) {
        const T t = isotropic_kernel_roughness(R, in.n_dx - in.n, in.n_dy - in.n, in.sigma2);
        return diag(filter_isotropic(r2.x, t, in.kappa), filter_isotropic(r2.y, t, in.kappa));
    }
};
template <class T>
Sym2<T> varef_apply(const Vec2<T>& r2, T variance) {
    const T ax = varef_filter_alpha(std::sqrt(r2.x), variance);
    const T ay = varef_filter_alpha(std::sqrt(r2.y), variance);
    return diag(ax * ax, ay * ay);
}
struct VarefScreen {
    template <class T>
    static Sym2<T> apply(const Vec2<T>& r2, const FilterInput<T>& in) {
        return varef_apply(r2, varef_screen_space_variance(in.n_dx - in.n, in.n_dy - in.n));
    }
};
struct VarefCurvature {
    template <class T>
    static Sym2<T> apply(const Vec2<T>& r2, const FilterInput<T>& in) {
        return varef_apply(r2, varef_curvature_variance(in.pixel_size, in.curvature));
    }
};

// The edge policy of methods.h around one method.
template <class M, class T>
Sym2<T> guarded(const FilterInput<T>& in) {
    auto sanitize_alpha = [](T a) { return std::isnan(a) ? T(1) : std::min(std::max(a, T(0)), T(1)); };
    const T ax = sanitize_alpha(in.alpha.x);
    const T ay = sanitize_alpha(in.alpha.y);
    const Vec2<T> r2{ax * ax, ay * ay};
    const bool usable = finite(in.h) && finite(in.h_dx) && finite(in.h_dy) && finite(in.n) && finite(in.n_dx) &&
                        finite(in.n_dy) && std::isfinite(in.sigma2) && in.sigma2 >= T(0) && in.kappa >= T(0) &&
                        std::isfinite(in.pixel_size) && std::isfinite(in.curvature);
    if (!usable) return from_axes(r2);
    const Sym2<T> out = M::apply(r2, in);
    return finite(out) ? out : diag(T(1), T(1));
}

template <class M>
constexpr FilterMethod entry(std::string_view name, std::string_view source, std::string_view summary, bool iso) {
    return {name, source, summary, iso, &guarded<M, float>, &guarded<M, double>};
}

constexpr std::array kMethods{
    entry<Slope>("slope", "K16 (TK21 Eq. 2)", "slope-space filtering, non-axis-aligned kernel", false),
    entry<SlopeAxisAligned>("slope-aa", "K16 / TK21 Listing 3 with division",
                            "slope-space filtering, axis-aligned kernel clamped to kappa", false),
    entry<ProjectedApprox>("projected-approx", "TK21 Listing 2, Eq. 9",
                           "projected-space approximation A + 2 Sigma, non-axis-aligned", false),
    entry<ProjectedAxisAligned>("projected-aa", "TK21 Listing 3",
                                "projected-space approximation, axis-aligned kernel clamped to kappa", false),
    entry<Projected>("projected", "TK21 Listing 1 (Eq. 4-8, App. D)",
                     "full projected-space filtering, non-axis-aligned", false),
    entry<Isotropic<IsotropicReduction::Max>>("iso-max", "TK21 Eq. 10",
                                              "isotropic, normal-based, max eigenvalue (conservative)", true),
    entry<Isotropic<IsotropicReduction::Sum>>("iso-sum", "TK21 Eq. 13, Listing 5",
                                              "isotropic, normal-based, eigenvalue sum (conservative)", true),
    entry<Isotropic<IsotropicReduction::Mean>>("iso-mean", "TK21 Eq. 14",
                                               "isotropic, normal-based, eigenvalue mean", true),
    entry<VarefScreen>("varef-screen", "VAREF Sec. 3A", "variance from normal derivatives, added to alpha", true),
    entry<VarefCurvature>("varef-curvature", "VAREF Sec. 3B",
                          "variance from pixel size times curvature, added to alpha", true),
};

}  // namespace

std::span<const FilterMethod> filter_methods() { return kMethods; }

const FilterMethod* find_filter_method(std::string_view name) {
    for (const FilterMethod& m : kMethods)
        if (m.name == name) return &m;
    return nullptr;
}

template <class T>
Sym2<T> evaluate(const FilterMethod& method, const FilterInput<T>& input) {
    if constexpr (std::is_same_v<T, float>)
        return method.evaluate_float(input);
    else
        return method.evaluate_double(input);
}

template <class T>
Result<Sym2<T>> evaluate_method(std::string_view name, const FilterInput<T>& input) {
    const FilterMethod* m = find_filter_method(name);
    if (!m) {
        std::string valid;
        for (const FilterMethod& e : kMethods) valid += (valid.empty() ? "" : ", ") + std::string(e.name);
        return make_error("unknown filter method '" + std::string(name) + "' (valid: " + valid + ")");
    }
    return evaluate(*m, input);
}

template Sym2<float> evaluate<float>(const FilterMethod&, const FilterInput<float>&);
template Sym2<double> evaluate<double>(const FilterMethod&, const FilterInput<double>&);
template Result<Sym2<float>> evaluate_method<float>(std::string_view, const FilterInput<float>&);
template Result<Sym2<double>> evaluate_method<double>(std::string_view, const FilterInput<double>&);

}  // namespace specbake
