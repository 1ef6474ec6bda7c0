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

__all__ = ["keyway_volume", "part_volumes"]


def part_volumes(asm: Assembly) -> dict[str, float]:
    """Volume (mm^3) of one piece of every rigid body of ``asm``, keyed by body name: the
    volume of its complete part (:meth:`Assembly.complete_parts`, the union of the body's
    pieces, manifold3d), so that a piece overlapping another of its body (the nut end around
    the ring gear, the flange around the nut end, a screw end inside the thread's run-out)
    counts once. Copies of one part (the rollers) get the same value."""
    return {body: part.volume_mm3 for part in asm.complete_parts().values() for body in part.instances}


def keyway_volume(journal_radius_mm: float, width_mm: float, depth_mm: float, length_mm: float) -> float:
    """Volume (mm^3) a DIN 6885-1 form A keyway removes from a journal: the stadium of
    ``length_mm`` x ``width_mm`` (ends of radius b / 2) seen along the journal's radius, from
    its floor at r - t1 out to the journal's surface.

    Over the stadium, the depth of material above the floor at distance y from its middle
    line is sqrt(r^2 - y^2) - (r - t1). The straight part integrates in closed form
    (y sqrt(r^2 - y^2) + r^2 asin(y / r)); the two half-disc ends together are a disc of
    radius a = b / 2, whose chord 2 sqrt(a^2 - y^2) weights the depth: with y = a sin(phi)
    the integrand is smooth, and 64-point Gauss-Legendre gives it to rounding.
    """
    import math

    import numpy as np

    r, a, t1 = journal_radius_mm, 0.5 * width_mm, depth_mm
    floor = r - t1
    straight = length_mm - 2.0 * a
    prim = lambda y: 0.5 * (y * math.sqrt(r * r - y * y) + r * r * math.asin(y / r))
    v_straight = straight * (prim(a) - prim(-a) - 2.0 * a * floor)
    x, w = np.polynomial.legendre.leggauss(64)
    phi = 0.5 * math.pi * x
    y = a * np.sin(phi)
    integrand = 2.0 * a * np.cos(phi) * (np.sqrt(r * r - y * y) - floor) * a * np.cos(phi)
    v_disc = float(0.5 * math.pi * np.sum(w * integrand))
    return v_straight + v_disc
