"""Load distribution over the thread teeth and equal-load pitch design (docs/theory/loads.md).

Pure math, no I/O.

Load path and signs (fixed here, used everywhere)
-------------------------------------------------
Tooth 1 is at the loaded end (z = 0), tooth n at the far end. The external load F0 is
carried screw -> rollers -> nut and flows toward -z: the screw tooth above each roller
tooth presses it down (roller *upper* flank, the "upper" screw-roller contact of
:mod:`prs_geom.contact`), and the roller tooth presses the nut tooth below it (roller
*lower* flank, nut tooth j the one below roller tooth j). The nut is supported at the
loaded end, so its body is in compression; the screw is pulled at the loaded end
(tension-compression: body in tension) or pushed at the far end (compression-compression).
All rollers carry the same loads (one roller is modelled): f_nr,j (nut-roller) and
f_rs,j (roller-screw), axial components, N. :func:`solve_loads_rollers` models all z rollers
side by side instead (own gaps and body each, shared nut and screw bodies).

Compatibility between teeth j and j + 1 (D = contact + tooth deflection, axial, mm):

    D_nr(f_nr,j) - D_nr(f_nr,j+1) = d_n,j + d_r,j + (p_r,j - p_n,j)
    D_rs(f_rs,j) - D_rs(f_rs,j+1) = s d_s,j - d_r,j + (p_s - p_r,j)

with the body deformations over one pitch d_i,j = N_i,j p / (E_i A_i), segment forces
N_n,j = z sum_{k>j} f_nr,k (compression), N_r,j = sum_{k>j} (f_nr,k - f_rs,k) (tension),
N_s,j = z sum_{k>j} f_rs,k (tension-compression, s = +1) or z sum_{k<=j} f_rs,k
(compression-compression, s = -1); equilibrium sum f_nr = sum f_rs = F0 / z.

Equal load (every coefficient 1): contact and tooth terms cancel and d_r = 0, so

    p_r,j = p_s + F0 p (n - j) / (n E_s A_s)     (tension-compression)
    p_r,j = p_s - F0 p j / (n E_s A_s)           (compression-compression)
    p_n,j = p_r,j + F0 p (n - j) / (n E_n A_n)   (both)

With the nut supported at the loaded end the far nut teeth move toward the support the
most, so they must start closer to the roller teeth: the nut pitch is the larger one
(docs/theory/loads.md derives the sign).

Compliances
-----------
* Hertz point contact of the roller's spherical flank (radius r_T) with the screw's or
  nut's straight flank, curvatures 1/r_T, 1/r_T and 0, +-sin(beta)/r_c at the actual contact
  radius r_c of the contact solver; ellipticity k from the complete elliptic integrals
  (:mod:`prs_geom.analysis.hertz`); normal approach delta = C Q^(2/3); the axial load is
  F = Q n_z, with n_z the axial component of the contact normal from the contact solver
  (about cos(beta) cos(lambda)), so the axial approach is C (F / n_z)^(2/3) / n_z.
* Thread teeth (Yamamoto, Appendix A): bending, shear, root tilt, root shear and radial
  terms. Yamamoto's terms are per unit circumferential width; ``design.loads.tooth_width``
  says which width one contact load acts over (:class:`~prs_geom.model.design.LoadSettings`).
  The default, "circumference-share": a roller's tooth load is spread over pi d_s / z on the
  screw and pi d_n / z on the nut (the z rollers share the circumference) and over the whole
  roller circumference pi d_r on the roller.
  Tooth geometry at the load line: b = axial tooth thickness at the contact radius,
  c = radial distance from the root to the contact radius, a = b + 2 c tan(beta).
  :class:`LoadModel` may instead carry a dense symmetric positive semi-definite linear
  compliance of the 2n contact pairs (``compliance``, e.g. from a finite-element influence
  matrix); Hertz stays the diagonal nonlinear term.
* Bodies: screw and roller root sections pi d_root^2 / 4, nut pi (D0^2 - d_root^2) / 4 with
  d_root the nut's groove-root (major) diameter.

The tooth loads are the solution of a complementarity problem, solved by
:mod:`prs_geom.analysis.load_solver` (its docstring states the energy, the method and why
it terminates).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any, Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from prs_geom.analysis.contact import ContactResult, analyse_contact
from prs_geom.analysis.hertz import hertz_contact
from prs_geom.analysis.load_details import HertzContact, LoadModelDetails, SectionAreas, ToothTerms
from prs_geom.analysis.load_solver import (MEMORY_MB, LoadBatch, LoadModel, LoadResult, RollerLoadResult,
                                           block_compliance, chunk_size, iteration_bound, solve_loads, solve_loads_batch,
                                           solve_loads_rollers)
from prs_geom.geometry.profiles import ThreadProfile, ThreadProfiles
from prs_geom.model.design import PRSDesign
from prs_geom.model.errors import DesignError
from prs_geom.runtime.progress import ProgressFn

__all__ = ["MEMORY_MB", "LoadBatch", "LoadModel", "LoadResult", "RollerLoadResult", "block_compliance",
           "iteration_bound", "solve_loads", "solve_loads_batch", "solve_loads_rollers", "build_model",
           "forward", "gap_terms", "gap_terms_rollers", "pitch_gaps", "axial_stiffness", "design_pitches",
           "closed_form_equal_load", "with_pitch_lists", "off_design", "pitch_error_sensitivity",
           "LoadDistribution", "LOAD_FRACTIONS", "load_distribution", "analyse_loads", "LoadsResult", "PitchDesign",
           "hertz_constant",
           "yamamoto_compliance", "sensitivity_chunks", "compliance_model", "ModelRisk", "ModelRiskCase",
           "model_risk", "MODEL_RISK_FRACTIONS", "MIN_MEAN_APPROACH_MM", "MAX_GAP_TO_APPROACH", "mean_approach_mm",
           "check_load_scale", "design_pitch"]


# --------------------------------------------------------------------------- Hertz
def hertz_constant(curvatures: Sequence[float], eta: float) -> tuple[float, dict[str, float]]:
    """C with normal approach delta = C Q^(2/3) (mm, Q in N) for principal curvatures
    (rho11, rho12, rho21, rho22) (1/mm; plane 2 is the circumferential direction) and
    eta = sum (1 - nu^2)/E (1/MPa), with the ellipse constants of
    :func:`prs_geom.analysis.hertz.hertz_contact` (semi-axes per Q^(1/3), mm N^(-1/3))."""
    r11, r12, r21, r22 = curvatures
    if r11 + r12 + r21 + r22 <= 0:
        raise DesignError("roller.arc_radius_mm", None, "the contact curvature sum must be positive")
    c = hertz_contact(curvatures, eta)
    return c.approach_constant, {"sum_rho_per_mm": c.curvature_sum_per_mm, "F_rho": c.curvature_difference,
                                 "ellipticity_k": c.ellipticity, "semi_major_per_cbrt_N_mm": c.semi_major_per_cbrt_n,
                                 "semi_minor_per_cbrt_N_mm": c.semi_minor_per_cbrt_n,
                                 "circumferential_semi_axis_per_cbrt_N_mm": c.plane_2_semi_axis_per_cbrt_n}


# --------------------------------------------------------------------------- Yamamoto
def yamamoto_compliance(beta: float, a: float, b: float, c: float, P: float, d: float,
                        E: float, nu: float, nut_outer: float | None = None) -> dict[str, float]:
    """Axial tooth deflection per unit load per unit width, mm / (N/mm), term by term."""
    ta = math.tan(beta)
    cot = 1.0 / ta
    lam1 = (1 - nu ** 2) * 3.0 / (4.0 * E) * ((1 - (2 - b / a) ** 2 + 2 * math.log(a / b)) * cot ** 3
                                               - 4 * (c / a) ** 2 * ta)
    lam2 = (1 + nu) * 6.0 / (5.0 * E) * cot * math.log(a / b)
    lam3 = (1 - nu ** 2) * 12.0 * c / (math.pi * E * a ** 2) * (c - 0.5 * b * ta)
    lam4 = (1 - nu ** 2) * 2.0 / (math.pi * E) * ((P / a) * math.log((P + 0.5 * a) / (P - 0.5 * a))
                                                  + 0.5 * math.log(4 * P ** 2 / a ** 2 - 1))
    if nut_outer is None:
        lam5 = (1 - nu) * ta ** 2 / 2.0 * (d / P) / E
    else:
        lam5 = ((nut_outer ** 2 + d ** 2) / (nut_outer ** 2 - d ** 2) + nu) * ta ** 2 / 2.0 * (d / P) / E
    return {"bending": lam1, "shear": lam2, "root_tilt": lam3, "root_shear": lam4, "radial": lam5}




def _section_areas(design: PRSDesign) -> dict[str, float]:
    return {
        "screw": math.pi * design.screw.minor_diameter_mm ** 2 / 4.0,
        "roller": math.pi * design.roller.minor_diameter_mm ** 2 / 4.0,
        "nut": math.pi * (design.nut.outer_diameter_mm ** 2 - design.nut.major_diameter_mm ** 2) / 4.0,
    }


#: Smallest mean elastic approach (mm) of a tooth contact at the design load: 1 nm. Below it
#: the load is not one the model describes: ground flanks are a hundred times rougher than
#: that (the smooth-surface Hertz law no longer holds), a micrometre of pitch error decides
#: the sharing alone, and the tooth-load Newton system loses its conditioning (at about
#: 0.1 nm on the standard design).
MIN_MEAN_APPROACH_MM = 1e-6
#: Largest ratio of the gaps a design's own pitch lists open between the teeth to the mean
#: elastic approach at the design load: beyond it the first teeth carry the load alone (the
#: pitch lists belong to another load) and the solver loses its conditioning (a 2 % pitch
#: step at 10 N on the standard design, about 900 times).
MAX_GAP_TO_APPROACH = 200.0


def mean_approach_mm(model: LoadModel, load_n: float) -> float:
    """Axial approach (mm) of a tooth contact carrying the mean share load / (n z) of
    ``load_n`` (N): Hertz plus tooth deflection, the larger of the two contacts."""
    f = load_n / (model.n * model.z)
    return float(max(model.deflection("nr", f), model.deflection("rs", f)))


def check_load_scale(design: PRSDesign, model: LoadModel | None = None, load_n: float | None = None,
                     field: str = "loading.axial_load_n", value: Any = None,
                     gaps: Sequence[tuple[NDArray, NDArray]] | None = None, min_approach: bool = True) -> float:
    """Raise :class:`DesignError` on ``field`` (shown with ``value``, default the load) when
    the load (N, default the design load) is too small for the load model: a mean tooth
    approach below :data:`MIN_MEAN_APPROACH_MM` (unless ``min_approach`` is false), or pitch
    gaps opening more than :data:`MAX_GAP_TO_APPROACH` times that approach. ``gaps``: the
    (g_nr, g_rs) gap pairs solved at this load (any leading batch axes; default the design's
    own pitch lists). Returns the mean approach (mm). The message says the load that would
    do (the approach grows at least as F^(2/3))."""
    model = model if model is not None else build_model(design)
    F = design.loading.axial_load_n if load_n is None else float(load_n)
    d = mean_approach_mm(model, F)
    gap = 0.0
    for g_nr, g_rs in (gaps if gaps is not None else [gap_terms(design)]):
        for g in (g_nr, g_rs):
            g = np.asarray(g, dtype=np.float64)
            if g.size:
                gap = max(gap, float(np.ptp(g, axis=-1).max()))
    need_gap = gap / MAX_GAP_TO_APPROACH
    need = max(MIN_MEAN_APPROACH_MM if min_approach else 0.0, need_gap)
    if math.isfinite(d) and d >= need and d > 0.0:
        return d
    # D(k F) >= k^(2/3) D(F) for k >= 1, so this load reaches the approach needed
    F_need = F * (need / d) ** 1.5 if d > 0 and math.isfinite(d) else math.inf
    shown = F if value is None else value
    if need_gap >= need and need_gap > 0.0:
        why = (f"the pitch lists open gaps of up to {gap * 1e3:.4g} um between the teeth, "
               f"{gap / d if d > 0 else math.inf:.3g} times the mean elastic approach of a tooth contact at "
               f"{F:.6g} N ({d * 1e3:.3g} um; more than {MAX_GAP_TO_APPROACH:g} times): the first teeth would carry "
               f"the load alone and the load model loses its conditioning; design the pitch lists for this load "
               f"(prs-geom design-pitch) or increase {field} to at least {F_need:.3g} N")
    else:
        why = (f"a tooth contact deflects by {d * 1e6:.3g} nm on average at {F:.6g} N, below the "
               f"{MIN_MEAN_APPROACH_MM * 1e6:g} nm the load model resolves (ground flanks are a hundred times "
               f"rougher, and a micrometre of pitch error would decide the load sharing alone): increase {field} "
               f"to at least {F_need:.3g} N")
    raise DesignError(field, shown, why)


def _hertz_contacts(design: PRSDesign, contact: ContactResult) -> tuple[HertzContact, HertzContact]:
    """The Hertz constants of the screw-roller and the roller-nut contact (in that order):
    the roller's flank arc against the straight flank of the screw or nut at the contact
    points of the contact stage (theoretical screw)."""
    mats = design.materials
    sin_beta = math.sin(design.thread.beta)
    arc_radius = design.roller.arc_radius_mm
    c_rs = contact.screw_roller["upper_at_theoretical"]
    c_nr = contact.roller_nut["lower"]

    def compliance_sum(part: str) -> float:
        other = getattr(mats, part)
        return (1 - mats.roller.poisson_ratio ** 2) / mats.roller.youngs_modulus_mpa + \
            (1 - other.poisson_ratio ** 2) / other.youngs_modulus_mpa

    def pair(part_curvature: float, eta: float, normal_z: float) -> HertzContact:
        c_normal, constants = hertz_constant((1 / arc_radius, 1 / arc_radius, 0.0, part_curvature), eta)
        return HertzContact(**constants, normal_axial_component=normal_z, C_normal=c_normal)

    return (pair(sin_beta / c_rs.part_radius_mm, compliance_sum("screw"), abs(c_rs.normal[2])),
            pair(-sin_beta / c_nr.part_radius_mm, compliance_sum("nut"), abs(c_nr.normal[2])))


def _tooth_width(design: PRSDesign, part: str, hertz: HertzContact, pitch_diameter: float) -> float:
    """The circumferential width (mm) the tooth terms of ``part`` act over, by the design's
    ``loads.tooth_width`` convention; ``hertz``: the contact the tooth carries."""
    convention = design.loads.tooth_width
    if convention == "unit":
        return 1.0
    if convention == "ring":
        return math.pi * pitch_diameter
    if convention == "contact-ellipse":
        z = design.roller.count
        mean_tooth_load = design.loading.axial_load_n / (design.thread.engaged_teeth * z)     # axial, N
        return 2.0 * hertz.circumferential_semi_axis_per_cbrt_N_mm * \
            (mean_tooth_load / hertz.normal_axial_component) ** (1.0 / 3.0)
    # circumference-share: the contacts of one tooth ring share its circumference
    return math.pi * pitch_diameter / (1 if part == "roller" else design.roller.count)


def _tooth_terms(design: PRSDesign, part: str, contact_radius: float, width: float,
                 profile) -> tuple[float, ToothTerms]:
    """Yamamoto's compliance of the tooth of ``part`` (``profile``) loaded at
    ``contact_radius`` (mm), per ``width`` (mm): the axial deflection per N (mm/N) and its
    terms. A contact off the tooth raises :class:`DesignError` on ``roller.arc_radius_mm``."""
    beta = design.thread.beta
    p = design.thread.pitch_mm
    b = 2.0 * float(profile.tooth_half_width(contact_radius))
    c = abs(contact_radius - profile.root_radius)
    a = b + 2.0 * c * math.tan(beta)
    if not 0.0 < b <= a < 2.0 * p:
        # Yamamoto's terms take log(a / b) and log(P - a / 2). It fails when the contact lies off
        # the tooth: the roller's flank arc touches a straight flank at a roller radius of about
        # r_T sin(beta), so the arc radius moves it
        r_t = design.roller.arc_radius_mm
        raise DesignError("roller.arc_radius_mm", r_t,
                          f"the {part} tooth at the contact (radius {contact_radius:.4g} mm) has a thickness b = "
                          f"{b:.4g} mm and a root thickness a = {a:.4g} mm; the tooth compliance needs 0 < b <= a "
                          f"< 2 p = {2.0 * p:g} mm, so the contact lies off the tooth (the flank arc touches at a "
                          f"roller radius of about r_T sin(beta) = {r_t * math.sin(beta):.4g} mm): choose "
                          f"roller.arc_radius_mm nearer r_r / sin(beta) = "
                          f"{0.5 * design.roller.pitch_diameter_mm / math.sin(beta):.4g} mm")
    mat = getattr(design.materials, part)
    terms = yamamoto_compliance(beta, a, b, c, p, 2 * profile.pitch_radius, mat.youngs_modulus_mpa,
                                mat.poisson_ratio, design.nut.outer_diameter_mm if part == "nut" else None)
    return sum(terms.values()) / width, ToothTerms(a_mm=a, b_mm=b, c_mm=c, width_mm=width,
                                                   **{k: v / width for k, v in terms.items()})


def _analytic_teeth(design: PRSDesign, contact: ContactResult, hertz_rs: HertzContact,
                    hertz_nr: HertzContact) -> dict[str, tuple[float, ToothTerms]]:
    """Compliance (mm/N) and terms of the four loaded teeth, by the name of their
    :class:`LoadModelDetails` field: the screw's, the roller's at the screw and at the nut
    side, the nut's."""
    prof = ThreadProfiles.from_design(design)
    screw_profile = contact.theoretical.profile
    c_rs = contact.screw_roller["upper_at_theoretical"]
    c_nr = contact.roller_nut["lower"]
    d_r = design.roller.pitch_diameter_mm
    return {
        "tooth_screw": _tooth_terms(design, "screw", c_rs.part_radius_mm, _tooth_width(
            design, "screw", hertz_rs, 2 * screw_profile.pitch_radius), screw_profile),
        "tooth_roller_screw_side": _tooth_terms(design, "roller", c_rs.roller_radius_mm, _tooth_width(
            design, "roller", hertz_rs, d_r), prof.roller),
        "tooth_roller_nut_side": _tooth_terms(design, "roller", c_nr.roller_radius_mm, _tooth_width(
            design, "roller", hertz_nr, d_r), prof.roller),
        "tooth_nut": _tooth_terms(design, "nut", c_nr.part_radius_mm, _tooth_width(
            design, "nut", hertz_nr, design.nut.pitch_diameter_mm), prof.nut),
    }


def build_model(design: PRSDesign, contact: ContactResult | None = None) -> LoadModel:
    """Compliances of a design, with the contact geometry of the contact stage (solved here
    when ``contact`` is not given). The design load must suit the model
    (:func:`check_load_scale`, a :class:`DesignError` on ``loading.axial_load_n`` if not)."""
    contact = contact if contact is not None else analyse_contact(design)
    hertz_rs, hertz_nr = _hertz_contacts(design, contact)
    teeth = _analytic_teeth(design, contact, hertz_rs, hertz_nr)
    details = LoadModelDetails(tooth_width=design.loads.tooth_width, hertz_rs=hertz_rs, hertz_nr=hertz_nr,
                               **{name: terms for name, (_, terms) in teeth.items()},
                               section_areas_mm2=SectionAreas(**_section_areas(design)))
    p = design.thread.pitch_mm
    mats = design.materials
    areas = details.section_areas_mm2

    def hertz(h: HertzContact) -> float:
        return h.C_normal * h.normal_axial_component ** (-5.0 / 3.0)

    model = LoadModel(
        n=design.thread.engaged_teeth, z=design.roller.count, pitch=p,
        sign_screw=1 if design.loading.installation == "tension-compression" else -1,
        hertz_nr=hertz(details.hertz_nr), hertz_rs=hertz(details.hertz_rs),
        tooth_nr=teeth["tooth_roller_nut_side"][0] + teeth["tooth_nut"][0],
        tooth_rs=teeth["tooth_roller_screw_side"][0] + teeth["tooth_screw"][0],
        body_screw=p / (mats.screw.youngs_modulus_mpa * areas.screw),
        body_roller=p / (mats.roller.youngs_modulus_mpa * areas.roller),
        body_nut=p / (mats.nut.youngs_modulus_mpa * areas.nut),
        details=details,
    )
    check_load_scale(design, model)
    return model


def gap_terms(design: PRSDesign, roller: Sequence[float] | None = None,
              nut: Sequence[float] | None = None) -> tuple[NDArray, NDArray]:
    """Cumulative initial gaps g_j = sum_{k<j} (p_r,k - p_n,k) and
    g'_j = sum_{k<j} (p_s - p_r,k), as differences (full precision), mm.

    ``roller`` / ``nut`` may carry a leading batch axis ((B, n - 1) pitch lists): the gaps
    then have shape (B, n), computed row by row exactly as for one list."""
    return pitch_gaps(design.thread.pitch_mm,
                      roller if roller is not None else design.pitch_list("roller"),
                      nut if nut is not None else design.pitch_list("nut"))


def pitch_gaps(pitch: float, roller: Sequence[float] | NDArray,
               nut: Sequence[float] | NDArray) -> tuple[NDArray, NDArray]:
    """:func:`gap_terms` of roller and nut pitch lists (mm) with the screw at ``pitch``: the
    cumulative sums run over the differences from the pitch, so sub-um corrections keep full
    float64 precision on 40 mm positions. A leading batch axis is kept."""
    p = pitch
    pr = np.asarray(roller, dtype=np.float64)
    pn = np.asarray(nut, dtype=np.float64)
    pr, pn = np.broadcast_arrays(pr, pn)
    zero = np.zeros(pr.shape[:-1] + (1,))
    g_nr = np.concatenate([zero, np.cumsum((pr - p) - (pn - p), axis=-1)], axis=-1)
    g_rs = np.concatenate([zero, np.cumsum(-(pr - p), axis=-1)], axis=-1)
    return g_nr, g_rs


def gap_terms_rollers(design: PRSDesign, roller: NDArray | None = None,
                      nut: Sequence[float] | None = None) -> tuple[NDArray, NDArray]:
    """(z, n) gaps of every roller from per-roller pitch lists ``roller`` (z, n - 1) (None:
    the design's list for all) and the nut's list."""
    z = design.roller.count
    pr = np.asarray(design.pitch_list("roller") if roller is None else roller, dtype=np.float64)
    pr = np.broadcast_to(pr, (z, design.thread.engaged_teeth - 1))
    return gap_terms(design, pr, nut)


def forward(design: PRSDesign, load: float | None = None, model: LoadModel | None = None,
            roller: Sequence[float] | None = None, nut: Sequence[float] | None = None,
            linear_at: float | None = None) -> LoadResult:
    """Tooth loads of ``design`` (or with other pitch lists) at ``load`` (N, default design load)."""
    model = model or build_model(design)
    g_nr, g_rs = gap_terms(design, roller, nut)
    return solve_loads(model, design.loading.axial_load_n if load is None else load, g_nr, g_rs,
                       linear_at=linear_at)


def axial_stiffness(design: PRSDesign, model: LoadModel | None = None, load: float | None = None) -> dict[str, float]:
    """Secant F0 / delta and tangent dF/d delta axial stiffness of the engaged threads (N/um)."""
    model = model or build_model(design)
    F = design.loading.axial_load_n if load is None else load
    g_nr, g_rs = gap_terms(design)
    b = solve_loads_batch(model, np.array([F, F * 1.001]), np.stack([g_nr, g_nr]), np.stack([g_rs, g_rs]))
    d1, d2 = (float(v) for v in b.axial_deflection_mm)
    return {"secant_N_per_um": F / d1 / 1e3,
            "tangent_N_per_um": (0.001 * F) / (d2 - d1) / 1e3,
            "axial_deflection_um": d1 * 1e3}


# --------------------------------------------------------------------------- inverse
@dataclass(frozen=True)
class PitchDesign:
    roller_mm: tuple[float, ...]
    nut_mm: tuple[float, ...]
    screw_mm: float
    target_nr: NDArray
    target_rs: NDArray


def design_pitches(design: PRSDesign, target_nr: Sequence[float] | None = None,
                   target_rs: Sequence[float] | None = None, model: LoadModel | None = None) -> PitchDesign:
    """Pitch lists of roller and nut that give the target coefficients at the design load.

    Targets are load-distribution coefficients per tooth (mean 1; None = equal). The tooth
    loads are fixed by the target, so the compatibility equations give the pitch
    differences directly: x = B f (docs/theory/loads.md). With a dense ``model.compliance``
    (the FE tooth matrices) a tooth's deflection is its Hertz approach plus the row of the
    dense compliance times all loads, so the lists hold under that coupled model.
    """
    model = model or build_model(design)
    n, z = model.n, model.z
    F0 = design.loading.axial_load_n
    mean = F0 / (n * z)
    t_nr = np.ones(n) if target_nr is None else np.asarray(target_nr, dtype=np.float64)
    t_rs = np.ones(n) if target_rs is None else np.asarray(target_rs, dtype=np.float64)
    for name, t in (("target.nut_roller", t_nr), ("target.roller_screw", t_rs)):
        if t.shape != (n,):
            raise DesignError(name, list(t), f"must have engaged_teeth = {n} coefficients")
        if not np.all(np.isfinite(t)) or np.any(t <= 0):
            raise DesignError(name, list(t), "coefficients must be finite and > 0")
        if abs(t.mean() - 1.0) > 1e-9:
            raise DesignError(name, list(t), f"coefficients must average 1 (mean is {t.mean():.12g})")
    f = np.concatenate([t_nr, t_rs]) * mean
    Snr, Srs = model.body_matrices()
    # per-tooth body terms d_j = S_{j+1} - S_j
    body_nr = np.diff(Snr @ f)
    body_rs = np.diff(Srs @ f)
    if model.compliance is None:
        D_nr = model.deflection("nr", f[:n])
        D_rs = model.deflection("rs", f[n:])
    else:
        # Hertz of each contact plus the dense tooth compliance (its coupled neighbours)
        lin = model.compliance @ f
        D_nr = model.hertz_nr * f[:n] ** (2.0 / 3.0) + lin[:n]
        D_rs = model.hertz_rs * f[n:] ** (2.0 / 3.0) + lin[n:]
    p = design.thread.pitch_mm
    # D_j - D_{j+1} = body_j + (gap step):  gap step nr = p_r - p_n, rs = p_s - p_r
    step_rs = (D_rs[:-1] - D_rs[1:]) - body_rs      # p_s - p_r,j
    step_nr = (D_nr[:-1] - D_nr[1:]) - body_nr      # p_r,j - p_n,j
    corr_r = -step_rs                                # p_r,j - p  (p_s = p)
    corr_n = corr_r - step_nr                        # p_n,j - p
    return PitchDesign(tuple(float(p + c) for c in corr_r), tuple(float(p + c) for c in corr_n),
                       p, t_nr, t_rs)


def closed_form_equal_load(design: PRSDesign) -> tuple[NDArray, NDArray]:
    """The equal-load corrections p_r,j - p and p_n,j - p (mm) in closed form (module doc)."""
    n = design.thread.engaged_teeth
    p = design.thread.pitch_mm
    F0 = design.loading.axial_load_n
    A = _section_areas(design)
    Es, En = design.materials.screw.youngs_modulus_mpa, design.materials.nut.youngs_modulus_mpa
    j = np.arange(1, n)
    if design.loading.installation == "tension-compression":
        cr = F0 * p * (n - j) / (n * Es * A["screw"])
    else:
        cr = -F0 * p * j / (n * Es * A["screw"])
    cn = cr + F0 * p * (n - j) / (n * En * A["nut"])
    return cr, cn


def with_pitch_lists(design: PRSDesign, pd: PitchDesign, name: str | None = None) -> PRSDesign:
    """A new design carrying the designed pitch lists."""
    return design.with_changes(
        name=name or design.name,
        roller=replace(design.roller, pitch_list_mm=pd.roller_mm),
        nut=replace(design.nut, pitch_list_mm=pd.nut_mm),
    )




# --------------------------------------------------------------------------- reports
def off_design(design: PRSDesign, fractions: Sequence[float] = (0.25, 0.5, 1.0, 1.5),
               model: LoadModel | None = None) -> list[dict[str, Any]]:
    """Coefficients of the design's pitch lists at other loads (one batched solve)."""
    model = model or build_model(design)
    F0 = design.loading.axial_load_n
    fractions = list(fractions)
    if not fractions:
        return []
    g_nr, g_rs = gap_terms(design)
    B = len(fractions)
    b = solve_loads_batch(model, np.array([fr * F0 for fr in fractions]), np.tile(g_nr, (B, 1)),
                          np.tile(g_rs, (B, 1)))
    out = []
    for i, fr in enumerate(fractions):
        r = b[i]
        out.append({"load_fraction": fr, "load_N": fr * F0,
                    "ldc_nut_roller": r.ldc_nr.tolist(), "ldc_roller_screw": r.ldc_rs.tolist(),
                    "max_ldc": float(max(r.ldc_nr.max(), r.ldc_rs.max())),
                    "teeth_out_of_contact": int((~r.active_nr).sum() + (~r.active_rs).sum())})
    return out


def _sensitivity_gaps(design: PRSDesign, error_mm: float) -> tuple[NDArray, NDArray]:
    """Gaps (2(n-1), n) with one roller pitch (rows 0..n-2) or one nut pitch (rows n-1..)
    off by ``error_mm``, computed exactly as :func:`gap_terms` of the perturbed lists."""
    pr = np.array(design.pitch_list("roller"))
    pn = np.array(design.pitch_list("nut"))
    k = len(pr)
    R = np.tile(pr, (2 * k, 1))
    N = np.tile(pn, (2 * k, 1))
    j = np.arange(k)
    R[j, j] += error_mm
    N[k + j, j] += error_mm
    return gap_terms(design, R, N)


def sensitivity_chunks(design: PRSDesign, model: LoadModel | None = None, memory_mb: float = MEMORY_MB) -> int:
    """Number of batch chunks :func:`pitch_error_sensitivity` solves (its progress steps)."""
    n = design.thread.engaged_teeth
    B = 2 * (n - 1)
    if B == 0:
        return 0
    kind = "dense" if model is not None and model.compliance is not None else "banded"
    return -(-B // chunk_size(1, n, kind, memory_mb))


def pitch_error_sensitivity(design: PRSDesign, error_mm: float = 1e-3, model: LoadModel | None = None,
                            progress: ProgressFn | None = None, memory_mb: float = MEMORY_MB) -> dict[str, Any]:
    """Largest change of any coefficient when one roller or nut pitch is off by ``error_mm``.

    All 2 (n - 1) perturbed designs are one batched solve, cut into chunks within
    ``memory_mb``; ``progress("sensitivity", samples done, 2 (n - 1))`` after each chunk."""
    model = model or build_model(design)
    base = forward(design, model=model)
    k = design.thread.engaged_teeth - 1
    worst = {"roller": (0.0, 0), "nut": (0.0, 0)}
    if k > 0:
        g_nr, g_rs = _sensitivity_gaps(design, error_mm)
        b = solve_loads_batch(model, design.loading.axial_load_n, g_nr, g_rs, memory_mb=memory_mb,
                              progress=progress, stage="sensitivity", start=base)
        dl = np.maximum(np.abs(b.ldc_nr - base.ldc_nr).max(axis=1), np.abs(b.ldc_rs - base.ldc_rs).max(axis=1))
        for i, part in enumerate(("roller", "nut")):
            v = dl[i * k:(i + 1) * k]
            j = int(np.argmax(v))
            if v[j] > 0.0:
                worst[part] = (float(v[j]), j + 1)
    return {"pitch_error_um": error_mm * 1e3,
            **{f"max_ldc_change_{k_}": v[0] for k_, v in worst.items()},
            **{f"worst_pitch_index_{k_}": v[1] for k_, v in worst.items()}}


@dataclass(frozen=True)
class LoadDistribution:
    """The load distribution of a design under one load model: what report.json's ``loads``
    section prints (:func:`prs_geom.exports.report.loads_section`).

    Attributes
    ----------
    design_load_n : float
        The design load (N).
    installation : str
        ``loading.installation`` of the design.
    result : LoadResult
        Tooth loads at the design load with the design's pitch lists.
    constant_pitch : LoadResult
        The same with constant pitch.
    linear : LoadResult
        The linear model, linearised at the mean tooth load of ``result``.
    stiffness : dict
        :func:`axial_stiffness` of the design.
    off_design : list of dict
        :func:`off_design` rows at :data:`LOAD_FRACTIONS`.
    sensitivity : dict
        :func:`pitch_error_sensitivity` of the design.
    model : LoadModel
        The load model of every solve.
    """

    design_load_n: float
    installation: str
    result: LoadResult
    constant_pitch: LoadResult
    linear: LoadResult
    stiffness: dict[str, Any]
    off_design: list[dict[str, Any]]
    sensitivity: dict[str, Any]
    model: LoadModel

    @property
    def max_ldc(self) -> float:
        """The worst coefficient of both sides at the design load."""
        return float(max(self.result.ldc_nr.max(), self.result.ldc_rs.max()))


#: Loads of the off-design rows of :class:`LoadDistribution`, as fractions of the design load.
LOAD_FRACTIONS = (0.25, 0.5, 1.0, 1.5)


def load_distribution(design: PRSDesign, model: LoadModel | None = None,
                      progress: ProgressFn | None = None) -> LoadDistribution:
    """The load distribution of ``design`` under ``model`` (default :func:`build_model`).

    ``progress("loads", done, total)`` is called after every sub-step: base solve, constant
    pitch, linear model, stiffness, each off-design load and each chunk of the sensitivity
    study."""
    model = model or build_model(design)
    total = 4 + len(LOAD_FRACTIONS) + sensitivity_chunks(design, model)
    count = [0]

    def tick(*_: Any) -> None:
        count[0] += 1
        if progress is not None:
            progress("loads", min(count[0], total), total)

    r = forward(design, model=model)
    tick()
    rc = forward(design.constant_pitch(), model=model)
    tick()
    lin = forward(design, model=model, linear_at=r.mean)
    tick()
    stiffness = axial_stiffness(design, model)
    tick()
    off = off_design(design, LOAD_FRACTIONS, model=model)
    for _ in off:
        tick()
    sens = pitch_error_sensitivity(design, model=model, progress=tick)
    return LoadDistribution(design_load_n=design.loading.axial_load_n, installation=design.loading.installation,
                            result=r, constant_pitch=rc, linear=lin, stiffness=stiffness, off_design=off,
                            sensitivity=sens, model=model)


def compliance_model(model: LoadModel) -> str:
    """The name of a load model's tooth compliance: ``"analytic"`` (the diagonal Yamamoto
    terms), ``"fe"`` (finite-element tooth matrices, :mod:`prs_geom.analysis.fe.compliance`) or
    ``"dense"`` (another dense compliance handed in)."""
    if model.compliance is None:
        return "analytic"
    compliance = model.details.compliance if model.details is not None else None
    return compliance or "dense"


# --------------------------------------------------------------------------- model risk
#: Loads of the model-risk study, as fractions of the design load (those of ``off_design``).
MODEL_RISK_FRACTIONS = (0.25, 0.5, 1.0, 1.5)


@dataclass(frozen=True)
class ModelRiskCase:
    """The coefficients of one set of pitch lists under one compliance model at one load.

    ``pitch_lists``: ``"constant pitch"``, ``"design pitch lists"`` (the design's own) or
    ``"equal load"``; ``designed_with``: the model the equal-load lists were designed with
    (None for the other two); ``evaluated_with``: the model of this solve."""

    pitch_lists: str
    designed_with: str | None
    evaluated_with: str
    load_fraction: float
    load_n: float
    ldc_nut_roller: NDArray
    ldc_roller_screw: NDArray
    teeth_out_of_contact: int

    @property
    def label(self) -> str:
        """E.g. ``"equal load designed with analytic, under fe"``."""
        made = f" designed with {self.designed_with}" if self.designed_with else ""
        return f"{self.pitch_lists}{made}, under {self.evaluated_with}"

@dataclass(frozen=True)
class ModelRisk:
    """How much the load sharing depends on the compliance model: every set of pitch lists
    (constant pitch, the design's own lists when graded, the equal-load lists designed with
    the models of ``designed_with``) evaluated with every model at every load fraction
    (:func:`model_risk`). ``descriptions``: one line per model name (may be empty)."""

    models: tuple[str, ...]
    design_load_n: float
    load_fractions: tuple[float, ...]
    cases: tuple[ModelRiskCase, ...]
    designed_with: tuple[str, ...] = ()
    descriptions: Mapping[str, str] = field(default_factory=dict)

    def worst(self, pitch_lists: str, designed_with: str | None, evaluated_with: str,
              load_fraction: float = 1.0) -> tuple[float, float]:
        """(worst nut-roller, worst roller-screw) coefficient of one case."""
        c = self.case(pitch_lists, designed_with, evaluated_with, load_fraction)
        return float(c.ldc_nut_roller.max()), float(c.ldc_roller_screw.max())

    def list_sets(self) -> list[tuple[str, str | None]]:
        """The sets of pitch lists, (pitch_lists, designed_with), in study order."""
        out: list[tuple[str, str | None]] = []
        for c in self.cases:
            if (c.pitch_lists, c.designed_with) not in out:
                out.append((c.pitch_lists, c.designed_with))
        return out

    def case(self, pitch_lists: str, designed_with: str | None, evaluated_with: str,
             load_fraction: float = 1.0) -> ModelRiskCase:
        """The case of these lists under ``evaluated_with`` at ``load_fraction``."""
        for c in self.cases:
            if (c.pitch_lists, c.designed_with, c.evaluated_with) == (pitch_lists, designed_with, evaluated_with) \
                    and c.load_fraction == load_fraction:
                return c
        raise KeyError((pitch_lists, designed_with, evaluated_with, load_fraction))

    @property
    def largest_model_difference(self) -> float:
        """max |LDC under one model - LDC under another| over every tooth, side, set of
        lists and load: how far the answer moves with the model."""
        worst = 0.0
        for c in self.cases:
            for o in self.cases:
                if (o.pitch_lists, o.designed_with, o.load_fraction) == (c.pitch_lists, c.designed_with,
                                                                          c.load_fraction):
                    worst = max(worst, float(np.abs(c.ldc_nut_roller - o.ldc_nut_roller).max()),
                                float(np.abs(c.ldc_roller_screw - o.ldc_roller_screw).max()))
        return worst

def model_risk(design: PRSDesign, models: dict[str, LoadModel],
               fractions: Sequence[float] = MODEL_RISK_FRACTIONS, designed_with: Sequence[str] | None = None,
               descriptions: Mapping[str, str] | None = None) -> ModelRisk:
    """Every set of pitch lists under every model (by name) at every load fraction.

    The lists: constant pitch, the design's own lists when it is graded, and the equal-load
    lists designed with each model named in ``designed_with`` (default: every model;
    :func:`design_pitches`). One batched solve per set of lists and model. ``descriptions``:
    a line per model for the reports."""
    designers = tuple(models) if designed_with is None else tuple(designed_with)
    unknown = [m for m in designers if m not in models]
    if unknown:
        raise ValueError(f"designed_with names models not given: {unknown}")
    F0 = design.loading.axial_load_n
    p = design.thread.pitch_mm
    k = design.thread.engaged_teeth - 1
    lists: list[tuple[str, str | None, Sequence[float], Sequence[float]]] = [
        ("constant pitch", None, [p] * k, [p] * k)]
    if design.graded:
        lists.append(("design pitch lists", None, design.pitch_list("roller"), design.pitch_list("nut")))
    for name in designers:
        pd = design_pitches(design, model=models[name])
        lists.append(("equal load", name, pd.roller_mm, pd.nut_mm))
    fr = np.array([float(f) for f in fractions])
    cases = []
    for label, made, pr, pn in lists:
        g_nr, g_rs = gap_terms(design, pr, pn)
        for name, m in models.items():
            b = solve_loads_batch(m, fr * F0, np.tile(g_nr, (fr.size, 1)), np.tile(g_rs, (fr.size, 1)))
            for i in range(fr.size):
                r = b[i]
                cases.append(ModelRiskCase(label, made, name, float(fr[i]), float(fr[i] * F0), r.ldc_nr, r.ldc_rs,
                                           int((~r.active_nr).sum() + (~r.active_rs).sum())))
    return ModelRisk(tuple(models), F0, tuple(float(f) for f in fr), tuple(cases), designers,
                     dict(descriptions or {}))


@dataclass(frozen=True)
class LoadsResult:
    """The loads stage of a build, computed once and passed on.

    ``distribution``: the load distribution (``distribution.result`` are the tooth loads at
    the design load with the design's pitch lists); ``equal_load`` the pitch lists that
    share equally at the design load. ``designed`` is what the plots show as the designed
    state: the design's own lists for a graded design, else the equal-load design, with its
    coefficients (``designed_ldc``), off-design rows and label.
    """

    model: LoadModel
    distribution: LoadDistribution
    equal_load: PitchDesign
    designed_ldc: dict[str, list[float]]
    designed_off_design: list[dict[str, Any]]
    designed_label: str
    designed_roller_mm: tuple[float, ...]
    designed_nut_mm: tuple[float, ...]
    model_risk: ModelRisk | None = None

    @property
    def result(self) -> LoadResult:
        """The tooth loads at the design load with the design's pitch lists."""
        return self.distribution.result

    @property
    def ldc_nut_roller(self) -> NDArray:
        """Load-distribution coefficients of the nut-roller contacts, tooth 1 first."""
        return self.result.ldc_nr

    @property
    def ldc_roller_screw(self) -> NDArray:
        """Load-distribution coefficients of the roller-screw contacts, tooth 1 first."""
        return self.result.ldc_rs

    @property
    def max_ldc(self) -> float:
        """The worst coefficient of both sides."""
        return self.distribution.max_ldc


def analyse_loads(design: PRSDesign, contact: ContactResult | None = None,
                  progress: ProgressFn | None = None, model: LoadModel | None = None,
                  compare: dict[str, LoadModel] | None = None, designed_with: Sequence[str] | None = None,
                  descriptions: Mapping[str, str] | None = None) -> LoadsResult:
    """The loads stage: load distribution, equal-load design and the curves
    of the designed state (see :class:`LoadsResult`).

    ``model``: the load model to use (default the analytic :func:`build_model`; the FE one
    comes from :func:`prs_geom.analysis.fe.compliance.fe_load_model`). ``compare``: models by
    name for the model-risk study (:func:`model_risk`, with ``designed_with`` and
    ``descriptions``), or None for none."""
    model = build_model(design, contact) if model is None else model
    distribution = load_distribution(design, model, progress)
    equal = design_pitches(design, model=model)
    if design.graded:
        result = distribution.result
        shown = {"ldc_nut_roller": result.ldc_nr.tolist(), "ldc_roller_screw": result.ldc_rs.tolist()}
        off, label = distribution.off_design, "design pitch lists"
        pr, pn = tuple(design.pitch_list("roller")), tuple(design.pitch_list("nut"))
    else:
        eq = with_pitch_lists(design, equal)
        r = forward(eq, model=model)
        shown = {"ldc_nut_roller": r.ldc_nr.tolist(), "ldc_roller_screw": r.ldc_rs.tolist()}
        off, label = off_design(eq, model=model), "equal-load pitch design"
        pr, pn = equal.roller_mm, equal.nut_mm
    risk = model_risk(design, compare, designed_with=designed_with, descriptions=descriptions) if compare else None
    return LoadsResult(model=model, distribution=distribution, equal_load=equal, designed_ldc=shown,
                       designed_off_design=off, designed_label=label, designed_roller_mm=pr, designed_nut_mm=pn,
                       model_risk=risk)


def design_pitch(design: PRSDesign, target: str | dict[str, Sequence[float]] = "equal",
                 name: str | None = None, contact: ContactResult | None = None,
                 model: LoadModel | None = None) -> PRSDesign:
    """A new design whose roller and nut pitch lists give the target load sharing at the
    design load: ``"equal"`` (every coefficient 1) or ``{"nut_roller": [...],
    "roller_screw": [...]}`` (n coefficients each, mean 1). Named ``name`` or
    ``<name>-graded``. ``model``: the load model (default the analytic one)."""
    if isinstance(target, str):
        if target != "equal":
            raise DesignError("target", target, 'must be "equal" or a mapping of coefficient lists')
        t_nr = t_rs = None
    else:
        t_nr, t_rs = target.get("nut_roller"), target.get("roller_screw")
    model = build_model(design, contact) if model is None else model
    pd = design_pitches(design, t_nr, t_rs, model=model)
    return with_pitch_lists(design, pd, name=name or f"{design.name}-graded")
