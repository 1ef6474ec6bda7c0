"""FCL per-tooth gap verification time (prs_geom.checks.fcl, docs/theory/contact.md).

Run:  python benchmarks/bench_fcl.py

Prints, for the default design and the graded example (10 rollers x 20 teeth x 2 sides = 400
comparisons, 0.01 um patch chord tolerance):
* the wall time of the full verification (best of 5) and its parts (analytic gaps and
  placements, patch meshing and BVHs, FCL distance requests), as ratios to the baseline of
  the same run: the vectorised analytic per-tooth gaps of both sides alone
  (:func:`prs_geom.analysis.contact.tooth_gaps` work, what any gap check has to do);
* the cost of one FCL distance request against building the two patch BVHs once, i.e. what
  building a BVH per contact instead of placing one by transforms would cost;
* the largest |FCL gap - designed gap| and the verdict tolerance.
Absolute times are for orientation only: this machine is shared and noisy.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from timing import best_time

from prs_geom.analysis.contact import euclidean_distance, solve_collinear, theoretical_screw, tooth_contacts
from prs_geom.checks.fcl import LOADED_FLANKS, verify_contacts
from prs_geom.model.design import default_design
from prs_geom.model.io import load_design

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def analytic_gaps(design, screw) -> None:
    """The baseline: the designed gaps of every tooth of both sides, vectorised."""
    for side, flank in LOADED_FLANKS.items():
        batch, q0, _ = tooth_contacts(design, side, flank, screw_profile=screw)
        euclidean_distance(batch, solve_collinear(batch, q0).q)


def main() -> None:
    designs = {"default": default_design(), "graded": load_design(EXAMPLES / "graded-pitch.toml")}
    print(f"{'design':>8} {'pairs':>6} {'baseline s':>11} {'verify s':>9} {'x base':>7} "
          f"{'analytic':>9} {'patches':>8} {'fcl':>8} {'us/request':>11} {'max |dg| um':>12} {'tol um':>7}")
    for name, d in designs.items():
        screw = theoretical_screw(d).profile
        t_base = best_time(lambda: analytic_gaps(d, screw), 5)
        reps = []
        t_ver = best_time(lambda: reps.append(verify_contacts(d, screw_profile=screw)), 5)
        rep = reps[-1]
        tm = rep["timings_s"]
        pairs = len(rep["comparisons"])
        per_req = tm["fcl"] / pairs
        print(f"{name:>8} {pairs:6d} {t_base:11.4f} {t_ver:9.3f} {t_ver / t_base:7.1f} "
              f"{tm['analytic'] / t_base:8.1f}x {tm['patches'] / t_base:7.1f}x {tm['fcl'] / t_base:7.1f}x "
              f"{per_req * 1e6:11.1f} {rep['max_abs_gap_difference_um']:12.2e} "
              f"{rep['difference_tolerance_mm'] * 1e3:7.4f}")
        # one BVH pair per side built once: building it per contact would cost this much more
        per_build = tm["patches"] / 2
        print(f"{'':>8} patch BVHs of one side = {per_build / per_req:.0f} distance requests; "
              f"a BVH per contact would multiply the FCL part by ~{(per_build + per_req) / per_req:.0f}; "
              f"triangles per side {np.mean([p['patch_triangles'] for p in rep['patches'].values()]):.0f}")


if __name__ == "__main__":
    main()
