// OpenGL renderer of the simulator: uploads a SimScene once, then renders (a) the ground truth, the
// Gaussian pixel-filtered (sigma^2 = 1/(2 pi), TK21 App. B) average of unfiltered GGX over N stratified
// sub-pixel positions with the normal map at full resolution (SPEC Sec. 8), and (b) candidates at one
// sample per pixel, each a fragment shader built on the runtime include (shaders/specaa.glsl).
// Specular only: radiance = D G2 / (4 n.v) * E per light (F = 1), so the images isolate the NDF filter.
#pragma once

#include "bake/glint_dictionary.h"
#include "core/image.h"
#include "core/result.h"
#include "verify/gl_context.h"
#include "verify/scene.h"

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace specbake::verify {

// Baked textures a candidate samples (uploaded with mips, trilinear, repeat), per texture set
// (texture_sets() in sim_scene.h: a normal map with its roughness).
struct SimBakedTextures {
    MipChain roughness;  // 1 channel: filtered perceptual roughness r
    MipChain kernel;     // 1 channel: isotropic kernel t
    MipChain lean;       // 5 channels: (m.x, m.y, M.xx, M.yy, M.xy)
};

// What one candidate shader needs besides the scene: GLSL defines placed before the include, a body that
// sets `vec3 A` (roughness matrix (xx, yy, xy) in the shading tangent frame) from `float a`, `vec3 hTS`,
// `vec3 n` (world shading normal) and `SpecaaSurface s`, the curvature attribute and the baked textures.
// A glint candidate (C21; `glint` set) uses the renderer's glint main instead of `body`: `defines` choose
// SIM_GLINT_SMOOTH (the smooth BRDF), SIM_GLINT_LEAN 0/1/2 (normal map point-sampled / slope-space LEAN
// without / with rho) and SIM_GLINT_KERNEL_SCALE (s_K; 0 is C20 without GGAA).
struct SimShaderSpec {
    std::string defines;
    std::string body;
    std::string curvature_source = "exact";  // key into SimRenderer::set_curvature()
    std::string baked_source;                // key into SimRenderer::set_baked(); empty: none bound
    bool glint = false;
};

// Result image: channel 0 radiance, channel 1 coverage in [0, 1] (fraction of the pixel filter that saw
// the object). Row 0 is the top of the image.
using SimImage = Image;

// How render_ground_truth() takes `spp` samples: (scale * passes_per_axis)^2 per pixel area.
struct GroundTruthLayout {
    int scale = 1;            // supersampling factor of each pass (<= 16, target <= 4096 texels a side)
    int passes_per_axis = 1;  // jittered passes along each axis
    int samples() const { return (scale * passes_per_axis) * (scale * passes_per_axis); }
};
GroundTruthLayout ground_truth_layout(int spp, int width, int height);

class SimRenderer {
public:
    // Uploads `scene` for `width` x `height` images. `include_glsl` is the text of the runtime include
    // (shaders/specaa.glsl, embedded in the specbake executable). Needs a current context (GlContext::create()).
    static Result<std::unique_ptr<SimRenderer>> create(const SimScene& scene, int width, int height,
                                                       std::string include_glsl);
    ~SimRenderer();

    // Per-vertex curvature of object `object` under `key` (the exact analytic one is "exact").
    void set_curvature(const std::string& key, int object, const VertexCurvature& curvature);
    // Baked textures of texture set `texture_set` (index into texture_sets(scene)) under `key`.
    void set_baked(const std::string& key, int texture_set, const SimBakedTextures& textures);

    // Ground truth of frame `frame` with about `spp` stratified samples per pixel area (see
    // ground_truth_layout). Each pass renders the scene at `scale` x the resolution with one jittered sample
    // per texel; every sample within 3 sigma of a pixel centre enters that pixel with its Gaussian weight
    // exp(-d^2 / (2 sigma^2)), and the weighted sums are normalised by the summed weights. `seed` picks
    // the jitter: different seeds give independent estimates of the same integral (the bench's floor).
    SimImage render_ground_truth(int frame, int spp, uint32_t seed = 0);
    // With `on` (the default) each ground-truth sample integrates the highlight over its stratum
    // analytically (renderer.cpp, kGroundTruthMain); off: point samples.
    void set_ground_truth_footprint(bool on);

    // Uploads the glint dictionary (a 2D array with its baked mips, as a run time binds it) and compiles the
    // glint ground truth. `ggx`: the GGX target (SPECAA_GLINT_GGX) for every glint material.
    Result<void> set_glint_dictionary(const GlintDictionary& dictionary, bool ggx);
    // Glint ground truth (C21 Sec. 6) of the materials that ask for glints, with the same sample layout and
    // pixel filter as render_ground_truth: the include's glint SDF without GGAA and without LEAN, the
    // normal map at full resolution, and the cell footprint frozen to the output pixel's (the passes'
    // UV derivatives scaled back by the supersampling factor), so only the half vector is supersampled.
    // Other objects occlude but are not covered (coverage 0).
    SimImage render_glint_ground_truth(int frame, int spp, uint32_t seed = 0);

    // Compiles the candidate shader; the error carries the GL info log.
    Result<int> compile_candidate(const SimShaderSpec& spec);
    // Sets the float uniform `name` of compiled candidate `id` (declared in its spec's defines).
    void set_candidate_uniform(int id, const char* name, float value);
    // Renders compiled candidate `id` at one sample per pixel centre.
    SimImage render_candidate(int id, int frame);
    // Wall time in milliseconds of `draws` back-to-back renders of candidate `id` at frame 0, bounded by
    // glFinish (the renderer is llvmpipe's CPU rasteriser on machines without a GPU).
    double time_candidate(int id, int draws);

    // The full fragment shader text of a candidate (for SPIR-V instruction counts).
    std::string candidate_source(const SimShaderSpec& spec) const;

private:
    SimRenderer() = default;
    void draw_candidate(int id, int frame);
    SimImage render_filtered(unsigned program, int frame, int spp, bool freeze_footprint, uint32_t seed);
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace specbake::verify
