// Peer methods kept for comparison: the VAREF variance-based roughness (screen-space and curvature modes),
// K16's GGX rectangle integral (box-filtered GGX NDF over an axis-aligned slope-space rectangle), and the
// run-time specular anti-aliasing that engines ship (Godot 4, Unity HDRP, three.js, Babylon.js), written
// from their published formulas (docs/accuracy.md#engine-peers says where each is from).
#pragma once

#include "core/vec.h"

namespace specbake {

// VAREF tuning constants (VAREF Sec. 4, shaders/pbr_functions.glsl).
inline constexpr double kVarefScale = 50.0;         // global variance multiplier
inline constexpr double kVarefMaxVariance = 0.1;    // cap of the geometric variance
inline constexpr double kVarefMinRoughness = 0.04;  // floor of the perceptual roughness r

// VAREF screen-space mode: sigma_g^2 = min(SCALE max(|dN/dx|^2, |dN/dy|^2), MAX_VARIANCE) from the
// world-space normal derivatives (VAREF Sec. 3A).
template <class T>
T varef_screen_space_variance(const Vec3<T>& dn_dx, const Vec3<T>& dn_dy);

// VAREF curvature mode: sigma_g^2 = min(SCALE (pixel_size_world * curvature)^2, MAX_VARIANCE) with
// curvature = 1/Radius in 1/world length (VAREF Sec. 3B).
template <class T>
T varef_curvature_variance(T pixel_size_world, T curvature);

// VAREF variance addition on one axis, VAREF Sec. 2: alpha' = alpha + sigma_g^2 (alpha = r^2), with the
// perceptual roughness r' = sqrt(alpha') clamped to [MIN_ROUGHNESS, 1]. Returns alpha' (not squared).
template <class T>
T varef_filter_alpha(T alpha, T variance);

// K16 "Convolving with GGX": mean of the axis-aligned GGX slope distribution P (roughness alpha, not
// squared) over the rectangle hpp +- footprint (half sides), times the Jacobian 1 / max(1e-3, h_z^4)
// back to the half-vector domain. hpp is the slope-space half vector h.xy / h.z; footprint > 0.
template <class T>
T k16_ggx_rect_ndf(const Vec2<T>& hpp, const Vec3<T>& h, const Vec2<T>& alpha, const Vec2<T>& footprint);

// K16 rectangle half sides from slope-space derivatives: (|dx| + |dy|) / 2, clamped to
// [min(alpha, 0.1), footprint_max] (K16 uses footprint_max = 1).
template <class T>
Vec2<T> k16_ggx_rect_footprint(const Vec2<T>& dhpp_dx, const Vec2<T>& dhpp_dy, const Vec2<T>& alpha,
                               T footprint_max);

// Run-time filters of engines, from the screen-space derivatives of a normal (each engine's choice of
// normal: the shading normal for Godot and Babylon.js, the interpolated vertex normal for Unity HDRP and
// three.js). Each returns the squared GGX roughness a = alpha^2 it shades with, for a material of
// perceptual roughness r (alpha = r^2).
//
// Godot 4 roughness limiter (TK19 with its defaults amount 0.25, limit 0.18), applied to r^2:
// r'^2 = min(1, r^2 + min(2 amount (|dn/dx|^2 + |dn/dy|^2), limit)).
template <class T>
T godot_limiter_alpha2(T r, const Vec3<T>& dn_dx, const Vec3<T>& dn_dy, T amount = T(0.25), T limit = T(0.18));

// Unity HDRP geometric specular AA (defaults: screen-space variance 0.1, threshold 0.2):
// a' = saturate(a + min(2 variance (|dn/dx|^2 + |dn/dy|^2), threshold^2)).
template <class T>
T unity_geometric_aa_alpha2(T a, const Vec3<T>& dn_dx, const Vec3<T>& dn_dy, T variance = T(0.1),
                            T threshold = T(0.2));

// three.js MeshStandardMaterial: r' = min(max(r, 0.0525) + g, 1) with g the largest component of
// max(|dn/dx|, |dn/dy|) (its `geometryRoughness`).
template <class T>
T threejs_geometry_roughness_alpha2(T r, const Vec3<T>& dn_dx, const Vec3<T>& dn_dy);

// Babylon.js SPECULARAA for analytic lights: r' = max(r, saturate(s)^0.333) with
// s = max(|dn/dx|^2, |dn/dy|^2).
template <class T>
T babylon_specular_aa_alpha2(T r, const Vec3<T>& dn_dx, const Vec3<T>& dn_dy);

}  // namespace specbake
