"""The synchronising gears of a design: sizing, checks, phasing, running clearance and the
shop measurements (docs/theory/gears.md). Pure math, no I/O.

One :class:`GearAnalysis` per build (:func:`analyse_gears`), passed on to the meshes (the
roller gear's phase), the report (``gears`` section) and the drawings (gear data).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

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

    def report(self) -> dict[str, Any]:
        """The report's ``gears`` section."""
        def gear(g: SpurGear, internal: bool) -> dict[str, Any]:
            k = g.recommended_span_teeth()
            pin = g.ideal_pin_diameter()
            return {"teeth": g.teeth, "module_mm": g.module_mm, "pressure_angle_deg": g.pressure_angle_deg,
                    "profile_shift": g.profile_shift, "addendum_coefficient": g.addendum_coefficient,
                    "dedendum_coefficient": g.dedendum_coefficient,
                    "pitch_diameter_mm": 2.0 * g.pitch_radius_mm, "base_diameter_mm": 2.0 * g.base_radius_mm,
                    "tip_diameter_mm": 2.0 * g.tip_radius_mm, "root_diameter_mm": 2.0 * g.root_radius_mm,
                    "tooth_thickness_mm": g.tooth_thickness_mm, "backlash_thinning_mm": g.backlash_mm,
                    "span_teeth": k, "span_measurement_mm": g.span_measurement(k),
                    "pin_diameter_mm": pin,
                    ("between_pins_mm" if internal else "over_pins_mm"): g.over_pins(pin)}

        c = self.checks
        return {
            "rule": self.pair.rule,
            "roller_gear": gear(self.roller_gear, False),
            "ring_gear": gear(self.ring_gear, True),
            "face_width_mm": self.face_width_mm,
            "centre_distance_mm": self.pair.centre_distance_mm,
            "ratio": self.pair.ratio,
            "working_pressure_angle_deg": c.working_pressure_angle_deg,
            "contact_ratio": c.contact_ratio,
            "backlash_circumferential_mm": c.backlash_circumferential_mm,
            "backlash_normal_mm": c.backlash_normal_mm,
            "checks": [{"name": i.name, "passed": i.passed, "value": i.value, "limit": i.limit, "unit": i.unit,
                        "rule": i.rule} for i in c.items],
            "phasing": {"consistent": self.phasing.consistent, "divisible": self.divisible,
                        "roller_gear_offset_deg": math.degrees(self.phasing.offset_rad),
                        "max_residual_deg": float(np.degrees(np.abs(self.phasing.residuals_rad).max(initial=0.0))),
                        "rule": "one roller gear offset meshes every roller when z divides z_ring - n_s z_g; "
                                "ring gear tooth 0 on the nut's +x axis at both ends"},
            "running_clearance": {"min_mm": self.sweep.min_clearance_mm, "overlap": self.sweep.any_overlap,
                                  "steps": int(len(self.sweep.advance_rad)),
                                  "chord_tolerance_mm": SWEEP_CHORD_MM,
                                  "what": "least 2D distance of every roller gear to the ring gear over one "
                                          "ring pitch of carrier travel"},
            "passed": self.passed,
        }


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
