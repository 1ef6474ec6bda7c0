"""The report serialiser: report.json's sections from the typed results of the analysis.

The one place where the report's layout and its prose live: each ``*_section`` function
turns one result object into the dict report.json prints under that section's key (keys in
a fixed order; the layout is described by ``prs_geom/exports/schemas/report.schema.json``),
and :func:`report_dict` assembles the whole report from a build's :class:`BuildResults`.
The warnings a build prints are worded here too. The analysis classes compute; they do not
know the report.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Mapping, Sequence

import numpy as np

from prs_geom.analysis.contact import ContactResult
from prs_geom.analysis.load_details import FeSummary, HertzContact, LoadModelDetails, ToothTerms
from prs_geom.analysis.loads import (LoadDistribution, LoadsResult, ModelRisk, ModelRiskCase, RollerLoadResult,
                                     compliance_model)

if TYPE_CHECKING:  # pragma: no cover
    from prs_geom.analysis.gears import GearAnalysis
    from prs_geom.analysis.inspection import PartInspection
    from prs_geom.analysis.kinematics import Kinematics
    from prs_geom.analysis.machining import MachiningSheet
    from prs_geom.analysis.rating import LimitCheck, RatingResult, VariantLife
    from prs_geom.checks.mechanism import MechanismCheck
    from prs_geom.exports.bom import PartsListRow
    from prs_geom.geometry.gears import SpurGear
    from prs_geom.mesh.assembly import Assembly
    from prs_geom.model.design import Tolerances

__all__ = ["ANGLE_CONVENTIONS", "GEAR_PHASING_RULE", "GEAR_RUNNING_CLEARANCE", "MODEL_RISK_NOT_COMPUTED",
           "REPORT_FORMAT_VERSION", "contact_section", "gears_section", "gear_failures", "load_details_dict",
           "constant_pitch_section", "loads_section", "model_risk_section", "inspection_section",
           "mechanism_section", "actuator_section", "actuator_warnings", "ActuatorStage", "assembly_section", "gear_warnings", "fe_cache_warnings", "rating_warnings",
           "roller_loads_dict", "TOLERANCE_DEFINITIONS", "tolerances_dict", "tolerance_section", "synthesis_section", "robust_section",
           "RATING_METHOD", "LIMIT_MESSAGES", "limit_warnings", "limit_check_dict", "rating_section",
           "step_section", "step_files", "step_warnings", "mechanism_warnings", "check_warnings", "PitchLists",
           "MeshStage", "ChecksResult",
           "BuildResults", "report_dict"]


# --------------------------------------------------------------------------- contact
#: What the angles, flanks and frames of the ``contact`` section mean.
ANGLE_CONVENTIONS = (
    "part_angle_deg: angle of the contact on the screw or nut from the line of centres "
    "(screw axis -> roller axis), positive counter-clockwise seen from +z; "
    "roller_angle_deg: angle in the roller frame from the direction pointing away from the "
    "screw axis (screw-side contacts near +-180, nut-side near 0); left-hand designs are "
    "mirror images (angles change sign). upper = roller upper flank (facing +z) against the "
    "lower flank of the screw/nut tooth above it; lower = the mirror contact. Points and "
    "normals in the screw frame (mm); normals point to +z."
)


def contact_section(contact: ContactResult) -> dict[str, Any]:
    """The ``contact`` section: the contact points, the theoretical screw pitch diameter and
    (graded designs) the per-tooth gaps."""
    theo, d = contact.theoretical, contact.design
    return {
        "conventions": ANGLE_CONVENTIONS,
        "screw_roller": {
            **{k: v.as_dict() for k, v in contact.screw_roller.items()},
            "nominal_pitch_diameter_mm": theo.nominal_pitch_diameter_mm,
            "theoretical_pitch_diameter_mm": theo.theoretical_pitch_diameter_mm,
            "diameter_correction_mm": theo.nominal_pitch_diameter_mm - theo.theoretical_pitch_diameter_mm,
            "interference_at_nominal_mm": max(0.0, -theo.gap_at_nominal_mm),
            "interference_at_nominal_normal_mm": contact.interference_at_nominal_normal_mm,
            "clearance_mm": d.contact.clearance_mm,
            "gap_at_theoretical_mm": theo.gap_at_theoretical_mm,
            "diameter_iterations": theo.iterations,
        },
        "roller_nut": {k: v.as_dict() for k, v in contact.roller_nut.items()},
        "tooth_gaps": contact.tooth_gaps,
    }


# --------------------------------------------------------------------------- gears
#: How the roller gears are phased (``gears.phasing.rule``).
GEAR_PHASING_RULE = ("one roller gear offset meshes every roller when z divides z_ring - n_s z_g; "
                     "ring gear tooth 0 on the nut's +x axis at both ends")
#: What the running clearance measures (``gears.running_clearance.what``).
GEAR_RUNNING_CLEARANCE = ("least 2D distance of every roller gear to the ring gear over one "
                          "ring pitch of carrier travel")


def _gear(g: "SpurGear", internal: bool) -> dict[str, Any]:
    """One gear's data and shop measurements (span over k teeth, size over or between pins)."""
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


def gears_section(gears: "GearAnalysis") -> dict[str, Any]:
    """The ``gears`` section: both gears, the pair, every check, the phasing and the running
    clearance of the synchronising gears."""
    from prs_geom.analysis.gears import SWEEP_CHORD_MM

    c = gears.checks
    return {
        "rule": gears.pair.rule,
        "roller_gear": _gear(gears.roller_gear, False),
        "ring_gear": _gear(gears.ring_gear, True),
        "face_width_mm": gears.face_width_mm,
        "centre_distance_mm": gears.pair.centre_distance_mm,
        "ratio": gears.pair.ratio,
        "working_pressure_angle_deg": c.working_pressure_angle_deg,
        "contact_ratio": c.contact_ratio,
        "backlash_circumferential_mm": c.backlash_circumferential_mm,
        "backlash_normal_mm": c.backlash_normal_mm,
        "checks": [{"name": i.name, "passed": i.passed, "value": i.value, "limit": i.limit, "unit": i.unit,
                    "rule": i.rule} for i in c.items],
        "phasing": {"consistent": gears.phasing.consistent, "divisible": gears.divisible,
                    "roller_gear_offset_deg": math.degrees(gears.phasing.offset_rad),
                    "max_residual_deg": float(np.degrees(np.abs(gears.phasing.residuals_rad).max(initial=0.0))),
                    "rule": GEAR_PHASING_RULE},
        "running_clearance": {"min_mm": gears.sweep.min_clearance_mm, "overlap": gears.sweep.any_overlap,
                              "steps": int(len(gears.sweep.advance_rad)),
                              "chord_tolerance_mm": SWEEP_CHORD_MM,
                              "what": GEAR_RUNNING_CLEARANCE},
        "passed": gears.passed,
    }


def gear_failures(gears: "GearAnalysis") -> list[str]:
    """The names of the failed gear checks, then ``phasing`` and ``running clearance`` when
    those fail."""
    failed = [i.name for i in gears.checks.items if not i.passed]
    return (failed + ([] if gears.phasing.consistent else ["phasing"])
            + (["running clearance"] if gears.sweep.any_overlap else []))


# --------------------------------------------------------------------------- warnings
def gear_warnings(gears: "GearAnalysis") -> list[str]:
    """The build's warning when a gear check, the phasing or the running clearance fails."""
    return [] if gears.passed else ["end gears: " + ", ".join(gear_failures(gears)) + " failed (report gears)"]


def fe_cache_warnings(cache: Any) -> list[str]:
    """The FE cache's own warnings, and one when the matrices could not be stored
    (``cache``: a :class:`prs_geom.analysis.fe.cache.CachedInfluence`)."""
    out = list(cache.warnings)
    if not cache.stored:
        out.append(f"the finite-element influence matrices could not be stored in {cache.folder} (they were "
                   f"computed and used; set $PRS_GEOM_CACHE to a writable folder to keep them)")
    return out


def rating_warnings(rating: "RatingResult") -> list[str]:
    """The build's warnings when the speed or the largest load exceeds its permissible limit."""
    lim = rating.limits
    out = [f"supports: {w}" for w in lim.supports.warnings]
    if not lim.speed_ok:
        out.append(f"rating: speed {lim.max_speed_rpm:.6g} rpm exceeds the permissible speed "
                   f"{lim.permissible_speed_rpm:.6g} rpm (report rating.limits)")
    if not rating.max_load_n <= lim.permissible_buckling_load_n:
        out.append(f"rating: largest load {rating.max_load_n:.6g} N exceeds the permissible buckling load "
                   f"{lim.permissible_buckling_load_n:.6g} N (report rating.limits)")
    return out


def step_section(writes: Sequence[tuple[str, dict[str, Any]]]) -> dict[str, Any]:
    """report.json's ``step`` section from the STEP files of a build, one per part: ``writes``
    holds (part, what :func:`prs_geom.exports.step.write_step` or ``write_solids`` returned)
    in the order written; the file-level keys are those of the last write."""
    section: dict[str, Any] = {"files": [], "parts": {}}
    for part, one in writes:
        section.update({k: v for k, v in one.items() if k not in ("file", "written", "parts")})
        section["parts"][part] = {**one["parts"][part], "file": one["file"]}
        if one["file"]:
            section["files"].append(one["file"])
    return section


def step_files(writes: Sequence[tuple[str, dict[str, Any]]]) -> list[str]:
    """The STEP files a build wrote (parts that could not be made valid solids write none)."""
    return [one["file"] for _, one in writes if one["file"]]


def step_warnings(writes: Sequence[tuple[str, dict[str, Any]]]) -> list[str]:
    """A warning for each STEP part that could not be made a valid solid."""
    return [f"STEP: the {part} could not be made a valid solid; {part}.step was not written: "
            f"{one['parts'][part]['reason']}" for part, one in writes if not one["parts"][part]["valid"]]


def mechanism_warnings(m: "MechanismCheck") -> list[str]:
    """The build's warning naming the failed mechanism checks."""
    failed = [name for name, ok in m.checks if not ok]
    return ["mechanism: " + "; ".join(failed) + " failed (report mechanism)"] if failed else []


def actuator_warnings(stage: "ActuatorStage") -> list[str]:
    """One warning per failed stroke-end check, naming the stroke end and the clearance."""
    out = []
    for c in stage.checks:
        if c.passed:
            continue
        if c.stroke_end == "both":
            out.append(f"actuator: {c.what}: margin {c.clearance_mm:.6g} N (must be > 0: give more or larger "
                       f"actuator.nut_mount bolts; report actuator.stroke_end_checks)")
        else:
            out.append(f"actuator: at the {'lower' if c.stroke_end == 'lo' else 'upper'} stroke end, {c.what}: "
                       f"{c.kind} clearance {c.clearance_mm:.4g} mm (must be > 0; report actuator.stroke_end_checks)")
    return out


def _span(z: "tuple[float, float] | None") -> list[float] | None:
    return None if z is None else [z[0], z[1]]


def _screw_end_dict(side: str, e: "ScrewEnd") -> dict[str, Any]:
    """One screw end of the ``actuator`` section (mm, screw frame)."""
    key = None if e.key is None else {"width_mm": e.key.width_mm, "height_mm": e.key.height_mm,
                                      "shaft_depth_mm": e.key.shaft_depth_mm, "z_mm": _span(e.key_z)}
    return {
        "side": side, "role": e.role, "run_out_mm": _span(e.run_out), "tip_z_mm": e.tip_z,
        "support_z_mm": e.support_z,
        "steps": [{"name": st.name, "z_mm": _span(st.z), "diameter_mm": st.diameter_mm} for st in e.steps],
        "bearings": [{"designation": b.designation, "bore_mm": b.size.bore_mm,
                      "outer_diameter_mm": b.size.outer_diameter_mm, "width_mm": b.size.width_mm,
                      "z_mm": _span(b.z)} for b in e.bearings],
        "seat_tolerance": e.seat_tolerance,
        "locknut": None if e.locknut is None else {
            "designation": e.locknut.designation, "thread": e.locknut.thread,
            "tolerance_class": e.locknut_tolerance, "outer_diameter_mm": e.locknut.outer_diameter_mm,
            "width_mm": e.locknut.width_mm, "z_mm": _span(e.locknut_z)},
        "shaft_ring": None if e.ring is None else {
            "designation": e.ring.designation, "groove_diameter_mm": e.ring.groove_diameter_mm,
            "groove_width_mm": e.ring.groove_width_mm, "z_mm": _span(e.ring_z)},
        "drive_key": key,
        "drive_flat": None if e.flat_depth_mm is None else {"depth_mm": e.flat_depth_mm, "z_mm": _span(e.key_z)},
        "drive_fit": e.drive_fit,
    }


def actuator_section(stage: "ActuatorStage") -> dict[str, Any]:
    """The ``actuator`` section: stroke, screw ends, nut mounting, supports, every size with
    its source, and the stroke-end checks (mm, screw frame, nut at mid-stroke)."""
    lay = stage.layout
    m, sup = lay.nut_mount, lay.supports
    mount: dict[str, Any] = {"kind": m.kind, "z_mm": _span(m.z)}
    if m.bolt is not None:
        mount.update(bolt=m.bolt.name, bolt_count=m.bolt_count, clearance_hole_mm=m.bolt.clearance_hole_mm,
                     bolt_circle_diameter_mm=m.bolt_circle_diameter_mm, flange_diameter_mm=m.flange_diameter_mm,
                     bolt_length_mm=m.bolt_length_mm)
    checks = [{"stroke_end": c.stroke_end, "what": c.what, "kind": c.kind, "clearance_mm": c.clearance_mm,
               "passed": c.passed} for c in stage.checks]
    return {
        "stroke_mm": lay.stroke_mm, "over_travel_mm": lay.over_travel_mm, "nut_shifts_mm": list(lay.shifts),
        "screw_length_mm": lay.screw_length_mm, "threaded_length_mm": lay.threaded_length_mm,
        "screw_z_mm": list(lay.screw_z), "thread_z_mm": list(lay.thread_z), "full_thread_z_mm": list(lay.full_thread_z),
        "nut_assembly_z_mm": list(lay.nut_assembly_z), "screw_run_out_mm": lay.screw_run_out_mm,
        "thread_chamfer_mm": lay.thread_chamfer_mm, "fixed_end": "lo" if lay.fixed_side < 0 else "hi",
        "ends": [_screw_end_dict(side, e) for side, e in zip(("lo", "hi"), lay.ends)],
        "nut_mount": mount,
        "supports": {"critical_speed_length_mm": sup.critical_speed_length_mm,
                     "critical_speed_ends": sup.critical_speed_ends, "buckling_length_mm": sup.buckling_length_mm,
                     "buckling_ends": sup.buckling_ends, "worst_stroke_end": sup.worst_stroke_end, "rule": sup.rule},
        "sizes": [{"key": k, "value": v.value, "source": v.source} for k, v in lay.sizes.items()],
        "stroke_end_checks": checks,
        "passed": all(c["passed"] for c in checks),
    }


# --------------------------------------------------------------------------- rating
#: How the ratings are computed, as the ``rating`` section says.
RATING_METHOD = ("Lundberg-Palmgren point contact per tooth-contact ring (docs/theory/ratings.md): constant "
                 "calibrated on the closed-form ball-raceway capacity 98.1 (N, mm) of ISO 281 / ISO 3408-5")

#: The sentence of each failed limit check (:data:`prs_geom.analysis.rating.LIMIT_CHECKS`),
#: ``{v}`` the value and ``{l}`` the limit.
LIMIT_MESSAGES = {
    "speed": "speed {v} rpm exceeds the permissible {l} rpm (the smaller of the d n limit and the critical speed "
             "limit)",
    "dn": "d n = nominal diameter x speed = {v} mm/min exceeds the nut speed limit rating.dn_limit_mm_rpm = "
          "{l} mm/min",
    "critical_speed": "speed {v} rpm exceeds the permissible critical speed {l} rpm (supports.critical_speed_factor "
                      "x the first whirling speed)",
    "buckling": "axial load {v} N exceeds the permissible buckling load {l} N (Euler load / "
                "supports.buckling_safety)",
    "static_safety": "static safety s0 = C_0a / F_max = {v} is below the required {l} "
                     "(rating.required_static_safety)",
}


def _plain(x: float) -> str:
    """A number as an engineer writes it: whole from 1000 up (10000, 13215714), 4 significant
    digits from 0.001 to 1000, else scientific (4.72e-05)."""
    if abs(x) >= 1000.0:
        return f"{x:.0f}"
    return f"{x:.4g}" if abs(x) >= 1e-3 else f"{x:.3g}"


def limit_warnings(checks: "Sequence[LimitCheck]") -> list[str]:
    """One sentence per failed check, e.g. "speed 10000 rpm exceeds the permissible 6250 rpm
    (...)"."""
    return [LIMIT_MESSAGES[c.name].format(v=_plain(c.value), l=_plain(c.limit)) for c in checks if not c.passed]


def limit_check_dict(c: "LimitCheck") -> dict[str, Any]:
    """One entry of ``rating.limits.checks``."""
    return {"name": c.name, "kind": c.kind, "value": c.value, "limit": c.limit, "unit": c.unit, "margin": c.margin,
            "passed": c.passed}


def _variant_life(v: "VariantLife") -> dict[str, Any]:
    return {"l10_revolutions": v.l10_revolutions, "l10_hours": v.l10_hours,
            "life_ratio_to_equal_sharing": v.life_ratio_to_equal_sharing,
            "max_hertz_pressure_mpa": v.max_hertz_pressure_mpa, "static_safety": v.static_safety,
            "hertz_pressure_mpa": {"roller_screw": v.pressure_roller_screw_mpa.tolist(),
                                   "nut_roller": v.pressure_nut_roller_mpa.tolist()},
            "gain_over_constant_pitch_hours": v.gain_over_constant_pitch_hours,
            "gain_factor_over_constant_pitch": v.gain_factor_over_constant_pitch}


def _rating_limits(r: "RatingResult") -> dict[str, Any]:
    lim, sup = r.limits, r.supports
    res = lim.supports
    return {"unsupported_length_mm": res.critical_speed_length_mm, "root_diameter_mm": lim.root_diameter_mm,
            "buckling_length_mm": res.buckling_length_mm, "supports_source": res.source, "supports_rule": res.rule,
            "critical_speed_ends": res.critical_speed_ends, "critical_speed_rpm": lim.critical_speed_rpm,
            "critical_speed_factor": sup.critical_speed_factor,
            "permissible_critical_speed_rpm": lim.permissible_critical_speed_rpm,
            "dn_limit_mm_rpm": lim.dn_limit_mm_rpm, "dn_speed_limit_rpm": lim.dn_speed_limit_rpm,
            "permissible_speed_rpm": lim.permissible_speed_rpm, "max_speed_rpm": lim.max_speed_rpm,
            "speed_ok": lim.speed_ok, "buckling_ends": res.buckling_ends, "buckling_load_n": lim.buckling_load_n,
            "buckling_safety": sup.buckling_safety, "permissible_buckling_load_n": lim.permissible_buckling_load_n,
            "buckling_ok": bool(r.max_load_n <= lim.permissible_buckling_load_n),
            "required_static_safety": r.settings.required_static_safety,
            "checks": [limit_check_dict(c) for c in r.checks], "all_passed": r.all_passed}


def _rating_drive(r: "RatingResult") -> dict[str, Any]:
    lim = r.limits
    return {**lim.efficiency, "friction_coefficient": r.settings.friction_coefficient, "lead_mm": lim.lead_mm,
            "torque_load_n": r.max_load_n, "drive_torque_nm": lim.drive_torque_nm,
            "back_drive_torque_nm": lim.back_drive_torque_nm, "holding_torque_nm": lim.back_drive_torque_nm}


def _rating_stiffness(r: "RatingResult") -> tuple[dict[str, Any], dict[str, Any]]:
    """The ``stiffness`` (single nut) and ``double_nut`` entries."""
    st = r.stiffness
    single = {"pitch_lists": st.pitch_lists, "load_n": st.load_n.tolist(),
              "axial_deflection_um": (st.deflection_mm * 1e3).tolist(), "secant_n_per_um": st.secant.tolist(),
              "tangent_n_per_um": st.tangent.tolist()}
    double = {"preload_n": st.preload_n, "preload_source": "rating.preload_n" if r.settings.preload_n is not None
              else "loading.axial_load_n / 2^(3/2)", "lift_off_load_n": float(st.double_nut["lift_off_n"]),
              "load_n": st.external_n.tolist(), "displacement_um": (st.displacement_mm * 1e3).tolist(),
              "stiffness_n_per_um": st.double_nut_stiffness.tolist(),
              "single_nut_displacement_um": (st.single_displacement_mm * 1e3).tolist()}
    return single, double


def rating_section(r: "RatingResult") -> dict[str, Any]:
    """The ``rating`` section: ratings, catalogue life of the duty, the life of each pitch
    variant, limits with their checks, efficiency and torques, stiffness single and double nut."""
    case = r.case
    stiffness, double = _rating_stiffness(r)
    return {
        "method": RATING_METHOD, "dynamic_load_rating_n": r.dynamic_load_rating_n,
        "static_load_rating_n": r.static_load_rating_n,
        "static_pressure_limit_mpa": r.settings.static_pressure_limit_mpa, "static_safety": r.static_safety,
        "max_load_n": r.max_load_n, "equivalent_load_n": case.equivalent_load_n,
        "equivalent_speed_rpm": case.equivalent_speed_rpm, "operating_factor": case.operating_factor,
        "reliability_pct": case.reliability_pct, "reliability_factor": r.reliability_factor,
        "l10_revolutions": r.l10_revolutions, "l10_hours": r.l10_hours, "target_life_hours": case.life_hours,
        "required_dynamic_load_n": r.required_dynamic_load_n, "duty_source": case.source,
        "duty_cases": [{"load_n": float(F), "revolution_weight": float(w), "speed_rpm": float(n)}
                       for F, w, n in zip(case.loads_n, case.weights, case.speeds_rpm)],
        "rings": r.rings.as_dict(),
        "calibration": {"constant": r.calibration_constant, "spread_to_closed_form": list(r.calibration_spread)},
        "distribution_life": {k: _variant_life(v) for k, v in r.distribution_life.items()},
        "robust": None if r.robust_computed else (r.robust_note or "not computed"),
        "limits": _rating_limits(r), "efficiency": _rating_drive(r), "stiffness": stiffness, "double_nut": double,
    }


def roller_loads_dict(result: RollerLoadResult) -> dict[str, Any]:
    """One solution of the per-roller solver: load coefficients of the tooth positions (n,)
    per side, per roller (z, n), roller load shares (z,) and the largest coefficient."""
    per = result.ldc_per_roller
    return {"ldc_nut_roller": result.ldc_nr.tolist(), "ldc_roller_screw": result.ldc_rs.tolist(),
            "ldc_per_roller": {k: v.tolist() for k, v in per.items()},
            "roller_load_share": result.roller_load_share.tolist(),
            "max_ldc": float(max(per["nut_roller"].max(), per["roller_screw"].max()))}


# --------------------------------------------------------------------------- tolerance
#: What the numbers of the ``tolerance`` section mean.
TOLERANCE_DEFINITIONS = {
    "worst_ldc": "per sample: the largest tooth load of any roller, tooth and side, divided by "
                 "the mean tooth load F / (n z), over every load of the study",
    "roller_load_share": "load of a roller divided by F / z (1 = equal sharing)",
    "importance": "variance of the worst coefficient with one error group switched on at a "
                  "time (same draws), as shares of their sum",
}


def tolerances_dict(t: "Tolerances", n: int) -> dict[str, Any]:
    """The error model ``t`` as the report writes it, with the per-tooth flank tolerances of n teeth (um)."""
    d = {k: getattr(t, k) for k in ("distribution", "flank_um", "roller_diameter_um", "screw_eccentricity_um",
                                    "nut_eccentricity_um", "lead_um", "temperature_k", "source")}
    per = t.flank_tolerances_um(n)
    d["per_tooth_flank_um"] = {k: list(v) for k, v in per.items()}
    if t.target_ldc is not None:
        d["target_ldc"] = t.target_ldc
    if t.confidence is not None:
        d["confidence"] = t.confidence
    return d


def _tolerance_cases(study: Any) -> list[dict[str, Any]]:
    from prs_geom.analysis import tolerance as tol

    stats, det, F0 = study.stats, study.deterministic, study.design_load_n
    return [{"load_fraction": F / F0, "load_N": F,
             "worst_ldc": tol.summary(stats.worst[i]),
             "nut_roller": tol.summary(stats.worst_nr[i]),
             "roller_screw": tol.summary(stats.worst_rs[i]),
             "roller_load_share_max": tol.summary(stats.share_max[i]),
             "roller_load_share_min": tol.summary(stats.share_min[i]),
             "deterministic": {"nut_roller": float(det[i, 0]), "roller_screw": float(det[i, 1]),
                               "worst_ldc": float(det[i].max())},
             "samples_with_open_teeth": int((stats.open_teeth[i] > 0).sum())}
            for i, F in enumerate(study.loads_n)]


def tolerance_section(study: Any) -> dict[str, Any]:
    """The ``tolerance`` section of a :class:`prs_geom.studies.ToleranceStudy`: the error
    model, the worst coefficient and the roller load shares over the samples, per load and
    overall, the importance ranking and, with a confidence, the quantile it holds."""
    from prs_geom.analysis import tolerance as tol

    stats, F0 = study.stats, study.design_load_n
    out = {
        "samples": int(stats.worst.shape[1]), "seed": study.tolerances.seed,
        "chunk_samples": study.chunk_samples,
        "tolerances": tolerances_dict(study.tolerances, study.engaged_teeth),
        "load_fractions": [F / F0 for F in study.loads_n],
        "worst_ldc": tol.summary(stats.worst.max(axis=0)),
        "deterministic_worst_ldc": float(study.deterministic.max()),
        "sides": {"nut_roller": tol.summary(stats.worst_nr.max(axis=0)),
                  "roller_screw": tol.summary(stats.worst_rs.max(axis=0))},
        "roller_load_share": {"max": tol.summary(stats.share_max.max(axis=0)),
                              "min": tol.summary(stats.share_min.min(axis=0))},
        "cases": _tolerance_cases(study),
        "importance": study.importance,
        "definitions": dict(TOLERANCE_DEFINITIONS),
    }
    if study.confidence is not None:
        out["at_confidence"] = {
            "confidence": study.confidence, "worst_ldc_quantile": study.worst_quantile,
            "upper_bound_95": study.quantile_upper_bound,
            "meaning": f"the worst LDC stays below worst_ldc_quantile in a fraction {study.confidence:g} of the "
                       f"samples; upper_bound_95 bounds that quantile of the population with 95 % "
                       f"confidence (order statistic; null if the sample is too small)"}
    return out


def synthesis_section(result: Any) -> dict[str, Any]:
    """A :class:`prs_geom.studies.SynthesisResult` as report.json's ``tolerance.synthesis``
    (tolerances in um)."""
    return {"target_ldc": result.target_ldc, "confidence": result.confidence,
            "confidence_bound": f"one-sided Clopper-Pearson lower bound at {result.bound_level:.0%}",
            "feasible": result.feasible, "uniform_flank_um": result.uniform_um,
            "per_tooth_flank_um": {k: list(v) for k, v in result.allocation_um.items()},
            "influence_ldc_per_um": {k: v.tolist() for k, v in result.influence_per_um.items()},
            "checks": result.checks}


def robust_section(result: Any) -> dict[str, Any]:
    """A :class:`prs_geom.studies.RobustResult`: the chosen family member and the comparison."""
    return {"a_nut_roller": result.a_nr, "a_roller_screw": result.a_rs, "evaluations": result.evaluations,
            **result.comparison}


# --------------------------------------------------------------------------- loads
def _hertz(h: HertzContact) -> dict[str, float]:
    return {"sum_rho_per_mm": h.sum_rho_per_mm, "F_rho": h.F_rho, "ellipticity_k": h.ellipticity_k,
            "semi_major_per_cbrt_N_mm": h.semi_major_per_cbrt_N_mm,
            "semi_minor_per_cbrt_N_mm": h.semi_minor_per_cbrt_N_mm,
            "circumferential_semi_axis_per_cbrt_N_mm": h.circumferential_semi_axis_per_cbrt_N_mm,
            "normal_axial_component": h.normal_axial_component, "C_normal": h.C_normal}


def _tooth(t: ToothTerms) -> dict[str, float]:
    return {"a_mm": t.a_mm, "b_mm": t.b_mm, "c_mm": t.c_mm, "width_mm": t.width_mm, "bending": t.bending,
            "shear": t.shear, "root_tilt": t.root_tilt, "root_shear": t.root_shear, "radial": t.radial}


def _fe_summary(fe: FeSummary, cache: Mapping[str, Any] | None) -> dict[str, Any]:
    out = {"model": "fe", "mesh_level": fe.mesh_level, "teeth": fe.teeth, "n_dofs": fe.n_dofs,
           "parts": {name: {"n_dofs": p.n_dofs, "asymmetry": p.asymmetry, "seconds": p.seconds,
                            "body_per_pitch_ratio_to_1d": p.body_per_pitch_ratio_to_1d}
                     for name, p in fe.parts.items()},
           "pair_compliance_middle_tooth_mm_per_N": dict(fe.pair_compliance_middle_tooth_mm_per_N),
           "pair_compliance_uniform_mm_per_N": dict(fe.pair_compliance_uniform_mm_per_N),
           "yamamoto_mm_per_N": dict(fe.yamamoto_mm_per_N),
           "eigenvalues_mm_per_N": list(fe.eigenvalues_mm_per_N), "variant": fe.variant, "bodies": fe.bodies,
           "local_term_reference_of_b": fe.local_reference, "unloaded_teeth_screw_roller": list(fe.extension_teeth),
           "nut_end_lengths_mm": list(fe.nut_end_lengths_mm)}
    if cache is not None:
        out["cache"] = dict(cache)
    return out


def load_details_dict(details: LoadModelDetails | None, cache: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """``loads.compliances.details``: what the load model was made from. ``cache``: where the
    FE influence matrices came from (:meth:`prs_geom.analysis.fe.cache.CachedInfluence.report`), shown
    inside the FE summary."""
    if details is None:
        return {}
    out: dict[str, Any] = {
        "tooth_width": details.tooth_width, "hertz_rs": _hertz(details.hertz_rs),
        "hertz_nr": _hertz(details.hertz_nr), "tooth_screw": _tooth(details.tooth_screw),
        "tooth_roller_screw_side": _tooth(details.tooth_roller_screw_side),
        "tooth_roller_nut_side": _tooth(details.tooth_roller_nut_side), "tooth_nut": _tooth(details.tooth_nut),
        "section_areas_mm2": {"screw": details.section_areas_mm2.screw, "roller": details.section_areas_mm2.roller,
                              "nut": details.section_areas_mm2.nut}}
    if details.compliance is not None:
        out["compliance"] = details.compliance
    if details.fe is not None:
        out["fe"] = _fe_summary(details.fe, cache)
    return out


def constant_pitch_section(dist: LoadDistribution) -> dict[str, Any]:
    """``loads.constant_pitch``: the coefficients of both sides with constant pitch and the
    worst of them."""
    rc = dist.constant_pitch
    return {"ldc_nut_roller": rc.ldc_nr.tolist(), "ldc_roller_screw": rc.ldc_rs.tolist(),
            "max_ldc": float(max(rc.ldc_nr.max(), rc.ldc_rs.max())),
            "max_ldc_nut_roller": float(rc.ldc_nr.max()), "max_ldc_roller_screw": float(rc.ldc_rs.max())}


def loads_section(dist: LoadDistribution, cache: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The ``loads`` section: coefficients and tooth loads at the design load, constant
    pitch, the linear model, stiffness, off-design, sensitivity and the compliances.
    ``cache``: as for :func:`load_details_dict`."""
    r, lin, model = dist.result, dist.linear, dist.model
    return {
        "design_load_N": dist.design_load_n,
        "installation": dist.installation,
        "ldc_nut_roller": r.ldc_nr.tolist(),
        "ldc_roller_screw": r.ldc_rs.tolist(),
        "max_ldc": dist.max_ldc,
        "max_ldc_nut_roller": float(r.ldc_nr.max()),
        "max_ldc_roller_screw": float(r.ldc_rs.max()),
        "tooth_loads_N": {"nut_roller": r.f_nr.tolist(), "roller_screw": r.f_rs.tolist()},
        "teeth_out_of_contact": int((~r.active_nr).sum() + (~r.active_rs).sum()),
        "axial_stiffness_N_per_um": dist.stiffness["secant_N_per_um"],
        "axial_stiffness": dist.stiffness,
        "constant_pitch": constant_pitch_section(dist),
        "linear_model": {"ldc_nut_roller": lin.ldc_nr.tolist(), "ldc_roller_screw": lin.ldc_rs.tolist(),
                         "linearised_at_N": r.mean},
        "off_design": dist.off_design,
        "sensitivity": dist.sensitivity,
        "compliances": {"model": compliance_model(model), "hertz_nr_mm_per_N2/3": model.hertz_nr,
                        "hertz_rs_mm_per_N2/3": model.hertz_rs,
                        "tooth_nr_mm_per_N": model.tooth_nr, "tooth_rs_mm_per_N": model.tooth_rs,
                        "body_screw_mm_per_N": model.body_screw, "body_roller_mm_per_N": model.body_roller,
                        "body_nut_mm_per_N": model.body_nut, "details": load_details_dict(model.details, cache)},
        "solver_iterations": r.iterations,
    }


#: The ``model_risk`` section of a build that did not compute it.
MODEL_RISK_NOT_COMPUTED = {
    "computed": False,
    "note": "not computed: the model risk compares the analytic and the finite-element compliance; build with "
            "--compliance fe (or loads.compliance = \"fe\"; needs pip install \"prs-geom[fe]\")"}


def _model_risk_case(c: ModelRiskCase) -> dict[str, Any]:
    return {"pitch_lists": c.pitch_lists, "designed_with": c.designed_with,
            "evaluated_with": c.evaluated_with, "load_fraction": c.load_fraction, "load_N": c.load_n,
            "ldc_nut_roller": c.ldc_nut_roller.tolist(), "ldc_roller_screw": c.ldc_roller_screw.tolist(),
            "max_ldc_nut_roller": float(c.ldc_nut_roller.max()),
            "max_ldc_roller_screw": float(c.ldc_roller_screw.max()),
            "min_ldc_nut_roller": float(c.ldc_nut_roller.min()),
            "min_ldc_roller_screw": float(c.ldc_roller_screw.min()),
            "max_ldc": float(max(c.ldc_nut_roller.max(), c.ldc_roller_screw.max())),
            "teeth_out_of_contact": c.teeth_out_of_contact}


def model_risk_section(risk: ModelRisk | None) -> dict[str, Any]:
    """The ``model_risk`` section: every set of pitch lists under every compliance model, or
    :data:`MODEL_RISK_NOT_COMPUTED` (a copy) when ``risk`` is None."""
    if risk is None:
        return dict(MODEL_RISK_NOT_COMPUTED)
    return {"computed": True, "models": list(risk.models), "main_model": "fe",
            "designed_with": list(risk.designed_with), "descriptions": dict(risk.descriptions),
            "design_load_N": risk.design_load_n,
            "load_fractions": list(risk.load_fractions),
            "largest_model_difference": risk.largest_model_difference,
            "cases": [_model_risk_case(c) for c in risk.cases]}


# --------------------------------------------------------------------------- inspection
def inspection_section(parts: Mapping[str, "PartInspection"]) -> dict[str, dict[str, Any]]:
    """The ``inspection`` section: every value of each part's inspection (units in the key
    names), the reference temperature and whether the numerical check passed."""
    from dataclasses import fields

    return {part: {**{f.name: getattr(r, f.name) for f in fields(r)}, "reference_temperature_degc": 20.0,
                   "check_passed": r.check_passed} for part, r in parts.items()}


# --------------------------------------------------------------------------- mechanism
def mechanism_section(m: "MechanismCheck") -> dict[str, Any]:
    """The ``mechanism`` section: sizes, fits, journal clearances, stack-up, and a pass/fail
    list of the checks."""
    lay, ring = m.layout, m.layout.ring
    checks = [{"name": name, "passed": ok} for name, ok in m.checks]
    return {
        "journal_diameter_mm": lay.journal_diameter_mm,
        "carrier": {"inner_diameter_mm": 2 * lay.carrier_inner_radius_mm,
                    "outer_diameter_mm": 2 * lay.carrier_outer_radius_mm,
                    "thickness_mm": lay.carrier_thickness_mm},
        "retaining_ring": {"designation": m.ring_designation, "bore_mm": ring.bore_mm,
                           "thickness_mm": ring.thickness_mm, "groove_diameter_mm": ring.groove_diameter_mm,
                           "groove_width_mm": ring.groove_width_mm, "edge_distance_mm": ring.edge_distance_mm,
                           "section_width_mm": ring.section_width_mm},
        "nut_end": {"bore_diameter_mm": 2 * lay.nut_bore_radius_mm, "length_mm": lay.ends[0].nut_end[1]
                    - lay.ends[0].nut_end[0]},
        "axial_layout_mm": [{"end": side, "gear": list(e.gear_zone), "journal": list(e.journal),
                             "carrier": list(e.carrier), "retaining_ring": list(e.ring),
                             "groove": list(e.groove), "nut_end": list(e.nut_end)}
                            for side, e in zip(("lo", "hi"), lay.ends)],
        "fits": [f.report() for f in m.fits],
        "journal_clearances": list(m.journal_clearances),
        "stack_up": lay.stack.report(),
        "checks": checks,
        "passed": all(c["passed"] for c in checks),
    }


# --------------------------------------------------------------------------- build results
#: Version of the report.json layout (``format_version``); the JSON Schema
#: ``prs_geom/exports/schemas/report.schema.json`` describes it.
REPORT_FORMAT_VERSION = 1


@dataclass(frozen=True)
class ActuatorStage:
    """The actuator of a build: its layout and the stroke-end checks
    (:func:`prs_geom.geometry.actuator.stroke_end_checks`)."""

    layout: "ActuatorLayout"
    checks: "tuple[StrokeEndCheck, ...]"


@dataclass(frozen=True)
class PitchLists:
    """The pitch lists of the three parts (mm, tooth 1 at the loaded end)."""

    screw_mm: tuple[float, ...]
    roller_mm: tuple[float, ...]
    nut_mm: tuple[float, ...]


@dataclass(frozen=True)
class MeshStage:
    """The meshes stage: the assembly at the design's chord tolerance (its checks are
    :attr:`BuildResults.mesh_checks`)."""

    assembly: "Assembly"
    #: the 3D view of report.html: the assembly at the display tolerance
    #: (:func:`prs_geom.exports.html.scene_payload`; None: made when the page is written)
    scene: dict[str, Any] | None = None


@dataclass(frozen=True)
class ChecksResult:
    """The checks of a build: the FCL verification of the contacts (``checks.fcl``) and the
    interference check (``checks.interference``), as those checks report them."""

    fcl: dict[str, Any]
    interference: dict[str, Any]


@dataclass
class BuildResults:
    """Each stage's result of a build (None: the stage did not run or has nothing for this
    design), filled in stage order; the exports render report.json and report.html from it.

    ``warnings`` is the build's warning list (the design's sizing warnings first, then each
    stage's, in stage order); ``fe_cache``: where the FE influence matrices of the loads stage
    came from (:meth:`prs_geom.analysis.fe.cache.CachedInfluence.report`; None for the analytic model).
    """

    design: Any
    #: ``"prs"`` or ``"harmonic"`` (the product line of ``design``)
    kind: str = "prs"
    warnings: list[str] = field(default_factory=list)
    pitch: PitchLists | None = None
    contact: ContactResult | None = None
    gears: "GearAnalysis | None" = None
    loads: LoadsResult | None = None
    fe_cache: dict[str, Any] | None = None
    rating: "RatingResult | None" = None
    #: the tolerance study (:class:`prs_geom.studies.ToleranceStudy`, a layer above the exports)
    tolerance: Any = None
    meshes: MeshStage | None = None
    #: ``checks.meshes``: each part mesh against its analytic surface
    #: (:func:`prs_geom.mesh.thread.mesh_report` rows; the checks stage's, or the meshes
    #: stage's in a build without checks)
    mesh_checks: list[dict[str, Any]] | None = None
    #: (part, what the STEP writer returned) per STEP file of a ``--step`` build (:func:`step_section`)
    step: tuple[tuple[str, dict[str, Any]], ...] | None = None
    #: the STEP assembly's report entry (:func:`prs_geom.exports.step_assembly.write_step_assembly`)
    step_assembly: dict[str, Any] | None = None
    mechanism: "MechanismCheck | None" = None
    actuator: "ActuatorStage | None" = None
    kinematics: "Kinematics | None" = None
    parts_list: list["PartsListRow"] | None = None
    checks: ChecksResult | None = None
    inspection: dict[str, "PartInspection"] | None = None
    machining: dict[str, "MachiningSheet"] | None = None
    #: the harmonic line: its ``harmonic`` section, mesh checks, ``assembly`` section and
    #: assembly checks (``checks.assembly``)
    harmonic: dict[str, Any] | None = None
    harmonic_meshes: list[dict[str, Any]] | None = None
    harmonic_assembly: dict[str, Any] | None = None
    harmonic_assembly_checks: dict[str, Any] | None = None
    #: every file written, in writing order (output-relative paths)
    files: list[str] = field(default_factory=list)
    #: each stage's time (s), by stage name in run order
    timings_s: dict[str, float] = field(default_factory=dict)


def check_warnings(mesh_checks: list[dict[str, Any]] | None, checks: ChecksResult | None = None) -> list[str]:
    """Every check whose measured difference exceeds its documented tolerance, as one line
    each: the ``warnings`` of the mesh checks (rows of ``checks.meshes``) and of the FCL
    verification."""
    out = []
    for row in mesh_checks or []:
        out += [f"mesh check ({row['part']}): {w}" for w in row.get("warnings", [])]
    fcl_check = checks.fcl if checks is not None else {}
    out += [f"FCL check: {w}" for w in (fcl_check or {}).get("warnings", [])]
    return out


def assembly_section(results: BuildResults) -> dict[str, Any]:
    """The ``assembly`` section: the placed parts, the rollers' carrier angles and spins (deg)
    and the triangle count of the meshes stage's assembly."""
    from prs_geom.geometry.frames import carrier_angles, roller_spin

    d, asm = results.design, results.meshes.assembly
    return {
        "parts": list(asm.placed),
        "roller_carrier_angles_deg": [float(np.degrees(a)) for a in carrier_angles(d)],
        "roller_spin_deg": [float(np.degrees(roller_spin(d, a)) % 360.0) for a in carrier_angles(d)],
        "triangles": int(sum(m.faces.shape[0] for m, _, _ in asm.placed.values())),
        "complete_parts": [part.report() for part in asm.complete_parts().values()],
    }


def _pitch_section(results: BuildResults) -> dict[str, Any] | None:
    """The ``pitch`` section: the pitch lists, with the equal-load lists of the loads stage."""
    if results.pitch is None:
        return None
    out: dict[str, Any] = {"screw_mm": list(results.pitch.screw_mm), "roller_mm": list(results.pitch.roller_mm),
                           "nut_mm": list(results.pitch.nut_mm)}
    if results.loads is not None:
        equal = results.loads.equal_load
        out["equal_load"] = {"roller_mm": list(equal.roller_mm), "nut_mm": list(equal.nut_mm)}
    return out


def _checks_section(results: BuildResults) -> dict[str, Any]:
    """The ``checks`` section: the mesh checks, the FCL verification and the interference
    check, those that ran."""
    out: dict[str, Any] = {}
    if results.harmonic_meshes is not None:
        out["meshes"] = results.harmonic_meshes
    if results.harmonic_assembly_checks is not None:
        out["assembly"] = results.harmonic_assembly_checks
    if results.mesh_checks is not None:
        out["meshes"] = results.mesh_checks
    if results.checks is not None:
        out.update({"fcl": results.checks.fcl, "interference": results.checks.interference})
    return out


def _harmonic_report(results: BuildResults) -> dict[str, Any]:
    from prs_geom._version import __version__
    from prs_geom.model.io import design_to_dict

    out = {"format_version": REPORT_FORMAT_VERSION, "prs_geom_version": __version__, "kind": "harmonic",
           "design": design_to_dict(results.design), "warnings": results.warnings, "harmonic": results.harmonic,
           "checks": _checks_section(results), "timings_s": results.timings_s, "files": results.files}
    if results.harmonic_assembly is not None:
        out["assembly"] = results.harmonic_assembly
    return out


def _stage_sections(results: BuildResults) -> dict[str, Any]:
    """The sections of the stages that ran and have one, in stage order."""
    out: dict[str, Any] = {}
    if results.gears is not None:
        out["gears"] = gears_section(results.gears)
    if results.loads is not None:
        out["model_risk"] = model_risk_section(results.loads.model_risk)
    if results.rating is not None:
        out["rating"] = rating_section(results.rating)
    if results.tolerance is not None:
        out["tolerance"] = tolerance_section(results.tolerance)
    if results.meshes is not None:
        out["assembly"] = assembly_section(results)
    if results.step is not None:
        out["step"] = step_section(results.step)
        if results.step_assembly is not None:
            out["step"]["assembly"] = results.step_assembly
    if results.mechanism is not None:
        out["mechanism"] = mechanism_section(results.mechanism)
    if results.actuator is not None:
        out["actuator"] = actuator_section(results.actuator)
    if results.kinematics is not None:
        out["kinematics"] = results.kinematics.as_dict()
    if results.parts_list is not None:
        out["parts_list"] = [r.as_dict() for r in results.parts_list]
    if results.inspection is not None:
        out["inspection"] = inspection_section(results.inspection)
    return out


def report_dict(results: BuildResults) -> dict[str, Any]:
    """report.json of a build from its results: the layout of
    ``prs_geom/exports/schemas/report.schema.json``, sections in stage order (a stage that did
    not run leaves its skeleton entry None, or has no entry)."""
    if results.kind == "harmonic":
        return _harmonic_report(results)
    from prs_geom._version import __version__
    from prs_geom.model.io import design_to_dict

    return {
        "format_version": REPORT_FORMAT_VERSION,
        "prs_geom_version": __version__,
        "design": design_to_dict(results.design),
        "warnings": results.warnings,
        "contact": contact_section(results.contact) if results.contact is not None else None,
        "loads": loads_section(results.loads.distribution, results.fe_cache) if results.loads is not None else None,
        "pitch": _pitch_section(results),
        "checks": _checks_section(results),
        "machining": ({part: sh.as_dict() for part, sh in results.machining.items()}
                      if results.machining is not None else None),
        "timings_s": results.timings_s,
        "files": results.files,
        **_stage_sections(results),
    }
