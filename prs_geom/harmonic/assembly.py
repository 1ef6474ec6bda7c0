"""The harmonic friction drive as a placed assembly: circular spline, wave generator and the
flexspline deformed by it, at one input position a (docs/theory/harmonic.md, section
"Wave generator and placed assembly").

Frame (the assembly frame): z along the common axis, z = 0 at the flexspline bottom (the
ratio model's x), x along the wave generator's major axis (theta = 0), y completing a
right-handed frame; mm, angles rad. theta is the polar angle about z from +x.

It also holds the parts' undeformed geometry (half-section profiles, revolved meshes in their
own frames), which :mod:`prs_geom.harmonic.exports` re-exports.

Assumptions (stated once, used everywhere below):

* **Flexspline deformation.** Every meridian section of the flexspline (wall and contact
  arc) turns rigidly about its bottom point A = (r0, 0) of the neutral layer, by the tilt
  ``beta(theta) = beta(a) cos(2 theta)``, with beta(a) the ratio model's tilt
  (:func:`~prs_geom.harmonic.model.tilt_angle`). On the major axis (theta = 0, pi) this is
  the model's section exactly; around the circumference it is the classic two-lobed wave of
  a cup flexspline (radial displacement growing linearly with z, "coning"), whose mean over
  theta is zero, so the open end keeps its circumference to first order (an inextensible
  ring). A point (r, z) of a meridian maps to

      r' = r0 + (r - r0) cos(beta) + z sin(beta),   z' = -(r - r0) sin(beta) + z cos(beta),

  which reproduces the model's arc centre (x_s cos b + c_s sin b, r0 + x_s sin b - c_s cos b).
  The cup bottom stays a fan from the axis (its rim turns with the wall, moving at most
  (t/2) sin(beta) axially: 8 um in the example at a = 58 mm); only continuity is modelled there.
* **Wave generator.** An elliptical disc (the cam with its flexible bearing taken as one
  solid, outer race = the ellipse), coaxial, not tilted, occupying the axial band
  ``z_s - h .. z_s + h`` under the contact (z_s = x_s = L - r_s the arc centre station,
  h = min(r_s / 2, 0.9 (z_j - x_s), 0.9 (x_s - t)), z_j the inner wall's top). Its semi-axes
  are the smallest radius of the deformed inner wall over the band on the major axis (x) and
  on the minor axis (y): it touches the flexspline on four lines (theta = 0, pi at the
  band's lower edge, where the outward-tilted wall is nearest; theta = +-pi/2 at its upper
  edge) and clears it elsewhere (an ellipse lies inside the cos(2 theta) wave by a second-
  order amount). A positive tilt gives the x semi-axis as the major one.
* **Circular spline.** Its undeformed mesh (own frame, bore small end at z = 0) translated
  along z by a: the cone's small end at distance a from the flexspline bottom (the model's
  control input). It does not turn, so its angular position is immaterial.
* **Default position.** The middle of the control range, (positions.min_mm +
  positions.max_mm) / 2 (the design has no nominal position).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from prs_geom.geometry.planar import point_segment_distance
from prs_geom.harmonic.model import HarmonicDesign, contact_point, contact_state, drive_contact, tilt_angle
from prs_geom.model.errors import DesignError

__all__ = ["PARTS", "DEFORMATION", "WAVE_GENERATOR_RULE", "POSITION_RULE", "revolution_sections",
           "circular_spline_mesh", "flexspline_profile", "circular_spline_profile", "flexspline_mesh",
           "default_position", "meridian_tilt", "tilt_meridian", "deform", "inner_wall_radius",
           "WaveGenerator", "wave_generator", "wave_generator_mesh", "wave_generator_deviation",
           "DeformedFlexspline", "deformed_flexspline", "flexspline_deviation", "HarmonicAssembly",
           "build_assembly", "cone_gap", "arc_cone_clearance", "assembly_checks", "mesh_rows",
           "assembly_summary", "section_profile", "face_reference_position", "circular_spline_placement",
           "GENERATOR_THICKNESS", "mapped_generator_mesh", "mapped_generator_deviation", "RATIO_SAMPLES",
           "measured_ratio", "RIDGE_ARC_SHARE", "circular_spline_arc_bound", "cone_start"]

#: Names of the placed parts, in scene order.
PARTS = ("circular_spline", "flexspline", "wave_generator")
#: Text of the deformation assumption (report.json, report.html).
DEFORMATION = ("each meridian section of the flexspline turns rigidly about its bottom point A by "
               "beta(theta) = beta(a) cos(2 theta), theta from the wave generator's major axis; "
               "the model's section on the major axis")
#: Text of the wave generator rule (report.json, report.html).
WAVE_GENERATOR_RULE = ("elliptical disc, coaxial, axial band x_s +- h with h = min(r_s/2, 0.9 (z_j - x_s), "
                       "0.9 (x_s - t)); semi-axes = smallest radius of the deformed inner wall over the band "
                       "on the x and y axes (touches on four lines, clears elsewhere)")
#: Text of the default position rule.
POSITION_RULE = "middle of the control range, (positions.min_mm + positions.max_mm) / 2"


# --------------------------------------------------------------------------- part geometry (undeformed)
def revolution_sections(radius: float, tol: float) -> int:
    """Sections of a revolution whose chords at ``radius`` (mm) stay within ``tol`` (mm) of the
    circle (sagitta radius (1 - cos(pi / n)) <= tol), at least 24."""
    return max(24, int(math.ceil(math.pi / math.acos(1.0 - tol / radius))))


def circular_spline_mesh(d: HarmonicDesign, tol: float | None = None) -> trimesh.Trimesh:
    """The ring (own frame, mm: radial drives with the cone's small end at z = 0; the end
    face at its reference place, :func:`circular_spline_profile`) at chord tolerance ``tol``
    (mm; default the design's)."""
    prof = circular_spline_profile(d)
    closed = np.concatenate([prof, prof[:1]])
    tol = d.mesh.chord_tolerance_mm if tol is None else tol
    # the ridge arc's chords take their share of the tolerance, the revolution the rest
    rev = tol - circular_spline_arc_bound(d, tol)
    return trimesh.creation.revolve(closed, sections=revolution_sections(float(prof[:, 0].max()), rev))


#: The share of the chord tolerance the sealed drive's ridge arc takes (its chords' sagitta).
RIDGE_ARC_SHARE = 0.25


def circular_spline_arc_bound(d: HarmonicDesign, tol: float) -> float:
    """Bound (mm) of the circular spline profile's chord error on an arc at chord tolerance
    ``tol`` (mm): the sealed drive's ridge (:data:`RIDGE_ARC_SHARE` of it), 0 for the straight
    cone walls of the other arrangements."""
    return RIDGE_ARC_SHARE * tol if d.drive.arrangement == "sealed" else 0.0


def cone_start(d: HarmonicDesign, a: float) -> float:
    """x (mm, working section) where the circular spline's cone wall starts at position a:
    a in the radial drives; the end face's ring keeps its radial place
    (:func:`face_reference_position`) and moves along the axis."""
    return face_reference_position(d) if d.arrangement.is_disc else a


def flexspline_profile(d: HarmonicDesign, tol: float | None = None) -> np.ndarray:
    """Closed (rho, z) polygon of the flexspline's half section in the drive frame of the
    design's arrangement (:mod:`prs_geom.harmonic.arrangement`), counter-clockwise. Radial
    inner wave: (0, 0), (ro, 0), the contact arc from the outer to the inner wall, (ri, t),
    (0, t). Radial outer wave: the wall and arc mirrored about the neutral layer, the cup
    bottom joined on the outer wall. End face: the disc from its clamp at r0 round the rim
    arc and back (no point on the axis). ``tol``: chord tolerance (mm; default the
    design's), half of it for the arc's chords."""
    arr = d.arrangement
    f = d.flexspline
    r0, t = f.neutral_radius_mm, f.wall_thickness_mm
    if arr.kind == "sealed":
        # the conical cup: walls t / 2 either side of the neutral line from A at alpha_f
        off, slope, L = 0.5 * t / math.cos(d.alpha), math.tan(d.alpha), f.length_mm
        return np.array([[0.0, 0.0], [r0 + off, 0.0], [r0 + off + L * slope, L], [r0 - off + L * slope, L],
                         [r0 - off + t * slope, t], [0.0, t]])
    sec = section_profile(d, tol)
    if arr.kind == "radial_inner":
        return sec
    body = sec[1:-1]                                  # (r, x): (ro, 0), arc ..., (ri, t)
    rho, z = arr.to_drive(body[:, 1], body[:, 0])
    if arr.kind == "radial_outer":
        wall = np.column_stack([rho, z])[::-1]        # mirrored and reversed: counter-clockwise again
        wall[0] = (r0 + 0.5 * t, 0.0)                 # the outer wall runs down to the bottom
        wall[-1] = (r0 - 0.5 * t, t)
        return np.concatenate([[[0.0, 0.0]], wall, [[0.0, t]]])
    loop = np.column_stack([rho, z])
    loop[-1] = (r0, -0.5 * t)                         # the disc's clamp face at r0
    return loop[::-1].copy()


def section_profile(d: HarmonicDesign, tol: float | None = None) -> np.ndarray:
    """Closed (r, x) polygon of the working section's cup (the radial inner-wave drive's
    half section, x from the clamp A), counter-clockwise: (0, 0), (ro, 0), the contact arc
    from the outer to the inner wall, (ri, t), (0, t). ``tol``: chord tolerance (mm; default
    the design's), half of it for the arc's chords."""
    f = d.flexspline
    tol = d.mesh.chord_tolerance_mm if tol is None else tol
    r0, t, rs, cs = f.neutral_radius_mm, f.wall_thickness_mm, f.arc_radius_mm, f.arc_centre_offset_mm
    ro, ri = r0 + 0.5 * t, r0 - 0.5 * t
    cr, cz = r0 - cs, d.x_s
    if cr + rs <= ro:
        raise ValueError("the contact arc does not bulge beyond the outer wall")
    # arc from the outer wall (lower junction) over the bulge to the inner wall (upper junction)
    th0 = -math.acos((ro - cr) / rs)              # below the centre, on the outer wall
    th1 = math.acos((ri - cr) / rs) if abs(ri - cr) < rs else math.pi / 2
    dth = 2 * math.acos(1 - 0.5 * tol / rs)   # half the tolerance for the arc chords
    th = np.linspace(th0, th1, max(8, int(math.ceil((th1 - th0) / dth)) + 1))
    arc = np.column_stack([cr + rs * np.cos(th), cz + rs * np.sin(th)])
    pts = [[0.0, 0.0], [ro, 0.0], *arc.tolist(), [ri, t], [0.0, t]]
    return np.array(pts)


def circular_spline_profile(d: HarmonicDesign) -> np.ndarray:
    """(rho, z) corners of the ring's half section in its own frame (mm), counter-clockwise.
    Radial drives: the section's ring (bore small end, outer radius at both ends, bore big
    end) with its small end at z = 0, mirrored about the neutral layer for the outer wave.
    End face: the section's ring at the reference position :func:`face_reference_position`
    turned into the drive (a ring whose conical face looks at the disc's rim)."""
    c = d.circular_spline
    arr = d.arrangement
    if arr.kind == "sealed":
        return _ridged_ring(d)
    ring = np.array([[c.bore_small_radius_mm, 0.0], [c.outer_radius_mm, 0.0],
                     [c.outer_radius_mm, c.bore_length_mm], [c.bore_large_radius_mm, c.bore_length_mm]])
    if arr.kind == "radial_inner":
        return ring
    x0 = face_reference_position(d) if arr.is_disc else 0.0
    rho, z = arr.to_drive(ring[:, 1] + x0, ring[:, 0])
    return np.column_stack([rho, z])[::-1].copy()


def _ridged_ring(d: HarmonicDesign) -> np.ndarray:
    """The sealed drive's circular spline (own frame, mm): a ring with a cylindrical bore
    (bore_small_radius_mm) over 0 .. H whose middle carries the working arc as a ridge (centre
    at z = H / 2, radius arc_centre_radius_mm), counter-clockwise; the arc's chords within
    :data:`RIDGE_ARC_SHARE` of the chord tolerance."""
    c = d.circular_spline
    H, b, rs, rc = c.bore_length_mm, c.bore_small_radius_mm, c.arc_radius_mm, c.arc_centre_radius_mm
    half = math.acos((rc - b) / rs)                  # the arc's angle either side of the axis's normal
    dth = 2 * math.acos(1 - RIDGE_ARC_SHARE * d.mesh.chord_tolerance_mm / rs)
    th = np.linspace(half, -half, max(8, int(math.ceil(2 * half / dth)) + 1))
    # from the ridge's upper end (z > H/2) down to its lower end, innermost point at th = 0
    arc = np.column_stack([rc - rs * np.cos(th), 0.5 * H + rs * np.sin(th)])
    return np.concatenate([[[b, 0.0], [c.outer_radius_mm, 0.0], [c.outer_radius_mm, H], [b, H]], arc])


def face_reference_position(d: HarmonicDesign) -> float:
    """The end face's ring: the section position a (mm) at which its own frame is the drive
    frame; at position a it is moved along the axis by
    :meth:`~prs_geom.harmonic.arrangement.Arrangement.face_travel` (the middle of the range)."""
    return default_position(d)


def circular_spline_placement(d: HarmonicDesign, a: float) -> float:
    """Axial placement (mm) of the circular spline's own frame at position a: a for the
    radial drives, the face travel from :func:`face_reference_position` for the end face."""
    if d.arrangement.is_disc:
        return float(d.arrangement.face_travel(a, face_reference_position(d), math.tan(d.alpha)))
    if d.drive.arrangement == "sealed":
        return float(a) - 0.5 * d.circular_spline.bore_length_mm
    return float(a)


def flexspline_mesh(d: HarmonicDesign) -> trimesh.Trimesh:
    """The undeformed cup (own frame, bottom at z = 0, mm): the profile revolved with half the
    chord tolerance as sagitta (the arc's chords take the other half)."""
    prof = flexspline_profile(d)
    # trimesh.revolve wants a line that is closed or touches the axis: the cup touches it,
    # the end face's disc is closed here
    if d.arrangement.is_disc:
        prof = np.concatenate([prof, prof[:1]])
    return trimesh.creation.revolve(prof, sections=revolution_sections(float(prof[:, 0].max()),
                                                                       0.5 * d.mesh.chord_tolerance_mm))


# --------------------------------------------------------------------------- deformation
def default_position(d: HarmonicDesign) -> float:
    """The position a (mm) the assembly is placed at by default: the middle of the range."""
    return 0.5 * (d.positions.min_mm + d.positions.max_mm)


def meridian_tilt(beta_a: float, theta: ArrayLike) -> NDArray[np.float64]:
    """Tilt (rad) of the meridian at polar angle ``theta`` (rad): beta(a) cos(2 theta)."""
    return beta_a * np.cos(2.0 * np.asarray(theta, dtype=np.float64))


def tilt_meridian(d: HarmonicDesign, r: ArrayLike, z: ArrayLike,
                  beta: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(r', z') (mm) of meridian points (r, z) (mm) turned by ``beta`` (rad, positive =
    the open end outward) about the bottom point A = (r0, 0); broadcasts."""
    r = np.asarray(r, dtype=np.float64)
    z = np.asarray(z, dtype=np.float64)
    beta = np.asarray(beta, dtype=np.float64)
    r0 = d.flexspline.neutral_radius_mm
    c, s = np.cos(beta), np.sin(beta)
    return r0 + (r - r0) * c + z * s, -(r - r0) * s + z * c


def deform(d: HarmonicDesign, r: ArrayLike, z: ArrayLike, theta: ArrayLike, beta_a: float) -> NDArray[np.float64]:
    """Assembly-frame points (..., 3) (mm) of undeformed flexspline points given by their
    drive-meridian coordinates (rho, z) (mm) and polar angle theta (rad); broadcasts. The
    turn is the section's (:func:`tilt_meridian`), carried into the drive by the
    arrangement's map."""
    theta = np.asarray(theta, dtype=np.float64)
    arr = d.arrangement
    x, rs = arr.to_section(r, z)
    rt, xt = tilt_meridian(d, rs, x, meridian_tilt(beta_a, theta))
    rr, zz = arr.to_drive(xt, rt)
    return np.stack(np.broadcast_arrays(rr * np.cos(theta), rr * np.sin(theta), zz), axis=-1)


def inner_wall_radius(d: HarmonicDesign, beta: ArrayLike, z: ArrayLike) -> NDArray[np.float64]:
    """Radius (mm) of the tilted inner wall line (undeformed radius r0 - t/2) at height z
    (mm, assembly frame) in a meridian tilted by ``beta`` (rad); broadcasts."""
    f = d.flexspline
    # the sealed drive's wall is a cone of half-angle alpha_f: its line turns to alpha_f + beta
    ang = np.asarray(beta, dtype=np.float64) + (d.alpha if d.drive.arrangement == "sealed" else 0.0)
    z = np.asarray(z, dtype=np.float64)
    h = 0.5 * f.wall_thickness_mm
    # the wall's foot (r0 - t/2, 0) turns to (r0 - h cos b, h sin b); the line runs along (sin b, cos b)
    return f.neutral_radius_mm - h * np.cos(ang) + (z - h * np.sin(ang)) * np.tan(ang)


# --------------------------------------------------------------------------- wave generator
@dataclass(frozen=True)
class WaveGenerator:
    """The wave generator: an elliptical disc about the z axis (assembly frame, mm).

    Attributes
    ----------
    semi_axis_x_mm, semi_axis_y_mm : float
        Semi-axes along x (the wave's major axis, theta = 0) and y (mm).
    z_min_mm, z_max_mm : float
        Axial band the disc occupies, from the flexspline bottom (mm).
    """

    semi_axis_x_mm: float
    semi_axis_y_mm: float
    z_min_mm: float
    z_max_mm: float

    def __post_init__(self) -> None:
        for f in ("semi_axis_x_mm", "semi_axis_y_mm", "z_min_mm", "z_max_mm"):
            v = float(getattr(self, f))
            if not math.isfinite(v):
                raise ValueError(f"wave generator {f} = {v}: must be finite")
            object.__setattr__(self, f, v)
        if self.semi_axis_x_mm <= 0 or self.semi_axis_y_mm <= 0:
            raise ValueError("wave generator semi-axes must be > 0")
        if not self.z_max_mm > self.z_min_mm >= 0:
            raise ValueError(f"wave generator band [{self.z_min_mm}, {self.z_max_mm}] mm: need 0 <= z_min < z_max")

    @property
    def width_mm(self) -> float:
        """Axial width of the disc (mm)."""
        return self.z_max_mm - self.z_min_mm

    def radius(self, theta: ArrayLike) -> NDArray[np.float64]:
        """Polar radius (mm) of the ellipse at angle theta (rad) from +x."""
        t = np.asarray(theta, dtype=np.float64)
        a, b = self.semi_axis_x_mm, self.semi_axis_y_mm
        return a * b / np.hypot(b * np.cos(t), a * np.sin(t))


def _inner_wall_top(d: HarmonicDesign) -> tuple[float, float]:
    """(r, z) (mm) of the undeformed profile's inner-wall top: where the contact arc meets
    the inner wall (the third last point of :func:`section_profile`)."""
    if d.drive.arrangement == "sealed":
        p = flexspline_profile(d)
        return float(p[-3, 0]), float(p[-3, 1])
    p = section_profile(d)
    return float(p[-3, 0]), float(p[-3, 1])


def wave_generator(d: HarmonicDesign, a: float) -> WaveGenerator:
    """The wave generator that tilts the flexspline to the model's state at position a (mm)
    (the rule in the module docstring). Raises DesignError where the band does not fit on
    the straight inner wall."""
    f = d.flexspline
    t = f.wall_thickness_mm
    beta = float(tilt_angle(d, a))
    r_j, z_j = _inner_wall_top(d)
    # under the contact: the arc's centre station, or the sealed drive's contact on its cone
    z_mid, arc = d.x_s, f.arc_radius_mm
    if d.drive.arrangement == "sealed":
        z_mid, arc = float(drive_contact(d, a).contact_z_mm), d.circular_spline.arc_radius_mm
    h = min(0.5 * arc, 0.9 * (z_j - z_mid), 0.9 * (z_mid - t))
    if not h > 0:
        raise DesignError("flexspline.arc_radius_mm", f.arc_radius_mm,
                          "leaves no straight inner wall under the contact arc for the wave generator")
    z1, z2 = z_mid - h, z_mid + h
    # the band must stay on the straight inner wall in every meridian once tilted (|tilt| <= |beta|)
    b = np.array([-abs(beta), abs(beta)])
    top = tilt_meridian(d, r_j, z_j, b)[1].min()
    floor = tilt_meridian(d, f.neutral_radius_mm - 0.5 * t, t, b)[1].max()
    if not (floor < z1 and z2 < top):
        raise DesignError("flexspline.arc_radius_mm", f.arc_radius_mm,
                          f"the wave generator band [{z1:.4g}, {z2:.4g}] mm leaves the inner wall "
                          f"[{floor:.4g}, {top:.4g}] mm")
    # smallest wall radius over the band: the wall is straight, so at one of the band's edges
    ax = float(np.min(inner_wall_radius(d, beta, [z1, z2])))
    ay = float(np.min(inner_wall_radius(d, -beta, [z1, z2])))
    return WaveGenerator(ax, ay, z1, z2)


def wave_generator_mesh(wg: WaveGenerator, tol: float) -> trimesh.Trimesh:
    """The disc (own frame: z = 0 at its lower face, mm) as a closed prism over the ellipse
    sampled at uniform parametric angle, vertices on the ellipse (an inscribed polygon) and
    one at each axis end for the fans. The vertex count is a multiple of 4, so the four
    contact lines (theta = 0, pi/2, pi, 3 pi/2) are vertices."""
    a, b = wg.semi_axis_x_mm, wg.semi_axis_y_mm
    # parametric sampling: sagitta <= (dt^2 / 8) max(a, b), as for a circle of the larger radius
    n = 4 * math.ceil(revolution_sections(max(a, b), tol) / 4)
    t = 2 * math.pi * np.arange(n) / n
    ring = np.column_stack([a * np.cos(t), b * np.sin(t)])
    V = np.concatenate([np.column_stack([ring, np.zeros(n)]), np.column_stack([ring, np.full(n, wg.width_mm)]),
                        [[0.0, 0.0, 0.0], [0.0, 0.0, wg.width_mm]]])
    k = np.arange(n)
    k1 = (k + 1) % n
    lo, hi, cb, ct = k, n + k, 2 * n, 2 * n + 1
    hi1 = n + k1
    faces = np.concatenate([
        np.column_stack([lo, k1, hi1]), np.column_stack([lo, hi1, hi]),        # side, outward
        np.column_stack([np.full(n, cb), k1, lo]),                            # bottom (-z)
        np.column_stack([np.full(n, ct), hi, hi1]),                           # top (+z)
    ])
    return trimesh.Trimesh(V, faces, process=False)


def wave_generator_deviation(wg: WaveGenerator, mesh: trimesh.Trimesh) -> float:
    """Largest radial distance (mm) from the side edges' midpoints (the chords) to the
    ellipse: the polygon's chord error (its vertices lie on the ellipse)."""
    V = np.asarray(mesh.vertices)
    n = (len(V) - 2) // 2
    ring = V[:n, :2]
    mid = 0.5 * (ring + np.roll(ring, -1, axis=0))
    phi = np.arctan2(mid[:, 1], mid[:, 0])
    return float(np.max(wg.radius(phi) - np.hypot(mid[:, 0], mid[:, 1])))


#: Thickness of the outer-wave and end-face generators' ring across the section (fraction of r0).
GENERATOR_THICKNESS = 0.2


def mapped_generator_mesh(d: HarmonicDesign, wg: WaveGenerator, tol: float) -> tuple[trimesh.Trimesh, float]:
    """The wave generator of the outer-wave and end-face drives (assembly frame, mm): in each
    meridian the section's generator (:func:`wave_generator`, the band x_s +- h under the
    contact, from the ellipse radius at theta inward by ``GENERATOR_THICKNESS`` r0) carried
    into the drive by the arrangement's map: a ring outside the flexspline (outer wave), a
    face cam under the disc's rim (end face). Its working face is placed a chord's sagitta
    further from the flexspline, so that the chords between meridians stay off it. Returns
    (mesh, the sagitta bound, mm)."""
    arr = d.arrangement
    thick = GENERATOR_THICKNESS * d.flexspline.neutral_radius_mm
    far = float(np.max(np.abs(arr.to_drive(np.array([wg.z_min_mm, wg.z_max_mm]),
                                           np.array([wg.semi_axis_x_mm, wg.semi_axis_y_mm]))[0])))
    n = 4 * math.ceil(revolution_sections(far + thick, 0.5 * tol) / 4)
    theta = 2 * math.pi * np.arange(n) / n
    sag = (far + thick) * (1.0 - math.cos(math.pi / n))
    eps = wg.radius(theta) - sag
    # section corners (x, r) per meridian: working face at eps, back face thick further in
    x = np.array([wg.z_min_mm, wg.z_max_mm, wg.z_max_mm, wg.z_min_mm])[:, None] + 0.0 * theta[None, :]
    r = np.stack([eps - thick, eps - thick, eps, eps])
    rho, z = arr.to_drive(x, r)
    loop = np.column_stack([rho[:, 0], z[:, 0]])
    area = 0.5 * float(np.sum(loop[:, 0] * np.roll(loop[:, 1], -1) - np.roll(loop[:, 0], -1) * loop[:, 1]))
    if area < 0:                        # the map reversed the loop: keep it counter-clockwise
        rho, z = rho[::-1], z[::-1]
    V = np.stack([rho * np.cos(theta), rho * np.sin(theta), z], axis=-1).reshape(-1, 3)
    faces, _, _ = _strip_faces(4, n, closed=True, offset=0)
    return trimesh.Trimesh(V, faces, process=False), sag


def mapped_generator_deviation(d: HarmonicDesign, wg: WaveGenerator, mesh: trimesh.Trimesh) -> float:
    """Largest distance (mm) of the mapped generator's working face (:func:`mapped_generator_mesh`)
    from the section's generator surface, sampled at the midpoints of its edges between
    meridians: the placement offset plus the chord error, across the section (the working
    face is the one at the ellipse radius, r in the section)."""
    V = np.asarray(mesh.vertices).reshape(4, -1, 3)
    n = V.shape[1]
    mid = 0.5 * (V + np.roll(V, -1, axis=1))
    theta = 2 * math.pi * (np.arange(n) + 0.5) / n
    rho = mid[..., 0] * np.cos(theta) + mid[..., 1] * np.sin(theta)
    _, r = d.arrangement.to_section(rho, mid[..., 2])
    gap = np.abs(wg.radius(theta)[None, :] - r)
    return float(np.max(gap[np.argsort(gap.mean(axis=1))[:2]]))


# --------------------------------------------------------------------------- flexspline
@dataclass(frozen=True, eq=False)
class DeformedFlexspline:
    """The flexspline at position a: its mesh (assembly frame, mm) and how it was made.

    Attributes
    ----------
    mesh : trimesh.Trimesh
        Closed mesh; for a cup vertex 0 and 1 are the axis points of the bottom's two faces,
        then ``profile`` point j at polar angle ``theta[k]`` is vertex ``2 + j n + k`` (a
        disc, ``closed``: ``j n + k``).
    profile : ndarray (m, 2)
        Undeformed (rho, z) profile points off the axis, drive frame, in the order of
        :func:`flexspline_profile` (straight walls subdivided for the twist bound), mm.
    theta : ndarray (n,)
        Polar angles of the meridians (rad), ``2 pi k / n``; n is a multiple of 4.
    beta_rad : float
        Tilt beta(a) on the major axis (rad).
    arc_chord_bound_mm : float
        Bound of the profile polygon's chord error on the contact arc (mm), half the
        tolerance (:func:`flexspline_profile`).
    closed : bool
        The profile is a loop (the end face's disc) instead of a cup closed at the axis.
    """

    mesh: trimesh.Trimesh
    profile: NDArray[np.float64]
    theta: NDArray[np.float64]
    beta_rad: float
    arc_chord_bound_mm: float
    closed: bool = False

    def meridian(self, k: int) -> NDArray[np.float64]:
        """(rho', z') (mm) of the closed deformed meridian polygon at ``theta[k]`` in the drive
        frame: the cup's with its axis points (bottom axis point first), the disc's loop with
        its first point repeated at the end."""
        V = np.asarray(self.mesh.vertices)
        n = len(self.theta)
        ring = V[(0 if self.closed else 2) + np.arange(len(self.profile)) * n + k]
        c, s = math.cos(self.theta[k]), math.sin(self.theta[k])
        # radial coordinate in the meridian's own direction (signed, so no abs() hides a flip)
        rz = np.column_stack([ring[:, 0] * c + ring[:, 1] * s, ring[:, 2]])
        if self.closed:
            return np.concatenate([rz, rz[:1]])
        return np.concatenate([[[0.0, V[0, 2]]], rz, [[0.0, V[1, 2]]]])


def _strip_faces(m: int, n: int, closed: bool = False,
                 offset: int = 2) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
    """Faces of the wall strips between profile points j, j+1 and meridians k, k+1, with
    each corner's profile index and unwrapped meridian index (for the deviation check).
    ``closed``: the profile is a loop (its last point joins the first). Vertex of profile
    point j at meridian k: ``offset + j n + k``."""
    j, k = np.meshgrid(np.arange(m if closed else m - 1), np.arange(n), indexing="ij")
    j, k = j.ravel(), k.ravel()
    corners_j = np.concatenate([np.column_stack([j, j, j + 1]), np.column_stack([j, j + 1, j + 1])])
    corners_k = np.concatenate([np.column_stack([k, k + 1, k + 1]), np.column_stack([k, k + 1, k])])
    faces = offset + (corners_j % m) * n + corners_k % n
    return faces, corners_j, corners_k


def deformed_flexspline(d: HarmonicDesign, a: float, tol: float | None = None,
                        beta: float | None = None) -> DeformedFlexspline:
    """The flexspline deformed by the wave generator at position a (mm), meshed watertight
    at chord tolerance ``tol`` (mm; default the design's), in the drive frame of the
    design's arrangement. ``beta`` (rad) overrides the model's tilt (0: the undeformed
    flexspline with the same vertices, for measurements that follow a material point).

    Error budget: tol / 2 for the contact arc's chords (the profile, as for the undeformed
    mesh), tol / 4 for the chords around the circumference (sections from the largest
    curvature of the deformed section, radius + 4 x the wave amplitude), tol / 4 for the
    twist of a wall quad between two meridians of different tilt (bilinear patch:
    deviation = segment length x tilt difference / 4, so the straight walls are cut into
    segments of at most tol / (2 |beta| dtheta)). :func:`flexspline_deviation` measures it.
    """
    tol = d.mesh.chord_tolerance_mm if tol is None else float(tol)
    beta = float(tilt_angle(d, a)) if beta is None else float(beta)
    prof = flexspline_profile(d, tol)
    disc = d.arrangement.is_disc
    # the cup's two axis points, (0, 0) first and (0, t) last, close it by fans
    body = prof if disc else prof[1:-1]
    # circumferential sections: wave amplitude w at each profile point
    up = deform(d, body[:, 0], body[:, 1], 0.0, abs(beta))
    dn = deform(d, body[:, 0], body[:, 1], 0.5 * math.pi, abs(beta))
    dn = np.column_stack([dn[:, 1], dn[:, 0], dn[:, 2]])   # the minor axis's meridian turned onto x
    # the larger of the radial (cup) and the axial (disc) wave
    w = 0.5 * float(np.max(np.abs(up - dn)[:, [0, 2]]))
    r_eff = float(np.max(np.hypot(up[:, 0], up[:, 1]))) + 4.0 * w
    n = 4 * math.ceil(revolution_sections(r_eff, 0.25 * tol) / 4)
    dtheta = 2 * math.pi / n
    seg = math.inf if beta == 0 else tol / (2.0 * abs(beta) * dtheta)
    # subdivide the long straight segments (walls) so that each is at most `seg` long
    ends = np.concatenate([body[1:], body[:1]]) if disc else body[1:]
    pts = [body[:1]]
    for p, q in zip(body[:len(ends)], ends):
        parts = max(1, math.ceil(float(np.linalg.norm(q - p)) / seg))
        u = np.arange(1, parts + 1)[:, None] / parts
        pts.append(p + u * (q - p))
    profile = np.concatenate(pts)[:-1] if disc else np.concatenate(pts)
    m = len(profile)
    theta = dtheta * np.arange(n)
    ring = deform(d, profile[:, 0][:, None], profile[:, 1][:, None], theta[None, :], beta).reshape(-1, 3)
    if disc:
        strips, _, _ = _strip_faces(m, n, closed=True, offset=0)
        mesh = trimesh.Trimesh(ring, strips, process=False)
        return DeformedFlexspline(mesh, profile, theta, beta, 0.5 * tol, closed=True)
    A0, A1 = [0.0, 0.0, 0.0], [0.0, 0.0, float(prof[-1, 1])]
    V = np.concatenate([[A0, A1], ring])
    strips, _, _ = _strip_faces(m, n)
    k = np.arange(n)
    bottom = np.column_stack([np.zeros(n, np.int64), 2 + (k + 1) % n, 2 + k])
    last = 2 + (m - 1) * n
    top = np.column_stack([last + k, last + (k + 1) % n, np.ones(n, np.int64)])
    F = np.concatenate([bottom, strips, top])
    mesh = trimesh.Trimesh(V, F, process=False)
    return DeformedFlexspline(mesh, profile, theta, beta, 0.5 * tol)


def flexspline_deviation(d: HarmonicDesign, fs: DeformedFlexspline) -> float:
    """Largest distance (mm) between the wall faces and the deformed profile polygon's
    surface, sampled at each face's centroid and edge midpoints: the mesh point against
    the exact image (:func:`deform`) of the same parameters (profile point, polar angle),
    across the surface (along its normal there, from central differences; the offset along
    it is a parameter shift, and its second-order share, offset^2 / (2 x the surface's
    radius of curvature), stays below 1e-3 mm at these chord tolerances).
    This is the circumferential chord and twist error; the arc's chord error is bounded
    separately (``arc_chord_bound_mm``). The bottom fans are exact by construction."""
    m, n = len(fs.profile), len(fs.theta)
    faces, cj, ck = _strip_faces(m, n, closed=fs.closed, offset=0 if fs.closed else 2)
    V = np.asarray(fs.mesh.vertices)
    dtheta = 2 * math.pi / n
    worst = 0.0
    weights = np.array([[1, 1, 1], [1, 1, 0], [0, 1, 1], [1, 0, 1]], float)
    weights /= weights.sum(axis=1, keepdims=True)
    # each face's segment direction in the profile, for the surface's normal
    seg = fs.profile[(cj[:, 1] + (cj[:, 1] == cj[:, 0])) % m] - fs.profile[cj[:, 0] % m]
    seg = seg / np.linalg.norm(seg, axis=1, keepdims=True)
    h = 1e-4
    for wgt in weights:                     # four sample points per face, each vectorised
        mesh_pt = np.einsum("c,fcd->fd", wgt, V[faces])
        rz = np.einsum("c,fcd->fd", wgt, fs.profile[cj % m])
        th = (ck * dtheta) @ wgt
        exact = deform(d, rz[:, 0], rz[:, 1], th, fs.beta_rad)
        # the offset across the exact surface (along it is a shift of parameters, not an
        # error: a radial segment's chord centroid sits at other (rho, theta) in the surface)
        d_s = deform(d, rz[:, 0] + h * seg[:, 0], rz[:, 1] + h * seg[:, 1], th, fs.beta_rad) - \
            deform(d, rz[:, 0] - h * seg[:, 0], rz[:, 1] - h * seg[:, 1], th, fs.beta_rad)
        d_t = deform(d, rz[:, 0], rz[:, 1], th + h, fs.beta_rad) - deform(d, rz[:, 0], rz[:, 1], th - h, fs.beta_rad)
        normal = np.cross(d_s, d_t)
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        worst = max(worst, float(np.max(np.abs(np.einsum("fd,fd->f", mesh_pt - exact, normal)))))
    return worst


# --------------------------------------------------------------------------- assembly
def _translation(z: float) -> NDArray[np.float64]:
    T = np.eye(4)
    T[2, 3] = z
    return T


@dataclass(frozen=True, eq=False)
class HarmonicAssembly:
    """The placed drive at position a.

    Attributes
    ----------
    design : HarmonicDesign
    position_mm : float
        a: the cone's small end from the flexspline bottom (mm).
    beta_rad : float
        Tilt of the flexspline generatrix on the major axis (rad).
    tolerance_mm : float
        Chord tolerance of the meshes (mm).
    wave_generator : WaveGenerator
    flexspline : DeformedFlexspline
    parts : dict
        Part name (:data:`PARTS`) -> (mesh in its own frame, 4x4 rigid placement in the
        assembly frame, mm).
    """

    design: HarmonicDesign
    position_mm: float
    beta_rad: float
    tolerance_mm: float
    wave_generator: WaveGenerator
    flexspline: DeformedFlexspline
    parts: dict[str, tuple[trimesh.Trimesh, NDArray[np.float64]]]

    def placed_vertices(self, name: str) -> NDArray[np.float64]:
        """Vertices (N, 3) of a part in the assembly frame (mm)."""
        mesh, T = self.parts[name]
        V = np.asarray(mesh.vertices, dtype=np.float64)
        return V @ T[:3, :3].T + T[:3, 3]


def build_assembly(d: HarmonicDesign, a: float | None = None, tol: float | None = None) -> HarmonicAssembly:
    """Place the three parts at position ``a`` (mm; default :func:`default_position`) with
    meshes at chord tolerance ``tol`` (mm; default the design's)."""
    a = default_position(d) if a is None else float(a)
    if not d.positions.min_mm <= a <= d.positions.max_mm:
        raise DesignError("position_mm", a, f"must lie in positions.min_mm .. max_mm = "
                                            f"[{d.positions.min_mm}, {d.positions.max_mm}]")
    tol = d.mesh.chord_tolerance_mm if tol is None else float(tol)
    wg = wave_generator(d, a)
    fs = deformed_flexspline(d, a, tol)
    if d.arrangement.generator_is_disc:
        generator = (wave_generator_mesh(wg, tol), _translation(wg.z_min_mm))
    else:
        generator = (mapped_generator_mesh(d, wg, tol)[0], np.eye(4))
    parts = {
        "circular_spline": (circular_spline_mesh(d, tol), _translation(circular_spline_placement(d, a))),
        "flexspline": (fs.mesh, np.eye(4)),
        "wave_generator": generator,
    }
    return HarmonicAssembly(d, a, fs.beta_rad, tol, wg, fs, parts)


# --------------------------------------------------------------------------- checks
def cone_gap(d: HarmonicDesign, rz: ArrayLike, a: float) -> NDArray[np.float64]:
    """Signed distance (mm) of meridian points (..., 2) = (r, z) from the cone line of the
    bore at position a: positive inside the bore (clearance), negative in the ring."""
    rz = np.asarray(rz, dtype=np.float64)
    al = d.alpha
    return (rz[..., 1] - a) * math.sin(al) - (rz[..., 0] - d.circular_spline.bore_small_radius_mm) * math.cos(al)


def arc_cone_clearance(d: HarmonicDesign, a: float, theta: ArrayLike) -> NDArray[np.float64]:
    """Exact clearance (mm) between the contact arc and the cone wall in the meridian at
    theta (rad): distance of the tilted arc centre from the cone line minus r_s. Zero on the
    major axis (the model's tangency). Valid while the arc's nearest point to the line lies
    on the arc (checked)."""
    f = d.flexspline
    beta = meridian_tilt(float(tilt_angle(d, a)), theta)
    if d.drive.arrangement == "sealed":
        return _sealed_clearance(d, a, beta)
    cr, cz = tilt_meridian(d, f.neutral_radius_mm - f.arc_centre_offset_mm, d.x_s, beta)
    prof = section_profile(d)
    r_c, z_c = f.neutral_radius_mm - f.arc_centre_offset_mm, d.x_s
    th0 = math.atan2(prof[2, 1] - z_c, prof[2, 0] - r_c)          # arc start (outer wall junction)
    th1 = math.atan2(prof[-3, 1] - z_c, prof[-3, 0] - r_c)        # arc end (inner wall junction)
    # the nearest point's direction in the untilted arc: -alpha + beta (the tilt turns the arc by -beta)
    foot = -d.alpha + beta
    if np.any(foot < th0) or np.any(foot > th1):
        raise ValueError("the cone's nearest point leaves the contact arc: the clearance formula does not apply")
    return cone_gap(d, np.stack([cr, cz], axis=-1), a) - f.arc_radius_mm


def _sealed_clearance(d: HarmonicDesign, a: float, beta: NDArray[np.float64]) -> NDArray[np.float64]:
    """The sealed drive's exact clearance (mm) between the circular spline's working arc and
    the flexspline's outer cone wall in meridians tilted by ``beta`` (rad): the arc centre's
    distance from the tilted neutral line, minus t / 2 and r_s; valid while the foot of that
    distance lies on the wall (checked)."""
    f, c = d.flexspline, d.circular_spline
    ang = d.alpha + beta
    h = c.arc_centre_radius_mm - f.neutral_radius_mm
    foot = a * np.cos(ang) + h * np.sin(ang)             # along the generatrix from A
    if np.any(foot <= 0) or np.any(foot * np.cos(ang) >= f.length_mm):
        raise ValueError("the arc's nearest point leaves the cone wall: the clearance formula does not apply")
    return -a * np.sin(ang) + h * np.cos(ang) - 0.5 * f.wall_thickness_mm - c.arc_radius_mm


def _contact_gaps(d: HarmonicDesign, fs: DeformedFlexspline, a: float) -> list[float]:
    """Smallest signed gap (mm) of the flexspline mesh's major-axis meridians (theta = 0 and
    pi) from the circular spline's working surface: the cone line within the ring (radial and
    end-face drives) or the working arc (sealed drive: distance from its centre to the
    meridian's segments minus r_s)."""
    n = len(fs.theta)
    c = d.circular_spline
    gaps = []
    for k in (0, n // 2):                   # theta = 0 and pi: the wave's two lobes
        if d.drive.arrangement == "sealed":
            mer = fs.meridian(k)
            centre = np.array([c.arc_centre_radius_mm, a])
            dist = point_segment_distance(centre, mer[:-1], mer[1:])
            gaps.append(float(np.min(dist)) - c.arc_radius_mm)
            continue
        x_lo = cone_start(d, a)
        mer = _section_meridian(d, fs.meridian(k))
        inside = (mer[:, 1] >= x_lo) & (mer[:, 1] <= x_lo + c.bore_length_mm)
        gaps.append(float(np.min(cone_gap(d, mer[inside], a))))
    return gaps


def _section_meridian(d: HarmonicDesign, mer: NDArray[np.float64]) -> NDArray[np.float64]:
    """(r, x) in the working section of drive-meridian points (rho, z) (mm), in the column
    order :func:`cone_gap` takes."""
    x, r = d.arrangement.to_section(mer[:, 0], mer[:, 1])
    return np.column_stack([r, x])


def _manifold(V: NDArray[np.float64], F: NDArray[np.int64]):
    import manifold3d

    m = manifold3d.Manifold(manifold3d.Mesh64(np.ascontiguousarray(V, dtype=np.float64),
                                              np.ascontiguousarray(F, dtype=np.uint64)))
    if m.status() != manifold3d.Error.NoError:
        raise ValueError(f"mesh is not a valid manifold solid: {m.status()}")
    return m


def assembly_checks(asm: HarmonicAssembly) -> dict[str, Any]:
    """Contact and interference checks of the placed assembly (all lengths mm).

    * ``contact_gap_mm``: smallest signed distance of the flexspline mesh's major-axis
      meridians (theta = 0 and pi, which are mesh meridians) from the cone line within the
      bore; the exact arc touches it, so the mesh value is the arc polygon's chord error
      (0 .. tol / 2; negative would be interference).
    * ``contact_offset_mm``: distance of the model's contact point
      (:func:`~prs_geom.harmonic.model.contact_point`) from the mesh's theta = 0 meridian.
    * exact clearances: arc to cone on the minor axis (and its minimum over theta), wave
      generator to inner wall (minimum and maximum over theta).
    * ``interference``: manifold3d intersection solid of each part pair; volume V, surface
      area A, mean thickness 2 V / A; an overlap thicker than 2 x tol is interference (the
      two facetted surfaces may each lie up to tol off the exact one where parts touch).
    """
    d, a, tol = asm.design, asm.position_mm, asm.tolerance_mm
    fs = asm.flexspline
    gaps = _contact_gaps(d, fs, a)
    px, pr = contact_point(d, a)
    meridian = _section_meridian(d, fs.meridian(0))
    offset = float(point_segment_distance(np.array([pr, px]), meridian[:-1], meridian[1:]).min())
    theta = np.linspace(0.0, 2 * math.pi, 721)
    arc_gap = arc_cone_clearance(d, a, theta)
    wg = asm.wave_generator
    wall = np.minimum(inner_wall_radius(d, meridian_tilt(asm.beta_rad, theta), wg.z_min_mm),
                      inner_wall_radius(d, meridian_tilt(asm.beta_rad, theta), wg.z_max_mm))
    wg_gap = wall - wg.radius(theta)
    solids = {name: _manifold(asm.placed_vertices(name), np.asarray(mesh.faces)) for name, (mesh, _) in
              asm.parts.items()}
    pairs = []
    for i, p in enumerate(PARTS):
        for q in PARTS[i + 1:]:
            inter = solids[p] ^ solids[q]
            vol = max(0.0, float(inter.volume()))
            area = float(inter.surface_area())
            thick = 2.0 * vol / area if area > 0 else 0.0
            status = "clear" if vol == 0.0 else ("touching" if thick <= 2.0 * tol else "interference")
            pairs.append({"pair": [p, q], "volume_mm3": vol, "mean_thickness_mm": thick, "status": status})
    found = any(p["status"] == "interference" for p in pairs)
    warnings = []
    if min(gaps) < -tol:
        warnings.append(f"flexspline-cone contact gap {min(gaps):.3g} mm is below -{tol:g} mm (interference)")
    if min(gaps) > tol:
        warnings.append(f"flexspline-cone contact gap {min(gaps):.3g} mm exceeds the chord tolerance {tol:g} mm")
    if offset > tol:
        warnings.append(f"the mesh misses the model's contact point by {offset:.3g} mm (> {tol:g} mm)")
    warnings += [f"{' - '.join(p['pair'])} overlap {p['mean_thickness_mm']:.3g} mm thick (> {2 * tol:g} mm)"
                 for p in pairs if p["status"] == "interference"]
    return {
        "position_mm": a,
        "chord_tolerance_mm": tol,
        "contact_point_mm": {"x": px, "r": pr},
        "contact_gap_mm": min(gaps),
        "contact_gap_per_lobe_mm": gaps,
        "contact_offset_mm": offset,
        "arc_cone_clearance_minor_axis_mm": float(arc_cone_clearance(d, a, math.pi / 2)),
        "arc_cone_clearance_min_mm": float(np.min(arc_gap)),
        "wave_generator_clearance_min_mm": float(np.min(wg_gap)),
        "wave_generator_clearance_max_mm": float(np.max(wg_gap)),
        "measured_ratio": measured_ratio(asm),
        "interference": {"found": found, "pairs": pairs,
                         "rule": "overlap thicker than 2 x chord tolerance (mean thickness 2V/A) is interference"},
        "warnings": warnings,
    }


#: Samples around the circumference of each measured circle (:func:`measured_ratio`).
RATIO_SAMPLES = 24


def _mean_radius(mesh: trimesh.Trimesh, rho: float, z: float) -> float:
    """Mean distance from the axis (mm) of the mesh's points nearest to the circle (rho, z)
    (mm) in ``RATIO_SAMPLES`` meridians: each meridian is the mesh cut by the half-plane at
    that angle (trimesh.intersections.mesh_plane), the nearest point of its segments to
    (rho, z) taken; the mesh's radius at that circle."""
    out = []
    for th in 2 * math.pi * (np.arange(RATIO_SAMPLES) + 0.25) / RATIO_SAMPLES:
        u = np.array([math.cos(th), math.sin(th), 0.0])
        seg = trimesh.intersections.mesh_plane(mesh, np.array([-u[1], u[0], 0.0]), np.zeros(3))
        seg = seg[(seg[:, :, :2] @ u[:2]).min(axis=1) > 0]          # the half-plane at th only
        p = np.stack([seg @ u, seg[:, :, 2]], axis=-1)              # (rho, z) segment ends
        e = p[:, 1] - p[:, 0]
        q = np.array([rho, z])
        t = np.clip(np.einsum("sd,sd->s", q - p[:, 0], e) / np.maximum(np.einsum("sd,sd->s", e, e), 1e-300), 0, 1)
        near = p[:, 0] + t[:, None] * e
        out.append(float(near[np.argmin(np.linalg.norm(near - q, axis=1)), 0]))
    return float(np.mean(out))


def measured_ratio(asm: HarmonicAssembly) -> dict[str, Any]:
    """The ratio measured on the placed meshes: the circumference difference at the contact
    taken from the circular spline's placed mesh (its radius at the contact circle) and the
    undeformed flexspline's mesh (its radius at the circle of the contact's material point),
    both as the mean radius of the mesh points nearest those circles
    (:func:`_mean_radius`); the flexspline's rolling radius is the mean of its two wall
    radii half way up the wall (radial drives) or the material circle's (end face). The
    contact's place is the model's (:func:`~prs_geom.harmonic.model.drive_contact`); the
    meshes resolve it when Delta is at least 100 chord tolerances (``resolved``)."""
    d, a, tol = asm.design, asm.position_mm, asm.tolerance_mm
    c = drive_contact(d, a)
    cs_mesh, _ = asm.parts["circular_spline"]
    placed = trimesh.Trimesh(asm.placed_vertices("circular_spline"), np.asarray(cs_mesh.faces), process=False)
    flat = deformed_flexspline(d, a, tol, beta=0.0).mesh
    R = _mean_radius(placed, float(c.contact_rho_mm), float(c.contact_z_mm))
    r = _mean_radius(flat, float(c.material_rho_mm), float(c.material_z_mm))
    f = d.flexspline
    if d.arrangement.is_disc:
        r_f = r
    elif d.drive.arrangement == "sealed":
        # the neutral layer at the material circle: half way between the cone's two walls
        wall = f.wall_thickness_mm / math.cos(d.alpha)
        r_f = 0.5 * (r + _mean_radius(flat, float(c.material_rho_mm) - wall, float(c.material_z_mm)))
    else:
        mid = 0.5 * d.x_s
        r_f = 0.5 * (_mean_radius(flat, f.neutral_radius_mm + f.wall_thickness_mm, mid)
                     + _mean_radius(flat, f.neutral_radius_mm - f.wall_thickness_mm, mid))
    delta = R - r
    model = float(c.ratio)
    measured = abs(r_f / delta)
    return {"position_mm": a, "circular_spline_radius_mm": R, "flexspline_radius_mm": r,
            "rolling_radius_mm": r_f, "radius_difference_mm": delta,
            "model_radius_difference_mm": float(c.radius_difference_mm), "ratio": measured, "model_ratio": model,
            "relative_difference": measured / model - 1.0,
            "resolved": bool(abs(float(c.radius_difference_mm)) >= 100.0 * tol)}


def mesh_rows(asm: HarmonicAssembly) -> list[dict[str, Any]]:
    """Mesh checks of the two new parts (the circular spline's is the existing one):
    triangles, closed, volume, measured deviation plus the arc bound against the tolerance."""
    tol = asm.tolerance_mm
    fs_mesh, _ = asm.parts["flexspline"]
    wg_mesh, _ = asm.parts["wave_generator"]
    rows = []
    d = asm.design
    wg_dev = (wave_generator_deviation(asm.wave_generator, wg_mesh) if d.arrangement.generator_is_disc
              else mapped_generator_deviation(d, asm.wave_generator, wg_mesh))
    for name, mesh, measured, bound in (
            ("flexspline", fs_mesh, flexspline_deviation(d, asm.flexspline), asm.flexspline.arc_chord_bound_mm),
            ("wave_generator", wg_mesh, wg_dev, 0.0)):
        dev = measured + bound
        rows.append({"part": name, "triangles": int(len(mesh.faces)), "watertight": bool(mesh.is_watertight),
                     "volume_mm3": float(mesh.volume), "chord_tolerance_mm": tol,
                     "measured_deviation_mm": measured, "arc_chord_bound_mm": bound, "max_deviation_mm": dev,
                     "warnings": [f"measured deviation {dev:.3g} mm exceeds the chord tolerance {tol:g} mm"]
                     if dev > tol else []})
    return rows


def assembly_summary(asm: HarmonicAssembly) -> dict[str, Any]:
    """The placed assembly as report.json holds it (``assembly``)."""
    d, a = asm.design, asm.position_mm
    st = contact_state(d, a)
    wg = asm.wave_generator
    return {
        "arrangement": d.drive.arrangement,
        "position_mm": a,
        "position_rule": POSITION_RULE,
        "beta_deg": math.degrees(asm.beta_rad),
        # the eccentricity of the wave: the neutral layer's open end (x = L) on the major axis
        "wave_amplitude_mm": float(tilt_meridian(d, d.flexspline.neutral_radius_mm, d.flexspline.length_mm,
                                                 asm.beta_rad)[0]) - d.flexspline.neutral_radius_mm,
        "ratio": float(st["ratio"]),
        "radius_difference_mm": float(st["radius_difference_mm"]),
        "deformation": DEFORMATION,
        "parts": list(PARTS),
        # every part is coaxial and unrotated: its placement is a translation along z
        "placement_z_mm": {name: float(T[2, 3]) for name, (_, T) in asm.parts.items()},
        "wave_generator": {"semi_axis_x_mm": wg.semi_axis_x_mm, "semi_axis_y_mm": wg.semi_axis_y_mm,
                           "z_min_mm": wg.z_min_mm, "z_max_mm": wg.z_max_mm, "width_mm": wg.width_mm,
                           "rule": WAVE_GENERATOR_RULE},
        "triangles": int(sum(len(m.faces) for m, _ in asm.parts.values())),
        "meshes": mesh_rows(asm),
    }
