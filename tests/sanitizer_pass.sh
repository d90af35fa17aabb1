#!/usr/bin/env bash
# The sanitizer pass of the test command: the unit tests built with ASan + UBSan (LeakSanitizer
# on; any report fails), then a smoke run of every libFuzzer target over its seed corpus
# (fuzz/corpus/) and 3000 mutated inputs from a fixed seed (reproducible; 120 s is only a cap).
# Strict: a loader must return or refuse with the usage error (exit 2 naming the file); any other
# exception, a sanitizer report, a hang or a memory blow-up fails the pass.
# Usage: tests/sanitizer_pass.sh [BUILD_DIR]   (default build-asan)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build-asan}
launcher=()
command -v ccache > /dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++-14 \
      -DMICROSIM_SANITIZE=ON -DMICROSIM_FUZZ=ON "${launcher[@]}"
cmake --build "$build" -j2
tests/sanitize.sh "$build" -j2
MICROSIM_FUZZ_SEED=1 fuzz/run_fuzzers.sh "$build" 120 3000
