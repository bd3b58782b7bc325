#!/usr/bin/env python3
"""UASTC (bake --gltf-mode replace) against the uncompressed bake, per level (issue 16, item 3).

Bakes a glTF model twice: `specbake texture` of its normal and ORM maps without supercompression (the
reference RGBA8 levels), and `specbake bake --gltf-mode replace` (UASTC levels by basisu, zstd). The UASTC
levels are decoded by basisu's own transcoder (`basisu -unpack`, its lossless UASTC -> ASTC 4x4 path,
written as RGBA PNGs) and compared texel by texel: roughness error in r units (G), RMS and max, at
level 0 and the worst level; mean-normal angle error (level 0 mean, max over levels); file size against
the plain UASTC levels and against the uncompressed RGBA8 levels; encode throughput (the replace bake's
extra time over a sidecar bake, per texel of every level of both chains).

Usage: bench/uastc_accuracy.py SPECBAKE BASISU MODEL.gltf NORMAL.png ORM.png
"""
import json
import math
import os
import struct
import subprocess
import sys
import tempfile
import time

from PIL import Image


def ktx2_levels(path):
    """Level bytes of an uncompressed KTX2 file, level 0 first."""
    b = open(path, 'rb').read()
    w, h = struct.unpack_from('<II', b, 20)
    n = struct.unpack_from('<I', b, 40)[0]
    if struct.unpack_from('<I', b, 44)[0] != 0:
        sys.exit(f'{path}: supercompressed; expected a plain reference')
    out = []
    for i in range(n):
        off, length = struct.unpack_from('<QQ', b, 80 + 24 * i)
        out.append((max(1, w >> i), max(1, h >> i), b[off:off + length]))
    return out


def run(args, cwd=None):
    start = time.monotonic()
    subprocess.run(args, check=True, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.monotonic() - start


def unpack(basisu, ktx2, work):
    """RGBA texels of every level of a UASTC KTX2 file, decoded by basisu."""
    d = tempfile.mkdtemp(dir=work)
    local = os.path.join(d, 'u.ktx2')
    with open(local, 'wb') as f:
        f.write(open(ktx2, 'rb').read())
    run([basisu, '-unpack', '-no_ktx', '-file', 'u.ktx2'], cwd=d)
    levels = []
    while os.path.exists(os.path.join(d, f'u_unpacked_rgba_ASTC_RGBA_{len(levels)}_0000.png')):
        levels.append(Image.open(os.path.join(d, f'u_unpacked_rgba_ASTC_RGBA_{len(levels)}_0000.png')).convert('RGBA'))
    return levels


def main():
    if len(sys.argv) != 6:
        sys.exit(__doc__)
    specbake, basisu, model, normal, orm = (os.path.abspath(a) for a in sys.argv[1:])
    work = tempfile.mkdtemp(prefix='specbake_uastc_')
    ref = os.path.join(work, 'ref')
    run([specbake, '-q', 'texture', '--normal', normal, '--roughness', orm, '--outputs', 'roughness,normal',
         '--supercompression', 'none', '-o', ref])
    sidecar = run([specbake, '-q', 'bake', model, '-o', os.path.join(work, 'sidecar')])
    rep = os.path.join(work, 'replace')
    replace = run([specbake, '-q', 'bake', model, '--gltf-mode', 'replace', '--basisu', basisu, '-o', rep])
    manifest = json.load(open(os.path.join(rep, 'manifest.json')))
    found = {}

    def walk(o):
        if isinstance(o, dict):
            if o.get('gpu_format') == 'UASTC':
                found[o['kind']] = o
            for v in o.values():
                walk(v)
        elif isinstance(o, list):
            for v in o:
                walk(v)
    walk(manifest)
    texels = 0
    rows = []
    for kind, ref_file in (('roughness_basisu', 'texture_roughness.ktx2'), ('normal_basisu', 'texture_normal.ktx2')):
        entry = found[kind]
        ref_levels = ktx2_levels(os.path.join(ref, ref_file))
        got = unpack(basisu, os.path.join(rep, entry['path']), work)
        if len(got) != len(ref_levels):
            sys.exit(f'{kind}: {len(got)} levels decoded, {len(ref_levels)} baked')
        rms0 = max0 = worst_rms = worst_max = angle0 = angle_max = 0.0
        for level, ((w, h, data), img) in enumerate(zip(ref_levels, got)):
            texels += w * h
            px = img.tobytes()
            s = mx = ang = 0.0
            for i in range(w * h):
                if kind == 'roughness_basisu':
                    d = (px[4 * i + 1] - data[4 * i + 1]) / 255.0
                    s += d * d
                    mx = max(mx, abs(d))
                else:
                    u = [data[4 * i + c] / 127.5 - 1.0 for c in range(3)]
                    v = [px[4 * i + c] / 127.5 - 1.0 for c in range(3)]
                    lu = math.sqrt(sum(t * t for t in u)) or 1.0
                    lv = math.sqrt(sum(t * t for t in v)) or 1.0
                    c = max(-1.0, min(1.0, sum(a * b for a, b in zip(u, v)) / (lu * lv)))
                    a = math.degrees(math.acos(c))
                    ang += a
                    angle_max = max(angle_max, a)
            rms = math.sqrt(s / (w * h))
            if level == 0:
                rms0, max0, angle0 = rms, mx, ang / (w * h)
            worst_rms, worst_max = max(worst_rms, rms), max(worst_max, mx)
        raw = sum(len(d) for _, _, d in ref_levels)
        rows.append((kind, rms0, max0, worst_rms, worst_max, angle0, angle_max, entry['bytes'],
                     entry['uastc_level_bytes'], raw))
    seconds = max(1e-9, replace - sidecar)
    print(f'{normal} + {orm}: replace bake {replace:.2f} s, sidecar bake {sidecar:.2f} s')
    print('| UASTC chain | r error level 0 RMS / max | r error worst level RMS / max | normal angle level 0 mean / all max '
          '| zstd file vs plain UASTC levels | vs uncompressed RGBA8 | encode Mtexel/s (basisu, extra time) |')
    print('|---|---|---|---|---|---|---|')
    for kind, rms0, max0, wr, wm, a0, amax, size, plain, raw in rows:
        rough = kind == 'roughness_basisu'
        print(f'| {kind} | {f"{rms0:.5f} / {max0:.4f}" if rough else "-"} | {f"{wr:.5f} / {wm:.4f}" if rough else "-"} | '
              f'{"-" if rough else f"{a0:.3f} / {amax:.2f} deg"} | {size / plain:.3f} | {size / raw:.3f} | '
              f'{texels / seconds * 1e-6:.1f} |')


if __name__ == '__main__':
    main()
