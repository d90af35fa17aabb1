#!/usr/bin/env python3
"""A .pbsdf written by `measure bsdf --polarized -o X.pbsdf` holds the record's per-bin Mueller BSDF.

Written from the format's description (docs/guide/pbsdf.md), not from microsim's writer: it reads
the RGL tensor file, rebuilds each node's pair of directions (light l, view v) from its angles
(theta_h, theta_d, phi_d), reads the record's matrices (polarization.bins of every incidence) for
that pair, bilinear between pixel centres of the equal-area map and linear in theta_i, converts
them from microsim's Stokes frames (axis normalize(z x w) of each direction) to the frames Mitsuba
3's measured_polarized builds for the pair, and compares with the stored block (float32).

--run MICROSIM: first writes a small table with that program (a Gaussian tile, gold at the five
default wavelengths, theta_i 0:80:20, one azimuth) into a temporary directory and checks it.

--power: the same comparison with a deliberately wrong table (every block transposed, or the
frames left unconverted, or the rotation's sign flipped) must fail; the run fails otherwise.
numpy only (/usr/bin/python3).
"""
import argparse
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile

import numpy as np

DTYPES = {3: np.uint16, 10: np.float32}


def read_tensor_file(path):
    """{name: ndarray} of an RGL tensor file: magic, version 1.0, the field table, the data."""
    b = open(path, "rb").read()
    if b[:12] != b"tensor_file\0" or b[12] != 1 or b[13] != 0:
        raise ValueError(path + ": not a tensor file of version 1.0")
    (n,) = struct.unpack_from("<I", b, 14)
    pos, out = 18, {}
    for _ in range(n):
        (length,) = struct.unpack_from("<H", b, pos)
        name = b[pos + 2:pos + 2 + length].decode()
        pos += 2 + length
        ndim, dtype, offset = struct.unpack_from("<HBQ", b, pos)
        pos += 11
        shape = struct.unpack_from("<" + "Q" * ndim, b, pos)
        pos += 8 * ndim
        dt = np.dtype(DTYPES[dtype]).newbyteorder("<")
        count = int(np.prod(shape)) if ndim else 1
        out[name] = np.frombuffer(b, dtype=dt, count=count, offset=offset).reshape(shape)
    return out


def normalize(v):
    return v / np.linalg.norm(v)


def pair_of_node(theta_h, theta_d, phi_d):
    """(l, v): h at elevation theta_h in the xz plane, l and v mirrored about h, phi_d the
    azimuth of l about h measured from t = (cos theta_h, 0, -sin theta_h) toward b = y."""
    h = np.array([np.sin(theta_h), 0.0, np.cos(theta_h)])
    t = np.array([np.cos(theta_h), 0.0, -np.sin(theta_h)])
    b = np.array([0.0, 1.0, 0.0])
    p = np.cos(phi_d) * t + np.sin(phi_d) * b
    return np.cos(theta_d) * h + np.sin(theta_d) * p, np.cos(theta_d) * h - np.sin(theta_d) * p


def microsim_axis(w):
    """microsim's Stokes reference axis of a direction: normalize(z x w); (0, 1, 0) on the pole."""
    a = np.cross([0.0, 0.0, 1.0], w)
    n = np.linalg.norm(a)
    return a / n if n > 1e-12 else np.array([0.0, 1.0, 0.0])


def plugin_axes(l, v):
    """The plugin's reference axes: the incident beam travels along zi = -l with
    ti = normalize((l - v) x zi), yi = normalize(ti x zi), xi = yi x zi; the outgoing beam along
    zo = v, the same with l and v exchanged."""
    zi = -l
    ti = normalize(np.cross(l - v, zi))
    yi = normalize(np.cross(ti, zi))
    zo = v
    to = normalize(np.cross(v - l, zo))
    yo = normalize(np.cross(to, zo))
    return np.cross(yi, zi), np.cross(yo, zo)


def rotation(f, a, b, sign=1.0):
    """Stokes vector in the frame of axis b from the one of axis a (beam along f): the angle
    from a to b counterclockwise about f, s1' = cos 2x s1 + sin 2x s2, s2' = -sin 2x s1 + cos 2x s2."""
    x = sign * np.arctan2(np.dot(f, np.cross(a, b)), np.dot(a, b))
    c, s = np.cos(2 * x), np.sin(2 * x)
    return np.array([[1, 0, 0, 0], [0, c, s, 0], [0, -s, c, 0], [0, 0, 0, 1]])


def to_square(d):
    """Square coordinates (a, b) of the equal-area map: Lambert's azimuthal map to the disk,
    then the inverse of Shirley and Chiu's concentric map."""
    z = min(1.0, abs(d[2]) / np.linalg.norm(d))
    r = np.sqrt(max(0.0, 1.0 - z))
    if r == 0.0:
        return 0.0, 0.0
    phi = np.arctan2(d[1], d[0])
    if phi < -0.25 * np.pi:
        phi += 2 * np.pi
    if phi < 0.25 * np.pi:
        return r, r * phi / (0.25 * np.pi)
    if phi < 0.75 * np.pi:
        return -r * (phi - 0.5 * np.pi) / (0.25 * np.pi), r
    if phi < 1.25 * np.pi:
        return -r, -r * (phi - np.pi) / (0.25 * np.pi)
    return r * (phi - 1.5 * np.pi) / (0.25 * np.pi), -r


def bilinear(bins, R, wo):
    """bins: [pixel][4][4] with pixel j * R + i; bilinear between pixel centres, edges held."""
    a, b = to_square(wo)
    x = min(max((a + 1) * 0.5 * R - 0.5, 0.0), R - 1.0)
    y = min(max((b + 1) * 0.5 * R - 0.5, 0.0), R - 1.0)
    i, j = min(int(x), R - 2), min(int(y), R - 2)
    fx, fy = x - i, y - j
    px = lambda i, j: bins[j * R + i]
    return (1 - fy) * ((1 - fx) * px(i, j) + fx * px(i + 1, j)) + fy * ((1 - fx) * px(i, j + 1) + fx * px(i + 1, j + 1))


def record_matrix(incidences, phi_i, l, v, lam):
    """The record's matrix for light l, view v (microsim frames): the pair turned about z so that l
    has the measured azimuth, bilinear on the bins, linear in theta_i, held outside."""
    turn = phi_i - np.arctan2(l[1], l[0])
    c, s = np.cos(turn), np.sin(turn)
    wo = np.array([c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]])
    theta = np.arccos(np.clip(l[2], -1, 1))
    th = [inc["theta"] for inc in incidences]
    read = lambda k: bilinear(incidences[k]["f"][lam], incidences[k]["R"], wo)
    if len(th) == 1 or theta <= th[0]:
        return read(0)
    if theta >= th[-1]:
        return read(len(th) - 1)
    k = int(np.searchsorted(th, theta, side="right")) - 1
    w = (theta - th[k]) / (th[k + 1] - th[k])
    return (1 - w) * read(k) + w * read(k + 1)


def worst_deviation(table, incidences, phi_i, variant="plugin", nodes_step=1):
    """Largest |stored - expected| / (|expected M00| + 1e-6) over the checked nodes, and their number."""
    th, td, pd, M = table["theta_h"][0], table["theta_d"][0], table["phi_d"][0], table["M"]
    if variant == "transposed":
        M = np.swapaxes(M, -1, -2)
    worst, checked = 0.0, 0
    for ip in range(0, len(pd), nodes_step):
        for idd in range(1, len(td), nodes_step):  # theta_d = 0: l = v, the plugin has no frame
            for ih in range(len(th)):
                l, v = pair_of_node(float(th[ih]), float(td[idd]), float(pd[ip]))
                if l[2] < 0.02 or v[2] < 0.02:
                    continue
                xi, xo = plugin_axes(l, v)
                sign = -1.0 if variant == "sign" else 1.0
                Rin = rotation(-l, microsim_axis(l), xi, sign)
                Rout = rotation(v, microsim_axis(v), xo, sign)
                for lam in range(M.shape[3]):
                    m = record_matrix(incidences, phi_i, l, v, min(lam, len(incidences[0]["f"]) - 1))
                    expected = m if variant == "unconverted" else Rout @ m @ Rin.T
                    dev = np.max(np.abs(M[ip, idd, ih, lam] - expected)) / (abs(expected[0, 0]) + 1e-6)
                    worst = max(worst, dev)
                    checked += 1
    return worst, checked


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("pbsdf", nargs="?")
    ap.add_argument("record", nargs="?", help="the run's JSON record")
    ap.add_argument("--run", metavar="MICROSIM", help="write a small table with this program first")
    ap.add_argument("--tolerance", type=float, default=1e-5, help="largest deviation / M00 (float32 storage)")
    ap.add_argument("--power", action="store_true", help="also require wrong tables to fail")
    a = ap.parse_args()
    if a.run:
        tmp = tempfile.mkdtemp(prefix="pbsdf_check_")
        surface = os.path.join(tmp, "gaussian.exr")
        a.pbsdf, a.record = os.path.join(tmp, "gold.pbsdf"), os.path.join(tmp, "gold.json")
        subprocess.run([a.run, "-q", "generate", "gaussian", "--alpha", "0.5", "--resolution", "64", "-o", surface],
                       check=True)
        subprocess.run([a.run, "-q", "measure", "bsdf", surface, "--material", "conductor", "--metal", "Au",
                        "--theta-i", "0:80:20", "--phi-i", "30", "--rays", "20000", "--resolution", "16",
                        "--table-resolution", "16", "--table-azimuths", "1", "--no-models", "--polarized",
                        "-o", a.pbsdf], check=True)
    elif not a.pbsdf or not a.record:
        ap.error("give PBSDF and RECORD, or --run MICROSIM")
    table = read_tensor_file(a.pbsdf)
    rec = json.load(open(a.record))
    if a.run:
        shutil.rmtree(os.path.dirname(a.pbsdf))
    if rec["table"]["azimuths"] != 1:
        sys.exit("the record lists one incidence azimuth's bins: write the table with one azimuth")
    phi_i = np.radians(rec["parameters"]["phi_i_deg"][0])
    incidences = []
    for inc in rec["incidences"]:
        bins = inc["polarization"]["bins"]
        incidences.append({"theta": np.radians(inc["theta_i_deg"]), "R": bins["resolution"],
                           "f": [np.array(fl) for fl in bins["f"]]})
    incidences.sort(key=lambda x: x["theta"])
    shape = table["M"].shape
    ok = (table["wvls"].shape == (5,) and shape[:4] == (table["phi_d"].shape[1], table["theta_d"].shape[1],
          table["theta_h"].shape[1], 5) and shape[4:] == (4, 4))
    print(f"fields: M {shape}, wvls {list(table['wvls'])}: {'ok' if ok else 'WRONG'}")
    worst, n = worst_deviation(table, incidences, phi_i)
    print(f"largest deviation / M00 over {n} node-wavelengths: {worst:.3g} (tolerance {a.tolerance:g})")
    ok = ok and n > 0 and worst <= a.tolerance
    if a.power:
        for variant in ("transposed", "unconverted", "sign"):
            w, _ = worst_deviation(table, incidences, phi_i, variant, nodes_step=2)
            fails = w > 100 * a.tolerance
            print(f"power: {variant} table deviates by {w:.3g}: {'fails as it must' if fails else 'PASSES (no power)'}")
            ok = ok and fails
    print("pbsdf check:", "ok" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
