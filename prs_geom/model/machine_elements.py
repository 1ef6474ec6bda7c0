"""Catalogue data of the standard machine elements an actuator is built from (pure data).

Every table names its source. Sizes in mm; the tables hold the catalogue values as
printed (nominal sizes), and the look-ups choose a row by a stated rule; the rules that
size the actuator from them are in :mod:`prs_geom.geometry.actuator`
(docs/theory/actuator.md).

* Rolling bearings: boundary dimensions (bore d, outside diameter D, width B, smallest
  chamfer r_s) of the ISO 15 dimension series 02 (deep groove 62xx, angular contact 72xx)
  and 03 (63xx, 73xx), bores 10 to 100 mm.
* Precision locknuts: the KM series of ISO 2982-2 (DIN 981): metric fine thread of
  ISO 261, width B and outside diameter, by the bearing bore they clamp.
* Retaining rings for shafts: DIN 471 regular series (groove diameter d2, groove width m,
  ring thickness s), shafts 10 to 100 mm.
* Parallel keys: DIN 6885-1 (form A): width b x height h and shaft keyway depth t1 by
  shaft diameter, and the standard key lengths.
* Cylindrical shaft ends: ISO 775 (DIN 748-1) diameters and lengths (long and short series).
* Socket head cap screws: ISO 4762 head diameter d_k, ISO 273 clearance holes (medium
  series), ISO 898-1 tensile stress area A_s and the proof stress of property class 8.8.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from prs_geom.model.standards import StandardTableError, nearest_sizes

__all__ = ["BEARING_SERIES", "BEARING_TABLE", "BOLT_PROOF_STRESS_8_8_MPA", "BOLT_SAFETY", "ISO_4762_LENGTHS_MM", "Bearing",
           "Bolt", "Key", "Locknut", "ShaftEnd", "ShaftRing", "bearing", "bearing_bores", "bolt", "bolt_sizes",
           "key_for_shaft", "key_lengths", "load_sized_bolt", "locknut", "locknut_bores", "shaft_end",
           "shaft_end_diameters", "shaft_ring", "shaft_ring_sizes"]

BEARING_TABLE = "ISO 15 (radial bearings, boundary dimensions), dimension series 02 and 03"

#: (d, D, B, r_s min) by dimension series (ISO 15). The 62xx/72xx bearings are series 02,
#: 63xx/73xx series 03; the bearing number's last two digits are d / 5 from d = 20 mm.
_BEARING_ROWS: dict[str, tuple[tuple[float, float, float, float], ...]] = {
    "02": ((10, 30, 9, 0.6), (12, 32, 10, 0.6), (15, 35, 11, 0.6), (17, 40, 12, 0.6), (20, 47, 14, 1.0),
           (25, 52, 15, 1.0), (30, 62, 16, 1.0), (35, 72, 17, 1.1), (40, 80, 18, 1.1), (45, 85, 19, 1.1),
           (50, 90, 20, 1.1), (55, 100, 21, 1.5), (60, 110, 22, 1.5), (65, 120, 23, 1.5), (70, 125, 24, 1.5),
           (75, 130, 25, 1.5), (80, 140, 26, 2.0), (85, 150, 28, 2.0), (90, 160, 30, 2.0), (95, 170, 32, 2.1),
           (100, 180, 34, 2.1)),
    "03": ((10, 35, 11, 0.6), (12, 37, 12, 1.0), (15, 42, 13, 1.0), (17, 47, 14, 1.0), (20, 52, 15, 1.1),
           (25, 62, 17, 1.1), (30, 72, 19, 1.1), (35, 80, 21, 1.5), (40, 90, 23, 1.5), (45, 100, 25, 1.5),
           (50, 110, 27, 2.0), (55, 120, 29, 2.0), (60, 130, 31, 2.1), (65, 140, 33, 2.1), (70, 150, 35, 2.1),
           (75, 160, 37, 2.1), (80, 170, 39, 2.1), (85, 180, 41, 3.0), (90, 190, 43, 3.0), (95, 200, 45, 3.0),
           (100, 215, 47, 3.0)),
}
#: Dimension series held here.
BEARING_SERIES = tuple(_BEARING_ROWS)
_BORE_CODES = {10: "00", 12: "01", 15: "02", 17: "03"}


@dataclass(frozen=True)
class Bearing:
    """One rolling bearing's boundary dimensions (mm, ISO 15)."""

    series: str
    bore_mm: float
    outer_diameter_mm: float
    width_mm: float
    chamfer_mm: float

    def designation(self, kind: str) -> str:
        """Catalogue number: ``kind`` "deep-groove" -> 6204, "angular-contact" -> 7204 B
        (40 degree contact angle, the type paired for axial loads)."""
        code = _BORE_CODES.get(int(self.bore_mm), f"{int(self.bore_mm) // 5:02d}")
        head = "6" if kind == "deep-groove" else "7"
        return f"{head}{self.series[-1]}{code}" + (" B" if kind == "angular-contact" else "")


def bearing_bores(series: str) -> tuple[float, ...]:
    """The bores d (mm) of a dimension series held here, ascending."""
    return tuple(float(r[0]) for r in _BEARING_ROWS[series])


def bearing(series: str, bore_mm: float) -> Bearing:
    """The bearing of ``series`` with bore ``bore_mm`` (table sizes only).

    Raises :class:`StandardTableError` naming the table, its range and the nearest bores."""
    rows = _BEARING_ROWS[series]
    for d, D, B, r in rows:
        if abs(d - bore_mm) < 1e-9:
            return Bearing(series, float(d), float(D), float(B), float(r))
    raise _not_in_table(BEARING_TABLE + f" (series {series})", "bearing bore", bore_mm, bearing_bores(series))


def _not_in_table(table: str, what: str, value: float, sizes: tuple[float, ...]) -> StandardTableError:
    return StandardTableError(table, value, f"{table} has no {what} of {value:g} mm (table sizes only, "
                                            f"{sizes[0]:g}-{sizes[-1]:g} mm); nearest: {nearest_sizes(sizes, value)} mm",
                              sizes[0], sizes[-1])


LOCKNUT_TABLE = "ISO 2982-2 (DIN 981) KM locknuts, threads of ISO 261"
#: (number, thread nominal d, pitch P, outside diameter, width B): KM locknuts.
_LOCKNUT_ROWS = ((0, 10, 0.75, 18, 4), (1, 12, 1.0, 22, 4), (2, 15, 1.0, 25, 5), (3, 17, 1.0, 28, 5),
                 (4, 20, 1.0, 32, 6), (5, 25, 1.5, 38, 7), (6, 30, 1.5, 45, 7), (7, 35, 1.5, 52, 8),
                 (8, 40, 1.5, 58, 9), (9, 45, 1.5, 65, 10), (10, 50, 1.5, 70, 11), (11, 55, 2.0, 75, 11),
                 (12, 60, 2.0, 80, 11), (13, 65, 2.0, 85, 12), (14, 70, 2.0, 92, 12), (15, 75, 2.0, 98, 13),
                 (16, 80, 2.0, 105, 15), (17, 85, 2.0, 110, 16), (18, 90, 2.0, 120, 16), (19, 95, 2.0, 125, 17),
                 (20, 100, 2.0, 130, 18))


@dataclass(frozen=True)
class Locknut:
    """A KM locknut and its shaft thread (mm): thread M d x P (ISO 261 fine)."""

    number: int
    thread_diameter_mm: float
    thread_pitch_mm: float
    outer_diameter_mm: float
    width_mm: float

    @property
    def designation(self) -> str:
        """e.g. ``"KM 4"``."""
        return f"KM {self.number}"

    @property
    def thread(self) -> str:
        """The shaft thread, e.g. ``"M20x1"``."""
        return f"M{self.thread_diameter_mm:g}x{self.thread_pitch_mm:g}"

    @property
    def thread_minor_diameter_mm(self) -> float:
        """External thread minor diameter d3 = d - 1.226869 P (ISO 724 basic profile, mm)."""
        return self.thread_diameter_mm - 1.226869 * self.thread_pitch_mm


def locknut_bores() -> tuple[float, ...]:
    """Thread diameters (mm) of the KM series held here, ascending."""
    return tuple(float(r[1]) for r in _LOCKNUT_ROWS)


def locknut(thread_diameter_mm: float) -> Locknut:
    """The KM locknut whose thread has nominal diameter ``thread_diameter_mm``."""
    for k, d, P, D, B in _LOCKNUT_ROWS:
        if abs(d - thread_diameter_mm) < 1e-9:
            return Locknut(k, float(d), P, float(D), float(B))
    raise _not_in_table(LOCKNUT_TABLE, "locknut thread diameter", thread_diameter_mm, locknut_bores())


SHAFT_RING_TABLE = "DIN 471 retaining rings for shafts, regular series"
#: (shaft d1, groove diameter d2, groove width m, ring thickness s).
_SHAFT_RING_ROWS = ((10, 9.6, 1.1, 1.0), (12, 11.5, 1.1, 1.0), (15, 14.3, 1.1, 1.0), (17, 16.2, 1.1, 1.0),
                    (20, 19.0, 1.3, 1.2), (25, 23.9, 1.3, 1.2), (30, 28.6, 1.6, 1.5), (35, 33.0, 1.6, 1.5),
                    (40, 37.5, 1.85, 1.75), (45, 42.5, 1.85, 1.75), (50, 47.0, 2.15, 2.0), (55, 52.0, 2.15, 2.0),
                    (60, 57.0, 2.15, 2.0), (65, 62.0, 2.65, 2.5), (70, 67.0, 2.65, 2.5), (75, 72.0, 2.65, 2.5),
                    (80, 76.5, 2.65, 2.5), (85, 81.5, 3.15, 3.0), (90, 86.5, 3.15, 3.0), (95, 91.5, 3.15, 3.0),
                    (100, 96.5, 3.15, 3.0))


@dataclass(frozen=True)
class ShaftRing:
    """A DIN 471 ring and its groove (mm)."""

    shaft_mm: float
    groove_diameter_mm: float
    groove_width_mm: float
    thickness_mm: float

    @property
    def designation(self) -> str:
        """e.g. ``"DIN 471 - 20 x 1.2"``."""
        return f"DIN 471 - {self.shaft_mm:g} x {self.thickness_mm:g}"

    @property
    def edge_distance_mm(self) -> float:
        """Shaft collar beyond the groove that carries the ring's load: 3 x the groove depth,
        at least 1.5 mm (the rule DIN 471 gives as n >= 3 t for the regular series)."""
        return max(1.5, 1.5 * (self.shaft_mm - self.groove_diameter_mm))


def shaft_ring_sizes() -> tuple[float, ...]:
    """Shaft diameters (mm) of the DIN 471 rows held here."""
    return tuple(float(r[0]) for r in _SHAFT_RING_ROWS)


def shaft_ring(shaft_mm: float) -> ShaftRing:
    """The DIN 471 ring for shaft diameter ``shaft_mm`` (table sizes only)."""
    for d, d2, m, s in _SHAFT_RING_ROWS:
        if abs(d - shaft_mm) < 1e-9:
            return ShaftRing(float(d), d2, m, s)
    raise _not_in_table(SHAFT_RING_TABLE, "shaft diameter", shaft_mm, shaft_ring_sizes())


KEY_TABLE = "DIN 6885-1 parallel keys (form A)"
#: (shaft over, shaft up to and including, b, h, t1 shaft keyway depth).
_KEY_ROWS = ((6, 8, 2, 2, 1.2), (8, 10, 3, 3, 1.8), (10, 12, 4, 4, 2.5), (12, 17, 5, 5, 3.0), (17, 22, 6, 6, 3.5),
             (22, 30, 8, 7, 4.0), (30, 38, 10, 8, 5.0), (38, 44, 12, 8, 5.0), (44, 50, 14, 9, 5.5),
             (50, 58, 16, 10, 6.0), (58, 65, 18, 11, 7.0), (65, 75, 20, 12, 7.5), (75, 85, 22, 14, 9.0),
             (85, 95, 25, 14, 9.0), (95, 110, 28, 16, 10.0))
#: Standard key lengths of DIN 6885-1 (mm).
_KEY_LENGTHS = (6, 8, 10, 12, 14, 16, 18, 20, 22, 25, 28, 32, 36, 40, 45, 50, 56, 63, 70, 80, 90, 100, 110, 125,
                140, 160, 180, 200, 220, 250)


@dataclass(frozen=True)
class Key:
    """A DIN 6885-1 parallel key's section and the shaft keyway depth (mm)."""

    width_mm: float
    height_mm: float
    shaft_depth_mm: float

    def designation(self, length_mm: float) -> str:
        """e.g. ``"DIN 6885 A 5 x 5 x 22"``."""
        return f"DIN 6885 A {self.width_mm:g} x {self.height_mm:g} x {length_mm:g}"


def key_for_shaft(shaft_mm: float) -> Key:
    """The key section DIN 6885-1 gives for a shaft of diameter ``shaft_mm``."""
    for lo, hi, b, h, t1 in _KEY_ROWS:
        if lo < shaft_mm <= hi + 1e-9:
            return Key(float(b), float(h), t1)
    raise StandardTableError(KEY_TABLE, shaft_mm, f"{KEY_TABLE} covers shafts over {_KEY_ROWS[0][0]} up to "
                                                  f"{_KEY_ROWS[-1][1]} mm; {shaft_mm:g} mm is outside",
                             _KEY_ROWS[0][0], _KEY_ROWS[-1][1])


def key_lengths() -> tuple[float, ...]:
    """The standard key lengths (mm)."""
    return tuple(float(x) for x in _KEY_LENGTHS)


SHAFT_END_TABLE = "ISO 775 (DIN 748-1) cylindrical shaft ends"
#: (diameters, long-series length, short-series length or None where the short series has none).
_SHAFT_END_ROWS = (((6, 7), 16, None), ((8, 9), 20, None), ((10, 11), 23, 20), ((12, 14), 30, 25),
                   ((16, 18, 19), 40, 28), ((20, 22, 24), 50, 36), ((25, 28), 60, 42),
                   ((30, 32, 35, 38), 80, 58), ((40, 42, 45, 48, 50, 55, 56), 110, 82),
                   ((60, 63, 65, 70, 71, 75), 140, 105), ((80, 85, 90, 95), 170, 130))


@dataclass(frozen=True)
class ShaftEnd:
    """A cylindrical shaft end of ISO 775 (mm)."""

    diameter_mm: float
    long_mm: float
    short_mm: float | None


def shaft_end_diameters() -> tuple[float, ...]:
    """The ISO 775 shaft-end diameters held here (mm), ascending."""
    return tuple(float(d) for ds, _, _ in _SHAFT_END_ROWS for d in ds)


def shaft_end(diameter_mm: float) -> ShaftEnd:
    """The ISO 775 shaft end of diameter ``diameter_mm`` (table sizes only)."""
    for ds, long_, short in _SHAFT_END_ROWS:
        if any(abs(d - diameter_mm) < 1e-9 for d in ds):
            return ShaftEnd(float(diameter_mm), float(long_), None if short is None else float(short))
    raise _not_in_table(SHAFT_END_TABLE, "shaft-end diameter", diameter_mm, shaft_end_diameters())


BOLT_TABLE = "ISO 4762 socket head cap screws, ISO 273 clearance holes (medium), ISO 898-1 stress areas"
#: Proof stress (MPa) of property class 8.8 for d <= 16 mm (ISO 898-1); 600 MPa above.
BOLT_PROOF_STRESS_8_8_MPA = 580.0
#: (d, coarse pitch, head diameter d_k, clearance hole medium, stress area A_s mm^2).
_BOLT_ROWS = ((4, 0.7, 7.0, 4.5, 8.78), (5, 0.8, 8.5, 5.5, 14.2), (6, 1.0, 10.0, 6.6, 20.1),
              (8, 1.25, 13.0, 9.0, 36.6), (10, 1.5, 16.0, 11.0, 58.0), (12, 1.75, 18.0, 13.5, 84.3),
              (16, 2.0, 24.0, 17.5, 157.0), (20, 2.5, 30.0, 22.0, 245.0), (24, 3.0, 36.0, 26.0, 353.0))


@dataclass(frozen=True)
class Bolt:
    """A socket head cap screw size and its clearance hole (mm, mm^2)."""

    diameter_mm: float
    pitch_mm: float
    head_diameter_mm: float
    clearance_hole_mm: float
    stress_area_mm2: float

    @property
    def name(self) -> str:
        """e.g. ``"M6"``."""
        return f"M{self.diameter_mm:g}"

    @property
    def proof_load_n(self) -> float:
        """Proof load of property class 8.8 (N): A_s x the proof stress (ISO 898-1)."""
        stress = BOLT_PROOF_STRESS_8_8_MPA if self.diameter_mm <= 16 else 600.0
        return self.stress_area_mm2 * stress


#: Nominal lengths (mm) of ISO 4762 socket head cap screws (the preferred series to 100 mm).
ISO_4762_LENGTHS_MM = (8, 10, 12, 16, 20, 25, 30, 35, 40, 45, 50, 55, 60, 65, 70, 80, 90, 100)


def bolt_sizes() -> tuple[str, ...]:
    """Bolt names held here (``"M4"`` ...), ascending."""
    return tuple(f"M{r[0]:g}" for r in _BOLT_ROWS)


#: Safety of the flange bolts' proof loads (class 8.8, ISO 898-1) over the design load.
BOLT_SAFETY = 2.0


def load_sized_bolt(bolt_count: int, axial_load_n: float) -> str:
    """The smallest bolt of :func:`bolt_sizes` of which ``bolt_count`` carry
    :data:`BOLT_SAFETY` times ``axial_load_n`` (N) on their proof loads; the largest when
    none does (the build's bolt check then fails: an absurd load gets a failed verdict, not a
    refusal). The one place the design load enters a part's geometry."""
    need = [b for b in bolt_sizes() if bolt_count * bolt(b).proof_load_n >= BOLT_SAFETY * axial_load_n]
    return need[0] if need else bolt_sizes()[-1]


def bolt(name: str) -> Bolt:
    """The bolt ``name`` ("M6"): ISO 4762 head, ISO 273 medium clearance hole, A_s."""
    text = str(name).strip().upper()
    for d, P, dk, dh, As in _BOLT_ROWS:
        if text == f"M{d:g}":
            return Bolt(float(d), P, dk, dh, As)
    raise StandardTableError(BOLT_TABLE, name, f"{BOLT_TABLE}: no bolt {name!r}; sizes held: "
                                               f"{', '.join(bolt_sizes())}", 4.0, 24.0)


def _check_tables() -> None:
    """Import-time consistency of the rows (ascending, positive): a typo fails loudly."""
    for rows in _BEARING_ROWS.values():
        assert all(a[0] < b[0] and a[1] < b[1] for a, b in zip(rows, rows[1:]))
        assert all(D > d and B > 0 and r > 0 for d, D, B, r in rows)
    assert all(D > d and B > 0 for _, d, _, D, B in _LOCKNUT_ROWS)
    assert all(d2 < d and m > s for d, d2, m, s in _SHAFT_RING_ROWS)
    assert all(math.isclose(a[1], b[0]) for a, b in zip(_KEY_ROWS, _KEY_ROWS[1:]))


_check_tables()
