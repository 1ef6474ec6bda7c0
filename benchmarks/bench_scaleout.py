"""Scale-out timings (prs_geom.runtime.scaleout, prs_geom.sweep).

Run:  python benchmarks/bench_scaleout.py [--dask]

Prints wall times and the speed-up against the serial run of the same work, and checks on
the way that every backend gave the serial results bit for bit:

* a synthetic chunked study: 16 chunks of random 200 x 200 SPD solves, each chunk with its own
  SeedSequence stream (what a tolerance study's chunks look like to the backends);
* a design-space sweep of the default design, 48 points (starts 4 5, rollers 6 8 10,
  pitch 1.5 2, teeth 10 20 30 40).

joblib with one process per CPU always; with --dask also a local Dask cluster of as many
processes, its start-up included (the Dask extra must be installed). The process pool's
start-up (workers import numpy, scipy and prs_geom) is included in the first joblib run; the
second shows the warm pool.
"""
from __future__ import annotations

import sys

import numpy as np

from timing import run_timed

from prs_geom.model.design import default_design
from prs_geom.runtime.scaleout import available_cpus, plan_chunks, run_chunks, spawn_seeds
from prs_geom.sweep import sweep

SIZE = 200


def study_chunk(payload):
    seed, items = payload
    rng = np.random.default_rng(seed)
    out = np.empty((len(items), SIZE))
    for r in range(len(items)):
        a = rng.standard_normal((SIZE, SIZE))
        out[r] = np.linalg.solve(a @ a.T + SIZE * np.eye(SIZE), rng.standard_normal(SIZE))
    return out


def main() -> None:
    dask = "--dask" in sys.argv[1:]
    n = available_cpus()
    chunks = plan_chunks(16 * 25, 25)
    payloads = list(zip(spawn_seeds(1, len(chunks)), chunks))
    runs = [("serial", {"workers": 1}), (f"joblib {n} (cold)", {"workers": n}), (f"joblib {n} (warm)", {"workers": n})]
    if dask:
        runs.append((f"dask local {n}", {"dask_workers": n}))

    print(f"synthetic study: {len(chunks)} chunks x 25 solves of {SIZE} x {SIZE}, {n} CPUs")
    ref = None
    for label, kw in runs:
        (t,), res = run_timed(lambda: run_chunks(study_chunk, payloads, **kw))
        ref = ref if ref is not None else (t, res)
        same = all(np.array_equal(a, b) for a, b in zip(res, ref[1]))
        print(f"  {label:<22} {t:7.2f} s  x{ref[0] / t:5.2f}  bit-identical: {same}")

    print("sweep of the default design, 48 points")
    axes = {"starts": [4, 5], "rollers": [6, 8, 10], "pitch_mm": [1.5, 2.0], "teeth": [10, 20, 30, 40]}
    ref = None
    for label, kw in runs:
        (t,), res = run_timed(lambda: sweep(default_design(), **axes, **kw))
        ref = ref if ref is not None else (t, res)
        print(f"  {label:<22} {t:7.2f} s  x{ref[0] / t:5.2f}  bit-identical: {res.csv_text() == ref[1].csv_text()}"
              f"  ({res.count('ok')} valid)")


if __name__ == "__main__":
    main()
