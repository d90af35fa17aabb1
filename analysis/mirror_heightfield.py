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


def main(src, dst):
    inp = oiio.ImageInput.open(src)
    if inp is None:
        sys.exit(f"mirror_heightfield: cannot read {src}")
    spec = inp.spec()
    pixels = inp.read_image(oiio.FLOAT)
    inp.close()
    if "Z" not in list(spec.channelnames) or spec.getattribute("microsim_surface") != "heightfield":
        sys.exit(f"mirror_heightfield: {src} is not a microsim heightfield")
    pixels = np.array(pixels, dtype=np.float32).reshape(spec.height, spec.width, spec.nchannels)
    # x is the image's column index: column i -> (N - i) mod N keeps sample 0 in place
    pixels = np.roll(pixels[:, ::-1, :], 1, axis=1)
    out_spec = oiio.ImageSpec(spec)
    out_spec.set_format(oiio.FLOAT)
    desc = json.loads(spec.getattribute("microsim_description"))
    desc["mirrored_x"] = not desc.get("mirrored_x", False)
    desc["mirrored_from"] = src
    out_spec.attribute("microsim_description", json.dumps(desc))
    out = oiio.ImageOutput.create(dst)
    if out is None or not out.open(dst, out_spec):
        sys.exit(f"mirror_heightfield: cannot write {dst}")
    out.write_image(pixels)
    out.close()


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
