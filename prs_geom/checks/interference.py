"""Interference check of the whole assembly (``prs-geom check``).

Every pair of scene parts that belong to different rigid bodies is tested with FCL
(one BVH per distinct mesh, built once, placed with transforms). Where FCL reports a
collision, manifold3d computes the intersection solid (FCL's penetration depth is not
reliable for meshes); its volume and mean thickness 2 V / A (A its surface area) are
reported, and the teeth involved are read from the FCL contact positions. A pair of meshes
already checked at the same placements is not checked again: the nominal-screw check shares
every part but the screw with the corrected one, so it queries only the pairs with the screw.

Mesh tolerance: two meshes that touch analytically (zero design clearance) may overlap by
up to the sum of their chordal deviations. An overlap whose mean thickness is at most
twice the chordal tolerance is therefore reported as ``contact_within_tolerance``, not as
interference; anything thicker is interference.
"""
from __future__ import annotations

import time
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
from prs_geom.checks.fcl import bvh_model
from prs_geom.mesh.budget import CHECK_TOLERANCE_MM, check_span, check_windows
from prs_geom.runtime.progress import ProgressFn, silent

__all__ = [
    "MAX_CONTACTS", "body_pairs", "check_assembly", "interference", "interference_checks", "pair_overlaps",
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
                  slab: tuple[float, float] | None = None) -> dict[tuple[str, str], _Overlap | None]:
    """FCL collision of every pair of different rigid bodies; manifold3d overlap of the
    colliding ones. ``cache``: see :func:`check_assembly`.

    ``slab``: keep only what lies between the planes z = slab (screw frame, mm): the
    contacts in [lo, hi) and the overlap solid trimmed to the slab (:func:`_trimmed`); a
    pair whose collision lies wholly outside the slab gives None.
    """
    cache = cache if cache is not None else {}
    # keyed by id(mesh); the mesh is kept beside its BVH so that the id stays its own
    bvhs: dict[int, tuple[trimesh.Trimesh, fcl.BVHModel]] = cache.setdefault("bvh", {})
    bases: dict[int, tuple[trimesh.Trimesh, manifold3d.Manifold]] = cache.setdefault("solid", {})
    # None: FCL found no collision
    outcomes: dict[_PairKey, _Overlap | None] = cache.setdefault("pair", {})
    pairs = body_pairs(list(asm.placed))
    objs: dict[str, fcl.CollisionObject] = {}

    def collision_object(name: str) -> fcl.CollisionObject:
        # built on first use: a part whose pairs are all reused needs no BVH
        if name not in objs:
            mesh, T, _ = asm.placed[name]
            if id(mesh) not in bvhs:
                bvhs[id(mesh)] = (mesh, bvh_model(np.asarray(mesh.vertices), np.asarray(mesh.faces)))
            objs[name] = fcl.CollisionObject(bvhs[id(mesh)][1], fcl.Transform(T[:3, :3], T[:3, 3]))
        return objs[name]

    def solid(name: str) -> manifold3d.Manifold:
        mesh, T, _ = asm.placed[name]
        if id(mesh) not in bases:
            bases[id(mesh)] = (mesh, to_manifold(mesh.vertices, mesh.faces))
        return bases[id(mesh)][1].transform(np.ascontiguousarray(T[:3, :4]))

    def outcome(a: str, b: str) -> _Overlap | None:
        # the contact request straight away, not a boolean one first: on a pair that does not
        # collide both traverse the same BVH nodes and cost the same (measured), and the
        # contact count and the teeth must come from this request on the pairs that do
        req = fcl.CollisionRequest(num_max_contacts=MAX_CONTACTS, enable_contact=True)
        res = fcl.CollisionResult()
        if not fcl.collide(collision_object(a), collision_object(b), req, res):
            return None
        inter = solid(a) ^ solid(b)
        z = np.fromiter((c.pos[2] for c in res.contacts), dtype=np.float64, count=len(res.contacts))
        if slab is None:
            return _Overlap(z, float(inter.volume()), float(inter.surface_area()))
        z = z[(z >= slab[0]) & (z < slab[1])]
        volume, area = _trimmed(inter, slab) if not inter.is_empty() else (0.0, 0.0)
        return _Overlap(z, volume, area) if len(z) or volume > 0.0 else None

    out: dict[tuple[str, str], _Overlap | None] = {}
    for i, (a, b) in enumerate(pairs):
        key = _pair_key(asm.placed[a], asm.placed[b])
        if key not in outcomes:
            outcomes[key] = outcome(a, b)
        out[(a, b)] = outcomes[key]
        progress("interference pairs", i + 1, len(pairs))
    return out


def _forget(cache: dict[str, dict[Any, Any]], mesh: trimesh.Trimesh) -> None:
    """Drop the BVH and the solid of ``mesh`` from a :func:`check_assembly` cache: a screw's,
    once its pairs are done, since the next check (the other screw) shares every mesh but
    that one. FCL's BVH takes about 490 MB per million triangles; the default design's screw,
    0.35 M triangles at the check tolerance, would otherwise stay beside the next screw's
    (measured on the default design: the checks' peak 537 -> 467 MB). Its pair outcomes stay: they are small and
    keyed by the mesh, which the caller still holds."""
    cache.get("bvh", {}).pop(id(mesh), None)
    cache.get("solid", {}).pop(id(mesh), None)


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
                   cache: dict[str, dict[Any, Any]] | None = None) -> dict[str, Any]:
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

    Returns
    -------
    dict
        The ``checks.interference`` fields of one screw (``found``, ``pairs``,
        ``contact_within_tolerance``, ...).
    """
    t0 = time.perf_counter()
    overlaps = pair_overlaps(asm, progress, cache)
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
                  cache: dict[str, dict[Any, Any]] | None = None) -> tuple[dict[str, Any], Assembly]:
    """:func:`interference` and its assembly; ``reuse``/``cache``: see
    :func:`~prs_geom.mesh.assembly.build_assembly` and :func:`check_assembly`."""
    tol = tol or min(design.mesh.chord_tolerance_mm, CHECK_TOLERANCE_MM)
    prof = _corrected_profile(design, screw, screw_profile)
    asm = build_assembly(design, tol=tol, screw_profile=prof, progress=progress, reuse=reuse)
    out = check_assembly(asm, tol, progress, cache)
    out.update(_screw_fields(design, screw, prof))
    return out, asm


def interference_checks(design: PRSDesign, screw_profile: ThreadProfile,
                        progress: ProgressFn = silent) -> dict[str, Any]:
    """The ``checks.interference`` section: the assembly with the theoretical screw
    (``screw_profile``) and, in ``nominal_screw``, with the nominal one.

    The roller, nut and gear meshes, their BVHs and solids are built once for both, and the
    nominal check queries only the pairs with the screw: every other pair is the same two
    meshes at the same placements in both assemblies (see :func:`check_assembly`).

    A design longer than :data:`~prs_geom.mesh.budget.CHECK_WINDOW_TEETH` teeth is checked window by window
    (:func:`check_windows`, :func:`windowed_interference_checks`).
    """
    if check_windows(design) is not None or check_span(design) is not None:
        return windowed_interference_checks(design, screw_profile, progress)
    cache: dict[str, dict[Any, Any]] = {}
    corrected, asm = _interference(design, "corrected", None, progress, screw_profile, cache=cache)
    _forget(cache, asm.placed["screw"][0])
    nominal, _ = _interference(design, "nominal", None, progress, None, reuse=asm, cache=cache)
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
    for i, (lo, hi) in enumerate(windows):
        cache: dict[str, dict[Any, Any]] = {}
        widened = (max(lo - margin, span[0]), min(hi + margin, span[1]))
        first: Assembly | None = None
        for screw in screws:
            t0 = time.perf_counter()
            prof = screw_profile if screw == "corrected" else None
            piece = window_assembly(design, tol, widened, prof, gear_parts, reuse=first, mech_parts=mech_parts)
            first = first or piece
            for pair, hit in pair_overlaps(piece, silent, cache, (lo, hi)).items():
                totals[screw][pair] = _merge(totals[screw].get(pair), hit)
            _forget(cache, piece.placed["screw"][0])
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
