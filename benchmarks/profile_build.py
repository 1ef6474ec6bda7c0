"""Where a build's CPU time goes (issue 36): the default build run serially under cProfile.

Run:  python benchmarks/profile_build.py [DESIGN] [--top N]

Prints the CPU time of each stage of the build and of each background job (the jobs a build
runs in worker processes: the FCL and interference checks, the mesh checks, the drawings and
the plots; here in this process, so that one profile sees them all), the imports, and the
functions with the most time of their own. With ``PRS_GEOM_WORKERS=0`` the build runs every job
in this process (a stage that takes a job includes its time); the stage times of a parallel build (report.json ``timings_s``) are inflated
where the workers share the cores, which is why this profile is serial. Figures are CPU seconds
of this run; compare them within one run, not across machines.
"""
from __future__ import annotations

import argparse
import cProfile
import os
import pstats
import sys
import tempfile
import time
from pathlib import Path

#: Functions whose cumulative time is one stage's or one background job's work.
PARTS = {
    "stage_contact": "contact (analytic)", "stage_gears": "gears", "stage_loads": "loads",
    "stage_rating": "rating", "stage_meshes": "meshes (meshing and mesh files)",
    "stage_mechanism": "mechanism and parts list", "stage_manufacturing": "manufacturing (sheets, DXF)",
    "stage_html": "report.html", "checks_job": "job: FCL and interference checks",
    "mesh_checks_job": "job: mesh checks", "write_all_drawings": "job: drawings (DXF, PDF)",
    "plot_detached": "job: plots", "_find_and_load": "imports",
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("design", nargs="?", help="design file (default: the built-in default design)")
    ap.add_argument("--top", type=int, default=15, help="functions listed by their own time")
    args = ap.parse_args()
    os.environ["PRS_GEOM_WORKERS"] = "0"
    from prs_geom import cli

    argv = ["build", *([args.design] if args.design else []), "--quiet"]
    with tempfile.TemporaryDirectory() as tmp:
        prof = cProfile.Profile()
        t0, c0 = time.perf_counter(), time.process_time()
        prof.enable()
        code = cli.main([*argv, "--out", str(Path(tmp) / "out")])
        prof.disable()
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    if code != 0:
        sys.exit(f"the build failed with exit code {code}")
    stats = pstats.Stats(prof)
    cumulative: dict[str, float] = {}
    for (_, _, name), (_, _, _, cum, _) in stats.stats.items():   # type: ignore[attr-defined]
        if name in PARTS:
            cumulative[name] = max(cumulative.get(name, 0.0), cum)
    print(f"serial build: wall {wall:.2f} s, CPU {cpu:.2f} s")
    for name, label in PARTS.items():
        if name in cumulative:
            print(f"  {label:38s} {cumulative[name]:7.2f} s CPU")
    print(f"functions by their own time (top {args.top}):")
    stats.sort_stats("tottime").print_stats(args.top)


if __name__ == "__main__":
    main()
