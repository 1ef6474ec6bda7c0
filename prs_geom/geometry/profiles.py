"""Thread profiles of screw, roller and nut (docs/theory/geometry.md).

Pure math, no I/O. Convention used everywhere in the toolkit ("normal-section
convention"): the designer's profile is given in the normal section at the pitch radius;
the axial-section profile is that profile with every axial width divided by cos(lambda),
lambda being the lead angle **at the pitch radius** (a constant per part). So the helical
surface of part i is

    f_i(r, theta) = (r cos theta, r sin theta, xi * h_i(r) / cos(lambda_i) + L_i theta / 2 pi + z0)

with xi = +1 for the upper flank (facing +z) and -1 for the lower flank.

This module describes one thread *period* in the axial section, centred on a tooth
(the material ridge of the part): u is the axial offset from the tooth mid-plane (mm),
u in [-p/2, p/2]; the groove centre is at u = +-p/2.

* ``tooth_half_width(r)`` is the axial half-width t(r) of the tooth at radius r (mm).
  External threads (screw, roller): t decreases from root (small r) to crest (large r).
  Internal thread (nut): t increases from crest (small r, the bore) to root (large r).
* Screw:  t = [p cos(lam)/4 - tan(beta)(r - r_s)] / cos(lam)   (groove h_s grows with r)
* Nut:    t = [p cos(lam)/4 + tan(beta)(r - r_n)] / cos(lam)
* Roller: t = [p cos(lam)/4 + sqrt(r_T^2 - r^2) - sqrt(r_T^2 - r_r^2)] / cos(lam)
  (arc of radius r_T centred on the roller axis: a sphere in 3D).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prs_geom.geometry.flanks import ArcFlank, FlankShape, StraightFlank

if TYPE_CHECKING:  # pragma: no cover
    from prs_geom.model.design import PRSDesign

__all__ = ["ThreadProfile", "ThreadProfiles"]


@dataclass(frozen=True)
class ThreadProfile:
    """Axial-section profile of one part's thread.

    Parameters
    ----------
    part : str
        "screw", "roller" or "nut".
    internal : bool
        True for the nut (material outside the thread surface).
    pitch : float
        Axial pitch p (mm).
    starts : int
        Number of starts n_i; lead L_i = n_i p.
    pitch_radius : float
        Nominal (pitch) radius r_i (mm) where the normal-section tooth half-width is
        p cos(lambda_i) / 4.
    crest_radius, root_radius : float
        Truncation radii (mm). External: crest > root; internal: crest < root.
    beta : float
        Flank half-angle (rad) in the normal section.
    flank : FlankShape
        The flank shape (:mod:`prs_geom.geometry.flanks`); it is referred to this
        profile's pitch radius on construction, so a profile copied with another pitch
        radius (the corrected screw) carries a matching flank.
    hand_sign : int
        +1 right hand, -1 left hand.
    lead_radius : float, optional
        Radius (mm) at which the lead angle of the normal-section convention is taken;
        the pitch radius when omitted. The contact analysis corrects the screw's pitch
        radius while keeping its lead angle at the nominal radius (so the correction is a
        pure axial shift of the flanks and the contact point does not move).
    """

    part: str
    internal: bool
    pitch: float
    starts: int
    pitch_radius: float
    crest_radius: float
    root_radius: float
    beta: float
    flank: FlankShape
    hand_sign: int = 1
    lead_radius: float | None = None

    def __post_init__(self) -> None:
        if self.flank.pitch_radius != self.pitch_radius:
            object.__setattr__(self, "flank", self.flank.at_pitch_radius(self.pitch_radius))

    # -- lead ----------------------------------------------------------------
    @property
    def lead(self) -> float:
        """Lead L = n p (mm), unsigned."""
        return self.starts * self.pitch


    @property
    def lead_angle(self) -> float:
        """Lead angle lambda = atan(L / 2 pi r) at the pitch (or lead) radius (rad), unsigned."""
        r = self.pitch_radius if self.lead_radius is None else self.lead_radius
        return math.atan(self.lead / (2.0 * math.pi * r))

    @property
    def cos_lead(self) -> float:
        """cos of :attr:`lead_angle`."""
        return math.cos(self.lead_angle)

    @property
    def inner_radius(self) -> float:
        """Smallest radius of the thread surface (mm)."""
        return min(self.crest_radius, self.root_radius)

    @property
    def outer_radius(self) -> float:
        """Largest radius of the thread surface (mm)."""
        return max(self.crest_radius, self.root_radius)

    # -- profile -------------------------------------------------------------
    def tooth_half_width(self, r: ArrayLike) -> NDArray[np.float64]:
        """Axial half-width t(r) of the tooth (mm) at radius r (mm), float64 array."""
        return self.flank.half_width(r, 0.25 * self.pitch * self.cos_lead) / self.cos_lead

    def tooth_half_width_slope(self, r: ArrayLike) -> NDArray[np.float64]:
        """dt/dr (dimensionless), the axial-section flank slope."""
        return self.flank.slope(r) / self.cos_lead

    def tooth_half_width_curvature(self, r: ArrayLike) -> NDArray[np.float64]:
        """d2t/dr2 (1/mm); zero on straight flanks."""
        return self.flank.curvature(r) / self.cos_lead

    def radius_at_half_width(self, t: ArrayLike) -> NDArray[np.float64]:
        """Inverse of :meth:`tooth_half_width`: radius where the tooth half-width is t."""
        c = self.cos_lead
        return self.flank.radius_at_half_width(np.asarray(t, dtype=np.float64) * c, 0.25 * self.pitch * c)

    def tooth_half_width_at_crest(self) -> float:
        """Axial tooth half-width (mm) at the crest radius."""
        return float(self.tooth_half_width(self.crest_radius))

    def groove_half_width_at_root(self) -> float:
        """Axial groove half-width (mm) at the root radius: p/2 less the tooth half-width there."""
        return 0.5 * self.pitch - float(self.tooth_half_width(self.root_radius))

    def corner_offsets(self) -> NDArray[np.float64]:
        """Axial offsets u of the four profile corners, increasing: root and crest corner
        of the lower flank, then crest and root corner of the upper flank (the tooth is
        wider at the root than at the crest on external and internal threads alike)."""
        tr = self.tooth_half_width(self.root_radius)
        tc = self.tooth_half_width(self.crest_radius)
        return np.array([-tr, -tc, tc, tr])

    def radius_at_offset(self, u: ArrayLike) -> NDArray[np.float64]:
        """Profile radius rho(u) (mm) at axial offset u from the tooth mid-plane.

        u is reduced to [-p/2, p/2) first; rho is the single-valued axial profile of the
        thread surface (root flat, flank, crest flat, flank, root flat).
        """
        u = np.asarray(u, dtype=np.float64)
        p = self.pitch
        uu = np.abs((u + 0.5 * p) % p - 0.5 * p)
        tr = float(self.tooth_half_width(self.root_radius))
        tc = float(self.tooth_half_width(self.crest_radius))
        r_flank = self.radius_at_half_width(np.clip(uu, min(tc, tr), max(tc, tr)))
        return np.where(uu >= tr, self.root_radius, np.where(uu <= tc, self.crest_radius, r_flank))


@dataclass(frozen=True)
class ThreadProfiles:
    """The three profiles of a design."""

    screw: ThreadProfile
    roller: ThreadProfile
    nut: ThreadProfile

    @classmethod
    def from_design(cls, design: "PRSDesign") -> "ThreadProfiles":
        """The screw, roller and nut profiles of a resolved design (straight flanks on screw and
        nut, the arc flank on the roller)."""
        t = design.thread
        s, r, n = design.screw, design.roller, design.nut
        common = dict(pitch=t.pitch_mm, beta=t.beta, hand_sign=t.hand_sign)
        tb = math.tan(t.beta)
        # the one place that chooses the flank shape of each part
        rs, rr, rn = 0.5 * s.pitch_diameter_mm, 0.5 * r.pitch_diameter_mm, 0.5 * n.pitch_diameter_mm
        return cls(
            screw=ThreadProfile(part="screw", internal=False, starts=s.starts, pitch_radius=rs,
                                crest_radius=0.5 * s.major_diameter_mm,
                                root_radius=0.5 * s.minor_diameter_mm,
                                flank=StraightFlank(tan_beta=tb, sign=-1, pitch_radius=rs), **common),
            roller=ThreadProfile(part="roller", internal=False, starts=1, pitch_radius=rr,
                                 crest_radius=0.5 * r.major_diameter_mm,
                                 root_radius=0.5 * r.minor_diameter_mm,
                                 flank=ArcFlank(arc_radius=r.arc_radius_mm, pitch_radius=rr), **common),
            nut=ThreadProfile(part="nut", internal=True, starts=n.starts, pitch_radius=rn,
                              crest_radius=0.5 * n.minor_diameter_mm,
                              root_radius=0.5 * n.major_diameter_mm,
                              flank=StraightFlank(tan_beta=tb, sign=+1, pitch_radius=rn), **common),
        )

    def __iter__(self):
        return iter((self.screw, self.roller, self.nut))
