"""Part volumes from the assembly meshes.

A *part* here is a rigid body of the placed assembly (:meth:`Assembly.rigid_body`): the
screw, with its ends for an actuator (``screw_end_lo``, ``screw_end_hi``, which overlap the
thread over the run-outs); each roller with its end gears and journals (``roller_<k>``); the
nut with its ring gears, ends and, for an actuator, its flange (``nut``); each carrier
(``carrier_lo``, ``carrier_hi``) and retaining ring (``retaining_ring_lo``,
``retaining_ring_hi``) when the design has the mechanism parts; an actuator's bearings,
locknut and shaft ring (envelopes of purchased parts: the parts list prints no volume for
them). Volumes are in mm^3, of the complete parts' meshes (:mod:`prs_geom.mesh.parts`, so
within the meshes' chord tolerance of the solids).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from prs_geom.mesh.assembly import Assembly

__all__ = ["part_volumes"]


def part_volumes(asm: Assembly) -> dict[str, float]:
    """Volume (mm^3) of one piece of every rigid body of ``asm``, keyed by body name: the
    volume of its complete part (:meth:`Assembly.complete_parts`, the union of the body's
    pieces, manifold3d), so that a piece overlapping another of its body (the nut end around
    the ring gear, the flange around the nut end, a screw end inside the thread's run-out)
    counts once. Copies of one part (the rollers) get the same value."""
    return {body: part.volume_mm3 for part in asm.complete_parts().values() for body in part.instances}
