#version 450
// Minimal forward-shading fragment shader using the specbake include: GGX specular from one directional
// light with the roughness filtered by the baked kernel mips (normal-map variance) and the per-pixel
// curvature of the mesh (normal derivatives). Bind the kernel texture written by
// `specbake texture --outputs kernel` with trilinear filtering.
#extension GL_GOOGLE_include_directive : require

layout(binding = 0) uniform sampler2D uKernel;    // baked kernel mips: RGB = Sigma (xx, yy, xy)
#define SPECAA_KERNEL_TEXTURE uKernel
#define SPECAA_KERNEL_ANISOTROPIC                     // the default bake; drop it for --isotropic-kernel (R = t)
#include "specaa.glsl"

layout(location = 0) in vec3 vNormal;    // world-space vertex normal
layout(location = 1) in vec4 vTangent;   // world-space TANGENT (xyz, w = handedness)
layout(location = 2) in vec2 vUv;
layout(location = 3) in vec3 vViewDir;   // world-space direction to the eye

layout(binding = 1) uniform Material {
    vec3 lightDir;     // world-space unit direction to the light
    float roughness;   // perceptual roughness r (glTF)
    vec3 lightColor;
};

layout(location = 0) out vec4 fragColor;

void main() {
    vec3 n = normalize(vNormal);
    SpecaaSurface s;
    s.roughness = roughness;
    s.uv = vUv;
    s.normal = n;
    s.tangent = vTangent.xyz;
    s.bitangent = cross(n, vTangent.xyz) * vTangent.w;
    vec3 v = normalize(vViewDir);
    s.view = v;  // the half vector turns with it across the pixel: part of the per-pixel kernel
    // The default rule: an anisotropic roughness matrix in the (T, B) frame.
    vec3 A = specaa_filtered_alpha2_matrix(s);

    vec3 h = normalize(v + lightDir);
    // Tangent-space vectors in the frame A lives in: T orthogonalised against n, B = cross(n, T) * w.
    vec3 t = normalize(vTangent.xyz - n * dot(n, vTangent.xyz));
    mat3 toTangent = transpose(mat3(t, cross(n, t) * vTangent.w, n));
    vec3 hT = toTangent * h, lT = toTangent * lightDir, vT = toTangent * v;
    float specular = specaa_default_D(hT, A, s) * specaa_ggx_G2(lT, vT, hT, A) / max(4.0 * vT.z, 1e-4);
    fragColor = vec4(lightColor * specular, 1.0);
}
