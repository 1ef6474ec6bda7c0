"""Helical thread surfaces and the graded-pitch warp (docs/theory/geometry.md).

Pure math, no I/O.

Helix coordinate
----------------
Every point of a thread surface belongs to one tooth (material ridge) period. The
*helix coordinate* m of that tooth at angle theta is the nominal axial position of its
mid-plane: m = m0 + k p + L theta / 2 pi for start k (right hand; see
:func:`prs_geom.mesh.thread_mesh` for the left hand). A point at axial offset u from the
mid-plane (u in [-p/2, p/2), see :mod:`prs_geom.profiles`) sits at

    z = W(m) + u,      r = rho(u)

Graded pitch: the warp W
------------------------
W(m) = m + c(m) where c is the cumulative pitch correction. Knots: tooth j = 1..n has its
mid-plane at m_j = m_1 + (j - 1) p at the reference angle theta = 0, and
c(m_j) = sum_{k<j} (p_k - p), so W(m_{j+1}) - W(m_j) = p_j exactly. Between knots c is
a monotone C1 piecewise cubic (Fritsch-Carlson / PCHIP; no overshoot, so W stays monotone);
outside the knot range c continues linearly with its end slope.

Interpretation: the warp acts on the tooth mid-plane coordinate, so every tooth keeps its
designed profile and thickness (rigid teeth) and the root between two teeth takes up the
pitch change. Consequences, stated so nobody has to rediscover them:

* at theta = 0 the axial distance between the same flank of teeth j and j + 1 is p_j at
  every radius, exactly;
* at another angle theta the flank of the tooth through knot j sits at
  W(m_j + L theta / 2 pi) + u: the pitch there blends p_j and its neighbour (no continuous
  helical surface can carry a different pitch per tooth at every angle), which is also what
  the rollers see as they spin, because rollers do not move axially relative to the nut;
* the screw translates relative to the rollers, so it stays constant pitch (W = identity).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import PchipInterpolator

__all__ = ["PitchWarp", "identity_warp"]


@dataclass(frozen=True)
class PitchWarp:
    """The warp W(m) = m + c(m) of a graded-pitch thread.

    Parameters
    ----------
    first_knot : float
        m_1, helix coordinate (mm) of tooth 1's mid-plane at theta = 0.
    pitch : float
        Nominal pitch p (mm).
    pitch_list : sequence of float or None
        The n - 1 pitches p_j (mm); None or all equal to p gives the identity.
    """

    first_knot: float
    pitch: float
    pitch_list: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        if self.pitch_list is not None:
            object.__setattr__(self, "pitch_list", tuple(float(x) for x in self.pitch_list))

    @property
    def is_identity(self) -> bool:
        """True when every tooth-to-tooth pitch equals the constant pitch (no warp)."""
        return self.pitch_list is None or all(pj == self.pitch for pj in self.pitch_list)

    @property
    def knots(self) -> NDArray[np.float64]:
        """Nominal mid-plane positions m_j of teeth 1..n at theta = 0 (mm)."""
        n = 1 if self.pitch_list is None else len(self.pitch_list) + 1
        return self.first_knot + self.pitch * np.arange(n, dtype=np.float64)

    @property
    def knot_corrections(self) -> NDArray[np.float64]:
        """c(m_j) = sum_{k<j} (p_k - p) (mm), tooth 1 the datum (0)."""
        if self.pitch_list is None:
            return np.zeros(1)
        # summed as differences so that the sub-micrometre corrections keep full precision
        return np.concatenate([[0.0], np.cumsum(np.asarray(self.pitch_list) - self.pitch)])

    def _interp(self) -> PchipInterpolator:
        cache = self.__dict__.get("_pchip")
        if cache is None:
            cache = PchipInterpolator(self.knots, self.knot_corrections, extrapolate=False)
            object.__setattr__(self, "_pchip", cache)
        return cache

    def correction(self, m: ArrayLike) -> NDArray[np.float64]:
        """c(m) (mm)."""
        m = np.asarray(m, dtype=np.float64)
        if self.is_identity:
            return np.zeros_like(m)
        return self._eval(m, 0)

    def correction_slope(self, m: ArrayLike) -> NDArray[np.float64]:
        """dc/dm (dimensionless)."""
        m = np.asarray(m, dtype=np.float64)
        if self.is_identity:
            return np.zeros_like(m)
        return self._eval(m, 1)

    def correction_curvature(self, m: ArrayLike) -> NDArray[np.float64]:
        """d2c/dm2 (1/mm); zero outside the knot range (linear continuation)."""
        m = np.asarray(m, dtype=np.float64)
        if self.is_identity:
            return np.zeros_like(m)
        return self._eval(m, 2)

    def _eval(self, m: NDArray[np.float64], nu: int) -> NDArray[np.float64]:
        f = self._interp()
        k = self.knots
        lo, hi = k[0], k[-1]
        c = self.knot_corrections
        s_lo, s_hi = f(lo, 1), f(hi, 1)
        inside = np.clip(m, lo, hi)
        val = f(inside, nu)
        if nu == 0:
            val = np.where(m < lo, c[0] + s_lo * (m - lo), val)
            val = np.where(m > hi, c[-1] + s_hi * (m - hi), val)
        elif nu == 1:
            val = np.where(m < lo, s_lo, np.where(m > hi, s_hi, val))
        else:
            val = np.where((m < lo) | (m > hi), 0.0, val)
        return np.asarray(val, dtype=np.float64)

    def __call__(self, m: ArrayLike) -> NDArray[np.float64]:
        """W(m) = m + c(m) (mm)."""
        m = np.asarray(m, dtype=np.float64)
        return m + self.correction(m)

    def inverse(self, z: ArrayLike) -> NDArray[np.float64]:
        """m with W(m) = z, by fixed-point iteration m <- z - c(m).

        Converges geometrically with ratio max|c'| (< 0.02 by design validation), so a
        handful of iterations reach float64 resolution.
        """
        z = np.asarray(z, dtype=np.float64)
        if self.is_identity:
            return z.copy()
        m = z - self.correction(z)
        for _ in range(60):
            m_new = z - self.correction(m)
            if np.max(np.abs(m_new - m), initial=0.0) <= 1e-15 * max(1.0, float(np.max(np.abs(z), initial=0.0))):
                return m_new
            m = m_new
        return m


def identity_warp(pitch: float) -> PitchWarp:
    """The warp of a constant-pitch thread."""
    return PitchWarp(0.0, pitch, None)

