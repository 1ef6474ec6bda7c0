"""Exact solids of the carrier and the retaining ring as cylinders to cut (no OpenCascade).

The carrier and the retaining ring of :mod:`prs_geom.geometry.mechanism` are circular
cylinders and planes: each is described here as a body cylinder less cutter cylinders
(:class:`CylinderSolid`), at the modelled sizes (fitted features at the middle of their
ISO 286 zone), in the part's own frame (mm, z = 0 at its face toward the nut end, z along
the axis, as ``<part>.stl``). :mod:`prs_geom.exports.step` turns a description into an
OpenCascade B-rep; its volume must equal ``exact_volume_mm3``, the closed form.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover
    from prs_geom.model.design import PRSDesign

__all__ = ["MECHANISM_SOLID_PARTS", "Cylinder", "CylinderSolid", "mechanism_part_mesh", "mechanism_solid"]

#: The mechanism parts described here.
MECHANISM_SOLID_PARTS = ("carrier", "retaining_ring")


@dataclass(frozen=True, kw_only=True)
class Cylinder:
    """A circular cylinder (mm) with its axis along +z: base centre ``origin``, ``radius``
    and ``height``; a sector of ``sweep_rad`` starting at the direction ``x_dir`` and
    running counter-clockwise about +z when ``sweep_rad`` is given, the full cylinder
    otherwise."""

    radius: float
    height: float
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)
    sweep_rad: float | None = None
    x_dir: tuple[float, float, float] = (1.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if not (self.radius > 0.0 and self.height > 0.0):
            raise ValueError(f"a cylinder needs a positive radius and height, not {self.radius!r}, {self.height!r}")
        if self.sweep_rad is not None and not 0.0 < self.sweep_rad <= 2.0 * math.pi:
            raise ValueError(f"a cylinder's sweep must lie in (0, 2 pi], not {self.sweep_rad!r}")


@dataclass(frozen=True, kw_only=True)
class CylinderSolid:
    """A part as ``body`` less each of ``cutters`` in turn, and its closed-form volume
    ``exact_volume_mm3`` (mm^3). The cutters run one unit past both end faces, so no cut
    face is coplanar with one."""

    part: str
    body: Cylinder
    cutters: tuple[Cylinder, ...]
    exact_volume_mm3: float


def _carrier(design: "PRSDesign", lay: Any) -> CylinderSolid:
    from prs_geom.geometry.frames import carrier_angles

    height = lay.carrier_thickness_mm
    bore_radius = 0.5 * lay.journal_fit.hole_diameter_mm
    centre_distance = lay.centre_distance_mm
    bores = tuple(Cylinder(radius=bore_radius, height=height + 2.0,
                           origin=(centre_distance * math.cos(psi), centre_distance * math.sin(psi), -1.0))
                  for psi in carrier_angles(design))
    return CylinderSolid(part="carrier", body=Cylinder(radius=lay.carrier_outer_radius_mm, height=height),
                         cutters=(Cylinder(radius=lay.carrier_inner_radius_mm, height=height + 2.0,
                                           origin=(0.0, 0.0, -1.0)), *bores),
                         exact_volume_mm3=lay.carrier_volume_mm3)


def _retaining_ring(lay: Any) -> CylinderSolid:
    from prs_geom.geometry.mechanism import RING_GAP_RAD

    height = lay.ring.thickness_mm
    half_gap = 0.5 * RING_GAP_RAD
    # a sector from the gap's edge round to its other edge, less the inner cylinder
    outer = Cylinder(radius=lay.ring_outer_radius_mm, height=height, sweep_rad=2.0 * math.pi - RING_GAP_RAD,
                     x_dir=(math.cos(half_gap), math.sin(half_gap), 0.0))
    inner = Cylinder(radius=lay.ring_inner_radius_mm, height=height + 2.0, origin=(0.0, 0.0, -1.0))
    return CylinderSolid(part="retaining_ring", body=outer, cutters=(inner,), exact_volume_mm3=lay.ring_volume_mm3)


def mechanism_solid(design: "PRSDesign", part: str) -> CylinderSolid:
    """The carrier or the retaining ring of ``design`` as cylinders to cut.

    Raises
    ------
    ValueError
        The design has no mechanism (``mechanism.enabled``) or ``part`` is not one of
        :data:`MECHANISM_SOLID_PARTS`.
    """
    from prs_geom.geometry.mechanism import layout

    lay = layout(design)
    if lay is None or part not in MECHANISM_SOLID_PARTS:
        raise ValueError(f"no mechanism part {part!r} in this design (mechanism.enabled and one of "
                         f"{', '.join(MECHANISM_SOLID_PARTS)})")
    return _carrier(design, lay) if part == "carrier" else _retaining_ring(lay)


def mechanism_part_mesh(design: "PRSDesign", part: str) -> Any:
    """The part's mesh at :data:`~prs_geom.mesh.mechanism.MECHANISM_CHORD_MM` in the frame of
    :func:`mechanism_solid` (``<part>_lo`` of :func:`~prs_geom.mesh.mechanism.mechanism_meshes`)."""
    from prs_geom.geometry.mechanism import layout
    from prs_geom.mesh.mechanism import MECHANISM_CHORD_MM, mechanism_meshes

    return mechanism_meshes(design, layout(design), MECHANISM_CHORD_MM)[f"{part}_lo"][0]
