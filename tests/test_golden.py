"""Golden outputs (issue 12, 17): a restructuring keeps every number and every file byte.

The goldens in tests/golden/data were written by tests/golden/regenerate.py; see
tests/golden/fingerprint.py for what is compared and how to regenerate them.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent / "golden"))

pytestmark = pytest.mark.golden

from fingerprint import DATA, DESIGNS, build_fingerprint, compare_numbers  # noqa: E402


@pytest.mark.parametrize("key", sorted(DESIGNS))
def test_build_matches_golden(key, tmp_path, monkeypatch):
    # a build as users run it: checks, drawings and plots in two worker processes
    monkeypatch.setenv("PRS_GEOM_WORKERS", "2")
    golden_file = DATA / f"{key}.json"
    if not golden_file.exists():
        pytest.fail(f"no golden for {key}: run tests/golden/regenerate.py")
    golden = json.loads(golden_file.read_text())
    new = build_fingerprint(key, tmp_path / key)
    diffs = compare_numbers(golden["report"], new["report"])
    assert not diffs, "report.json differs from the golden:\n" + "\n".join(diffs[:20])
    changed = {f for f in golden["files"].keys() | new["files"].keys()
               if golden["files"].get(f) != new["files"].get(f)}
    assert not changed, f"files differ from the golden: {sorted(changed)}"


def test_serial_build_matches_golden(tmp_path, monkeypatch):
    """Issue 17: the checks, drawings and plots run in worker processes by default; with
    ``PRS_GEOM_WORKERS=0`` everything runs in order in one process, and the report and
    every file are the same as the golden (which the parallel build matches, above)."""
    monkeypatch.setenv("PRS_GEOM_WORKERS", "0")
    golden = json.loads((DATA / "default.json").read_text())
    new = build_fingerprint("default", tmp_path / "default")
    assert not compare_numbers(golden["report"], new["report"])
    assert new["files"] == golden["files"]
