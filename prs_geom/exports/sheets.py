"""Machining sheets as CSV (one per part) and one XLSX workbook (a sheet per part).

CSV: ``#``-prefixed header lines (part, design, units, datum, ...), then one header row of
column keys and one row per tooth and flank. The sheets' numbers are rounded where they are
made (:mod:`prs_geom.analysis.machining`: mm to 1e-9 mm, um to 1e-6 um) and written in the
shortest form that reads back to the same float, always positional (``0.000001``, never
``1e-06``), so a reader gets back exactly the values in report.json and no float noise.
XLSX (openpyxl): a summary sheet with every part's header, then one table per part (numbers
to about 16 significant digits, the precision of the format; shown to 0.01 um), formatted
for printing (A4 landscape, fit to one page wide, title rows repeated on every page, units in
the column titles, page header with design, part, date and version).

Text (the design name and the tolerance source a design file brings) goes through
:mod:`prs_geom.exports.textsafe`: CSV fields and comment lines never begin a spreadsheet
formula, every text cell of the workbook is stored as a string.
"""
from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any, NamedTuple

from prs_geom.analysis.machining import COLUMNS, MachiningSheet
from prs_geom.exports.textsafe import csv_comment, csv_field, xlsx_append, xlsx_header_text, xlsx_text

__all__ = ["sheet_csv", "read_sheet_csv", "write_xlsx", "read_xlsx", "inspection_csv"]


def _cell(v) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return repr(v)
    return str(v)


def _sheet_cell(v) -> str:
    """A machining-sheet value: floats in the shortest round-trip digits, positional."""
    if isinstance(v, float):
        from numpy import format_float_positional

        return format_float_positional(v, unique=True, trim="0")
    return _cell(v)


def sheet_csv(sheet: MachiningSheet) -> str:
    buf = io.StringIO()
    for k, v in sheet.header.items():
        # header text (the design name, the tolerance source) inside a comment line
        buf.write(f"# {k}: {csv_comment(v) if isinstance(v, str) else _sheet_cell(v)}\n")
    for st in sheet.starts:
        buf.write(f"# start {st['start']}: " + ", ".join(
            f"{k} {_sheet_cell(v) if not isinstance(v, list) else ' '.join(map(str, v))}"
            for k, v in st.items() if k != "start") + "\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow([c[0] for c in COLUMNS])
    for row in sheet.rows:
        # numbers and the sheet's own words (flank, "-" for a flank no contact loads): no design text
        w.writerow([_sheet_cell(row[c[0]]) for c in COLUMNS])
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


class _XlsxStyles(NamedTuple):
    """The styles of the workbook, one instance each, shared by all their cells (openpyxl
    keeps one copy per distinct style anyway; a new object per cell costs time)."""

    bold: Any
    title_fill: Any
    title_border: Any
    wrap_top: Any
    key_font: Any
    row_border: Any


def _xlsx_styles() -> _XlsxStyles:
    from openpyxl.styles import Alignment, Border, Font, PatternFill, Side

    thin = Side(style="thin", color="999999")
    return _XlsxStyles(bold=Font(bold=True), title_fill=PatternFill("solid", fgColor="DDE6F0"),
                       title_border=Border(top=thin, bottom=thin, left=thin, right=thin),
                       wrap_top=Alignment(wrap_text=True, vertical="top"),
                       key_font=Font(italic=True, color="777777", size=8),
                       row_border=Border(bottom=Side(style="hair", color="CCCCCC")))


def _header_format(key: str) -> str:
    """The display format of a header value by its key's unit suffix."""
    return "0.00000" if key.endswith("_mm") else "0.00" if key.endswith("_um") or "_um_" in key else \
        "0.000" if key.endswith(("_deg", "_degC")) else "0.0000"


def _summary_headers(summary, sheets: dict[str, MachiningSheet], styles: _XlsxStyles) -> list[str]:
    """Title, part names and the header of every part side by side; returns the header keys."""
    from openpyxl.styles import Font

    parts = list(sheets)
    design = next(iter(sheets.values())).header["design"] if sheets else ""
    xlsx_append(summary, [f"Pitch-modification machining sheets of design '{design}'"])
    summary["A1"].font = Font(bold=True, size=13)
    xlsx_append(summary, ["field"] + parts)
    for c in range(1, len(parts) + 2):
        summary.cell(row=2, column=c).font = styles.bold
    keys = list(dict.fromkeys(k for sh in sheets.values() for k in sh.header))
    for k in keys:
        xlsx_append(summary, [k] + [sheets[p].header.get(k) for p in parts])
        fmt = _header_format(k)
        for c in range(2, len(parts) + 2):
            cell = summary.cell(row=summary.max_row, column=c)
            if isinstance(cell.value, float):
                cell.number_format = fmt
    return keys


def _summary_starts(summary, sheets: dict[str, MachiningSheet], first_row: int, styles: _XlsxStyles) -> None:
    """The thread starts of every part, a row each, from ``first_row`` on."""
    r0 = first_row
    summary.cell(row=r0, column=1, value="thread starts").font = styles.bold
    r0 += 1
    skeys = ["part", "start", "angular_index_deg", "axial_offset_mm", "nominal_lead_mm", "lead_min_mm",
             "lead_max_mm", "teeth_at_theta_0"]
    for c, k in enumerate(skeys, start=1):
        summary.cell(row=r0, column=c, value=k).font = styles.bold
    for p_ in sheets:
        for st in sheets[p_].starts:
            r0 += 1
            for c, k in enumerate(skeys, start=1):
                v = p_ if k == "part" else st[k]
                v = " ".join(map(str, v)) if isinstance(v, list) else v
                cell = summary.cell(row=r0, column=c)
                if isinstance(v, str):
                    xlsx_text(cell, v)
                else:
                    cell.value = v
                if k.endswith("_mm"):
                    cell.number_format = "0.00000"


def _write_summary(summary, sheets: dict[str, MachiningSheet], styles: _XlsxStyles, version: str,
                   date: str) -> None:
    """The ``summary`` sheet: the headers side by side, the thread starts, widths, print setup."""
    from openpyxl.utils import get_column_letter

    summary.title = "summary"
    parts = list(sheets)
    design = next(iter(sheets.values())).header["design"] if sheets else ""
    keys = _summary_headers(summary, sheets, styles)
    _summary_starts(summary, sheets, len(keys) + 4, styles)
    summary.column_dimensions["A"].width = max(len(k) for k in keys) + 2 if keys else 20
    for c in range(2, len(parts) + 2):
        summary.column_dimensions[get_column_letter(c)].width = 60
        for r in range(3, len(keys) + 3):
            summary.cell(row=r, column=c).alignment = styles.wrap_top
    summary.freeze_panes = "A3"                 # the title and the part names stay
    _print_setup(summary, design, "summary", version, date)


def _write_part_sheet(ws, part: str, sheet: MachiningSheet, styles: _XlsxStyles, version: str, date: str) -> None:
    """One part's sheet: title, column titles with units, column keys, a row per flank."""
    from openpyxl.styles import Font
    from openpyxl.utils import get_column_letter

    xlsx_append(ws, [f"Machining sheet: {part} of design '{sheet.header['design']}' "
                     f"(datum, process and tolerances on the summary sheet)"])
    ws["A1"].font = Font(bold=True, size=12)
    title_row, key_row = 2, 3
    for c, (key, title, unit) in enumerate(COLUMNS, start=1):
        cell = ws.cell(row=title_row, column=c, value=f"{title} ({unit})" if unit else title)
        cell.font = styles.bold
        cell.alignment = styles.wrap_top
        cell.fill = styles.title_fill
        cell.border = styles.title_border
        ws.cell(row=key_row, column=c, value=key).font = styles.key_font
    for i, row in enumerate(sheet.rows):
        for c, (key, _, unit) in enumerate(COLUMNS, start=1):
            v = row[key]
            v = ("yes" if v else "no") if isinstance(v, bool) else v
            cell = ws.cell(row=key_row + 1 + i, column=c)
            if isinstance(v, str):
                xlsx_text(cell, v)
            else:
                cell.value = v
            if unit == "mm":
                cell.number_format = "0.00000"
            elif unit == "um":
                cell.number_format = "0.00"
            cell.border = styles.row_border
    for c, (key, title, unit) in enumerate(COLUMNS, start=1):
        # wide enough for the key and the longest displayed number; titles wrap
        ws.column_dimensions[get_column_letter(c)].width = max(len(key) + 2, 12)
    ws.row_dimensions[title_row].height = 60
    ws.freeze_panes = ws.cell(row=key_row + 1, column=1)
    ws.print_title_rows = f"{title_row}:{key_row}"
    _print_setup(ws, sheet.header["design"], part, version, date)


def write_xlsx(sheets: dict[str, MachiningSheet], path: Path, version: str = "", date: str = "") -> None:
    """The workbook: a ``summary`` sheet (the header of every part side by side), then one
    sheet per part holding only the table (title row, column titles with units, column keys,
    one row per flank), frozen below the keys. Numbers are the sheet's (rounded to 1e-9 mm
    and 1e-6 um, :mod:`prs_geom.analysis.machining`) and read back unchanged; the display
    format rounds mm to 0.00001 (0.01 um) and um to 0.01. Print setup: A4
    landscape, fit to one page wide, title rows repeated, page header with design, part,
    date and version."""
    from openpyxl import Workbook

    wb = Workbook()
    styles = _xlsx_styles()
    _write_summary(wb.active, sheets, styles, version, date)
    for part, sheet in sheets.items():
        _write_part_sheet(wb.create_sheet(part), part, sheet, styles, version, date)
    wb.save(path)


def _print_setup(ws, design: str, part: str, version: str, date: str) -> None:
    ws.page_setup.orientation = "landscape"
    ws.page_setup.paperSize = ws.PAPERSIZE_A4
    ws.page_setup.fitToWidth = 1
    ws.page_setup.fitToHeight = 0
    ws.sheet_properties.pageSetUpPr.fitToPage = True
    ws.oddHeader.left.text = xlsx_header_text(f"{design} - {part}")
    ws.oddHeader.right.text = " ".join(x for x in (date, f"prs_geom {version}" if version else "") if x)
    ws.oddFooter.center.text = "page &P of &N"


def read_xlsx(path: Path) -> dict[str, list[dict[str, object]]]:
    """Rows of every sheet keyed by column key (for checks and round trips)."""
    from openpyxl import load_workbook

    wb = load_workbook(path, read_only=True)
    out = {}
    keys = [c[0] for c in COLUMNS]
    for ws in wb.worksheets:
        rows = list(ws.iter_rows(values_only=True))
        k = next((i for i, r in enumerate(rows) if r and list(r[:len(keys)]) == keys), None)
        if k is None:                       # the summary sheet
            continue
        out[ws.title] = [dict(zip(keys, r[:len(keys)])) for r in rows[k + 1:] if r and r[0] is not None]
    return out


def inspection_csv(reports: dict[str, dict]) -> str:
    """``inspection.csv``: one row per part (screw, roller, nut) with the over-wire /
    over-ball values of :func:`prs_geom.exports.report.inspection_section` (keys carry
    their units; numbers in shortest round-trip form, at 20 degC)."""
    rows = list(reports.values())
    keys = list(dict.fromkeys(k for r in rows for k in r))
    buf = io.StringIO()
    buf.write("# over-wire (screw, roller) and over-ball (nut) inspection at 20 degC; "
              "docs/theory/inspection.md\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(keys)
    for r in rows:
        w.writerow([csv_field(v) if isinstance(v, str) else _cell(v) for v in (r.get(k) for k in keys)])
    return buf.getvalue()
