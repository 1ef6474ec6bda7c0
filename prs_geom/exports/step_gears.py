"""Complete B-reps of the geared parts: the roller with its end gears and journals, the nut
with its ring gears, ends and flange (optional extra ``step``).

The thread bodies of :mod:`prs_geom.exports.step` are B-spline solids built without a
boolean. Putting gears on them with general OpenCascade booleans was measured far too slow
(the roller's gear-gap cutters 146-227 s, the nut fused with its ring gears 469-732 s;
docs/step.md), so each part is built the way its geometry allows:

* **Roller.** The gears are cut through the thread's ends, so the thread body is built long
  enough to carry them (``[-w, L + w]``, one B-spline fit, faces cut at the gear faces) and
  one cut removes, in each gear zone, a tube whose inner wall is the pinion's outline (its
  flanks interpolated B-splines through points of the analytic involute and fillet, its tip
  pushed beyond the thread crest when the two coincide, where the crest bounds the part
  anyway), plus the 45 degree chamfers at the thread ends. The journals are fused on.
* **Nut.** The ring gears, the nut ends and the flange meet the thread body only in its end
  planes. They are united among themselves (exact solids: cylinders, planes and the ring
  gear's prism), and the end planes are joined by 2-D booleans: the thread body's end face
  less the ends' face, and the reverse. The faces are then sewn (edges split where the
  outlines cross). No 3-D boolean touches a thread face.

Each result is checked like the complete screw: one valid solid, its volume against the
complete part's mesh (:data:`~prs_geom.checks.brep.COMPLETE_VOLUME_REL_LIMIT`; measured with
:func:`~prs_geom.checks.brep.gear_solid_volume`, because OpenCascade's integration
misjudges extruded gear outlines), and its extent against the mesh's. A datum slot under a
gear or a nut end is not built (the complete mesh fills it as a closed void); its volume is
reported as ``filled_voids_mm3``.
"""
from __future__ import annotations

import math
import time
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np
from numpy.typing import NDArray

from prs_geom.checks.brep import complete_solid_problems, measure_solid
from prs_geom.exports.step import (StepSolid, _band_faces, _body_face, _boolean, _circle_wire, _end_wire,
                                   _occ_cylinder, _occ_surface, _plane_face, _revolved, _sew_solid,
                                   complete_part_failed, complete_part_result, require_ocp)
from prs_geom.mesh.bspline_bands import fit_bands
from prs_geom.mesh.mechanism_solids import Cylinder

if TYPE_CHECKING:  # pragma: no cover
    from prs_geom.geometry.gears import SpurGear
    from prs_geom.model.design import PRSDesign

__all__ = ["TIP_CLEARANCE_MM", "ZONE_FACE_TURNS", "complete_nut_solid", "complete_roller_solid", "gear_outline_wire"]

#: A pinion tip within this of the roller's crest radius (mm) is drawn this far beyond it:
#: a tip cylinder on the crest cylinder makes the cut's intersections tangent (slow and
#: fragile), and beyond the crest the thread bounds the part, so the solid is the same.
TIP_CLEARANCE_MM = 0.05
#: Turns per thread face in a gear zone; the zone's faces also reach this far into the
#: thread, so that the tube's end plane (the gear face) cuts them across instead of running
#: along their edges. Measured on the reduced roller of the tests (6 teeth): the cut took 127 s
#: with 1/20-turn faces split at the gear face, 75 s with quarter-turn faces reaching a quarter
#: turn into the thread (docs/step.md).
ZONE_FACE_TURNS = 0.25


# --------------------------------------------------------------------------- outlines
def _spline_edge(points: NDArray[np.float64], z: float):
    """An edge interpolating the 2-D ``points`` in the plane z (a B-spline through every point)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge
    from OCP.collections import HArray1_gp_Pnt
    from OCP.GeomAPI import GeomAPI_Interpolate
    from OCP.gp import gp_Pnt

    arr = HArray1_gp_Pnt(1, len(points))
    for i, (x, y) in enumerate(points.tolist()):
        arr.SetValue(i + 1, gp_Pnt(x, y, z))
    interp = GeomAPI_Interpolate(arr, False, 1e-9)
    interp.Perform()
    return BRepBuilderAPI_MakeEdge(interp.Curve()).Edge()


def _arc_edge(p0: NDArray, angle_mid: float, radius: float, p1: NDArray, z: float):
    """The circular arc about the axis from ``p0`` through the point at ``angle_mid`` to ``p1``."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge
    from OCP.GC import GC_MakeArcOfCircle
    from OCP.gp import gp_Pnt

    mid = (radius * math.cos(angle_mid), radius * math.sin(angle_mid))
    arc = GC_MakeArcOfCircle(gp_Pnt(p0[0], p0[1], z), gp_Pnt(mid[0], mid[1], z), gp_Pnt(p1[0], p1[1], z))
    return BRepBuilderAPI_MakeEdge(arc.Value()).Edge()


def _rotated(points: NDArray[np.float64], angle: float) -> NDArray[np.float64]:
    c, s = math.cos(angle), math.sin(angle)
    return points @ np.array([[c, s], [-s, c]])


def gear_outline_wire(gear: "SpurGear", z: float, phase_rad: float = 0.0, tip_radius_mm: float | None = None):
    """The closed outline of ``gear`` in the plane z (gear frame rotated by ``phase_rad``,
    mm) as an OpenCascade wire: per tooth the left flank, the tip arc, the right flank and
    the root arc to the next tooth.

    Each flank is its root fillet and its involute, each an interpolating B-spline through
    points of the analytic curve (:meth:`~prs_geom.geometry.gears.SpurGear.flank_polyline`
    at 1 um chords for the fillet, 40 points of
    :meth:`~prs_geom.geometry.gears.SpurGear.involute_polar` for the involute), joined at
    the form radius. ``tip_radius_mm``: the involute continued to this radius (an external
    gear's tip moved outward, :data:`TIP_CLEARANCE_MM`); the gear's own tip when None.
    """
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeWire

    pts, first_involute = gear.flank_polyline(1e-3)
    pts = np.asarray(pts, dtype=np.float64)
    r_tip = gear.tip_radius_mm if tip_radius_mm is None else float(tip_radius_mm)
    r_form = float(np.hypot(*pts[first_involute]))
    involute = gear.flank_points(np.linspace(r_form, r_tip, 40))
    fillet = pts[: first_involute + 1]
    mirror = np.array([1.0, -1.0])
    wire = BRepBuilderAPI_MakeWire()
    pitch = 2.0 * math.pi / gear.teeth
    for j in range(gear.teeth):
        a = phase_rad + j * pitch
        right_fillet, right_inv = _rotated(fillet, a), _rotated(involute, a)
        left_fillet, left_inv = _rotated(fillet * mirror, a), _rotated(involute * mirror, a)
        if len(fillet) > 1:
            wire.Add(_spline_edge(left_fillet, z))
        wire.Add(_spline_edge(left_inv, z))
        wire.Add(_arc_edge(left_inv[-1], a, r_tip, right_inv[-1], z))
        wire.Add(_spline_edge(right_inv[::-1], z))
        if len(fillet) > 1:
            wire.Add(_spline_edge(right_fillet[::-1], z))
        next_root = _rotated(fillet[:1] * mirror, a + pitch)[0]
        wire.Add(_arc_edge(right_fillet[0], a + 0.5 * pitch, gear.root_radius_mm, next_root, z))
    if not wire.IsDone():
        raise RuntimeError(f"the outline of the {gear.teeth}-tooth gear does not close (wire error {wire.Error()})")
    return wire.Wire()


def _prism(face: Any, z0: float, z1: float):
    from OCP.BRepPrimAPI import BRepPrimAPI_MakePrism
    from OCP.gp import gp_Vec

    return BRepPrimAPI_MakePrism(face, gp_Vec(0.0, 0.0, z1 - z0)).Shape()


def _cylinder(radius: float, z0: float, z1: float, x: float = 0.0, y: float = 0.0):
    """The full cylinder of ``radius`` from z0 to z1 about the axis through (x, y) (mm)."""
    return _occ_cylinder(Cylinder(radius=radius, height=z1 - z0, origin=(x, y, z0)))


def _faces(shape: Any) -> list:
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    out, ex = [], TopExp_Explorer(shape, TopAbs_FACE)
    while ex.More():
        out.append(TopoDS.Face(ex.Current()))
        ex.Next()
    return out


def _on_plane(face: Any, z: float) -> bool:
    """True for a face on the plane z = const (normal along the axis)."""
    from OCP.BRep import BRep_Tool
    from OCP.GeomAbs import GeomAbs_Plane
    from OCP.GeomAdaptor import GeomAdaptor_Surface

    surf = GeomAdaptor_Surface(BRep_Tool.Surface_s(face))
    if surf.GetType() != GeomAbs_Plane:
        return False
    plane = surf.Plane()
    return abs(abs(plane.Axis().Direction().Z()) - 1.0) < 1e-12 and abs(plane.Location().Z() - z) < 1e-9


def _sewn_solid(faces: Sequence[Any]):
    """:func:`~prs_geom.exports.step._sew_solid` (whose sewing splits edges where one face's
    edge runs along pieces of several others: the joined end planes), raising RuntimeError
    with its reason when the faces do not close into one solid."""
    solid, reason = _sew_solid(list(faces))
    if solid is None:
        raise RuntimeError(reason)
    return solid


# --------------------------------------------------------------------------- shared steps
def _complete_result(thread: StepSolid, shape: Any, mesh_volume_mm3: float, mesh_bounds: Any,
                     filled_mm3: float, started: float) -> StepSolid:
    """``thread`` turned into the complete part ``shape`` with its checks (module doc)."""
    measured = measure_solid(shape, gears=True)
    problems = complete_solid_problems(measured, mesh_volume_mm3)
    return complete_part_result(thread, shape, measured, problems, mesh_volume_mm3, mesh_bounds, None, filled_mm3,
                                started)


def _geared(design: "PRSDesign", thread: StepSolid) -> tuple[Any, Any] | None:
    """The design's gear pair and mechanism layout when a complete geared part can be built
    on ``thread`` (end gears, the mechanism and a valid thread body), else None."""
    require_ocp()
    from prs_geom.geometry.gear_pair import design_gear_pair
    from prs_geom.geometry.mechanism import layout

    pair = design_gear_pair(design)
    if pair is None or not design.mechanism.enabled or not thread.valid:
        return None
    return pair, layout(design)


# --------------------------------------------------------------------------- roller
def _long_roller_body(design: "PRSDesign", w: float, target_mm: float):
    """The roller's thread body over [-w, L + w] without a datum slot (faces
    :data:`ZONE_FACE_TURNS` long in the gear zones, which reach that far past the gear faces
    z = 0 and z = L into the thread), its profile and its thread length L (mm)."""
    from prs_geom.geometry.profiles import ThreadProfiles
    from prs_geom.mesh.assembly import FIRST_MID_PITCHES, part_warps, thread_length
    from prs_geom.mesh.thread import part_chord_tolerance, thread_mesh

    prof = ThreadProfiles.from_design(design).roller
    L = thread_length(design)
    tm = thread_mesh(prof, -w, L + w, part_chord_tolerance(prof, design.mesh.chord_tolerance_mm),
                     FIRST_MID_PITCHES["roller"] * design.thread.pitch_mm, part_warps(design)["roller"])
    fit = fit_bands(tm, target_mm)
    surfaces = [_occ_surface(n, prof.hand_sign < 0, tm.z_lo, tm.z_hi) for n in fit.nets]
    reach = ZONE_FACE_TURNS * prof.lead
    faces = _band_faces(surfaces, tm, ((-w, reach, ZONE_FACE_TURNS), (reach, L - reach, 1.0),
                                       (L - reach, L + w, ZONE_FACE_TURNS)))
    faces += [_plane_face(z, [_end_wire(surfaces, z)]) for z in (-w, L + w)]
    return _sewn_solid(faces), prof, L


def complete_roller_solid(design: "PRSDesign", thread: StepSolid, mesh_volume_mm3: float,
                          mesh_bounds: Any = None) -> StepSolid:
    """The complete roller as one B-rep solid: thread, end gears cut through its ends,
    chamfers, journals (module doc). ``thread`` (the roller's :func:`~prs_geom.exports.step.step_solid`)
    itself when the design has no end gears or no mechanism, or ``thread`` is not valid.

    ``mesh_volume_mm3`` and ``mesh_bounds`` ((2, 3), mm) are the complete roller mesh's
    (:mod:`prs_geom.mesh.parts`), which the B-rep must match
    (:data:`~prs_geom.checks.brep.COMPLETE_VOLUME_REL_LIMIT`,
    :data:`~prs_geom.exports.step.BBOX_MESH_LIMIT_MM`). The thread bands are fitted to the
    thread body's deviation target. When OpenCascade fails, the result is not valid and has
    no shape.
    """
    geared = _geared(design, thread)
    if geared is None:
        return thread
    from prs_geom.geometry.datum import datum_mark
    from prs_geom.geometry.gear_phasing import roller_gear_phasing
    from prs_geom.mesh.assembly import carrier_angles, design_run_outs, roller_spin
    from prs_geom.mesh.thread import RUN_OUT_OVERSHOOT_MM

    pair, mech = geared
    started = time.perf_counter()
    psi = carrier_angles(design)
    chi = np.array([roller_spin(design, a) for a in psi])
    phase = roller_gear_phasing(pair.pinion, pair.ring, psi, chi).offset_rad
    w = pair.pinion.face_width_mm
    try:
        body, prof, L = _long_roller_body(design, w, thread.deviation_target_mm)
        rc = prof.crest_radius
        tip = pair.pinion.tip_radius_mm
        tip = rc + TIP_CLEARANCE_MM if tip > rc - TIP_CLEARANCE_MM else tip
        tools = []
        for z0, z1 in ((-w - 1.0, 0.0), (L, L + w + 1.0)):
            face = _plane_face(z0, [_circle_wire(rc + 1.0, z0), gear_outline_wire(pair.pinion, z0, phase, tip)])
            tools.append(_prism(face, z0, z1))
        for ro in design_run_outs(design, "roller"):    # 45 degree chamfers of the crest
            r_e, R = rc - ro.length_mm, rc + RUN_OUT_OVERSHOOT_MM
            z_end, inward = (0.0, 1.0) if ro.end == "lo" else (L, -1.0)
            tools.append(_revolved([(r_e, z_end), (R, z_end), (R, z_end + inward * (R - r_e))]))
        shape = _boolean("cut", body, tools)
        r_j = 0.5 * mech.journal_fit.shaft_diameter_mm
        shape = _boolean("fuse", shape, [_cylinder(r_j, *end.journal) for end in mech.ends])
    except Exception as exc:  # noqa: BLE001 - OCC raises its own Standard_Failure types
        return complete_part_failed(thread, "roller", exc)
    filled = datum_mark(prof, 0.0).volume      # the slot in face A, buried under the gear
    return _complete_result(thread, shape, mesh_volume_mm3, mesh_bounds, filled, started)


# --------------------------------------------------------------------------- nut
def _nut_end_solid(mech: Any, end: Any, ring_gear: Any, flange: Any):
    """One nut end as the complete mesh has it (:mod:`prs_geom.mesh.mechanism`): the outer
    cylinder less the bore, the groove and the sleeve's bore around the ring gear, united
    with the ring gear's prism and, on its side, the flange."""
    R = mech.nut_end_outer_radius_mm
    z0, z1 = end.nut_end
    out, pad = end.outward < 0, 1.0
    gear = end.gear_zone
    bored = (z0 - pad, gear[0]) if out else (gear[1], z1 + pad)
    cuts = [(mech.nut_bore_radius_mm, bored), (mech.groove_radius_mm, end.groove),
            (mech.nut_end_sleeve_inner_radius_mm, (gear[0] - (0.0 if out else pad), gear[1] + (pad if out else 0.0)))]
    shape = _boolean("cut", _cylinder(R, z0, z1), [_cylinder(r, a, b) for r, (a, b) in cuts])
    return _boolean("fuse", shape, [ring_gear] + ([flange] if flange is not None else []))


def _flange_solid(design: "PRSDesign", mech: Any) -> tuple[Any, tuple[float, float]] | None:
    """The nut flange (:mod:`prs_geom.mesh.actuator`): an annulus with its bolt holes, and
    its z span (mm); None without a flange mounting."""
    from prs_geom.geometry.actuator import actuator_layout
    from prs_geom.mesh.actuator import FLANGE_OVERLAP_MM

    lay = actuator_layout(design)
    if lay is None or lay.nut_mount.kind != "flange":
        return None
    m = lay.nut_mount
    z0, z1 = m.z
    r_bc = 0.5 * m.bolt_circle_diameter_mm
    angles = math.pi / m.bolt_count + 2.0 * math.pi * np.arange(m.bolt_count) / m.bolt_count
    holes = [_cylinder(0.5 * m.bolt.clearance_hole_mm, z0 - 1.0, z1 + 1.0, r_bc * math.cos(a), r_bc * math.sin(a))
             for a in angles]
    inner = _cylinder(mech.nut_end_outer_radius_mm - FLANGE_OVERLAP_MM, z0 - 1.0, z1 + 1.0)
    return _boolean("cut", _cylinder(0.5 * m.flange_diameter_mm, z0, z1), [inner] + holes), (z0, z1)


def _planar_difference(a: Any, b: Any) -> list:
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut

    op = BRepAlgoAPI_Cut(a, b)
    if not op.IsDone():
        raise RuntimeError("a planar difference of the nut's end faces failed")
    return _faces(op.Shape())


def complete_nut_solid(design: "PRSDesign", thread: StepSolid, mesh_volume_mm3: float,
                       mesh_bounds: Any = None) -> StepSolid:
    """The complete nut as one B-rep solid: thread, ring gears, nut ends with their grooves
    and, with a flange mounting, the flange (module doc). ``thread`` itself when the design
    has no end gears or no mechanism, or ``thread`` is not valid. Checks and failure as
    :func:`complete_roller_solid`."""
    geared = _geared(design, thread)
    if geared is None:
        return thread
    from prs_geom.geometry.gear_pair import ring_gear_outer_radius
    from prs_geom.mesh.bspline_bands import thread_solid_reference

    pair, mech = geared
    started = time.perf_counter()
    try:
        ref = thread_solid_reference(design, "nut", thread.chord_tolerance_mm)
        tm = ref.mesh
        fit = fit_bands(tm, ref.deviation_target_mm)
        surfaces = [_occ_surface(n, ref.mirror, tm.z_lo, tm.z_hi) for n in fit.nets]
        faces = _band_faces(surfaces, tm) + [_body_face(tm.body_radius, tm.z_lo, tm.z_hi)]
        flange = _flange_solid(design, mech)
        R_ring = ring_gear_outer_radius(design, pair)
        for end in sorted(mech.ends, key=lambda e: e.outward):
            z = tm.z_lo if end.outward < 0 else tm.z_hi
            ring = _prism(_plane_face(end.gear_zone[0], [_circle_wire(R_ring, end.gear_zone[0]),
                                                         gear_outline_wire(pair.ring, end.gear_zone[0])]),
                          *end.gear_zone)
            # the flange belongs to the end whose span it lies in
            on_end = flange is not None and end.nut_end[0] <= flange[1][0] < end.nut_end[1]
            rest = _nut_end_solid(mech, end, ring, flange[0] if on_end else None)
            thread_end = _plane_face(z, [_circle_wire(tm.body_radius, z), _end_wire(surfaces, z)])
            rest_end = _plane_face(z, [_circle_wire(mech.nut_end_outer_radius_mm, z), gear_outline_wire(pair.ring, z)])
            faces += [f for f in _faces(rest) if not _on_plane(f, z)]
            faces += _planar_difference(thread_end, rest_end) + _planar_difference(rest_end, thread_end)
        shape = _sewn_solid(faces)
    except Exception as exc:  # noqa: BLE001 - OCC raises its own Standard_Failure types
        return complete_part_failed(thread, "nut", exc)
    return _complete_result(thread, shape, mesh_volume_mm3, mesh_bounds, tm.datum_mark.volume, started)
