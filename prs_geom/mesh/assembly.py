"""Part meshes of a design and their placement as an assembly.

Frames and roller phasing are those of :mod:`prs_geom.geometry.frames`; this module meshes
each part once in its own frame and places the rollers as transforms of one roller mesh.

Simplified parts (named as such in the report): the roller end spur teeth are cylinders
of the roller root diameter, the nut ring gears are rings whose bore is the nut crest
diameter, each ``GEAR_LENGTH_PITCHES`` pitches long beyond the thread ends.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import trimesh
from numpy.typing import NDArray

from prs_geom.geometry.frames import (FIRST_MID_PITCHES, part_warps, roller_transform, screw_z_range,
                                     thread_length)
from prs_geom.model.design import PRSDesign
from prs_geom.geometry.datum import datum_mark
from prs_geom.mesh.thread import ThreadMesh, cut_datum_mark, thread_mesh
from prs_geom.geometry.profiles import ThreadProfile, ThreadProfiles
from prs_geom.progress import ProgressFn, silent

GEAR_LENGTH_PITCHES = 2.0

SIMPLIFIED_PARTS = {
    "roller_gear": "roller end spur teeth simplified to plain cylinders of the roller root diameter",
    "nut_ring_gear": "nut internal ring gears simplified to plain rings with the nut crest (bore) diameter",
}


def build_part(design: PRSDesign, part: str, tol: float | None = None,
               profiles: ThreadProfiles | None = None,
               screw_profile: ThreadProfile | None = None) -> ThreadMesh:
    """Mesh of one part in its own frame, with its angular datum mark cut into face A
    (the end face at the part's lower z, :mod:`prs_geom.geometry.datum`).

    ``screw_profile`` replaces the design's screw profile (e.g. with the corrected pitch
    diameter of the contact analysis).
    """
    tol = tol or design.mesh.chord_tolerance_mm
    prof = profiles or ThreadProfiles.from_design(design)
    p = design.thread.pitch_mm
    warps = part_warps(design)
    first_mid = FIRST_MID_PITCHES[part] * p
    if part == "screw":
        lo, hi = screw_z_range(design)
        profile = screw_profile or prof.screw
        tm = thread_mesh(profile, lo, hi, tol, first_mid, warps["screw"])
    elif part == "roller":
        tm = thread_mesh(prof.roller, 0.0, thread_length(design), tol, first_mid, warps["roller"])
    elif part == "nut":
        tm = thread_mesh(prof.nut, 0.0, thread_length(design), tol, first_mid, warps["nut"],
                         body_radius=0.5 * design.nut.outer_diameter_mm)
    else:
        raise ValueError(f"unknown part {part!r}")
    return cut_datum_mark(tm, datum_mark(tm.profile, tm.z_lo, tm.body_radius))


def _cylinder(r_in: float, r_out: float, z0: float, z1: float, tol: float) -> trimesh.Trimesh:
    """Closed cylinder (r_in = 0) or ring, polygon sagitta <= tol."""
    sections = max(16, int(math.ceil(math.pi / math.acos(1.0 - tol / r_out))))
    if r_in <= 0:
        m = trimesh.creation.cylinder(radius=r_out, height=z1 - z0, sections=sections)
    else:
        m = trimesh.creation.annulus(r_min=r_in, r_max=r_out, height=z1 - z0, sections=sections)
    m.apply_translation([0, 0, 0.5 * (z0 + z1)])
    return m


@dataclass
class Assembly:
    """Part meshes (in part frames) and the placed scene parts."""

    design: PRSDesign
    parts: dict[str, ThreadMesh]
    #: chord tolerance the parts were meshed at (mm)
    tolerance: float = 0.0
    #: scene part name -> (mesh in its own frame, 4x4 transform to the screw frame, kind)
    placed: dict[str, tuple[trimesh.Trimesh, NDArray[np.float64], str]] = field(default_factory=dict)

    def scene(self) -> trimesh.Scene:
        sc = trimesh.Scene()
        for name, (mesh, T, _) in self.placed.items():
            sc.add_geometry(mesh, node_name=name, geom_name=name, transform=T)
        return sc

    def placed_mesh(self, name: str) -> trimesh.Trimesh:
        mesh, T, _ = self.placed[name]
        m = mesh.copy()
        m.apply_transform(T)
        return m

    def combined_arrays(self) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """Vertices and faces of every placed part in one array pair (screw frame).

        Parts that share a mesh (the rollers) are transformed together in one einsum.
        """
        groups: dict[int, tuple[trimesh.Trimesh, list[NDArray[np.float64]]]] = {}
        for mesh, T, _ in self.placed.values():
            groups.setdefault(id(mesh), (mesh, []))[1].append(T)
        nv = sum(len(m.vertices) * len(Ts) for m, Ts in groups.values())
        nf = sum(len(m.faces) * len(Ts) for m, Ts in groups.values())
        V_out = np.empty((nv, 3), np.float64)
        F_out = np.empty((nf, 3), np.int64)
        v0 = f0 = 0
        for mesh, Ts in groups.values():
            V = np.asarray(mesh.vertices, dtype=np.float64)
            F = np.asarray(mesh.faces, dtype=np.int64)
            for T in Ts:
                np.matmul(V, T[:3, :3].T, out=V_out[v0:v0 + len(V)])
                V_out[v0:v0 + len(V)] += T[:3, 3]
                np.add(F, v0, out=F_out[f0:f0 + len(F)])
                v0 += len(V)
                f0 += len(F)
        return V_out, F_out

    def combined(self) -> trimesh.Trimesh:
        V, F = self.combined_arrays()
        return trimesh.Trimesh(V, F, process=False, validate=False)

    def rigid_body(self, name: str) -> str:
        """The rigid body a scene part belongs to (gear cylinders belong to their part)."""
        return name.split("_gear")[0].replace("nut_ring", "nut")


def build_assembly(design: PRSDesign, tol: float | None = None, progress: ProgressFn = silent,
                   screw_profile: ThreadProfile | None = None, gears: bool = True,
                   reuse: Assembly | None = None) -> Assembly:
    """All part meshes and their placement. Rollers share one mesh (placed z times).

    ``reuse``: an assembly of the same design and tolerance whose roller, nut and gear
    meshes are taken as they are (only the screw is meshed again), e.g. to check the same
    assembly with the nominal and the theoretical screw.
    """
    tol = tol or design.mesh.chord_tolerance_mm
    if reuse is not None:
        if reuse.design != design or reuse.tolerance != tol:
            raise ValueError("reuse needs an assembly of the same design and tolerance")
        parts = dict(reuse.parts)
        parts["screw"] = build_part(design, "screw", tol, None, screw_profile)
        progress("meshes", 1, 1)
        asm = Assembly(design, parts, tolerance=tol)
        for name, (mesh, T, kind) in reuse.placed.items():
            asm.placed[name] = (parts["screw"].to_trimesh(), T, kind) if name == "screw" else (mesh, T, kind)
        return asm
    prof = ThreadProfiles.from_design(design)
    parts = {}
    for i, name in enumerate(("screw", "roller", "nut")):
        parts[name] = build_part(design, name, tol, prof, screw_profile)
        progress("meshes", i + 1, 3)
    asm = Assembly(design, parts, tolerance=tol)
    I = np.eye(4)
    asm.placed["screw"] = (parts["screw"].to_trimesh(), I, "thread")
    asm.placed["nut"] = (parts["nut"].to_trimesh(), I, "thread")
    L = thread_length(design)
    gl = GEAR_LENGTH_PITCHES * design.thread.pitch_mm
    if gears:
        ring_in, ring_out = 0.5 * design.nut.minor_diameter_mm, 0.5 * design.nut.outer_diameter_mm
        asm.placed["nut_ring_gear_lo"] = (_cylinder(ring_in, ring_out, -gl, 0.0, tol), I, "simplified")
        asm.placed["nut_ring_gear_hi"] = (_cylinder(ring_in, ring_out, L, L + gl, tol), I, "simplified")
        gear_lo = _cylinder(0.0, 0.5 * design.roller.minor_diameter_mm, -gl, 0.0, tol)
        gear_hi = _cylinder(0.0, 0.5 * design.roller.minor_diameter_mm, L, L + gl, tol)
    roller_tm = parts["roller"].to_trimesh()
    z = design.roller.count
    for k in range(z):
        T = roller_transform(design, k)
        asm.placed[f"roller_{k}"] = (roller_tm, T, "thread")
        if gears:
            asm.placed[f"roller_{k}_gear_lo"] = (gear_lo, T, "simplified")
            asm.placed[f"roller_{k}_gear_hi"] = (gear_hi, T, "simplified")
        progress("placing rollers", k + 1, z)
    return asm
