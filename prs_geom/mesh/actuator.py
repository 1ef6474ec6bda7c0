"""Meshes of the actuator parts of :mod:`prs_geom.geometry.actuator`: the screw ends, the
support bearings, the KM locknut, the DIN 471 shaft ring and the nut flange.

This module owns the solids outside the threads that the actuator layout places; the
thread meshes (run-outs included) are :mod:`prs_geom.mesh.thread`'s. Every mesh is in the
screw frame (mm, z along the axis) with the nut at mid-stroke, meshed like the mechanism
parts (:mod:`prs_geom.mesh.mechanism`): polygons no coarser than
:data:`~prs_geom.mesh.mechanism.MECHANISM_CHORD_MM`, an outside with its vertices on its
circle (inside the true solid), a bore with its edges tangent to its circle (outside the
true bore). A purchased part on a shaft step of the same nominal diameter (a bearing on its
seat, the locknut on its thread, the shaft ring in its groove) therefore never overlaps the
screw as meshes: the nominal line contact shows as a gap of at most the chordal deviation.

* **Screw ends** (``screw_end_lo``, ``screw_end_hi``): the steps of
  :class:`~prs_geom.geometry.actuator.ScrewEnd` revolved as one profile, with the run-out
  span as a plain cylinder :data:`RUN_OUT_INSET_MM` (or the chord tolerance, if coarser)
  inside the screw's root radius. That cylinder lies inside the thread's body, so the end
  and the thread overlap there and unite into one connected screw (the run-out's groove
  fill belongs to the thread mesh). The drive journal carries its DIN 6885-1 form A keyway
  (width b, depth t1 from the journal surface, rounded ends of radius b / 2, over
  ``key_z``) or its flat (a plane at ``flat_depth_mm`` below the journal surface over
  ``key_z``), both on the +x side.
* **Purchased parts** as their envelopes (:class:`RingEnvelope`, :func:`purchased_envelopes`):
  each bearing a plain ring from bore to outside diameter over its width; the locknut a
  ring from its thread diameter to its outside diameter; the DIN 471 ring a ring from the
  groove diameter to the shaft diameter + 2 x :data:`SHAFT_RING_RIM_MM` over its thickness.
* **Flange bolts and drive key** as their envelopes (:class:`BoltEnvelope`,
  :func:`flange_bolts`; :class:`KeyEnvelope`, :func:`drive_key`): each ISO 4762 bolt a head
  cylinder (d_k, height k = d) on a shank cylinder (d, the bolt length l; no socket, no
  thread), its head on the flange's upper face and its shank down through the clearance
  hole (into the housing, which is not modelled), one per hole (``flange_bolt_<k>``); the
  DIN 6885-1 form A key (``drive_key``) the keyway's stadium (width b, round ends of radius
  b / 2, over ``key_z``) from the keyway floor to the key height h, on the +x side, its arc
  vertices staggered against the keyway's (its outline inside the keyway's polygon, touching
  it, and at most twice the chord tolerance inside the true stadium). Bolt and key are
  meshed once in their own frames and placed by translations (frames in the classes'
  docstrings).
* **Nut flange** (``nut_flange``): an annulus from the nut end's outside radius less
  :data:`FLANGE_OVERLAP_MM` (it overlaps the nut end, the same rigid body, so the two unite)
  to half the flange diameter over the flange's span, with ``bolt_count`` ISO 273
  clearance holes on the bolt circle, the first at 180 / ``bolt_count`` degrees so that
  none sits on the +x axis.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import trimesh
from numpy.typing import NDArray

from prs_geom.geometry.actuator import FLANGE_OVERLAP_MM, ActuatorLayout, ScrewEnd
from prs_geom.geometry.mechanism import MechanismLayout
from prs_geom.mesh.mechanism import MECHANISM_CHORD_MM, _circle, _extruded, _trimesh, segments
from prs_geom.model.design import PRSDesign

__all__ = ["FLANGE_OVERLAP_MM", "HEAD_HEIGHT_PER_DIAMETER", "PAD_MM", "RUN_OUT_INSET_MM", "SHAFT_RING_RIM_MM",
           "BoltEnvelope", "KeyEnvelope",
           "RingEnvelope", "actuator_meshes", "actuator_part_names", "bolt_angles", "drive_journal_radius", "drive_key",
           "flange_bolts", "purchased_envelopes", "screw_end_profile"]

#: The run-out cylinder of a screw end stays this far (mm) inside the screw's root radius, or
#: the chord tolerance when that is coarser: the thread mesh's root facets sag inside the root
#: circle by up to half its chord tolerance, and the cylinder must stay inside the thread body.
RUN_OUT_INSET_MM = 0.01
#: The DIN 471 ring's modelled envelope reaches this far (mm) beyond the shaft's radius (the
#: ring's radial section above the shaft, without its lugs).
SHAFT_RING_RIM_MM = 1.5
#: Cutters overshoot the faces they open by this much (mm), so no cut face is coplanar.
PAD_MM = 1.0
_PAD_MM = PAD_MM


@dataclass(frozen=True)
class RingEnvelope:
    """A purchased part modelled as its envelope, a plain ring (mm, screw frame).

    ``name`` is its scene part name, ``designation`` its catalogue designation; the ring
    spans the radii [``inner_radius_mm``, ``outer_radius_mm``] over ``z``.
    """

    name: str
    designation: str
    inner_radius_mm: float
    outer_radius_mm: float
    z: tuple[float, float]


def purchased_envelopes(lay: ActuatorLayout) -> tuple[RingEnvelope, ...]:
    """The envelopes of the purchased parts in scene order: the bearings (``bearing_<role>_<k>``,
    lower end first), the KM locknut (``locknut``), the DIN 471 ring (``shaft_ring``)."""
    out = [RingEnvelope(f"bearing_{end.role}_{k}", b.designation, 0.5 * b.size.bore_mm,
                        0.5 * b.size.outer_diameter_mm, b.z)
           for end in lay.ends for k, b in enumerate(end.bearings)]
    for end in lay.ends:
        if end.locknut is not None and end.locknut_z is not None:
            nut = end.locknut
            out.append(RingEnvelope("locknut", nut.designation, 0.5 * nut.thread_diameter_mm,
                                    0.5 * nut.outer_diameter_mm, end.locknut_z))
    for end in lay.ends:
        if end.ring is not None and end.ring_z is not None:
            ring = end.ring
            out.append(RingEnvelope("shaft_ring", ring.designation, 0.5 * ring.groove_diameter_mm,
                                    0.5 * ring.shaft_mm + SHAFT_RING_RIM_MM, end.ring_z))
    return tuple(out)


@dataclass(frozen=True)
class BoltEnvelope:
    """A flange bolt (ISO 4762 socket head cap screw) modelled as its envelope (mm).

    Own frame: axis z, z = 0 at the shank's tip; the shank (radius ``shank_radius_mm``) up
    to z = ``length_mm`` (the nominal length l, under the head), the head (radius
    ``head_radius_mm``) from there to ``length_mm + head_height_mm``. ``tip`` is where the
    frame's origin lies in the screw frame (mid-stroke): the bolt is placed by that
    translation, head up.
    """

    name: str
    designation: str
    shank_radius_mm: float
    length_mm: float
    head_radius_mm: float
    head_height_mm: float
    tip: tuple[float, float, float]

    def profile(self) -> list[tuple[float, float]]:
        """The (r, z) outline it is revolved from, counter-clockwise in the (r, z) plane."""
        top = self.length_mm + self.head_height_mm
        return [(0.0, 0.0), (self.shank_radius_mm, 0.0), (self.shank_radius_mm, self.length_mm),
                (self.head_radius_mm, self.length_mm), (self.head_radius_mm, top), (0.0, top)]

    @property
    def volume_mm3(self) -> float:
        """pi (r_s^2 l + r_h^2 k), mm^3."""
        return math.pi * (self.shank_radius_mm ** 2 * self.length_mm + self.head_radius_mm ** 2 * self.head_height_mm)


@dataclass(frozen=True)
class KeyEnvelope:
    """The drive's parallel key (DIN 6885-1 form A) modelled as its envelope (mm).

    Own frame: x = 0 at its bottom face (on the keyway floor) up to x = ``height_mm``, y
    across (|y| <= ``width_mm`` / 2), z along its length from 0 to ``length_mm``; the ends
    are half-discs of radius ``width_mm`` / 2. ``origin`` is where the frame's origin lies in
    the screw frame: the key is placed by that translation (the keyway is on the +x side).
    """

    name: str
    designation: str
    width_mm: float
    height_mm: float
    length_mm: float
    origin: tuple[float, float, float]

    @property
    def volume_mm3(self) -> float:
        """((l - b) b + pi b^2 / 4) h, mm^3."""
        b = self.width_mm
        return ((self.length_mm - b) * b + 0.25 * math.pi * b * b) * self.height_mm


#: ISO 4762 head height k (its maximum) in bolt diameters.
HEAD_HEIGHT_PER_DIAMETER = 1.0


def bolt_angles(count: int) -> NDArray[np.float64]:
    """Angular positions (rad, from +x about +z) of the flange's bolt holes: the first at
    180 / ``count`` degrees, so that none sits on the +x axis (the drive key's side)."""
    return math.pi / count + 2.0 * math.pi * np.arange(count) / count


def flange_bolts(lay: ActuatorLayout) -> tuple[BoltEnvelope, ...]:
    """The flange bolts' envelopes (``flange_bolt_<k>``, in hole order), none without a flange
    mounting: heads on the flange's upper face, shanks down through the holes."""
    m = lay.nut_mount
    if m.kind != "flange" or m.bolt is None:
        return ()
    r_bc = 0.5 * m.bolt_circle_diameter_mm
    d = m.bolt.diameter_mm
    tip = m.z[1] - m.bolt_length_mm
    designation = f"ISO 4762 {m.bolt.name} x {m.bolt_length_mm:g} - 8.8"
    return tuple(BoltEnvelope(f"flange_bolt_{k}", designation, 0.5 * d, m.bolt_length_mm, 0.5 * m.bolt.head_diameter_mm,
                              HEAD_HEIGHT_PER_DIAMETER * d, (r_bc * math.cos(a), r_bc * math.sin(a), tip))
                 for k, a in enumerate(bolt_angles(m.bolt_count)))


def drive_key(lay: ActuatorLayout) -> KeyEnvelope | None:
    """The drive key's envelope (``drive_key``) in its keyway, None for a flat or no drive."""
    for end in lay.ends:
        if end.key is not None and end.key_z is not None:
            floor = drive_journal_radius(end) - end.key.shaft_depth_mm
            length = end.key_z[1] - end.key_z[0]
            return KeyEnvelope("drive_key", end.key.designation(length), end.key.width_mm, end.key.height_mm,
                               length, (floor, 0.0, end.key_z[0]))
    return None


def actuator_part_names(lay: ActuatorLayout) -> list[str]:
    """The actuator's scene part names in placement order: ``screw_end_lo``, ``screw_end_hi``,
    ``nut_flange`` (a flange mounting only), the bearings, ``locknut``, ``shaft_ring``, the
    flange bolts ``flange_bolt_<k>``, ``drive_key`` (a keyed drive only)."""
    names = ["screw_end_lo", "screw_end_hi"]
    if lay.nut_mount.kind == "flange":
        names.append("nut_flange")
    names += [env.name for env in purchased_envelopes(lay)] + [b.name for b in flange_bolts(lay)]
    key = drive_key(lay)
    return names + ([key.name] if key is not None else [])


def actuator_meshes(design: PRSDesign, lay: ActuatorLayout,
                    tol: float) -> dict[str, tuple[trimesh.Trimesh, np.ndarray]]:
    """Meshes (mm) of the actuator parts, keyed by the names of :func:`actuator_part_names`,
    each as (mesh in its own frame, 4x4 transform to the screw frame with the nut parts at
    mid-stroke).

    The screw ends and the flange are meshed in place (transform the identity). A purchased
    part is meshed once per size in its own frame (axis z, z = 0 at its lower face) and
    placed by a transform: the two bearings of the fixed end are two copies of one mesh.

    Parameters
    ----------
    design : PRSDesign
        The design (screw root diameter; its mechanism layout for the nut end's radius).
    lay : ActuatorLayout
        Its actuator layout (:func:`~prs_geom.geometry.actuator.actuator_layout`).
    tol : float
        Chord tolerance (mm) of the thread meshes the screw ends meet; the actuator parts are
        meshed at ``min(tol, MECHANISM_CHORD_MM)``, the run-out cylinder kept
        ``max(RUN_OUT_INSET_MM, tol)`` inside the root radius.
    """
    from prs_geom.geometry.mechanism import layout
    from prs_geom.mesh.mechanism import translation

    I = np.eye(4)
    fine = min(tol, MECHANISM_CHORD_MM)
    r_run_out = 0.5 * design.screw.minor_diameter_mm - max(RUN_OUT_INSET_MM, tol)
    out = {f"screw_end_{side}": (_trimesh(_screw_end(end, r_run_out, fine)), I)
           for side, end in zip(("lo", "hi"), lay.ends)}
    mech = layout(design)
    if lay.nut_mount.kind == "flange" and mech is not None:
        out["nut_flange"] = (_trimesh(_flange(lay, mech, fine)), I)
    envelopes = purchased_envelopes(lay)
    # each ring turned by its own fraction of the finest polygon step: rings that touch face to
    # face (the bearing pair, the locknut on it) then share no vertex, which a mesh file without
    # topology (STL) would merge into edges of four faces
    step = math.pi / (max(segments(env.outer_radius_mm, fine) for env in envelopes) * len(envelopes)) \
        if envelopes else 0.0
    shared: dict[tuple[str, float, float, float], trimesh.Trimesh] = {}
    for i, env in enumerate(envelopes):
        width = env.z[1] - env.z[0]
        key = (env.designation, env.inner_radius_mm, env.outer_radius_mm, width)
        if key not in shared:
            shared[key] = _trimesh(_ring(RingEnvelope(env.name, env.designation, env.inner_radius_mm,
                                                      env.outer_radius_mm, (0.0, width)), fine))
        angle = i * step
        T = translation(env.z[0])
        T[:2, :2] = [[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]]
        out[env.name] = (shared[key], T)
    bolts = flange_bolts(lay)
    if bolts:
        bolt_mesh = _trimesh(_bolt(bolts[0], fine))
        out.update({b.name: (bolt_mesh, _translated(b.tip)) for b in bolts})
    key_env = drive_key(lay)
    if key_env is not None:
        solid = _stadium_prism(key_env.width_mm, (0.0, key_env.length_mm), 0.0, key_env.height_mm, fine,
                               staggered=True)
        out[key_env.name] = (_trimesh(solid), _translated(key_env.origin))
    return out


def _translated(origin: tuple[float, float, float]) -> NDArray[np.float64]:
    T = np.eye(4)
    T[:3, 3] = origin
    return T


def _bolt(env: BoltEnvelope, tol: float):
    """A bolt's envelope revolved in its own frame (vertices on its circles)."""
    import manifold3d

    return manifold3d.CrossSection([np.asarray(env.profile(), dtype=np.float64)]).revolve(
        segments(env.head_radius_mm, tol))


def screw_end_profile(end: ScrewEnd, r_run_out: float | None = None) -> list[tuple[float, float]]:
    """The (r, z) outline (mm) a screw end is revolved from: up the outside in z order, then
    back down the axis (counter-clockwise in the (r, z) plane). With ``r_run_out`` the run-out
    span is a cylinder of that radius (the mesh's overlap with the thread body); without, the
    steps alone (the run-out cylinder lies inside the thread's core, so a union does not
    need it)."""
    pieces = [(st.z[0], st.z[1], 0.5 * st.diameter_mm) for st in end.steps]
    if r_run_out is not None:
        pieces.append((end.run_out[0], end.run_out[1], r_run_out))
    pieces.sort()
    return [(0.0, pieces[0][0])] + [pt for z0, z1, r in pieces for pt in ((r, z0), (r, z1))] + [(0.0, pieces[-1][1])]


def drive_journal_radius(end: ScrewEnd) -> float:
    """Radius (mm) of the step the drive's key span ``end.key_z`` lies on (the end must have
    one)."""
    assert end.key_z is not None
    journal = next(st for st in end.steps if st.z[0] - 1e-9 <= end.key_z[0] and end.key_z[1] <= st.z[1] + 1e-9)
    return 0.5 * journal.diameter_mm


def _screw_end(end: ScrewEnd, r_run_out: float, tol: float):
    """The manifold3d solid of one screw end: the run-out cylinder and the steps revolved as
    one (r, z) profile, less the drive journal's keyway or flat."""
    import manifold3d

    prof = screw_end_profile(end, r_run_out)
    n = segments(max(r for r, _ in prof), tol)
    solid = manifold3d.CrossSection([np.asarray(prof, dtype=np.float64)]).revolve(n)
    if end.key_z is None:
        return solid
    r_j = drive_journal_radius(end)
    if end.key is not None:
        return solid - _keyway_cutter(r_j, end.key.width_mm, end.key.shaft_depth_mm, end.key_z, tol)
    assert end.flat_depth_mm is not None
    x0 = r_j - end.flat_depth_mm
    box = np.array([[x0, -r_j - _PAD_MM], [r_j + _PAD_MM, -r_j - _PAD_MM], [r_j + _PAD_MM, r_j + _PAD_MM],
                    [x0, r_j + _PAD_MM]])
    return solid - _extruded(box, [], *end.key_z)


def _keyway_cutter(r_j: float, width: float, depth: float, span: tuple[float, float], tol: float):
    """The DIN 6885-1 form A keyway as a solid to cut from a journal of radius ``r_j``: the
    key's stadium (:func:`_stadium_prism`) from the floor x = r_j - t1 out past the journal
    surface."""
    return _stadium_prism(width, span, r_j - depth, depth + _PAD_MM, tol)


def _stadium_prism(width: float, span: tuple[float, float], x0: float, height: float, tol: float,
                   staggered: bool = False):
    """A stadium (length ``span`` along z, width ``width`` along y, ends of radius width / 2;
    vertices on its arcs) in the (z, y) plane, extruded along +x from ``x0`` by ``height``.

    ``staggered``: the arcs' vertices half a step off those of the unstaggered stadium and on
    its chords' midpoints (radius a cos(pi / n), n the polygon's sides, a = width / 2): the
    polygon lies inside the unstaggered one, touching it in those midpoints, with no vertex
    in common (the key in its keyway: no shared volume, and no shared vertex that a mesh
    file without topology would merge into edges of four faces). Its sides and ends lie
    a sin^2(pi / n) <= 2 ``tol`` inside the true stadium."""
    a = 0.5 * width
    half = 0.5 * (span[1] - span[0]) - a            # half the straight part
    n = segments(a, tol)
    t = np.pi * ((np.arange(n // 2) + 0.5) if staggered else np.arange(n // 2 + 1)) / (n // 2)
    if staggered:
        a *= math.cos(math.pi / n)
    # u along -z (see the rotation below), v along y: right arc, then left arc
    right = np.column_stack([half + a * np.sin(t), -a * np.cos(t)])
    left = np.column_stack([-half - a * np.sin(t), a * np.cos(t)])
    stadium = np.vstack([right, left])
    solid = _extruded(stadium, [], 0.0, height)
    # (u, v, w) -> (x, y, z) = (w + x0, v, z_mid - u): a rotation (determinant +1)
    z_mid = 0.5 * (span[0] + span[1])
    M = np.array([[0.0, 0.0, 1.0, x0], [0.0, 1.0, 0.0, 0.0], [-1.0, 0.0, 0.0, z_mid]])
    return solid.transform(M)


def _ring(env: RingEnvelope, tol: float):
    """A plain ring: outside polygon on its circle, bore polygon tangent to its circle."""
    return _extruded(_circle(env.outer_radius_mm, tol), [_circle(env.inner_radius_mm, tol, hole=True)], *env.z)


def _flange(lay: ActuatorLayout, mech: MechanismLayout, tol: float):
    """The nut flange (module doc): annulus with the bolt holes, first hole at 180 / N deg."""
    m = lay.nut_mount
    assert m.bolt is not None
    count = m.bolt_count
    r_bc = 0.5 * m.bolt_circle_diameter_mm
    angles = bolt_angles(count)
    holes = [_circle(0.5 * m.bolt.clearance_hole_mm, tol, (r_bc * math.cos(a), r_bc * math.sin(a)), hole=True)
             for a in angles]
    inner = _circle(mech.nut_end_outer_radius_mm - FLANGE_OVERLAP_MM, tol, hole=True)
    return _extruded(_circle(0.5 * m.flange_diameter_mm, tol), [inner, *holes], *m.z)
