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

from .assembly import Assembly, build_assembly
from .contact import theoretical_screw
from .design import PRSDesign
from .fcl_verify import bvh_model
from .progress import ProgressFn, silent

MAX_CONTACTS = 20000
#: The check meshes at no coarser than this (mm), so that the overlap allowed for chordal
#: error (2 x tolerance) stays far below the interference it must detect.
CHECK_TOLERANCE_MM = 0.002


def _manifold(mesh: trimesh.Trimesh) -> manifold3d.Manifold:
    return manifold3d.Manifold(manifold3d.Mesh64(np.ascontiguousarray(mesh.vertices, dtype=np.float64),
                                                 np.ascontiguousarray(mesh.faces, dtype=np.uint64)))


def check_assembly(asm: Assembly, tol: float, progress: ProgressFn = silent) -> dict[str, Any]:
    """Collision of every pair of different rigid bodies; overlap volumes of colliding pairs."""
    t0 = time.perf_counter()
    d = asm.design
    bvhs: dict[int, fcl.BVHModel] = {}
    objs = {}
    for name, (mesh, T, _) in asm.placed.items():
        if id(mesh) not in bvhs:
            bvhs[id(mesh)] = bvh_model(np.asarray(mesh.vertices), np.asarray(mesh.faces))
        g = bvhs[id(mesh)]
        objs[name] = fcl.CollisionObject(g, fcl.Transform(T[:3, :3], T[:3, 3]))
    names = list(asm.placed)
    pairs = [(a, b) for i, a in enumerate(names) for b in names[i + 1:]
             if asm.rigid_body(a) != asm.rigid_body(b)]
    p = d.thread.pitch_mm
    found, touching = [], []
    bases: dict[int, manifold3d.Manifold] = {}

    def solid(name: str) -> manifold3d.Manifold:
        mesh, T, _ = asm.placed[name]
        if id(mesh) not in bases:
            bases[id(mesh)] = _manifold(mesh)
        return bases[id(mesh)].transform(np.ascontiguousarray(T[:3, :4]))

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
                 progress: ProgressFn = silent) -> dict[str, Any]:
    """Interference check with the ``"corrected"`` (theoretical) or ``"nominal"`` screw."""
    tol = tol or min(design.mesh.chord_tolerance_mm, CHECK_TOLERANCE_MM)
    prof = theoretical_screw(design).profile if screw == "corrected" else None
    asm = build_assembly(design, tol=tol, screw_profile=prof, progress=progress)
    out = check_assembly(asm, tol, progress)
    out["screw"] = screw
    out["screw_pitch_diameter_mm"] = 2.0 * (prof.pitch_radius if prof else 0.5 * design.screw.pitch_diameter_mm)
    return out
