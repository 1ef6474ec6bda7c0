"""Drawing sheets as PDF pages: an ezdxf drawing back end that writes PDF path operators.

ezdxf's drawing front end turns a paper-space layout into lines, paths and filled paths
(texts as glyph outlines from its font engine, hatches as line segments, line types as
dashes, everything clipped to the viewports); :class:`PdfSheetBackend` writes each call as
PDF content-stream operators and :func:`pdf_document` puts the pages in a PDF 1.4 file
(ISO 32000-1) of its own making, so the sheets need neither matplotlib nor a PDF library.

Conventions
-----------
* Coordinates: the page's user space is paper space scaled by ``cm`` to micrometres: every
  coordinate is written as an integer number of micrometres on paper (mm x 1000, rounded),
  so a drawn point is within 0.5 um of the DXF's. The page is the sheet (A3 landscape,
  :data:`~prs_geom.exports.sheet.SHEET`), origin bottom left, as in paper space.
* Line widths: the DXF lineweight of each entity (ISO 128-20: 0.5 mm outlines, 0.35 mm title
  block, 0.25 mm dimensions and centre lines, 0.18 mm hatching and thread roots) at true
  size, at least :data:`MIN_LINE_WIDTH_MM`; butt caps, so that a dash is as long as the line
  type says (round caps would close the gaps of a centre line drawn at 0.25 mm), round joins
  within a path, and a path that ends where it starts is closed (``h``), so that its first
  corner is a join too; a dot of a line type (a zero-length dash) is a round dot of the line
  width; a segment shorter than 1 um is not drawn.
* Fills: even-odd (``f*``), the rule ezdxf's front end draws holes by (a glyph's counters).
* The bytes depend only on the drawings: no date, no producer version, streams compressed
  with zlib at a fixed level.
"""
from __future__ import annotations

import zlib
from typing import Iterable

import numpy as np
from ezdxf.addons.drawing.backend import Backend, BkPath2d, BkPoints2d, ImageData
from ezdxf.addons.drawing.properties import BackendProperties
from ezdxf.math import Vec2
from numpy.typing import NDArray

__all__ = ["MIN_LINE_WIDTH_MM", "PdfSheetBackend", "pdf_document"]

#: Thinnest line drawn (mm on paper): a hairline of lineweight 0 prints at this width.
MIN_LINE_WIDTH_MM = 0.13
#: PDF points per micrometre (1 pt = 25.4/72 mm).
_PT_PER_UM = 72.0 / 25400.0
#: zlib level of the content streams: fixed, so that the bytes are too.
_ZLIB_LEVEL = 6

# ezdxf path command codes (ezdxf.path.Command) and the vertices each one stores
_LINE_TO, _CURVE3_TO, _CURVE4_TO, _MOVE_TO = 1, 2, 3, 4
_VERTICES = np.array([0, 1, 2, 3, 1])


#: Largest coordinate magnitude (um): a PDF integer is at most 2^31 - 1 (ISO 32000-1, Annex C).
_MAX_UM = 2 ** 31 - 1


def _um(xy: NDArray[np.float64]) -> NDArray[np.int64]:
    """Paper mm -> integer micrometres, to the nearest; ValueError for a coordinate that is
    not finite or not a PDF integer (|x| > 2147 m: a drawing gone wrong, never a sheet)."""
    um = np.rint(np.asarray(xy, dtype=np.float64) * 1000.0)
    if not np.all(np.abs(um) <= _MAX_UM):          # NaN fails this too
        bad = np.asarray(xy, dtype=np.float64).ravel()[~(np.abs(um.ravel()) <= _MAX_UM)][0]
        raise ValueError(f"drawing coordinate {bad!r} mm: not finite or beyond the PDF integer range")
    return um.astype(np.int64)


def path_operators(paths: Iterable[BkPath2d]) -> str:
    """The PDF path construction operators (``m``, ``l``, ``c``, ``h``) of ezdxf paths, in
    micrometres on paper; each path starts a subpath at its start point, and a subpath that
    ends where it starts is closed.

    ezdxf stores a quadratic Bezier as (control, end) after the start point; PDF has cubic
    curves only, so a quadratic from p0 is written as the cubic of the same curve: control
    points p0 + 2/3 (c - p0) and p1 + 2/3 (c - p1) (degree elevation, exact).
    """
    codes_list: list[NDArray] = []
    verts_list: list[NDArray] = []
    for path in paths:
        if len(path) == 0 and len(path.np_vertices()) == 0:
            continue
        codes_list.append(np.concatenate([[_MOVE_TO], np.asarray(path.command_codes(), dtype=np.int64)]))
        verts_list.append(path.np_vertices()[:, :2])
    if not codes_list:
        return ""
    codes = np.concatenate(codes_list)
    verts = np.concatenate(verts_list).astype(np.float64)
    counts = _VERTICES[codes]
    first = np.cumsum(counts) - counts                  # index of each command's first vertex
    out_counts = np.where(codes == _CURVE3_TO, 3, counts)
    out = np.empty((int(out_counts.sum()), 2))
    out_first = np.cumsum(out_counts) - out_counts
    simple = codes != _CURVE3_TO
    # each command's vertices in order, the quadratics' replaced below
    ramp = _ramp(counts[simple])
    out[np.repeat(out_first[simple], counts[simple]) + ramp] = verts[np.repeat(first[simple], counts[simple]) + ramp]
    quad = np.flatnonzero(~simple)
    if len(quad):
        p0, c, p1 = verts[first[quad] - 1], verts[first[quad]], verts[first[quad] + 1]
        out[out_first[quad]] = p0 + 2.0 / 3.0 * (c - p0)
        out[out_first[quad] + 1] = p1 + 2.0 / 3.0 * (c - p1)
        out[out_first[quad] + 2] = p1
    um = _um(out)
    # a space after a coordinate pair, the operator and a line break after a command's last
    last = out_first + out_counts - 1
    suffix = np.full(len(out), " ", dtype=object)
    suffix[last] = np.array(["", " l\n", " c\n", " c\n", " m\n"], dtype=object)[codes]
    # a subpath that ends where it starts is closed with h: its first corner is then a join
    # like the others, not two butt ends
    starts = np.flatnonzero(codes == _MOVE_TO)
    ends = np.append(starts[1:] - 1, len(codes) - 1)
    closed = (ends > starts) & np.all(um[out_first[starts]] == um[last[ends]], axis=1)
    suffix[last[ends[closed]]] += "h\n"
    return "".join(f"{x} {y}{s}" for (x, y), s in zip(um.tolist(), suffix.tolist()))


def _ramp(counts: NDArray) -> NDArray:
    """0, 1, ..., n-1 for each n of ``counts``, concatenated."""
    total = int(counts.sum())
    return np.arange(total) - np.repeat(np.cumsum(counts) - counts, counts)


def _rgb(color: str) -> str:
    """'#RRGGBB[AA]' -> 'r g b' in [0, 1] (alpha ignored: the sheets are opaque)."""
    r, g, b = (int(color[i:i + 2], 16) / 255.0 for i in (1, 3, 5))
    return f"{r:.4g} {g:.4g} {b:.4g}"


class PdfSheetBackend(Backend):
    """An ezdxf drawing back end that collects one page's PDF content stream.

    Parameters
    ----------
    size_mm
        The page (width, height) in mm; paper-space coordinates are drawn 1:1.
    """

    def __init__(self, size_mm: tuple[float, float]) -> None:
        super().__init__()
        self.size_mm = (float(size_mm[0]), float(size_mm[1]))
        self._ops: list[str] = []
        self._stroke: tuple[str, int] | None = None
        self._fill: str | None = None

    # -- state
    def _stroking(self, properties: BackendProperties) -> None:
        width = max(properties.lineweight * self.config.lineweight_scaling, MIN_LINE_WIDTH_MM)
        state = (_rgb(properties.color), int(round(width * 1000.0)))
        if state != self._stroke:
            self._ops.append(f"{state[0]} RG {state[1]} w\n")
            self._stroke = state

    def _filling(self, properties: BackendProperties) -> None:
        rgb = _rgb(properties.color)
        if rgb != self._fill:
            self._ops.append(f"{rgb} rg\n")
            self._fill = rgb

    # -- BackendInterface
    def set_background(self, color: str) -> None:
        w, h = _um(np.array(self.size_mm)).tolist()
        self._ops.append(f"{_rgb(color)} rg 0 0 {w} {h} re f\n")
        self._fill = None

    def draw_point(self, pos: Vec2, properties: BackendProperties) -> None:
        # a zero-length segment with round caps is a dot of the line width
        self._stroking(properties)
        x, y = _um(np.array([pos.x, pos.y])).tolist()
        self._ops.append(f"1 J {x} {y} m {x} {y} l S 0 J\n")

    def draw_line(self, start: Vec2, end: Vec2, properties: BackendProperties) -> None:
        self.draw_solid_lines([(start, end)], properties)

    def draw_solid_lines(self, lines: Iterable[tuple[Vec2, Vec2]], properties: BackendProperties) -> None:
        ends = np.array([(s.x, s.y, e.x, e.y) for s, e in lines], dtype=np.float64).reshape(-1, 4)
        if not len(ends):
            return
        self._stroking(properties)
        um = _um(ends)
        # a dot is a zero-length segment as ezdxf's back ends tell it (Vec2.isclose); a
        # segment shorter than the 1 um resolution is not drawn
        dots = np.hypot(ends[:, 2] - ends[:, 0], ends[:, 3] - ends[:, 1]) <= 1e-12
        lines = ~dots & ((um[:, 0] != um[:, 2]) | (um[:, 1] != um[:, 3]))
        if lines.any():
            self._ops.append("".join(f"{a} {b} m {c} {d} l\n" for a, b, c, d in um[lines].tolist()) + "S\n")
        if dots.any():
            # the dots of a line type: round caps make a zero-length segment a dot
            self._ops.append("1 J\n" + "".join(f"{a} {b} m {a} {b} l\n" for a, b, _, _ in um[dots].tolist())
                             + "S 0 J\n")

    def draw_path(self, path: BkPath2d, properties: BackendProperties) -> None:
        ops = path_operators([path])
        if ops:
            self._stroking(properties)
            self._ops.append(ops + "S\n")

    def draw_filled_paths(self, paths: Iterable[BkPath2d], properties: BackendProperties) -> None:
        ops = path_operators(paths)
        if ops:
            self._filling(properties)
            self._ops.append(ops + "f*\n")

    def draw_filled_polygon(self, points: BkPoints2d, properties: BackendProperties) -> None:
        xy = points.np_vertices()
        if len(xy) < 3:
            return
        self._filling(properties)
        um = _um(xy[:, :2]).tolist()
        self._ops.append(f"{um[0][0]} {um[0][1]} m\n" + "".join(f"{x} {y} l\n" for x, y in um[1:]) + "h f*\n")

    def draw_image(self, image_data: ImageData, properties: BackendProperties) -> None:
        raise NotImplementedError("the drawing sheets hold no raster images (IMAGE entities)")

    def clear(self) -> None:
        self._ops.clear()
        self._stroke = self._fill = None

    def content(self) -> bytes:
        """The page's content stream (uncompressed): micrometre user space, butt caps and
        round joins, then everything drawn, in drawing order."""
        head = f"q {_PT_PER_UM:.10f} 0 0 {_PT_PER_UM:.10f} 0 0 cm 0 J 1 j\n"
        return (head + "".join(self._ops) + "Q\n").encode("ascii")


def pdf_document(pages: list[tuple[tuple[float, float], bytes]], creator: str = "prs_geom") -> bytes:
    """A PDF 1.4 file of ``pages``: each a ((width, height) mm, content stream) pair.

    Objects: 1 the catalogue, 2 the page tree, 3 the document information (Creator and
    Producer ``creator``, no dates), then a page and its Flate-compressed content per page.
    The cross-reference table gives each object's byte offset (ISO 32000-1, 7.5.4).
    """
    if not pages:
        raise ValueError("a PDF needs at least one page")
    if not creator.isascii() or any(ch in creator for ch in "()\\\r\n"):
        raise ValueError(f"PDF creator {creator!r}: plain ASCII without parentheses, backslashes or line breaks")
    kids = " ".join(f"{4 + 2 * i} 0 R" for i in range(len(pages)))
    objects: list[bytes] = [
        b"<< /Type /Catalog /Pages 2 0 R >>",
        f"<< /Type /Pages /Kids [{kids}] /Count {len(pages)} >>".encode(),
        f"<< /Creator ({creator}) /Producer ({creator}) >>".encode(),
    ]
    for i, ((width, height), stream) in enumerate(pages):
        box = f"0 0 {width * 72.0 / 25.4:.4f} {height * 72.0 / 25.4:.4f}"
        objects.append(f"<< /Type /Page /Parent 2 0 R /MediaBox [{box}] /Resources << >> "
                       f"/Contents {5 + 2 * i} 0 R >>".encode())
        packed = zlib.compress(stream, _ZLIB_LEVEL)
        objects.append(f"<< /Length {len(packed)} /Filter /FlateDecode >>\nstream\n".encode() + packed
                       + b"\nendstream")
    # a binary comment line after the header marks the file as binary to transfer programs
    out = bytearray(b"%PDF-1.4\n%\xe2\xe3\xcf\xd3\n")
    offsets = []
    for number, body in enumerate(objects, start=1):
        offsets.append(len(out))
        out += f"{number} 0 obj\n".encode() + body + b"\nendobj\n"
    xref = len(out)
    out += f"xref\n0 {len(objects) + 1}\n0000000000 65535 f \n".encode()
    out += b"".join(f"{offset:010d} 00000 n \n".encode() for offset in offsets)
    out += f"trailer\n<< /Size {len(objects) + 1} /Root 1 0 R /Info 3 0 R >>\nstartxref\n{xref}\n%%EOF\n".encode()
    return bytes(out)
