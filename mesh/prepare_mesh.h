// prepare_mesh_for_curvature: everything a primitive needs before estimate_curvature, in one call:
// validate and repair, then generate normals and tangents where they are missing (reported).
#pragma once

#include <functional>

#include "core/result.h"
#include "mesh/generate_normals.h"
#include "core/trimesh.h"
#include "mesh/validate_mesh.h"
#include "mesh/weld_by_position.h"

namespace specbake {

struct PrepareOptions {
    NormalWeighting normal_weighting = NormalWeighting::Max;
    // How the mesh is welded for the topology report and for with_frames (pass the curvature's own
    // CurvatureOptions::weld so the estimate can reuse the weld).
    WeldOptions weld;
    // Called with the prepared mesh (normals and tangents in place) and its weld_by_position(mesh, weld)
    // while the topology report is still being built beside it, e.g. to estimate curvature: the two fill
    // each other's serial stretches on several cores. Not called when validation rejects the mesh.
    std::function<void(const TriMesh&, const WeldedTopology&)> with_frames;
};

// validate_mesh, then generate_normals when the mesh has none (report.generated_normals) and
// generate_tangents when it has none (report.generated_tangents; write them out with the curvature so the
// run time uses exactly the frame d refers to). Authored normals and tangents are kept as authored
// (apart from validate_mesh's documented repairs). The mesh is welded once, after the normals are final;
// the topology counts of the report (which read only positions, indices and that weld) are built
// concurrently with the tangents and options.with_frames.
Result<MeshReport> prepare_mesh_for_curvature(TriMesh& mesh, const PrepareOptions& options = {});

}  // namespace specbake
