#!/usr/bin/env python3
# Writes a glTF scene that asks for glints, for `specbake verify` / `bench` / `bake` (docs/glints.md#accuracy): two
# UV spheres side by side under a directional light, the left one glittery ("SPECBAKE_glints": {}) with an
# anisotropic, rotated ridge normal map, the right one plain with the same roughness. Standard library only.
import argparse
import json
import math
import os
import struct
import zlib

from make_stress_scenes import grid_mesh


def png_rgb8(path, width, height, rows):
    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    raw = b"".join(b"\x00" + bytes(row) for row in rows)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw, 9)))
        f.write(chunk(b"IEND", b""))


def ridge_rows(size):
    # Slope 0.3 cos(2 pi k.uv) along k / |k|, k = (35, 20): ridges 29.7 degrees off the u axis (tiles).
    kx, ky = 35.0, 20.0
    k = math.hypot(kx, ky)
    rows = []
    for y in range(size):
        row = []
        for x in range(size):
            u, v = (x + 0.5) / size, (y + 0.5) / size
            a = 0.3 * math.cos(2 * math.pi * (kx * u + ky * v))
            n = (-a * kx / k, -a * ky / k, 1.0)
            length = math.sqrt(sum(c * c for c in n))
            row += [round((c / length * 0.5 + 0.5) * 255) for c in n]
        rows.append(row)
    return rows


def sphere(rings, segments):
    def surface(u, v):
        theta, phi = v * math.pi, u * 2 * math.pi
        n = (math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi))
        return n, n, (u, v)

    return grid_mesh(rings, segments, surface)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("-o", "--output", required=True, help="folder for glitter.gltf, glitter.bin, ridges.png")
    args = ap.parse_args()
    os.makedirs(args.output, exist_ok=True)
    png_rgb8(os.path.join(args.output, "ridges.png"), 256, 256, ridge_rows(256))
    pos, nrm, uv, idx = sphere(96, 192)
    blobs = [struct.pack("<%df" % len(pos), *pos), struct.pack("<%df" % len(nrm), *nrm),
             struct.pack("<%df" % len(uv), *uv), struct.pack("<%dI" % len(idx), *idx)]
    views, offset = [], 0
    for b in blobs:
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(b)})
        offset += len(b)
    count = len(pos) // 3
    accessors = [
        {"bufferView": 0, "componentType": 5126, "count": count, "type": "VEC3", "min": [-1, -1, -1], "max": [1, 1, 1]},
        {"bufferView": 1, "componentType": 5126, "count": count, "type": "VEC3"},
        {"bufferView": 2, "componentType": 5126, "count": count, "type": "VEC2"},
        {"bufferView": 3, "componentType": 5125, "count": len(idx), "type": "SCALAR"},
    ]
    attributes = {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}
    roughness = math.sqrt(0.1)  # alpha 0.1: Beckmann sigma 0.071, in C21's glossy range
    light = {"rotation": [-0.3535534, -0.1464466, 0.0, 0.9238795]}  # from the upper left and front
    gltf = {
        "asset": {"version": "2.0", "generator": "specbake bench/make_glint_scene.py"},
        "extensionsUsed": ["SPECBAKE_glints", "KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "directional", "intensity": 1.0}]}},
        "buffers": [{"uri": "glitter.bin", "byteLength": offset}],
        "bufferViews": views,
        "accessors": accessors,
        "images": [{"uri": "ridges.png"}],
        "textures": [{"source": 0}],
        "materials": [
            {"name": "Glitter", "normalTexture": {"index": 0},
             "pbrMetallicRoughness": {"roughnessFactor": roughness, "metallicFactor": 1.0},
             "extensions": {"SPECBAKE_glints": {}}},
            {"name": "Plain", "pbrMetallicRoughness": {"roughnessFactor": roughness, "metallicFactor": 1.0}},
        ],
        "meshes": [{"name": "glitter", "primitives": [{"attributes": attributes, "indices": 3, "material": 0}]},
                   {"name": "plain", "primitives": [{"attributes": attributes, "indices": 3, "material": 1}]}],
        "nodes": [{"mesh": 0, "translation": [-1.15, 0, 0]}, {"mesh": 1, "translation": [1.15, 0, 0]},
                  dict(light, extensions={"KHR_lights_punctual": {"light": 0}})],
        "scenes": [{"nodes": [0, 1, 2]}],
        "scene": 0,
    }
    with open(os.path.join(args.output, "glitter.bin"), "wb") as f:
        for b in blobs:
            f.write(b)
    with open(os.path.join(args.output, "glitter.gltf"), "w") as f:
        json.dump(gltf, f, indent=1)


if __name__ == "__main__":
    main()
