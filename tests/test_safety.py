"""Issue 11: never lose a user's files; hold up at every documented limit.

Each test reproduces one report of "What was seen" and checks the fixed behaviour.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cli_helpers import run
from prs_geom.model.actuator import ActuatorSettings
from prs_geom.model.design import MeshSettings, PRSDesign, Roller, Thread
from prs_geom.model.io import dumps_toml, save_design
from prs_geom.exports.output import MANIFEST_NAME, AtomicOutputDir, OutputRefused, clean_stale

#: A design that builds in a few seconds (3 teeth, 3 rollers, coarse mesh, no actuator: its
#: 100 mm stroke would make the screw the largest mesh of these file-handling tests).
TINY = PRSDesign(name="tiny", thread=Thread(engaged_teeth=3), roller=Roller(count=3),
                 mesh=MeshSettings(chord_tolerance_mm=0.05), actuator=ActuatorSettings(enabled=False))
BUDGET = ["--memory-budget", "4G"]


def tree(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture()
def tiny_file(tmp_path) -> Path:
    path = tmp_path / "tiny.toml"
    save_design(TINY, path)
    return path


# --------------------------------------------------------------------------- output folders
def test_folder_with_a_user_file_is_refused_and_kept(tmp_path, tiny_file):
    user = tmp_path / "thesis"
    user.mkdir()
    (user / "chapter1.docx").write_bytes(b"years of work")
    (user / "data").mkdir()
    (user / "data" / "results.csv").write_text("1,2,3\n")
    before = tree(user)
    code, out, err = run(["build", str(tiny_file), "--out", str(user), "--quiet", *BUDGET])
    assert code == 2 and out == ""
    assert f"'{user}'" in err and "chapter1.docx" in err and "Nothing was touched" in err
    assert tree(user) == before
    # no temporary folder was left beside it either
    assert sorted(p.name for p in tmp_path.iterdir()) == ["thesis", "tiny.toml"]


def test_out_dot_never_deletes_anything(tmp_path, tiny_file, monkeypatch):
    work = tmp_path / "work"
    work.mkdir()
    (work / "notes.txt").write_text("mine")
    monkeypatch.chdir(work)
    for target in (".", str(work), str(tmp_path)):
        code, _, err = run(["build", str(tiny_file), "--out", target, "--quiet", *BUDGET])
        assert code == 2 and "current folder" in err
    assert (work / "notes.txt").read_text() == "mine"
    # an empty current folder is refused too: replacing it would strand the shell
    (work / "notes.txt").unlink()
    code, _, err = run(["build", str(tiny_file), "--out", ".", "--quiet", *BUDGET])
    assert code == 2 and work.is_dir() and list(work.iterdir()) == []


def test_existing_file_as_out_is_refused(tmp_path, tiny_file):
    f = tmp_path / "report.pdf"
    f.write_bytes(b"%PDF user file")
    code, _, err = run(["build", str(tiny_file), "--out", str(f), "--quiet", *BUDGET])
    assert code == 2 and "is an existing file" in err
    assert f.read_bytes() == b"%PDF user file"


def test_own_output_is_replaced_atomically_and_foreign_files_refused(tmp_path, tiny_file):
    out = tmp_path / "out"
    assert run(["build", str(tiny_file), "--out", str(out), "--quiet", *BUDGET])[0] == 0
    manifest = json.loads((out / MANIFEST_NAME).read_text())
    assert manifest["written_by"] == "prs-geom" and manifest["complete"] is True
    on_disk = sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())
    assert sorted(manifest["files"] + [MANIFEST_NAME]) == on_disk
    assert "report.json" in manifest["files"]
    # our own folder: rebuilt in place
    assert run(["build", str(tiny_file), "--out", str(out), "--quiet", *BUDGET])[0] == 0
    # a user file dropped into it, and an office lock file: refused, both named
    (out / "my-notes.txt").write_text("keep")
    (out / "~$machining.xlsx").write_bytes(b"lock")
    before = tree(out)
    code, _, err = run(["build", str(tiny_file), "--out", str(out), "--quiet", *BUDGET])
    assert code == 2 and "my-notes.txt" in err and "~$machining.xlsx (lock file" in err
    assert tree(out) == before


def test_init_and_design_pitch_refuse_to_overwrite_without_force(tmp_path, tiny_file):
    target = tmp_path / "mine.toml"
    target.write_text("# my own design\n")
    code, _, err = run(["init", "--out", str(target)])
    assert code == 2 and "already exists" in err and "--force" in err
    assert target.read_text() == "# my own design\n"
    code, _, err = run(["design-pitch", str(tiny_file), "--out", str(target)])
    assert code == 2 and target.read_text() == "# my own design\n"
    assert run(["init", "--out", str(target), "--force"])[0] == 0
    assert "[thread]" in target.read_text()
    lock = tmp_path / ".~lock.graded.toml#"
    code, _, err = run(["init", "--out", str(lock)])
    assert code == 2 and "lock file" in err and not lock.exists()


def test_stale_temporary_folders_of_dead_processes_are_cleaned(tmp_path):
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    stale = tmp_path / f".out.tmp-{dead.pid}-0123abcd"
    stale.mkdir()
    (stale / MANIFEST_NAME).write_text(json.dumps({"written_by": "prs-geom", "files": []}))
    (stale / "screw.stl").write_bytes(b"half")
    # a folder that looks alike but is not ours stays
    foreign = tmp_path / f".notes.tmp-{dead.pid}-89abcdef"
    foreign.mkdir()
    # set aside before a crash, its target missing: put back
    old = tmp_path / f".prev.old-{dead.pid}-00ff00ff"
    old.mkdir()
    (old / MANIFEST_NAME).write_text(json.dumps({"written_by": "prs-geom", "files": ["a.txt"]}))
    (old / "a.txt").write_text("previous output")
    done = clean_stale(tmp_path)
    assert not stale.exists() and foreign.is_dir()
    assert (tmp_path / "prev" / "a.txt").read_text() == "previous output"
    assert len(done) == 2
    # a live process's folder is left alone
    live = tmp_path / f".out.tmp-{os.getpid()}-0123abcd"
    live.mkdir()
    (live / MANIFEST_NAME).write_text(json.dumps({"written_by": "prs-geom", "files": []}))
    assert clean_stale(tmp_path) == [] and live.is_dir()


def _start_build(tiny_file: Path, out: Path) -> subprocess.Popen:
    # the installed console script, as a user runs it
    exe = Path(sys.executable).parent / "prs-geom"
    # SIGINT back to its default in the child: a process started with SIGINT ignored (as
    # some pytest-xdist workers are, and every child inherits) keeps ignoring it, and
    # Python then installs no KeyboardInterrupt handler
    return subprocess.Popen([str(exe), "build", str(tiny_file), "--out", str(out),
                             *BUDGET], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def _wait_for_temp(parent: Path, proc: subprocess.Popen, timeout: float = 60.0) -> Path:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        temps = [p for p in parent.iterdir() if ".tmp-" in p.name and (p / MANIFEST_NAME).exists()]
        if temps:
            return temps[0]
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.02)
    raise AssertionError("no temporary folder appeared")


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_interrupt_removes_the_temporary_folder_and_prints_one_line(tmp_path, tiny_file, sig, code):
    out = tmp_path / "out"
    proc = _start_build(tiny_file, out)
    temp = _wait_for_temp(tmp_path, proc)
    proc.send_signal(sig)
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == code
    assert stderr.strip().splitlines()[-1] == "interrupted" and "Traceback" not in stderr
    assert not temp.exists() and not out.exists()


def test_sigkill_leftovers_are_cleaned_by_the_next_run(tmp_path, tiny_file):
    out = tmp_path / "out"
    proc = _start_build(tiny_file, out)
    temp = _wait_for_temp(tmp_path, proc)
    proc.kill()
    proc.communicate()
    assert temp.exists()          # nothing can clean up after SIGKILL ...
    code, _, _ = run(["build", str(tiny_file), "--out", str(out), "--quiet", *BUDGET])
    assert code == 0 and not temp.exists()   # ... but the next run does
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "tiny.toml"]


def test_atomic_dir_keeps_target_on_error(tmp_path):
    target = tmp_path / "t"
    with AtomicOutputDir(target) as tmp:
        (tmp / "a.txt").write_text("one")
    with pytest.raises(KeyboardInterrupt):
        with AtomicOutputDir(target) as tmp:
            (tmp / "a.txt").write_text("two")
            raise KeyboardInterrupt
    assert (target / "a.txt").read_text() == "one"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t"]
    (target / "b.txt").write_text("user")
    with pytest.raises(OutputRefused):
        AtomicOutputDir(target)


# --------------------------------------------------------------------------- environment failures
def _mount_tmpfs(path: Path, options: str) -> bool:
    path.mkdir(parents=True, exist_ok=True)
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(path)], capture_output=True)
    return r.returncode == 0


def test_disk_full_is_one_line_with_path_and_reason(tmp_path, tiny_file):
    disk = tmp_path / "small-disk"
    if not _mount_tmpfs(disk, "size=300k"):
        pytest.skip("cannot mount a small tmpfs here (needs root)")
    try:
        code, _, err = run(["build", str(tiny_file), "--out", str(disk / "out"), "--quiet", *BUDGET])
        assert code == 3 and "No space left on device" in err and str(disk) in err
        assert "Traceback" not in err and len(err.strip().splitlines()) == 1
        assert list(disk.iterdir()) == []     # the temporary folder went too
    finally:
        subprocess.run(["umount", str(disk)])


def test_unwritable_output_is_one_line_with_path_and_reason(tmp_path, tiny_file):
    ro = tmp_path / "read-only"
    if not _mount_tmpfs(ro, "ro,size=100k"):
        pytest.skip("cannot mount a read-only tmpfs here (needs root)")
    try:
        code, _, err = run(["build", str(tiny_file), "--out", str(ro / "out"), "--quiet", *BUDGET])
        assert code == 3 and "Read-only file system" in err and str(ro) in err
        assert "Traceback" not in err
    finally:
        subprocess.run(["umount", str(ro)])
    code, _, err = run(["init", "--out", "/proc/no-such-folder/design.toml"])
    assert code == 3 and "/proc/no-such-folder" in err and "Traceback" not in err


# --------------------------------------------------------------------------- input
def test_utf8_with_bom_is_accepted(tmp_path):
    f = tmp_path / "bom.toml"
    f.write_bytes(b"\xef\xbb\xbf" + dumps_toml(TINY).encode())
    code, out, _ = run(["validate", str(f)])
    assert code == 0 and "design tiny is valid" in out
    j = tmp_path / "bom.json"
    j.write_bytes(b'\xef\xbb\xbf{"name": "bomjson"}')
    assert run(["validate", str(j)])[0] == 0


@pytest.mark.parametrize("raw, expect", [
    (b'name = "caf\xe9"\n', "byte 0xe9 at byte offset 11"),
    (b"\xff\xfen\x00a\x00", "UTF-16 byte-order mark"),
    (b'name = "x"\n\x00\x01\x02', "NUL byte at byte offset 11"),
])
def test_other_encodings_name_the_file_and_offset(tmp_path, raw, expect):
    f = tmp_path / "latin1.toml"
    f.write_bytes(raw)
    code, _, err = run(["build", str(f), "--out", str(tmp_path / "o"), *BUDGET])
    assert code == 2 and str(f) in err and expect in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


# --------------------------------------------------------------------------- resource guard
def test_huge_screw_is_refused_up_front_naming_the_field(tmp_path):
    f = tmp_path / "long.toml"
    f.write_text("[screw]\nlength_mm = 1e6\n")
    t0 = time.monotonic()
    code, _, err = run(["build", str(f), "--out", str(tmp_path / "o"), "--memory-budget", "8G"])
    # cannot run here (exit 3, QUEUE's convention for a budget), refused before any work
    assert code == 3 and time.monotonic() - t0 < 10
    assert "screw.length_mm = 1000000.0" in err and "estimated peak memory" in err and "8.0 GB" in err
    assert not (tmp_path / "o").exists()


def test_tiny_chord_tolerance_is_refused_against_a_small_budget(tmp_path):
    f = tmp_path / "fine.toml"
    f.write_text("[thread]\nengaged_teeth = 200\n[mesh]\nchord_tolerance_mm = 0.0001\n")
    code, _, err = run(["check", str(f), "--memory-budget", "2G"])
    assert code == 3 and "mesh.chord_tolerance_mm = 0.0001" in err and "thread.engaged_teeth = 200" in err
    code, _, err = run(["build", str(f), "--memory-budget", "lots"])
    assert code == 2 and err.startswith("error: --memory-budget = \"lots\"")


#: Peak memory (bytes) of the default build with 0 and 2 worker processes, measured by
#: benchmarks/bench_memory.py on the 2-core machine (issue 31; docs/cli.md "Memory budget").
MEASURED_DEFAULT_PEAK_BYTES = {0: 660_041_728, 2: 1_286_795_264}


def test_estimate_matches_built_meshes_and_bounds_memory():
    from prs_geom.mesh.assembly import build_part
    from prs_geom.mesh.budget import estimate, part_triangles

    for d in (TINY, PRSDesign(thread=Thread(engaged_teeth=8, flank_half_angle_deg=35.0))):
        est = part_triangles(d, d.mesh.chord_tolerance_mm)
        for part in ("screw", "roller", "nut"):
            actual = len(build_part(d, part).faces)
            assert abs(est[part] - actual) <= 0.03 * actual, (part, est[part], actual)
    # the default build's measured peaks (its process tree, sampled by benchmarks/bench_memory.py,
    # docs/cli.md "Memory budget"): the estimate bounds each, within 10 %
    e = estimate(PRSDesign())
    assert MEASURED_DEFAULT_PEAK_BYTES[0] <= e.peak_bytes <= 1.1 * MEASURED_DEFAULT_PEAK_BYTES[0]
    # with two worker processes the check meshes beside the export meshing: the peaks add,
    # and each worker has its own interpreter and libraries
    from prs_geom.mesh import budget

    p = budget.estimate(PRSDesign(), workers=2)
    assert MEASURED_DEFAULT_PEAK_BYTES[2] <= p.peak_bytes <= 1.1 * MEASURED_DEFAULT_PEAK_BYTES[2]
    export_peak = e.export_triangles * budget.BYTES_PER_EXPORT_TRIANGLE + e.placed_triangles * budget.BYTES_PER_PLACED_TRIANGLE
    check_peak = e.check_triangles * budget.BYTES_PER_CHECK_TRIANGLE
    m = budget.work_margin(PRSDesign().mesh.chord_tolerance_mm)
    assert m == budget.COARSE_WORK_MARGIN
    assert p.peak_bytes == pytest.approx(budget.BASE_BYTES + 2 * budget.WORKER_BASE_BYTES
                                         + m * (export_peak + check_peak), rel=1e-12)
    assert e.peak_bytes == pytest.approx(budget.BASE_BYTES + m * max(export_peak, check_peak), rel=1e-12)
    # the factor: 1.5 at fine tolerances, linear in log(tolerance) to the coarse one
    assert budget.work_margin(1e-5) == budget.work_margin(1e-4) == budget.WORK_MARGIN
    assert budget.work_margin(0.001) == pytest.approx(0.5 * (budget.WORK_MARGIN + budget.COARSE_WORK_MARGIN))


# --------------------------------------------------------------------------- messages
@pytest.mark.parametrize("text, expect", [
    # a bad list item names the field with its index
    ('[roller]\npitch_list_mm = [2.0, 2.0, "a"]\n', 'roller.pitch_list_mm[2] = "a": must be a number'),
    # a rule on a derived default names the user's fields it came from
    ("[roller]\npitch_diameter_mm = 12\n",
     "nut.major_diameter_mm = 40.8 (not in the design file: the default nut.pitch_diameter_mm + 1.6 H"),
    ('[thread]\nhand = "up"\n', 'thread.hand = "up": must be one of "right", "left"'),
    ("[loading]\naxial_load_n = -5\n", "loading.axial_load_n = -5: must be > 0"),
    ("format_version = 99\n", "format_version = 99: this design file was written by a newer prs-geom"),
])
def test_messages_name_what_the_user_wrote(tmp_path, text, expect):
    f = tmp_path / "d.toml"
    f.write_text(text)
    code, _, err = run(["validate", str(f)])
    assert code == 2 and expect in err, err
    assert "np.float64" not in err and "Traceback" not in err


def test_cli_flags_are_reported_under_their_own_name(tmp_path):
    code, _, err = run(["loads", "--load", "-1"])
    assert code == 2 and err.startswith("error: --load = -1.0")
    code, _, err = run(["loads", "--load", "nan"])
    assert code == 2 and err.startswith("error: --load = nan") and "axial_load_n" not in err


def test_debug_is_accepted_after_the_subcommand(tmp_path):
    code, _, err = run(["validate", str(tmp_path / "missing.toml")])
    assert code == 2 and "does not exist" in err and "Traceback" not in err
    with pytest.raises(Exception, match="does not exist"):
        run(["validate", str(tmp_path / "missing.toml"), "--debug"])


# --------------------------------------------------------------------------- check warnings
def test_check_over_tolerance_becomes_a_warning_everywhere(tmp_path, tiny_file, monkeypatch):
    """A check whose measured difference exceeds its tolerance reaches report.json, the
    console and report.html (forced here by a mesh check row that carries a warning)."""
    import prs_geom.mesh.thread as mesh_mod

    real = mesh_mod.mesh_report

    def with_warning(tm, *a, **k):
        row = real(tm, *a, **k)
        if row["part"] == "roller":
            row["warnings"] = ["measured deviation 0.0123 mm exceeds the chord tolerance 0.01 mm"]
        return row

    monkeypatch.setattr(mesh_mod, "mesh_report", with_warning)
    out = tmp_path / "out"
    code, _, err = run(["build", str(tiny_file), "--out", str(out), "--quiet", *BUDGET])
    assert code == 0
    expect = "mesh check (roller): measured deviation 0.0123 mm exceeds the chord tolerance 0.01 mm"
    report = json.loads((out / "report.json").read_text())
    assert expect in report["warnings"]
    assert f"warning: {expect}" in err
    page = (out / "report.html").read_text()
    assert f"<li>{expect}</li>" in page and "id='warnings'" in page


# --------------------------------------------------------------------------- load solver at the limits
@pytest.mark.parametrize("n", [100, 200, 500])
def test_loads_command_succeeds_for_many_teeth(tmp_path, n):
    """`prs-geom loads` for engaged_teeth 100, 200, 500 on the default design, constant and
    graded (the equal-load lists of design-pitch): complementarity solver, with progress."""
    const = tmp_path / "const.toml"
    const.write_text(f"[thread]\nengaged_teeth = {n}\n")
    graded = tmp_path / "graded.toml"
    assert run(["design-pitch", str(const), "--out", str(graded)])[0] == 0
    for f, worst in ((const, None), (graded, 1.0)):
        code, out, err = run(["loads", str(f), "--json"])
        assert code == 0, err
        rep = json.loads(out)
        assert len(rep["ldc_nut_roller"]) == n
        # the coefficients average 1 on each side; the graded design shares equally
        assert sum(rep["ldc_nut_roller"]) / n == pytest.approx(1.0, abs=1e-12)
        assert sum(rep["ldc_roller_screw"]) / n == pytest.approx(1.0, abs=1e-12)
        if worst is not None:
            assert rep["max_ldc"] == pytest.approx(worst, abs=1e-9)
        else:
            assert rep["max_ldc"] > 1.4
    code, _, err = run(["loads", str(const)])
    assert code == 0 and "] loads" in err          # the progress display on stderr names the stage


def test_budget_from_the_environment_applies_to_the_python_api(tmp_path, monkeypatch):
    import prs_geom as pg
    from prs_geom.model.errors import ResourceLimitError

    monkeypatch.setenv("PRS_GEOM_MEMORY_BUDGET", "100M")
    with pytest.raises(ResourceLimitError, match=r"over the budget 100.0 MB \(set by \$PRS_GEOM_MEMORY_BUDGET\)"):
        pg.build(pg.default_design(), tmp_path / "out")
    assert not (tmp_path / "out").exists()


# --------------------------------------------------------------------------- issue 28: ownership by content
def _build(design: Path, out: Path, *extra: str) -> tuple[int, str, str]:
    return run(["build", str(design), "--out", str(out), "--quiet", *BUDGET, *extra])


def test_an_edited_output_file_is_refused_and_kept_until_force(tmp_path, tiny_file):
    out = tmp_path / "out"
    assert _build(tiny_file, out)[0] == 0
    manifest = json.loads((out / MANIFEST_NAME).read_text())
    assert manifest["format_version"] == 2
    # the manifest holds the content hash of every file it lists
    import hashlib
    assert sorted(manifest["sha256"]) == sorted(manifest["files"])
    assert all(hashlib.sha256((out / f).read_bytes()).hexdigest() == h for f, h in manifest["sha256"].items())
    edited = (out / "parts_list.csv").read_text() + "my note,,,\n"
    (out / "parts_list.csv").write_text(edited)
    before = tree(out)
    code, _, err = _build(tiny_file, out)
    assert code == 2 and "parts_list.csv changed since prs-geom wrote it" in err and "--force" in err
    assert tree(out) == before          # nothing touched, the user's line kept
    code, _, _ = _build(tiny_file, out, "--force")
    assert code == 0 and "my note" not in (out / "parts_list.csv").read_text()


def test_a_design_file_inside_the_output_folder_is_kept_byte_for_byte(tmp_path, tiny_file):
    out = tmp_path / "out"
    assert _build(tiny_file, out)[0] == 0
    design = out / "design.toml"
    text = design.read_bytes() + b"# my own comment, kept\n"
    design.write_bytes(text)
    # the first-hour case: prs-geom build exports/<name>/design.toml
    code, _, err = run(["build", str(design), "--out", str(out), "--quiet", *BUDGET])
    assert code == 0, err
    assert design.read_bytes() == text
    manifest = json.loads((out / MANIFEST_NAME).read_text())
    assert "design.toml" in manifest["files"]
    # and again: the kept file does not count as an edit of prs-geom's output
    assert run(["build", str(design), "--out", str(out), "--quiet", *BUDGET])[0] == 0
    assert design.read_bytes() == text


def test_an_old_manifest_is_rebuilt_once_with_a_warning(tmp_path, tiny_file):
    out = tmp_path / "out"
    assert _build(tiny_file, out)[0] == 0
    m = json.loads((out / MANIFEST_NAME).read_text())
    m["format_version"] = 1
    del m["sha256"]
    (out / MANIFEST_NAME).write_text(json.dumps(m))
    (out / "parts_list.csv").write_text("edited, but the old manifest cannot tell\n")
    code, _, err = _build(tiny_file, out)
    assert code == 0 and "written by an older prs-geom" in err
    assert "sha256" in json.loads((out / MANIFEST_NAME).read_text())
    # from now on edits are seen
    (out / "parts_list.csv").write_text("edited\n")
    assert _build(tiny_file, out)[0] == 2


# --------------------------------------------------------------------------- issue 28: preconditions
@pytest.mark.parametrize("given", ["100", "1e9", "2.5", "100X"])
def test_memory_budget_needs_a_unit(tmp_path, tiny_file, given):
    code, _, err = run(["build", str(tiny_file), "--out", str(tmp_path / "o"), "--memory-budget", given])
    assert code == 2 and "must be a size with a unit, K, M or G" in err
    assert not (tmp_path / "o").exists()


def test_validate_and_build_give_one_memory_estimate(tmp_path, tiny_file):
    from prs_geom.pipeline import plan_build
    from prs_geom.mesh.budget import parse_size
    from prs_geom.model.errors import format_bytes

    workers, est = plan_build(TINY, parse_size("4G"))
    code, out, _ = run(["validate", str(tiny_file), "--memory-budget", "4G"])
    assert code == 0 and f"estimated peak memory {format_bytes(est.peak_bytes)}" in out
    # a budget between the serial and the parallel need: both commands fall back to one process
    from prs_geom.mesh.budget import estimate
    serial, parallel = estimate(TINY, workers=0).peak_bytes, estimate(TINY, workers=2).peak_bytes
    mid = f"{(serial + parallel) / 2 / 2**10:.0f}K"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("PRS_GEOM_WORKERS", "2")
        code, out, _ = run(["validate", str(tiny_file), "--memory-budget", mid])
        assert code == 0 and "in one process" in out and format_bytes(serial) in out
        # and a budget below the serial need is refused by validate as build refuses it
        low = f"{serial / 2 / 2**10:.0f}K"
        code, _, err = run(["validate", str(tiny_file), "--memory-budget", low])
        assert code == 3 and "too large to mesh here" in err


def test_step_without_the_extra_exits_3_before_any_work(tmp_path, tiny_file):
    # OpenCascade made unimportable for the child: a module OCP that raises ImportError
    fake = tmp_path / "fake"
    fake.mkdir()
    (fake / "OCP.py").write_text("raise ImportError('No module named OCP (test)')\n")
    env = {**os.environ, "PYTHONPATH": str(fake)}
    exe = Path(sys.executable).parent / "prs-geom"
    t0 = time.monotonic()
    r = subprocess.run([str(exe), "build", str(tiny_file), "--out", str(tmp_path / "o"), "--step", *BUDGET],
                       capture_output=True, text=True, env=env, timeout=300)
    assert r.returncode == 3 and 'pip install "prs-geom[step]"' in r.stderr
    # no stage ran: the progress display never started, nothing was written
    assert not any(line.startswith("[") for line in r.stderr.splitlines()), r.stderr
    assert not (tmp_path / "o").exists()
    assert time.monotonic() - t0 < 60


def test_a_design_file_in_a_folder_of_its_own_becomes_that_folders_build(tmp_path, tiny_file):
    """A user's project folder holding only the design file, given as the output folder:
    the build goes in beside it and the design file stays byte for byte."""
    proj = tmp_path / "proj"
    proj.mkdir()
    design = proj / "mine.toml"
    text = tiny_file.read_bytes() + b"# notes\n"
    design.write_bytes(text)
    code, _, err = run(["build", str(design), "--out", str(proj), "--quiet", *BUDGET])
    assert code == 0, err
    assert design.read_bytes() == text and (proj / "report.json").is_file()
    # with anything else of the user's there, the folder is still refused
    (proj / "notes.txt").write_text("mine")
    before = tree(proj)
    code, _, err = run(["build", str(design), "--out", str(proj), "--quiet", *BUDGET])
    assert code == 2 and "notes.txt" in err and tree(proj) == before


# --------------------------------------------------------------------------- issue 29
def test_a_dangling_symlink_as_out_is_refused_and_not_followed(tmp_path, tiny_file):
    link = tmp_path / "out"
    target = tmp_path / "elsewhere" / "made-by-following"
    link.symlink_to(target)
    code, _, err = run(["build", str(tiny_file), "--out", str(link), "--quiet", *BUDGET])
    assert code == 2 and "dangling symbolic link" in err
    assert link.is_symlink() and not (tmp_path / "elsewhere").exists()


def test_a_build_over_its_budget_at_run_time_is_stopped_with_exit_3_and_no_output(tmp_path):
    """The runtime guard (prs_geom.runtime.memwatch): a build whose real need exceeds the budget,
    here because the up-front estimate is bypassed, is stopped before it passes the budget
    by much: ResourceLimitError (exit 3 on the command line), no output, no worker left."""
    script = tmp_path / "over.py"
    out = tmp_path / "out"
    script.write_text(
        "import sys\n"
        "import prs_geom as pg\n"
        "import prs_geom.pipeline as pipeline\n"
        "from prs_geom.mesh.budget import parse_size\n"
        "from prs_geom.model.errors import ResourceLimitError\n"
        "from prs_geom.runtime.memwatch import process_tree_rss\n"
        "pipeline.plan_build = lambda design, budget=None: (2, None)   # the estimate bypassed\n"
        "base = process_tree_rss()[0]\n"
        "budget = base + parse_size('120M')\n"
        "try:\n"
        f"    pg.build(pg.default_design(), {str(out)!r}, memory_budget=budget)\n"
        "except ResourceLimitError as exc:\n"
        "    print('STOPPED', budget, exc)\n"
        "    sys.exit(3)\n"
        "print('BUILT')\n")
    env = {k: v for k, v in os.environ.items() if k != "PRS_GEOM_WORKERS"}
    r = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, env=env, timeout=600)
    assert r.returncode == 3, (r.stdout, r.stderr[-2000:])
    assert "was stopped: its resident memory reached" in r.stdout and "Nothing was written" in r.stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == ["over.py"]


def test_cli_maps_the_runtime_stop_to_exit_3(tmp_path, tiny_file, monkeypatch):
    import prs_geom.pipeline as pipeline
    from prs_geom.model.errors import ResourceLimitError

    def stopped(*a, **k):
        raise ResourceLimitError("the build of tiny was stopped: its resident memory reached ...")

    monkeypatch.setattr(pipeline, "run_stages", stopped)
    code, _, err = run(["build", str(tiny_file), "--out", str(tmp_path / "o"), *BUDGET])
    assert code == 3 and "was stopped" in err and not (tmp_path / "o").exists()
