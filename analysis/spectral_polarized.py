#!/usr/bin/python3
"""Spectral and polarized multiple scattering of gold and aluminium on Beckmann heightfields.

usage: spectral_polarized.py --build BUILD --out DIR [--profile published|small] [--check]

Generates Beckmann tiles (alpha 0.3 and 0.7, 16 cells per correlation length) and a flat plane,
runs `microsim measure bsdf --material conductor --metal Au|Al --polarized` at theta_i 0, 45 and
80 degrees, and the per-direction maps of the polarized walk (the analysis program
polarization_maps, same seed and paths); writes DIR/spectral_polarized.md (tables with errors
and the commands), DIR/img/*.png (figures) and DIR/runs/ (records). The published profile also
times the cost table (/usr/bin/time -v: wall time and peak memory).

Checks (exit 1 when one fails; --check also shows that each rejects a perturbed input):
  * flat plane: order-1 albedo at normal incidence = ((n-1)^2 + k^2) / ((n+1)^2 + k^2) of the
    record's own n, k at 450, 550, 650 nm, within 1e-12; at 45 and 80 degrees = the unpolarized
    Fresnel reflectance of the complex index, within 1e-12;
  * the map's flux-weighted mean of the pixels' degrees of polarization = the record's
    resolved_degree_of_polarization at the map's wavelength, within 1e-12 (same paths);
  * s input at normal incidence on alpha 0.7: the first order's resolved degree of polarization
    exceeds the second's by more than 5 standard errors of the difference, for both metals.
"""
import argparse
import cmath
import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

METALS = ["Au", "Al"]
ALPHAS = [0.3, 0.7]
THETAS = [0, 45, 80]
ORDERS = ["order_1", "order_2", "order_3", "order_4plus", "total"]
ORDER_LABEL = {"order_1": "1", "order_2": "2", "order_3": "3", "order_4plus": "4+", "total": "total"}
FLAT_NM = [450.0, 550.0, 650.0]
MAP_NM = 550.0
SEED = 1
CONVERGED = "surfaces/beckmann-1.0-converged.toml"
CELLS_PER_LENGTH = 16  # the converged grid (docs/findings/discretization.md)

PROFILES = {
    # tile cells per side (1024: the converged tile, 64 correlation lengths), rays per incidence,
    # wavelengths; cost runs
    "published": dict(resolution=1024, rays=1_000_000, wavelengths="400:800:25", cost_rays=200_000,
                      cost_args=[], cost_repeats=2),
    "small": dict(resolution=64, rays=4000, wavelengths="400:800:50", cost_rays=2000,
                  cost_args=["--resolution", 8, "--table-resolution", 8], cost_repeats=1),
}
# cost_repeats: runs per cost case (the spread of their wall times shows the shared machine's noise).
# The cost table's spectral cases: label -> --wavelengths (1, 5 and 16 wavelengths).
COST_WAVELENGTHS = [("1", "550"), ("5", "450:650:50"), ("16", "400:775:25")]
TOLERANCE = 1e-12


class CheckFailed(Exception):
    pass


# ---- optics -------------------------------------------------------------------------------

def fresnel_normal(n, k):
    """Unpolarized reflectance of the flat conductor n + ik at normal incidence."""
    return ((n - 1) ** 2 + k ** 2) / ((n + 1) ** 2 + k ** 2)


def fresnel_unpolarized(n, k, theta_deg):
    """Mean of |r_s|^2 and |r_p|^2 of the flat conductor n + ik at incidence theta (from air)."""
    c = math.cos(math.radians(theta_deg))
    s2 = 1.0 - c * c
    m2 = complex(n, k) ** 2
    root = cmath.sqrt(m2 - s2)
    rs = (c - root) / (c + root)
    rp = (m2 * c - root) / (m2 * c + root)
    return 0.5 * (abs(rs) ** 2 + abs(rp) ** 2)


# ---- runs ---------------------------------------------------------------------------------

class Runner:
    def __init__(self, build, out, src, reuse=False):
        self.reuse = reuse
        self.microsim = str(Path(build) / "microsim")
        self.maps = str(Path(build) / "polarization_maps")
        self.out, self.src = Path(out), Path(src)
        self.commands = []

    def run(self, args, shown=None):
        """Runs microsim (or the analysis program when args[0] is "polarization_maps") in the output
        directory and records the command as shown (paths relative to the repository)."""
        args = [str(a) for a in args]
        if args[0] == "polarization_maps":
            argv = [self.maps] + args[1:]
        else:
            argv = [self.microsim, "-q"] + args
        self.commands.append(shown or " ".join(args if args[0] == "polarization_maps" else ["microsim"] + args))
        if self.reuse and (self.out / args[-1]).exists():  # every run's output is its last argument
            return
        subprocess.run(argv, check=True, cwd=self.out, stdout=subprocess.DEVNULL)

    def timed(self, args):
        """Wall time (s) and peak resident memory (MB) of one microsim run, from /usr/bin/time -v."""
        p = subprocess.run(["/usr/bin/time", "-v", self.microsim, "-q"] + [str(a) for a in args], cwd=self.out,
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, check=True)
        wall = re.search(r"Elapsed \(wall clock\) time.*: (?:(\d+):)?(\d+):([\d.]+)", p.stderr)
        rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr)
        h, m, s = wall.groups()
        return (int(h or 0) * 60 + int(m)) * 60 + float(s), int(rss.group(1)) / 1024.0


def tile_name(alpha):
    return f"beckmann_a{alpha:.1f}".replace(".", "p") + ".exr"


def measure_name(metal, alpha):
    return f"{metal}_a{alpha:.1f}".replace(".", "p") + ".json"


def run_all(r, prof):
    """Surfaces, spectral polarized records, maps and flat-plane records; returns what was read."""
    res = prof["resolution"]
    r.run(["generate", "flat", "--config", r.src / "surfaces/flat.toml", "-o", "flat.exr"],
          "microsim generate flat --config surfaces/flat.toml -o flat.exr")
    ell = CELLS_PER_LENGTH / res  # the preset's 16 cells per correlation length on this tile
    for a in ALPHAS:
        r.run(["generate", "gaussian", "--config", r.src / CONVERGED, "--alpha", a, "--resolution", res,
               "--correlation-length", ell, "--seed", SEED, "-o", tile_name(a)],
              f"microsim generate gaussian --config {CONVERGED} --alpha {a} --resolution {res} "
              f"--correlation-length {ell} --seed {SEED} -o {tile_name(a)}")
    thetas = ",".join(map(str, THETAS))
    data = {"flat": {}, "rough": {}, "maps": {}}
    for metal in METALS:
        flat = f"flat_{metal}.json"
        r.run(["measure", "bsdf", "flat.exr", "--material", "conductor", "--metal", metal, "--wavelengths",
               prof["wavelengths"], "--theta-i", thetas, "--rays", 2000, "--no-models", "-o", flat])
        flat_nm = f"flat_{metal}_nm.json"
        r.run(["measure", "bsdf", "flat.exr", "--material", "conductor", "--metal", metal, "--wavelengths",
               ",".join(f"{x:g}" for x in FLAT_NM), "--theta-i", thetas, "--rays", 2000, "--no-models",
               "-o", flat_nm])
        data["flat"][metal] = (load(r.out / flat), load(r.out / flat_nm))
        for a in ALPHAS:
            name = measure_name(metal, a)
            r.run(["measure", "bsdf", tile_name(a), "--material", "conductor", "--metal", metal,
                   "--wavelengths", prof["wavelengths"], "--polarized", "--theta-i", thetas,
                   "--rays", prof["rays"], "--seed", SEED, "--no-models", "-o", name])
            maps = "maps_" + name
            r.run(["polarization_maps", tile_name(a), metal, f"{MAP_NM:g}", thetas, prof["rays"], SEED, maps])
            data["rough"][(metal, a)] = load(r.out / name)
            cells = data["rough"][(metal, a)]["surface"]["cells_per_correlation_length"]
            if cells != CELLS_PER_LENGTH:
                raise CheckFailed(f"{tile_name(a)}: {cells} cells per correlation length, not {CELLS_PER_LENGTH}")
            data["maps"][(metal, a)] = load(r.out / maps)
    return data


def load(path):
    with open(path) as f:
        return json.load(f)


def incidence(record, theta):
    return next(i for i in record["incidences"] if abs(i["theta_i_deg"] - theta) < 1e-9)


# ---- checks -------------------------------------------------------------------------------

def flat_rows(flat_record):
    """Per wavelength at normal incidence: nm, n, k, the closed form, the flat run's order-1 albedo."""
    sp = incidence(flat_record, 0)["spectral"]
    a1 = sp["albedo"]["reflected"]["order_1"]
    return [(nm, n, k, fresnel_normal(n, k), a)
            for nm, n, k, a in zip(sp["wavelengths_nm"], sp["eta"], sp["k"], a1)]


def check_flat(flat_record):
    """Largest |order-1 albedo - Fresnel| over wavelengths and incidences; raises above TOLERANCE."""
    worst = 0.0
    for nm, n, k, closed, a in flat_rows(flat_record):
        worst = max(worst, abs(a - closed))
    for theta in THETAS:
        sp = incidence(flat_record, theta)["spectral"]
        for n, k, a in zip(sp["eta"], sp["k"], sp["albedo"]["reflected"]["order_1"]):
            worst = max(worst, abs(a - fresnel_unpolarized(n, k, theta)))
        if any(x != 0.0 for x in sp["albedo"]["reflected"]["order_2"]):
            raise CheckFailed(f"flat plane at {theta} deg: order 2 not empty")
    if not worst <= TOLERANCE:
        raise CheckFailed(f"flat plane: order-1 albedo differs from Fresnel by {worst:.3g} > {TOLERANCE}")
    return worst


def map_mean_dop(inc_map, key, field="dop_s"):
    """Mean of the pixels' degrees of polarization weighted by the pixels' flux of that input."""
    e = inc_map["reflected"][key][0]
    weights = e["flux_s"] if field == "dop_s" else e["flux"]
    flux = sum(weights)
    return sum(f * d for f, d in zip(weights, e[field])) / flux if flux > 0 else 0.0


def check_maps(record, maps):
    """The map's flux-weighted mean DoP against the record's resolved DoP (same paths)."""
    worst = 0.0
    l = incidence(record, THETAS[0])["spectral"]["wavelengths_nm"].index(MAP_NM)
    for m in maps["incidences"]:
        pol = incidence(record, m["theta_i_deg"])["polarization"]["reflected"]
        for key in ORDERS:
            for field, inp in (("dop_s", "s"), ("dop_unpolarized", "unpolarized")):
                recorded = pol[key][l]["resolved_degree_of_polarization"][inp]
                worst = max(worst, abs(map_mean_dop(m, key, field) - recorded))
    if not worst <= TOLERANCE:
        raise CheckFailed(f"map mean degree of polarization differs from the record's by {worst:.3g}")
    return worst


def check_depolarization(record, margin=5.0):
    """s input, normal incidence: order 1 more polarized than order 2 by > margin sigma."""
    pol = incidence(record, 0)["polarization"]["reflected"]
    l = record["parameters"]["wavelengths_nm"].index(MAP_NM)
    d1, d2 = (pol[k][l]["resolved_degree_of_polarization"]["s"] for k in ("order_1", "order_2"))
    e1, e2 = (pol[k][l]["resolved_degree_of_polarization_stderr"]["s"] for k in ("order_1", "order_2"))
    z = (d1 - d2) / math.hypot(e1, e2)
    if not z > margin:
        raise CheckFailed(f"order 1 DoP {d1:.4f} not above order 2 {d2:.4f} by {margin} sigma (z = {z:.2f})")
    return z


def run_checks(data):
    out = {}
    for metal in METALS:
        out[("flat", metal)] = max(check_flat(data["flat"][metal][0]), check_flat(data["flat"][metal][1]))
        for a in ALPHAS:
            out[("maps", metal, a)] = check_maps(data["rough"][(metal, a)], data["maps"][(metal, a)])
        out[("depol", metal)] = check_depolarization(data["rough"][(metal, 0.7)])
    return out


def check_rejections(data):
    """Each check must refuse a wrong input: a perturbed flat albedo, map and swapped orders."""
    import copy
    flat = copy.deepcopy(data["flat"]["Au"][1])
    incidence(flat, 0)["spectral"]["albedo"]["reflected"]["order_1"][1] += 1e-10
    rough = copy.deepcopy(data["rough"][("Au", 0.7)])
    maps = copy.deepcopy(data["maps"][("Au", 0.7)])
    maps["incidences"][1]["reflected"]["order_2"][0]["dop_s"][27] += 0.01
    swapped = copy.deepcopy(rough)
    pol = incidence(swapped, 0)["polarization"]["reflected"]
    pol["order_1"], pol["order_2"] = pol["order_2"], pol["order_1"]
    for what, call in (("perturbed flat albedo", lambda: check_flat(flat)),
                       ("perturbed map pixel", lambda: check_maps(rough, maps)),
                       ("orders 1 and 2 swapped", lambda: check_depolarization(swapped))):
        try:
            call()
        except CheckFailed:
            continue
        raise SystemExit(f"check accepted a {what}")


# ---- cost ---------------------------------------------------------------------------------

def cost_table(r, prof):
    """Wall time and peak memory of the same .bsdf run: one index, 1/5/16 wavelengths, +-polarized."""
    rays, tile = prof["cost_rays"], tile_name(0.7)
    common = ["--theta-i", "0,45,80", "--rays", rays, "--no-models"] + prof["cost_args"] + ["-o", "cost.bsdf"]
    au = incidence(load(r.out / measure_name("Au", 0.7)), 0)["spectral"]
    l = au["wavelengths_nm"].index(MAP_NM)
    eta, k = au["eta"][l], au["k"][l]
    cases = [("one index (`--eta`/`--k`)", ["--eta", f"{eta:.6g}", "--k", f"{k:.6g}"])]
    cases += [(f"Au, {n} wavelength{'s' if n != '1' else ''}", ["--metal", "Au", "--wavelengths", w])
              for n, w in COST_WAVELENGTHS]
    cached = r.out / "cost_table.json"  # not cost.json: the runs write their record there
    if r.reuse and cached.exists():
        saved = load(cached)
        r.commands += saved["commands"]
        return [tuple(x) for x in saved["rows"]], tuple(saved["index"])
    rows, first = [], len(r.commands)
    for label, args in cases:
        for polarized in (False, True):
            argv = (["measure", "bsdf", tile, "--material", "conductor"] + args
                    + (["--polarized"] if polarized else []))
            runs = [r.timed(argv + common) for _ in range(prof["cost_repeats"])]
            r.commands.append("/usr/bin/time -v microsim -q " + " ".join(map(str, argv + common)))
            rows.append((label, polarized, [w for w, _ in runs], [m for _, m in runs]))
    cached.write_text(json.dumps({"rows": rows, "index": [eta, k], "commands": r.commands[first:]}))
    return rows, (eta, k)


# ---- figures ------------------------------------------------------------------------------

COLORS = {"order_1": "C0", "order_2": "C1", "order_3": "C2", "order_4plus": "C3", "total": "k"}


def figure_albedo(data, theta, path):
    fig, axes = plt.subplots(2, 2, figsize=(9, 6.4), sharex=True)
    for row, metal in enumerate(METALS):
        for col, a in enumerate(ALPHAS):
            ax = axes[row][col]
            sp = incidence(data["rough"][(metal, a)], theta)["spectral"]
            nm = sp["wavelengths_nm"]
            for key in ORDERS:
                y, e = sp["albedo"]["reflected"][key], sp["reflected_stderr"][key]
                ax.errorbar(nm, y, yerr=e, color=COLORS[key], lw=1.4 if key == "total" else 1.1,
                            label=f"order {ORDER_LABEL[key]}" if key != "total" else "total")
            flat = [fresnel_unpolarized(n, k, theta) for n, k in zip(sp["eta"], sp["k"])]
            ax.plot(nm, flat, "k--", lw=1, label="flat (Fresnel)")
            ax.set_yscale("log")
            ax.set_ylim(1e-4, 1.2)
            ax.set_title(f"{metal}, α = {a}", fontsize=10)
            ax.grid(alpha=0.3, which="both", lw=0.4)
            if row == 1:
                ax.set_xlabel("wavelength (nm)")
            if col == 0:
                ax.set_ylabel("reflected albedo")
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=8, ncol=6, loc="lower center")
    fig.suptitle(f"Albedo per scattering order, θi = {theta}°, Beckmann tiles", fontsize=11)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    fig.savefig(path, dpi=90)
    plt.close(fig)


def figure_dop(data, path):
    fig, axes = plt.subplots(2, 2, figsize=(9, 6.4), sharex=True, sharey=True)
    x = list(range(1, 5))
    for row, metal in enumerate(METALS):
        for col, a in enumerate(ALPHAS):
            ax = axes[row][col]
            rec = data["rough"][(metal, a)]
            l = rec["parameters"]["wavelengths_nm"].index(MAP_NM)
            for c, theta in enumerate(THETAS):
                pol = incidence(rec, theta)["polarization"]["reflected"]
                for inp, style in (("s", "-o"), ("unpolarized", ":s")):
                    y = [pol[k][l]["resolved_degree_of_polarization"][inp] for k in ORDERS[:4]]
                    e = [pol[k][l]["resolved_degree_of_polarization_stderr"][inp] for k in ORDERS[:4]]
                    flux = [pol[k][l]["mueller"][0][0] for k in ORDERS[:4]]
                    keep = [i for i in range(4) if flux[i] > 0]
                    ax.errorbar([x[i] for i in keep], [y[i] for i in keep], yerr=[e[i] for i in keep], fmt=style,
                                color=f"C{c}", ms=4, lw=1.1, capsize=2,
                                label=f"θi {theta}°, {'s input' if inp == 's' else 'unpolarized input'}")
            ax.set_title(f"{metal}, α = {a}, {MAP_NM:g} nm", fontsize=10)
            ax.set_xticks(x, ["1", "2", "3", "4+"])
            ax.set_ylim(0, 1.02)
            ax.grid(alpha=0.3, lw=0.4)
            if row == 1:
                ax.set_xlabel("scattering order")
            if col == 0:
                ax.set_ylabel("resolved degree of polarization")
    axes[1][0].legend(fontsize=7, loc="center left")
    fig.suptitle("Degree of polarization of the reflected light per order (direction by direction)", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def figure_maps(maps, metal, alpha, path):
    import numpy as np
    fig, axes = plt.subplots(3, 4, figsize=(8.6, 6.2), sharex=True, sharey=True, layout="constrained")
    cmap = plt.get_cmap("viridis").copy()
    cmap.set_bad("0.85")
    for row, m in enumerate(maps["incidences"]):
        R = m["map_resolution"]
        for col, key in enumerate(ORDERS[:4]):
            ax = axes[row][col]
            e = m["reflected"][key][0]
            img = np.full((R, R), np.nan)
            for px, (f, d) in enumerate(zip(e["flux"], e["dop_s"])):
                if f > 0:
                    img[px // R, px % R] = d
            im = ax.imshow(img, origin="lower", extent=(-1, 1, -1, 1), vmin=0, vmax=1, cmap=cmap)
            # the specular direction (-sin, 0, cos) at a = -sqrt(1 - cos theta_i), b = 0
            ax.plot([-math.sqrt(1 - math.cos(math.radians(m["theta_i_deg"])))], [0], "r+", ms=7)
            if row == 0:
                ax.set_title(f"order {ORDER_LABEL[key]}", fontsize=10)
            if col == 0:
                ax.set_ylabel(f"θi = {m['theta_i_deg']:g}°\nb", fontsize=9)
            if row == 2:
                ax.set_xlabel("a", fontsize=9)
            ax.tick_params(labelsize=7)
    fig.colorbar(im, ax=axes, shrink=0.8, label="degree of polarization (s input)")
    fig.suptitle(f"{metal}, α = {alpha}, {MAP_NM:g} nm: per-direction degree of polarization "
                 f"({maps['incidences'][0]['map_resolution']}×{maps['incidences'][0]['map_resolution']} "
                 "equal-area map; light from +a, + = specular; grey: no path)", fontsize=9)
    fig.savefig(path, dpi=90)
    plt.close(fig)


# ---- tables -------------------------------------------------------------------------------

def cite(key):
    """A bibliography link from a page of docs/findings/records."""
    return f"[[{key}]](../../theory/bibliography.md#{key.lower()})"


def pm(v, e, digits=4):
    """v ± e, with at least `digits` decimals and enough to show two significant digits of e."""
    if e > 0:
        digits = min(7, max(digits, 1 - math.floor(math.log10(e))))
    return f"{v:.{digits}f} ± {e:.{digits}f}"


def markdown(data, checks, cost, prof):
    out = []
    w = out.append
    w("# Spectral and polarized multiple scattering\n")
    w(f"Beckmann tiles of {prof['resolution']}² cells, 16 cells per correlation length "
      f"({prof['resolution'] // 16} lengths per side), seed {SEED}; {prof['rays']} paths per incidence; "
      f"wavelengths {prof['wavelengths']} nm; gold (Au, {cite('JohnsonChristy72')}) and aluminium "
      f"(Al, {cite('McPeak15')}) tables of the program.\n")
    w("## Flat plane against the closed form\n")
    w("Order-1 albedo of the flat plane at normal incidence against ((n − 1)² + k²) / ((n + 1)² + k²) "
      "of the record's own n and k:\n")
    w("| metal | λ (nm) | n | k | closed form | flat run, order 1 | difference |")
    w("|---|---|---|---|---|---|---|")
    for metal in METALS:
        for nm, n, k, closed, a in flat_rows(data["flat"][metal][1]):
            w(f"| {metal} | {nm:g} | {n:.4f} | {k:.4f} | {closed:.15f} | {a:.15f} | {a - closed:.1e} |")
    worst = max(checks[("flat", m)] for m in METALS)
    w(f"\nLargest |difference| over every wavelength of the runs at θi 0, 45 and 80° (against the "
      f"unpolarized Fresnel reflectance of n + ik at that angle): {worst:.1e}; orders ≥ 2 empty.\n")
    w("## Albedo per order\n")
    w(f"At {MAP_NM:g} nm (mean ± standard error over 32 replicates), and the flat plane's Fresnel "
      "reflectance at the same θi:\n")
    w("| metal | α | θi | order 1 | order 2 | order 3 | order 4+ | total | flat |")
    w("|---|---|---|---|---|---|---|---|---|")
    for metal in METALS:
        for a in ALPHAS:
            for theta in THETAS:
                sp = incidence(data["rough"][(metal, a)], theta)["spectral"]
                l = sp["wavelengths_nm"].index(MAP_NM)
                cells = [pm(sp["albedo"]["reflected"][k][l], sp["reflected_stderr"][k][l], 5) for k in ORDERS]
                flat = fresnel_unpolarized(sp["eta"][l], sp["k"][l], theta)
                w(f"| {metal} | {a} | {theta}° | " + " | ".join(cells) + f" | {flat:.5f} |")
    spectral_nm = [x for x in (400.0, 500.0, 600.0, 700.0, 800.0)
                   if x in data["rough"][(METALS[0], ALPHAS[0])]["parameters"]["wavelengths_nm"]]
    w("\nTotal albedo and the multiple-scattering share (orders ≥ 2 over the total) across the spectrum:\n")
    w("| metal | α | θi | " + " | ".join(f"{x:g} nm" for x in spectral_nm) + " |")
    w("|---|---|---|" + "---|" * len(spectral_nm))
    for metal in METALS:
        for a in ALPHAS:
            for theta in THETAS:
                sp = incidence(data["rough"][(metal, a)], theta)["spectral"]
                cells = []
                for x in spectral_nm:
                    l = sp["wavelengths_nm"].index(x)
                    tot = sp["albedo"]["reflected"]["total"][l]
                    ms = tot - sp["albedo"]["reflected"]["order_1"][l]
                    cells.append(f"{tot:.4f} ({100 * ms / tot:.1f} %)")
                w(f"| {metal} | {a} | {theta}° | " + " | ".join(cells) + " |")
    w("\n## Degree of polarization per order\n")
    w(f"Resolved degree of polarization (direction by direction, {MAP_NM:g} nm) of the reflected light "
      "of each order, for the s input and (second line of each case) the unpolarized input:\n")
    w("| metal | α | θi | input | order 1 | order 2 | order 3 | order 4+ | total |")
    w("|---|---|---|---|---|---|---|---|---|")
    for metal in METALS:
        for a in ALPHAS:
            rec = data["rough"][(metal, a)]
            l = rec["parameters"]["wavelengths_nm"].index(MAP_NM)
            for theta in THETAS:
                pol = incidence(rec, theta)["polarization"]["reflected"]
                for inp in ("s", "unpolarized"):
                    cells = []
                    for k in ORDERS:
                        e = pol[k][l]
                        cells.append(pm(e["resolved_degree_of_polarization"][inp],
                                        e["resolved_degree_of_polarization_stderr"][inp], 3)
                                     if e["mueller"][0][0] > 0 else "–")
                    w(f"| {metal} | {a} | {theta}° | {inp} | " + " | ".join(cells) + " |")
    w("\nChecks of this run: the maps' flux-weighted mean degrees of polarization equal the records' "
      f"resolved values within {max(v for k, v in checks.items() if k[0] == 'maps'):.1e}; at normal "
      "incidence on α 0.7 the s input's order 1 is more polarized than its order 2 by "
      + ", ".join(f"{checks[('depol', m)]:.0f} σ ({m})" for m in METALS) + ".\n")
    if cost:
        rows, (eta, k) = cost
        w("## Cost\n")
        sizes = " ".join(f"`{x}`" if str(x).startswith("--") else str(x) for x in prof["cost_args"])
        repeats = prof["cost_repeats"]
        w(f"`measure bsdf` on the α 0.7 tile, θi 0, 45, 80°, {prof['cost_rays']} paths per incidence, "
          f"{sizes or 'default map and table resolutions (64)'}, `-o cost.bsdf` (16 table azimuths), "
          f"`--no-models`; the one-index run uses gold's index at {MAP_NM:g} nm (n = {eta:.4g}, "
          f"k = {k:.4g}). {repeats} run{'s' if repeats > 1 else ''} each, wall time and peak resident "
          "memory from `/usr/bin/time -v`, on a 2-core machine shared with other jobs:\n")
        w("| index | unpolarized: wall (s) | peak memory (MB) | `--polarized`: wall (s) | peak memory (MB) |")
        w("|---|---|---|---|---|")
        base_wall, base_mb = min(rows[0][2]), max(rows[0][3])
        for i in range(0, len(rows), 2):
            cells = []
            for _, _, walls, mbs in (rows[i], rows[i + 1]):
                spread = f"{min(walls):.1f}" + (f"–{max(walls):.1f}" if len(walls) > 1 else "")
                cells.append(f"{spread} ({min(walls) / base_wall:.1f}×)")
                cells.append(f"{max(mbs):.0f} ({max(mbs) / base_mb:.1f}×)")
            w(f"| {rows[i][0]} | " + " | ".join(cells) + " |")
        w(f"\nWall time: the fastest and slowest of {repeats} runs (the ratio: fastest against the "
          "fastest one-index run); memory: the larger peak.")
        w("")
    return out


def commands_section(commands):
    lines = ["## Commands\n", "Run in one directory (`polarization_maps` is the analysis program of "
             "`analysis/polarization_maps.cpp`, built by the target of that name):\n", "```sh",
             "# long example"]
    lines += commands
    lines += ["```", ""]
    return lines


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--build", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--profile", choices=sorted(PROFILES), default="published")
    p.add_argument("--check", action="store_true", help="also show that each check rejects a wrong input")
    p.add_argument("--no-cost", action="store_true", help="skip the timed runs of the cost table")
    p.add_argument("--reuse", action="store_true",
                   help="keep the runs whose output exists in --out (figures and tables redrawn)")
    a = p.parse_args()
    prof = PROFILES[a.profile]
    src = Path(__file__).resolve().parent.parent
    out = Path(a.out)
    (out / "img").mkdir(parents=True, exist_ok=True)
    r = Runner(Path(a.build).resolve(), out, src, a.reuse)
    try:
        data = run_all(r, prof)
        checks = run_checks(data)
    except CheckFailed as e:
        sys.exit(f"spectral_polarized: check failed: {e}")
    if a.check:
        check_rejections(data)
    cost = None if a.no_cost else cost_table(r, prof)
    for theta in THETAS:
        figure_albedo(data, theta, out / "img" / f"spectral_albedo_orders_theta{theta}.png")
    figure_dop(data, out / "img" / "polarization_dop_orders.png")
    for metal in METALS:
        figure_maps(data["maps"][(metal, 0.7)], metal, 0.7, out / "img" / f"polarization_dop_maps_{metal}_a0p7.png")
    text = markdown(data, checks, cost, prof) + commands_section(r.commands)
    (out / "spectral_polarized.md").write_text("\n".join(text))
    print(f"spectral_polarized: checks passed; wrote {out / 'spectral_polarized.md'} and {out / 'img'}")


if __name__ == "__main__":
    main()
