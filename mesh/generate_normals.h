// generate_normals: smooth vertex normals for meshes that have none.
#pragma once

#include "core/trimesh.h"

namespace specbake {

enum class NormalWeighting {
    Angle,  // sum of face normals weighted by the corner angle (Thurmer & Wuthrich 1998)
    Area,   // sum of unnormalised face normals (area-weighted)
    Max,    // default: sum of e1 x e2 / (|e1|^2 |e2|^2) over the corner's two edges (Max, "Weights for Computing
            // Vertex Normals from Facet Normals", JGT 1999): exact for vertices on a sphere, however irregular
};

// Fills mesh.normals with one unit normal per vertex, smoothed over all triangles that meet at the vertex's
// position (welded by position, so unindexed soups come out smooth). Degenerate triangles contribute nothing;
// a vertex with no usable triangle gets +Z. Overwrites existing normals. Indices must be in range
// (validate_mesh checks that). Accuracy (bench/mesh_accuracy, "gen. normals" rows, shape-operator RMS k1 error
// of the generated field against the surface): on regular grids both weightings converge; on irregular
// triangulations neither does, and Max stays at ~8% (jittered torus) and ~4.5% (jittered ellipsoid) where
// Angle stays at ~11-13% on the torus and grows without bound on the ellipsoid (25% at 32x16, 400% at 128x64).
void generate_normals(TriMesh& mesh, NormalWeighting weighting = NormalWeighting::Max);

}  // namespace specbake
