"""The synchronising gears of a design: sizing, checks, phasing, running clearance and the
shop measurements (docs/theory/gears.md). Pure math, no I/O.

One :class:`GearAnalysis` per build (:func:`analyse_gears`), passed on to the meshes (the
roller gear's phase), the report (``gears`` section) and the drawings (gear data).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from prs_geom.geometry.frames import carrier_angles, roller_spin
from prs_geom.geometry.gear_checks import InternalPairChecks, SweepClearance
from prs_geom.geometry.gear_pair import GearPair, design_gear_pair, sweep_clearance
from prs_geom.geometry.gear_phasing import RollerGearPhasing, phasing_divisible, roller_gear_phasing
from prs_geom.geometry.gears import SpurGear
from prs_geom.model.design import PRSDesign

__all__ = ["SWEEP_STEPS", "SWEEP_CHORD_MM", "GearAnalysis", "analyse_gears"]

#: Carrier positions of the running check: one ring tooth pitch of carrier travel in this
#: many steps (the gear contact repeats every tooth pitch).
SWEEP_STEPS = 8
#: Outline chord tolerance of the running clearance check (mm).
SWEEP_CHORD_MM = 1e-3


@dataclass(frozen=True, eq=False)
class GearAnalysis:
    """The gears of a design, checked.

    Attributes
    ----------
    pair : GearPair
        Roller gear (pinion) and nut ring gear, their centre distance and the sizing rule.
    checks : InternalPairChecks
        Involute, fillet, trochoid and trimming interference, contact ratio, backlash.
    phasing : RollerGearPhasing
        The one angular offset of the roller gear (its tooth 0) from the roller's theta = 0
        that meshes every roller, and whether it exists (z divides z_ring - n_s z_g).
    sweep : SweepClearance
        Every roller gear's least clearance to the ring over one ring pitch of carrier
        travel (exact 2D polygon distance at ``SWEEP_CHORD_MM``).
    face_width_mm : float
        Gear face width (mm).
    """

    pair: GearPair
    checks: InternalPairChecks
    phasing: RollerGearPhasing
    sweep: SweepClearance
    face_width_mm: float
    divisible: bool

    @property
    def roller_gear(self) -> SpurGear:
        return self.pair.pinion

    @property
    def ring_gear(self) -> SpurGear:
        return self.pair.ring

    @property
    def passed(self) -> bool:
        return self.checks.passed and self.phasing.consistent and not self.sweep.any_overlap


def analyse_gears(design: PRSDesign) -> GearAnalysis | None:
    """Size and check the gears of ``design`` (None when its gears are disabled)."""
    pair = design_gear_pair(design)
    if pair is None:
        return None
    psi = carrier_angles(design)
    chi = np.array([roller_spin(design, a) for a in psi])
    phasing = roller_gear_phasing(pair.pinion, pair.ring, psi, chi)
    advance = np.linspace(0.0, 2.0 * math.pi / pair.ring.teeth, SWEEP_STEPS, endpoint=False)
    sweep = sweep_clearance(pair, psi, chi, phasing.offset_rad, advance, chord_tol_mm=SWEEP_CHORD_MM)
    return GearAnalysis(pair, pair.checks(), phasing, sweep, pair.pinion.face_width_mm,
                        phasing_divisible(design.roller.count, pair.ring.teeth, pair.pinion.teeth,
                                          design.screw.starts))
