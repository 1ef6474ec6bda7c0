"""``prs-geom build --only GROUPS`` (issue 36): only the chosen outputs and report.json, only
the stages they need, the folder still replaced whole, the manifest recording ``only``."""
from __future__ import annotations

import json
import sys
from fnmatch import fnmatchcase
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent / "golden"))

from cli_helpers import run  # noqa: E402
from fingerprint import file_digest  # noqa: E402

from prs_geom.exports.report_schema import validate_report  # noqa: E402
from prs_geom.model.design import ActuatorSettings, MeshSettings, PRSDesign, Roller, Thread  # noqa: E402
from prs_geom.model.io import save_design  # noqa: E402
from prs_geom.pipeline import OUTPUT_GROUPS, BuildOptions, selected_stages  # noqa: E402

SMALL = PRSDesign(name="only", thread=Thread(engaged_teeth=4), roller=Roller(count=3),
                  mesh=MeshSettings(chord_tolerance_mm=0.05), actuator=ActuatorSettings(enabled=False))
BUDGET = ["--memory-budget", "4G"]
MANIFEST = ".prs-geom-manifest.json"


@pytest.fixture(scope="module")
def full(tmp_path_factory):
    """A full build of the small design (the reference every --only output must equal)."""
    folder = tmp_path_factory.mktemp("only")
    design = folder / "only.toml"
    save_design(SMALL, design)
    with pytest.MonkeyPatch.context() as m:
        m.setenv("SOURCE_DATE_EPOCH", "1767225600")
        code, _, err = run(["build", str(design), "--out", str(folder / "full"), "--quiet", *BUDGET])
    assert code == 0, err
    return design, folder / "full"


def _build_only(design: Path, out: Path, groups: str, monkeypatch) -> tuple[int, str]:
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1767225600")
    code, _, err = run(["build", str(design), "--out", str(out), "--only", groups, "--quiet", *BUDGET])
    return code, err


@pytest.mark.parametrize("group", ["design", "meshes", "sheets", "drawings", "plots", "parts_list"])
def test_each_group_alone_writes_its_files_equal_to_a_full_build(full, tmp_path, group, monkeypatch):
    """Each group: exactly the full build's files of that group plus report.json and the
    manifest, each file equal to the full build's (stamps aside), only the stages the group
    needs run, report.json valid with ``only`` and without the sections of the other stages."""
    design, ref = full
    out = tmp_path / "out"
    code, err = _build_only(design, out, group, monkeypatch)
    assert code == 0, err
    patterns = OUTPUT_GROUPS[group][1]
    expected = {p.name for p in ref.iterdir() if any(fnmatchcase(p.name, pat) for pat in patterns)}
    assert expected, group                   # the group has files in a full build
    assert {p.name for p in out.iterdir()} == expected | {"report.json", MANIFEST}
    for name in expected:
        assert file_digest(out / name) == file_digest(ref / name), name
    report = json.loads((out / "report.json").read_text(encoding="utf-8"))
    validate_report(report)
    assert report["only"] == [group]
    assert sorted(report["files"]) == sorted(expected | {"report.json"})
    ran = list(report["timings_s"])
    assert ran == [name for name, _ in selected_stages((group,))]
    assert set(ran) == set(OUTPUT_GROUPS[group][0])
    full_report = json.loads((ref / "report.json").read_text(encoding="utf-8"))
    for key in ("loads", "rating", "machining", "assembly", "parts_list"):
        if key in report:
            assert report[key] == full_report[key], key
    if "loads" not in OUTPUT_GROUPS[group][0]:
        assert "loads" not in report
    assert json.loads((out / MANIFEST).read_text(encoding="utf-8"))["only"] == [group]


def test_only_replaces_an_earlier_full_output_whole(full, tmp_path, monkeypatch):
    """--only into a folder holding a full build: the folder is replaced, never merged (the
    other outputs are gone), and the groups come in the documented order whatever the order
    given."""
    design, _ = full
    out = tmp_path / "out"
    code, _, err = run(["build", str(design), "--out", str(out), "--quiet", *BUDGET])
    assert code == 0, err
    assert (out / "report.html").exists()
    code, err = _build_only(design, out, "sheets, meshes", monkeypatch)
    assert code == 0, err
    names = {p.name for p in out.iterdir()}
    assert "report.html" not in names and "drawings.pdf" not in names and "design.toml" not in names
    assert {"screw.stl", "machining.xlsx", "report.json"} <= names
    assert json.loads((out / "report.json").read_text(encoding="utf-8"))["only"] == ["meshes", "sheets"]


def test_unknown_group_is_exit_2_naming_it_and_writes_nothing(full, tmp_path, monkeypatch):
    design, _ = full
    out = tmp_path / "out"
    code, err = _build_only(design, out, "meshes,mesh", monkeypatch)
    assert code == 2
    assert "--only" in err and '"meshes,mesh"' in err and "design, meshes, step" in err
    assert not out.exists()


def test_only_is_refused_for_a_harmonic_drive(tmp_path, monkeypatch):
    root = Path(__file__).resolve().parents[1]
    code, err = _build_only(root / "examples" / "harmonic.toml", tmp_path / "h", "meshes", monkeypatch)
    assert code == 2 and "harmonic" in err
    assert not (tmp_path / "h").exists()


def test_build_options_order_the_groups_and_step_implies_the_step_files():
    opts = BuildOptions(only=("plots", "step", "meshes"))
    assert opts.only == ("meshes", "step", "plots") and opts.step
    assert BuildOptions().only == () and not BuildOptions().step
    # html reports every stage, so it runs them all
    assert [n for n, _ in selected_stages(("html",))] == [n for n, _ in selected_stages(())]
