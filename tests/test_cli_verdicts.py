"""Verdicts where an engineer expects them, at the command line.

``rating`` prints PASS/FAIL per limit (a failed limit is a warning, with ``--strict`` exit 1),
``validate`` warns on implausible values and drifting rollers (exit 0), ``tolerance`` refuses
to run without an error model (exit 2), and an error on a derived dimension names the part,
the formula and the field it came from (exit 2). The expected numbers are worked by hand
from the default design (24/8/40 mm, 5 starts, p = 2 mm, 20 teeth, 20 kN, 100 rpm).
"""
from __future__ import annotations

import json
import re

import pytest

from cli_helpers import run

#: Permissible speed of the default design: the d n limit 150000 mm/min over d = 24 mm (the
#: critical speed of the 48 mm screw, 0.8 x 1.93e6 rpm, does not govern).
PERMISSIBLE_RPM = 150_000.0 / 24.0


def _limit_rows(out: str) -> dict[str, list[str]]:
    """The limit-check table of the text output: check title -> its cells (split on the two
    or more spaces that must separate every column)."""
    lines = out.splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("limit check"))
    header = re.split(r"\s{2,}", lines[k].strip())
    assert header == ["limit check", "value", "limit", "unit", "margin", "result"]
    rows = {}
    for line in lines[k + 1:k + 6]:
        cells = re.split(r"\s{2,}", line.strip())
        assert len(cells) == 6, line
        rows[cells[0]] = cells
    return rows


# --------------------------------------------------------------------------- rating
def test_rating_default_design_passes_every_limit():
    code, out, err = run(["rating", "--strict"])
    assert code == 0, err
    rows = _limit_rows(out)
    assert list(rows) == ["speed (max)", "d n (max)", "critical speed (max)", "buckling (max)",
                          "static safety s0 (min)"]
    assert all(r[5] == "PASS" for r in rows.values())
    assert rows["speed (max)"][1:5] == ["100", "6250", "rpm", "+61.5"]          # 6250 / 100 - 1
    assert rows["d n (max)"][1:5] == ["2400", "150000", "mm/min", "+61.5"]      # 24 mm x 100 rpm
    assert "warning" not in err


def test_rating_speed_above_the_permissible_fails_with_a_warning_and_exit_0():
    code, out, err = run(["rating", "--speed-rpm", "10000"])
    assert code == 0, err
    rows = _limit_rows(out)
    assert rows["speed (max)"][1:] == ["10000", "6250", "rpm", "-0.375", "FAIL"]     # 6250 / 10000 - 1
    assert rows["d n (max)"][1:] == ["240000", "150000", "mm/min", "-0.375", "FAIL"]
    assert rows["critical speed (max)"][5] == "PASS" and rows["buckling (max)"][5] == "PASS"
    assert "warning: speed 10000 rpm exceeds the permissible 6250 rpm" in err
    assert "warning: d n = nominal diameter x speed = 240000 mm/min exceeds" in err
    assert err.count("warning: ") == 2


def test_rating_strict_exits_1_on_a_failed_limit_and_0_at_the_limit():
    code, out, err = run(["rating", "--speed-rpm", "10000", "--strict"])
    assert code == 1
    assert "error: speed 10000 rpm exceeds the permissible 6250 rpm" in err
    assert "FAIL" in out                                  # the report is still printed
    # exactly at the permissible speed the check passes (margin 0), just above it fails
    code, out, err = run(["rating", "--speed-rpm", f"{PERMISSIBLE_RPM!r}", "--strict"])
    assert code == 0, err
    assert _limit_rows(out)["speed (max)"][4:] == ["+0", "PASS"]
    code, out, err = run(["rating", "--speed-rpm", "6250.001", "--strict", "--json"])
    assert code == 1
    checks = {c["name"]: c for c in json.loads(out)["limits"]["checks"]}
    assert not checks["speed"]["passed"] and checks["speed"]["limit"] == PERMISSIBLE_RPM


def test_rating_absurd_load_fails_static_safety_and_buckling():
    code, out, err = run(["rating", "--mean-load", "2e9", "--json"])
    assert code == 0, err
    rep = json.loads(out)
    checks = {c["name"]: c for c in rep["limits"]["checks"]}
    # s0 = C_0a / F = 94382 N / 2e9 N = 4.7e-5 against the required 2
    assert checks["static_safety"]["value"] == pytest.approx(rep["static_load_rating_n"] / 2e9, rel=1e-12)
    assert checks["static_safety"]["value"] == pytest.approx(4.72e-5, rel=0.01)
    assert checks["static_safety"]["limit"] == 2.0 and not checks["static_safety"]["passed"]
    # Euler, fixed-supported, root 23.2 mm, L 184.75 mm (the actuator's buckling span,
    # docs/theory/actuator.md): pi^2 E I / (0.699 L)^2 / 2 = 8.9208e5 N
    assert not checks["buckling"]["passed"] and checks["buckling"]["limit"] == pytest.approx(8.9208e5, rel=1e-4)
    assert rep["limits"]["all_passed"] is False
    assert "warning: static safety s0 = C_0a / F_max = 4.72e-05 is below the required 2" in err
    assert "warning: axial load 2000000000 N exceeds the permissible buckling load 892081 N" in err


def test_rating_text_columns_never_touch():
    """The large load makes every number long (s0 1.46e-05 next to p_max 171650: the old
    output ran them together as "1716501.46e-05")."""
    code, out, err = run(["rating", "--mean-load", "2e9", "--speed-rpm", "10000"])
    assert code == 0, err
    assert "1716501.46e-05" not in out
    lines = out.splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("life from the tooth loads"))
    for line in lines[k:k + 3]:
        cells = re.split(r"\s{2,}", line.strip())
        assert len(cells) == 5, line
    assert re.split(r"\s{2,}", lines[k + 1].strip())[3:] == ["171650", "1.46e-05"]
    rows = _limit_rows(out)
    assert rows["static safety s0 (min)"][1:3] == ["4.71911e-05", "2"]
    assert rows["buckling (max)"][1:3] == ["2e+09", "892081"]


def test_rating_required_static_safety_from_the_design(tmp_path):
    f = tmp_path / "d.toml"
    f.write_text("[rating]\nrequired_static_safety = 5\n", encoding="utf-8")
    code, out, err = run(["rating", str(f), "--strict"])
    assert code == 1                                       # s0 = 4.72 < 5
    assert "error: static safety s0 = C_0a / F_max = 4.719 is below the required 5" in err
    f.write_text("[rating]\nrequired_static_safety = 25\n", encoding="utf-8")
    code, _, err = run(["rating", str(f)])
    assert code == 2 and err.startswith("error: rating.required_static_safety = 25: must be from 1 to 20")


# --------------------------------------------------------------------------- validate
def test_validate_warns_on_implausible_values_and_exits_0(tmp_path):
    f = tmp_path / "d.toml"
    # without the actuator: at p = 0.05 mm its 200 mm screw would be refused by the memory budget
    f.write_text("[thread]\npitch_mm = 0.05\n[gears]\nenabled = false\n[loading]\naxial_load_n = 2e6\n[rating]\n"
                 "speed_rpm = 30000\n[actuator]\nenabled = false\n",
                 encoding="utf-8")
    code, out, err = run(["validate", str(f)])
    assert code == 0, err
    assert "is valid" in out
    lines = [l for l in err.splitlines() if l.startswith("warning: ")]
    assert "warning: thread.pitch_mm = 0.05 is below the plausible minimum 0.1 mm: " in err
    assert "warning: rating.speed_rpm = 30000.0 is above the plausible maximum 20000 rpm: " in err
    # 2e6 N on the root of 24 - 1.6 x 0.0125 = 23.98 mm: 2e6 / (pi 23.98^2 / 4) = 4428 MPa > 1500
    assert "warning: loading.axial_load_n = 2000000.0 stresses the screw root section" in err
    assert "to 4428 MPa, above the plausible 1500 MPa" in err
    assert len(lines) == 3 and "drift" not in err


def test_validate_warns_on_drifting_rollers(tmp_path):
    # 4 starts on 24/8/40 mm: r_n = 20 != n_n r_r = 16: drift 2 x 12/32 x (4 - 5) = -0.75 mm per turn
    f = tmp_path / "d.toml"
    f.write_text("[screw]\nstarts = 4\n[nut]\nstarts = 4\n", encoding="utf-8")
    code, out, err = run(["validate", str(f)])
    assert code == 0, err
    drift = [l for l in err.splitlines() if "rollers drift axially by" in l]
    assert len(drift) == 1 and drift[0].startswith("warning: rollers drift axially by -0.75 mm per screw turn")
    assert "|drift| <= 1e-06 mm per turn" in drift[0] and "nut.starts = 4" in drift[0]
    code, out, err = run(["validate"])
    assert code == 0 and err == ""                       # the standard sizing: nothing to say


# --------------------------------------------------------------------------- derived dimensions
def test_error_on_a_derived_dimension_names_part_formula_and_source(tmp_path):
    f = tmp_path / "d.toml"
    f.write_text("[thread]\npitch_mm = 2000\n", encoding="utf-8")
    for cmd in ("validate", "rating", "build"):
        code, out, err = run([cmd, str(f)] + (["--out", str(tmp_path / "o")] if cmd == "build" else []))
        assert code == 2, (cmd, err)
        # H = 2000 / (4 tan 45) = 500 mm; screw root 24 - 1.6 x 500 = -776 mm
        assert err.startswith("error: screw.minor_diameter_mm = -776.0 (not in the design file: the default "
                              "screw.pitch_diameter_mm - 1.6 H = 24.0 - 1.6 H"), err
        assert "thread.pitch_mm = 2000.0" in err and "= 500 mm" in err
        assert "the screw minor (root) diameter must be > 0; reduce thread.pitch_mm" in err
    assert not (tmp_path / "o").exists()


# --------------------------------------------------------------------------- tolerance
def test_tolerance_without_an_error_model_stops_with_exit_2(tmp_path):
    code, out, err = run(["tolerance", "--samples", "5"])
    assert code == 2 and out == ""
    assert err.startswith("error: no error model: the design has no [tolerances] section and no error flag")
    assert "[tolerances] section" in err and "--flank-um T" in err and "--eccentricity-um T" in err
    # an error flag, or a [tolerances] section, is an error model (even at 0: asked for on purpose)
    code, out, err = run(["tolerance", "--flank-um", "0", "--samples", "3", "--json", "--workers", "1"])
    assert code == 0, err
    assert json.loads(out)["samples"] == 3
    f = tmp_path / "d.toml"
    f.write_text("[tolerances]\nflank_um = 0.5\nsamples = 4\n", encoding="utf-8")
    code, out, err = run(["tolerance", str(f), "--json", "--workers", "1"])
    assert code == 0, err
    assert json.loads(out)["samples"] == 4
