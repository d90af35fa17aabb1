#!/bin/bash
# Every command that writes, with every kind of output, on a nearly full disk: each run must exit
# non-zero and leave nothing behind (no output, no temporary, no partial file, no empty sidecar,
# no folder it created).
#
#   tests/full_disk.sh MICROSIM
#
# The disk is a small tmpfs mounted in a private mount namespace (unshare -m), filled by one file
# so that only a few pages stay free: none, half of what the command writes, and all of it but
# the last page (so that the writes fail midway, and for a set of outputs at its last file).
# Each command first runs on the ordinary disk to learn the size of what it writes.
# Exits 77 (CTest SKIP_RETURN_CODE) where private mount namespaces or tmpfs mounts are not
# permitted; prints one line per run and exits 1 if any run exited 0 or left a file.
set -u

microsim=$(readlink -f "$1")

if [ -z "${MICROSIM_FULL_DISK_NAMESPACE:-}" ]; then
  if ! unshare -m --propagation private true 2>/dev/null; then
    echo "SKIP: no private mount namespace here (unshare -m is not permitted); the full-disk runs need one"
    exit 77
  fi
  MICROSIM_FULL_DISK_NAMESPACE=1 exec unshare -m --propagation private bash "$0" "$microsim"
fi

work=$(mktemp -d "${TMPDIR:-/tmp}/microsim-full-disk-XXXXXX")
disk=$work/disk
in=$work/inputs
scratch=$work/scratch
mkdir -p "$disk" "$in" "$scratch"
cleanup() {
  umount "$disk" 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT
if ! mount -t tmpfs -o size=64k tmpfs "$disk" 2>/dev/null; then
  echo "SKIP: tmpfs cannot be mounted here (mount -t tmpfs is not permitted); the full-disk runs need it"
  exit 77
fi
umount "$disk"

ms() { "$microsim" -q "$@"; }

# Inputs, on the ordinary disk.
setup() {
  ms generate gaussian --resolution 64 --alpha 0.5 -o "$in/g.exr" &&
    ms generate box -o "$in/box.ply" &&
    ms measure bsdf "$in/g.exr" --material mirror --theta-i 30 --rays 5000 --resolution 8 -o "$in/t.bsdf" &&
    ms measure g1 "$in/g.exr" --theta 0,60 --rays 4000 --replicates 4 --shard 1/2 -o "$in/m.json" &&
    ms measure g1 "$in/g.exr" --theta 0,60 --rays 4000 --replicates 4 --shard 2/2 -o "$in/m.json" &&
    for j in $(seq 0 23); do
      row=""
      for i in $(seq 0 23); do row+="${row:+,}0.0$(( (i * 7 + j * 13) % 10 ))"; done
      echo "$row"
    done >"$in/h.csv"
}
if ! setup >"$work/setup.log" 2>&1; then
  echo "FAIL: the inputs could not be made:"
  cat "$work/setup.log"
  exit 1
fi

G=$in/g.exr
# name | command line (run in the folder it writes to; outputs are named relative to it)
cases=(
  "generate gaussian .exr|generate gaussian --resolution 128 --alpha 0.5 -o o.exr"
  "generate gaussian .ply + sidecar|generate gaussian --resolution 32 --alpha 0.5 -o o.ply"
  "generate tiled-boxes .ply + sidecar|generate tiled-boxes --tiles 8 -o o.ply"
  "generate box .obj + sidecar|generate box -o o.obj"
  "generate ellipsoid .off + sidecar|generate ellipsoid --alpha 0.5 -o o.off"
  "generate vcavity .ply + sidecar|generate vcavity --alpha 0.5 -o o.ply"
  "generate square-wave .ply + sidecar|generate square-wave --2d -o o.ply"
  "generate heightmap .exr|generate heightmap --input $in/h.csv --pixel-size 1 --periodic -o o.exr"
  "generate mesh .ply + sidecar|generate mesh --input $in/box.ply -o o.ply"
  "convert .exr -> .obj + sidecar|convert $G -o o.obj"
  "convert .exr -> .ply + sidecar|convert $G -o o.ply"
  "convert .ply -> .off + sidecar|convert $in/box.ply -o o.off"
  "convert .exr -> .exr|convert $G -o o.exr"
  "info --json|info $G --json o.json"
  "measure ndf .json|measure ndf $G -o o.json"
  "measure ndf .csv|measure ndf $G -o o.csv"
  "measure ndf .exr|measure ndf $G -o o.exr"
  "measure g1 .json|measure g1 $G --theta 0,30,60 --rays 2000 -o o.json"
  "measure g1 .csv|measure g1 $G --theta 0:80:5 --rays 2000 -o o.csv"
  "measure g1 --shard record|measure g1 $G --theta 0,60 --rays 4000 --replicates 4 --shard 1/2 -o o.json"
  "measure g2 .json|measure g2 $G --theta-o 30 --theta-i 30 --rays 2000 -o o.json"
  "measure g2 .csv|measure g2 $G --theta-o 30 --theta-i 30 --rays 2000 -o o.csv"
  "measure vndf .json|measure vndf $G --theta 30 --rays 2000 -o o.json"
  "measure vndf .csv|measure vndf $G --theta 30 --rays 2000 -o o.csv"
  "measure bsdf .json|measure bsdf $G --material mirror --theta-i 30 --rays 2000 --resolution 8 -o o.json"
  "measure bsdf .exr + record|measure bsdf $G --material mirror --theta-i 30 --rays 2000 --resolution 8 -o o.exr"
  "measure bsdf .bsdf + record|measure bsdf $G --material mirror --theta-i 30 --rays 2000 --resolution 8 -o o.bsdf"
  "measure bsdf .binary + record|measure bsdf $G --material mirror --theta-i 0,40 --rays 2000 --resolution 8 -o o.binary"
  "measure albedo .json|measure albedo $G --material mirror --mu-nodes 3 --rays 2000 -o o.json"
  "measure albedo .csv + record|measure albedo $G --material mirror --mu-nodes 3 --rays 2000 -o o.csv"
  "measure albedo .exr + rows + record|measure albedo $G --material mirror --mu-nodes 3 --rays 2000 -o o.exr"
  "merge .json|merge $in/m.json.shard-1-of-2.json $in/m.json.shard-2-of-2.json -o o.json"
  "render .png|render $in/t.bsdf --size 32 --samples 2 -o o.png"
  "render .exr|render $in/t.bsdf --size 16 --samples 2 -o o.exr"
  "render .json|render $in/t.bsdf --size 16 --samples 2 -o o.json"
  "render .png + .exr + .json|render $in/t.bsdf --size 16 --samples 2 -o o.png -o o.exr -o o.json"
  "validate .json|validate $G --rays 2000 -o o.json"
  "validate .csv|validate $G --rays 2000 -o o.csv"
  "validate --suite --surfaces-dir + .json|validate --suite smoke --rays 2000 --surfaces-dir sd -o o.json"
  "demo --out-dir|demo --resolution 64 --theta 0,60 --rays 2000 --out-dir d"
)

page=4096
pages() { echo $(( ($1 + page - 1) / page )); }

# What the command wrote in folder $1: "FILES BYTES PAGES" (PAGES: the tmpfs pages it takes).
written() {
  local files=0 bytes=0 p=0 size
  while IFS= read -r size; do
    files=$((files + 1))
    bytes=$((bytes + size))
    p=$((p + $(pages "$size")))
  done < <(find "$1" -mindepth 1 -type f ! -name .fill -printf '%s\n')
  echo "$files $bytes $p"
}

# Files and folders left on the disk besides the filling, one per line.
leftovers() { find "$disk" -mindepth 1 ! -name .fill -printf '%P (%s bytes)\n'; }

failures=0
runs=0
printf '%-44s %-14s %4s  %s\n' "command" "free" "exit" "left on the disk"
for c in "${cases[@]}"; do
  name=${c%%|*}
  cmdline=${c#*|}
  rm -rf "$scratch" && mkdir -p "$scratch"
  if ! (cd "$scratch" && eval ms "$cmdline") >"$work/sizing.log" 2>&1; then
    echo "FAIL: $name does not run on the ordinary disk:"
    cat "$work/sizing.log"
    failures=$((failures + 1))
    continue
  fi
  read -r files bytes total_pages < <(written "$scratch")
  half=$(( bytes / 2 / page ))
  all_but_last=$(( total_pages - 1 ))
  for free_pages in $(printf '%s\n' 0 "$half" "$all_but_last" | sort -nu); do
    size_kb=$(( (total_pages + 16) * page / 1024 ))
    mount -t tmpfs -o "size=${size_kb}k" tmpfs "$disk" || exit 1
    fallocate -l $(( (total_pages + 16 - free_pages) * page )) "$disk/.fill" || exit 1
    (cd "$disk" && eval ms "$cmdline") >"$work/run.log" 2>&1
    code=$?
    left=$(leftovers)
    one_line=$(grep -c '' "$work/run.log")
    verdict=ok
    if [ "$code" -eq 0 ] || [ -n "$left" ]; then verdict=FAIL; fi
    # The failure is reported by one line naming the file.
    if [ "$code" -ne 0 ] && ! grep -q '^microsim: failed: cannot write ' "$work/run.log"; then verdict=FAIL; fi
    if [ "$code" -ne 0 ] && [ "$one_line" -ne 1 ]; then verdict=FAIL; fi
    printf '%-44s %-14s %4s  %s\n' "$name" "$((free_pages * page / 1024)) KiB of $((bytes / 1024))" "$code" \
      "$([ -n "$left" ] && echo "$left" | tr '\n' ' ' || echo nothing) $([ "$verdict" = FAIL ] && echo "<- FAIL: $(head -c 200 "$work/run.log")")"
    runs=$((runs + 1))
    [ "$verdict" = FAIL ] && failures=$((failures + 1))
    umount "$disk"
  done
done
echo "$runs runs, $failures failed"
[ "$failures" -eq 0 ]
