"""Interference check of the whole assembly (``prs-geom check``).

Every pair of scene parts that belong to different rigid bodies is tested with FCL
(one BVH per distinct mesh, built once, placed with transforms). Where FCL reports a
collision, manifold3d computes the intersection solid (FCL's penetration depth is not
reliable for meshes); its volume and mean thickness 2 V / A (A its surface area) are
reported, and the teeth involved are read from the FCL contact positions.

Mesh tolerance: two meshes that touch analytically (zero design clearance) may overlap by
up to the sum of their chordal deviations. An overlap whose mean thickness is at most
twice the chordal tolerance is therefore reported as ``contact_within_tolerance``, not as
interference; anything thicker is interference.
"""
from __future__ import annotations

import time
from typing import Any

import fcl
import manifold3d
import numpy as np
import trimesh

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


def check_assembly(asm: Assembly, tol: float, progress: ProgressFn = silent,
                   cache: dict[str, dict[int, Any]] | None = None) -> dict[str, Any]:
    """Collision of every pair of different rigid bodies; overlap volumes of colliding pairs.

    ``cache`` keeps the FCL BVHs and manifold3d solids by mesh between calls, so a second
    check of an assembly that shares meshes builds only what is new.
    """
    t0 = time.perf_counter()
    d = asm.design
    cache = cache if cache is not None else {}
    # keyed by id(mesh); the mesh is kept beside its BVH so that the id stays its own
    bvhs: dict[int, tuple[trimesh.Trimesh, fcl.BVHModel]] = cache.setdefault("bvh", {})
    objs = {}
    for name, (mesh, T, _) in asm.placed.items():
        if id(mesh) not in bvhs:
            bvhs[id(mesh)] = (mesh, bvh_model(np.asarray(mesh.vertices), np.asarray(mesh.faces)))
        g = bvhs[id(mesh)][1]
        objs[name] = fcl.CollisionObject(g, fcl.Transform(T[:3, :3], T[:3, 3]))
    names = list(asm.placed)
    pairs = [(a, b) for i, a in enumerate(names) for b in names[i + 1:]
             if asm.rigid_body(a) != asm.rigid_body(b)]
    p = d.thread.pitch_mm
    found, touching = [], []
    bases: dict[int, tuple[trimesh.Trimesh, manifold3d.Manifold]] = cache.setdefault("solid", {})

    def solid(name: str) -> manifold3d.Manifold:
        mesh, T, _ = asm.placed[name]
        if id(mesh) not in bases:
            bases[id(mesh)] = (mesh, _manifold(mesh))
        return bases[id(mesh)][1].transform(np.ascontiguousarray(T[:3, :4]))

    for i, (a, b) in enumerate(pairs):
        req = fcl.CollisionRequest(num_max_contacts=MAX_CONTACTS, enable_contact=True)
        res = fcl.CollisionResult()
        if fcl.collide(objs[a], objs[b], req, res):
            inter = solid(a) ^ solid(b)
            vol = float(inter.volume())
            area = float(inter.surface_area())
            thick = 2.0 * vol / area if area > 0 else 0.0
            z = np.array([c.pos[2] for c in res.contacts])
            # tooth j spans ((j - 1) p, j p] along the nut/roller thread (tooth 1 at the loaded end)
            teeth = sorted({int(t) for t in np.clip(np.ceil(z / p), 1, d.thread.engaged_teeth)})
            row = {"pair": [a, b], "volume_mm3": vol, "mean_thickness_mm": thick,
                   "fcl_contacts": len(res.contacts), "teeth": teeth}
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
                  cache: dict[str, dict[int, Any]] | None = None) -> tuple[dict[str, Any], Assembly]:
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
    (``screw_profile``) and, in ``nominal_screw``, with the nominal one; the roller and nut
    meshes, their BVHs and solids are built once for both."""
    cache: dict[str, dict[int, Any]] = {}
    corrected, asm = _interference(design, "corrected", None, progress, screw_profile, cache=cache)
    nominal, _ = _interference(design, "nominal", None, progress, None, reuse=asm, cache=cache)
    corrected["nominal_screw"] = nominal
    return corrected
