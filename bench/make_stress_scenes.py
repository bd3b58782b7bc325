#!/usr/bin/env python3
"""Writes a corpus of glTF scenes whose materials have the statistics real assets have and the analytic
scenes lack, for `specbake verify` / `bench --scenes` (docs/accuracy.md#the-stress-corpus): a sphere and a
torus side by side per scene, each scene one material kind:

  noise-orm      fBm height bumps in the normal map, an ORM texture with noisy roughness (scanned metal)
  scratches      sparse thin grooves on a flat, glossy field (mixed texels: flat and steep in one texel)
  tiles          square tiles with flat tops and steep bevels (hard-surface trim sheets)
  hammered       dense dimples (cell-distance domes), glossy (hammered metal)
  brushed        fine grooves along one axis (brushed metal: all the variance in one slope)
  rough-stripes  no normal map; a roughness texture of sharp glossy/rough stripes (roughness-map handling)

Standard library only; deterministic (fixed seeds). Each scene is a folder <name>/<name>.gltf."""
import argparse
import json
import math
import os
import random
import struct
import zlib


def png_rgb8(path, size, pixels):
    """pixels: flat list of (r, g, b) floats in [0, 1], row-major."""
    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    raw = bytearray()
    for y in range(size):
        raw.append(0)
        for r, g, b in pixels[y * size:(y + 1) * size]:
            raw += bytes((round(min(1.0, max(0.0, r)) * 255), round(min(1.0, max(0.0, g)) * 255),
                          round(min(1.0, max(0.0, b)) * 255)))
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", size, size, 8, 2, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(bytes(raw), 9)))
        f.write(chunk(b"IEND", b""))


def value_noise(size, cells, rng):
    """Tileable smooth value noise with `cells` lattice cells per side, values in [-1, 1]."""
    lattice = [[rng.uniform(-1, 1) for _ in range(cells)] for _ in range(cells)]
    out = [0.0] * (size * size)
    for y in range(size):
        fy = y / size * cells
        y0 = int(fy)
        ty = fy - y0
        ty = ty * ty * (3 - 2 * ty)
        for x in range(size):
            fx = x / size * cells
            x0 = int(fx)
            tx = fx - x0
            tx = tx * tx * (3 - 2 * tx)
            a = lattice[y0 % cells][x0 % cells]
            b = lattice[y0 % cells][(x0 + 1) % cells]
            c = lattice[(y0 + 1) % cells][x0 % cells]
            d = lattice[(y0 + 1) % cells][(x0 + 1) % cells]
            out[y * size + x] = (a + (b - a) * tx) * (1 - ty) + (c + (d - c) * tx) * ty
    return out


def fbm(size, base_cells, octaves, rng, gain=0.5):
    out = [0.0] * (size * size)
    amplitude, cells = 1.0, base_cells
    for _ in range(octaves):
        n = value_noise(size, min(cells, size), rng)
        for i in range(len(out)):
            out[i] += amplitude * n[i]
        amplitude *= gain
        cells *= 2
    return out


def normals_from_height(size, height, scale):
    """Tangent-space normals of a periodic height field (units of texels times `scale`), encoded (n + 1) / 2."""
    px = []
    for y in range(size):
        for x in range(size):
            dx = (height[y * size + (x + 1) % size] - height[y * size + (x - 1) % size]) * 0.5 * scale
            dy = (height[((y + 1) % size) * size + x] - height[((y - 1) % size) * size + x]) * 0.5 * scale
            # glTF: +Y of the normal map points along +v's opposite (OpenGL convention, green up).
            n = (-dx, dy, 1.0)
            inv = 1.0 / math.sqrt(n[0] * n[0] + n[1] * n[1] + 1.0)
            px.append((n[0] * inv * 0.5 + 0.5, n[1] * inv * 0.5 + 0.5, inv * 0.5 + 0.5))
    return px


def scratches_height(size, rng):
    h = [0.0] * (size * size)
    for _ in range(60):
        x0, y0 = rng.uniform(0, size), rng.uniform(0, size)
        angle = rng.uniform(0, math.pi)
        length = rng.uniform(0.1, 0.5) * size
        depth = rng.uniform(0.5, 1.5)
        dx, dy = math.cos(angle), math.sin(angle)
        steps = int(length * 2)
        for s in range(steps):
            cx, cy = x0 + dx * s * 0.5, y0 + dy * s * 0.5
            for oy in (-1, 0, 1):
                for ox in (-1, 0, 1):
                    ix, iy = int(cx) + ox, int(cy) + oy
                    r2 = (ix + 0.5 - cx) ** 2 + (iy + 0.5 - cy) ** 2
                    w = math.exp(-r2 / 0.5)
                    i = (iy % size) * size + ix % size
                    h[i] = min(h[i], -depth * w)
    return h


def tiles_height(size, tiles, bevel):
    h = []
    period = size / tiles
    for y in range(size):
        for x in range(size):
            fx = (x + 0.5) % period / period
            fy = (y + 0.5) % period / period
            edge = min(fx, 1 - fx, fy, 1 - fy)  # distance to the tile's border, in tiles
            h.append(min(edge / bevel, 1.0) * period * bevel * 1.5)
    return h


def dimples_height(size, cells, rng):
    points = [(rng.uniform(0, size), rng.uniform(0, size)) for _ in range(cells * cells)]
    grid = {}
    cell = size / cells
    for px, py in points:
        grid.setdefault((int(px / cell), int(py / cell)), []).append((px, py))
    h = []
    for y in range(size):
        for x in range(size):
            best = 1e9
            gx, gy = int(x / cell), int(y / cell)
            for oy in (-1, 0, 1):
                for ox in (-1, 0, 1):
                    for px, py in grid.get(((gx + ox) % cells, (gy + oy) % cells), []):
                        ddx = (x + 0.5 - px + size / 2) % size - size / 2
                        ddy = (y + 0.5 - py + size / 2) % size - size / 2
                        best = min(best, ddx * ddx + ddy * ddy)
            r = math.sqrt(best) / cell
            h.append(-math.sqrt(max(0.0, 1.0 - min(r, 1.0) ** 2)) * cell * 0.6)
    return h


def brushed_height(size, rng):
    # Independent fine noise per row, smooth along u: grooves along u, the slope almost all along v.
    rows = [rng.uniform(-1, 1) for _ in range(size)]
    smooth = [(rows[(y - 1) % size] + 2 * rows[y] + rows[(y + 1) % size]) * 0.25 for y in range(size)]
    long = value_noise(size, 8, rng)
    return [smooth[y] * (1.0 + 0.3 * long[y * size + x]) for y in range(size) for x in range(size)]


def grid_mesh(rings, segments, surface):
    """Triangles of a (rings + 1) x (segments + 1) vertex grid; surface(u, v) gives (position, normal, uv)."""
    pos, nrm, uv, idx = [], [], [], []
    for r in range(rings + 1):
        for s in range(segments + 1):
            p, n, t = surface(s / segments, r / rings)
            pos += p
            nrm += n
            uv += t
    for r in range(rings):
        for s in range(segments):
            a = r * (segments + 1) + s
            b, c = a + 1, a + segments + 1
            idx += (a, c, b, b, c, c + 1)
    return pos, nrm, uv, idx


def sphere(rings, segments, radius):
    def surface(u, v):
        theta, phi = v * math.pi, u * 2 * math.pi
        n = (math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi))
        return [radius * c for c in n], n, (2 * u, v)  # 2:1 so texels are about square on the sphere

    return grid_mesh(rings, segments, surface)


def torus(rings, segments, major, minor):
    def surface(u, v):
        phi, theta = u * 2 * math.pi, v * 2 * math.pi
        n = (math.cos(theta) * math.cos(phi), math.sin(theta), -math.cos(theta) * math.sin(phi))
        c = (major * math.cos(phi), 0.0, -major * math.sin(phi))
        return [c[i] + minor * n[i] for i in range(3)], n, (3 * u, v)

    return grid_mesh(rings, segments, surface)


SCENES = {
    # name: (normal-map maker or None, roughness factor, ORM maker or None)
    "noise-orm": ("noise", 1.0, "noise"),
    "scratches": ("scratches", math.sqrt(0.03), None),
    "tiles": ("tiles", math.sqrt(0.12), None),
    "hammered": ("dimples", math.sqrt(0.02), None),
    "brushed": ("brushed", math.sqrt(0.06), None),
    "rough-stripes": (None, 1.0, "stripes"),
}


def write_scene(folder, name, size):
    normal_kind, roughness, orm_kind = SCENES[name]
    rng = random.Random(sum(map(ord, name)))
    os.makedirs(os.path.join(folder, name), exist_ok=True)
    images, material = [], {"name": name, "pbrMetallicRoughness": {"metallicFactor": 1.0, "roughnessFactor": roughness}}
    if normal_kind:
        if normal_kind == "noise":
            height, scale = fbm(size, 8, 6, rng), 6.0
        elif normal_kind == "scratches":
            height, scale = scratches_height(size, rng), 1.0
        elif normal_kind == "tiles":
            height, scale = tiles_height(size, 16, 0.08), 1.0
        elif normal_kind == "dimples":
            height, scale = dimples_height(size, 24, rng), 1.0
        else:
            height, scale = brushed_height(size, rng), 0.5
        png_rgb8(os.path.join(folder, name, "normal.png"), size, normals_from_height(size, height, scale))
        material["normalTexture"] = {"index": len(images)}
        images.append("normal.png")
    if orm_kind:
        if orm_kind == "noise":
            n = fbm(size, 4, 5, rng)
            rough = [0.25 + 0.25 * (v + 1.0) for v in n]  # perceptual roughness 0.25 .. 0.75
        else:
            rough = [0.12 if (x // (size // 32)) % 2 == 0 else 0.8 for _ in range(size) for x in range(size)]
        png_rgb8(os.path.join(folder, name, "orm.png"), size, [(1.0, r, 1.0) for r in rough])
        material["pbrMetallicRoughness"]["metallicRoughnessTexture"] = {"index": len(images)}
        images.append("orm.png")
    meshes = [sphere(96, 192, 1.0), torus(64, 192, 0.8, 0.35)]
    blobs, accessors, primitives = [], [], []
    for pos, nrm, uv, idx in meshes:
        count = len(pos) // 3
        base = len(blobs)
        lo = [min(pos[i::3]) for i in range(3)]
        hi = [max(pos[i::3]) for i in range(3)]
        blobs += [struct.pack("<%df" % len(pos), *pos), struct.pack("<%df" % len(nrm), *nrm),
                  struct.pack("<%df" % len(uv), *uv), struct.pack("<%dI" % len(idx), *idx)]
        accessors += [
            {"bufferView": base, "componentType": 5126, "count": count, "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": base + 1, "componentType": 5126, "count": count, "type": "VEC3"},
            {"bufferView": base + 2, "componentType": 5126, "count": count, "type": "VEC2"},
            {"bufferView": base + 3, "componentType": 5125, "count": len(idx), "type": "SCALAR"},
        ]
        primitives.append({"attributes": {"POSITION": base, "NORMAL": base + 1, "TEXCOORD_0": base + 2},
                           "indices": base + 3, "material": 0})
    views, offset = [], 0
    for b in blobs:
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(b)})
        offset += len(b)
    gltf = {
        "asset": {"version": "2.0", "generator": "specbake bench/make_stress_scenes.py"},
        "buffers": [{"uri": name + ".bin", "byteLength": offset}],
        "bufferViews": views,
        "accessors": accessors,
        "materials": [material],
        "meshes": [{"name": "sphere", "primitives": [primitives[0]]}, {"name": "torus", "primitives": [primitives[1]]}],
        "nodes": [{"mesh": 0, "translation": [-1.2, 0, 0]},
                  {"mesh": 1, "translation": [1.25, 0, 0], "rotation": [0.3826834, 0, 0, 0.9238795]}],
        "scenes": [{"nodes": [0, 1]}],
        "scene": 0,
    }
    if images:
        gltf["images"] = [{"uri": u} for u in images]
        gltf["textures"] = [{"source": i} for i in range(len(images))]
    with open(os.path.join(folder, name, name + ".bin"), "wb") as f:
        for b in blobs:
            f.write(b)
    with open(os.path.join(folder, name, name + ".gltf"), "w") as f:
        json.dump(gltf, f, indent=1)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-o", "--output", required=True, help="folder for the scene folders")
    ap.add_argument("--size", type=int, default=512, help="texture size (default 512)")
    ap.add_argument("--only", default="", help="comma-separated scene names (default: all)")
    args = ap.parse_args()
    names = [n for n in args.only.split(",") if n] or list(SCENES)
    for name in names:
        if name not in SCENES:
            ap.error("unknown scene '%s' (known: %s)" % (name, ", ".join(SCENES)))
        write_scene(args.output, name, args.size)
        print(os.path.join(args.output, name, name + ".gltf"))


if __name__ == "__main__":
    main()
