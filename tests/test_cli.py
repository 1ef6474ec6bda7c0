"""CLI behaviour: exit codes, error messages, atomic output."""
import dataclasses
import math
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cli_helpers import run, to_toml
from prs_geom import pipeline
from prs_geom.model.io import FIELD_COMMENTS, design_to_dict
from prs_geom.model.actuator import ActuatorSettings
from prs_geom.model.design import RatingSettings, Supports, Tolerances, default_design


def _write(data, path):
    Path(path).write_text(to_toml(data))


not_a_number = st.one_of(st.text(max_size=5), st.booleans(), st.just(math.nan), st.just(math.inf),
                         st.just(-math.inf))
non_positive = st.one_of(st.floats(max_value=0.0, allow_nan=False), not_a_number)
#: sizes (mm) outside 0.01 to 1e4 (a size below 10 um vanished in the rounding)
bad_size = st.one_of(non_positive, st.floats(1e-300, 0.0099), st.floats(1e4, 1e300, exclude_min=True))


def out_of(lo, hi, hi_open=False):
    """Values outside [lo, hi] (outside [lo, hi) when hi_open: hi itself is invalid)."""
    return st.one_of(st.floats(max_value=lo, exclude_max=True, allow_nan=False),
                     st.floats(min_value=hi, exclude_min=not hi_open, allow_nan=False), not_a_number)


def bad_int(lo, hi):
    return st.one_of(st.integers(max_value=lo - 1), st.integers(min_value=hi + 1),
                     st.floats(allow_nan=False), st.text(max_size=3), st.booleans())


def bad_choice(options):
    return st.one_of(st.text(max_size=12).filter(lambda s: s not in options), st.integers(), st.booleans())


def bad_pitch_list(n=20, p=2.0):
    return st.one_of(
        st.lists(st.just(p), max_size=30).filter(lambda l: len(l) != n - 1),
        st.integers(0, n - 2).flatmap(lambda k: st.floats(-10, 0).map(lambda v: [p] * k + [v] + [p] * (n - 2 - k))),
        st.integers(0, n - 2).flatmap(lambda k: st.floats(p * 1.021, p * 2).map(lambda v: [p] * k + [v] + [p] * (n - 2 - k))),
        st.text(max_size=4), st.floats(allow_nan=False),
    )


#: field path -> strategy of values that break that field's own rule
MATERIAL_PARTS = ("screw", "roller", "nut", "carrier", "retaining_ring")
INVALID = {
    "name": st.one_of(st.just(""), st.just("a b"), st.just("../up"), st.just("-x"), st.integers()),
    "thread.pitch_mm": bad_size,
    "thread.flank_half_angle_deg": out_of(10.0, 80.0),
    "thread.hand": bad_choice(("right", "left")),
    "thread.engaged_teeth": bad_int(2, 500),
    "screw.pitch_diameter_mm": bad_size,
    "screw.starts": bad_int(1, 20),
    "screw.major_diameter_mm": bad_size,
    "screw.minor_diameter_mm": bad_size,
    "screw.length_mm": st.one_of(non_positive, st.floats(0.01, 39.9), st.floats(1e7, 1e300, exclude_min=True)),
    "roller.pitch_diameter_mm": bad_size,
    "roller.count": bad_int(1, 60),
    "roller.arc_radius_mm": st.one_of(non_positive, st.floats(0.01, 4.3)),
    "roller.major_diameter_mm": bad_size,
    "roller.minor_diameter_mm": bad_size,
    "roller.pitch_list_mm": bad_pitch_list(),
    "nut.pitch_diameter_mm": bad_size,
    "nut.starts": bad_int(1, 20),
    "nut.outer_diameter_mm": st.one_of(non_positive, st.floats(0.01, 40.8)),
    "nut.major_diameter_mm": bad_size,
    "nut.minor_diameter_mm": bad_size,
    "nut.pitch_list_mm": bad_pitch_list(),
    # a hole zone on an external feature, a shaft zone on an internal one, not a zone at all
    "screw.pitch_diameter_tolerance": st.sampled_from(["H6", "h", "6h", "zz9", 6, ""]),
    "roller.pitch_diameter_tolerance": st.sampled_from(["H5", "h99", "k", 5.0]),
    "nut.pitch_diameter_tolerance": st.sampled_from(["h6", "H", "q6", 6]),
    **{f"materials.{part}.youngs_modulus_mpa": out_of(1e3, 1e7) for part in MATERIAL_PARTS},
    **{f"materials.{part}.poisson_ratio": out_of(0.0, 0.5, hi_open=True) for part in MATERIAL_PARTS},
    **{f"materials.{part}.density_kg_m3": out_of(500.0, 25000.0) for part in MATERIAL_PARTS},
    **{f"materials.{part}.name": st.one_of(st.just(""), st.just("   "), st.text(min_size=61, max_size=70),
                                           st.integers(), st.floats(allow_nan=False))
       for part in MATERIAL_PARTS},
    **{f"materials.{part}.{key}": st.one_of(st.text(min_size=61, max_size=70), st.just("a\nb"), st.integers())
       for part in MATERIAL_PARTS for key in ("grade", "heat_treatment")},
    "loading.axial_load_n": out_of(1.0, 1e10),
    "loading.installation": bad_choice(("tension-compression", "compression-compression")),
    "contact.clearance_mm": out_of(0.0, 0.1),
    "contact.precision_mm": out_of(1e-13, 1e-4),
    "mesh.chord_tolerance_mm": out_of(1e-4, 0.1),
    **{f"materials.{part}.thermal_expansion_per_k": out_of(0.0, 1e-3) for part in MATERIAL_PARTS},
    "loads.tooth_width": bad_choice(("circumference-share", "ring", "contact-ellipse", "unit")),
    "loads.compliance": bad_choice(("analytic", "fe")),
    "gears.enabled": st.one_of(st.integers(), st.text(max_size=3), st.floats(allow_nan=False)),
    # besides <= 0: modules that cut the default roller (d_r = 8 mm) into no whole tooth number
    "gears.module_mm": st.one_of(bad_size, st.sampled_from([0.3, 0.7, 3.0])),
    "gears.pressure_angle_deg": out_of(14.5, 30.0),
    "gears.backlash_mm": out_of(0.0, 1.0),
    "gears.face_width_mm": bad_size,
    "gears.accuracy_grade": bad_int(1, 11),
    "gears.thickness_tolerance_mm": out_of(0.001, 1.0),
    "gears.tip_tolerance": st.sampled_from(["H11", "h", "x99", 11]),
    "gears.ring_tip_tolerance": st.sampled_from(["h11", "H", 11.0]),
    # the [mechanism] section (layout rules that need the whole design are checked at build)
    "mechanism.enabled": st.one_of(st.integers(), st.text(max_size=3), st.floats(allow_nan=False)),
    # beyond the ISO 286 tables (500 mm) and not a DIN 472 bore (looked up at construction)
    "mechanism.journal_diameter_mm": st.one_of(bad_size, st.floats(500.01, 1e4)),
    "mechanism.carrier_thickness_mm": st.one_of(bad_size, st.floats(500.01, 1e4)),
    "mechanism.ring_bore_mm": st.one_of(bad_size, st.sampled_from([7.0, 59.0, 201.0, 250.0])),
    **{f"mechanism.{k}": st.sampled_from(["H7", "x7/g6", "H7/g99", "", "H7/G6", 7])
       for k in ("journal_fit", "carrier_fit")},
    "mechanism.carrier_guidance": bad_choice(("clear", "nut")),
    **{f"mechanism.{k}": out_of(0.0, 5.0) for k in ("carrier_radial_clearance_mm", "roller_end_play_mm",
                                                     "ring_play_mm")},
    "mechanism.length_tolerance": st.sampled_from(["x11", "js99", "", "H7/g6", 11]),
    # the [actuator] section (format version 2); sizes looked up in a table at construction
    **{f"actuator.{k}": st.one_of(st.integers(), st.text(max_size=3), st.floats(allow_nan=False))
       for k in ("enabled", "floating_end.enabled")},
    "actuator.stroke_mm": out_of(0.0, 1e5),
    "actuator.over_travel_mm": out_of(0.0, 1e3),
    **{f"actuator.{k}": bad_size for k in (
        "screw_run_out_mm", "thread_chamfer_mm", "fixed_end.bearing_width_mm", "fixed_end.bearing_outer_diameter_mm",
        "fixed_end.undercut_width_mm", "floating_end.bearing_width_mm", "floating_end.bearing_outer_diameter_mm",
        "drive.diameter_mm", "drive.length_mm", "drive.key_length_mm", "drive.flat_depth_mm",
        "nut_mount.bolt_circle_diameter_mm", "nut_mount.flange_diameter_mm", "nut_mount.flange_thickness_mm",
        "nut_mount.bolt_length_mm")},
    **{f"actuator.{k}": st.one_of(bad_size, st.sampled_from([21.0, 23.0, 101.0]))
       for k in ("fixed_end.bearing_bore_mm", "floating_end.bearing_bore_mm")},
    "actuator.fixed_end.locknut_thread_mm": st.one_of(bad_size, st.sampled_from([11.0, 21.0, 120.0])),
    **{f"actuator.{k}": bad_choice(("02", "03")) for k in ("fixed_end.bearing_series", "floating_end.bearing_series")},
    **{f"actuator.{k}": st.sampled_from(["x5", "k99", "", 5]) for k in (
        "fixed_end.seat_tolerance", "floating_end.seat_tolerance", "drive.fit")},
    "actuator.fixed_end.locknut_tolerance": bad_choice(("4h", "6e", "6f", "6g", "6h", "8g")),
    "actuator.drive.kind": bad_choice(("key", "flat")),
    "actuator.nut_mount.kind": bad_choice(("flange",)),
    "actuator.nut_mount.bolt": st.sampled_from(["M7", "M30", "", "6"]),
    "actuator.nut_mount.bolt_count": st.one_of(st.integers(-5, 2), st.integers(25, 100), st.floats(3, 24)),
    # the optional [supports] and [rating] sections
    "supports.unsupported_length_mm": out_of(0.01, 1e7),
    "supports.critical_speed_ends": bad_choice(("fixed-fixed", "fixed-supported", "supported-supported", "fixed-free")),
    "supports.buckling_ends": bad_choice(("fixed-fixed", "fixed-supported", "supported-supported", "fixed-free")),
    "supports.buckling_safety": out_of(1.0, 20.0),
    "supports.critical_speed_factor": out_of(0.1, 1.0),
    "rating.friction_coefficient": out_of(0.0, 0.5),
    "rating.speed_rpm": out_of(0.01, 1e5),
    "rating.life_hours": out_of(1.0, 1e7),
    "rating.reliability_pct": out_of(90.0, 99.0),
    "rating.operating_factor": out_of(1.0, 5.0),
    "rating.static_pressure_limit_mpa": out_of(1000.0, 6000.0),
    "rating.preload_n": out_of(1.0, 1e10),
    "rating.dn_limit_mm_rpm": out_of(1e3, 1e7),
    "rating.required_static_safety": out_of(1.0, 20.0),
    # the optional [tolerances] section
    "tolerances.distribution": bad_choice(("uniform", "normal")),
    **{f"tolerances.{k}": out_of(0.0, 100.0) for k in ("flank_um", "roller_diameter_um", "screw_eccentricity_um",
                                                         "nut_eccentricity_um", "lead_um")},
    "tolerances.temperature_k": out_of(0.0, 200.0),
    **{f"tolerances.{k}": st.one_of(st.lists(st.just(0.5), max_size=30).filter(lambda l: len(l) != 20),
                                     st.lists(st.floats(-10, -0.01), min_size=20, max_size=20), st.text(max_size=3))
       for k in ("screw_flank_um", "roller_screw_flank_um", "roller_nut_flank_um", "nut_flank_um")},
    "tolerances.samples": bad_int(1, 10_000_000),
    "tolerances.seed": st.one_of(st.integers(min_value=-(2 ** 63), max_value=-1), st.floats(allow_nan=False),
                                 st.text(max_size=3), st.booleans()),
    "tolerances.load_fractions": st.one_of(st.just([]), st.lists(st.floats(-5, 0), min_size=1, max_size=3),
                                           st.lists(st.floats(10.01, 1e6), min_size=1, max_size=3),
                                           st.lists(st.floats(1e-300, 0.0099), min_size=1, max_size=3),
                                           st.text(max_size=3)),
    "tolerances.source": st.one_of(st.integers(), st.floats(allow_nan=False), st.booleans()),
    "tolerances.target_ldc": st.one_of(st.floats(max_value=0.999, allow_nan=False, allow_infinity=False),
                                       st.floats(20.001, 1e300), st.text(max_size=3)),
    "tolerances.confidence": st.one_of(st.floats(max_value=0.0, allow_nan=False, allow_infinity=False),
                                       st.floats(min_value=1.0, allow_nan=False, allow_infinity=False),
                                       st.text(max_size=3)),
}


def test_every_design_field_has_an_invalid_case():
    """The table above covers every leaf of the design (so no field escapes the test)."""
    leaves = set()

    def walk(d, prefix):
        for k, v in d.items():
            path = f"{prefix}.{k}" if prefix else k
            walk(v, path) if isinstance(v, dict) else leaves.add(path)

    walk(design_to_dict(default_design()), "")
    leaves |= {"roller.pitch_list_mm", "nut.pitch_list_mm"}  # optional, absent by default
    leaves |= {"gears.module_mm", "gears.face_width_mm"}        # absent: by the sizing rule
    leaves |= {"mechanism.journal_diameter_mm", "mechanism.carrier_thickness_mm", "mechanism.ring_bore_mm"}
    leaves |= {k for k in FIELD_COMMENTS if k.startswith("actuator.")}          # absent: by the rules
    leaves |= {"screw.length_mm"}                  # absent for an actuator: from the stroke
    leaves |= {f"tolerances.{f.name}" for f in dataclasses.fields(Tolerances)}  # optional section
    leaves |= {f"supports.{f.name}" for f in dataclasses.fields(Supports)}      # optional section
    leaves |= {f"rating.{f.name}" for f in dataclasses.fields(RatingSettings)}  # optional section
    assert leaves == set(INVALID)


@pytest.mark.parametrize("field", sorted(INVALID))
@settings(max_examples=8)
@given(data=st.data())
def test_invalid_field_gives_exit_2_naming_field_and_no_output(field, data):
    value = data.draw(INVALID[field], label=field)
    doc = {}
    node = doc
    parts = field.split(".")
    for p in parts[:-1]:
        node = node.setdefault(p, {})
    node[parts[-1]] = value
    with tempfile.TemporaryDirectory() as tmp:
        f = Path(tmp) / "bad.toml"
        _write(doc, f)
        out = Path(tmp) / "out"
        code, stdout, stderr = run(["build", str(f), "--out", str(out), "--quiet"])
        assert code == 2, stderr
        assert stderr.startswith(f"error: {field}"), stderr
        assert "Traceback" not in stderr
        assert not out.exists()
        assert [p.name for p in Path(tmp).iterdir()] == ["bad.toml"]  # no temp folders left


def test_console_script_exit_code_and_debug_traceback(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[thread]\npitch_mm = 0\n")
    exe = [sys.executable, "-m", "prs_geom.cli"]
    r = subprocess.run(exe + ["build", str(bad), "--out", str(tmp_path / "o")], capture_output=True, text=True)
    assert r.returncode == 2
    assert "thread.pitch_mm = 0" in r.stderr and "must be > 0" in r.stderr
    assert "Traceback" not in r.stderr
    r = subprocess.run(exe + ["--debug", "build", str(bad)], capture_output=True, text=True)
    assert r.returncode != 0 and "Traceback" in r.stderr


def test_failing_build_leaves_earlier_output_unchanged(tmp_path, monkeypatch):
    from prs_geom.model.design import MeshSettings, PRSDesign, Roller, Thread
    from prs_geom.model.io import save_design

    # a small design: three builds of the default one took a minute
    small = tmp_path / "small.toml"
    save_design(PRSDesign(name="small", thread=Thread(engaged_teeth=3), roller=Roller(count=3),
                          mesh=MeshSettings(chord_tolerance_mm=0.05), actuator=ActuatorSettings(enabled=False)), small)
    out = tmp_path / "out"
    assert run(["build", str(small), "--out", str(out), "--quiet"])[0] == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert "report.json" in before

    def boom(ctx):
        ctx.write_text("half-written.txt", "partial")
        raise RuntimeError("simulated failure in a late stage")

    monkeypatch.setattr(pipeline, "STAGES", pipeline.STAGES + [("boom", boom)])
    code, _, err = run(["build", str(small), "--out", str(out), "--quiet"])
    # an unexpected exception is an internal error: one line, exit 70, no traceback
    assert code == 70 and "internal error RuntimeError: simulated failure" in err and "Traceback" not in err
    with pytest.raises(RuntimeError):
        run(["--debug", "build", str(small), "--out", str(out), "--quiet"])
    after = {p.name: p.read_bytes() for p in out.iterdir()}
    assert after == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "small.toml"]


def test_help_of_every_subcommand():
    for name in ("init", "validate", "build", "contact", "loads", "design-pitch", "check", "harmonic"):
        code, out, _ = run([name, "--help"])
        assert code == 0 and "usage: prs-geom " + name in out


def test_unknown_subcommand_is_usage_error():
    code, _, err = run(["frobnicate"])
    assert code == 2 and "invalid choice" in err


@pytest.mark.parametrize("argv, flag, call", [
    (["tolerance", "--target-ldc", "1.5", "--confidence", "1.5"], "--confidence",
     lambda studies, d: studies.synthesise(d, 1.5, 1.5)),
    (["tolerance", "--target-ldc", "0.5", "--samples", "100"], "--target-ldc",
     lambda studies, d: studies.synthesise(d, 0.5, 0.9)),
    (["tolerance", "--target-ldc", "1.5", "--samples", "50"], "--samples",
     lambda studies, d: studies.synthesise(d, 1.5, 0.95, samples=50)),
    (["design-pitch", "--robust", "--quantile", "1"], "--quantile",
     lambda studies, d: studies.robust_pitch(d, None, quantile=1.0)),
])
def test_library_errors_name_the_parameter_and_the_cli_prints_the_flag(argv, flag, call):
    """The studies' errors name their parameter (a library user has no flags); the command
    line prints the flag that set it (cli.FLAG_OF_PARAMETER)."""
    from prs_geom import cli, studies
    from prs_geom.model.errors import DesignError

    parameter = next(k for k, v in cli.FLAG_OF_PARAMETER.items() if v == flag)
    with pytest.raises(DesignError) as info:
        call(studies, default_design())
    assert info.value.field == parameter and not str(info.value).startswith("-")
    code, _, err = run(argv)
    assert code == 2 and err.startswith(f"error: {flag} = "), err
    assert err.strip().split(" = ", 1)[1] == str(info.value).split(" = ", 1)[1]   # the same rule


def test_execution_flags_are_one_definition():
    """Every command that runs chunked work takes the same execution flags, with the same
    help and the same check."""
    import argparse

    from prs_geom.cli import make_parser

    sub = next(a for a in make_parser()._actions if isinstance(a, argparse._SubParsersAction))
    flags = {}
    for name, parser in sub.choices.items():
        found = {s: (a.type, a.metavar) for a in parser._actions for s in a.option_strings
                 if s in ("--workers", "--scheduler", "--dask-workers")}
        if found:
            flags[name] = found
    assert set(flags) == {"design-pitch", "tolerance", "sweep"}
    assert len({tuple(sorted(f.items())) for f in flags.values()}) == 1
    for command in ("tolerance", "design-pitch --robust", "sweep"):
        code, _, err = run([*command.split(), "--workers", "0"])
        assert code == 2 and err.startswith("error: --workers = 0: must be >= 1"), (command, err)
