"""The actuator layout (prs_geom/geometry/actuator.py): stroke, threaded length, screw ends,
supports for the ratings, nut mounting, stroke-end checks, and the design-file keys.

Positions are recomputed here by hand from the catalogue rows (ISO 15: 7204 B / 6204 =
20 x 47 x 14 mm; KM 4: M20x1, 6 mm wide; ISO 775: 16 mm shaft end, short series 28 mm;
DIN 471 for 20 mm: groove 19.0 x 1.3 mm) and the mechanism's nut assembly (default design:
nut ends 15.75 mm long beyond the 40 mm thread), not read back from the layout.
"""
from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import pytest

from prs_geom.analysis.rating import analyse_rating, buckling_load, critical_speed, resolve_supports
from prs_geom.geometry.actuator import DESIGN_FILE, actuator_layout, stroke_end_checks
from prs_geom.model.actuator import ActuatorSettings, DriveEnd, FixedEnd, FloatingEnd, NutMount
from prs_geom.model.design import Loading, MechanismSettings, PRSDesign, Screw, Supports, default_design
from prs_geom.model.errors import DesignError
from prs_geom.model.io import FIELD_COMMENTS, dumps_json, dumps_toml, load_design, loads_json, loads_toml

ROOT = Path(__file__).resolve().parents[1]
FOUR_START = ROOT / "examples" / "four-start-seven-rollers.toml"

# the default design by hand: nut thread [0, 40], nut ends 15.75 mm, stroke 100, over-travel 5,
# run-out one lead 5 x 2 = 10 mm
NUT_ASSEMBLY = (-15.75, 55.75)
FULL = (NUT_ASSEMBLY[0] - 50.0 - 5.0, NUT_ASSEMBLY[1] + 50.0 + 5.0)      # (-70.75, 110.75)
THREAD = (FULL[0] - 10.0, FULL[1] + 10.0)                                # (-80.75, 120.75)
PAIR = (THREAD[0] - 2 * 14.0, THREAD[0])                                 # 7204 B pair
FLOATING = (THREAD[1], THREAD[1] + 14.0)                                 # 6204


def test_default_layout_by_hand():
    lay = actuator_layout(default_design())
    assert lay.nut_assembly_z == pytest.approx(NUT_ASSEMBLY, abs=1e-12)
    assert lay.full_thread_z == pytest.approx(FULL, abs=1e-12)
    assert lay.thread_z == pytest.approx(THREAD, abs=1e-12)
    assert lay.threaded_length_mm == pytest.approx(71.5 + 100 + 2 * (5 + 10), abs=1e-12)
    lo, hi = lay.ends
    assert (lo.role, hi.role) == ("fixed", "floating")        # tension-compression: fixed at -z
    assert [b.designation for b in lo.bearings] == ["7204 B", "7204 B"]
    assert [b.designation for b in hi.bearings] == ["6204"]
    assert (min(b.z[0] for b in lo.bearings), max(b.z[1] for b in lo.bearings)) == pytest.approx(PAIR)
    assert hi.bearings[0].z == pytest.approx(FLOATING)
    # outward from the pair: undercut 3 x 1 mm, thread = locknut width 6 mm, journal 28 mm
    names = [s.name for s in lo.steps]
    assert names == ["fixed bearing seat", "locknut thread undercut", "locknut thread M20x1", "drive journal"]
    journal = lo.steps[-1]
    assert journal.diameter_mm == 16.0
    assert journal.z == pytest.approx((PAIR[0] - 3.0 - 6.0 - 28.0, PAIR[0] - 3.0 - 6.0))
    assert lo.key.width_mm == 5.0 and lo.key.height_mm == 5.0 and lo.key.shaft_depth_mm == 3.0
    assert lo.key_z[1] - lo.key_z[0] == 22.0                  # longest standard length <= 28 - 4
    assert lo.locknut_z == pytest.approx((PAIR[0] - 6.0, PAIR[0]))
    # floating: seat 14, DIN 471 groove 1.3 (ring 1.2 thick), collar max(1.5, 1.5 x 1.0)
    assert hi.tip_z == pytest.approx(FLOATING[1] + 1.3 + 1.5)
    assert lay.screw_z == pytest.approx((journal.z[0], FLOATING[1] + 2.8))


def test_supports_from_the_bearing_positions():
    lay = actuator_layout(default_design())
    pair_middle = 0.5 * (PAIR[0] + PAIR[1])                  # -94.75
    floating_middle = 0.5 * (FLOATING[0] + FLOATING[1])      # 127.75
    sup = lay.supports
    assert sup.critical_speed_length_mm == pytest.approx(floating_middle - pair_middle)      # 222.5
    assert sup.critical_speed_ends == "fixed-supported"
    # the nut at its upper stroke end (+50): the engaged thread's far end at 40 + 50
    assert sup.buckling_length_mm == pytest.approx(90.0 - pair_middle)                       # 184.75
    assert sup.worst_stroke_end == "hi"
    # and the ratings use them
    d = default_design()
    rating = analyse_rating(d)
    E, d_root = d.materials.screw.youngs_modulus_mpa, d.screw.minor_diameter_mm
    assert rating.limits.critical_speed_rpm == pytest.approx(critical_speed(d_root, 222.5, "fixed-supported", E),
                                                             rel=1e-12)
    assert rating.limits.buckling_load_n == pytest.approx(buckling_load(d_root, 184.75, "fixed-supported", E),
                                                          rel=1e-12)
    assert rating.limits.supports.source == "geometry" and rating.limits.supports.warnings == ()


def test_compression_compression_puts_the_fixed_end_at_the_top():
    d = default_design().with_changes(loading=Loading(installation="compression-compression"))
    lay = actuator_layout(d)
    lo, hi = lay.ends
    assert (lo.role, hi.role) == ("floating", "fixed")
    pair = (THREAD[1], THREAD[1] + 28.0)
    floating = (THREAD[0] - 14.0, THREAD[0])
    assert (min(b.z[0] for b in hi.bearings), max(b.z[1] for b in hi.bearings)) == pytest.approx(pair)
    assert lay.supports.critical_speed_length_mm == pytest.approx(0.5 * sum(pair) - 0.5 * sum(floating))
    # worst: the nut at the lower stroke end, its thread's far end at 0 - 50
    assert lay.supports.buckling_length_mm == pytest.approx(0.5 * sum(pair) - (-50.0))
    assert lay.supports.worst_stroke_end == "lo"


def test_without_a_floating_bearing_the_screw_is_fixed_free():
    d = default_design().with_changes(actuator=ActuatorSettings(floating_end=FloatingEnd(enabled=False)))
    lay = actuator_layout(d)
    assert lay.ends[1].role == "free" and lay.ends[1].tip_z == pytest.approx(THREAD[1])
    assert lay.supports.critical_speed_ends == "fixed-free"
    assert lay.supports.critical_speed_length_mm == pytest.approx(THREAD[1] - 0.5 * (PAIR[0] + PAIR[1]))


def test_explicit_supports_override_with_a_warning():
    d = default_design().with_changes(supports=Supports(unsupported_length_mm=48.0, buckling_ends="fixed-fixed"))
    res = resolve_supports(d)
    assert res.critical_speed_length_mm == 48.0 and res.buckling_length_mm == 48.0
    assert res.buckling_ends == "fixed-fixed" and res.critical_speed_ends == "fixed-supported"
    assert res.source == "geometry, overridden by the design file"
    assert len(res.warnings) == 3
    assert any("supports.unsupported_length_mm = 48 mm overrides the critical speed's span from the actuator "
               "geometry (222.5 mm" in w for w in res.warnings)
    assert any('supports.buckling_ends = "fixed-fixed" overrides the buckling end fixity' in w for w in res.warnings)
    # a value equal to the geometry's is no override worth a warning
    same = default_design().with_changes(supports=Supports(critical_speed_ends="fixed-supported"))
    assert resolve_supports(same).warnings == ()


def test_without_an_actuator_the_supports_are_as_before():
    d = default_design().with_changes(actuator=ActuatorSettings(enabled=False))
    assert d.screw.length_mm == 48.0 and actuator_layout(d) is None
    res = resolve_supports(d)
    assert (res.critical_speed_length_mm, res.critical_speed_ends) == (48.0, "fixed-supported")
    assert res.warnings == ()


def test_stroke_end_checks_pass_and_can_fail():
    d = default_design()
    checks = stroke_end_checks(d, actuator_layout(d))
    assert checks and all(c.passed for c in checks)
    assert {c.stroke_end for c in checks} == {"lo", "hi", "both"}      # both: the flange bolts
    by = {(c.stroke_end, c.what): c.clearance_mm for c in checks}
    # the nut assembly's lower face at -15.75 - 50 against the pair's inner face at -80.75
    assert by[("lo", "nut assembly to 7204 B, inner row (fixed end)")] == pytest.approx(15.0)
    assert by[("lo", "nut assembly to 7204 B, outer row (fixed end)")] == pytest.approx(29.0)
    assert by[("lo", "nut assembly to KM 4 (fixed end)")] == pytest.approx(15.0 + 28.0)
    assert by[("hi", "nut assembly to 6204 (floating end)")] == pytest.approx(15.0)
    assert by[("lo", "carrier over the screw")] == pytest.approx(0.25)
    # a carrier bore on the screw crest leaves no radial clearance: the check fails
    tight = d.with_changes(mechanism=MechanismSettings(carrier_radial_clearance_mm=0.0))
    failed = [c for c in stroke_end_checks(tight, actuator_layout(tight)) if not c.passed]
    assert {c.what for c in failed} == {"carrier over the screw"}


def test_four_start_seven_roller_example():
    d = load_design(FOUR_START)
    assert (d.screw.starts, d.roller.count, d.nut.starts) == (4, 7, 4)
    lay = actuator_layout(d)
    assert all(c.passed for c in stroke_end_checks(d, lay))
    # screw root 20 - 0.8 = 19.2 mm: the largest series-02 bore <= 17.2 is 17 (7203 B, 6203)
    assert [b.designation for e in lay.ends for b in e.bearings] == ["7203 B", "7203 B", "6203"]
    assert lay.threaded_length_mm == pytest.approx(lay.nut_assembly_z[1] - lay.nut_assembly_z[0] + 100 + 2 * (5 + 8))


#: Every size key of [actuator] with a valid value different from the rule's, and what it sets.
OVERRIDES = {
    "actuator.stroke_mm": 60.0,
    "actuator.over_travel_mm": 2.0,
    "actuator.screw_run_out_mm": 6.0,
    "actuator.thread_chamfer_mm": 0.2,
    "actuator.fixed_end.bearing_bore_mm": 17.0,
    "actuator.fixed_end.bearing_width_mm": 15.0,
    "actuator.fixed_end.bearing_outer_diameter_mm": 50.0,
    "actuator.fixed_end.locknut_thread_mm": 17.0,
    "actuator.fixed_end.undercut_width_mm": 2.5,
    "actuator.floating_end.bearing_bore_mm": 17.0,
    "actuator.floating_end.bearing_width_mm": 12.5,
    "actuator.floating_end.bearing_outer_diameter_mm": 42.0,
    "actuator.drive.diameter_mm": 14.0,
    "actuator.drive.length_mm": 30.0,
    "actuator.drive.key_length_mm": 18.0,
    "actuator.drive.flat_depth_mm": 1.0,
    "actuator.nut_mount.bolt": "M6",
    "actuator.nut_mount.bolt_count": 8,
    "actuator.nut_mount.bolt_circle_diameter_mm": 68.0,
    "actuator.nut_mount.flange_diameter_mm": 82.0,
    "actuator.nut_mount.flange_thickness_mm": 10.0,
    "actuator.nut_mount.bolt_length_mm": 20.0,
    "screw.length_mm": 230.0,
}
#: Keys that choose rather than size (tested through what they choose).
CHOICES = {"actuator.enabled", "actuator.fixed_end.bearing_series", "actuator.fixed_end.seat_tolerance",
           "actuator.fixed_end.locknut_tolerance", "actuator.floating_end.enabled",
           "actuator.floating_end.bearing_series", "actuator.floating_end.seat_tolerance", "actuator.drive.kind",
           "actuator.drive.fit", "actuator.nut_mount.kind"}


def _with(key: str, value) -> PRSDesign:
    """The default design with one design-file key set, read through the file reader (JSON)."""
    data = json.loads(dumps_json(default_design()))
    *tables, leaf = key.split(".")
    node = data
    for t in tables:
        node = node[t]
    node[leaf] = value
    # a flat is sized only on a flat drive
    if key == "actuator.drive.flat_depth_mm":
        node["kind"] = "flat"
    return loads_json(json.dumps(data))


def test_every_key_of_the_section_is_covered_here():
    keys = {k for k in FIELD_COMMENTS if k.startswith("actuator.")}
    assert keys == set(OVERRIDES) - {"screw.length_mm"} | CHOICES


@pytest.mark.parametrize("key", sorted(OVERRIDES))
def test_every_size_is_overridable_from_the_design_file(key):
    value = OVERRIDES[key]
    d = _with(key, value)
    lay = actuator_layout(d)
    size = lay.sizes[key]
    assert size.value == value and size.source == DESIGN_FILE
    # and the rule's value (default design) differs, with its source named
    default = actuator_layout(default_design()).sizes.get(key)
    if default is not None:
        assert default.value != value and default.source != DESIGN_FILE and default.source


def test_overrides_move_the_geometry():
    lay = actuator_layout(_with("actuator.fixed_end.bearing_width_mm", 15.0))
    assert lay.ends[0].steps[0].z[1] - lay.ends[0].steps[0].z[0] == pytest.approx(30.0)    # the pair
    lay = actuator_layout(_with("actuator.stroke_mm", 60.0))
    assert lay.threaded_length_mm == pytest.approx(71.5 + 60 + 2 * 15)
    lay = actuator_layout(_with("screw.length_mm", 230.0))
    assert lay.threaded_length_mm == pytest.approx(230.0)
    assert lay.full_thread_z[0] == pytest.approx(FULL[0] - 0.5 * (230.0 - 201.5))
    lay = actuator_layout(_with("actuator.drive.flat_depth_mm", 1.0))
    assert lay.ends[0].key is None and lay.ends[0].flat_depth_mm == 1.0


def test_every_default_size_names_its_rule():
    lay = actuator_layout(default_design())
    for key, size in lay.sizes.items():
        assert size.source and size.source != DESIGN_FILE, key
    assert "ISO 15" in lay.sizes["actuator.fixed_end.bearing_bore_mm"].source
    assert "ISO 775" in lay.sizes["actuator.drive.length_mm"].source
    assert "ISO 898-1" in lay.sizes["actuator.nut_mount.bolt"].source
    # M5: six proof loads 6 x 14.2 mm^2 x 580 MPa = 49 416 N >= 2 x 20 000 N; M4 gives 30 554 N
    assert lay.sizes["actuator.nut_mount.bolt"].value == "M5"
    assert 6 * 14.2 * 580 >= 40_000 > 6 * 8.78 * 580


@pytest.mark.parametrize("key, value, words", [
    ("actuator.fixed_end.bearing_bore_mm", 25.0, "must be below the screw root diameter 23.2 mm"),
    ("actuator.fixed_end.bearing_bore_mm", 21.0, "has no bearing bore of 21 mm"),
    ("actuator.fixed_end.locknut_thread_mm", 25.0, "must be a KM locknut thread not above the bearing bore"),
    ("actuator.drive.diameter_mm", 19.0, "must be below the locknut thread's minor diameter"),
    ("actuator.drive.key_length_mm", 4.0, "must exceed the key width 5 mm"),
    ("actuator.nut_mount.flange_thickness_mm", 20.0, "must fit on the lower nut end"),
    ("screw.length_mm", 150.0, "must be at least 201.5 mm for this actuator"),
])
def test_a_size_that_cannot_be_built_is_an_error_naming_its_field(key, value, words):
    with pytest.raises(DesignError) as exc:
        actuator_layout(_with(key, value))
    assert exc.value.field == key and words in str(exc.value)


def test_version_1_files_read_as_they_did():
    for name in ("standard.toml", "graded-pitch.toml"):
        old = load_design(ROOT / "tests" / "data" / "v1" / name)
        assert not old.has_actuator and old.screw.length_mm == 48.0
        new = load_design(ROOT / "examples" / name)
        assert new.has_actuator and new.screw.length_mm is None
        assert replace(old, actuator=ActuatorSettings(), screw=replace(old.screw, length_mm=None)) == new
    # a version-1 file that has the section keeps it
    text = (ROOT / "tests" / "data" / "v1" / "standard.toml").read_text().replace("length_mm = 48.0\n", "")
    assert loads_toml(text + "\n[actuator]\nstroke_mm = 50.0\n").has_actuator


def test_section_values_are_validated():
    with pytest.raises(DesignError, match="actuator.stroke_mm"):
        loads_toml(dumps_toml(default_design()).replace("stroke_mm = 100.0", "stroke_mm = -1.0"))
    for cls, kwargs, fld in ((FixedEnd, {"bearing_series": "04"}, "bearing_series"),
                             (FixedEnd, {"locknut_tolerance": "7H"}, "locknut_tolerance"),
                             (DriveEnd, {"kind": "spline"}, "kind"), (NutMount, {"bolt": "M7"}, "bolt"),
                             (NutMount, {"bolt_count": 2}, "bolt_count"), (Screw, {"length_mm": -5.0}, "length_mm")):
        with pytest.raises(DesignError) as exc:
            cls(**kwargs)
        assert exc.value.field == fld


def test_critical_speed_scales_with_the_stroke():
    # whirl goes as 1 / L^2: doubling the bearing span quarters the critical speed
    base = default_design()
    span0 = actuator_layout(base).supports.critical_speed_length_mm
    longer = base.with_changes(actuator=ActuatorSettings(stroke_mm=100.0 + span0))
    span1 = actuator_layout(longer).supports.critical_speed_length_mm
    assert span1 == pytest.approx(2 * span0)
    r0, r1 = analyse_rating(base), analyse_rating(longer)
    assert r1.limits.critical_speed_rpm / r0.limits.critical_speed_rpm == pytest.approx(0.25, rel=1e-12)
    assert math.isfinite(r1.limits.buckling_load_n)


def test_the_flange_is_where_the_load_models_hold_the_nut():
    # the analytic load model and the FE model hold the nut at its loaded end, z = 0
    # (face_z0, prs_geom/analysis/fe/teeth.py) in both installations: the flange sits there
    for installation in ("tension-compression", "compression-compression"):
        d = default_design().with_changes(loading=Loading(installation=installation))
        lay = actuator_layout(d)
        z0, z1 = lay.nut_mount.z
        assert z0 == pytest.approx(NUT_ASSEMBLY[0]) and z1 == pytest.approx(NUT_ASSEMBLY[0] + 8.0) and z1 < 0.0
