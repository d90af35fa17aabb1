#!/bin/sh
# Albedo lookup tables E(mu, alpha) of mirror heightfields (docs/guide/albedo.md):
#   analysis/albedo_lut.sh BUILD_DIR OUT_DIR
# generates converged Gaussian tiles (16 cells per correlation length, 1024^2) with Beckmann and
# GGX slope statistics at each alpha of ALPHAS, and one anisotropic Beckmann tile, measures each
# family's table with `microsim measure albedo --material mirror` and prints the markdown summary
# (analysis/albedo_lut.py; figure OUT_DIR/albedo_lut.png).
# Sizes (environment): ALPHAS, RAYS (per mu node and surface), MU_NODES, RESOLUTION, ANISO (alpha_x,alpha_y).
set -eu
SRC=$(cd "$(dirname "$0")/.." && pwd)
BUILD=$(cd "$1" && pwd)
OUT=$2
M="$BUILD/microsim"
ALPHAS=${ALPHAS:-"0.05 0.1 0.2 0.3 0.4 0.5 0.7 1.0"}
RAYS=${RAYS:-500000}
MU_NODES=${MU_NODES:-12}
RESOLUTION=${RESOLUTION:-1024}
ANISO=${ANISO:-"0.2,0.6"}
mkdir -p "$OUT"
start=$(date +%s)
# The converged grid: 16 cells per correlation length whatever the resolution.
L=$(/usr/bin/python3 -c "print(16.0 / $RESOLUTION)")
beckmann="" ggx=""
for a in $ALPHAS; do
  "$M" -q generate gaussian --config "$SRC/surfaces/beckmann-1.0-converged.toml" --resolution "$RESOLUTION" \
    --correlation-length "$L" --alpha "$a" -o "$OUT/beckmann-$a.exr"
  "$M" -q generate gaussian-ggx --config "$SRC/surfaces/gaussian-ggx.toml" --resolution "$RESOLUTION" \
    --correlation-length "$L" --roughness-correlation-length "$(/usr/bin/python3 -c "print(min(16 * $L, 0.25))")" \
    --alpha "$a" -o "$OUT/ggx-$a.exr"
  beckmann="$beckmann $OUT/beckmann-$a.exr"
  ggx="$ggx $OUT/ggx-$a.exr"
done
ax=${ANISO%,*}
ay=${ANISO#*,}
"$M" -q generate gaussian --resolution "$RESOLUTION" --size 1 --correlation-length "$L" --seed 1 \
  --alpha-x "$ax" --alpha-y "$ay" -o "$OUT/beckmann-aniso.exr"
generated=$(date +%s)
for family in beckmann ggx; do
  eval files=\$$family
  # shellcheck disable=SC2086
  "$M" -q measure albedo $files --material mirror --mu-nodes "$MU_NODES" --rays "$RAYS" -o "$OUT/lut-$family.exr"
done
"$M" -q measure albedo "$OUT/beckmann-aniso.exr" --material mirror --mu-nodes "$MU_NODES" --rays "$RAYS" \
  -o "$OUT/lut-beckmann-aniso.exr"
end=$(date +%s)
/usr/bin/python3 "$SRC/analysis/albedo_lut.py" "$OUT" --resolution "$RESOLUTION" \
  --generate-seconds $((generated - start)) --measure-seconds $((end - generated))
