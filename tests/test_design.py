import math
import warnings

import pytest
from hypothesis import given, settings

from prs_geom.model.design import (MAX_PITCH_DEVIATION, Nut, PRSDesign, Roller, Screw, Thread,
                             default_design)
from prs_geom.model.errors import DesignError, DesignWarning
from prs_geom.geometry.profiles import ThreadProfiles
from strategies import standard_designs


def test_default_design_is_the_documented_standard_prs():
    d = default_design()
    assert (d.screw.pitch_diameter_mm, d.roller.pitch_diameter_mm, d.nut.pitch_diameter_mm) == (24, 8, 40)
    assert d.screw.starts == d.nut.starts == 5
    assert d.roller.count == 10 and d.thread.engaged_teeth == 20
    assert d.centre_distance_mm == 16.0
    assert d.sizing_warnings() == []
    # r_T defaults to r_r / sin(beta): tangent to the 45 deg flank at the pitch radius
    assert d.roller.arc_radius_mm == pytest.approx(4.0 * math.sqrt(2.0), rel=1e-15)
    # truncation: 0.6 / 0.8 of the sharp-V half depth p / (4 tan beta) = 0.5 mm
    assert d.screw.major_diameter_mm == pytest.approx(24.6)
    assert d.screw.minor_diameter_mm == pytest.approx(23.2)
    assert d.nut.major_diameter_mm == pytest.approx(40.8)
    assert d.nut.minor_diameter_mm == pytest.approx(39.4)


def test_roller_arc_is_tangent_to_beta_flank_at_pitch_radius():
    prof = ThreadProfiles.from_design(default_design())
    # axial-section slope dt/dr = -tan(beta)/cos(lambda) at r_r, the straight-flank value
    r = prof.roller
    assert r.tooth_half_width_slope(r.pitch_radius) == pytest.approx(-1.0 / r.cos_lead, rel=1e-12)
    # at the pitch radius all tooth half-widths are p/4 in the axial section
    for pr in prof:
        assert pr.tooth_half_width(pr.pitch_radius) == pytest.approx(0.5, abs=1e-15)


def test_sizing_relations_are_warnings_not_errors():
    d = PRSDesign(nut=Nut(pitch_diameter_mm=40.2, outer_diameter_mm=56.0))
    msgs = d.sizing_warnings()
    assert any("pitch circles do not touch" in m for m in msgs)
    assert any("drift" in m for m in msgs)
    with pytest.warns(DesignWarning):
        d.warn()


@pytest.mark.parametrize("kwargs, field, rule", [
    (dict(thread=Thread(engaged_teeth=5), roller=Roller(pitch_list_mm=(2.0, 2.0))),
     "roller.pitch_list_mm", "engaged_teeth - 1 = 4 entries"),
    (dict(roller=Roller(pitch_list_mm=(2.0,) * 18 + (2.1,))), "roller.pitch_list_mm[18]", "within 2%"),
    (dict(roller=Roller(count=12)), "roller.count", "overlap"),
    (dict(roller=Roller(arc_radius_mm=4.2)), "roller.arc_radius_mm", "crest radius"),
    (dict(screw=Screw(major_diameter_mm=25.0), roller=Roller(minor_diameter_mm=6.9)),
     "screw.major_diameter_mm", "tooth comes to a point"),
    (dict(screw=Screw(major_diameter_mm=24.9)), "screw.major_diameter_mm", "crest would hit the roller root"),
    (dict(screw=Screw(length_mm=30.0)), "screw.length_mm", "engaged length"),
    (dict(nut=Nut(outer_diameter_mm=40.5)), "nut.outer_diameter_mm", "must exceed"),
    (dict(screw=Screw(major_diameter_mm=23.0)), "screw.pitch_diameter_mm", "strictly between"),
])
def test_cross_field_rules_name_field_and_rule(kwargs, field, rule):
    with pytest.raises(DesignError) as exc:
        PRSDesign(**kwargs)
    assert exc.value.field == field
    assert rule in exc.value.rule
    assert field in str(exc.value)


def test_pitch_deviation_limit_is_relative_to_pitch():
    ok = PRSDesign(roller=Roller(pitch_list_mm=(2.0 * (1 + 0.99 * MAX_PITCH_DEVIATION),) * 19))
    assert ok.pitch_list("roller")[0] > 2.0
    assert ok.pitch_list("nut") == (2.0,) * 19
    assert ok.pitch_list("screw") == (2.0,) * 19


@settings(max_examples=40)
@given(standard_designs(pitch_lists=True))
def test_sampled_standard_designs_validate_without_warnings(d):
    with warnings.catch_warnings():
        warnings.simplefilter("error", DesignWarning)
        d.warn()
    prof = ThreadProfiles.from_design(d)
    for pr in prof:
        assert pr.tooth_half_width_at_crest() > 0
        assert pr.groove_half_width_at_root() > 0
