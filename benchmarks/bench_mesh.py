"""Mesh build speed and memory on the default design (issue 3).

Run:  python benchmarks/bench_mesh.py

For chordal tolerances 10, 1 and 0.5 um it prints, for the whole assembly (screw, nut,
z placed rollers): triangles, build time, triangles per second, seconds per million
triangles, peak memory per triangle, and the ratio of the build time to a baseline
measured in the same run: the time numpy needs just to fill vertex and face arrays of the
same size (one cos, one sin, one multiply per vertex; one add per face index), the
practical floor for any vectorised mesher. Each figure is the best of several runs.
"""
from __future__ import annotations

import gc
import tracemalloc

import numpy as np

from timing import best_time

from prs_geom.mesh.assembly import build_assembly
from prs_geom.model.design import default_design


def build(design, tol):
    asm = build_assembly(design, tol=tol, gears=False)
    return asm.combined_arrays()


def numpy_fill(nv: int, nf: int) -> None:
    theta = np.linspace(0.0, 1.0, nv)
    V = np.empty((nv, 3))
    np.cos(theta, out=V[:, 0])
    np.sin(theta, out=V[:, 1])
    np.multiply(theta, 2.0, out=V[:, 2])
    F = np.empty((nf, 3), np.int64)
    np.add(np.arange(nf)[:, None], np.arange(3)[None, :], out=F)


def main() -> None:
    d = default_design()
    print(f"{'tol_um':>7} {'triangles':>10} {'build_s':>8} {'Mtri/s':>7} {'s/Mtri':>7} "
          f"{'fill_s':>7} {'build/fill':>10} {'bytes/tri':>9}")
    for tol in (0.01, 0.001, 0.0005):
        V, F = build(d, tol)
        nv, nf = len(V), len(F)
        del V, F
        repeats = 5 if tol >= 0.001 else 3
        t_build = best_time(lambda: build(d, tol), repeats, collect=True)
        t_fill = best_time(lambda: numpy_fill(nv, nf), repeats, collect=True)
        gc.collect()
        tracemalloc.start()
        build(d, tol)
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        print(f"{tol * 1e3:7.1f} {nf:10d} {t_build:8.3f} {nf / t_build / 1e6:7.2f} "
              f"{t_build / (nf / 1e6):7.3f} {t_fill:7.3f} {t_build / t_fill:10.2f} {peak / nf:9.0f}")


if __name__ == "__main__":
    main()
