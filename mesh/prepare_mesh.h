// prepare_mesh_for_curvature: everything a primitive needs before estimate_curvature, in one call:
// validate and repair, then generate normals and tangents where they are missing (reported).
#pragma once

#include <functional>

#include "bake/result.h"
#include "mesh/generate_normals.h"
#include "mesh/trimesh.h"
#include "mesh/validate_mesh.h"

namespace specbake {

struct PrepareOptions {
    NormalWeighting normal_weighting = NormalWeighting::Max;
    // Called with the prepared mesh (normals and tangents in place) while the topology report is still being
    // built beside it, e.g. to estimate curvature: the two fill each other's serial stretches on several
    // cores. Not called when validation rejects the mesh.
    std::function<void(const TriMesh&)> with_frames;
};

// validate_mesh, then generate_normals when the mesh has none (report.generated_normals) and
// generate_tangents when it has none (report.generated_tangents; write them out with the curvature so the
// run time uses exactly the frame d refers to). Authored normals and tangents are kept as authored
// (apart from validate_mesh's documented repairs). The topology counts of the report (which read only
// positions and indices) are built concurrently with the normals, tangents and options.with_frames.
Result<MeshReport> prepare_mesh_for_curvature(TriMesh& mesh, const PrepareOptions& options = {});

}  // namespace specbake
