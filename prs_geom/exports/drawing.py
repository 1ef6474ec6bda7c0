"""Per-part engineering drawings: ``drawing_<part>.dxf`` (DXF R2010, mm) and ``drawings.pdf``.

One DXF per part (screw, roller, nut) and one PDF with one ISO A3 landscape page per part.

Model space (X along the part axis from the loaded end, Y the radius, mm):

* the axial section of the part over its threaded length, both sides of the axis: the upper
  half (Y > 0) is the section at theta = 0, the lower half (Y < 0) the section at
  theta = 180 deg (the flanks there sit half a lead further along the helix, so the halves
  are not mirror images). External parts are one closed LWPOLYLINE, the nut two (one per
  side of the bore). Straight flanks are exact; the roller's axial flank (an elliptical arc,
  :mod:`prs_geom.geometry.sections`) is written as 24 chords per flank. The screw is drawn
  at its THEORETICAL pitch diameter (``contact.screw_profile``), not the nominal one;
* the centre line (layer CENTER, linetype CENTER);
* DIMENSION entities, rendered: the pitch (axial, between the upper flanks of teeth 1 and 2
  at the pitch line at theta = 0), the major, pitch and minor diameters (linear, vertical),
  the nut body diameter, the threaded length;
* DETAIL A: the normal section of one tooth at 1:1 in its own region of model space, shown
  in a second paper-space viewport at 10:1, with the flank angle 2 beta (angular dimension
  between the flanks; for the roller between the flank tangents at the pitch point) and,
  on the roller, the flank arc radius r_T (radius dimension, the arc being a true bulge of
  the closed outline);
* the datum feature symbol A on the loaded-side end face (X = 0 for roller and nut; the
  screw's thread is centred on the nut, so its datum face is its loaded-side end, stated in
  a note) and B on the angular datum slot (:mod:`prs_geom.geometry.datum`), which the
  section at theta = 0 cuts through its mid-plane: a notch in face A of the upper outline,
  its depth dimensioned, its width and radial extent in a note.

Paper space: one ISO A3 landscape layout (420 x 297 mm) with a border (20 mm filing margin,
10 mm elsewhere), the section viewport at 2:1, 1:1 or 1:2 (the largest that fits), the
detail viewport at 10:1 and a title block (design, part, material E and nu, scale, units,
date, prs_geom version, design hash = sha256 of the design's TOML text, first 12 hex digits).
Text heights on paper per ISO 3098: 3.5 mm general, 5 mm titles. Layers OUTLINE, CENTER,
DIMENSIONS, TEXT, DETAIL, TITLE and HATCH (ISO 128-50 section lines, ANSI31). Header:
$INSUNITS = 4 (mm), $MEASUREMENT = 1, $EXTMIN / $EXTMAX the model-space bounding box
(ezdxf.bbox), $PLIMMIN / $PLIMMAX the sheet, and $LIMMIN / $LIMMAX the sheet at the section
scale in model units. Files are byte for byte
deterministic for a given date string (written by :func:`prs_geom.exports.dxf.save_dxf`)
except what ezdxf stamps with the clock on saving ($TDUPDATE, $VERSIONGUID and its "written
by" time, the fields ``tests/golden/fingerprint.py`` drops); $TDCREATE is the date string and
$FINGERPRINTGUID comes from the design hash. The PDF is the same bytes from run to run.
Text from the design file (the design name; on the mechanism drawings the material names) is
escaped for TEXT entities (:func:`prs_geom.exports.textsafe.dxf_text`) so that the drawing and
the PDF show it as typed; the PDF draws the texts' glyph outlines (ezdxf's font engine), so no
matplotlib mathtext is parsed.
"""
from __future__ import annotations

import functools
import hashlib
import io
import math
import random
from pathlib import Path

import numpy as np

from prs_geom._version import __version__
from prs_geom.exports.sheet import (FRAME, SHEET, TEXT_H, TITLE_BLOCK, TITLE_H, a3_paper_space, dim_override,
                                    part_notes, save_dxf, scale_text, title_block, use_drawing_font, wrap_to_width)
from prs_geom.exports.textsafe import dxf_text
from prs_geom.geometry.datum import DatumMark, datum_mark
from prs_geom.geometry.frames import FIRST_MID_PITCHES, part_warps, screw_z_range, thread_length
from prs_geom.geometry.primitives import EllipseArc, Segment
from prs_geom.geometry.profiles import ThreadProfile, ThreadProfiles
from prs_geom.geometry.sections import axial_section
from prs_geom.model.design import PRSDesign
from prs_geom.runtime.progress import ProgressFn
from prs_geom.model.io import design_hash

__all__ = ["PARTS", "LAYERS", "SCALES", "DETAIL_SCALE", "MAIN_VP", "NOTES", "DETAIL_VP", "ELLIPSE_CHORDS",
           "DRAWING_PDF", "drawing_name", "part_profiles", "z_range", "section_outlines", "part_datum_mark",
           "flank_x", "build_drawing", "render_pdf", "write_drawings"]

PARTS = ("screw", "roller", "nut")
LAYERS = {"OUTLINE": (7, "Continuous", 50), "CENTER": (1, "CENTER", 25), "DIMENSIONS": (3, "Continuous", 25),
          "TEXT": (2, "Continuous", 25), "DETAIL": (7, "Continuous", 50), "TITLE": (7, "Continuous", 35),
          "HATCH": (8, "Continuous", 18)}
SCALES = (2.0, 1.0, 0.5)                 # section scales tried, largest first
DETAIL_SCALE = 10.0
#: paper rectangles (x0, y0, x1, y1) of the section and detail viewports and the title block
MAIN_VP = (25.0, 140.0, 405.0, 275.0)
#: Notes block on the sheet: left x, top y (paper mm); lines wrap at the frame less 3 mm.
NOTES = (230.0, 133.0)
DETAIL_VP = (25.0, 15.0, 225.0, 92.0)
ELLIPSE_CHORDS = 24
DRAWING_PDF = "drawings.pdf"


def drawing_name(part: str) -> str:
    return f"drawing_{part}.dxf"


# --------------------------------------------------------------------------- geometry
def part_profiles(design: PRSDesign, contact) -> dict[str, ThreadProfile]:
    """The drawn profiles: the screw at the theoretical pitch diameter of ``contact``."""
    prof = ThreadProfiles.from_design(design)
    return {"screw": contact.screw_profile, "roller": prof.roller, "nut": prof.nut}


def z_range(design: PRSDesign, part: str) -> tuple[float, float]:
    return screw_z_range(design) if part == "screw" else (0.0, thread_length(design))


def _profile_points(profile: ThreadProfile, warp, first_mid: float, lo: float, hi: float) -> list[tuple[float, float]]:
    """The profile line from X = lo to X = hi as points (chords on elliptical flanks)."""
    pieces = []
    for pr in axial_section(profile, warp, first_mid, lo, hi, 1.0 if profile.internal else None):
        if pr.kind in ("end", "body"):
            continue
        if isinstance(pr, Segment):
            pts = [tuple(map(float, pr.start)), tuple(map(float, pr.end))]
        elif isinstance(pr, EllipseArc):
            ts = np.linspace(pr.end, pr.start, ELLIPSE_CHORDS + 1)   # X increases as t decreases
            pts = [pr.point(float(t)) for t in ts]
        else:  # pragma: no cover - axial sections hold segments and ellipses only
            raise TypeError(pr)
        if pts[0][0] > pts[-1][0]:
            pts.reverse()
        pieces.append(pts)
    pieces.sort(key=lambda p: (p[0][0], p[-1][0]))
    out: list[tuple[float, float]] = []
    for pts in pieces:
        for q in pts:
            if not out or abs(q[0] - out[-1][0]) > 1e-12 or abs(q[1] - out[-1][1]) > 1e-12:
                out.append(q)
    return out


def section_outlines(design: PRSDesign, part: str, profile: ThreadProfile) -> list[list[tuple[float, float]]]:
    """Closed outlines (first point not repeated) of the axial section: theta = 0 above the
    axis, theta = 180 deg below it."""
    warp = part_warps(design)[part]
    p = design.thread.pitch_mm
    lo, hi = z_range(design, part)
    first = FIRST_MID_PITCHES[part] * p
    half_lead = 0.5 * profile.lead * design.thread.hand_sign
    top = _profile_points(profile, warp, first, lo, hi)
    bot = [(x, -y) for x, y in _profile_points(profile, warp, first + half_lead, lo, hi)]
    mark = part_datum_mark(design, part, profile)
    x_floor = lo + mark.depth
    # the datum slot B lies in the theta = 0 half-plane: a notch in face A of the upper outline
    notch_up = [(lo, mark.r_inner), (x_floor, mark.r_inner), (x_floor, mark.r_outer), (lo, mark.r_outer)]
    if not profile.internal:
        return [notch_up + top + bot[::-1]]
    rb = 0.5 * design.nut.outer_diameter_mm
    return [top + [(hi, rb), (lo, rb)] + notch_up[::-1], bot + [(hi, -rb), (lo, -rb)]]


def part_datum_mark(design: PRSDesign, part: str, profile: ThreadProfile) -> DatumMark:
    """The angular datum slot B of a drawn part (the one cut into its mesh)."""
    body = 0.5 * design.nut.outer_diameter_mm if profile.internal else None
    return datum_mark(profile, z_range(design, part)[0], body)


def flank_x(design: PRSDesign, part: str, profile: ThreadProfile, tooth: int, r: float) -> float:
    """X of the upper flank of tooth ``tooth`` (1-based) at radius r, section theta = 0."""
    p = design.thread.pitch_mm
    mid = float(part_warps(design)[part](np.array([FIRST_MID_PITCHES[part] * p + (tooth - 1) * p]))[0])
    return mid + float(profile.tooth_half_width(r))


# --------------------------------------------------------------------------- DXF
def _new_doc():
    import ezdxf
    from ezdxf import units

    doc = ezdxf.new("R2010", setup=True)
    doc.units = units.MM
    doc.header["$INSUNITS"] = 4
    doc.header["$MEASUREMENT"] = 1
    for name, (color, lt, lw) in LAYERS.items():
        doc.layers.add(name, color=color, linetype=lt, lineweight=lw)
    use_drawing_font(doc)
    return doc


def _hatch(msp, boundary: list[tuple[float, float, float]], scale: float) -> None:
    """ISO 128-50 section lines (ANSI31, 45 deg, about 2.5 mm apart on paper) inside a
    closed boundary of (x, y, bulge) vertices, on layer HATCH."""
    h = msp.add_hatch(color=256, dxfattribs={"layer": "HATCH"})
    h.paths.add_polyline_path(boundary, is_closed=True)
    h.set_pattern_fill("ANSI31", scale=2.5 / 3.175 / scale)


def _choose_scale(length: float, height: float) -> float:
    w, h = MAIN_VP[2] - MAIN_VP[0], MAIN_VP[3] - MAIN_VP[1]
    for s in SCALES:
        if length * s + 110.0 <= w and height * s + 50.0 <= h:
            return s
    return SCALES[-1]


def _normal_tooth(profile: ThreadProfile) -> tuple[list[tuple[float, float, float]], float]:
    """Closed outline (x, y, bulge) of one tooth in the normal section centred at x = 0,
    closed by a break line below the root (external) or above it (nut); returns also the
    radius of that break line."""
    c = profile.cos_lead
    rr, rc = profile.root_radius, profile.crest_radius
    pn = profile.pitch * c
    q = 0.25 * pn
    wr = profile.flank.drawing_half_width(rr, q)
    wc = profile.flank.drawing_half_width(rc, q)
    depth = abs(rc - rr)
    rb = rr - 0.5 * depth if not profile.internal else rr + 0.5 * depth
    bulge = 0.0
    rt = getattr(profile.flank, "arc_radius", None)
    if rt is not None:  # a flank arc centred on the axis: bulge of the chord root -> crest
        a_r, a_c = math.asin(rr / rt), math.asin(rc / rt)
        # both flanks are run root -> crest -> root clockwise about their centres
        bulge = -math.tan(0.25 * (a_c - a_r))
    pts = [(-0.5 * pn, rb, 0.0), (-0.5 * pn, rr, 0.0), (-wr, rr, bulge), (-wc, rc, 0.0),
           (wc, rc, bulge), (wr, rr, 0.0), (0.5 * pn, rr, 0.0), (0.5 * pn, rb, 0.0)]
    return pts, rb


def build_drawing(design: PRSDesign, contact, part: str, date: str, version: str = __version__,
                  sheets: int = len(PARTS)):
    """The ezdxf document of one part's drawing (see the module docstring); ``sheets``: the
    number of sheets in the set it belongs to (its title block reads "Sheet n/sheets")."""
    from ezdxf import bbox

    doc = _new_doc()
    msp = doc.modelspace()
    profile = part_profiles(design, contact)[part]
    p = design.thread.pitch_mm
    lo, hi = z_range(design, part)
    outer = 0.5 * design.nut.outer_diameter_mm if part == "nut" else profile.outer_radius
    s = _choose_scale(hi - lo, 2.0 * outer)
    k = 1.0 / s                                   # paper mm -> model mm
    ov = dim_override(s)
    # -- section outlines and centre line
    for pts in section_outlines(design, part, profile):
        msp.add_lwpolyline(pts, close=True, dxfattribs={"layer": "OUTLINE"})
        _hatch(msp, [(x, y, 0.0) for x, y in pts], s)
    msp.add_line((lo - 6.0 * k, 0.0), (hi + 6.0 * k, 0.0),
                 dxfattribs={"layer": "CENTER", "ltscale": 4.0 * k})
    rp, rc, rr = profile.pitch_radius, profile.crest_radius, profile.root_radius
    r_major, r_minor = profile.outer_radius, profile.inner_radius
    # -- pitch: upper flanks of teeth 1 and 2 at the pitch line (theta = 0 side)
    x1, x2 = flank_x(design, part, profile, 1, rp), flank_x(design, part, profile, 2, rp)
    top = outer + 12.0 * k
    msp.add_linear_dim(base=(x1, top), p1=(x1, rp), p2=(x2, rp), text="P = <>", override=ov,
                       dxfattribs={"layer": "DIMENSIONS"}).render()
    # -- threaded length
    msp.add_linear_dim(base=(lo, -outer - 12.0 * k), p1=(lo, -outer if part == "nut" else -r_minor),
                       p2=(hi, -outer if part == "nut" else -r_minor), text="<> (threaded length)",
                       override=ov, dxfattribs={"layer": "DIMENSIONS"}).render()
    # -- diameters: vertical linear dimensions right of the part
    dia = [("%%c<> major", r_major), ("%%c<> pitch" + (" (theor.)" if part == "screw" else ""), rp),
           ("%%c<> minor", r_minor)]
    if part == "nut":
        dia.append(("%%c<> body", outer))
    for i, (label, r) in enumerate(dia):
        xb = hi + (12.0 + 12.0 * i) * k
        msp.add_linear_dim(base=(xb, 0.0), p1=(hi, r), p2=(hi, -r), angle=90.0, text=label,
                           override=ov, dxfattribs={"layer": "DIMENSIONS"}).render()
    # -- detail marker on the middle tooth of the main view (clear of the datum flags and the
    # slot's depth dimension at face A), datum A, angular datum note
    detail_tooth = max(2, design.thread.engaged_teeth // 2)
    xm = flank_x(design, part, profile, detail_tooth, rp) - float(profile.tooth_half_width(rp))
    ym = 0.5 * (rc + rr)
    msp.add_circle((xm, ym), radius=0.8 * p, dxfattribs={"layer": "TEXT"})
    msp.add_text("A", height=TEXT_H * k, dxfattribs={"layer": "TEXT"}).set_placement(
        (xm + 0.8 * p, ym + 0.8 * p))
    face = lo
    mark = part_datum_mark(design, part, profile)
    # datum A on the face clear of the slot (inside it for external parts, outside for the nut)
    y0 = 0.5 * mark.r_inner if not profile.internal else 0.5 * (rr + mark.r_inner)
    h = 3.0 * k
    b = 6.0 * k

    def datum_box(letter: str, x_leader: float, y: float) -> None:
        xa = x_leader - b
        msp.add_lwpolyline([(xa, y - 0.5 * b), (xa + b, y - 0.5 * b), (xa + b, y + 0.5 * b), (xa, y + 0.5 * b)],
                           close=True, dxfattribs={"layer": "TEXT"})
        msp.add_text(letter, height=TEXT_H * k, dxfattribs={"layer": "TEXT"}).set_placement(
            (xa + 0.5 * b, y), align=_align("MIDDLE_CENTER"))

    msp.add_lwpolyline([(face, y0 - 0.5 * h), (face, y0 + 0.5 * h), (face - 0.866 * h, y0)], close=True,
                       dxfattribs={"layer": "TEXT"})
    msp.add_line((face - 0.866 * h, y0), (face - 8.0 * k, y0), dxfattribs={"layer": "TEXT"})
    datum_box("A", face - 8.0 * k, y0)
    # datum B: the slot at theta = 0, its floor carrying the triangle, its depth dimensioned
    x_floor, y_mid = face + mark.depth, 0.5 * (mark.r_inner + mark.r_outer)
    hb = min(h, 0.8 * (mark.r_outer - mark.r_inner))
    msp.add_lwpolyline([(x_floor, y_mid - 0.5 * hb), (x_floor, y_mid + 0.5 * hb), (x_floor - 0.866 * hb, y_mid)],
                       close=True, dxfattribs={"layer": "TEXT"})
    # B's box sits one box further out than A's so the two never overlap
    msp.add_line((x_floor - 0.866 * hb, y_mid), (face - 10.0 * k - b, y_mid), dxfattribs={"layer": "TEXT"})
    datum_box("B", face - 10.0 * k - b, y_mid)
    msp.add_linear_dim(base=(face, mark.r_outer + 4.0 * k), p1=(face, mark.r_outer), p2=(x_floor, mark.r_outer),
                       text="<> (slot B depth)", override=ov, dxfattribs={"layer": "DIMENSIONS"}).render()
    # -- DETAIL A: normal section of one tooth, in its own region of model space
    dx = hi + (MAIN_VP[2] - MAIN_VP[0]) * k + 50.0     # beyond the section viewport's window
    tooth, rb = _normal_tooth(profile)
    msp.add_lwpolyline([(dx + x, y, bl) for x, y, bl in tooth], format="xyb", close=True,
                       dxfattribs={"layer": "DETAIL"})
    _hatch(msp, [(dx + x, y, bl) for x, y, bl in tooth], DETAIL_SCALE)
    kd = 1.0 / DETAIL_SCALE
    ovd = dim_override(DETAIL_SCALE)
    q = 0.25 * profile.pitch * profile.cos_lead
    slope = float(profile.flank.slope(rp))          # d(half-width)/dr at the pitch point (normal section)
    # directions (increasing radius) of the upper and lower flank tangents at the pitch points
    d_up = np.array([slope, 1.0]) / math.hypot(slope, 1.0)
    d_lo = np.array([-slope, 1.0]) / math.hypot(slope, 1.0)
    sgn = 1.0 if not profile.internal else -1.0     # towards the crest
    # the flank lines (tangents at the pitch points) meet at the apex beyond the crest; the
    # angle is dimensioned in the vertically opposite sector there (2 beta as well)
    apex_y = rp - q / slope
    apex = np.array([dx, apex_y])
    ra = 0.45 * p                                   # radius of the dimension arc
    first, second = (d_lo, d_up) if sgn > 0 else (-d_up, -d_lo)   # counter-clockwise order
    msp.add_angular_dim_3p(base=(dx, apex_y + sgn * ra), center=tuple(apex), p1=tuple(apex + ra * first),
                           p2=tuple(apex + ra * second), text="<> (included flank angle)", override=ovd,
                           dxfattribs={"layer": "DIMENSIONS"}).render()
    rt = getattr(profile.flank, "arc_radius", None)
    if rt is not None:
        c0 = q - math.sqrt(rt * rt - rp * rp)
        ang = math.degrees(math.asin(rp / rt))
        msp.add_radius_dim(center=(dx + c0, 0.0), radius=rt, angle=ang, text="<> (flank arc r_T)",
                           location=(dx + c0 + (rt + 0.5 * p) * math.cos(math.radians(ang)),
                                     (rt + 0.5 * p) * math.sin(math.radians(ang))),
                           override={**ovd, "dimtoh": 1}, dxfattribs={"layer": "DIMENSIONS"}).render()
    # -- paper space
    psp = a3_paper_space(doc, f"A3_{part.upper()}")
    vx0, vy0, vx1, vy1 = MAIN_VP
    vw, vh = vx1 - vx0, vy1 - vy0
    # window centre: the part plus the diameter dimensions on the right and datum A on the left
    cx = 0.5 * (lo + hi) + 0.5 * (12.0 * len(dia) + 6.0 - 16.0) * k
    psp.add_viewport(center=(0.5 * (vx0 + vx1), 0.5 * (vy0 + vy1)), size=(vw, vh), view_center_point=(cx, 0.0),
                     view_height=vh * k, status=2, dxfattribs={"layer": "VIEWPORTS"})
    mx0, my0 = cx - 0.5 * SHEET[0] * k, -0.5 * SHEET[1] * k
    model_limits = ((mx0, my0), (mx0 + SHEET[0] * k, my0 + SHEET[1] * k))
    dx0, dy0, dx1, dy1 = DETAIL_VP
    ycd = 0.5 * (rb + apex_y + sgn * 0.6 * p)
    psp.add_viewport(center=(0.5 * (dx0 + dx1), 0.5 * (dy0 + dy1)), size=(dx1 - dx0, dy1 - dy0),
                     view_center_point=(dx, ycd), view_height=(dy1 - dy0) * kd, status=3,
                     dxfattribs={"layer": "VIEWPORTS"})
    psp.add_lwpolyline([(dx0, dy0), (dx1, dy0), (dx1, dy1), (dx0, dy1)], close=True, dxfattribs={"layer": "DETAIL"})
    t = psp.add_text
    t(f"SECTION (axial; above the axis theta = 0, below theta = 180 deg)  {scale_text(s)}", height=TITLE_H,
      dxfattribs={"layer": "TEXT"}).set_placement((vx0, vy1 + 3.0))
    t(f"DETAIL A  {scale_text(DETAIL_SCALE)}  (normal section of one tooth)", height=TITLE_H,
      dxfattribs={"layer": "TEXT"}).set_placement((dx0, dy1 + 3.0))
    notes = ["Datum A: loaded-side end face (tooth 1 end, z = 0)" if part != "screw" else
             f"Datum A: loaded-side end face; nut tooth 1 end (z = 0) is {-lo:g} mm from it",
             f"Angular datum B: slot {mark.width:g} wide x {mark.depth:g} deep in face A, radius "
             f"{mark.r_inner:.3f} to {mark.r_outer:.3f}; its mid-plane is theta = 0 (+Y side here)",
             f"Teeth numbered from datum A; {design.thread.hand} hand, {profile.starts} start(s)"]
    if part == "screw":
        notes.append(f"Pitch dia. is the theoretical {2 * rp:.6f} mm (nominal {design.screw.pitch_diameter_mm:g})")
    if part in ("roller", "nut") and getattr(design, part).pitch_list_mm is not None:
        notes.append("Graded pitch: see machining sheet for the pitch list")
    if part in ("roller", "nut"):
        from prs_geom.geometry.gear_pair import design_gear_pair

        pair = design_gear_pair(design)
        if pair is not None:
            g = pair.pinion if part == "roller" else pair.ring
            k = g.recommended_span_teeth()
            pin = g.ideal_pin_diameter()
            where = "each roller end, beyond the thread" if part == "roller" else "each nut end (internal)"
            notes.append(f"Spur gear at {where}: z {g.teeth}, m {g.module_mm:g}, alpha {g.pressure_angle_deg:g} deg, "
                         f"x {g.profile_shift + 0.0:+.2f}, width {g.face_width_mm:g}")
            notes.append(f"  W{k} = {g.span_measurement(k):.4f} mm over {k} teeth; "
                         f"{'between' if g.internal else 'over'} pins d {pin:.4f}: {g.over_pins(pin):.4f} mm")
    notes += part_notes(getattr(design.materials, part), f"materials.{part}", "thread")
    lines = [w for n in notes for w in wrap_to_width(n, FRAME[2] - NOTES[0] - 3.0, TEXT_H)]
    # 5 mm a line down to the title block (its top at 75 mm); more lines step closer in the
    # smaller ISO 3098 height, whose text box still fits the closer step
    step = min(5.0, (NOTES[1] - TITLE_BLOCK[3] - 4.0) / max(len(lines) - 1, 1))
    height = TEXT_H if step >= 5.0 else 2.5
    for i, n in enumerate(lines):
        t(n, height=height, dxfattribs={"layer": "TEXT"}).set_placement((NOTES[0], NOTES[1] - step * i))
    mat = getattr(design.materials, part)
    rows = [("Design", dxf_text(design.name)), ("Part", part),
            ("Material", dxf_text(mat.grade or mat.name)),
            ("Heat treatment", dxf_text(mat.heat_treatment) if mat.heat_treatment else "none specified"),
            ("Scale", f"{scale_text(s)} (detail 10:1)"), ("Units", "mm"),
            ("Date", date), ("prs_geom", version), ("Design sha256", design_hash(design)),
            ("Sheet", f"{PARTS.index(part) + 1}/{sheets} A3")]
    title_block(psp, rows, f"PRS {part.upper()} - {dxf_text(design.name)}")
    # -- header: model-space extents (after the page setup, which resets them)
    ext = bbox.extents(msp)
    # ezdxf writes the header variables from the layouts on saving
    msp.dxf.extmin, msp.dxf.extmax = tuple(ext.extmin), tuple(ext.extmax)
    msp.dxf.limmin, msp.dxf.limmax = model_limits
    psp.dxf.limmin, psp.dxf.limmax = (0.0, 0.0), SHEET
    psp.dxf.extmin, psp.dxf.extmax = (0.0, 0.0, 0.0), (SHEET[0], SHEET[1], 0.0)
    doc.header["$EXTMIN"], doc.header["$EXTMAX"] = msp.dxf.extmin, msp.dxf.extmax
    _stamp(doc, design, part, date)
    return doc


def _stamp(doc, design: PRSDesign, part: str, date: str) -> None:
    """Creation date from ``date`` (when it is an ISO date) and a fingerprint GUID from the
    design hash and the part, so that only what ezdxf stamps on saving ($TDUPDATE,
    $VERSIONGUID, its "written by" time) changes from run to run."""
    import uuid
    from datetime import datetime

    from ezdxf.tools import juliandate

    try:
        when = datetime.fromisoformat(date.strip())
    except ValueError:
        when = None
    if when is not None:
        jd = juliandate(when.replace(tzinfo=None))
        doc.header["$TDCREATE"] = jd
        doc.header["$TDUCREATE"] = jd
    guid = uuid.UUID(hashlib.sha256(f"{design_hash(design)}:{part}".encode()).hexdigest()[:32])
    doc.header["$FINGERPRINTGUID"] = "{" + str(guid).upper() + "}"


def _align(name: str):
    from ezdxf.enums import TextEntityAlignment

    return getattr(TextEntityAlignment, name)


# --------------------------------------------------------------------------- PDF
def render_pdf(docs: list, path: Path) -> None:
    """One A3 page per document: its paper-space layout, via ezdxf's drawing add-on and
    matplotlib (black lines on white)."""
    # ezdxf jiggles hatch lines by a random offset (ezdxf.render.hatching); a fixed seed,
    # restored afterwards, makes the PDF the same bytes from run to run
    state = random.getstate()
    random.seed(0)
    try:
        _render_pages(docs, path)
    finally:
        random.setstate(state)


@functools.cache
def _sheet_axes_class() -> type:
    """An Axes class whose ``add_patch`` leaves the data limits alone, for the drawing sheets.

    ezdxf's matplotlib backend adds every path it draws (hatch lines, outlines, and one patch
    per line of text, holding the Bezier outlines of all its glyphs) with ``Axes.add_patch``,
    which walks the Bezier extrema of each path to grow the data limits: most of the PDF's
    cost (3.5 of 6 s under the profiler). A sheet's view is set explicitly after
    drawing (the sheet rectangle, ``adjustable="box"``, :func:`_render_pages`; that also
    overrides the autoscaling the backend's ``finalize`` asks for), so the data limits are
    never read; ``add_artist`` attaches the patch exactly as ``add_patch`` does
    (axes, transform, clip path, position in the drawing order), so the PDF bytes are the
    same. Built on first use: importing this module does not import matplotlib.
    """
    from matplotlib.axes import Axes
    from matplotlib.patches import Patch

    class SheetAxes(Axes):
        def add_patch(self, p: Patch) -> Patch:
            """Add ``p`` as ``Axes.add_patch`` would, without updating the data limits."""
            return self.add_artist(p)

    return SheetAxes


def _render_pages(docs: list, path: Path) -> None:
    from ezdxf.addons.drawing import Frontend, RenderContext
    from ezdxf.addons.drawing.config import BackgroundPolicy, ColorPolicy, Configuration
    from ezdxf.addons.drawing.matplotlib import MatplotlibBackend
    from matplotlib.backends.backend_pdf import PdfPages
    from matplotlib.figure import Figure

    cfg = Configuration(background_policy=BackgroundPolicy.WHITE, color_policy=ColorPolicy.BLACK)
    # rendered in memory, written in one go: matplotlib writing straight to a file that hits a
    # full disk reports a zlib stream error instead of the OSError (ENOSPC) that names the cause
    buffer = io.BytesIO()
    with PdfPages(buffer, metadata={"CreationDate": None, "Creator": "prs_geom"}) as pdf:
        for doc in docs:
            psp = doc.paperspace()
            fig = Figure(figsize=(SHEET[0] / 25.4, SHEET[1] / 25.4))
            ax = fig.add_axes((0.0, 0.0, 1.0, 1.0), axes_class=_sheet_axes_class())
            backend = MatplotlibBackend(ax, adjust_figure=False)
            Frontend(RenderContext(doc), backend, config=cfg).draw_layout(psp, finalize=True)
            # the view is the sheet, whatever was drawn: the data limits play no part
            ax.set_aspect("equal", adjustable="box")
            ax.set_xlim(0.0, SHEET[0])
            ax.set_ylim(0.0, SHEET[1])
            pdf.savefig(fig)
    Path(path).write_bytes(buffer.getvalue())


def write_drawings(design: PRSDesign, contact, out_dir: Path | str, date: str,
                   version: str = __version__, pdf: bool = True, extra: dict | None = None,
                   progress: ProgressFn | None = None) -> list[str]:
    """Write ``drawing_screw.dxf``, ``drawing_roller.dxf``, ``drawing_nut.dxf``, the documents
    of ``extra`` ({file name: ezdxf document}, e.g. the mechanism drawings of
    :func:`prs_geom.exports.mechanism_drawing.write_all_drawings`) and (``pdf``)
    ``drawings.pdf`` (a page each, in that order) into ``out_dir``; ``contact`` is the contact stage's
    :class:`~prs_geom.analysis.contact.ContactResult` (theoretical screw);
    ``progress(stage, done, total)`` after each drawing and the PDF. Returns the file names
    written."""
    out = Path(out_dir)
    names, docs = [], []
    total = len(PARTS) + len(extra or {}) + (1 if pdf else 0)

    def step() -> None:
        if progress is not None:
            progress("drawings", len(names), total)

    for part in PARTS:
        doc = build_drawing(design, contact, part, date, version, sheets=len(PARTS) + len(extra or {}))
        save_dxf(doc, out / drawing_name(part))
        names.append(drawing_name(part))
        docs.append(doc)
        step()
    for name, doc in (extra or {}).items():
        save_dxf(doc, out / name)
        names.append(name)
        docs.append(doc)
        step()
    if pdf:
        render_pdf(docs, out / DRAWING_PDF)
        names.append(DRAWING_PDF)
        step()
    return names
