#!/usr/bin/python3
"""Charts of a shadowlab sweep: reads results.json, writes PNG (for report.html), PDF and SVG (for
papers) into a figures folder, plus figures/charts.json listing the charts made and the ones skipped.
The error classes (rate metric, label, colour) come from classes.json next to RESULTS_JSON, which
the sweep writes from the C++ class table (`shadowlab classes --json` prints the same), so a class
added there gets its panel here without an edit.

Usage: /usr/bin/python3 charts.py RESULTS_JSON FIGURES_DIR

Run by `shadowlab sweep` after results.json is written (compare/SWEEPS.md). Needs Debian's
python3-matplotlib; the `python3` of a pyenv usually lacks it, hence /usr/bin/python3.

Every chart draws one panel per scene. When more keys are swept than a chart has axes for, each
point shows the configuration with the lowest error among those sharing the chart's coordinates
(said in the caption), so a chart never averages configurations that were never run together.
A chart whose swept key is absent from the grid is skipped with a reason (not an error).
"""
import gc
import json
import math
import multiprocessing
import os
import re
import sys
import textwrap

import matplotlib

matplotlib.use("Agg")  # no display; also keeps the script from touching any GUI toolkit
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402
from matplotlib.ticker import LogFormatterSciNotation, LogLocator  # noqa: E402
from matplotlib.transforms import blended_transform_factory  # noqa: E402

BIAS_KEYS = [("bias.slope", "bias.slope (x max depth slope)"),
             ("bias.constant", "bias.constant (units of r)"),
             ("bias.compare", "bias.compare (normalized depth)"),
             ("bias.normal", "bias.normal (map texels)")]
PNG_DPI = 100
# The charts that take longest to draw, started first (main). CPU seconds measured on the
# 100-configuration speed sweep of compare/SWEEPS.md: time_breakdown 0.5 (a bar per row),
# error_by_size 0.3, the others ~0.2 each; on the main job (324 rows, 9 scenes): error_by_size 4.2
# (54 panels), accuracy_vs_time 2.3, m_footprint 2.1, time_breakdown 2.0, bias_tradeoff 1.2.
DRAW_FIRST = ["error_by_size", "time_breakdown"]
# Reproducible files: no timestamps in PDF/SVG, fixed SVG ids.
matplotlib.rcParams["svg.hashsalt"] = "shadowlab"
matplotlib.rcParams["font.size"] = 9
# Titles at the top of their axes (where the automatic placement puts them too: no chart has
# labels or ticks above its axes), so that no draw computes the axes' tick boxes to place them
# (~8 % of the charts' CPU; the same bytes in every format).
matplotlib.rcParams["axes.titley"] = 1.0


def share_pdf_markers():
    """PDF markers shared as matplotlib means them to be. Its PDF writer keeps one XObject per
    marker shape and reuses it for every line with that shape (PdfFile.markerObject), keyed by the
    shape's drawing commands; matplotlib 3.6 (Debian 12) wraps those commands in a Verbatim, which
    compares by identity, so every draw_markers call wrote a new XObject and measured its Bezier
    extents again. Verbatim compared by its bytes restores the sharing: the same page, smaller
    files (the main job's error_by_size.pdf 184 -> 70 KB) and 0.66 s less CPU for the main job's
    charts. Nothing changes where Verbatim already compares by value."""
    from matplotlib.backends import backend_pdf
    verbatim = getattr(backend_pdf, "Verbatim", None)
    if verbatim is None or verbatim.__eq__ is not object.__eq__ or not hasattr(verbatim(b""), "_x"):
        return
    verbatim.__eq__ = lambda self, other: type(other) is verbatim and self._x == other._x
    verbatim.__hash__ = lambda self: hash(self._x)


share_pdf_markers()


def load_classes(results_path):
    """[(metric, label, colour)]: all errors first, then each error class of classes.json."""
    path = os.path.join(os.path.dirname(os.path.abspath(results_path)), "classes.json")
    try:
        with open(path, encoding="utf-8") as f:
            table = json.load(f)
    except FileNotFoundError:
        sys.exit(f"charts.py: {path}: error: no class table; expected the classes.json a sweep writes "
                 "next to results.json (or `shadowlab classes --json > classes.json`)")
    return [("error_rate", "all errors", None)] + [(c["rate_metric"], c["label"], c["color"]) for c in table
                                                    if c["error"] and c["rate_metric"]]


def num(d, key):
    v = d.get(key)
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return None
    return float(v) if math.isfinite(v) else None


def method_gpu_ms(row):
    """The method's time, what an engine pays (compare/TIMINGS.md): method_gpu_ms = shadow pass +
    lookup pass, the same time axis as the report's tables; rows without it (written before the
    lookup pass): shadow_gpu_ms + lookup_gpu_ms (absent: 0)."""
    t = row.get("timings", {})
    m = num(t, "method_gpu_ms")
    if m is not None:
        return m
    return (num(t, "shadow_gpu_ms") or 0.0) + (num(t, "lookup_gpu_ms") or 0.0)


def method_value(row, key):
    return row.get("method", {}).get(key)


def config_parts(config):
    """{key: value text} of a configuration's name: "key=value" parts joined by commas, a comma
    inside [...], {...} or "..." (a scene: vector, [4,10,6]) not splitting."""
    parts, depth, quoted, start = [], 0, False, 0
    for i, c in enumerate(config):
        if quoted:
            quoted = c != '"'
        elif c == '"':
            quoted = True
        elif c in "[{":
            depth += 1
        elif c in "]}" and depth > 0:
            depth -= 1
        elif c == "," and depth == 0:
            parts.append(config[start:i])
            start = i + 1
    parts.append(config[start:])
    return dict(p.split("=", 1) for p in parts if "=" in p)


def value_text(v):
    """A method value as a configuration's name writes it (config_name.h, canonicalValueText)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float) and v.is_integer() and abs(v) < 1e15:
        return str(int(v))
    return str(v) if not isinstance(v, float) else repr(v)


def swept_values(row, keys):
    """The row's values of the swept keys, as a tuple in `keys` order: from its config text, where
    a method key at its default is not named, else from the row's resolved method."""
    parts = config_parts(row["config"])
    method = row.get("method", {})
    return tuple(parts.get(k, value_text(method[k]) if k in method else "") for k in keys)


def best_by(rows, group_key, score):
    """For each group, the row with the lowest score (ties: first in sweep order)."""
    best = {}
    for r in rows:
        g = group_key(r)
        s = score(r)
        if s is None:
            continue
        if g not in best or s < best[g][0]:
            best[g] = (s, r)
    return {g: r for g, (s, r) in best.items()}


def panel_grid(n, width_per=4.6, height_per=3.4, max_cols=3):
    cols = min(max_cols, max(1, n))
    rows = int(math.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(width_per * cols, height_per * rows), squeeze=False)
    flat = [a for row in axes for a in row]
    for a in flat[n:]:
        a.set_visible(False)
    return fig, flat[:n]


_SUPERSCRIPT = str.maketrans("-0123456789", "\u207b\u2070\u00b9\u00b2\u00b3\u2074\u2075\u2076\u2077\u2078\u2079")


class PlainLogFormatter(LogFormatterSciNotation):
    """The log axes' default labels (10^-3, 2x10^-6) as plain Unicode text (10⁻³, 2×10⁻⁶) instead of
    mathtext: the same look, without matplotlib's mathtext parser, which took ~15 % of the charts'
    CPU (pyparsing, once per label, renderer and resolution: charts.py 2.60-2.63 -> 2.27-2.49 s of
    CPU on the 100-configuration sweep). A label it cannot write so (a non-integer exponent) stays
    mathtext."""

    def __call__(self, x, pos=None):
        label = super().__call__(x, pos)
        m = re.fullmatch(r"\$\\mathdefault\{(-?)([0-9.]+\\times)?([0-9.e]+)\^\{(-?[0-9]+)\}\}\$", label)
        if not m:
            m0 = re.fullmatch(r"\$\\mathdefault\{(-?)([0-9.]+)\}\$", label)
            return ("\u2212" if m0.group(1) else "") + m0.group(2) if m0 else label
        sign, coefficient, base, exponent = m.groups()
        coefficient = coefficient.replace("\\times", "\u00d7") if coefficient else ""
        return ("\u2212" if sign else "") + coefficient + base + exponent.translate(_SUPERSCRIPT)


class ViewLogLocator(LogLocator):
    """A log axis's ticks as LogLocator places them, only those inside the view. LogLocator also
    returns the decades around the view (one below, two above), and the axis makes a tick for each
    (five artists) and moves and labels it at every draw before it drops the ones outside: on a
    panel spanning 2 decades ~40 minor ticks for the ~16 drawn. The ticks drawn, and so every
    file, are the same bytes (the 324-row main job's charts: 16.2 -> 13.3 s of CPU)."""

    def tick_values(self, vmin, vmax):
        ticks = super().tick_values(vmin, vmax)
        lo, hi = min(vmin, vmax), max(vmin, vmax)
        if not lo > 0:  # LogLocator took the axis's smallest positive value instead: keep its ticks
            return ticks
        # The axis keeps a tick within 1e-10 of the view (in its log space): so does this, wider.
        return ticks[(ticks >= lo * (1 - 1e-9)) & (ticks <= hi * (1 + 1e-9))]


def lean_log_axes(fig, view_ticks=True):
    """Every log and symlog axis of `fig` labelled by PlainLogFormatter and (view_ticks) every log
    axis located by ViewLogLocator, each with the settings of the formatter or locator it replaces."""
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            for which in ("major", "minor"):
                f = getattr(axis, f"get_{which}_formatter")()
                if type(f) is LogFormatterSciNotation:
                    getattr(axis, f"set_{which}_formatter")(
                        PlainLogFormatter(base=f._base, labelOnlyBase=f.labelOnlyBase,
                                          minor_thresholds=f.minor_thresholds, linthresh=f._linthresh))
                loc = getattr(axis, f"get_{which}_locator")()
                if view_ticks and type(loc) is LogLocator:
                    getattr(axis, f"set_{which}_locator")(
                        ViewLogLocator(base=loc._base, subs=loc._subs, numticks=loc.numticks))


def save(fig, out_dir, chart_id):
    lean_log_axes(fig)
    fig.tight_layout()
    files = {}
    for ext, kwargs in (("png", {"dpi": PNG_DPI}), ("pdf", {"metadata": {"CreationDate": None}}),
                        ("svg", {"metadata": {"Date": None}})):
        name = f"{chart_id}.{ext}"
        tmp = os.path.join(out_dir, f".{name}.tmp")
        fig.savefig(tmp, format=ext, **kwargs)
        os.replace(tmp, os.path.join(out_dir, name))  # never a half-written figure
        files[ext] = "figures/" + name
    plt.close(fig)
    return files


def positive_floor(values):
    """A floor for zeros on a log axis: half the smallest positive value (or 1e-6)."""
    pos = [v for v in values if v is not None and v > 0]
    return (min(pos) / 2.0) if pos else 1e-6


def chart_error_by_size(scenes, rows_by_scene, swept, classes, out_dir):
    if "map.size" not in swept:
        return None, "map.size is not in the grid (sweep it, e.g. --grid map.size=256,512,1024,2048)"
    # One line per filter, and per fit too when the fit is swept (a union of grids may sweep fits
    # with one filter only: the lines are the combinations the rows have).
    line_keys = ["filter"] + (["fit"] if "fit" in swept else [])
    others = [k for k in swept if k not in ["map.size"] + line_keys]

    def line_of(r):
        return ", ".join(f"{k}={method_value(r, k)}" for k in line_keys)
    # A class no row has (its rate 0 everywhere, e.g. bleed without a filterable map) gets no panel,
    # only a line in the caption: a row of empty panels says less and costs most of the drawing.
    all_rows = [r for s in scenes for r in rows_by_scene[s]]
    absent = [label for metric, label, _ in classes[1:]
              if all((num(r["metrics"], metric) or 0.0) == 0.0 for r in all_rows)]
    classes = [c for c in classes if c[1] not in absent]
    fig, axes = panel_grid(len(scenes) * len(classes), width_per=3.3, height_per=2.8, max_cols=len(classes))
    drew_zero = False
    empty_panels = set()
    for si, scene in enumerate(scenes):
        rows = rows_by_scene[scene]
        filters = []
        for r in rows:
            f = line_of(r)
            if f not in filters:
                filters.append(f)
        # Each line's row at each size: the lowest error_rate, the same rows in every class's panel.
        best = best_by(rows, lambda r: (line_of(r), method_value(r, "map.size")),
                       lambda r: num(r["metrics"], "error_rate"))
        for ci, (metric, label, colour) in enumerate(classes):
            ax = axes[si * len(classes) + ci]
            if colour:  # the class's colour in errors.png, as the panel's frame
                for spine in ax.spines.values():
                    spine.set_edgecolor(colour)
                    spine.set_linewidth(1.5)
            lines = []
            for f in filters:
                pts = sorted((int(k[1]), num(r["metrics"], metric)) for k, r in best.items()
                             if k[0] == f and num(r["metrics"], metric) is not None)
                lines.append((f, pts))
            if not any(y > 0 for _, pts in lines for _, y in pts):
                # Every point would be a zero: say so in words instead of flat lines at an arbitrary
                # floor of an empty log axis (whose ticks and grid were also most of the panel's
                # drawing time). "In any configuration" when no row of the scene has the class.
                # No point at all: the rows lack the metric (results of a build without the class).
                anywhere = any((num(r["metrics"], metric) or 0.0) > 0.0 for r in rows)
                measured = any(pts for _, pts in lines)
                ax.set_xticks([])
                ax.set_yticks([])
                text = (f"no {label} errors\n" + ("in the configurations shown" if anywhere else "in any configuration")
                        if measured else f"no {metric}\nin the results")
                ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", color="0.35")
                ax.set_title(f"{scene}: {label}")
                empty_panels.add("shown" if anywhere else "any" if measured else "unmeasured")
                continue
            floor = positive_floor([y for _, pts in lines for _, y in pts])
            for f, pts in lines:
                xs = [p[0] for p in pts]
                ys = [p[1] if p[1] > 0 else floor for p in pts]
                line, = ax.plot(xs, ys, marker="o", label=f)
                zx = [p[0] for p in pts if p[1] <= 0]
                if zx:
                    drew_zero = True
                    ax.plot(zx, [floor] * len(zx), linestyle="none", marker="v", markersize=7,
                            markerfacecolor="white", color=line.get_color())
            ax.set_xscale("log", base=2)
            ax.set_yscale("log")
            ax.set_title(f"{scene}: {label}")
            ax.set_xlabel("shadow map size (texels per side)")
            ax.set_ylabel(f"{metric} (fraction of pixels)")
            ax.grid(True, which="both", alpha=0.3)
            if ci == 0:
                ax.legend(fontsize=7)
    caption = ("Error rate by class against shadow-map resolution (log-log), one line per "
               + " and ".join(line_keys) + ", one row of panels per scene; each class's panel is framed in its "
               "errors.png colour.")
    if others:
        caption += (" At each size and " + " and ".join(line_keys) + " the configuration with the lowest error_rate over "
                    + ", ".join(others) + " is shown.")
    if drew_zero:
        caption += " Hollow triangles: a rate of exactly 0, drawn at the panel's floor (log axes cannot show 0)."
    if "any" in empty_panels:
        caption += (" \"No ... errors in any configuration\": no configuration of the panel's scene has the class"
                    " (rate 0 in every row of the scene).")
    if "shown" in empty_panels:
        caption += (" \"No ... errors in the configurations shown\": the class's rate is 0 in every configuration"
                    " the panel would draw; some other configuration of the scene has it.")
    if "unmeasured" in empty_panels:
        caption += " \"No ... in the results\": the scene's rows have no such metric (written by an older build)."
    if absent:
        caption += " No configuration has " + ", ".join(absent) + " errors (rate 0 in every row): no panel."
    return save(fig, out_dir, "error_by_size"), caption


def chart_bias_tradeoff(scenes, rows_by_scene, swept, out_dir, key, key_label):
    # The best bias depends on the map resolution, so when map.size is swept (a handful of sizes)
    # each size gets its own pair of lines; any other swept key is reduced to its best row.
    per_size = "map.size" in swept and key != "map.size"
    others = [k for k in swept if k != key and not (per_size and k == "map.size")]
    fig, axes = panel_grid(len(scenes), width_per=5.2, height_per=3.8, max_cols=2)
    notes = []
    for ax, scene in zip(axes, scenes):
        rows = rows_by_scene[scene]
        sizes = sorted({int(method_value(r, "map.size")) for r in rows}) if per_size else [None]
        if len(sizes) > 6:  # too many lines to read: keep the smallest, middle and largest
            sizes = [sizes[0], sizes[len(sizes) // 2], sizes[-1]]
        colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
        for n, size in enumerate(sizes):
            subset = [r for r in rows if size is None or int(method_value(r, "map.size")) == size]
            best = best_by(subset, lambda r: float(method_value(r, key)),
                           lambda r: (num(r["metrics"], "acne_rate") or 0) + (num(r["metrics"], "leak_rate") or 0))
            xs = sorted(best)
            if not xs:
                continue
            acne = [num(best[x]["metrics"], "acne_rate") or 0 for x in xs]
            leak = [num(best[x]["metrics"], "leak_rate") or 0 for x in xs]
            total = [a + l for a, l in zip(acne, leak)]
            color = colors[n % len(colors)]
            tag = "" if size is None else f" @ {size}"
            ax.plot(xs, acne, marker="o", color=color, label=f"acne_rate{tag}")
            ax.plot(xs, leak, marker="s", linestyle="--", color=color, label=f"leak_rate{tag}")
            i = min(range(len(xs)), key=lambda k: (total[k], xs[k]))
            ax.plot([xs[i]], [total[i]], marker="*", markersize=14, color=color, markeredgecolor="black",
                    linestyle="none", label=f"best {key} = {xs[i]:g}{tag}")
            if size == sizes[-1]:
                notes.append(f"{scene}: best {key} = {xs[i]:g}{tag} (acne {acne[i]:.3%}, leak {leak[i]:.3%})")
        xs_all = sorted({float(method_value(r, key)) for r in rows})
        pos = [x for x in xs_all if x > 0]
        if len(xs_all) > 2 and min(xs_all) >= 0 and pos and max(pos) / min(pos) >= 50:
            ax.set_xscale("symlog", linthresh=min(pos))
        ax.set_yscale("symlog", linthresh=1e-4)
        ax.set_ylim(bottom=0)
        ax.set_title(scene)
        ax.set_xlabel(key_label)
        ax.set_ylabel("rate (fraction of compared pixels)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=6.5, ncol=2 if len(sizes) > 1 else 1)
    caption = (f"The bias trade-off for {key}: acne (solid) falls and leaking or peter panning (dashed) rises as the "
               "bias grows; a star marks the bias with the lowest acne_rate + leak_rate"
               + (", one colour per map size" if per_size else "") + ". The y axis is linear below 1e-4 and "
               "logarithmic above. " + "; ".join(notes) + ".")
    if others:
        caption += " At each point the configuration with the lowest acne_rate + leak_rate over " + ", ".join(others) + \
                   " is shown."
    return save(fig, out_dir, "bias_tradeoff_" + key.replace(".", "_")), caption


def pareto(points):
    """points: (time, error, label); returns the front by increasing time, strictly decreasing error."""
    front, best = [], math.inf
    for p in sorted(points, key=lambda p: (p[0], p[1])):
        if p[1] < best:
            front.append(p)
            best = p[1]
    return front


def chart_accuracy_vs_time(scenes, rows_by_scene, out_dir):
    fig, axes = panel_grid(len(scenes), width_per=9.0, height_per=4.0, max_cols=2)
    for ax, scene in zip(axes, scenes):
        pts = [(method_gpu_ms(r), num(r["metrics"], "error_rate"), r["config"]) for r in rows_by_scene[scene]
               if num(r["metrics"], "error_rate") is not None]
        floor = positive_floor([p[1] for p in pts])
        ys = [p[1] if p[1] > 0 else floor for p in pts]
        ax.scatter([p[0] for p in pts], ys, s=18, color="tab:gray", alpha=0.7, label="configuration")
        front = pareto(pts)
        fx = [p[0] for p in front]
        fy = [p[1] if p[1] > 0 else floor for p in front]
        ax.step(fx, fy, where="post", color="tab:orange", linewidth=1.6, label="Pareto front")
        ax.scatter(fx, fy, s=36, color="tab:orange", zorder=3)
        # Number the front on the plot and name the numbers in the legend (outside the axes), so
        # labels of nearby points never overlap: these configurations answer "what should I use
        # at this time budget".
        shown = front[:12]
        for k, p in enumerate(shown):
            ax.annotate(str(k + 1), (fx[k], fy[k]), textcoords="offset points", xytext=(4, 4), fontsize=7,
                        color="tab:orange", fontweight="bold")
            ax.plot([], [], " ", label=f"{k + 1}: {p[2]} ({p[0]:.1f} ms, {p[1]:.3%})")
        if len(front) > len(shown):
            ax.plot([], [], " ", label=f"... {len(front) - len(shown)} more on the front: see the report's table")
        ax.set_yscale("log")
        ax.set_title(f"{scene}: accuracy against time")
        ax.set_xlabel("method time: method_gpu_ms = shadow + lookup pass (ms, GPU timestamps)")
        ax.set_ylabel("error_rate (fraction of compared pixels)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=6.5, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0)
    caption = ("Accuracy against the method's time (method_gpu_ms: the shadow pass plus a lookup pass that computes "
               "only the method's visibility, what an engine would pay; the harness's evidence resolve, readback and "
               "comparison are not counted, see \"Where the time goes\"): each dot is one configuration; the orange "
               "steps are the Pareto front (no other configuration is both faster and more accurate), numbered and "
               "named in the legend. Zero error rates are drawn at the panel's floor.")
    return save(fig, out_dir, "accuracy_vs_time"), caption


# "Where the time goes": the stages of one configuration, stacked in this order, the method's first.
# (label, colour, value(timings) or None when the row lacks it). The evidence resolve is
# evidence_gpu_ms (with evidence on demand the resolve of the listed pixels only; rows of earlier
# builds: the camera pass less its visibility buffer); "other" is the row's wall time the stages leave (CPU recording,
# submit and wait, the reference when the scene changes, pictures). GPU stages are timestamps, the
# others CPU wall time; on a CPU driver (lavapipe) both are the same cores' time.
def _stage(key):
    return lambda t: num(t, key)


def _evidence_resolve(t):
    evidence = num(t, "evidence_gpu_ms")  # the listed pixels only (evidence on demand), or every pixel
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
    ("shadow pass: map layers (shadow_gpu_ms - moments_gpu_ms)", "tab:blue", _shadow_maps, True),
    ("shadow pass: moments of filterable maps (moments_gpu_ms)", "tab:green", _stage("moments_gpu_ms"), True),
    ("lookup pass (lookup_gpu_ms)", "tab:cyan", _stage("lookup_gpu_ms"), True),
    ("visibility buffer (visibility_gpu_ms)", "tab:olive", _stage("visibility_gpu_ms"), False),
    ("evidence resolve (evidence_gpu_ms; earlier rows: camera_gpu_ms - visibility_gpu_ms)", "tab:orange",
     _evidence_resolve, False),
    ("readback (readback_ms)", "tab:red", _stage("readback_ms"), False),
    ("compare (compare_ms)", "tab:purple", _stage("compare_ms"), False),
]
# The stages' legend lines wrap at this many characters: the legend sits beside every panel and
# takes its width from all of them (unwrapped, "other wall time (...)" left the bars a third of it).
LEGEND_WRAP = 48
OTHER_STAGE = ("other wall time (config_wall_ms less the stages: recording, submit, a pipeline's first-use compile "
               "and warm-up frame, reference, pictures)",
               "tab:gray")


def time_stages(row):
    """[(label, colour, ms)] of one row: TIME_STAGES it has, then the rest of config_wall_ms."""
    t = row.get("timings", {})
    out = [(label, colour, v(t)) for label, colour, v, _ in TIME_STAGES]
    out = [(label, colour, ms) for label, colour, ms in out if ms is not None]
    wall = num(t, "config_wall_ms")
    if wall is not None:
        out.append((OTHER_STAGE[0], OTHER_STAGE[1], max(wall - sum(ms for _, _, ms in out), 0.0)))
    return out


def chart_time_breakdown(scenes, rows_by_scene, out_dir):
    """Stacked per-stage time per configuration (one horizontal bar each, by method time), one panel
    per scene: the method's cost (shadow + lookup) beside the harness's."""
    if not any(time_stages(r) for s in scenes for r in rows_by_scene[s]):
        return None, "no row has timings"
    heights = [max(2.5, 0.16 * len(rows_by_scene[s]) + 1.2) for s in scenes]
    fig, axes = plt.subplots(len(scenes), 1, figsize=(11.0, sum(heights)), squeeze=False,
                             gridspec_kw={"height_ratios": heights})
    drawn = []
    for ax, scene in zip([a[0] for a in axes], scenes):
        rows = sorted(rows_by_scene[scene], key=method_gpu_ms)
        left = [0.0] * len(rows)
        stages = [time_stages(r) for r in rows]
        labels = [label for label, _, _, _ in TIME_STAGES] + [OTHER_STAGE[0]]
        colours = {label: colour for label, colour, _, _ in TIME_STAGES}
        colours[OTHER_STAGE[0]] = OTHER_STAGE[1]
        for label in labels:
            widths = [next((ms for l, _, ms in st if l == label), 0.0) for st in stages]
            if not any(w > 0 for w in widths):
                continue
            # One collection per stage rather than a bar (a patch) per row: the same rectangles,
            # drawn and written in one call each (100 rows x 8 stages were 800 patches).
            ax.add_collection(PolyCollection(
                [[(x0, y - 0.4), (x0 + w, y - 0.4), (x0 + w, y + 0.4), (x0, y + 0.4)]
                 for y, (x0, w) in enumerate(zip(left, widths)) if w > 0],
                facecolors=colours[label], edgecolors="none", label=textwrap.fill(label, LEGEND_WRAP)))
            left = [a + b for a, b in zip(left, widths)]
            if label not in drawn:
                drawn.append(label)
        ax.set_xlim(0.0, max(left) * 1.05 if rows and max(left) > 0 else 1.0)
        ax.set_ylim(-0.6, len(rows) - 0.4)
        # Each bar's configuration as a text beside it rather than as a tick label: the same words
        # in the same place without the bar's tick mark, and without an axis tick (five artists
        # moved and formatted at every draw) per row: ~20 % less CPU for 100 rows.
        ax.set_yticks([])
        beside = blended_transform_factory(ax.transAxes, ax.transData)
        for y, r in enumerate(rows):
            ax.text(-0.008, y, r["config"], fontsize=6, ha="right", va="center", transform=beside)
        ax.invert_yaxis()  # the fastest method on top
        ax.set_title(f"{scene}: where the time goes (configurations by method time, fastest first)", loc="left", fontsize=9)
        ax.set_xlabel("ms per configuration")
        ax.grid(True, axis="x", alpha=0.3)
        ax.legend(fontsize=6.5, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0)
    caption = ("Where the time goes: each bar is one configuration, its stages stacked. The blue and cyan parts are the "
               "method's cost (method_gpu_ms: the shadow pass and the lookup pass, what an engine would pay, the "
               "time axis of the Pareto front); the rest is the harness's: the visibility buffer, the evidence "
               "resolve, the readback, the comparison, and the configuration's remaining wall time "
               "(compare/TIMINGS.md). GPU stages are timestamps, the others CPU wall time.")
    files = save(fig, out_dir, "time_breakdown")
    return {**files, "stages": drawn}, caption


def footprint_groups(rows, swept):
    """Configurations with identical (m_median, m_p95, m_max), in sweep order. m depends on the map
    size and the fit, not on biases or filters, so a grid of 4 sizes x 8 biases has 4 distinct
    footprints; each group is labelled with the swept keys it shares and '*' for those it spans."""
    groups = []
    index = {}
    for r in rows:
        m = tuple(num(r["metrics"], k) for k in ("m_median", "m_p95", "m_max"))
        if m not in index:
            index[m] = len(groups)
            groups.append((m, []))
        groups[index[m]][1].append(r)
    labelled = []
    for m, members in groups:
        parts = []
        for k in swept:
            values = {swept_values(r, [k])[0] for r in members}
            parts.append(f"{k}={values.pop() if len(values) == 1 else '*'}")
        labelled.append((",".join(parts) if parts else members[0]["config"], m, len(members)))
    return labelled


def chart_m_footprint(scenes, rows_by_scene, swept, out_dir):
    have = any(num(r["metrics"], "m_p95") is not None for rs in rows_by_scene.values() for r in rs)
    if not have:
        return None, "the rows have no m_median/m_p95/m_max metrics"
    per_scene = {s: footprint_groups(rows_by_scene[s], swept) for s in scenes}
    n_groups = max(len(g) for g in per_scene.values())
    fig, axes = panel_grid(len(scenes), width_per=max(4.6, min(14.0, 0.3 * n_groups + 3.0)),
                           height_per=3.2 + (1.6 if n_groups <= 40 else 0.4), max_cols=1 if n_groups > 12 else 2)
    for ax, scene in zip(axes, scenes):
        groups = per_scene[scene]
        xs = list(range(len(groups)))
        med = [g[1][0] for g in groups]
        p95 = [g[1][1] for g in groups]
        mx = [g[1][2] for g in groups]
        floor = positive_floor(med + p95 + mx)
        fix = lambda v: v if v is not None and v > 0 else floor  # noqa: E731
        ax.vlines(xs, [fix(v) for v in med], [fix(v) for v in mx], color="0.6", linewidth=1.2, label="median..max")
        ax.scatter(xs, [fix(v) for v in med], marker="o", s=16, color="tab:blue", label="m_median", zorder=3)
        ax.scatter(xs, [fix(v) for v in p95], marker="^", s=22, color="tab:orange", label="m_p95", zorder=3)
        ax.scatter(xs, [fix(v) for v in mx], marker="_", s=60, color="tab:red", label="m_max", zorder=3)
        ax.axhline(1.0, color="tab:green", linestyle="--", linewidth=1, label="m = 1 (no aliasing)")
        ax.axhline(10.0, color="tab:red", linestyle=":", linewidth=1, label="m = 10 (severe)")
        ax.set_yscale("log")
        ax.set_xticks(xs)
        if len(groups) <= 40:
            ax.set_xticklabels([g[0] for g in groups], rotation=35, ha="right", fontsize=6.5)
        else:
            ax.set_xticklabels([str(x) if x % 5 == 0 else "" for x in xs], fontsize=6)
            ax.set_xlabel("distinct footprint (index in sweep order)")
        ax.set_title(f"{scene}: texel footprint m")
        ax.set_ylabel("m (pixels per map texel)")
        ax.grid(True, axis="y", which="both", alpha=0.3)
        ax.legend(fontsize=6.5, ncol=2)
    caption = ("Distribution of Lloyd et al.'s texel footprint m (the largest screen extent of one shadow-map texel, in "
               "pixels) over the compared pixels: median, 95th percentile and maximum. m <= 1: no perspective/projective "
               "aliasing; m > 10: severe. Configurations with the same footprint are drawn once; '*' marks a swept key "
               "whose values all share it (m does not depend on biases or filters).")
    return save(fig, out_dir, "m_footprint"), caption


def chart_frontiers(frontiers, out_dir):
    """Error against each swept scene: parameter, one line per method configuration, easy values on
    the left (the axis is flipped when smaller values are harder), each frontier marked with an X."""
    panels = []
    for f in frontiers:
        key = (f["scene"], f["parameter"])
        if key not in panels:
            panels.append(key)
    fig, axes = panel_grid(len(panels))
    metric, threshold = frontiers[0]["metric"], frontiers[0]["threshold"]
    for ax, (scene, parameter) in zip(axes, panels):
        lines = [f for f in frontiers if f["scene"] == scene and f["parameter"] == parameter]
        numeric = all(isinstance(p["value"], (int, float)) for f in lines for p in f["points"])
        values = [p["metric"] for f in lines for p in f["points"]]
        floor = positive_floor(values + [threshold])
        for i, f in enumerate(lines):
            xs = [p["value"] if numeric else k for k, p in enumerate(f["points"])]
            ys = [max(p["metric"], floor) for p in f["points"]]
            (line,) = ax.plot(xs, ys, marker="o", markersize=3, label=f["method"])
            if not f["holds"]:
                k = next(k for k, p in enumerate(f["points"]) if p["value"] == f["breaks_at"])
                ax.plot([xs[k]], [ys[k]], marker="X", markersize=10, color=line.get_color(),
                        markeredgecolor="black", linestyle="none")
        ax.axhline(max(threshold, floor), color="grey", linestyle="--", linewidth=0.8)
        ax.set_yscale("log")
        if numeric and lines[0]["direction"] == "decreasing":
            ax.invert_xaxis()  # easy (large) values on the left, like every other panel
        if not numeric:
            ax.set_xticks(range(len(lines[0]["points"])))
            ax.set_xticklabels([str(p["value"]) for p in lines[0]["points"]])
        ax.set_title(scene)
        # scene:failure stands for each scene's own declared pointer: name it.
        pointer = lines[0].get("pointer", "")
        shown = parameter if parameter == "scene:" + pointer else f"{parameter} = scene:{pointer}"
        ax.set_xlabel(shown + " (easy to hard)")
        ax.set_ylabel(metric)
        ax.legend(fontsize=6)
    caption = (f"{metric} against each swept scene parameter, one line per method configuration, easy values "
               f"on the left; the dashed line is the threshold ({threshold:g}) and an X marks each frontier, the "
               "first value above it (zeros are drawn at the floor of the log axis).")
    return save(fig, out_dir, "frontiers"), caption


def draw_task(function, args):
    return function(*args)


def main(argv):
    if len(argv) != 3:
        sys.stderr.write("usage: charts.py RESULTS_JSON FIGURES_DIR\n")
        return 2
    results_path, out_dir = argv[1], argv[2]
    with open(results_path, encoding="utf-8") as f:
        results = json.load(f)
    os.makedirs(out_dir, exist_ok=True)
    rows = results.get("rows", [])
    sweep = results.get("sweep", {})
    swept = [axis["key"] for axis in sweep.get("grid", [])]
    scenes = []
    for r in rows:
        if r["scene"] not in scenes:
            scenes.append(r["scene"])
    rows_by_scene = {s: [r for r in rows if r["scene"] == s] for s in scenes}

    # tasks: (id, title, function, args), drawn below; function None: skipped, args the reason
    charts, skipped, tasks = [], [], []

    if not rows:
        skipped.append({"id": "all", "title": "all charts", "reason": "results.json has no rows"})
    else:
        tasks.append(("error_by_size", "Error rate by class against map size",
                      chart_error_by_size, (scenes, rows_by_scene, swept, load_classes(results_path), out_dir)))
        bias_swept = [(k, label) for k, label in BIAS_KEYS if k in swept]
        if not bias_swept:
            tasks.append(("bias_tradeoff", "The bias trade-off", None,
                          "no bias key (bias.slope, bias.constant, bias.compare, bias.normal) is in the grid"))
        for key, label in bias_swept:
            tasks.append(("bias_tradeoff_" + key.replace(".", "_"), f"The bias trade-off: {key}",
                          chart_bias_tradeoff, (scenes, rows_by_scene, swept, out_dir, key, label)))
        tasks.append(("accuracy_vs_time", "Accuracy against time (Pareto front)",
                      chart_accuracy_vs_time, (scenes, rows_by_scene, out_dir)))
        tasks.append(("time_breakdown", "Where the time goes",
                      chart_time_breakdown, (scenes, rows_by_scene, out_dir)))
        tasks.append(("m_footprint", "Texel footprint m per configuration",
                      chart_m_footprint, (scenes, rows_by_scene, swept, out_dir)))
        # Only a sweep of a scene: parameter has frontiers; other sweeps get no chart and no note.
        frontiers = [f for f in results.get("frontiers", []) if f.get("points")]
        if frontiers:
            tasks.append(("frontiers", "Failure frontiers", chart_frontiers, (frontiers, out_dir)))

    # The charts are independent and each writes only its own files: drawn in two forked workers
    # (the sweep's report waits on this script; matplotlib is single-threaded), the costliest
    # first (DRAW_FIRST) so that the two finish together rather than one drawing a big chart
    # alone at the end. The manifest keeps the task order, so the output does not depend on
    # the drawing order or on which worker finished first.
    jobs = [(t[0], t[2], t[3]) for t in tasks if t[2] is not None]
    if len(jobs) > 1 and (os.cpu_count() or 1) > 1:
        order = sorted(range(len(jobs)), key=lambda i: DRAW_FIRST.index(jobs[i][0])
                       if jobs[i][0] in DRAW_FIRST else len(DRAW_FIRST))
        gc.freeze()  # matplotlib's import-time objects: the workers' collections skip them
        with multiprocessing.get_context("fork").Pool(2) as pool:
            out = pool.starmap(draw_task, [jobs[i][1:] for i in order], chunksize=1)
        by_job = dict(zip(order, out))
        drawn = iter([by_job[i] for i in range(len(jobs))])
    else:
        drawn = iter([draw_task(f, a) for _, f, a in jobs])
    results_list = [(None, t[3]) if t[2] is None else next(drawn) for t in tasks]
    for (chart_id, title, _, _), (files, text) in zip(tasks, results_list):
        if files is None:
            skipped.append({"id": chart_id, "title": title, "reason": text})
        else:
            charts.append({"id": chart_id, "title": title, "caption": text, **files})

    manifest = {"charts": charts, "skipped": skipped}
    tmp = os.path.join(out_dir, ".charts.json.tmp")
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(manifest, f, indent=2)
        f.write("\n")
    os.replace(tmp, os.path.join(out_dir, "charts.json"))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
