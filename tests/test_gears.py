"""Roller end spur gears and nut ring gears: involute geometry, measurements, pair checks,
phasing, 2D clearance and meshes (prs_geom.geometry.gears, gear_pair, gear_checks, gear_phasing,
planar, prs_geom.mesh.gears).

Every number is checked against something computed another way: the involute as an
unwrapped string, published worked examples, numerical measurements on the outline
(caliper planes, pins), a brute-force distance, the mechanism swept with the exact outlines.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from prs_geom.geometry import gears as G
from prs_geom.geometry.frames import carrier_angles, roller_spin
from prs_geom.geometry.gear_checks import internal_pair_checks, pinion_transform, standard_centre_distance
from prs_geom.geometry.gear_pair import GearPair, default_gear_pair, sweep_clearance
from prs_geom.geometry.gear_phasing import mesh_phase, phasing_divisible, roller_gear_phasing
from prs_geom.geometry.gears import SpurGear, involute, inverse_involute
from prs_geom.geometry.planar import min_clearance_2d, point_segment_distance, polygon_area, transform_2d
from prs_geom.mesh.gears import gear_mesh, star_shaped
from prs_geom.model.design import PRSDesign, Roller, Screw, default_design
from prs_geom.model.errors import DesignError

I3 = np.eye(3)


@pytest.fixture(scope="module")
def pair() -> GearPair:
    d = default_design()
    return default_gear_pair(d.roller.pitch_diameter_mm, d.nut.pitch_diameter_mm / d.roller.pitch_diameter_mm)


# --------------------------------------------------------------------------- helpers (independent)
def string_involute(rb: float, t: np.ndarray) -> np.ndarray:
    """The involute as the end of a string unwrapped from the base circle (start on +x)."""
    return rb * np.stack([np.cos(t) + t * np.sin(t), np.sin(t) - t * np.cos(t)], axis=-1)


def distance_to_string_involute(q: np.ndarray, rb: float) -> np.ndarray:
    """Distance from points q (n, 2) to the unwrapped-string involute, closed form: the foot
    of the normal from q has its string tangent point T(t) with q . (cos t, sin t) = r_b."""
    rq = np.hypot(q[:, 0], q[:, 1])
    phi = np.arctan2(q[:, 1], q[:, 0])
    best = np.full(len(q), np.inf)
    for sign in (1.0, -1.0):
        for wrap in (0.0, 2 * math.pi):
            t = phi + sign * np.arccos(np.clip(rb / rq, -1, 1)) + wrap
            ok = t >= 0
            d = np.hypot(*(q - string_involute(rb, t)).T)
            best = np.where(ok & (d < best), d, best)
    return best


def flank_frame(g: SpurGear, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Map outline points to tooth 0's right flank: (points, tooth index, was-left-flank)."""
    pitch = 2 * math.pi / g.teeth
    ang = np.arctan2(pts[:, 1], pts[:, 0])
    k = np.round(ang / pitch).astype(int) % g.teeth
    c, s = np.cos(-k * pitch), np.sin(-k * pitch)
    q = np.stack([c * pts[:, 0] - s * pts[:, 1], s * pts[:, 0] + c * pts[:, 1]], axis=-1)
    left = q[:, 1] < 0
    q[:, 1] = np.abs(q[:, 1])
    return q, k, left


def to_string_frame(g: SpurGear, q: np.ndarray) -> np.ndarray:
    """Right-flank points -> the frame of the string involute, from m, z, x, thinning only:
    external right flank at polar angle c - inv(a_r) (mirror, turn by c), internal at
    c' + inv(a_r) (turn by -c')."""
    a = math.radians(g.pressure_angle_deg)
    s = g.module_mm * (math.pi / 2 + 2 * g.profile_shift * math.tan(a)) - g.backlash_mm
    half = s / (g.module_mm * g.teeth)
    inv_a = math.tan(a) - a
    if g.internal:
        c = half - inv_a
        R = np.array([[math.cos(-c), -math.sin(-c)], [math.sin(-c), math.cos(-c)]])
        return q @ R.T
    c = half + inv_a
    m = q * np.array([1.0, -1.0])
    R = np.array([[math.cos(c), -math.sin(c)], [math.sin(c), math.cos(c)]])
    return m @ R.T


def involute_vertices(g: SpurGear, outline: np.ndarray, eps: float = 1e-9) -> np.ndarray:
    """Outline vertices on the involute: radius strictly between the form and tip circles."""
    r = np.hypot(outline[:, 0], outline[:, 1])
    lo, hi = sorted((g.form_radius_mm, g.tip_radius_mm))
    return outline[(r > lo + eps) & (r < hi - eps)]


def point_polyline_distance(p: np.ndarray, poly: np.ndarray, closed: bool = True) -> np.ndarray:
    a = poly
    b = np.roll(poly, -1, axis=0) if closed else poly[1:]
    a = a if closed else poly[:-1]
    ab = b - a
    t = np.clip(np.einsum("nmi,mi->nm", p[:, None, :] - a[None], ab) / np.einsum("mi,mi->m", ab, ab), 0, 1)
    d = p[:, None, :] - (a[None] + t[..., None] * ab[None])
    return np.sqrt((d ** 2).sum(-1)).min(axis=1)


def tooth_window(g: SpurGear, pts: np.ndarray, k: int = 0, width: float = 1.0) -> np.ndarray:
    """The outline points within +-width pitches of tooth k's centre, as one contiguous
    polyline (the polygon is re-started opposite the window first)."""
    pitch = 2 * math.pi / g.teeth
    ang = np.arctan2(pts[:, 1], pts[:, 0]) - k * pitch
    ang = (ang + math.pi) % (2 * math.pi) - math.pi
    start = int(np.argmax(np.abs(ang)))
    pts, ang = np.roll(pts, -start, axis=0), np.roll(ang, -start)
    return pts[np.abs(ang) <= width * pitch]


# --------------------------------------------------------------------------- basics
def test_involute_function_published_value_and_inverse():
    # inv 20 deg = 0.014904 (every gear table, e.g. SDP-SI "Elements of Metric Gear Technology")
    assert involute(math.radians(20)) == pytest.approx(0.0149044, abs=5e-8)
    a = np.linspace(0.01, 1.2, 50)
    assert np.allclose(inverse_involute(involute(a)), a, rtol=0, atol=1e-13)


@pytest.mark.parametrize("kwargs, field", [
    (dict(module_mm=-0.4, teeth=20), "module_mm"),
    (dict(module_mm=0.4, teeth=3), "teeth"),
    (dict(module_mm=0.4, teeth=20.0), "teeth"),
    (dict(module_mm=0.4, teeth=20, pressure_angle_deg=45), "pressure_angle_deg"),
    (dict(module_mm=0.4, teeth=20, backlash_mm=0.4), "backlash_mm"),
    (dict(module_mm=1.0, teeth=8, profile_shift=1.2), "profile_shift"),            # pointed
    (dict(module_mm=1.0, teeth=24, internal=True), "addendum_coefficient"),        # tip < base
    (dict(module_mm=1.0, teeth=20, tool_tip_radius_coefficient=0.6), "tool_tip_radius_coefficient"),
])
def test_validation_names_field_value_and_rule(kwargs, field):
    with pytest.raises(ValueError) as e:
        SpurGear(**kwargs)
    assert isinstance(e.value, DesignError)
    msg = str(e.value)
    assert msg.startswith(field + " = ") and ": " in msg and len(e.value.rule) > 5


def test_radii_and_thickness_formulas():
    g = SpurGear(2.0, 30, profile_shift=0.25, backlash_mm=0.05)
    assert g.pitch_radius_mm == 30.0
    assert g.base_radius_mm == pytest.approx(30 * math.cos(math.radians(20)))
    assert g.tip_radius_mm == pytest.approx(30 + 2 * 1.25)
    assert g.root_radius_mm == pytest.approx(30 - 2 * 1.0)
    assert g.tooth_thickness_at(30.0) == pytest.approx(g.tooth_thickness_mm, abs=1e-12)
    ring = SpurGear(2.0, 80, profile_shift=-0.25, internal=True)
    assert ring.tip_radius_mm == pytest.approx(80 - 2 * 0.75)     # x < 0 moves the ring tip out
    assert ring.root_radius_mm == pytest.approx(80 + 2 * 1.5)
    # ISO sign: x1 + x2 = 0 keeps the standard centre distance
    assert standard_centre_distance(g, ring) == pytest.approx(50.0, abs=1e-12)


def test_tooth_thickness_and_chord_against_published_example():
    """SDP-SI / KHK "Elements of Metric Gear Technology", Table 10-1 (chordal thickness of a
    spur gear): m = 10, alpha = 20 deg, z = 12, x = +0.3 -> s = 17.8918, theta = 8.54270 deg,
    s_j = 17.8256, chordal addendum h_j = 13.6657 (h_a = 13.000). The chord is measured here on
    the outline polygon: where it crosses the reference circle."""
    g = SpurGear(10.0, 12, profile_shift=0.3)
    assert g.tooth_thickness_mm == pytest.approx(17.8918, abs=5e-5)
    assert math.degrees(g.tooth_thickness_mm / (2 * g.pitch_radius_mm)) == pytest.approx(8.54270, abs=5e-6)
    o = tooth_window(g, np.asarray(g.outline(1e-4)), width=0.5)
    r = np.hypot(o[:, 0], o[:, 1])
    cross = np.nonzero((r[:-1] - 60.0) * (r[1:] - 60.0) <= 0)[0]
    pts = []
    for i in cross:
        u = (60.0 - r[i]) / (r[i + 1] - r[i])
        pts.append(o[i] + u * (o[i + 1] - o[i]))
    assert len(pts) == 2
    s_j = float(np.hypot(*(pts[0] - pts[1])))
    assert s_j == pytest.approx(17.8256, abs=1e-4)
    theta = math.asin(0.5 * s_j / 60.0)
    h_j = (g.tip_radius_mm - 60.0) + 60.0 * (1 - math.cos(theta))
    assert h_j == pytest.approx(13.6657, abs=1e-4)


# --------------------------------------------------------------------------- outline geometry
GEARS = {
    "roller_gear": SpurGear(0.4, 20, backlash_mm=0.02),
    "ring_gear": SpurGear(0.4, 100, internal=True, addendum_coefficient=0.9, backlash_mm=0.02),
    "shifted_17": SpurGear(1.0, 17, profile_shift=0.3, backlash_mm=0.03),
    "small_ring": SpurGear(1.0, 46, internal=True, profile_shift=-0.2),
}


@pytest.mark.parametrize("name", sorted(GEARS))
def test_outline_vertices_lie_on_the_unwrapped_string_involute(name):
    g = GEARS[name]
    o = np.asarray(g.outline(1e-3))
    q, _, _ = flank_frame(g, involute_vertices(g, o))
    assert len(q) > 10 * g.teeth
    d = distance_to_string_involute(to_string_frame(g, q), g.base_radius_mm)
    assert d.max() < 1e-7          # 0.1 um (they are exact: ~1e-14 mm)


@pytest.mark.parametrize("name", sorted(GEARS))
@pytest.mark.parametrize("tol", [1e-3, 1e-4])
def test_outline_chord_error_within_tolerance(name, tol):
    g = GEARS[name]
    o = np.asarray(g.outline(tol))
    assert polygon_area(o) > 0                                   # counter-clockwise
    # involute chords against the true involute, densely sampled between their end points
    flank, first = g.flank_polyline(tol)
    inv = np.asarray(flank[first:])
    rb = g.base_radius_mm
    t = np.sqrt(np.maximum((np.hypot(*inv.T) / rb) ** 2 - 1, 0))
    s = np.linspace(0, 1, 41)[1:-1]
    tt = t[:-1, None] + (t[1:] - t[:-1])[:, None] * s[None]
    c = g.involute_polar(np.clip(rb * np.sqrt(1 + tt ** 2), rb, None))
    rr = rb * np.sqrt(1 + tt ** 2)
    curve = np.stack([rr * np.cos(c), rr * np.sin(c)], -1)             # (segments, samples, 2)
    dev = point_segment_distance(curve, inv[:-1, None, :], inv[1:, None, :])
    assert dev.max() <= tol
    assert dev.max() > 0.2 * tol                                       # not grossly oversampled
    # the whole tooth (fillet, tip and root arcs too) against a 100x finer outline
    fine = tooth_window(g, np.asarray(g.outline(tol / 100)), width=0.5)
    coarse = tooth_window(g, o, width=0.7)
    d = point_polyline_distance(fine, coarse, closed=False)
    assert d.max() <= tol * (1 + 1e-9) + tol / 100


def test_outline_phase_convention_tooth0_on_plus_x():
    for g in GEARS.values():
        o = np.asarray(g.outline(1e-3))
        # tooth 0 is symmetric about +x: the outline maps onto itself under y -> -y
        mirrored = o * np.array([1.0, -1.0])
        d = point_polyline_distance(tooth_window(g, mirrored, width=0.4), tooth_window(g, o, width=0.6), closed=False)
        assert d.max() < 1e-12
        # the +x axis crosses the outline on the tip circle (tooth 0 there, not a space)
        q = np.roll(o, -1, axis=0)
        i = np.nonzero((o[:, 1] <= 0) & (q[:, 1] > 0) & (o[:, 0] > 0))[0]
        assert len(i) == 1
        x = o[i, 0] - o[i, 1] * (q[i, 0] - o[i, 0]) / (q[i, 1] - o[i, 1])
        assert abs(x[0] - g.tip_radius_mm) <= 1e-3


def test_undercut_limit_matches_the_generated_fillet():
    """x_min = h_FfP* - z sin^2(a)/2 against the rack-generated trochoid: just above x_min the
    fillet stays outside the involute, just below it cuts in (undercut)."""
    for z in (10, 12, 14):
        xmin = SpurGear(1.0, z).undercut_limit_shift
        assert xmin == pytest.approx(1.0 - 0.5 * z * math.sin(math.radians(20)) ** 2, abs=1e-3)
        above = SpurGear(1.0, z, profile_shift=xmin + 0.01)
        below = SpurGear(1.0, z, profile_shift=xmin - 0.1)
        assert not above.undercut and below.undercut
        f, bF = G._rack_fillet_curve(above)
        p = f(np.linspace(0, bF, 20001))
        r = np.hypot(*p.T)
        ok = r >= above.base_radius_mm
        excess = np.arctan2(p[ok, 1], p[ok, 0]) - above.involute_polar(r[ok])
        assert excess.min() > -1e-12                         # never inside the involute
        assert below.form_radius_mm > below.base_radius_mm   # crossing found above r_b
        f, bF = G._rack_fillet_curve(below)
        p = f(np.linspace(0, bF, 20001))
        r = np.hypot(*p.T)
        ok = r >= below.base_radius_mm
        assert (np.arctan2(p[ok, 1], p[ok, 0]) - below.involute_polar(r[ok])).min() < -1e-9
        # analytic form radius = end of the generated fillet (no undercut)
        assert above.form_radius_mm == pytest.approx(float(np.hypot(*G._rack_fillet_curve(above)[0](np.array([bF]))[0])), abs=1e-12)


# --------------------------------------------------------------------------- measurements
def test_span_measurement_published_example():
    """machinecalcs.com "Span Measurement Over Teeth Calculator", worked example: m = 2 mm,
    z = 20, alpha = 20 deg, x = 0 -> k = 3, W = 15.321 mm."""
    g = SpurGear(2.0, 20)
    assert g.recommended_span_teeth() == 3
    assert g.span_measurement(3) == pytest.approx(15.321, abs=5e-4)
    # ISO 21771: a profile shift adds 2 x m sin(a), one more tooth adds a base pitch,
    # thinning removes j cos(a)
    g2 = SpurGear(2.0, 20, profile_shift=0.3, backlash_mm=0.05)
    assert g2.span_measurement(3) - g.span_measurement(3) == pytest.approx(
        2 * 0.3 * 2.0 * math.sin(math.radians(20)) - 0.05 * math.cos(math.radians(20)), abs=1e-12)
    assert g.span_measurement(4) - g.span_measurement(3) == pytest.approx(g.base_pitch_mm, abs=1e-12)


@pytest.mark.parametrize("g", [SpurGear(0.4, 20, backlash_mm=0.02), SpurGear(1.0, 17, profile_shift=0.3, backlash_mm=0.03),
                               SpurGear(1.5, 43, profile_shift=-0.2)], ids=["roller", "shifted17", "neg43"])
def test_span_measurement_by_parallel_planes_on_the_outline(g):
    """Two parallel planes tangent to the outer flanks of k teeth (0 .. k-1): the caliper
    reading is the spread of the flank vertices along the normal to the group's axis."""
    tol = 1e-5
    k = g.recommended_span_teeth()
    o = np.asarray(g.outline(tol))
    q, tooth, left = flank_frame(g, o)
    r = np.hypot(*o.T)
    inv = (r > g.form_radius_mm + 1e-9) & (r < g.tip_radius_mm - 1e-9)
    axis = (k - 1) * math.pi / g.teeth
    n = np.array([-math.sin(axis), math.cos(axis)])       # perpendicular to the group's axis
    lo = o[inv & (tooth == 0) & left] @ n                 # outer flank of tooth 0
    hi = o[inv & (tooth == k - 1) & ~left] @ n            # outer flank of tooth k-1
    W = hi.max() - lo.min()
    assert W == pytest.approx(g.span_measurement(k), abs=2 * tol)
    # the tangent points are on the involute, near the measuring circle
    r1, _ = g.span_contact_radii(k)
    assert g.form_radius_mm < r1 < g.tip_radius_mm


def _pin_centre_numerically(g: SpurGear, dp: float, tol: float) -> float:
    """Radius of the centre of a pin of diameter dp resting in the space centred at pi/z,
    found by bisection on the distance from the pin centre to the outline polygon."""
    o = tooth_window(g, np.asarray(g.outline(tol)), k=0, width=1.5)
    u = np.array([math.cos(math.pi / g.teeth), math.sin(math.pi / g.teeth)])
    lo, hi = sorted((g.root_radius_mm, g.tip_radius_mm))
    lo, hi = lo - 2 * dp, hi + 2 * dp
    for _ in range(60):
        R = 0.5 * (lo + hi)
        d = point_polyline_distance((R * u)[None], o, closed=False)[0]
        # external: moving out widens the space; internal: moving out narrows it
        if (d < 0.5 * dp) != g.internal:
            lo = R
        else:
            hi = R
    return 0.5 * (lo + hi)


@pytest.mark.parametrize("g", [SpurGear(0.4, 20, backlash_mm=0.02), SpurGear(1.0, 17, profile_shift=0.3),
                               SpurGear(0.4, 100, internal=True, addendum_coefficient=0.9, backlash_mm=0.02),
                               SpurGear(1.0, 61, internal=True, profile_shift=0.2)],
                         ids=["roller", "odd17", "ring", "odd_ring61"])
def test_over_and_between_pins_by_placing_pins_on_the_outline(g):
    tol = 1e-5
    dp = g.ideal_pin_diameter()
    # the ideal pin touches at the measuring circle r + sigma x m
    R = g.pin_centre_radius(dp)
    u = np.array([math.cos(math.pi / g.teeth), math.sin(math.pi / g.teeth)])
    o = tooth_window(g, np.asarray(g.outline(tol)), k=0, width=1.5)
    d = point_polyline_distance((R * u)[None], o, closed=False)[0]
    assert d == pytest.approx(0.5 * dp, abs=2 * tol)
    rr = np.hypot(*o.T)
    near = o[np.argmin(np.hypot(*(o - R * u).T))]
    assert float(np.hypot(*near)) == pytest.approx(g.pitch_radius_mm + g.sigma * g.profile_shift * g.module_mm, abs=0.02 * g.module_mm)
    del rr
    for pin in (dp, 1.1 * dp if not g.internal else 0.9 * dp):
        Rn = _pin_centre_numerically(g, pin, tol)
        c = 1.0 if g.teeth % 2 == 0 else math.cos(0.5 * math.pi / g.teeth)
        M_num = 2 * Rn * c + g.sigma * pin
        assert g.over_pins(pin) == pytest.approx(M_num, abs=10 * tol)
    # rule of thumb (tandwiel.info): ~1.73 m external, ~1.65 m internal at 20 deg, x = 0,
    # no thinning
    plain = SpurGear(1.0, g.teeth, internal=g.internal, addendum_coefficient=g.addendum_coefficient)
    assert plain.ideal_pin_diameter() == pytest.approx(1.65 if g.internal else 1.73, abs=0.02)


# --------------------------------------------------------------------------- pair checks
def test_default_sizing_for_the_default_design(pair):
    d = default_design()
    p, r = pair.pinion, pair.ring
    assert (p.module_mm, p.teeth, r.teeth) == (0.4, 20, 100)
    assert (p.profile_shift, r.profile_shift) == (0.0, 0.0)
    assert (p.addendum_coefficient, r.addendum_coefficient) == (1.0, 0.9)
    assert p.module_mm * p.teeth == pytest.approx(d.roller.pitch_diameter_mm)     # working pitch = thread pitch dia
    assert pair.centre_distance_mm == pytest.approx(d.centre_distance_mm)         # a = r_s + r_r = r_n - r_r
    assert pair.ratio == pytest.approx(d.nut.pitch_diameter_mm / d.roller.pitch_diameter_mm)
    c = pair.checks()
    assert c.passed, c.failed
    assert c.working_pressure_angle_deg == pytest.approx(20.0, abs=1e-9)
    assert c.backlash_circumferential_mm == pytest.approx(0.04, abs=1e-12)        # 0.02 + 0.02 thinning
    assert c.backlash_normal_mm == pytest.approx(0.04 * math.cos(math.radians(20)), abs=1e-12)
    # contact ratio from its definition: path of contact A..E over the base pitch
    rb1, rb2, a = p.base_radius_mm, r.base_radius_mm, pair.centre_distance_mm
    AE = (math.sqrt(p.tip_radius_mm ** 2 - rb1 ** 2) - math.sqrt(r.tip_radius_mm ** 2 - rb2 ** 2)
          + a * math.sin(math.radians(20)))
    assert c.contact_ratio == pytest.approx(AE / p.base_pitch_mm, rel=1e-12)
    assert c.contact_ratio > 1.7
    assert p.span_measurement() == pytest.approx(0.4 * math.cos(math.radians(20)) * (2.5 * math.pi + 20 * involute(math.radians(20)))
                                                 - 0.02 * math.cos(math.radians(20)), abs=1e-12)
    assert p.recommended_span_teeth() == 3


def test_default_sizing_options_and_refusals():
    d = default_design()
    capped = default_gear_pair(8.0, 5.0, max_pinion_tip_diameter_mm=d.roller.major_diameter_mm)
    assert 2 * capped.pinion.tip_radius_mm == pytest.approx(d.roller.major_diameter_mm)
    assert capped.pinion.addendum_coefficient == pytest.approx(0.75)
    assert capped.checks().passed and capped.checks().contact_ratio > 1.5
    with pytest.raises(DesignError, match="roller_pitch_diameter_mm"):
        default_gear_pair(7.1, 5.0)                       # no standard module divides it
    # a roller gear that needs shifting: 16 teeth of 0.5 mm only
    shifted = default_gear_pair(8.0, 5.0, modules=(0.5,))
    assert shifted.pinion.profile_shift == pytest.approx(0.07) and shifted.ring.profile_shift == pytest.approx(-0.07)
    assert not shifted.pinion.undercut and shifted.checks().passed
    assert shifted.centre_distance_mm == pytest.approx(16.0)
    with pytest.raises(DesignError, match="module"):
        GearPair(SpurGear(0.4, 20), SpurGear(0.5, 80, internal=True), 15.0)


def test_full_ring_addendum_is_refused_and_the_sweep_agrees(pair):
    """With h_a2* = 1 the ring tip meets the pinion below its form circle (fillet contact): the
    check fails, and the swept outlines show the clearance eaten into (< j_n / 2)."""
    ring = SpurGear(0.4, 100, internal=True, backlash_mm=0.02)
    bad = GearPair(pair.pinion, ring, pair.centre_distance_mm)
    c = bad.checks()
    assert c.failed == ("pinion_fillet_contact",)
    adv = np.linspace(0, 2 * math.pi / 100, 13)
    s_bad = sweep_clearance(bad, [0.0], [0.0], mesh_phase(bad.pinion, bad.ring, 0.0), adv, chord_tol_mm=1e-3)
    s_ok = sweep_clearance(pair, [0.0], [0.0], mesh_phase(pair.pinion, pair.ring, 0.0), adv, chord_tol_mm=1e-3)
    half = 0.5 * c.backlash_normal_mm
    assert half - 1e-3 <= s_ok.min_clearance_mm <= half
    assert s_bad.min_clearance_mm < half - 3e-3       # the ring tip runs into the pinion fillet


def test_undercut_pinion_fails():
    p = SpurGear(1.0, 12)
    r = SpurGear(1.0, 60, internal=True, addendum_coefficient=0.8)
    assert p.undercut
    assert "pinion_undercut" in internal_pair_checks(p, r).failed
    shifted = SpurGear(1.0, 12, profile_shift=0.3)
    assert "pinion_undercut" not in internal_pair_checks(shifted, SpurGear(1.0, 60, internal=True, profile_shift=-0.3,
                                                                           addendum_coefficient=0.8)).failed


@pytest.mark.parametrize("zc, z2", [(15, 34), (20, 38), (25, 43), (34, 52), (50, 68), (100, 118)])
def test_trimming_check_reproduces_the_published_limits(zc, z2):
    """SDP-SI / KHK "Elements of Metric Gear Technology", Table 5-3a: smallest standard
    internal gear a standard pinion cutter (z_c, addendum 1.25 m, x = 0, 20 deg) can be
    pulled out of radially without trimming."""
    cutter = SpurGear(1.0, zc, addendum_coefficient=1.25)
    assert internal_pair_checks(cutter, SpurGear(1.0, z2, internal=True))["trimming_interference"].passed
    if z2 - 1 >= 34:          # below 34 teeth a standard internal gear has no involute tip
        assert not internal_pair_checks(cutter, SpurGear(1.0, z2 - 1, internal=True))["trimming_interference"].passed


@pytest.mark.parametrize("z1", [30, 40, 60])
def test_trochoid_check_on_standard_pairs(z1):
    """SDP-SI / KHK sec. 5.2(b): with standard gears at 20 deg, trochoid interference is
    avoided when the tooth difference is larger than about 9."""
    ok = [internal_pair_checks(SpurGear(1.0, z1), SpurGear(1.0, z1 + dz, internal=True))["trochoid_interference"].passed
          for dz in (7, 8, 10, 12)]
    assert ok == [False, False, True, True]


@pytest.mark.parametrize("z2, interferes", [(46, True), (48, False)])
def test_trochoid_check_agrees_with_the_swept_outlines(z2, interferes):
    """A small tooth difference: the analytic trochoid check and the mechanism swept with the
    exact outlines (one ring pitch, at the symmetric phase) must agree."""
    p = SpurGear(1.0, 40, backlash_mm=0.005)
    r = SpurGear(1.0, z2, internal=True, addendum_coefficient=0.8, backlash_mm=0.005)
    c = internal_pair_checks(p, r)
    assert c["trochoid_interference"].passed is (not interferes)
    assert c["pinion_fillet_contact"].passed and c["involute_interference"].passed
    s = sweep_clearance(GearPair(p, r, c.centre_distance_mm), [0.0], [0.0], mesh_phase(p, r, 0.0),
                        np.linspace(0, 2 * math.pi / z2, 31), chord_tol_mm=2e-3)
    assert s.any_overlap is interferes


@pytest.mark.parametrize("da", [-0.01, 0.01])
def test_backlash_at_another_centre_distance_as_measured(pair, da):
    """An internal pair loses backlash when the centre distance grows (the pinion moves into the
    ring): j_n(a + da) ~ j_n(a) - 2 da sin(a_w). The value is checked against the clearance of
    the placed outlines (half the normal backlash on each side at the symmetric phase)."""
    a = pair.centre_distance_mm + da
    c = internal_pair_checks(pair.pinion, pair.ring, a)
    assert (c.working_pressure_angle_deg - 20.0) * da > 0
    dj = c.backlash_normal_mm - pair.checks().backlash_normal_mm
    assert dj == pytest.approx(-2 * da * math.sin(math.radians(20)), rel=0.01)
    T = pinion_transform(0.0, a, mesh_phase(pair.pinion, pair.ring, 0.0))
    got = min_clearance_2d(pair.pinion.outline(1e-4), T, pair.ring.outline(1e-4), I3, b_material_inside=False)
    assert got.distance_mm == pytest.approx(0.5 * c.backlash_normal_mm, abs=3e-4)


# --------------------------------------------------------------------------- 2D clearance
def _brute_distance(A: np.ndarray, B: np.ndarray) -> float:
    """Non-crossing polygons: the closest pair of segments always has an end point in it."""
    return min(point_polyline_distance(A, B).min(), point_polyline_distance(B, A).min())


def test_min_clearance_matches_brute_force_and_detects_overlap():
    rng = np.random.default_rng(7)
    for trial in range(20):
        n, m = rng.integers(20, 200, size=2)
        ta, tb = np.sort(rng.uniform(0, 2 * math.pi, n)), np.sort(rng.uniform(0, 2 * math.pi, m))
        A = np.stack([np.cos(ta), np.sin(ta)], -1) * rng.uniform(0.5, 1.0, n)[:, None]
        B = np.stack([np.cos(tb), np.sin(tb)], -1) * rng.uniform(0.5, 1.0, m)[:, None]
        Tb = transform_2d(rng.uniform(0, 6), 2.2 + rng.uniform(0, 1), rng.uniform(-0.5, 0.5))
        Bt = B @ Tb[:2, :2].T + Tb[:2, 2]
        got = min_clearance_2d(A, I3, B, Tb)
        assert not got.overlap
        assert got.distance_mm == pytest.approx(_brute_distance(A, Bt), rel=1e-12, abs=1e-15)
        assert math.dist(got.point_a, got.point_b) == pytest.approx(got.distance_mm, rel=1e-9, abs=1e-15)
    # crossing boundaries
    sq = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    got = min_clearance_2d(sq, I3, sq, transform_2d(0.3, 0.5, 0.5))
    assert got.overlap and got.distance_mm == 0.0
    # one inside the other without touching: overlap for solids, clearance for a bore
    small = 0.2 * sq + 0.4
    got = min_clearance_2d(small, I3, sq, I3)
    assert got.overlap and got.distance_mm == pytest.approx(0.4)
    got = min_clearance_2d(small, I3, sq, I3, b_material_inside=False)
    assert not got.overlap


def test_mesh_phase_centres_the_pinion_symmetrically(pair):
    """At mesh_phase the pinion can turn the same angle either way before touching the ring,
    and that angle is the backlash: j_t / 2 on the working pitch circle."""
    p, r, a = pair.pinion, pair.ring, pair.centre_distance_mm
    P, R = p.outline(2e-4), r.outline(2e-4)
    for psi in (0.0, 0.4321):
        chi = mesh_phase(p, r, psi)

        def free(sign: float) -> float:
            lo, hi = 0.0, 0.02
            for _ in range(30):
                mid = 0.5 * (lo + hi)
                hit = min_clearance_2d(P, pinion_transform(psi, a, chi + sign * mid), R, I3, b_material_inside=False).overlap
                lo, hi = (lo, mid) if hit else (mid, hi)
            return lo

        up, down = free(1.0), free(-1.0)
        assert up == pytest.approx(down, abs=1e-4)
        assert up * p.pitch_radius_mm == pytest.approx(0.5 * pair.checks().backlash_circumferential_mm, abs=1e-3)


# --------------------------------------------------------------------------- phasing
def test_roller_gear_phasing_default_design(pair):
    d = default_design()
    psi = carrier_angles(d)
    chi = np.array([roller_spin(d, float(x)) for x in psi])
    ph = roller_gear_phasing(pair.pinion, pair.ring, psi, chi)
    assert ph.consistent
    assert np.abs(ph.residuals_rad).max() < 1e-12
    assert ph.offset_rad == pytest.approx(math.pi / pair.pinion.teeth, abs=1e-12)   # z_r - n_s z_g = 0
    assert phasing_divisible(d.roller.count, pair.ring.teeth, pair.pinion.teeth, d.screw.starts)


def test_roller_gear_phasing_running_sweep(pair):
    """Every roller of the default design, identical gears with the common offset, over a
    carrier advance of one ring pitch: clearance = half the normal backlash (less the chord
    tolerance) and no overlap; half a pinion pitch off, every roller collides."""
    d = default_design()
    psi = carrier_angles(d)
    chi = np.array([roller_spin(d, float(x)) for x in psi])
    off = roller_gear_phasing(pair.pinion, pair.ring, psi, chi).offset_rad
    adv = np.linspace(0.0, 2 * math.pi / pair.ring.teeth, 4)
    s = sweep_clearance(pair, psi, chi, off, adv, chord_tol_mm=1e-3)
    half = 0.5 * pair.checks().backlash_normal_mm
    assert not s.any_overlap
    assert s.clearance_mm.min() >= half - 2e-3
    assert s.clearance_mm.max() <= half + 1e-6
    wrong = sweep_clearance(pair, psi, chi, off + math.pi / pair.pinion.teeth, adv[:1], chord_tol_mm=1e-3)
    assert wrong.overlap.all()


@pytest.mark.parametrize("starts, rollers", [(4, 7), (4, 3), (4, 10), (4, 5), (6, 7), (6, 10), (5, 7)])
def test_phasing_consistency_equals_the_divisibility_rule(pair, starts, rollers):
    """A non-standard thread (n_s != n_n = 5) on the default gears: identical rollers mesh iff
    z | (z_ring - n_s z_g). The roller spins come from the thread (frames.roller_spin)."""
    d = PRSDesign(screw=Screw(starts=starts), roller=Roller(count=rollers))
    psi = carrier_angles(d)
    chi = np.array([roller_spin(d, float(x)) for x in psi])
    ph = roller_gear_phasing(pair.pinion, pair.ring, psi, chi)
    rule = phasing_divisible(rollers, pair.ring.teeth, pair.pinion.teeth, starts)
    assert ph.consistent is rule
    assert rule is ((100 - starts * 20) % rollers == 0)
    if not rule:
        assert np.abs(ph.residuals_rad).max() > 0.1 * math.pi / pair.pinion.teeth
        # and the mechanism shows it: some roller collides
        s = sweep_clearance(pair, psi, chi, ph.offset_rad, [0.0], chord_tol_mm=2e-3)
        assert s.any_overlap or s.clearance_mm.min() < 0.5 * pair.checks().backlash_normal_mm - 5e-3


# --------------------------------------------------------------------------- meshes
@pytest.mark.parametrize("which", ["pinion", "ring"])
def test_gear_mesh_closed_outward_and_volume(pair, which):
    trimesh = pytest.importorskip("trimesh")
    g = getattr(pair, which)
    tol, z0, z1 = 1e-3, -4.0, 0.5
    kw = {"outer_radius_mm": 24.0} if g.internal else {}
    V, F = gear_mesh(g, z0, z1, tol, phase_rad=0.3, **kw)
    assert V.dtype == np.float64 and F.dtype == np.int64 and V.shape[1] == 3 and F.shape[1] == 3
    m = trimesh.Trimesh(V, F, process=False)
    assert m.is_watertight and m.is_winding_consistent and m.volume > 0
    area = polygon_area(g.outline(tol))
    if g.internal:
        bottom = V[(V[:, 2] == z0) & (np.hypot(V[:, 0], V[:, 1]) > g.root_radius_mm + 1)]
        outer = bottom[np.argsort(np.arctan2(bottom[:, 1], bottom[:, 0]))]
        assert np.allclose(np.hypot(*outer[:, :2].T), 24.0)
        area = polygon_area(outer[:, :2]) - area
    assert m.volume == pytest.approx(area * (z1 - z0), rel=1e-9)
    # outward normals: the centroid of each wall face is left by its normal
    cen = V[F].mean(axis=1)
    wall = np.abs(m.face_normals[:, 2]) < 1e-9
    radial = np.einsum("ij,ij->i", m.face_normals[wall, :2], cen[wall, :2])
    inner = np.hypot(*cen[wall, :2].T) < (g.root_radius_mm + 0.5 if g.internal else np.inf)
    if g.internal:
        assert np.all(radial[inner] < 0) and np.all(radial[~inner] > 0)
    # the phase turns the part: every outline vertex, turned by 0.3 rad, is a vertex at z1
    top = V[V[:, 2] == z1][:, :2]
    c, s = math.cos(0.3), math.sin(0.3)
    turned = np.asarray(g.outline(tol)) @ np.array([[c, -s], [s, c]]).T
    key = lambda p: set(map(tuple, np.round(p, 9)))      # noqa: E731
    assert key(turned) <= key(top)


def test_gear_mesh_refuses_undercut_outline_and_bad_arguments(pair):
    under = SpurGear(1.0, 8)
    assert under.undercut
    assert not star_shaped(np.asarray(under.outline(1e-3)))
    with pytest.raises(DesignError, match="star-shaped"):
        gear_mesh(under, 0, 1)
    with pytest.raises(DesignError, match="outer_radius_mm"):
        gear_mesh(pair.ring, 0, 1)
    with pytest.raises(DesignError, match="z1"):
        gear_mesh(pair.pinion, 1, 0)
    assert star_shaped(np.asarray(pair.pinion.outline(1e-3))) and star_shaped(np.asarray(pair.ring.outline(1e-3)))
