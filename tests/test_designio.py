import json
import subprocess
import sys

import pytest
from hypothesis import given, settings

from prs_geom.model.design import PRSDesign, Roller, default_design
from prs_geom.model.io import (design_from_dict, design_to_dict, dumps_json, dumps_toml,
                               load_design, loads_json, loads_toml, save_design)
from prs_geom.model.errors import DesignError
from strategies import standard_designs


def test_default_round_trips_through_toml_and_json(tmp_path):
    d = default_design()
    assert loads_toml(dumps_toml(d)) == d
    assert loads_json(dumps_json(d)) == d
    for name in ("d.toml", "d.json"):
        save_design(d, tmp_path / name)
        assert load_design(tmp_path / name) == d


@settings(max_examples=60)
@given(standard_designs(pitch_lists=True))
def test_sampled_designs_round_trip_bit_for_bit(d):
    back = loads_toml(dumps_toml(d))
    assert back == d
    # equality of floats is exact: compare the bit patterns of the pitch lists too
    assert [x.hex() for x in back.roller.pitch_list_mm] == [x.hex() for x in d.roller.pitch_list_mm]
    assert loads_json(dumps_json(d)) == d


def test_empty_file_is_the_default_design():
    assert loads_toml("") == default_design()
    assert loads_toml('name = "x"\n[roller]\ncount = 8\n') == PRSDesign(name="x", roller=Roller(count=8))


def test_init_then_build_round_trips(tmp_path):
    """prs-geom init > d.toml && prs-geom build d.toml --out X (DONE-WHEN of issue 2)."""
    exe = [sys.executable, "-m", "prs_geom.cli"]
    toml_text = subprocess.run(exe + ["init"], check=True, capture_output=True, text=True).stdout
    (tmp_path / "d.toml").write_text(toml_text)
    assert "# axial pitch p (mm)" in toml_text  # commented
    loaded = load_design(tmp_path / "d.toml")
    assert loaded == default_design()
    out = tmp_path / "x"
    subprocess.run(exe + ["build", str(tmp_path / "d.toml"), "--out", str(out), "--quiet"], check=True)
    report = json.loads((out / "report.json").read_text())
    assert design_from_dict(report["design"]) == loaded
    assert load_design(out / "design.toml") == loaded
    for key in ("prs_geom_version", "design", "contact", "loads", "pitch", "checks", "timings_s"):
        assert key in report
    assert report["pitch"]["roller_mm"] == [2.0] * 19


@pytest.mark.parametrize("text, field", [
    ("[thread]\npitch_mm = -1\n", "thread.pitch_mm"),
    ("[materials.nut]\npoisson_ratio = 0.7\n", "materials.nut.poisson_ratio"),
    ("[roller]\ncolour = 3\n", "roller.colour"),
    ("thread = 3\n", "thread"),
    ("[thread\n", "design file '<text>'"),
])
def test_errors_name_the_dotted_field(text, field):
    with pytest.raises(DesignError) as exc:
        loads_toml(text)
    assert exc.value.field == field


def test_dict_form_omits_absent_pitch_lists():
    data = design_to_dict(default_design())
    assert "pitch_list_mm" not in data["roller"]
    assert data["materials"]["screw"]["youngs_modulus_mpa"] == 212000.0


def test_kind_of_the_wrong_type_is_a_field_error():
    """Found by the fuzzing: kind = [] used to be an internal error (unhashable list)."""
    from prs_geom.model.io import loads_toml
    for text in ('kind = []\n', 'kind = 3\n', 'kind = {a = 1}\n'):
        with pytest.raises(DesignError, match=r"^kind = .*: must be one of"):
            loads_toml(text)


def test_required_static_safety_round_trips_and_defaults():
    """rating.required_static_safety (issue 28): written, read back in TOML and JSON; a
    [rating] section without it takes the catalogue default 2."""
    from prs_geom.model.design import RatingSettings

    d = PRSDesign(rating=RatingSettings(required_static_safety=4.5))
    assert "required_static_safety = 4.5" in dumps_toml(d)
    assert loads_toml(dumps_toml(d)) == d and loads_json(dumps_json(d)) == d
    assert loads_toml("[rating]\nspeed_rpm = 50\n").rating.required_static_safety == 2.0


@pytest.mark.parametrize("content", ["new text", b"new bytes"])
def test_an_atomic_write_that_fails_midway_leaves_the_old_file_and_no_temporary(tmp_path, monkeypatch, content):
    """write_file_atomic: a writer that dies after writing part of the file leaves the target
    as it was (absent, or its old content) and no temporary file in the folder."""
    from pathlib import Path

    from prs_geom.model.io import write_file_atomic

    def half_then_fail(self, data, *args, **kwargs):
        with open(self, "wb") as fh:
            fh.write((data.encode() if isinstance(data, str) else data)[:3])
        raise OSError("disk full")

    monkeypatch.setattr(Path, "write_text", half_then_fail)
    monkeypatch.setattr(Path, "write_bytes", half_then_fail)
    with pytest.raises(OSError, match="disk full"):
        write_file_atomic(tmp_path / "new.txt", content)
    assert list(tmp_path.iterdir()) == []
    monkeypatch.undo()
    (tmp_path / "old.txt").write_text("old", encoding="utf-8")
    monkeypatch.setattr(Path, "write_text", half_then_fail)
    monkeypatch.setattr(Path, "write_bytes", half_then_fail)
    with pytest.raises(OSError, match="disk full"):
        write_file_atomic(tmp_path / "old.txt", content)
    monkeypatch.undo()
    assert [p.name for p in tmp_path.iterdir()] == ["old.txt"]
    assert (tmp_path / "old.txt").read_text(encoding="utf-8") == "old"
    write_file_atomic(tmp_path / "old.txt", content)
    assert (tmp_path / "old.txt").read_bytes() == (content.encode() if isinstance(content, str) else content)
    assert [p.name for p in tmp_path.iterdir()] == ["old.txt"]


def test_material_grade_and_heat_treatment_read_with_the_part_defaults():
    """materials.<part>.grade / heat_treatment (issue 33): a [materials.screw] table without
    them keeps the threaded parts' defaults (100Cr6, hardened), not the bare Material's
    empty ones; given, they replace them; the carrier's default grade is empty (not
    specified); a multi-line or over-long grade is refused naming its field; a design round-trips."""
    from prs_geom.model.design import THREAD_STEEL_GRADE, THREAD_STEEL_HEAT_TREATMENT

    d = design_from_dict({"materials": {"screw": {"name": "bearing steel"}, "nut": {"grade": "42CrMo4 (1.7225)"}}})
    assert (d.materials.screw.name, d.materials.screw.grade, d.materials.screw.heat_treatment) == (
        "bearing steel", THREAD_STEEL_GRADE, THREAD_STEEL_HEAT_TREATMENT)
    assert (d.materials.nut.grade, d.materials.nut.heat_treatment) == ("42CrMo4 (1.7225)", THREAD_STEEL_HEAT_TREATMENT)
    assert (d.materials.carrier.grade, d.materials.carrier.heat_treatment) == ("", "")
    with pytest.raises(DesignError) as err:
        design_from_dict({"materials": {"roller": {"grade": "100Cr6\nsecond line"}}})
    assert err.value.field == "materials.roller.grade"
    with pytest.raises(DesignError, match="at most 60"):
        design_from_dict({"materials": {"carrier": {"heat_treatment": "x" * 61}}})
    assert design_from_dict(design_to_dict(d)) == d
