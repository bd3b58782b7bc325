# Sourced by the fuzz scripts and .ci/sanitize: the targets, their libFuzzer flags and the sanitizer
# settings (leaks of Mesa's and LLVM's own start-up allocations are suppressed: .ci/lsan.supp).
SPECBAKE_FUZZ_TARGETS="gltf image container mesh config filter"
_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:detect_stack_use_after_return=0:strict_string_checks=1:check_initialization_order=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$_root/.ci/lsan.supp:print_suppressions=0}
if [ -z "${ASAN_SYMBOLIZER_PATH:-}" ]; then
  for s in llvm-symbolizer llvm-symbolizer-14; do
    if command -v "$s" >/dev/null; then export ASAN_SYMBOLIZER_PATH=$(command -v "$s"); break; fi
  done
fi
# Per-target flags: memory limits well under the machine's, a timeout per input, and the input sizes
# each reader is fuzzed at (fuzz_gltf.cpp says why glTF stays under 8 KiB).
fuzz_flags() {
  local common="-rss_limit_mb=2048 -malloc_limit_mb=1024 -timeout=10"
  case "$1" in
    gltf) echo "$common -max_len=8192" ;;
    image) echo "$common -max_len=16384" ;;
    container) echo "$common -max_len=4096" ;;
    mesh) echo "$common -max_len=4096" ;;
    config) echo "$common -max_len=2048" ;;
    filter) echo "$common -max_len=300" ;;
  esac
}
# Executions of each target in CI (fuzz/run_ci.sh), about 20 s each under the sanitizers on the CI
# machine; with a fixed seed the run is the same every time, so a red CI is a reproducible finding.
fuzz_ci_runs() {
  case "$1" in
    gltf) echo 8000 ;;
    image) echo 3000 ;;
    container) echo 200000 ;;
    mesh) echo 4000 ;;
    config) echo 15000 ;;
    filter) echo 400000 ;;
  esac
}
