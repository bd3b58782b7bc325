#include "verify/renderer.h"

#include "verify/float3_math_internal.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>

namespace specbake::verify {
namespace {

using Mat4 = std::array<float, 16>;  // column-major, as glUniformMatrix4fv expects

// Right-handed look-at times OpenGL perspective projection (depth to [-1, 1]).
Mat4 view_projection(const SimCamera& c, float aspect, float near_plane, float far_plane) {
    const Float3 f = unit(sub(c.target, c.position));
    const Float3 s = unit(cross3(f, c.up));
    const Float3 u = cross3(s, f);
    const float g = 1.0f / std::tan(0.5f * c.fov_y_degrees * std::numbers::pi_v<float> / 180.0f);
    const float p00 = g / aspect, p11 = g, p22 = (far_plane + near_plane) / (near_plane - far_plane),
                p23 = 2 * far_plane * near_plane / (near_plane - far_plane);
    // rows of the view matrix: s, u, -f; translation -R * eye
    const float tx = -dot3(s, c.position), ty = -dot3(u, c.position), tz = dot3(f, c.position);
    Mat4 m{};
    const float view[3][4] = {{s[0], s[1], s[2], tx}, {u[0], u[1], u[2], ty}, {-f[0], -f[1], -f[2], tz}};
    for (int col = 0; col < 4; ++col) {
        m[col * 4 + 0] = p00 * view[0][col];
        m[col * 4 + 1] = p11 * view[1][col];
        m[col * 4 + 2] = p22 * view[2][col] + (col == 3 ? p23 : 0.0f);
        m[col * 4 + 3] = -view[2][col];
    }
    return m;
}

// Deterministic hash to [0, 1) for the jitter inside each stratum.
double hash01(uint32_t a, uint32_t b, uint32_t c) {
    uint64_t h = 0x9E3779B97F4A7C15ull ^ (uint64_t(a) << 40) ^ (uint64_t(b) << 20) ^ c;
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdull;
    h ^= h >> 33;
    h *= 0xc4ceb9fe1a85ec53ull;
    h ^= h >> 33;
    return double(h >> 11) * (1.0 / 9007199254740992.0);
}

constexpr const char* kVertexShader = R"(#version 450 core
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec4 aTangent;
layout(location = 3) in vec2 aUv;
layout(location = 4) in vec4 aCurvature;
layout(location = 5) in float aEdge;
uniform mat4 uViewProjection;
uniform vec2 uJitterNdc;
out vec3 vPosition;
out vec3 vNormal;
out vec4 vTangent;
out vec2 vUv;
out vec4 vCurvature;
out float vEdge;
invariant gl_Position;
void main() {
    vPosition = aPosition;
    vNormal = aNormal;
    vTangent = aTangent;
    vUv = aUv;
    vCurvature = aCurvature;
    vEdge = aEdge;
    gl_Position = uViewProjection * vec4(aPosition, 1.0);
    gl_Position.xy += uJitterNdc * gl_Position.w;
}
)";

// Inputs shared by the ground-truth and candidate fragment shaders.
constexpr const char* kFragmentInputs = R"(
in vec3 vPosition;
in vec3 vNormal;
in vec4 vTangent;
in vec2 vUv;
in vec4 vCurvature;
in float vEdge;
uniform vec3 uCameraPosition;
uniform vec3 uCameraForward;
uniform int uLightType[8];        // 0 directional, 1 point, 2 spot
uniform vec3 uLightDirection[8];  // directional: towards the light; spot: the spot's axis
uniform vec3 uLightPosition[8];
uniform float uLightRadiance[8];  // directional: irradiance; point/spot: intensity
uniform float uLightRange[8];     // 0: unlimited
uniform vec2 uLightCone[8];       // spot: (scale, offset) of the glTF angular attenuation
uniform int uLightCount;
uniform float uRoughness;
uniform int uNormalMapped;
uniform int uRoughnessMapped;
uniform float uUvScale;
uniform sampler2D uNormalMap;
uniform sampler2D uRoughnessMap;
uniform float uTanHalfFovY;
uniform float uViewportHeight;
uniform sampler2D uBakedRoughness;
uniform sampler2D uBakedKernel;
uniform sampler2D uBakedLean0;
uniform sampler2D uBakedLean1;
layout(location = 0) out vec4 oColor;
// Unit vector from `p` towards light k and the irradiance E it delivers to a surface facing it, with the
// KHR_lights_punctual falloff: inverse square, range window clamp(1 - (d / range)^4, 0, 1) and the spot's
// smooth cone, saturate(cos * scale + offset)^2.
vec3 simLight(int k, vec3 p, out float E) {
    if (uLightType[k] == 0) { E = uLightRadiance[k]; return uLightDirection[k]; }
    vec3 d = uLightPosition[k] - p;
    float d2 = max(dot(d, d), 1.0e-12);
    vec3 l = d * inversesqrt(d2);
    E = uLightRadiance[k] / d2;
    if (uLightRange[k] > 0.0) {
        float x = d2 / (uLightRange[k] * uLightRange[k]);
        E *= clamp(1.0 - x * x, 0.0, 1.0);
    }
    if (uLightType[k] == 2) {
        float c = clamp(dot(uLightDirection[k], -l) * uLightCone[k].x + uLightCone[k].y, 0.0, 1.0);
        E *= c * c;
    }
    return l;
}
)";

// Ground truth: unfiltered isotropic GGX written independently of the include, in the Walter et al. 2007
// form D = a / (pi ((n.h)^2 (a - 1) + 1)^2) and Smith Lambda = (-1 + sqrt(1 + a tan^2)) / 2, so that an
// error in the include's GGX shows up as a difference instead of cancelling.
// Each sample stands for its stratum, a square of uStratum high-resolution texels a side (w). With
// uStratum > 0 the highlight is integrated analytically around each sample instead of point-sampled:
// near the sample the shading normal and the half vector move linearly (bilinear texels, interpolated
// vertex normals), so averaging D over a screen-space Gaussian of variance v per axis is D convolved with
// the image of that Gaussian under J = d(projected half vector)/d(screen), i.e. GGX with the roughness
// matrix a I + K, K = 2 v J J^T (TK21 Eq. 3 and 9, with this Gaussian in place of the pixel filter).
// v = w^2 / 2: Gaussians of standard deviation 0.71 w placed every w sum to a constant within 1e-4, so a
// highlight far narrower than a sample (r = 0.045 under a punctual light) enters the pixel with the same
// weight wherever it falls between samples (the box's own variance, w^2 / 12, would leave a 39% ripple;
// w^2 / 4 measured a floor of 12% of no filtering's error on NormalTangentTest, w^2 / 2 8%).
// The price is a pixel filter wider by v (1/512 pixel^2 at 256 spp against sigma^2 = 0.159), which
// shrinks 4x per 4x samples, so the estimator converges to the point-sampled integral.
constexpr const char* kGroundTruthMain = R"(
const float PI = 3.14159265358979;
uniform float uStratum;  // stratum width w in high-resolution texels; 0: point samples
float lambdaGGX(float c, float a) { float c2 = c * c; return 0.5 * (-1.0 + sqrt(1.0 + a * (1.0 - c2) / c2)); }
void main() {
    vec3 nGeo = normalize(vNormal);
    vec3 t = normalize(vTangent.xyz - nGeo * dot(nGeo, vTangent.xyz));
    vec3 b = cross(nGeo, t) * vTangent.w;
    vec3 n = nGeo;
    if (uNormalMapped != 0) {
        vec3 m = textureLod(uNormalMap, vUv * uUvScale, 0.0).xyz * 2.0 - 1.0;
        n = normalize(t * m.x + b * m.y + nGeo * m.z);
    }
    vec3 tn = normalize(t - n * dot(n, t));
    vec3 bn = cross(n, tn);
    vec3 v = normalize(uCameraPosition - vPosition);
    float r = uRoughnessMapped != 0 ? textureLod(uRoughnessMap, vUv * uUvScale, 0.0).r : uRoughness;
    float alpha = r * r;
    float a = max(alpha * alpha, 1.0e-12);
    float nv = dot(n, v);
    float radiance = 0.0;
    for (int k = 0; k < uLightCount; ++k) {
        float E;
        vec3 l = simLight(k, vPosition, E);
        vec3 h = normalize(l + v);
        // Derivatives in uniform control flow, before any sample is skipped.
        vec2 hp = vec2(dot(h, tn), dot(h, bn));
        vec2 du = dFdx(hp) * uStratum;
        vec2 dv = dFdy(hp) * uStratum;
        vec3 K = 1.0 * vec3(du.x * du.x + dv.x * dv.x, du.y * du.y + dv.y * dv.y, du.x * du.y + dv.x * dv.y);
        // Quad derivatives across a texel or triangle crease can be large: a stratum never spreads the
        // half vector by more than the pixel kernel clamp (kappa = 0.18).
        float kmax = 0.5 * (K.x + K.y) + sqrt(0.25 * (K.x - K.y) * (K.x - K.y) + K.z * K.z);
        if (!(kmax <= 0.18)) K = kmax > 0.18 ? K * (0.18 / kmax) : vec3(0.0);
        float nl = dot(n, l);
        float nh = dot(n, h);
        if (nl <= 0.0 || nv <= 0.0 || nh <= 0.0 || dot(h, l) <= 0.0) continue;
        float D;
        if (K.x + K.y > 0.0) {
            // Anisotropic GGX with roughness matrix A = a I + K: D = 1 / (pi sqrt(det A) h_z^4 (1 + s^T A^-1 s)^2),
            // s = h.xy / h_z the slope of h in the shading frame.
            vec3 A = vec3(a + K.x, a + K.y, K.z);
            float det = A.x * A.y - A.z * A.z;
            vec2 sl = hp / nh;
            float q = (A.y * sl.x * sl.x - 2.0 * A.z * sl.x * sl.y + A.x * sl.y * sl.y) / det;
            float nh2 = nh * nh;
            D = 1.0 / (PI * sqrt(det) * nh2 * nh2 * (1.0 + q) * (1.0 + q));
        } else {
            float d = nh * nh * (a - 1.0) + 1.0;
            D = a / (PI * d * d);
        }
        float aG = a + 0.5 * (K.x + K.y);
        float G2 = 1.0 / (1.0 + lambdaGGX(nl, aG) + lambdaGGX(nv, aG));
        radiance += D * G2 / (4.0 * nv) * E;
    }
    oColor = vec4(radiance, 1.0, 0.0, 1.0);
}
)";

constexpr const char* kCandidateMainHead = R"(
void main() {
    vec3 nGeo = normalize(vNormal);
    vec3 t = normalize(vTangent.xyz - nGeo * dot(nGeo, vTangent.xyz));
    vec3 b = cross(nGeo, t) * vTangent.w;
    vec2 uv = vUv * uUvScale;
    vec3 n = nGeo;
    if (uNormalMapped != 0) {
        vec3 m = texture(uNormalMap, uv).xyz * 2.0 - 1.0;
        n = normalize(t * m.x + b * m.y + nGeo * m.z);
    }
    // Shading tangent frame around the (normal-mapped) shading normal.
    vec3 tn = normalize(t - n * dot(n, t));
    vec3 bn = cross(n, tn) * vTangent.w;
    vec3 v = normalize(uCameraPosition - vPosition);
    vec3 vTS = vec3(dot(v, tn), dot(v, bn), dot(v, n));
    SpecaaSurface s;
    // An unfiltered material samples its roughness map with the hardware's plain mips.
    s.roughness = uRoughnessMapped != 0 ? texture(uRoughnessMap, uv).r : uRoughness;
    s.uv = uv;
    s.normal = nGeo;
    s.position = vPosition;
    s.tangent = t;
    s.bitangent = b;
    s.curvature = vCurvature;
    s.view = v;
    float alpha = s.roughness * s.roughness;
    float a = alpha * alpha;
    float viewDepth = dot(vPosition - uCameraPosition, uCameraForward);
    float radiance = 0.0;
    for (int k = 0; k < uLightCount; ++k) {
        float E;
        vec3 l = simLight(k, vPosition, E);
        vec3 h = normalize(l + v);
        vec3 hTS = vec3(dot(h, tn), dot(h, bn), dot(h, n));
        vec3 lTS = vec3(dot(l, tn), dot(l, bn), dot(l, n));
        vec3 A;
)";

// The NDF is GGX with the filtered matrix unless the candidate's defines name another (SIM_NDF).
// SIM_HORIZON_BOUND (a diagnostic, verify --variant): the spread the filter adds along the view's
// tangential direction is bounded by (n.v)^2, the squared projected distance from the shading normal to the
// view's horizon: normals past it face away and are in no pixel's footprint
// (docs/accuracy.md#the-whole-corpus-at-bench-settings). SIM_G2_MATERIAL (a diagnostic): G2 masks with the
// material's a instead of the filtered matrix (docs/accuracy.md#other-rules-measured-and-not-kept).
constexpr const char* kCandidateMainTail = R"(
#ifdef SIM_HORIZON_BOUND
        {
            vec2 d = vTS.xy;
            float l2 = dot(d, d);
            if (l2 > 1.0e-12) {
                d *= inversesqrt(l2);
                vec3 K = A - vec3(a, a, 0.0);
                float kvv = d.x * d.x * K.x + 2.0 * d.x * d.y * K.z + d.y * d.y * K.y;
                float bound = vTS.z * vTS.z;
                if (kvv > bound) {
                    mat2 P = mat2(1.0) - outerProduct(d, d);
                    mat2 Km = P * mat2(K.x, K.z, K.z, K.y) * P + bound * outerProduct(d, d);
                    A = vec3(a + Km[0][0], a + Km[1][1], Km[0][1]);
                }
            }
        }
#endif
#ifndef SIM_NDF
#define SIM_NDF(h, A, a) specaa_ggx_D(h, A, (a) * (a))
#endif
#ifdef SIM_G2_MATERIAL
        vec3 AG = vec3(a, a, 0.0);
#else
        vec3 AG = A;
#endif
        if (lTS.z > 0.0 && vTS.z > 0.0)
            radiance += SIM_NDF(hTS, A, a) * specaa_ggx_G2(lTS, vTS, hTS, AG) / (4.0 * vTS.z) * E;
    }
    oColor = vec4(radiance, 1.0, 0.0, 1.0);
}
)";

// Glint ground truth and candidates (C21): the include's glint path for materials with uGlint set; other
// objects write coverage 0. SIM_GLINT_REFERENCE: C21's reference (no GGAA, no LEAN, normal and roughness
// maps at full resolution, the cell footprint frozen to the output pixel by uGlintFootprintScale).
// Derivatives are taken before any non-uniform branch: the UV's here, the half vector's at the top of the
// light loop, whose bound is uniform.
constexpr const char* kGlintMain = R"(
uniform sampler2DArray uGlintDictionary;
uniform int uGlint;
uniform vec4 uGlintParams;  // logDensity, relativeArea, densityRandomization, uvScale
uniform float uGlintFootprintScale;
#ifndef SIM_GLINT_LEAN
#define SIM_GLINT_LEAN 0
#endif
#ifndef SIM_GLINT_KERNEL_SCALE
#define SIM_GLINT_KERNEL_SCALE 0.0
#endif
#ifdef SIM_GLINT_REFERENCE
#define SIM_FETCH(tex, uv) textureLod(tex, uv, 0.0)
#else
#define SIM_FETCH(tex, uv) texture(tex, uv)
#endif
void main() {
    vec3 nGeo = normalize(vNormal);
    vec3 t = normalize(vTangent.xyz - nGeo * dot(nGeo, vTangent.xyz));
    vec3 b = cross(nGeo, t) * vTangent.w;
    vec2 uvMap = vUv * uUvScale;
    vec2 uvGlint = vUv * uGlintParams.w;
    vec4 duv = specaa_glint_derivatives(uvGlint) * uGlintFootprintScale;
    float r = uRoughnessMapped != 0 ? SIM_FETCH(uRoughnessMap, uvMap).r : uRoughness;
    float alpha = r * r;
    // Beckmann slope covariance alpha^2 / 2 per axis (sigma = alpha / sqrt 2, C21 Sec. 3).
    vec3 sigma = vec3(0.5 * alpha * alpha, 0.5 * alpha * alpha, 0.0);
    vec3 n = nGeo;
#if SIM_GLINT_LEAN > 0
    if (uNormalMapped != 0) {
        // Slope-space LEAN moments (the base roughness folded in): Sigma = M - m m^T (C21 Eq. 16), the
        // shading normal from the mean slope m = -n.xy / n.z.
        vec4 m0 = texture(uBakedLean0, uvMap);
        float mxy = texture(uBakedLean1, uvMap).r;
        sigma = vec3(m0.z - m0.x * m0.x, m0.w - m0.y * m0.y, SIM_GLINT_LEAN == 2 ? mxy - m0.x * m0.y : 0.0);
        n = normalize(-m0.x * t - m0.y * b + nGeo);
    }
#else
    if (uNormalMapped != 0) {
        vec3 m = SIM_FETCH(uNormalMap, uvMap).xyz * 2.0 - 1.0;
        n = normalize(t * m.x + b * m.y + nGeo * m.z);
    }
#endif
    vec3 tn = normalize(t - n * dot(n, t));
    vec3 bn = cross(n, tn) * vTangent.w;
    vec3 v = normalize(uCameraPosition - vPosition);
    vec3 vTS = vec3(dot(v, tn), dot(v, bn), dot(v, n));
    vec3 srr = specaa_glint_sigma_rho(sigma);
    SpecaaGlintParams g;
    g.logDensity = uGlintParams.x;
    g.relativeArea = uGlintParams.y;
    g.densityRandomization = uGlintParams.z;
    g.maxAnisotropy = 4.0;
    g.kernelScale = SIM_GLINT_KERNEL_SCALE;
    float radiance = 0.0;
    for (int k = 0; k < uLightCount; ++k) {
        float E;
        vec3 l = simLight(k, vPosition, E);
        vec3 lTS = vec3(dot(l, tn), dot(l, bn), dot(l, n));
        vec3 hTS = normalize(lTS + vTS);
        vec4 dh = specaa_glint_derivatives(hTS.xy);  // Eq. 21, in the normal-mapped frame
#ifdef SIM_GLINT_SMOOTH
        float G = specaa_glint_vcavity_G2(lTS, vTS, hTS);
        if (G > 0.0 && hTS.z > 0.0) {
            vec2 hs = -hTS.xy / hTS.z;
#ifdef SPECAA_GLINT_GGX
            float p22 = specaa_glint_ggx_P22(hs, srr);
#else
            float p22 = specaa_glint_beckmann_P22(hs, srr);
#endif
            float z2 = hTS.z * hTS.z;
            radiance += p22 / (z2 * z2) * G / (4.0 * vTS.z) * E;
        }
#else
        radiance += specaa_glint_specular(uGlintDictionary, uvGlint, duv, lTS, vTS, dh, srr, g) * E;
#endif
    }
    oColor = uGlint != 0 ? vec4(radiance, 1.0, 0.0, 1.0) : vec4(0.0);
}
)";

Result<GLuint> compile_program(const std::string& vertex, const std::string& fragment) {
    auto vs = compile_glsl_shader(GL_VERTEX_SHADER, vertex);
    if (!vs) return vs.error();
    auto fs = compile_glsl_shader(GL_FRAGMENT_SHADER, fragment);
    if (!fs) {
        glDeleteShader(*vs);
        return fs.error();
    }
    return link_program(*vs, *fs);
}

void set_trilinear_repeat(GLuint tex) {
    glTextureParameteri(tex, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTextureParameteri(tex, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(tex, GL_TEXTURE_WRAP_S, GL_REPEAT);
    glTextureParameteri(tex, GL_TEXTURE_WRAP_T, GL_REPEAT);
}

GLuint upload_mips(const MipChain& chain, int first_channel, int channel_count) {
    static constexpr GLenum internal[] = {0, GL_R32F, GL_RG32F, GL_RGB32F, GL_RGBA32F};
    static constexpr GLenum format[] = {0, GL_RED, GL_RG, GL_RGB, GL_RGBA};
    GLuint tex = 0;
    glCreateTextures(GL_TEXTURE_2D, 1, &tex);
    glTextureStorage2D(tex, GLsizei(chain.levels.size()), internal[channel_count], chain.width(), chain.height());
    std::vector<float> buffer;
    for (size_t level = 0; level < chain.levels.size(); ++level) {
        const Image& im = chain.levels[level];
        buffer.resize(im.texel_count() * size_t(channel_count));
        for (size_t i = 0; i < im.texel_count(); ++i)
            for (int c = 0; c < channel_count; ++c)
                buffer[i * channel_count + c] = im.pixels[i * im.channels + first_channel + c];
        glTextureSubImage2D(tex, GLint(level), 0, 0, im.width, im.height, format[channel_count], GL_FLOAT,
                            buffer.data());
    }
    set_trilinear_repeat(tex);
    return tex;
}

// A 1- or 3-channel map with a full chain of box-filtered mips (glGenerateTextureMipmap), trilinear, repeat.
GLuint upload_with_box_mips(const Image& map) {
    const bool rgb = map.channels == 3;
    GLuint tex = 0;
    const int levels = 1 + int(std::floor(std::log2(double(std::max(map.width, map.height)))));
    glCreateTextures(GL_TEXTURE_2D, 1, &tex);
    glTextureStorage2D(tex, levels, rgb ? GL_RGB32F : GL_R32F, map.width, map.height);
    glTextureSubImage2D(tex, 0, 0, 0, map.width, map.height, rgb ? GL_RGB : GL_RED, GL_FLOAT, map.pixels.data());
    glGenerateTextureMipmap(tex);
    set_trilinear_repeat(tex);
    return tex;
}

// A float colour target with a depth buffer.
struct RenderTarget {
    GLuint fbo = 0, color = 0, depth = 0;
    int width = 0, height = 0;

    bool create(GLenum color_format, int w, int h) {
        glCreateTextures(GL_TEXTURE_2D, 1, &color);
        glTextureStorage2D(color, 1, color_format, w, h);
        glCreateTextures(GL_TEXTURE_2D, 1, &depth);
        glTextureStorage2D(depth, 1, GL_DEPTH_COMPONENT32F, w, h);
        glCreateFramebuffers(1, &fbo);
        glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, color, 0);
        glNamedFramebufferTexture(fbo, GL_DEPTH_ATTACHMENT, depth, 0);
        width = w;
        height = h;
        return glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
    }
    void destroy() {
        if (!fbo) return;
        glDeleteFramebuffers(1, &fbo);
        glDeleteTextures(1, &color);
        glDeleteTextures(1, &depth);
        *this = RenderTarget{};
    }
};

}  // namespace

struct SimRenderer::Impl {
    const SimScene* scene = nullptr;
    int width = 0, height = 0;
    RenderTarget target;  // candidates, at the image size
    RenderTarget gt;      // ground-truth passes, at the supersampled size
    struct Mesh {
        GLuint vao = 0, vertices = 0, indices = 0;
        GLsizei index_count = 0;
        std::map<std::string, GLuint> curvature;  // per-vertex vec4 buffers
    };
    std::vector<Mesh> meshes;
    std::vector<GLuint> normal_maps;
    std::vector<GLuint> roughness_maps;
    std::vector<int> object_sets;  // per object: index into texture_sets(), -1 without a normal map
    struct Baked {
        GLuint roughness = 0, kernel = 0, lean0 = 0, lean1 = 0;
    };
    std::map<std::pair<std::string, int>, Baked> baked;
    GLuint ground_truth = 0;
    GLuint glint_ground_truth = 0;
    GLuint glint_dictionary = 0;
    std::string glint_defines;  // dictionary layout and target, before the include
    bool footprint_ground_truth = true;
    struct Candidate {
        GLuint program = 0;
        SimShaderSpec spec;
    };
    std::vector<Candidate> candidates;
    std::string include;

    void set_frame_uniforms(GLuint program, int frame, float jitter_x, float jitter_y, float footprint_scale = 1.0f) const {
        const SimCamera cam = camera_at_frame(*scene, frame, height);
        const Float3 offset = sub(cam.target, cam.position);
        const float dist = std::sqrt(dot3(offset, offset));
        const float near_plane = std::max(0.01f, dist - 4.0f * scene->object_radius) * 0.25f;
        const float far_plane = dist + 64.0f * scene->object_radius;
        const Mat4 vp = view_projection(cam, float(width) / float(height), near_plane, far_plane);
        glProgramUniformMatrix4fv(program, glGetUniformLocation(program, "uViewProjection"), 1, GL_FALSE, vp.data());
        glProgramUniform2f(program, glGetUniformLocation(program, "uJitterNdc"), jitter_x, jitter_y);
        glProgramUniform3fv(program, glGetUniformLocation(program, "uCameraPosition"), 1, cam.position.data());
        const Float3 forward = unit(offset);
        glProgramUniform3fv(program, glGetUniformLocation(program, "uCameraForward"), 1, forward.data());
        const int count = int(std::min(scene->lights.size(), kMaxSimLights));
        for (int k = 0; k < count; ++k) {
            const SimLight& light = scene->lights[size_t(k)];
            const auto location = [&](const char* name) {
                return glGetUniformLocation(program, (std::string(name) + "[" + std::to_string(k) + "]").c_str());
            };
            glProgramUniform1i(program, location("uLightType"), int(light.type));
            glProgramUniform3fv(program, location("uLightDirection"), 1, light.direction.data());
            glProgramUniform3fv(program, location("uLightPosition"), 1, light.position.data());
            glProgramUniform1f(program, location("uLightRadiance"), light.radiance);
            glProgramUniform1f(program, location("uLightRange"), light.range);
            // KHR_lights_punctual spot attenuation: scale = 1 / max(0.001, cos(inner) - cos(outer)),
            // offset = -cos(outer) scale.
            const float scale = 1.0f / std::max(0.001f, std::cos(light.inner_cone) - std::cos(light.outer_cone));
            glProgramUniform2f(program, location("uLightCone"), scale, -std::cos(light.outer_cone) * scale);
        }
        glProgramUniform1i(program, glGetUniformLocation(program, "uLightCount"), count);
        glProgramUniform1f(program, glGetUniformLocation(program, "uTanHalfFovY"),
                           std::tan(0.5f * cam.fov_y_degrees * std::numbers::pi_v<float> / 180.0f));
        glProgramUniform1f(program, glGetUniformLocation(program, "uViewportHeight"), float(height));
        const char* samplers[] = {"uNormalMap",  "uBakedRoughness", "uBakedKernel",
                                  "uBakedLean0", "uBakedLean1",     "uRoughnessMap"};
        for (int unit_index = 0; unit_index < 6; ++unit_index)
            glProgramUniform1i(program, glGetUniformLocation(program, samplers[unit_index]), unit_index);
        // Glint programs only (the others have no such uniforms: location -1 is ignored).
        glProgramUniform1i(program, glGetUniformLocation(program, "uGlintDictionary"), 6);
        glProgramUniform1f(program, glGetUniformLocation(program, "uGlintFootprintScale"), footprint_scale);
    }

    // Binds object `o`'s material, curvature and baked textures for `program`.
    void bind_object(GLuint program, size_t o, const SimShaderSpec* spec) {
        const SimObject& object = scene->objects[o];
        const SimMaterial& mat = object.material;
        glProgramUniform1f(program, glGetUniformLocation(program, "uRoughness"), mat.roughness);
        glProgramUniform1f(program, glGetUniformLocation(program, "uUvScale"), mat.uv_scale);
        glProgramUniform1i(program, glGetUniformLocation(program, "uNormalMapped"), mat.normal_map >= 0 ? 1 : 0);
        glProgramUniform1i(program, glGetUniformLocation(program, "uRoughnessMapped"), mat.roughness_map >= 0 ? 1 : 0);
        const SimGlints& g = mat.glints;
        glProgramUniform1i(program, glGetUniformLocation(program, "uGlint"), g.enabled ? 1 : 0);
        glProgramUniform4f(program, glGetUniformLocation(program, "uGlintParams"), g.log_density, g.relative_area,
                           g.density_randomization, g.uv_scale);
        GLuint textures[6] = {mat.normal_map >= 0 ? normal_maps[size_t(mat.normal_map)] : 0, 0, 0, 0, 0,
                              mat.roughness_map >= 0 ? roughness_maps[size_t(mat.roughness_map)] : 0};
        Mesh& mesh = meshes[o];
        GLuint curvature = mesh.curvature.at("exact");
        if (spec) {
            if (auto it = mesh.curvature.find(spec->curvature_source); it != mesh.curvature.end())
                curvature = it->second;
            if (!spec->baked_source.empty() && object_sets[o] >= 0) {
                if (auto it = baked.find({spec->baked_source, object_sets[o]}); it != baked.end()) {
                    textures[1] = it->second.roughness;
                    textures[2] = it->second.kernel;
                    textures[3] = it->second.lean0;
                    textures[4] = it->second.lean1;
                }
            } else if (!spec->baked_source.empty()) {
                // Nothing baked for this material (no normal map, SPEC Sec. 6): the engine binds its own
                // roughness (map or constant) in the roughness slot and no kernel or LEAN variance.
                textures[1] = mat.roughness_map >= 0 ? roughness_maps[size_t(mat.roughness_map)]
                                                     : constant_texture(mat.roughness);
                textures[2] = textures[3] = textures[4] = constant_texture(0.0f);
            }
        }
        glBindTextures(0, 6, textures);
        if (glint_dictionary) glBindTextureUnit(6, glint_dictionary);
        glVertexArrayVertexBuffer(mesh.vao, 1, curvature, 0, 4 * sizeof(float));
        glBindVertexArray(mesh.vao);
    }

    // A 1 x 1 texture holding `value` in every channel (cached).
    std::map<float, GLuint> constants;
    GLuint constant_texture(float value) {
        if (auto it = constants.find(value); it != constants.end()) return it->second;
        GLuint tex = 0;
        glCreateTextures(GL_TEXTURE_2D, 1, &tex);
        glTextureStorage2D(tex, 1, GL_RGBA32F, 1, 1);
        const float texel[4] = {value, value, value, value};
        glTextureSubImage2D(tex, 0, 0, 0, 1, 1, GL_RGBA, GL_FLOAT, texel);
        return constants[value] = tex;
    }

    void draw_all(GLuint program, const SimShaderSpec* spec) {
        glUseProgram(program);
        for (size_t o = 0; o < meshes.size(); ++o) {
            bind_object(program, o, spec);
            glDrawElements(GL_TRIANGLES, meshes[o].index_count, GL_UNSIGNED_INT, nullptr);
        }
    }

    SimImage read_back() const {
        std::vector<float> rgba(size_t(width) * height * 4);
        glGetTextureImage(target.color, 0, GL_RGBA, GL_FLOAT, GLsizei(rgba.size() * sizeof(float)), rgba.data());
        SimImage image(width, height, 2);
        for (int y = 0; y < height; ++y) {
            for (int x = 0; x < width; ++x) {
                const float* src = &rgba[(size_t(height - 1 - y) * width + x) * 4];
                float* dst = image.texel(x, y);
                dst[0] = src[0];
                dst[1] = src[1];
            }
        }
        return image;
    }
};

Result<std::unique_ptr<SimRenderer>> SimRenderer::create(const SimScene& scene, int width, int height,
                                                         std::string include_glsl) {
    if (width < 2 || height < 2 || width > 8192 || height > 8192)
        return make_error("image size must be between 2x2 and 8192x8192");
    if (include_glsl.find("specaa_filtered_alpha2") == std::string::npos)
        return make_error("the runtime include text is missing specaa_filtered_alpha2 (not shaders/specaa.glsl?)");
    std::unique_ptr<SimRenderer> r(new SimRenderer());
    r->impl_ = std::make_unique<Impl>();
    Impl& im = *r->impl_;
    im.scene = &scene;
    im.width = width;
    im.height = height;
    im.include = std::move(include_glsl);

    if (!im.target.create(GL_RGBA32F, width, height))
        return make_error("headless OpenGL: float framebuffer is incomplete");

    for (const SimObject& object : scene.objects) {
        const TriMesh& m = object.mesh;
        if (!m.has_normals() || !m.has_tangents() || !m.has_uv0())
            return make_error(m.name + ": the simulator needs normals, tangents and UVs");
        Impl::Mesh mesh;
        std::vector<float> interleaved;
        interleaved.reserve(m.vertex_count() * 13);
        // Attribute 5 (vEdge): each vertex's mean edge length, for SPECAA_PIXEL_KERNEL_EDGE (scene.h).
        const std::vector<float> edge = mean_edge_lengths(m);
        for (size_t v = 0; v < m.vertex_count(); ++v) {
            interleaved.insert(interleaved.end(), &m.positions[3 * v], &m.positions[3 * v] + 3);
            interleaved.insert(interleaved.end(), &m.normals[3 * v], &m.normals[3 * v] + 3);
            interleaved.insert(interleaved.end(), &m.tangents[4 * v], &m.tangents[4 * v] + 4);
            interleaved.insert(interleaved.end(), &m.uv0[2 * v], &m.uv0[2 * v] + 2);
            interleaved.push_back(edge[v]);
        }
        glCreateBuffers(1, &mesh.vertices);
        glNamedBufferStorage(mesh.vertices, GLsizeiptr(interleaved.size() * sizeof(float)), interleaved.data(), 0);
        glCreateBuffers(1, &mesh.indices);
        glNamedBufferStorage(mesh.indices, GLsizeiptr(m.indices.size() * sizeof(uint32_t)), m.indices.data(), 0);
        mesh.index_count = GLsizei(m.indices.size());
        glCreateVertexArrays(1, &mesh.vao);
        glVertexArrayVertexBuffer(mesh.vao, 0, mesh.vertices, 0, 13 * sizeof(float));
        glVertexArrayElementBuffer(mesh.vao, mesh.indices);
        const GLint sizes[] = {3, 3, 4, 2, 1};  // position, normal, tangent, uv, edge length (attribute 5)
        const GLuint locations[] = {0, 1, 2, 3, 5};
        GLuint offset = 0;
        for (GLuint a = 0; a < 5; ++a) {
            glEnableVertexArrayAttrib(mesh.vao, locations[a]);
            glVertexArrayAttribFormat(mesh.vao, locations[a], sizes[a], GL_FLOAT, GL_FALSE, offset * sizeof(float));
            glVertexArrayAttribBinding(mesh.vao, locations[a], 0);
            offset += GLuint(sizes[a]);
        }
        glEnableVertexArrayAttrib(mesh.vao, 4);
        glVertexArrayAttribFormat(mesh.vao, 4, 4, GL_FLOAT, GL_FALSE, 0);
        glVertexArrayAttribBinding(mesh.vao, 4, 1);
        im.meshes.push_back(std::move(mesh));
    }
    texture_sets(scene, &im.object_sets);
    // Scene files have no analytic curvature: zeros, so "exact" is always bound (the candidates that use
    // curvature then name an estimator, see sim_candidates.h).
    for (size_t o = 0; o < scene.objects.size(); ++o) {
        const SimObject& object = scene.objects[o];
        if (object.exact_curvature.values.size() == 4 * object.mesh.vertex_count())
            r->set_curvature("exact", int(o), object.exact_curvature);
        else
            r->set_curvature("exact", int(o), VertexCurvature{std::vector<float>(4 * object.mesh.vertex_count(), 0.0f)});
    }

    // The engine's usual mips: box-filtered encoded normals (renormalised in the shader) and box-filtered r.
    for (const Image& map : scene.normal_maps) im.normal_maps.push_back(upload_with_box_mips(map));
    for (const Image& map : scene.roughness_maps) im.roughness_maps.push_back(upload_with_box_mips(map));

    auto gt = compile_program(kVertexShader, std::string("#version 450 core\n") + kFragmentInputs + kGroundTruthMain);
    if (!gt) return make_error("ground-truth " + gt.error().message);
    im.ground_truth = *gt;
    return r;
}

SimRenderer::~SimRenderer() {
    if (!impl_) return;
    Impl& im = *impl_;
    for (auto& c : im.candidates) glDeleteProgram(c.program);
    glDeleteProgram(im.ground_truth);
    if (im.glint_ground_truth) glDeleteProgram(im.glint_ground_truth);
    if (im.glint_dictionary) glDeleteTextures(1, &im.glint_dictionary);
    for (auto& m : im.meshes) {
        glDeleteVertexArrays(1, &m.vao);
        glDeleteBuffers(1, &m.vertices);
        glDeleteBuffers(1, &m.indices);
        for (auto& [key, buffer] : m.curvature) glDeleteBuffers(1, &buffer);
    }
    for (auto& [key, b] : im.baked) {
        const GLuint t[] = {b.roughness, b.kernel, b.lean0, b.lean1};
        glDeleteTextures(4, t);
    }
    glDeleteTextures(GLsizei(im.normal_maps.size()), im.normal_maps.data());
    glDeleteTextures(GLsizei(im.roughness_maps.size()), im.roughness_maps.data());
    for (auto& [value, tex] : im.constants) glDeleteTextures(1, &tex);
    im.target.destroy();
    im.gt.destroy();
}

void SimRenderer::set_ground_truth_footprint(bool on) { impl_->footprint_ground_truth = on; }

void SimRenderer::set_curvature(const std::string& key, int object, const VertexCurvature& curvature) {
    auto& buffers = impl_->meshes[size_t(object)].curvature;
    if (auto it = buffers.find(key); it != buffers.end()) glDeleteBuffers(1, &it->second);
    GLuint buffer = 0;
    glCreateBuffers(1, &buffer);
    glNamedBufferStorage(buffer, GLsizeiptr(curvature.values.size() * sizeof(float)), curvature.values.data(), 0);
    buffers[key] = buffer;
}

void SimRenderer::set_baked(const std::string& key, int texture_set, const SimBakedTextures& textures) {
    Impl::Baked b;
    if (!textures.roughness.levels.empty()) b.roughness = upload_mips(textures.roughness, 0, 1);
    if (!textures.kernel.levels.empty()) b.kernel = upload_mips(textures.kernel, 0, textures.kernel.channels());
    if (!textures.lean.levels.empty()) {
        b.lean0 = upload_mips(textures.lean, 0, 4);
        b.lean1 = upload_mips(textures.lean, 4, 1);
    }
    impl_->baked[{key, texture_set}] = b;
}

Result<void> SimRenderer::set_glint_dictionary(const GlintDictionary& d, bool ggx) {
    Impl& im = *impl_;
    if (im.glint_dictionary) return make_error("the glint dictionary is already set");
    glCreateTextures(GL_TEXTURE_2D_ARRAY, 1, &im.glint_dictionary);
    glTextureStorage3D(im.glint_dictionary, d.mip_count, GL_RGBA16F, d.settings.width, 1, d.layers);
    for (int m = 0; m < d.mip_count; ++m)
        glTextureSubImage3D(im.glint_dictionary, m, 0, 0, 0, d.settings.width >> m, 1, d.layers, GL_RGBA, GL_FLOAT,
                            d.mips[size_t(m)].pixels.data());
    // The include's addressing (shaders/src/specaa_glints.inc): linear, linear mips, clamp to edge.
    glTextureParameteri(im.glint_dictionary, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTextureParameteri(im.glint_dictionary, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(im.glint_dictionary, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(im.glint_dictionary, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    char sigma[64];
    std::snprintf(sigma, sizeof sigma, "%.17g", glint_sigma_o(d.settings));
    im.glint_defines = "#define SPECAA_GLINT_COUNT " + std::to_string(d.settings.count) + "\n#define SPECAA_GLINT_LEVELS " +
                       std::to_string(d.settings.levels) + "\n#define SPECAA_GLINT_SIGMA_O " + sigma + "\n" +
                       (ggx ? "#define SPECAA_GLINT_GGX\n" : "");
    SimShaderSpec reference;
    reference.glint = true;
    reference.defines = "#define SIM_GLINT_REFERENCE\n";
    auto program = compile_program(kVertexShader, candidate_source(reference));
    if (!program) return make_error("glint ground-truth " + program.error().message);
    im.glint_ground_truth = *program;
    return {};
}

SimImage SimRenderer::render_ground_truth(int frame, int spp, uint32_t seed) {
    return render_filtered(impl_->ground_truth, frame, spp, false, seed);
}

SimImage SimRenderer::render_glint_ground_truth(int frame, int spp, uint32_t seed) {
    return render_filtered(impl_->glint_ground_truth, frame, spp, true, seed);
}

SimImage SimRenderer::render_filtered(unsigned program, int frame, int spp, bool freeze_footprint, uint32_t seed) {
    Impl& im = *impl_;
    const GroundTruthLayout layout = ground_truth_layout(spp, im.width, im.height);
    const int s = layout.scale, q = layout.passes_per_axis;
    const int hw = im.width * s, hh = im.height * s;
    if (im.gt.fbo == 0 || im.gt.width != hw || im.gt.height != hh) {
        im.gt.destroy();
        im.gt.create(GL_RG32F, hw, hh);
    }
    // Gaussian pixel filter, TK21 App. B, truncated at 3 sigma.
    const double sigma2 = 1.0 / (2.0 * std::numbers::pi);
    const double radius = 3.0 * std::sqrt(sigma2);
    const int reach = int(std::ceil(radius * s)) + 1;
    std::vector<double> sum_l(size_t(im.width) * im.height, 0.0), sum_c(sum_l.size(), 0.0), sum_w(sum_l.size(), 0.0);
    std::vector<float> hires(size_t(hw) * hh * 2);
    glBindFramebuffer(GL_FRAMEBUFFER, im.gt.fbo);
    glViewport(0, 0, hw, hh);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_BLEND);
    for (int pj = 0; pj < q; ++pj) {
        for (int pi = 0; pi < q; ++pi) {
            // Pass (pi, pj) puts one sample in sub-stratum (pi, pj) of every high-resolution texel, jittered
            // inside it: over all passes every pixel gets (s q)^2 stratified samples.
            const uint32_t id = uint32_t(pj * q + pi);
            const double jx = (pi + hash01(uint32_t(frame), id, 1 + 2 * seed)) / q;
            const double jy = (pj + hash01(uint32_t(frame), id, 2 + 2 * seed)) / q;
            // The texel (i, j) then samples the image at ((i + jx) / s, (j + jy) / s) in pixels (y down):
            // shift the geometry by (0.5 - jx, -(0.5 - jy)) high-resolution texels.
            im.set_frame_uniforms(program, frame, float(2.0 * (0.5 - jx) / hw), float(-2.0 * (0.5 - jy) / hh),
                                  freeze_footprint ? float(s) : 1.0f);
            // The GGX ground truth integrates the highlight over each sample's stratum; the glint ground truth
            // keeps point samples (its footprint is frozen to the pixel instead).
            glProgramUniform1f(program, glGetUniformLocation(program, "uStratum"),
                               !freeze_footprint && im.footprint_ground_truth ? float(1.0 / q) : 0.0f);
            const float zero[4] = {0, 0, 0, 0};
            const float one = 1.0f;
            glClearNamedFramebufferfv(im.gt.fbo, GL_COLOR, 0, zero);
            glClearNamedFramebufferfv(im.gt.fbo, GL_DEPTH, 0, &one);
            im.draw_all(program, nullptr);
            glGetTextureImage(im.gt.color, 0, GL_RG, GL_FLOAT, GLsizei(hires.size() * sizeof(float)), hires.data());
            for (int y = 0; y < im.height; ++y) {
                const double cy = y + 0.5;
                for (int x = 0; x < im.width; ++x) {
                    const double cx = x + 0.5;
                    double l = 0, c = 0, w = 0;
                    for (int j = std::max(0, y * s - reach); j < std::min(hh, (y + 1) * s + reach); ++j) {
                        const double dy = (j + jy) / s - cy;
                        // GL rows are bottom-up; image rows top-down.
                        const float* row = &hires[size_t(hh - 1 - j) * hw * 2];
                        for (int i = std::max(0, x * s - reach); i < std::min(hw, (x + 1) * s + reach); ++i) {
                            const double dx = (i + jx) / s - cx;
                            const double d2 = dx * dx + dy * dy;
                            if (d2 > radius * radius) continue;
                            const double g = std::exp(-0.5 * d2 / sigma2);
                            l += g * row[2 * i];
                            c += g * row[2 * i + 1];
                            w += g;
                        }
                    }
                    const size_t k = size_t(y) * im.width + x;
                    sum_l[k] += l;
                    sum_c[k] += c;
                    sum_w[k] += w;
                }
            }
        }
    }
    SimImage image(im.width, im.height, 2);
    for (size_t k = 0; k < sum_l.size(); ++k) {
        // Near the image border part of the filter falls outside the image; the weights renormalise.
        image.pixels[2 * k] = sum_w[k] > 0 ? float(sum_l[k] / sum_w[k]) : 0.0f;
        image.pixels[2 * k + 1] = sum_w[k] > 0 ? float(sum_c[k] / sum_w[k]) : 0.0f;
    }
    return image;
}

GroundTruthLayout ground_truth_layout(int spp, int width, int height) {
    GroundTruthLayout layout;
    const int side = std::max(1, int(std::lround(std::sqrt(double(std::max(spp, 1))))));
    // Largest supersampling factor <= 16 that divides the samples per axis and keeps the target <= 4096 a
    // side (8192 for images above 4096): neighbouring samples of one pass are then one stratum apart, so
    // the quad derivatives the footprint estimator takes span the stratum itself (kGroundTruthMain).
    const int limit = std::max(4096, std::max(width, height));
    for (int s = std::min(16, side); s >= 1; --s) {
        if (side % s == 0 && width * s <= limit && height * s <= limit) {
            layout.scale = s;
            break;
        }
    }
    layout.passes_per_axis = side / layout.scale;
    return layout;
}

std::string SimRenderer::candidate_source(const SimShaderSpec& spec) const {
    const Impl& im = *impl_;
    if (spec.glint)
        return std::string("#version 450 core\n") + im.glint_defines + spec.defines + kFragmentInputs + im.include +
               kGlintMain;
    return std::string("#version 450 core\n") + spec.defines + kFragmentInputs + im.include + kCandidateMainHead +
           spec.body + kCandidateMainTail;
}

Result<int> SimRenderer::compile_candidate(const SimShaderSpec& spec) {
    if (spec.glint && !impl_->glint_dictionary) return make_error("a glint candidate needs set_glint_dictionary() first");
    auto program = compile_program(kVertexShader, candidate_source(spec));
    if (!program) return program.error();
    impl_->candidates.push_back({*program, spec});
    return int(impl_->candidates.size() - 1);
}

void SimRenderer::set_candidate_uniform(int id, const char* name, float value) {
    const GLuint program = impl_->candidates[size_t(id)].program;
    glProgramUniform1f(program, glGetUniformLocation(program, name), value);
}

void SimRenderer::draw_candidate(int id, int frame) {
    Impl& im = *impl_;
    const auto& c = im.candidates[size_t(id)];
    glBindFramebuffer(GL_FRAMEBUFFER, im.target.fbo);
    glViewport(0, 0, im.width, im.height);
    const float zero[4] = {0, 0, 0, 0};
    const float one = 1.0f;
    glClearNamedFramebufferfv(im.target.fbo, GL_COLOR, 0, zero);
    glClearNamedFramebufferfv(im.target.fbo, GL_DEPTH, 0, &one);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_BLEND);
    im.set_frame_uniforms(c.program, frame, 0.0f, 0.0f);
    im.draw_all(c.program, &c.spec);
}

SimImage SimRenderer::render_candidate(int id, int frame) {
    draw_candidate(id, frame);
    return impl_->read_back();
}

double SimRenderer::time_candidate(int id, int draws) {
    glFinish();
    const auto start = std::chrono::steady_clock::now();
    for (int k = 0; k < std::max(1, draws); ++k) draw_candidate(id, 0);
    glFinish();
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace specbake::verify
