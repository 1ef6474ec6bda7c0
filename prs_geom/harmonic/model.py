"""Stepless harmonic friction drive with a conical circular spline (docs/theory/harmonic.md).

Pure math, no I/O (exports in :mod:`prs_geom.harmonic_exports`).

Model (reconstructed in docs/theory/harmonic.md; its assumptions, stated here):

* Axial-section geometry, all lengths mm, angles rad inside. The flexspline is a cup of
  neutral radius r0 and length L; its bottom A = (0, r0) on the neutral layer is the
  origin of the axial coordinate x. The circular spline's bore is a cone: radius b1 at its
  small end, b2 at its big end, length H, half-angle alpha with tan(alpha) = (b2 - b1) / H.
  The small end sits at axial distance a from the flexspline bottom (the control input).
* The wave generator pushes the flexspline's open end outward; its generatrix is taken as
  a rigid line tilting by beta about A (no bending of the cup wall, no ovalisation across the
  major axis: the ratio model looks only at the major-axis section).
* The contact surface of the flexspline end is a circular arc of radius r_s whose centre lies
  x_s = L - r_s along the generatrix from A and c_s inside it (toward the axis).
* Contact: the arc is tangent to the cone wall. The cone line is r = b1 + (x - a) tan(alpha),
  and with a0 = (b1 - r0) / tan(alpha) the tangency condition is
      x_s sin(alpha - beta) + c_s cos(alpha - beta) = r_s + (a - a0) sin(alpha),
  solved for beta in closed form (a sine of a shifted angle).
* Contact arc angle phi = alpha - beta. Undeformed contact radius (the same material point
  of the untilted flexspline) r_c = r0 - c_s + r_s cos(phi); cone radius at the contact
  R_c = r0 + x_s sin(beta) - c_s cos(beta) + r_s cos(alpha); radius difference
  Delta = R_c - r_c; ratio i = r0 / Delta (friction drive: the flexspline rolls on the
  bore, output turns by Delta / r0 per input turn).
* Delta falls as the small end moves away (a grows); the ratio grows without bound at the
  position a_inf where Delta = 0. Manufacturing errors of the two radii enter Delta
  directly, so a high maximum ratio needs tight tolerances (:func:`tolerance_for_ratio`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import optimize

# the shared validators: both product lines word their errors alike
from prs_geom.harmonic.arrangement import (ARRANGEMENTS, NOT_MODELLED, Arrangement, SectionContact,
                                          sealed_contact, sealed_infinite_position, sealed_tilt,
                                          section_contact)
from prs_geom.harmonic.drive import (FLEXSPLINE_MATERIALS, FIXED_MEMBERS, StrengthLimit, contact_load,
                                     disc_wave_stress, flexspline_bending_stress, harmonic_ratio,
                                     planetary_stage, strength_limit, tolerance_grade)
from prs_geom.model.validation import bounded, check_name, positive, real, size
from prs_geom.model.errors import DesignError
from prs_geom.model.standards import GRADE_NAMES, it_tolerance_by_name_um

__all__ = ["Flexspline", "CircularSpline", "Positions", "HarmonicMesh", "Drive", "Generator", "ADJUSTING_MECHANISMS",
           "HARMONIC_FIELD_COMMENTS",
           "HarmonicDesign", "tilt_angle", "contact_state", "radius_difference", "ratio", "contact_point",
           "infinite_ratio_position", "speed_range", "tolerance_for_ratio", "harmonic_report", "ratio_table",
           "strength_section", "strength_warnings", "design_ratio", "drive_load", "adjusting", "drive_section",
           "generator_stage", "stages_in_series", "TABLE_POSITIONS", "table_positions", "drive_contact",
           "section_radius_difference", "flexspline_stress"]

@dataclass(frozen=True)
class Flexspline:
    neutral_radius_mm: float = 50.0
    length_mm: float = 100.0
    arc_radius_mm: float = 15.0
    arc_centre_offset_mm: float = 11.18
    wall_thickness_mm: float = 1.0
    #: The sealed drive's conical flexspline: half-angle of its wall (deg; 0 = a cylindrical cup)
    cone_half_angle_deg: float = 0.0

    def __post_init__(self) -> None:
        for f in ("neutral_radius_mm", "length_mm", "arc_radius_mm", "arc_centre_offset_mm", "wall_thickness_mm"):
            object.__setattr__(self, f, size(f, getattr(self, f)))
        object.__setattr__(self, "cone_half_angle_deg", bounded("cone_half_angle_deg", self.cone_half_angle_deg,
                                                                0.0, 30.0, "must be from 0 to 30 degrees"))
        if self.arc_radius_mm >= self.length_mm:
            raise DesignError("arc_radius_mm", self.arc_radius_mm, f"must be less than length_mm ({self.length_mm})")
        if self.wall_thickness_mm >= 0.5 * self.neutral_radius_mm:
            raise DesignError("wall_thickness_mm", self.wall_thickness_mm, "must be less than half the neutral radius")


@dataclass(frozen=True)
class CircularSpline:
    bore_small_radius_mm: float = 53.0
    bore_large_radius_mm: float = 57.0
    bore_length_mm: float = 50.0
    outer_radius_mm: float = 65.0
    #: The sealed drive's working arc in the bore: its radius and its centre's radius (mm)
    arc_radius_mm: float = 15.0
    arc_centre_radius_mm: float = 72.0

    def __post_init__(self) -> None:
        for f in ("bore_small_radius_mm", "bore_large_radius_mm", "bore_length_mm", "outer_radius_mm",
                  "arc_radius_mm", "arc_centre_radius_mm"):
            object.__setattr__(self, f, size(f, getattr(self, f)))
        if self.bore_large_radius_mm <= self.bore_small_radius_mm:
            raise DesignError("bore_large_radius_mm", self.bore_large_radius_mm,
                              f"must exceed bore_small_radius_mm ({self.bore_small_radius_mm}): the bore is a cone")
        if self.outer_radius_mm <= self.bore_large_radius_mm:
            raise DesignError("outer_radius_mm", self.outer_radius_mm,
                              f"must exceed bore_large_radius_mm ({self.bore_large_radius_mm})")


@dataclass(frozen=True)
class Positions:
    """Axial position a (mm) of the cone's small end from the flexspline bottom."""

    min_mm: float = 42.0
    max_mm: float = 74.0
    drawing_mm: tuple[float, ...] = (42.0, 60.0, 73.5)

    def __post_init__(self) -> None:
        object.__setattr__(self, "min_mm", real("min_mm", self.min_mm))
        object.__setattr__(self, "max_mm", real("max_mm", self.max_mm))
        if self.max_mm <= self.min_mm:
            raise DesignError("max_mm", self.max_mm, f"must exceed min_mm ({self.min_mm})")
        if isinstance(self.drawing_mm, (str, bytes)) or not hasattr(self.drawing_mm, "__iter__"):
            raise DesignError("drawing_mm", self.drawing_mm, "must be a list of positions (mm)")
        vals = tuple(real(f"drawing_mm[{k}]", v) for k, v in enumerate(self.drawing_mm))
        for k, v in enumerate(vals):
            if not self.min_mm <= v <= self.max_mm:
                raise DesignError(f"drawing_mm[{k}]", v, f"must lie in [min_mm, max_mm] = [{self.min_mm}, {self.max_mm}]")
        object.__setattr__(self, "drawing_mm", vals)


@dataclass(frozen=True)
class HarmonicMesh:
    chord_tolerance_mm: float = 0.01

    def __post_init__(self) -> None:
        t = positive("chord_tolerance_mm", self.chord_tolerance_mm)
        if not 1e-4 <= t <= 0.1:
            raise DesignError("chord_tolerance_mm", t, "must be from 0.0001 mm to 0.1 mm")
        object.__setattr__(self, "chord_tolerance_mm", t)


#: Adjusting mechanisms the source names (screw and nut, ball screw, worm gear, rack and
#: pinion, gear train); each is described by its axial travel per turn of its input.
ADJUSTING_MECHANISMS = ("screw", "ball-screw", "worm", "rack", "gears")


@dataclass(frozen=True)
class Drive:
    """How the drive is held, pressed and adjusted (design section ``[drive]``, format 3).

    Parameters
    ----------
    fixed_member : str
        ``"circular_spline"`` (the flexspline is the output, turning against the generator)
        or ``"flexspline"`` (the circular spline is the output, turning with it).
    flexspline_material : str
        A key of :data:`prs_geom.harmonic.drive.FLEXSPLINE_MATERIALS` (``"steel"``, ``"pa66"``):
        the strength check and the contact's elastic constants.
    friction_coefficient : float
        Traction coefficient at the contact (lubricated steel on steel: 0.05 to 0.1).
    pressing_force_n : float
        Axial force of the pressing device (spring, cone discs, nut), N.
    slip_safety_factor : float
        The transmissible torque is divided by it (>= 1).
    adjusting_mechanism : str
        One of :data:`ADJUSTING_MECHANISMS` (for the record; its effect is the travel).
    adjusting_travel_per_turn_mm : float
        Axial travel of the circular spline per turn of the adjusting input, mm (a screw's
        lead; a worm or gear train divides it by its ratio).
    stages : int
        Identical stages in series, adjusted together (1 to 4): the total ratio is the stage
        ratio to that power (each stage's output drives the next one's generator).
    arrangement : str
        A key of :data:`prs_geom.harmonic.arrangement.ARRANGEMENTS`: where the working section
        (the ``[flexspline]``, ``[circular_spline]`` and ``[positions]`` fields) sits in the drive,
        ``"radial_inner"`` (the published drive), ``"radial_outer"``, ``"end_face"`` or ``"sealed"``
        (the cone on the flexspline: ``flexspline.cone_half_angle_deg``, the working arc in the
        circular spline's bore: ``circular_spline.arc_radius_mm``, ``arc_centre_radius_mm``).
    """

    fixed_member: str = "circular_spline"
    flexspline_material: str = "steel"
    friction_coefficient: float = 0.1
    pressing_force_n: float = 500.0
    slip_safety_factor: float = 1.5
    adjusting_mechanism: str = "screw"
    adjusting_travel_per_turn_mm: float = 1.0
    stages: int = 1
    arrangement: str = "radial_inner"

    def __post_init__(self) -> None:
        if self.arrangement not in ARRANGEMENTS:
            raise DesignError("arrangement", self.arrangement, f"must be one of {', '.join(ARRANGEMENTS)}")
        if self.fixed_member not in FIXED_MEMBERS:
            raise DesignError("fixed_member", self.fixed_member, f"must be one of {', '.join(FIXED_MEMBERS)}")
        if self.flexspline_material not in FLEXSPLINE_MATERIALS:
            raise DesignError("flexspline_material", self.flexspline_material,
                              f"must be one of {', '.join(FLEXSPLINE_MATERIALS)}")
        if self.adjusting_mechanism not in ADJUSTING_MECHANISMS:
            raise DesignError("adjusting_mechanism", self.adjusting_mechanism,
                              f"must be one of {', '.join(ADJUSTING_MECHANISMS)}")
        mu = positive("friction_coefficient", self.friction_coefficient)
        if mu > 0.5:
            raise DesignError("friction_coefficient", mu, "must be at most 0.5 (a traction coefficient)")
        object.__setattr__(self, "friction_coefficient", mu)
        object.__setattr__(self, "pressing_force_n", positive("pressing_force_n", self.pressing_force_n))
        sf = positive("slip_safety_factor", self.slip_safety_factor)
        if sf < 1.0:
            raise DesignError("slip_safety_factor", sf, "must be at least 1")
        object.__setattr__(self, "slip_safety_factor", sf)
        object.__setattr__(self, "adjusting_travel_per_turn_mm",
                           positive("adjusting_travel_per_turn_mm", self.adjusting_travel_per_turn_mm))
        if isinstance(self.stages, bool) or not isinstance(self.stages, int) or not 1 <= self.stages <= 4:
            raise DesignError("stages", self.stages, "must be a whole number of stages from 1 to 4")


@dataclass(frozen=True)
class Generator:
    """The wave generator (design section ``[generator]``, format 3).

    ``kind`` ``"elliptical"`` (the published example: an elliptical disc on the input, the
    generator turns with it) or ``"planetary"`` (cone discs on the input drive support shafts
    whose rollers roll on the flexspline; the carrier is the wave:
    :func:`prs_geom.harmonic.drive.planetary_stage`). The planetary one's cone contact: the sun
    disc's radius ``sun_radius_mm`` and the shaft cone's ``planet_cone_radius_mm`` at
    positions.min_mm, their common half-angle ``cone_half_angle_deg``, the working roller's
    radius ``roller_radius_mm``, and ``shift_per_position`` (mm of axial shift of the cone
    contact per mm of position a: how the pressing cone discs follow the adjustment).
    """

    kind: str = "elliptical"
    sun_radius_mm: float = 10.0
    planet_cone_radius_mm: float = 10.0
    cone_half_angle_deg: float = 30.0
    roller_radius_mm: float = 8.0
    shift_per_position: float = 0.1

    def __post_init__(self) -> None:
        if self.kind not in ("elliptical", "planetary"):
            raise DesignError("kind", self.kind, 'must be "elliptical" or "planetary"')
        for f in ("sun_radius_mm", "planet_cone_radius_mm", "roller_radius_mm"):
            object.__setattr__(self, f, size(f, getattr(self, f)))
        object.__setattr__(self, "cone_half_angle_deg", bounded("cone_half_angle_deg", self.cone_half_angle_deg,
                                                                5.0, 60.0, "must be from 5 to 60 degrees"))
        object.__setattr__(self, "shift_per_position", bounded("shift_per_position", self.shift_per_position, 0.0,
                                                               1.0, "must be from 0 to 1 (mm per mm of position a)"))


#: Comments written above each key of a harmonic design file (unit and meaning).
HARMONIC_FIELD_COMMENTS: dict[str, str] = {
    "kind": '"prs" (default) or "harmonic"',
    "flexspline.neutral_radius_mm": "flexspline neutral-layer radius r0 (mm)",
    "flexspline.length_mm": "flexspline length L from the bottom (mm)",
    "flexspline.arc_radius_mm": "contact arc radius r_s (mm)",
    "flexspline.arc_centre_offset_mm": "arc centre offset c_s inside the neutral layer (mm)",
    "flexspline.wall_thickness_mm": "cup wall thickness for the mesh (mm)",
    "circular_spline.bore_small_radius_mm": "cone bore radius b1 at the small end (mm)",
    "circular_spline.bore_large_radius_mm": "cone bore radius b2 at the big end (mm)",
    "circular_spline.bore_length_mm": "cone bore length H (mm)",
    "circular_spline.outer_radius_mm": "outer radius of the circular spline ring (mm)",
    "positions.min_mm": "smallest position a of the cone small end from the flexspline bottom (mm)",
    "positions.max_mm": "largest position a (mm), below the infinite-ratio position",
    "positions.drawing_mm": "positions a drawn in the DXF (mm)",
    "drive.fixed_member": '"circular_spline" (flexspline output, turns against the generator) or "flexspline"',
    "drive.flexspline_material": '"steel" or "pa66": strength limit and contact elasticity',
    "drive.friction_coefficient": "traction coefficient at the contact (lubricated steel 0.05-0.1)",
    "drive.pressing_force_n": "axial force of the pressing device (spring, cone discs, nut) (N)",
    "drive.slip_safety_factor": "transmissible torque divided by this (>= 1)",
    "drive.adjusting_mechanism": '"screw", "ball-screw", "worm", "rack" or "gears"',
    "drive.adjusting_travel_per_turn_mm": "axial travel of the circular spline per adjusting-input turn (mm)",
    "drive.stages": "identical stages in series, adjusted together (1 to 4)",
    "drive.arrangement": '"radial_inner", "radial_outer", "end_face" or "sealed" (cone on the flexspline)',
    "flexspline.cone_half_angle_deg": "sealed drive: half-angle of the conical flexspline wall (deg)",
    "circular_spline.arc_radius_mm": "sealed drive: working arc radius in the bore (mm)",
    "circular_spline.arc_centre_radius_mm": "sealed drive: radius of the working arc's centre (mm)",
    "generator.kind": '"elliptical" (disc, turns with the input) or "planetary" (cone discs, carrier = wave)',
    "generator.sun_radius_mm": "planetary: input cone disc radius at the cone contact, at positions.min_mm (mm)",
    "generator.planet_cone_radius_mm": "planetary: support-shaft cone radius at that contact (mm)",
    "generator.cone_half_angle_deg": "planetary: half-angle of the two cones' common generatrix (degrees)",
    "generator.roller_radius_mm": "planetary: working roller radius, rolling on the flexspline (mm)",
    "generator.shift_per_position": "planetary: axial shift of the cone contact per mm of position a",
}


@dataclass(frozen=True)
class HarmonicDesign:
    """A conical-circular-spline harmonic friction drive; defaults = the published worked
    example (docs/theory/harmonic.md).

    Examples
    --------
    The worked example's ratio at the axial position a = 73.5 mm:

    >>> import prs_geom as pg
    >>> from prs_geom.harmonic.model import ratio
    >>> drive = pg.HarmonicDesign()
    >>> round(float(ratio(drive, 73.5)), 1)
    963.6
    """

    #: ``kind`` written in its design files (read back through prs_geom.pipeline.DESIGN_KINDS)
    FILE_KIND: ClassVar[str] = "harmonic"
    FIELD_COMMENTS: ClassVar[dict[str, str]] = HARMONIC_FIELD_COMMENTS

    name: str = "harmonic-example"
    flexspline: Flexspline = field(default_factory=Flexspline)
    circular_spline: CircularSpline = field(default_factory=CircularSpline)
    positions: Positions = field(default_factory=Positions)
    mesh: HarmonicMesh = field(default_factory=HarmonicMesh)
    drive: Drive = field(default_factory=Drive)
    generator: Generator = field(default_factory=Generator)

    def __post_init__(self) -> None:
        check_name(self.name)
        if self.drive.arrangement == "sealed":
            self._check_sealed()
        else:
            self._check_section()
        if self.generator.kind == "planetary":
            # the cone contact moves monotonically: the ends of travel bound both radii
            generator_stage(self, (self.positions.min_mm, self.positions.max_mm))

    def _check_section(self) -> None:
        """The working section of the radial and end-face drives: the arc reaches the cone
        over the whole range, Delta stays positive and of one sign in the drive."""
        f, c = self.flexspline, self.circular_spline
        if c.bore_small_radius_mm <= f.neutral_radius_mm:
            raise DesignError("circular_spline.bore_small_radius_mm", c.bore_small_radius_mm,
                              f"must exceed the flexspline neutral radius {f.neutral_radius_mm}")
        # the tangency equation must be solvable over the whole range, with Delta > 0
        amp = math.hypot(self.x_s, f.arc_centre_offset_mm)
        for fld, a in (("positions.min_mm", self.positions.min_mm), ("positions.max_mm", self.positions.max_mm)):
            rhs = f.arc_radius_mm + (a - self.a0) * math.sin(self.alpha)
            if abs(rhs) >= amp:
                raise DesignError(fld, a, "the contact arc cannot reach the cone wall at this position")
        a_inf = infinite_ratio_position(self)
        if a_inf is not None and self.positions.max_mm >= a_inf:
            raise DesignError("positions.max_mm", self.positions.max_mm,
                              f"must be below the infinite-ratio position {a_inf:.6f} mm (radius difference reaches 0)")
        grid = np.linspace(self.positions.min_mm, self.positions.max_mm, 201)
        if float(np.min(section_radius_difference(self, grid))) <= 0:
            raise DesignError("positions.min_mm", self.positions.min_mm, "the radius difference must stay positive")
        if self.drive.arrangement == "end_face":
            self._check_disc()
        delta = drive_contact(self, grid).radius_difference_mm
        if not (np.all(delta > 0) or np.all(delta < 0)):
            raise DesignError("positions.min_mm", self.positions.min_mm,
                              f"the {self.drive.arrangement} drive's radius difference changes sign over the "
                              "control range (its ratio passes through infinity)")

    def _check_sealed(self) -> None:
        """The sealed drive: a conical flexspline, the working arc inside the bore, the arc in
        reach and touching the cone's straight outer wall over the whole range, beta > 0
        (below the infinite-ratio position)."""
        f, c = self.flexspline, self.circular_spline
        if f.cone_half_angle_deg <= 0.0:
            raise DesignError("flexspline.cone_half_angle_deg", f.cone_half_angle_deg,
                              "must be > 0 for the sealed drive (its flexspline is the cone)")
        if not c.arc_centre_radius_mm - c.arc_radius_mm < c.bore_small_radius_mm < c.arc_centre_radius_mm:
            raise DesignError("circular_spline.arc_centre_radius_mm", c.arc_centre_radius_mm,
                              f"minus arc_radius_mm must lie inside the bore (bore_small_radius_mm "
                              f"{c.bore_small_radius_mm}) and the centre outside it: the arc is a ridge in the bore")
        if c.outer_radius_mm <= c.arc_centre_radius_mm:
            raise DesignError("circular_spline.outer_radius_mm", c.outer_radius_mm,
                              f"must exceed arc_centre_radius_mm ({c.arc_centre_radius_mm})")
        ridge = math.sqrt(c.arc_radius_mm ** 2 - (c.arc_centre_radius_mm - c.bore_small_radius_mm) ** 2)
        if ridge >= 0.5 * c.bore_length_mm:
            raise DesignError("circular_spline.bore_length_mm", c.bore_length_mm,
                              f"must exceed the working arc's width {2 * ridge:.4g} mm")
        a_inf = infinite_ratio_position(self)
        for fld, a in (("positions.min_mm", self.positions.min_mm), ("positions.max_mm", self.positions.max_mm)):
            beta = float(tilt_angle(self, a))
            if not beta > 0:
                raise DesignError(fld, a, f"must be below the infinite-ratio position {a_inf:.6f} mm "
                                          "(the cone must be tilted outward to reach the arc)")
            z_c = float(drive_contact(self, a).contact_z_mm)
            if not f.wall_thickness_mm < z_c < f.length_mm:
                raise DesignError(fld, a, f"puts the contact at z = {z_c:.4g} mm, off the flexspline's wall "
                                          f"(0 .. length_mm = {f.length_mm})")
            ang = math.radians(f.cone_half_angle_deg) + beta
            if abs(ang) >= math.asin(ridge / c.arc_radius_mm):
                raise DesignError(fld, a, "puts the contact off the working arc's ridge")
            # the bore must clear the tilted cone where the ring ends (the wall leans outward)
            z_end = min(a + 0.5 * c.bore_length_mm, f.length_mm)
            h = 0.5 * f.wall_thickness_mm
            outer = f.neutral_radius_mm + h * math.cos(ang) + (z_end + h * math.sin(ang)) * math.tan(ang)
            if outer >= c.bore_small_radius_mm:
                raise DesignError("circular_spline.bore_small_radius_mm", c.bore_small_radius_mm,
                                  f"must clear the tilted flexspline at the ring's end (radius {outer:.4g} mm "
                                  f"at position {a:g} mm)")

    def _check_disc(self) -> None:
        """The end-face disc: clamped at r0, it must not reach the axis, and its inner face
        must stay a face (the arc's centre offset within the neutral radius)."""
        f = self.flexspline
        if f.arc_centre_offset_mm + f.arc_radius_mm >= f.neutral_radius_mm:
            raise DesignError("flexspline.arc_centre_offset_mm", f.arc_centre_offset_mm,
                              "with arc_radius_mm must stay below neutral_radius_mm for the end-face disc")

    @property
    def arrangement(self) -> Arrangement:
        """The arrangement map of the working section (``drive.arrangement``)."""
        return Arrangement(self.drive.arrangement, self.flexspline.neutral_radius_mm)

    @property
    def alpha(self) -> float:
        """Cone half-angle (rad): tan(alpha) = (b2 - b1) / H; the sealed drive's the
        flexspline's (``flexspline.cone_half_angle_deg``)."""
        if self.drive.arrangement == "sealed":
            return math.radians(self.flexspline.cone_half_angle_deg)
        c = self.circular_spline
        return math.atan((c.bore_large_radius_mm - c.bore_small_radius_mm) / c.bore_length_mm)

    @property
    def a0(self) -> float:
        """a0 = (b1 - r0) / tan(alpha) (mm)."""
        return (self.circular_spline.bore_small_radius_mm - self.flexspline.neutral_radius_mm) / math.tan(self.alpha)

    @property
    def x_s(self) -> float:
        """Axial station of the arc centre along the generatrix, L - r_s (mm)."""
        return self.flexspline.length_mm - self.flexspline.arc_radius_mm


# --------------------------------------------------------------------------- model
def tilt_angle(d: HarmonicDesign, a: ArrayLike) -> NDArray[np.float64]:
    """beta(a) (rad) from the tangency condition, vectorised over a (mm); the sealed drive's
    by :func:`prs_geom.harmonic.arrangement.sealed_tilt`."""
    a = np.asarray(a, dtype=np.float64)
    f = d.flexspline
    if d.drive.arrangement == "sealed":
        c = d.circular_spline
        return sealed_tilt(a, f.neutral_radius_mm, f.wall_thickness_mm, d.alpha, c.arc_centre_radius_mm,
                           c.arc_radius_mm)
    amp = math.hypot(d.x_s, f.arc_centre_offset_mm)
    delta = math.atan2(f.arc_centre_offset_mm, d.x_s)
    rhs = f.arc_radius_mm + (a - d.a0) * math.sin(d.alpha)
    # x_s sin(u) + c_s cos(u) = amp sin(u + delta) = rhs, u = alpha - beta (small branch)
    u = np.arcsin(rhs / amp) - delta
    return d.alpha - u


def drive_contact(d: HarmonicDesign, a: ArrayLike) -> SectionContact:
    """The contact at positions a (mm) in the drive frame of the design's arrangement
    (:func:`prs_geom.harmonic.arrangement.section_contact`)."""
    f = d.flexspline
    if d.drive.arrangement == "sealed":
        c = d.circular_spline
        return sealed_contact(a, tilt_angle(d, a), f.neutral_radius_mm, f.wall_thickness_mm, d.alpha,
                              c.arc_centre_radius_mm, c.arc_radius_mm)
    return section_contact(d.arrangement, tilt_angle(d, a), d.alpha, d.x_s, f.arc_centre_offset_mm,
                           f.arc_radius_mm)


def contact_state(d: HarmonicDesign, a: ArrayLike) -> dict[str, NDArray[np.float64]]:
    """beta, phi (rad), and in the drive frame of the arrangement: the flexspline's radius at
    the contact r_c (the material point, undeformed), the circular spline's R_c, Delta = R_c -
    r_c (mm), the flexspline's rolling radius (mm) and the ratio |r_f / Delta|, vectorised.
    For the radial inner-wave drive these are the section's own values (module docstring)."""
    beta = tilt_angle(d, a)
    c = drive_contact(d, a)
    return {"a_mm": np.asarray(a, dtype=np.float64), "beta_rad": beta, "phi_rad": d.alpha - beta,
            "contact_radius_mm": c.material_rho_mm, "cone_radius_mm": c.contact_rho_mm,
            "radius_difference_mm": c.radius_difference_mm,
            "rolling_radius_mm": c.flexspline_rolling_radius_mm, "ratio": c.ratio}


def section_radius_difference(d: HarmonicDesign, a: ArrayLike) -> NDArray[np.float64]:
    """Delta (mm) of the working section in its own frame (the radial inner-wave drive's):
    positive on the small-tilt branch, zero at the infinite-ratio position (the sealed drive's
    own section: its Delta)."""
    f = d.flexspline
    if d.drive.arrangement == "sealed":
        return drive_contact(d, a).radius_difference_mm
    return section_contact(Arrangement("radial_inner", f.neutral_radius_mm), tilt_angle(d, a), d.alpha, d.x_s,
                           f.arc_centre_offset_mm, f.arc_radius_mm).radius_difference_mm


def radius_difference(d: HarmonicDesign, a: ArrayLike) -> NDArray[np.float64]:
    """Delta (mm) in the drive frame (:func:`contact_state`)."""
    return contact_state(d, a)["radius_difference_mm"]


def ratio(d: HarmonicDesign, a: ArrayLike) -> NDArray[np.float64]:
    return contact_state(d, a)["ratio"]


def contact_point(d: HarmonicDesign, a: float) -> tuple[float, float]:
    """(x, r) of the contact in the working section's frame, x from the clamp A (mm); for the
    radial inner-wave and the sealed drive the axial section (x from the flexspline bottom)."""
    f = d.flexspline
    if d.drive.arrangement == "sealed":
        c = drive_contact(d, a)
        return float(c.contact_z_mm), float(c.contact_rho_mm)
    beta = float(tilt_angle(d, a))
    cx = d.x_s * math.cos(beta) + f.arc_centre_offset_mm * math.sin(beta)
    cr = f.neutral_radius_mm + d.x_s * math.sin(beta) - f.arc_centre_offset_mm * math.cos(beta)
    return cx - f.arc_radius_mm * math.sin(d.alpha), cr + f.arc_radius_mm * math.cos(d.alpha)


def infinite_ratio_position(d: HarmonicDesign) -> float | None:
    """a (mm) where Delta = 0 (the ratio becomes infinite), or None if not reached."""
    f = d.flexspline
    if d.drive.arrangement == "sealed":
        c = d.circular_spline
        return sealed_infinite_position(f.neutral_radius_mm, f.wall_thickness_mm, d.alpha, c.arc_centre_radius_mm,
                                        c.arc_radius_mm)
    amp = math.hypot(d.x_s, f.arc_centre_offset_mm)
    a_hi = d.a0 + (amp - f.arc_radius_mm) / math.sin(d.alpha) - 1e-9
    a_lo = d.a0
    g = lambda x: float(section_radius_difference(d, x))  # noqa: E731
    if g(a_lo) <= 0 or g(a_hi) > 0:
        return None
    return optimize.brentq(g, a_lo, a_hi, xtol=1e-13)


def speed_range(d: HarmonicDesign) -> dict[str, float]:
    i_min = float(ratio(d, d.positions.min_mm))
    i_max = float(ratio(d, d.positions.max_mm))
    return {"ratio_min": i_min, "ratio_max": i_max, "speed_range": i_max / i_min}


def tolerance_for_ratio(d: HarmonicDesign, max_ratio: float, ratio_error: float = 0.1) -> dict[str, Any]:
    """Radius tolerance (and ISO IT grade of the bore diameter) that keeps the ratio within
    ``ratio_error`` (relative) at the position where the ratio is ``max_ratio``.

    Delta = r0 / i; an error e on each of the two radii changes Delta by up to 2 e, so the
    ratio changes by 2 e / Delta relative: e = ratio_error Delta / 2. A centred diameter
    tolerance band T gives radius errors of +-T/4, so T = 4 e. ``it_grade`` is the coarsest
    ISO 286 grade (name, IT01..IT13, :mod:`prs_geom.model.standards`) whose standard
    tolerance on the bore diameter fits in T (None: finer than IT01 needed). The other
    arrangements take their rolling radius for r0 and the contact diameter for the bore's,
    both at positions.max_mm.
    """
    if not max_ratio > 0:
        raise DesignError("max_ratio", max_ratio, "must be > 0")
    delta = d.flexspline.neutral_radius_mm / max_ratio
    dia = 2.0 * d.circular_spline.bore_large_radius_mm
    if d.drive.arrangement != "radial_inner":
        # the arrangement's rolling radius and contact diameter, at the largest position
        end = drive_contact(d, d.positions.max_mm)
        delta = float(end.flexspline_rolling_radius_mm) / max_ratio
        dia = 2.0 * float(end.contact_rho_mm)
    e = ratio_error * delta / 2.0
    T_um = 4.0 * e * 1e3
    grade = None
    for name in reversed(GRADE_NAMES):
        if it_tolerance_by_name_um(name, dia) <= T_um:
            grade = name
            break
    return {"max_ratio": max_ratio, "ratio_error": ratio_error, "radius_difference_mm": delta,
            "radius_tolerance_um": e * 1e3, "diameter_band_um": T_um, "bore_diameter_mm": dia,
            "it_grade": grade, "ratio_change_per_um": 2e-3 / delta}


#: Positions of the ratio table and the drive summary, evenly over the control range.
TABLE_POSITIONS = 65


def table_positions(d: HarmonicDesign) -> NDArray[np.float64]:
    """The ``TABLE_POSITIONS`` positions a (mm) from positions.min_mm to positions.max_mm."""
    return np.linspace(d.positions.min_mm, d.positions.max_mm, TABLE_POSITIONS)


def ratio_table(d: HarmonicDesign, a_values: ArrayLike | None = None) -> list[dict[str, Any]]:
    """The contact state at each position a (mm; default 65 positions over the control
    range), one row each: a, generatrix tilt beta and contact angle phi (deg), contact and
    cone radius and their difference (mm), ratio (magnitude, the source's r0 / Delta), the
    signed ratios with the circular spline and with the flexspline fixed
    (:func:`prs_geom.harmonic.drive.harmonic_ratio`: flexspline rolling radius r0, circular
    spline r0 + Delta) and the finest ISO 286 grade whose tolerance at the contact diameter
    is at least Delta (:func:`prs_geom.harmonic.drive.tolerance_grade`)."""
    if a_values is None:
        a_values = table_positions(d)
    st = contact_state(d, a_values)
    r_f = st["rolling_radius_mm"]
    delta = st["radius_difference_mm"]
    signed = {m: harmonic_ratio(r_f, r_f + delta, m) for m in FIXED_MEMBERS}
    grades = tolerance_grade(delta, 2.0 * st["contact_radius_mm"])
    staged = stages_in_series(signed[d.drive.fixed_member], d.drive.stages)
    load = drive_load(d, st)
    turns, per_degree = adjusting(d, st["a_mm"])
    # + 0.0: the end face's first travel is -0.0, printed as such
    travel = d.arrangement.face_travel(st["a_mm"], d.positions.min_mm, math.tan(d.alpha)) + 0.0
    planet = [{} for _ in range(len(st["a_mm"]))]
    if d.generator.kind == "planetary":
        p = generator_stage(d, st["a_mm"])
        planet = [{"generator_ratio": float(p.stage_ratio[k]), "total_ratio": float(p.product_ratio[k]),
                   "total_ratio_coupled": float(p.coupled_ratio[k])} for k in range(len(st["a_mm"]))]
    return [{"a_mm": float(st["a_mm"][k]), "beta_deg": float(np.degrees(st["beta_rad"][k])),
             "phi_deg": float(np.degrees(st["phi_rad"][k])),
             "contact_radius_mm": float(st["contact_radius_mm"][k]),
             "cone_radius_mm": float(st["cone_radius_mm"][k]),
             "radius_difference_mm": float(delta[k]),
             "ratio": float(st["ratio"][k]),
             "ratio_circular_spline_fixed": float(signed["circular_spline"][k]),
             "ratio_flexspline_fixed": float(signed["flexspline"][k]),
             "ratio_all_stages": float(staged[k]),
             "it_grade": grades[k],
             "circular_spline_travel_mm": float(travel[k]),
             "adjusting_turns": float(turns[k]), "ratio_change_per_degree": float(per_degree[k]),
             "output_torque_nm": float(load.output_torque_nm[k]), "input_torque_nm": float(load.input_torque_nm[k]),
             "contact_pressure_mpa": float(load.max_pressure_mpa[k]),
             "circumferential_semi_axis_mm": float(load.semi_axes_mm[k, 1]),
             "hertz_valid": bool(load.hertz_valid[k]), **planet[k]} for k in range(len(st["a_mm"]))]


def generator_stage(d: HarmonicDesign, a: ArrayLike):
    """The planetary wave generator's stage and the drive's total ratio at positions a (mm)
    (:func:`prs_geom.harmonic.drive.planetary_stage`; the ring is the flexspline's inner
    surface, radius r0 - t / 2)."""
    g = d.generator
    a = np.asarray(a, dtype=np.float64)
    f = d.flexspline
    try:
        return planetary_stage(g.shift_per_position * (a - d.positions.min_mm), g.sun_radius_mm,
                               g.planet_cone_radius_mm, g.cone_half_angle_deg, g.roller_radius_mm,
                               f.neutral_radius_mm - 0.5 * f.wall_thickness_mm, design_ratio(d, a),
                               d.drive.fixed_member)
    except ValueError as exc:
        raise DesignError("generator.shift_per_position", g.shift_per_position,
                          f"must keep the cone contact on both cones over the travel: {exc}") from None


def stages_in_series(stage_ratio: ArrayLike, stages: int) -> NDArray[np.float64]:
    """The ratio of ``stages`` identical stages in series: each stage's output turns the next
    one's wave generator, so the ratios (signs included) multiply: i^stages."""
    return np.asarray(stage_ratio, dtype=np.float64) ** int(stages)


def design_ratio(d: HarmonicDesign, a: ArrayLike) -> NDArray[np.float64]:
    """The signed ratio (generator over output speed) of the design's fixed member
    (``drive.fixed_member``) at positions a (mm)."""
    c = drive_contact(d, a)
    r_f = c.flexspline_rolling_radius_mm
    return harmonic_ratio(r_f, r_f + c.radius_difference_mm, d.drive.fixed_member)


def drive_load(d: HarmonicDesign, state: dict[str, NDArray[np.float64]]):
    """The contact's forces, torques and pressure at the positions of ``state``
    (:func:`contact_state`), for the design's pressing force, friction, safety factor and
    flexspline material (:func:`prs_geom.harmonic.drive.contact_load`)."""
    dr = d.drive
    kind = d.drive.arrangement
    half_angle, curvature, arc = d.arrangement.working_half_angle(d.alpha), None, d.flexspline.arc_radius_mm
    if kind != "radial_inner":
        r_m, r_c = state["contact_radius_mm"], state["cone_radius_mm"]
        delta = np.abs(state["radius_difference_mm"])
        if kind == "radial_outer":
            # concave flexspline (its inner face, flattened at the major axis by 3 Delta / r0^2)
            # on the convex outer wall: the same sum as the inner-wave drive's, mirrored
            curvature = math.cos(d.alpha) * (1.0 / r_c - 1.0 / r_m + 3.0 * delta / d.flexspline.neutral_radius_mm ** 2)
        elif kind == "sealed":
            # the convex cone (ovalised by 3 Delta / r_f^2) in the ridge's bore; the normal leans
            # by alpha + beta from the radial, the meridian curvature is the ridge's arc
            ang = d.alpha + state["beta_rad"]
            curvature = np.cos(ang) * (1.0 / r_m + 3.0 * delta / state["rolling_radius_mm"] ** 2 - 1.0 / r_c)
            arc = d.circular_spline.arc_radius_mm
        else:
            # the face's half-angle about the axis is 90 deg - alpha: its circumferential normal
            # curvature sin(alpha) / rho; the rim's axial wave W cos(2 theta) adds 4 W / rho^2
            wave = (r_m - d.flexspline.neutral_radius_mm) * np.abs(np.sin(state["beta_rad"]))
            curvature = np.abs(math.sin(d.alpha) * (1.0 / r_c - 1.0 / r_m)) + 4.0 * wave / r_m ** 2
    return contact_load(half_angle, arc, d.flexspline.neutral_radius_mm,
                        state["contact_radius_mm"], state["cone_radius_mm"], state["radius_difference_mm"],
                        design_ratio(d, state["a_mm"]), dr.pressing_force_n, dr.friction_coefficient,
                        dr.slip_safety_factor, FLEXSPLINE_MATERIALS[dr.flexspline_material], curvature)


def adjusting(d: HarmonicDesign, a: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(turns of the adjusting input from positions.min_mm, change of the design's signed
    ratio per degree of the adjusting input) at positions a (mm). The derivative is a central
    difference of the closed-form ratio with a step of 1e-6 mm (relative error about 1e-6
    where the ratio's curvature is largest). The mechanism moves the circular spline along
    the axis: |d(travel) / da| is 1 for the radial drives and tan(alpha) for the end face
    (:meth:`prs_geom.harmonic.arrangement.Arrangement.travel_per_position`)."""
    a = np.asarray(a, dtype=np.float64)
    travel = d.drive.adjusting_travel_per_turn_mm / d.arrangement.travel_per_position(math.tan(d.alpha))
    h = 1e-6
    hi = np.minimum(a + h, d.positions.max_mm)
    lo = np.maximum(a - h, d.positions.min_mm)
    slope = (design_ratio(d, hi) - design_ratio(d, lo)) / (hi - lo)
    return (a - d.positions.min_mm) / travel, slope * travel / 360.0


def _strength_limits(d: HarmonicDesign) -> dict[str, Any]:
    f = d.flexspline
    if d.drive.arrangement == "end_face":
        return {key: _disc_strength_limit(d, mat) for key, mat in FLEXSPLINE_MATERIALS.items()}
    lo, hi = (float(radius_difference(d, a)) for a in (d.positions.min_mm, d.positions.max_mm))
    # the ring that bends is the flexspline at the contact: r0 in the radial drives, the
    # cone's neutral radius there in the sealed one (at the smallest ratio, where it counts)
    ring = float(drive_contact(d, d.positions.min_mm).flexspline_rolling_radius_mm)
    return {key: strength_limit(mat, ring, f.wall_thickness_mm, lo, hi) for key, mat in FLEXSPLINE_MATERIALS.items()}


def flexspline_stress(d: HarmonicDesign, a: ArrayLike, mat: Any) -> NDArray[np.float64]:
    """The flexspline's largest bending stress (MPa) at positions a (mm) for material ``mat``:
    the thin ring ovalised by Delta (radial drives,
    :func:`prs_geom.harmonic.drive.flexspline_bending_stress`) or the disc's rim bent out of
    its plane by W = L sin(beta) (end face, :func:`prs_geom.harmonic.drive.disc_wave_stress`)."""
    f = d.flexspline
    if d.arrangement.is_disc:
        return disc_wave_stress(f.length_mm * np.sin(tilt_angle(d, a)), f.neutral_radius_mm + f.length_mm,
                                f.wall_thickness_mm, mat.youngs_modulus_mpa)
    return flexspline_bending_stress(radius_difference(d, a), f.neutral_radius_mm, f.wall_thickness_mm,
                                     mat.youngs_modulus_mpa)


def _disc_strength_limit(d: HarmonicDesign, mat: Any) -> StrengthLimit:
    """The end-face disc's strength limit: its rim (radius r0 + L) carries the axial wave
    W = L sin(beta) (:func:`prs_geom.harmonic.drive.disc_wave_stress`); the largest allowed
    tilt gives the smallest ratio through the section's contact at that tilt."""
    f = d.flexspline
    rim = f.neutral_radius_mm + f.length_mm
    per_wave = float(disc_wave_stress(1.0, rim, f.wall_thickness_mm, mat.youngs_modulus_mpa))
    s_beta = min(1.0, mat.allowed_bending_stress_mpa / per_wave / f.length_mm)
    limit = section_contact(d.arrangement, math.asin(s_beta), d.alpha, d.x_s, f.arc_centre_offset_mm,
                            f.arc_radius_mm)
    ends = drive_contact(d, (d.positions.min_mm, d.positions.max_mm))
    stress = flexspline_stress(d, (d.positions.min_mm, d.positions.max_mm), mat)
    i_min = float(limit.ratio)
    i_lo, i_hi = (float(v) for v in ends.ratio)
    return StrengthLimit(mat, float(abs(limit.radius_difference_mm)), i_min, float(stress[0]), float(stress[1]),
                         i_hi / max(i_lo, i_min), i_lo >= i_min)


def strength_warnings(d: HarmonicDesign) -> list[str]:
    """A line when the design's smallest ratio bends its flexspline (``drive.flexspline_material``)
    past the allowed stress, with the numbers."""
    i_lo = float(ratio(d, d.positions.min_mm))
    key = d.drive.flexspline_material
    s = _strength_limits(d)[key]
    out = [] if s.within else [
        f"flexspline strength ({key}): the {d.flexspline.wall_thickness_mm:g} mm wall bends to "
        f"{s.stress_at_min_position_mpa:.0f} MPa at positions.min_mm (allowed "
        f"{s.material.allowed_bending_stress_mpa:g} MPa): smallest ratio {s.min_ratio:.1f}, the design "
        f"reaches {i_lo:.1f}"]
    return out


def drive_section(d: HarmonicDesign, rows: list[dict[str, Any]] | None = None) -> dict[str, Any]:
    """report.json's ``harmonic.drive``: the fixed member and the signed ratio range, the
    pressing force and the cone's normal force, the torque range, where Hertz's contact model
    holds, the adjusting mechanism's range and resolution; read off ``rows``, the ratio table
    over the control range (default :func:`ratio_table` at :func:`table_positions`)."""
    dr = d.drive
    rows = ratio_table(d) if rows is None else rows
    first, last = rows[0], rows[-1]
    signed = f"ratio_{dr.fixed_member}_fixed"
    valid = [r["a_mm"] for r in rows if r["hertz_valid"]]
    half_angle = d.arrangement.working_half_angle(d.alpha)
    return {"arrangement": dr.arrangement, "arrangement_description": ARRANGEMENTS[dr.arrangement],
            "fixed_member": dr.fixed_member, "output": "flexspline" if dr.fixed_member == "circular_spline"
            else "circular_spline", "ratio_at_min_position": first[signed], "ratio_at_max_position": last[signed],
            "flexspline_material": dr.flexspline_material, "pressing_force_n": dr.pressing_force_n,
            "normal_force_n": dr.pressing_force_n / math.sin(half_angle),
            "normal_force_factor": 1.0 / math.sin(half_angle),
            "friction_coefficient": dr.friction_coefficient, "slip_safety_factor": dr.slip_safety_factor,
            "output_torque_nm": first["output_torque_nm"],
            "input_torque_at_max_position_nm": last["input_torque_nm"],
            "max_contact_pressure_mpa": max(r["contact_pressure_mpa"] for r in rows),
            "hertz_valid_up_to_mm": max(valid) if valid else None,
            "adjusting_mechanism": dr.adjusting_mechanism,
            "adjusting_travel_per_turn_mm": dr.adjusting_travel_per_turn_mm,
            "adjusting_turns": last["adjusting_turns"],
            "ratio_change_per_degree_at_max_position": last["ratio_change_per_degree"],
            "efficiency": "not modelled: the source gives no efficiency for this drive"}


def strength_section(d: HarmonicDesign) -> list[dict[str, Any]]:
    """The flexspline's strength limit for each reference material
    (:data:`prs_geom.harmonic.drive.FLEXSPLINE_MATERIALS`) with the design's wall: the
    largest radius difference, the smallest ratio, the wall stress at both ends of travel,
    the usable speed range and whether the design's smallest ratio is within it."""
    out = []
    for key, s in _strength_limits(d).items():
        mat = s.material
        out.append({"material": key, "name": mat.name, "youngs_modulus_mpa": mat.youngs_modulus_mpa,
                    "allowed_bending_stress_mpa": mat.allowed_bending_stress_mpa, "source": mat.source,
                    "max_radius_difference_mm": s.max_radius_difference_mm, "min_ratio": s.min_ratio,
                    "stress_at_min_position_mpa": s.stress_at_min_position_mpa,
                    "stress_at_max_position_mpa": s.stress_at_max_position_mpa,
                    "speed_range": s.speed_range, "within": s.within})
    return out


def harmonic_report(d: HarmonicDesign, a_values: ArrayLike | None = None) -> dict[str, Any]:
    """report.json's ``harmonic`` section: the cone geometry, the speed range, the ratio
    table (:func:`ratio_table`) and the diameter tolerances for three ratios."""
    rng = speed_range(d)
    table = ratio_table(d, a_values)
    return {
        "alpha_deg": math.degrees(d.alpha),
        "a0_mm": d.a0,
        "infinite_ratio_position_mm": infinite_ratio_position(d),
        **rng,
        "table": table,
        "tolerance": [tolerance_for_ratio(d, i) for i in (100.0, 500.0, rng["ratio_max"])],
        "strength": strength_section(d),
        "drive": drive_section(d, table if a_values is None else None),
        "arrangement": d.drive.arrangement,
        "assumptions": "rigid generatrix tilting about the flexspline's clamp; major-axis section only; "
                       f"{ARRANGEMENTS[d.drive.arrangement]}; not modelled: {NOT_MODELLED}; multi-stage drives "
                       "as identical stages in series; "
                       "see prs_geom/harmonic/model.py and docs/theory/harmonic.md",
    }
