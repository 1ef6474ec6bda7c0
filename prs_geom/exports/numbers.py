"""Numbers for people: the one formatter of the HTML reports (``report.html`` of both
product lines).

:func:`format_quantity` turns a value into text with its unit; :func:`format_cell` is the
same without the unit (a table's column title carries it); :func:`exact` is the value's
full text (``repr`` of the float64), which the reports put in a ``title`` attribute so the
exact number stays one hover away. Pure text, no HTML.

Which quantity a value is
-------------------------
The quantity fixes the unit and the precision. In this order:

1. ``unit`` and ``precision`` given by the caller;
2. the annotations of the report schema (``prs_geom/exports/schemas/report.schema.json``)
   for ``key``: ``"x-unit"`` (a unit, e.g. ``"N m"``) and ``"x-precision"`` on a property
   (or on the definition it refers to). ``key`` is the value's path in report.json with
   dots (``"machining.nut.rows.designed_pitch_mm"``; array indices left out; a schema
   ``additionalProperties`` matches any name) or a bare key name, which takes the
   annotation when every property of that name in the schema carries the same one;
3. the key's unit suffix, case-insensitive (see :data:`SUFFIXES`): ``_mm`` mm, ``_um`` µm,
   ``_mm3`` mm³, ``_n`` N, ``_kn`` kN, ``_mpa`` MPa, ``_deg`` degree, ``_rad`` rad,
   ``_rpm`` rpm, ``_s`` s, ``_hours`` h, ``_revolutions`` rev, ``_k`` K, ``_degc`` °C,
   ``_kg`` kg, ``_kg_m3`` kg/m³, ``_pct`` %, ``_nm`` N m (a torque, not a nanometre),
   ``_n_per_um`` N/µm, ``_um_per_k`` µm/K, ``_per_k`` 1/K, ``_per_um`` 1/µm;
4. otherwise a dimensionless number (a ratio, an LDC, a factor).

``x-precision`` is either a resolution in the unit (a power of ten: ``1e-06`` prints mm to
the nanometre) or a string ``"N significant digits"``.

Precision of each quantity (:data:`QUANTITIES`)
-----------------------------------------------
* lengths in mm to 0.0001 mm (0.1 µm), fixed decimals; µm to 0.001 µm (pitch corrections
  of 0.01 to 0.5 µm per tooth stay visible); degrees to 0.0001°; rpm to 1 rpm; µm/K to
  0.001; °C and % to 0.1;
* forces (N, kN), pressures (MPa), torques, volumes (mm³), masses, densities, stiffness,
  hours: 4 significant digits but never coarser than 1 unit (20 000 N, 56 766 N, 12.35 N,
  0.5000 N);
* ratios, LDC and other dimensionless numbers, revolutions, seconds, rad, 1/K: 4
  significant digits;
* never more than 10 significant digits.

Fixed-decimal quantities always show their decimals (``8.0000 mm``, ``0.000 µm``), so
the precision can be read off the text.

Rules for every quantity
------------------------
* Rounded half to even at the precision (Python's float formatting). A value that rounds
  to zero prints as zero with no sign: ``-0.0`` µm is ``0.000 µm``, ``-1.75e-16`` mm is
  ``0.0000 mm``. Significant-digit quantities have a noise floor (:attr:`Quantity.zero`)
  below which they are zero too (-1.75e-16 mm³ is ``0 mm³``).
* Plain decimal, the integer part grouped by threes with a narrow no-break space (U+202F)
  from 10 000 up (ISO 80000-1): ``1 926 100 rpm``. Scientific notation ``1.926×10⁶`` only
  where plain decimal would print digits that are not significant or a run of leading
  zeros: a significant-digit quantity without a whole-unit floor at or above 10^digits
  (``2.287×10⁷ rev``), any such quantity below 0.001 (``1.895×10⁻⁵ mm³``), and any value
  from 10¹⁰ up.
* Booleans: ``yes`` / ``no``. ``None``, NaN and a missing value: an em dash ``—`` (never the
  words None or nan). Infinity: ``∞`` (``-∞``).
* Integers print as they are (grouped from 10 000 up), with the unit; text passes through.
* Units as people write them: ``µm`` (not um), ``mm³``, ``°`` (no space before it).
"""
from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from typing import Any

import numpy as np

__all__ = ["DASH", "INF", "TIMES", "GROUP", "MAX_DIGITS", "Quantity", "UNIT_LABELS", "QUANTITIES", "SUFFIXES",
           "unit_label", "key_label", "quantity", "format_cell", "format_quantity", "exact"]

DASH = "\u2014"          # em dash: no value
INF = "\u221e"
TIMES = "\u00d7"
GROUP = "\u202f"         # narrow no-break space between digit groups
MAX_DIGITS = 10          # never more significant digits than this
_SUPERSCRIPT = str.maketrans("-0123456789", "\u207b\u2070\u00b9\u00b2\u00b3\u2074\u2075\u2076\u2077\u2078\u2079")


@dataclass(frozen=True)
class Quantity:
    """How a quantity prints: its unit label, digits after the point (``decimals``: fixed,
    or the floor when ``sig`` is given too), significant digits ``sig``, and ``zero``: the
    magnitude below which a significant-digit value is zero (noise)."""

    unit: str = ""
    decimals: int | None = None
    sig: int | None = 4
    zero: float = 1e-12


#: Unit labels as printed, by every spelling the reports use.
UNIT_LABELS = {"um": "µm", "µm": "µm", "μm": "µm", "mm3": "mm³", "mm^3": "mm³", "mm2": "mm²", "mm^2": "mm²",
               "deg": "°", "degree": "°", "degrees": "°", "degc": "°C", "mpa": "MPa", "gpa": "GPa", "n": "N",
               "kn": "kN", "nm": "N m", "n m": "N m", "n/um": "N/µm", "um/k": "µm/K", "1/k": "1/K", "per_k": "1/K",
               "1/um": "1/µm", "kg/m^3": "kg/m³", "kg/m3": "kg/m³", "hours": "h", "revolutions": "rev", "pct": "%",
               "k": "K"}

#: Precision of each unit (by its printed label); "" is a dimensionless number.
QUANTITIES: dict[str, Quantity] = {
    "mm": Quantity("mm", decimals=4, sig=None),
    "µm": Quantity("µm", decimals=3, sig=None),
    "°": Quantity("°", decimals=4, sig=None),
    "rpm": Quantity("rpm", decimals=0, sig=None),
    "µm/K": Quantity("µm/K", decimals=3, sig=None),
    "°C": Quantity("°C", decimals=1, sig=None),
    "%": Quantity("%", decimals=1, sig=None),
    "N": Quantity("N", decimals=0, zero=1e-9),
    "kN": Quantity("kN", decimals=0, zero=1e-12),
    "MPa": Quantity("MPa", decimals=0, zero=1e-9),
    "GPa": Quantity("GPa", decimals=0, zero=1e-12),
    "N m": Quantity("N m", decimals=0, zero=1e-12),
    "N/µm": Quantity("N/µm", decimals=0, zero=1e-9),
    "mm³": Quantity("mm³", decimals=0, zero=1e-9),
    "mm²": Quantity("mm²", decimals=0, zero=1e-9),
    "kg": Quantity("kg", decimals=0, zero=1e-12),
    "kg/m³": Quantity("kg/m³", decimals=0, zero=1e-9),
    "h": Quantity("h", decimals=0, zero=1e-9),
    "rev": Quantity("rev", zero=1e-9),
    "s": Quantity("s", zero=1e-12),
    "rad": Quantity("rad", zero=1e-15),
    "K": Quantity("K", zero=1e-12),
    "1/K": Quantity("1/K", zero=1e-20),
    "1/µm": Quantity("1/µm", zero=1e-20),
    "": Quantity("", zero=1e-12),
}

#: Key suffixes (lower case, longest first) and their units, where the schema annotates none.
SUFFIXES = (("_n_per_um", "N/µm"), ("_um_per_k", "µm/K"), ("_kg_m3", "kg/m³"), ("_per_um", "1/µm"),
            ("_per_k", "1/K"), ("_mm3", "mm³"), ("_mm2", "mm²"), ("_mm", "mm"), ("_um", "µm"), ("_kn", "kN"),
            ("_n", "N"), ("_mpa", "MPa"), ("_gpa", "GPa"), ("_degc", "°C"), ("_deg", "°"), ("_rad", "rad"),
            ("_rpm", "rpm"), ("_hours", "h"), ("_revolutions", "rev"), ("_s", "s"), ("_kg", "kg"), ("_k", "K"),
            ("_pct", "%"), ("_nm", "N m"))

_SIG = re.compile(r"^\s*(\d+)\s*(s|sig|significant|significant digits?)\s*$", re.I)


def unit_label(unit: str | None) -> str:
    """The printed label of a unit as the code spells it (``um`` -> ``µm``, ``deg`` -> ``°``,
    ``mm^3`` -> ``mm³``); unknown units pass through."""
    if not unit:
        return ""
    return UNIT_LABELS.get(unit.lower(), unit) if unit not in QUANTITIES else unit


def _unit_of_suffix(name: str) -> str | None:
    low = name.lower()
    for suffix, unit in SUFFIXES:
        if low.endswith(suffix):
            return unit
    return None


def key_label(key: str) -> str:
    """A column or row title from a report key: words, then the unit in parentheses
    (``measurement_correction_um`` -> ``measurement correction (µm)``)."""
    low = key.lower()
    for suffix, unit in SUFFIXES:
        if low.endswith(suffix) and len(key) > len(suffix):
            return f"{key[:-len(suffix)].replace('_', ' ')} ({unit})"
    return key.replace("_", " ")


# --------------------------------------------------------------------------- schema annotations
@lru_cache(maxsize=1)
def _annotations() -> tuple[dict[tuple[str, ...], dict[str, Any]], dict[str, dict[str, Any]]]:
    """The ``x-unit`` / ``x-precision`` annotations of the report schema: by path (tuple of
    property names, ``*`` for ``additionalProperties``) and by bare property name (names
    whose every property in the schema carries the same annotation)."""
    text = resources.files("prs_geom.exports.schemas").joinpath("report.schema.json").read_text(encoding="utf-8")
    root = json.loads(text)
    by_path: dict[tuple[str, ...], dict[str, Any]] = {}
    by_name: dict[str, set[str]] = {}

    def own(node: dict[str, Any]) -> dict[str, Any]:
        found = {k: node[k] for k in ("x-unit", "x-precision") if k in node}
        if "$ref" in node:
            found = {**own(_resolve(root, node["$ref"])), **found}
        return found

    def walk(node: Any, path: tuple[str, ...], depth: int) -> None:
        if not isinstance(node, dict) or depth > 40:
            return
        if "$ref" in node:
            walk(_resolve(root, node["$ref"]), path, depth + 1)
        for name, sub in (node.get("properties") or {}).items():
            if not isinstance(sub, dict):
                continue
            note = own(sub)
            by_name.setdefault(name, set()).add(json.dumps(note, sort_keys=True))
            if note:
                by_path[path + (name,)] = {**by_path.get(path + (name,), {}), **note}
            walk(sub, path + (name,), depth + 1)
        for key in ("additionalProperties", "items"):
            sub = node.get(key)
            if isinstance(sub, dict):
                nxt = path + ("*",) if key == "additionalProperties" else path
                note = own(sub)
                if note and nxt != path:
                    by_path[nxt] = {**by_path.get(nxt, {}), **note}
                walk(sub, nxt, depth + 1)
        for sub in (node.get("patternProperties") or {}).values():
            walk(sub, path + ("*",), depth + 1)
        for key in ("allOf", "anyOf", "oneOf", "prefixItems"):
            for sub in node.get(key) or []:
                walk(sub, path, depth + 1)
        for key in ("then", "else"):
            walk(node.get(key), path, depth + 1)

    walk(root, (), 0)
    names = {n: json.loads(next(iter(s))) for n, s in by_name.items() if len(s) == 1 and s != {"{}"}}
    return by_path, names


def _resolve(root: dict[str, Any], ref: str) -> dict[str, Any]:
    target: Any = root
    for part in ref.lstrip("#/").split("/"):
        target = target[part]
    return target


def _schema_note(key: str) -> dict[str, Any]:
    by_path, by_name = _annotations()
    parts = tuple(key.split("."))
    if len(parts) > 1:
        if parts in by_path:
            return by_path[parts]
        for path, note in by_path.items():
            if len(path) == len(parts) and all(p == "*" or p == q for p, q in zip(path, parts)):
                return note
    return by_name.get(parts[-1], {})


def _parse_precision(precision: Any, base: Quantity) -> Quantity:
    if precision is None:
        return base
    if isinstance(precision, str):
        m = _SIG.match(precision)
        if not m:
            raise ValueError(f"precision {precision!r}: a resolution (1e-06) or 'N significant digits'")
        return Quantity(base.unit, decimals=None, sig=int(m.group(1)), zero=base.zero)
    step = float(precision)
    if not step > 0:
        raise ValueError(f"precision {precision!r} must be a positive resolution")
    return Quantity(base.unit, decimals=max(0, round(-math.log10(step))), sig=None, zero=base.zero)


@lru_cache(maxsize=4096)
def quantity(unit: str | None = None, precision: Any = None, key: str | None = None) -> Quantity:
    """The :class:`Quantity` of a value: from ``unit`` / ``precision``, else the schema's
    annotations of ``key``, else its suffix (module docstring)."""
    note = _schema_note(key) if key else {}
    if unit is None:
        unit = note.get("x-unit")
    if unit is None and key:
        unit = _unit_of_suffix(key.rsplit(".", 1)[-1])
    label = unit_label(unit)
    base = QUANTITIES.get(label) or Quantity(label)
    return _parse_precision(precision if precision is not None else note.get("x-precision"), base)


# --------------------------------------------------------------------------- formatting
def _group(digits: str) -> str:
    """Group an unsigned integer string by threes from 10 000 up."""
    if len(digits) < 5:
        return digits
    head = len(digits) % 3 or 3
    return digits[:head] + "".join(GROUP + digits[i:i + 3] for i in range(head, len(digits), 3))


def _plain(x: float, d: int) -> str:
    s = f"{abs(x):.{d}f}"
    whole, _, frac = s.partition(".")
    out = _group(whole) + ("." + frac if frac else "")
    return ("-" + out) if x < 0 and s.strip("0.") else out


def _scientific(x: float, sig: int) -> str:
    m, e = f"{x:.{sig - 1}e}".split("e")
    return f"{m}{TIMES}10{str(int(e)).translate(_SUPERSCRIPT)}"


def _number(x: float, q: Quantity) -> str:
    """``x`` (finite) as text at the quantity's precision, without the unit."""
    if q.sig is None:                                    # fixed decimals
        d = q.decimals or 0
        if x == 0 or abs(x) < 0.5 * 10.0 ** -d:
            return f"{0:.{d}f}"
        e = math.floor(math.log10(abs(x)))
        if e >= MAX_DIGITS:
            return _scientific(x, MAX_DIGITS)
        return _plain(x, max(0, min(d, MAX_DIGITS - 1 - e)))
    if x == 0 or abs(x) < q.zero:
        return f"{0:.{q.decimals if q.decimals is not None else q.sig - 1}f}"
    e = int(f"{x:.{q.sig - 1}e}".rpartition("e")[2])        # decimal exponent after rounding
    if e >= MAX_DIGITS or e < -3 or (q.decimals is None and e >= q.sig):
        return _scientific(x, q.sig)
    d = q.sig - 1 - e
    if q.decimals is not None:
        d = max(d, q.decimals)
    return _plain(x, max(0, min(d, MAX_DIGITS - 1 - e)))


def _as_float(value: Any) -> float | None:
    """``value`` as a Python float when it is a real (non-integer, non-bool) number."""
    if isinstance(value, (float, np.floating)):      # np.float64 is a float: repr it as one
        return float(value)
    return None


def format_cell(value: Any, unit: str | None = None, *, precision: Any = None, key: str | None = None) -> str:
    """``value`` as a table cell shows it: the number at its quantity's precision, without
    the unit (the column title has it); see the module docstring for the rules. Lists and
    tuples are their items, comma-separated."""
    if value is None:
        return DASH
    if isinstance(value, str):
        return value
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    x = _as_float(value)
    if x is not None:
        if math.isnan(x):
            return DASH
        if math.isinf(x):
            return INF if x > 0 else "-" + INF
        return _number(x, quantity(unit, precision, key))
    if isinstance(value, (int, np.integer)):
        n = int(value)
        return ("-" if n < 0 else "") + _group(str(abs(n)))
    if isinstance(value, (list, tuple, np.ndarray)):
        return ", ".join(format_cell(v, unit, precision=precision, key=key) for v in value)
    return str(value)


def format_quantity(value: Any, unit: str | None = None, *, precision: Any = None, key: str | None = None) -> str:
    """``value`` as text with its unit (``23.8679 mm``, ``0.000 µm``, ``1 926 100 rpm``,
    ``7.5963°``, ``—`` for no value).

    Parameters
    ----------
    value : float, int, bool, None, str or a list of them
    unit : str, optional
        The unit as the code spells it (``"mm"``, ``"um"``, ``"N"``, ``"deg"``, ...); by
        default from ``key``.
    precision : float or str, optional
        A resolution in the unit (``1e-6``) or ``"N significant digits"``; by default the
        quantity's (module docstring).
    key : str, optional
        The value's key or dotted path in report.json: the schema's ``x-unit`` /
        ``x-precision`` annotations, else the key's unit suffix, say what it is.
    """
    text = format_cell(value, unit, precision=precision, key=key)
    if text == DASH or isinstance(value, (str, bool, np.bool_)):
        return text
    label = quantity(unit, precision, key).unit
    if not label:
        return text
    return text + label if label == "°" else f"{text} {label}"


def exact(value: Any) -> str | None:
    """The full text of a real number (``repr`` of the float64, reads back to the same
    double) for a tooltip; None for anything else (integers, text, booleans, None)."""
    x = _as_float(value)
    return None if x is None else repr(x)
