"""Memory estimate against measured peaks (issue 29): does the budget hold?

Run:  python benchmarks/bench_memory.py [--quick]

For a grid of designs (engaged teeth x chord tolerance x worker processes) it prints the
up-front estimate of ``prs_geom.pipeline.plan_build`` and the measured peak of a real
``prs-geom build`` given exactly that estimate as its ``--memory-budget``: the largest
resident set of the build's whole process tree (main process, workers, resource trackers),
sampled every 20 ms from /proc by this process. A row holds when the build succeeded and
its peak stayed under the budget; a build stopped by the runtime guard (exit 3) is a row
where the estimate was too low. The ratio peak / estimate is the calibration's margin
(goal: <= 1 on every row). docs/cli.md "Memory budget" carries the table.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def measure(design_file: Path, out: Path, budget: int, workers: int) -> tuple[int, int, float]:
    """(exit code, peak bytes of the process tree, seconds) of one build."""
    from prs_geom.runtime.memwatch import process_tree_rss

    exe = str(Path(sys.executable).parent / "prs-geom")
    env = {**os.environ, "PRS_GEOM_WORKERS": str(workers)}
    t0 = time.monotonic()
    proc = subprocess.Popen([exe, "build", str(design_file), "--out", str(out), "--quiet",
                             "--memory-budget", f"{-(-budget // 1024)}K"], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    peak = 0
    while proc.poll() is None:
        peak = max(peak, process_tree_rss(proc.pid)[0])
        time.sleep(0.02)
    return proc.returncode, peak, time.monotonic() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a smaller grid")
    args = ap.parse_args()
    from prs_geom.model.errors import format_bytes
    from prs_geom.model.design import MeshSettings, default_design
    from prs_geom.model.io import save_design
    from prs_geom.pipeline import plan_build
    from dataclasses import replace

    # (teeth, tolerances): the default actuator (20 teeth, 0.01 mm) first; 1e-4 mm on 4 teeth,
    # the case where an old estimate was 40 % low
    grid = (((20, (0.01,)), (4, (0.01, 0.0001))) if args.quick else
            ((20, (0.01, 0.002, 0.001)), (4, (0.01, 0.001, 0.0001)), (40, (0.01,))))
    print(f"{'teeth':>5} {'tol mm':>7} {'workers':>7} {'estimate':>10} {'peak':>10} {'peak/est':>8} "
          f"{'exit':>4} {'s':>6}")
    worst = 0.0
    default_rows: list[tuple[int, float]] = []
    with tempfile.TemporaryDirectory() as tmpname:
        tmp = Path(tmpname)
        for n, tols in grid:
            for tol in tols:
                d = default_design()
                d = d.with_changes(name=f"t{n}", thread=replace(d.thread, engaged_teeth=n),
                                   mesh=MeshSettings(chord_tolerance_mm=tol))
                f = tmp / f"t{n}-{tol}.toml"
                save_design(d, f)
                for w in (0, 2):
                    os.environ["PRS_GEOM_WORKERS"] = str(w)
                    try:
                        planned, est = plan_build(d, 64 * 2 ** 30)
                    finally:
                        del os.environ["PRS_GEOM_WORKERS"]
                    if planned != w:
                        continue   # a design built serially whatever is asked (long designs)
                    out = tmp / f"o-{n}-{tol}-{w}"
                    code, peak, secs = measure(f, out, int(est.peak_bytes), w)
                    ratio = peak / est.peak_bytes
                    worst = max(worst, ratio)
                    if n == 20 and tol == 0.01:
                        default_rows.append((w, ratio))
                    print(f"{n:5d} {tol:7g} {w:7d} {format_bytes(est.peak_bytes):>10} {format_bytes(peak):>10} "
                          f"{ratio:8.2f} {code:4d} {secs:6.1f}", flush=True)
                    subprocess.run(["rm", "-rf", str(out)])
    print(f"worst peak / estimate {worst:.2f} (goal <= 1: the budget holds)")
    for w, ratio in default_rows:
        print(f"default build, {w} workers: estimate / peak {1 / ratio:.3f} (goal 1 to 1.1: within 10 %)")


if __name__ == "__main__":
    main()
