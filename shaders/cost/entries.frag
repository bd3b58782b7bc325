#version 450
// GLSL wrapper of entries.inc (see shaders/count_instructions.sh).
#extension GL_GOOGLE_include_directive : require
#if defined(SPECAA_COST_TEXTURES)
layout(binding = 0) uniform sampler2D uBaked0;
layout(binding = 1) uniform sampler2D uBaked1;
#endif
#if defined(SPECAA_COST_GLINT)
layout(binding = 2) uniform sampler2DArray uGlintDictionary;
#define SPECAA_COST_GLINT_DICTIONARY uGlintDictionary
#endif
#include "specaa.glsl"
#include "cost/entries.inc"

layout(location = 0) in vec3 vHalfVector;
layout(location = 1) in vec3 vNormal;
layout(location = 2) in vec3 vPosition;
layout(location = 3) in vec4 vTangent;
layout(location = 4) in vec4 vCurvature;
layout(location = 5) in vec2 vUv;
layout(location = 6) in float vRoughness;
layout(location = 7) in vec3 vView;
layout(location = 0) out vec4 fragColor;

void main() {
    fragColor = specaa_cost_eval(vHalfVector, vNormal, vPosition, vTangent, vCurvature, vUv, vRoughness, vView);
}
