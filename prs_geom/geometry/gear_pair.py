"""The roller-gear / ring-gear pair of a roller screw and its sizing rule (pure math).

Owns :class:`GearPair` (a pinion inside a ring gear at a centre distance), the default sizing
from the thread (:func:`default_gear_pair`: module series, profile shift against undercut,
ring addendum shortening, backlash allocation), the pair of a design
(:func:`design_gear_pair`) and the ring gear body's outer radius. Conventions are those of
:mod:`~prs_geom.geometry.gears`; the rule and its reasons in docs/theory/gears.md.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from numpy.typing import ArrayLike

from prs_geom.geometry.gear_checks import (InternalPairChecks, SweepClearance, internal_pair_checks, pinion_transform,
                                           require_internal_pair)
from prs_geom.geometry.gears import DEFAULT_FACE_WIDTH_MM, SpurGear
from prs_geom.geometry.planar import frozen_float64, min_clearance_2d
from prs_geom.model.errors import DesignError
from prs_geom.model.validation import positive, real

__all__ = ["DEFAULT_TOTAL_BACKLASH_MM", "GearPair", "ISO54_MODULES_MM", "RING_ADDENDUM_STEPS", "default_gear_pair",
           "design_gear_pair", "ring_gear_outer_radius", "sweep_clearance"]

#: Standard modules (mm), ascending, that the default sizing picks from: ISO 54:1996 first
#: choice from 1 mm, and below 1 mm the values 0.3, 0.4, 0.5, 0.6, 0.8 of the fine-module
#: series (DIN 780).
ISO54_MODULES_MM: tuple[float, ...] = (0.3, 0.4, 0.5, 0.6, 0.8, 1.0, 1.25, 1.5, 2.0, 2.5, 3.0,
                                       4.0, 5.0, 6.0, 8.0, 10.0, 12.0, 16.0, 20.0, 25.0)
#: Total circumferential backlash (mm) of a default roller-gear / ring-gear pair, split
#: equally between the two gears as tooth thinning.
DEFAULT_TOTAL_BACKLASH_MM: float = 0.04
#: Ring-gear addendum coefficients tried by :func:`default_gear_pair`, longest first: the
#: usual tip shortening of internal gears that keeps the ring tip off the pinion's fillet.
RING_ADDENDUM_STEPS: tuple[float, ...] = (1.0, 0.95, 0.9, 0.85, 0.8, 0.75, 0.7, 0.65, 0.6)


@dataclass(frozen=True)
class GearPair:
    """A roller gear (pinion) meshing inside a nut ring gear at ``centre_distance_mm``.

    ``rule`` records how the pair was chosen (empty when built by hand).
    """

    pinion: SpurGear
    ring: SpurGear
    centre_distance_mm: float
    rule: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        require_internal_pair(self.pinion, self.ring)
        object.__setattr__(self, "centre_distance_mm", positive("centre_distance_mm", self.centre_distance_mm))

    @property
    def ratio(self) -> float:
        """z_ring / z_pinion (= r_n / r_r, the nut-to-roller ratio n_n)."""
        return self.ring.teeth / self.pinion.teeth

    def checks(self, **limits: float) -> InternalPairChecks:
        """:func:`~prs_geom.geometry.gear_checks.internal_pair_checks` at this pair's centre distance."""
        return internal_pair_checks(self.pinion, self.ring, self.centre_distance_mm, **limits)


def default_gear_pair(roller_pitch_diameter_mm: float, nut_to_roller_ratio: float, *,
                      pressure_angle_deg: float = 20.0, backlash_mm: float = DEFAULT_TOTAL_BACKLASH_MM,
                      face_width_mm: float = DEFAULT_FACE_WIDTH_MM,
                      max_pinion_tip_diameter_mm: float | None = None,
                      modules: Sequence[float] = ISO54_MODULES_MM) -> GearPair:
    """Size the roller gear and nut ring gear of a roller screw.

    Rule
    ----
    The gear's working pitch diameter must equal the roller's thread pitch diameter d_r and
    the ratio must equal n_n = r_n / r_r, so with x_ring = -x_pinion (standard centre distance
    and pressure angle kept): m z_g = d_r and z_ring = n_n z_g, both whole numbers; the centre
    distance is a = m (z_ring - z_g)/2 = r_n - r_r.

    1. Take the modules of ``modules`` (``ISO54_MODULES_MM``) from the **largest**
       down; keep those for which z_g = d_r / m and z_ring = n_n z_g are integers.
    2. First pass, no profile shift: the first module whose pinion is undercut-free at x = 0
       (z_g >= 2 h_FfP*/sin^2 a, 18 teeth at 20 deg) and whose pair passes every
       :func:`~prs_geom.geometry.gear_checks.internal_pair_checks` check wins.
    3. Else a second pass in the same order with x_pinion = x_min rounded up to 0.01 (no
       undercut) and x_ring = -x_pinion.
    4. Ring addendum: 1.0 m, shortened in steps of 0.05 m (down to 0.6 m,
       ``RING_ADDENDUM_STEPS``) until every check passes. Internal gears need it: with a full
       addendum the ring tip reaches down the line of action almost to the pinion's base
       tangent point and touches the pinion below its form circle (fillet contact).
    5. Backlash: ``backlash_mm`` total circumferential, half as thinning on each gear.
    6. ``max_pinion_tip_diameter_mm`` (e.g. the roller's thread major diameter when the teeth
       are cut through the threaded ends): the pinion addendum is shortened to fit, and the
       checks (contact ratio) decide.

    Raises
    ------
    DesignError
        When no module of the series satisfies the rule.
    """
    d_r = positive("roller_pitch_diameter_mm", roller_pitch_diameter_mm)
    n_n = positive("nut_to_roller_ratio", nut_to_roller_ratio)
    if n_n <= 1.0:
        raise DesignError("nut_to_roller_ratio", nut_to_roller_ratio, "must exceed 1 (ring larger than roller)")
    j = real("backlash_mm", backlash_mm)
    if j < 0:
        raise DesignError("backlash_mm", backlash_mm, "must be >= 0")
    candidates = _whole_tooth_modules(d_r, n_n, modules)
    if not candidates:
        raise DesignError("roller_pitch_diameter_mm", roller_pitch_diameter_mm,
                          f"no module of {tuple(modules)} divides it into whole tooth numbers "
                          f"(with ratio {n_n:g})")
    sizing = _Sizing(pressure_angle_deg=pressure_angle_deg, total_backlash_mm=j, face_width_mm=face_width_mm,
                     max_pinion_tip_diameter_mm=max_pinion_tip_diameter_mm)
    tried: list[str] = []
    for shifted in (False, True):
        for m, zg, zr in candidates:
            pair = _pair_of_module(m, zg, zr, shifted, sizing, tried)
            if pair is not None:
                return pair
    raise DesignError("roller_pitch_diameter_mm", roller_pitch_diameter_mm,
                      "no standard module gives a valid roller/ring gear pair: " + "; ".join(tried))


def _whole_tooth_modules(d_r: float, n_n: float, modules: Sequence[float]) -> list[tuple[float, int, int]]:
    """(m, z_g, z_ring) of the modules, largest first, with z_g = d_r / m >= 4 and
    z_ring = n_n z_g whole numbers (to 1e-9 relative)."""
    out = []
    for m in sorted((float(v) for v in modules), reverse=True):
        zg, zr = d_r / m, n_n * d_r / m
        if abs(zg - round(zg)) > 1e-9 * zg or abs(zr - round(zr)) > 1e-9 * zr or round(zg) < 4:
            continue
        out.append((m, int(round(zg)), int(round(zr))))
    return out


@dataclass(frozen=True)
class _Sizing:
    """The inputs of :func:`default_gear_pair` shared by every module tried."""

    pressure_angle_deg: float
    total_backlash_mm: float
    face_width_mm: float
    max_pinion_tip_diameter_mm: float | None


def _pair_of_module(m: float, zg: int, zr: int, shifted: bool, sizing: _Sizing,
                    tried: list[str]) -> GearPair | None:
    """The pair of module m in the pass ``shifted`` (profile shift x_min against undercut) or
    None, with a note on ``tried`` saying why not (nothing when the module belongs to the
    other pass)."""
    probe = SpurGear(m, zg, sizing.pressure_angle_deg)
    x = 0.0
    if probe.undercut_limit_shift > 0.0:
        if not shifted:
            tried.append(f"m={m:g}: z_g={zg} undercut at x=0")
            return None
        x = math.ceil(probe.undercut_limit_shift * 100.0 - 1e-9) / 100.0
    elif shifted:
        return None
    ha1 = 1.0
    if sizing.max_pinion_tip_diameter_mm is not None:
        ha1 = min(1.0, (0.5 * sizing.max_pinion_tip_diameter_mm - 0.5 * m * zg) / m - x)
        if ha1 <= 0.0:
            tried.append(f"m={m:g}: no addendum left under the tip limit")
            return None
    pair, failed = _pair_with_longest_ring_addendum(m, zg, zr, x, ha1, shifted, sizing)
    if pair is None:
        tried.append(f"m={m:g} (x={x:+.2f}): fails {', '.join(failed)}")
    return pair


def _pair_with_longest_ring_addendum(m: float, zg: int, zr: int, x: float, ha1: float, shifted: bool,
                                     sizing: _Sizing) -> tuple[GearPair | None, tuple[str, ...]]:
    """The pair with pinion shift x, pinion addendum ha1 and the longest ring addendum of
    ``RING_ADDENDUM_STEPS`` that passes every check, at a = m (z_ring - z_g) / 2; else None and
    what failed last."""
    j = sizing.total_backlash_mm
    a = 0.5 * m * (zr - zg)
    failed: tuple[str, ...] = ()
    for ha2 in RING_ADDENDUM_STEPS:
        try:
            pin = SpurGear(module_mm=m, teeth=zg, pressure_angle_deg=sizing.pressure_angle_deg, profile_shift=x,
                           internal=False, addendum_coefficient=ha1, dedendum_coefficient=1.25,
                           backlash_mm=0.5 * j, face_width_mm=sizing.face_width_mm)
            ring = SpurGear(module_mm=m, teeth=zr, pressure_angle_deg=sizing.pressure_angle_deg, profile_shift=-x,
                            internal=True, addendum_coefficient=ha2, dedendum_coefficient=1.25,
                            backlash_mm=0.5 * j, face_width_mm=sizing.face_width_mm)
        except DesignError as exc:
            return None, (str(exc),)
        res = internal_pair_checks(pin, ring, a)
        if res.passed:
            rule = (f"largest module of the series with z_g = d_r/m and z_ring = n_n z_g whole "
                    f"{'(profile shift against undercut)' if shifted else 'and no undercut at x = 0'}"
                    f" whose pair passes all checks with the longest ring addendum: m = {m:g} mm, "
                    f"z_g = {zg}, z_ring = {zr}, x = {x:+.2f}/{-x:+.2f}, h_a* = {ha1:.3g}/{ha2:.2f}, "
                    f"total backlash {j:g} mm")
            return GearPair(pinion=pin, ring=ring, centre_distance_mm=a, rule=rule), ()
        failed = res.failed
    return None, failed



def design_gear_pair(design) -> GearPair | None:
    """The roller/ring gear pair of a :class:`~prs_geom.model.design.PRSDesign` (None when
    ``design.gears.enabled`` is false).

    :func:`default_gear_pair` with the design's pressure angle, backlash and face width
    (default two thread pitches); the module series is the design's ``gears.module_mm``
    alone when given, else ISO 54. The roller gear's tip is capped at the roller's thread
    major diameter: the teeth are cut through the threaded roller ends, so nothing of the
    gear stands above the thread. n_n = d_n / d_r.
    """
    g = design.gears
    if not g.enabled:
        return None
    width = g.face_width_mm if g.face_width_mm is not None else 2.0 * design.thread.pitch_mm
    modules = (g.module_mm,) if g.module_mm is not None else ISO54_MODULES_MM
    try:
        return default_gear_pair(design.roller.pitch_diameter_mm,
                                 design.nut.pitch_diameter_mm / design.roller.pitch_diameter_mm,
                                 pressure_angle_deg=g.pressure_angle_deg, backlash_mm=g.backlash_mm,
                                 face_width_mm=width, max_pinion_tip_diameter_mm=design.roller.major_diameter_mm,
                                 modules=modules)
    except DesignError as exc:
        field = "gears.module_mm" if g.module_mm is not None else "roller.pitch_diameter_mm"
        raise DesignError(field, g.module_mm if g.module_mm is not None else design.roller.pitch_diameter_mm,
                          f"no valid roller/ring gear pair: {exc.rule}") from exc


def ring_gear_outer_radius(design, pair: GearPair) -> float:
    """Outside radius (mm) of the modelled ring gear body: halfway from the ring's root
    circle to the nut body (an outer cylinder flush with the nut's would meet its
    differently sampled polygon in slivers when the nut's parts are united)."""
    return 0.5 * (pair.ring.root_radius_mm + 0.5 * design.nut.outer_diameter_mm)


def sweep_clearance(pair: GearPair, carrier_angles_rad: ArrayLike, roller_spins_rad: ArrayLike,
                    offset_rad: float, advance_rad: ArrayLike, *, chord_tol_mm: float = 1e-3) -> SweepClearance:
    """Run the mechanism and measure every roller gear's clearance to the ring gear.

    Roller k at carrier advance t: centre on the ray psi_k + t at the pair's centre distance,
    gear spin (from the line of centres) chi_k + offset - (z_ring / z_g) t: the rolling
    relation of the gears (and of the threads, n_n = z_ring / z_g). The ring is fixed in its
    own frame (tooth 0 on +x).
    """
    psi = np.atleast_1d(np.asarray(carrier_angles_rad, dtype=float))
    chi = np.atleast_1d(np.asarray(roller_spins_rad, dtype=float))
    adv = np.atleast_1d(np.asarray(advance_rad, dtype=float))
    P = pair.pinion.outline(chord_tol_mm)
    Rg = pair.ring.outline(chord_tol_mm)
    I3 = np.eye(3)
    ratio = pair.ring.teeth / pair.pinion.teeth
    cl = np.empty((len(psi), len(adv)))
    ov = np.empty((len(psi), len(adv)), dtype=bool)
    for k in range(len(psi)):
        for s, t in enumerate(adv):
            T = pinion_transform(psi[k] + t, pair.centre_distance_mm, chi[k] + offset_rad - ratio * t)
            r = min_clearance_2d(P, T, Rg, I3, b_material_inside=False)
            cl[k, s], ov[k, s] = r.distance_mm, r.overlap
    return SweepClearance(advance_rad=frozen_float64(adv), clearance_mm=frozen_float64(cl), overlap=frozen_float64(ov))
