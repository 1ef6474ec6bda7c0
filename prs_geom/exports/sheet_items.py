"""The annotation items the part sheets share (DXF, ezdxf): diameter callouts with ISO 286
limits, ISO 1101 feature control frames, ISO 5459 datum feature symbols, running
dimensions, data tables, the ISO 5456-2 projection symbol, and the rows that keep labels
apart.

Model-space items are sized for a view scale ``s`` (paper mm = s x model mm): a text of
:data:`~prs_geom.exports.sheet.TEXT_H` on paper is ``TEXT_H / s`` high in the model. Widths
are measured in the pinned font (:data:`~prs_geom.exports.sheet.DRAWING_FONT`), so that the
rows that keep labels apart hold on every machine.

Conventions:

* a limit callout reads ``[2x ]Ø<size> <zone> (<upper>/<lower>)``: the zone symbol
  (ISO 286-1) and its limit deviations in mm, "0" for a zero deviation, so that a shop
  reads both the zone and the limits without a table;
* a feature control frame is a row of boxes: the characteristic's symbol (↗ circular
  run-out, ⊥ perpendicularity, ◎ coaxiality), the tolerance value (Ø before it for a
  cylindrical zone) and the datum reference (``B-C``, a common datum of two cylinders).
"""
from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence

from prs_geom.exports.sheet import TEXT_H, pin_drawing_font

__all__ = ["RUNOUT", "PERPENDICULARITY", "COAXIALITY", "text_width", "deviation_text", "limits_text",
           "LabelRows", "tolerance_override", "callout_override", "diameter_callout", "feature_frame", "frame_width", "datum_symbol", "running_dimensions", "table", "table_widths",
           "projection_symbol", "TABLE_H", "TABLE_ROW", "mtext_width", "dimension_text_width"]

RUNOUT = "\u2197"            # ↗ circular run-out (ISO 1101)
PERPENDICULARITY = "\u22a5"  # ⊥
COAXIALITY = "\u25ce"        # ◎
#: Text height (paper mm) and row pitch of the data tables.
TABLE_H = 2.5
TABLE_ROW = 4.0


def text_width(text: str, height: float) -> float:
    """Width (same unit as ``height``) of ``text`` in the pinned font; the DXF escape ``%%c``
    counts as the diameter sign it stands for."""
    from ezdxf.fonts import fonts

    return fonts.make_font(pin_drawing_font(), height, 1.0).text_width(text.replace("%%c", "\u00d8"))


@functools.cache
def _scratch():
    """A scratch DXF document (pinned font) to render and measure dimension texts in."""
    import ezdxf

    from prs_geom.exports.sheet import use_drawing_font

    doc = ezdxf.new("R2010", setup=True)
    use_drawing_font(doc)
    return doc


def mtext_width(content: str, height: float) -> float:
    """Width of an MTEXT of ``content`` at ``height`` as ezdxf's text-size tool measures it
    (the measure the drawings' text-box checks use: a DXF escape such as ``%%c`` and a
    stacked fraction count as their characters in line)."""
    from ezdxf.tools import text_size

    msp = _scratch().modelspace()
    m = msp.add_mtext(content, dxfattribs={"char_height": height, "style": "Standard"})
    width = text_size.mtext_size(m).total_width
    msp.delete_entity(m)
    return width


def dimension_text_width(override: dict, text: str, length: float) -> float:
    """Width (model mm) of the text a linear DIMENSION of ``length`` with ``override`` and
    ``text`` renders, measured as :func:`mtext_width` does (rendered in a scratch document)."""
    msp = _scratch().modelspace()
    dim = msp.add_linear_dim(base=(0.0, 0.0), p1=(0.0, 0.0), p2=(length, 0.0), text=text, override=override)
    dim.render()
    from ezdxf.tools import text_size

    width = max((text_size.mtext_size(e).total_width for e in dim.dimension.virtual_entities()
                 if e.dxftype() == "MTEXT"), default=0.0)
    msp.delete_entity(dim.dimension)
    return width


def deviation_text(mm: float, decimals: int = 3) -> str:
    """A limit deviation as the sheets print it: "0", or signed with ``decimals`` decimals
    (three: whole micrometres, as ISO 286 tabulates them)."""
    steps = round(mm * 10 ** decimals)
    return "0" if steps == 0 else f"{steps / 10 ** decimals:+.{decimals}f}"


def limits_text(symbol: str, zone) -> str:
    """``"<zone> (<upper>/<lower>)"`` of an ISO 286 :class:`ToleranceZone` ``zone``."""
    return f"{symbol} ({deviation_text(zone.upper_mm)}/{deviation_text(zone.lower_mm)})"


class LabelRows:
    """Horizontal rows of labels above (``sign`` +1) or below (-1) a view, the first at
    ``y0``, ``pitch`` apart (model mm), between ``x_min`` and ``x_max``: each label goes
    where it keeps ``gap`` clear of the labels already placed, as close to its anchor as it
    can; a row further out costs ``row_cost`` of sideways shift."""

    def __init__(self, y0: float, pitch: float, gap: float, sign: int = 1, x_min: float = -math.inf,
                 x_max: float = math.inf, row_cost: float = 0.0) -> None:
        self.y0, self.pitch, self.gap, self.sign = y0, pitch, gap, sign
        self.x_min, self.x_max, self.row_cost = x_min, x_max, row_cost
        self.rows: list[list[tuple[float, float]]] = []

    def _nearest(self, taken: list[tuple[float, float]], x: float, width: float) -> float | None:
        """The centre nearest ``x`` where a label of ``width`` fits in a row holding ``taken``."""
        half = 0.5 * width + self.gap
        lo, hi = self.x_min + half, self.x_max - half
        if lo > hi:
            return None
        edges = sorted(taken)
        free, start = [], -math.inf
        for a, b in edges:
            free.append((start, a - half))
            start = max(start, b + half)
        free.append((start, math.inf))
        best = None
        for a, b in free:
            a, b = max(a, lo), min(b, hi)
            if a > b:
                continue
            c = min(max(x, a), b)
            if best is None or abs(c - x) < abs(best - x):
                best = c
        return best

    def place(self, x: float, width: float) -> tuple[float, float]:
        """Centre (x, y) of a label of ``width`` anchored at ``x``."""
        best: tuple[float, int, float] | None = None
        for i in range(len(self.rows) + 1):
            taken = self.rows[i] if i < len(self.rows) else []
            c = self._nearest(taken, x, width)
            if c is None:
                continue
            cost = abs(c - x) + i * self.row_cost
            if best is None or cost < best[0] - 1e-9:
                best = (cost, i, c)
        if best is None:
            raise ValueError("a label is wider than the view")
        _, i, c = best
        if i == len(self.rows):
            self.rows.append([])
        self.rows[i].append((c - 0.5 * width, c + 0.5 * width))
        return c, self.y0 + self.sign * i * self.pitch

    @property
    def extent(self) -> float:
        """y of the last row used."""
        return self.y0 + self.sign * max(len(self.rows) - 1, 0) * self.pitch


def tolerance_override(zone) -> dict:
    """DIMENSION style overrides that print an ISO 286 zone's limit deviations (mm) after
    the measurement, stacked (DIMTOL): the deviations live in the DIMENSION as data
    (DIMTP, DIMTM) that a CAD program reads, not only as text."""
    return {"dimtol": 1, "dimtp": zone.upper_mm, "dimtm": -zone.lower_mm, "dimtdec": 3, "dimtzin": 8,
            "dimtfac": 0.7}


def callout_override(override: dict, text: str, zone=None) -> dict:
    """The style override of :func:`diameter_callout`'s DIMENSION."""
    ov = {**override, "dimtmove": 2, "dimtih": 1, "dimtoh": 1, **({"dimpost": text} if "<>" in text else {})}
    if zone is not None:
        ov.update(tolerance_override(zone))
    return ov


def diameter_callout(msp, z: float, radius: float, text: str, label: tuple[float, float], override: dict,
                     zone=None) -> None:
    """A vertical DIMENSION of the diameter 2 ``radius`` at ``z`` (the dimension line across
    the part, arrows on the surface) whose text stands at ``label``, joined to the dimension
    line's end by a leader (layer DIMENSIONS). ``text`` is the DIMPOST pattern, ``<>`` the
    measured size (e.g. ``"2x %%c<> h11"``); with ``zone`` (an ISO 286
    :class:`~prs_geom.model.standards.ToleranceZone`) its limit deviations follow
    (:func:`tolerance_override`). The DIMENSION's own text stays ``<>``: the first number a
    reader finds in it is the measurement. A ``text`` without ``<>`` (a thread designation
    such as "M20x1-6g", whose first number is the size) is the DIMENSION's text itself."""
    post = "<>" in text
    ov = callout_override(override, text, zone)
    msp.add_linear_dim(base=(z, 0.0), p1=(z, -radius), p2=(z, radius), angle=90.0, text="<>" if post else text,
                       location=label,
                       override=ov, dxfattribs={"layer": "DIMENSIONS"}).render()
    y_end = radius if label[1] > 0 else -radius
    h = override["dimtxt"] * override["dimscale"]
    y_text = label[1] - math.copysign(0.7 * h, label[1])
    msp.add_line((z, y_end), (label[0], y_text), dxfattribs={"layer": "DIMENSIONS"})


def feature_frame(msp, centre: tuple[float, float], cells: Sequence[str], h: float) -> tuple[float, float]:
    """An ISO 1101 feature control frame centred at ``centre``: one box per cell (text
    height ``h``, model mm), returned as (width, height) of the frame."""
    widths = [max(text_width(c, h) + 1.2 * h, 2.0 * h) for c in cells]
    W, H = sum(widths), 2.0 * h
    x = centre[0] - 0.5 * W
    y0, y1 = centre[1] - 0.5 * H, centre[1] + 0.5 * H
    msp.add_lwpolyline([(x, y0), (x + W, y0), (x + W, y1), (x, y1)], close=True, dxfattribs={"layer": "TEXT"})
    from ezdxf.enums import TextEntityAlignment

    for c, w in zip(cells, widths):
        msp.add_text(c, height=h, dxfattribs={"layer": "TEXT"}).set_placement(
            (x + 0.5 * w, centre[1]), align=TextEntityAlignment.MIDDLE_CENTER)
        x += w
        if x < centre[0] + 0.5 * W - 1e-9:
            msp.add_line((x, y0), (x, y1), dxfattribs={"layer": "TEXT"})
    return W, H


def frame_width(cells: Sequence[str], h: float) -> float:
    """Width of :func:`feature_frame`'s frame for ``cells`` at text height ``h``."""
    return sum(max(text_width(c, h) + 1.2 * h, 2.0 * h) for c in cells)


def datum_symbol(msp, anchor: tuple[float, float], letter: str, box_centre: tuple[float, float], h: float) -> None:
    """An ISO 5459 datum feature symbol: a filled triangle on the feature at ``anchor``
    (pointing at it from the side of ``box_centre``), a line to a square box with
    ``letter`` at ``box_centre``; text height ``h`` (model mm)."""
    from ezdxf.enums import TextEntityAlignment

    dx, dy = box_centre[0] - anchor[0], box_centre[1] - anchor[1]
    n = math.hypot(dx, dy)
    ux, uy = dx / n, dy / n
    t = 0.8 * h
    base = (anchor[0] + ux * t, anchor[1] + uy * t)
    tri = [(base[0] - uy * 0.6 * t, base[1] + ux * 0.6 * t), (base[0] + uy * 0.6 * t, base[1] - ux * 0.6 * t),
           anchor]
    msp.add_solid([tri[0], tri[1], tri[2]], dxfattribs={"layer": "TEXT"})
    b = 2.0 * h
    edge = (box_centre[0] - ux * 0.5 * b, box_centre[1] - uy * 0.5 * b)
    msp.add_line(base, edge, dxfattribs={"layer": "TEXT"})
    x0, y0 = box_centre[0] - 0.5 * b, box_centre[1] - 0.5 * b
    msp.add_lwpolyline([(x0, y0), (x0 + b, y0), (x0 + b, y0 + b), (x0, y0 + b)], close=True,
                       dxfattribs={"layer": "TEXT"})
    msp.add_text(letter, height=h, dxfattribs={"layer": "TEXT"}).set_placement(
        box_centre, align=TextEntityAlignment.MIDDLE_CENTER)


def running_dimensions(msp, origin: float, stations: Sequence[float], y_row: float, surface: Callable[[float], float],
                       h: float) -> float:
    """ISO 129-1 running dimensions along X below a view: the origin (a small circle at
    ``origin``), an extension line from the part's lower outline (``surface(x)``, a y) down
    to the row ``y_row`` at each station, and each station's distance from the origin as a
    text turned 90 deg below the row, moved sideways (with a jog) where stations are closer
    than a text height. Returns the lowest y the texts reach (model mm)."""
    from ezdxf.enums import TextEntityAlignment

    xs = sorted(stations)
    step = 1.6 * h
    placed = list(xs)
    for i in range(1, len(placed)):
        placed[i] = max(placed[i], placed[i - 1] + step)
    overshoot = placed[-1] - xs[-1] if placed else 0.0
    if overshoot > 0:                   # centre the spread block on the stations
        placed = [p - 0.5 * overshoot for p in placed]
        for i in range(1, len(placed)):
            placed[i] = max(placed[i], placed[i - 1] + step)
    msp.add_circle((origin, y_row), radius=0.4 * h, dxfattribs={"layer": "DIMENSIONS"})
    lowest = y_row
    for x, xt in zip(xs, placed):
        msp.add_line((x, surface(x) - 0.3 * h), (x, y_row), dxfattribs={"layer": "DIMENSIONS"})
        jog = y_row - 1.2 * h
        msp.add_line((x, y_row), (xt, jog), dxfattribs={"layer": "DIMENSIONS"})
        if abs(x - origin) < 1e-9:
            continue
        label = f"{x - origin:.2f}".rstrip("0").rstrip(".")
        msp.add_text(label, height=h, rotation=90.0, dxfattribs={"layer": "DIMENSIONS"}).set_placement(
            (xt, jog - 0.3 * h), align=TextEntityAlignment.MIDDLE_RIGHT)
        lowest = min(lowest, jog - 0.3 * h - text_width(label, h))
    return lowest


def table_widths(rows: Sequence[Sequence[str]], h: float = TABLE_H) -> tuple[float, ...]:
    """Column widths (mm) that hold every cell of ``rows`` at text height ``h`` with 1 mm
    either side."""
    return tuple(max(text_width(row[c], h) for row in rows) + 2.5 for c in range(len(rows[0])))


def table(psp, x0: float, y_top: float, title: str, rows: Sequence[Sequence[str]],
          widths: Sequence[float] | None = None, h: float = TABLE_H, pitch: float = TABLE_ROW) -> float:
    """A data table in paper space: ``title`` above (none when empty), then one ruled row
    per tuple of cells, columns ``widths`` wide (mm; measured from the texts when None).
    Returns the table's lower edge (mm)."""
    ws = list(widths) if widths is not None else list(table_widths(rows, h))
    xs = [x0]
    for w in ws:
        xs.append(xs[-1] + w)
    if title:
        psp.add_text(title, height=TEXT_H, dxfattribs={"layer": "TEXT"}).set_placement((x0, y_top - TEXT_H))
    y = y_top - TEXT_H - 2.0
    top = y
    for row in rows:
        for x, cell in zip(xs, row):
            if cell:
                psp.add_text(cell, height=h, dxfattribs={"layer": "TEXT"}).set_placement((x + 1.0, y - 0.75 * pitch))
        y -= pitch
        psp.add_line((x0, y), (xs[-1], y), dxfattribs={"layer": "TITLE"})
    for x in xs:
        psp.add_line((x, top), (x, y), dxfattribs={"layer": "TITLE"})
    psp.add_line((x0, top), (xs[-1], top), dxfattribs={"layer": "TITLE"})
    return y


def projection_symbol(psp, x: float, y: float, size: float = 6.0) -> None:
    """The ISO 5456-2 symbol of first-angle projection with its lower left corner at (x, y)
    (paper mm): a truncated cone's side view, and right of it its view from the left (two
    circles), the centre lines through both."""
    d, D = 0.5 * size, size
    L = 1.2 * size
    cy = y + 0.5 * D
    psp.add_lwpolyline([(x, cy - 0.5 * d), (x + L, cy - 0.5 * D), (x + L, cy + 0.5 * D), (x, cy + 0.5 * d)],
                       close=True, dxfattribs={"layer": "TITLE"})
    cx = x + L + 0.4 * size + 0.5 * D
    psp.add_circle((cx, cy), 0.5 * D, dxfattribs={"layer": "TITLE"})
    psp.add_circle((cx, cy), 0.5 * d, dxfattribs={"layer": "TITLE"})
    psp.add_line((x - 1.0, cy), (cx + 0.5 * D + 1.0, cy), dxfattribs={"layer": "CENTER"})
    psp.add_line((cx, cy - 0.5 * D - 1.0), (cx, cy + 0.5 * D + 1.0), dxfattribs={"layer": "CENTER"})
