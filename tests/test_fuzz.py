"""Issue 11: fuzzing the design-file reader and the build.

Hypothesis mutates valid designs (the default, the tiny build design, the graded example
and the harmonic example): values of any type, signs, huge and tiny numbers, deleted and
unknown keys (``format_version`` and ``kind`` included), broken syntax and raw bytes.
Every case must end with exit 0 or 2, one ``error:`` line and never a traceback; a build
must never touch an existing output folder unless it succeeds and the folder is its own.
Most cases only validate (fast); a few build a small design (the ``heavy`` marker runs
more of them with PRS_HEAVY=full).
"""
from __future__ import annotations

import copy
import math
import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cli_helpers import run, to_toml
from prs_geom.model.actuator import ActuatorSettings
from prs_geom.model.design import (GearSettings, MeshSettings, PRSDesign, RatingSettings, Roller, Supports, Thread,
                                   Tolerances)
from prs_geom.model.io import design_to_dict, dumps_toml
from prs_geom.pipeline import load_any_design as load_design

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
TINY = PRSDesign(name="tiny", thread=Thread(engaged_teeth=3), roller=Roller(count=3),
                 mesh=MeshSettings(chord_tolerance_mm=0.05), actuator=ActuatorSettings(enabled=False))


def _with_header(d: dict, kind: str | None = None) -> dict:
    out = {"format_version": 1}
    if kind:
        out["kind"] = kind
    out.update(d)
    return out


BASES = [
    _with_header(design_to_dict(PRSDesign())),
    _with_header(design_to_dict(TINY)),
    # the optional [tolerances] section (added after the first fuzzing), with per-tooth lists
    _with_header(design_to_dict(PRSDesign(name="toleranced", tolerances=Tolerances(
        flank_um=0.5, nut_flank_um=(0.4,) * 20, roller_diameter_um=1.0, samples=5, load_fractions=(0.5, 1.0))))),
    _with_header(design_to_dict(load_design(EXAMPLES / "graded-pitch.toml"))),
    # the optional [supports] and [rating] sections and explicit [gears] values (added later)
    _with_header(design_to_dict(PRSDesign(name="rated", supports=Supports(unsupported_length_mm=300.0),
                                          rating=RatingSettings(preload_n=3000.0),
                                          gears=GearSettings(module_mm=0.4, face_width_mm=3.0)))),
    _with_header(design_to_dict(load_design(EXAMPLES / "harmonic.toml")), "harmonic"),
]


def _paths(d: dict, prefix: tuple = ()) -> list[tuple]:
    out = []
    for k, v in d.items():
        out.append(prefix + (k,))
        if isinstance(v, dict):
            out += _paths(v, prefix + (k,))
    return out


numbers = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 1e-300, -1e-300, 1e300, -1e300, 5e-324, 1e-9, 1e9, 2.0 ** 53]),
    st.integers(min_value=-(2 ** 63), max_value=2 ** 63 - 1),
)
leaf = st.one_of(numbers, st.booleans(), st.text(max_size=12), st.lists(numbers, max_size=25))
any_value = st.one_of(leaf, st.dictionaries(st.text(max_size=6), leaf, max_size=3))


@st.composite
def mutated_design(draw) -> bytes:
    base = copy.deepcopy(draw(st.sampled_from(BASES)))
    for _ in range(draw(st.integers(1, 3))):
        paths = _paths(base)
        path = draw(st.sampled_from(paths))
        parent = base
        for key in path[:-1]:
            parent = parent[key]
        old = parent[path[-1]]
        op = draw(st.sampled_from(["replace", "scale", "negate", "delete", "unknown", "list_item"]))
        if op == "replace":
            parent[path[-1]] = draw(any_value)
        elif op == "scale" and isinstance(old, (int, float)) and not isinstance(old, bool):
            parent[path[-1]] = type(old)(old * draw(st.sampled_from([0, 1e-6, 0.5, 0.99, 1.01, 2, 1e3, 1e12])))
        elif op == "negate" and isinstance(old, (int, float)) and not isinstance(old, bool):
            parent[path[-1]] = -old
        elif op == "delete":
            del parent[path[-1]]
        elif op == "unknown":
            parent[draw(st.text(min_size=1, max_size=10))] = draw(leaf)
        elif op == "list_item" and isinstance(old, list) and old:
            k = draw(st.integers(0, len(old) - 1))
            old[k] = draw(any_value)
    text = to_toml(base).encode("utf-8")
    # raw damage: syntax, encodings, bytes
    damage = draw(st.sampled_from(["none", "none", "none", "bytes", "truncate", "bom", "garbage_line"]))
    if damage == "bytes":
        at = draw(st.integers(0, len(text)))
        text = text[:at] + draw(st.binary(min_size=1, max_size=4)) + text[at:]
    elif damage == "truncate":
        text = text[:draw(st.integers(0, len(text)))]
    elif damage == "bom":
        text = b"\xef\xbb\xbf" + text
    elif damage == "garbage_line":
        text = text + draw(st.text(max_size=20)).encode("utf-8", "surrogatepass") + b"\n"
    return text


#: The one exit-3 outcome a design file can cause: its build's estimated memory is over the
#: budget (validate and build check it up front, docs/cli.md "memory budget").
BUDGET_REFUSAL = "error: this design is too large to mesh here: "


def _assert_clean(code: int, out: str, err: str) -> None:
    assert code in (0, 2, 3), (code, err)
    assert "Traceback" not in err and "Traceback" not in out
    if code in (2, 3):
        lines = err.strip().splitlines()
        assert lines and lines[-1].startswith("error: "), err
        assert "np.float64" not in err
    if code == 3:
        assert lines[-1].startswith(BUDGET_REFUSAL) and "over the budget" in lines[-1], err


@settings(max_examples=3000 if os.environ.get("PRS_HEAVY") == "full" else 300, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
          deadline=None)
@given(raw=mutated_design())
def test_validate_never_crashes(tmp_path_factory, raw):
    f = tmp_path_factory.mktemp("fuzz") / "d.toml"
    f.write_bytes(raw)
    code, out, err = run(["validate", str(f)])
    _assert_clean(code, out, err)


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@st.composite
def small_build_design(draw) -> bytes:
    """Mutations of the tiny design that stay small when valid."""
    base = copy.deepcopy(BASES[1])
    path = draw(st.sampled_from([p for p in _paths(base) if not isinstance(_get(base, p), dict)]))
    parent = base
    for key in path[:-1]:
        parent = parent[key]
    old = parent[path[-1]]
    if isinstance(old, (int, float)) and not isinstance(old, bool) and path[-1] not in ("engaged_teeth",
                                                                                      "count", "starts"):
        parent[path[-1]] = draw(st.one_of(st.sampled_from([-old, 0, 1e300, math.nan]),
                                          st.floats(0.9 * old, 1.1 * old) if old > 0 else st.just(old)))
    else:
        parent[path[-1]] = draw(leaf)
    return to_toml(base).encode()


def _build_case(tmp_path: Path, raw: bytes) -> None:
    f = tmp_path / "d.toml"
    f.write_bytes(raw)
    user = tmp_path / "user"
    user.mkdir()
    (user / "keep.txt").write_text("mine")
    own = tmp_path / "own"
    assert run(["build", str(tmp_path / "seed.toml"), "--out", str(own), "--quiet",
                "--memory-budget", "2G"])[0] == 0
    own_before, user_before = _snapshot(own), _snapshot(user)
    code, out, err = run(["build", str(f), "--out", str(user), "--quiet", "--memory-budget", "2G"])
    _assert_clean(code, out, err)
    assert code == 2 and _snapshot(user) == user_before        # a user folder: always refused
    code, out, err = run(["build", str(f), "--out", str(own), "--quiet", "--memory-budget", "2G"])
    _assert_clean(code, out, err)
    if code in (2, 3):
        assert _snapshot(own) == own_before                     # a failed build leaves it as it was
    else:
        assert (own / "report.json").is_file()


def _get(d, path):
    for k in path:
        d = d[k]
    return d


def _build_examples(heavy: bool) -> int:
    return 12 if heavy else 3


@pytest.mark.heavy
@given(raw=small_build_design())
@settings(max_examples=_build_examples(os.environ.get("PRS_HEAVY") == "full"), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
def test_small_builds_never_crash_or_touch_existing_folders(tmp_path_factory, raw):
    tmp = tmp_path_factory.mktemp("fuzzbuild")
    (tmp / "seed.toml").write_text(dumps_toml(TINY))
    _build_case(tmp, raw)
