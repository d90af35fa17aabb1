#!/usr/bin/python3
"""Writes the surface seen from below: a microsim heightfield EXR with its heights negated.

Light arriving from below a surface is light arriving from above the flipped surface (z -> -z),
with the inverse relative index: this is how tables_bsdf_orders.sh measures the reciprocity of
transmission with a command that takes incidence from above only.

usage: flip_heightfield.py IN.exr OUT.exr
"""
import json
import sys

import numpy as np
import OpenImageIO as oiio


def main(src, dst):
    inp = oiio.ImageInput.open(src)
    if inp is None:
        sys.exit(f"flip_heightfield: cannot read {src}")
    spec = inp.spec()
    pixels = inp.read_image(oiio.FLOAT)
    inp.close()
    names = list(spec.channelnames)
    if "Z" not in names or spec.getattribute("microsim_surface") != "heightfield":
        sys.exit(f"flip_heightfield: {src} is not a microsim heightfield")
    pixels = np.array(pixels, dtype=np.float32).reshape(spec.height, spec.width, spec.nchannels)
    pixels[:, :, names.index("Z")] *= -1.0
    out_spec = oiio.ImageSpec(spec)
    out_spec.set_format(oiio.FLOAT)
    desc = json.loads(spec.getattribute("microsim_description"))
    desc["flipped"] = not desc.get("flipped", False)
    desc["flipped_from"] = src
    out_spec.attribute("microsim_description", json.dumps(desc))
    out = oiio.ImageOutput.create(dst)
    if out is None or not out.open(dst, out_spec):
        sys.exit(f"flip_heightfield: cannot write {dst}")
    out.write_image(pixels)
    out.close()


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
