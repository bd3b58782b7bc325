// TriMesh: one indexed triangle primitive as plain arrays, the currency between io/ (import, glTF) and
// mesh/ (analysis). Units are object space as authored; nothing here is transformed.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace specbake {

struct TriMesh {
    std::string name;                // for messages: "<file>: mesh 'Sphere' primitive 0"
    std::vector<float> positions;    // xyz per vertex
    std::vector<float> normals;      // xyz per vertex (shading normals as authored); empty when absent
    std::vector<float> tangents;     // xyzw per vertex, w = handedness (glTF TANGENT); empty when absent
    std::vector<float> uv0;          // uv per vertex (TEXCOORD_0); empty when absent
    std::vector<uint32_t> indices;   // 3 per triangle
    int material = -1;               // index into the source scene's materials, -1 when none

    size_t vertex_count() const { return positions.size() / 3; }
    size_t triangle_count() const { return indices.size() / 3; }
    bool has_normals() const { return !normals.empty() && normals.size() == positions.size(); }
    bool has_tangents() const { return !tangents.empty() && tangents.size() / 4 == vertex_count(); }
    bool has_uv0() const { return !uv0.empty() && uv0.size() / 2 == vertex_count(); }
};

// Per-vertex curvature attribute _SPECAA_CURVATURE (SPEC Sec. 4): (k1, k2, d.x, d.y) per vertex,
// k in 1/object-space length, |k1| >= |k2|, d the unit k1 direction in the vertex tangent frame.
struct VertexCurvature {
    std::vector<float> values;  // 4 per vertex
};

}  // namespace specbake
