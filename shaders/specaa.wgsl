// specaa.wgsl: specbake runtime include for specular anti-aliasing (WGSL: WebGPU, three.js WebGPURenderer,
// Bevy). Generated from shaders/src/ by shaders/generate.cmake (the shared body through shaders/to_wgsl.py);
// edit the sources there, not this file.
//
// WGSL has no preprocessor, so this is the body in two configurations (docs/shader-include.md#webgpu-wgsl):
// - no baked texture: specaa_filtered_alpha2_matrix, specaa_default_D, specaa_ggx_G2, specaa_filtered_alpha2,
//   specaa_filtered_roughness (the material's roughness widened by the per-pixel kernel of the vertex
//   normal's quad derivatives), and every function of the body with textures as parameters;
// - the bake's default Sigma kernel texture: the same entry points with the suffix _kernel and the texture
//   and its sampler as their last parameters (at the end of the file).
// The "define before including" options of the header comment below are the GLSL/HLSL includes'; here the
// four tunable values are the consts that follow (edit them in place). Functions using derivatives
// (dpdx/dpdy) or textureSample run in fragment shaders, in uniform control flow; the others in any stage.
const SPECAA_SIGMA2: f32 = 0.15915494309189535;  // pixel-filter variance in pixels^2, 1/(2 pi) (TK21 App. B)
const SPECAA_KAPPA: f32 = 0.18;                  // clamp of derivative-based kernels (TK21 Eq. 10, K16)
const SPECAA_GGX_SPREAD: f32 = 8.0;              // specaa_default_D with baked data: GGX(A) above k_max = 1/8
const SPECAA_KERNEL_GATE: f32 = 0.5;             // fade of baked kernels narrower than this times a

// Level of detail of a texture of level-0 size `size` at uv: the isotropic LOD of the GL spec (Sec. 8.14),
// log2 of the footprint's major axis in texels (WGSL has no LOD query; specaa_texture_lod).
fn specaa_lod_from_derivatives(size: vec2<f32>, uv: vec2<f32>) -> f32 {
    let dx = dpdx(uv) * size;
    let dy = dpdy(uv) * size;
    return 0.5 * log2(max(dot(dx, dx), dot(dy, dy)));
}
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
// (One line: GLSL before 4.20 has no line continuation.)
// Kernel traces above this are treated as this: the filtered roughness is then 1 within float precision,
// and the closed forms below stay finite.
// ---------------------------------------------------------------------------------------------------
// Edge policy (header comment). Finiteness is read from the bits: GLSL does not require NaN support,
// and a compiler may fold isnan() or x != x away; an exponent of all ones cannot be.
// ---------------------------------------------------------------------------------------------------
// Largest magnitude of the components as bits: at least SPECAA_NOT_FINITE exactly when one is +-inf or
// NaN. Vector bit operations and maxima keep the tests cheap (no short-circuit branches).
fn specaa_magnitude_bits(x: f32) -> u32 { return bitcast<u32>(x) & 0x7fffffffu; }
// (The mask as a vector: WGSL does not apply a scalar to every component of a vector operand.)
fn specaa_magnitude_bits3(v: vec3<f32>) -> vec3<u32> {
    return bitcast<vec3<u32>>(v) & vec3<u32>(0x7fffffffu, 0x7fffffffu, 0x7fffffffu);
}
fn specaa_max_component(m: vec3<u32>) -> u32 { return max(max(m.x, m.y), m.z); }
fn specaa_is_finite(x: f32) -> bool { return specaa_magnitude_bits(x) < 0x7f800000u; }
fn specaa_is_finite3(v: vec3<f32>) -> bool { return specaa_max_component(specaa_magnitude_bits3(v)) < 0x7f800000u; }
// Squared roughness clamped to [0, 1]; NaN counts as fully rough.
fn specaa_sanitize_alpha2(a: f32) -> f32 { return select(clamp(a, 0.0, 1.0), 1.0, specaa_magnitude_bits(a) > 0x7f800000u); }
fn specaa_sanitize_alpha2_2(a: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(specaa_sanitize_alpha2(a.x), specaa_sanitize_alpha2(a.y));
}
// A derivative-based kernel clamped to kappa; an unbounded one (+inf, or NaN from inf - inf or 0 * inf)
// is clamped to kappa too (TK21 Eq. 10: the clamp bounds the kernel whatever the derivatives).
fn specaa_clamp_kernel(kernel: f32) -> f32 { return select(SPECAA_KAPPA, min(kernel, SPECAA_KAPPA), specaa_is_finite(kernel)); }
// The vector v and its quad derivatives dx, dy are finite.
fn specaa_usable(v: vec3<f32>, dx: vec3<f32>, dy: vec3<f32>) -> bool {
    let m: vec3<u32> = max(specaa_magnitude_bits3(v), max(specaa_magnitude_bits3(dx), specaa_magnitude_bits3(dy)));
    return specaa_max_component(m) < 0x7f800000u;
}
// The policy around a filtered matrix r of squared roughness a: diag(a) without usable inputs (zero
// kernel), the fully rough I when the kernel overflowed.
fn specaa_guard_matrix(usable: bool, a: vec2<f32>, r: vec3<f32>) -> vec3<f32> {
    let filtered: vec3<f32> = select(vec3<f32>(1.0, 1.0, 0.0), r, specaa_is_finite3(r));
    return select(vec3<f32>(a, 0.0), filtered, usable);
}
// ---------------------------------------------------------------------------------------------------
// Symmetric 2x2 matrices stored as float3(xx, yy, xy).
// ---------------------------------------------------------------------------------------------------
// Determinant xx yy - xy^2.
fn specaa_sym_det(m: vec3<f32>) -> f32 { return m.x * m.y - m.z * m.z; }
// Largest eigenvalue of a symmetric 2x2 matrix (closed form of the 2x2 characteristic polynomial).
fn specaa_sym_max_eigenvalue(m: vec3<f32>) -> f32 {
    let halfDiff: f32 = 0.5 * (m.x - m.y);
    return 0.5 * (m.x + m.y) + sqrt(halfDiff * halfDiff + m.z * m.z);
}
// A positive semi-definite matrix with each eigenvalue clamped to [0, cap] (eigenvectors kept): TK21
// Sec. 4's clamp of the non-axis-aligned kernel ("clamp the eigenvalues of Sigma"), the matrix analogue of
// Listing 3's per-axis min. m = l2 I + (l1 - l2) P1 with the projector P1 = (m - l2 I) / (l1 - l2), so the
// result is c2 I + (c1 - c2) P1, c_i = clamp(l_i, 0, cap); both above the cap: cap I. For a huge, nearly
// rank-one m the rounded l2 can come out negative (cancellation in halfTrace - radius); the clamp to 0
// keeps the result positive semi-definite and at most cap.
fn specaa_sym_clamp_eigenvalues(m: vec3<f32>, cap: f32) -> vec3<f32> {
    let halfTrace: f32 = 0.5 * (m.x + m.y);
    let halfDiff: f32 = 0.5 * (m.x - m.y);
    let radius: f32 = sqrt(halfDiff * halfDiff + m.z * m.z);
    let l2: f32 = halfTrace - radius;
    let c1: f32 = clamp(halfTrace + radius, 0.0, cap);
    let c2: f32 = clamp(l2, 0.0, cap);
    let f: f32 = select(0.0, (c1 - c2) / (2.0 * radius), radius > 0.0);
    return vec3<f32>(c2 + f * (m.x - l2), c2 + f * (m.y - l2), f * m.z);
}
// Nearest positive semi-definite matrix: negative eigenvalues set to 0 (Frobenius projection). Used on
// covariances formed as a difference of moments, Sigma = M - m m^T (SPEC Sec. 3), which rounding can
// push slightly indefinite. Uses the spectral projector (Sigma - lmin I) / (lmax - lmin).
fn specaa_sym_clamp_psd(m: vec3<f32>) -> vec3<f32> {
    let halfTrace: f32 = 0.5 * (m.x + m.y);
    let halfDiff: f32 = 0.5 * (m.x - m.y);
    let radius: f32 = sqrt(halfDiff * halfDiff + m.z * m.z);
    let lmax: f32 = halfTrace + radius;
    let lmin: f32 = halfTrace - radius;
    if (lmin >= 0.0) { return m; }
    if (lmax <= 0.0) { return vec3<f32>(0.0, 0.0, 0.0); }
    return (lmax / (2.0 * radius)) * vec3<f32>(m.x - lmin, m.y - lmin, m.z);
}
// Kernel matrix K = 2 Sigma = 2 sigma^2 [du; dv]^T [du; dv] from the screen-space derivatives of a 2D
// quantity along x (du) and y (dv), TK21 Eq. (3) (K16: C = U U^T with the roughness factor 2).
fn specaa_kernel_matrix(du: vec2<f32>, dv: vec2<f32>) -> vec3<f32> {
    return (2.0 * SPECAA_SIGMA2) * vec3<f32>(du.x * du.x + dv.x * dv.x,
                                                 du.y * du.y + dv.y * dv.y,
                                                 du.x * du.y + dv.x * dv.y);
}
// ---------------------------------------------------------------------------------------------------
// Half-vector projections (TK21 Sec. 3-4.1, T19 Listing 1).
// ---------------------------------------------------------------------------------------------------
// Slope-space half vector -h.xy / |h.z| (K16 "parallel plane", TK21 Listings 2-3 with the division).
// Not finite at h.z = 0: the slope-space methods break down at grazing half vectors (TK21 Sec. 3).
fn specaa_slope_half_vector(h: vec3<f32>) -> vec2<f32> { return h.xy / -abs(h.z); }
// Orthographically projected half vector (h.x, h.y), TK21 Sec. 4.1: derivatives shrink by det J = h_z.
fn specaa_projected_half_vector(h: vec3<f32>) -> vec2<f32> { return h.xy; }
// ---------------------------------------------------------------------------------------------------
// Filters from given derivatives (du, dv = value at the right/upper neighbour minus the fragment's).
// alpha2 = (alpha_x^2, alpha_y^2) of the material.
// ---------------------------------------------------------------------------------------------------
// Non-axis-aligned filtering diag(alpha2) + K, no clamp. With slope-space derivatives this is K16's
// R' = R + 2C (TK21 Eq. 2); with projected derivatives the practical approximation TK21 Eq. (9), Listing 2.
fn specaa_filter_non_axis_aligned(alpha2: vec2<f32>, du: vec2<f32>, dv: vec2<f32>) -> vec3<f32> {
    return vec3<f32>(alpha2.x, alpha2.y, 0.0) + specaa_kernel_matrix(du, dv);
}
// Axis-aligned filtering over the bounding rectangle |du| + |dv| of the footprint with the kappa clamp,
// TK21 Listing 3 (K16 "More Temporal Stability"): saturate(alpha2 + min(2 sigma^2 bounds^2, kappa)).
fn specaa_filter_axis_aligned(alpha2: vec2<f32>, du: vec2<f32>, dv: vec2<f32>) -> vec2<f32> {
    let bounds: vec2<f32> = abs(du) + abs(dv);
    let kernel: vec2<f32> = (2.0 * SPECAA_SIGMA2) * (bounds * bounds);
    return saturate(alpha2 + vec2<f32>(specaa_clamp_kernel(kernel.x), specaa_clamp_kernel(kernel.y)));
}
// Full projected-space filtering of an axis-aligned material, TK21 Eq. (4)-(8):
// A_bar = ((B + K)^-1 + I)^-1 with B = diag(a / (1 - a)), B_bar = B + K. Written as
// A_bar = (B_bar + det(B_bar) I) / (1 + tr(B_bar) + det(B_bar)) (the App. D form) and multiplied by
// c = (1 - a_x)(1 - a_y), so a = 1 (B infinite) and a = 0 with K = 0 (singular) stay exact (A_bar = 1
// resp. 0). c det(B_bar) = a_x a_y + c B_xx K_yy + c B_yy K_xx + c det(K) is a sum of non-negative terms,
// so det(B_bar) >= det(B) (the clamp of Listing 1) holds by construction. detK = det(K) >= 0, K PSD.
fn specaa_filter_projected_matrix_det(alpha2: vec2<f32>, kernel: vec3<f32>, kernelDet: f32) -> vec3<f32> {
    // Half the trace first: a finite K whose trace overflows still scales down to the cap (then A_bar ~ I)
    // instead of to 0; an infinite K gives NaN here, which the callers' edge policy turns into I.
    var K: vec3<f32> = kernel;
    var detK: f32 = kernelDet;
    let halfTraceK: f32 = 0.5 * K.x + 0.5 * K.y;
    var traceK: f32 = K.x + K.y;
    if (halfTraceK > 0.5 * 1.0e8) {
        let scale: f32 = (0.5 * 1.0e8) / halfTraceK;
        K *= scale;
        detK *= scale * scale;
        traceK = 1.0e8;
    }
    let ax: f32 = saturate(alpha2.x);
    let ay: f32 = saturate(alpha2.y);
    let c: f32 = (1.0 - ax) * (1.0 - ay);
    let bx: f32 = ax * (1.0 - ay); // c B_xx
    let by: f32 = ay * (1.0 - ax); // c B_yy
    let cDet: f32 = ax * ay + bx * K.y + by * K.x + c * max(detK, 0.0); // c det(B_bar)
    let denominator: f32 = c + bx + by + c * traceK + cDet; // c (1 + tr(B_bar) + det(B_bar)) > 0
    return vec3<f32>(bx + c * K.x + cDet, by + c * K.y + cDet, c * K.z) / denominator;
}
// Full projected-space filtering by a kernel matrix K (PSD), e.g. baked Sigma plus a curvature kernel.
fn specaa_filter_projected_matrix(alpha2: vec2<f32>, K: vec3<f32>) -> vec3<f32> {
    return specaa_filter_projected_matrix_det(alpha2, K, specaa_sym_det(K));
}
// Full projected-space filtering from projected half-vector derivatives, TK21 Listing 1. det(K) comes
// from Cauchy-Binet, (2 sigma^2)^2 (du x dv)^2, exact where K_xx K_yy - K_xy^2 would cancel (a footprint
// stretched along one direction, e.g. at grazing angles).
fn specaa_filter_projected(alpha2: vec2<f32>, du: vec2<f32>, dv: vec2<f32>) -> vec3<f32> {
    let cross2: f32 = (2.0 * SPECAA_SIGMA2) * (du.x * dv.y - du.y * dv.x);
    return specaa_filter_projected_matrix_det(alpha2, specaa_kernel_matrix(du, dv), cross2 * cross2);
}
// Isotropic kernels from world-space normal derivatives dnU, dnV (TK21 Sec. 5; Eq. 12: their lengths
// equal the projected derivatives of the pairwise averaged normal). Sigma = sigma^2 Gram(dnU, dnV).
// Max: 2 lambda_max(Sigma), TK21 Eq. (10) (tightest conservative isotropic kernel).
fn specaa_iso_kernel_max(dnU: vec3<f32>, dnV: vec3<f32>) -> f32 {
    let gram: vec3<f32> = vec3<f32>(dot(dnU, dnU), dot(dnV, dnV), dot(dnU, dnV));
    return 2.0 * SPECAA_SIGMA2 * specaa_sym_max_eigenvalue(gram);
}
// Sum: 2 tr(Sigma) = 2 sigma^2 (|dnU|^2 + |dnV|^2), TK21 Eq. (13), Listing 5 (conservative).
fn specaa_iso_kernel_sum(dnU: vec3<f32>, dnV: vec3<f32>) -> f32 {
    return 2.0 * SPECAA_SIGMA2 * (dot(dnU, dnU) + dot(dnV, dnV));
}
// Mean: tr(Sigma) = sigma^2 (|dnU|^2 + |dnV|^2), TK21 Eq. (14) (less conservative, lowest error there).
fn specaa_iso_kernel_mean(dnU: vec3<f32>, dnV: vec3<f32>) -> f32 {
    return SPECAA_SIGMA2 * (dot(dnU, dnU) + dot(dnV, dnV));
}
// Clamped isotropic filtering, TK21 Eq. (10)/(13)/(14) as in Listing 5: saturate(a + min(t, kappa)).
fn specaa_filter_isotropic(alpha2: f32, kernel: f32) -> f32 {
    return saturate(alpha2 + specaa_clamp_kernel(kernel));
}
// ---------------------------------------------------------------------------------------------------
// Derivative-based methods: the filters above with derivatives from the 2x2 pixel quad (ddx/ddy).
// hTS: unit tangent-space half vector; normal: unit world-space shading normal.
// ---------------------------------------------------------------------------------------------------
// "slope": K16 slope-space non-axis-aligned filtering, R' = R + 2C (TK21 Eq. 2).
fn specaa_slope(alpha2: vec2<f32>, hTS: vec3<f32>) -> vec3<f32> {
    let a: vec2<f32> = specaa_sanitize_alpha2_2(alpha2);
    let hs: vec2<f32> = specaa_slope_half_vector(hTS);
    return specaa_guard_matrix(specaa_usable(hTS, dpdx(hTS), dpdy(hTS)), a, specaa_filter_non_axis_aligned(a, dpdx(hs), dpdy(hs)));
}
// "slope-aa": K16 axis-aligned rectangle in slope space with the kappa clamp (Listing 3 with division).
fn specaa_slope_aa(alpha2: vec2<f32>, hTS: vec3<f32>) -> vec2<f32> {
    let a: vec2<f32> = specaa_sanitize_alpha2_2(alpha2);
    let hs: vec2<f32> = specaa_slope_half_vector(hTS);
    let r: vec2<f32> = specaa_filter_axis_aligned(a, dpdx(hs), dpdy(hs));
    return select(a, r, specaa_usable(hTS, dpdx(hTS), dpdy(hTS)));
}
// "projected-approx": TK21 Listing 2, Eq. (9), non-axis-aligned, projected derivatives, no clamp.
fn specaa_projected_approx(alpha2: vec2<f32>, hTS: vec3<f32>) -> vec3<f32> {
    let a: vec2<f32> = specaa_sanitize_alpha2_2(alpha2);
    let hp: vec2<f32> = specaa_projected_half_vector(hTS);
    return specaa_guard_matrix(specaa_usable(hTS, dpdx(hTS), dpdy(hTS)), a, specaa_filter_non_axis_aligned(a, dpdx(hp), dpdy(hp)));
}
// "projected-aa": TK21 Listing 3, axis-aligned, projected derivatives, kappa clamp.
fn specaa_projected_aa(alpha2: vec2<f32>, hTS: vec3<f32>) -> vec2<f32> {
    let a: vec2<f32> = specaa_sanitize_alpha2_2(alpha2);
    let hp: vec2<f32> = specaa_projected_half_vector(hTS);
    let r: vec2<f32> = specaa_filter_axis_aligned(a, dpdx(hp), dpdy(hp));
    return select(a, r, specaa_usable(hTS, dpdx(hTS), dpdy(hTS)));
}
// "projected": TK21 Listing 1, full projected-space filtering (Eq. 4-8).
fn specaa_projected(alpha2: vec2<f32>, hTS: vec3<f32>) -> vec3<f32> {
    let a: vec2<f32> = specaa_sanitize_alpha2_2(alpha2);
    let hp: vec2<f32> = specaa_projected_half_vector(hTS);
    return specaa_guard_matrix(specaa_usable(hTS, dpdx(hTS), dpdy(hTS)), a, specaa_filter_projected(a, dpdx(hp), dpdy(hp)));
}
// "iso-max": TK21 Eq. (10) from normal derivatives; returns the filtered a.
fn specaa_iso_max(alpha2: f32, normal: vec3<f32>) -> f32 {
    let a: f32 = specaa_sanitize_alpha2(alpha2);
    let dnU: vec3<f32> = dpdx(normal);
    let dnV: vec3<f32> = dpdy(normal);
    return select(a, specaa_filter_isotropic(a, specaa_iso_kernel_max(dnU, dnV)), specaa_usable(normal, dnU, dnV));
}
// "iso-sum": TK21 Eq. (13), Listing 5 (T19 Listing 2); returns the filtered a.
fn specaa_iso_sum(alpha2: f32, normal: vec3<f32>) -> f32 {
    let a: f32 = specaa_sanitize_alpha2(alpha2);
    let dnU: vec3<f32> = dpdx(normal);
    let dnV: vec3<f32> = dpdy(normal);
    return select(a, specaa_filter_isotropic(a, specaa_iso_kernel_sum(dnU, dnV)), specaa_usable(normal, dnU, dnV));
}
// "iso-mean": TK21 Eq. (14); returns the filtered a.
fn specaa_iso_mean(alpha2: f32, normal: vec3<f32>) -> f32 {
    let a: f32 = specaa_sanitize_alpha2(alpha2);
    let dnU: vec3<f32> = dpdx(normal);
    let dnV: vec3<f32> = dpdy(normal);
    return select(a, specaa_filter_isotropic(a, specaa_iso_kernel_mean(dnU, dnV)), specaa_usable(normal, dnU, dnV));
}
// ---------------------------------------------------------------------------------------------------
// Isotropic projected-space filtering and kernel reductions (SPEC Sec. 3, the texture bake's formulas).
// ---------------------------------------------------------------------------------------------------
// Full projected-space filtering of a scalar a by an isotropic kernel t, TK21 Eq. (4)-(7) in closed form:
// a' = (a + t (1 - a)) / (1 + t (1 - a)). t = 0 leaves a unchanged; a = 1 stays 1.
fn specaa_filter_projected_isotropic(alpha2: f32, kernel: f32) -> f32 {
    let k: f32 = min(kernel, 1.0e8) * (1.0 - alpha2);
    return (alpha2 + k) / (1.0 + k);
}
// Approximate filtering a' = min(1, a + t), TK21 Eq. (9) (the bake's --filter approx).
fn specaa_filter_approx_isotropic(alpha2: f32, kernel: f32) -> f32 { return min(1.0, alpha2 + kernel); }
// Reductions of a covariance Sigma to an isotropic kernel t (SPEC Sec. 3): mean tr(Sigma) (Eq. 14
// analogue), sum 2 tr(Sigma) (Eq. 13), max 2 lambda_max(Sigma) (Eq. 10).
fn specaa_reduce_mean(sigma: vec3<f32>) -> f32 { return sigma.x + sigma.y; }
fn specaa_reduce_sum(sigma: vec3<f32>) -> f32 { return 2.0 * (sigma.x + sigma.y); }
fn specaa_reduce_max(sigma: vec3<f32>) -> f32 { return 2.0 * specaa_sym_max_eigenvalue(sigma); }
// ---------------------------------------------------------------------------------------------------
// Baked textures (SPEC Sec. 3), sampled at the hardware-selected mip.
// ---------------------------------------------------------------------------------------------------
// a = r^4 from perceptual roughness r (SPEC Sec. 2), and back.
fn specaa_alpha2_from_roughness(r: f32) -> f32 { let alpha: f32 = r * r; return alpha * alpha; }
fn specaa_roughness_from_alpha2(alpha2: f32) -> f32 { return sqrt(sqrt(max(alpha2, 0.0))); }
// Baked filtered roughness mips: returns a of channel SPECAA_ROUGHNESS_CHANNEL (perceptual r).
fn specaa_sample_roughness(tex: texture_2d<f32>, smp: sampler, uv: vec2<f32>) -> f32 {
    return specaa_alpha2_from_roughness(textureSample(tex, smp, uv).g);
}
// Baked isotropic kernel mips: t in channel R.
// A non-finite texel gives a zero kernel (edge policy).
fn specaa_sample_kernel(tex: texture_2d<f32>, smp: sampler, uv: vec2<f32>) -> f32 {
    let t: f32 = textureSample(tex, smp, uv).r;
    return select(0.0, max(t, 0.0), specaa_is_finite(t));
}
// Baked anisotropic kernel mips: Sigma = (xx, yy, xy) in RGB (A: the rough share below); clamped to PSD
// after filtering.
fn specaa_sample_kernel_covariance(tex: texture_2d<f32>, smp: sampler, uv: vec2<f32>) -> vec3<f32> {
    let sigma: vec3<f32> = specaa_sym_clamp_psd(textureSample(tex, smp, uv).rgb);
    return select(vec3<f32>(0.0, 0.0, 0.0), sigma, specaa_is_finite3(sigma));
}
// Rough share g of a baked Sigma kernel texel (alpha channel): the part of its normals steeper than slope
// 0.02, which holds all of Sigma (specaa_default_D). Non-finite or absent (1) gives the single lobe.
fn specaa_rough_share(g: f32) -> f32 { return select(1.0, saturate(g), specaa_is_finite(g)); }
fn specaa_sample_kernel_rough_share(tex: texture_2d<f32>, smp: sampler, uv: vec2<f32>) -> f32 {
    return specaa_rough_share(textureSample(tex, smp, uv).a);
}
// The Sigma kernel texel as stored (Sigma.xx, Sigma.yy, Sigma.xy, g), with the diagnostics' mip choice.
fn specaa_sample_kernel_raw(tex: texture_2d<f32>, smp: sampler, uv: vec2<f32>) -> vec4<f32> {
    let t: vec4<f32> = textureSample(tex, smp, uv);
    return t;
}
// Both from one fetch: (Sigma.xx, Sigma.yy, Sigma.xy, g), Sigma clamped to PSD (zero if not finite).
fn specaa_sample_kernel_texel(tex: texture_2d<f32>, smp: sampler, uv: vec2<f32>) -> vec4<f32> {
    let t: vec4<f32> = specaa_sample_kernel_raw(tex, smp, uv);
    let sigma: vec3<f32> = specaa_sym_clamp_psd(t.rgb);
    return vec4<f32>(select(vec3<f32>(0.0, 0.0, 0.0), sigma, specaa_is_finite3(sigma)),
                         specaa_rough_share(t.a));
}
// Covariance from LEAN moments, Sigma = M - m m^T clamped to PSD (SPEC Sec. 3; C21 Eq. 16).
// lean0 = (m.x, m.y, M.xx, M.yy), lean1 = M.xy. Moments filter linearly, so any mip/trilinear mix of
// them still yields the covariance of the normals in the filtered footprint. Non-finite moments give 0.
fn specaa_lean_covariance(lean0: vec4<f32>, lean1: f32) -> vec3<f32> {
    let sigma: vec3<f32> = specaa_sym_clamp_psd(vec3<f32>(lean0.z - lean0.x * lean0.x,
                                                             lean0.w - lean0.y * lean0.y,
                                                             lean1 - lean0.x * lean0.y));
    return select(vec3<f32>(0.0, 0.0, 0.0), sigma, specaa_is_finite3(sigma));
}
// Baked mean normal (`*_normal`, docs/texture-bake.md#output-layouts), tangent space, unit length. Two-channel texels
// (BC5 under `--block bc`, ASTC's (x, y, 0, 1) under `--block astc`) hold x, y as (n + 1) / 2: z = sqrt(max(0, 1 - x^2 - y^2)) (the mean normal lies in
// the upper hemisphere), renormalised where filtering or quantisation put (x, y) outside the unit disc.
// RGB texels hold (n + 1) / 2, renormalised after filtering; a zero vector gives (0, 0, 1).
fn specaa_decode_normal_xy(texel: vec2<f32>) -> vec3<f32> {
    let xy: vec2<f32> = texel * 2.0 - 1.0;
    let n: vec3<f32> = vec3<f32>(xy, sqrt(max(0.0, 1.0 - dot(xy, xy))));
    return n / sqrt(dot(n, n)); // |n| >= 1 (z = 1 at xy = 0): no division by zero
}
fn specaa_decode_normal_rgb(texel: vec3<f32>) -> vec3<f32> {
    let n: vec3<f32> = texel * 2.0 - 1.0;
    let l2: f32 = dot(n, n);
    return select(vec3<f32>(0.0, 0.0, 1.0), n / sqrt(max(l2, 1.0e-30)), l2 > 0.0);
}
// The baked mean normal at uv: two channels with SPECAA_NORMAL_TWO_CHANNEL (BC5, ASTC), else RGB(A).
fn specaa_sample_mean_normal(tex: texture_2d<f32>, smp: sampler, uv: vec2<f32>) -> vec3<f32> {
    return specaa_decode_normal_rgb(textureSample(tex, smp, uv).rgb);
}
// LEAN lookup from the two moment textures (layout in the header comment).
fn specaa_sample_lean(tex0: texture_2d<f32>, smp0: sampler, tex1: texture_2d<f32>, smp1: sampler,
                                 uv: vec2<f32>) -> vec3<f32> {
    return specaa_lean_covariance(textureSample(tex0, smp0, uv), textureSample(tex1, smp1, uv).r);
}
// ---------------------------------------------------------------------------------------------------
// Curvature-based kernel from the _SPECAA_CURVATURE attribute (SPEC Sec. 4) and the pixel footprint.
// ---------------------------------------------------------------------------------------------------
// Shape operator S = k1 d d^T + k2 d' d'^T (d' = d rotated by 90 degrees) in the tangent frame from
// curvature = (k1, k2, d.x, d.y). The normal moves by dp = -S dx for a tangent step dx (first order), so
// S maps the footprint to projected-normal derivatives. A zero d (umbilic) uses k1 on both axes.
fn specaa_shape_operator(curvature: vec4<f32>) -> vec3<f32> {
    let len: f32 = length(curvature.zw);
    if (len < 1.0e-6) { return vec3<f32>(curvature.x, curvature.x, 0.0); }
    let d: vec2<f32> = curvature.zw / len;
    let k1: f32 = curvature.x;
    let k2: f32 = curvature.y;
    return vec3<f32>(k1 * d.x * d.x + k2 * d.y * d.y,
                         k1 * d.y * d.y + k2 * d.x * d.x,
                         (k1 - k2) * d.x * d.y);
}
// Pixel footprint in the tangent plane: the position derivatives along screen x and y expressed in the
// (T, B) frame, returned as (u.x, u.y, v.x, v.y). Units of the positions (object space for the curvature).
fn specaa_footprint_tangent(dPdx: vec3<f32>, dPdy: vec3<f32>, tangent: vec3<f32>,
                                       bitangent: vec3<f32>) -> vec4<f32> {
    let t: vec3<f32> = normalize(tangent);
    let b: vec3<f32> = normalize(bitangent);
    return vec4<f32>(dot(dPdx, t), dot(dPdx, b), dot(dPdy, t), dot(dPdy, b));
}
// Pixel footprint from the quad derivatives of the interpolated position (same space as T, B).
fn specaa_footprint(position: vec3<f32>, tangent: vec3<f32>, bitangent: vec3<f32>) -> vec4<f32> {
    return specaa_footprint_tangent(dpdx(position), dpdy(position), tangent, bitangent);
}
// Width of one pixel on a plane facing the camera at view depth z (perspective, vertical field of view
// with tan(fovY/2), viewport height in pixels): 2 z tan(fovY/2) / height. Grazing elongation is ignored.
fn specaa_pixel_footprint_from_depth(viewDepth: f32, tanHalfFovY: f32, viewportHeight: f32) -> f32 {
    return 2.0 * viewDepth * tanHalfFovY / viewportHeight;
}
// Curvature kernel matrix K = 2 sigma^2 (S u u^T S + S v v^T S), TK21 Eq. (3) with the projected-normal
// derivatives S u, S v of the curved shading-normal field (K16 "virtual quadric") instead of quad
// differences. footprint = (u.x, u.y, v.x, v.y) from specaa_footprint*.
// turn: the half vector's turn per screen axis in the same frame, (x.t, x.b, y.t, y.b) (specaa_view_turn),
// taken off the normal's: the spread of h relative to n over the footprint.
fn specaa_curvature_kernel_turned(curvature: vec4<f32>, footprint: vec4<f32>, turn: vec4<f32>) -> vec3<f32> {
    let S: vec3<f32> = specaa_shape_operator(curvature);
    let du: vec2<f32> = vec2<f32>(S.x * footprint.x + S.z * footprint.y, S.z * footprint.x + S.y * footprint.y);
    let dv: vec2<f32> = vec2<f32>(S.x * footprint.z + S.z * footprint.w, S.z * footprint.z + S.y * footprint.w);
    return specaa_kernel_matrix(du - turn.xy, dv - turn.zw);
}
// The normal's spread alone (no turn of the half vector).
fn specaa_curvature_kernel(curvature: vec4<f32>, footprint: vec4<f32>) -> vec3<f32> {
    return specaa_curvature_kernel_turned(curvature, footprint, vec4<f32>(0.0, 0.0, 0.0, 0.0));
}
// Isotropic curvature kernel for a square footprint of width w: mean reduction tr(Sigma) =
// sigma^2 w^2 (k1^2 + k2^2) (TK21 Eq. 14 with |dn| = |k| w per principal direction).
fn specaa_curvature_kernel_isotropic(curvature: vec4<f32>, footprintWidth: f32) -> f32 {
    return SPECAA_SIGMA2 * footprintWidth * footprintWidth * (curvature.x * curvature.x + curvature.y * curvature.y);
}
// ---------------------------------------------------------------------------------------------------
// GGX and Beckmann with a roughness matrix A (TK21 Sec. 2.1, App. A).
// ---------------------------------------------------------------------------------------------------
// Clamped determinant max(det(A), tau) of TK21 App. A.4 (tau = alpha_x^2 alpha_y^2 of the unfiltered
// material), floored at 1e-30 so a mirror (A = 0, tau = 0) stays finite instead of a Dirac delta.
fn specaa_clamped_det(A: vec3<f32>, tau: f32) -> f32 { return max(max(specaa_sym_det(A), tau), 1.0e-30); }
// [h.x, h.y] A^-1 [h.x, h.y]^T with A^-1 = adj(A) / detClamped (TK21 App. A.4).
fn specaa_inverse_quadratic_form(A: vec3<f32>, v: vec2<f32>, detClamped: f32) -> f32 {
    return (v.x * v.x * A.y - 2.0 * v.x * v.y * A.z + v.y * v.y * A.x) / detClamped;
}
// GGX NDF, TK21 Eq. (1) with the determinant clamp of App. A.4. 0 for h.z <= 0.
fn specaa_ggx_D(h: vec3<f32>, A: vec3<f32>, tau: f32) -> f32 {
    if (h.z <= 0.0) { return 0.0; }
    let detClamped: f32 = specaa_clamped_det(A, tau);
    let q: f32 = specaa_inverse_quadratic_form(A, h.xy, detClamped) + h.z * h.z;
    return 1.0 / (3.14159265358979 * sqrt(detClamped) * q * q);
}
// Beckmann NDF with a roughness matrix, TK21 Sec. 2.1, same clamp. 0 for h.z <= 0.
fn specaa_beckmann_D(h: vec3<f32>, A: vec3<f32>, tau: f32) -> f32 {
    if (h.z <= 0.0) { return 0.0; }
    let detClamped: f32 = specaa_clamped_det(A, tau);
    let z2: f32 = h.z * h.z;
    return exp(-specaa_inverse_quadratic_form(A, h.xy, detClamped) / z2) /
           (3.14159265358979 * sqrt(detClamped) * z2 * z2);
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
fn specaa_filtered_D(h: vec3<f32>, A: vec3<f32>, alpha2: f32) -> f32 {
    let tau: f32 = alpha2 * alpha2;
    let detClamped: f32 = specaa_clamped_det(A, tau);
    let r2: f32 = dot(h.xy, h.xy);
    let q: f32 = select(1.0 / sqrt(detClamped), specaa_inverse_quadratic_form(A, h.xy, detClamped) / r2, r2 > 0.0);
    let rho: f32 = saturate(alpha2 * sqrt(detClamped) * q * q);
    let ggx: f32 = specaa_ggx_D(h, A, tau);
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
fn specaa_filtered_D_isotropic(h: vec3<f32>, alpha2: f32, filteredAlpha2: f32) -> f32 {
    let f: f32 = max(filteredAlpha2, 1.0e-12);
    let a: f32 = min(alpha2, f);
    let r2: f32 = dot(h.xy, h.xy);
    let z2: f32 = h.z * h.z;
    let t: f32 = sqrt(a * f); // in [a, f]
    let g: f32 = max(min(f, 1.8 * t), 1.0e-12); // a mirror (a = 0): no GGX part
    let fb: f32 = f + 1.2 * t - 0.6 * a;
    let s2: f32 = g * z2 + r2;
    // tan^2(theta_h), bounded so that (1 + u)^2 stays finite where e^(-u / f_b) is 0 (h_z -> 0).
    let u: f32 = min(r2 / z2, 1.0e18);
    let beckmann: f32 = exp(-u / fb) * (1.0 + u) * (1.0 + u) / (3.14159265358979 * fb);
    return select(0.0, beckmann * (1.0 - a / g) + a / (3.14159265358979 * s2 * s2), h.z > 0.0);
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
fn specaa_convolved_D(h: vec3<f32>, A: vec3<f32>, alpha2: f32) -> f32 {
    if (h.z <= 0.0) { return 0.0; }
    let a: f32 = max(alpha2, 1.0e-12);
    // The added kernel, projected onto the PSD cone (an anisotropic material's A - a I can be indefinite).
    let K: vec3<f32> = specaa_sym_clamp_psd(A - vec3<f32>(a, a, 0.0));
    let kmax: f32 = max(specaa_sym_max_eigenvalue(K), 0.0);
    // No footprint to speak of: GGX(A), floored at 1e-12 I so that a mirror (A = 0) stays finite off its peak.
    if (kmax <= 1.0e-3 * a) { return specaa_ggx_D(h, A + vec3<f32>(1.0e-12, 1.0e-12, 0.0), a * a); }
    let wlo: f32 = 0.05 * min(1.0, a / kmax);
    let slo: f32 = log(wlo);
    let range: f32 = log(10.0) - slo;
    let nodes: i32 = i32(clamp(ceil(range / 1.1), 11.0, 31.0)) + 1;
    let ds: f32 = range / f32(nodes - 1);
    let z2: f32 = h.z * h.z;
    let c: f32 = dot(h.xy, h.xy) / (z2 * a);
    let unit: f32 = 1.0 / (3.14159265358979 * a * z2 * z2);
    var sum: f32 = 0.0;
    var sumUnfiltered: f32 = 0.0;
    for (var j: i32 = 0; j < 32; j++) {
        if (j >= nodes) { break; }
        let w: f32 = exp(slo + ds * f32(j));
        let v: f32 = a / w;
        let weight: f32 = select(1.0, 0.5, (j == 0 || j == nodes - 1));
        sum += weight * exp(-w) * w * specaa_beckmann_D(h, K + vec3<f32>(v, v, 0.0), v * v);
        sumUnfiltered += weight * exp(-w * (1.0 + c)) * w * w * unit; // Beckmann(a / w I)
    }
    // Below w_lo, Beckmann(a / w I + K) to first order in K, integrated in closed form (series where the
    // closed forms cancel in float): I1 + q I3 / a^2 - tr(K) I2 / (2 a), In = int_0^w_lo w^n e^(-w (1 + c)) dw.
    let c1: f32 = 1.0 + c;
    let x: f32 = c1 * wlo;
    let e: f32 = exp(-x);
    let below: f32 = select(wlo * wlo * (0.5 - x / 3.0), (1.0 - e * (1.0 + x)) / (c1 * c1), x > 1.0e-2);
    let p2: f32 = 1.0 + x + 0.5 * x * x;
    let wlo3: f32 = wlo * wlo * wlo;
    let i2: f32 = select(2.0 * (1.0 - e * p2) / (c1 * c1 * c1), wlo3 * (1.0 / 3.0 - x / 4.0 + x * x / 10.0 - x * x * x / 36.0), x < 0.5);
    let i3: f32 = select(6.0 * (1.0 - e * (p2 + x * x * x / 6.0)) / (c1 * c1 * c1 * c1), wlo3 * wlo * (0.25 - x / 5.0 + x * x / 12.0 - x * x * x / 42.0), x < 0.5);
    let q: f32 = (h.x * h.x * K.x + 2.0 * h.x * h.y * K.z + h.y * h.y * K.y) / z2;
    let firstOrder: f32 = q / (a * a) * i3 - 0.5 * (K.x + K.y) / a * i2;
    let direct: f32 = sum * ds + (below + firstOrder) * unit;
    let difference: f32 = max(0.0, specaa_ggx_D(h, vec3<f32>(a, a, 0.0), a * a) + (sum - sumUnfiltered) * ds + firstOrder * unit);
    let blend: f32 = saturate(log2(10.0 * kmax / a) * 0.30103);
    let D: f32 = difference + blend * (direct - difference);
    // Grazing half vectors (h_z^4 below float's range) overflow the sums; the convolution is GGX(a)'s tail
    // there, a / (pi (|h.xy|^2 + a h_z^2)^2).
    let s2: f32 = dot(h.xy, h.xy) + a * z2;
    return select(a / (3.14159265358979 * s2 * s2), D, specaa_is_finite(D));
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
fn specaa_closed_form_nodes(b: f32) -> vec4<f32> {
    let z: f32 = clamp(log2(b) * 0.30102999566, -3.0, 4.0);
    // (p1, q, p2) by Horner's rule, one coefficient vector per power of z.
    let c0: vec3<f32> = select(vec3<f32>(-0.589765801, 2.49577999, -2.55947913), vec3<f32>(13.4053507, 0.175485909, -0.78612125), z < -0.25);
    let c1: vec3<f32> = select(vec3<f32>(1.15587235, 0.554438611, -0.177032328), vec3<f32>(18.6896586, 0.837682955, 0.779175295), z < -0.25);
    let c2: vec3<f32> = select(vec3<f32>(-1.77857435, 0.921497471, -1.03833038), vec3<f32>(8.00904241, -0.121406802, 1.05666563), z < -0.25);
    let c3: vec3<f32> = select(vec3<f32>(0.425394192, -0.115584935, 0.133253855), vec3<f32>(0.357309142, -0.297962248, -0.559140109), z < -0.25);
    let p: vec3<f32> = c0 + z * (c1 + z * (c2 + z * c3));
    let rest: f32 = exp(-1.0 / b);
    let w1: f32 = select(rest / (1.0 + exp(-p.y)), p.y * b / (1.0 + b), z < -0.25); // selects: no branch
    return vec4<f32>(w1, rest - w1, exp(-p.x), exp(-p.z));
}
// The truncated mixture of the closed form (GGX(a)'s lobes wider than k), r2 = |h.xy|^2, z2 = h_z^2 > 0.
fn specaa_closed_form_tail(r2: f32, z2: f32, a: f32, k: f32) -> f32 {
    let L: f32 = (r2 / z2 + a) / k;
    let Lc: f32 = min(L, 80.0); // e^-L (1 + L) below float's range beyond (and no inf * 0 at h_z = 0)
    let s2: f32 = r2 + a * z2;
    return select((0.5 - L / 3.0 + L * L / 8.0) * a / (3.14159265358979 * k * k * z2 * z2), a * (1.0 - exp(-Lc) * (1.0 + Lc)) / (3.14159265358979 * s2 * s2), L > 0.05);
}
// GGX(a) convolved with a small footprint, to second order in K (the convolution's Taylor expansion, written
// for the isotropic slope density f(q) = 1 / (pi a (1 + q / a)^2): f + f' tr(K) / 2 + f'' m^T K m):
// a / (pi s2^2) (1 - tr(K) h_z^2 / s2 + 6 h.xy^T K h.xy h_z^2 / s2^2), s2 = a h_z^2 + |h.xy|^2 (finite as
// h_z -> 0). Exact as K -> 0, within 0.6% of D at k = 0.03 a; trK = tr(K), hKh = h.xy^T K h.xy.
fn specaa_small_footprint_D(r2: f32, z2: f32, a: f32, trK: f32, hKh: f32) -> f32 {
    let s2: f32 = a * z2 + r2;
    return a / (3.14159265358979 * s2 * s2) * (1.0 - trK * z2 / s2 + 6.0 * hKh * z2 / (s2 * s2));
}
// Share of the fitted nodes in the closed form: 0 (the second-order expansion) below k = 0.03 a, where
// the fit's error would exceed the change the footprint makes, 1 above k = 0.1 a, log-linear between.
fn specaa_closed_form_share(b: f32) -> f32 { return saturate((log2(b) * 0.30102999566 + 1.5228787) * 1.9124059); }
// Beckmann(K + v I) (TK21 Sec. 2.1), 0 where its exponential underflows (h_z -> 0).
fn specaa_beckmann_node(h: vec3<f32>, K: vec3<f32>, v: f32) -> f32 {
    let B: vec3<f32> = K + vec3<f32>(v, v, 0.0);
    let detB: f32 = max(specaa_sym_det(B), 1.0e-30);
    let z2: f32 = h.z * h.z;
    let g: f32 = exp(-specaa_inverse_quadratic_form(B, h.xy, detB) / z2);
    return select(0.0, g / (3.14159265358979 * sqrt(detB) * z2 * z2), g > 0.0);
}
// The closed form for a roughness matrix A (K = A - a I projected onto the PSD cone, as specaa_convolved_D);
// GGX(A) itself where k_max <= 1e-3 a. `alpha2` is the a the footprint spreads.
fn specaa_convolved_D_closed_form(h: vec3<f32>, A: vec3<f32>, alpha2: f32) -> f32 {
    if (h.z <= 0.0) { return 0.0; }
    let a: f32 = max(alpha2, 1.0e-12);
    let K: vec3<f32> = specaa_sym_clamp_psd(A - vec3<f32>(a, a, 0.0));
    if (max(specaa_sym_max_eigenvalue(K), 0.0) <= 1.0e-3 * a) { return specaa_ggx_D(h, A + vec3<f32>(1.0e-12, 1.0e-12, 0.0), a * a); }
    let k: f32 = max(0.5 * (K.x + K.y), 1.0e-6 * a);
    let n: vec4<f32> = specaa_closed_form_nodes(k / a);
    let nodes: f32 = n.x * specaa_beckmann_node(h, K, a * n.z) + n.y * specaa_beckmann_node(h, K, a * n.w);
    let r2: f32 = dot(h.xy, h.xy);
    let z2: f32 = h.z * h.z;
    let fitted: f32 = specaa_closed_form_tail(r2, z2, a, k) + nodes;
    let hKh: f32 = h.x * h.x * K.x + 2.0 * h.x * h.y * K.z + h.y * h.y * K.y;
    let small: f32 = specaa_small_footprint_D(r2, z2, a, K.x + K.y, hKh);
    let share: f32 = specaa_closed_form_share(k / a); // written out: the expansion is huge and wrong at large k
    return max(0.0, share * fitted + (1.0 - share) * small);
}
// The closed form for an isotropic footprint K = k I (the balanced tier's, whose A is isotropic): no matrix
// algebra; k = 0 is GGX(a).
fn specaa_convolved_D_isotropic(h: vec3<f32>, alpha2: f32, kernel: f32) -> f32 {
    let a: f32 = max(alpha2, 1.0e-12);
    let k: f32 = max(kernel, 1.0e-6 * a);
    let n: vec4<f32> = specaa_closed_form_nodes(k / a);
    let z2: f32 = h.z * h.z;
    let r2: f32 = dot(h.xy, h.xy);
    let v: vec2<f32> = k + a * n.zw; // the nodes' widths
    let g: vec2<f32> = exp(-r2 / (z2 * v));
    let unit: f32 = 3.14159265358979 * z2 * z2;
    // Selects rather than branches (both sides are evaluated; the discarded one may be inf or NaN at h_z = 0).
    let nodeX: f32 = select(0.0, n.x * g.x / (unit * v.x), g.x > 0.0);
    let nodeY: f32 = select(0.0, n.y * g.y / (unit * v.y), g.y > 0.0);
    let nodes: f32 = nodeX + nodeY;
    let fitted: f32 = specaa_closed_form_tail(r2, z2, a, k) + nodes;
    let small: f32 = specaa_small_footprint_D(r2, z2, a, 2.0 * k, k * r2);
    let share: f32 = specaa_closed_form_share(k / a); // written out: the expansion is huge and wrong at large k
    return select(0.0, max(0.0, share * fitted + (1.0 - share) * small), h.z > 0.0);
}
// GGX Smith Lambda, TK21 App. A.3: -1/2 + sqrt(s + o.z^2) / (2 |o.z|), s = [o.x, o.y] A [o.x, o.y]^T,
// evaluated as s / (2 |o.z| (sqrt(s + o.z^2) + |o.z|)) (same value, no cancellation for smooth A).
// +inf at o.z = 0 with s > 0.
fn specaa_ggx_lambda(o: vec3<f32>, A: vec3<f32>) -> f32 {
    let s: f32 = o.x * o.x * A.x + 2.0 * o.x * o.y * A.z + o.y * o.y * A.y;
    let z: f32 = abs(o.z);
    return s / (2.0 * z * (sqrt(s + z * z) + z));
}
// Height-correlated G2 = chi+(i.h) chi+(o.h) / (1 + Lambda(i) + Lambda(o)), TK21 App. A.1, evaluated as
// 2 |i.z| |o.z| / (|o.z| sqrt(q_i) + |i.z| sqrt(q_o)) (same expression times 2 |i.z| |o.z|), which is
// finite at grazing i or o (G2 -> 0). In [0, 1].
fn specaa_ggx_G2(i: vec3<f32>, o: vec3<f32>, h: vec3<f32>, A: vec3<f32>) -> f32 {
    if (dot(i, h) <= 0.0 || dot(o, h) <= 0.0) { return 0.0; }
    let qi: f32 = i.x * i.x * A.x + 2.0 * i.x * i.y * A.z + i.y * i.y * A.y + i.z * i.z;
    let qo: f32 = o.x * o.x * A.x + 2.0 * o.x * o.y * A.z + o.y * o.y * A.y + o.z * o.z;
    let denominator: f32 = abs(o.z) * sqrt(qi) + abs(i.z) * sqrt(qo);
    return select(0.0, 2.0 * abs(i.z) * abs(o.z) / denominator, denominator > 0.0);
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
    roughness: f32, // perceptual roughness r of the material (unused with a roughness texture)
    uv: vec2<f32>, // texture coordinates of the baked textures
    normal: vec3<f32>, // unit interpolated vertex normal (before normal mapping), any space
    position: vec3<f32>, // position in the space of tangent/bitangent (SPECAA_USE_CURVATURE)
    tangent: vec3<f32>, // T = TANGENT.xyz (matrix form, SPECAA_USE_CURVATURE)
    bitangent: vec3<f32>, // B = cross(N, T) * TANGENT.w
    curvature: vec4<f32>, // _SPECAA_CURVATURE (k1, k2, d.x, d.y) (SPECAA_USE_CURVATURE)
    view: vec3<f32>, // unit vector from the surface to the eye, in the space of normal and tangent
}
// Squared roughness a of the material: the baked filtered roughness texture if bound, else r^4.
// Clamped to [0, 1], NaN as 1 (edge policy).
fn specaa_base_alpha2(s: SpecaaSurface) -> f32 {
    return specaa_sanitize_alpha2(specaa_alpha2_from_roughness(s.roughness));
}
// The normal map's spread at this fragment's mip as a kernel matrix, before the gate below (0 without
// kernel/LEAN data); an isotropic kernel texture gives K = t I.
fn specaa_baked_spread_matrix(s: SpecaaSurface) -> vec3<f32> {
    return vec3<f32>(0.0, 0.0, 0.0);
}
// Baked kernel matrix of the default: the spread above, faded out where it is much narrower than the
// material's lobe, K f^2 with f = saturate(lambda_max(K) / (SPECAA_KERNEL_GATE a)) (NaN passes through
// for the guards downstream). A spread far below a changes D by a small fraction, and on a smooth bump
// map under a rough material (the normal-mapped sphere at alpha 0.2-0.5) that change raised the flicker
// above no filtering's (alpha 0.2: 1.0025x tone-mapped, 0.3: 1.017x, 0.5: 1.012x); no filtering's flicker
// there is the engine's trilinear sampling of the mean normal, which no widening of the lobe removes.
// Kernels of half of a or more pass whole. docs/accuracy.md#the-gate has the forms measured (gates 0.25, 0.5
// and 1, linear and squared fade). The opt-in two lobes gate their rough lobe's kernel the same way.
fn specaa_gate_baked_kernel(K: vec3<f32>, a: f32) -> vec3<f32> {
    let f: f32 = saturate(specaa_sym_max_eigenvalue(K) / max(SPECAA_KERNEL_GATE * a, 1.0e-30));
    return K * select(1.0, f * f, f == f);
}
fn specaa_baked_kernel_matrix(s: SpecaaSurface) -> vec3<f32> {
    return specaa_gate_baked_kernel(specaa_baked_spread_matrix(s), specaa_base_alpha2(s));
}
// The mean tr(K) / 2 of specaa_baked_kernel_matrix (the fast tier's baked kernel; a = specaa_base_alpha2),
// without the matrix for the Sigma kernel: from the texel's eigenvalues l1 >= l2, tr(clamp_psd(Sigma)) =
// max(l1, 0) + max(l2, 0) and lambda_max = max(l1, 0), so tr(K) / 2 = sqrt(g) tr f^2 with the gate's
// f = saturate(2 sqrt(g) max(l1, 0) / (SPECAA_KERNEL_GATE a)). A non-finite texel (l1 or l2 not finite) gives 0.
fn specaa_baked_kernel_mean(s: SpecaaSurface, a: f32) -> f32 {
    let baked: vec3<f32> = specaa_baked_kernel_matrix(s);
    return 0.5 * (baked.x + baked.y);
}
// Footprint of the pixel in the (T, B) frame (specaa_footprint) and whether it and the curvature are
// usable (finite inputs and derivatives; edge policy).
fn specaa_curvature_footprint(s: SpecaaSurface, footprint: ptr<function, vec4<f32>>) -> bool {
    let dPdx: vec3<f32> = dpdx(s.position);
    let dPdy: vec3<f32> = dpdy(s.position);
    (*footprint) = specaa_footprint_tangent(dPdx, dPdy, s.tangent, s.bitangent);
    let m: vec3<u32> = max(max(specaa_magnitude_bits3(s.position), specaa_magnitude_bits3(dPdx)),
                         max(specaa_magnitude_bits3(dPdy), specaa_magnitude_bits3((*footprint).xyw)));
    let c: vec4<u32> = max(bitcast<vec4<u32>>(s.curvature), vec4<u32>(0u, 0u, 0u, bitcast<u32>((*footprint).z))) &
                     vec4<u32>(0x7fffffffu, 0x7fffffffu, 0x7fffffffu, 0x7fffffffu);
    return max(specaa_max_component(m), max(max(c.x, c.y), max(c.z, c.w))) < 0x7f800000u;
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
fn specaa_view_turn_axis(s: SpecaaSurface, dView: vec3<f32>) -> vec3<f32> {
    let turn: vec3<f32> = (dView - s.normal * dot(s.normal, dView)) * (0.5 / max(dot(s.normal, s.view), 1.0e-3));
    return select(vec3<f32>(0.0, 0.0, 0.0), turn, specaa_is_finite3(turn));
}
// Both screen axes' turns in the (T, B) frame, (x.t, x.b, y.t, y.b), for specaa_curvature_kernel_turned.
fn specaa_view_turn(s: SpecaaSurface, tangent: vec3<f32>, bitangent: vec3<f32>) -> vec4<f32> {
    let t: vec3<f32> = normalize(tangent);
    let b: vec3<f32> = normalize(bitangent);
    let x: vec3<f32> = specaa_view_turn_axis(s, dpdx(s.view));
    let y: vec3<f32> = specaa_view_turn_axis(s, dpdy(s.view));
    return vec4<f32>(dot(x, t), dot(x, b), dot(y, t), dot(y, b));
}
// The per-pixel kernel from _SPECAA_CURVATURE over the position's footprint, less the half vector's turn,
// unclamped; returns whether the inputs are usable (specaa_curvature_footprint).
fn specaa_curvature_pixel_kernel(s: SpecaaSurface, K: ptr<function, vec3<f32>>) -> bool {
    var footprint: vec4<f32>;
    let usable: bool = specaa_curvature_footprint(s, &footprint);
    (*K) = specaa_curvature_kernel_turned(s.curvature, footprint, specaa_view_turn(s, s.tangent, s.bitangent));
    return usable;
}
// Per-pixel kernel matrix of the curved geometry in the (T, B) frame: from _SPECAA_CURVATURE and the
// position footprint, or from the quad derivatives of the vertex normal projected onto T and B
// (TK21 Sec. 5.1). Each eigenvalue clamped to at most kappa, the eigenvectors kept (TK21 Sec. 4: "clamp the
// eigenvalues of Sigma"; scaling the whole matrix by kappa / lambda_max instead would also shrink the minor
// axis, and an elongated footprint's peak would come out too bright: ClearCoatTest far,
// docs/accuracy.md#the-per-pixel-kernels-clamp); an overflowing kernel is kappa I, unusable inputs give 0
// (edge policy).
fn specaa_pixel_kernel_matrix(s: SpecaaSurface) -> vec3<f32> {
    let dnU: vec3<f32> = dpdx(s.normal);
    let dnV: vec3<f32> = dpdy(s.normal);
    let t: vec3<f32> = normalize(s.tangent);
    let b: vec3<f32> = normalize(s.bitangent);
    let m: vec3<u32> = max(max(specaa_magnitude_bits3(s.normal), specaa_magnitude_bits3(dnU)),
                         max(specaa_magnitude_bits3(dnV), max(specaa_magnitude_bits3(t), specaa_magnitude_bits3(b))));
    let usable: bool = specaa_max_component(m) < 0x7f800000u;
    // The turn taken off before projecting: four dot products fewer than specaa_view_turn's (x.t, x.b, y.t, y.b).
    let turnU: vec3<f32> = specaa_view_turn_axis(s, dpdx(s.view));
    let turnV: vec3<f32> = specaa_view_turn_axis(s, dpdy(s.view));
    let K: vec3<f32> = specaa_kernel_matrix(vec2<f32>(dot(dnU - turnU, t), dot(dnU - turnU, b)),
                                           vec2<f32>(dot(dnV - turnV, t), dot(dnV - turnV, b)));
    let lmax: f32 = specaa_sym_max_eigenvalue(K);
    let clamped: vec3<f32> = select(K, specaa_sym_clamp_eigenvalues(K, SPECAA_KAPPA), lmax > SPECAA_KAPPA);
    let bounded: bool = max(specaa_magnitude_bits(lmax), specaa_max_component(specaa_magnitude_bits3(clamped))) < 0x7f800000u;
    return select(vec3<f32>(0.0, 0.0, 0.0), select(vec3<f32>(SPECAA_KAPPA, SPECAA_KAPPA, 0.0), clamped, bounded), usable);
}
// Per-pixel isotropic kernel t (mean reduction, TK21 Eq. 14), clamped to kappa. Tangent-free on the
// derivative path (world-space normal derivatives). Edge policy as for the matrix.
fn specaa_pixel_kernel(s: SpecaaSurface) -> f32 {
    let dnU: vec3<f32> = dpdx(s.normal);
    let dnV: vec3<f32> = dpdy(s.normal);
    let usable: bool = specaa_max_component(max(specaa_magnitude_bits3(s.normal),
                                           max(specaa_magnitude_bits3(dnU), specaa_magnitude_bits3(dnV)))) < 0x7f800000u;
    // Finite derivatives give a kernel in [0, +inf] (never NaN): min() is specaa_clamp_kernel there.
    return select(0.0, min(specaa_iso_kernel_mean(dnU - specaa_view_turn_axis(s, dpdx(s.view)), dnV - specaa_view_turn_axis(s, dpdy(s.view))), SPECAA_KAPPA), usable);
}
// Filtered squared roughness a (isotropic form of the default). The baked and per-pixel kernels are variances of
// independent footprints, so they add in projected space (TK21 Eq. 6) before mapping back (Eq. 7).
fn specaa_filtered_alpha2(s: SpecaaSurface) -> f32 {
    let baked: vec3<f32> = specaa_baked_kernel_matrix(s);
    let a: f32 = specaa_filter_projected_isotropic(specaa_base_alpha2(s), 0.5 * (baked.x + baked.y) + specaa_pixel_kernel(s));
    return select(1.0, a, specaa_is_finite(a));
}
// Filtered perceptual roughness r = a^(1/4): drop-in for the material's roughness.
fn specaa_filtered_roughness(s: SpecaaSurface) -> f32 { return specaa_roughness_from_alpha2(specaa_filtered_alpha2(s)); }
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
fn specaa_environment_kernel(s: SpecaaSurface) -> f32 {
    // Without s.view the differentiated direction is the normal itself: dn whole, as specaa_iso_kernel_mean
    // takes it, not the part of dr / 2 across r.
    let hasView: bool = dot(s.view, s.view) > 0.0;
    let r: vec3<f32> = select(s.normal, reflect(-s.view, s.normal), hasView);
    let scale: f32 = select(1.0, 0.5, hasView);
    let across: f32 = select(0.0, 1.0, hasView);
    var ex: vec3<f32> = scale * dpdx(r);
    var ey: vec3<f32> = scale * dpdy(r);
    ex -= across * r * dot(ex, r);
    ey -= across * r * dot(ey, r);
    let usable: bool = specaa_max_component(max(specaa_magnitude_bits3(r), max(specaa_magnitude_bits3(ex), specaa_magnitude_bits3(ey)))) <
                  0x7f800000u;
    return select(0.0, min(specaa_iso_kernel_mean(ex, ey), SPECAA_KAPPA), usable);
}
// Filtered squared roughness for a prefiltered environment lookup (the a to pick its mip by): the baked
// spread and specaa_environment_kernel added in projected space (TK21 Eq. 6-7), as specaa_filtered_alpha2
// adds the highlight's kernel.
fn specaa_environment_alpha2(s: SpecaaSurface) -> f32 {
    let baked: vec3<f32> = specaa_baked_kernel_matrix(s);
    let a: f32 = specaa_filter_projected_isotropic(specaa_base_alpha2(s), 0.5 * (baked.x + baked.y) + specaa_environment_kernel(s));
    return select(1.0, a, specaa_is_finite(a));
}
// Filtered perceptual roughness r = a^(1/4) for a prefiltered environment lookup.
fn specaa_environment_roughness(s: SpecaaSurface) -> f32 { return specaa_roughness_from_alpha2(specaa_environment_alpha2(s)); }
// Isotropic a widened by the kernel matrix K in projected space (TK21 Eq. 6-7), non-finite results as I.
fn specaa_widened_matrix(a: f32, K: vec3<f32>) -> vec3<f32> {
    return specaa_guard_matrix(true, vec2<f32>(a, a), specaa_filter_projected_matrix(vec2<f32>(a, a), K));
}
// The default: filtered roughness matrix A_bar in the (T, B) frame, for specaa_default_D / specaa_ggx_G2 (or
// specaa_ggx_D with tau = a^2 of the unfiltered material). Same composition as specaa_filtered_alpha2, with the per-pixel
// kernel kept anisotropic.
fn specaa_filtered_alpha2_matrix(s: SpecaaSurface) -> vec3<f32> {
    return specaa_widened_matrix(specaa_base_alpha2(s), specaa_baked_kernel_matrix(s) + specaa_pixel_kernel_matrix(s));
}
// Level of detail the hardware samples a texture at uv (negative under magnification).
fn specaa_texture_lod(tex: texture_2d<f32>, smp: sampler, uv: vec2<f32>) -> f32 { return specaa_lod_from_derivatives(vec2<f32>(textureDimensions(tex, 0)), uv); }
// GGX(alpha2) convolved with the footprint K = A - a I (the reference tier's specaa_default_D): the quadrature,
// or with SPECAA_CLOSED_FORM_D (diagnostic) its closed form on the anisotropic matrix.
fn specaa_footprint_D(h: vec3<f32>, A: vec3<f32>, alpha2: f32) -> f32 {
    return specaa_convolved_D(h, A, alpha2);
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
fn specaa_default_D(h: vec3<f32>, filteredA: vec3<f32>, s: SpecaaSurface) -> f32 {
    let A: vec3<f32> = filteredA;
    let a: f32 = specaa_base_alpha2(s);
    let share: f32 = 1.0; // rough share g of the texel (two lobes where g < 1)
    let flatD: f32 = 0.0; // the flat share's lobe
    var w: f32 = 0.0;
    w = select(1.0, w, w == w);
    let ggx: f32 = specaa_ggx_D(h, A + vec3<f32>(1.0e-12, 1.0e-12, 0.0), a * a); // floored: a mirror stays finite
    var roughD: f32 = ggx;
    if (w < 1.0) { roughD = ggx + (1.0 - w) * (specaa_footprint_D(h, A, a) - ggx); }
    return share * roughD + (1.0 - share) * flatD;
}

// ===================================================================================================
// The default entry points with the bake's default output, the Sigma kernel texture (`*_kernel`:
// RGBA = Sigma xx, yy, xy and its rough share g, R16G16B16A16_SFLOAT, bound with linear mip filtering):
// the body again with SPECAA_KERNEL_TEXTURE and SPECAA_KERNEL_ANISOTROPIC (shaders/to_wgsl.py), each
// function that differs from the one above, or calls one that does, named with the suffix _kernel and
// taking the texture and its sampler as its last parameters:
//   specaa_filtered_alpha2_matrix_kernel(s, kernelTexture, kernelSampler)
//   specaa_default_D_kernel(h, A, s, kernelTexture, kernelSampler)  (with specaa_ggx_G2 as above)
//   specaa_filtered_roughness_kernel / specaa_filtered_alpha2_kernel(s, kernelTexture, kernelSampler)
// ===================================================================================================

// specaa_baked_spread_matrix with the baked texture.
fn specaa_baked_spread_matrix_kernel(s: SpecaaSurface, kernelTexture: texture_2d<f32>, kernelSampler: sampler) -> vec3<f32> {
    // The single lobe of a texel with rough share g: K = 2 Sigma sqrt(g), not 2 Sigma. A texel of a flat
    // field with a few steep grooves or seams (g small) is a spike at the flat normal plus a wide rough
    // part; the Gaussian of its covariance spreads the spike's highlight over the grooves' slopes, while
    // the Gaussian closest to the mixture in L2 (the radiance error over half vectors) is far narrower
    // (K / (2 Sigma) = 0.11-0.24 at g = 0.1-0.5 for a rough part 10x the material's lobe). The covariance
    // is what keeps the rough part's sparkle down where it is lit; sqrt(g) sits between the two ends
    // (g^0 and g^1). g = 1 (every texel steep, or bakes before the rough share) is the covariance itself.
    // The measurements (g^0, g^0.25, g^0.5, g^0.75, g^1): docs/accuracy.md#the-single-lobe-of-a-mixed-texel.
    let k: vec4<f32> = specaa_sample_kernel_texel(kernelTexture, kernelSampler, s.uv);
    return (2.0 * sqrt(k.w)) * k.xyz;
}

// specaa_baked_kernel_matrix with the baked texture.
fn specaa_baked_kernel_matrix_kernel(s: SpecaaSurface, kernelTexture: texture_2d<f32>, kernelSampler: sampler) -> vec3<f32> {
    return specaa_gate_baked_kernel(specaa_baked_spread_matrix_kernel(s, kernelTexture, kernelSampler), specaa_base_alpha2(s));
}

// specaa_baked_kernel_mean with the baked texture.
fn specaa_baked_kernel_mean_kernel(s: SpecaaSurface, a: f32, kernelTexture: texture_2d<f32>, kernelSampler: sampler) -> f32 {
    let k: vec4<f32> = specaa_sample_kernel_raw(kernelTexture, kernelSampler, s.uv);
    let halfTrace: f32 = 0.5 * (k.x + k.y);
    let halfDiff: f32 = 0.5 * (k.x - k.y);
    let radius: f32 = sqrt(halfDiff * halfDiff + k.z * k.z);
    let l1: f32 = max(halfTrace + radius, 0.0);
    let l2: f32 = halfTrace - radius;
    let share: f32 = sqrt(specaa_rough_share(k.w));
    let f: f32 = saturate(2.0 * share * l1 / max(SPECAA_KERNEL_GATE * a, 1.0e-30));
    let t: f32 = share * (l1 + max(l2, 0.0)) * select(1.0, f * f, f == f);
    return select(0.0, t, specaa_is_finite(l1) && specaa_is_finite(l2));
}

// specaa_filtered_alpha2 with the baked texture.
fn specaa_filtered_alpha2_kernel(s: SpecaaSurface, kernelTexture: texture_2d<f32>, kernelSampler: sampler) -> f32 {
    let baked: vec3<f32> = specaa_baked_kernel_matrix_kernel(s, kernelTexture, kernelSampler);
    let a: f32 = specaa_filter_projected_isotropic(specaa_base_alpha2(s), 0.5 * (baked.x + baked.y) + specaa_pixel_kernel(s));
    return select(1.0, a, specaa_is_finite(a));
}

// specaa_filtered_roughness with the baked texture.
fn specaa_filtered_roughness_kernel(s: SpecaaSurface, kernelTexture: texture_2d<f32>, kernelSampler: sampler) -> f32 { return specaa_roughness_from_alpha2(specaa_filtered_alpha2_kernel(s, kernelTexture, kernelSampler)); }

// specaa_environment_alpha2 with the baked texture.
fn specaa_environment_alpha2_kernel(s: SpecaaSurface, kernelTexture: texture_2d<f32>, kernelSampler: sampler) -> f32 {
    let baked: vec3<f32> = specaa_baked_kernel_matrix_kernel(s, kernelTexture, kernelSampler);
    let a: f32 = specaa_filter_projected_isotropic(specaa_base_alpha2(s), 0.5 * (baked.x + baked.y) + specaa_environment_kernel(s));
    return select(1.0, a, specaa_is_finite(a));
}

// specaa_environment_roughness with the baked texture.
fn specaa_environment_roughness_kernel(s: SpecaaSurface, kernelTexture: texture_2d<f32>, kernelSampler: sampler) -> f32 { return specaa_roughness_from_alpha2(specaa_environment_alpha2_kernel(s, kernelTexture, kernelSampler)); }

// specaa_filtered_alpha2_matrix with the baked texture.
fn specaa_filtered_alpha2_matrix_kernel(s: SpecaaSurface, kernelTexture: texture_2d<f32>, kernelSampler: sampler) -> vec3<f32> {
    return specaa_widened_matrix(specaa_base_alpha2(s), specaa_baked_kernel_matrix_kernel(s, kernelTexture, kernelSampler) + specaa_pixel_kernel_matrix(s));
}

// specaa_default_D with the baked texture.
fn specaa_default_D_kernel(h: vec3<f32>, filteredA: vec3<f32>, s: SpecaaSurface, kernelTexture: texture_2d<f32>, kernelSampler: sampler) -> f32 {
    let A: vec3<f32> = filteredA;
    let a: f32 = specaa_base_alpha2(s);
    let share: f32 = 1.0; // rough share g of the texel (two lobes where g < 1)
    let flatD: f32 = 0.0; // the flat share's lobe
    let lod: f32 = specaa_texture_lod(kernelTexture, kernelSampler, s.uv);
    // The blend weight is judged on the spread's shape: the baked spread's major axis and the minor axis of
    // the rest of K = A - a I (the per-pixel kernel). The pixel kernel is the image of the Gaussian pixel
    // filter under the surface's curvature (TK21 Eq. 3), for which the convolution is exact; a large one
    // along one direction only (a rim's or a strongly curved small part's arc of normals, up to kappa) keeps
    // the convolution, as GGX(A)'s tails would put a flickering halo along it; one large in every direction
    // (geometry of mesh within the footprint, a dome a pixel wide, which the clamped kernel hides) takes
    // GGX(A), which is what fits there (docs/accuracy.md#the-ggxa-share-judged-on-the-spreads-shape).
    // Diagnostics: SPECAA_BLEND_FROM_LARGEST_AXIS judges it on the largest eigenvalue of
    // all of K (the rule before), SPECAA_BLEND_FROM_BAKED_SPREAD on the baked spread alone.
    let spread: vec3<f32> = A - vec3<f32>(a, a, 0.0);
    let bakedSpread: vec3<f32> = specaa_baked_kernel_matrix_kernel(s, kernelTexture, kernelSampler);
    let rest: vec3<f32> = spread - bakedSpread;
    let restMinor: f32 = 0.5 * (rest.x + rest.y) - sqrt(0.25 * (rest.x - rest.y) * (rest.x - rest.y) + rest.z * rest.z);
    var bakedShare: f32 = saturate(SPECAA_GGX_SPREAD * specaa_sym_max_eigenvalue(bakedSpread));
    // The Sigma kernel's texel also holds the shape of its spread: the rough share g (the part of its normals
    // steeper than slope 0.02), which for a spike and a slab is 2 / kurtosis. GGX(A) stands for a heavy-tailed
    // spread, the convolution for a Gaussian one, so the baked spread asks for GGX(A) by 1 - g = 1 - 2 / kurtosis
    // (0 for a broad spread whose normals all lie on the slope, 1 for a few steep normals among flat ones).
    // Measured: LightsPunctualLamp near, a broad spread (g 0.6-0.95) that GGX(A) haloed, joins and no pair
    // leaves (docs/accuracy.md#the-ggxa-share-judged-on-the-spreads-shape). SPECAA_BLEND_FROM_SPREAD_SIZE
    // (diagnostic) judges on the size alone, as before; so does SPECAA_KERNEL_COVARIANCE, the lobe of earlier
    // releases, which reads no g.
    bakedShare *= 1.0 - specaa_sample_kernel_rough_share(kernelTexture, kernelSampler, s.uv);
    var w: f32 = saturate(lod) * max(bakedShare, saturate(SPECAA_GGX_SPREAD * restMinor));
    w = select(1.0, w, w == w);
    let ggx: f32 = specaa_ggx_D(h, A + vec3<f32>(1.0e-12, 1.0e-12, 0.0), a * a); // floored: a mirror stays finite
    var roughD: f32 = ggx;
    if (w < 1.0) { roughD = ggx + (1.0 - w) * (specaa_footprint_D(h, A, a) - ggx); }
    return share * roughD + (1.0 - share) * flatD;
}
