"""Analytic contact points (issue 4)."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import optimize

from prs_geom.exports.report import contact_section
from prs_geom.analysis.contact import (ContactBatch, analyse_contact, contact_point, euclidean_distance,
                              solve_collinear, solve_gap_stationary, theoretical_screw, tooth_contacts)
from prs_geom.model.design import ContactSettings, Nut, PRSDesign, Roller, Screw, Thread, default_design
from prs_geom.model.errors import ConvergenceError
from strategies import standard_designs


def subset(batch, idx):
    return ContactBatch(batch.A, batch.B, *[getattr(batch, f)[idx] for f in
                        ("m_a", "xi_a", "m_b", "xi_b", "ox", "oy", "alpha", "z_offset")])


@settings(max_examples=25, deadline=None)
@given(standard_designs(max_teeth=12, pitch_lists=True), st.sampled_from(["screw", "nut"]),
       st.sampled_from(["upper", "lower"]))
def test_newton_and_gap_function_agree(d, side, flank):
    batch, q0, info = tooth_contacts(d, side, flank)
    res = solve_collinear(batch, q0)
    assert res.residual.max() < 1e-12
    idx = np.unique([0, len(q0) // 2, len(q0) - 1])
    sub = subset(batch, idx)
    pa, pb = batch.points(res.q)
    # start between the nominal point and the answer: the start only picks the basin
    xy_nom = np.column_stack([q0[idx, 0] * np.cos(q0[idx, 1]), q0[idx, 0] * np.sin(q0[idx, 1])])
    xy0 = 0.5 * (xy_nom + pa[idx, :2])
    alt = solve_gap_stationary(sub, xy0, q0[idx, 1], q0[idx, 3])
    np.testing.assert_allclose(alt[:, :2], pa[idx, :2], atol=1e-9, rtol=0)
    np.testing.assert_allclose(alt[:, 2], res.gap[idx], atol=1e-9, rtol=0)
    # the points coincide in x, y and the unit normals are collinear
    np.testing.assert_allclose(pa[:, :2], pb[:, :2], atol=1e-11)
    na, nb = batch.normals(res.q)
    np.testing.assert_allclose(np.cross(na, nb), 0.0, atol=1e-12)


def test_analytic_jacobian_matches_finite_differences():
    d = PRSDesign(roller=Roller(pitch_list_mm=tuple(2.0 + 1e-3 * math.sin(j) for j in range(19))))
    batch, q0, _ = tooth_contacts(d, "screw", "upper", np.array([1, 4]), np.array([3, 11]))
    q = q0 + np.array([0.01, 0.02, -0.01, 0.03])
    F, J = batch.residual_and_jacobian(q)
    h = 1e-7
    for k in range(4):
        dq = np.zeros(4)
        dq[k] = h
        Fp, _ = batch.residual_and_jacobian(q + dq)
        Fm, _ = batch.residual_and_jacobian(q - dq)
        np.testing.assert_allclose(J[:, :, k], (Fp - Fm) / (2 * h), atol=2e-6)


def test_newton_converges_quadratically():
    d = default_design()
    batch, q0, _ = tooth_contacts(d, "screw", "upper", np.array([0]), np.array([5]))
    res = solve_collinear(batch, q0)
    assert res.iterations <= 6
    # errors of successive iterates shrink quadratically
    q = q0.copy()
    errs = []
    for _ in range(4):
        F, J = batch.residual_and_jacobian(q)
        q = q + np.linalg.solve(J, -F[..., None])[..., 0]
        errs.append(np.abs(q - res.q).max())
    assert errs[2] < 10 * errs[1] ** 2 + 1e-15


@settings(max_examples=20, deadline=None)
@given(standard_designs(max_teeth=8))
def test_roller_nut_contact_on_line_of_centres_with_zero_gap(d):
    for flank in ("upper", "lower"):
        c = contact_point(d, "nut", flank)
        assert c.part_radius_mm == pytest.approx(0.5 * d.nut.pitch_diameter_mm, abs=1e-10)
        assert c.roller_radius_mm == pytest.approx(0.5 * d.roller.pitch_diameter_mm, abs=1e-10)
        assert abs(c.part_angle_deg) < 1e-8 and abs(c.roller_angle_deg) < 1e-8
        assert abs(c.gap_mm) < 1e-12
        # the point lies on the line of centres (y = 0 in the frame of roller 0)
        assert abs(c.point_mm[1]) < 1e-10


@settings(max_examples=20, deadline=None)
@given(standard_designs(max_teeth=8))
def test_upper_and_lower_flank_are_mirror_images(d):
    up = contact_point(d, "screw", "upper")
    lo = contact_point(d, "screw", "lower")
    assert lo.part_radius_mm == pytest.approx(up.part_radius_mm, abs=1e-10)
    assert lo.roller_radius_mm == pytest.approx(up.roller_radius_mm, abs=1e-10)
    assert lo.part_angle_deg == pytest.approx(-up.part_angle_deg, abs=1e-8)
    assert lo.roller_angle_deg == pytest.approx(-up.roller_angle_deg, abs=1e-8)
    assert lo.gap_mm == pytest.approx(up.gap_mm, abs=1e-10)
    # mirror through the line of centres: y and the normal's x, y components flip accordingly
    assert lo.point_mm[1] == pytest.approx(-up.point_mm[1], abs=1e-10)
    assert lo.normal[0] == pytest.approx(-up.normal[0], abs=1e-10)
    assert lo.normal[1] == pytest.approx(up.normal[1], abs=1e-10)


@settings(max_examples=15, deadline=None)
@given(standard_designs(max_teeth=8), st.sampled_from([0.0, 0.005, 0.02]))
def test_corrected_diameter_reaches_clearance_without_moving_the_contact(d, clearance):
    d = d.with_changes(contact=ContactSettings(clearance_mm=clearance))
    theo = theoretical_screw(d)
    assert theo.gap_at_nominal_mm < 0  # the nominal screw interferes
    assert abs(theo.gap_at_theoretical_mm - clearance) <= d.contact.precision_mm
    assert theo.theoretical_pitch_diameter_mm < theo.nominal_pitch_diameter_mm
    before = contact_point(d, "screw", "upper")
    after = contact_point(d, "screw", "upper", theo.profile)
    for f in ("part_radius_mm", "part_angle_deg", "roller_radius_mm", "roller_angle_deg"):
        assert getattr(after, f) == pytest.approx(getattr(before, f), abs=1e-10)
    # the correction is a pure axial flank shift: gap change = tan(beta)/cos(lambda) * dr
    prof = theo.profile
    dr = 0.5 * (theo.nominal_pitch_diameter_mm - theo.theoretical_pitch_diameter_mm)
    assert after.gap_mm - before.gap_mm == pytest.approx(math.tan(prof.beta) / prof.cos_lead * dr, abs=1e-10)


def test_domain_magnitudes_19_5_6_5_32_5():
    """DOMAIN.md section 3: a screw contact angle of a few degrees and a diameter
    correction of order 0.1 mm."""
    d = PRSDesign(screw=Screw(pitch_diameter_mm=19.5), roller=Roller(pitch_diameter_mm=6.5, count=8),
                  nut=Nut(pitch_diameter_mm=32.5, outer_diameter_mm=45.0))
    c = contact_point(d, "screw", "upper")
    assert 2.0 < abs(c.part_angle_deg) < 6.0
    theo = theoretical_screw(d)
    corr = theo.nominal_pitch_diameter_mm - theo.theoretical_pitch_diameter_mm
    assert 0.05 < corr < 0.3


def test_euclidean_distance_matches_brute_force_minimisation():
    d = PRSDesign(roller=Roller(pitch_list_mm=tuple(2.0 + 5e-4 * j / 19 for j in range(19))))
    theo = theoretical_screw(d)
    batch, q0, _ = tooth_contacts(d, "screw", "upper", np.array([2]), np.array([4]), theo.profile)
    batch.z_offset[:] = -0.004   # open the gap by 4 um
    res = solve_collinear(batch, q0)
    dist, q = euclidean_distance(batch, res.q)
    assert dist[0] > 0

    def separation(v):
        # a finite-difference probe may step past the flank arc's end (NaN there, no warning)
        with np.errstate(invalid="ignore"):
            pa, pb = batch.points(v[None, :])
        return (pa - pb).ravel()

    # an independent minimiser of |pa - pb| over the four surface parameters (trust region on
    # the separation vector, finite differences), started from the collinear solution
    best = optimize.least_squares(separation, res.q[0], xtol=1e-15, ftol=1e-15, gtol=1e-15,
                                  diff_step=1e-9)
    found = float(np.linalg.norm(best.fun))
    assert best.success and np.isfinite(found)
    assert found == pytest.approx(dist[0], abs=1e-9)
    assert found >= dist[0] - 1e-12  # the common-normal point is the minimum


def test_graded_roller_opens_tooth_gaps_by_its_corrections():
    """With the nut constant and the roller graded, the roller-nut gap of tooth j changes
    by the roller's cumulative correction (to first order in the normal direction)."""
    pl = tuple(2.0 + 1e-3 for _ in range(19))   # 1 um longer pitch per tooth
    d = PRSDesign(roller=Roller(pitch_list_mm=pl))
    rep = contact_section(analyse_contact(d))
    gaps = np.array(rep["tooth_gaps"]["nut"]["upper"]["gap_mm"])
    n = d.thread.engaged_teeth
    # roller tooth j moved up by (j - 1) * 1 um against the nut tooth above: gap shrinks
    axial = -(np.arange(1, n + 1) - 1) * 1e-3
    c = contact_point(d, "nut", "upper")
    normal_z = c.normal[2]
    np.testing.assert_allclose(gaps[0, 1:], axial[1:] * normal_z, rtol=2e-3)


def test_contact_section_fields():
    rep = contact_section(analyse_contact(default_design()))
    sr = rep["screw_roller"]
    for key in ("nominal_pitch_diameter_mm", "theoretical_pitch_diameter_mm", "interference_at_nominal_mm",
                "upper_at_nominal", "lower_at_nominal", "upper_at_theoretical"):
        assert key in sr
    assert sr["interference_at_nominal_mm"] == pytest.approx(-sr["upper_at_nominal"]["gap_mm"])
    c = sr["upper_at_nominal"]
    assert np.linalg.norm(c["normal"]) == pytest.approx(1.0, abs=1e-14)
    assert rep["tooth_gaps"] is None  # constant pitch
    assert "part_angle_deg" in rep["conventions"]


def test_left_hand_contact_is_mirror_image():
    r = contact_point(default_design(), "screw", "upper")
    lft = contact_point(PRSDesign(thread=Thread(hand="left")), "screw", "upper")
    assert lft.part_angle_deg == pytest.approx(-r.part_angle_deg, abs=1e-12)
    assert lft.point_mm[1] == pytest.approx(-r.point_mm[1], abs=1e-12)
    assert lft.gap_mm == pytest.approx(r.gap_mm, abs=1e-14)


def test_non_convergence_is_an_error_not_numbers():
    d = default_design()
    batch, q0, _ = tooth_contacts(d, "screw", "upper", np.array([0]), np.array([1]))
    with pytest.raises(ConvergenceError):
        solve_collinear(batch, q0 + np.array([50.0, 3.0, 40.0, 2.0]), max_iter=3)
