// Procedural test and benchmark shapes with analytic normals and tangents (glTF conventions: tangent
// along increasing u, w chosen so cross(N, T) * w points along decreasing v). Parametric shapes are UV grids
// with a seam (duplicated column at u = 0/1); `jitter` in [0, 0.45] moves interior grid points by up to that
// fraction of a cell in parameter space (then back onto the surface), giving irregular triangulations;
// `seed` makes the jitter reproducible. All lengths in object units.
#pragma once

#include <cstdint>

#include "core/trimesh.h"

namespace specbake {

// Sphere of radius r centred at the origin: `segments` around, `rings` pole to pole, seam at u = 0,
// one pole vertex per segment (as UV-sphere exporters do).
TriMesh make_uv_sphere(float radius, int segments, int rings, float jitter = 0.0f, uint32_t seed = 1);

// Icosahedron subdivided `subdivisions` times, projected onto the sphere; no UVs-based seams, tangents from
// the longitude direction (w = +1), with a fixed fallback at the poles.
TriMesh make_icosphere(float radius, int subdivisions);

// Open cylinder around +Z of radius r and given height (centred at z = 0), `segments` around, `rows` along.
TriMesh make_cylinder(float radius, float height, int segments, int rows, float jitter = 0.0f, uint32_t seed = 1);

// Torus around +Z: major radius R (centre of tube), minor radius r; `segments` around Z, `sides` around the tube.
TriMesh make_torus(float major_radius, float minor_radius, int segments, int sides, float jitter = 0.0f,
                   uint32_t seed = 1);

// Ellipsoid x^2/a^2 + y^2/b^2 + z^2/c^2 = 1 with exact (normalised gradient) normals, UV-sphere layout.
TriMesh make_ellipsoid(float a, float b, float c, int segments, int rings, float jitter = 0.0f, uint32_t seed = 1);

// Axis-aligned cube of half-size h with 24 vertices (4 per face, split normals: hard edges), flat normals.
TriMesh make_flat_cube(float half_size);

// Regular grid on z = 0 of n x n quads (each split on one diagonal), size x size, normals +Z: the flat case.
TriMesh make_plane(float size, int n);

// Scales all positions by s (normals and tangents unchanged for s > 0).
void scale_mesh(TriMesh& mesh, float s);

}  // namespace specbake
