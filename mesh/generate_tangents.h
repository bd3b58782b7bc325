// generate_tangents: glTF TANGENT (xyzw) for meshes that have none, following MikkTSpace (the algorithm glTF
// names): per triangle dP/du from the UV derivatives; per vertex the corners' dP/du projected into the
// vertex's tangent plane, normalised and summed with the corner angle (measured in that plane) as weight;
// the sum normalised. T points along increasing u; B = cross(N, T) * w along decreasing glTF v (increasing v
// of the bottom-left-origin convention MikkTSpace tools use).
#pragma once

#include "core/trimesh.h"

namespace specbake {

// Fills mesh.tangents (unit xyz orthogonal to the normal, w = +-1). Requires normals. Differences from
// MikkTSpace itself: corners are gathered per vertex index (MikkTSpace first merges vertices with equal
// position, normal and UV, so exact index-level duplicates accumulate separately here), and a vertex whose
// corners disagree in handedness keeps one tangent with the angle-weighted majority's w instead of being
// split. Without UVs, or where every UV triangle at a vertex is degenerate, T is a fixed perpendicular of N
// (Frisvad's orthonormal basis) with w = +1, so every vertex still has a frame. Linear time, parallel, the
// same result for any thread count and on any CPU (AVX2 or not); working memory a few MB per thread.
void generate_tangents(TriMesh& mesh);

}  // namespace specbake
