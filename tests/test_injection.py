"""Issue 29, item 1: text from a design file never becomes a formula or a code in a deliverable.

Unit tests of :mod:`prs_geom.exports.textsafe` against hand-written outputs, then builds with
the injection set in every free-text field of a design (the material names and the tolerance
source; the design name is refused by validation, tested here too) read back format by
format: every XLSX cell (openpyxl), every CSV field (csv module), the texts of the drawings
(ezdxf), the strings the PDF draws, report.html. The harmonic line's writers are checked with
a name forced past its validation.
"""
from __future__ import annotations

import csv
import html
import io
import re
import textwrap
from pathlib import Path

import pytest

from prs_geom.exports.textsafe import (csv_comment, csv_field, dxf_text, dxf_wrap, mpl_text, xlsx_append,
                                       xlsx_header_text, xlsx_text, xlsx_value)
from prs_geom.model.design import (Material, Materials, MeshSettings, PRSDesign, Roller, Thread,
                                   Tolerances)
from prs_geom.model.errors import DesignError

#: The injection set: spreadsheet formulas (OWASP's examples), CAD text codes, mathtext, HTML.
INJECTIONS = (
    '=HYPERLINK("http://evil.example/x","click")',
    "+cmd|' /C calc'!A0",
    "-2+3+cmd|' /C calc'!A0",
    "@SUM(1+1)*cmd|' /C calc'!A0",
    "\t=1+1",
    "\r=1+1",
    "%%c%%d",
    "\\P{\\H2;x}",
    "$\\frac{1}{2}$",
    "<script>alert(1)</script>",
)
#: A tolerance source with a formula after every kind of separator and a line break.
SOURCE = 'src,=1+1;@SUM(1)\t-2\n"=3+3" ^J %%u'
#: Characters that make a spreadsheet cell a formula when they begin it (OWASP, CSV Injection).
FORMULA = "=+-@"
DANGER = FORMULA + "\t\r\n"


def _shown(text: str) -> str:
    """What a one-line drawing text shows for ``text``: C0 controls and DEL as their Unicode
    control pictures (the rule of prs_geom.exports.textsafe)."""
    return "".join("\u2421" if c == "\x7f" else chr(0x2400 + ord(c)) if c < " " else c for c in text)


def _squash(text: str) -> str:
    return " ".join(text.split())


def _begins(text: str, chars: str) -> bool:
    return bool(text) and text[0] in chars


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


# --------------------------------------------------------------------------- CSV rules
@pytest.mark.parametrize("text, expected", [
    ('=HYPERLINK("http://evil.example/x","click")', '\'=HYPERLINK("http://evil.example/x","click")'),
    ("+cmd|' /C calc'!A0", "'+cmd|' /C calc'!A0"),
    ("-2+3+cmd|' /C calc'!A0", "'-2+3+cmd|' /C calc'!A0"),
    ("@SUM(1+1)*cmd|' /C calc'!A0", "'@SUM(1+1)*cmd|' /C calc'!A0"),
    ("\t=1+1", "'\t'=1+1"),                 # a TAB begins a cell; after it a new one may begin
    ("\tsteel", "'\tsteel"),
    ("\r=1+1", "'\n=1+1"),                 # a lone CR would end the row: written as LF
    ("a\r\nb\rc", "a\nb\nc"),
    ("\nsteel", "'\nsteel"),
    ("  =1+1", "'  =1+1"),                  # cells trimmed on import begin with "="
    ("-", "'-"),
    ("-0.5 mm", "'-0.5 mm"),
    ("steel;=1+1", "steel;'=1+1"),          # ";" splits cells in many locales
    ('a; "@x', "a;' \"@x"),
    ("a\t-b", "a\t'-b"),
    ("a,=1+1", "a,=1+1"),                   # a comma makes the csv module quote the field
    ("%%c%%d", "%%c%%d"),
    ("<script>alert(1)</script>", "<script>alert(1)</script>"),
    ("steel", "steel"),
    ("1.4301 (X5CrNi18-10)", "1.4301 (X5CrNi18-10)"),
    ("", ""),
    # text that is a plain number is read as that number, never as a formula
    ("-0.5", "-0.5"), ("+3", "+3"), ("-1e-06", "-1e-06"), ("-.5", "-.5"),
])
def test_csv_field(text, expected):
    assert csv_field(text) == expected


@pytest.mark.parametrize("value", [-0.5, 3, 0.0, None, True, -1e300])
def test_csv_field_leaves_numbers_alone(value):
    assert csv_field(value) is value


@pytest.mark.parametrize("text, expected", [
    ('x,=1+1\n;"=2"', "x,'=1+1 ;'\"=2\""),
    ("a\r\nb\x0bc\u2028d", "a  b c d"),     # every str.splitlines break: one line
    ("a, -1", "a,' -1"),
    ("a;\t@b", "a;'\t'@b"),
    ("per flank, z = 0; B: the mid-plane", "per flank, z = 0; B: the mid-plane"),
    ("=1+1", "=1+1"),                       # inside a comment line, after "# key: "
])
def test_csv_comment(text, expected):
    assert csv_comment(text) == expected
    assert len(csv_comment(text).splitlines()) == 1


def test_csv_fields_read_back_through_the_csv_module():
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow([csv_field(t) for t in INJECTIONS] + [-0.5, "-0.5"])
    (row,) = list(csv.reader(io.StringIO(buf.getvalue(), newline="")))
    for field, text in zip(row, INJECTIONS):
        assert field == csv_field(text)
        assert field.replace("'", "") == text.replace("'", "").replace("\r", "\n")
        assert not _begins(field, DANGER)
    assert row[-2:] == ["-0.5", "-0.5"]


# --------------------------------------------------------------------------- XLSX rules
@pytest.mark.parametrize("text, expected", [
    ("=1+1", "=1+1"),
    ("a\rb", "a_x000D_b"),
    ("\x01\x1f", "_x0001__x001F_"),
    ("\t\n", "\t\n"),
    ("_x0041_", "_x005F_x0041_"),
    ("x_x00zz_", "x_x00zz_"),
    ("\ufffe", "_xFFFE_"),
])
def test_xlsx_value(text, expected):
    assert xlsx_value(text) == expected


def test_xlsx_header_text():
    assert xlsx_header_text("A&B&P") == "A&&B&&P"
    assert xlsx_header_text("default - summary") == "default - summary"


def test_xlsx_text_stores_every_text_as_a_string(tmp_path):
    from openpyxl import Workbook, load_workbook
    from openpyxl.utils.escape import unescape

    wb = Workbook()
    ws = wb.active
    texts = INJECTIONS + ("_x0041_", "a\x01b", "=")
    for r, t in enumerate(texts, start=1):
        assert xlsx_text(ws.cell(row=r, column=1), t).data_type == "s"
    xlsx_append(ws, ["=1+1", 2.5, None, "", "@A1"])
    wb.save(tmp_path / "t.xlsx")
    back = load_workbook(tmp_path / "t.xlsx").active
    for r, t in enumerate(texts, start=1):
        cell = back.cell(row=r, column=1)
        assert cell.data_type == "s"
        # what a spreadsheet shows (ST_Xstring escapes undone) is the text as typed
        assert unescape(cell.value) == t
        if not any(c < " " and c not in "\t\n" for c in t) and "_x" not in t:
            assert cell.value == t
    last = [c.value for c in back[len(texts) + 1]]
    assert last[:2] == ["=1+1", 2.5] and last[4] == "@A1"
    assert all(c.data_type != "f" for row in back.iter_rows() for c in row)


# --------------------------------------------------------------------------- DXF rules
@pytest.mark.parametrize("text, as_text, as_mtext", [
    ("%%c%%d", "%%%%%%c%%%%%%d", "%%%%%%c%%%%%%d"),
    ("\\P{\\H2;x}", "\\P{\\H2;x}", "\\\\P\\{\\\\H2;x\\}"),
    ("$\\frac{1}{2}$", "$\\frac{1}{2}$", "$\\\\frac\\{1\\}\\{2\\}$"),
    ("a^b", "a^ b", "a^ b"),
    ("\t=1+1", "\u2409=1+1", "^I=1+1"),
    ("\r=1+1", "\u240d=1+1", "\\P=1+1"),
    ("a\r\nb", "a\u240d\u240ab", "a\\Pb"),
    ("\x7f\x00", "\u2421\u2400", "\u2421\u2400"),
    ("50 %", "50 %%%", "50 %%%"),
    ("<script>alert(1)</script>", "<script>alert(1)</script>", "<script>alert(1)</script>"),
])
def test_dxf_text(text, as_text, as_mtext):
    assert dxf_text(text) == as_text
    assert dxf_text(text, mtext=True) == as_mtext


@pytest.mark.parametrize("text", INJECTIONS + ("a^b", "50%", "x\\", "{}\\~", "%%123", "^J^I%%%"))
def test_dxf_text_reads_back_literally(text):
    import ezdxf

    msp = ezdxf.new("R2010").modelspace()
    assert msp.add_text(dxf_text(text)).plain_text() == _shown(text)
    mtext = text.replace("\r\n", "\n").replace("\r", "\n")
    assert msp.add_mtext(dxf_text(text, mtext=True)).plain_text() == mtext


def test_dxf_wrap_wraps_as_textwrap_and_never_cuts_an_escape():
    from ezdxf.tools.text import plain_text

    plain = ("Journal bores 10x %%c12 H7: 12.000 to 12.018 mm, journals g6; the carrier angles of the "
             "rollers follow the nut's starts, see the sheet")
    assert dxf_wrap(plain, 40, "  ") == textwrap.wrap(plain, 40, subsequent_indent="  ")
    user = "a^b %%c " * 6 + "%" * 30 + "^" * 10 + "-" * 5
    lines = dxf_wrap("Parts: " + dxf_text(user), 20, "  ")
    assert len(lines) > 3
    # no line ends in a cut escape or in a literal caret (which ezdxf would drop): the lines
    # read back hold every character (long words are broken, so white space is left out)
    assert "".join("".join(plain_text(line).split()) for line in lines) == "".join(("Parts: " + user).split())
    assert not any(line.endswith(("^", "^ ")) for line in lines[:-1])


# --------------------------------------------------------------------------- matplotlib
@pytest.mark.parametrize("text, expected", [
    ("$\\frac{1}{2}$", "\\$\\frac{1}{2}\\$"),
    ("a\\$b", "a\\\\$b"),
    ("plain", "plain"),
])
def test_mpl_text_is_drawn_as_typed(text, expected):
    from matplotlib.text import Text

    assert mpl_text(text) == expected
    # the string matplotlib draws, and no mathtext parsed
    assert Text(0, 0, mpl_text(text))._preprocess_math(mpl_text(text)) == (text, False)


# --------------------------------------------------------------------------- names
@pytest.mark.parametrize("text", INJECTIONS)
def test_design_names_refuse_the_injection_set(text):
    from prs_geom.harmonic.model import HarmonicDesign

    with pytest.raises(DesignError):
        PRSDesign(name=text)
    with pytest.raises(DesignError):
        HarmonicDesign(name=text)


# --------------------------------------------------------------------------- builds
PARTS = ("screw", "roller", "nut", "carrier", "retaining_ring")
#: Parts-list lines of the assembly drawing: item, part, quantity (3 rollers, 2 carriers and rings).
ITEMS = {"screw": (1, "screw", 1), "roller": (2, "roller", 3), "nut": (3, "nut", 1),
         "carrier": (4, "carrier", 2), "retaining_ring": (5, "retaining ring", 2)}


@pytest.fixture(scope="module", params=[0, 1], ids=["set-1-5", "set-6-10"])
def injected_build(request, tmp_path_factory):
    """A small design with five strings of the injection set as its material names and a
    hostile tolerance source, built serially; (names by part, output folder)."""
    from prs_geom.pipeline import build

    names = dict(zip(PARTS, INJECTIONS[5 * request.param:5 * request.param + 5]))
    design = PRSDesign(name="small", thread=Thread(engaged_teeth=3), roller=Roller(count=3),
                       mesh=MeshSettings(chord_tolerance_mm=0.05),
                       materials=Materials(**{p: Material(name=n) for p, n in names.items()}),
                       tolerances=Tolerances(flank_um=2.0, samples=20, source=SOURCE))
    out = tmp_path_factory.mktemp("injected") / "out"
    build(design, out)
    return names, out


def _read_csv(text: str) -> tuple[list[str], list[list[str]]]:
    """The ``#`` comment lines before the table and the table's rows (csv module)."""
    comments, pos = [], 0
    while text.startswith("#", pos):
        end = text.index("\n", pos)
        comments.append(text[pos:end])
        pos = end + 1
    return comments, list(csv.reader(io.StringIO(text[pos:], newline="")))


def _cells_after_separators(text: str, separators: str) -> list[str]:
    """The cells a spreadsheet splitting ``text`` at any of ``separators`` would begin after
    a separator (each up to the next separator)."""
    return [re.split(f"[{re.escape(separators)}]", text[i + 1:])[0]
            for i, c in enumerate(text) if c in separators]


def test_build_csv_fields_are_neutralised(injected_build):
    names, out = injected_build
    files = sorted(out.glob("*.csv"))
    assert {f.name for f in files} >= {"parts_list.csv", "machining_roller.csv", "machining_nut.csv",
                                       "inspection.csv"}
    for f in files:
        comments, rows = _read_csv(f.read_bytes().decode("utf-8"))
        for line in comments:
            assert len(line.splitlines()) == 1, (f.name, line)
            for cell in _cells_after_separators(line, ",;\t"):
                start = cell.lstrip()
                assert not _begins(start, FORMULA + '"') or _is_number(start), (f.name, line)
        for row in rows:
            for field in row:
                # the machining sheets write a lone "-" for a flank no contact loads: no formula
                if _begins(field, DANGER) or _begins(field.lstrip(), FORMULA):
                    assert _is_number(field) or field == "-", (f.name, field)
                for cell in _cells_after_separators(field, ";\t"):
                    assert not _begins(cell.lstrip().lstrip('"'), FORMULA), (f.name, field)
    _, rows = _read_csv((out / "parts_list.csv").read_bytes().decode("utf-8"))
    table = [dict(zip(rows[0], r)) for r in rows[1:]]
    for part, name in names.items():
        field = table[ITEMS[part][0] - 1]["material"]
        assert field.replace("'", "") == name.replace("'", "").replace("\r", "\n")
        assert field.startswith("'") == _begins(name, DANGER)
    for part in ("roller", "nut"):
        comments, _ = _read_csv((out / f"machining_{part}.csv").read_bytes().decode("utf-8"))
        (tol,) = [c for c in comments if c.startswith("# tolerance: ")]
        assert tol.replace("'", "") == ("# tolerance: per flank from the design's [tolerances]: "
                                        + SOURCE.replace("\n", " ")).replace("'", "")


def test_build_xlsx_cells_are_strings_never_formulas(injected_build):
    from openpyxl import load_workbook
    from openpyxl.utils.escape import unescape

    from prs_geom.exports.bom import read_parts_list_xlsx

    names, out = injected_build
    for f in ("parts_list.xlsx", "machining.xlsx"):
        wb = load_workbook(out / f)
        for ws in wb.worksheets:
            for row in ws.iter_rows():
                for cell in row:
                    assert cell.data_type != "f", (f, ws.title, cell.coordinate, cell.value)
                    if isinstance(cell.value, str):
                        assert cell.data_type == "s", (f, ws.title, cell.coordinate)
    rows = read_parts_list_xlsx(out / "parts_list.xlsx")
    for part, name in names.items():
        value = rows[ITEMS[part][0] - 1]["material"]
        assert unescape(value) == name                 # what a spreadsheet shows
        if "\r" not in name:
            assert value == name                       # and, read by openpyxl, the text itself
    summary = load_workbook(out / "machining.xlsx")["summary"]
    tolerance = [r for r in summary.iter_rows(values_only=True) if r[0] == "tolerance"][0]
    assert set(tolerance[1:3]) == {"per flank from the design's [tolerances]: " + SOURCE}


def _dxf_texts(path: Path) -> list[str]:
    """Plain text of every TEXT and MTEXT entity of a drawing (layouts and blocks)."""
    import ezdxf

    doc = ezdxf.readfile(path)
    spaces = list(doc.layouts) + list(doc.blocks)
    return [e.plain_text() for space in spaces for e in space.query("TEXT MTEXT")]


def test_build_drawings_show_the_text_literally(injected_build):
    names, out = injected_build
    carrier = _dxf_texts(out / "drawing_carrier.dxf")
    assert f"Material: {_shown(names['carrier'])}" in carrier
    assert "Design: small" in carrier
    assert any(t.startswith("\u00d8") for t in carrier)          # the drawing's own %%c still a diameter
    for f in ("drawing_nut_end.dxf", "drawing_assembly.dxf"):
        assert f"Material: {_shown(names['nut'])}" in _dxf_texts(out / f)
    notes = _squash(" ".join(_dxf_texts(out / "drawing_assembly.dxf")))
    for part, name in names.items():
        item, label, qty = ITEMS[part]
        assert _squash(f"{item} {label} {qty} {_shown(name)}") in notes


def test_build_pdf_draws_the_text_literally(injected_build, tmp_path, monkeypatch):
    """drawings.pdf holds the texts as glyph outlines (ezdxf's font engine), no text layer and
    no matplotlib text: the strings checked are those ezdxf turns into outlines when the
    build's drawings are rendered to a PDF again."""
    import ezdxf
    from ezdxf.addons.drawing.unified_text_renderer import UnifiedTextRenderer

    from prs_geom.exports.drawing import render_pdf

    names, out = injected_build
    assert (out / "drawings.pdf").read_bytes().startswith(b"%PDF")
    drawn: list[str] = []
    original = UnifiedTextRenderer.get_text_glyph_paths

    def record(self, text, *args, **kwargs):
        drawn.append(text)
        return original(self, text, *args, **kwargs)

    monkeypatch.setattr(UnifiedTextRenderer, "get_text_glyph_paths", record)
    docs = [ezdxf.readfile(out / f) for f in ("drawing_carrier.dxf", "drawing_assembly.dxf")]
    render_pdf(docs, tmp_path / "drawings.pdf")
    assert f"Material: {_shown(names['carrier'])}" in drawn
    assert f"Material: {_shown(names['nut'])}" in drawn
    page = _squash(" ".join(drawn))
    for name in names.values():
        assert _squash(_shown(name)) in page


def test_build_pdf_text_layer(injected_build):
    pypdf = pytest.importorskip("pypdf", reason="pypdf is not installed in the venv; the PDF's texts "
                                                "are checked as the strings it draws (test above)")
    names, out = injected_build
    text = "".join(page.extract_text() for page in pypdf.PdfReader(out / "drawings.pdf").pages)
    if not text.strip():
        pytest.skip("drawings.pdf draws its texts as glyph outlines: it has no text layer to read")
    for name in names.values():
        assert _squash(_shown(name)) in _squash(text)


def test_build_report_html_escapes_the_text(injected_build):
    names, out = injected_build
    page = (out / "report.html").read_bytes().decode("utf-8")      # CR kept as written
    assert "<script>alert" not in page
    for name in names.values():
        assert html.escape(name) in page


# --------------------------------------------------------------------------- harmonic
def test_harmonic_ratio_table_neutralises_text():
    from prs_geom.harmonic.exports import ratio_table_csv

    table = [{"a_mm": 42.0, "ratio": -19.5, "note": text} for text in INJECTIONS]
    header, *rows = list(csv.reader(io.StringIO(ratio_table_csv(table), newline="")))
    assert header == ["a_mm", "ratio", "note"]
    for row, text in zip(rows, INJECTIONS):
        assert row[:2] == ["42.0", "-19.5"]
        assert row[2] == csv_field(text)
        assert not _begins(row[2], DANGER)


def test_harmonic_build_writes_its_name_literally(tmp_path):
    """The harmonic design's one free text is its name, which validation keeps to file-name
    characters (test above); forced past validation, its writers still write it as text."""
    from prs_geom.harmonic.model import HarmonicDesign, HarmonicMesh
    from prs_geom.pipeline import build

    # the report schema (checked on every build of the suite, tests/conftest.py) refuses such a
    # name as the invalid design name it is: the build itself is run unchecked
    build = getattr(build, "__wrapped__", build)
    design = HarmonicDesign(mesh=HarmonicMesh(chord_tolerance_mm=0.1))
    hostile = "=HYPERLINK(\"http://evil.example/x\",\"click\") %%c ^J $\\frac{1}{2}$ <script>alert(1)</script>"
    object.__setattr__(design, "name", hostile)
    out = tmp_path / "harmonic"
    build(design, out)
    header, *rows = list(csv.reader(io.StringIO((out / "ratio_table.csv").read_text(encoding="utf-8"),
                                                newline="")))
    words = {"it_grade": lambda f: f == "" or re.fullmatch(r"IT(01|0|[1-9]|1[0-3])", f),
             "hertz_valid": lambda f: f in ("True", "False")}
    assert rows and all(words.get(h, _is_number)(f) for row in rows for h, f in zip(header, row))
    assert not any(_begins(f, DANGER) for f in header)
    texts = _dxf_texts(out / "axial_sections.dxf")
    assert any(t.startswith(hostile + ": harmonic friction drive") for t in texts)
    page = (out / "report.html").read_text(encoding="utf-8")
    assert "<script>alert" not in page and html.escape(hostile) in page


def test_sweep_csv_neutralises_text():
    from prs_geom.sweep import SweepResult, Column

    result = SweepResult("small", 1000.0, (1.0,), (Column("point", "-", ""), Column("x", "mm", ""),
                                                    Column("reason", "-", "")),
                         tuple((k, -0.5, text) for k, text in enumerate(INJECTIONS)))
    header, *rows = list(csv.reader(io.StringIO(result.csv_text(), newline="")))
    for row, text in zip(rows, INJECTIONS):
        assert row[1] == "-0.5" and row[2] == csv_field(text)
        assert not _begins(row[2], DANGER)


def test_parts_list_writers_without_a_build(tmp_path):
    """The parts-list writers on their own: every free-text field of a row neutralised."""
    from openpyxl import load_workbook

    from prs_geom.exports.bom import PartsListRow, parts_list_csv, write_parts_list_xlsx

    rows = [PartsListRow(k + 1, "screw", 1, text, 7850.0, -1.0, text, text) for k, text in enumerate(INJECTIONS)]
    _, table = _read_csv(parts_list_csv(rows, "small"))
    for row, text in zip(table[1:], INJECTIONS):
        for field in (row[3], row[8], row[9]):
            assert field == csv_field(text)
        assert row[5] == "-1.0"
    write_parts_list_xlsx(rows, tmp_path / "p.xlsx", "small")
    ws = load_workbook(tmp_path / "p.xlsx").active
    assert all(c.data_type != "f" for row in ws.iter_rows() for c in row)
    assert {c.value for row in ws.iter_rows() for c in row if c.column == 4} >= {xlsx_value(t) for t in INJECTIONS}


def test_design_with_hostile_materials_round_trips_through_its_file(tmp_path):
    """The design file of a build holds the names as written (design.toml is data, not a
    deliverable for a spreadsheet)."""
    from prs_geom.model.io import load_design, save_design

    design = PRSDesign(materials=Materials(**{p: Material(name=n) for p, n in zip(PARTS, INJECTIONS)}))
    save_design(design, tmp_path / "d.toml")
    assert load_design(tmp_path / "d.toml") == design
