"""prs_geom.sweep: design-space sweeps equal the direct calls, bit for bit on any backend."""
from __future__ import annotations

import csv
import io
import json
import sys

import numpy as np
import pytest

from prs_geom.analysis.loads import (axial_stiffness, build_model, design_pitch, design_pitches, forward,
                                     off_design, with_pitch_lists)
from prs_geom.model.design import Loading, Nut, PRSDesign, Roller, Screw, Thread, default_design
from prs_geom.model.errors import DesignError, EnvironmentFailure
from prs_geom.model.plausibility import design_warnings
from prs_geom.runtime.scaleout import DASK_INSTALL
from prs_geom.sweep import CHUNK_POINTS, SweepPoint, point_design, sweep

AXES = {"starts": [4, 5], "rollers": [8, 10], "pitch_mm": [1.5], "teeth": [6, 10], "loads": [0.5, 1.0]}
N_POINTS = 16


@pytest.fixture(scope="module")
def serial():
    calls = []
    res = sweep(default_design(), **AXES, workers=1, progress=lambda *a: calls.append(a))
    return res, calls


def by_hand(s: int, z: int, p: float, n: int, f: float) -> PRSDesign:
    """The design of a sweep point of the default design, written out as a designer would."""
    return PRSDesign(thread=Thread(pitch_mm=p, engaged_teeth=n), screw=Screw(starts=s), roller=Roller(count=z),
                     nut=Nut(starts=s), loading=Loading(axial_load_n=20_000.0 * f))


def test_sweep_order_columns_and_progress(serial):
    res, calls = serial
    rows = res.rows()
    assert len(rows) == N_POINTS == CHUNK_POINTS * 4
    # product order: starts slowest, loads fastest, each axis as given
    assert [(r["screw_starts"], r["rollers"], r["engaged_teeth"], r["load_fraction"]) for r in rows[:5]] == [
        (4, 8, 6, 0.5), (4, 8, 6, 1.0), (4, 8, 10, 0.5), (4, 8, 10, 1.0), (4, 10, 6, 0.5)]
    assert [r["point"] for r in rows] == list(range(1, N_POINTS + 1))
    assert rows[-1]["screw_starts"] == rows[-1]["nut_starts"] == 5 and rows[-1]["design_load_N"] == 20_000.0
    assert res.units["pitch_mm"] == "mm" and res.units["graded_stiffness_N_per_um"] == "N/um"
    assert res.units["max_pitch_correction_um"] == "um" and res.units["design_load_N"] == "N"
    assert [c.name for c in res.columns][13:17] == ["graded_max_ldc_25pct", "graded_max_ldc_50pct",
                                                    "graded_max_ldc_100pct", "graded_max_ldc_150pct"]
    assert calls == [("sweep", k, N_POINTS) for k in (4, 8, 12, 16)]
    # the 4-start points break the standard sizing of 24/8/40 mm and their rollers drift:
    # valid with warnings, not valid
    assert res.count("ok") == res.count("warnings") == N_POINTS // 2
    assert res.counts() == {"ok": 8, "warnings": 8, "invalid": 0, "failed": 0}
    assert res.summary() == "16 points, 8 valid, 8 valid with warnings, 0 invalid, 0 failed"


def test_sweep_values_equal_the_direct_calls(serial):
    res, _ = serial
    for row in res.rows():
        s, z, p, n, f = (row["screw_starts"], row["rollers"], row["pitch_mm"], row["engaged_teeth"],
                         row["load_fraction"])
        d = by_hand(s, z, p, n, f)
        assert point_design(default_design(), SweepPoint(0, s, z, p, n, f)) == d
        model = build_model(d)
        const = forward(d, model=model)
        pd = design_pitches(d, model=model)
        graded = with_pitch_lists(d, pd)
        off = off_design(graded, (0.25, 0.5, 1.0, 1.5), model=model)
        assert row["status"] == ("ok" if s == 5 else "warnings") and row["reason"] == ""
        assert row["constant_max_ldc"] == max(const.ldc_nr.max(), const.ldc_rs.max())
        for o in off:
            assert row[f"graded_max_ldc_{o['load_fraction'] * 100:g}pct"] == o["max_ldc"]
        assert row["constant_stiffness_N_per_um"] == axial_stiffness(d, model)["secant_N_per_um"]
        assert row["graded_stiffness_N_per_um"] == axial_stiffness(graded, model)["secant_N_per_um"]
        corr = np.abs(np.concatenate([pd.roller_mm, pd.nut_mm]) - p).max() * 1e3
        assert row["max_pitch_correction_um"] == corr
        # the sizing relations the point breaks (starts 4 on 24/8/40 mm) are reported, not errors
        assert row["sizing_warnings"] == " | ".join(d.sizing_warnings())
        assert (row["sizing_warnings"] != "") == (s == 4)
        assert row["plausibility_warnings"] == " | ".join(design_warnings(d))
        # 4 starts on 24/8/40 mm: drift h p (r_s / (r_s + r_n)) (n_n - r_n / r_r) = 1.5 x 0.375 x (4 - 5)
        assert ("rollers drift axially by -0.5625 mm per screw turn" in row["plausibility_warnings"]) == (s == 4)


def test_equal_load_design_shares_equally_at_its_load_only(serial):
    res, _ = serial
    for row in res.rows():
        assert abs(row["graded_max_ldc_100pct"] - 1.0) < 1e-9
        # away from the design load the graded design no longer shares equally
        assert row["graded_max_ldc_25pct"] > 1.01 and row["graded_max_ldc_150pct"] > 1.005
        assert row["constant_max_ldc"] > 1.01
        assert 0.05 < row["max_pitch_correction_um"] < 5.0
        assert 100.0 < row["constant_stiffness_N_per_um"] < row["graded_stiffness_N_per_um"] < 5000.0


def test_joblib_equals_serial_bit_for_bit(serial):
    res, _ = serial
    par = sweep(default_design(), **AXES, workers=2)
    assert par == res
    assert par.csv_text() == res.csv_text()         # repr of every float: the same bits


def test_invalid_points_carry_the_design_error():
    with pytest.raises(DesignError) as info:
        PRSDesign(roller=Roller(count=12))
    res = sweep(default_design(), rollers=[10, 12], pitch_mm=[2.0, -1.5], workers=1)
    rows = {(r["rollers"], r["pitch_mm"]): r for r in res.rows()}
    assert rows[12, 2.0]["status"] == "invalid" and rows[12, 2.0]["reason"] == str(info.value)
    assert "12 rollers on a 16.0 mm centre radius overlap" in rows[12, 2.0]["reason"]
    # a part's own rule is named by its design-file path
    assert rows[10, -1.5]["reason"] == "thread.pitch_mm = -1.5: must be > 0"
    for key in ((12, 2.0), (10, -1.5), (12, -1.5)):
        assert rows[key]["status"] == "invalid"
        assert rows[key]["constant_max_ldc"] is None and rows[key]["graded_max_ldc_100pct"] is None
    assert rows[10, 2.0]["status"] == "ok" and rows[10, 2.0]["constant_max_ldc"] > 1.2
    assert res.count("ok") == 1 and res.count("invalid") == 3


def test_written_dimensions_are_kept_and_defaulted_ones_follow_the_point():
    # screw.length_mm written in the design: 30 teeth x 2 mm no longer fit, and the sweep says so
    base = PRSDesign(screw=Screw(length_mm=48.0))
    rows = sweep(base, teeth=[20, 30], workers=1).rows()
    assert rows[0]["status"] == "ok"
    assert rows[1]["reason"] == ("screw.length_mm = 48.0: must be at least the engaged length n p = 60.0 mm "
                                 "(thread.engaged_teeth x thread.pitch_mm = 30 x 2.0)")
    # defaulted on the default design: re-derived for the point, so the point is valid
    d = point_design(default_design(), SweepPoint(0, None, 10, 1.5, 30, 1.0))
    assert d.screw.length_mm is None and d == by_hand(5, 10, 1.5, 30, 1.0)   # the actuator sizes it
    # a graded base design is swept from constant pitch
    graded = design_pitch(PRSDesign(thread=Thread(engaged_teeth=6)))
    assert graded.graded
    g_row, c_row = (sweep(x, workers=1).rows()[0] for x in (graded, PRSDesign(thread=Thread(engaged_teeth=6))))
    assert g_row["constant_max_ldc"] == c_row["constant_max_ldc"] > 1.01


def test_tolerances_are_dropped_so_that_other_tooth_counts_stay_valid():
    from prs_geom.model.design import Tolerances

    base = PRSDesign(tolerances=Tolerances(flank_um=1.0, screw_flank_um=(0.5,) * 20))
    with pytest.raises(DesignError, match="tolerances.screw_flank_um"):
        base.with_changes(thread=Thread(engaged_teeth=6), screw=Screw(length_mm=None))
    row = sweep(base, teeth=[6], workers=1).rows()[0]
    assert row["status"] == "ok" and row["constant_max_ldc"] == sweep(
        default_design(), teeth=[6], workers=1).rows()[0]["constant_max_ldc"]
    assert point_design(base, SweepPoint(0, None, 10, 2.0, 6, 1.0)).tolerances is None


def test_small_sweeps_run_in_this_process_unless_workers_are_asked_for(monkeypatch):
    import prs_geom.runtime.scaleout as scaleout

    seen = []
    real = scaleout.run_chunks

    def recording(task, payloads, **kw):
        seen.append((len(payloads), kw["workers"]))
        return real(task, payloads, **{**kw, "workers": 1})

    monkeypatch.setattr(scaleout, "run_chunks", recording)
    sweep(default_design(), teeth=[6, 7, 8], workers=None)
    sweep(default_design(), teeth=[6, 7, 8], workers=3)
    sweep(default_design(), teeth=list(range(2, 18)), pitch_mm=[2.0], workers=None)
    assert seen == [(1, 1), (1, 3), (4, None)]


def test_bad_axes_are_refused_up_front():
    with pytest.raises(DesignError, match=r"rollers = \[\]: must list at least one value"):
        sweep(default_design(), rollers=[])
    with pytest.raises(DesignError, match=r"loads\[1\] = 0.0: must be a number > 0"):
        sweep(default_design(), loads=[1.0, 0.0])
    with pytest.raises(DesignError, match="workers = 0"):
        sweep(default_design(), workers=0)


def test_csv_keeps_full_precision(serial):
    res, _ = serial
    rows = list(csv.DictReader(io.StringIO(res.csv_text())))
    assert list(rows[0]) == [c.name for c in res.columns]
    for text, row in zip(rows, res.rows()):
        assert float(text["constant_max_ldc"]) == row["constant_max_ldc"]
        assert float(text["max_pitch_correction_um"]) == row["max_pitch_correction_um"]
        assert int(text["engaged_teeth"]) == row["engaged_teeth"]


# --------------------------------------------------------------------------- command line
def _run(argv):
    """(exit code, stdout, stderr) of ``prs-geom sweep argv`` on the default design."""
    from cli_helpers import run as cli

    return cli(["sweep", *argv])


def test_run_prints_json_and_writes_the_csv(tmp_path):
    out_csv = tmp_path / "s.csv"
    code, out, err = _run(["--rollers", "10", "12", "--teeth", "6", "--workers", "1", "--json", "--out",
                           str(out_csv)])
    assert code == 0, err
    data = json.loads(out)
    assert [r["status"] for r in data["rows"]] == ["ok", "invalid"]
    assert data["counts"] == {"ok": 1, "warnings": 0, "invalid": 1, "failed": 0}
    assert data["rows"][1]["constant_max_ldc"] is None
    assert {"name": "pitch_mm", "unit": "mm", "description": "axial pitch p"} in data["columns"]
    assert out_csv.read_text(encoding="utf-8").splitlines()[0].startswith("point,screw_starts,nut_starts,rollers")
    assert f"wrote {out_csv}: 2 points, 1 valid, 0 valid with warnings, 1 invalid, 0 failed" in err
    code, out, _ = _run(["--rollers", "10", "12", "--teeth", "6", "--workers", "1"])
    assert "2 points, 1 valid" in out and "invalid: roller.count = 12" in out


def test_run_without_the_dask_extra_names_the_install_command(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)
    code, _, err = _run(["--teeth", "6", "--dask-workers", "2"])
    assert code == 3 and 'pip install "prs-geom[dask]"' in err
    assert DASK_INSTALL == 'pip install "prs-geom[dask]"'


def test_run_flags_are_checked_before_the_work():
    """The execution flags are those of every command (one definition, one check): exit 2
    naming the flag."""
    code, _, err = _run(["--workers", "2", "--scheduler", "tcp://h:1"])
    assert code == 2 and err.startswith("error: --workers = 2") and "Dask" in err
    code, _, err = _run(["--workers", "0"])
    assert code == 2 and err.startswith("error: --workers = 0: must be >= 1")


def test_cli_sweep_exit_codes(tmp_path, monkeypatch):
    """``prs-geom sweep`` as wired in prs_geom/cli.py: table, CSV file, exit 2 and 3."""
    from cli_helpers import run as cli

    out = tmp_path / "sweep.csv"
    code, stdout, err = cli(["sweep", "--teeth", "6", "8", "--workers", "1", "--out", str(out), "--quiet"])
    assert code == 0, err
    rows = list(csv.DictReader(out.read_text(encoding="utf-8").splitlines()))
    assert [r["engaged_teeth"] for r in rows] == ["6", "8"] and "2 points, 2 valid" in stdout
    code, _, err = cli(["sweep", "--teeth", "6", "--workers", "1", "--out", str(out)])
    assert code == 2 and "already exists" in err
    code, _, err = cli(["sweep", "--loads", "-1", "--workers", "1"])
    assert code == 2 and "loads[0] = -1.0" in err
    monkeypatch.setitem(sys.modules, "distributed", None)
    code, _, err = cli(["sweep", "--teeth", "6", "--scheduler", "tcp://127.0.0.1:8786"])
    assert code == 3 and DASK_INSTALL in err


def test_valid_with_warnings_is_counted_apart_in_table_csv_and_json(tmp_path):
    """A drifting point (4 starts on the 24/8/40 mm default: r_n = 20 != n_n r_r = 16) and an
    implausible one (a 0.05 mm pitch, probably metres) are valid with warnings; a point that
    breaks a rule is invalid; the counts, the status column and the JSON say so."""
    out_csv = tmp_path / "s.csv"
    code, out, err = _run(["--starts", "4", "5", "--rollers", "10", "12", "--teeth", "6", "--workers", "1",
                           "--out", str(out_csv)])
    assert code == 0
    assert "4 points, 1 valid, 1 valid with warnings, 2 invalid, 0 failed" in out
    assert "rollers drift axially by -0.75 mm per screw turn" in out          # 2 x 0.375 x (4 - 5)
    rows = list(csv.DictReader(io.StringIO(out_csv.read_text(encoding="utf-8"))))
    assert [(r["screw_starts"], r["rollers"], r["status"]) for r in rows] == [
        ("4", "10", "warnings"), ("4", "12", "invalid"), ("5", "10", "ok"), ("5", "12", "invalid")]
    assert "drift" in rows[0]["plausibility_warnings"] and rows[2]["plausibility_warnings"] == ""
    assert float(rows[0]["constant_max_ldc"]) > 1.0            # a point with warnings is evaluated
    res = sweep(default_design(), pitch_mm=[0.05], teeth=[6], workers=1)
    row = res.rows()[0]
    assert row["status"] == "warnings" and row["sizing_warnings"] == ""
    assert row["plausibility_warnings"].startswith("thread.pitch_mm = 0.05 is below the plausible minimum 0.1 mm")
    assert res.to_json()["counts"] == {"ok": 0, "warnings": 1, "invalid": 0, "failed": 0}
