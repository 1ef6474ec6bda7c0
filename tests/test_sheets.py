"""The XLSX machining workbook keeps its look with shared style objects (issue 17): titles,
column titles, key row, data rows, number formats and column widths, cell by cell."""
from __future__ import annotations

import pytest
from readers import assert_xlsx_cell

from prs_geom.analysis.machining import COLUMNS, machining_sheets
from prs_geom.exports.sheets import read_xlsx, write_xlsx
from prs_geom.model.design import default_design


@pytest.fixture(scope="module")
def workbook(tmp_path_factory):
    from openpyxl import load_workbook

    sheets = machining_sheets(default_design())
    path = tmp_path_factory.mktemp("xlsx") / "machining.xlsx"
    write_xlsx(sheets, path, "9.8.7-test", "2026-01-02")
    return sheets, path, load_workbook(path)


def test_values_read_back(workbook):
    sheets, path, _ = workbook
    back = read_xlsx(path)
    assert set(back) == set(sheets)
    for part, sheet in sheets.items():
        assert len(back[part]) == len(sheet.rows)
        for got, row in zip(back[part], sheet.rows):
            for key, _, _ in COLUMNS:
                assert_xlsx_cell(got[key], row[key])


def test_summary_styles(workbook):
    sheets, _, wb = workbook
    s = wb["summary"]
    assert s["A1"].font.b and s["A1"].font.sz == 13
    assert all(s.cell(row=2, column=c).font.b for c in range(1, len(sheets) + 2))
    assert s.cell(row=3, column=2).alignment.wrap_text and s.cell(row=3, column=2).alignment.vertical == "top"
    assert s.column_dimensions["B"].width == 60
    assert s.freeze_panes == "A3"


def test_part_table_styles(workbook):
    sheets, _, wb = workbook
    for part, sheet in sheets.items():
        ws = wb[part]
        assert ws["A1"].font.b and ws["A1"].font.sz == 12
        for c, (key, _, unit) in enumerate(COLUMNS, start=1):
            title, keycell = ws.cell(row=2, column=c), ws.cell(row=3, column=c)
            assert title.font.b and title.alignment.wrap_text
            assert title.fill.fill_type == "solid" and title.fill.fgColor.rgb.endswith("DDE6F0")
            assert {title.border.top.style, title.border.bottom.style, title.border.left.style,
                    title.border.right.style} == {"thin"}
            assert keycell.value == key and keycell.font.i and keycell.font.sz == 8
            assert ws.column_dimensions[title.column_letter].width == max(len(key) + 2, 12)
            for r in range(4, 4 + len(sheet.rows)):
                cell = ws.cell(row=r, column=c)
                assert cell.border.bottom.style == "hair"
                assert cell.number_format == {"mm": "0.00000", "um": "0.00"}.get(unit, "General")
        assert ws.row_dimensions[2].height == 60
