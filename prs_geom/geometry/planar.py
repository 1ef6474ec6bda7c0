"""Planar (2D) geometry in pure numpy: transforms, distances and tests on closed polygons.

Owns the generic 2D toolkit of the package: homogeneous 2D transforms
(:func:`rotation_2d`, :func:`transform_2d`, :func:`apply_transform_2d`), point-to-segment and
segment-to-segment distances, the even-odd point-in-polygon test, the signed (shoelace) area
and the exact minimum clearance between two closed polygons (:func:`min_clearance_2d`).

Conventions: points are ``(..., 2)`` float arrays (x, y) in mm; angles in radians,
counter-clockwise positive; a closed polygon is given by its vertices in order, the first not
repeated at the end; a 3x3 homogeneous transform maps column vectors (x, y, 1).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["Clearance2D", "apply_transform_2d", "frozen_float64", "min_clearance_2d", "point_in_polygon",
           "point_segment_distance", "polygon_area", "rotation_2d", "segment_segment_distance",
           "transform_2d"]


def frozen_float64(a: ArrayLike) -> NDArray[np.float64]:
    """A C-contiguous, read-only float64 array of ``a`` (a copy unless it already is one)."""
    out = np.ascontiguousarray(a, dtype=np.float64)
    out.flags.writeable = False
    return out


# --------------------------------------------------------------------------- transforms
def rotation_2d(angle_rad: float) -> NDArray[np.float64]:
    """2x2 rotation matrix by ``angle_rad`` (counter-clockwise), acting on column vectors."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, -s], [s, c]])


def transform_2d(angle_rad: float, tx: float = 0.0, ty: float = 0.0) -> NDArray[np.float64]:
    """3x3 homogeneous transform: rotation by ``angle_rad`` about the origin, then translation."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, -s, tx], [s, c, ty], [0.0, 0.0, 1.0]])


def apply_transform_2d(transform: NDArray[np.float64], points: NDArray[np.float64]) -> NDArray[np.float64]:
    """Points ``(..., 2)`` mapped by the 3x3 homogeneous ``transform``."""
    return points @ transform[:2, :2].T + transform[:2, 2]


# --------------------------------------------------------------------------- distances
def _dot(u: NDArray, v: NDArray) -> NDArray:
    return np.einsum("...i,...i->...", u, v)


def _closest_on_segment(p: NDArray, a: NDArray, b: NDArray) -> NDArray[np.float64]:
    """Closest point to p on the segment a-b (all (..., 2), broadcast); a when a = b."""
    ab = b - a
    length_sq = _dot(ab, ab)
    t = np.clip(_dot(p - a, ab) / np.where(length_sq > 0, length_sq, 1.0), 0.0, 1.0)
    return a + t[..., None] * ab


def point_segment_distance(p: ArrayLike, a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    """Distance (mm) from points p to segments a-b (all (..., 2), broadcast)."""
    p, a, b = (np.asarray(v, dtype=float) for v in (p, a, b))
    d = p - _closest_on_segment(p, a, b)
    return np.sqrt(_dot(d, d))


def _cross(u: NDArray, v: NDArray) -> NDArray:
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def segment_segment_distance(p0: NDArray, p1: NDArray, q0: NDArray,
                             q1: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """Distance between segments p0-p1 and q0-q1 (broadcast (..., 2)) and the closest points.

    Returns ``(distance, point_on_p, point_on_q)``; for properly crossing segments the
    distance is 0 and both points are the crossing.
    """
    d1, d2 = p1 - p0, q1 - q0
    o1 = _cross(d1, q0 - p0)
    o2 = _cross(d1, q1 - p0)
    o3 = _cross(d2, p0 - q0)
    o4 = _cross(d2, p1 - q0)
    crossing = (o1 * o2 < 0) & (o3 * o4 < 0)
    best = np.full(np.broadcast_shapes(o1.shape, o3.shape), np.inf)
    pa = np.zeros(best.shape + (2,))
    pb = np.zeros(best.shape + (2,))
    # without a crossing the closest pair has an end point of one segment in it
    for pt, a, b, pt_is_p in ((p0, q0, q1, True), (p1, q0, q1, True), (q0, p0, p1, False), (q1, p0, p1, False)):
        foot = _closest_on_segment(pt, a, b)
        dv = pt - foot
        d = np.sqrt(_dot(dv, dv))
        better = d < best
        best = np.where(better, d, best)
        ptb = np.broadcast_to(pt, pa.shape)
        if pt_is_p:
            pa = np.where(better[..., None], ptb, pa)
            pb = np.where(better[..., None], foot, pb)
        else:
            pa = np.where(better[..., None], foot, pa)
            pb = np.where(better[..., None], ptb, pb)
    best = np.where(crossing, 0.0, best)
    if np.any(crossing):
        t = o1 / np.where(o1 - o2 == 0, 1.0, o1 - o2)
        x = q0 + t[..., None] * d2
        pa = np.where(crossing[..., None], x, pa)
        pb = np.where(crossing[..., None], x, pb)
    return best, pa, pb


# --------------------------------------------------------------------------- polygons
def point_in_polygon(points: ArrayLike, polygon: ArrayLike) -> NDArray[np.bool_]:
    """Even-odd rule: which of ``points`` (n, 2) lie inside the closed ``polygon`` (N, 2)."""
    p = np.atleast_2d(np.asarray(points, dtype=float))
    v = np.asarray(polygon, dtype=float)
    w = np.roll(v, -1, axis=0)
    y0, y1 = v[None, :, 1], w[None, :, 1]
    py = p[:, None, 1]
    straddle = (y0 > py) != (y1 > py)
    xi = v[None, :, 0] + (py - y0) * (w[None, :, 0] - v[None, :, 0]) / np.where(y1 == y0, 1.0, y1 - y0)
    hits = straddle & (p[:, None, 0] < xi)
    return (np.count_nonzero(hits, axis=1) % 2) == 1


def polygon_area(pts: ArrayLike) -> float:
    """Signed area (mm^2) of a closed polygon (shoelace); > 0 counter-clockwise."""
    p = np.asarray(pts, dtype=float)
    q = np.roll(p, -1, axis=0)
    return 0.5 * float(np.sum(p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]))


# --------------------------------------------------------------------------- clearance
@dataclass(frozen=True)
class Clearance2D:
    """Result of :func:`min_clearance_2d`.

    distance_mm : minimum distance between the two boundaries (0 when they cross or touch).
    overlap : True when the materials intersect (boundaries cross, or one boundary lies
        inside the other's material).
    point_a, point_b : closest points (transformed frame) on boundary a and b.
    """

    distance_mm: float
    overlap: bool
    point_a: tuple[float, float]
    point_b: tuple[float, float]


#: Consecutive segments per group of :func:`min_clearance_2d`'s pruning.
_GROUP = 16


@dataclass(frozen=True)
class _SegmentGroups:
    """Segments of a closed polygon for pruning: per segment its start, end, midpoint and half
    length; per group of ``_GROUP`` consecutive segments the segment indices (G, _GROUP) and
    the bounding circle (G, 3: centre x, centre y, radius). The last group repeats its last
    segment as padding (a duplicate never changes a minimum)."""

    start: NDArray
    end: NDArray
    mid: NDArray
    half_length: NDArray
    index: NDArray
    circle: NDArray


def _segment_groups(P: NDArray) -> _SegmentGroups:
    n = len(P)
    P0, P1 = P, np.roll(P, -1, axis=0)
    mid = 0.5 * (P0 + P1)
    half = 0.5 * np.hypot(*(P1 - P0).T)
    n_groups = -(-n // _GROUP)
    idx = np.minimum(np.arange(n_groups * _GROUP), n - 1).reshape(n_groups, _GROUP)
    pts = np.concatenate([P0[idx], P1[idx]], axis=1)
    c = 0.5 * (pts.min(axis=1) + pts.max(axis=1))
    R = np.sqrt(((pts - c[:, None, :]) ** 2).sum(-1)).max(axis=1)
    return _SegmentGroups(start=P0, end=P1, mid=mid, half_length=half, index=idx,
                          circle=np.concatenate([c, R[:, None]], axis=1))


def _candidate_segment_pairs(ga: _SegmentGroups, gb: _SegmentGroups) -> tuple[NDArray, NDArray]:
    """Indices (SA, SB) of the segment pairs that may hold the minimum distance.

    An upper bound d_ub (a vertex-to-vertex distance of the most promising group pair, then
    the smallest midpoint-to-midpoint distance of the surviving groups: points of the
    boundaries) prunes the group pairs, then the segment pairs, whose bounding circles are
    farther apart than d_ub.
    """
    ca, cb = ga.circle, gb.circle
    centre_gap = np.sqrt(((ca[:, None, :2] - cb[None, :, :2]) ** 2).sum(-1))
    lower_bound = centre_gap - ca[:, None, 2] - cb[None, :, 2]               # (Ga, Gb)
    i, j = np.unravel_index(np.argmin(lower_bound), lower_bound.shape)
    d_ub = float(np.sqrt(((ga.start[ga.index[i]][:, None] - gb.start[gb.index[j]][None, :]) ** 2).sum(-1)).min())
    gi, gj = np.nonzero(lower_bound <= d_ub)
    sa = ga.index[gi][:, :, None]                                           # (n, G, 1)
    sb = gb.index[gj][:, None, :]                                           # (n, 1, G)
    mid_gap = np.sqrt(((ga.mid[sa] - gb.mid[sb]) ** 2).sum(-1))             # (n, G, G)
    d_ub = min(d_ub, float(mid_gap.min()))
    keep = mid_gap - ga.half_length[sa] - gb.half_length[sb] <= d_ub
    return np.broadcast_to(sa, keep.shape)[keep], np.broadcast_to(sb, keep.shape)[keep]


def min_clearance_2d(outline_a: ArrayLike, transform_a: ArrayLike, outline_b: ArrayLike,
                     transform_b: ArrayLike, *, a_material_inside: bool = True,
                     b_material_inside: bool = True) -> Clearance2D:
    """Exact minimum distance between two closed polygons and whether their materials overlap.

    Parameters
    ----------
    outline_a, outline_b : (N, 2) arrays
        Closed polygons (not repeated at the end), e.g. a gear outline.
    transform_a, transform_b : (3, 3) arrays
        Homogeneous 2D transforms applied to each outline (:func:`transform_2d`).
    a_material_inside, b_material_inside : bool
        Which side of each polygon is material: True for a gear (inside), False for a ring
        gear outline (material outside the bore polygon).

    Notes
    -----
    Method (all numpy, exact): segments in groups of 16 with bounding circles. An upper bound
    d_ub (a vertex-to-vertex distance of the most promising group pair, then the distance
    between two segment midpoints, both points of the boundaries) prunes every group pair and
    then every segment pair whose bounding circles are farther apart than d_ub; the survivors
    get the exact segment-segment distance (0 for crossing segments). Overlap: a boundary
    crossing, or a vertex of one polygon inside the other's material (even-odd
    point-in-polygon), which catches a whole boundary buried in material.
    """
    A = apply_transform_2d(np.asarray(transform_a, dtype=float), np.asarray(outline_a, dtype=float))
    B = apply_transform_2d(np.asarray(transform_b, dtype=float), np.asarray(outline_b, dtype=float))
    ga, gb = _segment_groups(A), _segment_groups(B)
    SA, SB = _candidate_segment_pairs(ga, gb)
    d, xa, xb = segment_segment_distance(ga.start[SA], ga.end[SA], gb.start[SB], gb.end[SB])
    k = int(np.argmin(d))
    best = float(d[k])
    overlap = best <= 0.0
    if not overlap:
        a_in_b = bool(point_in_polygon(A[:1], B)[0]) == b_material_inside
        b_in_a = bool(point_in_polygon(B[:1], A)[0]) == a_material_inside
        overlap = a_in_b or b_in_a
    return Clearance2D(distance_mm=best, overlap=overlap, point_a=(float(xa[k, 0]), float(xa[k, 1])),
                       point_b=(float(xb[k, 0]), float(xb[k, 1])))
