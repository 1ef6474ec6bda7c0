"""Part frames and roller placement (pure math, no mesh library).

Part frames (z along the part axis, mm):

* nut: thread from z = 0 (loaded end, tooth 1) to z = n p; nut tooth j (the ridge whose
  pitch list entries count) has its mid-plane at z = (j - 1) p at theta = 0, on the -z
  side of roller tooth j: the nut tooth that carries roller tooth j when the load flows
  toward -z (screw pulled at the loaded end; see docs/theory/loads.md).
* roller: thread from 0 to n p; tooth j mid-plane at z = (j - 1/2) p at local theta = 0.
* screw: thread (:func:`screw_z_range`) centred on the nut thread at mid-stroke; a tooth mid-plane
  at z = p/2 at theta = 0.

Assembly (screw frame = nut frame): roller k sits at carrier angle psi_k = 2 pi k / z with
its axis at (a cos psi_k, a sin psi_k); its local theta = 0 points away from the screw.
Phases: with the mid-planes above, roller 0 (psi = 0, no spin) has a tooth mid-plane in
the screw groove mid-plane on the line of centres and in the nut groove mid-plane at the
nut side; the nut groove mid-plane at psi = 0 sits p/2 from the screw groove mid-plane.
Roller k is spun about its own axis by chi_k = -n_s psi_k, which moves its teeth axially
by the screw lead times psi_k / 2 pi (mod p), so every roller meshes with the same screw
and, with n_n = n_s, the same nut. The same formula holds for both hands: a left-hand
assembly is the mirror image (y -> -y) of the right-hand one, and mirroring maps
(psi, chi) to (-psi, -chi). See docs/theory/conventions.md.
"""
from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prs_geom.model.design import PRSDesign
from prs_geom.geometry.helix import PitchWarp, identity_warp

__all__ = [
    "FIRST_MID_PITCHES", "carrier_angles", "part_warps", "roller_spin", "roller_transform", "rotation_z",
    "screw_thread_length", "screw_z_range", "thread_length", "translation",
]


def rotation_z(angle: ArrayLike) -> NDArray[np.float64]:
    """Homogeneous rotations about +z by ``angle`` (rad).

    Right-handed: a positive angle turns +x toward +y, i.e. counter-clockwise seen from +z
    looking down -z. Applied to column vectors, ``rotation_z(a) @ (x, y, z, 1)`` is the
    point turned by ``a``::

        [[cos a, -sin a, 0, 0],
         [sin a,  cos a, 0, 0],
         [0,      0,     1, 0],
         [0,      0,     0, 1]]

    Parameters
    ----------
    angle
        A scalar or an array of angles (rad), any shape ``S``.

    Returns
    -------
    NDArray[np.float64]
        Shape ``S + (4, 4)``: (4, 4) for a scalar. The rotation alone is ``[..., :3, :3]``.
    """
    a = np.asarray(angle, dtype=np.float64)
    c, s = np.cos(a), np.sin(a)
    T = np.zeros(a.shape + (4, 4))
    T[..., 0, 0], T[..., 0, 1], T[..., 1, 0], T[..., 1, 1] = c, -s, s, c
    T[..., 2, 2] = T[..., 3, 3] = 1.0
    return T


def translation(x: float, y: float = 0.0, z: float = 0.0) -> NDArray[np.float64]:
    """4x4 homogeneous translation by (x, y, z) (mm)."""
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def carrier_angles(design: PRSDesign) -> NDArray[np.float64]:
    """psi_k = 2 pi k / z (rad)."""
    z = design.roller.count
    return 2.0 * math.pi * np.arange(z) / z


def roller_spin(design: PRSDesign, psi: float) -> float:
    """chi_k (rad) for a roller at carrier angle psi (see module docstring)."""
    return -design.screw.starts * psi


def roller_transform(design: PRSDesign, k: int) -> NDArray[np.float64]:
    """4x4 transform from roller k's part frame to the screw frame."""
    psi = float(carrier_angles(design)[k])
    return rotation_z(psi) @ translation(design.centre_distance_mm) @ rotation_z(roller_spin(design, psi))


def thread_length(design: PRSDesign) -> float:
    """Engaged thread length n p (mm): the roller and nut threads run over [0, n p]."""
    return design.thread.engaged_teeth * design.thread.pitch_mm


def screw_z_range(design: PRSDesign) -> tuple[float, float]:
    """(z_lo, z_hi) (mm) of the screw thread (run-outs included) in the screw frame, centred
    on the nut thread at mid-stroke: ``screw.length_mm`` long, or for an actuator what the
    nut assembly, the stroke, the over-travels and the run-outs need
    (:func:`prs_geom.geometry.actuator.screw_thread_span`)."""
    from prs_geom.geometry.actuator import screw_thread_span

    return screw_thread_span(design)


def screw_thread_length(design: PRSDesign) -> float:
    """Threaded length of the screw (mm), run-outs included (:func:`screw_z_range`)."""
    lo, hi = screw_z_range(design)
    return hi - lo


def part_warps(design: PRSDesign) -> dict[str, PitchWarp]:
    """Graded-pitch warps of the three parts (identity for the screw)."""
    p = design.thread.pitch_mm
    return {
        "screw": identity_warp(p),
        "roller": PitchWarp(0.5 * p, p, design.roller.pitch_list_mm),
        "nut": PitchWarp(0.0, p, design.nut.pitch_list_mm),
    }


#: Helix coordinate of a tooth mid-plane of start 0 at theta = 0, by part (in pitches).
FIRST_MID_PITCHES = {"screw": 0.5, "roller": 0.5, "nut": 0.0}
