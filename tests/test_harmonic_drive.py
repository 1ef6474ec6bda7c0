"""The harmonic drive family's kinematics, strength limit and tolerance grades
(prs_geom.harmonic.drive; issue 35)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from prs_geom.harmonic.drive import (FLEXSPLINE_MATERIALS, flexspline_bending_stress, harmonic_ratio, strength_limit,
                                     tolerance_grade, toothed_ratio)
from prs_geom.harmonic.model import HarmonicDesign, radius_difference, ratio_table, strength_section
from prs_geom.model.errors import DesignError


def _willis(r_f: float, r_c: float, fixed: str) -> float:
    """The same ratio by a second path: Willis' equation of the differential whose carrier is
    the wave generator, r_f (w_f - w_g) = r_c (w_c - w_g) (no slip at the travelling contact),
    with the generator at w_g = 1 and the fixed member at rest, solved as a linear system."""
    # unknowns [w_f, w_c]; rows: rolling, fixed member at rest
    A = np.array([[r_f, -r_c], [1.0, 0.0] if fixed == "flexspline" else [0.0, 1.0]])
    b = np.array([r_f - r_c, 0.0])
    w_f, w_c = np.linalg.solve(A, b)
    return 1.0 / (w_c if fixed == "flexspline" else w_f)


@pytest.mark.parametrize("r_f, r_c", [(50.0, 50.0519), (50.0, 52.5667), (53.0, 50.0), (10.0, 10.4)])
@pytest.mark.parametrize("fixed", ["circular_spline", "flexspline"])
def test_ratio_equals_the_rolling_system(r_f, r_c, fixed):
    assert float(harmonic_ratio(r_f, r_c, fixed)) == pytest.approx(_willis(r_f, r_c, fixed), rel=1e-12)


def test_output_direction_per_fixed_member():
    """Inner wave (flexspline inside): with the circular spline fixed the flexspline turns
    against the generator, with the flexspline fixed the circular spline turns with it; an
    outer-wave drive (flexspline outside) reverses both."""
    assert harmonic_ratio(50.0, 50.1, "circular_spline") < 0 < harmonic_ratio(50.0, 50.1, "flexspline")
    assert harmonic_ratio(50.1, 50.0, "circular_spline") > 0 > harmonic_ratio(50.1, 50.0, "flexspline")


def test_toothed_ratio_is_teeth_over_tooth_difference():
    """The harmonic gear drive: -z_f / (z_c - z_f) with the circular spline fixed and
    +z_c / (z_c - z_f) with the flexspline fixed (200 / 202 teeth: -100 and +101, the
    textbook harmonic drive)."""
    assert toothed_ratio(200, 202, "circular_spline") == pytest.approx(-100.0, rel=1e-15)
    assert toothed_ratio(200, 202, "flexspline") == pytest.approx(101.0, rel=1e-15)
    for zf, zc in ((100, 102), (160, 162), (98, 100)):
        assert toothed_ratio(zf, zc) == pytest.approx(-zf / (zc - zf))
        assert toothed_ratio(zf, zc, "flexspline") == pytest.approx(zc / (zc - zf))
    with pytest.raises(DesignError, match="circular_teeth"):
        toothed_ratio(100, 100)
    with pytest.raises(DesignError, match="fixed_member"):
        toothed_ratio(100, 102, "housing")


def test_signed_ratios_of_the_worked_example():
    """The published magnitudes are the circular-spline-fixed ratio; with the flexspline
    fixed the output is the circular spline and the ratio is one more, positive."""
    rows = ratio_table(HarmonicDesign(), [42.0, 73.0, 73.5, 74.0])
    for row in rows:
        assert row["ratio_circular_spline_fixed"] == pytest.approx(-row["ratio"], rel=1e-12)
        assert row["ratio_flexspline_fixed"] == pytest.approx(row["ratio"] + 1.0, rel=1e-12)
    assert [round(r["ratio"], 1) for r in rows[1:]] == [545.0, 963.6, 4155.1]


def test_iso_grades_at_the_published_positions():
    """The source: at a = 73.5 the radius difference 0.0519 mm is about the grade-8 tolerance
    of that size, at a = 74 the 0.0120 mm about grade 5 (contact diameter 107.5 mm, ISO 286
    80-120 mm: IT8 54 um, IT5 15 um, IT4 10 um)."""
    rows = ratio_table(HarmonicDesign(), [73.5, 74.0])
    assert [round(r["radius_difference_mm"], 4) for r in rows] == [0.0519, 0.0120]
    assert [round(r["contact_radius_mm"], 3) for r in rows] == [53.773, 53.772]
    assert [r["it_grade"] for r in rows] == ["IT8", "IT5"]
    # at a = 42 the 2.57 mm difference is coarser than any grade of the table
    assert tolerance_grade(2.5667, 107.6) == [None]


def test_strength_limit_of_steel_and_nylon_flexsplines():
    """The source: the smallest ratio is about 20 for metal flexsplines and below 10 for
    plastics such as nylon. The worked example's geometry with its 1.0 mm wall: steel
    (E 206 GPa, 300 MPa allowed) between 15 and 30, PA66 (E 3 GPa, 25 MPa) below 10."""
    d = HarmonicDesign()
    assert d.flexspline.wall_thickness_mm == 1.0
    by = {m["material"]: m for m in strength_section(d)}
    steel, pa66 = by["steel"], by["pa66"]
    assert FLEXSPLINE_MATERIALS["steel"].youngs_modulus_mpa == 206_000.0
    assert 15.0 < steel["min_ratio"] < 30.0 and pa66["min_ratio"] < 10.0
    # sigma = 3 E t Delta / (2 r^2): steel 123.6 MPa per mm of Delta on r0 = 50 mm
    assert float(flexspline_bending_stress(1.0, 50.0, 1.0, 206_000.0)) == pytest.approx(123.6, rel=1e-12)
    assert steel["min_ratio"] == pytest.approx(50.0 / (300.0 / 123.6), rel=1e-12)
    # the example's smallest ratio 19.5 (a = 42) bends a steel wall past 300 MPa: flagged
    lo = float(radius_difference(d, 42.0))
    assert steel["stress_at_min_position_mpa"] == pytest.approx(123.6 * lo, rel=1e-12)
    assert steel["stress_at_min_position_mpa"] > 300.0
    assert not steel["within"] and pa66["within"]
    s = strength_limit(FLEXSPLINE_MATERIALS["steel"], 50.0, 1.0, 2.0, 0.05)
    assert s.within and s.speed_range == pytest.approx((50 / 0.05) / (50 / 2.0))


def test_thin_ring_stress_by_a_second_path():
    """sigma = 3 E t Delta / (2 r^2) against the curvature change of w = Delta cos(2 theta)
    computed numerically: kappa = (w'' + w) / r^2, sigma = E (t / 2) max |kappa|."""
    r, t, E, delta = 50.0, 1.0, 206_000.0, 0.3
    theta = np.linspace(0.0, 2.0 * np.pi, 20001)
    w = delta * np.cos(2.0 * theta)
    h = theta[1] - theta[0]
    w2 = np.gradient(np.gradient(w, h), h)
    kappa = (w2 + w) / r ** 2
    sigma = E * 0.5 * t * np.abs(kappa[100:-100]).max()
    assert float(flexspline_bending_stress(delta, r, t, E)) == pytest.approx(sigma, rel=1e-5)


# --------------------------------------------------------------------------- the [drive] section (format 3)
def test_earlier_example_files_still_read():
    """Every example file of format 2 (tests/data/v2, the examples before the [drive]
    section) reads and equals today's example: the new section's defaults are the published
    example's arrangement."""
    from pathlib import Path

    from prs_geom.pipeline import load_any_design

    root = Path(__file__).resolve().parent
    for f in sorted((root / "data" / "v2").glob("*.toml")):
        assert load_any_design(f) == load_any_design(root.parent / "examples" / f.name), f.name


def test_drive_section_is_validated_naming_the_field():
    from prs_geom.harmonic.model import Drive

    for kwargs, fld in (({"fixed_member": "housing"}, "fixed_member"), ({"flexspline_material": "wood"},
                        "flexspline_material"), ({"friction_coefficient": 0.8}, "friction_coefficient"),
                        ({"slip_safety_factor": 0.5}, "slip_safety_factor"),
                        ({"adjusting_mechanism": "lever"}, "adjusting_mechanism"),
                        ({"adjusting_travel_per_turn_mm": 0.0}, "adjusting_travel_per_turn_mm")):
        with pytest.raises(DesignError) as exc:
            Drive(**kwargs)
        assert exc.value.field == fld


def test_pressing_force_torque_and_contact_pressure():
    """On the 4.57 deg cone the normal force is the axial pressing force / sin(alpha), 12.54
    times; the output torque is mu N r_c / S; the generator's is that over |ratio|; Hertz's
    pressure and ellipse against the closed form of a sphere on a plane."""
    from prs_geom.harmonic.drive import contact_load
    from prs_geom.harmonic.model import contact_state, design_ratio, drive_load

    d = HarmonicDesign()
    st = contact_state(d, np.array([42.0, 60.0, 73.5]))
    load = drive_load(d, st)
    assert load.normal_force_n[0] / 500.0 == pytest.approx(1.0 / np.sin(np.radians(4.5739)), rel=1e-4)
    assert load.normal_force_n[0] / 500.0 == pytest.approx(12.54, abs=0.01)
    np.testing.assert_allclose(load.output_torque_nm, 0.1 * load.normal_force_n * st["contact_radius_mm"] / 1.5e3,
                               rtol=1e-12)
    np.testing.assert_allclose(load.input_torque_nm,
                               load.output_torque_nm / np.abs(design_ratio(d, st["a_mm"])), rtol=1e-12)
    # the contact conforms more as Delta shrinks: the ellipse grows round the circumference
    assert np.all(np.diff(load.semi_axes_mm[:, 1]) > 0) and load.hertz_valid[0] and not load.hertz_valid[-1]
    # second path, a closed form: made a sphere on a plane (arc radius 10 mm, circumferential
    # curvature 1/10 mm, a flat bore), the contact is circular, a = (3 Q R eta / 4)^(1/3)
    mat = FLEXSPLINE_MATERIALS["steel"]
    alpha = np.radians(30.0)
    R = 10.0
    # the flexspline's circumferential curvature cos(alpha) (1/r_c + 3 Delta / r0^2) = 1/R with Delta = 0
    r_c = np.cos(alpha) * R
    c = contact_load(alpha, R, 50.0, r_c, 1e12, 0.0, 100.0, 1000.0, 0.1, 1.0, mat)
    eta = 2 * (1 - 0.3 ** 2) / 206_000.0
    Q = 0.5 * 1000.0 / np.sin(alpha)
    a = (3 * Q * R * eta / 4) ** (1 / 3)
    np.testing.assert_allclose(c.semi_axes_mm[0], [a, a], rtol=1e-6)
    assert c.max_pressure_mpa[0] == pytest.approx(3 * Q / (2 * np.pi * a * a), rel=1e-6)


def test_adjusting_mechanism_turns_and_resolution():
    """Turns from positions.min_mm = travel / lead; the resolution is the signed ratio's
    derivative times the lead per degree, checked against a finite difference of the ratio
    over one degree of the adjusting input."""
    from prs_geom.harmonic.model import adjusting, design_ratio

    d = HarmonicDesign()
    a = np.array([50.0, 70.0, 73.5])
    turns, per_degree = adjusting(d, a)
    np.testing.assert_allclose(turns, (a - 42.0) / 1.0)
    step = 1.0 / 360.0                                   # one degree of a 1 mm lead screw, mm
    fd = (design_ratio(d, a + step / 2) - design_ratio(d, a - step / 2))
    np.testing.assert_allclose(per_degree, fd, rtol=2e-3)
    assert np.all(per_degree < 0)                        # circular spline fixed: the ratio grows negative
    ff = replace(d, drive=replace(d.drive, fixed_member="flexspline"))
    assert np.all(adjusting(ff, a)[1] > 0)


# --------------------------------------------------------------------------- planetary generator
def test_planetary_stage_against_the_rolling_contacts():
    """The stage ratio 1 + r_ring r_p / (r_sun r_w) equals the input speed the contact
    conditions give for a carrier turning once with the ring at rest; the coupled ratio
    equals them with the ring at the harmonic output speed; with the flexspline fixed the
    product and the coupled ratio agree; the product is stage x harmonic at every position."""
    from prs_geom.harmonic.drive import planetary_stage

    i_h = np.array([-19.48, -100.0, -963.6])
    shift = np.array([0.0, 1.0, 3.2])
    p = planetary_stage(shift, 10.0, 10.0, 30.0, 8.0, 49.5, i_h)
    for k in range(3):
        r_s, r_p = p.sun_radius_mm[k], p.planet_cone_radius_mm[k]
        w_sun_fixed = _rolling_relative(r_s, r_p, 8.0, 49.5, 0.0)
        assert p.stage_ratio[k] == pytest.approx(w_sun_fixed, rel=1e-12)
        w_sun = _rolling_relative(r_s, r_p, 8.0, 49.5, 1.0 / i_h[k])
        assert p.coupled_ratio[k] == pytest.approx(w_sun * i_h[k], rel=1e-12)
    np.testing.assert_allclose(p.product_ratio, p.stage_ratio * i_h, rtol=1e-15)
    ff = planetary_stage(shift, 10.0, 10.0, 30.0, 8.0, 49.5, -i_h + 1.0, "flexspline")
    np.testing.assert_allclose(ff.coupled_ratio, ff.product_ratio, rtol=1e-15)
    # the cones trade radius along their common generatrix: the sum stays
    np.testing.assert_allclose(p.sun_radius_mm + p.planet_cone_radius_mm, 20.0, rtol=1e-15)


def _rolling_relative(r_sun, r_planet, r_roller, r_ring, w_ring):
    """Second path: no slip at both contacts written in the carrier's frame (carrier speed
    1). The shaft spins at w_p relative to the carrier; at the ring contact the roller's
    surface (radius r_w) matches the ring's, which moves at (w_ring - 1) r_ring relative to the
    carrier: w_p r_w = (w_ring - 1) r_ring; at the sun contact (external, opposite surface
    directions) (w_sun - 1) r_sun = -w_p r_p. Solved as a 2x2 linear system for
    [w_sun, w_p]."""
    A = np.array([[0.0, r_roller], [r_sun, r_planet]])
    b = np.array([(w_ring - 1.0) * r_ring, r_sun])
    return float(np.linalg.solve(A, b)[0])


def test_planetary_design_section_and_ratio_table():
    from prs_geom.harmonic.model import Generator, generator_stage

    d = replace(HarmonicDesign(), generator=Generator(kind="planetary"))
    rows = ratio_table(d, [42.0, 60.0, 74.0])
    p = generator_stage(d, [42.0, 60.0, 74.0])
    for row, k in zip(rows, range(3)):
        assert row["total_ratio"] == pytest.approx(row["generator_ratio"] * row["ratio_circular_spline_fixed"],
                                                   rel=1e-12)
        assert row["generator_ratio"] == p.stage_ratio[k]
    # the stage ratio falls as the cone contact moves out on the sun (position grows)
    assert rows[0]["generator_ratio"] > rows[1]["generator_ratio"] > rows[2]["generator_ratio"] > 1.0
    assert "generator_ratio" not in ratio_table(HarmonicDesign(), [42.0])[0]
    with pytest.raises(DesignError) as exc:
        replace(HarmonicDesign(), generator=Generator(kind="planetary", shift_per_position=1.0))
    assert exc.value.field == "generator.shift_per_position"
    with pytest.raises(DesignError) as exc:
        Generator(kind="cam")
    assert exc.value.field == "kind"


def test_stages_in_series_multiply():
    """Multi-stage drives as stages in series: each stage's output turns the next one's
    generator, so two identical stages with the circular spline fixed turn the last output
    with the input (-i)^2 > 0, three against it; the ratio table carries it."""
    from prs_geom.harmonic.model import stages_in_series

    i = np.array([-19.48, -963.6])
    np.testing.assert_allclose(stages_in_series(i, 2), i * i, rtol=1e-15)
    np.testing.assert_allclose(stages_in_series(i, 3), i * i * i, rtol=1e-15)
    d = HarmonicDesign()
    two = replace(d, drive=replace(d.drive, stages=2))
    row1, row2 = ratio_table(d, [73.5])[0], ratio_table(two, [73.5])[0]
    assert row1["ratio_all_stages"] == row1["ratio_circular_spline_fixed"]
    assert row2["ratio_all_stages"] == pytest.approx(row1["ratio_circular_spline_fixed"] ** 2, rel=1e-15)
    assert row2["ratio_all_stages"] > 9e5                       # 963.6^2, turning with the input
    from prs_geom.harmonic.model import Drive
    with pytest.raises(DesignError) as exc:
        Drive(stages=5)
    assert exc.value.field == "stages"
