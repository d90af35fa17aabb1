#!/usr/bin/python3
"""Table and figures of the discretization study (the JSON of analysis/convergence.sh).

usage: convergence.py OUT_DIR [--fixed-tile 32] [--fixed-cells 8] [--img DIR] [--markdown FILE]

Every quantity is the mean over the level's K tiles with the between-surface standard error
(sd / sqrt(K), floored at the ray-count error of the mean). A level is converged for a quantity
when it equals the reference level (the finest grid, or the largest tile) within two combined
standard errors, or within 1% relative for albedos above 1e-3 (whichever is larger).
"""
import argparse
import glob
import json
import math
import os
import re
import sys

ORDER_NAMES = ["order 1", "order 2", "order 3", "order 4+", "total"]
# In-plane bins of 5 degrees (psi = -90 + 5 b ... ), grouped: forward peak, its shoulder, backward.
LOBE_GROUPS = {"75-90": (33, 34, 35), "60-75": (30, 31, 32), "-45 to -15": (9, 10, 11, 12, 13, 14)}


def load_levels(out):
    levels = {}
    for f in sorted(glob.glob(os.path.join(out, "*_c*_t*.json"))):
        m = re.match(r"(.+)_a([0-9.]+)_c(\d+)_t(\d+)\.json$", os.path.basename(f))
        if not m:
            continue
        with open(f) as fh:
            j = json.load(fh)
        j["cost"] = read_time(f[:-5] + ".time")
        levels[(m.group(1), m.group(2), int(m.group(3)), int(m.group(4)))] = j
    return levels


def read_time(path):
    cost = {"cpu_seconds": float("nan"), "peak_rss_mib": float("nan"), "wall": ""}
    if not os.path.exists(path):
        return cost
    user = sys_ = 0.0
    for line in open(path):
        line = line.strip()
        if line.startswith("User time"):
            user = float(line.split(":")[-1])
        elif line.startswith("System time"):
            sys_ = float(line.split(":")[-1])
        elif line.startswith("Maximum resident set size"):
            cost["peak_rss_mib"] = int(line.split(":")[-1]) / 1024.0
        elif line.startswith("Elapsed"):
            cost["wall"] = line.split(": ")[-1]
    cost["cpu_seconds"] = user + sys_
    return cost


def ensemble(values, ray_errors=None):
    """Mean over tiles and its between-surface error, floored at the ray-count error of the mean."""
    k = len(values)
    if k == 0:
        return float("nan"), float("nan"), 0
    mean = sum(values) / k
    se = math.sqrt(sum((v - mean) ** 2 for v in values) / (k - 1) / k) if k > 1 else float("nan")
    if ray_errors:
        se = max(se, math.sqrt(sum(s * s for s in ray_errors)) / k)
    return mean, se, k


def bin_g1(tile, theta_lo, phi_lo):
    for b in tile["g1_80_bins"]:
        if abs(b["theta_lo"] - theta_lo) < 1e-6 and abs(b["phi_lo"] - phi_lo) < 1e-6:
            return b["g1"]
    return None


def quantities(level):
    """Ordered list of (name, is_albedo, mean, se, K) of one level."""
    tiles = level["tiles"]
    rows = []

    def add(name, per_tile, albedo=False):
        by_seed = {}
        for t, p in zip(tiles, per_tile):
            if p is None:
                continue
            by_seed[t["seed"]] = (p[0], p[1]) if isinstance(p, list) else (p, 0.0)
        if not by_seed:
            return
        vals = list(by_seed.values())
        m, s, k = ensemble([v[0] for v in vals], [v[1] for v in vals])
        rows.append((name, albedo, m, s, k, by_seed))

    ggx = level.get("kind") == "gaussian-ggx"
    # GGX has no slope variance: its rms-slope alpha is set by the generator's tail cap.
    add("rms-slope alpha (tail-capped)" if ggx else "fitted alpha", [t["alpha_fit"] for t in tiles])
    if "median_tan_theta_m" in tiles[0]:
        # Median of tan theta_m over the projected area: alpha (GGX), alpha sqrt(ln 2) (Beckmann).
        norm = 1.0 if ggx else math.sqrt(math.log(2))
        add("fitted alpha (median tan theta_m)", [t["median_tan_theta_m"] / norm for t in tiles])
    for ring in (0, 6, 9, 12, 13, 14):
        lo = 5 * ring
        add(f"D / nominal, theta_m {lo}-{lo + 5} deg",
            [t["d_ring"][ring] / level["d_ring_nominal"][ring] for t in tiles])
    add("G1(80 deg) averaged", [t["g1_80"] for t in tiles])
    for (tl, pl, what) in ((20, 0, "toward"), (40, 0, "toward"), (40, 180, "away")):
        add(f"G1(80 deg, m) theta_m {tl}-{tl + 10}, phi_m {pl}-{pl + 45} ({what})",
            [bin_g1(t, tl, pl) for t in tiles])
    add("G2(70, 70 deg), same azimuth", [t["g2_70_70_dphi0"] for t in tiles])
    add("G2(70, 70 deg), opposite azimuths", [t["g2_70_70_dphi180"] for t in tiles])
    add("VNDF(80 deg) chi2 divergence from nominal", [t["vndf_80_divergence"] for t in tiles])
    for th in (0, 60, 80):
        for k in range(4):
            add(f"mirror {th} deg {ORDER_NAMES[k]}", [t[f"mirror_{th}"][k] for t in tiles], True)
    for th in (0, 60):
        for side in ("reflected", "transmitted"):
            for k in (0, 1, 2, 3, 4):
                add(f"dielectric 1.5, {th} deg {side} {ORDER_NAMES[k]}",
                    [t[f"dielectric_{th}_{side}"][k] for t in tiles], True)
    def lobe(t, key, bins):  # mean f over the bins, error of independent bins
        vals = [t[key][b] for b in bins]
        return [sum(v[0] for v in vals) / len(vals), math.sqrt(sum(v[1] ** 2 for v in vals)) / len(vals)]

    for label, bins in LOBE_GROUPS.items():
        add(f"lobe 80 deg order 1, theta_o {label} (mean f)", [lobe(t, "lobe_80_order_1", bins) for t in tiles])
        add(f"lobe 80 deg total, theta_o {label} (mean f)", [lobe(t, "lobe_80_total", bins) for t in tiles])
    return rows


def difference(row, ref, paired):
    """Difference of a level from the reference and its standard error. Paired (tiles of the same
    seed on both levels, common random numbers): the mean of the per-tile differences, error from
    their spread (floored at the ray-count error); else the two ensemble errors combined."""
    if paired:
        common = sorted(set(row[5]) & set(ref[5]))
        if len(common) >= 2:
            d = [row[5][k][0] - ref[5][k][0] for k in common]
            rays = [math.hypot(row[5][k][1], ref[5][k][1]) for k in common]
            m, se, _ = ensemble(d, rays)
            return m, se
    return row[2] - ref[2], math.hypot(row[3], ref[3])


def converged(row, ref, paired):
    """|difference| within 2 standard errors, or 1% relative for albedos > 1e-3."""
    d, se = difference(row, ref, paired)
    tol = 2 * se
    if row[1] and abs(ref[2]) > 1e-3:
        tol = max(tol, 0.01 * abs(ref[2]))
    return abs(d) <= tol


def fmt(m, s):
    if s != s or s <= 0:
        return f"{m:.5g}"
    digits = max(0, min(6, 1 - int(math.floor(math.log10(s)))))
    return f"{m:.{digits}f} ± {s:.1g}"


def sweep_table(levels, keys, labels, ref_index, title, lines, marked=None, paired=False, diffs=None):
    """Markdown table: quantity x level; a dagger marks a level that is not converged. `diffs`
    (a list) receives the table of differences from the reference."""
    rows = [quantities(levels[k]) for k in keys]
    ref = rows[ref_index]
    if diffs is not None:
        diffs.append(f"\n{title} Difference from the reference ({'paired, same tiles' if paired else 'unpaired'}), "
                     "in % of the reference value (absolute where it is below 1e-6): Δ ± standard error.\n")
        diffs.append("| quantity | " + " | ".join(labels[i] for i in range(len(keys)) if i != ref_index) +
                     f" | {labels[ref_index]} (reference) |")
        diffs.append("|" + "---|" * (len(keys) + 1))
        for r0 in ref:
            cells = []
            for li, rows_l in enumerate(rows):
                if li == ref_index:
                    continue
                r = next((x for x in rows_l if x[0] == r0[0]), None)
                if r is None:
                    cells.append("-")
                    continue
                d, se = difference(r, r0, paired)
                mark = "" if converged(r, r0, paired) else " †"
                if abs(r0[2]) > 1e-6:
                    cells.append(f"{100 * d / abs(r0[2]):+.2f} ± {100 * se / abs(r0[2]):.2f}{mark}")
                else:
                    cells.append(f"{d:+.2g} ± {se:.1g}{mark}")
            diffs.append(f"| {r0[0]} | " + " | ".join(cells) + f" | {fmt(r0[2], r0[3])} |")
    head = "| quantity | " + " | ".join(
        labels[i] + (" **(default)**" if marked is not None and i == marked else "") for i in range(len(keys))) + \
        " | converged from |"
    lines.append(f"\n{title}\n")
    lines.append(head)
    lines.append("|" + "---|" * (len(keys) + 2))
    first_ok = {}
    for qi, r0 in enumerate(ref):
        name = r0[0]
        cells = []
        ok = []
        for li, rows_l in enumerate(rows):
            r = next((x for x in rows_l if x[0] == name), None)
            if r is None:
                cells.append("-")
                ok.append(True)
                continue
            c = converged(r, r0, paired) if li != ref_index else True
            ok.append(c)
            cells.append(fmt(r[2], r[3]) + ("" if c else " †"))
        # The coarsest level from which every finer level is converged.
        start = len(keys) - 1
        for li in range(len(keys) - 1, -1, -1):
            if all(ok[li:]):
                start = li
        first_ok[name] = start
        lines.append(f"| {name} | " + " | ".join(cells) + f" | {labels[start]} |")
    return first_ok


def cost_table(levels, keys, lines):
    lines.append("\n| level | tile | tiles | CPU s (user+sys) | CPU s per tile | peak RSS (MiB) | wall |")
    lines.append("|---|---|---|---|---|---|---|")
    for k in keys:
        j = levels[k]
        c = j["cost"]
        n = j["resolution"]
        lines.append(f"| {k[2]} cells/l, L/l = {k[3]} | {n}² | {j['surfaces']} | {c['cpu_seconds']:.0f} | "
                     f"{c['cpu_seconds'] / j['surfaces']:.1f} | {c['peak_rss_mib']:.0f} | {c['wall']} |")


def figures(levels, kind, alpha, cells_keys, tiles_keys, img, tag, paired=False):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib not available: no figures", file=sys.stderr)
        return []
    os.makedirs(img, exist_ok=True)
    written = []
    picks = ["fitted alpha", "fitted alpha (median tan theta_m)", "G1(80 deg) averaged", "G2(70, 70 deg), opposite azimuths",
             "mirror 60 deg order 1", "mirror 60 deg order 2", "mirror 60 deg order 3",
             "mirror 80 deg order 1", "dielectric 1.5, 60 deg transmitted order 2",
             "lobe 80 deg order 1, theta_o 75-90 (mean f)"]
    for keys, xlab, which in ((cells_keys, "cells per correlation length l / dx", 2),
                              (tiles_keys, "correlation lengths per tile L / l", 3)):
        if len(keys) < 2:
            continue
        rows = [dict((r[0], r) for r in quantities(levels[k])) for k in keys]
        ref = rows[-1]
        xs = [k[which] for k in keys]
        fig, ax = plt.subplots(figsize=(6.4, 4.0), dpi=80)
        for i, name in enumerate(picks):
            if name not in ref:
                continue
            mr = ref[name][2]
            pairs = [difference(r[name], ref[name], paired and which == 2) if r is not ref else (0.0, 0.0)
                     for r in rows]
            y = [p[0] / abs(mr) * 100 for p in pairs]
            e = [p[1] / abs(mr) * 100 for p in pairs]
            off = 1 + 0.02 * (i - len(picks) / 2)
            ax.errorbar([x * off for x in xs], y, yerr=e, marker="o", ms=3, capsize=2, label=name)
        ax.axhline(0, color="k", lw=0.5)
        ax.axhspan(-1, 1, color="0.9", zorder=0)
        ax.set_xscale("log", base=2)
        ax.set_xticks(xs)
        ax.set_xticklabels([str(x) for x in xs])
        ax.set_xlabel(xlab)
        ax.set_ylabel("difference from the reference level (%)")
        ax.set_title(f"{kind} α = {alpha}: " + ("grid sweep, L/l = %d" % keys[0][3] if which == 2
                                               else "tile sweep, %d cells per l" % keys[0][2]), fontsize=10)
        ax.set_ylim(-25, 25)
        ax.legend(fontsize=6, loc="upper right", ncol=2)
        fig.tight_layout()
        name = os.path.join(img, f"convergence_{tag}_{'cells' if which == 2 else 'tile'}.png")
        fig.savefig(name)
        plt.close(fig)
        written.append(name)
    # The in-plane lobe at 80 deg per grid level.
    if cells_keys:
        fig, ax = plt.subplots(figsize=(6.4, 3.6), dpi=80)
        for k in cells_keys:
            tiles = levels[k]["tiles"]
            nb = len(tiles[0]["lobe_80_order_1"])
            psi = [-90 + 180 * (b + 0.5) / nb for b in range(nb)]
            m1 = [ensemble([t["lobe_80_order_1"][b][0] for t in tiles])[0] for b in range(nb)]
            mt = [ensemble([t["lobe_80_total"][b][0] for t in tiles])[0] for b in range(nb)]
            line, = ax.plot(psi, m1, marker=".", ms=3, label=f"{k[2]} cells/l, order 1")
            ax.plot(psi, mt, ls=":", color=line.get_color())
        ax.set_yscale("log")
        ax.set_xlabel("signed θo in the plane of incidence (deg; specular side > 0)")
        ax.set_ylabel("f cos θo  (1/sr)")
        ax.set_title(f"{kind} α = {alpha}, mirror, θi = 80°: in-plane lobe (dotted: all orders)", fontsize=10)
        ax.legend(fontsize=7)
        fig.tight_layout()
        name = os.path.join(img, f"convergence_{tag}_lobe80.png")
        fig.savefig(name)
        plt.close(fig)
        written.append(name)
    return written


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--fixed-tile", type=int, default=32)
    ap.add_argument("--fixed-cells", type=int, default=8)
    ap.add_argument("--default-cells", type=int, default=None, help="mark this grid level as the default")
    ap.add_argument("--img", default=None, help="figures folder (default OUT/img)")
    ap.add_argument("--markdown", default=None, help="table file (default OUT/convergence.md)")
    a = ap.parse_args()
    levels = load_levels(a.out)
    img = a.img or os.path.join(a.out, "img")
    lines = ["# Discretization study of Gaussian heightfields",
             "",
             "Mean over K independent tiles ± between-surface standard error. † : differs from the "
             "reference level (last column of the sweep) by more than two combined standard errors "
             "(and, for albedos above 1e-3, by more than 1%). 'converged from': the coarsest level "
             "from which every finer level is converged."]
    summary = {}
    for (kind, alpha) in sorted({(k[0], k[1]) for k in levels}):
        mine = {k: v for k, v in levels.items() if k[0] == kind and k[1] == alpha}
        cells_keys = sorted([k for k in mine if k[3] == a.fixed_tile], key=lambda k: k[2])
        tiles_keys = sorted([k for k in mine if k[2] == a.fixed_cells], key=lambda k: k[3])
        lines.append(f"\n## {kind}, α = {alpha}")
        marked = None
        if a.default_cells is not None:
            marked = next((i for i, k in enumerate(cells_keys) if k[2] == a.default_cells), None)
        diffs = []
        paired = bool(cells_keys) and all(levels[k].get("nested") for k in cells_keys)
        s1 = sweep_table(levels, cells_keys, [f"{k[2]} cells/l" for k in cells_keys], len(cells_keys) - 1,
                         f"Grid sweep at L/l = {a.fixed_tile} (tile {a.fixed_tile} correlation lengths wide); "
                         "reference: the finest grid.", lines, marked, paired, diffs) if cells_keys else {}
        s2 = sweep_table(levels, tiles_keys, [f"L/l = {k[3]}" for k in tiles_keys], len(tiles_keys) - 1,
                         f"Tile sweep at {a.fixed_cells} cells per l; reference: the largest tile.",
                         lines, None, False, diffs) if len(tiles_keys) > 1 else {}
        # Further grids at other tile sizes (the check of a proposed default against a finer grid
        # on the same tiles).
        for t in sorted({k[3] for k in mine if k[3] != a.fixed_tile}):
            ks = sorted([k for k in mine if k[3] == t], key=lambda k: k[2])
            if len(ks) < 2:
                continue
            pr = all(levels[k].get("nested") for k in ks)
            sweep_table(levels, ks, [f"{k[2]} cells/l" for k in ks], len(ks) - 1,
                        f"Grid check at L/l = {t}; reference: the finest grid.", lines, None, pr, diffs)
        lines.extend(diffs)
        lines.append("\nCost per level (every quantity above; /usr/bin/time -v, niced, on a shared 2-core machine):")
        cost_table(levels, sorted(mine, key=lambda k: (k[3], k[2])), lines)
        smith = {}
        for k in cells_keys:
            for th in (0, 60, 80):
                key = f"smith_walk_mirror_{th}"
                if key in mine[k]:
                    smith[th] = mine[k][key]
        if smith:
            lines.append("\nSmith random walk of the nominal NDF (mirror; walks' own error):")
            lines.append("\n| θi | " + " | ".join(ORDER_NAMES[:4]) + " |")
            lines.append("|---|---|---|---|---|")
            for th, v in sorted(smith.items()):
                lines.append(f"| {th}° | " + " | ".join(fmt(x[0], x[1]) for x in v[:4]) + " |")
        tag = f"{kind}_a{alpha}".replace(".", "p")
        figs = figures(levels, kind, alpha, cells_keys, tiles_keys, img, tag, paired)
        summary[f"{kind} {alpha}"] = {"grid": {n: (cells_keys[i][2] if cells_keys else None) for n, i in s1.items()},
                                      "tile": {n: (tiles_keys[i][3] if tiles_keys else None) for n, i in s2.items()},
                                      "figures": figs}
    text = "\n".join(lines) + "\n"
    md = a.markdown or os.path.join(a.out, "convergence.md")
    with open(md, "w") as f:
        f.write(text)
    with open(os.path.join(a.out, "convergence_summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    print(text)


if __name__ == "__main__":
    main()
