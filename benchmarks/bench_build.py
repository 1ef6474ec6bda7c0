"""Whole-build speed and memory (issue 17), every figure a ratio to a baseline of the same run.

Run:  python benchmarks/bench_build.py [--quick]

Prints

1. builds of the default design, the graded example and the 4-start, 7-roller example
   (``prs-geom build`` in a fresh interpreter, median of 3): wall and CPU time (the build's
   and its workers'), peak memory, the ratio to the **import baseline**
   ``python -c "import numpy, trimesh"`` timed in the same run (median of 3; goal for the
   default build: <= 6, issue 36) and to the **floor** of the build's own output (numpy
   filling its triangle count and ``tofile`` of its bytes), each build with an empty stage
   cache; the default build's split by stage (``timings_s``); rebuilds of the default design
   into the same folder with the stage cache of its cold build, after changing only
   ``loading.axial_load_n`` (20 -> 20.5, 21, 21.5 kN, which size the same flange bolt; goal
   <= 4 x the import baseline) and with nothing changed; and, for comparison with earlier notes only, the earlier
   "meshing plus every exporter" baseline (:data:`EXPORTERS`), which grows with every slow
   exporter and so cannot show one;
2. ``prs-geom --help`` and ``prs-geom init`` against ``python -c "import numpy"`` (goal
   <= 1.5 x);
3. scaling with engaged teeth (20, 100, 200): build time and peak memory, ratio to n = 20
   (goal: n = 200 <= 10 x the n = 20 build, under 1 GB);
4. scaling with chord tolerance (10, 1, 0.1 um) of the meshing plus mesh-file writing job
   (the baseline of 1, in a fresh interpreter): time and peak memory, ratio to 10 um;
5. the console and interrupts (issue 28): the longest silent gap on stderr of a default
   build with its progress display in plain-line mode, from the first line to the exit
   (goal <= 2 s), and the delay from SIGINT to the exit of a build interrupted at several
   points, sent to the main process only and to the whole process group (goal: prompt,
   well under the 16 s a build once took; the exit code must be 130).

``--quick`` drops n = 200 and 0.1 um (the heavy cases) and uses one repetition. The package
is byte-compiled first, as ``pip install`` leaves it (:func:`compiled`).
Peak memory is the largest sum, over the build's process tree (the main process and its
workers), of the proportional set size (psutil, sampled every 20 ms): what the build holds
at once, shared library pages counted once. CPU time is summed over that tree too. Set
``PRS_GEOM_WORKERS=0`` to measure the serial build.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from timing import best_time  # noqa: E402

from prs_geom.pipeline import STAGES  # noqa: E402

#: Runs ``prs-geom ARGV`` in this interpreter's environment (its time and memory are watched
#: from outside, :func:`watch_tree`).
CHILD = ("import sys\n"
         "from prs_geom import cli\n"
         "sys.exit(cli.main(sys.argv[1:]))\n")
#: The import baseline of issue 36: what any numpy-and-trimesh tool pays before it works.
IMPORT_BASELINE = [sys.executable, "-c", "import numpy, trimesh"]
#: The designs of section 1: the default, the graded example and the 4-start, 7-roller one.
DESIGNS = {"default": None, "graded example": "graded-pitch.toml", "4-start 7-roller": "four-start-seven-rollers.toml"}


#: Runs :func:`mesh_job` at chord tolerance argv[1] (mm) into the new folder argv[2].
MESH_CHILD = ("import sys\n"
              f"sys.path.insert(0, {str(HERE)!r})\n"
              "from pathlib import Path\n"
              "from bench_build import mesh_job\n"
              "out = Path(sys.argv[2]); out.mkdir()\n"
              "mesh_job(float(sys.argv[1]), out)\n")


def mesh_job(tol: float | None, out: Path) -> None:
    """The baseline job: mesh the default assembly (theoretical screw, chord tolerance
    ``tol`` mm, the design's when None) and write its mesh exports into ``out``."""
    from prs_geom.analysis.contact import theoretical_screw
    from prs_geom.exports.meshes import export_meshes
    from prs_geom.mesh.assembly import build_assembly
    from prs_geom.model.design import default_design
    from prs_geom.model.io import design_hash

    d = default_design()
    asm = build_assembly(d, tol=tol, screw_profile=theoretical_screw(d).profile)
    export_meshes(asm, out, design_hash(d), None)


#: Every exporter of a default build, by module and attribute: the functions that mesh for
#: the files or write them (the issue's "meshing plus file writing"; QUEUE: "file writing
#: means every exporter the default build runs"). ``build_assembly`` is counted where the
#: meshes stage calls it, not inside the interference check (bound before the patch).
EXPORTERS = [("prs_geom.mesh.assembly", "build_assembly", "meshing"),
             ("prs_geom.exports.meshes", "export_meshes", "mesh files"),
             ("prs_geom.exports.mechanism_drawing", "write_all_drawings", "drawings"),
             ("prs_geom.exports.dxf", "write_dxf", "sheets and DXF"),
             ("prs_geom.exports.sheets", "write_xlsx", "sheets and DXF"),
             ("prs_geom.exports.sheets", "sheet_csv", "sheets and DXF"),
             ("prs_geom.exports.sheets", "inspection_csv", "sheets and DXF"),
             ("prs_geom.pipeline", "BuildContext.write_text", "sheets and DXF"),
             ("prs_geom.exports.plots", "plot_loads", "plots"),
             ("prs_geom.exports.plots", "plot_rating", "plots"),
             ("prs_geom.exports.plots", "plot_tolerance", "plots"),
             ("prs_geom.exports.bom", "parts_list_csv", "sheets and DXF"),
             ("prs_geom.exports.bom", "write_parts_list_xlsx", "sheets and DXF"),
             ("prs_geom.exports.html", "write_html", "report.html")]

#: A serial build (``PRS_GEOM_WORKERS=0``) of argv with every exporter timed (the outermost
#: call only, so that nested exporters count once); prints the seconds per group as JSON.
EXPORT_CHILD = ("import importlib, json, os, sys, time\n"
                f"sys.path.insert(0, {str(HERE)!r})\n"
                "from bench_build import EXPORTERS\n"
                "import prs_geom.checks.interference, prs_geom.pipeline\n"
                "from prs_geom import cli\n"
                "spent, depth = {}, [0]\n"
                "def timed(fn, group):\n"
                "    def wrapper(*a, **k):\n"
                "        depth[0] += 1\n"
                "        t0 = time.perf_counter()\n"
                "        try:\n"
                "            return fn(*a, **k)\n"
                "        finally:\n"
                "            depth[0] -= 1\n"
                "            if depth[0] == 0:\n"
                "                spent[group] = spent.get(group, 0.0) + time.perf_counter() - t0\n"
                "    return wrapper\n"
                "for module, attr, group in EXPORTERS:\n"
                "    owner = importlib.import_module(module)\n"
                "    *path, name = attr.split('.')\n"
                "    for part in path:\n"
                "        owner = getattr(owner, part)\n"
                "    setattr(owner, name, timed(getattr(owner, name), group))\n"
                "t0 = time.perf_counter()\n"
                "code = cli.main(sys.argv[1:])\n"
                "print('EXPORT_S', json.dumps({'wall': time.perf_counter() - t0, **spent}), file=sys.stderr)\n"
                "sys.exit(code)\n")


def exporters_baseline(out: Path) -> tuple[float, dict[str, float]]:
    """Seconds spent meshing for the files and writing them in a serial default build (a
    fresh interpreter): total and per group."""
    import os

    if out.exists():
        shutil.rmtree(out)
    env = {**os.environ, "PRS_GEOM_WORKERS": "0"}
    r = subprocess.run([sys.executable, "-c", EXPORT_CHILD, "build", "--out", str(out), "--quiet"],
                       capture_output=True, text=True, env=env)
    if r.returncode != 0:
        raise SystemExit(f"baseline build failed ({r.returncode}):\n{r.stderr[-2000:]}")
    line = next(x for x in r.stderr.splitlines() if x.startswith("EXPORT_S"))
    groups = json.loads(line.split(None, 1)[1])
    groups.pop("wall")
    return sum(groups.values()), groups


def watch_tree(argv: list[str], pss: bool = True) -> tuple[float, float, int, int, str]:
    """Run ``argv`` and watch its process tree (psutil, every 20 ms) until it exits:
    (wall s, CPU s, peak PSS of the tree in kB, peak RSS of its largest process in kB,
    stderr). PSS (proportional set size) counts a page shared by n processes 1/n in each,
    so the sum is what the tree holds at once; the CPU time is the sum of each process's
    last observed user + system time (a process that lives less than 20 ms may be missed:
    the build's workers live for the whole build). resource.getrusage(RUSAGE_CHILDREN)
    misses worker processes that are not reaped before the parent reads it, as the loky
    workers are not, and so measured too little. Reading PSS (/proc/<pid>/smaps) costs CPU
    on a 2-core machine: ``pss=False`` reads the cheap RSS only (peak PSS then 0), for the
    timed runs."""
    import psutil

    t0 = time.perf_counter()
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    root = psutil.Process(proc.pid)
    cpu: dict[int, float] = {}
    pss_peak = rss_peak = 0
    while proc.poll() is None:
        try:
            tree = [root] + root.children(recursive=True)
        except psutil.Error:
            break
        held = 0
        for q in tree:
            try:
                info, times = (q.memory_full_info() if pss else q.memory_info()), q.cpu_times()
            except psutil.Error:
                continue
            held += info.pss if pss else 0
            rss_peak = max(rss_peak, info.rss)
            cpu[q.pid] = times.user + times.system
        pss_peak = max(pss_peak, held)
        time.sleep(0.02 if pss else 0.05)
    err = proc.stderr.read()
    proc.wait()
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} failed ({proc.returncode}):\n{err[-2000:]}")
    return wall, sum(cpu.values()), pss_peak // 1024, rss_peak // 1024, err


def run_child(argv: list[str], code: str = CHILD) -> tuple[float, int]:
    """(wall seconds, peak kB) of ``prs-geom argv`` (or of ``code`` with ``argv``) in a fresh
    interpreter; the peak is that of the process tree's PSS (:func:`watch_tree`)."""
    wall, _, peak, _, _ = watch_tree([sys.executable, "-c", code, *argv])
    return wall, peak


def child_cpu(argv: list[str], out: Path) -> tuple[float, float, int]:
    """(wall s, CPU s, peak kB) of one ``prs-geom argv`` in a fresh interpreter, ``out``
    emptied first (:func:`watch_tree`)."""
    if out.exists():
        shutil.rmtree(out)
    wall, cpu, _, _, _ = watch_tree([sys.executable, "-c", CHILD, *argv], pss=False)
    return wall, cpu, 0


def median(values: list[float]) -> float:
    v = sorted(values)
    return v[len(v) // 2] if len(v) % 2 else 0.5 * (v[len(v) // 2 - 1] + v[len(v) // 2])


def import_baseline(repeats: int) -> float:
    """Median wall seconds of ``python -c "import numpy, trimesh"`` (:data:`IMPORT_BASELINE`)."""
    return median([best_time(lambda: subprocess.run(IMPORT_BASELINE, check=True, capture_output=True), 1)
                   for _ in range(repeats)])


def floor_seconds(triangles: int, nbytes: int, tmp: Path) -> float:
    """The physical floor of a build's output: numpy filling ``triangles`` float32 triangles
    (9 coordinates each, from a vectorised expression) and ``tofile`` of ``nbytes`` bytes;
    best of 3."""
    import numpy as np

    def job() -> None:
        idx = np.arange(triangles * 9, dtype=np.float32)
        tri = (np.sin(idx) * 50.0).reshape(triangles, 3, 3)
        np.resize(tri.view(np.uint8).ravel(), nbytes).tofile(tmp / "floor.bin")

    return best_time(job, 3)


def fresh_cache(tmp: Path) -> Path:
    """Point the builds of this run at a new, empty stage and FE cache (``$PRS_GEOM_CACHE``)."""
    folder = Path(tempfile.mkdtemp(prefix="cache-", dir=tmp))
    os.environ["PRS_GEOM_CACHE"] = str(folder)
    os.environ["PRS_GEOM_STAGE_CACHE"] = "1"
    return folder


def rebuild_ratios(tmp: Path, base: float, repeats: int) -> None:
    """Rebuilds of the default design into one folder with a warm stage cache: after a load
    change (the goal of issue 36: <= 4 x the import baseline) and with nothing changed."""
    fresh_cache(tmp)
    out = tmp / "rebuild"
    design = tmp / "load.toml"
    subprocess.run([sys.executable, "-m", "prs_geom", "init", "--out", str(design), "--quiet"], check=True)
    text = design.read_text(encoding="utf-8")
    child_cpu(["build", str(design), "--out", str(out), "--quiet"], out)        # cold: fills the cache
    loads, same = [], []
    for k in range(repeats):
        design.write_text(text.replace("axial_load_n = 20000.0", f"axial_load_n = {20500.0 + 500.0 * k}"),
                          encoding="utf-8")
        # timed without the PSS sampler, whose reads of /proc/<pid>/smaps take CPU from a
        # 1-2 s build on a 2-core machine (as for the timed cold builds, child_cpu)
        loads.append(watch_tree([sys.executable, "-c", CHILD, "build", str(design), "--out", str(out), "--quiet"],
                                pss=False)[0])
        same.append(watch_tree([sys.executable, "-c", CHILD, "build", str(design), "--out", str(out), "--quiet"],
                               pss=False)[0])
    reused = json.loads((out / ".prs-geom-manifest.json").read_text(encoding="utf-8")).get("reused_from_cache")
    w, p = median(loads), median(same)
    print(f"   default, rebuilt after a load change   wall {w:6.2f} s; wall / import {w / base:5.1f} (goal <= 4)")
    print(f"   default, rebuilt with nothing changed  wall {p:6.2f} s; wall / import {p / base:5.1f}; "
          f"reused {len(reused or [])} of {len(STAGES)} stages")


def build_ratios(tmp: Path, repeats: int) -> None:
    """Section 1: per design of :data:`DESIGNS`, the median of ``repeats`` cold builds (wall,
    CPU, peak), its ratio to the import baseline measured in this run (goal: the default
    build <= 6 x) and to the floor of its own output (:func:`floor_seconds`)."""
    root = HERE.parent / "examples"
    base = import_baseline(max(repeats, 3))
    print(f"1. builds: import baseline (python -c 'import numpy, trimesh', median) {base:.3f} s")
    for label, example in DESIGNS.items():
        out = tmp / label.replace(" ", "_")
        argv = ["build", *([str(root / example)] if example else []), "--out", str(out), "--quiet"]
        runs = []
        for _ in range(repeats):
            fresh_cache(tmp)            # a cold build: nothing to reuse
            runs.append(child_cpu(argv, out))
        wall, cpu = median([r[0] for r in runs]), median([r[1] for r in runs])
        fresh_cache(tmp)
        shutil.rmtree(out)
        peak = run_child(argv)[1]       # one more cold build, its memory watched (not timed)
        report = json.loads((out / "report.json").read_text(encoding="utf-8"))
        tris = int(report["assembly"]["triangles"])
        nbytes = sum(f.stat().st_size for f in out.rglob("*") if f.is_file())
        floor = floor_seconds(tris, nbytes, tmp)
        goal = " (goal <= 6)" if example is None else ""
        print(f"   {label:18s} wall {wall:6.2f} s, CPU {cpu:6.2f} s, peak {peak / 1024:5.0f} MB; "
              f"wall / import {wall / base:5.1f}{goal}; floor ({tris} triangles, {nbytes / 1e6:.0f} MB) "
              f"{floor:.3f} s, wall / floor {wall / floor:5.1f}")
        if example is None:
            for groups in ("meshes", "sheets"):
                o = tmp / f"only_{groups}"
                w = median([(fresh_cache(tmp), child_cpu(["build", "--only", groups, "--out", str(o), "--quiet"], o))
                            [1][0] for _ in range(repeats)])
                print(f"   default --only {groups:8s} wall {w:6.2f} s; wall / import {w / base:5.1f}")
            stages = report["timings_s"]
            print("   default build, stage work (s, wherever it ran; with workers the sum exceeds the wall):")
            for name, sec in stages.items():
                print(f"     {name:14s} {sec:7.3f} s")
            rebuild_ratios(tmp, base, repeats)


def best_child(argv: list[str], repeats: int, out: Path | None = None, code: str = CHILD) -> tuple[float, int]:
    best = (float("inf"), 0)
    for _ in range(repeats):
        if out is not None and out.exists():
            shutil.rmtree(out)
        wall, peak = run_child(argv, code)
        best = (min(best[0], wall), max(best[1], peak))
    return best


def teeth_design(tmp: Path, teeth: int) -> Path:
    """The default design with ``teeth`` engaged teeth (screw length by the default rule)."""
    from dataclasses import replace

    from prs_geom.model.design import default_design
    from prs_geom.model.io import dumps_toml

    d = default_design()
    d = replace(d, name=f"teeth{teeth}", thread=replace(d.thread, engaged_teeth=teeth),
                screw=replace(d.screw, length_mm=None))
    path = tmp / f"teeth{teeth}.toml"
    path.write_text(dumps_toml(d), encoding="utf-8")
    return path


def silent_gap(tmp: Path) -> tuple[float, float, int]:
    """(longest gap between two stderr lines after the first, wall time, lines) of a default
    build with the plain-line progress display (stderr is a pipe)."""
    import threading

    exe = str(Path(sys.executable).parent / "prs-geom")
    out = tmp / "gap"
    t0 = time.monotonic()
    proc = subprocess.Popen([exe, "build", "--out", str(out)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)
    stamps: list[float] = []

    def read() -> None:
        assert proc.stderr is not None
        for _ in proc.stderr:
            stamps.append(time.monotonic())

    reader = threading.Thread(target=read)
    reader.start()
    proc.wait()
    end = time.monotonic()
    reader.join()
    shutil.rmtree(out, ignore_errors=True)
    # the stage table and "wrote ..." come at the end together; the process exit closes the last gap
    points = stamps + [end]
    gaps = [b - a for a, b in zip(points, points[1:])]
    return max(gaps), end - t0, len(stamps)


def interrupt_delay(tmp: Path, after_s: float, group: bool) -> tuple[float, int]:
    """(seconds from SIGINT to exit, exit code) of a default build interrupted ``after_s``
    seconds after its start, by a signal to the main process or to its process group."""
    import os
    import signal

    exe = str(Path(sys.executable).parent / "prs-geom")
    out = tmp / "sigint"

    def child_setup() -> None:
        os.setsid()
        signal.signal(signal.SIGINT, signal.SIG_DFL)

    proc = subprocess.Popen([exe, "build", "--out", str(out), "--quiet"], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, preexec_fn=child_setup)
    time.sleep(after_s)
    t0 = time.monotonic()
    if group:
        os.killpg(proc.pid, signal.SIGINT)
    else:
        os.kill(proc.pid, signal.SIGINT)
    code = proc.wait()
    delay = time.monotonic() - t0
    shutil.rmtree(out, ignore_errors=True)
    return delay, code


def compiled() -> None:
    """Byte-compile the prs_geom package being measured, as ``pip install`` (README) leaves
    it. A checkout installed in editable mode and run with ``PYTHONDONTWRITEBYTECODE`` set
    (this machine's environment) would otherwise compile its 200 modules from source in
    every build, 0.13 s that an installed package does not spend (numpy and trimesh of the
    import baseline are compiled too)."""
    import compileall

    import prs_geom

    compileall.compile_dir(str(Path(prs_geom.__file__).parent), quiet=1)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="skip the heavy cases, one repetition")
    ap.add_argument("--builds-only", action="store_true", help="section 1 only (the build ratios)")
    args = ap.parse_args()
    reps = 1 if args.quick else 3
    compiled()
    with tempfile.TemporaryDirectory() as tmpname:
        tmp = Path(tmpname)
        build_ratios(tmp, 3)
        # the later sections measure cold builds (the same design again and again): no stage cache
        os.environ["PRS_GEOM_STAGE_CACHE"] = "0"
        if args.builds_only:
            return
        out = tmp / "default"
        wall, _ = best_child(["build", "--out", str(out), "--quiet"], reps, out)
        exporters = min((exporters_baseline(tmp / "exporters") for _ in range(reps)), key=lambda x: x[0])
        # kept for comparison with earlier notes: a baseline that grows with every slow
        # exporter, so it cannot show that one is slow (issue 36)
        print(f"   (earlier baseline) meshing + every exporter, serial, timed in place {exporters[0]:.2f} s: "
              + ", ".join(f"{k} {v:.2f}" for k, v in exporters[1].items()) + f"; best build / that "
              f"{wall / exporters[0]:.2f}")

        # alternated, best of 15 each: start-up times of 0.1-0.2 s are at the mercy of the machine
        exe = str(Path(sys.executable).parent / "prs-geom")
        jobs = {"python -c 'import numpy'": [sys.executable, "-c", "import numpy"],
                "prs-geom --help": [exe, "--help"], "prs-geom init": [exe, "init"]}
        best = {k: float("inf") for k in jobs}
        for _ in range(15):
            for k, argv in jobs.items():
                best[k] = min(best[k], best_time(lambda: subprocess.run(argv, check=True, capture_output=True), 1))
        numpy_s = best["python -c 'import numpy'"]
        print("2. start-up (best of 15, alternated)")
        print(f"   python -c 'import numpy' {numpy_s:.3f} s")
        for k in ("prs-geom --help", "prs-geom init"):
            print(f"   {k:16s} {best[k]:.3f} s  ratio {best[k] / numpy_s:.2f} (goal <= 1.5)")

        print("3. engaged teeth (build)")
        ref = None
        for teeth in (20, 100) if args.quick else (20, 100, 200):
            design = teeth_design(tmp, teeth)
            o = tmp / f"t{teeth}"
            w, p = best_child(["build", str(design), "--out", str(o), "--quiet"], 1, o)
            ref = ref or w
            print(f"   n = {teeth:3d}: {w:7.2f} s, peak {p / 1024:6.0f} MB, time / (n = 20) {w / ref:5.2f}")

        print("4. chord tolerance (meshing + mesh files)")
        ref = None
        for tol_um in (10.0, 1.0) if args.quick else (10.0, 1.0, 0.1):
            o = tmp / f"m{tol_um:g}"
            w, p = best_child([f"{tol_um / 1000:g}", str(o)], 1, o, MESH_CHILD)
            ref = ref or w
            print(f"   {tol_um:5.1f} um: {w:7.2f} s, peak {p / 1024:6.0f} MB, time / (10 um) {w / ref:6.2f}")

        print("5. console and interrupts")
        gap, total, n_lines = silent_gap(tmp)
        print(f"   default build, plain progress lines: {n_lines} lines in {total:.1f} s, longest silent "
              f"gap {gap:.2f} s (goal <= 2 s)")
        worst = {False: 0.0, True: 0.0}
        for after in (1.0, 3.0, 5.0, 7.0):
            for group in (False, True):
                delay, code = interrupt_delay(tmp, after, group)
                worst[group] = max(worst[group], delay)
                print(f"   SIGINT to the {'process group' if group else 'main process'} at {after:.0f} s: "
                      f"exit {code} after {delay:.2f} s")
        print(f"   worst delay SIGINT -> exit: main process {worst[False]:.2f} s, process group "
              f"{worst[True]:.2f} s")


if __name__ == "__main__":
    main()
