"""Pitch-modification machining data for roller and nut (docs/theory/manufacturing.md).

Pure math, no I/O; the sheets are written by :mod:`prs_geom.sheets`.

Process, per part:

1. Cut the thread at constant pitch p_b = the smallest pitch of the part's list, with a tooth
   thickness stock of Delta_n (the largest cumulative shift, below), so the base tooth j has
   its mid-plane at (j - 1) p_b + Delta_n / 2 from the datum.
2. Grind each flank to its designed position. Grinding only removes material, so a lower
   flank (facing -z, toward the loaded end) can only move +z and an upper flank only -z.
   With Delta_j = z_j - (j - 1) p_b >= 0 (z_j the designed position of tooth j, increasing in
   j because every p_j >= p_b):
   * lower flank: axial shift +Delta_j (datum tooth 1, shift 0);
   * upper flank: axial shift Delta_j - Delta_n <= 0 (datum tooth n, shift 0).
   Both flanks of every tooth end at the designed positions with the designed thickness,
   matching the geometry model (rigid teeth on a warped helix coordinate).

Normal stock at the contact point = |axial shift| * |n_z|, n_z the axial component of the
unit contact normal from the contact solver (roller lower flank and nut flanks: roller-nut
contact; roller upper flank: screw-roller contact with the theoretical screw).

Datums: A, the loaded-side end face (z = 0 of the part frame, a physical face of both
parts), and B, the mid-plane of the radial slot cut into A at theta = 0
(:mod:`prs_geom.geometry.datum`). Every position on the sheet is a
flank's axial position at the pitch diameter, at theta = 0, from A: designed, and on the base
cut (tooth 1's mid-plane lies p/2 from A on the roller and on A on the nut, so the nut's
tooth 1 lower flank is not on the part there: ``on_part`` marks it); the axial shift
is their difference. Inspection value: the
designed flank position (mm). Per-flank tolerances come from the design's ``[tolerances]``
(e.g. written by a tolerance synthesis), else "not synthesised". All lengths at 20 degC.
Loaded flanks (load path of :mod:`prs_geom.loads`): roller upper flank by the screw, roller
lower flank by the nut; nut upper flank by the roller. The nut's lower flank carries no
load; grinding it keeps the designed tooth thickness and may be skipped.

Numbers on the sheets: every length in mm is rounded to 1e-9 mm (``round(x, 9)``)
and every length in um to 1e-6 um (``round(x, 6)``), the same 1 pm, a thousandth of the
smallest pitch correction that matters, so that no sheet carries float noise such as
0.49999999999999956. The designed and base flank positions are rounded first and the axial
shift is derived from the rounded pair, shift_um = round((designed - base) x 1000, 6), so that
on every row, read back from the CSV with Python's float(),
``round(base + shift / 1000, 9) == designed`` holds exactly (and |base + shift / 1000 -
designed| < 1e-12 mm); the sign of the shift and the 0 of the datum flanks survive the
rounding (it is monotone). Pitches, thicknesses, stock and lead deviations follow the same
rule; a pitch on the sheet may therefore differ from the design file's by up to 5e-10 mm.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from prs_geom.analysis.contact import ContactResult, analyse_contact
from prs_geom.model.design import PRSDesign, Tolerances
from prs_geom.geometry.datum import datum_mark
from prs_geom.geometry.profiles import ThreadProfile, ThreadProfiles

__all__ = ["COLUMNS", "REFERENCE_TEMPERATURE_C", "MM_DECIMALS", "UM_DECIMALS", "mm", "um", "MachiningSheet",
           "start_table", "INDEXING", "machining_sheet", "machining_sheets"]

COLUMNS = [
    ("tooth", "tooth", ""),
    ("flank", "flank", ""),
    ("loaded_by", "loaded by", ""),
    ("designed_pitch_mm", "designed pitch to next tooth", "mm"),
    ("base_pitch_mm", "base pitch (first cut)", "mm"),
    ("designed_position_mm", "designed flank position from datum", "mm"),
    ("base_position_mm", "base-cut flank position from datum", "mm"),
    ("axial_shift_um", "axial shift to produce = designed - base", "um"),
    ("lead_deviation_um", "cumulative lead deviation of the tooth from p (j - 1)", "um"),
    ("tooth_thickness_mm", "tooth thickness at pitch dia., designed", "mm"),
    ("base_tooth_thickness_mm", "tooth thickness at pitch dia., as cut with stock", "mm"),
    ("normal_stock_um", "normal stock to remove at contact", "um"),
    ("tolerance_um", "flank position tolerance +-", "um"),
    ("worked", "flank worked", ""),
    ("on_part", "flank on the part at theta = 0 (no: partial end tooth)", ""),
    ("inspection_position_mm", "inspection: flank axial position at pitch dia.", "mm"),
]
#: The flank tolerance list (:class:`~prs_geom.model.design.Tolerances`) of each loaded flank.
_TOLERANCE_FIELD = {("roller", "upper"): "roller_screw_flank_um", ("roller", "lower"): "roller_nut_flank_um",
                    ("nut", "upper"): "nut_flank_um"}
#: Reference temperature of every length on the sheets (ISO 1), degC.
REFERENCE_TEMPERATURE_C = 20.0
#: Decimals of the lengths on the sheets: mm to 1e-9 mm, um to 1e-6 um (module docstring).
MM_DECIMALS, UM_DECIMALS = 9, 6


def mm(x: float) -> float:
    """A length in mm as the sheets state it: rounded to 1e-9 mm, never -0.0."""
    return round(float(x), MM_DECIMALS) + 0.0


def um(x: float) -> float:
    """A length in um as the sheets state it: rounded to 1e-6 um, never -0.0."""
    return round(float(x), UM_DECIMALS) + 0.0


@dataclass(frozen=True)
class MachiningSheet:
    """One part's sheet: ``header`` (datum, process, tolerances, ...), ``rows`` (one per
    tooth and flank, :data:`COLUMNS`) and ``starts`` (one per thread start, :func:`start_table`)."""

    part: str
    header: dict[str, Any]
    rows: list[dict[str, Any]]
    starts: list[dict[str, Any]]

    def as_dict(self) -> dict[str, Any]:
        return {"part": self.part, "header": self.header, "rows": self.rows, "starts": self.starts}


def start_table(design: PRSDesign, part: str) -> list[dict[str, Any]]:
    """The thread starts of ``part`` as a shop sets them up (docs/theory/manufacturing.md).

    Start k (1-based) begins at angular index (k - 1) 360 / N deg from mark B, turning with
    the thread's hand, which puts its first tooth (k - 1) p further from A along the axis
    at theta = 0. Along a start the teeth at theta = 0 are k, k + N, k + 2N, ...; its lead
    is the axial advance per turn, N p nominal, and on a graded part the sum of the N
    designed pitches between two successive teeth of the start (smallest and largest given)."""
    starts = {"roller": 1, "nut": design.nut.starts, "screw": design.screw.starts}[part]
    p = design.thread.pitch_mm
    pl = np.asarray(design.pitch_list(part), dtype=np.float64)
    n = len(pl) + 1
    z = np.concatenate([[0.0], np.cumsum(pl)])
    out = []
    for k in range(starts):
        teeth = list(range(k + 1, n + 1, starts))
        leads = [float(z[j - 1 + starts] - z[j - 1]) for j in teeth if j - 1 + starts < n]
        out.append({
            "start": k + 1,
            "angular_index_deg": mm(360.0 * k / starts),
            "axial_offset_mm": mm(z[k] if k < n else k * p),
            "nominal_lead_mm": mm(starts * p),
            "lead_min_mm": mm(min(leads) if leads else starts * p),
            "lead_max_mm": mm(max(leads) if leads else starts * p),
            "teeth_at_theta_0": teeth,
        })
    return out


#: How a shop indexes between the starts of a multi-start part (the sheet header).
INDEXING = ("grind start 1 over the engaged length; then for each next start index the part by "
            "+360/N deg about its axis (the thread's hand) with the wheel at the same axial setting, "
            "check the start's first flank from datum A against the sheet, and grind it; the lower "
            "flanks of all starts first, then the upper flanks")


@dataclass(frozen=True)
class _BaseCut:
    """The base cut of a part with designed pitch list ``pitches`` (n - 1,) mm: base pitch
    p_b (the smallest), designed positions z_j and cumulative shifts Delta_j = z_j - (j - 1)
    p_b (n,), mm, and the thickness stock Delta_n (mm)."""

    pitches: NDArray
    base_pitch: float
    positions: NDArray
    shifts: NDArray
    stock: float

    @staticmethod
    def of(pl: NDArray) -> "_BaseCut":
        p_b = float(pl.min())
        # positions as sums of small differences (full float64 precision for sub-um shifts)
        delta = np.concatenate([[0.0], np.cumsum(pl - p_b)])
        return _BaseCut(pitches=pl, base_pitch=p_b, positions=np.concatenate([[0.0], np.cumsum(pl)]), shifts=delta,
                        stock=float(delta[-1]))


def machining_sheet(design: PRSDesign, part: str, normal_axial: dict[str, float],
                    inspection: dict[str, Any] | None = None) -> MachiningSheet:
    """The sheet of ``part`` ("roller" or "nut"); ``normal_axial`` maps "screw" and "nut" to
    the |n_z| of the screw-roller and roller-nut contacts; ``inspection``: the part's report
    from :func:`prs_geom.exports.report.inspection_section`, stated in the header."""
    cut = _BaseCut.of(np.asarray(design.pitch_list(part), dtype=np.float64))
    prof = getattr(ThreadProfiles.from_design(design), part)
    return MachiningSheet(part, _sheet_header(design, part, cut, prof, inspection),
                          _flank_rows(design, part, cut, prof, normal_axial), start_table(design, part))


def _flank_rows(design: PRSDesign, part: str, cut: _BaseCut, prof: ThreadProfile,
                normal_axial: dict[str, float]) -> list[dict[str, Any]]:
    """One row per tooth and flank (:data:`COLUMNS`), lengths rounded as the module
    docstring states."""
    pl, p_b, z, delta, delta_n = cut.pitches, cut.base_pitch, cut.positions, cut.shifts, cut.stock
    n = len(pl) + 1
    t = float(prof.tooth_half_width(prof.pitch_radius))
    loaded = {"roller": {"lower": "nut", "upper": "screw"}, "nut": {"lower": "-", "upper": "roller"}}[part]
    nz = {"roller": {"lower": normal_axial["nut"], "upper": normal_axial["screw"]},
          "nut": {"lower": normal_axial["nut"], "upper": normal_axial["nut"]}}[part]
    # datum A: the loaded-side end face (part z = 0); tooth 1's mid-plane at theta = 0 lies
    # p/2 inside it on the roller and on it on the nut (docs/theory/conventions.md)
    mid1 = 0.5 * design.thread.pitch_mm if part == "roller" else 0.0
    length = n * design.thread.pitch_mm
    tol = design.tolerances
    per_tooth = tol.flank_tolerances_um(n) if tol is not None else None
    lead_dev = (z - np.arange(n) * design.thread.pitch_mm) * 1e3
    rows = []
    for j in range(n):
        for flank in ("lower", "upper"):
            # flank positions at the pitch diameter from the datum (lower flank of tooth 1):
            # designed z_j (+ 2t upper), base cut (j - 1) p_b (+ Delta_n + 2t upper)
            shift = delta[j] if flank == "lower" else delta[j] - delta_n
            exact = float(mid1 + z[j] - t) if flank == "lower" else float(mid1 + z[j] + t)
            # base = (j - 1) p_b (lower), (j - 1) p_b + Delta_n + 2 t (upper), taken as
            # designed - shift so that the shift keeps its exact sign (0 on the datum teeth);
            # both rounded to 1e-9 mm, the shift derived from the rounded pair (module docstring)
            designed, base_pos = mm(exact), mm(exact - float(shift))
            shift_um = um((designed - base_pos) * 1e3)
            fld = _TOLERANCE_FIELD.get((part, flank))
            rows.append({
                "tooth": j + 1,
                "flank": flank,
                "loaded_by": loaded[flank],
                "designed_pitch_mm": mm(pl[j]) if j < n - 1 else None,
                "base_pitch_mm": mm(p_b),
                "designed_position_mm": designed,
                "base_position_mm": base_pos,
                "axial_shift_um": shift_um,
                "lead_deviation_um": um(lead_dev[j]),
                "tooth_thickness_mm": mm(2.0 * t),
                "base_tooth_thickness_mm": mm(2.0 * t + delta_n),
                "normal_stock_um": um(abs(shift_um) * nz[flank]),
                "tolerance_um": (um(per_tooth[fld][j]) if per_tooth is not None and fld is not None else None),
                "worked": bool(abs(shift_um) > 0.0),
                # a flank of a partial end tooth (cut by the end face at theta = 0)
                "on_part": bool(-1e-12 <= designed <= length + 1e-12),
                "inspection_position_mm": designed,
            })
    return rows


def _tolerance_text(tol: Tolerances | None) -> str:
    """Where the sheet's flank tolerances come from."""
    if tol is None:
        return "not synthesised: the design has no [tolerances] section (prs-geom tolerance --target-ldc ... --out)"
    tol_text = f"per flank from the design's [tolerances]: {tol.source}"
    if tol.target_ldc is not None:
        # a design file may state the target without the confidence
        conf = f", confidence {tol.confidence:g}" if tol.confidence is not None else ""
        tol_text += f" (target worst LDC {tol.target_ldc:g}{conf}, seed {tol.seed})"
    return tol_text


def _sheet_header(design: PRSDesign, part: str, cut: _BaseCut, prof: ThreadProfile,
                  inspection: dict[str, Any] | None) -> dict[str, Any]:
    """The sheet header: datums, process, tolerances, thermal data, indexing, inspection."""
    pl, p_b, delta_n = cut.pitches, cut.base_pitch, cut.stock
    n = len(pl) + 1
    tol = design.tolerances
    tol_text = _tolerance_text(tol)
    alpha = getattr(design.materials, part).thermal_expansion_per_k
    mark = datum_mark(prof, 0.0, 0.5 * design.nut.outer_diameter_mm if prof.internal else None)
    header = {
        "part": part,
        "design": design.name,
        "units": "lengths mm, shifts, deviations and stock um; all at 20 degC",
        "datum": "A: the loaded-side end face (tooth 1 end, z = 0 of the part frame); B: the mid-plane of "
                 f"the radial slot in face A at theta = 0 ({mark.width:g} mm wide, {mark.depth:g} mm deep, radius "
                 f"{mark.r_inner:.3f} to {mark.r_outer:.3f} mm); every position is the flank's axial distance "
                 "from A at the pitch diameter, at theta = 0",
        "base_pitch_mm": mm(p_b),
        "base_tooth_thickness_stock_um": um(delta_n * 1e3),
        "pitch_diameter_mm": mm(2.0 * prof.pitch_radius),
        "flank_half_angle_deg": design.thread.flank_half_angle_deg,
        "teeth": n,
        "tolerance": tol_text,
        "cumulative_lead_tolerance_um": (tol.lead_um if tol is not None and tol.lead_um > 0 else None),
        "reference_temperature_degC": REFERENCE_TEMPERATURE_C,
        "thermal_growth_of_engaged_length_um_per_K": um((n - 1) * design.thread.pitch_mm * alpha * 1e3),
        "process": "cut at the base pitch with the thickness stock, then grind lower flanks +z "
                   "(datum tooth 1) and upper flanks -z (datum tooth n)",
        "constant_pitch": bool(np.all(pl == pl[0])),
        "thread_starts": {"roller": 1, "nut": design.nut.starts}[part],
        "indexing": INDEXING if part == "nut" and design.nut.starts > 1 else "single start",
    }
    if inspection is not None:
        header["inspection"] = (
            f"{inspection['gauge']} diameter {inspection['gauge_diameter_mm']:.6f} mm, measurement M = "
            f"{inspection['measurement_mm']:.6f} mm at 20 degC "
            f"({inspection['temperature_coefficient_um_per_k']:.3f} um/K); {inspection['method']}")
    return header


def machining_sheets(design: PRSDesign, contact: ContactResult | None = None,
                     inspection: dict[str, dict[str, Any]] | None = None) -> dict[str, MachiningSheet]:
    """Sheets of roller and nut, with the contact normals of the contact stage (solved here
    when ``contact`` is not given). ``inspection``: the per-part reports of
    :func:`prs_geom.exports.report.inspection_section`, whose over-wire / over-ball
    values go into each sheet's header."""
    contact = contact if contact is not None else analyse_contact(design)
    nz = {"screw": abs(contact.screw_roller["upper_at_theoretical"].normal[2]),
          "nut": abs(contact.roller_nut["lower"].normal[2])}
    return {part: machining_sheet(design, part, nz, (inspection or {}).get(part)) for part in ("roller", "nut")}
