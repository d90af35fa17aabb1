"""Figures of the report. Each function `f(path, *data)` reads microsim records (already
loaded) and writes one PNG at `path`; it raises NoData("reason") when the records lack what it
needs (the report then lists the figure as not drawn, with the reason). Any other exception is
a bug and fails the report.
"""
import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from . import models  # noqa: E402
from .readers import column, num, has_field  # noqa: E402

DPI = 100


class NoData(Exception):
    """The records do not hold what a figure needs."""

VERDICT_COLORS = {
    "pass": "#2a9d4b",
    "FAIL": "#d62728",
    "agrees": "#1f77b4",
    "deviates (finding)": "#ff7f0e",
    "measured": "#7f7f7f",
}


def _save(fig, path):
    fig.tight_layout()
    fig.savefig(path, dpi=DPI, bbox_inches="tight")
    plt.close(fig)
    return path


def _nominal(description):
    """(kind, alpha_x, alpha_y) of a surface description, or None."""
    if not isinstance(description, dict) or "nominal_ndf" not in description:
        return None
    ax, ay = num(description.get("alpha_x")), num(description.get("alpha_y"))
    if not (ax > 0 and ay > 0):
        return None
    return description["nominal_ndf"], ax, ay


# ----------------------------------------------------------------------------------------------
# Validation overview


def validation_z(path, validation):
    """z of every z-tested row in units of its own threshold (Sidak; Student t with K - 1 dof for
    rows whose error is the spread of K surfaces), one line per (quantity vs model), colored by
    verdict."""
    rows = [r for r in validation.get("rows", []) if num(r.get("z")) == num(r.get("z"))]
    if not rows:
        raise NoData("no z-tested rows in the validation record")
    zt = num(validation.get("z_threshold"), 3.0)

    def scaled(r):  # z / the row's threshold (records without per-row thresholds: the run's)
        return num(r.get("z")) / num(r.get("z_threshold"), zt)
    cats = []
    for r in rows:
        c = "%s vs %s [%s]" % (r.get("quantity"), r.get("model_name"), r.get("kind"))
        if c not in cats:
            cats.append(c)
    fig, ax = plt.subplots(figsize=(9, 0.45 * len(cats) + 1.6))
    rng = np.random.default_rng(0)
    for verdict, color in VERDICT_COLORS.items():
        sel = [r for r in rows if r.get("verdict") == verdict]
        if not sel:
            continue
        y = np.array([cats.index("%s vs %s [%s]" % (r.get("quantity"), r.get("model_name"), r.get("kind")))
                      for r in sel]) + rng.uniform(-0.25, 0.25, len(sel))
        ax.scatter([scaled(r) for r in sel], y, s=9, color=color, alpha=0.7,
                   label="%s (%d)" % (verdict, len(sel)))
    for s in (-1, 1):
        ax.axvline(s, color="k", ls="--", lw=0.8)
    ax.set_xscale("symlog", linthresh=1.0)
    ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda x, _: "%g" % x))  # not -10^0
    ax.set_yticks(range(len(cats)))
    ax.set_yticklabels(cats, fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel("z / threshold, z = (measured - model) / stderr")
    ax.legend(fontsize=8, loc="lower right")
    ax.set_title("Validation: z-scores by check (identities must pass; models may deviate)\n"
                 "dashed: the threshold, |z| = %.2f (Sidak over %d tests), Student t with K - 1 dof "
                 "for ensemble rows" % (zt, int(num(validation.get("comparisons"), 0))), fontsize=10)
    ax.grid(True, axis="x", alpha=0.3)
    return _save(fig, path)


# ----------------------------------------------------------------------------------------------
# NDF


def ndf_map(path, channels, attrs, title=""):
    """Upper hemisphere of D (measured, nominal, ratio) from a `measure ndf` EXR."""
    if "D" not in channels:
        raise NoData("the EXR has no D channel")
    d = channels["D"]
    n_theta, n_phi = d.shape
    upper = n_theta // 2  # rows cover theta in [0, 180]; keep [0, 90]
    theta_edges = np.linspace(0, 90, upper + 1)
    phi_edges = np.linspace(0, 2 * np.pi, n_phi + 1)
    panels = [("D measured", d[:upper])]
    if "D_nominal" in channels:
        nom = channels["D_nominal"][:upper]
        panels.append(("D nominal", nom))
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(nom > 1e-3 * nom.max(), d[:upper] / nom, np.nan)
        panels.append(("measured / nominal", ratio))
    fig, axes = plt.subplots(1, len(panels), subplot_kw={"projection": "polar"},
                             figsize=(4.2 * len(panels), 4.2))
    axes = np.atleast_1d(axes)
    pos = d[:upper][d[:upper] > 0]
    vmin = max(pos.min(), pos.max() * 1e-4) if pos.size else 1e-3
    vmax = pos.max() if pos.size else 1.0
    for ax, (name, data) in zip(axes, panels):
        if name.startswith("measured /"):
            m = ax.pcolormesh(phi_edges, theta_edges, data, cmap="RdBu_r", vmin=0.5, vmax=1.5, shading="flat")
        else:
            m = ax.pcolormesh(phi_edges, theta_edges, np.maximum(data, vmin * 1e-3), cmap="viridis",
                              norm=matplotlib.colors.LogNorm(vmin=vmin, vmax=vmax), shading="flat")
        fig.colorbar(m, ax=ax, shrink=0.7, pad=0.1)
        ax.set_title(name, fontsize=10)
        ax.set_yticks([30, 60, 90])
        ax.set_yticklabels(["30", "60", "90"], fontsize=7)
        ax.tick_params(axis="x", labelsize=7)
    fig.suptitle(title + "  (radius: theta_m in degrees, angle: phi_m; D per steradian)", fontsize=10)
    return _save(fig, path)


def ndf_rings(path, entries):
    """D(theta_m) per ring with error bars against the nominal NDF, one column per entry."""
    usable = [(e["name"], e["measurements"]["d_nominal"]) for e in entries
              if isinstance(e.get("measurements", {}).get("d_nominal"), dict)]
    if not usable:
        raise NoData("no entry with a nominal NDF")
    fig, axes = plt.subplots(2, len(usable), figsize=(4.6 * len(usable), 6), squeeze=False,
                             gridspec_kw={"height_ratios": [2, 1]}, sharex="col")
    for c, (name, m) in enumerate(usable):
        lo, hi = np.array(m["theta_lo_deg"]), np.array(m["theta_hi_deg"])
        mid = 0.5 * (lo + hi)
        d, se, nom = np.array(m["d"], float), np.array(m["d_stderr"], float), np.array(m["d_nominal"], float)
        keep = (mid < 90) & ((d > 0) | (nom > 1e-6 * nom.max()))
        ax = axes[0, c]
        ax.errorbar(mid[keep], d[keep], yerr=se[keep], fmt="o", ms=3, capsize=2,
                    label="measured (stderr: %s)" % m.get("error", "?"))
        ax.step(np.append(lo[keep], hi[keep][-1:]), np.append(nom[keep], nom[keep][-1:]), where="post",
                color="k", lw=1, label="%s alpha=(%g, %g), bin-averaged" % (m.get("nominal"), m.get("alpha_x"), m.get("alpha_y")))
        ax.set_yscale("log")
        ax.set_title(name, fontsize=10)
        ax.set_ylabel("D (phi-averaged ring)")
        ax.legend(fontsize=7)
        ax.grid(True, alpha=0.3)
        ax2 = axes[1, c]
        ok = keep & (nom > 0)
        rel = (d[ok] - nom[ok]) / nom[ok]
        ax2.errorbar(mid[ok], rel, yerr=se[ok] / nom[ok], fmt="o", ms=3, capsize=2)
        ax2.axhline(0, color="k", lw=0.8)
        ax2.set_ylim(-0.5, 0.5)
        ax2.set_xlabel("theta_m (deg)")
        ax2.set_ylabel("(D - nominal) / nominal")
        ax2.grid(True, alpha=0.3)
    fig.suptitle("Normal distribution D of the generated surfaces against the nominal NDF", fontsize=11)
    return _save(fig, path)


# ----------------------------------------------------------------------------------------------
# G1


def g1_curves(path, record, title=""):
    """Averaged G1 vs theta from `measure g1` (one surface or an ensemble) against Smith."""
    rows = record.get("rows", [])
    if not rows or not has_field(rows, "g1"):
        raise NoData("no G1 rows")
    nominal = _nominal(record.get("surface"))
    phis = sorted(set(column(rows, "phi_deg")))
    fig, axes = plt.subplots(2, 1, figsize=(7.5, 6.5), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    ax, ax2 = axes
    ensemble = isinstance(record.get("per_surface"), list)
    err_kind = "between %d surfaces" % len(record["per_surface"]) if ensemble else "ray count, one surface"
    for k, phi in enumerate(phis):
        sel = [r for r in rows if num(r.get("phi_deg")) == phi]
        sel.sort(key=lambda r: num(r.get("theta_deg")))
        th = column(sel, "theta_deg")
        g, gse = column(sel, "g1"), column(sel, "g1_stderr")
        gr, grse = column(sel, "g1_raycast"), column(sel, "g1_raycast_stderr")
        sn = column(sel, "smith_numeric")
        suffix = "" if len(phis) == 1 else ", phi=%g" % phi
        color = "C%d" % k
        ax.errorbar(th, g, yerr=gse, fmt="o", ms=4, capsize=2, color=color,
                    label="G1 area sampling (stderr %s)%s" % (err_kind, suffix))
        if has_field(sel, "g1_raycast"):
            ax.errorbar(th + 0.6, gr, yerr=grse, fmt="s", ms=3, mfc="none", capsize=2, color=color,
                        label="G1 ray casting%s" % suffix)
        ax.plot(th, sn, "x", color="k", ms=6, label="Smith with the surface's facets (smith_numeric)" if k == 0 else None)
        if nominal:
            kind, axx, ayy = nominal
            t = np.linspace(0, min(89.5, th.max() + 2), 300)
            ax.plot(t, models.smith_g1(kind, axx, ayy, np.radians(t), math.radians(phi)), "-", color=color, lw=1,
                    label="Smith %s nominal alpha=(%g, %g)%s" % (kind, axx, ayy, suffix))
            sm = models.smith_g1(kind, axx, ayy, np.radians(th), math.radians(phi))
            ax2.errorbar(th, (g - sm) / sm, yerr=gse / sm, fmt="o", ms=4, capsize=2, color=color,
                         label="vs Smith nominal%s" % suffix)
        ax2.errorbar(th + 0.6, (g - sn) / sn, yerr=gse / sn, fmt="x", ms=5, capsize=2, color="k" if k == 0 else color,
                     label="vs smith_numeric%s" % suffix)
    ax.set_ylabel("G1(v), projected-area average")
    ax.legend(fontsize=7, loc="lower left")
    ax.grid(True, alpha=0.3)
    ax.set_title((title + ": " if title else "") + "masking G1 against Smith (V-cavity's average is the same curve)",
                 fontsize=10)
    ax2.axhline(0, color="k", lw=0.8)
    ax2.set_xlabel("view zenith theta (deg)")
    ax2.set_ylabel("relative deviation")
    ax2.legend(fontsize=7)
    ax2.grid(True, alpha=0.3)
    return _save(fig, path)


def _pooled_bins(per_surface, theta, phi, min_count=100):
    """Per normal bin, the mean over surfaces of g1 and the models at (theta, phi); error: ray
    count, combined over surfaces (sqrt(sum se^2) / K). Bins with fewer than min_count area
    samples or ray hits on some surface are left out (as in the validation's z tests)."""
    acc = {}
    for s in per_surface:
        for row in s.get("rows", []):
            if num(row.get("theta_deg")) != theta or num(row.get("phi_deg")) != phi:
                continue
            for b in row.get("bins", []):
                if "g1_raycast" not in b:
                    continue  # back-facing bin
                if num(b.get("samples"), min_count) < min_count or num(b.get("raycast_hits"), min_count) < min_count:
                    continue
                key = (tuple(b["theta_m_range_deg"]), tuple(b["phi_m_range_deg"]))
                a = acc.setdefault(key, {"g1": [], "se": [], "smith": [], "vc": [], "ray": [], "rayse": []})
                a["g1"].append(num(b.get("g1")))
                a["se"].append(num(b.get("g1_stderr")))
                a["ray"].append(num(b.get("g1_raycast")))
                a["rayse"].append(num(b.get("g1_raycast_stderr")))
                a["smith"].append(num(b.get("smith_numeric")))
                a["vc"].append(num(b.get("vcavity")))
    out = {}
    surfaces = len(per_surface)
    for key, a in acc.items():
        k = len(a["g1"])
        if k < surfaces:
            continue  # too few samples on some surface
        out[key] = {
            "g1": np.mean(a["g1"]), "se": math.sqrt(np.sum(np.square(a["se"]))) / k,
            "ray": np.mean(a["ray"]), "rayse": math.sqrt(np.sum(np.square(a["rayse"]))) / k,
            "smith": np.mean(a["smith"]), "vc": np.mean(a["vc"]), "n": k,
        }
    return out


def g1_per_normal(path, entry):
    """G1(v, m) against theta_m, one curve per azimuth sector of m relative to the view (the
    test of Smith's independence of masking and normals), with Smith and V-cavity beside it."""
    per_surface = entry.get("measurements", {}).get("g1")
    if not per_surface:
        raise NoData("entry %s has no G1 measurements" % entry.get("name"))
    rows = per_surface[0].get("rows", [])
    dirs = sorted({(num(r.get("theta_deg")), num(r.get("phi_deg"))) for r in rows if num(r.get("theta_deg")) > 0})
    if not dirs:
        raise NoData("no oblique view direction")
    dirs = dirs[-3:] if len(dirs) > 3 else dirs
    if len(_pooled_bins(per_surface, *dirs[0])) < 3:
        raise NoData("fewer than 3 normal bins with enough samples (e.g. a flat plane)")
    fig, axes = plt.subplots(1, len(dirs), figsize=(4.8 * len(dirs), 4.2), squeeze=False)
    for col, (ax, (theta, phi)) in enumerate(zip(axes[0], dirs)):
        bins = _pooled_bins(per_surface, theta, phi)
        # Sectors by |phi_m - phi_v| folded to [0, 180]: 0 = facets tilted toward the viewer.
        sectors = {}
        for (tr, pr), b in bins.items():
            dphi = abs(((0.5 * (pr[0] + pr[1]) - phi) + 180) % 360 - 180)
            sectors.setdefault(round(dphi, 1), []).append((0.5 * (tr[0] + tr[1]), b))
        smith = None
        for k, dphi in enumerate(sorted(sectors)):
            pts = sorted(sectors[dphi], key=lambda p: p[0])
            # Average the two mirror sectors (+-dphi) bin by bin.
            by_theta = {}
            for t, b in pts:
                by_theta.setdefault(t, []).append(b)
            t = np.array(sorted(by_theta))
            g = np.array([np.mean([b["g1"] for b in by_theta[x]]) for x in t])
            se = np.array([math.sqrt(sum(b["se"] ** 2 for b in by_theta[x])) / len(by_theta[x]) for x in t])
            vc = np.array([np.mean([b["vc"] for b in by_theta[x]]) for x in t])
            smith = np.mean([b["smith"] for x in t for b in by_theta[x]])
            color = "C%d" % k
            ax.errorbar(t, g, yerr=se, fmt="o-", ms=3, lw=1, capsize=2, color=color,
                        label="measured, |phi_m - phi_v| = %g" % dphi)
            ax.plot(t, vc, "--", color=color, lw=1, label="V-cavity" if k == 0 else None)
        if smith is not None:
            ax.axhline(smith, color="k", lw=1.2, label="Smith (independent of m)")
        ax.set_title("view theta = %g deg, phi = %g deg" % (theta, phi), fontsize=10)
        ax.set_xlabel("theta_m (deg, bin center)")
        ax.set_ylabel("G1(v, m)")
        ax.set_ylim(0, 1.05)
        ax.grid(True, alpha=0.3)
        if col == 0:  # one legend: at grazing views the curves reach down to where it would sit
            ax.legend(fontsize=7, loc="lower left")
    n = len(per_surface)
    fig.suptitle("%s: masking per normal bin (%d surface%s pooled, ray-count errors); dashed: V-cavity [Heitz14, eq. 24]"
                 % (entry.get("name"), n, "s" if n > 1 else ""), fontsize=10)
    return _save(fig, path)


# ----------------------------------------------------------------------------------------------
# G2 (measure g2; fields in docs/reference/records.md)

G2_MODELS = [
    ("smith_separable", "Smith separable [Heitz14, eq. 20]", "-"),
    ("smith_height_correlated", "Smith height-correlated [Heitz14, eq. 21]", "--"),
    ("smith_direction_correlated", "Smith direction-correlated [Heitz14, eq. 22]", ":"),
    ("smith_height_direction_correlated", "Smith height-direction-correlated [Heitz14, eq. 23]", "-."),
    ("vcavity", "V-cavity", (0, (1, 1))),
]


def g2_curves(path, record, title=""):
    rows = record.get("rows", [])
    if not rows or not has_field(rows, "g2"):
        raise NoData("no G2 rows")
    for key in ("theta_o_deg", "theta_i_deg"):
        if not has_field(rows, key):
            raise NoData("G2 rows lack %s" % key)

    def dphi(r):
        d = abs((num(r.get("phi_i_deg"), 0) - num(r.get("phi_o_deg"), 0) + 180) % 360 - 180)
        return round(d, 3)

    panels = sorted({(num(r.get("theta_o_deg")), dphi(r)) for r in rows})
    panels = panels[:6]
    ncol = min(3, len(panels))
    nrow = (len(panels) + ncol - 1) // ncol
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.6 * ncol, 3.8 * nrow), squeeze=False)
    for k, (ax, (to, dp)) in enumerate(zip(axes.flat, panels)):
        sel = sorted([r for r in rows if num(r.get("theta_o_deg")) == to and dphi(r) == dp],
                     key=lambda r: num(r.get("theta_i_deg")))
        ti = column(sel, "theta_i_deg")
        ax.errorbar(ti, column(sel, "g2"), yerr=column(sel, "g2_stderr"), fmt="o", ms=4, capsize=2,
                    color="k", label="measured")
        for key, label, ls in G2_MODELS:
            if has_field(sel, key):
                ax.plot(ti, column(sel, key), ls=ls, lw=1.2, label=label)
        ax.set_title("theta_o = %g deg, delta phi = %g deg" % (to, dp), fontsize=10)
        ax.set_xlabel("theta_i (deg)")
        ax.set_ylabel("G2 (symmetric weight)")
        ax.grid(True, alpha=0.3)
        if k == 0:  # one legend, where the curves leave room at every roughness
            ax.legend(fontsize=6, loc="lower left")
    for ax in list(axes.flat)[len(panels):]:
        ax.axis("off")
    fig.suptitle((title + ": " if title else "") + "masking-shadowing G2 against the four Smith forms and V-cavity\n"
                 "G2 averaged over the facets facing both o and i with the symmetric weight "
                 "A_f (max(0, o.m_f) + max(0, i.m_f)) / 2, so that G2(v, v) = G1(v)", fontsize=10)
    return _save(fig, path)


# ----------------------------------------------------------------------------------------------
# BSDF (measure bsdf; fields in docs/reference/records.md)

ORDER_KEYS = ["order_1", "order_2", "order_3", "order_4plus", "total"]


def g2_hotspot(path, entry):
    """G2(v, v) of `validate`'s g2 check (per surface) against G1 of an independent `measure g1`
    run with the same weights ([GeomBSDF24, eq. 16]: G2(v, m, v) = G1(v, m)) and Smith's direction-correlated
    form 1/(1 + Lambda) [Heitz14, eq. 22], with ray-count errors."""
    per_surface = entry.get("measurements", {}).get("g2")
    points = []
    for k, surface in enumerate(per_surface or []):
        for h in surface.get("hotspot", []):
            points.append((k, h))
    if not points:
        raise NoData("entry %s has no G2 hotspot measurements" % entry.get("name"))
    n = len(per_surface)
    fig, (ax, axd) = plt.subplots(1, 2, figsize=(10, 3.8))
    for i, (k, h) in enumerate(points):
        first = i == 0  # one legend entry per series
        t = num(h.get("theta_deg")) + 0.6 * (k - (n - 1) / 2)
        ax.errorbar([t - 0.25], [num(h.get("g2"))], yerr=[num(h.get("g2_stderr"))], fmt="o", ms=4, capsize=2,
                    color="k", label="G2(v, v), measure g2" if first else None)
        ax.errorbar([t + 0.25], [num(h.get("g1_independent"))], yerr=[num(h.get("g1_independent_stderr"))],
                    fmt="s", ms=4, capsize=2, color="tab:blue", mfc="none",
                    label="G1(v), independent measure g1" if first else None)
        ax.plot([t], [num(h.get("direction_correlated_numeric"))], "x", color="tab:orange",
                label="Smith direction-correlated, 1/(1+Lambda)" if first else None)
        se = math.hypot(num(h.get("g2_stderr"), 0.0), num(h.get("g1_independent_stderr"), 0.0))
        if se > 0:
            axd.plot([t], [(num(h.get("g2")) - num(h.get("g1_independent"))) / se], "o", color="k")
    ax.set_xlabel("theta_o = theta_i (deg)")
    ax.set_ylabel("averaged G2 / G1")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    axd.axhline(0, color="k", lw=0.8)
    for s_ in (-3, 3):
        axd.axhline(s_, color="k", ls="--", lw=0.8)
    axd.set_xlabel("theta (deg)")
    axd.set_ylabel("z = (G2 - G1) / stderr")
    axd.grid(True, alpha=0.3)
    fig.suptitle("%s: the hotspot G2(v, m, v) = G1(v, m) [GeomBSDF24, eq. 16], %d surface%s"
                 % (entry.get("name"), n, "s" if n > 1 else ""), fontsize=10)
    return _save(fig, path)


def bsdf_albedo(path, record, title=""):
    alb = record.get("albedo")
    if not isinstance(alb, dict):
        raise NoData("no albedo in the BSDF record")
    fig, ax = plt.subplots(figsize=(7, 3.8))
    # Sides with light in them (a mirror transmits nothing); log scale: orders 3 and 4+ are small.
    sides = [sd for sd in ("reflected", "transmitted")
             if isinstance(alb.get(sd), dict) and any(num(alb[sd].get(o), 0.0) > 0 for o in ORDER_KEYS)]
    if not sides:
        raise NoData("no light in any order")
    width = 0.8 / len(sides)
    x = np.arange(len(ORDER_KEYS))
    walk = (record.get("albedo_models") or {}).get("smith_multiple") or {}
    positive = []
    for k, side in enumerate(sides):
        vals = alb[side]
        errs = record.get(side + "_stderr") or alb.get(side + "_stderr") or {}
        y = np.array([num(vals.get(o)) for o in ORDER_KEYS])
        e = np.array([num(errs.get(o), 0.0) for o in ORDER_KEYS])
        xs = x + (k - (len(sides) - 1) / 2) * width
        ax.bar(xs, y, width * 0.9, yerr=e, capsize=3, color="C%d" % k, label="%s, measured" % side)
        positive += [v for v in y if v > 0]
        for xi, yi, ei in zip(xs, y, e):
            if yi > 0:
                ax.text(xi, yi * 1.15, "%.4g\n+-%.1g" % (yi, ei), ha="center", va="bottom", fontsize=6)
        if isinstance(walk.get(side), dict):  # the Smith random walk of the nominal NDF, same material
            wy = np.array([num(walk[side].get(o)) for o in ORDER_KEYS])
            we = np.array([num((walk.get(side + "_stderr") or {}).get(o), 0.0) for o in ORDER_KEYS])
            ax.errorbar(xs, wy, yerr=we, fmt="_", ms=18, mew=2, color="k", capsize=0,
                        label="Smith random walk" if k == 0 else None)
            positive += [v for v in wy if v > 0]
    ax.set_yscale("log")
    ax.set_ylim(min(positive) / 3, 4)
    ax.set_xticks(x)
    ax.set_xticklabels(["order 1", "order 2", "order 3", "order 4+", "total"])
    ax.set_ylabel("albedo")
    ax.set_title((title + ": " if title else "") + "albedo per scattering order", fontsize=10)
    ax.legend(fontsize=8, loc="upper center")
    ax.grid(True, axis="y", alpha=0.3)
    return _save(fig, path)


BSDF_MODELS = [
    ("smith_single", "Smith single scattering (height-correlated G2)", "-"),
    ("vcavity_single", "V-cavity single scattering", "--"),
    ("smith_multiple", "Smith random walk, all orders", ":"),
]


def _lobe(ax, rows, with_total=True):
    rows = sorted(rows, key=lambda r: num(r.get("theta_o_deg")))
    th = column(rows, "theta_o_deg")
    ax.errorbar(th, column(rows, "f_order_1"), yerr=column(rows, "f_order_1_stderr"), fmt="o", ms=3,
                capsize=2, color="C0", label="measured order 1")
    if with_total and has_field(rows, "f_total"):
        ax.errorbar(th, column(rows, "f_total"), yerr=column(rows, "f_total_stderr"), fmt="s", ms=3,
                    mfc="none", capsize=2, color="C3", label="measured, all orders")
    for key, label, ls in BSDF_MODELS:
        if has_field(rows, key) and (with_total or key != "smith_multiple"):
            ax.plot(th, column(rows, key), ls=ls, color="k", lw=1.1, label=label)
    ax.set_xlabel("theta_o (deg, signed: + on the specular side)")
    ax.set_ylabel("f (1/sr)")
    ax.grid(True, alpha=0.3)


def bsdf_lobes(path, record, title=""):
    rows = record.get("in_plane")
    if not isinstance(rows, list) or not rows or not has_field(rows, "f_order_1"):
        raise NoData("no in_plane rows in the BSDF record")
    fig, ax = plt.subplots(figsize=(7.5, 4.3))
    _lobe(ax, rows)
    ax.set_yscale("log")
    fmax = max([v for k in ("f_order_1", "f_total") for v in column(rows, k) if v == v and v > 0] or [1.0])
    ax.set_ylim(bottom=1e-4 * fmax)  # four decades below the peak
    ax.legend(fontsize=7)
    ax.set_title((title + ": " if title else "") + "in-plane BSDF lobe per order against the models", fontsize=10)
    return _save(fig, path)


def table4(path, records):
    """[Heitz14, Table 4]: in-plane single-scattering lobes at theta = 1.5 rad for several alphas."""
    usable = [(a, r) for a, r in records if isinstance(r.get("in_plane"), list) and r["in_plane"]]
    if not usable:
        raise NoData("no BSDF record with in_plane rows")
    ncol = min(3, len(usable) + 1)  # one cell more for the legend
    nrow = (len(usable) + 1 + ncol - 1) // ncol
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.0 * ncol, 3.3 * nrow), squeeze=False)
    for ax, (alpha, rec) in zip(axes.flat, usable):
        _lobe(ax, rec["in_plane"], with_total=False)
        # Log scale: V-cavity's grazing peak is 10x Smith's and hides the measured lobe on a linear one.
        ax.set_yscale("log")
        peak = max((num(r.get("f_order_1")) for r in rec["in_plane"] if num(r.get("f_order_1")) > 0), default=1.0)
        ax.set_ylim(1e-3 * peak, 3 * peak)
        ax.set_title("alpha = %g" % alpha, fontsize=10)
    handles, labels = axes.flat[0].get_legend_handles_labels()
    for ax in list(axes.flat)[len(usable):]:
        ax.axis("off")
    list(axes.flat)[-1].legend(handles, labels, fontsize=8, loc="center")
    fig.suptitle("[Heitz14, Table 4] reproduced: order-1 lobe at grazing theta = 1.5 rad (85.9 deg), Beckmann tiles, "
                 "against Smith and V-cavity", fontsize=10)
    return _save(fig, path)


# ----------------------------------------------------------------------------------------------
# Tiled boxes (measure g1 on generate tiled-boxes; fields in docs/reference/records.md)


def tiled_boxes(path, points):
    """points: list of (tiles N, measure g1 record). Visible area ratio against N per theta."""
    series = {}
    for n, rec in points:
        for r in rec.get("rows", []):
            series.setdefault(num(r.get("theta_deg")), []).append(
                (n, num(r.get("visible_area_ratio")), num(r.get("visible_area_ratio_stderr"), 0.0)))
    if not series:
        raise NoData("no visible_area_ratio rows")
    fig, ax = plt.subplots(figsize=(6.5, 4))
    for k, theta in enumerate(sorted(series)):
        pts = sorted(series[theta])
        n = np.array([p[0] for p in pts], float)
        ax.errorbar(n, [p[1] for p in pts], yerr=[p[2] for p in pts], fmt="o-", ms=4, capsize=2,
                    color="C%d" % k, label="theta = %g deg" % theta)
    ax.axhline(1, color="k", lw=0.8)
    ax.set_xscale("log", base=2)
    ax.set_xlabel("tiles per side N")
    ax.set_ylabel("visible projected area / ((v.n) A)")
    ax.set_title("Tiled boxes [GeomBSDF24, Fig. 6]: the visible area ratio converges to 1 as N grows", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return _save(fig, path)


# ----------------------------------------------------------------------------------------------
# Multiple scattering of finite objects, V-grooves and V-cavity ensembles (measure bsdf records;
# the closed forms are the records' albedo_models / in_plane fields, models/vgroove_multiple.hpp)

OBJECT_ORDERS = ["order_1", "order_2", "order_3", "order_4plus"]


def incidences(record):
    """The per-incidence objects of a measure bsdf record (one incidence: the record itself)."""
    inc = record.get("incidences")
    return inc if isinstance(inc, list) and inc else [record]


def _total_albedo(inc):
    a = (inc.get("albedo") or {}).get("reflected") or {}
    e = inc.get("reflected_stderr") or {}
    return num(a.get("total")), num(e.get("total"), 0.0)


def box_albedo(path, record, h_over_w):
    """Total albedo of a mirror box per unit macro area against its visible area ratio."""
    pts = sorted((num(i.get("theta_i_deg")),) + _total_albedo(i) +
                 (num((i.get("normalization") or {}).get("reflected_below_base_plane"), 0.0),)
                 for i in incidences(record))
    pts = [p for p in pts if p[1] == p[1]]
    if not pts:
        raise NoData("no total albedo in the box record")
    th, a, e, below = (np.array(c) for c in zip(*pts))
    ratio = 1 + h_over_w * np.tan(np.radians(th))
    fig, (ax, axz) = plt.subplots(2, 1, figsize=(6.5, 5.2), sharex=True, gridspec_kw={"height_ratios": [3, 1.3]})
    fine = np.linspace(0, max(th), 200)
    ax.plot(fine, 1 + h_over_w * np.tan(np.radians(fine)), "k-", lw=1, label="1 + (H/W) tan theta_i")
    ax.errorbar(th, a, yerr=e, fmt="o", ms=4, capsize=2, color="C0", label="traced total albedo")
    ax.plot(th, below, "s", ms=3, mfc="none", color="C1", label="of which leaves below the base plane")
    ax.set_ylabel("albedo per unit macro area")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    z = np.where(e > 0, (a - ratio) / np.where(e > 0, e, 1), 0.0)
    axz.axhspan(-3, 3, color="0.9")
    axz.plot(th, z, "o", ms=4, color="C0")
    axz.axhline(0, color="k", lw=0.8)
    axz.set_ylabel("z")
    axz.set_xlabel("theta_i (deg), across a face")
    axz.grid(True, alpha=0.3)
    ax.set_title("Mirror box H/W = %g: total albedo = visible area ratio [GeomBSDF24, Fig. 5]" % h_over_w, fontsize=10)
    return _save(fig, path)


def tiled_boxes_albedo(path, points, h_over_w):
    """points: (N, measure bsdf record of N x N tiled mirror boxes). Total albedo against N."""
    series = {}
    for n, rec in points:
        for i in incidences(rec):
            a, e = _total_albedo(i)
            if a == a:
                series.setdefault(num(i.get("theta_i_deg")), []).append((n, a, e))
    if not series:
        raise NoData("no total albedo in the tiled-box records")
    fig, (ax, axz) = plt.subplots(2, 1, figsize=(6.5, 5.2), sharex=True, gridspec_kw={"height_ratios": [3, 1.3]})
    nn = np.logspace(0, np.log2(max(n for n, _ in points)), 50, base=2)
    for k, theta in enumerate(sorted(series)):
        pts = sorted(series[theta])
        n, a, e = (np.array(c, float) for c in zip(*pts))
        ax.plot(nn, 1 + h_over_w / nn * math.tan(math.radians(theta)), "-", color="C%d" % k, lw=0.9)
        ax.errorbar(n, a, yerr=e, fmt="o", ms=4, capsize=2, color="C%d" % k,
                    label="theta_i = %g deg (line: 1 + (H/(N W)) tan theta_i)" % theta)
        model = 1 + h_over_w / n * math.tan(math.radians(theta))
        axz.plot(n * (1 + 0.04 * k), np.where(e > 0, (a - model) / np.where(e > 0, e, 1), 0.0), "o", ms=4,
                 color="C%d" % k)
    ax.axhline(1, color="k", lw=0.8)
    axz.axhspan(-3, 3, color="0.9")
    axz.axhline(0, color="k", lw=0.8)
    axz.set_ylabel("z")
    axz.grid(True, alpha=0.3)
    axz.set_xscale("log", base=2)
    axz.set_xlabel("tiles per side N")
    ax.set_ylabel("total albedo per unit macro area")
    ax.set_title("Tiled mirror boxes [GeomBSDF24, Fig. 6]: the albedo returns to 1 as N grows", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    return _save(fig, path)


def vgroove_orders(path, records):
    """records: (facet angle deg, measure bsdf record over theta_i x phi_i). Per-order albedo
    against theta_i (markers: traced; lines: the closed form vgroove_multiple)."""
    usable = [(tf, r) for tf, r in records if any(isinstance(i.get("rows"), list) for i in incidences(r))]
    if not usable:
        raise NoData("no V-groove records with rows")
    fig, axes = plt.subplots(1, len(usable), figsize=(4.2 * len(usable), 3.9), squeeze=False, sharey=True)
    zmax, nz = 0.0, 0
    for ax, (tf, rec) in zip(axes[0], usable):
        phis = sorted({num(i.get("phi_i_deg")) for i in incidences(rec)})
        for pk, phi in enumerate(phis):
            incs = sorted((i for i in incidences(rec) if num(i.get("phi_i_deg")) == phi),
                          key=lambda i: num(i.get("theta_i_deg")))
            th = np.array([num(i.get("theta_i_deg")) for i in incs])
            for k, order in enumerate(OBJECT_ORDERS):
                meas, err, model = [], [], []
                for i in incs:
                    row = next((r for r in i.get("rows", []) if r.get("side") == "reflected" and r.get("order") == order), {})
                    meas.append(num(row.get("albedo")))
                    err.append(num(row.get("albedo_stderr"), 0.0))
                    model.append(num(row.get("vgroove_multiple")))
                    z = num(row.get("z_vgroove_multiple"))
                    if z == z and num(row.get("albedo_stderr"), 0.0) > 1e-6:
                        zmax, nz = max(zmax, abs(z)), nz + 1
                ls = "-" if pk == 0 else "--"
                ax.plot(th, model, ls, color="C%d" % k, lw=1,
                        label=("closed form, order %s" % order[6:]) if pk == 0 else None)
                ax.errorbar(th, meas, yerr=err, fmt="o" if pk == 0 else "^", ms=3.5, mfc="none" if pk else None,
                            capsize=1.5, color="C%d" % k, label=("traced, phi_i = %g" % phi) if k == 0 else None)
        ax.set_title("facet angle %g deg" % tf, fontsize=10)
        ax.set_xlabel("theta_i (deg)")
        ax.grid(True, alpha=0.3)
    axes[0][0].set_ylabel("albedo per order (mirror)")
    axes[0][0].legend(fontsize=6)
    fig.suptitle("Periodic mirror V-grooves: traced per-order albedo against the closed form (2D unfolding); "
                 "max |z| = %.2f over %d rows with an error" % (zmax, nz), fontsize=10)
    return _save(fig, path)


def vcavity_albedo_orders(path, record):
    """V-cavity ensemble: per-order albedo against theta_i, traced vs the V-cavity
    multiple-scattering model, the closed form over the ensemble's own grooves and the Smith walk."""
    incs = sorted((i for i in incidences(record) if isinstance(i.get("rows"), list)), key=lambda i: num(i.get("theta_i_deg")))
    if not incs:
        raise NoData("no rows in the V-cavity record")
    th = np.array([num(i.get("theta_i_deg")) for i in incs])
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.8))
    for ax, order in zip(axes, OBJECT_ORDERS[:3]):
        def col(key):
            out = []
            for i in incs:
                row = next((r for r in i["rows"] if r.get("side") == "reflected" and r.get("order") == order), {})
                out.append(num(row.get(key)))
            return np.array(out)
        own = np.array([num(((i.get("albedo_models") or {}).get("vcavity_multiple_grooves") or {})
                            .get("reflected", {}).get(order)) for i in incs])
        ax.errorbar(th, col("albedo"), yerr=col("albedo_stderr"), fmt="o", ms=4, capsize=2, color="C0",
                    label="traced ensemble")
        ax.plot(th, own, "x", ms=7, color="C2", label="closed form, own grooves")
        ax.plot(th, col("vcavity_multiple"), "-", color="k", lw=1, label="V-cavity multiple (nominal D)")
        sm = col("smith_multiple")
        if np.any(sm == sm):
            ax.errorbar(th, sm, yerr=col("smith_multiple_stderr"), fmt="s--", ms=3, mfc="none", capsize=2,
                        color="C3", lw=0.8, label="Smith random walk")
        ax.set_title(order.replace("_", " "), fontsize=10)
        ax.set_xlabel("theta_i (deg)")
        ax.grid(True, alpha=0.3)
        if order == "order_3":
            ax.set_yscale("log")
    axes[0].set_ylabel("albedo (mirror)")
    axes[0].legend(fontsize=7)
    fig.suptitle("V-cavity ensemble (Beckmann alpha = 0.5): albedo per order", fontsize=10)
    return _save(fig, path)


def vcavity_lobes(path, record, thetas):
    """In-plane lobes per order at a few theta_i: traced, the closed form over the ensemble's own
    grooves, the V-cavity multiple-scattering model of the nominal D and the Smith walk."""
    incs = [i for i in incidences(record) if isinstance(i.get("in_plane"), list)
            and any(abs(num(i.get("theta_i_deg")) - t) < 1e-6 for t in thetas)]
    if not incs:
        raise NoData("no in_plane rows at the requested incidences")
    incs.sort(key=lambda i: num(i.get("theta_i_deg")))
    orders = [("order_1", "_order_1"), ("order_2", "_order_2"), ("total", "")]
    fig, axes = plt.subplots(len(incs), 3, figsize=(12, 3.1 * len(incs)), squeeze=False)
    for r_, inc in enumerate(incs):
        rows = sorted((r for r in inc["in_plane"] if r.get("side") == "reflected"), key=lambda r: num(r.get("theta_o_deg")))
        th = column(rows, "theta_o_deg")
        for c, (order, suffix) in enumerate(orders):
            ax = axes[r_][c]
            ax.errorbar(th, column(rows, "f_" + order), yerr=column(rows, "f_%s_stderr" % order), fmt="o", ms=3,
                        capsize=2, color="C0", label="traced ensemble")
            ax.step(th, column(rows, "vcavity_multiple_grooves" + suffix), where="mid", color="C2", lw=0.9,
                    label="closed form, own grooves")
            m, me = column(rows, "vcavity_multiple" + suffix), column(rows, "vcavity_multiple%s_stderr" % suffix)
            ax.plot(th, m, "-", color="k", lw=1.1, label="V-cavity multiple (nominal D)")
            ax.fill_between(th, m - 2 * me, m + 2 * me, color="k", alpha=0.12, lw=0)
            sk = "smith_multiple" + suffix
            if has_field(rows, sk):
                ax.plot(th, column(rows, sk), ":", color="C3", lw=1.3, label="Smith random walk")
            if order == "order_1" and has_field(rows, "vcavity_single"):
                ax.plot(th, column(rows, "vcavity_single"), "--", color="0.5", lw=0.9, label="V-cavity single scattering")
            ax.set_title("theta_i = %g deg, %s" % (num(inc.get("theta_i_deg")), order.replace("_", " ")), fontsize=9)
            ax.grid(True, alpha=0.3)
            if r_ == len(incs) - 1:
                ax.set_xlabel("theta_o (deg, signed: + on the specular side)")
            if c == 0:
                ax.set_ylabel("f (1/sr)")
    axes[0][0].legend(fontsize=6)
    fig.suptitle("V-cavity ensemble: in-plane lobes per order (a finite ensemble's lobe is a sum of the "
                 "beams of the grooves whose exits fall in the band)", fontsize=10)
    return _save(fig, path)


# Measured surfaces (generate heightmap; info's metrology)


def measured_surface(path, heights, dx, dy, guard_band=None, title=""):
    """The heightmap as an image, with the interior the estimators measure (inside the guard
    band) outlined."""
    z = np.asarray(heights, dtype=float)
    if z.ndim != 2 or z.size < 4:
        raise NoData("no 2D heightmap")
    ny, nx = z.shape
    fig, ax = plt.subplots(figsize=(5.6, 4.6))
    x0, y0 = -0.5 * nx * dx, -0.5 * ny * dy
    im = ax.imshow(z, origin="lower", cmap="viridis", extent=(x0, x0 + nx * dx, y0, y0 + ny * dy))
    fig.colorbar(im, ax=ax, label="height")
    if isinstance(guard_band, dict) and isinstance(guard_band.get("interior"), dict):
        i = guard_band["interior"]
        from matplotlib.patches import Rectangle
        ax.add_patch(Rectangle((i["x0"], i["y0"]), i["x1"] - i["x0"], i["y1"] - i["y0"],
                                                  fill=False, ec="w", lw=1.2, ls="--"))
        ax.set_title("%s%d x %d pixels\ndashed: measured interior (guard %d x %d cells)"
                     % (title + ": " if title else "", nx, ny, guard_band.get("cells_x", 0),
                        guard_band.get("cells_y", 0)), fontsize=9)
    else:
        ax.set_title("%s%d x %d pixels" % (title + ": " if title else "", nx, ny), fontsize=9)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    return _save(fig, path)


def measured_slopes(path, heights, dx, dy, metrology, title=""):
    """Density of the slope radius q = |grad h| of the triangles (two per cell, split as traced)
    against Beckmann and GGX with the alphas `info` fitted (moment and maximum likelihood),
    and the observed / expected counts in info's equal-probability bins."""
    z = np.asarray(heights, dtype=float)
    if z.ndim != 2 or not isinstance(metrology, dict) or "beckmann_alpha_x" not in metrology:
        raise NoData("no slope metrology")
    h00, h10, h01, h11 = z[:-1, :-1], z[:-1, 1:], z[1:, :-1], z[1:, 1:]
    sx = np.concatenate([((h10 - h00) / dx).ravel(), ((h11 - h01) / dx).ravel()])
    sy = np.concatenate([((h01 - h00) / dy).ravel(), ((h11 - h10) / dy).ravel()])
    q = np.hypot(sx - sx.mean(), sy - sy.mean())
    ab = math.sqrt(0.5 * (num(metrology["beckmann_alpha_x"]) ** 2 + num(metrology["beckmann_alpha_y"]) ** 2))
    ag = num(metrology.get("ggx_alpha"))
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    top = np.quantile(q, 0.999)
    counts, edges = np.histogram(q, bins=60, range=(0, top))
    width = edges[1] - edges[0]
    dens = counts / (len(q) * width)
    err = np.sqrt(counts) / (len(q) * width)
    c = 0.5 * (edges[1:] + edges[:-1])
    ax.errorbar(c, dens, yerr=err, fmt="o", ms=2.5, capsize=1.5, color="k", label="measured (triangles)")
    t = np.linspace(0, top, 400)
    ax.plot(t, 2 * t / ab ** 2 * np.exp(-t ** 2 / ab ** 2), "C0-", label="Beckmann, alpha %.3f (moment)" % ab)
    if ag == ag and ag > 0:
        ax.plot(t, 2 * t / ag ** 2 / (1 + t ** 2 / ag ** 2) ** 2, "C3--", label="GGX, alpha %.3f (max. likelihood)" % ag)
    ax.set_xlabel("slope radius |grad h|")
    ax.set_ylabel("density")
    ax.set_yscale("log")
    ax.set_ylim(bottom=max(1e-4 * np.max(dens), 0.5 / (len(q) * width)))
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    for k, (key, label) in enumerate((("slope_fit_beckmann", "Beckmann"), ("slope_fit_ggx", "GGX"))):
        fit = metrology.get(key)
        if not isinstance(fit, dict) or not fit.get("observed"):
            continue
        o, e = np.array(fit["observed"], float), np.array(fit["expected"], float)
        x = np.arange(len(o)) + (k - 0.5) * 0.35
        ax2.errorbar(x, o / e, yerr=np.sqrt(np.maximum(o, 1)) / e, fmt="o", ms=3, capsize=2, color="C0" if k == 0 else "C3",
                     label="%s: chi2/dof %.3g" % (label, num(fit.get("chi2")) / max(1, num(fit.get("dof"), 1))))
    ax2.axhline(1, color="k", lw=1)
    ax2.set_xlabel("equal-probability bin of the model (slope radius, increasing)")
    ax2.set_ylabel("observed / expected")
    ax2.grid(True, alpha=0.3)
    ax2.legend(fontsize=7)
    fig.suptitle((title + ": " if title else "") + "slope distribution against Beckmann and GGX "
                 "(pixels are correlated: compare the models, not absolute chi2)", fontsize=10)
    return _save(fig, path)
