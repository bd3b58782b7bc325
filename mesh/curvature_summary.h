// summarize_curvature: the few numbers the bake plan decides on (SPEC Sec. 6, "curvature only where the
// shading normals actually curve"), dimensionless so one threshold fits every asset scale.
#pragma once

#include "core/trimesh.h"

namespace specbake {

struct CurvatureSummary {
    float max_abs_k1 = 0.0f;       // 1/object length
    float p95_abs_k1 = 0.0f;       // 95th percentile of |k1| over referenced vertices
    float bbox_diagonal = 0.0f;    // object length
    // p95_abs_k1 * bbox_diagonal: 2 sqrt(3) for a sphere, 0 for flat or hard-edged faceted meshes.
    float relative_p95() const { return p95_abs_k1 * bbox_diagonal; }
};

CurvatureSummary summarize_curvature(const TriMesh& mesh, const VertexCurvature& curvature);

}  // namespace specbake
