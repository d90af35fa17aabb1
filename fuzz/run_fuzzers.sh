#!/usr/bin/env bash
# Runs the libFuzzer targets over their seed corpus (fuzz/corpus/<target>/).
# Usage: fuzz/run_fuzzers.sh BUILD_DIR [SECONDS_PER_TARGET [RUNS_PER_TARGET [TARGET...]]]
#   BUILD_DIR configured with MICROSIM_FUZZ=ON; defaults: 10 s and 5000 runs per target (the CI
#   smoke run). New inputs go to BUILD_DIR/fuzz-corpus/<target>/ (the committed corpus is only
#   read); a crashing input is saved as BUILD_DIR/fuzz-artifacts/<target>/crash-* and fails the run.
#   MICROSIM_FUZZ_SEED=N fixes libFuzzer's random seed: with a RUNS bound (and SECONDS only as a
#   safety cap) the run is then the same on every machine, as CI needs.
set -euo pipefail
build=$(cd "${1:?usage: fuzz/run_fuzzers.sh BUILD_DIR [SECONDS [RUNS [TARGET...]]]}" && pwd)
seconds=${2:-10}
runs=${3:-5000}
shift $(( $# < 3 ? $# : 3 ))
src=$(cd "$(dirname "$0")/.." && pwd)
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_exr fuzz_exr_header fuzz_mesh fuzz_suite fuzz_angles fuzz_toml)
symbolizer=$(command -v llvm-symbolizer-14 || command -v llvm-symbolizer || true)
export ASAN_SYMBOLIZER_PATH=$symbolizer
export ASAN_OPTIONS=detect_leaks=1:halt_on_error=1
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
export LSAN_OPTIONS=suppressions=$src/tests/lsan.supp:print_suppressions=0
for t in "${targets[@]}"; do
  out=$build/fuzz-corpus/$t
  art=$build/fuzz-artifacts/$t
  mkdir -p "$out" "$art"
  start=$(date +%s)
  # -runs stops after RUNS inputs, -max_total_time after SECONDS, whichever comes first; one
  # worker (the CPU is shared); 2 GB memory cap and 10 s per input count as crashes.
  "$build/fuzz/$t" ${MICROSIM_FUZZ_SEED:+-seed=$MICROSIM_FUZZ_SEED} -runs="$runs" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
      -malloc_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$art/" \
      "$out" "$src/fuzz/corpus/$t" 2> "$build/fuzz-$t.log" || {
    tail -n 60 "$build/fuzz-$t.log" >&2
    echo "$t: FAILED (input saved in $art/)" >&2
    exit 1
  }
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$build/fuzz-$t.log")
  echo "$t: $execs executions in $(( $(date +%s) - start )) s, no crash"
done
