#!/usr/bin/env bash
# examples/bazel built by Bazel (Debian's bazel-bootstrap, offline): the actions run in the Linux sandbox
# with only their declared inputs (an undeclared texture fails the bake naming it), a rebuild after
# `bazel clean` is served from --disk_cache, an edited input re-runs only its action, and the outputs are
# the bytes of a plain specbake run.
# Usage: bazel_example.sh SOURCE_DIR SPECBAKE OIIO_MODULE WORK_DIR   (exit 77: Bazel not installed, skipped)
set -euo pipefail
src=$1; specbake=$2; module=$3; work=$4
command -v bazel >/dev/null || { echo "bazel not installed (Debian: bazel-bootstrap): skipped"; exit 77; }
fail() { echo "FAILED: $*" >&2; exit 1; }

# The source layout the WORKSPACE expects: examples/{bazel,assets} and the build folder two levels up,
# holding the CMake-built executable and module.
rm -rf "$work"; mkdir -p "$work/examples" "$work/build/cli"
cp -r "$src/examples/bazel" "$src/examples/assets" "$work/examples/"
cp "$specbake" "$module" "$work/build/cli/"
cd "$work/examples/bazel"
# --batch: no server left running; the output base and the cache live in the work folder.
bz() { bazel --batch --output_user_root="$work/root" "$@"; }
flags=(--disk_cache="$work/cache" --color=no --curses=no)
targets=(//:tile //:panel //:pebble //:tile_maps)
# "INFO: 6 processes: 4 linux-sandbox, 2 internal." -> the count of one kind.
processes() { grep -o "[0-9]* $1" <<<"$2" | tail -1 | cut -d' ' -f1; }

log=$(bz build "${flags[@]}" "${targets[@]}" 2>&1) || fail "first build: $log"
echo "$log" | grep -E "processes|Elapsed"
[ "$(processes linux-sandbox "$log")" = 4 ] || fail "expected 4 sandboxed actions: $log"

# An undeclared input: the texture is not in the sandbox, and the bake says which file is missing.
mkdir undeclared
cat > undeclared/BUILD.bazel <<'BUILD'
load("//:specbake.bzl", "specbake_scene")
specbake_scene(
    name = "tile_without_orm",
    scene = "@assets//:tile.gltf",
    srcs = ["@assets//:quad.bin", "@assets//:tile_n.png"],
)
BUILD
if log=$(bz build "${flags[@]}" //undeclared:tile_without_orm 2>&1); then fail "built without a declared input: $log"; fi
grep "specbake: error:" <<<"$log" | grep -q "tile_orm.png" || fail "the error does not name tile_orm.png: $log"
grep "specbake: error:" <<<"$log"
rm -r undeclared

# After `bazel clean` everything comes from the disk cache: no action runs.
bz clean >/dev/null 2>&1
log=$(bz build "${flags[@]}" "${targets[@]}" 2>&1) || fail "build after clean: $log"
echo "$log" | grep -E "processes|Elapsed"
[ "$(processes "remote cache hit" "$log")" = 4 ] || fail "expected 4 cache hits after bazel clean: $log"
[ -z "$(processes linux-sandbox "$log")" ] || fail "an action ran after bazel clean: $log"

# One edited input (bytes after the PNG's IEND: the same picture, a different file): only its action runs.
printf '\0' >> ../assets/panel_n.png
log=$(bz build "${flags[@]}" "${targets[@]}" 2>&1) || fail "build after the edit: $log"
echo "$log" | grep -E "processes|Elapsed"
[ "$(processes linux-sandbox "$log")" = 1 ] || fail "expected one action after editing panel_n.png: $log"

# The same bytes as a plain run of the same command (manifest.json records the input paths as given,
# so of it the list of outputs with their hashes is compared).
bin=$(bz info "${flags[@]}" bazel-bin 2>/dev/null)
cd "$work/examples/assets"
"$specbake" -q bake panel.gltf --format glb --container ktx2 -o "$work/plain/panel"
"$specbake" -q --config ../bazel/specbake.toml texture --normal tile_n.png --roughness tile_orm.png --format ktx2 \
  -o "$work/plain/tile_maps"
for t in panel tile_maps; do
  diff -r -x manifest.json "$bin/$t" "$work/plain/$t" || fail "$t: Bazel's outputs differ from a plain run"
  python3 - "$bin/$t/manifest.json" "$work/plain/$t/manifest.json" <<'PY' || fail "$t: manifests list different outputs"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:])
sys.exit(0 if a["outputs"] == b["outputs"] else 1)
PY
done
echo "bazel example: OK"
