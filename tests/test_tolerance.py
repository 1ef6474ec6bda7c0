"""Error model and Monte Carlo tolerance studies (prs_geom.analysis.tolerance, prs_geom.studies).

References used here:
* the linearised load model (Hertz replaced by its tangent) is affine in the gaps, so its
  per-tooth mean and covariance under normal errors follow in closed form from the influence
  matrix G: mean unchanged, covariance G S G^T (S the error covariance); Monte Carlo must
  agree within sampling error (z-scores of the mean and of the standard deviation);
* zero tolerances must reproduce the deterministic single-roller solver (a different code path,
  one roller standing for all);
* the Clopper-Pearson bound against scipy's exact binomial tail.
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import stats

from prs_geom.analysis import tolerance as T
from prs_geom.analysis.contact import analyse_contact
from prs_geom.analysis.loads import build_model, design_pitches, forward, with_pitch_lists
from prs_geom.exports.report import tolerance_section
from prs_geom.model.design import PRSDesign, Tolerances, default_design
from prs_geom.model.errors import DesignError
from prs_geom import studies

from cli_helpers import run as _run


@pytest.fixture(scope="module")
def graded():
    d = default_design()
    g = with_pitch_lists(d, design_pitches(d), "graded")
    c = analyse_contact(g)
    return g, c, build_model(g, c)


# --------------------------------------------------------------------------- error model
def test_zero_tolerance_reproduces_deterministic_solver(graded):
    d, c, m = graded
    em = T.error_model(d, c, Tolerances())
    prob = T.study_problem(d, m, em, [0.25, 1.0, 1.5])
    s = T.evaluate(prob, em.sample(np.random.SeedSequence(3), 4))
    for i, F in enumerate(prob.loads_n):
        r = forward(d, F, model=m)
        assert np.max(np.abs(s.worst_nr[i] - r.ldc_nr.max())) < 1e-12
        assert np.max(np.abs(s.worst_rs[i] - r.ldc_rs.max())) < 1e-12
        assert np.max(np.abs(s.share_max[i] - 1.0)) < 1e-12


def test_radial_closure_factor_is_flank_slope(graded):
    """A radial move of a straight 45 deg flank moves its axial position by tan(beta) / cos(lead
    angle) to first order; the contact-normal formula must agree within the lead-angle effect."""
    d, c, _ = graded
    em = T.error_model(d, c, Tolerances())
    beta = math.radians(d.thread.flank_half_angle_deg)
    for k in em.closure_rs + em.closure_nr:
        assert abs(k - math.tan(beta)) < 0.02


def test_temperature_equals_lead_error(graded):
    """Second formulation: a screw warmer by dT has its pitch longer by p alpha dT, exactly the
    gaps of a screw lead error of p alpha dT (n - 1) accumulated over the engaged length."""
    d, c, _ = graded
    em = T.error_model(d, c, Tolerances())
    dT = 7.0
    x_t = np.zeros((1, em.size))
    x_t[0, em.columns("temperature").start] = dT
    x_l = np.zeros((1, em.size))
    alpha = d.materials.screw.thermal_expansion_per_k
    x_l[0, em.columns("lead").start] = d.thread.pitch_mm * alpha * dT * (d.thread.engaged_teeth - 1)
    for a, b in zip(em.gaps(x_t), em.gaps(x_l)):
        assert np.max(np.abs(a - b)) < 1e-15


def test_larger_roller_carries_more_and_eccentric_nut_shares_by_cosine(graded):
    d, c, m = graded
    em = T.error_model(d, c, Tolerances())
    prob = T.study_problem(d, m, em, [1.0])
    x = np.zeros((2, em.size))
    x[0, em.columns("roller_diameter").start + 3] = 2e-3          # roller 3 is 2 um larger
    x[1, em.columns("nut_eccentricity").start] = 2e-3              # nut offset 2 um towards +x
    r = T.solve_samples(prob, x, d.loading.axial_load_n)
    share = r.roller_load_share * d.roller.count
    assert share[0, 3] == share[0].max() and share[0, 3] > 1.05
    assert abs(share[0].sum() - d.roller.count) < 1e-12
    # the nut moving towards +x opens the contacts of roller 0 (at +x) and closes roller z/2's
    theta = 2 * np.pi * np.arange(d.roller.count) / d.roller.count
    assert np.argmin(share[1]) == 0 and np.argmax(share[1]) == d.roller.count // 2
    # symmetric pattern: rollers at +-theta share equally (up to the contact point's azimuth
    # psi, about 1e-6 rad off the roller's plane on the graded design)
    assert abs(share[1, 1] - share[1, -1]) < 1e-5
    assert np.corrcoef(share[1], -np.cos(theta))[0, 1] > 0.99


def test_sampling_is_reproducible_and_term_wise_common(graded):
    d, c, _ = graded
    em = T.error_model(d, c, Tolerances(flank_um=1.0, roller_diameter_um=2.0))
    a = em.sample(np.random.SeedSequence(11), 50)
    b = em.sample(np.random.SeedSequence(11), 50)
    assert np.array_equal(a, b)
    only = em.only(("roller_diameter",)).sample(np.random.SeedSequence(11), 50)
    cols = em.columns("roller_diameter")
    assert np.array_equal(only[:, cols], a[:, cols])                 # common draws
    assert np.all(only[:, em.columns("roller_nut_flank")] == 0)
    assert np.all(np.abs(a[:, em.columns("roller_nut_flank")]) <= 1e-3)
    assert np.abs(a[:, em.columns("roller_nut_flank")]).max() > 0.9e-3


# --------------------------------------------------------------------------- linear check
def test_linear_model_monte_carlo_matches_closed_form(graded):
    """Done-when: with the linearised model and normal errors the per-tooth LDC mean and standard
    deviation from Monte Carlo match G S G^T within sampling error."""
    d, c, m = graded
    tol = Tolerances(distribution="normal", flank_um=1.0, roller_diameter_um=1.0, nut_eccentricity_um=1.0,
                     screw_eccentricity_um=1.0, lead_um=1.0, temperature_k=1.0)
    em = T.error_model(d, c, tol)
    prob = T.study_problem(d, m, em, [1.0])
    F = d.loading.axial_load_n
    G, base = T.linear_influence(prob, F)
    _, std = T.linear_moments(G, em)
    N = 1500
    x = em.sample(np.random.SeedSequence(2026), N)
    res = T.solve_samples(prob, x, F, linear_at=F / (d.thread.engaged_teeth * d.roller.count))
    assert res.active_nr.all() and res.active_rs.all()              # the linear regime holds
    per = res.ldc_per_roller
    ldc = np.stack([per["nut_roller"], per["roller_screw"]], axis=1)
    mean0 = np.stack([base.f_nr, base.f_rs]) / (F / (d.thread.engaged_teeth * d.roller.count))
    # affine: every sample is base + G x (the influence matrix is the model's, not a fit)
    assert np.max(np.abs(ldc - mean0 - np.einsum("szjm,bm->bszj", G, x))) < 1e-8
    z_mean = (ldc.mean(axis=0) - mean0) / (std / math.sqrt(N))
    z_std = (ldc.std(axis=0, ddof=1) - std) / (std / math.sqrt(2 * N))
    # 400 coefficients: the largest |z| of 400 standard normals exceeds 4.5 with probability 0.3 %
    assert np.abs(z_mean).max() < 4.5
    assert np.abs(z_std).max() < 4.5
    assert std.min() > 0.005                                        # the errors do matter


# --------------------------------------------------------------------------- studies
def test_median_worst_ldc_grows_with_tolerance(graded):
    d, c, m = graded
    med = []
    for t in (0.0, 0.5, 1.0, 2.0):
        st = studies.tolerance_study(d, Tolerances(flank_um=t, samples=120, seed=5), contact=c, model=m,
                                     importance=False)
        med.append(tolerance_section(st)["worst_ldc"]["median"])
    assert abs(med[0] - 1.0) < 1e-9                                  # graded: equal at the design load
    assert med[0] < med[1] < med[2] < med[3]
    assert med[3] > 1.3


def test_cli_zero_tolerance_reproduces_loads(tmp_path):
    code, stdout, stderr = _run(["tolerance", "--flank-um", "0", "--samples", "3", "--load-fraction", "0.5", "1",
                                 "--json"])
    assert code == 0, stderr
    out = json.loads(stdout)
    assert out["samples"] == 3 and out["seed"] == 0
    loads = json.loads(_run(["loads", "--json"])[1])
    assert abs(out["cases"][1]["worst_ldc"]["max"] - loads["max_ldc"]) < 1e-12
    assert abs(out["cases"][1]["worst_ldc"]["median"] - loads["max_ldc"]) < 1e-12
    half = [row for row in loads["off_design"] if row["load_fraction"] == 0.5][0]
    assert abs(out["cases"][0]["worst_ldc"]["p99"] - half["max_ldc"]) < 1e-12
    assert set(out["worst_ldc"]) >= {"median", "p95", "p99", "max"}


def test_cli_errors_name_the_flag(tmp_path):
    code, _, err = _run(["tolerance", "--flank-um", "-1"])
    assert code == 2 and "--flank-um = -1" in err
    code, _, err = _run(["tolerance", "--eccentricity-um", "500"])
    assert code == 2 and "--eccentricity-um = 500" in err
    code, _, err = _run(["tolerance", "--out", str(tmp_path / "x.toml")])
    assert code == 2 and "--target-ldc" in err
    assert not (tmp_path / "x.toml").exists()
    bad = tmp_path / "spec.toml"
    bad.write_text("[[case]]\nload_n = 1000.0\ntime_share = 0.5\n", encoding="utf-8")
    code, _, err = _run(["tolerance", "--spectrum", str(bad)])
    assert code == 2 and "time_share" in err and "sum to 1" in err


def test_importance_ranks_the_dominant_term(graded):
    d, c, m = graded
    st = studies.tolerance_study(d, Tolerances(flank_um=0.1, nut_eccentricity_um=3.0, samples=150, seed=1),
                                 contact=c, model=m)
    rank = st.importance
    assert [r["term"] for r in rank] == ["nut_eccentricity", "flank"]
    assert rank[0]["share"] > 0.7 and abs(sum(r["share"] for r in rank) - 1) < 1e-12


def test_clopper_pearson_against_binomial_tail():
    for k, n, level in ((90, 100, 0.95), (199, 200, 0.9), (5, 10, 0.95)):
        p = T.clopper_pearson_lower(k, n, level)
        # the exact bound: P(X >= k | p) = 1 - level
        assert abs(stats.binom.sf(k - 1, n, p) - (1 - level)) < 1e-9
    assert T.clopper_pearson_lower(0, 10) == 0.0


def test_synthesis_meets_target_in_independent_rerun(graded):
    """Done-when: the synthesised tolerance, re-checked by an independent run with a different
    seed, meets the target at the stated confidence."""
    d, c, m = graded
    target, conf, N = 1.15, 0.9, 200
    res = studies.synthesise(d, target, conf, samples=N, seed=3, contact=c, model=m)
    assert res.feasible
    assert 0.05 <= res.uniform_um <= 2.0
    for name in ("uniform", "allocated"):
        chk = res.checks[name]
        assert chk["clopper_pearson_lower"] >= conf
        assert chk["verification"]["meets_confidence"]
    # a third, independent run of the written tolerances (another seed, more samples)
    t = res.tolerances
    assert t.target_ldc == target and t.confidence == conf
    st = studies.tolerance_study(d, Tolerances(**{**t.__dict__, "samples": 300, "seed": 99}), contact=c,
                                 model=m, importance=False)
    assert np.mean(st.worst <= target) >= conf
    # one step looser fails the bound: the synthesis found the largest tolerance on its grid
    looser = studies.tolerance_study(
        d, Tolerances(flank_um=round(res.uniform_um + studies.TOLERANCE_STEP_UM, 6), samples=N, seed=3),
        contact=c, model=m, importance=False)
    k = int((looser.worst <= target).sum())
    assert res.checks["capped_at_um"] is None
    assert T.clopper_pearson_lower(k, N, studies.CP_LEVEL) < conf
    # the allocation is looser where the influence is smaller
    infl = np.concatenate(list(res.influence_per_um.values()))
    alloc = np.concatenate([np.array(v) for v in res.allocation_um.values()])
    assert alloc[np.argmin(infl)] >= alloc[np.argmax(infl)]


def test_synthesis_reports_infeasible_target(graded):
    d, c, m = graded
    res = studies.synthesise(d, 1.01, 0.9, Tolerances(nut_eccentricity_um=5.0), samples=50, seed=0,
                             contact=c, model=m)
    assert not res.feasible and res.tolerances is None
    assert "not met even with exact flanks" in res.checks["reason"]


def test_tolerances_validation_names_field():
    with pytest.raises(DesignError, match=r"tolerances.nut_flank_um"):
        PRSDesign(tolerances=Tolerances(nut_flank_um=(1.0,) * 3))
    with pytest.raises(DesignError, match=r"distribution"):
        Tolerances(distribution="gauss")
    with pytest.raises(DesignError, match=r"load_fractions\[1\]"):
        Tolerances(load_fractions=(1.0, -2.0))


def test_sample_does_not_depend_on_earlier_draws(graded):
    """The same SeedSequence object sampled twice gives the same draws (no hidden spawn state)."""
    d, c, _ = graded
    em = T.error_model(d, c, Tolerances(flank_um=1.0))
    ss = np.random.SeedSequence(5).spawn(2)[1]
    first = em.sample(ss, 7)
    assert np.array_equal(em.sample(ss, 7), first)
    assert np.array_equal(em.sample(np.random.SeedSequence(5).spawn(2)[1], 7), first)


def test_build_of_toleranced_design_reports_the_study(tmp_path):
    """A design with [tolerances] gets the study in report.json (schema-checked by conftest),
    report.html and the plot; the numbers are those of the tolerance command."""
    from prs_geom.pipeline import build

    d = PRSDesign(name="tol", thread=default_design().thread,
                  tolerances=Tolerances(flank_um=0.5, nut_eccentricity_um=1.0, samples=30, seed=4,
                                        load_fractions=(0.5, 1.0)))
    rep = build(d, tmp_path / "out")
    sec = rep["tolerance"]
    direct = studies.tolerance_study(d)
    assert json.dumps(sec, sort_keys=True) == json.dumps(tolerance_section(direct), sort_keys=True)
    assert {"tolerance_ldc.png", "tolerance_ldc.svg"} <= set(rep["files"])
    html = (tmp_path / "out" / "report.html").read_text(encoding="utf-8")
    assert "Tolerances and load sharing" in html and f"{sec['worst_ldc']['p95']:.6g}"[:5] in html
    assert [r["term"] for r in sec["importance"]] and sec["samples"] == 30
    code, out, err = _run(["tolerance", str(tmp_path / "out" / "design.toml"), "--json", "--workers", "1"])
    assert code == 0, err
    assert json.loads(out)["worst_ldc"] == sec["worst_ldc"]


def test_quantile_upper_bound_covers_the_true_quantile():
    """Coverage of the order-statistic bound, checked on uniform samples whose true quantile is q:
    over 400 repetitions the bound lies above q in at least ~95 % of them (binomial 3 sigma)."""
    rng = np.random.default_rng(8)
    q, N, reps = 0.9, 200, 400
    hits = sum(T.quantile_upper_bound(rng.random(N), q) >= q for _ in range(reps))
    assert hits >= reps * 0.95 - 3 * math.sqrt(reps * 0.05 * 0.95)
    assert T.quantile_upper_bound(np.arange(10.0), 0.99) is None


def test_cli_confidence_reports_quantile():
    code, out, err = _run(["tolerance", "--flank-um", "0.5", "--samples", "300", "--confidence", "0.9", "--json",
                           "--workers", "1"])
    assert code == 0, err
    a = json.loads(out)["at_confidence"]
    assert a["confidence"] == 0.9 and a["upper_bound_95"] >= a["worst_ldc_quantile"] > 1.4


def test_error_map_matches_pitch_list_gaps(graded):
    """Independent formulation: roller and nut flank and lead errors are pitch-list changes, so
    their gap changes must equal gap_terms_rollers of the perturbed lists."""
    from prs_geom.analysis.loads import gap_terms_rollers
    d, c, _ = graded
    em = T.error_model(d, c, Tolerances())
    n, z = d.thread.engaged_teeth, d.roller.count
    g0 = gap_terms_rollers(d)
    pr = np.tile(np.array(d.pitch_list("roller")), (z, 1))
    pn = np.array(d.pitch_list("nut"))
    e = 1e-3
    # roller 2's nut-side flank of tooth 5 moved +e: pitch 4 (to tooth 5) longer, pitch 5 shorter
    x = np.zeros((1, em.size))
    x[0, em.columns("roller_nut_flank").start + 2 * n + 4] = e
    dn, ds = em.gaps(x)
    pr2 = pr.copy()
    pr2[2, 3] += e
    pr2[2, 4] -= e
    ref = gap_terms_rollers(d, pr2, pn)
    assert np.max(np.abs(dn[0] - (ref[0] - g0[0]))) < 1e-13        # nut side as the pitch list says
    # (the screw-side gap of the roller flank is the other flank: untouched here)
    assert np.max(np.abs(ds[0])) == 0
    # nut base lead longer by L over the engaged length: every nut pitch + L / (n - 1)
    x = np.zeros((1, em.size))
    x[0, em.columns("lead").start + 1 + z] = e
    dn, ds = em.gaps(x)
    ref = gap_terms_rollers(d, pr, pn + e / (n - 1))
    # (cumulative sums of 2 mm pitches: rounding about 1e-15 mm per tooth)
    assert np.max(np.abs(dn[0] - (ref[0] - g0[0]))) < 1e-13 and np.max(np.abs(ds[0] - (ref[1] - g0[1]))) < 1e-13
    # roller 4's base lead
    x = np.zeros((1, em.size))
    x[0, em.columns("lead").start + 1 + 4] = e
    dn, ds = em.gaps(x)
    pr2 = pr.copy()
    pr2[4] += e / (n - 1)
    ref = gap_terms_rollers(d, pr2, pn)
    # (cumulative sums of 2 mm pitches: rounding about 1e-15 mm per tooth)
    assert np.max(np.abs(dn[0] - (ref[0] - g0[0]))) < 1e-13 and np.max(np.abs(ds[0] - (ref[1] - g0[1]))) < 1e-13


def test_eccentric_screw_loads_the_roller_it_moves_towards(graded):
    d, c, m = graded
    em = T.error_model(d, c, Tolerances())
    prob = T.study_problem(d, m, em, [1.0])
    x = np.zeros((1, em.size))
    x[0, em.columns("screw_eccentricity").start] = 2e-3            # screw offset 2 um towards roller 0
    share = T.solve_samples(prob, x, d.loading.axial_load_n).roller_load_share[0] * d.roller.count
    assert np.argmax(share) == 0 and np.argmin(share) == d.roller.count // 2 and share[0] > 1.1


def test_synthesis_refuses_too_few_samples_up_front(graded):
    d, c, m = graded
    with pytest.raises(DesignError, match=r"^samples = 50: too few .* at least 59"):
        studies.synthesise(d, 1.5, 0.95, samples=50, contact=c, model=m)
    with pytest.raises(DesignError, match=r"^target_ldc = nan"):
        studies.synthesise(d, float("nan"), 0.95, samples=100, contact=c, model=m)
    code, out, err = _run(["tolerance", "--target-ldc", "1.5", "--samples", "50"])
    assert code == 2 and "at least 59" in err
    code, out, err = _run(["tolerance", "--confidence", "1.5", "--samples", "5000"])
    assert code == 2 and "--confidence = 1.5" in err
    code, out, err = _run(["tolerance", "--workers", "2", "--dask-workers", "2"])
    assert code == 2 and err.startswith("error: --workers")


def test_a_study_without_an_error_model_is_refused_naming_the_design_field():
    """Issue 28: no [tolerances] and no tolerances given: a DesignError on the design field
    ``tolerances`` (the library knows no CLI flags), raised before any solve; an explicit
    model, even of zeros, is accepted."""
    d = default_design()
    with pytest.raises(DesignError) as exc:
        studies.tolerance_study(d, None, model=object(), contact=object())      # never reaches them
    assert exc.value.field == "tolerances" and exc.value.value is None
    assert "no error model" in exc.value.rule and "tolerances.flank_um" in exc.value.rule
    assert "--" not in exc.value.rule
    with pytest.raises(DesignError, match=r"^tolerances = \(not set\): the design has no error model"):
        studies.require_error_model(d)
    zero = Tolerances()
    assert studies.require_error_model(d, zero) is zero
    with_section = d.with_changes(tolerances=Tolerances(flank_um=0.5))
    assert studies.require_error_model(with_section).flank_um == 0.5
