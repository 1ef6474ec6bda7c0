"""The plot process of a rebuild (prs_geom.runtime.sidecar): results and errors come back in
order and with their types, a stray print does not corrupt the replies, the process is
reaped when let go and leaves by itself when its parent dies; its figures are the same bytes
as those drawn in this process."""
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
from prs_geom.runtime.pool import Background
from prs_geom.runtime.sidecar import Sidecar


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
