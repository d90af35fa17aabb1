#!/bin/sh
# One command from a plain heightmap file to validation results and a BSDF table for renderers:
# a non-periodic patch (a crop of a generated Beckmann tile, written as a CSV grid as an
# instrument would export it) imported as a window with the default guard band, then `info`,
# `validate` and `measure bsdf -o .bsdf`. Usage: analysis/measured_surface_example.sh [BUILD] [OUT]
set -e
SRC=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$SRC/build}
OUT=${2:-$(mktemp -d)}
M="$BUILD/microsim"
mkdir -p "$OUT"
# The stand-in for an instrument's export: 192 x 192 heights of a 256^2 tile, as CSV.
"$M" generate gaussian --alpha 0.5 --resolution 256 --correlation-length 0.015625 --seed 7 -o "$OUT/source.exr" --quiet
/usr/bin/python3 - "$OUT/source.exr" "$OUT/scan.csv" <<'PY'
import sys
import numpy as np
import OpenImageIO as oiio
inp = oiio.ImageInput.open(sys.argv[1])
z = np.asarray(inp.read_image(format="float")).reshape(inp.spec().height, inp.spec().width, -1)[:, :, 0]
inp.close()
np.savetxt(sys.argv[2], z[:192, :192], delimiter=",", fmt="%.9g")
PY
# From here on: what a user runs on a real scan.csv (pixel size 1/256 in the file's length unit).
"$M" generate heightmap --input "$OUT/scan.csv" --pixel-size 0.00390625 --detrend plane -o "$OUT/scan.exr" \
  && "$M" info "$OUT/scan.exr" \
  && "$M" validate "$OUT/scan.exr" --rays 100000 -o "$OUT/scan-validate.json" \
  && "$M" measure bsdf "$OUT/scan.exr" --material conductor --eta 0.2 --k 3.6 --theta-i 0:80:10 --phi-i 0 \
       --rays 100000 --resolution 32 -o "$OUT/scan.bsdf"
echo "wrote $OUT/scan-validate.json and $OUT/scan.bsdf"
