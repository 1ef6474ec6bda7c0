"""Broad phase of the interference check: which placed parts can touch at all.

Every placed part gets two exact bounds in the screw frame, both taken from its triangles
(not from the analytic part, so that they hold for the mesh FCL is asked about):

- its axis-aligned box, and
- the interval of its distances from the screw axis (z): the largest is a vertex's, the
  smallest the 2D distance of the origin from the triangles' projections onto the xy
  plane (zero when a projection covers the origin).

Two parts whose boxes or radial intervals are apart by more than :data:`GAP_MM` have no
point in common, so FCL would report no collision: the pair is settled without a query and
neither part needs a BVH for it. The radial interval is what settles the coaxial fits (the
screw inside the nut bore, the carriers and ring gears around the screw), whose boxes
overlap.

A large mesh is queried against one partner body through the triangles whose boxes meet
that body's box (:func:`near_faces`): every triangle that can meet the partner is among
them, so FCL finds the same intersecting triangle pairs, and only a slice of the large
mesh's BVH exists at a time.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["GAP_MM", "PlacedBounds", "can_touch", "face_boxes", "longest_edge", "near_faces", "placed_bounds"]

#: Separation (mm) above which two bounds are apart: far above the rounding of coordinates
#: of order 100 mm (1e-14 mm), far below any chord tolerance (1e-4 mm at the finest).
GAP_MM = 1e-6


@dataclass(frozen=True)
class PlacedBounds:
    """Bounds of one placed mesh in the screw frame (mm).

    Attributes
    ----------
    lo, hi : ndarray (3,)
        Corners of the axis-aligned bounding box.
    r_min, r_max : float
        Smallest and largest distance of a point of the mesh from the screw axis.
    """

    lo: NDArray[np.float64]
    hi: NDArray[np.float64]
    r_min: float
    r_max: float


def _world(vertices: NDArray, transform: NDArray) -> NDArray[np.float64]:
    """Vertices (n, 3) placed by a 4x4 transform, float64."""
    V = np.asarray(vertices, dtype=np.float64)
    T = np.asarray(transform, dtype=np.float64)
    return V @ T[:3, :3].T + T[:3, 3]


def longest_edge(vertices: NDArray, faces: NDArray) -> float:
    """Length (mm) of a mesh's longest edge; the same wherever the mesh is placed."""
    tri = np.asarray(vertices, dtype=np.float64)[np.asarray(faces)]
    d = tri - np.roll(tri, 1, axis=1)
    return float(np.sqrt(np.max(np.einsum("ijk,ijk->ij", d, d)))) if len(tri) else 0.0


def _min_axis_distance(tri_xy: NDArray) -> float:
    """Smallest distance of the origin from triangles projected on the xy plane, (n, 3, 2).

    A projection that covers the origin gives zero; one that degenerates to a segment
    (a face in a plane through the axis) counts as covering it when its three edge cross
    products are all zero, which can only lower the bound.
    """
    a, b, c = tri_xy[:, 0], tri_xy[:, 1], tri_xy[:, 2]

    def cross(p: NDArray, q: NDArray) -> NDArray:
        # z of (q - p) x (0 - p): the side of the origin from edge p -> q
        return (q[:, 0] - p[:, 0]) * (-p[:, 1]) - (q[:, 1] - p[:, 1]) * (-p[:, 0])

    s = np.stack([cross(a, b), cross(b, c), cross(c, a)], axis=1)
    if np.any(np.all(s >= 0.0, axis=1) | np.all(s <= 0.0, axis=1)):
        return 0.0
    best = np.inf
    for p, q in ((a, b), (b, c), (c, a)):
        d = q - p
        dd = np.einsum("ij,ij->i", d, d)
        t = np.clip(np.divide(-np.einsum("ij,ij->i", p, d), dd, out=np.zeros_like(dd), where=dd > 0.0), 0.0, 1.0)
        foot = p + t[:, None] * d
        best = min(best, float(np.sqrt(np.min(np.einsum("ij,ij->i", foot, foot)))))
    return best


def placed_bounds(vertices: NDArray, faces: NDArray, transform: NDArray,
                  edge: float | None = None) -> PlacedBounds:
    """The :class:`PlacedBounds` of a mesh placed by ``transform`` (4x4, mesh frame to
    screw frame). ``edge``: the mesh's :func:`longest_edge` when known (mm)."""
    F = np.asarray(faces)
    if not len(F):
        raise ValueError("placed_bounds: the mesh has no faces")
    # every vertex, used by a face or not: an unused one can only widen the bounds
    W = _world(vertices, transform)
    r = np.sqrt(np.einsum("ij,ij->i", W[:, :2], W[:, :2]))
    edge = longest_edge(vertices, F) if edge is None else edge
    # no point of a face is nearer the axis than its nearest vertex less the longest edge,
    # so only the faces with a vertex within that of the nearest vertex are measured
    r_corner = r[F]
    near = np.any(r_corner <= r_corner.min() + edge, axis=1)
    return PlacedBounds(W.min(axis=0), W.max(axis=0), _min_axis_distance(W[F[near]][:, :, :2]), float(r.max()))


def can_touch(a: PlacedBounds, b: PlacedBounds, gap: float = GAP_MM) -> bool:
    """Whether two placed meshes may have a point in common: their boxes and their radial
    intervals both meet (within ``gap``, mm)."""
    boxes = bool(np.all(a.lo <= b.hi + gap) and np.all(b.lo <= a.hi + gap))
    return boxes and a.r_min <= b.r_max + gap and b.r_min <= a.r_max + gap


def face_boxes(vertices: NDArray, faces: NDArray, transform: NDArray) -> tuple[NDArray, NDArray]:
    """Corners (n, 3) of the axis-aligned box of every face of a mesh placed by
    ``transform`` (screw frame, mm)."""
    tri = _world(vertices, transform)[np.asarray(faces)]
    return tri.min(axis=1), tri.max(axis=1)


def near_faces(boxes: tuple[NDArray, NDArray], lo: NDArray, hi: NDArray, gap: float = GAP_MM) -> NDArray[np.intp]:
    """Indices of the faces whose boxes (:func:`face_boxes`) meet the box ``lo``-``hi``
    (screw frame, mm, widened by ``gap``): every face that can meet anything inside it."""
    face_lo, face_hi = boxes
    keep = np.all(face_hi >= np.asarray(lo) - gap, axis=1) & np.all(face_lo <= np.asarray(hi) + gap, axis=1)
    return np.flatnonzero(keep)
