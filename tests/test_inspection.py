"""Over-wire / over-ball inspection values (prs_geom.analysis.inspection).

References used by these tests, all independent of the closed form under test:

* the numerical placement of a cylinder (wire) or sphere (ball) on the analytic helicoids
  built from the profile objects (Brent root of a Nelder-Mead minimum distance), both
  flanks separately: acceptance bar 0.1 um;
* the classical three-wire formula without lead correction, M = d2 + w (1 + 1/sin(alpha))
  - (P/2) cot(alpha), best wire w = P / (2 cos(alpha)), alpha the flank half-angle of the
  axial section: the textbook formula (Machinery's Handbook, "three-wire method"); the form
  used here was checked against its restatements D = M - (W (1 + csc(theta)) - P cot(theta)/2)
  (stone-calculator.com, "Pitch diameter from three wire system method") and, for 60 deg
  threads, E = M - 3 W + 0.86603 P with W = 0.57735 P (machinecalcs.com, "Three-wire thread
  measurement"); the internal (over-ball) form is the same triangle mirrored about the pitch
  line;
* scaling laws: a radial shift of a straight flank moves M by the same amount; a uniform
  thermal growth of the part moves M by the stated coefficient; a left-hand thread is the
  mirror image of the right-hand one.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import replace

import pytest

from prs_geom.analysis.contact import analyse_contact
from prs_geom.exports.report import inspection_section
from prs_geom.analysis.inspection import (GrooveAtPitchLine, PartInspection, best_gauge, classical_seat,
                                          groove_at_pitch_line, helical_flanks, inspect_part, inspection,
                                          place_gauge)
from prs_geom.geometry.profiles import ThreadProfiles
from prs_geom.model.design import Nut, PRSDesign, Screw, Thread, default_design

BAR_UM = 0.1


def _design(**sections) -> PRSDesign:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # broken standard-sizing relations are on purpose here
        return PRSDesign(**sections)


@pytest.fixture(scope="module")
def default_result():
    d = default_design()
    return d, analyse_contact(d), inspection(d)


@pytest.fixture(scope="module")
def large_lead_result():
    # 8 starts on the 24 mm screw: lead angle about 12 deg at the screw pitch line
    d = _design(name="eight_starts", screw=Screw(starts=8), nut=Nut(starts=8))
    return d, inspection(d)


@pytest.fixture(scope="module")
def left_hand_result():
    d = _design(name="left", thread=Thread(hand="left"))
    return d, inspection(d)


def _assert_numerically_confirmed(result: dict[str, PartInspection]) -> None:
    for part, r in result.items():
        assert r.numerical_check_um <= BAR_UM, (part, r.numerical_check_um)
        # the numerically seated gauge touches the flanks on the pitch cylinder
        assert r.contact_radius_check_um <= BAR_UM, (part, r.contact_radius_check_um)
        assert r.check_passed


def test_default_design_agrees_with_numerical_placement(default_result):
    d, contact, result = default_result
    assert set(result) == {"screw", "roller", "nut"}
    _assert_numerically_confirmed(result)
    # the screw is inspected at its theoretical (corrected) pitch diameter
    assert result["screw"].pitch_diameter_mm == pytest.approx(contact.theoretical_screw_pitch_diameter_mm,
                                                              abs=1e-12)
    assert result["screw"].pitch_diameter_mm < d.screw.pitch_diameter_mm - 0.05
    assert result["screw"].gauge == "wire" and result["roller"].gauge == "wire"
    assert result["nut"].gauge == "ball"


def test_large_lead_angle_agrees_with_numerical_placement(large_lead_result):
    _, result = large_lead_result
    assert result["screw"].lead_angle_deg > 11.0
    _assert_numerically_confirmed(result)
    # at 12 deg the lead-angle correction is tens of micrometres: the check is not vacuous
    assert abs(result["screw"].measurement_correction_um) > 10.0
    assert abs(result["screw"].gauge_correction_um) > 30.0


def test_left_hand_is_the_mirror_image(default_result, left_hand_result):
    _, _, right = default_result
    _, left = left_hand_result
    _assert_numerically_confirmed(left)
    for part in right:
        assert left[part].measurement_mm == pytest.approx(right[part].measurement_mm, abs=1e-9)
        assert left[part].gauge_diameter_mm == pytest.approx(right[part].gauge_diameter_mm, abs=1e-9)
        # the settled wire leans the other way
        assert left[part].wire_inclination_deg == pytest.approx(-right[part].wire_inclination_deg, abs=1e-9)


@pytest.mark.parametrize("half_angle_deg, internal", [(30.0, False), (30.0, True), (45.0, False), (45.0, True)])
def test_vanishing_lead_gives_the_classical_three_wire_formula(half_angle_deg, internal):
    """Single start, lead angle -> 0: the corrected best gauge and M reduce to the textbook
    values (module docstring references), which the code under test does not evaluate
    in this form."""
    p, d2 = 1.5, 9.026  # an M10 x 1.5 external thread's pitch diameter (ISO 724)
    al = math.radians(half_angle_deg)
    slope = -math.tan(al) if internal else math.tan(al)
    groove = GrooveAtPitchLine(p, 1e-7 * p, 1, 0.5 * d2, slope)
    seat = best_gauge(groove, "wire")
    w = 2.0 * seat.radius_mm
    assert w == pytest.approx(p / (2.0 * math.cos(al)), abs=1e-9)
    M = 2.0 * (seat.centre_radius_mm + seat.radius_mm)
    if internal:  # over the balls' outer extremes: the external triangle mirrored
        M_book = d2 - w * (1.0 / math.sin(al) - 1.0) + 0.5 * p / math.tan(al)
    else:
        M_book = d2 + w * (1.0 + 1.0 / math.sin(al)) - 0.5 * p / math.tan(al)
    assert M == pytest.approx(M_book, abs=1e-9)
    if half_angle_deg == 30.0 and not internal:
        assert w == pytest.approx(0.57735 * p, abs=1e-5 * p)
        assert M == pytest.approx(d2 + 3.0 * w - 0.86603 * p, abs=1e-5 * p)


def test_single_start_small_lead_stays_near_the_classical_value():
    """A single-start screw and nut (lead angles 1.5 and 0.9 deg): the correction is a
    fraction of a micrometre on M and is confirmed by the numerical placement."""
    d = _design(name="single", screw=Screw(starts=1), nut=Nut(starts=1))
    result = inspection(d)
    _assert_numerically_confirmed(result)
    for part in ("screw", "nut"):
        r = result[part]
        assert r.lead_angle_deg < 2.0
        assert abs(r.measurement_correction_um) < 1.0
        assert "odd start count" in r.method


def test_correction_is_second_order_in_the_lead():
    """Halving the lead quarters the correction of the best-gauge measurement."""
    def correction(lead: float) -> float:
        g = GrooveAtPitchLine(2.0, lead, 1, 12.0, 1.0)
        seat = best_gauge(g, "ball")
        # M - M_classical for the same ball: the rho terms cancel
        return 2.0 * (seat.centre_radius_mm - classical_seat(g, seat.radius_mm))

    ratio = correction(1.0) / correction(0.5)
    assert ratio == pytest.approx(4.0, rel=2e-2)


def test_settled_wire_is_the_deepest(default_result):
    """The wire's inclination is where it sits deepest: tilting it either way lifts it."""
    _, contact, result = default_result
    prof = contact.screw_profile
    g = groove_at_pitch_line(prof)
    seat = best_gauge(g, "wire")
    assert math.degrees(seat.inclination_rad) == pytest.approx(result["screw"].wire_inclination_deg, abs=1e-12)
    flanks = helical_flanks(prof)
    for tilt in (-0.004, 0.004):
        lifted = place_gauge(flanks, seat.radius_mm, "wire", seat.inclination_rad + tilt, seat.centre_radius_mm,
                             g.pitch_radius_mm)
        assert min(lifted.centre_radius_mm) > seat.centre_radius_mm + 1e-6
    # a wire held along the pitch-line helix tangent reads more than the settled one
    assert result["screw"].pitch_helix_wire_excess_um > 0.05


@pytest.mark.parametrize("part", ["screw", "nut"])
def test_larger_pitch_diameter_reads_larger_by_the_same_amount(default_result, part):
    """Same gauge, straight flanks moved radially by delta/2 (pitch diameter + delta):
    M grows by delta, up to a second-order lead term below tan^2(lambda)."""
    d, contact, result = default_result
    prof = contact.screw_profile if part == "screw" else ThreadProfiles.from_design(d).nut
    seat = best_gauge(groove_at_pitch_line(prof), result[part].gauge)
    M = 2.0 * (seat.centre_radius_mm + seat.radius_mm)
    assert M == pytest.approx(result[part].measurement_mm, abs=1e-12)
    delta = 0.010
    bigger = replace(prof, pitch_radius=prof.pitch_radius + 0.5 * delta,
                     lead_radius=prof.lead_radius or prof.pitch_radius)
    g = groove_at_pitch_line(bigger)
    placed = place_gauge(helical_flanks(bigger), seat.radius_mm, result[part].gauge, seat.inclination_rad,
                         seat.centre_radius_mm, g.pitch_radius_mm)
    grown = 2.0 * (placed.centre_radius_mm[0] + seat.radius_mm) - M
    assert grown > 0.0
    assert abs(grown / delta - 1.0) < math.tan(math.radians(result[part].lead_angle_deg)) ** 2


def test_temperature_coefficients(default_result):
    """A nut 10 K warm, measured with balls at 20 degC: its numerically placed M moves by the
    part-only coefficient; the engaged length grows 11.5 um/m/K x n p."""
    d, _, result = default_result
    prof = ThreadProfiles.from_design(d).nut
    r = result["nut"]
    dT = 10.0
    f = 1.0 + d.materials.nut.thermal_expansion_per_k * dT
    warm = replace(prof, pitch=prof.pitch * f, pitch_radius=prof.pitch_radius * f,
                   crest_radius=prof.crest_radius * f, root_radius=prof.root_radius * f)
    seat = best_gauge(groove_at_pitch_line(prof), "ball")
    placed = place_gauge(helical_flanks(warm), seat.radius_mm, "ball", 0.0, seat.centre_radius_mm * f,
                         warm.pitch_radius)
    grown_um = 1e3 * (2.0 * (placed.centre_radius_mm[0] + seat.radius_mm) - r.measurement_mm)
    assert grown_um == pytest.approx(r.temperature_coefficient_part_only_um_per_k * dT, abs=1e-3)
    # gauges of the same steel at the same temperature: everything scales
    assert r.temperature_coefficient_um_per_k == pytest.approx(11.5e-3 * r.measurement_mm, rel=1e-12)
    # 20 teeth x 2 mm = 40 mm of steel: 0.46 um/K
    assert r.engaged_length_growth_um_per_k == pytest.approx(0.46, abs=1e-12)


def test_report_has_units_in_its_keys(default_result):
    _, _, result = default_result
    rep = inspection_section(result)
    for part, values in rep.items():
        for key in values:
            assert key in ("part", "gauge", "method", "check_passed") or key.endswith(
                ("_mm", "_um", "_deg", "_um_per_k", "_degc")), key
        assert values["reference_temperature_degc"] == 20.0
        assert values["measurement_mm"] == pytest.approx(values["gauge_centre_diameter_mm"]
                                                         + values["gauge_diameter_mm"], abs=1e-12)


def test_results_are_validated():
    with pytest.raises(ValueError):
        GrooveAtPitchLine(2.0, 10.0, 1, 12.0, 0.0)
    with pytest.raises(ValueError):
        GrooveAtPitchLine(-2.0, 10.0, 1, 12.0, 1.0)
    with pytest.raises(ValueError):
        best_gauge(GrooveAtPitchLine(2.0, 10.0, 1, 12.0, 1.0), "pin")
    d = default_design()
    with pytest.raises(ValueError, match="internal"):
        inspect_part(d, ThreadProfiles.from_design(d).nut, "wire")


def test_balls_on_the_screw_read_what_the_settled_wires_read(default_result):
    """A ball seated numerically (a sphere, no inclination) in the screw groove reads the
    wire's M: the settled wire sits where the ball of its size sits."""
    d, contact, result = default_result
    balls = inspect_part(d, contact.screw_profile, "ball")
    assert balls.numerical_check_um <= BAR_UM
    assert balls.measurement_mm == pytest.approx(result["screw"].measurement_mm, abs=1e-10)
    assert balls.gauge_diameter_mm == pytest.approx(result["screw"].gauge_diameter_mm, abs=1e-10)
    assert balls.wire_inclination_deg == 0.0 and result["screw"].wire_inclination_deg > 7.0
