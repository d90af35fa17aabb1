#!/usr/bin/env bash
# Discretization study of Gaussian heightfields: every level of the two sweeps, each an ensemble
# of independent tiles (between-surface errors), then the table and the figures
# (analysis/convergence.py). A long run, not a test.
#
#   analysis/convergence.sh [BUILD_DIR] [OUT_DIR]
#
# Needs `cmake --build BUILD_DIR --target convergence`. Results go to OUT_DIR (default
# BUILD_DIR/convergence_study); a level is skipped when its JSON exists (delete it to redo).
# Environment (defaults in brackets):
#   KINDS ["gaussian:1.0"]  surfaces, kind:alpha, e.g. "gaussian:1.0 gaussian:0.5 gaussian:0.2 gaussian-ggx:0.5"
#   CELLS ["2 4 8 16 32"]   sweep 1: cells per correlation length l, at L/l = FIXED_TILE [32]
#   TILES ["16 32 64 128 256"] sweep 2: correlation lengths per tile L/l, at FIXED_CELLS [8] cells per l
#   RAYS_BSDF [2000000]     paths per BSDF configuration and level (split over the tiles)
#   RAYS_G [1000000]        rays per G1/G2/VNDF direction and level
#   SMITH_WALKS [4000000]   Smith random walks per incidence (once per surface kind)
#   SURFACES [16, 8, 4, 3 tiles at L/l <= 16, 32, 64, more]  tiles per level
#   NICE [10]               niceness of the runs
#   SWEEP [both]            cells, tiles or both; NO_TABLE=1: runs only
# The cost of every level (CPU seconds, peak resident memory) is read from /usr/bin/time -v.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
build="${1:-$root/build}"
out="${2:-$build/convergence_study}"
B="$build/convergence"
[ -x "$B" ] || { echo "no convergence binary in $build (cmake --build $build --target convergence)" >&2; exit 1; }
mkdir -p "$out"
kinds="${KINDS:-gaussian:1.0}"
cells="${CELLS:-2 4 8 16 32}"
tiles="${TILES:-16 32 64 128 256}"
fixed_tile="${FIXED_TILE:-32}"
fixed_cells="${FIXED_CELLS:-8}"
rays_bsdf="${RAYS_BSDF:-2000000}"
rays_g="${RAYS_G:-1000000}"
smith="${SMITH_WALKS:-4000000}"
niceness="${NICE:-10}"

# Tiles per level: enough for a between-surface error, fewer on big tiles (their tile-to-tile
# spread is smaller: it scales like l / L). The grid sweep's tiles share their random numbers
# across grids (convergence.cpp): its differences between levels are paired, tile by tile.
surfaces_for() {
  local t="$1"
  if [ -n "${SURFACES:-}" ]; then echo "$SURFACES"; return; fi
  if [ "$t" -le 16 ]; then echo 16; elif [ "$t" -le 32 ]; then echo 8; elif [ "$t" -le 64 ]; then echo 4; else echo 3; fi
}

level() {  # level KIND ALPHA CELLS TILE [extra args]
  local kind="$1" a="$2" c="$3" t="$4"; shift 4
  local name="${kind}_a${a}_c${c}_t${t}"
  local j="$out/$name.json"
  [ -s "$j" ] && return 0
  local k; k=$(surfaces_for "$t")
  echo "+ $name: $((c * t))^2 cells, $k tiles" >&2
  /usr/bin/time -v -o "$out/$name.time" nice -n "$niceness" "$B" --kind "$kind" --alpha "$a" \
    --cells-per-l "$c" --lengths-per-tile "$t" --surfaces "$k" --rays-bsdf "$rays_bsdf" \
    --rays-g "$rays_g" "$@" -o "$j" 2> "$out/$name.log"
}

sweep="${SWEEP:-both}"  # cells, tiles or both (two instances with cells and tiles may run at once)
for ka in $kinds; do
  kind="${ka%%:*}"; a="${ka##*:}"
  if [ "$sweep" != tiles ]; then
    first=1
    for c in $cells; do
      if [ $first = 1 ]; then level "$kind" "$a" "$c" "$fixed_tile" --smith-walks "$smith"; first=0
      else level "$kind" "$a" "$c" "$fixed_tile"; fi
    done
  fi
  if [ "$sweep" != cells ]; then
    for t in $tiles; do
      # The level shared with the grid sweep is that sweep's (skip it when both run at once).
      [ "$sweep" = tiles ] && [ "$t" = "$fixed_tile" ] && echo " $cells " | grep -q " $fixed_cells " && continue
      level "$kind" "$a" "$fixed_cells" "$t"
    done
  fi
done
[ "${NO_TABLE:-0}" = 1 ] && exit 0

/usr/bin/python3 "$here/convergence.py" "$out" --fixed-tile "$fixed_tile" --fixed-cells "$fixed_cells"
