"""The physical datums of every part: end face A and the angular mark B (no I/O).

Datum A is the part's loaded-side end face, the plane z = ``z_face`` of the part frame (z = 0
for roller and nut, the screw's lower end for the screw). Datum B fixes theta = 0: a radial
slot of rectangular section cut into face A, centred on the +x half-axis of the part frame
(the axial section plane at theta = 0 of the drawings and machining sheets). Its walls are
parallel to the x-z plane, its floor parallel to face A. A shop finds theta = 0 by probing
the slot walls (the slot's mid-plane) and every axial position from face A.

Sizing rule (stated so that a reader can reproduce it, and chosen so that the slot lies
wholly inside solid material, away from every thread flank, so that it changes no contact
and its volume is exactly width x depth x radial length):

* external threads (screw, roller): radially from 0.3 to 0.8 of the root radius;
* nut: across the middle 60 % of the wall between the thread's root radius and the body;
* width and depth: a quarter of the pitch each, but at most a third of the radial length
  (short slots on small parts stay slots, not pockets).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from prs_geom.geometry.profiles import ThreadProfile

__all__ = ["DatumMark", "datum_mark"]


@dataclass(frozen=True)
class DatumMark:
    """Angular datum B: a radial slot in face A at theta = 0.

    Attributes
    ----------
    z_face : float
        Axial position of face A in the part frame (mm).
    r_inner, r_outer : float
        Radial extent of the slot along +x (mm), ``0 <= r_inner < r_outer``.
    width : float
        Slot width along y (mm), centred on y = 0.
    depth : float
        Slot depth into the part, along +z from face A (mm).
    """

    z_face: float
    r_inner: float
    r_outer: float
    width: float
    depth: float

    def __post_init__(self) -> None:
        for name in ("r_inner", "r_outer", "width", "depth"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0.0):
                raise ValueError(f"DatumMark.{name} = {v!r}: must be a finite length >= 0 mm")
        if not self.r_outer > self.r_inner:
            raise ValueError(f"DatumMark.r_outer = {self.r_outer!r} must exceed r_inner = {self.r_inner!r}")
        if not (self.width > 0.0 and self.depth > 0.0):
            raise ValueError("DatumMark width and depth must be > 0 mm")

    @property
    def volume(self) -> float:
        """Material removed (mm^3): the slot is a box wholly inside the solid."""
        return (self.r_outer - self.r_inner) * self.width * self.depth

    def box(self, overshoot: float = 0.0) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """Lower and upper corners (x, y, z) of the slot box, extended ``overshoot`` mm out
        of face A (so a boolean cut does not leave a coplanar skin)."""
        return ((self.r_inner, -0.5 * self.width, self.z_face - overshoot),
                (self.r_outer, 0.5 * self.width, self.z_face + self.depth))


def datum_mark(profile: ThreadProfile, z_face: float, body_radius: float | None = None) -> DatumMark:
    """The angular datum mark of a part by the sizing rule of this module.

    Parameters
    ----------
    profile : ThreadProfile
        The part's thread profile (pitch, root radius, internal or external).
    z_face : float
        Face A in the part frame (mm).
    body_radius : float, optional
        Outer radius of the nut body (mm); required for internal threads.
    """
    if profile.internal:
        if body_radius is None:
            raise ValueError("the nut's datum mark needs the body radius")
        wall = body_radius - profile.outer_radius
        r0, r1 = profile.outer_radius + 0.2 * wall, body_radius - 0.2 * wall
    else:
        r0, r1 = 0.3 * profile.root_radius, 0.8 * profile.root_radius
    size = min(0.25 * profile.pitch, (r1 - r0) / 3.0)
    return DatumMark(z_face=z_face, r_inner=r0, r_outer=r1, width=size, depth=size)
