"""Exact 2D drawing primitives: straight segments, circular and elliptical arcs (no I/O).

Coordinates: X along the part axis (mm), Y the radius (mm). The DXF exporter writes them as
LINE, ARC and ELLIPSE entities.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["CircleArc", "EllipseArc", "Segment"]


@dataclass(frozen=True)
class Segment:
    """Straight segment from ``start`` to ``end`` (X, Y in mm); ``kind`` names the profile piece."""

    start: tuple[float, float]
    end: tuple[float, float]
    kind: str = "segment"   # "flank_lower", "flank_upper", "crest", "root", "end", "body"


@dataclass(frozen=True)
class EllipseArc:
    """Points centre + (a cos t, b sin t), t from start to end (counter-clockwise)."""

    centre: tuple[float, float]
    a: float       # semi-axis along X
    b: float       # semi-axis along Y (b <= a)
    start: float
    end: float
    kind: str

    def point(self, t: float) -> tuple[float, float]:
        """The arc's point (X, Y in mm) at parameter t (rad)."""
        return (self.centre[0] + self.a * math.cos(t), self.centre[1] + self.b * math.sin(t))


@dataclass(frozen=True)
class CircleArc:
    """Circular arc about ``centre`` (mm) of ``radius`` (mm) from ``start_deg`` to ``end_deg``
    (degrees, counter-clockwise, as DXF ARC writes them); ``kind`` names the profile piece."""

    centre: tuple[float, float]
    radius: float
    start_deg: float
    end_deg: float
    kind: str
