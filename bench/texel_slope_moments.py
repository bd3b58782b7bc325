#!/usr/bin/env python3
"""Shape of a normal map's slope distribution per texel of its box-filtered mips (docs/accuracy.md,
"A fourth moment per texel would not say which shape").

For each level L (2^L x 2^L base texels per texel) and each texel whose rough share g (the share of base
normals with slope |n.xy| / n.z above 0.02, the bake's kFlatSlope) is above 0.05, prints percentiles of the
ratio E|d|^4 / (E|d|^2)^2 of the slopes d about the texel's mean: 2 for a Gaussian, 4/3 for a uniform disc,
1 for a ring; over the rough share it is g times the ratio over the whole texel (the flat share at d ~ 0).

Usage: python3 bench/texel_slope_moments.py NORMAL_MAP.png [LEVEL ...]   (needs numpy and Pillow)
"""
import sys

import numpy as np
from PIL import Image

FLAT_SLOPE = 0.02


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    Image.MAX_IMAGE_PIXELS = None
    texels = np.asarray(Image.open(sys.argv[1]).convert("RGB")).astype(np.float64)
    levels = [int(a) for a in sys.argv[2:]] or [2, 3, 4, 5, 6]
    n = texels / 255.0 * 2.0 - 1.0  # glTF decode of the stored channels, blue kept
    n /= np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-12)
    z = np.maximum(n[..., 2], 1e-6)
    sx, sy = n[..., 0] / z, n[..., 1] / z
    q = sx * sx + sy * sy
    rough = (np.sqrt(q) > FLAT_SLOPE).astype(np.float64)
    print(f"{sys.argv[1]}: {texels.shape[1]}x{texels.shape[0]}")
    for level in levels:
        b = 1 << level
        h, w = sx.shape[0] // b, sx.shape[1] // b
        if h == 0 or w == 0:
            continue

        def box(x):
            return x[: h * b, : w * b].reshape(h, b, w, b).mean(axis=(1, 3))

        mx, my = box(sx), box(sy)
        exx, eyy, exy = box(sx * sx), box(sy * sy), box(sx * sy)
        eq2, eqx, eqy = box(q * q), box(q * sx), box(q * sy)
        m2 = mx * mx + my * my
        var = exx + eyy - m2  # E|d|^2
        # E|d|^4 about the mean from the raw moments: E|s|^4 - 4 E[|s|^2 s].m + 2 E|s|^2 |m|^2
        # + 4 m^T E[s s^T] m - 3 |m|^4.
        fourth = eq2 - 4 * (eqx * mx + eqy * my) + 2 * (exx + eyy) * m2 \
            + 4 * (mx * mx * exx + 2 * mx * my * exy + my * my * eyy) - 3 * m2 * m2
        g = box(rough)
        sel = (g > 0.05) & (var > 1e-3)
        if not sel.any():
            print(f"  level {level}: no texel with a rough share")
            continue
        ratio = fourth[sel] / var[sel] ** 2
        pct = lambda v: " ".join(f"{x:.2f}" for x in np.percentile(v, [10, 25, 50, 75, 90]))
        print(f"  level {level}: {sel.sum()} texels; whole texel p10-p90 {pct(ratio)}; rough share {pct(ratio * g[sel])}")


if __name__ == "__main__":
    main()
