"""Interference check reuse: the nominal-screw check reuses the BVHs, solids and
pair outcomes of the corrected-screw check, and reports what a check from scratch reports."""
from __future__ import annotations

from typing import Any

import pytest

import prs_geom.checks.interference as itf
from prs_geom.analysis.contact import theoretical_screw
from prs_geom.model.design import default_design

#: Coarse meshes keep the test quick; what is tested does not depend on the tolerance.
TOL = 0.01


def _quiet(*_: Any) -> None:
    return None


def _strip_times(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {k: _strip_times(v) for k, v in obj.items() if k != "time_s"}
    if isinstance(obj, list):
        return [_strip_times(v) for v in obj]
    return obj


@pytest.fixture(scope="module")
def design():
    return default_design()


@pytest.fixture(scope="module")
def screw_profile(design):
    return theoretical_screw(design).profile


@pytest.fixture(scope="module")
def checks(design, screw_profile):
    """The corrected and the nominal check sharing one cache, with the FCL queries and BVH
    builds of each counted."""
    queries: list[int] = []
    bvhs: list[int] = []
    collide, bvh_model = itf.fcl.collide, itf.bvh_model

    def counting_collide(*args):
        queries.append(1)
        return collide(*args)

    def counting_bvh(V, F):
        bvhs.append(len(F))
        return bvh_model(V, F)

    cache: dict[str, dict[Any, Any]] = {}
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(itf.fcl, "collide", counting_collide)
        mp.setattr(itf, "bvh_model", counting_bvh)
        corrected, asm = itf._interference(design, "corrected", TOL, _quiet, screw_profile, cache=cache)
        counts = {"corrected": (len(queries), len(bvhs))}
        queries.clear()
        bvhs.clear()
        nominal, _ = itf._interference(design, "nominal", TOL, _quiet, None, reuse=asm, cache=cache)
        counts["nominal"] = (len(queries), len(bvhs))
        counts["nominal_faces"] = list(bvhs)
    return {"corrected": corrected, "nominal": nominal, "asm": asm, "cache": cache, "counts": counts}


@pytest.fixture(scope="module")
def fresh_nominal(design):
    """The nominal check from scratch: its own meshes, BVHs and queries."""
    return itf._interference(design, "nominal", TOL, _quiet, None)[0]


def _touching(asm, pairs):
    """The pairs whose placed meshes' bounds meet (the broad phase's own functions)."""
    from prs_geom.checks.broad_phase import can_touch, placed_bounds

    bounds = {name: placed_bounds(mesh.vertices, mesh.faces, T) for name, (mesh, T, _) in asm.placed.items()}
    return [(a, b) for a, b in pairs if can_touch(bounds[a], bounds[b])]


def test_nominal_check_queries_only_the_pairs_with_the_new_screw(checks):
    asm = checks["asm"]
    pairs = itf.body_pairs(list(asm.placed))
    assert checks["corrected"]["pairs_checked"] == len(pairs)
    touching = _touching(asm, pairs)
    # the broad phase settles most pairs: FCL is asked only of those whose bounds meet
    assert len(touching) < len(pairs) / 5
    assert checks["counts"]["corrected"][0] == len(touching)
    # the nominal check asks only the pairs with the new screw mesh that can touch it (the
    # screw ends are the same meshes); the screw is met through slices of its faces, one
    # BVH per other body at most, no whole BVH
    with_screw = [p for p in touching if "screw" in p]
    assert checks["counts"]["nominal"][0] == len(with_screw)
    screw_faces = len(asm.placed["screw"][0].faces)
    assert screw_faces >= itf.SPLIT_FACES
    assert 0 < checks["counts"]["nominal"][1] <= len({asm.rigid_body(b) for _, b in with_screw})
    assert screw_faces not in checks["counts"]["nominal_faces"]
    nominal = checks["nominal"]
    assert nominal["pairs_checked"] == checks["corrected"]["pairs_checked"]
    # the nominal screw interferes; the contacts without the screw (roller-nut flanks, the
    # actuator's bearing pair) are reused, not lost; the screw's own contacts (the bearings on
    # the shoulders at its thread's end faces) are queried again and found again
    assert nominal["found"]
    rows = {name: checks[name]["contact_within_tolerance"] for name in ("corrected", "nominal")}
    assert [r for r in rows["nominal"] if "screw" not in r["pair"]] == \
        [r for r in rows["corrected"] if "screw" not in r["pair"]]
    assert [r["pair"] for r in rows["nominal"] if "screw" in r["pair"]] == \
        [r["pair"] for r in rows["corrected"] if "screw" in r["pair"]] == \
        [["screw", "bearing_fixed_0"], ["screw", "bearing_floating_0"]]


def test_reused_outcomes_are_those_of_a_check_from_scratch(checks, fresh_nominal):
    assert _strip_times(checks["nominal"]) == _strip_times(fresh_nominal)
    # a second check of the same assembly with the same cache asks nothing new and agrees
    again = itf.check_assembly(checks["asm"], TOL, _quiet, checks["cache"])
    assert _strip_times(again) == {k: v for k, v in _strip_times(checks["corrected"]).items()
                                   if k not in ("screw", "screw_pitch_diameter_mm")}


def test_teeth_and_contact_counts_of_the_screw_roller_threads(design, fresh_nominal):
    """The teeth are read from FCL's contact heights: every engaged tooth of every nominal
    screw-roller thread pair, as plain ints."""
    threads = [r for r in fresh_nominal["pairs"] if r["pair"][0] == "screw" and "gear" not in r["pair"][1]]
    assert len(threads) == design.roller.count
    for row in threads:
        assert row["teeth"] == list(range(1, design.thread.engaged_teeth + 1))
        assert row["fcl_contacts"] > 0 and all(type(t) is int for t in row["teeth"])
