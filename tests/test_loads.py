"""Load distribution and equal-load pitch design (issue 5)."""
import json
import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cli_helpers import run
from prs_geom.model.design import Loading, default_design
from prs_geom.model.io import load_design
from prs_geom.model.errors import ConvergenceError
from prs_geom.exports.report import loads_section
from prs_geom.analysis.loads import (build_model, closed_form_equal_load, design_pitches, forward,
                            gap_terms, hertz_constant, load_distribution, solve_loads, with_pitch_lists,
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
    rep = loads_section(load_distribution(default_design()))
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


# --------------------------------------------------------------------------- the complementarity solver
from prs_geom.model.design import PRSDesign, Thread  # noqa: E402
from prs_geom.model.errors import DesignError  # noqa: E402
from prs_geom.exports.report import roller_loads_dict  # noqa: E402
from prs_geom.analysis.loads import (block_compliance, gap_terms_rollers, iteration_bound, off_design,  # noqa: E402
                            pitch_error_sensitivity, sensitivity_chunks, solve_loads_batch, solve_loads_rollers)

INSTALLATIONS = ("tension-compression", "compression-compression")
FRACTIONS = (0.01, 0.25, 1.0, 3.0)


def _design(n, installation="tension-compression"):
    d = PRSDesign(thread=Thread(engaged_teeth=n))
    return d.with_changes(loading=replace(d.loading, installation=installation))


def assert_complementarity(m, load, g_nr, g_rs, r, C=None):
    """The conditions of DOMAIN.md section 4 evaluated independently of the solver: the
    module's original cumulative body matrices (non-symmetric in compression-compression),
    explicit Hertz + tooth deflections, every tooth. Returns the number of open teeth."""
    n, z = m.n, m.z
    Snr, Srs = m.body_matrices()
    f = np.concatenate([r.f_nr, r.f_rs])
    if C is None:
        D = np.concatenate([m.deflection("nr", r.f_nr), m.deflection("rs", r.f_rs)])
    else:
        D = np.concatenate([m.hertz_nr * r.f_nr ** (2 / 3), m.hertz_rs * r.f_rs ** (2 / 3)]) + C @ f
    a = np.concatenate([np.full(n, r.approach_nr_mm), np.full(n, r.approach_rs_mm)])
    w = D + np.concatenate([g_nr, g_rs]) + np.vstack([Snr, Srs]) @ f - a
    scale = max(np.abs(a).max(), float(m.deflection("nr", load / (z * n))))
    active = np.concatenate([r.active_nr, r.active_rs])
    assert np.all(np.isfinite(f)) and np.all(f >= 0)
    assert np.all(f[active] > 0) and np.all(f[~active] == 0)
    assert z * r.f_nr.sum() == pytest.approx(load, rel=1e-12)
    assert z * r.f_rs.sum() == pytest.approx(load, rel=1e-12)
    assert np.abs(w[active]).max() <= 1e-9 * scale          # contact: the gap is closed exactly
    assert np.all(w[~active] >= -1e-12 * scale)              # open tooth: the gap is open
    return int((~active).sum())


def _range_case(n, installation, pitch, strategies, fractions=FRACTIONS):
    d = _design(n, installation)
    m = build_model(d)
    if pitch == "graded":
        d = with_pitch_lists(d, design_pitches(d, model=m))
    g_nr, g_rs = gap_terms(d)
    F0 = d.loading.axial_load_n
    opened = {}
    for fr in fractions:
        ref = None
        for strategy in strategies:
            r = solve_loads(m, fr * F0, g_nr, g_rs, strategy=strategy)
            opened[fr] = assert_complementarity(m, fr * F0, g_nr, g_rs, r)
            assert r.iterations <= iteration_bound()
            if ref is None:
                ref = r
            else:   # the barrier path reaches the same loads as phase 1
                np.testing.assert_allclose(r.f_nr, ref.f_nr, rtol=0, atol=1e-9 * ref.mean)
                np.testing.assert_allclose(r.f_rs, ref.f_rs, rtol=0, atol=1e-9 * ref.mean)
    if pitch == "graded" and n >= 20 and 0.01 in opened:
        assert opened[0.01] > 0          # the graded design at 1 % load: teeth lose contact
    return opened


@pytest.mark.parametrize("n", [2, 3, 20, 100])
@pytest.mark.parametrize("installation", INSTALLATIONS)
@pytest.mark.parametrize("pitch", ["constant", "graded"])
def test_solver_converges_across_documented_range(n, installation, pitch):
    _range_case(n, installation, pitch, ("auto", "barrier"))


@pytest.mark.heavy
@pytest.mark.parametrize("n", [200, 500])
@pytest.mark.parametrize("installation", INSTALLATIONS)
@pytest.mark.parametrize("pitch", ["constant", "graded"])
def test_solver_converges_for_long_engagements(n, installation, pitch, heavy_scale):
    if heavy_scale == "full":
        _range_case(n, installation, pitch, ("auto", "barrier"))
    else:
        _range_case(n, installation, pitch, ("auto",), fractions=(0.01, 3.0))


def test_large_gap_step_opens_teeth_on_both_sides():
    d = _design(100, "compression-compression")
    m = build_model(d)
    p = d.thread.pitch_mm
    pr, pn = np.full(99, p), np.full(99, p)
    pr[39] += 0.02          # 20 um: roller teeth 41.. move away from the nut, toward the screw
    pn[69] -= 0.02          # nut teeth 71.. move away from the roller
    g_nr, g_rs = gap_terms(d, pr, pn)
    opened = []
    for load in (200.0, 20000.0, 60000.0):
        for strategy in ("auto", "barrier"):
            r = solve_loads(m, load, g_nr, g_rs, strategy=strategy)
            opened.append(assert_complementarity(m, load, g_nr, g_rs, r))
            if load == 200.0:   # the load takes the path nut - roller teeth 1..40 - screw teeth 41..100
                assert np.array_equal(r.active_nr, np.arange(100) < 40)
                assert np.array_equal(r.active_rs, np.arange(100) >= 40)
    assert opened[0] == 100 and opened[0] >= opened[2] >= opened[4] > 0   # teeth close as the load grows


def test_active_set_cycling_case_of_the_previous_solver():
    """The Newton/active-set solver this module had raised "tooth-load active set did not
    settle" on these gaps (0.1 um steps per pitch, 200 N); now phase 1 in deflection
    variables converges, and the barrier path agrees."""
    d = default_design()
    m = build_model(d)
    a = [-1, 0, 1, 0, -2, -1, -1, 1, 0, 6, -1, 0, -2, 0, -1, -3, 0, 5, -3]
    b = [-2, 0, 1, 4, -2, 0, -2, -3, -1, -3, 1, 3, -2, -2, 4, -1, 4, -9, -1]
    g0n, g0s = gap_terms(d)
    g_nr = g0n + 1e-4 * np.concatenate([[0], np.cumsum(a)])
    g_rs = g0s + 1e-4 * np.concatenate([[0], np.cumsum(b)])
    r = solve_loads(m, 200.0, g_nr, g_rs)
    assert assert_complementarity(m, 200.0, g_nr, g_rs, r) == 6
    rb = solve_loads(m, 200.0, g_nr, g_rs, strategy="barrier")
    assert rb.barrier and not r.barrier
    np.testing.assert_allclose(rb.f_nr, r.f_nr, rtol=0, atol=1e-10 * r.mean)
    np.testing.assert_allclose(rb.f_rs, r.f_rs, rtol=0, atol=1e-10 * r.mean)


def _perturbed_gaps(d, B, seed, amp_mm=1e-3):
    rng = np.random.default_rng(seed)
    n = d.thread.engaged_teeth
    g_nr, g_rs = gap_terms(d)
    steps = rng.normal(0.0, amp_mm, (2, B, n - 1))
    zero = np.zeros((B, 1))
    return (g_nr + np.hstack([zero, np.cumsum(steps[0], axis=1)]),
            g_rs + np.hstack([zero, np.cumsum(steps[1], axis=1)]))


@pytest.mark.parametrize("installation", INSTALLATIONS)
def test_batch_agrees_with_scalar_solves(installation):
    d = _design(20, installation)
    m = build_model(d)
    B = 40
    G_nr, G_rs = _perturbed_gaps(d, B, seed=3)
    loads = np.linspace(0.01, 3.0, B) * d.loading.axial_load_n
    b = solve_loads_batch(m, loads, G_nr, G_rs)
    assert len(b) == B and b.f_nr.shape == (B, 20) and b.approach_nr_mm.shape == (B,)
    open_teeth = 0
    for i in range(B):
        r = solve_loads(m, loads[i], G_nr[i], G_rs[i])
        np.testing.assert_allclose(b.f_nr[i], r.f_nr, rtol=0, atol=1e-12 * r.mean)
        np.testing.assert_allclose(b.f_rs[i], r.f_rs, rtol=0, atol=1e-12 * r.mean)
        assert b.approach_nr_mm[i] == pytest.approx(r.approach_nr_mm, rel=1e-12)
        assert b.approach_rs_mm[i] == pytest.approx(r.approach_rs_mm, rel=1e-12)
        np.testing.assert_array_equal(b.active_nr[i], r.active_nr)
        np.testing.assert_allclose(b.ldc_rs[i], r.ldc_rs, rtol=1e-12)
        open_teeth += assert_complementarity(m, loads[i], G_nr[i], G_rs[i], b[i])
    assert open_teeth > 0
    # chunks cut by a tiny memory budget give the same numbers
    c = solve_loads_batch(m, loads, G_nr, G_rs, memory_mb=0.05)
    np.testing.assert_array_equal(c.f_nr, b.f_nr)
    np.testing.assert_array_equal(c.approach_rs_mm, b.approach_rs_mm)
    # a scalar load broadcasts, per-sample linearisation points work
    lin = solve_loads_batch(m, 2000.0, G_nr[:3], G_rs[:3], linear_at=np.array([5.0, 10.0, 20.0]))
    r1 = solve_loads(m, 2000.0, G_nr[1], G_rs[1], linear_at=10.0)
    np.testing.assert_allclose(lin.f_rs[1], r1.f_rs, rtol=0, atol=1e-12 * r1.mean)
    # a start point changes the path, not the answer
    s = solve_loads_batch(m, loads, G_nr, G_rs, start=b[0])
    np.testing.assert_allclose(s.f_nr, b.f_nr, rtol=0, atol=1e-11 * b.mean.min())


def test_symmetric_body_operator_is_the_cumulative_body_terms():
    for installation in INSTALLATIONS:
        m = build_model(_design(12, installation))
        K = m.body_operator()
        assert np.array_equal(K, K.T)
        assert np.linalg.eigvalsh(K).min() > -1e-12 * np.abs(K).max()
        S = np.vstack(m.body_matrices())
        f = np.random.default_rng(1).uniform(0.0, 50.0, 24)
        f[12:] *= f[:12].sum() / f[12:].sum()      # equilibrium: sum f_nr = sum f_rs
        F = m.z * f[12:].sum()
        shift = np.zeros(24)
        if installation == "tension-compression":
            np.testing.assert_allclose(S, K, rtol=0, atol=1e-20)
        else:   # z sum_{k<=j} f_rs = F - z sum_{k>j} f_rs: a shift of the gaps
            shift[12:] = -m.body_screw * F * np.arange(12)
        np.testing.assert_allclose(S @ f, K @ f + shift, rtol=0, atol=1e-14)
        # all rollers side by side, each carrying the same loads: K of one roller
        K3 = replace(m, z=3).body_operator(rollers=3)
        m3 = replace(m, z=3)
        np.testing.assert_allclose(K3 @ np.tile(f, 3), np.tile(m3.body_operator() @ f, 3), rtol=1e-13)


def test_independent_solutions_of_a_case_with_open_teeth():
    """Against (1) scipy's root of the reduced equations for the active set found, in the
    module's original body matrices, and (2) scipy's SLSQP minimisation of the energy."""
    from scipy import optimize
    for installation in INSTALLATIONS:
        d = _design(20, installation)
        m = build_model(d)
        n, z = m.n, m.z
        pr = np.full(n - 1, d.thread.pitch_mm)
        pr[9] += 0.003
        g_nr, g_rs = gap_terms(d, pr)
        F = 2000.0
        r = solve_loads(m, F, g_nr, g_rs)
        assert (~r.active_nr).sum() + (~r.active_rs).sum() >= 4
        fr = np.concatenate([r.f_nr, r.f_rs])
        S = np.vstack(m.body_matrices())
        g = np.concatenate([g_nr, g_rs])
        h = np.repeat([m.hertz_nr, m.hertz_rs], n)
        t = np.repeat([m.tooth_nr, m.tooth_rs], n)
        fbar = F / (z * n)
        A = np.nonzero(np.concatenate([r.active_nr, r.active_rs]))[0]

        def residual(x):        # x = [(f / fbar)^(1/3) of the active teeth, a_n, a_s]
            f = np.zeros(2 * n)
            f[A] = x[:-2] ** 3 * fbar
            a = np.repeat(x[-2:], n)
            w = h * np.sign(f) * np.abs(f) ** (2 / 3) + t * f + g + S @ f - a
            return np.concatenate([w[A] / 1e-3, [f[:n].sum() * z / F - 1, f[n:].sum() * z / F - 1]])

        sol = optimize.root(residual, np.concatenate([np.ones(len(A)), [0.005, 0.005]]), method="hybr",
                            options={"xtol": 1e-15})
        f1 = np.zeros(2 * n)
        f1[A] = sol.x[:-2] ** 3 * fbar
        assert np.abs(residual(sol.x)).max() < 1e-12
        np.testing.assert_allclose(f1, fr, rtol=0, atol=1e-9 * fbar)
        assert sol.x[-2] == pytest.approx(r.approach_nr_mm, rel=1e-9)
        assert sol.x[-1] == pytest.approx(r.approach_rs_mm, rel=1e-9)

        K = m.body_operator()
        ge = g.copy()
        if m.sign_screw < 0:
            ge[n:] -= m.body_screw * F * np.arange(n)
        Es = fbar * 0.005

        def energy(u):
            f = u * fbar
            return (0.6 * h @ np.abs(f) ** (5 / 3) + 0.5 * t @ (f * f) + 0.5 * f @ K @ f + ge @ f) / Es

        def grad(u):
            f = u * fbar
            return (h * np.abs(f) ** (2 / 3) + t * f + K @ f + ge) * fbar / Es

        eq = np.kron(np.eye(2), np.ones(n))
        opt = optimize.minimize(energy, np.ones(2 * n), jac=grad, bounds=[(0, None)] * (2 * n), method="SLSQP",
                                constraints=[{"type": "eq", "fun": lambda u: eq @ u - n, "jac": lambda u: eq}],
                                options={"ftol": 1e-16, "maxiter": 1000})
        assert opt.success
        np.testing.assert_allclose(opt.x * fbar, fr, rtol=0, atol=1e-6 * fbar)
        assert energy(fr / fbar) <= energy(opt.x) + 1e-12 * abs(energy(opt.x))


def test_equal_load_design_gives_coefficients_one_to_rounding():
    for installation in INSTALLATIONS:
        d = _design(20, installation)
        m = build_model(d)
        pd = design_pitches(d, model=m)
        r = forward(with_pitch_lists(d, pd), model=m)
        assert np.abs(r.ldc_nr - 1).max() < 1e-12 and np.abs(r.ldc_rs - 1).max() < 1e-12
        cr, cn = closed_form_equal_load(d)
        p = d.thread.pitch_mm
        np.testing.assert_allclose(np.array(pd.roller_mm) - p, cr, atol=1e-15, rtol=1e-9)
        np.testing.assert_allclose(np.array(pd.nut_mm) - p, cn, atol=1e-15, rtol=1e-9)


@pytest.mark.parametrize("installation", INSTALLATIONS)
def test_equal_rollers_reduce_to_the_single_roller_model(installation):
    d = _design(20, installation)
    m = build_model(d)
    graded = with_pitch_lists(d, design_pitches(d, model=m))
    for design, load in ((d, 20000.0), (graded, 200.0), (d, 60000.0)):
        g_nr, g_rs = gap_terms(design)
        r = solve_loads(m, load, g_nr, g_rs)
        zr = solve_loads_rollers(m, load, np.tile(g_nr, (m.z, 1)), np.tile(g_rs, (m.z, 1)))
        assert zr.ldc_nr.shape == (20,) and zr.ldc_per_roller["nut_roller"].shape == (m.z, 20)
        np.testing.assert_allclose(zr.ldc_nr, r.ldc_nr, rtol=0, atol=1e-12)
        np.testing.assert_allclose(zr.ldc_rs, r.ldc_rs, rtol=0, atol=1e-12)
        for side, ref in (("nut_roller", r.ldc_nr), ("roller_screw", r.ldc_rs)):
            np.testing.assert_allclose(zr.ldc_per_roller[side], np.tile(ref, (m.z, 1)), rtol=0, atol=1e-12)
        np.testing.assert_allclose(zr.roller_load_share, np.full(m.z, 1 / m.z), rtol=1e-12)
        np.testing.assert_allclose(zr.approach_nr_mm, r.approach_nr_mm, rtol=1e-12)
        np.testing.assert_allclose(zr.approach_rs_mm, r.approach_rs_mm, rtol=1e-12)
        assert zr.axial_deflection_mm == pytest.approx(r.axial_deflection_mm, rel=1e-12)
        np.testing.assert_array_equal(zr.active_nr, np.tile(r.active_nr, (m.z, 1)))
        rep = roller_loads_dict(zr)
        assert rep["ldc_nut_roller"] == pytest.approx(r.ldc_nr.tolist(), abs=1e-12)
        assert len(rep["ldc_per_roller"]["roller_screw"]) == m.z and len(rep["roller_load_share"]) == m.z
    # the helper for per-roller pitch lists gives the same gaps for equal rollers
    G_nr, G_rs = gap_terms_rollers(graded)
    np.testing.assert_array_equal(G_nr, np.tile(gap_terms(graded)[0], (m.z, 1)))


def _roller_residuals(m, load, G_nr, G_rs, zr):
    """Complementarity of the z-roller form written out with explicit sums (DOMAIN.md
    section 4 segment forces: nut and screw summed over all rollers, roller per roller)."""
    z, n = G_nr.shape
    s = m.sign_screw
    dmax = 0.0
    for r in range(z):
        fn, fs = zr.f_nr[r], zr.f_rs[r]
        wn, ws = [], []
        for j in range(n):
            Sn = sum(m.body_nut * zr.f_nr[:, k + 1:].sum() + m.body_roller * (fn[k + 1:].sum() - fs[k + 1:].sum())
                     for k in range(j))
            Ns = [zr.f_rs[:, k + 1:].sum() if s > 0 else zr.f_rs[:, :k + 1].sum() for k in range(j)]
            Ss = sum(s * m.body_screw * Ns[k] - m.body_roller * (fn[k + 1:].sum() - fs[k + 1:].sum())
                     for k in range(j))
            wn.append(m.deflection("nr", fn[j]) + G_nr[r, j] + Sn - zr.approach_nr_mm[r])
            ws.append(m.deflection("rs", fs[j]) + G_rs[r, j] + Ss - zr.approach_rs_mm[r])
        w = np.array(wn + ws)
        f = np.concatenate([fn, fs])
        act = np.concatenate([zr.active_nr[r], zr.active_rs[r]])
        assert np.all(f >= 0) and np.all(f[~act] == 0)
        assert np.all(w[~act] >= -1e-12 * 0.01)
        dmax = max(dmax, np.abs(w[act]).max(initial=0.0))
        assert fn.sum() == pytest.approx(fs.sum(), rel=1e-12, abs=1e-9)      # the roller floats
    assert zr.f_nr.sum() == pytest.approx(load, rel=1e-12)
    assert zr.f_rs.sum() == pytest.approx(load, rel=1e-12)
    delta = zr.approach_nr_mm + zr.approach_rs_mm                              # common approach
    np.testing.assert_allclose(delta, delta[0], rtol=1e-12)
    assert dmax < 1e-11


def test_two_unequal_rollers_share_the_load_by_their_engagement():
    d = default_design()
    m2 = replace(build_model(d), z=2)
    g_nr, g_rs = gap_terms(d)
    # roller 2 engages 1 um earlier on both flanks (e.g. a thicker roller thread)
    G_nr, G_rs = np.stack([g_nr, g_nr - 1e-3]), np.stack([g_rs, g_rs - 1e-3])
    for load in (2000.0, 20000.0):
        zr = solve_loads_rollers(m2, load, G_nr, G_rs)
        share = zr.roller_load_share
        assert share[1] > share[0] > 0.3 and share.sum() == pytest.approx(1.0, rel=1e-12)
        _roller_residuals(m2, load, G_nr, G_rs, zr)
    # the earlier-engaged roller's share falls with the load (its 1 um matters less)
    lo = solve_loads_rollers(m2, 2000.0, G_nr, G_rs).roller_load_share[1]
    hi = solve_loads_rollers(m2, 20000.0, G_nr, G_rs).roller_load_share[1]
    assert lo > hi > 0.5
    # a pure axial shift of a roller (+c nut side, -c screw side) changes nothing: it floats
    sh = solve_loads_rollers(m2, 20000.0, np.stack([g_nr, g_nr + 2e-3]), np.stack([g_rs, g_rs - 2e-3]))
    np.testing.assert_allclose(sh.roller_load_share, [0.5, 0.5], rtol=1e-12)
    # a roller 50 um out of engagement at a small load carries nothing and floats freely
    far = solve_loads_rollers(m2, 200.0, np.stack([g_nr, g_nr + 0.05]), np.stack([g_rs, g_rs + 0.05]))
    assert far.roller_load_share.tolist() == [1.0, 0.0] and not far.active_nr[1].any()
    _roller_residuals(m2, 200.0, np.stack([g_nr, g_nr + 0.05]), np.stack([g_rs, g_rs + 0.05]), far)
    # batched z-roller problems, and the barrier path, give the same loads
    bz = solve_loads_rollers(m2, [2000.0, 20000.0], np.stack([G_nr, G_nr]), np.stack([G_rs, G_rs]),
                             strategy="barrier")
    one = solve_loads_rollers(m2, 20000.0, G_nr, G_rs)
    assert bz.f_nr.shape == (2, 2, 20) and bz.roller_load_share.shape == (2, 2)
    np.testing.assert_allclose(bz.f_nr[1], one.f_nr, rtol=0, atol=1e-9 * one.mean)


def test_dense_linear_compliance():
    d = default_design()
    m = build_model(d)
    g_nr, g_rs = gap_terms(d)
    r = solve_loads(m, 20000.0, g_nr, g_rs)
    # the default diagonal given as a dense matrix: the same loads
    C0 = m.linear_compliance()
    assert np.array_equal(np.diag(C0), np.repeat([m.tooth_nr, m.tooth_rs], 20))
    rd = solve_loads(m.with_compliance(C0), 20000.0, g_nr, g_rs)
    np.testing.assert_allclose(rd.f_nr, r.f_nr, rtol=0, atol=1e-12 * r.mean)
    np.testing.assert_allclose(rd.f_rs, r.f_rs, rtol=0, atol=1e-12 * r.mean)
    assert rd.approach_rs_mm == pytest.approx(r.approach_rs_mm, rel=1e-12)
    # the dense linear algebra on the default model agrees with the banded one
    rb = solve_loads(m, 20000.0, g_nr, g_rs, linear_solver="dense")
    np.testing.assert_allclose(rb.f_rs, r.f_rs, rtol=0, atol=1e-12 * r.mean)
    # a coupled compliance: neighbouring teeth share deflection, the two flanks couple
    j = np.arange(20)
    near = np.exp(-np.abs(j[:, None] - j[None, :]) / 1.5)
    C = block_compliance(m.tooth_nr * near, m.tooth_rs * near, 0.2 * np.sqrt(m.tooth_nr * m.tooth_rs) * near)
    mc = m.with_compliance(C)
    assert mc.compliance is not None and np.array_equal(mc.linear_compliance(), C)
    rc = solve_loads(mc, 20000.0, g_nr, g_rs)
    assert_complementarity(mc, 20000.0, g_nr, g_rs, rc, C=C)
    assert np.abs(rc.ldc_rs - r.ldc_rs).max() > 1e-3
    # batched, z rollers, barrier path
    b = solve_loads_batch(mc, [2000.0, 20000.0], np.stack([g_nr, g_nr]), np.stack([g_rs, g_rs]), strategy="barrier")
    np.testing.assert_allclose(b.f_nr[1], rc.f_nr, rtol=0, atol=1e-9 * rc.mean)
    zr = solve_loads_rollers(mc, 20000.0, np.tile(g_nr, (10, 1)), np.tile(g_rs, (10, 1)))
    np.testing.assert_allclose(zr.ldc_rs, rc.ldc_rs, rtol=0, atol=1e-12)
    with pytest.raises(DesignError, match="symmetric"):
        m.with_compliance(C + np.triu(np.full((40, 40), 1e-7), 1))
    with pytest.raises(DesignError, match="semi-definite"):
        m.with_compliance(C - 2 * m.tooth_nr * np.eye(40))
    with pytest.raises(DesignError, match=r"\(40, 40\)"):
        m.with_compliance(np.eye(20))


def test_sensitivity_is_one_batched_solve_in_chunks():
    d = load_design(__import__("pathlib").Path(__file__).parent.parent / "examples" / "graded-pitch.toml")
    m = build_model(d)
    calls = []
    got = pitch_error_sensitivity(d, model=m, progress=lambda *a: calls.append(a))
    assert calls == [("sensitivity", 38, 38)]
    small = []
    chunked = pitch_error_sensitivity(d, model=m, memory_mb=0.1, progress=lambda *a: small.append(a))
    assert chunked == got
    assert len(small) == sensitivity_chunks(d, m, memory_mb=0.1) > 3
    assert [c[1] for c in small] == sorted(c[1] for c in small) and small[-1][1:] == (38, 38)
    # the definition, one scalar solve per perturbed pitch list
    base = forward(d, model=m)
    worst = {}
    for part in ("roller", "nut"):
        best = (0.0, 0)
        for j in range(19):
            pr, pn = np.array(d.pitch_list("roller")), np.array(d.pitch_list("nut"))
            (pr if part == "roller" else pn)[j] += 1e-3
            res = forward(d, model=m, roller=pr, nut=pn)
            dl = max(np.abs(res.ldc_nr - base.ldc_nr).max(), np.abs(res.ldc_rs - base.ldc_rs).max())
            if dl > best[0]:
                best = (dl, j + 1)
        worst[part] = best
    for part in ("roller", "nut"):
        assert got[f"max_ldc_change_{part}"] == pytest.approx(worst[part][0], rel=1e-12)
        assert got[f"worst_pitch_index_{part}"] == worst[part][1]


def test_load_distribution_reports_progress_per_substep():
    d = default_design()
    calls = []
    rep = loads_section(load_distribution(d, progress=lambda *a: calls.append(a)))
    total = 4 + 4 + sensitivity_chunks(d)
    assert calls == [("loads", i, total) for i in range(1, total + 1)]
    assert rep["max_ldc"] == pytest.approx(max(rep["ldc_roller_screw"] + rep["ldc_nut_roller"]))
    assert loads_section(load_distribution(d)) == rep
    off = off_design(d, (0.5, 2.0))
    r = forward(d, 2.0 * d.loading.axial_load_n)
    assert off[1]["ldc_roller_screw"] == pytest.approx(r.ldc_rs.tolist(), rel=1e-12)


def test_iteration_cap_raises_instead_of_returning_numbers():
    d = default_design()
    m = build_model(d)
    g_nr, g_rs = gap_terms(d)
    for strategy in ("auto", "barrier"):
        with pytest.raises(ConvergenceError, match="no result"):
            solve_loads(m, 20000.0, g_nr, g_rs, max_iter=2, strategy=strategy)
    with pytest.raises(ConvergenceError):
        solve_loads_batch(m, [2000.0, 20000.0], np.stack([g_nr, g_nr]), np.stack([g_rs, g_rs]), max_iter=3)
    with pytest.raises(ValueError, match="loads"):
        solve_loads(m, -1.0, g_nr, g_rs)
    with pytest.raises(ValueError, match="shape"):
        solve_loads_batch(m, 1.0, g_nr, g_rs)
