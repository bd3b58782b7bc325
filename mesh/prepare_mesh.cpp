#include "mesh/prepare_mesh.h"

#include <tbb/task_group.h>

#include "mesh/generate_tangents.h"

namespace specbake {

Result<MeshReport> prepare_mesh_for_curvature(TriMesh& mesh, const PrepareOptions& options) {
    Result<MeshReport> report = check_and_repair_mesh(mesh);
    if (!report) return report;
    // The topology pass reads positions and indices and writes only its own report fields; everything
    // below writes normals, tangents and the generated_* flags.
    tbb::task_group topology;
    topology.run([&] { add_topology_report(mesh, *report); });
    if (!mesh.has_normals()) {
        generate_normals(mesh, options.normal_weighting);
        report->generated_normals = true;
    }
    if (!mesh.has_tangents()) {
        generate_tangents(mesh);
        report->generated_tangents = true;
    }
    if (options.with_frames) options.with_frames(mesh);
    topology.wait();
    return report;
}

}  // namespace specbake
