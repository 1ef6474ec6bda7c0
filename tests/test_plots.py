"""Plot exporter (issue 17): matplotlib loads on first use, figures are made without pyplot
and give the bytes pyplot's would, and a plot renders the same in a worker process."""
from __future__ import annotations

import json
import multiprocessing as mp
import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from prs_geom.exports import plots

ROOT = Path(__file__).resolve().parent.parent


def _tolerance_args(out: Path) -> tuple:
    rng = np.random.default_rng(7)
    worst = 1.2 + 0.05 * rng.standard_normal(400)
    return out, "plottest", worst, [("50 % load", worst * 0.98), ("100 % load", worst)], 1.15


def test_importing_the_exporters_loads_no_plotting_or_sheet_library():
    code = ("import sys, json; import prs_geom.exports.plots, prs_geom.exports.drawing, prs_geom.exports.sheets; "
            "print(json.dumps(sorted(m for m in ('matplotlib', 'ezdxf', 'openpyxl') if m in sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert json.loads(out.stdout) == []


def test_figures_without_pyplot_give_pyplot_bytes(tmp_path):
    """:func:`plots._figure` stands in for ``pyplot.subplots``: the same PNG and SVG bytes."""
    plt = plots.plt
    x = np.linspace(0.0, 3.0, 25)
    made = {}
    for how, (fig, axes) in (("pyplot", plt.subplots(1, 2, figsize=(6, 3), sharey=True)),
                             ("figure", plots._figure(1, 2, figsize=(6, 3), sharey=True))):
        axes[0].plot(x, np.sin(x), "o-", label="sin")
        axes[1].plot(x, np.cos(x), "s-")
        axes[0].legend()
        fig.suptitle("same")
        (tmp_path / how).mkdir()
        svgs: dict[str, str] = {}
        plots.save_figure(fig, tmp_path / how, "f", svgs)
        made[how] = ((tmp_path / how / "f.png").read_bytes(), (tmp_path / how / "f.svg").read_bytes(), svgs["f"])
    assert made["figure"] == made["pyplot"]
    assert not plt.get_fignums()                    # save_figure closed the pyplot one


def test_plot_in_a_worker_process_gives_the_same_files(tmp_path):
    """:func:`plots.plot_detached` in a fresh (spawned) interpreter: same file bytes and SVG
    texts as in this process, so a pipeline may render plots off its critical path."""
    here, there = tmp_path / "here", tmp_path / "there"
    here.mkdir()
    there.mkdir()
    svgs: dict[str, str] = {}
    files = plots.plot_tolerance(*_tolerance_args(here), svgs=svgs)
    with ProcessPoolExecutor(1, mp_context=mp.get_context("spawn")) as pool:
        files_w, svgs_w = pool.submit(plots.plot_detached, plots.plot_tolerance, *_tolerance_args(there)).result()
    assert files_w == files == ["tolerance_ldc.png", "tolerance_ldc.svg"]
    assert svgs_w == svgs
    for name in files:
        assert (there / name).read_bytes() == (here / name).read_bytes(), name
