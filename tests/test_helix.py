import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from prs_geom.geometry.helix import PitchWarp, identity_warp


lists = st.integers(2, 25).flatmap(
    lambda n: st.lists(st.floats(-2e-3, 2e-3), min_size=n - 1, max_size=n - 1).map(
        lambda d: tuple(2.0 + x for x in d)))


@settings(max_examples=50)
@given(lists, st.floats(-5, 5))
def test_warp_puts_knots_at_listed_pitches(pl, first):
    w = PitchWarp(first, 2.0, pl)
    z = w(w.knots)
    # W(m_{j+1}) - W(m_j) = p_j; differences of nearby numbers: compare to 1e-12 mm
    np.testing.assert_allclose(np.diff(z), pl, atol=1e-12, rtol=0)
    assert z[0] == pytest.approx(first, abs=1e-15)


@settings(max_examples=50)
@given(lists, st.floats(-5, 60))
def test_warp_is_monotone_c1_and_invertible(pl, m):
    w = PitchWarp(0.7, 2.0, pl)
    mm = np.linspace(-10, 60, 20001)
    W = w(mm)
    assert np.all(np.diff(W) > 0)
    # C1: slope continuous across knots (compare left/right numerical derivatives)
    h = 1e-7
    for k in w.knots:
        left = (w(k) - w(k - h)) / h
        right = (w(k + h) - w(k)) / h
        assert left == pytest.approx(right, abs=1e-5)
    assert w.inverse(w(m)) == pytest.approx(m, abs=1e-12)
    # slope agrees with finite differences
    d = (w.correction(m + 1e-6) - w.correction(m - 1e-6)) / 2e-6
    assert w.correction_slope(m) == pytest.approx(d, abs=1e-6)


def test_identity_and_constant_lists():
    assert identity_warp(2.0).is_identity
    w = PitchWarp(0.0, 2.0, (2.0,) * 5)
    assert w.is_identity
    np.testing.assert_array_equal(w(np.array([1.0, 3.0])), [1.0, 3.0])


def test_linear_extrapolation_outside_knots():
    w = PitchWarp(1.0, 2.0, (2.001, 2.002, 2.003))
    s_end = w.correction_slope(w.knots[-1])
    x = w.knots[-1] + 5.0
    assert w.correction(x) == pytest.approx(w.knot_corrections[-1] + 5.0 * s_end, abs=1e-15)
