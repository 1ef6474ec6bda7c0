"""Exceptions raised by prs_geom.

Every validation failure names what the user wrote (the dotted field path of the design
file with a list index where there is one, e.g. ``roller.pitch_list_mm[3]``, or the CLI
flag, e.g. ``--load``), the value as the user would write it (TOML spelling: ``2.0``,
``"left"``, ``[1, 2]``, never ``np.float64(2.0)``), and the rule it broke, so that a
designer can fix the file without reading the code.

Exit codes of the command line (docs/cli.md "Exit codes"): :class:`DesignError` and
:class:`OutputRefused` 2, :class:`EnvironmentFailure` 3,
:class:`ConvergenceError` and other analysis findings 1.
"""
from __future__ import annotations

import math
import numbers
from typing import Any

__all__ = ["SHOWN_FIELD_CHARS", "SHOWN_PREFIX_CHARS", "SHOWN_TEXT_CHARS", "SHOWN_VALUE_CHARS", "ConvergenceError",
           "DesignError", "DesignWarning", "EnvironmentFailure", "OutputRefused", "PRSGeomError", "format_value",
           "key_name", "quote", "ResourceLimitError", "format_bytes"]


def quote(text: str) -> str:
    """A TOML basic string: quotes and backslashes escaped, every non-printable character
    (control characters, line separators) as \\uXXXX, so a message stays one line."""
    out = []
    for ch in text:
        if ch in '"\\':
            out.append("\\" + ch)
        elif not ch.isprintable():
            out.append(f"\\u{ord(ch):04X}" if ord(ch) <= 0xFFFF else f"\\U{ord(ch):08X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


_BARE_KEY = __import__("re").compile(r"^[A-Za-z0-9_-]+$")


#: A text value (or key) longer than this, in characters as quoted, is shown in messages by
#: its first :data:`SHOWN_PREFIX_CHARS` characters and its length, so that an error about a
#: 200 MB name stays one short line.
SHOWN_TEXT_CHARS = 80
SHOWN_PREFIX_CHARS = 40
#: A formatted value longer than this is cut (lists and tables show 8 entries, 2 levels deep).
SHOWN_VALUE_CHARS = 200
#: A field path longer than this is shown with its middle left out.
SHOWN_FIELD_CHARS = 160


def _quote_short(text: str, limit: int = SHOWN_TEXT_CHARS) -> str:
    """:func:`quote` of ``text``, or of its first :data:`SHOWN_PREFIX_CHARS` characters (fewer
    when they need escapes) followed by ``... (N characters)`` when the quoted text would be
    longer than ``limit``. Only the shown part of a long text is looked at."""
    head = quote(text[:limit + 1])
    if len(text) <= limit and len(head) <= limit + 2:
        return head
    shown = []
    used = 0
    for ch in text[:SHOWN_PREFIX_CHARS]:
        q = quote(ch)[1:-1]
        if used + len(q) > SHOWN_PREFIX_CHARS:
            break
        shown.append(q)
        used += len(q)
    return '"' + "".join(shown) + f'"... ({len(text)} characters)'


def key_name(key: Any) -> str:
    """A design-file key as TOML spells it: bare when it can be, else quoted (a long key by
    its first characters and its length)."""
    key = str(key)
    if len(key) <= SHOWN_TEXT_CHARS and _BARE_KEY.match(key):
        return key
    return _quote_short(key)


def _format_int(value: int) -> str:
    bits = abs(value).bit_length()
    if bits <= 200:  # up to 61 digits: written out
        return str(value)
    return f"(a {'negative ' if value < 0 else ''}whole number of about {int(bits * math.log10(2)) + 1} digits)"


def format_value(value: Any) -> str:
    """``value`` spelled as a user writes it in a TOML design file or on the command line.

    Long values are shortened, so a message stays one short line whatever the file held:
    text longer than :data:`SHOWN_TEXT_CHARS` characters by its first characters and its
    length, huge whole numbers by their number of digits, lists and tables by their first 8
    entries and 2 levels deep, and the whole at most :data:`SHOWN_VALUE_CHARS` characters.
    """
    shown = _format(value, 0)
    if len(shown) > SHOWN_VALUE_CHARS:
        shown = shown[:SHOWN_VALUE_CHARS - 4] + " ..."
    return shown


def _format(value: Any, depth: int) -> str:
    if value is None:
        return "(not set)"
    if isinstance(value, (bool,)) or type(value).__name__ == "bool_":
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):
        return _format_int(int(value))
    if isinstance(value, numbers.Real):
        v = float(value)
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(value, str):
        return _quote_short(value)
    if isinstance(value, bytes):
        return repr(value[:SHOWN_PREFIX_CHARS]) + (f"... ({len(value)} bytes)"
                                                     if len(value) > SHOWN_PREFIX_CHARS else "")
    if isinstance(value, dict):
        if depth >= 2:
            return "{...}" if value else "{}"
        items = list(value.items())
        shown = ", ".join(f"{key_name(k)} = {_format(v, depth + 1)}" for k, v in items[:8])
        return "{" + shown + (f", ... ({len(items)} entries)" if len(items) > 8 else "") + "}"
    if hasattr(value, "__iter__"):
        items = list(value)
        if depth >= 2:
            return "[...]" if items else "[]"
        shown = ", ".join(_format(v, depth + 1) for v in items[:8])
        return "[" + shown + (f", ... ({len(items)} entries)" if len(items) > 8 else "") + "]"
    text = str(value)
    return text if len(text) <= SHOWN_TEXT_CHARS else text[:SHOWN_PREFIX_CHARS] + f"... ({len(text)} characters)"


def _short_field(field: str) -> str:
    """A field path for a message: a very long one with its middle left out."""
    if len(field) <= SHOWN_FIELD_CHARS:
        return field
    half = SHOWN_FIELD_CHARS // 2 - 3
    return field[:half] + " ... " + field[-half:]


class PRSGeomError(Exception):
    """Base class of all errors raised on purpose by prs_geom.

    Examples
    --------
    Every error the package raises on purpose is one of these, so one ``except`` tells
    them from a bug:

    >>> import prs_geom as pg
    >>> from prs_geom.model.design import Roller
    >>> try:
    ...     pg.PRSDesign(roller=Roller(count=0))
    ... except pg.PRSGeomError as err:
    ...     print(type(err).__name__)
    DesignError
    """


class DesignError(PRSGeomError, ValueError):
    """An invalid design value.

    Parameters
    ----------
    field : str
        Dotted path of the field as the user wrote it, e.g. ``"roller.pitch_diameter_mm"``
        or ``"roller.pitch_list_mm[3]"``, or a CLI flag such as ``"--load"``.
    value : Any
        The value that was given.
    rule : str
        The rule the value breaks, in words a designer understands.
    note : str, optional
        Where the value came from when the user did not write it (a default derived from
        other fields): printed after the value.

    Examples
    --------
    >>> import prs_geom as pg
    >>> from prs_geom.model.design import Roller
    >>> try:
    ...     pg.PRSDesign(roller=Roller(count=0))
    ... except pg.DesignError as err:
    ...     print(err.field, err.value, "|", err.rule)
    count 0 | must be a whole number from 1 to 60
    """

    def __init__(self, field: str, value: Any, rule: str, note: str = "") -> None:
        self.field = field
        self.value = value
        self.rule = rule
        self.note = note
        shown = format_value(value)
        super().__init__(f"{_short_field(field)} = {shown}{f' ({note})' if note else ''}: {rule}")

    @classmethod
    def about_file(cls, path: str, problem: str, what: str = "design file") -> "DesignError":
        """An error about a whole input file (kind, size, encoding, syntax):
        ``design file 'PATH': problem`` (``what`` names the kind of file)."""
        err = cls(f"{what} {path!r}", path, problem)
        err.args = (f"{what} {path!r}: {problem}",)
        return err

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else super().__str__()

    def __reduce__(self):
        # a build's background workers send their errors back pickled (prs_geom.runtime.pool)
        return _rebuild_design_error, (self.field, self.value, self.rule, self.note, self.args)

    def prefixed(self, section: str) -> "DesignError":
        """The same error with ``section.`` put before the field path."""
        return DesignError(f"{section}.{self.field}" if section else self.field, self.value, self.rule,
                           self.note)

    def renamed(self, field: str) -> "DesignError":
        """The same error reported under another name (e.g. the CLI flag that set it)."""
        return DesignError(field, self.value, self.rule, self.note)


def _rebuild_design_error(field: str, value: Any, rule: str, note: str, args: tuple) -> DesignError:
    err = DesignError(field, value, rule, note)
    err.args = args
    return err


class OutputRefused(PRSGeomError):
    """An output path holds something prs-geom did not write (exit code 2); nothing was
    touched.

    Examples
    --------
    >>> import os, prs_geom as pg
    >>> os.makedirs("notes", exist_ok=True)
    >>> with open("notes/todo.txt", "w") as f:
    ...     _ = f.write("mine")
    >>> try:
    ...     pg.build(pg.default_design(), "notes")
    ... except pg.OutputRefused as err:
    ...     print("refused:", "todo.txt" in str(err))
    refused: True
    >>> open("notes/todo.txt").read()
    'mine'
    """


class ResourceLimitError(PRSGeomError):
    """A job does not fit the memory budget (exit code 3): refused up front when its
    estimated peak exceeds the budget (:func:`prs_geom.mesh.budget.guard`), or stopped when
    its resident memory passes it while running (:mod:`prs_geom.runtime.memwatch`). Nothing
    was written."""


def format_bytes(n: float) -> str:
    """A byte count for a message: ``1.5 GB``, ``412.2 MB``, ``12.0 kB``, ``512 B`` (binary
    multiples, one decimal; three significant digits past 1e5 of a unit)."""
    for unit, scale in (("GB", 2 ** 30), ("MB", 2 ** 20), ("kB", 2 ** 10)):
        if n >= scale:
            v = n / scale
            return f"{v:.1f} {unit}" if v < 1e5 else f"{v:.3g} {unit}"
    return f"{n:.0f} B"


class ConvergenceError(PRSGeomError, RuntimeError):
    """A numerical solver did not converge; no numbers are returned.

    Examples
    --------
    A caller that wants numbers or nothing catches it like any runtime error:

    >>> import prs_geom as pg
    >>> issubclass(pg.ConvergenceError, RuntimeError), issubclass(pg.ConvergenceError, pg.PRSGeomError)
    (True, True)
    """


class EnvironmentFailure(PRSGeomError):
    """The machine cannot do what was asked: a path that cannot be read or written
    (permission, disk full, missing folder) or a missing optional extra (exit code 3).

    The message names the path (or the extra and its install command) and the reason.

    Examples
    --------
    >>> import prs_geom as pg
    >>> with open("a-file", "w") as f:
    ...     _ = f.write("x")
    >>> try:
    ...     pg.build(pg.default_design(), "a-file/out")
    ... except pg.EnvironmentFailure as err:
    ...     print(str(err).startswith("cannot write"))
    True
    """


class DesignWarning(UserWarning):
    """A standard-sizing relation of docs/theory/geometry.md is broken (allowed on purpose).

    Examples
    --------
    >>> import warnings, prs_geom as pg
    >>> from prs_geom.model.design import Nut
    >>> design = pg.PRSDesign(nut=Nut(starts=4))
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     messages = design.warn()
    >>> [w.category.__name__ for w in caught]
    ['DesignWarning', 'DesignWarning']
    >>> messages[1]
    'screw starts 5 != nut starts 4'
    """
