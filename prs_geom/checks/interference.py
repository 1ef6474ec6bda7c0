"""Interference check of the whole assembly (``prs-geom check``).

Every pair of scene parts that belong to different rigid bodies is settled. A pair whose
placed meshes' bounds are apart cannot collide and is not asked of FCL
(:mod:`prs_geom.checks.broad_phase`: boxes, and distances from the screw axis for the
coaxial fits); on the default design 167 of its 2 657 pairs are left. Those are
tested with FCL: one BVH per distinct small mesh, built once and placed with transforms,
and for a large mesh placed once (the screw, the nut) a BVH of only its faces near the
other body, built per body pair and freed after it. Where FCL reports a collision,
manifold3d computes the intersection solid (FCL's penetration depth is not reliable for
meshes); its volume and mean thickness 2 V / A (A its surface area) are reported, and the
teeth involved are read from the FCL contact positions. A pair of meshes already checked
at the same placements is not checked again: the nominal-screw check shares every part but
the screw with the corrected one, so it queries only the pairs with the screw.

Mesh tolerance: two meshes that touch analytically (zero design clearance) may overlap by
up to the sum of their chordal deviations. An overlap whose mean thickness is at most
twice the chordal tolerance is therefore reported as ``contact_within_tolerance``, not as
interference; anything thicker is interference.
"""
from __future__ import annotations

import time
from collections import Counter
from dataclasses import dataclass
from typing import Any

import fcl
import manifold3d
import numpy as np
import trimesh
from numpy.typing import NDArray

from prs_geom.geometry.profiles import ThreadProfile
from prs_geom.mesh.assembly import Assembly, build_assembly
from prs_geom.mesh.thread import from_manifold, to_manifold
from prs_geom.analysis.contact import theoretical_screw
from prs_geom.model.design import PRSDesign
from prs_geom.checks.broad_phase import (PlacedBounds, can_touch, face_boxes, longest_edge, near_faces,
                                         placed_bounds)
from prs_geom.checks.fcl import bvh_model
from prs_geom.mesh.budget import CHECK_TOLERANCE_MM, check_span, check_windows
from prs_geom.runtime.progress import ProgressFn, silent

__all__ = [
    "MAX_CONTACTS", "SPLIT_FACES", "body_pairs", "check_assembly", "interference", "interference_checks", "pair_overlaps",
    "windowed_interference_checks",
]

MAX_CONTACTS = 20000


@dataclass(frozen=True)
class _Overlap:
    """What a colliding pair of placed meshes gave: FCL's contact heights and the size of the
    overlap solid. Pure geometry of the two placed meshes (no design data), so it can be
    reused by any check of the same meshes at the same placements."""

    contact_z: NDArray   # z (mm, screw frame) of every FCL contact, in FCL's order
    volume: float        # mm^3, manifold3d intersection solid
    area: float          # mm^2, its surface area


#: Memo key of a placed pair: both meshes by identity (the cache keeps them alive, so an id is
#: never reused for another mesh) and both transforms by value.
_PairKey = tuple[int, bytes, int, bytes]


def _pair_key(a: tuple[trimesh.Trimesh, NDArray, str], b: tuple[trimesh.Trimesh, NDArray, str]) -> _PairKey:
    """The memo key of two placed parts (``Assembly.placed`` entries), in pair order."""
    return (id(a[0]), np.asarray(a[1], dtype=np.float64).tobytes(),
            id(b[0]), np.asarray(b[1], dtype=np.float64).tobytes())


def _trimmed(inter: manifold3d.Manifold, slab: tuple[float, float]) -> tuple[float, float]:
    """Volume (mm^3) and surface area (mm^2) of the part of ``inter`` between the planes
    z = slab, the area without the faces the planes cut: summed over slabs that tile the
    axis they give the whole solid's volume and surface area."""
    lo, hi = slab
    bb = inter.bounding_box()
    if bb[2] >= lo and bb[5] <= hi:
        return float(inter.volume()), float(inter.surface_area())
    piece = inter
    if bb[2] < lo:
        piece = piece.trim_by_plane((0.0, 0.0, 1.0), lo)
    if bb[5] > hi:
        piece = piece.trim_by_plane((0.0, 0.0, -1.0), -hi)
    if piece.is_empty():
        return 0.0, 0.0
    V, F = from_manifold(piece)
    tri = V[F]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    z = tri[:, :, 2]
    # a cut face lies in a slab plane (the helical flanks and the part end faces never do:
    # the window planes are chosen inside the thread, away from every end face)
    eps = 1e-9 * max(1.0, abs(bb[2]), abs(bb[5]))
    cut = np.all(np.abs(z - lo) <= eps, axis=1) | np.all(np.abs(z - hi) <= eps, axis=1)
    return float(piece.volume()), float(area[~cut].sum())


def _merge(a: _Overlap | None, b: _Overlap | None) -> _Overlap | None:
    """One pair's overlap over two slabs."""
    if a is None or b is None:
        return a if b is None else b
    return _Overlap(np.concatenate([a.contact_z, b.contact_z]), a.volume + b.volume, a.area + b.area)


def body_pairs(names: list[str]) -> list[tuple[str, str]]:
    """Every pair of scene parts (in ``names`` order) that belong to different rigid bodies
    (:meth:`~prs_geom.mesh.assembly.Assembly.rigid_body`)."""
    return [(a, b) for i, a in enumerate(names) for b in names[i + 1:]
            if Assembly.rigid_body(a) != Assembly.rigid_body(b)]


def _corrected_profile(design: PRSDesign, screw: str, given: ThreadProfile | None) -> ThreadProfile | None:
    """The screw profile a check uses: ``given`` or the theoretical one for "corrected",
    None (the design's nominal screw) for "nominal"."""
    if screw != "corrected":
        return None
    return given if given is not None else theoretical_screw(design).profile


def _screw_fields(design: PRSDesign, screw: str, prof: ThreadProfile | None) -> dict[str, Any]:
    """The fields naming the screw of one check (``screw``, ``screw_pitch_diameter_mm``)."""
    return {"screw": screw,
            "screw_pitch_diameter_mm": 2.0 * (prof.pitch_radius if prof else 0.5 * design.screw.pitch_diameter_mm)}


def pair_overlaps(asm: Assembly, progress: ProgressFn = silent,
                  cache: dict[str, dict[Any, Any]] | None = None,
                  slab: tuple[float, float] | None = None,
                  keep: str = "all") -> dict[tuple[str, str], _Overlap | None]:
    """FCL collision of every pair of different rigid bodies; manifold3d overlap of the
    colliding ones. ``cache``: see :func:`check_assembly`.

    A pair whose bounds are apart (:mod:`prs_geom.checks.broad_phase`) has no collision and
    is not asked of FCL. The pairs that can touch are queried body pair by body pair; a
    mesh of at least :data:`SPLIT_FACES` triangles meets the other body through a BVH of
    only its faces near that body (:func:`_Queries.collision_object`), dropped when the
    body pair is done. Then the colliding pairs' overlap solids are computed, after the
    queries, so that the BVHs and the solids are not all held at once.

    ``slab``: keep only what lies between the planes z = slab (screw frame, mm): the
    contacts in [lo, hi) and the overlap solid trimmed to the slab (:func:`_trimmed`); a
    pair whose collision lies wholly outside the slab gives None.

    ``keep``: whether the BVHs and solids stay in ``cache`` for a next check of the same
    assembly ("all") or are freed as soon as they are used ("none": a whole-mesh BVH after
    its mesh's last query, before the solids are built; the solids at the end). The pair
    outcomes stay either way. A build frees them: keeping the roller's BVHs for the
    nominal-screw check saves that check 0.35 s of CPU but held 70 MB more at the checks
    worker's peak (default design: 279 against 245-253 MB USS).
    """
    if keep not in ("all", "none"):
        raise ValueError(f"keep={keep!r}: must be 'all' or 'none'")
    cache = cache if cache is not None else {}
    # None: FCL found no collision
    outcomes: dict[_PairKey, _Overlap | None] = cache.setdefault("pair", {})
    pairs = body_pairs(list(asm.placed))
    keys = {pair: _pair_key(asm.placed[pair[0]], asm.placed[pair[1]]) for pair in pairs}
    # one pair per new memo key: a pair of the same meshes at the same placements is asked once
    todo: list[tuple[str, str]] = []
    seen: set[_PairKey] = set()
    for pair in pairs:
        if keys[pair] not in outcomes and keys[pair] not in seen:
            seen.add(keys[pair])
            todo.append(pair)
    queries = _Queries(asm, cache)
    asked = [pair for pair in todo if queries.can_touch(*pair)]
    done = len(pairs) - len(asked)
    progress("interference pairs", done, len(pairs))
    for pair in set(todo) - set(asked):
        outcomes[keys[pair]] = None
    # with keep="none" a whole-mesh BVH goes after its mesh's last query
    left = Counter(id(asm.placed[name][0]) for pair in asked for name in pair)
    hits: dict[_PairKey, tuple[tuple[str, str], NDArray]] = {}
    for group in _by_body_pair(asked):
        for a, b in group:
            z = queries.contact_z(a, b)
            if z is None:
                outcomes[keys[(a, b)]] = None
            else:
                hits[keys[(a, b)]] = ((a, b), z)
            for name in (a, b):
                mesh_id = id(asm.placed[name][0])
                left[mesh_id] -= 1
                if not left[mesh_id] and keep == "none":
                    queries.forget_bvh(mesh_id)
            done += 1
            progress("interference pairs", done, len(pairs))
        queries.drop_slices()
    for key, ((a, b), z) in hits.items():
        outcomes[key] = queries.overlap(a, b, z, slab)
    if keep == "none":
        queries.release()
    return {pair: outcomes[keys[pair]] for pair in pairs}


#: A mesh with at least this many triangles meets another body through a BVH of its faces
#: near that body (:func:`~prs_geom.checks.broad_phase.near_faces`) when they are at most
#: half of it: the screw meets each roller through about a tenth of its triangles.
SPLIT_FACES = 30_000


def _by_body_pair(pairs: list[tuple[str, str]]) -> list[list[tuple[str, str]]]:
    """``pairs`` grouped by their two rigid bodies, groups in order of first appearance."""
    groups: dict[tuple[str, ...], list[tuple[str, str]]] = {}
    for a, b in pairs:
        groups.setdefault(tuple(sorted((Assembly.rigid_body(a), Assembly.rigid_body(b)))), []).append((a, b))
    return list(groups.values())


def _slice_bvh(vertices: NDArray, faces: NDArray) -> fcl.BVHModel:
    """The BVH of some faces of a mesh, with only the vertices they use (FCL's build time
    grows with the vertices it is given as well as with the faces)."""
    used, local = np.unique(faces, return_inverse=True)
    return bvh_model(vertices[used], local.reshape(faces.shape))


class _Queries:
    """The FCL and manifold3d work of :func:`pair_overlaps` on one assembly: the placed
    parts' bounds, their collision objects (whole-mesh BVHs kept in the cache, slices of
    large meshes only for the current body pair) and the overlap solids."""

    def __init__(self, asm: Assembly, cache: dict[str, dict[Any, Any]]) -> None:
        self.asm = asm
        # keyed by id(mesh) (and the placement): the mesh is kept beside what was built from it
        # so that the id stays its own
        self.bvhs: dict[int, tuple[trimesh.Trimesh, fcl.BVHModel]] = cache.setdefault("bvh", {})
        self.solids: dict[int, tuple[trimesh.Trimesh, manifold3d.Manifold]] = cache.setdefault("solid", {})
        # the bounds hold every mesh that was in a queried pair: its id, a memo key's part,
        # stays its own while the cache lives
        self.bounds: dict[tuple[int, bytes], tuple[trimesh.Trimesh, PlacedBounds]] = cache.setdefault("bounds", {})
        self.edges: dict[int, tuple[trimesh.Trimesh, float]] = cache.setdefault("edge", {})
        self.objects: dict[str, fcl.CollisionObject] = {}
        self.slices: dict[tuple[str, str], fcl.CollisionObject | None] = {}
        # the face boxes of the one large mesh being sliced
        self.boxes: dict[str, tuple[NDArray, NDArray]] = {}
        self.placements = Counter(id(mesh) for mesh, _, _ in asm.placed.values())

    def placed_bounds(self, name: str) -> PlacedBounds:
        mesh, T, _ = self.asm.placed[name]
        key = (id(mesh), np.asarray(T, dtype=np.float64).tobytes())
        if key not in self.bounds:
            if id(mesh) not in self.edges:
                self.edges[id(mesh)] = (mesh, longest_edge(mesh.vertices, mesh.faces))
            self.bounds[key] = (mesh, placed_bounds(mesh.vertices, mesh.faces, T, self.edges[id(mesh)][1]))
        return self.bounds[key][1]

    def can_touch(self, a: str, b: str) -> bool:
        return can_touch(self.placed_bounds(a), self.placed_bounds(b))

    def _whole(self, name: str) -> fcl.CollisionObject:
        if name not in self.objects:
            mesh, T, _ = self.asm.placed[name]
            if id(mesh) not in self.bvhs:
                self.bvhs[id(mesh)] = (mesh, bvh_model(np.asarray(mesh.vertices), np.asarray(mesh.faces)))
            self.objects[name] = fcl.CollisionObject(self.bvhs[id(mesh)][1], fcl.Transform(T[:3, :3], T[:3, 3]))
        return self.objects[name]

    def collision_object(self, name: str, other: str) -> tuple[fcl.CollisionObject, bool]:
        """``name``'s collision object for a query against ``other`` and whether it is a
        slice: of a large mesh, its faces near ``other``'s rigid body; else the whole mesh's
        BVH."""
        mesh, T, _ = self.asm.placed[name]
        if len(mesh.faces) < SPLIT_FACES or self.placements[id(mesh)] > 1:
            # a mesh placed several times (the rollers) keeps one BVH for all its placements
            return self._whole(name), False
        body = Assembly.rigid_body(other)
        if (name, body) not in self.slices:
            parts = [self.placed_bounds(n) for n in self.asm.placed if Assembly.rigid_body(n) == body]
            lo = np.min([p.lo for p in parts], axis=0)
            hi = np.max([p.hi for p in parts], axis=0)
            faces = np.asarray(mesh.faces)
            if name not in self.boxes:
                self.boxes = {name: face_boxes(mesh.vertices, faces, T)}
            near = near_faces(self.boxes[name], lo, hi)
            self.slices[(name, body)] = None if 2 * len(near) > len(faces) else fcl.CollisionObject(
                _slice_bvh(np.asarray(mesh.vertices), faces[near]), fcl.Transform(T[:3, :3], T[:3, 3]))
        piece = self.slices[(name, body)]
        return (piece, True) if piece is not None else (self._whole(name), False)

    def release(self) -> None:
        """Free the BVHs and the solids. The bounds stay: they keep every mesh of a memo key
        alive, so that its id is never another mesh's."""
        self.objects.clear()
        self.slices.clear()
        self.bvhs.clear()
        self.solids.clear()

    def forget_bvh(self, mesh_id: int) -> None:
        """Free the whole-mesh BVH of the mesh ``mesh_id`` and the collision objects on it."""
        self.bvhs.pop(mesh_id, None)
        for name in [n for n in self.objects if id(self.asm.placed[n][0]) == mesh_id]:
            del self.objects[name]

    def drop_slices(self) -> None:
        """Free the slices of the body pair just done."""
        self.slices.clear()

    def contact_z(self, a: str, b: str) -> NDArray | None:
        """z (mm, screw frame) of FCL's contacts of ``a`` and ``b`` in FCL's order, None when
        they do not collide."""
        # the contact request straight away, not a boolean one first: on a pair that does not
        # collide both traverse the same BVH nodes and cost the same (measured), and the
        # contact count and the teeth must come from this request on the pairs that do
        (obj_a, sliced_a), (obj_b, sliced_b) = self.collision_object(a, b), self.collision_object(b, a)
        res = self._collide(obj_a, obj_b)
        if res is not None and len(res.contacts) >= MAX_CONTACTS and (sliced_a or sliced_b):
            # FCL stops at MAX_CONTACTS: which ones it gives depends on the BVH, so a
            # capped pair is asked again of the whole meshes, as a check without slices asks
            res = self._collide(self._whole(a), self._whole(b))
        if res is None:
            return None
        return np.fromiter((c.pos[2] for c in res.contacts), dtype=np.float64, count=len(res.contacts))

    @staticmethod
    def _collide(a: fcl.CollisionObject, b: fcl.CollisionObject) -> fcl.CollisionResult | None:
        req = fcl.CollisionRequest(num_max_contacts=MAX_CONTACTS, enable_contact=True)
        res = fcl.CollisionResult()
        return res if fcl.collide(a, b, req, res) else None

    def solid(self, name: str) -> manifold3d.Manifold:
        mesh, T, _ = self.asm.placed[name]
        if id(mesh) not in self.solids:
            self.solids[id(mesh)] = (mesh, to_manifold(mesh.vertices, mesh.faces))
        return self.solids[id(mesh)][1].transform(np.ascontiguousarray(T[:3, :4]))

    def overlap(self, a: str, b: str, z: NDArray, slab: tuple[float, float] | None) -> _Overlap | None:
        """The overlap of two colliding parts whose FCL contacts are at heights ``z``."""
        inter = self.solid(a) ^ self.solid(b)
        if slab is None:
            return _Overlap(z, float(inter.volume()), float(inter.surface_area()))
        z = z[(z >= slab[0]) & (z < slab[1])]
        volume, area = _trimmed(inter, slab) if not inter.is_empty() else (0.0, 0.0)
        return _Overlap(z, volume, area) if len(z) or volume > 0.0 else None


def _section(design: PRSDesign, overlaps: dict[tuple[str, str], _Overlap | None], tol: float,
             seconds: float) -> dict[str, Any]:
    """The ``checks.interference`` fields of one screw from the pair overlaps (pair order)."""
    p = design.thread.pitch_mm
    found, touching = [], []
    for (a, b), hit in overlaps.items():
        if hit is None:
            continue
        thick = 2.0 * hit.volume / hit.area if hit.area > 0 else 0.0
        # tooth j spans ((j - 1) p, j p] along the nut/roller thread (tooth 1 at the loaded end)
        tooth = np.clip(np.ceil(hit.contact_z / p), 1, design.thread.engaged_teeth)
        teeth = np.unique(tooth).astype(int).tolist()
        row = {"pair": [a, b], "volume_mm3": hit.volume, "mean_thickness_mm": thick,
               "fcl_contacts": len(hit.contact_z), "teeth": teeth}
        (found if thick > 2.0 * tol else touching).append(row)
    return {
        "found": bool(found),
        "pairs": found,
        "contact_within_tolerance": touching,
        "pairs_checked": len(overlaps),
        "chord_tolerance_mm": tol,
        "rule": "overlap thicker than 2 x chord tolerance (mean thickness 2V/A) is interference",
        "time_s": seconds,
    }


def check_assembly(asm: Assembly, tol: float, progress: ProgressFn = silent,
                   cache: dict[str, dict[Any, Any]] | None = None, keep: str = "all") -> dict[str, Any]:
    """Collision of every pair of different rigid bodies; overlap volumes of colliding pairs.

    Parameters
    ----------
    asm : Assembly
        The placed parts (``asm.placed``: mesh, transform, kind).
    tol : float
        Chordal tolerance (mm) of the meshes: overlaps no thicker than 2 ``tol`` are
        ``contact_within_tolerance``.
    progress : ProgressFn
        Called once per pair.
    cache : dict, optional
        Kept between calls: the FCL BVHs and manifold3d solids by mesh, and the outcome of
        every pair by its two meshes and placements. A second check of an assembly that
        shares meshes (the nominal-screw check reuses the roller, nut and gear meshes of the
        corrected one) builds only the new BVHs and solids and queries only the pairs that
        involve a new mesh; the other pairs are the same computation on the same inputs, so
        their stored outcome is what a new query would give.
    keep : {"all", "none"}
        Whether the BVHs and solids stay in ``cache`` for the next check (:func:`pair_overlaps`).

    Returns
    -------
    dict
        The ``checks.interference`` fields of one screw (``found``, ``pairs``,
        ``contact_within_tolerance``, ...).
    """
    t0 = time.perf_counter()
    overlaps = pair_overlaps(asm, progress, cache, keep=keep)
    return _section(asm.design, overlaps, tol, time.perf_counter() - t0)


def interference(design: PRSDesign, screw: str = "corrected", tol: float | None = None,
                 progress: ProgressFn = silent, screw_profile: ThreadProfile | None = None) -> dict[str, Any]:
    """Interference check with the ``"corrected"`` (theoretical) or ``"nominal"`` screw.

    The corrected screw's profile is ``screw_profile`` (from the contact stage; solved here
    when not given). A design longer than :data:`~prs_geom.mesh.budget.CHECK_WINDOW_TEETH` teeth is checked in
    axial windows (:func:`windowed_interference_checks`) unless ``tol`` is given.
    """
    if tol is None and (check_windows(design) is not None or check_span(design) is not None):
        return _windowed(design, _corrected_profile(design, screw, screw_profile), progress, (screw,))[screw]
    return _interference(design, screw, tol, progress, screw_profile)[0]


def _interference(design: PRSDesign, screw: str, tol: float | None, progress: ProgressFn,
                  screw_profile: ThreadProfile | None, reuse: Assembly | None = None,
                  cache: dict[str, dict[Any, Any]] | None = None, keep: str = "all") -> tuple[dict[str, Any], Assembly]:
    """:func:`interference` and its assembly; ``reuse``/``cache``/``keep``: see
    :func:`~prs_geom.mesh.assembly.build_assembly` and :func:`check_assembly`."""
    tol = tol or min(design.mesh.chord_tolerance_mm, CHECK_TOLERANCE_MM)
    prof = _corrected_profile(design, screw, screw_profile)
    asm = build_assembly(design, tol=tol, screw_profile=prof, progress=progress, reuse=reuse)
    out = check_assembly(asm, tol, progress, cache, keep)
    out.update(_screw_fields(design, screw, prof))
    return out, asm


def interference_checks(design: PRSDesign, screw_profile: ThreadProfile,
                        progress: ProgressFn = silent) -> dict[str, Any]:
    """The ``checks.interference`` section: the assembly with the theoretical screw
    (``screw_profile``) and, in ``nominal_screw``, with the nominal one.

    The roller, nut and gear meshes are built once for both, and the nominal check queries
    only the pairs with the screw: every other pair is the same two meshes at the same
    placements in both assemblies (see :func:`check_assembly`). The BVHs and solids are
    freed after each check (``keep="none"``, :func:`pair_overlaps`).

    A design longer than :data:`~prs_geom.mesh.budget.CHECK_WINDOW_TEETH` teeth is checked window by window
    (:func:`check_windows`, :func:`windowed_interference_checks`).
    """
    if check_windows(design) is not None or check_span(design) is not None:
        return windowed_interference_checks(design, screw_profile, progress)
    cache: dict[str, dict[Any, Any]] = {}
    corrected, asm = _interference(design, "corrected", None, progress, screw_profile, cache=cache, keep="none")
    nominal, _ = _interference(design, "nominal", None, progress, None, reuse=asm, cache=cache, keep="none")
    corrected["nominal_screw"] = nominal
    return corrected


def windowed_interference_checks(design: PRSDesign, screw_profile: ThreadProfile,
                                 progress: ProgressFn = silent) -> dict[str, Any]:
    """:func:`interference_checks` in axial windows, so that memory is bounded by a window.

    For each slab of :func:`~prs_geom.mesh.budget.check_windows` every part is meshed over
    the slab widened by one pitch on each side
    (:func:`~prs_geom.mesh.assembly.window_assembly`; the end gears are meshed once), both
    screws are checked against it, and only what lies inside the slab is kept: FCL contacts
    with lo <= z < hi and the overlap solid trimmed to the slab (:func:`pair_overlaps`).
    Then the meshes, BVHs and solids are freed.

    Over the slabs the overlap volumes and the surface areas (without the cut faces) add
    up to those of the whole solids, so the mean thickness 2 V / A and the verdict are those
    of a whole check up to the meshes' end-curve differences (measured: volumes within
    1e-13 relative, the same contacts and teeth; ``tests/test_interference_windows.py``).
    The FCL contact count is the sum over the slabs: FCL reports at most
    :data:`MAX_CONTACTS` per query, so it can exceed a whole check's count.
    ``axial_windows`` in the result gives the number of slabs.
    """
    both = _windowed(design, screw_profile, progress, ("corrected", "nominal"))
    both["corrected"]["nominal_screw"] = both["nominal"]
    return both["corrected"]


def _windowed(design: PRSDesign, screw_profile: ThreadProfile | None, progress: ProgressFn,
              screws: tuple[str, ...]) -> dict[str, dict[str, Any]]:
    """The windowed check of :func:`windowed_interference_checks` with each screw of
    ``screws`` ("corrected": ``screw_profile``, "nominal": the design's); the roller, nut and
    gear meshes of a window are shared by the screws."""
    from prs_geom.mesh.assembly import end_gears, mechanism_parts, scene_names, window_assembly

    tol = min(design.mesh.chord_tolerance_mm, CHECK_TOLERANCE_MM)
    windows = check_windows(design) or [(-np.inf, np.inf)]
    margin = design.thread.pitch_mm
    # an actuator's screw is meshed over the nut assembly only (check_span)
    span = check_span(design) or (-np.inf, np.inf)
    gear_parts = end_gears(design, tol)
    mech_parts = mechanism_parts(design, tol)
    totals: dict[str, dict[tuple[str, str], _Overlap | None]] = {screw: {} for screw in screws}
    seconds = {screw: 0.0 for screw in screws}
    # one window (an actuator's nut span, the default design): its pairs are the progress;
    # with several, the windows are (a pair count per window would run back to 0 each time)
    pair_progress = progress if len(windows) == 1 else silent
    for i, (lo, hi) in enumerate(windows):
        cache: dict[str, dict[Any, Any]] = {}
        widened = (max(lo - margin, span[0]), min(hi + margin, span[1]))
        first: Assembly | None = None
        for j, screw in enumerate(screws):
            t0 = time.perf_counter()
            prof = screw_profile if screw == "corrected" else None
            piece = window_assembly(design, tol, widened, prof, gear_parts, reuse=first, mech_parts=mech_parts)
            first = first or piece
            for pair, hit in pair_overlaps(piece, pair_progress, cache, (lo, hi), "none").items():
                totals[screw][pair] = _merge(totals[screw].get(pair), hit)
            seconds[screw] += time.perf_counter() - t0
        del first, piece, cache
        progress("interference windows", i + 1, len(windows))
    # every pair of the whole assembly: those never together in a window lie in different
    # slabs and cannot touch
    pairs = body_pairs(scene_names(design, gear_parts is not None, mech_parts is not None))
    out: dict[str, dict[str, Any]] = {}
    for screw, overlaps in totals.items():
        if not set(overlaps) <= set(pairs):   # pragma: no cover - the windows place only scene parts
            raise RuntimeError(f"windowed check met pairs outside the scene: {sorted(set(overlaps) - set(pairs))}")
        section = _section(design, {pair: overlaps.get(pair) for pair in pairs}, tol, seconds[screw])
        if len(windows) > 1:
            section["axial_windows"] = len(windows)
        section.update(_screw_fields(design, screw, screw_profile if screw == "corrected" else None))
        out[screw] = section
    return out
