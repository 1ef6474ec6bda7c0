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
        # the axis, and for a part with gears the gears' reference lines (ISO 2203) at +-r
        # (and the centre lines of the screw's SECTION K-K, in its own region)
        centre = [e for e in doc.modelspace() if e.dxf.layer == "CENTER"]
        assert all(e.dxftype() == "LINE" for e in centre)
        assert sum(e.dxf.start.y == e.dxf.end.y == 0.0 and e.dxf.start.x < 0.0 for e in centre) == 1


def test_detail_dimensions_are_the_design_values(drawings):
    """DETAIL A (normal section of one tooth): the included flank angle (for the roller
    between the flank tangents at the pitch point) and the roller's flank arc radius r_T."""
    d, contact, _, _, docs = drawings
    expected = {"screw": 2.0 * d.thread.flank_half_angle_deg, "nut": 2.0 * d.thread.flank_half_angle_deg,
                # tangents at the pitch point: 2 asin(r_r / r_T) (= 2 beta for the default r_T)
                "roller": 2.0 * math.degrees(math.asin(0.5 * d.roller.pitch_diameter_mm / d.roller.arc_radius_mm))}
    for part, doc in docs.items():
        dims = _dims(doc)
        angle = dims["<> flank angle"]
        assert angle.dimtype == 5 and angle.get_measurement() == pytest.approx(expected[part], abs=1e-6)
        if part == "roller":
            assert dims["<> r_T"].dimtype == 4
            assert dims["<> r_T"].get_measurement() == pytest.approx(d.roller.arc_radius_mm, abs=1e-9)


def _complete_part_span(d, part):
    """The complete part's end faces (mm, part frame) and largest radius, from the layouts
    (not from the drawing code): the screw's end faces; the roller's journals; the nut's
    ends and flange."""
    from prs_geom.geometry.actuator import actuator_layout
    from prs_geom.geometry.mechanism import layout

    act, mech = actuator_layout(d), layout(d)
    if part == "screw":
        return act.screw_z, 0.5 * d.screw.major_diameter_mm
    if part == "roller":
        return (mech.ends[0].journal[0], mech.ends[1].journal[1]), 0.5 * d.roller.major_diameter_mm
    return (mech.ends[0].nut_end[0], mech.ends[1].nut_end[1]), 0.5 * act.nut_mount.flange_diameter_mm


def test_section_outline_is_the_complete_part(drawings):
    """The hatched section is the complete part (issue 33): closed outlines from end face to
    end face of the screw (its ends), the roller (journals) and the nut (ends, flange), as far
    out as its largest radius; threads in the ISO 6410-1 convention (the section reaches the
    crest, the root a thin line over the thread)."""
    d, contact, _, _, docs = drawings
    for part, doc in docs.items():
        outline = [e for e in doc.modelspace() if e.dxf.layer == "OUTLINE" and e.dxftype() == "LWPOLYLINE"]
        assert outline and all(e.closed for e in outline)
        pts = np.array([(x, y) for e in outline for x, y, *_ in e.get_points("xy")])
        (z0, z1), r_max = _complete_part_span(d, part)
        assert pts[:, 0].min() == pytest.approx(z0, abs=1e-9) and pts[:, 0].max() == pytest.approx(z1, abs=1e-9)
        assert pts[:, 1].max() == pytest.approx(r_max, abs=1e-9)
        assert pts[:, 1].min() == pytest.approx(-r_max, abs=1e-9)
        hatches = [e for e in doc.modelspace() if e.dxftype() == "HATCH"]
        assert len(hatches) >= len(outline)
        thin = {round(abs(e.dxf.start.y), 9) for e in doc.modelspace() if e.dxf.layer == "THIN"}
        root = {"screw": d.screw.minor_diameter_mm, "roller": d.roller.minor_diameter_mm,
                "nut": d.nut.major_diameter_mm}[part]
        assert round(0.5 * root, 9) in thin, part


def test_extents_and_limits(drawings):
    _, _, _, _, docs = drawings
    for doc in docs.values():
        ext = bbox.extents(doc.modelspace())
        np.testing.assert_allclose(doc.header["$EXTMIN"], ext.extmin, atol=1e-9)
        np.testing.assert_allclose(doc.header["$EXTMAX"], ext.extmax, atol=1e-9)
        assert tuple(doc.header["$PLIMMIN"])[:2] == (0.0, 0.0)
        assert tuple(doc.header["$PLIMMAX"])[:2] == (420.0, 297.0)


def test_paper_space_title_block_and_viewports(drawings):
    """ISO 7200 title block (identification number, revision = the design hash, document
    type, date of issue, creator, sheet) and the ISO 5456-2 first-angle projection symbol;
    the section viewport at the largest ISO 5455 scale that holds the view with its
    annotation, the detail at 10:1."""
    d, _, _, _, docs = drawings
    # the section, the detail at 10:1 and the screw's SECTION K-K (drive journal)
    scales = {"screw": [1.0, 2.0, 10.0], "roller": [5.0, 10.0], "nut": [1.0, 10.0]}
    for i, (part, doc) in enumerate(docs.items()):
        layouts = [name for name in doc.layout_names() if name != "Model"]
        assert layouts == [f"A3_{part.upper()}"]
        psp = doc.paperspace(layouts[0])
        texts = " | ".join(e.dxf.text for e in psp if e.dxftype() == "TEXT" and e.dxf.layer == "TITLE")
        h = design_hash(d)
        for needle in (f"Design: {d.name}", f"Part: {part}", f"Creator: prs_geom {VERSION}",
                       f"Date of issue: {DATE}", "Material: 100Cr6 (1.3505)", f"Drawing no.: DRAWTEST-0{i + 1}",
                       f"Revision: {h[:8]}", "Document type: Detail drawing", "Heat treatment: hardened and tempered",
                       f"Design sha256: {h}"):
            assert needle in texts, (part, needle)
        # the projection symbol: a truncated cone's outline and its two circles, in the title block
        circles = sorted(round(e.dxf.radius, 6) for e in psp if e.dxftype() == "CIRCLE" and e.dxf.layer == "TITLE")
        assert circles == [1.5, 3.0]
        heights = {round(e.dxf.height, 6) for e in psp if e.dxftype() == "TEXT"}
        assert {3.5, 5.0} <= heights
        vps = [e for e in psp if e.dxftype() == "VIEWPORT"]
        views = [v for v in vps if v.dxf.status != 1]
        assert len(views) >= 2
        got = sorted(round(v.dxf.height / v.dxf.view_height, 9) for v in views)
        assert got == scales[part], part
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
            # a caret only where a DIMENSION stacks its limit deviations (MTEXT \\S upper^lower;)
            assert "^" not in re.sub(r"[+-]?\d+(\.\d+)?\^ ?[+-]?\d+(\.\d+)?", "", t), (name, layout, t)
            assert not re.search(r"(%%c|\u00d8|\u2300)\s*(%%c|\u00d8|\u2300)", t, re.I), (name, layout, t)
    assert sheets == [f"{n}/6 A3" for n in range(1, 7)]


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


def _reference_pdf(dxf_paths: list[Path], path: Path) -> None:
    """The sheets drawn by an independent renderer: ezdxf's matplotlib back end on A3 figures
    whose axes are the sheet, one page each (how drawings.pdf was written up to issue 36)."""
    from ezdxf.addons.drawing import Frontend, RenderContext
    from ezdxf.addons.drawing.config import BackgroundPolicy, ColorPolicy, Configuration
    from ezdxf.addons.drawing.matplotlib import MatplotlibBackend
    from matplotlib.backends.backend_pdf import PdfPages
    from matplotlib.figure import Figure

    from prs_geom.exports.sheet import SHEET

    cfg = Configuration(background_policy=BackgroundPolicy.WHITE, color_policy=ColorPolicy.BLACK)
    with PdfPages(path) as pdf:
        for dxf in dxf_paths:
            doc = ezdxf.readfile(dxf)
            fig = Figure(figsize=(SHEET[0] / 25.4, SHEET[1] / 25.4))
            ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
            Frontend(RenderContext(doc), MatplotlibBackend(ax, adjust_figure=False), config=cfg).draw_layout(
                doc.paperspace(), finalize=True)
            ax.set_aspect("equal", adjustable="box")
            ax.set_xlim(0.0, SHEET[0])
            ax.set_ylim(0.0, SHEET[1])
            pdf.savefig(fig)


def _pgm_ink_mask(path: Path) -> np.ndarray:
    parts = path.read_bytes().split(maxsplit=4)
    w, h = int(parts[1]), int(parts[2])
    return np.frombuffer(parts[4][: w * h], dtype=np.uint8).reshape(h, w) < 160


def test_pdf_pages_draw_what_an_independent_renderer_draws(drawings, tmp_path):
    """Issue 36: drawings.pdf is written by prs_geom's own PDF back end
    (prs_geom.exports.sheet_pdf). Each page, rasterised by poppler at 60 dpi, has its ink
    where ezdxf's matplotlib back end, a renderer of other authors, puts it on the same
    sheet: at most 0.5 % of either's ink pixels lie more than 2 px (0.85 mm) from the
    other's (measured: at most 0.1 %; line widths differ: the PDF draws ISO 128 widths,
    matplotlib about 0.25 mm for all)."""
    from scipy import ndimage

    if shutil.which("pdftoppm") is None:
        pytest.skip("pdftoppm not installed: pages not rasterised")
    _, _, out, names, _ = drawings
    reference = tmp_path / "reference.pdf"
    _reference_pdf([out / n for n in names if n.endswith(".dxf")], reference)
    for pdf, stem in ((out / "drawings.pdf", "ours"), (reference, "ref")):
        subprocess.run(["pdftoppm", "-r", "60", "-gray", str(pdf), str(tmp_path / stem)], check=True)
    ours, ref = sorted(tmp_path.glob("ours-*.pgm")), sorted(tmp_path.glob("ref-*.pgm"))
    assert len(ours) == len(ref) == 6
    for a_path, b_path in zip(ours, ref):
        a, b = _pgm_ink_mask(a_path), _pgm_ink_mask(b_path)
        assert a.shape == b.shape                    # the same A3 page at 60 dpi
        assert a.mean() > 0.02, a_path               # a drawn sheet, not a blank page
        near_a, near_b = ndimage.binary_dilation(a, iterations=2), ndimage.binary_dilation(b, iterations=2)
        assert (a & ~near_b).sum() <= 0.005 * a.sum(), a_path
        assert (b & ~near_a).sum() <= 0.005 * b.sum(), b_path


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
    # the journal bores: the measurement, the zone after it (DIMPOST)
    assert dims["<>"].get_measurement() == pytest.approx(fit.nominal_diameter_mm, abs=1e-9)
    assert dims["<>"].override().get("dimpost") == "<> H7"
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
    assert dims["<>"].override().get("dimpost") in ("m <> H13", "%%c<> H11")
    widths = [e for e in nut_end.modelspace() if e.dxftype() == "DIMENSION" and e.override().get("dimpost") == "m <> H13"]
    assert len(widths) == 1 and widths[0].get_measurement() == pytest.approx(ring.groove_width_mm, abs=1e-9)
    assert dims["n <> min"].get_measurement() == pytest.approx(end.groove[0] - end.nut_end[0], abs=1e-9)
    assert dims["n <> min"].get_measurement() >= ring.edge_distance_mm - 1e-12
    assert dims["<> to groove (from A)"].get_measurement() == pytest.approx(-end.groove[1], abs=1e-9)
    assert dims["<> nut end"].get_measurement() == pytest.approx(end.nut_end[1] - end.nut_end[0], abs=1e-9)
    for label, dia in (("%%c<> groove", ring.groove_diameter_mm), ("%%c<> outside", d.nut.outer_diameter_mm)):
        assert dims[label].get_measurement() == pytest.approx(dia, abs=1e-9)
    bores = [e for e in nut_end.modelspace() if e.dxftype() == "DIMENSION" and e.override().get("dimpost") == "%%c<> H11"]
    assert len(bores) == 1 and bores[0].get_measurement() == pytest.approx(ring.bore_mm, abs=1e-9)
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
    # the parts list (ISO 7573) on the sheet: a row of cells per item, read back by its height
    rows: dict[float, list] = {}
    for e in doc.paperspace():
        if e.dxftype() == "TEXT" and e.dxf.layer == "TEXT" and e.dxf.height == 2.5:
            rows.setdefault(round(e.dxf.insert.y, 6), []).append(e)
    table = [[e.dxf.text for e in sorted(r, key=lambda e: e.dxf.insert.x)] for _, r in sorted(rows.items(), reverse=True)]
    assert table[0] == ["Item", "Part", "Qty", "Material", "Designation"]
    for it, row in zip(items, table[1:]):
        assert row[:3] == [str(it.item), it.part, str(it.quantity)]
        assert row[3] == ("purchased" if it.material is None else it.material.name)
        assert (row[4] if len(row) > 4 else "") == (it.designation or "")


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
        x_notes = 230.0 if sheet in ("screw", "roller", "nut") else 25.0
        lines = [e.dxf.text for e in sorted((e for e in psp if e.dxftype() == "TEXT" and e.dxf.layer == "TEXT"
                                             and abs(e.dxf.insert.x - x_notes) < 1e-6), key=lambda e: -e.dxf.insert.y)]
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


# --------------------------------------------------------------------------- issue 33: a shop's sheets
def _example(example):
    from prs_geom.model.design import default_design
    from prs_geom.model.io import load_design

    return default_design() if example == "default" else load_design(EXAMPLES / f"{example}.toml")


@pytest.fixture(scope="module", params=["default", "graded-pitch", "four-start-seven-rollers"])
def sheet_set(request):
    """The six sheets of a design (default, graded, 4-start 7-roller), built in memory."""
    from prs_geom.exports.bom import part_items
    from prs_geom.exports.drawing import build_drawing
    from prs_geom.exports.mechanism_drawing import mechanism_drawings
    from prs_geom.geometry.mechanism import layout

    d = _example(request.param)
    contact = analyse_contact(d)
    docs = {part: build_drawing(d, contact, part, DATE, VERSION, sheets=6) for part in PARTS}
    for name, doc in mechanism_drawings(d, layout(d), part_items(d), DATE, VERSION).items():
        docs[name.removeprefix("drawing_").removesuffix(".dxf")] = doc
    return d, contact, docs


def _limit_dims(doc):
    """Every toleranced DIMENSION read back: (measurement, DIMPOST, upper, lower) with the
    limit deviations DIMTP and -DIMTM (mm)."""
    out = []
    for e in doc.modelspace():
        if e.dxftype() == "DIMENSION":
            ov = e.override()
            if ov.get("dimtol", 0) and re.search(r"<> [A-Za-z]{1,2}\d{1,2}$", ov.get("dimpost", "")):
                out.append((e.get_measurement(), ov.get("dimpost", ""), ov.get("dimtp", 0.0), -ov.get("dimtm", 0.0)))
    return out


def _expected_limits(d, contact):
    """The functional features each sheet must tolerance, from the design and its layouts
    (not the drawing code): {sheet: [(nominal mm, ISO 286 zone)]}."""
    from prs_geom.geometry.actuator import actuator_layout
    from prs_geom.geometry.gear_pair import design_gear_pair
    from prs_geom.geometry.mechanism import layout

    act, mech, pair = actuator_layout(d), layout(d), design_gear_pair(d)
    screw = [(contact.theoretical_screw_pitch_diameter_mm, d.screw.pitch_diameter_tolerance)]
    for end in act.ends:
        for st in end.steps:
            if st.name.endswith("bearing seat"):
                screw.append((st.diameter_mm, end.seat_tolerance))
            elif st.name == "drive journal":
                screw.append((st.diameter_mm, d.actuator.drive.fit))
        if end.key is not None:      # SECTION K-K: the keyway's width, DIN 6885-1 normal fit
            screw.append((end.key.width_mm, "N9"))
    hole, shaft = d.mechanism.journal_fit.split("/")
    bore = "H11" if d.mechanism.carrier_guidance == "clear" else d.mechanism.carrier_fit.split("/")[0]
    return {"screw": screw,
            "roller": [(d.roller.pitch_diameter_mm, d.roller.pitch_diameter_tolerance),
                       (min(2 * pair.pinion.tip_radius_mm, d.roller.major_diameter_mm), d.gears.tip_tolerance),
                       (mech.journal_diameter_mm, shaft), (mech.journal_diameter_mm, shaft)],
            "nut": [(d.nut.pitch_diameter_mm, d.nut.pitch_diameter_tolerance),
                    (2 * pair.ring.tip_radius_mm, d.gears.ring_tip_tolerance), (mech.ring.bore_mm, bore)],
            "carrier": [(mech.journal_diameter_mm, hole)],
            "nut_end": [(mech.ring.bore_mm, bore), (mech.ring.groove_width_mm, "H13")]}


def test_functional_features_carry_their_iso286_limits(sheet_set):
    """Issue 33: every listed functional feature (pitch diameters, bearing seats, drive
    journal, roller journals, gear tips, carrier journal bores, nut end bore, ring groove
    width) is a DIMENSION of its nominal size whose DIMPOST names the ISO 286 zone and whose
    limit deviations (DIMTP, DIMTM) are model/standards.py's for that size and zone."""
    from prs_geom.model.standards import tolerance_zone

    d, contact, docs = sheet_set
    for sheet, features in _expected_limits(d, contact).items():
        dims = _limit_dims(docs[sheet])
        for nominal, zone_symbol in features:
            found = [x for x in dims if abs(x[0] - nominal) < 1e-9 and re.search(rf"<> {zone_symbol}$", x[1])]
            assert found, (sheet, nominal, zone_symbol, dims)
            zone = tolerance_zone(nominal, zone_symbol)
            for _, _, upper, lower in found:
                assert upper == pytest.approx(zone.upper_mm, abs=1e-12) and lower == pytest.approx(zone.lower_mm, abs=1e-12)
        # and nothing toleranced that is not a listed feature (a feature on both ends twice,
        # unless its callout reads "2x")
        assert len(dims) == len(features), (sheet, dims)
    # the keyway depth from the journal's far side, d - t1, with DIN 6885-1's limits
    from prs_geom.geometry.actuator import actuator_layout

    end = next(e for e in actuator_layout(d).ends if e.key_z is not None)
    if end.key is not None:
        (depth,) = [e for e in docs["screw"].modelspace() if e.dxftype() == "DIMENSION"
                    and e.override().get("dimpost") == "<> (d - t1)"]
        d_j = next(st.diameter_mm for st in end.steps if st.name == "drive journal")
        assert depth.get_measurement() == pytest.approx(d_j - end.key.shaft_depth_mm, abs=1e-9)
        assert (depth.override().get("dimtp"), -depth.override().get("dimtm")) == (0.0, -0.1)


def _table_cells(doc):
    """The data tables of a thread sheet read back: {label: value} from the 2.5 mm texts left
    of the notes, a label and its value on one row, left to right."""
    rows: dict[float, list] = {}
    psp = [lay for lay in doc.layouts if lay.name != "Model"][0]
    for e in psp:
        if e.dxftype() == "TEXT" and e.dxf.layer == "TEXT" and e.dxf.height == 2.5 and e.dxf.insert.x < 229.0:
            rows.setdefault(round(e.dxf.insert.y, 6), []).append(e)
    cells = {}
    for row in rows.values():
        texts = [e.dxf.text for e in sorted(row, key=lambda e: e.dxf.insert.x)]
        for label, value in zip(texts[0::2], texts[1::2]):
            cells.setdefault(label, value)
    return cells


def _dev(mm):
    um = round(mm * 1000)
    return "0" if um == 0 else f"{um / 1000:+.3f}"


def test_thread_gear_and_pitch_tables_equal_the_design_and_report(sheet_set):
    """Issue 33: the thread data table (pitch, starts, lead, hand, flank, pitch diameter with
    its zone and limits, major/minor, threaded length, teeth, lead deviation), the gear data
    table (the report's gear data: module, teeth, pressure angle, shift, tip with its zone;
    span W_k and the pin size, upper limit = the report's thinned-tooth value, span from nominal
    by the backlash thinning, lower limit a thickness tolerance further, both times cos alpha)
    and the pitch list equal the design at their printed precision."""
    from prs_geom.exports.report import _gear
    from prs_geom.geometry.frames import screw_thread_length
    from prs_geom.geometry.gear_pair import design_gear_pair
    from prs_geom.model.standards import tolerance_zone

    d, contact, docs = sheet_set
    pair = design_gear_pair(d)
    n, p = d.thread.engaged_teeth, d.thread.pitch_mm
    for part in PARTS:
        cells = _table_cells(docs[part])
        spec = getattr(d, part)
        starts = 1 if part == "roller" else spec.starts
        dp = contact.theoretical_screw_pitch_diameter_mm if part == "screw" else spec.pitch_diameter_mm
        zone = tolerance_zone(dp, spec.pitch_diameter_tolerance)
        assert cells["Starts"] == str(starts) and cells["Hand"] == d.thread.hand
        assert cells["Pitch P"].startswith(f"{p:.4f} mm") and cells["Lead"] == f"{starts * p:.4f} mm"
        key = "Pitch diameter (theor.)" if part == "screw" else "Pitch diameter"
        assert cells[key] == (f"\u00d8{dp:.4f} {spec.pitch_diameter_tolerance} "
                              f"({_dev(zone.upper_mm)}/{_dev(zone.lower_mm)})")
        major, minor = ((spec.major_diameter_mm, spec.minor_diameter_mm) if part != "nut"
                        else (spec.major_diameter_mm, spec.minor_diameter_mm))
        assert cells["Major / minor dia."] == f"\u00d8{major:.4f} / \u00d8{minor:.4f}"
        length = screw_thread_length(d) if part == "screw" else n * p
        assert cells["Threaded length"] == f"{length:.2f} mm" and cells["Engaged teeth"] == str(n)
        assert "\u00b5m" in cells["Lead deviation"]
        if part == "screw":
            assert "Module m" not in cells
            continue
        g = pair.pinion if part == "roller" else pair.ring
        rep = _gear(g, part == "nut")
        assert cells["Module m"] == f"{rep['module_mm']:g} mm" and cells["Teeth z"] == str(rep["teeth"])
        assert cells["Pressure angle"] == f"{rep['pressure_angle_deg']:g}\u00b0"
        assert float(cells["Profile shift x"]) == pytest.approx(rep["profile_shift"], abs=5e-5)
        assert cells["Accuracy"] == f"ISO 1328-1 class {d.gears.accuracy_grade}"
        assert cells["Reference dia. d"] == f"({rep['pitch_diameter_mm']:.4f})"     # a reference dimension
        cos_a = math.cos(math.radians(rep["pressure_angle_deg"]))
        k = rep["span_teeth"]
        span = re.fullmatch(r"([\d.]+) \(([^/]+)/([^)]+)\)", cells[f"Span W{k} ({k} teeth)"])
        base, up, lo = float(span[1]), float(span[2]), float(span[3])
        assert base + up == pytest.approx(rep["span_measurement_mm"], abs=1.01e-4)
        # ISO 21771: W_k = (k - 1) p_b + s_b, so a tooth thinner by ds spans ds cos(alpha) less
        sign = -1.0
        assert up == pytest.approx(sign * rep["backlash_thinning_mm"] * cos_a, abs=1.01e-4)
        assert lo - up == pytest.approx(sign * d.gears.thickness_tolerance_mm * cos_a, abs=1.01e-4)
        pins = "between_pins_mm" if part == "nut" else "over_pins_mm"
        label = f"{'Between' if part == 'nut' else 'Over'} pins \u00d8{rep['pin_diameter_mm']:.4f}"
        m = re.fullmatch(r"([\d.]+) \(([^/]+)/([^)]+)\)", cells[label])
        # the thinned tooth (the report's) is the limit nearer the nominal size
        near = min((float(m[2]), float(m[3])), key=abs)
        assert float(m[1]) + near == pytest.approx(rep[pins], abs=1.01e-4), part
        pl = spec.pitch_list_mm
        if pl is not None:
            for j, v in enumerate(pl):
                assert cells[f"{j + 1}-{j + 2}"] == f"{v:.6f}"
        else:
            assert "1-2" not in cells


def _outline_segments(doc, layout):
    """The part outlines of a layout as segments: in model space the OUTLINE and DETAIL
    entities (polylines, lines, circles as 96-gons); in paper space those of model space
    seen through each viewport (mapped and kept where both ends lie inside it)."""
    def model_segments():
        segs = []
        for e in doc.modelspace():
            if e.dxf.layer not in ("OUTLINE", "DETAIL"):
                continue
            if e.dxftype() == "LWPOLYLINE":
                pts = [(x, y) for x, y, *_ in e.get_points("xy")]
                segs += list(zip(pts, pts[1:] + pts[:1] if e.closed else pts[1:]))
            elif e.dxftype() == "LINE":
                segs.append(((e.dxf.start.x, e.dxf.start.y), (e.dxf.end.x, e.dxf.end.y)))
            elif e.dxftype() == "CIRCLE":
                c, r = e.dxf.center, e.dxf.radius
                t = np.linspace(0, 2 * np.pi, 97)
                pts = list(zip(c.x + r * np.cos(t), c.y + r * np.sin(t)))
                segs += list(zip(pts[:-1], pts[1:]))
        return np.array(segs, dtype=float).reshape(-1, 2, 2)

    segs = model_segments()
    if layout.name == "Model":
        return segs
    out = []
    for vp in layout.query("VIEWPORT"):
        if vp.dxf.status <= 1:
            continue
        s = vp.dxf.height / vp.dxf.view_height
        vc = np.array([vp.dxf.view_center_point.x, vp.dxf.view_center_point.y])
        pc = np.array([vp.dxf.center.x, vp.dxf.center.y])
        mapped = (segs - vc) * s + pc
        half = np.array([vp.dxf.width, vp.dxf.height]) / 2
        inside = np.all(np.abs(mapped - pc) <= half, axis=(1, 2))
        out.append(mapped[inside])
    return np.concatenate(out) if out else np.zeros((0, 2, 2))


def test_no_text_crosses_a_part_outline(sheet_set):
    """Issue 33: no text box (TEXT, MTEXT and the dimensions' measurement texts, sized by
    ezdxf on the pinned font) comes closer to a part outline (layers OUTLINE and DETAIL; in
    paper space as the viewports show them) than a tenth of its height: 0.35 mm on paper for
    3.5 mm text (each grown by 5 % of its height, the segment too). Leaders, dimension and
    extension lines are not outlines."""
    from readers import boxes_overlap, dxf_text_boxes

    _, _, docs = sheet_set
    hits = []
    for name, doc in docs.items():
        for lay in doc.layouts:
            segs = _outline_segments(doc, lay)
            for label, quad, h in dxf_text_boxes(doc, lay):
                lo, hi = quad.min(axis=0) - h, quad.max(axis=0) + h
                near = segs[np.all((segs.max(axis=1) >= lo) & (segs.min(axis=1) <= hi), axis=1)]
                hits += [(name, lay.name, label, tuple(np.round(seg.ravel(), 3))) for seg in near
                         if boxes_overlap(quad, seg, 0.05 * h)]
    assert not hits, hits[:8]


def test_every_model_space_text_is_seen_through_a_viewport(sheet_set):
    """A model-space text outside every viewport's window would not be on the sheet (nor in
    the PDF): each text box of model space lies inside the window of a viewport of the
    sheet."""
    from readers import dxf_text_boxes

    _, _, docs = sheet_set
    unseen = []
    for name, doc in docs.items():
        psp = [lay for lay in doc.layouts if lay.name != "Model"][0]
        windows = []
        for vp in psp.query("VIEWPORT"):
            if vp.dxf.status > 1:
                half = 0.5 * vp.dxf.view_height * np.array([vp.dxf.width / vp.dxf.height, 1.0])
                c = np.array([vp.dxf.view_center_point.x, vp.dxf.view_center_point.y])
                windows.append((c - half, c + half))
        for label, quad, _ in dxf_text_boxes(doc, doc.modelspace()):
            if not any(np.all(quad >= lo) and np.all(quad <= hi) for lo, hi in windows):
                unseen.append((name, label))
    assert not unseen, unseen


def test_assembly_sheet_hatches_parts_shows_stroke_ends_and_uncrossed_leaders(sheet_set):
    """Issue 33: the assembly's sectioned parts hatched per part at different angles or
    spacings (ISO 128-50; the screw, rollers, bolts and key not sectioned, ISO 128-44), the nut
    dash-dot-dot at both stroke ends with the stroke dimensioned between them, and no two
    balloon leaders crossing."""
    from prs_geom.exports.mechanism_drawing import _crosses
    from prs_geom.geometry.actuator import actuator_layout

    d, _, docs = sheet_set
    doc = docs["assembly"]
    msp = doc.modelspace()
    styles = {(round(h.dxf.pattern_angle, 6), round(h.dxf.pattern_scale, 9)) for h in msp.query("HATCH")}
    assert len(styles) >= 5
    phantom = [e for e in msp if e.dxf.layer == "PHANTOM"]
    assert len(phantom) == 2 and doc.layers.get("PHANTOM").dxf.linetype == "PHANTOM"
    act = actuator_layout(d)
    xs = sorted(min(x for x, *_ in e.get_points("xy")) for e in phantom)
    assert xs[1] - xs[0] == pytest.approx(act.stroke_mm, abs=1e-9)
    stroke = _dims(doc)["<> stroke"]
    assert stroke.get_measurement() == pytest.approx(act.stroke_mm, abs=1e-9)
    leaders = [((e.dxf.start.x, e.dxf.start.y), (e.dxf.end.x, e.dxf.end.y)) for e in msp.query("LINE[layer=='BALLOONS']")]
    assert len(leaders) == len({e.dxf.text for e in msp.query("TEXT[layer=='BALLOONS']")}) == 11
    crossing = [(a, b) for i, a in enumerate(leaders) for b in leaders[i + 1:] if _crosses(*a, *b)]
    assert not crossing
