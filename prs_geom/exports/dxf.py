"""DXF drawing of the thread profiles (ezdxf, DXF R2010, millimetres).

Content: the half axial section of screw, roller and nut at the reference angle theta = 0
over the full thread length with the designed (graded) pitches, and the normal-section
tooth profile of each part. Each view is a named BLOCK (``SCREW_AXIAL``, ``ROLLER_AXIAL``,
``NUT_AXIAL``, ``SCREW_NORMAL``, ``ROLLER_NORMAL``, ``NUT_NORMAL``) in its own part
coordinates (X along the axis, Y the radius, mm) inserted into model space, so a CAD user
can move the views and a reader can measure them without offsets.

Entities: straight flanks, crests, roots and end lines as LINE; the roller flank as a true
ARC in the normal section and a true ELLIPSE in the axial section (the normal-section circle
stretched axially by 1 / cos(lambda): see :mod:`prs_geom.sections`); no polylines.
Layers: ``PROFILE``, ``CENTRE`` (axis lines, linetype CENTER), ``PITCH`` (pitch lines,
linetype DASHED), ``ANNOTATION`` (labels and the title block). Header: $INSUNITS = 4 (mm),
$MEASUREMENT = 1 (metric). The design name is written as literal text
(:func:`prs_geom.exports.textsafe.dxf_text`).
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import ezdxf
from ezdxf import units

from prs_geom._version import __version__
from prs_geom.exports.sheet import save_dxf
from prs_geom.exports.textsafe import dxf_text
from prs_geom.geometry.frames import FIRST_MID_PITCHES, part_warps, screw_z_range, thread_length
from prs_geom.model.design import PRSDesign
from prs_geom.geometry.profiles import ThreadProfiles
from prs_geom.geometry.primitives import CircleArc, EllipseArc, Segment
from prs_geom.geometry.sections import axial_section, normal_section

__all__ = ["LAYERS", "TEXT_HEIGHT", "VIEWPORT", "write_dxf"]

LAYERS = {"PROFILE": (7, "Continuous"), "CENTRE": (1, "CENTER"), "PITCH": (3, "DASHED"),
          "ANNOTATION": (2, "Continuous"), "TITLE": (7, "Continuous")}
TEXT_HEIGHT = 1.2


def _add(block, prims) -> None:
    for pr in prims:
        if isinstance(pr, Segment):
            block.add_line(pr.start, pr.end, dxfattribs={"layer": "PROFILE"})
        elif isinstance(pr, EllipseArc):
            block.add_ellipse(center=(pr.centre[0], pr.centre[1]), major_axis=(pr.a, 0.0),
                              ratio=pr.b / pr.a, start_param=pr.start, end_param=pr.end,
                              dxfattribs={"layer": "PROFILE"})
        elif isinstance(pr, CircleArc):
            block.add_arc(center=pr.centre, radius=pr.radius, start_angle=pr.start_deg,
                          end_angle=pr.end_deg, dxfattribs={"layer": "PROFILE"})


def write_dxf(design: PRSDesign, path: Path, extra: dict[str, Any] | None = None,
              profiles: Any = None, date: str = "") -> None:
    """Write the drawing; ``extra`` adds key numbers to the title block (e.g. the
    theoretical screw pitch diameter). ``profiles``: the parts' thread profiles by part
    (:func:`prs_geom.exports.drawing.part_profiles`: the screw at its theoretical pitch
    diameter, as the build draws it); the design's nominal ones when None. ``date``: the
    title block's date (the build's)."""
    doc = ezdxf.new("R2010", setup=True)
    doc.units = units.MM
    doc.header["$INSUNITS"] = 4
    doc.header["$MEASUREMENT"] = 1
    for name, (color, lt) in LAYERS.items():
        doc.layers.add(name, color=color, linetype=lt)
    from prs_geom.exports.sheet import use_drawing_font

    use_drawing_font(doc)
    msp = doc.modelspace()
    nominal = ThreadProfiles.from_design(design)
    prof = profiles if profiles is not None else {part: getattr(nominal, part) for part in ("screw", "roller", "nut")}
    warps = part_warps(design)
    p = design.thread.pitch_mm
    L = thread_length(design)
    zr = {"screw": screw_z_range(design), "roller": (0.0, L), "nut": (0.0, L)}
    y = 0.0
    x_detail = max(zr["screw"][1], L) + 15.0
    placements = {}
    for part in ("screw", "roller", "nut"):
        pr = prof[part]
        body = 0.5 * design.nut.outer_diameter_mm if part == "nut" else None
        lo, hi = zr[part]
        blk = doc.blocks.new(f"{part.upper()}_AXIAL")
        _add(blk, axial_section(pr, warps[part], FIRST_MID_PITCHES[part] * p, lo, hi, body))
        blk.add_line((lo - 3, 0), (hi + 3, 0), dxfattribs={"layer": "CENTRE"})
        blk.add_line((lo - 1, pr.pitch_radius), (hi + 1, pr.pitch_radius), dxfattribs={"layer": "PITCH"})
        blk.add_text(f"{part}: axial section at theta = 0, pitch dia. {2 * pr.pitch_radius:g} mm",
                     height=TEXT_HEIGHT, dxfattribs={"layer": "ANNOTATION"}).set_placement(
            (lo, (body or pr.outer_radius) + 2.0))
        msp.add_blockref(blk.name, (0.0, y))
        _dimension_view(msp, pr, lo, hi, y, body)
        nb = doc.blocks.new(f"{part.upper()}_NORMAL")
        _add(nb, normal_section(pr))
        nb.add_line((0, pr.inner_radius - 1.0), (0, pr.outer_radius + 0.5), dxfattribs={"layer": "CENTRE"})
        nb.add_line((-0.5 * p, pr.pitch_radius), (0.5 * p, pr.pitch_radius), dxfattribs={"layer": "PITCH"})
        nb.add_text(f"{part}: normal section", height=0.3, dxfattribs={"layer": "ANNOTATION"}).set_placement(
            (-0.5 * p, pr.outer_radius + 0.8))
        msp.add_blockref(nb.name, (x_detail, y))
        placements[part] = y
        y += (body or pr.outer_radius) + 12.0
    # title block
    lines = [
        f"prs_geom {__version__}  design: {dxf_text(design.name)}",
        f"units mm; pitch p = {p:g}; flank half-angle {design.thread.flank_half_angle_deg:g} deg; "
        f"{design.thread.hand} hand; {design.thread.engaged_teeth} teeth; {design.roller.count} rollers",
        f"pitch dia. screw {2.0 * prof['screw'].pitch_radius:.6f} ({design.screw.starts} starts), roller "
        f"{design.roller.pitch_diameter_mm:g}, nut {design.nut.pitch_diameter_mm:g} ({design.nut.starts} starts); "
        f"roller arc r_T {design.roller.arc_radius_mm:.6g}",
        "roller and nut drawn with their pitch lists (tooth 1 at the loaded end, X = 0)",
    ]
    for k, v in (extra or {}).items():
        lines.append(f"{k}: {v}")
    x0, y0 = 0.0, -8.0 - 2.0 * TEXT_HEIGHT * len(lines)
    width = 160.0
    msp.add_lwpolyline([(x0, y0), (x0 + width, y0), (x0 + width, -4.0), (x0, -4.0)], close=True,
                       dxfattribs={"layer": "ANNOTATION"})
    for i, text in enumerate(lines):
        msp.add_text(text, height=TEXT_HEIGHT, dxfattribs={"layer": "ANNOTATION"}).set_placement(
            (x0 + 2.0, -6.0 - 2.0 * TEXT_HEIGHT * (i + 1) + TEXT_HEIGHT))
    # $EXTMIN/$EXTMAX: the real model-space extents (CAD "zoom extents" and viewers use them)
    from ezdxf import bbox
    ext = bbox.extents(msp)
    _sheet(doc, design, ext, date)
    msp.dxf.extmin, msp.dxf.extmax = tuple(ext.extmin), tuple(ext.extmax)
    doc.header["$EXTMIN"], doc.header["$EXTMAX"] = msp.dxf.extmin, msp.dxf.extmax
    save_dxf(doc, path)


def _dimension_view(msp, pr: Any, lo: float, hi: float, y: float, body: float | None) -> None:
    """The axial view's dimensions (placed at its insertion height ``y``): the thread length
    under it and, right of it, the pitch diameter as a half-section dimension (from the axis
    to the pitch line, its text the diameter: ISO 129-1's one-sided dimension line)."""
    from prs_geom.exports.sheet import dim_override

    ov = dim_override(1.0, decimals=6)
    ov.update(dimtxt=TEXT_HEIGHT, dimasz=1.0, dimexo=0.5, dimexe=0.8, dimgap=0.4)
    top = body or pr.outer_radius
    msp.add_linear_dim(base=(hi + 4.0, y), p1=(hi, y), p2=(hi, y + pr.pitch_radius), angle=90.0,
                       text=f"%%c{2.0 * pr.pitch_radius:.6f} pitch", override=ov,
                       dxfattribs={"layer": "ANNOTATION"}).render()
    msp.add_linear_dim(base=(lo, y + top + 5.0), p1=(lo, y + top), p2=(hi, y + top), text="<> thread length",
                       override=ov, dxfattribs={"layer": "ANNOTATION"}).render()


#: Paper rectangles (x0, y0, x1, y1, mm) of the sheet's viewport; the frame and the title
#: block are the part drawings' (:mod:`prs_geom.exports.drawing`).
VIEWPORT = (25.0, 80.0, 405.0, 280.0)


def _sheet(doc, design: PRSDesign, ext: Any, date: str) -> None:
    """The A3 paper space: frame, one viewport on every view at the largest scale of
    (2, 1, 1/2, 1/5, 1/10) that fits, the title block."""
    from prs_geom.exports.sheet import a3_paper_space, scale_text, title_block
    from prs_geom.model.io import design_hash

    psp = a3_paper_space(doc, "A3_PROFILES", frame_layer="ANNOTATION")
    vx0, vy0, vx1, vy1 = VIEWPORT
    w, h = ext.extmax[0] - ext.extmin[0], ext.extmax[1] - ext.extmin[1]
    scale = next((s for s in (2.0, 1.0, 0.5, 0.2, 0.1) if w * s <= vx1 - vx0 and h * s <= vy1 - vy0), 0.05)
    centre = (0.5 * (ext.extmin[0] + ext.extmax[0]), 0.5 * (ext.extmin[1] + ext.extmax[1]))
    psp.add_viewport(center=(0.5 * (vx0 + vx1), 0.5 * (vy0 + vy1)), size=(vx1 - vx0, vy1 - vy0),
                     view_center_point=centre, view_height=(vy1 - vy0) / scale, status=2,
                     dxfattribs={"layer": "ANNOTATION"})
    rows = [("Design", dxf_text(design.name)), ("Content", "thread profiles"), ("Scale", scale_text(scale)),
            ("Units", "mm"), ("Date", date), ("prs_geom", __version__), ("Design sha256", design_hash(design)),
            ("Use", "the part drawings for making")]
    title_block(psp, rows, f"PRS THREAD PROFILES - {dxf_text(design.name)}")
