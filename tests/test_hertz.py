"""Hertz point contact (prs_geom.analysis.hertz) against published closed forms."""
from __future__ import annotations

import math

import pytest
from scipy import special

from prs_geom.analysis.hertz import ellipticity, hertz_contact

ETA = 2 * (1 - 0.3 ** 2) / 212000.0          # two steel bodies, 1/MPa (= 1 / E*)


def test_ellipticity_solves_the_defining_equation():
    for F in (0.05, 0.3, 0.7, 0.95):
        k = ellipticity(F)
        m = 1 - 1 / k ** 2
        E, K = special.ellipe(m), special.ellipk(m)
        assert ((k * k + 1) * E - 2 * K) / ((k * k - 1) * E) == pytest.approx(F, abs=1e-12)
        assert k > 1
    assert ellipticity(0.0) == 1.0


@pytest.mark.parametrize("R, Q", [(5.0, 150.0), (0.8, 3.0), (40.0, 20000.0)])
def test_sphere_on_a_plane(R, Q):
    """Johnson, Contact Mechanics (1985), section 4.2: a = (3 Q R / (4 E*))^(1/3),
    delta = a^2 / R."""
    c = hertz_contact((1 / R, 1 / R, 0.0, 0.0), ETA)
    a_ref = (3 * Q * R * ETA / 4) ** (1 / 3)
    assert c.ellipticity == 1.0
    assert c.semi_axes(Q) == pytest.approx((a_ref, a_ref), rel=1e-13)
    assert c.approach(Q) == pytest.approx(a_ref ** 2 / R, rel=1e-13)


def test_crossed_equal_cylinders_are_a_sphere_on_a_plane():
    """Two cylinders of radius R with axes crossed at right angles touch in a circle, as a
    sphere of radius R on a plane (Johnson, Contact Mechanics, section 4.2); the curvature
    difference is that of the sum over both bodies, not of each body's own difference."""
    R, Q = 6.0, 500.0
    c = hertz_contact((1 / R, 0.0, 0.0, 1 / R), ETA)
    a_ref = (3 * Q * R * ETA / 4) ** (1 / 3)
    assert c.curvature_difference == 0.0 and c.ellipticity == 1.0
    assert c.semi_axes(Q) == pytest.approx((a_ref, a_ref), rel=1e-13)
    assert c.approach(Q) == pytest.approx(a_ref ** 2 / R, rel=1e-13)


@pytest.mark.parametrize("a, b", [(1.0, 0.8), (1.0, 0.3), (2.5, 0.1)])
def test_elliptical_contact_matches_johnson(a, b):
    """Johnson, Contact Mechanics (1985), section 3.5: for the ellipsoidal pressure of peak
    p0 on the ellipse with semi-axes a > b, e^2 = 1 - b^2 / a^2, the gap coefficients are
    A = p0 b (K - E) / (E* e^2 a^2), B = p0 b ((a/b)^2 E - K) / (E* e^2 a^2), the approach
    delta = p0 b K / E* and the load P = 2 pi a b p0 / 3. Curvature sums 2A (plane 1, along
    a) and 2B (plane 2) with load P must give back a, b and delta."""
    p0, e_star = 1500.0, 1.0 / ETA
    e2 = 1 - (b / a) ** 2
    K, E = special.ellipk(e2), special.ellipe(e2)
    A = p0 * b * (K - E) / (e_star * e2 * a * a)
    B = p0 * b * ((a / b) ** 2 * E - K) / (e_star * e2 * a * a)
    delta = p0 * b * K / e_star
    P = 2 * math.pi * a * b * p0 / 3
    # the sums split unevenly over both bodies: only the plane sums matter
    c = hertz_contact((1.2 * A, 0.5 * B, 0.8 * A, 1.5 * B), ETA)
    assert c.major_in_plane_1
    assert c.plane_2_semi_axis_per_cbrt_n == c.semi_minor_per_cbrt_n
    assert c.ellipticity == pytest.approx(a / b, rel=1e-10)
    assert c.semi_axes(P) == pytest.approx((a, b), rel=1e-10)
    assert c.semi_major_per_cbrt_n * P ** (1 / 3) == pytest.approx(a, rel=1e-10)
    assert c.semi_minor_per_cbrt_n * P ** (1 / 3) == pytest.approx(b, rel=1e-10)
    assert c.approach(P) == pytest.approx(delta, rel=1e-10)
    # the same contact turned by 90 degrees
    turned = hertz_contact((0.5 * B, 1.2 * A, 1.5 * B, 0.8 * A), ETA)
    assert not turned.major_in_plane_1
    assert turned.approach_constant == pytest.approx(c.approach_constant, rel=1e-13)


def test_no_contact_without_a_positive_curvature_sum():
    with pytest.raises(ValueError):
        hertz_contact((0.1, 0.1, -0.1, -0.1), ETA)
