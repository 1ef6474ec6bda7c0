"""The ``[actuator]`` section of a design: stroke, screw ends, nut mounting, run-outs.

Validated values only; every size left out (None) follows a rule of
:func:`prs_geom.geometry.actuator.actuator_layout` from the catalogue tables of
:mod:`prs_geom.model.machine_elements` (docs/theory/actuator.md). A value given here
replaces the rule's result; a given table size (a bearing bore, a locknut thread, a
shaft-end diameter, a bolt) must be one the table holds, unless the sizes the table would
supply are given with it (bearing width and outside diameter).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from prs_geom.model.errors import DesignError
from prs_geom.model.validation import bounded, choice, integer, optional_size, size

__all__ = ["DRIVE_KINDS", "NUT_MOUNTS", "THREAD_CLASSES", "ActuatorSettings", "DriveEnd", "FixedEnd",
           "FloatingEnd", "NutMount"]

#: How the drive journal takes the motor torque: a DIN 6885-1 key or a milled flat.
DRIVE_KINDS = ("key", "flat")
#: How the nut is mounted: a flange with a bolt circle at its loaded end (docs/theory/actuator.md
#: says why; a keyed plain body needs a keyway cut in the nut's thread body, which the complete
#: nut solid will carry).
NUT_MOUNTS = ("flange",)
#: ISO 965-1 tolerance classes accepted for the locknut thread on the screw (external).
THREAD_CLASSES = ("4h", "6e", "6f", "6g", "6h", "8g")
#: Dimension series of the bearings (ISO 15): see machine_elements.BEARING_SERIES.
_SERIES = ("02", "03")


def _set(obj: Any, name: str, value: Any) -> None:
    object.__setattr__(obj, name, value)


def _flag(fld: str, value: Any) -> bool:
    if not isinstance(value, bool):
        raise DesignError(fld, value, "must be true or false")
    return value


def _zone(fld: str, value: Any) -> str:
    from prs_geom.model.standards import tolerance_zone

    try:
        tolerance_zone(20.0, value)
    except (ValueError, TypeError) as exc:
        raise DesignError(fld, value, f"must be an ISO 286 tolerance zone such as \"k5\": {exc}") from None
    return value


def _sizes(obj: Any, names: tuple[str, ...]) -> None:
    for name in names:
        _set(obj, name, optional_size(name, getattr(obj, name)))


@dataclass(frozen=True)
class FixedEnd:
    """The screw's fixed end: a pair of angular contact ball bearings (72xx B, back to
    back) on a seat, clamped by a KM locknut on a metric fine thread.

    ``bearing_bore_mm``: default the largest bore of ``bearing_series`` (ISO 15) not above
    the screw root diameter less 1 mm; ``bearing_width_mm`` and ``bearing_outer_diameter_mm``
    default to the table's. ``seat_tolerance``: ISO 286 zone of the seat (default k5: a
    rotating inner ring under normal load). ``locknut_thread_mm``: nominal diameter of the
    ISO 261 fine thread (default the bearing bore; pitch from the KM row);
    ``locknut_tolerance``: its ISO 965-1 class; ``undercut_width_mm``: thread undercut
    (default 3 P).
    """

    bearing_series: str = "02"
    bearing_bore_mm: float | None = None
    bearing_width_mm: float | None = None
    bearing_outer_diameter_mm: float | None = None
    seat_tolerance: str = "k5"
    locknut_thread_mm: float | None = None
    locknut_tolerance: str = "6g"
    undercut_width_mm: float | None = None

    def __post_init__(self) -> None:
        choice("bearing_series", self.bearing_series, _SERIES)
        _sizes(self, ("bearing_bore_mm", "bearing_width_mm", "bearing_outer_diameter_mm", "locknut_thread_mm",
                      "undercut_width_mm"))
        _zone("seat_tolerance", self.seat_tolerance)
        choice("locknut_tolerance", self.locknut_tolerance, THREAD_CLASSES)
        _bearing_lookup(self)
        if self.locknut_thread_mm is not None:
            from prs_geom.model.machine_elements import locknut
            from prs_geom.model.standards import StandardTableError

            try:
                locknut(self.locknut_thread_mm)
            except StandardTableError as exc:
                raise DesignError("locknut_thread_mm", self.locknut_thread_mm, str(exc)) from None


def _bearing_lookup(end: Any) -> None:
    """A given bore must be a table bore unless width and outside diameter come with it."""
    if end.bearing_bore_mm is None or (end.bearing_width_mm is not None
                                       and end.bearing_outer_diameter_mm is not None):
        if end.bearing_outer_diameter_mm is not None and end.bearing_bore_mm is not None \
                and end.bearing_outer_diameter_mm <= end.bearing_bore_mm:
            raise DesignError("bearing_outer_diameter_mm", end.bearing_outer_diameter_mm,
                              f"must exceed bearing_bore_mm ({end.bearing_bore_mm:g} mm)")
        return
    from prs_geom.model.machine_elements import bearing
    from prs_geom.model.standards import StandardTableError

    try:
        bearing(end.bearing_series, end.bearing_bore_mm)
    except StandardTableError as exc:
        raise DesignError("bearing_bore_mm", end.bearing_bore_mm,
                          f"{exc}; or give bearing_width_mm and bearing_outer_diameter_mm for a bearing "
                          f"outside the table") from None


@dataclass(frozen=True)
class FloatingEnd:
    """The screw's floating end: one deep groove ball bearing (62xx) on a seat, held on the
    shaft by a DIN 471 ring, free to slide axially in its housing. ``enabled = false``
    leaves the end free (a fixed-free screw). Sizes as in :class:`FixedEnd`."""

    enabled: bool = True
    bearing_series: str = "02"
    bearing_bore_mm: float | None = None
    bearing_width_mm: float | None = None
    bearing_outer_diameter_mm: float | None = None
    seat_tolerance: str = "k5"

    def __post_init__(self) -> None:
        _flag("enabled", self.enabled)
        choice("bearing_series", self.bearing_series, _SERIES)
        _sizes(self, ("bearing_bore_mm", "bearing_width_mm", "bearing_outer_diameter_mm"))
        _zone("seat_tolerance", self.seat_tolerance)
        _bearing_lookup(self)


@dataclass(frozen=True)
class DriveEnd:
    """The drive journal beyond the fixed end's locknut: an ISO 775 cylindrical shaft end.

    ``diameter_mm``: default the largest ISO 775 diameter at least 1 mm below the locknut
    thread's minor diameter (the locknut must pass over it); ``length_mm``: default the
    short series length of that diameter; ``fit``: ISO 286 zone (k6). ``kind``: "key"
    (DIN 6885-1 section for the diameter, ``key_length_mm`` default the longest standard
    length not above the journal length less 4 mm) or "flat" (``flat_depth_mm`` default
    0.1 x the diameter, over the key length).
    """

    kind: str = "key"
    diameter_mm: float | None = None
    length_mm: float | None = None
    fit: str = "k6"
    key_length_mm: float | None = None
    flat_depth_mm: float | None = None

    def __post_init__(self) -> None:
        choice("kind", self.kind, DRIVE_KINDS)
        _sizes(self, ("diameter_mm", "length_mm", "key_length_mm", "flat_depth_mm"))
        _zone("fit", self.fit)


@dataclass(frozen=True)
class NutMount:
    """How the nut is mounted, at its loaded end (z = 0 side, where the load model and the
    FE model hold the nut).

    ``kind = "flange"`` (the one mounting so far): a flange on the lower nut end with ``bolt_count`` ISO 4762
    bolts of property class 8.8 on a bolt circle. ``bolt``: default the smallest size whose
    proof loads carry twice the design load; ``bolt_circle_diameter_mm``: default the nut
    outside diameter plus a head diameter plus 1 mm (the heads clear the nut body);
    ``flange_diameter_mm``: bolt circle plus a head diameter plus 2 mm, rounded up to 1 mm;
    ``flange_thickness_mm``: 1.5 x the bolt diameter, rounded up to 1 mm; ``bolt_length_mm``:
    the flange thickness plus 1.5 bolt diameters engaged in the housing, rounded up to the
    ISO 4762 length series.
    """

    kind: str = "flange"
    bolt: str | None = None
    bolt_count: int = 6
    bolt_circle_diameter_mm: float | None = None
    flange_diameter_mm: float | None = None
    flange_thickness_mm: float | None = None
    bolt_length_mm: float | None = None

    def __post_init__(self) -> None:
        choice("kind", self.kind, NUT_MOUNTS)
        _set(self, "bolt_count", integer("bolt_count", self.bolt_count, 3, 24))
        _sizes(self, ("bolt_circle_diameter_mm", "flange_diameter_mm", "flange_thickness_mm", "bolt_length_mm"))
        if self.bolt is not None:
            from prs_geom.model.machine_elements import bolt
            from prs_geom.model.standards import StandardTableError

            try:
                bolt(self.bolt)
            except StandardTableError as exc:
                raise DesignError("bolt", self.bolt, str(exc)) from None


@dataclass(frozen=True)
class ActuatorSettings:
    """The screw and nut as an actuator (docs/theory/actuator.md).

    ``stroke_mm``: the nut's travel along the screw (default 100 mm, about four screw
    diameters: a short-stroke actuator of this screw size). ``over_travel_mm``: extra full
    thread beyond each stroke end for an end stop (default 5 mm). ``screw_run_out_mm``:
    length of the grinding-wheel exit at each screw thread end (default one lead).
    ``thread_chamfer_mm``: axial size of the 45 degree chamfer that ends the roller and nut
    threads at their gears (default 0.8 x the depth from the crest to the pitch diameter). The screw's
    threaded length follows: the nut assembly, the stroke, the over-travels and the
    run-outs. ``enabled = false`` leaves the actuator out (the screw is then
    ``screw.length_mm`` of thread, as in format version 1 without this section); it needs
    the mechanism (``mechanism.enabled``), whose nut ends it mounts.
    """

    enabled: bool = True
    stroke_mm: float = 100.0
    over_travel_mm: float = 5.0
    screw_run_out_mm: float | None = None
    thread_chamfer_mm: float | None = None
    fixed_end: FixedEnd = field(default_factory=FixedEnd)
    floating_end: FloatingEnd = field(default_factory=FloatingEnd)
    drive: DriveEnd = field(default_factory=DriveEnd)
    nut_mount: NutMount = field(default_factory=NutMount)

    def __post_init__(self) -> None:
        _flag("enabled", self.enabled)
        _set(self, "stroke_mm", bounded("stroke_mm", self.stroke_mm, 0.0, 1e5,
                                        "must be from 0 to 100 000 mm (the nut's travel; lengths are in mm)"))
        _set(self, "over_travel_mm", bounded("over_travel_mm", self.over_travel_mm, 0.0, 1e3,
                                             "must be from 0 to 1000 mm"))
        _sizes(self, ("screw_run_out_mm", "thread_chamfer_mm"))
        if self.screw_run_out_mm is not None:
            size("screw_run_out_mm", self.screw_run_out_mm)
