"""Meshes of the mechanism parts of :mod:`prs_geom.geometry.mechanism`: carriers, roller
journals, retaining rings and nut ends.

Every part is prisms of polygons (manifold3d cross-sections extruded along z), meshed no
coarser than :data:`MECHANISM_CHORD_MM`, so that its volume is within 0.1 % of the closed
form. Polygons sit on the safe side of their circles: an outside (shaft, ring, carrier rim)
has its vertices on the circle, so it lies inside it; a bore has its edges tangent to the
circle, so it lies outside it. Two parts with a positive clearance by design therefore
never overlap as meshes, and a measured clearance exceeds the designed one by at most the
chordal deviation of the shaft.
"""
from __future__ import annotations

import math

import numpy as np
import trimesh
from numpy.typing import NDArray

from prs_geom.geometry.frames import carrier_angles
from prs_geom.geometry.mechanism import RING_GAP_RAD, MechanismLayout
from prs_geom.mesh.thread import from_manifold
from prs_geom.model.design import PRSDesign

__all__ = ["MECHANISM_CHORD_MM", "mechanism_meshes", "segments", "translation"]

#: The mechanism parts are never meshed coarser than this (mm).
MECHANISM_CHORD_MM = 1e-3


def segments(radius: float, tol: float) -> int:
    """Polygon sides whose sagitta on ``radius`` is at most ``tol`` (a multiple of 4, >= 16)."""
    half = math.acos(max(-1.0, 1.0 - tol / radius)) if tol < radius else math.pi / 2
    n = max(16, math.ceil(math.pi / half))
    return 4 * math.ceil(n / 4)


def _circle(radius: float, tol: float, centre: tuple[float, float] = (0.0, 0.0), hole: bool = False) -> NDArray[np.float64]:
    """Polygon of a circle (counter-clockwise): vertices on it, or for a ``hole`` edges
    tangent to it (vertices at radius / cos(pi / n))."""
    n = segments(radius, tol)
    r = radius / math.cos(math.pi / n) if hole else radius
    t = 2.0 * math.pi * np.arange(n) / n
    return np.column_stack([centre[0] + r * np.cos(t), centre[1] + r * np.sin(t)])


def _arc(radius: float, tol: float, start: float, stop: float) -> NDArray[np.float64]:
    """Vertices on a circular arc from angle ``start`` to ``stop`` (rad, both included),
    counter-clockwise, in as many steps as the full circle's polygon has sides."""
    n = segments(radius, tol)
    t = np.append(start + (stop - start) * np.arange(n) / n, stop)
    return np.column_stack([radius * np.cos(t), radius * np.sin(t)])


def _extruded(outer: NDArray, holes: list[NDArray], z0: float, z1: float):
    """The manifold3d solid of a polygon with holes (counter-clockwise polygons) between
    the planes z0 < z1."""
    import manifold3d

    polys = [np.ascontiguousarray(outer)] + [np.ascontiguousarray(h[::-1]) for h in holes]
    section = manifold3d.CrossSection(polys, manifold3d.FillRule.EvenOdd)
    return section.extrude(z1 - z0).translate((0.0, 0.0, z0))


def _trimesh(solid) -> "trimesh.Trimesh":
    return trimesh.Trimesh(*from_manifold(solid), process=False, validate=False)


def _prism(outer: NDArray, holes: list[NDArray], z0: float, z1: float) -> "trimesh.Trimesh":
    return _trimesh(_extruded(outer, holes, z0, z1))


def translation(z: float) -> NDArray[np.float64]:
    """The 4x4 transform that moves a part by ``z`` (mm) along the axis."""
    T = np.eye(4)
    T[2, 3] = z
    return T


def mechanism_meshes(design: PRSDesign, lay: MechanismLayout,
                     tol: float) -> dict[str, tuple["trimesh.Trimesh", NDArray[np.float64]]]:
    """Meshes (mm) keyed ``journal_lo/hi`` (roller frame), ``carrier_lo/hi``,
    ``retaining_ring_lo/hi`` and ``nut_end_lo/hi``, each as (mesh in its own frame, 4x4
    transform from that frame to the roller frame for a journal, to the screw frame (= the
    nut frame at assembly) for the others).

    The two carriers are one mesh, and so are the two retaining rings (both prisms of one
    outline): in the part's own frame (z = 0 at its lower face), moved to each end by a
    translation, so that an exported assembly places two copies of one part. The journals
    and nut ends are meshed in place (transform the identity)."""
    tol = min(tol, MECHANISM_CHORD_MM)
    I = np.eye(4)
    out: dict[str, tuple[trimesh.Trimesh, NDArray[np.float64]]] = {}
    r_j = 0.5 * lay.journal_fit.shaft_diameter_mm
    r_b = 0.5 * lay.journal_fit.hole_diameter_mm
    a = lay.centre_distance_mm
    journal = _circle(r_j, tol)
    carrier = (_circle(lay.carrier_outer_radius_mm, tol),
               [_circle(lay.carrier_inner_radius_mm, tol, hole=True),
                *(_circle(r_b, tol, (a * math.cos(psi), a * math.sin(psi)), hole=True) for psi in carrier_angles(design))])
    # the C-shaped ring, its opening centred on +x: outer arc out, inner arc back
    half = 0.5 * RING_GAP_RAD
    ring = np.vstack([_arc(lay.ring_outer_radius_mm, tol, half, 2.0 * math.pi - half),
                      _arc(lay.ring_inner_radius_mm, tol, half, 2.0 * math.pi - half)[::-1]])
    lo = lay.ends[0]
    carrier_mesh = _prism(*carrier, 0.0, lo.carrier[1] - lo.carrier[0])
    ring_mesh = _prism(ring, [], 0.0, lo.ring[1] - lo.ring[0])
    for side, end in zip(("lo", "hi"), lay.ends):
        out[f"journal_{side}"] = (_prism(journal, [], *end.journal), I)
        out[f"carrier_{side}"] = (carrier_mesh, translation(end.carrier[0]))
        out[f"retaining_ring_{side}"] = (ring_mesh, translation(end.ring[0]))
        out[f"nut_end_{side}"] = (_nut_end(lay, end, tol), I)
    return out


def _nut_end(lay: MechanismLayout, end, tol: float) -> "trimesh.Trimesh":
    """The nut end: one outer cylinder (relieved, :data:`~prs_geom.geometry.mechanism.NUT_END_RELIEF_MM`)
    with the bores cut out of it: the sleeve's bore around the ring gear (overlapping the
    gear's body, same rigid body) and the retaining-ring bore with its groove. Cut from one
    solid rather than united from touching prisms, so it is one closed shell."""
    R = lay.nut_end_outer_radius_mm
    z0, z1 = end.nut_end
    out = end.outward < 0
    pad = 1.0      # cutters overshoot the open end faces, so no cut face is coplanar with them
    body = _extruded(_circle(R, tol), [], z0, z1)
    gear = end.gear_zone if (lay.ring_gear_outer_radius_mm is not None and lay.gear_face_width_mm > 0.0) else None
    if out:
        bored = (z0 - pad, gear[0] if gear else z1 + pad)
    else:
        bored = (gear[1] if gear else z0 - pad, z1 + pad)
    cuts = [(lay.nut_bore_radius_mm, bored), (lay.groove_radius_mm, end.groove)]
    if gear:
        cuts.append((lay.nut_end_sleeve_inner_radius_mm, (gear[0] - (0.0 if out else pad), gear[1] + (pad if out else 0.0))))
    for radius, (za, zb) in cuts:
        body = body - _extruded(_circle(radius, tol, hole=True), [], za, zb)
    return _trimesh(body)
