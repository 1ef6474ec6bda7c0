"""Issue 29 (items 2, 6 and 10): input files that cannot hurt.

Every file the user names (design files, spectrum files, ``design-pitch --target``) is read by
:func:`prs_geom.model.io.read_user_file` and parsed under the limits of
:mod:`prs_geom.model.io`: regular files only (a device behind a symlink, a FIFO with no
writer, a folder are refused without reading), a size cap checked before and while reading,
a cap on every text value and key, a nesting cap, 64-bit whole numbers, JSON keys given once.
Each breach is exit 2 with one short ``error:`` line that quotes the path and at most a short
prefix of a long value.

The hostile cases run the real command line in a child process with a generous timeout (so a
hang fails instead of blocking the suite) and measure the child's own peak memory with
``os.wait4``: the default design's import alone is about 90 MB, so under 200 MB means the
file was not read past the cap.
"""
from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

import pytest

from cli_helpers import run
from prs_geom.model.design import PRSDesign
from prs_geom.model.errors import DesignError, format_value
from prs_geom.model.io import (MAX_INPUT_BYTES, MAX_KEY_CHARS, MAX_NESTING, MAX_TEXT_CHARS, design_from_dict,
                               dumps_json, dumps_toml, load_spectrum, loads_json, loads_toml, read_user_file)
from prs_geom.pipeline import load_any_design

pytestmark = pytest.mark.skipif(not hasattr(os, "wait4") or not hasattr(os, "mkfifo"),
                                reason="POSIX only (FIFOs, devices, wait4)")

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
TIMEOUT_S = 60.0
PEAK_LIMIT_KB = 200 * 1024          # ru_maxrss is in KiB on Linux
MESSAGE_LIMIT = 300
HUGE_BYTES = 200_000_000


def run_child(args: list[str], cwd: Path) -> tuple[int, str, str, int]:
    """(exit code, stdout, stderr, peak resident KiB) of ``prs-geom args`` in a child process.

    The command runs below a small launcher interpreter, which reports the command's own
    ``ru_maxrss`` (``os.wait4``): on Linux a child's peak includes the image of the process
    it was forked from, and this test process may hold a few hundred MB after other tests
    (a build in process), while the launcher holds about 10 MB. A command still running
    after :data:`TIMEOUT_S` is killed and the test fails."""
    import json
    import subprocess

    out, err = cwd / ".child-stdout", cwd / ".child-stderr"
    env = {**os.environ, "PRS_GEOM_WORKERS": "0"}
    env.pop("PRS_GEOM_MEMORY_BUDGET", None)
    launcher = (
        "import json, os, subprocess, sys, time\n"
        "args, out, err, timeout = json.loads(sys.argv[1])\n"
        "with open(out, 'wb') as fo, open(err, 'wb') as fe:\n"
        "    p = subprocess.Popen([sys.executable, '-m', 'prs_geom.cli', *args], stdout=fo, stderr=fe,\n"
        "                         stdin=subprocess.DEVNULL)\n"
        "deadline = time.monotonic() + timeout\n"
        "while True:\n"
        "    pid, status, usage = os.wait4(p.pid, os.WNOHANG)\n"
        "    if pid:\n"
        "        break\n"
        "    if time.monotonic() > deadline:\n"
        "        p.kill(); os.wait4(p.pid, 0)\n"
        "        print(json.dumps(None)); sys.exit(0)\n"
        "    time.sleep(0.05)\n"
        "print(json.dumps([os.waitstatus_to_exitcode(status), usage.ru_maxrss]))\n")
    r = subprocess.run([sys.executable, "-c", launcher, json.dumps([args, str(out), str(err), TIMEOUT_S])],
                       cwd=cwd, env=env, capture_output=True, text=True, timeout=TIMEOUT_S + 60)
    result = json.loads(r.stdout.strip().splitlines()[-1])
    if result is None:
        pytest.fail(f"prs-geom {' '.join(args)} still running after {TIMEOUT_S} s")
    code, peak_kb = result
    text_out, text_err = out.read_text(), err.read_text()
    out.unlink()
    err.unlink()
    return code, text_out, text_err, peak_kb


def listing(folder: Path) -> set[str]:
    return {p.relative_to(folder).as_posix() for p in folder.rglob("*")}


def assert_refused(code: int, err: str, peak_kb: int | None = None, *needles: str) -> None:
    """Exit 2, exactly one short ``error:`` line naming every needle, no traceback."""
    assert code == 2, err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    errors = [ln for ln in lines if ln.startswith("error: ")]
    assert len(errors) == 1, err
    assert len(errors[0]) < MESSAGE_LIMIT, (len(errors[0]), errors[0][:400])
    for needle in needles:
        assert needle in errors[0], (needle, errors[0])
    if peak_kb is not None:
        assert peak_kb < PEAK_LIMIT_KB, f"child peak {peak_kb / 1024:.0f} MB"


# --------------------------------------------------------------------------- hostile files
def _special(tmp_path: Path, kind: str, suffix: str = ".toml") -> tuple[Path, str]:
    """A path of the given kind and the word the refusal must use."""
    path = tmp_path / f"{kind}{suffix}"
    if kind == "zero":                       # a symlink to an endless device
        if not os.path.exists("/dev/zero"):
            pytest.skip("no /dev/zero")
        path.symlink_to("/dev/zero")
        return path, "character device"
    if kind == "fifo":                       # no writer: opening it blocking would hang
        os.mkfifo(path)
        return path, "named pipe (FIFO)"
    if kind == "dir":
        path.mkdir()
        return path, "folder"
    raise AssertionError(kind)


def _commands(path: str, out: str) -> dict[str, tuple[list[str], str]]:
    """Commands that read the hostile file, and the kind of file each names in its error."""
    return {
        "validate": (["validate", path], "design file"),
        "build": (["build", path, "--out", out, "--quiet"], "design file"),
        "rating": (["rating", "--spectrum", path], "spectrum file"),
        "design-pitch": (["design-pitch", "--target", path], "--target file"),
    }


@pytest.mark.parametrize("kind", ["zero", "fifo", "dir"])
@pytest.mark.parametrize("command", ["validate", "build", "rating", "design-pitch"])
def test_non_regular_files_are_refused_without_reading(tmp_path, kind, command):
    path, word = _special(tmp_path, kind, ".json" if command == "design-pitch" else ".toml")
    out = tmp_path / "out"
    args, what = _commands(str(path), str(out))[command]
    before = listing(tmp_path)
    t0 = time.monotonic()
    code, stdout, err, peak = run_child(args, tmp_path)
    assert_refused(code, err, peak, what, repr(str(path)), word, "regular file")
    assert time.monotonic() - t0 < TIMEOUT_S
    assert stdout == ""
    assert listing(tmp_path) == before and not out.exists()       # nothing written


@pytest.fixture(scope="module")
def huge_name_file(tmp_path_factory):
    """A 200 MB file: a design whose material name is 200 MB of letters (deleted after)."""
    path = tmp_path_factory.mktemp("huge") / "huge.toml"
    with open(path, "wb") as fh:
        fh.write(b'name = "huge"\n[materials.screw]\nname = "')
        block = b"n" * (1 << 20)
        written = 0
        while written < HUGE_BYTES:
            fh.write(block)
            written += len(block)
        fh.write(b'"\n')
    yield path
    path.unlink()


@pytest.mark.parametrize("command", ["validate", "build", "rating", "design-pitch"])
def test_200_mb_name_is_refused_by_its_size(tmp_path, huge_name_file, command):
    out = tmp_path / "out"
    args, what = _commands(str(huge_name_file), str(out))[command]
    before = listing(tmp_path)
    code, _, err, peak = run_child(args, tmp_path)
    assert_refused(code, err, peak, what, repr(str(huge_name_file)), "MiB", "larger than the 4 MiB")
    assert "nnnnnnnnnn" not in err
    assert listing(tmp_path) == before and not out.exists()


def test_long_text_under_the_size_cap_is_refused_with_a_short_message(tmp_path):
    """3 MB of name passes the size cap and meets the text cap: the message quotes a prefix."""
    f = tmp_path / "d.toml"
    f.write_text('[materials.screw]\nname = "' + "n" * 3_000_000 + '"\n')
    code, _, err, peak = run_child(["validate", str(f)], tmp_path)
    assert_refused(code, err, peak, "materials.screw.name", "(3000000 characters)", f"at most {MAX_TEXT_CHARS}")
    assert "n" * 41 not in err


@pytest.mark.parametrize("length, rule", [(61, "1 to 60 characters"),
                                          (MAX_TEXT_CHARS + 1, f"at most {MAX_TEXT_CHARS}")])
def test_long_names_give_short_messages(tmp_path, length, rule):
    """The model's own 60-character rule and the reader's text cap: both short lines."""
    f = tmp_path / "d.toml"
    f.write_text('[materials.nut]\nname = "' + "\u00e9" * length + '"\n')
    code, _, err = run(["validate", str(f)])
    assert_refused(code, err, None, "materials.nut.name", rule)


def test_long_keys_and_unprintable_text_give_short_messages(tmp_path):
    f = tmp_path / "d.toml"
    f.write_text("[screw]\n" + "k" * (MAX_KEY_CHARS + 1) + " = 1\n")
    code, _, err = run(["validate", str(f)])
    assert_refused(code, err, None, f"({MAX_KEY_CHARS + 1} characters)", f"keys have at most {MAX_KEY_CHARS}")
    # under the key cap, but 6 characters each when escaped: the unknown key is shown by a prefix
    f.write_text('[screw]\n"' + "\\u0001" * 90 + '" = 1\n')
    code, _, err = run(["validate", str(f)])
    assert_refused(code, err, None, "unknown key", "(90 characters)")


# --------------------------------------------------------------------------- nesting, numbers, duplicates
def _toml_nested(depth: int) -> str:
    return "name = \"deep\"\nx = " + "{a = " * depth + "1" + "}" * depth + "\n"


def _json_nested(depth: int) -> str:
    return '{"name": "deep", "x": ' + "[" * depth + "1" + "]" * depth + "}"


@pytest.mark.parametrize("name, text, needle", [
    ("d.toml", _toml_nested(500), "nested too deeply"),          # RecursionError in tomllib
    ("d.toml", _toml_nested(MAX_NESTING + 5), f"nested more than {MAX_NESTING} levels"),
    ("d.json", _json_nested(100_000), "nested too deeply"),      # RecursionError in json
    ("d.json", _json_nested(MAX_NESTING + 5), f"nested more than {MAX_NESTING} levels"),
])
def test_deep_nesting_is_exit_2(tmp_path, name, text, needle):
    f = tmp_path / name
    f.write_text(text)
    code, _, err, peak = run_child(["validate", str(f)], tmp_path)
    assert_refused(code, err, peak, needle)


@pytest.mark.parametrize("name, text, needle", [
    ("d.json", '{"thread": {"engaged_teeth": ' + "1" * 5000 + "}}", "more than 4300 digits"),
    ("d.toml", "[thread]\nengaged_teeth = " + "1" * 5000 + "\n", "more than 4300 digits"),
    ("d.toml", "[thread]\nengaged_teeth = 0x" + "f" * 5000 + "\n", "thread.engaged_teeth = (a whole number of about"),
    ("d.toml", "[thread]\nengaged_teeth = " + "9" * 4000 + "\n", "64-bit"),
    ("d.json", '{"tolerances": {"seed": ' + str(2 ** 63) + "}}", "tolerances.seed = 9223372036854775808"),
    ("d.toml", "[loading]\naxial_load_n = " + "9" * 400 + "\n", "loading.axial_load_n"),
])
def test_huge_whole_numbers_are_exit_2(tmp_path, name, text, needle):
    f = tmp_path / name
    f.write_text(text)
    code, _, err = run(["validate", str(f)])
    assert_refused(code, err, None, needle)


def test_largest_64_bit_whole_number_is_still_read(tmp_path):
    f = tmp_path / "d.json"
    f.write_text(json.dumps({"name": "seeded", "tolerances": {"flank_um": 1.0, "seed": 2 ** 63 - 1}}))
    assert load_any_design(f).tolerances.seed == 2 ** 63 - 1


@pytest.mark.parametrize("text, needle", [
    ('{"name": "a", "name": "b"}', 'name = "b": this key is given more than once'),
    ('{"materials": {"screw": {"name": "a", "density_kg_m3": 7850, "name": "b"}}}', "materials.screw.name"),
    ('{"roller": {"pitch_list_mm": [2.0], "count": 5}, "roller": {"count": 6}}', "roller = {count = 6}"),
])
def test_duplicate_json_keys_are_refused(tmp_path, text, needle):
    f = tmp_path / "d.json"
    f.write_text(text)
    code, _, err = run(["validate", str(f)])
    assert_refused(code, err, None, needle, "more than once")
    with pytest.raises(DesignError, match="more than once"):
        loads_json(text)


def test_toml_duplicate_keys_are_still_refused(tmp_path):
    f = tmp_path / "d.toml"
    f.write_text('name = "a"\nname = "b"\n')
    code, _, err = run(["validate", str(f)])
    assert_refused(code, err, None, "is not valid TOML")


# --------------------------------------------------------------------------- spectrum and target files
SPECTRUM_CASES = {
    "nested": _toml_nested(500),
    "deep": _toml_nested(MAX_NESTING + 5),
    "digits": "[[case]]\nload_n = " + "1" * 5000 + "\ntime_share = 1.0\n",
    "int64": "[[case]]\nload_n = " + str(2 ** 64) + "\ntime_share = 1.0\n",
    "text": '[[case]]\nload_n = "' + "x" * 100_000 + '"\ntime_share = 1.0\n',
    "duplicate": "[[case]]\nload_n = 1.0\nload_n = 2.0\ntime_share = 1.0\n",
}


@pytest.mark.parametrize("case", sorted(SPECTRUM_CASES))
def test_hostile_spectrum_files_are_exit_2(tmp_path, case):
    f = tmp_path / "s.toml"
    f.write_text(SPECTRUM_CASES[case])
    code, _, err = run(["rating", "--spectrum", str(f)])
    # the file is named; a long message shortens its middle, so only the name is certain
    assert_refused(code, err, None, "spectrum file", "s.toml'")


TARGET_CASES = {
    "nested": ("t.json", _json_nested(100_000), "nested too deeply"),
    "nested-toml": ("t.toml", _toml_nested(500), "nested too deeply"),
    "deep": ("t.json", _json_nested(MAX_NESTING + 5), "nested more than"),
    "digits": ("t.json", '{"nut_roller": [' + "1" * 5000 + "]}", "4300 digits"),
    "text": ("t.json", '{"nut_roller": "' + "x" * 100_000 + '"}', "target.nut_roller"),
    "duplicate": ("t.json", '{"nut_roller": [1.0], "nut_roller": [2.0]}', "target.nut_roller"),
    "csv": ("t.csv", "tooth,nut_roller,roller_screw\n1," + "x" * 200_000 + ",1\n", "not a valid target file"),
}


@pytest.mark.parametrize("case", sorted(TARGET_CASES))
def test_hostile_target_files_are_exit_2(tmp_path, case):
    name, text, needle = TARGET_CASES[case]
    f = tmp_path / name
    f.write_text(text)
    out = tmp_path / "new.toml"
    code, _, err = run(["design-pitch", "--target", str(f), "--out", str(out)])
    assert_refused(code, err, None, needle)
    assert err.startswith("error: --target file") or err.startswith("error: target.")
    assert not out.exists()


# --------------------------------------------------------------------------- the reader itself
def test_read_cap_holds_for_a_file_whose_size_is_not_known(tmp_path):
    """/proc files report size 0: the size check passes, and reading stops at the cap + 1."""
    src = Path("/proc/self/maps")
    if not src.is_file():
        pytest.skip("no /proc")
    with pytest.raises(DesignError, match="has more than the 10 bytes a design file may have"):
        read_user_file(src, "design file", limit=10)
    f = tmp_path / "small.toml"
    f.write_bytes(b"x" * 10)
    assert read_user_file(f, limit=10) == b"x" * 10
    f.write_bytes(b"x" * 11)
    with pytest.raises(DesignError, match="11 bytes, larger than the 10 bytes"):
        read_user_file(f, limit=10)


def test_missing_and_dangling_paths_are_exit_2(tmp_path):
    link = tmp_path / "dangling.toml"
    link.symlink_to(tmp_path / "nowhere.toml")
    for path in (tmp_path / "missing.toml", link):
        code, _, err = run(["validate", str(path)])
        assert_refused(code, err, None, f"design file {str(path)!r}: does not exist")


def test_size_cap_is_the_documented_one(tmp_path):
    assert MAX_INPUT_BYTES == 4 * 1024 * 1024
    f = tmp_path / "d.toml"
    f.write_bytes(b"#" * MAX_INPUT_BYTES + b"\n")
    code, _, err = run(["validate", str(f)])
    assert_refused(code, err, None, f"{MAX_INPUT_BYTES + 1} bytes")


def test_format_value_is_short_for_any_value():
    assert format_value("x" * 10 ** 7) == '"' + "x" * 40 + '"... (10000000 characters)'
    assert format_value("short") == '"short"'
    assert format_value("\u0000" * 30).endswith("(30 characters)")
    assert format_value(2 ** 20000) \
        == "(a whole number of about 6021 digits)"
    assert format_value(2 ** 63) == "9223372036854775808"
    assert len(format_value([["x" * 100] * 100] * 100)) <= 200
    assert len(format_value({f"k{i}": {"a": {"b": 1}} for i in range(100)})) <= 200
    err = DesignError("a." * 500 + "b", "y" * 10 ** 6, "rule")
    assert len(str(err)) < MESSAGE_LIMIT and err.field == "a." * 500 + "b"


# --------------------------------------------------------------------------- ordinary files
@pytest.mark.parametrize("example", sorted(p.name for p in EXAMPLES.glob("*.toml")))
def test_examples_still_load_unchanged(tmp_path, example):
    """Every example reads to the same design as the plain TOML parser gives, and its TOML and
    JSON forms read back equal."""
    import tomllib

    from prs_geom.pipeline import DESIGN_KINDS

    path = EXAMPLES / example
    design = load_any_design(path)
    assert design == design_from_dict(tomllib.loads(path.read_text(encoding="utf-8")), DESIGN_KINDS)
    assert loads_toml(dumps_toml(design), kinds=DESIGN_KINDS) == design
    assert loads_json(dumps_json(design), kinds=DESIGN_KINDS) == design
    code, _, err = run(["validate", str(path), "--quiet"])
    assert code == 0, err


def test_spectrum_and_target_files_still_load(tmp_path):
    s = tmp_path / "s.toml"
    s.write_text("[[case]]\nload_n = 5000.0\ntime_share = 0.6\n\n[[case]]\nload_n = 20000.0\ntime_share = 0.4\n")
    assert load_spectrum(s).loads_n == (5000.0, 20000.0)
    n = PRSDesign().thread.engaged_teeth
    t = tmp_path / "t.json"
    t.write_text(json.dumps({"nut_roller": [1.0] * n, "roller_screw": [1.0] * n}))
    from prs_geom.cli import _read_target

    assert _read_target(str(t), n) == ([1.0] * n, [1.0] * n)
    c = tmp_path / "t.csv"
    c.write_text("tooth,nut_roller,roller_screw\n" + "".join(f"{k},1.0,1.0\n" for k in range(n)))
    assert _read_target(str(c), n) == ([1.0] * n, [1.0] * n)
