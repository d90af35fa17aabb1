#!/bin/bash
# ctest -R install_tree: `cmake --install` into a temporary prefix, then, with the build tree's
# image-reader module hidden (as if the build folder had been moved or removed), from the prefix
# alone: the program imports a PNG and an EXR heightmap, an outside project (tests/package_consumer)
# builds against the installed package and reads the PNG through the library, and the installed
# Python package imports the PNG.
#   install_tree.sh BUILD_DIR MODULE SOURCE_DIR WORK_DIR PYTHON PYTHON_INSTALL_DIR CXX [LAUNCHER]
# MODULE: the build tree's image-reader module (hidden while the install tree runs).
# PYTHON_INSTALL_DIR: the package's folder relative to the prefix, or "" when the module is not
# built. The test runs alone (RUN_SERIAL): while the module is hidden, the build tree's programs
# cannot read images.
set -euo pipefail
build=$1 module=$2 source=$3 work=$4 python=$5 pydir=$6 cxx=$7 launcher=${8:-}
hidden=$module.hidden-by-install-tree
# A run killed while the module was hidden left it renamed: put it back first.
if [ -e "$hidden" ] && [ ! -e "$module" ]; then mv "$hidden" "$module"; fi
[ -e "$module" ] || { echo "no $module: build the program first" >&2; exit 1; }

rm -rf "$work"
mkdir -p "$work"
prefix=$work/prefix
step() { echo "--- $*"; }

step "cmake --install into $prefix"
cmake --install "$build" --prefix "$prefix" > "$work/install.log"
for f in bin/microsim lib/microsim/libmicrosim_oiio_reader.so lib/cmake/microsim/microsimConfig.cmake; do
  [ -e "$prefix/$f" ] || { echo "not installed: $f" >&2; exit 1; }
done

mv "$module" "$hidden"
trap 'mv "$hidden" "$module"' EXIT

step "heightmaps: a 16-bit PNG written with OpenImageIO, an EXR tile written by the program"
cd "$work"
"$python" - <<'PY'
import numpy as np, OpenImageIO as oiio
y, x = np.mgrid[0:64, 0:64] * (2 * np.pi / 64)
z = np.sin(x) * np.cos(2 * y) + 0.3 * np.sin(3 * x + y)  # periodic over the 64 pixels
counts = np.round((z - z.min()) / np.ptp(z) * 60000).astype(np.uint16)
out = oiio.ImageOutput.create("height.png")
out.open("height.png", oiio.ImageSpec(64, 64, 1, "uint16"))
out.write_image(counts)
out.close()
PY
"$prefix/bin/microsim" -q generate gaussian --resolution 64 --alpha 0.5 --seed 1 -o height.exr

step "installed program: generate heightmap from the PNG and the EXR, then info"
for img in height.png height.exr; do
  "$prefix/bin/microsim" -q generate heightmap --input "$img" --pixel-size 1 --length-unit um \
    --height-scale 1e-4 --periodic -o "$img-tile.exr"
  "$prefix/bin/microsim" info "$img-tile.exr" --json "$img-info.json" > /dev/null
  [ -s "$img-info.json" ] && echo "$img: imported, info written"
done

step "outside project against the installed package (CMAKE_PREFIX_PATH = the prefix only)"
launch=()
[ -n "$launcher" ] && launch=(-DCMAKE_CXX_COMPILER_LAUNCHER="$launcher")
cmake -S "$source/tests/package_consumer" -B "$work/consumer" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CXX_COMPILER="$cxx" "${launch[@]}" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF > "$work/consumer-configure.log"
cmake --build "$work/consumer" > "$work/consumer-build.log"
"$work/consumer/consumer" height.png

if [ -n "$pydir" ]; then
  step "installed Python package: import microsim, import the PNG"
  PYTHONPATH="$prefix/$pydir" "$python" - "$prefix" <<'PY'
import os, sys
import microsim
prefix = os.path.realpath(sys.argv[1])
assert os.path.realpath(microsim.__file__).startswith(prefix + os.sep), microsim.__file__
s = microsim.generate("heightmap", input="height.png", pixel_size=1, length_unit="um",
                      height_scale=1e-4, periodic=True)
print("import microsim:", microsim.__file__, "surface", s)
PY
else
  step "no Python module in this build: its install is not checked"
fi
echo "install tree ok"
