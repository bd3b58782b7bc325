#!/usr/bin/env bash
# Long fuzzing campaign: at least RUNS (default 10^6) executions per target, from the generated seeds and
# the saved regressions, in a build configured with -DSPECBAKE_BUILD_FUZZ=ON. A run that stops on a
# finding is resumed from the grown corpus (at most 5 times a target) until RUNS executions are done.
# Prints one line per target: executions, coverage (libFuzzer's cov / ft), findings (inputs in
# BUILD/fuzz-findings). Usage: fuzz/run_long.sh [BUILD_DIR] [TARGET...]; env RUNS, JOBS (parallel targets),
# MAX_SECONDS (a cap per target: the run stops there with the executions done so far).
set -uo pipefail
cd "$(dirname "$0")/.."
# Absolute paths: the config target works inside its scratch folder.
BUILD=$(cd "${1:-build-asan}" && pwd)
shift || true
RUNS=${RUNS:-1000000}
JOBS=${JOBS:-1}
MAX_SECONDS=${MAX_SECONDS:-0}
source fuzz/fuzz_env.sh
scratch_root=$( [ -d /dev/shm ] && echo /dev/shm || echo "${TMPDIR:-/tmp}" )
export SPECBAKE_FUZZ_SCRATCH="$scratch_root/specbake-fuzz-run-$$"
mkdir -p "$SPECBAKE_FUZZ_SCRATCH"
trap 'rm -rf "$SPECBAKE_FUZZ_SCRATCH"' EXIT
targets=${*:-$SPECBAKE_FUZZ_TARGETS}
seeds="$BUILD/fuzz-seeds"
[ -d "$seeds" ] || "$BUILD/fuzz/make_seeds" "$seeds" || exit 1
findings="$BUILD/fuzz-findings"
mkdir -p "$findings" "$BUILD/fuzz-long"

one_target() {
  local target=$1 exe="$BUILD/fuzz/fuzz_$1" corpus="$BUILD/fuzz-corpus/$1" log="$BUILD/fuzz-long/$1.log"
  mkdir -p "$corpus"
  : >"$log"
  local done_runs=0 found=0 attempt=0 start=$SECONDS
  while [ "$done_runs" -lt "$RUNS" ] && [ "$attempt" -lt 6 ]; do
    local left=0
    if [ "$MAX_SECONDS" -gt 0 ]; then
      left=$((MAX_SECONDS - (SECONDS - start)))
      [ "$left" -le 0 ] && break
    fi
    attempt=$((attempt + 1))
    local part="$log.$attempt"
    "$exe" $(fuzz_flags "$target") -artifact_prefix="$findings/$target-" -runs=$((RUNS - done_runs)) \
      -max_total_time="$left" -print_final_stats=1 "$corpus" "$seeds/$target" >"$part" 2>&1
    local rc=$?
    cat "$part" >>"$log"
    local n
    n=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$part" | tail -1 | grep -o '[0-9]*$')
    if [ -z "$n" ]; then  # stopped on a finding: count up to the last status line
      n=$(grep -oE '^#[0-9]+' "$part" | tail -1 | tr -d '#')
    fi
    done_runs=$((done_runs + ${n:-0}))
    [ "$rc" -ne 0 ] && found=$((found + 1))
    rm -f "$part"
  done
  local cov
  cov=$(grep -oE 'cov: [0-9]+ ft: [0-9]+' "$log" | tail -1)
  printf '%-10s executions %9d  %-22s  findings %d  corpus %d files  %d s\n' "$target" "$done_runs" "$cov" "$found" \
    "$(ls "$corpus" | wc -l)" $((SECONDS - start))
}

export -f one_target fuzz_flags
export BUILD RUNS MAX_SECONDS findings seeds
if [ "$JOBS" -gt 1 ]; then
  printf '%s\n' $targets | xargs -P "$JOBS" -I{} bash -c 'one_target {}'
else
  for t in $targets; do one_target "$t"; done
fi
ls "$findings"
