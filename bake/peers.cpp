// Peer methods: VAREF variance-based roughness, the K16 GGX rectangle integral and engines' run-time filters.
#include "bake/peers.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace specbake {

template <class T>
T varef_screen_space_variance(const Vec3<T>& dn_dx, const Vec3<T>& dn_dy) {
    // VAREF Sec. 3A.
    const T v = T(kVarefScale) * std::max(dot(dn_dx, dn_dx), dot(dn_dy, dn_dy));
    return std::min(v, T(kVarefMaxVariance));
}

template <class T>
T varef_curvature_variance(T pixel_size_world, T curvature) {
    // VAREF Sec. 3B: (pixelSizeWorld / Radius)^2 with curvature = 1 / Radius.
    const T x = pixel_size_world * curvature;
    return std::min(T(kVarefScale) * x * x, T(kVarefMaxVariance));
}

template <class T>
T varef_filter_alpha(T alpha, T variance) {
    // VAREF Sec. 2: roughness' = sqrt(roughness^2 + sigma_g^2), floored at MIN_ROUGHNESS.
    const T r = std::clamp(std::sqrt(alpha + variance), T(kVarefMinRoughness), T(1));
    return r * r;
}

namespace {

// Antiderivative of (1/pi) / (1 + u^2 + v^2)^2 in u and v: d^2 F / (du dv) is the GGX slope distribution
// in normalised slope coordinates (u, v) = (x / alpha_x, y / alpha_y); K16 slide "Convolving with GGX".
template <class T>
T ggx_slope_antiderivative(T u, T v) {
    const T su = std::sqrt(T(1) + u * u);
    const T sv = std::sqrt(T(1) + v * v);
    return (u / su * std::atan(v / su) + v / sv * std::atan(u / sv)) / (T(2) * std::numbers::pi_v<T>);
}

}  // namespace

template <class T>
T k16_ggx_rect_ndf(const Vec2<T>& hpp, const Vec3<T>& h, const Vec2<T>& alpha, const Vec2<T>& footprint) {
    const T u1 = (hpp.x - footprint.x) / alpha.x, u2 = (hpp.x + footprint.x) / alpha.x;
    const T v1 = (hpp.y - footprint.y) / alpha.y, v2 = (hpp.y + footprint.y) / alpha.y;
    const T integral = ggx_slope_antiderivative(u2, v2) - ggx_slope_antiderivative(u1, v2) -
                       ggx_slope_antiderivative(u2, v1) + ggx_slope_antiderivative(u1, v1);
    const T area = T(4) * footprint.x * footprint.y;
    const T hz2 = h.z * h.z;
    return integral / area / std::max(T(1e-3), hz2 * hz2);  // K16: Jacobian hpp -> h
}

template <class T>
Vec2<T> k16_ggx_rect_footprint(const Vec2<T>& dhpp_dx, const Vec2<T>& dhpp_dy, const Vec2<T>& alpha,
                               T footprint_max) {
    // K16: fp = (|dFdx| + |dFdy|) / 2, clamped to [min(roughness, 0.1), fp_max].
    const T fx = T(0.5) * (std::abs(dhpp_dx.x) + std::abs(dhpp_dy.x));
    const T fy = T(0.5) * (std::abs(dhpp_dx.y) + std::abs(dhpp_dy.y));
    return {std::min(std::max(fx, std::min(alpha.x, T(0.1))), footprint_max),
            std::min(std::max(fy, std::min(alpha.y, T(0.1))), footprint_max)};
}

template <class T>
T godot_limiter_alpha2(T r, const Vec3<T>& dn_dx, const Vec3<T>& dn_dy, T amount, T limit) {
    const T variance = amount * (dot(dn_dx, dn_dx) + dot(dn_dy, dn_dy));
    const T r2 = std::min(T(1), r * r + std::min(T(2) * variance, limit));
    return r2 * r2;
}

template <class T>
T unity_geometric_aa_alpha2(T a, const Vec3<T>& dn_dx, const Vec3<T>& dn_dy, T variance, T threshold) {
    const T v = variance * (dot(dn_dx, dn_dx) + dot(dn_dy, dn_dy));
    return std::clamp(a + std::min(T(2) * v, threshold * threshold), T(0), T(1));
}

template <class T>
T threejs_geometry_roughness_alpha2(T r, const Vec3<T>& dn_dx, const Vec3<T>& dn_dy) {
    const T g = std::max({std::abs(dn_dx.x), std::abs(dn_dy.x), std::abs(dn_dx.y), std::abs(dn_dy.y),
                          std::abs(dn_dx.z), std::abs(dn_dy.z)});
    const T rf = std::min(std::max(r, T(0.0525)) + g, T(1));
    return rf * rf * rf * rf;
}

template <class T>
T babylon_specular_aa_alpha2(T r, const Vec3<T>& dn_dx, const Vec3<T>& dn_dy) {
    const T slope2 = std::max(dot(dn_dx, dn_dx), dot(dn_dy, dn_dy));
    const T rf = std::max(r, std::pow(std::clamp(slope2, T(0), T(1)), T(0.333)));
    return rf * rf * rf * rf;
}

#define SPECBAKE_INSTANTIATE(T)                                                                      \
    template T varef_screen_space_variance<T>(const Vec3<T>&, const Vec3<T>&);                      \
    template T varef_curvature_variance<T>(T, T);                                                   \
    template T varef_filter_alpha<T>(T, T);                                                         \
    template T k16_ggx_rect_ndf<T>(const Vec2<T>&, const Vec3<T>&, const Vec2<T>&, const Vec2<T>&); \
    template Vec2<T> k16_ggx_rect_footprint<T>(const Vec2<T>&, const Vec2<T>&, const Vec2<T>&, T);    \
    template T godot_limiter_alpha2<T>(T, const Vec3<T>&, const Vec3<T>&, T, T);                   \
    template T unity_geometric_aa_alpha2<T>(T, const Vec3<T>&, const Vec3<T>&, T, T);              \
    template T threejs_geometry_roughness_alpha2<T>(T, const Vec3<T>&, const Vec3<T>&);            \
    template T babylon_specular_aa_alpha2<T>(T, const Vec3<T>&, const Vec3<T>&);
SPECBAKE_INSTANTIATE(float)
SPECBAKE_INSTANTIATE(double)
#undef SPECBAKE_INSTANTIATE

}  // namespace specbake
