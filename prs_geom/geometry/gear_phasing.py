"""Phasing of the roller gears: the spin that meshes a pinion with the ring gear (pure math).

Owns the mesh phase of one pinion at a carrier angle (:func:`mesh_phase`), whether one gear
offset on identical rollers meshes every roller (:func:`roller_gear_phasing`) and the
assembly rule behind it (:func:`phasing_divisible`). Conventions (units, gear frame) are those
of :mod:`~prs_geom.geometry.gears`; derivations in docs/theory/gears.md.

Phasing
-------
A pinion (roller gear) whose centre is at distance a on the ray at carrier angle psi from
the ring centre is described, like a roller (docs/theory/conventions.md "Roller placement"),
by its spin chi about its own axis **relative to its line of centres**:
T = R_z(psi) Tr(a, 0, 0) R_z(chi). ``mesh_phase`` returns the spin that centres its teeth
in the ring's tooth spaces: chi = pi / z_p - psi z_r / z_p (mod 2 pi / z_p).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prs_geom.geometry.gear_checks import require_internal_pair
from prs_geom.geometry.gears import SpurGear
from prs_geom.geometry.planar import frozen_float64

__all__ = ["RollerGearPhasing", "mesh_phase", "phasing_divisible", "roller_gear_phasing"]

_TWO_PI = 2.0 * math.pi


def mesh_phase(pinion: SpurGear, ring: SpurGear, carrier_angle_rad: ArrayLike) -> NDArray[np.float64] | float:
    """Spin of the pinion (rad) that centres its teeth in the ring's tooth spaces.

    Frame: ring frame with ring tooth 0 centred on +x; the pinion centre is at distance a on
    the ray at ``carrier_angle_rad`` psi; the pinion is placed by R_z(psi) Tr(a) R_z(chi), so
    chi is measured from the line of centres (pinion tooth 0 on the line, pointing away from
    the ring centre, at chi = 0). With this chi the mesh is mirror-symmetric about the line
    through the pinion tooth and the ring space it sits in, so the backlash is shared equally
    by both flank sides.

    chi = pi / z1 - psi z2 / z1, reduced to [0, 2 pi / z1).

    Derivation: at psi = pi / z2 a ring space is centred on the line of centres, and so is a
    pinion tooth at chi = 0 (mirror symmetry). Conjugate involutes keep the rolling relation
    of the working pitch circles exactly, r_w1 d(chi) = -r_w2 d(psi) relative to the line of
    centres, with r_w2 / r_w1 = z2 / z1 at any centre distance.
    """
    require_internal_pair(pinion, ring)
    z1, z2 = pinion.teeth, ring.teeth
    psi = np.asarray(carrier_angle_rad, dtype=float)
    out = np.mod(math.pi / z1 - psi * (z2 / z1), _TWO_PI / z1)
    return float(out) if out.ndim == 0 else out


@dataclass(frozen=True)
class RollerGearPhasing:
    """Whether identical rollers (one gear offset relative to the thread) all mesh.

    Attributes
    ----------
    consistent : bool
        True when mesh_phase(psi_k) - chi_k is the same modulo 2 pi / z_g for every roller.
    offset_rad : float
        The angle of gear tooth 0 in the roller part frame (rad, in [0, 2 pi / z_g)): the gear
        is cut with its tooth 0 at this angle from the roller's reference direction theta = 0.
        Taken from roller 0 when not consistent.
    residuals_rad : ndarray
        Per roller, (mesh_phase - chi_k - offset) wrapped to [-pi/z_g, pi/z_g): how far each
        roller's gear would be turned out of the symmetric position.
    """

    consistent: bool
    offset_rad: float
    residuals_rad: NDArray[np.float64]


def roller_gear_phasing(pinion: SpurGear, ring: SpurGear, carrier_angles_rad: ArrayLike,
                        roller_spins_rad: ArrayLike, *, tol_rad: float = 1e-9) -> RollerGearPhasing:
    """Check that one gear offset on the (identical) rollers meshes every roller.

    Parameters
    ----------
    carrier_angles_rad : array (z,)
        psi_k of the rollers (rad), e.g. ``prs_geom.geometry.frames.carrier_angles``.
    roller_spins_rad : array (z,)
        chi_k, the spins the thread imposes (rad), chi_k = -n_s psi_k
        (``frames.roller_spin``).

    Notes
    -----
    With psi_k = 2 pi k / z and chi_k = -n_s psi_k the residual of roller k is
    -(2 pi k / z)(z2 - n_s z1)/z1 mod 2 pi / z1: zero for all k exactly when z divides
    (z_ring - n_s z_g) (:func:`phasing_divisible`).
    """
    psi = np.atleast_1d(np.asarray(carrier_angles_rad, dtype=float))
    chi = np.atleast_1d(np.asarray(roller_spins_rad, dtype=float))
    if psi.shape != chi.shape:
        raise ValueError("carrier_angles_rad and roller_spins_rad must have the same shape")
    period = _TWO_PI / pinion.teeth
    raw = np.asarray(mesh_phase(pinion, ring, psi)) - chi
    offset = float(np.mod(raw[0], period))
    res = np.mod(raw - offset + 0.5 * period, period) - 0.5 * period
    return RollerGearPhasing(consistent=bool(np.all(np.abs(res) <= tol_rad)), offset_rad=offset,
                             residuals_rad=frozen_float64(res))


def phasing_divisible(roller_count: int, ring_teeth: int, pinion_teeth: int, screw_starts: int) -> bool:
    """The assembly rule: identical rollers all mesh with one ring gear iff
    z (roller count) divides z_ring - n_s z_g (for psi_k = 2 pi k / z, chi_k = -n_s psi_k)."""
    return (ring_teeth - screw_starts * pinion_teeth) % roller_count == 0
