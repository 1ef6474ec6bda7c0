"""Triangle meshes of spur gears: prisms of the exact 2D gear outline (numpy only).

A gear mesh is the outline of :meth:`prs_geom.geometry.gears.SpurGear.outline` (vertices on
the involute, fillet and circles, chord error <= the tolerance) extruded between two planes
z = z0 and z = z1 of the gear frame, closed and consistently wound with outward normals:

* external gear: a solid; each end cap is a fan from the axis;
* internal (ring) gear: an annulus between the tooth outline (inside) and a circle of radius
  ``outer_radius_mm`` (the ring body); each end cap is a strip of quads between the two.

Both cap triangulations need every ray from the axis to meet the tooth outline once (the
outline is star-shaped about the axis, i.e. its polar angle increases strictly along it).
That holds for generated gears without undercut and is verified; an undercut outline is
refused. For the annulus the outer circle gets a vertex at the polar angle of every outline
vertex and the outline one at the angle of every extra circle vertex (a point on its
segment, so the shape is unchanged), so each cap is a strip of radial quads, two triangles
each, and the walls use the same vertices (no T-junctions).
"""
from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from prs_geom.geometry.gears import SpurGear
from prs_geom.geometry.planar import rotation_2d
from prs_geom.model.errors import DesignError

__all__ = ["gear_mesh", "star_shaped"]

_TWO_PI = 2.0 * math.pi


def _unwrapped_angles(pts: NDArray[np.float64]) -> NDArray[np.float64]:
    """Polar angles along a closed polygon, unwrapped, starting in (-pi, pi]."""
    return np.unwrap(np.arctan2(pts[:, 1], pts[:, 0]))


def star_shaped(outline: NDArray[np.float64]) -> bool:
    """True when the polar angle increases strictly along the closed polygon and turns once
    (every ray from the origin meets the outline exactly once)."""
    ang = _unwrapped_angles(outline)
    step = np.diff(np.concatenate([ang, [ang[0] + _TWO_PI]]))
    return bool(np.all(step > 0.0) and abs(step.sum() - _TWO_PI) < 1e-9)


def _circle_steps(radius: float, tol: float) -> int:
    """Vertices of a polygon inscribed in a circle with sagitta <= tol."""
    return max(8, math.ceil(math.pi / math.acos(max(1.0 - tol / radius, -1.0))))


def _prism_walls(n: int, lo: NDArray[np.int64], hi: NDArray[np.int64], outward_ccw: bool) -> NDArray[np.int64]:
    """Wall quads between rings ``lo`` and ``hi`` of n vertices, two triangles each.

    For a counter-clockwise ring, (lo_i, lo_i+1, hi_i+1) has its normal on the right of the
    walking direction, i.e. outward from the enclosed region; ``outward_ccw=False`` flips."""
    i = np.arange(n)
    k = (i + 1) % n
    t1 = np.stack([lo[i], lo[k], hi[k]], axis=1)
    t2 = np.stack([lo[i], hi[k], hi[i]], axis=1)
    faces = np.concatenate([t1, t2])
    return faces if outward_ccw else faces[:, ::-1]


def gear_mesh(gear: SpurGear, z0: float, z1: float, chord_tol_mm: float = 1e-3, *,
              phase_rad: float = 0.0, outer_radius_mm: float | None = None
              ) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Closed triangle mesh of a gear between the planes z0 < z1 (gear frame, mm).

    Parameters
    ----------
    gear : SpurGear
        External gear (solid) or internal ring gear (annulus).
    z0, z1 : float
        End planes (mm), z0 < z1.
    chord_tol_mm : float
        Chord tolerance of the outline and of the outer circle (mm).
    phase_rad : float
        Rotation of the gear about its axis (rad, counter-clockwise seen from +z): tooth 0 is
        centred at this angle.
    outer_radius_mm : float
        Body radius of a ring gear (mm), larger than its root radius; required for internal
        gears, ignored for external ones.

    Returns
    -------
    vertices : (N, 3) float64
    faces : (M, 3) int64
        Counter-clockwise seen from outside (outward normals); watertight, every edge shared by
        exactly two faces. Vertex order: outline at z0, outline at z1, then (external) the two
        axis points or (internal) the outer circle at z0 and at z1.

    Raises
    ------
    DesignError
        For z1 <= z0, a missing or too small ``outer_radius_mm`` of a ring gear, or an outline
        that is not star-shaped about the axis (undercut gears).
    """
    z0, z1 = float(z0), float(z1)
    if not z1 > z0:
        raise DesignError("z1", z1, f"must exceed z0 = {z0!r}")
    outline = np.asarray(gear.outline(chord_tol_mm))
    if not star_shaped(outline):
        raise DesignError("gear", f"z={gear.teeth}, x={gear.profile_shift}",
                          "outline is not star-shaped about the axis (undercut?): the cap "
                          "triangulation needs every ray from the axis to meet it once")
    rot = rotation_2d(phase_rad)
    if not gear.internal:
        return _external_gear_mesh(outline @ rot.T, z0, z1)
    return _ring_gear_mesh(gear, outline, rot, z0, z1, chord_tol_mm, outer_radius_mm)


def _external_gear_mesh(P: NDArray[np.float64], z0: float,
                        z1: float) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """:func:`gear_mesh` of an external gear: the placed outline ``P`` (n, 2) as a prism
    between z0 and z1, its caps fanned from the two axis points."""
    n = len(P)
    V = np.concatenate([
        np.column_stack([P, np.full(n, z0)]),
        np.column_stack([P, np.full(n, z1)]),
        [[0.0, 0.0, z0], [0.0, 0.0, z1]],
    ])
    lo, hi = np.arange(n), np.arange(n, 2 * n)
    i = np.arange(n)
    k = (i + 1) % n
    bottom = np.stack([np.full(n, 2 * n), lo[k], lo[i]], axis=1)     # normal -z
    top = np.stack([np.full(n, 2 * n + 1), hi[i], hi[k]], axis=1)    # normal +z
    F = np.concatenate([_prism_walls(n, lo, hi, True), bottom, top])
    return V, F.astype(np.int64)


def _ring_gear_mesh(gear: SpurGear, outline: NDArray[np.float64], rot: NDArray[np.float64], z0: float, z1: float,
                    chord_tol_mm: float,
                    outer_radius_mm: float | None) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """:func:`gear_mesh` of a ring gear: the tooth outline and the body circle on one common
    set of angles, joined by radial quads in the caps."""
    if outer_radius_mm is None:
        raise DesignError("outer_radius_mm", outer_radius_mm, "is required for a ring gear (its body radius)")
    R = float(outer_radius_mm)
    if not R > gear.root_radius_mm:
        raise DesignError("outer_radius_mm", outer_radius_mm,
                          f"must exceed the ring root radius {gear.root_radius_mm:.6g} mm")
    # common angle set: the outline's vertex angles plus the circle's own uniform vertices
    ang_in = _unwrapped_angles(outline)
    a_start = ang_in[0]
    rel_in = ang_in - a_start                                   # [0, 2 pi), increasing
    m = _circle_steps(R, chord_tol_mm)
    rel_circ = _TWO_PI * np.arange(1, m) / m
    extra = rel_circ[np.min(np.abs(rel_circ[:, None] - rel_in[None, :]), axis=1) > 1e-12]
    rel = np.concatenate([rel_in, extra])
    is_in = np.concatenate([np.ones(len(rel_in), bool), np.zeros(len(extra), bool)])
    order = np.argsort(rel, kind="stable")
    rel, is_in = rel[order], is_in[order]
    # inner ring: outline vertices, plus points on the outline segments at the extra angles
    ang = a_start + rel
    seg = np.searchsorted(rel_in, rel, side="right") - 1        # segment start index
    p0 = outline[seg]
    p1 = outline[(seg + 1) % len(outline)]
    d = np.column_stack([np.cos(ang), np.sin(ang)])
    e = p1 - p0
    # ray (origin, d) meets segment p0 + u e: solve p0 + u e = t d  ->  u = (p0 x d)/(d x e)
    u = (p0[:, 0] * d[:, 1] - p0[:, 1] * d[:, 0]) / (d[:, 0] * e[:, 1] - d[:, 1] * e[:, 0])
    inner = np.where(is_in[:, None], outline[np.minimum(seg, len(outline) - 1)], p0 + u[:, None] * e)
    outer = R * d
    inner, outer = inner @ rot.T, outer @ rot.T
    n = len(rel)
    V = np.concatenate([
        np.column_stack([inner, np.full(n, z0)]),
        np.column_stack([inner, np.full(n, z1)]),
        np.column_stack([outer, np.full(n, z0)]),
        np.column_stack([outer, np.full(n, z1)]),
    ])
    il, ih = np.arange(n), np.arange(n, 2 * n)
    ol, oh = np.arange(2 * n, 3 * n), np.arange(3 * n, 4 * n)
    i = np.arange(n)
    k = (i + 1) % n
    # caps: radial quad (inner_i, inner_k, outer_k, outer_i) counter-clockwise seen from +z
    top = np.concatenate([np.stack([ih[i], oh[k], ih[k]], 1), np.stack([ih[i], oh[i], oh[k]], 1)])
    bottom = np.concatenate([np.stack([il[i], il[k], ol[k]], 1), np.stack([il[i], ol[k], ol[i]], 1)])
    F = np.concatenate([
        _prism_walls(n, ol, oh, True),       # outer body wall, normals away from the axis
        _prism_walls(n, il, ih, False),      # tooth wall, normals into the bore
        top, bottom,
    ])
    return V, F.astype(np.int64)
