"""Stepless harmonic friction drive (issue 7)."""
import json
import math
from pathlib import Path

import ezdxf
import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from cli_helpers import run
from prs_geom.model.io import dumps_toml, loads_toml, toml_string
from prs_geom.model.errors import DesignError
from prs_geom.harmonic.model import (CircularSpline, Flexspline, HarmonicDesign, Positions, contact_point,
                               contact_state, infinite_ratio_position, it_tolerance_um, ratio,
                               tilt_angle, tolerance_for_ratio)
from prs_geom.harmonic.exports import circular_spline_mesh, flexspline_mesh, flexspline_profile
from prs_geom.pipeline import build
from prs_geom.pipeline import DESIGN_KINDS, load_any_design as load_design

EXAMPLES = Path(__file__).parent.parent / "examples"




def test_worked_example_reproduces_published_values():
    d = HarmonicDesign()
    assert math.degrees(d.alpha) == pytest.approx(4.5739, abs=5e-5)
    assert d.a0 == pytest.approx(37.5, abs=1e-12)
    st = contact_state(d, [73.0, 73.5, 74.0])
    assert round(float(st["ratio"][0]), 1) == 545.0
    assert round(float(st["ratio"][1]), 1) == 963.6
    assert round(float(st["ratio"][2]), 1) == 4155.1
    assert round(float(st["contact_radius_mm"][1]), 3) == 53.773
    assert round(float(st["contact_radius_mm"][2]), 3) == 53.772
    assert round(float(st["radius_difference_mm"][1]), 4) == 0.0519
    assert round(float(st["radius_difference_mm"][2]), 4) == 0.0120
    assert float(ratio(d, 42.0)) == pytest.approx(19.4, rel=0.01)


def test_contact_is_tangent_to_the_cone_wall():
    """Independent geometry: the arc centre is r_s from the cone line, and the contact point
    lies on the line at the cone radius R_c."""
    d = HarmonicDesign()
    f, c = d.flexspline, d.circular_spline
    for a in (42.0, 55.0, 73.5):
        beta = float(tilt_angle(d, a))
        C = np.array([d.x_s * math.cos(beta) + f.arc_centre_offset_mm * math.sin(beta),
                      f.neutral_radius_mm + d.x_s * math.sin(beta) - f.arc_centre_offset_mm * math.cos(beta)])
        P0 = np.array([a, c.bore_small_radius_mm])
        u = np.array([c.bore_length_mm, c.bore_large_radius_mm - c.bore_small_radius_mm])
        u /= np.linalg.norm(u)
        w = C - P0
        dist = abs(u[0] * w[1] - u[1] * w[0])
        assert dist == pytest.approx(f.arc_radius_mm, abs=1e-10)
        x, r = contact_point(d, a)
        assert r == pytest.approx(c.bore_small_radius_mm + (x - a) * math.tan(d.alpha), abs=1e-10)
        assert r == pytest.approx(float(contact_state(d, a)["cone_radius_mm"]), abs=1e-10)


def test_ratio_is_monotone_and_infinite_at_delta_zero():
    d = HarmonicDesign()
    a = np.linspace(d.positions.min_mm, d.positions.max_mm, 5001)
    i = ratio(d, a)
    assert np.all(np.diff(i) > 0)
    a_inf = infinite_ratio_position(d)
    assert d.positions.max_mm < a_inf < 74.2
    assert abs(float(contact_state(d, a_inf)["radius_difference_mm"])) < 1e-10


def test_meshes_are_watertight_with_the_right_volume():
    d = HarmonicDesign()
    cs = circular_spline_mesh(d)
    fs = flexspline_mesh(d)
    for m in (cs, fs):
        assert m.is_watertight and m.is_winding_consistent and m.volume > 0
    c = d.circular_spline
    frustum = math.pi * c.bore_length_mm / 3 * (c.bore_small_radius_mm ** 2 + c.bore_small_radius_mm *
                                                 c.bore_large_radius_mm + c.bore_large_radius_mm ** 2)
    exact = math.pi * c.outer_radius_mm ** 2 * c.bore_length_mm - frustum
    # inscribed polygon of the revolution: relative error ~ (pi / sections)^2 / 6 ... within tolerance budget
    assert abs(cs.volume - exact) <= cs.area * d.mesh.chord_tolerance_mm
    # flexspline: Pappus on the profile polygon (exact solid of the polygon)
    P = flexspline_profile(d)
    x, y = P[:, 0], P[:, 1]
    cross = x * np.roll(y, -1) - np.roll(x, -1) * y
    area = 0.5 * cross.sum()
    cx = ((x + np.roll(x, -1)) * cross).sum() / (6 * area)
    pappus = abs(2 * math.pi * cx * area)
    assert abs(fs.volume - pappus) <= fs.area * d.mesh.chord_tolerance_mm


def test_tolerance_for_ratio_and_iso_grades():
    # ISO 286-1 table values for 80-120 mm: IT6 = 22 um, IT7 = 35 um (formula within rounding)
    assert it_tolerance_um(100.0, 6) == pytest.approx(22.0, rel=0.03)
    assert it_tolerance_um(100.0, 7) == pytest.approx(35.0, rel=0.03)
    assert it_tolerance_um(60.0, 8) == pytest.approx(46.0, rel=0.03)
    d = HarmonicDesign()
    t = tolerance_for_ratio(d, 545.0, 0.1)
    assert t["radius_difference_mm"] == pytest.approx(50.0 / 545.0)
    assert t["radius_tolerance_um"] == pytest.approx(0.1 * 50.0 / 545.0 / 2 * 1e3)
    assert it_tolerance_um(t["bore_diameter_mm"], t["it_grade"]) <= t["diameter_band_um"]
    assert it_tolerance_um(t["bore_diameter_mm"], t["it_grade"] + 1) > t["diameter_band_um"]
    # a higher maximum ratio needs a finer grade
    assert tolerance_for_ratio(d, 100.0)["it_grade"] > t["it_grade"]


@pytest.mark.parametrize("make, field", [
    (lambda: HarmonicDesign(positions=Positions(max_mm=74.5, drawing_mm=(50.0,))), "positions.max_mm"),
    (lambda: CircularSpline(bore_large_radius_mm=52.0), "bore_large_radius_mm"),
    (lambda: Flexspline(arc_radius_mm=120.0), "arc_radius_mm"),
    (lambda: Positions(drawing_mm=(80.0,)), "drawing_mm[0]"),
])
def test_invalid_harmonic_designs(make, field):
    with pytest.raises(DesignError) as exc:
        make()
    assert exc.value.field == field


def test_harmonic_design_file_round_trips_and_example_equals_default():
    d = load_design(EXAMPLES / "harmonic.toml")
    assert d == HarmonicDesign()
    assert loads_toml(dumps_toml(d), kinds=DESIGN_KINDS) == d


def test_harmonic_cli(tmp_path):
    code, out, _ = run(["harmonic", "--a", "73", "73.5", "74"])
    assert code == 0 and "545.0" in out and "963.6" in out and "4155.1" in out
    code, out, _ = run(["harmonic", str(EXAMPLES / "harmonic.toml"), "--json"])
    rep = json.loads(out)
    assert rep["alpha_deg"] == pytest.approx(4.5739, abs=1e-4) and len(rep["table"]) == 65
    code, _, err = run(["harmonic", "--a", "90"])
    assert code == 2 and err.startswith("error: --a (value 1) = 90.0: must lie in positions.min_mm")
    # repeated flags add up (they used to keep only the last)
    code, out, _ = run(["harmonic", "--a", "42", "--a", "73"])
    assert code == 0 and "19.5" in out and "545.0" in out
    bad = tmp_path / "bad.toml"
    bad.write_text('kind = "harmonic"\n[circular_spline]\nbore_length_mm = -1\n')
    code, _, err = run(["harmonic", str(bad)])
    assert code == 2 and "circular_spline.bore_length_mm" in err
    code, _, err = run(["loads", str(EXAMPLES / "harmonic.toml")])
    assert code == 2 and err.startswith("error: kind")


def test_build_harmonic_writes_exports(tmp_path):
    out = tmp_path / "h"
    report = build(load_design(EXAMPLES / "harmonic.toml"), out)
    for f in ("ratio.png", "ratio.svg", "ratio_table.csv", "axial_sections.dxf", "circular_spline.stl",
              "flexspline.stl", "report.json", "design.toml"):
        assert (out / f).is_file(), f
    rows = (out / "ratio_table.csv").read_text().splitlines()
    assert rows[0].startswith("a_mm,beta_deg")
    assert len(rows) == 66
    assert float(rows[1].split(",")[-1]) == report["harmonic"]["table"][0]["ratio"]
    for name in ("circular_spline", "flexspline"):
        m = trimesh.load(out / f"{name}.stl")
        assert m.is_watertight
    for row in report["checks"]["meshes"]:
        assert 0 < row["revolution_deviation_mm"] and row["max_deviation_mm"] <= row["chord_tolerance_mm"]
    doc = ezdxf.readfile(out / "axial_sections.dxf")
    assert doc.header["$INSUNITS"] == 4
    blocks = [b for b in doc.blocks if b.name.startswith("POSITION_")]
    assert len(blocks) == 3
    arcs = [e for e in blocks[2] if e.dxftype() == "ARC"]
    assert len(arcs) == 1 and arcs[0].dxf.radius == pytest.approx(15.0)


HARMONIC_FIELDS = [
    "flexspline.neutral_radius_mm", "flexspline.length_mm", "flexspline.arc_radius_mm",
    "flexspline.arc_centre_offset_mm", "flexspline.wall_thickness_mm",
    "circular_spline.bore_small_radius_mm", "circular_spline.bore_large_radius_mm",
    "circular_spline.bore_length_mm", "circular_spline.outer_radius_mm", "mesh.chord_tolerance_mm",
]


@pytest.mark.parametrize("field", HARMONIC_FIELDS)
@settings(max_examples=6)
@given(value=st.one_of(st.floats(max_value=0.0, allow_nan=False), st.just(math.nan), st.just(math.inf),
                       st.text(max_size=3), st.booleans()))
def test_invalid_harmonic_field_gives_exit_2_and_no_output(field, value):
    import tempfile
    section, key = field.split(".")
    lit = ("nan" if math.isnan(value) else "inf") if isinstance(value, float) and not math.isfinite(value) \
        else toml_string(value) if isinstance(value, str) else str(value).lower() if isinstance(value, bool) else repr(value)
    with tempfile.TemporaryDirectory() as tmp:
        f = Path(tmp) / "bad.toml"
        f.write_text(f'kind = "harmonic"\n[{section}]\n{key} = {lit}\n')
        out = Path(tmp) / "out"
        code, _, err = run(["build", str(f), "--out", str(out), "--quiet"])
        assert code == 2 and err.startswith(f"error: {field}"), err
        assert not out.exists()
