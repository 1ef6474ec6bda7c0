"""Ratings, life, limits, efficiency and stiffness of a planetary roller screw
(docs/theory/ratings.md). Pure math, no I/O.

Roller screws have no ISO rating method. Their makers rate them like ball screws
(ISO 3408-5), all in the Lundberg-Palmgren frame of ISO 281; this module does the same,
with each loaded tooth contact as a rolling element, from the contact geometry the load
stage already knows (the Hertz ellipse of each contact, the contact radii, the number of
loaded teeth and rollers) instead of catalogue factors.

Dynamic capacity of one contact ring (Lundberg and Palmgren 1947; the form of ISO/TR 1281-1
and Harris & Kotzalas, *Rolling Bearing Analysis*, the chapter on fatigue life)
---------------------------------------------------------------------------------------
A "ring" is the band of a flank that one tooth contact rolls over: the screw flank at tooth
position j (n rings, shared by the z rollers), the nut flank at tooth j (n rings), and on
every roller the flank of tooth j facing the screw and the flank facing the nut (z n rings
each). Lundberg-Palmgren: the probability S that a ring survives N stress cycles obeys
ln(1/S) = A tau_0^c N^e V / z_0^h with the stressed volume V = a z_0 l (a: semi-axis across
the rolling direction, l: track length), tau_0 = T sigma_max the orthogonal shear stress
amplitude at depth z_0 = zeta b (b: semi-axis in the rolling direction), T and zeta functions
of b/a only, c = 31/3, h = 7/3, e = 10/9 (point contact). Hertz gives a, b proportional to
Q^(1/3) and sigma_max = 3Q / (2 pi a b), so the life of a ring in 10^6 revolutions of the
screw is L = (Q_c / Q)^3 with

    Q_c = K G^(-0.3) l^(-0.3) u^(-1/3),   G = (3 T / (2 pi a* b*))^c a* (zeta b*)^(1-h),

a*, b* the semi-axes per N^(1/3), u the stress cycles at a point of the ring per screw
revolution and K the material constant. K is not fitted to roller screws: it is the constant
that makes this general form reproduce the published closed form of the same theory for a
ball on a grooved raceway, Q_c = 98.1 (2f/(2f-1))^0.41 (1 -+ gamma)^1.39 / (1 +- gamma)^(1/3)
(gamma/cos alpha)^0.3 D^1.8 Z^(-1/3) (N, mm; the basis of ISO 281 and ISO 3408-5), fitted
over its range of use (conformity f 0.515 to 0.54, gamma 0.05 to 0.3, both raceways; the
closed form stays within -3 % / +5 % of the general form there, :func:`calibration_spread`:
the closed form's (2f/(2f-1))^0.41 is itself a fit of the same Hertz functions). Carried over to a
roller screw this way, the rating holds for through-hardened bearing steel like the
constant it comes from; no material factor b_m is applied.

Cycles per screw revolution (ideal rolling at the pitch circles, DOMAIN 9: carrier speed
w_c = w_s r_s / (r_s + r_n)): screw ring u = z (1 - w_c/w_s), nut
ring u = z w_c/w_s, each roller flank ring u = (w_c/w_s) r_n / r_r (one contact per roller
turn relative to the carrier). Track length l = 2 pi r at the contact radius of that part.

System life and ratings
-----------------------
The rings fail independently, so (Lundberg-Palmgren, as ISO 281 combines rings)
1/L^e = sum over rings 1/L_ring^e. With equal sharing every contact of a side carries
Q = F / (n z n_z) (n_z the axial component of the contact normal), which gives the basic
dynamic axial load rating C_a = [sum_k N_k (n z n_z,k Q_c,k)^(-10/3)]^(-0.3) (N_k rings of
class k) with L10 = (C_a / F)^3 10^6 revolutions. With the actual tooth loads of the load
model the same sum runs over the rings with their own loads: the life of constant pitch,
equal-load pitch, the design's lists or a robust design, from one formula; equal sharing
gives back C_a exactly, and by convexity of Q^(10/3) no other sharing of the same load lives
longer (the test of the graded pitch). A duty cycle enters each ring as its cubic mean
load over the revolutions of the cases (ISO 281 / ISO 3408-5 practice).

Static rating C_0a: the axial load at which the most loaded contact reaches the Hertz
pressure ``rating.static_pressure_limit_mpa`` (4200 MPa, ISO 76 point contact), with equal
sharing; the static safety against the material limit from the actual tooth loads is
(p_lim / p_max)^3 (the load factor, p is proportional to Q^(1/3)).

Limit checks: ``limits.checks`` lists speed, d n, critical speed, buckling and
static safety as ``{name, kind, value, limit, unit, margin, passed}`` at the largest duty
speed and load (:data:`LIMIT_CHECKS`; margin = limit / value - 1 for an upper limit, value /
limit - 1 for the lower limit s_0 >= ``rating.required_static_safety``; >= 0 passes).

Catalogue life (DOMAIN 7, ISO 3408-5): F_m = (sum F_i^3 n_i q_i / sum n_i q_i)^(1/3),
n_m = sum n_i q_i, L10 = a_1 (C_a / (f_w F_m))^3 10^6 revolutions, hours L10 / (60 n_m),
a_1 from the table of ISO 3408-5 / ISO 281:1990 at its points (95 %: 0.62, 96: 0.53,
97: 0.44, 98: 0.33, 99: 0.21), between them 4.48 (ln(100/R))^(2/3).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any, Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import PchipInterpolator

from prs_geom.analysis.contact import ContactResult, analyse_contact
from prs_geom.analysis.loads import (LoadModel, build_model, check_load_scale, design_pitches, hertz_constant,
                                     pitch_gaps, solve_loads_batch)
from prs_geom.model.design import LIFE_RANGE_HOURS, SPEED_RANGE_RPM, PRSDesign, RatingSettings, Supports
from prs_geom.model.errors import DesignError
from prs_geom.model.spectrum import Spectrum
from prs_geom.model.validation import LOAD_RANGE_N

__all__ = ["LP_C", "LP_H", "WEIBULL_E", "LP_BALL_CONSTANT", "A1_TABLE", "END_CASES", "STEEL_DENSITY_T_PER_MM3",
           "reliability_factor", "equivalent_load", "life_revolutions", "life_hours", "required_dynamic_load",
           "lp_stress_functions", "ring_capacity", "lp_ball_raceway_capacity", "general_ball_raceway_capacity",
           "calibration_constant", "calibration_spread", "ContactRings", "contact_rings", "dynamic_load_rating",
           "static_load_rating", "system_life", "hertz_pressure", "efficiency", "drive_torque", "critical_speed",
           "buckling_load", "double_nut", "LIMIT_CHECKS", "LimitCheck", "limit_check", "limit_checks",
           "RatingCase", "rating_case", "VariantLife", "RatingStiffness", "RatingLimits", "RatingCurves",
           "ResolvedSupports", "resolve_supports",
           "RatingResult", "analyse_rating", "CURVE_FRACTIONS"]

#: Lundberg-Palmgren exponents of point contact: stress c, depth h, Weibull slope e; they
#: give the load-life exponent (c - h + 2) / (3 e) = 3.
LP_C, LP_H, WEIBULL_E = 31.0 / 3.0, 7.0 / 3.0, 10.0 / 9.0
#: Constant of the closed-form capacity of a ball raceway, N and mm (Lundberg and Palmgren
#: 1947; 7450 in lbf and inches; Harris & Kotzalas, Rolling Bearing Analysis).
LP_BALL_CONSTANT = 98.1
#: Elastic constants of the bearing steel behind that constant (E MPa, nu).
REFERENCE_STEEL = (207_000.0, 0.3)
#: The calibration range of the closed form: ball-bearing groove conformities and gamma.
CALIBRATION_CONFORMITY = (0.515, 0.52, 0.525, 0.53, 0.54)
CALIBRATION_GAMMA = (0.05, 0.1, 0.15, 0.2, 0.25, 0.3)
#: Reliability factor a_1 of ISO 3408-5 and ISO 281:1990 at the points of their table (%).
A1_TABLE = {90.0: 1.0, 95.0: 0.62, 96.0: 0.53, 97.0: 0.44, 98.0: 0.33, 99.0: 0.21}
#: End-support cases: first eigenvalue lambda of the Euler-Bernoulli beam (critical speed
#: n = (60 / 2 pi) (lambda / L)^2 sqrt(E I / rho A)) and effective-length factor of Euler
#: buckling (F = pi^2 E I / (k L)^2); Timoshenko & Gere, Theory of Elastic Stability, and any
#: vibration text. They reproduce the catalogue constants 276/190/122/43 x 10^6 (steel) of
#: Eichenberger Gewinde AG, "Bases de calculs" of its Carry ball screws, p. 35.
END_CASES: dict[str, tuple[float, float]] = {
    "fixed-fixed": (4.730040745, 0.5),
    "fixed-supported": (3.926602312, 0.699),
    "supported-supported": (math.pi, 1.0),
    "fixed-free": (1.875104069, 2.0),
}
#: Density of the screw steel (t/mm^3, i.e. 7850 kg/m^3), for the whirling speed.
STEEL_DENSITY_T_PER_MM3 = 7.85e-9
#: Loads of the life and stiffness curves, as fractions of the design load.
CURVE_FRACTIONS = tuple(float(x) for x in np.round(np.linspace(0.1, 1.5, 15), 6))


# --------------------------------------------------------------------------- catalogue formulas
def reliability_factor(reliability_pct: float) -> float:
    """Life factor a_1 for a reliability R (%) from 90 to 99 (ISO 3408-5, ISO 281:1990):
    the table value at its points, else 4.48 (ln(100/R))^(2/3) (which rounds to the table)."""
    r = float(reliability_pct)
    if not (math.isfinite(r) and 90.0 <= r <= 99.0):
        raise DesignError("reliability_pct", reliability_pct, "must be from 90 to 99 %")
    for k, v in A1_TABLE.items():
        if abs(r - k) < 1e-9:
            return v
    return 4.48 * math.log(100.0 / r) ** (2.0 / 3.0)


def equivalent_load(spectrum: Spectrum) -> tuple[float, float]:
    """Cubic-mean load F_m (N) and mean speed n_m (rpm) of a duty cycle with speeds:
    F_m = (sum F_i^3 n_i q_i / sum n_i q_i)^(1/3), n_m = sum n_i q_i (ISO 3408-5; DOMAIN 7)."""
    if not spectrum.has_speeds:
        raise DesignError("case[0].speed_rpm", None, "the ratings need speed_rpm on every case of the spectrum")
    F = np.array([c.load_n for c in spectrum.cases])
    n = np.array([c.speed_rpm for c in spectrum.cases])
    q = np.array([c.time_share for c in spectrum.cases])
    nq = n * q
    return float(np.cbrt((F ** 3 * nq).sum() / nq.sum())), float(nq.sum())


def life_revolutions(C: float, F: float, a1: float = 1.0, fw: float = 1.0) -> float:
    """L10 (or L_R with a_1) in revolutions: a_1 (C / (f_w F))^3 10^6."""
    return a1 * (C / (fw * F)) ** 3 * 1e6


def life_hours(revolutions: float, speed_rpm: float) -> float:
    """Life in hours at the mean speed: L / (60 n_m)."""
    return revolutions / (60.0 * speed_rpm)


def required_dynamic_load(F: float, speed_rpm: float, hours: float, a1: float = 1.0, fw: float = 1.0) -> float:
    """Dynamic load rating C (N) for a target life: f_w F (60 n_m L_h / (a_1 10^6))^(1/3)."""
    return fw * F * (60.0 * speed_rpm * hours / (a1 * 1e6)) ** (1.0 / 3.0)


# --------------------------------------------------------------------------- Lundberg-Palmgren
def lp_stress_functions(rolling_over_transverse: float | NDArray) -> tuple[NDArray, NDArray]:
    """T = tau_0 / sigma_max and zeta = z_0 / b of Lundberg-Palmgren for a contact ellipse with
    semi-axes b (rolling direction) and a (across): t > 1 solves (t^2 - 1)(2t - 1) = (b/a)^2,
    T = sqrt(2t - 1) / (2t (t + 1)), zeta = 1 / ((t + 1) sqrt(2t - 1)).

    Newton on the cubic, vectorised; it increases monotonically for t > 1 and is convex there,
    so Newton from the right converges."""
    r2 = np.asarray(rolling_over_transverse, dtype=np.float64) ** 2
    t = 1.0 + np.maximum(1.0, np.cbrt(r2))          # to the right of the root
    for _ in range(60):
        g = (t * t - 1.0) * (2.0 * t - 1.0) - r2
        dg = 6.0 * t * t - 2.0 * t - 2.0
        step = g / dg
        t = t - step
        if np.all(np.abs(step) <= 1e-15 * t):
            break
    s = np.sqrt(2.0 * t - 1.0)
    return s / (2.0 * t * (t + 1.0)), 1.0 / ((t + 1.0) * s)


def _geometry_term(rolling: float, transverse: float) -> float:
    """G = (3T / (2 pi a* b*))^c a* (zeta b*)^(1-h) of the module docstring (semi-axes per
    N^(1/3), mm)."""
    T, zeta = (float(v) for v in lp_stress_functions(rolling / transverse))
    return (3.0 * T / (2.0 * math.pi * transverse * rolling)) ** LP_C * transverse * (zeta * rolling) ** (1.0 - LP_H)


def _axes(circ: float, a: float, b: float) -> tuple[float, float]:
    """(rolling, transverse) semi-axes per N^(1/3) from the circumferential, semi-major and
    semi-minor semi-axes of a Hertz contact (:func:`hertz_constant`): the rolling direction
    is the circumferential one (plane 2 of its curvature order)."""
    return circ, (b if abs(circ - a) <= abs(circ - b) else a)


def _unit_capacity(rolling: float, transverse: float, track_mm: float, cycles: float) -> float:
    """G^(-0.3) l^(-0.3) u^(-1/3): the capacity of a ring without the material constant."""
    return _geometry_term(rolling, transverse) ** -0.3 * track_mm ** -0.3 * cycles ** (-1.0 / 3.0)


def _ball_raceway(D: float, gamma: float, f: float, inner: bool) -> tuple[tuple[float, ...], float, float]:
    """Curvatures (ball, ball, groove, rolling), track length and cycles per inner-ring turn per
    ball of a ball on the inner or outer raceway (contact angle 0, outer ring fixed)."""
    if inner:
        curv = (2.0 / D, 2.0 / D, -1.0 / (f * D), 2.0 * gamma / (D * (1.0 - gamma)))
        return curv, math.pi * D * (1.0 - gamma) / gamma, (1.0 + gamma) / 2.0
    curv = (2.0 / D, 2.0 / D, -1.0 / (f * D), -2.0 * gamma / (D * (1.0 + gamma)))
    return curv, math.pi * D * (1.0 + gamma) / gamma, (1.0 - gamma) / 2.0


def lp_ball_raceway_capacity(D: float, gamma: float, f: float, Z: int, inner: bool = True) -> float:
    """Closed-form Lundberg-Palmgren capacity of a ball raceway at contact angle 0 (N, mm):
    98.1 (2f/(2f-1))^0.41 (1 -+ gamma)^1.39 / (1 +- gamma)^(1/3) gamma^0.3 D^1.8 Z^(-1/3)."""
    shape = (1 - gamma) ** 1.39 / (1 + gamma) ** (1 / 3) if inner else (1 + gamma) ** 1.39 / (1 - gamma) ** (1 / 3)
    return LP_BALL_CONSTANT * (2 * f / (2 * f - 1)) ** 0.41 * shape * gamma ** 0.3 * D ** 1.8 * Z ** (-1.0 / 3.0)


def _reference_eta() -> float:
    E, nu = REFERENCE_STEEL
    return 2.0 * (1.0 - nu * nu) / E


def general_ball_raceway_capacity(D: float, gamma: float, f: float, Z: int, inner: bool = True,
                                  K: float | None = None) -> float:
    """The same capacity from the general form of this module (Hertz of the ball contact,
    track length, Z (1 +- gamma)/2 cycles per turn) with constant K (default the calibrated)."""
    curv, track, per_ball = _ball_raceway(D, gamma, f, inner)
    _, h = hertz_constant(curv, _reference_eta())
    return (calibration_constant() if K is None else K) * _unit_capacity(
        *_axes(h["circumferential_semi_axis_per_cbrt_N_mm"], h["semi_major_per_cbrt_N_mm"],
               h["semi_minor_per_cbrt_N_mm"]), track, Z * per_ball)


@lru_cache(maxsize=1)
def _calibration() -> tuple[float, float, float]:
    ratios = []
    for f in CALIBRATION_CONFORMITY:
        for g in CALIBRATION_GAMMA:
            for inner in (True, False):
                ratios.append(lp_ball_raceway_capacity(10.0, g, f, 10, inner)
                              / general_ball_raceway_capacity(10.0, g, f, 10, inner, K=1.0))
    r = np.array(ratios)
    K = float(np.exp(np.log(r).mean()))
    return K, float(r.min() / K), float(r.max() / K)


def calibration_constant() -> float:
    """K of the general form: the geometric mean, over the calibration range, of the ratio of
    the closed form to the general form with K = 1 (computed once)."""
    return _calibration()[0]


def calibration_spread() -> tuple[float, float]:
    """Smallest and largest ratio closed form / general form over the calibration range."""
    return _calibration()[1:]


def ring_capacity(rolling: float, transverse: float, track_mm: float, cycles_per_rev: float) -> float:
    """Dynamic capacity Q_c (N, normal load) of one contact ring for 10^6 screw revolutions at
    90 % survival: semi-axes per N^(1/3) in and across the rolling direction (mm), track
    length (mm), stress cycles at a point of the track per screw revolution."""
    return calibration_constant() * _unit_capacity(rolling, transverse, track_mm, cycles_per_rev)


# --------------------------------------------------------------------------- the rings of a design
@dataclass(frozen=True)
class ContactRings:
    """The four classes of rings of a design (module docstring), in the order screw, roller
    (screw side), roller (nut side), nut. ``side``: 0 for the roller-screw contact, 1 for the
    nut-roller contact; ``count``: rings of the class; ``capacity_n``: Q_c (normal, N);
    ``cycles``: u per screw revolution; ``track_mm``: l. Per side: ``axial_component`` n_z,
    ``axes_per_cbrt_n`` (rolling, transverse) and the tooth-load to axial-rating factor."""

    names: tuple[str, ...]
    side: tuple[int, ...]
    count: tuple[int, ...]
    capacity_n: tuple[float, ...]
    cycles: tuple[float, ...]
    track_mm: tuple[float, ...]
    axial_component: tuple[float, float]
    axes_per_cbrt_n: tuple[tuple[float, float], tuple[float, float]]
    n: int
    z: int

    def as_dict(self) -> dict[str, Any]:
        return {name: {"contact": ("roller-screw", "nut-roller")[s], "rings": c, "capacity_n": q,
                       "cycles_per_screw_rev": u, "track_mm": l}
                for name, s, c, q, u, l in zip(self.names, self.side, self.count, self.capacity_n, self.cycles,
                                              self.track_mm)}


def contact_rings(design: PRSDesign, contact: ContactResult, model: LoadModel) -> ContactRings:
    """The rings of ``design`` from its contact points and the Hertz details of its load model."""
    if model.details is None:
        raise ValueError("the rating needs the Hertz constants of a load model built by build_model")
    rs, nr = model.details.hertz_rs, model.details.hertz_nr
    c_rs = contact.screw_roller["upper_at_theoretical"]
    c_nr = contact.roller_nut["lower"]
    r_s, r_r, r_n = (0.5 * design.screw.pitch_diameter_mm, 0.5 * design.roller.pitch_diameter_mm,
                     0.5 * design.nut.pitch_diameter_mm)
    z, n = design.roller.count, design.thread.engaged_teeth
    carrier = r_s / (r_s + r_n)                        # w_c / w_s, DOMAIN 9
    roller = carrier * r_n / r_r                       # roller turns relative to the carrier per screw turn
    ax = tuple(_axes(h.circumferential_semi_axis_per_cbrt_N_mm, h.semi_major_per_cbrt_N_mm,
                     h.semi_minor_per_cbrt_N_mm) for h in (rs, nr))
    rows = [("screw", 0, n, z * (1.0 - carrier), 2 * math.pi * c_rs.part_radius_mm),
            ("roller_screw_side", 0, z * n, roller, 2 * math.pi * c_rs.roller_radius_mm),
            ("roller_nut_side", 1, z * n, roller, 2 * math.pi * c_nr.roller_radius_mm),
            ("nut", 1, n, z * carrier, 2 * math.pi * c_nr.part_radius_mm)]
    caps = tuple(ring_capacity(*ax[s], l, u) for _, s, _, u, l in rows)
    return ContactRings(tuple(r[0] for r in rows), tuple(r[1] for r in rows), tuple(r[2] for r in rows), caps,
                        tuple(r[3] for r in rows), tuple(r[4] for r in rows),
                        (float(rs.normal_axial_component), float(nr.normal_axial_component)), ax, n, z)


def dynamic_load_rating(rings: ContactRings) -> float:
    """C_a (N): C_a = [sum_k N_k (n z n_z,k Q_c,k)^(-10/3)]^(-0.3) (equal sharing)."""
    s = 0.0
    for side, count, q in zip(rings.side, rings.count, rings.capacity_n):
        s += count * (rings.n * rings.z * rings.axial_component[side] * q) ** (-10.0 / 3.0)
    return s ** -0.3


def static_load_rating(rings: ContactRings, pressure_limit_mpa: float) -> tuple[float, list[float]]:
    """C_0a (N) with equal sharing, and the normal contact load of each side at the limit:
    p = 3 Q^(1/3) / (2 pi a* b*) = p_lim gives Q_0 = (2 pi a* b* p_lim / 3)^3."""
    q0 = [(2.0 * math.pi * a * b * pressure_limit_mpa / 3.0) ** 3 for a, b in rings.axes_per_cbrt_n]
    return rings.n * rings.z * min(q * nz for q, nz in zip(q0, rings.axial_component)), q0


def hertz_pressure(rings: ContactRings, side: int, axial_tooth_load: NDArray) -> NDArray:
    """Maximum Hertz pressure (MPa) of contacts carrying axial tooth loads (N), any shape."""
    a, b = rings.axes_per_cbrt_n[side]
    q = np.maximum(np.asarray(axial_tooth_load, dtype=np.float64), 0.0) / rings.axial_component[side]
    return 3.0 * np.cbrt(q) / (2.0 * math.pi * a * b)


def system_life(rings: ContactRings, f_rs: NDArray, f_nr: NDArray, weights: NDArray | None = None) -> NDArray:
    """Life (10^6 screw revolutions, 90 %) of the ring system with axial tooth loads of one
    roller (all rollers alike) f_rs, f_nr, shape (..., C, n) for C duty cases of revolution
    weights ``weights`` (C,) (default one case, shape (..., n)): each ring takes its cubic
    mean load over the cases, then 1/L^e = sum over rings (Q_ring / Q_c)^(10/3)."""
    f_rs = np.asarray(f_rs, dtype=np.float64)
    f_nr = np.asarray(f_nr, dtype=np.float64)
    if weights is None:
        f_rs, f_nr, w = f_rs[..., None, :], f_nr[..., None, :], np.ones(1)
    else:
        w = np.asarray(weights, dtype=np.float64)
        w = w / w.sum()
    loads = (np.maximum(f_rs, 0.0) / rings.axial_component[0], np.maximum(f_nr, 0.0) / rings.axial_component[1])
    # each ring's cubic mean load over the cases (revolution-weighted)
    q_eq = [np.cbrt(np.tensordot(q ** 3, w, axes=([-2], [0]))) for q in loads]
    total = 0.0
    for side, count, qc in zip(rings.side, rings.count, rings.capacity_n):
        per_tooth = (q_eq[side] / qc) ** (10.0 / 3.0)
        total = total + (count // rings.n) * per_tooth.sum(axis=-1)     # rollers: z rings per tooth
    with np.errstate(divide="ignore"):
        return np.asarray(total, dtype=np.float64) ** (-1.0 / WEIBULL_E)


# --------------------------------------------------------------------------- efficiency, limits
def efficiency(lead_mm: float, pitch_diameter_mm: float, mu: float, beta_rad: float) -> dict[str, float]:
    """Forward tan(lambda)/tan(lambda + rho') and back-driving tan(lambda - rho')/tan(lambda)
    efficiency, rho' = atan(mu / cos beta), lambda the lead angle at the pitch diameter (DOMAIN 7;
    the thread-friction form of a screw, e.g. Niemann, Maschinenelemente I). A negative
    back-driving value means the screw holds the load by itself (reported as 0)."""
    lam = math.atan(lead_mm / (math.pi * pitch_diameter_mm))
    rho = math.atan(mu / math.cos(beta_rad))
    fwd = math.tan(lam) / math.tan(lam + rho)
    back = math.tan(lam - rho) / math.tan(lam)
    return {"lead_angle_deg": math.degrees(lam), "friction_angle_deg": math.degrees(rho), "forward": fwd,
            "back_driving": max(back, 0.0), "self_locking": back <= 0.0}


def drive_torque(load_n: float, lead_mm: float, eta_forward: float) -> float:
    """Torque (N m) to drive a load F against the thread: F L / (2 pi eta)."""
    return load_n * lead_mm / (2.0 * math.pi * eta_forward) / 1e3


def critical_speed(root_diameter_mm: float, length_mm: float, ends: str, E_mpa: float,
                   density_t_per_mm3: float = STEEL_DENSITY_T_PER_MM3) -> float:
    """First whirling speed (rpm) of the screw as an Euler-Bernoulli beam on the root diameter:
    (60 / 2 pi) (lambda / L)^2 sqrt(E I / (rho A)), I = pi d^4 / 64, A = pi d^2 / 4."""
    lam = END_CASES[ends][0]
    d = root_diameter_mm
    return 60.0 / (2.0 * math.pi) * (lam / length_mm) ** 2 * math.sqrt(E_mpa / density_t_per_mm3) * d / 4.0


def buckling_load(root_diameter_mm: float, length_mm: float, ends: str, E_mpa: float) -> float:
    """Euler buckling load (N): pi^2 E I / (k L)^2 on the root diameter, k of :data:`END_CASES`."""
    k = END_CASES[ends][1]
    I = math.pi * root_diameter_mm ** 4 / 64.0
    return math.pi ** 2 * E_mpa * I / (k * length_mm) ** 2


def double_nut(loads_n: NDArray, deflection_mm: NDArray, preload_n: float,
               external_n: NDArray) -> dict[str, NDArray | float]:
    """A double nut of two equal halves preloaded against each other by F_pr.

    ``loads_n``/``deflection_mm``: the axial force-deflection curve delta(F) of one half
    (increasing, starting at (0, 0)), interpolated by a monotone cubic (PCHIP) in F^(2/3), the
    variable in which Hertz is linear: the infinite slope at F = 0, which the unloaded half
    reaches at lift-off, is then exact, and the pair's stiffness has no kinks from the table. Under an external load F the
    loaded half carries F_A and the other F_B = F_A - F, with the halves' deflections changing
    by equal and opposite amounts: delta(F_A) + delta(F_A - F) = 2 delta(F_pr). The preload is
    lost when F_B = 0, at the load F_lift with delta(F_lift) = 2 delta(F_pr) (2^(3/2) F_pr =
    2.83 F_pr for a purely Hertzian curve, the rule of the Rollvis catalogue, calculation
    example p. 16); beyond it the loaded half works alone. Returns F_A, F_B, the nut's
    displacement x = delta(F_A) - delta(F_pr) (mm) and the lift-off load, vectorised over
    ``external_n``."""
    Fg = np.asarray(loads_n, dtype=np.float64)
    dg = np.asarray(deflection_mm, dtype=np.float64)
    ug = np.cbrt(Fg) ** 2
    curve = PchipInterpolator(ug, dg, extrapolate=True)

    def delta(F: NDArray) -> NDArray:
        return curve(np.cbrt(np.maximum(F, 0.0)) ** 2)

    d_pr = float(delta(preload_n))
    lift = float(PchipInterpolator(dg, ug)(2.0 * d_pr)) ** 1.5
    F = np.asarray(external_n, dtype=np.float64)
    lo = np.maximum(F, preload_n)
    hi = np.maximum(lift, F)
    for _ in range(80):                          # bisection: delta(F_A) + delta(F_A - F) rises with F_A
        mid = 0.5 * (lo + hi)
        high = delta(mid) + delta(np.maximum(mid - F, 0.0)) > 2.0 * d_pr
        hi = np.where(high, mid, hi)
        lo = np.where(high, lo, mid)
    FA = np.where(F >= lift, F, 0.5 * (lo + hi))
    return {"loaded_half_n": FA, "other_half_n": FA - F, "displacement_mm": delta(FA) - d_pr,
            "lift_off_n": lift}


# --------------------------------------------------------------------------- limit checks
#: The limit checks of ``rating.limits.checks``, in order: name -> (kind, unit, what is
#: compared). "upper": the value must not exceed the limit, margin = limit / value - 1;
#: "lower": the value must not fall below it, margin = value / limit - 1. Either way a
#: margin >= 0 passes and reads as headroom: 0.25 means the limit is 25 % above the value
#: (upper) or the value 25 % above the limit (lower); -0.5 means the value is twice the upper
#: limit or half the lower one.
LIMIT_CHECKS: dict[str, tuple[str, str, str]] = {
    "speed": ("upper", "rpm", "largest duty speed against the permissible speed (the smaller of the d n "
                              "speed limit and the permissible critical speed)"),
    "dn": ("upper", "mm/min", "nominal diameter x largest duty speed against rating.dn_limit_mm_rpm"),
    "critical_speed": ("upper", "rpm", "largest duty speed against supports.critical_speed_factor x the first "
                                       "whirling speed"),
    "buckling": ("upper", "N", "largest duty load against the Euler buckling load / supports.buckling_safety"),
    "static_safety": ("lower", "-", "s_0 = C_0a / largest duty load against rating.required_static_safety"),
}


@dataclass(frozen=True)
class LimitCheck:
    """One limit check of :data:`LIMIT_CHECKS`: ``value`` against ``limit`` (both in ``unit``),
    ``kind`` "upper" or "lower", ``margin`` (upper: limit / value - 1, lower: value / limit - 1)
    and ``passed`` when the value does not cross the limit (it may equal it)."""

    name: str
    kind: str
    value: float
    limit: float
    unit: str
    margin: float
    passed: bool

    def __post_init__(self) -> None:
        if self.name not in LIMIT_CHECKS or self.kind != LIMIT_CHECKS[self.name][0]:
            raise ValueError(f"limit check {self.name!r} of kind {self.kind!r} is not one of LIMIT_CHECKS")


def limit_check(name: str, value: float, limit: float) -> LimitCheck:
    """The check ``name`` of :data:`LIMIT_CHECKS` of ``value`` against ``limit``, with its margin
    (upper: limit / value - 1, lower: value / limit - 1); passed when the margin is >= 0 (the
    value may equal the limit)."""
    kind, unit, _ = LIMIT_CHECKS[name]
    value, limit = float(value), float(limit)
    margin = limit / value - 1.0 if kind == "upper" else value / limit - 1.0
    passed = value <= limit if kind == "upper" else value >= limit
    return LimitCheck(name=name, kind=kind, value=value, limit=limit, unit=unit, margin=margin, passed=bool(passed))


def limit_checks(limits: "RatingLimits", max_load_n: float, static_safety: float, required_static_safety: float,
                 nominal_diameter_mm: float) -> tuple[LimitCheck, ...]:
    """The five checks of :data:`LIMIT_CHECKS`, in its order, at the largest duty speed
    (``limits.max_speed_rpm``) and the largest duty load ``max_load_n`` (N)."""
    n = limits.max_speed_rpm
    return (limit_check("speed", n, limits.permissible_speed_rpm),
            limit_check("dn", nominal_diameter_mm * n, limits.dn_limit_mm_rpm),
            limit_check("critical_speed", n, limits.permissible_critical_speed_rpm),
            limit_check("buckling", max_load_n, limits.permissible_buckling_load_n),
            limit_check("static_safety", static_safety, required_static_safety))


# --------------------------------------------------------------------------- the analysis
def _finite(value: Any, field: str, field_value: Any, rule: str) -> float:
    """``value`` (or what the callable ``value`` returns) when it is a finite number > 0, else
    a :class:`DesignError` on ``field``: a guard (the design bounds keep every rating finite;
    an overflow, an underflow to 0 or a division by zero names the field if not)."""
    try:
        v = float(value() if callable(value) else value)
    except (OverflowError, ZeroDivisionError, ValueError):
        v = math.nan
    if not (math.isfinite(v) and v > 0.0):
        raise DesignError(field, field_value, rule)
    return v


@dataclass(frozen=True)
class RatingCase:
    """What the life is asked for: the duty cycle (cases with loads N, revolution weights and
    speeds rpm; the limits are checked at the largest load and speed), the operating factor, reliability (%), target life (h) and where the
    numbers came from (``source``)."""

    loads_n: tuple[float, ...]
    weights: tuple[float, ...]
    speeds_rpm: tuple[float, ...]
    equivalent_load_n: float
    equivalent_speed_rpm: float
    operating_factor: float
    reliability_pct: float
    life_hours: float
    source: str
    #: what set the smallest duty load, as the user wrote it (errors name it)
    load_field: str = "loading.axial_load_n"

    @property
    def max_load_n(self) -> float:
        return max(self.loads_n)


def rating_case(design: PRSDesign, spectrum: Spectrum | None = None, mean_load_n: float | None = None,
                speed_rpm: float | None = None, life_hours_target: float | None = None,
                operating_factor: float | None = None, reliability_pct: float | None = None) -> RatingCase:
    """The :class:`RatingCase` of a design: a spectrum with speeds (cubic mean, mean speed), or
    a mean load and speed (default the design load and ``rating.speed_rpm``); the design's
    ``[rating]`` gives what is not stated. Errors name the CLI flag (or the spectrum case).

    Loads and speeds have the ranges of the design's own (1 to 1e10 N,
    :data:`~prs_geom.model.validation.LOAD_RANGE_N`; 0.01 to 1e5 rpm,
    :data:`~prs_geom.model.design.SPEED_RANGE_RPM`; a target life of 1 to 1e7 h)."""
    rs = design.rating or RatingSettings()
    fw = rs.operating_factor if operating_factor is None else operating_factor
    R = rs.reliability_pct if reliability_pct is None else reliability_pct
    H = rs.life_hours if life_hours_target is None else life_hours_target
    (F_lo, F_hi), (n_lo, n_hi), (H_lo, H_hi) = LOAD_RANGE_N, SPEED_RANGE_RPM, LIFE_RANGE_HOURS
    for flag, value, ok, rule in (("--fw", fw, lambda v: 1.0 <= v <= 5.0, "must be from 1 to 5"),
                                  ("--reliability", R, lambda v: 90.0 <= v <= 99.0,
                                   "must be from 90 to 99 % (the a_1 table of ISO 3408-5 / ISO 281:1990)"),
                                  ("--life-hours", H, lambda v: H_lo <= v <= H_hi,
                                   f"must be from {H_lo:g} to {H_hi:g} h")):
        if isinstance(value, bool) or not (isinstance(value, (int, float)) and math.isfinite(value) and ok(value)):
            raise DesignError(flag, value, rule)
    if spectrum is not None:
        if mean_load_n is not None or speed_rpm is not None:
            raise DesignError("--spectrum", "with --mean-load/--speed-rpm",
                              "give either a spectrum or a mean load and speed, not both")
        for k, c in enumerate(spectrum.cases):
            if not F_lo <= c.load_n <= F_hi:
                raise DesignError(f"spectrum case[{k}].load_n", c.load_n, f"must be from {F_lo:g} N to {F_hi:g} N "
                                                                          f"for the ratings (forces are in N)")
            if c.speed_rpm is not None and not n_lo <= c.speed_rpm <= n_hi:
                raise DesignError(f"spectrum case[{k}].speed_rpm", c.speed_rpm,
                                  f"must be from {n_lo:g} to {n_hi:g} rpm for the ratings")
        Fm, nm = equivalent_load(spectrum)
        low = int(np.argmin(spectrum.loads_n))
        return RatingCase(spectrum.loads_n, tuple(float(w) for w in spectrum.weights),
                          tuple(float(c.speed_rpm) for c in spectrum.cases), Fm, nm, float(fw), float(R), float(H),
                          "spectrum", f"spectrum case[{low}].load_n")
    for flag, value, lo, hi, unit in (("--mean-load", mean_load_n, F_lo, F_hi, "N"),
                                      ("--speed-rpm", speed_rpm, n_lo, n_hi, "rpm")):
        if value is not None and (isinstance(value, bool) or not (isinstance(value, (int, float))
                                                                  and math.isfinite(value) and lo <= value <= hi)):
            raise DesignError(flag, value, f"must be a number from {lo:g} to {hi:g} {unit}")
    F = design.loading.axial_load_n if mean_load_n is None else float(mean_load_n)
    n = rs.speed_rpm if speed_rpm is None else float(speed_rpm)
    src = "mean load from " + ("--mean-load" if mean_load_n is not None else "loading.axial_load_n") + \
        ", speed from " + ("--speed-rpm" if speed_rpm is not None else "rating.speed_rpm")
    return RatingCase((F,), (1.0,), (n,), F, n, float(fw), float(R), float(H), src,
                      "--mean-load" if mean_load_n is not None else "loading.axial_load_n")


def _variants(design: PRSDesign, model: LoadModel, equal_lists: tuple[Sequence[float], Sequence[float]] | None,
              robust_lists: tuple[Sequence[float], Sequence[float]] | None) -> dict[str, tuple[NDArray, NDArray]]:
    """Pitch lists (roller, nut) of the variants compared: constant pitch, the equal-load
    design, the design's own lists (graded designs) and a robust design (when given)."""
    p, n = design.thread.pitch_mm, design.thread.engaged_teeth
    const = (np.full(n - 1, p), np.full(n - 1, p))
    if equal_lists is None:
        pd = design_pitches(design, model=model)
        equal_lists = (pd.roller_mm, pd.nut_mm)
    out = {"constant_pitch": const, "equal_load": tuple(np.asarray(v, dtype=np.float64) for v in equal_lists)}
    if design.graded:
        own = (np.asarray(design.pitch_list("roller")), np.asarray(design.pitch_list("nut")))
        # a design carrying the equal-load lists is that variant: list it once
        if not all(np.allclose(a, b, rtol=0.0, atol=1e-9) for a, b in zip(own, out["equal_load"])):
            out["design"] = own
    if robust_lists is not None:
        out["robust"] = tuple(np.asarray(v, dtype=np.float64) for v in robust_lists)
    return out


@dataclass(frozen=True)
class _Capacity:
    """Load ratings of the contact rings (N), the reliability factor a_1, the operating factor
    f_w and the catalogue L10 life of the equivalent load (revolutions)."""

    rings: ContactRings
    dynamic_n: float
    static_n: float
    reliability_factor: float
    operating_factor: float
    life_revolutions: float


def _capacity(design: PRSDesign, contact: ContactResult, model: LoadModel, case: RatingCase,
              rs: RatingSettings) -> _Capacity:
    """Ratings of the contact rings and the catalogue life of the duty ``case``."""
    rings = contact_rings(design, contact, model)
    Ca = dynamic_load_rating(rings)
    C0a, _ = static_load_rating(rings, rs.static_pressure_limit_mpa)
    a1 = reliability_factor(case.reliability_pct)
    fw = case.operating_factor
    return _Capacity(rings=rings, dynamic_n=Ca, static_n=C0a, reliability_factor=a1, operating_factor=fw,
                     life_revolutions=life_revolutions(Ca, case.equivalent_load_n, a1, fw))


@dataclass(frozen=True)
class _VariantLoads:
    """Tooth loads of every pitch variant (``names``, V of them) at the duty loads
    ``duty_loads_n`` (C) followed by the curve loads ``curve_loads_n`` (N): ``f_nr``,
    ``f_rs`` (V, C + K, n) N, screw-to-nut displacement from first contact
    ``deflection_mm`` (V, C + K) and the gap closed at first contact ``first_contact_mm``
    (V,) mm."""

    names: list[str]
    duty_loads_n: NDArray
    curve_loads_n: NDArray
    f_nr: NDArray
    f_rs: NDArray
    deflection_mm: NDArray
    first_contact_mm: NDArray


def _solve_variants(design: PRSDesign, model: LoadModel, case: RatingCase,
                    variants: dict[str, tuple[NDArray, NDArray]]) -> _VariantLoads:
    """One batched solve: every variant at every duty case and at the loads of the curves."""
    F0 = design.loading.axial_load_n
    names = list(variants)
    cases = np.asarray(case.loads_n, dtype=np.float64)
    curve = np.asarray(CURVE_FRACTIONS) * F0
    loads_one = np.concatenate([cases, curve])
    per = len(loads_one)
    g_nr, g_rs = zip(*(pitch_gaps(design.thread.pitch_mm, r, nt) for r, nt in (variants[k] for k in names)))
    # every variant is solved at the duty loads and at the curve loads: each small enough for
    # the load model (docs: the mean tooth approach and the gaps, analysis.loads.check_load_scale)
    gap_pairs = list(zip(g_nr, g_rs))
    low = int(np.argmin(cases))
    check_load_scale(design, model, float(cases[low]), case.load_field,
                     float(cases[low]) if case.load_field != "loading.axial_load_n" else F0, gaps=gap_pairs)
    check_load_scale(design, model, float(curve.min()), gaps=gap_pairs, min_approach=False)
    G_nr = np.repeat(np.stack(g_nr), per, axis=0)
    G_rs = np.repeat(np.stack(g_rs), per, axis=0)
    b = solve_loads_batch(model, np.tile(loads_one, len(names)), G_nr, G_rs)
    # screw-to-nut displacement from first contact: at zero load the approach of a side can
    # reach min_j g_j (the first tooth to touch; 0 for constant pitch), not 0 (graded gaps)
    first = np.array([gn.min() + gr.min() for gn, gr in zip(g_nr, g_rs)])
    return _VariantLoads(names=names, duty_loads_n=cases, curve_loads_n=curve,
                         f_nr=b.f_nr.reshape(len(names), per, -1), f_rs=b.f_rs.reshape(len(names), per, -1),
                         deflection_mm=b.axial_deflection_mm.reshape(len(names), per) - first[:, None],
                         first_contact_mm=first)


@dataclass(frozen=True)
class VariantLife:
    """The life of one pitch variant from its tooth loads: L10 (revolutions and h at the
    equivalent speed), its ratio to the catalogue life of equal sharing, the Hertz pressure per
    tooth at the largest duty load (MPa; ``pressure_roller_screw_mpa``,
    ``pressure_nut_roller_mpa``, tooth 1 the loaded end) with its maximum, the static safety
    (p_lim / p_max)^3 and the gain over constant pitch (h, and as a factor)."""

    l10_revolutions: float
    l10_hours: float
    life_ratio_to_equal_sharing: float
    max_hertz_pressure_mpa: float
    static_safety: float
    pressure_roller_screw_mpa: NDArray
    pressure_nut_roller_mpa: NDArray
    gain_over_constant_pitch_hours: float
    gain_factor_over_constant_pitch: float


@dataclass(frozen=True)
class _DistributionLife:
    """Per variant its :class:`VariantLife` (``dist``), the system life at the curve loads
    ``life_curve`` (V, K) (revolutions) and the largest duty load ``max_load_n`` (N)."""

    dist: dict[str, VariantLife]
    life_curve: NDArray
    max_load_n: float


def _distribution_life(design: PRSDesign, case: RatingCase, rs: RatingSettings, cap: _Capacity,
                       solved: _VariantLoads) -> _DistributionLife:
    """L10 life from the actual tooth loads of every variant, its Hertz pressures and static
    safety at the largest duty load, and its gain over constant pitch."""
    rings, names, cases = cap.rings, solved.names, solved.duty_loads_n
    f_nr, f_rs = solved.f_nr, solved.f_rs
    F0 = design.loading.axial_load_n
    C = len(cases)
    w = np.asarray(case.weights)
    rev_factor = cap.reliability_factor * 1e6 / cap.operating_factor ** 3          # loads x f_w: life / f_w^3
    life_dist = system_life(rings, f_rs[:, :C], f_nr[:, :C], w) * rev_factor
    life_curve = system_life(rings, f_rs[:, C:], f_nr[:, C:]) * rev_factor      # (V, K)
    n_m = case.equivalent_speed_rpm
    k_max = int(np.argmax(cases))
    low = int(np.argmin(cases))
    hours = [life_hours(float(life_dist[i]), n_m) for i in range(len(names))]
    # static check at the largest load of the duty, as catalogues do (no f_w)
    pressures = [(hertz_pressure(rings, 0, f_rs[i, k_max]), hertz_pressure(rings, 1, f_nr[i, k_max]))
                 for i in range(len(names))]
    p_max = [float(max(p_rs.max(), p_nr.max())) for p_rs, p_nr in pressures]
    safety = [(rs.static_pressure_limit_mpa / p) ** 3 for p in p_max]
    for i, k in enumerate(names):
        for key, value in (("l10_revolutions", float(life_dist[i])), ("l10_hours", hours[i]),
                           ("static_safety", safety[i])):
            _finite(value, case.load_field, float(cases[low]) if case.load_field != "loading.axial_load_n"
                    else F0, f"gives a {key} of {value!r} ({k} pitch lists) out of floating-point range")
    const_h = hours[names.index("constant_pitch")]
    dist = {k: VariantLife(l10_revolutions=float(life_dist[i]), l10_hours=hours[i],
                           life_ratio_to_equal_sharing=float(life_dist[i] / cap.life_revolutions),
                           max_hertz_pressure_mpa=p_max[i], static_safety=safety[i],
                           pressure_roller_screw_mpa=pressures[i][0], pressure_nut_roller_mpa=pressures[i][1],
                           gain_over_constant_pitch_hours=hours[i] - const_h,
                           gain_factor_over_constant_pitch=hours[i] / const_h)
            for i, k in enumerate(names)}
    return _DistributionLife(dist=dist, life_curve=life_curve, max_load_n=float(cases[k_max]))


@dataclass(frozen=True)
class RatingStiffness:
    """Axial stiffness of the design as built (pitch lists ``pitch_lists``): single nut at the
    curve loads ``load_n`` (N) with displacement ``deflection_mm``, secant and tangent
    stiffness (N/um); preloaded double nut (:func:`double_nut` result ``double_nut``) at the
    external loads ``external_n`` with displacement ``displacement_mm``, stiffness
    ``double_nut_stiffness`` (N/um) and the single nut's displacement at those loads
    ``single_displacement_mm``."""

    pitch_lists: str
    load_n: NDArray
    deflection_mm: NDArray
    secant: NDArray
    tangent: NDArray
    preload_n: float
    double_nut: dict[str, Any]
    external_n: NDArray
    displacement_mm: NDArray
    double_nut_stiffness: NDArray
    single_displacement_mm: NDArray


def _stiffness(design: PRSDesign, model: LoadModel, rs: RatingSettings,
               variants: dict[str, tuple[NDArray, NDArray]], solved: _VariantLoads) -> RatingStiffness:
    """Stiffness of the design as built (its own lists: constant pitch unless graded), single
    and with a preloaded double nut."""
    F0 = design.loading.axial_load_n
    names, C = solved.names, len(solved.duty_loads_n)
    own = ("design" if "design" in names else "equal_load") if design.graded else "constant_pitch"
    io = names.index(own)
    Fc, dc = solved.curve_loads_n, solved.deflection_mm[io, C:]
    preload = rs.preload_n if rs.preload_n is not None else F0 / 2.0 ** 1.5
    grid_top = max(1.6 * F0, 3.2 * preload)
    Fg = grid_top * np.linspace(0.0, 1.0, 41) ** 1.5          # uniform in F^(2/3): dense at low load
    Fg_solve = Fg[1:]
    rr, nn = variants[own]
    gn, gr = pitch_gaps(design.thread.pitch_mm, rr, nn)
    preload_field = "rating.preload_n" if rs.preload_n is not None else "loading.axial_load_n"
    check_load_scale(design, model, float(Fg_solve[0]), preload_field,
                     rs.preload_n if rs.preload_n is not None else F0, gaps=[(gn, gr)], min_approach=False)
    bg = solve_loads_batch(model, Fg_solve, np.tile(gn, (len(Fg_solve), 1)), np.tile(gr, (len(Fg_solve), 1)))
    dg = np.concatenate([[0.0], bg.axial_deflection_mm - solved.first_contact_mm[io]])
    ext = np.linspace(0.0, 1.5 * F0, 61)
    dn = double_nut(Fg, dg, preload, ext)
    x = dn["displacement_mm"]
    return RatingStiffness(pitch_lists=own, load_n=Fc, deflection_mm=dc, secant=Fc / dc / 1e3,
                      tangent=np.gradient(Fc, dc) / 1e3, preload_n=preload, double_nut=dn, external_n=ext,
                      displacement_mm=x, double_nut_stiffness=np.gradient(ext, x) / 1e3,
                      single_displacement_mm=PchipInterpolator(np.cbrt(Fg) ** 2, dg)(np.cbrt(ext) ** 2))


@dataclass(frozen=True)
class ResolvedSupports:
    """The free lengths (mm) and end fixities the critical speed and buckling use, where
    they came from (``source``: "geometry", "design file" or "geometry, overridden by the
    design file"; ``rule``: how the geometry gave them) and one warning per ``[supports]``
    value that overrides a different value of the geometry. ``length_field`` names the
    design field an out-of-range rating blames."""

    critical_speed_length_mm: float
    critical_speed_ends: str
    buckling_length_mm: float
    buckling_ends: str
    source: str
    rule: str
    warnings: tuple[str, ...]
    length_field: str


def resolve_supports(design: PRSDesign) -> ResolvedSupports:
    """The screw's supports for the ratings: from the actuator geometry
    (:func:`prs_geom.geometry.actuator.support_spans`) with the ``[supports]`` values given
    in the design file overriding it (each with a warning when it differs), or, without an
    actuator, the ``[supports]`` values with ``screw.length_mm`` and "fixed-supported" for
    what is absent."""
    from prs_geom.geometry.actuator import actuator_layout

    sup = design.supports or Supports()
    lay = actuator_layout(design)
    if lay is None:
        length = sup.unsupported_length_mm if sup.unsupported_length_mm is not None else design.screw.length_mm
        fld = "supports.unsupported_length_mm" if sup.unsupported_length_mm is not None else "screw.length_mm"
        return ResolvedSupports(length, sup.critical_speed_ends or "fixed-supported", length,
                                sup.buckling_ends or "fixed-supported", "design file",
                                "supports.unsupported_length_mm, else the screw's threaded length", (), fld)
    geo = lay.supports
    given = {"critical_speed_length_mm": sup.unsupported_length_mm, "buckling_length_mm": sup.unsupported_length_mm,
             "critical_speed_ends": sup.critical_speed_ends, "buckling_ends": sup.buckling_ends}
    fields = {"critical_speed_length_mm": "supports.unsupported_length_mm",
              "buckling_length_mm": "supports.unsupported_length_mm",
              "critical_speed_ends": "supports.critical_speed_ends", "buckling_ends": "supports.buckling_ends"}
    words = {"critical_speed_length_mm": "the critical speed's span", "buckling_length_mm": "the buckling span",
             "critical_speed_ends": "the critical speed's end fixity", "buckling_ends": "the buckling end fixity"}
    values, warns = {}, []
    for key, value in given.items():
        geometric = getattr(geo, key)
        values[key] = geometric if value is None else value
        if value is not None and value != geometric:
            shown = f"{value:g} mm" if isinstance(value, float) else f'"{value}"'
            geo_shown = f"{geometric:.6g} mm" if isinstance(geometric, float) else f'"{geometric}"'
            warns.append(f"{fields[key]} = {shown} overrides {words[key]} from the actuator geometry ({geo_shown}: "
                         f"{geo.rule}); remove it from [supports] to rate the actuator as laid out")
    overridden = any(v is not None for v in given.values())
    return ResolvedSupports(values["critical_speed_length_mm"], values["critical_speed_ends"],
                            values["buckling_length_mm"], values["buckling_ends"],
                            "geometry, overridden by the design file" if overridden else "geometry", geo.rule,
                            tuple(warns), "supports.unsupported_length_mm" if sup.unsupported_length_mm is not None
                            else "actuator.stroke_mm")


@dataclass(frozen=True)
class RatingLimits:
    """Speed and buckling limits and the drive: free screw length and root diameter (mm),
    critical speed (first whirling speed), its permissible fraction, d n speed limit and the
    permissible speed (the smaller of both) at the largest duty speed ``max_speed_rpm`` (rpm);
    Euler buckling load and the permissible load (N), the d n limit (mm/min), lead (mm),
    :func:`efficiency` result, drive and back-drive torque at the largest load (N m)."""

    supports: "ResolvedSupports"
    root_diameter_mm: float
    critical_speed_rpm: float
    permissible_critical_speed_rpm: float
    buckling_load_n: float
    permissible_buckling_load_n: float
    dn_limit_mm_rpm: float
    dn_speed_limit_rpm: float
    permissible_speed_rpm: float
    max_speed_rpm: float
    lead_mm: float
    efficiency: dict[str, float]
    drive_torque_nm: float
    back_drive_torque_nm: float

    @property
    def free_length_mm(self) -> float:
        """The free length of the critical speed (mm)."""
        return self.supports.critical_speed_length_mm

    @property
    def speed_ok(self) -> bool:
        """The largest duty speed is within the permissible speed."""
        return bool(self.max_speed_rpm <= self.permissible_speed_rpm)


def _limits(design: PRSDesign, rs: RatingSettings, sup: Supports, max_load_n: float,
            max_speed_rpm: float) -> RatingLimits:
    """Critical speed, buckling, speed limits, efficiency and torques."""
    E_s = design.materials.screw.youngs_modulus_mpa
    d_root = design.screw.minor_diameter_mm
    res = resolve_supports(design)
    n_cr = _finite(lambda: critical_speed(d_root, res.critical_speed_length_mm, res.critical_speed_ends, E_s),
                   res.length_field, res.critical_speed_length_mm, "gives a critical speed out of floating-point range")
    F_buck = _finite(lambda: buckling_load(d_root, res.buckling_length_mm, res.buckling_ends, E_s),
                     res.length_field, res.buckling_length_mm, "gives a buckling load out of floating-point range")
    n_dn = rs.dn_limit_mm_rpm / design.screw.pitch_diameter_mm
    n_perm = min(sup.critical_speed_factor * n_cr, n_dn)
    lead = design.screw.starts * design.thread.pitch_mm
    eff = efficiency(lead, design.screw.pitch_diameter_mm, rs.friction_coefficient, design.thread.beta)
    T_back = max_load_n * lead * eff["back_driving"] / (2.0 * math.pi) / 1e3
    return RatingLimits(supports=res, root_diameter_mm=d_root, critical_speed_rpm=n_cr,
                        permissible_critical_speed_rpm=sup.critical_speed_factor * n_cr, buckling_load_n=F_buck,
                        permissible_buckling_load_n=F_buck / sup.buckling_safety, dn_limit_mm_rpm=rs.dn_limit_mm_rpm,
                        dn_speed_limit_rpm=n_dn, permissible_speed_rpm=n_perm, max_speed_rpm=max_speed_rpm,
                        lead_mm=lead, efficiency=eff, drive_torque_nm=drive_torque(max_load_n, lead, eff["forward"]),
                        back_drive_torque_nm=T_back)


@dataclass(frozen=True)
class RatingCurves:
    """What the rating plot draws besides the stiffness: the variants ``names``, the curve
    loads ``curve_loads_n`` (``fractions`` of the design load, N) with the L10 life of each
    variant ``life_hours`` (h) and the catalogue life (C_a / F)^3 ``catalogue_life_hours``
    (h), and the Hertz pressure per tooth ``pressure`` (variant -> (roller-screw, nut-roller),
    MPa) at the largest duty load ``pressure_load_n`` (N) against ``pressure_limit_mpa``."""

    names: tuple[str, ...]
    fractions: tuple[float, ...]
    curve_loads_n: NDArray
    life_hours: dict[str, NDArray]
    catalogue_life_hours: NDArray
    pressure: dict[str, tuple[NDArray, NDArray]]
    pressure_load_n: float
    pressure_limit_mpa: float


@dataclass(frozen=True)
class RatingResult:
    """The ratings of a design under the duty ``case`` with the design's rating ``settings``
    and ``supports``: basic dynamic and static axial load ratings of the contact ``rings``
    (N), the reliability factor a_1, the catalogue L10 life (revolutions, h at the equivalent
    speed) and the C_a it would need for the target life (N), the static safety C_0a / F_max
    at the largest duty load ``max_load_n`` (N), the calibration constant K of the capacity
    and the spread of the closed form around it; the life of each pitch variant from its tooth
    loads (``distribution_life``; ``robust_computed`` when a robust design is among them, else
    ``robust_note`` may say why not), the speed and buckling limits and the drive
    (``limits``), the five limit ``checks`` (:data:`LIMIT_CHECKS` order), the stiffness of the
    design as built and the plot ``curves``. :func:`prs_geom.exports.report.rating_section`
    serialises it."""

    case: RatingCase
    settings: RatingSettings
    supports: Supports
    rings: ContactRings
    dynamic_load_rating_n: float
    static_load_rating_n: float
    reliability_factor: float
    l10_revolutions: float
    l10_hours: float
    required_dynamic_load_n: float
    max_load_n: float
    static_safety: float
    calibration_constant: float
    calibration_spread: tuple[float, float]
    distribution_life: dict[str, VariantLife]
    robust_computed: bool
    robust_note: str | None
    limits: RatingLimits
    checks: tuple[LimitCheck, ...]
    stiffness: RatingStiffness
    curves: RatingCurves = field(compare=False)

    @property
    def all_passed(self) -> bool:
        """Every limit check passed."""
        return all(c.passed for c in self.checks)


def analyse_rating(design: PRSDesign, contact: ContactResult | None = None, model: LoadModel | None = None,
                   case: RatingCase | None = None, *, equal_lists: tuple[Sequence[float], Sequence[float]] | None = None,
                   robust_lists: tuple[Sequence[float], Sequence[float]] | None = None,
                   robust_note: str | None = None) -> RatingResult:
    """Ratings, life (catalogue and from the tooth loads), limits, efficiency and stiffness.


    ``contact``/``model``: the contact and load stages' results (computed when not given);
    ``case``: the duty (default :func:`rating_case` of the design); ``equal_lists``: the
    equal-load pitch lists (roller, nut) if known; ``robust_lists``: pitch lists of a robust
    design to compare (the pipeline layer makes them with :func:`prs_geom.studies.robust_pitch`),
    ``robust_note`` says why there are none. All tooth loads come from one batched solve.

    Examples
    --------
    >>> import prs_geom as pg
    >>> rating = pg.analyse_rating(pg.default_design())
    >>> round(rating.dynamic_load_rating_n), round(rating.l10_hours)
    (56766, 3811)
    >>> [(c.name, c.passed) for c in rating.checks][-1]
    ('static_safety', True)
    """
    contact = contact if contact is not None else analyse_contact(design)
    model = model if model is not None else build_model(design, contact)
    case = case if case is not None else rating_case(design)
    rs = design.rating or RatingSettings()
    sup = design.supports or Supports()
    cap = _capacity(design, contact, model, case, rs)
    variants = _variants(design, model, equal_lists, robust_lists)
    solved = _solve_variants(design, model, case, variants)
    life = _distribution_life(design, case, rs, cap, solved)
    stiff = _stiffness(design, model, rs, variants, solved)
    limits = _limits(design, rs, sup, life.max_load_n, max(case.speeds_rpm))
    return _rating_result(design, case, rs, sup, cap, solved, life, stiff, limits, robust_note)


def _rating_result(design: PRSDesign, case: RatingCase, rs: RatingSettings, sup: Supports, cap: _Capacity,
                   solved: _VariantLoads, life: _DistributionLife, stiff: RatingStiffness, limits: RatingLimits,
                   robust_note: str | None) -> RatingResult:
    """The result and the plot curves from the computed steps."""
    names, curve, n_m, Fmax = solved.names, solved.curve_loads_n, case.equivalent_speed_rpm, life.max_load_n
    static_safety = cap.static_n / Fmax
    curves = RatingCurves(
        names=tuple(names), fractions=tuple(CURVE_FRACTIONS), curve_loads_n=curve,
        life_hours={k: life.life_curve[i] / (60.0 * n_m) for i, k in enumerate(names)},
        catalogue_life_hours=life_revolutions(cap.dynamic_n, 1.0, cap.reliability_factor, cap.operating_factor)
        / curve ** 3 / (60.0 * n_m),
        pressure={k: (v.pressure_roller_screw_mpa, v.pressure_nut_roller_mpa) for k, v in life.dist.items()},
        pressure_load_n=Fmax, pressure_limit_mpa=rs.static_pressure_limit_mpa)
    return RatingResult(
        case=case, settings=rs, supports=sup, rings=cap.rings, dynamic_load_rating_n=cap.dynamic_n,
        static_load_rating_n=cap.static_n, reliability_factor=cap.reliability_factor,
        l10_revolutions=cap.life_revolutions, l10_hours=life_hours(cap.life_revolutions, n_m),
        required_dynamic_load_n=required_dynamic_load(case.equivalent_load_n, n_m, case.life_hours,
                                                      cap.reliability_factor, cap.operating_factor),
        max_load_n=Fmax, static_safety=static_safety, calibration_constant=calibration_constant(),
        calibration_spread=tuple(calibration_spread()), distribution_life=life.dist,
        robust_computed="robust" in names, robust_note=robust_note, limits=limits,
        checks=limit_checks(limits, Fmax, static_safety, rs.required_static_safety, design.screw.pitch_diameter_mm),
        stiffness=stiff, curves=curves)
