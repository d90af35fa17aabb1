#!/usr/bin/python3
"""Energy-compensation models against explicit surfaces: albedo per order and the shape of the orders >= 2 lobe.

For each NDF (Beckmann, GGX), roughness alpha and incidence theta_i, K tiles (seeds) of the converged surfaces
are measured with `microsim measure bsdf` (mirror, and a conductor); the records give the explicit albedo per
order and the Smith random walk's [Heitz16] (smith_multiple), the EXR the orders >= 2 hemisphere maps
(order_2 + order_3 + order_4plus). Beside them the models of microsim.models: single scattering (E_ss),
Kulla-Conty [KullaConty17], Turquin [Turquin19], the Smith walk's orders >= 2 map, and the V-cavity
multiple-scattering model (every V-groove's interreflections in closed form [Xie18], grooves drawn with
(n.m) D(m) [Heitz14, Sec. 6]; its albedo and map from vcavity_multiple_map).

  energy_compensation.py --microsim build/microsim --out DIR [--small] [--seeds 6] [--rays 300000] ...

Writes DIR/energy_compensation.md (tables), DIR/energy_compensation.json (numbers) and the figures
DIR/ec_albedo_<ndf>.png, DIR/ec_lobes_<ndf>.png (largest alpha), DIR/ec_error_vs_alpha.png, and the maps
DIR/energy_compensation_maps.npz (for --report-only). Runs are skipped when their
record exists. --small: one alpha, four 512^2 tiles, two incidences, then checks that the pipeline tells a wrong lobe apart
(exit 1 otherwise): the CTest energy_compensation_small.
"""
import argparse
import json
import math
import os
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SLOTS_MS = ["order_2", "order_3", "order_4plus"]
CONDUCTOR = (0.47, 2.4)  # gold-like index at about 600 nm (the guide's example); F0 = 0.76


def parse():
    p = argparse.ArgumentParser()
    p.add_argument("--microsim", default=os.path.join(ROOT, "build", "microsim"))
    p.add_argument("--out", default=os.path.join(ROOT, "build", "energy_compensation"))
    p.add_argument("--ndfs", default="beckmann,ggx")
    p.add_argument("--alphas", default="0.1,0.3,0.5,0.7,1.0")
    p.add_argument("--thetas", default="0,60,80")
    p.add_argument("--seeds", type=int, default=6)
    p.add_argument("--rays", type=int, default=300000)
    p.add_argument("--resolution", type=int, default=16, help="hemisphere map R")
    p.add_argument("--tile", type=int, default=1024, help="tile resolution (16 cells per correlation length)")
    p.add_argument("--materials", default="mirror,conductor")
    p.add_argument("--walks", type=int, default=2000000, help="Smith walks per model map")
    p.add_argument("--small", action="store_true")
    p.add_argument("--no-figures", action="store_true")
    p.add_argument("--figures", action="store_true", help="with --small: draw the figures too")
    p.add_argument("--report-only", action="store_true", help="tables and figures from the saved results")
    a = p.parse_args()
    if a.small:
        a.ndfs, a.alphas, a.thetas, a.seeds, a.rays, a.tile = "beckmann", "1.0", "0,60", 4, 100000, 512
        a.resolution = 8
        a.materials, a.walks, a.no_figures = "mirror", 200000, not a.figures
    return a


# ------------------------------------------------------------------------------------------------ runs

def surface_path(a, ndf, alpha, seed):
    return os.path.join(a.out, f"tile_{ndf}_a{alpha}_s{seed}.exr")


def run(a, *args):
    subprocess.run([a.microsim, "-q", *args], check=True)


def make_surface(a, ndf, alpha, seed):
    f = surface_path(a, ndf, alpha, seed)
    if os.path.exists(f):
        return f
    # 16 cells per correlation length (the converged grid); a smaller tile keeps that grid
    size = repr(a.tile / 1024)
    if ndf == "beckmann":
        run(a, "generate", "gaussian", "--config", os.path.join(ROOT, "surfaces", "beckmann-1.0-converged.toml"),
            "--alpha", str(alpha), "--seed", str(seed), "--resolution", str(a.tile), "--size", size, "-o", f)
    else:
        run(a, "generate", "gaussian-ggx", "--config", os.path.join(ROOT, "surfaces", "gaussian-ggx.toml"),
            "--alpha", str(alpha), "--seed", str(seed), "--resolution", str(a.tile), "--size", size, "-o", f)
    return f


def measure(a, ndf, alpha, seed, material):
    out = os.path.join(a.out, f"bsdf_{ndf}_a{alpha}_s{seed}_{material}.exr")
    if not os.path.exists(out.replace(".exr", ".json")):
        mat = ["--material", "mirror"] if material == "mirror" else \
            ["--material", "conductor", "--eta", str(CONDUCTOR[0]), "--k", str(CONDUCTOR[1])]
        run(a, "measure", "bsdf", make_surface(a, ndf, alpha, seed), *mat, "--theta-i", a.thetas,
            "--rays", str(a.rays), "--resolution", str(a.resolution), "--seed", str(seed), "-o", out)
    return out


def read_maps(exr, n_inc):
    """Per incidence: the orders >= 2 map (sum of the slots) and the order-1 map, in EXR row order."""
    import OpenImageIO as oiio
    inp = oiio.ImageInput.open(exr)
    spec = inp.spec()
    names = list(spec.channelnames)
    px = inp.read_image(format="float")
    inp.close()
    px = np.asarray(px, dtype=np.float64)
    maps = []
    for k in range(n_inc):
        pre = f"incidence_{k}.reflected.f_" if n_inc > 1 else "reflected.f_"
        ms = sum(px[:, :, names.index(pre + s)] for s in SLOTS_MS)
        maps.append({"ms": ms, "order_1": px[:, :, names.index(pre + "order_1")]})
    return maps


# ------------------------------------------------------------------------------------------------ models

def models_of(ndf_name, alpha, material):
    import microsim
    M = microsim.models
    ndf = M.NDF(ndf_name, alpha)
    mat = M.Material.mirror() if material == "mirror" else M.Material.conductor(*CONDUCTOR)
    return M, ndf, mat, M.EssTable(ndf)


def direction(theta_deg):
    t = math.radians(theta_deg)
    return [math.sin(t), 0.0, math.cos(t)]


# ------------------------------------------------------------------------------------------------ statistics

def mean_se(xs):
    xs = np.asarray(xs, dtype=float)
    if len(xs) < 2:
        return float(xs.mean()), float("nan")
    return float(xs.mean()), float(xs.std(ddof=1) / math.sqrt(len(xs)))


def hellinger(M, f, g):
    """M.hellinger_distance, NaN when a map holds no power (no path of orders >= 2 left through it)."""
    if not (np.sum(np.maximum(f, 0)) > 0 and np.sum(np.maximum(g, 0)) > 0):
        return float("nan")
    return M.hellinger_distance(f, g)


def jackknife_distance(M, maps, model):
    """Hellinger distance of the model to the mean explicit map, with the leave-one-tile-out jackknife error."""
    K = len(maps)
    d = hellinger(M, np.mean(maps, axis=0), model)
    if K < 2:
        return d, float("nan")
    loo = [hellinger(M, np.mean([m for j, m in enumerate(maps) if j != k], axis=0), model) for k in range(K)]
    se = math.sqrt((K - 1) / K * sum((x - np.mean(loo)) ** 2 for x in loo))
    return d, se


def noise_floor(M, maps):
    """Distance of the explicit lobe to itself: the mean map of the even-numbered tiles against the odd ones'
    (each half holds K/2 tiles, so the floor is that of K/2 tiles: about sqrt(2) times the full mean's)."""
    if len(maps) < 2:
        return float("nan")
    return hellinger(M, np.mean(maps[0::2], axis=0), np.mean(maps[1::2], axis=0))


# ------------------------------------------------------------------------------------------------ study

def study(a):
    import microsim
    thetas = [float(t) for t in a.thetas.split(",")]
    rows, lobes = [], {}
    for material in a.materials.split(","):
        for ndf_name in a.ndfs.split(","):
            for alpha in [float(x) for x in a.alphas.split(",")]:
                recs, mapsets = [], []
                for s in range(1, a.seeds + 1):
                    out = measure(a, ndf_name, alpha, s, material)
                    with open(out.replace(".exr", ".json")) as f:
                        recs.append(json.load(f))
                    mapsets.append(read_maps(out, len(thetas)))
                M, ndf, mat, table = models_of(ndf_name, alpha, material)
                R = a.resolution
                f_avg = M.fresnel_average(mat)
                F_ms = M.kulla_conty_fresnel_factor(f_avg, table.E_avg)
                F0 = float(mat.reflectance(1.0, True))
                for t, th in enumerate(thetas):
                    inc = [r["incidences"][t] for r in recs]
                    assert all(abs(x["theta_i_deg"] - th) < 1e-9 for x in inc)
                    alb = lambda slot: mean_se([x["albedo"]["reflected"][slot] for x in inc])
                    e1, e1_se = alb("order_1")
                    ems, ems_se = mean_se([sum(x["albedo"]["reflected"][s] for s in SLOTS_MS) for x in inc])
                    etot, etot_se = alb("total")
                    mu = math.cos(math.radians(th))
                    wi = direction(th)
                    E = float(table.E(mu))
                    e_ss_f = float(inc[0]["albedo_models"]["smith_single"]["reflected"])  # E_ss with Fresnel
                    vc = float(inc[0]["albedo_models"]["vcavity_single"]["reflected"])
                    walk = [x["albedo_models"]["smith_multiple"]["reflected"] for x in inc]
                    walk_ms, walk_ms_se = mean_se([sum(w[s] for s in SLOTS_MS) for w in walk])
                    walk_tot, _ = mean_se([w["total"] for w in walk])
                    kc_ms = F_ms * (1.0 - E)
                    tq_ms = F0 * (1.0 - E) / E * e_ss_f
                    vcm_map, vcm_ms, vcm_tot = M.vcavity_multiple_map(ndf, mat, wi, R, 2)
                    ms_models = {"smith_single": 0.0, "vcavity_single": 0.0, "heitz16_walk": walk_ms,
                                 "kulla_conty": kc_ms, "turquin": tq_ms, "vcavity_multiple": vcm_ms}
                    total_models = {"smith_single": e_ss_f, "vcavity_single": vc, "heitz16_walk": walk_tot,
                                    "kulla_conty": e_ss_f + kc_ms, "turquin": e_ss_f + tq_ms,
                                    "vcavity_multiple": vcm_tot}
                    # lobes of orders >= 2
                    ms_maps = [ms[t]["ms"] for ms in mapsets]
                    model_maps = {
                        "kulla_conty": M.compensation_map(table, mat, "kulla_conty", wi, R, 8),
                        "turquin": M.compensation_map(table, mat, "turquin", wi, R, 8),
                        "heitz16_walk": M.smith_walk_map(ndf, mat, wi, R, 2, a.walks, 1)[0],
                        "vcavity_multiple": vcm_map,
                    }
                    dist = {k: jackknife_distance(M, ms_maps, v) for k, v in model_maps.items()}
                    floor = noise_floor(M, ms_maps)
                    rows.append(dict(material=material, ndf=ndf_name, alpha=alpha, theta=th, tiles=len(inc),
                                     explicit=dict(order_1=[e1, e1_se], ms=[ems, ems_se], total=[etot, etot_se]),
                                     E_ss=E, E_avg=table.E_avg, F_avg=f_avg, F_ms=F_ms, F0=F0,
                                     ms_models=ms_models, total_models=total_models, walk_ms_se=walk_ms_se,
                                     lobe_distance={k: list(v) for k, v in dist.items()}, noise_floor=floor))
                    lobes[(material, ndf_name, alpha, th)] = (np.mean(ms_maps, axis=0), model_maps,
                                                              np.mean([ms[t]["order_1"] for ms in mapsets], axis=0))
    return rows, lobes


# ------------------------------------------------------------------------------------------------ output

MODELS = ["heitz16_walk", "kulla_conty", "turquin", "vcavity_multiple"]
NAMES = {"smith_single": "Smith single", "vcavity_single": "V-cavity single", "heitz16_walk": "Heitz16 walk",
         "kulla_conty": "Kulla-Conty", "turquin": "Turquin", "vcavity_multiple": "V-cavity multiple"}
STYLES = {"heitz16_walk": ("s-", "C0"), "kulla_conty": ("^--", "C1"), "turquin": ("v:", "C2"),
          "vcavity_multiple": ("D-.", "C3")}


def table_albedo_md(rows, material):
    """Albedos: explicit (mean of tiles +- standard error between tiles) and each model's minus explicit."""
    head = (["NDF", "α", "θi", "E₁ explicit", "E≥2 explicit", "E total explicit", "ΔE₁ Smith", "ΔE₁ V-cavity"]
            + [f"ΔE≥2 {NAMES[m]}" for m in MODELS] + [f"ΔE total {NAMES[m]}" for m in ["smith_single"] + MODELS])
    out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        if r["material"] != material:
            continue
        e = r["explicit"]
        cells = [r["ndf"], f"{r['alpha']:g}", f"{r['theta']:g}"]
        cells += [f"{e[k][0]:.4f} ± {e[k][1]:.4f}" for k in ("order_1", "ms", "total")]
        cells += [f"{r['total_models'][m] - e['order_1'][0]:+.4f}" for m in ("smith_single", "vcavity_single")]
        cells += [f"{r['ms_models'][m] - e['ms'][0]:+.4f}" for m in MODELS]
        cells += [f"{r['total_models'][m] - e['total'][0]:+.4f}" for m in ["smith_single"] + MODELS]
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out)


def table_lobe_md(rows, material):
    """Hellinger distances of the orders >= 2 lobes to the explicit mean lobe (jackknife errors), noise floor."""
    head = ["NDF", "α", "θi", "E≥2 explicit"] + [f"H {NAMES[m]}" for m in MODELS] + ["H noise floor"]
    out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        if r["material"] != material:
            continue
        cells = [r["ndf"], f"{r['alpha']:g}", f"{r['theta']:g}", f"{r['explicit']['ms'][0]:.4f}"]
        for m in MODELS:
            d, se = r["lobe_distance"][m]
            cells.append("–" if d != d else f"{d:.3f} ± {se:.3f}")
        cells.append("–" if r["noise_floor"] != r["noise_floor"] else f"{r['noise_floor']:.3f}")
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out)


def figures(a, rows, lobes):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    thetas = sorted({r["theta"] for r in rows})
    alphas = sorted({r["alpha"] for r in rows})
    mats = sorted({r["material"] for r in rows}, key=lambda m: m != "mirror")
    for ndf in sorted({r["ndf"] for r in rows}):
        fig, axes = plt.subplots(len(mats), len(alphas), figsize=(3 * len(alphas), 3 * len(mats)), squeeze=False)
        for mi, mat in enumerate(mats):
            for ai, al in enumerate(alphas):
                ax = axes[mi][ai]
                rs = [r for r in rows if r["ndf"] == ndf and r["alpha"] == al and r["material"] == mat]
                th = [r["theta"] for r in rs]
                ax.errorbar(th, [r["explicit"]["ms"][0] for r in rs], yerr=[r["explicit"]["ms"][1] for r in rs],
                            fmt="ko", label="explicit", capsize=3)
                for m in MODELS:
                    ax.plot(th, [r["ms_models"][m] for r in rs], STYLES[m][0], color=STYLES[m][1], label=NAMES[m],
                            alpha=0.8)
                ax.set_title(f"{mat}, α={al:g}", fontsize=9)
                ax.set_xlabel("θi (deg)")
                if ai == 0:
                    ax.set_ylabel("albedo of orders ≥ 2")
                if mi == 0 and ai == 0:
                    ax.legend(fontsize=7)
        fig.suptitle(f"{ndf}: albedo of orders ≥ 2 (explicit: mean of tiles ± s.e.)")
        fig.tight_layout()
        fig.savefig(os.path.join(a.out, f"ec_albedo_{ndf}.png"), dpi=90)
        plt.close(fig)
    # lobe maps at the roughest alpha, mirror
    for ndf in sorted({r["ndf"] for r in rows}):
        al = max(alphas)
        fig, axes = plt.subplots(len(thetas), 1 + len(MODELS), figsize=(12.5, 2.6 * len(thetas)), squeeze=False)
        for ti, th in enumerate(thetas):
            key = (mats[0], ndf, al, th)
            if key not in lobes:
                continue
            expl, mm, _ = lobes[key]
            imgs = [expl] + [mm[m] for m in MODELS]
            # The scale of the explicit and the Smith-based maps: the V-cavity model's lobe is far more
            # peaked and saturates there (its peak over the scale in its title).
            vmax = max(float(np.max(x)) for x, m in zip(imgs, ["explicit"] + MODELS) if m != "vcavity_multiple")
            for ci, (img, m) in enumerate(zip(imgs, ["explicit"] + MODELS)):
                ax = axes[ti][ci]
                ax.imshow(img, cmap="magma", vmin=0, vmax=vmax)
                ax.set_xticks([])
                ax.set_yticks([])
                name = NAMES.get(m, m)
                peak = float(np.max(img)) / vmax if vmax > 0 else 0.0
                extra = f" (peak ×{peak:.0f})" if peak > 1.5 else ""
                ax.set_title(f"{name}, θi={th:g}°{extra}", fontsize=8)
        fig.suptitle(f"{ndf}, α={al:g}, {mats[0]}: f of orders ≥ 2 (equal-area hemisphere map, common scale per row; "
                     "the V-cavity model saturates)", fontsize=9)
        fig.tight_layout()
        fig.savefig(os.path.join(a.out, f"ec_lobes_{ndf}.png"), dpi=90)
        plt.close(fig)
    # model error vs alpha
    fig, axes = plt.subplots(2, len(thetas), figsize=(3.5 * len(thetas), 6), squeeze=False)
    for ti, th in enumerate(thetas):
        for ndf, mk in zip(sorted({r["ndf"] for r in rows}), ["o", "s"]):
            # albedo errors of the material with Fresnel (with a mirror the three Smith-based models agree:
            # 1 - E_ss)
            rs = [r for r in rows if r["ndf"] == ndf and r["theta"] == th and r["material"] == mats[-1]]
            x = [r["alpha"] for r in rs]
            for m in MODELS:
                c = STYLES[m][1]
                axes[0][ti].errorbar(x, [r["ms_models"][m] - r["explicit"]["ms"][0] for r in rs],
                                     yerr=[r["explicit"]["ms"][1] for r in rs], fmt=mk + "-", color=c, capsize=2,
                                     label=f"{NAMES[m]} ({ndf})", alpha=0.8)
            # lobe shapes of the mirror
            rs = [r for r in rows if r["ndf"] == ndf and r["theta"] == th and r["material"] == mats[0]]
            x = [r["alpha"] for r in rs]
            for m in MODELS:
                c = STYLES[m][1]
                axes[1][ti].errorbar(x, [r["lobe_distance"][m][0] for r in rs],
                                     yerr=[r["lobe_distance"][m][1] for r in rs], fmt=mk + "-", color=c, capsize=2,
                                     alpha=0.8)
            axes[1][ti].plot(x, [r["noise_floor"] for r in rs], mk + ":", color="gray", label=f"noise floor ({ndf})")
        axes[0][ti].axhline(0, color="k", lw=0.5)
        axes[0][ti].set_title(f"θi={th:g}°: albedo, {mats[-1]}", fontsize=9)
        axes[1][ti].set_title(f"θi={th:g}°: lobe shape, {mats[0]}", fontsize=9)
        axes[0][ti].set_ylabel("model − explicit, albedo of orders ≥ 2")
        axes[1][ti].set_ylabel("Hellinger distance of the ≥ 2 lobe")
        axes[1][ti].set_xlabel("α")
    axes[0][0].legend(fontsize=6)
    axes[1][0].legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "ec_error_vs_alpha.png"), dpi=90)
    plt.close(fig)


def vcavity_checks(M, r, vcm_map):
    """The V-cavity multiple-scattering model in the study: with a mirror its total albedo is 1 (every ray leaves
    its groove), its order 1 is the record's V-cavity single scattering (the same grooves' single bounces,
    [Heitz14, eq. 24], computed by another route), its map holds its albedo of orders >= 2, and its lobe distance
    is measured. A wrong model (the map scaled, an order moved, the light lost) fails one of them."""
    ok = True
    tot, ms = r["total_models"]["vcavity_multiple"], r["ms_models"]["vcavity_multiple"]
    single = r["total_models"]["vcavity_single"]
    power = float(np.sum(vcm_map * M.hemisphere_cos_integrals(vcm_map.shape[0])))
    print(f"theta {r['theta']:g}: V-cavity multiple total {tot:.6f}, order 1 {tot - ms:.5f} against V-cavity single "
          f"{single:.5f}, map power {power:.5f} against E>=2 {ms:.5f}, H {r['lobe_distance']['vcavity_multiple'][0]:.3f}")
    if abs(tot - 1.0) > 1e-9:
        print("FAIL: V-cavity multiple-scattering mirror albedo is not 1"); ok = False
    if abs((tot - ms) - single) > 1e-4:
        print("FAIL: V-cavity multiple-scattering order 1 differs from the V-cavity single scattering"); ok = False
    if abs(power - ms) > 1e-9 * max(1.0, ms):
        print("FAIL: V-cavity multiple-scattering map does not hold its albedo"); ok = False
    if ms > 0 and not (r["lobe_distance"]["vcavity_multiple"][0] >= 0):
        print("FAIL: no V-cavity multiple-scattering lobe distance"); ok = False
    return ok


def small_checks(rows, lobes):
    """The pipeline must tell a wrong lobe apart: the explicit order-1 lobe taken for the orders >= 2 lobe is
    further from it than the noise floor and than the Smith walk's lobe; the explicit and compensated mirror
    albedos are 1; the V-cavity multiple-scattering model passes vcavity_checks."""
    import microsim
    M = microsim.models
    ok = True
    for r in rows:
        expl, mm, order_1 = lobes[(r["material"], r["ndf"], r["alpha"], r["theta"])]
        ok &= vcavity_checks(M, r, mm["vcavity_multiple"])
        d_wrong = M.hellinger_distance(expl, order_1)
        d_walk = r["lobe_distance"]["heitz16_walk"][0]
        print(f"theta {r['theta']:g}: wrong-lobe distance {d_wrong:.3f}, walk {d_walk:.3f}, floor {r['noise_floor']:.3f}")
        if not (d_wrong > 2 * max(d_walk, r["noise_floor"])):
            print("FAIL: a wrong lobe is not told apart"); ok = False
        if abs(r["explicit"]["total"][0] - 1.0) > 1e-6:
            print("FAIL: mirror albedo is not 1"); ok = False
        if abs(r["total_models"]["kulla_conty"] - 1.0) > 1e-3 or abs(r["total_models"]["turquin"] - 1.0) > 1e-3:
            print("FAIL: compensated mirror albedo is not 1"); ok = False
    return ok


def main():
    a = parse()
    os.makedirs(a.out, exist_ok=True)
    saved = os.path.join(a.out, "energy_compensation_maps.npz")
    if a.report_only:
        with open(os.path.join(a.out, "energy_compensation.json")) as f:
            rows = json.load(f)
        z = np.load(saved)
        lobes = {}
        for r in rows:
            key = (r["material"], r["ndf"], r["alpha"], r["theta"])
            tag = "_".join(str(x) for x in key)
            lobes[key] = (z[tag + "_explicit"], {m: z[tag + "_" + m] for m in MODELS}, z[tag + "_order_1"])
    else:
        rows, lobes = study(a)
        with open(os.path.join(a.out, "energy_compensation.json"), "w") as f:
            json.dump(rows, f, indent=1)
        arrays = {}
        for key, (expl, mm, o1) in lobes.items():
            tag = "_".join(str(x) for x in key)
            arrays[tag + "_explicit"], arrays[tag + "_order_1"] = expl, o1
            for m, v in mm.items():
                arrays[tag + "_" + m] = v
        np.savez_compressed(saved, **arrays)
    md = [f"Tiles: {a.seeds} seeds of {a.tile}² (16 cells per correlation length), {a.rays} rays per incidence, "
          f"maps {a.resolution}², Smith walk maps {a.walks} walks.", ""]
    for mat in a.materials.split(","):
        md += [f"### {mat}: albedos", "", table_albedo_md(rows, mat), "",
               f"### {mat}: shape of the orders ≥ 2 lobe", "", table_lobe_md(rows, mat), ""]
    with open(os.path.join(a.out, "energy_compensation.md"), "w") as f:
        f.write("\n".join(md))
    print("\n".join(md))
    if not a.no_figures:
        figures(a, rows, lobes)
    if a.small:
        sys.exit(0 if small_checks(rows, lobes) else 1)


if __name__ == "__main__":
    main()
