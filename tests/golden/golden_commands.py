"""The fixed command set of the golden check (golden_check.py): small sizes, fixed seeds.

Every measure command on every kind of scene (a periodic tile, a non-periodic heightmap window,
a box, tiled boxes, a V-cavity, an ensemble of tiles), shards merged, `mpirun -n 2`, every
export format and a validate smoke run. Paths are relative to the build's output folder.
"""
import math
import random
import re


class Step:
    def __init__(self, name, args=None, mpi=False, python=None, needs=()):
        self.name = name
        self.args = args.split() if isinstance(args, str) else (args or [])
        self.mpi = mpi
        self.python = python
        self.needs = set(needs)  # names of the steps that make its inputs


def write_heightmap_csv(folder):
    """A 48 x 48 instrument-like heightmap (a sum of fixed waves), as a comma-separated matrix."""
    rng = random.Random(7)
    waves = [(rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(0, 2 * math.pi),
              rng.uniform(0.3, 1.0)) for _ in range(24)]
    with open(folder + "/scan.csv", "w") as f:
        for j in range(48):
            row = []
            for i in range(48):
                z = sum(a * math.sin(fx * i + fy * j + p) for fx, fy, p, a in waves)
                row.append("%.9g" % z)
            f.write(",".join(row) + "\n")


SURFACES = [
    Step("gen tile", "generate gaussian --resolution 48 --alpha 0.5 --seed 2 -q -o tile.exr"),
    Step("gen tile2", "generate gaussian --resolution 48 --alpha 0.5 --seed 3 -q -o tile2.exr"),
    Step("gen tile3", "generate gaussian --resolution 48 --alpha 0.5 --seed 4 -q -o tile3.exr"),
    Step("scan.csv", python=write_heightmap_csv),
    Step("gen window", "generate heightmap --input scan.csv --pixel-size 1 --guard 2 -q -o win.exr",
         needs=["scan.csv"]),
    Step("gen box", "generate box --config {src}/surfaces/box.toml -q -o box.ply"),
    Step("gen tiled", "generate tiled-boxes --tiles 3 -q -o tiled.ply"),
    Step("gen vcavity", "generate vcavity --grooves 64 --seed 1 -q -o vc.ply"),
]

SCENES = {  # name -> (files, the step that makes them)
    "tile": ("tile.exr", ["gen tile"]),
    "window": ("win.exr", ["gen window", "scan.csv"]),
    "box": ("box.ply", ["gen box"]),
    "tiled": ("tiled.ply", ["gen tiled"]),
    "vcavity": ("vc.ply", ["gen vcavity"]),
    "ensemble": ("tile.exr tile2.exr tile3.exr", ["gen tile", "gen tile2", "gen tile3"]),
}

# Every measure command, small; {s} is the scene's files. ndf and bsdf take one surface, so the
# ensemble runs g1, g2 and vndf only.
MEASURES = {
    "ndf": "measure ndf {s} --theta-bins 18 --phi-bins 8",
    "g1": "measure g1 {s} --theta 0,60,85 --phi 0,30 --rays 3000 --seed 3",
    "g2": "measure g2 {s} --theta-o 30,70 --theta-i 50 --phi-i 180 --rays 3000 --seed 3",
    "vndf": "measure vndf {s} --theta 30,75 --rays 8000 --sampler-samples 500 --seed 3",
    "bsdf": "measure bsdf {s} --material conductor --eta 0.2 --k 3 --theta-i 40 --rays 3000 "
            "--resolution 8 --seed 3",
}

OPTS = "--threads 2 -q"


def measure_steps():
    out = []
    for scene, (files, needs) in SCENES.items():
        for what, cmd in MEASURES.items():
            if scene == "ensemble" and what in ("ndf", "bsdf"):
                continue
            name = "%s_%s" % (what, scene)
            out.append(Step(name, "%s %s -o %s.json" % (cmd.format(s=files), OPTS, name), needs=needs))
    return out


def shard_steps():
    """--shard 1/2 + --shard 2/2 + merge: the window at grazing incidence (side walls met) and
    every estimator on a tile and a V-cavity."""
    runs = [
        ("g1_window_89", "measure g1 win.exr --theta 89 --rays 4000 --seed 3", SCENES["window"][1]),
        ("g1_tile", "measure g1 tile.exr --theta 40,80 --rays 3000", SCENES["tile"][1]),
        ("g2_window", "measure g2 win.exr --theta-o 70 --theta-i 80 --phi-i 180 --rays 3000",
         SCENES["window"][1]),
        ("vndf_window", "measure vndf win.exr --theta 85 --rays 8000 --sampler-samples 0", SCENES["window"][1]),
        ("bsdf_tile", "measure bsdf tile.exr --material mirror --theta-i 50 --rays 3000 --resolution 8",
         SCENES["tile"][1]),
        ("bsdf_box", "measure bsdf box.ply --material dielectric --eta 1.5 --theta-i 30 --rays 3000 "
                     "--resolution 8 --no-models", SCENES["box"][1]),
        ("g2_vcavity", "measure g2 vc.ply --theta-o 30,75 --theta-i 60 --rays 3000", SCENES["vcavity"][1]),
        ("vndf_vcavity", "measure vndf vc.ply --theta 70 --rays 8000 --sampler-samples 0", SCENES["vcavity"][1]),
    ]
    out = []
    for name, cmd, needs in runs:
        part = "shard_%s.json" % name
        for k in (1, 2):
            out.append(Step("shard %s %d/2" % (name, k), "%s %s --shard %d/2 -o %s" % (cmd, OPTS, k, part),
                            needs=needs))
        out.append(Step("merge %s" % name,
                        "merge %s.shard-1-of-2.json %s.shard-2-of-2.json %s -o merged_%s.json"
                        % (part, part, OPTS, name), needs=["shard %s %d/2" % (name, k) for k in (1, 2)]))
    return out


def mpi_steps():
    runs = [
        ("g1_window_89", "measure g1 win.exr --theta 89 --rays 4000 --seed 3", SCENES["window"][1]),
        ("g2_tile", "measure g2 tile.exr --theta-o 40 --theta-i 60 --rays 3000", SCENES["tile"][1]),
        ("vndf_tile", "measure vndf tile.exr --theta 45 --rays 8000", SCENES["tile"][1]),
        ("bsdf_tile", "measure bsdf tile.exr --material dielectric --eta 1.5 --theta-i 20 --rays 3000 "
                      "--resolution 8", SCENES["tile"][1]),
    ]
    return [Step("mpirun %s" % name, "%s --threads 1 -q -o mpi_%s.json" % (cmd, name), mpi=True, needs=needs)
            for name, cmd, needs in runs]


def export_steps():
    t = SCENES["tile"][1]
    return [
        Step("export ndf csv", "measure ndf tile.exr --theta-bins 18 --phi-bins 8 %s -o ndf_tile.csv" % OPTS, needs=t),
        Step("export ndf exr", "measure ndf tile.exr --theta-bins 18 --phi-bins 8 %s -o ndf_tile.exr" % OPTS, needs=t),
        Step("export g1 csv", "measure g1 tile.exr --theta 30,70 --rays 2000 %s -o g1_tile.csv" % OPTS, needs=t),
        Step("export g2 csv", "measure g2 tile.exr --theta-o 40 --theta-i 60 --rays 2000 %s -o g2_tile.csv" % OPTS,
             needs=t),
        Step("export vndf csv", "measure vndf tile.exr --theta 45 --rays 4000 %s -o vndf_tile.csv" % OPTS, needs=t),
        Step("export bsdf exr", "measure bsdf tile.exr --material mirror --theta-i 0,40 --rays 2000 --resolution 8 "
                                "%s -o bsdf_tile.exr" % OPTS, needs=t),
        Step("export bsdf rgl", "measure bsdf tile.exr --material conductor --eta 0.2 --k 3 --rays 1000 "
                                "--theta-i 0:80:40 --table-resolution 4 --resolution 8 --no-models %s "
                                "-o bsdf_tile.bsdf" % OPTS, needs=t),
        Step("export bsdf merl", "measure bsdf tile.exr --material conductor --eta 0.2 --k 3 --rays 1000 "
                                 "--theta-i 0:80:40 --resolution 8 --no-models %s -o bsdf_tile.binary" % OPTS,
             needs=t),
        Step("convert ply", "convert tile.exr %s -o tile.ply" % OPTS, needs=t),
        Step("convert obj", "convert tile.exr %s -o tile.obj" % OPTS, needs=t),
        Step("convert box obj", "convert box.ply %s -o box_copy.obj" % OPTS, needs=SCENES["box"][1]),
        Step("info json", "info tile.exr %s --json info_tile.json" % OPTS, needs=t),
        Step("info window json", "info win.exr %s --json info_win.json" % OPTS, needs=SCENES["window"][1]),
    ]


def validate_steps():
    return [
        Step("validate tile", "validate tile.exr --theta 30,70 --rays 2000 %s -o validate_tile.json" % OPTS,
             needs=SCENES["tile"][1]),
        Step("validate vcavity", "validate vc.ply --checks g1,g2,vndf --theta 60 --rays 3000 %s "
                                 "-o validate_vc.json" % OPTS, needs=SCENES["vcavity"][1]),
    ]


def steps(only=None, source_dir=None):
    """All steps in order (surfaces first); with `only`, the matching steps and their inputs."""
    import os
    src = source_dir or os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    everything = SURFACES + measure_steps() + shard_steps() + mpi_steps() + export_steps() + validate_steps()
    for s in everything:
        s.args = [a.replace("{src}", src) for a in s.args]
    if not only:
        return everything
    pattern = re.compile(only)
    keep = {s.name for s in everything if pattern.search(s.name)}
    by_name = {s.name: s for s in everything}
    grew = True
    while grew:
        more = set().union(*(by_name[n].needs for n in keep)) - keep
        grew = bool(more)
        keep |= more
    return [s for s in everything if s.name in keep]
