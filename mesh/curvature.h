// estimate_curvature: the per-vertex attribute _SPECAA_CURVATURE (SPEC Sec. 4): principal curvatures
// (k1, k2) of the shading-normal field with |k1| >= |k2|, in 1/object-space length, positive where the
// surface bends away from its normal (sphere of radius R with outward normals: +1/R), and d, the unit k1
// direction in the vertex tangent frame (T = tangent.xyz, B = cross(N, T) * tangent.w).
#pragma once

#include <optional>
#include <string_view>

#include "core/result.h"
#include "core/trimesh.h"
#include "mesh/weld_by_position.h"

namespace specbake {

enum class CurvatureEstimator {
    ShapeOperator,  // SPEC Sec. 4: per-face least-squares shape operator from the normal differences
                    // along the face's edges, mixed-Voronoi weighted at the vertices (Rusinkiewicz 2004)
    JetFitting,     // CGAL Monge jet fitting of welded positions: geometric curvature, oriented by the normals
    NormalCone,     // one-ring bound: largest normal turn per edge length, cheapest
    SecondOrder,    // one least-squares fit per vertex over its one-ring with Rusinkiewicz 2004's
                    // curvature-derivative term: second order on irregular meshes
    Patch,          // the per-face operators of ShapeOperator, averaged at a vertex over its smooth patch:
                    // faces steeper than the one-ring's area-weighted median weigh by (median / |S_f|)^2
};

// What `bake`, `plan`, `mesh` and `verify` use unless told otherwise: the curvature the default run-time rule
// reads (docs/accuracy.md#the-default-rule-and-the-curvature-it-reads).
inline constexpr CurvatureEstimator kDefaultCurvatureEstimator = CurvatureEstimator::Patch;

struct CurvatureOptions {
    WeldOptions weld;
    int max_threads = 0;       // 0: all available; the output is identical for any thread count
    int jet_degree = 3;        // JetFitting: degree of the fitted polynomial (2..4); 3 measured best
    int jet_min_points = 16;   // JetFitting: grow the k-ring around a vertex until it holds this many positions
};

// Requires normals and tangents (mesh/prepare_mesh.h provides both); fails naming mesh.name otherwise or
// when validate_mesh would reject the mesh. Degenerate triangles are skipped; vertices with no usable
// triangle (and JetFitting vertices with too few neighbours) get (0, 0, 1, 0).
Result<VertexCurvature> estimate_curvature(const TriMesh& mesh, CurvatureEstimator estimator,
                                           const CurvatureOptions& options = {});

// The same with the welding done by the caller: `topology` must be weld_by_position(mesh, options.weld) of
// this mesh as it is now, so a caller that needs the welded positions for other analyses (the topology
// report) welds once.
Result<VertexCurvature> estimate_curvature(const TriMesh& mesh, const WeldedTopology& topology,
                                           CurvatureEstimator estimator, const CurvatureOptions& options = {});

// "shape-operator", "jet-fitting", "normal-cone", "second-order", "patch" (the CLI spellings).
std::string_view to_string(CurvatureEstimator estimator);
std::optional<CurvatureEstimator> parse_curvature_estimator(std::string_view name);

// The four estimators behind estimate_curvature, one file each; inputs already checked and welded.
VertexCurvature curvature_shape_operator(const TriMesh& mesh, const WeldedTopology& topology);
VertexCurvature curvature_jet_fitting(const TriMesh& mesh, const WeldedTopology& topology, int degree,
                                      int min_points);
VertexCurvature curvature_normal_cone(const TriMesh& mesh, const WeldedTopology& topology);
VertexCurvature curvature_second_order(const TriMesh& mesh, const WeldedTopology& topology);
VertexCurvature curvature_patch(const TriMesh& mesh, const WeldedTopology& topology);

}  // namespace specbake
