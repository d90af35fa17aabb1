"""The report: runs microsim, draws the figures, writes index.html.

A section is one function `section_NAME(ctx)` in SECTIONS: it runs what it needs through
ctx.run(...), draws its figures with msreport.plots and returns a Section. A section whose
command does not exist in this microsim build (an older build without G2, BSDF or tiled boxes)
returns a Section with `skipped` set; the page lists it with the reason. Adding a
quantity to the report is adding one such function.
"""
import html
import json
import os
import shlex
import subprocess
import time

from . import plots
from .readers import load_json, num, read_exr

# Run sizes. "default": the report of docs/guide/validate.md (at most 10 minutes on 2 cores);
# "smoke": seconds, for the CTest smoke test (same code paths, tiny runs).
PROFILES = {
    "default": {
        "suite": "default",
        "g1_theta": "0:85:5",
        "g1_rays": 100000,
        "g1_max_phis": 2,
        "g2_rays": 200000,
        "bsdf_rays": 1000000,
        # 8 cells per correlation length, 64 per tile: the grazing order-1 lobe is 19% low at 4
        # cells per l and within its error of 32 cells at 8 (docs/findings/records/convergence.md).
        "table4_resolution": 512,
        "table4_cells_per_l": 8,
        "table4_rays": 1000000,
        "tiles": [1, 2, 4, 8, 16],
        "tiles_rays": 200000,
        "objects_rays": 200000,
        "vgroove_rays": 20000,
        "vcavity_grooves": 4096,
        "vcavity_rays": 200000,
        "vcavity_theta": "0,30,60,80",
        "preview_resolution": 256,
        "preview_rays": 200000,
        "preview_theta": "0:85:5",
        "preview_size": 160,
        "preview_samples": 64,
        "preview_cases": [(0.5, "mirror"), (1.0, "mirror"), (0.5, "gold")],
        # A 512^2 tile at 8 cells per correlation length l, cropped to 384^2 heights (48 l): the
        # default guard band (8 l a side) leaves an interior of about 32 l.
        "measured_resolution": 512,
        "measured_cells_per_l": 8,
        "measured_rays": 200000,
    },
    "smoke": {
        "suite": "smoke",
        "g1_theta": "0:80:20",
        "g1_rays": 10000,
        "g1_max_phis": 2,
        "g2_rays": 10000,
        "bsdf_rays": 20000,
        "table4_resolution": 64,
        "table4_cells_per_l": 4,
        "table4_rays": 20000,
        "tiles": [1, 2, 4],
        "tiles_rays": 10000,
        "objects_rays": 5000,
        "vgroove_rays": 2000,
        "vcavity_grooves": 256,
        "vcavity_rays": 20000,
        "vcavity_theta": "0,60",
        "preview_resolution": 64,
        "preview_rays": 5000,
        "preview_theta": "0:80:40",
        "preview_size": 24,
        "preview_samples": 4,
        "preview_cases": [(0.5, "mirror")],
        "measured_resolution": 64,
        "measured_rays": 10000,
        "measured_guard": 2,  # correlation lengths: the default 8 leaves no interior at this size
    },
}

TABLE4_ALPHAS = [0.1, 0.4, 0.7, 1.0, 1.3]
TABLE4_THETA_DEG = 1.5 * 180.0 / 3.141592653589793  # [Heitz14, Table 4]: theta = 1.5 rad


class Section:
    def __init__(self, key, title, intro=""):
        self.key, self.title, self.intro = key, title, intro
        self.figures = []  # (relative path, caption)
        self.html = ""     # extra HTML (tables)
        self.skipped = None
        self.failed = None  # a command of this section failed: shown on the page, exit code 1
        self.notes = []

    def skip(self, reason):
        """This section cannot run here (a command missing from this build, no data)."""
        self.skipped = reason
        return self

    def figure(self, ctx, name, draw, caption, *args):
        """Draws one figure; missing data (plots.NoData) becomes a note, not a failure."""
        path = os.path.join(ctx.fig_dir, name)
        try:
            draw(path, *args)
        except plots.NoData as e:
            self.notes.append("%s not drawn: %s" % (name, e))
            return
        self.figures.append((os.path.relpath(path, ctx.out), caption))


class Context:
    def __init__(self, microsim, out, profile, threads=None, verbose=True):
        self.microsim = microsim
        self.out = out
        self.data_dir = os.path.join(out, "data")
        self.fig_dir = os.path.join(out, "figures")
        self.surf_dir = os.path.join(self.data_dir, "surfaces")
        self.profile = PROFILES[profile]
        self.profile_name = profile
        self.threads = threads
        self.verbose = verbose
        self.log = []  # (command line, seconds, exit code)
        self.validation = None
        self.validation_failed = False
        for d in (self.data_dir, self.fig_dir, self.surf_dir):
            os.makedirs(d, exist_ok=True)

    def data(self, name):
        return os.path.join(self.data_dir, name)

    def run(self, args, check=True, quiet=True):
        """Runs microsim ARGS; returns CompletedProcess. check: raise on a non-zero exit."""
        cmd = [self.microsim] + list(args)
        if quiet:
            cmd.append("--quiet")
        if self.threads:
            cmd += ["--threads", str(self.threads)]
        t0 = time.time()
        if self.verbose:
            print("  $ " + " ".join(shlex.quote(c) for c in cmd), flush=True)
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        dt = time.time() - t0
        shown = [c.replace(self.out, "REPORT") if c.startswith(self.out) else c for c in cmd]
        self.log.append((" ".join(shlex.quote(c) for c in shown), dt, p.returncode))
        if check and p.returncode != 0:
            words = " ".join(a for a in list(args)[:2] if not a.startswith("-") and "/" not in a)
            raise RuntimeError("microsim %s failed (exit %d): %s" % (words, p.returncode, p.stderr.strip()))
        return p

    def has_command(self, *words):
        """True when `microsim WORDS --help` exists in this build."""
        p = subprocess.run([self.microsim] + list(words) + ["--help"], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, text=True)
        return p.returncode == 0

    def entries(self):
        return (self.validation or {}).get("entries", [])

    def surface_files(self, entry_name):
        return [f["file"] for f in (self.validation or {}).get("surface_files", []) if f["entry"] == entry_name]


def _nominal_entries(ctx):
    return [e for e in ctx.entries() if isinstance(e.get("measurements", {}).get("d_nominal"), dict)]


# ----------------------------------------------------------------------------------------------
# Sections


def section_validation(ctx):
    s = Section("validation", "Validation suite",
                "`microsim validate --suite %s`: every applicable check of every surface of the suite. "
                "Identities (two estimators of one quantity, geometric consequences, [GeomBSDF24, eq. 1b/1c]) must "
                "pass; approximate models (Smith per normal bin, V-cavity, the nominal NDF the generator "
                "aimed at) are findings: their deviations are results, not errors. Nominal models are judged "
                "only over ensembles of surfaces, with the between-surface error and Student t (K - 1 "
                "degrees of freedom); for one surface they are measured beside the model (info)."
                % ctx.profile["suite"])
    out = ctx.data("validation.json")
    p = ctx.run(["validate", "--suite", ctx.profile["suite"], "-o", out, "--surfaces-dir", ctx.surf_dir],
                check=False, quiet=False)
    with open(ctx.data("validation.txt"), "w") as f:
        f.write(p.stdout)
    if p.returncode not in (0, 1) or not os.path.isfile(out):
        raise RuntimeError("microsim validate failed (exit %d): %s" % (p.returncode, p.stderr.strip()))
    ctx.validation = load_json(out)
    ctx.validation_failed = p.returncode == 1
    s.figure(ctx, "validation_z.png", plots.validation_z,
             "z-scores of all z-tested rows, by check, in units of each row's threshold (Sidak over all "
             "rows; Student t with K - 1 dof for ensemble rows). Identities (green pass / red FAIL) must stay "
             "inside the dashed lines; approximate models (blue agrees / orange deviates) may not.",
             ctx.validation)
    s.html = validation_table_html(ctx.validation)
    return s


def section_ndf(ctx):
    s = Section("ndf", "Normal distribution D",
                "D measured exactly from the facets (sum of facet areas per bin / (A x solid angle)); error bars "
                "from spatial blocks of one tile, or between the surfaces of an ensemble.")
    entries = _nominal_entries(ctx)
    if not entries:
        return s.skip("no suite entry with a nominal NDF")
    s.figure(ctx, "ndf_rings.png", plots.ndf_rings,
             "D per 5-degree ring (phi-averaged) against the nominal NDF, bin-averaged; bottom: relative "
             "deviation. The far tail holds few facets.", entries)
    for e in entries:
        files = ctx.surface_files(e["name"])
        if not files:
            continue
        exr = ctx.data("ndf_%s.exr" % e["name"])
        ctx.run(["measure", "ndf", files[0], "-o", exr, "--theta-bins", "90", "--phi-bins", "72"])
        ch, attrs = read_exr(exr)
        s.figure(ctx, "ndf_map_%s.png" % e["name"], plots.ndf_map,
                 "%s (first surface): D over the upper hemisphere in 2 x 5 degree bins, the nominal NDF and "
                 "their ratio (from `measure ndf -o .exr`)." % e["name"], ch, attrs, e["name"])
    return s


def section_g1(ctx):
    s = Section("g1", "Masking G1",
                "Averaged G1 (projected-area average over front-facing facets) by area sampling and by ray "
                "casting, against Smith with the surface's own facets (smith_numeric) and Smith with the "
                "nominal NDF. Every model satisfying the weak white furnace test (Smith, V-cavity: [Heitz14, eq. 19]) "
                "has the same average G1 = 1/(1+Lambda); the models differ per normal, shown next.")
    entries = _nominal_entries(ctx)
    if not entries:
        return s.skip("no suite entry with a nominal NDF")
    for e in entries:
        files = ctx.surface_files(e["name"])
        if not files:
            continue
        out = ctx.data("g1_%s.json" % e["name"])
        # The suite's azimuths, at most g1_max_phis of them (first and last: e.g. 0 and 90).
        phis = e["parameters"]["phi_deg"]
        if len(phis) > ctx.profile["g1_max_phis"]:
            phis = [phis[0], phis[-1]]
        ctx.run(["measure", "g1"] + files + ["--theta", ctx.profile["g1_theta"], "--phi",
                                             ",".join("%g" % p for p in phis),
                                             "--rays", str(ctx.profile["g1_rays"]), "-o", out])
        s.figure(ctx, "g1_%s.png" % e["name"], plots.g1_curves,
                 "%s: G1(theta) with %s error bars against Smith; bottom: relative deviations."
                 % (e["name"], "between-surface" if len(files) > 1 else "ray-count"), load_json(out), e["name"])
    for e in ctx.entries():
        if e.get("measurements", {}).get("g1"):
            s.figure(ctx, "g1_bins_%s.png" % e["name"], plots.g1_per_normal,
                     "%s: G1(v, m) per normal bin (10 x 45 degree bins), by the azimuth of m relative to the "
                     "view. Smith predicts one horizontal line; V-cavity (dashed) a function of m only."
                     % e["name"], e)
    return s


def section_g2(ctx):
    s = Section("g2", "Masking-shadowing G2",
                "G2 averaged over the facets facing both directions with the weight A_f (max(0, o.m_f) + "
                "max(0, i.m_f)) / 2 (G1's projected area at o = i, so that G2(v, v) = G1(v)), against the four "
                "Smith forms of [Heitz14, Sec. 5] (eq. 20-23) and the V-cavity model.")
    if not ctx.has_command("measure", "g2"):
        return s.skip("`microsim measure g2` is not in this build")
    entries = [e for e in _nominal_entries(ctx) if ctx.surface_files(e["name"])]
    if not entries:
        return s.skip("no surface with a nominal NDF")
    e = entries[0]
    out = ctx.data("g2_%s.json" % e["name"])
    ctx.run(["measure", "g2", ctx.surface_files(e["name"])[0], "--theta-o", "30,60,80", "--phi-o", "0",
             "--theta-i", "0:80:10", "--phi-i", "0,180", "--rays", str(ctx.profile["g2_rays"]), "-o", out])
    s.figure(ctx, "g2_%s.png" % e["name"], plots.g2_curves,
             "%s: G2 against theta_i for several theta_o, in the plane of incidence (delta phi = 0: same "
             "side, 180: opposite sides)." % e["name"], load_json(out), e["name"])
    for entry in ctx.entries():
        g2 = entry.get("measurements", {}).get("g2")
        if isinstance(g2, list) and any(surface.get("hotspot") for surface in g2):
            s.figure(ctx, "g2_hotspot_%s.png" % entry["name"], plots.g2_hotspot,
                     "%s (validate): at o = i the measured G2 equals G1 measured by an independent run with "
                     "the same weights, and Smith's direction-correlated form; right: z of G2 - G1 (dashed: "
                     "+-3)." % entry["name"], entry)
    return s


def section_bsdf(ctx):
    s = Section("bsdf", "BSDF per scattering order",
                "Random walks on the explicit surface (mirror facets): albedo and in-plane lobe per scattering "
                "order, against the single-scattering models and the Smith random-walk model [Heitz14, Sec. 4.3 and 7].")
    if not ctx.has_command("measure", "bsdf"):
        return s.skip("`microsim measure bsdf` is not in this build")
    entries = [e for e in _nominal_entries(ctx) if ctx.surface_files(e["name"])]
    if not entries:
        return s.skip("no surface with a nominal NDF")
    for e in entries[:2]:
        out = ctx.data("bsdf_%s.json" % e["name"])
        ctx.run(["measure", "bsdf", ctx.surface_files(e["name"])[0], "--material", "mirror", "--theta-i", "60",
                 "--phi-i", "0", "--orders", "4", "--rays", str(ctx.profile["bsdf_rays"]), "-o", out])
        rec = load_json(out)
        s.figure(ctx, "bsdf_albedo_%s.png" % e["name"], plots.bsdf_albedo,
                 "%s, mirror, theta_i = 60 deg: albedo per order (a mirror conserves energy: total 1)." % e["name"],
                 rec, e["name"])
        s.figure(ctx, "bsdf_lobe_%s.png" % e["name"], plots.bsdf_lobes,
                 "%s, mirror, theta_i = 60 deg: in-plane lobe, order 1 and all orders, against the models."
                 % e["name"], rec, e["name"])
    return s


def section_table4(ctx):
    s = Section("table4", "[Heitz14, Table 4] reproduced",
                "Order-1 lobes of Beckmann tiles at grazing incidence theta = 1.5 rad for alpha = 0.1 ... 1.3 "
                "([Heitz14, Table 4]: Smith shifts the lobe toward the view direction as alpha grows, V-cavity does "
                "not; the explicit surface decides).")
    if not ctx.has_command("measure", "bsdf"):
        return s.skip("`microsim measure bsdf` is not in this build")
    records = []
    for a in TABLE4_ALPHAS:
        surf = os.path.join(ctx.surf_dir, "table4-alpha%g.exr" % a)
        res = ctx.profile["table4_resolution"]
        ctx.run(["generate", "gaussian", "--alpha", "%g" % a, "--resolution", str(res),
                 "--correlation-length", "%g" % (ctx.profile["table4_cells_per_l"] / res), "--seed", "1",
                 "-o", surf])
        out = ctx.data("table4_alpha%g.json" % a)
        ctx.run(["measure", "bsdf", surf, "--material", "mirror", "--theta-i", "%.6f" % TABLE4_THETA_DEG,
                 "--phi-i", "0", "--orders", "4", "--rays", str(ctx.profile["table4_rays"]), "-o", out])
        records.append((a, load_json(out)))
    s.figure(ctx, "table4.png", plots.table4,
             "In-plane order-1 lobes at theta_i = 1.5 rad (by reciprocity the lobes of [Heitz14, Table 4], which fixes "
             "the view), measured against Smith and V-cavity single scattering.", records)
    return s


def section_tiled_boxes(ctx):
    s = Section("tiled_boxes", "Tiled boxes",
                "[GeomBSDF24, Fig. 5-6]: a box is visibly larger than its macrosurface at grazing angles; tiling it N x N "
                "times (scaled by 1/N) makes the visible projected area converge to (v.n) A.")
    if not ctx.has_command("generate", "tiled-boxes"):
        return s.skip("`microsim generate tiled-boxes` is not in this build")
    preset = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "..", "surfaces",
                          "tiled-boxes.toml")
    points = []
    for n in ctx.profile["tiles"]:
        surf = os.path.join(ctx.surf_dir, "tiled-boxes-%d.ply" % n)
        args = ["generate", "tiled-boxes", "--tiles", str(n), "-o", surf]
        if os.path.isfile(preset):
            args[2:2] = ["--config", os.path.normpath(preset)]
        ctx.run(args)
        out = ctx.data("tiled_boxes_%d.json" % n)
        ctx.run(["measure", "g1", surf, "--theta", "30,60,80", "--rays", str(ctx.profile["tiles_rays"]), "-o", out])
        points.append((n, load_json(out)))
    s.figure(ctx, "tiled_boxes.png", plots.tiled_boxes,
             "Visible area ratio of N x N tiled boxes at theta = 30, 60, 80 deg with ray-count errors.", points)
    return s


BOX_H_OVER_W = 0.5
VGROOVE_FACET_DEG = [45, 60, 70]
VCAVITY_LOBE_THETA = [0, 30, 60]


def section_objects_grooves(ctx):
    s = Section("objects_grooves", "Multiple scattering of boxes, V-grooves and V-cavities",
                "measure bsdf on surfaces that are not heightfields, mirror facets. A finite object's albedo is per "
                "unit macro area [GeomBSDF24, eq. 4a], so a mirror box reflects its visible area ratio 1 + (H/W) tan theta_i "
                "and N x N tiled boxes return to 1 as 1 + (H/(N W)) tan theta_i. Periodic V-grooves and V-cavity "
                "ensembles beside the closed-form multiple scattering of a mirror V-groove per order "
                "(models/vgroove_multiple.hpp: 2D unfolding; Xie and Hanrahan 2018), averaged over grooves drawn from "
                "D for the V-cavity model [Heitz14, Sec. 6], and beside the Smith random walk.")
    if not ctx.has_command("measure", "bsdf") or not ctx.has_command("generate", "vcavity"):
        return s.skip("`microsim measure bsdf` or `generate vcavity` is not in this build")
    p = ctx.profile
    hw = "%g" % BOX_H_OVER_W
    # Mirror box, theta_i 0..75 across a face.
    box = os.path.join(ctx.surf_dir, "box.ply")
    ctx.run(["generate", "box", "--height", hw, "-o", box])
    out = ctx.data("objects_box.json")
    ctx.run(["measure", "bsdf", box, "--material", "mirror", "--theta-i", "0:75:15", "--phi-i", "0",
             "--rays", str(p["objects_rays"]), "--resolution", "16", "-o", out])
    s.figure(ctx, "objects_box.png", plots.box_albedo,
             "Mirror box H/W = %s: total albedo per unit macro area against 1 + (H/W) tan theta_i with ray-count "
             "errors; below: z. The walls send part of the light below the base plane (squares): it is in the "
             "albedo, not in the hemisphere maps." % hw, load_json(out), BOX_H_OVER_W)
    # Tiled boxes N = 1..16.
    points = []
    for n in p["tiles"]:
        surf = os.path.join(ctx.surf_dir, "objects-tiled-%d.ply" % n)
        ctx.run(["generate", "tiled-boxes", "--height", hw, "--tiles", str(n), "-o", surf])
        out = ctx.data("objects_tiled_%d.json" % n)
        ctx.run(["measure", "bsdf", surf, "--material", "mirror", "--theta-i", "30,60", "--phi-i", "0",
                 "--rays", str(p["objects_rays"]), "--resolution", "16", "-o", out])
        points.append((n, load_json(out)))
    s.figure(ctx, "objects_tiled_boxes.png", plots.tiled_boxes_albedo,
             "N x N tiled mirror boxes (H/W = %s, scaled by 1/N): total albedo per unit macro area against N at "
             "theta_i = 30 and 60 deg; lines: 1 + (H/(N W)) tan theta_i (only the outer walls stick out)." % hw,
             points, BOX_H_OVER_W)
    # Periodic V-grooves per order against the closed form.
    records = []
    for tf in VGROOVE_FACET_DEG:
        surf = os.path.join(ctx.surf_dir, "vgroove-%d.exr" % tf)
        ctx.run(["generate", "vgroove", "--facet-angle", str(tf), "-o", surf])
        out = ctx.data("objects_vgroove_%d.json" % tf)
        ctx.run(["measure", "bsdf", surf, "--material", "mirror", "--theta-i", "0:80:10", "--phi-i", "0,45",
                 "--rays", str(p["vgroove_rays"]), "--resolution", "16", "-o", out])
        records.append((tf, load_json(out)))
    s.figure(ctx, "objects_vgroove_orders.png", plots.vgroove_orders,
             "Periodic mirror V-grooves, facet angles %s deg: per-order albedo against theta_i at phi_i = 0 (circles, "
             "solid lines) and 45 deg (triangles, dashed), traced in 3D and from the closed form; the bounce count "
             "is bounded and set by the incidence projected into the groove's cross-section."
             % ", ".join(str(t) for t in VGROOVE_FACET_DEG), records)
    # V-cavity ensemble, Beckmann alpha 0.5.
    surf = os.path.join(ctx.surf_dir, "vcavity-beckmann-0.5.ply")
    ctx.run(["generate", "vcavity", "--alpha", "0.5", "--grooves", str(p["vcavity_grooves"]), "-o", surf])
    out = ctx.data("objects_vcavity.json")
    ctx.run(["measure", "bsdf", surf, "--material", "mirror", "--theta-i", p["vcavity_theta"], "--phi-i", "0",
             "--rays", str(p["vcavity_rays"]), "--resolution", "16", "-o", out])
    rec = load_json(out)
    s.figure(ctx, "objects_vcavity_albedo.png", plots.vcavity_albedo_orders,
             "V-cavity ensemble of %d grooves (Beckmann alpha = 0.5), mirror: albedo per order traced groove by "
             "groove, the closed form over the ensemble's own grooves (the exact expectation of the traced value), "
             "the V-cavity multiple-scattering model of the nominal D, and the Smith random walk (order 3 on a log "
             "scale: a V-groove needs facets steeper than about 55-60 deg for a third bounce)." % p["vcavity_grooves"],
             rec)
    s.figure(ctx, "objects_vcavity_lobes.png", plots.vcavity_lobes,
             "The same ensemble: in-plane lobes (band of +-5.6 deg around the plane of incidence) per order at "
             "theta_i = %s deg (those measured). Every groove reflects into a few discrete directions, so the lobe of a finite "
             "ensemble is the sum of the beams of the few grooves whose exits fall in the band: the traced lobe "
             "equals the closed form over the ensemble's own grooves bin by bin, while the nominal V-cavity model "
             "(grey band: 2 Monte Carlo errors) is its expectation over D; its order 1 is the V-cavity single "
             "scattering (dashed)." % ", ".join(str(t) for t in VCAVITY_LOBE_THETA), rec, VCAVITY_LOBE_THETA)
    return s


def _markdown_tables_html(text):
    """The headings, paragraphs and pipe tables of a Markdown file as HTML (enough for the study's tables)."""
    esc = html.escape
    out, table = [], []

    def flush():
        if table:
            rows = [r for r in table if not set(r.replace("|", "").strip()) <= set("-: ")]
            out.append("<table>")
            for i, r in enumerate(rows):
                cells = [c.strip() for c in r.strip().strip("|").split("|")]
                tag = "th" if i == 0 else "td"
                out.append("<tr>" + "".join("<%s>%s</%s>" % (tag, esc(c).replace("**", ""), tag) for c in cells) + "</tr>")
            out.append("</table>")
            table.clear()

    for line in text.splitlines():
        if line.startswith("|"):
            table.append(line)
            continue
        flush()
        if line.startswith("#"):
            level = min(4, 2 + line.count("#", 0, line.find(" ")))
            out.append("<h%d>%s</h%d>" % (level, esc(line.lstrip("# ")), level))
        elif line.strip():
            out.append("<p>%s</p>" % esc(line))
    flush()
    return "\n".join(out)


def section_convergence(ctx):
    s = Section("convergence", "Converged surfaces: the discretization study",
                "What a triangulated Gaussian heightfield measures depends on the cells per correlation length "
                "(l / dx) and on the correlation lengths per tile (L / l). The study (analysis/convergence.sh, "
                "a long run not repeated here) measures every reported quantity on ensembles of tiles at "
                "2 ... 32 cells per l and 16 ... 256 l per tile, for Beckmann alpha = 0.2, 0.5, 1 and the GGX "
                "heightfield (alpha = 0.5); shown: its recorded table and figures.")
    root = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
    table = os.path.join(root, "docs", "findings", "records", "convergence.md")
    img = os.path.join(root, "docs", "img")
    figs = sorted(f for f in os.listdir(img) if f.startswith("convergence_") and f.endswith(".png")) \
        if os.path.isdir(img) else []
    if not os.path.isfile(table) or not figs:
        return s.skip("no recorded study (docs/findings/records/convergence.md, docs/img/convergence_*.png)")
    import shutil
    captions = {"cells": "Difference from the finest grid (32 cells per l; paired: the same tiles on every grid) "
                         "against cells per correlation length; grey band: 1%. Beckmann at 32 l per tile, the GGX "
                         "heightfield at 64 (its preset's tile).",
                "tile": "Difference from the largest tile (256 l per tile) "
                        "against correlation lengths per tile (independent tiles per level); grey band: 1%.",
                "lobe80": "In-plane lobe of a mirror at theta_i = 80 deg per grid level (order 1, and all orders dotted)."}
    for f in figs:
        kind = f[:-4].rsplit("_", 1)[-1]
        s.figure(ctx, f, lambda path, src=os.path.join(img, f): shutil.copyfile(src, path),
                 captions.get(kind, f))
    with open(table) as fh:
        s.html = _markdown_tables_html(fh.read())
    # The model statements re-measured on the default (converged) grid, when recorded.
    models = os.path.join(root, "docs", "findings", "records", "converged-models.md")
    if os.path.isfile(models):
        with open(models) as fh:
            s.html += _markdown_tables_html(fh.read())
    return s


# Gold-like conductor (index at about 600 nm) for the previews.
GOLD_ETA, GOLD_K = 0.47, 2.4


def section_previews(ctx):
    s = Section("previews", "Sphere previews of the measured tables",
                "A Beckmann tile measured into an RGL .bsdf table (measure bsdf), rendered on a sphere (render) "
                "beside the single-scattering microfacet BRDF (height-correlated Smith G2) and the Smith random "
                "walk (all orders) of the same alpha and material. Rows: directional light (irradiance pi, from "
                "upper left, 45 deg off the view axis), uniform white environment (radiance = albedo). Columns: "
                "measured, single scattering, Smith walk, measured - Smith walk (red +, blue -, full colour at "
                "+-0.1).")
    if not ctx.has_command("render"):
        return s.skip("`microsim render` is not in this build")
    p = ctx.profile
    rows = []
    for alpha, material in p["preview_cases"]:
        surf = os.path.join(ctx.surf_dir, "preview-alpha%g.exr" % alpha)
        if not os.path.isfile(surf):
            ctx.run(["generate", "gaussian", "--alpha", "%g" % alpha, "--resolution", str(p["preview_resolution"]),
                     "--seed", "1", "-o", surf])
        mat = ["--material", "mirror"] if material == "mirror" else \
            ["--material", "conductor", "--eta", str(GOLD_ETA), "--k", str(GOLD_K)]
        name = "preview_alpha%g_%s" % (alpha, material)
        table = ctx.data(name + ".bsdf")
        ctx.run(["measure", "bsdf", surf] + mat + ["--theta-i", p["preview_theta"], "--rays", str(p["preview_rays"]),
                                                    "--no-models", "-o", table])
        record = ctx.data(name + "_render.json")

        def draw(path, table=table, record=record):
            ctx.run(["render", table, "--size", str(p["preview_size"]), "--samples", str(p["preview_samples"]),
                     "-o", path, "-o", record])
        s.figure(ctx, name + ".png", draw,
                 "alpha = %g, %s: measured | single scattering | Smith walk | measured - walk; top: directional "
                 "light, bottom: white environment." % (alpha, "mirror" if material == "mirror" else
                                                       "gold-like conductor (eta %g + %gi)" % (GOLD_ETA, GOLD_K)))
        if os.path.isfile(record):
            summ = load_json(record)["summary"]
            rows.append((alpha, material, summ))
    if rows:
        h = ["<table><tr><th>alpha</th><th>material</th><th>light</th><th>measured</th><th>single</th>"
             "<th>Smith walk</th><th>rms(measured - walk)</th></tr>"]
        for alpha, material, summ in rows:
            for light in ("directional", "environment"):
                d = summ[light]
                h.append("<tr><td>%g</td><td>%s</td><td>%s</td><td>%.4f</td><td>%.4f</td><td>%.4f</td><td>%.4f</td></tr>"
                         % (alpha, material, light, d["measured"]["mean"], d["single"]["mean"], d["walk"]["mean"],
                            d["difference"]["rms"]))
        h.append("</table><p>Means of the radiance over the sphere's pixels.</p>")
        s.html = "".join(h)
    return s


def section_measured(ctx):
    s = Section("measured", "A measured surface",
                "From a plain heightmap file, as an instrument exports it: a crop of a generated Beckmann tile "
                "(alpha 0.5, not periodic) written as a CSV grid, imported with `generate heightmap` (a "
                "non-periodic window: the estimators measure its interior inside the default guard band, the "
                "border geometry masks), then `info` (metrology), `measure g1` (per normal against Smith) and "
                "`measure bsdf`. analysis/measured_surface_example.sh runs the same chain to `validate` and a "
                "renderer's .bsdf table.")
    if not ctx.has_command("generate", "heightmap"):
        return s.skip("`microsim generate heightmap` is not in this build")
    import numpy as np
    res = ctx.profile["measured_resolution"]
    tile = os.path.join(ctx.surf_dir, "measured-source.exr")
    length = (["--correlation-length", "%.9g" % (ctx.profile["measured_cells_per_l"] / res)]
              if "measured_cells_per_l" in ctx.profile else [])
    ctx.run(["generate", "gaussian", "--alpha", "0.5", "--resolution", str(res), "--seed", "7", "-o", tile] + length)
    ch, _ = read_exr(tile)
    z = ch["Z"]
    n = (3 * res) // 4  # a crop: not periodic
    csv = ctx.data("measured-patch.csv")
    dx = 1.0 / res
    np.savetxt(csv, z[:n, :n], delimiter=",", fmt="%.9g")
    surf = os.path.join(ctx.surf_dir, "measured-patch.exr")
    guard = ["--guard", str(ctx.profile["measured_guard"])] if "measured_guard" in ctx.profile else []
    ctx.run(["generate", "heightmap", "--input", csv, "--pixel-size", "%.9g" % dx, "--detrend", "plane",
             "-o", surf] + guard)
    info = ctx.data("measured_info.json")
    ctx.run(["info", surf, "--json", info])
    rec_info = load_json(info)
    met = rec_info.get("metrology", {})
    desc = rec_info.get("surface", {})
    hz, _ = read_exr(surf)
    s.figure(ctx, "measured_surface.png", plots.measured_surface,
             "The imported patch (%d x %d heights from a CSV grid, plane removed) and the interior the "
             "estimators measure." % (n, n), hz["Z"], dx, dx, desc.get("guard_band"), "measured patch")
    s.figure(ctx, "measured_slopes.png", plots.measured_slopes,
             "Slopes of the patch's triangles against Beckmann (moment alpha) and GGX (maximum-likelihood "
             "alpha), the fits of `info`.", hz["Z"], dx, dx, met, "measured patch")
    g1 = ctx.data("measured_g1.json")
    ctx.run(["measure", "g1", surf, "--theta", "30,60,80", "--phi", "0", "--rays", str(ctx.profile["measured_rays"]),
             "-o", g1])
    rec = load_json(g1)
    for row in rec.get("rows", []):
        for b in row.get("bins", []):
            if "vcavity_numeric" in b:
                b["vcavity"] = b["vcavity_numeric"]
    s.figure(ctx, "measured_g1_bins.png", plots.g1_per_normal,
             "G1(v, m) per normal bin on the measured patch against Smith with its own facets and V-cavity "
             "(ray-count errors).", {"name": "measured patch", "measurements": {"g1": [rec]}})
    bsdf = ctx.data("measured_bsdf.json")
    ctx.run(["measure", "bsdf", surf, "--material", "mirror", "--theta-i", "60", "--phi-i", "0", "--orders", "4",
             "--rays", str(ctx.profile["measured_rays"]), "-o", bsdf])
    rb = load_json(bsdf)
    s.figure(ctx, "measured_bsdf_albedo.png", plots.bsdf_albedo,
             "Measured patch, mirror, theta_i = 60 deg: albedo per order (rays leaving through the patch's side "
             "walls downward are lost: the total is 1 minus those).", rb, "measured patch")
    s.figure(ctx, "measured_bsdf_lobe.png", plots.bsdf_lobes,
             "Measured patch, mirror, theta_i = 60 deg: in-plane lobe, order 1 and all orders.", rb, "measured patch")
    gb = desc.get("guard_band") or {}
    s.html = ("<p>Metrology: Sq %s, Sdq %s, Beckmann alpha (%s, %s), GGX alpha %s, Sal %s; guard band %s x %s "
              "cells (%s correlation lengths), interior %s x %s cells.</p>"
              % tuple(_fmt(x, 4) for x in (met.get("sq"), met.get("sdq"), met.get("beckmann_alpha_x"),
                                            met.get("beckmann_alpha_y"), met.get("ggx_alpha"), met.get("sal"),
                                            gb.get("cells_x"), gb.get("cells_y"),
                                            gb.get("width_correlation_lengths"),
                                            (gb.get("interior") or {}).get("cells_x"),
                                            (gb.get("interior") or {}).get("cells_y"))))
    return s


# The figures the findings pages of the documentation show (docs/findings/*.md), by their stable
# names in the report (default profile and suite). `make_report.py --figures DIR` writes them there.
FINDINGS_FIGURES = [
    "validation_z.png", "g1_beckmann-0.5.png", "g1_bins_beckmann-0.5.png",
    "g2_beckmann-0.5.png", "g2_hotspot_beckmann-0.5-checks.png",
    "bsdf_albedo_beckmann-0.5.png", "bsdf_lobe_beckmann-0.5.png", "table4.png",
    "objects_box.png", "objects_tiled_boxes.png", "objects_vgroove_orders.png",
    "objects_vcavity_albedo.png", "objects_vcavity_lobes.png",
]


def export_figures(ctx, folder, names=None):
    """Copies the findings figures NAMES (default FINDINGS_FIGURES) of this report into FOLDER,
    as palette PNGs (a few tens of kB each: they are committed with the documentation).
    Returns the paths written; raises RuntimeError naming the figures this report did not draw."""
    from PIL import Image
    names = FINDINGS_FIGURES if names is None else names
    missing = [n for n in names if not os.path.isfile(os.path.join(ctx.fig_dir, n))]
    if missing:
        raise RuntimeError("figures for %s not drawn by this report: %s" % (folder, ", ".join(missing)))
    os.makedirs(folder, exist_ok=True)
    written = []
    for n in names:
        with Image.open(os.path.join(ctx.fig_dir, n)) as im:
            small = im.convert("RGB").quantize(colors=128, method=Image.Quantize.MEDIANCUT)
            path = os.path.join(folder, n)
            small.save(path, optimize=True)
        written.append(path)
    return written


SECTIONS = [section_validation, section_ndf, section_g1, section_g2, section_bsdf, section_table4,
            section_tiled_boxes, section_objects_grooves, section_convergence, section_previews,
            section_measured]


# ----------------------------------------------------------------------------------------------
# HTML


def _fmt(x, digits=6):
    v = num(x)
    if v != v:
        return "-"
    return "%.*g" % (digits, v)


def collapse_rows(rows):
    """Rows as the CLI prints them: a group shown once, by its worst row. Returns
    [(row, members, outside)]."""
    blocks, index = [], {}
    for r in rows:
        g = r.get("group") or ""
        if not g:
            blocks.append([r])
            continue
        if g not in index:
            index[g] = len(blocks)
            blocks.append([])
        blocks[index[g]].append(r)
    out = []
    for members in blocks:
        def badness(r):  # as the CLI: a FAIL first, then |z| (deterministic: |d| / tolerance)
            z = num(r.get("z"))
            if z == z:
                b = abs(z) / num(r.get("z_threshold"), 1.0)
            elif r.get("z_infinite"):
                b = float("inf")
            elif r.get("kind") == "deterministic":
                b = abs(num(r.get("measured")) - num(r.get("model"))) / max(num(r.get("tolerance"), 0.0), 1e-300)
            else:
                b = -1
            return (r.get("verdict") == "FAIL", b)
        worst = max(members, key=badness)
        outside = sum(1 for r in members if r.get("verdict") in ("FAIL", "deviates (finding)"))
        out.append((worst, len(members), outside))
    return out


def summary_table_html(rows):
    """One line per (entry, quantity vs model): how many rows, how many outside, the largest
    |relative deviation| and |z| -- the findings at a glance."""
    order, acc = [], {}
    for r in rows:
        key = (r.get("entry", ""), "%s vs %s" % (r.get("quantity"), r.get("model_name")), r.get("kind", ""))
        if key not in acc:
            order.append(key)
            acc[key] = {"n": 0, "out": 0, "rel": 0.0, "z": 0.0, "fail": 0}
        a = acc[key]
        a["n"] += 1
        a["out"] += r.get("verdict") in ("FAIL", "deviates (finding)")
        a["fail"] += r.get("verdict") == "FAIL"
        rel, z = num(r.get("rel_dev")), num(r.get("z"))
        if rel == rel:
            a["rel"] = max(a["rel"], abs(rel))
        if z == z:
            a["z"] = max(a["z"], abs(z))
        elif r.get("z_infinite"):
            a["z"] = float("inf")
    out = ['<table class="validation"><thead><tr><th>entry</th><th>quantity vs model</th><th>kind</th>'
           '<th>rows</th><th>outside the threshold</th><th>max |rel. dev.|</th><th>max |z|</th></tr></thead><tbody>']
    for key in order:
        a = acc[key]
        if a["fail"]:
            cls = "v-FAIL"
        elif a["out"]:
            cls = "v-deviates"
        else:
            cls = "v-pass" if key[2] in ("identity", "deterministic") else "v-agrees"
        out.append('<tr><td>%s</td><td>%s</td><td>%s</td><td>%d</td><td class="%s">%d%s</td><td>%.3g%%</td>'
                   '<td>%s</td></tr>' % (html.escape(key[0]), html.escape(key[1]), html.escape(key[2]), a["n"], cls,
                                          a["out"], " FAIL" if a["fail"] else "", 100 * a["rel"],
                                          "-" if a["z"] == 0 and key[2] in ("deterministic", "info") else "%.3g" % a["z"]))
    out.append("</tbody></table>")
    return "\n".join(out)


def validation_table_html(v):
    summ = v.get("summary", {})
    parts = ['<p class="summary">%d rows: <b class="v-pass">%d pass</b>, <b class="v-FAIL">%d FAIL</b>, '
             '<b class="v-agrees">%d agree</b>, <b class="v-deviates">%d deviate (finding)</b>, %d measured only. '
             '|z| threshold %.2f (Sidak over %d z-tests, family-wise significance %g; rows whose error '
             'is the spread of K surfaces use the Student t quantile with K - 1 degrees of freedom at the '
             'same rate, column |z| max).</p>'
             % (summ.get("rows", 0), summ.get("pass", 0), summ.get("fail", 0), summ.get("agrees", 0),
                summ.get("deviates", 0), summ.get("measured", 0), num(v.get("z_threshold")),
                int(num(v.get("comparisons"), 0)), num(v.get("significance")))]
    parts.append(summary_table_html(v.get("rows", [])))
    parts.append("<p>All rows (groups of per-bin rows shown by their worst row):</p>")
    parts.append('<table class="validation"><thead><tr><th>quantity</th><th>condition</th><th>measured &plusmn; stderr'
                 '</th><th>model</th><th>z</th><th>|z| max</th><th>rel. dev.</th><th>verdict</th><th>kind</th>'
                 '<th>source</th>'
                 '</tr></thead><tbody>')
    for r, n, outside in collapse_rows(v.get("rows", [])):
        cond = html.escape(r.get("condition", ""))
        if n > 1:
            cond += ' <span class="group">[worst of %d, %d outside]</span>' % (n, outside)
        z = "inf" if r.get("z_infinite") else _fmt(r.get("z"), 3)
        if r.get("kind") == "deterministic":
            z = "|d| = %s (tol %s)" % (_fmt(abs(num(r.get("measured")) - num(r.get("model"))), 2), _fmt(r.get("tolerance"), 2))
        rel = num(r.get("rel_dev"))
        measured = _fmt(r.get("measured")) + ("" if r.get("stderr") is None else " &plusmn; " + _fmt(r.get("stderr"), 2))
        verdict = r.get("verdict", "")
        vclass = "v-" + verdict.split(" ")[0]
        thr = "-" if r.get("z_threshold") is None else _fmt(r.get("z_threshold"), 3) + (
            "" if r.get("t_dof") is None else " (t, %d dof)" % int(num(r.get("t_dof"))))
        parts.append("<tr><td>%s vs %s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td>"
                     '<td class="%s">%s</td><td>%s</td><td>%s</td></tr>'
                     % (html.escape(r.get("quantity", "")), html.escape(r.get("model_name", "")), cond, measured,
                        _fmt(r.get("model")), z, thr, "-" if rel != rel else "%.3f%%" % (100 * rel), vclass,
                        html.escape(verdict), html.escape(r.get("kind", "")), html.escape(r.get("reference", ""))))
    parts.append("</tbody></table>")
    return "\n".join(parts)


CSS = """
body { font-family: sans-serif; max-width: 1200px; margin: 2em auto; color: #222; }
h1 { font-size: 1.6em; } h2 { border-bottom: 1px solid #ccc; padding-bottom: .2em; margin-top: 2em; }
figure { margin: 1.5em 0; } figure img { max-width: 100%; border: 1px solid #eee; }
figcaption { font-size: .9em; color: #444; }
table { border-collapse: collapse; font-size: .78em; }
td, th { border: 1px solid #ddd; padding: 2px 6px; text-align: left; vertical-align: top; }
th { background: #f4f4f4; }
.v-pass { color: #2a9d4b; } .v-FAIL { color: #d62728; font-weight: bold; } .v-agrees { color: #1f77b4; }
.v-deviates { color: #ff7f0e; } .v-measured { color: #777; } .group { color: #777; }
.skipped { color: #777; font-style: italic; } code { background: #f4f4f4; padding: 0 3px; }
"""


def write_html(ctx, sections, wall_seconds):
    v = ctx.validation or {}
    esc = html.escape
    out = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
           "<title>microsim validation report</title><style>%s</style></head><body>" % CSS,
           "<h1>microsim validation report</h1>",
           "<p>microsim %s, %s threads, profile <code>%s</code>, suite <code>%s</code>; built in %.0f s on %s. "
           "Data: <a href=\"data/\">data/</a> (validation record <a href=\"data/validation.json\">validation.json</a>, "
           "table <a href=\"data/validation.txt\">validation.txt</a>).</p>"
           % (esc(str(v.get("microsim_version", "?"))), esc(str(v.get("threads", "?"))), esc(ctx.profile_name),
              esc(ctx.profile["suite"]), wall_seconds, time.strftime("%Y-%m-%d %H:%M"))]
    out.append("<ul>")
    for s in sections:
        state = (' <span class="v-FAIL">(failed)</span>' if s.failed else
                 ' <span class="skipped">(skipped)</span>' if s.skipped else "")
        out.append('<li><a href="#%s">%s</a>%s</li>' % (s.key, esc(s.title), state))
    out.append("</ul>")
    for s in sections:
        out.append('<h2 id="%s">%s</h2>' % (s.key, esc(s.title)))
        if s.intro:
            out.append("<p>%s</p>" % esc(s.intro).replace("`", ""))
        if s.failed:
            out.append('<p class="v-FAIL">This section failed: %s</p>' % esc(s.failed))
            continue
        if s.skipped:
            out.append('<p class="skipped">Skipped: %s</p>' % esc(s.skipped))
            continue
        for path, caption in s.figures:
            out.append('<figure><img src="%s" alt="%s"><figcaption>%s</figcaption></figure>'
                       % (esc(path), esc(os.path.basename(path)), esc(caption)))
        for n in s.notes:
            out.append('<p class="skipped">%s</p>' % esc(n))
        if s.html:
            out.append(s.html)
    out.append("<h2 id=\"commands\">Commands run</h2><table><tr><th>command</th><th>seconds</th><th>exit</th></tr>")
    for cmd, dt, rc in ctx.log:
        out.append("<tr><td><code>%s</code></td><td>%.1f</td><td>%d</td></tr>" % (esc(cmd), dt, rc))
    out.append("</table></body></html>")
    path = os.path.join(ctx.out, "index.html")
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write("\n".join(out))
    os.replace(tmp, path)
    return path


def build(ctx):
    """Runs every section; returns (sections, wall seconds)."""
    t0 = time.time()
    sections = []
    for fn in SECTIONS:
        t = time.time()
        key = fn.__name__.replace("section_", "")
        try:
            s = fn(ctx)
        except RuntimeError as e:
            if fn is section_validation:
                raise  # nothing else can run without the validation record
            s = Section(key, key.replace("_", " "))
            s.failed = str(e)
        if ctx.verbose or s.failed:
            state = ("FAILED: " + s.failed if s.failed else "skipped: " + s.skipped if s.skipped
                     else "%d figure(s)" % len(s.figures))
            print("%-12s %s (%.1f s)" % (s.key, state, time.time() - t), flush=True)
        sections.append(s)
    wall = time.time() - t0
    with open(os.path.join(ctx.data_dir, "report.json"), "w") as f:
        json.dump({"profile": ctx.profile_name, "wall_seconds": wall,
                   "sections": [{"key": s.key, "figures": [p for p, _ in s.figures], "skipped": s.skipped,
                                 "failed": s.failed, "notes": s.notes} for s in sections],
                   "commands": [{"command": c, "seconds": d, "exit": r} for c, d, r in ctx.log]}, f, indent=1)
    return sections, wall
