// validate_mesh's topology counts and build_halfedge_mesh against OpenMesh's own add_face, an independent
// construction: on manifold meshes the boundary edges and every one-ring must agree, OpenMesh must refuse
// exactly the faces that would make an edge or a vertex non-manifold, and what build_halfedge_mesh makes of
// those must pass OpenMesh's mesh checker.
#include <gtest/gtest.h>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Utils/MeshCheckerT.hh>
#include <algorithm>
#include <sstream>

#include "mesh/halfedge_mesh.h"
#include "mesh/procedural_shapes.h"
#include "mesh/validate_mesh.h"
#include "mesh/weld_by_position.h"
#include "tests/mesh/nonmanifold_meshes.h"

namespace specbake {
namespace {

using HalfEdgeMesh = OpenMesh::TriMesh_ArrayKernelT<>;

struct OpenMeshCounts {
    size_t refused_faces = 0;
    size_t boundary_edges = 0;
    std::vector<std::vector<uint32_t>> rings;  // per welded position: sorted neighbouring positions
};

OpenMeshCounts openmesh_counts(const TriMesh& m) {
    TriMesh positions_only;
    positions_only.positions = m.positions;
    const WeldedTopology t = weld_by_position(positions_only);
    HalfEdgeMesh hm;
    std::vector<HalfEdgeMesh::VertexHandle> vh(t.position_count);
    std::vector<char> made(t.position_count, 0);
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        const uint32_t p = t.position_id[v];
        if (made[p]) continue;
        made[p] = 1;
        vh[p] = hm.add_vertex(HalfEdgeMesh::Point(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]));
    }
    OpenMeshCounts c;
    for (size_t f = 0; f < m.triangle_count(); ++f) {
        const uint32_t a = t.position_id[m.indices[3 * f]], b = t.position_id[m.indices[3 * f + 1]],
                       d = t.position_id[m.indices[3 * f + 2]];
        if (a == b || b == d || a == d) continue;
        if (!hm.add_face(vh[a], vh[b], vh[d]).is_valid()) ++c.refused_faces;
    }
    for (auto e : hm.edges())
        if (hm.is_boundary(e)) ++c.boundary_edges;
    c.rings.resize(t.position_count);
    std::vector<uint32_t> position_of(hm.n_vertices());
    for (uint32_t p = 0; p < t.position_count; ++p)
        if (made[p]) position_of[vh[p].idx()] = p;
    for (auto v : hm.vertices()) {
        for (auto w : hm.vv_range(v)) c.rings[position_of[v.idx()]].push_back(position_of[w.idx()]);
        std::sort(c.rings[position_of[v.idx()]].begin(), c.rings[position_of[v.idx()]].end());
    }
    return c;
}

HalfEdgeTopology halfedge_of(const TriMesh& m) {
    WeldOptions by_position;
    by_position.split_by_normals = false;
    return build_halfedge_mesh(m, weld_by_position(m, by_position));
}

// OpenMesh's checker (outgoing halfedges on the boundary, next/prev cycles, faces referenced) and every
// vertex manifold.
void expect_valid(const HalfEdgeTopology& h, const std::string& what) {
    std::ostringstream problems;
    OpenMesh::Utils::MeshCheckerT<HalfEdgeMesh> checker(h.mesh);
    EXPECT_TRUE(checker.check(OpenMesh::Utils::MeshCheckerT<HalfEdgeMesh>::CHECK_ALL, problems))
        << what << ": " << problems.str();
    for (auto v : h.mesh.vertices()) EXPECT_TRUE(h.mesh.is_manifold(v)) << what << " vertex " << v.idx();
}

TEST(TopologyVsOpenMesh, BoundaryEdgesAgreeOnManifoldMeshes) {
    std::vector<TriMesh> meshes = {make_icosphere(1.0f, 2), make_cylinder(1.0f, 2.0f, 24, 6),
                                   make_uv_sphere(1.0f, 16, 8), make_torus(3.0f, 1.0f, 20, 10, 0.3f, 2),
                                   make_flat_cube(1.0f), make_plane(1.0f, 5)};
    // Cut a hole: drop every fifth triangle of a sphere.
    TriMesh holes = make_uv_sphere(1.0f, 32, 16);
    std::vector<uint32_t> kept;
    for (size_t f = 0; f < holes.triangle_count(); ++f)
        if (f % 5 != 0) kept.insert(kept.end(), &holes.indices[3 * f], &holes.indices[3 * f + 3]);
    holes.indices = kept;
    meshes.push_back(holes);
    size_t compared = 0;
    for (TriMesh& m : meshes) {
        const OpenMeshCounts om = openmesh_counts(m);
        Result<MeshReport> r = validate_mesh(m);
        ASSERT_TRUE(r.ok());
        if (om.refused_faces == 0) {
            EXPECT_EQ(r->boundary_edges, om.boundary_edges) << m.name;
            EXPECT_EQ(r->nonmanifold_edges, 0u) << m.name;
            ++compared;
        }
    }
    EXPECT_EQ(compared, meshes.size());
}

TEST(TopologyVsOpenMesh, NonManifoldEdgeIsOneOpenMeshRefuses) {
    // Three fins on one edge.
    TriMesh fins;
    fins.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1};
    fins.indices = {0, 1, 2, 1, 0, 3, 0, 1, 4};
    Result<MeshReport> r = validate_mesh(fins);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->nonmanifold_edges, 1u);
    EXPECT_EQ(openmesh_counts(fins).refused_faces, 1u);
}

TEST(HalfEdgeMesh, SameOneRingsAsAddFaceOnManifoldMeshes) {
    std::vector<TriMesh> meshes = {make_icosphere(1.0f, 2), make_cylinder(1.0f, 2.0f, 24, 6),
                                   make_uv_sphere(1.0f, 16, 8), make_torus(3.0f, 1.0f, 20, 10, 0.3f, 2),
                                   make_flat_cube(1.0f), make_plane(1.0f, 5)};
    for (const TriMesh& m : meshes) {
        const OpenMeshCounts om = openmesh_counts(m);
        ASSERT_EQ(om.refused_faces, 0u);
        const HalfEdgeTopology h = halfedge_of(m);
        expect_valid(h, m.name);
        EXPECT_EQ(h.mesh.n_faces(), m.triangle_count());
        EXPECT_EQ(h.detached_faces + h.split_vertices + h.nonmanifold_vertices + h.nonmanifold_edges, 0u);
        size_t boundary = 0;
        for (auto e : h.mesh.edges()) boundary += h.mesh.is_boundary(e);
        EXPECT_EQ(boundary, om.boundary_edges);
        EXPECT_EQ(h.boundary_edges, om.boundary_edges);
        ASSERT_EQ(h.mesh.n_vertices(), om.rings.size());
        for (auto v : h.mesh.vertices()) {
            std::vector<uint32_t> ring;
            for (auto w : h.mesh.vv_range(v)) ring.push_back(h.vertex_position[w.idx()]);
            std::sort(ring.begin(), ring.end());
            EXPECT_EQ(ring, om.rings[h.vertex_position[v.idx()]]) << "position " << h.vertex_position[v.idx()];
        }
        // Every face is its triangle, same winding (up to rotation).
        for (auto f : h.mesh.faces()) {
            const uint32_t t = h.face_triangle[f.idx()];
            std::vector<uint32_t> corners;
            for (auto v : h.mesh.fv_range(f)) corners.push_back(h.vertex_position[v.idx()]);
            const WeldedTopology w = weld_by_position(m);
            const uint32_t a = w.position_id[m.indices[3 * t]];
            const auto at = std::find(corners.begin(), corners.end(), a);
            ASSERT_NE(at, corners.end());
            std::rotate(corners.begin(), at, corners.end());
            EXPECT_EQ(corners[1], w.position_id[m.indices[3 * t + 1]]);
            EXPECT_EQ(corners[2], w.position_id[m.indices[3 * t + 2]]);
        }
    }
}

TEST(HalfEdgeMesh, NonManifoldInputIsSplitAndCounted) {
    // Three fins on one edge: the third is detached, both ends of the edge are non-manifold.
    TriMesh fins;
    fins.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1};
    fins.indices = {0, 1, 2, 1, 0, 3, 0, 1, 4};
    HalfEdgeTopology h = halfedge_of(fins);
    expect_valid(h, "fins");
    EXPECT_EQ(h.mesh.n_faces(), 3u);
    EXPECT_EQ(h.detached_faces, 1u);
    EXPECT_EQ(h.nonmanifold_edges, 1u);
    EXPECT_EQ(h.nonmanifold_vertices, 2u);
    EXPECT_EQ(h.boundary_edges, 6u);
    EXPECT_EQ(h.face_triangle[2], 2u);  // the detached face comes last

    // Two closed cones sharing their apex: one vertex per fan, each with its full ring of six.
    TriMesh hourglass = test::hourglass_mesh();
    EXPECT_EQ(openmesh_counts(hourglass).refused_faces, 6u);  // add_face refuses the whole second cone
    h = halfedge_of(hourglass);
    expect_valid(h, "hourglass");
    EXPECT_EQ(h.mesh.n_faces(), 12u);
    EXPECT_EQ(h.detached_faces, 0u);
    EXPECT_EQ(h.split_vertices, 1u);
    EXPECT_EQ(h.nonmanifold_vertices, 1u);
    size_t apexes = 0;
    for (auto v : h.mesh.vertices()) {
        if (h.vertex_position[v.idx()] != 0) continue;
        ++apexes;
        EXPECT_EQ(h.mesh.valence(v), 6u);
        EXPECT_FALSE(h.mesh.is_boundary(v));
    }
    EXPECT_EQ(apexes, 2u);

    // A face against its neighbours' orientation in a closed mesh: detached, the rest stays one manifold
    // sheet with a triangular hole; no vertex is non-manifold (the link ignores orientation).
    TriMesh flipped = make_icosphere(1.0f, 1);
    const size_t last = flipped.triangle_count() - 1;
    std::swap(flipped.indices[3 * last + 1], flipped.indices[3 * last + 2]);
    h = halfedge_of(flipped);
    expect_valid(h, "flipped");
    EXPECT_EQ(h.mesh.n_faces(), flipped.triangle_count());
    EXPECT_EQ(h.detached_faces, 1u);
    EXPECT_EQ(h.nonmanifold_vertices, 0u);
    EXPECT_EQ(h.nonmanifold_edges, 0u);
    size_t boundary = 0;
    for (auto e : h.mesh.edges()) boundary += h.mesh.is_boundary(e);
    EXPECT_EQ(boundary, 6u);  // the hole's three edges and the detached face's three

    // The same triangle twice: the copy is detached. Twice with opposite windings (a two-sided sheet): both
    // attached, closed into a pillow with no boundary.
    TriMesh twice;
    twice.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    twice.indices = {0, 1, 2, 0, 1, 2};
    h = halfedge_of(twice);
    expect_valid(h, "same triangle twice");
    EXPECT_EQ(h.detached_faces, 1u);
    EXPECT_EQ(h.mesh.n_faces(), 2u);
    twice.indices = {0, 1, 2, 0, 2, 1};
    h = halfedge_of(twice);
    expect_valid(h, "pillow");
    EXPECT_EQ(h.detached_faces, 0u);
    EXPECT_EQ(h.boundary_edges, 0u);
    for (auto e : h.mesh.edges()) EXPECT_FALSE(h.mesh.is_boundary(e));
}

}  // namespace
}  // namespace specbake
