#!/usr/bin/python3
"""Prints the BSDF-per-order tables from the JSON summaries written by tables_bsdf_orders.sh.

usage: tables_bsdf_orders.py OUT_DIR
"""
import glob
import json
import math
import os
import sys

out = sys.argv[1] if len(sys.argv) > 1 else "build/tables_bsdf_orders"


def load(name):
    with open(os.path.join(out, name)) as f:
        return json.load(f)


def z(x, m, s):
    return (x - m) / s if s > 0 else float("nan")


def fmt_z(v):
    return "   -  " if v != v else f"{v:6.2f}"


ORDERS = ["order_1", "order_2", "order_3", "order_4plus", "total"]

# ---------------------------------------------------------------------------------------------
print("== 1. Flat dielectric: albedos against Fresnel [GeomBSDF24, eq. 7d, 10b]; 1048576 rays each")
print(f"{'eta':>7} {'theta':>6} {'R':>9} {'+-':>8} {'F':>9} {'z':>6} {'T':>9} {'+-':>8} {'1-F':>9} {'z':>6} {'R+T':>10} {'lost':>5}")
for eta in ["1.5", "0.6666666666666666"]:
    for th in [0, 30, 60, 80]:
        j = load(f"flat_e{eta}_t{th}.json")
        R, T = j["albedo"]["reflected"]["total"], j["albedo"]["transmitted"]["total"]
        sR, sT = j["reflected_stderr"]["total"], j["transmitted_stderr"]["total"]
        F = j["albedo_models"]["smooth_interface"]["reflected"]
        print(f"{float(eta):7.4f} {th:6d} {R:9.6f} {sR:8.6f} {F:9.6f} {fmt_z(z(R, F, sR))} "
              f"{T:9.6f} {sT:8.6f} {1 - F:9.6f} {fmt_z(z(T, 1 - F, sT))} {R + T:10.7f} {j['lost_paths']:5d}")
print("(R = 1 exactly beyond the critical angle of 1/1.5, 41.8 deg: total internal reflection.)")

# ---------------------------------------------------------------------------------------------
print()
print("== 2. Mirror Beckmann tiles (1024^2, correlation length 4 cells), 1048576 rays per run")
files = sorted(glob.glob(os.path.join(out, "mirror_a*_s*_t*.json")))
runs = {}
for f in files:
    base = os.path.basename(f)[len("mirror_"):-len(".json")]
    a, s, t = base.split("_")
    runs.setdefault((float(a[1:]), int(t[1:])), {})[int(s[1:])] = load(os.path.basename(f))
print("Seed-1 tile, ray-count errors; smith_multiple = Smith random walk (same number of walks);")
print("smith_single = analytic single-scattering albedo (height-correlated G2).")
print(f"{'alpha':>5} {'theta':>5} {'order':>12} {'measured':>9} {'+-':>8} {'smith_mult':>10} {'+-':>8} {'z':>7} {'rel.dev':>8} "
      f"{'smith_single':>12} {'z':>7} {'rel.dev':>8} {'vcav_single':>11}")
for (a, t), per_seed in sorted(runs.items()):
    j = per_seed[min(per_seed)]
    mm = j["albedo_models"]["smith_multiple"]
    for k in ORDERS:
        x, s = j["albedo"]["reflected"][k], j["reflected_stderr"][k]
        m, ms = mm["reflected"][k], mm["reflected_stderr"][k]
        zz = z(x, m, math.hypot(s, ms))
        rel = (x - m) / m if m else float("nan")
        line = f"{a:5.1f} {t:5d} {k:>12} {x:9.5f} {s:8.5f} {m:10.5f} {ms:8.5f} {fmt_z(zz):>7} {100 * rel:7.2f}%"
        if k == "order_1":
            ss = j["albedo_models"]["smith_single"]["reflected"]
            vc = j["albedo_models"]["vcavity_single"]["reflected"]
            line += f" {ss:12.5f} {fmt_z(z(x, ss, s)):>7} {100 * (x - ss) / ss:7.2f}% {vc:11.5f}"
        print(line)
    print(f"{'':11} total albedo 1 - {1 - j['albedo']['reflected']['total']:.2e} (stderr "
          f"{j['reflected_stderr']['total']:.1e}); lost paths {j['lost_paths']}, unterminated {j['unterminated_paths']}")

if any(len(v) > 1 for v in runs.values()):
    print()
    print("Ensemble of tiles (seeds " + ", ".join(str(s) for s in sorted(next(iter(runs.values())))) +
          "): mean over tiles, between-surface standard error (the error to use against a nominal model)")
    print(f"{'alpha':>5} {'theta':>5} {'order':>12} {'mean':>9} {'se_tiles':>8} {'se_rays':>8} {'smith_mult':>10} {'z':>7} "
          f"{'rel.dev':>8} {'smith_single':>12} {'z':>7} {'rel.dev':>8}")
    for (a, t), per_seed in sorted(runs.items()):
        K = len(per_seed)
        for k in ORDERS:
            xs = [per_seed[s]["albedo"]["reflected"][k] for s in per_seed]
            mean = sum(xs) / K
            sd = math.sqrt(sum((x - mean) ** 2 for x in xs) / (K - 1)) if K > 1 else 0.0
            se = sd / math.sqrt(K)
            se_rays = math.sqrt(sum(per_seed[s]["reflected_stderr"][k] ** 2 for s in per_seed)) / K
            ms = [per_seed[s]["albedo_models"]["smith_multiple"]["reflected"][k] for s in per_seed]
            mse = [per_seed[s]["albedo_models"]["smith_multiple"]["reflected_stderr"][k] for s in per_seed]
            m = sum(ms) / K
            m_se = math.sqrt(sum(e * e for e in mse)) / K
            tot_se = math.hypot(se, m_se)
            line = (f"{a:5.1f} {t:5d} {k:>12} {mean:9.5f} {se:8.5f} {se_rays:8.5f} {m:10.5f} {fmt_z(z(mean, m, tot_se)):>7} "
                    f"{100 * (mean - m) / m if m else float('nan'):7.2f}%")
            if k == "order_1":
                ss = per_seed[min(per_seed)]["albedo_models"]["smith_single"]["reflected"]
                line += f" {ss:12.5f} {fmt_z(z(mean, ss, se)):>7} {100 * (mean - ss) / ss:7.2f}%"
            if k == "total":
                line += f"   lost paths per tile: {[per_seed[s]['lost_paths'] for s in sorted(per_seed)]}"
            print(line)

# ---------------------------------------------------------------------------------------------
print()
print("== 3. [Heitz14, Table 4]: in-plane order-1 lobe, mirror Beckmann, theta_i = 1.5 rad (85.94 deg),")
print("   4194304 rays per tile, 32 bins of 5.625 deg, band +-2.8 deg; f = radiance BRDF. Mean over the")
print("   ensemble of tiles; se_tiles = between-surface standard error (at grazing incidence a few")
print("   lit facets dominate each bin: one tile differs from the next by far more than its ray error)")


def ensemble(js, get):
    xs = [get(j) for j in js]
    K = len(xs)
    m = sum(xs) / K
    sd = math.sqrt(sum((x - m) ** 2 for x in xs) / (K - 1)) if K > 1 else 0.0
    return m, sd / math.sqrt(K)


verdicts = []
for a in ["0.1", "0.4", "0.7", "1.0", "1.3"]:
    names = sorted(glob.glob(os.path.join(out, f"table4_a{a}_s*.json")))
    if not names:
        continue
    js = [load(os.path.basename(n)) for n in names]
    K = len(js)
    j0 = js[0]
    a1, a1se = ensemble(js, lambda j: j["albedo"]["reflected"]["order_1"])
    print(f"-- alpha = {a} ({K} tiles): order-1 albedo {a1:.4f} +- {a1se:.4f}, "
          f"smith_single {j0['albedo_models']['smith_single']['reflected']:.4f}, "
          f"vcavity_single {j0['albedo_models']['vcavity_single']['reflected']:.4f}")
    print(f"   {'theta_o':>8} {'f_order_1':>10} {'se_tiles':>8} {'se_rays':>8} {'smith':>10} {'z':>7} {'vcavity':>10} {'z':>7} "
          f"{'f_total':>9} {'smith_mult':>10}")
    nb = len([r for r in j0["in_plane"] if r["side"] == "reflected"])
    chi_s = chi_v = 0.0
    n = 0
    num_s = num_v = den = 0.0
    means = []
    top = max(r["smith_single"] for r in j0["in_plane"])
    for b in range(nb):
        r0 = j0["in_plane"][b]
        f1, se = ensemble(js, lambda j: j["in_plane"][b]["f_order_1"])
        se_r = math.sqrt(sum(j["in_plane"][b]["f_order_1_stderr"] ** 2 for j in js)) / K
        ft, _ = ensemble(js, lambda j: j["in_plane"][b]["f_total"])
        smm, _ = ensemble(js, lambda j: j["in_plane"][b]["smith_multiple"])
        sm, vc = r0["smith_single"], r0["vcavity_single"]
        means.append((r0["theta_o_deg"], f1, sm, vc))
        if f1 > 3 * se or sm > 0.01 * top:
            print(f"   {r0['theta_o_deg']:8.2f} {f1:10.4f} {se:8.4f} {se_r:8.4f} {sm:10.4f} {fmt_z(z(f1, sm, se)):>7} "
                  f"{vc:10.4f} {fmt_z(z(f1, vc, se)):>7} {ft:9.4f} {smm:10.4f}")
        if se > 0 and f1 > 5 * se:
            chi_s += z(f1, sm, se) ** 2
            chi_v += z(f1, vc, se) ** 2
            n += 1
        w = math.cos(math.radians(r0["theta_o_deg"]))
        num_s += w * (f1 - sm) ** 2
        num_v += w * (f1 - vc) ** 2
        den += w * f1 ** 2
    pm = max(means, key=lambda t: t[1])[0]
    ps = max(means, key=lambda t: t[2])[0]
    pv = max(means, key=lambda t: t[3])[0]
    # mean of theta_o over the lobe (cos-weighted), a shape measure: backscattering pulls it down
    cm = sum(t[1] * math.cos(math.radians(t[0])) * t[0] for t in means) / sum(t[1] * math.cos(math.radians(t[0])) for t in means)
    cs = sum(t[2] * math.cos(math.radians(t[0])) * t[0] for t in means) / sum(t[2] * math.cos(math.radians(t[0])) for t in means)
    cv = sum(t[3] * math.cos(math.radians(t[0])) * t[0] for t in means) / sum(t[3] * math.cos(math.radians(t[0])) for t in means)
    ds, dv = math.sqrt(num_s / den), math.sqrt(num_v / den)
    verdicts.append((a, ds, dv, chi_s / max(n, 1), chi_v / max(n, 1), pm, ps, pv, cm, cs, cv,
                     "Smith" if ds < dv else "V-cavity"))
print()
print("Summary: relative L2 distance of the measured order-1 lobe (ensemble mean) to each model,")
print("cos-weighted over the in-plane bins; chi^2 per bin (between-surface errors, bins with f > 5 se);")
print("peak bin; lobe centroid (mean signed theta_o weighted by f cos theta_o)")
print(f"{'alpha':>5} {'L2 smith':>9} {'L2 vcav':>9} {'chi2/n smith':>12} {'chi2/n vcav':>12} {'peak':>6} {'centroid meas':>13} "
      f"{'smith':>7} {'vcav':>7}  follows")
for a, ds, dv, cs2, cv2, pm, ps, pv, cm, cs, cv, fol in verdicts:
    print(f"{float(a):5.1f} {ds:9.4f} {dv:9.4f} {cs2:12.1f} {cv2:12.1f} {pm:6.2f} {cm:13.2f} {cs:7.2f} {cv:7.2f}  {fol}")

# ---------------------------------------------------------------------------------------------
print()
print("== 4. Dielectric Beckmann alpha 0.5, 4194304 rays per run (lobes: the ensemble of tiles;")
print("   reciprocity: the seed-1 tile and the same tile seen from below)")
print("R + T (each path leaves up or down):")
for name in sorted(glob.glob(os.path.join(out, "diel_*.json"))):
    j = load(os.path.basename(name))
    p = j["parameters"]
    RT, sRT = j["reflected_plus_transmitted"], j["reflected_plus_transmitted_stderr"]
    print(f"  {os.path.basename(name):32} eta {p['eta']:.4f} theta {p['theta_i_deg']:8.4f} phi {p['phi_i_deg']:4.0f}: "
          f"R {j['albedo']['reflected']['total']:.5f}  T {j['albedo']['transmitted']['total']:.5f}  "
          f"R+T {RT:.7f} +- {sRT:.1e}  lost {j['lost_paths']}  (smith_multiple R "
          f"{j['albedo_models']['smith_multiple']['reflected']['total']:.5f}, T "
          f"{j['albedo_models']['smith_multiple']['transmitted']['total']:.5f})")

for stem, label in [("diel_e1.5_t53_p0", "eta 1.5, theta_i 53.44 (into glass)"),
                    ("diel_e0.6666666666666666_t31_p0", "eta 1/1.5, theta_i 30.94 (into the less dense medium)")]:
    names = sorted(glob.glob(os.path.join(out, stem + "_s*.json")))
    if not names:
        continue
    js = [load(os.path.basename(n)) for n in names]
    K, j0 = len(js), js[0]
    t1, t1se = ensemble(js, lambda j: j["albedo"]["transmitted"]["order_1"])
    rt, rtse = ensemble(js, lambda j: j["reflected_plus_transmitted"])
    print()
    print(f"Order-1 transmission lobe, {label}, {K} tiles: albedo T1 {t1:.5f} +- {t1se:.5f} (tiles), "
          f"smith_single {j0['albedo_models']['smith_single']['transmitted']:.5f}, "
          f"vcavity_single {j0['albedo_models']['vcavity_single']['transmitted']:.5f}; R+T {rt:.7f}")
    print(f"   {'theta_o':>8} {'f_order_1':>10} {'se_tiles':>8} {'se_rays':>8} {'smith_BTDF':>10} {'z':>7} {'rel':>7} "
          f"{'vcav_BTDF':>10} {'z':>7} {'f_total':>9} {'smith_mult':>10}")
    rows0 = j0["in_plane"]
    top = max(r["smith_single"] for r in rows0 if r["side"] == "transmitted")
    for b, r0 in enumerate(rows0):
        if r0["side"] != "transmitted":
            continue
        f1, se = ensemble(js, lambda j: j["in_plane"][b]["f_order_1"])
        se_r = math.sqrt(sum(j["in_plane"][b]["f_order_1_stderr"] ** 2 for j in js)) / K
        ft, _ = ensemble(js, lambda j: j["in_plane"][b]["f_total"])
        smm, _ = ensemble(js, lambda j: j["in_plane"][b]["smith_multiple"])
        sm, vc = r0["smith_single"], r0["vcavity_single"]
        if f1 > 3 * se or sm > 0.02 * top:
            rel = (f1 - sm) / sm if sm > 0 else float("nan")
            print(f"   {r0['theta_o_deg']:8.2f} {f1:10.4f} {se:8.4f} {se_r:8.4f} {sm:10.4f} {fmt_z(z(f1, sm, se)):>7} {100 * rel:6.1f}% "
                  f"{vc:10.4f} {fmt_z(z(f1, vc, se)):>7} {ft:9.4f} {smm:10.4f}")


def bin_row(j, side, theta):
    rows = [r for r in j["in_plane"] if r["side"] == side]
    return min(rows, key=lambda r: abs(r["theta_o_deg"] - theta))


print()
print("Reciprocity of the measured tables [GeomBSDF24, eq. 4c]: f(o <- i) / eta_o^2 = f(i <- o) / eta_i^2;")
print("light from below = light from above on the flipped tile (heights negated) with the inverse index")
print(f"{'path':>44} {'f(o<-i)':>10} {'+-':>8} {'f(i<-o)':>10} {'+-':>8} {'eta_o^2/eta_i^2':>15} {'z':>7}")
checks = [
    ("reflection 14.06 -> 53.44 (eta 1.5)", "diel_e1.5_t14_p0.json", "reflected", 53.4375,
     "diel_e1.5_t53_p180.json", "reflected", 14.0625, 1.0),
    ("transmission 53.44 above -> 30.94 below (1.5)", "diel_e1.5_t53_p0_s1.json", "transmitted", 30.9375,
     "diel_flip_e0.6666666666666666_t31_p180.json", "transmitted", 53.4375, 1.5 ** 2),
    ("transmission 30.94 above -> 53.44 below (1/1.5)", "diel_e0.6666666666666666_t31_p0_s1.json", "transmitted", 53.4375,
     "diel_flip_e1.5_t53_p180.json", "transmitted", 30.9375, (1 / 1.5) ** 2),
]
for label, fa, sa, ta, fb, sb, tb, ratio in checks:
    if not (os.path.exists(os.path.join(out, fa)) and os.path.exists(os.path.join(out, fb))):
        continue
    ra, rb = bin_row(load(fa), sa, ta), bin_row(load(fb), sb, tb)
    x, sx = ra["f_total"], ra["f_total_stderr"]
    y, sy = rb["f_total"], rb["f_total_stderr"]
    # f(o<-i) = ratio * f(i<-o)
    zz = (x - ratio * y) / math.hypot(sx, ratio * sy)
    print(f"{label:>44} {x:10.4f} {sx:8.4f} {y:10.4f} {sy:8.4f} {ratio:15.4f} {fmt_z(zz):>7}")
