"""Structured, graded triangle meshes of axisymmetric sections, generated with numpy.

Pure math, no I/O, no mesh library: node coordinates and triangles are built as arrays
from tensor-product grids (no Python loop over nodes or elements).

Frame: the meridian half-plane of a part, r radial (mm, >= 0), z axial (mm). A threaded
section holds ``teeth`` whole thread periods, z in [0, teeth * pitch]; tooth j (1-based)
has its mid-plane at z = (j - 1/2) p, so tooth 1 is next to the face z = 0 (the loaded end)
and z grows toward the free end. The end faces cut through groove centres, or end a plain
body piece beyond the thread (``ThreadSection.end_lengths``: a nut's ends).

Blocks of a threaded section
----------------------------
* the *body*: a tensor grid over r between the thread root radius and ``far_radius``
  (0 for a solid shaft, the outer radius for a nut) and over the whole axial length;
* one *tooth* block per tooth, from the root radius to the crest radius, mapped as
  r = r_root + s (r_crest - r_root), z = z_mid + eta t(r) with s in [0, 1],
  eta in [-1, 1] and t(r) the axial tooth half-width: the flanks eta = +-1 follow the
  profile exactly at the nodes, curved flanks included.
The body's axial nodes under a tooth are the tooth's base nodes z_mid + eta t(r_root), so
the blocks share nodes and the mesh is conforming. Each grid cell is cut into two
triangles along one diagonal; all triangles are turned counter-clockwise in (r, z).

Grading and levels
------------------
Every 1D node distribution is a fixed map of a uniform parameter on each segment
between break points (root and crest radii, the loaded bands' ends and centres, tooth
corners). Level L multiplies every segment's interval count by 2^L, so the meshes of
successive levels are nested (every node of level L is a node of level L + 1) and the
element sizes halve everywhere: the uniform refinement a Richardson estimate assumes.
The maps cluster nodes where the solution is rough: power maps x = t^q toward the
re-entrant root corners (stress singularities) and a two-sided map toward band ends
(the kinks of the load distribution).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from numpy.typing import NDArray

__all__ = ["segment_nodes", "graded_line", "TriangleMesh", "ThreadSection", "thread_section_mesh",
           "grid_mesh", "rectangle_mesh"]

#: Power of the one-sided and two-sided clustering maps (element size at a clustered end
#: ~ L (1/n)^q for n intervals). q = 2 resolves the root-corner singularity of a 225 deg
#: re-entrant corner well enough that the band displacements converge at about O(h^2).
CLUSTER_POWER = 2.0


def segment_nodes(x0: float, x1: float, n: int, cluster: str = "none", power: float = CLUSTER_POWER) -> NDArray:
    """n + 1 nodes from x0 to x1 (both included), clustered toward one end, both or none.

    Parameters
    ----------
    x0, x1 : float
        Segment ends (any unit; mm here).
    n : int
        Number of intervals (>= 1).
    cluster : {"none", "start", "end", "both"}
        Where the nodes crowd: x = t^q toward the start, 1 - (1 - t)^q toward the end,
        t^q / (t^q + (1 - t)^q) toward both, t the uniform parameter.
    power : float
        The exponent q (>= 1).
    """
    if n < 1:
        raise ValueError("a segment needs at least one interval")
    t = np.linspace(0.0, 1.0, n + 1)
    if cluster == "start":
        g = t ** power
    elif cluster == "end":
        g = 1.0 - (1.0 - t) ** power
    elif cluster == "both":
        g = t ** power / (t ** power + (1.0 - t) ** power)
    elif cluster == "none":
        g = t
    else:
        raise ValueError(f"unknown clustering {cluster!r}")
    out = x0 + (x1 - x0) * g
    out[0], out[-1] = x0, x1
    return out


def graded_line(breaks: NDArray, counts: NDArray, clusters: list[str], level: int,
                power: float = CLUSTER_POWER) -> NDArray:
    """Concatenated :func:`segment_nodes` over consecutive break points, each segment's
    interval count multiplied by 2^level; shared break points appear once."""
    breaks = np.asarray(breaks, dtype=np.float64)
    scale = 2 ** int(level)
    parts = [segment_nodes(breaks[i], breaks[i + 1], int(counts[i]) * scale, clusters[i], power)[:-1]
             for i in range(len(breaks) - 1)]
    return np.concatenate(parts + [breaks[-1:]])


@dataclass(frozen=True)
class TriangleMesh:
    """A triangle mesh of a meridian section with the node sets the loads and supports use.

    Parameters
    ----------
    points : (2, N) float array
        Node coordinates (r, z), mm.
    triangles : (3, M) int array
        Node indices of each triangle, counter-clockwise in (r, z).
    node_sets : dict[str, int array]
        Named node index sets of boundary lines (faces, flanks): ``"face_z0"``,
        ``"face_z1"`` (end faces), ``"axis"`` (r = 0, solid sections only), and for
        threaded sections ``"flank_<j>_<side>"`` with j the 1-based tooth and side
        ``"upper"`` (eta = +1, facing +z) or ``"lower"``, ordered root to crest.
    """

    points: NDArray
    triangles: NDArray
    node_sets: dict[str, NDArray] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        p = np.asarray(self.points, dtype=np.float64)
        t = np.asarray(self.triangles, dtype=np.int64)
        if p.ndim != 2 or p.shape[0] != 2 or t.ndim != 2 or t.shape[0] != 3:
            raise ValueError("points must be (2, N) and triangles (3, M)")
        if t.size and (t.min() < 0 or t.max() >= p.shape[1]):
            raise ValueError("triangle node index out of range")
        if np.any(p[0] < -1e-12):
            raise ValueError("an axisymmetric section lies in r >= 0")
        area = _signed_area(p, t)
        if np.any(area <= 0.0):
            raise ValueError("degenerate or clockwise triangle")
        object.__setattr__(self, "points", p)
        object.__setattr__(self, "triangles", t)

    @property
    def n_nodes(self) -> int:
        return int(self.points.shape[1])

    @property
    def n_triangles(self) -> int:
        return int(self.triangles.shape[1])


def _signed_area(p: NDArray, t: NDArray) -> NDArray:
    a, b, c = p[:, t[0]], p[:, t[1]], p[:, t[2]]
    return 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))


def _grid_triangles(index: NDArray) -> NDArray:
    """Two triangles per cell of a structured node-index grid (ni + 1, nj + 1): (3, 2 ni nj)."""
    a, b = index[:-1, :-1].ravel(), index[1:, :-1].ravel()
    c, d = index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    return np.concatenate([np.stack([a, b, c]), np.stack([a, c, d])], axis=1)


def _counter_clockwise(p: NDArray, t: NDArray) -> NDArray:
    """Triangles reordered so that every signed area is positive (a mapped grid may mirror)."""
    flip = _signed_area(p, t) < 0.0
    t = t.copy()
    t[[1, 2]] = np.where(flip, t[[2, 1]], t[[1, 2]])
    return t


def rectangle_mesh(r0: float, r1: float, z0: float, z1: float, nr: int, nz: int, level: int = 0,
                   cluster_r: str = "none", cluster_z: str = "none") -> TriangleMesh:
    """A graded structured mesh of the rectangle [r0, r1] x [z0, z1] (mm).

    ``nr``, ``nz`` are the level-0 interval counts (times 2^level); see :func:`grid_mesh`
    for the node sets.
    """
    return grid_mesh(segment_nodes(r0, r1, nr * 2 ** level, cluster_r),
                     segment_nodes(z0, z1, nz * 2 ** level, cluster_z))


def grid_mesh(r: NDArray, z: NDArray) -> TriangleMesh:
    """The structured mesh of the tensor grid of increasing radii ``r`` and axial positions
    ``z`` (mm). Node sets: ``"face_z0"`` (z = z[0]), ``"face_z1"`` (z = z[-1]), ``"inner"``
    (r = r[0]), ``"outer"`` (r = r[-1]) and ``"axis"`` when r[0] = 0."""
    r, z = np.asarray(r, dtype=np.float64), np.asarray(z, dtype=np.float64)
    if np.any(np.diff(r) <= 0) or np.any(np.diff(z) <= 0):
        raise ValueError("grid coordinates must increase")
    r0 = float(r[0])
    R, Z = np.meshgrid(r, z, indexing="ij")
    idx = np.arange(R.size).reshape(R.shape)
    p = np.stack([R.ravel(), Z.ravel()])
    t = _counter_clockwise(p, _grid_triangles(idx))
    sets = {"face_z0": idx[:, 0], "face_z1": idx[:, -1], "inner": idx[0, :], "outer": idx[-1, :]}
    if r0 == 0.0:
        sets["axis"] = idx[0, :]
    return TriangleMesh(p, t, sets)


@dataclass(frozen=True)
class ThreadSection:
    """The meridian section of a threaded part: geometry and mesh density.

    Parameters
    ----------
    pitch : float
        Axial pitch p (mm).
    teeth : int
        Number of whole thread periods (teeth) in the section (>= 1).
    root_radius, crest_radius : float
        Thread root and crest radii (mm); crest > root for an external thread (screw,
        roller), crest < root for an internal thread (nut).
    far_radius : float
        The body's other radius (mm): 0 for a solid shaft (external thread), the outer
        radius of the ring for a nut.
    half_width : callable
        Axial tooth half-width t(r) (mm) for an array of radii between root and crest
        (axial-section profile, :meth:`prs_geom.geometry.profiles.ThreadProfile.tooth_half_width`).
    bands : tuple of (float, float)
        Loaded bands, as (centre radius, radial half-extent) in mm: the tooth grid gets
        break points at each band's centre and ends.
    eta_intervals, groove_intervals, body_intervals : int
        Level-0 interval counts across the tooth, per half groove (each root flat half)
        and radially across the body.
    radial_size : float
        Level-0 target interval length (mm) along the tooth height between break points.
    band_intervals : int
        Level-0 intervals per band half.
    end_lengths : (float, float)
        Plain body (no teeth) beyond the threaded periods, before z = 0 and after
        z = teeth p (mm): a nut's ends beyond its thread. The section then spans
        [-end_lengths[0], teeth p + end_lengths[1]] and its end faces are those of the body.
    """

    pitch: float
    teeth: int
    root_radius: float
    crest_radius: float
    far_radius: float
    half_width: Callable[[NDArray], NDArray] = field(compare=False)
    bands: tuple[tuple[float, float], ...] = ()
    eta_intervals: int = 8
    groove_intervals: int = 3
    body_intervals: int = 8
    radial_size: float = 0.15
    band_intervals: int = 2
    end_lengths: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        if not (self.pitch > 0 and self.teeth >= 1):
            raise ValueError("pitch must be > 0 and teeth >= 1")
        if self.root_radius <= 0 or self.crest_radius <= 0 or self.crest_radius == self.root_radius:
            raise ValueError("root and crest radii must be positive and distinct")
        external = self.crest_radius > self.root_radius
        if external and self.far_radius != 0.0:
            raise ValueError("an external thread's body is a solid shaft: far_radius = 0")
        if not external and self.far_radius <= self.root_radius:
            raise ValueError("a nut's outer radius must exceed its thread root radius")
        lo, hi = sorted((self.root_radius, self.crest_radius))
        t = np.asarray(self.half_width(np.array([lo, hi])), dtype=np.float64)
        if not (np.all(t > 0) and np.all(2 * t < self.pitch)):
            raise ValueError("the tooth must have a positive width narrower than the pitch at root and crest")
        for rc, dr in self.bands:
            if not (lo < rc - dr and rc + dr < hi and dr > 0):
                raise ValueError(f"band at r = {rc} +- {dr} mm leaves the flank [{lo}, {hi}] mm")
        for name in ("eta_intervals", "groove_intervals", "body_intervals", "band_intervals"):
            if int(getattr(self, name)) < 1:
                raise ValueError(f"{name} must be >= 1")
        if len(self.end_lengths) != 2 or not all(e >= 0.0 for e in self.end_lengths):
            raise ValueError("end_lengths are two lengths >= 0 (mm)")

    @property
    def external(self) -> bool:
        """True for a screw or roller (teeth point outward)."""
        return self.crest_radius > self.root_radius


def _tooth_radial_grid(sec: ThreadSection, level: int) -> NDArray:
    """Radii of the tooth grid rows, root first: break points at band ends and centres."""
    r0, r1 = sec.root_radius, sec.crest_radius
    sgn = 1.0 if r1 > r0 else -1.0
    inner = []
    for rc, dr in sec.bands:
        inner += [rc - dr, rc, rc + dr]
    # distance from the root along the tooth height, sorted, duplicates merged
    dist = np.unique(np.round(np.abs(np.array(inner, dtype=np.float64) - r0), 12))
    breaks = np.concatenate([[0.0], dist, [abs(r1 - r0)]])
    is_band = np.zeros(len(breaks) - 1, dtype=bool)
    for rc, dr in sec.bands:
        lo, hi = sorted((abs(rc - dr - r0), abs(rc + dr - r0)))
        mid = 0.5 * (breaks[:-1] + breaks[1:])
        is_band |= (mid > lo) & (mid < hi)
    lengths = np.diff(breaks)
    counts = np.where(is_band, sec.band_intervals,
                      np.maximum(1, np.ceil(lengths / sec.radial_size))).astype(int)
    clusters = ["both"] * len(counts)
    clusters[0] = "start" if not is_band[0] else "both"  # the root corner is the singular end
    d = graded_line(breaks, counts, clusters, level)
    return r0 + sgn * d


def thread_section_mesh(sec: ThreadSection, level: int = 0) -> TriangleMesh:
    """The graded, conforming triangle mesh of a threaded section (module docstring).

    Node sets: ``"face_z0"``, ``"face_z1"``, ``"axis"`` (external threads) and
    ``"flank_<j>_upper"`` / ``"flank_<j>_lower"`` for j = 1..teeth, root to crest.
    """
    if level < 0:
        raise ValueError("level must be >= 0")
    p, k = sec.pitch, sec.teeth
    r_root = sec.root_radius
    t_root = float(np.asarray(sec.half_width(np.array([r_root])))[0])
    # one period's axial nodes relative to the tooth mid-plane: half groove, tooth base, half groove
    eta = graded_line(np.array([-1.0, 1.0]), np.array([sec.eta_intervals]), ["both"], level)
    left = segment_nodes(-0.5 * p, -t_root, sec.groove_intervals * 2 ** level, "end")
    right = segment_nodes(t_root, 0.5 * p, sec.groove_intervals * 2 ** level, "start")
    period = np.concatenate([left[:-1], eta * t_root, right[1:]])
    n_per = len(period) - 1
    base_start = len(left) - 1                   # index of eta = -1 within a period
    mids = (np.arange(k) + 0.5) * p
    z_axial = np.concatenate([(mids[:, None] + period[None, :-1]).ravel(), [k * p]])
    z_axial, first = _with_ends(z_axial, sec, level)

    # body grid: radial index 0 at the thread root, clustered there
    body_r = segment_nodes(r_root, sec.far_radius, sec.body_intervals * 2 ** level, "start")
    Rb, Zb = np.meshgrid(body_r, z_axial, indexing="ij")
    n_body = Rb.size
    body_idx = np.arange(n_body).reshape(Rb.shape)

    # tooth grids (k, ns + 1, ne + 1); row 0 is the body's root row
    radii = _tooth_radial_grid(sec, level)
    ne = len(eta) - 1
    ns = len(radii) - 1
    t_rows = np.asarray(sec.half_width(radii[1:]), dtype=np.float64)           # (ns,)
    Zt = mids[:, None, None] + eta[None, None, :] * t_rows[None, :, None]      # (k, ns, ne + 1)
    Rt = np.broadcast_to(radii[1:][None, :, None], Zt.shape)
    n_tooth_new = Zt.size
    tooth_idx = np.empty((k, ns + 1, ne + 1), dtype=np.int64)
    tooth_idx[:, 1:, :] = n_body + np.arange(n_tooth_new).reshape(k, ns, ne + 1)
    base_cols = first + (np.arange(k) * n_per + base_start)[:, None] + np.arange(ne + 1)[None, :]
    tooth_idx[:, 0, :] = body_idx[0][base_cols]

    points = np.concatenate([np.stack([Rb.ravel(), Zb.ravel()]),
                             np.stack([Rt.ravel(), Zt.ravel()])], axis=1)
    tri_body = _grid_triangles(body_idx)
    tri_teeth = _grid_triangles_stack(tooth_idx)
    t = _counter_clockwise(points, np.concatenate([tri_body, tri_teeth], axis=1))

    sets: dict[str, NDArray] = {"face_z0": body_idx[:, 0], "face_z1": body_idx[:, -1]}
    if sec.external:
        sets["axis"] = body_idx[-1, :]
    for j in range(k):
        sets[f"flank_{j + 1}_upper"] = tooth_idx[j, :, -1]
        sets[f"flank_{j + 1}_lower"] = tooth_idx[j, :, 0]
    return TriangleMesh(points, t, sets)


def _with_ends(z_axial: NDArray, sec: ThreadSection, level: int) -> tuple[NDArray, int]:
    """The axial nodes with the plain end pieces (``sec.end_lengths``) added, and the index
    of z = 0 in them. An end piece's intervals grow from the groove's size next to the thread
    (clustered toward it) to about half a pitch."""
    lo, hi = (float(e) for e in sec.end_lengths)
    parts, first = [z_axial], 0
    for length, side in ((lo, -1), (hi, 1)):
        if length <= 0.0:
            continue
        n = max(2, math.ceil(2.0 * length / sec.pitch)) * 2 ** level
        if side < 0:
            nodes = segment_nodes(-length, 0.0, n, "end")[:-1]
            parts.insert(0, nodes)
            first = nodes.size
        else:
            end = sec.teeth * sec.pitch
            parts.append(segment_nodes(end, end + length, n, "start")[1:])
    return np.concatenate(parts), first


def _grid_triangles_stack(index: NDArray) -> NDArray:
    """:func:`_grid_triangles` of a stack of equally shaped grids (k, ni + 1, nj + 1)."""
    a, b = index[:, :-1, :-1].ravel(), index[:, 1:, :-1].ravel()
    c, d = index[:, 1:, 1:].ravel(), index[:, :-1, 1:].ravel()
    return np.concatenate([np.stack([a, b, c]), np.stack([a, c, d])], axis=1)
