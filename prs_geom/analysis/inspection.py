"""Over-wire and over-ball inspection values of screw, roller and nut
(docs/theory/inspection.md).

Pure math, no I/O. Every length in mm (float64), differences reported in um, angles in
rad inside and deg in results.

Frame and conventions
---------------------
Part frame: z along the part axis. The thread surfaces are those of
:mod:`prs_geom.geometry.profiles` (normal-section convention): in the axial section a
tooth of part i has the half-width t(r) = w(r) / cos(lambda_L), lambda_L the lead angle at
the profile's lead radius, and its flanks sweep helically,

    z = z_mid +- t(r) + h L theta / 2 pi,        h = +1 right hand, -1 left hand.

The *groove* between two teeth has the axial half-width g(r) = p/2 - t(r); its flanks,
seen from the groove mid-plane, are

    S+ : z = +g(r) + k theta,        S- : z = -g(r) + k theta,        k = h L / 2 pi.

g grows outward on an external thread (screw, roller: slope s = dg/dr > 0) and shrinks
outward on the internal nut thread (s < 0). At the pitch radius r_p, g(r_p) = p/4 on every
part (the tooth and the groove are equally wide there, by definition of the pitch radius).

The gauge (a wire, i.e. a cylinder, or a ball, i.e. a sphere, of radius rho) sits in the
groove with its centre C = (R, 0, z_mid) on the x axis. The rotation by pi about the x axis
maps S+ onto S- and the gauge onto itself, so a gauge that touches S+ touches S- at the
mirror point: one flank suffices for the closed form, and the numerical check places the
gauge on both flanks independently.

Best ball and best wire ("semi-closed form")
--------------------------------------------
The best gauge touches both flanks on the pitch cylinder r = r_p. For a ball the contact
conditions (the squared distance D(r, theta) from C to S+ stationary and equal to rho^2)
give, with e = p/4 + k theta the axial distance of the contact from the centre's plane,

    R cos(theta) = r_p + e s,   R sin(theta) = -k e / r_p,   rho = e sqrt(1 + s^2 + k^2/r_p^2),

explicit once theta is known; theta is the root of r_p (r_p + e s) sin(theta) +
k e cos(theta) = 0 (R eliminated), found by Brent's method. For k -> 0 this reduces to the
classical theta = 0, rho = (p/4) / cos(alpha), R = r_p + (p/4) s, tan(alpha) = |s|.

A wire (cylinder) pressed by a flat anvil lies parallel to the anvil: its axis passes
through C along (0, cos gamma, sin gamma), gamma free. A frictionless wire settles where it
sits deepest; by the envelope theorem dR/dgamma vanishes when the contact lies in the
plane through C normal to the wire, where the wire's contact conditions are the ball's.
The wire contains the ball of its radius at C, so it cannot sit deeper than that ball: the
settled wire sits exactly where the ball sits, inclined by tan(gamma) = -r_p sin(theta) / e.
Best wire and best ball are the same size and read the same M. (A wire held along the
groove's helix tangent at the pitch cylinder, tan(gamma) = k / r_p, sits higher; the result
reports by how much.)

Measurement M
-------------
* External threads (screw, roller), wires: the three-wire arrangement: two wires in
  adjacent grooves on one side (axially p apart at the same angle; on a multi-start screw
  the neighbouring grooves belong to different starts and are congruent), one wire in the
  groove on the opposite side (axially offset by L/2 mod p: p/2 for an odd start count,
  0 for an even one), read between two flat parallel anvils: M = 2 (R + rho). For an even
  start count two wires diametrically opposite at the same height read the same M.
* Internal thread (nut), balls: a two-point diametral measurement with ball styli in two
  grooves on opposite sides (axially offset by L/2 mod p), read over the balls' outer
  extremes, as an instrument set on a plain setting ring reads it: M = 2 (R + rho). The
  distance between the balls' inner extremes is M - 2 d_ball.

Classical reference (no lead correction), half-angle alpha of the axial section at the pitch
line, tan(alpha) = |s|, sigma = +1 external, -1 internal:

    R_c = r_p + sigma (rho / sin(alpha) - (p/4) cot(alpha)),   M_c = 2 (R_c + rho),

which for an external thread is the textbook three-wire formula
M = d2 + w (1 + 1/sin(alpha)) - (p/2) cot(alpha).

Temperature
-----------
All values refer to 20 degC (ISO 1). A part of expansion coefficient alpha_T measured with
gauges of the same material at the same temperature reads M (1 + alpha_T dT): dM/dT =
alpha_T M. With the gauges held at 20 degC only the part grows: by Euler's theorem for the
homogeneous function M(part, w), dM/dT = alpha_T (M - w dM/dw), dM/dw from the numerical
placement. The engaged thread length n p grows by alpha_T n p per kelvin.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy import optimize

from prs_geom.analysis.contact import ContactResult, analyse_contact
from prs_geom.geometry.profiles import ThreadProfile, ThreadProfiles
from prs_geom.model.design import PRSDesign

TWO_PI = 2.0 * math.pi
GAUGES = ("wire", "ball")
PARTS = ("screw", "roller", "nut")
#: Gauge used for each part: wires on the external threads, balls in the nut bore.
DEFAULT_GAUGE = {"screw": "wire", "roller": "wire", "nut": "ball"}
#: Acceptance bar of the numerical check (um).
CHECK_TOLERANCE_UM = 0.1
#: Relative step of the wire size for dM/dw (central difference on the numerical placement).
_DW_REL = 1e-3


# --------------------------------------------------------------------------- groove data
@dataclass(frozen=True)
class GrooveAtPitchLine:
    """What the best-gauge closed form needs of one thread groove, at the pitch cylinder.

    Parameters
    ----------
    pitch_mm : float
        Axial pitch p (mm).
    lead_mm : float
        Lead L = n p (mm), unsigned.
    hand_sign : int
        +1 right hand, -1 left hand.
    pitch_radius_mm : float
        Radius r_p (mm) where the groove's axial half-width is p/4.
    flank_slope : float
        s = dg/dr at r_p: slope of the groove's axial half-width (dimensionless);
        positive on an external thread, negative on an internal one.
    """

    pitch_mm: float
    lead_mm: float
    hand_sign: int
    pitch_radius_mm: float
    flank_slope: float

    def __post_init__(self) -> None:
        for name in ("pitch_mm", "lead_mm", "pitch_radius_mm"):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and v > 0.0):
                raise ValueError(f"{name} must be a positive finite length (mm), got {v!r}")
            object.__setattr__(self, name, v)
        if self.hand_sign not in (1, -1):
            raise ValueError(f"hand_sign must be +1 or -1, got {self.hand_sign!r}")
        s = float(self.flank_slope)
        if not (math.isfinite(s) and s != 0.0):
            raise ValueError(f"flank_slope must be finite and non-zero, got {s!r}")
        object.__setattr__(self, "flank_slope", s)

    @property
    def internal(self) -> bool:
        """True when the groove narrows outward (nut)."""
        return self.flank_slope < 0.0

    @property
    def helix_k(self) -> float:
        """Signed axial advance per radian k = h L / 2 pi (mm/rad)."""
        return self.hand_sign * self.lead_mm / TWO_PI

    @property
    def lead_angle(self) -> float:
        """Lead angle at the pitch radius, atan(L / 2 pi r_p) (rad), unsigned."""
        return math.atan(self.lead_mm / (TWO_PI * self.pitch_radius_mm))

    @property
    def pitch_helix_angle(self) -> float:
        """Signed helix angle of the groove at the pitch cylinder, atan(k / r_p) (rad): the
        inclination of a wire laid along the helix tangent there (for comparison only; the
        settled wire lies flatter)."""
        return math.atan2(self.helix_k, self.pitch_radius_mm)

    @property
    def axial_half_angle(self) -> float:
        """Flank half-angle alpha of the axial section at the pitch line (rad)."""
        return math.atan(abs(self.flank_slope))


def groove_at_pitch_line(profile: ThreadProfile) -> GrooveAtPitchLine:
    """The groove data of ``profile`` at its pitch radius, from the flank object's slope.

    The axial groove half-width is g = p/2 - t, so s = -dt/dr; the profile's lead angle is
    the one at its lead radius (the theoretical screw keeps the nominal one), the helix
    itself advances by L per turn at every radius.
    """
    r_p = profile.pitch_radius
    slope = -float(profile.tooth_half_width_slope(r_p))
    return GrooveAtPitchLine(profile.pitch, profile.lead, profile.hand_sign, r_p, slope)


# --------------------------------------------------------------------------- closed form
@dataclass(frozen=True)
class GaugeSeat:
    """Where a gauge of radius ``radius_mm`` sits: its centre (point or axis crossing) at
    ``centre_radius_mm`` from the part axis; it touches S+ at polar angle
    ``contact_angle_rad`` (from the centre's meridian, right-hand sense about +z) and
    radius ``contact_radius_mm``; a wire's axis is inclined by ``inclination_rad`` from the
    plane z = const (direction (0, cos gamma, sin gamma), positive for a right hand)."""

    radius_mm: float
    centre_radius_mm: float
    contact_angle_rad: float
    contact_radius_mm: float
    inclination_rad: float = 0.0

    def __post_init__(self) -> None:
        for name in ("radius_mm", "centre_radius_mm", "contact_angle_rad", "contact_radius_mm", "inclination_rad"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"{name} must be finite, got {getattr(self, name)!r}")
        if self.radius_mm <= 0.0 or self.centre_radius_mm <= 0.0 or self.contact_radius_mm <= 0.0:
            raise ValueError("gauge, centre and contact radii must be positive (mm)")
        if abs(self.inclination_rad) >= 0.5 * math.pi:
            raise ValueError(f"inclination_rad must lie within +-pi/2, got {self.inclination_rad!r}")


def _wire_direction(gamma: float) -> tuple[float, float]:
    return math.cos(gamma), math.sin(gamma)


def best_gauge(groove: GrooveAtPitchLine, gauge: str) -> GaugeSeat:
    """Best wire or ball of ``groove``: touches both flanks on the pitch cylinder, with the
    lead-angle correction (semi-closed form, module docstring).

    The settled wire and the ball of the same radius touch the flanks at the same points
    (module docstring), so both gauges share the seat; the wire adds its inclination
    tan(gamma) = -r_p sin(theta) / e.

    Parameters
    ----------
    groove : GrooveAtPitchLine
    gauge : {"wire", "ball"}

    Returns
    -------
    GaugeSeat
        Gauge radius rho (mm), centre radius R (mm), contact angle theta (rad) on S+,
        contact radius (= r_p), wire inclination gamma (rad; 0 for a ball).
    """
    if gauge not in GAUGES:
        raise ValueError(f"gauge must be one of {GAUGES}, got {gauge!r}")
    r, s, k = groove.pitch_radius_mm, groove.flank_slope, groove.helix_k
    g0 = 0.25 * groove.pitch_mm

    def theta_equation(th: float) -> float:
        # tan(theta) = -k e / (r (r + e s)) written without the tangent's poles:
        # R sin(theta) = -k e / r and R cos(theta) = r + e s, eliminated R
        e = g0 + k * th
        return math.sin(th) * r * (r + e * s) + math.cos(th) * k * e

    if k == 0.0:
        th = 0.0
    else:
        # the contact slides against the helix: theta has the sign of -k and the contact
        # stays on the near side of the centre's axial plane (e > 0), |theta| < g0 / |k|
        lim = -math.copysign(min(0.9 * g0 / abs(k), 0.25 * math.pi), k)
        lo, hi = sorted((0.0, lim))
        th = optimize.brentq(theta_equation, lo, hi, xtol=1e-16, rtol=4.0 * np.finfo(float).eps,
                             maxiter=200)
    e = g0 + k * th
    R = math.hypot(r + e * s, k * e / r)
    rho = e * math.sqrt(1.0 + s * s + (k / r) ** 2)
    gamma = math.atan2(-r * math.sin(th), e) if gauge == "wire" else 0.0
    return GaugeSeat(rho, R, th, r, gamma)


def classical_seat(groove: GrooveAtPitchLine, radius_mm: float) -> float:
    """Centre radius R_c (mm) of a gauge of radius ``radius_mm`` by the classical
    axial-section formula (no lead correction): R_c = r_p + sigma (rho/sin(alpha) -
    (p/4) cot(alpha)), sigma = +1 external, -1 internal."""
    al = groove.axial_half_angle
    sigma = -1.0 if groove.internal else 1.0
    return groove.pitch_radius_mm + sigma * (radius_mm / math.sin(al) - 0.25 * groove.pitch_mm / math.tan(al))


def classical_best_radius(groove: GrooveAtPitchLine) -> float:
    """Classical best gauge radius (p/4) / cos(alpha) (mm), axial section, no lead correction."""
    return 0.25 * groove.pitch_mm / math.cos(groove.axial_half_angle)


# --------------------------------------------------------------------------- numerical check
@dataclass(frozen=True)
class HelicalFlanks:
    """The two flanks of one groove as analytic helicoids, built from a profile's tooth
    half-width t(r) (independent of :class:`GrooveAtPitchLine`): groove mid-plane at z = 0
    for theta = 0; S+ z = +(p/2 - t(r)) + k theta, S- z = -(p/2 - t(r)) + k theta."""

    half_width: Callable[[float], float]
    pitch_mm: float
    helix_k: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.pitch_mm) and self.pitch_mm > 0.0 and math.isfinite(self.helix_k)):
            raise ValueError(f"pitch_mm must be positive and helix_k finite, got {self.pitch_mm!r}, "
                             f"{self.helix_k!r}")

    def z(self, side: int, r: float, theta: float) -> float:
        """Axial position (mm) of flank ``side`` (+1: S+, -1: S-) at (r, theta)."""
        return side * (0.5 * self.pitch_mm - self.half_width(r)) + self.helix_k * theta


def helical_flanks(profile: ThreadProfile) -> HelicalFlanks:
    """The groove flanks of ``profile`` (its t(r), pitch, lead and hand)."""
    def t(r: float) -> float:
        return float(profile.tooth_half_width(r))
    return HelicalFlanks(t, profile.pitch, profile.hand_sign * profile.lead / TWO_PI)


def _min_sq_distance(flanks: HelicalFlanks, side: int, centre_radius: float, direction: tuple[float, float] | None,
                     start: tuple[float, float]) -> tuple[float, float, float]:
    """Smallest squared distance (mm^2) from the gauge centre (point, or the axis line
    through (R, 0, 0) along (0, cos g, sin g)) to flank ``side``, minimised over
    (r, r0 theta) (scaled so both variables are lengths); returns (D, r, theta)."""
    r0 = start[0]

    def sq(v: np.ndarray) -> float:
        r, th = float(v[0]), float(v[1]) / r0
        dx, dy, dz = r * math.cos(th) - centre_radius, r * math.sin(th), flanks.z(side, r, th)
        d2 = dx * dx + dy * dy + dz * dz
        if direction is not None:
            along = dy * direction[0] + dz * direction[1]
            d2 -= along * along
        return d2

    # Newton on the central-difference gradient and Hessian of the squared distance (only
    # values of the surface are used, no derivative of the profile): the step h = 1e-4 mm
    # leaves an O(h^2) bias of the stationary point far below 1 nm, and the minimum value
    # depends on the point only to second order
    h = 1e-4
    x = np.array([start[0], start[1] * r0], dtype=np.float64)
    e1, e2 = np.array([h, 0.0]), np.array([0.0, h])
    for _ in range(50):
        f0 = sq(x)
        fp1, fm1, fp2, fm2 = sq(x + e1), sq(x - e1), sq(x + e2), sq(x - e2)
        f12 = sq(x + e1 + e2) - sq(x + e1 - e2) - sq(x - e1 + e2) + sq(x - e1 - e2)
        grad = np.array([fp1 - fm1, fp2 - fm2]) / (2.0 * h)
        hess = np.array([[fp1 - 2.0 * f0 + fm1, 0.25 * f12], [0.25 * f12, fp2 - 2.0 * f0 + fm2]]) / (h * h)
        step = np.linalg.solve(hess, -grad)
        # keep the iteration local: the minimum sits within a gauge radius of the start
        norm = float(np.hypot(*step))
        if norm > 0.2:
            step *= 0.2 / norm
        x = x + step
        # 1e-9 mm: the difference noise of the gradient (eps D / h) sets a floor near 1e-12
        if norm < 1e-9:
            break
    else:
        raise ArithmeticError("minimum distance to the flank did not converge")
    # Newton finds any stationary point: insist on a minimum (positive definite Hessian)
    if not (hess[0, 0] > 0.0 and np.linalg.det(hess) > 0.0):
        raise ArithmeticError("the stationary distance to the flank is not a minimum")
    return float(sq(x)), float(x[0]), float(x[1]) / r0


@dataclass(frozen=True)
class NumericalSeat:
    """A gauge placed numerically: centre radius and contact radius on each flank."""

    centre_radius_mm: tuple[float, float]
    contact_radius_mm: tuple[float, float]


def place_gauge(flanks: HelicalFlanks, radius_mm: float, gauge: str, inclination: float,
                centre_guess_mm: float, contact_guess_mm: float, sides: tuple[int, ...] = (1, -1)) -> NumericalSeat:
    """Seat a wire or ball of radius ``radius_mm`` on each flank separately: the centre
    radius R where the smallest distance from the gauge centre (point or axis) to the
    analytic helicoid equals the gauge radius (secant root on R of a numerically minimised distance).

    Parameters
    ----------
    flanks : HelicalFlanks
    radius_mm : float
        Gauge radius rho (mm).
    gauge : {"wire", "ball"}
    inclination : float
        Wire axis inclination gamma (rad, signed), ignored for a ball.
    centre_guess_mm, contact_guess_mm : float
        Start values (mm): the classical centre radius and the pitch radius do.
    sides : tuple of {+1, -1}
        Flanks to seat on (S+, S-).

    Returns
    -------
    NumericalSeat
        Centre and contact radius (mm) per flank in ``sides`` order.
    """
    direction = _wire_direction(inclination) if gauge == "wire" else None
    centres, contacts = [], []
    for side in sides:
        def excess(R: float) -> float:
            return math.sqrt(_min_sq_distance(flanks, side, R, direction, (contact_guess_mm, 0.0))[0]) - radius_mm

        # the excess is close to linear in R (slope about sin(alpha)): the secant method
        # converges in a few steps from the classical guess; the residual is checked below
        R = float(optimize.newton(excess, centre_guess_mm, x1=centre_guess_mm + 1e-3 * radius_mm,
                                  tol=1e-13, rtol=0.0, maxiter=60))
        if not abs(excess(R)) <= 1e-11:
            raise ArithmeticError(f"numerical gauge placement did not converge (excess {excess(R):.3g} mm)")
        centres.append(R)
        contacts.append(_min_sq_distance(flanks, side, R, direction, (contact_guess_mm, 0.0))[1])
    return NumericalSeat(tuple(centres), tuple(contacts))


# --------------------------------------------------------------------------- result
@dataclass(frozen=True)
class PartInspection:
    """Inspection values of one part at 20 degC.

    Attributes
    ----------
    part : str
        "screw", "roller" or "nut".
    gauge : str
        "wire" (three-wire method) or "ball" (two-point over balls).
    pitch_diameter_mm : float
        The pitch diameter the part is made to (mm; the screw's theoretical one).
    lead_angle_deg : float
        Lead angle at the pitch diameter (deg).
    gauge_diameter_mm : float
        Best wire or ball diameter (mm), lead-angle corrected.
    gauge_centre_diameter_mm : float
        Twice the distance of the gauge centre (ball centre or wire axis) from the part
        axis (mm).
    measurement_mm : float
        M = gauge centre diameter + gauge diameter (mm), arrangement in ``method``.
    classical_gauge_diameter_mm, classical_measurement_mm : float
        Axial-section values without lead correction (mm); the classical M is for the
        corrected best gauge.
    gauge_correction_um, measurement_correction_um : float
        Lead-angle corrections (um): corrected minus classical.
    numerical_check_um : float
        Largest |M_numerical - M| over both flanks (um).
    contact_radius_check_um : float
        Largest distance of the numerically found contacts from the pitch cylinder (um).
    wire_inclination_deg : float
        Inclination of the settled wire's axis from the plane z = const (deg, positive for a
        right hand); 0 for a ball.
    pitch_helix_wire_excess_um : float
        How much more the same wire reads when its axis is held along the groove's helix
        tangent at the pitch cylinder instead of settled (um, >= 0); 0 for a ball.
    temperature_coefficient_um_per_k : float
        dM/dT with part and gauges at the same temperature, gauges of the part's material.
    temperature_coefficient_part_only_um_per_k : float
        dM/dT with the gauges held at 20 degC.
    engaged_length_growth_um_per_k : float
        Thermal growth of the engaged thread length n p (um/K).
    method : str
    """

    part: str
    gauge: str
    pitch_diameter_mm: float
    lead_angle_deg: float
    gauge_diameter_mm: float
    gauge_centre_diameter_mm: float
    measurement_mm: float
    classical_gauge_diameter_mm: float
    classical_measurement_mm: float
    gauge_correction_um: float
    measurement_correction_um: float
    numerical_check_um: float
    contact_radius_check_um: float
    wire_inclination_deg: float
    pitch_helix_wire_excess_um: float
    temperature_coefficient_um_per_k: float
    temperature_coefficient_part_only_um_per_k: float
    engaged_length_growth_um_per_k: float
    method: str

    def __post_init__(self) -> None:
        if self.part not in PARTS:
            raise ValueError(f"part must be one of {PARTS}, got {self.part!r}")
        if self.gauge not in GAUGES:
            raise ValueError(f"gauge must be one of {GAUGES}, got {self.gauge!r}")
        for name, value in self.__dict__.items():
            if isinstance(value, float) and not math.isfinite(value):
                raise ValueError(f"{name} must be finite, got {value!r}")
        for name in ("pitch_diameter_mm", "gauge_diameter_mm", "gauge_centre_diameter_mm", "measurement_mm"):
            if getattr(self, name) <= 0.0:
                raise ValueError(f"{name} must be positive, got {getattr(self, name)!r}")
        if abs(self.measurement_mm - self.gauge_centre_diameter_mm - self.gauge_diameter_mm) > 1e-9:
            raise ValueError("measurement_mm must equal gauge_centre_diameter_mm + gauge_diameter_mm")

    @property
    def check_passed(self) -> bool:
        """True when the numerical placement agrees with the closed form within 0.1 um."""
        return self.numerical_check_um <= CHECK_TOLERANCE_UM and self.contact_radius_check_um <= 1.0

def _method_text(part: str, gauge: str, starts: int) -> str:
    if gauge == "wire":
        opposite = ("axially offset p/2 (odd start count)" if starts % 2 else
                    "at the same height (even start count; two diametrically opposite wires read the same M)")
        return (f"three-wire: two wires in adjacent grooves on one side (p apart), one in the opposite "
                f"groove {opposite}; flat parallel anvils; M = over the wires = 2 (R + rho); each wire "
                f"settled (deepest seat, axis inclined by wire_inclination_deg, where a ball of its "
                f"size would sit); lead-angle corrected best wire touches both flanks on the pitch "
                f"cylinder")
    opposite = "axially offset p/2 (odd start count)" if starts % 2 else "at the same height (even start count)"
    inner = "outer extremes (inner distance between balls = M - 2 d)" if part == "nut" else "outer extremes"
    return (f"two balls in grooves on opposite sides, {opposite}; two-point diametral reading over the "
            f"balls' {inner}; lead-angle corrected best ball touches both flanks on the pitch cylinder")


def inspect_part(design: PRSDesign, profile: ThreadProfile, gauge: str | None = None) -> PartInspection:
    """Inspection values of one part's thread (``profile``) with a wire or a ball.

    Parameters
    ----------
    design : PRSDesign
        For the materials and the engaged length.
    profile : ThreadProfile
        The thread as made (for the screw: the theoretical profile of the contact stage).
    gauge : {"wire", "ball"}, optional
        Default: wires on the external threads, balls in the nut.
    """
    part = profile.part
    gauge = gauge or DEFAULT_GAUGE[part]
    if gauge == "wire" and profile.internal:
        # a straight pin leaves the helical groove radially outward, i.e. into the nut body:
        # only its local seat would be right, not a measurement over it
        raise ValueError(f"{part}: wires cannot measure an internal thread; use balls")
    groove = groove_at_pitch_line(profile)
    seat = best_gauge(groove, gauge)
    rho, R = seat.radius_mm, seat.centre_radius_mm
    M = 2.0 * (R + rho)
    rho_c = classical_best_radius(groove)
    M_c = 2.0 * (classical_seat(groove, rho) + rho)

    flanks = helical_flanks(profile)

    def numerical(radius: float, inclination: float,
                  sides: tuple[int, ...] = (1,)) -> tuple[NumericalSeat, list[float]]:
        placed = place_gauge(flanks, radius, gauge, inclination, classical_seat(groove, radius),
                             groove.pitch_radius_mm, sides)
        return placed, [2.0 * (c + radius) for c in placed.centre_radius_mm]

    placed, M_num = numerical(rho, seat.inclination_rad, (1, -1))
    check = max(abs(m - M) for m in M_num)
    contact_err = max(abs(c - groove.pitch_radius_mm) for c in placed.contact_radius_mm)
    # dM/dw for the part-only thermal coefficient: central difference of the numerical M
    # over the gauge diameter w = 2 rho (one flank suffices, both are mirror images)
    h = _DW_REL * rho
    M_plus, M_minus = (numerical(rho + d, seat.inclination_rad)[1][0] for d in (h, -h))
    dM_dw = (M_plus - M_minus) / (4.0 * h)  # w = 2 rho, so dw = 4 h across the difference
    # the same wire laid along the pitch-cylinder helix tangent instead of settled: what a
    # wire held at that inclination (or a formula assuming it) would read in excess
    tangent_excess = (numerical(rho, groove.pitch_helix_angle)[1][0] - M) if gauge == "wire" else 0.0
    alpha_t = getattr(design.materials, part).thermal_expansion_per_k
    n_p = design.thread.engaged_teeth * design.thread.pitch_mm
    return PartInspection(
        part=part, gauge=gauge, pitch_diameter_mm=2.0 * groove.pitch_radius_mm,
        lead_angle_deg=math.degrees(groove.lead_angle),
        gauge_diameter_mm=2.0 * rho, gauge_centre_diameter_mm=2.0 * R, measurement_mm=M,
        classical_gauge_diameter_mm=2.0 * rho_c, classical_measurement_mm=M_c,
        gauge_correction_um=2e3 * (rho - rho_c), measurement_correction_um=1e3 * (M - M_c),
        numerical_check_um=1e3 * check, contact_radius_check_um=1e3 * contact_err,
        wire_inclination_deg=math.degrees(seat.inclination_rad),
        pitch_helix_wire_excess_um=1e3 * tangent_excess,
        temperature_coefficient_um_per_k=1e3 * alpha_t * M,
        temperature_coefficient_part_only_um_per_k=1e3 * alpha_t * (M - 2.0 * rho * dM_dw),
        engaged_length_growth_um_per_k=1e3 * alpha_t * n_p,
        method=_method_text(part, gauge, profile.starts),
    )


def inspection(design: PRSDesign, contact: ContactResult | None = None) -> dict[str, PartInspection]:
    """Inspection values of screw (three wires, at the theoretical pitch diameter), roller
    (three wires) and nut (two balls), at 20 degC.

    Parameters
    ----------
    design : PRSDesign
    contact : ContactResult, optional
        The contact stage of the build (its theoretical screw is the screw as made);
        computed when omitted.
    """
    contact = contact if contact is not None else analyse_contact(design)
    profiles = ThreadProfiles.from_design(design)
    made = {"screw": contact.screw_profile, "roller": profiles.roller, "nut": profiles.nut}
    return {part: inspect_part(design, made[part]) for part in PARTS}


__all__ = ["GAUGES", "GaugeSeat", "GrooveAtPitchLine", "HelicalFlanks", "NumericalSeat", "PartInspection",
           "best_gauge", "classical_best_radius", "classical_seat", "groove_at_pitch_line", "helical_flanks",
           "inspect_part", "inspection", "place_gauge"]
