#!/bin/sh
# Audit of the mirror walk's orders >= 4 on converged Beckmann alpha = 1 tiles
# (docs/theory/discretization.md): the library's tracer against an independent double-precision tracer on
# the same triangles and origins, and where the paths of order >= 4 go (segment lengths, facet
# adjacency, edge distances, hit heights and curvature, continuation against Smith's masking).
# Writes $OUT_FILE (default BUILD/studies/walk_audit.raw.md; analysis/run_study.sh walk_audit
# makes the docs page of it). About 20 CPU-s per grid level at the defaults (nice 10).
#   analysis/walk_audit.sh [BUILD] [extra options for every level, e.g. --paths 100000]
set -e
SRC=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$SRC/build}
[ $# -gt 0 ] && shift
cmake -S "$SRC" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$BUILD" -j2 --target walk_audit >/dev/null
OUT="${OUT_FILE:-$BUILD/studies/walk_audit.raw.md}"
mkdir -p "$(dirname "$OUT")"
: > "$OUT.tmp"
for c in 16 8 32; do
  nice -n 10 "$BUILD/walk_audit" --alpha 1 --cells-per-l $c --lengths-per-tile 16 --paths 300000 \
    --seeds 1,2 --theta 0,60,80 "$@" >> "$OUT.tmp"
done
mv "$OUT.tmp" "$OUT"
echo "wrote $OUT"
