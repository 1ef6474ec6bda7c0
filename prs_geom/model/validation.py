"""Validators of design values, shared by every design model (PRS and harmonic).

Each takes the field path as the user wrote it and the value, returns the value in its
canonical type, or raises :class:`~prs_geom.model.errors.DesignError` naming the field, the
value as written and the rule.
"""
from __future__ import annotations

import math
import re
from typing import Any, Callable

from prs_geom.model.errors import DesignError, format_value

__all__ = ["LOAD_RANGE_N", "MAX_LENGTH_MM", "MAX_SIZE_MM", "MIN_SIZE_MM", "NAME_RE", "bounded", "check_name", "choice",
           "force", "integer", "length", "optional_force", "optional_length", "optional_positive", "optional_size",
           "pitch_list", "positive", "real", "size"]

#: Allowed design names (they name output folders).
NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")
#: Largest accepted size (mm) of a diameter, radius or pitch: a sanity bound, since a
#: value above 10 m is a unit mistake (lengths are in mm), and the geometry code needs
#: finite, representable sizes.
MAX_SIZE_MM = 1e4
#: Smallest accepted size (mm) of a diameter, radius, pitch, width or thickness: 10 um, below
#: any machined feature. The model rounds defaulted diameters to 0.1 um, so a smaller size
#: vanishes in that rounding (a thread of pitch 1e-5 mm gets crest = root), and the contact,
#: tooth and body formulas divide by sizes (a size of 5e-324 mm underflows to zero there).
MIN_SIZE_MM = 1e-2
#: Largest accepted length along the axis (mm): 10 km, a thousand times the longest rolling
#: screws made. Physical lengths are the business of the plausibility warnings (above 12 m)
#: and, for meshing, of the memory guard (exit 3 naming the field, far shorter); this bound
#: keeps the ratings that need no mesh (critical speed and buckling go as 1/L^2) finite and
#: nonzero, with a wide margin (1e308 mm overflowed L^2).
MAX_LENGTH_MM = 1e7
#: Accepted range (N) of an axial force (design load, preload, duty loads). Below 1 N the
#: elastic approach of the teeth is nanometres (the load model's Newton system loses its
#: conditioning at about 1e-2 N on the standard design, and micrometre pitch corrections
#: decide everything). 1e10 N is a thousand times the largest plausible load (validate warns
#: above 1e7 N): an absurd load still gets its verdicts (static safety, buckling FAIL) rather
#: than a refusal, and the life ((C / F)^3, 1e308 N made it 0 and the gain 0 / 0) and the Hertz
#: pressures stay finite for any design.
LOAD_RANGE_N = (1.0, 1e10)


def real(fld: str, value: Any) -> float:
    """A finite number (int or float, not bool)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise DesignError(fld, value, "must be a number")
    v = float(value)
    if not math.isfinite(v):
        raise DesignError(fld, value, "must be a finite number")
    return v


def positive(fld: str, value: Any) -> float:
    """A finite number > 0."""
    v = real(fld, value)
    if v <= 0.0:
        raise DesignError(fld, value, "must be > 0")
    return v


def bounded(fld: str, value: Any, lo: float, hi: float, rule: str,
            number: Callable[[str, Any], float] = real) -> float:
    """``number(fld, value)`` (a finite number, by default) in the closed range [lo, hi];
    ``rule`` is the message when it is outside."""
    v = number(fld, value)
    if not lo <= v <= hi:
        raise DesignError(fld, value, rule)
    return v


def integer(fld: str, value: Any, lo: int, hi: int) -> int:
    """A whole number in [lo, hi] (an int, not a float or bool)."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise DesignError(fld, value, f"must be a whole number from {lo} to {hi}")
    if not lo <= value <= hi:
        raise DesignError(fld, value, f"must be a whole number from {lo} to {hi}")
    return value


def choice(fld: str, value: Any, options: tuple[str, ...]) -> str:
    """One of ``options``."""
    if value not in options:
        raise DesignError(fld, value, "must be one of " + ", ".join(format_value(o) for o in options))
    return value


def size(fld: str, value: Any) -> float:
    """A size in mm from :data:`MIN_SIZE_MM` to :data:`MAX_SIZE_MM`."""
    v = positive(fld, value)
    if v > MAX_SIZE_MM:
        raise DesignError(fld, value, f"must be at most {MAX_SIZE_MM:g} mm (10 m; sizes are in mm)")
    if v < MIN_SIZE_MM:
        raise DesignError(fld, value, f"must be at least {MIN_SIZE_MM:g} mm (10 um; sizes are in mm)")
    return v


def length(fld: str, value: Any) -> float:
    """A length along the axis in mm, from :data:`MIN_SIZE_MM` to :data:`MAX_LENGTH_MM`."""
    return bounded(fld, value, MIN_SIZE_MM, MAX_LENGTH_MM,
                   f"must be from {MIN_SIZE_MM:g} mm to {MAX_LENGTH_MM:g} mm (10 km; lengths are in mm)", positive)


def force(fld: str, value: Any) -> float:
    """An axial force in N within :data:`LOAD_RANGE_N`."""
    lo, hi = LOAD_RANGE_N
    return bounded(fld, value, lo, hi, f"must be from {lo:g} N to {hi:g} N (forces are in N)", positive)


def optional_positive(fld: str, value: Any) -> float | None:
    """None (not given: a default applies) or a positive number."""
    return None if value is None else positive(fld, value)


def optional_size(fld: str, value: Any) -> float | None:
    """None (not given: a default applies) or a size (:func:`size`)."""
    return None if value is None else size(fld, value)


def optional_length(fld: str, value: Any) -> float | None:
    """None (not given: a default applies) or a length along the axis (:func:`length`)."""
    return None if value is None else length(fld, value)


def optional_force(fld: str, value: Any) -> float | None:
    """None (not given: a default applies) or a force (:func:`force`)."""
    return None if value is None else force(fld, value)


def pitch_list(fld: str, value: Any) -> tuple[float, ...] | None:
    """None or a list of positive pitches (mm); items are named ``fld[k]`` in errors."""
    if value is None:
        return None
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__iter__"):
        raise DesignError(fld, value, "must be a list of pitches in mm")
    return tuple(positive(f"{fld}[{k}]", v) for k, v in enumerate(value))


def check_name(value: Any) -> str:
    """A design name: it names the output folder, so only safe file-name characters."""
    if not isinstance(value, str) or not NAME_RE.match(value):
        raise DesignError("name", value, "must be 1-64 characters of letters, digits, '_', '.', '-', "
                                         "starting with a letter or digit (it names the output folder)")
    return value
