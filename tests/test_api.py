"""Issue 12: the public Python API and the README example that uses it."""
from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import prs_geom as pg

ROOT = Path(__file__).resolve().parent.parent


def _fresh_run(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    """``python ARGS`` in a fresh interpreter in ``cwd`` as a user runs it: worker processes
    on (PRS_GEOM_WORKERS removed from the environment, which the suite sets to 0)."""
    env = {k: v for k, v in os.environ.items() if k != "PRS_GEOM_WORKERS"}
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, cwd=cwd, env=env, timeout=900)


def _readme_api_block() -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text[text.index("## Python API"):]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_readme_api_block_runs_as_a_plain_script(tmp_path):
    """Issue 28: the README block saved as api.py (no ``__main__`` guard) and run with
    ``python api.py``: the build's worker processes must not re-run the script (the old
    spawn pool printed the analysis three times and failed with BrokenProcessPool)."""
    (tmp_path / "api.py").write_text(_readme_api_block(), encoding="utf-8")
    r = _fresh_run(["api.py"], tmp_path)
    assert r.returncode == 0, r.stderr[-3000:]
    lines = r.stdout.splitlines()
    assert len(lines) == 1, r.stdout     # printed once: the workers did not run the script again
    dia, worst = map(float, lines[0].split())
    # the contact solver's theoretical pitch diameter and the constant-pitch worst LDC of the
    # default design (the same numbers as tests/test_contact.py and tests/test_loads.py)
    assert dia == pytest.approx(23.86787, abs=1e-5)
    assert worst == pytest.approx(1.4292, abs=1e-4)
    graded = pg.load_design(tmp_path / "graded.toml")
    assert graded.roller.pitch_list_mm is not None and pg.default_design().roller.pitch_list_mm is None
    report = json.loads((tmp_path / "exports" / "graded" / "report.json").read_text())
    # the equal-load pitch lists share the load equally: worst coefficient 1
    assert report["loads"]["max_ldc"] == pytest.approx(1.0, abs=1e-9)
    assert report["timings_s"]["checks"] > 0


def test_every_example_script_runs_with_workers(tmp_path):
    """Every ``examples/*.py`` as ``python FILE OUT`` in a fresh folder, workers on."""
    scripts = sorted((ROOT / "examples").glob("*.py"))
    assert scripts
    for script in scripts:
        r = _fresh_run([str(script), str(tmp_path / script.stem / "out")], tmp_path)
        assert r.returncode == 0, (script.name, r.stderr[-3000:])
        if script.name == "api_example.py":
            dia = float(re.search(r"theoretical screw pitch diameter: ([0-9.]+) mm", r.stdout).group(1))
            worst = float(re.search(r"coefficient \(constant pitch\): ([0-9.]+)", r.stdout).group(1))
            assert dia == pytest.approx(23.86787, abs=1e-5)
            assert worst == pytest.approx(1.4292, abs=1e-4)
            graded = float(re.search(r"worst coefficient ([0-9.]+)", r.stdout).group(1))
            assert graded == pytest.approx(1.0, abs=1e-9)
            assert r.stdout.count("theoretical screw pitch diameter") == 1
            assert (tmp_path / script.stem / "out" / "report.json").is_file()


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


def test_build_meshes_are_the_part_files(tmp_path):
    """pg.build_meshes gives the solids ``prs-geom build`` writes: the complete screw, roller
    and nut equal their STL files read back by trimesh (float32 rounding), and the thread
    bodies alone are smaller by the gears, journals, ends and flange."""
    import trimesh

    from prs_geom.model.design import MeshSettings, Thread

    d = pg.default_design().with_changes(thread=Thread(engaged_teeth=6), mesh=MeshSettings(chord_tolerance_mm=0.05))
    meshes = pg.build_meshes(d)
    pg.build(d, tmp_path / "out")
    for part in ("screw", "roller", "nut", "carrier", "retaining_ring"):
        stl = trimesh.load(tmp_path / "out" / f"{part}.stl")
        assert meshes[part].volume == pytest.approx(stl.volume, rel=1e-6), part
    for part in ("screw", "roller", "nut"):
        assert meshes[f"{part}_thread"].volume < 0.9 * meshes[part].volume, part
    assert {"roller_0", "roller_0_gear_lo", "nut_ring_gear_hi"} <= set(meshes)
    # every complete part in its own frame, as its entry in the assembly's report section
    from prs_geom.mesh.assembly import build_assembly

    for name, part in build_assembly(d, screw_profile=pg.analyse(d).contact.screw_profile).complete_parts().items():
        np.testing.assert_allclose(meshes[name].bounds, [part.vertices.min(axis=0), part.vertices.max(axis=0)],
                                   atol=1e-9, err_msg=name)
