#!/usr/bin/env bash
# The sanitizer pass of the test command: the unit tests built with ASan + UBSan (LeakSanitizer
# on; any report fails), then a smoke run of every libFuzzer target over its seed corpus
# (fuzz/corpus/) and 3000 inputs from a fixed seed (reproducible; 120 s is only a cap). Lenient:
# a loader that refuses a malformed file with a library exception (exit 1) instead of the usage
# error (exit 2) is not yet a failure; drop MICROSIM_FUZZ_LENIENT once every header field is
# validated. Usage: tests/sanitizer_pass.sh [BUILD_DIR]   (default build-asan)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build-asan}
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++-14 \
      -DMICROSIM_SANITIZE=ON -DMICROSIM_FUZZ=ON
cmake --build "$build" -j2
tests/sanitize.sh "$build" -j2
MICROSIM_FUZZ_LENIENT=1 MICROSIM_FUZZ_SEED=1 fuzz/run_fuzzers.sh "$build" 120 3000
