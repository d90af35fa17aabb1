#!/usr/bin/env bash
# The model statements of docs/findings (masking, G2, grazing lobes), measured on converged
# surfaces: generate gaussian's default grid (16 cells per correlation length, 64 per 1024^2
# tile), ensembles of independent tiles (between-surface errors beside the ray-count ones).
#   - G1 averaged (0-85 deg) and per normal bin at 80 deg against Smith and V-cavity, alpha 0.5;
#   - G2 at o = i against G1 [GeomBSDF24, eq. 16] and the G2 forms at 75/75 deg, opposite azimuths;
#   - [Heitz14, Table 4]: the in-plane order-1 lobe at theta_i = 1.5 rad against Smith's single
#     scattering, mirror Beckmann alpha = 1 (ALPHAS_T4 for more roughnesses).
#
#   analysis/converged_models.sh [BUILD_DIR] [OUT_DIR]
#
# Runs are skipped when their output exists. Environment: SEEDS ["1 2 3 4"], CELLS_PER_L [16]
# (4 reproduces the earlier 4-cells-per-l tiles), RAYS_G [1000000] per tile and direction (the
# recorded tables: 500000, RAYS_T4=1048576, ALPHAS_T4="0.4 0.7 1.0 1.3"),
# RAYS_T4 [4194304] per tile, ALPHAS_T4 ["1.0"], NICE [10]. Then analysis/converged_models.py.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
build="${1:-$root/build}"
out="${2:-$build/converged_models}"
M="$build/microsim"
[ -x "$M" ] || { echo "no microsim binary in $build" >&2; exit 1; }
seeds="${SEEDS:-1 2 3 4}"
cells="${CELLS_PER_L:-16}"
rays_g="${RAYS_G:-1000000}"
rays_t4="${RAYS_T4:-4194304}"
alphas_t4="${ALPHAS_T4:-1.0}"
niceness="${NICE:-10}"
ell=$(/usr/bin/python3 -c "print(repr($cells / 1024))")
mkdir -p "$out"
run() {  # run OUTPUT args...: skip when OUTPUT exists
  local f="$1"; shift
  [ -s "$f" ] && return 0
  echo "+ microsim $*" >&2
  /usr/bin/time -v -o "$f.time" nice -n "$niceness" "$M" -q "$@"
}
tiles() {  # tiles ALPHA: generates the ensemble, prints the file names
  local a="$1" s f list=""
  for s in $seeds; do
    f="$out/b${a}_c${cells}_s$s.exr"
    [ -s "$f" ] || nice -n "$niceness" "$M" -q generate gaussian --resolution 1024 --correlation-length "$ell" \
      --alpha "$a" --seed "$s" -o "$f"
    list="$list $f"
  done
  echo "$list"
}

t05=$(tiles 0.5)
# shellcheck disable=SC2086
run "$out/g1_80_c$cells.json" measure g1 $t05 --theta 80 --phi 0 --rays "$rays_g" --seed 2 -o "$out/g1_80_c$cells.json"
th15=$(/usr/bin/python3 -c "import math; print(repr(math.degrees(1.5)))")
for a in $alphas_t4; do
  for f in $(tiles "$a"); do
    j="${f%.exr}_t4.json"
    run "$j" measure bsdf "$f" --material mirror --theta-i "$th15" --phi-i 0 --rays "$rays_t4" \
      --resolution 64 --seed 1 -o "${j%.json}.exr"
  done
done
# G2 at o = i against an independent G1 run (other seed), and at opposite azimuths.
for t in 30 60 70 80; do
  # shellcheck disable=SC2086
  run "$out/g2_same${t}_c$cells.json" measure g2 $t05 --theta-o "$t" --phi-o 0 --theta-i "$t" --phi-i 0 \
    --rays "$rays_g" --seed 7 -o "$out/g2_same${t}_c$cells.json"
done
# shellcheck disable=SC2086
run "$out/g1_same_c$cells.json" measure g1 $t05 --theta 30,60,70,80 --phi 0 --rays "$rays_g" --seed 8 -o "$out/g1_same_c$cells.json"
# shellcheck disable=SC2086
run "$out/g2_opp_c$cells.json" measure g2 $t05 --theta-o 75 --phi-o 0 --theta-i 75 --phi-i 180 \
  --rays "$rays_g" --seed 9 -o "$out/g2_opp_c$cells.json"

# shellcheck disable=SC2086
run "$out/g1_avg_c$cells.json" measure g1 $t05 --theta 0:85:5 --phi 0 --rays $((rays_g / 4)) --seed 1 -o "$out/g1_avg_c$cells.json"
echo "done: /usr/bin/python3 $here/converged_models.py $out $cells" >&2
