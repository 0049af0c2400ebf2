#!/usr/bin/python3
"""Tests of the chart script's own logic (compare/report/charts.py and svgpdf.py), run by CTest as
`charts_py`. The sweep tests (report_chromium_test) check a real sweep's report in a browser; these
check what the script decides, on planted rows with known answers:

- every family keeps one colour and marker in every chart; each point has a tooltip and a link to
  its row;
- the bias chart draws each family's own curve (a VSM row without acne never hides the depth
  comparison's acne at the same bias);
- "where the time goes" is one bar per family and map size, the median over scenes;
- the findings name the dominant class, the best and the cheapest-within-2x configuration, and the
  first failing map size; a row that compared no pixel is never ranked;
- the Pareto fronts do not depend on the rows' order;
- every text in the SVG and the PDF is at least 8 pt; the PDF is well formed.
"""
import json
import os
import re
import shutil
import sys
import tempfile
import unittest
import zlib

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "compare", "report"))
import charts  # noqa: E402
import svgpdf  # noqa: E402

CLASSES = [{"key": "acne", "label": "acne", "error": True, "rate_metric": "acne_rate", "color": "#eb2323"},
           {"key": "leak", "label": "leak", "error": True, "rate_metric": "leak_rate", "color": "#1e78ff"},
           {"key": "aliasing", "label": "aliasing", "error": True, "rate_metric": "aliasing_rate",
            "color": "#ffd700"}]
FAMILIES = [{"key": "none / sphere", "label": "none / sphere", "color": "#1f77b4", "marker": "circle"},
            {"key": "vsm / sphere", "label": "vsm / sphere", "color": "#2ca02c", "marker": "triangle"}]


def row(scene, filt, size, slope, acne, leak, alias, ms, spread=0.0, pixels=1000):
    return {"scene": scene, "config": f"bias.slope={slope:g},filter={filt},map.size={size}", "light": "sun",
            "family": f"{filt} / sphere",
            "method": {"filter": filt, "fit": "sphere", "map.size": size, "bias.slope": slope},
            "metrics": {"error_rate": acne + leak + alias, "acne_rate": acne, "leak_rate": leak,
                        "aliasing_rate": alias, "pixels_compared": pixels, "m_median": 1.0, "m_p95": 2.0,
                        "m_max": 9.0},
            "timings": {"method_gpu_ms": ms, "method_gpu_ms_min": ms - spread, "method_gpu_ms_max": ms + spread,
                        "shadow_gpu_ms": ms * 0.75, "lookup_gpu_ms": ms * 0.25, "camera_gpu_ms": 2.0,
                        "visibility_gpu_ms": 1.0, "evidence_gpu_ms": 1.0, "readback_ms": 0.5, "compare_ms": 1.5,
                        "config_wall_ms": ms + 10.0}}


def planted_rows():
    """Scene "grazing": filter none has 46 % acne at slope 0, falling with the bias, leaks rising;
    vsm has no acne at any slope but costs 3x. Scene "flat": the same times, tiny errors."""
    rows = []
    for scene, scale in (("grazing", 1.0), ("flat", 0.01)):
        for size in (512, 1024):
            for slope, acne, leak in ((0, 0.46, 0.0), (1, 0.05, 0.001), (4, 0.0, 0.02)):
                rows.append(row(scene, "none", size, slope, acne * scale, leak * scale, 0.004 * 512 / size,
                                1.0 * size / 512))
                rows.append(row(scene, "vsm", size, slope, 0.0, leak * scale * 2, 0.003 * 512 / size,
                                3.0 * size / 512, spread=0.1))
    return rows


def write_results(folder, rows, extra=None):
    results = {"schema": "shadowlab.results/1", "rows": rows, "families": FAMILIES,
               "sweep": {"grid": [{"key": "bias.slope"}, {"key": "filter"}, {"key": "map.size"}],
                         "frontier": {"metric": "error_rate", "threshold": 0.01}},
               "frontiers": []}
    results.update(extra or {})
    with open(os.path.join(folder, "results.json"), "w", encoding="utf-8") as f:
        json.dump(results, f)
    with open(os.path.join(folder, "classes.json"), "w", encoding="utf-8") as f:
        json.dump(CLASSES, f)
    return os.path.join(folder, "results.json")


class ReportTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="charts_test_")

    def tearDown(self):
        shutil.rmtree(self.dir)

    def run_charts(self, rows, extra=None):
        path = write_results(self.dir, rows, extra)
        figures = os.path.join(self.dir, "figures")
        self.assertEqual(charts.main(["charts.py", path, figures]), 0)
        with open(os.path.join(figures, "charts.json"), encoding="utf-8") as f:
            return json.load(f), figures

    def svg(self, figures, chart):
        with open(os.path.join(figures, chart + ".svg"), encoding="utf-8") as f:
            return f.read()

    def test_families_keep_colour_and_marker_and_every_point_links_its_row(self):
        rows = planted_rows()
        manifest, figures = self.run_charts(rows)
        ids = [c["id"] for c in manifest["charts"]]
        self.assertEqual(ids, ["accuracy_vs_time", "class_mix", "bias_bias_slope", "error_by_size",
                               "time_breakdown", "m_footprint"])
        for chart in ("accuracy_vs_time", "bias_bias_slope", "error_by_size"):
            svg = self.svg(figures, chart)
            # Each point: <a href="#row-N"><shape ... fill=COLOUR ...><title>SCENE: CONFIG...</title>
            points = re.findall(r'<a href="#row-(\d+)"><(circle|polygon) [^>]*?fill="(#[0-9a-f]{6})"[^>]*>'
                                r'<title>([^<]*)</title>', svg)
            self.assertGreaterEqual(len(points), 8, chart)  # 2 scenes x 2 families x 2 sizes at least
            for index, shape, fill, title in points:
                r = rows[int(index)]
                family = next(f for f in FAMILIES if f["key"] == r["family"])
                self.assertIn(f"{r['scene']}: {r['config']}", title, chart)
                if fill != "#ffffff":  # hollow points (zeros, leaks) are white inside, outlined in the colour
                    self.assertEqual(fill, family["color"], (chart, r["config"]))
                self.assertEqual(shape, "circle" if family["marker"] == "circle" else "polygon", chart)
        # The families' table travels in the manifest, as results.json has it.
        self.assertEqual(manifest["families"], FAMILIES)

    def test_bias_curves_are_per_family_never_the_minimum_over_families(self):
        manifest, figures = self.run_charts(planted_rows())
        svg = self.svg(figures, "bias_bias_slope")
        # The depth comparison's acne at slope 0 is drawn (46 % in grazing at the chosen size), though
        # vsm has none there: the minimum over families would have shown 0.
        self.assertIn("grazing: bias.slope=0,filter=none,map.size=1024", svg)
        self.assertIn("acne_rate 46% at bias.slope = 0", svg)
        self.assertIn("acne_rate 0% at bias.slope = 0", svg)  # vsm's own point
        bias = next(c for c in manifest["charts"] if c["id"] == "bias_bias_slope")
        self.assertEqual(bias["map_size"], 1024, "the size with most bias values (a tie: the larger)")
        self.assertIn("at map.size = 1024", bias["caption"])

    def test_time_breakdown_is_per_family_and_size_median_over_scenes(self):
        rows = planted_rows()
        # A third scene twice as slow: the median over three scenes is the middle one.
        rows += [dict(r, scene="slow", timings={k: v * 2 for k, v in r["timings"].items()})
                 for r in planted_rows() if r["scene"] == "grazing"]
        groups = charts.time_groups(["grazing", "flat", "slow"],
                                    {s: [r for r in rows if r["scene"] == s] for s in ("grazing", "flat", "slow")},
                                    charts.Families({"families": FAMILIES}))
        self.assertEqual([(k, size) for k, size, _ in groups],
                         [("none / sphere", 512), ("none / sphere", 1024), ("vsm / sphere", 512),
                          ("vsm / sphere", 1024)])
        lookup = "lookup pass (lookup_gpu_ms)"
        self.assertAlmostEqual(groups[0][2][lookup], 0.25)  # median of 0.25, 0.25, 0.5
        self.assertAlmostEqual(groups[3][2][lookup], 6.0 * 0.25)
        manifest, figures = self.run_charts(rows)
        svg = self.svg(figures, "time_breakdown")
        self.assertEqual(svg.count("lookup pass (lookup_gpu_ms) "), 4, "one bar per family and size")

    def test_findings_name_class_best_cheapest_and_failures(self):
        rows = planted_rows()
        # A row that compared no pixel (error 0 of 0) must not be "best" nor on any front.
        empty = row("grazing", "none", 512, 8, 0.0, 0.0, 0.0, 0.1, pixels=0)
        rows.append(empty)
        manifest, _ = self.run_charts(rows)
        f = next(x for x in manifest["findings"] if x["scene"] == "grazing")
        text = {k: " ".join("".join(p["text"] for p in s) for s in f[k]) for k in ("wrong", "fixes", "costs", "fails")}
        self.assertTrue(text["wrong"].startswith("acne: 87% of the errors; "), text["wrong"])
        self.assertIn("worst: bias.slope=0,filter=none,map.size=512 (acne_rate 46%)", text["wrong"])
        # Best: vsm at slope 0, 1024 (0 acne, 0 leak, 0.15 % aliasing); cheapest within 2x of 0.15 %:
        # none at slope 4 is 2 % leak (no), so the best itself; the bias-1 none rows are 5 % acne.
        self.assertIn("Best: bias.slope=0,filter=vsm,map.size=1024 (0.15%, 6 ms", text["fixes"])
        self.assertNotIn("bias.slope=8", json.dumps(f), "the empty row is ranked nowhere")
        flat_text = {k: " ".join("".join(p["text"] for p in s) for s in x[k])
                     for x in manifest["findings"] if x["scene"] == "flat" for k in ("fixes", "costs")}
        # flat: 0.15 % best (vsm, 6 ms); within 2x (0.3 %) the cheapest is none at slope 4, 1024: 0.22 %, 2 ms.
        self.assertIn("Cheapest within 2x of its error: bias.slope=4,filter=none,map.size=1024 (0.22%, 2 ms).",
                      flat_text["fixes"])
        # Budgets: 1.5x the fastest (1 ms) and the median time (2.5 ms); the best costs 6x the fastest.
        self.assertEqual(flat_text["costs"], "Within 1.5 ms: bias.slope=4,filter=none,map.size=512 (0.42%). "
                         "Within 2.5 ms: bias.slope=4,filter=none,map.size=1024 (0.22%). "
                         "The best costs 6x the fastest (1 ms).")
        self.assertIn("error_rate above 1% at every map size: none / sphere", text["fails"])
        # Along the bias, per family: the depth comparison's acne and both families' leaks.
        self.assertIn("none / sphere: acne above 1% up to bias.slope 1 (5%); leaks above 1% from bias.slope 4 (2%).",
                      text["fails"])
        self.assertIn("vsm / sphere: leaks above 1% from bias.slope 4 (4%).", text["fails"])
        self.assertIn("Below 1% at every map size: vsm / sphere.", text["fails"])
        hrefs = [p["href"] for k in ("wrong", "fixes", "costs", "fails") for s in f[k] for p in s if "href" in p]
        self.assertIn("#triptych-grazing-best", hrefs)
        self.assertIn("#class_mix-grazing", hrefs)
        self.assertIn("#accuracy_vs_time-grazing", hrefs)
        fronts = next(c for c in manifest["charts"] if c["id"] == "accuracy_vs_time")["fronts"]
        self.assertNotIn(len(rows) - 1, fronts["grazing"])
        flat = next(x for x in manifest["findings"] if x["scene"] == "flat")
        self.assertIn("No family's error_rate exceeds 1% at any map size.",
                      " ".join("".join(p["text"] for p in s) for s in flat["fails"]))
        # At a glance: one short sentence per question, the same answers.
        glance = {k: "".join(p["text"] for p in f["glance"][k]) for k in ("wrong", "fixes", "costs", "fails")}
        self.assertEqual(glance["wrong"], "acne 87%")
        self.assertEqual(glance["fixes"], "bias.slope=0,filter=vsm,map.size=1024: 0.15%")
        self.assertEqual(glance["costs"], "3 ms: bias.slope=0,filter=vsm,map.size=512 (0.3%)")
        self.assertEqual(glance["fails"], "none / sphere at every map size")
        flat_glance = {k: "".join(p["text"] for p in flat["glance"][k]) for k in ("costs", "fails")}
        self.assertEqual(flat_glance["costs"], "2 ms: bias.slope=4,filter=none,map.size=1024 (0.22%)")
        self.assertEqual(flat_glance["fails"], "no family above 1%")

    def test_light_size_chart_draws_each_family_against_the_swept_light_size(self):
        rows = planted_rows()
        self.assertIn("light_size", [k["id"] for k in self.run_charts(rows)[0]["skipped"]],
                      "no sized light swept: the chart is skipped with its reason")
        # Scene "soft": a fixed kernel's penumbra error grows with the light; pcss's stays low.
        for radius, pcf_mae, pcss_mae in ((0.1, 0.02, 0.03), (0.3, 0.08, 0.035), (0.6, 0.2, 0.04)):
            for filt, mae in (("none", pcf_mae), ("vsm", pcss_mae)):
                r = row("soft", filt, 1024, 2, 0.0, 0.0, 0.01, 2.0)
                r["config"] = f"filter={filt},scene:/lights/0/radius={radius:g}"
                r["metrics"]["penumbra_mae"] = mae
                rows.append(r)
        manifest, figures = self.run_charts(rows)
        chart = next(c for c in manifest["charts"] if c["id"] == "light_size")
        self.assertEqual(chart["panels"], {"soft": "light_size-soft"}, "only the scene whose light is swept")
        svg = self.svg(figures, "light_size")
        self.assertIn("penumbra_mae", svg)
        self.assertIn("radius (/lights/0/radius)", svg)
        # One marker per family and size, each with its row's tooltip and link.
        self.assertEqual(svg.count("penumbra_mae 0.2"), 1)
        self.assertEqual(svg.count("penumbra_mae 0.04"), 1)
        self.assertEqual(sum(svg.count(f'href="#row-{i}"') for i in range(len(rows) - 6, len(rows))), 6)
        self.assertEqual(charts.light_size_of({"config": "filter=pcf,scene:/lights/0/radius=0.3"}),
                         ("/lights/0/radius", 0.3))
        self.assertEqual(charts.light_size_of({"config": "scene:/lights/1/angular_diameter_deg=2"}),
                         ("/lights/1/angular_diameter_deg", 2.0))
        self.assertIsNone(charts.light_size_of({"config": "scene:/lights/0/elevation_deg=30"}))

    def test_pareto_fronts_do_not_depend_on_row_order(self):
        rows = planted_rows()
        manifest, _ = self.run_charts(rows)
        fronts = next(c for c in manifest["charts"] if c["id"] == "accuracy_vs_time")["fronts"]
        reversed_rows = list(reversed(planted_rows()))
        manifest2, _ = self.run_charts(reversed_rows)
        fronts2 = next(c for c in manifest2["charts"] if c["id"] == "accuracy_vs_time")["fronts"]
        n = len(rows)
        for scene in fronts:
            self.assertEqual([rows[i]["config"] for i in fronts[scene]],
                             [reversed_rows[i]["config"] for i in fronts2[scene]], scene)
            self.assertEqual([n - 1 - i for i in fronts[scene]], fronts2[scene])

    def test_text_is_at_least_8pt_in_svg_and_pdf(self):
        manifest, figures = self.run_charts(planted_rows())
        for c in manifest["charts"]:
            svg = self.svg(figures, c["id"])
            self.assertTrue(svg.startswith('<svg xmlns="http://www.w3.org/2000/svg" width="540pt"'), c["id"])
            sizes = [float(v) for v in re.findall(r'font-size="([0-9.]+)"', svg)]
            self.assertTrue(sizes, c["id"])
            self.assertGreaterEqual(min(sizes), 8.0, c["id"])
            with open(os.path.join(figures, c["id"] + ".pdf"), "rb") as f:
                pdf = f.read()
            self.assertTrue(pdf.startswith(b"%PDF-1.4") and pdf.endswith(b"%%EOF\n"), c["id"])
            # The cross-reference table points at each object.
            xref = int(pdf[pdf.rindex(b"startxref") + 10:].split()[0])
            offsets = [int(line[:10]) for line in pdf[xref:].split(b"\n")[3:9]]
            for k, off in enumerate(offsets):
                self.assertTrue(pdf[off:].startswith(f"{k + 1} 0 obj".encode()), (c["id"], k))
            stream = pdf[pdf.index(b"stream\n") + 7:pdf.index(b"\nendstream")]
            ops = zlib.decompress(stream).decode("latin-1")
            pdf_sizes = [float(v) for v in re.findall(r"/F[12] ([0-9.]+) Tf", ops)]
            self.assertEqual(len(pdf_sizes), len(sizes), c["id"])
            self.assertGreaterEqual(min(pdf_sizes), 8.0, c["id"])
            # The page is the SVG's size: 540 pt wide.
            self.assertIn(f"/MediaBox [0 0 540 {svgpdf._f(c['height_pt'])}]".encode(), pdf)

    def test_canvas_refuses_text_under_8pt(self):
        c = svgpdf.Canvas(100, 100)
        with self.assertRaises(AssertionError):
            c.text(0, 10, "tiny", 6.5)



if __name__ == "__main__":
    unittest.main()
