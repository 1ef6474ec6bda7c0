"""Machining sheets as CSV (one per part) and one XLSX workbook (a sheet per part).

CSV: ``#``-prefixed header lines (part, design, units, datum, ...), then one header row of
column keys and one row per tooth and flank. Numbers are written with Python's shortest
round-trip representation, so a reader gets back exactly the values in report.json.
XLSX (openpyxl): the same header and table (numbers to about 16 significant digits, the
precision of the format), formatted for printing (landscape, fit to one
page wide, title rows repeated on every page, units in the column titles).
"""
from __future__ import annotations

import csv
import io
from pathlib import Path

from prs_geom.analysis.machining import COLUMNS, MachiningSheet


def _cell(v) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return repr(v)
    return str(v)


def sheet_csv(sheet: MachiningSheet) -> str:
    buf = io.StringIO()
    for k, v in sheet.header.items():
        buf.write(f"# {k}: {_cell(v)}\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow([c[0] for c in COLUMNS])
    for row in sheet.rows:
        w.writerow([_cell(row[c[0]]) for c in COLUMNS])
    return buf.getvalue()


def read_sheet_csv(text: str) -> tuple[dict[str, str], list[dict[str, str]]]:
    """Header dict and rows (strings) of a sheet CSV."""
    lines = text.splitlines()
    header = {}
    body = []
    for line in lines:
        if line.startswith("# "):
            k, _, v = line[2:].partition(": ")
            header[k] = v
        else:
            body.append(line)
    return header, list(csv.DictReader(body))


def write_xlsx(sheets: dict[str, MachiningSheet], path: Path) -> None:
    from openpyxl import Workbook
    from openpyxl.styles import Alignment, Border, Font, PatternFill, Side
    from openpyxl.utils import get_column_letter

    wb = Workbook()
    wb.remove(wb.active)
    thin = Side(style="thin", color="999999")
    for part, sheet in sheets.items():
        ws = wb.create_sheet(part)
        ws.append([f"Pitch-modification machining sheet: {part} of design '{sheet.header['design']}'"])
        ws["A1"].font = Font(bold=True, size=13)
        r = 2
        for k, v in sheet.header.items():
            ws.cell(row=r, column=1, value=k).font = Font(bold=True)
            ws.cell(row=r, column=2, value=v)
            r += 1
        r += 1
        title_row = r
        for c, (key, title, unit) in enumerate(COLUMNS, start=1):
            cell = ws.cell(row=r, column=c, value=f"{title} ({unit})" if unit else title)
            cell.font = Font(bold=True)
            cell.alignment = Alignment(wrap_text=True, vertical="top")
            cell.fill = PatternFill("solid", fgColor="DDE6F0")
            cell.border = Border(top=thin, bottom=thin, left=thin, right=thin)
        key_row = r + 1
        for c, (key, _, _) in enumerate(COLUMNS, start=1):
            ws.cell(row=key_row, column=c, value=key).font = Font(italic=True, color="777777", size=8)
        for i, row in enumerate(sheet.rows):
            for c, (key, _, unit) in enumerate(COLUMNS, start=1):
                v = row[key]
                cell = ws.cell(row=key_row + 1 + i, column=c, value=("yes" if v else "no") if isinstance(v, bool) else v)
                if unit == "mm":
                    cell.number_format = "0.0000000"
                elif unit == "um":
                    cell.number_format = "0.0000"
                cell.border = Border(bottom=Side(style="hair", color="CCCCCC"))
        for c in range(1, len(COLUMNS) + 1):
            ws.column_dimensions[get_column_letter(c)].width = 16 if c > 3 else 10
        ws.row_dimensions[title_row].height = 45
        ws.freeze_panes = ws.cell(row=key_row + 1, column=1)
        ws.print_title_rows = f"{title_row}:{key_row}"
        ws.page_setup.orientation = "landscape"
        ws.page_setup.paperSize = ws.PAPERSIZE_A4
        ws.page_setup.fitToWidth = 1
        ws.page_setup.fitToHeight = 0
        ws.sheet_properties.pageSetUpPr.fitToPage = True
        ws.oddHeader.center.text = f"{sheet.header['design']} - {part}"
        ws.oddFooter.center.text = "page &P of &N"
    wb.save(path)


def read_xlsx(path: Path) -> dict[str, list[dict[str, object]]]:
    """Rows of every sheet keyed by column key (for checks and round trips)."""
    from openpyxl import load_workbook

    wb = load_workbook(path, read_only=True)
    out = {}
    keys = [c[0] for c in COLUMNS]
    for ws in wb.worksheets:
        rows = list(ws.iter_rows(values_only=True))
        k = next(i for i, r in enumerate(rows) if r and list(r[:len(keys)]) == keys)
        out[ws.title] = [dict(zip(keys, r[:len(keys)])) for r in rows[k + 1:] if r and r[0] is not None]
    return out
