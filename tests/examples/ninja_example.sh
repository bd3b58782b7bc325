#!/usr/bin/env bash
# examples/ninja built by Ninja: everything bakes, a second build does no work, an edited texture rebakes
# only the asset that uses it, and the outputs are the bytes of a plain specbake run.
# Usage: ninja_example.sh SOURCE_DIR SPECBAKE WORK_DIR   (exit 77: Ninja not installed, test skipped)
set -euo pipefail
src=$1; specbake=$2; work=$3
command -v ninja >/dev/null || { echo "ninja not installed (Debian: ninja-build): skipped"; exit 77; }
fail() { echo "FAILED: $*" >&2; exit 1; }

rm -rf "$work"; mkdir -p "$work"
cp -r "$src/examples/ninja" "$src/examples/assets" "$work/"
export PATH="$(dirname "$specbake"):$PATH"
cd "$work/ninja"

out=$(ninja -j 2) || fail "first build: $out"
echo "$out"
for f in baked/tile/tile.gltf baked/panel/panel.gltf baked/pebble/pebble.glb baked/tile_maps/texture_kernel.ktx2; do
  [ -f "$f" ] || fail "$f was not written"
done
grep -q 'panel_n.png' .ninja_deps || fail "Ninja did not record the texture panel.gltf references (depfile)"

out=$(ninja -j 2)
[ "$out" = "ninja: no work to do." ] || fail "second build did work: $out"

# Bytes after the PNG's IEND chunk: the same picture, a different file.
printf '\0' >> ../assets/panel_n.png
out=$(ninja -j 2)
echo "$out"
[ "$(grep -c 'specbake ' <<<"$out")" = 1 ] || fail "expected one action after editing panel_n.png: $out"
grep -q 'specbake bake ../assets/panel.gltf' <<<"$out" || fail "panel.gltf was not the one rebaked: $out"
out=$(ninja -j 2)
[ "$out" = "ninja: no work to do." ] || fail "build after the rebake did work: $out"

# The same command by hand gives the same bytes (manifest included: the same paths are recorded).
"$specbake" -q bake ../assets/panel.gltf -o plain/panel
"$specbake" -q texture --normal ../assets/tile_n.png --roughness ../assets/tile_orm.png -o plain/tile_maps
diff -r baked/panel plain/panel || fail "Ninja's panel differs from a plain run"
diff -r baked/tile_maps plain/tile_maps || fail "Ninja's tile_maps differ from a plain run"
echo "ninja example: OK"
