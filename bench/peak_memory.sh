#!/bin/bash
# Benchmark (not a test): peak resident memory and processor time of each command on Beckmann
# alpha = 0.5 tiles at the default correlation length, from /usr/bin/time -v (whole process).
#   bench/peak_memory.sh [-b build/microsim] [-d DIR] [-t THREADS] [resolution...]
# (default 1024 4096 8192; 16384 needs about 10 GB and a quarter of an hour of processor time).
# Per tile: generate gaussian, info, measure g1 --theta 60 --rays 100000, measure ndf (default
# bins), measure bsdf --material mirror --theta-i 30 --rays 20000 --no-models. Prints one line
# per command: peak MiB, bytes per facet (2 facets per cell), user + system seconds, wall.
# The tile file is deleted after its commands ran (1 GB at 16384^2).
set -euo pipefail
bin="$(dirname "$0")/../build/microsim"
dir="$(mktemp -d -t microsim_peak.XXXXXX)"
threads=2
while getopts "b:d:t:" o; do
  case $o in
    b) bin=$OPTARG ;;
    d) dir=$OPTARG ;;
    t) threads=$OPTARG ;;
    *) echo "usage: $0 [-b microsim] [-d dir] [-t threads] [resolution...]" >&2; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
resolutions=("${@:-1024 4096 8192}")
[ -x /usr/bin/time ] || { echo "needs /usr/bin/time (apt-get install time)" >&2; exit 2; }
mkdir -p "$dir"
printf "%-9s %-9s %10s %9s %10s %10s\n" tile command peak_MiB B/facet cpu_s wall
for n in ${resolutions[@]}; do
  f="$dir/tile$n.exr"
  for c in generate info g1 ndf bsdf; do
    case $c in
      generate) args=(generate gaussian --resolution "$n" --alpha 0.5 --seed 1 -o "$f") ;;
      info) args=(info "$f" --json "$dir/info$n.json") ;;
      g1) args=(measure g1 "$f" --theta 60 --rays 100000 -o "$dir/g1_$n.json") ;;
      ndf) args=(measure ndf "$f" -o "$dir/ndf_$n.json") ;;
      bsdf) args=(measure bsdf "$f" --material mirror --theta-i 30 --rays 20000 --no-models -o "$dir/bsdf_$n.json") ;;
    esac
    /usr/bin/time -v -o "$dir/time.txt" "$bin" -q --threads "$threads" "${args[@]}" > /dev/null
    awk -v n="$n" -v c="$c" '
      /Maximum resident/ { kb = $NF }
      /User time/ { u = $NF }
      /System time/ { s = $NF }
      /Elapsed/ { w = $NF }
      END { printf "%5d^2   %-9s %10.0f %9.2f %10.1f %10s\n", n, c, kb / 1024, kb * 1024 / (2 * n * n), u + s, w }' \
      "$dir/time.txt"
  done
  rm -f "$f"
done
