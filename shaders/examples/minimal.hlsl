// Minimal forward-shading pixel shader using the specbake include (HLSL): GGX specular from one
// directional light with the roughness filtered by the baked kernel mips (normal-map variance) and the
// per-pixel curvature of the mesh (normal derivatives). Entry point: main.
Texture2D gKernel : register(t0);        // baked kernel mips: RGB = Sigma (xx, yy, xy)
SamplerState gTrilinear : register(s0);
#define SPECAA_KERNEL_TEXTURE gKernel
#define SPECAA_KERNEL_ANISOTROPIC            // the default bake; drop it for --isotropic-kernel (R = t)
#define SPECAA_SAMPLER gTrilinear
#include "specaa.hlsl"

cbuffer Material : register(b1) {
    float3 lightDir;     // world-space unit direction to the light
    float roughness;     // perceptual roughness r (glTF)
    float3 lightColor;
};

struct PixelInput {
    float4 position : SV_Position;
    float3 normal : NORMAL;       // world-space vertex normal
    float4 tangent : TANGENT;     // world-space TANGENT (xyz, w = handedness)
    float2 uv : TEXCOORD0;
    float3 viewDir : TEXCOORD1;   // world-space direction to the eye
};

float4 main(PixelInput input) : SV_Target {
    float3 n = normalize(input.normal);
    SpecaaSurface s = (SpecaaSurface)0;
    s.roughness = roughness;
    s.uv = input.uv;
    s.normal = n;
    s.tangent = input.tangent.xyz;
    s.bitangent = cross(n, input.tangent.xyz) * input.tangent.w;
    float3 v = normalize(input.viewDir);
    s.view = v;  // the half vector turns with it across the pixel: part of the per-pixel kernel
    // The default rule: an anisotropic roughness matrix in the (T, B) frame.
    float3 A = specaa_filtered_alpha2_matrix(s);

    float3 h = normalize(v + lightDir);
    // Tangent-space vectors in the frame A lives in: T orthogonalised against n, B = cross(n, T) * w.
    float3 t = normalize(input.tangent.xyz - n * dot(n, input.tangent.xyz));
    float3x3 toTangent = float3x3(t, cross(n, t) * input.tangent.w, n);
    float3 hT = mul(toTangent, h), lT = mul(toTangent, lightDir), vT = mul(toTangent, v);
    float specular = specaa_default_D(hT, A, s) * specaa_ggx_G2(lT, vT, hT, A) / max(4.0 * vT.z, 1e-4);
    return float4(lightColor * specular, 1.0);
}
