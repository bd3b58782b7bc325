// Procedural texture maps for the scene tests: small normal and ORM maps whose values a test can compute
// on its own.
#pragma once

#include "core/image.h"

#include <cmath>

namespace specbake::testing {

// A size x size tangent-space normal map of the height field with slopes (ax sin(2 pi x / 8),
// ay cos(2 pi y / 16)): n = normalize(-sx, -sy, 1), stored as (n + 1) / 2.
inline Image sine_normal_map(int size, double ax, double ay) {
    Image img(size, size, 3);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const double sx = ax * std::sin(2 * M_PI * x / 8.0), sy = ay * std::cos(2 * M_PI * y / 16.0);
            const double len = std::sqrt(sx * sx + sy * sy + 1.0);
            float* t = img.texel(x, y);
            t[0] = float(0.5 * (-sx / len + 1.0));
            t[1] = float(0.5 * (-sy / len + 1.0));
            t[2] = float(0.5 * (1.0 / len + 1.0));
        }
    return img;
}

}  // namespace specbake::testing
