#!/usr/bin/python3
"""Charts and findings of a shadowlab sweep: reads results.json, writes each chart as SVG (inlined in
report.html, a tooltip and a link to its row on every point) and PDF (for print) into a figures
folder, and figures/charts.json: the charts made, the ones skipped, and the findings (per scene:
what goes wrong, what fixes it, what it costs, what fails first) that the report puts first.

Usage: /usr/bin/python3 charts.py RESULTS_JSON FIGURES_DIR

The error classes (rate metric, label, colour) come from classes.json next to RESULTS_JSON, which
the sweep writes from the C++ class table; the method families (filter x fit, techniques: key,
label, colour, marker) from results.json's "families", which the sweep writes from
`methodFamily` (compare/study/src/sweep_report.cpp), each row naming its "family". Neither is
derived here, so a class or family added there is drawn without an edit.

Every chart draws each family in its one colour and marker. Where a chart has fewer axes than the
grid has keys, each point is the family's configuration with the lowest error among those sharing
the chart's coordinates (the caption names the keys), never the minimum over families.
A chart whose swept key is absent from the grid is skipped with a reason (not an error).
Drawing is plain Python (compare/report/svgpdf.py), no plotting library: the report for the main
job's rows takes a fraction of a second.
"""
import json
import math
import os
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from svgpdf import Canvas, MIN_FONT_PT, text_width as helvetica_width  # noqa: E402

BIAS_KEYS = [("bias.slope", "bias.slope (x max depth slope)"),
             ("bias.constant", "bias.constant (units of r)"),
             ("bias.compare", "bias.compare (normalized depth)"),
             ("bias.normal", "bias.normal (map texels)")]
FONT = 8.0  # every chart's text (ticks, labels, legends); titles FONT + 1
PAGE_WIDTH = 540.0  # pt: a 7.5 in text width; every figure is this wide, so it prints at its size
GREY = "#8a8a8a"


def text_width(s, size):
    """Room to leave for `s` at `size` pt: Helvetica's width (the PDF's font) plus 12 %, enough for
    the wider sans-serif fonts a browser may substitute in the SVG (DejaVu Sans)."""
    return helvetica_width(s, size) * 1.12
# A rate at or above which a configuration fails (the sweep's frontier threshold when it has one).
DEFAULT_FAIL_THRESHOLD = 0.01


# ---------------------------------------------------------------------------------------------
# Rows


def num(d, key):
    v = d.get(key) if isinstance(d, dict) else None
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return None
    return float(v) if math.isfinite(v) else None


def method_gpu_ms(row):
    """The method's time, what an engine pays (compare/TIMINGS.md): method_gpu_ms = shadow pass +
    lookup pass (with timing repetitions: their median); rows without it: shadow + lookup."""
    t = row.get("timings", {})
    m = num(t, "method_gpu_ms")
    if m is not None:
        return m
    # An outside renderer's row (adapters/README.md): the renderer's own time for its frame.
    r = num(t, "renderer_frame_ms")
    if r is not None:
        return r
    return (num(t, "shadow_gpu_ms") or 0.0) + (num(t, "lookup_gpu_ms") or 0.0)


def time_axis_name(rows):
    """What the time axis shows: method_gpu_ms, or renderer_frame_ms where every row is an outside
    renderer's."""
    outside = rows and all(num(r.get("timings", {}), "method_gpu_ms") is None and
                           num(r.get("timings", {}), "renderer_frame_ms") is not None for r in rows)
    return "renderer_frame_ms" if outside else "method_gpu_ms"


def method_spread(row):
    """(min, max) of the method's time over the row's timed repetitions, or None (one sample)."""
    t = row.get("timings", {})
    lo, hi = num(t, "method_gpu_ms_min"), num(t, "method_gpu_ms_max")
    return (lo, hi) if lo is not None and hi is not None else None


def compared_nothing(row):
    """A row whose frame compared no pixel (its rates are 0 of 0): never ranked or drawn as best."""
    metrics = row.get("metrics", {})
    return metrics.get("nothing_compared") is True or num(metrics, "pixels_compared") == 0


def rankable(row):
    return not compared_nothing(row) and num(row.get("metrics", {}), "error_rate") is not None


def method_value(row, key):
    return row.get("method", {}).get(key)


def pareto(points):
    """points: (time, error, payload); the front by increasing time, strictly decreasing error
    (the same rule as the report's table, compare/study/src/sweep_report.cpp paretoFront)."""
    front, best = [], math.inf
    for p in sorted(points, key=lambda p: (p[0], p[1])):
        if p[1] < best:
            front.append(p)
            best = p[1]
    return front


def pct(rate, digits=3):
    """A rate as a percentage with `digits` significant digits (0.0123 -> '1.23%')."""
    if rate is None:
        return "-"
    v = rate * 100.0
    if v == 0:
        return "0%"
    return f"{v:.{digits}g}%" if abs(v) >= 10 ** -(digits) else f"{v:.1e}%"


def ms(v):
    return "-" if v is None else f"{v:.3g} ms"


class Families:
    """results.json's family table: key -> (label, colour, marker), in the sweep's order."""

    def __init__(self, results):
        table = results.get("families") or []
        self.order = [f["key"] for f in table]
        self.info = {f["key"]: f for f in table}

    def of(self, row):
        key = row.get("family")
        if key not in self.info:  # rows of an older build: one unnamed family
            key = key or "configuration"
            if key not in self.info:
                self.info[key] = {"key": key, "label": key, "color": GREY, "marker": "circle"}
                self.order.append(key)
        return key

    def label(self, key):
        return self.info[key]["label"]

    def colour(self, key):
        return self.info[key]["color"]

    def shape(self, key):
        return self.info[key]["marker"]


def tooltip(row, extra=""):
    m = row.get("metrics", {})
    spread = method_spread(row)
    t = f"{row['scene']}: {row['config']}\nerror_rate {pct(num(m, 'error_rate'))}"
    for k in ("acne_rate", "leak_rate", "aliasing_rate"):
        if num(m, k):
            t += f", {k} {pct(num(m, k))}"
    t += f"\nmethod_gpu_ms {method_gpu_ms(row):.3g}"
    if spread:
        t += f" ({spread[0]:.3g}..{spread[1]:.3g})"
    return t + extra


def row_href(row):
    return f"#row-{row['_index']}"


# ---------------------------------------------------------------------------------------------
# Axes


def nice_linear_ticks(lo, hi, n=5):
    if hi <= lo:
        hi = lo + 1.0
    raw = (hi - lo) / n
    mag = 10 ** math.floor(math.log10(raw))
    step = next(s * mag for s in (1, 2, 2.5, 5, 10) if s * mag >= raw)
    start = math.ceil(lo / step - 1e-9) * step
    ticks = []
    v = start
    while v <= hi + step * 1e-9:
        ticks.append(round(v, 12))
        v += step
    return ticks


def log_ticks(lo, hi):
    """Ticks 1-2-5 per decade when the span is small, decades otherwise."""
    a, b = math.floor(math.log10(lo)), math.ceil(math.log10(hi))
    span = math.log10(hi) - math.log10(lo)
    subs = (1, 2, 5) if span <= 1.6 else (1, 3) if span <= 2.6 else (1,)
    stride = max(1, (b - a) // 6)
    ticks = [s * 10.0 ** e for e in range(a, b + 1, stride if subs == (1,) else 1) for s in subs]
    return [t for t in ticks if lo * (1 - 1e-9) <= t <= hi * (1 + 1e-9)]


def tick_text(v, percent=False):
    if percent:
        v *= 100.0
        s = f"{v:.3g}"
        if "e" in s:
            s = f"{v:.0e}"
        return s + "%"
    if abs(v) >= 1000 and v == int(v):
        return str(int(v))
    return f"{v:.3g}"


class Axes:
    """A panel's data area at (x, y, w, h) on a canvas, with linear, log or categorical axes."""

    def __init__(self, canvas, x, y, w, h, xlim, ylim, xlog=False, ylog=False, xcats=None):
        self.c, self.x, self.y, self.w, self.h = canvas, x, y, w, h
        self.xlim, self.ylim, self.xlog, self.ylog, self.xcats = xlim, ylim, xlog, ylog, xcats

    def _t(self, v, lim, log):
        lo, hi = lim
        if log:
            v, lo, hi = math.log10(v), math.log10(lo), math.log10(hi)
        return (v - lo) / (hi - lo) if hi != lo else 0.5

    def px(self, v):
        if self.xcats is not None:
            n = len(self.xcats)
            return self.x + self.w * (self.xcats.index(v) + 0.5) / n
        return self.x + self.w * self._t(v, self.xlim, self.xlog)

    def py(self, v):
        return self.y + self.h * (1.0 - self._t(v, self.ylim, self.ylog))

    def frame(self, title=None, xlabel=None, ylabel=None, yticks=None, xticks=None, ypercent=False,
              xtick_labels=None):
        c = self.c
        for t in yticks or []:
            yy = self.py(t)
            c.line([(self.x, yy), (self.x + self.w, yy)], "#e4e4e4", 0.5)
            c.text(self.x - 3, yy + FONT * 0.35, tick_text(t, ypercent), FONT, "end")
        if self.xcats is not None:
            for k, v in enumerate(self.xcats):
                xx = self.px(v)
                label = xtick_labels[k] if xtick_labels else str(v)
                c.line([(xx, self.y + self.h), (xx, self.y + self.h + 2.5)], "#000000", 0.5)
                c.text(xx, self.y + self.h + 3 + FONT, label, FONT, "middle")
        else:
            for t in xticks or []:
                xx = self.px(t)
                c.line([(xx, self.y), (xx, self.y + self.h)], "#eeeeee", 0.5)
                c.line([(xx, self.y + self.h), (xx, self.y + self.h + 2.5)], "#000000", 0.5)
                c.text(xx, self.y + self.h + 3 + FONT, tick_text(t), FONT, "middle")
        c.rect(self.x, self.y, self.w, self.h, stroke="#505050", width=0.6)
        if title:
            c.text(self.x, self.y - 4, title, FONT + 1, "start", bold=True)
        if xlabel:
            c.text(self.x + self.w / 2, self.y + self.h + 6 + 2 * FONT, xlabel, FONT, "middle")
        if ylabel:
            c.text(self.x - 30, self.y + self.h / 2, ylabel, FONT, "middle", rotate=90)


def panel_layout(n, cols, panel_h, top, left=44.0, right=10.0, gap_x=40.0, gap_y=52.0, width=PAGE_WIDTH):
    """[(x, y, w, h)] of n panels in rows of `cols`, and the figure's height."""
    cols = max(1, min(cols, n))
    pw = (width - left - right - gap_x * (cols - 1)) / cols
    boxes = []
    for i in range(n):
        r, k = divmod(i, cols)
        boxes.append((left + k * (pw + gap_x), top + r * (panel_h + gap_y), pw, panel_h))
    rows = int(math.ceil(n / cols))
    return boxes, top + rows * panel_h + (rows - 1) * gap_y + 34.0


def family_legend(c, fam, keys, y, x0=8.0, width=PAGE_WIDTH, extra=()):
    """One line (wrapped) of the families' markers and labels from y; returns the y below it.
    `extra`: (draw(x, y), label) pairs appended after the families."""
    x = x0
    items = [(lambda xx, yy, k=k: c.marker(xx + 4, yy - 3, fam.shape(k), fam.colour(k), 3.6), fam.label(k))
             for k in keys] + list(extra)
    for draw, label in items:
        w = 12 + text_width(label, FONT) + 12
        if x + w > width - 4 and x > x0:
            x = x0
            y += FONT + 6
        draw(x, y)
        c.text(x + 12, y, label, FONT)
        x += w
    return y + FONT + 6


def positive_floor(values, default=1e-5):
    pos = [v for v in values if v is not None and v > 0]
    return min(pos) / 2.0 if pos else default


# ---------------------------------------------------------------------------------------------
# Charts: each returns (canvas, caption, extra manifest fields) or (None, reason, None).


def chart_accuracy_vs_time(scenes, rows_by_scene, fam):
    used = [k for k in fam.order if any(fam.of(r) == k for s in scenes for r in rows_by_scene[s])]
    cols = 3 if len(scenes) > 2 else len(scenes)
    # The legend's height first (it wraps), then the panels under it.
    probe = Canvas(PAGE_WIDTH, 10)
    top = family_legend(probe, fam, used, 14, extra=[(lambda xx, yy: None, "1, 2, ...: Pareto front")]) + 16
    boxes, height = panel_layout(len(scenes), cols, 150.0, top)
    c = Canvas(PAGE_WIDTH, height)
    family_legend(c, fam, used, 14, extra=[
        (lambda xx, yy: c.line([(xx, yy - 3), (xx + 9, yy - 3)], "#000000", 1.2), "1, 2, ...: Pareto front")])
    panels = {}
    fronts = {}
    for (x, y, w, h), scene in zip(boxes, scenes):
        rows = [r for r in rows_by_scene[scene] if rankable(r)]
        pid = "accuracy_vs_time-" + scene
        panels[scene] = pid
        c.begin_group(pid)
        if not rows:
            Axes(c, x, y, w, h, (0, 1), (0, 1)).frame(title=scene)
            c.text(x + w / 2, y + h / 2, "no compared pixels", FONT, "middle", GREY)
            c.end_group()
            continue
        times = [method_gpu_ms(r) for r in rows]
        spreads = [method_spread(r) for r in rows]
        errs = [num(r["metrics"], "error_rate") for r in rows]
        floor = positive_floor(errs)
        tlo = min([t for t in times if t > 0] + [s[0] for s in spreads if s and s[0] > 0] or [0.01])
        thi = max(times + [s[1] for s in spreads if s] or [1.0])
        xlim = (tlo / 1.25, thi * 1.25)
        ylo, yhi = min(max(e, floor) for e in errs), max(max(e, floor) for e in errs)
        ylim = (ylo / 1.6, yhi * 1.6) if yhi > ylo else (ylo / 3, ylo * 3)
        ax = Axes(c, x, y, w, h, xlim, ylim, xlog=True, ylog=True)
        ax.frame(title=scene, xlabel=time_axis_name(rows) + " (ms)",
                 ylabel="error_rate", yticks=log_ticks(*ylim), xticks=log_ticks(*xlim), ypercent=True)
        # Spread first (under the points): the timed repetitions' min..max.
        for r, t, s, e in zip(rows, times, spreads, errs):
            if s:
                yy = ax.py(max(e, floor))
                c.line([(ax.px(max(s[0], xlim[0])), yy), (ax.px(min(s[1], xlim[1])), yy)], fam.colour(fam.of(r)), 0.8)
        front = pareto([(t, e, r) for t, e, r in zip(times, errs, rows)])
        fronts[scene] = [p[2]["_index"] for p in front]
        pts = [(ax.px(max(t, xlim[0])), ax.py(max(e, floor))) for t, e, _ in front]
        steps = []
        for k, (px, py) in enumerate(pts):
            steps.append((px, py))
            if k + 1 < len(pts):
                steps.append((pts[k + 1][0], py))
        c.line(steps, "#000000", 1.1)
        on_front = {id(p[2]): k + 1 for k, p in enumerate(front)}
        for r, t, e in sorted(zip(rows, times, errs), key=lambda p: id(p[0]) in on_front):
            k = fam.of(r)
            extra = f"\nPareto front #{on_front[id(r)]}" if id(r) in on_front else ""
            c.marker(ax.px(max(t, xlim[0])), ax.py(max(e, floor)), fam.shape(k), fam.colour(k),
                     3.4 if id(r) in on_front else 2.6, hollow=e <= 0, title=tooltip(r, extra), href=row_href(r))
        for n, (px, py) in enumerate(pts):
            c.text(px + 3, py - 4, str(n + 1), FONT, "start", "#000000", bold=True)
        c.end_group()
    caption = ("Accuracy against the method's time (method_gpu_ms: shadow pass + lookup pass, what an engine "
               "pays; log-log), one point per configuration in its family's colour and marker. The black steps are "
               "the Pareto front (no configuration is both faster and more accurate), numbered as in the report's "
               "table \"Best configurations per scene\". A horizontal bar through a point spans its timed "
               "repetitions (min..max; the point is their median). Hollow: an error_rate of 0, drawn at the "
               "panel's floor. Hover a point for its configuration; click it for its row.")
    return c, caption, {"panels": panels, "fronts": fronts}


def chart_bias(scenes, rows_by_scene, swept, fam, key, key_label):
    """acne_rate and leak_rate against one bias key, one pair of lines per family at fixed filter
    and fit, at one map size (the one with most bias values), never the minimum over families."""
    all_rows = [r for s in scenes for r in rows_by_scene[s] if rankable(r)]
    size = None
    if "map.size" in swept and key != "map.size":
        counts = {}
        for r in all_rows:
            counts.setdefault(method_value(r, "map.size"), set()).add((fam.of(r), str(method_value(r, key))))
        size = max(counts, key=lambda s: (len(counts[s]), s if isinstance(s, (int, float)) else -1))
    others = [k for k in swept if k not in (key, "map.size", "filter", "fit", "technique")]

    def curves(rows):
        """family -> sorted [(bias, row)]: per family and bias the row with the lowest acne + leak over
        `others` (a family here is one filter and fit, so this never mixes families)."""
        by = {}
        for r in rows:
            if size is not None and method_value(r, "map.size") != size:
                continue
            b = num(r.get("method", {}), key)
            if b is None:
                continue
            score = (num(r["metrics"], "acne_rate") or 0) + (num(r["metrics"], "leak_rate") or 0)
            cur = by.setdefault(fam.of(r), {}).get(b)
            if cur is None or score < cur[0]:
                by[fam.of(r)][b] = (score, r)
        return {k: sorted((b, sr[1]) for b, sr in v.items()) for k, v in by.items() if len(v) >= 2}

    per_scene = {s: curves([r for r in rows_by_scene[s] if rankable(r)]) for s in scenes}
    used = [k for k in fam.order if any(k in per_scene[s] for s in scenes)]
    if not used:
        return None, f"no family has two or more {key} values" + (f" at map.size={size}" if size else ""), None
    solid = lambda xx, yy: c.line([(xx - 2, yy - 3), (xx + 10, yy - 3)], "#303030", 1.2)  # noqa: E731
    dashed = lambda xx, yy: c.line([(xx - 2, yy - 3), (xx + 10, yy - 3)], "#303030", 1.2, dash=(3, 2))  # noqa: E731
    probe = Canvas(PAGE_WIDTH, 10)
    top = family_legend(probe, fam, used, 14, extra=[(lambda a, b: None, "acne_rate"),
                                                      (lambda a, b: None, "leak_rate")]) + 16
    boxes, height = panel_layout(len(scenes), 3 if len(scenes) > 2 else len(scenes), 140.0, top)
    c = Canvas(PAGE_WIDTH, height)
    family_legend(c, fam, used, 14, extra=[(solid, "acne_rate"), (dashed, "leak_rate")])
    values = sorted({b for s in scenes for cv in per_scene[s].values() for b, _ in cv})
    rates = [num(r["metrics"], m) for s in scenes for cv in per_scene[s].values() for _, r in cv
             for m in ("acne_rate", "leak_rate")]
    floor = max(positive_floor(rates, 1e-4), 1e-6)
    ylim = (floor / 1.5, max(max(v for v in rates if v is not None), floor * 10) * 1.5)
    panels = {}
    drew_zero = False
    for (x, y, w, h), scene in zip(boxes, scenes):
        pid = f"bias_{key.replace('.', '_')}-{scene}"
        panels[scene] = pid
        c.begin_group(pid)
        ax = Axes(c, x, y, w, h, None, ylim, ylog=True, xcats=values)
        ax.frame(title=scene, xlabel=key_label, ylabel="rate", yticks=log_ticks(*ylim), ypercent=True,
                 xtick_labels=[f"{v:g}" for v in values])
        for k in [k for k in fam.order if k in per_scene[scene]]:
            cv = per_scene[scene][k]
            for metric, dash in (("acne_rate", None), ("leak_rate", (3, 2))):
                pts = [(ax.px(b), ax.py(max(num(r["metrics"], metric) or 0.0, floor))) for b, r in cv]
                c.line(pts, fam.colour(k), 1.2, dash)
                for (b, r), (px, py) in zip(cv, pts):
                    v = num(r["metrics"], metric) or 0.0
                    drew_zero = drew_zero or v <= 0
                    c.marker(px, py, fam.shape(k), fam.colour(k), 2.8, hollow=(metric == "leak_rate" or v <= 0),
                             title=tooltip(r, f"\n{metric} {pct(v)} at {key} = {b:g}"), href=row_href(r))
        c.end_group()
    caption = (f"The bias trade-off for {key}: acne_rate (solid) and leak_rate (dashed) of each family (one filter and "
               f"fit, its colour and marker) against {key}"
               + (f", at map.size = {size}" if size is not None else "") + "; acne should fall and leaks rise as the "
               "bias grows. Leak points are hollow. Families swept at fewer than two values are not drawn.")
    if others:
        caption += (" At each point the family's configuration with the lowest acne_rate + leak_rate over "
                    + ", ".join(others) + " is shown.")
    if drew_zero:
        caption += f" A rate of 0 is drawn at the panel's floor ({pct(floor)})."
    return c, caption, {"panels": panels, "map_size": size}


def chart_error_by_size(scenes, rows_by_scene, swept, fam):
    if "map.size" not in swept:
        return None, "map.size is not in the grid (sweep it, e.g. --grid map.size=256,512,1024,2048)", None
    others = [k for k in swept if k not in ("map.size", "filter", "fit", "technique")]
    per_scene = {}
    for s in scenes:
        by = {}
        for r in rows_by_scene[s]:
            if not rankable(r):
                continue
            size = num(r.get("method", {}), "map.size")
            if size is None:
                continue
            e = num(r["metrics"], "error_rate")
            cur = by.setdefault(fam.of(r), {}).get(size)
            if cur is None or e < num(cur["metrics"], "error_rate"):
                by[fam.of(r)][size] = r
        per_scene[s] = {k: sorted(v.items()) for k, v in by.items()}
    sizes = sorted({sz for s in scenes for cv in per_scene[s].values() for sz, _ in cv})
    used = [k for k in fam.order if any(k in per_scene[s] for s in scenes)]
    probe = Canvas(PAGE_WIDTH, 10)
    top = family_legend(probe, fam, used, 14) + 16
    boxes, height = panel_layout(len(scenes), 3 if len(scenes) > 2 else len(scenes), 130.0, top)
    c = Canvas(PAGE_WIDTH, height)
    family_legend(c, fam, used, 14)
    panels = {}
    for (x, y, w, h), scene in zip(boxes, scenes):
        pid = "error_by_size-" + scene
        panels[scene] = pid
        c.begin_group(pid)
        errs = [num(r["metrics"], "error_rate") for cv in per_scene[scene].values() for _, r in cv]
        floor = positive_floor(errs)
        ys = [max(e, floor) for e in errs] or [floor]
        ylim = (min(ys) / 1.6, max(ys) * 1.6) if max(ys) > min(ys) else (min(ys) / 3, min(ys) * 3)
        ax = Axes(c, x, y, w, h, None, ylim, ylog=True, xcats=sizes)
        ax.frame(title=scene, xlabel="map.size (texels per side)", ylabel="error_rate", yticks=log_ticks(*ylim),
                 ypercent=True, xtick_labels=[f"{v:g}" for v in sizes])
        for k in [k for k in fam.order if k in per_scene[scene]]:
            cv = per_scene[scene][k]
            pts = [(ax.px(sz), ax.py(max(num(r["metrics"], "error_rate"), floor))) for sz, r in cv]
            c.line(pts, fam.colour(k), 1.1)
            for (sz, r), (px, py) in zip(cv, pts):
                c.marker(px, py, fam.shape(k), fam.colour(k), 2.8, hollow=num(r["metrics"], "error_rate") <= 0,
                         title=tooltip(r), href=row_href(r))
        c.end_group()
    caption = ("error_rate against the shadow map's size, one line per family (its colour and marker); log y. "
               + ("At each size the family's configuration with the lowest error_rate over " + ", ".join(others)
                  + " is shown. " if others else "") + "Hollow: an error_rate of 0, drawn at the panel's floor.")
    return c, caption, {"panels": panels}


LIGHT_SIZE_KEYS = ("radius", "angular_diameter_deg")  # a sized light's keys (scenes/FORMAT.md)


def light_size_of(row):
    """(key, value) of the sized light's scene: value in the row's configuration name, or None."""
    for part in row.get("config", "").split(","):
        if part.startswith("scene:/lights/") and "=" in part:
            pointer, value = part.split("=", 1)
            if pointer.rsplit("/", 1)[-1] in LIGHT_SIZE_KEYS:
                try:
                    return pointer[len("scene:"):], float(value)
                except ValueError:
                    return None
    return None


def chart_light_size(scenes, rows_by_scene, fam):
    """Per scene whose sized light is swept: the visibility error against the light's size, one line
    per family (at each size the family's configuration with the lowest error)."""
    per_scene, pointers = {}, {}
    for s in scenes:
        by = {}
        for r in rows_by_scene[s]:
            size = light_size_of(r)
            if size is None or not rankable(r):
                continue
            pointers[s] = size[0]
            metric = "penumbra_mae" if num(r["metrics"], "penumbra_mae") is not None else "error_rate"
            e = num(r["metrics"], metric)
            if e is None:
                continue
            cur = by.setdefault(fam.of(r), {}).get(size[1])
            if cur is None or e < cur[0]:
                by[fam.of(r)][size[1]] = (e, metric, r)
        if by:
            per_scene[s] = {k: sorted(v.items()) for k, v in by.items()}
    if not per_scene:
        return None, ("no sized light is swept (sweep one, e.g. a grid with \"scenes\": [\"soft_post\"] and "
                      "\"scene:/lights/0/radius\": [0.1, 0.3, 0.6])"), None
    shown = list(per_scene)
    used = [k for k in fam.order if any(k in per_scene[s] for s in shown)]
    probe = Canvas(PAGE_WIDTH, 10)
    top = family_legend(probe, fam, used, 14) + 16
    boxes, height = panel_layout(len(shown), min(3, len(shown)), 150.0, top)
    c = Canvas(PAGE_WIDTH, height)
    family_legend(c, fam, used, 14)
    panels, metrics = {}, set()
    for (x, y, w, h), scene in zip(boxes, shown):
        pid = "light_size-" + scene
        panels[scene] = pid
        c.begin_group(pid)
        curves = per_scene[scene]
        sizes = sorted({v for cv in curves.values() for v, _ in cv})
        errs = [e for cv in curves.values() for _, (e, _, _) in cv]
        metric = next(m for cv in curves.values() for _, (_, m, _) in cv)
        metrics.add(metric)
        hi = max(errs) if errs and max(errs) > 0 else 1e-3
        ax = Axes(c, x, y, w, h, (sizes[0], sizes[-1]) if len(sizes) > 1 else (sizes[0] - 1, sizes[0] + 1),
                  (0.0, hi * 1.15))
        ax.frame(title=scene, xlabel=pointers[scene].rsplit("/", 1)[-1] + " (" + pointers[scene] + ")",
                 ylabel=metric, yticks=nice_linear_ticks(0.0, hi * 1.15),
                 xticks=nice_linear_ticks(sizes[0], sizes[-1]) if len(sizes) > 1 else [sizes[0]])
        for k in [k for k in fam.order if k in curves]:
            cv = curves[k]
            pts = [(ax.px(v), ax.py(e)) for v, (e, _, _) in cv]
            c.line(pts, fam.colour(k), 1.1)
            for (v, (e, m, r)), (px, py) in zip(cv, pts):
                c.marker(px, py, fam.shape(k), fam.colour(k), 2.8, title=tooltip(r, f"\n{m} {e:.3g}"),
                         href=row_href(r))
        c.end_group()
    caption = ("The visibility error against the sized light's size, one line per family (its colour and marker): "
               + " / ".join(sorted(metrics)) + " (compare/METRICS.md), at each size the family's configuration with "
               "the lowest. A fixed filter kernel keeps one penumbra width whatever the light; a contact-hardening "
               "filter (pcss, dpcf) follows the light's size.")
    return c, caption, {"panels": panels}


def chart_class_mix(scenes, rows_by_scene, classes):
    """Per scene, the error classes' shares of all its configurations' errors: which class dominates."""
    bars = []
    for s in scenes:
        rows = [r for r in rows_by_scene[s] if rankable(r)]
        totals = [sum(num(r["metrics"], m) or 0.0 for r in rows) for m, _, _ in classes]
        errors = sum(num(r["metrics"], "error_rate") or 0.0 for r in rows)
        bars.append((s, totals, errors / len(rows) if rows else None))
    top = 14 + FONT + 10
    label_w = max(text_width(s, FONT) for s in scenes) + 10
    bar_h, gap = 13.0, 6.0
    height = top + len(scenes) * (bar_h + gap) + 40
    c = Canvas(PAGE_WIDTH, height)
    x = 8.0
    for metric, label, colour in classes:
        c.rect(x, 14 - 7.5, 8, 8, fill=colour)
        c.text(x + 11, 14, label, FONT)
        x += 11 + text_width(label, FONT) + 12
    x0, x1 = 8 + label_w, PAGE_WIDTH - 70
    panels = {}
    for i, (s, totals, mean_error) in enumerate(bars):
        y = top + i * (bar_h + gap)
        pid = "class_mix-" + s
        panels[s] = pid
        c.begin_group(pid)
        c.text(x0 - 4, y + bar_h * 0.72, s, FONT, "end")
        whole = sum(totals)
        left = x0
        for (metric, label, colour), t in zip(classes, totals):
            if whole <= 0 or t <= 0:
                continue
            w = (x1 - x0) * t / whole
            c.rect(left, y, w, bar_h, fill=colour, title=f"{s}: {label} {t / whole:.1%} of the errors "
                   f"(mean {metric} {pct(t / max(1, len(rows_by_scene[s])))})")
            if w > text_width("99%", FONT) + 4:
                c.text(left + w / 2, y + bar_h * 0.72, f"{t / whole:.0%}", FONT, "middle",
                       "#ffffff" if sum(_rgb_sum(colour)) < 1.6 else "#000000")
            left += w
        if whole <= 0:
            c.text(x0 + 2, y + bar_h * 0.72, "no errors in any configuration", FONT, "start", GREY)
        c.text(x1 + 4, y + bar_h * 0.72, pct(mean_error), FONT)
        c.end_group()
    c.text(x1 + 4, top - 6, "mean error", FONT)
    caption = ("Which error class dominates each scene: each class's share of the errors summed over the scene's "
               "configurations (classes in their errors.png colours); on the right the mean error_rate over them.")
    return c, caption, {"panels": panels}


def _rgb_sum(colour):
    cc = colour.lstrip("#")
    return [int(cc[i:i + 2], 16) / 255.0 for i in (0, 2, 4)]


# "Where the time goes": the stages of a configuration, stacked in this order, the method's first.
# (label, colour, value(timings) or None when the row lacks it).
def _stage(key):
    return lambda t: num(t, key)


def _evidence_resolve(t):
    evidence = num(t, "evidence_gpu_ms")
    if evidence is not None:
        return evidence
    camera, visibility = num(t, "camera_gpu_ms"), num(t, "visibility_gpu_ms")  # rows of earlier builds
    if camera is None:
        return None
    return max(camera - (visibility or 0.0), 0.0)


def _shadow_maps(t):
    shadow, moments = num(t, "shadow_gpu_ms"), num(t, "moments_gpu_ms")
    if shadow is None:
        return None
    return max(shadow - (moments or 0.0), 0.0)


TIME_STAGES = [
    ("shadow pass: map layers (shadow_gpu_ms - moments_gpu_ms)", "#1f77b4", _shadow_maps, True),
    ("shadow pass: moments (moments_gpu_ms)", "#2ca02c", _stage("moments_gpu_ms"), True),
    ("lookup pass (lookup_gpu_ms)", "#17becf", _stage("lookup_gpu_ms"), True),
    ("visibility buffer (visibility_gpu_ms)", "#bcbd22", _stage("visibility_gpu_ms"), False),
    ("evidence resolve (evidence_gpu_ms)", "#ff7f0e", _evidence_resolve, False),
    ("readback (readback_ms)", "#d62728", _stage("readback_ms"), False),
    ("compare (compare_ms)", "#9467bd", _stage("compare_ms"), False),
]
OTHER_STAGE = ("other wall time (config_wall_ms less the stages)", "#b0b0b0")


def time_stages(row):
    """[(label, colour, ms)] of one row: TIME_STAGES it has, then the rest of config_wall_ms."""
    t = row.get("timings", {})
    out = [(label, colour, v(t)) for label, colour, v, _ in TIME_STAGES]
    out = [(label, colour, v) for label, colour, v in out if v is not None]
    wall = num(t, "config_wall_ms")
    if wall is not None:
        out.append((OTHER_STAGE[0], OTHER_STAGE[1], max(wall - sum(v for _, _, v in out), 0.0)))
    return out


def time_groups(scenes, rows_by_scene, fam):
    """[(family, map size, {stage: median ms})]: per scene the median over the group's rows, then
    the median over scenes; groups in family order, then by size."""
    per = {}
    for s in scenes:
        by = {}
        for r in rows_by_scene[s]:
            by.setdefault((fam.of(r), method_value(r, "map.size")), []).append(r)
        for g, rows in by.items():
            stage_ms = {}
            for r in rows:
                for label, _, v in time_stages(r):
                    stage_ms.setdefault(label, []).append(v)
            for label, vs in stage_ms.items():
                per.setdefault(g, {}).setdefault(label, []).append(statistics.median(vs))
    order = {k: i for i, k in enumerate(fam.order)}

    def size_key(v):
        return (0, float(v)) if isinstance(v, (int, float)) else (1, str(v))
    groups = sorted(per, key=lambda g: (order.get(g[0], len(order)), size_key(g[1])))
    return [(g[0], g[1], {label: statistics.median(v) for label, v in per[g].items()}) for g in groups]


def chart_time_breakdown(scenes, rows_by_scene, fam):
    """One stacked bar per family and map size: each stage's median over scenes (of its median over
    the group's rows in each scene). One panel, readable on one screen."""
    groups = time_groups(scenes, rows_by_scene, fam)
    if not any(stages for _, _, stages in groups):
        return None, "no row has timings", None
    labels = [label for label, _, _, _ in TIME_STAGES] + [OTHER_STAGE[0]]
    colours = {label: colour for label, colour, _, _ in TIME_STAGES}
    colours[OTHER_STAGE[0]] = OTHER_STAGE[1]
    drawn = [label for label in labels if any(st.get(label, 0) > 0 for _, _, st in groups)]
    # Legend: two columns of stages.
    top = 12.0
    c_probe_rows = int(math.ceil(len(drawn) / 2))
    legend_h = c_probe_rows * (FONT + 5)
    names = [f"{fam.label(k)}" + (f" @ {size:g}" if isinstance(size, (int, float)) else "") for k, size, _ in groups]
    label_w = max(text_width(n, FONT) for n in names) + 22
    bar_h, gap = 10.0, 3.5
    y0 = top + legend_h + 14
    height = y0 + len(groups) * (bar_h + gap) + 36
    c = Canvas(PAGE_WIDTH, height)
    for i, label in enumerate(drawn):
        col, r = divmod(i, c_probe_rows)
        x = 8 + col * (PAGE_WIDTH / 2)
        y = top + r * (FONT + 5)
        c.rect(x, y - 7, 8, 8, fill=colours[label])
        c.text(x + 11, y, label, FONT)
    x0, x1 = 8 + label_w, PAGE_WIDTH - 40  # the bars; their labels and markers left of x0
    totals = [sum(st.get(label, 0) for label in drawn) for _, _, st in groups]
    tmax = max(totals) if totals and max(totals) > 0 else 1.0
    ticks = nice_linear_ticks(0, tmax, 6)
    scale = (x1 - x0) / max(ticks[-1], tmax)
    for t in ticks:
        xx = x0 + t * scale
        c.line([(xx, y0 - 3), (xx, y0 + len(groups) * (bar_h + gap))], "#e4e4e4", 0.5)
        c.text(xx, y0 + len(groups) * (bar_h + gap) + FONT + 3, tick_text(t), FONT, "middle")
    c.text((x0 + x1) / 2, y0 + len(groups) * (bar_h + gap) + 2 * FONT + 8,
           "ms per configuration (median over scenes)", FONT, "middle")
    for i, ((k, size, st), name) in enumerate(zip(groups, names)):
        y = y0 + i * (bar_h + gap)
        c.marker(x0 - label_w + 4, y + bar_h / 2, fam.shape(k), fam.colour(k), 3.0)
        c.text(x0 - 4, y + bar_h * 0.8, name, FONT, "end")
        left = x0
        for label in drawn:
            v = st.get(label, 0.0)
            if v <= 0:
                continue
            c.rect(left, y, v * scale, bar_h, fill=colours[label], title=f"{name}: {label} {v:.3g} ms")
            left += v * scale
        method = sum(st.get(label, 0.0) for label, _, _, is_method in TIME_STAGES if is_method)
        c.text(left + 3, y + bar_h * 0.8, f"{method:.3g}", FONT, "start", "#303030")
    caption = ("Where the time goes, per family and map size: each stage's median over the scenes (in each scene, "
               "the median over the group's configurations, e.g. its biases). Blue, green and cyan are the method's "
               "cost (method_gpu_ms: shadow pass and lookup pass; its value written after the bar); the rest is the "
               "harness's (visibility buffer, evidence resolve, readback, comparison, the configuration's remaining "
               "wall time; compare/TIMINGS.md). GPU stages are timestamps, the others CPU wall time.")
    return c, caption, {"stages": drawn}


def chart_m_footprint(scenes, rows_by_scene, swept, fam):
    have = any(num(r.get("metrics", {}), "m_p95") is not None for rs in rows_by_scene.values() for r in rs)
    if not have:
        return None, "the rows have no m_median/m_p95/m_max metrics", None
    # m depends on the map size and the fit (not on biases or filters): one line per fit.
    def fit_of(r):
        return str(method_value(r, "fit") or "sphere")
    fits = []
    for s in scenes:
        for r in rows_by_scene[s]:
            if fit_of(r) not in fits:
                fits.append(fit_of(r))
    fit_family = {}
    for k in fam.order:  # each fit drawn in the colour of the first family with that fit
        for s in scenes:
            for r in rows_by_scene[s]:
                if fam.of(r) == k and fit_of(r) not in fit_family:
                    fit_family[fit_of(r)] = k
    sizes = sorted({num(r.get("method", {}), "map.size") for s in scenes for r in rows_by_scene[s]} - {None})
    if not sizes:
        return None, "the rows have no map.size", None
    def legend(c):
        items = []
        for f in fits:
            k = fit_family.get(f)
            items.append((lambda xx, yy, k=k: c.marker(xx + 4, yy - 3, fam.shape(k) if k else "circle",
                                                       fam.colour(k) if k else GREY, 3.4), f"fit={f}"))
        return items
    probe = Canvas(PAGE_WIDTH, 10)
    top = family_legend(probe, fam, [], 14, extra=legend(probe)) + 16
    boxes, height = panel_layout(len(scenes), 3 if len(scenes) > 2 else len(scenes), 120.0, top)
    c = Canvas(PAGE_WIDTH, height)
    family_legend(c, fam, [], 14, extra=legend(c))
    panels = {}
    for (x, y, w, h), scene in zip(boxes, scenes):
        pid = "m_footprint-" + scene
        panels[scene] = pid
        c.begin_group(pid)
        pts = {}
        for r in rows_by_scene[scene]:
            size = num(r.get("method", {}), "map.size")
            m = tuple(num(r.get("metrics", {}), k) for k in ("m_median", "m_p95", "m_max"))
            if size is None or m[1] is None:
                continue
            pts.setdefault(fit_of(r), {}).setdefault(size, (m, r))
        vals = [v for f in pts.values() for m, _ in f.values() for v in m if v and v > 0] + [1.0, 10.0]
        ylim = (min(vals) / 1.5, max(vals) * 1.5)
        ax = Axes(c, x, y, w, h, None, ylim, ylog=True, xcats=sizes)
        ax.frame(title=scene, xlabel="map.size", ylabel="m (px per texel)", yticks=log_ticks(*ylim),
                 xtick_labels=[f"{v:g}" for v in sizes])
        for yv, dash in ((1.0, (3, 2)), (10.0, (1, 2))):
            c.line([(x, ax.py(yv)), (x + w, ax.py(yv))], "#606060", 0.7, dash)
        nfit = max(1, len(fits))
        for i, f in enumerate(fits):
            if f not in pts:
                continue
            k = fit_family.get(f)
            colour = fam.colour(k) if k else GREY
            shift = (i - (nfit - 1) / 2) * min(5.0, w / len(sizes) / (nfit + 1))
            line = []
            for size in sizes:
                if size not in pts[f]:
                    continue
                (med, p95, mx), r = pts[f][size]
                xx = ax.px(size) + shift
                if med and mx and med > 0 and mx > 0:
                    c.line([(xx, ax.py(med)), (xx, ax.py(mx))], colour, 0.8)
                if p95 and p95 > 0:
                    line.append((xx, ax.py(p95)))
                    c.marker(xx, ax.py(p95), fam.shape(k) if k else "circle", colour, 2.6,
                             title=f"{scene}: fit={f}, map.size={size:g}\nm_median {med:.3g}, m_p95 {p95:.3g}, "
                                   f"m_max {mx:.3g}", href=row_href(r))
            c.line(line, colour, 0.9)
        c.end_group()
    caption = ("Lloyd et al.'s texel footprint m (the screen extent of one shadow-map texel, in pixels) over the "
               "compared pixels, per fit and map size: the point is m_p95, the bar spans m_median..m_max. Dashed: "
               "m = 1 (no perspective aliasing); dotted: m = 10 (severe). m does not depend on biases or filters.")
    return c, caption, {"panels": panels}


PALETTE = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#222222", "#bcbd22",
           "#17becf"]


def chart_frontiers(frontiers):
    panels_keys = []
    for f in frontiers:
        key = (f["scene"], f["parameter"])
        if key not in panels_keys:
            panels_keys.append(key)
    metric, threshold = frontiers[0]["metric"], frontiers[0]["threshold"]
    methods = []
    for f in frontiers:
        if f["method"] not in methods:
            methods.append(f["method"])
    top = 14.0
    y = top
    probe_lines = int(math.ceil(len(methods) / 2))
    legend_h = probe_lines * (FONT + 5)
    boxes, height = panel_layout(len(panels_keys), 2 if len(panels_keys) > 1 else 1, 140.0, top + legend_h + 16)
    c = Canvas(PAGE_WIDTH, height)
    for i, m in enumerate(methods):
        col, r = divmod(i, probe_lines)
        xx = 8 + col * PAGE_WIDTH / 2
        yy = y + r * (FONT + 5)
        c.line([(xx, yy - 3), (xx + 10, yy - 3)], PALETTE[i % len(PALETTE)], 1.4)
        label = m if text_width(m, FONT) < PAGE_WIDTH / 2 - 24 else m[:60] + "..."
        c.text(xx + 13, yy, label, FONT)
    panels = {}
    for (x, y, w, h), (scene, parameter) in zip(boxes, panels_keys):
        lines = [f for f in frontiers if f["scene"] == scene and f["parameter"] == parameter]
        pid = f"frontiers-{scene}-{parameter}"
        panels.setdefault(scene, pid)
        c.begin_group(pid)
        cats = [p["value"] for p in lines[0]["points"]]
        cat_text = [str(v) if not isinstance(v, float) else f"{v:g}" for v in cats]
        values = [p["metric"] for f in lines for p in f["points"]] + [threshold]
        floor = positive_floor(values)
        ylim = (floor / 1.5, max(values) * 1.5)
        ax = Axes(c, x, y, w, h, None, ylim, ylog=True, xcats=list(range(len(cats))))
        pointer = lines[0].get("pointer", "")
        shown = parameter if parameter == "scene:" + pointer else f"{parameter} = scene:{pointer}"
        ax.frame(title=scene, xlabel=shown + " (easy to hard)", ylabel=metric, yticks=log_ticks(*ylim),
                 xtick_labels=cat_text)
        c.line([(x, ax.py(max(threshold, floor))), (x + w, ax.py(max(threshold, floor)))], "#606060", 0.8, (3, 2))
        for f in lines:
            colour = PALETTE[methods.index(f["method"]) % len(PALETTE)]
            pts = []
            for k, p in enumerate(f["points"]):
                if k >= len(cats):
                    break
                pts.append((ax.px(k), ax.py(max(p["metric"], floor))))
            c.line(pts, colour, 1.1)
            for k, ((px, py), p) in enumerate(zip(pts, f["points"])):
                breaks = not f["holds"] and p["value"] == f["breaks_at"]
                c.marker(px, py, "star" if breaks else "circle", colour, 4.5 if breaks else 2.2,
                         title=f"{f['method']}: {parameter} = {p['value']}, {metric} {pct(p['metric'])}"
                               + (" (breaks here)" if breaks else ""))
        c.end_group()
    caption = (f"{metric} against each swept scene parameter, one line per method configuration, easy values on the "
               f"left; the dashed line is the threshold ({pct(threshold)}) and a star marks each frontier, the first "
               "value above it (zeros are drawn at the floor of the log axis).")
    return c, caption, {"panels": panels}


# ---------------------------------------------------------------------------------------------
# Findings: per scene, what goes wrong, what fixes it, what it costs, what fails first.


def _piece(text, href=None):
    return {"text": text, "href": href} if href else {"text": text}


def findings(scenes, rows_by_scene, classes, fam, results, panels):
    """[{scene, wrong, fixes, costs, fails}], each a list of sentences, each a list of pieces
    {text, href?} (the report links a piece to the chart panel or triptych that shows it)."""
    threshold = results.get("sweep", {}).get("frontier", {}).get("threshold", DEFAULT_FAIL_THRESHOLD)
    frontiers = [f for f in results.get("frontiers", []) if f.get("points")]
    out = []

    def link(chart, scene):
        pid = panels.get(chart, {}).get(scene)
        return "#" + pid if pid else None

    bias_chart = next((k for k in panels if k.startswith("bias_")), None)
    for s in scenes:
        rows = [r for r in rows_by_scene[s] if rankable(r)]
        # glance: one short sentence per column, the report's first screen (a line or two a cell).
        entry = {"scene": s, "wrong": [], "fixes": [], "costs": [], "fails": [],
                 "glance": {"wrong": [], "fixes": [], "costs": [], "fails": []}}
        glance = entry["glance"]
        out.append(entry)
        if not rows:
            entry["wrong"].append([_piece("No configuration compared any pixel.")])
            glance["wrong"] = [_piece("nothing compared")]
            continue
        # What goes wrong: the dominant class over all configurations, and where it is worst.
        totals = [(sum(num(r["metrics"], m) or 0.0 for r in rows), m, label) for m, label, _ in classes]
        whole = sum(t for t, _, _ in totals)
        if whole <= 0:
            entry["wrong"].append([_piece("No configuration has an error.")])
            glance["wrong"] = [_piece("no errors")]
        else:
            totals.sort(key=lambda t: -t[0])
            t, metric, label = totals[0]
            glance["wrong"] = [_piece(f"{label} {t / whole:.0%}", link("class_mix", s))]
            if len(totals) > 1 and totals[1][0] > 0.15 * whole:
                glance["wrong"].append(_piece(f", {totals[1][2]} {totals[1][0] / whole:.0%}"))
            worst = max(rows, key=lambda r: num(r["metrics"], metric) or 0.0)
            sentence = [_piece(f"{label}: {t / whole:.0%} of the errors", link("class_mix", s)),
                        _piece("; worst: "), _piece(worst["config"], row_href(worst)),
                        _piece(f" ({metric} {pct(num(worst['metrics'], metric))}).")]
            entry["wrong"].append(sentence)
            if len(totals) > 1 and totals[1][0] > 0.15 * whole:
                entry["wrong"].append([_piece(f"Then {totals[1][2]}: {totals[1][0] / whole:.0%}.")])
        # What fixes it and what it costs: the best configuration, the cheapest within 2x of its error,
        # and the best at the fastest configuration's budget and the median time.
        # The first lowest error in row order: the row the report's "best" triptych shows.
        best = min(rows, key=lambda r: num(r["metrics"], "error_rate"))
        e_best = num(best["metrics"], "error_rate")
        within = [r for r in rows if num(r["metrics"], "error_rate") <= (2 * e_best if e_best > 0 else 0.0)]
        cheap = min(within, key=lambda r: (method_gpu_ms(r), num(r["metrics"], "error_rate")))
        acc = link("accuracy_vs_time", s)
        entry["fixes"].append([_piece("Best: "), _piece(best["config"], row_href(best)),
                               _piece(f" ({pct(e_best)}, {ms(method_gpu_ms(best))}; "),
                               _piece("triptych", f"#triptych-{s}-best"), _piece(").")])
        glance["fixes"] = [_piece(best["config"], row_href(best)), _piece(f": {pct(e_best)}")]
        glance["costs"] = [_piece(ms(method_gpu_ms(cheap)), acc), _piece(": "),
                           _piece(cheap["config"], row_href(cheap)),
                           _piece(f" ({pct(num(cheap['metrics'], 'error_rate'))})")]
        if cheap is not best:
            entry["fixes"].append([_piece("Cheapest within 2x of its error: "),
                                   _piece(cheap["config"], row_href(cheap)),
                                   _piece(f" ({pct(num(cheap['metrics'], 'error_rate'))}, "
                                          f"{ms(method_gpu_ms(cheap))}).")])
        times = sorted(method_gpu_ms(r) for r in rows)
        budgets = []
        for b in (times[0] * 1.5, statistics.median(times)):
            if all(abs(b - x) > 1e-9 for x in budgets):
                budgets.append(b)
        shown = set()
        for b in budgets:
            fits = [r for r in rows if method_gpu_ms(r) <= b]
            if not fits:
                continue
            r = min(fits, key=lambda r: (num(r["metrics"], "error_rate"), method_gpu_ms(r)))
            if r["_index"] in shown:
                continue
            shown.add(r["_index"])
            entry["costs"].append([_piece(f"Within {ms(b)}", acc), _piece(": "), _piece(r["config"], row_href(r)),
                                   _piece(f" ({pct(num(r['metrics'], 'error_rate'))}).")])
        entry["costs"].append([_piece(f"The best costs {method_gpu_ms(best) / max(times[0], 1e-9):.3g}x the fastest "
                                      f"({ms(times[0])}).")])
        # What fails first: the failure frontiers when swept, else per family the largest map size
        # whose best error_rate exceeds the threshold, and the depth-comparison families' acne at
        # their smallest bias.
        mine = [f for f in frontiers if f.get("scene") == s]
        if mine:
            def breaks_index(f):
                return next((i for i, p in enumerate(f["points"]) if p.get("value") == f.get("breaks_at")), math.inf)

            broken = [f for f in mine if not f.get("holds") and f.get("breaks_at") is not None]
            if broken:
                f = min(broken, key=breaks_index)  # the first to break, walking from easy to hard
                glance["fails"] = [_piece(f"{f['method']} at {f.get('breaks_at')}", link("frontiers", s))]
            else:
                glance["fails"] = [_piece("no frontier crossed", link("frontiers", s))]
            for f in mine[:4]:
                entry["fails"].append([_piece(f.get("sentence") or f"{f['method']}: breaks at {f.get('breaks_at')}",
                                              link("frontiers", s))])
        else:
            by_family = {}
            for r in rows:
                size = num(r.get("method", {}), "map.size")
                e = num(r["metrics"], "error_rate")
                cur = by_family.setdefault(fam.of(r), {}).get(size)
                if cur is None or e < num(cur["metrics"], "error_rate"):
                    by_family[fam.of(r)][size] = r
            holds, fails = [], []
            for k in fam.order:
                if k not in by_family or None in by_family[k]:
                    continue
                sizes = sorted(by_family[k], reverse=True)  # easy (large maps) to hard
                broke = next((sz for sz in sizes if num(by_family[k][sz]["metrics"], "error_rate") > threshold), None)
                if broke is None:
                    holds.append(fam.label(k))
                elif broke == sizes[0]:
                    fails.append((fam.label(k), (math.inf, "at every map size"), by_family[k][broke]))
                else:
                    fails.append((fam.label(k), (broke, f"from map.size {broke:g} down"), by_family[k][broke]))
            if fails:
                label, where, r = max(fails, key=lambda f: f[1][0])  # the largest map size that fails
                glance["fails"] = [_piece(f"{label} {where[1]}", row_href(r))]
                by_size = {}
                for label, where, r in fails:
                    by_size.setdefault(where, []).append((label, r))
                sentence = [_piece(f"error_rate above {pct(threshold)} ")]
                for n, (where, items) in enumerate(sorted(by_size.items(), key=lambda kv: -kv[0][0])):
                    sentence.append(_piece(("; " if n else "") + where[1] + ": "))
                    for m, (label, r) in enumerate(items):
                        if m:
                            sentence.append(_piece(", "))
                        sentence.append(_piece(label, row_href(r)))
                        sentence.append(_piece(f" ({pct(num(r['metrics'], 'error_rate'))})"))
                sentence.append(_piece("."))
                entry["fails"].append(sentence)
            if holds and fails:
                entry["fails"].append([_piece(f"Below {pct(threshold)} at every map size: " + ", ".join(holds) + ".",
                                              link("error_by_size", s))])
            elif holds:
                entry["fails"].append([_piece(f"No family's error_rate exceeds {pct(threshold)} at any map size",
                                              link("error_by_size", s)), _piece(".")])
            # Along the bias: per family with a bias curve, the largest bias with acne above the
            # threshold and the smallest with leaks above it.
            if bias_chart:
                key = "bias." + bias_chart[len("bias_bias_"):].replace("_", ".") if bias_chart.startswith(
                    "bias_bias_") else "bias.slope"
                curves = {}
                for r in rows:
                    b = num(r.get("method", {}), key)
                    if b is not None:
                        curves.setdefault(fam.of(r), []).append((b, r))
                for k in fam.order:
                    pts = curves.get(k, [])
                    if len({b for b, _ in pts}) < 2:
                        continue
                    acne = [(b, r) for b, r in pts if (num(r["metrics"], "acne_rate") or 0) > threshold]
                    leak = [(b, r) for b, r in pts if (num(r["metrics"], "leak_rate") or 0) > threshold]
                    parts = []
                    if acne:
                        b, r = max(acne, key=lambda p: p[0])
                        parts += [_piece(f"acne above {pct(threshold)} up to {key} {b:g} ("),
                                  _piece(pct(num(r["metrics"], "acne_rate")), row_href(r)), _piece(")")]
                    if leak:
                        b, r = min(leak, key=lambda p: p[0])
                        parts += [_piece(("; " if parts else "") + f"leaks above {pct(threshold)} from {key} {b:g} ("),
                                  _piece(pct(num(r["metrics"], "leak_rate")), row_href(r)), _piece(")")]
                    if parts and not glance["fails"]:
                        b, r = (max(acne, key=lambda p: p[0]) if acne else min(leak, key=lambda p: p[0]))
                        what = "acne" if acne else "leaks"
                        glance["fails"] = [_piece(f"{fam.label(k)}: {what} at {key} {b:g}", row_href(r))]
                    if parts:
                        entry["fails"].append([_piece(fam.label(k), link(bias_chart, s)), _piece(": ")] + parts
                                              + [_piece(".")])
            if not glance["fails"]:
                glance["fails"] = [_piece(f"no family above {pct(threshold)}", link("error_by_size", s))]
    return out


# ---------------------------------------------------------------------------------------------


def load_classes(results_path):
    """[(metric, label, colour)] of each error class of classes.json."""
    path = os.path.join(os.path.dirname(os.path.abspath(results_path)), "classes.json")
    try:
        with open(path, encoding="utf-8") as f:
            table = json.load(f)
    except FileNotFoundError:
        sys.exit(f"charts.py: {path}: error: no class table; expected the classes.json a sweep writes "
                 "next to results.json (or `shadowlab classes --json > classes.json`)")
    return [(c["rate_metric"], c["label"], c["color"]) for c in table if c["error"] and c["rate_metric"]]


def write_atomic(path, data):
    tmp = os.path.join(os.path.dirname(path), "." + os.path.basename(path) + ".tmp")
    with open(tmp, "wb") as f:
        f.write(data)
    os.replace(tmp, path)  # never a half-written figure


def save(canvas, out_dir, chart_id):
    write_atomic(os.path.join(out_dir, chart_id + ".svg"), canvas.to_svg().encode("utf-8"))
    write_atomic(os.path.join(out_dir, chart_id + ".pdf"), canvas.to_pdf())
    return {"svg": f"figures/{chart_id}.svg", "pdf": f"figures/{chart_id}.pdf",
            "width_pt": canvas.width, "height_pt": canvas.height}


def main(argv):
    if len(argv) != 3:
        sys.stderr.write("usage: charts.py RESULTS_JSON FIGURES_DIR\n")
        return 2
    results_path, out_dir = argv[1], argv[2]
    with open(results_path, encoding="utf-8") as f:
        results = json.load(f)
    os.makedirs(out_dir, exist_ok=True)
    rows = results.get("rows", [])
    for i, r in enumerate(rows):
        r["_index"] = i  # the row's place in results.json: the report's anchor row-<i>
    sweep = results.get("sweep", {})
    swept = [axis["key"] for axis in sweep.get("grid", [])]
    scenes = []
    for r in rows:
        if r["scene"] not in scenes:
            scenes.append(r["scene"])
    rows_by_scene = {s: [r for r in rows if r["scene"] == s] for s in scenes}
    fam = Families(results)
    classes = load_classes(results_path)

    charts, skipped, panels = [], [], {}

    def run(chart_id, title, function, *args):
        canvas, text, extra = function(*args)
        if canvas is None:
            skipped.append({"id": chart_id, "title": title, "reason": text})
            return
        entry = {"id": chart_id, "title": title, "caption": text, **save(canvas, out_dir, chart_id)}
        if extra:
            entry.update(extra)
            panels[chart_id] = extra.get("panels", {})
        charts.append(entry)

    if not rows:
        skipped.append({"id": "all", "title": "all charts", "reason": "results.json has no rows"})
    else:
        run("accuracy_vs_time", "Accuracy against time (Pareto front)", chart_accuracy_vs_time, scenes,
            rows_by_scene, fam)
        run("class_mix", "Which error class dominates", chart_class_mix, scenes, rows_by_scene, classes)
        bias_swept = [(k, label) for k, label in BIAS_KEYS if k in swept]
        if not bias_swept:
            skipped.append({"id": "bias_tradeoff", "title": "The bias trade-off",
                            "reason": "no bias key (bias.slope, bias.constant, bias.compare, bias.normal) is in the "
                                      "grid"})
        for key, label in bias_swept:
            run("bias_" + key.replace(".", "_"), f"The bias trade-off per family: {key}", chart_bias, scenes,
                rows_by_scene, swept, fam, key, label)
        run("error_by_size", "Error rate against map size", chart_error_by_size, scenes, rows_by_scene, swept, fam)
        run("light_size", "Error against light size", chart_light_size, scenes, rows_by_scene, fam)
        run("time_breakdown", "Where the time goes", chart_time_breakdown, scenes, rows_by_scene, fam)
        run("m_footprint", "Texel footprint m", chart_m_footprint, scenes, rows_by_scene, swept, fam)
        frontiers = [f for f in results.get("frontiers", []) if f.get("points")]
        if frontiers:
            run("frontiers", "Failure frontiers", chart_frontiers, frontiers)

    manifest = {"charts": charts, "skipped": skipped,
                "families": [fam.info[k] for k in fam.order],
                "findings": findings(scenes, rows_by_scene, classes, fam, results, panels) if rows else [],
                "min_font_pt": MIN_FONT_PT}
    write_atomic(os.path.join(out_dir, "charts.json"), (json.dumps(manifest, indent=1) + "\n").encode("utf-8"))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
