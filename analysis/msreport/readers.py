"""Reading microsim outputs: JSON records and EXR tables.

Field access is tolerant: a record written by an older or newer microsim may lack a field, and
the plots skip what is missing instead of failing. The field names are those documented in
docs/reference/records.md and docs/reference/file-formats.md:
  measure g1     rows: theta_deg, phi_deg, g1, g1_stderr, g1_raycast, g1_raycast_stderr,
                 visible_area_ratio(_stderr), smith_numeric, smith_nominal, bins[...]
  measure ndf    .exr channels D, D_stderr, D_nominal; .json rows theta_lo_deg, theta_hi_deg,
                 d, d_stderr, d_nominal
  measure g2     rows: theta_o_deg, phi_o_deg, theta_i_deg, phi_i_deg, g2, g2_stderr,
                 smith_separable, smith_height_correlated, smith_height_direction_correlated,
                 (smith_direction_correlated), vcavity, bins[...]
  measure bsdf   albedo {reflected, transmitted: {order_1, order_2, order_3, order_4plus, total}},
                 reflected_stderr, transmitted_stderr; in_plane rows: theta_o_deg (signed),
                 f_order_1(_stderr), f_total(_stderr), smith_single, vcavity_single,
                 smith_multiple(_order_k), vgroove_multiple(_order_k),
                 vcavity_multiple(_order_k)(_stderr), vcavity_multiple_grooves(_order_k)(_stderr);
                 several incidences: the same fields per object of `incidences`
  validate       rows: quantity, model_name, condition, entry, kind, measured, stderr, model, z,
                 rel_dev, verdict, group, ...; entries[].measurements per check
"""
import json
import math
import os

import numpy as np


def load_json(path):
    with open(path) as f:
        return json.load(f)


def num(x, default=float("nan")):
    """A JSON number as float; null, missing or non-numbers become `default` (NaN)."""
    if isinstance(x, bool) or x is None:
        return default
    if isinstance(x, (int, float)):
        return float(x)
    return default


def column(rows, key):
    """numpy array of rows[i][key] (NaN where missing or null)."""
    return np.array([num(r.get(key)) if isinstance(r, dict) else float("nan") for r in rows])


def has_field(rows, key):
    return any(isinstance(r, dict) and num(r.get(key)) == num(r.get(key)) for r in rows)


def read_exr(path):
    """An EXR table: (dict channel name -> 2D float array [row, col], dict of header attributes).

    Uses OpenImageIO. Rows are the y axis of the file (top row first), as microsim writes them.
    """
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise IOError("cannot open %s: %s" % (path, oiio.geterror()))
    try:
        spec = inp.spec()
        pixels = inp.read_image(format="float")
        if pixels is None:
            raise IOError("cannot read %s: %s" % (path, inp.geterror()))
        pixels = np.asarray(pixels).reshape(spec.height, spec.width, spec.nchannels)
        channels = {name: pixels[:, :, c] for c, name in enumerate(spec.channelnames)}
        attrs = {}
        for p in spec.extra_attribs:
            attrs[p.name] = p.value
        return channels, attrs
    finally:
        inp.close()


def exists(path):
    return path is not None and os.path.isfile(path) and os.path.getsize(path) > 0


def finite(x):
    return x is not None and isinstance(x, (int, float)) and math.isfinite(x)
