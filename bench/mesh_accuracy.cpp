// Accuracy of the curvature estimators against closed forms (issue 4 item 3): for each estimator, shape and
// tessellation, the RMS relative error of k1 and k2 (relative to |k1| of the closed form), the RMS angular
// error of the k1 direction where the surface is anisotropic, and the time per million faces (wall clock,
// including welding; small meshes are dominated by fixed costs). Radii are not powers of two, so float
// rounding of positions against normals shows.
// Usage: mesh_accuracy [--threads N] [--estimator NAME] [--jet-degree D] [--jet-points N]
//   NAME: shape-operator (the default), second-order, jet-fitting or normal-cone
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <utility>

#include "mesh/curvature.h"
#include "mesh/generate_normals.h"
#include "mesh/generate_tangents.h"
#include "mesh/procedural_shapes.h"
#include "tests/mesh/analytic_curvature.h"

using namespace specbake;

namespace {

struct Shape {
    std::string name;
    TriMesh mesh;
    std::function<testing::Principal(const float*)> truth;
};

std::vector<Shape> shapes() {
    std::vector<Shape> s;
    for (int n : {16, 32, 64, 128}) {
        s.push_back({"uv-sphere " + std::to_string(n) + "x" + std::to_string(n / 2), make_uv_sphere(1.7f, n, n / 2),
                     [](const float* x) { return testing::sphere_curvature(1.7, x); }});
    }
    for (int sub : {2, 3, 4, 5}) {
        s.push_back({"icosphere sub " + std::to_string(sub), make_icosphere(1.7f, sub),
                     [](const float* x) { return testing::sphere_curvature(1.7, x); }});
    }
    for (int n : {16, 32, 64, 128}) {
        s.push_back({"cylinder " + std::to_string(n) + "x" + std::to_string(n / 2), make_cylinder(1.7f, 3.0f, n, n / 2),
                     [](const float* x) { return testing::cylinder_curvature(1.7, 3.0, x); }});
    }
    for (int n : {16, 32, 64, 128}) {
        s.push_back({"torus " + std::to_string(n) + "x" + std::to_string(n), make_torus(3.0f, 1.0f, n, n),
                     [](const float* x) { return testing::torus_curvature(3.0, 1.0, x); }});
    }
    for (int n : {16, 32, 64, 128}) {
        s.push_back({"torus jitter .3 " + std::to_string(n) + "x" + std::to_string(n), make_torus(3.0f, 1.0f, n, n, 0.3f, 17),
                     [](const float* x) { return testing::torus_curvature(3.0, 1.0, x); }});
    }
    for (int n : {16, 32, 64, 128}) {
        s.push_back({"ellipsoid 3:2:1.5 " + std::to_string(n) + "x" + std::to_string(n / 2),
                     make_ellipsoid(3.0f, 2.0f, 1.5f, n, n / 2),
                     [](const float* x) { return testing::ellipsoid_curvature(3.0, 2.0, 1.5, x); }});
    }
    for (int n : {32, 64, 128}) {
        s.push_back({"ellipsoid jitter .3 " + std::to_string(n) + "x" + std::to_string(n / 2),
                     make_ellipsoid(3.0f, 2.0f, 1.5f, n, n / 2, 0.3f, 23),
                     [](const float* x) { return testing::ellipsoid_curvature(3.0, 2.0, 1.5, x); }});
    }
    // Normals generated from the triangles (angle-weighted), as for a file without normals: the estimate then
    // measures the curvature of the generated normal field.
    const std::pair<NormalWeighting, const char*> weightings[] = {{NormalWeighting::Angle, "angle"},
                                                                  {NormalWeighting::Max, "Max"}};
    for (const auto& [weighting, label] : weightings) {
        for (int n : {32, 64, 128}) {
            const std::string suffix = std::string(" gen. normals (") + label + ")";
            TriMesh t = make_torus(3.0f, 1.0f, n, n, 0.3f, 17);
            generate_normals(t, weighting);
            generate_tangents(t);
            s.push_back({"torus jitter .3 " + std::to_string(n) + "x" + std::to_string(n) + suffix, t,
                         [](const float* x) { return testing::torus_curvature(3.0, 1.0, x); }});
            TriMesh e = make_ellipsoid(3.0f, 2.0f, 1.5f, n, n / 2);
            generate_normals(e, weighting);
            generate_tangents(e);
            s.push_back({"ellipsoid " + std::to_string(n) + "x" + std::to_string(n / 2) + suffix, e,
                         [](const float* x) { return testing::ellipsoid_curvature(3.0, 2.0, 1.5, x); }});
            TriMesh j = make_ellipsoid(3.0f, 2.0f, 1.5f, n, n / 2, 0.3f, 23);
            generate_normals(j, weighting);
            generate_tangents(j);
            s.push_back({"ellipsoid jitter .3 " + std::to_string(n) + "x" + std::to_string(n / 2) + suffix, j,
                         [](const float* x) { return testing::ellipsoid_curvature(3.0, 2.0, 1.5, x); }});
        }
    }
    for (float scale : {0.001f, 1000.0f}) {
        TriMesh m = make_torus(3.0f, 1.0f, 64, 64, 0.3f, 17);
        scale_mesh(m, scale);
        const double R = 3.0 * scale, r = 1.0 * scale;
        char name[64];
        std::snprintf(name, sizeof name, "torus jitter .3 64x64 x%g", double(scale));
        s.push_back({name, m, [=](const float* x) { return testing::torus_curvature(R, r, x); }});
    }
    return s;
}

}  // namespace

int main(int argc, char** argv) {
    CurvatureOptions options;
    std::string only;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (std::strcmp(argv[i], "--threads") == 0) options.max_threads = std::atoi(argv[i + 1]);
        else if (std::strcmp(argv[i], "--estimator") == 0) only = argv[i + 1];
        else if (std::strcmp(argv[i], "--jet-degree") == 0) options.jet_degree = std::atoi(argv[i + 1]);
        else if (std::strcmp(argv[i], "--jet-points") == 0) options.jet_min_points = std::atoi(argv[i + 1]);
        else {
            std::fprintf(stderr, "mesh_accuracy: unknown option %s\n", argv[i]);
            return 2;
        }
    }

    if (!only.empty() && !parse_curvature_estimator(only)) {
        std::fprintf(stderr, "mesh_accuracy: unknown estimator %s\n", only.c_str());
        return 2;
    }
    std::printf("| estimator | shape | faces | RMS k1 | RMS k2 | max k1 | RMS angle d (deg) | s / Mfaces |\n");
    std::printf("|---|---|---:|---:|---:|---:|---:|---:|\n");
    const std::vector<Shape> all = shapes();
    for (CurvatureEstimator e : {CurvatureEstimator::ShapeOperator, CurvatureEstimator::SecondOrder,
                                 CurvatureEstimator::JetFitting, CurvatureEstimator::NormalCone}) {
        if (!only.empty() && only != to_string(e)) continue;
        for (const Shape& s : all) {
            const auto t0 = std::chrono::steady_clock::now();
            Result<VertexCurvature> c = estimate_curvature(s.mesh, e, options);
            const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            if (!c) {
                std::printf("| %s | %s | error: %s |\n", std::string(to_string(e)).c_str(), s.name.c_str(),
                            c.error().message.c_str());
                continue;
            }
            const testing::CurvatureErrors err = testing::compare(s.mesh, *c, s.truth);
            char angle[32] = "-";
            if (err.scored_directions) std::snprintf(angle, sizeof angle, "%.3f", err.rms_angle_deg);
            std::printf("| %s | %s | %zu | %.2e | %.2e | %.2e | %s | %.3f |\n", std::string(to_string(e)).c_str(),
                        s.name.c_str(), s.mesh.triangle_count(), err.rms_k1, err.rms_k2, err.max_k1, angle,
                        seconds * 1e6 / double(s.mesh.triangle_count()));
        }
    }
    return 0;
}
