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


def key_name(key: Any) -> str:
    """A design-file key as TOML spells it: bare when it can be, else quoted."""
    key = str(key)
    return key if _BARE_KEY.match(key) else quote(key)


def format_value(value: Any) -> str:
    """``value`` spelled as a user writes it in a TOML design file or on the command line."""
    if value is None:
        return "(not set)"
    if isinstance(value, (bool,)) or type(value).__name__ == "bool_":
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        v = float(value)
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(value, str):
        return quote(value)
    if isinstance(value, bytes):
        return repr(value)
    if isinstance(value, dict):
        return "{" + ", ".join(f"{key_name(k)} = {format_value(v)}" for k, v in value.items()) + "}"
    if hasattr(value, "__iter__"):
        items = list(value)
        shown = ", ".join(format_value(v) for v in items[:8])
        return "[" + shown + (f", ... ({len(items)} entries)" if len(items) > 8 else "") + "]"
    return str(value)


class PRSGeomError(Exception):
    """Base class of all errors raised on purpose by prs_geom."""


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
    """

    def __init__(self, field: str, value: Any, rule: str, note: str = "") -> None:
        self.field = field
        self.value = value
        self.rule = rule
        self.note = note
        shown = format_value(value)
        super().__init__(f"{field} = {shown}{f' ({note})' if note else ''}: {rule}")

    @classmethod
    def about_file(cls, path: str, problem: str) -> "DesignError":
        """An error about a whole input file (encoding, syntax): ``design file 'PATH': problem``."""
        err = cls(f"design file {path!r}", path, problem)
        err.args = (f"design file {path!r}: {problem}",)
        return err

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else super().__str__()

    def __reduce__(self):
        # a build's background workers send their errors back pickled (prs_geom.background)
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
    touched."""


class ConvergenceError(PRSGeomError, RuntimeError):
    """A numerical solver did not converge; no numbers are returned."""


class EnvironmentFailure(PRSGeomError):
    """The machine cannot do what was asked: a path that cannot be read or written
    (permission, disk full, missing folder) or a missing optional extra (exit code 3).

    The message names the path (or the extra and its install command) and the reason.
    """


class DesignWarning(UserWarning):
    """A standard-sizing relation of docs/theory/geometry.md is broken (allowed on purpose)."""
