#!/usr/bin/python3
"""Tests of the chart script's own logic (compare/report/charts.py), run by CTest as `charts_py`
with Debian's python3-matplotlib. The sweep tests (report_chromium_test) check that a real sweep's
charts exist and load; these check what the script decides:

- ViewLogLocator (lean_log_axes) draws the same ticks as matplotlib's LogLocator, byte for byte,
  from fewer tick objects: it only leaves out the decades around the view that the axis would drop.
- error_by_size writes "no <class> errors" into a panel whose points would all be zero, and says
  whether no configuration of the scene has the class or only the configurations shown lack it.
- time_breakdown names every bar (a text beside it, not an axis tick).
- PDF files hold one XObject per marker shape (share_pdf_markers).
"""
import io
import math
import os
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "compare", "report"))
import charts  # noqa: E402  (selects the Agg backend)
import matplotlib.pyplot as plt  # noqa: E402


def draw_log_panel(ylim, view, xlim=None):
    """PNG and SVG bytes of one log-log panel, and how many tick objects its y axis made."""
    fig, ax = plt.subplots(figsize=(3.2, 2.4))
    lo, hi = ylim if ylim else (3e-5, 2e-2)
    ax.plot([1, 2, 3, 4], [lo, math.sqrt(lo * hi), hi * 0.9, hi], marker="o")
    ax.set_yscale("log")
    ax.set_xscale("log", base=2)
    if ylim:
        ax.set_ylim(*ylim)
    if xlim:
        ax.set_xlim(*xlim)
    ax.grid(True, which="both", alpha=0.3)
    charts.lean_log_axes(fig, view_ticks=view)
    fig.tight_layout()
    files = {}
    for ext, kwargs in (("png", {"dpi": 80}), ("svg", {"metadata": {"Date": None}})):
        buf = io.BytesIO()
        fig.savefig(buf, format=ext, **kwargs)
        files[ext] = buf.getvalue()
    ticks = len(ax.yaxis.majorTicks) + len(ax.yaxis.minorTicks)
    plt.close(fig)
    return files, ticks


class ViewLogLocatorTest(unittest.TestCase):
    def test_same_bytes_fewer_ticks(self):
        cases = [
            ((1e-3, 1e-1), None),  # limits on decades: ticks exactly at both ends of the view
            ((1.2e-6, 2.4e-6), None),  # under a decade: the minor ticks carry the labels
            ((1.5e-7, 4e-4), None),  # a few decades, minor grid lines
            ((1e-12, 1e3), None),  # 15 decades: no minor ticks, a stride of several decades
            (None, (0.9, 4.5)),  # autoscaled y
        ]
        for ylim, xlim in cases:
            with self.subTest(ylim=ylim):
                plain, plain_ticks = draw_log_panel(ylim, False, xlim)
                viewed, view_ticks = draw_log_panel(ylim, True, xlim)
                self.assertEqual(plain["png"], viewed["png"], "the PNG differs")
                self.assertEqual(plain["svg"], viewed["svg"], "the SVG differs")
                self.assertLessEqual(view_ticks, plain_ticks)
        # The case the locator is for: a few decades make several times fewer ticks.
        _, plain_ticks = draw_log_panel((1.5e-7, 4e-4), False)
        _, view_ticks = draw_log_panel((1.5e-7, 4e-4), True)
        self.assertLess(2 * view_ticks, plain_ticks, (view_ticks, plain_ticks))

    def test_decade_limits_keep_their_ticks(self):
        # LogLocator computes 10^-1 as 0.09999999999999999: the view's ends keep their ticks anyway.
        locator = charts.ViewLogLocator(base=10.0, subs=(1.0,), numticks=9)
        ticks = locator.tick_values(1e-3, 1e-1)
        self.assertEqual(len(ticks), 3, ticks)
        for got, want in zip(ticks, (1e-3, 1e-2, 1e-1)):
            self.assertAlmostEqual(got / want, 1.0, places=12)


class PdfMarkersTest(unittest.TestCase):
    def test_one_xobject_per_marker_shape(self):
        # Three lines of circles and one of squares: two marker XObjects, whatever the colours.
        fig, ax = plt.subplots(figsize=(3, 2))
        for k in range(3):
            ax.plot([1, 2, 3], [k, k + 1, k + 2], marker="o")
        ax.plot([1, 2, 3], [5, 5, 5], marker="s")
        buf = io.BytesIO()
        fig.savefig(buf, format="pdf", metadata={"CreationDate": None})
        plt.close(fig)
        pdf = buf.getvalue()
        self.assertEqual(pdf.count(b"/Subtype /Form"), 2, "one XObject per marker shape")
        self.assertTrue(pdf.startswith(b"%PDF-") and pdf.rstrip().endswith(b"%%EOF"))


def row(scene, slope, size, error, acne, leak):
    return {"scene": scene, "config": f"bias.slope={slope},map.size={size}",
            "method": {"filter": "none", "map.size": size, "bias.slope": slope},
            "metrics": {"error_rate": error, "acne_rate": acne, "leak_rate": leak}}


class ErrorBySizeTest(unittest.TestCase):
    def test_zero_panels_are_named(self):
        classes = [("error_rate", "all errors", None), ("acne_rate", "acne", "#d62728"),
                   ("leak_rate", "leak", "#1f77b4")]
        rows = {
            # "flat": no configuration leaks.
            "flat": [row("flat", s, n, e, e, 0.0) for s, e in ((0, 0.02), (1, 0.01)) for n in (256, 1024)],
            # "shown": only the worse slope leaks, and the panel shows each size's best slope (0).
            "shown": [row("shown", 0, n, 0.01, 0.01, 0.0) for n in (256, 1024)]
            + [row("shown", 1, n, 0.03, 0.02, 0.01) for n in (256, 1024)],
            # "old": rows of a build without leak_rate.
            "old": [row("old", s, n, 0.01, 0.01, None) for s in (0, 1) for n in (256, 1024)],
        }
        for r in rows["old"]:
            del r["metrics"]["leak_rate"]
        with tempfile.TemporaryDirectory() as out:
            files, caption = charts.chart_error_by_size(["flat", "shown", "old"], rows, ["map.size", "bias.slope"],
                                                        classes, out)
            with open(os.path.join(out, "error_by_size.svg"), encoding="utf-8") as f:
                svg = f.read()
        self.assertEqual(svg.count("<!-- no leak errors -->"), 2, "one panel of each measured scene")
        self.assertEqual(svg.count("<!-- in any configuration -->"), 1)
        self.assertEqual(svg.count("<!-- in the configurations shown -->"), 1)
        self.assertEqual(svg.count("<!-- no leak_rate -->"), 1, "the old scene's rows have no leak_rate")
        self.assertIn("written by an older build", caption)
        self.assertNotIn("<!-- no acne errors -->", svg)
        self.assertIn("no configuration of the panel's scene has the class", caption)
        self.assertIn("some other configuration of the scene has it", caption)
        self.assertNotIn("Hollow triangles", caption, "no zero is drawn as a point")
        self.assertEqual(sorted(files), ["pdf", "png", "svg"])


class TimeBreakdownTest(unittest.TestCase):
    def test_every_bar_is_named(self):
        configs = [f"bias.slope={s},map.size={n}" for s in (0, 1) for n in (256, 1024)]
        rows = [{"scene": "a", "config": c, "method": {}, "metrics": {},
                 "timings": {"method_gpu_ms": 10.0 + k, "shadow_gpu_ms": 4.0, "lookup_gpu_ms": 6.0 + k,
                             "evidence_gpu_ms": 2.0, "readback_ms": 1.0, "compare_ms": 1.0,
                             "config_wall_ms": 30.0 + k}}
                for k, c in enumerate(configs)]
        with tempfile.TemporaryDirectory() as out:
            files, _ = charts.chart_time_breakdown(["a"], {"a": rows}, out)
            with open(os.path.join(out, "time_breakdown.svg"), encoding="utf-8") as f:
                svg = f.read()
        for c in configs:
            self.assertEqual(svg.count(f"<!-- {c} -->"), 1, c)
        self.assertEqual(files["stages"][0], charts.TIME_STAGES[0][0])



class SweptValuesTest(unittest.TestCase):
    """A configuration's name leaves out a method key at its default (config_name.h): its value
    comes from the row's method, written as the name would write it."""

    def test_default_values_come_from_the_method(self):
        row = {"config": "map.size=256,scene:/camera/look_at=[4,10,6]",
               "method": {"map.size": 256, "bias.slope": 1.5, "bias.compare": 0.0005, "filter": "none",
                          "cascades.count": 4, "tsm.focus": 1.0, "bias.adaptive": False}}
        keys = ["map.size", "bias.slope", "bias.compare", "filter", "tsm.focus", "bias.adaptive",
                "scene:/camera/look_at", "scene:/lights/0/elevation_deg"]
        self.assertEqual(charts.swept_values(row, keys),
                         ("256", "1.5", "0.0005", "none", "1", "false", "[4,10,6]", ""))

    def test_commas_inside_brackets_do_not_split(self):
        self.assertEqual(charts.config_parts('a=[1,2],b={"x":1,"y":2},c="p,q",d=3'),
                         {"a": "[1,2]", "b": '{"x":1,"y":2}', "c": '"p,q"', "d": "3"})
        self.assertEqual(charts.config_parts("default"), {})


if __name__ == "__main__":
    unittest.main()
