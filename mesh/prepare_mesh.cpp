#include "mesh/prepare_mesh.h"

#include "mesh/generate_tangents.h"

namespace specbake {

Result<MeshReport> prepare_mesh_for_curvature(TriMesh& mesh, const PrepareOptions& options) {
    Result<MeshReport> report = validate_mesh(mesh);
    if (!report) return report;
    if (!mesh.has_normals()) {
        generate_normals(mesh, options.normal_weighting);
        report->generated_normals = true;
    }
    if (!mesh.has_tangents()) {
        generate_tangents(mesh);
        report->generated_tangents = true;
    }
    return report;
}

}  // namespace specbake
