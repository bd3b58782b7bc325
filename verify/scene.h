// Scenes of the ground-truth simulator: triangle meshes with shading normals, tangents, UVs and curvature,
// one material each (GGX roughness, optional normal map), directional lights and an orbiting camera.
// The built-in scenes are analytic surfaces tessellated finely and shaded with interpolated normals, so
// the ground truth and the candidates see exactly the same shading-normal field (SPEC Sec. 8).
#pragma once

#include "core/image.h"
#include "core/result.h"
#include "core/trimesh.h"

#include <array>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace specbake::verify {

using Float3 = std::array<float, 3>;

// A material's glints (C21), from its SPECBAKE_glints extension (io/gltf/glint_extension.h): simulated only for
// materials that ask for them. The Beckmann slope covariance is alpha^2 / 2 per axis (alpha = r^2), with
// the normal map's LEAN moments added by the LEAN candidates.
struct SimGlints {
    bool enabled = false;
    float log_density = 15.0f;           // ln(microfacets per unit area of the glint UV)
    float relative_area = 1.0f;          // fraction of cells that carry facets
    float density_randomization = 2.0f;  // std of the per-cell level jitter
    float uv_scale = 1.0f;               // glint UV = TEXCOORD_0 * uv_scale
    bool ggx = false;                    // target "ggx" (SPECAA_GLINT_GGX) instead of Beckmann
};

struct SimMaterial {
    float roughness = 0.5f;  // perceptual roughness r (SPEC Sec. 2); alpha = r^2
    int normal_map = -1;     // index into SimScene::normal_maps, -1 for none
    int roughness_map = -1;  // index into SimScene::roughness_maps (replaces `roughness`), -1 for none
    float uv_scale = 1.0f;   // the maps repeat this many times over the UV square
    SimGlints glints;
};

struct SimObject {
    TriMesh mesh;                      // world space; normals, tangents (w = handedness) and UVs present
    // Analytic (k1, k2, d) of the shading-normal field, SPEC Sec. 4; empty when unknown (scene files), and
    // the curvature candidates then use the default estimator instead.
    VertexCurvature exact_curvature;
    SimMaterial material;
};

// Lights the renderer shades with at once; a scene file with more keeps the first ones (noted).
inline constexpr size_t kMaxSimLights = 8;

// A punctual light (KHR_lights_punctual): directional, point or spot. Radiance is monochrome: the
// simulator scores the NDF filter, so the light's colour enters only through its luminance.
struct SimLight {
    enum class Type { Directional, Point, Spot };
    Type type = Type::Directional;
    Float3 direction{0, 1, 0};  // directional: unit vector from the surface towards the light;
                                // spot: unit vector the spot points along
    Float3 position{0, 0, 0};   // point and spot
    float radiance = 1.0f;      // directional: irradiance on a surface facing it; point/spot: intensity
                                // (irradiance = intensity / d^2)
    float range = 0.0f;         // point/spot: glTF range (smooth cut-off), 0 for unlimited
    float inner_cone = 0.0f;    // spot: glTF innerConeAngle and outerConeAngle in radians
    float outer_cone = 0.7853982f;
};

struct SimCamera {
    Float3 position{0, 0, 4};
    Float3 target{0, 0, 0};
    Float3 up{0, 1, 0};
    float fov_y_degrees = 40.0f;
};

struct SimScene {
    std::string name;
    std::vector<SimObject> objects;
    std::vector<Image> normal_maps;     // 3 channels, encoded (n + 1) / 2, +Y green, any size
    std::vector<Image> roughness_maps;  // 1 channel, perceptual roughness r in [0, 1]
    std::vector<SimLight> lights;
    SimCamera camera;
    // Camera motion for temporal metrics: each frame orbits the camera about the target around `up` by the
    // angle that moves a point object_radius in front of the target by about motion_pixels pixels
    // (measured at the target's depth; slightly more on the near side).
    float motion_pixels = 0.35f;
    float object_radius = 1.0f;  // for the motion scale and the automatic framing
    bool from_file = false;          // read by load_sim_scene(): materials keep their own roughness
    bool glints_only = false;        // the built-in glitter scenes: only the glint candidates are scored
    std::vector<std::string> notes;  // what a scene file contained that the simulator leaves out
};

// What one texture bake runs on: a normal map with its material's roughness map or constant roughness.
struct SimTextureSet {
    int normal_map = -1;
    int roughness_map = -1;
    float roughness = 0.5f;
    friend bool operator==(const SimTextureSet&, const SimTextureSet&) = default;
};

// The distinct texture sets of the scene's normal-mapped materials, in first-use order. With
// `object_sets`, also each object's index into them (-1 without a normal map).
std::vector<SimTextureSet> texture_sets(const SimScene& scene, std::vector<int>* object_sets = nullptr);

// True when every object carries its analytic curvature (the built-in scenes).
bool has_exact_curvature(const SimScene& scene);

// Each vertex's mean incident edge length (object space; 0 for a vertex on no triangle): the face size the
// diagnostic SPECAA_PIXEL_KERNEL_EDGE weighs the footprint against (the renderer's attribute vEdge,
// docs/accuracy.md#the-faces-own-turn-and-the-vertexs-average).
std::vector<float> mean_edge_lengths(const TriMesh& mesh);

// Names of the built-in analytic scenes: "sphere", "cylinder" (grazing view), "torus", "bumpy-sphere"
// (normal-mapped).
std::span<const std::string_view> builtin_scene_names();
// Names of the built-in glint scenes (C21): "glitter-sphere" (a glittery sphere under a directional light)
// and "glitter-plane" (a plane tilted 60 degrees with an anisotropic, rotated ridge normal map under a
// point light); make_builtin_scene builds them with glints on (logDensity 15).
std::span<const std::string_view> builtin_glint_scene_names();

// True when some object's material asks for glints.
bool has_glints(const SimScene& scene);

// The built-in scene `name` with every material at perceptual roughness `roughness`. `tessellation`
// scales the mesh resolution (1 = default: a few pixels per triangle at 128 x 128).
Result<SimScene> make_builtin_scene(std::string_view name, float roughness, float tessellation = 1.0f);

// The camera of frame `frame` of `height` pixels: the scene camera orbited about its target (see
// SimScene::motion_pixels). Frame 0 is the scene camera itself.
SimCamera camera_at_frame(const SimScene& scene, int frame, int height);

}  // namespace specbake::verify
