"""A small vector canvas for the report's charts, written as SVG (inline in report.html, with a
tooltip and a link per point) and as PDF (for print), from the same drawing calls.

Why not matplotlib: the report's charts drew for ~5 s of CPU per 324 rows there (tight_layout and a
full draw per format), and matplotlib's SVG has no per-point tooltip or link. The charts need lines,
markers, rectangles and text in a few sizes: this module draws those and nothing else.

Units are PostScript points (1/72 in), y down (as SVG; the PDF writer flips it). The SVG's width
and height are given in pt, so a chart prints at the size it was laid out for: 8 pt text is 8 pt on
paper. Text is Helvetica in the PDF (a standard font, not embedded) and Helvetica/Arial in the SVG;
widths come from Helvetica's metrics (Adobe's AFM, ASCII only; chart text is ASCII).
"""
import math
import zlib

# Helvetica advance widths (1/1000 em) of ASCII 32..126, from Adobe's Helvetica AFM (phvr8a.afm).
_HELVETICA = [278, 278, 355, 556, 556, 889, 667, 222, 333, 333, 389, 584, 278, 333, 278, 278, 556, 556, 556, 556,
              556, 556, 556, 556, 556, 556, 278, 278, 584, 584, 584, 556, 1015, 667, 667, 722, 722, 667, 611, 778,
              722, 278, 500, 667, 556, 833, 722, 778, 667, 778, 722, 667, 611, 722, 667, 944, 667, 667, 611, 278,
              278, 278, 469, 556, 222, 556, 556, 500, 556, 556, 278, 556, 556, 222, 222, 500, 222, 833, 556, 556,
              556, 556, 333, 500, 278, 556, 500, 722, 500, 500, 500, 334, 260, 334, 584]
# The smallest text any chart draws (pt): readable in print.
MIN_FONT_PT = 8.0


def text_width(s, size):
    """Width in pt of `s` set in Helvetica at `size` pt (bold taken as 5 % wider)."""
    return sum(_HELVETICA[ord(c) - 32] if 32 <= ord(c) < 127 else 556 for c in s) * size / 1000.0


def _esc(s):
    return s.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace('"', "&quot;")


def _rgb(colour):
    """'#rrggbb' -> (r, g, b) in 0..1."""
    c = colour.lstrip("#")
    return tuple(int(c[i:i + 2], 16) / 255.0 for i in (0, 2, 4))


def _f(v):
    """A coordinate as short text (0.01 pt is finer than any printer)."""
    s = f"{v:.2f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


# Marker shapes as polygons on a unit radius (circle: drawn as a circle).
MARKER_SHAPES = ["circle", "square", "triangle", "diamond", "triangle_down", "pentagon", "hexagon", "star"]


def _polygon(shape):
    if shape == "square":
        return [(-0.85, -0.85), (0.85, -0.85), (0.85, 0.85), (-0.85, 0.85)]
    if shape == "triangle":
        return [(0, -1.15), (1.0, 0.75), (-1.0, 0.75)]
    if shape == "triangle_down":
        return [(0, 1.15), (1.0, -0.75), (-1.0, -0.75)]
    if shape == "diamond":
        return [(0, -1.2), (0.9, 0), (0, 1.2), (-0.9, 0)]
    if shape in ("pentagon", "hexagon"):
        n = 5 if shape == "pentagon" else 6
        return [(math.sin(2 * math.pi * k / n) * 1.05, -math.cos(2 * math.pi * k / n) * 1.05) for k in range(n)]
    if shape == "star":
        pts = []
        for k in range(10):
            r = 1.25 if k % 2 == 0 else 0.5
            pts.append((math.sin(math.pi * k / 5) * r, -math.cos(math.pi * k / 5) * r))
        return pts
    return None  # circle


class Canvas:
    """Drawing calls recorded as operations, written by to_svg and to_pdf."""

    def __init__(self, width, height):
        self.width, self.height = float(width), float(height)
        self.ops = []

    # Drawing calls. `title`: the SVG tooltip; `href`: the SVG link (both absent from the PDF).
    def line(self, pts, colour, width=1.0, dash=None):
        if len(pts) >= 2:
            self.ops.append(("line", [(float(x), float(y)) for x, y in pts], colour, width, dash))

    def rect(self, x, y, w, h, fill=None, stroke=None, width=0.5, title=None, href=None):
        self.ops.append(("rect", float(x), float(y), float(w), float(h), fill, stroke, width, title, href))

    def marker(self, x, y, shape, colour, size=4.0, hollow=False, title=None, href=None):
        self.ops.append(("marker", float(x), float(y), shape, colour, size, hollow, title, href))

    def text(self, x, y, s, size=8.0, anchor="start", colour="#000000", rotate=0, bold=False):
        """`s` at baseline (x, y); anchor start/middle/end; rotate: degrees counter-clockwise."""
        assert size >= MIN_FONT_PT, f"{size} pt is below the charts' smallest text"
        self.ops.append(("text", float(x), float(y), str(s), float(size), anchor, colour, rotate, bold))

    def begin_group(self, gid, title=None):
        """A named group (an SVG <g id>, e.g. one scene's panel, so that a sentence can link to it)."""
        self.ops.append(("begin", gid, title))

    def end_group(self):
        self.ops.append(("end",))

    # Writers.
    def to_svg(self):
        out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{_f(self.width)}pt" height="{_f(self.height)}pt" '
               f'viewBox="0 0 {_f(self.width)} {_f(self.height)}" font-family="Helvetica, Arial, sans-serif">\n']
        for op in self.ops:
            kind = op[0]
            if kind == "line":
                _, pts, colour, width, dash = op
                d = " ".join(f"{_f(x)},{_f(y)}" for x, y in pts)
                dash_attr = f' stroke-dasharray="{" ".join(_f(v) for v in dash)}"' if dash else ""
                out.append(f'<polyline points="{d}" fill="none" stroke="{colour}" stroke-width="{_f(width)}"'
                           f'{dash_attr} stroke-linejoin="round"/>\n')
            elif kind == "rect":
                _, x, y, w, h, fill, stroke, width, title, href = op
                attrs = f'fill="{fill or "none"}"' + (f' stroke="{stroke}" stroke-width="{_f(width)}"' if stroke else "")
                shape = f'<rect x="{_f(x)}" y="{_f(y)}" width="{_f(w)}" height="{_f(h)}" {attrs}'
                out.append(self._wrap(shape, title, href))
            elif kind == "marker":
                _, x, y, shape, colour, size, hollow, title, href = op
                fill = "#ffffff" if hollow else colour
                poly = _polygon(shape)
                if poly is None:
                    el = f'<circle cx="{_f(x)}" cy="{_f(y)}" r="{_f(size)}"'
                else:
                    el = '<polygon points="' + " ".join(f"{_f(x + px * size)},{_f(y + py * size)}" for px, py in poly) + '"'
                el += f' fill="{fill}" stroke="{colour if hollow else "#202020"}" stroke-width="{0.9 if hollow else 0.4}"'
                out.append(self._wrap(el, title, href))
            elif kind == "text":
                _, x, y, s, size, anchor, colour, rotate, bold = op
                attrs = f'x="{_f(x)}" y="{_f(y)}" font-size="{_f(size)}"'
                if anchor != "start":
                    attrs += f' text-anchor="{anchor}"'
                if colour != "#000000":
                    attrs += f' fill="{colour}"'
                if bold:
                    attrs += ' font-weight="bold"'
                if rotate:
                    attrs += f' transform="rotate({_f(-rotate)} {_f(x)} {_f(y)})"'
                out.append(f"<text {attrs}>{_esc(s)}</text>\n")
            elif kind == "begin":
                _, gid, title = op
                out.append(f'<g id="{_esc(gid)}">' + (f"<title>{_esc(title)}</title>" if title else "") + "\n")
            elif kind == "end":
                out.append("</g>\n")
        out.append("</svg>\n")
        return "".join(out)

    @staticmethod
    def _wrap(element, title, href):
        if title:
            element += f"><title>{_esc(title)}</title></{element[1:element.index(' ')]}>"
        else:
            element += "/>"
        if href:
            element = f'<a href="{_esc(href)}">{element}</a>'
        return element + "\n"

    def to_pdf(self):
        """One page of the canvas's size; Helvetica and Helvetica-Bold (standard, not embedded)."""
        h = self.height
        c = []

        def rgb(colour, stroke):
            r, g, b = _rgb(colour)
            return f"{r:.3f} {g:.3f} {b:.3f} {'RG' if stroke else 'rg'}"

        for op in self.ops:
            kind = op[0]
            if kind == "line":
                _, pts, colour, width, dash = op
                c.append(f"{rgb(colour, True)} {_f(width)} w [{' '.join(_f(v) for v in dash or [])}] 0 d 1 j")
                c.append(f"{_f(pts[0][0])} {_f(h - pts[0][1])} m " +
                         " ".join(f"{_f(x)} {_f(h - y)} l" for x, y in pts[1:]) + " S")
            elif kind == "rect":
                _, x, y, w, hh, fill, stroke, width, _, _ = op
                path = f"{_f(x)} {_f(h - y - hh)} {_f(w)} {_f(hh)} re"
                if fill and stroke:
                    c.append(f"{rgb(fill, False)} {rgb(stroke, True)} {_f(width)} w [] 0 d {path} B")
                elif fill:
                    c.append(f"{rgb(fill, False)} {path} f")
                elif stroke:
                    c.append(f"{rgb(stroke, True)} {_f(width)} w [] 0 d {path} S")
            elif kind == "marker":
                _, x, y, shape, colour, size, hollow, _, _ = op
                poly = _polygon(shape)
                if poly is None:
                    k = 0.5523 * size  # four cubic Beziers approximate the circle
                    yy = h - y
                    path = (f"{_f(x + size)} {_f(yy)} m {_f(x + size)} {_f(yy + k)} {_f(x + k)} {_f(yy + size)} "
                            f"{_f(x)} {_f(yy + size)} c {_f(x - k)} {_f(yy + size)} {_f(x - size)} {_f(yy + k)} "
                            f"{_f(x - size)} {_f(yy)} c {_f(x - size)} {_f(yy - k)} {_f(x - k)} {_f(yy - size)} "
                            f"{_f(x)} {_f(yy - size)} c {_f(x + k)} {_f(yy - size)} {_f(x + size)} {_f(yy - k)} "
                            f"{_f(x + size)} {_f(yy)} c h")
                else:
                    path = (f"{_f(x + poly[0][0] * size)} {_f(h - y - poly[0][1] * size)} m " +
                            " ".join(f"{_f(x + px * size)} {_f(h - y - py * size)} l" for px, py in poly[1:]) + " h")
                if hollow:
                    c.append(f"1 1 1 rg {rgb(colour, True)} 0.9 w [] 0 d {path} B")
                else:
                    c.append(f"{rgb(colour, False)} 0.125 0.125 0.125 RG 0.4 w [] 0 d {path} B")
            elif kind == "text":
                _, x, y, s, size, anchor, colour, rotate, bold = op
                w = text_width(s, size)
                shift = {"start": 0.0, "middle": w / 2, "end": w}[anchor]
                a = math.radians(rotate)
                ca, sa = math.cos(a), math.sin(a)
                tx, ty = x - shift * ca, (h - y) - shift * sa
                s_pdf = s.encode("latin-1", "replace").decode("latin-1")
                s_pdf = s_pdf.replace("\\", "\\\\").replace("(", "\\(").replace(")", "\\)")
                c.append(f"BT {rgb(colour, False)} /{'F2' if bold else 'F1'} {_f(size)} Tf "
                         f"{ca:.4f} {sa:.4f} {-sa:.4f} {ca:.4f} {_f(tx)} {_f(ty)} Tm ({s_pdf}) Tj ET")
        content = zlib.compress("\n".join(c).encode("latin-1", "replace"), 6)
        objects = [
            b"<< /Type /Catalog /Pages 2 0 R >>",
            b"<< /Type /Pages /Kids [3 0 R] /Count 1 >>",
            (f"<< /Type /Page /Parent 2 0 R /MediaBox [0 0 {_f(self.width)} {_f(self.height)}] "
             "/Resources << /Font << /F1 5 0 R /F2 6 0 R >> >> /Contents 4 0 R >>").encode(),
            f"<< /Length {len(content)} /Filter /FlateDecode >>\nstream\n".encode() + content + b"\nendstream",
            b"<< /Type /Font /Subtype /Type1 /BaseFont /Helvetica /Encoding /WinAnsiEncoding >>",
            b"<< /Type /Font /Subtype /Type1 /BaseFont /Helvetica-Bold /Encoding /WinAnsiEncoding >>",
        ]
        pdf = bytearray(b"%PDF-1.4\n%\xe2\xe3\xcf\xd3\n")
        offsets = []
        for i, body in enumerate(objects):
            offsets.append(len(pdf))
            pdf += f"{i + 1} 0 obj\n".encode() + body + b"\nendobj\n"
        xref = len(pdf)
        pdf += f"xref\n0 {len(objects) + 1}\n0000000000 65535 f \n".encode()
        for off in offsets:
            pdf += f"{off:010d} 00000 n \n".encode()
        pdf += f"trailer\n<< /Size {len(objects) + 1} /Root 1 0 R >>\nstartxref\n{xref}\n%%EOF\n".encode()
        return bytes(pdf)
