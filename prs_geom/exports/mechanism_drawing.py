"""Drawings of the mechanism parts: ``drawing_carrier.dxf``, ``drawing_nut_end.dxf`` and the
assembly drawing ``drawing_assembly.dxf`` with item balloons matching the parts list; each a
page of ``drawings.pdf`` after the thread parts (:func:`write_all_drawings`).

Conventions as :mod:`prs_geom.exports.drawing` (DXF R2010, mm, ISO A3 landscape paper space,
the same layers, text heights, title block and deterministic header), with a layer
BALLOONS. Sizes come from :func:`prs_geom.geometry.mechanism.layout`, so what is dimensioned
is what is meshed and checked (but for the nut ends' 0.1 mm relief on the outside radius,
a meshing device, :data:`~prs_geom.geometry.mechanism.NUT_END_RELIEF_MM`):

* **carrier** (front view and the axial section through roller 0's bore): outside, bore
  and pitch-circle diameters, the journal bore with its ISO 286 hole zone and limits, the
  thickness; the z bores on the carrier angles in a note;
* **nut end** (axial half-section of the lower end, X from the thread end = datum A
  outward, Y the radius): the bore d1, the groove diameter d2 and width m (H13) with its
  position from datum A, the edge distance n, the outside diameter, the end's length;
* **assembly** (axial half-section of every part as its outline, upper half): one balloon
  per parts-list item (item number in a circle, a leader to the part) and the parts list
  table on the sheet.

The design and material names are written as literal text
(:func:`prs_geom.exports.textsafe.dxf_text`; notes wrap to the width measured in the
pinned font, :func:`~prs_geom.exports.sheet.wrap_to_width`, which never cuts an escape).
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from prs_geom._version import __version__
from prs_geom.exports.drawing import PROJECTION_AT, _hatch, _new_doc, _stamp
from prs_geom.exports.sheet import (SHEET, TEXT_H, TITLE_BLOCK, TITLE_H, a3_paper_space, dim_override, iso7200_rows,
                                    part_notes, scale_text, title_block, wrap_to_width)
from prs_geom.exports.sheet_items import projection_symbol, table, tolerance_override
from prs_geom.exports.textsafe import dxf_text
from prs_geom.geometry.mechanism import MechanismLayout
from prs_geom.model.design import PRSDesign
from prs_geom.model.standards import tolerance_zone
from prs_geom.runtime.progress import ProgressFn

__all__ = ["NOTE_SMALL_H", "MECHANISM_DRAWINGS", "BALLOON_D", "SCALES", "VIEW", "ASSEMBLY_HATCH", "carrier_drawing",
           "nut_end_drawing", "assembly_drawing", "balloon_slots", "mechanism_drawings", "write_all_drawings"]

#: Mechanism drawings in sheet order: (key, file name).
MECHANISM_DRAWINGS = (("carrier", "drawing_carrier.dxf"), ("nut_end", "drawing_nut_end.dxf"),
                      ("assembly", "drawing_assembly.dxf"))
#: Balloon circle diameter on paper (mm).
BALLOON_D = 8.0
SCALES = (4.0, 2.0, 1.0, 0.5, 0.25)


def _fit_scale(width: float, height: float, box: tuple[float, float]) -> float:
    for s in SCALES:
        if width * s <= box[0] and height * s <= box[1]:
            return s
    return SCALES[-1]


def _sheet(doc, name: str, design: PRSDesign, title: str, rows: list[tuple[str, str]], notes: list[str],
           view_centre: tuple[float, float], scale: float, label: str, date: str,
           parts_list: list[tuple[str, ...]] | None = None) -> None:
    """Paper space: frame, the viewport :data:`VIEW` at ``scale`` centred on ``view_centre``
    (model mm), its label, the notes below it, the title block; header extents and stamp."""
    from ezdxf import bbox

    msp = doc.modelspace()
    psp = a3_paper_space(doc, name)
    vx0, vy0, vx1, vy1 = VIEW
    k = 1.0 / scale
    psp.add_viewport(center=(0.5 * (vx0 + vx1), 0.5 * (vy0 + vy1)), size=(vx1 - vx0, vy1 - vy0),
                     view_center_point=view_centre, view_height=(vy1 - vy0) * k, status=2,
                     dxfattribs={"layer": "VIEWPORTS"})
    psp.add_text(f"{label}  {scale_text(scale)}", height=TITLE_H,
                 dxfattribs={"layer": "TEXT"}).set_placement((vx0, vy1 + 3.0))
    # notes from x = 25 mm up to the title block's left edge, less a 3 mm gap
    top = 70.0
    if parts_list:
        # the parts list (ISO 7573) above the notes, left of the title block
        top = table(psp, 25.0, 82.0, "", parts_list) - 5.0
    lines = [w for n in notes for w in wrap_to_width(n, TITLE_BLOCK[0] - 28.0, TEXT_H)]
    # 5 mm a line; when the lines would run past y = 13 mm (the frame is at 10 mm), closer and
    # in the smaller ISO 3098 height 2.5 mm, whose text box still fits the closer step
    step = min(5.0, (top - 13.0) / max(len(lines) - 1, 1))
    height = TEXT_H if step >= 5.0 else NOTE_SMALL_H
    for i, n in enumerate(lines):
        psp.add_text(n, height=height, dxfattribs={"layer": "TEXT"}).set_placement((25.0, top - step * i))
    title_block(psp, rows, title)
    projection_symbol(psp, *PROJECTION_AT)
    ext = bbox.extents(msp)
    msp.dxf.extmin, msp.dxf.extmax = tuple(ext.extmin), tuple(ext.extmax)
    cx, cy = view_centre
    msp.dxf.limmin = (cx - 0.5 * SHEET[0] * k, cy - 0.5 * SHEET[1] * k)
    msp.dxf.limmax = (cx + 0.5 * SHEET[0] * k, cy + 0.5 * SHEET[1] * k)
    psp.dxf.limmin, psp.dxf.limmax = (0.0, 0.0), SHEET
    psp.dxf.extmin, psp.dxf.extmax = (0.0, 0.0, 0.0), (SHEET[0], SHEET[1], 0.0)
    doc.header["$EXTMIN"], doc.header["$EXTMAX"] = msp.dxf.extmin, msp.dxf.extmax
    _stamp(doc, design, name, date)


#: Text height (paper mm) of the notes when they are too many for 5 mm lines: the smaller
#: ISO 3098 height, so that a long parts list (an actuator's) keeps its lines apart.
NOTE_SMALL_H = 2.5
#: The one viewport of a mechanism sheet (paper mm): above the notes and the title block.
VIEW = (25.0, 85.0, 405.0, 275.0)


def _rows(design: PRSDesign, part: str, material, scale: float, date: str, version: str,
          sheet: int, kind: str = "Detail drawing") -> list[tuple[str, str]]:
    return iso7200_rows(design, part, material, scale_text(scale), date, version, sheet,
                        3 + len(MECHANISM_DRAWINGS), kind)


def carrier_drawing(design: PRSDesign, lay: MechanismLayout, date: str, version: str = __version__):
    """The carrier: front view (left) and axial section through roller 0's bore (right)."""
    from prs_geom.geometry.frames import carrier_angles

    doc = _new_doc()
    msp = doc.modelspace()
    R, r_in, t = lay.carrier_outer_radius_mm, lay.carrier_inner_radius_mm, lay.carrier_thickness_mm
    a, r_b = lay.centre_distance_mm, 0.5 * lay.journal_fit.nominal_diameter_mm
    gap = 0.6 * R + 20.0
    s = _fit_scale(2 * R + gap + t + 60.0, 2 * R + 40.0, (VIEW[2] - VIEW[0], VIEW[3] - VIEW[1]))
    k = 1.0 / s
    ov = dim_override(s)
    lay_out = {"layer": "OUTLINE"}
    # front view centred at the origin
    msp.add_circle((0.0, 0.0), R, dxfattribs=lay_out)
    msp.add_circle((0.0, 0.0), r_in, dxfattribs=lay_out)
    for psi in carrier_angles(design):
        msp.add_circle((a * math.cos(psi), a * math.sin(psi)), r_b, dxfattribs=lay_out)
    msp.add_circle((0.0, 0.0), a, dxfattribs={"layer": "CENTER", "ltscale": 2.0 * k})
    for ang in (0.0, 90.0):
        c, si = math.cos(math.radians(ang)), math.sin(math.radians(ang))
        msp.add_line((-(R + 4 * k) * c, -(R + 4 * k) * si), ((R + 4 * k) * c, (R + 4 * k) * si),
                     dxfattribs={"layer": "CENTER", "ltscale": 2.0 * k})
    # a DIAMETER dimension writes its own diameter sign before <> (a "%%c" here doubled it)
    guided = design.mechanism.carrier_guidance == "nut" and lay.carrier_fit is not None
    shaft = lay.carrier_fit.fit.split("/")[1] if guided else None
    outside = {"dimpost": f"<> {shaft}", **tolerance_override(tolerance_zone(2 * R, shaft))} if shaft else {}
    def outside_at(centre: tuple[float, float], angle: float) -> tuple[float, float]:
        """A text location on the ray from ``centre`` at ``angle`` (deg), beyond the outline."""
        c, si = math.cos(math.radians(angle)), math.sin(math.radians(angle))
        reach = R + 16.0 * k + math.hypot(*centre)
        return centre[0] + reach * c, centre[1] + reach * si

    free = {"dimtmove": 1, "dimtih": 1, "dimtoh": 1}
    msp.add_diameter_dim(center=(0.0, 0.0), radius=R, angle=135.0, text="<>" if shaft else "<> outside",
                         location=outside_at((0.0, 0.0), 135.0), override={**ov, **free, **outside},
                         dxfattribs={"layer": "DIMENSIONS"}).render()
    msp.add_diameter_dim(center=(0.0, 0.0), radius=r_in, angle=225.0, text="<> bore",
                         location=outside_at((0.0, 0.0), 225.0), override={**ov, **free},
                         dxfattribs={"layer": "DIMENSIONS"}).render()
    fit = lay.journal_fit
    hole = fit.fit.split("/")[0]
    # the bore is drawn and dimensioned at its nominal size, with its ISO 286 zone and limits
    bores = {"dimpost": f"<> {hole}", **free,
             **tolerance_override(tolerance_zone(fit.nominal_diameter_mm, hole))}
    msp.add_diameter_dim(center=(a, 0.0), radius=0.5 * fit.nominal_diameter_mm, angle=60.0,
                         text="<>", location=outside_at((a, 0.0), 60.0), override={**ov, **bores},
                         dxfattribs={"layer": "DIMENSIONS"}).render()
    x0 = R + gap
    _carrier_section(msp, design, lay, x0, s)
    lim = fit.limits
    notes = [f"{design.roller.count} journal bores equally spaced on the pitch circle at "
             f"psi_k = 360 k / {design.roller.count} deg, bore 0 on the section plane",
             f"Journal bores {design.roller.count}x %%c{fit.nominal_diameter_mm:g} {hole}: "
             f"{fit.nominal_diameter_mm + lim.hole.lower_mm:.3f} "
             f"to {fit.nominal_diameter_mm + lim.hole.upper_mm:.3f} mm; fit {fit.fit} with the roller journals, "
             f"clearance {1e3 * fit.min_clearance_mm:.0f} to {1e3 * fit.max_clearance_mm:.0f} um",
             f"Runs clear of the screw crest and the nut bore by "
             f"{design.mechanism.carrier_radial_clearance_mm:g} mm on the radius"
             if design.mechanism.carrier_guidance == "clear" else
             f"Guided in the nut bore: fit {lay.carrier_fit.fit}",
             "Parts list item 4 (2 off)",
             *part_notes(design.materials.carrier, "materials.carrier", "carrier")]
    _sheet(doc, "A3_CARRIER", design, f"PRS CARRIER - {dxf_text(design.name)}",
           _rows(design, "carrier", design.materials.carrier, s, date, version, 4), notes,
           (0.5 * (-R + x0 + t) + 10 * k, 0.0), s, "FRONT VIEW and SECTION through a journal bore", date)
    return doc


def _carrier_section(msp, design: PRSDesign, lay: MechanismLayout, x0: float, s: float) -> None:
    """The carrier's section through roller 0's bore (psi = 0) from X = ``x0``: X axial, Y
    radial (upper half through the bore, lower half at psi = 180 deg), hatched, with its
    thickness and the bores' pitch circle dimensioned."""
    from prs_geom.geometry.frames import carrier_angles

    k = 1.0 / s
    ov = dim_override(s)
    R, r_in, t = lay.carrier_outer_radius_mm, lay.carrier_inner_radius_mm, lay.carrier_thickness_mm
    a, r_b = lay.centre_distance_mm, 0.5 * lay.journal_fit.nominal_diameter_mm

    def quad(y0: float, y1: float) -> list[tuple[float, float]]:
        return [(x0, y0), (x0 + t, y0), (x0 + t, y1), (x0, y1)]
    upper = [quad(r_in, a - r_b), quad(a + r_b, R)]
    opposite_bore = any(abs(math.cos(p) + 1.0) < 1e-12 for p in carrier_angles(design))
    lower = [quad(-(a - r_b), -r_in), quad(-R, -(a + r_b))] if opposite_bore else [quad(-R, -r_in)]
    for q in upper + lower:
        msp.add_lwpolyline(q, close=True, dxfattribs={"layer": "OUTLINE"})
        _hatch(msp, [(x, y, 0.0) for x, y in q], s)
    msp.add_line((x0 - 4 * k, 0.0), (x0 + t + 4 * k, 0.0), dxfattribs={"layer": "CENTER", "ltscale": 2.0 * k})
    msp.add_line((x0 - 3 * k, a), (x0 + t + 3 * k, a), dxfattribs={"layer": "CENTER", "ltscale": 2.0 * k})
    msp.add_linear_dim(base=(x0, R + 10 * k), p1=(x0, R), p2=(x0 + t, R), text="<> thickness", override=ov,
                       dxfattribs={"layer": "DIMENSIONS"}).render()
    msp.add_linear_dim(base=(x0 + t + 12 * k, 0.0), p1=(x0 + t, a), p2=(x0 + t, -a if opposite_bore else 0.0),
                       angle=90.0, text="%%c<> pitch circle" if opposite_bore else "<> bore centre radius",
                       override=ov, dxfattribs={"layer": "DIMENSIONS"}).render()


def nut_end_drawing(design: PRSDesign, lay: MechanismLayout, date: str, version: str = __version__):
    """The lower nut end in axial half-section, X = outward distance from datum A (the
    thread's end face), with the retaining-ring groove."""
    doc = _new_doc()
    msp = doc.modelspace()
    end = lay.ends[0]
    length = end.nut_end[1] - end.nut_end[0]
    R = lay.nut_outer_radius_mm
    w = lay.gear_face_width_mm
    ring = lay.ring
    d1, d2 = ring.bore_mm, ring.groove_diameter_mm
    g_in = -end.groove[1]        # groove flank distances from datum A (X outward)
    g_out = -end.groove[0]
    s = _fit_scale(length + 80.0, R + 40.0, (VIEW[2] - VIEW[0], VIEW[3] - VIEW[1]))
    k = 1.0 / s
    ov = dim_override(s)
    r1 = 0.5 * d1
    pts = [(0.0, R), (length, R), (length, r1), (g_out, r1), (g_out, 0.5 * d2), (g_in, 0.5 * d2), (g_in, r1)]
    if w > 0.0:     # around the ring gear the nut's material starts at the gear's root circle
        from prs_geom.geometry.gear_pair import design_gear_pair

        gear_root = design_gear_pair(design).ring.root_radius_mm
        pts += [(w, r1), (w, gear_root), (0.0, gear_root)]
    else:
        pts += [(0.0, r1)]
    msp.add_lwpolyline(pts, close=True, dxfattribs={"layer": "OUTLINE"})
    _hatch(msp, [(x, y, 0.0) for x, y in pts], s)
    msp.add_line((-6 * k, 0.0), (length + 6 * k, 0.0), dxfattribs={"layer": "CENTER", "ltscale": 4.0 * k})
    dim = {"override": ov, "dxfattribs": {"layer": "DIMENSIONS"}}
    msp.add_linear_dim(base=(0.0, R + 10 * k), p1=(0.0, R), p2=(length, R), text="<> nut end", **dim).render()
    msp.add_linear_dim(base=(0.0, R + 20 * k), p1=(0.0, R), p2=(g_in, 0.5 * d2),
                       text="<> to groove (from A)", **dim).render()
    # below the part's lowest edge (the ring gear's root), so no text crosses its outline
    y_low = min(y for _, y in pts)
    msp.add_linear_dim(base=(g_in, y_low - 8 * k), p1=(g_in, 0.5 * d2), p2=(g_out, 0.5 * d2), text="<>",
                       override={**ov, "dimpost": "m <> H13",
                                 **tolerance_override(tolerance_zone(ring.groove_width_mm, "H13"))},
                       dxfattribs={"layer": "DIMENSIONS"}).render()
    msp.add_linear_dim(base=(g_out, y_low - 16 * k), p1=(g_out, r1), p2=(length, r1), text="n <> min",
                       **dim).render()
    # diameters of the half-section: the dimension line runs across the axis to the mirror
    # point, as on a half-section drawing
    from prs_geom.geometry.part_sections import RING_BORE_ZONE

    guided = design.mechanism.carrier_guidance == "nut" and lay.carrier_fit is not None
    bore_zone = lay.carrier_fit.fit.split("/")[0] if guided else RING_BORE_ZONE
    groove_tol = ({"dimtol": 1, "dimtp": ring.groove_upper_mm, "dimtm": -ring.groove_lower_mm, "dimtdec": 3,
                   "dimtzin": 8, "dimtfac": 0.7} if ring.groove_upper_mm is not None else {})
    extra = {"%%c<> groove": groove_tol,
             "%%c<> bore": {"dimpost": f"%%c<> {bore_zone}", **tolerance_override(tolerance_zone(d1, bore_zone))}}
    for i, (label, r) in enumerate((("%%c<> outside", R), ("%%c<> groove", 0.5 * d2), ("%%c<> bore", r1))):
        xb = length + (12.0 + 12.0 * i) * k
        msp.add_linear_dim(base=(xb, 0.0), p1=(length, r), p2=(length, -r), angle=90.0,
                           text="<>" if label == "%%c<> bore" else label, override={**ov, **extra.get(label, {})},
                           dxfattribs={"layer": "DIMENSIONS"}).render()
    tol = ""
    if ring.groove_upper_mm is not None:
        tol = f" (+{ring.groove_upper_mm:g}/{ring.groove_lower_mm:+g})"
    notes = ["Datum A: the nut thread's end face (tooth 1 end, z = 0); X outward from it",
             f"Groove for {ring.designation}: d2 {d2:g}{tol}, m {ring.groove_width_mm:g} H13 "
             f"(max {ring.groove_width_max_mm:.3f}), n >= {ring.edge_distance_mm:g}",
             f"Ring gear in the first {w:g} mm (root diameter {2 * gear_root:.3f}): see the nut drawing"
             if w > 0 else "No ring gear",
             "The upper end is the mirror image about the nut's mid-plane; parts list item 3",
             *part_notes(design.materials.nut, "materials.nut", "nut_end")]
    _sheet(doc, "A3_NUT_END", design, f"PRS NUT END - {dxf_text(design.name)}",
           _rows(design, "nut end", design.materials.nut, s, date, version, 5), notes,
           (0.5 * length + 20 * k, 0.5 * R), s, "SECTION (axial, upper half) of the nut end", date)
    return doc


#: Section lines of the assembly per part (ISO 128-50: adjacent parts hatched at different
#: angles or spacings): (angle deg, spacing on paper mm). Shafts, rollers, bolts and keys are
#: not sectioned lengthwise (ISO 128-44), so they have none.
ASSEMBLY_HATCH = {"nut": (45.0, 2.5), "carrier": (135.0, 2.0), "retaining ring": (45.0, 1.0),
                  "bearing": (135.0, 1.5), "locknut": (45.0, 1.5), "shaft ring": (135.0, 1.0)}


def _hatch_style(part: str) -> tuple[float, float] | None:
    key = "bearing" if part.startswith("bearing") else part
    return ASSEMBLY_HATCH.get(key)


def assembly_drawing(design: PRSDesign, lay: MechanismLayout, parts: list[Any], date: str,
                     version: str = __version__):
    """Axial half-section of every part (screw frame, upper half, the nut at mid-stroke and,
    dash-dot-dot, at both stroke ends), sectioned parts hatched per part
    (:data:`ASSEMBLY_HATCH`), one balloon per parts-list item (``parts``:
    :class:`~prs_geom.exports.bom.PartItem`) with leaders that do not cross, and the parts
    list on the sheet."""
    from prs_geom.geometry.actuator import actuator_layout
    from prs_geom.geometry.frames import screw_z_range

    doc = _new_doc()
    doc.layers.add("BALLOONS", color=7)
    doc.layers.add("PHANTOM", color=7, linetype="PHANTOM")
    msp = doc.modelspace()
    L = design.thread.engaged_teeth * design.thread.pitch_mm
    lo, hi = lay.ends[0].nut_end[0], lay.ends[1].nut_end[1]
    zs0, zs1 = screw_z_range(design)
    R = lay.nut_outer_radius_mm
    a = lay.centre_distance_mm
    act = actuator_layout(design)
    # the view's extent: the screw's end faces and the largest part radius of an actuator
    v0, v1, top_r = _actuator_extent(act, min(lo, zs0), max(hi, zs1), R)
    s = _fit_scale(v1 - v0 + 60.0, top_r + 40.0, (VIEW[2] - VIEW[0], VIEW[3] - VIEW[1]))
    k = 1.0 / s

    def rect(z0: float, z1: float, r0: float, r1: float, part: str = "") -> list[tuple[float, float]]:
        q = [(z0, r0), (z1, r0), (z1, r1), (z0, r1)]
        msp.add_lwpolyline(q, close=True, dxfattribs={"layer": "OUTLINE"})
        style = _hatch_style(part)
        if style is not None:
            h = msp.add_hatch(color=256, dxfattribs={"layer": "HATCH"})
            h.paths.add_polyline_path(q, is_closed=True)
            h.set_pattern_fill("ANSI31", scale=style[1] / 3.175 * k, angle=style[0] - 45.0)
        return q

    targets = _assembly_outlines(design, lay, rect, L, (zs0, zs1), a, R)
    if act is not None:
        targets.update(_actuator_outlines(rect, act, lay))
        _stroke_ends(msp, act, lay, k)
    msp.add_line((v0 - 6 * k, 0.0), (v1 + 6 * k, 0.0),
                 dxfattribs={"layer": "CENTER", "ltscale": 4.0 * k})
    ov = dim_override(s)
    msp.add_linear_dim(base=(lo, -8 * k), p1=(lo, 0.0), p2=(hi, 0.0), text="<> nut overall", override=ov,
                       dxfattribs={"layer": "DIMENSIONS"}).render()
    _balloons(msp, parts, targets, (v0, v1), top_r + 18.0 * k, k)
    doc_parts = [("Item", "Part", "Qty", "Material", "Designation")] + [
        (str(r.item), r.part, str(r.quantity), "purchased" if r.material is None else dxf_text(r.material.name),
         r.designation or "") for r in parts]
    psp_notes = ["Outlines: threads and gears at their crest diameters; roller 0 in the section plane"
                 + ("; purchased parts as envelopes, a flange bolt turned into the section plane; the nut "
                    "dash-dot-dot at both stroke ends" if act is not None else "")]
    _sheet(doc, "A3_ASSEMBLY", design, f"PRS ASSEMBLY - {dxf_text(design.name)}",
           _rows(design, "assembly", design.materials.nut, s, date, version, 6, "Assembly drawing"), psp_notes,
           (0.5 * (v0 + v1), 0.5 * top_r + 8 * k), s, "ASSEMBLY (axial half-section)", date,
           parts_list=doc_parts)
    return doc


def _assembly_outlines(design: PRSDesign, lay: MechanismLayout, rect: Any, L: float, screw: tuple[float, float],
                       a: float, R: float) -> dict[str, tuple[float, float]]:
    """The screw's thread, roller 0, the nut and its ends, the carriers and the rings; the
    balloon target of each."""
    zs0, zs1 = screw
    rs_major = 0.5 * design.screw.major_diameter_mm
    rr_major = 0.5 * design.roller.major_diameter_mm
    rn_minor = 0.5 * design.nut.minor_diameter_mm
    w = lay.gear_face_width_mm
    rj = 0.5 * lay.journal_diameter_mm
    rect(zs0, zs1, 0.0, rs_major, "screw")
    # roller 0 in the section plane: thread envelope, gears, journals
    rect(-w, L + w, a - rr_major, a + rr_major, "roller")
    for e in lay.ends:
        rect(e.journal[0], e.journal[1], a - rj, a + rj, "roller")
    rect(0.0, L, rn_minor, R, "nut")
    for e in lay.ends:
        rect(*e.nut_end, lay.nut_bore_radius_mm, R, "nut")
        rect(*e.carrier, lay.carrier_inner_radius_mm, lay.carrier_outer_radius_mm, "carrier")
        rect(*e.ring, lay.ring_inner_radius_mm, lay.ring_outer_radius_mm, "retaining ring")
    c, rz = lay.ends[0].carrier, lay.ends[0].ring
    return {"screw": (0.5 * (zs0 + zs1), 0.5 * rs_major), "roller": (0.5 * L, a + 0.5 * rr_major),
            "nut": (0.5 * L, 0.5 * (rn_minor + R)),
            "carrier": (0.5 * (c[0] + c[1]), 0.5 * (lay.carrier_inner_radius_mm + a - rj)),
            "retaining ring": (0.5 * (rz[0] + rz[1]), 0.5 * (lay.ring_inner_radius_mm + lay.ring_outer_radius_mm))}


def _stroke_ends(msp, act: Any, lay: MechanismLayout, k: float) -> None:
    """The nut assembly's outline (dash-dot-dot, layer PHANTOM) at both stroke ends and the
    stroke dimensioned between them."""
    z0, z1 = act.nut_assembly_z
    r_top = 0.5 * act.nut_mount.flange_diameter_mm if act.nut_mount.kind == "flange" else lay.nut_outer_radius_mm
    r_in = 0.5 * lay.carrier_inner_radius_mm + 0.5 * lay.nut_bore_radius_mm
    for shift in act.shifts:
        q = [(z0 + shift, r_in), (z1 + shift, r_in), (z1 + shift, r_top), (z0 + shift, r_top)]
        msp.add_lwpolyline(q, close=True, dxfattribs={"layer": "PHANTOM", "ltscale": 2.0 * k})
    lo, hi = z0 + act.shifts[0], z0 + act.shifts[1]
    msp.add_linear_dim(base=(lo, -20 * k), p1=(lo, 0.0), p2=(hi, 0.0), text="<> stroke",
                       override=dim_override(1.0 / k), dxfattribs={"layer": "DIMENSIONS"}).render()


def _crosses(p1, q1, p2, q2) -> bool:
    """True when the segments p1-q1 and p2-q2 cross (proper intersection)."""
    def orient(a, b, c) -> float:
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])

    d1, d2 = orient(p2, q2, p1), orient(p2, q2, q1)
    d3, d4 = orient(p1, q1, p2), orient(p1, q1, q2)
    return d1 * d2 < 0 and d3 * d4 < 0


def balloon_slots(targets: list[tuple[float, float]], xs: list[float], y: float) -> list[int]:
    """Which balloon position (of ``xs`` at height ``y``) each target gets so that no two
    leaders cross: in the targets' x order, then pairs of crossing leaders swapped until none
    crosses (each swap shortens the total length, so it ends)."""
    order = sorted(range(len(targets)), key=lambda i: (targets[i][0], targets[i][1]))
    slot = [0] * len(targets)
    for rank, i in enumerate(order):
        slot[i] = rank
    for _ in range(len(targets) ** 2 + 1):
        swapped = False
        for i in range(len(targets)):
            for j in range(i + 1, len(targets)):
                if _crosses(targets[i], (xs[slot[i]], y), targets[j], (xs[slot[j]], y)):
                    slot[i], slot[j] = slot[j], slot[i]
                    swapped = True
        if not swapped:
            break
    return slot


def _balloons(msp, parts: list[Any], targets: dict[str, tuple[float, float]], span: tuple[float, float],
              top: float, k: float) -> None:
    """One balloon per item in a row at ``top``, leaders to the targets without crossings."""
    v0, v1 = span
    n = len(parts)
    xs = [v0 + (v1 - v0) * (i + 0.5) / n for i in range(n)]
    pts = [targets[row.part] for row in parts]
    slots = balloon_slots(pts, xs, top)
    r_b = 0.5 * BALLOON_D * k
    for row, (tx, ty), slot in zip(parts, pts, slots):
        bx = xs[slot]
        msp.add_circle((bx, top), r_b, dxfattribs={"layer": "BALLOONS"})
        msp.add_text(str(row.item), height=TEXT_H * k, dxfattribs={"layer": "BALLOONS"}).set_placement(
            (bx, top), align=_middle())
        dx, dy = tx - bx, ty - top
        d = math.hypot(dx, dy)
        msp.add_line((bx + r_b * dx / d, top + r_b * dy / d), (tx, ty), dxfattribs={"layer": "BALLOONS"})
        msp.add_circle((tx, ty), 0.6 * k, dxfattribs={"layer": "BALLOONS"})     # the leader's dot


def _actuator_extent(act: Any, z0: float, z1: float, r: float) -> tuple[float, float, float]:
    """The assembly view's axial extent and top radius (mm) widened to an actuator's parts."""
    if act is None:
        return z0, z1, r
    radii = [0.5 * b.size.outer_diameter_mm for e in act.ends for b in e.bearings]
    radii += [0.5 * act.nut_mount.flange_diameter_mm]
    return min(z0, act.screw_z[0]), max(z1, act.screw_z[1]), max([r, *radii])


def _actuator_outlines(rect: Any, act: Any, lay: MechanismLayout) -> dict[str, tuple[float, float]]:
    """Outlines (``rect(z0, z1, r0, r1)``) of an actuator's parts in the upper half-section:
    the screw ends' steps, the bearings, the locknut, the shaft ring, the flange with one bolt
    turned into the section plane, the drive key; returns the balloon target of each
    purchased item, keyed by its parts-list name (:func:`prs_geom.exports.bom.part_items`)."""
    targets: dict[str, tuple[float, float]] = {}
    for end in act.ends:
        for st in end.steps:
            rect(st.z[0], st.z[1], 0.0, 0.5 * st.diameter_mm, "screw")
        for b in end.bearings:
            rect(b.z[0], b.z[1], 0.5 * b.size.bore_mm, 0.5 * b.size.outer_diameter_mm, "bearing")
            targets[f"bearing, {end.role} end"] = (b.middle_z, 0.25 * (b.size.bore_mm + b.size.outer_diameter_mm))
        if end.locknut is not None and end.locknut_z is not None:
            ln = end.locknut
            rect(*end.locknut_z, 0.5 * ln.thread_diameter_mm, 0.5 * ln.outer_diameter_mm, "locknut")
            targets["locknut"] = (0.5 * sum(end.locknut_z), 0.25 * (ln.thread_diameter_mm + ln.outer_diameter_mm))
        if end.ring is not None and end.ring_z is not None:
            rect(*end.ring_z, 0.5 * end.ring.groove_diameter_mm, 0.5 * end.ring.shaft_mm + 1.5, "shaft ring")
            targets["shaft ring"] = (0.5 * sum(end.ring_z), 0.5 * end.ring.shaft_mm + 0.75)
        if end.key is not None and end.key_z is not None:
            r_j = 0.5 * end.steps[-1].diameter_mm
            floor = r_j - end.key.shaft_depth_mm
            rect(*end.key_z, floor, floor + end.key.height_mm, "drive key")
            targets["drive key"] = (0.5 * sum(end.key_z), floor + 0.5 * end.key.height_mm)
    m = act.nut_mount
    if m.kind == "flange" and m.bolt is not None:
        rect(*m.z, lay.nut_outer_radius_mm, 0.5 * m.flange_diameter_mm, "nut")
        length = m.bolt_length_mm
        r_bc, d = 0.5 * m.bolt_circle_diameter_mm, m.bolt.diameter_mm
        # the head on the flange's nut side, the shank through the flange into the housing
        rect(m.z[1], m.z[1] + d, r_bc - 0.5 * m.bolt.head_diameter_mm, r_bc + 0.5 * m.bolt.head_diameter_mm,
             "flange bolt")
        rect(m.z[1] - length, m.z[1], r_bc - 0.5 * d, r_bc + 0.5 * d, "flange bolt")
        targets["flange bolt"] = (m.z[1] + 0.5 * d, r_bc)
    return targets


def _middle():
    from ezdxf.enums import TextEntityAlignment

    return TextEntityAlignment.MIDDLE_CENTER


def mechanism_drawings(design: PRSDesign, lay: MechanismLayout, parts: list[Any], date: str,
                       version: str = __version__) -> dict[str, Any]:
    """The three ezdxf documents keyed by file name, in sheet order."""
    return {"drawing_carrier.dxf": carrier_drawing(design, lay, date, version),
            "drawing_nut_end.dxf": nut_end_drawing(design, lay, date, version),
            "drawing_assembly.dxf": assembly_drawing(design, lay, parts, date, version)}


def write_all_drawings(design: PRSDesign, contact: Any, out_dir: Path | str, date: str,
                       version: str = __version__, pdf: bool = True, progress: ProgressFn | None = None) -> list[str]:
    """The build's drawings: the thread parts' (:func:`prs_geom.exports.drawing.write_drawings`)
    and, when the design has them, the carrier, nut end and assembly drawings, all as pages
    of ``drawings.pdf``. ``progress(stage, done, total)`` after each drawing and the PDF.
    Returns the file names written."""
    from prs_geom.exports.bom import part_items
    from prs_geom.exports.drawing import write_drawings
    from prs_geom.geometry.mechanism import layout

    lay = layout(design)
    extra = mechanism_drawings(design, lay, part_items(design), date, version) if lay is not None else None
    return write_drawings(design, contact, out_dir, date, version, pdf, extra, progress=progress)
