#include "mesh/prepare_mesh.h"

#include <tbb/task_group.h>

#include "mesh/generate_tangents.h"

namespace specbake {

Result<MeshReport> prepare_mesh_for_curvature(TriMesh& mesh, const PrepareOptions& options) {
    Result<MeshReport> report = check_and_repair_mesh(mesh);
    if (!report) return report;
    if (!mesh.has_normals()) {
        generate_normals(mesh, options.normal_weighting);
        report->generated_normals = true;
    }
    // One weld for the report and the curvature: the position ids do not depend on the normals, the groups
    // (which the report ignores) need them final.
    const WeldedTopology welded = weld_by_position(mesh, options.weld);
    // The topology pass reads positions, indices and the weld and writes only its own report fields; what
    // runs beside it writes tangents and the generated_tangents flag.
    tbb::task_group topology;
    topology.run([&] { add_topology_report(mesh, welded, *report); });
    if (!mesh.has_tangents()) {
        generate_tangents(mesh);
        report->generated_tangents = true;
    }
    if (options.with_frames) options.with_frames(mesh, welded);
    topology.wait();
    return report;
}

}  // namespace specbake
