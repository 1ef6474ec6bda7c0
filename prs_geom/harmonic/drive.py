"""The harmonic drive family's kinematics, strength limit and tolerance grades
(docs/theory/harmonic.md, "The drive family").

Pure math, no I/O. What the source article states about the whole family of stepless
harmonic friction drives, as functions of the quantities the geometry model
(:mod:`prs_geom.harmonic.model`) gives:

* **Kinematics of the circumference difference** (:func:`harmonic_ratio`). The flexspline
  and the circular spline touch where the wave generator holds them together; that point
  travels round with the generator. Rolling without slip there, the arc each member passes
  relative to the wave is the same: r_f (w_f - w_g) = r_c (w_c - w_g), r_f and r_c the
  rolling radii of the flexspline and the circular spline at the contact. With the circular
  spline fixed, i = w_g / w_f = r_f / (r_f - r_c); with the flexspline fixed,
  i = w_g / w_c = r_c / (r_c - r_f). Sign: positive when the output turns with the wave
  generator. In an inner-wave drive (flexspline inside, r_f < r_c) the flexspline turns
  against the generator (i < 0) and the circular spline with it; in an outer-wave drive
  both signs flip. With teeth on both members the radii become the tooth counts:
  -z_f / (z_c - z_f) and +z_c / (z_c - z_f) (the harmonic gear drive; :func:`toothed_ratio`).
* **Strength limit** (:func:`flexspline_bending_stress`, :func:`strength_limit`). The
  generator forces the flexspline's section into an oval whose radial deflection at the
  major axis is the radius difference Delta (the flexspline must reach the circular
  spline). A thin ring of neutral radius r and wall t bent into w = Delta cos(2 theta)
  changes its curvature by (w'' + w) / r^2 = -3 Delta cos(2 theta) / r^2, so its wall
  bends with the largest stress sigma = 3 E t Delta / (2 r^2) on the major and minor axes
  (thin-ring theory, the classical harmonic-drive flexspline estimate). The allowed stress
  sets the largest Delta and with it the smallest ratio |i| = r / Delta_max.
* **Tolerance grades** (:func:`tolerance_grade`): for a radius difference Delta at a contact
  diameter D, the finest ISO 286 grade whose standard tolerance at D is at least Delta
  (:func:`prs_geom.model.standards.finest_grade_at_least`): the source relates Delta to the
  machining grade of the two members (0.0519 mm about IT8, 0.0120 mm about IT5 near
  107.5 mm).

Units: mm, N, MPa; ratios dimensionless, signed as above.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prs_geom.model.errors import DesignError
from prs_geom.model.standards import finest_grade_at_least
from prs_geom.model.validation import positive

__all__ = ["FIXED_MEMBERS", "harmonic_ratio", "toothed_ratio", "FlexsplineMaterial", "FLEXSPLINE_MATERIALS",
           "flexspline_bending_stress", "disc_wave_stress", "StrengthLimit", "strength_limit", "tolerance_grade",
           "CIRCULAR_SPLINE_STEEL", "HERTZ_VALID_FRACTION", "ContactLoad", "contact_load", "PlanetaryStage",
           "planetary_stage"]

#: The member held by the housing: the other one is the output.
FIXED_MEMBERS = ("circular_spline", "flexspline")


def _fixed(fixed: str) -> str:
    if fixed not in FIXED_MEMBERS:
        raise DesignError("fixed_member", fixed, f"must be one of {', '.join(FIXED_MEMBERS)}")
    return fixed


def harmonic_ratio(flexspline_radius_mm: ArrayLike, circular_radius_mm: ArrayLike,
                   fixed: str = "circular_spline") -> NDArray[np.float64]:
    """Signed ratio w_generator / w_output of a harmonic friction drive (module docstring).

    Parameters
    ----------
    flexspline_radius_mm, circular_radius_mm : array_like
        Rolling radii r_f and r_c of the two members at the contact (mm); r_f < r_c for an
        inner-wave drive, r_f > r_c for an outer-wave one.
    fixed : {"circular_spline", "flexspline"}
        The member held still; the other is the output.
    """
    r_f = np.asarray(flexspline_radius_mm, dtype=np.float64)
    r_c = np.asarray(circular_radius_mm, dtype=np.float64)
    with np.errstate(divide="ignore"):
        if _fixed(fixed) == "circular_spline":
            return r_f / (r_f - r_c)
        return r_c / (r_c - r_f)


def toothed_ratio(flexspline_teeth: int, circular_teeth: int, fixed: str = "circular_spline") -> float:
    """Signed ratio of a harmonic gear drive: -z_f / (z_c - z_f) with the circular spline
    fixed, +z_c / (z_c - z_f) with the flexspline fixed (inner wave, z_c > z_f)."""
    for name, z in (("flexspline_teeth", flexspline_teeth), ("circular_teeth", circular_teeth)):
        if isinstance(z, bool) or not isinstance(z, (int, np.integer)) or z < 1:
            raise DesignError(name, z, "must be a whole number of teeth >= 1")
    if flexspline_teeth == circular_teeth:
        raise DesignError("circular_teeth", circular_teeth, "must differ from flexspline_teeth (the tooth "
                                                            "difference drives the output)")
    return float(harmonic_ratio(float(flexspline_teeth), float(circular_teeth), fixed))


@dataclass(frozen=True)
class FlexsplineMaterial:
    """Elastic modulus and allowed bending stress of a flexspline material.

    Parameters
    ----------
    name : str
        What it is.
    youngs_modulus_mpa : float
        E, MPa.
    allowed_bending_stress_mpa : float
        The bending stress the flexspline wall may carry in service (alternating with every
        generator half-turn), MPa.
    source : str
        Where the numbers come from.
    poisson_ratio : float
        nu (for the contact's elastic constant).
    """

    name: str
    youngs_modulus_mpa: float
    allowed_bending_stress_mpa: float
    source: str
    poisson_ratio: float = 0.3

    def __post_init__(self) -> None:
        for f in ("youngs_modulus_mpa", "allowed_bending_stress_mpa"):
            object.__setattr__(self, f, positive(f, getattr(self, f)))


#: Reference flexspline materials: a spring/bearing steel and a polyamide (the source names
#: metal and nylon flexsplines; the numbers are those its family issue states and the usual
#: handbook values).
FLEXSPLINE_MATERIALS: dict[str, FlexsplineMaterial] = {
    "steel": FlexsplineMaterial(
        "steel (flexspline grade, e.g. 40CrNiMoA hardened and tempered)", 206_000.0, 300.0,
        "E: handbook value for alloy steel; 300 MPa: allowed alternating bending stress of harmonic-drive "
        "flexsplines in the design literature (about a third of the fatigue-limited range)"),
    "pa66": FlexsplineMaterial(
        "polyamide PA66 (nylon 66)", 3_000.0, 25.0,
        "E: conditioned PA66 datasheets (2.8-3.3 GPa); 25 MPa: allowed long-term bending stress of PA66 "
        "gears and flexible parts (about a third of its flexural strength); nu 0.39", 0.39),
}


def flexspline_bending_stress(radius_difference_mm: ArrayLike, radius_mm: float, wall_mm: float,
                              youngs_modulus_mpa: float) -> NDArray[np.float64]:
    """Largest circumferential bending stress (MPa) of a thin ring of neutral radius
    ``radius_mm`` and wall ``wall_mm`` ovalised to a radial deflection Delta at its major
    axis: sigma = 3 E t Delta / (2 r^2) (module docstring)."""
    delta = np.abs(np.asarray(radius_difference_mm, dtype=np.float64))
    return 3.0 * youngs_modulus_mpa * wall_mm * delta / (2.0 * radius_mm ** 2)


def disc_wave_stress(axial_amplitude_mm: ArrayLike, radius_mm: ArrayLike, wall_mm: float,
                     youngs_modulus_mpa: float) -> NDArray[np.float64]:
    """Largest bending stress (MPa) of the end-face drive's disc rim, a thin ring of radius
    ``radius_mm`` bent out of its plane into w = W cos(2 theta) (W = ``axial_amplitude_mm``):
    its curvature changes by w'' / r^2 = 4 W / r^2 at the major axis, so
    sigma = E (t / 2) 4 W / r^2 = 2 E t W / r^2. The twist of the rim and the disc's radial
    bending near its clamp are left out (an estimate, as the thin-ring one of the cup)."""
    w = np.abs(np.asarray(axial_amplitude_mm, dtype=np.float64))
    r = np.asarray(radius_mm, dtype=np.float64)
    return 2.0 * youngs_modulus_mpa * wall_mm * w / r ** 2


@dataclass(frozen=True)
class StrengthLimit:
    """What the flexspline's allowed stress permits.

    Attributes
    ----------
    material : FlexsplineMaterial
        The material.
    max_radius_difference_mm : float
        The largest Delta before the wall reaches the allowed stress, mm.
    min_ratio : float
        The smallest |ratio| that follows, r0 / Delta_max (circular spline fixed).
    stress_at_min_position_mpa, stress_at_max_position_mpa : float
        The wall's bending stress at the design's two ends of travel, MPa.
    speed_range : float
        |ratio| at the largest position over the larger of the design's smallest |ratio|
        and ``min_ratio``: the range the drive may use.
    within : bool
        True when the design's smallest |ratio| is at least ``min_ratio``.
    """

    material: FlexsplineMaterial
    max_radius_difference_mm: float
    min_ratio: float
    stress_at_min_position_mpa: float
    stress_at_max_position_mpa: float
    speed_range: float
    within: bool


def strength_limit(material: FlexsplineMaterial, neutral_radius_mm: float, wall_mm: float,
                   delta_at_min_mm: float, delta_at_max_mm: float) -> StrengthLimit:
    """The strength limit of a flexspline (module docstring) against a design whose radius
    difference runs from ``delta_at_min_mm`` (smallest ratio) to ``delta_at_max_mm``."""
    k = flexspline_bending_stress(1.0, neutral_radius_mm, wall_mm, material.youngs_modulus_mpa)
    d_max = material.allowed_bending_stress_mpa / float(k)
    i_min = neutral_radius_mm / d_max
    s_lo = float(k) * abs(delta_at_min_mm)
    s_hi = float(k) * abs(delta_at_max_mm)
    i_design_min = neutral_radius_mm / abs(delta_at_min_mm)
    i_design_max = neutral_radius_mm / abs(delta_at_max_mm)
    return StrengthLimit(material, d_max, i_min, s_lo, s_hi, i_design_max / max(i_design_min, i_min),
                         i_design_min >= i_min)


def tolerance_grade(radius_difference_mm: ArrayLike, contact_diameter_mm: ArrayLike) -> list[str | None]:
    """Per position: the finest ISO 286 grade whose standard tolerance at the contact
    diameter is at least the radius difference (None: coarser than IT13)."""
    d = np.atleast_1d(np.abs(np.asarray(radius_difference_mm, dtype=np.float64)))
    dia = np.broadcast_to(np.asarray(contact_diameter_mm, dtype=np.float64), d.shape)
    return [finest_grade_at_least(float(D), float(x) * 1e3) for x, D in zip(d, dia)]


#: The circular spline's material for the contact (steel, E 206 GPa, nu 0.3).
CIRCULAR_SPLINE_STEEL = (206_000.0, 0.3)
#: Hertz's quadratic gap holds while the circumferential semi-axis is below this fraction of
#: the contact radius (the ovalised flexspline's gap follows cos 2 theta, not a parabola,
#: beyond it).
HERTZ_VALID_FRACTION = 0.1


@dataclass(frozen=True)
class ContactLoad:
    """Forces, torques and contact pressure at each position (arrays over the positions).

    Attributes
    ----------
    normal_force_n : ndarray
        Total normal force on the cone, F / sin(alpha) (both contact zones), N.
    output_torque_nm, input_torque_nm : ndarray
        Transmissible torque on the output member, mu N r / S (N m), and on the generator,
        the output torque over |ratio| (no losses counted), N m.
    max_pressure_mpa : ndarray
        Hertz's largest pressure of one contact zone (half the normal force), MPa.
    semi_axes_mm : ndarray (n, 2)
        Meridian and circumferential semi-axes of the contact ellipse, mm.
    hertz_valid : ndarray of bool
        The circumferential semi-axis is below ``HERTZ_VALID_FRACTION`` of the contact radius.
    """

    normal_force_n: NDArray[np.float64]
    output_torque_nm: NDArray[np.float64]
    input_torque_nm: NDArray[np.float64]
    max_pressure_mpa: NDArray[np.float64]
    semi_axes_mm: NDArray[np.float64]
    hertz_valid: NDArray[np.bool_]


def contact_load(alpha_rad: float, arc_radius_mm: float, neutral_radius_mm: float, contact_radius_mm: ArrayLike,
                 cone_radius_mm: ArrayLike, radius_difference_mm: ArrayLike, ratio: ArrayLike,
                 pressing_force_n: float, friction_coefficient: float, slip_safety_factor: float,
                 material: FlexsplineMaterial, circumferential_curvature_sum: ArrayLike | None = None) -> ContactLoad:
    """The contact's forces, torque capacity and Hertz pressure (docs/theory/harmonic.md,
    "Pressing force and torque").

    On a cone of half-angle alpha the pressing device's axial force F becomes the normal force
    N = F / sin(alpha), shared by the two contact zones of the elliptical generator. The
    friction force mu N acts at the contact radius: the output member carries
    T = mu N r_c / S. Each zone is a Hertz contact: meridian curvatures 1 / r_s (the arc) and
    0 (the cone line); circumferential, the ovalised flexspline at its major axis,
    1 / r_c + 3 Delta / r0^2 (thin ring), against the bore, -1 / R_c, both times cos(alpha)
    (normal curvature of a surface of revolution). The pair nearly conforms around the
    circumference, so the ellipse is long there; Hertz holds while that semi-axis is small
    against r_c (``hertz_valid``).

    ``alpha_rad`` is the half-angle of the circular spline's working cone about the axis (the
    end-face drive's face: 90 deg - alpha). ``circumferential_curvature_sum`` (1/mm, per
    position) replaces the radial inner-wave drive's sum
    cos(alpha) (1 / r_c + 3 Delta / r0^2 - 1 / R_c) for the other arrangements."""
    from prs_geom.analysis.hertz import hertz_contact

    r_c = np.atleast_1d(np.asarray(contact_radius_mm, dtype=np.float64))
    R_c = np.broadcast_to(np.asarray(cone_radius_mm, dtype=np.float64), r_c.shape)
    delta = np.broadcast_to(np.asarray(radius_difference_mm, dtype=np.float64), r_c.shape)
    i = np.broadcast_to(np.asarray(ratio, dtype=np.float64), r_c.shape)
    normal = np.full(r_c.shape, pressing_force_n / math.sin(alpha_rad))
    torque = friction_coefficient * normal * r_c / slip_safety_factor * 1e-3
    E_c, nu_c = CIRCULAR_SPLINE_STEEL
    eta = (1 - material.poisson_ratio ** 2) / material.youngs_modulus_mpa + (1 - nu_c ** 2) / E_c
    ca = math.cos(alpha_rad)
    p_max, axes = np.empty(r_c.shape), np.empty(r_c.shape + (2,))
    for k in range(r_c.size):     # a handful of positions; each a scalar Hertz solve
        if circumferential_curvature_sum is None:
            flex = ca * (1.0 / r_c[k] + 3.0 * delta[k] / neutral_radius_mm ** 2)
            h = hertz_contact((1.0 / arc_radius_mm, flex, 0.0, -ca / R_c[k]), eta)
        else:
            h = hertz_contact((1.0 / arc_radius_mm, float(np.ravel(circumferential_curvature_sum)[k]), 0.0, 0.0),
                              eta)
        a, b = h.semi_axes(0.5 * normal[k])
        p_max[k] = 3.0 * 0.5 * normal[k] / (2.0 * math.pi * a * b)
        # plane 1 is the meridian, plane 2 the circumference
        axes[k] = (a, b) if h.major_in_plane_1 else (b, a)
    valid = axes[:, 1] <= HERTZ_VALID_FRACTION * r_c
    return ContactLoad(normal, torque, torque / np.abs(i), p_max, axes, valid)


# --------------------------------------------------------------------------- planetary generator
@dataclass(frozen=True)
class PlanetaryStage:
    """The planetary wave generator's kinematics at each position (arrays over positions).

    Attributes
    ----------
    sun_radius_mm, planet_cone_radius_mm : ndarray
        Contact radii of the input cone disc (the sun) and of the support shaft's cone (the
        planet) at their common generatrix, mm.
    stage_ratio : ndarray
        w_input / w_carrier with the flexspline's inner surface (the ring) at rest:
        1 + (r_ring r_planet_cone) / (r_sun r_roller).
    product_ratio : ndarray
        stage ratio x the harmonic ratio (the source's statement).
    coupled_ratio : ndarray
        The same drive with the ring turning at the output speed (Willis with all three
        members moving): i_h (1 + K) - K, K = stage_ratio - 1.
    """

    sun_radius_mm: NDArray[np.float64]
    planet_cone_radius_mm: NDArray[np.float64]
    stage_ratio: NDArray[np.float64]
    product_ratio: NDArray[np.float64]
    coupled_ratio: NDArray[np.float64]


def planetary_stage(shift_mm: ArrayLike, sun_radius_mm: float, planet_cone_radius_mm: float,
                    cone_half_angle_deg: float, roller_radius_mm: float, ring_radius_mm: float,
                    harmonic_ratio_: ArrayLike, fixed: str = "circular_spline") -> PlanetaryStage:
    """The planetary wave generator (docs/theory/harmonic.md, "Planetary wave generator").

    Two cone discs keyed to the input (the sun) drive support shafts (the planets) through
    conical surfaces; each shaft carries a working roller that rolls on the flexspline's inner
    surface (the ring) and the carrier holding the shafts is the wave. The sun and planet cones
    touch along a common generatrix of half-angle gamma: when the contact moves axially by s,
    the sun's radius grows by s tan(gamma) and the planet cone's shrinks by as much (their sum,
    the shaft's distance from the axis, is fixed). Rolling without slip at both contacts
    (velocities relative to the carrier) gives, with the ring at rest,
    w_sun / w_carrier = 1 + (r_ring r_p) / (r_sun r_w). The ring is the flexspline: with the
    circular spline fixed it turns at the output speed, and Willis' equation with all three
    members moving gives the drive's ratio i_h (1 + K) - K (``coupled_ratio``; the source's
    product i_h (1 + K) neglects the ring's slow turn); with the flexspline fixed the two agree.
    """
    s = np.asarray(shift_mm, dtype=np.float64)
    t = math.tan(math.radians(cone_half_angle_deg))
    r_s = sun_radius_mm + s * t
    r_p = planet_cone_radius_mm - s * t
    if np.any(r_s <= 0) or np.any(r_p <= 0):
        raise ValueError(f"a cone contact shift of {float(np.max(np.abs(s))):.3f} mm runs off the sun disc or "
                         f"the planet cone (a radius reaches 0)")
    K = (ring_radius_mm * r_p) / (r_s * roller_radius_mm)
    stage = 1.0 + K
    i_h = np.asarray(harmonic_ratio_, dtype=np.float64)
    coupled = i_h * (1.0 + K) - K if _fixed(fixed) == "circular_spline" else stage * i_h
    return PlanetaryStage(r_s, r_p, stage, stage * i_h, coupled)
