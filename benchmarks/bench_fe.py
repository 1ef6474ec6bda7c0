"""Finite-element tooth model timings (prs_geom.analysis.fe, prs_geom.analysis.fe.cache).

Run:  python benchmarks/bench_fe.py [--quick]

For the default design at the converged mesh level (``CONVERGED_LEVEL``) over its engaged
teeth (what ``--compliance fe`` uses):

1. cold: the screw, roller and nut influence matrices computed and stored in an empty
   cache folder (goal: <= 30 s on two cores), with the degrees of freedom per part;
2. warm: the same call reading the cache, in this process (median of 5) and in a fresh
   interpreter (the call alone; goal: <= 0.5 s), with that interpreter's import time;
3. the load analysis: ``analyse_loads`` with the FE model (model risk included) against the
   analytic one, as a ratio measured in the same run;
4. without ``--quick``: the 7-tooth sections of the calibration studies and the convergence
   study over levels 0, 1, 2 with the Richardson estimate (docs/theory/fe.md, Convergence).

``--quick`` skips (4). Wall times on this machine are noisy; the ratios in (3) are the
comparable numbers.
"""
from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from prs_geom.analysis.contact import analyse_contact
import numpy as np

from prs_geom.analysis.fe import CONVERGED_LEVEL, DEFAULT_TEETH, convergence_study, influence_matrices
from prs_geom.analysis.loads import analyse_loads
from prs_geom.analysis.fe.cache import cached_influence
from prs_geom.model.design import default_design

FRESH = """
import time, sys
t0 = time.perf_counter()
from prs_geom.model.design import default_design
from prs_geom.analysis.contact import analyse_contact
from prs_geom.analysis.fe.cache import cached_influence
d = default_design(); c = analyse_contact(d)
t1 = time.perf_counter()
r = cached_influence(d, c, folder=sys.argv[1])
t2 = time.perf_counter()
assert all(r.hits.values())
print(f"{t1 - t0:.3f} {t2 - t1:.3f} {'skfem' in sys.modules}")
"""


def main(quick: bool = False) -> None:
    design = default_design()
    n = design.thread.engaged_teeth
    contact = analyse_contact(design)
    print(f"influence matrices, default design, level {CONVERGED_LEVEL}, {n} teeth, {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "fe"
        t0 = time.perf_counter()
        cold = cached_influence(design, contact, folder=folder)
        t_cold = time.perf_counter() - t0
        for m in cold.influence:
            print(f"  {m.part:>7}: {m.n_dofs:7d} dofs, {m.seconds:6.2f} s")
        print(f"cold (computed and stored): {t_cold:.2f} s for {cold.influence.n_dofs} dofs (goal <= 30 s)")
        warm = []
        for _ in range(5):
            t0 = time.perf_counter()
            r = cached_influence(design, contact, folder=folder)
            warm.append(time.perf_counter() - t0)
            assert all(r.hits.values())
        print(f"warm, this process: median {statistics.median(warm) * 1e3:.1f} ms (goal <= 0.5 s)")
        out = subprocess.run([sys.executable, "-c", FRESH, str(folder)], capture_output=True, text=True, check=True)
        imports, call, skfem = out.stdout.split()
        print(f"warm, fresh interpreter: {float(call) * 1e3:.1f} ms for the call (goal <= 0.5 s) after "
              f"{float(imports):.2f} s of imports and the contact stage; scikit-fem imported: {skfem}")

        from prs_geom.analysis.fe.compliance import fe_load_model
        from prs_geom.analysis.loads import build_model

        analytic = build_model(design, contact)
        fe = fe_load_model(analytic, cold.influence)
        t0 = time.perf_counter()
        analyse_loads(design, contact, model=analytic)
        t_a = time.perf_counter() - t0
        t0 = time.perf_counter()
        analyse_loads(design, contact, model=fe, compare={"analytic": analytic, "fe": fe})
        t_f = time.perf_counter() - t0
        print(f"analyse_loads: analytic {t_a:.3f} s, FE with model risk {t_f:.3f} s: ratio {t_f / t_a:.2f}")
        print(f"cold matrices / analytic analyse_loads: {t_cold / t_a:.0f}")
    if not quick:
        t0 = time.perf_counter()
        mats = influence_matrices(design, level=CONVERGED_LEVEL, teeth=DEFAULT_TEETH, contact=contact)
        print(f"{DEFAULT_TEETH}-tooth sections (calibration studies): {time.perf_counter() - t0:.2f} s, "
              f"{mats.n_dofs} dofs")
        t0 = time.perf_counter()
        study = convergence_study(design, (0, 1, 2), teeth=DEFAULT_TEETH, contact=contact)
        print(f"convergence, levels 0-1-2 of {DEFAULT_TEETH}-tooth sections ({time.perf_counter() - t0:.1f} s): "
              f"largest change of a diagonal entry from level 1 to 2, observed order, Richardson error of level 2")
        for part in ("screw", "roller", "nut"):
            order = study.order[part]
            print(f"  {part:>7}: {study.finest_change[part] * 100:.3f} % (goal <= 0.5 %), order "
                  f"{np.nanmin(order):.2f}-{np.nanmax(order):.2f}, error <= {study.error_estimate[part].max() * 100:.3f} %")


if __name__ == "__main__":
    main(quick="--quick" in sys.argv[1:])
