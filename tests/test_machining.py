"""Machining sheets: process logic, CSV and XLSX read back (issue 6)."""
from pathlib import Path

import numpy as np
import pytest

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
        assert sh.header["base_pitch_mm"] == pl.min()
        assert stock == pytest.approx(np.sum(pl - pl.min()), abs=1e-15)
        for row in sh.rows:
            j = row["tooth"] - 1
            side = -1 if row["flank"] == "lower" else 1
            shift = row["axial_shift_um"] * 1e-3
            # lower flanks can only move +z, upper flanks only -z
            assert shift >= 0 if side < 0 else shift <= 0
            # base flank (thick base tooth) + shift = designed flank position
            base_flank = row["base_position_mm"] + side * (t + 0.5 * stock)
            designed_flank = np.sum(pl[:j]) + side * t
            assert base_flank + shift == pytest.approx(designed_flank, abs=1e-12)
            assert row["inspection_position_mm"] == pytest.approx(designed_flank + t, abs=1e-12)
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
        for got, want in zip(rows, ref):
            for key, _, _ in COLUMNS:
                w = want[key]
                if isinstance(w, bool):
                    assert got[key] == ("yes" if w else "no")
                elif isinstance(w, float):
                    # XLSX numbers carry ~16 significant digits (Excel shows 15)
                    assert got[key] == pytest.approx(w, rel=1e-15, abs=1e-300)
                elif w is None:
                    assert got[key] is None
                else:
                    assert got[key] == w


def test_xlsx_is_formatted_for_printing(built):
    from openpyxl import load_workbook
    d, out, report = built
    ws = load_workbook(out / "machining.xlsx")["roller"]
    assert ws.page_setup.orientation == "landscape"
    assert ws.page_setup.fitToWidth == 1
    assert ws.print_title_rows is not None
    assert ws.freeze_panes is not None
