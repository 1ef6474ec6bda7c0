"""Where the working section sits in the drive: the arrangements of the stepless harmonic
friction drive (docs/theory/harmonic.md, section "Arrangements").

Pure math, no I/O, no mesh library.

The ratio model (:mod:`prs_geom.harmonic.model`) solves one **working section**: the
flexspline's generatrix, clamped at A and tilting rigidly by beta about it, carries the
contact arc; the circular spline's conical wall is a straight line moved by the position a
along the generatrix. The section is written in its own reference frame (x along the
generatrix from A, r across it, A = (0, r0)), which is the axial half-section of the radial
inner-wave drive. Each arrangement places that same section in the drive by a rigid map of
the meridian plane (drive frame: z along the axis, rho the distance from it):

* ``radial_inner`` (the published drive): z = x, rho = r. The generator inside, the conical
  bore of the circular spline outside.
* ``radial_outer``: the section mirrored about the neutral layer, z = x, rho = 2 r0 - r. The
  circular spline's conical *outer wall* inside the flexspline (its radius 2 r0 - b), the
  contact arc bulging toward the axis, the generator outside pressing inward.
* ``end_face``: the section turned by 90 degrees, rho = r0 + x, z = r - r0. The flexspline is
  a disc clamped at radius r0 and reaching to r0 + L; the generator pushes its rim axially
  onto the circular spline's conical face (half-angle 90 deg - alpha), which slides along the
  axis. Moving the face line axially by e is the same line as moving it along the generatrix
  by -e / tan(alpha), so the section's position a maps to the axial face position
  e = -(a - a_ref) tan(alpha) (:meth:`Arrangement.face_travel`).

A rigid map keeps every distance of the section, so the tilt beta, the tangency and the
clearances are those of the reference section; what changes is which coordinate is the
distance from the drive axis, and with it the radius difference at the contact:
Delta = rho(contact point) - rho(the same material point on the undeformed flexspline),
and the flexspline's rolling radius (r0 for the radial drives, whose neutral layer keeps its
length; rho of the undeformed contact point for the disc). The deformation of every meridian
is the section's turn about A by beta(theta), carried into the drive by the map (the mirror
and the quarter turn reverse its sense of rotation in (rho, z)).

* ``sealed`` (the source's sealed drive): the cone is on the flexspline and the contact arc on
  the circular spline, so it is not a map of the published section but a section of its own
  (:func:`sealed_tilt`, :func:`sealed_contact`), drawn in the drive frame directly (z = x,
  rho = r). The flexspline is a conical cup (half-angle alpha_f, neutral radius r0 at its bottom
  A), joined to the housing by a sealing wall on a bellows so that it moves axially without
  turning; the circular spline's bore carries the working arc (radius r_s, centre at radius
  rho_C) and is the output. Position a is the axial distance from A to the arc's centre. The
  generator tilts the cone's generatrix about A by beta until its outer surface (t / 2 off the
  neutral line) touches the arc:

      -a sin(alpha_f + beta) + (rho_C - r0) cos(alpha_f + beta) = t / 2 + r_s,

  so beta = arccos((t/2 + r_s) / hypot(a, rho_C - r0)) - atan2(a, rho_C - r0) - alpha_f.
  Moving the cone under the fixed arc changes the flexspline's radius under it, hence Delta;
  Delta = 0 (infinite ratio) where the untilted cone touches the arc.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["ARRANGEMENTS", "NOT_MODELLED", "Arrangement", "SectionContact", "section_contact", "sealed_tilt",
           "sealed_contact", "sealed_infinite_position"]

#: The arrangements the tool models, with one line each (report.json, report.html, docs).
ARRANGEMENTS: dict[str, str] = {
    "radial_inner": "radial inner-wave drive: generator inside the flexspline, conical bore in the circular spline "
                    "(the published example)",
    "radial_outer": "radial outer-wave drive: generator outside, conical outer wall on the circular spline inside "
                    "the flexspline (the section mirrored about the neutral layer)",
    "end_face": "end-face (axial) drive: the flexspline a disc clamped at r0, its rim pushed axially onto the "
                "circular spline's conical face, which slides along the axis (the section turned by 90 degrees)",
    "sealed": "sealed drive: conical flexspline moving axially on a bellows-mounted sealing wall, the working arc "
              "in the circular spline's bore (the output); the cone is on the flexspline",
}
#: Parts of the source's family that the tool does not model.
NOT_MODELLED = ("the sealing wall and bellows of the sealed drive as parts (their stiffness and the axial "
                "travel they allow); stages of different geometry; the working part as a separate insert")


@dataclass(frozen=True)
class Arrangement:
    """A rigid map of the working section into the drive's meridian plane (module docstring).

    Parameters
    ----------
    kind : str
        A key of :data:`ARRANGEMENTS`.
    neutral_radius_mm : float
        r0 (mm): the clamp A of the section is at x = 0, r = r0.
    """

    kind: str = "radial_inner"
    neutral_radius_mm: float = 50.0

    def __post_init__(self) -> None:
        if self.kind not in ARRANGEMENTS:
            raise ValueError(f"arrangement {self.kind!r}: must be one of {', '.join(ARRANGEMENTS)}")
        if not (math.isfinite(self.neutral_radius_mm) and self.neutral_radius_mm > 0):
            raise ValueError(f"neutral_radius_mm = {self.neutral_radius_mm}: must be finite and > 0")

    @property
    def is_disc(self) -> bool:
        """True when the flexspline is a disc clamped at r0 (no cup bottom to the axis)."""
        return self.kind == "end_face"

    @property
    def generator_is_disc(self) -> bool:
        """True when the wave generator is the elliptical disc inside the flexspline (the
        radial inner-wave and sealed drives); else it is the section's generator mapped."""
        return self.kind in ("radial_inner", "sealed")

    def working_half_angle(self, alpha: float) -> float:
        """Half-angle (rad) about the axis of the cone the pressing force acts on: alpha, the
        end face's face 90 deg - alpha."""
        return 0.5 * math.pi - alpha if self.is_disc else alpha

    @property
    def affine(self) -> tuple[tuple[tuple[float, float], tuple[float, float]], tuple[float, float]]:
        """The map as (M, c): (rho, z) = M (x, r) + c, M orthogonal (a rotation or a mirror)."""
        r0 = self.neutral_radius_mm
        if self.kind in ("radial_inner", "sealed"):
            return ((0.0, 1.0), (1.0, 0.0)), (0.0, 0.0)
        if self.kind == "radial_outer":
            return ((0.0, -1.0), (1.0, 0.0)), (2.0 * r0, 0.0)
        return ((1.0, 0.0), (0.0, 1.0)), (r0, -r0)

    def to_drive(self, x: ArrayLike, r: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(rho, z) (mm) in the drive's meridian of section points (x, r) (mm); broadcasts."""
        x = np.asarray(x, dtype=np.float64)
        r = np.asarray(r, dtype=np.float64)
        ((a, b), (c, d)), (e, f) = self.affine
        return a * x + b * r + e, c * x + d * r + f

    def to_section(self, rho: ArrayLike, z: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(x, r) (mm) of drive-meridian points (rho, z) (mm): the inverse of :meth:`to_drive`
        (M is orthogonal, so its inverse is its transpose)."""
        ((a, b), (c, d)), (e, f) = self.affine
        u = np.asarray(rho, dtype=np.float64) - e
        v = np.asarray(z, dtype=np.float64) - f
        return a * u + c * v, b * u + d * v

    def face_travel(self, a: ArrayLike, a_ref: float, tan_alpha: float) -> NDArray[np.float64]:
        """Axial travel (mm) of the circular spline from its place at ``a_ref`` to position a
        (mm): a - a_ref for the radial drives (the section's a is axial); for the end face
        the face line moved along the generatrix by a - a_ref is the same line moved along
        the axis by -(a - a_ref) tan(alpha)."""
        a = np.asarray(a, dtype=np.float64)
        if self.kind == "end_face":
            return -(a - a_ref) * tan_alpha
        return a - a_ref

    def travel_per_position(self, tan_alpha: float) -> float:
        """|d(axial travel) / da|: 1 for the radial drives, tan(alpha) for the end face."""
        return tan_alpha if self.kind == "end_face" else 1.0


@dataclass(frozen=True)
class SectionContact:
    """The contact of one position set in the drive frame (arrays over positions, mm).

    Attributes
    ----------
    contact_rho_mm, contact_z_mm : ndarray
        The contact point (deformed flexspline on the circular spline) in the drive meridian.
    material_rho_mm, material_z_mm : ndarray
        The same material point of the flexspline, undeformed.
    radius_difference_mm : ndarray
        Delta = contact_rho - material_rho: the circular spline's rolling radius minus the
        flexspline's material radius at the contact (negative: the flexspline's circle is
        the longer one, as in the outer-wave and end-face drives).
    flexspline_rolling_radius_mm : ndarray
        r_f: r0 for the radial drives (the neutral layer keeps its length), the material
        point's radius for the disc.
    ratio : ndarray
        |r_f / Delta| (the source's magnitude; signs: :func:`prs_geom.harmonic.drive.harmonic_ratio`
        with r_f and r_f + Delta).
    """

    contact_rho_mm: NDArray[np.float64]
    contact_z_mm: NDArray[np.float64]
    material_rho_mm: NDArray[np.float64]
    material_z_mm: NDArray[np.float64]
    radius_difference_mm: NDArray[np.float64]
    flexspline_rolling_radius_mm: NDArray[np.float64]
    ratio: NDArray[np.float64]


def section_contact(arrangement: Arrangement, beta: ArrayLike, alpha: float, arc_centre_x_mm: float,
                    arc_centre_offset_mm: float, arc_radius_mm: float) -> SectionContact:
    """The contact in the drive frame from the section's tilt ``beta`` (rad, over positions)
    and cone half-angle ``alpha`` (rad): the arc centre (x_s, r0 - c_s) turned by beta about
    A, the contact point r_s from it along the cone's normal (-sin alpha, cos alpha), the
    same material point on the undeformed arc at phi = alpha - beta
    (x_s - r_s sin phi, r0 - c_s + r_s cos phi); both mapped by the arrangement."""
    beta = np.asarray(beta, dtype=np.float64)
    r0 = arrangement.neutral_radius_mm
    xs, cs, rs = arc_centre_x_mm, arc_centre_offset_mm, arc_radius_mm
    cx = xs * np.cos(beta) + cs * np.sin(beta)
    cr = r0 + xs * np.sin(beta) - cs * np.cos(beta)
    phi = alpha - beta
    rho_c, z_c = arrangement.to_drive(cx - rs * math.sin(alpha), cr + rs * math.cos(alpha))
    rho_m, z_m = arrangement.to_drive(xs - rs * np.sin(phi), r0 - cs + rs * np.cos(phi))
    delta = rho_c - rho_m
    r_f = rho_m if arrangement.is_disc else np.full_like(delta, r0)
    with np.errstate(divide="ignore"):
        ratio = np.abs(r_f / delta)
    return SectionContact(rho_c, z_c, rho_m, z_m, delta, r_f, ratio)


def sealed_tilt(a: ArrayLike, neutral_radius_mm: float, wall_mm: float, cone_half_angle_rad: float,
                arc_centre_radius_mm: float, arc_radius_mm: float) -> NDArray[np.float64]:
    """The sealed drive's tilt beta (rad) at positions a (mm), closed form of the tangency in
    the module docstring (the small-tilt branch). NaN where the arc is out of reach."""
    a = np.asarray(a, dtype=np.float64)
    h = arc_centre_radius_mm - neutral_radius_mm
    with np.errstate(invalid="ignore"):
        return (np.arccos((0.5 * wall_mm + arc_radius_mm) / np.hypot(a, h)) - np.arctan2(a, h)
                - cone_half_angle_rad)


def sealed_infinite_position(neutral_radius_mm: float, wall_mm: float, cone_half_angle_rad: float,
                             arc_centre_radius_mm: float, arc_radius_mm: float) -> float:
    """a (mm) where the untilted cone touches the arc (beta = 0, Delta = 0)."""
    h = arc_centre_radius_mm - neutral_radius_mm
    return (h * math.cos(cone_half_angle_rad) - 0.5 * wall_mm - arc_radius_mm) / math.sin(cone_half_angle_rad)


def sealed_contact(a: ArrayLike, beta: ArrayLike, neutral_radius_mm: float, wall_mm: float,
                   cone_half_angle_rad: float, arc_centre_radius_mm: float, arc_radius_mm: float) -> SectionContact:
    """The sealed drive's contact in the drive frame at positions a (mm) and tilts beta (rad):
    the contact point r_s from the arc's centre (a, rho_C) toward the tilted cone (along its
    normal), the same material point of the flexspline turned back by -beta about
    A = (0, r0); Delta = rho(contact) - rho(material), the rolling radius the neutral layer's
    radius there (rho(material) - (t / 2) cos(alpha_f))."""
    a = np.asarray(a, dtype=np.float64)
    beta = np.asarray(beta, dtype=np.float64)
    r0 = neutral_radius_mm
    ang = cone_half_angle_rad + beta
    z_c = a + arc_radius_mm * np.sin(ang)
    rho_c = arc_centre_radius_mm - arc_radius_mm * np.cos(ang)
    # turn back about A = (z 0, rho r0)
    c, s = np.cos(beta), np.sin(beta)
    z_m = z_c * c + (rho_c - r0) * s
    rho_m = r0 - z_c * s + (rho_c - r0) * c
    delta = rho_c - rho_m
    r_f = rho_m - 0.5 * wall_mm * math.cos(cone_half_angle_rad)
    with np.errstate(divide="ignore"):
        ratio = np.abs(r_f / delta)
    return SectionContact(rho_c, z_c, rho_m, z_m, delta, r_f, ratio)
