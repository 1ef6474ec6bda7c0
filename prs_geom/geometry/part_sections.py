"""The axial section of each complete thread part (screw, roller, nut) as a drawing shows
it: cylindrical zones, threads and gears in their conventional representation, and the
functional features that carry ISO 286 limits.

A complete part (:mod:`prs_geom.mesh.parts`) is the thread with what the layouts add to it:
the screw's ends (:mod:`prs_geom.geometry.actuator`), the roller's end gears and journals,
the nut's ring gears, ends and flange (:mod:`prs_geom.geometry.mechanism`). Its section
through the axis is drawn here as a union of annular zones in the (z, r) plane, z in the
part's frame (screw frame for the screw and the nut, roller frame for the roller) and r the
radius (mm):

* a thread in the simplified representation of ISO 6410-1: the section reaches the crest
  (the major diameter of an external thread, the minor of the internal nut thread), the
  root is a thin line, and the exact tooth form is the drawing's detail;
* a spur gear as ISO 2203 draws it: the section reaches the tip circle (the roller gear's
  tip capped at the thread's crest, as it is cut through the continued thread), the root
  a thin line, the reference (pitch) circle a dash-dot line.

Pure geometry: numbers from the design and its layouts, no mesh and no file.
"""
from __future__ import annotations

from dataclasses import dataclass

from prs_geom.geometry.frames import screw_z_range, thread_length
from prs_geom.geometry.profiles import ThreadProfile, ThreadProfiles
from prs_geom.model.design import PRSDesign

__all__ = ["SECTION_PARTS", "Zone", "ToothedZone", "LimitFeature", "PartSection", "part_section",
           "merged_cells", "outline_polygons"]

#: The parts drawn as complete-part sections.
SECTION_PARTS = ("screw", "roller", "nut")
#: The ISO 286 zone of the nut end bore (the DIN 472 ring's housing bore d1) when the
#: carriers run clear of it (``mechanism.carrier_guidance = "clear"``): DIN 472 asks H11.
RING_BORE_ZONE = "H11"


@dataclass(frozen=True)
class Zone:
    """An annulus of the section: z span (mm, part frame), inner and outer radius (mm; the
    inner 0 for solid material on the axis)."""

    name: str
    z: tuple[float, float]
    r_inner: float
    r_outer: float


@dataclass(frozen=True)
class ToothedZone:
    """A thread or gear zone in its conventional representation: the crest (tip) radius the
    section reaches, the root radius (a thin line) and, for a gear, the reference radius (a
    dash-dot line; None for a thread). ``internal`` for the nut thread and the ring gear."""

    name: str
    z: tuple[float, float]
    crest_radius: float
    root_radius: float
    internal: bool
    reference_radius: float | None = None


@dataclass(frozen=True)
class LimitFeature:
    """A functional diameter with its ISO 286 zone: ``diameter_mm`` the nominal size drawn
    and dimensioned, ``symbol`` the zone (a shaft zone for an external feature, a hole zone
    for an internal one), ``z`` where along the part it is dimensioned, ``count`` how many
    such features the part has (the callout reads "2x"), ``field`` the design-file field (or
    rule) the zone comes from."""

    name: str
    diameter_mm: float
    symbol: str
    z: float
    internal: bool
    field: str
    count: int = 1


@dataclass(frozen=True)
class PartSection:
    """The section of one complete part (module doc). ``datum_face_z`` is face A (the axial
    datum); ``datum_axis`` names the features (of ``features``) that are the datum cylinders
    B (and C for a common axis B-C)."""

    part: str
    zones: tuple[Zone, ...]
    toothed: tuple[ToothedZone, ...]
    features: tuple[LimitFeature, ...]
    datum_face_z: float
    datum_face_radius: tuple[float, float]
    datum_axis: tuple[str, ...]
    hollow: bool
    thread_z: tuple[float, float]

    @property
    def z_span(self) -> tuple[float, float]:
        """The part's end faces (mm)."""
        return min(z.z[0] for z in self.zones), max(z.z[1] for z in self.zones)

    @property
    def outer_radius(self) -> float:
        """Largest radius of the section (mm)."""
        return max(z.r_outer for z in self.zones)

    def feature(self, name: str) -> LimitFeature:
        """The feature named ``name``."""
        return next(f for f in self.features if f.name == name)


def merged_cells(zones: tuple[Zone, ...]) -> list[tuple[float, float, list[tuple[float, float]]]]:
    """The union of ``zones`` as cells between consecutive z boundaries: (z0, z1, radial
    intervals (r0, r1) of material, sorted and merged), neighbours with equal intervals
    joined."""
    zs = sorted({z for zone in zones for z in zone.z})
    cells: list[tuple[float, float, list[tuple[float, float]]]] = []
    for z0, z1 in zip(zs[:-1], zs[1:]):
        mid = 0.5 * (z0 + z1)
        spans = sorted((zone.r_inner, zone.r_outer) for zone in zones if zone.z[0] <= mid <= zone.z[1])
        merged: list[tuple[float, float]] = []
        for a, b in spans:
            if merged and a <= merged[-1][1] + 1e-12:
                merged[-1] = (merged[-1][0], max(merged[-1][1], b))
            else:
                merged.append((a, b))
        if cells and cells[-1][2] == merged and abs(cells[-1][1] - z0) < 1e-12:
            cells[-1] = (cells[-1][0], z1, merged)
        elif merged:
            cells.append((z0, z1, merged))
    return cells


def outline_polygons(zones: tuple[Zone, ...]) -> list[list[tuple[float, float]]]:
    """Closed outlines (z, r) of the section's upper half (r >= 0), counter-clockwise: one
    polygon when every cell holds one interval of material and the cells touch (the usual
    part), else one per cell. A solid part's polygon runs along the axis (r = 0)."""
    cells = merged_cells(zones)
    single = all(len(c[2]) == 1 for c in cells) and all(
        abs(a[1] - b[0]) < 1e-12 and not (a[2][0][1] < b[2][0][0] or b[2][0][1] < a[2][0][0])
        for a, b in zip(cells[:-1], cells[1:]))
    if not single:
        return [[(z0, r0), (z1, r0), (z1, r1), (z0, r1)] for z0, z1, spans in cells for r0, r1 in spans]
    top: list[tuple[float, float]] = []
    bottom: list[tuple[float, float]] = []
    for z0, z1, ((r0, r1),) in cells:
        top += [(z0, r1), (z1, r1)]
        bottom += [(z0, r0), (z1, r0)]
    poly = bottom + top[::-1]
    out: list[tuple[float, float]] = []
    for p in poly:                     # drop repeated points and points on a straight run
        if out and abs(out[-1][0] - p[0]) < 1e-12 and abs(out[-1][1] - p[1]) < 1e-12:
            continue
        out.append(p)
    keep = [p for i, p in enumerate(out) if not _collinear(out[i - 1], p, out[(i + 1) % len(out)])]
    return [keep]


def _collinear(a: tuple[float, float], b: tuple[float, float], c: tuple[float, float]) -> bool:
    return abs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) < 1e-12


def part_section(design: PRSDesign, part: str, screw_profile: ThreadProfile | None = None) -> PartSection:
    """The complete ``part``'s section (module doc); ``screw_profile``: the screw's thread as
    drawn (its theoretical pitch diameter, :attr:`ContactResult.screw_profile`), else the
    design's nominal one."""
    prof = ThreadProfiles.from_design(design)
    if part == "screw":
        return _screw(design, screw_profile or prof.screw)
    if part == "roller":
        return _roller(design, prof.roller)
    if part == "nut":
        return _nut(design, prof.nut)
    raise ValueError(f"part must be one of {SECTION_PARTS}, not {part!r}")


def _pitch_feature(design: PRSDesign, part: str, profile: ThreadProfile, z: tuple[float, float]) -> LimitFeature:
    return LimitFeature("pitch diameter", 2.0 * profile.pitch_radius, getattr(design, part).pitch_diameter_tolerance,
                        0.5 * (z[0] + z[1]), profile.internal, f"{part}.pitch_diameter_tolerance")


def _screw(design: PRSDesign, profile: ThreadProfile) -> PartSection:
    from prs_geom.geometry.actuator import actuator_layout

    lay = actuator_layout(design)
    z_thread = screw_z_range(design)
    zones = [Zone("thread", z_thread, 0.0, profile.crest_radius)]
    full = lay.full_thread_z if lay is not None else z_thread
    toothed = [ToothedZone("thread", full, profile.crest_radius, profile.root_radius, False)]
    features = [_pitch_feature(design, "screw", profile, full)]
    face, face_r, axis = z_thread[0], (0.0, profile.crest_radius), ("major diameter",)
    if lay is not None:
        for end in lay.ends:
            for st in end.steps:
                zones.append(Zone(st.name, st.z, 0.0, 0.5 * st.diameter_mm))
        seats = []
        for end in lay.ends:
            for st in end.steps:
                mid = 0.5 * (st.z[0] + st.z[1])
                if st.name.endswith("bearing seat"):
                    seats.append(st)
                    features.append(LimitFeature(st.name, st.diameter_mm, str(end.seat_tolerance), mid, False,
                                                 f"actuator.{'fixed' if end.role == 'fixed' else 'floating'}_end."
                                                 f"seat_tolerance"))
                elif st.name == "drive journal":
                    features.append(LimitFeature(st.name, st.diameter_mm, str(end.drive_fit), mid, False,
                                                 "actuator.drive.fit"))
        if seats:
            fixed = lay.ends[0] if lay.ends[0].role == "fixed" else lay.ends[1]
            seat = next(st for st in fixed.steps if st.name.endswith("bearing seat"))
            # face A: the shoulder the fixed bearings are clamped against (thread side of the seat)
            face = seat.z[1] if fixed.outward < 0 else seat.z[0]
            face_r = (0.5 * seat.diameter_mm, profile.root_radius)
            axis = tuple(st.name for st in sorted(seats, key=lambda s: s.z[0]))
    if axis == ("major diameter",):
        features.append(LimitFeature("major diameter", 2.0 * profile.crest_radius, "", z_thread[0], False, ""))
    return PartSection("screw", tuple(zones), tuple(toothed), tuple(features), face, face_r, axis, False, full)


def _roller(design: PRSDesign, profile: ThreadProfile) -> PartSection:
    from prs_geom.geometry.gear_pair import design_gear_pair
    from prs_geom.geometry.mechanism import layout

    L = thread_length(design)
    crest = profile.crest_radius
    zones = [Zone("thread", (0.0, L), 0.0, crest)]
    toothed = [ToothedZone("thread", (0.0, L), crest, profile.root_radius, False)]
    features = [_pitch_feature(design, "roller", profile, (0.0, L))]
    face, face_r, axis = 0.0, (0.0, crest), ("major diameter",)
    pair = design_gear_pair(design)
    gear_spans = [(-pair.pinion.face_width_mm, 0.0), (L, L + pair.pinion.face_width_mm)] if pair else []
    for side, span in zip(("lo", "hi"), gear_spans):
        tip = min(pair.pinion.tip_radius_mm, crest)
        zones.append(Zone(f"gear {side}", span, 0.0, tip))
        toothed.append(ToothedZone(f"gear {side}", span, tip, pair.pinion.root_radius_mm, False,
                                   pair.pinion.pitch_radius_mm))
    if pair is not None:
        features.append(LimitFeature("gear tip diameter", 2.0 * min(pair.pinion.tip_radius_mm, crest),
                                     design.gears.tip_tolerance, 0.5 * sum(gear_spans[0]), False,
                                     "gears.tip_tolerance", count=2))
        face, face_r = gear_spans[0][0], (0.0, pair.pinion.root_radius_mm)
    mech = layout(design)
    if mech is not None:
        d_j = mech.journal_diameter_mm
        shaft = mech.journal_fit.fit.split("/")[1]
        for side, end in zip(("lo", "hi"), mech.ends):
            zones.append(Zone(f"journal {side}", end.journal, 0.0, 0.5 * d_j))
            features.append(LimitFeature(f"journal {side}", d_j, shaft, 0.5 * sum(end.journal), False,
                                         "mechanism.journal_fit"))
        lo = mech.ends[0]
        face = lo.journal[1] if lo.journal[1] <= face + 1e-9 else face
        face_r = (0.5 * d_j, face_r[1] if pair is None else pair.pinion.root_radius_mm)
        axis = ("journal lo", "journal hi")
    if axis == ("major diameter",):
        features.append(LimitFeature("major diameter", 2.0 * crest, "", 0.0, False, ""))
    return PartSection("roller", tuple(zones), tuple(toothed), tuple(features), face, face_r, axis, False, (0.0, L))


def _nut(design: PRSDesign, profile: ThreadProfile) -> PartSection:
    from prs_geom.geometry.actuator import actuator_layout
    from prs_geom.geometry.gear_pair import design_gear_pair, ring_gear_outer_radius
    from prs_geom.geometry.mechanism import layout
    from prs_geom.geometry.actuator import FLANGE_OVERLAP_MM

    L = thread_length(design)
    R = 0.5 * design.nut.outer_diameter_mm
    zones = [Zone("thread", (0.0, L), profile.crest_radius, R)]
    toothed = [ToothedZone("thread", (0.0, L), profile.crest_radius, profile.root_radius, True)]
    features = [_pitch_feature(design, "nut", profile, (0.0, L)),
                LimitFeature("outside diameter", 2.0 * R, "", 0.5 * L, False, "")]
    pair = design_gear_pair(design)
    mech = layout(design)
    if pair is not None:
        w = pair.ring.face_width_mm
        r_ring = ring_gear_outer_radius(design, pair)
        r_sleeve = R if mech is not None else r_ring
        for side, span in (("lo", (-w, 0.0)), ("hi", (L, L + w))):
            zones.append(Zone(f"ring gear {side}", span, pair.ring.tip_radius_mm, max(r_ring, r_sleeve)))
            toothed.append(ToothedZone(f"ring gear {side}", span, pair.ring.tip_radius_mm, pair.ring.root_radius_mm,
                                       True, pair.ring.pitch_radius_mm))
        features.append(LimitFeature("ring gear tip diameter", 2.0 * pair.ring.tip_radius_mm,
                                     design.gears.ring_tip_tolerance, -0.5 * w, True, "gears.ring_tip_tolerance",
                                     count=2))
    if mech is not None:
        # the drawing shows the nut end flush with the nut body: the mesh's relief
        # (NUT_END_RELIEF_MM) is a meshing device, not a machined step
        R_end = R
        for side, end in zip(("lo", "hi"), mech.ends):
            gear = end.gear_zone if pair is not None else None
            z0, z1 = end.nut_end
            bored = (z0, gear[0]) if (gear and end.outward < 0) else ((gear[1], z1) if gear else (z0, z1))
            g0, g1 = end.groove
            for name, span, r_in in ((f"end bore {side}", (bored[0], g0), mech.nut_bore_radius_mm),
                                     (f"ring groove {side}", (g0, g1), mech.groove_radius_mm),
                                     (f"end bore {side} outer", (g1, bored[1]), mech.nut_bore_radius_mm)):
                if span[1] - span[0] > 1e-9:
                    zones.append(Zone(name, span, r_in, R_end))
        guided = design.mechanism.carrier_guidance == "nut"
        lo = mech.ends[0]
        zone = design.mechanism.carrier_fit.split("/")[0] if guided else RING_BORE_ZONE
        fld = "mechanism.carrier_fit" if guided else "DIN 472 housing bore (carriers run clear)"
        z_bore = 0.5 * (lo.groove[0] + lo.nut_end[0]) if lo.outward < 0 else 0.5 * (lo.groove[1] + lo.nut_end[1])
        features.append(LimitFeature("end bore", 2.0 * mech.nut_bore_radius_mm, zone, z_bore, True, fld, count=2))
    lay = actuator_layout(design)
    face, face_r = 0.0, (profile.crest_radius, R)
    if lay is not None and lay.nut_mount.kind == "flange" and mech is not None:
        m = lay.nut_mount
        zones.append(Zone("flange", m.z, R - FLANGE_OVERLAP_MM, 0.5 * m.flange_diameter_mm))
        # face A: the flange's face towards the thread (the face that seats on the housing)
        face = m.z[1]
        face_r = (R, 0.5 * m.flange_diameter_mm)
    return PartSection("nut", tuple(zones), tuple(toothed), tuple(features), face, face_r, ("outside diameter",),
                       True, (0.0, L))
