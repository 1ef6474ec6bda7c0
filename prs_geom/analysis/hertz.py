"""Hertz point contact of two elastic bodies (pure numpy/scipy, no I/O).

Units: curvatures 1/mm (convex positive, concave negative), the elastic constant
eta = sum over both bodies of (1 - nu^2) / E in 1/MPa (eta = 1 / E* of Johnson), loads N,
lengths mm.

Geometry: the two bodies touch at a point with aligned principal planes 1 and 2; body i
has principal curvatures rho_i1 (plane 1) and rho_i2 (plane 2). With the curvature sum
sum_rho = rho_11 + rho_12 + rho_21 + rho_22 (> 0) and the curvature difference

    F(rho) = |(rho_11 - rho_12) + (rho_21 - rho_22)| / sum_rho
           = |(rho_11 + rho_21) - (rho_12 + rho_22)| / sum_rho,

the ellipticity k = a / b >= 1 of the contact ellipse solves (complete elliptic integrals
K(e), E(e) of modulus e, e^2 = 1 - 1/k^2, scipy's parameter m = e^2)

    F(rho) = [(k^2 + 1) E(e) - 2 K(e)] / [(k^2 - 1) E(e)]

and, for a normal load Q (Harris, Rolling Bearing Analysis, ch. 6; the same closed form as
Johnson, Contact Mechanics, 1985, section 3.5, written in k instead of e),

    a = (2 k^2 E(e) / pi)^(1/3) (3 Q eta / (2 sum_rho))^(1/3)     semi-major axis
    b = (2 E(e) / (pi k))^(1/3) (3 Q eta / (2 sum_rho))^(1/3)     semi-minor axis, b = a / k
    delta = C Q^(2/3),
    C = (2 K(e) / pi) (pi / (2 k^2 E(e)))^(1/3) (3 eta / (2 sum_rho))^(2/3) sum_rho / 2,

delta the normal approach of two points far from the contact. The major axis lies in the
principal plane with the smaller curvature sum. The circular case (k = 1, K = E = pi / 2)
is a = (3 Q R eta / 4)^(1/3), delta = a^2 / R for a sphere of radius R on a plane.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

from scipy import optimize, special

__all__ = ["ellipticity", "HertzContact", "hertz_contact"]


def ellipticity(F_rho: float) -> float:
    """k >= 1 with F(rho) = [(k^2 + 1) E(e) - 2 K(e)] / [(k^2 - 1) E(e)], e^2 = 1 - 1/k^2.

    ``F_rho`` is the curvature difference in [0, 1) (module docstring); k = 1 for
    F_rho <= 1e-12 (circular contact), else the root on [1 + 1e-9, 1e4] to 1e-14."""
    if F_rho <= 1e-12:
        return 1.0

    def f(k: float) -> float:
        m = 1.0 - 1.0 / (k * k)
        E, K = special.ellipe(m), special.ellipk(m)
        return ((k * k + 1.0) * E - 2.0 * K) / ((k * k - 1.0) * E) - F_rho

    return optimize.brentq(f, 1.0 + 1e-9, 1e4, xtol=1e-14, rtol=1e-15)


@dataclass(frozen=True)
class HertzContact:
    """The load-independent constants of one Hertz point contact (module docstring).

    Parameters
    ----------
    curvature_sum_per_mm : float
        sum_rho (1/mm), > 0.
    curvature_difference : float
        F(rho), in [0, 1).
    ellipticity : float
        k = a / b >= 1.
    eta_per_mpa : float
        sum of (1 - nu^2) / E over both bodies (1/MPa).
    approach_constant : float
        C of delta = C Q^(2/3) (mm N^(-2/3)).
    semi_major_per_cbrt_n, semi_minor_per_cbrt_n : float
        a / Q^(1/3) and b / Q^(1/3) (mm N^(-1/3)).
    major_in_plane_1 : bool
        The major axis lies in principal plane 1 (plane 1 has the smaller curvature sum, or
        the sums are equal).
    """

    curvature_sum_per_mm: float
    curvature_difference: float
    ellipticity: float
    eta_per_mpa: float
    approach_constant: float
    semi_major_per_cbrt_n: float
    semi_minor_per_cbrt_n: float
    major_in_plane_1: bool

    def __post_init__(self) -> None:
        for name in ("curvature_sum_per_mm", "eta_per_mpa", "approach_constant", "semi_major_per_cbrt_n",
                     "semi_minor_per_cbrt_n"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        if not self.ellipticity >= 1.0:
            raise ValueError(f"ellipticity must be >= 1, got {self.ellipticity}")

    @property
    def plane_2_semi_axis_per_cbrt_n(self) -> float:
        """The semi-axis along principal plane 2 per Q^(1/3) (mm N^(-1/3))."""
        return self.semi_minor_per_cbrt_n if self.major_in_plane_1 else self.semi_major_per_cbrt_n

    def semi_axes(self, load_n: float) -> tuple[float, float]:
        """(a, b) in mm under normal load ``load_n`` (N), a the semi-major axis."""
        k = self.ellipticity
        E = float(special.ellipe(1.0 - 1.0 / (k * k)))
        a = (2.0 * k * k * E / math.pi) ** (1.0 / 3.0) \
            * (3.0 * load_n * self.eta_per_mpa / (2.0 * self.curvature_sum_per_mm)) ** (1.0 / 3.0)
        return a, a / k

    def approach(self, load_n: float) -> float:
        """Normal approach delta = C Q^(2/3) (mm) under normal load ``load_n`` (N)."""
        return self.approach_constant * load_n ** (2.0 / 3.0)


def hertz_contact(curvatures: Sequence[float], eta: float) -> HertzContact:
    """The Hertz constants of principal curvatures (rho_11, rho_12, rho_21, rho_22) (1/mm;
    body 1 planes 1, 2, then body 2 planes 1, 2) and eta = sum (1 - nu^2) / E (1/MPa).

    Raises ValueError unless the curvature sum is positive (a conformal or concave-dominated
    pair has no Hertz contact)."""
    r11, r12, r21, r22 = (float(c) for c in curvatures)
    sum_rho = r11 + r12 + r21 + r22
    if not sum_rho > 0:
        raise ValueError(f"the contact curvature sum must be positive, got {sum_rho}")
    F_rho = abs((r11 - r12) + (r21 - r22)) / sum_rho
    k = ellipticity(F_rho)
    m = 1.0 - 1.0 / (k * k)
    E, K = float(special.ellipe(m)), float(special.ellipk(m))
    C = (2.0 * K / math.pi) * (math.pi / (2.0 * k * k * E)) ** (1.0 / 3.0) \
        * (3.0 * eta / (2.0 * sum_rho)) ** (2.0 / 3.0) * sum_rho / 2.0
    base = (3.0 * eta / (2.0 * sum_rho)) ** (1.0 / 3.0)
    return HertzContact(curvature_sum_per_mm=sum_rho, curvature_difference=F_rho, ellipticity=k, eta_per_mpa=eta,
                        approach_constant=C, semi_major_per_cbrt_n=(2.0 * k * k * E / math.pi) ** (1.0 / 3.0) * base,
                        semi_minor_per_cbrt_n=(2.0 * E / (math.pi * k)) ** (1.0 / 3.0) * base,
                        major_in_plane_1=r11 + r21 <= r12 + r22)
