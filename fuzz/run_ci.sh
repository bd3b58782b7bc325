#!/usr/bin/env bash
# The fuzz part of CI (.ci/sanitize): every target replays its generated seeds and saved regressions
# (fuzz/regressions/<target>/), then fuzzes from them with a fixed seed for fuzz_ci_runs executions
# (fuzz/fuzz_env.sh, ~20 s each; at most FUZZ_SECONDS). Any crash, leak, undefined behaviour, timeout or
# out-of-memory fails the run; the input is kept in BUILD/fuzz-findings. Folders of fuzz/regressions/
# named <reader>_open/ hold reproducers of problems not fixed yet and are not replayed.
# Usage: fuzz/run_ci.sh [BUILD_DIR]   (a build configured with -DSPECBAKE_BUILD_FUZZ=ON)
set -euo pipefail
cd "$(dirname "$0")/.."
# Absolute paths: the config target works inside its scratch folder.
BUILD=$(cd "${1:-build-asan}" && pwd)
SECONDS_PER_TARGET=${FUZZ_SECONDS:-60}  # a cap: each target stops after fuzz_ci_runs executions
source fuzz/fuzz_env.sh
scratch_root=$( [ -d /dev/shm ] && echo /dev/shm || echo "${TMPDIR:-/tmp}" )
export SPECBAKE_FUZZ_SCRATCH="$scratch_root/specbake-fuzz-run-$$"
mkdir -p "$SPECBAKE_FUZZ_SCRATCH"
trap 'rm -rf "$SPECBAKE_FUZZ_SCRATCH"' EXIT
seeds="$BUILD/fuzz-seeds"
# The seed generator is not under test, and LeakSanitizer's tracer can crash on its exit (signal 11, as
# in .ci/sanitize's CLI processes): it runs without the leak check, which stays on for every fuzz target.
rm -rf "$seeds" && ASAN_OPTIONS=${ASAN_OPTIONS/detect_leaks=1/detect_leaks=0} "$BUILD/fuzz/make_seeds" "$seeds"
findings="$BUILD/fuzz-findings"
mkdir -p "$findings"
status=0
for target in $SPECBAKE_FUZZ_TARGETS; do
  exe="$BUILD/fuzz/fuzz_$target"
  corpus="$BUILD/fuzz-corpus/$target"
  mkdir -p "$corpus"
  replay=("$seeds/$target"/*)
  if [ -d "fuzz/regressions/$target" ] && compgen -G "fuzz/regressions/$target/*" >/dev/null; then
    replay+=("$PWD/fuzz/regressions/$target"/*)
  fi
  log="$BUILD/fuzz-$target.log"
  if ! "$exe" $(fuzz_flags "$target") -artifact_prefix="$findings/$target-" "${replay[@]}" >"$log" 2>&1; then
    echo "fuzz $target: a seed or regression input fails (log $log):"; tail -n 30 "$log"; status=1; continue
  fi
  if ! "$exe" $(fuzz_flags "$target") -artifact_prefix="$findings/$target-" -seed=1 -runs="$(fuzz_ci_runs "$target")" \
        -max_total_time="$SECONDS_PER_TARGET" -print_final_stats=1 "$corpus" "$seeds/$target" >>"$log" 2>&1; then
    echo "fuzz $target: finding (log $log):"; tail -n 30 "$log"; status=1; continue
  fi
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | tail -1 | grep -o '[0-9]*$' || true)
  cov=$(grep -oE 'cov: [0-9]+ ft: [0-9]+' "$log" | tail -1 || true)
  echo "fuzz $target: ${#replay[@]} seeds and regressions replayed, ${runs:-?} executions, $cov, no finding"
done
exit $status
