"""Contact solver throughput and FCL verification time (issue 4).

Run:  python benchmarks/bench_contact.py

Prints contact solves per second of the vectorised collinear-normal Newton for batches of
increasing size (all teeth of all rollers, tiled), the same solver called one contact at a
time (the baseline of the same run) and their ratio; then the wall time of the full FCL
verification (both sides, every tooth of every roller, 0.01 um patches) and of the interference check,
each as a ratio to the vectorised solve of all 200 contacts of the default design.
"""
from __future__ import annotations

import numpy as np

from timing import best_time

from prs_geom.analysis.contact import ContactBatch, solve_collinear, tooth_contacts
from prs_geom.model.design import default_design
from prs_geom.model.io import load_design
from prs_geom.checks.fcl import verify_contacts
from prs_geom.checks.interference import interference


def tile(batch: ContactBatch, q0: np.ndarray, reps: int):
    f = {k: np.tile(getattr(batch, k), reps) for k in ("m_a", "xi_a", "m_b", "xi_b", "ox", "oy", "alpha", "z_offset")}
    return ContactBatch(batch.A, batch.B, **f), np.tile(q0, (reps, 1))


def main() -> None:
    d = load_design(__import__("pathlib").Path(__file__).parent.parent / "examples" / "graded-pitch.toml")
    batch, q0, _ = tooth_contacts(d, "screw", "upper")
    n0 = batch.n
    one = [tile(ContactBatch(batch.A, batch.B, *[getattr(batch, k)[i:i + 1] for k in
                             ("m_a", "xi_a", "m_b", "xi_b", "ox", "oy", "alpha", "z_offset")]), q0[i:i + 1], 1)
           for i in range(n0)]
    t_scalar = best_time(lambda: [solve_collinear(b, q) for b, q in one], 3)
    print(f"baseline: one contact per call: {n0 / t_scalar:10.0f} solves/s")
    print(f"{'contacts':>9} {'solves/s':>12} {'x baseline':>11}")
    t_200 = None
    for reps in (1, 10, 100):
        b, q = tile(batch, q0, reps)
        t = best_time(lambda: solve_collinear(b, q))
        if reps == 1:
            t_200 = t
        print(f"{b.n:9d} {b.n / t:12.0f} {(b.n / t) / (n0 / t_scalar):11.1f}")
    dd = default_design()
    t_fcl = best_time(lambda: verify_contacts(dd), 3)
    print(f"full FCL verification (default design): {t_fcl:.3f} s = {t_fcl / t_200:.0f} x the vectorised "
          f"solve of all {n0} contacts")
    t_int = best_time(lambda: interference(dd, "corrected"), 1)
    print(f"interference check (corrected screw, 2 um meshes): {t_int:.2f} s = {t_int / t_200:.0f} x")


if __name__ == "__main__":
    main()
