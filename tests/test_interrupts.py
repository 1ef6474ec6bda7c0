"""An interrupt reaches every process of a build.

Whichever process receives SIGINT or SIGTERM (the main process only, as ``kill -INT PID``
does, or the whole process group, as Ctrl-C in a terminal does), the build stops with exit
130 or 143, prints one line, and leaves no worker process and no temporary folder behind.
The benchmark ``benchmarks/bench_build.py`` measures how promptly; here the timeouts are
generous and only the behaviour is asserted.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from prs_geom.model.actuator import ActuatorSettings
from prs_geom.model.design import MeshSettings, PRSDesign, Roller, Thread
from prs_geom.model.io import save_design

#: Builds for several seconds with its checks, drawings and plots in worker processes.
SMALL = PRSDesign(name="small", thread=Thread(engaged_teeth=6), roller=Roller(count=4),
                  mesh=MeshSettings(chord_tolerance_mm=0.02), actuator=ActuatorSettings(enabled=False))


#: How ``ps`` shows a build's worker process (:class:`prs_geom.runtime.sidecar.SidecarPool`)
#: and a study's (loky).
BUILD_WORKER = "prs_geom.runtime.sidecar"
STUDY_WORKER = "popen_loky"


def _group_alive(pgid: int) -> list[str]:
    """Processes of process group ``pgid`` that are not zombies (a killed child whose
    parent has gone waits for init to reap it: it runs nothing and holds no memory)."""
    out = subprocess.run(["ps", "-ww", "-eo", "pgid=,stat=,pid=,args="], capture_output=True, text=True).stdout
    rows = [line.split(None, 3) for line in out.splitlines()]
    return [" ".join(r) for r in rows if len(r) >= 3 and r[0] == str(pgid) and not r[1].startswith("Z")]


def _start(design_file: Path, out: Path, extra_env: dict[str, str] | None = None) -> tuple[subprocess.Popen, list[str]]:
    exe = Path(sys.executable).parent / "prs-geom"
    env = {k: v for k, v in os.environ.items() if k != "PRS_GEOM_WORKERS"}   # workers on
    env["TMPDIR"] = str(out.parent)   # so that a progress folder left behind would be seen
    env.update(extra_env or {})

    def child_setup() -> None:
        os.setsid()   # a process group of its own, as a terminal gives a command
        # SIGINT back to its default: a process started with SIGINT ignored keeps ignoring it
        signal.signal(signal.SIGINT, signal.SIG_DFL)

    proc = subprocess.Popen([str(exe), "build", str(design_file), "--out", str(out), "--memory-budget", "4G"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            preexec_fn=child_setup)
    lines: list[str] = []

    def read() -> None:
        assert proc.stderr is not None
        for line in proc.stderr:
            lines.append(line.rstrip("\n"))

    threading.Thread(target=read, daemon=True).start()
    return proc, lines


@pytest.mark.parametrize("target, sig, code", [("main", signal.SIGINT, 130), ("group", signal.SIGINT, 130),
                                               ("main", signal.SIGTERM, 143), ("group", signal.SIGTERM, 143),
                                               ("worker", signal.SIGINT, 130)])
def test_interrupt_stops_every_process_and_prints_one_line(tmp_path, target, sig, code):
    design_file = tmp_path / "small.toml"
    save_design(SMALL, design_file)
    out = tmp_path / "out"
    proc, lines = _start(design_file, out)
    try:
        # wait until the workers are at work (the progress display names them)
        t0 = time.monotonic()
        while not any("(worker)" in line or "in workers" in line for line in lines):
            assert proc.poll() is None, "\n".join(lines)
            assert time.monotonic() - t0 < 120, "no worker job started:\n" + "\n".join(lines)
            time.sleep(0.05)
        before = len(lines)
        if target == "main":
            os.kill(proc.pid, sig)
        elif target == "group":
            os.killpg(proc.pid, sig)
        else:   # one worker only: it hands the signal to the main process
            workers = [r.split()[2] for r in _group_alive(proc.pid) if BUILD_WORKER in r]
            assert workers, _group_alive(proc.pid)
            os.kill(int(workers[0]), sig)
        proc.wait(timeout=120)
        # the workers were killed and reaped before the main process left: none is alive
        # now (a worker that outlived it would end only by its parent watch, 0.5 s later)
        t0 = time.monotonic()
        while _group_alive(proc.pid) and time.monotonic() - t0 < 0.25:
            time.sleep(0.02)
        assert not any(BUILD_WORKER in r for r in _group_alive(proc.pid)), _group_alive(proc.pid)
        time.sleep(0.2)   # let the reader thread take the last lines
        assert proc.returncode == code, "\n".join(lines)
        after = [line for line in lines[before:] if not line.startswith("[")]   # progress lines start with [
        assert after == ["interrupted"], "\n".join(lines)
        assert not any("Traceback" in line for line in lines)
        # no worker left: the group holds no live process (generous: the OS reaps the killed)
        t0 = time.monotonic()
        while _group_alive(proc.pid) and time.monotonic() - t0 < 30:
            time.sleep(0.2)
        assert _group_alive(proc.pid) == []
        # no output and no temporary folder
        assert sorted(p.name for p in tmp_path.iterdir()) == ["small.toml"]
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def test_ctrl_c_in_a_plain_script_using_the_api_cleans_up(tmp_path):
    """The Python API from a plain script (no ``__main__`` guard), Ctrl-C to the process
    group while the workers run: the script ends with KeyboardInterrupt (Python's own
    behaviour), and the workers, the temporary output and the progress folder are gone."""
    design_file = tmp_path / "small.toml"
    save_design(SMALL, design_file)
    script = tmp_path / "api.py"
    script.write_text("import sys\nimport prs_geom as pg\n"
                      f"pg.build(pg.load_design({str(design_file)!r}), {str(tmp_path / 'out')!r},\n"
                      "         progress=lambda stage, done, total: print(stage, flush=True, file=sys.stderr))\n")
    env = {k: v for k, v in os.environ.items() if k != "PRS_GEOM_WORKERS"}
    env["TMPDIR"] = str(tmp_path)

    def child_setup() -> None:
        os.setsid()
        signal.signal(signal.SIGINT, signal.SIG_DFL)

    proc = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=env, preexec_fn=child_setup, cwd=tmp_path)
    try:
        # the interference check reports from its worker: wait until a worker is at work
        t0 = time.monotonic()
        while not any(BUILD_WORKER in r for r in _group_alive(proc.pid)):
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() - t0 < 120
            time.sleep(0.05)
        time.sleep(1.5)
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=120)
        assert proc.returncode != 0 and "KeyboardInterrupt" in err
        assert err.count("Traceback") == 1, err      # one, the script's own: no chained second interrupt
        t0 = time.monotonic()
        while _group_alive(proc.pid) and time.monotonic() - t0 < 30:
            time.sleep(0.2)
        assert _group_alive(proc.pid) == []
        assert sorted(p.name for p in tmp_path.iterdir()) == ["api.py", "small.toml"]
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def _snapshot(folder: Path) -> dict[str, tuple[int, int]]:
    return {str(p.relative_to(folder)): (p.stat().st_size, p.stat().st_mtime_ns)
            for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.mark.parametrize("command", ["build", "tolerance", "tolerance-dask"])
def test_sigkill_of_the_main_process_leaves_no_worker_running_or_writing(tmp_path, command):
    """SIGKILL of the main process (what the out-of-memory killer sends) mid-build
    and mid-tolerance study: every worker notices its parent is gone and exits at once
    (parent watch), so soon after no child remains and nothing is written any more."""
    design_file = tmp_path / "small.toml"
    save_design(SMALL, design_file)
    exe = Path(sys.executable).parent / "prs-geom"
    env = {k: v for k, v in os.environ.items() if k != "PRS_GEOM_WORKERS"}
    env["TMPDIR"] = str(tmp_path)
    argv = [str(exe), "build", str(design_file), "--out", str(tmp_path / "out"), "--memory-budget", "4G"] \
        if command == "build" else \
        [str(exe), "tolerance", str(design_file), "--flank-um", "1", "--samples", "200000",
         *(["--dask-workers", "2"] if command == "tolerance-dask" else ["--workers", "2"])]
    # the build's workers, loky's, or the processes of a local Dask cluster (multiprocessing spawn)
    worker_mark = {"build": BUILD_WORKER, "tolerance": STUDY_WORKER, "tolerance-dask": "spawn_main"}[command]
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env,
                            preexec_fn=os.setsid, cwd=tmp_path)
    try:
        t0 = time.monotonic()
        while not any(worker_mark in r for r in _group_alive(proc.pid)):
            assert proc.poll() is None, "the command ended before its workers started"
            assert time.monotonic() - t0 < 120
            time.sleep(0.05)
        time.sleep(1.0)   # the workers at work
        workers = [r for r in _group_alive(proc.pid) if worker_mark in r]
        assert workers
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        t0 = time.monotonic()
        while _group_alive(proc.pid) and time.monotonic() - t0 < 30:
            time.sleep(0.2)
        assert _group_alive(proc.pid) == [], "left running after SIGKILL"
        before = _snapshot(tmp_path)
        time.sleep(2.0)
        assert _snapshot(tmp_path) == before, "something was written after the main process died"
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass


@pytest.mark.parametrize("where", [["--workers", "2"]])
def test_ctrl_c_to_a_study_prints_one_line(tmp_path, where):
    """A Ctrl-C (SIGINT to the process group) during a tolerance study on loky:
    exit 130 and the one line, no tracebacks from the workers."""
    exe = Path(sys.executable).parent / "prs-geom"
    env = {k: v for k, v in os.environ.items() if k != "PRS_GEOM_WORKERS"}

    def child_setup() -> None:
        os.setsid()
        signal.signal(signal.SIGINT, signal.SIG_DFL)

    proc = subprocess.Popen([str(exe), "tolerance", "--flank-um", "1", "--samples", "200000", *where, "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            preexec_fn=child_setup, cwd=tmp_path)
    # loky: two workers; Dask: two nannies and their two workers, and a Ctrl-C while the
    # cluster starts is lost by design (scaleout, background.signals_ignored): wait for all
    mark = "spawn_main" if where[0] == "--dask-workers" else STUDY_WORKER
    need = 4 if where[0] == "--dask-workers" else 2
    try:
        t0 = time.monotonic()
        while sum(mark in r for r in _group_alive(proc.pid)) < need:
            assert proc.poll() is None and time.monotonic() - t0 < 120
            time.sleep(0.05)
        time.sleep(2.0)
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=120)
        assert proc.returncode == 130 and err.splitlines() == ["interrupted"], err[-3000:]
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def test_ctrl_c_during_a_rebuild_stops_its_plot_process(tmp_path):
    """A rebuild after a load change (stage cache on) has a plot process of its own
    (prs_geom.runtime.sidecar) from its start: Ctrl-C to the process group stops the build
    with one line and exit 130, leaves no process, and the output folder keeps the earlier
    build. (SIGINT to one worker alone is handed to the main process by the same
    worker_init as the pool's: the test above.)"""
    import dataclasses

    env = {"PRS_GEOM_STAGE_CACHE": "1", "PRS_GEOM_CACHE": str(tmp_path / "cache")}
    design_file = tmp_path / "small.toml"
    save_design(SMALL, design_file)
    out = tmp_path / "out"
    first, lines = _start(design_file, out, env)
    assert first.wait(timeout=300) == 0, "\n".join(lines)
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    design_file = tmp_path / "small-21kN.toml"
    save_design(SMALL.with_changes(loading=dataclasses.replace(SMALL.loading, axial_load_n=21_000.0)), design_file)
    proc, lines = _start(design_file, out, env)
    try:
        t0 = time.monotonic()
        while not (side := [r for r in _group_alive(proc.pid) if "prs_geom.runtime.sidecar" in r]):
            assert proc.poll() is None, "the rebuild ended before its plot process was seen:\n" + "\n".join(lines)
            assert time.monotonic() - t0 < 60
            time.sleep(0.02)
        assert side
        os.killpg(proc.pid, signal.SIGINT)
        proc.wait(timeout=120)
        time.sleep(0.2)   # let the reader thread take the last lines
        assert proc.returncode == 130, "\n".join(lines)
        assert [line for line in lines if not line.startswith("[")] == ["interrupted"], "\n".join(lines)
        t0 = time.monotonic()
        while _group_alive(proc.pid) and time.monotonic() - t0 < 30:
            time.sleep(0.2)
        assert _group_alive(proc.pid) == []
        assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
