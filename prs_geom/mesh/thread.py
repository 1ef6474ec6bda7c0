"""Watertight triangle meshes of threaded parts, built from the analytic surfaces.

Construction (vectorised: no Python loop over vertices, faces, strands, teeth or turns;
the work per vertex and per triangle is a few numpy passes, see :func:`thread_mesh`):

* The thread surface is swept by *strands*: helices through fixed profile points (groove
  centre, root and crest corners, flank samples) of every start. Adjacent strands bound a
  *band*; the band between the last strand of a period and the first of the next lies on
  the root cylinder, which is where graded-pitch teeth take up their pitch change.
* Strands are sampled at global angular columns theta_i = i * 2 pi / N (N per turn) and
  at their exact crossings with the end planes. Where a band meets an end plane, extra
  vertices are placed on the analytic end curve at every column, so the end faces are
  exact planes whose edges contain the profile corner points (strand crossings) and follow
  the analytic end curve as closely as the body follows the surface.
* Each band is triangulated by merging its two boundary chains in theta; end faces are
  fans from the axis (external threads) or annuli to the body circle (nut). The nut's
  body circle also has a vertex at the angle of the top of every fall of the end polygon,
  so no edge from the circle to the polygon cuts across the deep notch a near-radial flank
  makes in the end curve (small flank angles, thin walls).
* :func:`thread_mesh` runs these as named steps: strands, column sampling, end points and
  end polygons, band chains, end faces (:func:`_end_faces`, the only step that closes the
  ends), then the vertex and face arrays.
* Thread run-outs (:func:`apply_run_outs`: the screw's grinding-wheel exit, the chamfers
  of roller and nut) and the angular datum mark (:func:`cut_datum_mark`) are manifold3d
  booleans on the finished mesh; the face kinds are carried through manifold3d's face ids.

Tessellation from the chordal tolerance ``tol`` (mm): half of it for the helix sagitta
r (1 - cos(dtheta / 2)) at the outermost radius, a quarter for the profile chord (the
roller arc), a quarter for the helicoid twist across a flank band; the nut's outer body
polygon, a separate surface, keeps its sagitta within ``tol``. The achieved error is
measured by :func:`measure_deviation` (exact distance in the axial half-plane, an upper
bound of the 3D distance), never assumed, and :func:`mesh_report` lists a warning for
every region that exceeds ``tol``.
These shares hold for every flank half-angle of the design rules (10-80 deg): measured
worst about 0.8 tol (roller, steep flanks), 0.5-0.6 tol on screw and nut.

Every vertex is computed on the analytic surface in float64.
"""
from __future__ import annotations

import math
import dataclasses
import functools
from dataclasses import dataclass, field
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from prs_geom.geometry.datum import DatumMark
from prs_geom.geometry.helix import PitchWarp, identity_warp
from prs_geom.geometry.profiles import ThreadProfile

__all__ = [
    "COLUMN_MARGIN", "DEVIATION_CHUNK_FACES", "EndPolygon", "FACE_BODY", "FACE_END_HI", "FACE_END_LO",
    "FACE_MARK", "FACE_RUN_OUT", "FACE_THREAD", "RUN_OUT_CREST_GAP_MM", "RUN_OUT_KINDS",
    "RUN_OUT_OVERSHOOT_MM", "RUN_OUT_ROOT_MARGIN_MM", "RunOut", "run_out_volume", "Tessellation", "ThreadMesh",
    "VOLUME_ACCURACY", "analytic_radius", "analytic_thread_volume", "apply_run_outs", "axial_line_crossings",
    "choose_tessellation", "cut_datum_mark", "deviation_warnings", "edge_flags", "flank_distance", "float32_rounding",
    "from_manifold", "manifold_status", "measure_deviation", "merge_strips", "mesh_report",
    "part_chord_tolerance", "profile_distance", "profile_strands", "run_out_distance", "thread_mesh",
    "to_manifold",
]

FACE_THREAD, FACE_END_LO, FACE_END_HI, FACE_BODY, FACE_MARK, FACE_RUN_OUT = 0, 1, 2, 3, 4, 5
#: Columns closer than this fraction of a column step to a strand end are dropped, so
#: that no sliver triangles appear next to the end planes.
COLUMN_MARGIN = 0.05


# --------------------------------------------------------------------------- sampling
@dataclass(frozen=True)
class Tessellation:
    """Angular and profile sampling chosen from a chordal tolerance."""

    columns_per_turn: int
    flank_radii: NDArray[np.float64]  # root corner .. crest corner, inclusive
    chord_tolerance: float

    @property
    def dtheta(self) -> float:
        return 2.0 * math.pi / self.columns_per_turn


#: Relative volume accuracy the part meshes keep besides the chord tolerance. Inscribed chords
#: of a thread of outer radius r take about tol / r of its volume away (measured at 0.01 mm:
#: roller, r = 4.3 mm, 0.23 %; screw 0.06 %; nut 0.05 %), so a small part is meshed at
#: ``VOLUME_ACCURACY * r`` when that is finer: its mesh volume stays within 0.1 % of the solid.
VOLUME_ACCURACY = 8e-4


def part_chord_tolerance(profile: ThreadProfile, tol: float) -> float:
    """The chord tolerance (mm) a part is meshed at: ``tol``, or finer for a small part (see
    :data:`VOLUME_ACCURACY`)."""
    return min(tol, VOLUME_ACCURACY * profile.outer_radius)


def choose_tessellation(profile: ThreadProfile, tol: float, body_radius: float | None = None) -> Tessellation:
    """Sampling that keeps every error term within its share of ``tol`` (mm)."""
    r_max = profile.outer_radius
    dtheta = 2.0 * math.acos(1.0 - 0.5 * tol / r_max)
    n_cols = max(12, int(math.ceil(2.0 * math.pi / dtheta)))
    dtheta = 2.0 * math.pi / n_cols
    r_root, r_crest = profile.root_radius, profile.crest_radius
    # helicoid twist across a flank band: ~ dr * dtheta * tan(lambda(r_in)) / 4 <= tol / 4
    tan_in = profile.lead / (2.0 * math.pi * profile.inner_radius)
    dr_twist = tol / (dtheta * tan_in)
    k = max(1, int(math.ceil(abs(r_crest - r_root) / dr_twist)))
    # profile chord: a quarter of the tolerance in the axial section, where the flank is
    # stretched by 1/cos(lambda)
    radii = profile.flank.sample_radii(r_root, r_crest, k, 0.25 * tol * profile.cos_lead)
    return Tessellation(columns_per_turn=n_cols, flank_radii=radii, chord_tolerance=tol)


def profile_strands(profile: ThreadProfile, tess: Tessellation) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Axial offsets u and radii r of the strands of one period, u increasing from the
    groove centre -p/2: root corner, lower flank, crest corners, upper flank, root corner."""
    rf = tess.flank_radii
    tf = profile.tooth_half_width(rf)
    u = np.concatenate([[-0.5 * profile.pitch], -tf, tf[::-1]])
    r = np.concatenate([[profile.root_radius], rf, rf[::-1]])
    return u, r


# --------------------------------------------------------------------------- result
@dataclass
class ThreadMesh:
    """A part mesh with the data needed to check it against its analytic surface.

    Vertices are in the part frame (z along the part axis); ``face_kind`` labels thread
    surface, lower/upper end faces, the nut's outer body cylinder, the walls and floor
    of the angular datum mark (``datum_mark``, :mod:`prs_geom.geometry.datum`) and the
    thread run-outs (``run_outs``, :func:`apply_run_outs`).
    """

    part: str
    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    face_kind: NDArray[np.int8]
    profile: ThreadProfile
    warp: PitchWarp
    first_mid: float
    z_lo: float
    z_hi: float
    chord_tolerance: float
    body_radius: float | None = None
    meta: dict[str, Any] = field(default_factory=dict)
    datum_mark: DatumMark | None = None
    run_outs: tuple[RunOut, ...] = ()

    def to_trimesh(self) -> trimesh.Trimesh:
        return trimesh.Trimesh(self.vertices, self.faces, process=False, validate=False)


# --------------------------------------------------------------------------- merging
def _merge_flat(A: NDArray[np.int64], ta: NDArray, na: NDArray[np.int64], B: NDArray[np.int64],
                tb: NDArray, nb: NDArray[np.int64]) -> NDArray[np.int64]:
    """:func:`merge_strips` on chains given concatenated, strip after strip, with the chain
    lengths ``na`` and ``nb`` per strip (a strip may have empty chains: no triangles)."""
    na, nb = np.asarray(na, np.int64), np.asarray(nb, np.int64)
    n_strips, n_a = len(na), len(A)
    a0, b0 = np.cumsum(na) - na, np.cumsum(nb) - nb
    ev_a, ev_b = np.maximum(na - 1, 0), np.maximum(nb - 1, 0)   # events: vertices after the first
    first = np.ones(len(A), bool)
    first[a0[na > 0]] = False
    ia = np.flatnonzero(first)
    first = np.ones(len(B), bool)
    first[b0[nb > 0]] = False
    ib = np.flatnonzero(first)
    strips = np.arange(n_strips)
    ev_strip = np.concatenate([np.repeat(strips, ev_a), np.repeat(strips, ev_b)])
    ev_theta = np.concatenate([ta[ia], tb[ib]])
    is_b = np.arange(len(ev_strip)) >= len(ia)
    # merged order: by strip, theta, A before B, chain order
    order = np.lexsort((is_b, ev_theta, ev_strip))
    s = ev_strip[order]
    is_b = is_b[order]
    g = np.concatenate([ia, ib])[order]                      # the event's index in A or B
    b_before = np.cumsum(is_b) - is_b - (np.cumsum(ev_b) - ev_b)[s]   # B events before, in the strip
    a_before = np.arange(len(s)) - (np.cumsum(ev_a + ev_b) - ev_a - ev_b)[s] - b_before
    # A event (chain index i): (A[i-1], A[i], current B); B event j: (current A, B[j], B[j-1])
    idx = np.empty((len(s), 3), np.int64)
    idx[:, 0] = np.where(is_b, a0[s] + a_before, g - 1)
    idx[:, 1] = np.where(is_b, n_a + g, g)
    idx[:, 2] = np.where(is_b, n_a + g - 1, n_a + b0[s] + b_before)
    return np.concatenate([A, B])[idx]


def merge_strips(a_ids: list[NDArray], a_th: list[NDArray], b_ids: list[NDArray],
                 b_th: list[NDArray]) -> NDArray[np.int64]:
    """Triangulate strips between chain pairs (A lower, B upper), both sorted by theta.

    For every strip the triangles are counter-clockwise in the (theta, u) plane with A
    below B; the strip starts at rung (A[0], B[0]) and ends at rung (A[-1], B[-1]).
    Events (chain vertices after the first) are taken in increasing theta, A before B
    at equal theta. Vectorised over all strips at once.
    """
    na = np.array([len(x) for x in a_ids])
    nb = np.array([len(x) for x in b_ids])
    return _merge_flat(np.concatenate(a_ids), np.concatenate(a_th), na,
                       np.concatenate(b_ids), np.concatenate(b_th), nb)


def _ranges(starts: NDArray[np.int64], counts: NDArray[np.int64]) -> tuple[NDArray, NDArray]:
    """Concatenated aranges: (values, owner index) for each (start, count)."""
    counts = np.maximum(counts, 0)
    owner = np.repeat(np.arange(len(starts)), counts)
    offs = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
    return starts[owner] + offs, owner


def _runs(starts: NDArray[np.int64], counts: NDArray[np.int64]) -> NDArray[np.int64]:
    """Concatenated aranges starting at ``starts`` (counts >= 0): a running sum of ones with
    a jump at every run start, in one array."""
    live = counts > 0
    s, c = starts[live], counts[live]
    out = np.ones(int(c.sum()), np.int64)
    if len(out):
        out[0] = s[0]
        out[(np.cumsum(c) - c)[1:]] = s[1:] - s[:-1] - c[:-1] + 1
        np.cumsum(out, out=out)
    return out


def _open_columns(lo: NDArray, hi: NDArray, dth: float) -> tuple[NDArray, NDArray]:
    """First and last column index strictly inside (lo, hi) with the sliver margin."""
    c0 = np.floor(lo / dth + COLUMN_MARGIN).astype(np.int64) + 1
    c1 = np.ceil(hi / dth - COLUMN_MARGIN).astype(np.int64) - 1
    return c0, c1


def _ring_angles(th_poly: NDArray, r_poly: NDArray, step_max: float) -> NDArray:
    """Angles in [0, 2 pi), increasing, of the nut's body circle at one end: uniform angles
    plus the angle of the top of every fall of the end polygon (the vertex after which its
    radius starts to decrease with theta). Uniform angles within the sliver margin of an
    added one are dropped; the uniform step leaves room for that, so no gap exceeds
    ``step_max`` (rad).

    Why: the annulus is merged in theta, so a circle vertex fans to the polygon vertices
    that follow it. Where the polygon falls steeply (a near-radial flank: small flank
    angles), a circle vertex behind the top of the fall sees the lower vertices after it
    only across the top, and the triangle covers the thread groove (up to 10x the tolerance
    on thin nuts). From a circle vertex at the top, a fall that is linear in theta (a
    straight flank at constant or gently graded pitch) and the crest after it are in view.
    """
    two_pi = 2.0 * math.pi
    n_o = max(12, int(math.ceil(two_pi * (1.0 + COLUMN_MARGIN) / step_max)))
    step = two_pi / n_o
    eps = 1e-9 * float(np.max(r_poly))
    falls = _rolled(r_poly, 1) < r_poly - eps           # the polygon is closed: one turn
    tops = falls & ~_rolled(falls, -1)
    t = np.sort(np.mod(th_poly[tops], two_pi))
    uni = step * np.arange(n_o)
    if len(t) == 0:
        return uni
    k = np.searchsorted(t, uni) % len(t)
    gap = np.minimum(np.abs((uni - t[k] + math.pi) % two_pi - math.pi),
                     np.abs((uni - t[k - 1] + math.pi) % two_pi - math.pi))
    return np.sort(np.concatenate([t, uni[gap > COLUMN_MARGIN * step]]))


def _rolled(x: NDArray, k: int) -> NDArray:
    """``np.roll(x, -k)``: element i is x[i + k], cyclically (a cheaper call)."""
    return np.concatenate([x[k:], x[:k]])


def _xyz(r: NDArray, th: NDArray, z) -> NDArray:
    return np.column_stack([r * np.cos(th), r * np.sin(th), np.broadcast_to(z, np.shape(th))])


def _closed(ids: NDArray, th: NDArray) -> tuple[NDArray, NDArray]:
    """A closed chain over one turn: its first vertex again at the end, one turn on."""
    return np.concatenate([ids, ids[:1]]), np.concatenate([th, th[:1] + 2.0 * math.pi])


def _body_rings(lower: EndPolygon, upper: EndPolygon, first_id: int, body_radius: float, tol: float,
                z_lo: float, z_hi: float) -> tuple[NDArray, list]:
    """The nut's body circles at z_lo and z_hi (vertex ids from ``first_id`` on) and the merge
    strips (A ids, A theta, B ids, B theta) of the two end annuli (end polygon below, circle
    above: normals -z) and of the body cylinder between the circles."""
    two_pi = 2.0 * math.pi
    # body polygon: no step wider than step_max, whose sagitta is tol
    step_max = 2.0 * math.acos(1.0 - tol / body_radius)
    strips, rings = [], []
    next_id = first_id
    for poly in (lower, upper):
        ang = _ring_angles(poly.theta, np.hypot(poly.points[:, 0], poly.points[:, 1]), step_max)
        rids = next_id + np.arange(len(ang))
        next_id += len(ang)
        rings.append((rids, ang))
        rel = (ang - poly.theta[0]) % two_pi            # circle vertices from the polygon start on
        order = np.argsort(rel, kind="stable")
        strips.append((*_closed(poly.ids, poly.theta), *_closed(rids[order], poly.theta[0] + rel[order])))
    # body cylinder between the two circles (their angles differ where the tops of the
    # falls were added); every triangle spans at most one circle step
    (lo_ids, lo_ang), (hi_ids, hi_ang) = rings
    strips.append((*_closed(lo_ids, lo_ang), *_closed(hi_ids, hi_ang)))
    ang = np.concatenate([lo_ang, hi_ang])
    circles = _xyz(body_radius, ang, np.repeat([z_lo, z_hi], [len(lo_ang), len(hi_ang)]))
    return circles, strips


# --------------------------------------------------------------------------- builder
@dataclass(frozen=True)
class _Strands:
    """The helices that sweep the thread surface, strand g = 0 .. count - 1: the profile
    points of :func:`profile_strands` for start 0, then for start 1, and so on.

    Per strand: ``radius`` (mm), ``offset`` u from its tooth mid-plane (mm), ``tooth_mid``
    (the helix coordinate of that mid-plane at theta = 0, mm) and ``theta_lo``,
    ``theta_hi``: the angles (rad, right-hand frame) where it meets z_lo and z_hi.
    """

    radius: NDArray[np.float64]
    offset: NDArray[np.float64]
    tooth_mid: NDArray[np.float64]
    theta_lo: NDArray[np.float64]
    theta_hi: NDArray[np.float64]

    @property
    def count(self) -> int:
        return len(self.radius)


def _strands(profile: ThreadProfile, tess: Tessellation, z_lo: float, z_hi: float, first_mid: float,
             warp: PitchWarp) -> _Strands:
    """The strands of ``profile`` and their end angles: strand g is the curve
    z = W(tooth_mid + L theta / 2 pi) + offset at radius r (W: the warp, L: the lead)."""
    u_period, r_period = profile_strands(profile, tess)
    per_period = len(u_period)
    strand = np.arange(profile.starts * per_period)
    point = strand % per_period
    offset, radius = u_period[point], r_period[point]
    tooth_mid = first_mid + (strand // per_period) * profile.pitch

    def theta_at(z_end: float) -> NDArray[np.float64]:
        return 2.0 * math.pi * (warp.inverse(z_end - offset) - tooth_mid) / profile.lead

    return _Strands(radius=radius, offset=offset, tooth_mid=tooth_mid, theta_lo=theta_at(z_lo),
                    theta_hi=theta_at(z_hi))


@dataclass(frozen=True)
class _Columns:
    """The angular sampling of the strands and of the end curves, and the vertex ids it sets.

    Band g lies between strand g and its ``partner`` strand g + 1; the last band's partner
    is strand 0 one turn on, so ``partner_theta_lo`` / ``partner_theta_hi`` (the partner's
    end angles in band g's parameter) are shifted by -2 pi there. Columns are the global
    angles k * ``dtheta`` strictly inside a range, with the sliver margin
    (:func:`_open_columns`): strand g has columns ``first[g]`` .. ``last[g]``
    (``count[g]`` >= 0 of them). End curve e (e < n: band e cut by z_lo; e >= n: band e - n
    cut by z_hi) runs from the partner's end point to strand g's and has columns
    ``end_first[e]`` on (``end_count[e]``); ``end_start[e]`` is the index of its first
    vertex among all end-curve vertices.

    Vertex ids: the strand columns (strand g's from ``vertex0[g]`` on), then the strand end
    points at z_lo, those at z_hi, the end-curve vertices at z_lo, those at z_hi.
    """

    dtheta: float
    partner: NDArray[np.int64]
    partner_theta_lo: NDArray[np.float64]
    partner_theta_hi: NDArray[np.float64]
    first: NDArray[np.int64]
    last: NDArray[np.int64]
    count: NDArray[np.int64]
    vertex0: NDArray[np.int64]
    end_first: NDArray[np.int64]
    end_count: NDArray[np.int64]
    end_start: NDArray[np.int64]

    @property
    def n_strands(self) -> int:
        return len(self.first)

    @property
    def n_column_vertices(self) -> int:
        return int(self.count.sum())

    def end_point_ids(self, upper: bool) -> NDArray[np.int64]:
        """Vertex ids of the strands' end points at z_lo (``upper`` False) or z_hi."""
        return self.n_column_vertices + (self.n_strands if upper else 0) + np.arange(self.n_strands)

    def end_curve_vertex0(self) -> NDArray[np.int64]:
        """Vertex id of every end curve's first vertex."""
        return self.n_column_vertices + 2 * self.n_strands + self.end_start


def _column_sampling(strands: _Strands, dtheta: float) -> _Columns:
    """The columns of every strand (between its end angles) and of every end curve."""
    n = strands.count
    partner = _rolled(np.arange(n), 1)
    wrap = np.zeros(n)
    wrap[-1] = -2.0 * math.pi
    partner_lo, partner_hi = strands.theta_lo[partner] + wrap, strands.theta_hi[partner] + wrap
    first, last = _open_columns(np.concatenate([strands.theta_lo, partner_lo, partner_hi]),
                                np.concatenate([strands.theta_hi, strands.theta_lo, strands.theta_hi]), dtheta)
    span = last[:n] - first[:n] + 1
    end_count = np.maximum(last[n:] - first[n:] + 1, 0)
    return _Columns(dtheta=dtheta, partner=partner, partner_theta_lo=partner_lo, partner_theta_hi=partner_hi,
                    first=first[:n], last=last[:n], count=np.maximum(span, 0), vertex0=np.cumsum(span) - span,
                    end_first=first[n:], end_count=end_count, end_start=np.cumsum(end_count) - end_count)


def _end_points(profile: ThreadProfile, strands: _Strands, cols: _Columns, warp: PitchWarp, z_lo: float,
                z_hi: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The vertices after the strand columns (right-hand frame, in id order, see
    :class:`_Columns`): the strand end points at z_lo and z_hi, then the end curves, each a
    point of the analytic end curve at every column; and the end-curve vertices' angles."""
    n = strands.count
    end_theta = _runs(cols.end_first, cols.end_count) * cols.dtheta
    helix = (np.repeat(np.concatenate([strands.tooth_mid, strands.tooth_mid]), cols.end_count)
             + profile.lead * end_theta / (2 * math.pi))
    n_lower = int(cols.end_start[n])
    z = np.repeat([z_lo, z_hi, z_lo, z_hi], [n, n, n_lower, len(end_theta) - n_lower])
    u = z[2 * n:] - warp(helix)
    points = _xyz(np.concatenate([strands.radius, strands.radius, profile.radius_at_offset(u)]),
                  np.concatenate([strands.theta_lo, strands.theta_hi, end_theta]), z)
    return points, end_theta


@dataclass(frozen=True)
class EndPolygon:
    """The cut of the thread surface by an end plane: a closed polygon over exactly one turn.

    ``ids`` (vertex ids), ``theta`` (rad, increasing, spanning less than 2 pi) and
    ``points`` ((n, 3) mm, right-hand part frame) of its vertices: band after band in
    decreasing band index, each the partner strand's end point then the band's end curve.
    """

    ids: NDArray[np.int64]
    theta: NDArray[np.float64]
    points: NDArray[np.float64]

    def __post_init__(self) -> None:
        if not len(self.ids) == len(self.theta) == len(self.points) or np.shape(self.points)[1:] != (3,):
            raise ValueError(f"an end polygon needs one theta and one (x, y, z) point per vertex id, got "
                             f"{len(self.ids)} ids, {len(self.theta)} angles, points {np.shape(self.points)}")


def _end_polygons(cols: _Columns, end_theta: NDArray[np.float64],
                  end_points: NDArray[np.float64]) -> tuple[EndPolygon, EndPolygon]:
    """The end polygons at z_lo and z_hi; ``end_points``, ``end_theta`` from :func:`_end_points`."""
    n = cols.n_strands
    n_cols = cols.n_column_vertices
    band = np.arange(n)[::-1]
    curve = np.concatenate([band, n + band])                 # end curves in polygon order
    cnt = cols.end_count[curve]
    lead_at = np.cumsum(cnt + 1) - cnt - 1                   # each curve's partner end point
    rest = _runs(lead_at + 1, cnt)
    idx = _runs(cols.end_start[curve], cnt)
    ids = np.empty(len(idx) + 2 * n, np.int64)
    theta = np.empty(len(idx) + 2 * n)
    ids[lead_at] = n_cols + (curve >= n) * n + cols.partner[curve % n]
    theta[lead_at] = np.concatenate([cols.partner_theta_lo, cols.partner_theta_hi])[curve]
    ids[rest] = n_cols + 2 * n + idx
    theta[rest] = end_theta[idx]
    n_lower = int(cols.end_start[n]) + n
    lower, upper = (ids[:n_lower], theta[:n_lower]), (ids[n_lower:], theta[n_lower:])
    return tuple(EndPolygon(ids=i, theta=t, points=end_points[i - n_cols]) for i, t in (lower, upper))


@dataclass(frozen=True)
class _BandMiddles:
    """Per band: the lengths of its chains A and B (:func:`thread_mesh` Notes), its partner
    strand's first column in the band's parameter, its regular middle (columns
    ``middle_first`` - 1 .. ``middle_first`` + ``middle_count`` - 1), and the chain indices
    of column ``middle_first`` - 1 in A and B (no middle: the last vertex of each chain)."""

    len_a: NDArray[np.int64]
    len_b: NDArray[np.int64]
    partner_first: NDArray[np.int64]
    middle_first: NDArray[np.int64]
    middle_count: NDArray[np.int64]
    a_at_middle: NDArray[np.int64]
    b_at_middle: NDArray[np.int64]


def _band_middles(cols: _Columns, columns_per_turn: int) -> _BandMiddles:
    """The chain lengths and regular middles of every band."""
    n_lower_curve = cols.end_count[:cols.n_strands]
    len_a = n_lower_curve + cols.count + 3
    len_b = cols.count[cols.partner] + 1 + cols.end_count[cols.n_strands:]
    partner_first, partner_last = cols.first[cols.partner], cols.last[cols.partner]
    partner_first[-1] -= columns_per_turn
    partner_last[-1] -= columns_per_turn
    middle_first = np.maximum(cols.first, partner_first) + 1
    middle_count = np.maximum(np.minimum(cols.last, partner_last) - middle_first + 1, 0)
    has_middle = middle_count > 0
    # A: after the partner's end point at z_lo, the lower end curve and strand g's end point
    a_at_middle = np.where(has_middle, n_lower_curve + 2 + (middle_first - 1 - cols.first), len_a - 1)
    b_at_middle = np.where(has_middle, middle_first - 1 - partner_first, len_b - 1)
    return _BandMiddles(len_a=len_a, len_b=len_b, partner_first=partner_first, middle_first=middle_first,
                        middle_count=middle_count, a_at_middle=a_at_middle, b_at_middle=b_at_middle)


def _piece_lengths(mid: _BandMiddles, chain_len: NDArray[np.int64],
                   at_middle: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Lengths of a chain's pieces outside the middles (strip 2 g: the prefix up to column
    ``middle_first`` - 1, strip 2 g + 1: the suffix from the middle's last column on, empty
    without a middle) and the chain index each piece starts at."""
    after = at_middle + mid.middle_count
    length = np.column_stack([at_middle + 1, np.where(mid.middle_count > 0, chain_len - after, 0)]).ravel()
    start = np.column_stack([np.zeros_like(after), after]).ravel()
    return length, start


def _chain_a_pieces(strands: _Strands, cols: _Columns,
                    mid: _BandMiddles) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.int64]]:
    """Vertex ids, angles and piece lengths of chain A's pieces: partner end point at z_lo |
    lower end curve | strand g's end point at z_lo | strand g's columns | its end point at z_hi."""
    n = cols.n_strands
    length, start = _piece_lengths(mid, mid.len_a, mid.a_at_middle)
    i, owner = _ranges(start, length)
    band = owner >> 1
    n_curve = cols.end_count[:n]
    curve_len = n_curve[band]
    segment = ((i > 0).astype(np.int64) + (i > curve_len) + (i > curve_len + 1)
               + (i > curve_len + 1 + cols.count[band]))
    key = segment * n + band
    lo_ids, hi_ids = cols.end_point_ids(False), cols.end_point_ids(True)
    zero = np.zeros(n, np.int64)
    ids = np.concatenate([lo_ids[cols.partner], cols.end_curve_vertex0()[:n] - 1, lo_ids,
                          cols.vertex0 - n_curve - 2, hi_ids])[key]
    col = np.concatenate([zero, cols.end_first[:n] - 1, zero, cols.first - n_curve - 2, zero])[key] + i
    ranged = (segment == 1) | (segment == 3)
    ids[ranged] += i[ranged]
    theta = np.where(ranged, col * cols.dtheta,
                     np.concatenate([cols.partner_theta_lo, strands.theta_lo, strands.theta_lo, strands.theta_lo,
                                     strands.theta_hi])[key])
    return ids, theta, length


def _chain_b_pieces(cols: _Columns,
                    mid: _BandMiddles) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.int64]]:
    """Vertex ids, angles and piece lengths of chain B's pieces: the partner's columns |
    its end point at z_hi | upper end curve."""
    n = cols.n_strands
    length, start = _piece_lengths(mid, mid.len_b, mid.b_at_middle)
    j, owner = _ranges(start, length)
    band = owner >> 1
    partner_count = cols.count[cols.partner]
    columns_len = partner_count[band]
    segment = (j >= columns_len).astype(np.int64) + (j > columns_len)
    key = segment * n + band
    ids = np.concatenate([cols.vertex0[cols.partner], cols.end_point_ids(True)[cols.partner],
                          cols.end_curve_vertex0()[n:] - partner_count - 1])[key]
    col = np.concatenate([mid.partner_first, np.zeros(n, np.int64),
                          cols.end_first[n:] - partner_count - 1])[key] + j
    ranged = segment != 1
    ids[ranged] += j[ranged]
    theta = np.where(ranged, col * cols.dtheta, cols.partner_theta_hi[band])
    return ids, theta, length


@dataclass(frozen=True)
class _Bands:
    """The triangle rows of the thread bands (:func:`thread_mesh` Notes).

    Band g owns rows ``row0[g]`` .. ``row0[g] + rows[g] - 1`` (all bands: one block from
    row 0); its regular middle starts at row ``middle_row0[g]`` with the quad on strand
    columns ``middle_a[g]``, ``middle_b[g]`` (:func:`_band_rows`). ``irregular_rows`` are
    the other rows, in the order :func:`_merge_flat` emits the triangles of the chain
    pieces ``a_*``, ``b_*`` (strip 2 g: band g's prefixes, 2 g + 1: its suffixes).
    """

    row0: NDArray[np.int64]
    rows: NDArray[np.int64]
    middle_row0: NDArray[np.int64]
    middle_a: NDArray[np.int64]
    middle_b: NDArray[np.int64]
    irregular_rows: NDArray[np.int64]
    a_ids: NDArray[np.int64]
    a_theta: NDArray[np.float64]
    a_len: NDArray[np.int64]
    b_ids: NDArray[np.int64]
    b_theta: NDArray[np.float64]
    b_len: NDArray[np.int64]

    @property
    def n_rows(self) -> int:
        return int(self.rows.sum())

    def irregular_triangles(self) -> NDArray[np.int64]:
        """The triangles of ``irregular_rows`` (right-hand winding as merged)."""
        return _merge_flat(self.a_ids, self.a_theta, self.a_len, self.b_ids, self.b_theta, self.b_len)


def _band_chains(strands: _Strands, cols: _Columns, columns_per_turn: int) -> _Bands:
    """Every band's chains joined into triangle rows: the regular middles written
    arithmetically, the pieces next to the end planes to be merged."""
    mid = _band_middles(cols, columns_per_turn)
    a_ids, a_theta, a_len = _chain_a_pieces(strands, cols, mid)
    b_ids, b_theta, b_len = _chain_b_pieces(cols, mid)
    rows = mid.len_a + mid.len_b - 2
    row0 = np.cumsum(rows) - rows
    n_prefix = mid.a_at_middle + mid.b_at_middle
    n_suffix = rows - n_prefix - 2 * mid.middle_count
    irregular = _runs(np.column_stack([row0, row0 + n_prefix + 2 * mid.middle_count]).ravel(),
                      np.column_stack([n_prefix, n_suffix]).ravel())
    middle_a = cols.vertex0 + mid.middle_first - 1 - cols.first               # strand g's column before the middle
    middle_b = cols.vertex0[cols.partner] + mid.middle_first - 1 - mid.partner_first
    return _Bands(row0=row0, rows=rows, middle_row0=row0 + n_prefix, middle_a=middle_a, middle_b=middle_b,
                  irregular_rows=irregular, a_ids=a_ids, a_theta=a_theta, a_len=a_len, b_ids=b_ids,
                  b_theta=b_theta, b_len=b_len)


def _end_faces(lower: EndPolygon, upper: EndPolygon, first_id: int, z_lo: float, z_hi: float,
               body_radius: float | None, tol: float) -> tuple[NDArray[np.float64], list[tuple[NDArray, int]]]:
    """Close the thread surface at the end planes z = z_lo and z = z_hi.

    Parameters
    ----------
    lower, upper : EndPolygon
        The thread surface's cuts by z_lo and z_hi (right-hand frame); their edges are
        edges of the thread surface, so the end faces must use exactly these edges.
    first_id : int
        The id of the first vertex this function adds.
    z_lo, z_hi : float
        The end planes (mm).
    body_radius : float or None
        None for an external thread (screw, roller): each end face is a fan from a vertex
        on the axis. Else (nut) the outer body radius (mm): each end face is the annulus
        between the polygon and a body circle, and the body cylinder joins the circles,
        its polygon within ``tol`` (mm) of the cylinder.

    Returns
    -------
    vertices : NDArray
        (k, 3) the added vertices (mm, right-hand part frame), ids ``first_id`` on.
    faces : list of (NDArray, int)
        (m, 3) vertex-id triangles with their face kind: FACE_END_LO (normals -z),
        FACE_END_HI (normals +z) and, for the nut, FACE_BODY (normals outward), wound
        for those normals in the right-hand frame.
    """
    if body_radius is None:
        fans = []
        for poly, centre in ((lower, first_id), (upper, first_id + 1)):   # axis points at z_lo, z_hi
            nxt = _rolled(poly.ids, 1)
            fan = np.empty((len(poly.ids), 3), np.int64)
            fan[:, 0] = centre
            fan[:, 1], fan[:, 2] = (nxt, poly.ids) if poly is lower else (poly.ids, nxt)
            fans.append(fan)
        return np.array([[0.0, 0.0, z_lo], [0.0, 0.0, z_hi]]), [(fans[0], FACE_END_LO), (fans[1], FACE_END_HI)]
    circles, strips = _body_rings(lower, upper, first_id, body_radius, tol, z_lo, z_hi)
    tri = merge_strips(*(list(x) for x in zip(*strips)))
    at = np.cumsum([0] + [len(a) + len(b) - 2 for a, _, b, _ in strips])
    return circles, [(tri[at[0]:at[1]], FACE_END_LO), (tri[at[1]:at[2], [0, 2, 1]], FACE_END_HI),
                     (tri[at[2]:], FACE_BODY)]


def thread_mesh(profile: ThreadProfile, z_lo: float, z_hi: float, tol: float,
                first_mid: float = 0.0, warp: PitchWarp | None = None,
                body_radius: float | None = None) -> ThreadMesh:
    """Mesh of a threaded part between the planes z = z_lo and z = z_hi (part frame).

    Parameters
    ----------
    profile : ThreadProfile
        The part's profile (hand from ``profile.hand_sign``).
    z_lo, z_hi : float
        End planes (mm).
    tol : float
        Chordal tolerance (mm).
    first_mid : float
        m0: helix coordinate (mm) of a tooth mid-plane of start 0 at theta = 0.
    warp : PitchWarp, optional
        Graded-pitch warp acting on the helix coordinate; identity when omitted.
    body_radius : float, optional
        Outer body radius of an internal thread (nut); required when ``profile.internal``.

    Returns
    -------
    ThreadMesh
        Closed, consistently wound (outward normals) triangle mesh.

    Notes
    -----
    Vectorised over strands, teeth and turns (no Python loop over any of them): the bulk is
    a few numpy passes over the strand column vertices and over the band triangles, and
    the arrays are bit for bit those of merging every band's full chains.

    * Strand column vertices: the cosine, sine and helix advance of a column depend on its
      index only, so they are evaluated once per column (tables over the column range) and
      gathered per strand; every value is the float64 result of the same operations as
      evaluating it per vertex (theta = column * dtheta).
    * Band triangles: band g merges chain A (the partner strand h = g + 1's end point at
      z_lo, the end curve at z_lo, strand g's end point, its columns, its end point at z_hi)
      with chain B (strand h's columns, its end point at z_hi, the end curve at z_hi) in
      theta, A first at equal theta. Within each chain the events (vertices after the
      first) increase in theta: the columns keep the sliver margin from the end points of
      their own strand and end curve. So where both strands have columns k - 1 .. k_last
      (the middle, from k_first = max(first columns) + 1), the merge takes A_k, B_k,
      A_k+1, ... (equal thetas k * dtheta, A first) and emits the quads (a_k-1, a_k, b_k,
      b_k-1) as two triangles each: written arithmetically (:func:`_band_rows`). The chain
      pieces before and after the middle (about one turn of columns over all bands, next
      to the end planes) are merged in one vectorised call.
    * End faces: :func:`_end_faces` closes the end polygons.
    """
    warp = warp or identity_warp(profile.pitch)
    if profile.internal and body_radius is None:
        raise ValueError("an internal thread needs body_radius")
    tess = choose_tessellation(profile, tol)
    strands = _strands(profile, tess, z_lo, z_hi, first_mid, warp)
    cols = _column_sampling(strands, tess.dtheta)
    end_points, end_theta = _end_points(profile, strands, cols, warp, z_lo, z_hi)
    lower, upper = _end_polygons(cols, end_theta, end_points)
    bands = _band_chains(strands, cols, tess.columns_per_turn)
    added, end_faces = _end_faces(lower, upper, cols.n_column_vertices + len(end_points), z_lo, z_hi,
                                  body_radius if profile.internal else None, tol)
    left = profile.hand_sign < 0
    vertices = _vertices(profile, strands, cols, warp, np.concatenate([end_points, added]), left)
    faces, kind = _faces(bands, end_faces, flip_thread=bool(profile.internal) != left, left=left)
    return ThreadMesh(part=profile.part, vertices=vertices, faces=faces, face_kind=kind, profile=profile,
                      warp=warp, first_mid=first_mid, z_lo=z_lo, z_hi=z_hi, chord_tolerance=tol,
                      body_radius=body_radius,
                      meta={"columns_per_turn": tess.columns_per_turn, "strands": strands.count,
                            "flank_segments": len(tess.flank_radii) - 1})


def _vertices(profile: ThreadProfile, strands: _Strands, cols: _Columns, warp: PitchWarp,
              after_columns: NDArray[np.float64], left: bool) -> NDArray[np.float64]:
    """All vertices in the part's hand: the strand columns (bulk), then ``after_columns``
    (right-hand frame), y negated for a left hand."""
    n_cols = cols.n_column_vertices
    vertices = np.empty((n_cols + len(after_columns), 3))
    tail = vertices[n_cols:]
    tail[:] = after_columns
    if left:
        tail *= np.array([1.0, -1.0, 1.0])
    if n_cols:
        _strand_column_vertices(vertices[:n_cols], strands, cols, profile.lead, warp, left)
    return vertices


def _faces(bands: _Bands, end_faces: list[tuple[NDArray, int]], flip_thread: bool,
           left: bool) -> tuple[NDArray[np.int64], NDArray[np.int8]]:
    """Faces and face kinds in the part's hand: the thread bands (bulk, reversed when
    ``flip_thread``: the nut's material is outside), then the end faces (reversed for a
    left hand)."""
    n_rows = bands.n_rows
    n_end_faces = sum(len(f) for f, _ in end_faces)
    faces = np.empty((n_rows + n_end_faces, 3), np.int64)
    kind = np.empty(n_rows + n_end_faces, np.int8)
    kind[:n_rows] = FACE_THREAD
    _band_rows(faces, bands.row0, bands.rows, bands.middle_row0, bands.middle_a, bands.middle_b, flip_thread)
    irregular = bands.irregular_triangles()
    faces[bands.irregular_rows] = irregular[:, [0, 2, 1]] if flip_thread else irregular
    row = n_rows
    for f, face_kind in end_faces:
        faces[row:row + len(f)] = f[:, [0, 2, 1]] if left else f
        kind[row:row + len(f)] = face_kind
        row += len(f)
    return faces, kind


def _strand_column_vertices(out: NDArray, strands: _Strands, cols: _Columns, lead: float, warp: PitchWarp,
                            left: bool) -> None:
    """Vertices of strand g at columns ``cols.first[g]`` on (``cols.count[g]``), strand after
    strand, into ``out``: (r cos theta, r sin theta, W(tooth_mid + L theta / 2 pi) + u) at
    theta = column * dtheta, y negated for a left hand.

    cos, sin and the helix advance L theta / 2 pi depend on the column only: they are
    tabulated over the column range and gathered (the same float64 values as computing
    them per vertex). Few and reused temporaries: memory traffic is what this costs."""
    first, count = cols.first, cols.count
    live = count > 0
    cmin = int(first[live].min())
    cmax = int((first + count - 1)[live].max())
    th_tab = np.arange(cmin, cmax + 1) * cols.dtheta
    col = _runs(first - cmin, count)              # column index into the tables, per vertex
    x, y, z = out[:, 0], out[:, 1], out[:, 2]
    r = np.repeat(strands.radius, count)
    buf = np.take(np.cos(th_tab), col, mode="clip")   # in range; "clip" only skips a buffer
    np.multiply(r, buf, out=x)
    np.take(np.sin(th_tab), col, out=buf, mode="clip")
    np.multiply(r, buf, out=y)
    if left:
        np.negative(y, out=y)                     # (r sin) * -1, bit for bit
    del r
    np.take(lead * th_tab / (2 * math.pi), col, out=buf, mode="clip")
    del col
    m = np.add(np.repeat(strands.tooth_mid, count), buf, out=buf)
    if isinstance(warp, PitchWarp) and warp.is_identity:
        # W(m) + u = (m + 0.0) + u, bit for bit m + (u + 0.0)
        np.add(m, np.repeat(strands.offset + 0.0, count), out=z)
    else:
        np.add(warp(m), np.repeat(strands.offset, count), out=z)


def _band_rows(faces: NDArray[np.int64], row0: NDArray, n_rows: NDArray, first: NDArray, a: NDArray,
               b: NDArray, flip: bool) -> None:
    """Write the regular middle pattern of every band into the rows of ``faces`` its band covers.

    Band g owns rows row0[g] .. row0[g] + n_rows[g] - 1 (all bands together: a contiguous
    block from row 0); its middle starts at row first[g] and is a run of quads t = 0, 1, ...:
    row first + 2 t = (a + t, a + t + 1, b + t), row first + 2 t + 1 = (a + t + 1, b + t + 1,
    b + t), with a = a[g], b = b[g] (columns 1 and 2 swapped if ``flip``). The other rows of
    the block get values the caller must overwrite: those of a band outside its middle, and
    a last odd row.

    Every value is r // 2 + a constant of its band, column and row parity (r: the row), so
    the row pairs (2 s, 2 s + 1) of band g, g the band of row 2 s, are s + one 6-vector of
    band g. Read as one flat array, that is a running sum whose steps repeat with period 6
    within a band: the steps are gathered into the face array and summed in place. A pair
    across two bands is wrong in its second row, the first row of the next band; that row
    is never in a middle (a band's chains start with at least two events before it).
    """
    n_pairs = int(n_rows.sum()) // 2
    if n_pairs == 0:
        return
    off = np.empty((len(a), 2, 3), np.int64)       # band, row parity, column
    c1, c2 = (2, 1) if flip else (1, 2)
    for v in (0, 1):
        par = (v + first) & 1                       # parity of (row - first) in these rows
        d = (v - first - par) // 2                  # quad t = r // 2 + d
        off[:, v, 0] = a + d + par
        off[:, v, c1] = np.where(par == 1, b + d + 1, a + d + 1)
        off[:, v, c2] = b + d
    s0 = np.minimum((row0 + 1) // 2, n_pairs)       # pairs whose first row is in band g
    cnt = np.minimum((row0 + n_rows + 1) // 2, n_pairs) - s0
    live = cnt > 0
    off, cnt = off.reshape(-1, 6)[live], cnt[live]
    step = np.empty_like(off)
    step[:, 0] = off[:, 0] + 1 - off[:, 5]
    step[:, 1:] = np.diff(off, axis=1)
    pairs = faces[:2 * n_pairs].reshape(n_pairs, 6)
    np.take(step, np.repeat(np.arange(len(cnt)), cnt), axis=0, out=pairs, mode="clip")
    pairs[(np.cumsum(cnt) - cnt)[1:], 0] = off[1:, 0] + 1 - off[:-1, 5]
    pairs[0, 0] = off[0, 0]
    flat = pairs.reshape(-1)
    np.cumsum(flat, out=flat)


def _boolean_keeping_kinds(tm: ThreadMesh, tools: Sequence[tuple[str, Callable[[], Any], int]],
                           what: str) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int8]]:
    """Vertices, faces and face kinds of ``tm`` with the ``tools`` (operation "add" or
    "subtract", a function building the manifold3d solid in the part frame, face kind)
    applied in order, in one manifold3d pass (float64; building the part's solid is most
    of its cost). The tools are built after the part: manifold3d numbers its inputs in
    the order they are built and orders the output's triangles by that number.

    manifold3d keeps every vertex of ``tm`` that no tool touches bit for bit and tells for
    each output triangle the input it came from (its run's original id) and its face id
    there: the faces of ``tm`` keep their kind, each tool's faces get the tool's kind.
    ``what`` names the operation in the error message.
    """
    import manifold3d

    n_faces = len(tm.faces)
    part = manifold3d.Manifold(manifold3d.Mesh64(
        np.ascontiguousarray(tm.vertices, dtype=np.float64), np.ascontiguousarray(tm.faces, dtype=np.uint64),
        face_id=np.arange(n_faces, dtype=np.uint64)))
    part_id = int(np.asarray(part.to_mesh64().run_original_id)[0])   # the id manifold3d gave the input
    solid, tool_kind = part, {}
    for op, build, face_kind in tools:
        tool = build()
        solid = solid + tool if op == "add" else solid - tool
        if len(tools) > 1:   # a tool may be a union of originals: each of its ids
            tool_kind.update(dict.fromkeys(np.asarray(tool.to_mesh64().run_original_id).tolist(), face_kind))
    if solid.status() != manifold3d.Error.NoError:   # pragma: no cover - manifold3d refuses only broken input
        raise RuntimeError(f"{what} of the {tm.part} failed: {solid.status()}")
    out = solid.to_mesh64()
    V = np.array(np.asarray(out.vert_properties)[:, :3], dtype=np.float64, order="C")  # writable copy
    F = np.array(out.tri_verts, dtype=np.int64, order="C")
    # triangles are grouped in runs, one per input manifold; face ids index into that input
    run_index = np.asarray(out.run_index, dtype=np.int64)
    run_of_face = np.searchsorted(run_index[1:], np.arange(len(F)) * 3, side="right")
    run_ids = np.asarray(out.run_original_id)
    run_kind = np.array([tool_kind.get(i, tools[-1][2]) for i in run_ids.tolist()], np.int8)  # one per run
    from_part = run_ids[run_of_face] == part_id
    kind = run_kind[run_of_face]
    kind[from_part] = tm.face_kind[np.asarray(out.face_id, dtype=np.int64)[from_part]]
    return V, F, kind


def cut_datum_mark(tm: ThreadMesh, mark: DatumMark) -> ThreadMesh:
    """``tm`` with the angular datum slot ``mark`` cut out of its face A (manifold3d, float64).

    The boolean keeps every vertex of ``tm`` bit for bit (it only adds the vertices where
    the slot meets face A and the slot's own corners) and carries each face's kind over
    through manifold3d's face ids; the slot's walls and floor get ``FACE_MARK``. The slot
    is symmetric about y = 0, so it is the same on right- and left-hand parts.
    """
    V, F, kind = _boolean_keeping_kinds(tm, [("subtract", lambda: _datum_slot(mark), FACE_MARK)], "datum mark cut")
    return dataclasses.replace(tm, vertices=V, faces=F, face_kind=kind, meta=dict(tm.meta), datum_mark=mark)


def _datum_slot(mark: DatumMark) -> Any:
    """The manifold3d box of the datum slot, reaching 1 mm out of face A."""
    import manifold3d

    (x0, y0, z0), (x1, y1, z1) = mark.box(overshoot=1.0)
    return manifold3d.Manifold.cube([x1 - x0, y1 - y0, z1 - z0]).translate([x0, y0, z0])


# --------------------------------------------------------------------------- run-outs
#: The wheel exit's frustum ends this far (mm) below the crest radius at the end plane. A
#: cone meeting the crest cylinder exactly would make coincident surfaces whose two
#: samplings differ by nanometres, which an STL cannot tell from one vertex; 5 um keeps the
#: surfaces apart (by at least that much, see :func:`_run_out_segments`) and is far below
#: any grinding tolerance.
RUN_OUT_CREST_GAP_MM = 0.005
#: The frustum's inner end lies this far (mm) below the root radius, so that its inner base
#: is buried in the core and the root rises from the full groove depth.
RUN_OUT_ROOT_MARGIN_MM = 0.02
#: The chamfer tools reach this far (mm) out of the end plane and beyond the crest, so that
#: no face of a tool lies in a face of the part.
RUN_OUT_OVERSHOOT_MM = 1.0
#: The run-out kinds of :class:`RunOut`.
RUN_OUT_KINDS = ("wheel-exit", "chamfer")


@dataclass(frozen=True)
class RunOut:
    """A thread run-out at one end plane of a part (applied by :func:`apply_run_outs`).

    Attributes
    ----------
    end : str
        "lo" or "hi": the end plane z_lo or z_hi of the part (part frame, z along the axis).
    kind : str
        "wheel-exit": an external thread running out into free shaft (the screw): over the
        last ``length_mm`` before the end plane the groove's root rises linearly from the
        root radius to the crest radius (the grinding wheel leaving the groove); the flanks
        are unchanged (the real wheel exit also narrows the groove: left out).
        "chamfer": a thread running into a shoulder (roller gear faces, nut ring-gear seats):
        a 45 degree chamfer of the crest, from the crest ``length_mm`` inside the end plane
        to ``length_mm`` below the crest (external; above it, internal) in the end plane.
        ``length_mm`` = |crest - pitch radius| chamfers down to the pitch radius.
    length_mm : float
        Axial length (mm): the wheel exit's length, or the chamfer's axial size.
    """

    end: str
    kind: str
    length_mm: float

    def __post_init__(self) -> None:
        if self.end not in ("lo", "hi"):
            raise ValueError(f"RunOut.end = {self.end!r}: must be 'lo' or 'hi' (the end plane z_lo or z_hi)")
        if self.kind not in RUN_OUT_KINDS:
            raise ValueError(f"RunOut.kind = {self.kind!r}: must be one of {RUN_OUT_KINDS}")
        if not (math.isfinite(self.length_mm) and self.length_mm > 0.0):
            raise ValueError(f"RunOut.length_mm = {self.length_mm!r}: must be a finite length > 0 mm")


def run_out_volume(profile: ThreadProfile, run_out: RunOut) -> float:
    """Volume (mm^3) a run-out adds to a constant-pitch part (negative: removes), from the
    profile alone.

    Around the axis at radius r the material fills the fraction f(r) = 2 t(r) / p of every
    axial pitch (t the tooth half-width, :meth:`ThreadProfile.tooth_half_width`; for a
    helix the same fraction of every circle), so a solid of revolution that covers the
    axial length l(r) at radius r changes the volume by the integral of 2 pi r l(r) (1 - f)
    dr (filled grooves) or of 2 pi r l(r) f dr (cut teeth). l(r) is linear in r for both
    tools (:class:`RunOut`): the frustum from the root (less its margin) at the inner end
    to the crest less :data:`RUN_OUT_CREST_GAP_MM` at the end plane, and the 45 degree
    chamfer. Both radial ranges lie between the root and the crest, on the flank, where f is
    smooth: 64-point Gauss-Legendre quadrature gives it to about 1e-12 relative (the same
    with 128 points).
    """
    rc, rr = profile.crest_radius, profile.root_radius
    L = run_out.length_mm
    if run_out.kind == "wheel-exit":
        r_end, r_in = rc - RUN_OUT_CREST_GAP_MM, rr - RUN_OUT_ROOT_MARGIN_MM
        lo, hi = rr, r_end                       # below the root the groove fraction is 0
        length = lambda r: L * (r_end - r) / (r_end - r_in)
        weight = lambda r: 1.0 - 2.0 * profile.tooth_half_width(r) / profile.pitch
        sign = 1.0
    else:
        r_e = rc + (L if profile.internal else -L)
        lo, hi = (rc, r_e) if profile.internal else (r_e, rc)
        length = (lambda r: r_e - r) if profile.internal else (lambda r: r - r_e)
        weight = lambda r: 2.0 * profile.tooth_half_width(r) / profile.pitch
        sign = -1.0
    x, w = np.polynomial.legendre.leggauss(64)
    a, b = min(lo, hi), max(lo, hi)
    r = 0.5 * (b - a) * x + 0.5 * (b + a)
    return sign * float(np.sum(0.5 * (b - a) * w * 2.0 * math.pi * r * length(r) * weight(r)))


def _check_run_outs(profile: ThreadProfile, run_outs: Sequence[RunOut], part_length: float) -> None:
    """Raise ValueError (field, value, rule) for run-outs ``profile`` cannot take on a part of
    axial length ``part_length`` (mm)."""
    ends = [ro.end for ro in run_outs]
    if len(set(ends)) != len(ends):
        raise ValueError(f"RunOut.end: {ends} names an end twice; a part takes one run-out per end")
    chamfer_max = abs(profile.crest_radius - profile.pitch_radius)
    for ro in run_outs:
        if not ro.length_mm < 0.5 * part_length:
            raise ValueError(f"RunOut.length_mm = {ro.length_mm!r} at end {ro.end!r}: must be below half the "
                             f"{profile.part}'s thread length {part_length:g} mm")
        if ro.kind == "wheel-exit" and profile.internal:
            raise ValueError(f"RunOut.kind = 'wheel-exit' on the {profile.part}: a grinding-wheel exit needs "
                             "an external thread")
        if ro.kind == "chamfer" and ro.length_mm > chamfer_max * (1.0 + 1e-9):
            raise ValueError(f"RunOut.length_mm = {ro.length_mm!r} (chamfer at end {ro.end!r}): must not exceed "
                             f"|crest - pitch radius| = {chamfer_max:g} mm of the {profile.part}; a deeper "
                             "chamfer reaches the flank contacts near the pitch radius")


def _end_plane(tm: ThreadMesh, ro: RunOut) -> tuple[float, float]:
    """The end plane z (mm) of ``ro`` and its outward sign s: the axial depth into the part
    of a point at z is d = s (z_end - z)."""
    return (tm.z_hi, 1.0) if ro.end == "hi" else (tm.z_lo, -1.0)


def _run_out_outline(tm: ThreadMesh, ro: RunOut) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The run-out of ``tm`` in the axial half-plane, in (r, d) coordinates (mm; d: the axial
    depth from the end plane into the part, :func:`_end_plane`).

    Returns the tool polygon (m, 2) to revolve (added for a wheel exit, removed for a
    chamfer) and the segments (k, 2, 2) of the tool's surface that can be faces of the
    result: the analytic run-out surface :func:`measure_deviation` checks against.
    The wheel exit's frustum is clipped to the piece ``tm`` (a window may end inside it).
    """
    prof = tm.profile
    rc, L = prof.crest_radius, ro.length_mm
    o = RUN_OUT_OVERSHOOT_MM
    if ro.kind == "wheel-exit":
        r_end, r_in = rc - RUN_OUT_CREST_GAP_MM, prof.root_radius - RUN_OUT_ROOT_MARGIN_MM
        d_far = min(L, tm.z_hi - tm.z_lo)
        r_far = r_end + (r_in - r_end) * d_far / L
        poly = np.array([[0.0, 0.0], [r_end, 0.0], [r_far, d_far], [0.0, d_far]])
        # the far base is buried in the core unless a window clips the frustum
        return poly, np.stack([poly[:3], poly[1:4]], axis=1)[: 3 if d_far < L else 2]
    segment = np.array([[[rc + (L if prof.internal else -L), 0.0], [rc, L]]])
    r_e = float(segment[0, 0, 0])
    if prof.internal:   # countersink: r < r_e - d, inside the bore, short of the body
        o = min(o, 0.5 * (tm.body_radius - r_e))
        r_in = rc - min(RUN_OUT_OVERSHOOT_MM, 0.5 * rc)
        poly = np.array([[r_e + o, -o], [r_in, -o], [r_in, r_e - r_in]])
    else:               # r > r_e + d, beyond the crest
        o = min(o, 0.5 * r_e)
        R = rc + RUN_OUT_OVERSHOOT_MM
        poly = np.array([[r_e - o, -o], [R, -o], [R, R - r_e]])
    return poly, segment


def _run_out_segments(tm: ThreadMesh) -> int:
    """Angular segments of the run-out tools: a multiple of the thread's columns per turn
    whose sagitta r (1 - cos(pi / n)) at the outer radius r is within ``tm.chord_tolerance``.

    The tools' vertices then lie at the thread's column angles k 2 pi / n_columns (and
    between), so near the crest the frustum's polygon runs parallel to the crest's, 5 um
    (:data:`RUN_OUT_CREST_GAP_MM`) inside, and never within nanometres of it.
    """
    tol, r = tm.chord_tolerance, tm.profile.outer_radius
    n_cols = choose_tessellation(tm.profile, tol).columns_per_turn
    n_sag = int(math.ceil(math.pi / math.acos(1.0 - tol / r)))
    return n_cols * int(math.ceil(n_sag / n_cols))


def _revolved(poly_rz: NDArray[np.float64], n: int) -> Any:
    """The manifold3d solid of the polygon ``poly_rz`` ((m, 2): r >= 0, z; mm, part frame)
    revolved about the z axis in ``n`` segments, vertices at theta = 2 pi k / n.

    Built from exact float64 vertices (a CrossSection would round them to its fixed
    precision, and a frustum's base must lie exactly in the end plane). cos and sin are
    mirrored exactly (k and n - k), so the solid is the same for left-hand parts. Vertices
    with r = 0 are one vertex on the axis.
    """
    import manifold3d

    r, z = poly_rz[:, 0], poly_rz[:, 1]
    if np.sum(r * np.roll(z, -1) - np.roll(r, -1) * z) < 0:   # counter-clockwise in (r, z): outward normals
        r, z = r[::-1], z[::-1]
    k = np.arange(n)
    half = np.minimum(k, n - k)
    cos, sin = np.cos(2 * math.pi * half / n), np.sign(n - 2 * k) * np.sin(2 * math.pi * half / n)
    on_axis = r == 0.0
    count = np.where(on_axis, 1, n)
    first = np.cumsum(count) - count
    ring = np.arange(int(count.sum())) - np.repeat(first, count)        # k of each vertex in its ring
    V = np.column_stack([np.repeat(r, count) * cos[ring], np.repeat(r, count) * sin[ring], np.repeat(z, count)])
    ids = first[:, None] + np.where(on_axis[:, None], 0, k[None, :])                   # (m, n)
    a, b = ids, np.roll(ids, -1, axis=1)
    c, d = np.roll(b, -1, axis=0), np.roll(a, -1, axis=0)
    F = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    F = F[(F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 2] != F[:, 0])]         # fans at the axis
    return manifold3d.Manifold(manifold3d.Mesh64(np.ascontiguousarray(V), np.ascontiguousarray(F, dtype=np.uint64)))


def apply_run_outs(tm: ThreadMesh, run_outs: Sequence[RunOut], part_range: tuple[float, float] | None = None,
                   mark: DatumMark | None = None) -> ThreadMesh:
    """``tm`` with thread run-outs at its end planes (manifold3d booleans, float64).

    Rules (mm, part frame: z along the axis, right-handed; every tool is a solid of
    revolution, so the result is the same for left-hand parts):

    * "wheel-exit" (external threads only): union with a frustum whose radius rises
      linearly from root - :data:`RUN_OUT_ROOT_MARGIN_MM` at depth ``length_mm`` to
      crest - :data:`RUN_OUT_CREST_GAP_MM` in the end plane, so the groove's root rises
      from the root to the crest; the flanks are unchanged (the real wheel exit also
      narrows the groove: left out). The frustum ends in the end plane: its base is
      coplanar with the end face, which manifold3d unites into one clean face.
    * "chamfer": subtract the region r > r_e + d (external) or r < r_e - d (internal, a
      countersink), d the depth from the end plane, r_e = crest -/+ ``length_mm``: a
      45 degree chamfer of the crest. The tool reaches :data:`RUN_OUT_OVERSHOOT_MM` out of
      the end plane and beyond the crest, and stays inside the nut's body radius.

    The tools' polygons keep their sagitta within ``tm.chord_tolerance``
    (:func:`_run_out_segments`). The thread's faces keep their kinds; the run-out faces get
    ``FACE_RUN_OUT``. A chamfer down to the pitch radius never reaches a flank contact
    (those lie at least p / 4 from the end planes near the pitch radius).

    Parameters
    ----------
    tm : ThreadMesh
        The part, or a piece of it between window planes (:func:`thread_mesh`).
    run_outs : sequence of RunOut
        At most one per end.
    part_range : (float, float), optional
        The whole part's end planes (mm) when ``tm`` is a piece of it: the run-outs are
        checked against that length and applied only at the ends the piece reaches (a
        wheel exit reaching past the piece is clipped to it). Default: ``tm``'s own planes.
    mark : DatumMark, optional
        Also cut this datum mark, after the run-outs, as :func:`cut_datum_mark` does, but
        in the same manifold3d pass (building the part's solid is most of a pass's cost).

    Returns
    -------
    ThreadMesh
        A copy with the run-outs applied and recorded in ``run_outs`` (without a run-out
        to apply: ``tm`` itself, or ``cut_datum_mark(tm, mark)``).

    Raises
    ------
    ValueError
        A wheel exit on an internal thread, a length not below half the part's length, a
        chamfer deeper than |crest - pitch radius|, or two run-outs at one end (counting
        those ``tm`` already has).
    """
    lo, hi = part_range or (tm.z_lo, tm.z_hi)
    _check_run_outs(tm.profile, (*tm.run_outs, *run_outs), hi - lo)
    applied = tuple(ro for ro in run_outs if (tm.z_lo == lo if ro.end == "lo" else tm.z_hi == hi))
    if not applied:
        return tm if mark is None else cut_datum_mark(tm, mark)
    wheel_exits = [ro for ro in applied if ro.kind == "wheel-exit"]
    chamfers = [ro for ro in applied if ro.kind == "chamfer"]
    steps = [(op, functools.partial(_run_out_tools, tm, tools), FACE_RUN_OUT)
             for op, tools in (("add", wheel_exits), ("subtract", chamfers)) if tools]
    if mark is not None:
        steps.append(("subtract", functools.partial(_datum_slot, mark), FACE_MARK))
    V, F, kind = _boolean_keeping_kinds(tm, steps, "thread run-out")
    return dataclasses.replace(tm, vertices=V, faces=F, face_kind=kind, meta=dict(tm.meta),
                               run_outs=tm.run_outs + applied, datum_mark=mark or tm.datum_mark)


def _run_out_tools(tm: ThreadMesh, run_outs: Sequence[RunOut]) -> Any:
    """The union of the tools (manifold3d solids, part frame) of ``run_outs`` on ``tm``."""
    n = _run_out_segments(tm)
    solid = None
    for ro in run_outs:   # at most two: one per end
        z_end, s = _end_plane(tm, ro)
        poly, _ = _run_out_outline(tm, ro)
        tool = _revolved(np.column_stack([poly[:, 0], z_end - s * poly[:, 1]]), n)
        solid = tool if solid is None else solid + tool
    return solid


def _segment_distance(r: NDArray, d: NDArray, segments: NDArray) -> NDArray:
    """Distance (mm) in the axial half-plane from the points (r, d) to the nearest of the
    segments ((k, 2, 2): end points (r, d))."""
    P = np.stack([r, d], axis=-1)[:, None, :]                  # (N, 1, 2)
    A, B = segments[None, :, 0, :], segments[None, :, 1, :]    # (1, k, 2)
    AB = B - A
    t = np.clip(np.sum((P - A) * AB, -1) / np.sum(AB * AB, -1), 0.0, 1.0)
    return np.min(np.linalg.norm(P - A - t[..., None] * AB, axis=-1), axis=1, initial=np.inf)


def run_out_distance(tm: ThreadMesh, r: NDArray, z: NDArray) -> NDArray:
    """Distance (mm) in the axial half-plane from the points (r, z) (part frame) to the
    nearest analytic run-out surface of ``tm``: the wheel exit's cone |r - r_cone(z)| and
    its base in the end plane, the chamfer's 45 degree cone |(r - r_e) -/+ d| / sqrt(2)
    (d the depth from the end plane), each bounded to its extent. Surfaces of revolution:
    this is the 3D distance."""
    best = np.full(np.shape(r), np.inf)
    for ro in tm.run_outs:
        z_end, s = _end_plane(tm, ro)
        best = np.minimum(best, _segment_distance(r, s * (z_end - z), _run_out_outline(tm, ro)[1]))
    return best


def _wheel_exit_radius(tm: ThreadMesh, z: NDArray) -> NDArray:
    """The largest radius (mm) a wheel-exit frustum of ``tm`` has in the plane z (part
    frame), 0 where none reaches: end-face points of the screw out to it are legitimate."""
    out = np.zeros(np.shape(z))
    for ro in tm.run_outs:
        if ro.kind == "wheel-exit":
            z_end, s = _end_plane(tm, ro)
            (_, (r_end, _), (r_far, d_far), _) = _run_out_outline(tm, ro)[0]
            d = s * (z_end - z)
            inside = (d >= 0.0) & (d <= d_far)
            out = np.where(inside, np.maximum(out, r_end + (r_far - r_end) * d / d_far), out)
    return out


# --------------------------------------------------------------------------- checking
#: Barycentric sample points per face: centroid, edge midpoints, three inner points.
_BARY = np.array([[1 / 3, 1 / 3, 1 / 3], [0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5],
                  [2 / 3, 1 / 6, 1 / 6], [1 / 6, 2 / 3, 1 / 6], [1 / 6, 1 / 6, 2 / 3]])


def analytic_radius(tm: ThreadMesh, theta: NDArray, z: NDArray) -> NDArray:
    """Radius of the analytic thread surface at (theta, z) in the right-hand part frame."""
    prof, warp = tm.profile, tm.warp
    L, p = prof.lead, prof.pitch
    mu0 = tm.first_mid + L * theta / (2 * math.pi)
    k = np.round((warp.inverse(z) - mu0) / p)
    u = z - warp(mu0 + k * p)
    return prof.radius_at_offset(u)


def flank_distance(prof: ThreadProfile, u: NDArray, r: NDArray) -> NDArray:
    """Exact distance (mm) in the axial half-plane from (u, r) to the flank u = t(r') of
    the tooth side u > 0, r' between the root and crest radii (the flank *segment*); the
    flank object measures it (:meth:`~prs_geom.geometry.flanks.FlankShape.axial_distance`)."""
    return prof.flank.axial_distance(np.asarray(u, dtype=np.float64), np.asarray(r, dtype=np.float64),
                                     0.25 * prof.pitch * prof.cos_lead, prof.cos_lead,
                                     prof.root_radius, prof.crest_radius)


def profile_distance(tm: ThreadMesh, theta: NDArray, r: NDArray, z: NDArray) -> NDArray:
    """Distance (mm) in the axial half-plane at theta from (r, z) to the analytic profile.

    Exact in that half-plane: the minimum over the pieces of the three nearest teeth (each
    at its own warped mid-plane) of the distance to the crest segment, the flank segment
    (:func:`flank_distance`) and the root segment to the next tooth. The axial-section
    curve lies on the helical surface, so this is an upper bound of the 3D distance to the
    surface (larger by at most the factor 1 / cos of the angle between the surface normal
    and the axial half-plane, below 1 % for these lead angles).
    """
    prof, warp = tm.profile, tm.warp
    L, p = prof.lead, prof.pitch
    r = np.asarray(r, dtype=np.float64)
    z = np.asarray(z, dtype=np.float64)
    mu0 = tm.first_mid + L * np.asarray(theta, dtype=np.float64) / (2 * math.pi)
    k = np.round((warp.inverse(z) - mu0) / p)
    tc, tr = prof.tooth_half_width_at_crest(), float(prof.tooth_half_width(prof.root_radius))
    rc, rr = prof.crest_radius, prof.root_radius
    mids = [warp(mu0 + (k + j) * p) for j in (-1, 0, 1)]
    best = np.full(r.shape, np.inf)
    for j, m in enumerate(mids):
        u = z - m
        best = np.minimum(best, np.hypot(r - rc, np.maximum(np.abs(u) - tc, 0.0)))   # crest
        best = np.minimum(best, flank_distance(prof, np.abs(u), r))                    # flank
        if j < 2:                                                                       # root to next tooth
            lo, hi = m + tr, mids[j + 1] - tr
            best = np.minimum(best, np.hypot(r - rr, np.maximum(np.maximum(lo - z, z - hi), 0.0)))
    return best


#: Faces sampled at once by :func:`measure_deviation`: its point arrays (7 per face) and the
#: flank Newton's temporaries cost about 1.5 kB a face, so a chunk holds about 25 MB (measured
#: on the default screw, 116 k faces: the mesh checks' peak 283 -> 175 MB USS at 2 ** 17 -> 2 ** 14,
#: and 15 % faster).
DEVIATION_CHUNK_FACES = 2 ** 14


def measure_deviation(tm: ThreadMesh) -> dict[str, float]:
    """Sample every face (7 points) and measure the distance to the analytic surface.

    Returns the largest deviation (mm) on the thread surface body, on the thread surface
    next to the end planes, on the end faces (radial overshoot of the analytic end region,
    which a wheel exit widens to its frustum's base), on the body cylinder, on the datum
    mark and on the run-out faces (:func:`run_out_distance`), plus the number of sample
    points. The faces are sampled in
    chunks of :data:`DEVIATION_CHUNK_FACES` (every distance is per point, so the maxima
    do not depend on the chunking; only the memory does).
    """
    V = tm.vertices * (np.array([1.0, -1.0, 1.0]) if tm.profile.hand_sign < 0 else 1.0)
    out: dict[str, float] = {}
    for start in range(0, len(tm.faces), DEVIATION_CHUNK_FACES):
        stop = start + DEVIATION_CHUNK_FACES
        for key, value in _deviation_chunk(tm, V, tm.faces[start:stop], tm.face_kind[start:stop]).items():
            out[key] = out.get(key, 0) + value if key == "samples" else max(out.get(key, 0.0), value)
    out["samples"] = int(out.get("samples", 0))
    out["max_deviation_mm"] = max(v for k_, v in out.items() if k_.startswith("max_"))
    return out


def _deviation_chunk(tm: ThreadMesh, V: NDArray[np.float64], faces: NDArray[np.int64],
                     face_kind: NDArray[np.int8]) -> dict[str, float]:
    """:func:`measure_deviation` of the faces ``faces`` (kinds ``face_kind``) of ``tm``,
    ``V`` its vertices mirrored to right hand; the maxima of the regions the chunk has."""
    tri = V[faces]                                      # (F, 3, 3)
    pts = np.einsum("sk,fkd->fsd", _BARY, tri)          # (F, S, 3)
    kind = np.repeat(face_kind, len(_BARY))
    pts = pts.reshape(-1, 3)
    r = np.hypot(pts[:, 0], pts[:, 1])
    th = np.arctan2(pts[:, 1], pts[:, 0])
    z = pts[:, 2]
    out: dict[str, float] = {"samples": int(len(pts))}
    thread = kind == FACE_THREAD
    d = profile_distance(tm, th[thread], r[thread], z[thread])
    zt = tri[:, :, 2]
    near_end = (np.isclose(zt, tm.z_lo, atol=0, rtol=0) | np.isclose(zt, tm.z_hi, atol=0, rtol=0)).any(1)
    near_end = np.repeat(near_end, len(_BARY))[thread]
    out["max_deviation_body_mm"] = float(d[~near_end].max(initial=0.0))
    out["max_deviation_end_mm"] = float(d[near_end].max(initial=0.0))
    caps = (kind == FACE_END_LO) | (kind == FACE_END_HI)
    rho = analytic_radius(tm, th[caps], z[caps])
    zc = np.where(kind[caps] == FACE_END_LO, tm.z_lo, tm.z_hi)
    planar = np.abs(z[caps] - zc)
    if tm.profile.internal:
        over = np.maximum(rho - r[caps], 0.0) + np.maximum(r[caps] - tm.body_radius, 0.0)
    elif any(ro.kind == "wheel-exit" for ro in tm.run_outs):
        # the end face and the frustum's base are one face: out to either radius
        over = np.maximum(r[caps] - np.maximum(rho, _wheel_exit_radius(tm, zc)), 0.0)
    else:
        over = np.maximum(r[caps] - rho, 0.0)
    out["max_deviation_end_face_mm"] = float(np.maximum(over, planar).max(initial=0.0))
    if tm.run_outs:
        run_out = kind == FACE_RUN_OUT
        out["max_deviation_run_out_mm"] = float(run_out_distance(tm, r[run_out], z[run_out]).max(initial=0.0))
    if tm.body_radius is not None:
        body = kind == FACE_BODY
        out["max_deviation_body_cylinder_mm"] = float(np.abs(r[body] - tm.body_radius).max(initial=0.0))
    if tm.datum_mark is not None:
        # every slot sample lies on one of the slot's five planes: its distance is the
        # smallest distance to them, and it must not stray outside the box either
        mark = tm.datum_mark
        (x0, y0, _), (x1, y1, z1) = mark.box()
        P = pts[kind == FACE_MARK]
        on_plane = np.min(np.abs(np.column_stack([P[:, 0] - x0, P[:, 0] - x1, P[:, 1] - y0, P[:, 1] - y1,
                                                  P[:, 2] - z1])), axis=1, initial=np.inf)
        outside = np.max(np.column_stack([x0 - P[:, 0], P[:, 0] - x1, y0 - P[:, 1], P[:, 1] - y1,
                                          mark.z_face - P[:, 2], P[:, 2] - z1, np.zeros(len(P))]), axis=1,
                         initial=-np.inf)
        out["max_deviation_datum_mark_mm"] = float(np.maximum(on_plane, outside).max(initial=0.0))
    return out


# --------------------------------------------------------------------------- volumes
def analytic_thread_volume(profile: ThreadProfile, length: float, body_radius: float | None = None) -> float:
    """Exact volume (mm^3) of a constant-pitch threaded part of axial ``length``.

    A plane z = const cuts the thread surface r = rho(z - L theta / 2 pi) in a curve whose
    enclosed area is (pi / p) * integral of rho(u)^2 over one period, the same at every z
    (theta sweeps n_i whole periods). The integral is closed-form piece by piece.
    """
    p = profile.pitch
    rr, rc = profile.root_radius, profile.crest_radius
    tr, tc = float(profile.tooth_half_width(rr)), float(profile.tooth_half_width(rc))
    c = profile.cos_lead
    flank = profile.flank.radial_moment(rr, rc) / c
    integral = 2 * (0.5 * p - tr) * rr ** 2 + 2 * tc * rc ** 2 + 2 * flank
    inner = math.pi / p * integral * length
    if profile.internal:
        return math.pi * body_radius ** 2 * length - inner
    return inner


def to_manifold(vertices: NDArray[np.float64], faces: NDArray[np.int64]):
    """The manifold3d solid of a triangle mesh (float64 vertices, as given)."""
    import manifold3d

    return manifold3d.Manifold(manifold3d.Mesh64(np.ascontiguousarray(vertices, dtype=np.float64),
                                                 np.ascontiguousarray(faces, dtype=np.uint64)))


def from_manifold(solid) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Vertices (float64, a writable copy) and faces of a manifold3d solid."""
    m = solid.to_mesh64()
    return (np.array(np.asarray(m.vert_properties)[:, :3], dtype=np.float64),
            np.array(m.tri_verts, dtype=np.int64))


def edge_flags(faces: NDArray[np.int64]) -> tuple[bool, bool]:
    """(watertight, winding consistent) of a triangle mesh, as trimesh defines them
    (``Trimesh.is_watertight``, ``is_winding_consistent``): watertight when every edge bounds
    exactly two faces; winding consistent when the two faces of each such edge run it in
    opposite directions; a mesh without faces is neither. One sort of int64 edge keys:
    trimesh's own check builds its edge caches, 57 MB on the default screw (116 k faces)."""
    F = np.asarray(faces, dtype=np.int64)
    if not len(F):
        return False, False
    start, end = F.ravel(), np.roll(F, -1, axis=1).ravel()
    n = int(F.max()) + 1
    key = np.minimum(start, end) * n + np.maximum(start, end)
    order = np.argsort(key, kind="stable")
    key = key[order]
    first = np.flatnonzero(np.concatenate([[True], key[1:] != key[:-1]]))
    count = np.diff(np.append(first, len(key)))
    pairs = first[count == 2]
    start = start[order]
    return bool(np.all(count == 2)), bool(np.all(start[pairs] != start[pairs + 1]))


def manifold_status(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> str:
    """manifold3d's verdict on a mesh ("NoError" when it accepts it as a solid), in float64."""
    return str(to_manifold(vertices, faces).status()).split(".")[-1]


def float32_rounding(vertices: NDArray[np.float64]) -> float:
    """Largest coordinate change (mm) from storing ``vertices`` as float32 (STL, GLB)."""
    return float(np.abs(vertices.astype(np.float32).astype(np.float64) - vertices).max(initial=0.0))


#: Region names of :func:`measure_deviation` as they read in a warning.
_REGION_TEXT = {"body": "thread surface", "end": "thread surface next to the end planes",
                "end_face": "end faces", "body_cylinder": "outer body cylinder",
                "datum_mark": "angular datum mark", "run_out": "thread run-outs"}


def deviation_warnings(deviation: dict[str, float], tol: float) -> list[str]:
    """One line per region whose measured deviation (mm) exceeds the chord tolerance ``tol``
    (the report's collector prefixes the part name)."""
    return [f"measured deviation {v:.4g} mm on the {_REGION_TEXT.get(k, k)} exceeds the "
            f"chord tolerance {tol:g} mm ({v / tol:.2f} x)"
            for k, v in deviation.items() if not v <= tol]


def mesh_report(tm: ThreadMesh, analytic_volume: float | None = None) -> dict[str, Any]:
    """The ``checks.meshes`` entry of one part: counts, closure, manifold3d verdict, the
    sampled deviation from the analytic surface and the volume check.

    ``warnings`` (list of str, empty when the mesh passes) names every region whose
    measured deviation exceeds the chord tolerance, with the value and the tolerance.
    """
    dev = measure_deviation(tm)
    regions = {k[len("max_deviation_"):-3]: v for k, v in dev.items()
               if k.startswith("max_deviation_") and k != "max_deviation_mm"}
    # the edge checks without trimesh's edge caches: the mesh checks run in a worker while
    # the checks worker holds its BVHs, the build's peak
    watertight, winding = edge_flags(tm.faces)
    volume = float(tm.to_trimesh().volume)
    row: dict[str, Any] = {
        "part": tm.part,
        "triangles": int(len(tm.faces)),
        "watertight": watertight,
        "winding_consistent": winding,
        "manifold": manifold_status(tm.vertices, tm.faces) == "NoError",
        "chord_tolerance_mm": tm.chord_tolerance,
        "max_deviation_mm": dev["max_deviation_mm"],
        "deviation_mm": regions,
        "deviation_samples": dev["samples"],
        "deviation_measure": "exact distance in the axial half-plane to the analytic profile "
                             "(an upper bound of the 3D distance), 7 points per face",
        "volume_mm3": volume,
        "float32_rounding_mm": float32_rounding(tm.vertices),
    }
    if tm.datum_mark is not None:
        mk = tm.datum_mark
        row["datum_mark"] = {"z_face_mm": mk.z_face, "r_inner_mm": mk.r_inner, "r_outer_mm": mk.r_outer,
                             "width_mm": mk.width, "depth_mm": mk.depth, "volume_mm3": mk.volume}
    if analytic_volume is not None:
        row["analytic_volume_mm3"] = analytic_volume
        row["volume_rel_error"] = (row["volume_mm3"] - analytic_volume) / analytic_volume
    row.update(tm.meta)
    row["warnings"] = deviation_warnings(regions, tm.chord_tolerance)
    return row


def axial_line_crossings(vertices: NDArray[np.float64], faces: NDArray[np.int64], x: float,
                         y: float, with_direction: bool = False):
    """Sorted z of every crossing of the line {(x, y, z)} with the mesh, float64.

    Exact barycentric interpolation on the triangles whose xy-projection contains (x, y);
    used to read flank positions off a mesh. With ``with_direction`` also returns the sign
    of the crossed face's normal z component: -1 where the line enters the solid going
    up (+z), +1 where it leaves it.
    """
    tri = vertices[faces]
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    d = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])
    w1 = ((b[:, 0] - x) * (c[:, 1] - y) - (c[:, 0] - x) * (b[:, 1] - y))
    w2 = ((c[:, 0] - x) * (a[:, 1] - y) - (a[:, 0] - x) * (c[:, 1] - y))
    w3 = ((a[:, 0] - x) * (b[:, 1] - y) - (b[:, 0] - x) * (a[:, 1] - y))
    with np.errstate(divide="ignore", invalid="ignore"):
        l1, l2, l3 = w1 / d, w2 / d, w3 / d
    hit = (d != 0) & (l1 >= 0) & (l2 >= 0) & (l3 >= 0)
    z = l1[hit] * a[hit, 2] + l2[hit] * b[hit, 2] + l3[hit] * c[hit, 2]
    direction = np.sign(d[hit])  # the xy-projected winding is the sign of the normal's z
    order = np.argsort(z, kind="stable")
    z, direction = z[order], direction[order]
    # a line through a shared edge or vertex hits two or more faces at the same z
    keep = np.concatenate([[True], np.diff(z) > 1e-9]) if len(z) else np.zeros(0, bool)
    return (z[keep], direction[keep]) if with_direction else z[keep]
