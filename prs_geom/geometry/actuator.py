"""The screw and nut as an actuator: stroke, screw ends, supports, nut mounting, run-outs.

Pure geometry (no mesh library, no I/O). :func:`actuator_layout` sizes every part outside
the mechanism from a design, its mechanism layout (:func:`prs_geom.geometry.mechanism.layout`)
and the catalogue tables of :mod:`prs_geom.model.machine_elements`, each size by a stated
rule that a key of the design's ``[actuator]`` section overrides (docs/theory/actuator.md).
Every size carries where it came from (:class:`Sized`).

Axial positions are in the screw frame (z along the axis; the nut thread over [0, L] with
the nut at mid-stroke, L = n p). The nut travels by a shift s in [-S/2, +S/2] (S the
stroke): at s the nut, its ends, carriers, rings and rollers sit s further along +z.

* **Threaded length.** Full-depth thread under the whole nut assembly (nut ends included)
  at both stroke ends plus ``over_travel_mm`` at each end; then a grinding-wheel exit of
  ``screw_run_out_mm`` (default one lead) at each thread end.
* **Fixed end** on the side where the load model holds the screw (the -z side for
  "tension-compression", +z for "compression-compression": ``face_z0``/``face_z1`` of the
  FE model), from the thread end outward: a pair of 72xx B bearings on a seat, a thread
  undercut, the KM locknut's thread, the drive journal.
* **Floating end** on the other side: one 62xx bearing on a seat, a DIN 471 ring groove and
  its collar.
* **Nut mounting** at the nut's loaded end (z < 0, where the load model and the FE model
  hold the nut): a bolted flange on the lower nut end.
* **Supports** (:class:`SupportSpans`): the critical speed spans the bearings (the pair's
  middle to the floating bearing's middle, fixed-supported; fixed-free without a floating
  bearing); buckling spans the pair's middle to the far end of the engaged thread with the
  nut at the stroke end farther from the fixed end (fixed-supported: the nut is taken as a
  support that lets the screw tilt, which is conservative).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

from prs_geom.geometry.mechanism import layout
from prs_geom.model.design import PRSDesign
from prs_geom.model.errors import DesignError
from prs_geom.model.machine_elements import (BOLT_SAFETY, ISO_4762_LENGTHS_MM, Bearing, Bolt, Key, Locknut, ShaftRing,
                                             bearing, bearing_bores, bolt, key_for_shaft, key_lengths, load_sized_bolt,
                                             locknut, locknut_bores, shaft_end, shaft_end_diameters, shaft_ring)
from prs_geom.model.standards import StandardTableError

__all__ = ["DESIGN_FILE", "FLANGE_OVERLAP_MM", "ActuatorLayout", "NutMountLayout", "PlacedBearing", "ScrewEnd", "ShaftStep", "Sized",
           "StrokeEndCheck", "SupportSpans", "actuator_layout", "screw_thread_span", "stroke_end_checks",
           "support_spans"]

#: Source of a size given in the design file.
DESIGN_FILE = "design file"
#: A flange bolt engages this many bolt diameters of thread in the housing (steel or cast iron).
BOLT_ENGAGEMENT = 1.5
#: The nut flange reaches this far (mm) inside the nut end's outside radius, so that the two
#: overlap instead of meeting in one (differently sampled) cylinder (mesh, STEP and drawing).
FLANGE_OVERLAP_MM = 0.5
#: The bearing seat steps down at least this much (mm on the diameter) below the screw root,
#: so that the thread's grinding never touches the seat.
SEAT_STEP_MM = 1.0


@dataclass(frozen=True)
class Sized:
    """A size (mm, or a count or a name) and where it came from: :data:`DESIGN_FILE` or the
    rule or table that gave it."""

    value: float | str
    source: str


@dataclass(frozen=True)
class ShaftStep:
    """A cylindrical piece of the screw outside its thread (mm, screw frame)."""

    name: str
    z: tuple[float, float]
    diameter_mm: float


@dataclass(frozen=True)
class PlacedBearing:
    """A bearing (or one row of a pair) on its seat: its catalogue sizes and axial span."""

    designation: str
    size: Bearing
    z: tuple[float, float]

    @property
    def middle_z(self) -> float:
        return 0.5 * (self.z[0] + self.z[1])


@dataclass(frozen=True)
class ScrewEnd:
    """One screw end, from the thread end outward (``outward`` -1 at z < 0, +1 beyond)."""

    role: str                              # "fixed", "floating" or "free"
    outward: int
    run_out: tuple[float, float]           # the wheel exit (z span)
    steps: tuple[ShaftStep, ...]           # outward order
    bearings: tuple[PlacedBearing, ...]
    locknut: Locknut | None = None
    locknut_z: tuple[float, float] | None = None
    locknut_tolerance: str | None = None
    ring: ShaftRing | None = None
    ring_z: tuple[float, float] | None = None
    key: Key | None = None
    key_z: tuple[float, float] | None = None
    flat_depth_mm: float | None = None
    seat_tolerance: str | None = None
    drive_fit: str | None = None

    @property
    def tip_z(self) -> float:
        """The screw's end face on this side."""
        if not self.steps:
            return self.run_out[0] if self.outward < 0 else self.run_out[1]
        return self.steps[-1].z[0] if self.outward < 0 else self.steps[-1].z[1]

    @property
    def support_z(self) -> float | None:
        """Where the end holds the screw for the ratings: the bearings' middle."""
        if not self.bearings:
            return None
        return 0.5 * (min(b.z[0] for b in self.bearings) + max(b.z[1] for b in self.bearings))


@dataclass(frozen=True)
class NutMountLayout:
    """The nut's mounting (mm, nut frame = screw frame at mid-stroke)."""

    kind: str
    z: tuple[float, float]                 # the flange's span
    bolt: Bolt | None = None
    bolt_count: int = 0
    bolt_circle_diameter_mm: float = 0.0
    flange_diameter_mm: float = 0.0
    bolt_length_mm: float = 0.0


@dataclass(frozen=True)
class SupportSpans:
    """Free lengths (mm) and end fixities of the screw for the ratings, from the geometry."""

    critical_speed_length_mm: float
    critical_speed_ends: str
    buckling_length_mm: float
    buckling_ends: str
    worst_stroke_end: str                  # "lo" or "hi": where the buckling span is longest
    rule: str


@dataclass(frozen=True)
class ActuatorLayout:
    """Every size and position of the actuator parts of a design (mm)."""

    stroke_mm: float
    over_travel_mm: float
    nut_assembly_z: tuple[float, float]    # at mid-stroke
    thread_z: tuple[float, float]          # the screw thread incl. run-outs
    full_thread_z: tuple[float, float]
    screw_run_out_mm: float
    thread_chamfer_mm: float
    fixed_side: int                        # -1 or +1
    ends: tuple[ScrewEnd, ScrewEnd]        # (lower, upper)
    nut_mount: NutMountLayout
    supports: SupportSpans
    sizes: dict[str, Sized]

    @property
    def shifts(self) -> tuple[float, float]:
        """The nut's shifts (mm) at the lower and upper stroke ends."""
        return (-0.5 * self.stroke_mm, 0.5 * self.stroke_mm)

    @property
    def screw_z(self) -> tuple[float, float]:
        """The screw's end faces (mm)."""
        return (self.ends[0].tip_z, self.ends[1].tip_z)

    @property
    def screw_length_mm(self) -> float:
        """Overall screw length, end face to end face (mm)."""
        return self.ends[1].tip_z - self.ends[0].tip_z

    @property
    def threaded_length_mm(self) -> float:
        """Threaded length incl. the run-outs (mm)."""
        return self.thread_z[1] - self.thread_z[0]


class _Sizer:
    """Collects each size with its source; a given value wins over the rule."""

    def __init__(self) -> None:
        self.sizes: dict[str, Sized] = {}

    def take(self, key: str, given: float | str | None, rule_value: float | str | None, rule: str) -> object:
        if given is not None:
            self.sizes[key] = Sized(given, DESIGN_FILE)
            return given
        self.sizes[key] = Sized(rule_value, rule)
        return rule_value


def _ceil(x: float, step: float = 1.0) -> float:
    return math.ceil(x / step - 1e-9) * step


def _bearing(sz: _Sizer, key: str, end, d_root: float) -> Bearing:
    """The bearing of an end: table row by the bore rule, or the given sizes."""
    bores = [b for b in bearing_bores(end.bearing_series) if b <= d_root - SEAT_STEP_MM]
    rule = (f"the largest bore of ISO 15 dimension series {end.bearing_series} not above the screw root "
            f"diameter {d_root:.4g} mm less {SEAT_STEP_MM:g} mm")
    d = sz.take(f"{key}.bearing_bore_mm", end.bearing_bore_mm, bores[-1] if bores else None, rule)
    if d is None:
        raise DesignError(f"{key}.bearing_bore_mm", None,
                          f"no bearing of ISO 15 series {end.bearing_series} fits below the screw root diameter "
                          f"{d_root:.4g} mm (smallest bore {bearing_bores(end.bearing_series)[0]:g} mm): give "
                          f"{key}.bearing_bore_mm, bearing_width_mm and bearing_outer_diameter_mm")
    if d >= d_root:
        raise DesignError(f"{key}.bearing_bore_mm", d, f"must be below the screw root diameter {d_root:.4g} mm "
                                                       f"(the seat steps down from the thread)")
    try:
        row = bearing(end.bearing_series, d)
    except StandardTableError:
        row = None
    table = f"ISO 15 series {end.bearing_series}, bore {d:g} mm"
    B = sz.take(f"{key}.bearing_width_mm", end.bearing_width_mm, row and row.width_mm, table)
    D = sz.take(f"{key}.bearing_outer_diameter_mm", end.bearing_outer_diameter_mm,
                row and row.outer_diameter_mm, table)
    return Bearing(end.bearing_series, float(d), float(D), float(B), row.chamfer_mm if row else 0.6)


def _fixed_end(design: PRSDesign, sz: _Sizer, outward: int, z_end: float, run_out: tuple[float, float],
               d_root: float) -> ScrewEnd:
    """The fixed end from the thread end ``z_end`` outward (module doc)."""
    a = design.actuator
    fe, dr = a.fixed_end, a.drive
    b = _bearing(sz, "actuator.fixed_end", fe, d_root)
    threads = [t for t in locknut_bores() if t <= b.bore_mm]
    d_t = sz.take("actuator.fixed_end.locknut_thread_mm", fe.locknut_thread_mm, threads[-1] if threads else None,
                  f"{'the bearing bore' if threads and threads[-1] == b.bore_mm else 'the largest KM thread below the bearing bore'} "
                  f"(ISO 2982-2 KM locknuts, ISO 261 fine threads)")
    if d_t is None or d_t > b.bore_mm:
        raise DesignError("actuator.fixed_end.locknut_thread_mm", d_t,
                          f"must be a KM locknut thread not above the bearing bore {b.bore_mm:g} mm (the bearing "
                          f"slides over it)")
    nut = locknut(d_t)
    u = sz.take("actuator.fixed_end.undercut_width_mm", fe.undercut_width_mm, 3.0 * nut.thread_pitch_mm,
                "3 x the locknut thread pitch (a thread undercut the tool can leave into)")
    d_u = nut.thread_diameter_mm - 1.5 * nut.thread_pitch_mm
    ends = [t for t in shaft_end_diameters() if t <= nut.thread_minor_diameter_mm - 1.0]
    d_j = sz.take("actuator.drive.diameter_mm", dr.diameter_mm, ends[-1] if ends else None,
                  f"the largest ISO 775 shaft-end diameter at least 1 mm below the locknut thread's minor diameter "
                  f"{nut.thread_minor_diameter_mm:.4g} mm")
    if d_j is None or d_j >= nut.thread_minor_diameter_mm:
        raise DesignError("actuator.drive.diameter_mm", d_j, f"must be below the locknut thread's minor diameter "
                                                             f"{nut.thread_minor_diameter_mm:.4g} mm (the locknut "
                                                             f"passes over the journal)")
    try:
        row = shaft_end(d_j)
        short = row.short_mm if row.short_mm is not None else row.long_mm
    except StandardTableError:
        short = None
    l_j = sz.take("actuator.drive.length_mm", dr.length_mm, short,
                  f"ISO 775 short series for {d_j:g} mm (the long series where the short has none)")
    if l_j is None:
        raise DesignError("actuator.drive.length_mm", None, f"ISO 775 has no shaft end of {d_j:g} mm: give "
                                                           f"actuator.drive.length_mm")
    steps: list[ShaftStep] = []
    z = z_end

    def step(name: str, length: float, diameter: float) -> tuple[float, float]:
        nonlocal z
        span = (min(z, z + outward * length), max(z, z + outward * length))
        steps.append(ShaftStep(name, span, diameter))
        z += outward * length
        return span

    seat = step("fixed bearing seat", 2.0 * b.width_mm, b.bore_mm)
    inner, outer = (seat[1] - b.width_mm, seat[1]), (seat[0], seat[0] + b.width_mm)
    if outward > 0:
        inner, outer = (seat[0], seat[0] + b.width_mm), (seat[1] - b.width_mm, seat[1])
    des = b.designation("angular-contact")
    bearings = (PlacedBearing(des, b, inner), PlacedBearing(des, b, outer))
    step("locknut thread undercut", u, d_u)
    step(f"locknut thread {nut.thread}", nut.width_mm, nut.thread_diameter_mm)
    face = seat[0] if outward < 0 else seat[1]
    lock_z = (face - nut.width_mm, face) if outward < 0 else (face, face + nut.width_mm)
    journal = step("drive journal", float(l_j), float(d_j))
    key, key_z, flat = _drive_feature(sz, dr, float(d_j), journal)
    return ScrewEnd("fixed", outward, run_out, tuple(steps), bearings, locknut=nut, locknut_z=lock_z,
                    locknut_tolerance=fe.locknut_tolerance, key=key, key_z=key_z, flat_depth_mm=flat,
                    seat_tolerance=fe.seat_tolerance, drive_fit=dr.fit)


def _drive_feature(sz: _Sizer, dr, d_j: float, journal: tuple[float, float]
                   ) -> tuple[Key | None, tuple[float, float] | None, float | None]:
    """The key (or flat) of the drive journal, centred on the journal's length."""
    l_j = journal[1] - journal[0]
    lengths = [k for k in key_lengths() if k <= l_j - 4.0]
    kl = sz.take("actuator.drive.key_length_mm", dr.key_length_mm, lengths[-1] if lengths else None,
                 "the longest DIN 6885-1 standard length not above the journal length less 4 mm")
    if kl is None or kl > l_j:
        raise DesignError("actuator.drive.key_length_mm", kl, f"must be at most the journal length {l_j:g} mm")
    mid = 0.5 * (journal[0] + journal[1])
    span = (mid - 0.5 * float(kl), mid + 0.5 * float(kl))
    if dr.kind == "flat":
        depth = sz.take("actuator.drive.flat_depth_mm", dr.flat_depth_mm, round(0.1 * d_j, 3),
                        "0.1 x the journal diameter")
        if depth >= 0.5 * d_j:
            raise DesignError("actuator.drive.flat_depth_mm", depth, f"must be below half the journal diameter "
                                                                     f"{d_j:g} mm")
        return None, span, float(depth)
    try:
        key = key_for_shaft(d_j)
    except StandardTableError as exc:
        raise DesignError("actuator.drive.diameter_mm", d_j, str(exc)) from None
    if not float(kl) > key.width_mm:
        raise DesignError("actuator.drive.key_length_mm", kl, f"must exceed the key width {key.width_mm:g} mm "
                          "(a form A key has two round ends of radius b / 2)")
    sz.sizes["actuator.drive.key"] = Sized(key.designation(float(kl)), f"DIN 6885-1 for a {d_j:g} mm shaft")
    return key, span, None


def _floating_end(design: PRSDesign, sz: _Sizer, outward: int, z_end: float, run_out: tuple[float, float],
                  d_root: float) -> ScrewEnd:
    """The floating end from the thread end outward: seat, DIN 471 groove, collar."""
    fl = design.actuator.floating_end
    if not fl.enabled:
        return ScrewEnd("free", outward, run_out, (), ())
    b = _bearing(sz, "actuator.floating_end", fl, d_root)
    try:
        ring = shaft_ring(b.bore_mm)
    except StandardTableError as exc:
        raise DesignError("actuator.floating_end.bearing_bore_mm", b.bore_mm,
                          f"no DIN 471 ring holds the bearing on this seat: {exc}") from None
    z = z_end
    steps = []
    spans = []
    for name, length, dia in (("floating bearing seat", b.width_mm, b.bore_mm),
                              ("retaining ring groove", ring.groove_width_mm, ring.groove_diameter_mm),
                              ("retaining ring collar", ring.edge_distance_mm, b.bore_mm)):
        span = (min(z, z + outward * length), max(z, z + outward * length))
        steps.append(ShaftStep(name, span, dia))
        spans.append(span)
        z += outward * length
    bear = PlacedBearing(b.designation("deep-groove"), b, spans[0])
    g = spans[1]
    ring_z = (g[0], g[0] + ring.thickness_mm) if outward > 0 else (g[1] - ring.thickness_mm, g[1])
    return ScrewEnd("floating", outward, run_out, tuple(steps), (bear,), ring=ring, ring_z=ring_z,
                    seat_tolerance=fl.seat_tolerance)


def _nut_mount(design: PRSDesign, sz: _Sizer, nut_lo_end: tuple[float, float]) -> NutMountLayout:
    """The flange on the lower nut end (module doc)."""
    m = design.actuator.nut_mount
    D_nut = design.nut.outer_diameter_mm
    name = sz.take("actuator.nut_mount.bolt", m.bolt,
                   load_sized_bolt(m.bolt_count, design.loading.axial_load_n) if m.bolt is None else None,
                   f"the smallest ISO 4762 size whose {m.bolt_count} proof loads (class 8.8, ISO 898-1) carry "
                   f"{BOLT_SAFETY:g} x the design load")
    bl = bolt(str(name))
    bc = sz.take("actuator.nut_mount.bolt_circle_diameter_mm", m.bolt_circle_diameter_mm,
                 D_nut + bl.head_diameter_mm + 1.0, "the nut outside diameter + a head diameter + 1 mm")
    Df = sz.take("actuator.nut_mount.flange_diameter_mm", m.flange_diameter_mm,
                 _ceil(float(bc) + bl.head_diameter_mm + 2.0), "bolt circle + a head diameter + 2 mm, up to 1 mm")
    t = sz.take("actuator.nut_mount.flange_thickness_mm", m.flange_thickness_mm,
                min(_ceil(1.5 * bl.diameter_mm), nut_lo_end[1] - nut_lo_end[0]),
                "1.5 x the bolt diameter, up to 1 mm (at most the lower nut end's length)")
    sz.sizes["actuator.nut_mount.bolt_count"] = Sized(m.bolt_count, DESIGN_FILE if m.bolt_count != 6 else
                                                      "6 (an even count for a symmetric pattern)")
    if float(bc) - bl.clearance_hole_mm <= D_nut:
        raise DesignError("actuator.nut_mount.bolt_circle_diameter_mm", bc,
                          f"the bolt holes ({bl.clearance_hole_mm:g} mm, ISO 273) would cut the nut body "
                          f"({D_nut:g} mm): the bolt circle must exceed {D_nut + bl.clearance_hole_mm:g} mm")
    if float(Df) < float(bc) + bl.clearance_hole_mm:
        raise DesignError("actuator.nut_mount.flange_diameter_mm", Df,
                          f"must reach beyond the bolt holes: at least {float(bc) + bl.clearance_hole_mm:g} mm")
    need = float(t) + BOLT_ENGAGEMENT * bl.diameter_mm
    fits = [x for x in ISO_4762_LENGTHS_MM if x >= need - 1e-9]
    bolt_len = sz.take("actuator.nut_mount.bolt_length_mm", m.bolt_length_mm,
                       float(fits[0]) if fits else float(math.ceil(need / 10.0 - 1e-9) * 10),
                       f"flange thickness + {BOLT_ENGAGEMENT:g} bolt diameters engaged in the housing, up to the "
                       f"ISO 4762 length series (to 10 mm beyond 100 mm)")
    length = nut_lo_end[1] - nut_lo_end[0]
    if float(t) > length:
        raise DesignError("actuator.nut_mount.flange_thickness_mm", t,
                          f"must fit on the lower nut end ({length:.4g} mm long)")
    if float(bolt_len) <= float(t):
        raise DesignError("actuator.nut_mount.bolt_length_mm", bolt_len,
                          f"must exceed the flange thickness {float(t):g} mm (the bolt must reach the housing)")
    return NutMountLayout("flange", (nut_lo_end[0], nut_lo_end[0] + float(t)), bolt=bl, bolt_count=m.bolt_count,
                          bolt_circle_diameter_mm=float(bc), flange_diameter_mm=float(Df),
                          bolt_length_mm=float(bolt_len))


def screw_thread_span(design: PRSDesign) -> tuple[float, float]:
    """(z_lo, z_hi) (mm) of the screw thread incl. run-outs in the screw frame: the
    actuator's (:func:`actuator_layout`), or ``screw.length_mm`` centred on the nut thread."""
    lay = actuator_layout(design)
    if lay is not None:
        return lay.thread_z
    L = design.thread.engaged_teeth * design.thread.pitch_mm
    extra = 0.5 * (design.screw.length_mm - L)
    return -extra, L + extra


def actuator_layout(design: PRSDesign) -> ActuatorLayout | None:
    """The actuator parts of ``design`` (None without an actuator, :attr:`PRSDesign.has_actuator`).

    Raises :class:`~prs_geom.model.errors.DesignError` naming the ``actuator`` (or
    ``screw.length_mm``) field whose value or rule cannot be met.
    """
    if not design.has_actuator:
        return None
    return _layout(design)


# frames, meshing, the budget and the ratings all ask for it: computed once per design (a
# design is a frozen, hashable value)
@lru_cache(maxsize=64)
def _layout(design: PRSDesign) -> ActuatorLayout:
    mech = layout(design)
    assert mech is not None
    a = design.actuator
    sz = _Sizer()
    p, n_s = design.thread.pitch_mm, design.screw.starts
    L = design.thread.engaged_teeth * p
    A0, A1 = mech.ends[0].nut_end[0], mech.ends[1].nut_end[1]
    S, o = a.stroke_mm, a.over_travel_mm
    l_ro = float(sz.take("actuator.screw_run_out_mm", a.screw_run_out_mm, n_s * p,
                         "one lead (the grinding wheel is withdrawn over one turn)"))
    sz.take("actuator.stroke_mm", a.stroke_mm if a.stroke_mm != 100.0 else None, 100.0,
            "100 mm: about four screw diameters, a short-stroke actuator of this size")
    sz.take("actuator.over_travel_mm", a.over_travel_mm if a.over_travel_mm != 5.0 else None, 5.0,
            "5 mm of full thread beyond each stroke end, for an end stop")
    h = min(0.5 * (design.roller.major_diameter_mm - design.roller.pitch_diameter_mm),
            0.5 * (design.nut.pitch_diameter_mm - design.nut.minor_diameter_mm))
    ch = float(sz.take("actuator.thread_chamfer_mm", a.thread_chamfer_mm, round(0.8 * h, 6),
                       "0.8 x the crest to the pitch diameter at 45 degrees, the smaller of roller and nut (the "
                       "flank contacts lie inside, and the end face, datum A, still reaches the pitch diameter "
                       "where the machining sheet measures from it)"))
    if ch > h * (1.0 + 1e-9):
        raise DesignError("actuator.thread_chamfer_mm", ch, f"must be at most {h:.4g} mm, the crest to the pitch "
                                                            f"diameter of the roller and the nut: a deeper chamfer "
                                                            f"reaches the flank contacts")
    full = (A0 - 0.5 * S - o, A1 + 0.5 * S + o)
    need = (full[1] - full[0]) + 2.0 * l_ro
    if design.screw.length_mm is not None:
        if design.screw.length_mm < need - 1e-9:
            raise DesignError("screw.length_mm", design.screw.length_mm,
                              f"must be at least {need:.6g} mm for this actuator: the nut assembly "
                              f"{A1 - A0:.6g} mm + actuator.stroke_mm {S:g} + 2 x (actuator.over_travel_mm {o:g} + "
                              f"run-out {l_ro:g}) mm")
        extra = 0.5 * (design.screw.length_mm - need)
        full = (full[0] - extra, full[1] + extra)
        sz.sizes["screw.length_mm"] = Sized(design.screw.length_mm, DESIGN_FILE)
    else:
        sz.sizes["screw.length_mm"] = Sized(need, "the nut assembly + the stroke + 2 x (over-travel + run-out)")
    thread = (full[0] - l_ro, full[1] + l_ro)
    d_root = design.screw.minor_diameter_mm
    fixed = -1 if design.loading.installation == "tension-compression" else 1
    ends = []
    for outward in (-1, 1):
        z_end = thread[0] if outward < 0 else thread[1]
        run_out = (thread[0], full[0]) if outward < 0 else (full[1], thread[1])
        make = _fixed_end if outward == fixed else _floating_end
        ends.append(make(design, sz, outward, z_end, run_out, d_root))
    mount = _nut_mount(design, sz, mech.ends[0].nut_end)
    shifts = (-0.5 * S, 0.5 * S)
    return ActuatorLayout(stroke_mm=S, over_travel_mm=o, nut_assembly_z=(A0, A1), thread_z=thread,
                          full_thread_z=full, screw_run_out_mm=l_ro, thread_chamfer_mm=ch, fixed_side=fixed,
                          ends=(ends[0], ends[1]), nut_mount=mount,
                          supports=support_spans((ends[0], ends[1]), fixed, shifts, L), sizes=dict(sz.sizes))


def support_spans(ends: tuple[ScrewEnd, ScrewEnd], fixed_side: int, shifts: tuple[float, float],
                  thread_length: float) -> SupportSpans:
    """The screw's free lengths and end fixities from the bearing positions (module doc).

    ``ends``: the lower and upper screw end; ``fixed_side``: -1 or +1, the fixed end's side;
    ``shifts``: the nut's shifts (mm) at the lower and upper stroke end; ``thread_length``:
    the engaged length n p (mm); the nut thread spans [s, s + n p] at shift s."""
    fixed = ends[0] if fixed_side < 0 else ends[1]
    other = ends[1] if fixed_side < 0 else ends[0]
    z_f = fixed.support_z
    assert z_f is not None
    if other.support_z is not None:
        cs_len, cs_ends = abs(other.support_z - z_f), "fixed-supported"
        cs_rule = "between the middle of the fixed bearing pair and the middle of the floating bearing"
    else:
        cs_len, cs_ends = abs(other.tip_z - z_f), "fixed-free"
        cs_rule = "from the middle of the fixed bearing pair to the free screw end"
    # the far end of the engaged thread at each stroke end; the worst is the farthest
    far = [abs((s + (thread_length if fixed_side < 0 else 0.0)) - z_f) for s in shifts]
    worst = int(far[1] > far[0])
    rule = (f"critical speed: {cs_rule}; buckling: from the middle of the fixed bearing pair to the far end of "
            f"the engaged thread with the nut at its {'upper' if worst else 'lower'} stroke end "
            f"(the nut taken as a support that lets the screw tilt)")
    return SupportSpans(critical_speed_length_mm=cs_len, critical_speed_ends=cs_ends, buckling_length_mm=far[worst],
                        buckling_ends="fixed-supported", worst_stroke_end=("lo", "hi")[worst], rule=rule)


@dataclass(frozen=True)
class StrokeEndCheck:
    """One clearance at a stroke end (mm): ``kind`` "radial" (a bore of the nut assembly
    over the screw's largest radius within its span) or "axial" (a gap along z); and the
    flange bolts' margin (``kind`` "load (N)", ``stroke_end`` "both": their proof loads over
    the bolt safety less the design load, N)."""

    stroke_end: str
    what: str
    kind: str
    clearance_mm: float

    @property
    def passed(self) -> bool:
        return self.clearance_mm > 0.0


def _screw_radius_max(lay: ActuatorLayout, crest_radius: float, z0: float, z1: float) -> float:
    """The screw's largest radius over [z0, z1] (mm): the crest over the thread, the
    steps' radii beyond it, 0 beyond its ends."""
    r = 0.0
    if z1 > lay.thread_z[0] and z0 < lay.thread_z[1]:
        r = crest_radius
    for end in lay.ends:
        for st in end.steps:
            if z1 > st.z[0] and z0 < st.z[1]:
                r = max(r, 0.5 * st.diameter_mm)
    return r


def stroke_end_checks(design: PRSDesign, lay: ActuatorLayout) -> tuple[StrokeEndCheck, ...]:
    """The checks that stay cheap along the stroke (the thread engagement does not change):
    at both stroke ends, the rollers stay on full thread, the nut assembly stays clear of
    the bearings and locknuts, every bore of the nut assembly clears the screw beneath it,
    and the screw passes through both carriers (reaches beyond their outer faces); and the
    flange bolts carry the design load with their safety."""
    mech = layout(design)
    assert mech is not None
    L = design.thread.engaged_teeth * design.thread.pitch_mm
    w = mech.gear_face_width_mm
    crest = 0.5 * design.screw.major_diameter_mm
    out: list[StrokeEndCheck] = []
    for side, s in zip(("lo", "hi"), lay.shifts):
        def add(what: str, kind: str, value: float) -> None:
            out.append(StrokeEndCheck(side, what, kind, value))
        add("rollers (with gears) on full-depth screw thread", "axial",
            min(s - w - lay.full_thread_z[0], lay.full_thread_z[1] - (s + L + w)) + 1e-12)
        a0, a1 = lay.nut_assembly_z[0] + s, lay.nut_assembly_z[1] + s
        for end in lay.ends:
            rows = ("inner row", "outer row")
            parts = [(b.designation + (f", {rows[k]}" if len(end.bearings) > 1 else ""), b.z)
                     for k, b in enumerate(end.bearings)]
            if end.locknut_z is not None:
                parts.append((end.locknut.designation, end.locknut_z))
            for name, z in parts:
                gap = z[0] - a1 if end.outward > 0 else a0 - z[1]
                add(f"nut assembly to {name} ({end.role} end)", "axial", gap)
        bores = [("carrier", mech.carrier_inner_radius_mm, e.carrier) for e in mech.ends]
        bores += [("retaining ring", mech.ring_inner_radius_mm, e.ring) for e in mech.ends]
        bores += [("nut end bore", mech.nut_bore_radius_mm, (e.nut_end[0], e.nut_end[1])) for e in mech.ends]
        for name, r_bore, z in bores:
            r = _screw_radius_max(lay, crest, z[0] + s, z[1] + s)
            add(f"{name} over the screw", "radial", r_bore - r)
        for k, e in enumerate(mech.ends):
            reach = (e.carrier[0] + s - lay.screw_z[0]) if k == 0 else (lay.screw_z[1] - e.carrier[1] - s)
            add(f"screw through the {'lower' if k == 0 else 'upper'} carrier", "axial", reach)
    m = lay.nut_mount
    if m.bolt is not None:
        carried = m.bolt_count * m.bolt.proof_load_n / BOLT_SAFETY
        out.append(StrokeEndCheck("both", f"{m.bolt_count} x {m.bolt.name} flange bolts: proof loads / "
                                          f"{BOLT_SAFETY:g} over the design load", "load (N)",
                                  carried - design.loading.axial_load_n))
    return tuple(out)
