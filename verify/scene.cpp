#include "verify/scene.h"

#include "verify/float3_math_internal.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>

namespace specbake::verify {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

// One vertex of a parametric surface: position, unit normal, unit tangent along increasing u (w = +1,
// B = cross(N, T)) and the curvature attribute (k1, k2, d) with d in the (T, B) frame.
struct SurfacePoint {
    Float3 position;
    Float3 normal;
    Float3 tangent;
    std::array<float, 4> curvature;
};

// Tessellates (u, v) in [0, 1]^2 into a `nu` x `nv` grid of quads (seams duplicated, so UVs stay continuous).
SimObject tessellate(const std::string& name, int nu, int nv, const std::function<SurfacePoint(float, float)>& f) {
    SimObject object;
    TriMesh& m = object.mesh;
    m.name = name;
    for (int j = 0; j <= nv; ++j) {
        for (int i = 0; i <= nu; ++i) {
            const float u = float(i) / float(nu), v = float(j) / float(nv);
            const SurfacePoint p = f(u, v);
            m.positions.insert(m.positions.end(), p.position.begin(), p.position.end());
            m.normals.insert(m.normals.end(), p.normal.begin(), p.normal.end());
            m.tangents.insert(m.tangents.end(), {p.tangent[0], p.tangent[1], p.tangent[2], 1.0f});
            m.uv0.insert(m.uv0.end(), {u, v});
            object.exact_curvature.values.insert(object.exact_curvature.values.end(), p.curvature.begin(),
                                                 p.curvature.end());
        }
    }
    const auto index = [nu](int i, int j) { return uint32_t(j * (nu + 1) + i); };
    for (int j = 0; j < nv; ++j) {
        for (int i = 0; i < nu; ++i) {
            m.indices.insert(m.indices.end(), {index(i, j), index(i, j + 1), index(i + 1, j)});
            m.indices.insert(m.indices.end(), {index(i + 1, j), index(i, j + 1), index(i + 1, j + 1)});
        }
    }
    return object;
}

// Sphere of radius R around `centre`, poles on +-Y: k1 = k2 = 1/R (SPEC Sec. 4 sign convention).
SimObject make_sphere(float radius, Float3 centre, int nu, int nv) {
    return tessellate("sphere", nu, nv, [=](float u, float v) {
        const float phi = 2 * kPi * u;
        // Keep away from the poles by half a ring so the tangent is defined at every vertex.
        const float theta = kPi * (0.002f + 0.996f * v);
        const Float3 n{std::sin(theta) * std::cos(phi), std::cos(theta), -std::sin(theta) * std::sin(phi)};
        return SurfacePoint{{centre[0] + radius * n[0], centre[1] + radius * n[1], centre[2] + radius * n[2]},
                            n,
                            unit({-std::sin(phi), 0.0f, -std::cos(phi)}),
                            {1.0f / radius, 1.0f / radius, 1.0f, 0.0f}};
    });
}

// Cylinder of radius R along X, from -L/2 to L/2: k1 = 1/R around the axis (d = +B), k2 = 0 along it.
SimObject make_cylinder(float radius, float length, int nu, int nv) {
    return tessellate("cylinder", nu, nv, [=](float u, float v) {
        const float phi = 2 * kPi * v;
        const Float3 n{0.0f, std::cos(phi), std::sin(phi)};
        return SurfacePoint{{length * (u - 0.5f), radius * n[1], radius * n[2]}, n, {1.0f, 0.0f, 0.0f},
                            {1.0f / radius, 0.0f, 0.0f, 1.0f}};
    });
}

// Torus around Y with major radius R and tube radius r < R / 2. Principal directions are the tube circle
// (k = 1/r, along B) and the big circle (k = cos(psi) / (R + r cos(psi)), along T; negative inside).
SimObject make_torus(float major, float minor, int nu, int nv) {
    return tessellate("torus", nu, nv, [=](float u, float v) {
        const float phi = 2 * kPi * u, psi = 2 * kPi * v;
        const Float3 n{std::cos(psi) * std::cos(phi), std::sin(psi), -std::cos(psi) * std::sin(phi)};
        const float ring = major + minor * std::cos(psi);
        return SurfacePoint{{ring * std::cos(phi), minor * std::sin(psi), -ring * std::sin(phi)},
                            n,
                            {-std::sin(phi), 0.0f, -std::cos(phi)},
                            {1.0f / minor, std::cos(psi) / ring, 0.0f, 1.0f}};
    });
}

// Tileable bump map: a sum of plane waves with integer frequencies (so it repeats exactly), amplitude
// falling as 1/f, frequencies up to a quarter of the texel rate so every mip level loses detail.
Image make_bump_normal_map(int size, float slope_scale, uint32_t seed) {
    struct Wave {
        float kx, ky, phase, amplitude;
    };
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> uniform01(0.0f, 1.0f);
    std::vector<Wave> waves;
    const int max_frequency = size / 4;
    for (int w = 0; w < 48; ++w) {
        const float f = 4.0f * std::pow(float(max_frequency) / 4.0f, uniform01(rng));
        const float angle = 2 * kPi * uniform01(rng);
        waves.push_back({std::round(f * std::cos(angle)), std::round(f * std::sin(angle)), 2 * kPi * uniform01(rng),
                         1.0f / std::max(1.0f, f)});
    }
    Image map(size, size, 3);
    for (int y = 0; y < size; ++y) {
        for (int x = 0; x < size; ++x) {
            float dhdx = 0, dhdy = 0;
            for (const Wave& w : waves) {
                const float arg = 2 * kPi * (w.kx * x + w.ky * y) / float(size) + w.phase;
                // Height h = amplitude sin(arg) / (2 pi |k|); its gradient per unit UV is amplitude cos(arg) k/|k|.
                const float k = std::max(1.0f, std::sqrt(w.kx * w.kx + w.ky * w.ky));
                dhdx += w.amplitude * std::cos(arg) * w.kx / k;
                dhdy += w.amplitude * std::cos(arg) * w.ky / k;
            }
            const Float3 n = unit({-slope_scale * dhdx, -slope_scale * dhdy, 1.0f});
            float* t = map.texel(x, y);
            for (int c = 0; c < 3; ++c) t[c] = 0.5f * (n[c] + 1.0f);
        }
    }
    return map;
}

// Scratch normal map: sparse grooves on a flat field (most texels exactly flat, a few steep), the mixed
// texels of scratched metal or panel seams, where one Gaussian per texel would spread the flat field's
// highlight over the grooves' slopes. 90 straight grooves of random direction, length and depth, each a
// Gaussian-profile trough 1.2 texels wide; slopes up to ~1.
Image make_scratch_normal_map(int size, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> uniform01(0.0f, 1.0f);
    std::vector<float> height(size_t(size) * size_t(size), 0.0f);
    auto at = [&](int x, int y) -> float& {  // periodic
        return height[size_t((y % size + size) % size) * size_t(size) + size_t((x % size + size) % size)];
    };
    for (int g = 0; g < 90; ++g) {
        const float x0 = uniform01(rng) * float(size), y0 = uniform01(rng) * float(size), angle = kPi * uniform01(rng);
        const float length = (0.1f + 0.4f * uniform01(rng)) * float(size), depth = 0.5f + uniform01(rng);
        const float dx = std::cos(angle), dy = std::sin(angle);
        for (float t = 0; t < length; t += 0.5f) {
            const float cx = x0 + dx * t, cy = y0 + dy * t;
            for (int oy = -2; oy <= 2; ++oy)
                for (int ox = -2; ox <= 2; ++ox) {
                    const int ix = int(std::floor(cx)) + ox, iy = int(std::floor(cy)) + oy;
                    const float r2 = (float(ix) + 0.5f - cx) * (float(ix) + 0.5f - cx) + (float(iy) + 0.5f - cy) * (float(iy) + 0.5f - cy);
                    float& h = at(ix, iy);
                    h = std::min(h, -depth * std::exp(-r2 / 0.72f));
                }
        }
    }
    Image map(size, size, 3);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const Float3 n = unit({-0.5f * (at(x + 1, y) - at(x - 1, y)), -0.5f * (at(x, y + 1) - at(x, y - 1)), 1.0f});
            float* t = map.texel(x, y);
            for (int c = 0; c < 3; ++c) t[c] = 0.5f * (n[c] + 1.0f);
        }
    return map;
}

// Ridge normal map of the glitter plane: slope a cos(2 pi k.uv) (k / |k|) with the integer wave vector
// k = (35, 20) (29.7 degrees from the u axis, so it tiles), amplitude 0.3: strongly anisotropic and not
// axis-aligned, the case where the slope correlation rho of C21 Eq. 18 matters (C21 Fig. 7).
Image make_ridge_normal_map(int size) {
    const float kx = 35.0f, ky = 20.0f, k = std::sqrt(kx * kx + ky * ky), amplitude = 0.3f;
    Image map(size, size, 3);
    for (int y = 0; y < size; ++y) {
        for (int x = 0; x < size; ++x) {
            const float u = (float(x) + 0.5f) / float(size), v = (float(y) + 0.5f) / float(size);
            const float a = amplitude * std::cos(2 * kPi * (kx * u + ky * v));
            const Float3 n = unit({-a * kx / k, -a * ky / k, 1.0f});
            float* t = map.texel(x, y);
            for (int c = 0; c < 3; ++c) t[c] = 0.5f * (n[c] + 1.0f);
        }
    }
    return map;
}

// Square of side `size` in the y = 0 plane, normal +Y, u along +X and v along -Z (B = cross(N, T)).
SimObject make_plane(float size, int n) {
    return tessellate("plane", n, n, [=](float u, float v) {
        return SurfacePoint{{size * (u - 0.5f), 0.0f, size * (0.5f - v)}, {0, 1, 0}, {1, 0, 0}, {0, 0, 1, 0}};
    });
}

SimLight directional_light(Float3 towards_light) {
    SimLight light;
    light.direction = towards_light;
    return light;
}

int scaled(int n, float tessellation) { return std::max(8, int(std::lround(n * tessellation))); }

}  // namespace

std::span<const std::string_view> builtin_scene_names() {
    static constexpr std::string_view names[] = {"sphere", "cylinder", "torus", "bumpy-sphere"};
    return names;
}

std::span<const std::string_view> builtin_glint_scene_names() {
    static constexpr std::string_view names[] = {"glitter-sphere", "glitter-plane"};
    return names;
}

bool has_glints(const SimScene& scene) {
    return std::any_of(scene.objects.begin(), scene.objects.end(),
                       [](const SimObject& o) { return o.material.glints.enabled; });
}

Result<SimScene> make_builtin_scene(std::string_view name, float roughness, float tessellation) {
    if (!(roughness >= 0.0f && roughness <= 1.0f))
        return make_error("roughness must be in [0, 1], got " + std::to_string(roughness));
    if (!(tessellation > 0.0f && tessellation <= 16.0f))
        return make_error("tessellation must be in (0, 16], got " + std::to_string(tessellation));
    SimScene scene;
    scene.name = std::string(name);
    const Float3 key_light = unit({-0.45f, 0.65f, 0.6f});
    if (name == "sphere" || name == "bumpy-sphere" || name == "scratched-sphere") {
        scene.objects.push_back(make_sphere(1.0f, {0, 0, 0}, scaled(256, tessellation), scaled(128, tessellation)));
        scene.camera = {{0.0f, 0.4f, 3.6f}, {0, 0, 0}, {0, 1, 0}, 40.0f};
        scene.lights.push_back(directional_light(key_light));
        scene.object_radius = 1.0f;
        if (name == "bumpy-sphere") {
            scene.normal_maps.push_back(make_bump_normal_map(512, 0.35f, 7));
            scene.objects[0].material.normal_map = 0;
            scene.objects[0].material.uv_scale = 4.0f;
        } else if (name == "scratched-sphere") {
            scene.normal_maps.push_back(make_scratch_normal_map(512, 11));
            scene.objects[0].material.normal_map = 0;
            scene.objects[0].material.uv_scale = 2.0f;
        }
    } else if (name == "glitter-sphere") {
        scene.objects.push_back(make_sphere(1.0f, {0, 0, 0}, scaled(256, tessellation), scaled(128, tessellation)));
        scene.camera = {{0.0f, 0.4f, 3.6f}, {0, 0, 0}, {0, 1, 0}, 40.0f};
        scene.lights.push_back(directional_light(key_light));
        scene.object_radius = 1.0f;
    } else if (name == "glitter-plane") {
        // A 10 x 10 plane seen 30 degrees above it (60 degrees from its normal: anisotropic footprints),
        // lit by a point light 1.5 from the centre along the mirror direction, so the half vector sweeps the
        // slope distribution across the image.
        scene.objects.push_back(make_plane(10.0f, scaled(64, tessellation)));
        const float e = kPi / 6.0f;
        scene.camera = {{0.0f, 2.4f * std::sin(e), 2.4f * std::cos(e)}, {0, 0, 0}, {0, 1, 0}, 40.0f};
        SimLight light;
        light.type = SimLight::Type::Point;
        light.position = {0.0f, 1.5f * std::sin(e), -1.5f * std::cos(e)};
        light.radiance = 2.25f;  // irradiance 1 at the centre, 1.5 away
        scene.lights.push_back(light);
        scene.object_radius = 1.0f;
        scene.normal_maps.push_back(make_ridge_normal_map(256));
        scene.objects[0].material.normal_map = 0;
        scene.objects[0].material.uv_scale = 4.0f;  // 161 ridges per UV unit, about 2 pixels each at 64 x 64
    } else if (name == "cylinder") {
        // Seen almost along its axis from slightly above, lit from the far end: the visible highlight sits
        // where view and light graze the surface, where slope-space derivatives blow up (TK21 Sec. 3).
        scene.objects.push_back(make_cylinder(0.5f, 12.0f, scaled(256, tessellation), scaled(128, tessellation)));
        scene.camera = {{5.8f, 0.75f, 0.9f}, {0.0f, 0.0f, 0.0f}, {0, 1, 0}, 40.0f};
        scene.lights.push_back(directional_light(unit({-1.0f, 0.35f, -0.25f})));
        scene.object_radius = 0.5f;
    } else if (name == "torus") {
        scene.objects.push_back(make_torus(1.0f, 0.35f, scaled(256, tessellation), scaled(96, tessellation)));
        scene.camera = {{0.0f, 2.2f, 3.0f}, {0, 0, 0}, {0, 1, 0}, 40.0f};
        scene.lights.push_back(directional_light(key_light));
        scene.object_radius = 1.35f;
    } else {
        std::string names;
        for (auto n : builtin_scene_names()) names += (names.empty() ? "" : ", ") + std::string(n);
        names += ", scratched-sphere";
        for (auto n : builtin_glint_scene_names()) names += ", " + std::string(n);
        return make_error("unknown built-in scene '" + std::string(name) + "' (built-in scenes: " + names + ")");
    }
    for (auto& object : scene.objects) object.material.roughness = roughness;
    if (name.starts_with("glitter-")) {
        scene.glints_only = true;
        for (auto& object : scene.objects) object.material.glints.enabled = true;
    }
    return scene;
}

std::vector<SimTextureSet> texture_sets(const SimScene& scene, std::vector<int>* object_sets) {
    std::vector<SimTextureSet> sets;
    if (object_sets) object_sets->clear();
    for (const SimObject& o : scene.objects) {
        int index = -1;
        if (o.material.normal_map >= 0) {
            const SimTextureSet set{o.material.normal_map, o.material.roughness_map,
                                    o.material.roughness_map >= 0 ? 0.0f : o.material.roughness};
            const auto it = std::find(sets.begin(), sets.end(), set);
            index = int(it - sets.begin());
            if (it == sets.end()) sets.push_back(set);
        }
        if (object_sets) object_sets->push_back(index);
    }
    return sets;
}

std::vector<float> mean_edge_lengths(const TriMesh& mesh) {
    std::vector<double> sum(mesh.vertex_count(), 0.0);
    std::vector<int> count(mesh.vertex_count(), 0);
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        for (size_t e = 0; e < 3; ++e) {
            const size_t i = mesh.indices[t + e], j = mesh.indices[t + (e + 1) % 3];
            double d2 = 0.0;
            for (size_t c = 0; c < 3; ++c) {
                const double d = double(mesh.positions[3 * i + c]) - double(mesh.positions[3 * j + c]);
                d2 += d * d;
            }
            const double length = std::sqrt(d2);
            sum[i] += length;
            sum[j] += length;
            ++count[i];
            ++count[j];
        }
    }
    std::vector<float> out(mesh.vertex_count(), 0.0f);
    for (size_t v = 0; v < out.size(); ++v)
        if (count[v] > 0) out[v] = float(sum[v] / count[v]);
    return out;
}

bool has_exact_curvature(const SimScene& scene) {
    return std::all_of(scene.objects.begin(), scene.objects.end(), [](const SimObject& o) {
        return o.exact_curvature.values.size() == 4 * o.mesh.vertex_count();
    });
}

SimCamera camera_at_frame(const SimScene& scene, int frame, int height) {
    SimCamera camera = scene.camera;
    const Float3 offset{camera.position[0] - camera.target[0], camera.position[1] - camera.target[1],
                        camera.position[2] - camera.target[2]};
    const float distance = std::sqrt(offset[0] * offset[0] + offset[1] * offset[1] + offset[2] * offset[2]);
    // One pixel subtends 2 tan(fov/2) / height radians; a point at the object's radius moves by
    // radius * angle, which on screen at `distance` is (radius / distance) * angle / pixel_angle pixels.
    const float pixel_angle = 2.0f * std::tan(0.5f * camera.fov_y_degrees * kPi / 180.0f) / float(height);
    const float angle = float(frame) * scene.motion_pixels * pixel_angle * distance / scene.object_radius;
    // Rotate the offset about the up axis (Rodrigues).
    const Float3 k = unit(camera.up);
    const float c = std::cos(angle), s = std::sin(angle);
    const float kd = k[0] * offset[0] + k[1] * offset[1] + k[2] * offset[2];
    const Float3 kx{k[1] * offset[2] - k[2] * offset[1], k[2] * offset[0] - k[0] * offset[2],
                    k[0] * offset[1] - k[1] * offset[0]};
    for (int i = 0; i < 3; ++i)
        camera.position[i] = camera.target[i] + offset[i] * c + kx[i] * s + k[i] * kd * (1 - c);
    return camera;
}

}  // namespace specbake::verify
