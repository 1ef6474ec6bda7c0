"""The whole mechanism (issue 19): carriers, roller journals, DIN 472 retaining rings and nut
ends; their fits, clearances, stack-up, interference with every other part, and the parts
list read back from a build."""
from __future__ import annotations

import math

import pytest

from prs_geom.analysis.contact import theoretical_screw
from prs_geom.checks.interference import check_assembly
from prs_geom.checks.mechanism import check_mechanism
from prs_geom.exports.report import mechanism_section
from prs_geom.exports.bom import read_parts_list_csv, read_parts_list_xlsx
from prs_geom.geometry.actuator import actuator_layout
from prs_geom.geometry.frames import screw_z_range, thread_length
from prs_geom.geometry.mechanism import layout
from prs_geom.geometry.profiles import ThreadProfiles
from prs_geom.mesh.assembly import build_assembly
from prs_geom.mesh.thread import analytic_thread_volume
from prs_geom.model.design import Nut, PRSDesign, Roller, Screw, default_design
from prs_geom.model.errors import DesignError
from prs_geom.model.standards import din472_sizes

#: The issue's two designs: the default (5 starts, 10 rollers) and a 4-start, 7-roller one in
#: the standard sizing r_s = (n_s - 2) r_r, r_n = n_n r_r.
DESIGNS = {
    "default": default_design,
    "four-start-seven-rollers": lambda: PRSDesign(
        name="s4z7", screw=Screw(pitch_diameter_mm=16.0, starts=4), roller=Roller(pitch_diameter_mm=8.0, count=7),
        nut=Nut(pitch_diameter_mm=32.0, starts=4, outer_diameter_mm=46.0)),
}
#: Coarse thread meshes keep the interference test quick; the mechanism parts are meshed at
#: 1 um whatever the tolerance (prs_geom.mesh.mechanism.MECHANISM_CHORD_MM).
TOL = 0.01


@pytest.fixture(scope="module", params=sorted(DESIGNS))
def placed(request):
    d = DESIGNS[request.param]()
    asm = build_assembly(d, tol=TOL, screw_profile=theoretical_screw(d).profile)
    return d, layout(d), asm


def test_default_sizes_follow_the_stated_rules():
    d = default_design()
    lay = layout(d)
    # journal: 0.6 x roller root diameter 7.2 mm = 4.32, down to 0.5 mm
    assert d.roller.minor_diameter_mm == pytest.approx(7.2)
    assert lay.journal_diameter_mm == 4.0
    # carrier: 1.5 x 4 = 6 mm; bore = screw crest radius 12.3 + 0.25 clearance
    assert lay.carrier_thickness_mm == 6.0
    assert lay.carrier_inner_radius_mm == pytest.approx(12.55)
    # ring: the smallest DIN 472 bore >= 2 x (a + bore radius + web + clearance)
    need = 2.0 * (16.0 + 2.006 + 2.0 + 0.25)
    sizes = din472_sizes()
    assert lay.ring.bore_mm == min(s for s in sizes if s >= need)
    assert max(s for s in sizes if s < need) < need
    # ISO 286-2: H7 over 3 up to 6 mm is +12/0 um, g6 is -4/-12 um
    f = lay.journal_fit
    assert (f.min_clearance_mm, f.max_clearance_mm) == pytest.approx((0.004, 0.024))
    assert f.modelled_clearance_mm == pytest.approx(0.014)


def test_stack_up_worst_case_from_the_iso_286_table():
    """Nominal play 2 x roller end play + 2 x ring play; the worst case takes off half of
    IT11 of the nut's groove span (63.9 mm: 190 um), of each carrier (6 mm: 75 um) and of the
    roller (48 mm: 160 um), ISO 286-1 Table 1; h11 rings only add play when thinner."""
    st = layout(default_design()).stack
    assert st.nominal_mm == pytest.approx(0.4, abs=1e-12)
    assert st.min_mm == pytest.approx(0.4 - 0.095 - 2 * 0.0375 - 0.080, abs=1e-12)
    assert st.max_mm == pytest.approx(0.4 + 0.095 + 2 * 0.0375 + 0.080 + 2 * 0.060, abs=1e-12)
    assert st.passed


def test_no_pair_of_parts_interferes(placed):
    d, lay, asm = placed
    names = set(asm.placed)
    z = d.roller.count
    assert {"carrier_lo", "carrier_hi", "retaining_ring_lo", "retaining_ring_hi", "nut_end_lo", "nut_end_hi"} <= names
    assert sum(n.startswith("roller_") and "_journal_" in n for n in names) == 2 * z
    rep = check_assembly(asm, TOL)
    assert rep["found"] is False
    # the pairs that touch by design overlap by no more than the chordal deviation
    for row in rep["contact_within_tolerance"]:
        assert row["mean_thickness_mm"] <= 2 * TOL


def test_journal_clearances_lie_in_the_fit_range(placed):
    d, lay, asm = placed
    sec = mechanism_section(check_mechanism(asm, lay, lay.ring.designation))
    rows = sec["journal_clearances"]
    assert len(rows) == 2 * d.roller.count
    lo, hi = 0.5 * lay.journal_fit.min_clearance_mm, 0.5 * lay.journal_fit.max_clearance_mm
    c = 0.5 * lay.journal_fit.modelled_clearance_mm
    # journal polygon: vertices on the circle, at most 1 um inside it; bore polygon outside
    for r in rows:
        assert lo <= r["fcl_clearance_mm"] <= hi
        assert c - 1e-9 <= r["fcl_clearance_mm"] <= c + 1e-3 + 1e-9
    assert sec["stack_up"]["min_play_mm"] > 0
    assert sec["passed"]


def test_mesh_volumes_agree_with_closed_forms(placed):
    d, lay, asm = placed
    for name, exact in (("carrier_lo", lay.carrier_volume_mm3), ("carrier_hi", lay.carrier_volume_mm3),
                        ("retaining_ring_lo", lay.ring_volume_mm3), ("nut_end_hi", lay.nut_end_volume_mm3),
                        ("roller_0_journal_lo", lay.journal_volume_mm3)):
        mesh = asm.placed[name][0]
        assert mesh.is_watertight
        assert mesh.volume == pytest.approx(exact, rel=1e-3), name


def test_layout_errors_name_the_field():
    with pytest.raises(DesignError, match="mechanism.journal_diameter_mm"):
        layout(PRSDesign(mechanism=default_design().mechanism.__class__(journal_diameter_mm=7.5)))
    # a bore DIN 472 does not hold is refused by the section itself (issue 29: the table look-up
    # of a value given alone belongs to the design's own validation)
    with pytest.raises(DesignError, match=r"ring_bore_mm = 59.0: must be a DIN 472 bore size: .*nearest sizes: 58, 60"):
        default_design().mechanism.__class__(ring_bore_mm=59.0)
    with pytest.raises(DesignError, match="journal_fit"):
        default_design().mechanism.__class__(journal_fit="H7/x6")


def _thread(**kw):
    from prs_geom.model.design import Thread
    return Thread(**kw)


def test_a_stack_up_beyond_iso_286_is_refused_naming_the_table_and_its_range():
    """Issue 29: engaged_teeth = 500 (nut length 1023.9 mm) passed validation and crashed the
    build after the meshing (ISO 286 ends at 500 mm). Now the layout refuses it, naming the
    field that drives the length, the table, its range, the value and the largest tooth count
    that fits; one tooth fewer than that fits."""
    from prs_geom.geometry.mechanism import check_layout

    with pytest.raises(DesignError) as err:
        check_layout(PRSDesign(thread=_thread(engaged_teeth=500)))
    msg = str(err.value)
    assert msg.startswith("thread.engaged_teeth = 500: the nut length")
    assert "1023.9 mm" in msg and "ISO 286" in msg and "up to and including 500 mm" in msg
    assert "reduce thread.engaged_teeth to at most 238" in msg and "mechanism.enabled = false" in msg
    lay = check_layout(PRSDesign(thread=_thread(engaged_teeth=238)))
    assert lay.stack.dimensions[0].nominal_mm <= 500.0
    with pytest.raises(DesignError, match="thread.engaged_teeth = 239"):
        check_layout(PRSDesign(thread=_thread(engaged_teeth=239)))
    # the gear faces drive it: named, not the teeth
    from prs_geom.model.design import GearSettings
    with pytest.raises(DesignError, match=r"^gears.face_width_mm = 300.0: .*621.9 mm.*500 mm"):
        check_layout(PRSDesign(thread=_thread(engaged_teeth=3), gears=GearSettings(face_width_mm=300.0)))
    # without a mechanism there is no stack-up: the design is fine (the gears are still sized)
    from prs_geom.model.design import MechanismSettings
    assert check_layout(PRSDesign(thread=_thread(engaged_teeth=500),
                                  mechanism=MechanismSettings(enabled=False))) is None


def test_values_given_alone_are_looked_up_at_construction():
    from prs_geom.model.design import MechanismSettings
    with pytest.raises(DesignError, match=r"^journal_diameter_mm = 600.0: the journal fit H7/g6 .*500 mm"):
        MechanismSettings(journal_diameter_mm=600.0)
    with pytest.raises(DesignError, match=r"^carrier_thickness_mm = 501.0: the stack-up zone js11 .*500 mm"):
        MechanismSettings(carrier_thickness_mm=501.0)
    with pytest.raises(DesignError, match=r"DIN 472 .*8-200 mm"):
        MechanismSettings(ring_bore_mm=250.0)
    assert MechanismSettings(ring_bore_mm=60.0).ring_bore_mm == 60.0


def test_a_carrier_beyond_din_472_names_the_table_range():
    # pitch diameters 400/100/600 mm: the carriers need a bore far beyond DIN 472's 200 mm
    d = PRSDesign(screw=Screw(pitch_diameter_mm=400.0, starts=5), roller=Roller(pitch_diameter_mm=100.0, count=10),
                  nut=Nut(pitch_diameter_mm=600.0, starts=5, outer_diameter_mm=700.0))
    from prs_geom.geometry.mechanism import check_layout
    with pytest.raises(DesignError, match=r"^mechanism.ring_bore_mm = \(not set\): no DIN 472 ring takes a carrier "
                                          r"of 617 mm .*tabulated for bores of 8 to 200 mm"):
        check_layout(d)


def test_validate_and_build_refuse_up_front(tmp_path):
    """The CLI: validate says exit 2 with the table's range; build refuses before any work
    (no output folder) instead of an internal error after the meshing."""
    from cli_helpers import run
    f = tmp_path / "d.toml"
    f.write_text("[thread]\nengaged_teeth = 500\n")
    code, out, err = run(["validate", str(f)])
    assert code == 2 and err.startswith("error: thread.engaged_teeth = 500") and "500 mm" in err
    assert "Traceback" not in err and out == ""
    code, _, err = run(["build", str(f), "--out", str(tmp_path / "out"), "--quiet"])
    assert code == 2 and "ISO 286" in err
    assert not (tmp_path / "out").exists()
    # a design whose stack-up has no play at worst case: valid, with the build's warning
    f.write_text("[thread]\nengaged_teeth = 238\n")
    code, out, err = run(["validate", str(f)])
    assert code == 0 and "warning: mechanism: the axial stack-up" in err and "is valid" in out


def test_parts_list_read_back(default_build):
    """CSV and XLSX read back: 1 screw, z rollers, 1 nut, 2 carriers, 2 retaining rings and
    the actuator's purchased parts (no volume, no mass); each mass is density x volume, and the
    volumes agree with closed forms within 0.1 % (thread volumes: the exact constant-pitch
    formula; gears: their meshes; the screw ends and the nut flange: cylinders, keyway and
    bolt holes)."""
    rep, out = default_build.report, default_build.out
    d = default_design()
    lay = layout(d)
    act = actuator_layout(d)
    csv_rows = read_parts_list_csv((out / "parts_list.csv").read_text(encoding="utf-8"))
    xlsx_rows = read_parts_list_xlsx(out / "parts_list.xlsx")
    assert [(r["part"], int(r["quantity"])) for r in csv_rows] == [
        ("screw", 1), ("roller", d.roller.count), ("nut", 1), ("carrier", 2), ("retaining ring", 2),
        ("bearing, fixed end", 2), ("bearing, floating end", 1), ("locknut", 1), ("shaft ring", 1),
        ("flange bolt", 6), ("drive key", 1)]
    assert [(r["part"], r["quantity"]) for r in xlsx_rows] == [(r["part"], int(r["quantity"])) for r in csv_rows]
    by_part = {r["part"]: r for r in csv_rows}
    # the catalogue designations of the default actuator (ISO 15, ISO 2982-2, DIN 471, ISO 4762
    # with 8 mm flange + 1.5 x 5 mm = 15.5 -> 16 mm, DIN 6885-1 for a 16 mm journal)
    assert [by_part[p]["designation"] for p in ("bearing, fixed end", "bearing, floating end", "locknut",
                                                "shaft ring", "flange bolt", "drive key")] == [
        "7204 B", "6204", "KM 4", "DIN 471 - 20 x 1.2", "ISO 4762 M5 x 16 - 8.8", "DIN 6885 A 5 x 5 x 22"]
    made = [(r, x) for r, x in zip(csv_rows, xlsx_rows) if r["material"] != "purchased"]
    assert len(made) == 5
    for r, x in zip(csv_rows, xlsx_rows):
        if r["material"] == "purchased":
            assert r["volume_mm3"] == r["mass_kg"] == r["density_kg_m3"] == "" and x["mass_kg"] is None
    for r, x in made:
        rho, vol, mass = float(r["density_kg_m3"]), float(r["volume_mm3"]), float(r["mass_kg"])
        assert mass == pytest.approx(rho * vol * 1e-9, rel=1e-12)
        assert x["mass_kg"] == pytest.approx(mass, rel=1e-12)
    from openpyxl import load_workbook

    assert load_workbook(out / "parts_list.xlsx").worksheets[0].freeze_panes == "A4"
    # one STL per mechanism part, in its own frame, with the closed-form volume
    import trimesh

    for name, exact in (("carrier", lay.carrier_volume_mm3), ("retaining_ring", lay.ring_volume_mm3)):
        stl = trimesh.load(out / f"{name}.stl", file_type="stl")
        assert stl.is_watertight and stl.bounds[0][2] == 0.0
        assert stl.volume == pytest.approx(exact, rel=1e-3)
    assert by_part["retaining ring"]["designation"] == f"DIN 472 - {lay.ring.bore_mm:g} x {lay.ring.thickness_mm:g}"

    prof = ThreadProfiles.from_design(d)
    from prs_geom.geometry.datum import datum_mark
    from prs_geom.mesh.assembly import end_gears

    def datum(profile, z_lo, body=None):
        return datum_mark(profile, z_lo, body).volume

    lo, hi = screw_z_range(d)
    screw_prof = theoretical_screw(d).profile
    # the ends: their steps (the run-out cylinders lie in the thread and fill its datum slot)
    # less the drive keyway, b t1 (l - b) + pi b^2 / 4 t1 less the journal's curvature over it
    key, (k0, k1) = act.ends[0].key, act.ends[0].key_z
    b, t1, r_j = key.width_mm, key.shaft_depth_mm, 0.5 * act.ends[0].steps[-1].diameter_mm
    a = 0.5 * b
    section = a * math.sqrt(r_j ** 2 - a ** 2) + r_j ** 2 * math.asin(a / r_j) - b * (r_j - t1)
    keyway = section * (k1 - k0 - b) + math.pi * a * a * t1     # the dome over its round ends: ~2 mm^3
    steps = sum(math.pi * (0.5 * st.diameter_mm) ** 2 * (st.z[1] - st.z[0]) for e in act.ends for st in e.steps)
    # the run-outs (wheel exits on the screw, chamfers on roller and nut): their own closed
    # form, tested against an independent quadrature in tests/test_thread_run_outs.py
    from prs_geom.mesh.assembly import design_run_outs
    from prs_geom.mesh.thread import run_out_volume

    def run_outs(part, profile):
        return sum(run_out_volume(profile, ro) for ro in design_run_outs(d, part))

    screw = analytic_thread_volume(screw_prof, hi - lo) + steps - keyway + run_outs("screw", screw_prof)
    L = thread_length(d)
    R = 0.5 * d.nut.outer_diameter_mm
    gears = end_gears(d, d.mesh.chord_tolerance_mm)
    roller = (analytic_thread_volume(prof.roller, L) - datum(prof.roller, 0.0) + 2 * lay.journal_volume_mm3
              + gears["roller_lo"].volume + gears["roller_hi"].volume + run_outs("roller", prof.roller))
    # the nut end overlaps the ring gear's body (an annulus) around the gear: counted once
    overlap = math.pi * (lay.ring_gear_outer_radius_mm ** 2 - lay.nut_end_sleeve_inner_radius_mm ** 2) \
        * lay.gear_face_width_mm
    # the flange outside the nut end, less its bolt holes
    m = act.nut_mount
    flange = (math.pi * (0.25 * m.flange_diameter_mm ** 2 - lay.nut_end_outer_radius_mm ** 2)
              - m.bolt_count * math.pi * (0.5 * m.bolt.clearance_hole_mm) ** 2) * (m.z[1] - m.z[0])
    nut = (analytic_thread_volume(prof.nut, L, R) - datum(prof.nut, 0.0, R) + 2 * lay.nut_end_volume_mm3
           + gears["ring_lo"].volume + gears["ring_hi"].volume - 2 * overlap + flange + run_outs("nut", prof.nut))
    for part, exact in (("screw", screw), ("roller", roller), ("nut", nut), ("carrier", lay.carrier_volume_mm3),
                        ("retaining ring", lay.ring_volume_mm3)):
        rho = float(by_part[part]["density_kg_m3"])
        assert float(by_part[part]["mass_kg"]) == pytest.approx(rho * exact * 1e-9, rel=1e-3), part


def test_build_reports_the_mechanism(default_build):
    rep, out = default_build.report, default_build.out
    sec = rep["mechanism"]
    assert sec["passed"] and all(c["passed"] for c in sec["checks"])
    assert rep["checks"]["interference"]["found"] is False
    assert rep["checks"]["interference"]["nominal_screw"]["found"] is True
    assert "parts_list.csv" in rep["files"] and "parts_list.xlsx" in rep["files"]
    html = (out / "report.html").read_text(encoding="utf-8")
    assert "id='parts-list'" in html and "id='mechanism'" in html
    assert rep["parts_list"][4]["designation"] in html


def test_carrier_guided_in_the_nut_bore():
    """carrier_guidance = "nut": the carrier's outside runs in the nut end bore with H8/f7.
    ISO 286-2: H8 over 30 up to 50 mm is +39/0 um, f7 is -25/-50 um, so the DIN 472 41 mm
    bore gives 25 to 89 um diametral clearance; the meshes sit at the middle of both zones."""
    from prs_geom.model.design import MechanismSettings

    d = PRSDesign(mechanism=MechanismSettings(carrier_guidance="nut"))
    lay = layout(d)
    f = lay.carrier_fit
    assert f is not None and f.fit == "H8/f7" and f.nominal_diameter_mm == lay.ring.bore_mm == 41.0
    assert (f.min_clearance_mm, f.max_clearance_mm) == pytest.approx((0.025, 0.089))
    assert 2 * lay.carrier_outer_radius_mm == pytest.approx(41.0 - 0.0375)
    assert 2 * lay.nut_bore_radius_mm == pytest.approx(41.0 + 0.0195)
    asm = build_assembly(d, tol=TOL, screw_profile=theoretical_screw(d).profile)
    sec = mechanism_section(check_mechanism(asm, lay, lay.ring.designation))
    assert [c["name"] for c in sec["checks"]][:2] == ["fit: roller journal in carrier bore", "fit: carrier in nut bore"]
    assert sec["passed"]
    assert check_assembly(asm, TOL)["found"] is False
