// generate_normals: smooth vertex normals for meshes that have none.
#pragma once

#include "mesh/trimesh.h"

namespace specbake {

enum class NormalWeighting {
    Angle,  // default: sum of face normals weighted by the corner angle (Thurmer & Wuthrich 1998);
            // independent of how the surface is triangulated
    Area,   // sum of unnormalised face normals (area-weighted)
};

// Fills mesh.normals with one unit normal per vertex, smoothed over all triangles that meet at the vertex's
// position (welded by position, so unindexed soups come out smooth). Degenerate triangles contribute nothing;
// a vertex with no usable triangle gets +Z. Overwrites existing normals. Accuracy: second order on regular
// grids, first order on irregular triangulations, so the curvature of a generated normal field on an
// irregular mesh stays ~10% off however fine the mesh (bench/mesh_accuracy, "gen. normals" rows). Indices must be in range
// (validate_mesh checks that).
void generate_normals(TriMesh& mesh, NormalWeighting weighting = NormalWeighting::Angle);

}  // namespace specbake
