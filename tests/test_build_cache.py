"""The stage cache: a rebuild redoes only the stages whose inputs changed, and gives the same
outputs (prs_geom.build_cache, prs_geom.runtime.stage_cache, prs_geom.pipeline.run_stages).

What a stage reads is not taken from the declarations under test: ``tests/stage_reads.py``
watches builds read their designs field by field. The declarations must cover every read,
and a change of one design field must miss the cache in exactly the stages that read it
(themselves or through an upstream result) and hit it in every other one.
"""
from __future__ import annotations

import dataclasses
import json
import os
import re
import sys
from pathlib import Path

import numpy as np
import pytest

import prs_geom as pg
from prs_geom.build_cache import DEFINITION, closure, covers, inputs, stage_keys
from prs_geom.model.design import PRSDesign, RatingSettings, Supports, Tolerances
from prs_geom.model.errors import DesignError
from prs_geom.pipeline import STAGES, BuildOptions, build, load_any_design
from prs_geom.runtime.stage_cache import (KEEP, StageCache, StageRecord, Uncacheable, decode, encode,
                                          source_fingerprint)
from stage_reads import stage_reads

sys.path.insert(0, str(Path(__file__).resolve().parent / "golden"))
from fingerprint import DATA, compare_numbers, fingerprint  # noqa: E402

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
STAGE_NAMES = [name for name, _ in STAGES]
DATE = "2026-01-01"
EPOCH = "1767225600"


def coarse(design: PRSDesign) -> PRSDesign:
    """``design`` meshed at 10 um: the fields a build reads do not depend on the chord
    tolerance, and the watched builds take a third of the time."""
    return design.with_changes(mesh=dataclasses.replace(design.mesh, chord_tolerance_mm=0.01))


def full_design() -> PRSDesign:
    """The default design with every optional section present and the flange bolt given,
    so that every field is one the stages can read directly (the load then sizes no part)."""
    d = pg.default_design()
    mount = dataclasses.replace(d.actuator.nut_mount, bolt="M5")
    return coarse(d).with_changes(tolerances=Tolerances(flank_um=1.0, samples=64, target_ldc=1.5, confidence=0.9),
                                  supports=Supports(unsupported_length_mm=300.0), rating=RatingSettings(preload_n=500.0),
                                  actuator=dataclasses.replace(d.actuator, nut_mount=mount))


@pytest.fixture(scope="module")
def reads(tmp_path_factory, heavy_scale) -> dict[str, dict[str, set[str]]]:
    """Design label -> stage -> the fields its build read (serial builds, watched)."""
    designs = {"full": full_design(), "graded-pitch": coarse(load_any_design(EXAMPLES / "graded-pitch.toml"))}
    if heavy_scale == "full":
        designs["default"] = pg.default_design()
        for name in ("four-start-seven-rollers", "standard"):
            designs[name] = load_any_design(EXAMPLES / f"{name}.toml")
    root = tmp_path_factory.mktemp("reads")
    return {label: stage_reads(d, root / label) for label, d in designs.items()}


def _read_closure(read: dict[str, set[str]], stage: str, design: PRSDesign) -> set[str]:
    """The fields ``stage`` read itself or through the results it uses."""
    _, upstream = inputs(stage, design)
    return set(read[stage]).union(*(_read_closure(read, u, design) for u in upstream))


# --------------------------------------------------------------------------- declarations
def test_every_field_a_stage_reads_is_in_its_key(reads):
    """Each field a watched build read is covered by the stage's key; the one exception is the
    design load where it only sizes the flange bolt (covered by ``definition``'s sized bolt)."""
    designs = {"full": full_design(), "default": pg.default_design()}
    for label, read in reads.items():
        design = designs[label] if label in designs else coarse(load_any_design(EXAMPLES / f"{label}.toml"))
        for stage in STAGE_NAMES:
            keyed = closure(stage, design)
            missing = sorted(f for f in read[stage] if not covers(keyed, f)
                             and not (f == "loading.axial_load_n" and DEFINITION in keyed
                                      and design.actuator.nut_mount.bolt is None))
            assert not missing, f"{label}: stage {stage} reads {missing}, which its key does not cover"


def _leaf_fields(design: PRSDesign) -> list[str]:
    out = ["name"]
    for f in dataclasses.fields(design):
        section = getattr(design, f.name)
        if dataclasses.is_dataclass(section):
            out += [f"{f.name}.{g.name}" for g in dataclasses.fields(section)]
    return out


def _candidates(value, design: PRSDesign):
    """Other values to try for a field holding ``value`` (the first valid one is taken)."""
    n, p = design.thread.engaged_teeth, design.thread.pitch_mm
    if isinstance(value, bool):
        return [not value]
    if isinstance(value, int):
        return [value + 1, value - 1, value + 2]
    if isinstance(value, float):
        return [value * 1.01, value * 0.99, value + 0.01, value - 0.01, value + 0.001, value + 0.5, value - 0.5,
                value * 1.2, value * 0.8]
    if isinstance(value, str) and re.fullmatch(r"[A-Za-z]+\d+(/[A-Za-z]+\d+)?", value):
        # an ISO 286 class or fit: the next grade of its last part
        head, grade = re.fullmatch(r"(.*?)(\d+)", value).groups()
        return [f"{head}{int(grade) + 1}", f"{head}{int(grade) - 1}"]
    if isinstance(value, tuple) and value and all(isinstance(v, float) for v in value):
        return [tuple(v * (1 + 1e-6) for v in value)]
    if isinstance(value, tuple):
        return [(*value, 0.5), value[:-1]] if value else [(0.5,), (1.0,)]
    if dataclasses.is_dataclass(value):
        out = []
        for g in dataclasses.fields(value):
            out += [dataclasses.replace(value, **{g.name: v}) for v in _candidates(getattr(value, g.name), design)
                    if _valid(lambda: dataclasses.replace(value, **{g.name: v}))]
        return out[:1]
    if value is None:
        # an optional size or list: a pitch list or a list per tooth, then sizes and names
        return [tuple([p + 1e-4] * (n - 1)), tuple([1.0] * n), 1.0, 5.0, 20.0, 100.0, 0.5, 300.0, "M6", "fixed-fixed"]
    if isinstance(value, str):
        return ["default-renamed", "M6", "M4", "03", "02"] + _STRINGS
    return []


def _valid(make) -> bool:
    try:
        make()
        return True
    except (DesignError, ValueError, TypeError, KeyError):
        return False


def _string_choices() -> list[str]:
    """Every string of the model's choice tables (the values a string field may take)."""
    import prs_geom.model.actuator as actuator
    import prs_geom.model.design as design

    out = []
    for module in (design, actuator):
        for value in vars(module).values():
            if isinstance(value, (tuple, frozenset)) and value and all(isinstance(v, str) for v in value):
                out += sorted(value)
    return out


_STRINGS = _string_choices()


def perturbed(design: PRSDesign, path: str) -> PRSDesign | None:
    """``design`` with the one field ``path`` changed to another valid value, or None."""
    if path == "name":
        return design.with_changes(name=design.name + "-b")
    section_name, field = path.split(".")
    section = getattr(design, section_name)
    for value in _candidates(getattr(section, field), design):
        try:
            new = design.with_changes(**{section_name: dataclasses.replace(section, **{field: value})})
        except (DesignError, ValueError, TypeError, KeyError):
            continue
        if new != design:
            return new
    return None


def test_a_field_change_misses_exactly_the_stages_that_read_it(reads):
    """The property of the cache keys, field by field over the full design: the stages whose
    watched reads (with their upstream results') include the field get a new key (a miss),
    every other stage keeps its key (a hit). A stage reads a field when it does in a build
    of any of the watched designs (the default design's copy with new pitch lists reads the
    name, the full design's does not)."""
    base = full_design()
    # the other designs size the flange bolt from the load: their reads of the load through
    # the bolt are not reads of the full design, whose bolt is given
    read = {stage: set(reads["full"][stage]).union(*(r[stage] - {"loading.axial_load_n"} for r in reads.values()))
            for stage in STAGE_NAMES}
    options = BuildOptions()
    keys0 = stage_keys(base, STAGE_NAMES, options, DATE, source_fingerprint())
    changed, skipped = 0, []
    for path in _leaf_fields(base):
        new = perturbed(base, path)
        if new is None:
            skipped.append(path)
            continue
        keys1 = stage_keys(new, STAGE_NAMES, options, DATE, source_fingerprint())
        missed = {s for s in STAGE_NAMES if keys0[s][0] != keys1[s][0]}
        readers = {s for s in STAGE_NAMES if path in _read_closure(read, s, base)}
        assert missed == readers, (f"{path}: missed {sorted(missed)}, but read by {sorted(readers)} "
                                   f"(missing misses {sorted(readers - missed)}, extra {sorted(missed - readers)})")
        changed += 1
    fields = _leaf_fields(base)
    assert changed >= 0.9 * len(fields), f"only {changed} of {len(fields)} fields perturbed; skipped {skipped}"
    for must in ("loading.axial_load_n", "thread.pitch_mm", "mesh.chord_tolerance_mm", "roller.pitch_list_mm",
                 "tolerances.seed", "rating.speed_rpm", "gears.module_mm"):
        assert must not in skipped


def test_the_design_load_reaches_the_parts_only_through_the_flange_bolt():
    """Without a given bolt, a load that sizes the same bolt keeps the geometry stages' keys
    (20 -> 22 kN: M5 both); one that sizes another bolt (20 -> 30 kN: M5 -> M6) changes them."""
    from prs_geom.model.machine_elements import load_sized_bolt

    d = pg.default_design()
    assert d.actuator.nut_mount.bolt is None
    count = d.actuator.nut_mount.bolt_count
    assert load_sized_bolt(count, 20_000.0) == load_sized_bolt(count, 22_000.0) == "M5"
    assert load_sized_bolt(count, 30_000.0) == "M6"
    keys = {F: stage_keys(d.with_changes(loading=dataclasses.replace(d.loading, axial_load_n=F)), STAGE_NAMES,
                          BuildOptions(), DATE, "x") for F in (20_000.0, 22_000.0, 30_000.0)}
    same = {s for s in STAGE_NAMES if keys[20_000.0][s] == keys[22_000.0][s]}
    assert same == {"pitch", "contact", "gears", "tolerance", "meshes", "mechanism", "checks", "manufacturing"}
    same_big = {s for s in STAGE_NAMES if keys[20_000.0][s] == keys[30_000.0][s]}
    assert same_big == {"pitch", "contact", "gears", "tolerance"}


# --------------------------------------------------------------------------- record format
def test_records_round_trip_exactly_and_keep_shared_objects_shared():
    import trimesh

    from prs_geom.mesh.parts import CompletePart

    d = pg.default_design()
    rng = np.random.default_rng(1)
    V = rng.random((5, 3)) / 3.0          # digits that only an exact float64 store keeps
    F = np.array([[0, 1, 2], [2, 3, 4]])
    part = CompletePart("p", V, F, 1.0 / 3.0, ("a",), ("b", "c"), np.eye(4)[None].repeat(2, axis=0))
    part.edge_check()                     # a field set after construction (init=False) travels too
    mesh = trimesh.Trimesh(V, F, process=False)
    value = {"part": part, "again": part, "vertices": V, "mesh": mesh, "mesh2": mesh, "design": d,
             "screw_material": d.materials.screw, (1, "k"): [np.float64(2.5), None, True],
             "set": frozenset({"a", "b"}), "nan": float("nan"), "path": Path("a/b")}
    tree, arrays = encode(value, d)
    # another design at decode: its objects stand where the encoded design's were
    other = d.with_changes(name="other")
    back = decode(tree, arrays, other)
    assert back["design"] is other and back["screw_material"] is other.materials.screw
    got = back["part"]
    assert isinstance(got, CompletePart) and got is back["again"]            # one object in, one out
    assert got.vertices is back["vertices"] and got.vertices.dtype == np.float64
    assert np.array_equal(got.vertices, V) and np.array_equal(got.faces, F) and got.volume_mm3 == 1.0 / 3.0
    assert got.instances == ("b", "c") and got._edges == part._edges
    assert back["mesh"] is back["mesh2"] and np.array_equal(back["mesh"].vertices, V)
    assert back[(1, "k")] == [2.5, None, True] and isinstance(back[(1, "k")][0], np.float64)
    assert back["set"] == frozenset({"a", "b"}) and np.isnan(back["nan"]) and back["path"] == Path("a/b")


def test_records_refuse_what_they_cannot_carry():
    with pytest.raises(Uncacheable, match="object array"):
        encode(np.array([object()]))
    with pytest.raises(Uncacheable, match="complex"):
        encode(1j)

    @dataclasses.dataclass
    class Foreign:         # a dataclass of this test module, not of prs_geom
        x: int = 1

    Foreign.__module__ = "somewhere_else"
    with pytest.raises(Uncacheable, match="somewhere_else"):
        encode(Foreign())
    with pytest.raises(ValueError, match="outside prs_geom"):
        decode(json.dumps({"id": 0, "class": "os:path", "fields": {}}), {})


def _record(tmp_path: Path, cache: StageCache, stage: str, key: str, content: bytes) -> StageRecord:
    import hashlib

    src = tmp_path / f"{key}.bin"
    src.write_bytes(content)
    record = StageRecord({"pitch": None}, ("w",), (("f.bin", hashlib.sha256(content).hexdigest()),), {"p": "<svg/>"})
    assert cache.write(stage, key, f"desc {key}", record, {"f.bin": src})
    return record


def test_a_record_reads_back_and_a_tampered_one_does_not(tmp_path):
    cache = StageCache(tmp_path / "c")
    key = "ab" * 32
    record = _record(tmp_path, cache, "pitch", key, b"content")
    got, status = cache.read("pitch", key, f"desc {key}")
    assert status == "hit" and got == record
    assert cache.read("pitch", key, "another description") == (None, "foreign")
    sha = record.files[0][1]
    cache.blob(sha).write_bytes(b"edited")
    assert cache.read("pitch", key, f"desc {key}") == (None, "tampered")
    assert not cache.blob(sha).exists()        # the wrong blob is dropped, to be written again


def test_least_recently_used_records_and_their_blobs_go(tmp_path):
    cache = StageCache(tmp_path / "c")
    keys = [f"{i:x}" * 64 for i in range(KEEP + 2)]
    shas = []
    for i, key in enumerate(keys):
        shas.append(_record(tmp_path, cache, "pitch", key[:64], f"content {i}".encode()).files[0][1])
        os.utime(cache.store.path("pitch", key[:64]), (1000 + i, 1000 + i))
    cache.evict("pitch")
    cache.collect_blobs(spare_s=3600.0)          # just written: spared
    assert all(cache.blob(s).exists() for s in shas)
    cache.collect_blobs(spare_s=0.0)
    kept = sorted(p.name for p in Path(cache.folder).glob("pitch-*.npz"))
    assert kept == sorted(f"pitch-{k[:32]}.npz" for k in keys[-KEEP:])
    assert [cache.blob(s).exists() for s in shas] == [False] * 2 + [True] * KEEP
    (Path(cache.folder) / "blobs" / "notes.txt").write_text("mine")   # not a blob name: left alone
    cache.collect_blobs(spare_s=0.0)
    assert (Path(cache.folder) / "blobs" / "notes.txt").exists()


# --------------------------------------------------------------------------- builds
@pytest.fixture
def stage_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("PRS_GEOM_STAGE_CACHE", "1")
    monkeypatch.setenv("PRS_GEOM_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("SOURCE_DATE_EPOCH", EPOCH)
    return tmp_path / "cache"


def _reused(folder: Path) -> list[str]:
    return json.loads((folder / ".prs-geom-manifest.json").read_text())["reused_from_cache"]


def _same_outputs(a: Path, b: Path) -> None:
    fa, fb = fingerprint(a), fingerprint(b)
    assert compare_numbers(fa["report"], fb["report"]) == []
    assert fa["files"] == fb["files"]


@pytest.mark.slow
def test_a_rebuild_reuses_unchanged_stages_and_writes_the_golden_outputs(stage_cache, tmp_path, monkeypatch):
    """Cold, then the same design again (every stage from the cache: the golden fingerprint),
    then the design load 20 -> 22 kN (the flange bolt stays M5): only the stages that read
    the load run, and the outputs equal a build without the cache; so do they with the plot
    process of a command-line rebuild, and when a record fails only when read."""
    build(pg.default_design(), tmp_path / "cold", memory_budget=8 * 2 ** 30)
    assert not (json.loads((tmp_path / "cold" / ".prs-geom-manifest.json").read_text())).get("reused_from_cache")
    build(pg.default_design(), tmp_path / "warm", memory_budget=8 * 2 ** 30)
    assert _reused(tmp_path / "warm") == STAGE_NAMES
    golden = json.loads((DATA / "default.json").read_text())
    warm = fingerprint(tmp_path / "warm")
    assert compare_numbers(golden["report"], warm["report"]) == []
    assert warm["files"] == golden["files"]
    # a build without the checks stage restores the meshes of a full build and checks them itself
    build(pg.default_design(), tmp_path / "only", options=BuildOptions(only=("meshes",)), memory_budget=8 * 2 ** 30)
    assert _reused(tmp_path / "only") == ["pitch", "contact", "meshes"]
    only = json.loads((tmp_path / "only" / "report.json").read_text())
    assert compare_numbers(golden["report"]["checks"]["meshes"], only["checks"]["meshes"]) == []

    # the designer's loop on the command line, with workers allowed: the rebuild of 22 kN into
    # the folder of the 20 kN build starts its plot process before the pipeline's imports
    # (same design_sha256 in the manifest), which draws the load figures; the stage records
    # are read when their stages come. Only the stages that read the load run, and the outputs
    # are those of a build without the cache.
    from prs_geom.cli import main
    from prs_geom.runtime import sidecar

    started = []
    real_init = sidecar.Sidecar.__init__

    def counting_init(self, *args, **kwargs):
        real_init(self, *args, **kwargs)
        started.append(self)

    monkeypatch.setattr(sidecar.Sidecar, "__init__", counting_init)
    monkeypatch.setenv("PRS_GEOM_WORKERS", "2")
    d = pg.default_design()
    loaded = d.with_changes(loading=dataclasses.replace(d.loading, axial_load_n=22_000.0))
    pg.save_design(loaded, tmp_path / "loaded.toml")
    assert main(["build", str(tmp_path / "loaded.toml"), "--out", str(tmp_path / "warm"), "--quiet"]) == 0
    assert len(started) == 1 and started[0]._proc.returncode is not None     # started, and reaped
    assert _reused(tmp_path / "warm") == ["pitch", "contact", "gears", "tolerance", "meshes", "mechanism",
                                          "checks", "manufacturing"]
    monkeypatch.setenv("PRS_GEOM_WORKERS", "0")
    build(loaded, tmp_path / "fresh", memory_budget=8 * 2 ** 30, cache=False)
    assert "reused_from_cache" not in json.loads((tmp_path / "fresh" / ".prs-geom-manifest.json").read_text())
    _same_outputs(tmp_path / "warm", tmp_path / "fresh")

    # a record that proves unsound only when its stage comes (read late): the checks stage
    # computes after all, its jobs started then (serially: the plan expected no workers)
    for record in (stage_cache / "stages").glob("checks-*.npz"):
        record.write_bytes(b"not a zip")
    assert main(["build", str(tmp_path / "loaded.toml"), "--out", str(tmp_path / "late"), "--quiet"]) == 0
    late = set(_reused(tmp_path / "late"))
    assert "checks" not in late and {"contact", "meshes", "manufacturing"} <= late
    _same_outputs(tmp_path / "late", tmp_path / "fresh")


@pytest.mark.slow
def test_a_damaged_cache_is_recomputed_not_used(stage_cache, tmp_path):
    """A blob edited in the cache (an STL of the meshes stage) fails its hash: the meshes stage
    runs again and the outputs are right; an unreadable record is a miss too."""
    d = pg.default_design().with_changes(mesh=dataclasses.replace(pg.default_design().mesh, chord_tolerance_mm=0.01))
    options = BuildOptions(only=("meshes",))
    build(d, tmp_path / "a", options=options, memory_budget=8 * 2 ** 30)
    blob = next(p for p in (stage_cache / "stages" / "blobs").iterdir()
                if p.read_bytes()[:8] == (tmp_path / "a" / "nut.stl").read_bytes()[:8]
                and p.stat().st_size == (tmp_path / "a" / "nut.stl").stat().st_size)
    blob.write_bytes(b"\0" * blob.stat().st_size)
    for record in (stage_cache / "stages").glob("contact-*.npz"):
        record.write_bytes(b"not a zip")
    build(d, tmp_path / "b", options=options, memory_budget=8 * 2 ** 30)
    assert _reused(tmp_path / "b") == ["pitch"]
    _same_outputs(tmp_path / "a", tmp_path / "b")


@pytest.mark.slow
def test_no_cache_reads_nothing_and_stores_again(stage_cache, tmp_path):
    from prs_geom.cli import main

    options = BuildOptions(only=("sheets",))
    build(pg.default_design(), tmp_path / "a", options=options, memory_budget=8 * 2 ** 30)
    assert main(["build", "--quiet", "--only", "sheets", "--no-cache", "--out", str(tmp_path / "b")]) == 0
    assert "reused_from_cache" not in json.loads((tmp_path / "b" / ".prs-geom-manifest.json").read_text())
    assert "PRS_GEOM_NO_CACHE" not in os.environ     # --no-cache lasts the build only
    assert main(["build", "--quiet", "--only", "sheets", "--out", str(tmp_path / "c")]) == 0
    assert _reused(tmp_path / "c") == ["pitch", "contact", "manufacturing"]
    _same_outputs(tmp_path / "a", tmp_path / "c")


def test_design_hash_leaves_out_the_operating_fields():
    """The hash the files print covers what is made: the canonical JSON of the design less
    the operating fields, plus the bolt the load sizes (an independent spelling here)."""
    import hashlib

    from prs_geom.model.io import DESIGN_FORMAT_VERSION, OPERATING_FIELDS, design_hash, design_to_dict

    d = pg.default_design()
    data = design_to_dict(d)
    data["loading"].pop("axial_load_n")
    for section in ("loads", "rating", "supports"):
        data.pop(section, None)
    data = {"format_version": DESIGN_FORMAT_VERSION, **data, "sized.actuator.nut_mount.bolt": "M5"}
    text = json.dumps(data, sort_keys=True, separators=(",", ":"))
    assert design_hash(d) == hashlib.sha256(text.encode()).hexdigest()[:12]
    assert OPERATING_FIELDS == {"loading.axial_load_n", "loads", "rating", "supports"}
    same = [d.with_changes(loading=dataclasses.replace(d.loading, axial_load_n=22_000.0)),
            d.with_changes(rating=RatingSettings(speed_rpm=250.0)),
            d.with_changes(supports=Supports(unsupported_length_mm=400.0)),
            d.with_changes(loads=dataclasses.replace(d.loads, tooth_width="ring"))]
    assert {design_hash(x) for x in same} == {design_hash(d)}
    other = [d.with_changes(loading=dataclasses.replace(d.loading, axial_load_n=30_000.0)),     # an M6 bolt
             d.with_changes(loading=dataclasses.replace(d.loading, installation="compression-compression")),
             d.with_changes(name="renamed"),
             d.with_changes(mesh=dataclasses.replace(d.mesh, chord_tolerance_mm=0.002))]
    assert len({design_hash(x) for x in other} | {design_hash(d)}) == 5
