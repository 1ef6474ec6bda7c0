"""Checks of a roller gear (external pinion) meshing inside a nut ring gear (pure math).

Owns the compatibility rule of such a pair (:func:`require_internal_pair`), its zero-backlash
centre distance (:func:`standard_centre_distance`), the mesh geometry and interference checks
(:func:`internal_pair_checks`: backlash, contact ratio, undercut, involute, fillet, trochoid
and trimming interference, root clearances, tip thicknesses) and the running clearance of
every roller gear against the ring over a carrier sweep (:func:`sweep_clearance`).
Conventions (units, gear frame, profile-shift signs) are those of
:mod:`~prs_geom.geometry.gears`; formulas and sources in docs/theory/gears.md.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
import numpy as np
from numpy.typing import ArrayLike, NDArray

from prs_geom.geometry.gears import SpurGear, involute, inverse_involute
from prs_geom.geometry.planar import frozen_float64, min_clearance_2d, transform_2d
from prs_geom.model.errors import DesignError
from prs_geom.model.validation import positive

__all__ = ["CheckResult", "InternalPairChecks", "SweepClearance", "internal_pair_checks", "pinion_transform",
           "require_internal_pair", "standard_centre_distance"]


@dataclass(frozen=True)
class CheckResult:
    """One check of a gear pair: the number, the limit and the rule."""

    name: str
    passed: bool
    value: float
    limit: float
    unit: str
    rule: str


@dataclass(frozen=True)
class InternalPairChecks:
    """Geometry and checks of a pinion (roller gear) meshing inside a ring (nut gear).

    Attributes
    ----------
    centre_distance_mm : float
        Working centre distance a (mm).
    working_pressure_angle_deg : float
        alpha_w, cos alpha_w = (r_b2 - r_b1) / a.
    working_pitch_radii_mm : tuple[float, float]
        r_w1 = a z1 / (z2 - z1), r_w2 = a z2 / (z2 - z1).
    contact_ratio : float
        Transverse contact ratio epsilon_alpha.
    backlash_circumferential_mm, backlash_normal_mm : float
        Backlash present at a: circumferential on the working pitch circles, and along the line
        of action (= circumferential x cos alpha_w).
    start_active_radius_pinion_mm, end_active_radius_ring_mm : float
        Radii where the path of contact starts on the pinion (ring tip) and ends on the ring
        (pinion tip).
    items : tuple[CheckResult, ...]
        The checks; ``passed`` is True when all pass.
    """

    centre_distance_mm: float
    working_pressure_angle_deg: float
    working_pitch_radii_mm: tuple[float, float]
    contact_ratio: float
    backlash_circumferential_mm: float
    backlash_normal_mm: float
    start_active_radius_pinion_mm: float
    end_active_radius_ring_mm: float
    items: tuple[CheckResult, ...]

    @property
    def passed(self) -> bool:
        """True when every check passes."""
        return all(c.passed for c in self.items)

    @property
    def failed(self) -> tuple[str, ...]:
        """Names of the failed checks, in order."""
        return tuple(c.name for c in self.items if not c.passed)

    def __getitem__(self, name: str) -> CheckResult:
        """The check called ``name``; KeyError when there is none."""
        for c in self.items:
            if c.name == name:
                return c
        raise KeyError(name)


def require_internal_pair(pinion: SpurGear, ring: SpurGear) -> None:
    """Raise :class:`~prs_geom.model.errors.DesignError` unless ``pinion`` is external,
    ``ring`` internal, both of the same module and pressure angle, and the ring has more teeth."""
    if pinion.internal:
        raise DesignError("pinion.internal", pinion.internal, "the pinion (roller gear) must be external")
    if not ring.internal:
        raise DesignError("ring.internal", ring.internal, "the ring (nut gear) must be internal")
    if abs(pinion.module_mm - ring.module_mm) > 1e-12 * ring.module_mm:
        raise DesignError("ring.module_mm", ring.module_mm, f"must equal the pinion module {pinion.module_mm!r}")
    if abs(pinion.pressure_angle_deg - ring.pressure_angle_deg) > 1e-12:
        raise DesignError("ring.pressure_angle_deg", ring.pressure_angle_deg,
                          f"must equal the pinion pressure angle {pinion.pressure_angle_deg!r}")
    if ring.teeth <= pinion.teeth:
        raise DesignError("ring.teeth", ring.teeth, f"must exceed the pinion teeth {pinion.teeth}")


def standard_centre_distance(pinion: SpurGear, ring: SpurGear) -> float:
    """Zero-backlash centre distance of the pair (mm): a = m (z2 - z1) cos a / (2 cos a_w),
    inv a_w = inv a - 2 tan a (x1 + x2) / (z2 - z1) (ISO 21771 signs); equals m (z2 - z1)/2
    when x1 + x2 = 0. Thinning for backlash does not move it."""
    require_internal_pair(pinion, ring)
    a, m = pinion.alpha, pinion.module_mm
    dz = ring.teeth - pinion.teeth
    inv_w = involute(a) - 2.0 * math.tan(a) * (pinion.profile_shift + ring.profile_shift) / dz
    aw = inverse_involute(inv_w)
    return 0.5 * m * dz * math.cos(a) / math.cos(aw)


def internal_pair_checks(pinion: SpurGear, ring: SpurGear, centre_distance_mm: float | None = None, *,
                         min_contact_ratio: float = 1.2, min_tip_thickness: float = 0.2,
                         min_root_clearance: float = 0.1, min_backlash_mm: float = 0.0) -> InternalPairChecks:
    """Mesh geometry and interference checks of an external pinion inside an internal ring.

    Parameters
    ----------
    pinion, ring : SpurGear
        External and internal gear of the same module and pressure angle, z2 > z1.
    centre_distance_mm : float, optional
        Working centre distance a (mm); default :func:`standard_centre_distance`.
    min_contact_ratio : float
        Smallest accepted transverse contact ratio (default 1.2, the usual design floor).
    min_tip_thickness : float
        Smallest accepted tip thickness of either gear, in modules (default 0.2 m).
    min_root_clearance : float
        Smallest accepted radial tip-to-root clearance, in modules (default 0.1 m).
    min_backlash_mm : float
        Smallest accepted normal backlash (mm); default 0: flanks must not touch.

    Checks (names of ``items``)
    ---------------------------
    ``backlash``
        Normal backlash at a (mm) >= ``min_backlash_mm`` and > 0. Computed from the tooth
        thicknesses on the working pitch circles: j_t = e_w2 - s_w1, j_n = j_t cos a_w.
    ``contact_ratio``
        eps = [sqrt(r_a1^2 - r_b1^2) - sqrt(r_a2^2 - r_b2^2) + a sin a_w] / p_b.
    ``pinion_undercut``
        x1 >= x_min = h_FfP* - z1 sin^2 a / 2 (rack generation, ISO 53 A: h_FfP* = 1).
    ``involute_interference``
        The ring tip circle must cut the line of action on the ring side of the pinion's base
        tangent point T1: T1A = sqrt(r_a2^2 - r_b2^2) - a sin a_w >= 0; equivalent to
        z1/z2 >= 1 - tan a_a2 / tan a_w (SDP-SI / KHK, "Elements of Metric Gear Technology"
        eq. 5-5).
    ``pinion_fillet_contact``
        The contact starts on the generated involute of the pinion: r_A1 >= r_Ff1, with
        r_A1 = sqrt(r_b1^2 + T1A^2) (DIN 3960 / ISO 21771 d_Nf >= d_Ff).
    ``ring_fillet_contact``
        The contact ends inside the ring's involute: r_E2 <= r_Ff2, r_E2 = sqrt(r_b2^2 +
        (sqrt(r_a1^2 - r_b1^2) + a sin a_w)^2).
    ``trochoid_interference``
        theta1 z1/z2 + inv a_w - inv a_a2 >= theta2, theta1 = acos((r_a2^2 - r_a1^2 - a^2) /
        (2 a r_a1)) + inv a_a1 - inv a_w, theta2 = acos((a^2 + r_a2^2 - r_a1^2) / (2 a r_a2))
        (SDP-SI / KHK eqs. 5-6, 5-7): the pinion tip must not cut the ring tip on leaving mesh.
    ``trimming_interference``
        theta1 + inv a_a1 - inv a_w >= (z2/z1) (theta2 + inv a_a2 - inv a_w) with
        theta1 = asin(sqrt((1 - (cos a_a1 / cos a_a2)^2) / (1 - (z1/z2)^2))), theta2 =
        asin(sqrt(((cos a_a2 / cos a_a1)^2 - 1) / ((z2/z1)^2 - 1))) (eqs. 5-9, 5-10): the
        pinion can be pulled out radially (else it must be assembled axially).
    ``root_clearance_pinion_tip`` / ``root_clearance_ring_tip``
        r_f2 - (a + r_a1) and (r_a2 - a) - r_f1 >= ``min_root_clearance`` m.
    ``tip_thickness_pinion`` / ``tip_thickness_ring``
        s_a >= ``min_tip_thickness`` m.

    The value of each item is the margin-carrying number named in its rule; margins are
    reported even when a formula's premise fails (then the item fails with value nan).
    """
    require_internal_pair(pinion, ring)
    a_std = standard_centre_distance(pinion, ring)
    a = a_std if centre_distance_mm is None else positive("centre_distance_mm", centre_distance_mm)
    mesh = _working_mesh(pinion, ring, a)
    backlash, j_t, j_n = _backlash_check(pinion, ring, mesh, min_backlash_mm)
    path = _path_of_contact(pinion, ring, mesh)
    m = pinion.module_mm
    items = (backlash, *_contact_checks(pinion, ring, path, min_contact_ratio), *_tip_path_checks(pinion, ring, mesh),
             *_size_checks(pinion, ring, a, min_root_clearance * m, min_tip_thickness * m))
    return InternalPairChecks(
        centre_distance_mm=a, working_pressure_angle_deg=math.degrees(mesh.working_angle),
        working_pitch_radii_mm=mesh.working_pitch_radii, contact_ratio=path.contact_ratio,
        backlash_circumferential_mm=j_t, backlash_normal_mm=j_n,
        start_active_radius_pinion_mm=path.start_radius_pinion, end_active_radius_ring_mm=path.end_radius_ring,
        items=items)


@dataclass(frozen=True)
class _WorkingMesh:
    """The pair at centre distance a (mm): cos and angle (rad) of the working pressure angle
    alpha_w, cos alpha_w = (r_b2 - r_b1) / a, and the working pitch radii (r_w1, r_w2)."""

    centre_distance: float
    cos_working_angle: float
    working_angle: float
    working_pitch_radii: tuple[float, float]


def _working_mesh(pinion: SpurGear, ring: SpurGear, a: float) -> _WorkingMesh:
    z1, z2 = pinion.teeth, ring.teeth
    rb1, rb2 = pinion.base_radius_mm, ring.base_radius_mm
    cw = (rb2 - rb1) / a
    if not 0.0 < cw < 1.0:
        raise DesignError("centre_distance_mm", a,
                          f"must exceed r_b2 - r_b1 = {rb2 - rb1:.6g} mm (no working pressure angle)")
    return _WorkingMesh(centre_distance=a, cos_working_angle=cw, working_angle=math.acos(cw),
                        working_pitch_radii=(a * z1 / (z2 - z1), a * z2 / (z2 - z1)))


@dataclass(frozen=True)
class _PathOfContact:
    """Lengths (mm) along the line of action and the contact ratio.

    tip_roll_pinion, tip_roll_ring : sqrt(r_a^2 - r_b^2) of each gear; t1a : T1A, from the
    pinion's base tangent point to where the ring tip cuts the line of action (< 0: below T1);
    start_radius_pinion : r_A1; end_radius_ring : r_E2.
    """

    tip_roll_pinion: float
    tip_roll_ring: float
    contact_ratio: float
    t1a: float
    start_radius_pinion: float
    end_radius_ring: float


def _path_of_contact(pinion: SpurGear, ring: SpurGear, mesh: _WorkingMesh) -> _PathOfContact:
    a, aw = mesh.centre_distance, mesh.working_angle
    rb1, rb2 = pinion.base_radius_mm, ring.base_radius_mm
    ra1, ra2 = pinion.tip_radius_mm, ring.tip_radius_mm
    g1 = math.sqrt(ra1 * ra1 - rb1 * rb1)
    g2 = math.sqrt(ra2 * ra2 - rb2 * rb2)
    t1a = g2 - a * math.sin(aw)
    return _PathOfContact(tip_roll_pinion=g1, tip_roll_ring=g2,
                          contact_ratio=(g1 - g2 + a * math.sin(aw)) / pinion.base_pitch_mm, t1a=t1a,
                          start_radius_pinion=math.hypot(rb1, max(t1a, 0.0)),
                          end_radius_ring=math.hypot(rb2, g1 + a * math.sin(aw)))


def _item(name: str, value: float, limit: float, ok: bool, unit: str, rule: str) -> CheckResult:
    """A check that passes when ``ok`` holds and ``value`` is finite."""
    return CheckResult(name=name, passed=bool(ok) and math.isfinite(value), value=float(value), limit=float(limit),
                       unit=unit, rule=rule)


def _backlash_check(pinion: SpurGear, ring: SpurGear, mesh: _WorkingMesh,
                    min_backlash_mm: float) -> tuple[CheckResult, float, float]:
    """The ``backlash`` item, the circumferential j_t and the normal j_n backlash (mm), from the
    tooth thicknesses on the working pitch circles (both roll without slip there)."""
    rw1, rw2 = mesh.working_pitch_radii
    s_w1 = 2.0 * rw1 * float(pinion.involute_polar(rw1))
    e_w2 = 2.0 * rw2 * (math.pi / ring.teeth - float(ring.involute_polar(max(rw2, ring.base_radius_mm))))
    j_t = e_w2 - s_w1
    j_n = j_t * mesh.cos_working_angle
    item = _item("backlash", j_n, min_backlash_mm, j_n > max(min_backlash_mm, 0.0), "mm",
                 "normal backlash j_n = (e_w2 - s_w1) cos a_w must be > 0 and >= the stated minimum")
    return item, j_t, j_n


def _contact_checks(pinion: SpurGear, ring: SpurGear, path: _PathOfContact,
                    min_contact_ratio: float) -> tuple[CheckResult, ...]:
    """``contact_ratio``, ``pinion_undercut``, ``involute_interference`` and the two fillet
    contact items."""
    eps, t1a = path.contact_ratio, path.t1a
    r_a1, r_e2 = path.start_radius_pinion, path.end_radius_ring
    r_ff1, r_ff2 = pinion.form_radius_mm, ring.form_radius_mm
    return (
        _item("contact_ratio", eps, min_contact_ratio, eps >= min_contact_ratio, "",
              "transverse contact ratio [sqrt(ra1^2-rb1^2) - sqrt(ra2^2-rb2^2) + a sin a_w] / p_b"),
        _item("pinion_undercut", pinion.profile_shift, pinion.undercut_limit_shift, not pinion.undercut, "",
              "pinion profile shift x1 >= h_FfP* - z1 sin^2(a)/2 (no undercut by the generating rack)"),
        _item("involute_interference", t1a, 0.0, t1a >= 0.0, "mm",
              "ring tip must meet the line of action between T1 and T2: sqrt(ra2^2 - rb2^2) - a sin a_w >= 0"),
        _item("pinion_fillet_contact", r_a1 - r_ff1, 0.0, t1a >= 0.0 and r_a1 >= r_ff1 - 1e-12, "mm",
              "contact must start on the pinion involute: start-of-active-profile radius r_A1 >= form radius r_Ff1"),
        _item("ring_fillet_contact", r_ff2 - r_e2, 0.0, r_e2 <= r_ff2 + 1e-12, "mm",
              "contact must end on the ring involute: end-of-active-profile radius r_E2 <= form radius r_Ff2"),
    )


def _tip_path_checks(pinion: SpurGear, ring: SpurGear, mesh: _WorkingMesh) -> tuple[CheckResult, CheckResult]:
    """``trochoid_interference`` and ``trimming_interference`` (nan when the formula's premise
    fails, which fails the item)."""
    a, inv_aw = mesh.centre_distance, involute(mesh.working_angle)
    z1, z2 = pinion.teeth, ring.teeth
    ra1, ra2 = pinion.tip_radius_mm, ring.tip_radius_mm
    aa1, aa2 = math.acos(pinion.base_radius_mm / ra1), math.acos(ring.base_radius_mm / ra2)
    c1 = (ra2 * ra2 - ra1 * ra1 - a * a) / (2.0 * a * ra1)
    c2 = (a * a + ra2 * ra2 - ra1 * ra1) / (2.0 * a * ra2)
    if abs(c1) <= 1.0 and abs(c2) <= 1.0:
        th1 = math.acos(c1) + involute(aa1) - inv_aw
        th2 = math.acos(c2)
        troch = th1 * z1 / z2 + inv_aw - involute(aa2) - th2
    else:
        troch = math.nan
    q1 = (1.0 - (math.cos(aa1) / math.cos(aa2)) ** 2) / (1.0 - (z1 / z2) ** 2)
    q2 = ((math.cos(aa2) / math.cos(aa1)) ** 2 - 1.0) / ((z2 / z1) ** 2 - 1.0)
    if 0.0 <= q1 <= 1.0 and 0.0 <= q2 <= 1.0:
        th1 = math.asin(math.sqrt(q1))
        th2 = math.asin(math.sqrt(q2))
        trim = th1 + involute(aa1) - inv_aw - (z2 / z1) * (th2 + involute(aa2) - inv_aw)
    else:
        trim = math.nan
    return (
        _item("trochoid_interference", troch, 0.0, troch >= 0.0, "rad",
              "pinion tip must clear the ring tip on leaving mesh: th1 z1/z2 + inv a_w - inv a_a2 - th2 >= 0"),
        _item("trimming_interference", trim, 0.0, trim >= 0.0, "rad",
              "pinion must come out radially: th1 + inv a_a1 - inv a_w - (z2/z1)(th2 + inv a_a2 - inv a_w) >= 0"),
    )


def _size_checks(pinion: SpurGear, ring: SpurGear, a: float, min_clearance_mm: float,
                 min_tip_mm: float) -> tuple[CheckResult, ...]:
    """The two root clearances and the two tip thicknesses against their minima (mm)."""
    cl1 = ring.root_radius_mm - (a + pinion.tip_radius_mm)
    cl2 = (ring.tip_radius_mm - a) - pinion.root_radius_mm
    return (
        _item("root_clearance_pinion_tip", cl1, min_clearance_mm, cl1 >= min_clearance_mm, "mm",
              "pinion tip to ring root: r_f2 - (a + r_a1) >= min clearance"),
        _item("root_clearance_ring_tip", cl2, min_clearance_mm, cl2 >= min_clearance_mm, "mm",
              "ring tip to pinion root: (r_a2 - a) - r_f1 >= min clearance"),
        _item("tip_thickness_pinion", pinion.tip_thickness_mm, min_tip_mm, pinion.tip_thickness_mm >= min_tip_mm,
              "mm", "pinion tip thickness s_a1 >= min"),
        _item("tip_thickness_ring", ring.tip_thickness_mm, min_tip_mm, ring.tip_thickness_mm >= min_tip_mm,
              "mm", "ring tip thickness s_a2 >= min"),
    )



@dataclass(frozen=True)
class SweepClearance:
    """Clearance of every roller gear against the ring over a carrier sweep.

    advance_rad : (n_steps,) carrier advances (rad); clearance_mm : (n_rollers, n_steps) minimum
    boundary distance (mm); overlap : same shape, 1.0 where the materials overlap, else 0.0.
    All read-only float64.
    """

    advance_rad: NDArray[np.float64]
    clearance_mm: NDArray[np.float64]
    overlap: NDArray[np.float64]

    @property
    def min_clearance_mm(self) -> float:
        """Smallest clearance (mm) of any roller at any step."""
        return float(self.clearance_mm.min())

    @property
    def any_overlap(self) -> bool:
        """True when any roller gear overlaps the ring at any step."""
        return bool(self.overlap.any())


def pinion_transform(carrier_angle_rad: float, centre_distance_mm: float, spin_rad: float) -> NDArray[np.float64]:
    """R_z(psi) Tr(a) R_z(chi) as a 3x3 2D transform (pinion frame -> ring frame)."""
    return (transform_2d(carrier_angle_rad) @ transform_2d(0.0, centre_distance_mm)
            @ transform_2d(spin_rad))

