"""DXF profile drawing read back with ezdxf (issue 6)."""
import math
from collections import Counter

import ezdxf
import numpy as np
import pytest

from prs_geom.model.design import Nut, PRSDesign, Roller
from prs_geom.exports.dxf import write_dxf
from prs_geom.geometry.profiles import ThreadProfiles

PL_R = tuple(2.0 + 4e-4 * (19 - j) / 19 + 1e-4 * math.sin(j) for j in range(19))
PL_N = tuple(2.0 + 6e-4 * (19 - j) / 19 + 2e-4 * math.cos(j) for j in range(19))


@pytest.fixture(scope="module")
def drawing(tmp_path_factory):
    d = PRSDesign(name="dxf", roller=Roller(pitch_list_mm=PL_R), nut=Nut(pitch_list_mm=PL_N))
    path = tmp_path_factory.mktemp("dxf") / "p.dxf"
    write_dxf(d, path, {"theoretical screw pitch dia.": "23.8 mm"})
    return d, ezdxf.readfile(path)


def test_header_layers_and_entity_types(drawing):
    d, doc = drawing
    assert doc.dxfversion >= "AC1024"      # R2010 or newer
    assert doc.header["$INSUNITS"] == 4    # millimetres
    assert doc.header["$MEASUREMENT"] == 1
    for layer in ("PROFILE", "CENTRE", "PITCH", "ANNOTATION"):
        assert layer in doc.layers
    assert doc.layers.get("CENTRE").dxf.linetype.upper() == "CENTER"
    blocks = {b.name: Counter(e.dxftype() for e in b) for b in doc.blocks if b.name.endswith(("AXIAL", "NORMAL"))}
    assert set(blocks) == {f"{p}_{v}" for p in ("SCREW", "ROLLER", "NUT") for v in ("AXIAL", "NORMAL")}
    assert blocks["ROLLER_NORMAL"]["ARC"] == 2 and "LWPOLYLINE" not in blocks["ROLLER_NORMAL"]
    assert blocks["ROLLER_AXIAL"]["ELLIPSE"] >= 2 * 19
    assert blocks["SCREW_AXIAL"]["LINE"] > 50 and "ELLIPSE" not in blocks["SCREW_AXIAL"]
    texts = " ".join(e.dxf.text for e in doc.modelspace() if e.dxftype() == "TEXT")
    assert "design: dxf" in texts and "theoretical screw pitch dia." in texts
    refs = [e.dxf.name for e in doc.modelspace() if e.dxftype() == "INSERT"]
    assert len(refs) == 6


def test_roller_normal_section_arc_is_the_design_arc(drawing):
    d, doc = drawing
    arcs = [e for e in doc.blocks.get("ROLLER_NORMAL") if e.dxftype() == "ARC"]
    for a in arcs:
        assert a.dxf.radius == pytest.approx(d.roller.arc_radius_mm, abs=1e-12)
        assert a.dxf.center.y == pytest.approx(0.0, abs=1e-12)   # centred on the roller axis


def test_roller_flank_positions_match_pitch_list(drawing):
    """Flank X at the pitch radius, read from the ELLIPSE entities, tooth to tooth."""
    d, doc = drawing
    r = ThreadProfiles.from_design(d).roller.pitch_radius
    up, low = [], []
    for e in doc.blocks.get("ROLLER_AXIAL"):
        if e.dxftype() != "ELLIPSE":
            continue
        cx, a = e.dxf.center.x, e.dxf.major_axis.x
        b = a * e.dxf.ratio
        t0, t1 = e.dxf.start_param, e.dxf.end_param
        t = math.asin(r / b)
        if t0 - 1e-12 <= t <= t1 + 1e-12:          # upper flank (0 < t < pi/2)
            up.append(cx + a * math.cos(t))
        elif t0 - 1e-12 <= math.pi - t <= t1 + 1e-12:
            low.append(cx + a * math.cos(math.pi - t))
    up, low = np.sort(up), np.sort(low)
    assert len(up) == len(low) == 20
    np.testing.assert_allclose(np.diff(up), PL_R, atol=1e-5, rtol=0)    # 0.01 um
    np.testing.assert_allclose(np.diff(low), PL_R, atol=1e-5, rtol=0)
    # tooth thickness at the pitch radius is p/2 (axial section)
    np.testing.assert_allclose(up - low, 1.0, atol=1e-9)


def test_nut_flank_positions_match_pitch_list(drawing):
    d, doc = drawing
    r = ThreadProfiles.from_design(d).nut.pitch_radius
    flanks = {"lower": [], "upper": []}
    for e in doc.blocks.get("NUT_AXIAL"):
        if e.dxftype() != "LINE" or e.dxf.layer != "PROFILE":
            continue
        (x0, y0), (x1, y1) = (e.dxf.start.x, e.dxf.start.y), (e.dxf.end.x, e.dxf.end.y)
        if abs(x1 - x0) < 1e-9 or abs(y1 - y0) < 1e-9 or not (min(y0, y1) <= r <= max(y0, y1)):
            continue
        x = x0 + (x1 - x0) * (r - y0) / (y1 - y0)
        # nut (internal) tooth: lower flank rises toward the bore going +X
        flanks["lower" if y1 < y0 else "upper"].append(x)
    low, up = np.sort(flanks["lower"]), np.sort(flanks["upper"])
    # nut tooth j has its mid-plane at (j - 1) p: tooth 1 at X = 0 is cut by the end face,
    # so its lower flank is missing; the pitch list starts at tooth 1 -> 2 for the upper flanks
    np.testing.assert_allclose(np.diff(up[:20]), PL_N, atol=1e-5, rtol=0)
    np.testing.assert_allclose(np.diff(low[:19]), PL_N[1:], atol=1e-5, rtol=0)


def test_profiles_dxf_extents_are_set(tmp_path):
    """Read back with ezdxf: $EXTMIN/$EXTMAX equal the bounding box of the model-space entities."""
    import ezdxf
    from ezdxf import bbox

    from prs_geom.exports.dxf import write_dxf
    from prs_geom.model.design import default_design
    path = tmp_path / "p.dxf"
    write_dxf(default_design(), path)
    doc = ezdxf.readfile(path)
    ext = bbox.extents(doc.modelspace())
    assert tuple(doc.header["$EXTMIN"])[:2] == pytest.approx(tuple(ext.extmin)[:2], abs=1e-9)
    assert tuple(doc.header["$EXTMAX"])[:2] == pytest.approx(tuple(ext.extmax)[:2], abs=1e-9)
    assert ext.extmax[0] - ext.extmin[0] > 50.0


def test_profiles_dxf_is_a_sheet_with_the_theoretical_screw(tmp_path):
    """Issue 33: profiles.dxf draws the screw at the theoretical pitch diameter the contact
    analysis solves (its half-section dimension reads it to 1e-6 mm, as the title text does),
    dimensions every view (pitch diameter, thread length = the part's), and has an A3 paper
    space with a viewport at a standard scale and a title block (design, scale, date)."""
    import ezdxf

    from prs_geom.analysis.contact import analyse_contact
    from prs_geom.exports.drawing import part_profiles
    from prs_geom.geometry.frames import screw_z_range, thread_length
    from prs_geom.model.design import default_design

    d = default_design()
    contact = analyse_contact(d)
    path = tmp_path / "profiles.dxf"
    write_dxf(d, path, None, part_profiles(d, contact), "2026-11-28")
    doc = ezdxf.readfile(path)
    assert not doc.audit().errors
    dims = [e for e in doc.modelspace() if e.dxftype() == "DIMENSION"]
    pitch = sorted(e.dxf.text for e in dims if "pitch" in e.dxf.text)
    theoretical = contact.theoretical_screw_pitch_diameter_mm
    assert abs(theoretical - d.screw.pitch_diameter_mm) > 0.1          # the two differ visibly
    assert pitch == sorted([f"%%c{theoretical:.6f} pitch", f"%%c{d.roller.pitch_diameter_mm:.6f} pitch",
                            f"%%c{d.nut.pitch_diameter_mm:.6f} pitch"])
    for e in dims:                                 # each half-section dimension measures the radius
        if "pitch" in e.dxf.text:
            assert 2.0 * e.get_measurement() == pytest.approx(float(e.dxf.text[3:].split()[0]), abs=1e-6)
    lengths = sorted(round(e.get_measurement(), 9) for e in dims if "thread length" in e.dxf.text)
    lo, hi = screw_z_range(d)
    assert lengths == sorted([round(hi - lo, 9), round(thread_length(d), 9), round(thread_length(d), 9)])
    psp = doc.paperspace("A3_PROFILES")
    texts = " | ".join(e.dxf.text for e in psp if e.dxftype() == "TEXT")
    for needle in (f"Design: {d.name}", "Scale: 1:1", "Date: 2026-11-28"):
        assert needle in texts
    views = [e for e in psp if e.dxftype() == "VIEWPORT" and e.dxf.status != 1]
    assert len(views) == 1 and views[0].dxf.height / views[0].dxf.view_height == pytest.approx(1.0)
