"""Tooth-load solver timings (prs_geom.analysis.load_solver).

Run:  python benchmarks/bench_loads.py

Prints (medians of several repeats, as ratios; absolute times only for orientation):
* the solve time of ``forward`` on the default design with n = 20, 100, 500 engaged teeth,
  as a ratio to n = 20 (model built once, outside the timing);
* the time of ``loads_report`` at n = 20 and n = 500 (model included), and their ratio;
* forward solves per second of one batched solve of B = 1000 problems with random
  micrometre pitch errors at n = 20, against the same solver called one problem at a time
  (the baseline of the same run), and their ratio;
* z-roller samples per second (:func:`solve_loads_rollers`, all z = 10 rollers of the
  default design side by side, B = 1000 samples with +-1 um errors on every flank) with the
  default linear solver ("banded") and the previous one ("segments"), and their ratio.
"""
from __future__ import annotations

import numpy as np

from prs_geom.model.design import PRSDesign, Thread, default_design
from timing import median_time

from prs_geom.analysis.loads import (build_model, forward, gap_terms, gap_terms_rollers, loads_report, solve_loads,
                                     solve_loads_batch, solve_loads_rollers)


def design(n: int) -> PRSDesign:
    return PRSDesign(thread=Thread(engaged_teeth=n))


def main() -> None:
    print("forward solve (default design, model prepared):")
    print(f"{'teeth':>6} {'time ms':>9} {'x n=20':>8}")
    t20 = None
    for n in (20, 100, 500):
        d = design(n)
        m = build_model(d)
        t = median_time(lambda: forward(d, model=m), 9)
        t20 = t20 or t
        print(f"{n:6d} {t * 1e3:9.2f} {t / t20:8.1f}")

    print("loads_report (model included):")
    tr = {}
    for n, reps in ((20, 5), (500, 3)):
        d = design(n)
        tr[n] = median_time(lambda: loads_report(d), reps)
        print(f"{n:6d} {tr[n]:9.3f} s")
    print(f"  n=500 / n=20: {tr[500] / tr[20]:.0f} x")

    d = design(20)
    m = build_model(d)
    g_nr, g_rs = gap_terms(d)
    B = 1000
    rng = np.random.default_rng(0)
    steps = rng.normal(0.0, 1e-3, (2, B, 19))            # 1 um standard deviation per pitch
    zero = np.zeros((B, 1))
    G_nr = g_nr + np.hstack([zero, np.cumsum(steps[0], axis=1)])
    G_rs = g_rs + np.hstack([zero, np.cumsum(steps[1], axis=1)])
    F = d.loading.axial_load_n
    t_batch = median_time(lambda: solve_loads_batch(m, F, G_nr, G_rs), 5)
    k = 200
    t_scalar = median_time(lambda: [solve_loads(m, F, G_nr[i], G_rs[i]) for i in range(k)], 3) / k
    b = solve_loads_batch(m, F, G_nr, G_rs)
    print(f"batched vs one at a time (n = 20, B = {B}, 1 um pitch errors; "
          f"{int((~b.active_nr).sum() + (~b.active_rs).sum())} open teeth in all, "
          f"{int(b.barrier.sum())} samples needed the barrier, at most {int(b.iterations.max())} Newton steps):")
    print(f"  one at a time: {1.0 / t_scalar:10.0f} solves/s")
    print(f"  batched:       {B / t_batch:10.0f} solves/s   = {t_scalar * B / t_batch:.1f} x")

    d = default_design()
    m = build_model(d)
    g_nr, g_rs = gap_terms_rollers(d)
    e = np.random.default_rng(0).uniform(-1e-3, 1e-3, (B,) + g_nr.shape)
    G_nr, G_rs = g_nr + e, g_rs - 0.5 * e
    F = d.loading.axial_load_n
    t_new = median_time(lambda: solve_loads_rollers(m, F, G_nr, G_rs), 5)
    t_old = median_time(lambda: solve_loads_rollers(m, F, G_nr, G_rs, linear_solver="segments"), 2)
    r = solve_loads_rollers(m, F, G_nr, G_rs)
    print(f"z rollers side by side (default design, z = {m.z}, n = {m.n}, B = {B}, +-1 um flank errors; "
          f"at most {int(r.iterations.max())} Newton steps):")
    print(f"  linear solver 'segments' (previous): {B / t_old:8.0f} samples/s")
    print(f"  linear solver 'banded' (default):    {B / t_new:8.0f} samples/s   = {t_old / t_new:.1f} x")


if __name__ == "__main__":
    main()
