"""Per-part engineering drawings (DXF + PDF) read back with ezdxf, an independent reader."""
import math
import re
import shutil
import subprocess
from datetime import datetime
from pathlib import Path

import ezdxf
import numpy as np
import pytest

from prs_geom.geometry.frames import screw_thread_length
from ezdxf import bbox
from ezdxf.tools import juliandate

from prs_geom.analysis.contact import analyse_contact
from prs_geom.exports.drawing import PARTS, design_hash
from prs_geom.exports.mechanism_drawing import write_all_drawings
from prs_geom.model.design import Nut, PRSDesign, Roller

PL_R = tuple(2.0 + 4e-4 * (19 - j) / 19 + 1e-4 * math.sin(j) for j in range(19))
PL_N = tuple(2.0 + 6e-4 * (19 - j) / 19 + 2e-4 * math.cos(j) for j in range(19))
DATE = "2026-01-02"
VERSION = "9.8.7-test"


@pytest.fixture(scope="module")
def drawings(tmp_path_factory):
    d = PRSDesign(name="drawtest", roller=Roller(pitch_list_mm=PL_R), nut=Nut(pitch_list_mm=PL_N))
    contact = analyse_contact(d)
    out = tmp_path_factory.mktemp("drawings")
    names = write_all_drawings(d, contact, out, DATE, VERSION)
    docs = {part: ezdxf.readfile(out / f"drawing_{part}.dxf") for part in PARTS}
    return d, contact, out, names, docs


def _dims(doc):
    return {e.dxf.text: e for e in doc.modelspace() if e.dxftype() == "DIMENSION"}


def test_files_header_layers_and_audit(drawings):
    d, _, out, names, docs = drawings
    assert names == ["drawing_screw.dxf", "drawing_roller.dxf", "drawing_nut.dxf", "drawing_carrier.dxf",
                     "drawing_nut_end.dxf", "drawing_assembly.dxf", "drawings.pdf"]
    for part, doc in docs.items():
        assert doc.dxfversion == "AC1024"                     # R2010
        assert doc.header["$INSUNITS"] == 4 and doc.header["$MEASUREMENT"] == 1
        auditor = doc.audit()
        assert not auditor.has_errors, [str(e) for e in auditor.errors]
        for layer in ("OUTLINE", "CENTER", "DIMENSIONS", "TEXT", "DETAIL", "TITLE"):
            assert layer in doc.layers
        assert doc.layers.get("CENTER").dxf.linetype.upper() == "CENTER"
        centre = [e for e in doc.modelspace() if e.dxf.layer == "CENTER"]
        assert len(centre) == 1 and centre[0].dxftype() == "LINE"
        assert centre[0].dxf.start.y == centre[0].dxf.end.y == 0.0


def test_dimension_measurements_are_the_design_values(drawings):
    d, contact, _, _, docs = drawings
    n, p = d.thread.engaged_teeth, d.thread.pitch_mm
    expected = {
        "screw": {"P = <>": p, "<> (threaded length)": screw_thread_length(d),
                  "%%c<> major": d.screw.major_diameter_mm, "%%c<> minor": d.screw.minor_diameter_mm,
                  "%%c<> pitch (theor.)": contact.theoretical_screw_pitch_diameter_mm,
                  "<> (included flank angle)": 2.0 * d.thread.flank_half_angle_deg},
        "roller": {"P = <>": PL_R[0], "<> (threaded length)": n * p,
                   "%%c<> major": d.roller.major_diameter_mm, "%%c<> minor": d.roller.minor_diameter_mm,
                   "%%c<> pitch": d.roller.pitch_diameter_mm,
                   # tangents at the pitch point: 2 asin(r_r / r_T) (= 2 beta for the default r_T)
                   "<> (included flank angle)": 2.0 * math.degrees(math.asin(0.5 * d.roller.pitch_diameter_mm
                                                               / d.roller.arc_radius_mm)),
                   "<> (flank arc r_T)": d.roller.arc_radius_mm},
        "nut": {"P = <>": PL_N[0], "<> (threaded length)": n * p,
                "%%c<> major": d.nut.major_diameter_mm, "%%c<> minor": d.nut.minor_diameter_mm,
                "%%c<> pitch": d.nut.pitch_diameter_mm, "%%c<> body": d.nut.outer_diameter_mm,
                "<> (included flank angle)": 2.0 * d.thread.flank_half_angle_deg},
    }
    assert expected["roller"]["<> (included flank angle)"] == pytest.approx(90.0, abs=1e-9)
    assert contact.theoretical_screw_pitch_diameter_mm < d.screw.pitch_diameter_mm - 1e-4
    for part, doc in docs.items():
        # the angular datum slot B: its depth, a quarter pitch by the sizing rule
        expected[part]["<> (slot B depth)"] = 0.25 * p
        dims = _dims(doc)
        assert set(dims) == set(expected[part]), part
        for text, value in expected[part].items():
            assert dims[text].get_measurement() == pytest.approx(value, abs=1e-6), (part, text)
            assert dims[text].dxf.layer == "DIMENSIONS"
            assert dims[text].dxf.geometry in doc.blocks        # rendered
        kinds = {t: dims[t].dimtype for t in dims}
        assert kinds["<> (included flank angle)"] == 5                         # angular, 3 points
        if part == "roller":
            assert kinds["<> (flank arc r_T)"] == 4                # radius


def test_outlines_are_closed_and_the_screw_is_at_its_theoretical_pitch_diameter(drawings):
    d, contact, _, _, docs = drawings
    for part, doc in docs.items():
        outline = [e for e in doc.modelspace() if e.dxf.layer == "OUTLINE"]
        assert outline and all(e.dxftype() == "LWPOLYLINE" and e.closed for e in outline)
        assert len(outline) == (2 if part == "nut" else 1)
        detail = [e for e in doc.modelspace() if e.dxf.layer == "DETAIL"]
        assert len(detail) == 1 and detail[0].closed
    # at the theoretical pitch radius the screw's axial tooth and groove are both p / 2
    (pl,) = [e for e in docs["screw"].modelspace() if e.dxf.layer == "OUTLINE"]
    pts = np.array([(x, y) for x, y, *_ in pl.get_points("xy")])
    r = 0.5 * contact.theoretical_screw_pitch_diameter_mm
    top = pts[pts[:, 1] > 0]
    xs = []
    for (x0, y0), (x1, y1) in zip(top[:-1], top[1:]):
        if (y0 - r) * (y1 - r) < 0:
            xs.append(x0 + (x1 - x0) * (r - y0) / (y1 - y0))
    # the thread ends (run-out planes of the actuator) cut a tooth or a groove anywhere: whole
    # widths only between the first and the last crossing
    widths = np.diff(np.sort(xs))[1:-1]
    assert len(widths) > 30
    np.testing.assert_allclose(widths, 0.5 * d.thread.pitch_mm, atol=1e-9)
    assert pts[:, 1].max() == pytest.approx(0.5 * d.screw.major_diameter_mm, abs=1e-12)
    assert pts[:, 1].min() == pytest.approx(-0.5 * d.screw.major_diameter_mm, abs=1e-12)


def test_extents_and_limits(drawings):
    _, _, _, _, docs = drawings
    for doc in docs.values():
        ext = bbox.extents(doc.modelspace())
        np.testing.assert_allclose(doc.header["$EXTMIN"], ext.extmin, atol=1e-9)
        np.testing.assert_allclose(doc.header["$EXTMAX"], ext.extmax, atol=1e-9)
        assert tuple(doc.header["$PLIMMIN"])[:2] == (0.0, 0.0)
        assert tuple(doc.header["$PLIMMAX"])[:2] == (420.0, 297.0)


def test_paper_space_title_block_and_viewports(drawings):
    d, _, _, _, docs = drawings
    for part, doc in docs.items():
        layouts = [name for name in doc.layout_names() if name != "Model"]
        assert layouts == [f"A3_{part.upper()}"]
        psp = doc.paperspace(layouts[0])
        texts = " | ".join(e.dxf.text for e in psp if e.dxftype() == "TEXT" and e.dxf.layer == "TITLE")
        # the largest standard scale that fits the section viewport with its dimensions: the
        # nut body (56 mm) needs 112 + 24 mm at 2:1 and the viewport is 135 mm tall; the
        # actuator's screw thread (201.5 mm) fits only at 1:1
        scale = "2:1" if part == "roller" else "1:1"
        for needle in (f"Design: {d.name}", f"Part: {part}", f"Scale: {scale}", f"prs_geom: {VERSION}",
                       f"Date: {DATE}", "Units: mm", "Material: 100Cr6 (1.3505)",
                       "Heat treatment: hardened and tempered",      # wrapped in its cell at 2.5 mm
                       f"Design sha256: {design_hash(d)}"):
            assert needle in texts, (part, needle)
        heights = {round(e.dxf.height, 6) for e in psp if e.dxftype() == "TEXT"}
        assert {3.5, 5.0} <= heights
        vps = [e for e in psp if e.dxftype() == "VIEWPORT"]
        views = [v for v in vps if v.dxf.status != 1]
        assert len(views) >= 2
        scales = sorted(round(v.dxf.height / v.dxf.view_height, 9) for v in views)
        assert scales == [2.0 if part == "roller" else 1.0, 10.0]
        for v in views:   # inside the A3 sheet
            assert 0 < v.dxf.center.x - v.dxf.width / 2 and v.dxf.center.x + v.dxf.width / 2 < 420
            assert 0 < v.dxf.center.y - v.dxf.height / 2 and v.dxf.center.y + v.dxf.height / 2 < 297


def _layout_texts(doc):
    """Every TEXT / MTEXT string of every layout, with the measurement texts the dimensions
    render (ezdxf's virtual entities), as (layout name, text)."""
    out = []
    for layout in doc.layouts:
        for e in layout:
            found = list(e.virtual_entities()) if e.dxftype() == "DIMENSION" else [e]
            out += [(layout.name, v.plain_text() if v.dxftype() == "MTEXT" else v.dxf.text)
                    for v in found if v.dxftype() in ("TEXT", "MTEXT")]
    return out


def test_sheets_form_one_numbered_set_with_clean_texts(drawings):
    """The six sheets of drawings.pdf read "Sheet n/6" for n = 1 ... 6 in page order (issue 33:
    one sheet numbered 1/3 next to 4/6); no text carries a caret (a DXF control code: "kg/m^3"
    printed as "kg/mq") or a doubled diameter sign."""
    _, _, out, names, _ = drawings
    dxfs = [n for n in names if n.endswith(".dxf")]
    assert len(dxfs) == 6
    sheets = []
    for name in dxfs:
        texts = _layout_texts(ezdxf.readfile(out / name))
        sheets += [t.split("Sheet: ")[1] for _, t in texts if t.startswith("Sheet: ")]
        for layout, t in texts:
            assert "^" not in t, (name, layout, t)
            assert not re.search(r"(%%c|\u00d8|\u2300)\s*(%%c|\u00d8|\u2300)", t, re.I), (name, layout, t)
    assert sheets == [f"{n}/6 A3" for n in range(1, 7)]
    density = [t for _, t in _layout_texts(ezdxf.readfile(out / "drawing_carrier.dxf")) if t.startswith("Density")]
    assert density == ["Density: 7850 kg/m\u00b3"]


#: what ezdxf stamps on every save with the current time (the creation date and the
#: fingerprint GUID come from the date string and the design, so they must match)
_VOLATILE = re.compile(rb"\n\$(TDUPDATE|TDUUPDATE|TDINDWG|TDUSRTIMER|VERSIONGUID)\r?\n *\d+\r?\n[^\r\n]*")
_STAMP = re.compile(rb"\n[0-9.]+ @ \d{4}-\d\d-\d\dT[^\r\n]*")


def test_dxf_bytes_are_deterministic(drawings, tmp_path):
    d, contact, out, _, _ = drawings
    names = write_all_drawings(d, contact, tmp_path, DATE, VERSION)
    assert (tmp_path / names[-1]).read_bytes() == (out / names[-1]).read_bytes()     # the PDF too
    names = names[:-1]
    created = re.search(rb"\n\$TDCREATE\r?\n *40\r?\n([^\r\n]*)", (tmp_path / names[0]).read_bytes())
    assert float(created.group(1)) == juliandate(datetime(2026, 1, 2))
    for name in names:
        a, b = ((tmp_path / name).read_bytes(), (out / name).read_bytes())
        assert _STAMP.sub(b"", _VOLATILE.sub(b"", a)) == _STAMP.sub(b"", _VOLATILE.sub(b"", b))


def _pgm_ink(path) -> float:
    data = path.read_bytes()
    parts = data.split(maxsplit=4)             # P5, width, height, maxval, pixels
    w, h = int(parts[1]), int(parts[2])
    px = np.frombuffer(parts[4][: w * h], dtype=np.uint8)
    return float((px < 128).mean())


def test_pdf_has_one_non_empty_page_per_part(drawings, tmp_path):
    """A page per thread part and per mechanism drawing (carrier, nut end, assembly)."""
    _, _, out, _, _ = drawings
    pdf = out / "drawings.pdf"
    raw = pdf.read_bytes()
    assert raw.startswith(b"%PDF") and len(raw) > 50_000
    assert raw.count(b"/Type /Page") - raw.count(b"/Type /Pages") == 6
    if shutil.which("pdftoppm") is None:
        pytest.skip("pdftoppm not installed: page rendering not checked")
    subprocess.run(["pdftoppm", "-r", "20", "-gray", str(pdf), str(tmp_path / "pg")], check=True)
    pages = sorted(tmp_path.glob("pg-*.pgm"))
    assert len(pages) == 6
    for page in pages:
        assert _pgm_ink(page) > 0.005, page


def test_datum_slot_b_in_the_drawing_is_the_slot_cut_in_the_mesh(drawings):
    """The notch of face A in the theta = 0 outline is the slot of the part mesh: the same
    corners in the drawing, and in the mesh a point inside the slot is outside the solid
    while the same point moved by the slot width sideways (y) is inside it."""
    from prs_geom.exports.drawing import part_datum_mark, part_profiles
    from prs_geom.mesh.assembly import build_part

    d, contact, _, _, docs = drawings
    for part, doc in docs.items():
        profile = part_profiles(d, contact)[part]
        mark = part_datum_mark(d, part, profile)
        pts = set()
        for e in doc.modelspace():
            if e.dxf.layer == "OUTLINE":
                pts |= {(round(x, 12), round(y, 12)) for x, y, *_ in e.get_points("xy")}
        corners = [(mark.z_face, mark.r_inner), (mark.z_face + mark.depth, mark.r_inner),
                   (mark.z_face + mark.depth, mark.r_outer), (mark.z_face, mark.r_outer)]
        assert all((round(x, 12), round(y, 12)) in pts for x, y in corners), part
        # the lower outline (theta = 180 deg) has no slot
        assert (round(mark.z_face + mark.depth, 12), round(-mark.r_inner, 12)) not in pts
        tm = build_part(d, part, screw_profile=contact.screw_profile if part == "screw" else None)
        assert tm.datum_mark == mark
        centre = np.array([0.5 * (mark.r_inner + mark.r_outer), 0.0, mark.z_face + 0.5 * mark.depth])
        probes = [centre, centre + [0.0, mark.width, 0.0], centre + [0.0, -mark.width, 0.0],
                  centre + [0.0, 0.0, mark.depth]]
        assert [_inside(tm.vertices, tm.faces, q) for q in probes] == [False, True, True, True], part


def _inside(V: np.ndarray, F: np.ndarray, q: np.ndarray) -> bool:
    """Point in a closed mesh by ray parity (Moller-Trumbore), along a skew direction that
    meets no edge or vertex of these meshes."""
    d = np.array([0.31, 0.17, -0.93])
    d /= np.linalg.norm(d)
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    e1, e2 = b - a, c - a
    h = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, h)
    ok = np.abs(det) > 1e-15
    s_ = q - a
    u = np.einsum("ij,ij->i", s_, h) / np.where(ok, det, 1.0)
    qv = np.cross(s_, e1)
    v = (qv @ d) / np.where(ok, det, 1.0)
    t = np.einsum("ij,ij->i", e2, qv) / np.where(ok, det, 1.0)
    hits = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    return bool(hits.sum() % 2)


def test_pdf_sheet_axes_give_the_bytes_of_plain_axes(drawings, tmp_path, monkeypatch):
    """Issue 17: the sheets add ezdxf's patches without growing the axes' data limits (the
    view is the sheet, set afterwards); the page is byte for byte the one plain matplotlib
    Axes give. The roller sheet has every kind of entity: text, hatches, linear, angular and
    radius dimensions, bulges."""
    from matplotlib.axes import Axes

    from prs_geom.exports import drawing
    from prs_geom.exports.drawing import build_drawing, render_pdf

    d, contact, _, _, _ = drawings
    fast, plain = tmp_path / "fast.pdf", tmp_path / "plain.pdf"
    render_pdf([build_drawing(d, contact, "roller", DATE, VERSION)], fast)
    monkeypatch.setattr(drawing, "_sheet_axes_class", lambda: Axes)
    render_pdf([build_drawing(d, contact, "roller", DATE, VERSION)], plain)
    assert fast.read_bytes() == plain.read_bytes()


# --------------------------------------------------------------------------- mechanism drawings
def test_mechanism_drawings_dimension_the_layout(drawings):
    """Carrier and nut end read back with ezdxf: every DIMENSION measures the size the
    meshes and checks use (prs_geom.geometry.mechanism.layout); files audit clean."""
    from prs_geom.geometry.mechanism import layout

    d, _, out, _, _ = drawings
    lay = layout(d)
    carrier = ezdxf.readfile(out / "drawing_carrier.dxf")
    nut_end = ezdxf.readfile(out / "drawing_nut_end.dxf")
    for doc in (carrier, nut_end):
        auditor = doc.audit()
        assert not auditor.has_errors, [str(e) for e in auditor.errors]
        assert doc.header["$INSUNITS"] == 4
    dims = _dims(carrier)
    fit = lay.journal_fit
    assert dims["<> outside"].get_measurement() == pytest.approx(2 * lay.carrier_outer_radius_mm, abs=1e-9)
    assert dims["<> bore"].get_measurement() == pytest.approx(2 * lay.carrier_inner_radius_mm, abs=1e-9)
    assert dims["<> journal bores"].get_measurement() == pytest.approx(fit.nominal_diameter_mm, abs=1e-9)
    # every drawn dimension text carries at most one diameter sign (a DIAMETER dimension adds
    # its own before the measurement; the verify kit found "%%c%%c40.5000 outside")
    for doc in (carrier, nut_end):
        for dim in (e for e in doc.modelspace() if e.dxftype() == "DIMENSION"):
            texts = [t.plain_text() if t.dxftype() == "MTEXT" else t.dxf.text
                     for t in dim.get_geometry_block() if t.dxftype() in ("MTEXT", "TEXT")]
            assert all(t.count("%%c") + t.count("\u2300") + t.count("\u00d8") <= 1 for t in texts), texts
    assert dims["<> thickness"].get_measurement() == pytest.approx(lay.carrier_thickness_mm, abs=1e-9)
    assert dims["%%c<> pitch circle"].get_measurement() == pytest.approx(2 * lay.centre_distance_mm, abs=1e-9)
    # z bores on the centre-distance circle
    bores = [e for e in carrier.modelspace() if e.dxftype() == "CIRCLE" and e.dxf.layer == "OUTLINE"
             and abs(e.dxf.radius - 0.5 * fit.nominal_diameter_mm) < 1e-12]
    assert len(bores) == d.roller.count
    for b in bores:
        assert math.hypot(b.dxf.center.x, b.dxf.center.y) == pytest.approx(lay.centre_distance_mm, abs=1e-12)
    ring, end = lay.ring, lay.ends[0]
    dims = _dims(nut_end)
    assert dims["m <>"].get_measurement() == pytest.approx(ring.groove_width_mm, abs=1e-9)
    assert dims["n <> min"].get_measurement() == pytest.approx(end.groove[0] - end.nut_end[0], abs=1e-9)
    assert dims["n <> min"].get_measurement() >= ring.edge_distance_mm - 1e-12
    assert dims["<> to groove (from A)"].get_measurement() == pytest.approx(-end.groove[1], abs=1e-9)
    assert dims["<> nut end"].get_measurement() == pytest.approx(end.nut_end[1] - end.nut_end[0], abs=1e-9)
    for label, dia in (("%%c<> groove", ring.groove_diameter_mm), ("%%c<> bore", ring.bore_mm),
                       ("%%c<> outside", d.nut.outer_diameter_mm)):
        assert dims[label].get_measurement() == pytest.approx(dia, abs=1e-9)
    # no digits in a label: the first number a reader finds in a dimension is its value
    for doc in (carrier, nut_end):
        for e in doc.modelspace():
            if e.dxftype() == "DIMENSION":
                assert not re.search(r"\d", e.dxf.text), e.dxf.text


def test_assembly_balloons_match_the_parts_list(drawings):
    """One balloon per parts-list item, numbered like parts_list.csv, each circle with its
    number and a leader that ends on its part's outline region."""
    from prs_geom.exports.bom import part_items

    d, _, out, _, _ = drawings
    doc = ezdxf.readfile(out / "drawing_assembly.dxf")
    items = part_items(d)
    msp = doc.modelspace()
    texts = sorted(int(e.dxf.text) for e in msp if e.dxftype() == "TEXT" and e.dxf.layer == "BALLOONS")
    # screw, roller, nut, carrier, retaining ring; the actuator's bearings (fixed, floating),
    # locknut, shaft ring, flange bolts and drive key
    assert texts == [it.item for it in items] == list(range(1, 12))
    leaders = [e for e in msp if e.dxftype() == "LINE" and e.dxf.layer == "BALLOONS"]
    assert len(leaders) == len(items)
    notes = " ".join(e.dxf.text for e in doc.paperspace() if e.dxftype() == "TEXT")
    for it in items:
        assert f"{it.item}  {it.part}  x{it.quantity}" in notes
    assert items[4].designation in notes


EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.mark.parametrize("example", ["default", "graded-pitch", "four-start-seven-rollers"])
def test_no_two_text_boxes_overlap_on_any_sheet(example):
    """Issue 33: on every sheet (model and paper space) of the default, graded and 4-start,
    7-roller designs, no two text boxes (TEXT, MTEXT and the dimensions' measurement texts,
    sized by ezdxf on the pinned DejaVu Sans) come closer than a tenth of the smaller text's
    height (0.35 mm on paper for 3.5 mm text; each box grown by 5 % of its height); every
    paper-space text lies inside the frame, and every title-block text inside its column; no
    paper-space text is below ISO 3098's 2.5 mm."""
    import itertools

    from readers import boxes_overlap, dxf_text_boxes

    from prs_geom.exports.bom import part_items
    from prs_geom.exports.drawing import build_drawing
    from prs_geom.exports.sheet import DRAWING_FONT, FRAME, TITLE_BLOCK
    from prs_geom.exports.mechanism_drawing import mechanism_drawings
    from prs_geom.geometry.mechanism import layout
    from prs_geom.model.design import default_design
    from prs_geom.model.io import load_design

    d = default_design() if example == "default" else load_design(EXAMPLES / f"{example}.toml")
    contact = analyse_contact(d)
    docs = {part: build_drawing(d, contact, part, DATE, VERSION, sheets=6) for part in PARTS}
    docs.update(mechanism_drawings(d, layout(d), part_items(d), DATE, VERSION))
    clashes = []
    for name, doc in docs.items():
        assert {s.dxf.font for s in doc.styles} == {DRAWING_FONT}, name
        for lay in doc.layouts:
            boxes = dxf_text_boxes(doc, lay)
            assert boxes or lay.name == "Model", (name, lay.name)
            clashes += [(name, lay.name, a, b) for (a, qa, ha), (b, qb, hb) in itertools.combinations(boxes, 2)
                        if boxes_overlap(qa, qb, 0.05 * min(ha, hb))]
            if lay.name != "Model":
                # ISO 3098: no text on paper below 2.5 mm
                clashes += [(name, lay.name, a, f"height {h:g}") for a, _, h in boxes if h < 2.5 - 1e-9]
                fx0, fy0, fx1, fy1 = FRAME
                clashes += [(name, lay.name, a, "frame") for a, q, _ in boxes
                            if q[:, 0].min() < fx0 or q[:, 0].max() > fx1 or q[:, 1].min() < fy0 or q[:, 1].max() > fy1]
                x0, _, x1, y1 = TITLE_BLOCK
                xm = 0.5 * (x0 + x1)
                for label, q, _ in boxes:
                    lo, hi = q[:, 0].min(), q[:, 0].max()
                    if q[:, 1].max() < y1 - 10.0 and lo >= x0:       # a title-block cell
                        if not (hi <= xm or lo >= xm) or hi > x1:
                            clashes.append((name, lay.name, label, "title-block column"))
    assert not clashes


def test_every_part_sheet_states_material_general_tolerances_and_surface_texture(drawings):
    """Issue 33: each part sheet (screw, roller, nut, carrier, nut end) carries its material
    line (name, grade and heat treatment from the design's materials, or the design-file
    field to set where a grade is not given), the general-tolerance note (ISO 2768-1 m, ISO
    22081) and the surface texture note (ISO 21920-1, Ra in µm); the assembly sheet none of
    them. Read back from the DXF texts, wrapped lines joined."""
    from prs_geom.exports.sheet import GENERAL_TOLERANCES, SURFACE_TEXTURE, material_note

    d, _, out, _, _ = drawings
    sheets = {"screw": ("screw", "thread"), "roller": ("roller", "thread"), "nut": ("nut", "thread"),
              "carrier": ("carrier", "carrier"), "nut_end": ("nut", "nut_end")}
    for sheet, (part, texture) in sheets.items():
        doc = ezdxf.readfile(out / f"drawing_{sheet}.dxf")
        psp = [lay for lay in doc.layouts if lay.name != "Model"][0]
        lines = [e.dxf.text for e in sorted((e for e in psp if e.dxftype() == "TEXT" and e.dxf.layer == "TEXT"),
                                            key=lambda e: -e.dxf.insert.y)]
        # wrapped notes continue on lines indented by two spaces
        joined = " | ".join(lines).replace(" |   ", " ")
        material = getattr(d.materials, part)
        for note in (material_note(material, f"materials.{part}"), GENERAL_TOLERANCES,
                     f"Surface texture (ISO 21920-1): {SURFACE_TEXTURE[texture]}"):
            assert note in joined, (sheet, note)
    assert "100Cr6 (1.3505); heat treatment: hardened and tempered, 58-62 HRC" in material_note(d.materials.roller, "x")
    assert "grade not specified (materials.carrier.grade)" in material_note(d.materials.carrier, "materials.carrier")
    doc = ezdxf.readfile(out / "drawing_assembly.dxf")
    assert not any(GENERAL_TOLERANCES[:20] in t for _, t in _layout_texts(doc))
