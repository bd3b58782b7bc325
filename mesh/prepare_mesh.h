// prepare_mesh_for_curvature: everything a primitive needs before estimate_curvature, in one call:
// validate and repair, then generate normals and tangents where they are missing (reported).
#pragma once

#include "bake/result.h"
#include "mesh/generate_normals.h"
#include "mesh/trimesh.h"
#include "mesh/validate_mesh.h"

namespace specbake {

struct PrepareOptions {
    NormalWeighting normal_weighting = NormalWeighting::Max;
};

// validate_mesh, then generate_normals when the mesh has none (report.generated_normals) and
// generate_tangents when it has none (report.generated_tangents; write them out with the curvature so the
// run time uses exactly the frame d refers to). Authored normals and tangents are kept as authored
// (apart from validate_mesh's documented repairs).
Result<MeshReport> prepare_mesh_for_curvature(TriMesh& mesh, const PrepareOptions& options = {});

}  // namespace specbake
