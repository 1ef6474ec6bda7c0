"""Finite-element tooth model timings (prs_geom.analysis.fe).

Run:  python benchmarks/bench_fe.py

Prints, for the default design at the converged mesh level (``CONVERGED_LEVEL``): the
wall time to compute the screw, roller and nut influence matrices of a 7-tooth section
(the default) and of the full engaged length (20 teeth, what the width calibration
uses), with the degrees of freedom of each model. Goal: the 7-tooth matrices in <= 30 s
on two cores. The time includes the contact stage (contact points and Hertz bands).
"""
from __future__ import annotations

import time

from prs_geom.analysis.contact import analyse_contact
from prs_geom.analysis.fe import CONVERGED_LEVEL, DEFAULT_TEETH, influence_matrices
from prs_geom.model.design import default_design


def main() -> None:
    design = default_design()
    print(f"influence matrices, default design, level {CONVERGED_LEVEL}:")
    print(f"{'teeth':>6} {'part':>7} {'dofs':>8} {'time s':>8}")
    for teeth in (DEFAULT_TEETH, design.thread.engaged_teeth):
        t0 = time.perf_counter()
        contact = analyse_contact(design)
        mats = influence_matrices(design, level=CONVERGED_LEVEL, teeth=teeth, contact=contact)
        total = time.perf_counter() - t0
        for m in mats:
            print(f"{teeth:6d} {m.part:>7} {m.n_dofs:8d} {m.seconds:8.2f}")
        print(f"{teeth:6d} {'all':>7} {mats.n_dofs:8d} {total:8.2f}")


if __name__ == "__main__":
    main()
