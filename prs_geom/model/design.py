"""The design model of a planetary roller screw (PRS).

Frozen dataclasses, validated at construction. Field names carry their unit
(``_mm``, ``_deg``, ``_n``, ``_mpa``); inside the toolkit angles are radians, but a design
stores the degrees the designer typed so that a saved design reads back to the same object.

Conventions (see docs/theory/conventions.md):

* Units: mm, N, MPa; angles in degrees in files, radians in computations.
* Frame: the screw frame, z along the screw axis, origin at the loaded end of the nut
  thread (tooth 1 side), x through the centre of roller 0.
* Teeth are numbered j = 1..n from the loaded end; a pitch list holds the n - 1 axial
  distances between tooth j and tooth j + 1, in mm.
* For the nut (an internal thread) ``major_diameter_mm`` is the groove root (largest
  diameter) and ``minor_diameter_mm`` the crest (bore).

Which relations are errors and which are warnings:

* Errors: anything that makes the geometry impossible (non-positive sizes, crest not
  above root, a tooth or groove of zero width, roller arc radius smaller than the roller
  crest radius, crests reaching into the mating roots, rollers overlapping each other,
  nut body thinner than its thread, pitch lists of the wrong length or far from the
  nominal pitch, materials outside physical bounds).
* Warnings (:class:`~prs_geom.errors.DesignWarning`): the standard-sizing relations
  r_n = r_s + 2 r_r, r_n = n_n r_r, n_s = n_n, r_s = (n_s - 2) r_r, which a designer may
  break on purpose.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace
from typing import Any

from prs_geom.model.actuator import ActuatorSettings
from prs_geom.model.errors import DesignError, DesignWarning
from prs_geom.model.validation import (bounded, check_name, choice, force, integer, optional_force, optional_length,
                                       optional_size, pitch_list, positive, real, size)

__all__ = ["CARRIER_GUIDANCE", "COMPLIANCE_MODELS", "DEFAULT_ADDENDUM_FACTOR", "DEFAULT_DEDENDUM_FACTOR",
           "DEFAULT_REQUIRED_STATIC_SAFETY", "DISTRIBUTIONS", "DN_LIMIT_RANGE_MM_RPM", "END_SUPPORTS", "FLANK_FIELDS",
           "HANDS", "INSTALLATIONS", "LIFE_RANGE_HOURS", "LOAD_FRACTION_RANGE", "MAX_PITCH_DEVIATION",
           "MAX_TOLERANCE_UM", "RELIABILITY_RANGE", "REQUIRED_STATIC_SAFETY_RANGE", "SIZING_RTOL", "SPEED_RANGE_RPM",
           "TOOTH_WIDTHS", "ContactSettings", "GearSettings", "LoadSettings", "Loading", "Material", "Materials",
           "MechanismSettings", "MeshSettings", "Nut", "PRSDesign", "RatingSettings", "Roller", "Screw", "Supports",
           "Thread", "Tolerances", "default_design"]

#: Installation types of docs/theory/loads.md.
INSTALLATIONS = ("tension-compression", "compression-compression")
HANDS = ("right", "left")
#: Default crest/root truncation as fractions of the sharp-V half depth p / (4 tan beta).
DEFAULT_ADDENDUM_FACTOR = 0.6
DEFAULT_DEDENDUM_FACTOR = 0.8
#: A pitch-list entry may differ from the nominal pitch by at most this fraction: graded
#: pitch corrections are micrometres, anything larger is a typing error, and beyond a few
#: per cent the warped tooth would no longer be the profile that was designed.
MAX_PITCH_DEVIATION = 0.02
#: Relative tolerance under which a standard-sizing relation counts as held.
SIZING_RTOL = 1e-9

def _um(x: float) -> float:
    """Round a defaulted diameter to 0.1 um, as a drawing would state it."""
    return round(x, 4)


def _set(obj: Any, name: str, value: Any) -> None:
    object.__setattr__(obj, name, value)


# --------------------------------------------------------------------------- parts
@dataclass(frozen=True)
class Thread:
    """Thread data shared by screw, rollers and nut.

    Parameters
    ----------
    pitch_mm : float
        Axial pitch p (mm), the same for all three threads; lead L_i = n_i p; a size
        (0.01 to 10000 mm, :func:`~prs_geom.model.validation.size`).
    flank_half_angle_deg : float
        Flank half-angle beta (deg) in the normal section, measured from the radial line.
    hand : {"right", "left"}
        Hand of all three threads (they share it, docs/theory/geometry.md).
    engaged_teeth : int
        Number n of roller teeth engaged with screw and nut (2 to 500); roller and nut thread
        lengths are n p. The mechanism's axial stack-up (n p plus gears, carriers and rings)
        must also stay within the ISO 286 tables (up to 500 mm): ``prs-geom validate`` and
        ``build`` check it with the layout (:func:`prs_geom.geometry.mechanism.check_layout`).
    """

    pitch_mm: float = 2.0
    flank_half_angle_deg: float = 45.0
    hand: str = "right"
    engaged_teeth: int = 20

    def __post_init__(self) -> None:
        _set(self, "pitch_mm", size("pitch_mm", self.pitch_mm))
        _set(self, "flank_half_angle_deg", bounded("flank_half_angle_deg", self.flank_half_angle_deg, 10.0, 80.0,
                                                   "must be between 10 and 80 degrees"))
        choice("hand", self.hand, HANDS)
        integer("engaged_teeth", self.engaged_teeth, 2, 500)

    @property
    def beta(self) -> float:
        """Flank half-angle (rad)."""
        return math.radians(self.flank_half_angle_deg)

    @property
    def hand_sign(self) -> int:
        """+1 for a right-hand thread, -1 for a left-hand thread."""
        return 1 if self.hand == "right" else -1


def iso286_zone(fld: str, value: Any, internal: bool) -> str:
    """An ISO 286 tolerance zone symbol for a feature of one kind: a hole zone (capital
    letter, ``internal``) or a shaft zone (small letter), tabulated at some size."""
    from prs_geom.model.standards import tolerance_zone

    kind, letter = ("hole", "a capital letter, e.g. \"H6\"") if internal else ("shaft", "a small letter, e.g. \"h6\"")
    if not isinstance(value, str):
        raise DesignError(fld, value, f"must be an ISO 286 {kind} zone: {letter}")
    try:
        tolerance_zone(10.0, value)
    except (ValueError, TypeError) as exc:
        raise DesignError(fld, value, f"must be an ISO 286 {kind} zone, {letter}: {exc}") from None
    if value[0].isupper() != internal:
        raise DesignError(fld, value, f"must be an ISO 286 {kind} zone: {letter} (the feature is "
                                      f"{'internal' if internal else 'external'})")
    return value


@dataclass(frozen=True)
class Screw:
    """The screw: external, multi-start, constant pitch.

    ``major_diameter_mm``/``minor_diameter_mm`` default to a truncation of
    0.6/0.8 of the sharp-V half depth p/(4 tan beta); ``length_mm`` (threaded length)
    defaults, for an actuator, to what the nut assembly, the stroke, the over-travels and the
    run-outs need (:func:`prs_geom.geometry.actuator.actuator_layout`; it stays None here)
    and otherwise to the engaged length n p plus four pitches. Diameters are sizes (0.01 to 10000 mm), the
    length an axial length (0.01 to 1e7 mm, at least n p). ``pitch_diameter_tolerance``:
    the ISO 286 shaft zone the drawing gives the (theoretical) pitch diameter.
    """

    pitch_diameter_mm: float = 24.0
    starts: int = 5
    major_diameter_mm: float | None = None
    minor_diameter_mm: float | None = None
    length_mm: float | None = None
    pitch_diameter_tolerance: str = "h6"

    def __post_init__(self) -> None:
        _set(self, "pitch_diameter_mm", size("pitch_diameter_mm", self.pitch_diameter_mm))
        integer("starts", self.starts, 1, 20)
        for name in ("major_diameter_mm", "minor_diameter_mm"):
            _set(self, name, optional_size(name, getattr(self, name)))
        _set(self, "length_mm", optional_length("length_mm", self.length_mm))
        iso286_zone("pitch_diameter_tolerance", self.pitch_diameter_tolerance, internal=False)


@dataclass(frozen=True)
class Roller:
    """The rollers: external, single start, convex arc flank, optional graded pitch.

    ``arc_radius_mm`` is the flank arc radius r_T (arc centred on the roller axis);
    default r_r / sin(beta), tangent to a beta flank at the pitch radius.
    ``pitch_list_mm`` holds n - 1 tooth-to-tooth axial distances; absent = constant pitch.
    ``pitch_diameter_tolerance``: the ISO 286 shaft zone of the pitch diameter on the drawing.
    """

    pitch_diameter_mm: float = 8.0
    count: int = 10
    arc_radius_mm: float | None = None
    major_diameter_mm: float | None = None
    minor_diameter_mm: float | None = None
    pitch_list_mm: tuple[float, ...] | None = None
    pitch_diameter_tolerance: str = "h5"

    def __post_init__(self) -> None:
        _set(self, "pitch_diameter_mm", size("pitch_diameter_mm", self.pitch_diameter_mm))
        integer("count", self.count, 1, 60)
        for name in ("arc_radius_mm", "major_diameter_mm", "minor_diameter_mm"):
            _set(self, name, optional_size(name, getattr(self, name)))
        _set(self, "pitch_list_mm", pitch_list("pitch_list_mm", self.pitch_list_mm))
        iso286_zone("pitch_diameter_tolerance", self.pitch_diameter_tolerance, internal=False)


@dataclass(frozen=True)
class Nut:
    """The nut: internal, multi-start thread in a cylindrical body.

    For this internal thread ``major_diameter_mm`` is the groove root and
    ``minor_diameter_mm`` the crest (bore). ``outer_diameter_mm`` is the body D0.
    ``pitch_diameter_tolerance``: the ISO 286 hole zone of the pitch diameter on the drawing.
    """

    pitch_diameter_mm: float = 40.0
    starts: int = 5
    outer_diameter_mm: float = 56.0
    major_diameter_mm: float | None = None
    minor_diameter_mm: float | None = None
    pitch_list_mm: tuple[float, ...] | None = None
    pitch_diameter_tolerance: str = "H6"

    def __post_init__(self) -> None:
        _set(self, "pitch_diameter_mm", size("pitch_diameter_mm", self.pitch_diameter_mm))
        integer("starts", self.starts, 1, 20)
        _set(self, "outer_diameter_mm", size("outer_diameter_mm", self.outer_diameter_mm))
        for name in ("major_diameter_mm", "minor_diameter_mm"):
            _set(self, name, optional_size(name, getattr(self, name)))
        _set(self, "pitch_list_mm", pitch_list("pitch_list_mm", self.pitch_list_mm))
        iso286_zone("pitch_diameter_tolerance", self.pitch_diameter_tolerance, internal=True)


@dataclass(frozen=True)
class Material:
    """Linear elastic material: Young's modulus E (MPa), Poisson's ratio nu and the linear
    thermal expansion coefficient alpha (1/K; measurements refer to 20 degC, ISO 1); its
    density (kg/m^3) and the name the parts list prints; the grade (designation and
    material number, e.g. "100Cr6 (1.3505)") and the heat treatment the part drawing
    prints (empty: not specified, and the drawing says so)."""

    youngs_modulus_mpa: float = 212_000.0
    poisson_ratio: float = 0.3
    thermal_expansion_per_k: float = 11.5e-6
    density_kg_m3: float = 7850.0
    name: str = "steel"
    grade: str = ""
    heat_treatment: str = ""

    def __post_init__(self) -> None:
        # from magnesium alloys (1740) to tungsten carbide (15600) with margin
        _set(self, "density_kg_m3", bounded("density_kg_m3", self.density_kg_m3, 500.0, 25000.0,
                                            "must be from 500 to 25000 kg/m^3 (steel: 7850)", positive))
        # the raw length: the parts list and report.json carry the name as written
        if not isinstance(self.name, str) or not self.name.strip() or len(self.name) > 60:
            raise DesignError("name", self.name, "must be a material name of 1 to 60 characters")
        for key in ("grade", "heat_treatment"):
            value = getattr(self, key)
            if not isinstance(value, str) or len(value) > 60 or "\n" in value:
                raise DesignError(key, value, "must be one line of at most 60 characters (empty: not specified)")
        # engineering solids span about 1 GPa (polymers) to 1.2 TPa (diamond); far outside,
        # the tooth compliances vanish or explode and the load system loses its conditioning
        _set(self, "youngs_modulus_mpa", bounded("youngs_modulus_mpa", self.youngs_modulus_mpa, 1e3, 1e7,
                                                 "must be from 1e3 to 1e7 MPa (1 GPa to 10 TPa)", positive))
        nu = real("poisson_ratio", self.poisson_ratio)
        if not 0.0 <= nu < 0.5:
            raise DesignError("poisson_ratio", self.poisson_ratio, "must be in [0, 0.5)")
        _set(self, "poisson_ratio", nu)
        # engineering metals and polymers lie between about 0.5e-6 (Invar) and 2e-4 1/K
        _set(self, "thermal_expansion_per_k", bounded("thermal_expansion_per_k", self.thermal_expansion_per_k,
                                                      0.0, 1e-3, "must be in [0, 0.001] 1/K (steel: 11.5e-6)"))


#: The threaded parts' default grade and heat treatment: a through-hardening rolling-bearing
#: steel (ISO 683-17) at rolling-contact hardness, as for ball and roller screw threads.
THREAD_STEEL_GRADE = "100Cr6 (1.3505)"
THREAD_STEEL_HEAT_TREATMENT = "hardened and tempered, 58-62 HRC"


def _thread_steel() -> Material:
    return Material(grade=THREAD_STEEL_GRADE, heat_treatment=THREAD_STEEL_HEAT_TREATMENT)


@dataclass(frozen=True)
class Materials:
    """One material per part; the threaded parts default to :data:`THREAD_STEEL_GRADE`,
    hardened (the carrier's and the retaining ring's grade are the designer's to set)."""

    screw: Material = field(default_factory=_thread_steel)
    roller: Material = field(default_factory=_thread_steel)
    nut: Material = field(default_factory=_thread_steel)
    carrier: Material = field(default_factory=Material)
    retaining_ring: Material = field(default_factory=Material)


@dataclass(frozen=True)
class Loading:
    """Design load and installation (docs/theory/loads.md).

    ``axial_load_n`` is the external axial load F0 (N) carried by all rollers together, from
    1 N to 1e10 N (:data:`~prs_geom.model.validation.LOAD_RANGE_N`: below 1 N the teeth
    deflect by nanometres and the load model loses its conditioning; up to 1e10 N the numbers
    stay finite and an absurd load gets failed verdicts; the plausibility warnings start at
    1e7 N). The load must also suit the load model of the design
    (:func:`prs_geom.analysis.loads.check_load_scale`).
    ``installation``: "tension-compression" (screw pulled, nut pushed, loads enter from the
    same end) or "compression-compression".
    """

    axial_load_n: float = 20_000.0
    installation: str = "tension-compression"

    def __post_init__(self) -> None:
        _set(self, "axial_load_n", force("axial_load_n", self.axial_load_n))
        choice("installation", self.installation, INSTALLATIONS)


#: Tooth-width conventions of the Yamamoto tooth terms (docs/theory/loads.md, "Tooth width").
TOOTH_WIDTHS = ("circumference-share", "ring", "contact-ellipse", "unit")
#: Tooth-compliance models of the load model (docs/theory/fe.md).
COMPLIANCE_MODELS = ("analytic", "fe")


@dataclass(frozen=True)
class LoadSettings:
    """Settings of the load-distribution model (docs/theory/loads.md).

    ``tooth_width``: the circumferential width over which the Yamamoto tooth terms (given per
    unit width) spread one contact load:

    * ``"circumference-share"`` (default): the part's pitch circumference divided by the
      contacts on one tooth ring: pi d_s / z (screw), pi d_n / z (nut), pi d_r (roller, one
      contact per flank);
    * ``"ring"``: the whole pitch circumference pi d of every part;
    * ``"contact-ellipse"``: the circumferential diameter 2 b of the Hertz contact ellipse at
      the design load;
    * ``"unit"``: 1 mm (the formulas as published, per unit width).

    ``compliance``: the linear tooth compliance of the load model:

    * ``"analytic"`` (default): the diagonal Yamamoto terms at ``tooth_width``;
    * ``"fe"``: the axisymmetric finite-element influence matrices of the teeth, coupled
      between neighbouring teeth and between a roller's two flanks (docs/theory/fe.md;
      needs the optional extra ``prs-geom[fe]``; computed once per geometry and material and
      cached). ``tooth_width`` then only sets the analytic model of the model-risk study.
    """

    tooth_width: str = "circumference-share"
    compliance: str = "analytic"

    def __post_init__(self) -> None:
        choice("tooth_width", self.tooth_width, TOOTH_WIDTHS)
        choice("compliance", self.compliance, COMPLIANCE_MODELS)


#: Distributions of a tolerance: uniform within +-T, or normal with T = 3 sigma.
DISTRIBUTIONS = ("uniform", "normal")
#: Largest tolerance accepted (um): beyond this the errors are not tolerances but a
#: different design, and the linearisations of the error model no longer hold.
MAX_TOLERANCE_UM = 100.0
#: Accepted range of ``tolerances.load_fractions`` (fractions of the design load): below 1 %
#: the tooth approach is a few nanometres against tolerances of micrometres (the study would
#: only count which tooth touches first); above 10 times it is another design load.
LOAD_FRACTION_RANGE = (0.01, 10.0)
#: Per-tooth flank tolerance lists of :class:`Tolerances`: (field, part, mating contact).
FLANK_FIELDS = ("screw_flank_um", "roller_screw_flank_um", "roller_nut_flank_um", "nut_flank_um")


def _tolerance(fld: str, value: Any, hi: float = MAX_TOLERANCE_UM) -> float:
    return bounded(fld, value, 0.0, hi, f"must be in [0, {hi:g}]")


@dataclass(frozen=True)
class Tolerances:
    """The manufacturing error model of a design (docs/theory/tolerances.md).

    Every tolerance T is a half-width: an error lies within +-T (``distribution`` "uniform")
    or has standard deviation T / 3 ("normal"). All in micrometres (um) or kelvin (K); 0
    switches a term off.

    * ``flank_um``: axial position of every loaded flank of every tooth of every part
      (screw, each roller's nut-side and screw-side flank, nut), independent per flank and
      per roller; the per-tooth lists (n values each, tooth 1 at the loaded end) override it
      for their flank: ``screw_flank_um``, ``roller_screw_flank_um``,
      ``roller_nut_flank_um``, ``nut_flank_um``.
    * ``roller_diameter_um``: pitch-diameter error of each roller (on the diameter).
    * ``screw_eccentricity_um``, ``nut_eccentricity_um``: radial offset of the screw or nut
      thread axis from the common axis (half the radial run-out), random direction.
    * ``lead_um``: error of the base lead of each part, as the axial error accumulated over
      the engaged length (n - 1) p (screw, each roller, nut independently).
    * ``temperature_k``: temperature of each part (screw, rollers together, nut) against
      the others; each part's pitch grows by its ``materials.*.thermal_expansion_per_k``.
    * ``samples``, ``seed``, ``load_fractions``: the Monte Carlo study ``prs-geom build``
      runs when the design has this section (load fractions of ``loading.axial_load_n``,
      each from 0.01 to 10, :data:`LOAD_FRACTION_RANGE`).
    * ``source``: where the numbers come from; ``target_ldc`` and ``confidence``: the target
      of a tolerance synthesis that wrote them (``prs-geom tolerance --target-ldc``).
    """

    distribution: str = "uniform"
    flank_um: float = 0.0
    screw_flank_um: tuple[float, ...] | None = None
    roller_screw_flank_um: tuple[float, ...] | None = None
    roller_nut_flank_um: tuple[float, ...] | None = None
    nut_flank_um: tuple[float, ...] | None = None
    roller_diameter_um: float = 0.0
    screw_eccentricity_um: float = 0.0
    nut_eccentricity_um: float = 0.0
    lead_um: float = 0.0
    temperature_k: float = 0.0
    samples: int = 1000
    seed: int = 0
    load_fractions: tuple[float, ...] = (1.0,)
    source: str = "entered by the designer"
    target_ldc: float | None = None
    confidence: float | None = None

    def __post_init__(self) -> None:
        choice("distribution", self.distribution, DISTRIBUTIONS)
        for name in ("flank_um", "roller_diameter_um", "screw_eccentricity_um", "nut_eccentricity_um",
                     "lead_um"):
            _set(self, name, _tolerance(name, getattr(self, name)))
        _set(self, "temperature_k", _tolerance("temperature_k", self.temperature_k, 200.0))
        for name in FLANK_FIELDS:
            v = getattr(self, name)
            if v is None:
                continue
            if isinstance(v, (str, bytes, dict)) or not hasattr(v, "__iter__"):
                raise DesignError(name, v, "must be a list of tolerances in um, one per engaged tooth")
            _set(self, name, tuple(_tolerance(f"{name}[{k}]", x) for k, x in enumerate(v)))
        _set(self, "samples", integer("samples", self.samples, 1, 10_000_000))
        _set(self, "seed", integer("seed", self.seed, 0, 2 ** 63 - 1))
        fr = self.load_fractions
        if isinstance(fr, (str, bytes, dict)) or not hasattr(fr, "__iter__") or len(fr) == 0:
            raise DesignError("load_fractions", fr, "must be a non-empty list of load fractions")
        out = []
        lo, hi = LOAD_FRACTION_RANGE
        for k, x in enumerate(fr):
            v = positive(f"load_fractions[{k}]", x)
            if v > hi:
                raise DesignError(f"load_fractions[{k}]", x, f"must be at most {hi:g} (fractions of the design load)")
            if v < lo:
                raise DesignError(f"load_fractions[{k}]", x,
                                  f"must be at least {lo:g} (1 % of the design load; below it the teeth deflect by "
                                  f"nanometres against tolerances of micrometres)")
            out.append(v)
        _set(self, "load_fractions", tuple(out))
        if not isinstance(self.source, str):
            raise DesignError("source", self.source, "must be text")
        if self.target_ldc is not None:
            t = real("target_ldc", self.target_ldc)
            if t < 1.0:
                raise DesignError("target_ldc", self.target_ldc, "must be >= 1 (the mean tooth carries 1)")
            _set(self, "target_ldc", t)
        if self.confidence is not None:
            c = real("confidence", self.confidence)
            if not 0.0 < c < 1.0:
                raise DesignError("confidence", self.confidence, "must be in (0, 1)")
            _set(self, "confidence", c)

    def flank_tolerances_um(self, n: int) -> dict[str, tuple[float, ...]]:
        """Per-tooth tolerance (um) of every flank field (:data:`FLANK_FIELDS`), n values each."""
        return {name: getattr(self, name) if getattr(self, name) is not None else (self.flank_um,) * n
                for name in FLANK_FIELDS}

    @property
    def any_error(self) -> bool:
        """True when some term has a tolerance above zero."""
        flanks = any(v is not None and max(v, default=0.0) > 0 for v in
                     (getattr(self, f) for f in FLANK_FIELDS))
        return flanks or any(getattr(self, k) > 0 for k in (
            "flank_um", "roller_diameter_um", "screw_eccentricity_um", "nut_eccentricity_um", "lead_um",
            "temperature_k"))


@dataclass(frozen=True)
class ContactSettings:
    """Settings of the contact solver (docs/theory/contact.md).

    ``clearance_mm``: axial clearance the corrected screw diameter leaves at the
    screw-roller contact (0 = line contact without interference).
    ``precision_mm``: tolerance on that clearance when correcting the diameter.
    """

    clearance_mm: float = 0.0
    precision_mm: float = 1e-10

    def __post_init__(self) -> None:
        _set(self, "clearance_mm", bounded("clearance_mm", self.clearance_mm, 0.0, 0.1, "must be in [0, 0.1] mm"))
        _set(self, "precision_mm", bounded("precision_mm", self.precision_mm, 1e-13, 1e-4,
                                           "must be in [1e-13, 1e-4] mm", positive))


@dataclass(frozen=True)
class MeshSettings:
    """Tessellation settings.

    ``chord_tolerance_mm``: the largest distance allowed between the mesh and the analytic
    surface (mm); from 0.1 um to 0.1 mm.
    """

    chord_tolerance_mm: float = 0.01

    def __post_init__(self) -> None:
        _set(self, "chord_tolerance_mm", bounded("chord_tolerance_mm", self.chord_tolerance_mm, 1e-4, 0.1,
                                                 "must be from 0.0001 mm (0.1 um) to 0.1 mm", positive))


@dataclass(frozen=True)
class GearSettings:
    """The synchronising spur gears: a gear on each roller end meshing with a ring gear at
    each nut end (docs/theory/gears.md).

    The gears' working pitch diameters are fixed by the thread (roller gear m z_g = d_r,
    ring z_ring = (d_n / d_r) z_g), so the designer chooses the module (``module_mm``, or
    none: the largest ISO 54 module that gives whole tooth numbers and passes every check),
    the pressure angle, the total circumferential backlash (half as tooth thinning on each
    gear) and the face width (none: two thread pitches). Profile shift and the ring
    addendum follow from the rule of :func:`prs_geom.geometry.gear_pair.default_gear_pair`.
    ``enabled = false`` leaves the gears out of meshes, checks and report.

    For the drawings: ``accuracy_grade``, the ISO 1328-1 flank tolerance class (1 to 11);
    ``thickness_tolerance_mm``, the tooth thickness tolerance T_sn below the thinned
    (backlash) tooth, which gives the lower deviation of the span and over-pins sizes;
    ``tip_tolerance`` and ``ring_tip_tolerance``, the ISO 286 zones of the roller gear's tip
    diameter (a shaft zone) and of the ring gear's (a hole zone).
    """

    enabled: bool = True
    module_mm: float | None = None
    pressure_angle_deg: float = 20.0
    backlash_mm: float = 0.04
    face_width_mm: float | None = None
    accuracy_grade: int = 6
    thickness_tolerance_mm: float = 0.02
    tip_tolerance: str = "h11"
    ring_tip_tolerance: str = "H11"

    def __post_init__(self) -> None:
        if not isinstance(self.enabled, bool):
            raise DesignError("enabled", self.enabled, "must be true or false")
        _set(self, "module_mm", optional_size("module_mm", self.module_mm))
        _set(self, "pressure_angle_deg", bounded("pressure_angle_deg", self.pressure_angle_deg, 14.5, 30.0,
                                                 "must be from 14.5 to 30 deg"))
        _set(self, "backlash_mm", bounded("backlash_mm", self.backlash_mm, 0.0, 1.0, "must be from 0 to 1 mm"))
        _set(self, "face_width_mm", optional_size("face_width_mm", self.face_width_mm))
        integer("accuracy_grade", self.accuracy_grade, 1, 11)
        _set(self, "thickness_tolerance_mm", bounded("thickness_tolerance_mm", self.thickness_tolerance_mm, 0.001,
                                                     1.0, "must be from 0.001 to 1 mm"))
        iso286_zone("tip_tolerance", self.tip_tolerance, internal=False)
        iso286_zone("ring_tip_tolerance", self.ring_tip_tolerance, internal=True)


#: How the carriers are held radially (docs/theory/mechanism.md): running clear of the screw
#: and of the nut bore, or guided in the nut bore with ``mechanism.carrier_fit``.
CARRIER_GUIDANCE = ("clear", "nut")


@dataclass(frozen=True)
class MechanismSettings:
    """The parts that make the three threads a mechanism (docs/theory/mechanism.md): two
    carriers with z journal bores, a journal at each roller end beyond its gear, a DIN 472
    internal retaining ring in a groove at each nut end, and the nut ends that carry the
    ring gears and the grooves.

    Every size left out follows the rule of :func:`prs_geom.geometry.mechanism.layout`:
    journal diameter 0.6 x the roller root diameter rounded down to 0.5 mm, carrier
    thickness 1.5 x the journal diameter rounded up to 0.5 mm, retaining ring the smallest
    DIN 472 bore that takes the carrier with its radial clearance. Fits are ISO 286 symbols
    (hole/shaft, e.g. "H7/g6"); ``length_tolerance`` is the ISO 286 zone of every axial
    length of the stack-up. ``enabled = false`` leaves them out (three threads and gears).

    The standard tables are read here for what this section states alone: a given
    ``ring_bore_mm`` must be a DIN 472 bore (8 to 200 mm, table sizes only), a given
    ``journal_diameter_mm`` a size the ISO 286 tables hold for ``journal_fit`` and a given
    ``carrier_thickness_mm`` one they hold for ``length_tolerance`` (up to 500 mm). What needs
    the whole design (the stack-up, the ring a carrier needs) is checked by
    :func:`prs_geom.geometry.mechanism.check_layout`, which ``prs-geom validate`` and ``build``
    run before any meshing.
    """

    enabled: bool = True
    journal_diameter_mm: float | None = None
    journal_fit: str = "H7/g6"
    carrier_thickness_mm: float | None = None
    carrier_guidance: str = "clear"
    carrier_fit: str = "H8/f7"
    carrier_radial_clearance_mm: float = 0.25
    roller_end_play_mm: float = 0.1
    ring_play_mm: float = 0.1
    ring_bore_mm: float | None = None
    length_tolerance: str = "js11"

    def __post_init__(self) -> None:
        if not isinstance(self.enabled, bool):
            raise DesignError("enabled", self.enabled, "must be true or false")
        _set(self, "journal_diameter_mm", optional_size("journal_diameter_mm", self.journal_diameter_mm))
        _set(self, "carrier_thickness_mm", optional_size("carrier_thickness_mm", self.carrier_thickness_mm))
        _set(self, "ring_bore_mm", optional_size("ring_bore_mm", self.ring_bore_mm))
        choice("carrier_guidance", self.carrier_guidance, CARRIER_GUIDANCE)
        for name in ("carrier_radial_clearance_mm", "roller_end_play_mm", "ring_play_mm"):
            _set(self, name, bounded(name, getattr(self, name), 0.0, 5.0, "must be from 0 to 5 mm"))
        from prs_geom.model.standards import Fit, tolerance_zone

        for name in ("journal_fit", "carrier_fit"):
            try:
                Fit.parse(getattr(self, name))
            except (ValueError, TypeError) as exc:
                raise DesignError(name, getattr(self, name), f"must be an ISO 286 fit such as \"H7/g6\": {exc}")
        try:
            tolerance_zone(10.0, self.length_tolerance)
        except (ValueError, TypeError) as exc:
            raise DesignError("length_tolerance", self.length_tolerance,
                              f"must be an ISO 286 tolerance zone such as \"js11\": {exc}")
        self._table_lookups()

    def _table_lookups(self) -> None:
        """The standard-table look-ups of the values given here (class docstring)."""
        from prs_geom.model.standards import Fit, StandardTableError, din472_ring, tolerance_zone

        if self.ring_bore_mm is not None:
            try:
                din472_ring(self.ring_bore_mm)
            except StandardTableError as exc:
                raise DesignError("ring_bore_mm", self.ring_bore_mm, f"must be a DIN 472 bore size: {exc}") from None
        if self.journal_diameter_mm is not None:
            try:
                Fit.parse(self.journal_fit).limits(self.journal_diameter_mm)
            except StandardTableError as exc:
                raise DesignError("journal_diameter_mm", self.journal_diameter_mm,
                                  f"the journal fit {self.journal_fit} cannot be looked up there: {exc}") from None
        if self.carrier_thickness_mm is not None:
            try:
                tolerance_zone(self.carrier_thickness_mm, self.length_tolerance)
            except StandardTableError as exc:
                raise DesignError("carrier_thickness_mm", self.carrier_thickness_mm,
                                  f"the stack-up zone {self.length_tolerance} cannot be looked up there: "
                                  f"{exc}") from None


#: End-support cases of the screw for critical speed and buckling (docs/theory/ratings.md):
#: the end nearer the nut first, "supported" = a radial bearing that lets the end tilt.
END_SUPPORTS = ("fixed-fixed", "fixed-supported", "supported-supported", "fixed-free")


@dataclass(frozen=True)
class Supports:
    """How the screw is held, for its critical speed and buckling load (docs/theory/ratings.md).

    For an actuator (``[actuator]``) every length and fixity comes from the geometry: the
    bearing positions, and the nut at its worst stroke end
    (:func:`prs_geom.geometry.actuator.support_spans`); a value given here overrides it and
    the build warns that it differs from the geometry. Without an actuator:
    ``unsupported_length_mm``: free length between the bearings (or bearing and nut) that
    bends and buckles (mm, 0.01 to 1e7: an axial length, the ratings go as 1/L^2);
    absent = ``screw.length_mm``. ``critical_speed_ends`` and
    ``buckling_ends``: the end fixity of each case, one of :data:`END_SUPPORTS` (a shaft
    may be mounted differently for whirl, where the nut does not hold it, than for
    buckling); absent = "fixed-supported". ``buckling_safety``: the permissible buckling load is the Euler load divided
    by this (>= 1). ``critical_speed_factor``: the permissible speed is this fraction of the
    first whirling speed (0.1 to 1; catalogues use 0.5 to 0.8, and a permissible speed of a
    few per cent of the whirling speed no longer says anything about it).
    """

    unsupported_length_mm: float | None = None
    critical_speed_ends: str | None = None
    buckling_ends: str | None = None
    buckling_safety: float = 2.0
    critical_speed_factor: float = 0.8

    def __post_init__(self) -> None:
        _set(self, "unsupported_length_mm", optional_length("unsupported_length_mm", self.unsupported_length_mm))
        for name in ("critical_speed_ends", "buckling_ends"):
            if getattr(self, name) is not None:
                choice(name, getattr(self, name), END_SUPPORTS)
        _set(self, "buckling_safety", bounded("buckling_safety", self.buckling_safety, 1.0, 20.0,
                                              "must be from 1 to 20"))
        _set(self, "critical_speed_factor", bounded(
            "critical_speed_factor", self.critical_speed_factor, 0.1, 1.0,
            "must be from 0.1 to 1 (catalogues use 0.5 to 0.8)"))


#: Reliabilities (%) the life can be stated for: ISO 3408-5 and ISO 281:1990 tabulate a_1
#: from 90 to 99 % (docs/theory/ratings.md).
RELIABILITY_RANGE = (90.0, 99.0)
#: Default of ``rating.required_static_safety``: the lower limit of the static safety factor
#: f_s = C_0a / F_max a rolling-screw maker's catalogue gives for loads without vibration or
#: impact (THK ball screw selection, "static safety factor": 2 without, 5 with vibration or
#: impact). A catalogue value, not a standard's.
DEFAULT_REQUIRED_STATIC_SAFETY = 2.0
#: Accepted range of ``rating.required_static_safety``: below 1 the load would exceed the
#: static rating; above 20 the check no longer says anything about the contacts.
REQUIRED_STATIC_SAFETY_RANGE = (1.0, 20.0)
#: Accepted range of ``rating.speed_rpm`` (rpm): from one turn in 100 minutes (the life in
#: hours, L / (60 n), stays finite; 5e-324 rpm overflowed it) to 100 000 rpm.
SPEED_RANGE_RPM = (0.01, 1e5)
#: Accepted range of ``rating.life_hours`` (h): a target life of less than an hour is no
#: rating question; 1e7 h is more than a thousand years.
LIFE_RANGE_HOURS = (1.0, 1e7)
#: Accepted range of ``rating.dn_limit_mm_rpm`` (mm/min): makers state 50 000 to 300 000 for
#: ball and roller screws; below 1000 the permissible speed of any size is under 1 rpm.
DN_LIMIT_RANGE_MM_RPM = (1e3, 1e7)


@dataclass(frozen=True)
class RatingSettings:
    """Inputs of the ratings, life and efficiency (docs/theory/ratings.md).

    ``friction_coefficient``: Coulomb friction mu on the thread flanks; the friction angle
    is rho' = atan(mu / cos(beta)). ``speed_rpm``: mean screw speed for the life in hours
    when no spectrum gives one. ``life_hours``: target life for the required dynamic load
    rating. ``speed_rpm`` from 0.01 to 1e5 rpm, ``life_hours`` from 1 to 1e7 h
    (:data:`SPEED_RANGE_RPM`, :data:`LIFE_RANGE_HOURS`). ``reliability_pct``: reliability of
    the stated life (90 to 99 %, factor a_1).
    ``operating_factor``: f_w >= 1 on the load (shocks, vibration). ``static_pressure_limit_mpa``:
    the Hertz pressure of the static load rating (4200 MPa for hardened bearing steel in
    point contact, ISO 76). ``preload_n``: preload of the double-nut option, 1 to 1e10 N like
    every force (:data:`~prs_geom.model.validation.LOAD_RANGE_N`); absent = design load /
    2^(3/2), the preload a Hertzian double nut loses exactly at the design load.
    ``dn_limit_mm_rpm``: the nut speed limit as nominal diameter x speed (mm/min), the maker's
    figure for the roller screw (1e3 to 1e7, :data:`DN_LIMIT_RANGE_MM_RPM`).
    ``required_static_safety``: the smallest static
    safety s_0 = C_0a / F_max the limit checks accept (1 to 20); default 2, the lower limit
    a rolling-screw maker's catalogue gives for loads without vibration or impact (THK ball
    screw selection, "static safety factor": f_s >= 2 without, >= 5 with vibration or
    impact); raise it for shocks.
    """

    friction_coefficient: float = 0.025
    speed_rpm: float = 100.0
    life_hours: float = 20_000.0
    reliability_pct: float = 90.0
    operating_factor: float = 1.0
    static_pressure_limit_mpa: float = 4200.0
    preload_n: float | None = None
    dn_limit_mm_rpm: float = 150_000.0
    required_static_safety: float = DEFAULT_REQUIRED_STATIC_SAFETY

    def __post_init__(self) -> None:
        _set(self, "friction_coefficient", bounded("friction_coefficient", self.friction_coefficient, 0.0, 0.5,
                                                   "must be in [0, 0.5]"))
        _set(self, "speed_rpm", bounded("speed_rpm", self.speed_rpm, *SPEED_RANGE_RPM,
                                        "must be from 0.01 to 100000 rpm", positive))
        _set(self, "life_hours", bounded("life_hours", self.life_hours, *LIFE_RANGE_HOURS,
                                         "must be from 1 to 1e7 hours", positive))
        _set(self, "reliability_pct", bounded(
            "reliability_pct", self.reliability_pct, *RELIABILITY_RANGE,
            "must be from 90 to 99 % (the range of the a_1 table of ISO 3408-5 / ISO 281:1990)"))
        _set(self, "operating_factor", bounded("operating_factor", self.operating_factor, 1.0, 5.0,
                                               "must be from 1 to 5"))
        _set(self, "static_pressure_limit_mpa", bounded(
            "static_pressure_limit_mpa", self.static_pressure_limit_mpa, 1000.0, 6000.0,
            "must be from 1000 to 6000 MPa (hardened steel: 4000 to 4200)"))
        _set(self, "preload_n", optional_force("preload_n", self.preload_n))
        _set(self, "dn_limit_mm_rpm", bounded("dn_limit_mm_rpm", self.dn_limit_mm_rpm, *DN_LIMIT_RANGE_MM_RPM,
                                              "must be from 1000 to 1e7 mm/min (makers state 50000 to 300000)",
                                              positive))
        _set(self, "required_static_safety", bounded(
            "required_static_safety", self.required_static_safety, *REQUIRED_STATIC_SAFETY_RANGE,
            "must be from 1 to 20 (s_0 = C_0a / F_max; catalogues ask 2 without and 5 with vibration or impact)"))


# --------------------------------------------------------------------------- assembly
@dataclass(frozen=True)
class PRSDesign:
    """A complete planetary roller screw design.

    Construction resolves every defaulted dimension (truncation diameters, roller arc
    radius, screw length) to a number, then checks the cross-part rules. A resolved design
    saved and loaded again compares equal to itself.

    Examples
    --------
    >>> import prs_geom as pg
    >>> from prs_geom.model.design import Roller
    >>> design = pg.PRSDesign(name="six-rollers", roller=Roller(count=6))
    >>> design.roller.count, design.screw.starts, design.thread.pitch_mm
    (6, 5, 2.0)
    >>> design.nut.major_diameter_mm    # resolved from the defaults: pitch diameter + 1.6 H
    40.8
    """

    name: str = "default"
    thread: Thread = field(default_factory=Thread)
    screw: Screw = field(default_factory=Screw)
    roller: Roller = field(default_factory=Roller)
    nut: Nut = field(default_factory=Nut)
    materials: Materials = field(default_factory=Materials)
    loading: Loading = field(default_factory=Loading)
    loads: LoadSettings = field(default_factory=LoadSettings)
    contact: ContactSettings = field(default_factory=ContactSettings)
    mesh: MeshSettings = field(default_factory=MeshSettings)
    gears: GearSettings = field(default_factory=GearSettings)
    mechanism: MechanismSettings = field(default_factory=MechanismSettings)
    actuator: ActuatorSettings = field(default_factory=ActuatorSettings)
    #: optional: present only when the designer states tolerances (io reads it as a table)
    tolerances: Tolerances | None = field(default=None, metadata={"section": Tolerances})
    #: optional: screw supports for critical speed and buckling (absent: the defaults of
    #: :class:`Supports`, unsupported length = screw length)
    supports: Supports | None = field(default=None, metadata={"section": Supports})
    #: optional: inputs of the ratings (absent: the defaults of :class:`RatingSettings`)
    rating: RatingSettings | None = field(default=None, metadata={"section": RatingSettings})

    def __post_init__(self) -> None:
        check_name(self.name)
        self._resolve_defaults()
        self._check()

    # -- errors ---------------------------------------------------------------
    def _error(self, fld: str, value: Any, rule: str) -> DesignError:
        """A :class:`DesignError` on ``fld``; when the user did not write that field, the
        message says which default it took and from which fields."""
        return DesignError(fld, value, rule, self.__dict__.get("_defaulted", {}).get(fld, ""))

    # -- defaults -------------------------------------------------------------
    def _resolve_defaults(self) -> None:
        p, beta = self.thread.pitch_mm, self.thread.beta
        half_depth = p / (4.0 * math.tan(beta))
        add, ded = DEFAULT_ADDENDUM_FACTOR * half_depth, DEFAULT_DEDENDUM_FACTOR * half_depth
        n = self.thread.engaged_teeth
        # the notes name the formula, the fields it reads and their values, so that an error
        # on a derived dimension says where it came from
        h_from = (f"H = thread.pitch_mm / (4 tan thread.flank_half_angle_deg) = {half_depth:.6g} mm with "
                  f"thread.pitch_mm = {p!r} and thread.flank_half_angle_deg = "
                  f"{self.thread.flank_half_angle_deg!r}")
        s, r, u = self.screw, self.roller, self.nut
        notes = {
            "screw.major_diameter_mm": f"screw.pitch_diameter_mm + 1.2 H = {s.pitch_diameter_mm!r} + 1.2 H, {h_from}",
            "screw.minor_diameter_mm": f"screw.pitch_diameter_mm - 1.6 H = {s.pitch_diameter_mm!r} - 1.6 H, {h_from}",
            "screw.length_mm": (f"(thread.engaged_teeth + 4) x thread.pitch_mm = ({n} + 4) x {p!r}"
                                if not self.has_actuator else "the nut assembly + actuator.stroke_mm + 2 x "
                                "(actuator.over_travel_mm + actuator.screw_run_out_mm)"),
            "roller.arc_radius_mm": (f"roller.pitch_diameter_mm / (2 sin thread.flank_half_angle_deg) = "
                                     f"{r.pitch_diameter_mm!r} / (2 sin {self.thread.flank_half_angle_deg!r})"),
            "roller.major_diameter_mm": f"roller.pitch_diameter_mm + 1.2 H = {r.pitch_diameter_mm!r} + 1.2 H, {h_from}",
            "roller.minor_diameter_mm": f"roller.pitch_diameter_mm - 1.6 H = {r.pitch_diameter_mm!r} - 1.6 H, {h_from}",
            "nut.major_diameter_mm": f"nut.pitch_diameter_mm + 1.6 H = {u.pitch_diameter_mm!r} + 1.6 H, {h_from}",
            "nut.minor_diameter_mm": f"nut.pitch_diameter_mm - 1.2 H = {u.pitch_diameter_mm!r} - 1.2 H, {h_from}",
        }
        defaulted = {}
        for path, how in notes.items():
            part, key = path.split(".")
            if getattr(getattr(self, part), key) is None:
                defaulted[path] = f"not in the design file: the default {how}"
        # not a dataclass field: derived bookkeeping, ignored by equality and I/O
        _set(self, "_defaulted", defaulted)

        _set(self, "screw", self._derived("screw", s, dict(
            major_diameter_mm=s.major_diameter_mm or _um(s.pitch_diameter_mm + 2 * add),
            minor_diameter_mm=s.minor_diameter_mm or _um(s.pitch_diameter_mm - 2 * ded),
            length_mm=s.length_mm or (None if self.has_actuator else (n + 4) * p),
        )))
        _set(self, "roller", self._derived("roller", r, dict(
            arc_radius_mm=r.arc_radius_mm or 0.5 * r.pitch_diameter_mm / math.sin(beta),
            major_diameter_mm=r.major_diameter_mm or _um(r.pitch_diameter_mm + 2 * add),
            minor_diameter_mm=r.minor_diameter_mm or _um(r.pitch_diameter_mm - 2 * ded),
        )))
        _set(self, "nut", self._derived("nut", u, dict(
            major_diameter_mm=u.major_diameter_mm or _um(u.pitch_diameter_mm + 2 * ded),
            minor_diameter_mm=u.minor_diameter_mm or _um(u.pitch_diameter_mm - 2 * add),
        )))

    #: What each defaultable dimension is, and what to change when its default breaks a rule.
    _DERIVED_WORDS = {
        "major_diameter_mm": ("{part} major diameter", "reduce thread.pitch_mm or give {part}.major_diameter_mm"),
        "minor_diameter_mm": ("{part} minor (root) diameter",
                              "reduce thread.pitch_mm, increase {part}.pitch_diameter_mm or give "
                              "{part}.minor_diameter_mm"),
        "length_mm": ("{part} threaded length", "reduce thread.pitch_mm or thread.engaged_teeth, or give "
                                                "{part}.length_mm"),
        "arc_radius_mm": ("{part} flank arc radius r_T", "reduce roller.pitch_diameter_mm or give "
                                                        "roller.arc_radius_mm"),
    }

    def _derived(self, part: str, spec: Any, values: dict[str, Any]) -> Any:
        """``spec`` with its defaulted dimensions filled in; a default that breaks the part's
        own rule (e.g. a negative root diameter from a huge pitch) is reported under the full
        field path, with the formula and the fields it came from, the part in words and what
        to change."""
        try:
            return replace(spec, **values)
        except DesignError as exc:
            path = f"{part}.{exc.field}"
            note = self.__dict__.get("_defaulted", {}).get(path)
            if note is None:
                raise exc.prefixed(part) from None
            what, fix = self._DERIVED_WORDS.get(exc.field, ("{part} " + exc.field, "give " + path))
            raise DesignError(path, exc.value, f"the {what.format(part=part)} {exc.rule}; "
                                               f"{fix.format(part=part)}", note) from None

    # -- rules ----------------------------------------------------------------
    def normal_half_widths(self) -> dict[str, tuple[float, float]]:
        """Normal-section half-widths (mm) of each part's tooth at its crest and of its
        groove at its root, from the design numbers (docs/theory/geometry.md).

        The tooth half-width at radius r is w(r) = p cos(lambda)/4 + delta(r) with
        delta = -tan(beta)(r - r_s) (screw), +tan(beta)(r - r_n) (nut) and
        sqrt(r_T^2 - r^2) - sqrt(r_T^2 - r_r^2) (roller arc), lambda the lead angle at the
        pitch radius; the groove half-width is p cos(lambda)/2 - w. The same profile is
        built as objects by :mod:`prs_geom.geometry.profiles` (a test checks they agree);
        the model states it here so that validation needs nothing above the model.
        """
        p, tb = self.thread.pitch_mm, math.tan(self.thread.beta)
        out = {}
        for part, spec, starts in (("screw", self.screw, self.screw.starts),
                                   ("roller", self.roller, 1), ("nut", self.nut, self.nut.starts)):
            r0 = 0.5 * spec.pitch_diameter_mm
            c = math.cos(math.atan(starts * p / (2.0 * math.pi * r0)))
            major, minor = 0.5 * spec.major_diameter_mm, 0.5 * spec.minor_diameter_mm
            crest, root = (minor, major) if part == "nut" else (major, minor)
            if part == "roller":
                rt = spec.arc_radius_mm

                def delta(r: float) -> float:
                    return math.sqrt(rt * rt - r * r) - math.sqrt(rt * rt - r0 * r0)
            else:
                sign = 1.0 if part == "nut" else -1.0

                def delta(r: float) -> float:
                    return sign * tb * (r - r0)
            w_crest = 0.25 * p * c + delta(crest)
            w_root = 0.25 * p * c + delta(root)
            out[part] = (w_crest, 0.5 * p * c - w_root)
        return out

    def _check(self) -> None:
        """The cross-part rules, in order; the first broken one raises :class:`DesignError`."""
        self._check_part_diameters()
        self._check_tooth_widths()
        self._check_radial_fits()
        self._check_lengths_and_lists()

    def _check_part_diameters(self) -> None:
        """Each pitch diameter lies between its part's minor and major diameters, and the roller
        flank arc (centred on the roller axis) reaches beyond the roller crest."""
        s, r, u = self.screw, self.roller, self.nut
        for part, spec in (("screw", s), ("roller", r), ("nut", u)):
            if not spec.minor_diameter_mm < spec.pitch_diameter_mm < spec.major_diameter_mm:
                raise self._error(f"{part}.pitch_diameter_mm", spec.pitch_diameter_mm,
                                  f"the {part} pitch diameter must lie strictly between {part}.minor_diameter_mm "
                                  f"({spec.minor_diameter_mm}) and {part}.major_diameter_mm "
                                  f"({spec.major_diameter_mm})")
        if r.arc_radius_mm <= 0.5 * r.major_diameter_mm:
            raise self._error("roller.arc_radius_mm", r.arc_radius_mm,
                              f"the roller flank arc radius must exceed the roller crest radius "
                              f"roller.major_diameter_mm / 2 = {0.5 * r.major_diameter_mm} mm (the flank arc "
                              f"is centred on the roller axis): increase roller.arc_radius_mm or reduce "
                              f"roller.major_diameter_mm")

    def _check_tooth_widths(self) -> None:
        """Tooth and groove half-widths (:meth:`normal_half_widths`) stay positive over the whole
        flank height; the message spells the formula and the fields it read."""
        p = self.thread.pitch_mm
        r = self.roller
        beta_txt = f"thread.flank_half_angle_deg = {self.thread.flank_half_angle_deg!r}"
        for part, (crest_w, root_w) in self.normal_half_widths().items():
            spec = getattr(self, part)
            starts = 1 if part == "roller" else spec.starts
            lam = math.degrees(math.atan(starts * p / (math.pi * spec.pitch_diameter_mm)))
            # the formulas of normal_half_widths with the fields they read
            if part == "roller":
                crest_f = "p cos(lambda) / 4 + sqrt(r_T^2 - r_major^2) - sqrt(r_T^2 - r_pitch^2)"
                root_f = "p cos(lambda) / 4 - sqrt(r_T^2 - r_minor^2) + sqrt(r_T^2 - r_pitch^2)"
                flank = f"r_T = roller.arc_radius_mm = {r.arc_radius_mm:.6g} mm"
            else:
                out_f, in_f = "tan(beta) (r_major - r_pitch)", "tan(beta) (r_pitch - r_minor)"
                crest_f = "p cos(lambda) / 4 - " + (in_f if part == "nut" else out_f)
                root_f = "p cos(lambda) / 4 - " + (out_f if part == "nut" else in_f)
                flank = beta_txt
            src = (f"thread.pitch_mm = {p!r}, lead angle lambda = atan({starts} p / (pi {part}.pitch_diameter_mm)) "
                   f"= {lam:.4g} deg, {part}.pitch_diameter_mm = {spec.pitch_diameter_mm!r}, {part}.major_diameter_mm "
                   f"= {spec.major_diameter_mm!r}, {part}.minor_diameter_mm = {spec.minor_diameter_mm!r}, {flank}")
            if crest_w <= 0.0:
                fld = f"{part}.minor_diameter_mm" if part == "nut" else f"{part}.major_diameter_mm"
                raise self._error(fld, getattr(spec, fld.split(".")[1]),
                                  f"the {part} tooth comes to a point below the crest: {part} tooth half-width "
                                  f"at the crest = {crest_f} = {crest_w:.4g} mm with {src}; it must be > 0: "
                                  f"reduce the crest height ({fld}) or increase thread.pitch_mm")
            if root_w <= 0.0:
                fld = f"{part}.major_diameter_mm" if part == "nut" else f"{part}.minor_diameter_mm"
                raise self._error(fld, getattr(spec, fld.split(".")[1]),
                                  f"the {part} groove closes above the root: {part} groove half-width at the "
                                  f"root = {root_f} = {root_w:.4g} mm with {src}; it must be > 0: make the root "
                                  f"shallower ({fld}) or increase thread.pitch_mm")

    def _check_radial_fits(self) -> None:
        """At the centre distance a = r_s + r_r no crest reaches the mating root, the nut body is
        thicker than its thread and neighbouring rollers clear each other."""
        s, r, u = self.screw, self.roller, self.nut
        a = 0.5 * (s.pitch_diameter_mm + r.pitch_diameter_mm)
        a_txt = (f"centre distance a = (screw.pitch_diameter_mm + roller.pitch_diameter_mm) / 2 = "
                 f"({s.pitch_diameter_mm!r} + {r.pitch_diameter_mm!r}) / 2 = {a} mm")
        if 0.5 * s.major_diameter_mm + 0.5 * r.minor_diameter_mm >= a:
            raise self._error("screw.major_diameter_mm", s.major_diameter_mm,
                              f"screw crest radius + roller root radius = {0.5 * s.major_diameter_mm:.6g} + "
                              f"{0.5 * r.minor_diameter_mm:.6g} mm must be less than the {a_txt} (crest would "
                              f"hit the roller root): reduce screw.major_diameter_mm or roller.minor_diameter_mm")
        if 0.5 * r.major_diameter_mm + 0.5 * s.minor_diameter_mm >= a:
            raise self._error("roller.major_diameter_mm", r.major_diameter_mm,
                              f"roller crest radius + screw root radius = {0.5 * r.major_diameter_mm:.6g} + "
                              f"{0.5 * s.minor_diameter_mm:.6g} mm must be less than the {a_txt} (crest would "
                              f"hit the screw root): reduce roller.major_diameter_mm or screw.minor_diameter_mm")
        if a + 0.5 * r.major_diameter_mm >= 0.5 * u.major_diameter_mm:
            raise self._error("nut.major_diameter_mm", u.major_diameter_mm,
                              f"nut root radius must exceed centre distance + roller crest "
                              f"radius = {a + 0.5 * r.major_diameter_mm} mm ({a_txt}, roller crest radius "
                              f"roller.major_diameter_mm / 2 = {0.5 * r.major_diameter_mm:.6g} mm): increase "
                              f"nut.major_diameter_mm or nut.pitch_diameter_mm")
        if a + 0.5 * r.minor_diameter_mm >= 0.5 * u.minor_diameter_mm:
            raise self._error("nut.minor_diameter_mm", u.minor_diameter_mm,
                              f"nut crest radius must exceed centre distance + roller root "
                              f"radius = {a + 0.5 * r.minor_diameter_mm} mm ({a_txt}, roller root radius "
                              f"roller.minor_diameter_mm / 2 = {0.5 * r.minor_diameter_mm:.6g} mm): increase "
                              f"nut.minor_diameter_mm or nut.pitch_diameter_mm")
        if u.outer_diameter_mm <= u.major_diameter_mm:
            raise self._error("nut.outer_diameter_mm", u.outer_diameter_mm,
                              f"the nut body must be thicker than its thread: must exceed nut.major_diameter_mm "
                              f"({u.major_diameter_mm})")
        gap = 2.0 * a * math.sin(math.pi / r.count) if r.count > 1 else math.inf
        if gap <= r.major_diameter_mm:
            raise self._error("roller.count", r.count,
                              f"{r.count} rollers on a {a} mm centre radius overlap: roller "
                              f"centre spacing 2 a sin(pi / roller.count) = {gap:.4g} mm ({a_txt}) must exceed "
                              f"the roller crest diameter roller.major_diameter_mm = {r.major_diameter_mm} mm: "
                              f"use fewer rollers or a larger screw.pitch_diameter_mm")

    def _check_lengths_and_lists(self) -> None:
        """The screw covers the engaged length; the target load-distribution coefficient, the
        flank tolerance lists and the pitch lists fit the number of engaged teeth."""
        p = self.thread.pitch_mm
        n = self.thread.engaged_teeth
        s, r, u = self.screw, self.roller, self.nut
        if s.length_mm is not None and s.length_mm < n * p:
            raise self._error("screw.length_mm", s.length_mm,
                              f"must be at least the engaged length n p = {n * p} mm (thread.engaged_teeth "
                              f"x thread.pitch_mm = {n} x {p!r})")
        tol = self.tolerances
        if tol is not None and tol.target_ldc is not None and tol.target_ldc > n:
            raise self._error("tolerances.target_ldc", tol.target_ldc,
                              f"must be at most engaged_teeth = {n} (the worst coefficient of a tooth that carries "
                              f"the whole load of its roller)")
        if tol is not None:
            for name in FLANK_FIELDS:
                v = getattr(tol, name)
                if v is not None and len(v) != n:
                    raise self._error(f"tolerances.{name}", list(v),
                                      f"must have engaged_teeth = {n} entries, has {len(v)}")
        for part, spec in (("roller", r), ("nut", u)):
            lst = spec.pitch_list_mm
            if lst is None:
                continue
            if len(lst) != n - 1:
                raise self._error(f"{part}.pitch_list_mm", list(lst),
                                  f"must have engaged_teeth - 1 = {n - 1} entries, has {len(lst)}")
            for k, pj in enumerate(lst):
                if abs(pj - p) > MAX_PITCH_DEVIATION * p:
                    raise self._error(f"{part}.pitch_list_mm[{k}]", pj,
                                      f"must be within {MAX_PITCH_DEVIATION:.0%} of the pitch "
                                      f"{p} mm (graded-pitch corrections are micrometres)")

    # -- warnings ------------------------------------------------------------
    def sizing_warnings(self) -> list[str]:
        """Standard-sizing relations (docs/theory/geometry.md) this design breaks on purpose."""
        rs, rr, rn = (0.5 * self.screw.pitch_diameter_mm, 0.5 * self.roller.pitch_diameter_mm,
                      0.5 * self.nut.pitch_diameter_mm)
        ns, nn = self.screw.starts, self.nut.starts
        out = []

        def off(x: float, y: float) -> bool:
            return abs(x - y) > SIZING_RTOL * max(abs(x), abs(y), 1.0)

        if off(rn, rs + 2 * rr):
            out.append(f"nut pitch radius {rn} != screw + 2 roller pitch radii {rs + 2 * rr}: "
                       f"the nut and roller pitch circles do not touch")
        if off(rn, nn * rr):
            out.append(f"nut pitch radius {rn} != nut starts x roller pitch radius {nn * rr}: "
                       f"nut and roller lead angles differ, rollers will drift axially")
        if ns != nn:
            out.append(f"screw starts {ns} != nut starts {nn}")
        if off(rs, (ns - 2) * rr):
            out.append(f"screw pitch radius {rs} != (screw starts - 2) x roller pitch radius "
                       f"{(ns - 2) * rr}")
        return out

    def warn(self) -> list[str]:
        """Issue a :class:`DesignWarning` for each broken sizing relation; return them."""
        msgs = self.sizing_warnings()
        for m in msgs:
            warnings.warn(m, DesignWarning, stacklevel=2)
        return msgs

    # -- derived quantities ---------------------------------------------------
    @property
    def has_actuator(self) -> bool:
        """True when the design is built as an actuator (stroke, screw ends, nut mounting):
        ``actuator.enabled`` and the mechanism it mounts (``mechanism.enabled``)."""
        return self.actuator.enabled and self.mechanism.enabled

    @property
    def graded(self) -> bool:
        """True when the roller or the nut carries a pitch list."""
        return self.roller.pitch_list_mm is not None or self.nut.pitch_list_mm is not None

    @property
    def centre_distance_mm(self) -> float:
        """Screw-roller centre distance a = r_s + r_r (mm), held fixed."""
        return 0.5 * (self.screw.pitch_diameter_mm + self.roller.pitch_diameter_mm)

    def pitch_list(self, part: str) -> tuple[float, ...]:
        """The n - 1 tooth-to-tooth pitches of ``part`` (mm); constant when not given."""
        n, p = self.thread.engaged_teeth, self.thread.pitch_mm
        if part == "screw":
            return (p,) * (n - 1)
        lst = getattr(self, part).pitch_list_mm
        return lst if lst is not None else (p,) * (n - 1)

    def with_changes(self, **sections: Any) -> "PRSDesign":
        """A new validated design with whole sections or the name replaced."""
        return replace(self, **sections)

    def constant_pitch(self) -> "PRSDesign":
        """The same design without pitch lists (every part at the constant pitch)."""
        if not self.graded:
            return self
        return replace(self, roller=replace(self.roller, pitch_list_mm=None), nut=replace(self.nut, pitch_list_mm=None))


def default_design() -> PRSDesign:
    """The built-in standard PRS: 24/8/40 mm pitch diameters, 5 starts, p = 2 mm,
    10 rollers, 20 engaged teeth, steel, 20 kN, tension-compression.

    Examples
    --------
    >>> import prs_geom as pg
    >>> d = pg.default_design()
    >>> d.screw.pitch_diameter_mm, d.roller.pitch_diameter_mm, d.nut.pitch_diameter_mm
    (24.0, 8.0, 40.0)
    >>> d.screw.starts, d.roller.count, d.loading.axial_load_n
    (5, 10, 20000.0)
    """
    return PRSDesign()

