// Welding, validation and repair, normal and tangent generation (SPEC Sec. 4, issue 4 item 1).
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "mesh/generate_normals.h"
#include "mesh/generate_tangents.h"
#include "mesh/mesh_math.h"
#include "mesh/prepare_mesh.h"
#include "mesh/procedural_shapes.h"
#include "mesh/validate_mesh.h"
#include "mesh/weld_by_position.h"
#include "tests/mesh/nonmanifold_meshes.h"

namespace specbake {
namespace {

double angle_deg(const float* a, const float* b) {
    const double d = a[0] * double(b[0]) + a[1] * double(b[1]) + a[2] * double(b[2]);
    const double la = std::sqrt(a[0] * double(a[0]) + a[1] * double(a[1]) + a[2] * double(a[2]));
    const double lb = std::sqrt(b[0] * double(b[0]) + b[1] * double(b[1]) + b[2] * double(b[2]));
    return std::acos(std::clamp(d / (la * lb), -1.0, 1.0)) * 180.0 / M_PI;
}

TEST(Weld, SeamsShareAGroupHardEdgesDoNot) {
    // UV sphere 8 x 4: the seam column (8 + 1 columns, 3 interior rings) and 2 x 8 pole vertices.
    const TriMesh sphere = make_uv_sphere(1.0f, 8, 4);
    const WeldedTopology t = weld_by_position(sphere);
    EXPECT_EQ(sphere.vertex_count(), 9u * 3u + 16u);
    EXPECT_EQ(t.position_count, 8u * 3u + 2u);
    EXPECT_EQ(t.group_count, t.position_count);  // normals agree at every seam and pole
    // Cube with split normals: 8 positions, 24 groups (each corner has three different normals).
    const TriMesh cube = make_flat_cube(1.0f);
    const WeldedTopology c = weld_by_position(cube);
    EXPECT_EQ(c.position_count, 8u);
    EXPECT_EQ(c.group_count, 24u);
    // -0 and +0 are one position.
    TriMesh zeros;
    zeros.positions = {0.0f, 1.0f, 2.0f, -0.0f, 1.0f, 2.0f, 0.0f, 1.0f, 2.5f};
    const WeldedTopology z = weld_by_position(zeros);
    EXPECT_EQ(z.position_count, 2u);
    EXPECT_EQ(z.position_id[0], z.position_id[1]);
}

TEST(Validate, RejectsWhatCannotBeRepaired) {
    TriMesh m = make_plane(1.0f, 2);
    m.name = "bad.gltf: mesh 'Plane'";
    TriMesh out_of_range = m;
    out_of_range.indices[4] = 1000;
    Result<MeshReport> r = validate_mesh(out_of_range);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("bad.gltf"), std::string::npos);
    EXPECT_NE(r.error().message.find("1000"), std::string::npos);

    TriMesh nan_position = m;
    nan_position.positions[4] = std::nanf("");
    EXPECT_FALSE(validate_mesh(nan_position).ok());
    TriMesh inf_position = m;
    inf_position.positions[0] = INFINITY;
    EXPECT_FALSE(validate_mesh(inf_position).ok());

    TriMesh no_triangles = m;
    no_triangles.indices.clear();
    EXPECT_FALSE(validate_mesh(no_triangles).ok());
    TriMesh ragged = m;
    ragged.indices.pop_back();
    EXPECT_FALSE(validate_mesh(ragged).ok());
    TriMesh short_normals = m;
    short_normals.normals.resize(3);
    EXPECT_FALSE(validate_mesh(short_normals).ok());
}

TEST(Validate, RepairsNormalsTangentsAndUvs) {
    TriMesh m = make_flat_cube(1.0f);
    m.normals[0] = m.normals[1] = m.normals[2] = 0.0f;   // vertex 0: zero
    m.normals[3] = std::nanf("");                         // vertex 1: non-finite
    for (int k = 0; k < 3; ++k) m.normals[6 + k] *= 0.1f;  // vertex 2: length 0.1
    for (int k = 0; k < 3; ++k) m.tangents[4 * 3 + k] = m.normals[3 * 3 + k];  // vertex 3: tangent parallel to N
    m.tangents[4 * 4 + 3] = 0.3f;                                               // vertex 4: w not +-1
    m.uv0[2 * 5] = INFINITY;                                                    // vertex 5: non-finite u
    const TriMesh original = make_flat_cube(1.0f);
    Result<MeshReport> r = validate_mesh(m);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->repaired_normals, 2u);
    EXPECT_EQ(r->renormalized_normals, 1u);
    EXPECT_EQ(r->repaired_tangents, 2u);
    EXPECT_EQ(r->repaired_uvs, 1u);
    // Repaired normals are the flat face normal (that vertex's own triangles), not a corner average.
    for (int v : {0, 1, 2}) EXPECT_LT(angle_deg(&m.normals[3 * v], &original.normals[3 * v]), 1e-4) << v;
    const float* t3 = &m.tangents[12];
    const double dot = t3[0] * m.normals[9] + t3[1] * m.normals[10] + t3[2] * m.normals[11];
    EXPECT_NEAR(dot, 0.0, 1e-6);
    EXPECT_EQ(m.tangents[19], 1.0f);
    EXPECT_EQ(m.uv0[10], 0.0f);
    // Untouched values stay bit-identical.
    for (size_t i = 9 * 3; i < m.normals.size(); ++i) EXPECT_EQ(m.normals[i], original.normals[i]);
    EXPECT_NE(r->summary().find("zero or non-finite normals regenerated"), std::string::npos);
}

TEST(Validate, CountsTopologyDefects) {
    // Three triangles on edge (0, 1): a non-manifold edge, and both its ends non-manifold vertices.
    // Vertex 5 is unreferenced; vertex 6 duplicates vertex 1, so triangle (6, 1, 2) is degenerate.
    TriMesh m;
    m.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 5, 5, 5, 1, 0, 0};
    m.indices = {0, 1, 2, 1, 0, 3, 0, 1, 4, 6, 1, 2};
    Result<MeshReport> r = validate_mesh(m);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->nonmanifold_edges, 1u);
    EXPECT_EQ(r->nonmanifold_vertices, 2u);
    EXPECT_EQ(r->boundary_edges, 6u);
    EXPECT_EQ(r->unreferenced_vertices, 1u);
    EXPECT_EQ(r->duplicate_vertices, 1u);
    EXPECT_EQ(r->degenerate_triangles, 1u);
}

TEST(Validate, ClosedMeshHasNoBoundaryAndHourglassVertexIsFound) {
    TriMesh ico = make_icosphere(1.0f, 1);
    Result<MeshReport> r = validate_mesh(ico);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->boundary_edges, 0u);
    EXPECT_EQ(r->nonmanifold_edges, 0u);
    EXPECT_EQ(r->nonmanifold_vertices, 0u);
    // Two cones sharing their apex only.
    TriMesh hourglass = test::hourglass_mesh();
    r = validate_mesh(hourglass);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->nonmanifold_vertices, 1u);
    EXPECT_EQ(r->boundary_edges, 12u);
}

TEST(Normals, AngleWeightedMatchesTheSphere) {
    TriMesh m = make_uv_sphere(2.0f, 64, 32);
    const std::vector<float> analytic = m.normals;
    m.normals.clear();
    generate_normals(m, NormalWeighting::Angle);
    double worst = 0.0;
    for (size_t v = 0; v < m.vertex_count(); ++v) worst = std::max(worst, angle_deg(&m.normals[3 * v], &analytic[3 * v]));
    EXPECT_LT(worst, 0.5);
    // Unindexed soup: every triangle its own vertices; welding by position still gives smooth normals.
    TriMesh soup;
    for (uint32_t i : m.indices) {
        soup.indices.push_back(uint32_t(soup.vertex_count()));
        soup.positions.insert(soup.positions.end(), &m.positions[3 * i], &m.positions[3 * i + 3]);
    }
    generate_normals(soup, NormalWeighting::Area);
    for (size_t k = 0; k < soup.indices.size(); ++k) {
        const uint32_t i = m.indices[k];
        const float* x = &m.positions[3 * i];
        const float radial[3] = {x[0], x[1], x[2]};
        EXPECT_LT(angle_deg(&soup.normals[3 * k], radial), 1.0);
    }
}

TEST(Normals, MaxWeightsAreExactOnAnIrregularSphere) {
    // Max 1999: for vertices on a sphere the weighted sum is exactly radial, however irregular the
    // triangulation; angle weights are not (independent check: the radial direction of each position).
    TriMesh m = make_uv_sphere(2.0f, 32, 16, 0.4f, 5);
    m.normals.clear();
    generate_normals(m, NormalWeighting::Max);
    TriMesh angle = m;
    generate_normals(angle, NormalWeighting::Angle);
    double worst_max = 0.0, worst_angle = 0.0;
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        const float* radial = &m.positions[3 * v];
        worst_max = std::max(worst_max, angle_deg(&m.normals[3 * v], radial));
        worst_angle = std::max(worst_angle, angle_deg(&angle.normals[3 * v], radial));
    }
    EXPECT_LT(worst_max, 1e-3);
    EXPECT_GT(worst_angle, 10.0 * worst_max);
    // The default is Max.
    TriMesh by_default = m;
    by_default.normals.clear();
    generate_normals(by_default);
    EXPECT_EQ(by_default.normals, m.normals);
}

TEST(Tangents, FollowUAndTheGltfBitangentConvention) {
    TriMesh m = make_torus(3.0f, 1.0f, 64, 32);
    const std::vector<float> analytic = m.tangents;
    m.tangents.clear();
    generate_tangents(m);
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        // On the u seam a vertex sees the triangles of one side only (as in MikkTSpace, whose vertices differ
        // in UV there), so T is the one-sided secant: off by half a segment, 360 / 64 / 2 degrees.
        const bool seam = m.uv0[2 * v] == 0.0f || m.uv0[2 * v] == 1.0f;
        EXPECT_LT(angle_deg(&m.tangents[4 * v], &analytic[4 * v]), seam ? 2.9 : 0.1) << v;
        EXPECT_EQ(m.tangents[4 * v + 3], analytic[4 * v + 3]) << v;
        const float* n = &m.normals[3 * v];
        EXPECT_NEAR(n[0] * m.tangents[4 * v] + n[1] * m.tangents[4 * v + 1] + n[2] * m.tangents[4 * v + 2], 0.0, 1e-6);
    }
    // Flipping v flips the handedness.
    TriMesh flipped = make_torus(3.0f, 1.0f, 64, 32);
    for (size_t v = 0; v < flipped.vertex_count(); ++v) flipped.uv0[2 * v + 1] = 1.0f - flipped.uv0[2 * v + 1];
    generate_tangents(flipped);
    for (size_t v = 0; v < flipped.vertex_count(); ++v) EXPECT_EQ(flipped.tangents[4 * v + 3], -analytic[4 * v + 3]);
    // Plane with glTF UVs (v down the image while y goes up): T = +x, w = +1 (B = +y).
    TriMesh plane = make_plane(1.0f, 3);
    plane.tangents.clear();
    generate_tangents(plane);
    for (size_t v = 0; v < plane.vertex_count(); ++v) {
        EXPECT_NEAR(plane.tangents[4 * v], 1.0f, 1e-6);
        EXPECT_EQ(plane.tangents[4 * v + 3], 1.0f);
    }
    // No UVs: still a unit tangent perpendicular to the normal.
    TriMesh ico = make_icosphere(1.0f, 2);
    ico.tangents.clear();
    generate_tangents(ico);
    for (size_t v = 0; v < ico.vertex_count(); ++v) {
        const float* t = &ico.tangents[4 * v];
        const float* n = &ico.normals[3 * v];
        EXPECT_NEAR(t[0] * t[0] + t[1] * t[1] + t[2] * t[2], 1.0, 1e-5);
        EXPECT_NEAR(t[0] * n[0] + t[1] * n[1] + t[2] * n[2], 0.0, 1e-5);
    }
}

TEST(Tangents, CornerAngleMatchesLibmAtan2) {
    // The tangent corner weights: against libm's double atan2 over random magnitudes (1e-6 .. 1e6 each, so
    // both reduction branches and the tan(pi/8) split are hit) and a dense sweep of the angle.
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    double worst = 0.0;
    for (int i = 0; i < 200000; ++i) {
        const double y = std::abs(unit(rng)) * std::pow(10.0, 6.0 * unit(rng));
        const double x = unit(rng) * std::pow(10.0, 6.0 * unit(rng));
        worst = std::max(worst, std::abs(detail::corner_angle(y, x) - std::atan2(y, x)));
    }
    for (int i = 0; i <= 100000; ++i) {
        const double th = M_PI * i / 100000.0;
        const double y = std::max(0.0, std::sin(th)), x = std::cos(th);
        worst = std::max(worst, std::abs(detail::corner_angle(y, x) - std::atan2(y, x)));
    }
    EXPECT_LT(worst, 3e-11);
    // Edges, as atan2: zero sine, zero cosine, NaN.
    EXPECT_EQ(detail::corner_angle(0.0, 2.0), 0.0);
    EXPECT_EQ(detail::corner_angle(0.0, 0.0), 0.0);
    EXPECT_DOUBLE_EQ(detail::corner_angle(0.0, -2.0), M_PI);
    EXPECT_DOUBLE_EQ(detail::corner_angle(3.0, 0.0), M_PI / 2.0);
    EXPECT_DOUBLE_EQ(detail::corner_angle(1.0, 1.0), M_PI / 4.0);
    EXPECT_TRUE(std::isnan(detail::corner_angle(std::nan(""), 1.0)));
}

// Brute-force MikkTSpace sums per vertex, the reference of the Tangents tests: each corner's dP/du (solved per
// triangle from its UVs) projected into the vertex tangent plane and normalised, summed with the corner angle
// in that plane (libm atan2) as weight, and without weight. Triangles with degenerate UVs are skipped and
// counted.
struct TangentSums {
    std::vector<double> weighted, unweighted;  // 3 per vertex
    size_t degenerate = 0;
};
TangentSums brute_force_tangent_sums(const TriMesh& m) {
    TangentSums out;
    out.weighted.assign(3 * m.vertex_count(), 0.0);
    out.unweighted.assign(3 * m.vertex_count(), 0.0);
    auto at = [&](uint32_t v, int k) { return double(m.positions[3 * v + k]); };
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        const uint32_t* f = &m.indices[3 * t];
        const double du1 = m.uv0[2 * f[1]] - double(m.uv0[2 * f[0]]), dv1 = m.uv0[2 * f[1] + 1] - double(m.uv0[2 * f[0] + 1]);
        const double du2 = m.uv0[2 * f[2]] - double(m.uv0[2 * f[0]]), dv2 = m.uv0[2 * f[2] + 1] - double(m.uv0[2 * f[0] + 1]);
        const double det = du1 * dv2 - du2 * dv1;
        if (det == 0.0) {
            ++out.degenerate;
            continue;
        }
        double dpdu[3];
        for (int k = 0; k < 3; ++k) dpdu[k] = ((at(f[1], k) - at(f[0], k)) * dv2 - (at(f[2], k) - at(f[0], k)) * dv1) / det;
        for (int c = 0; c < 3; ++c) {
            const uint32_t v = f[c];
            const double n[3] = {m.normals[3 * v], m.normals[3 * v + 1], m.normals[3 * v + 2]};
            auto project = [&](const double* a, double* p) {
                const double d = a[0] * n[0] + a[1] * n[1] + a[2] * n[2];
                for (int k = 0; k < 3; ++k) p[k] = a[k] - d * n[k];
            };
            double e1[3], e2[3], a1[3], a2[3], tp[3];
            for (int k = 0; k < 3; ++k) {
                a1[k] = at(f[(c + 1) % 3], k) - at(v, k);
                a2[k] = at(f[(c + 2) % 3], k) - at(v, k);
            }
            project(a1, e1);
            project(a2, e2);
            project(dpdu, tp);
            const double cross[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
            const double angle = std::atan2(std::sqrt(cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]),
                                            e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2]);
            const double tl = std::sqrt(tp[0] * tp[0] + tp[1] * tp[1] + tp[2] * tp[2]);
            for (int k = 0; k < 3; ++k) {
                out.weighted[3 * v + k] += angle * tp[k] / tl;
                out.unweighted[3 * v + k] += tp[k] / tl;
            }
        }
    }
    return out;
}

double unit_component(const double* x, int k) { return x[k] / std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]); }

TEST(Tangents, IrregularTorusMatchesABruteForceMikkTSpaceSum) {
    // Irregular triangles make the corner-angle weights matter.
    TriMesh m = make_torus(3.0f, 1.0f, 24, 12, 0.4f, 5);
    m.tangents.clear();
    generate_tangents(m);
    const TangentSums ref = brute_force_tangent_sums(m);
    ASSERT_EQ(ref.degenerate, 0u);
    double weights_matter = 0.0;  // how far equal weights would be off: the test sees a wrong weighting
    for (size_t v = 0; v < m.vertex_count(); ++v)
        for (int k = 0; k < 3; ++k) {
            EXPECT_NEAR(m.tangents[4 * v + k], unit_component(&ref.weighted[3 * v], k), 2e-7) << v;
            weights_matter = std::max(weights_matter, std::abs(m.tangents[4 * v + k] - unit_component(&ref.unweighted[3 * v], k)));
        }
    EXPECT_GT(weights_matter, 1e-3);
}

TEST(Tangents, ThreadCountAndVertexOrderLeaveTheBitsAlone) {
    // About 100k vertices, so the vertices are split into several chunks (parallel tasks, with triangles on
    // the chunk borders); every 37th triangle with collapsed UVs (skipped corners), and a triangle count that
    // is not a multiple of the batch size.
    TriMesh m = make_torus(3.0f, 1.0f, 400, 250, 0.4f, 9);
    m.tangents.clear();
    for (size_t t = 0; t < m.triangle_count(); t += 37) {
        const uint32_t* f = &m.indices[3 * t];
        for (int k = 0; k < 2; ++k) m.uv0[2 * f[2] + k] = m.uv0[2 * f[1] + k] = m.uv0[2 * f[0] + k];
    }
    m.indices.resize(m.indices.size() - 3);
    ASSERT_GT(m.vertex_count(), 100000u);
    auto tangents_with = [](TriMesh mesh, size_t threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        generate_tangents(mesh);
        return mesh.tangents;
    };
    const std::vector<float> one = tangents_with(m, 1);
    EXPECT_EQ(tangents_with(m, 2), one);
    EXPECT_EQ(tangents_with(m, 3), one);
    // Vertices renumbered at random: each vertex still sums its corners in the same order, so the same bits,
    // although no block of triangles now has a narrow vertex-index range.
    std::vector<uint32_t> perm(m.vertex_count());
    for (size_t v = 0; v < perm.size(); ++v) perm[v] = uint32_t(v);
    std::shuffle(perm.begin(), perm.end(), std::mt19937(4));
    TriMesh shuffled = m;
    for (size_t v = 0; v < perm.size(); ++v) {
        for (int k = 0; k < 3; ++k) shuffled.positions[3 * perm[v] + k] = m.positions[3 * v + k];
        for (int k = 0; k < 3; ++k) shuffled.normals[3 * perm[v] + k] = m.normals[3 * v + k];
        for (int k = 0; k < 2; ++k) shuffled.uv0[2 * perm[v] + k] = m.uv0[2 * v + k];
    }
    for (uint32_t& i : shuffled.indices) i = perm[i];
    const std::vector<float> renumbered = tangents_with(shuffled, 2);
    for (size_t v = 0; v < perm.size(); ++v)
        for (int k = 0; k < 4; ++k) ASSERT_EQ(renumbered[4 * perm[v] + k], one[4 * v + k]) << v;
    // And the values: the brute force wherever a vertex has a UV triangle left.
    const TangentSums ref = brute_force_tangent_sums(m);
    EXPECT_GT(ref.degenerate, 0u);
    size_t fallback = 0;
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        const double* sum = &ref.weighted[3 * v];
        if (sum[0] == 0.0 && sum[1] == 0.0 && sum[2] == 0.0) {
            ++fallback;
            continue;
        }
        for (int k = 0; k < 3; ++k) ASSERT_NEAR(one[4 * v + k], unit_component(sum, k), 2e-7) << v;
    }
    EXPECT_LT(fallback, m.vertex_count() / 100);
}

TEST(Tangents, UvSphereMatchesTheAnalyticDPdu) {
    // u = longitude / 2 pi, so dP/du is along (-y, x, 0) wherever the latitude circle is defined; glTF v runs
    // from the north pole down, so B = cross(N, T) * w must point north: w = +1 everywhere.
    TriMesh m = make_uv_sphere(1.3f, 64, 32);
    m.tangents.clear();
    generate_tangents(m);
    double worst_inside = 0.0, worst_seam = 0.0;
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        const float* x = &m.positions[3 * v];
        if (std::hypot(x[0], x[1]) < 1e-3) continue;  // pole vertices: dP/du vanishes
        const float analytic[3] = {-x[1], x[0], 0.0f};
        const double angle = angle_deg(&m.tangents[4 * v], analytic);
        const bool seam = m.uv0[2 * v] == 0.0f || m.uv0[2 * v] == 1.0f;
        (seam ? worst_seam : worst_inside) = std::max(seam ? worst_seam : worst_inside, angle);
        EXPECT_EQ(m.tangents[4 * v + 3], 1.0f) << v;
    }
    EXPECT_LT(worst_inside, 0.05);
    // Seam vertices see one side only (their UVs differ from the other side's): half a segment, 2.8 degrees.
    EXPECT_LT(worst_seam, 360.0 / 64.0 / 2.0 + 0.05);
    std::printf("UV sphere tangents: worst %.4f deg inside, %.4f deg on the seam\n", worst_inside, worst_seam);
}

TEST(Prepare, GeneratesWhatIsMissingAndSaysSo) {
    TriMesh m = make_uv_sphere(1.0f, 16, 8);
    m.normals.clear();
    m.tangents.clear();
    Result<MeshReport> r = prepare_mesh_for_curvature(m);
    ASSERT_TRUE(r.ok());
    EXPECT_TRUE(r->generated_normals);
    EXPECT_TRUE(r->generated_tangents);
    EXPECT_TRUE(m.has_normals());
    EXPECT_TRUE(m.has_tangents());
    EXPECT_NE(r->summary().find("normals generated"), std::string::npos);
}

}  // namespace
}  // namespace specbake
