#!/usr/bin/env bash
# BSDF albedos of finite objects and V-grooves beside their exact values and closed forms:
# mirror box H/W = 0.5 (total albedo vs the visible area ratio 1 + (H/W) tan theta_i), tiled
# boxes N = 1..16, periodic V-grooves (facet angles 45, 60, 70 deg; several theta_i, phi_i) per
# order vs the closed form, and a V-cavity ensemble (Beckmann alpha 0.5) vs the V-cavity
# multiple-scattering model and the Smith random walk. Prints the tables
# (analysis/objects_grooves_tables.py).
#
#   analysis/objects_grooves_tables.sh [BUILD_DIR] [OUT_DIR]
#
# Runs are skipped when their JSON exists. About 5 minutes on 2 cores.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
build="${1:-$root/build}"
out="${2:-$build/objects_grooves}"
M="$build/microsim"
mkdir -p "$out"
[ -x "$M" ] || { echo "no microsim binary in $build (cmake --build $build --target microsim)" >&2; exit 1; }
run() { local json="$1"; shift; [ -s "$json" ] || { echo "+ microsim $*" >&2; "$M" -q "$@"; }; }
surface() { local f="$1"; shift; [ -s "$f" ] || "$M" -q generate "$@" -o "$f"; }

surface "$out/box.ply" box --height 0.5
for th in 0 30 60; do
  run "$out/box_$th.json" measure bsdf "$out/box.ply" --material mirror --theta-i $th --phi-i 0 --rays 1000000 -o "$out/box_$th.json"
done
for n in 1 2 4 8 16; do
  surface "$out/tiled_$n.ply" tiled-boxes --height 0.5 --tiles $n
  run "$out/tiled_${n}_60.json" measure bsdf "$out/tiled_$n.ply" --material mirror --theta-i 60 --phi-i 0 --rays 1000000 --resolution 16 -o "$out/tiled_${n}_60.json"
done
for tf in 45 60 70; do
  surface "$out/vgroove_$tf.exr" vgroove --facet-angle $tf
  for th in 0 20 45 70; do for ph in 0 30 60; do
    run "$out/vgroove_${tf}_${th}_${ph}.json" measure bsdf "$out/vgroove_$tf.exr" --material mirror --theta-i $th --phi-i $ph --rays 200000 -o "$out/vgroove_${tf}_${th}_${ph}.json"
  done; done
done
surface "$out/vcavity.ply" vcavity --alpha 0.5
for th in 0 30 60 80; do
  run "$out/vcavity_$th.json" measure bsdf "$out/vcavity.ply" --material mirror --theta-i $th --phi-i 0 --rays 1000000 --resolution 32 -o "$out/vcavity_$th.json"
done
/usr/bin/python3 "$here/objects_grooves_tables.py" "$out"
