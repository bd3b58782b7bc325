// Small non-manifold meshes shared by the topology and preparation tests.
#pragma once

#include "core/trimesh.h"

#include <cmath>
#include <cstdint>
#include <numbers>

namespace specbake::test {

// Two closed cones of six triangles each, sharing only their apex (vertex 0): a non-manifold vertex with
// two fans and no boundary.
inline TriMesh hourglass_mesh() {
    TriMesh hourglass;
    hourglass.positions = {0, 0, 0};
    for (int cone = 0; cone < 2; ++cone)
        for (int i = 0; i < 6; ++i) {
            const double a = i * std::numbers::pi / 3.0;
            hourglass.positions.insert(hourglass.positions.end(),
                                       {float(std::cos(a)), float(std::sin(a)), cone ? 1.0f : -1.0f});
        }
    for (uint32_t cone = 0; cone < 2; ++cone)
        for (uint32_t i = 0; i < 6; ++i)
            hourglass.indices.insert(hourglass.indices.end(), {0, 1 + 6 * cone + i, 1 + 6 * cone + (i + 1) % 6});
    return hourglass;
}

}  // namespace specbake::test
