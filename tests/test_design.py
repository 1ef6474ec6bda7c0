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


# --------------------------------------------------------------------------- issue 28: derived values, plausibility
@pytest.mark.parametrize("kwargs, field, value, words", [
    # 2000 mm pitch: H = 2000 / (4 tan 45) = 500 mm, root 24 - 1.6 x 500 = -776 mm
    (dict(thread=Thread(pitch_mm=2000.0)), "screw.minor_diameter_mm", -776.0,
     ("screw minor (root) diameter must be > 0", "thread.pitch_mm = 2000.0", "H = thread.pitch_mm / (4 tan "
      "thread.flank_half_angle_deg) = 500 mm", "screw.pitch_diameter_mm - 1.6 H = 24.0 - 1.6 H",
      "reduce thread.pitch_mm")),
    # 40 mm pitch: H = 10 mm; the screw root 24 - 16 = 8 mm holds, the roller's 8 - 16 = -8 mm does not
    (dict(thread=Thread(pitch_mm=40.0)), "roller.minor_diameter_mm", -8.0,
     ("roller minor (root) diameter must be > 0", "thread.pitch_mm = 40.0", "= 10 mm")),
    # the nut bore: 40 - 1.2 H < 0 needs H > 33.3: pitch 140 (H = 35, screw root 24 - 56 < 0 first)
    (dict(thread=Thread(pitch_mm=140.0)), "screw.minor_diameter_mm", 24.0 - 1.6 * 35.0,
     ("screw minor (root) diameter", "thread.pitch_mm = 140.0")),
])
def test_a_derived_dimension_error_names_part_formula_and_source(kwargs, field, value, words):
    with pytest.raises(DesignError) as exc:
        PRSDesign(**kwargs)
    assert exc.value.field == field and exc.value.value == pytest.approx(value)
    text = str(exc.value)
    assert text.startswith(f"{field} = ") and "not in the design file: the default" in text
    for w in words:
        assert w in text, (w, text)


def test_cross_part_rules_state_the_derived_value_and_its_sources():
    # tooth half-width at the screw crest p cos(lambda) / 4 - tan(beta) (r_major - r_pitch):
    # 2 cos(atan(10 / (24 pi))) / 4 - (12.5 - 12) = -0.00434 mm (lambda = 7.555 deg)
    lam = math.atan(10.0 / (24.0 * math.pi))
    crest = 2.0 * math.cos(lam) / 4.0 - 0.5
    with pytest.raises(DesignError) as exc:
        PRSDesign(screw=Screw(major_diameter_mm=25.0), roller=Roller(minor_diameter_mm=6.9))
    text = str(exc.value)
    assert f"= {crest:.4g} mm" in text and "-0.00434" in text
    assert "the screw tooth comes to a point" in text and "thread.pitch_mm = 2.0" in text
    assert f"= {math.degrees(lam):.4g} deg" in text
    # the centre distance a = (24 + 8) / 2 = 16 mm and the fields it comes from
    with pytest.raises(DesignError) as exc:
        PRSDesign(screw=Screw(major_diameter_mm=24.9))
    assert "(screw.pitch_diameter_mm + roller.pitch_diameter_mm) / 2 = (24.0 + 8.0) / 2 = 16.0 mm" in str(exc.value)
    assert "12.45 + 3.6 mm" in str(exc.value)
    with pytest.raises(DesignError) as exc:
        PRSDesign(roller=Roller(count=12))
    # 2 a sin(pi / 12) = 32 sin(15 deg) = 8.282 mm < 8.6 mm
    assert f"= {32.0 * math.sin(math.pi / 12):.4g} mm" in str(exc.value) and "8.6 mm" in str(exc.value)


def test_required_static_safety_default_bounds_and_file():
    from prs_geom.model.design import DEFAULT_REQUIRED_STATIC_SAFETY, RatingSettings
    from prs_geom.model.io import dumps_toml, loads_toml

    assert RatingSettings().required_static_safety == DEFAULT_REQUIRED_STATIC_SAFETY == 2.0
    assert RatingSettings(required_static_safety=1).required_static_safety == 1.0
    assert RatingSettings(required_static_safety=20.0).required_static_safety == 20.0
    for bad, rule in ((0.99, "from 1 to 20"), (20.5, "from 1 to 20"), (float("nan"), "finite"), ("2", "number"),
                      (True, "number")):
        with pytest.raises(DesignError) as exc:
            RatingSettings(required_static_safety=bad)
        assert exc.value.field == "required_static_safety" and rule in exc.value.rule
    d = loads_toml("[rating]\nrequired_static_safety = 5\n")
    assert d.rating.required_static_safety == 5.0 and loads_toml(dumps_toml(d)) == d
    with pytest.raises(DesignError) as exc:
        loads_toml("[rating]\nrequired_static_safety = 0.5\n")
    assert exc.value.field == "rating.required_static_safety"


def test_roller_drift_per_screw_turn_by_hand():
    from prs_geom.analysis.kinematics import speed_ratios
    from prs_geom.model.plausibility import DRIFT_TOLERANCE_MM, drift_warning, roller_drift_per_screw_turn_mm

    d = default_design()
    assert roller_drift_per_screw_turn_mm(d) == 0.0 and drift_warning(d) is None
    # equals the kinematics module on a design it accepts
    assert roller_drift_per_screw_turn_mm(d) == pytest.approx(speed_ratios(d).roller_drift_per_turn_mm, abs=1e-15)
    # 4 starts on 24/8/40: h p (r_s / (r_s + r_n)) (n_n - r_n / r_r) = 2 x 12/32 x (4 - 5) = -0.75 mm
    four = PRSDesign(screw=Screw(starts=4), nut=Nut(starts=4))
    assert roller_drift_per_screw_turn_mm(four) == pytest.approx(-0.75, rel=1e-15)
    assert "drift axially by -0.75 mm per screw turn" in drift_warning(four)
    assert "nut.pitch_diameter_mm must equal nut.starts x roller.pitch_diameter_mm = 32" in drift_warning(four)
    left = PRSDesign(thread=Thread(hand="left"), screw=Screw(starts=4), nut=Nut(starts=4))
    assert roller_drift_per_screw_turn_mm(left) == pytest.approx(0.75, rel=1e-15)
    # screw starts alone differing (n_s = 4, n_n = 5, r_n = n_n r_r): a sizing warning, no drift
    mixed = PRSDesign(screw=Screw(starts=4))
    assert mixed.sizing_warnings() and drift_warning(mixed) is None
    # a nut 1e-7 mm off the relation drifts 2 x 12/32.00000005 x (5e-9 / 4) ~ 1e-9 mm: inside the tolerance
    near = PRSDesign(nut=Nut(pitch_diameter_mm=40.0 + 1e-7))
    assert 0 < abs(roller_drift_per_screw_turn_mm(near)) < DRIFT_TOLERANCE_MM and drift_warning(near) is None


def test_plausible_ranges_flag_unit_slips_only():
    from prs_geom.model.design import Loading, Materials, Material, RatingSettings
    from prs_geom.model.plausibility import MAX_ROOT_STRESS_MPA, PLAUSIBLE_RANGES, plausibility_warnings

    assert plausibility_warnings(default_design()) == []
    assert 10 <= len(PLAUSIBLE_RANGES) <= 20
    for path, rng in PLAUSIBLE_RANGES.items():
        assert rng.reason and (rng.low is None or rng.high is None or rng.low < rng.high), path
    w = plausibility_warnings(PRSDesign(thread=Thread(pitch_mm=0.05)))
    assert w[0].startswith("thread.pitch_mm = 0.05 is below the plausible minimum 0.1 mm: ") and "metres" in w[0]
    w = plausibility_warnings(PRSDesign(rating=RatingSettings(speed_rpm=30000.0)))
    assert w == [w[0]] and w[0].startswith("rating.speed_rpm = 30000.0 is above the plausible maximum 20000 rpm")
    steel_gpa = Material(youngs_modulus_mpa=2100.0)          # 210 GPa typed as 2.1 GPa
    w = plausibility_warnings(PRSDesign(materials=Materials(screw=steel_gpa)))
    assert len(w) == 1 and w[0].startswith("materials.screw.youngs_modulus_mpa = 2100.0 is below the plausible "
                                           "minimum 50000 MPa")
    # 2e6 N on the 23.2 mm root: 2e6 / (pi 23.2^2 / 4) = 4731 MPa > 1500 MPa (and below 1e7 N)
    w = plausibility_warnings(PRSDesign(loading=Loading(axial_load_n=2e6)))
    stress = 2e6 / (math.pi * 23.2 ** 2 / 4)
    assert len(w) == 1 and f"to {stress:.4g} MPa" in w[0] and stress > MAX_ROOT_STRESS_MPA
    # the limits themselves are plausible
    assert plausibility_warnings(PRSDesign(thread=Thread(pitch_mm=0.1, engaged_teeth=20))) == []
