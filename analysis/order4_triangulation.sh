#!/bin/sh
# Orders 4 and up of the mirror BSDF under the other triangulation of the same heights: Beckmann
# alpha = 1 tiles (16 cells per l, L/l = 32, 512^2), each measured as generated (cells split along
# (i+1, j)-(i, j+1)) at phi_i = 0 and mirrored in x (analysis/mirror_heightfield.py: the other
# diagonal) at phi_i = 180 deg, the same incidence on the same heights. Paired differences, lost and
# unterminated paths and the tracer's counters: analysis/order4_triangulation.py. About 6 CPU-s per
# tile, angle and million rays (nice 10).
#   analysis/order4_triangulation.sh OUTDIR [BUILD] [TILES] [RAYS]
set -e
SRC=$(cd "$(dirname "$0")/.." && pwd)
OUT=${1:?usage: order4_triangulation.sh OUTDIR [BUILD] [TILES] [RAYS]}
BUILD=${2:-$SRC/build}
TILES=${3:-8}
RAYS=${4:-4000000}
M="$BUILD/microsim"
mkdir -p "$OUT"
for s in $(seq 1 "$TILES"); do
  "$M" -q generate gaussian --resolution 512 --size 1 --correlation-length 0.03125 --alpha 1 --seed "$s" \
    -o "$OUT/tile_$s.exr"
  /usr/bin/python3 "$SRC/analysis/mirror_heightfield.py" "$OUT/tile_$s.exr" "$OUT/tile_${s}_mirrored.exr"
  nice -n 10 "$M" -q measure bsdf "$OUT/tile_$s.exr" --material mirror --theta-i 0,60,80 --phi-i 0 \
    --rays "$RAYS" --orders 8 --no-models -o "$OUT/tile_$s.json"
  nice -n 10 "$M" -q measure bsdf "$OUT/tile_${s}_mirrored.exr" --material mirror --theta-i 0,60,80 \
    --phi-i 180 --rays "$RAYS" --orders 8 --no-models -o "$OUT/tile_${s}_mirrored.json"
done
/usr/bin/python3 "$SRC/analysis/order4_triangulation.py" "$OUT" "$TILES"
