"""Flank shapes as objects (issue 12): each answers point, normal, curvature, inverse and
outline, checked against independent references (finite differences, the circle it is, the
straight line it is)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from prs_geom.geometry.flanks import ArcFlank, FlankShape, StraightFlank
from prs_geom.geometry.primitives import CircleArc, Segment
from prs_geom.geometry.profiles import ThreadProfiles
from prs_geom.model.design import default_design

Q = 0.25 * 2.0 * math.cos(0.05)      # a quarter normal pitch (mm)
FLANKS = {
    "screw": StraightFlank(math.tan(math.radians(45.0)), -1, 12.0),
    "nut": StraightFlank(math.tan(math.radians(40.0)), +1, 20.0),
    "roller": ArcFlank(4.0 / math.sin(math.radians(45.0)), 4.0),
}
RADII = {"screw": np.linspace(11.2, 12.3, 9), "nut": np.linspace(19.7, 20.4, 9), "roller": np.linspace(3.6, 4.3, 9)}


@pytest.mark.parametrize("part", sorted(FLANKS))
def test_flank_protocol_against_finite_differences(part):
    f, r = FLANKS[part], RADII[part]
    assert isinstance(f, FlankShape)
    assert f.half_width(f.pitch_radius, Q) == pytest.approx(Q, abs=1e-15)   # delta = 0 at the pitch radius
    h = 1e-5
    fd_slope = (f.half_width(r + h, Q) - f.half_width(r - h, Q)) / (2 * h)
    fd_curv = (f.half_width(r + h, Q) - 2 * f.half_width(r, Q) + f.half_width(r - h, Q)) / h ** 2
    assert np.allclose(f.slope(r), fd_slope, atol=1e-8)
    assert np.allclose(f.curvature(r), fd_curv, atol=2e-4)
    assert np.allclose(f.radius_at_half_width(f.half_width(r, Q), Q), r, atol=1e-12)
    pts = f.point(r, Q)
    assert np.allclose(pts[:, 0], f.half_width(r, Q)) and np.allclose(pts[:, 1], r)
    n = f.normal(r)
    tangent = np.stack([f.slope(r), np.ones_like(r)], axis=-1)      # d(x, r)/dr
    assert np.allclose(np.einsum("ij,ij->i", n, tangent), 0.0, atol=1e-12)
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0)
    assert np.all(n[:, 0] > 0)        # the upper flank's normal points away from the tooth (+x)


def test_arc_flank_is_the_circle_about_the_axis():
    f = FLANKS["roller"]
    r = RADII["roller"]
    # every point lies on a circle of radius r_T centred on the axis at x_c = Q - sqrt(rT^2 - r0^2)
    xc = Q - math.sqrt(f.arc_radius ** 2 - f.pitch_radius ** 2)
    pts = f.point(r, Q)
    assert np.allclose(np.hypot(pts[:, 0] - xc, pts[:, 1]), f.arc_radius, atol=1e-12)
    # and its normal is the circle's radial direction
    assert np.allclose(f.normal(r), (pts - [xc, 0.0]) / f.arc_radius, atol=1e-12)
    up, lo = f.normal_outline(Q, r[0], r[-1])
    assert isinstance(up, CircleArc) and up.centre == pytest.approx((xc, 0.0)) and up.radius == f.arc_radius
    assert lo.centre == pytest.approx((-xc, 0.0))
    # the sampled radii meet the chord tolerance on the circle
    chord = 1e-4
    radii = f.sample_radii(r[0], r[-1], 1, chord)
    phi = np.arcsin(radii / f.arc_radius)
    sagitta = f.arc_radius * (1 - np.cos(np.diff(phi) / 2))
    assert sagitta.max() <= chord * (1 + 1e-9) and radii[0] == r[0] and radii[-1] == r[-1]


def test_straight_flank_outline_and_moment():
    f = FLANKS["screw"]
    lo, up = f.normal_outline(Q, 11.2, 12.3)
    assert isinstance(lo, Segment) and lo.kind == "flank_lower" and up.kind == "flank_upper"
    assert up.start == pytest.approx((float(f.half_width(12.3, Q)), 12.3))
    # radial moment = integral of r^2 |delta'| dr, against a quadrature
    rr = np.linspace(11.2, 12.3, 20001)
    ref = np.trapezoid(rr ** 2 * np.abs(f.slope(rr)), rr)
    assert f.radial_moment(11.2, 12.3) == pytest.approx(ref, rel=1e-8)
    a = FLANKS["roller"]
    rr = np.linspace(3.6, 4.3, 200001)
    assert a.radial_moment(3.6, 4.3) == pytest.approx(np.trapezoid(rr ** 2 * np.abs(a.slope(rr)), rr), rel=1e-7)


def test_profiles_refer_their_flank_to_their_pitch_radius_and_match_the_model_rule():
    d = default_design()
    prof = ThreadProfiles.from_design(d)
    assert isinstance(prof.roller.flank, ArcFlank) and isinstance(prof.screw.flank, StraightFlank)
    from dataclasses import replace
    corrected = replace(prof.screw, pitch_radius=11.9, lead_radius=prof.screw.pitch_radius)
    assert corrected.flank.pitch_radius == 11.9
    # the model's width rule (its own numbers) agrees with the profile objects
    widths = d.normal_half_widths()
    for part in ("screw", "roller", "nut"):
        p = getattr(prof, part)
        crest = float(p.tooth_half_width(p.crest_radius)) * p.cos_lead
        root_groove = (0.5 * p.pitch - float(p.tooth_half_width(p.root_radius))) * p.cos_lead
        assert widths[part][0] == pytest.approx(crest, rel=1e-12)
        assert widths[part][1] == pytest.approx(root_groove, rel=1e-12)
