"""Ideal kinematics of the PRS (prs_geom.analysis.kinematics, docs/theory/kinematics.md).

References used here are independent of the module's formulas: hand-computed numbers of
DOMAIN section 9, finite differences of the poses, the helical surfaces of
docs/theory/geometry.md evaluated at moved points, and the contact analysis' normals.
"""
from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from prs_geom.analysis.contact import analyse_contact
from prs_geom.analysis.kinematics import Kinematics, check_kinematic_sizing, kinematics, poses
from prs_geom.geometry.frames import FIRST_MID_PITCHES, carrier_angles, roller_transform, rotation_z
from prs_geom.geometry.profiles import ThreadProfiles
from prs_geom.model.design import Nut, PRSDesign, Roller, Screw, Thread

TWO_PI = 2.0 * math.pi


def four_start_seven_roller(hand: str = "right") -> PRSDesign:
    """Standard sizing with 4 starts: r_s = (4 - 2) r_r, r_n = 4 r_r; 7 rollers (z does
    not divide 2 n_s, so the roller spin phases chi_k = -n_s psi_k matter)."""
    return PRSDesign(name="s4z7", thread=Thread(hand=hand),
                     screw=Screw(pitch_diameter_mm=12.0, starts=4),
                     roller=Roller(pitch_diameter_mm=6.0, count=7),
                     nut=Nut(pitch_diameter_mm=24.0, starts=4, outer_diameter_mm=32.0))


DESIGNS = {
    "default-right": lambda: PRSDesign(),
    "default-left": lambda: PRSDesign(thread=Thread(hand="left")),
    "s4z7-right": lambda: four_start_seven_roller("right"),
    "s4z7-left": lambda: four_start_seven_roller("left"),
    # screw starts != nut starts (r_s != (n_s - 2) r_r): the general engagement formula
    "screw-4-nut-5": lambda: PRSDesign(screw=Screw(starts=4)),
    "screw-4-nut-5-left-z7": lambda: PRSDesign(thread=Thread(hand="left"), screw=Screw(starts=4),
                                               roller=Roller(count=7)),
}


@functools.lru_cache(maxsize=None)
def design_and_kin(key: str) -> tuple[PRSDesign, Kinematics]:
    d = DESIGNS[key]()
    return d, kinematics(d)


def pitch_radii(d: PRSDesign) -> tuple[float, float, float]:
    return 0.5 * d.screw.pitch_diameter_mm, 0.5 * d.roller.pitch_diameter_mm, 0.5 * d.nut.pitch_diameter_mm


def wrap(x, p):
    """x reduced to [-p/2, p/2)."""
    return (np.asarray(x) + 0.5 * p) % p - 0.5 * p


# --------------------------------------------------------------------------- numbers
@pytest.mark.parametrize("hand, travel", [("right", -10.0), ("left", +10.0)])
def test_default_design_numbers_of_domain_section_9(hand, travel):
    """24/8/40 mm pitch diameters: w_c = 12/32 w_s = 0.375 w_s, roller spin -0.375 x 20/4
    relative to the carrier, -1.5 absolute; nut travel one lead (5 starts x 2 mm) per turn,
    toward -z for a right-hand screw turned positively about +z (the screw advances into
    the nut like a bolt), toward +z for left hand."""
    k = kinematics(PRSDesign(thread=Thread(hand=hand)))
    assert k.carrier_speed_ratio == pytest.approx(0.375, abs=1e-15)
    assert k.roller_spin_ratio_relative == pytest.approx(-1.875, abs=1e-15)
    assert k.roller_spin_ratio_absolute == pytest.approx(-1.5, abs=1e-15)
    assert k.nut_travel_per_screw_turn_mm == pytest.approx(travel, abs=1e-12)
    assert k.roller_drift_per_screw_turn_mm == pytest.approx(0.0, abs=1e-15)
    assert k.nut_speed_mm_s == pytest.approx(travel / TWO_PI, abs=1e-15)


@pytest.mark.parametrize("hand", ["right", "left"])
def test_four_start_seven_roller_numbers(hand):
    """d = 12/6/24 mm, 4 starts, p = 2: w_c = 6/18 = 1/3, relative spin -1/3 x 12/3 = -4/3,
    absolute -1; nut travel 4 x 2 = 8 mm per turn."""
    d = four_start_seven_roller(hand)
    k = kinematics(d)
    h = d.thread.hand_sign
    assert k.carrier_speed_ratio == pytest.approx(1.0 / 3.0, abs=1e-15)
    assert k.roller_spin_ratio_relative == pytest.approx(-4.0 / 3.0, abs=1e-15)
    assert k.roller_spin_ratio_absolute == pytest.approx(-1.0, abs=1e-15)
    assert k.nut_travel_per_screw_turn_mm == pytest.approx(-h * 8.0, abs=1e-12)
    assert k.roller_drift_per_screw_turn_mm == pytest.approx(0.0, abs=1e-15)


def test_screw_starts_other_than_nut_starts_general_travel():
    """n_s = 4 in the default 5-start nut: -p [n_s - (n_s - n_n) w_c/w_s]
    = -2 (4 + 0.375) = -8.75 mm per turn (checked against the threads below)."""
    _, k = design_and_kin("screw-4-nut-5")
    assert k.carrier_speed_ratio == pytest.approx(0.375, abs=1e-15)
    assert k.nut_travel_per_screw_turn_mm == pytest.approx(-8.75, abs=1e-12)


def test_willis_formula_holds_for_the_ratios():
    """Willis, relative to the carrier: (w_r - w_c)/(w_s - w_c) = -r_s/r_r (external
    mesh) and (w_n - w_c)/(w_r - w_c) = +r_r/r_n (internal mesh), with w_n = 0."""
    for key in ("default-right", "s4z7-right"):
        d, k = design_and_kin(key)
        rs, rr, rn = pitch_radii(d)
        wc, wr = k.carrier_speed_ratio, k.roller_spin_ratio_absolute
        assert (wr - wc) / (1.0 - wc) == pytest.approx(-rs / rr, rel=1e-14)
        assert (0.0 - wc) / (wr - wc) == pytest.approx(rr / rn, rel=1e-14)


# --------------------------------------------------------------------------- refusals
def test_non_standard_nut_sizing_is_refused_with_the_fields_named():
    # nut pitch circle off the roller pitch circle
    d = PRSDesign(nut=Nut(pitch_diameter_mm=41.0))
    fields = r"nut\.pitch_diameter_mm.*screw\.pitch_diameter_mm.*roller\.pitch_diameter_mm"
    with pytest.raises(ValueError, match=fields):
        check_kinematic_sizing(d)
    with pytest.raises(ValueError, match="nut.starts"):
        kinematics(d)
    # circles touch but the gear ratio n_n = 4 differs from r_n / r_r = 5
    d = PRSDesign(nut=Nut(starts=4))
    with pytest.raises(ValueError, match=r"nut\.starts x roller\.pitch_diameter_mm"):
        poses(d, [0.0])


def test_bad_inputs():
    d, k = design_and_kin("default-right")
    with pytest.raises(ValueError, match="1-D"):
        poses(d, np.zeros((2, 2)))
    with pytest.raises(ValueError, match="finite"):
        poses(d, [0.0, np.nan])
    with pytest.raises(ValueError, match="another design"):
        kinematics(PRSDesign(thread=Thread(hand="left")), analyse_contact(d))
    with pytest.raises(ValueError, match="body"):
        k.material_velocity("carriage", [0.0, 0.0, 0.0])


# --------------------------------------------------------------------------- poses
@pytest.mark.parametrize("key", ["default-right", "default-left", "s4z7-right"])
def test_poses_at_zero_are_the_static_assembly(key):
    d, _ = design_and_kin(key)
    P = poses(d, np.array([0.0]))
    eye = np.eye(4)
    for T in (P.screw[0], P.carrier[0], P.nut[0]):
        np.testing.assert_allclose(T, eye, atol=1e-12, rtol=0)
    for k in range(d.roller.count):
        np.testing.assert_allclose(P.roller[k, 0], roller_transform(d, k), atol=1e-12, rtol=0)
        np.testing.assert_allclose(P.roller_in_carrier[k, 0], roller_transform(d, k), atol=1e-12, rtol=0)
    assert P.roller.dtype == np.float64 and P.roller.shape == (d.roller.count, 1, 4, 4)
    assert not P.roller.flags.writeable


@pytest.mark.parametrize("hand", ["right", "left"])
def test_poses_after_one_revolution(hand):
    d = PRSDesign(thread=Thread(hand=hand))
    h = d.thread.hand_sign
    P = poses(d, [TWO_PI])
    np.testing.assert_allclose(P.screw[0], np.eye(4), atol=1e-12, rtol=0)
    # carrier: 0.375 rev about z, travelled with the nut by one lead (5 x 2 mm)
    expect_c = rotation_z(0.375 * TWO_PI)
    expect_c[2, 3] = -h * 10.0
    np.testing.assert_allclose(P.carrier[0], expect_c, atol=1e-12, rtol=0)
    expect_n = np.eye(4)
    expect_n[2, 3] = -h * 10.0
    np.testing.assert_allclose(P.nut[0], expect_n, atol=1e-12, rtol=0)
    # roller k: axis at carrier angle psi_k + 0.75 pi, absolute turn (1 - n_s) psi_k - 1.5 rev
    a = d.centre_distance_mm
    for k, psi in enumerate(carrier_angles(d)):
        T = P.roller[k, 0]
        orbit = psi + 0.375 * TWO_PI
        axis = [a * math.cos(orbit), a * math.sin(orbit), -h * 10.0]
        np.testing.assert_allclose(T[:3, 3], axis, atol=1e-12)
        turn = (1 - d.screw.starts) * psi - 1.5 * TWO_PI
        np.testing.assert_allclose(T[:3, :3], rotation_z(turn)[:3, :3], atol=1e-12)
        np.testing.assert_allclose(P.carrier[0] @ P.roller_in_carrier[k, 0], T, atol=1e-12)


def test_poses_are_vectorised_and_rigid():
    d, _ = design_and_kin("s4z7-right")
    phi = np.linspace(-3.0, 9.0, 13)
    P = poses(d, phi)
    assert P.screw.shape == (13, 4, 4) and P.roller.shape == (7, 13, 4, 4)
    for T in (P.screw, P.carrier, P.nut, P.roller.reshape(-1, 4, 4)):
        R = T[..., :3, :3]
        eye = np.broadcast_to(np.eye(3), R.shape)
        np.testing.assert_allclose(R @ np.swapaxes(R, -1, -2), eye, atol=1e-13)
        np.testing.assert_allclose(T[..., 3, :], np.broadcast_to([0, 0, 0, 1.0], T[..., 3, :].shape))
    one = poses(d, phi[5])
    np.testing.assert_allclose(one.roller[:, 0], P.roller[:, 5], atol=0, rtol=0)


# --------------------------------------------------------------------------- rolling, by finite differences
def fd_velocity(T_of, phi: float, X: np.ndarray, step: float = 1e-5) -> np.ndarray:
    """Velocity (per rad of screw angle) of the body point at world X: central difference
    of the pose, the point held in the body frame."""
    local = np.linalg.inv(T_of(np.array([phi]))[0]) @ np.append(X, 1.0)
    Tp, Tm = T_of(np.array([phi + step, phi - step]))
    return ((Tp - Tm) @ local)[:3] / (2.0 * step)


def body_pose(d: PRSDesign, body: str, k: int = 0):
    def T_of(angles):
        P = poses(d, angles)
        return P.roller[k] if body == "roller" else getattr(P, body)
    return T_of


@pytest.mark.parametrize("key", ["default-right", "default-left", "s4z7-right", "s4z7-left"])
@pytest.mark.parametrize("phi", [0.0, 0.7, 2.9, TWO_PI + 1.3])
def test_pure_rolling_at_the_pitch_points_from_pose_differences(key, phi):
    """At the pitch point on the screw side the roller and screw material points have the
    same in-plane velocity (their relative velocity is the nut's axial speed: the roller
    travels with the nut along the screw); at the nut side the whole relative velocity
    vanishes. Evaluated on every roller by finite differences of the poses."""
    d, _ = design_and_kin(key)
    rs, _, rn = pitch_radii(d)
    P = poses(d, [phi])
    nut_dz = (P.nut[0, 2, 3] - 0.0) / phi if phi else None
    for k, psi in enumerate(carrier_angles(d)):
        for radius, mate in ((rs, "screw"), (rn, "nut")):
            # pitch point on roller k's line of centres, carried by the carrier
            X = (P.carrier[0] @ np.array([radius * math.cos(psi), radius * math.sin(psi), 10.0, 1.0]))[:3]
            rel = fd_velocity(body_pose(d, "roller", k), phi, X) - fd_velocity(body_pose(d, mate), phi, X)
            assert np.abs(rel[:2]).max() < 1e-8, (k, mate, rel)
            if mate == "nut":
                assert abs(rel[2]) < 1e-8, (k, rel)
            else:
                v_nut = fd_velocity(body_pose(d, "nut"), phi, X)[2]
                assert rel[2] == pytest.approx(v_nut, abs=1e-8)
                if nut_dz is not None:
                    assert v_nut == pytest.approx(nut_dz, abs=1e-8)


@pytest.mark.parametrize("key", ["default-right", "default-left", "s4z7-left", "screw-4-nut-5"])
def test_analytic_velocities_equal_pose_differences(key):
    d, kin = design_and_kin(key)
    for side, cps in (("screw", kin.screw_roller), ("nut", kin.roller_nut)):
        for cs in cps.values():
            X = np.array(cs.point_mm)
            for body, v in (("roller", cs.roller_velocity_mm_s), (side, cs.mate_velocity_mm_s)):
                np.testing.assert_allclose(v, fd_velocity(body_pose(d, body), 0.0, X), atol=1e-8)
    X = np.array([3.0, -7.0, 2.0])
    fd = fd_velocity(body_pose(d, "carrier"), 0.0, X)
    np.testing.assert_allclose(kin.material_velocity("carrier", X), fd, atol=1e-8)


# --------------------------------------------------------------------------- thread engagement
def flank_height(T: np.ndarray, X: np.ndarray, first_mid: float, lead: float, hand: int, p: float,
                 half_width, xi: int) -> float:
    """World z of flank xi of the part tooth nearest X, on the vertical line through X.

    The part (pose T, a rotation about z plus a translation along z) carries the helical
    surface Z = m + h L theta / 2 pi + xi t(r) in its own frame (geometry.md, constant pitch).
    """
    local = np.linalg.inv(T) @ np.append(X, 1.0)
    r, theta = math.hypot(local[0], local[1]), math.atan2(local[1], local[0])
    helix = first_mid + hand * lead * theta / TWO_PI
    mid = helix + p * round((local[2] - helix) / p)
    return float(mid + xi * half_width(r) + T[2, 3])


ENGAGEMENT_ANGLES = [0.3, 1.0, 2.5, math.pi, TWO_PI, -0.7, 2 * TWO_PI + 0.2, 37.0]


@pytest.mark.parametrize("key", sorted(DESIGNS))
def test_thread_engagement_is_kept_at_both_contacts(key):
    """Move the analytic contact point of roller 0 with the carrier; the axial gap between
    the roller flank and the screw (nut) flank there, from the helical surfaces of the
    moved parts, stays what it was at angle 0 (where it is the contact analysis' gap).
    Every other roller: the same for the tooth mid-planes at its two pitch points."""
    d, kin = design_and_kin(key)
    contact = analyse_contact(d)
    h, p = d.thread.hand_sign, d.thread.pitch_mm
    prof = ThreadProfiles.from_design(d)
    parts = {"screw": (contact.screw_profile, d.screw.starts * p),
             "nut": (prof.nut, d.nut.starts * p), "roller": (prof.roller, p)}

    def height(pose_T, part, X, xi):
        pr, lead = parts[part]
        return flank_height(pose_T, X, FIRST_MID_PITCHES[part] * p, lead, h, p, pr.tooth_half_width, xi)

    angles = np.array([0.0] + ENGAGEMENT_ANGLES)
    P = poses(d, angles)
    upper = (("screw", contact.screw_roller["upper_at_theoretical"]), ("nut", contact.roller_nut["upper"]))
    for side, cp in upper:
        X0 = np.append(cp.point_mm, 1.0)
        gaps = []
        for i in range(len(angles)):
            X = (P.carrier[i] @ X0)[:3]
            mate = P.screw[i] if side == "screw" else P.nut[i]
            # upper contact: roller upper flank (+1) against the mate's lower flank (-1)
            gaps.append(height(mate, side, X, -1) - height(P.roller[0, i], "roller", X, +1))
        gaps = np.array(gaps)
        assert gaps[0] == pytest.approx(cp.gap_mm, abs=1e-9), side
        assert np.abs(wrap(gaps - gaps[0], p)).max() < 1e-9, (side, gaps - gaps[0])
    # mid-plane phases at the pitch points of every roller
    rs, _, rn = pitch_radii(d)
    mid = lambda T, part, X: height(T, part, X, 0)  # noqa: E731
    for k, psi in enumerate(carrier_angles(d)):
        for radius, side in ((rs, "screw"), (rn, "nut")):
            X0 = np.array([radius * math.cos(psi), radius * math.sin(psi), 9.0, 1.0])
            offs = []
            for i in range(len(angles)):
                X = (P.carrier[i] @ X0)[:3]
                mate = P.screw[i] if side == "screw" else P.nut[i]
                offs.append(mid(mate, side, X) - mid(P.roller[k, i], "roller", X))
            assert np.abs(wrap(np.array(offs) - offs[0], p)).max() < 1e-9, (k, side)


def test_engagement_check_sees_a_wrong_travel():
    """The check above is sensitive: the nut travel with the opposite sign, or 1 um off
    per turn, breaks it at a fractional angle."""
    d, kin = design_and_kin("s4z7-right")
    p = d.thread.pitch_mm
    prof = ThreadProfiles.from_design(d)
    rs = 0.5 * d.screw.pitch_diameter_mm
    phi = 0.3
    P = poses(d, [0.0, phi])
    X0 = np.array([rs, 0.0, 9.0, 1.0])
    for wrong in (-2.0 * kin.nut_travel_per_screw_turn_mm, 1e-3):
        shift = np.eye(4)
        shift[2, 3] = wrong * phi / TWO_PI
        offs = []
        for i, extra in ((0, np.eye(4)), (1, shift)):
            X = (P.carrier[i] @ X0)[:3]
            s = flank_height(P.screw[i], X, FIRST_MID_PITCHES["screw"] * p, 4 * p, 1, p,
                             prof.screw.tooth_half_width, 0)
            r = flank_height(extra @ P.roller[0, i], X, FIRST_MID_PITCHES["roller"] * p, p, 1, p,
                             prof.roller.tooth_half_width, 0)
            offs.append(s - r)
        assert abs(wrap(offs[1] - offs[0], p)) > 1e-5


# --------------------------------------------------------------------------- sliding
@pytest.mark.parametrize("key", ["default-right", "default-left", "s4z7-right", "screw-4-nut-5"])
def test_sliding_at_the_contacts(key):
    """Screw-roller: the contact sits off the pitch circle, so it slides (about 2.2 mm/s per
    rad/s on the default design), yet the sliding lies in the common tangent plane (the
    contact persists: meshing condition, which holds only with the right nut travel).
    Roller-nut on these designs: the contact is the pitch point, pure rolling."""
    d, kin = design_and_kin(key)
    for fl in ("upper", "lower"):
        s = kin.screw_roller[fl]
        n = np.array(s.normal)
        v = np.array(s.sliding_velocity_mm_s)
        assert s.sliding_speed_mm_s > 0.1
        assert abs(v @ n) < 1e-12 and abs(s.normal_sliding_mm_s) < 1e-12
        # the tangential resolution is complete
        assert math.hypot(s.sliding_along_rolling_mm_s, s.sliding_across_rolling_mm_s) == pytest.approx(
            s.sliding_speed_mm_s, rel=1e-12)
        assert abs(np.array(s.rolling_direction) @ n) < 1e-12
        r = kin.roller_nut[fl]
        assert r.sliding_speed_mm_s < 1e-12 and abs(r.normal_sliding_mm_s) < 1e-12
    if key == "default-right":
        assert kin.screw_roller["upper"].sliding_speed_mm_s == pytest.approx(2.2323, abs=1e-4)


@pytest.mark.parametrize("key", ["default-right", "default-left", "s4z7-right"])
def test_sliding_at_the_pitch_points_is_pure_rolling(key):
    """Pure-rolling reference: at the screw pitch point the in-plane sliding is zero and
    only the axial motion of the roller with the nut remains; at the nut pitch point the
    sliding vanishes entirely."""
    d, kin = design_and_kin(key)
    rs, _, rn = pitch_radii(d)
    v = kin.sliding_velocity("screw", [rs, 0.0, 5.0])
    assert np.abs(v[:2]).max() < 1e-12
    assert v[2] == pytest.approx(kin.nut_speed_mm_s, abs=1e-12)
    assert np.abs(kin.sliding_velocity("nut", [rn, 0.0, 5.0])).max() < 1e-12
    # the same from the roller k > 0 frames
    k = d.roller.count - 1
    psi = carrier_angles(d)[k]
    v = kin.sliding_velocity("nut", [rn * math.cos(psi), rn * math.sin(psi), 1.0], roller=k)
    assert np.abs(v).max() < 1e-12


def test_off_pitch_nut_contact_slides():
    """A roller arc radius other than r_r / sin(beta) moves the nut contact off the pitch
    circle (docs/theory/contact.md): the roller-nut contact then slides too."""
    d = PRSDesign(roller=Roller(arc_radius_mm=7.0))
    kin = kinematics(d)
    s = kin.roller_nut["upper"]
    assert s.sliding_speed_mm_s > 1e-3
    assert abs(s.normal_sliding_mm_s) < 1e-9
