"""The plot process of a rebuild (prs_geom.runtime.sidecar): results and errors come back in
order and with their types, a stray print does not corrupt the replies, the process is
reaped when let go and leaves by itself when its parent dies; its figures are the same bytes
as those drawn in this process. The build's pool of such processes (SidecarPool): each job
goes to an idle process, a process that dies fails its job and the queued ones only, and
the pool starts its processes and nothing else."""
from __future__ import annotations

import operator
import os
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from prs_geom.exports.plots import plot_detached, plot_loads, warm_up
from prs_geom.model.errors import DesignError
from prs_geom.model.validation import positive
from prs_geom.runtime.memwatch import _children
from prs_geom.runtime.pool import Background
from prs_geom.runtime.sidecar import Sidecar, SidecarPool, shared_pool


def _local() -> None:    # pragma: no cover - never runs: the plot process cannot import this module
    pass


def test_jobs_come_back_in_order_with_values_errors_and_times():
    """Functions of importable modules (as the build's plot functions are): a value, a stray
    print on standard output (it goes to standard error, not into the replies), a design
    error with its type and field, and a job that does not unpickle there, which fails alone."""
    sidecar = Sidecar()
    try:
        slow = sidecar.submit(time.sleep, (0.5,), {})
        assert not slow.done()
        square = sidecar.submit(operator.mul, (3.0, 3.0), {})
        stray = sidecar.submit(print, ("a stray line on standard output",), {})
        failing = sidecar.submit(positive, ("roller.count", -3.5), {})
        local = sidecar.submit(_local, (), {})
        last = sidecar.submit(os.getpid, (), {})
        value, seconds = last.result()      # waits past the jobs before it
        assert value == sidecar.pid != os.getpid() and seconds >= 0.0
        assert slow.done() and slow.result()[1] >= 0.5
        assert square.done() and square.result()[0] == 9.0
        assert stray.result()[0] is None
        with pytest.raises(DesignError) as info:
            failing.result()
        assert info.value.field == "roller.count" and info.value.value == -3.5
        with pytest.raises(ModuleNotFoundError):
            local.result()
    finally:
        sidecar.close()
    assert sidecar._proc.returncode is not None      # reaped


def test_background_sends_only_figures_to_its_sidecar():
    with Background(0, sidecar=Sidecar()) as bg:
        proc = bg.sidecar._proc
        plot = bg.submit(os.getpid, plot=True)
        other = bg.submit(os.getpid)
        assert plot.in_worker and not other.in_worker
        assert plot.result() == proc.pid and other.result() == os.getpid()
    assert proc.returncode is not None      # let go with the pool


def test_a_figure_drawn_in_the_sidecar_has_the_same_bytes(tmp_path):
    """plot_loads through the plot process (warmed up with a figure of its own first) and
    in this process: the same PNG and SVG bytes and SVG text."""
    n = 9
    teeth = np.linspace(0.6, 1.4, n)
    const = {"ldc_nut_roller": teeth, "ldc_roller_screw": teeth[::-1].copy()}
    off = [{"load_fraction": f, "load_N": 2e4 * f, **const} for f in (0.5, 1.0)]
    args = ("demo", const, const, off, np.linspace(0.0, 0.3, n - 1), np.linspace(0.0, 0.2, n - 1), "designed")
    (tmp_path / "here").mkdir()
    (tmp_path / "there").mkdir()
    here = plot_detached(plot_loads, tmp_path / "here", *args)
    sidecar = Sidecar(warm_up)
    try:
        there, _ = sidecar.submit(plot_detached, (plot_loads, tmp_path / "there", *args), {}).result()
    finally:
        sidecar.close()
    assert here == there
    for name in here[0]:
        assert (tmp_path / "here" / name).read_bytes() == (tmp_path / "there" / name).read_bytes(), name


def test_the_sidecar_leaves_when_its_parent_is_killed(tmp_path):
    """A main process killed with SIGKILL (the out-of-memory killer) leaves no plot process."""
    script = textwrap.dedent("""
        import os, sys
        from prs_geom.runtime.sidecar import Sidecar
        s = Sidecar()
        print(s.pid, flush=True)
        os.kill(os.getpid(), 9)
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    pid = int(proc.stdout.split()[0])
    deadline = time.monotonic() + 10.0
    while time.monotonic() < deadline:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.1)
    else:
        os.kill(pid, 9)
        pytest.fail("the plot process outlived its parent by 10 s")


def test_the_pool_sends_each_job_to_an_idle_process():
    """A long job holds the first process; the jobs after it all run on the second one
    meanwhile (a pool, not a queue per process). Closing the pool kills the long job, whose
    result then fails, and reaps both processes."""
    pool = SidecarPool(2)
    try:
        long = pool.submit(time.sleep, (5.0,), {})
        quick = [pool.submit(os.getpid, (), {}) for _ in range(3)]
        pids = {job.result()[0] for job in quick}
        assert pids == {pool.processes[1].pid} and not long.done()
        errors = [pool.submit(positive, ("roller.count", -3.5), {}), pool.submit(_local, (), {})]
        with pytest.raises(DesignError) as info:
            errors[0].result()
        assert info.value.field == "roller.count"
        with pytest.raises(ModuleNotFoundError):
            errors[1].result()
        assert pool.submit(operator.mul, (3.0, 4.0), {}).result()[0] == 12.0    # the pool goes on
    finally:
        pool.close()
    with pytest.raises(RuntimeError, match="closed before the job was done"):
        long.result()
    assert all(p._proc.returncode is not None for p in pool.processes)


def test_a_process_that_dies_fails_its_job_and_the_later_ones_only():
    """A worker that ends mid-job (as one killed by the memory watch does): its job and
    every later one raise RuntimeError with its exit code; the job of the other process
    keeps its result."""
    pool = SidecarPool(2)
    try:
        other = pool.submit(time.sleep, (0.5,), {})
        dying = pool.submit(os._exit, (3,), {})
        with pytest.raises(RuntimeError, match="exit code 3"):
            dying.result()
        assert other.result()[1] >= 0.5
        with pytest.raises(RuntimeError, match="exit code 3"):
            pool.submit(os.getpid, (), {}).result()
    finally:
        pool.close()


def test_a_build_pool_starts_its_processes_and_nothing_else():
    """Background with processes of its own (the build's): started by start(), its children
    are its two processes, with no resource tracker beside them (loky starts two; the
    standard library's pool one), each a child of this process; killed on leaving."""
    before = set(_children(os.getpid()))
    with Background(2, processes=SidecarPool) as bg:
        bg.start()
        pool = bg._pool
        started = set(_children(os.getpid())) - before
        assert started == {p.pid for p in pool.processes}
        parents = {bg.submit(os.getppid).result() for _ in range(4)}
        assert parents == {os.getpid()}
        assert set(_children(os.getpid())) - before == started
    assert all(p._proc.returncode is not None for p in pool.processes)
    assert not set(_children(os.getpid())) - before


def test_the_shared_pool_serves_build_after_build_until_one_fails():
    """The build's pool (shared_pool) outlives a build that ends normally: the next one gets
    the same processes, imports done; a build that fails kills them, and the next gets new
    ones."""
    with Background(2, processes=shared_pool) as bg:
        first = {bg.submit(os.getpid).result() for _ in range(4)}
        pool = bg._pool
    assert pool.usable and all(p._proc.poll() is None for p in pool.processes)
    with Background(2, processes=shared_pool) as bg:
        assert bg.submit(os.getpid).result() in first and bg._pool is pool
    with pytest.raises(KeyError):
        with Background(2, processes=shared_pool) as bg:
            bg.submit(os.getpid).result()
            raise KeyError("a stage failed")
    assert not pool.usable and all(p._proc.returncode is not None for p in pool.processes)
    with Background(2, processes=shared_pool) as bg:
        assert bg.submit(os.getpid).result() not in first
        bg._pool.close()


def test_an_idle_pool_closes_itself_and_the_next_job_gets_a_new_one():
    """A reusable pool with no job for idle_s seconds kills and reaps its processes; a
    Background that still holds it starts a new pool for its next job."""
    with Background(1, processes=lambda n: SidecarPool(n, idle_s=0.3)) as bg:
        first = bg.submit(os.getpid).result()
        pool = bg._pool
        deadline = time.monotonic() + 10.0
        while pool.processes[0]._proc.returncode is None and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not pool.usable and pool.processes[0]._proc.returncode is not None
        assert bg.submit(os.getpid).result() != first
        bg._pool.close()


def _blas_threads(info: list[dict]) -> set[int]:
    return {lib["num_threads"] for lib in info if lib["user_api"] == "blas"}


def test_every_process_of_a_build_runs_blas_on_one_thread(monkeypatch):
    """pool.BUILD_THREADS: a pool worker's BLAS runs one thread (threadpoolctl read in the
    worker), and so does this process's inside build_threads and not after, whatever the
    core count; the user's setting wins in both, and a shared pool started before the user
    changed it is replaced, not reused."""
    from threadpoolctl import threadpool_info

    from prs_geom.runtime.pool import BUILD_THREADS, THREAD_ENV, build_threads

    for name in THREAD_ENV:
        monkeypatch.delenv(name, raising=False)
    assert BUILD_THREADS == 1
    before = _blas_threads(threadpool_info())
    assert before, "numpy's BLAS is loaded in this process"
    pool = shared_pool(1)
    try:
        pool.submit(np.zeros, (3,), {}).result()         # numpy (and its BLAS) loaded there
        assert _blas_threads(pool.submit(threadpool_info, (), {}).result()[0]) == {1}
        with build_threads():
            assert _blas_threads(threadpool_info()) == {1}
        assert _blas_threads(threadpool_info()) == before

        # a count the build would not choose (OpenBLAS takes at most one thread per core)
        user = min(2, os.cpu_count() or 1)
        monkeypatch.setenv("OPENBLAS_NUM_THREADS", str(user))
        again = shared_pool(1)
        assert again is not pool and not pool.usable
        again.submit(np.zeros, (3,), {}).result()
        assert _blas_threads(again.submit(threadpool_info, (), {}).result()[0]) == {user}
        with build_threads():
            assert _blas_threads(threadpool_info()) == before
    finally:
        shared_pool(1).close()
        pool.close()
