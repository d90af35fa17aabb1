#!/usr/bin/python3
"""Writes a microsim heightfield EXR mirrored in x: sample (i, j) <- sample ((N - i) mod N, j).

microsim splits heightfield cell (i, j) along its (i+1, j)-(i, j+1) diagonal. The mirrored tile
holds the same heights, so measured at the mirrored incidence (phi_i -> 180 deg - phi_i) it is the
same surface split along the other diagonal, (i, j)-(i+1, j+1): the difference of the two runs
(paired, same tile) is the effect of the triangulation alone. Periodic tiles only.

usage: mirror_heightfield.py IN.exr OUT.exr
"""
import json
import sys

import numpy as np
import OpenImageIO as oiio

from flip_heightfield import rewrite_heightfield


def mirror_x(pixels, names):
    # x is the image's column index: column i -> (N - i) mod N keeps sample 0 in place
    return np.roll(pixels[:, ::-1, :], 1, axis=1)


def main(src, dst):
    rewrite_heightfield(src, dst, "mirror_heightfield", mirror_x, "mirrored_x", "mirrored_from")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
