#!/usr/bin/env python3
"""Writes the exact structured surfaces of the G2/VNDF tables as OBJ meshes with microsim sidecars
(FILE.obj.json), the same constructions as tests/shapes.hpp:

  square_wave OUT.obj [period top height periods]   periodic square wave, ridges along y
  ellipsoid   OUT.obj AX AY [n_theta n_phi]          upper half-ellipsoid, semi-axes (1/AX, 1/AY, 1):
                                                      GGX(AX, AY) normals [TSBlog24], finite object
"""
import json
import math
import sys


def write(path, verts, tris, macro, description):
    with open(path, "w") as f:
        for v in verts:
            f.write("v %.9g %.9g %.9g\n" % v)
        for t in tris:
            f.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))
    with open(path + ".json", "w") as f:
        json.dump({"microsim_surface": "mesh", "macrosurface": macro, "description": description}, f, indent=1)


def square_wave(path, period=1.0, top=0.5, h=0.25, periods=4, size_y=1.0, ny=4):
    b = period - top
    x0 = -0.5 * periods * period
    prof = []
    for k in range(periods):
        s = x0 + k * period
        prof += [(s, 0.0), (s + 0.5 * b, 0.0), (s + 0.5 * b, h), (s + 0.5 * b + top, h), (s + 0.5 * b + top, 0.0)]
    prof.append((-x0, 0.0))
    n = len(prof)
    verts = [(x, -0.5 * size_y + size_y * j / ny, z) for j in range(ny + 1) for (x, z) in prof]
    tris = []
    for j in range(ny):
        for k in range(n - 1):
            a, bb, c, d = j * n + k, j * n + k + 1, (j + 1) * n + k + 1, (j + 1) * n + k
            tris += [(a, bb, c), (a, c, d)]
    macro = {"normal": [0, 0, 1], "area": periods * period * size_y, "periodic": True,
             "size_x": periods * period, "size_y": size_y}
    write(path, verts, tris, macro, {"kind": "square_wave", "period": period, "top": top, "height": h})


def ellipsoid(path, ax, ay, n_theta=90, n_phi=144):
    a, b, c = 1 / ax, 1 / ay, 1.0

    def point(th, ph):
        m = (math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th))
        d = math.sqrt((a * m[0]) ** 2 + (b * m[1]) ** 2 + (c * m[2]) ** 2)
        return (a * a * m[0] / d, b * b * m[1] / d, c * c * m[2] / d)

    verts = [point(0, 0)]
    for k in range(1, n_theta + 1):
        for j in range(n_phi):
            verts.append(point(0.5 * math.pi * k / n_theta, 2 * math.pi * j / n_phi))

    def vid(k, j):
        return 1 + (k - 1) * n_phi + j % n_phi

    tris = [(0, vid(1, j), vid(1, j + 1)) for j in range(n_phi)]
    for k in range(1, n_theta):
        for j in range(n_phi):
            tris += [(vid(k, j), vid(k + 1, j), vid(k + 1, j + 1)), (vid(k, j), vid(k + 1, j + 1), vid(k, j + 1))]
    macro = {"normal": [0, 0, 1], "area": math.pi * a * b, "periodic": False, "size_x": 2 * a, "size_y": 2 * b}
    write(path, verts, tris, macro, {"kind": "ellipsoid", "nominal_ndf": "ggx", "alpha_x": ax, "alpha_y": ay})


if __name__ == "__main__":
    if len(sys.argv) < 3 or sys.argv[1] not in ("square_wave", "ellipsoid"):
        sys.exit(__doc__)
    args = [float(x) for x in sys.argv[3:]]
    if sys.argv[1] == "square_wave":
        square_wave(sys.argv[2], *args[:3], *(int(x) for x in args[3:4]))
    else:
        ellipsoid(sys.argv[2], args[0], args[1], *(int(x) for x in args[2:4]))
