"""The main view of a thread part's sheet: the complete part's axial section, both halves
hatched, threads and gears in their conventional representation
(:mod:`prs_geom.geometry.part_sections`), with its annotation (model space, X = z in the
part frame, Y = the radius, mm):

* every diameter of the section as a vertical DIMENSION across the part, its text above
  the view with a leader; the functional features carry their ISO 286 zone and limits
  (:func:`~prs_geom.exports.sheet_items.limits_text`), the others are general tolerances;
* the datum features: A the axial face, B (and C) the datum cylinders (ISO 5459);
* the feature control frames (ISO 1101) of :func:`geometric_tolerances`;
* running dimensions of every step from the left end face (the last is the overall length).

Texts sit above and below the part, never on it: the rows of
:class:`~prs_geom.exports.sheet_items.LabelRows` start a clearance :data:`CLEAR` (paper mm)
beyond the largest radius.
"""
from __future__ import annotations

from dataclasses import dataclass

from prs_geom.exports.sheet import TEXT_H, dim_override
from prs_geom.exports.sheet_items import (COAXIALITY, PERPENDICULARITY, RUNOUT, LabelRows, callout_override,
                                          datum_symbol, diameter_callout, dimension_text_width, feature_frame,
                                          frame_width, running_dimensions, tolerance_override)
from prs_geom.geometry.part_sections import PartSection, merged_cells, outline_polygons
from prs_geom.model.design import PRSDesign
from prs_geom.model.standards import tolerance_zone

__all__ = ["CLEAR", "GEOMETRIC_TOLERANCES_MM", "KEYWAY_WIDTH_ZONE", "FrameSpec", "geometric_tolerances",
           "diameter_labels", "draw_part_view", "draw_drive_section", "keyway_depth_limits"]

#: Clearance (paper mm) between the part's outline and the nearest text row.
CLEAR = 6.0
#: The geometric tolerances the sheets give (mm), prs_geom's defaults for a precision PRS:
#: circular run-out of the pitch cylinder and of the gear tips to the datum axis,
#: perpendicularity of face A to it, coaxiality of the other journals and bores.
GEOMETRIC_TOLERANCES_MM = {"runout pitch": {"screw": 0.01, "roller": 0.005, "nut": 0.01},
                           "runout gear": 0.01, "perpendicularity": 0.005, "coaxiality": 0.01}


@dataclass(frozen=True)
class FrameSpec:
    """One feature control frame: the cells (symbol, tolerance, datum), and the toleranced
    feature's anchor (z, r) in the section (r > 0: upper outline)."""

    cells: tuple[str, ...]
    anchor: tuple[float, float]
    what: str


def _datum_ref(sec: PartSection) -> str:
    return "B-C" if len(sec.datum_axis) == 2 else "B"


def geometric_tolerances(sec: PartSection) -> list[FrameSpec]:
    """The feature control frames of a part (module doc)."""
    g = GEOMETRIC_TOLERANCES_MM
    ref = _datum_ref(sec)
    thread = next(t for t in sec.toothed if t.name == "thread")
    zmid = 0.5 * (thread.z[0] + thread.z[1])
    out = [FrameSpec((RUNOUT, f"{g['runout pitch'][sec.part]:g}", ref), (zmid + 0.25 * (thread.z[1] - thread.z[0]),
                                                                          thread.crest_radius), "pitch cylinder")]
    gears = [t for t in sec.toothed if t.name != "thread"]
    if gears:
        t = gears[-1]
        out.append(FrameSpec((RUNOUT, f"{g['runout gear']:g}", ref), (0.5 * (t.z[0] + t.z[1]), t.crest_radius),
                             "gear tip"))
    out.append(FrameSpec((PERPENDICULARITY, f"{g['perpendicularity']:g}", ref),
                         (sec.datum_face_z, sec.datum_face_radius[1]), "face A"))
    coaxial = [f for f in sec.features if f.symbol and f.name not in sec.datum_axis
               and f.name in ("drive journal", "end bore")]
    if len(sec.datum_axis) == 2 and sec.part == "roller":
        coaxial = [sec.feature(sec.datum_axis[1])]
    for f in coaxial[:1]:
        out.append(FrameSpec((COAXIALITY, f"\u00d8{g['coaxiality']:g}", "B" if sec.part == "roller" else ref),
                             (f.z, 0.5 * f.diameter_mm), f.name))
    return out


def diameter_labels(design: PRSDesign, sec: PartSection) -> list[tuple[float, float, str, bool, object]]:
    """Every diameter the view dimensions: (z, radius, DIMPOST pattern with ``<>`` for the
    measured size, internal, ISO 286 zone or None). The features of ``sec`` first (their
    zone where they have one), then each remaining step of the outline (a general
    tolerance), the locknut thread by its designation."""
    out: list[tuple[float, float, str, bool, object]] = []
    seen: set[tuple[float, bool]] = set()
    for f in sec.features:
        zone = tolerance_zone(f.diameter_mm, f.symbol) if f.symbol else None
        count = f"{f.count}x " if f.count > 1 else ""
        what = "pitch " if f.name == "pitch diameter" else ""
        out.append((f.z, 0.5 * f.diameter_mm, f"{count}{what}%%c<> {f.symbol}".rstrip(),
                    f.internal, zone))
        seen.add((round(f.diameter_mm, 6), f.internal))
    for z0, z1, r, internal, name in _visible_radii(sec):
        thread = name.startswith("locknut thread M")
        if (round(2.0 * r, 6), internal) in seen and not thread:
            continue
        if internal and any(t.crest_radius == r for t in sec.toothed if t.name == "thread"):
            text = "%%c<> minor"
        elif thread:
            text = f"{name.split()[-1]}-{_locknut_class(design)}"
        else:
            text = "%%c<>"
        seen.add((round(2.0 * r, 6), internal))
        out.append((0.5 * (z0 + z1), r, text, internal, None))
    return out


def _visible_radii(sec: PartSection) -> list[tuple[float, float, float, bool, str]]:
    """The radii the section's outline shows: per cell of the union its outer radius and
    (not on the axis) its inner radius, as (z0, z1, r, internal, the zone's name), the
    longest cell of a radius first."""
    out = []
    for z0, z1, spans in merged_cells(sec.zones):
        mid = 0.5 * (z0 + z1)
        for r, internal in ((spans[-1][1], False), (spans[0][0], True)):
            if r <= 0.0:
                continue
            name = next((z.name for z in sec.zones if z.z[0] <= mid <= z.z[1]
                         and (z.r_outer if not internal else z.r_inner) == r), "")
            out.append((z0, z1, r, internal, name))
    return sorted(out, key=lambda t: t[0] - t[1])


def _locknut_class(design: PRSDesign) -> str:
    return design.actuator.fixed_end.locknut_tolerance


def _surface(sec: PartSection):
    cells = merged_cells(sec.zones)

    def lower(x: float) -> float:
        for z0, z1, spans in cells:
            if z0 - 1e-9 <= x <= z1 + 1e-9:
                return -max(b for _, b in spans)
        return 0.0

    return lower


def draw_part_view(msp, design: PRSDesign, sec: PartSection, s: float, hatch) -> dict[str, float]:
    """Draw the view (module doc) at scale ``s`` into model space ``msp``; ``hatch(msp,
    boundary, s)`` fills a closed boundary. Returns its extent {"top", "bottom", "left",
    "right"} (model mm)."""
    k = 1.0 / s
    _outline(msp, sec, hatch, s, k)
    R = sec.outer_radius
    z0, z1 = sec.z_span
    zc = 0.5 * (z0 + z1)
    half = max(0.5 * (z1 - z0) + 30.0 * k, 150.0 * k)
    h = TEXT_H * k
    rows = LabelRows(R + CLEAR * k, 2.2 * h, 3.0 * k, x_min=zc - half, x_max=zc + half, row_cost=40.0 * k)
    ov = {**dim_override(s, 4), "dimzin": 8}
    for z, r, text, _, zone in sorted(diameter_labels(design, sec), key=lambda t: t[0]):
        w = dimension_text_width(callout_override(ov, text, zone), "<>" if "<>" in text else text, 2.0 * r)
        label = rows.place(z, w)
        diameter_callout(msp, z, r, text, label, ov, zone)
    for spec in geometric_tolerances(sec):
        w = frame_width(spec.cells, h)
        cx, cy = rows.place(spec.anchor[0], w)
        feature_frame(msp, (cx, cy), spec.cells, h)
        msp.add_line((cx, cy - h), spec.anchor, dxfattribs={"layer": "TEXT"})
    _datums(msp, sec, rows, h)
    below = -R - CLEAR * k
    # the last running dimension is the overall length
    lowest = running_dimensions(msp, z0, _stations(sec), below, _surface(sec), h)
    return {"top": rows.extent + h, "bottom": lowest, "left": zc - half, "right": zc + half}


def _stations(sec: PartSection) -> list[float]:
    zs = {c[0] for c in merged_cells(sec.zones)} | {c[1] for c in merged_cells(sec.zones)}
    zs |= {t.z[0] for t in sec.toothed} | {t.z[1] for t in sec.toothed}
    return sorted(zs)


def _outline(msp, sec: PartSection, hatch, s: float, k: float) -> None:
    """Outlines (both halves), hatching, thread and gear lines, the centre line."""
    for poly in outline_polygons(sec.zones):
        if sec.hollow or any(r == 0.0 for _, r in poly) is False:
            halves = [poly, [(z, -r) for z, r in poly]]
        else:
            top = [(z, r) for z, r in poly if r > 0.0]
            halves = [top + [(z, -r) for z, r in reversed(top)]]
        for pts in halves:
            msp.add_lwpolyline(pts, close=True, dxfattribs={"layer": "OUTLINE"})
            hatch(msp, [(x, y, 0.0) for x, y in pts], s)
    for t in sec.toothed:
        for sign in (1.0, -1.0):
            msp.add_line((t.z[0], sign * t.root_radius), (t.z[1], sign * t.root_radius), dxfattribs={"layer": "THIN"})
            if t.reference_radius is not None:
                msp.add_line((t.z[0] - 1.0 * k, sign * t.reference_radius), (t.z[1] + 1.0 * k, sign * t.reference_radius),
                             dxfattribs={"layer": "CENTER", "ltscale": 0.5 * k})
        if t.name == "thread":          # the thread's length limits (ISO 6410-1: a thick line)
            for z in t.z:
                for sign in (1.0, -1.0):
                    msp.add_line((z, sign * t.root_radius), (z, sign * t.crest_radius), dxfattribs={"layer": "OUTLINE"})
    z0, z1 = sec.z_span
    msp.add_line((z0 - 6.0 * k, 0.0), (z1 + 6.0 * k, 0.0), dxfattribs={"layer": "CENTER", "ltscale": 4.0 * k})


def _datums(msp, sec: PartSection, rows: LabelRows, h: float) -> None:
    """Datum A on face A's upper edge, B (and C) on the datum cylinders' upper outline
    (ISO 5459), their letter boxes in the label rows."""
    face_r = sec.datum_face_radius
    anchors = [("A", (sec.datum_face_z, 0.5 * (face_r[0] + face_r[1])))]
    for letter, name in zip("BC", sec.datum_axis):
        f = sec.feature(name)
        r = 0.5 * f.diameter_mm
        # beside the feature's diameter dimension, on the side away from the part's middle
        shift = 2.5 * h if f.z < 0.5 * sum(sec.z_span) else -2.5 * h
        anchors.append((letter, (f.z + shift, r)))
    for letter, anchor in anchors:
        box = rows.place(anchor[0], 2.0 * h)
        datum_symbol(msp, anchor, letter, box, h)


#: The ISO 286 zone of a DIN 6885-1 shaft keyway's width (normal fit), and the limit
#: deviations (mm) of the depth measured from the journal's far side, d - t1 (DIN 6885-1:
#: t1 + 0.1 for keys up to 22 mm wide, + 0.2 above).
KEYWAY_WIDTH_ZONE = "N9"


def keyway_depth_limits(width_mm: float) -> tuple[float, float]:
    """(upper, lower) deviations (mm) of d - t1 for a key ``width_mm`` wide."""
    return 0.0, (-0.1 if width_mm <= 22.0 else -0.2)


def draw_drive_section(msp, end, origin: tuple[float, float], s: float, hatch) -> str | None:
    """SECTION K-K through the drive journal of screw end ``end`` (a key or a flat), centred
    at ``origin`` in model space, at scale ``s``: the journal's cross-section hatched, the
    keyway's width (ISO 286 N9) and the depth d - t1 (DIN 6885-1 limits), or the flat's
    width across. Returns a note for the sheet, or None when the end has no drive feature."""
    import math

    if end is None or end.key_z is None:
        return None
    journal = next(st for st in end.steps if st.name == "drive journal")
    r = 0.5 * journal.diameter_mm
    cx, cy = origin
    ov = {**dim_override(s, 4), "dimzin": 8}
    k = 1.0 / s
    if end.key is not None:
        b, t1 = end.key.width_mm, end.key.shaft_depth_mm
        y_edge = math.sqrt(r * r - 0.25 * b * b)
        # clockwise (negative bulge) from the keyway's right edge round the bottom to its left edge
        arc = 2.0 * math.pi - 2.0 * math.asin(0.5 * b / r)
        pts = [(cx + 0.5 * b, cy + y_edge, -math.tan(0.25 * arc)), (cx - 0.5 * b, cy + y_edge, 0.0),
               (cx - 0.5 * b, cy + r - t1, 0.0), (cx + 0.5 * b, cy + r - t1, 0.0)]
        zone = tolerance_zone(b, KEYWAY_WIDTH_ZONE)
        msp.add_linear_dim(base=(cx, cy + r + 8.0 * k), p1=(cx - 0.5 * b, cy + y_edge), p2=(cx + 0.5 * b, cy + y_edge),
                           text="<>", override={**ov, "dimpost": f"<> {KEYWAY_WIDTH_ZONE}", **tolerance_override(zone)},
                           dxfattribs={"layer": "DIMENSIONS"}).render()
        up, lo = keyway_depth_limits(b)
        msp.add_linear_dim(base=(cx + r + 10.0 * k, cy), p1=(cx + 0.5 * b, cy + r - t1), p2=(cx, cy - r), angle=90.0,
                           text="<>", override={**ov, "dimpost": "<> (d - t1)", "dimtol": 1, "dimtp": up, "dimtm": -lo,
                                                "dimtdec": 1, "dimtzin": 8, "dimtfac": 0.7},
                           dxfattribs={"layer": "DIMENSIONS"}).render()
        note = f"Keyway DIN 6885-1 for key {end.key.designation(end.key_z[1] - end.key_z[0])}"
    else:
        f = end.flat_depth_mm
        y_edge = r - f
        half = math.sqrt(r * r - y_edge * y_edge)
        arc = 2.0 * math.pi - 2.0 * math.asin(half / r)
        pts = [(cx + half, cy + y_edge, -math.tan(0.25 * arc)), (cx - half, cy + y_edge, 0.0)]
        msp.add_linear_dim(base=(cx + r + 10.0 * k, cy), p1=(cx + half, cy + y_edge), p2=(cx, cy - r), angle=90.0,
                           text="<> across the flat", override=ov, dxfattribs={"layer": "DIMENSIONS"}).render()
        note = f"Drive flat {f:g} deep"
    msp.add_lwpolyline(pts, format="xyb", close=True, dxfattribs={"layer": "DETAIL"})
    hatch(msp, pts, s)
    for dx, dy in ((1.0, 0.0), (0.0, 1.0)):
        msp.add_line((cx - dx * (r + 3 * k), cy - dy * (r + 3 * k)), (cx + dx * (r + 3 * k), cy + dy * (r + 3 * k)),
                     dxfattribs={"layer": "CENTER", "ltscale": 1.0 * k})
    return f"{note}, {end.key_z[1] - end.key_z[0]:g} long, centred on the drive journal (SECTION K-K)"
