#!/usr/bin/python3
"""Tables of analysis/converged_models.sh: the model statements of docs/findings on an ensemble of tiles.

usage: converged_models.py OUT_DIR [CELLS_PER_L]

Every value is the mean over the K tiles with two errors: +- the between-surface standard error
(spread of the K tile values / sqrt K) and [rays ...] the ray-count error of that mean.
"""
import glob
import json
import math
import os
import sys

out = sys.argv[1] if len(sys.argv) > 1 else "build/converged_models"
cells = sys.argv[2] if len(sys.argv) > 2 else "16"


def load(name):
    p = os.path.join(out, name)
    if not os.path.exists(p):
        return None
    with open(p) as f:
        return json.load(f)


def ens(xs, ses=None):
    """mean, between-surface error, ray error of the mean."""
    k = len(xs)
    m = sum(xs) / k
    sb = math.sqrt(sum((x - m) ** 2 for x in xs) / (k - 1) / k) if k > 1 else 0.0
    sr = math.sqrt(sum(s * s for s in ses)) / k if ses else 0.0
    return m, sb, sr


def per_surface_rows(j):
    return [p["rows"] for p in j["per_surface"]]


def fmt(m, sb, sr, d=4):
    return f"{m:.{d}f} ± {sb:.{d}f} [rays {sr:.{d}f}]"


print(f"# Model statements on {cells}-cells-per-l tiles (1024², 1024/{cells} = {1024 // int(cells)} l per tile)\n")
print("Mean over the tiles ± between-surface standard error [rays: ray-count error of the mean].\n")

# --- G1 averaged against Smith with the nominal NDF
j = load(f"g1_avg_c{cells}.json")
if j:
    P = per_surface_rows(j)
    K = len(P)
    print(f"## Averaged G1 against Smith (nominal Beckmann 0.5), {K} tiles\n")
    print("| θ | G1 | Smith nominal | (G1 − Smith)/Smith |")
    print("|---|---|---|---|")
    worst = 0
    for d in range(len(P[0])):
        g = [P[k][d]["g1"] for k in range(K)]
        s = [P[k][d]["g1_stderr"] for k in range(K)]
        m, sb, sr = ens(g, s)
        sm = P[0][d]["smith_nominal"]
        rel = (m - sm) / sm
        worst = max(worst, abs(rel))
        print(f"| {P[0][d]['theta_deg']:.0f}° | {fmt(m, sb, sr, 5)} | {sm:.5f} | {100 * rel:+.3f} ± {100 * sb / sm:.3f}% |")
    print(f"\nlargest |relative deviation| over θ ≤ 85°: {100 * worst:.3f}%\n")

# --- G1 per normal bin at 80 deg
j = load(f"g1_80_c{cells}.json")
if j:
    P = per_surface_rows(j)
    K = len(P)
    print(f"## G1 per normal bin at θ = 80°, φ = 0, {K} tiles\n")
    print("Deviation = measured / model − 1, per bin populated (front-facing, sampled) on every tile; z with")
    print("the combined error sqrt(between² + rays²); Šidák 1% threshold over the populated bins.\n")
    def key(x):
        return (tuple(x["theta_m_range_deg"]), tuple(x["phi_m_range_deg"]))
    by_key = [{key(x): x for x in P[k][0]["bins"]} for k in range(K)]
    rows = []
    for kb in sorted(by_key[0]):
        if any(kb not in by_key[k] for k in range(K)):
            continue
        bins = [by_key[k][kb] for k in range(K)]
        if any("g1_stderr" not in x or "smith_numeric" not in x or x.get("g1", 0) <= 0 for x in bins):
            continue
        g = [x["g1"] for x in bins]
        m, sb, sr = ens(g, [x["g1_stderr"] for x in bins])
        sm = sum(x["smith_numeric"] for x in bins) / K
        vc = sum(x["vcavity_numeric"] for x in bins) / K
        se = math.hypot(sb, sr)
        rows.append((bins[0]["theta_m_range_deg"], bins[0]["phi_m_range_deg"], m, sb, sr, sm, vc,
                     (m - sm) / se if se > 0 else 0.0, sum(x["area_fraction"] for x in bins) / K))
    n = len(rows)
    # Sidak two-sided threshold at 1% over n bins (normal quantile by bisection on erfc).
    p = 1 - (1 - 0.01) ** (1 / n)
    lo, hi = 0.0, 10.0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if math.erfc(mid / math.sqrt(2)) > p: lo = mid
        else: hi = mid
    zt = lo
    dev = [r for r in rows if abs(r[7]) > zt]
    ds = [r[2] / r[5] - 1 for r in rows]
    dv = [r[2] / r[6] - 1 for r in rows if r[6] > 0]
    print(f"populated bins {n}; Smith (the facets' Λ, no m dependence) outside the threshold z = {zt:.2f} in "
          f"{len(dev)}; measured/Smith − 1 from {100 * min(ds):+.0f}% to {100 * max(ds):+.0f}%; "
          f"measured/V-cavity − 1 from {100 * min(dv):+.0f}% to {100 * max(dv):+.0f}%\n")
    print("| θm | φm | area | G1(m) | Smith | V-cavity | z Smith |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r[0][0]:.0f}-{r[0][1]:.0f} | {r[1][0]:.0f}-{r[1][1]:.0f} | {r[8]:.4f} | {fmt(r[2], r[3], r[4])} | "
              f"{r[5]:.4f} | {r[6]:.4f} | {r[7]:+.1f} |")
    print()

# --- G2 at o = i against G1
j2 = [load(f"g2_same{t}_c{cells}.json") for t in (30, 60, 70, 80)]
j1 = load(f"g1_same_c{cells}.json")
j2 = [j for j in j2 if j]
if j2 and j1:
    P1 = per_surface_rows(j1)
    P2 = [sum((per_surface_rows(j)[k] for j in j2), []) for k in range(len(j2[0]["per_surface"]))]
    K = len(P2)
    print(f"## G2(o, o) against G1(o) [GeomBSDF24, eq. 16], φ = 0, {K} tiles, independent ray seeds\n")
    print("| θ | G2(o, o) | G1(o) | G2 − G1, paired per tile | z (rays) |")
    print("|---|---|---|---|---|")
    for r2 in range(len(P2[0])):
        t = P2[0][r2]["theta_o_deg"]
        d1 = [i for i in range(len(P1[0])) if abs(P1[0][i]["theta_deg"] - t) < 1e-9][0]
        g2 = [P2[k][r2]["g2"] for k in range(K)]
        g1 = [P1[k][d1]["g1"] for k in range(K)]
        e2 = [P2[k][r2]["g2_stderr"] for k in range(K)]
        e1 = [P1[k][d1]["g1_stderr"] for k in range(K)]
        a, b = ens(g2, e2), ens(g1, e1)
        diff = ens([x - y for x, y in zip(g2, g1)], [math.hypot(x, y) for x, y in zip(e2, e1)])
        zr = diff[0] / diff[2] if diff[2] > 0 else 0.0
        print(f"| {t:.0f}° | {fmt(*a, 5)} | {fmt(*b, 5)} | {diff[0]:+.5f} ± {diff[1]:.5f} [rays {diff[2]:.5f}] | {zr:+.1f} |")
    print()

# --- G2 at opposite azimuths: forms from the per-bin G1 and from Smith's G1
j = load(f"g2_opp_c{cells}.json")
if j:
    P = per_surface_rows(j)
    K = len(P)
    r0 = P[0][0]
    print(f"## G2 at θo = θi = {r0['theta_o_deg']:.0f}°, Δφ = {r0['delta_phi_deg']:.0f}°, {K} tiles\n")
    g2 = ens([P[k][0]["g2"] for k in range(K)], [P[k][0]["g2_stderr"] for k in range(K)])
    print(f"measured G2 {fmt(*g2, 4)}\n")
    print("| form | from each bin's measured G1: G2 − form | with the facets' Λ (Smith G1, no m): form |")
    print("|---|---|---|")
    for f in ["separable", "height_correlated", "direction_correlated", "height_direction_correlated"]:
        dd = ens([P[k][0][f + "_from_g1_diff"] for k in range(K)],
                 [P[k][0][f + "_from_g1_diff_stderr"] for k in range(K)])
        sm = ens([P[k][0]["smith_" + f] for k in range(K)])
        print(f"| {f} | {dd[0]:+.4f} ± {dd[1]:.4f} [rays {dd[2]:.4f}] | {sm[0]:.4f} ± {sm[1]:.4f} |")
    print()

# --- [Heitz14, Table 4]
names = sorted(glob.glob(os.path.join(out, f"b*_c{cells}_s*_t4.json")))
alphas = sorted({os.path.basename(n).split("_")[0][1:] for n in names}, key=float)
for a in alphas:
    js = [load(os.path.basename(n)) for n in names if os.path.basename(n).startswith(f"b{a}_c{cells}_")]
    K = len(js)
    print(f"## [Heitz14, Table 4]: mirror Beckmann α = {a}, θi = 1.5 rad, in-plane order-1 lobe, {K} tiles\n")
    a1 = ens([j["albedo"]["reflected"]["order_1"] for j in js])
    print(f"order-1 albedo {a1[0]:.4f} ± {a1[1]:.4f}; Smith single scattering "
          f"{js[0]['albedo_models']['smith_single']['reflected']:.4f}; V-cavity "
          f"{js[0]['albedo_models']['vcavity_single']['reflected']:.4f}\n")
    print("| θo | f order 1 | Smith single | measured / Smith | V-cavity single |")
    print("|---|---|---|---|---|")
    ip = [[r for r in j["in_plane"] if r["side"] == "reflected"] for j in js]
    sm_all = [r["smith_single"] for r in ip[0]]
    fwd = 1 if sum(s for r, s in zip(ip[0], sm_all) if r["theta_o_deg"] > 0) > sum(
        s for r, s in zip(ip[0], sm_all) if r["theta_o_deg"] < 0) else -1
    lobe_f, lobe_s = [0.0] * K, 0.0
    for b, r0 in enumerate(ip[0]):
        t = r0["theta_o_deg"] * fwd
        if t < 60:
            continue
        f = ens([ip[k][b]["f_order_1"] for k in range(K)], [ip[k][b]["f_order_1_stderr"] for k in range(K)])
        sm, vc = r0["smith_single"], r0["vcavity_single"]
        print(f"| {t:.2f}° | {fmt(*f, 3)} | {sm:.3f} | {f[0] / sm:.3f} ± {f[1] / sm:.3f} [rays {f[2] / sm:.3f}] | {vc:.3f} |")
        if t >= 75:
            w = math.cos(math.radians(t))
            for k in range(K):
                lobe_f[k] += w * ip[k][b]["f_order_1"]
            lobe_s += w * sm
    lf = ens(lobe_f)
    print(f"\nforward lobe θo ≥ 75° (cos-weighted sum of f): measured / Smith {lf[0] / lobe_s:.3f} ± {lf[1] / lobe_s:.3f}\n")
