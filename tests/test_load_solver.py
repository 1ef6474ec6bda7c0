"""Tooth-load solver: the linear systems of its Newton steps and the z-roller form.

Every solution is checked against a formulation that shares no code path with it: the
"segments" (segment-force, banded LU) and "dense" Newton systems, the single-roller solver for
equal rollers, and the complementarity conditions written out with explicit segment-force
sums (docs/theory/loads.md, "Compatibility and equilibrium": nut and screw carry the sum
over the rollers, each roller its own loads, the compression-compression screw its segment
force from tooth 1).
"""
from __future__ import annotations

import tracemalloc
from dataclasses import replace

import numpy as np
import pytest

from prs_geom.analysis import load_solver as S
from prs_geom.analysis.loads import build_model, design_pitches, gap_terms, gap_terms_rollers, with_pitch_lists
from prs_geom.analysis.load_solver import solve_loads, solve_loads_batch, solve_loads_rollers
from prs_geom.model.design import Loading, PRSDesign, Thread

INSTALLATIONS = ("tension-compression", "compression-compression")


def _design(n=20, installation="tension-compression"):
    return PRSDesign(thread=Thread(engaged_teeth=n), loading=Loading(installation=installation))


def _roller_gaps(d, B, amp_mm, seed):
    """(B, z, n) gaps of the design with independent uniform errors of +-amp on every tooth
    flank of every roller."""
    g_nr, g_rs = gap_terms_rollers(d)
    rng = np.random.default_rng(seed)
    e = rng.uniform(-amp_mm, amp_mm, (2, B) + g_nr.shape)
    return g_nr + e[0], g_rs + e[1]


def roller_gaps_w(m, G_nr, G_rs, res):
    """Gaps w (B, z, 2, n) of a z-roller solution from explicit segment forces: nut segment k
    carries sum_r sum_{i>k} f_nr, the screw segment sum_r sum_{i>k} f_rs (tension) or
    sum_r sum_{i<=k} f_rs (compression: the load enters at the other end), roller r's segment
    sum_{i>k} (f_nr - f_rs) of its own; the body term of tooth j sums segments 1..j-1."""
    def beyond(x):                         # sum_{i>k} x_i of segment k (0-based: k..k+1)
        return np.cumsum(x[..., ::-1], axis=-1)[..., ::-1] - x

    def before(seg):                       # sum of segments 1..j-1 at tooth j
        return np.concatenate([np.zeros(seg.shape[:-1] + (1,)), np.cumsum(seg[..., :-1], axis=-1)], axis=-1)

    fn, fs = res.f_nr, res.f_rs                                    # (B, z, n)
    Nn = beyond(fn).sum(axis=1, keepdims=True)
    Ns = (beyond(fs) if m.sign_screw > 0 else np.cumsum(fs, axis=-1)).sum(axis=1, keepdims=True)
    Nr = beyond(fn) - beyond(fs)
    seg_nr = m.body_nut * Nn + m.body_roller * Nr
    seg_rs = m.sign_screw * m.body_screw * Ns - m.body_roller * Nr
    w_nr = m.deflection("nr", fn) + G_nr + before(seg_nr) - res.approach_nr_mm[..., None]
    w_rs = m.deflection("rs", fs) + G_rs + before(seg_rs) - res.approach_rs_mm[..., None]
    return np.stack([w_nr, w_rs], axis=2)


def check_rollers(m, F, G_nr, G_rs, res):
    """The complementarity conditions of every sample; returns the number of open teeth."""
    F = np.broadcast_to(np.asarray(F, dtype=float), (G_nr.shape[0],))
    z, n = m.z, m.n
    f = np.stack([res.f_nr, res.f_rs], axis=2)
    act = np.stack([res.active_nr, res.active_rs], axis=2)
    w = roller_gaps_w(m, G_nr, G_rs, res)
    a = np.stack([res.approach_nr_mm, res.approach_rs_mm], axis=2)
    dref = np.maximum(np.abs(a).max(axis=(1, 2)), m.deflection("nr", F / (z * n)))[:, None, None, None]
    assert np.all(np.isfinite(f)) and np.all(f >= 0)
    assert np.all(f[act] > 0) and np.all(f[~act] == 0)
    assert np.all(np.abs(np.where(act, w, 0.0)) <= 1e-12 * dref)          # contact: gap closed
    assert np.all(np.where(act, 0.0, w) >= -1e-12 * dref)                  # open tooth: gap open
    # equilibrium of every roller (it floats) and of the whole; one screw-to-nut approach
    np.testing.assert_allclose(res.f_nr.sum(-1), res.f_rs.sum(-1), rtol=0, atol=1e-12 * F.max() / z)
    np.testing.assert_allclose(res.f_nr.sum(axis=(1, 2)), F, rtol=1e-12)
    np.testing.assert_allclose(res.f_rs.sum(axis=(1, 2)), F, rtol=1e-12)
    delta = a.sum(axis=2)
    np.testing.assert_allclose(delta, np.broadcast_to(delta[:, :1], delta.shape), rtol=1e-12)
    return int((~act).sum())


def max_diff(a, b, F, m):
    """max |f_a - f_b| / (F0 / (n z)) over both sides and all samples."""
    scale = (np.broadcast_to(np.asarray(F, dtype=float), (a.f_nr.shape[0],)) / (m.n * m.z))[:, None, None]
    return max((np.abs(a.f_nr - b.f_nr) / scale).max(), (np.abs(a.f_rs - b.f_rs) / scale).max())


# ------------------------------------------------------------------ the Newton linear systems
def _random_system(m, R, B, seed, rollers=True):
    """A problem and random Newton-system data: tangent stiffnesses k >= 0 (0 for teeth held
    open), residuals r (0 there), equilibrium residuals; sample 0 has roller 1 floating."""
    rng = np.random.default_rng(seed)
    n = m.n
    g = np.zeros((B, R, n) if rollers else (B, n))
    p = S._make_problem(m, 1e4 * rng.uniform(0.1, 3, B), g, g, None, rollers=rollers)
    kt = 1.0 / m.tooth_rs
    k = kt * rng.uniform(0.05, 1.0, (B, R, 2, n))
    k[rng.random(k.shape) < 0.3] = 0.0
    k[:, 0, :, 0] = kt                                 # a load path: roller 0, tooth 1, both sides
    if R > 1:
        k[0, 1] = 0.0
    floating = (k == 0).all(axis=(2, 3))
    r = np.where(k > 0, rng.normal(0, 1e-3, k.shape), 0.0)
    rc_roll = rng.normal(0, 50.0, (B, R))
    rc_tot = rng.normal(0, 500.0, B)
    return p, k, r, rc_roll, rc_tot, floating


@pytest.mark.parametrize("installation", INSTALLATIONS)
@pytest.mark.parametrize("n, R", [(2, 10), (20, 10), (20, 3), (20, 1), (7, 1)])
def test_newton_systems_solve_their_equations(installation, n, R):
    """Each linear solver's (q, dy) satisfies q + K (k q) - dy = r tooth by tooth with K the
    model's own body operator, the roller and total equilibria (du = 0 for a floating
    roller) and one approach increment per sample; the three solvers agree."""
    m = build_model(_design(n, installation))
    if R > 1:
        m = replace(m, z=R)
    B = 6
    p, k, r, rc_roll, rc_tot, floating = _random_system(m, R, B, seed=n + R, rollers=R > 1)
    assert floating.sum() == (R > 1)
    K = m.body_operator(rollers=R if R > 1 else None)              # (2 R n, 2 R n), mm/N
    out = {}
    for kind in ("banded", "segments", "dense"):
        lin = S._Linear(p, np.full(B, 1.0 / m.tooth_rs), kind)
        q, dy = lin.solve(np.arange(B), k, r, rc_roll, rc_tot, floating)
        d = k * q
        lhs = q + (d.reshape(B, -1) @ K.T).reshape(q.shape) - dy[..., None]
        # every tooth, also those held open (k = 0, r = 0: q is the gap change they see)
        assert np.abs(lhs - r).max() <= 1e-12 * np.abs(q).max()
        eq_roll = d[:, :, 0].sum(-1) - d[:, :, 1].sum(-1)
        assert np.abs(np.where(floating, 0.0, eq_roll - rc_roll)).max() <= 1e-12 * np.abs(rc_roll).max()
        assert np.abs(dy[floating][:, 0]).max(initial=0.0) <= 1e-12 * np.abs(dy).max()
        assert np.abs(p.m * d[:, :, 1].sum(axis=(1, 2)) - rc_tot).max() <= 1e-12 * np.abs(rc_tot).max()
        app = dy.sum(axis=2)
        assert np.abs(app - app[:, :1]).max() <= 1e-12 * np.abs(app).max()
        out[kind] = q, dy
    for kind in ("segments", "dense"):
        for a, b in zip(out["banded"], out[kind]):
            assert np.abs(a - b).max() <= 1e-12 * np.abs(b).max()


# ------------------------------------------------------------------ z rollers side by side
CASES = {
    # name: (n, installation, error amplitude mm, load fractions, linear_at N or None)
    "default": (20, "tension-compression", 1e-3, (0.01, 1.0, 3.0), None),
    "compression": (20, "compression-compression", 1e-3, (0.01, 1.0, 3.0), None),
    "20um": (20, "tension-compression", 20e-3, (0.01, 1.0, 3.0), None),
    "20um-compression": (20, "compression-compression", 20e-3, (0.01, 3.0), None),
    "n2": (2, "tension-compression", 5e-3, (0.01, 3.0), None),
    "n2-compression": (2, "compression-compression", 5e-3, (0.01, 3.0), None),
    "linear": (20, "compression-compression", 5e-3, (0.01, 1.0, 3.0), 60.0),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_rollers_agree_with_the_other_formulations(case):
    n, installation, amp, fractions, linear_at = CASES[case]
    d = _design(n, installation)
    m = build_model(d)
    F = d.loading.axial_load_n * np.repeat(fractions, 2)
    G_nr, G_rs = _roller_gaps(d, F.size, amp, seed=n)
    res = {kind: solve_loads_rollers(m, F, G_nr, G_rs, linear_at=linear_at, linear_solver=kind)
           for kind in ("auto", "banded", "segments", "dense")}
    for kind in ("segments", "dense"):
        assert max_diff(res["banded"], res[kind], F, m) <= 1e-12
        assert np.abs(res["banded"].approach_rs_mm - res[kind].approach_rs_mm).max() <= \
            1e-12 * np.abs(res[kind].approach_rs_mm).max()
    np.testing.assert_array_equal(res["auto"].f_nr, res["banded"].f_nr)      # auto is the banded form
    if linear_at is None:
        opened = check_rollers(m, F, G_nr, G_rs, res["banded"])
        if amp >= 5e-3:
            assert opened > 0                     # large errors: some teeth lose contact
    else:
        # the linear model: the same problem with Hertz replaced by its tangent at linear_at
        lin = replace(m, hertz_nr=0.0, hertz_rs=0.0,
                      tooth_nr=m.tooth_nr + (2 / 3) * m.hertz_nr * linear_at ** (-1 / 3),
                      tooth_rs=m.tooth_rs + (2 / 3) * m.hertz_rs * linear_at ** (-1 / 3))
        shift_nr = m.hertz_nr * linear_at ** (2 / 3) / 3         # e0 of the tangent, added to the gaps
        shift_rs = m.hertz_rs * linear_at ** (2 / 3) / 3
        ref = solve_loads_rollers(lin, F, G_nr + shift_nr, G_rs + shift_rs, linear_solver="segments")
        assert max_diff(res["banded"], ref, F, m) <= 1e-12
        check_rollers(lin, F, G_nr + shift_nr, G_rs + shift_rs, res["banded"])


def test_rollers_with_many_teeth_agree_with_segments():
    d = _design(100, "compression-compression")
    m = build_model(d)
    F = d.loading.axial_load_n * np.array([0.01, 3.0])
    G_nr, G_rs = _roller_gaps(d, 2, 20e-3, seed=100)
    a = solve_loads_rollers(m, F, G_nr, G_rs)
    b = solve_loads_rollers(m, F, G_nr, G_rs, linear_solver="segments")
    assert max_diff(a, b, F, m) <= 1e-12
    assert check_rollers(m, F, G_nr, G_rs, a) > 0


@pytest.mark.parametrize("installation", INSTALLATIONS)
def test_a_roller_out_of_engagement_floats(installation):
    """Roller 3 is 10 um clear of both flanks: at a small load it carries nothing and floats
    (its approach is not tied to an equilibrium row); at 300 % it engages."""
    d = _design(20, installation)
    m = build_model(d)
    G_nr, G_rs = _roller_gaps(d, 3, 2e-3, seed=7)
    G_nr[:, 3] += 0.01
    G_rs[:, 3] += 0.01
    F = d.loading.axial_load_n * np.array([0.01, 0.05, 3.0])
    res = {kind: solve_loads_rollers(m, F, G_nr, G_rs, linear_solver=kind) for kind in ("banded", "segments", "dense")}
    r = res["banded"]
    assert not r.active_nr[:2, 3].any() and not r.active_rs[:2, 3].any()
    assert np.all(r.roller_load_share[:2, 3] == 0.0) and r.roller_load_share[2, 3] > 0
    np.testing.assert_allclose(r.roller_load_share.sum(-1), 1.0, rtol=1e-15)
    for kind in ("segments", "dense"):
        assert max_diff(r, res[kind], F, m) <= 1e-12
    check_rollers(m, F, G_nr, G_rs, r)


@pytest.mark.parametrize("installation", INSTALLATIONS)
def test_equal_rollers_reproduce_the_single_roller_batch(installation):
    d = _design(20, installation)
    m = build_model(d)
    graded = with_pitch_lists(d, design_pitches(d, model=m))
    rows = []
    for design, frac in ((d, 1.0), (graded, 0.01), (d, 3.0)):       # graded at 1 %: teeth open
        g_nr, g_rs = gap_terms(design)
        rows.append((frac * d.loading.axial_load_n, g_nr, g_rs))
    F = np.array([r[0] for r in rows])
    g_nr, g_rs = np.stack([r[1] for r in rows]), np.stack([r[2] for r in rows])
    one = solve_loads_batch(m, F, g_nr, g_rs)
    assert (~one.active_nr).sum() + (~one.active_rs).sum() > 0
    zr = solve_loads_rollers(m, F, np.repeat(g_nr[:, None], m.z, 1), np.repeat(g_rs[:, None], m.z, 1))
    scale = (F / (m.n * m.z))[:, None, None]
    np.testing.assert_allclose(zr.f_nr / scale, np.repeat(one.f_nr[:, None], m.z, 1) / scale, rtol=0, atol=1e-12)
    np.testing.assert_allclose(zr.f_rs / scale, np.repeat(one.f_rs[:, None], m.z, 1) / scale, rtol=0, atol=1e-12)
    np.testing.assert_allclose(zr.approach_nr_mm, np.repeat(one.approach_nr_mm[:, None], m.z, 1), rtol=1e-12)
    np.testing.assert_allclose(zr.approach_rs_mm, np.repeat(one.approach_rs_mm[:, None], m.z, 1), rtol=1e-12)
    np.testing.assert_array_equal(zr.active_rs, np.repeat(one.active_rs[:, None], m.z, 1))
    # and the single-roller batch against its own segment-force formulation
    seg = solve_loads_batch(m, F, g_nr, g_rs, linear_solver="segments")
    np.testing.assert_allclose(one.f_rs / scale[:, 0], seg.f_rs / scale[:, 0], rtol=0, atol=1e-12)


def test_barrier_path_and_chunks_give_the_same_roller_loads():
    d = _design(20)
    m = replace(build_model(d), z=4)
    g_nr, g_rs = gap_terms(d)
    rng = np.random.default_rng(3)
    G_nr = g_nr + rng.uniform(-10e-3, 10e-3, (3, 4, 20))
    G_rs = g_rs + rng.uniform(-10e-3, 10e-3, (3, 4, 20))
    F = np.array([200.0, 20000.0, 60000.0])
    a = solve_loads_rollers(m, F, G_nr, G_rs)
    b = solve_loads_rollers(m, F, G_nr, G_rs, strategy="barrier")
    assert b.barrier.all() and not a.barrier.any()
    assert max_diff(a, b, F, m) <= 1e-12                # both end in face Newton on the same face
    c = solve_loads_rollers(m, F, G_nr, G_rs, memory_mb=1e-6)      # one sample per chunk
    np.testing.assert_array_equal(c.f_nr, a.f_nr)
    np.testing.assert_array_equal(c.approach_rs_mm, a.approach_rs_mm)
    check_rollers(m, F, G_nr, G_rs, a)


# ------------------------------------------------------------------ pieces
@pytest.mark.parametrize("linear_at", [None, 30.0])
def test_tooth_inverse_inverts_the_tooth_law(linear_at):
    """_tooth_inv against the model's forward law (Hertz + tooth compliance, odd extension)
    over eleven decades of load, and 0 -> 0."""
    m = build_model(_design(5))
    g = np.zeros((4, 5))
    p = S._make_problem(m, 2e4, g, g, linear_at, rollers=False)
    f = np.geomspace(1e-6, 1e5, 4 * 2 * 5).reshape(4, 1, 2, 5)
    f[0, 0, 0, :2] = [0.0, -7.0]
    dl = S._tooth(p, f)
    if linear_at is None:       # the model's own law, written independently
        np.testing.assert_allclose(dl[:, 0, 0], m.deflection("nr", f[:, 0, 0]), rtol=1e-14, atol=0)
        np.testing.assert_allclose(dl[:, 0, 1], m.deflection("rs", f[:, 0, 1]), rtol=1e-14, atol=0)
    back = S._tooth_inv(p, dl)
    if linear_at is None:
        np.testing.assert_allclose(back, f, rtol=4e-15, atol=0)
    else:                       # affine law: the inverse loses what e0 + e1 f lost to rounding
        np.testing.assert_allclose(back, f, rtol=4e-15, atol=4e-16 * np.abs(p.e0).max() / p.e1.min())


def test_memory_estimate_bounds_the_measured_peak():
    """_bytes_per_sample (which cuts batches into chunks) is at least the peak of traced
    allocations per sample of a solve, for the z-roller and the single-roller forms."""
    d = _design(20)
    m = build_model(d)
    G_nr, G_rs = _roller_gaps(d, 200, 1e-3, seed=1)
    cases = [("banded", m.z, lambda: solve_loads_rollers(m, 2e4, G_nr, G_rs, memory_mb=1e5)),
             ("segments", m.z, lambda: solve_loads_rollers(m, 2e4, G_nr[:20], G_rs[:20], linear_solver="segments",
                                                          memory_mb=1e5)),
             ("banded", 1, lambda: solve_loads_batch(m, 2e4, G_nr[:, 0], G_rs[:, 0], memory_mb=1e5))]
    for kind, R, run in cases:
        B = 20 if kind == "segments" else 200
        tracemalloc.start()
        try:
            run()
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        est = S._bytes_per_sample(R, 20, kind)
        assert peak / B <= est <= 3.0 * peak / B, (kind, R, peak / B, est)
    # the z-roller form: about 30 times less memory per sample than the segment form
    assert S.chunk_size(10, 20, "banded", 256.0) >= 25 * S.chunk_size(10, 20, "segments", 256.0)


def test_linear_solver_names_are_checked():
    d = _design(5)
    m = build_model(d)
    g_nr, g_rs = gap_terms(d)
    for bad in ("schur", "lu", ""):
        with pytest.raises(ValueError, match="linear_solver"):
            solve_loads(m, 2e4, g_nr, g_rs, linear_solver=bad)
    mc = m.with_compliance(m.linear_compliance())
    for kind in ("banded", "segments"):
        with pytest.raises(ValueError, match="linear_solver"):
            solve_loads(mc, 2e4, g_nr, g_rs, linear_solver=kind)
    # without body compliance the body-deflection form is impossible; auto falls back
    rigid = replace(m, body_nut=0.0)
    with pytest.raises(ValueError, match="positive body"):
        solve_loads(rigid, 2e4, g_nr, g_rs, linear_solver="banded")
    a = solve_loads(rigid, 2e4, g_nr, g_rs)
    b = solve_loads(rigid, 2e4, g_nr, g_rs, linear_solver="dense")
    np.testing.assert_allclose(a.f_rs, b.f_rs, rtol=0, atol=1e-12 * a.mean)
