"""Per-part shop drawings: ``drawing_<part>.dxf`` (DXF R2010, mm) and ``drawings.pdf``.

One DXF per thread part (screw, roller, nut) and one PDF with one ISO A3 landscape page per
sheet, numbered n/N as one set with the mechanism sheets
(:mod:`prs_geom.exports.mechanism_drawing`). Each thread-part sheet is what a shop makes the
complete part from (:mod:`prs_geom.mesh.parts`: the screw with its ends, the roller with its
gears and journals, the nut with its ring gears, ends and flange):

* SECTION: the complete part's axial section (:mod:`prs_geom.geometry.part_sections`), both
  halves hatched (ISO 128-50 section lines), threads in the simplified representation of
  ISO 6410-1 and gears as ISO 2203 draws them, at the largest ISO 5455 scale that holds it
  with its annotation (:mod:`prs_geom.exports.part_view`): every diameter dimensioned, the
  functional ones with their ISO 286 zone and limit deviations (DIMPOST and DIMTOL, so the
  deviations are data a CAD program reads), datum features A (axial face) and B, C (datum
  cylinders), ISO 1101 feature control frames, running dimensions from the left end face.
  Model space: X = z in the part frame (mm), Y = the radius; the screw at its THEORETICAL
  pitch diameter (``contact.screw_profile``);
* DETAIL A: the normal section of one tooth at 10:1 with its flank angle (the roller's
  between the flank tangents at the pitch point) and the roller's flank arc radius r_T;
* THREAD DATA (:func:`thread_table`), GEAR DATA (:func:`gear_table`, ISO 1328-1 class, span
  and pin sizes with deviations per ISO 21771) and, for a graded part, the PITCH LIST
  (:func:`pitch_table`);
* notes (datums, tooth numbering, material grade and heat treatment, general tolerances
  ISO 2768-1 m and ISO 22081, surface texture ISO 21920-1) and an ISO 7200 title block
  (identification number from the design name, revision = the design hash, document type,
  date of issue, creator, sheet n/N) with the ISO 5456-2 first-angle projection symbol.

No text crosses a part outline or another text (``tests/test_drawing.py`` measures them in
the pinned font, :data:`~prs_geom.exports.sheet.DRAWING_FONT`). Text heights on paper per
ISO 3098: 3.5 mm general, 2.5 mm in tables, 5 mm titles. Layers OUTLINE, THIN (thread and
gear roots), CENTER, DIMENSIONS, TEXT, DETAIL, TITLE and HATCH. Header: $INSUNITS = 4 (mm),
$MEASUREMENT = 1, $EXTMIN / $EXTMAX the model-space bounding box (ezdxf.bbox), $PLIMMIN /
$PLIMMAX the sheet, and $LIMMIN / $LIMMAX the sheet at the section scale in model units.
Files are byte for byte deterministic for a given date string (written by
:func:`prs_geom.exports.sheet.save_dxf`) except what ezdxf stamps with the clock on saving
($TDUPDATE, $VERSIONGUID and its "written by" time, the fields
``tests/golden/fingerprint.py`` drops); $TDCREATE is the date string and $FINGERPRINTGUID
comes from the design hash. The PDF is the same bytes from run to run. Text from the design
file (the design name, material names) is escaped for TEXT entities
(:func:`prs_geom.exports.textsafe.dxf_text`); the PDF draws the texts' glyph outlines
(ezdxf's font engine; :mod:`prs_geom.exports.sheet_pdf` writes the pages), so no text is
parsed as markup on the way.
"""
from __future__ import annotations

import hashlib
import math
import random
from pathlib import Path

import numpy as np

from prs_geom._version import __version__
from prs_geom.exports.part_view import draw_part_view
from prs_geom.exports.sheet import (FRAME, SHEET, TEXT_H, TITLE_BLOCK, TITLE_H, a3_paper_space, dim_override,
                                    iso7200_rows, part_notes, save_dxf, scale_text, title_block, use_drawing_font,
                                    wrap_to_width)
from prs_geom.exports.sheet_items import TABLE_ROW, limits_text, projection_symbol, table, table_widths
from prs_geom.exports.textsafe import dxf_text
from prs_geom.geometry.part_sections import PartSection, part_section
from prs_geom.geometry.profiles import ThreadProfile, ThreadProfiles
from prs_geom.model.design import PRSDesign
from prs_geom.model.io import design_hash
from prs_geom.model.standards import tolerance_zone
from prs_geom.runtime.progress import ProgressFn

__all__ = ["PARTS", "LAYERS", "SCALES", "DETAIL_SCALE", "MAIN_VP", "NOTES", "DETAIL_VP", "TABLES", "TABLES_TOP",
           "PITCH_TABLE_MAX", "DRIVE_VP", "DEFAULT_LEAD_DEVIATION", "PROJECTION_AT", "DRAWING_PDF", "drawing_name", "part_profiles",
           "thread_table", "gear_table", "pitch_table", "build_drawing", "render_pdf", "write_drawings"]

PARTS = ("screw", "roller", "nut")
LAYERS = {"OUTLINE": (7, "Continuous", 50), "CENTER": (1, "CENTER", 25), "DIMENSIONS": (3, "Continuous", 25),
          "TEXT": (2, "Continuous", 25), "DETAIL": (7, "Continuous", 50), "TITLE": (7, "Continuous", 35),
          "HATCH": (8, "Continuous", 18), "THIN": (7, "Continuous", 18)}
SCALES = (5.0, 2.0, 1.0, 0.5, 0.2)       # ISO 5455 section scales tried, largest first
DETAIL_SCALE = 10.0
#: paper rectangles (x0, y0, x1, y1) of the section and detail viewports
MAIN_VP = (25.0, 138.0, 405.0, 279.0)
#: Notes block on the sheet: left x, top y (paper mm); lines wrap at the frame less 3 mm.
NOTES = (230.0, 133.0)
DETAIL_VP = (25.0, 15.0, 120.0, 72.0)
#: The screw sheet's SECTION K-K viewport (paper mm), right of the thread data table.
DRIVE_VP = (130.0, 15.0, 225.0, 120.0)
#: Left edges (paper mm) of the thread data table and of the gear and pitch-list tables, and
#: the top of both columns.
TABLES = (25.0, 125.0)
TABLES_TOP = 134.0
#: Longest pitch list drawn as a table on the sheet; a longer one is named by its machining sheet.
PITCH_TABLE_MAX = 30
#: The lead deviation stated when the design has no ``tolerances.lead_um``: ISO 3408-3's
#: permissible travel variation within 300 mm of tolerance class 3, which roller screw
#: makers use for their accuracy classes too.
DEFAULT_LEAD_DEVIATION = "v300p 12 \u00b5m (ISO 3408-3 class 3)"
#: Lower left corner (paper mm) of the projection symbol, in the title block's top line.
PROJECTION_AT = (388.0, 66.5)
DRAWING_PDF = "drawings.pdf"


def drawing_name(part: str) -> str:
    return f"drawing_{part}.dxf"


# --------------------------------------------------------------------------- geometry
def part_profiles(design: PRSDesign, contact) -> dict[str, ThreadProfile]:
    """The drawn profiles: the screw at the theoretical pitch diameter of ``contact``."""
    prof = ThreadProfiles.from_design(design)
    return {"screw": contact.screw_profile, "roller": prof.roller, "nut": prof.nut}


def _mm(x: float, decimals: int = 4) -> str:
    return f"{x:.{decimals}f}"


def thread_table(design: PRSDesign, contact, part: str) -> list[tuple[str, str]]:
    """The thread data table's rows (label, value) of ``part``: profile, pitch, starts, lead,
    hand, flank angle, pitch diameter with its ISO 286 limits (the screw's theoretical one),
    major and minor diameters, threaded length, engaged teeth, lead deviation."""
    prof = part_profiles(design, contact)[part]
    th = design.thread
    p = th.pitch_mm
    graded = part in ("roller", "nut") and getattr(design, part).pitch_list_mm is not None
    d_p = 2.0 * prof.pitch_radius
    sym = getattr(design, part).pitch_diameter_tolerance
    rt = getattr(prof.flank, "arc_radius", None)
    flank = (f"arc r_T {rt:.4f} mm; {2.0 * th.flank_half_angle_deg:g}\u00b0 at d_p" if rt is not None
             else f"straight, 2\u03b2 = {2.0 * th.flank_half_angle_deg:g}\u00b0")
    major, minor = (prof.outer_radius, prof.inner_radius)
    if design.tolerances is not None and design.tolerances.lead_um > 0.0:
        lead_dev = f"\u00b1{design.tolerances.lead_um:g} \u00b5m over {(th.engaged_teeth - 1) * p:g} mm (tolerances)"
    else:
        lead_dev = DEFAULT_LEAD_DEVIATION
    return [("Profile", f"{'internal' if prof.internal else 'external'} PRS {part} thread"),
            ("Pitch P", f"{_mm(p)} mm" + (" nominal; graded, see pitch list" if graded else "")),
            ("Starts", f"{prof.starts}"), ("Lead", f"{_mm(prof.starts * p)} mm"),
            ("Hand", th.hand), ("Flank", flank),
            ("Pitch diameter" + (" (theor.)" if part == "screw" else ""),
             f"\u00d8{_mm(d_p)} {limits_text(sym, tolerance_zone(d_p, sym))}"),
            ("Major / minor dia.", f"\u00d8{_mm(2.0 * major)} / \u00d8{_mm(2.0 * minor)}"),
            ("Threaded length", f"{_mm(_thread_span(design, part), 2)} mm"),
            ("Engaged teeth", f"{th.engaged_teeth}"), ("Lead deviation", lead_dev)]


def _thread_span(design: PRSDesign, part: str) -> float:
    from prs_geom.geometry.frames import screw_z_range, thread_length

    if part != "screw":
        return thread_length(design)
    lo, hi = screw_z_range(design)
    return hi - lo


def gear_table(design: PRSDesign, part: str) -> list[tuple[str, str]]:
    """The gear data table's rows of the roller gear or the nut's ring gear (empty for the
    screw or without gears): module, teeth, pressure angle, profile shift, face width, tip
    diameter with its ISO 286 limits, ISO 1328-1 class, span W_k and the over-pins (between
    pins for the ring) size with their deviations from the tooth thinning (backlash) and the
    thickness tolerance (ISO 21771)."""
    import dataclasses

    from prs_geom.geometry.gear_pair import design_gear_pair

    pair = design_gear_pair(design) if part in ("roller", "nut") else None
    if pair is None:
        return []
    g = pair.pinion if part == "roller" else pair.ring
    gs = design.gears
    k = g.recommended_span_teeth()
    pin = g.ideal_pin_diameter()
    nominal = dataclasses.replace(g, backlash_mm=0.0)
    thinnest = dataclasses.replace(g, backlash_mm=g.backlash_mm + gs.thickness_tolerance_mm)

    def limits(f) -> str:
        base = f(nominal)
        a, b = f(g) - base, f(thinnest) - base
        return f"{_mm(base)} ({deviation_pair(max(a, b), min(a, b))})"

    tip = 2.0 * g.tip_radius_mm
    if part == "roller":
        tip = min(tip, 2.0 * ThreadProfiles.from_design(design).roller.crest_radius)
    sym = gs.tip_tolerance if part == "roller" else gs.ring_tip_tolerance
    return [("Module m", f"{g.module_mm:g} mm"), ("Teeth z", f"{g.teeth}"),
            ("Pressure angle", f"{g.pressure_angle_deg:g}\u00b0"), ("Profile shift x", f"{g.profile_shift + 0.0:+.4f}"),
            ("Face width", f"{g.face_width_mm:g} mm"),
            # in parentheses: a reference dimension (ISO 129-1), for information, not inspected
            ("Reference dia. d", f"({_mm(2.0 * g.pitch_radius_mm)})"),
            ("Tip diameter", f"\u00d8{_mm(tip)} {limits_text(sym, tolerance_zone(tip, sym))}"),
            ("Accuracy", f"ISO 1328-1 class {gs.accuracy_grade}"),
            (f"Span W{k} ({k} teeth)", limits(lambda x: x.span_measurement(k))),
            (f"{'Between' if g.internal else 'Over'} pins \u00d8{pin:.4f}", limits(lambda x: x.over_pins(pin)))]


def deviation_pair(upper: float, lower: float) -> str:
    """"upper/lower" deviations (mm) at four decimals (0.1 um, as span and pin sizes are
    measured), "0" for zero."""
    from prs_geom.exports.sheet_items import deviation_text

    return f"{deviation_text(upper, 4)}/{deviation_text(lower, 4)}"


def pitch_table(design: PRSDesign, part: str) -> list[tuple[str, str]] | str | None:
    """The pitch list of a graded roller or nut as table rows ("1-2", "2.000424"), six
    decimals (mm); a list longer than :data:`PITCH_TABLE_MAX` as a note naming its machining
    sheet; None for a constant pitch."""
    pl = getattr(design, part).pitch_list_mm if part in ("roller", "nut") else None
    if pl is None:
        return None
    if len(pl) > PITCH_TABLE_MAX:
        return (f"Graded pitch: {len(pl)} tooth-to-tooth pitches, see machining_{part}.csv and machining.xlsx "
                f"of design sha256 {design_hash(design)}")
    return [(f"{j + 1}-{j + 2}", f"{v:.6f}") for j, v in enumerate(pl)]


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


def _choose_view(design: PRSDesign, sec: PartSection):
    """The largest scale of :data:`SCALES` whose view (with its annotation) fits the main
    viewport: (document, model space, scale, view extents (x0, y0, x1, y1))."""
    from ezdxf import bbox

    w, h = MAIN_VP[2] - MAIN_VP[0], MAIN_VP[3] - MAIN_VP[1]
    for s in SCALES:
        doc = _new_doc()
        msp = doc.modelspace()
        draw_part_view(msp, design, sec, s, _hatch)
        ext = bbox.extents(msp)
        box = (ext.extmin.x, ext.extmin.y, ext.extmax.x, ext.extmax.y)
        if (box[2] - box[0]) * s <= w - 4.0 and (box[3] - box[1]) * s <= h - 6.0:
            break
    return doc, msp, s, box


def _detail(msp, profile: ThreadProfile, dx: float) -> float:
    """DETAIL A at ``dx`` in model space: the normal section of one tooth with its flank
    angle (and the roller's flank arc radius); returns the y of the detail's centre."""
    p = profile.pitch
    tooth, rb = _normal_tooth(profile)
    msp.add_lwpolyline([(dx + x, y, bl) for x, y, bl in tooth], format="xyb", close=True,
                       dxfattribs={"layer": "DETAIL"})
    _hatch(msp, [(dx + x, y, bl) for x, y, bl in tooth], DETAIL_SCALE)
    # whole numbers print without trailing zeros (90 deg, not 90.0000 deg)
    ovd = {**dim_override(DETAIL_SCALE), "dimzin": 8, "dimazin": 2}
    q = 0.25 * profile.pitch * profile.cos_lead
    rp = profile.pitch_radius
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
                           p2=tuple(apex + ra * second), text="<> flank angle", override=ovd,
                           dxfattribs={"layer": "DIMENSIONS"}).render()
    rt = getattr(profile.flank, "arc_radius", None)
    if rt is not None:
        c0 = q - math.sqrt(rt * rt - rp * rp)
        ang = math.degrees(math.asin(rp / rt))
        msp.add_radius_dim(center=(dx + c0, 0.0), radius=rt, angle=ang, text="<> r_T",
                           location=(dx + c0 + (rt + 0.5 * p) * math.cos(math.radians(ang)),
                                     (rt + 0.5 * p) * math.sin(math.radians(ang))),
                           override={**ovd, "dimtoh": 1}, dxfattribs={"layer": "DIMENSIONS"}).render()
    return 0.5 * (rb + apex_y + sgn * 0.6 * p)


def build_drawing(design: PRSDesign, contact, part: str, date: str, version: str = __version__,
                  sheets: int = len(PARTS)):
    """The ezdxf document of one part's sheet (see the module docstring); ``sheets``: the
    number of sheets in the set it belongs to (its title block reads "Sheet n/sheets")."""
    from ezdxf import bbox

    sec = part_section(design, part, contact.screw_profile if part == "screw" else None)
    doc, msp, s, box = _choose_view(design, sec)
    k = 1.0 / s
    profile = part_profiles(design, contact)[part]
    dx = box[2] + (MAIN_VP[2] - MAIN_VP[0]) * k + 50.0     # beyond the section viewport's window
    before = len(msp)
    _detail(msp, profile, dx)
    # the detail's extent: its entities, the r_T dimension by its text alone (its centre, on
    # the part's axis far below the tooth, is not shown)
    shown = [v for e in list(msp)[before:]
             for v in ([t for t in e.virtual_entities() if t.dxftype() == "MTEXT"]
                       if e.dxftype() == "DIMENSION" and e.dimtype == 4 else [e])]
    det = bbox.extents(shown)
    dcx, ycd = 0.5 * (det.extmin.x + det.extmax.x), 0.5 * (det.extmin.y + det.extmax.y)
    # 10:1, or 5:1 where the tooth with its dimensions is wider or taller than the viewport
    ds = DETAIL_SCALE if max(det.size.x / (DETAIL_VP[2] - DETAIL_VP[0]),
                             det.size.y / (DETAIL_VP[3] - DETAIL_VP[1])) * DETAIL_SCALE <= 0.95 else 0.5 * DETAIL_SCALE
    psp = a3_paper_space(doc, f"A3_{part.upper()}")
    drive_note = _drive_view(msp, psp, design, part, dx + 30.0)
    vx0, vy0, vx1, vy1 = MAIN_VP
    cx, cy = 0.5 * (box[0] + box[2]), 0.5 * (box[1] + box[3]) + 0.5 * 8.0 * k
    psp.add_viewport(center=(0.5 * (vx0 + vx1), 0.5 * (vy0 + vy1)), size=(vx1 - vx0, vy1 - vy0),
                     view_center_point=(cx, cy), view_height=(vy1 - vy0) * k, status=2,
                     dxfattribs={"layer": "VIEWPORTS"})
    dx0, dy0, dx1, dy1 = DETAIL_VP
    psp.add_viewport(center=(0.5 * (dx0 + dx1), 0.5 * (dy0 + dy1)), size=(dx1 - dx0, dy1 - dy0),
                     view_center_point=(dcx, ycd), view_height=(dy1 - dy0) / ds, status=3,
                     dxfattribs={"layer": "VIEWPORTS"})
    psp.add_lwpolyline([(dx0, dy0), (dx1, dy0), (dx1, dy1), (dx0, dy1)], close=True, dxfattribs={"layer": "DETAIL"})
    psp.add_text(f"SECTION (axial, complete part; threads ISO 6410-1, gears ISO 2203)  {scale_text(s)}",
                 height=TITLE_H, dxfattribs={"layer": "TEXT"}).set_placement((vx0, vy1 + 2.0))
    psp.add_text(f"DETAIL A  {scale_text(ds)}  (normal section)", height=TEXT_H,
                 dxfattribs={"layer": "TEXT"}).set_placement((dx0, dy1 + 2.0))
    _tables(psp, design, contact, part, sec)
    _notes(psp, design, part, sec, drive_note)
    index = PARTS.index(part) + 1
    title_block(psp, iso7200_rows(design, part, getattr(design.materials, part), f"{scale_text(s)} (detail {scale_text(ds)})",
                                  date, version, index, sheets),
                f"PRS {part.upper()} - {dxf_text(design.name)}")
    projection_symbol(psp, *PROJECTION_AT)
    # -- header: model-space extents (after the page setup, which resets them)
    ext = bbox.extents(msp)
    msp.dxf.extmin, msp.dxf.extmax = tuple(ext.extmin), tuple(ext.extmax)
    mx0, my0 = cx - 0.5 * SHEET[0] * k, cy - 0.5 * SHEET[1] * k
    msp.dxf.limmin, msp.dxf.limmax = (mx0, my0), (mx0 + SHEET[0] * k, my0 + SHEET[1] * k)
    psp.dxf.limmin, psp.dxf.limmax = (0.0, 0.0), SHEET
    psp.dxf.extmin, psp.dxf.extmax = (0.0, 0.0, 0.0), (SHEET[0], SHEET[1], 0.0)
    doc.header["$EXTMIN"], doc.header["$EXTMAX"] = msp.dxf.extmin, msp.dxf.extmax
    _stamp(doc, design, part, date)
    return doc


def _tables(psp, design: PRSDesign, contact, part: str, sec: PartSection) -> None:
    """The thread data table (left, above the detail), the gear data and pitch-list tables
    (right of it, up to the notes)."""
    rows = thread_table(design, contact, part)
    table(psp, TABLES[0], TABLES_TOP, "THREAD DATA", rows)
    x = TABLES[0] + sum(table_widths(rows)) + 5.0
    y = TABLES_TOP
    gear = gear_table(design, part)
    if gear:
        y = table(psp, x, y, "GEAR DATA (each end)", gear) - 3.0
    pitches = pitch_table(design, part)
    if pitches is None:
        return
    if isinstance(pitches, str):
        for i, line in enumerate(wrap_to_width(pitches, NOTES[0] - x - 5.0, 2.5)):
            psp.add_text(line, height=2.5, dxfattribs={"layer": "TEXT"}).set_placement((x, y - 4.0 - 4.0 * i))
        return
    # as many columns of (teeth, pitch) as the space down to the frame needs
    per_column = max(int((y - TEXT_H - 2.0 - FRAME[1] - 3.0) // TABLE_ROW), 1)
    w = table_widths(pitches)
    for c in range(0, len(pitches), per_column):
        table(psp, x, y, "PITCH LIST (mm)" if c == 0 else "", pitches[c:c + per_column], w)
        x += sum(w) + 2.0


def _drive_view(msp, psp, design: PRSDesign, part: str, x: float) -> str | None:
    """SECTION K-K of the screw's drive journal (keyway or flat) at model X = ``x``, in the
    viewport :data:`DRIVE_VP` at the largest of 5:1, 2:1, 1:1 that holds it; its note."""
    from ezdxf import bbox

    from prs_geom.exports.part_view import draw_drive_section
    from prs_geom.geometry.actuator import actuator_layout

    lay = actuator_layout(design) if part == "screw" else None
    end = next((e for e in lay.ends if e.key_z is not None), None) if lay is not None else None
    if end is None:
        return None
    r = max(st.diameter_mm for st in end.steps if st.name == "drive journal") * 0.5
    w, h = DRIVE_VP[2] - DRIVE_VP[0], DRIVE_VP[3] - DRIVE_VP[1]
    s = next((c for c in (5.0, 2.0, 1.0) if (2 * r + 30.0 / c) * c <= min(w, h) - 10.0), 0.5)
    before = len(msp)
    note = draw_drive_section(msp, end, (x + r, 0.0), s, _hatch)
    ext = bbox.extents(list(msp)[before:])
    centre = (0.5 * (ext.extmin.x + ext.extmax.x), 0.5 * (ext.extmin.y + ext.extmax.y))
    x0, y0, x1, y1 = DRIVE_VP
    psp.add_viewport(center=(0.5 * (x0 + x1), 0.5 * (y0 + y1)), size=(w, h), view_center_point=centre,
                     view_height=h / s, status=4, dxfattribs={"layer": "VIEWPORTS"})
    psp.add_text(f"SECTION K-K (drive journal)  {scale_text(s)}", height=TEXT_H,
                 dxfattribs={"layer": "TEXT"}).set_placement((x0, y1 + 2.0))
    return note


def _notes(psp, design: PRSDesign, part: str, sec: PartSection, drive_note: str | None = None) -> None:
    """The notes above the title block: datums, tooth numbering, geometric tolerances'
    source, material, general tolerances, surface texture."""
    axis = " and ".join(sec.datum_axis)
    face = {"screw": "the fixed bearings' shoulder", "roller": "the loaded-side gear's outer face (journal shoulder)",
            "nut": "the flange face"}[part] if sec.datum_axis != ("major diameter",) else "the loaded-side end face"
    n0 = sec.thread_z[0] - sec.datum_face_z
    notes = [f"Datum A: {face}; datum B{'-C' if len(sec.datum_axis) == 2 else ''}: the axis of the {axis}",
             f"Thread tooth 1 (loaded end, z = 0) at {n0:.2f} mm from datum A; teeth numbered from there",
             "Geometric tolerances: prs_geom defaults for a precision PRS (ISO 1101, datums ISO 5459); "
             "values in parentheses are reference dimensions (ISO 129-1), not inspected"]
    if drive_note:
        notes.append(drive_note)
    notes += part_notes(getattr(design.materials, part), f"materials.{part}", "thread")
    lines = [w for n in notes for w in wrap_to_width(n, FRAME[2] - NOTES[0] - 3.0, TEXT_H)]
    # 5 mm a line down to the title block (its top at 75 mm); more lines step closer in the
    # smaller ISO 3098 height, whose text box still fits the closer step
    step = min(5.0, (NOTES[1] - TITLE_BLOCK[3] - 4.0) / max(len(lines) - 1, 1))
    height = TEXT_H if step >= 5.0 else 2.5
    for i, n in enumerate(lines):
        psp.add_text(n, height=height, dxfattribs={"layer": "TEXT"}).set_placement((NOTES[0], NOTES[1] - step * i))


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
    """One A3 page per document: its paper-space layout drawn by ezdxf's drawing add-on
    into PDF operators (:mod:`prs_geom.exports.sheet_pdf`), black lines on white, each
    line at its layer's ISO 128 width."""
    # ezdxf jiggles hatch lines by a random offset (ezdxf.render.hatching); a fixed seed,
    # restored afterwards, makes the PDF the same bytes from run to run
    state = random.getstate()
    random.seed(0)
    try:
        data = _render_pages(docs)
    finally:
        random.setstate(state)
    Path(path).write_bytes(data)


def _render_pages(docs: list) -> bytes:
    from ezdxf.addons.drawing import Frontend, RenderContext
    from ezdxf.addons.drawing.config import BackgroundPolicy, ColorPolicy, Configuration

    from prs_geom.exports.sheet_pdf import PdfSheetBackend, pdf_document

    cfg = Configuration(background_policy=BackgroundPolicy.WHITE, color_policy=ColorPolicy.BLACK)
    pages = []
    for doc in docs:
        # the page is the sheet, whatever is drawn: paper space 1:1, origin bottom left
        backend = PdfSheetBackend(SHEET)
        Frontend(RenderContext(doc), backend, config=cfg).draw_layout(doc.paperspace(), finalize=True)
        pages.append((SHEET, backend.content()))
    return pdf_document(pages)


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
