"""STEP export of the threaded parts and the mechanism parts as closed B-rep solids
(optional extra ``step``).

This module converts to OpenCascade shapes and writes the file; the numbers come from
elsewhere: the B-spline nets of the thread surface from :mod:`prs_geom.mesh.bspline_bands`
(fitted to the analytic surface within a measured deviation), the carrier and retaining ring
as cylinders to cut from :mod:`prs_geom.mesh.mechanism_solids`, and the checks that make a
solid trustworthy (``BRepCheck_Analyzer``, volume against the reference mesh or the closed
form, OCC's faces against the nets, the file read back) from :mod:`prs_geom.checks.brep`.
OpenCascade comes from ``cadquery-ocp`` (module ``OCP``), imported inside the functions only,
so importing this module works without the extra; calling one without it raises
:class:`~prs_geom.model.errors.EnvironmentFailure` with the install command. docs/step.md
explains the construction, the tolerance and the limits.

Construction of a threaded part (no boolean at all): each band's net becomes a
``Geom_BSplineSurface`` (mirrored y -> -y for a left-hand part) cut into faces of at most
:data:`~prs_geom.mesh.bspline_bands.TURNS_PER_FACE` turns; these faces, the plane end faces
bounded by the bands' iso-curves z = const, the nut's body cylinder and the five faces of
the angular datum slot B (:mod:`prs_geom.geometry.datum`, a rectangular hole in face A) are
sewn into one shell (``BRepBuilderAPI_Sewing``), made a solid and oriented outward. Every solid is in its own
part frame (mm, z along the part axis, face A at the lower z).
"""
from __future__ import annotations

import contextlib
import dataclasses
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np
from numpy.typing import NDArray

from prs_geom.checks.brep import (closed_form_volume_problem, complete_solid_problems, measure_solid, occ_bbox,
                                  reread_problems, surface_handover_error, thread_solid_problems)
from prs_geom.mesh.bspline_bands import (DEGREE, BandFit, BSplineNet, ThreadSolidReference, face_z_cuts, fit_bands,
                                         sampled_bbox, thread_solid_reference)
from prs_geom.mesh.mechanism_solids import Cylinder, CylinderSolid, mechanism_part_mesh, mechanism_solid
from prs_geom.model.errors import EnvironmentFailure
from prs_geom.model.io import atomic_path

if TYPE_CHECKING:  # pragma: no cover
    from prs_geom.geometry.profiles import ThreadProfile
    from prs_geom.mesh.thread import ThreadMesh
    from prs_geom.model.design import PRSDesign

__all__ = ["AUTHORITY_NOTE", "BBOX_MESH_LIMIT_MM", "INSTALL_HINT", "MECHANISM_STEP_PARTS", "PARTS", "SEW_TOLERANCE",
           "STEP_SCHEMA", "StepFileContent", "StepSolid", "complete_part_failed", "complete_part_result", "complete_screw_solid", "mechanism_step_solid",
           "read_document", "read_step", "require_ocp", "stadium_prism", "step_solid", "write_document", "write_solids",
           "write_step"]

PARTS = ("screw", "roller", "nut")
#: The mechanism parts with a STEP file of their own (the journals and nut ends belong to the
#: complete roller and nut, :mod:`prs_geom.exports.step_gears`).
MECHANISM_STEP_PARTS = ("carrier", "retaining_ring")
#: Install command named by :class:`EnvironmentFailure` when OCP is missing.
INSTALL_HINT = 'pip install "prs-geom[step]"'
#: STEP schema written (``write.step.schema``): AP214 international standard.
STEP_SCHEMA = "AP214IS"
#: What the file header says about precision (FILE_DESCRIPTION).
AUTHORITY_NOTE = ("prs-geom B-rep of the analytic thread surfaces within the chord tolerance; "
                  "the machining sheet is the authority for sub-micrometre pitch grading")
#: Sewing tolerance (mm): shared iso-curves are identical to rounding, so this only has to
#: absorb float64 noise, far below any tolerance a shop can see.
SEW_TOLERANCE = 1e-6


# --------------------------------------------------------------------------- results
@dataclass(frozen=True, kw_only=True)
class StepSolid:
    """One part as a B-rep solid and the checks made on it.

    Attributes
    ----------
    part : str
        "screw", "roller" or "nut", or a mechanism part (:data:`MECHANISM_STEP_PARTS`).
    shape : TopoDS_Shape or None
        The solid in the part frame (mm, z along the part axis, face A at the lower z),
        None when it could not be built at all.
    valid : bool
        True when ``BRepCheck_Analyzer`` accepts the shape, it is one closed solid, its
        volume agrees with the reference mesh within
        :data:`~prs_geom.checks.brep.VOLUME_REL_LIMIT`, its B-spline
        faces stay within ``deviation_target_mm`` of the analytic surface and OCC holds
        the same surfaces as were fitted.
    reason : str
        Empty when valid, else what failed.
    volume_mm3 : float
        Volume of the B-rep (``BRepGProp``), datum slot cut (mm^3).
    mesh_volume_mm3 : float
        Volume of the part's triangle mesh with its datum slot
        (:func:`prs_geom.mesh.assembly.build_part` at ``mesh_tolerance_mm``) (mm^3).
    volume_rel_diff : float
        (volume_mm3 - mesh_volume_mm3) / mesh_volume_mm3.
    bbox : tuple of float
        (xmin, ymin, zmin, xmax, ymax, zmax) of the solid in the part frame (mm): its
        extent, sampled on the fitted faces (:func:`~prs_geom.mesh.bspline_bands.sampled_bbox`,
        error about 1e-5 mm). NaN when no solid was built.
    build_time_s : float
        Wall time of the whole call: surfaces, sewing, slot, checks (s).
    faces : int
        Number of B-rep faces.
    chord_tolerance_mm : float
        The tolerance the part was built for (mm).
    mesh_tolerance_mm : float
        The chord tolerance of the reference mesh (mm).
    max_deviation_mm : float
        Largest measured distance of the B-spline faces from the analytic surface (mm).
    analytic_volume_mm3 : float or None
        Exact volume for constant pitch (closed form minus the slot), None when graded.
    design_mesh_volume_mm3 : float
        Volume of the part's mesh at the design tolerance ``chord_tolerance_mm`` (mm^3),
        for comparison: its inscribed polygons make it smaller by up to about 0.3 %.
    deviation_target_mm : float
        The deviation the B-spline faces were fitted to
        (:func:`~prs_geom.mesh.bspline_bands.thread_solid_reference`) (mm).
    max_tolerance_mm : float
        Largest OpenCascade tolerance of a vertex, edge or face of the solid (mm): how
        closely the sewn topology fits together (1e-7, the minimum, on every part measured).
    grid : dict
        Sampling of the B-spline faces: degree, grid columns per turn and along the part,
        points across each band kind.
    complete : bool
        True when the solid is the complete part (the thread united with its ends,
        :func:`complete_screw_solid`); ``volume_mm3``, ``mesh_volume_mm3`` and ``bbox`` are
        then the complete part's, the deviation fields the thread body's.
    thread_volume_mm3, thread_analytic_volume_mm3 : float or None
        Of a complete part: its thread body's B-rep volume and that body's closed form
        (constant pitch) (mm^3), None otherwise.
    filled_voids_mm3 : float
        Volume of closed voids filled in the union (a datum slot an end covers), mm^3.
    """

    part: str
    shape: Any
    valid: bool
    reason: str
    volume_mm3: float
    mesh_volume_mm3: float
    volume_rel_diff: float
    bbox: tuple[float, float, float, float, float, float]
    build_time_s: float
    faces: int
    chord_tolerance_mm: float = 0.0
    mesh_tolerance_mm: float = 0.0
    max_deviation_mm: float = math.nan
    analytic_volume_mm3: float | None = None
    design_mesh_volume_mm3: float = math.nan
    deviation_target_mm: float = math.nan
    max_tolerance_mm: float = math.nan
    grid: dict[str, Any] = field(default_factory=dict)
    complete: bool = False
    thread_volume_mm3: float | None = None
    thread_analytic_volume_mm3: float | None = None
    filled_voids_mm3: float = 0.0

    def report(self) -> dict[str, Any]:
        """The per-part entry of the report section ``step`` (JSON types only; a value that
        could not be measured is None)."""
        def num(x: float | None) -> float | None:
            return None if x is None or not math.isfinite(x) else float(x)

        return {
            "valid": self.valid,
            "reason": self.reason,
            "volume_mm3": num(self.volume_mm3),
            "mesh_volume_mm3": num(self.mesh_volume_mm3),
            "volume_rel_diff": num(self.volume_rel_diff),
            "analytic_volume_mm3": num(self.analytic_volume_mm3),
            "design_mesh_volume_mm3": num(self.design_mesh_volume_mm3),
            "faces": self.faces,
            "time_s": self.build_time_s,
            "chord_tolerance_mm": self.chord_tolerance_mm,
            "mesh_tolerance_mm": self.mesh_tolerance_mm,
            "max_deviation_mm": num(self.max_deviation_mm),
            "deviation_target_mm": num(self.deviation_target_mm),
            "max_tolerance_mm": num(self.max_tolerance_mm),
            "bbox_mm": [num(x) for x in self.bbox],
            "grid": dict(self.grid),
            "complete": self.complete,
            "thread_volume_mm3": num(self.thread_volume_mm3),
            "thread_analytic_volume_mm3": num(self.thread_analytic_volume_mm3),
            "filled_voids_mm3": float(self.filled_voids_mm3),
        }


# --------------------------------------------------------------------------- OCP
def require_ocp() -> None:
    """Raise :class:`EnvironmentFailure` with the install command when OCP is missing."""
    try:
        import OCP  # noqa: F401
    except ImportError:
        raise EnvironmentFailure("the STEP export needs OpenCascade (the optional extra 'step', "
                                 f"package cadquery-ocp), which is not installed: {INSTALL_HINT}") from None


# --------------------------------------------------------------------------- OCC faces
def _occ_surface(net: BSplineNet, mirror: bool, z_lo: float, z_hi: float):
    """The net as a Geom_BSplineSurface (U across the band, V along z), segmented to
    z_lo <= V <= z_hi."""
    from OCP.collections import Array1_double, Array1_int, Array2_gp_Pnt
    from OCP.Geom import Geom_BSplineSurface
    from OCP.gp import gp_Pnt

    P = net.poles * (np.array([1.0, -1.0, 1.0]) if mirror else 1.0)
    nu, nv = P.shape[0], P.shape[1]
    poles = Array2_gp_Pnt(1, nu, 1, nv)
    for i in range(nu):
        for j, (x, y, zz) in enumerate(P[i].tolist()):
            poles.SetValue(i + 1, j + 1, gp_Pnt(x, y, zz))

    def knots(t: NDArray):
        vals, counts = np.unique(t, return_counts=True)
        kn, mu = Array1_double(1, len(vals)), Array1_int(1, len(vals))
        for i, (a, c) in enumerate(zip(vals.tolist(), counts.tolist())):
            kn.SetValue(i + 1, a)
            mu.SetValue(i + 1, int(c))
        return kn, mu

    uk, um = knots(net.tv)
    vk, vm = knots(net.tz)
    surf = Geom_BSplineSurface(poles, uk, vk, um, vm, DEGREE, DEGREE, False, False)
    surf.Segment(float(net.tv[0]), float(net.tv[-1]), z_lo, z_hi)
    return surf


def _end_wire(surfaces: list, z_end: float):
    """The closed wire of the band iso-curves V = z_end, in band order."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeWire

    mk = BRepBuilderAPI_MakeWire()
    for s in surfaces:
        mk.Add(BRepBuilderAPI_MakeEdge(s.VIso(z_end)).Edge())
    if not mk.IsDone():
        raise RuntimeError(f"the end curve at z = {z_end:g} mm does not close (wire error {mk.Error()})")
    return mk.Wire()


def _circle_wire(radius: float, z_end: float):
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeWire
    from OCP.gp import gp_Ax2, gp_Circ, gp_Dir, gp_Pnt

    circ = gp_Circ(gp_Ax2(gp_Pnt(0.0, 0.0, z_end), gp_Dir(0.0, 0.0, 1.0)), radius)
    return BRepBuilderAPI_MakeWire(BRepBuilderAPI_MakeEdge(circ).Edge()).Wire()


def _plane_face(z_end: float, wires: Sequence):
    """Plane face z = z_end bounded by ``wires`` (outer first), wire orientation fixed."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.gp import gp_Dir, gp_Pln, gp_Pnt
    from OCP.ShapeFix import ShapeFix_Face

    mk = BRepBuilderAPI_MakeFace(gp_Pln(gp_Pnt(0.0, 0.0, z_end), gp_Dir(0.0, 0.0, 1.0)), wires[0], True)
    for w in wires[1:]:
        mk.Add(w)
    if not mk.IsDone():
        raise RuntimeError(f"the end face at z = {z_end:g} mm could not be made (error {mk.Error()})")
    fix = ShapeFix_Face(mk.Face())
    fix.FixOrientation()   # a hole's wire must run opposite to the outer one
    fix.Perform()
    return fix.Face()


def _body_face(radius: float, z_lo: float, z_hi: float):
    """The nut's outer cylinder between the end planes (an exact cylindrical face)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.Geom import Geom_CylindricalSurface
    from OCP.gp import gp_Ax3, gp_Dir, gp_Pnt

    cyl = Geom_CylindricalSurface(gp_Ax3(gp_Pnt(0.0, 0.0, 0.0), gp_Dir(0.0, 0.0, 1.0)), radius)
    return BRepBuilderAPI_MakeFace(cyl, 0.0, 2.0 * math.pi, z_lo, z_hi, 1e-7).Face()


def _sew_solid(faces: list):
    """Sew the faces into one shell and make it an outward-oriented solid.

    Returns (solid or None, reason)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeSolid, BRepBuilderAPI_Sewing
    from OCP.BRepLib import BRepLib
    from OCP.TopAbs import TopAbs_SHELL
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    sew = BRepBuilderAPI_Sewing(SEW_TOLERANCE)
    for f in faces:
        sew.Add(f)
    sew.Perform()
    if sew.NbFreeEdges() or sew.NbMultipleEdges() or sew.NbDegeneratedShapes():
        return None, (f"sewing left {sew.NbFreeEdges()} free, {sew.NbMultipleEdges()} multiple edges and "
                      f"{sew.NbDegeneratedShapes()} degenerated shapes")
    shells = []
    ex = TopExp_Explorer(sew.SewedShape(), TopAbs_SHELL)
    while ex.More():
        shells.append(TopoDS.Shell(ex.Current()))
        ex.Next()
    if len(shells) != 1:
        return None, f"sewing gave {len(shells)} shells, not one"
    solid = BRepBuilderAPI_MakeSolid(shells[0]).Solid()
    if not BRepLib.OrientClosedSolid_s(solid):
        return None, "the sewn shell does not enclose a volume (OrientClosedSolid failed)"
    return solid, ""


def _slot(mark) -> tuple[Any, list]:
    """The datum slot B built directly as faces (no boolean): the rectangle it opens in face
    A (a wire to add to face A as a hole) and its four walls and floor.

    The slot is the box of :meth:`prs_geom.geometry.datum.DatumMark.box` below face A,
    wholly inside material (the sizing rule keeps it off every thread surface), symmetric in
    y, so it is the same on right- and left-hand parts.
    """
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakePolygon
    from OCP.gp import gp_Pnt

    (x0, y0, z0), (x1, y1, z1) = mark.box()

    def quad(*pts):
        poly = BRepBuilderAPI_MakePolygon(*(gp_Pnt(*q) for q in pts), True)
        return poly.Wire()

    rect = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
    opening = quad(*((x, y, z0) for x, y in rect))
    faces = [BRepBuilderAPI_MakeFace(quad(*((x, y, z1) for x, y in rect)), True).Face()]   # floor
    for (xa, ya), (xb, yb) in zip(rect, rect[1:] + rect[:1]):                               # walls
        faces.append(BRepBuilderAPI_MakeFace(quad((xa, ya, z0), (xb, yb, z0), (xb, yb, z1), (xa, ya, z1)),
                                             True).Face())
    return opening, faces



def _band_faces(surfaces: Sequence, tm: "ThreadMesh",
                spans: Sequence[tuple[float, float, float]] | None = None) -> list:
    """One face per band surface and (at most) TURNS_PER_FACE turns, each on its own segment
    of the band's spline.

    A face on the whole surface would write all of it into the file once per face;
    tessellators (CAD viewers, BRepMesh) handle one-turn faces far better than 20-turn ones,
    and the cut edges, the same iso-curve from both sides, sew exactly. ``spans``: (z_a, z_b,
    share) per piece of the part, each cut into faces of at most ``share`` x TURNS_PER_FACE
    turns (the complete roller's gear zones); the whole part at share 1 when None."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.Geom import Geom_BSplineSurface

    faces = []
    for z_a, z_b, share in spans or ((tm.z_lo, tm.z_hi, 1.0),):
        cuts = face_z_cuts(z_a, z_b, share * tm.profile.lead)
        for surf in surfaces:
            u0, u1 = surf.Bounds()[:2]
            for za, zb in zip(cuts[:-1], cuts[1:]):
                piece = Geom_BSplineSurface(surf)
                if (za, zb) != (tm.z_lo, tm.z_hi):     # the surface is already cut to the part
                    piece.Segment(u0, u1, za, zb)
                faces.append(BRepBuilderAPI_MakeFace(piece, 1e-7).Face())
    return faces


def _build_solid(tm: "ThreadMesh", nets: Sequence[BSplineNet], mirror: bool):
    """Faces of the part (bands, end planes, slot, nut body), sewn into one solid.

    Returns (solid or None, the band surfaces, reason)."""
    prof, mark = tm.profile, tm.datum_mark
    surfaces = [_occ_surface(n, mirror, tm.z_lo, tm.z_hi) for n in nets]
    faces = _band_faces(surfaces, tm)
    opening, slot_faces = _slot(mark)
    for z_end in (tm.z_lo, tm.z_hi):
        wires = [_end_wire(surfaces, z_end)]
        if prof.internal:
            wires.insert(0, _circle_wire(tm.body_radius, z_end))
        if z_end == mark.z_face:
            wires.append(opening)
        faces.append(_plane_face(z_end, wires))
    if prof.internal:
        faces.append(_body_face(tm.body_radius, tm.z_lo, tm.z_hi))
    shape, reason = _sew_solid(faces + slot_faces)
    return shape, surfaces, reason


def _thread_step_solid(part: str, ref: ThreadSolidReference, fit: BandFit, started: float, reason: str,
                       shape: Any = None, measured: Any = None,
                       bbox: tuple[float, ...] = (math.nan,) * 6) -> StepSolid:
    """The :class:`StepSolid` of a threaded part from its reference, its fit and what was
    measured on the shape (``measured`` None: no shape to measure)."""
    volume = measured.volume_mm3 if measured is not None else math.nan
    rel = (volume - ref.mesh_volume_mm3) / ref.mesh_volume_mm3 if math.isfinite(volume) else math.nan
    return StepSolid(part=part, shape=shape, valid=not reason, reason=reason, volume_mm3=volume,
                     mesh_volume_mm3=ref.mesh_volume_mm3, volume_rel_diff=rel, bbox=bbox,
                     build_time_s=time.perf_counter() - started,
                     faces=measured.faces if measured is not None else 0,
                     chord_tolerance_mm=ref.chord_tolerance_mm, mesh_tolerance_mm=ref.mesh.chord_tolerance,
                     max_deviation_mm=fit.max_deviation_mm, analytic_volume_mm3=ref.analytic_volume_mm3,
                     design_mesh_volume_mm3=ref.design_mesh_volume_mm3, deviation_target_mm=ref.deviation_target_mm,
                     max_tolerance_mm=measured.max_tolerance_mm if measured is not None else math.nan,
                     grid=fit.grid)


def step_solid(design: "PRSDesign", part: str, tol: float | None = None,
               screw_profile: "ThreadProfile | None" = None) -> StepSolid:
    """One threaded part as a closed B-rep solid in its part frame, with its checks.

    Parameters
    ----------
    design : PRSDesign
        The design.
    part : {"screw", "roller", "nut"}
        Which part. Frames: :mod:`prs_geom.geometry.frames` (z along the part axis, mm;
        roller and nut from z = 0 to n p, the screw over ``screw_z_range``).
    tol : float, optional
        Chord tolerance (mm); ``design.mesh.chord_tolerance_mm`` when omitted. The B-spline
        faces keep within :data:`~prs_geom.mesh.bspline_bands.DEVIATION_SHARE` x tol of the
        analytic surface, tighter on small parts (``deviation_target_mm``), measured.
    screw_profile : ThreadProfile, optional
        The screw profile to build (e.g. ``theoretical_screw(design).profile``); the
        design's nominal screw when omitted.

    Returns
    -------
    StepSolid
        ``valid`` False with a ``reason`` when any check fails
        (:func:`prs_geom.checks.brep.thread_solid_problems`); the shape is then not to be
        written (:func:`write_step` leaves it out).

    Raises
    ------
    EnvironmentFailure
        OCP (the optional extra ``step``) is not installed.
    """
    require_ocp()
    if part not in PARTS:
        raise ValueError(f"unknown part {part!r}; one of {', '.join(PARTS)}")
    started = time.perf_counter()
    ref = thread_solid_reference(design, part, float(tol or design.mesh.chord_tolerance_mm), screw_profile)
    tm = ref.mesh
    fit = fit_bands(tm, ref.deviation_target_mm)
    try:
        shape, surfaces, reason = _build_solid(tm, fit.nets, ref.mirror)
        if shape is None:
            return _thread_step_solid(part, ref, fit, started, reason)
        measured = measure_solid(shape)
        bbox = sampled_bbox(fit.nets, tm, ref.mirror)
        handover = surface_handover_error(surfaces, fit.nets, ref.mirror)
    except Exception as exc:  # noqa: BLE001 - OCC raises its own Standard_Failure types
        return _thread_step_solid(part, ref, fit, started, f"OpenCascade failed: {type(exc).__name__}: {exc}")
    problems = thread_solid_problems(measured, ref.mesh_volume_mm3, fit.max_deviation_mm, ref.deviation_target_mm,
                                     handover, (tm.z_lo, tm.z_hi))
    return _thread_step_solid(part, ref, fit, started, "; ".join(problems), shape, measured, bbox)

# --------------------------------------------------------------------------- STEP file
@dataclass(frozen=True)
class StepFileContent:
    """What a STEP file holds, read back through XCAF (``STEPCAFControl_Reader``).

    Attributes
    ----------
    names : tuple of str
        Names of the free shapes (one per part), in file order.
    shapes : tuple of TopoDS_Shape
        The shapes, same order.
    schema : str
        The FILE_SCHEMA identifier of the header.
    description : tuple of str
        The FILE_DESCRIPTION strings of the header.
    """

    names: tuple[str, ...]
    shapes: tuple[Any, ...]
    schema: str
    description: tuple[str, ...]


@contextlib.contextmanager
def _quiet_occ():
    """Silence OpenCascade's default messenger (the STEP translator prints transfer
    statistics to stdout) below failures, for the duration of the block."""
    from OCP.Message import Message, Message_Gravity

    printers = Message.DefaultMessenger_s().Printers()
    saved = []
    for i in range(1, printers.Length() + 1):
        pr = printers.Value(i)
        saved.append((pr, pr.GetTraceLevel()))
        pr.SetTraceLevel(Message_Gravity.Message_Fail)
    try:
        yield
    finally:
        for pr, level in saved:
            pr.SetTraceLevel(level)


def _new_document():
    from OCP.TCollection import TCollection_ExtendedString
    from OCP.TDocStd import TDocStd_Document
    from OCP.XCAFApp import XCAFApp_Application

    doc = TDocStd_Document(TCollection_ExtendedString("XmlXCAF"))
    XCAFApp_Application.GetApplication_s().InitDocument(doc)
    return doc


def read_document(path: str | os.PathLike) -> tuple[Any, Any, Any]:
    """Read a STEP file into a new XCAF document: (reader, document, shape tool), names
    kept, OpenCascade's transfer messages silenced.

    Raises
    ------
    EnvironmentFailure
        OCP missing, or the file cannot be read as STEP.
    """
    require_ocp()
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.STEPCAFControl import STEPCAFControl_Reader
    from OCP.XCAFDoc import XCAFDoc_DocumentTool

    reader = STEPCAFControl_Reader()
    reader.SetNameMode(True)
    with _quiet_occ():
        if reader.ReadFile(str(path)) != IFSelect_RetDone:
            raise EnvironmentFailure(f"cannot read {path} as a STEP file")
        doc = _new_document()
        if not reader.Transfer(doc):
            raise EnvironmentFailure(f"cannot transfer the shapes of {path}")
    return reader, doc, XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())


def read_step(path: str | os.PathLike) -> StepFileContent:
    """Read a STEP file with its part names (XCAF) and header.

    Parameters
    ----------
    path : str or PathLike
        The file.

    Returns
    -------
    StepFileContent
        The free shapes with their names, the schema and the FILE_DESCRIPTION.

    Raises
    ------
    EnvironmentFailure
        OCP missing, or the file cannot be read as STEP.
    """
    from OCP.collections import Sequence_TDF_Label
    from OCP.TDataStd import TDataStd_Name
    from OCP.XCAFDoc import XCAFDoc_ShapeTool

    reader, doc, tool = read_document(path)
    labels = Sequence_TDF_Label()
    tool.GetFreeShapes(labels)
    names, shapes = [], []
    for i in range(1, labels.Length() + 1):
        label = labels.Value(i)
        attr = TDataStd_Name()
        names.append(attr.Get().ToExtString() if label.FindAttribute(TDataStd_Name.GetID_s(), attr) else "")
        shapes.append(XCAFDoc_ShapeTool.GetShape_s(label))
    model = reader.Reader().StepModel()
    from OCP.APIHeaderSection import APIHeaderSection_MakeHeader

    header = APIHeaderSection_MakeHeader(model)
    description = tuple(header.DescriptionValue(k).ToCString() for k in range(1, header.NbDescription() + 1))
    schema = header.SchemaIdentifiersValue(1).ToCString() if header.NbSchemaIdentifiers() else ""
    return StepFileContent(names=tuple(names), shapes=tuple(shapes), schema=schema, description=description)


def write_document(doc: Any, path: str, target: Path, colours: bool = False) -> None:
    """Write an XCAF document as one STEP AP214 file at ``path`` (names kept, colours with
    ``colours``), its header naming ``target`` and carrying :data:`AUTHORITY_NOTE`."""
    from OCP.APIHeaderSection import APIHeaderSection_MakeHeader
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.Interface import Interface_Static
    from OCP.STEPCAFControl import STEPCAFControl_Writer
    from OCP.STEPControl import STEPControl_AsIs
    from OCP.TCollection import TCollection_HAsciiString

    from prs_geom._version import __version__

    # the schema is a process-wide setting read when the writer makes its model: set it for
    # this file only and put the previous value back
    previous = Interface_Static.CVal_s("write.step.schema")
    Interface_Static.SetCVal_s("write.step.schema", STEP_SCHEMA)
    try:
        with _quiet_occ():
            writer = STEPCAFControl_Writer()
            writer.SetNameMode(True)
            writer.SetColorMode(colours)
            if not writer.Transfer(doc, STEPControl_AsIs):
                raise RuntimeError("the STEP writer refused the shapes")
            # the header exists once the shapes are transferred; MakeHeader edits it in place
            header = APIHeaderSection_MakeHeader(writer.ChangeWriter().Model())
            header.SetName(TCollection_HAsciiString(target.name))
            header.SetDescriptionValue(1, TCollection_HAsciiString(AUTHORITY_NOTE))
            header.SetOriginatingSystem(TCollection_HAsciiString(f"prs-geom {__version__}"))
            if writer.Write(path) != IFSelect_RetDone:
                raise EnvironmentFailure(f"cannot write {target}: the STEP writer failed (does the folder "
                                         "exist and is it writable?)")
    finally:
        Interface_Static.SetCVal_s("write.step.schema", previous)


def _write_file(path: str, solids: Sequence[StepSolid], target: Path) -> None:
    """One STEP AP214 file: each solid a free shape named after its part (XCAF label name ->
    PRODUCT name), the authority note in FILE_DESCRIPTION."""
    from OCP.TCollection import TCollection_ExtendedString
    from OCP.TDataStd import TDataStd_Name
    from OCP.XCAFDoc import XCAFDoc_DocumentTool

    doc = _new_document()
    tool = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    for s in solids:
        label = tool.AddShape(s.shape, False)
        TDataStd_Name.Set_s(label, TCollection_ExtendedString(s.part))
    write_document(doc, path, target)


def write_step(design: "PRSDesign", path: str | os.PathLike, parts: Sequence[str] = PARTS,
               tol: float | None = None, screw_profile: "ThreadProfile | None" = None) -> dict[str, Any]:
    """Build the parts (:func:`step_solid`) and write one STEP AP214 file with one named
    solid per valid part, each in its own part frame (:func:`write_solids`).

    Parameters
    ----------
    design : PRSDesign
        The design.
    path : str or PathLike
        The file to write (``.step``).
    parts : sequence of {"screw", "roller", "nut"}
        The parts; their names in the file are these.
    tol : float, optional
        Chord tolerance (mm); ``design.mesh.chord_tolerance_mm`` when omitted.
    screw_profile : ThreadProfile, optional
        The screw to export, normally ``theoretical_screw(design).profile``
        (:mod:`prs_geom.analysis.contact`); the nominal screw when omitted.

    Returns
    -------
    dict
        The report section ``step`` (:func:`write_solids`).

    Raises
    ------
    EnvironmentFailure
        OCP (the optional extra ``step``) is not installed, or the file cannot be written.

    Examples
    --------
    The roller as one STEP solid (needs the ``step`` extra, cadquery-ocp):

    >>> import prs_geom as pg
    >>> info = pg.write_step(pg.default_design(), "roller.step", parts=["roller"])
    >>> info["written"], info["parts"]["roller"]["valid"]
    (['roller'], True)
    >>> abs(info["parts"]["roller"]["volume_mm3"] / info["parts"]["roller"]["analytic_volume_mm3"] - 1) < 1e-6
    True
    """
    require_ocp()
    for p in parts:
        if p not in PARTS:
            raise ValueError(f"unknown part {p!r}; one of {', '.join(PARTS)}")
    return write_solids([step_solid(design, p, tol, screw_profile) for p in parts], path)


def _step_section(solids: Sequence[StepSolid]) -> dict[str, Any]:
    """The report section ``step`` before anything is written: no file, every part's row."""
    return {
        "file": None,
        "schema": STEP_SCHEMA,
        "authority": AUTHORITY_NOTE,
        "frames": "each solid in its own part frame (mm, z along the part axis, face A at the lower end; "
                  "prs_geom.geometry.frames); place the rollers with the assembly transforms",
        "written": [],
        "parts": {s.part: s.report() for s in solids},
    }


class _RereadRejected(Exception):
    """The file read back differs from the solids written (the temporary file is dropped)."""

    def __init__(self, problems: list[str]) -> None:
        super().__init__("; ".join(problems))
        self.problems = problems


def write_solids(solids: Sequence[StepSolid], path: str | os.PathLike) -> dict[str, Any]:
    """Write the valid ``solids`` to one STEP AP214 file, read it back and check it.

    The file is written to a hidden sibling (:func:`prs_geom.model.io.atomic_path`) and read
    back (:func:`read_step`): every written part must be there by name with OpenCascade's
    bounding box unchanged (:func:`prs_geom.checks.brep.reread_problems`); only then is it
    moved into place, so ``path`` is never left half-written or holding a broken file, and no
    temporary file is left behind, whatever fails.

    Parameters
    ----------
    solids : sequence of StepSolid
        Parts from :func:`step_solid`; invalid ones (``valid`` False) are left out of the
        file and reported with their reason.
    path : str or PathLike
        The file to write.

    Returns
    -------
    dict
        The report section ``step``: ``file`` (the file name, None when nothing was
        written: no valid part, or the read-back check failed, see ``reread_problems``),
        ``schema``, ``authority`` (the note in the header), ``frames``, ``written`` (the
        part names in the file), ``parts`` (per part :meth:`StepSolid.report`, plus
        ``reread_name`` and ``reread_bbox_max_diff_mm`` (mm) for the written ones).
    """
    require_ocp()
    path = Path(path)
    good = [s for s in solids if s.valid]
    section = _step_section(solids)
    if not good:
        return section
    try:
        # the writer creates the hidden sibling itself, with the usual permissions
        with atomic_path(path) as tmp:
            _write_file(str(tmp), good, path)
            back = read_step(tmp)
            problems = reread_problems([(s.part, s.shape) for s in good], back.names, back.shapes, section["parts"])
            if problems:
                raise _RereadRejected(problems)
    except _RereadRejected as rejected:
        section["reread_problems"] = rejected.problems
        return section
    section["file"] = path.name
    section["written"] = [s.part for s in good]
    return section


# --------------------------------------------------------------------------- mechanism parts
def _occ_cylinder(cylinder: Cylinder):
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder
    from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt

    axes = gp_Ax2(gp_Pnt(*cylinder.origin), gp_Dir(0.0, 0.0, 1.0), gp_Dir(*cylinder.x_dir))
    if cylinder.sweep_rad is None:
        return BRepPrimAPI_MakeCylinder(axes, cylinder.radius, cylinder.height).Shape()
    return BRepPrimAPI_MakeCylinder(axes, cylinder.radius, cylinder.height, cylinder.sweep_rad).Shape()


def _occ_cylinder_solid(description: CylinderSolid):
    """The body cylinder less each cutter in turn (``BRepAlgoAPI_Cut``)."""
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut

    shape = _occ_cylinder(description.body)
    for cutter in description.cutters:
        op = BRepAlgoAPI_Cut(shape, _occ_cylinder(cutter))
        op.Build()
        shape = op.Shape()
    return shape


def mechanism_step_solid(design: "PRSDesign", part: str, mesh: Any = None) -> StepSolid:
    """The carrier or the retaining ring (:func:`prs_geom.mesh.mechanism_solids.mechanism_solid`)
    as an exact B-rep: circular cylinders and planes (OpenCascade primitives and booleans), in
    its own frame (z = 0 at its face toward the nut end, as ``<part>.stl``), at the modelled
    sizes (fitted features at the middle of their ISO 286 zone).

    ``mesh_volume_mm3`` is the volume of the part's mesh (polygons at <= 1 um): ``mesh``
    (anything with a ``volume``, e.g. the build's placed ``<part>_lo``), meshed here when
    not given; ``analytic_volume_mm3`` is the closed form, which the B-rep's volume must
    agree with (:func:`prs_geom.checks.brep.closed_form_volume_problem`).

    Raises
    ------
    ValueError
        The design has no mechanism or ``part`` is not one of :data:`MECHANISM_STEP_PARTS`.
    EnvironmentFailure
        OCP (the optional extra ``step``) is not installed.
    """
    require_ocp()
    from prs_geom.mesh.mechanism import MECHANISM_CHORD_MM

    started = time.perf_counter()
    if part not in MECHANISM_STEP_PARTS:
        raise ValueError(f"no mechanism part {part!r} in this design (mechanism.enabled and one of "
                         f"{', '.join(MECHANISM_STEP_PARTS)})")
    description = mechanism_solid(design, part)
    shape = _occ_cylinder_solid(description)
    if mesh is None:
        mesh = mechanism_part_mesh(design, part)
    mesh_volume = float(mesh.volume)
    measured = measure_solid(shape)
    exact = description.exact_volume_mm3
    reason = closed_form_volume_problem(measured, exact)
    volume = measured.volume_mm3
    return StepSolid(part=part, shape=shape, valid=not reason, reason=reason, volume_mm3=volume,
                     mesh_volume_mm3=mesh_volume, volume_rel_diff=(volume - mesh_volume) / mesh_volume,
                     bbox=occ_bbox(shape), build_time_s=time.perf_counter() - started, faces=measured.faces,
                     chord_tolerance_mm=0.0, mesh_tolerance_mm=MECHANISM_CHORD_MM, max_deviation_mm=0.0,
                     analytic_volume_mm3=exact, design_mesh_volume_mm3=mesh_volume, deviation_target_mm=0.0,
                     max_tolerance_mm=math.nan)


# --------------------------------------------------------------------------- complete screw
#: A complete part's B-rep bounding box against its mesh's (mm): the meshes' polygons lie on
#: or inside the true circles by at most their chord tolerance.
BBOX_MESH_LIMIT_MM = 0.05


def _revolved(profile: Sequence[tuple[float, float]]):
    """The solid of revolution about z of the closed (r, z) polygon ``profile`` (mm): planes,
    cylinders and cones, exact."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakePolygon
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeRevol
    from OCP.gp import gp_Ax1, gp_Dir, gp_Pnt

    poly = BRepBuilderAPI_MakePolygon()
    for r, z in profile:
        poly.Add(gp_Pnt(float(r), 0.0, float(z)))
    poly.Close()
    face = BRepBuilderAPI_MakeFace(poly.Wire(), True).Face()
    return BRepPrimAPI_MakeRevol(face, gp_Ax1(gp_Pnt(0.0, 0.0, 0.0), gp_Dir(0.0, 0.0, 1.0))).Shape()


def _boolean(kind: str, shape: Any, tools: Sequence[Any]):
    """``shape`` fused with or cut by ``tools`` in one OpenCascade boolean (parallel)."""
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut, BRepAlgoAPI_Fuse
    from OCP.collections import List_TopoDS_Shape

    op = BRepAlgoAPI_Fuse() if kind == "fuse" else BRepAlgoAPI_Cut()
    args, tls = List_TopoDS_Shape(), List_TopoDS_Shape()
    args.Append(shape)
    for t in tools:
        tls.Append(t)
    op.SetArguments(args)
    op.SetTools(tls)
    op.SetRunParallel(True)
    op.SetUseOBB(True)       # oriented boxes drop most face pairs before intersecting them
    op.Build()
    if not op.IsDone():
        raise RuntimeError(f"the {kind} of the complete part failed")
    return op.Shape()


def _drive_cutter(end: Any):
    """The keyway (DIN 6885-1 form A: a box with two half-round ends, floor at r_j - t1) or
    the flat of a screw end's drive journal, on the +x side, as the mesh cuts it
    (:mod:`prs_geom.mesh.actuator`), overshooting the journal by ``PAD_MM``."""
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    from OCP.gp import gp_Pnt

    from prs_geom.mesh.actuator import PAD_MM, drive_journal_radius

    r_j = drive_journal_radius(end)
    z0, z1 = end.key_z
    if end.key is None:
        x0 = r_j - end.flat_depth_mm
        return BRepPrimAPI_MakeBox(gp_Pnt(x0, -r_j - PAD_MM, z0), gp_Pnt(r_j + PAD_MM, r_j + PAD_MM, z1)).Shape()
    x0 = r_j - end.key.shaft_depth_mm
    return stadium_prism(end.key.width_mm, (z0, z1), x0, r_j + PAD_MM - x0)


def stadium_prism(width: float, span: tuple[float, float], x0: float, height: float) -> Any:
    """The exact solid of a DIN 6885-1 form A key or keyway: a stadium in the plane x = x0
    (along z over ``span``, ``width`` across y, half-round ends of radius width / 2: two
    lines and two half circles) extruded along +x by ``height`` (mm)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakeWire
    from OCP.BRepPrimAPI import BRepPrimAPI_MakePrism
    from OCP.GC import GC_MakeArcOfCircle
    from OCP.gp import gp_Pnt, gp_Vec

    a, (z0, z1) = 0.5 * width, span
    right_lo, right_hi = gp_Pnt(x0, a, z0 + a), gp_Pnt(x0, a, z1 - a)
    left_hi, left_lo = gp_Pnt(x0, -a, z1 - a), gp_Pnt(x0, -a, z0 + a)
    wire = BRepBuilderAPI_MakeWire()
    wire.Add(BRepBuilderAPI_MakeEdge(right_lo, right_hi).Edge())
    wire.Add(BRepBuilderAPI_MakeEdge(GC_MakeArcOfCircle(right_hi, gp_Pnt(x0, 0.0, z1), left_hi).Value()).Edge())
    wire.Add(BRepBuilderAPI_MakeEdge(left_hi, left_lo).Edge())
    wire.Add(BRepBuilderAPI_MakeEdge(GC_MakeArcOfCircle(left_lo, gp_Pnt(x0, 0.0, z0), right_lo).Value()).Edge())
    face = BRepBuilderAPI_MakeFace(wire.Wire(), True).Face()
    return BRepPrimAPI_MakePrism(face, gp_Vec(height, 0.0, 0.0)).Shape()


def _fill_voids(shape: Any) -> tuple[Any, float]:
    """``shape`` as the solid of its outer shell, and the volume of the closed voids dropped
    (mm^3): a datum slot an end covers, as :func:`prs_geom.mesh.parts.union_pieces` fills it."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeSolid
    from OCP.BRepClass3d import BRepClass3d
    from OCP.TopAbs import TopAbs_SHELL, TopAbs_SOLID
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    from prs_geom.checks.brep import count_subshapes, shape_volume

    if count_subshapes(shape, TopAbs_SOLID) != 1 or count_subshapes(shape, TopAbs_SHELL) == 1:
        return shape, 0.0
    ex = TopExp_Explorer(shape, TopAbs_SOLID)
    outer = BRepBuilderAPI_MakeSolid(BRepClass3d.OuterShell_s(TopoDS.Solid(ex.Current()))).Solid()
    return outer, shape_volume(outer) - shape_volume(shape)


def _complete_screw_closed_form(thread_exact: float | None, prof: "ThreadProfile", lay: Any,
                                run_outs: Sequence[Any]) -> float | None:
    """Exact volume (mm^3) of the complete screw: the thread body's closed form (None for a
    graded thread: then None), each wheel exit's (:func:`prs_geom.mesh.thread.run_out_volume`),
    the end steps' cylinders, less the keyway (:func:`prs_geom.mesh.volumes.keyway_volume`)
    or the flat (a circular segment times its length)."""
    from prs_geom.mesh.actuator import drive_journal_radius
    from prs_geom.mesh.thread import run_out_volume
    from prs_geom.mesh.volumes import keyway_volume

    if thread_exact is None:
        return None
    total = thread_exact + sum(run_out_volume(prof, ro) for ro in run_outs)
    for end in lay.ends:
        total += sum(math.pi * (0.5 * st.diameter_mm) ** 2 * (st.z[1] - st.z[0]) for st in end.steps)
        if end.key_z is None:
            continue
        r_j, length = drive_journal_radius(end), end.key_z[1] - end.key_z[0]
        if end.key is not None:
            total -= keyway_volume(r_j, end.key.width_mm, end.key.shaft_depth_mm, length)
        else:
            x0 = r_j - end.flat_depth_mm
            total -= length * (r_j ** 2 * math.acos(x0 / r_j) - x0 * math.sqrt(r_j ** 2 - x0 ** 2))
    return total


def complete_screw_solid(design: "PRSDesign", thread: StepSolid, mesh_volume_mm3: float,
                         screw_profile: "ThreadProfile | None" = None,
                         mesh_bounds: Any = None) -> StepSolid:
    """The complete screw as one B-rep solid: the thread body ``thread`` (:func:`step_solid`,
    screw frame) united with the grinding-wheel exits and both screw ends of the actuator
    (:mod:`prs_geom.geometry.actuator`), the drive journal's keyway or flat cut, all exact
    (planes, cylinders, cones; OpenCascade booleans). ``thread`` itself when the design has no
    actuator or the thread body is not valid.

    The solids are those of the complete screw's mesh (:mod:`prs_geom.mesh.parts`):
    the wheel exit is the frustum of :func:`prs_geom.mesh.thread.apply_run_outs` (root less
    its margin at the run-out's inner end to the crest less its gap in the end plane), the
    ends the steps revolved (:func:`prs_geom.mesh.actuator.screw_end_profile`; the run-out
    cylinder inside the thread's core adds nothing to the union and is left out). The result
    must be one valid solid within :data:`~prs_geom.checks.brep.COMPLETE_VOLUME_REL_LIMIT` of
    ``mesh_volume_mm3``, the complete screw's mesh volume; the thread body's own checks
    (analytic volume, B-spline deviation) stay in the fields taken from ``thread``.
    ``screw_profile`` is the profile ``thread`` was built from (the design's nominal screw
    when omitted). ``mesh_bounds`` ((2, 3): min and max corner, mm), when given, the complete
    mesh's extent: the B-rep's bounding box must agree within :data:`BBOX_MESH_LIMIT_MM`.
    A free end (no steps) adds nothing. When OpenCascade fails, the result is not valid and
    has no shape (the build then writes no ``screw.step`` and says why).
    """
    require_ocp()
    from prs_geom.geometry.actuator import actuator_layout
    from prs_geom.geometry.profiles import ThreadProfiles
    from prs_geom.mesh.actuator import screw_end_profile
    from prs_geom.mesh.assembly import design_run_outs
    from prs_geom.mesh.thread import RUN_OUT_CREST_GAP_MM, RUN_OUT_ROOT_MARGIN_MM

    lay = actuator_layout(design)
    if lay is None or not thread.valid:
        return thread
    started = time.perf_counter()
    z_lo, z_hi = thread.bbox[2], thread.bbox[5]
    prof = screw_profile or ThreadProfiles.from_design(design).screw
    run_outs = design_run_outs(design, "screw")
    exact = _complete_screw_closed_form(thread.analytic_volume_mm3, prof, lay, run_outs)
    tools = []
    try:
        for run_out in run_outs:
            z_end, inward = (z_lo, 1.0) if run_out.end == "lo" else (z_hi, -1.0)
            r_end, r_in = prof.crest_radius - RUN_OUT_CREST_GAP_MM, prof.root_radius - RUN_OUT_ROOT_MARGIN_MM
            z_in = z_end + inward * run_out.length_mm
            tools.append(_revolved([(0.0, z_end), (r_end, z_end), (r_in, z_in), (0.0, z_in)]))
        for end in lay.ends:
            if not end.steps:             # a free end: the thread runs out into nothing
                continue
            solid = _revolved(screw_end_profile(end))
            if end.key_z is not None:
                solid = _boolean("cut", solid, [_drive_cutter(end)])
            tools.append(solid)
        shape, filled = _fill_voids(_boolean("fuse", thread.shape, tools))
        measured = measure_solid(shape)
    except Exception as exc:  # noqa: BLE001 - OCC raises its own Standard_Failure types
        return complete_part_failed(thread, "screw", exc)
    if exact is not None:
        exact += filled                   # a slot an end covers is filled, as in the mesh
    problems = complete_solid_problems(measured, mesh_volume_mm3)
    if exact is not None and (closed := closed_form_volume_problem(measured, exact)):
        problems.append(closed)
    return complete_part_result(thread, shape, measured, problems, mesh_volume_mm3, mesh_bounds, exact, filled,
                                started)


def complete_part_failed(thread: StepSolid, part: str, exc: Exception) -> StepSolid:
    """``thread`` marked not valid, without a shape, when OpenCascade failed on the complete
    ``part`` (the build then writes no file for it and says why)."""
    reason = f"OpenCascade failed on the complete {part}: {type(exc).__name__}: {exc}"
    return dataclasses.replace(thread, valid=False, reason=reason, shape=None)


def complete_part_result(thread: StepSolid, shape: Any, measured: Any, problems: list[str], mesh_volume_mm3: float,
                         mesh_bounds: Any, exact: float | None, filled: float, started: float) -> StepSolid:
    """``thread`` (a thread body's :class:`StepSolid`) turned into the complete part
    ``shape``: its ``measured`` values, the ``problems`` found so far plus a bounding box
    off the complete mesh's ``mesh_bounds`` ((2, 3), mm; not checked when None) by more than
    :data:`BBOX_MESH_LIMIT_MM`, its closed form ``exact`` (None: none) and the filled voids
    (mm^3); the thread body's own checks stay in the deviation and ``thread_*`` fields."""
    bbox = occ_bbox(shape)
    if mesh_bounds is not None:
        # an end, a keyway or a gear in the wrong place keeps the volume; the extent shows it
        off = float(np.max(np.abs(np.asarray(bbox) - np.asarray(mesh_bounds, dtype=float).ravel())))
        if not off <= BBOX_MESH_LIMIT_MM:
            problems.append(f"bounding box differs from the complete mesh's by {off:.3g} mm "
                            f"(limit {BBOX_MESH_LIMIT_MM:g} mm)")
    reason = "; ".join(problems)
    volume = measured.volume_mm3
    return dataclasses.replace(
        thread, shape=shape, valid=not reason, reason=reason, volume_mm3=volume, mesh_volume_mm3=mesh_volume_mm3,
        volume_rel_diff=(volume - mesh_volume_mm3) / mesh_volume_mm3, bbox=bbox, faces=measured.faces,
        build_time_s=thread.build_time_s + time.perf_counter() - started, analytic_volume_mm3=exact,
        design_mesh_volume_mm3=mesh_volume_mm3, max_tolerance_mm=measured.max_tolerance_mm,
        complete=True, thread_volume_mm3=thread.volume_mm3, thread_analytic_volume_mm3=thread.analytic_volume_mm3,
        filled_voids_mm3=filled)
