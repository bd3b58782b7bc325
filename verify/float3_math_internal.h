// The few 3-vector operations the simulator's scenes, scene files and renderer need (single precision, as
// the GL uniforms they end in).
#pragma once

#include "verify/scene.h"

#include <cmath>

namespace specbake::verify {

inline Float3 sub(Float3 a, Float3 b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline float dot3(Float3 a, Float3 b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Float3 cross3(Float3 a, Float3 b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

// v / |v|. A zero vector has no direction; it gives +z, so a degenerate node transform, light direction or
// camera (target on the eye, up along the view) yields finite uniforms instead of NaN ones.
inline Float3 unit(Float3 v) {
    const float l = std::sqrt(dot3(v, v));
    return l > 0 ? Float3{v[0] / l, v[1] / l, v[2] / l} : Float3{0, 0, 1};
}

}  // namespace specbake::verify
