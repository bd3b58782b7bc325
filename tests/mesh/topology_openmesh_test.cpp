// validate_mesh's topology counts against OpenMesh's half-edge structure, an independent implementation:
// on manifold meshes the boundary edges must agree, and OpenMesh must refuse exactly the faces that would
// make an edge or a vertex non-manifold.
#include <gtest/gtest.h>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include "mesh/procedural_shapes.h"
#include "mesh/validate_mesh.h"
#include "mesh/weld_by_position.h"

namespace specbake {
namespace {

using HalfEdgeMesh = OpenMesh::TriMesh_ArrayKernelT<>;

struct OpenMeshCounts {
    size_t refused_faces = 0;
    size_t boundary_edges = 0;
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
    return c;
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

}  // namespace
}  // namespace specbake
