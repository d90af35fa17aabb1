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


def rewrite_heightfield(src, dst, tool, transform, flag, source_key):
    """Reads a microsim heightfield EXR, applies transform(pixels, channel_names) and writes it
    with `flag` toggled and `source_key` = src in its description."""
    inp = oiio.ImageInput.open(src)
    if inp is None:
        sys.exit(f"{tool}: cannot read {src}")
    spec = inp.spec()
    pixels = inp.read_image(oiio.FLOAT)
    inp.close()
    names = list(spec.channelnames)
    if "Z" not in names or spec.getattribute("microsim_surface") != "heightfield":
        sys.exit(f"{tool}: {src} is not a microsim heightfield")
    pixels = np.array(pixels, dtype=np.float32).reshape(spec.height, spec.width, spec.nchannels)
    pixels = transform(pixels, names)
    out_spec = oiio.ImageSpec(spec)
    out_spec.set_format(oiio.FLOAT)
    desc = json.loads(spec.getattribute("microsim_description"))
    desc[flag] = not desc.get(flag, False)
    desc[source_key] = src
    out_spec.attribute("microsim_description", json.dumps(desc))
    out = oiio.ImageOutput.create(dst)
    if out is None or not out.open(dst, out_spec):
        sys.exit(f"{tool}: cannot write {dst}")
    out.write_image(pixels)
    out.close()


def negate_heights(pixels, names):
    pixels[:, :, names.index("Z")] *= -1.0
    return pixels


def main(src, dst):
    rewrite_heightfield(src, dst, "flip_heightfield", negate_heights, "flipped", "flipped_from")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
