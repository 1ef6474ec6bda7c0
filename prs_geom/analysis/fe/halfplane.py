"""The contact band: Hertz semi-axes and the half-plane local term (pure math, no I/O).

Why these two
-------------
The load model counts the contact deformation with Hertz's point-contact approach
(:mod:`prs_geom.analysis.hertz`), the approach of points *far* from the
contact ellipse, and the tooth deformation separately. A ring load spread over the Hertz
width on an axisymmetric flank has, next to the tooth's structural deformation, a local
indentation of its own: the plane-strain compression between the loaded band and the
material around it. In the real part that neighbourhood is three-dimensional and belongs
to Hertz; in the smeared ring model it is a two-dimensional field that grows like
ln(distance / band width). Counting it in the tooth compliance would count the local
indentation twice, so :func:`local_term` gives it in closed form and the tooth
calibration subtracts it from the finite-element diagonal.

Plane-strain half-plane under a normal line load P (force per length) at the origin,
y into the body (Flamant's stresses sigma_rr = -2 P cos(theta) / (pi rho), integrated
here for the displacements): the displacement along the load axis at a point of polar
distance rho and angle theta from that axis is, up to a rigid translation,

    u_y(rho, theta) = -A ln(rho) + (A - B)/2 cos^2(theta) - B sin^2(theta),
    A = 2 (1 - nu^2) P / (pi E),   B = 2 nu (1 + nu) P / (pi E),

so on the surface (theta = +-pi/2) u_y = -A ln|x| - B. The *local term* of a band is the
load-weighted mean of u_y over the band minus u_y at a reference point inside the tooth:
the point where the tooth's axial section through the contact point meets the tooth
mid-plane (axial distance b/2 from the flank, b the axial tooth thickness at the
contact radius). That is where the beam models of the tooth (Yamamoto's bending and shear
terms) take their deflection, so the finite-element flank displacement minus the local
term is the tooth's structural deflection, and Hertz adds the contact on top.

Band distribution: the Hertz pressure p0 sqrt(1 - x^2/a^2 - y^2/b^2) integrated across the
ellipse's other axis gives a line load proportional to 1 - s^2 / a_m^2 along the meridian,
a_m the semi-axis that lies in the meridian plane (:func:`hertz_semi_axes`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import integrate

from prs_geom.analysis.hertz import hertz_contact

__all__ = ["HertzEllipse", "hertz_semi_axes", "band_weight", "local_term"]


@dataclass(frozen=True)
class HertzEllipse:
    """Hertz contact ellipse of a roller flank on a screw or nut flank.

    Parameters
    ----------
    normal_load_n : float
        Normal contact load Q (N).
    meridian_semi_axis_mm : float
        Semi-axis lying in the meridian (profile) plane, mm: the half-width of the loaded
        band along the flank.
    circumferential_semi_axis_mm : float
        Semi-axis along the circumference, mm: the ellipse width is twice this.
    ellipticity : float
        k = major / minor semi-axis (>= 1).
    """

    normal_load_n: float
    meridian_semi_axis_mm: float
    circumferential_semi_axis_mm: float
    ellipticity: float

    def __post_init__(self) -> None:
        for name in ("normal_load_n", "meridian_semi_axis_mm", "circumferential_semi_axis_mm"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be positive, got {v}")
        if not self.ellipticity >= 1.0:
            raise ValueError("ellipticity must be >= 1")


def hertz_semi_axes(meridian_curvatures: tuple[float, float], circumferential_curvatures: tuple[float, float],
                    eta: float, normal_load: float) -> HertzEllipse:
    """Semi-axes of the Hertz ellipse (:func:`prs_geom.analysis.hertz.hertz_contact`, the
    same constants as the load model's Hertz approach).

    a = (2 k^2 E(e) / pi)^(1/3) (3 Q eta / (2 sum_rho))^(1/3), b = a / k; the major axis a
    lies in the plane with the smaller curvature sum.

    Parameters
    ----------
    meridian_curvatures, circumferential_curvatures : (float, float)
        Principal curvatures (1/mm) of (roller, flank) in the meridian plane and across it
        (roller 1/r_T in both; screw flank 0 and +sin(beta)/r_c, nut 0 and -sin(beta)/r_c).
    eta : float
        sum over both bodies of (1 - nu^2)/E (1/MPa).
    normal_load : float
        Q (N).
    """
    if not (sum(meridian_curvatures) > 0 and sum(circumferential_curvatures) > 0):
        raise ValueError("both curvature sums must be positive")
    (r11, r21), (r12, r22) = meridian_curvatures, circumferential_curvatures
    contact = hertz_contact((r11, r12, r21, r22), eta)
    a, b = contact.semi_axes(normal_load)
    merid, circ = (a, b) if contact.major_in_plane_1 else (b, a)
    return HertzEllipse(normal_load, merid, circ, contact.ellipticity)


def band_weight(s: np.ndarray, half_width: float) -> np.ndarray:
    """Unnormalised line-load shape 1 - (s / a_m)^2 on |s| <= a_m, 0 outside."""
    x = np.asarray(s, dtype=np.float64) / half_width
    return np.where(np.abs(x) < 1.0, 1.0 - x * x, 0.0)


def _self_log_constant() -> float:
    """kappa = double integral of w(x) w(x') ln|x - x'| for the normalised parabolic shape
    w = 3/4 (1 - x^2) on [-1, 1]: the band's own mean of ln|x - x'| is ln(a_m) + kappa."""
    g, wg = np.polynomial.legendre.leggauss(8)

    def autocorr(d: float) -> float:
        # integral of w(x) w(x - d) over the overlap [d - 1, 1] (exact: degree-4 polynomial)
        lo, hi = d - 1.0, 1.0
        x = 0.5 * (hi - lo) * g + 0.5 * (hi + lo)
        f = 0.5625 * (1.0 - x * x) * (1.0 - (x - d) ** 2)
        return 0.5 * (hi - lo) * float(wg @ f)

    val, _ = integrate.quad(autocorr, 0.0, 2.0, weight="alg-loga", wvar=(0.0, 0.0), epsabs=1e-14, epsrel=1e-13)
    return 2.0 * val


_KAPPA = _self_log_constant()


def local_term(half_width: float, ref_distance: float, ref_angle: float, E: float, nu: float) -> float:
    """Half-plane local term of a parabolic band, mm per (N/mm) of normal line load.

    The load-weighted mean normal displacement of the band (half-width ``half_width``, mm)
    minus the normal displacement of the reference point at distance ``ref_distance`` (mm)
    from the band centre, ``ref_angle`` (rad) from the load axis (module docstring);
    plane strain, Young's modulus E (MPa), Poisson's ratio nu. Positive: the band moves
    farther into the body than the reference point.
    """
    if not (half_width > 0 and ref_distance > 0):
        raise ValueError("band half-width and reference distance must be positive")
    A = 2.0 * (1.0 - nu * nu) / (math.pi * E)
    B = 2.0 * nu * (1.0 + nu) / (math.pi * E)
    band_mean = -A * (math.log(half_width) + _KAPPA) - B
    # the reference point's displacement, averaged over the load positions x' in the band
    g, wg = np.polynomial.legendre.leggauss(64)
    xs = half_width * g
    w = 0.75 * (1.0 - g * g) * wg                      # normalised weight x Gauss weight
    xr = ref_distance * math.sin(ref_angle) - xs
    yr = ref_distance * math.cos(ref_angle)
    rho2 = xr * xr + yr * yr
    cos2 = yr * yr / rho2
    u_ref = float(w @ (-0.5 * A * np.log(rho2) + 0.5 * (A - B) * cos2 - B * (1.0 - cos2)))
    return band_mean - u_ref
