// HLSL wrapper of entries.inc (see shaders/count_instructions.sh). Entry point: main.
#if defined(SPECAA_COST_TEXTURES)
Texture2D uBaked0 : register(t0);
Texture2D uBaked1 : register(t1);
SamplerState uSampler : register(s0);
#define SPECAA_SAMPLER uSampler
#endif
#if defined(SPECAA_COST_GLINT)
Texture2DArray uGlintDictionary : register(t2);
SamplerState uGlintSampler : register(s1);
#define SPECAA_COST_GLINT_DICTIONARY uGlintDictionary, uGlintSampler
#endif
#include "specaa.hlsl"
#include "cost/entries.inc"

float4 main(float3 hTS : TEXCOORD0, float3 normal : NORMAL, float3 position : TEXCOORD1,
            float4 tangent : TANGENT, float4 curvature : TEXCOORD2, float2 uv : TEXCOORD3,
            float roughness : TEXCOORD4, float3 view : TEXCOORD5) : SV_Target {
    return specaa_cost_eval(hTS, normal, position, tangent, curvature, uv, roughness, view);
}
