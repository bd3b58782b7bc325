// Shared by the curvature estimators (internal to specbake_mesh): one orthonormal frame per curvature
// group, and the step from a per-group 2x2 shape operator to the per-vertex (k1, k2, d) of SPEC Sec. 4.
#pragma once

#include <vector>

#include "mesh/mesh_math.h"
#include "mesh/scratch_array.h"
#include "mesh/weld_by_position.h"

namespace specbake::detail {

// Frame of each curvature group: the unit normal of its first vertex and a fixed perpendicular basis.
struct GroupFrames {
    std::vector<Vec3d> n, u, v;
};
GroupFrames make_group_frames(const TriMesh& mesh, const WeldedTopology& topology);

// Symmetric 2x2 shape operator [[a, b], [b, c]] in a group's (u, v) basis, 1/length.
struct Shape2 {
    double a = 0.0, b = 0.0, c = 0.0;
};

// The frame make_group_frames gives a group whose first vertex has this (not necessarily unit) normal.
void group_frame(const float normal[3], Vec3d& n, Vec3d& u, Vec3d& v);

// Principal curvatures of one group (|k1| >= |k2|) and the unit k1 direction in object space.
struct GroupPrincipal {
    double k1, k2, dir[3];
};

// Eigen-decomposition of an operator given in the (u, v) basis. An isotropic operator (umbilic, or no data)
// gets the direction u.
GroupPrincipal principal_curvatures(const Shape2& s, const Vec3d& u, const Vec3d& v);

// Writes (k1, k2, d) for every vertex from its group's principal curvatures, d being the k1 direction
// expressed in that vertex's own tangent frame (T orthogonalised against N, B = cross(N, T) * w).
VertexCurvature vertex_curvature_from_principal(const TriMesh& mesh, const WeldedTopology& topology,
                                                const GroupPrincipal* principal);

// The same for one vertex v with its group's principal curvatures p: out = (k1, k2, d.x, d.y).
void vertex_curvature_at(const TriMesh& mesh, const WeldedTopology& topology, size_t v, const GroupPrincipal& p,
                         float out[4]);

// Both steps for operators in the group frames: (k1, k2, d) for every vertex.
VertexCurvature vertex_curvature_from_groups(const TriMesh& mesh, const WeldedTopology& topology,
                                             const GroupFrames& frames, const std::vector<Shape2>& shape);

// Corners (3 * triangle + corner) of each curvature group, in increasing corner order (a counting sort), so
// per-group sums are the same for any thread count: group g owns order[start[g] .. start[g + 1]).
struct GroupCorners {
    ScratchArray<uint32_t> start, order;
};
GroupCorners group_corners(const TriMesh& mesh, const WeldedTopology& topology);

// True when the triangle's corners are not three distinct positions or it is numerically a line.
bool skip_triangle(const TriMesh& mesh, const WeldedTopology& topology, size_t t);

}  // namespace specbake::detail
