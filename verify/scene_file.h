// Scenes of the ground-truth simulator read from files (`specbake verify SCENE`): a glTF/GLB scene with its
// node transforms, materials (roughness factor, metallicRoughness G channel, normal texture and its scale),
// KHR_lights_punctual lights and cameras; or any other Assimp-readable mesh with its node transforms and
// material roughness. Only what the scene contains is simulated (SPEC Sec. 6): without lights, one default
// directional light; without a camera, an automatic orbit framing the scene. Everything the simulator
// leaves out (other UV sets, texture transforms, animation, orthographic cameras) is listed in
// SimScene::notes.
#pragma once

#include "core/result.h"
#include "io/files/input_policy.h"
#include "verify/scene.h"

#include <filesystem>

namespace specbake::verify {

// Loads `path` as world-space simulator objects. Meshes get generated normals and tangents where the file
// has none (as the scene bake does); their curvature is unknown (SimObject::exact_curvature stays empty).
// Errors name the file: unreadable, not a scene, no triangles, a texture that does not decode; the scene
// and its textures are read under `policy`.
Result<SimScene> load_sim_scene(const std::filesystem::path& path, const io::InputPolicy& policy = {});

}  // namespace specbake::verify
