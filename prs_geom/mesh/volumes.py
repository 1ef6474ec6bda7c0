"""Part volumes from the assembly meshes.

A *part* here is a rigid body of the placed assembly (:meth:`Assembly.rigid_body`): the
screw, with its ends for an actuator (``screw_end_lo``, ``screw_end_hi``, which overlap the
thread over the run-outs); each roller with its end gears and journals (``roller_<k>``); the
nut with its ring gears, ends and, for an actuator, its flange (``nut``); each carrier
(``carrier_lo``, ``carrier_hi``) and retaining ring (``retaining_ring_lo``,
``retaining_ring_hi``) when the design has the mechanism parts; an actuator's bearings,
locknut and shaft ring (envelopes of purchased parts: the parts list prints no volume for
them). Volumes are in mm^3, from the meshes (so within the meshes' chord tolerance of the
solids).
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from prs_geom.mesh.thread import to_manifold

if TYPE_CHECKING:
    from prs_geom.mesh.assembly import Assembly

__all__ = ["part_volumes"]

#: Bounding boxes overlapping by no more than this (mm) on some axis only touch.
_TOUCH_MM = 1e-9


def part_volumes(asm: Assembly) -> dict[str, float]:
    """Volume (mm^3) of one piece of every rigid body of ``asm``, keyed by body name.

    The sum of its scene parts' mesh volumes less the volume of every overlap of two of them
    (manifold3d), so that a part overlapping another of its body (the nut end around the ring
    gear, the flange around the nut end, a screw end inside the thread's run-out) counts
    once. Only pairs whose bounding boxes overlap with positive thickness on
    every axis are intersected (parts that meet in an end face, like the threads and the
    gears, do not overlap); the result is exact while no three parts share a region, which
    the layout of docs/theory/mechanism.md guarantees. Bodies made of the same meshes (the
    rollers) are computed once and get the same value.
    """
    bodies: dict[str, list[Any]] = {}
    for name, (mesh, _, _) in asm.placed.items():
        bodies.setdefault(asm.rigid_body(name), []).append(mesh)
    done: dict[tuple[int, ...], float] = {}
    out = {}
    for body, meshes in bodies.items():
        key = tuple(id(m) for m in meshes)
        if key not in done:
            done[key] = _union_volume(meshes)
        out[body] = done[key]
    return out


def _union_volume(meshes: list[Any]) -> float:
    """Volume (mm^3) of the union of closed trimesh meshes of which no three share a region."""
    total = sum(float(m.volume) for m in meshes)
    boxes = [np.asarray(m.bounds) for m in meshes]
    for i in range(len(meshes)):
        for j in range(i + 1, len(meshes)):
            lo = np.maximum(boxes[i][0], boxes[j][0])
            hi = np.minimum(boxes[i][1], boxes[j][1])
            if np.all(hi - lo > _TOUCH_MM):
                overlap = _solid(meshes[i]) ^ _solid(meshes[j])
                total -= float(overlap.volume())
    return total


def _solid(mesh: Any) -> Any:
    return to_manifold(mesh.vertices, mesh.faces)
