// validate_mesh: checks a TriMesh for everything that would break analysis, rejects what cannot be repaired
// and repairs the rest in place, returning counts for messages and manifests.
#pragma once

#include <cstddef>
#include <string>

#include "core/result.h"
#include "core/trimesh.h"
#include "mesh/weld_by_position.h"

namespace specbake {

struct MeshReport {
    size_t vertices = 0;
    size_t triangles = 0;
    size_t degenerate_triangles = 0;   // repeated index or zero area: kept in the index buffer, skipped by curvature
    size_t duplicate_vertices = 0;     // vertices at the position of an earlier vertex (welded for topology)
    size_t unreferenced_vertices = 0;  // no triangle uses them; their curvature is 0
    size_t boundary_edges = 0;         // edges with one triangle, after welding by position
    size_t nonmanifold_edges = 0;      // edges with three or more triangles, after welding by position
    size_t nonmanifold_vertices = 0;   // vertices whose triangles form more than one fan (or a fan plus a gap)
    size_t detached_faces = 0;         // triangles the half-edge mesh holds on their own vertices (third sheet on
                                       // an edge, or against a neighbour's orientation; see halfedge_mesh.h)
    size_t split_vertices = 0;         // extra half-edge vertices for the further fans of non-manifold vertices
    size_t repaired_normals = 0;       // zero or non-finite normals replaced by the generated normal
    size_t renormalized_normals = 0;   // finite normals with |n| off 1 by more than 1e-3, rescaled to unit length
    size_t repaired_tangents = 0;      // non-finite, zero or normal-parallel tangents rebuilt; w forced to +-1
    size_t repaired_uvs = 0;           // non-finite UVs set to 0
    bool generated_normals = false;    // set by prepare_mesh_for_curvature
    bool generated_tangents = false;   // set by prepare_mesh_for_curvature

    // One line, e.g. "1200 vertices, 2000 triangles, 3 degenerate triangles, 12 normals repaired".
    std::string summary() const;
};

// Rejects (Error naming mesh.name): no triangles, index count not a multiple of 3, an index >= vertex count,
// a non-finite position, attribute arrays whose size does not match the vertex count.
// Repairs (counted in the report), leaving every usable authored value bit-identical: normals that are zero
// or non-finite get the angle-weighted normal of the triangles that use that vertex (+Z when all of them
// are degenerate); normals whose length is off 1 by more than 1e-3 are rescaled; tangents that are
// non-finite, zero or parallel to the normal are rebuilt perpendicular to it, and w is snapped to +-1;
// non-finite UVs become 0. Triangles are never removed: degenerate ones are counted (curvature skips them).
// The topology counts come from the OpenMesh half-edge mesh of the welded positions (build_halfedge_mesh).
Result<MeshReport> validate_mesh(TriMesh& mesh);

// validate_mesh in its two steps, for callers that overlap the second with other work on the mesh:
// check_and_repair_mesh rejects and repairs (everything that reads or changes attributes), and
// add_topology_report fills the topology counts (duplicate and unreferenced vertices, degenerate triangles
// to split vertices), reading only
// positions and indices, so it may run while normals and tangents are generated.
Result<MeshReport> check_and_repair_mesh(TriMesh& mesh);
void add_topology_report(const TriMesh& mesh, MeshReport& report);

// add_topology_report on positions the caller welded (weld_by_position of this mesh with any options: only
// the position ids are used), so the weld can be shared with the curvature estimate.
void add_topology_report(const TriMesh& mesh, const WeldedTopology& positions, MeshReport& report);

}  // namespace specbake
