import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from prs_geom.model.design import default_design
from prs_geom.geometry.profiles import ThreadProfiles
from strategies import standard_designs


@settings(max_examples=30)
@given(standard_designs(), st.floats(0.0, 1.0))
def test_radius_at_half_width_inverts_tooth_half_width(d, frac):
    for pr in ThreadProfiles.from_design(d):
        r = pr.inner_radius + frac * (pr.outer_radius - pr.inner_radius)
        t = pr.tooth_half_width(r)
        assert pr.radius_at_half_width(t) == pytest.approx(r, abs=1e-12)


def test_profile_formulas_match_domain_section_1():
    d = default_design()
    prof = ThreadProfiles.from_design(d)
    p, beta = 2.0, math.radians(45)
    s = prof.screw
    lam = math.atan(10.0 / (2 * math.pi * 12.0))
    assert s.lead_angle == pytest.approx(lam, rel=1e-15)
    r = 12.2
    groove = p * math.cos(lam) / 4 + math.tan(beta) * (r - 12.0)  # DOMAIN h_s, normal section
    assert s.tooth_half_width(r) == pytest.approx((p * math.cos(lam) / 2 - groove) / math.cos(lam), rel=1e-14)
    n = prof.nut
    lam_n = math.atan(10.0 / (2 * math.pi * 20.0))
    groove_n = p * math.cos(lam_n) / 4 - math.tan(beta) * (r + 8 - 20.0)
    assert n.tooth_half_width(r + 8) == pytest.approx((p * math.cos(lam_n) / 2 - groove_n) / math.cos(lam_n), rel=1e-14)
    ro = prof.roller
    lam_r = math.atan(2.0 / (2 * math.pi * 4.0))
    rt = 4 * math.sqrt(2)
    h = p * math.cos(lam_r) / 4 + math.sqrt(rt**2 - 4.1**2) - math.sqrt(rt**2 - 16)
    assert ro.tooth_half_width(4.1) == pytest.approx(h / math.cos(lam_r), rel=1e-14)
    # nut and roller lead angles are equal in standard sizing
    assert n.lead_angle == pytest.approx(ro.lead_angle, rel=1e-15)


def test_radius_at_offset_traces_root_flank_crest():
    pr = ThreadProfiles.from_design(default_design()).screw
    u = np.linspace(-1.0, 1.0, 2001)
    r = pr.radius_at_offset(u)
    assert r.max() == pytest.approx(pr.crest_radius) and r.min() == pytest.approx(pr.root_radius)
    # periodic with the pitch, symmetric about the tooth mid-plane
    np.testing.assert_allclose(pr.radius_at_offset(u + 2.0), r, atol=1e-12)
    np.testing.assert_allclose(pr.radius_at_offset(-u), r, atol=1e-12)
    # on the flank it is the inverse of the half-width
    uf = 0.5 * (pr.tooth_half_width(pr.crest_radius) + pr.tooth_half_width(pr.root_radius))
    assert pr.tooth_half_width(pr.radius_at_offset(uf)) == pytest.approx(uf, abs=1e-14)
