"""Load distribution and equal-load pitch design (issue 5)."""
import json
import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cli_helpers import run
from prs_geom.design import Loading, default_design
from prs_geom.designio import load_design
from prs_geom.errors import ConvergenceError
from prs_geom.loads import (build_model, closed_form_equal_load, design_pitches, ellipticity, forward,
                            gap_terms, hertz_constant, loads_report, solve_loads, with_pitch_lists,
                            yamamoto_compliance)
from strategies import standard_designs




@settings(max_examples=15, deadline=None)
@given(standard_designs(max_teeth=25), st.sampled_from(["tension-compression", "compression-compression"]))
def test_designed_pitches_give_equal_load_in_forward_model(d, installation):
    d = d.with_changes(loading=replace(d.loading, installation=installation))
    model = build_model(d)
    pd = design_pitches(d, model=model)
    graded = with_pitch_lists(d, pd)
    r = forward(graded, model=model)
    assert np.abs(r.ldc_nr - 1).max() < 1e-6
    assert np.abs(r.ldc_rs - 1).max() < 1e-6
    # and the corrections are the closed form of DOMAIN.md section 4 (body strain only)
    cr, cn = closed_form_equal_load(d)
    p = d.thread.pitch_mm
    np.testing.assert_allclose(np.array(pd.roller_mm) - p, cr, atol=1e-13, rtol=0)
    np.testing.assert_allclose(np.array(pd.nut_mm) - p, cn, atol=1e-13, rtol=0)


def test_closed_form_magnitudes_of_domain_check():
    """DOMAIN.md Appendix A: 24/8/40, D0 56, 20 kN: screw body ~0.46 um and nut body ~0.17 um
    per pitch at full load; cumulative corrections a few um."""
    d = default_design()
    cr, cn = closed_form_equal_load(d)
    n = d.thread.engaged_teeth
    screw_per_pitch = cr[0] * n / (n - 1)          # F0 p / (E A_s)
    nut_per_pitch = (cn[0] - cr[0]) * n / (n - 1)  # F0 p / (E A_n)
    assert screw_per_pitch * 1e3 == pytest.approx(0.46, abs=0.03)
    assert nut_per_pitch * 1e3 == pytest.approx(0.17, abs=0.02)
    assert 2.0 < np.sum(cn) * 1e3 < 10.0


def test_constant_pitch_worst_tooth_is_clearly_above_one():
    rep = loads_report(default_design())
    assert rep["max_ldc"] > 1.2
    assert rep["ldc_roller_screw"][0] == pytest.approx(rep["max_ldc"])
    assert sum(rep["ldc_nut_roller"]) == pytest.approx(20.0, rel=1e-12)
    assert sum(rep["ldc_roller_screw"]) == pytest.approx(20.0, rel=1e-12)
    # tension-compression: both sides load the teeth at the loaded end most
    assert np.all(np.diff(rep["ldc_roller_screw"]) < 0)
    assert rep["axial_stiffness"]["tangent_N_per_um"] > rep["axial_stiffness"]["secant_N_per_um"] > 0


def test_forward_solution_satisfies_domain_compatibility_written_tooth_by_tooth():
    """Second formulation: segment forces and the two difference equations of DOMAIN.md
    section 4 evaluated with explicit sums."""
    for inst in ("tension-compression", "compression-compression"):
        d = load_design(__import__("pathlib").Path(__file__).parent.parent / "examples" / "graded-pitch.toml")
        d = d.with_changes(loading=Loading(axial_load_n=13000.0, installation=inst))
        m = build_model(d)
        r = forward(d, model=m)
        fn, fr = r.f_nr, r.f_rs
        n, z, p = m.n, m.z, m.pitch
        pr, pn, ps = d.pitch_list("roller"), d.pitch_list("nut"), p
        for j in range(n - 1):
            Nn = z * sum(fn[j + 1:])
            Nr = sum(fn[j + 1:]) - sum(fr[j + 1:])
            Ns = z * sum(fr[j + 1:]) if inst == "tension-compression" else z * sum(fr[:j + 1])
            s = 1 if inst == "tension-compression" else -1
            lhs_n = m.deflection("nr", fn[j]) - m.deflection("nr", fn[j + 1])
            rhs_n = Nn * m.body_nut + Nr * m.body_roller + (pr[j] - pn[j])
            lhs_s = m.deflection("rs", fr[j]) - m.deflection("rs", fr[j + 1])
            rhs_s = s * Ns * m.body_screw - Nr * m.body_roller + (ps - pr[j])
            assert lhs_n == pytest.approx(rhs_n, abs=1e-13)
            assert lhs_s == pytest.approx(rhs_s, abs=1e-13)
        assert fn.sum() * z == pytest.approx(13000.0, rel=1e-13)
        assert fr.sum() * z == pytest.approx(13000.0, rel=1e-13)


def test_linear_and_nonlinear_agree_at_small_loads_only():
    d = default_design()
    m = build_model(d)
    for load in (0.2, 2.0, 20.0):
        small = forward(d, load, m)
        lin = forward(d, load, m, linear_at=small.mean)
        diff = max(np.abs(lin.ldc_nr - small.ldc_nr).max(), np.abs(lin.ldc_rs - small.ldc_rs).max())
        spread = max(np.abs(small.ldc_nr - 1).max(), np.abs(small.ldc_rs - 1).max())
        # the tangent model is second-order accurate in the load spread
        assert diff < 0.2 * spread ** 2
    assert diff < 5e-4
    big = forward(d, 20000.0, m)
    linb = forward(d, 20000.0, m, linear_at=big.mean)
    assert np.abs(linb.ldc_rs - big.ldc_rs).max() > 1e-3


def test_hertz_sphere_on_flat_matches_closed_form():
    """Sphere of radius R on a plane: delta = (9 Q^2 / (16 R E*^2))^(1/3), 1/E* = eta."""
    R, eta = 5.0, 2 * (1 - 0.3 ** 2) / 212000.0
    C, info = hertz_constant((1 / R, 1 / R, 0.0, 0.0), eta)
    assert info["ellipticity_k"] == 1.0
    assert C == pytest.approx((9.0 / (16.0 * R)) ** (1 / 3) * eta ** (2 / 3), rel=1e-9)


def test_ellipticity_solves_the_defining_equation():
    from scipy import special
    for F in (0.05, 0.3, 0.7, 0.95):
        k = ellipticity(F)
        m = 1 - 1 / k ** 2
        E, K = special.ellipe(m), special.ellipk(m)
        assert ((k * k + 1) * E - 2 * K) / ((k * k - 1) * E) == pytest.approx(F, abs=1e-12)
        assert k > 1


def test_yamamoto_terms_against_hand_evaluation():
    a, b, c = 1.5, 0.9, 0.3   # a = b + 2 c tan(45 deg)
    ext = yamamoto_compliance(math.radians(45), a, b, c, 2.0, 40.0, 212000.0, 0.3)
    nut = yamamoto_compliance(math.radians(45), a, b, c, 2.0, 40.0, 212000.0, 0.3, nut_outer=56.0)
    E = 212000.0
    assert ext["shear"] == pytest.approx(1.3 * 6 / (5 * E) * math.log(a / b), rel=1e-12)
    assert ext["radial"] == pytest.approx(0.7 * 0.5 * 20.0 / E, rel=1e-12)
    assert nut["radial"] == pytest.approx(((56 ** 2 + 40 ** 2) / (56 ** 2 - 40 ** 2) + 0.3) * 0.5 * 20.0 / E, rel=1e-12)
    # at 45 deg flanks the bending bracket of Appendix A is negative (its cot^3 term no
    # longer dominates); the total compliance stays positive
    assert ext["bending"] < 0 < sum(ext.values())


def test_target_distribution_is_reproduced():
    d = default_design()
    n = d.thread.engaged_teeth
    ramp = 1.0 + 0.2 * (np.arange(n) - (n - 1) / 2) / (n - 1)
    m = build_model(d)
    pd = design_pitches(d, ramp, ramp[::-1].copy(), model=m)
    r = forward(with_pitch_lists(d, pd), model=m)
    np.testing.assert_allclose(r.ldc_nr, ramp, atol=1e-6)
    np.testing.assert_allclose(r.ldc_rs, ramp[::-1], atol=1e-6)


def test_teeth_lose_contact_instead_of_pulling():
    d = default_design()
    m = build_model(d)
    p = d.thread.pitch_mm
    pr = np.full(19, p)
    pr[9] += 0.01  # a 10 um pitch error: teeth 11..20 of the roller move away from the screw
    r = forward(d, 2000.0, m, roller=pr)
    assert np.all(r.f_rs >= 0) and np.all(r.f_nr >= 0)
    assert (~r.active_rs).sum() > 0
    assert np.all(r.f_rs[~r.active_rs] == 0)
    assert r.f_rs.sum() * m.z == pytest.approx(2000.0, rel=1e-12)


def test_non_convergence_raises():
    d = default_design()
    m = build_model(d)
    g_nr, g_rs = gap_terms(d)
    with pytest.raises(ConvergenceError):
        solve_loads(m, 20000.0, g_nr, g_rs, max_iter=1)


def test_design_pitch_cli_writes_buildable_design(tmp_path):
    out = tmp_path / "new.toml"
    code, _, err = run(["design-pitch", "--out", str(out)])
    assert code == 0 and out.exists()
    d = load_design(out)
    assert d.name == "default-graded"
    r = forward(d)
    assert np.abs(r.ldc_nr - 1).max() < 1e-6 and np.abs(r.ldc_rs - 1).max() < 1e-6
    # a target file
    n = 20
    tgt = tmp_path / "t.json"
    ramp = list(1.0 + 0.1 * (np.arange(n) - 9.5) / 19)
    tgt.write_text(json.dumps({"nut_roller": ramp, "roller_screw": [1.0] * n}))
    code, text, _ = run(["design-pitch", "--target", str(tgt)])
    assert code == 0 and "pitch_list_mm" in text


@pytest.mark.parametrize("content, field", [
    ('{"nut_roller": [1.0], "roller_screw": [1.0]}', "target.nut_roller"),
    ('{"nut_roller": ' + json.dumps([1.0] * 20) + ', "roller_screw": ' + json.dumps([2.0] * 20) + "}",
     "target.roller_screw"),
    ("not json", "--target"),
])
def test_design_pitch_bad_target_exit_2(tmp_path, content, field):
    tgt = tmp_path / "t.json"
    tgt.write_text(content)
    out = tmp_path / "new.toml"
    code, _, err = run(["design-pitch", "--target", str(tgt), "--out", str(out)])
    assert code == 2 and err.startswith(f"error: {field}")
    assert not out.exists()


def test_loads_cli_table_and_json():
    code, out, _ = run(["loads", "--json"])
    rep = json.loads(out)
    assert code == 0 and rep["design_load_N"] == 20000.0 and len(rep["ldc_nut_roller"]) == 20
    code, out, _ = run(["loads", "--load", "5000"])
    assert code == 0 and "5000 N" in out
    code, _, err = run(["loads", "--load", "-3"])
    assert code == 2 and "--load" in err
