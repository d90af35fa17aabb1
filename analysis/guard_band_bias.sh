#!/bin/sh
# The guard band's bias table (docs/theory/discretization.md): a periodic Beckmann
# tile measured as a non-periodic window with guards of 0, 1, 2, 4, 8 correlation lengths,
# against the periodic tile restricted to the same interior. Long (tens of CPU-minutes at
# 1024^2 and 10^6 rays): runs at nice 10. Extra arguments go to the program, e.g.
#   analysis/guard_band_bias.sh build --resolution 512 --rays 1000000 --csv bias.csv
set -e
SRC=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$SRC/build}
[ $# -gt 0 ] && shift
cmake -S "$SRC" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$BUILD" -j2 --target guard_band_bias >/dev/null
exec nice -n 10 "$BUILD/guard_band_bias" "$@"
