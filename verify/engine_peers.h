// GLSL of the engines' run-time specular anti-aliasing, the simulator's peer rows "godot", "unity-hdrp",
// "threejs" and "babylon": each the squared GGX roughness a = alpha^2 it shades with, from the material's
// perceptual roughness r (or a) and a normal's screen-space derivatives. Written from the engines'
// published formulas; the C++ twins and where each formula comes from are in bake/peers.h, and
// tests/gl/test_engine_peers.cpp holds the two together on a real GL implementation.
#pragma once

namespace specbake::verify {

inline constexpr const char* kEnginePeersGlsl = R"(
float peer_godot_alpha2(float r, vec3 dndx, vec3 dndy) {
    float variance = 0.25 * (dot(dndx, dndx) + dot(dndy, dndy));
    float r2 = min(1.0, r * r + min(2.0 * variance, 0.18));
    return r2 * r2;
}
float peer_unity_alpha2(float a, vec3 dndx, vec3 dndy) {
    float variance = 0.1 * (dot(dndx, dndx) + dot(dndy, dndy));
    return clamp(a + min(2.0 * variance, 0.2 * 0.2), 0.0, 1.0);
}
float peer_threejs_alpha2(float r, vec3 dndx, vec3 dndy) {
    vec3 d = max(abs(dndx), abs(dndy));
    float rf = min(max(r, 0.0525) + max(max(d.x, d.y), d.z), 1.0);
    return rf * rf * rf * rf;
}
float peer_babylon_alpha2(float r, vec3 dndx, vec3 dndy) {
    float slope2 = max(dot(dndx, dndx), dot(dndy, dndy));
    float rf = max(r, pow(clamp(slope2, 0.0, 1.0), 0.333));
    return rf * rf * rf * rf;
}
)";

}  // namespace specbake::verify
