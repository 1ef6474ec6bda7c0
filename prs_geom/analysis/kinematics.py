"""Ideal kinematics of the planetary roller screw (docs/theory/kinematics.md).

Owns the rigid-body motion of the mechanism when the screw is driven and the nut is held
from turning: the speed ratios of the planetary train (carrier, roller spin), the nut's
axial travel, the rollers' axial drift relative to the nut, the 4x4 poses of every part
as functions of the screw angle (for animation), and the sliding velocity at the analytic
screw-roller and roller-nut contact points of :mod:`prs_geom.analysis.contact`.
Pure numpy, no I/O, no mesh library.

Frames
------
All poses and velocities are in the screw's **fixed world frame**: the screw frame of
docs/theory/conventions.md at screw angle 0 (z along the screw axis, +x through the axis
of roller 0, origin on the axis in the loaded-end plane of the nut thread). It is the
frame the static assembly is built in, so at screw angle 0 every pose is the static
placement (identity, or :func:`prs_geom.geometry.frames.roller_transform` for roller k).

Units and signs
---------------
Lengths mm, angles rad, speeds per unit screw speed: every speed below is the value at
w_s = 1 rad/s (so mm/s per rad/s of screw speed, i.e. mm per rad). Angular speeds are
positive for a right-handed rotation about +z. The nut is held from turning; the screw
does not translate.

* carrier w_c / w_s = r_s / (r_s + r_n) (Willis' formula, ring fixed), positive: the
  carrier turns with the screw;
* roller spin relative to the carrier w_r,rel / w_s = -(w_c / w_s) r_n / r_r, negative;
  absolute w_r,abs / w_s = w_c / w_s + w_r,rel / w_s;
* nut travel per screw turn (signed, along +z) s_n = -h p [n_s - (n_s - n_n) w_c / w_s],
  h = +1 right hand, -1 left hand: a right-hand design turned positively about +z moves
  its nut toward -z (the screw advances into the nut like a bolt); with n_s = n_n this is
  -h L_s whatever the radii;
* roller drift relative to the nut per screw turn h p (n_n w_c / w_s + w_r,rel / w_s),
  zero when r_n = n_n r_r.

Sliding velocities are those of the **roller** surface relative to the mating surface
(screw or nut) at the contact point: v_slide = v_roller - v_mate.

Designs whose nut pitch circle does not touch the roller pitch circle
(r_n != r_s + 2 r_r) or whose nut-roller ratio differs from the end gears' ratio
(r_n != n_n r_r) are refused with a ValueError: there the gears, the nut thread and the
pitch circles prescribe different roller spins, and which contact slips is not a question
of kinematics. Screw starts different from nut starts are accepted (general
thread-engagement formula above).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prs_geom.analysis.contact import ContactPoint, ContactResult, analyse_contact
from prs_geom.geometry.frames import carrier_angles, roller_transform, rotation_z
from prs_geom.model.design import SIZING_RTOL, PRSDesign

__all__ = ["BODIES", "SIDES", "check_kinematic_sizing", "SpeedRatios", "speed_ratios", "ContactSliding",
           "Kinematics", "contact_sliding", "kinematics", "Poses", "poses"]

TWO_PI = 2.0 * math.pi
#: Bodies whose material velocity :meth:`Kinematics.material_velocity` gives.
BODIES = ("screw", "carrier", "roller", "nut")
#: The mating part of the roller at each contact side.
SIDES = ("screw", "nut")


# --------------------------------------------------------------------------- sizing
def _pitch_radii(design: PRSDesign) -> tuple[float, float, float]:
    """Nominal pitch radii r_s, r_r, r_n (mm)."""
    return (0.5 * design.screw.pitch_diameter_mm, 0.5 * design.roller.pitch_diameter_mm,
            0.5 * design.nut.pitch_diameter_mm)


def check_kinematic_sizing(design: PRSDesign) -> None:
    """Raise ValueError when the ideal kinematics of this module does not apply.

    Two relations must hold (relative tolerance ``SIZING_RTOL`` of the design model):

    * r_n = r_s + 2 r_r (``nut.pitch_diameter_mm = screw.pitch_diameter_mm +
      2 roller.pitch_diameter_mm``): the roller pitch circle touches the nut pitch circle
      at the fixed centre distance a = r_s + r_r, so "rolling at the pitch circles" is a
      motion;
    * r_n = n_n r_r (``nut.pitch_diameter_mm = nut.starts x roller.pitch_diameter_mm``): the
      end gears, sized z_ring = n_n z_g, then impose the same roller spin as rolling on the
      nut pitch circle, and the rollers do not drift axially against their carriers.

    ``screw.starts`` may differ from ``nut.starts``: the nut travel then follows the general
    thread-engagement formula (docs/theory/kinematics.md).
    """
    rs, rr, rn = _pitch_radii(design)
    nn = design.nut.starts

    def off(x: float, y: float) -> bool:
        return abs(x - y) > SIZING_RTOL * max(abs(x), abs(y), 1.0)

    broken = []
    if off(rn, rs + 2.0 * rr):
        broken.append(f"nut.pitch_diameter_mm ({2 * rn:g}) must equal screw.pitch_diameter_mm + "
                      f"2 x roller.pitch_diameter_mm ({2 * (rs + 2 * rr):g}): otherwise the roller "
                      f"and nut pitch circles do not touch and rolling at the pitch circles is no motion")
    if off(rn, nn * rr):
        broken.append(f"nut.pitch_diameter_mm ({2 * rn:g}) must equal nut.starts x "
                      f"roller.pitch_diameter_mm ({2 * nn * rr:g}): otherwise the end gears "
                      f"(z_ring = n_n z_g) and the nut thread prescribe different roller spins "
                      f"and the rollers would drift against their carriers")
    if broken:
        raise ValueError("ideal PRS kinematics needs the standard nut sizing; " + "; ".join(broken))


@dataclass(frozen=True)
class SpeedRatios:
    """The planetary train of a design, per unit screw speed (see the module docstring).

    Attributes
    ----------
    carrier : float
        w_c / w_s (-).
    roller_relative : float
        Roller spin about its own axis relative to the carrier, w_r,rel / w_s (-).
    roller_absolute : float
        Roller spin in the world frame, w_r,abs / w_s (-).
    nut_travel_per_turn_mm : float
        Axial travel of the nut (and carriers) per screw turn, signed along +z (mm).
    roller_drift_per_turn_mm : float
        Axial travel of each roller relative to the nut per screw turn (mm); 0 for every
        design :func:`check_kinematic_sizing` accepts (kept as computed, not forced).
    """

    carrier: float
    roller_relative: float
    roller_absolute: float
    nut_travel_per_turn_mm: float
    roller_drift_per_turn_mm: float


def speed_ratios(design: PRSDesign) -> SpeedRatios:
    """Speed ratios and axial travels of ``design`` (ValueError: :func:`check_kinematic_sizing`)."""
    check_kinematic_sizing(design)
    rs, rr, rn = _pitch_radii(design)
    h = design.thread.hand_sign
    p = design.thread.pitch_mm
    ns, nn = design.screw.starts, design.nut.starts
    # Willis with the nut (ring) held: (w_r - w_c)/(w_s - w_c) = -r_s/r_r and
    # (0 - w_c)/(w_r - w_c) = r_r/r_n give w_c/w_s = r_s/(r_s + r_n)
    carrier = rs / (rs + rn)
    rel = -carrier * rn / rr
    # thread engagement at both contacts (docs/theory/kinematics.md): the roller's spin
    # cancels out of the nut travel; signed leads h n p
    travel = -h * p * (ns - (ns - nn) * carrier)
    drift = h * p * (nn * carrier + rel)
    return SpeedRatios(carrier, rel, carrier + rel, travel, drift)


# --------------------------------------------------------------------------- velocities
def _cross_z(w: float | NDArray, v: NDArray) -> NDArray:
    """(w e_z) x v for v of shape (..., 3)."""
    out = np.zeros(np.broadcast_shapes(np.shape(v), (3,)))
    out[..., 0] = -w * v[..., 1]
    out[..., 1] = w * v[..., 0]
    return out


@dataclass(frozen=True)
class ContactSliding:
    """Velocities at one contact point at screw speed w_s = 1 rad/s (world frame, mm/s).

    Attributes
    ----------
    side : {"screw", "nut"}
        The roller's mating part.
    flank : {"upper", "lower"}
        Which roller flank (docs/theory/conventions.md, "Upper and lower flanks").
    point_mm, normal : tuple of float
        Contact point (mm) and unit common normal (toward +z) of roller 0 at screw angle 0,
        from the contact analysis (screw-roller: at the theoretical screw diameter).
    roller_velocity_mm_s, mate_velocity_mm_s : tuple of float
        Velocities of the roller's and the mating part's material points at the contact.
    sliding_velocity_mm_s : tuple of float
        v_roller - v_mate (mm/s).
    sliding_speed_mm_s : float
        Its magnitude (mm/s).
    normal_sliding_mm_s : float
        Its component along the normal (mm/s): zero (to rounding) for a contact that
        persists, the meshing condition of conjugate surfaces.
    contact_point_velocity_mm_s : tuple of float
        Velocity of the contact point itself: it is fixed in the carrier in x, y and
        follows the roller helix along z.
    rolling_velocity_mm_s : tuple of float
        Entrainment velocity: mean of the two surface velocities relative to the contact
        point, projected on the tangent plane (mm/s).
    rolling_direction : tuple of float
        Its unit vector (the rolling direction of the contact).
    sliding_along_rolling_mm_s, sliding_across_rolling_mm_s : float
        Sliding components along the rolling direction and along normal x rolling
        direction (mm/s); with the normal component they resolve v_slide completely.
    slide_to_roll_ratio : float
        |tangential sliding| / |rolling velocity| (-).
    spin_rad_s : float
        Relative angular velocity of roller and mate about the contact normal (rad/s),
        the spin of the contact.
    """

    side: str
    flank: str
    point_mm: tuple[float, float, float]
    normal: tuple[float, float, float]
    roller_velocity_mm_s: tuple[float, float, float]
    mate_velocity_mm_s: tuple[float, float, float]
    sliding_velocity_mm_s: tuple[float, float, float]
    sliding_speed_mm_s: float
    normal_sliding_mm_s: float
    contact_point_velocity_mm_s: tuple[float, float, float]
    rolling_velocity_mm_s: tuple[float, float, float]
    rolling_direction: tuple[float, float, float]
    sliding_along_rolling_mm_s: float
    sliding_across_rolling_mm_s: float
    slide_to_roll_ratio: float
    spin_rad_s: float

    def as_dict(self) -> dict[str, Any]:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.__dict__.items()}


def _vec(v: NDArray) -> tuple[float, float, float]:
    return tuple(float(x) for x in v)  # type: ignore[return-value]


@dataclass(frozen=True)
class Kinematics:
    """Ideal kinematics of a design, per unit screw speed w_s = 1 rad/s.

    Built by :func:`kinematics`. Screw driven, nut held from turning, rolling at the pitch
    circles (the end gears enforce it at the nut). Signs: module docstring.

    Attributes
    ----------
    design : PRSDesign
    hand_sign : int
        +1 right hand, -1 left hand.
    carrier_speed_ratio : float
        w_c / w_s = r_s / (r_s + r_n) (-).
    roller_spin_ratio_relative : float
        w_r,rel / w_s = -(w_c / w_s) r_n / r_r, spin about the roller axis relative to the
        carrier (-).
    roller_spin_ratio_absolute : float
        w_r,abs / w_s = w_c / w_s + w_r,rel / w_s (-).
    nut_travel_per_screw_turn_mm : float
        Signed nut (and carrier) travel along +z per screw turn (mm): -h n_s p for
        n_s = n_n, else -h p [n_s - (n_s - n_n) w_c / w_s].
    roller_drift_per_screw_turn_mm : float
        Roller axial travel relative to the nut per screw turn (mm), 0 for accepted designs.
    screw_roller, roller_nut : Mapping[str, ContactSliding]
        Contact velocities keyed by roller flank "upper" / "lower"; screw-roller at the
        theoretical screw pitch diameter (the screw that is made).
    """

    design: PRSDesign
    hand_sign: int
    carrier_speed_ratio: float
    roller_spin_ratio_relative: float
    roller_spin_ratio_absolute: float
    nut_travel_per_screw_turn_mm: float
    roller_drift_per_screw_turn_mm: float
    screw_roller: Mapping[str, ContactSliding]
    roller_nut: Mapping[str, ContactSliding]

    #: the screw speed every velocity of this object refers to (rad/s)
    screw_speed_rad_s: float = 1.0

    # -- derived speeds ------------------------------------------------------
    @property
    def nut_speed_mm_s(self) -> float:
        """Axial nut velocity at w_s = 1 rad/s (mm/s, signed along +z)."""
        return self.nut_travel_per_screw_turn_mm / TWO_PI

    @property
    def roller_axial_speed_mm_s(self) -> float:
        """Axial roller velocity in the world frame at w_s = 1 rad/s (mm/s)."""
        return (self.nut_travel_per_screw_turn_mm + self.roller_drift_per_screw_turn_mm) / TWO_PI

    def angular_speed(self, body: str) -> float:
        """Angular speed about +z (rad/s at w_s = 1 rad/s) of ``body`` in :data:`BODIES`;
        the roller's is its absolute spin about its own axis."""
        return {"screw": 1.0, "carrier": self.carrier_speed_ratio,
                "roller": self.roller_spin_ratio_absolute, "nut": 0.0}[_body(body)]

    def material_velocity(self, body: str, point_mm: ArrayLike, roller: int = 0) -> NDArray[np.float64]:
        """Velocity (mm/s at w_s = 1 rad/s) of the material point of ``body`` that sits at
        ``point_mm`` (world frame, shape (..., 3)) in the assembly at screw angle 0.

        ``roller`` picks roller k (axis at a (cos psi_k, sin psi_k)); ignored for the other
        bodies. Rigid motions about parallel axes: v = w e_z x (P - axis) + v_axial.
        """
        P = np.asarray(point_mm, dtype=np.float64)
        body = _body(body)
        if body == "screw":
            return _cross_z(1.0, P)
        if body == "nut":
            v = np.zeros(np.broadcast_shapes(P.shape, (3,)))
            v[..., 2] = self.nut_speed_mm_s
            return v
        if body == "carrier":
            v = _cross_z(self.carrier_speed_ratio, P)
            v[..., 2] += self.nut_speed_mm_s
            return v
        C = self.roller_axis_mm(roller)
        v = _cross_z(self.carrier_speed_ratio, C) + _cross_z(self.roller_spin_ratio_absolute, P - C)
        v[..., 2] += self.roller_axial_speed_mm_s
        return v

    def roller_axis_mm(self, roller: int = 0) -> NDArray[np.float64]:
        """Point (x, y, 0) of roller ``roller``'s axis at screw angle 0 (mm)."""
        psi = float(carrier_angles(self.design)[roller])
        a = self.design.centre_distance_mm
        return np.array([a * math.cos(psi), a * math.sin(psi), 0.0])

    def sliding_velocity(self, side: str, point_mm: ArrayLike, roller: int = 0) -> NDArray[np.float64]:
        """v_roller - v_mate (mm/s at w_s = 1 rad/s) at ``point_mm`` (world, (..., 3)),
        mate = ``side`` ("screw" or "nut")."""
        if side not in SIDES:
            raise ValueError(f"side must be one of {SIDES}, got {side!r}")
        return self.material_velocity("roller", point_mm, roller) - self.material_velocity(side, point_mm)

    def contact_point_velocity(self, point_mm: ArrayLike) -> NDArray[np.float64]:
        """Velocity of a contact point of roller 0 (mm/s at w_s = 1 rad/s).

        In the carrier the contact keeps its (x, y) and rides the roller's helix: the
        roller flank at a carrier-fixed (x, y) moves along z at
        drift - h p w_r,rel / 2 pi relative to the carrier, which itself travels with the nut.
        """
        P = np.asarray(point_mm, dtype=np.float64)
        v = _cross_z(self.carrier_speed_ratio, P)
        lead_r = self.hand_sign * self.design.thread.pitch_mm  # signed single-start lead
        v[..., 2] += self.roller_axial_speed_mm_s - lead_r * self.roller_spin_ratio_relative / TWO_PI
        return v

    def as_dict(self) -> dict[str, Any]:
        """Plain numbers (for a report section)."""
        return {
            "screw_speed_rad_s": self.screw_speed_rad_s,
            "carrier_speed_ratio": self.carrier_speed_ratio,
            "roller_spin_ratio_relative": self.roller_spin_ratio_relative,
            "roller_spin_ratio_absolute": self.roller_spin_ratio_absolute,
            "nut_travel_per_screw_turn_mm": self.nut_travel_per_screw_turn_mm,
            "roller_drift_per_screw_turn_mm": self.roller_drift_per_screw_turn_mm,
            "screw_roller": {k: v.as_dict() for k, v in self.screw_roller.items()},
            "roller_nut": {k: v.as_dict() for k, v in self.roller_nut.items()},
        }


def _body(body: str) -> str:
    if body not in BODIES:
        raise ValueError(f"body must be one of {BODIES}, got {body!r}")
    return body


def contact_sliding(kin: Kinematics, side: str, flank: str, point_mm: ArrayLike,
                    normal: ArrayLike) -> ContactSliding:
    """Sliding, rolling and spin at a contact of roller 0 (see :class:`ContactSliding`).

    ``point_mm`` and the unit ``normal`` are in the world frame at screw angle 0.
    """
    P = np.asarray(point_mm, dtype=np.float64)
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    v_roller = kin.material_velocity("roller", P)
    v_mate = kin.material_velocity(side, P)
    slide = v_roller - v_mate
    v_cp = kin.contact_point_velocity(P)
    rolling = 0.5 * ((v_roller - v_cp) + (v_mate - v_cp))
    rolling_t = rolling - (rolling @ n) * n
    speed_roll = float(np.linalg.norm(rolling_t))
    e_roll = rolling_t / speed_roll if speed_roll > 0.0 else np.zeros(3)
    e_across = np.cross(n, e_roll)
    slide_t = slide - (slide @ n) * n
    spin = (kin.angular_speed("roller") - kin.angular_speed(side)) * float(n[2])
    return ContactSliding(
        side=side, flank=flank, point_mm=_vec(P), normal=_vec(n),
        roller_velocity_mm_s=_vec(v_roller), mate_velocity_mm_s=_vec(v_mate),
        sliding_velocity_mm_s=_vec(slide), sliding_speed_mm_s=float(np.linalg.norm(slide)),
        normal_sliding_mm_s=float(slide @ n), contact_point_velocity_mm_s=_vec(v_cp),
        rolling_velocity_mm_s=_vec(rolling_t), rolling_direction=_vec(e_roll),
        sliding_along_rolling_mm_s=float(slide @ e_roll),
        sliding_across_rolling_mm_s=float(slide @ e_across),
        slide_to_roll_ratio=float(np.linalg.norm(slide_t)) / speed_roll if speed_roll > 0.0 else math.inf,
        spin_rad_s=spin,
    )


def kinematics(design: PRSDesign, contact: ContactResult | None = None) -> Kinematics:
    """The ideal kinematics of ``design`` per unit screw speed.

    Parameters
    ----------
    design : PRSDesign
        Must satisfy :func:`check_kinematic_sizing` (else ValueError).
    contact : ContactResult, optional
        The design's contact stage (:func:`prs_geom.analysis.contact.analyse_contact`);
        computed when not given. Its screw-roller contacts at the theoretical screw and
        its roller-nut contacts (roller 0, middle tooth) are where the sliding is evaluated.

    Returns
    -------
    Kinematics
    """
    ratios = speed_ratios(design)
    if contact is None:
        contact = analyse_contact(design)
    elif contact.design != design:
        raise ValueError("contact was computed for another design than the one given")
    base = Kinematics(design, design.thread.hand_sign, ratios.carrier, ratios.roller_relative,
                      ratios.roller_absolute, ratios.nut_travel_per_turn_mm,
                      ratios.roller_drift_per_turn_mm, {}, {})

    def one(side: str, flank: str, cp: ContactPoint) -> ContactSliding:
        return contact_sliding(base, side, flank, cp.point_mm, cp.normal)

    sr = {fl: one("screw", fl, contact.screw_roller[f"{fl}_at_theoretical"]) for fl in ("upper", "lower")}
    rn = {fl: one("nut", fl, contact.roller_nut[fl]) for fl in ("upper", "lower")}
    return Kinematics(design, base.hand_sign, base.carrier_speed_ratio, base.roller_spin_ratio_relative,
                      base.roller_spin_ratio_absolute, base.nut_travel_per_screw_turn_mm,
                      base.roller_drift_per_screw_turn_mm, sr, rn)


# --------------------------------------------------------------------------- poses
def _translations_z(z: NDArray) -> NDArray[np.float64]:
    """(N, 4, 4) translations along z by ``z`` (mm)."""
    T = np.zeros(z.shape + (4, 4))
    T[..., 0, 0] = T[..., 1, 1] = T[..., 2, 2] = T[..., 3, 3] = 1.0
    T[..., 2, 3] = z
    return T


def _frozen(a: NDArray) -> NDArray:
    a.flags.writeable = False
    return a


@dataclass(frozen=True)
class Poses:
    """Part poses over screw angles: 4x4 float64 transforms part frame -> world frame.

    World = the screw's fixed frame (the frame of the static assembly at screw angle 0).
    N = number of screw angles, z = number of rollers. Arrays are read-only.

    Attributes
    ----------
    screw_angle_rad : ndarray (N,)
        Screw rotation about +z (rad).
    screw : ndarray (N, 4, 4)
        R_z(angle).
    carrier : ndarray (N, 4, 4)
        T_z(nut travel) R_z(w_c / w_s angle): the carrier turns and travels with the nut.
    nut : ndarray (N, 4, 4)
        T_z(nut travel): the nut is held from turning.
    roller : ndarray (z, N, 4, 4)
        Roller k in the world: carrier @ roller_in_carrier.
    roller_in_carrier : ndarray (z, N, 4, 4)
        Roller k relative to the carrier node: T_z(drift) roller_transform(k)
        R_z(w_r,rel / w_s angle), spin about the roller's own axis.
    """

    screw_angle_rad: NDArray[np.float64]
    screw: NDArray[np.float64]
    carrier: NDArray[np.float64]
    nut: NDArray[np.float64]
    roller: NDArray[np.float64]
    roller_in_carrier: NDArray[np.float64]


def poses(design: PRSDesign, screw_angles_rad: ArrayLike) -> Poses:
    """Poses of screw, carrier, rollers and nut at the given screw angles (vectorised).

    Parameters
    ----------
    design : PRSDesign
        Must satisfy :func:`check_kinematic_sizing` (else ValueError).
    screw_angles_rad : array_like, shape (N,) or scalar
        Screw rotations about +z from the assembly position (rad), positive right-handed.

    Returns
    -------
    Poses
        At angle 0 every transform is the static placement exactly (identity; rollers
        ``roller_transform(design, k)``).
    """
    phi = np.atleast_1d(np.asarray(screw_angles_rad, dtype=np.float64))
    if phi.ndim != 1:
        raise ValueError(f"screw_angles_rad must be a scalar or a 1-D array, got shape {phi.shape}")
    if not np.all(np.isfinite(phi)):
        raise ValueError("screw_angles_rad must be finite")
    r = speed_ratios(design)
    turns = phi / TWO_PI
    nut = _translations_z(r.nut_travel_per_turn_mm * turns)
    carrier = nut @ rotation_z(r.carrier * phi)
    static = np.stack([roller_transform(design, k) for k in range(design.roller.count)])  # (z, 4, 4)
    # spin about the roller's own axis: right-multiply in its part frame
    in_carrier = (_translations_z(r.roller_drift_per_turn_mm * turns)[None]
                  @ static[:, None] @ rotation_z(r.roller_relative * phi)[None])
    world = carrier[None] @ in_carrier
    return Poses(_frozen(phi.copy()), _frozen(rotation_z(phi)), _frozen(carrier), _frozen(nut),
                 _frozen(world), _frozen(in_carrier))
