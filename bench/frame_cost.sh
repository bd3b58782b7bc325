#!/bin/bash
# Frame time of the include's quality tiers and of the engines' run-time filters, relative to no filtering,
# with every pixel of a 1920x1080 frame shaded (the normal-mapped bumpy sphere filling the view) under 1 and
# under 4 directional lights. Each candidate is drawn round robin with the others (`specbake verify
# --repeats`), so load changes on a shared machine hit all of them alike; read the ratios, not the times.
#
#   bench/frame_cost.sh                  # llvmpipe (Mesa's CPU rasteriser), as on machines without a GPU
#   bench/frame_cost.sh --gpu            # the GPU Mesa's EGL picks; exits 2 saying so when there is none
#   bench/frame_cost.sh --quick          # 480x270, 2 repeats: checks the script in a few seconds
#
# Options: --specbake PATH (default: build/cli/specbake), --size WxH (default 1920x1080), --repeats N
# (default 5), --lights "1 4", --output FILE (also write the table there).
set -euo pipefail

specbake=build/cli/specbake
size=1920x1080
repeats=5
lights="1 4"
gpu=0
output=""
while [ $# -gt 0 ]; do
    case "$1" in
        --specbake) specbake=$2; shift 2 ;;
        --size) size=$2; shift 2 ;;
        --repeats) repeats=$2; shift 2 ;;
        --lights) lights=$2; shift 2 ;;
        --gpu) gpu=1; shift ;;
        --quick) size=480x270; repeats=2; shift ;;
        --output) output=$2; shift 2 ;;
        -h|--help) sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        *) echo "frame_cost.sh: unknown option '$1' (see --help)" >&2; exit 64 ;;
    esac
done
if [ ! -x "$specbake" ]; then
    echo "frame_cost.sh: $specbake is not an executable (build it, or give --specbake PATH)" >&2
    exit 1
fi
if [ "$gpu" = 1 ]; then
    unset LIBGL_ALWAYS_SOFTWARE
else
    export LIBGL_ALWAYS_SOFTWARE=1
fi

# The run-time peers (the engines' derivative filters), the baked roughness alone, and the three tiers as
# the bench scores them: fast (SPECAA_QUALITY=0) and balanced (SPECAA_QUALITY=1) on the baked roughness,
# the binding they are meant for, and the reference, the default as shipped (Sigma
# kernel mips and the baked curvature), also without the curvature attribute (default-derivatives).
only=filament,godot,unity-hdrp,threejs,babylon,baked-texture,fast,balanced,default-derivatives,default
variants=()

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# The renderer first, from a 16x16 frame: --gpu stops here when it is a CPU rasteriser.
"$specbake" -q verify --builtin bumpy-sphere --size 16x16 --frames 1 --spp 1 --no-floor --no-limit --repeats 0 \
    --only none > "$work/probe.md"
line=$(grep -m1 '^Scene ' "$work/probe.md" || true)
renderer=${line##*; }
case "$renderer" in
    *llvmpipe*|*softpipe*|*SwiftShader*|"")
        if [ "$gpu" = 1 ]; then
            echo "frame_cost.sh: not run on a GPU: the renderer here is '${renderer:-unknown}' (no GPU Mesa can use)" >&2
            exit 2
        fi ;;
esac
for n in $lights; do
    "$specbake" -q verify --builtin bumpy-sphere --alpha 0.05 --size "$size" --distance 0.4 --lights "$n" \
        --frames 1 --spp 1 --no-floor --no-limit --repeats "$repeats" --only "$only" "${variants[@]}" \
        > "$work/$n.md"
done

# One row per candidate: SPIR-V instructions and frame time x no filtering per light count.
table=$(python3 - "$work" "$lights" "$renderer" "$size" "$repeats" <<'PY'
import sys, os
work, lights, renderer, size, repeats = sys.argv[1], sys.argv[2].split(), sys.argv[3], sys.argv[4], sys.argv[5]
order = ['none', 'baked-texture', 'filament', 'godot', 'unity-hdrp', 'threejs', 'babylon',
         'fast', 'balanced', 'default-derivatives', 'default']
label = {'default': 'default (reference tier, baked curvature)',
         'default-derivatives': 'reference tier without the curvature attribute',
         'balanced': 'balanced tier (SPECAA_QUALITY=1), baked roughness', 'fast': 'fast tier (SPECAA_QUALITY=0), baked roughness',
         'baked-texture': 'baked roughness alone'}
rows = {}
for n in lights:
    hdr = None
    for line in open(os.path.join(work, n + '.md')):
        cells = [c.strip() for c in line.strip().strip('|').split('|')]
        if line.startswith('| candidate |'):
            hdr = cells
            continue
        if hdr and line.startswith('| ') and not line.startswith('|---') and len(cells) == len(hdr):
            r = dict(zip(hdr, cells))
            rows.setdefault(r['candidate'], {})['spirv'] = r['SPIR-V']
            rows[r['candidate']][n] = r['frame x']
        elif hdr and not line.startswith('|'):
            hdr = None
missing = [c for c in order if c not in rows]
if missing:
    sys.exit('frame_cost.sh: specbake verify printed no row for ' + ', '.join(missing))
print('Frame time x no filtering, %s, every pixel shaded, %s repeats; %s' % (size, repeats, renderer))
print()
print('| candidate | SPIR-V instructions | ' + ' | '.join('frame x, %s light%s' % (n, '' if n == '1' else 's') for n in lights) + ' |')
print('|---|---:|' + '---:|' * len(lights))
for c in order:
    print('| %s | %s | %s |' % (label.get(c, c), rows[c]['spirv'], ' | '.join(rows[c].get(n, '-') for n in lights)))
PY
)
echo "$table"
if [ -n "$output" ]; then
    printf '%s\n' "$table" > "$output.tmp" && mv "$output.tmp" "$output"
fi
