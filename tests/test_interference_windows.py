"""Windowed interference check of long designs: checked slab by slab, a design
gives the verdict, the pair rows, the overlap volumes, thicknesses, contact counts and teeth of
the whole check, and the slabs tile the axis."""
from __future__ import annotations

from dataclasses import replace
from typing import Any

import manifold3d
import numpy as np
import pytest

import prs_geom.checks.interference as itf
from prs_geom.analysis.contact import theoretical_screw
from prs_geom.mesh import budget
from prs_geom.model.design import default_design

#: Coarse meshes keep the test quick; the slab bookkeeping does not depend on the tolerance.
TOL = 0.01
TEETH = 24


def _quiet(*_: Any) -> None:
    return None


@pytest.fixture(scope="module")
def design():
    # the threads and mechanism alone: an actuator's check is clipped to the nut assembly
    # (budget.check_span), which the whole check of this comparison is not
    d = default_design()
    return replace(d, thread=replace(d.thread, engaged_teeth=TEETH), screw=replace(d.screw, length_mm=None),
                   actuator=replace(d.actuator, enabled=False))


@pytest.fixture(scope="module")
def whole_and_windowed(design):
    """The whole check (both screws, as for a short design) and the windowed one in three
    slabs of 8 teeth, at the same coarse check tolerance."""
    prof = theoretical_screw(design).profile
    cache: dict[str, dict[Any, Any]] = {}
    whole, asm = itf._interference(design, "corrected", TOL, _quiet, prof, cache=cache)
    whole["nominal_screw"] = itf._interference(design, "nominal", TOL, _quiet, None, reuse=asm, cache=cache)[0]
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(itf, "CHECK_TOLERANCE_MM", TOL)
        mp.setattr(budget, "CHECK_WINDOW_TEETH", 8)
        windowed = itf.interference_checks(design, prof, progress=_quiet)
    return whole, windowed


def test_slabs_tile_the_axis_at_whole_teeth(design, monkeypatch):
    assert budget.check_windows(default_design()) is None     # 20 teeth: checked whole
    monkeypatch.setattr(budget, "CHECK_WINDOW_TEETH", 10)
    slabs = budget.check_windows(design)
    p = design.thread.pitch_mm
    # ceil(24 / 10) = 3 slabs of 8 teeth; open at both ends
    assert slabs == [(-np.inf, 8 * p), (8 * p, 16 * p), (16 * p, np.inf)]
    monkeypatch.setattr(budget, "CHECK_WINDOW_TEETH", 7)
    cuts = [lo for lo, _ in budget.check_windows(design)[1:]]
    assert np.allclose(np.diff([0.0, *cuts, TEETH * p]) / p, [6, 6, 6, 6])


@pytest.mark.parametrize("screw", ["corrected", "nominal"])
def test_windowed_check_reports_the_whole_check(whole_and_windowed, screw):
    whole, windowed = whole_and_windowed
    if screw == "nominal":
        whole, windowed = whole["nominal_screw"], windowed["nominal_screw"]
    assert windowed["axial_windows"] == 3
    assert windowed["pairs_checked"] == whole["pairs_checked"]
    assert windowed["found"] == whole["found"]
    assert windowed["found"] == (screw == "nominal")    # the nominal screw interferes, as in the golden
    for key in ("pairs", "contact_within_tolerance"):
        a, b = whole[key], windowed[key]
        assert [r["pair"] for r in a] == [r["pair"] for r in b]
        # rows to compare: flank contacts on both screws, interference with the nominal one
        assert len(a) > 0 or (key, screw) == ("pairs", "corrected")
        for ra, rb in zip(a, b):
            assert ra["teeth"] == rb["teeth"]
            assert ra["fcl_contacts"] == rb["fcl_contacts"]
            # the slab pieces of the overlap solids add up to the whole solid: rounding only
            assert rb["volume_mm3"] == pytest.approx(ra["volume_mm3"], rel=1e-9, abs=1e-12)
            assert rb["mean_thickness_mm"] == pytest.approx(ra["mean_thickness_mm"], rel=1e-9, abs=1e-12)


def test_check_command_of_one_screw_is_windowed_too(design, whole_and_windowed, monkeypatch):
    """``prs-geom check`` (one screw) windows a long design like the build does."""
    monkeypatch.setattr(itf, "CHECK_TOLERANCE_MM", TOL)
    monkeypatch.setattr(budget, "CHECK_WINDOW_TEETH", 8)
    one = itf.interference(design, "nominal")
    both = whole_and_windowed[1]["nominal_screw"]
    assert one["axial_windows"] == 3
    # the same computation, except that manifold3d's last bits depend on what it evaluated
    # before (its solids are lazy CSG trees)
    for key in ("pairs", "contact_within_tolerance"):
        assert [{k: v for k, v in r.items() if k not in ("volume_mm3", "mean_thickness_mm")} for r in one[key]] \
            == [{k: v for k, v in r.items() if k not in ("volume_mm3", "mean_thickness_mm")} for r in both[key]]
        for a, b in zip(one[key], both[key]):
            assert (a["volume_mm3"], a["mean_thickness_mm"]) == pytest.approx(
                (b["volume_mm3"], b["mean_thickness_mm"]), rel=1e-12, abs=1e-15)
    rest = [k for k in one if k not in ("time_s", "pairs", "contact_within_tolerance")]
    assert {k: one[k] for k in rest} == {k: both[k] for k in rest}


def test_trimmed_pieces_add_up_to_the_solid():
    """A sphere cut into slabs: volumes and surface areas (without the cut faces) sum to the
    sphere's own (manifold3d's polygon sphere, so compared with its uncut values)."""
    sphere = manifold3d.Manifold.sphere(2.0, 256).translate((0.3, -0.2, 1.0))
    cuts = [-np.inf, -0.4, 0.5, 1.0, 2.2, np.inf]
    pieces = [itf._trimmed(sphere, (lo, hi)) for lo, hi in zip(cuts[:-1], cuts[1:])]
    assert sum(v for v, _ in pieces) == pytest.approx(sphere.volume(), rel=1e-12)
    assert sum(a for _, a in pieces) == pytest.approx(sphere.surface_area(), rel=1e-12)
    # and each piece's volume is that of the spherical segment it cuts (closed form, to the
    # polygon sphere's own volume error)
    r = 2.0
    def cap(h):   # volume of the part of a ball of radius r below height h over its bottom
        h = min(max(h, 0.0), 2 * r)
        return np.pi * h * h * (3 * r - h) / 3
    for (lo, hi), (v, _) in zip(zip(cuts[:-1], cuts[1:]), pieces):
        exact = cap(hi - 1.0 + r) - cap(lo - 1.0 + r)
        assert v == pytest.approx(exact, rel=1e-3)


def test_budget_counts_one_window_of_check_meshes(design, monkeypatch):
    monkeypatch.setattr(budget, "CHECK_WINDOW_TEETH", TEETH)
    whole = budget.estimate(design, export=False)
    monkeypatch.setattr(budget, "CHECK_WINDOW_TEETH", 8)
    windowed = budget.estimate(design, export=False)
    assert windowed.check_triangles == pytest.approx(whole.check_triangles * 10 / TEETH)


def test_long_design_builds_without_workers(tmp_path, monkeypatch):
    """A design whose check runs in windows is built serially even when workers are asked
    for (the check beside the export meshing would add the two peaks again)."""
    import prs_geom.pipeline as pipeline

    seen: list[Any] = []

    class Stop(Exception):
        pass

    def fake_run_stages(*args, workers=None, **kwargs):
        seen.append(workers)
        raise Stop

    monkeypatch.setenv("PRS_GEOM_WORKERS", "2")
    monkeypatch.setattr(pipeline, "run_stages", fake_run_stages)
    for window, expected in ((TEETH, 2), (8, 0)):
        monkeypatch.setattr(budget, "CHECK_WINDOW_TEETH", window)
        d = replace(default_design(), thread=replace(default_design().thread, engaged_teeth=TEETH),
                    screw=replace(default_design().screw, length_mm=None))
        with pytest.raises(Stop):
            pipeline.build(d, tmp_path / f"w{window}", memory_budget=2 ** 40)
    assert seen == [2, 0]


def test_progress_counts_pairs_in_one_window_and_windows_in_several(design, monkeypatch):
    """An actuator's check is one window (its nut span): the progress counts its pairs, up
    to all of them, once per screw. Several windows: it counts the windows only (a pair
    count would start again at 0 in each)."""
    monkeypatch.setattr(itf, "CHECK_TOLERANCE_MM", TOL)
    actuator = default_design()
    assert budget.check_windows(actuator) is None and budget.check_span(actuator) is not None
    calls: list[tuple[str, int, int]] = []
    itf.interference_checks(actuator, theoretical_screw(actuator).profile,
                            progress=lambda stage, done, total: calls.append((stage, done, total)))
    pairs = [c for c in calls if c[0] == "interference pairs"]
    finished = [c for c in pairs if c[1] == c[2]]
    assert len(finished) == 2 and finished[0][2] > 1000               # both screws, every pair
    assert all(0 <= done <= total for _, done, total in pairs)
    assert calls[-1] == ("interference windows", 1, 1)
    calls.clear()
    monkeypatch.setattr(budget, "CHECK_WINDOW_TEETH", 8)
    itf.interference_checks(design, theoretical_screw(design).profile,
                            progress=lambda stage, done, total: calls.append((stage, done, total)))
    assert calls == [("interference windows", k, 3) for k in (1, 2, 3)]
