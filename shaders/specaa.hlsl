// specaa.hlsl: specbake runtime include for specular anti-aliasing (HLSL, Shader Model 5 or later).
// Generated from shaders/src/ by shaders/generate.cmake; edit the sources there, not this file.
// The API is documented below the language macros; SPECAA_* macros map the shared body to HLSL.
#ifndef SPECAA_INCLUDED
#define SPECAA_INCLUDED

#define SPECAA_FLOAT2 float2
#define SPECAA_FLOAT3 float3
#define SPECAA_FLOAT4 float4
#define SPECAA_UINT2 uint2
#define SPECAA_UINT3 uint3
#define SPECAA_UINT4 uint4
#define SPECAA_SATURATE(x) saturate(x)
#define SPECAA_DDX(x) ddx(x)
// The bits of a float as uint (the edge policy tests finiteness on them).
#define SPECAA_AS_UINT(x) asuint(x)
#define SPECAA_AS_UINT3(x) asuint(x)
#define SPECAA_AS_UINT4(x) asuint(x)
#define SPECAA_DDY(x) ddy(x)
// Selection c ? a : b (HLSL's ?: evaluates both sides and selects).
#define SPECAA_SELECT(c, a, b) ((c) ? (a) : (b))
#define SPECAA_SELECT2(c, a, b) ((c) ? (a) : (b))
#define SPECAA_SELECT3(c, a, b) ((c) ? (a) : (b))
// Texture parameters: HLSL passes a Texture2D and its SamplerState.
#define SPECAA_TEXTURE_PARAMS(tex, smp) Texture2D tex, SamplerState smp
#define SPECAA_TEXTURE_ARGS(tex, smp) tex, smp
#define SPECAA_SAMPLE(tex, smp, uv) tex.Sample(smp, uv)
#define SPECAA_SAMPLE_BIAS(tex, smp, uv, bias) tex.SampleBias(smp, uv, bias)
#define SPECAA_SAMPLE_GRAD(tex, smp, uv, gx, gy) tex.SampleGrad(smp, uv, gx, gy)
// Level of detail the sampler computes for uv (relative to level 0, not clamped to the mip range).
#define SPECAA_QUERY_LOD(tex, smp, uv) tex.CalculateLevelOfDetailUnclamped(smp, uv)
#define SPECAA_UINT3 uint3
// Glint dictionary (2D texture array) parameters and its explicit-gradient read.
#define SPECAA_TEXTURE_ARRAY_PARAMS(tex, smp) Texture2DArray tex, SamplerState smp
#define SPECAA_TEXTURE_ARRAY_ARGS(tex, smp) tex, smp
#define SPECAA_SAMPLE_ARRAY_GRAD(tex, smp, uvw, gx, gy) tex.SampleGrad(smp, uvw, gx, gy)

// ===================================================================================================
// specbake runtime include: specular anti-aliasing by NDF filtering (SPEC Sec. 5).
//
// Conventions (SPEC Sec. 2). Perceptual roughness r (glTF), alpha = r^2, squared roughness a = alpha^2.
// A roughness matrix is a symmetric 2x2 matrix [[xx, xy], [xy, yy]] in the tangent frame, stored as
// float3(xx, yy, xy), in squared-roughness units (A = diag(alpha_x^2, alpha_y^2) when axis-aligned;
// A = 2 x slope covariance, TK21 Sec. 2.1). A "kernel matrix" K = 2 Sigma is what filtering adds to a
// roughness matrix (TK21 Eq. 3 and 6); an isotropic kernel t is what it adds to a scalar a (TK21 Eq. 10,
// 13, 14; SPEC Sec. 3: t = tr(Sigma) for the mean reduction). Tangent-space vectors: z along the normal.
//
// Configuration (define before including):
//   SPECAA_QUALITY  the cost tier of the default entry points (specaa_filtered_alpha2_matrix,
//                   specaa_default_D); pick by the run-time cost you accept per light:
//                   SPECAA_QUALITY_FAST (0)      the isotropic filtered roughness (baked data + per-pixel
//                                                kernel, specaa_filtered_alpha2) as A = a' I, and two lobes
//                                                fitted to the convolution with the material's tails
//                                                (specaa_filtered_D_isotropic): the cheapest; bind the baked
//                                                roughness (+35-50 SPIR-V instructions over GGX(a); with the
//                                                Sigma kernel +86-89).
//                   SPECAA_QUALITY_BALANCED (1)  the same isotropic A, and GGX of the material convolved
//                                                with the footprint a' - a in closed form
//                                                (specaa_convolved_D_isotropic, no loop); bind the baked
//                                                roughness (+121-136 over GGX(a)).
//                   SPECAA_QUALITY_REFERENCE (2) the default (the anisotropic matrix form and the convolution
//                                                by quadrature, specaa_convolved_D: a loop of 12-32 lobes).
//                   Default SPECAA_QUALITY_REFERENCE. Costs and accuracy per tier:
//                   docs/shader-include.md#quality-tiers.
//   SPECAA_SIGMA2   pixel-filter variance in pixels^2, default 1/(2 pi) (TK21 App. B).
//   SPECAA_KAPPA    clamp of derivative-based kernels, default 0.18 (TK21 Eq. 10, K16).
//   SPECAA_GGX_SPREAD  specaa_default_D with a kernel or LEAN texture: GGX(A) where the minified
//                   footprint's spread k_max (the baked spread's major axis, weighed by its heavy
//                   tail 1 - g with the Sigma kernel, or the per-pixel kernel's minor one) exceeds
//                   1 / this, default 8.
//   Baked data for the default entry point (at most one of the roughness texture and kernel/LEAN):
//   SPECAA_ROUGHNESS_TEXTURE name   baked filtered roughness mips (perceptual r), channel
//                                   SPECAA_ROUGHNESS_CHANNEL (default g: the RGBA ORM layout, A = 1;
//                                   define it as r for the one-channel R8/R16 file).
//   SPECAA_KERNEL_TEXTURE name      baked projected-space kernel mips: with SPECAA_KERNEL_ANISOTROPIC
//                                   RGBA = (xx, yy, xy, g) of Sigma and its rough share g
//                                   (R16G16B16A16_SFLOAT), the bake's default; without it R = t (isotropic
//                                   mean, R16_SFLOAT; `specbake texture --isotropic-kernel`).
//                                   The single lobe takes K = 2 Sigma sqrt(g) (specaa_baked_kernel_matrix);
//   SPECAA_KERNEL_COVARIANCE        K = 2 Sigma whatever g (the covariance-matched lobe of earlier releases).
//   SPECAA_KERNEL_GATE              a baked kernel K whose largest eigenvalue is below this times the
//                                   material's a is faded out, K saturate(lambda_max(K) / (gate a))^2
//                                   (specaa_baked_kernel_matrix); default 0.5, 0 keeps every kernel whole.
//   SPECAA_KERNEL_TWO_LOBES         specaa_default_D splits the Sigma kernel's texel into its flat share
//                                   (the material's lobe) and its rough share g (all of Sigma): opt-in.
//   SPECAA_LEAN_TEXTURE0 name       LEAN moments, projected space (SPEC Sec. 3), in two textures:
//   SPECAA_LEAN_TEXTURE1 name         TEXTURE0 RGBA = (m.x, m.y, M.xx, M.yy), TEXTURE1 R = M.xy
//                                     (at least 16-bit float, trilinear filtering).
//   Every baked file has 1, 2 or 4 channels in the same order in KTX2, DDS, EXR and PNG
//   (docs/texture-bake.md#output-layouts); bind them with linear mip filtering (LINEAR_MIPMAP_LINEAR):
//   loaders such as three.js KTX2Loader default to nearest.
//   SPECAA_NORMAL_TWO_CHANNEL       the baked mean normal (`*_normal`) read by specaa_sample_mean_normal
//                                   has two channels (BC5 of `--block bc`, ASTC of `--block astc`: x, y as
//                                   (n + 1) / 2); z is rebuilt as sqrt(max(0, 1 - x^2 - y^2)). Without it:
//                                   RGBA8, (n + 1) / 2.
//   SPECAA_SAMPLER name             HLSL only: the SamplerState used with the textures above.
//   SPECAA_USE_CURVATURE            per-pixel kernel from _SPECAA_CURVATURE (SPEC Sec. 4) and the
//                                   position derivatives instead of normal derivatives.
//   SPECAA_NO_PIXEL_KERNEL          baked data only (no per-pixel kernel).
//   Diagnostics (to attribute an error to one part of the default; not for shipping):
//   SPECAA_NO_BAKED_KERNEL          the baked kernel/LEAN spread is taken as zero (the per-pixel kernel only).
//   SPECAA_DEFAULT_D_WEIGHT w       specaa_default_D with this blend weight everywhere (0: the convolved
//                                   NDF, 1: GGX(A)).
//   SPECAA_KERNEL_LOD_BIAS b        the Sigma kernel texel sampled with this LOD bias (the mip the
//                                   hardware picks against a finer or coarser footprint).
//   SPECAA_GATE_PIXEL_KERNEL        the per-pixel kernel faded out like the baked one (SPECAA_KERNEL_GATE).
//   SPECAA_PIXEL_KERNEL_MIN, _MAX, _MEAN  with SPECAA_USE_CURVATURE: per pixel the smaller or the larger (by
//                                   trace) of the quad-derivative kernel and the curvature kernel, or their mean.
//   SPECAA_BLEND_FROM_SPREAD_SIZE   specaa_default_D's GGX(A) share judged on the baked spread's size alone,
//                                   not weighed by its heavy tail 1 - g (the rule before).
//   SPECAA_PIXEL_KERNEL_EDGE expr   with SPECAA_USE_CURVATURE: the two blended by how much of a face the
//                                   footprint covers, w = saturate(SPECAA_EDGE_SCALE (default 3.5) F / L) on
//                                   the curvature kernel, F the longer position derivative, L = expr, the
//                                   vertex's mean edge length (an attribute the shader provides).
//   SPECAA_KERNEL_AREA_LOD          the Sigma kernel texel sampled at the mip of the footprint's area, not of
//                                   its major axis (the hardware's isotropic choice).
//   SPECAA_CLOSED_FORM_D            the reference tier's convolution in closed form
//                                   (specaa_convolved_D_closed_form on its anisotropic matrix): the closed
//                                   form's share of the balanced tier's error, apart from its isotropic A.
//   SPECAA_BLEND_FROM_LARGEST_AXIS  specaa_default_D's blend weight from the largest eigenvalue of all of
//                                   K = A - a I, the per-pixel kernel included (the rule before the shape).
//   SPECAA_BLEND_FROM_BAKED_SPREAD  specaa_default_D's blend weight from the baked spread alone.
//   SPECAA_NO_VIEW_TURN             the per-pixel kernel without the half vector's turn with the view
//                                   direction (the normal's spread alone, the kernel before s.view).
//   SPECAA_TIER_VIEW_TURN           the fast and balanced tiers with the half vector's turn (which they leave out).
// Textures are sampled with implicit derivatives, so the hardware selects the mip: the baked mips are
// the footprint filter of the normal map, the per-pixel kernel adds the geometric curvature.
//
// Domain: unit vectors, a in [0, 1], finite derivatives. Outside it, the derivative-based methods and the
// default entry points follow the edge policy of the bake's filter core (bake/methods.h): a is clamped to
// [0, 1] and a NaN a counts as 1 (fully rough); a non-finite input of a kernel (the vector whose quad
// derivatives are taken or those derivatives, the curvature, the tangent frame, a baked texel) gives a
// zero kernel; a kernel that overflows is infinitely wide: the clamped methods and the per-pixel kernels
// of the default add kappa, the others give the fully rough matrix I. Their results are always finite.
// The filters from given derivatives, the reductions and the NDFs take inputs inside the domain.
// ===================================================================================================

#define SPECAA_QUALITY_FAST 0
#define SPECAA_QUALITY_BALANCED 1
#define SPECAA_QUALITY_REFERENCE 2
#ifndef SPECAA_QUALITY
#define SPECAA_QUALITY SPECAA_QUALITY_REFERENCE
#endif
// (One line: GLSL before 4.20 has no line continuation.)
#if SPECAA_QUALITY != SPECAA_QUALITY_FAST && SPECAA_QUALITY != SPECAA_QUALITY_BALANCED && SPECAA_QUALITY != SPECAA_QUALITY_REFERENCE
#error "specaa: SPECAA_QUALITY is SPECAA_QUALITY_FAST (0), SPECAA_QUALITY_BALANCED (1) or SPECAA_QUALITY_REFERENCE (2)"
#endif
#ifndef SPECAA_SIGMA2
#define SPECAA_SIGMA2 0.15915494309189535
#endif
#ifndef SPECAA_KAPPA
#define SPECAA_KAPPA 0.18
#endif
#ifndef SPECAA_GGX_SPREAD
#define SPECAA_GGX_SPREAD 8.0
#endif
#ifndef SPECAA_KERNEL_GATE
#define SPECAA_KERNEL_GATE 0.5
#endif
#ifndef SPECAA_ROUGHNESS_CHANNEL
#define SPECAA_ROUGHNESS_CHANNEL g
#endif
#define SPECAA_PI 3.14159265358979

// Kernel traces above this are treated as this: the filtered roughness is then 1 within float precision,
// and the closed forms below stay finite.
#define SPECAA_MAX_KERNEL 1.0e8

// ---------------------------------------------------------------------------------------------------
// Edge policy (header comment). Finiteness is read from the bits: GLSL does not require NaN support,
// and a compiler may fold isnan() or x != x away; an exponent of all ones cannot be.
// ---------------------------------------------------------------------------------------------------

// Largest magnitude of the components as bits: at least SPECAA_NOT_FINITE exactly when one is +-inf or
// NaN. Vector bit operations and maxima keep the tests cheap (no short-circuit branches).
#define SPECAA_NOT_FINITE 0x7f800000u
uint specaa_magnitude_bits(float x) { return SPECAA_AS_UINT(x) & 0x7fffffffu; }
// (The mask as a vector: WGSL does not apply a scalar to every component of a vector operand.)
SPECAA_UINT3 specaa_magnitude_bits3(SPECAA_FLOAT3 v) {
    return SPECAA_AS_UINT3(v) & SPECAA_UINT3(0x7fffffffu, 0x7fffffffu, 0x7fffffffu);
}
uint specaa_max_component(SPECAA_UINT3 m) { return max(max(m.x, m.y), m.z); }
bool specaa_is_finite(float x) { return specaa_magnitude_bits(x) < SPECAA_NOT_FINITE; }
bool specaa_is_finite3(SPECAA_FLOAT3 v) { return specaa_max_component(specaa_magnitude_bits3(v)) < SPECAA_NOT_FINITE; }

// Squared roughness clamped to [0, 1]; NaN counts as fully rough.
float specaa_sanitize_alpha2(float a) { return SPECAA_SELECT(specaa_magnitude_bits(a) > SPECAA_NOT_FINITE, 1.0, clamp(a, 0.0, 1.0)); }
SPECAA_FLOAT2 specaa_sanitize_alpha2_2(SPECAA_FLOAT2 a) {
    return SPECAA_FLOAT2(specaa_sanitize_alpha2(a.x), specaa_sanitize_alpha2(a.y));
}

// A derivative-based kernel clamped to kappa; an unbounded one (+inf, or NaN from inf - inf or 0 * inf)
// is clamped to kappa too (TK21 Eq. 10: the clamp bounds the kernel whatever the derivatives).
float specaa_clamp_kernel(float kernel) { return SPECAA_SELECT(specaa_is_finite(kernel), min(kernel, SPECAA_KAPPA), SPECAA_KAPPA); }

// The vector v and its quad derivatives dx, dy are finite.
bool specaa_usable(SPECAA_FLOAT3 v, SPECAA_FLOAT3 dx, SPECAA_FLOAT3 dy) {
    SPECAA_UINT3 m = max(specaa_magnitude_bits3(v), max(specaa_magnitude_bits3(dx), specaa_magnitude_bits3(dy)));
    return specaa_max_component(m) < SPECAA_NOT_FINITE;
}

// The policy around a filtered matrix r of squared roughness a: diag(a) without usable inputs (zero
// kernel), the fully rough I when the kernel overflowed.
SPECAA_FLOAT3 specaa_guard_matrix(bool usable, SPECAA_FLOAT2 a, SPECAA_FLOAT3 r) {
    SPECAA_FLOAT3 filtered = SPECAA_SELECT3(specaa_is_finite3(r), r, SPECAA_FLOAT3(1.0, 1.0, 0.0));
    return SPECAA_SELECT3(usable, filtered, SPECAA_FLOAT3(a, 0.0));
}

// ---------------------------------------------------------------------------------------------------
// Symmetric 2x2 matrices stored as float3(xx, yy, xy).
// ---------------------------------------------------------------------------------------------------

// Determinant xx yy - xy^2.
float specaa_sym_det(SPECAA_FLOAT3 m) { return m.x * m.y - m.z * m.z; }

// Largest eigenvalue of a symmetric 2x2 matrix (closed form of the 2x2 characteristic polynomial).
float specaa_sym_max_eigenvalue(SPECAA_FLOAT3 m) {
    float halfDiff = 0.5 * (m.x - m.y);
    return 0.5 * (m.x + m.y) + sqrt(halfDiff * halfDiff + m.z * m.z);
}

// A positive semi-definite matrix with each eigenvalue clamped to [0, cap] (eigenvectors kept): TK21
// Sec. 4's clamp of the non-axis-aligned kernel ("clamp the eigenvalues of Sigma"), the matrix analogue of
// Listing 3's per-axis min. m = l2 I + (l1 - l2) P1 with the projector P1 = (m - l2 I) / (l1 - l2), so the
// result is c2 I + (c1 - c2) P1, c_i = clamp(l_i, 0, cap); both above the cap: cap I. For a huge, nearly
// rank-one m the rounded l2 can come out negative (cancellation in halfTrace - radius); the clamp to 0
// keeps the result positive semi-definite and at most cap.
SPECAA_FLOAT3 specaa_sym_clamp_eigenvalues(SPECAA_FLOAT3 m, float cap) {
    float halfTrace = 0.5 * (m.x + m.y);
    float halfDiff = 0.5 * (m.x - m.y);
    float radius = sqrt(halfDiff * halfDiff + m.z * m.z);
    float l2 = halfTrace - radius;
    float c1 = clamp(halfTrace + radius, 0.0, cap), c2 = clamp(l2, 0.0, cap);
    float f = radius > 0.0 ? (c1 - c2) / (2.0 * radius) : 0.0;
    return SPECAA_FLOAT3(c2 + f * (m.x - l2), c2 + f * (m.y - l2), f * m.z);
}

// Nearest positive semi-definite matrix: negative eigenvalues set to 0 (Frobenius projection). Used on
// covariances formed as a difference of moments, Sigma = M - m m^T (SPEC Sec. 3), which rounding can
// push slightly indefinite. Uses the spectral projector (Sigma - lmin I) / (lmax - lmin).
SPECAA_FLOAT3 specaa_sym_clamp_psd(SPECAA_FLOAT3 m) {
    float halfTrace = 0.5 * (m.x + m.y);
    float halfDiff = 0.5 * (m.x - m.y);
    float radius = sqrt(halfDiff * halfDiff + m.z * m.z);
    float lmax = halfTrace + radius;
    float lmin = halfTrace - radius;
    if (lmin >= 0.0) return m;
    if (lmax <= 0.0) return SPECAA_FLOAT3(0.0, 0.0, 0.0);
    return (lmax / (2.0 * radius)) * SPECAA_FLOAT3(m.x - lmin, m.y - lmin, m.z);
}

// Kernel matrix K = 2 Sigma = 2 sigma^2 [du; dv]^T [du; dv] from the screen-space derivatives of a 2D
// quantity along x (du) and y (dv), TK21 Eq. (3) (K16: C = U U^T with the roughness factor 2).
SPECAA_FLOAT3 specaa_kernel_matrix(SPECAA_FLOAT2 du, SPECAA_FLOAT2 dv) {
    return (2.0 * SPECAA_SIGMA2) * SPECAA_FLOAT3(du.x * du.x + dv.x * dv.x,
                                                 du.y * du.y + dv.y * dv.y,
                                                 du.x * du.y + dv.x * dv.y);
}

// ---------------------------------------------------------------------------------------------------
// Half-vector projections (TK21 Sec. 3-4.1, T19 Listing 1).
// ---------------------------------------------------------------------------------------------------

// Slope-space half vector -h.xy / |h.z| (K16 "parallel plane", TK21 Listings 2-3 with the division).
// Not finite at h.z = 0: the slope-space methods break down at grazing half vectors (TK21 Sec. 3).
SPECAA_FLOAT2 specaa_slope_half_vector(SPECAA_FLOAT3 h) { return h.xy / -abs(h.z); }

// Orthographically projected half vector (h.x, h.y), TK21 Sec. 4.1: derivatives shrink by det J = h_z.
SPECAA_FLOAT2 specaa_projected_half_vector(SPECAA_FLOAT3 h) { return h.xy; }

// ---------------------------------------------------------------------------------------------------
// Filters from given derivatives (du, dv = value at the right/upper neighbour minus the fragment's).
// alpha2 = (alpha_x^2, alpha_y^2) of the material.
// ---------------------------------------------------------------------------------------------------

// Non-axis-aligned filtering diag(alpha2) + K, no clamp. With slope-space derivatives this is K16's
// R' = R + 2C (TK21 Eq. 2); with projected derivatives the practical approximation TK21 Eq. (9), Listing 2.
SPECAA_FLOAT3 specaa_filter_non_axis_aligned(SPECAA_FLOAT2 alpha2, SPECAA_FLOAT2 du, SPECAA_FLOAT2 dv) {
    return SPECAA_FLOAT3(alpha2.x, alpha2.y, 0.0) + specaa_kernel_matrix(du, dv);
}

// Axis-aligned filtering over the bounding rectangle |du| + |dv| of the footprint with the kappa clamp,
// TK21 Listing 3 (K16 "More Temporal Stability"): saturate(alpha2 + min(2 sigma^2 bounds^2, kappa)).
SPECAA_FLOAT2 specaa_filter_axis_aligned(SPECAA_FLOAT2 alpha2, SPECAA_FLOAT2 du, SPECAA_FLOAT2 dv) {
    SPECAA_FLOAT2 bounds = abs(du) + abs(dv);
    SPECAA_FLOAT2 kernel = (2.0 * SPECAA_SIGMA2) * (bounds * bounds);
    return SPECAA_SATURATE(alpha2 + SPECAA_FLOAT2(specaa_clamp_kernel(kernel.x), specaa_clamp_kernel(kernel.y)));
}

// Full projected-space filtering of an axis-aligned material, TK21 Eq. (4)-(8):
// A_bar = ((B + K)^-1 + I)^-1 with B = diag(a / (1 - a)), B_bar = B + K. Written as
// A_bar = (B_bar + det(B_bar) I) / (1 + tr(B_bar) + det(B_bar)) (the App. D form) and multiplied by
// c = (1 - a_x)(1 - a_y), so a = 1 (B infinite) and a = 0 with K = 0 (singular) stay exact (A_bar = 1
// resp. 0). c det(B_bar) = a_x a_y + c B_xx K_yy + c B_yy K_xx + c det(K) is a sum of non-negative terms,
// so det(B_bar) >= det(B) (the clamp of Listing 1) holds by construction. detK = det(K) >= 0, K PSD.
SPECAA_FLOAT3 specaa_filter_projected_matrix_det(SPECAA_FLOAT2 alpha2, SPECAA_FLOAT3 kernel, float kernelDet) {
    // Half the trace first: a finite K whose trace overflows still scales down to the cap (then A_bar ~ I)
    // instead of to 0; an infinite K gives NaN here, which the callers' edge policy turns into I.
    SPECAA_FLOAT3 K = kernel;
    float detK = kernelDet;
    float halfTraceK = 0.5 * K.x + 0.5 * K.y;
    float traceK = K.x + K.y;
    if (halfTraceK > 0.5 * SPECAA_MAX_KERNEL) {
        float scale = (0.5 * SPECAA_MAX_KERNEL) / halfTraceK;
        K *= scale;
        detK *= scale * scale;
        traceK = SPECAA_MAX_KERNEL;
    }
    float ax = SPECAA_SATURATE(alpha2.x);
    float ay = SPECAA_SATURATE(alpha2.y);
    float c = (1.0 - ax) * (1.0 - ay);
    float bx = ax * (1.0 - ay);                                   // c B_xx
    float by = ay * (1.0 - ax);                                   // c B_yy
    float cDet = ax * ay + bx * K.y + by * K.x + c * max(detK, 0.0);  // c det(B_bar)
    float denominator = c + bx + by + c * traceK + cDet;         // c (1 + tr(B_bar) + det(B_bar)) > 0
    return SPECAA_FLOAT3(bx + c * K.x + cDet, by + c * K.y + cDet, c * K.z) / denominator;
}

// Full projected-space filtering by a kernel matrix K (PSD), e.g. baked Sigma plus a curvature kernel.
SPECAA_FLOAT3 specaa_filter_projected_matrix(SPECAA_FLOAT2 alpha2, SPECAA_FLOAT3 K) {
    return specaa_filter_projected_matrix_det(alpha2, K, specaa_sym_det(K));
}

// Full projected-space filtering from projected half-vector derivatives, TK21 Listing 1. det(K) comes
// from Cauchy-Binet, (2 sigma^2)^2 (du x dv)^2, exact where K_xx K_yy - K_xy^2 would cancel (a footprint
// stretched along one direction, e.g. at grazing angles).
SPECAA_FLOAT3 specaa_filter_projected(SPECAA_FLOAT2 alpha2, SPECAA_FLOAT2 du, SPECAA_FLOAT2 dv) {
    float cross2 = (2.0 * SPECAA_SIGMA2) * (du.x * dv.y - du.y * dv.x);
    return specaa_filter_projected_matrix_det(alpha2, specaa_kernel_matrix(du, dv), cross2 * cross2);
}

// Isotropic kernels from world-space normal derivatives dnU, dnV (TK21 Sec. 5; Eq. 12: their lengths
// equal the projected derivatives of the pairwise averaged normal). Sigma = sigma^2 Gram(dnU, dnV).
// Max: 2 lambda_max(Sigma), TK21 Eq. (10) (tightest conservative isotropic kernel).
float specaa_iso_kernel_max(SPECAA_FLOAT3 dnU, SPECAA_FLOAT3 dnV) {
    SPECAA_FLOAT3 gram = SPECAA_FLOAT3(dot(dnU, dnU), dot(dnV, dnV), dot(dnU, dnV));
    return 2.0 * SPECAA_SIGMA2 * specaa_sym_max_eigenvalue(gram);
}

// Sum: 2 tr(Sigma) = 2 sigma^2 (|dnU|^2 + |dnV|^2), TK21 Eq. (13), Listing 5 (conservative).
float specaa_iso_kernel_sum(SPECAA_FLOAT3 dnU, SPECAA_FLOAT3 dnV) {
    return 2.0 * SPECAA_SIGMA2 * (dot(dnU, dnU) + dot(dnV, dnV));
}

// Mean: tr(Sigma) = sigma^2 (|dnU|^2 + |dnV|^2), TK21 Eq. (14) (less conservative, lowest error there).
float specaa_iso_kernel_mean(SPECAA_FLOAT3 dnU, SPECAA_FLOAT3 dnV) {
    return SPECAA_SIGMA2 * (dot(dnU, dnU) + dot(dnV, dnV));
}

// Clamped isotropic filtering, TK21 Eq. (10)/(13)/(14) as in Listing 5: saturate(a + min(t, kappa)).
float specaa_filter_isotropic(float alpha2, float kernel) {
    return SPECAA_SATURATE(alpha2 + specaa_clamp_kernel(kernel));
}

// ---------------------------------------------------------------------------------------------------
// Derivative-based methods: the filters above with derivatives from the 2x2 pixel quad (ddx/ddy).
// hTS: unit tangent-space half vector; normal: unit world-space shading normal.
// ---------------------------------------------------------------------------------------------------

// "slope": K16 slope-space non-axis-aligned filtering, R' = R + 2C (TK21 Eq. 2).
SPECAA_FLOAT3 specaa_slope(SPECAA_FLOAT2 alpha2, SPECAA_FLOAT3 hTS) {
    SPECAA_FLOAT2 a = specaa_sanitize_alpha2_2(alpha2);
    SPECAA_FLOAT2 hs = specaa_slope_half_vector(hTS);
    return specaa_guard_matrix(specaa_usable(hTS, SPECAA_DDX(hTS), SPECAA_DDY(hTS)), a, specaa_filter_non_axis_aligned(a, SPECAA_DDX(hs), SPECAA_DDY(hs)));
}

// "slope-aa": K16 axis-aligned rectangle in slope space with the kappa clamp (Listing 3 with division).
SPECAA_FLOAT2 specaa_slope_aa(SPECAA_FLOAT2 alpha2, SPECAA_FLOAT3 hTS) {
    SPECAA_FLOAT2 a = specaa_sanitize_alpha2_2(alpha2);
    SPECAA_FLOAT2 hs = specaa_slope_half_vector(hTS);
    SPECAA_FLOAT2 r = specaa_filter_axis_aligned(a, SPECAA_DDX(hs), SPECAA_DDY(hs));
    return SPECAA_SELECT2(specaa_usable(hTS, SPECAA_DDX(hTS), SPECAA_DDY(hTS)), r, a);
}

// "projected-approx": TK21 Listing 2, Eq. (9), non-axis-aligned, projected derivatives, no clamp.
SPECAA_FLOAT3 specaa_projected_approx(SPECAA_FLOAT2 alpha2, SPECAA_FLOAT3 hTS) {
    SPECAA_FLOAT2 a = specaa_sanitize_alpha2_2(alpha2);
    SPECAA_FLOAT2 hp = specaa_projected_half_vector(hTS);
    return specaa_guard_matrix(specaa_usable(hTS, SPECAA_DDX(hTS), SPECAA_DDY(hTS)), a, specaa_filter_non_axis_aligned(a, SPECAA_DDX(hp), SPECAA_DDY(hp)));
}

// "projected-aa": TK21 Listing 3, axis-aligned, projected derivatives, kappa clamp.
SPECAA_FLOAT2 specaa_projected_aa(SPECAA_FLOAT2 alpha2, SPECAA_FLOAT3 hTS) {
    SPECAA_FLOAT2 a = specaa_sanitize_alpha2_2(alpha2);
    SPECAA_FLOAT2 hp = specaa_projected_half_vector(hTS);
    SPECAA_FLOAT2 r = specaa_filter_axis_aligned(a, SPECAA_DDX(hp), SPECAA_DDY(hp));
    return SPECAA_SELECT2(specaa_usable(hTS, SPECAA_DDX(hTS), SPECAA_DDY(hTS)), r, a);
}

// "projected": TK21 Listing 1, full projected-space filtering (Eq. 4-8).
SPECAA_FLOAT3 specaa_projected(SPECAA_FLOAT2 alpha2, SPECAA_FLOAT3 hTS) {
    SPECAA_FLOAT2 a = specaa_sanitize_alpha2_2(alpha2);
    SPECAA_FLOAT2 hp = specaa_projected_half_vector(hTS);
    return specaa_guard_matrix(specaa_usable(hTS, SPECAA_DDX(hTS), SPECAA_DDY(hTS)), a, specaa_filter_projected(a, SPECAA_DDX(hp), SPECAA_DDY(hp)));
}

// "iso-max": TK21 Eq. (10) from normal derivatives; returns the filtered a.
float specaa_iso_max(float alpha2, SPECAA_FLOAT3 normal) {
    float a = specaa_sanitize_alpha2(alpha2);
    SPECAA_FLOAT3 dnU = SPECAA_DDX(normal);
    SPECAA_FLOAT3 dnV = SPECAA_DDY(normal);
    return SPECAA_SELECT(specaa_usable(normal, dnU, dnV), specaa_filter_isotropic(a, specaa_iso_kernel_max(dnU, dnV)), a);
}

// "iso-sum": TK21 Eq. (13), Listing 5 (T19 Listing 2); returns the filtered a.
float specaa_iso_sum(float alpha2, SPECAA_FLOAT3 normal) {
    float a = specaa_sanitize_alpha2(alpha2);
    SPECAA_FLOAT3 dnU = SPECAA_DDX(normal);
    SPECAA_FLOAT3 dnV = SPECAA_DDY(normal);
    return SPECAA_SELECT(specaa_usable(normal, dnU, dnV), specaa_filter_isotropic(a, specaa_iso_kernel_sum(dnU, dnV)), a);
}

// "iso-mean": TK21 Eq. (14); returns the filtered a.
float specaa_iso_mean(float alpha2, SPECAA_FLOAT3 normal) {
    float a = specaa_sanitize_alpha2(alpha2);
    SPECAA_FLOAT3 dnU = SPECAA_DDX(normal);
    SPECAA_FLOAT3 dnV = SPECAA_DDY(normal);
    return SPECAA_SELECT(specaa_usable(normal, dnU, dnV), specaa_filter_isotropic(a, specaa_iso_kernel_mean(dnU, dnV)), a);
}

// ---------------------------------------------------------------------------------------------------
// Isotropic projected-space filtering and kernel reductions (SPEC Sec. 3, the texture bake's formulas).
// ---------------------------------------------------------------------------------------------------

// Full projected-space filtering of a scalar a by an isotropic kernel t, TK21 Eq. (4)-(7) in closed form:
// a' = (a + t (1 - a)) / (1 + t (1 - a)). t = 0 leaves a unchanged; a = 1 stays 1.
float specaa_filter_projected_isotropic(float alpha2, float kernel) {
    float k = min(kernel, SPECAA_MAX_KERNEL) * (1.0 - alpha2);
    return (alpha2 + k) / (1.0 + k);
}

// Approximate filtering a' = min(1, a + t), TK21 Eq. (9) (the bake's --filter approx).
float specaa_filter_approx_isotropic(float alpha2, float kernel) { return min(1.0, alpha2 + kernel); }

// Reductions of a covariance Sigma to an isotropic kernel t (SPEC Sec. 3): mean tr(Sigma) (Eq. 14
// analogue), sum 2 tr(Sigma) (Eq. 13), max 2 lambda_max(Sigma) (Eq. 10).
float specaa_reduce_mean(SPECAA_FLOAT3 sigma) { return sigma.x + sigma.y; }
float specaa_reduce_sum(SPECAA_FLOAT3 sigma) { return 2.0 * (sigma.x + sigma.y); }
float specaa_reduce_max(SPECAA_FLOAT3 sigma) { return 2.0 * specaa_sym_max_eigenvalue(sigma); }

// ---------------------------------------------------------------------------------------------------
// Baked textures (SPEC Sec. 3), sampled at the hardware-selected mip.
// ---------------------------------------------------------------------------------------------------

// a = r^4 from perceptual roughness r (SPEC Sec. 2), and back.
float specaa_alpha2_from_roughness(float r) { float alpha = r * r; return alpha * alpha; }
float specaa_roughness_from_alpha2(float alpha2) { return sqrt(sqrt(max(alpha2, 0.0))); }

// Baked filtered roughness mips: returns a of channel SPECAA_ROUGHNESS_CHANNEL (perceptual r).
float specaa_sample_roughness(SPECAA_TEXTURE_PARAMS(tex, smp), SPECAA_FLOAT2 uv) {
    return specaa_alpha2_from_roughness(SPECAA_SAMPLE(tex, smp, uv).SPECAA_ROUGHNESS_CHANNEL);
}

// Baked isotropic kernel mips: t in channel R.
// A non-finite texel gives a zero kernel (edge policy).
float specaa_sample_kernel(SPECAA_TEXTURE_PARAMS(tex, smp), SPECAA_FLOAT2 uv) {
    float t = SPECAA_SAMPLE(tex, smp, uv).r;
    return SPECAA_SELECT(specaa_is_finite(t), max(t, 0.0), 0.0);
}

// Baked anisotropic kernel mips: Sigma = (xx, yy, xy) in RGB (A: the rough share below); clamped to PSD
// after filtering.
SPECAA_FLOAT3 specaa_sample_kernel_covariance(SPECAA_TEXTURE_PARAMS(tex, smp), SPECAA_FLOAT2 uv) {
    SPECAA_FLOAT3 sigma = specaa_sym_clamp_psd(SPECAA_SAMPLE(tex, smp, uv).rgb);
    return SPECAA_SELECT3(specaa_is_finite3(sigma), sigma, SPECAA_FLOAT3(0.0, 0.0, 0.0));
}

// Rough share g of a baked Sigma kernel texel (alpha channel): the part of its normals steeper than slope
// 0.02, which holds all of Sigma (specaa_default_D). Non-finite or absent (1) gives the single lobe.
float specaa_rough_share(float g) { return SPECAA_SELECT(specaa_is_finite(g), SPECAA_SATURATE(g), 1.0); }
float specaa_sample_kernel_rough_share(SPECAA_TEXTURE_PARAMS(tex, smp), SPECAA_FLOAT2 uv) {
    return specaa_rough_share(SPECAA_SAMPLE(tex, smp, uv).a);
}

// The Sigma kernel texel as stored (Sigma.xx, Sigma.yy, Sigma.xy, g), with the diagnostics' mip choice.
SPECAA_FLOAT4 specaa_sample_kernel_raw(SPECAA_TEXTURE_PARAMS(tex, smp), SPECAA_FLOAT2 uv) {
#if defined(SPECAA_KERNEL_LOD_BIAS)
    SPECAA_FLOAT4 t = SPECAA_SAMPLE_BIAS(tex, smp, uv, SPECAA_KERNEL_LOD_BIAS);
#elif defined(SPECAA_KERNEL_AREA_LOD)
    // The derivatives scaled by sqrt(area) / major axis: the isotropic LOD of the result is the footprint's
    // area, not its major axis.
    SPECAA_FLOAT2 gx = SPECAA_DDX(uv), gy = SPECAA_DDY(uv);
    float major2 = max(dot(gx, gx), dot(gy, gy));
    float scale = sqrt(abs(gx.x * gy.y - gx.y * gy.x) / max(major2, 1.0e-30));
    SPECAA_FLOAT4 t = SPECAA_SAMPLE_GRAD(tex, smp, uv, gx * scale, gy * scale);
#else
    SPECAA_FLOAT4 t = SPECAA_SAMPLE(tex, smp, uv);
#endif
    return t;
}

// Both from one fetch: (Sigma.xx, Sigma.yy, Sigma.xy, g), Sigma clamped to PSD (zero if not finite).
SPECAA_FLOAT4 specaa_sample_kernel_texel(SPECAA_TEXTURE_PARAMS(tex, smp), SPECAA_FLOAT2 uv) {
    SPECAA_FLOAT4 t = specaa_sample_kernel_raw(SPECAA_TEXTURE_ARGS(tex, smp), uv);
    SPECAA_FLOAT3 sigma = specaa_sym_clamp_psd(t.rgb);
    return SPECAA_FLOAT4(SPECAA_SELECT3(specaa_is_finite3(sigma), sigma, SPECAA_FLOAT3(0.0, 0.0, 0.0)),
                         specaa_rough_share(t.a));
}

// Covariance from LEAN moments, Sigma = M - m m^T clamped to PSD (SPEC Sec. 3; C21 Eq. 16).
// lean0 = (m.x, m.y, M.xx, M.yy), lean1 = M.xy. Moments filter linearly, so any mip/trilinear mix of
// them still yields the covariance of the normals in the filtered footprint. Non-finite moments give 0.
SPECAA_FLOAT3 specaa_lean_covariance(SPECAA_FLOAT4 lean0, float lean1) {
    SPECAA_FLOAT3 sigma = specaa_sym_clamp_psd(SPECAA_FLOAT3(lean0.z - lean0.x * lean0.x,
                                                             lean0.w - lean0.y * lean0.y,
                                                             lean1 - lean0.x * lean0.y));
    return SPECAA_SELECT3(specaa_is_finite3(sigma), sigma, SPECAA_FLOAT3(0.0, 0.0, 0.0));
}

// Baked mean normal (`*_normal`, docs/texture-bake.md#output-layouts), tangent space, unit length. Two-channel texels
// (BC5 under `--block bc`, ASTC's (x, y, 0, 1) under `--block astc`) hold x, y as (n + 1) / 2: z = sqrt(max(0, 1 - x^2 - y^2)) (the mean normal lies in
// the upper hemisphere), renormalised where filtering or quantisation put (x, y) outside the unit disc.
// RGB texels hold (n + 1) / 2, renormalised after filtering; a zero vector gives (0, 0, 1).
SPECAA_FLOAT3 specaa_decode_normal_xy(SPECAA_FLOAT2 texel) {
    SPECAA_FLOAT2 xy = texel * 2.0 - 1.0;
    SPECAA_FLOAT3 n = SPECAA_FLOAT3(xy, sqrt(max(0.0, 1.0 - dot(xy, xy))));
    return n / sqrt(dot(n, n));  // |n| >= 1 (z = 1 at xy = 0): no division by zero
}
SPECAA_FLOAT3 specaa_decode_normal_rgb(SPECAA_FLOAT3 texel) {
    SPECAA_FLOAT3 n = texel * 2.0 - 1.0;
    float l2 = dot(n, n);
    return SPECAA_SELECT3(l2 > 0.0, n / sqrt(max(l2, 1.0e-30)), SPECAA_FLOAT3(0.0, 0.0, 1.0));
}
// The baked mean normal at uv: two channels with SPECAA_NORMAL_TWO_CHANNEL (BC5, ASTC), else RGB(A).
SPECAA_FLOAT3 specaa_sample_mean_normal(SPECAA_TEXTURE_PARAMS(tex, smp), SPECAA_FLOAT2 uv) {
#if defined(SPECAA_NORMAL_TWO_CHANNEL)
    return specaa_decode_normal_xy(SPECAA_SAMPLE(tex, smp, uv).rg);
#else
    return specaa_decode_normal_rgb(SPECAA_SAMPLE(tex, smp, uv).rgb);
#endif
}

// LEAN lookup from the two moment textures (layout in the header comment).
SPECAA_FLOAT3 specaa_sample_lean(SPECAA_TEXTURE_PARAMS(tex0, smp0), SPECAA_TEXTURE_PARAMS(tex1, smp1),
                                 SPECAA_FLOAT2 uv) {
    return specaa_lean_covariance(SPECAA_SAMPLE(tex0, smp0, uv), SPECAA_SAMPLE(tex1, smp1, uv).r);
}

// ---------------------------------------------------------------------------------------------------
// Curvature-based kernel from the _SPECAA_CURVATURE attribute (SPEC Sec. 4) and the pixel footprint.
// ---------------------------------------------------------------------------------------------------

// Shape operator S = k1 d d^T + k2 d' d'^T (d' = d rotated by 90 degrees) in the tangent frame from
// curvature = (k1, k2, d.x, d.y). The normal moves by dp = -S dx for a tangent step dx (first order), so
// S maps the footprint to projected-normal derivatives. A zero d (umbilic) uses k1 on both axes.
SPECAA_FLOAT3 specaa_shape_operator(SPECAA_FLOAT4 curvature) {
    float len = length(curvature.zw);
    if (len < 1.0e-6) return SPECAA_FLOAT3(curvature.x, curvature.x, 0.0);
    SPECAA_FLOAT2 d = curvature.zw / len;
    float k1 = curvature.x;
    float k2 = curvature.y;
    return SPECAA_FLOAT3(k1 * d.x * d.x + k2 * d.y * d.y,
                         k1 * d.y * d.y + k2 * d.x * d.x,
                         (k1 - k2) * d.x * d.y);
}

// Pixel footprint in the tangent plane: the position derivatives along screen x and y expressed in the
// (T, B) frame, returned as (u.x, u.y, v.x, v.y). Units of the positions (object space for the curvature).
SPECAA_FLOAT4 specaa_footprint_tangent(SPECAA_FLOAT3 dPdx, SPECAA_FLOAT3 dPdy, SPECAA_FLOAT3 tangent,
                                       SPECAA_FLOAT3 bitangent) {
    SPECAA_FLOAT3 t = normalize(tangent);
    SPECAA_FLOAT3 b = normalize(bitangent);
    return SPECAA_FLOAT4(dot(dPdx, t), dot(dPdx, b), dot(dPdy, t), dot(dPdy, b));
}

// Pixel footprint from the quad derivatives of the interpolated position (same space as T, B).
SPECAA_FLOAT4 specaa_footprint(SPECAA_FLOAT3 position, SPECAA_FLOAT3 tangent, SPECAA_FLOAT3 bitangent) {
    return specaa_footprint_tangent(SPECAA_DDX(position), SPECAA_DDY(position), tangent, bitangent);
}

// Width of one pixel on a plane facing the camera at view depth z (perspective, vertical field of view
// with tan(fovY/2), viewport height in pixels): 2 z tan(fovY/2) / height. Grazing elongation is ignored.
float specaa_pixel_footprint_from_depth(float viewDepth, float tanHalfFovY, float viewportHeight) {
    return 2.0 * viewDepth * tanHalfFovY / viewportHeight;
}

// Curvature kernel matrix K = 2 sigma^2 (S u u^T S + S v v^T S), TK21 Eq. (3) with the projected-normal
// derivatives S u, S v of the curved shading-normal field (K16 "virtual quadric") instead of quad
// differences. footprint = (u.x, u.y, v.x, v.y) from specaa_footprint*.
// turn: the half vector's turn per screen axis in the same frame, (x.t, x.b, y.t, y.b) (specaa_view_turn),
// taken off the normal's: the spread of h relative to n over the footprint.
SPECAA_FLOAT3 specaa_curvature_kernel_turned(SPECAA_FLOAT4 curvature, SPECAA_FLOAT4 footprint, SPECAA_FLOAT4 turn) {
    SPECAA_FLOAT3 S = specaa_shape_operator(curvature);
    SPECAA_FLOAT2 du = SPECAA_FLOAT2(S.x * footprint.x + S.z * footprint.y, S.z * footprint.x + S.y * footprint.y);
    SPECAA_FLOAT2 dv = SPECAA_FLOAT2(S.x * footprint.z + S.z * footprint.w, S.z * footprint.z + S.y * footprint.w);
    return specaa_kernel_matrix(du - turn.xy, dv - turn.zw);
}

// The normal's spread alone (no turn of the half vector).
SPECAA_FLOAT3 specaa_curvature_kernel(SPECAA_FLOAT4 curvature, SPECAA_FLOAT4 footprint) {
    return specaa_curvature_kernel_turned(curvature, footprint, SPECAA_FLOAT4(0.0, 0.0, 0.0, 0.0));
}

// Isotropic curvature kernel for a square footprint of width w: mean reduction tr(Sigma) =
// sigma^2 w^2 (k1^2 + k2^2) (TK21 Eq. 14 with |dn| = |k| w per principal direction).
float specaa_curvature_kernel_isotropic(SPECAA_FLOAT4 curvature, float footprintWidth) {
    return SPECAA_SIGMA2 * footprintWidth * footprintWidth * (curvature.x * curvature.x + curvature.y * curvature.y);
}

// ---------------------------------------------------------------------------------------------------
// GGX and Beckmann with a roughness matrix A (TK21 Sec. 2.1, App. A).
// ---------------------------------------------------------------------------------------------------

// Clamped determinant max(det(A), tau) of TK21 App. A.4 (tau = alpha_x^2 alpha_y^2 of the unfiltered
// material), floored at 1e-30 so a mirror (A = 0, tau = 0) stays finite instead of a Dirac delta.
float specaa_clamped_det(SPECAA_FLOAT3 A, float tau) { return max(max(specaa_sym_det(A), tau), 1.0e-30); }

// [h.x, h.y] A^-1 [h.x, h.y]^T with A^-1 = adj(A) / detClamped (TK21 App. A.4).
float specaa_inverse_quadratic_form(SPECAA_FLOAT3 A, SPECAA_FLOAT2 v, float detClamped) {
    return (v.x * v.x * A.y - 2.0 * v.x * v.y * A.z + v.y * v.y * A.x) / detClamped;
}

// GGX NDF, TK21 Eq. (1) with the determinant clamp of App. A.4. 0 for h.z <= 0.
float specaa_ggx_D(SPECAA_FLOAT3 h, SPECAA_FLOAT3 A, float tau) {
    if (h.z <= 0.0) return 0.0;
    float detClamped = specaa_clamped_det(A, tau);
    float q = specaa_inverse_quadratic_form(A, h.xy, detClamped) + h.z * h.z;
    return 1.0 / (SPECAA_PI * sqrt(detClamped) * q * q);
}

// Beckmann NDF with a roughness matrix, TK21 Sec. 2.1, same clamp. 0 for h.z <= 0.
float specaa_beckmann_D(SPECAA_FLOAT3 h, SPECAA_FLOAT3 A, float tau) {
    if (h.z <= 0.0) return 0.0;
    float detClamped = specaa_clamped_det(A, tau);
    float z2 = h.z * h.z;
    return exp(-specaa_inverse_quadratic_form(A, h.xy, detClamped) / z2) /
           (SPECAA_PI * sqrt(detClamped) * z2 * z2);
}

// NDF of a filtered lobe with the tails of the unfiltered material (TK21 Sec. 7). Widening GGX to
// A = a I + K also raises its tails: along the direction u of h.xy GGX(A) falls as
// 1 / (pi sqrt(det A) (u^T A^-1 u)^2 theta^4), while the footprint's true NDF (GGX(a) spread by the
// footprint's normal distribution) keeps the tails of GGX(a), ~ a / (pi theta^4). Along the widened axis
// of an anisotropic A (a grazing footprint) the excess is (K/a)^(3/2), not K/a. The mixture
// rho GGX(A) + (1 - rho) Beckmann(A) with rho = a sqrt(det A) (u^T A^-1 u)^2 (clamped to [0, 1]) keeps the
// width of the filtered lobe, has exactly the unfiltered tail in every direction and integrates to one
// like both parts (along each ray of slopes their difference integrates to zero); with K = 0 it is
// GGX(a). `alpha2` is the unfiltered a of the material.
float specaa_filtered_D(SPECAA_FLOAT3 h, SPECAA_FLOAT3 A, float alpha2) {
    float tau = alpha2 * alpha2;
    float detClamped = specaa_clamped_det(A, tau);
    float r2 = dot(h.xy, h.xy);
    float q = r2 > 0.0 ? specaa_inverse_quadratic_form(A, h.xy, detClamped) / r2 : 1.0 / sqrt(detClamped);
    float rho = SPECAA_SATURATE(alpha2 * sqrt(detClamped) * q * q);
    float ggx = specaa_ggx_D(h, A, tau);
    return ggx + (1.0 - rho) * (specaa_beckmann_D(h, A, tau) - ggx);
}

// specaa_filtered_D for an isotropic A = f I (the fast tier's NDF): rho GGX(g) + (1 - rho) Beckmann(f_b), a
// two-lobe stand-in for GGX(a) convolved with the footprint k = f - a (specaa_convolved_D) that keeps the
// unfiltered lobe's tails exactly and integrates to one: rho g = a, so the GGX part falls as
// a / (pi tan^4(theta_h)) like GGX(a) (TK21 Sec. 7), and each part integrates to one. With g = f_b = f
// (rho = a / f; the tier's NDF before, `SPECAA_FAST_PLAIN_MIXTURE`) the peak is 1.24 / 1.14x the
// convolution's for k = a / 10 a and the flanks 0.70 / 0.49x (tan^2 = 6.5-11 f): 51% largest relative
// error. A narrower GGX part, g = min(f, 1.8 sqrt(a f)) (its share a / g larger), fills the flanks and a
// wider Beckmann part, f_b = f + 1.2 sqrt(a f) - 0.6 a, lowers the peak: (g, f_b) fitted in that form to the
// convolution (its scale-mixture integral in double) for the smallest largest relative error over k / a in
// [1e-2, 1e3] and tan^2 / a in [0, 1e6]: 30% (docs/accuracy.md#the-fast-tiers-ndf). Stable forms:
// a / (pi (g h_z^2 + |h.xy|^2)^2) (finite as h_z -> 0), Beckmann e^(-u / f_b) (1 + u)^2 / (pi f_b) with
// u = tan^2(theta_h) bounded where the exponential is 0; 0 for h_z <= 0. f and g are floored at 1e-12 so that
// a mirror stays finite. C++ twin: bake/ggx.cpp filtered_ndf_isotropic.
float specaa_filtered_D_isotropic(SPECAA_FLOAT3 h, float alpha2, float filteredAlpha2) {
    float f = max(filteredAlpha2, 1.0e-12);
    float a = min(alpha2, f);
    float r2 = dot(h.xy, h.xy);
    float z2 = h.z * h.z;
#if defined(SPECAA_FAST_PLAIN_MIXTURE)
    float g = f;
    float fb = f;
#else
    float t = sqrt(a * f);  // in [a, f]
    float g = max(min(f, 1.8 * t), 1.0e-12);  // a mirror (a = 0): no GGX part
    float fb = f + 1.2 * t - 0.6 * a;
#endif
    float s2 = g * z2 + r2;
    // tan^2(theta_h), bounded so that (1 + u)^2 stays finite where e^(-u / f_b) is 0 (h_z -> 0).
    float u = min(r2 / z2, 1.0e18);
    float beckmann = exp(-u / fb) * (1.0 + u) * (1.0 + u) / (SPECAA_PI * fb);
    return SPECAA_SELECT(h.z > 0.0, beckmann * (1.0 - a / g) + a / (SPECAA_PI * s2 * s2), 0.0);
}

// NDF of GGX(alpha2) seen through the pixel footprint: GGX(a) convolved with the footprint's distribution
// of slopes, N(0, K / 2) with K = A - a I (TK21 Eq. 3: the kernel is twice the footprint's slope
// covariance). GGX is a Gaussian scale mixture (a bivariate Student t with two degrees of freedom):
// GGX(a) = int_0^inf e^-w Beckmann(a / w I) dw, so the convolution is, exactly,
// int_0^inf e^-w Beckmann(a / w I + K) dw: a core as wide as the footprint and the unfiltered lobe's own
// tails (from the small w), where GGX(A) widens both (its tails K / a too heavy) and specaa_filtered_D's
// Beckmann part undershoots between them. Evaluated by the trapezoid rule in ln w, steps of at most 1.1,
// from w_lo = 0.05 min(1, a / k_max) to 10 (e^-10 of the weight is left out; 12 to 32 nodes), and the
// part below w_lo in closed form (a / w >= 20 k_max) with Beckmann(a / w I + K) to first order in K:
// int_0^w_lo w e^(-w (1 + c)) (1 + q w^2 / a^2 - tr(K) w / (2 a)) dw / (pi a h_z^4), c = tan^2(theta_h) / a,
// q = h.xy^T K h.xy / h_z^2 (in the tails most of the lobe lies there). That sum's own error (about 1% in
// the tails, from the node at w_lo) exceeds what a footprint much smaller than the lobe changes there, so
// for k_max < a the same nodes also sum the K = 0 integrand and the result is GGX(a) + (sum_K - sum_0):
// exact as K -> 0, its error a fraction of the footprint's effect; from k_max = a / 10 to a it blends
// (in log k_max) into the direct sum. Relative error against a dense quadrature under 0.1% for
// K / a <= 0.1, 1.6% to K / a = 3, 4% beyond, out to tan^2 = 2 (tests/bake/test_ggx.cpp checks it
// against a brute-force convolution to 4%, and the small-footprint effect to 10% of itself).
// GGX(A) itself where k_max <= 1e-3 a (within 0.1%).
// `alpha2` is the a the footprint spreads: the material's, or the baked roughness texture's.
float specaa_convolved_D(SPECAA_FLOAT3 h, SPECAA_FLOAT3 A, float alpha2) {
    if (h.z <= 0.0) return 0.0;
    float a = max(alpha2, 1.0e-12);
    // The added kernel, projected onto the PSD cone (an anisotropic material's A - a I can be indefinite).
    SPECAA_FLOAT3 K = specaa_sym_clamp_psd(A - SPECAA_FLOAT3(a, a, 0.0));
    float kmax = max(specaa_sym_max_eigenvalue(K), 0.0);
    // No footprint to speak of: GGX(A), floored at 1e-12 I so that a mirror (A = 0) stays finite off its peak.
    if (kmax <= 1.0e-3 * a) return specaa_ggx_D(h, A + SPECAA_FLOAT3(1.0e-12, 1.0e-12, 0.0), a * a);
    float wlo = 0.05 * min(1.0, a / kmax);
    float slo = log(wlo);
    float range = log(10.0) - slo;
    int nodes = int(clamp(ceil(range / 1.1), 11.0, 31.0)) + 1;
    float ds = range / float(nodes - 1);
    float z2 = h.z * h.z;
    float c = dot(h.xy, h.xy) / (z2 * a);
    float unit = 1.0 / (SPECAA_PI * a * z2 * z2);
    float sum = 0.0;
    float sumUnfiltered = 0.0;
    for (int j = 0; j < 32; ++j) {
        if (j >= nodes) break;
        float w = exp(slo + ds * float(j));
        float v = a / w;
        float weight = (j == 0 || j == nodes - 1) ? 0.5 : 1.0;
        sum += weight * exp(-w) * w * specaa_beckmann_D(h, K + SPECAA_FLOAT3(v, v, 0.0), v * v);
        sumUnfiltered += weight * exp(-w * (1.0 + c)) * w * w * unit;  // Beckmann(a / w I)
    }
    // Below w_lo, Beckmann(a / w I + K) to first order in K, integrated in closed form (series where the
    // closed forms cancel in float): I1 + q I3 / a^2 - tr(K) I2 / (2 a), In = int_0^w_lo w^n e^(-w (1 + c)) dw.
    float c1 = 1.0 + c;
    float x = c1 * wlo;
    float e = exp(-x);
    float below = x > 1.0e-2 ? (1.0 - e * (1.0 + x)) / (c1 * c1) : wlo * wlo * (0.5 - x / 3.0);
    float p2 = 1.0 + x + 0.5 * x * x;
    float wlo3 = wlo * wlo * wlo;
    float i2 = x < 0.5 ? wlo3 * (1.0 / 3.0 - x / 4.0 + x * x / 10.0 - x * x * x / 36.0) : 2.0 * (1.0 - e * p2) / (c1 * c1 * c1);
    float i3 = x < 0.5 ? wlo3 * wlo * (0.25 - x / 5.0 + x * x / 12.0 - x * x * x / 42.0)
                       : 6.0 * (1.0 - e * (p2 + x * x * x / 6.0)) / (c1 * c1 * c1 * c1);
    float q = (h.x * h.x * K.x + 2.0 * h.x * h.y * K.z + h.y * h.y * K.y) / z2;
    float firstOrder = q / (a * a) * i3 - 0.5 * (K.x + K.y) / a * i2;
    float direct = sum * ds + (below + firstOrder) * unit;
    float difference = max(0.0, specaa_ggx_D(h, SPECAA_FLOAT3(a, a, 0.0), a * a) + (sum - sumUnfiltered) * ds + firstOrder * unit);
    float blend = SPECAA_SATURATE(log2(10.0 * kmax / a) * 0.30103);
    float D = difference + blend * (direct - difference);
    // Grazing half vectors (h_z^4 below float's range) overflow the sums; the convolution is GGX(a)'s tail
    // there, a / (pi (|h.xy|^2 + a h_z^2)^2).
    float s2 = dot(h.xy, h.xy) + a * z2;
    return SPECAA_SELECT(specaa_is_finite(D), D, a / (SPECAA_PI * s2 * s2));
}

// specaa_convolved_D without the loop (SPECAA_QUALITY balanced): the same convolution of GGX(a) with the
// footprint, int_0^inf e^-w Beckmann(a / w I + K) dw, with k = tr(K) / 2 (the mean reduction) and b = k / a.
// Its lobes wider than k (w < 1 / b) are taken without K: GGX(a)'s scale mixture truncated there, in closed
// form, a (1 - e^-L (1 + L)) / (pi (|h.xy|^2 + a h_z^2)^2) with L = (tan^2(theta_h) + a) / k, which carries
// GGX(a)'s tails and the mass 1 - e^(-1/b). The rest, mass e^(-1/b), is two Beckmann lobes
// Beckmann(a e^(-p_i) I + K) with weights w1 (q b / (1 + b) for b < 10^-0.25, e^(-1/b) / (1 + e^-q) above)
// and w2 = e^(-1/b) - w1, so D integrates to one whatever the fit. (p1, q, p2) are cubics in log10(b) fitted
// to the isotropic convolution (minimax relative error over tan^2(theta_h) / a in [0, 1e7] and b in
// [1e-3, 1e4]; b is clamped to that range). Largest relative error of D against the convolution: 9.5% for
// an isotropic K (the fit; 8.7% against a brute-force convolution in tests/bake/test_ggx.cpp), up to 70%
// for a strongly anisotropic one (k_max / k_min = 40), whose slopes between its two widths fall as a power
// the isotropic truncated mixture does not have; the integral over the hemisphere is one. Below k = 0.1 a
// the fit's error would exceed the change the footprint makes (a smooth sphere's highlight would flicker
// more than unfiltered, docs/accuracy.md#the-convolutions-accuracy), so there it blends (log-linearly from
// k = 0.1 a) into the convolution's second-order expansion, alone below k = 0.03 a, exact as K -> 0
// (specaa_small_footprint_D). C++ twin: bake/ggx.cpp convolved_ndf_closed_form.

// (w1, w2, e^-p1, e^-p2) of the closed form's two nodes at b = k / a.
SPECAA_FLOAT4 specaa_closed_form_nodes(float b) {
    float z = clamp(log2(b) * 0.30102999566, -3.0, 4.0);
    // (p1, q, p2) by Horner's rule, one coefficient vector per power of z.
    SPECAA_FLOAT3 c0 = z < -0.25 ? SPECAA_FLOAT3(13.4053507, 0.175485909, -0.78612125)
                                 : SPECAA_FLOAT3(-0.589765801, 2.49577999, -2.55947913);
    SPECAA_FLOAT3 c1 = z < -0.25 ? SPECAA_FLOAT3(18.6896586, 0.837682955, 0.779175295)
                                 : SPECAA_FLOAT3(1.15587235, 0.554438611, -0.177032328);
    SPECAA_FLOAT3 c2 = z < -0.25 ? SPECAA_FLOAT3(8.00904241, -0.121406802, 1.05666563)
                                 : SPECAA_FLOAT3(-1.77857435, 0.921497471, -1.03833038);
    SPECAA_FLOAT3 c3 = z < -0.25 ? SPECAA_FLOAT3(0.357309142, -0.297962248, -0.559140109)
                                 : SPECAA_FLOAT3(0.425394192, -0.115584935, 0.133253855);
    SPECAA_FLOAT3 p = c0 + z * (c1 + z * (c2 + z * c3));
    float rest = exp(-1.0 / b);
    float w1 = SPECAA_SELECT(z < -0.25, p.y * b / (1.0 + b), rest / (1.0 + exp(-p.y)));  // selects: no branch
    return SPECAA_FLOAT4(w1, rest - w1, exp(-p.x), exp(-p.z));
}

// The truncated mixture of the closed form (GGX(a)'s lobes wider than k), r2 = |h.xy|^2, z2 = h_z^2 > 0.
float specaa_closed_form_tail(float r2, float z2, float a, float k) {
    float L = (r2 / z2 + a) / k;
    float Lc = min(L, 80.0);  // e^-L (1 + L) below float's range beyond (and no inf * 0 at h_z = 0)
    float s2 = r2 + a * z2;
    return SPECAA_SELECT(L > 0.05, a * (1.0 - exp(-Lc) * (1.0 + Lc)) / (SPECAA_PI * s2 * s2),
                         (0.5 - L / 3.0 + L * L / 8.0) * a / (SPECAA_PI * k * k * z2 * z2));
}

// GGX(a) convolved with a small footprint, to second order in K (the convolution's Taylor expansion, written
// for the isotropic slope density f(q) = 1 / (pi a (1 + q / a)^2): f + f' tr(K) / 2 + f'' m^T K m):
// a / (pi s2^2) (1 - tr(K) h_z^2 / s2 + 6 h.xy^T K h.xy h_z^2 / s2^2), s2 = a h_z^2 + |h.xy|^2 (finite as
// h_z -> 0). Exact as K -> 0, within 0.6% of D at k = 0.03 a; trK = tr(K), hKh = h.xy^T K h.xy.
float specaa_small_footprint_D(float r2, float z2, float a, float trK, float hKh) {
    float s2 = a * z2 + r2;
    return a / (SPECAA_PI * s2 * s2) * (1.0 - trK * z2 / s2 + 6.0 * hKh * z2 / (s2 * s2));
}

// Share of the fitted nodes in the closed form: 0 (the second-order expansion) below k = 0.03 a, where
// the fit's error would exceed the change the footprint makes, 1 above k = 0.1 a, log-linear between.
float specaa_closed_form_share(float b) { return SPECAA_SATURATE((log2(b) * 0.30102999566 + 1.5228787) * 1.9124059); }

// Beckmann(K + v I) (TK21 Sec. 2.1), 0 where its exponential underflows (h_z -> 0).
float specaa_beckmann_node(SPECAA_FLOAT3 h, SPECAA_FLOAT3 K, float v) {
    SPECAA_FLOAT3 B = K + SPECAA_FLOAT3(v, v, 0.0);
    float detB = max(specaa_sym_det(B), 1.0e-30);
    float z2 = h.z * h.z;
    float g = exp(-specaa_inverse_quadratic_form(B, h.xy, detB) / z2);
    return g > 0.0 ? g / (SPECAA_PI * sqrt(detB) * z2 * z2) : 0.0;
}

// The closed form for a roughness matrix A (K = A - a I projected onto the PSD cone, as specaa_convolved_D);
// GGX(A) itself where k_max <= 1e-3 a. `alpha2` is the a the footprint spreads.
float specaa_convolved_D_closed_form(SPECAA_FLOAT3 h, SPECAA_FLOAT3 A, float alpha2) {
    if (h.z <= 0.0) return 0.0;
    float a = max(alpha2, 1.0e-12);
    SPECAA_FLOAT3 K = specaa_sym_clamp_psd(A - SPECAA_FLOAT3(a, a, 0.0));
    if (max(specaa_sym_max_eigenvalue(K), 0.0) <= 1.0e-3 * a)
        return specaa_ggx_D(h, A + SPECAA_FLOAT3(1.0e-12, 1.0e-12, 0.0), a * a);
    float k = max(0.5 * (K.x + K.y), 1.0e-6 * a);
    SPECAA_FLOAT4 n = specaa_closed_form_nodes(k / a);
    float nodes = n.x * specaa_beckmann_node(h, K, a * n.z) + n.y * specaa_beckmann_node(h, K, a * n.w);
    float r2 = dot(h.xy, h.xy);
    float z2 = h.z * h.z;
    float fitted = specaa_closed_form_tail(r2, z2, a, k) + nodes;
    float hKh = h.x * h.x * K.x + 2.0 * h.x * h.y * K.z + h.y * h.y * K.y;
    float small = specaa_small_footprint_D(r2, z2, a, K.x + K.y, hKh);
    float share = specaa_closed_form_share(k / a);  // written out: the expansion is huge and wrong at large k
    return max(0.0, share * fitted + (1.0 - share) * small);
}

// The closed form for an isotropic footprint K = k I (the balanced tier's, whose A is isotropic): no matrix
// algebra; k = 0 is GGX(a).
float specaa_convolved_D_isotropic(SPECAA_FLOAT3 h, float alpha2, float kernel) {
    float a = max(alpha2, 1.0e-12);
    float k = max(kernel, 1.0e-6 * a);
    SPECAA_FLOAT4 n = specaa_closed_form_nodes(k / a);
    float z2 = h.z * h.z;
    float r2 = dot(h.xy, h.xy);
    SPECAA_FLOAT2 v = k + a * n.zw;  // the nodes' widths
    SPECAA_FLOAT2 g = exp(-r2 / (z2 * v));
    float unit = SPECAA_PI * z2 * z2;
    // Selects rather than branches (both sides are evaluated; the discarded one may be inf or NaN at h_z = 0).
    float nodeX = SPECAA_SELECT(g.x > 0.0, n.x * g.x / (unit * v.x), 0.0);
    float nodeY = SPECAA_SELECT(g.y > 0.0, n.y * g.y / (unit * v.y), 0.0);
    float nodes = nodeX + nodeY;
    float fitted = specaa_closed_form_tail(r2, z2, a, k) + nodes;
    float small = specaa_small_footprint_D(r2, z2, a, 2.0 * k, k * r2);
    float share = specaa_closed_form_share(k / a);  // written out: the expansion is huge and wrong at large k
    return SPECAA_SELECT(h.z > 0.0, max(0.0, share * fitted + (1.0 - share) * small), 0.0);
}

// GGX Smith Lambda, TK21 App. A.3: -1/2 + sqrt(s + o.z^2) / (2 |o.z|), s = [o.x, o.y] A [o.x, o.y]^T,
// evaluated as s / (2 |o.z| (sqrt(s + o.z^2) + |o.z|)) (same value, no cancellation for smooth A).
// +inf at o.z = 0 with s > 0.
float specaa_ggx_lambda(SPECAA_FLOAT3 o, SPECAA_FLOAT3 A) {
    float s = o.x * o.x * A.x + 2.0 * o.x * o.y * A.z + o.y * o.y * A.y;
    float z = abs(o.z);
    return s / (2.0 * z * (sqrt(s + z * z) + z));
}

// Height-correlated G2 = chi+(i.h) chi+(o.h) / (1 + Lambda(i) + Lambda(o)), TK21 App. A.1, evaluated as
// 2 |i.z| |o.z| / (|o.z| sqrt(q_i) + |i.z| sqrt(q_o)) (same expression times 2 |i.z| |o.z|), which is
// finite at grazing i or o (G2 -> 0). In [0, 1].
float specaa_ggx_G2(SPECAA_FLOAT3 i, SPECAA_FLOAT3 o, SPECAA_FLOAT3 h, SPECAA_FLOAT3 A) {
    if (dot(i, h) <= 0.0 || dot(o, h) <= 0.0) return 0.0;
    float qi = i.x * i.x * A.x + 2.0 * i.x * i.y * A.z + i.y * i.y * A.y + i.z * i.z;
    float qo = o.x * o.x * A.x + 2.0 * o.x * o.y * A.z + o.y * o.y * A.y + o.z * o.z;
    float denominator = abs(o.z) * sqrt(qi) + abs(i.z) * sqrt(qo);
    return denominator > 0.0 ? 2.0 * abs(i.z) * abs(o.z) / denominator : 0.0;
}

// ---------------------------------------------------------------------------------------------------
// Default entry point: filtered roughness from whatever baked data is bound plus a per-pixel kernel.
// The default rule is the matrix form, specaa_filtered_alpha2_matrix (an anisotropic per-pixel kernel
// in the tangent frame), with specaa_default_D (GGX convolved with the footprint where no normal-map data
// is baked) and specaa_ggx_G2: of the combinations `specbake bench` scores it has the lowest linear and
// tone-mapped error and flicker (docs/accuracy.md#the-rule). specaa_filtered_alpha2 /
// specaa_filtered_roughness are its isotropic form, a drop-in for BRDFs that take one roughness.
// ---------------------------------------------------------------------------------------------------

// Per-fragment inputs. Fill every field the configuration uses (see the header comment).
struct SpecaaSurface {
    float roughness;             // perceptual roughness r of the material (unused with a roughness texture)
    SPECAA_FLOAT2 uv;            // texture coordinates of the baked textures
    SPECAA_FLOAT3 normal;        // unit interpolated vertex normal (before normal mapping), any space
    SPECAA_FLOAT3 position;      // position in the space of tangent/bitangent (SPECAA_USE_CURVATURE)
    SPECAA_FLOAT3 tangent;       // T = TANGENT.xyz (matrix form, SPECAA_USE_CURVATURE)
    SPECAA_FLOAT3 bitangent;     // B = cross(N, T) * TANGENT.w
    SPECAA_FLOAT4 curvature;     // _SPECAA_CURVATURE (k1, k2, d.x, d.y) (SPECAA_USE_CURVATURE)
    SPECAA_FLOAT3 view;          // unit vector from the surface to the eye, in the space of normal and tangent
};

#if defined(SPECAA_ROUGHNESS_TEXTURE) && (defined(SPECAA_KERNEL_TEXTURE) || defined(SPECAA_LEAN_TEXTURE0))
#error "specaa: the baked roughness already contains the kernel; bind either the roughness or the kernel/LEAN textures"
#endif

// Squared roughness a of the material: the baked filtered roughness texture if bound, else r^4.
// Clamped to [0, 1], NaN as 1 (edge policy).
float specaa_base_alpha2(SpecaaSurface s) {
#if defined(SPECAA_ROUGHNESS_TEXTURE)
    return specaa_sanitize_alpha2(specaa_sample_roughness(SPECAA_TEXTURE_ARGS(SPECAA_ROUGHNESS_TEXTURE, SPECAA_SAMPLER), s.uv));
#else
    return specaa_sanitize_alpha2(specaa_alpha2_from_roughness(s.roughness));
#endif
}

// The normal map's spread at this fragment's mip as a kernel matrix, before the gate below (0 without
// kernel/LEAN data); an isotropic kernel texture gives K = t I.
SPECAA_FLOAT3 specaa_baked_spread_matrix(SpecaaSurface s) {
#if defined(SPECAA_NO_BAKED_KERNEL)
    return SPECAA_FLOAT3(0.0, 0.0, 0.0);
#elif defined(SPECAA_LEAN_TEXTURE0)
    return 2.0 * specaa_sample_lean(SPECAA_TEXTURE_ARGS(SPECAA_LEAN_TEXTURE0, SPECAA_SAMPLER),
                                    SPECAA_TEXTURE_ARGS(SPECAA_LEAN_TEXTURE1, SPECAA_SAMPLER), s.uv);
#elif defined(SPECAA_KERNEL_TEXTURE) && defined(SPECAA_KERNEL_ANISOTROPIC)
    // The single lobe of a texel with rough share g: K = 2 Sigma sqrt(g), not 2 Sigma. A texel of a flat
    // field with a few steep grooves or seams (g small) is a spike at the flat normal plus a wide rough
    // part; the Gaussian of its covariance spreads the spike's highlight over the grooves' slopes, while
    // the Gaussian closest to the mixture in L2 (the radiance error over half vectors) is far narrower
    // (K / (2 Sigma) = 0.11-0.24 at g = 0.1-0.5 for a rough part 10x the material's lobe). The covariance
    // is what keeps the rough part's sparkle down where it is lit; sqrt(g) sits between the two ends
    // (g^0 and g^1). g = 1 (every texel steep, or bakes before the rough share) is the covariance itself.
    // The measurements (g^0, g^0.25, g^0.5, g^0.75, g^1): docs/accuracy.md#the-single-lobe-of-a-mixed-texel.
    SPECAA_FLOAT4 k = specaa_sample_kernel_texel(SPECAA_TEXTURE_ARGS(SPECAA_KERNEL_TEXTURE, SPECAA_SAMPLER), s.uv);
#if defined(SPECAA_KERNEL_COVARIANCE)
    return 2.0 * k.xyz;
#else
    return (2.0 * sqrt(k.w)) * k.xyz;
#endif
#elif defined(SPECAA_KERNEL_TEXTURE)
    float t = specaa_sample_kernel(SPECAA_TEXTURE_ARGS(SPECAA_KERNEL_TEXTURE, SPECAA_SAMPLER), s.uv);
    return SPECAA_FLOAT3(t, t, 0.0);
#else
    return SPECAA_FLOAT3(0.0, 0.0, 0.0);
#endif
}

// Baked kernel matrix of the default: the spread above, faded out where it is much narrower than the
// material's lobe, K f^2 with f = saturate(lambda_max(K) / (SPECAA_KERNEL_GATE a)) (NaN passes through
// for the guards downstream). A spread far below a changes D by a small fraction, and on a smooth bump
// map under a rough material (the normal-mapped sphere at alpha 0.2-0.5) that change raised the flicker
// above no filtering's (alpha 0.2: 1.0025x tone-mapped, 0.3: 1.017x, 0.5: 1.012x); no filtering's flicker
// there is the engine's trilinear sampling of the mean normal, which no widening of the lobe removes.
// Kernels of half of a or more pass whole. docs/accuracy.md#the-gate has the forms measured (gates 0.25, 0.5
// and 1, linear and squared fade). The opt-in two lobes gate their rough lobe's kernel the same way.
SPECAA_FLOAT3 specaa_gate_baked_kernel(SPECAA_FLOAT3 K, float a) {
    float f = SPECAA_SATURATE(specaa_sym_max_eigenvalue(K) / max(SPECAA_KERNEL_GATE * a, 1.0e-30));
    return K * SPECAA_SELECT(f == f, f * f, 1.0);
}
SPECAA_FLOAT3 specaa_baked_kernel_matrix(SpecaaSurface s) {
    return specaa_gate_baked_kernel(specaa_baked_spread_matrix(s), specaa_base_alpha2(s));
}

// The mean tr(K) / 2 of specaa_baked_kernel_matrix (the fast tier's baked kernel; a = specaa_base_alpha2),
// without the matrix for the Sigma kernel: from the texel's eigenvalues l1 >= l2, tr(clamp_psd(Sigma)) =
// max(l1, 0) + max(l2, 0) and lambda_max = max(l1, 0), so tr(K) / 2 = sqrt(g) tr f^2 with the gate's
// f = saturate(2 sqrt(g) max(l1, 0) / (SPECAA_KERNEL_GATE a)). A non-finite texel (l1 or l2 not finite) gives 0.
float specaa_baked_kernel_mean(SpecaaSurface s, float a) {
#if defined(SPECAA_KERNEL_TEXTURE) && defined(SPECAA_KERNEL_ANISOTROPIC) && !defined(SPECAA_KERNEL_COVARIANCE) && !defined(SPECAA_NO_BAKED_KERNEL)
    SPECAA_FLOAT4 k = specaa_sample_kernel_raw(SPECAA_TEXTURE_ARGS(SPECAA_KERNEL_TEXTURE, SPECAA_SAMPLER), s.uv);
    float halfTrace = 0.5 * (k.x + k.y);
    float halfDiff = 0.5 * (k.x - k.y);
    float radius = sqrt(halfDiff * halfDiff + k.z * k.z);
    float l1 = max(halfTrace + radius, 0.0);
    float l2 = halfTrace - radius;
    float share = sqrt(specaa_rough_share(k.w));
    float f = SPECAA_SATURATE(2.0 * share * l1 / max(SPECAA_KERNEL_GATE * a, 1.0e-30));
    float t = share * (l1 + max(l2, 0.0)) * SPECAA_SELECT(f == f, f * f, 1.0);
    return SPECAA_SELECT(specaa_is_finite(l1) && specaa_is_finite(l2), t, 0.0);
#else
    SPECAA_FLOAT3 baked = specaa_baked_kernel_matrix(s);
    return 0.5 * (baked.x + baked.y);
#endif
}

// Footprint of the pixel in the (T, B) frame (specaa_footprint) and whether it and the curvature are
// usable (finite inputs and derivatives; edge policy).
bool specaa_curvature_footprint(SpecaaSurface s, out SPECAA_FLOAT4 footprint) {
    SPECAA_FLOAT3 dPdx = SPECAA_DDX(s.position);
    SPECAA_FLOAT3 dPdy = SPECAA_DDY(s.position);
    footprint = specaa_footprint_tangent(dPdx, dPdy, s.tangent, s.bitangent);
    SPECAA_UINT3 m = max(max(specaa_magnitude_bits3(s.position), specaa_magnitude_bits3(dPdx)),
                         max(specaa_magnitude_bits3(dPdy), specaa_magnitude_bits3(footprint.xyw)));
    SPECAA_UINT4 c = max(SPECAA_AS_UINT4(s.curvature), SPECAA_UINT4(0u, 0u, 0u, SPECAA_AS_UINT(footprint.z))) &
                     SPECAA_UINT4(0x7fffffffu, 0x7fffffffu, 0x7fffffffu, 0x7fffffffu);
    return max(specaa_max_component(m), max(max(c.x, c.y), max(c.z, c.w))) < SPECAA_NOT_FINITE;
}

// The half vector's turn across the pixel footprint from the view direction's turn along one screen axis
// (dView: the quad derivative of s.view along it), tangential to the normal. The highlight lies where the
// half vector h = (l + v) / |l + v| meets the normal, so the spread the pixel filter sees is that of h
// relative to n: per screen axis dn - dh, not dn alone (K16, TK21 Eq. (2) filter the half vector's
// derivatives). At the highlight h = n, so |l + v| = 2 n.v and dh is the tangential part of
// dv / (2 n.v); the light's direction is taken as fixed (a distant light; a point light's own turn is left
// out). Without it the kernel is the normal's spread only: a convex surface's highlight comes out
// narrower in the image than the pixel filter makes it, and a flat one's is not filtered at all
// (docs/accuracy.md#the-view-directions-turn). n.v is floored at 1e-3 (the kernel is clamped to kappa
// after); a turn that is not finite adds nothing (edge policy). The fast and balanced tiers leave it out:
// their isotropic kernel spreads the turn, which lies along the view's tangential direction, over both axes,
// and their tone-mapped measures got worse with it (SPECAA_TIER_VIEW_TURN, a diagnostic, puts it back:
// docs/accuracy.md#the-balanced-tier); it would also cost +60 SPIR-V instructions in the fast tier, over its budget.
// SPECAA_NO_VIEW_TURN (diagnostic) leaves it out of the reference tier too.
SPECAA_FLOAT3 specaa_view_turn_axis(SpecaaSurface s, SPECAA_FLOAT3 dView) {
#if defined(SPECAA_NO_VIEW_TURN) || (SPECAA_QUALITY != SPECAA_QUALITY_REFERENCE && !defined(SPECAA_TIER_VIEW_TURN))
    return SPECAA_FLOAT3(0.0, 0.0, 0.0);
#else
    SPECAA_FLOAT3 turn = (dView - s.normal * dot(s.normal, dView)) * (0.5 / max(dot(s.normal, s.view), 1.0e-3));
    return SPECAA_SELECT3(specaa_is_finite3(turn), turn, SPECAA_FLOAT3(0.0, 0.0, 0.0));
#endif
}

// Both screen axes' turns in the (T, B) frame, (x.t, x.b, y.t, y.b), for specaa_curvature_kernel_turned.
SPECAA_FLOAT4 specaa_view_turn(SpecaaSurface s, SPECAA_FLOAT3 tangent, SPECAA_FLOAT3 bitangent) {
    SPECAA_FLOAT3 t = normalize(tangent);
    SPECAA_FLOAT3 b = normalize(bitangent);
    SPECAA_FLOAT3 x = specaa_view_turn_axis(s, SPECAA_DDX(s.view));
    SPECAA_FLOAT3 y = specaa_view_turn_axis(s, SPECAA_DDY(s.view));
    return SPECAA_FLOAT4(dot(x, t), dot(x, b), dot(y, t), dot(y, b));
}

// The per-pixel kernel from _SPECAA_CURVATURE over the position's footprint, less the half vector's turn,
// unclamped; returns whether the inputs are usable (specaa_curvature_footprint).
bool specaa_curvature_pixel_kernel(SpecaaSurface s, out SPECAA_FLOAT3 K) {
    SPECAA_FLOAT4 footprint;
    bool usable = specaa_curvature_footprint(s, footprint);
    K = specaa_curvature_kernel_turned(s.curvature, footprint, specaa_view_turn(s, s.tangent, s.bitangent));
    return usable;
}

// Per-pixel kernel matrix of the curved geometry in the (T, B) frame: from _SPECAA_CURVATURE and the
// position footprint, or from the quad derivatives of the vertex normal projected onto T and B
// (TK21 Sec. 5.1). Each eigenvalue clamped to at most kappa, the eigenvectors kept (TK21 Sec. 4: "clamp the
// eigenvalues of Sigma"; scaling the whole matrix by kappa / lambda_max instead would also shrink the minor
// axis, and an elongated footprint's peak would come out too bright: ClearCoatTest far,
// docs/accuracy.md#the-per-pixel-kernels-clamp); an overflowing kernel is kappa I, unusable inputs give 0
// (edge policy).
SPECAA_FLOAT3 specaa_pixel_kernel_matrix(SpecaaSurface s) {
#if defined(SPECAA_NO_PIXEL_KERNEL)
    return SPECAA_FLOAT3(0.0, 0.0, 0.0);
#else
#if defined(SPECAA_USE_CURVATURE) && (defined(SPECAA_PIXEL_KERNEL_MIN) || defined(SPECAA_PIXEL_KERNEL_MAX) || defined(SPECAA_PIXEL_KERNEL_MEAN) || defined(SPECAA_PIXEL_KERNEL_EDGE))
#define SPECAA_PIXEL_KERNEL_BOTH  // diagnostics: the quad-derivative kernel and the curvature kernel combined
#endif
#if defined(SPECAA_USE_CURVATURE) && !defined(SPECAA_PIXEL_KERNEL_BOTH)
    SPECAA_FLOAT3 K;
    bool usable = specaa_curvature_pixel_kernel(s, K);
#else
    SPECAA_FLOAT3 dnU = SPECAA_DDX(s.normal);
    SPECAA_FLOAT3 dnV = SPECAA_DDY(s.normal);
    SPECAA_FLOAT3 t = normalize(s.tangent);
    SPECAA_FLOAT3 b = normalize(s.bitangent);
    SPECAA_UINT3 m = max(max(specaa_magnitude_bits3(s.normal), specaa_magnitude_bits3(dnU)),
                         max(specaa_magnitude_bits3(dnV), max(specaa_magnitude_bits3(t), specaa_magnitude_bits3(b))));
    bool usable = specaa_max_component(m) < SPECAA_NOT_FINITE;
    // The turn taken off before projecting: four dot products fewer than specaa_view_turn's (x.t, x.b, y.t, y.b).
    SPECAA_FLOAT3 turnU = specaa_view_turn_axis(s, SPECAA_DDX(s.view));
    SPECAA_FLOAT3 turnV = specaa_view_turn_axis(s, SPECAA_DDY(s.view));
    SPECAA_FLOAT3 K = specaa_kernel_matrix(SPECAA_FLOAT2(dot(dnU - turnU, t), dot(dnU - turnU, b)),
                                           SPECAA_FLOAT2(dot(dnV - turnV, t), dot(dnV - turnV, b)));
#if defined(SPECAA_PIXEL_KERNEL_BOTH)
    // Diagnostics: per pixel the smaller (SPECAA_PIXEL_KERNEL_MIN) or the larger (_MAX) by trace of the
    // quad-derivative kernel and the vertex-curvature kernel, or their mean (_MEAN)
    // (docs/accuracy.md#the-faces-own-turn-and-the-vertexs-average).
    SPECAA_FLOAT3 Kc;
    bool usableCurvature = specaa_curvature_pixel_kernel(s, Kc);
#if defined(SPECAA_PIXEL_KERNEL_EDGE)
#if !defined(SPECAA_EDGE_SCALE)
#define SPECAA_EDGE_SCALE 3.5
#endif
    {
        float edge = SPECAA_PIXEL_KERNEL_EDGE;
        float foot = max(length(SPECAA_DDX(s.position)), length(SPECAA_DDY(s.position)));
        float w = SPECAA_SATURATE(SPECAA_EDGE_SCALE * foot / max(edge, 1.0e-30));
        K = SPECAA_SELECT3(usableCurvature, w * Kc + (1.0 - w) * K, K);
    }
#elif defined(SPECAA_PIXEL_KERNEL_MIN)
    K = SPECAA_SELECT3(usableCurvature && Kc.x + Kc.y < K.x + K.y, Kc, K);
#elif defined(SPECAA_PIXEL_KERNEL_MAX)
    K = SPECAA_SELECT3(usableCurvature && Kc.x + Kc.y > K.x + K.y, Kc, K);
#else
    K = SPECAA_SELECT3(usableCurvature, 0.5 * (Kc + K), K);
#endif
#endif
#endif
    float lmax = specaa_sym_max_eigenvalue(K);
    SPECAA_FLOAT3 clamped = SPECAA_SELECT3(lmax > SPECAA_KAPPA, specaa_sym_clamp_eigenvalues(K, SPECAA_KAPPA), K);
    bool bounded = max(specaa_magnitude_bits(lmax), specaa_max_component(specaa_magnitude_bits3(clamped))) < SPECAA_NOT_FINITE;
    return SPECAA_SELECT3(usable, SPECAA_SELECT3(bounded, clamped, SPECAA_FLOAT3(SPECAA_KAPPA, SPECAA_KAPPA, 0.0)),
                          SPECAA_FLOAT3(0.0, 0.0, 0.0));
#endif
}

// Per-pixel isotropic kernel t (mean reduction, TK21 Eq. 14), clamped to kappa. Tangent-free on the
// derivative path (world-space normal derivatives). Edge policy as for the matrix.
float specaa_pixel_kernel(SpecaaSurface s) {
#if defined(SPECAA_NO_PIXEL_KERNEL)
    return 0.0;
#elif defined(SPECAA_USE_CURVATURE)
    SPECAA_FLOAT3 K;
    bool usable = specaa_curvature_pixel_kernel(s, K);
    return SPECAA_SELECT(usable, specaa_clamp_kernel(0.5 * (K.x + K.y)), 0.0);
#else
    SPECAA_FLOAT3 dnU = SPECAA_DDX(s.normal);
    SPECAA_FLOAT3 dnV = SPECAA_DDY(s.normal);
    bool usable = specaa_max_component(max(specaa_magnitude_bits3(s.normal),
                                           max(specaa_magnitude_bits3(dnU), specaa_magnitude_bits3(dnV)))) < SPECAA_NOT_FINITE;
    // Finite derivatives give a kernel in [0, +inf] (never NaN): min() is specaa_clamp_kernel there.
    return SPECAA_SELECT(usable, min(specaa_iso_kernel_mean(dnU - specaa_view_turn_axis(s, SPECAA_DDX(s.view)),
                                                         dnV - specaa_view_turn_axis(s, SPECAA_DDY(s.view))), SPECAA_KAPPA), 0.0);
#endif
}

// Filtered squared roughness a (isotropic form of the default). The baked and per-pixel kernels are variances of
// independent footprints, so they add in projected space (TK21 Eq. 6) before mapping back (Eq. 7).
float specaa_filtered_alpha2(SpecaaSurface s) {
    SPECAA_FLOAT3 baked = specaa_baked_kernel_matrix(s);
    float a = specaa_filter_projected_isotropic(specaa_base_alpha2(s), 0.5 * (baked.x + baked.y) + specaa_pixel_kernel(s));
    return SPECAA_SELECT(specaa_is_finite(a), a, 1.0);
}

// Filtered perceptual roughness r = a^(1/4): drop-in for the material's roughness.
float specaa_filtered_roughness(SpecaaSurface s) { return specaa_roughness_from_alpha2(specaa_filtered_alpha2(s)); }

// The per-pixel kernel for a prefiltered environment lookup along r = reflect(-v, n) (split-sum image-based
// lighting: the lobe is looked up around r, one lookup per pixel). Across the pixel the lookup direction
// turns by dr, with the normal and with the view: dr = 2 (dn.v + n.dv) n + 2 (n.v) dn - dv. The pixel
// filter spreads the lookup over those directions, and a turn of h by e moves r by 2 e at the lobe's centre,
// so per screen axis the kernel's derivative is half the part of dr across r (TK21 Eq. 3 with dr / 2 for the
// normal's derivative). At normal incidence that is dn - dv_t / 2, the highlight's kernel with the half
// vector's turn (specaa_view_turn_axis); towards grazing the two part: the highlight's turn grows as
// 1 / (2 n.v) (a light at the mirror direction of a grazing view), while r's turn stays about |dv|, so the
// highlight's kernel is too wide for the environment there (three.js's environment-lit sphere, RMSE against
// its 16 x 16 supersampled image 0.1065 unfiltered: 0.199 with the highlight's kernel, 0.115 with this one:
// web/three/README.md#tested). Quad derivatives of r over the vertex normal s.normal and s.view, clamped to
// kappa; a zero s.view (not filled) gives the quad-derivative kernel of the normal itself; non-finite inputs
// give 0 (edge policy).
float specaa_environment_kernel(SpecaaSurface s) {
#if defined(SPECAA_NO_PIXEL_KERNEL)
    return 0.0;
#else
    // Without s.view the differentiated direction is the normal itself: dn whole, as specaa_iso_kernel_mean
    // takes it, not the part of dr / 2 across r.
    bool hasView = dot(s.view, s.view) > 0.0;
    SPECAA_FLOAT3 r = SPECAA_SELECT3(hasView, reflect(-s.view, s.normal), s.normal);
    float scale = SPECAA_SELECT(hasView, 0.5, 1.0);
    float across = SPECAA_SELECT(hasView, 1.0, 0.0);
    SPECAA_FLOAT3 ex = scale * SPECAA_DDX(r);
    SPECAA_FLOAT3 ey = scale * SPECAA_DDY(r);
    ex -= across * r * dot(ex, r);
    ey -= across * r * dot(ey, r);
    bool usable = specaa_max_component(max(specaa_magnitude_bits3(r), max(specaa_magnitude_bits3(ex), specaa_magnitude_bits3(ey)))) <
                  SPECAA_NOT_FINITE;
    return SPECAA_SELECT(usable, min(specaa_iso_kernel_mean(ex, ey), SPECAA_KAPPA), 0.0);
#endif
}

// Filtered squared roughness for a prefiltered environment lookup (the a to pick its mip by): the baked
// spread and specaa_environment_kernel added in projected space (TK21 Eq. 6-7), as specaa_filtered_alpha2
// adds the highlight's kernel.
float specaa_environment_alpha2(SpecaaSurface s) {
    SPECAA_FLOAT3 baked = specaa_baked_kernel_matrix(s);
    float a = specaa_filter_projected_isotropic(specaa_base_alpha2(s), 0.5 * (baked.x + baked.y) + specaa_environment_kernel(s));
    return SPECAA_SELECT(specaa_is_finite(a), a, 1.0);
}

// Filtered perceptual roughness r = a^(1/4) for a prefiltered environment lookup.
float specaa_environment_roughness(SpecaaSurface s) { return specaa_roughness_from_alpha2(specaa_environment_alpha2(s)); }

// Isotropic a widened by the kernel matrix K in projected space (TK21 Eq. 6-7), non-finite results as I.
SPECAA_FLOAT3 specaa_widened_matrix(float a, SPECAA_FLOAT3 K) {
    return specaa_guard_matrix(true, SPECAA_FLOAT2(a, a), specaa_filter_projected_matrix(SPECAA_FLOAT2(a, a), K));
}

// The default: filtered roughness matrix A_bar in the (T, B) frame, for specaa_default_D / specaa_ggx_G2 (or
// specaa_ggx_D with tau = a^2 of the unfiltered material). Same composition as specaa_filtered_alpha2, with the per-pixel
// kernel kept anisotropic.
SPECAA_FLOAT3 specaa_filtered_alpha2_matrix(SpecaaSurface s) {
#if SPECAA_QUALITY != SPECAA_QUALITY_REFERENCE
    // The fast and balanced tiers: the isotropic form (specaa_filtered_alpha2's value, to rounding) written for
    // their bindings.
    float t = specaa_pixel_kernel(s);
#if defined(SPECAA_KERNEL_TEXTURE) || defined(SPECAA_LEAN_TEXTURE0)
    float a = specaa_base_alpha2(s);
    float f = specaa_filter_projected_isotropic(a, specaa_baked_kernel_mean(s, a) + t);
    f = SPECAA_SELECT(specaa_is_finite(f), f, 1.0);
#else
    // a in [0, 1] and t in [0, kappa]: finite.
    float f = specaa_filter_projected_isotropic(specaa_base_alpha2(s), t);
#endif
    return SPECAA_FLOAT3(f, f, 0.0);
#elif defined(SPECAA_GATE_PIXEL_KERNEL)
    float a = specaa_base_alpha2(s);
    return specaa_widened_matrix(a, specaa_baked_kernel_matrix(s) + specaa_gate_baked_kernel(specaa_pixel_kernel_matrix(s), a));
#else
    return specaa_widened_matrix(specaa_base_alpha2(s), specaa_baked_kernel_matrix(s) + specaa_pixel_kernel_matrix(s));
#endif
}

// Level of detail the hardware samples a texture at uv (negative under magnification).
float specaa_texture_lod(SPECAA_TEXTURE_PARAMS(tex, smp), SPECAA_FLOAT2 uv) { return SPECAA_QUERY_LOD(tex, smp, uv); }

// GGX(alpha2) convolved with the footprint K = A - a I (the reference tier's specaa_default_D): the quadrature,
// or with SPECAA_CLOSED_FORM_D (diagnostic) its closed form on the anisotropic matrix.
float specaa_footprint_D(SPECAA_FLOAT3 h, SPECAA_FLOAT3 A, float alpha2) {
#if defined(SPECAA_CLOSED_FORM_D)
    return specaa_convolved_D_closed_form(h, A, alpha2);
#else
    return specaa_convolved_D(h, A, alpha2);
#endif
}

// The default NDF for the default matrix A = specaa_filtered_alpha2_matrix(s): GGX(A) + (1 - w)
// (specaa_convolved_D - GGX(A)), GGX of the material convolved with the footprint's spread K = A - a I
// where that spread is Gaussian, GGX(A) where it is not.
// - No baked normal-map data (w = 0): the spread is the image of the pixel filter under the surface's
//   curvature, a Gaussian, and the convolution is exact.
// - Baked kernel or LEAN texture (the material's own a; K holds the texel's spread and the pixel kernel
//   of the vertex normal's curvature):
//   w = saturate(LOD) saturate(SPECAA_GGX_SPREAD k_max), k_max = max(major axis of the baked spread, minor
//   axis of the per-pixel kernel) (the spread's shape, below). Under magnification (LOD <= 0) the footprint lies
//   inside one texel and the interpolated normals vary smoothly: the convolution. Minified, a small spread
//   of small slopes is still close to Gaussian (slope and projected variance within 10% up to
//   k_max ~ 0.05), but a broad one covers much of the hemisphere (a normal map's domes and bevels hold
//   every slope up to the horizon), where a Gaussian in slope space has too little weight far from the
//   mean and GGX(A) (TK21's projected-space widening; A = I is the uniform hemisphere) follows closer:
//   GGX(A) from k_max = 1 / SPECAA_GGX_SPREAD = 0.125 (slope standard deviation 0.25) on. The measurements
//   (SPECAA_GGX_SPREAD 4, 8, 16 and the LOD factor): docs/accuracy.md#normal-mapped-materials-the-blend.
// - Baked Sigma kernel with SPECAA_KERNEL_TWO_LOBES (opt-in): two lobes with the texel's mean and
//   covariance. The texel's flat share 1 - g (normals within slope 0.02 of the surface's, alpha channel)
//   keeps the material's own lobe convolved with the pixel kernel only; its rough share g holds all of
//   Sigma, as the lobe above with K = 2 Sigma / g (gated like every baked kernel) + pixel kernel. One
//   Gaussian of the whole texel spreads a flat field's highlight over the slopes of the few scratches or
//   seams in it; the two lobes keep it (docs/accuracy.md#two-lobes-per-texel: they win on the stress scenes' scratches
//   and tiles, but over the bench's normal-mapped scenes they have more error than the default's single
//   lobe, K = 2 Sigma sqrt(g), at 1.7x its cost, so they are not the default). g = 1 (earlier bakes
//   wrote A = 1) is the single lobe.
// - Baked roughness texture (a already holds the texel's spread, K only the pixel's): w = saturate(LOD),
//   the convolution under magnification, GGX(A) from the texture's mip 1 on.
// NaN inputs give GGX(A).
// SPECAA_QUALITY fast: specaa_filtered_D_isotropic on its isotropic A (no texture LOD query, no convolution):
// GGX(A) alone makes the material's tails a' / a times too bright, a halo around every highlight whose
// footprint spread is large against a (the analytic scenes at alpha 0.01: tone-mapped flicker 3.6x no
// filtering's on the sphere, 9.9x on the cylinder; docs/accuracy.md#the-fast-tier); its two lobes keep
// the material's tails and come within 30% of the convolution (docs/accuracy.md#the-fast-tiers-ndf).
// SPECAA_QUALITY balanced: the convolution itself, in closed form (specaa_convolved_D_isotropic) on the same
// A, whatever the binding (no GGX(A) share, no texture LOD query): the baked roughness holds the texel's
// spread in a, with GGX's tails, and the footprint adds the pixel kernel's Gaussian. For a footprint ten
// times a the plain tail mixture (a / a') GGX(a') + (1 - a / a') Beckmann(a') is 14% brighter than the
// convolution at the peak and half as bright on its flanks (0.49x at tan^2 = 7.8 a'): the tone-mapped harm
// the fast tier did on the analytic scenes (docs/accuracy.md#the-balanced-tier).
float specaa_default_D(SPECAA_FLOAT3 h, SPECAA_FLOAT3 filteredA, SpecaaSurface s) {
#if SPECAA_QUALITY == SPECAA_QUALITY_FAST
    return specaa_filtered_D_isotropic(h, specaa_base_alpha2(s), filteredA.x);
#elif SPECAA_QUALITY == SPECAA_QUALITY_BALANCED
    float a = specaa_base_alpha2(s);
    return specaa_convolved_D_isotropic(h, a, max(filteredA.x - a, 0.0));
#else
    SPECAA_FLOAT3 A = filteredA;
    float a = specaa_base_alpha2(s);
    float share = 1.0;   // rough share g of the texel (two lobes where g < 1)
    float flatD = 0.0;   // the flat share's lobe
#if defined(SPECAA_ROUGHNESS_TEXTURE)
    float w = SPECAA_SATURATE(specaa_texture_lod(SPECAA_TEXTURE_ARGS(SPECAA_ROUGHNESS_TEXTURE, SPECAA_SAMPLER), s.uv));
#elif defined(SPECAA_KERNEL_TEXTURE) || defined(SPECAA_LEAN_TEXTURE0)
#if defined(SPECAA_KERNEL_TEXTURE)
    float lod = specaa_texture_lod(SPECAA_TEXTURE_ARGS(SPECAA_KERNEL_TEXTURE, SPECAA_SAMPLER), s.uv);
#else
    float lod = specaa_texture_lod(SPECAA_TEXTURE_ARGS(SPECAA_LEAN_TEXTURE0, SPECAA_SAMPLER), s.uv);
#endif
#if defined(SPECAA_KERNEL_TEXTURE) && defined(SPECAA_KERNEL_ANISOTROPIC) && defined(SPECAA_KERNEL_TWO_LOBES)
    // Sampled and differentiated in uniform control flow; only the convolution is skipped for g = 1.
    SPECAA_FLOAT4 k = specaa_sample_kernel_texel(SPECAA_TEXTURE_ARGS(SPECAA_KERNEL_TEXTURE, SPECAA_SAMPLER), s.uv);
    share = k.w;
    SPECAA_FLOAT3 pixel = specaa_pixel_kernel_matrix(s);
    SPECAA_FLOAT3 flatA = specaa_widened_matrix(a, pixel);
    SPECAA_FLOAT3 roughK = specaa_gate_baked_kernel((2.0 / max(share, 1.0e-3)) * k.xyz, a);
    SPECAA_FLOAT3 roughA = specaa_widened_matrix(a, roughK + pixel);
    if (share < 1.0) {
        flatD = specaa_footprint_D(h, flatA, a);
        A = roughA;
    }
#endif
    // The blend weight is judged on the spread's shape: the baked spread's major axis and the minor axis of
    // the rest of K = A - a I (the per-pixel kernel). The pixel kernel is the image of the Gaussian pixel
    // filter under the surface's curvature (TK21 Eq. 3), for which the convolution is exact; a large one
    // along one direction only (a rim's or a strongly curved small part's arc of normals, up to kappa) keeps
    // the convolution, as GGX(A)'s tails would put a flickering halo along it; one large in every direction
    // (geometry of mesh within the footprint, a dome a pixel wide, which the clamped kernel hides) takes
    // GGX(A), which is what fits there (docs/accuracy.md#the-ggxa-share-judged-on-the-spreads-shape).
    // Diagnostics: SPECAA_BLEND_FROM_LARGEST_AXIS judges it on the largest eigenvalue of
    // all of K (the rule before), SPECAA_BLEND_FROM_BAKED_SPREAD on the baked spread alone.
    SPECAA_FLOAT3 spread = A - SPECAA_FLOAT3(a, a, 0.0);
#if defined(SPECAA_BLEND_FROM_LARGEST_AXIS)
    float w = SPECAA_SATURATE(lod) * SPECAA_SATURATE(SPECAA_GGX_SPREAD * specaa_sym_max_eigenvalue(spread));
#else
#if defined(SPECAA_KERNEL_TEXTURE) && defined(SPECAA_KERNEL_ANISOTROPIC) && defined(SPECAA_KERNEL_TWO_LOBES)
    SPECAA_FLOAT3 bakedSpread = roughK;
#else
    SPECAA_FLOAT3 bakedSpread = specaa_baked_kernel_matrix(s);
#endif
#if defined(SPECAA_BLEND_FROM_BAKED_SPREAD)
    float w = SPECAA_SATURATE(lod) * SPECAA_SATURATE(SPECAA_GGX_SPREAD * specaa_sym_max_eigenvalue(bakedSpread));
#else
    SPECAA_FLOAT3 rest = spread - bakedSpread;
    float restMinor = 0.5 * (rest.x + rest.y) - sqrt(0.25 * (rest.x - rest.y) * (rest.x - rest.y) + rest.z * rest.z);
    float bakedShare = SPECAA_SATURATE(SPECAA_GGX_SPREAD * specaa_sym_max_eigenvalue(bakedSpread));
#if defined(SPECAA_KERNEL_TEXTURE) && defined(SPECAA_KERNEL_ANISOTROPIC) && !defined(SPECAA_KERNEL_TWO_LOBES) && !defined(SPECAA_KERNEL_COVARIANCE) && !defined(SPECAA_BLEND_FROM_SPREAD_SIZE)
    // The Sigma kernel's texel also holds the shape of its spread: the rough share g (the part of its normals
    // steeper than slope 0.02), which for a spike and a slab is 2 / kurtosis. GGX(A) stands for a heavy-tailed
    // spread, the convolution for a Gaussian one, so the baked spread asks for GGX(A) by 1 - g = 1 - 2 / kurtosis
    // (0 for a broad spread whose normals all lie on the slope, 1 for a few steep normals among flat ones).
    // Measured: LightsPunctualLamp near, a broad spread (g 0.6-0.95) that GGX(A) haloed, joins and no pair
    // leaves (docs/accuracy.md#the-ggxa-share-judged-on-the-spreads-shape). SPECAA_BLEND_FROM_SPREAD_SIZE
    // (diagnostic) judges on the size alone, as before; so does SPECAA_KERNEL_COVARIANCE, the lobe of earlier
    // releases, which reads no g.
    bakedShare *= 1.0 - specaa_sample_kernel_rough_share(SPECAA_TEXTURE_ARGS(SPECAA_KERNEL_TEXTURE, SPECAA_SAMPLER), s.uv);
#endif
    float w = SPECAA_SATURATE(lod) * max(bakedShare, SPECAA_SATURATE(SPECAA_GGX_SPREAD * restMinor));
#endif
#endif
#else
    float w = 0.0;
#endif
    w = SPECAA_SELECT(w == w, w, 1.0);
#if defined(SPECAA_DEFAULT_D_WEIGHT)
    w = SPECAA_DEFAULT_D_WEIGHT;
#endif
    float ggx = specaa_ggx_D(h, A + SPECAA_FLOAT3(1.0e-12, 1.0e-12, 0.0), a * a);  // floored: a mirror stays finite
    float roughD = ggx;
    if (w < 1.0) roughD = ggx + (1.0 - w) * (specaa_footprint_D(h, A, a) - ggx);
    return share * roughD + (1.0 - share) * flatD;
#endif
}
// ===================================================================================================
// Glints: geometric glint anti-aliasing, C21 (Chermain et al. 2021) on the procedural glint BRDF of
// C20, with the dictionary that `specbake glints` bakes (glint_dictionary.ktx2, see its manifest).
//
// The patch slope distribution (C21 Eq. 3) sums, over the cells of a virtual UV pyramid under the pixel
// footprint, per-cell SDFs P22_M(m) = P_x(x_o) P_y(y_o) / det M (Eq. 4-6), where m_o = M^-1 m, M is the
// slope-correlated transform of Eq. 18 times a random rotation per cell, and P_x, P_y are two marginals
// of the dictionary picked per cell. GGAA (Eq. 15, 19, 21) filters each marginal with textureGrad using
// the pixel derivatives of the projected half vector mapped into dictionary space.
//
// Configuration (define before including; they must match the dictionary's manifest):
//   SPECAA_GLINT_LEVELS     distribution levels L, default 16
//   SPECAA_GLINT_COUNT      marginals N, default 192 (4 per RGBA texel)
//   SPECAA_GLINT_SIGMA_O    sigma_o = alpha_dict / sqrt 2, default 0.5 / sqrt 2
//   SPECAA_GLINT_MAX_CELLS  cells visited per level and pixel, default 64 (the weights are renormalised)
//   SPECAA_GLINT_GGX        converge to GGX (the include's specaa_ggx_D with A = 2 Sigma) instead of
//                           Beckmann: each cell's transform is divided by sqrt(E), E ~ Exp(1) per cell
//                           (clamped at 1/64), as GGX slopes are the scale mixture N(0, Sigma / E)
// The dictionary is a 2D array texture (RGBA16F), sampled with linear filtering, linear mip filtering,
// clamp-to-edge (or mirrored) addressing in u, no anisotropic filtering.
//
// Derivatives: the glint functions take no derivatives themselves. Call specaa_glint_derivatives() on
// the UV and, per light, on the projected half vector h.xy in uniform control flow (before any
// branch on the light or the material) and pass the results in: derivatives inside non-uniform control
// flow are undefined in GLSL and HLSL.
//
// Slope covariance: (sigma_x, sigma_y, rho) from a slope covariance Sigma, e.g. slope-space LEAN
// moments Sigma = M - m m^T, whose second moments already hold the material roughness alpha^2 / 2
// (Olano & Baker 2010; C21 Eq. 16), or Sigma = A / 2 of a roughness matrix A.
// ===================================================================================================

#ifndef SPECAA_GLINT_LEVELS
#define SPECAA_GLINT_LEVELS 16
#endif
#ifndef SPECAA_GLINT_COUNT
#define SPECAA_GLINT_COUNT 192
#endif
#ifndef SPECAA_GLINT_SIGMA_O
#define SPECAA_GLINT_SIGMA_O 0.35355339059327373
#endif
#ifndef SPECAA_GLINT_MAX_CELLS
#define SPECAA_GLINT_MAX_CELLS 64
#endif

// Per-material glint parameters (the SPECBAKE_glints material extension).
struct SpecaaGlintParams {
    float logDensity;            // ln(microfacets per unit area of the scaled UV), e.g. 15
    float relativeArea;          // fraction of cells that carry microfacets, in [0, 1]
    float densityRandomization;  // std of the per-cell distribution-level jitter (C20: 2)
    float maxAnisotropy;         // footprint eccentricity clamp (C21: 4)
    float kernelScale;           // GGAA kernel scale s_K (C21: 0.5); 0 reads mip 0: C20 without GGAA
};

SpecaaGlintParams specaa_glint_default_params() {
    SpecaaGlintParams g;
    g.logDensity = 15.0;
    g.relativeArea = 1.0;
    g.densityRandomization = 2.0;
    g.maxAnisotropy = 4.0;
    g.kernelScale = 0.5;
    return g;
}

// (ddx(v), ddy(v)) of a 2D quantity. Call in uniform control flow (see above).
SPECAA_FLOAT4 specaa_glint_derivatives(SPECAA_FLOAT2 v) { return SPECAA_FLOAT4(SPECAA_DDX(v), SPECAA_DDY(v)); }

// pcg3d (Jarzynski & Olano 2020, "Hash Functions for GPU Rendering"): three 32-bit draws per key with no
// lattice repeat, unlike C20's seed s + 1549 t (cells (s, t) and (s + 1549, t - 1) are then equal).
SPECAA_UINT3 specaa_glint_pcg3d(SPECAA_UINT3 v) {
    v = v * 1664525u + SPECAA_UINT3(1013904223u, 1013904223u, 1013904223u);
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v = v ^ (v >> 16u);
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    return v;
}

// Uniform in [0, 1) from the top 24 bits (exact in float).
float specaa_glint_unit(uint x) { return float(x >> 8u) * (1.0 / 16777216.0); }

// (sigma_x, sigma_y, rho) of a slope covariance (xx, yy, xy), clamped as C21's shader does:
// sigma in [0.01, 1], rho in [-0.99, 0.99].
SPECAA_FLOAT3 specaa_glint_sigma_rho(SPECAA_FLOAT3 sigma) {
    float sx = clamp(sqrt(max(sigma.x, 0.0)), 0.01, 1.0);
    float sy = clamp(sqrt(max(sigma.y, 0.0)), 0.01, 1.0);
    return SPECAA_FLOAT3(sx, sy, clamp(sigma.z / (sx * sy), -0.99, 0.99));
}

// M^-1 of C21 Eq. 18, M = (1 / sigma_o) [[sx sqrt(1 - rho^2), rho sx], [0, sy]], as (m00, m01, m10, m11):
// M^-1 = sigma_o [[1 / (sx sqrt(1 - rho^2)), -rho / (sy sqrt(1 - rho^2))], [0, 1 / sy]].
SPECAA_FLOAT4 specaa_glint_inverse_transform(SPECAA_FLOAT3 sxsyrho) {
    float c = sqrt(1.0 - sxsyrho.z * sxsyrho.z);
    return SPECAA_GLINT_SIGMA_O * SPECAA_FLOAT4(1.0 / (sxsyrho.x * c), -sxsyrho.z / (sxsyrho.y * c), 0.0, 1.0 / sxsyrho.y);
}

// GGX slope distribution with A = 2 Sigma: 1 / (pi sqrt(det A) (1 + m^T A^-1 m)^2) (SPECAA_GLINT_GGX).
float specaa_glint_ggx_P22(SPECAA_FLOAT2 m, SPECAA_FLOAT3 sxsyrho) {
    float c2 = 1.0 - sxsyrho.z * sxsyrho.z;
    float x = m.x / sxsyrho.x, y = m.y / sxsyrho.y;
    float t = 1.0 + 0.5 * (x * x - 2.0 * sxsyrho.z * x * y + y * y) / c2;
    return 1.0 / (2.0 * SPECAA_PI * sxsyrho.x * sxsyrho.y * sqrt(c2) * t * t);
}

// Correlated Beckmann slope distribution N(0, Sigma) at slope m, Sigma from (sx, sy, rho): the limit of
// the glint SDF at high density and the coarse-level fallback (C21 Sec. 3).
float specaa_glint_beckmann_P22(SPECAA_FLOAT2 m, SPECAA_FLOAT3 sxsyrho) {
    float c2 = 1.0 - sxsyrho.z * sxsyrho.z;
    float x = m.x / sxsyrho.x, y = m.y / sxsyrho.y;
    float q = (x * x - 2.0 * sxsyrho.z * x * y + y * y) / c2;
    return exp(-0.5 * q) / (2.0 * SPECAA_PI * sxsyrho.x * sxsyrho.y * sqrt(c2));
}

// One marginal of the dictionary: marginal i at distribution level k, read at dictionary-space slope x
// with the dictionary-space kernel derivatives gx, gy (Eq. 19).
float specaa_glint_marginal(SPECAA_TEXTURE_ARRAY_PARAMS(dict, smp), int k, int i, float x, float gx, float gy) {
    float u = abs(x) * (0.25 / SPECAA_GLINT_SIGMA_O);
    float layer = float(k * (SPECAA_GLINT_COUNT / 4) + i / 4);
    SPECAA_FLOAT4 texel = SPECAA_SAMPLE_ARRAY_GRAD(dict, smp, SPECAA_FLOAT3(u, 0.5, layer), SPECAA_FLOAT2(gx, 0.0),
                                                   SPECAA_FLOAT2(gy, 0.0));
    int c = i - 4 * (i / 4);
    return c == 0 ? texel.x : c == 1 ? texel.y : c == 2 ? texel.z : texel.w;
}

// SDF of cell (s, t) of spatial level `level` (C20 Alg. 3 with C21 Eq. 15 and 18). hs: half-vector
// slope; dh: (ddx, ddy) of the projected half vector (Eq. 21); minv: Eq. 18 inverse; beckmann: the
// analytic SDF at hs, returned by cells whose jittered level reaches L.
float specaa_glint_cell(SPECAA_TEXTURE_ARRAY_PARAMS(dict, smp), int s, int t, int level, float levelDist,
                        SPECAA_FLOAT2 hs, SPECAA_FLOAT4 dh, SPECAA_FLOAT4 minv, float beckmann, SpecaaGlintParams g) {
    // Coherent index (C20 Eq. 8): a cell shares its draws with its first descendant at every finer level.
    SPECAA_UINT3 r1 = specaa_glint_pcg3d(SPECAA_UINT3(uint(s) << uint(level), uint(t) << uint(level), 0x2545F491u));
    SPECAA_UINT3 r2 = specaa_glint_pcg3d(r1 ^ SPECAA_UINT3(0x9E3779B9u, 0x85EBCA6Bu, 0xC2B2AE35u));
    if (specaa_glint_unit(r1.x) >= g.relativeArea) return 0.0;
    // Density randomisation: the distribution level jittered by a normal of std zeta (Box-Muller).
    float n = sqrt(-2.0 * log(1.0 - specaa_glint_unit(r1.y))) * cos(2.0 * SPECAA_PI * specaa_glint_unit(r1.z));
    int k = int(clamp(floor(levelDist + g.densityRandomization * n + 0.5), 0.0, float(SPECAA_GLINT_LEVELS)));
    if (k >= SPECAA_GLINT_LEVELS) return beckmann;
#if defined(SPECAA_GLINT_GGX)
    SPECAA_UINT3 r3 = specaa_glint_pcg3d(r2 ^ SPECAA_UINT3(0x27D4EB2Fu, 0x165667B1u, 0xD3A2646Cu));
    float e = max(-log(1.0 - specaa_glint_unit(r3.x)), 1.0 / 64.0);
#else
    float e = 1.0;
#endif
    float theta = 2.0 * SPECAA_PI * specaa_glint_unit(r2.x);
    float ct = sqrt(e) * cos(theta), st = sqrt(e) * sin(theta);
    // sqrt(E) R(-theta) M^-1 (Eq. 5); a rotation keeps det M^-1, the GGX scale multiplies it by E.
    SPECAA_FLOAT4 m = SPECAA_FLOAT4(ct * minv.x + st * minv.z, ct * minv.y + st * minv.w,
                                    -st * minv.x + ct * minv.z, -st * minv.y + ct * minv.w);
    SPECAA_FLOAT2 ho = SPECAA_FLOAT2(m.x * hs.x + m.y * hs.y, m.z * hs.x + m.w * hs.y);
    if (abs(ho.x) > 4.0 * SPECAA_GLINT_SIGMA_O || abs(ho.y) > 4.0 * SPECAA_GLINT_SIGMA_O) return 0.0;
    int i = min(int(specaa_glint_unit(r2.y) * float(SPECAA_GLINT_COUNT)), SPECAA_GLINT_COUNT - 1);
    int j = min(int(specaa_glint_unit(r2.z) * float(SPECAA_GLINT_COUNT)), SPECAA_GLINT_COUNT - 1);
    // Kernel derivatives in texture space: s_K M^-1_cell dh / (4 sigma_o) (Eq. 19, 21).
    float scale = g.kernelScale * 0.25 / SPECAA_GLINT_SIGMA_O;
    SPECAA_FLOAT2 gx = scale * SPECAA_FLOAT2(m.x * dh.x + m.y * dh.y, m.z * dh.x + m.w * dh.y);
    SPECAA_FLOAT2 gy = scale * SPECAA_FLOAT2(m.x * dh.z + m.y * dh.w, m.z * dh.z + m.w * dh.w);
    float px = specaa_glint_marginal(SPECAA_TEXTURE_ARRAY_ARGS(dict, smp), k, i, ho.x, gx.x, gy.x);
    float py = specaa_glint_marginal(SPECAA_TEXTURE_ARRAY_ARGS(dict, smp), k, j, ho.y, gx.y, gy.y);
    return px * py * (minv.x * minv.w - minv.y * minv.z) * e;
}

// Footprint of the pixel in scaled UV (C21 step 5, pbrt-v3 MIPMap::Lookup): the two axes with the minor
// one stretched to major / maxAnisotropy, and the continuous spatial level whose cell size is the minor
// axis. Returns (major.xy, minor.xy) in `axes` and the level, clamped to [0, L - 1].
float specaa_glint_footprint(SPECAA_FLOAT4 duv, float maxAnisotropy, out SPECAA_FLOAT4 axes) {
    float lx = length(duv.xy), ly = length(duv.zw);
    SPECAA_FLOAT2 major = lx >= ly ? duv.xy : duv.zw;
    SPECAA_FLOAT2 minor = lx >= ly ? duv.zw : duv.xy;
    float majorLength = max(lx, ly), minorLength = min(lx, ly);
    float floorLength = majorLength / maxAnisotropy;
    if (minorLength < floorLength) {
        // A zero minor axis takes the direction perpendicular to the major one.
        SPECAA_FLOAT2 direction = minorLength > 0.0 ? minor / minorLength : SPECAA_FLOAT2(-major.y, major.x) / majorLength;
        minor = direction * floorLength;
        minorLength = floorLength;
    }
    axes = SPECAA_FLOAT4(major, minor);
    return clamp(float(SPECAA_GLINT_LEVELS - 1) + log2(max(minorLength, 1.0e-30)), 0.0, float(SPECAA_GLINT_LEVELS - 1));
}

// Mean SDF of the cells of one spatial level under the footprint, Gaussian-weighted over the EWA
// ellipse (C20 Alg. 2): W = exp(-2 r^2) - exp(-2) inside r < 1, the ellipse at least one cell wide.
float specaa_glint_level(SPECAA_TEXTURE_ARRAY_PARAMS(dict, smp), SPECAA_FLOAT2 uv, SPECAA_FLOAT4 axes, int level,
                         SPECAA_FLOAT2 hs, SPECAA_FLOAT4 dh, SPECAA_FLOAT4 minv, float beckmann, SpecaaGlintParams g) {
    // Distribution level: log4 of the expected microfacets per cell, 4^(level - (L - 1)) e^logDensity.
    float levelDist = float(level - (SPECAA_GLINT_LEVELS - 1)) + g.logDensity * 0.72134752044448170;  // 1 / (2 ln 2)
    // Every cell would draw the analytic level (C21 step 6).
    if (g.relativeArea > 0.99 && floor(levelDist + 0.5) >= float(SPECAA_GLINT_LEVELS)) return beckmann;
    float scale = exp2(float(SPECAA_GLINT_LEVELS - 1 - level));
    SPECAA_FLOAT2 p = uv * scale - SPECAA_FLOAT2(0.5, 0.5);
    SPECAA_FLOAT2 d0 = axes.xy * scale, d1 = axes.zw * scale;
    float A = d0.y * d0.y + d1.y * d1.y + 1.0;
    float B = -2.0 * (d0.x * d0.y + d1.x * d1.y);
    float C = d0.x * d0.x + d1.x * d1.x + 1.0;
    float F = A * C - 0.25 * B * B;
    A /= F;
    B /= F;
    C /= F;
    float det = 4.0 * A * C - B * B;
    float halfU = 2.0 * sqrt(det * C) / det, halfV = 2.0 * sqrt(A * det) / det;
    int s0 = int(ceil(p.x - halfU)), s1 = int(floor(p.x + halfU));
    int t0 = int(ceil(p.y - halfV)), t1 = int(floor(p.y + halfV));
    float sum = 0.0, weights = 0.0;
    int visited = 0;
    for (int t = t0; t <= t1 && visited < SPECAA_GLINT_MAX_CELLS; ++t) {
        for (int s = s0; s <= s1 && visited < SPECAA_GLINT_MAX_CELLS; ++s) {
            ++visited;
            float ds = float(s) - p.x, dt = float(t) - p.y;
            float r2 = A * ds * ds + B * ds * dt + C * dt * dt;
            if (r2 < 1.0) {
                float w = exp(-2.0 * r2) - 0.1353352832366127;  // exp(-2)
                sum += w * specaa_glint_cell(SPECAA_TEXTURE_ARRAY_ARGS(dict, smp), s, t, level, levelDist, hs, dh, minv,
                                             beckmann, g);
                weights += w;
            }
        }
    }
    return weights > 1.0e-6 ? sum / weights : 0.0;
}

// Patch SDF P22 of the pixel (C21 Eq. 3): the two spatial levels around the footprint's level, blended
// linearly. uv: scaled texture coordinates; duv: specaa_glint_derivatives(uv); hs: half-vector slope
// (-h.x / h.z, -h.y / h.z); dh: specaa_glint_derivatives(h.xy); sxsyrho: specaa_glint_sigma_rho.
float specaa_glint_P22(SPECAA_TEXTURE_ARRAY_PARAMS(dict, smp), SPECAA_FLOAT2 uv, SPECAA_FLOAT4 duv, SPECAA_FLOAT2 hs,
                       SPECAA_FLOAT4 dh, SPECAA_FLOAT3 sxsyrho, SpecaaGlintParams g) {
    SPECAA_FLOAT4 axes;
    float l = specaa_glint_footprint(duv, g.maxAnisotropy, axes);
    int il = int(floor(l));
    float w = l - float(il);
    SPECAA_FLOAT4 minv = specaa_glint_inverse_transform(sxsyrho);
#if defined(SPECAA_GLINT_GGX)
    float beckmann = specaa_glint_ggx_P22(hs, sxsyrho);  // the analytic fallback of the target
#else
    float beckmann = specaa_glint_beckmann_P22(hs, sxsyrho);
#endif
    float p = (1.0 - w) * specaa_glint_level(SPECAA_TEXTURE_ARRAY_ARGS(dict, smp), uv, axes, il, hs, dh, minv, beckmann, g);
    if (w > 0.0)
        p += w * specaa_glint_level(SPECAA_TEXTURE_ARRAY_ARGS(dict, smp), uv, axes, il + 1, hs, dh, minv, beckmann, g);
    return p;
}

// Glint NDF D = P22 / h.z^4 (C21 Eq. 2) at the unit tangent-space half vector h; 0 for h.z <= 0.
float specaa_glint_D(SPECAA_TEXTURE_ARRAY_PARAMS(dict, smp), SPECAA_FLOAT2 uv, SPECAA_FLOAT4 duv, SPECAA_FLOAT3 h,
                     SPECAA_FLOAT4 dh, SPECAA_FLOAT3 sxsyrho, SpecaaGlintParams g) {
    if (h.z <= 0.0) return 0.0;
    SPECAA_FLOAT2 hs = -h.xy / h.z;
    float z2 = h.z * h.z;
    return specaa_glint_P22(SPECAA_TEXTURE_ARRAY_ARGS(dict, smp), uv, duv, hs, dh, sxsyrho, g) / (z2 * z2);
}

// V-cavity masking-shadowing of C20/C21: min(1, 2 h.z o.z / o.h) min(1, 2 h.z i.z / i.h); 0 when a
// direction is below the surface or on the back of h.
float specaa_glint_vcavity_G2(SPECAA_FLOAT3 i, SPECAA_FLOAT3 o, SPECAA_FLOAT3 h) {
    float ih = dot(i, h), oh = dot(o, h);
    if (i.z <= 0.0 || o.z <= 0.0 || ih <= 0.0 || oh <= 0.0) return 0.0;
    return min(1.0, 2.0 * h.z * o.z / oh) * min(1.0, 2.0 * h.z * i.z / ih);
}

// Glint specular term times cos(i): D G2 / (4 o.z) with F = 1 (multiply by the Fresnel term), C21 Eq. 1.
float specaa_glint_specular(SPECAA_TEXTURE_ARRAY_PARAMS(dict, smp), SPECAA_FLOAT2 uv, SPECAA_FLOAT4 duv,
                            SPECAA_FLOAT3 i, SPECAA_FLOAT3 o, SPECAA_FLOAT4 dh, SPECAA_FLOAT3 sxsyrho,
                            SpecaaGlintParams g) {
    SPECAA_FLOAT3 h = normalize(i + o);
    float G = specaa_glint_vcavity_G2(i, o, h);
    if (G <= 0.0) return 0.0;
    return specaa_glint_D(SPECAA_TEXTURE_ARRAY_ARGS(dict, smp), uv, duv, h, dh, sxsyrho, g) * G / (4.0 * o.z);
}

#endif  // SPECAA_INCLUDED
