// weld_by_position: the topology curvature is measured on. Vertices at the same position are one
// topological vertex; among them, vertices whose normals also agree (split only by UV seams or other
// attributes) form one curvature group and share one curvature; different normals (hard edges) keep
// separate groups, each seeing only the triangles on its own side (SPEC Sec. 4).
#pragma once

#include <cstdint>
#include <vector>

#include "core/trimesh.h"

namespace specbake {

struct WeldedTopology {
    std::vector<uint32_t> position_id;  // per vertex: index of its topological vertex (bitwise-equal position)
    std::vector<uint32_t> group_id;     // per vertex: index of its curvature group (same position and normal)
    std::vector<uint32_t> group_vertex; // per group: its first vertex, whose normal represents the group
    uint32_t position_count = 0;
    uint32_t group_count = 0;
};

struct WeldOptions {
    // Normals at one position within this angle (degrees) share curvature. Authored seams duplicate the
    // normal exactly; hard edges differ by far more.
    float normal_angle_degrees = 1.0f;
    // false: one group per position whatever the normals (the topology alone, as validation needs it).
    bool split_by_normals = true;
};

// Positions are compared exactly (after mapping -0 to +0): exporters duplicate seam vertices bit for bit.
// Ids are numbered in order of first occurrence, so the result is deterministic. Without normals every
// vertex of a position is in one group. Linear time (hashing), parallel over hash buckets, the same ids for
// any thread count.
WeldedTopology weld_by_position(const TriMesh& mesh, const WeldOptions& options = {});

}  // namespace specbake
