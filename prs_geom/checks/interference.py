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
from prs_geom.analysis.contact import theoretical_screw
from prs_geom.model.design import PRSDesign
from prs_geom.checks.fcl import bvh_model
from prs_geom.progress import ProgressFn, silent

MAX_CONTACTS = 20000
#: The check meshes at no coarser than this (mm), so that the overlap allowed for chordal
#: error (2 x tolerance) stays far below the interference it must detect.
CHECK_TOLERANCE_MM = 0.002


def _manifold(mesh: trimesh.Trimesh) -> manifold3d.Manifold:
    return manifold3d.Manifold(manifold3d.Mesh64(np.ascontiguousarray(mesh.vertices, dtype=np.float64),
                                                 np.ascontiguousarray(mesh.faces, dtype=np.uint64)))


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
    d = asm.design
    cache = cache if cache is not None else {}
    # keyed by id(mesh); the mesh is kept beside its BVH so that the id stays its own
    bvhs: dict[int, tuple[trimesh.Trimesh, fcl.BVHModel]] = cache.setdefault("bvh", {})
    bases: dict[int, tuple[trimesh.Trimesh, manifold3d.Manifold]] = cache.setdefault("solid", {})
    # None: FCL found no collision
    outcomes: dict[_PairKey, _Overlap | None] = cache.setdefault("pair", {})
    names = list(asm.placed)
    pairs = [(a, b) for i, a in enumerate(names) for b in names[i + 1:]
             if asm.rigid_body(a) != asm.rigid_body(b)]
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
            bases[id(mesh)] = (mesh, _manifold(mesh))
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
        return _Overlap(z, float(inter.volume()), float(inter.surface_area()))

    p = d.thread.pitch_mm
    found, touching = [], []
    for i, (a, b) in enumerate(pairs):
        key = _pair_key(asm.placed[a], asm.placed[b])
        if key not in outcomes:
            outcomes[key] = outcome(a, b)
        hit = outcomes[key]
        if hit is not None:
            thick = 2.0 * hit.volume / hit.area if hit.area > 0 else 0.0
            # tooth j spans ((j - 1) p, j p] along the nut/roller thread (tooth 1 at the loaded end)
            tooth = np.clip(np.ceil(hit.contact_z / p), 1, d.thread.engaged_teeth)
            teeth = np.unique(tooth).astype(int).tolist()
            row = {"pair": [a, b], "volume_mm3": hit.volume, "mean_thickness_mm": thick,
                   "fcl_contacts": len(hit.contact_z), "teeth": teeth}
            (found if thick > 2.0 * tol else touching).append(row)
        progress("interference pairs", i + 1, len(pairs))
    return {
        "found": bool(found),
        "pairs": found,
        "contact_within_tolerance": touching,
        "pairs_checked": len(pairs),
        "chord_tolerance_mm": tol,
        "rule": "overlap thicker than 2 x chord tolerance (mean thickness 2V/A) is interference",
        "time_s": time.perf_counter() - t0,
    }


def interference(design: PRSDesign, screw: str = "corrected", tol: float | None = None,
                 progress: ProgressFn = silent, screw_profile: ThreadProfile | None = None) -> dict[str, Any]:
    """Interference check with the ``"corrected"`` (theoretical) or ``"nominal"`` screw.

    The corrected screw's profile is ``screw_profile`` (from the contact stage; solved here
    when not given).
    """
    return _interference(design, screw, tol, progress, screw_profile)[0]


def _interference(design: PRSDesign, screw: str, tol: float | None, progress: ProgressFn,
                  screw_profile: ThreadProfile | None, reuse: Assembly | None = None,
                  cache: dict[str, dict[Any, Any]] | None = None) -> tuple[dict[str, Any], Assembly]:
    """:func:`interference` and its assembly; ``reuse``/``cache``: see
    :func:`~prs_geom.mesh.assembly.build_assembly` and :func:`check_assembly`."""
    tol = tol or min(design.mesh.chord_tolerance_mm, CHECK_TOLERANCE_MM)
    prof = None
    if screw == "corrected":
        prof = screw_profile if screw_profile is not None else theoretical_screw(design).profile
    asm = build_assembly(design, tol=tol, screw_profile=prof, progress=progress, reuse=reuse)
    out = check_assembly(asm, tol, progress, cache)
    out["screw"] = screw
    out["screw_pitch_diameter_mm"] = 2.0 * (prof.pitch_radius if prof else 0.5 * design.screw.pitch_diameter_mm)
    return out, asm


def interference_checks(design: PRSDesign, screw_profile: ThreadProfile,
                        progress: ProgressFn = silent) -> dict[str, Any]:
    """The ``checks.interference`` section: the assembly with the theoretical screw
    (``screw_profile``) and, in ``nominal_screw``, with the nominal one.

    The roller, nut and gear meshes, their BVHs and solids are built once for both, and the
    nominal check queries only the pairs with the screw: every other pair is the same two
    meshes at the same placements in both assemblies (see :func:`check_assembly`).
    """
    cache: dict[str, dict[Any, Any]] = {}
    corrected, asm = _interference(design, "corrected", None, progress, screw_profile, cache=cache)
    nominal, _ = _interference(design, "nominal", None, progress, None, reuse=asm, cache=cache)
    corrected["nominal_screw"] = nominal
    return corrected
