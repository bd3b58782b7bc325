#!/usr/bin/env python3
# Writes a generated asset library for the studio-scale benchmark (bench/studio_scale.py): small normal + ORM
# map pairs, each on a one-quad glTF "material card", small glTF scenes (ellipsoids), and one large card of
# the same total texels as all the small maps. Standard library only; deterministic for given arguments.
"""Writes the generated asset library of the studio-scale benchmark."""
import argparse
import json
import math
import os
import struct
import zlib


def png_bytes(width, height, rows):
    """RGB8 PNG from a list of `height` row byte strings of 3 * width bytes."""
    raw = b"".join(b"\x00" + r for r in rows)

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw, 1)) + chunk(b"IEND", b""))


def write(path, data):
    with open(path, "wb") as f:
        f.write(data)


def bump_tile(size, period, amp):
    """Rows of an RGB8 normal map of sine bumps (height amp * sin(kx) sin(ky)), +Y green."""
    k = 2.0 * math.pi / period
    rows = []
    for y in range(size):
        row = bytearray()
        for x in range(size):
            u, v = x + 0.5, y + 0.5
            gx = amp * k * math.cos(k * u) * math.sin(k * v)
            gy = amp * k * math.sin(k * u) * math.cos(k * v)
            n = math.sqrt(gx * gx + gy * gy + 1.0)
            row += bytes((round(255 * (0.5 - 0.5 * gx / n)), round(255 * (0.5 - 0.5 * gy / n)),
                          round(255 * (0.5 + 0.5 / n))))
        rows.append(bytes(row))
    return rows


def orm_tile(size, roughness_lo, roughness_hi):
    """Rows of an ORM map: occlusion gradient, roughness ramp along y, metallic stripes."""
    rows = []
    for y in range(size):
        r = roughness_lo + (roughness_hi - roughness_lo) * y / max(1, size - 1)
        row = bytearray()
        for x in range(size):
            row += bytes((round(255 * (1.0 - 0.3 * y / size)), round(255 * r), 255 if (x // 16) % 2 == 0 else 0))
        rows.append(bytes(row))
    return rows


def rolled(rows, dx, dy):
    """The tile shifted by (dx, dy) texels, wrapping: a different map with the same statistics."""
    n = len(rows)
    out = rows[dy % n:] + rows[:dy % n]
    s = 3 * (dx % (len(rows[0]) // 3))
    return [r[s:] + r[:s] for r in out]


def quad_buffer():
    """A unit quad: positions, normals, texcoords (float32), indices (uint16), in that order."""
    pos = [0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0]
    nrm = [0, 0, 1] * 4
    uv = [0, 1, 1, 1, 1, 0, 0, 0]
    idx = [0, 1, 2, 0, 2, 3]
    data = struct.pack("<12f", *pos) + struct.pack("<12f", *nrm) + struct.pack("<8f", *uv) + struct.pack("<6H", *idx)
    return data + b"\x00" * (-len(data) % 4)


def card_gltf(name, normal_uri, orm_uri, buffer_uri, buffer_len):
    return {
        "asset": {"version": "2.0", "generator": "specbake bench/make_library.py"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": name}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3,
                                    "material": 0}]}],
        "materials": [{"name": name, "normalTexture": {"index": 0},
                       "pbrMetallicRoughness": {"metallicRoughnessTexture": {"index": 1}, "roughnessFactor": 1.0}}],
        "textures": [{"source": 0}, {"source": 1}],
        "images": [{"uri": normal_uri}, {"uri": orm_uri}],
        "buffers": [{"uri": buffer_uri, "byteLength": buffer_len}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48, "target": 34962},
                        {"buffer": 0, "byteOffset": 48, "byteLength": 48, "target": 34962},
                        {"buffer": 0, "byteOffset": 96, "byteLength": 32, "target": 34962},
                        {"buffer": 0, "byteOffset": 128, "byteLength": 12, "target": 34963}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0],
                       "max": [1, 1, 0]},
                      {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
                      {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
                      {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"}],
    }


def ellipsoid_glb(name, rings, segments, radii, roughness):
    """A UV ellipsoid with analytic normals, as a self-contained GLB."""
    a, b, c = radii
    pos, nrm, uv, idx = [], [], [], []
    for i in range(rings + 1):
        th = math.pi * i / rings
        for j in range(segments + 1):
            ph = 2 * math.pi * j / segments
            x, y, z = math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph)
            pos += [a * x, b * y, c * z]
            nx, ny, nz = x / a, y / b, z / c
            n = math.sqrt(nx * nx + ny * ny + nz * nz)
            nrm += [nx / n, ny / n, nz / n]
            uv += [j / segments, i / rings]
    for i in range(rings):
        for j in range(segments):
            p, q = i * (segments + 1) + j, (i + 1) * (segments + 1) + j
            if i > 0:
                idx += [p, p + 1, q]
            if i < rings - 1:
                idx += [p + 1, q + 1, q]
    count = len(pos) // 3
    blobs = [struct.pack("<%df" % len(pos), *pos), struct.pack("<%df" % len(nrm), *nrm),
             struct.pack("<%df" % len(uv), *uv), struct.pack("<%dI" % len(idx), *idx)]
    views, offset, data = [], 0, b""
    for k, blob in enumerate(blobs):
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(blob),
                      "target": 34963 if k == 3 else 34962})
        data += blob
        offset += len(blob)
    gltf = {
        "asset": {"version": "2.0", "generator": "specbake bench/make_library.py"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": name}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3,
                                    "material": 0}]}],
        "materials": [{"name": name, "pbrMetallicRoughness": {"metallicFactor": 1.0, "roughnessFactor": roughness}}],
        "buffers": [{"byteLength": len(data)}],
        "bufferViews": views,
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": count, "type": "VEC3",
                       "min": [-a, -b, -c], "max": [a, b, c]},
                      {"bufferView": 1, "componentType": 5126, "count": count, "type": "VEC3"},
                      {"bufferView": 2, "componentType": 5126, "count": count, "type": "VEC2"},
                      {"bufferView": 3, "componentType": 5125, "count": len(idx), "type": "SCALAR"}],
    }
    js = json.dumps(gltf, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    data += b"\x00" * (-len(data) % 4)
    body = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(data), 0x004E4942) + data
    return struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("-o", "--output", required=True, help="library folder (created)")
    ap.add_argument("--maps", type=int, default=1000, help="normal + ORM pairs (default 1000)")
    ap.add_argument("--map-size", type=int, default=128, help="width = height of each map (default 128)")
    ap.add_argument("--scenes", type=int, default=200, help="glTF scenes (default 200)")
    ap.add_argument("--quick", action="store_true", help="40 maps of 64x64 and 10 scenes (for CI)")
    args = ap.parse_args()
    if args.quick:
        args.maps, args.map_size, args.scenes = 40, 64, 10
    size = args.map_size
    root = args.output
    for sub in ("textures", "scenes", "large"):
        os.makedirs(os.path.join(root, sub), exist_ok=True)

    # A few base tiles, each map a shifted copy of one: distinct files, comparable work per map.
    normals = [bump_tile(size, p, amp) for p, amp in ((16, 1.2), (10, 0.8), (24, 1.5), (6, 0.5))]
    orms = [orm_tile(size, 0.05, 0.5), orm_tile(size, 0.1, 0.8)]
    quad = quad_buffer()
    write(os.path.join(root, "textures", "quad.bin"), quad)
    cards, scenes = [], []
    large_n, large_o = [], []
    for i in range(args.maps):
        name = "t%04d" % i
        n_rows = rolled(normals[i % len(normals)], 7 * i, 13 * i)
        o_rows = rolled(orms[i % len(orms)], 0, 5 * i)
        write(os.path.join(root, "textures", name + "_n.png"), png_bytes(size, size, n_rows))
        write(os.path.join(root, "textures", name + "_orm.png"), png_bytes(size, size, o_rows))
        card = card_gltf(name, name + "_n.png", name + "_orm.png", "quad.bin", len(quad))
        write(os.path.join(root, "textures", name + ".gltf"), json.dumps(card, indent=1).encode())
        cards.append(os.path.join("textures", name + ".gltf"))
        large_n.append(n_rows)
        large_o.append(o_rows)
    for i in range(args.scenes):
        name = "s%03d" % i
        radii = (1.0 + 0.5 * math.sin(i), 1.0 + 0.3 * math.cos(1.7 * i), 0.8 + 0.2 * math.sin(2.3 * i))
        glb = ellipsoid_glb(name, 24 + i % 9, 48 + 2 * (i % 7), radii, 0.15 + 0.1 * (i % 4))
        write(os.path.join(root, "scenes", name + ".glb"), glb)
        scenes.append(os.path.join("scenes", name + ".glb"))

    # The large card: all the small maps side by side (columns x rows of tiles), the same total texels.
    columns = next(c for c in range(int(math.sqrt(args.maps)), 0, -1) if args.maps % c == 0)
    tile_rows = args.maps // columns
    if columns < tile_rows:
        columns, tile_rows = tile_rows, columns

    def mosaic(tiles):
        rows = []
        for r in range(tile_rows):
            for y in range(size):
                rows.append(b"".join(tiles[r * columns + c][y] for c in range(columns)))
        return rows

    write(os.path.join(root, "large", "large_n.png"), png_bytes(columns * size, tile_rows * size, mosaic(large_n)))
    write(os.path.join(root, "large", "large_orm.png"), png_bytes(columns * size, tile_rows * size, mosaic(large_o)))
    write(os.path.join(root, "large", "quad.bin"), quad)
    large = card_gltf("large", "large_n.png", "large_orm.png", "quad.bin", len(quad))
    write(os.path.join(root, "large", "large.gltf"), json.dumps(large, indent=1).encode())

    for list_name, items in (("textures.txt", cards), ("scenes.txt", scenes), ("all.txt", cards + scenes)):
        with open(os.path.join(root, list_name), "w") as f:
            f.write("".join(os.path.join(os.path.abspath(root), p) + "\n" for p in items))
    with open(os.path.join(root, "library.json"), "w") as f:
        json.dump({"maps": args.maps, "map_size": size, "scenes": args.scenes,
                   "large": [columns * size, tile_rows * size]}, f, indent=1)
    print("wrote %d map pairs of %dx%d, %d scenes and a %dx%d large card to %s" %
          (args.maps, size, size, args.scenes, columns * size, tile_rows * size, root))


if __name__ == "__main__":
    main()
