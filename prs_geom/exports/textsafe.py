"""Design text written into shop files, shown as the text it is: never a formula, never a code.

A design file can come from outside, and its free text reaches the deliverables: the design
``name`` (parts list titles, drawings), ``materials.<part>.name`` (parts list, drawings) and
``tolerances.source`` (machining sheets). Validation leaves the free text free (a material
may be called anything up to 60 characters; the design name is restricted to file-name
characters by :func:`prs_geom.model.validation.check_name`), so each writer passes user text
through the function of its format here. Only user text goes through them: the numbers keep
their own formatting and the project's own codes (the ``%%c`` diameter sign of the drawings)
keep working.

CSV (:func:`csv_field`, :func:`csv_comment`)
    The rule is OWASP's "CSV Injection" (https://owasp.org/www-community/attacks/CSV_Injection):
    a spreadsheet (Excel, LibreOffice Calc) reads a cell that begins with ``=`` as a formula,
    and no cell may begin with ``=``, ``+``, ``-``, ``@``, TAB, CR or LF; a single quote
    ``'`` in front of the cell makes the spreadsheet read it as text. OWASP adds that a field
    separator or a quote inside the text can start a new cell in the middle of it. So:

    * a CR (alone or in CR LF) in a text field becomes a LF: the project's CSV files end
      their lines with LF, so the ``csv`` module quotes a field holding a LF but would write
      a lone CR unquoted, and readers end the row there (a new row that could begin with a
      formula);
    * a text field gets the ``'`` prefix when its first character is one of ``= + - @``, TAB,
      CR or LF, or when its first character that is not white space is one of ``= + - @``
      (decided here: spreadsheets that trim the cells on import would otherwise see the
      formula). A text that is a plain decimal number (``-0.5``, ``+3``, ``1e-06``) is left
      alone: a spreadsheet reads it as that number, never as a formula;
    * inside a field, after a ``;`` or a TAB (separators that spreadsheets guess in many
      locales, and which the ``csv`` module does not quote), a ``'`` is inserted when what
      follows (after white space and double quotes) begins with ``= + - @``. A ``,``, a
      ``"`` or a LF makes the ``csv`` module quote the whole field, and a quoted field is
      one cell whatever separator the spreadsheet picks, so those need nothing;
    * text inside a ``#`` comment line (:func:`csv_comment`) is not quoted at all: its line
      breaks become spaces (a comment is one line; readers split lines as
      :meth:`str.splitlines` does), and after every ``,``, ``;`` or TAB a ``'`` is inserted
      when what follows (after white space) begins with ``= + - @`` or a double quote (a cell
      beginning with ``"`` would be read as a quoted cell running on into the next lines).

    Numbers never pass through these functions; a non-text value is returned unchanged.

XLSX (:func:`xlsx_text`, :func:`xlsx_append`, :func:`xlsx_header_text`)
    openpyxl stores a Python string that begins with ``=`` as a formula. User text is
    assigned and then marked as a string (``cell.data_type = "s"``), so the cell holds the
    exact text and nothing is evaluated; no ``'`` is added. XML 1.0 cannot carry most
    control characters (openpyxl refuses them) and turns a CR into a LF on reading, so
    those characters, U+FFFE and U+FFFF are written in the spreadsheet's own escape
    ``_xHHHH_`` (ECMA-376 ``ST_Xstring``, which Excel shows as the character), and a
    literal ``_xHHHH_`` in the text has its underscore escaped (``_x005F_``) so that it is
    shown as typed. TAB and LF are kept as they are. In page headers and footers ``&``
    starts a code, so :func:`xlsx_header_text` doubles it (``&&`` prints one ``&``).

DXF (:func:`dxf_text`, :func:`dxf_wrap`)
    Rules as ezdxf implements them (``ezdxf.tools.text.plain_text``, ``caret_decode``,
    ``fast_plain_mtext`` and ``MTextParser``; ezdxf's TEXT and MTEXT documentation), which
    follow AutoCAD:

    * TEXT: ``%%c``, ``%%d``, ``%%p`` are the diameter, degree and plus-minus signs,
      ``%%u``, ``%%o``, ``%%k`` toggle under-, over- and strike-through lines, ``%%nnn`` a
      character code and ``%%%`` a single percent sign; so every ``%`` of user text is
      written ``%%%``. DXF strings use caret notation (``^J`` is a line feed, ``^I`` a
      TAB) and ``^`` followed by a space is a literal caret; so every ``^`` is written ``^ ``.
      A TEXT entity is one line: ezdxf drops CR and LF from it and draws the other control
      characters as ``?``, so the control characters U+0000-U+001F and U+007F are written as
      their Unicode control pictures (U+2400-U+241F, U+2421: ``␉`` for TAB, ``␍`` for CR,
      ``␊`` for LF), which show that the character is there.
    * MTEXT (``mtext=True``) in addition: ``\\`` starts an inline code (``\\P`` new
      paragraph, ``\\~`` no-break space, ``\\H2;`` height...) and ``{`` ``}`` group codes, so
      they are written ``\\\\``, ``\\{``, ``\\}``; a line break (LF, CR LF or CR) is written
      ``\\P`` and a TAB ``^I``, both shown as what they are; the other control characters
      become control pictures as for TEXT.

    :func:`dxf_wrap` wraps a line of drawing text as :func:`textwrap.wrap` does, but never
    inside a ``%%x`` or ``^x`` sequence, which the escapes above contain, nor right after a
    literal caret: ezdxf (not AutoCAD) drops a ``^`` that ends a TEXT line, so a user text
    that itself ends with ``^`` at the end of a TEXT entity loses that caret in ezdxf's
    reading and in the PDF drawn from it.

PDF
    ``drawings.pdf`` is drawn from the DXF documents by ezdxf's drawing add-on: the plain text
    of each TEXT entity (as above) is turned into glyph outlines by ezdxf's own font engine
    and written as filled PDF paths (:mod:`prs_geom.exports.sheet_pdf`): the PDF holds no
    text strings, so nothing in it is parsed and a ``$...$`` is drawn as typed. Where user
    text goes into a matplotlib text (plot titles), :func:`mpl_text` escapes ``$``
    (matplotlib draws ``\\$`` as ``$`` and parses no mathtext in a string without an
    unescaped ``$``).

HTML
    report.html escapes every text with :func:`html.escape` (:mod:`prs_geom.exports.html`).
"""
from __future__ import annotations

import re
import textwrap
from typing import Any, Iterable

__all__ = ["FORMULA_STARTS", "csv_field", "csv_comment", "xlsx_value", "xlsx_text", "xlsx_append",
           "xlsx_header_text", "dxf_text", "dxf_wrap", "mpl_text"]

#: Characters that make a spreadsheet read a cell as a formula when they begin it.
FORMULA_STARTS = frozenset("=+-@")
#: Characters OWASP lists as dangerous at the beginning of a cell (FORMULA_STARTS, TAB, CR, LF).
CELL_STARTS = FORMULA_STARTS | frozenset("\t\r\n")
#: The prefix that makes a spreadsheet read the cell as text (OWASP).
TEXT_PREFIX = "'"
#: A plain decimal number: what a spreadsheet reads as a number, never as a formula.
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
_SPACE = re.compile(r"\s*")
_SPACE_OR_QUOTE = re.compile(r'[\s"]*')
#: The characters at which :meth:`str.splitlines` ends a line.
_LINE_BREAKS = "\n\r\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029"


def _guard_after(text: str, separators: str, dangerous: frozenset[str] | str) -> str:
    """``text`` with ``'`` inserted after every separator whose following text (after
    white space, and double quotes unless ``"`` itself is dangerous) begins with a dangerous
    character."""
    if not any(s in text for s in separators):
        return text
    skip = _SPACE if '"' in dangerous else _SPACE_OR_QUOTE
    out = []
    for i, ch in enumerate(text):
        out.append(ch)
        if ch in separators:
            start = skip.match(text, i + 1).end()
            if text[start:start + 1] and text[start] in dangerous:
                out.append(TEXT_PREFIX)
    return "".join(out)


def csv_field(value: Any) -> Any:
    """A CSV field holding user text, neutralised (module docstring, "CSV").

    >>> csv_field('=HYPERLINK("http://evil.example/x","click")')
    '\\'=HYPERLINK("http://evil.example/x","click")'
    >>> csv_field("-0.5"), csv_field(-0.5), csv_field("steel")
    ('-0.5', -0.5, 'steel')
    """
    if not isinstance(value, str) or not value:
        return value
    text = value.replace("\r\n", "\n").replace("\r", "\n") if "\r" in value else value
    text = _guard_after(text, ";\t", FORMULA_STARTS)
    first = text.lstrip()[:1]
    if text[0] in CELL_STARTS or (first and first in FORMULA_STARTS):
        if not _NUMBER.fullmatch(text):
            return TEXT_PREFIX + text
    return text


def csv_comment(text: str) -> str:
    """User text for the inside of a ``#`` comment line of a CSV file (module docstring):
    one line, and no cell of it begins a formula or a quoted cell.

    >>> csv_comment('x,=1+1\\n;"=2"')
    'x,\\'=1+1 ;\\'"=2"'
    """
    text = str(text)
    if any(c in text for c in _LINE_BREAKS):
        text = "".join(" " if c in _LINE_BREAKS else c for c in text)
    return _guard_after(text, ",;\t", FORMULA_STARTS | {'"'})


# --------------------------------------------------------------------------- XLSX
#: Characters XML 1.0 cannot hold (openpyxl refuses them), CR (read back as LF) and the
#: non-characters U+FFFE, U+FFFF: written as ``_xHHHH_``.
_XLSX_ESCAPED = re.compile("[\x00-\x08\x0b-\x0d\x0e-\x1f\ufffe\uffff]")
_XLSX_LITERAL_ESCAPE = re.compile(r"_(x[0-9A-Fa-f]{4}_)")


def xlsx_value(text: str) -> str:
    """The string to store in a worksheet cell so that a spreadsheet shows exactly ``text``
    (the ``_xHHHH_`` rules of the module docstring).

    >>> xlsx_value("a\\rb_x0041_")
    'a_x000D_b_x005F_x0041_'
    """
    text = _XLSX_LITERAL_ESCAPE.sub(r"_x005F_\1", text)
    return _XLSX_ESCAPED.sub(lambda m: f"_x{ord(m.group(0)):04X}_", text)


def xlsx_text(cell: Any, text: str) -> Any:
    """Store user ``text`` in the openpyxl ``cell`` as a string, never a formula; returns the
    cell."""
    cell.value = xlsx_value(text)
    cell.data_type = "s"
    return cell


def xlsx_append(ws: Any, values: Iterable[Any]) -> None:
    """``ws.append(values)`` with every string stored as text (:func:`xlsx_text`)."""
    values = list(values)
    ws.append([xlsx_value(v) if isinstance(v, str) else v for v in values])
    row = getattr(ws, "_current_row", ws.max_row)      # the row append() just wrote
    for c, v in enumerate(values, start=1):
        if isinstance(v, str) and v:
            ws.cell(row=row, column=c).data_type = "s"


def xlsx_header_text(text: str) -> str:
    """User text for a worksheet page header or footer: ``&`` (which starts a code such as
    ``&P``) doubled."""
    return str(text).replace("&", "&&")


# --------------------------------------------------------------------------- DXF
def _control_picture(ch: str) -> str:
    """The Unicode control picture of a C0 control character or DEL (U+2400 + code, U+2421)."""
    return "\u2421" if ch == "\x7f" else chr(0x2400 + ord(ch))


def dxf_text(text: str, mtext: bool = False) -> str:
    """User text for a DXF TEXT entity (``mtext=False``) or MTEXT content, escaped so that the
    drawing shows it literally (module docstring, "DXF").

    >>> dxf_text("%%c50^2")
    '%%%%%%c50^ 2'
    >>> dxf_text("\\\\P{x}", mtext=True)
    '\\\\\\\\P\\\\{x\\\\}'
    """
    out = []
    text = str(text)
    if mtext:
        text = text.replace("\r\n", "\n")
    for ch in text:
        if ch == "%":
            out.append("%%%")
        elif ch == "^":
            out.append("^ ")
        elif mtext and ch in "\\{}":
            out.append("\\" + ch)
        elif mtext and ch in "\n\r":
            out.append("\\P")
        elif mtext and ch == "\t":
            out.append("^I")
        elif ch < " " or ch == "\x7f":
            out.append(_control_picture(ch))
        else:
            out.append(ch)
    return "".join(out)


def _dxf_bounds(text: str) -> set[int]:
    """Indices of ``text`` at which a line may end: none cuts a ``%%x`` or ``^x`` sequence,
    and none follows a literal caret ``^ `` (ezdxf drops a caret that ends a line of TEXT)."""
    bounds, i, n = {0}, 0, len(text)
    while i < n:
        caret = False
        if text.startswith("%%", i) and i + 2 < n:
            i += 3
        elif text[i] == "^" and i + 1 < n:
            caret = text[i + 1] == " "
            i += 2
        else:
            i += 1
        if not caret or i == n:
            bounds.add(i)
    return bounds


class _DxfWrapper(textwrap.TextWrapper):
    """A :class:`textwrap.TextWrapper` whose breaks never cut a ``%%x`` or ``^x`` sequence;
    on text without those sequences it wraps exactly as the base class."""

    def _split(self, text: str) -> list[str]:
        bounds = _dxf_bounds(text)
        chunks: list[str] = []
        pos = 0
        for chunk in super()._split(text):
            if chunks and pos not in bounds:
                chunks[-1] += chunk          # keep "^" and the space after it together
            else:
                chunks.append(chunk)
            pos += len(chunk)
        return chunks

    def _handle_long_word(self, reversed_chunks: list[str], cur_line: list[str], cur_len: int,
                          width: int) -> None:
        if not self.break_long_words:
            super()._handle_long_word(reversed_chunks, cur_line, cur_len, width)
            return
        chunk = reversed_chunks[-1]
        room = max(1, width - cur_len)
        cut = room
        if self.break_on_hyphens and len(chunk) > room:
            hyphen = chunk.rfind("-", 0, room)
            if hyphen > 0 and chunk[:hyphen].strip("-"):
                cut = hyphen + 1
        bounds = sorted(b for b in _dxf_bounds(chunk) if b > 0)
        fitting = [b for b in bounds if b <= cut]
        cut = fitting[-1] if fitting else bounds[0]
        cur_line.append(chunk[:cut])
        reversed_chunks[-1] = chunk[cut:]


def dxf_wrap(text: str, width: int, subsequent_indent: str = "") -> list[str]:
    """:func:`textwrap.wrap` for DXF TEXT content holding escaped user text
    (:func:`dxf_text`): the same lines, but no break inside a ``%%x`` or ``^x`` sequence."""
    return _DxfWrapper(width=width, subsequent_indent=subsequent_indent).wrap(text)


# --------------------------------------------------------------------------- matplotlib
def mpl_text(text: str) -> str:
    """User text for a matplotlib text (title, label): every ``$`` escaped, so no mathtext
    is parsed and the text is drawn as typed.

    >>> mpl_text("$\\\\frac{1}{2}$")
    '\\\\$\\\\frac{1}{2}\\\\$'
    """
    return str(text).replace("$", "\\$")
