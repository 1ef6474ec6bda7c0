"""Part meshes of a design and their placement as an assembly.

Frames and roller phasing are those of :mod:`prs_geom.geometry.frames`; this module meshes
each part once in its own frame and places the rollers as transforms of one roller mesh.

End gears (:func:`end_gears`, docs/theory/gears.md): a spur gear on each roller end, one
face width beyond the thread, cut through the continued thread; an internal ring gear at
each nut end. They are placed as their own scene parts (``roller_<k>_gear_lo/hi``,
``nut_ring_gear_lo/hi``) that move with their roller or nut (:meth:`Assembly.rigid_body`).

Actuator parts (:mod:`prs_geom.mesh.actuator`, a design with ``[actuator]``): the screw ends,
the nut flange, the bearings, the KM locknut and the DIN 471 ring, meshed in the screw frame
with the nut at mid-stroke and placed with the identity after the retaining rings. The screw
ends belong to the screw and the flange to the nut; each purchased part is its own body.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from prs_geom.geometry.actuator import actuator_layout
from prs_geom.geometry.frames import (FIRST_MID_PITCHES, carrier_angles, part_warps, roller_spin,
                                     roller_transform, screw_z_range, thread_length)
from prs_geom.model.design import PRSDesign
from prs_geom.geometry.datum import datum_mark
from prs_geom.mesh.thread import (RunOut, ThreadMesh, apply_run_outs, cut_datum_mark, from_manifold,
                                  part_chord_tolerance, thread_mesh, to_manifold)
from prs_geom.geometry.profiles import ThreadProfile, ThreadProfiles
from prs_geom.runtime.progress import ProgressFn, silent

__all__ = [
    "Assembly", "GEAR_CHORD_MM", "SIDES", "build_assembly", "build_part", "design_run_outs", "end_gears", "mechanism_parts",
    "part_z_range", "scene_names", "window_assembly",
]


def part_z_range(design: PRSDesign, part: str) -> tuple[float, float]:
    """Axial extent (mm) of a part's thread in its own frame: the screw centred on the
    engaged length (:func:`~prs_geom.geometry.frames.screw_z_range`), roller and nut over it."""
    if part == "screw":
        return screw_z_range(design)
    if part in ("roller", "nut"):
        return 0.0, thread_length(design)
    raise ValueError(f"unknown part {part!r}")


def build_part(design: PRSDesign, part: str, tol: float | None = None,
               profiles: ThreadProfiles | None = None,
               screw_profile: ThreadProfile | None = None,
               z_window: tuple[float, float] | None = None,
               run_outs: Sequence[RunOut] | None = None) -> ThreadMesh | None:
    """Mesh of one part in its own frame, with its angular datum mark cut into face A
    (the end face at the part's lower z, :mod:`prs_geom.geometry.datum`), at ``tol`` or
    finer for a small part (:func:`~prs_geom.mesh.thread.part_chord_tolerance`).

    ``run_outs``: thread run-outs at the part's end planes
    (:func:`~prs_geom.mesh.thread.apply_run_outs`), applied before the datum mark is cut
    (in the same boolean pass); None (default): the design's (:func:`design_run_outs`),
    ``()``: none.

    ``screw_profile`` replaces the design's screw profile (e.g. with the corrected pitch
    diameter of the contact analysis).

    ``z_window``: mesh only the part's piece between these planes (part frame, mm), closed
    by end faces on them; None when the part does not reach into the window. The datum mark
    is cut only when the piece starts at the part's own face A. Columns and strands are
    those of the whole part (they depend on the profile and the tolerance, not on the end
    planes), so away from its end faces the piece is the whole part's surface. A run-out
    is applied only at an end of the part that the piece reaches (clipped to the piece).
    """
    tol = tol or design.mesh.chord_tolerance_mm
    prof = profiles or ThreadProfiles.from_design(design)
    p = design.thread.pitch_mm
    warps = part_warps(design)
    first_mid = FIRST_MID_PITCHES[part] * p
    lo, hi = part_z_range(design, part)
    z_lo, z_hi = (lo, hi) if z_window is None else (max(lo, z_window[0]), min(hi, z_window[1]))
    if z_hi <= z_lo:
        return None
    if part == "screw":
        profile = screw_profile or prof.screw
        tm = thread_mesh(profile, z_lo, z_hi, part_chord_tolerance(profile, tol), first_mid, warps["screw"])
    elif part == "roller":
        tm = thread_mesh(prof.roller, z_lo, z_hi, part_chord_tolerance(prof.roller, tol), first_mid, warps["roller"])
    else:
        tm = thread_mesh(prof.nut, z_lo, z_hi, part_chord_tolerance(prof.nut, tol), first_mid,
                         warps["nut"], body_radius=0.5 * design.nut.outer_diameter_mm)
    mark = datum_mark(tm.profile, tm.z_lo, tm.body_radius) if z_lo == lo else None
    if run_outs is None:
        run_outs = design_run_outs(design, part)
    if run_outs:   # the run-outs, then the mark, in one boolean pass
        return apply_run_outs(tm, run_outs, part_range=(lo, hi), mark=mark)
    return tm if mark is None else cut_datum_mark(tm, mark)


def design_run_outs(design: PRSDesign, part: str) -> tuple[RunOut, ...]:
    """The thread run-outs of a part of an actuator (none without one), by the rules of
    :mod:`prs_geom.geometry.actuator`: a grinding-wheel exit of ``screw_run_out_mm`` at both
    screw thread ends, a 45 degree chamfer of ``thread_chamfer_mm`` at both roller and nut
    thread ends."""
    from prs_geom.geometry.actuator import actuator_layout

    lay = actuator_layout(design)
    if lay is None:
        return ()
    if part == "screw":
        return (RunOut("lo", "wheel-exit", lay.screw_run_out_mm), RunOut("hi", "wheel-exit", lay.screw_run_out_mm))
    return (RunOut("lo", "chamfer", lay.thread_chamfer_mm), RunOut("hi", "chamfer", lay.thread_chamfer_mm))


#: Gear outlines are never meshed coarser than this (mm).
GEAR_CHORD_MM = 1e-3


def end_gears(design: PRSDesign, tol: float, prof: ThreadProfiles | None = None) -> dict[str, trimesh.Trimesh] | None:
    """Meshes of the roller end gears and the nut ring gears, in the roller and nut frames
    (None when the design's gears are disabled).

    Each roller gear spans one face width beyond its thread end (z in [-w, 0] and [L, L + w])
    and is the roller thread continued there, intersected with the involute gear prism: the
    teeth are cut through the threaded end, so the gear's tip carries the thread and meshes
    with the screw like the thread does. Its tooth 0 sits at the phasing offset from the
    roller's theta = 0 (:func:`prs_geom.geometry.gear_phasing.roller_gear_phasing`), the same on
    every roller. The ring gears span the same z ranges in the nut frame, tooth 0 on +x, rings
    from their root to halfway to the nut body diameter.
    """
    from prs_geom.geometry.gear_pair import design_gear_pair, ring_gear_outer_radius
    from prs_geom.geometry.gear_phasing import roller_gear_phasing
    from prs_geom.mesh.gears import gear_mesh

    pair = design_gear_pair(design)
    if pair is None:
        return None
    # the ring gear's fillet sampled coarser than ~1 um can step back in polar angle, which
    # the prism's cap triangulation refuses; 1 um outlines cost a few thousand vertices
    gear_tol = min(tol, GEAR_CHORD_MM)
    prof = prof or ThreadProfiles.from_design(design)
    psi = carrier_angles(design)
    chi = np.array([roller_spin(design, a) for a in psi])
    offset = roller_gear_phasing(pair.pinion, pair.ring, psi, chi).offset_rad
    w = pair.pinion.face_width_mm
    L = thread_length(design)
    p = design.thread.pitch_mm
    warp = part_warps(design)["roller"]
    out: dict[str, trimesh.Trimesh] = {}
    # the prism overshoots the thread's end planes, so only they bound the gear axially
    Vg, Fg = gear_mesh(pair.pinion, -w - 1.0, L + w + 1.0, gear_tol, phase_rad=offset)
    prism = to_manifold(Vg, Fg)
    for name, (z0, z1) in (("roller_lo", (-w, 0.0)), ("roller_hi", (L, L + w))):
        tm = thread_mesh(prof.roller, z0, z1, part_chord_tolerance(prof.roller, tol),
                         FIRST_MID_PITCHES["roller"] * p, warp)
        out[name] = trimesh.Trimesh(*from_manifold(to_manifold(tm.vertices, tm.faces) ^ prism),
                                    process=False, validate=False)
    ring_outer = ring_gear_outer_radius(design, pair)
    for name, (z0, z1) in (("ring_lo", (-w, 0.0)), ("ring_hi", (L, L + w))):
        V, F = gear_mesh(pair.ring, z0, z1, gear_tol, outer_radius_mm=ring_outer)
        out[name] = trimesh.Trimesh(V, F, process=False, validate=False)
    return out


@dataclass
class Assembly:
    """Part meshes (in part frames) and the placed scene parts."""

    design: PRSDesign
    parts: dict[str, ThreadMesh]
    #: chord tolerance the parts were meshed at (mm)
    tolerance: float = 0.0
    #: scene part name -> (mesh in its own frame, 4x4 transform to the screw frame, kind)
    placed: dict[str, tuple[trimesh.Trimesh, NDArray[np.float64], str]] = field(default_factory=dict)
    _complete: dict[str, Any] | None = field(default=None, init=False, repr=False, compare=False)

    def complete_parts(self) -> dict[str, Any]:
        """The complete parts (:func:`prs_geom.mesh.parts.complete_parts`), formed on the
        first call and kept: every export and check of a build uses the same unions."""
        if self._complete is None:
            from prs_geom.mesh.parts import complete_parts

            self._complete = complete_parts(self)
        return self._complete

    def complete_part(self, name: str) -> Any:
        """The complete part ``name`` (``screw``, ``roller``, ...) of :meth:`complete_parts`."""
        return self.complete_parts()[name]

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

    @staticmethod
    def rigid_body(name: str) -> str:
        """The rigid body a scene part belongs to: gears and journals belong to their roller,
        ring gears, nut ends and the nut flange to the nut, the screw ends to the screw; each
        carrier, retaining ring, bearing, the locknut and the shaft ring is its own."""
        body = name.split("_gear")[0].split("_journal")[0]
        if body.startswith("screw_"):
            return "screw"
        return "nut" if body.startswith("nut_") else body


def build_assembly(design: PRSDesign, tol: float | None = None, progress: ProgressFn = silent,
                   screw_profile: ThreadProfile | None = None, gears: bool = True,
                   reuse: Assembly | None = None, mechanism: bool = True) -> Assembly:
    """All part meshes and their placement. Rollers share one mesh (placed z times).
    ``gears``/``mechanism``: include the end gears / the mechanism parts (carriers,
    journals, retaining rings, nut ends and, for an actuator, its parts) when the design
    has them.

    ``reuse``: an assembly of the same design and tolerance whose roller, nut and gear
    meshes are taken as they are (only the screw is meshed again), e.g. to check the same
    assembly with the nominal and the theoretical screw.
    """
    tol = tol or design.mesh.chord_tolerance_mm
    if reuse is not None:
        asm = _with_new_screw(reuse, design, tol, screw_profile)
        progress("meshes", 1, 1)
        return asm
    prof = ThreadProfiles.from_design(design)
    parts = {}
    for i, name in enumerate(("screw", "roller", "nut")):
        parts[name] = build_part(design, name, tol, prof, screw_profile)
        progress("meshes", i + 1, 3)
    asm = Assembly(design, parts, tolerance=tol)
    _place(asm, end_gears(design, tol, prof) if gears else None, progress,
           mech_parts=mechanism_parts(design, tol) if mechanism else None)
    return asm


#: The two ends of a part pair (low z, high z).
SIDES = ("lo", "hi")


def _scene_entries(design: PRSDesign, gears: bool, mechanism: bool) -> list[tuple[str, str, str, int | None, str]]:
    """The scene parts in placement order, each (scene name, mesh table, key in the table,
    roller index whose transform places it or None for the screw frame, kind): screw, nut,
    the ring gears, the nut ends, then each roller followed by its gears and journals, then
    the carriers and the retaining rings, then for an actuator (mechanism included) the screw
    ends, the nut flange, the bearings, the locknut and the shaft ring
    (:func:`~prs_geom.mesh.actuator.actuator_part_names`). Tables: "parts" (the thread
    meshes), "gears" (:func:`end_gears`), "mechanism" (:func:`mechanism_parts`, the actuator
    parts included)."""
    e = [("screw", "parts", "screw", None, "thread"), ("nut", "parts", "nut", None, "thread")]
    if gears:
        e += [(f"nut_ring_gear_{s}", "gears", f"ring_{s}", None, "gear") for s in SIDES]
    if mechanism:
        e += [(f"nut_end_{s}", "mechanism", f"nut_end_{s}", None, "mechanism") for s in SIDES]
    for k in range(design.roller.count):
        e.append((f"roller_{k}", "parts", "roller", k, "thread"))
        if gears:
            e += [(f"roller_{k}_gear_{s}", "gears", f"roller_{s}", k, "gear") for s in SIDES]
        if mechanism:
            e += [(f"roller_{k}_journal_{s}", "mechanism", f"journal_{s}", k, "mechanism") for s in SIDES]
    if mechanism:
        e += [(f"{part}_{s}", "mechanism", f"{part}_{s}", None, "mechanism")
              for part in ("carrier", "retaining_ring") for s in SIDES]
        lay = actuator_layout(design)
        if lay is not None:
            from prs_geom.mesh.actuator import actuator_part_names

            e += [(name, "mechanism", name, None, "actuator") for name in actuator_part_names(lay)]
    return e


def scene_names(design: PRSDesign, gears: bool, mechanism: bool = False) -> list[str]:
    """Scene part names in the order :func:`build_assembly` places them (:func:`_scene_entries`)."""
    return [entry[0] for entry in _scene_entries(design, gears, mechanism)]


def mechanism_parts(design: PRSDesign, tol: float) -> dict[str, tuple[trimesh.Trimesh, NDArray[np.float64]]] | None:
    """Meshes of the carriers, journals, retaining rings and nut ends
    (:func:`prs_geom.mesh.mechanism.mechanism_meshes`) and, for an actuator, of its parts
    (:func:`prs_geom.mesh.actuator.actuator_meshes`, screw frame at mid-stroke), each as (mesh
    in its own frame, transform to the screw frame, or to the roller frame for a journal);
    None when the design has no mechanism."""
    from prs_geom.geometry.mechanism import layout

    lay = layout(design)
    if lay is None:
        return None
    from prs_geom.mesh.mechanism import mechanism_meshes

    out = mechanism_meshes(design, lay, tol)
    act = actuator_layout(design)
    if act is not None:
        from prs_geom.mesh.actuator import actuator_meshes

        out.update(actuator_meshes(design, act, tol))
    return out


def _place(asm: Assembly, gear_parts: dict[str, trimesh.Trimesh] | None, progress: ProgressFn = silent,
           gear_window: tuple[float, float] | None = None,
           mech_parts: dict[str, tuple[trimesh.Trimesh, NDArray[np.float64]]] | None = None) -> None:
    """Place ``asm.parts``, the gears and the mechanism parts in ``asm.placed``, in the order
    of :func:`scene_names`; with ``gear_window``, only the gears and mechanism parts whose
    placed z range (the same in the roller frames and the screw frame) meets it."""
    design = asm.design
    I = np.eye(4)
    tables: dict[str, dict[str, tuple[trimesh.Trimesh, NDArray[np.float64]]]] = {
        "parts": {name: (tm.to_trimesh(), I) for name, tm in asm.parts.items()},
        "gears": {name: (mesh, I) for name, mesh in (gear_parts or {}).items()},
        "mechanism": mech_parts or {}}
    transforms = {k: roller_transform(design, k) for k in range(design.roller.count)}
    z = design.roller.count
    for name, table, key, k, kind in _scene_entries(design, gear_parts is not None, mech_parts is not None):
        entry = tables[table].get(key)
        if entry is None:
            continue
        mesh, T_own = entry
        if table != "parts" and gear_window is not None:
            zs = np.asarray(mesh.vertices) @ T_own[2, :3] + T_own[2, 3]
            if not (zs.max() > gear_window[0] and zs.min() < gear_window[1]):
                continue
        T = T_own if k is None else transforms[k] @ T_own
        asm.placed[name] = (mesh, T, kind)
        if table == "parts" and key == "roller":
            progress("placing rollers", k + 1, z)


def _with_new_screw(reuse: Assembly, design: PRSDesign, tol: float, screw_profile: ThreadProfile | None,
                    z_window: tuple[float, float] | None = None) -> Assembly:
    """``reuse`` (an assembly of the same design and tolerance) with its screw meshed again
    (``screw_profile``, over ``z_window``; left out where the window misses the screw) and
    every other part and placement kept as they are."""
    if reuse.design != design or reuse.tolerance != tol:
        raise ValueError("reuse needs an assembly of the same design and tolerance")
    screw = build_part(design, "screw", tol, None, screw_profile, z_window)
    others = {k: v for k, v in reuse.parts.items() if k != "screw"}
    asm = Assembly(design, others if screw is None else {"screw": screw, **others}, tolerance=tol)
    placed = {} if screw is None else {"screw": (screw.to_trimesh(), np.eye(4), "thread")}
    asm.placed = {**placed, **{n: v for n, v in reuse.placed.items() if n != "screw"}}
    return asm


def window_assembly(design: PRSDesign, tol: float, z_window: tuple[float, float],
                    screw_profile: ThreadProfile | None = None,
                    gear_parts: dict[str, trimesh.Trimesh] | None = None,
                    reuse: Assembly | None = None,
                    mech_parts: dict[str, tuple[trimesh.Trimesh, NDArray[np.float64]]] | None = None) -> Assembly:
    """The assembly's piece between the planes z = ``z_window`` (screw frame, mm): every
    thread part meshed over that window only (:func:`build_part`), and the gears of
    ``gear_parts`` (:func:`end_gears`) and mechanism parts of ``mech_parts``
    (:func:`mechanism_parts`), both meshed once for all windows, that reach into it.

    The rollers' frames differ from the screw frame by a rotation about and a shift
    perpendicular to the axis, so one window in z is the same window in every part frame.
    ``reuse``: a window assembly of the same design, tolerance and window whose roller,
    nut and gears are kept (only the screw is meshed again, as in :func:`build_assembly`).
    """
    if reuse is not None:
        return _with_new_screw(reuse, design, tol, screw_profile, z_window)
    prof = ThreadProfiles.from_design(design)
    parts = {}
    for name in ("screw", "roller", "nut"):
        tm = build_part(design, name, tol, prof, screw_profile, z_window)
        if tm is not None:
            parts[name] = tm
    asm = Assembly(design, parts, tolerance=tol)
    _place(asm, gear_parts, gear_window=z_window, mech_parts=mech_parts)
    return asm
