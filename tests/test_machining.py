"""Machining sheets: process logic, CSV and XLSX read back (issue 6)."""
from pathlib import Path

import numpy as np
import pytest
from readers import assert_xlsx_cell

from prs_geom.model.io import load_design
from prs_geom.analysis.machining import COLUMNS, machining_sheets
from prs_geom.pipeline import build
from prs_geom.geometry.profiles import ThreadProfiles
from prs_geom.exports.sheets import read_sheet_csv, read_xlsx

EXAMPLES = Path(__file__).parent.parent / "examples"


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    d = load_design(EXAMPLES / "graded-pitch.toml")
    out = tmp_path_factory.mktemp("m") / "out"
    report = build(d, out)
    return d, out, report


def test_grinding_only_removes_material_and_lands_on_design():
    d = load_design(EXAMPLES / "graded-pitch.toml")
    sheets = machining_sheets(d)
    for part, sh in sheets.items():
        pl = np.array(d.pitch_list(part))
        t = float(getattr(ThreadProfiles.from_design(d), part).tooth_half_width(
            getattr(ThreadProfiles.from_design(d), part).pitch_radius))
        stock = sh.header["base_tooth_thickness_stock_um"] * 1e-3
        # every length rounded to 1e-9 mm (um: 1e-6 um): the sheet states the numbers to 1 pm
        assert sh.header["base_pitch_mm"] == round(pl.min(), 9)
        assert stock == pytest.approx(np.sum(pl - pl.min()), abs=5e-10)
        for row in sh.rows:
            j = row["tooth"] - 1
            side = -1 if row["flank"] == "lower" else 1
            shift = row["axial_shift_um"] * 1e-3
            # lower flanks can only move +z, upper flanks only -z
            assert shift >= 0 if side < 0 else shift <= 0
            # independent: the designed flank from the pitch list and the profile's half-width,
            # the base flank from the thick base tooth (mid-plane (j-1) p_b + stock/2)
            # datum A = the end face: tooth 1's mid-plane at p/2 (roller) or 0 (nut) from it
            mid1 = 0.5 * d.thread.pitch_mm if part == "roller" else 0.0
            designed_flank = mid1 + np.sum(pl[:j]) + side * t
            base_flank = mid1 + j * pl.min() + 0.5 * stock + side * (t + 0.5 * stock)
            assert row["on_part"] == (0 <= designed_flank <= d.thread.engaged_teeth * d.thread.pitch_mm)
            assert row["designed_position_mm"] == pytest.approx(designed_flank, abs=5e-10 + 1e-13)
            # (base_flank reads the rounded stock: one more rounding in the reference)
            assert row["base_position_mm"] == pytest.approx(base_flank, abs=1e-9)
            # the sheet identity a shop checks, on the numbers as written: exact at the
            # stated rounding, and to float precision
            assert round(row["base_position_mm"] + row["axial_shift_um"] / 1000, 9) == row["designed_position_mm"]
            assert abs(row["base_position_mm"] + row["axial_shift_um"] / 1000 - row["designed_position_mm"]) < 1e-12
            assert row["inspection_position_mm"] == row["designed_position_mm"]
            assert row["lead_deviation_um"] == pytest.approx((np.sum(pl[:j]) - j * d.thread.pitch_mm) * 1e3,
                                                             abs=5e-7 + 1e-12)
            assert row["base_tooth_thickness_mm"] - row["tooth_thickness_mm"] == pytest.approx(stock, abs=1.5e-9)
            assert row["tolerance_um"] is None
        assert "not synthesised" in sh.header["tolerance"]
        # datums: tooth 1 lower and tooth n upper flanks are not worked
        assert sh.rows[0]["axial_shift_um"] == 0 and sh.rows[-1]["axial_shift_um"] == 0
        assert sh.rows[0]["worked"] is False and sh.rows[2]["worked"] is True


def test_normal_stock_is_axial_shift_times_normal_component():
    d = load_design(EXAMPLES / "graded-pitch.toml")
    sh = machining_sheets(d)["roller"]
    for row in sh.rows[2:6]:
        assert 0.6 < row["normal_stock_um"] / abs(row["axial_shift_um"]) < 0.75   # |n_z| ~ cos45 cos(lambda)


def test_csv_reads_back_to_report_numbers(built):
    d, out, report = built
    for part in ("roller", "nut"):
        header, rows = read_sheet_csv((out / f"machining_{part}.csv").read_text())
        ref = report["machining"][part]
        assert header["design"] == d.name and header["part"] == part
        assert float(header["base_pitch_mm"]) == ref["header"]["base_pitch_mm"]
        assert len(rows) == len(ref["rows"]) == 2 * d.thread.engaged_teeth
        for got in rows:      # the shop's identity, on the numbers as read back
            assert abs(float(got["designed_position_mm"]) - (float(got["base_position_mm"])
                                                             + float(got["axial_shift_um"]) / 1000)) < 1e-9
        for got, want in zip(rows, ref["rows"]):
            for key, _, unit in COLUMNS:
                if isinstance(want[key], float):
                    assert float(got[key]) == want[key]          # exact round trip
                elif want[key] is None:
                    assert got[key] == ""
                elif isinstance(want[key], bool):
                    assert got[key] == ("yes" if want[key] else "no")
                else:
                    assert str(got[key]) == str(want[key])


def test_xlsx_reads_back_to_report_numbers(built):
    d, out, report = built
    wb = read_xlsx(out / "machining.xlsx")
    assert set(wb) == {"roller", "nut"}
    for part, rows in wb.items():
        ref = report["machining"][part]["rows"]
        assert len(rows) == len(ref)
        for got in rows:
            assert abs(got["designed_position_mm"] - (got["base_position_mm"] + got["axial_shift_um"] / 1000)) < 1e-9
        for got, want in zip(rows, ref):
            for key, _, _ in COLUMNS:
                assert_xlsx_cell(got[key], want[key])


def test_xlsx_is_formatted_for_printing(built):
    from openpyxl import load_workbook
    d, out, report = built
    ws = load_workbook(out / "machining.xlsx")["roller"]
    assert ws.page_setup.orientation == "landscape"
    assert ws.page_setup.fitToWidth == 1
    assert ws.print_title_rows is not None
    assert ws.freeze_panes is not None


def test_tolerances_of_the_design_reach_the_sheet():
    """Per-flank tolerances written by a synthesis (the [tolerances] lists) are printed per
    loaded flank with their source; the nut's unloaded lower flank has none."""
    from dataclasses import replace as _replace

    from prs_geom.model.design import Tolerances
    d = load_design(EXAMPLES / "graded-pitch.toml")
    n = d.thread.engaged_teeth
    tol = Tolerances(roller_screw_flank_um=tuple(0.3 + 0.01 * j for j in range(n)),
                     roller_nut_flank_um=(0.4,) * n, nut_flank_um=tuple(0.5 + 0.02 * j for j in range(n)),
                     screw_flank_um=(0.6,) * n, source="synthesised by a test", target_ldc=1.2, confidence=0.95)
    sheets = machining_sheets(_replace(d, tolerances=tol))
    for row in sheets["roller"].rows:
        j = row["tooth"] - 1
        want = tol.roller_screw_flank_um[j] if row["flank"] == "upper" else tol.roller_nut_flank_um[j]
        assert row["tolerance_um"] == round(want, 6)          # 0.31, not 0.31000000000000005
    for row in sheets["nut"].rows:
        j = row["tooth"] - 1
        assert row["tolerance_um"] == (round(tol.nut_flank_um[j], 6) if row["flank"] == "upper" else None)
    h = sheets["nut"].header["tolerance"]
    assert "synthesised by a test" in h and "1.2" in h and "0.95" in h


def test_xlsx_summary_sheet_and_number_formats(built):
    from openpyxl import load_workbook
    d, out, report = built
    wb = load_workbook(out / "machining.xlsx")
    assert wb.sheetnames == ["summary", "roller", "nut"]
    s = wb["summary"]
    assert [c.value for c in s[2]][:3] == ["field", "roller", "nut"]
    ws = wb["roller"]
    assert ws.freeze_panes == "A4"                           # only the three title rows stay
    keys = [c[0] for c in COLUMNS]
    for c, (key, _, unit) in enumerate(COLUMNS, start=1):
        cell = ws.cell(row=4, column=c)
        if unit == "mm":
            assert cell.number_format == "0.00000"              # 0.01 um
        elif unit == "um":
            assert cell.number_format == "0.00"
    assert ws.cell(row=3, column=1).value == keys[0]
    assert ws.oddHeader.left.text.startswith(d.name) and "prs_geom" in ws.oddHeader.right.text


def test_sheet_flanks_and_datum_exist_on_the_meshed_parts():
    """Independent reader: the meshed parts (part frames) cut by the line theta = 0 at the
    pitch radius. Every flank the sheet says is on the part is a mesh crossing within the
    mesh tolerance, the first crossing after datum A (the end face z = 0) is the first flank
    the sheet marks on the part, and the flanks marked off the part are not there."""
    import trimesh

    from prs_geom.pipeline import build_meshes
    d = load_design(EXAMPLES / "graded-pitch.toml")
    sheets = machining_sheets(d)
    meshes = build_meshes(d)
    tol = 0.03                                   # chord 0.01 mm on a 45 deg flank, plus the helix
    for part in ("roller", "nut"):
        mesh = meshes[f"{part}_thread"]        # the thread body: datum A is its end face z = 0
        r = getattr(ThreadProfiles.from_design(d), part).pitch_radius
        # the section by the plane y = 0 (segments), crossed by the line x = r, x > 0
        seg = trimesh.intersections.mesh_plane(mesh, [0.0, 1.0, 0.0], [0.0, 0.0, 0.0])
        x1, x2, z1, z2 = seg[:, 0, 0], seg[:, 1, 0], seg[:, 0, 2], seg[:, 1, 2]
        cross = (x1 - r) * (x2 - r) < 0
        u = (r - x1[cross]) / (x2[cross] - x1[cross])
        z = np.unique(np.round(np.sort(z1[cross] + u * (z2[cross] - z1[cross])), 9))
        rows = sheets[part].rows
        on = [row["designed_position_mm"] for row in rows if row["on_part"]]
        off = [row["designed_position_mm"] for row in rows if not row["on_part"]]
        for pos in on:
            assert np.min(np.abs(z - pos)) < tol, (part, pos)
        for pos in off:
            assert np.min(np.abs(z - pos)) > 0.2, (part, pos)
        inside = z[z > 1e-6]
        assert abs(inside[0] - min(on)) < tol           # the datum tooth's flank is the first one
        assert abs(mesh.bounds[0][2]) < 1e-9            # datum A: the end face z = 0 bounds the part
        if part == "nut":                                # ... and at the pitch radius it is material
            assert np.min(np.abs(z)) < 1e-6


def test_start_table_of_the_multi_start_nut():
    """Independent check: the teeth of start k at theta = 0 are k, k + N, ...; the start's
    lead is the sum of N consecutive designed pitches; the angular index splits the turn."""
    d = load_design(EXAMPLES / "graded-pitch.toml")
    sheets = machining_sheets(d)
    N = d.nut.starts
    pl = np.array(d.pitch_list("nut"))
    starts = sheets["nut"].starts
    assert [s["start"] for s in starts] == list(range(1, N + 1))
    assert [s["angular_index_deg"] for s in starts] == [round(360.0 * k / N, 9) for k in range(N)]
    for k, s in enumerate(starts):
        assert s["teeth_at_theta_0"][:2] == [k + 1, k + 1 + N]
        # lengths to 1e-9 mm (issue 28): the rounded exact value
        assert s["axial_offset_mm"] == pytest.approx(np.sum(pl[:k]), abs=5e-10 + 1e-15)
        leads = [np.sum(pl[j - 1:j - 1 + N]) for j in s["teeth_at_theta_0"] if j - 1 + N <= len(pl)]
        assert s["lead_min_mm"] == pytest.approx(min(leads), abs=5e-10 + 1e-14)
        assert s["lead_max_mm"] == pytest.approx(max(leads), abs=5e-10 + 1e-14)
        assert s["nominal_lead_mm"] == N * d.thread.pitch_mm
    assert sorted(t for s in starts for t in s["teeth_at_theta_0"]) == list(range(1, d.thread.engaged_teeth + 1))
    assert sheets["roller"].starts[0]["teeth_at_theta_0"] == list(range(1, d.thread.engaged_teeth + 1))
    assert "index the part by +360/N" in sheets["nut"].header["indexing"]


def test_build_reports_inspection_and_sheets_carry_it(built):
    d, out, report = built
    insp = report["inspection"]
    assert set(insp) == {"screw", "roller", "nut"}
    for part, rep in insp.items():
        assert abs(rep["numerical_check_um"]) < 0.1 and rep["check_passed"]
    for part in ("roller", "nut"):
        header, _ = read_sheet_csv((out / f"machining_{part}.csv").read_text())
        assert f"M = {insp[part]['measurement_mm']:.6f} mm" in header["inspection"]


def test_inspection_csv_reads_back(built):
    import csv as _csv
    d, out, report = built
    lines = [l for l in (out / "inspection.csv").read_text().splitlines() if not l.startswith("#")]
    rows = list(_csv.DictReader(lines))
    assert [r["part"] for r in rows] == ["screw", "roller", "nut"]
    for r in rows:
        assert float(r["measurement_mm"]) == report["inspection"][r["part"]]["measurement_mm"]


# --------------------------------------------------------------------------- numbers without float noise (issue 28)
#: Decimals a sheet number may carry, by unit: mm to 1e-9 mm, um to 1e-6 um (1 pm both).
DECIMALS = {"mm": 9, "um": 6}


def _decimals(text: str) -> int:
    assert "e" not in text.lower(), text             # positional, never 1e-06
    return len(text.partition(".")[2])


def _assert_clean(rows, float_of=float):
    """Every numeric cell: at most 9 (mm) or 6 (um) decimals, equal to its own rounding; the
    shop identity designed = base + shift / 1000 exactly at 1e-9 mm and to 1e-12 mm."""
    for row in rows:
        for key, _, unit in COLUMNS:
            if unit in DECIMALS and row[key] not in ("", None):
                if isinstance(row[key], str):
                    assert _decimals(row[key]) <= DECIMALS[unit], (key, row[key])
                x = float_of(row[key])
                assert round(x, DECIMALS[unit]) == x, (key, x)
        d, b, s = (float_of(row[k]) for k in ("designed_position_mm", "base_position_mm", "axial_shift_um"))
        assert round(b + s / 1000, 9) == d
        assert abs(b + s / 1000 - d) < 1e-12


def test_default_sheet_reads_as_typed():
    """The constant-pitch default design: roller tooth thickness p/2 = 1 mm, so the flanks of
    tooth j lie at 2j - 1.5 (lower) and 2j - 0.5 mm (upper) from datum A; the sheet says
    exactly that (it used to say 1.0000000000000009 and 3.5000000000000004)."""
    from prs_geom.exports.sheets import sheet_csv
    from prs_geom.model.design import default_design

    sh = machining_sheets(default_design())["roller"]
    for row in sh.rows:
        j = row["tooth"]
        want = 2 * j - 1.5 if row["flank"] == "lower" else 2 * j - 0.5
        assert row["designed_position_mm"] == row["base_position_mm"] == want
        assert row["tooth_thickness_mm"] == 1.0 and row["axial_shift_um"] == 0.0
    text = sheet_csv(sh)
    assert "\n2,upper,screw,2.0,2.0,3.5,3.5,0.0,0.0,1.0,1.0,0.0,,no,yes,3.5\n" in text
    _assert_clean(read_sheet_csv(text)[1])


def test_csv_and_xlsx_numbers_carry_no_float_noise(built):
    d, out, report = built
    for part in ("roller", "nut"):
        header, rows = read_sheet_csv((out / f"machining_{part}.csv").read_text())
        assert len(rows) == 2 * d.thread.engaged_teeth
        assert any(float(r["axial_shift_um"]) != 0.0 for r in rows)     # a graded part: real shifts
        _assert_clean(rows)
        assert _decimals(header["base_tooth_thickness_stock_um"]) <= 6
        assert _decimals(header["base_pitch_mm"]) <= 9
        # the sign rule survives the rounding: lower flanks +z, upper -z, datum flanks exactly 0
        for r in rows:
            s = float(r["axial_shift_um"])
            assert s >= 0 if r["flank"] == "lower" else s <= 0
        assert float(rows[0]["axial_shift_um"]) == 0.0 and float(rows[-1]["axial_shift_um"]) == 0.0
    for part, rows in read_xlsx(out / "machining.xlsx").items():
        _assert_clean(rows)
