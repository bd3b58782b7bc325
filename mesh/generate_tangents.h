// generate_tangents: glTF TANGENT (xyzw) for meshes that have none, in the MikkTSpace convention glTF
// specifies: T along increasing u, bitangent B = cross(N, T) * w along decreasing glTF v (increasing v of
// the bottom-left-origin convention MikkTSpace tools use), per-corner contributions weighted by the corner
// angle and orthogonalised to the vertex normal before they are summed.
#pragma once

#include "mesh/trimesh.h"

namespace specbake {

// Fills mesh.tangents (unit xyz orthogonal to the normal, w = +-1). Requires normals. Differences from an
// exact MikkTSpace port: vertices are not re-split where corners disagree in handedness (the majority of
// angle weight decides w), and vertices are not merged by (position, normal, uv) first, so exact index-level
// duplicates accumulate separately. Without UVs, or where the UV mapping is degenerate at a vertex, T is a
// fixed perpendicular of N (Frisvad's orthonormal basis) with w = +1, so every vertex still has a frame.
void generate_tangents(TriMesh& mesh);

}  // namespace specbake
