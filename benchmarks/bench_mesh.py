"""Thread mesh generation speed and memory on the default design (issues 3 and 17).

Run:  python benchmarks/bench_mesh.py [--build] [--wall]

For chordal tolerances 10, 1 and 0.1 um it times :func:`prs_geom.mesh.thread.thread_mesh`
generating the three part meshes as the build makes them
(:func:`prs_geom.mesh.assembly.build_part`: the screw with the theoretical profile of the
contact analysis, the roller, the nut, each at its part chord tolerance) and compares the
time with a baseline measured in the same run: :func:`numpy_fill` of vertex and face arrays
of the same sizes (one cos, one sin, one multiply per vertex; one add per face index), the
practical floor of any vectorised mesher. The ratio is per *generated* triangle: the
placed triangles (screw, nut and the roller placed ``z`` times, as the assembly shows them;
what earlier versions of this benchmark counted: the roller's triangles z times over) are
stated beside them. Both counts are of the thread meshes as generated, before
the datum mark cut (a few dozen triangles more per part).

Columns: generated and placed triangles, mesh time, fill time, mesh / fill, ns per
generated triangle, and the peak traced memory (tracemalloc) of the three generations and
of the three fills (one part after the other, so the largest part sets it); per part the
same, with the peaks per triangle. Times are the best of several runs (more for the small
meshes, whose times are short), mesh and fill runs alternating so that both see the same
machine load, in CPU time (see :data:`CLOCK`); the ratio is the figure to compare across
machines. ``--build`` adds the rest of one part build at 10 and 1 um: the datum mark cut
(manifold3d) and the mesh report (deviation sampling, trimesh checks).
"""
from __future__ import annotations

import gc
import sys
import time
import tracemalloc

import numpy as np

from prs_geom.analysis.contact import theoretical_screw
from prs_geom.geometry.datum import datum_mark
from prs_geom.geometry.frames import FIRST_MID_PITCHES, part_warps, screw_z_range, thread_length
from prs_geom.geometry.profiles import ThreadProfiles
from prs_geom.mesh.thread import cut_datum_mark, mesh_report, part_chord_tolerance, thread_mesh
from prs_geom.model.design import default_design

TOLERANCES_MM = (0.01, 0.001, 0.0001)
#: The clock of every timing: CPU time of this process. On a shared machine wall time also
#: counts the waits for a core, which decide the short (millisecond) runs more than the work;
#: mesher and fill are single-threaded numpy either way. ``--wall`` times wall clock instead.
CLOCK = time.process_time
PARTS = ("screw", "roller", "nut")


def numpy_fill(nv: int, nf: int) -> None:
    theta = np.linspace(0.0, 1.0, nv)
    V = np.empty((nv, 3))
    np.cos(theta, out=V[:, 0])
    np.sin(theta, out=V[:, 1])
    np.multiply(theta, 2.0, out=V[:, 2])
    F = np.empty((nf, 3), np.int64)
    np.add(np.arange(nf)[:, None], np.arange(3)[None, :], out=F)


def part_calls(design, tol: float) -> dict[str, tuple[tuple, dict]]:
    """thread_mesh arguments of the three parts, as build_part passes them."""
    prof = ThreadProfiles.from_design(design)
    screw = theoretical_screw(design).profile
    p = design.thread.pitch_mm
    warps = part_warps(design)
    lo, hi = screw_z_range(design)
    length = thread_length(design)
    return {
        "screw": ((screw, lo, hi, part_chord_tolerance(screw, tol), FIRST_MID_PITCHES["screw"] * p,
                   warps["screw"]), {}),
        "roller": ((prof.roller, 0.0, length, part_chord_tolerance(prof.roller, tol),
                    FIRST_MID_PITCHES["roller"] * p, warps["roller"]), {}),
        "nut": ((prof.nut, 0.0, length, part_chord_tolerance(prof.nut, tol), FIRST_MID_PITCHES["nut"] * p,
                 warps["nut"]), {"body_radius": 0.5 * design.nut.outer_diameter_mm}),
    }


def best_pair(fa, fb, repeats: int) -> tuple[float, float]:
    """Best seconds of ``fa`` and of ``fb`` over ``repeats`` alternating runs."""
    ta = tb = float("inf")
    for _ in range(repeats):
        for fn, is_a in ((fa, True), (fb, False)):
            gc.collect()
            t0 = CLOCK()
            fn()
            dt = CLOCK() - t0
            if is_a:
                ta = min(ta, dt)
            else:
                tb = min(tb, dt)
    return ta, tb


def peak_bytes(fn) -> int:
    gc.collect()
    tracemalloc.start()
    fn()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak


def bench_generation(design, tol: float, repeats: int) -> dict:
    calls = part_calls(design, tol)
    meshes = {name: thread_mesh(*a, **kw) for name, (a, kw) in calls.items()}
    sizes = {name: (len(m.vertices), len(m.faces)) for name, m in meshes.items()}
    del meshes

    def mesh_all() -> None:
        for a, kw in calls.values():
            thread_mesh(*a, **kw)

    def fill_all() -> None:
        for nv, nf in sizes.values():
            numpy_fill(nv, nf)

    t_mesh, t_fill = best_pair(mesh_all, fill_all, repeats)
    per_part = {}
    for name, (a, kw) in calls.items():
        nv, nf = sizes[name]
        t_part, t_part_fill = best_pair(lambda: thread_mesh(*a, **kw), lambda: numpy_fill(nv, nf), repeats)
        per_part[name] = {"t_mesh": t_part, "t_fill": t_part_fill, "peak": peak_bytes(lambda: thread_mesh(*a, **kw)),
                          "peak_fill": peak_bytes(lambda: numpy_fill(nv, nf))}
    generated = sum(nf for _, nf in sizes.values())
    placed = sizes["screw"][1] + sizes["nut"][1] + design.roller.count * sizes["roller"][1]
    return {"tol": tol, "sizes": sizes, "generated": generated, "placed": placed, "t_mesh": t_mesh,
            "t_fill": t_fill, "per_part": per_part, "peak": peak_bytes(mesh_all), "peak_fill": peak_bytes(fill_all)}


def bench_build(design, tol: float, repeats: int) -> None:
    """thread_mesh against the rest of one part build (datum cut, mesh report)."""
    for name, (a, kw) in part_calls(design, tol).items():
        tm = thread_mesh(*a, **kw)
        mark = datum_mark(tm.profile, tm.z_lo, tm.body_radius)
        cut = cut_datum_mark(tm, mark)
        t = {"thread_mesh": min(_timed(lambda: thread_mesh(*a, **kw)) for _ in range(repeats)),
             "cut_datum_mark": min(_timed(lambda: cut_datum_mark(tm, mark)) for _ in range(repeats)),
             "mesh_report": min(_timed(lambda: mesh_report(cut)) for _ in range(repeats))}
        print(f"{tol * 1e3:7.1f} {name:>7} " + " ".join(f"{k} {v * 1e3:8.1f} ms" for k, v in t.items()))


def _timed(fn) -> float:
    gc.collect()
    t0 = CLOCK()
    fn()
    return CLOCK() - t0


def main(argv: list[str]) -> None:
    global CLOCK
    if "--wall" in argv:
        CLOCK = time.perf_counter
    d = default_design()
    print(f"default design, {d.roller.count} rollers; {'wall' if '--wall' in argv else 'CPU'} times, "
          f"the best of alternating runs\n")
    print(f"{'tol_um':>7} {'generated':>10} {'placed':>10} {'mesh_s':>8} {'fill_s':>8} {'mesh/fill':>9} "
          f"{'ns/tri':>7} {'peak_MB':>8} {'fill_MB':>8}")
    rows = []
    for tol in TOLERANCES_MM:
        r = bench_generation(d, tol, {0.01: 25, 0.001: 9}.get(tol, 3))
        rows.append(r)
        print(f"{tol * 1e3:7.1f} {r['generated']:10d} {r['placed']:10d} {r['t_mesh']:8.4f} {r['t_fill']:8.4f} "
              f"{r['t_mesh'] / r['t_fill']:9.2f} {r['t_mesh'] / r['generated'] * 1e9:7.0f} "
              f"{r['peak'] / 2**20:8.1f} {r['peak_fill'] / 2**20:8.1f}")
    print(f"\nper part\n{'tol_um':>7} {'part':>7} {'vertices':>9} {'triangles':>10} {'mesh_s':>8} {'fill_s':>8} "
          f"{'mesh/fill':>9} {'peak_MB':>8} {'B/tri':>6} {'fill_B/tri':>10}")
    for r in rows:
        for name in PARTS:
            nv, nf = r["sizes"][name]
            q = r["per_part"][name]
            print(f"{r['tol'] * 1e3:7.1f} {name:>7} {nv:9d} {nf:10d} {q['t_mesh']:8.4f} {q['t_fill']:8.4f} "
                  f"{q['t_mesh'] / q['t_fill']:9.2f} {q['peak'] / 2**20:8.1f} {q['peak'] / nf:6.0f} "
                  f"{q['peak_fill'] / nf:10.0f}")
    if "--build" in argv:
        print("\npart build beyond thread_mesh (best of 3)")
        for tol in (0.01, 0.001):
            bench_build(d, tol, 3)


if __name__ == "__main__":
    main(sys.argv[1:])
