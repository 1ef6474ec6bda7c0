"""Plausibility warnings of a valid design: values the model accepts but that are
probably a unit slip or a typing error, and rollers that would drift axially.

Errors (:class:`~prs_geom.model.errors.DesignError`) stop a design; these are warnings:
``prs-geom validate`` prints one line each (field, value, rule) and exits 0, and
``prs-geom sweep`` counts a point that draws one as "valid with warnings". Pure model code:
no analysis, nothing above the model layer.

Plausible ranges (:data:`PLAUSIBLE_RANGES`, docs/cli.md "Plausibility warnings"): per design
field a low and a high bound (None: no bound on that side), the unit and the reason. They
are deliberately wide: a value outside is not wrong for the model, but no roller screw is
built that way, and the usual cause is a unit (metres, kN, GPa) or a misplaced decimal.
One derived rule checks the load against the screw: :data:`MAX_ROOT_STRESS_MPA`.

Roller drift (docs/theory/kinematics.md "Roller drift"): rolling without slip at the
pitch circles, with the nut held and the screw turning, moves each roller axially against
the nut by

    s_r = h p (w_c / w_s) (n_n - r_n / r_r)   per screw turn,  w_c / w_s = r_s / (r_s + r_n)

(h = +1 right hand, -1 left hand), the formula of
:func:`prs_geom.analysis.kinematics.speed_ratios`. It is zero exactly when r_n = n_n r_r
(equal lead angles of nut and roller; with n_s = n_n and r_n = r_s + 2 r_r this is the
standard r_s = (n_s - 2) r_r). A drifting roller walks out of its carrier: the design is
warned when |s_r| exceeds :data:`DRIFT_TOLERANCE_MM` per screw turn.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from prs_geom.model.design import PRSDesign, RatingSettings
from prs_geom.model.errors import format_value

__all__ = ["DRIFT_TOLERANCE_MM", "MAX_ROOT_STRESS_MPA", "PLAUSIBLE_RANGES", "Plausible", "design_warnings",
           "drift_warning", "plausibility_warnings", "roller_drift_per_screw_turn_mm"]

__all__ = ["Plausible", "PLAUSIBLE_RANGES", "MAX_ROOT_STRESS_MPA", "DRIFT_TOLERANCE_MM", "plausibility_warnings",
           "roller_drift_per_screw_turn_mm", "drift_warning", "design_warnings"]


@dataclass(frozen=True)
class Plausible:
    """A plausible range: ``low`` and ``high`` (None: unbounded on that side, inclusive
    bounds), the ``unit`` as printed and the ``reason`` the warning gives."""

    low: float | None
    high: float | None
    unit: str
    reason: str


_DIAMETER = ("roller screws are made from a few mm to a few hundred mm: below 1 mm the value is probably "
             "in metres, above 1000 mm probably in micrometres")
_MODULUS = ("rolling parts are steel (about 210 GPa), titanium (about 110 GPa) or ceramics (up to about "
            "400 GPa): outside 50 to 500 GPa the value is probably not in MPa")
_LENGTH = ("screw lengths are of the order of 0.1 to a few m: below 1 mm the value is probably in metres, "
           "above 12 m probably not in mm")

#: field path -> plausible range (docs/cli.md "Plausibility warnings").
PLAUSIBLE_RANGES: dict[str, Plausible] = {
    "thread.pitch_mm": Plausible(0.1, 20.0, "mm", "roller screw pitches are about 0.5 to 10 mm: below 0.1 mm "
                                                  "the value is probably in metres, above 20 mm probably the "
                                                  "lead or not in mm"),
    "thread.flank_half_angle_deg": Plausible(30.0, 60.0, "deg", "roller screw threads have a 45 deg half-angle "
                                                                "(90 deg included); outside 30 to 60 deg the "
                                                                "value is probably the included angle or a typo"),
    "screw.pitch_diameter_mm": Plausible(1.0, 1000.0, "mm", _DIAMETER),
    "roller.pitch_diameter_mm": Plausible(1.0, 1000.0, "mm", _DIAMETER),
    "nut.pitch_diameter_mm": Plausible(1.0, 1000.0, "mm", _DIAMETER),
    "nut.outer_diameter_mm": Plausible(1.0, 1000.0, "mm", _DIAMETER),
    "roller.count": Plausible(3, None, "", "fewer than 3 rollers cannot centre the screw in the nut"),
    "screw.length_mm": Plausible(1.0, 12_000.0, "mm", _LENGTH),
    "supports.unsupported_length_mm": Plausible(1.0, 12_000.0, "mm", _LENGTH),
    "loading.axial_load_n": Plausible(10.0, 1e7, "N", "below 10 N the value is probably in kN; above 10 MN no "
                                                      "roller screw carries it (probably not in N)"),
    "materials.screw.youngs_modulus_mpa": Plausible(50e3, 500e3, "MPa", _MODULUS),
    "materials.roller.youngs_modulus_mpa": Plausible(50e3, 500e3, "MPa", _MODULUS),
    "materials.nut.youngs_modulus_mpa": Plausible(50e3, 500e3, "MPa", _MODULUS),
    "rating.speed_rpm": Plausible(None, 20_000.0, "rpm", "faster than any roller screw runs: probably not in "
                                                         "rpm (rad/s? mm/min?)"),
    "rating.friction_coefficient": Plausible(None, 0.2, "", "lubricated rolling flanks run at about 0.01 to 0.1 "
                                                            "(0.025 gives the catalogue efficiency); above 0.2 is "
                                                            "dry sliding"),
    "rating.life_hours": Plausible(None, 200_000.0, "h", "more than 23 years of running day and night: probably "
                                                         "not in hours"),
    "rating.dn_limit_mm_rpm": Plausible(1e4, 5e5, "mm/min", "makers state roller-screw d n limits of the order "
                                                            "of 1e5 mm/min: probably not diameter (mm) x speed "
                                                            "(rpm)"),
}
#: Largest plausible axial stress of the design load on the screw root section (MPa): above
#: it the screw itself would yield (the yield strength of hardened screw steels is of this
#: order), far beyond any load rating of its threads: the load is probably not in N.
MAX_ROOT_STRESS_MPA = 1500.0
#: Largest roller drift per screw turn accepted without a warning (mm): 1 nm, far below any
#: manufacturing tolerance; the sizing relation r_n = n_n r_r holds to SIZING_RTOL well inside it.
DRIFT_TOLERANCE_MM = 1e-6


def _value(design: PRSDesign, path: str) -> Any:
    """The value of a dotted field path; an absent optional section takes its defaults
    (``rating``) or has no value (``supports``: None)."""
    obj: Any = design
    for key in path.split("."):
        if obj is None:
            return None
        obj = getattr(obj, key)
        if obj is None and key == "rating":
            obj = RatingSettings()
    return obj


def _number(v: float, unit: str) -> str:
    return f"{v:g}{' ' + unit if unit else ''}"


def plausibility_warnings(design: PRSDesign) -> list[str]:
    """One line per field outside its plausible range (field, value, rule), then the load
    against the screw root section."""
    out = []
    for path, rng in PLAUSIBLE_RANGES.items():
        v = _value(design, path)
        if v is None:
            continue
        if rng.low is not None and v < rng.low:
            bound = f"below the plausible minimum {_number(rng.low, rng.unit)}"
        elif rng.high is not None and v > rng.high:
            bound = f"above the plausible maximum {_number(rng.high, rng.unit)}"
        else:
            continue
        out.append(f"{path} = {format_value(v)} is {bound}: {rng.reason}")
    d_root = design.screw.minor_diameter_mm
    stress = design.loading.axial_load_n / (math.pi * d_root ** 2 / 4.0)
    if stress > MAX_ROOT_STRESS_MPA:
        out.append(f"loading.axial_load_n = {format_value(design.loading.axial_load_n)} stresses the screw root "
                   f"section (screw.minor_diameter_mm = {format_value(d_root)}) to {stress:.4g} MPa, above the "
                   f"plausible {MAX_ROOT_STRESS_MPA:g} MPa: the screw itself would yield long before its threads "
                   f"reach their rating; the load is probably not in N")
    return out


def roller_drift_per_screw_turn_mm(design: PRSDesign) -> float:
    """Axial travel of each roller against the nut per screw turn (mm, signed along +z),
    rolling without slip at the pitch circles (module docstring):
    h p (r_s / (r_s + r_n)) (n_n - r_n / r_r)."""
    rs, rr, rn = (0.5 * design.screw.pitch_diameter_mm, 0.5 * design.roller.pitch_diameter_mm,
                  0.5 * design.nut.pitch_diameter_mm)
    return design.thread.hand_sign * design.thread.pitch_mm * rs / (rs + rn) * (design.nut.starts - rn / rr)


def drift_warning(design: PRSDesign) -> str | None:
    """The warning of a design whose rollers drift axially by more than
    :data:`DRIFT_TOLERANCE_MM` per screw turn, else None."""
    drift = roller_drift_per_screw_turn_mm(design)
    if abs(drift) <= DRIFT_TOLERANCE_MM:
        return None
    d_r, d_n, nn = design.roller.pitch_diameter_mm, design.nut.pitch_diameter_mm, design.nut.starts
    return (f"rollers drift axially by {drift:.6g} mm per screw turn against the nut (rule: |drift| <= "
            f"{DRIFT_TOLERANCE_MM:g} mm per turn; drift = h p (d_s / (d_s + d_n)) (n_n - d_n / d_r), h = +1 "
            f"right hand, -1 left hand, with thread.hand = {format_value(design.thread.hand)}, thread.pitch_mm = {format_value(design.thread.pitch_mm)}, screw.pitch_diameter_mm = "
            f"{format_value(design.screw.pitch_diameter_mm)}, nut.pitch_diameter_mm = {format_value(d_n)}, "
            f"roller.pitch_diameter_mm = {format_value(d_r)}, nut.starts = {nn}): nut.pitch_diameter_mm must "
            f"equal nut.starts x roller.pitch_diameter_mm = {nn * d_r:g} (with equal starts and d_n = d_s + "
            f"2 d_r: d_s = (starts - 2) d_r)")


def design_warnings(design: PRSDesign) -> list[str]:
    """Every warning of ``prs-geom validate`` beyond the sizing relations: the plausible
    ranges, the root stress and the roller drift."""
    out = plausibility_warnings(design)
    drift = drift_warning(design)
    if drift is not None:
        out.append(drift)
    return out
