#!/usr/bin/python3
"""Summary of the albedo lookup tables written by analysis/albedo_lut.sh (markdown on stdout).

usage: albedo_lut.py OUT_DIR [--resolution N] [--generate-seconds S] [--measure-seconds S]
       [--figure PATH]

Reads OUT_DIR/lut-<family>.json (records of `microsim measure albedo`), prints per family and
alpha E_avg of all orders and of order 1 (single scattering) with their statistical and
quadrature errors and the largest standard error of the error map, and draws E(mu) of order 1
per alpha (figure OUT_DIR/albedo_lut.png unless --figure).
"""
import argparse
import glob
import json
import os
import sys


def averages(record, series):
    return {a["surface"]: a for a in record["averages"] if a["series"] == series}


def max_stderr(record, surface, column):
    return max(r[column + "_stderr"] for r in record["rows"] if r["surface"] == surface)


def curve(record, surface, column):
    rows = [r for r in record["rows"] if r["surface"] == surface]
    return [r["mu"] for r in rows], [r[column] for r in rows], [r[column + "_stderr"] for r in rows]


def fmt(x, digits=5):
    return "–" if x is None else f"{x:.{digits}f}"


def sci(x):
    return "–" if x is None else f"{x:.1e}"


def table(name, record):
    total, single = averages(record, "albedo"), averages(record, "reflected_order_1")
    print(f"### {name}\n")
    print("| alpha | E_avg (all orders) | stderr | E_avg order 1 | stderr | quadrature error (order 1) "
          "| 1 - E_avg order 1 | max stderr E | max stderr E order 1 | lost paths |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for s in record["surfaces"]:
        f = s["file"]
        alpha = s["alpha"]
        ndf = s["nominal_ndf"] or {}
        label = fmt(alpha, 3) if ndf.get("alpha_x") == ndf.get("alpha_y") else \
            f"{ndf['alpha_x']:.2f} x {ndf['alpha_y']:.2f}"
        t, o = total[f], single[f]
        print(f"| {label} | {fmt(t['average'], 6)} | {sci(t['average_stderr'])} | {fmt(o['average'])} | "
              f"{sci(o['average_stderr'])} | {sci(o['quadrature_error'])} | {fmt(1 - o['average'])} | "
              f"{sci(max_stderr(record, f, 'albedo'))} | {sci(max_stderr(record, f, 'reflected_order_1'))} | "
              f"{s['lost_paths']} |")
    print()


def figure(records, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax, (name, record) in zip(axes, records):
        cmap = plt.get_cmap("viridis")
        n = len(record["surfaces"])
        for k, s in enumerate(record["surfaces"]):
            mu, e, se = curve(record, s["file"], "reflected_order_1")
            ax.errorbar(mu, e, yerr=se, marker="o", ms=3, color=cmap(k / max(1, n - 1)),
                        label=f"alpha {s['alpha']:.2f}")
            mu, e, _ = curve(record, s["file"], "albedo")
            ax.plot(mu, e, color=cmap(k / max(1, n - 1)), lw=0.6, ls=":")
        ax.set_title(f"{name}: E(mu) of order 1 (dotted: all orders)")
        ax.set_xlabel("mu = cos theta_i")
        ax.set_xlim(0, 1)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("directional albedo E")
    axes[1].legend(fontsize=7, loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--resolution", type=int, default=None)
    p.add_argument("--generate-seconds", type=float, default=None)
    p.add_argument("--measure-seconds", type=float, default=None)
    p.add_argument("--figure", default=None)
    a = p.parse_args()
    records = []
    for name in ("beckmann", "ggx", "beckmann-aniso"):
        path = os.path.join(a.out, f"lut-{name}.json")
        if os.path.exists(path):
            with open(path) as f:
                records.append((name, json.load(f)))
    if not records:
        sys.exit(f"no lut-*.json in {a.out}")
    r0 = records[0][1]
    q = r0["quadrature"]
    print("# Albedo lookup tables of mirror heightfields\n")
    print(f"Converged Gaussian tiles ({a.resolution or '?'}^2 cells, 16 cells per correlation length), "
          f"mirror; {q['description']}; {r0['parameters']['rays_per_node']} rays per node and surface, "
          f"{r0['parameters']['replicates']} replicates; threads {r0.get('threads')}.")
    if a.generate_seconds is not None:
        print(f"Wall time: {a.generate_seconds:.0f} s generating, {a.measure_seconds:.0f} s measuring "
              f"({os.cpu_count()} processors).")
    print()
    for name, record in records:
        table(name, record)
    figure([r for r in records if r[0] != "beckmann-aniso"], a.figure or os.path.join(a.out, "albedo_lut.png"))
    print(f"Figure: {a.figure or os.path.join(a.out, 'albedo_lut.png')}")


if __name__ == "__main__":
    main()
