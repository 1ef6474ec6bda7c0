"""Issue 12: the public Python API and the README example that uses it."""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

import prs_geom as pg

ROOT = Path(__file__).resolve().parent.parent


def test_readme_api_example_runs_and_prints_the_numbers(tmp_path):
    r = subprocess.run([sys.executable, str(ROOT / "examples" / "api_example.py"), str(tmp_path / "out")],
                       capture_output=True, text=True, cwd=tmp_path, timeout=600)
    assert r.returncode == 0, r.stderr
    dia = float(re.search(r"theoretical screw pitch diameter: ([0-9.]+) mm", r.stdout).group(1))
    worst = float(re.search(r"coefficient \(constant pitch\): ([0-9.]+)", r.stdout).group(1))
    # the contact solver's value and the constant-pitch worst coefficient of the default design
    assert dia == pytest.approx(23.86787, abs=1e-5)
    assert worst == pytest.approx(1.4292, abs=1e-4)
    graded = float(re.search(r"worst coefficient ([0-9.]+)", r.stdout).group(1))
    assert graded == pytest.approx(1.0, abs=1e-9)
    assert (tmp_path / "out" / "report.json").is_file()


def test_api_round_trip_and_objects(tmp_path):
    d = pg.default_design()
    path = tmp_path / "d.toml"
    pg.save_design(d, path)
    assert pg.load_design(path) == d
    with pytest.raises(pg.OutputRefused):
        pg.save_design(d, path)          # never overwrites without being asked
    res = pg.analyse(d)
    assert isinstance(res, pg.Analysis)
    assert res.loads.ldc_roller_screw.shape == (d.thread.engaged_teeth,)
    assert res.loads.max_ldc == pytest.approx(max(res.loads.ldc_nut_roller.max(), res.loads.ldc_roller_screw.max()))
    assert res.contact.theoretical_screw_pitch_diameter_mm < d.screw.pitch_diameter_mm
    harmonic = pg.load_design(ROOT / "examples" / "harmonic.toml")
    assert isinstance(harmonic, pg.HarmonicDesign)
