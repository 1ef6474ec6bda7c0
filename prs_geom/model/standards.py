"""Standard data tables: ISO 286 limits and fits, DIN 472 retaining rings for bores.

Owns published reference data that a designer looks up rather than computes, as plain
Python data (no file reading, no I/O), and the small functions that read it:

* ISO 286-1:2010 Table 1 (standard tolerance grades IT01, IT0 and IT1..IT13) and Tables 2 and 3
  (fundamental deviations of the holes F, G, H, JS, K, N and the shafts e, f, g, h, js, k,
  m, n, p), for nominal sizes over 0 up to and including 500 mm, the same numbers as the
  limit-deviation tables of ISO 286-2. :func:`tolerance_zone` turns a nominal size and a
  symbol such as ``"H7"`` or ``"g6"`` into limit deviations; :class:`Fit` pairs a hole and
  a shaft (``Fit.parse("H7/g6")``) and gives the clearance range.
* DIN 472 regular series (retaining rings, "circlips", for bores): ring and groove
  dimensions for bores d1 = 8..200 mm (:func:`din472_ring`, :func:`din472_sizes`).

Units are in every name: sizes in millimetres (``_mm``), ISO deviations and tolerance
grades in micrometres (``_um``).

Size-range convention (ISO 286-1, 5.1 and Table 1): a range "over a up to and including b"
holds every size D with a < D <= b, so 10 mm belongs to 6-10 and 10.001 mm to 10-18. The
first range is "up to and including 3". For the letters held here the standard has no
intermediate subdivisions below 500 mm (those exist for a-c and r-zc only), so the
thirteen main ranges are the whole table.

Sources (values typed here by hand from the published tables, each cross-checked):

* ISO 286-1:2010 Tables 1-3 / ISO 286-2:2010. Cross-checked against the ISO 286 data of
  github.com/Ralul/TI-84 ``ISO-286.py`` (IT01..IT18, the deviations e..p, the Delta
  table), against a second public ISO 286 data module (IT6..IT9 rows) and against the
  formula i = 0.45 D^(1/3) + 0.001 D (tests only). Disagreement found: that TI-84 file
  gives IT9 = 20 um for 3-6 mm; the standard (and the formula, 40 i = 29.6 um) says 30.
* DIN 472:2017-06 (an editorial revision of DIN 472:2011-10, per its foreword; the sizes
  go back to the 1981 edition, and the public sources below, which do not name the edition
  they copy, agree with each other except as noted). Ring data d1, s, d3, a, b, d5, d2
  from the FreeCAD Fasteners workbench table (github.com/shaise/FreeCAD_FastenersWB
  ``FsData/din472def.csv``), checked row by row for 8-18 mm against a circlip maker's
  catalogue page "Standard Internal Circlips: DIN 472 Metric" (vdocuments.mx copy of
  osl.ir/download/mechanics/standards/khar/din-472.pdf; it also prints m, n and the d2
  deviation), and against NopSCADlib ``vitamins/circlips.scad`` (12, 15, 19, 21, 28 mm),
  a DIN 472 table quoting fasteners.eu (16, 20, 22, 26, 32, 35, 42, 47 mm) and a public
  TypeScript circlip table (8-100 mm, 21 sizes, with t and n). Groove width m (min, H13)
  depends on s only (0.8 -> 0.9 ... 4 -> 4.15), as in every source. The edge distance n
  is the printed value for 8-18 mm and the 21 sizes of that table; it equals 3 t
  (t = (d2 - d1)/2, rounded to 0.1 mm) in every printed row here and in DIN 471:2011
  Table 1, and that relation fills the other rows (so n for d1 > 100 mm is derived, not
  read). Disagreements: FreeCAD gives d2 = 20.4 for d1 = 28 (three other sources and the
  neighbouring rows: 29.4, used) and d2 = 103.0 for d1 = 100 (the TypeScript table and
  the t = 1.75 of the 80-100 mm rows: 103.5, used); its d3 = 42.5 for d1 = 39 breaks the
  d3 - d2 step of its neighbours and nothing confirms it, so d3 is left out there. The
  TypeScript table gives s = 1.5 for d1 = 32; the other sources and its own m = 1.3 say
  s = 1.2 (used). The d2 deviation (lower 0) is held only where printed: +0.09 mm for
  d1 = 8-9, +0.11 mm for 10-18; elsewhere it is ``None``, not guessed. The mass per 1000
  pieces is not held: the one source seen for it (a Russian dealer's page) had garbled rows.
"""
from __future__ import annotations

import math
import re
from bisect import bisect_left
from dataclasses import dataclass
from typing import Any

from prs_geom.model.errors import DesignError

__all__ = ["DELTA_UM", "DIN472_TABLE", "FIT_KINDS", "GRADES", "HOLE_LETTERS", "HOLE_LOWER_DEVIATION_UM",
           "HOLE_UPPER_BASE_UM", "ISO286_TABLE", "IT_GRADES_UM", "SHAFT_LETTERS", "SHAFT_LOWER_DEVIATION_UM",
           "SHAFT_UPPER_DEVIATION_UM", "SIZE_RANGES_MM", "SIZE_RANGE_UPPER_MM", "Fit", "FitLimits", "RetainingRing",
           "StandardTableError", "ToleranceZone", "din472_ring", "din472_sizes", "nearest_sizes", "it_tolerance_um", "size_range_index",
           "size_range_mm", "tolerance_zone", "IT_FINEST_UM", "GRADE_NAMES", "it_tolerance_by_name_um",
           "finest_grade_at_least"]


class StandardTableError(DesignError):
    """A look-up that leaves a standard table: a size beyond its range, a symbol, grade or
    bore it does not hold. A design error (exit code 2, like every
    :class:`~prs_geom.model.errors.DesignError`, and a ``ValueError``); the message names
    the table, its range and the value that left it.

    Attributes
    ----------
    table : str
        The table, e.g. ``"ISO 286 tolerance grades"`` or ``"DIN 472"``.
    value : Any
        The value looked up.
    lo, hi : float or None
        The tabulated range of the value (mm) where the table has one.
    """

    def __init__(self, table: str, value: Any, message: str, lo: float | None = None,
                 hi: float | None = None) -> None:
        super().__init__(table, value, message)
        self.args = (message,)
        self.table, self.lo, self.hi = table, lo, hi


# --- ISO 286 ---------------------------------------------------------------------------

#: Upper ends (mm) of the ISO 286 nominal size ranges; range k is "over UPPER[k-1] up to
#: and including UPPER[k]", the first one "up to and including 3".
SIZE_RANGE_UPPER_MM: tuple[float, ...] = (3, 6, 10, 18, 30, 50, 80, 120, 180, 250, 315, 400, 500)
#: The ranges as (over, up to and including) pairs, mm.
SIZE_RANGES_MM: tuple[tuple[float, float], ...] = tuple(zip((0,) + SIZE_RANGE_UPPER_MM[:-1],
                                                            SIZE_RANGE_UPPER_MM))

#: ISO 286-1 Table 1: standard tolerance IT (um) per grade, one value per size range.
IT_GRADES_UM: dict[int, tuple[float, ...]] = {
    # IT1..IT4: the fine grades (gauges, and the harmonic drive's tolerance rule)
    1: (0.8, 1, 1, 1.2, 1.5, 1.5, 2, 2.5, 3.5, 4.5, 6, 7, 8),
    2: (1.2, 1.5, 1.5, 2, 2.5, 2.5, 3, 4, 5, 7, 8, 9, 10),
    3: (2, 2.5, 2.5, 3, 4, 4, 5, 6, 8, 10, 12, 13, 15),
    4: (3, 4, 4, 5, 6, 7, 8, 10, 12, 14, 16, 18, 20),
    5: (4, 5, 6, 8, 9, 11, 13, 15, 18, 20, 23, 25, 27),
    6: (6, 8, 9, 11, 13, 16, 19, 22, 25, 29, 32, 36, 40),
    7: (10, 12, 15, 18, 21, 25, 30, 35, 40, 46, 52, 57, 63),
    8: (14, 18, 22, 27, 33, 39, 46, 54, 63, 72, 81, 89, 97),
    9: (25, 30, 36, 43, 52, 62, 74, 87, 100, 115, 130, 140, 155),
    10: (40, 48, 58, 70, 84, 100, 120, 140, 160, 185, 210, 230, 250),
    11: (60, 75, 90, 110, 130, 160, 190, 220, 250, 290, 320, 360, 400),
    # IT12 and IT13 are kept for groove widths (DIN 472 m is H13)
    12: (100, 120, 150, 180, 210, 250, 300, 350, 400, 460, 520, 570, 630),
    13: (140, 180, 220, 270, 330, 390, 460, 540, 630, 720, 810, 890, 970),
}

#: ISO 286-1 Table 3, shafts: upper deviation es (um) of e, f, g, h (all grades).
SHAFT_UPPER_DEVIATION_UM: dict[str, tuple[float, ...]] = {
    "e": (-14, -20, -25, -32, -40, -50, -60, -72, -85, -100, -110, -125, -135),
    "f": (-6, -10, -13, -16, -20, -25, -30, -36, -43, -50, -56, -62, -68),
    "g": (-2, -4, -5, -6, -7, -9, -10, -12, -14, -15, -17, -18, -20),
    "h": (0,) * 13,
}
#: ISO 286-1 Table 3, shafts: lower deviation ei (um) of m, n, p (all grades) and of k for
#: grades IT4..IT7 (k of other grades, and of every grade up to 3 mm, has ei = 0).
SHAFT_LOWER_DEVIATION_UM: dict[str, tuple[float, ...]] = {
    "k": (0, 1, 1, 1, 2, 2, 2, 3, 3, 4, 4, 4, 5),
    "m": (2, 4, 6, 7, 8, 9, 11, 13, 15, 17, 20, 21, 23),
    "n": (4, 8, 10, 12, 15, 17, 20, 23, 27, 31, 34, 37, 40),
    "p": (6, 12, 15, 18, 22, 26, 32, 37, 43, 50, 56, 62, 68),
}
#: ISO 286-1 Table 2, holes: lower deviation EI (um) of F, G, H (all grades).
HOLE_LOWER_DEVIATION_UM: dict[str, tuple[float, ...]] = {
    "F": (6, 10, 13, 16, 20, 25, 30, 36, 43, 50, 56, 62, 68),
    "G": (2, 4, 5, 6, 7, 9, 10, 12, 14, 15, 17, 18, 20),
    "H": (0,) * 13,
}
#: ISO 286-1 Table 2, holes: upper deviation ES (um) of K and N up to IT8, before the
#: Delta is added (ES = value + Delta). Above IT8: K has ES = 0, N has ES = -4 up to 3 mm
#: and 0 above.
HOLE_UPPER_BASE_UM: dict[str, tuple[float, ...]] = {
    "K": (0, -1, -1, -1, -2, -2, -2, -3, -3, -4, -4, -4, -5),
    "N": (-4, -8, -10, -12, -15, -17, -20, -23, -27, -31, -34, -37, -40),
}
#: ISO 286-1 Table 2 (right-hand columns): Delta (um) for grades IT3..IT8; it carries the
#: shaft rule over to the hole so that e.g. H7/k6 and K7/h6 give the same fit.
DELTA_UM: dict[int, tuple[float, ...]] = {
    3: (0, 1, 1, 1, 1.5, 1.5, 2, 2, 3, 3, 4, 4, 5),
    4: (0, 1.5, 1.5, 2, 2, 3, 3, 4, 4, 4, 4, 5, 5),
    5: (0, 1, 2, 3, 3, 4, 5, 5, 6, 6, 7, 7, 7),
    6: (0, 3, 3, 3, 4, 5, 6, 7, 7, 9, 9, 11, 13),
    7: (0, 4, 6, 7, 8, 9, 11, 13, 15, 17, 20, 21, 23),
    8: (0, 6, 7, 9, 12, 14, 16, 19, 23, 26, 29, 32, 34),
}

HOLE_LETTERS: tuple[str, ...] = ("F", "G", "H", "JS", "K", "N")
SHAFT_LETTERS: tuple[str, ...] = ("e", "f", "g", "h", "js", "k", "m", "n", "p")
GRADES: tuple[int, ...] = tuple(sorted(IT_GRADES_UM))
#: ISO 286-1 Table 1, the two grades finer than IT1 (named, not numbered: IT01 and IT0).
IT_FINEST_UM: dict[str, tuple[float, ...]] = {
    "IT01": (0.3, 0.4, 0.4, 0.5, 0.6, 0.6, 0.8, 1, 1.2, 2, 2.5, 3, 4),
    "IT0": (0.5, 0.6, 0.6, 0.8, 1, 1, 1.2, 1.5, 2, 3, 4, 5, 6),
}
#: Every grade of the table, finest first, by name ("IT01", "IT0", "IT1", ... "IT13").
GRADE_NAMES: tuple[str, ...] = tuple(IT_FINEST_UM) + tuple(f"IT{g}" for g in GRADES)
#: How the errors name the ISO 286 table.
ISO286_TABLE = "ISO 286 tolerance grades"
_SYMBOL_RE = re.compile(r"^([A-Za-z]{1,2})(\d{1,2})$")


def size_range_index(nominal_mm: float) -> int:
    """Index of the ISO 286 size range holding ``nominal_mm`` (over a up to and including b).

    Raises
    ------
    StandardTableError
        For a size that is not a finite number in (0, 500] mm (ISO 286-1 tabulates the
        tolerance grades and deviations held here up to 500 mm; the table ends there).
    """
    if isinstance(nominal_mm, bool) or not isinstance(nominal_mm, (int, float)) \
            or not math.isfinite(nominal_mm) or not 0 < nominal_mm <= SIZE_RANGE_UPPER_MM[-1]:
        raise StandardTableError(
            ISO286_TABLE, nominal_mm, f"ISO 286 nominal size {nominal_mm!r} mm is outside the table: it must be "
                                      f"over 0 up to and including {SIZE_RANGE_UPPER_MM[-1]:g} mm", 0.0,
            float(SIZE_RANGE_UPPER_MM[-1]))
    return bisect_left(SIZE_RANGE_UPPER_MM, nominal_mm)


def it_tolerance_by_name_um(name: str, nominal_mm: float) -> float:
    """Standard tolerance (um) of the grade named ``name`` (``"IT01"``, ``"IT0"``, ``"IT1"``
    ... ``"IT13"``) for a nominal size (mm), ISO 286-1 Table 1."""
    if name in IT_FINEST_UM:
        return float(IT_FINEST_UM[name][size_range_index(nominal_mm)])
    if name not in GRADE_NAMES:
        raise StandardTableError(ISO286_TABLE, name, f"ISO 286 grade {name!r} is not tabulated here; known: "
                                                     f"{', '.join(GRADE_NAMES)}")
    return it_tolerance_um(int(name[2:]), nominal_mm)


def finest_grade_at_least(nominal_mm: float, tolerance_um: float) -> str | None:
    """The finest ISO 286 grade (name) whose standard tolerance at ``nominal_mm`` is at least
    ``tolerance_um``; None when even IT13 is smaller."""
    for name in GRADE_NAMES:
        if it_tolerance_by_name_um(name, nominal_mm) >= tolerance_um:
            return name
    return None


def size_range_mm(nominal_mm: float) -> tuple[float, float]:
    """The (over, up to and including) size range of ``nominal_mm``, in mm."""
    return SIZE_RANGES_MM[size_range_index(nominal_mm)]


def it_tolerance_um(grade: int, nominal_mm: float) -> float:
    """Standard tolerance IT``grade`` (um) for a nominal size (mm), ISO 286-1 Table 1."""
    if isinstance(grade, bool) or grade not in IT_GRADES_UM:
        raise StandardTableError(ISO286_TABLE, grade, f"ISO 286 grade IT{grade!r} is not tabulated here; known: "
                                                      f"IT{GRADES[0]}..IT{GRADES[-1]}")
    return float(IT_GRADES_UM[grade][size_range_index(nominal_mm)])


@dataclass(frozen=True)
class ToleranceZone:
    """Limit deviations of one hole or shaft tolerance class at one nominal size.

    Attributes
    ----------
    symbol : str
        The class, e.g. ``"H7"`` (capital letter: hole) or ``"g6"`` (lower case: shaft).
    nominal_mm : float
        Nominal size, mm.
    upper_um, lower_um : float
        Upper and lower limit deviation from the nominal size, um (ES/EI for a hole,
        es/ei for a shaft).
    """

    symbol: str
    nominal_mm: float
    upper_um: float
    lower_um: float

    def __post_init__(self) -> None:
        if not isinstance(self.symbol, str) or not self.symbol:
            raise ValueError(f"ToleranceZone.symbol {self.symbol!r} must be a non-empty string")
        for name in ("nominal_mm", "upper_um", "lower_um"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValueError(f"ToleranceZone.{name} {v!r} must be a finite number")
        if self.nominal_mm <= 0:
            raise ValueError(f"ToleranceZone.nominal_mm {self.nominal_mm!r} must be > 0")
        if self.upper_um < self.lower_um:
            raise ValueError(f"ToleranceZone {self.symbol}: upper deviation {self.upper_um} um is "
                             f"below the lower deviation {self.lower_um} um")

    @property
    def upper_mm(self) -> float:
        """Upper limit deviation, mm."""
        return self.upper_um / 1000.0

    @property
    def lower_mm(self) -> float:
        """Lower limit deviation, mm."""
        return self.lower_um / 1000.0

    @property
    def width_um(self) -> float:
        """Tolerance (upper - lower deviation), um: the IT value of the grade."""
        return self.upper_um - self.lower_um

    @property
    def max_size_mm(self) -> float:
        """Largest permitted size, mm."""
        return self.nominal_mm + self.upper_mm

    @property
    def min_size_mm(self) -> float:
        """Smallest permitted size, mm."""
        return self.nominal_mm + self.lower_mm


def _parse_symbol(symbol: str) -> tuple[str, int, bool]:
    """Split ``"H7"`` into (letter, grade, is_hole), or raise naming the rule broken."""
    text = symbol.strip() if isinstance(symbol, str) else symbol
    m = _SYMBOL_RE.match(text) if isinstance(text, str) else None
    if m is None:
        raise StandardTableError(ISO286_TABLE, symbol,
                                 f"ISO 286 fit symbol {symbol!r}: expected a deviation letter and a grade "
                                 f"number, e.g. 'H7' (hole, capital) or 'g6' (shaft, lower case)")
    letter, grade = m.group(1), int(m.group(2))
    if letter.isupper():
        is_hole, known = True, HOLE_LETTERS
    elif letter.islower():
        is_hole, known = False, SHAFT_LETTERS
    else:
        raise StandardTableError(ISO286_TABLE, symbol,
                                 f"ISO 286 fit symbol {symbol!r}: letter {letter!r} mixes cases; holes are "
                                 f"capital ({', '.join(HOLE_LETTERS)}), shafts lower case "
                                 f"({', '.join(SHAFT_LETTERS)})")
    if letter not in known:
        kind = "hole" if is_hole else "shaft"
        raise StandardTableError(ISO286_TABLE, symbol,
                                 f"ISO 286 fit symbol {symbol!r}: unknown {kind} deviation letter {letter!r}; "
                                 f"known: {', '.join(known)}")
    if grade not in IT_GRADES_UM:
        raise StandardTableError(ISO286_TABLE, symbol,
                                 f"ISO 286 fit symbol {symbol!r}: grade IT{grade} is not tabulated; known: "
                                 f"IT{GRADES[0]}..IT{GRADES[-1]}")
    if letter in HOLE_UPPER_BASE_UM and grade < min(DELTA_UM):
        raise StandardTableError(ISO286_TABLE, symbol,
                                 f"ISO 286 fit symbol {symbol!r}: {letter} is tabulated from IT{min(DELTA_UM)} "
                                 f"(its Delta starts there)")
    return letter, grade, is_hole


def _deviations_um(letter: str, grade: int, k: int, it: float) -> tuple[float, float]:
    """(upper, lower) deviation (um) of class ``letter``+``grade`` in size range ``k``."""
    if letter in ("js", "JS"):
        return it / 2, -it / 2                 # symmetric, ISO 286-1 5.3.1.4 (unrounded)
    if letter in SHAFT_UPPER_DEVIATION_UM:     # e..h: es fixed, ei = es - IT
        es = SHAFT_UPPER_DEVIATION_UM[letter][k]
        return es, es - it
    if letter in SHAFT_LOWER_DEVIATION_UM:     # k..p: ei fixed, es = ei + IT
        ei = SHAFT_LOWER_DEVIATION_UM[letter][k]
        if letter == "k" and not 4 <= grade <= 7:
            ei = 0.0                            # k below IT4 or above IT7: ei = 0
        return ei + it, ei
    if letter in HOLE_LOWER_DEVIATION_UM:      # F..H: EI fixed, ES = EI + IT
        ei = HOLE_LOWER_DEVIATION_UM[letter][k]
        return ei + it, ei
    base = HOLE_UPPER_BASE_UM[letter][k]       # K, N: ES = base + Delta up to IT8
    if grade <= 8:
        es = base + DELTA_UM[grade][k]
    else:
        es = base if (letter == "N" and k == 0) else 0.0
    return es, es - it


def tolerance_zone(nominal_mm: float, symbol: str) -> ToleranceZone:
    """Limit deviations of an ISO 286 tolerance class at a nominal size.

    Parameters
    ----------
    nominal_mm : float
        Nominal size, mm, over 0 up to and including 500 (10 mm is in the 6-10 range).
    symbol : str
        Deviation letter and grade: holes F, G, H, JS, K, N; shafts e, f, g, h, js, k, m,
        n, p; grades 1..13 (K and N from 3), e.g. ``"H7"``, ``"g6"``, ``"js5"``.

    Returns
    -------
    ToleranceZone
        Upper and lower deviation in um (``upper_mm``/``lower_mm`` in mm).

    Raises
    ------
    StandardTableError
        For an unknown letter or grade or a size outside the table, naming the value and
        the rule (a ``ValueError`` and a design error, exit code 2).
    """
    letter, grade, _ = _parse_symbol(symbol)
    k = size_range_index(nominal_mm)
    it = float(IT_GRADES_UM[grade][k])
    upper, lower = _deviations_um(letter, grade, k, it)
    return ToleranceZone(symbol=symbol.strip(), nominal_mm=float(nominal_mm),
                         upper_um=float(upper), lower_um=float(lower))


FIT_KINDS: tuple[str, ...] = ("clearance", "transition", "interference")


@dataclass(frozen=True)
class FitLimits:
    """A hole-shaft fit evaluated at one nominal size.

    Attributes
    ----------
    hole, shaft : ToleranceZone
        The two zones at ``nominal_mm`` (mm).
    min_clearance_mm, max_clearance_mm : float
        Smallest and largest clearance, mm: hole lower - shaft upper deviation and hole
        upper - shaft lower deviation. Negative clearance is interference.
    kind : str
        ``"clearance"`` (min >= 0), ``"interference"`` (max <= 0) or ``"transition"``.
    """

    hole: ToleranceZone
    shaft: ToleranceZone
    min_clearance_mm: float
    max_clearance_mm: float
    kind: str

    def __post_init__(self) -> None:
        if self.hole.nominal_mm != self.shaft.nominal_mm:
            raise ValueError(f"FitLimits: hole at {self.hole.nominal_mm} mm and shaft at "
                             f"{self.shaft.nominal_mm} mm must share one nominal size")
        if not self.min_clearance_mm <= self.max_clearance_mm:
            raise ValueError(f"FitLimits: min clearance {self.min_clearance_mm} mm exceeds max "
                             f"clearance {self.max_clearance_mm} mm")
        if self.kind not in FIT_KINDS:
            raise ValueError(f"FitLimits.kind {self.kind!r} must be one of {', '.join(FIT_KINDS)}")

    @property
    def nominal_mm(self) -> float:
        """Nominal size of the fit, mm."""
        return self.hole.nominal_mm


@dataclass(frozen=True)
class Fit:
    """An ISO 286 fit: a hole class and a shaft class, e.g. ``Fit("H7", "g6")``.

    Both symbols are checked at construction (letter, case, grade); :meth:`parse` reads
    the written form ``"H7/g6"``, :meth:`limits` evaluates the fit at a nominal size (mm).
    """

    hole: str
    shaft: str

    def __post_init__(self) -> None:
        if not _parse_symbol(self.hole)[2]:
            raise StandardTableError(ISO286_TABLE, str(self),
                                     f"ISO 286 fit '{self}': the hole class {self.hole!r} must start with a "
                                     f"capital letter ({', '.join(HOLE_LETTERS)}); the hole comes first, "
                                     f"e.g. 'H7/g6'")
        if _parse_symbol(self.shaft)[2]:
            raise StandardTableError(ISO286_TABLE, str(self),
                                     f"ISO 286 fit '{self}': the shaft class {self.shaft!r} must start with a "
                                     f"lower-case letter ({', '.join(SHAFT_LETTERS)}), e.g. 'H7/g6'")
        object.__setattr__(self, "hole", self.hole.strip())
        object.__setattr__(self, "shaft", self.shaft.strip())

    def __str__(self) -> str:
        return f"{self.hole}/{self.shaft}"

    @classmethod
    def parse(cls, text: str) -> Fit:
        """Read ``"H7/g6"`` (hole class / shaft class)."""
        parts = text.split("/") if isinstance(text, str) else []
        if len(parts) != 2:
            raise StandardTableError(ISO286_TABLE, text, f"ISO 286 fit {text!r}: expected 'hole/shaft', e.g. 'H7/g6'")
        return cls(parts[0].strip(), parts[1].strip())

    def limits(self, nominal_mm: float) -> FitLimits:
        """Both zones and the clearance range (mm) at ``nominal_mm`` (mm)."""
        hole = tolerance_zone(nominal_mm, self.hole)
        shaft = tolerance_zone(nominal_mm, self.shaft)
        lo = (hole.lower_um - shaft.upper_um) / 1000.0
        hi = (hole.upper_um - shaft.lower_um) / 1000.0
        kind = "clearance" if lo >= 0 else "interference" if hi <= 0 else "transition"
        return FitLimits(hole=hole, shaft=shaft, min_clearance_mm=lo, max_clearance_mm=hi, kind=kind)


# --- DIN 472 ---------------------------------------------------------------------------

#: DIN 472 regular series, one row per bore, mm:
#: d1 bore, s ring thickness, d3 free outer diameter (None: not confirmed), a lug width
#: (max), b section width opposite the gap (approx.), d5 lug hole diameter (min),
#: d2 groove diameter, m groove width (min, H13), n edge distance (min).
_DIN472_ROWS: tuple[tuple[float, float, float | None, float, float, float, float, float, float], ...] = (
    # d1    s    d3     a     b    d5    d2     m     n
    (8, 0.8, 8.7, 2.4, 1.1, 1.0, 8.4, 0.9, 0.6),
    (9, 0.8, 9.8, 2.5, 1.3, 1.0, 9.4, 0.9, 0.6),
    (10, 1.0, 10.8, 3.2, 1.4, 1.2, 10.4, 1.1, 0.6),
    (11, 1.0, 11.8, 3.3, 1.5, 1.2, 11.4, 1.1, 0.6),
    (12, 1.0, 13.0, 3.4, 1.7, 1.5, 12.5, 1.1, 0.8),
    (13, 1.0, 14.1, 3.6, 1.8, 1.5, 13.6, 1.1, 0.9),
    (14, 1.0, 15.1, 3.7, 1.9, 1.7, 14.6, 1.1, 0.9),
    (15, 1.0, 16.2, 3.7, 2.0, 1.7, 15.7, 1.1, 1.1),
    (16, 1.0, 17.3, 3.8, 2.0, 1.7, 16.8, 1.1, 1.2),
    (17, 1.0, 18.3, 3.9, 2.1, 1.7, 17.8, 1.1, 1.2),
    (18, 1.0, 19.5, 4.1, 2.2, 2.0, 19.0, 1.1, 1.5),
    (19, 1.0, 20.5, 4.1, 2.2, 2.0, 20.0, 1.1, 1.5),
    (20, 1.0, 21.5, 4.2, 2.3, 2.0, 21.0, 1.1, 1.5),
    (21, 1.0, 22.5, 4.2, 2.4, 2.0, 22.0, 1.1, 1.5),
    (22, 1.0, 23.5, 4.2, 2.5, 2.0, 23.0, 1.1, 1.5),
    (23, 1.2, 24.6, 4.2, 2.5, 2.0, 24.1, 1.3, 1.7),
    (24, 1.2, 25.9, 4.4, 2.6, 2.0, 25.2, 1.3, 1.8),
    (25, 1.2, 26.9, 4.5, 2.7, 2.0, 26.2, 1.3, 1.8),
    (26, 1.2, 27.9, 4.7, 2.8, 2.0, 27.2, 1.3, 1.8),
    (27, 1.2, 29.1, 4.7, 2.9, 2.0, 28.4, 1.3, 2.1),
    (28, 1.2, 30.1, 4.8, 2.9, 2.0, 29.4, 1.3, 2.1),
    (29, 1.2, 31.1, 4.8, 3.0, 2.0, 30.4, 1.3, 2.1),
    (30, 1.2, 32.1, 4.8, 3.0, 2.0, 31.4, 1.3, 2.1),
    (31, 1.2, 33.4, 5.2, 3.2, 2.5, 32.7, 1.3, 2.6),
    (32, 1.2, 34.4, 5.4, 3.2, 2.5, 33.7, 1.3, 2.6),
    (33, 1.2, 35.5, 5.4, 3.3, 2.5, 34.7, 1.3, 2.6),
    (34, 1.5, 36.5, 5.4, 3.3, 2.5, 35.7, 1.6, 2.6),
    (35, 1.5, 37.8, 5.4, 3.4, 2.5, 37.0, 1.6, 3.0),
    (36, 1.5, 38.8, 5.4, 3.5, 2.5, 38.0, 1.6, 3.0),
    (37, 1.5, 39.8, 5.5, 3.6, 2.5, 39.0, 1.6, 3.0),
    (38, 1.5, 40.8, 5.5, 3.7, 2.5, 40.0, 1.6, 3.0),
    (39, 1.5, None, 5.6, 3.8, 2.5, 41.0, 1.6, 3.0),
    (40, 1.75, 43.5, 5.8, 3.9, 2.5, 42.5, 1.85, 3.8),
    (41, 1.75, 44.5, 5.9, 4.0, 2.5, 43.5, 1.85, 3.8),
    (42, 1.75, 45.5, 5.9, 4.1, 2.5, 44.5, 1.85, 3.8),
    (43, 1.75, 46.5, 5.9, 4.2, 2.5, 45.5, 1.85, 3.8),
    (44, 1.75, 47.5, 6.0, 4.2, 2.5, 46.5, 1.85, 3.8),
    (45, 1.75, 48.5, 6.2, 4.3, 2.5, 47.5, 1.85, 3.8),
    (46, 1.75, 49.5, 6.3, 4.4, 2.5, 48.5, 1.85, 3.8),
    (47, 1.75, 50.5, 6.4, 4.4, 2.5, 49.5, 1.85, 3.8),
    (48, 1.75, 51.5, 6.4, 4.5, 2.5, 50.5, 1.85, 3.8),
    (49, 1.75, 52.5, 6.5, 4.5, 2.5, 51.5, 1.85, 3.8),
    (50, 2.0, 54.2, 6.5, 4.6, 2.5, 53.0, 2.15, 4.5),
    (51, 2.0, 55.2, 6.5, 4.7, 2.5, 54.0, 2.15, 4.5),
    (52, 2.0, 56.2, 6.7, 4.7, 2.5, 55.0, 2.15, 4.5),
    (53, 2.0, 57.2, 6.7, 4.9, 2.5, 56.0, 2.15, 4.5),
    (54, 2.0, 58.2, 6.7, 5.0, 2.5, 57.0, 2.15, 4.5),
    (55, 2.0, 59.2, 6.8, 5.0, 2.5, 58.0, 2.15, 4.5),
    (56, 2.0, 60.2, 6.8, 5.1, 2.5, 59.0, 2.15, 4.5),
    (57, 2.0, 61.2, 6.8, 5.1, 2.5, 60.0, 2.15, 4.5),
    (58, 2.0, 62.2, 6.9, 5.2, 2.5, 61.0, 2.15, 4.5),
    (60, 2.0, 64.2, 7.3, 5.4, 2.5, 63.0, 2.15, 4.5),
    (62, 2.0, 66.2, 7.3, 5.5, 2.5, 65.0, 2.15, 4.5),
    (63, 2.0, 67.2, 7.3, 5.6, 2.5, 66.0, 2.15, 4.5),
    (64, 2.0, 68.2, 7.6, 5.8, 2.5, 67.0, 2.15, 4.5),
    (65, 2.5, 69.2, 7.6, 5.8, 3.0, 68.0, 2.65, 4.5),
    (67, 2.5, 71.5, 7.7, 6.0, 3.0, 70.0, 2.65, 4.5),
    (68, 2.5, 72.5, 7.8, 6.1, 3.0, 71.0, 2.65, 4.5),
    (70, 2.5, 74.5, 7.8, 6.2, 3.0, 73.0, 2.65, 4.5),
    (72, 2.5, 76.5, 7.8, 6.4, 3.0, 75.0, 2.65, 4.5),
    (75, 2.5, 79.5, 7.8, 6.6, 3.0, 78.0, 2.65, 4.5),
    (77, 2.5, 81.5, 7.9, 6.7, 3.0, 80.0, 2.65, 4.5),
    (78, 2.5, 82.5, 8.5, 6.8, 3.0, 81.0, 2.65, 4.5),
    (80, 2.5, 85.5, 8.5, 7.0, 3.0, 83.5, 2.65, 5.3),
    (82, 2.5, 87.5, 8.5, 7.0, 3.0, 85.5, 2.65, 5.3),
    (85, 3.0, 90.5, 8.6, 7.2, 3.5, 88.5, 3.15, 5.3),
    (87, 3.0, 92.5, 8.6, 7.3, 3.5, 90.5, 3.15, 5.3),
    (88, 3.0, 93.5, 8.6, 7.4, 3.5, 91.5, 3.15, 5.3),
    (90, 3.0, 95.5, 8.6, 7.6, 3.5, 93.5, 3.15, 5.3),
    (92, 3.0, 97.5, 8.7, 7.8, 3.5, 95.5, 3.15, 5.3),
    (95, 3.0, 100.5, 8.8, 8.1, 3.5, 98.5, 3.15, 5.3),
    (97, 3.0, 102.5, 8.8, 8.2, 3.5, 100.5, 3.15, 5.3),
    (98, 3.0, 103.5, 9.0, 8.3, 3.5, 101.5, 3.15, 5.3),
    (100, 3.0, 105.5, 9.2, 8.4, 3.5, 103.5, 3.15, 5.3),
    (102, 4.0, 108.0, 9.5, 8.5, 3.5, 106.0, 4.15, 6.0),
    (105, 4.0, 112.0, 9.5, 8.7, 3.5, 109.0, 4.15, 6.0),
    (107, 4.0, 114.0, 9.5, 8.8, 3.5, 111.0, 4.15, 6.0),
    (108, 4.0, 115.0, 9.5, 8.9, 3.5, 112.0, 4.15, 6.0),
    (110, 4.0, 117.0, 10.4, 9.0, 3.5, 114.0, 4.15, 6.0),
    (112, 4.0, 119.0, 10.5, 9.1, 3.5, 116.0, 4.15, 6.0),
    (115, 4.0, 122.0, 10.5, 9.3, 3.5, 119.0, 4.15, 6.0),
    (117, 4.0, 124.0, 10.6, 9.5, 3.5, 121.0, 4.15, 6.0),
    (118, 4.0, 125.0, 10.7, 9.6, 3.5, 122.0, 4.15, 6.0),
    (120, 4.0, 127.0, 11.0, 9.7, 3.5, 124.0, 4.15, 6.0),
    (122, 4.0, 129.0, 11.0, 9.8, 4.0, 126.0, 4.15, 6.0),
    (125, 4.0, 132.0, 11.0, 10.0, 4.0, 129.0, 4.15, 6.0),
    (127, 4.0, 134.0, 11.0, 10.1, 4.0, 131.0, 4.15, 6.0),
    (128, 4.0, 135.0, 11.0, 10.2, 4.0, 132.0, 4.15, 6.0),
    (130, 4.0, 137.0, 11.0, 10.2, 4.0, 134.0, 4.15, 6.0),
    (132, 4.0, 139.0, 11.0, 10.3, 4.0, 136.0, 4.15, 6.0),
    (135, 4.0, 142.0, 11.2, 10.5, 4.0, 139.0, 4.15, 6.0),
    (137, 4.0, 144.0, 11.2, 10.5, 4.0, 141.0, 4.15, 6.0),
    (138, 4.0, 145.0, 11.2, 10.6, 4.0, 142.0, 4.15, 6.0),
    (140, 4.0, 147.0, 11.2, 10.7, 4.0, 144.0, 4.15, 6.0),
    (142, 4.0, 149.0, 11.3, 10.8, 4.0, 146.0, 4.15, 6.0),
    (145, 4.0, 152.0, 11.4, 10.9, 4.0, 149.0, 4.15, 6.0),
    (147, 4.0, 154.0, 11.6, 11.0, 4.0, 151.0, 4.15, 6.0),
    (148, 4.0, 155.0, 11.8, 11.1, 4.0, 152.0, 4.15, 6.0),
    (150, 4.0, 158.0, 12.0, 11.2, 4.0, 155.0, 4.15, 7.5),
    (152, 4.0, 161.0, 12.0, 11.4, 4.0, 157.0, 4.15, 7.5),
    (155, 4.0, 164.0, 12.0, 11.4, 4.0, 160.0, 4.15, 7.5),
    (158, 4.0, 167.0, 13.0, 11.6, 4.0, 163.0, 4.15, 7.5),
    (160, 4.0, 169.0, 13.0, 11.6, 4.0, 165.0, 4.15, 7.5),
    (165, 4.0, 174.5, 13.0, 11.8, 4.0, 170.0, 4.15, 7.5),
    (168, 4.0, 177.5, 13.5, 12.2, 4.0, 173.0, 4.15, 7.5),
    (170, 4.0, 179.5, 13.5, 12.2, 4.0, 175.0, 4.15, 7.5),
    (175, 4.0, 184.5, 13.5, 12.7, 4.0, 180.0, 4.15, 7.5),
    (178, 4.0, 187.5, 14.2, 13.2, 4.0, 183.0, 4.15, 7.5),
    (180, 4.0, 189.5, 14.2, 13.2, 4.0, 185.0, 4.15, 7.5),
    (185, 4.0, 194.5, 14.2, 13.7, 4.0, 190.0, 4.15, 7.5),
    (190, 4.0, 199.5, 14.2, 13.8, 4.0, 195.0, 4.15, 7.5),
    (195, 4.0, 204.5, 14.2, 13.8, 4.0, 200.0, 4.15, 7.5),
    (200, 4.0, 209.5, 14.2, 14.0, 4.0, 205.0, 4.15, 7.5),
)
#: How the errors name the DIN 472 table.
DIN472_TABLE = "DIN 472 retaining rings"
#: Upper deviation (mm) of the groove diameter d2 where a source prints it, as
#: (first d1, last d1, upper); the lower deviation is 0.
_DIN472_D2_UPPER_MM: tuple[tuple[float, float, float], ...] = ((8, 9, 0.09), (10, 18, 0.11))


def _opt_positive(name: str, v: float | None) -> None:
    if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float))
                          or not math.isfinite(v) or v <= 0):
        raise ValueError(f"RetainingRing.{name} {v!r} must be a finite number > 0 (mm)")


@dataclass(frozen=True)
class RetainingRing:
    """One DIN 472 ring for a bore and the groove it needs; every size in mm.

    Attributes
    ----------
    bore_mm : float
        d1, the bore diameter (nominal size of the ring).
    thickness_mm : float
        s, ring thickness.
    groove_diameter_mm : float
        d2, diameter of the groove bottom (> d1).
    groove_upper_mm, groove_lower_mm : float or None
        Limit deviations of d2 (None where no source printed them; lower is 0).
    groove_width_mm : float
        m, the smallest groove width; the width is toleranced H13 (:attr:`groove_width_max_mm`).
    edge_distance_mm : float
        n, the smallest distance from the groove to the end of the bore (the collar that
        carries the axial load).
    free_diameter_mm : float or None
        d3, outer diameter of the ring not fitted (None where not confirmed).
    lug_width_mm : float
        a, radial width of a lug (max).
    section_width_mm : float
        b, radial width of the ring opposite the gap (approx.).
    lug_hole_mm : float
        d5, diameter of the plier holes (min).
    """

    bore_mm: float
    thickness_mm: float
    groove_diameter_mm: float
    groove_width_mm: float
    edge_distance_mm: float
    lug_width_mm: float
    section_width_mm: float
    lug_hole_mm: float
    free_diameter_mm: float | None = None
    groove_upper_mm: float | None = None
    groove_lower_mm: float | None = None

    def __post_init__(self) -> None:
        for name in ("bore_mm", "thickness_mm", "groove_diameter_mm", "groove_width_mm",
                     "edge_distance_mm", "lug_width_mm", "section_width_mm", "lug_hole_mm"):
            v = getattr(self, name)
            if v is None:
                raise ValueError(f"RetainingRing.{name} is required (mm)")
            _opt_positive(name, v)
        _opt_positive("free_diameter_mm", self.free_diameter_mm)
        if self.groove_diameter_mm <= self.bore_mm:
            raise ValueError(f"RetainingRing {self.bore_mm:g}: groove diameter {self.groove_diameter_mm:g} "
                             f"mm must exceed the bore")
        if self.groove_width_mm <= self.thickness_mm:
            raise ValueError(f"RetainingRing {self.bore_mm:g}: groove width {self.groove_width_mm:g} mm "
                             f"must exceed the ring thickness {self.thickness_mm:g} mm")
        if self.free_diameter_mm is not None and self.free_diameter_mm <= self.groove_diameter_mm:
            raise ValueError(f"RetainingRing {self.bore_mm:g}: free diameter {self.free_diameter_mm:g} mm "
                             f"must exceed the groove diameter (the ring presses into the groove)")
        if (self.groove_upper_mm is None) != (self.groove_lower_mm is None):
            raise ValueError(f"RetainingRing {self.bore_mm:g}: give both groove deviations or neither")
        if self.groove_upper_mm is not None and self.groove_upper_mm < self.groove_lower_mm:
            raise ValueError(f"RetainingRing {self.bore_mm:g}: groove upper deviation is below the lower")

    @property
    def groove_depth_mm(self) -> float:
        """t = (d2 - d1) / 2, groove depth at the nominal sizes, mm."""
        return (self.groove_diameter_mm - self.bore_mm) / 2

    @property
    def groove_width_max_mm(self) -> float:
        """Largest groove width, mm: m plus the H13 tolerance of m (ISO 286)."""
        return self.groove_width_mm + tolerance_zone(self.groove_width_mm, "H13").upper_mm

    @property
    def designation(self) -> str:
        """Order designation, e.g. ``"DIN 472 - 40 x 1.75"`` (bore x thickness, mm)."""
        return f"DIN 472 - {self.bore_mm:g} x {self.thickness_mm:g}"


def din472_sizes() -> tuple[float, ...]:
    """Bore diameters d1 (mm) of the DIN 472 regular series held here, ascending."""
    return tuple(float(r[0]) for r in _DIN472_ROWS)


def din472_ring(bore_mm: float) -> RetainingRing:
    """The DIN 472 ring and groove for a table bore diameter d1 (mm).

    Raises
    ------
    StandardTableError
        If ``bore_mm`` is not a table size (exact sizes only); the message lists the
        nearest sizes and the table's range.
    """
    sizes = din472_sizes()
    if isinstance(bore_mm, bool) or not isinstance(bore_mm, (int, float)) or not math.isfinite(bore_mm):
        raise StandardTableError(DIN472_TABLE, bore_mm, f"DIN 472 bore {bore_mm!r} must be a finite number (mm)",
                                 sizes[0], sizes[-1])
    for row in _DIN472_ROWS:
        if abs(row[0] - bore_mm) < 1e-9:
            d1, s, d3, a, b, d5, d2, m, n = row
            upper = next((u for lo, hi, u in _DIN472_D2_UPPER_MM if lo <= d1 <= hi), None)
            return RetainingRing(bore_mm=float(d1), thickness_mm=s, groove_diameter_mm=d2,
                                 groove_width_mm=m, edge_distance_mm=n, lug_width_mm=a,
                                 section_width_mm=b, lug_hole_mm=d5, free_diameter_mm=d3,
                                 groove_upper_mm=upper, groove_lower_mm=None if upper is None else 0.0)
    raise StandardTableError(DIN472_TABLE, bore_mm, f"DIN 472 has no ring for a {bore_mm:g} mm bore (table sizes "
                                                    f"only, {sizes[0]:g}-{sizes[-1]:g} mm); nearest sizes: "
                                                    f"{nearest_sizes(sizes, bore_mm)} mm", sizes[0], sizes[-1])


def nearest_sizes(sizes: tuple[float, ...], value: float) -> str:
    """The table sizes next to ``value`` below and above it, e.g. ``"40, 42"`` (for the
    message of a size a table does not hold)."""
    below = [d for d in sizes if d < value][-1:]
    above = [d for d in sizes if d > value][:1]
    return ", ".join(f"{d:g}" for d in below + above)
