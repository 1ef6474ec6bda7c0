"""Issue 29, "every numeric path guarded": every numeric field of the PRS design, set to each
of nan, +-inf, +-1e308, 5e-324, 0 and -1, through ``validate``, ``contact``, ``loads`` and
``rating`` (in-process), ends with exit 0 or 2, never 1 (a solver failing on bad input) or 70
(an overflow, an underflow or a division by zero in the analysis). Exit 2 names the field
first (``error: <field> = <value>: ...``); exit 0 prints only finite numbers (the ``--json``
output has no NaN or Infinity).

The fields are enumerated from the design dataclasses (every int or float field, and element
0 of every list of numbers), not listed by hand, so that a new field is fuzzed the day it is
added. ``build`` runs the values the model accepts on a small design (3 teeth, 3 rollers,
0.05 mm chord tolerance); a build takes seconds, so by default only one such value per
section of :data:`BUILD_SECTIONS` is built (the ``heavy`` marker, PRS_HEAVY=full, builds
them all).
"""
from __future__ import annotations

import dataclasses
import json
import math
import typing
from functools import lru_cache
from pathlib import Path

import pytest

from cli_helpers import run, to_toml
from prs_geom.model.design import (FLANK_FIELDS, MeshSettings, Nut, PRSDesign, Roller, Thread, Tolerances,
                                   default_design)
from prs_geom.model.io import design_to_dict

#: The values of the issue: not numbers, beyond any range, the smallest subnormal, zero, negative.
VALUES = (math.nan, math.inf, -math.inf, 1e308, -1e308, 5e-324, 0, -1)
COMMANDS = ("validate", "contact", "loads", "rating")
#: The small design of the build sweep.
SMALL = {"thread": {"engaged_teeth": 3}, "roller": {"count": 3}, "mesh": {"chord_tolerance_mm": 0.05},
         "actuator": {"enabled": False}}
#: Sections whose accepted values the default (reduced) build sweep builds, one value each:
#: the Monte Carlo study, the gear meshes and checks, the mechanism parts and stack-up, the
#: contact solve that sizes the theoretical screw of every mesh.
BUILD_SECTIONS = ("tolerances", "gears", "mechanism", "contact")


def _numeric_fields(cls: type, prefix: str = "") -> list[tuple[str, bool]]:
    """(dotted path, is a list) of every int/float field of ``cls`` and its sections, from
    the type hints (``bool`` and text fields left out)."""
    hints = typing.get_type_hints(cls)
    out = []
    for f in dataclasses.fields(cls):
        t = hints[f.name]
        section = f.metadata.get("section") or (t if dataclasses.is_dataclass(t) else None)
        if section is not None:
            out += _numeric_fields(section, f"{prefix}{f.name}.")
            continue
        args = typing.get_args(t)
        flat = {t, *args, *(x for a in args for x in typing.get_args(a))}
        if flat & {int, float} and bool not in flat:
            out.append((prefix + f.name, any(typing.get_origin(x) is tuple for x in (t, *args))))
    return out


FIELDS = _numeric_fields(PRSDesign)


def _reference_lists(n: int) -> dict[str, list]:
    """A valid value of every list field for a design of ``n`` teeth (element 0 is replaced)."""
    p = Thread().pitch_mm
    ref = PRSDesign(thread=Thread(engaged_teeth=n), roller=Roller(pitch_list_mm=(p,) * (n - 1)),
                    nut=Nut(pitch_list_mm=(p,) * (n - 1)),
                    tolerances=Tolerances(**{k: (0.0,) * n for k in FLANK_FIELDS}))
    out = {}

    def walk(d: dict, prefix: str) -> None:
        for k, v in d.items():
            if isinstance(v, dict):
                walk(v, f"{prefix}{k}.")
            elif isinstance(v, list):
                out[prefix + k] = v

    walk(design_to_dict(ref), "")
    return out


def _document(path: str, is_list: bool, value, base: dict | None = None, n: int = 20) -> tuple[dict, str]:
    """A design document (``base`` plus the field) and the name an error must give."""
    doc = json.loads(json.dumps(base or {}))
    node = doc
    *sections, key = path.split(".")
    for s in sections:
        node = node.setdefault(s, {})
    if is_list:
        lst = list(_reference_lists(n)[path])
        lst[0] = value
        node[key] = lst
        return doc, f"{path}[0]"
    node[key] = value
    return doc, path


def _no_constant(name: str):
    raise ValueError(f"non-finite number {name} in the output")


def _check(argv: list[str], name: str) -> str | None:
    """None when ``prs-geom argv`` ends as the issue asks, else what went wrong."""
    code, out, err = run(argv)
    if code == 2:
        return None if err.startswith(f"error: {name}") else f"exit 2 not naming {name}: {err.strip()[:300]}"
    if code != 0:
        return f"exit {code}: {err.strip()[-300:]}"
    if "--json" in argv:
        try:
            json.loads(out, parse_constant=_no_constant)
        except ValueError as exc:
            return f"exit 0 with {exc}"
    return None


def test_the_fields_are_every_numeric_leaf_of_the_design():
    """The enumeration covers every number the design file holds (the default design's
    leaves, the optional sections and lists included) and nothing that is not a number."""
    paths = {p for p, _ in FIELDS}
    leaves = set()

    def walk(d: dict, prefix: str) -> None:
        for k, v in d.items():
            if isinstance(v, dict):
                walk(v, f"{prefix}{k}.")
            elif isinstance(v, (int, float)) and not isinstance(v, bool):
                leaves.add(prefix + k)

    full = PRSDesign(tolerances=Tolerances(target_ldc=1.1, confidence=0.9))
    walk(design_to_dict(full), "")
    assert leaves <= paths
    assert {"thread.engaged_teeth", "loading.axial_load_n", "materials.retaining_ring.density_kg_m3",
            "supports.unsupported_length_mm", "rating.preload_n", "roller.pitch_list_mm",
            "tolerances.load_fractions", "mechanism.ring_bore_mm", "gears.module_mm"} <= paths
    assert not paths & {"name", "thread.hand", "gears.enabled", "tolerances.source", "loads.compliance"}
    assert len(FIELDS) >= 80


@pytest.mark.parametrize("path,is_list", FIELDS, ids=[p for p, _ in FIELDS])
def test_each_value_gives_exit_0_or_2_naming_the_field(path, is_list, tmp_path):
    f = tmp_path / "d.toml"
    failures = []
    for value in VALUES:
        doc, name = _document(path, is_list, value)
        f.write_text(to_toml(doc))
        for command in COMMANDS:
            argv = [command, str(f)] + ([] if command == "validate" else ["--json"])
            problem = _check(argv, name)
            if problem:
                failures.append(f"{command} {name} = {value!r}: {problem}")
    assert failures == []


@lru_cache(maxsize=1)
def _accepted_on_the_small_design() -> tuple[tuple[str, bool, object], ...]:
    """(path, is a list, value) of every field and value the small design accepts."""
    import tempfile

    out = []
    with tempfile.TemporaryDirectory() as tmp:
        f = Path(tmp) / "d.toml"
        for path, is_list in FIELDS:
            for value in VALUES:
                doc, _ = _document(path, is_list, value, SMALL, n=SMALL["thread"]["engaged_teeth"])
                f.write_text(to_toml(doc))
                if run(["validate", str(f)])[0] == 0:
                    out.append((path, is_list, value))
    return tuple(out)


def _build_cases(full: bool) -> list[tuple[str, bool, object]]:
    accepted = _accepted_on_the_small_design()
    if full:
        return list(accepted)
    # one per section, the subnormal first where the section accepts one
    cases = []
    for section in BUILD_SECTIONS:
        mine = sorted((c for c in accepted if c[0].split(".")[0] == section), key=lambda c: c[2] != 5e-324)
        cases += mine[:1]
    return cases


@pytest.mark.heavy
def test_build_of_every_accepted_value_gives_exit_0_or_2(tmp_path, heavy_scale):
    cases = _build_cases(heavy_scale == "full")
    assert len(cases) >= 20 if heavy_scale == "full" else len(cases) == len(BUILD_SECTIONS)
    f = tmp_path / "d.toml"
    failures = []
    for k, (path, is_list, value) in enumerate(cases):
        doc, name = _document(path, is_list, value, SMALL, n=SMALL["thread"]["engaged_teeth"])
        f.write_text(to_toml(doc))
        out = tmp_path / f"out{k}"
        problem = _check(["build", str(f), "--out", str(out), "--quiet"], name)
        if problem is None and out.exists():
            try:
                json.loads((out / "report.json").read_text(encoding="utf-8"), parse_constant=_no_constant)
            except ValueError as exc:
                problem = f"report.json: {exc}"
        if problem:
            failures.append(f"build {name} = {value!r}: {problem}")
    assert failures == []


def test_the_issue_cases():
    """The cases the audit found, one by one: exit 2 naming the field and the range."""
    import tempfile

    cases = [("rating", "loading.axial_load_n", 1e308, "must be from 1 N to 1e+10 N"),
             ("rating", "screw.length_mm", 1e308, "1e+07 mm"),
             ("rating", "supports.unsupported_length_mm", 5e-324, "must be from 0.01 mm"),
             ("rating", "rating.preload_n", 1e308, "must be from 1 N to 1e+10 N"),
             ("loads", "loading.axial_load_n", 5e-324, "must be from 1 N to 1e+10 N"),
             ("validate", "thread.pitch_mm", 5e-324, "must be at least 0.01 mm")]
    with tempfile.TemporaryDirectory() as tmp:
        f = Path(tmp) / "d.toml"
        for command, path, value, rule in cases:
            f.write_text(to_toml(_document(path, False, value)[0]))
            code, _, err = run([command, str(f)])
            assert code == 2 and err.startswith(f"error: {path} = {value!r}") and rule in err, (path, err)


def test_loads_too_small_for_the_model_name_the_field(tmp_path):
    """Within the bounds, a load the model cannot describe is refused with the load that
    would do: a stiff material at 1 N (sub-nanometre approach), and pitch lists whose 2 % step
    dwarfs the approach at 10 N (the solver used to give up, exit 1)."""
    f = tmp_path / "d.toml"
    stiff = {part: {"youngs_modulus_mpa": 1e7} for part in ("screw", "roller", "nut")}
    f.write_text(to_toml({"loading": {"axial_load_n": 1.0}, "materials": stiff}))
    code, _, err = run(["loads", str(f)])
    assert code == 2 and err.startswith("error: loading.axial_load_n = 1.0: a tooth contact deflects by")
    assert "increase loading.axial_load_n to at least" in err
    p = Thread().pitch_mm
    steps = [p * 1.0199] + [p] * 18
    f.write_text(to_toml({"loading": {"axial_load_n": 10.0}, "roller": {"pitch_list_mm": steps}}))
    for command in ("loads", "rating"):
        code, _, err = run([command, str(f)])
        assert code == 2 and err.startswith("error: loading.axial_load_n = 10.0: the pitch lists open gaps"), err
    f.write_text(to_toml({"loading": {"axial_load_n": 100.0}, "roller": {"pitch_list_mm": steps}}))
    assert run(["loads", str(f)])[0] == 0


def test_rating_flags_and_spectrum_have_the_design_ranges(tmp_path):
    for argv, name in ((["--mean-load", "1e308"], "--mean-load"), (["--mean-load", "5e-324"], "--mean-load"),
                       (["--speed-rpm", "5e-324"], "--speed-rpm"), (["--life-hours", "1e308"], "--life-hours")):
        code, _, err = run(["rating"] + argv)
        assert code == 2 and err.startswith(f"error: {name} = "), err
    spec = tmp_path / "duty.toml"
    spec.write_text("[[case]]\nload_n = 1e300\ntime_share = 1.0\nspeed_rpm = 100.0\n")
    code, _, err = run(["rating", "--spectrum", str(spec)])
    assert code == 2 and "case[0].load_n" in err and "1e+10 N" in err, err


def test_a_small_design_still_builds_at_the_bounds(tmp_path):
    """The smallest accepted load and preload and the shortest free length give finite
    ratings (the bounds are inside what the analysis handles)."""
    from prs_geom.analysis.rating import analyse_rating
    from prs_geom.exports.report import rating_section
    from prs_geom.model.design import Loading, RatingSettings, Supports

    d = default_design().with_changes(loading=Loading(axial_load_n=1.0), rating=RatingSettings(preload_n=1e10),
                                      supports=Supports(unsupported_length_mm=0.01))
    sec = rating_section(analyse_rating(d))
    json.loads(json.dumps(sec), parse_constant=_no_constant)
    d = PRSDesign(thread=Thread(engaged_teeth=3), roller=Roller(count=3), mesh=MeshSettings(chord_tolerance_mm=0.05),
                  loading=Loading(axial_load_n=1e10), rating=RatingSettings(preload_n=1.0, speed_rpm=0.01))
    json.loads(json.dumps(rating_section(analyse_rating(d))), parse_constant=_no_constant)


def test_a_target_without_its_confidence_reaches_the_machining_sheets():
    """Found by the build sweep: ``tolerances.target_ldc`` without ``confidence`` (the file may
    say one without the other) was exit 70 in the machining sheets; a target above the tooth
    count is refused (no coefficient can exceed it)."""
    from prs_geom.analysis.contact import analyse_contact
    from prs_geom.analysis.machining import machining_sheets
    from prs_geom.model.errors import DesignError

    d = PRSDesign(thread=Thread(engaged_teeth=3), tolerances=Tolerances(flank_um=1.0, target_ldc=1.2))
    sheets = machining_sheets(d, analyse_contact(d))
    assert "target worst LDC 1.2, seed 0" in json.dumps({k: v.as_dict() for k, v in sheets.items()})
    with pytest.raises(DesignError, match=r"^tolerances.target_ldc = 4.0: must be at most engaged_teeth = 3"):
        PRSDesign(thread=Thread(engaged_teeth=3), tolerances=Tolerances(target_ldc=4.0))
