// Curvature estimators against closed forms (SPEC Sec. 4): spheres, cylinders, tori and ellipsoids at
// several tessellations and scales, seams, hard edges, sign, direction, degenerate triangles, determinism.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "mesh/curvature.h"
#include "mesh/curvature_summary.h"
#include "mesh/prepare_mesh.h"
#include "mesh/procedural_shapes.h"
#include "tests/mesh/analytic_curvature.h"

namespace specbake {
namespace {

using testing::CurvatureErrors;
using testing::Principal;

VertexCurvature estimate(const TriMesh& m, CurvatureEstimator e = CurvatureEstimator::ShapeOperator,
                         int threads = 0) {
    CurvatureOptions o;
    o.max_threads = threads;
    Result<VertexCurvature> r = estimate_curvature(m, e, o);
    EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
    return r.ok() ? r.value() : VertexCurvature{std::vector<float>(4 * m.vertex_count(), 0.0f)};
}

// The shape-operator fits: the default (per face, SPEC Sec. 4) and the second-order fit per vertex. Both must
// meet the closed-form bounds below.
constexpr CurvatureEstimator kFits[] = {CurvatureEstimator::ShapeOperator, CurvatureEstimator::SecondOrder,
                                        CurvatureEstimator::Patch};
constexpr CurvatureEstimator kAll[] = {CurvatureEstimator::ShapeOperator, CurvatureEstimator::SecondOrder,
                                       CurvatureEstimator::JetFitting, CurvatureEstimator::NormalCone,
                                       CurvatureEstimator::Patch};

TEST(Curvature, SphereIsOneOverRadius) {
    for (CurvatureEstimator f : kFits) {
        SCOPED_TRACE(std::string(to_string(f)));
        for (float radius : {0.01f, 1.0f, 250.0f}) {
            const TriMesh m = make_uv_sphere(radius, 64, 32);
            const CurvatureErrors e = testing::compare(m, estimate(m, f), [&](const float* x) {
                return testing::sphere_curvature(radius, x);
            });
            EXPECT_LT(e.max_k1, 1e-3) << to_string(f) << " R = " << radius;
            EXPECT_LT(e.max_k2, 1e-3) << to_string(f) << " R = " << radius;
            EXPECT_EQ(e.scored, m.vertex_count()) << to_string(f);
        }
        const TriMesh ico = make_icosphere(2.0f, 4);
        const CurvatureErrors e = testing::compare(ico, estimate(ico, f), [](const float* x) {
            return testing::sphere_curvature(2.0, x);
        });
        EXPECT_LT(e.max_k1, 1e-3) << to_string(f);
    }
    // Irregular UV sphere (poles with one vertex per segment, jittered interior): the second-order fit
    // reproduces spherical normals n = p / R whatever the triangulation.
    const TriMesh jittered = make_uv_sphere(1.7f, 64, 32, 0.3f, 5);
    const CurvatureErrors j =
        testing::compare(jittered, estimate(jittered, CurvatureEstimator::SecondOrder), [](const float* x) {
            return testing::sphere_curvature(1.7, x);
        });
    EXPECT_LT(j.max_k1, 1e-3);
    EXPECT_LT(j.max_k2, 1e-3);
}

TEST(Curvature, FitsWithinOnePercentAt64Segments) {
    const float R = 3.0f, r = 1.0f, H = 4.0f;
    struct Case {
        const char* name;
        TriMesh mesh;
        std::function<Principal(const float*)> truth;
    };
    std::vector<Case> cases;
    cases.push_back({"cylinder", make_cylinder(R, H, 64, 24), [=](const float* x) {
                         return testing::cylinder_curvature(R, H, x);
                     }});
    cases.push_back({"torus", make_torus(R, r, 64, 64), [=](const float* x) {
                         return testing::torus_curvature(R, r, x);
                     }});
    cases.push_back({"ellipsoid", make_ellipsoid(3.0f, 2.0f, 1.5f, 64, 32), [](const float* x) {
                         return testing::ellipsoid_curvature(3.0, 2.0, 1.5, x);
                     }});
    cases.push_back({"jittered torus", make_torus(R, r, 64, 64, 0.3f, 7), [=](const float* x) {
                         return testing::torus_curvature(R, r, x);
                     }});
    for (CurvatureEstimator f : kFits)
        for (const Case& c : cases) {
            const CurvatureErrors e = testing::compare(c.mesh, estimate(c.mesh, f), c.truth);
            EXPECT_LT(e.rms_k1, 0.01) << to_string(f) << " " << c.name;
            EXPECT_LT(e.rms_k2, 0.01) << to_string(f) << " " << c.name;
            EXPECT_GT(e.scored, c.mesh.vertex_count() / 2) << to_string(f) << " " << c.name;
            if (e.scored_directions) EXPECT_LT(e.rms_angle_deg, 2.0) << to_string(f) << " " << c.name;
        }
}

TEST(Curvature, DirectionFollowsThePrincipalAxes) {
    for (CurvatureEstimator f : kFits) {
        SCOPED_TRACE(std::string(to_string(f)));
        // Cylinder: k1 = 1/R around the axis, i.e. along the tangent T (dP/du) of this parametrisation.
        const TriMesh cyl = make_cylinder(1.0f, 2.0f, 64, 16);
        const VertexCurvature c = estimate(cyl, f);
        for (size_t v = 0; v < cyl.vertex_count(); ++v) {
            EXPECT_NEAR(std::abs(c.values[4 * v + 2]), 1.0, 1e-3) << v;
            EXPECT_NEAR(c.values[4 * v + 3], 0.0, 0.05) << v;
        }
        // Torus: k1 = 1/r along the meridian, which is the bitangent direction here.
        const TriMesh torus = make_torus(3.0f, 1.0f, 64, 64);
        const VertexCurvature t = estimate(torus, f);
        const CurvatureErrors e = testing::compare(torus, t, [](const float* x) {
            return testing::torus_curvature(3.0, 1.0, x);
        });
        EXPECT_GT(e.scored_directions, torus.vertex_count() / 2);
        EXPECT_LT(e.rms_angle_deg, 1.0);
        for (size_t v = 0; v < torus.vertex_count(); ++v) EXPECT_NEAR(std::abs(t.values[4 * v + 3]), 1.0, 1e-3) << v;
    }
}

TEST(Curvature, ErrorsShrinkWithRefinement) {
    for (CurvatureEstimator f : kFits) {
        SCOPED_TRACE(std::string(to_string(f)));
        const float R = 3.0f, r = 1.0f;
        double previous_k1 = 1e9, previous_k2 = 1e9;
        for (int n : {16, 32, 64, 128}) {
            const TriMesh m = make_torus(R, r, n, n, 0.3f, 11);
            const CurvatureErrors e = testing::compare(m, estimate(m, f), [=](const float* x) {
                return testing::torus_curvature(R, r, x);
            });
            EXPECT_LT(e.rms_k1, previous_k1) << n;
            EXPECT_LT(e.rms_k2, previous_k2) << n;
            previous_k1 = e.rms_k1;
            previous_k2 = e.rms_k2;
        }
        EXPECT_LT(previous_k1, 0.005);
    }
}

// The second-order fit is second order on irregular triangulations (see curvature_second_order.cpp):
// halving the edge length divides the error by about four. The default, face-averaged operator is first
// order here (jittered ellipsoid 3.0% / 1.5% / 0.72% at 32 / 64 / 128 segments), pinned below.
TEST(Curvature, SecondOrderOnIrregularMeshes) {
    const auto estimate = [](const TriMesh& m) { return specbake::estimate(m, CurvatureEstimator::SecondOrder); };
    auto ellipsoid = [](const float* x) { return testing::ellipsoid_curvature(3.0, 2.0, 1.5, x); };
    auto torus = [](const float* x) { return testing::torus_curvature(3.0, 1.0, x); };
    std::vector<CurvatureErrors> e, t;
    for (int n : {32, 64, 128}) {
        const TriMesh m = make_ellipsoid(3.0f, 2.0f, 1.5f, n, n / 2, 0.3f, 23);
        e.push_back(testing::compare(m, estimate(m), ellipsoid));
        const TriMesh tm = make_torus(3.0f, 1.0f, n, n, 0.3f, 17);
        t.push_back(testing::compare(tm, estimate(tm), torus));
    }
    // Measured 0.42% (k1) and 0.29% (k2) on the jittered ellipsoid at 64 segments: the bound leaves room for
    // rounding differences between compilers and still fails a first-order estimate (1.5%).
    EXPECT_LT(e[1].rms_k1, 0.006);
    EXPECT_LT(e[1].rms_k2, 0.006);
    // Ratios measured 3.8-4.0 (ellipsoid) and 3.2-3.9 (torus); first order would give 2.
    for (size_t i = 1; i < e.size(); ++i) {
        EXPECT_GT(e[i - 1].rms_k1 / e[i].rms_k1, 3.0) << i;
        EXPECT_GT(e[i - 1].rms_k2 / e[i].rms_k2, 3.0) << i;
        EXPECT_GT(t[i - 1].rms_k1 / t[i].rms_k1, 3.0) << i;
    }
}

// The default estimator is the per-face fit of SPEC Sec. 4: on irregular meshes its error halves with the
// edge length (first order), which tells it apart from the second-order fit above. Measured on the
// jittered ellipsoid: RMS k1 3.04% / 1.48% / 0.72% at 32 / 64 / 128 segments (ratios 2.05, 2.05).
TEST(Curvature, DefaultIsFirstOrderOnIrregularMeshes) {
    auto ellipsoid = [](const float* x) { return testing::ellipsoid_curvature(3.0, 2.0, 1.5, x); };
    std::vector<CurvatureErrors> e;
    for (int n : {32, 64, 128}) {
        const TriMesh m = make_ellipsoid(3.0f, 2.0f, 1.5f, n, n / 2, 0.3f, 23);
        e.push_back(testing::compare(m, estimate(m), ellipsoid));
    }
    for (size_t i = 1; i < e.size(); ++i) {
        EXPECT_GT(e[i - 1].rms_k1 / e[i].rms_k1, 1.6) << i;
        EXPECT_LT(e[i - 1].rms_k1 / e[i].rms_k1, 2.6) << i;
    }
}

// Second-order fit: vertices whose spokes cannot determine the curvature derivative (valence 3, a lone
// triangle) fall back to the linear fit, which is exact for spherical normals n = p / R: 1/R, finite, at every vertex.
TEST(Curvature, LowValenceVerticesStayExactOnSphericalNormals) {
    const auto estimate = [](const TriMesh& m) { return specbake::estimate(m, CurvatureEstimator::SecondOrder); };
    const float R = 1.3f;
    const float a = R / std::sqrt(3.0f);
    TriMesh tetra;
    tetra.positions = {a, a, a, a, -a, -a, -a, a, -a, -a, -a, a};
    tetra.indices = {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2};
    TriMesh single;
    single.positions = {R, 0, 0, 0, R, 0, 0, 0, R};
    single.indices = {0, 1, 2};
    for (TriMesh* m : {&tetra, &single}) {
        for (size_t k = 0; k < m->positions.size(); ++k) m->normals.push_back(m->positions[k] / R);
        ASSERT_TRUE(prepare_mesh_for_curvature(*m).ok());
        const VertexCurvature c = estimate(*m);
        for (size_t v = 0; v < m->vertex_count(); ++v) {
            EXPECT_NEAR(c.values[4 * v], 1.0 / R, 1e-5) << v;
            EXPECT_NEAR(c.values[4 * v + 1], 1.0 / R, 1e-5) << v;
        }
    }
}

TEST(Curvature, ScalingByS_DividesCurvatureByS) {
    for (CurvatureEstimator f : kFits) {
        SCOPED_TRACE(std::string(to_string(f)));
        const TriMesh base = make_torus(3.0f, 1.0f, 48, 32, 0.25f, 3);
        const VertexCurvature c0 = estimate(base, f);
        for (float s : {0.001f, 3.7f, 1000.0f}) {
            TriMesh scaled = base;
            scale_mesh(scaled, s);
            const VertexCurvature c1 = estimate(scaled, f);
            for (size_t v = 0; v < base.vertex_count(); ++v) {
                const double scale = std::max(std::abs(c0.values[4 * v]), std::abs(c0.values[4 * v + 1]));
                EXPECT_NEAR(double(c1.values[4 * v]) * s, c0.values[4 * v], 1e-5 * scale) << "s " << s << " v " << v;
                EXPECT_NEAR(double(c1.values[4 * v + 1]) * s, c0.values[4 * v + 1], 1e-5 * scale)
                    << "s " << s << " v " << v;
            }
        }
    }
}

TEST(Curvature, ConcaveSideIsNegative) {
    for (CurvatureEstimator f : kFits) {
        SCOPED_TRACE(std::string(to_string(f)));
        // The inside of a sphere: normals pointing at the centre, winding flipped to match.
        TriMesh m = make_uv_sphere(2.0f, 48, 24);
        for (float& x : m.normals) x = -x;
        for (size_t t = 0; t < m.triangle_count(); ++t) std::swap(m.indices[3 * t + 1], m.indices[3 * t + 2]);
        const VertexCurvature c = estimate(m, f);
        for (size_t v = 0; v < m.vertex_count(); ++v) {
            EXPECT_NEAR(c.values[4 * v], -0.5, 1e-3);
            EXPECT_NEAR(c.values[4 * v + 1], -0.5, 1e-3);
        }
        // The torus' inner equator is a saddle: the parallel curvature is -1/(R - r).
        const TriMesh torus = make_torus(3.0f, 1.0f, 64, 64);
        const VertexCurvature t = estimate(torus, f);
        bool saw_inner = false;
        for (size_t v = 0; v < torus.vertex_count(); ++v) {
            const float* x = &torus.positions[3 * v];
            if (std::hypot(x[0], x[1]) < 2.0001 && std::abs(x[2]) < 1e-4) {
                EXPECT_NEAR(t.values[4 * v + 1], -0.5, 0.005);
                EXPECT_NEAR(t.values[4 * v], 1.0, 0.005);
                saw_inner = true;
            }
        }
        EXPECT_TRUE(saw_inner);
    }
}

// k1 is the curvature of largest magnitude, not the largest value: inside a cylinder (normals towards the
// axis) k1 = -1/R around the axis and k2 = 0 along it.
TEST(Curvature, LargestMagnitudeComesFirstOnConcaveSides) {
    for (CurvatureEstimator f : kFits) {
        SCOPED_TRACE(std::string(to_string(f)));
        const float R = 1.5f, H = 2.0f;
        TriMesh m = make_cylinder(R, H, 64, 16);
        for (float& x : m.normals) x = -x;
        for (size_t t = 0; t < m.triangle_count(); ++t) std::swap(m.indices[3 * t + 1], m.indices[3 * t + 2]);
        const VertexCurvature c = estimate(m, f);
        size_t scored = 0;
        for (size_t v = 0; v < m.vertex_count(); ++v) {
            if (!testing::cylinder_curvature(R, H, &m.positions[3 * v]).use) continue;
            EXPECT_NEAR(c.values[4 * v], -1.0 / R, 1e-3) << v;
            EXPECT_NEAR(c.values[4 * v + 1], 0.0, 1e-3) << v;
            EXPECT_NEAR(std::abs(c.values[4 * v + 2]), 1.0, 1e-3) << v;  // around the axis: along T
            ++scored;
        }
        EXPECT_GT(scored, m.vertex_count() / 2);
    }
}

TEST(Curvature, SeamVerticesShareCurvature) {
    for (CurvatureEstimator f : kFits) {
        SCOPED_TRACE(std::string(to_string(f)));
        // Welding the seam by hand must not change anything: split vertices see the same one-ring.
        const TriMesh seamed = make_torus(3.0f, 1.0f, 40, 24, 0.2f, 5);
        TriMesh welded = seamed;
        std::vector<uint32_t> first(seamed.vertex_count());
        for (size_t v = 0; v < seamed.vertex_count(); ++v) {
            first[v] = uint32_t(v);
            for (size_t w = 0; w < v; ++w)
                if (std::memcmp(&seamed.positions[3 * v], &seamed.positions[3 * w], 12) == 0) {
                    first[v] = uint32_t(w);
                    break;
                }
        }
        size_t seam_vertices = 0;
        for (size_t v = 0; v < seamed.vertex_count(); ++v) seam_vertices += first[v] != v;
        EXPECT_GT(seam_vertices, 60u);
        for (uint32_t& i : welded.indices) i = first[i];
        const VertexCurvature a = estimate(seamed, f), b = estimate(welded, f);
        for (size_t v = 0; v < seamed.vertex_count(); ++v) {
            const float* ca = &a.values[4 * v];
            const float* cb = &b.values[4 * first[v]];
            EXPECT_NEAR(ca[0], cb[0], 1e-5 * std::abs(cb[0]) + 1e-6) << v;
            EXPECT_NEAR(ca[1], cb[1], 1e-5 * std::abs(cb[0]) + 1e-6) << v;
            // Same tangent frames here, so the same direction (up to sign).
            EXPECT_NEAR(std::abs(ca[2] * cb[2] + ca[3] * cb[3]), 1.0, 1e-4) << v;
        }
    }
}

TEST(Curvature, HardEdgesKeepFlatSidesFlat) {
    const TriMesh cube = make_flat_cube(1.5f);
    for (CurvatureEstimator e :
         {CurvatureEstimator::ShapeOperator, CurvatureEstimator::SecondOrder, CurvatureEstimator::NormalCone}) {
        const VertexCurvature c = estimate(cube, e);
        for (size_t v = 0; v < cube.vertex_count(); ++v) {
            EXPECT_NEAR(c.values[4 * v], 0.0, 1e-6) << to_string(e);
            EXPECT_NEAR(c.values[4 * v + 1], 0.0, 1e-6) << to_string(e);
        }
    }
    // A faceted sphere: every triangle its own flat normal -> zero curvature, whatever the geometry.
    const TriMesh smooth = make_icosphere(1.0f, 2);
    TriMesh facets;
    for (size_t t = 0; t < smooth.triangle_count(); ++t) {
        const float* p[3];
        for (int c = 0; c < 3; ++c) p[c] = &smooth.positions[3 * smooth.indices[3 * t + c]];
        const double e1[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
        const double e2[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        const double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int c = 0; c < 3; ++c) {
            facets.indices.push_back(uint32_t(facets.vertex_count()));
            facets.positions.insert(facets.positions.end(), p[c], p[c] + 3);
            for (int k = 0; k < 3; ++k) facets.normals.push_back(float(n[k] / l));
        }
    }
    ASSERT_TRUE(prepare_mesh_for_curvature(facets).ok());
    for (CurvatureEstimator f : kFits) {
        const VertexCurvature c = estimate(facets, f);
        for (float x : c.values) EXPECT_TRUE(std::isfinite(x)) << to_string(f);
        for (size_t v = 0; v < facets.vertex_count(); ++v) EXPECT_NEAR(c.values[4 * v], 0.0, 1e-5) << to_string(f);
    }
}

TEST(Curvature, DegenerateTrianglesAreSkipped) {
    TriMesh m = make_uv_sphere(1.0f, 32, 16);
    const VertexCurvature before[] = {estimate(m, kFits[0]), estimate(m, kFits[1])};
    const size_t n = m.vertex_count();
    // Repeated index, three coincident positions, and a collinear sliver through existing vertices.
    m.indices.insert(m.indices.end(), {0, 0, 1, 5, 5, 5, 40, 41, 40});
    const float mid[3] = {0.5f * (m.positions[3 * 40] + m.positions[3 * 41]),
                          0.5f * (m.positions[3 * 40 + 1] + m.positions[3 * 41 + 1]),
                          0.5f * (m.positions[3 * 40 + 2] + m.positions[3 * 41 + 2])};
    m.positions.insert(m.positions.end(), mid, mid + 3);
    m.normals.insert(m.normals.end(), {0.0f, 0.0f, 1.0f});
    m.tangents.insert(m.tangents.end(), {1.0f, 0.0f, 0.0f, 1.0f});
    m.uv0.insert(m.uv0.end(), {0.0f, 0.0f});
    m.indices.insert(m.indices.end(), {40, uint32_t(n), 41});
    Result<MeshReport> report = prepare_mesh_for_curvature(m);
    ASSERT_TRUE(report.ok());
    EXPECT_GE(report->degenerate_triangles, 3u);
    for (CurvatureEstimator e : kAll) {
        const VertexCurvature after = estimate(m, e);
        for (float x : after.values) ASSERT_TRUE(std::isfinite(x)) << to_string(e);
        for (int f = 0; f < 2; ++f)
            if (e == kFits[f])
                for (size_t v = 0; v < n; ++v) EXPECT_EQ(after.values[4 * v], before[f].values[4 * v]) << v;
    }
}

// Default estimator, vertices whose own frame is unusable: a tangent along the normal takes a fixed
// perpendicular, a zero normal gets no curvature (its triangles carry no normal difference and are skipped).
// The rest of the sphere keeps 1/R, and every direction is a unit vector.
TEST(Curvature, UnusableVertexFramesKeepTheOutputDefined) {
    const float R = 2.0f;
    TriMesh m = make_uv_sphere(R, 32, 16);
    auto nearest = [&](double x, double y, double z) {
        size_t best = 0;
        double best_dot = -2.0;
        for (size_t v = 0; v < m.vertex_count(); ++v) {
            const float* p = &m.positions[3 * v];
            const double d = (p[0] * x + p[1] * y + p[2] * z) / (R * std::sqrt(x * x + y * y + z * z));
            if (d > best_dot) best_dot = d, best = v;
        }
        return best;
    };
    const size_t along = nearest(1.0, 1.0, 0.3), zero = nearest(-1.0, 0.5, -0.2);
    for (int k = 0; k < 3; ++k) m.tangents[4 * along + k] = m.normals[3 * along + k];
    for (int k = 0; k < 3; ++k) m.normals[3 * zero + k] = 0.0f;
    const VertexCurvature c = estimate(m);
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        const float* x = &c.values[4 * v];
        EXPECT_NEAR(std::hypot(x[2], x[3]), 1.0, 1e-6) << v;
        if (v == zero) {
            EXPECT_EQ(x[0], 0.0f);
            EXPECT_EQ(x[1], 0.0f);
        } else {
            EXPECT_NEAR(x[0], 1.0 / R, 1e-3) << v;
            EXPECT_NEAR(x[1], 1.0 / R, 1e-3) << v;
        }
    }
}

// A gently curved patch (shading normals n = normalize(c x, c y, 1) on a flat grid: curvature c in every
// direction, the closed form) crossed by a lip one narrow column wide where n.x climbs by s per unit length
// (s = 60 c), as a rim or a bevel beside a dome. The vertices on the lip's two sides touch three gentle
// faces of width 1 and three steep faces of width 0.1: their gentle faces interpolate the vertex values, so
// the value must be the gentle patch's c. The one-ring average (shape-operator) carries the lip into them;
// patch must not.
TEST(Curvature, PatchKeepsASteepLipOutOfTheGentleVertices) {
    const double c = 0.05, s = 60.0 * c, lip_width = 0.1;
    const int n = 12, lip = 6;  // grid columns 0..n, the lip between columns lip and lip + 1
    std::vector<double> xs;
    for (int i = 0; i <= n; ++i) xs.push_back(i <= lip ? i : lip + lip_width + (i - lip - 1));
    TriMesh m;
    m.name = "lip";
    for (int j = 0; j <= n; ++j) {
        for (int i = 0; i <= n; ++i) {
            const double x = xs[size_t(i)] - 6.0, y = j - 6.0;
            const double climb = s * std::clamp(xs[size_t(i)] - lip, 0.0, lip_width);
            const double nx = c * x + climb, ny = c * y, len = std::sqrt(nx * nx + ny * ny + 1.0);
            m.positions.insert(m.positions.end(), {float(x), float(y), 0.0f});
            m.normals.insert(m.normals.end(), {float(nx / len), float(ny / len), float(1.0 / len)});
            m.tangents.insert(m.tangents.end(), {1.0f, 0.0f, 0.0f, 1.0f});
        }
    }
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            const uint32_t a = uint32_t(j * (n + 1) + i), b = a + 1, d = a + uint32_t(n + 1), e = d + 1;
            m.indices.insert(m.indices.end(), {a, b, e, a, e, d});
        }
    }
    const VertexCurvature so = estimate(m, CurvatureEstimator::ShapeOperator);
    const VertexCurvature patch = estimate(m, CurvatureEstimator::Patch);
    int checked = 0;
    for (int j = 2; j <= n - 2; ++j) {
        for (int i : {lip, lip + 1}) {
            const size_t v = size_t(j * (n + 1) + i);
            // The gentle patch's |k1| at this vertex: the field's curvature there, c up to the tilt of n.
            EXPECT_NEAR(std::abs(patch.values[4 * v]), c, 0.15 * c) << "vertex " << i << "," << j;
            EXPECT_GT(std::abs(so.values[4 * v]), 3.0 * c) << "vertex " << i << "," << j;
            ++checked;
        }
    }
    EXPECT_EQ(checked, 18);
    // Away from the lip both are the gentle patch's curvature.
    const size_t far = size_t(6 * (n + 1) + 2);
    EXPECT_NEAR(std::abs(patch.values[4 * far]), c, 0.15 * c);
    EXPECT_NEAR(std::abs(so.values[4 * far]), c, 0.15 * c);
}

TEST(Curvature, SameOutputForAnyThreadCount) {
    const TriMesh m = make_torus(3.0f, 1.0f, 200, 100, 0.3f, 9);
    for (CurvatureEstimator e : kAll) {
        const VertexCurvature one = estimate(m, e, 1), two = estimate(m, e, 2), many = estimate(m, e, 7);
        EXPECT_EQ(one.values, two.values) << to_string(e);
        EXPECT_EQ(one.values, many.values) << to_string(e);
    }
}

TEST(Curvature, OtherEstimatorsApproximateTheClosedForms) {
    const TriMesh torus = make_torus(3.0f, 1.0f, 64, 64);
    auto truth = [](const float* x) { return testing::torus_curvature(3.0, 1.0, x); };
    const CurvatureErrors jet = testing::compare(torus, estimate(torus, CurvatureEstimator::JetFitting), truth);
    EXPECT_LT(jet.rms_k1, 0.02);
    EXPECT_LT(jet.rms_k2, 0.02);
    EXPECT_LT(jet.rms_angle_deg, 3.0);
    const CurvatureErrors cone = testing::compare(torus, estimate(torus, CurvatureEstimator::NormalCone), truth);
    EXPECT_LT(cone.rms_k1, 0.05);
    // Jet fitting is geometric: the sign comes from the shading normal, so a sphere is +1/R.
    const TriMesh sphere = make_icosphere(2.0f, 4);
    const CurvatureErrors s = testing::compare(sphere, estimate(sphere, CurvatureEstimator::JetFitting),
                                               [](const float* x) { return testing::sphere_curvature(2.0, x); });
    EXPECT_LT(s.max_k1, 0.01);
}

TEST(Curvature, RejectsMeshesItCannotMeasure) {
    TriMesh m = make_plane(1.0f, 4);
    m.name = "plane.obj: mesh 'quad'";
    m.tangents.clear();
    Result<VertexCurvature> r = estimate_curvature(m, CurvatureEstimator::ShapeOperator);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("plane.obj"), std::string::npos);
    m = make_plane(1.0f, 4);
    m.indices.push_back(999);
    m.indices.push_back(0);
    m.indices.push_back(1);
    EXPECT_FALSE(estimate_curvature(m, CurvatureEstimator::ShapeOperator).ok());
    EXPECT_EQ(parse_curvature_estimator("jet-fitting"), CurvatureEstimator::JetFitting);
    EXPECT_FALSE(parse_curvature_estimator("magic").has_value());
    const VertexCurvature flat = estimate(make_plane(2.0f, 8));
    for (size_t v = 0; v < flat.values.size() / 4; ++v) EXPECT_EQ(flat.values[4 * v], 0.0f);
}

}  // namespace
}  // namespace specbake

namespace specbake {
namespace {

TEST(CurvatureSummary, SphereAndPlane) {
    const TriMesh sphere = make_icosphere(2.0f, 3);
    const CurvatureSummary s = summarize_curvature(sphere, estimate(sphere));
    EXPECT_NEAR(s.max_abs_k1, 0.5, 1e-3);
    EXPECT_NEAR(s.p95_abs_k1, 0.5, 1e-3);
    // Bounding box of the icosphere: its extreme vertices lie on the sphere, so the diagonal is at most 4 sqrt(3).
    EXPECT_LE(s.bbox_diagonal, 4.0 * std::sqrt(3.0) + 1e-5);
    EXPECT_GT(s.bbox_diagonal, 4.0 * std::sqrt(3.0) * 0.9);
    const TriMesh plane = make_plane(3.0f, 6);
    const CurvatureSummary p = summarize_curvature(plane, estimate(plane));
    EXPECT_EQ(p.max_abs_k1, 0.0f);
    EXPECT_EQ(p.relative_p95(), 0.0f);
    EXPECT_NEAR(p.bbox_diagonal, 3.0 * std::sqrt(2.0), 1e-5);
}

}  // namespace
}  // namespace specbake
