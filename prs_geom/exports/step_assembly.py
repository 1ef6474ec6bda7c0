"""The STEP assembly (``assembly.step``, optional extra ``step``): one product per distinct
part, placed once per copy, with names and colours.

The structure is that of the complete parts (:mod:`prs_geom.mesh.parts`): a product per
part (``screw``, ``roller``, ``nut``, ``carrier``, ``retaining_ring``, and the envelopes of
the purchased parts), its shape in the part's own frame, and one component per copy named
after its rigid body (``roller_0`` ... ``roller_<z-1>``, ``carrier_lo``, ``carrier_hi``),
placed by the copy's transform: the same transform as the GLB node of that name and the 3MF
build item, so a CAD user gets the assembly as the analysis placed it, at mid-stroke (the
nut's frame on the screw frame; ``stroke_position_mm`` 0 in the report, measured from the
middle of the stroke).

Shapes: the per-part B-rep solids of :mod:`prs_geom.exports.step` and
:mod:`prs_geom.exports.step_gears` (the complete screw, roller and nut or their thread bodies, the
exact carrier and retaining ring) and, for a purchased part, its envelope as an exact solid
(OpenCascade primitives: a ring, a bolt's head and shank revolved, a key's stadium
extruded). The product's colour is the part's display colour of the GLB
(:data:`prs_geom.exports.scene.MATERIALS`, converted to sRGB). XCAF writes the file (AP214,
product structure with NEXT_ASSEMBLY_USAGE_OCCURRENCE and item-defined transformations) and
reads it back (:func:`read_step_assembly`) before it is moved into place.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

import numpy as np
from numpy.typing import NDArray

from prs_geom.exports.step import _new_document, require_ocp
from prs_geom.model.errors import EnvironmentFailure
from prs_geom.model.io import atomic_path

if TYPE_CHECKING:  # pragma: no cover
    from prs_geom.mesh.parts import CompletePart

__all__ = ["ASSEMBLY_FILE", "StepAssemblyContent", "StepInstance", "assembly_files", "bolt_shape", "envelope_shapes",
           "key_shape", "placement_problems", "product_labels", "read_step_assembly", "rotation_angle",
           "write_step_assembly"]

#: The assembly file's name.
ASSEMBLY_FILE = "assembly.step"
#: Placements read back may differ from the written ones by no more than this (mm and rad).
PLACEMENT_TOLERANCE = (1e-6, 1e-9)


@dataclass(frozen=True)
class StepInstance:
    """One placed copy read back: its name, its product's name and its 4x4 placement (mm)."""

    name: str
    product: str
    transform: NDArray[np.float64]


@dataclass(frozen=True)
class StepAssemblyContent:
    """What an assembly STEP file holds, read back through XCAF.

    Attributes
    ----------
    name : str
        The root assembly's name.
    products : dict of str to TopoDS_Shape
        Each distinct product's shape by name (in its own frame).
    instances : tuple of StepInstance
        Every component of the root assembly, in file order.
    description : tuple of str
        The FILE_DESCRIPTION strings of the header.
    """

    name: str
    products: dict[str, Any]
    instances: tuple[StepInstance, ...]
    description: tuple[str, ...]


def _trsf(T: NDArray[np.float64]):
    from OCP.gp import gp_Trsf

    t = gp_Trsf()
    t.SetValues(*(float(x) for x in np.asarray(T, dtype=np.float64)[:3, :4].ravel()))
    return t


def _matrix(trsf) -> NDArray[np.float64]:
    T = np.eye(4)
    for i in range(3):
        for j in range(4):
            T[i, j] = trsf.Value(i + 1, j + 1)
    return T


def envelope_shapes(design: Any) -> dict[str, Any]:
    """The purchased parts of ``design``'s actuator (none without one) as exact B-reps, keyed
    by complete-part name (``bearing_fixed``, ``locknut``, ``flange_bolt``, ``drive_key``
    ...), each in its part frame like its mesh: the rings
    (:func:`prs_geom.mesh.actuator.purchased_envelopes`) at their catalogue radii (axis z,
    z = 0 at the lower face), the flange bolt (:func:`bolt_shape`) and the drive key
    (:func:`key_shape`)."""
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder
    from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt

    from prs_geom.geometry.actuator import actuator_layout
    from prs_geom.mesh.actuator import drive_key, flange_bolts, purchased_envelopes
    from prs_geom.mesh.parts import part_name

    lay = actuator_layout(design)
    out: dict[str, Any] = {}
    if lay is None:
        return out
    for env in purchased_envelopes(lay):
        name = part_name(env.name)
        if name in out:
            continue
        width = env.z[1] - env.z[0]
        body = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0.0, 0.0, 0.0), gp_Dir(0.0, 0.0, 1.0)),
                                        env.outer_radius_mm, width).Shape()
        # the bore overshoots both faces, so no cut face is coplanar with one
        bore = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0.0, 0.0, -1.0), gp_Dir(0.0, 0.0, 1.0)),
                                        env.inner_radius_mm, width + 2.0).Shape()
        op = BRepAlgoAPI_Cut(body, bore)
        op.Build()
        out[name] = op.Shape()
    bolts = flange_bolts(lay)
    if bolts:
        out["flange_bolt"] = bolt_shape(bolts[0])
    key = drive_key(lay)
    if key is not None:
        out[key.name] = key_shape(key)
    return out


def bolt_shape(env: Any) -> Any:
    """A flange bolt's envelope (:class:`~prs_geom.mesh.actuator.BoltEnvelope`) as an exact
    solid in its own frame: its (r, z) outline revolved about z (planes and cylinders,
    :func:`prs_geom.exports.step._revolved`)."""
    from prs_geom.exports.step import _revolved

    return _revolved(env.profile())


def key_shape(env: Any) -> Any:
    """The drive key's envelope (:class:`~prs_geom.mesh.actuator.KeyEnvelope`) as an exact
    solid in its own frame: its stadium (:func:`prs_geom.exports.step.stadium_prism`, the
    keyway's) in the plane x = 0 over [0, l], extruded along +x by the key height."""
    from prs_geom.exports.step import stadium_prism

    return stadium_prism(env.width_mm, (0.0, env.length_mm), 0.0, env.height_mm)


def product_labels(design: Any) -> dict[str, str]:
    """The STEP product name of each complete part: its parts-list line's part name
    (``retaining ring``, ``bearing, fixed end``), so that a product and its line match."""
    from prs_geom.exports.bom import part_items
    from prs_geom.mesh.parts import part_name

    return {part_name(body): it.part for it in part_items(design)
            for body in (it.body or it.envelope,) if body is not None}


def _shape_kind(part: "CompletePart", thread_bodies: tuple[str, ...]) -> str:
    if part.purchased:
        return "envelope"
    return "thread body" if part.name in thread_bodies else "solid"


def _write(path: str, title: str, products: list[tuple[str, "CompletePart", Any]], target: Path) -> None:
    from OCP.Quantity import Quantity_Color, Quantity_TOC_sRGB
    from OCP.TCollection import TCollection_ExtendedString
    from OCP.TDataStd import TDataStd_Name
    from OCP.TopLoc import TopLoc_Location
    from OCP.XCAFDoc import XCAFDoc_ColorType, XCAFDoc_DocumentTool

    from prs_geom.exports.scene import MATERIALS, part_family
    from prs_geom.exports.step import write_document

    doc = _new_document()
    tool = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    colours = XCAFDoc_DocumentTool.ColorTool_s(doc.Main())
    root = tool.NewShape()
    TDataStd_Name.Set_s(root, TCollection_ExtendedString(title))
    for product, part, shape in products:
        label = tool.AddShape(shape, False)
        TDataStd_Name.Set_s(label, TCollection_ExtendedString(product))
        r, g, b = MATERIALS[part_family(part.name)].srgb
        colours.SetColor(label, Quantity_Color(r, g, b, Quantity_TOC_sRGB), XCAFDoc_ColorType.XCAFDoc_ColorSurf)
        for k, body in enumerate(part.instances):
            comp = tool.AddComponent(root, label, TopLoc_Location(_trsf(part.transforms[k])))
            TDataStd_Name.Set_s(comp, TCollection_ExtendedString(body))
    tool.UpdateAssemblies()
    write_document(doc, path, target, colours=True)


def _name(label) -> str:
    from OCP.TDataStd import TDataStd_Name

    attr = TDataStd_Name()
    return attr.Get().ToExtString() if label.FindAttribute(TDataStd_Name.GetID_s(), attr) else ""


def read_step_assembly(path: str | os.PathLike) -> StepAssemblyContent:
    """Read an assembly STEP file with XCAF: its products, components and placements.

    Raises
    ------
    EnvironmentFailure
        OCP missing, or the file cannot be read as STEP, or it holds no assembly.
    """
    from OCP.APIHeaderSection import APIHeaderSection_MakeHeader
    from OCP.collections import Sequence_TDF_Label as TDF_LabelSequence
    from OCP.TDF import TDF_Label
    from OCP.XCAFDoc import XCAFDoc_ShapeTool

    from prs_geom.exports.step import read_document

    reader, _, tool = read_document(path)
    free = TDF_LabelSequence()
    tool.GetFreeShapes(free)
    roots = [free.Value(i) for i in range(1, free.Length() + 1) if XCAFDoc_ShapeTool.IsAssembly_s(free.Value(i))]
    if len(roots) != 1:
        raise EnvironmentFailure(f"{path} holds {len(roots)} root assemblies, not one")
    root = roots[0]
    comps = TDF_LabelSequence()
    XCAFDoc_ShapeTool.GetComponents_s(root, comps, False)
    products: dict[str, Any] = {}
    instances = []
    for i in range(1, comps.Length() + 1):
        comp = comps.Value(i)
        ref = TDF_Label()
        XCAFDoc_ShapeTool.GetReferredShape_s(comp, ref)
        product = _name(ref)
        products.setdefault(product, XCAFDoc_ShapeTool.GetShape_s(ref))
        loc = XCAFDoc_ShapeTool.GetLocation_s(comp)
        instances.append(StepInstance(_name(comp), product, _matrix(loc.Transformation())))
    header = APIHeaderSection_MakeHeader(reader.Reader().StepModel())
    description = tuple(header.DescriptionValue(k).ToCString() for k in range(1, header.NbDescription() + 1))
    return StepAssemblyContent(name=_name(root), products=products, instances=tuple(instances),
                               description=description)


def write_step_assembly(parts: Mapping[str, "CompletePart"], shapes: Mapping[str, Any], path: str | os.PathLike,
                        title: str, labels: Mapping[str, str] | None = None,
                        thread_bodies: tuple[str, ...] = ("screw", "roller", "nut")) -> dict[str, Any]:
    """Write the assembly of ``parts`` (:meth:`prs_geom.mesh.assembly.Assembly.complete_parts`)
    with the product shapes ``shapes`` (by part name; a part without one is left out and
    listed as missing), read it back and check every product and placement; only then move
    it into place.

    Parameters
    ----------
    parts : mapping of str to CompletePart
        The complete parts with their copies' transforms.
    shapes : mapping of str to TopoDS_Shape
        Each part's B-rep in its part frame (:func:`envelope_shapes` for the purchased parts).
    path : str or PathLike
        The file to write.
    title : str
        The root assembly's name (the design's).
    labels : mapping of str to str, optional
        Product name by part name (:func:`product_labels`); the part name where absent.
    thread_bodies : tuple of str
        Parts whose shape is the thread's B-rep only, without the gears, journals, ends and
        flange of the complete part: reported as such (``shape`` "thread body").

    Returns
    -------
    dict
        The report entry ``step.assembly``: ``file`` (None when the read-back check failed,
        see ``problems``), ``products`` (product name -> {instances, shape}), ``missing``
        (parts without a shape), ``stroke_position_mm`` (0: mid-stroke),
        ``placement_max_diff_mm`` and ``placement_max_diff_rad`` (largest difference read back).
    """
    require_ocp()
    path = Path(path)
    labels = labels or {}
    chosen = [(labels.get(name, name), part, shapes[name]) for name, part in parts.items() if name in shapes]
    section: dict[str, Any] = {
        "file": None, "stroke_position_mm": 0.0, "missing": [name for name in parts if name not in shapes],
        "products": {product: {"instances": list(part.instances), "shape": _shape_kind(part, thread_bodies)}
                     for product, part, _ in chosen},
        "placement_max_diff_mm": None, "placement_max_diff_rad": None,
    }
    try:
        with atomic_path(path) as tmp:
            _write(str(tmp), title, chosen, path)
            back = read_step_assembly(tmp)
            problems, dmm, drad = placement_problems(chosen, back)
            section["placement_max_diff_mm"], section["placement_max_diff_rad"] = dmm, drad
            if problems:
                section["problems"] = problems
                raise _Rejected()
    except _Rejected:
        return section
    section["file"] = path.name
    return section


def assembly_files(section: Mapping[str, Any] | None) -> list[str]:
    """The file the assembly entry says was written (none when the check failed)."""
    return [section["file"]] if section is not None and section["file"] else []


def rotation_angle(R: NDArray[np.float64]) -> float:
    """The angle (rad) of a rotation matrix, accurate near zero (atan2 of the sine from the
    skew part and the cosine from the trace; arccos of the trace alone loses half the digits
    there)."""
    skew = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return float(math.atan2(0.5 * np.linalg.norm(skew), 0.5 * (np.trace(R) - 1.0)))


class _Rejected(Exception):
    pass


def placement_problems(chosen: list[tuple[str, "CompletePart", Any]],
                       back: StepAssemblyContent) -> tuple[list[str], float, float]:
    """What the read-back assembly gets wrong: a product or copy missing or misplaced beyond
    :data:`PLACEMENT_TOLERANCE`; and the largest placement differences (mm, rad)."""
    problems = []
    by_name = {inst.name: inst for inst in back.instances}
    dmm = drad = 0.0
    for product, part, _ in chosen:
        if product not in back.products:
            problems.append(f"product {product} is not in the file")
        for k, body in enumerate(part.instances):
            inst = by_name.get(body)
            if inst is None or inst.product != product:
                problems.append(f"copy {body} of {product} is not in the file")
                continue
            T = part.transforms[k]
            dmm = max(dmm, float(np.abs(inst.transform[:3, 3] - T[:3, 3]).max()))
            drad = max(drad, rotation_angle(inst.transform[:3, :3].T @ T[:3, :3]))
    if dmm > PLACEMENT_TOLERANCE[0] or drad > PLACEMENT_TOLERANCE[1]:
        problems.append(f"placements read back differ by {dmm:.3g} mm and {drad:.3g} rad")
    return problems, dmm, drad
