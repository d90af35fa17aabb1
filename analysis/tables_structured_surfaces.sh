#!/bin/sh
# Tables of structured and non-heightfield microsurfaces.
# Builds microsim and analysis/tables_structured_surfaces.cpp, shows bad mesh input refused by the CLI, then
# prints every table (markdown) with standard errors. About 5-10 minutes on 2 cores.
# Usage: analysis/tables_structured_surfaces.sh [BUILD_DIR] [--quick]
set -e
SRC=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$SRC/build}
[ "$1" = "--quick" ] && BUILD=$SRC/build
QUICK=""
for a in "$@"; do [ "$a" = "--quick" ] && QUICK="--quick"; done
cmake -S "$SRC" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$BUILD" -j2 --target microsim tables_structured_surfaces >/dev/null
M="$BUILD/microsim"
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT

echo "## 0. Bad mesh input: one line on stderr, exit code 2, no output file"
echo
# Three triangles on one edge; two triangles with opposite orientations; a repeated vertex;
# a box without its top (open where it must be closed); a closed tetrahedron (no rim).
printf 'OFF\n5 3 0\n0 0 1\n1 0 1\n0 1 1\n0 -1 1\n0 0 2\n3 0 1 2\n3 1 0 3\n3 0 1 4\n' > "$T/nonmanifold.off"
printf 'OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n3 0 1 3\n' > "$T/flipped.off"
printf 'OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 0 1\n' > "$T/degenerate.off"
printf 'OFF\n8 8 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n3 1 2 6\n3 1 6 5\n3 0 4 7\n3 0 7 3\n3 3 7 6\n3 3 6 2\n3 0 1 5\n3 0 5 4\n' > "$T/open.off"
printf 'OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n' > "$T/closed.off"
echo "| input | exit code | stderr | output written |"
echo "|---|---|---|---|"
for f in nonmanifold flipped degenerate open closed; do
  set +e
  "$M" generate mesh --input "$T/$f.off" -o "$T/$f.ply" 2> "$T/err.txt" >/dev/null
  code=$?
  set -e
  written=no
  [ -e "$T/$f.ply" ] && written=yes
  echo "| $f.off | $code | $(cat "$T/err.txt" | tr '|' '/') ($(wc -l < "$T/err.txt") line) | $written |"
done
echo
"$BUILD/tables_structured_surfaces" $QUICK
