"""Tolerance-study throughput (prs_geom.studies, prs_geom.analysis.tolerance).

Run:  python benchmarks/bench_tolerance.py [SAMPLES]

Prints, for the default design (20 teeth, 10 rollers side by side, flank tolerance 1 um,
roller diameter 2 um, nut eccentricity 2 um, design load):
* Monte Carlo samples per second of one study run in this process (workers=1) and with
  joblib on every CPU, and their ratio (same numbers: the script checks they are identical);
* z-roller forward solves per second, batched (one call for all samples) against the same
  solver called one sample at a time (the baseline of the same run), and their ratio.
Absolute rates are for orientation only: this machine is shared and noisy.
"""
from __future__ import annotations

import statistics
import sys

import numpy as np

from timing import run_timed

from prs_geom import studies
from prs_geom.analysis import tolerance as T
from prs_geom.analysis.contact import analyse_contact
from prs_geom.analysis.loads import build_model
from prs_geom.model.design import Tolerances, default_design
from prs_geom.runtime.scaleout import available_cpus


def timed(fn, repeats=3):
    """Median seconds of ``repeats`` calls and the last result."""
    times, out = run_timed(fn, repeats)
    return statistics.median(times), out


def main(samples: int = 2000) -> None:
    d = default_design()
    c = analyse_contact(d)
    m = build_model(d, c)
    tol = Tolerances(flank_um=1.0, roller_diameter_um=2.0, nut_eccentricity_um=2.0, samples=samples, seed=1)

    def study(workers):
        return studies.tolerance_study(d, tol, contact=c, model=m, importance=False,
                                       execution=studies.Execution(workers=workers))

    study(available_cpus())                                   # start the worker pool once
    t1, s1 = timed(lambda: study(1))
    tn, sn = timed(lambda: study(available_cpus()))
    same = all(np.array_equal(getattr(s1.stats, k), getattr(sn.stats, k)) for k in ("worst_nr", "worst_rs"))
    print(f"tolerance study, default design, {samples} samples, z = {d.roller.count} rollers side by side:")
    print(f"  in this process:        {samples / t1:10.0f} samples/s")
    print(f"  joblib, {available_cpus()} workers:      {samples / tn:10.0f} samples/s   = {t1 / tn:.2f} x "
          f"(identical numbers: {same})")

    em = T.error_model(d, c, tol)
    prob = T.study_problem(d, m, em, [1.0])
    B = 1000
    x = em.sample(np.random.SeedSequence(3), B)
    F = d.loading.axial_load_n
    tb, _ = timed(lambda: T.solve_samples(prob, x, F))
    k = 50
    ts, _ = timed(lambda: [T.solve_samples(prob, x[i:i + 1], F) for i in range(k)])
    ts /= k
    print(f"z-roller forward solves (B = {B}):")
    print(f"  one at a time: {1.0 / ts:10.0f} solves/s")
    print(f"  batched:       {B / tb:10.0f} solves/s   = {ts * B / tb:.1f} x")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 2000)
