"""Watertight triangle meshes of threaded parts, built from the analytic surfaces.

Construction (no Python loop over vertices or faces; loops run over the few dozen
profile strands only):

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
  makes in the end curve (small flank angles, thin walls: up to 10x the tolerance before).

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
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from prs_geom.geometry.datum import DatumMark
from prs_geom.geometry.helix import PitchWarp, identity_warp
from prs_geom.geometry.profiles import ThreadProfile

FACE_THREAD, FACE_END_LO, FACE_END_HI, FACE_BODY, FACE_MARK = 0, 1, 2, 3, 4
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
    return Tessellation(n_cols, radii, tol)


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
    surface, lower/upper end faces, the nut's outer body cylinder and the walls and floor
    of the angular datum mark (``datum_mark``, :mod:`prs_geom.geometry.datum`).
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

    def to_trimesh(self) -> trimesh.Trimesh:
        return trimesh.Trimesh(self.vertices, self.faces, process=False, validate=False)


# --------------------------------------------------------------------------- merging
def merge_strips(a_ids: list[NDArray], a_th: list[NDArray], b_ids: list[NDArray],
                 b_th: list[NDArray]) -> NDArray[np.int64]:
    """Triangulate strips between chain pairs (A lower, B upper), both sorted by theta.

    For every strip the triangles are counter-clockwise in the (theta, u) plane with A
    below B; the strip starts at rung (A[0], B[0]) and ends at rung (A[-1], B[-1]).
    Vectorised over all strips at once.
    """
    na = np.array([len(x) for x in a_ids])
    nb = np.array([len(x) for x in b_ids])
    A = np.concatenate(a_ids)
    B = np.concatenate(b_ids)
    a0 = np.concatenate([[0], np.cumsum(na)[:-1]])
    b0 = np.concatenate([[0], np.cumsum(nb)[:-1]])
    strip_a = np.repeat(np.arange(len(na)), na)
    strip_b = np.repeat(np.arange(len(nb)), nb)
    ka = np.arange(len(A)) - a0[strip_a]
    kb = np.arange(len(B)) - b0[strip_b]
    ta, tb = np.concatenate(a_th), np.concatenate(b_th)
    ea, eb = ka >= 1, kb >= 1
    ev_strip = np.concatenate([strip_a[ea], strip_b[eb]])
    ev_theta = np.concatenate([ta[ea], tb[eb]])
    ev_isb = np.concatenate([np.zeros(ea.sum(), np.int64), np.ones(eb.sum(), np.int64)])
    ev_k = np.concatenate([ka[ea], kb[eb]])
    order = np.lexsort((ev_isb, ev_theta, ev_strip))
    ev_strip, ev_isb, ev_k = ev_strip[order], ev_isb[order], ev_k[order]
    # A and B events seen so far in the strip, this one excluded
    cum_b = np.cumsum(ev_isb) - ev_isb
    cum_a = np.cumsum(1 - ev_isb) - (1 - ev_isb)
    first = np.concatenate([[True], ev_strip[1:] != ev_strip[:-1]])
    start_idx = np.maximum.accumulate(np.where(first, np.arange(len(ev_strip)), 0))
    nb_before = cum_b - cum_b[start_idx]
    na_before = cum_a - cum_a[start_idx]
    sa, sb = a0[ev_strip], b0[ev_strip]
    is_a = ev_isb == 0
    i_a = np.where(is_a, ev_k, na_before)       # current A index after the event
    j_b = np.where(is_a, nb_before, ev_k)       # current B index after the event
    tri = np.empty((len(ev_strip), 3), np.int64)
    tri[is_a, 0] = A[sa[is_a] + i_a[is_a] - 1]
    tri[is_a, 1] = A[sa[is_a] + i_a[is_a]]
    tri[is_a, 2] = B[sb[is_a] + j_b[is_a]]
    ib = ~is_a
    tri[ib, 0] = A[sa[ib] + i_a[ib]]
    tri[ib, 1] = B[sb[ib] + j_b[ib]]
    tri[ib, 2] = B[sb[ib] + j_b[ib] - 1]
    return tri


def _ranges(starts: NDArray[np.int64], counts: NDArray[np.int64]) -> tuple[NDArray, NDArray]:
    """Concatenated aranges: (values, owner index) for each (start, count)."""
    counts = np.maximum(counts, 0)
    owner = np.repeat(np.arange(len(starts)), counts)
    offs = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
    return starts[owner] + offs, owner


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
    falls = np.roll(r_poly, -1) < r_poly - eps          # the polygon is closed: one turn
    tops = falls & ~np.roll(falls, 1)
    t = np.sort(np.mod(th_poly[tops], two_pi))
    uni = step * np.arange(n_o)
    if len(t) == 0:
        return uni
    k = np.searchsorted(t, uni) % len(t)
    gap = np.minimum(np.abs((uni - t[k] + math.pi) % two_pi - math.pi),
                     np.abs((uni - t[k - 1] + math.pi) % two_pi - math.pi))
    return np.sort(np.concatenate([t, uni[gap > COLUMN_MARGIN * step]]))


# --------------------------------------------------------------------------- builder
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
    """
    warp = warp or identity_warp(profile.pitch)
    if profile.internal and body_radius is None:
        raise ValueError("an internal thread needs body_radius")
    tess = choose_tessellation(profile, tol)
    dth = tess.dtheta
    ncol = tess.columns_per_turn
    L, p = profile.lead, profile.pitch
    u_s, r_s = profile_strands(profile, tess)
    M = len(u_s)
    G = profile.starts * M
    g = np.arange(G)
    k_g = g // M
    u_g = u_s[g % M]
    r_g = r_s[g % M]
    base_g = first_mid + k_g * p   # helix coordinate of strand g's tooth at theta = 0

    def theta_at(z_e: float, idx=g) -> NDArray:
        m = warp.inverse(z_e - u_g[idx])
        return 2.0 * math.pi * (m - base_g[idx]) / L

    th_lo, th_hi = theta_at(z_lo), theta_at(z_hi)
    c0, c1 = _open_columns(th_lo, th_hi, dth)

    def xyz(r: NDArray, th: NDArray, z: NDArray) -> NDArray:
        return np.column_stack([r * np.cos(th), r * np.sin(th), z])

    # --- strand column vertices
    cols, owner = _ranges(c0, c1 - c0 + 1)
    th_c = cols * dth
    z_c = warp(base_g[owner] + L * th_c / (2 * math.pi)) + u_g[owner]
    verts = [xyz(r_g[owner], th_c, z_c)]
    n_strand_cols = c1 - c0 + 1
    strand_base = np.concatenate([[0], np.cumsum(n_strand_cols)[:-1]])
    nv = len(cols)
    # --- strand end vertices
    e_lo = nv + g
    e_hi = nv + G + g
    verts.append(xyz(r_g, th_lo, np.full(G, z_lo)))
    verts.append(xyz(r_g, th_hi, np.full(G, z_hi)))
    nv += 2 * G

    # --- bands (g, h): h = g + 1, the last band wraps to strand 0 one turn on
    h = (g + 1) % G
    wrap = np.where(g == G - 1, -2.0 * math.pi, 0.0)  # theta offset of strand h in band param
    colshift = np.where(g == G - 1, -ncol, 0)
    th_lo_h, th_hi_h = th_lo[h] + wrap, th_hi[h] + wrap

    end_ids: dict[str, NDArray] = {}
    end_th: dict[str, NDArray] = {}
    end_owner: dict[str, NDArray] = {}
    for name, z_e, lo_b, hi_b in (("lo", z_lo, th_lo_h, th_lo), ("hi", z_hi, th_hi_h, th_hi)):
        b0, b1 = _open_columns(lo_b, hi_b, dth)
        ecol, eown = _ranges(b0, b1 - b0 + 1)
        eth = ecol * dth
        m = base_g[eown] + L * eth / (2 * math.pi)
        u_star = z_e - warp(m)
        verts.append(xyz(profile.radius_at_offset(u_star), eth, np.full(len(ecol), z_e)))
        end_ids[name] = nv + np.arange(len(ecol))
        end_th[name] = eth
        end_owner[name] = eown
        nv += len(ecol)
    vertices = np.concatenate(verts)

    # --- chains per band (loop over strands only)
    split = {n: np.searchsorted(end_owner[n], np.arange(G + 1)) for n in end_ids}
    A_ids, A_th, B_ids, B_th = [], [], [], []
    for gi in range(G):
        hi_ = h[gi]
        lo_sl = slice(split["lo"][gi], split["lo"][gi + 1])
        hi_sl = slice(split["hi"][gi], split["hi"][gi + 1])
        gcols = strand_base[gi] + np.arange(n_strand_cols[gi])
        hcols = strand_base[hi_] + np.arange(n_strand_cols[hi_])
        A_ids.append(np.concatenate([[e_lo[hi_]], end_ids["lo"][lo_sl], [e_lo[gi]], gcols, [e_hi[gi]]]))
        A_th.append(np.concatenate([[th_lo_h[gi]], end_th["lo"][lo_sl], [th_lo[gi]],
                                    np.arange(c0[gi], c1[gi] + 1) * dth, [th_hi[gi]]]))
        B_ids.append(np.concatenate([hcols, [e_hi[hi_]], end_ids["hi"][hi_sl]]))
        B_th.append(np.concatenate([(np.arange(c0[hi_], c1[hi_] + 1) + colshift[gi]) * dth,
                                    [th_hi_h[gi]], end_th["hi"][hi_sl]]))
    faces_thread = merge_strips(A_ids, A_th, B_ids, B_th)

    # --- end polygons, theta increasing over exactly one turn: bands in decreasing g
    polys = {}
    for name, e in (("lo", e_lo), ("hi", e_hi)):
        sl = split[name]
        ids, ths = [], []
        th_e = th_lo if name == "lo" else th_hi
        for gi in range(G - 1, -1, -1):
            hi_ = h[gi]
            ids.append(np.concatenate([[e[hi_]], end_ids[name][sl[gi]:sl[gi + 1]]]))
            ths.append(np.concatenate([[th_e[hi_] + wrap[gi]], end_th[name][sl[gi]:sl[gi + 1]]]))
        polys[name] = (np.concatenate(ids), np.concatenate(ths))

    face_lists = [faces_thread]
    kinds = [np.full(len(faces_thread), FACE_THREAD, np.int8)]
    if not profile.internal:
        centre_lo, centre_hi = len(vertices), len(vertices) + 1
        vertices = np.concatenate([vertices, [[0.0, 0.0, z_lo], [0.0, 0.0, z_hi]]])
        for name, centre, kind in (("lo", centre_lo, FACE_END_LO), ("hi", centre_hi, FACE_END_HI)):
            P = polys[name][0]
            Pn = np.roll(P, -1)
            fan = np.column_stack([np.full(len(P), centre), P, Pn])
            if name == "lo":
                fan = fan[:, [0, 2, 1]]
            face_lists.append(fan)
            kinds.append(np.full(len(fan), kind, np.int8))
    else:
        faces_thread[:] = faces_thread[:, [0, 2, 1]]  # material outside: normals point inward
        # body polygon: no step wider than step_max, whose sagitta is tol
        step_max = 2.0 * math.acos(1.0 - tol / body_radius)
        two_pi = 2.0 * math.pi
        rings = {}
        for name, z_e, kind in (("lo", z_lo, FACE_END_LO), ("hi", z_hi, FACE_END_HI)):
            P, th = polys[name]
            ang = _ring_angles(th, np.hypot(vertices[P, 0], vertices[P, 1]), step_max)
            rids = len(vertices) + np.arange(len(ang))
            vertices = np.concatenate([vertices, np.column_stack(
                [body_radius * np.cos(ang), body_radius * np.sin(ang), np.full(len(ang), z_e)])])
            rings[name] = (rids, ang)
            rel = (ang - th[0]) % two_pi            # circle vertices from the polygon start on
            order = np.argsort(rel, kind="stable")
            b_th = th[0] + rel[order]
            a_ids = [np.concatenate([P, [P[0]]])]
            a_th = [np.concatenate([th, [th[0] + two_pi]])]
            b_ids = [np.concatenate([rids[order], rids[order[:1]]])]
            f = merge_strips(a_ids, a_th, b_ids, [np.concatenate([b_th, b_th[:1] + two_pi])])  # normals -z
            if name == "hi":
                f = f[:, [0, 2, 1]]
            face_lists.append(f)
            kinds.append(np.full(len(f), kind, np.int8))
        # body cylinder between the two circles (their angles differ where the tops of the
        # falls were added); every triangle spans at most one circle step
        (lo_ids, lo_ang), (hi_ids, hi_ang) = rings["lo"], rings["hi"]
        side = merge_strips([np.concatenate([lo_ids, lo_ids[:1]])],
                            [np.concatenate([lo_ang, lo_ang[:1] + two_pi])],
                            [np.concatenate([hi_ids, hi_ids[:1]])],
                            [np.concatenate([hi_ang, hi_ang[:1] + two_pi])])
        face_lists.append(side)
        kinds.append(np.full(len(side), FACE_BODY, np.int8))

    faces = np.concatenate(face_lists)
    kind = np.concatenate(kinds)
    if profile.hand_sign < 0:
        vertices = vertices * np.array([1.0, -1.0, 1.0])
        faces = faces[:, [0, 2, 1]]
    return ThreadMesh(profile.part, vertices, faces, kind, profile, warp, first_mid, z_lo, z_hi,
                      tol, body_radius, meta={"columns_per_turn": ncol, "strands": G,
                                              "flank_segments": len(tess.flank_radii) - 1})


def cut_datum_mark(tm: ThreadMesh, mark: DatumMark) -> ThreadMesh:
    """``tm`` with the angular datum slot ``mark`` cut out of its face A (manifold3d, float64).

    The boolean keeps every vertex of ``tm`` bit for bit (it only adds the vertices where
    the slot meets face A and the slot's own corners) and carries each face's kind over
    through manifold3d's face ids; the slot's walls and floor get ``FACE_MARK``. The slot
    is symmetric about y = 0, so it is the same on right- and left-hand parts.
    """
    import manifold3d

    n_faces = len(tm.faces)
    part = manifold3d.Manifold(manifold3d.Mesh64(
        np.ascontiguousarray(tm.vertices, dtype=np.float64), np.ascontiguousarray(tm.faces, dtype=np.uint64),
        face_id=np.arange(n_faces, dtype=np.uint64)))
    part_id = int(np.asarray(part.to_mesh64().run_original_id)[0])   # the id manifold3d gave the input
    (x0, y0, z0), (x1, y1, z1) = mark.box(overshoot=1.0)
    slot = manifold3d.Manifold.cube([x1 - x0, y1 - y0, z1 - z0]).translate([x0, y0, z0])
    cut = part - slot
    if cut.status() != manifold3d.Error.NoError:   # pragma: no cover - manifold3d refuses only broken input
        raise RuntimeError(f"datum mark cut of the {tm.part} failed: {cut.status()}")
    out = cut.to_mesh64()
    V = np.array(np.asarray(out.vert_properties)[:, :3], dtype=np.float64, order="C")  # writable copy
    F = np.array(out.tri_verts, dtype=np.int64, order="C")
    # triangles are grouped in runs, one per input manifold; face ids index into that input
    run_index = np.asarray(out.run_index, dtype=np.int64)
    run_of_face = np.searchsorted(run_index[1:], np.arange(len(F)) * 3, side="right")
    from_part = np.asarray(out.run_original_id)[run_of_face] == part_id
    kind = np.full(len(F), FACE_MARK, np.int8)
    kind[from_part] = tm.face_kind[np.asarray(out.face_id, dtype=np.int64)[from_part]]
    return ThreadMesh(tm.part, V, F, kind, tm.profile, tm.warp, tm.first_mid, tm.z_lo, tm.z_hi,
                      tm.chord_tolerance, tm.body_radius, meta=dict(tm.meta), datum_mark=mark)


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


def measure_deviation(tm: ThreadMesh) -> dict[str, float]:
    """Sample every face (7 points) and measure the distance to the analytic surface.

    Returns the largest deviation (mm) on the thread surface body, on the thread surface
    next to the end planes, on the end faces (radial overshoot of the analytic end region)
    and on the body cylinder, plus the number of sample points.
    """
    V = tm.vertices * (np.array([1.0, -1.0, 1.0]) if tm.profile.hand_sign < 0 else 1.0)
    tri = V[tm.faces]                                   # (F, 3, 3)
    pts = np.einsum("sk,fkd->fsd", _BARY, tri)          # (F, S, 3)
    kind = np.repeat(tm.face_kind, len(_BARY))
    pts = pts.reshape(-1, 3)
    r = np.hypot(pts[:, 0], pts[:, 1])
    th = np.arctan2(pts[:, 1], pts[:, 0])
    z = pts[:, 2]
    out = {"samples": int(len(pts))}
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
    else:
        over = np.maximum(r[caps] - rho, 0.0)
    out["max_deviation_end_face_mm"] = float(np.maximum(over, planar).max(initial=0.0))
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
                                                  P[:, 2] - z1])), axis=1)
        outside = np.max(np.column_stack([x0 - P[:, 0], P[:, 0] - x1, y0 - P[:, 1], P[:, 1] - y1,
                                          mark.z_face - P[:, 2], P[:, 2] - z1, np.zeros(len(P))]), axis=1)
        out["max_deviation_datum_mark_mm"] = float(np.maximum(on_plane, outside).max(initial=0.0))
    out["max_deviation_mm"] = max(v for k_, v in out.items() if k_.startswith("max_"))
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


def manifold_status(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> str:
    """manifold3d's verdict on a mesh ("NoError" when it accepts it as a solid), in float64."""
    import manifold3d

    m = manifold3d.Manifold(manifold3d.Mesh64(np.ascontiguousarray(vertices, dtype=np.float64),
                                              np.ascontiguousarray(faces, dtype=np.uint64)))
    return str(m.status()).split(".")[-1]


def float32_rounding(vertices: NDArray[np.float64]) -> float:
    """Largest coordinate change (mm) from storing ``vertices`` as float32 (STL, GLB)."""
    return float(np.abs(vertices.astype(np.float32).astype(np.float64) - vertices).max(initial=0.0))


#: Region names of :func:`measure_deviation` as they read in a warning.
_REGION_TEXT = {"body": "thread surface", "end": "thread surface next to the end planes",
                "end_face": "end faces", "body_cylinder": "outer body cylinder",
                "datum_mark": "angular datum mark"}


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
    m = tm.to_trimesh()
    dev = measure_deviation(tm)
    regions = {k[len("max_deviation_"):-3]: v for k, v in dev.items()
               if k.startswith("max_deviation_") and k != "max_deviation_mm"}
    row: dict[str, Any] = {
        "part": tm.part,
        "triangles": int(len(tm.faces)),
        "watertight": bool(m.is_watertight),
        "winding_consistent": bool(m.is_winding_consistent),
        "manifold": manifold_status(tm.vertices, tm.faces) == "NoError",
        "chord_tolerance_mm": tm.chord_tolerance,
        "max_deviation_mm": dev["max_deviation_mm"],
        "deviation_mm": regions,
        "deviation_samples": dev["samples"],
        "deviation_measure": "exact distance in the axial half-plane to the analytic profile "
                             "(an upper bound of the 3D distance), 7 points per face",
        "volume_mm3": float(m.volume),
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
