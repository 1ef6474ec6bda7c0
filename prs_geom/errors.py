"""Exceptions raised by prs_geom.

Every validation failure names the offending field (dotted path as it appears in a
design file), the value that was given, and the rule it broke, so that a designer can
fix the file without reading the code.
"""
from __future__ import annotations

from typing import Any


class PRSGeomError(Exception):
    """Base class of all errors raised on purpose by prs_geom."""


class DesignError(PRSGeomError, ValueError):
    """An invalid design value.

    Parameters
    ----------
    field : str
        Dotted path of the field, e.g. ``"roller.pitch_diameter_mm"``.
    value : Any
        The value that was given.
    rule : str
        The rule the value breaks, in words a designer understands.
    """

    def __init__(self, field: str, value: Any, rule: str) -> None:
        self.field = field
        self.value = value
        self.rule = rule
        super().__init__(f"{field} = {value!r}: {rule}")

    def prefixed(self, section: str) -> "DesignError":
        """The same error with ``section.`` put before the field path."""
        return DesignError(f"{section}.{self.field}" if section else self.field, self.value, self.rule)


class ConvergenceError(PRSGeomError, RuntimeError):
    """A numerical solver did not converge; no numbers are returned."""


class DesignWarning(UserWarning):
    """A standard-sizing relation of DOMAIN.md section 1 is broken (allowed on purpose)."""
