"""The parts that make the threads a mechanism: sizes, axial layout, fits and stack-up.

Pure geometry (no mesh library, no I/O). :func:`layout` sizes, from a design and the rules
below (each overridable in the design's ``[mechanism]`` table, docs/theory/mechanism.md):

* **Roller journals**, one at each roller end beyond its gear: diameter 0.6 x the roller
  root diameter rounded down to 0.5 mm; length the carrier thickness, so that a roller
  pushed outward until its gear face meets the carrier ends flush with the carrier's
  outer face and never reaches the retaining ring.
* **Carriers**, two rings with z journal bores on the centre-distance circle at the carrier
  angles psi_k: thickness 1.5 x the journal diameter rounded up to 0.5 mm; bore running
  clear of the screw crest by ``carrier_radial_clearance_mm``; outside running clear of the
  nut end bore by the same clearance (``carrier_guidance = "clear"``) or guided in it with
  ``carrier_fit`` (``"nut"``). The inner face sits ``roller_end_play_mm`` outboard of the
  roller gear faces.
* **Retaining rings**, DIN 472, in a groove at each nut end, ``ring_play_mm`` outboard of
  the carrier: the smallest ring whose bore d1 leaves the carrier its radial clearance;
  the nut end bore is d1, the groove diameter d2, its width m, its edge distance n.
* **Nut ends**, of the nut's body, from its thread end outward: around the ring gear (the
  gear face width), then the bore d1 with the groove, ending n beyond the groove.

Axial positions are in the screw frame (z along the axis, the nut and roller threads over
[0, L], L = n p), which is also the nut frame and, along z, every roller frame. A part's
lower and upper copy are mirror images about z = L / 2.

Modelled sizes of fitted features are the middle of their ISO 286 zone, so that the
meshes sit at the mean clearance; the fit's range itself is checked analytically at both
limits (:class:`FitCheck`). Volumes are closed forms of the true (circular) shapes; the
mesh volumes are compared with them in the tests.

Every size that leaves a standard table (a journal, carrier or stack-up length beyond the
500 mm of ISO 286, a carrier too large for the 200 mm of DIN 472) is a
:class:`~prs_geom.model.errors.DesignError` naming the design field that drives it, the
table, its range and the value. :func:`check_layout` runs all of this (and the gear sizing)
without meshing: ``prs-geom validate`` and ``build`` call it before any work.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from prs_geom.model.design import PRSDesign
from prs_geom.model.errors import DesignError
from prs_geom.model.standards import (SIZE_RANGE_UPPER_MM, Fit, FitLimits, RetainingRing, StandardTableError,
                                      din472_ring, din472_sizes, tolerance_zone)

__all__ = ["ISO286_END_MM", "MIN_CARRIER_WEB_MM", "NUT_END_RELIEF_MM", "RING_GAP_RAD", "Dimension", "EndLayout",
           "FitCheck", "MechanismLayout", "StackUp", "check_layout", "layout", "layout_warnings"]

#: Opening of the modelled retaining ring (rad): DIN 472 rings are open C shapes; the lugs
#: and their holes are not modelled (their volume is a few per cent of the ring's).
RING_GAP_RAD = math.radians(30.0)
#: The nut ends are relieved by this much on the radius (mm): meeting the threaded part in its
#: end plane on the same outer cylinder, two differently sampled polygons would leave
#: vertices a few nanometres apart there, which a mesh file without topology (STL) cannot
#: tell from one vertex (the union would read back as not closed).
NUT_END_RELIEF_MM = 0.1
#: Smallest radial web (mm) between a carrier's journal bore and its inner or outer edge.
MIN_CARRIER_WEB_MM = 0.5


def _floor_to(x: float, step: float) -> float:
    return math.floor(x / step + 1e-9) * step


def _ceil_to(x: float, step: float) -> float:
    return math.ceil(x / step - 1e-9) * step


@dataclass(frozen=True)
class FitCheck:
    """A journal (or carrier) fit at its nominal diameter: the ISO 286 limits, the
    diametral clearance range they allow and the modelled (mid-zone) sizes (mm)."""

    feature: str
    fit: str
    nominal_diameter_mm: float
    limits: FitLimits
    hole_diameter_mm: float      # modelled: middle of the hole zone
    shaft_diameter_mm: float     # modelled: middle of the shaft zone

    @property
    def min_clearance_mm(self) -> float:
        """Smallest diametral clearance (mm) of the zones: largest shaft in smallest hole."""
        return self.limits.min_clearance_mm

    @property
    def max_clearance_mm(self) -> float:
        """Largest diametral clearance (mm) of the zones: smallest shaft in largest hole."""
        return self.limits.max_clearance_mm

    @property
    def modelled_clearance_mm(self) -> float:
        """Diametral clearance of the modelled sizes."""
        return self.hole_diameter_mm - self.shaft_diameter_mm

    @property
    def passed(self) -> bool:
        """A running fit: positive clearance at both limits of the zones."""
        return self.min_clearance_mm > 0.0

    def report(self) -> dict:
        """The fit as report.json writes it (sizes and clearances in mm)."""
        return {"feature": self.feature, "fit": self.fit,
                "nominal_diameter_mm": self.nominal_diameter_mm,
                "hole_limits_mm": [self.limits.hole.min_size_mm, self.limits.hole.max_size_mm],
                "shaft_limits_mm": [self.limits.shaft.min_size_mm, self.limits.shaft.max_size_mm],
                "min_clearance_mm": self.min_clearance_mm, "max_clearance_mm": self.max_clearance_mm,
                "modelled_clearance_mm": self.modelled_clearance_mm, "passed": self.passed}


def _fit_check(feature: str, symbol: str, diameter: float) -> FitCheck:
    lim = Fit.parse(symbol).limits(diameter)
    hole = diameter + 0.5 * (lim.hole.lower_mm + lim.hole.upper_mm)
    shaft = diameter + 0.5 * (lim.shaft.lower_mm + lim.shaft.upper_mm)
    return FitCheck(feature, symbol, diameter, lim, hole, shaft)


@dataclass(frozen=True)
class Dimension:
    """One toleranced length of the axial stack-up (mm)."""

    name: str
    nominal_mm: float
    lower_mm: float      # deviation
    upper_mm: float      # deviation
    #: +1: a longer dimension gives more play (the nut's groove span); -1: less
    sense: int
    count: int = 1

    def report(self) -> dict:
        """The dimension as report.json writes it (mm)."""
        return {"name": self.name, "nominal_mm": self.nominal_mm, "lower_deviation_mm": self.lower_mm,
                "upper_deviation_mm": self.upper_mm, "sense": self.sense, "count": self.count}


@dataclass(frozen=True)
class StackUp:
    """Axial play of the carrier-roller-carrier chain between the two retaining rings.

    The rings bear on the outer flanks of their grooves (the carriers push them outward),
    so the chain is: span between the grooves' outer flanks (nut) minus 2 ring thicknesses,
    2 carrier thicknesses and the roller length between its gear faces. Worst case: every
    dimension at the limit that reduces (or increases) the play.
    """

    dimensions: tuple[Dimension, ...]

    @property
    def nominal_mm(self) -> float:
        """Axial play (mm) with every dimension at its nominal size."""
        return sum(d.sense * d.count * d.nominal_mm for d in self.dimensions)

    @property
    def min_mm(self) -> float:
        """Worst-case smallest axial play (mm)."""
        return sum(d.sense * d.count * (d.nominal_mm + (d.lower_mm if d.sense > 0 else d.upper_mm))
                   for d in self.dimensions)

    @property
    def max_mm(self) -> float:
        """Worst-case largest axial play (mm)."""
        return sum(d.sense * d.count * (d.nominal_mm + (d.upper_mm if d.sense > 0 else d.lower_mm))
                   for d in self.dimensions)

    @property
    def passed(self) -> bool:
        """True when the play stays positive at the worst case."""
        return self.min_mm > 0.0

    def report(self) -> dict:
        """The stack-up as report.json writes it (mm)."""
        return {"chain": [d.report() for d in self.dimensions], "nominal_play_mm": self.nominal_mm,
                "min_play_mm": self.min_mm, "max_play_mm": self.max_mm, "passed": self.passed,
                "rule": "worst case; the play must stay positive at the minimum"}


@dataclass(frozen=True)
class EndLayout:
    """Axial positions (mm, screw frame) of one end's parts; ``outward`` is -1 at the
    lower end (z < 0) and +1 at the upper end (z > L)."""

    outward: int
    gear_zone: tuple[float, float]      # the roller gear / ring gear faces' span
    journal: tuple[float, float]
    carrier: tuple[float, float]
    ring: tuple[float, float]
    groove: tuple[float, float]
    nut_end: tuple[float, float]         # the nut end piece, from the thread end outward


@dataclass(frozen=True)
class MechanismLayout:
    """Every size and position of the mechanism parts of a design (mm)."""

    gear_face_width_mm: float
    ring_gear_outer_radius_mm: float | None
    journal_diameter_mm: float
    journal_fit: FitCheck
    carrier_inner_radius_mm: float
    carrier_outer_radius_mm: float
    carrier_thickness_mm: float
    carrier_fit: FitCheck | None
    centre_distance_mm: float
    roller_count: int
    ring: RetainingRing
    ring_inner_radius_mm: float
    nut_bore_radius_mm: float
    nut_outer_radius_mm: float
    ends: tuple[EndLayout, EndLayout]
    stack: StackUp

    @property
    def groove_radius_mm(self) -> float:
        """Radius of the ring groove's bottom, d2 / 2."""
        return 0.5 * self.ring.groove_diameter_mm

    @property
    def ring_outer_radius_mm(self) -> float:
        """The ring's outside as fitted: seated on the groove bottom."""
        return self.groove_radius_mm

    # closed-form volumes of the true shapes (mm^3) ---------------------------------
    @property
    def journal_volume_mm3(self) -> float:
        """Volume of one journal (mm^3): a cylinder of the modelled shaft diameter through the carrier."""
        r = 0.5 * self.journal_fit.shaft_diameter_mm
        return math.pi * r * r * self.carrier_thickness_mm

    @property
    def carrier_volume_mm3(self) -> float:
        """Volume of one carrier (mm^3): the annulus less the roller bores."""
        rb = 0.5 * self.journal_fit.hole_diameter_mm
        ring = math.pi * (self.carrier_outer_radius_mm ** 2 - self.carrier_inner_radius_mm ** 2)
        return (ring - self.roller_count * math.pi * rb * rb) * self.carrier_thickness_mm

    @property
    def ring_volume_mm3(self) -> float:
        """Volume of one retaining ring (mm^3): an open annulus (gap RING_GAP_RAD)."""
        return 0.5 * (2.0 * math.pi - RING_GAP_RAD) * (self.ring_outer_radius_mm ** 2
                                                       - self.ring_inner_radius_mm ** 2) * self.ring.thickness_mm

    @property
    def nut_end_volume_mm3(self) -> float:
        """One nut end: the sleeve around the ring gear and the bored part with its groove
        (outside radius :attr:`nut_end_outer_radius_mm`)."""
        end = self.ends[0]
        R = self.nut_end_outer_radius_mm
        v = 0.0
        if self.ring_gear_outer_radius_mm is not None:
            v += math.pi * (R * R - self.nut_end_sleeve_inner_radius_mm ** 2) * self.gear_face_width_mm
        bored = abs(end.nut_end[1] - end.nut_end[0]) - self.gear_face_width_mm
        v += math.pi * (R * R - self.nut_bore_radius_mm ** 2) * bored
        v -= math.pi * (self.groove_radius_mm ** 2 - self.nut_bore_radius_mm ** 2) * self.ring.groove_width_mm
        return v

    @property
    def nut_end_outer_radius_mm(self) -> float:
        """Outside radius of the nut ends: the nut's, relieved by :data:`NUT_END_RELIEF_MM`."""
        return self.nut_outer_radius_mm - NUT_END_RELIEF_MM

    @property
    def nut_end_sleeve_inner_radius_mm(self) -> float:
        """Inner radius of the nut end around the ring gear: a quarter into the ring gear's
        body, so that the two overlap rather than meet in one (differently sampled) cylinder."""
        assert self.ring_gear_outer_radius_mm is not None
        return self.ring_gear_outer_radius_mm - 0.25 * (self.nut_end_outer_radius_mm - self.ring_gear_outer_radius_mm)


def _zone_mm(nominal: float, symbol: str) -> tuple[float, float]:
    z = tolerance_zone(nominal, symbol)
    return z.lower_mm, z.upper_mm


#: The end of the ISO 286 tables (mm): no tolerance grade or deviation above this size.
ISO286_END_MM = float(SIZE_RANGE_UPPER_MM[-1])
_ISO286_RANGE = (f"ISO 286 tolerance grades are tabulated over 0 up to and including {ISO286_END_MM:g} mm "
                 f"(the table ends there)")


def _stack_dimension(design: PRSDesign, name: str, what: str, nominal: float, symbol: str, sense: int,
                     count: int, terms: list[tuple[str, object, float, str]], note: str = "") -> Dimension:
    """A :class:`Dimension` of the stack-up with its ISO 286 zone; a length beyond the table
    is a :class:`DesignError` on the field of ``terms`` (field, value, mm it adds, words) that
    adds the most, with the table's range and what to change."""
    try:
        lo, hi = _zone_mm(nominal, symbol)
    except StandardTableError:
        fld, value, _, _ = max(terms, key=lambda t: t[2])
        parts = " + ".join(words for *_, words in terms)
        p, n = design.thread.pitch_mm, design.thread.engaged_teeth
        L = n * p
        rest = nominal - L if any(t[0] == "thread.engaged_teeth" for t in terms) else None
        if fld == "thread.engaged_teeth" and rest is not None:
            n_max = math.floor((ISO286_END_MM - rest) / p + 1e-9)
            fix = (f"reduce thread.engaged_teeth to at most {n_max} (or thread.pitch_mm)" if n_max >= 2 else
                   "shorten the parts outside the threads")
        else:
            fix = f"reduce {fld}"
        raise DesignError(fld, value, f"{what} {nominal:.6g} mm ({parts}): {_ISO286_RANGE}, so the stack-up "
                                      f"zone mechanism.length_tolerance = \"{symbol}\" has no value for it; {fix}, "
                                      f"or leave the mechanism out (mechanism.enabled = false)", note) from None
    return Dimension(name, nominal, lo, hi, sense, count)


def layout(design: PRSDesign) -> MechanismLayout | None:
    """The mechanism parts of ``design`` (None when ``mechanism.enabled`` is false).

    Raises :class:`~prs_geom.model.errors.DesignError` naming the ``mechanism`` field when
    the parts cannot be placed (no DIN 472 ring that fits, a carrier web below
    :data:`MIN_CARRIER_WEB_MM`, a journal wider than the roller root).
    """
    m = design.mechanism
    if not m.enabled:
        return None
    from prs_geom.geometry.gear_pair import design_gear_pair, ring_gear_outer_radius

    pair = design_gear_pair(design)
    L = design.thread.engaged_teeth * design.thread.pitch_mm
    w = pair.pinion.face_width_mm if pair is not None else 0.0
    R_o = 0.5 * design.nut.outer_diameter_mm
    ring_gear_outer = ring_gear_outer_radius(design, pair) if pair is not None else None
    a = design.centre_distance_mm
    z = design.roller.count

    d_j, journal = _journal(design, pair)
    t_c = m.carrier_thickness_mm or _ceil_to(1.5 * d_j, 0.5)
    c_r = m.carrier_radial_clearance_mm
    r_in = 0.5 * design.screw.major_diameter_mm + c_r
    r_bore = 0.5 * journal.hole_diameter_mm
    if a - r_bore - r_in < MIN_CARRIER_WEB_MM:
        raise DesignError("mechanism.journal_diameter_mm", d_j,
                          f"leaves a carrier web of {a - r_bore - r_in:.3g} mm between the journal bore and "
                          f"the carrier bore (centre distance {a:g} mm, carrier bore radius {r_in:.4g} mm = "
                          f"screw crest + mechanism.carrier_radial_clearance_mm); at least "
                          f"{MIN_CARRIER_WEB_MM} mm is needed: choose a smaller journal")
    # carrier outside: the journal bores plus a web as wide as the inner one, at least 0.5 d_j
    web = max(MIN_CARRIER_WEB_MM, 0.5 * d_j, a - r_bore - r_in)
    r_out_min = a + r_bore + web
    guided = m.carrier_guidance == "nut"
    ring = _ring(design, r_out_min, c_r, guided)
    d1 = ring.bore_mm
    carrier_fit = _fit_check("carrier in nut bore", m.carrier_fit, d1) if guided else None
    r_out = 0.5 * carrier_fit.shaft_diameter_mm if carrier_fit else 0.5 * d1 - c_r
    if r_out < r_out_min - 1e-9:
        raise DesignError("mechanism.ring_bore_mm", d1,
                          f"leaves the carrier an outside radius of {r_out:.4g} mm, below the {r_out_min:.4g} mm "
                          f"its journal bores need: choose a larger DIN 472 size")
    bore_radius = 0.5 * (carrier_fit.hole_diameter_mm if carrier_fit else d1)
    # the ring's narrowest radial section b, measured from the bore
    ring_inner = 0.5 * d1 - ring.section_width_mm
    if ring_inner >= r_out:
        raise DesignError("mechanism.ring_bore_mm", d1,
                          f"the DIN 472 ring's inner edge (r = {ring_inner:.4g} mm) does not reach over the "
                          f"carrier (outside r = {r_out:.4g} mm): it would not hold it")
    g, c = m.roller_end_play_mm, m.ring_play_mm
    s = ring.thickness_mm
    if R_o - 0.5 * ring.groove_diameter_mm < MIN_CARRIER_WEB_MM:
        raise DesignError("nut.outer_diameter_mm", design.nut.outer_diameter_mm,
                          f"leaves {R_o - 0.5 * ring.groove_diameter_mm:.3g} mm of wall outside the retaining "
                          f"ring groove (d2 = {ring.groove_diameter_mm:g} mm); at least {MIN_CARRIER_WEB_MM} mm")

    ends = _end_layouts(L, w, g, t_c, c, ring)
    stack = _stack_up(design, ends, L, w, t_c, g, c, s)
    return MechanismLayout(
        gear_face_width_mm=w, ring_gear_outer_radius_mm=ring_gear_outer, journal_diameter_mm=d_j,
        journal_fit=journal, carrier_inner_radius_mm=r_in, carrier_outer_radius_mm=r_out,
        carrier_thickness_mm=t_c, carrier_fit=carrier_fit, centre_distance_mm=a, roller_count=z,
        ring=ring, ring_inner_radius_mm=ring_inner, nut_bore_radius_mm=bore_radius,
        nut_outer_radius_mm=R_o, ends=ends, stack=stack)


def _journal(design: PRSDesign, pair) -> tuple[float, FitCheck]:
    """The roller journal's diameter (given, or 0.6 x the roller root rounded down to 0.5 mm)
    and its fit in the carrier bore."""
    m = design.mechanism
    roller_root = design.roller.minor_diameter_mm
    if pair is not None:
        roller_root = min(roller_root, 2.0 * pair.pinion.root_radius_mm)
    d_j = m.journal_diameter_mm or _floor_to(0.6 * roller_root, 0.5)
    if d_j <= 0.0 or d_j >= roller_root:
        raise DesignError("mechanism.journal_diameter_mm", d_j,
                          f"must be positive and below the roller's root diameter {roller_root:.4g} mm "
                          f"(the journal steps down from the gear)")
    j_note = "" if m.journal_diameter_mm else ("not in the design file: the default 0.6 x the roller root "
                                               "diameter, rounded down to 0.5 mm")
    try:
        journal = _fit_check("roller journal in carrier bore", m.journal_fit, d_j)
    except StandardTableError as exc:
        raise DesignError("mechanism.journal_diameter_mm", d_j,
                          f"the journal fit mechanism.journal_fit = \"{m.journal_fit}\" has no value at this "
                          f"diameter ({exc}; {_ISO286_RANGE}): give a smaller mechanism.journal_diameter_mm",
                          j_note) from None
    return d_j, journal


def _ring(design: PRSDesign, r_out_min: float, c_r: float, guided: bool) -> RetainingRing:
    """The DIN 472 ring: the given size, or the smallest whose bore takes the carrier (its
    outside radius ``r_out_min`` plus the radial clearance ``c_r`` unless it is guided)."""
    m = design.mechanism
    if m.ring_bore_mm is not None:
        d1 = m.ring_bore_mm
        try:
            ring = din472_ring(d1)
        except ValueError as exc:
            raise DesignError("mechanism.ring_bore_mm", d1, str(exc)) from None
    else:
        need = 2.0 * (r_out_min + (0.0 if guided else c_r))
        sizes = [s for s in din472_sizes() if s >= need]
        if not sizes:
            raise DesignError("mechanism.ring_bore_mm", None,
                              f"no DIN 472 ring takes a carrier of {2 * r_out_min:.4g} mm outside diameter: the "
                              f"nut end bore would be {need:.4g} mm, and DIN 472 retaining rings are tabulated for "
                              f"bores of {min(din472_sizes()):g} to {max(din472_sizes()):g} mm (largest bore "
                              f"{max(din472_sizes()):g} mm; the table ends there): reduce screw.pitch_diameter_mm "
                              f"and roller.pitch_diameter_mm, or leave the mechanism out (mechanism.enabled = false)")
        ring = din472_ring(sizes[0])
    return ring


def _end_layouts(L: float, w: float, g: float, t_c: float, c: float,
                 ring: RetainingRing) -> tuple[EndLayout, EndLayout]:
    """Both ends' axial positions from the thread ends outward: gear, end play ``g``,
    carrier ``t_c``, ring play ``c``, ring in its groove, the groove's edge distance."""
    s, m_w, n_e = ring.thickness_mm, ring.groove_width_mm, ring.edge_distance_mm

    def end(outward: int) -> EndLayout:
        base = 0.0 if outward < 0 else L            # the thread end
        def span(a0: float, a1: float) -> tuple[float, float]:
            lo, hi = base + outward * a0, base + outward * a1
            return (min(lo, hi), max(lo, hi))
        gear = span(0.0, w)
        carrier = span(w + g, w + g + t_c)
        journal = span(w, w + t_c)
        ring_z = span(w + g + t_c + c, w + g + t_c + c + s)
        # the ring bears on the groove's outer flank; the groove reaches m - s back inward
        groove = span(w + g + t_c + c + s - m_w, w + g + t_c + c + s)
        nut_end = span(0.0, w + g + t_c + c + s + n_e)
        return EndLayout(outward, gear, journal, carrier, ring_z, groove, nut_end)

    return (end(-1), end(+1))


def _stack_up(design: PRSDesign, ends: tuple[EndLayout, EndLayout], L: float, w: float, t_c: float, g: float,
              c: float, s: float) -> StackUp:
    """The axial stack-up (:class:`StackUp`) with each length's ISO 286 zone."""
    m = design.mechanism
    lo, hi = ends[0], ends[1]
    groove_span = hi.groove[1] - lo.groove[0]
    roller_len = L + 2.0 * w
    tol = m.length_tolerance
    n_teeth, p = design.thread.engaged_teeth, design.thread.pitch_mm
    thread = ("thread.engaged_teeth", n_teeth, L, f"engaged length n p = {n_teeth} x {p!r} = {L:.6g} mm")
    gears_w = ("gears.face_width_mm", design.gears.face_width_mm if design.gears.face_width_mm is not None else w,
               2.0 * w, f"2 gear faces of {w:.6g} mm")
    carriers = ("mechanism.carrier_thickness_mm", t_c, 2.0 * t_c, f"2 carriers of {t_c:.6g} mm")
    plays = ("mechanism.ring_play_mm", c, 2.0 * (g + c + s),
             f"2 x (end play {g:g} + ring play {c:g} + ring {s:g}) mm")
    stack = StackUp((
        _stack_dimension(design, "nut: span between the groove outer flanks", "the nut length between the "
                         "outer flanks of its ring grooves is", groove_span, tol, +1, 1,
                         [thread, gears_w, carriers, plays]),
        # the DIN 472 thickness tolerance is not in the ring table here: taken as h11
        Dimension("retaining ring thickness s (DIN 472, h11)", s, *_zone_mm(s, "h11"), -1, 2),
        _stack_dimension(design, "carrier thickness", "the carrier thickness is", t_c, tol, -1, 2,
                         [carriers]),
        _stack_dimension(design, "roller length between gear faces", "the roller length between its gear faces is",
                         roller_len, tol, -1, 1, [thread, gears_w]),
    ))
    return stack


def check_layout(design: PRSDesign) -> MechanismLayout | None:
    """Every rule of a build that needs no meshing, for the parts beyond the threads: the end
    gears' sizing (:func:`~prs_geom.geometry.gear_pair.design_gear_pair`) and, when the design has
    a mechanism, its :func:`layout` with every standard-table look-up (ISO 286 fits and the
    stack-up zones, the DIN 472 ring). The actuator's sizes (which depend on this layout) are
    :func:`~prs_geom.geometry.actuator.actuator_layout`'s, which the same callers run next. ``prs-geom validate`` and ``build`` run it before any
    work, so that a design they accept does not fail later for a rule it could have checked.

    Returns the layout (None without a mechanism). Raises
    :class:`~prs_geom.model.errors.DesignError` naming the field; the checks whose failure a
    build reports as a warning (a fit without running clearance, a stack-up without play)
    are in :func:`layout_warnings`.
    """
    if design.mechanism.enabled:
        return layout(design)
    from prs_geom.geometry.gear_pair import design_gear_pair

    design_gear_pair(design)
    return None


def layout_warnings(lay: MechanismLayout | None) -> list[str]:
    """The analytic mechanism checks that fail (a build reports them as warnings): fits
    without clearance at the limits of their zones, an axial stack-up without play at worst
    case. One line each, naming the field to change."""
    if lay is None:
        return []
    out = []
    for fit, fld in ((lay.journal_fit, "mechanism.journal_fit"), (lay.carrier_fit, "mechanism.carrier_fit")):
        if fit is not None and not fit.passed:
            out.append(f"mechanism: the {fit.feature} fit {fit.fit} at {fit.nominal_diameter_mm:g} mm has a minimum "
                       f"clearance of {fit.min_clearance_mm * 1e3:.4g} um (a running fit needs it > 0): change {fld}")
    if not lay.stack.passed:
        out.append(f"mechanism: the axial stack-up has {lay.stack.min_mm:.4g} mm of play at worst case (it must "
                   f"stay positive): increase mechanism.ring_play_mm or mechanism.roller_end_play_mm, or choose a "
                   f"finer mechanism.length_tolerance")
    return out
