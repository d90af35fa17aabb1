#!/usr/bin/python3
"""Unit tests of the report's plotting and reading code (CTest: analysis_plots).

The G2, BSDF, Table 4 and tiled-box figures read records of measure g2, measure bsdf and
generate tiled-boxes. These tests feed the plot functions records with the documented field names and *synthetic* values (smooth made-up curves,
never shown in a report) to check that the figures are drawn, and that a record lacking the
fields gives NoData instead of a crash.
"""
import math
import os
import sys
import tempfile
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from msreport import models, plots, report  # noqa: E402


def png_ok(path):
    with open(path, "rb") as f:
        return f.read(8) == b"\x89PNG\r\n\x1a\n"


class Models(unittest.TestCase):
    def test_smith_g1_limits(self):
        # Normal incidence: no masking; Beckmann Lambda(a) -> 0 for large a.
        self.assertAlmostEqual(float(models.smith_g1("beckmann", 0.5, 0.5, 0.0)), 1.0)
        self.assertLess(float(models.smith_g1("beckmann", 0.5, 0.5, math.radians(85))), 0.5)
        # GGX Lambda at a = 1: (-1 + sqrt 2) / 2.
        self.assertAlmostEqual(float(models.ggx_lambda(1.0)), (math.sqrt(2) - 1) / 2, places=12)
        # Beckmann Lambda at a = 1: (erf(1) - 1)/2 + exp(-1)/(2 sqrt(pi)).
        expect = (math.erf(1) - 1) / 2 + math.exp(-1) / (2 * math.sqrt(math.pi))
        self.assertAlmostEqual(float(models.beckmann_lambda(1.0)), expect, places=12)

    def test_d_normalization(self):
        # [GeomBSDF24, eq. 1c]: integral of D cos over the hemisphere is 1 (midpoint rule in theta).
        n = 200000
        h = math.pi / 2 / n
        t = (np.arange(n) + 0.5) * h
        for d in (models.beckmann_d, models.ggx_d):
            total = float((d(0.4, t) * np.cos(t) * np.sin(t)).sum() * 2 * math.pi * h)
            self.assertAlmostEqual(total, 1.0, places=4)


class Figures(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="msreport_test_")

    def path(self, name):
        return os.path.join(self.tmp, name)

    def test_g2_curves_from_documented_fields(self):
        rows = []
        for to in (30, 60):
            for phi_i in (0, 180):
                for ti in range(0, 81, 10):
                    g = math.cos(math.radians(ti)) ** 0.1  # synthetic
                    rows.append({"theta_o_deg": to, "phi_o_deg": 0, "theta_i_deg": ti, "phi_i_deg": phi_i,
                                 "g2": g, "g2_stderr": 0.01, "smith_separable": g * 0.98,
                                 "smith_height_correlated": g * 0.99,
                                 "smith_height_direction_correlated": g * 0.995, "vcavity": g * 0.97})
        p = plots.g2_curves(self.path("g2.png"), {"rows": rows}, "synthetic")
        self.assertTrue(png_ok(p))
        with self.assertRaises(plots.NoData):
            plots.g2_curves(self.path("g2b.png"), {"rows": [{"theta_deg": 10, "g1": 1}]})

    def bsdf_record(self):
        in_plane = []
        for t in range(-85, 86, 5):
            f = math.exp(-((t - 60) / 15.0) ** 2)  # synthetic lobe
            in_plane.append({"theta_o_deg": t, "f_order_1": f, "f_order_1_stderr": 0.01 * f + 1e-4,
                             "f_total": 1.1 * f + 1e-3, "f_total_stderr": 0.01, "smith_single": 0.95 * f,
                             "vcavity_single": 0.9 * f, "smith_multiple": 1.08 * f + 1e-3})
        orders = {"order_1": 0.9, "order_2": 0.08, "order_3": 0.015, "order_4plus": 0.005, "total": 1.0}
        return {"albedo": {"reflected": orders, "transmitted": {k: 0.0 for k in orders}},
                "reflected_stderr": {k: 4e-4 for k in orders}, "transmitted_stderr": {k: 0.0 for k in orders},
                "in_plane": in_plane}

    def test_bsdf_figures_from_documented_fields(self):
        rec = self.bsdf_record()
        self.assertTrue(png_ok(plots.bsdf_albedo(self.path("albedo.png"), rec, "synthetic")))
        self.assertTrue(png_ok(plots.bsdf_lobes(self.path("lobe.png"), rec, "synthetic")))
        self.assertTrue(png_ok(plots.table4(self.path("t4.png"), [(0.1, rec), (0.4, rec), (1.3, rec)])))
        with self.assertRaises(plots.NoData):
            plots.bsdf_lobes(self.path("x.png"), {"albedo": rec["albedo"]})
        with self.assertRaises(plots.NoData):
            plots.bsdf_albedo(self.path("y.png"), {"in_plane": rec["in_plane"]})

    def test_tiled_boxes_from_measure_g1_rows(self):
        pts = []
        for n in (1, 2, 4, 8):
            rows = [{"theta_deg": t, "visible_area_ratio": 1 + 0.5 * math.tan(math.radians(t)) / n,
                     "visible_area_ratio_stderr": 1e-3} for t in (30, 60, 80)]  # synthetic
            pts.append((n, {"rows": rows}))
        self.assertTrue(png_ok(plots.tiled_boxes(self.path("tiles.png"), pts)))
        with self.assertRaises(plots.NoData):
            plots.tiled_boxes(self.path("t2.png"), [(1, {"rows": []})])

    def test_object_and_groove_figures_from_documented_fields(self):
        orders = ["order_1", "order_2", "order_3", "order_4plus", "total"]

        def incidence(theta):  # synthetic values with the documented fields of measure bsdf
            a = {o: 0.25 for o in orders}
            a["total"] = 1 + 0.5 * math.tan(math.radians(theta))
            rows = [{"side": "reflected", "order": o, "albedo": 0.25, "albedo_stderr": 1e-3,
                     "vgroove_multiple": 0.25, "z_vgroove_multiple": 0.0, "vcavity_multiple": 0.24,
                     "smith_multiple": 0.2, "smith_multiple_stderr": 1e-3} for o in orders]
            plane = []
            for k in range(16):
                r = {"side": "reflected", "theta_o_deg": -84.375 + 11.25 * k}
                for sfx in ("", "_order_1", "_order_2"):
                    for name in ("vcavity_multiple", "vcavity_multiple_grooves", "smith_multiple"):
                        r[name + sfx] = 0.3
                        r[name + sfx + "_stderr"] = 0.01
                for o in ("order_1", "order_2", "total"):
                    r["f_" + o], r["f_%s_stderr" % o] = 0.3, 0.01
                r["vcavity_single"] = 0.3
                plane.append(r)
            return {"theta_i_deg": theta, "phi_i_deg": 0, "albedo": {"reflected": a},
                    "reflected_stderr": {o: 1e-3 for o in orders}, "rows": rows, "in_plane": plane,
                    "normalization": {"reflected_below_base_plane": 0.1},
                    "albedo_models": {"vcavity_multiple_grooves": {"reflected": a}}}
        rec = {"incidences": [incidence(t) for t in (0, 30, 60)]}
        self.assertTrue(png_ok(plots.box_albedo(self.path("box.png"), rec, 0.5)))
        self.assertTrue(png_ok(plots.tiled_boxes_albedo(self.path("tb.png"), [(1, rec), (2, rec)], 0.5)))
        self.assertTrue(png_ok(plots.vgroove_orders(self.path("vg.png"), [(45, rec), (70, rec)])))
        self.assertTrue(png_ok(plots.vcavity_albedo_orders(self.path("vca.png"), rec)))
        self.assertTrue(png_ok(plots.vcavity_lobes(self.path("vcl.png"), rec, [0, 30])))
        single = incidence(30)  # a one-incidence record is its own incidence
        self.assertTrue(png_ok(plots.box_albedo(self.path("box1.png"), single, 0.5)))
        with self.assertRaises(plots.NoData):
            plots.vcavity_lobes(self.path("x.png"), rec, [45])
        with self.assertRaises(plots.NoData):
            plots.box_albedo(self.path("y.png"), {"incidences": [{"theta_i_deg": 0}]}, 0.5)

    def test_validation_z_and_table(self):
        rows = [
            {"quantity": "g1", "model_name": "g1_raycast", "kind": "identity", "z": 0.5, "verdict": "pass",
             "measured": 0.9, "stderr": 0.01, "model": 0.895, "rel_dev": 0.005, "condition": "a", "group": ""},
            {"quantity": "g1_bin", "model_name": "vcavity", "kind": "model", "z": 12.0, "verdict": "deviates (finding)",
             "measured": 0.9, "stderr": 0.01, "model": 0.78, "rel_dev": 0.15, "condition": "b1", "group": "g"},
            {"quantity": "g1_bin", "model_name": "vcavity", "kind": "model", "z": -1.0, "verdict": "agrees",
             "measured": 0.9, "stderr": 0.01, "model": 0.91, "rel_dev": -0.01, "condition": "b2", "group": "g"},
            {"quantity": "eq_1c", "model_name": "one", "kind": "deterministic", "z": None, "verdict": "pass",
             "measured": 1.0, "stderr": None, "model": 1.0, "rel_dev": 0.0, "tolerance": 1e-9, "condition": "c",
             "group": ""},
        ]
        v = {"rows": rows, "z_threshold": 3.5, "comparisons": 3, "significance": 0.01,
             "summary": {"rows": 4, "pass": 2, "fail": 0, "agrees": 1, "deviates": 1, "measured": 0}}
        self.assertTrue(png_ok(plots.validation_z(self.path("z.png"), v)))
        collapsed = report.collapse_rows(rows)
        self.assertEqual(len(collapsed), 3)
        worst, n, outside = collapsed[1]
        self.assertEqual((worst["condition"], n, outside), ("b1", 2, 1))
        html = report.validation_table_html(v)
        self.assertIn("worst of 2, 1 outside", html)
        self.assertIn("deviates (finding)", html)
        # An ensemble row with its own Student t threshold is shown with its degrees of freedom.
        rows.append({"quantity": "g1", "model_name": "smith_nominal", "kind": "model", "z": 5.0,
                     "verdict": "agrees", "measured": 0.9, "stderr": 0.01, "model": 0.85, "rel_dev": 0.06,
                     "condition": "d", "group": "", "t_dof": 3, "z_threshold": 60.3})
        self.assertTrue(png_ok(plots.validation_z(self.path("z2.png"), v)))
        self.assertIn("(t, 3 dof)", report.validation_table_html(v))

    def test_g2_hotspot_from_validate_measurements(self):
        hot = [{"theta_deg": t, "g2": 0.9, "g2_stderr": 0.002, "g1_independent": 0.901,
                "g1_independent_stderr": 0.002, "direction_correlated_numeric": 0.9005, "bins": []}
               for t in (30, 60, 80)]  # synthetic
        entry = {"name": "e", "measurements": {"g2": [{"label": "seed 1", "rows": [], "hotspot": hot}]}}
        self.assertTrue(png_ok(plots.g2_hotspot(self.path("h.png"), entry)))
        with self.assertRaises(plots.NoData):
            plots.g2_hotspot(self.path("h2.png"), {"name": "x", "measurements": {"g2": [{"rows": []}]}})


class FindingsFigures(unittest.TestCase):
    """make_report.py --figures DIR: the findings pages' figures, copied under their stable names."""

    def test_export_copies_the_named_figures_as_palette_pngs(self):
        from PIL import Image

        class Ctx:
            fig_dir = tempfile.mkdtemp(prefix="msreport_figs_")
        plots.tiled_boxes(os.path.join(Ctx.fig_dir, "a.png"), [
            (n, {"rows": [{"theta_deg": t, "visible_area_ratio": 1 + math.tan(math.radians(t)) / n,
                           "visible_area_ratio_stderr": 1e-3} for t in (30, 60, 80)]}) for n in (1, 2, 4)])  # synthetic
        out = tempfile.mkdtemp(prefix="msreport_export_")
        written = report.export_figures(Ctx, out, ["a.png"])
        self.assertEqual(written, [os.path.join(out, "a.png")])
        self.assertTrue(png_ok(written[0]))
        with Image.open(written[0]) as im, Image.open(os.path.join(Ctx.fig_dir, "a.png")) as src:
            self.assertEqual(im.mode, "P")
            self.assertEqual(im.size, src.size)
        # A figure this report did not draw is an error naming it, not a silent gap in the docs.
        with self.assertRaisesRegex(RuntimeError, "b.png"):
            report.export_figures(Ctx, out, ["a.png", "b.png"])


if __name__ == "__main__":
    unittest.main()
