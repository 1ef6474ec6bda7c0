"""Flank shapes of a thread tooth, as objects (pure math, no I/O).

A flank is described in the *normal section* at the pitch radius (the normal-section
convention, docs/theory/conventions.md) by its offset from the pitch point: the tooth
half-width at radius r is

    w(r) = p cos(lambda) / 4 + delta(r),        delta(r_pitch) = 0

measured from the tooth mid-plane, for the upper flank (the lower flank is its mirror
image). The axial section divides every axial width by cos(lambda).

Two shapes exist:

* :class:`StraightFlank`: delta = s tan(beta) (r - r_pitch) with s = -1 for an external
  thread (screw: the tooth narrows outward) and s = +1 for an internal one (nut);
* :class:`ArcFlank`: the roller's convex flank, an arc of radius r_T centred on the roller
  axis (a sphere in 3D): delta = sqrt(r_T^2 - r^2) - sqrt(r_T^2 - r_pitch^2).

Every consumer (profiles, meshes, sections, drawings, checks) asks the flank object; the
kind is chosen once, in :meth:`prs_geom.geometry.profiles.ThreadProfiles.from_design`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prs_geom.geometry.planar import point_segment_distance
from prs_geom.geometry.primitives import CircleArc, EllipseArc, Segment

__all__ = ["ArcFlank", "FlankShape", "StraightFlank"]


@runtime_checkable
class FlankShape(Protocol):
    """What every flank shape answers (radii r in mm, normal section)."""

    pitch_radius: float

    def at_pitch_radius(self, pitch_radius: float) -> "FlankShape":
        """The same shape referred to another pitch radius (delta = 0 there)."""

    def half_width(self, r: ArrayLike, quarter: float) -> NDArray[np.float64]:
        """Normal-section tooth half-width ``quarter + delta(r)`` (mm); ``quarter`` is
        p cos(lambda)/4."""

    def drawing_half_width(self, r: float, quarter: float) -> float:
        """:meth:`half_width` as the drawings compute it (the arc's centre first): equal up
        to rounding, kept so that drawings stay byte for byte what they were."""

    def slope(self, r: ArrayLike) -> NDArray[np.float64]:
        """d delta / dr (dimensionless)."""

    def curvature(self, r: ArrayLike) -> NDArray[np.float64]:
        """d^2 delta / dr^2 (1/mm)."""

    def radius_at_half_width(self, w: ArrayLike, quarter: float) -> NDArray[np.float64]:
        """The radius where the normal-section half-width is ``w`` (inverse of half_width)."""

    def point(self, r: ArrayLike, quarter: float) -> NDArray[np.float64]:
        """Points (x, r) of the upper flank in the normal section, x from the mid-plane (mm)."""

    def normal(self, r: ArrayLike) -> NDArray[np.float64]:
        """Unit normals (n_x, n_r) of the upper flank, pointing out of the tooth."""

    def radial_moment(self, r_a: float, r_b: float) -> float:
        """|integral of r^2 d delta| between two radii (mm^3): the flank's share of the
        cross-section integral of a thread's volume."""

    def sample_radii(self, r_from: float, r_to: float, segments: int, chord: float) -> NDArray[np.float64]:
        """Radii from ``r_from`` to ``r_to`` (both included) in at least ``segments`` steps,
        with the normal-section chord sagitta at most ``chord`` (mm)."""

    def curvature_bound(self, r_max: float) -> float:
        """An upper bound (1/mm) of the flank's contribution to the normal curvature of the
        helical surface at radii up to ``r_max`` (used to size fine mesh patches)."""

    def axial_distance(self, u: NDArray, r: NDArray, quarter: float, cos_lead: float, r_root: float,
                       r_crest: float) -> NDArray[np.float64]:
        """Exact distance (mm) in the axial half-plane from points (u, r) (u from the tooth
        mid-plane) to the upper flank between the root and crest radii (the flank segment,
        axial widths / cos(lambda))."""

    def normal_outline(self, quarter: float, r_root: float, r_crest: float) -> list:
        """Both flanks of a tooth centred at x = 0 in the normal section, as drawing
        primitives (in the order drawings have always listed them)."""

    def axial_outline(self, mid: float, quarter: float, cos_lead: float, r_root: float,
                      r_crest: float) -> list:
        """The lower and upper flank of the tooth with mid-plane ``mid`` in the axial
        section (axial widths / cos(lambda)), as drawing primitives (lower first)."""


@dataclass(frozen=True)
class StraightFlank:
    """A straight flank: delta = sign tan(beta) (r - pitch_radius).

    Parameters
    ----------
    tan_beta : float
        tan of the flank half-angle beta (from the radial line).
    sign : {-1, +1}
        -1 for an external thread (tooth narrows outward), +1 for an internal thread.
    pitch_radius : float
        Radius (mm) where delta = 0.
    """

    tan_beta: float
    sign: int
    pitch_radius: float

    def at_pitch_radius(self, pitch_radius: float) -> "StraightFlank":
        return replace(self, pitch_radius=pitch_radius)

    def half_width(self, r: ArrayLike, quarter: float) -> NDArray[np.float64]:
        r = np.asarray(r, dtype=np.float64)
        if self.sign > 0:
            return quarter + self.tan_beta * (r - self.pitch_radius)
        return quarter - self.tan_beta * (r - self.pitch_radius)

    def drawing_half_width(self, r: float, quarter: float) -> float:
        return float(self.half_width(r, quarter))

    def slope(self, r: ArrayLike) -> NDArray[np.float64]:
        r = np.asarray(r, dtype=np.float64)
        return np.full_like(r, self.tan_beta if self.sign > 0 else -self.tan_beta)

    def curvature(self, r: ArrayLike) -> NDArray[np.float64]:
        return np.zeros_like(np.asarray(r, dtype=np.float64))

    def radius_at_half_width(self, w: ArrayLike, quarter: float) -> NDArray[np.float64]:
        w = np.asarray(w, dtype=np.float64)
        if self.sign > 0:
            return self.pitch_radius + (w - quarter) / self.tan_beta
        return self.pitch_radius - (w - quarter) / self.tan_beta

    def point(self, r: ArrayLike, quarter: float) -> NDArray[np.float64]:
        r = np.asarray(r, dtype=np.float64)
        return np.stack([self.half_width(r, quarter), r], axis=-1)

    def normal(self, r: ArrayLike) -> NDArray[np.float64]:
        r = np.asarray(r, dtype=np.float64)
        s = self.slope(r)
        n = np.stack([np.ones_like(r), -s], axis=-1)
        return n / np.linalg.norm(n, axis=-1, keepdims=True)

    def radial_moment(self, r_a: float, r_b: float) -> float:
        return self.tan_beta * abs(r_b ** 3 - r_a ** 3) / 3.0

    def sample_radii(self, r_from: float, r_to: float, segments: int, chord: float) -> NDArray[np.float64]:
        return np.linspace(r_from, r_to, max(1, segments) + 1)

    def curvature_bound(self, r_max: float) -> float:
        return 0.0

    def axial_distance(self, u: NDArray, r: NDArray, quarter: float, cos_lead: float, r_root: float,
                       r_crest: float) -> NDArray[np.float64]:
        tr = float(self.half_width(r_root, quarter)) / cos_lead
        tc = float(self.half_width(r_crest, quarter)) / cos_lead
        return point_segment_distance(np.stack(np.broadcast_arrays(u, r), axis=-1), (tc, r_crest), (tr, r_root))

    def normal_outline(self, quarter: float, r_root: float, r_crest: float) -> list:
        wr, wc = self.drawing_half_width(r_root, quarter), self.drawing_half_width(r_crest, quarter)
        return [Segment((-wr, r_root), (-wc, r_crest), "flank_lower"),
                Segment((wc, r_crest), (wr, r_root), "flank_upper")]

    def axial_outline(self, mid: float, quarter: float, cos_lead: float, r_root: float,
                      r_crest: float) -> list:
        tr = float(self.half_width(r_root, quarter)) / cos_lead
        tc = float(self.half_width(r_crest, quarter)) / cos_lead
        return [Segment((mid - tr, r_root), (mid - tc, r_crest), "flank_lower"),
                Segment((mid + tc, r_crest), (mid + tr, r_root), "flank_upper")]


@dataclass(frozen=True)
class ArcFlank:
    """The roller's convex flank: an arc of radius ``arc_radius`` centred on the part axis,
    delta = sqrt(r_T^2 - r^2) - sqrt(r_T^2 - pitch_radius^2)."""

    arc_radius: float
    pitch_radius: float

    def at_pitch_radius(self, pitch_radius: float) -> "ArcFlank":
        return replace(self, pitch_radius=pitch_radius)

    def half_width(self, r: ArrayLike, quarter: float) -> NDArray[np.float64]:
        r = np.asarray(r, dtype=np.float64)
        rt = self.arc_radius
        return quarter + np.sqrt(rt * rt - r * r) - math.sqrt(rt * rt - self.pitch_radius ** 2)

    def drawing_half_width(self, r: float, quarter: float) -> float:
        rt = self.arc_radius
        c0 = quarter - math.sqrt(rt * rt - self.pitch_radius ** 2)
        return c0 + math.sqrt(rt * rt - r * r)

    def slope(self, r: ArrayLike) -> NDArray[np.float64]:
        r = np.asarray(r, dtype=np.float64)
        return -r / np.sqrt(self.arc_radius ** 2 - r * r)

    def curvature(self, r: ArrayLike) -> NDArray[np.float64]:
        r = np.asarray(r, dtype=np.float64)
        rt2 = self.arc_radius ** 2
        return -rt2 / (rt2 - r * r) ** 1.5

    def radius_at_half_width(self, w: ArrayLike, quarter: float) -> NDArray[np.float64]:
        w = np.asarray(w, dtype=np.float64)
        rt = self.arc_radius
        s = w - quarter + math.sqrt(rt * rt - self.pitch_radius ** 2)
        return np.sqrt(rt * rt - s * s)

    def point(self, r: ArrayLike, quarter: float) -> NDArray[np.float64]:
        r = np.asarray(r, dtype=np.float64)
        return np.stack([self.half_width(r, quarter), r], axis=-1)

    def normal(self, r: ArrayLike) -> NDArray[np.float64]:
        # radial direction of the circle about (x_c, 0): (x - x_c, r) / r_T
        r = np.asarray(r, dtype=np.float64)
        return np.stack([np.sqrt(self.arc_radius ** 2 - r * r), r], axis=-1) / self.arc_radius

    def radial_moment(self, r_a: float, r_b: float) -> float:
        a = self.arc_radius

        def F(x: float) -> float:  # antiderivative of x^3 / sqrt(a^2 - x^2)
            return -(math.sqrt(a * a - x * x) * (x * x + 2 * a * a)) / 3.0
        return abs(F(r_b) - F(r_a))

    def sample_radii(self, r_from: float, r_to: float, segments: int, chord: float) -> NDArray[np.float64]:
        rt = self.arc_radius
        phi0, phi1 = math.asin(r_from / rt), math.asin(r_to / rt)
        dphi = 2.0 * math.acos(1.0 - chord / rt)
        k = max(segments, int(math.ceil(abs(phi1 - phi0) / dphi)))
        radii = rt * np.sin(np.linspace(phi0, phi1, k + 1))
        radii[0], radii[-1] = r_from, r_to
        return radii

    def curvature_bound(self, r_max: float) -> float:
        return 2.0 / (self.arc_radius - r_max)

    def axial_distance(self, u: NDArray, r: NDArray, quarter: float, cos_lead: float, r_root: float,
                       r_crest: float, iterations: int = 4) -> NDArray[np.float64]:
        """The axial section of the arc is the ellipse u' = (K + r_T cos phi) / cos(lambda),
        r' = r_T sin phi; the foot point is found by Newton on phi, started from the foot
        on the unstretched circle, and clamped to the flank's phi range (the squared
        distance is unimodal on an arc much shorter than a half turn, so clamping gives the
        segment distance)."""
        rt, c = self.arc_radius, cos_lead
        K = quarter - math.sqrt(rt * rt - self.pitch_radius ** 2)
        ph_a, ph_b = sorted((math.asin(r_root / rt), math.asin(r_crest / rt)))
        phi0 = np.arctan2(r, u * c - K)
        phi = phi0
        for _ in range(iterations):
            s, co = np.sin(phi), np.cos(phi)
            eu, er = (K + rt * co) / c - u, rt * s - r            # foot minus point
            du, dr = -rt * s / c, rt * co                          # d(foot)/dphi
            g = eu * du + er * dr
            gp = du * du + dr * dr + eu * (-rt * co / c) + er * (-rt * s)
            phi = phi - g / gp
        # any phi in range gives a point of the flank, hence an upper bound; keep the start
        # where Newton left the reals (far from the flank, never the nearest piece)
        phi = np.clip(np.where(np.isfinite(phi), phi, phi0), ph_a, ph_b)
        return np.hypot((K + rt * np.cos(phi)) / c - u, rt * np.sin(phi) - r)

    def normal_outline(self, quarter: float, r_root: float, r_crest: float) -> list:
        rt = self.arc_radius
        c0 = quarter - math.sqrt(rt * rt - self.pitch_radius ** 2)
        a_r, a_c = math.degrees(math.asin(r_root / rt)), math.degrees(math.asin(r_crest / rt))
        return [CircleArc((c0, 0.0), rt, a_r, a_c, "flank_upper"),
                CircleArc((-c0, 0.0), rt, 180.0 - a_c, 180.0 - a_r, "flank_lower")]

    def axial_outline(self, mid: float, quarter: float, cos_lead: float, r_root: float,
                      r_crest: float) -> list:
        # X = mid +- (c0 + sqrt(rt^2 - Y^2)) / c: the normal-section circle stretched axially
        c, rt = cos_lead, self.arc_radius
        c0 = quarter - math.sqrt(rt * rt - self.pitch_radius ** 2)
        t_r, t_c = math.asin(r_root / rt), math.asin(r_crest / rt)
        return [EllipseArc((mid - c0 / c, 0.0), rt / c, rt, math.pi - t_c, math.pi - t_r, "flank_lower"),
                EllipseArc((mid + c0 / c, 0.0), rt / c, rt, t_r, t_c, "flank_upper")]
