"""Checks and measurements of OpenCascade B-rep solids (the STEP export's parts).

Every function takes OpenCascade shapes (``cadquery-ocp``, module ``OCP``, imported inside
the functions, so importing this module works without the optional extra ``step``):
validity (``BRepCheck_Analyzer``, one solid), volume, bounding boxes, tolerances, the
agreement of OCC's B-spline faces with the fitted nets of
:mod:`prs_geom.mesh.bspline_bands`, and of a solid with its copy read back from a file.
Lengths are mm, volumes mm^3.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from prs_geom.mesh.bspline_bands import evaluate_net

if TYPE_CHECKING:  # pragma: no cover
    from prs_geom.mesh.bspline_bands import BSplineNet

__all__ = ["COMPLETE_VOLUME_REL_LIMIT", "GEAR_FACE_DEFLECTION_MM", "REREAD_BBOX_TOLERANCE", "SURFACE_HANDOVER_SHARE", "VOLUME_REL_LIMIT", "SolidMeasurement",
           "bbox_gap", "closed_form_volume_problem", "complete_solid_problems", "count_subshapes", "gear_solid_volume", "is_valid_shape", "measure_solid",
           "occ_bbox", "reread_problems", "shape_volume", "surface_handover_error", "thread_solid_problems"]

#: Largest relative volume difference B-rep vs reference mesh (or closed form) that counts as valid.
VOLUME_REL_LIMIT = 1e-3
#: A complete part's B-rep against its mesh: the mesh's polygons (ends, keyway) sit inside the
#: true circles by their chord tolerance, 0.05-0.08 % of the volume on the default design.
COMPLETE_VOLUME_REL_LIMIT = 2e-3
#: Largest difference (mm) between the bounding box of a solid and of its copy read back
#: from the STEP file (on top of OCC's box gaps); measured: below 1e-12 mm.
REREAD_BBOX_TOLERANCE = 1e-6
#: Largest distance between OCC's faces and the fitted splines, per mm of the largest |z|
#: of the part (at least 1 mm): rounding only, a wrong knot or pole is far beyond it.
SURFACE_HANDOVER_SHARE = 1e-9


def count_subshapes(shape: Any, kind: Any) -> int:
    """Number of sub-shapes of type ``kind`` (a ``TopAbs_ShapeEnum``) in ``shape``."""
    from OCP.TopExp import TopExp_Explorer

    n = 0
    ex = TopExp_Explorer(shape, kind)
    while ex.More():
        n += 1
        ex.Next()
    return n


def shape_volume(shape: Any) -> float:
    """Volume (mm^3) of a shape (``BRepGProp.VolumeProperties_s``)."""
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    # adaptive integration: the default Gauss rule misjudges long B-spline faces by 2e-4
    BRepGProp.VolumeProperties_s(shape, props, 1e-6, False)
    return float(props.Mass())


def occ_bbox(shape: Any) -> tuple[float, float, float, float, float, float]:
    """OpenCascade's bounding box (``BRepBndLib.Add_s``, no triangulation): (xmin, ymin,
    zmin, xmax, ymax, zmax) (mm), enlarged by the shape tolerances and the box's gap.

    Fast and deterministic, so it compares a solid with its re-imported copy; on B-spline
    faces it encloses the control points, which stand off a quintic helix band (0.2 mm
    beyond the default roller, 0.6 mm beyond the screw), so it is not the part's extent
    (see :func:`prs_geom.mesh.bspline_bands.sampled_bbox`).
    """
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    BRepBndLib.Add_s(shape, box, False)
    lo, hi = box.CornerMin(), box.CornerMax()
    return (lo.X(), lo.Y(), lo.Z(), hi.X(), hi.Y(), hi.Z())


def bbox_gap(shape: Any) -> float:
    """The gap (mm) OpenCascade adds around the shape's bounding box (``Bnd_Box.GetGap``)."""
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    BRepBndLib.Add_s(shape, box, False)
    return float(box.GetGap())


def is_valid_shape(shape: Any) -> bool:
    """``BRepCheck_Analyzer(shape).IsValid()``."""
    from OCP.BRepCheck import BRepCheck_Analyzer

    return bool(BRepCheck_Analyzer(shape).IsValid())


def surface_handover_error(surfaces: Sequence[Any], nets: Sequence["BSplineNet"], mirror: bool) -> float:
    """Largest distance (mm) between OCC's surfaces (``Geom_BSplineSurface``, one per net)
    and the scipy splines at a few parameter points per face: catches a wrong knot or pole
    hand-over. ``mirror``: the surfaces are the nets' mirror images y -> -y."""
    worst = 0.0
    for surf, net in zip(surfaces, nets):
        u0, u1 = float(net.tv[0]), float(net.tv[-1])
        z0, z1 = surf.Bounds()[2:]
        us = np.array([u0, 0.37 * u0 + 0.63 * u1, u1])
        zs = np.array([z0, 0.71 * z0 + 0.29 * z1, 0.5 * (z0 + z1), z1])
        ref = evaluate_net(net, us, zs)
        if mirror:
            ref = ref * np.array([1.0, -1.0, 1.0])
        for i, u in enumerate(us.tolist()):
            for j, z in enumerate(zs.tolist()):
                q = surf.Value(u, z)
                worst = max(worst, math.dist((q.X(), q.Y(), q.Z()), ref[i, j]))
    return worst


@dataclass(frozen=True)
class SolidMeasurement:
    """What :func:`measure_solid` measures on a shape: volume (mm^3), faces, solids,
    the largest OpenCascade tolerance of a vertex, edge or face (mm) and whether
    ``BRepCheck_Analyzer`` accepts it."""

    volume_mm3: float
    faces: int
    solids: int
    max_tolerance_mm: float
    analyzer_valid: bool


#: Deflection (mm) of the triangulation that measures the faces other than B-spline surfaces
#: in :func:`gear_solid_volume`; the faces are planes, cylinders, cones and extruded gear
#: outlines, whose volume a triangulation at this deflection misses by about 1e-5.
GEAR_FACE_DEFLECTION_MM = 1e-3


def gear_solid_volume(shape: Any, deflection_mm: float = GEAR_FACE_DEFLECTION_MM) -> float:
    """Volume (mm^3) of a solid with extruded gear-outline faces: B-spline faces (the thread
    bands) integrated exactly, every other face from a triangulation at ``deflection_mm``.

    OpenCascade's integration misjudges a prism on a gear outline of interpolated flank
    curves: the default ring gear (100 teeth, 4 mm) gives 2339.2, 2371.7 or 2385.9 mm^3 by
    the rule chosen, against 2341.77 mm^3 from the outline's area times its height; triangulating
    the non-B-spline faces gives 2341.85 at 1e-4 mm (measured). Triangulating the thread
    bands too would cost 90 s on the nut; their exact integral is the one
    :func:`shape_volume` verifies against closed forms to 1e-6.
    """
    from OCP.BRep import BRep_Tool
    from OCP.BRepGProp import BRepGProp
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.GeomAbs import GeomAbs_BSplineSurface
    from OCP.GeomAdaptor import GeomAdaptor_Surface
    from OCP.GProp import GProp_GProps
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    ex = TopExp_Explorer(shape, TopAbs_FACE)
    while ex.More():
        face = TopoDS.Face(ex.Current())
        if GeomAdaptor_Surface(BRep_Tool.Surface_s(face)).GetType() != GeomAbs_BSplineSurface:
            BRepMesh_IncrementalMesh(face, deflection_mm, False, 0.1, True)
        ex.Next()
    props = GProp_GProps()
    # faces with a triangulation use it, the B-spline faces (none) their surfaces
    BRepGProp.VolumeProperties_s(shape, props, False, False, True)
    return float(props.Mass())


def measure_solid(shape: Any, gears: bool = False) -> SolidMeasurement:
    """Volume, face and solid counts, largest tolerance and validity of ``shape``;
    ``gears``: the volume by :func:`gear_solid_volume` (a solid with gear faces)."""
    from OCP.ShapeAnalysis import ShapeAnalysis_ShapeTolerance
    from OCP.TopAbs import TopAbs_FACE, TopAbs_SHAPE, TopAbs_SOLID

    volume = gear_solid_volume(shape) if gears else shape_volume(shape)
    faces = count_subshapes(shape, TopAbs_FACE)
    max_tol = ShapeAnalysis_ShapeTolerance().Tolerance(shape, 1, TopAbs_SHAPE)
    valid = is_valid_shape(shape)
    return SolidMeasurement(volume_mm3=volume, faces=faces, solids=count_subshapes(shape, TopAbs_SOLID),
                            max_tolerance_mm=max_tol, analyzer_valid=valid)


def thread_solid_problems(measured: SolidMeasurement, mesh_volume_mm3: float, max_deviation_mm: float,
                          deviation_target_mm: float, handover_mm: float, z_range: tuple[float, float]) -> list[str]:
    """What is wrong with a threaded part's B-rep (empty when nothing): rejected by
    ``BRepCheck_Analyzer``, not one solid, volume off the reference mesh's by more than
    ``VOLUME_REL_LIMIT``, B-spline faces beyond the deviation target, OCC's faces not the
    fitted splines (beyond ``SURFACE_HANDOVER_SHARE`` x max(1, |z_lo|, |z_hi|))."""
    problems = _solid_near_mesh(measured, mesh_volume_mm3, VOLUME_REL_LIMIT, f"the mesh's {mesh_volume_mm3:.6g} mm^3")
    if not max_deviation_mm <= deviation_target_mm:
        problems.append(f"B-spline faces deviate {max_deviation_mm:.3g} mm from the analytic surface "
                        f"(limit {deviation_target_mm:.3g} mm)")
    z_lo, z_hi = z_range
    if not handover_mm <= SURFACE_HANDOVER_SHARE * max(1.0, abs(z_hi), abs(z_lo)):
        problems.append(f"OpenCascade's faces differ from the fitted splines by {handover_mm:.3g} mm")
    return problems


def complete_solid_problems(measured: SolidMeasurement, mesh_volume_mm3: float) -> list[str]:
    """What is wrong with a complete part's B-rep (the thread body united with its ends):
    rejected by ``BRepCheck_Analyzer``, not one solid, or a volume off the complete part's
    mesh (:mod:`prs_geom.mesh.parts`) by more than :data:`COMPLETE_VOLUME_REL_LIMIT`."""
    return _solid_near_mesh(measured, mesh_volume_mm3, COMPLETE_VOLUME_REL_LIMIT,
                            f"the complete part's mesh ({mesh_volume_mm3:.6g} mm^3)")


def _solid_near_mesh(measured: SolidMeasurement, mesh_volume_mm3: float, limit: float, mesh_label: str) -> list[str]:
    """The problems shared by every B-rep built against a mesh: rejected by
    ``BRepCheck_Analyzer``, not one solid, volume off ``mesh_volume_mm3`` (named
    ``mesh_label`` in the message) by more than ``limit`` (relative)."""
    problems = []
    if not measured.analyzer_valid:
        problems.append("BRepCheck_Analyzer rejects the shape")
    if measured.solids != 1:
        problems.append(f"{measured.solids} solids instead of one")
    rel = (measured.volume_mm3 - mesh_volume_mm3) / mesh_volume_mm3
    if not abs(rel) <= limit:
        problems.append(f"volume {measured.volume_mm3:.6g} mm^3 differs from {mesh_label} by "
                        f"{100 * rel:.3g} % (limit {100 * limit:g} %)")
    return problems


def closed_form_volume_problem(measured: SolidMeasurement, exact_volume_mm3: float) -> str:
    """What is wrong with an exact B-rep (primitives and booleans) whose volume has a closed
    form: not one valid solid, or a volume off ``exact_volume_mm3`` by more than
    ``VOLUME_REL_LIMIT``; empty when nothing."""
    ok = measured.analyzer_valid and measured.solids == 1
    rel = (measured.volume_mm3 - exact_volume_mm3) / exact_volume_mm3
    if ok and abs(rel) <= VOLUME_REL_LIMIT:
        return ""
    if not ok:
        return "not one valid solid"
    return f"volume {measured.volume_mm3:.6g} mm^3 differs from the closed form by {rel:.2e}"


def reread_problems(written: Sequence[tuple[str, Any]], names: Sequence[str], shapes: Sequence[Any],
                    rows: dict[str, dict[str, Any]]) -> list[str]:
    """Compare the solids written to a file with the file read back.

    Each written (name, shape) must be among ``names`` (the free shapes read back, with
    ``shapes`` in the same order) with OpenCascade's bounding box unchanged within
    ``REREAD_BBOX_TOLERANCE`` plus the two boxes' gaps. Records ``reread_name`` and
    ``reread_bbox_max_diff_mm`` (mm) in ``rows[name]``; returns what failed.
    """
    problems = []
    for name, shape in written:
        row = rows[name]
        row["reread_name"] = name in names
        if not row["reread_name"]:
            problems.append(f"the {name} is missing by name in the file read back")
            continue
        other = shapes[list(names).index(name)]
        a, b = occ_bbox(shape), occ_bbox(other)
        diff = max(abs(x - y) for x, y in zip(a, b))
        row["reread_bbox_max_diff_mm"] = diff
        if not diff <= REREAD_BBOX_TOLERANCE + max(bbox_gap(shape), bbox_gap(other)):
            problems.append(f"the {name}'s bounding box read back differs by {diff:.3g} mm")
    return problems
