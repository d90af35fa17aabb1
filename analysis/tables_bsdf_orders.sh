#!/usr/bin/env bash
# Multiple-scattering BSDF tables on explicit surfaces beside the analytic
# models. Runs the commands, then prints the tables (analysis/tables_bsdf_orders.py).
#
#   analysis/tables_bsdf_orders.sh [BUILD_DIR] [OUT_DIR]
#
# BUILD_DIR holds the microsim binary (default: build/ next to this folder); results go to
# OUT_DIR (default: BUILD_DIR/tables_bsdf_orders). Runs are skipped when their JSON exists (delete OUT_DIR to
# redo). About 40 minutes on 2 cores. SEEDS (default "1 2 3 4") sets the ensemble of tiles
# for the mirror table; RAYS_SCALE (default 1) multiplies every ray count.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
build="${1:-$root/build}"
out="${2:-$build/tables_bsdf_orders}"
M="$build/microsim"
seeds="${SEEDS:-1 2 3 4}"
scale="${RAYS_SCALE:-1}"
rays() { /usr/bin/python3 -c "print(int($1 * $scale))"; }
mkdir -p "$out"
# The tables of docs/findings/multiple-scattering.md were made on 4 cells per correlation length (CELLS_PER_L, default 4;
# 16 is the converged grid, analysis/converged_models.sh re-measures the model statements there).
ell=$(/usr/bin/python3 -c "print(repr(${CELLS_PER_L:-4} / 1024))")
[ -x "$M" ] || { echo "no microsim binary in $build (cmake --build $build --target microsim)" >&2; exit 1; }

run() {  # run JSON_PATH args...: skip when the JSON exists
  local json="$1"; shift
  if [ ! -s "$json" ]; then
    echo "+ microsim $*" >&2
    "$M" -q "$@"
  fi
}
surface() {  # surface FILE generate-args...
  local f="$1"; shift
  [ -s "$f" ] || "$M" -q generate "$@" -o "$f"
}

# 1. Flat dielectric: Fresnel exactly [GeomBSDF24, eq. 7d, 10b].
surface "$out/flat.exr" flat --resolution 16
for eta in 1.5 0.6666666666666666; do
  for th in 0 30 60 80; do
    j="$out/flat_e${eta}_t${th}.json"
    run "$j" measure bsdf "$out/flat.exr" --material dielectric --eta "$eta" --theta-i "$th" --phi-i 0 \
      --rays "$(rays 1048576)" --resolution 32 -o "$j"
  done
done

# 2. Mirror Beckmann tiles alpha 0.5 and 1.0 (1024^2, correlation length 4 cells), theta 0 and 60,
#    an ensemble of independent tiles for the between-surface error.
for a in 0.5 1.0; do
  for s in $seeds; do
    surface "$out/beckmann_a${a}_s${s}.exr" gaussian --resolution 1024 --correlation-length "$ell" --alpha "$a" --seed "$s"
    for th in 0 60; do
      j="$out/mirror_a${a}_s${s}_t${th}.json"
      run "$j" measure bsdf "$out/beckmann_a${a}_s${s}.exr" --material mirror --theta-i "$th" --phi-i 0 \
        --rays "$(rays 1048576)" --resolution 32 -o "$j"
    done
  done
done

# 3. [Heitz14, Table 4]: in-plane lobes at grazing incidence theta = 1.5 rad, on the same ensemble of
#    tiles (at grazing incidence few facets are lit: one tile's lobe differs from the next by
#    far more than the ray-count error, so the comparison uses the between-surface error).
th15=$(/usr/bin/python3 -c "import math; print(repr(math.degrees(1.5)))")
for a in 0.1 0.4 0.7 1.0 1.3; do
  for s in $seeds; do
    surface "$out/beckmann_a${a}_s${s}.exr" gaussian --resolution 1024 --correlation-length "$ell" --alpha "$a" --seed "$s"
    j="$out/table4_a${a}_s${s}.json"
    run "$j" measure bsdf "$out/beckmann_a${a}_s${s}.exr" --material mirror --theta-i "$th15" --phi-i 0 \
      --rays "$(rays 4194304)" --resolution 32 -o "${j%.json}.exr"
  done
done

# 4. Dielectric Beckmann alpha 0.5, eta 1.5 and 1/1.5. Incidence angles at centers of the 32
#    in-plane bins (5.625 deg wide): 53.4375 (bin 25), 30.9375 (bin 21), 14.0625 (bin 19), so
#    that reversed paths read the same bins. Light from below = light from above on the tile
#    seen from below (flip_heightfield.py) with the inverse index.
S="$out/beckmann_a0.5_s1.exr"
F="$out/beckmann_a0.5_s1_flipped.exr"
[ -s "$F" ] || /usr/bin/python3 "$here/flip_heightfield.py" "$S" "$F"
inv=0.6666666666666666
d() {  # d NAME SURFACE ETA THETA PHI
  local j="$out/diel_$1.json"
  run "$j" measure bsdf "$2" --material dielectric --eta "$3" --theta-i "$4" --phi-i "$5" \
    --rays "$(rays 4194304)" --resolution 32 -o "${j%.json}.exr"
}
for s in $seeds; do                       # lobes on the ensemble of tiles
  surface "$out/beckmann_a0.5_s${s}.exr" gaussian --resolution 1024 --correlation-length "$ell" --alpha 0.5 --seed "$s"
  d e1.5_t53_p0_s$s "$out/beckmann_a0.5_s${s}.exr" 1.5 53.4375 0   # glass below: 53.4 -> ~32 deg
  d e${inv}_t31_p0_s$s "$out/beckmann_a0.5_s${s}.exr" "$inv" 30.9375 0   # less dense below: 30.9 -> ~50 deg
done
d e1.5_t14_p0 "$S" 1.5 14.0625 0          # reflection reciprocity partner
d e1.5_t53_p180 "$S" 1.5 53.4375 180      # reverse of the reflection path 14 -> 53
d flip_e${inv}_t31_p180 "$F" "$inv" 30.9375 180   # reverse of the transmission path (from below)
d flip_e1.5_t53_p180 "$F" 1.5 53.4375 180 # reverse of that transmission path (from below)

/usr/bin/python3 "$here/tables_bsdf_orders.py" "$out"

# 5. Performance: random-walk rays/s against a bare Embree loop.
if [ -x "$build/microsim_bench_bsdf" ]; then
  echo
  echo "== Performance (bench/bench_bsdf.cpp, 1024^2 Gaussian tile, 500000 paths per row)"
  "$build/microsim_bench_bsdf" 1024 500000
fi
