"""Stepless harmonic friction drive (issue 7)."""
import html
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
from readers import khronos_issues, read_3mf, solid, stl_merged
from prs_geom.model.io import dumps_toml, loads_toml, toml_string
from prs_geom.model.errors import DesignError
from prs_geom.harmonic.model import (CircularSpline, Flexspline, HarmonicDesign, Positions, contact_point,
                               contact_state, infinite_ratio_position, ratio,
                               tilt_angle, tolerance_for_ratio)
from prs_geom.model.standards import GRADE_NAMES, it_tolerance_by_name_um
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
    """The band's grade comes from the project's ISO 286 table (80-120 mm: IT6 22 um,
    IT7 35 um; 114 mm bore), the coarsest that fits in the band."""
    d = HarmonicDesign()
    t = tolerance_for_ratio(d, 545.0, 0.1)
    assert t["radius_difference_mm"] == pytest.approx(50.0 / 545.0)
    assert t["radius_tolerance_um"] == pytest.approx(0.1 * 50.0 / 545.0 / 2 * 1e3)
    k = GRADE_NAMES.index(t["it_grade"])
    assert it_tolerance_by_name_um(t["it_grade"], t["bore_diameter_mm"]) <= t["diameter_band_um"]
    assert it_tolerance_by_name_um(GRADE_NAMES[k + 1], t["bore_diameter_mm"]) > t["diameter_band_um"]
    assert t["it_grade"] == "IT5"          # band 18.3 um at 114 mm: IT5 = 15 um fits, IT6 = 22 um does not
    # a higher maximum ratio needs a finer grade
    assert GRADE_NAMES.index(tolerance_for_ratio(d, 100.0)["it_grade"]) > k


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
    for f in ("ratio.png", "ratio.svg", "drive.png", "drive.svg", "ratio_table.csv", "axial_sections.dxf",
              "circular_spline.stl", "flexspline.stl", "report.json", "design.toml"):
        assert (out / f).is_file(), f
    rows = (out / "ratio_table.csv").read_text().splitlines()
    assert rows[0].startswith("a_mm,beta_deg")
    assert len(rows) == 66
    head = rows[0].split(",")
    assert float(rows[1].split(",")[head.index("ratio")]) == report["harmonic"]["table"][0]["ratio"]
    assert rows[-1].split(",")[head.index("it_grade")] == "IT5"          # a = 74: 0.0120 mm, about IT5
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
    # the header holds the drawing's real extents (the three positions stacked up the sheet)
    from ezdxf import bbox

    ext = bbox.extents(doc.modelspace())
    np.testing.assert_allclose(doc.header["$EXTMIN"][:2], tuple(ext.extmin)[:2], atol=1e-9)
    np.testing.assert_allclose(doc.header["$EXTMAX"][:2], tuple(ext.extmax)[:2], atol=1e-9)
    assert doc.header["$EXTMAX"][1] > 2 * 65.0          # above the second position's ring (outer radius 65)


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


@pytest.mark.parametrize("field", [f for f in HARMONIC_FIELDS if not f.startswith("mesh.")])
def test_a_harmonic_dimension_past_10_m_is_exit_2_naming_it(field, tmp_path):
    """Every dimension of the drive is a size of at most 10 m (as the roller screw's): a
    flexspline 7e16 mm long once reached the tangency solver and failed as an internal
    error (exit 70) instead of a design error."""
    section, key = field.split(".")
    f = tmp_path / "huge.toml"
    f.write_text(f'kind = "harmonic"\n[{section}]\n{key} = 6.9e16\n')
    code, _, err = run(["validate", str(f)])
    assert code == 2, err
    assert err.startswith(f"error: {field} = 6.9e+16: must be at most 10000 mm"), err


# --------------------------------------------------------------------------- placed assembly
# The drive placed at one input position a (prs_geom/harmonic/assembly.py): the flexspline
# deformed by the wave generator, its files (STL, GLB, 3MF) read back by independent readers
# and report.html parsed back and opened in a browser.
import re
import shutil
import subprocess


from prs_geom._version import __version__
from prs_geom.harmonic.assembly import (assembly_checks, build_assembly, default_position, deform,
                                        inner_wall_radius, meridian_tilt, wave_generator)
from prs_geom.harmonic.model import harmonic_report
from prs_geom.model.io import design_hash

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
ASSEMBLY_FILES = ("flexspline_placed.stl", "wave_generator.stl", "assembly.glb", "assembly.3mf", "report.html")


@pytest.fixture(scope="module")
def placed(tmp_path_factory):
    """A default harmonic build: the build writes the placed-assembly outputs."""
    d = HarmonicDesign()
    out = tmp_path_factory.mktemp("placed") / "out"
    return d, out, build(d, out)


def test_deformation_reproduces_the_model_section_on_the_major_axis():
    """Independent formula: the tilted arc centre of the ratio model (docs/theory/harmonic.md)
    is where the deformation takes the undeformed arc centre, on both lobes; on the minor
    axis the tilt is reversed; the mean radial displacement of the open end is zero to first
    order (an inextensible end)."""
    d = HarmonicDesign()
    f = d.flexspline
    a = default_position(d)
    assert a == 0.5 * (d.positions.min_mm + d.positions.max_mm) == 58.0
    beta = float(tilt_angle(d, a))
    xc = d.x_s * math.cos(beta) + f.arc_centre_offset_mm * math.sin(beta)
    rc = f.neutral_radius_mm + d.x_s * math.sin(beta) - f.arc_centre_offset_mm * math.cos(beta)
    r_u = f.neutral_radius_mm - f.arc_centre_offset_mm
    p = deform(d, r_u, d.x_s, np.array([0.0, math.pi]), beta)
    np.testing.assert_allclose(p, [[rc, 0.0, xc], [-rc, 0.0, xc]], atol=1e-12)
    assert float(meridian_tilt(beta, math.pi / 2)) == pytest.approx(-beta, abs=1e-15)
    th = np.linspace(0, 2 * math.pi, 4096, endpoint=False)
    end = deform(d, f.neutral_radius_mm, f.length_mm, th, beta)
    w = np.hypot(end[:, 0], end[:, 1]) - f.neutral_radius_mm
    assert abs(w.mean()) < 0.5 * f.length_mm * beta ** 2 and w.max() == pytest.approx(f.length_mm * math.sin(beta))


def test_wave_generator_touches_on_four_lines_and_clears_elsewhere():
    d = HarmonicDesign()
    a = default_position(d)
    beta = float(tilt_angle(d, a))
    wg = wave_generator(d, a)
    f = d.flexspline
    # the band sits under the contact, on the inner wall (arc centre station +- r_s / 2)
    assert (wg.z_min_mm, wg.z_max_mm) == pytest.approx((d.x_s - 7.5, d.x_s + 7.5))
    # inner wall line in the tilted meridian, written out: foot (r0 - t/2) turned about A
    h = f.wall_thickness_mm / 2

    def wall(b, z):
        foot = np.array([f.neutral_radius_mm - h * math.cos(b), h * math.sin(b)])
        return foot[0] + (z - foot[1]) * math.tan(b)
    assert wg.semi_axis_x_mm == pytest.approx(wall(beta, wg.z_min_mm), abs=1e-12)     # outward wall: lower edge
    assert wg.semi_axis_y_mm == pytest.approx(wall(-beta, wg.z_max_mm), abs=1e-12)    # inward wall: upper edge
    assert wg.semi_axis_x_mm > f.neutral_radius_mm - h > wg.semi_axis_y_mm
    th = np.linspace(0, 2 * math.pi, 3601)
    b = meridian_tilt(beta, th)
    clear = np.minimum(inner_wall_radius(d, b, wg.z_min_mm), inner_wall_radius(d, b, wg.z_max_mm)) - wg.radius(th)
    assert clear.min() > -1e-9
    assert clear[[0, 900, 1800, 2700]] == pytest.approx(0.0, abs=1e-9)
    assert 0.05 < clear.max() < 0.5


@pytest.mark.parametrize("a", [42.0, 73.5])
def test_placed_assembly_at_other_positions_touches_without_interference(a):
    d = HarmonicDesign()
    asm = build_assembly(d, a, tol=0.02)
    c = assembly_checks(asm)
    assert asm.position_mm == a and asm.beta_rad == pytest.approx(float(tilt_angle(d, a)))
    assert 0.0 <= c["contact_gap_mm"] <= 0.5 * 0.02
    assert c["contact_offset_mm"] <= 0.02
    assert not c["interference"]["found"] and c["warnings"] == []
    assert c["arc_cone_clearance_min_mm"] == pytest.approx(0.0, abs=1e-9)
    with pytest.raises(DesignError):
        build_assembly(d, 80.0)


def test_harmonic_outputs_files_and_report_keys(placed):
    d, out, report = placed
    for f in ASSEMBLY_FILES:
        assert (out / f).is_file() and f in report["files"], f
    asm = report["assembly"]
    assert asm["position_mm"] == 58.0 and asm["parts"] == ["circular_spline", "flexspline", "wave_generator"]
    assert asm["beta_deg"] == pytest.approx(math.degrees(float(tilt_angle(d, 58.0))), rel=1e-12)
    assert asm["wave_amplitude_mm"] == pytest.approx(d.flexspline.length_mm * math.sin(math.radians(asm["beta_deg"])))
    assert asm["placement_z_mm"] == {"circular_spline": 58.0, "flexspline": 0.0,
                                     "wave_generator": asm["wave_generator"]["z_min_mm"]}
    for row in asm["meshes"]:
        assert row["watertight"] and row["max_deviation_mm"] <= row["chord_tolerance_mm"], row
    assert report["checks"]["assembly"]["warnings"] == []
    # the one warning: the example's smallest ratio bends a steel flexspline past its allowed stress
    assert [w.split(":")[0] for w in report["warnings"]] == ["flexspline strength (steel)"]
    head = (out / "flexspline_placed.stl").read_bytes()[:80].decode("ascii")
    assert head.startswith("prs_geom flexspline placed; units mm; assembly frame; design sha256 " + design_hash(d))


def test_placed_flexspline_touches_the_cone_at_the_model_contact_point(placed):
    """From flexspline_placed.stl alone: its mesh edges in the major-axis half plane
    (theta = 0, and theta = pi mirrored) pass within the chord tolerance of the model's
    contact point, and their vertices stay inside the cone of the circular spline placed at a,
    the nearest within the tolerance."""
    d, out, report = placed
    tol = d.mesh.chord_tolerance_mm
    a = report["assembly"]["position_mm"]
    x_c, r_c = contact_point(d, a)
    m = stl_merged(out / "flexspline_placed.stl")
    V = np.asarray(m.vertices, dtype=np.float64)
    c = d.circular_spline
    for sign in (1.0, -1.0):
        on = (np.abs(V[:, 1]) < 1e-9) & (sign * V[:, 0] > 0)      # sin(pi) r is not 0 exactly
        E = m.edges_unique
        E = E[on[E[:, 0]] & on[E[:, 1]]]
        P, Q = V[E[:, 0]][:, [0, 2]] * [sign, 1], V[E[:, 1]][:, [0, 2]] * [sign, 1]     # (r, z)
        p = np.array([r_c, x_c])
        t = np.clip(np.einsum("ij,ij->i", p - P, Q - P) / np.einsum("ij,ij->i", Q - P, Q - P), 0, 1)
        dist = np.linalg.norm(P + t[:, None] * (Q - P) - p, axis=1).min()
        assert dist <= tol, dist
        rz = V[on][:, [0, 2]] * [sign, 1]
        rz = rz[(rz[:, 1] >= a) & (rz[:, 1] <= a + c.bore_length_mm)]
        cone = c.bore_small_radius_mm + (rz[:, 1] - a) * math.tan(d.alpha)
        gap = (cone - rz[:, 0]) * math.cos(d.alpha)          # normal distance to the cone line
        assert -1e-5 <= gap.min() <= 0.5 * tol, gap.min()    # float32 STL coordinates
    assert report["checks"]["assembly"]["contact_gap_mm"] == pytest.approx(gap.min(), abs=1e-5)


def test_assembly_read_back_from_3mf_has_no_interference_and_matches_the_stls(placed):
    d, out, report = placed
    tol = d.mesh.chord_tolerance_mm
    m = read_3mf(out / "assembly.3mf")
    assert m["unit"] == m["mm"]
    assert set(m["objects"]) == set(m["items"]) == {"circular_spline", "flexspline", "wave_generator"}
    assert m["item_object"] == {k: k for k in m["items"]}
    a = report["assembly"]["position_mm"]
    np.testing.assert_allclose(m["items"]["circular_spline"][:3, 3], [0, 0, a], atol=1e-9)
    np.testing.assert_allclose(m["items"]["flexspline"], np.eye(4), atol=0)
    for name, stl in (("circular_spline", "circular_spline.stl"), ("flexspline", "flexspline_placed.stl"),
                      ("wave_generator", "wave_generator.stl")):
        V, F = m["objects"][name]
        ref = stl_merged(out / stl)
        # both hold float32-sized coordinates, but lib3mf's decimal text does not round-trip
        # float32 exactly (53.0 is written 52.999999488): one float32 step at 32..64 mm
        # (3.8e-6 mm) over the surface bounds the volume difference
        assert len(F) == len(ref.faces)
        assert abs(trimesh.Trimesh(V, F, process=False).volume - ref.volume) <= ref.area * 3.9e-6
    solids = {}
    for name, (V, F) in m["objects"].items():
        T = m["items"][name]
        solids[name] = solid(V @ T[:3, :3].T + T[:3, 3], F)
    for p, q in (("circular_spline", "flexspline"), ("flexspline", "wave_generator"),
                 ("circular_spline", "wave_generator")):
        inter = solids[p] ^ solids[q]
        vol = inter.volume()
        thick = 2 * vol / inter.surface_area() if vol > 0 else 0.0
        assert thick <= 2 * tol, (p, q, vol, thick)
    # the check sees interference: the ring moved 2 mm further (narrower bore at the contact)
    V, F = m["objects"]["circular_spline"]
    moved = solid(V + [0, 0, a + 2.0], F) ^ solids["flexspline"]
    assert 2 * moved.volume() / moved.surface_area() > 2 * tol
    # the deformed flexspline keeps the undeformed volume to second order in the tilt
    beta = math.radians(report["assembly"]["beta_deg"])
    undeformed = next(r for r in report["checks"]["meshes"] if r["part"] == "flexspline")["volume_mm3"]
    assert abs(stl_merged(out / "flexspline_placed.stl").volume / undeformed - 1) < beta ** 2


def test_glb_has_three_named_parts_in_metres_y_up(placed):
    import struct
    d, out, report = placed
    data = (out / "assembly.glb").read_bytes()
    n = struct.unpack("<I", data[12:16])[0]
    doc = json.loads(data[20:20 + n])
    nodes = {nd["name"]: nd for nd in doc["nodes"]}
    assert {"circular_spline", "flexspline", "wave_generator"} <= set(nodes)
    a = report["assembly"]["position_mm"]
    np.testing.assert_allclose(nodes["circular_spline"]["translation"], [0, 0, a * 1e-3], atol=1e-15)
    scene = trimesh.load(out / "assembly.glb")
    assert {"circular_spline", "flexspline", "wave_generator"} <= set(scene.graph.nodes_geometry)
    lo, hi = scene.bounds
    c = d.circular_spline
    # Y up = the drive's axis: flexspline bottom (0) to the ring's far end (a + H); the ring's
    # outer diameter across x and z
    assert lo[1] == pytest.approx(0.0, abs=1e-5) and hi[1] == pytest.approx((a + c.bore_length_mm) * 1e-3, rel=1e-6)
    assert hi[0] - lo[0] == pytest.approx(2 * c.outer_radius_mm * 1e-3, rel=1e-6)
    assert hi[2] - lo[2] == pytest.approx(2 * c.outer_radius_mm * 1e-3, rel=1e-4)
    assert len(doc["materials"]) == 3


def _table_rows(page: str, table_id: str) -> list[list[str]]:
    body = re.search(rf"<table id='{table_id}'>(.*?)</table>", page, re.S).group(1)
    return [re.findall(r"<td[^>]*>(.*?)</td>", r) for r in re.findall(r"<tr>(.*?)</tr>", body) if "<td" in r]


def _table_titles(page: str, table_id: str) -> list[list[str]]:
    """The exact values of a table's cells: each number's full float64 text is in the
    ``title`` of its cell (the cell shows it rounded to its quantity's precision)."""
    body = re.search(rf"<table id='{table_id}'>(.*?)</table>", page, re.S).group(1)
    return [re.findall(r"<td[^>]*title='([^']*)'[^>]*>", r) for r in re.findall(r"<tr>(.*?)</tr>", body)
            if "<td" in r]


def test_report_html_holds_the_ratio_table_at_full_precision_and_is_self_contained(placed):
    d, out, report = placed
    page = (out / "report.html").read_text(encoding="utf-8")
    # issue 35: the arrangement sketch, the stress and torque curves, the strength and drive tables
    assert page.count("<svg") >= 2 and "arrangement, strength and torque" in page
    assert "circular spline fixed (hatched), flexspline output" in page
    for table_id in ("strength-table", "drive-table"):
        assert f"<table id='{table_id}'>" in page
    ref = harmonic_report(d)
    keys = ["a_mm", "beta_deg", "phi_deg", "contact_radius_mm", "cone_radius_mm", "radius_difference_mm", "ratio",
            "ratio_circular_spline_fixed", "ratio_flexspline_fixed"]
    rows = _table_titles(page, "ratio-table")
    shown = _table_rows(page, "ratio-table")
    assert len(rows) == len(ref["table"]) == 65
    for cells, text, row in zip(rows, shown, ref["table"]):
        assert [float(c) for c in cells] == [row[k] for k in keys]          # exact: shortest repr in the tooltip
        assert html.unescape(text[-1]) == (row["it_grade"] or "> IT13")      # the ISO grade beside the ratio
        # shown to the precision of the quantity: 4 decimals for mm and degrees, 4 digits for the ratio
        assert [float(t) for t in text[:6]] == [round(row[k], 4) for k in keys[:6]]
        assert float(text[6]) == pytest.approx(row["ratio"], rel=5e-4)
    speed = {c[0]: float(c[1]) for c in _table_rows(page, "speed-range")}
    exact = {c[0]: float(t[0]) for c, t in zip(_table_rows(page, "speed-range"), _table_titles(page, "speed-range"))}
    assert exact["speed range"] == ref["speed_range"] and exact["ratio at positions.max_mm"] == ref["ratio_max"]
    assert speed["speed range"] == pytest.approx(ref["speed_range"], rel=5e-4)
    assert design_hash(d) in page and __version__ in page
    assert not re.search(r"""(src|href)\s*=\s*["'](https?:|//|/|\.\.?/)""", page)
    assert "<link" not in page and "@import" not in page and "<script src" not in page
    assert page.count("<svg") == 2 and "scene-data" in page and "<canvas id='view'" in page
    scene = json.loads(re.search(r"<script type='application/json' id='scene-data'>(.*?)</script>", page,
                                 re.S).group(1).replace("<\\/", "</"))
    assert [i["name"] for i in scene["instances"]] == ["circular_spline", "flexspline", "wave_generator"]
    assert [i["cut"] for i in scene["instances"]] == [True, True, False]


@pytest.mark.skipif(CHROMIUM is None, reason="chromium not installed (apt-get install chromium)")
def test_report_html_viewer_draws_in_a_headless_browser(placed, tmp_path):
    d, out, report = placed
    flags = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
             "--disable-background-networking", "--disable-component-update", "--disable-sync",
             "--virtual-time-budget=20000"]
    r = subprocess.run([CHROMIUM, *flags, f"--user-data-dir={tmp_path / 'profile'}", "--dump-dom",
                        (out / "report.html").as_uri()], capture_output=True, encoding="utf-8", errors="replace",
                       timeout=180)
    assert r.returncode == 0, r.stderr[-2000:]
    body = r.stdout[r.stdout.index("<body"):r.stdout.index(">", r.stdout.index("<body")) + 1]
    assert 'data-viewer="ok"' in body and "data-errors" not in body, body
    assert 'data-edge-pixels="0"' in body


def test_glb_passes_the_khronos_validator(placed, tmp_path):
    d, out, report = placed
    issues = khronos_issues(out / "assembly.glb", tmp_path)
    assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"][:10]
