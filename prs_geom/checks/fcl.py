"""FCL verification of the per-tooth unloaded gaps (docs/theory/contact.md, "FCL verification").

What is checked
---------------
Every roller tooth j = 1..n of every roller k = 0..z-1, on both sides, at the flank that
carries the load (the load path of :mod:`prs_geom.analysis.loads`): the roller's *upper*
flank against the screw tooth above it (side "screw"), the roller's *lower* flank against the
nut tooth below it (side "nut"). Constant-pitch and graded designs alike.

What "gap" means (both numbers compared are this quantity)
---------------------------------------------------------
The **designed gap** g_des(k, j) is the unloaded gap of ``ContactResult.tooth_gaps``
(:func:`prs_geom.analysis.contact.tooth_gaps`, ``gap_mm``): the signed minimum Euclidean
distance between the two analytic flank surfaces of that tooth at the nominal placement of
the assembly, measured along their common normal (mm; positive = clearance, negative =
interference depth). It is computed here with the same solver when the caller does not pass
it (``designed_gaps``).

FCL cannot measure an interference (its distance is zero for touching or overlapping meshes),
so for each side every roller is *settled*: translated rigidly along the part axis by s_k
(opening that side's flanks, the same shift for all its teeth) until its smallest axial gap
is ``VERIFY_CLEARANCE_MM``. FCL then measures d_fcl(k, j), the distance between the meshed
flank patches at the settled placement. The translation is known exactly, so the gap at the
nominal placement follows by removing the change of distance the translation causes:

    g_fcl(k, j) = d_fcl(k, j) - [D(k, j; s_k) - D(k, j; 0)]

with D(s) the analytic common-normal distance as a function of the rigid axial translation.
By the envelope theorem dD/ds = n_z, the axial component of the unit common normal (about
cos(beta) cos(lambda) ~ 0.70), so the bracket is n_z s_k up to a second-order term; the exact
analytic difference is used and its deviation from n_z s_k is reported
(``settling_nonlinearity_mm``, about 1e-9 mm). When the designed gaps are those of the
design itself, g_fcl - g_des = d_fcl - D(s_k): the FCL distance between the meshes against the
analytic distance between the surfaces at the same placement, which is what the tolerance
bounds. Both gaps are in the normal direction; the load model's gaps are axial and relative to
tooth 1 (``pitch_gaps`` of the pitch lists); each comparison also carries that value and the
report the largest deviation of the FCL gaps from it (the phase effect of a graded warp,
docs/theory/geometry.md; informational, no warning).

How FCL measures
----------------
For each side one fine mesh patch of each flank is built once, in its part frame, around the
analytic nearest point of a reference contact (the one whose warp slope is nearest the middle
of all slopes, so the transform error below is smallest), radially covering the nearest
points of all contacts plus a margin, angularly +- ``half / r_ref``. Each patch is meshed for
half the chord tolerance ``tol``, with separate radial and angular grid steps from a bound of
the surface's second fundamental form (:func:`patch_steps`); the achieved error is measured at
the triangle centroids and edge midpoints.
FCL's BVH of each patch is then placed by rigid transforms at every contact: a rotation about
the part axis taking the reference nearest point's angle to the contact's, plus the axial
shift of the tooth mid-plane helix W(m + L theta / 2 pi) between the two points; the roller
patch is then placed by the assembly's roller transform
(:func:`prs_geom.geometry.frames.roller_transform`) and the settling shift. One FCL distance
request per placed pair.

Transform error: along the radial line through the contact's nearest point the moved patch
coincides with the surface exactly (W does not depend on r). Away from it, on a graded part,
the moved patch has the warp slope of the reference tooth instead of this tooth's:
e(u) = W(m_ref + k (theta_ref + u)) + shift - W(m + k (theta + u)) ~ k [c'(ref) - c'(here)] u
over the patch's angular span |u| <= half / r_ref (k = L / 2 pi). It is evaluated on the span
for every contact and both patches; the largest sum e_A + e_B is ``transform_error_bound_mm``
(0 for constant pitch). Each patch lies within its chord error plus its transform error of the
true surface, so |g_fcl - g_des| <= tol + transform_error_bound_mm =
``difference_tolerance_mm``, the verdict's tolerance. Every comparison beyond it is listed in
``warnings``. Because every contact sits at the same place of the same patch grid, the mesh
error is nearly the same on every tooth: tooth-to-tooth differences are far more accurate
than the tolerance.

Notes attached to a warning: an analytic nearest point outside the real flank (between root
and crest radius; the analytic surfaces continue beyond the truncation, so such a "contact"
is an edge contact the analytic model does not describe), or an FCL nearest point still on an
artificial patch edge after ``MAX_PATCH_GROWTH`` doublings of the patch.
"""
from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import fcl
import numpy as np
from numpy.typing import NDArray

from prs_geom.analysis.contact import (ContactBatch, PartFlanks, euclidean_distance, solve_collinear,
                                       theoretical_screw, tooth_contacts)
from prs_geom.analysis.loads import gap_terms
from prs_geom.geometry.frames import roller_transform, rotation_z
from prs_geom.geometry.profiles import ThreadProfile
from prs_geom.model.design import PRSDesign

__all__ = [
    "BAND_SLACK_MM", "BOUND_SAMPLES", "Comparison", "DEFAULT_TOL_MM", "EDGE_STEPS", "LOADED_FLANKS",
    "MAX_PATCH_GROWTH", "MAX_RADIAL_STEP_MM", "PATCH_HALF_SIZE_MM", "SIDE_NAMES", "SideResult",
    "TRANSFORM_SAMPLES", "VERIFY_CLEARANCE_MM", "bvh_model", "check_comparisons", "comparison_warning",
    "flank_patch", "load_model_deviation", "patch_radii", "patch_steps", "transform_error", "verify_contacts",
    "verify_side",
]

#: Default chordal tolerance (mm) of the two patches together: 0.01 um, far below the
#: 0.01-0.5 um tooth-to-tooth steps of the graded gaps.
DEFAULT_TOL_MM = 1e-5
#: The flank of the roller tooth that carries the load, per side (load path of the loads model).
LOADED_FLANKS: Mapping[str, str] = {"screw": "upper", "nut": "lower"}
#: Axial clearance (mm) each roller is settled to at its closest tooth, per side.
VERIFY_CLEARANCE_MM = 0.005
#: Patch margin (mm): radial margin around the nearest points and angular half-span (arc
#: length at the reference radius) around each placed contact.
PATCH_HALF_SIZE_MM = 0.1
#: Patch margin growths (x2 each) allowed when FCL's nearest point sits on a patch edge.
MAX_PATCH_GROWTH = 3
#: A nearest point closer than this many grid steps to an artificial patch edge counts as on it.
EDGE_STEPS = 1.0
#: Analytic points this far (mm) outside the flank's radial band count as off the flank.
BAND_SLACK_MM = 1e-9
#: Angles at which the transform error is evaluated across a patch's angular span.
TRANSFORM_SAMPLES = 65
#: Radii at which the profile terms of the patch's sagitta bound are sampled.
BOUND_SAMPLES = 2049
#: Largest radial grid step (mm): straight flanks have straight radial lines, and only the
#: twist bounds their radial step; the cap keeps every cell's second-order estimate local.
MAX_RADIAL_STEP_MM = 0.02

SIDE_NAMES = {"screw": "screw-roller", "nut": "roller-nut"}


# --------------------------------------------------------------------------- patches
def _grid_mesh(u: NDArray, v: NDArray, fn: Callable[[NDArray, NDArray], NDArray]) -> tuple[NDArray, NDArray]:
    """Triangulated parameter grid u x v mapped by fn(U, V) -> (n, 3)."""
    U, V = np.meshgrid(u, v, indexing="ij")
    P = fn(U.ravel(), V.ravel())
    nu, nv = len(u), len(v)
    idx = np.arange(nu * nv).reshape(nu, nv)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    F = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return P, F


def patch_radii(part: PartFlanks, r_values: NDArray | float, half: float) -> tuple[float, float]:
    """Radial range of a patch: the radii ``r_values`` +- ``half`` (mm), clipped to the
    flank band [inner, outer] radius of the part; when that leaves nothing (every point off
    the flank) the band strip of width 2 ``half`` nearest the points."""
    prof = part.profile
    lo_b, hi_b = prof.inner_radius, prof.outer_radius
    r = np.atleast_1d(np.asarray(r_values, dtype=np.float64))
    lo = min(max(float(r.min()) - half, lo_b), hi_b)
    hi = max(min(float(r.max()) + half, hi_b), lo_b)
    if hi - lo < 1e-6 * max(1.0, hi_b):
        if float(r.min()) >= hi_b:
            lo, hi = max(lo_b, hi_b - 2 * half), hi_b
        else:
            lo, hi = lo_b, min(hi_b, lo_b + 2 * half)
    return lo, hi


def _warp_bounds(part: PartFlanks) -> tuple[float, float]:
    """Bounds of |1 + c'| and |c''| of the part's warp (1 and 0 for constant pitch).

    c is a piecewise cubic (PCHIP) between the knots and linear outside, so c'' is linear on
    each interval: its extremes are the one-sided values at the knots, evaluated just inside
    every interval. c' is sampled 32 times per interval (a quadratic per interval).
    """
    w = part.warp
    if w.is_identity:
        return 1.0, 0.0
    kn = w.knots
    eps = 1e-9 * w.pitch
    fine = np.linspace(kn[0], kn[-1], 32 * (len(kn) - 1) + 1)
    slope = 1.0 + float(np.max(np.abs(w.correction_slope(fine))))
    ends = np.concatenate([kn[:-1] + eps, kn[1:] - eps])
    return slope, float(np.max(np.abs(w.correction_curvature(ends))))


def patch_steps(part: PartFlanks, tol: float, r_lo: float, r_hi: float) -> tuple[float, float]:
    """Grid steps (h_r in mm, h_theta in rad) of a patch over radii [r_lo, r_hi] whose
    triangles lie within ``tol`` (mm) of the flank surface.

    The surface P(r, theta) = (r cos theta, r sin theta, Z) is linearly interpolated on each
    grid triangle; for a quadratic P the error at barycentric point lambda is
    1/2 sum_{i<j} lambda_i lambda_j D2P[d_ij, d_ij] (d_ij the parameter edges), whose normal part
    is at most max_ij |II(d_ij, d_ij)| / 6 (sum lambda_i lambda_j <= 1/3), with the second
    fundamental form of the explicit surface (w = sqrt(1 + |grad Z|^2) >= sqrt(1 + Z_r^2))

        II(dr, dth) = [Z_rr dr^2 - 2 (Z_theta / r) dr dth + (r Z_r + Z_thth) dth^2] / w
                   <= A dr^2 + 2 B dr dth + C dth^2,

    A = max |t''| / w, B = max k |1 + c'| / (r w), C = max (r |t'| + k^2 |c''|) / w over the
    radii (sampled on ``BOUND_SAMPLES`` radii; the profile terms are smooth in r) and the warp
    (k = L / 2 pi). The three edges of a cell are dr, dth and the diagonal (dr, dth), whose bound
    dominates. The largest cell area dr dth with A dr^2 + 2 B dr dth + C dth^2 = 6 tol has
    dr / dth = sqrt(C / A); a straight flank (A = 0: its radial lines are straight) is limited by
    the twist term alone, so dr is capped at ``MAX_RADIAL_STEP_MM`` to keep the cells local.
    The achieved error is measured afterwards (:func:`flank_patch`).
    """
    prof = part.profile
    k = prof.lead / (2 * math.pi)
    slope, curv = _warp_bounds(part)
    r = np.linspace(r_lo, r_hi, BOUND_SAMPLES)
    t1 = np.abs(prof.tooth_half_width_slope(r))
    t2 = np.abs(prof.tooth_half_width_curvature(r))
    w = np.sqrt(1.0 + t1 * t1)
    A = float(np.max(t2 / w))
    B = float(np.max(k * slope / (r * w)))
    C = float(np.max((r * t1 + k * k * curv) / w))
    budget = 6.0 * tol
    dr = MAX_RADIAL_STEP_MM
    if A > 0.0:
        rho = math.sqrt(C / A)                                   # optimal dr / dth
        dr = min(dr, rho * math.sqrt(budget / (2.0 * C + 2.0 * B * rho)))
    dr = min(dr, math.sqrt(budget / A) if A > 0.0 else dr)
    # the largest dth with A dr^2 + 2 B dr dth + C dth^2 <= budget
    dth = (-B * dr + math.sqrt((B * dr) ** 2 + C * (budget - A * dr * dr))) / C
    return dr, dth


def flank_patch(part: PartFlanks, r_c: float, th_c: float, m: float, xi: float, tol: float,
                half: float = PATCH_HALF_SIZE_MM,
                r_range: tuple[float, float] | None = None) -> tuple[NDArray, NDArray, float]:
    """Patch of Z(r, theta) around (r_c, th_c) in the part frame with chordal error <= tol.

    Radii ``r_range`` (default r_c +- half clipped to the flank, :func:`patch_radii`),
    angles th_c +- half / r_c, grid steps of :func:`patch_steps`. The achieved error is measured
    at the triangle centroids and the midpoints of their edges (normal distance: the axial
    distance to the surface over w = sqrt(1 + |grad Z|^2)) and returned.
    Returns vertices (mm, part frame), faces and the measured error (mm).
    """
    r_lo, r_hi = r_range if r_range is not None else patch_radii(part, r_c, half)
    h_r, h_t = patch_steps(part, tol, r_lo, r_hi)
    nr = max(2, int(math.ceil((r_hi - r_lo) / h_r)) + 1)
    nt = max(2, int(math.ceil(2 * half / r_c / h_t)) + 1)
    rr = np.linspace(r_lo, r_hi, nr)
    tt = th_c + np.linspace(-half, half, nt) / r_c

    def surf(r: NDArray, th: NDArray) -> NDArray:
        Z = part.z_derivatives(r, th, np.full_like(r, m), np.full_like(r, xi))[0]
        return np.column_stack([r * np.cos(th), r * np.sin(th), Z])

    V, F = _grid_mesh(rr, tt, surf)
    T = V[F]
    probes = np.concatenate([T.mean(axis=1), 0.5 * (T[:, 0] + T[:, 1]), 0.5 * (T[:, 1] + T[:, 2]),
                             0.5 * (T[:, 0] + T[:, 2])])
    rc = np.hypot(probes[:, 0], probes[:, 1])
    tc = th_c + np.arctan2(-probes[:, 0] * math.sin(th_c) + probes[:, 1] * math.cos(th_c),
                           probes[:, 0] * math.cos(th_c) + probes[:, 1] * math.sin(th_c))
    Zs, Zr, Zt = part.z_derivatives(rc, tc, np.full_like(rc, m), np.full_like(rc, xi))[:3]
    err = float(np.max(np.abs(probes[:, 2] - Zs) / np.sqrt(1 + Zr ** 2 + (Zt / rc) ** 2)))
    return V, F, err


def bvh_model(V: NDArray, F: NDArray) -> fcl.BVHModel:
    """An FCL BVH of a triangle mesh (float64 vertices)."""
    g = fcl.BVHModel()
    g.beginModel(len(V), len(F))
    g.addSubModel(np.ascontiguousarray(V, dtype=np.float64), np.ascontiguousarray(F, dtype=np.int32))
    g.endModel()
    return g


@dataclass(frozen=True)
class _Patch:
    """A flank patch's BVH in its part frame and the data to tell its artificial edges."""

    obj: fcl.CollisionObject
    r_lo: float
    r_hi: float
    r_edge_real: tuple[bool, bool]   # r_lo / r_hi is the real root or crest radius
    th_c: float                      # reference angle (rad), the patch's angular centre
    half_angle: float                # angular half-span (rad)
    step_r: float                    # radial grid step (mm)
    step_t: float                    # angular grid step (rad)
    error: float                     # measured chordal error (mm)
    triangles: int

    def on_artificial_edge(self, p_local: NDArray) -> NDArray:
        """Whether points (N, 3) in the patch frame lie on an edge the flank does not have."""
        r = np.hypot(p_local[:, 0], p_local[:, 1])
        dth = np.arctan2(-p_local[:, 0] * math.sin(self.th_c) + p_local[:, 1] * math.cos(self.th_c),
                         p_local[:, 0] * math.cos(self.th_c) + p_local[:, 1] * math.sin(self.th_c))
        e = EDGE_STEPS * self.step_r
        out = np.abs(dth) >= self.half_angle - EDGE_STEPS * self.step_t   # always artificial
        if not self.r_edge_real[0]:
            out |= r <= self.r_lo + e
        if not self.r_edge_real[1]:
            out |= r >= self.r_hi - e
        return out


def _build_patch(part: PartFlanks, r_pts: NDArray, r_c: float, th_c: float, m: float, xi: float,
                 tol: float, half: float) -> _Patch:
    lo, hi = patch_radii(part, r_pts, half)
    V, F, err = flank_patch(part, r_c, th_c, m, xi, tol, half, (lo, hi))
    prof = part.profile
    real = (abs(lo - prof.inner_radius) <= 1e-12 * hi, abs(hi - prof.outer_radius) <= 1e-12 * hi)
    h_r, h_t = patch_steps(part, tol, lo, hi)
    return _Patch(obj=fcl.CollisionObject(bvh_model(V, F), fcl.Transform()), r_lo=lo, r_hi=hi, r_edge_real=real,
                  th_c=th_c, half_angle=half / r_c, step_r=h_r, step_t=h_t, error=err, triangles=int(len(F)))


def _helix_z(part: PartFlanks, m: NDArray, th: NDArray) -> NDArray:
    """Axial position W(m + L theta / 2 pi) of the tooth mid-plane (no profile term), mm."""
    return part.warp(m + part.profile.lead * th / (2 * math.pi))


def _reference(part: PartFlanks, m: NDArray, th: NDArray) -> int:
    """The contact whose warp slope c' is nearest the middle of all slopes: the patch built
    there and moved to the others has the smallest slope mismatch (transform error)."""
    s = part.warp.correction_slope(m + part.profile.lead * th / (2 * math.pi))
    return int(np.argmin(np.abs(s - 0.5 * (s.max() + s.min()))))


def transform_error(part: PartFlanks, m: NDArray, th: NDArray, ref: int, half_angle: float) -> NDArray:
    """Largest axial distance (mm) between the patch built at contact ``ref`` and moved to each
    contact, and the true surface there, over the patch's angular span +- ``half_angle``.

    The moved patch is W(m_ref + k (th_ref + u)) + [W(m + k th) - W(m_ref + k th_ref)] + xi t(r)
    against the surface W(m + k (th + u)) + xi t(r) (k = L / 2 pi): equal at u = 0 and at
    every radius, apart by ~ k (c'_ref - c') u elsewhere; zero for constant pitch.
    """
    if part.warp.is_identity:
        return np.zeros(len(m))
    k = part.profile.lead / (2 * math.pi)
    u = np.linspace(-half_angle, half_angle, TRANSFORM_SAMPLES)
    a = (m + k * th)[:, None]
    a_ref = m[ref] + k * th[ref]
    w = part.warp
    moved = w(a_ref + k * u)[None, :] + (w(a) - w(a_ref))
    return np.max(np.abs(moved - w(a + k * u[None, :])), axis=1)


# --------------------------------------------------------------------------- results
@dataclass(frozen=True)
class Comparison:
    """One tooth of one roller on one side: FCL against the analytic surfaces and the designed gap.

    Distances in mm at the settled placement; gaps in mm at the nominal placement, along the
    common normal (see the module docstring); ``load_model_gap_mm`` axial, relative to tooth 1.
    """

    side: str
    flank: str
    roller: int
    tooth: int
    analytic_distance_mm: float
    fcl_distance_mm: float
    point_difference_mm: float
    designed_gap_mm: float
    fcl_gap_mm: float
    normal_axial_component: float
    load_model_gap_mm: float

    @property
    def difference_mm(self) -> float:
        """FCL distance - analytic distance at the settled placement (mm)."""
        return self.fcl_distance_mm - self.analytic_distance_mm

    @property
    def gap_difference_mm(self) -> float:
        """FCL gap - designed gap (mm)."""
        return self.fcl_gap_mm - self.designed_gap_mm

    def as_dict(self) -> dict[str, Any]:
        """The comparison's entry of ``checks.fcl.comparisons`` (gaps in um)."""
        return {"side": self.side, "flank": self.flank, "roller": self.roller, "tooth": self.tooth,
                "analytic_distance_mm": self.analytic_distance_mm, "fcl_distance_mm": self.fcl_distance_mm,
                "difference_mm": self.difference_mm, "point_difference_mm": self.point_difference_mm,
                "fcl_gap_um": self.fcl_gap_mm * 1e3, "designed_gap_um": self.designed_gap_mm * 1e3,
                "gap_difference_um": self.gap_difference_mm * 1e3,
                "normal_axial_component": self.normal_axial_component,
                "load_model_gap_um": self.load_model_gap_mm * 1e3}


@dataclass(frozen=True)
class SideResult:
    """The comparisons of one side (roller-major: roller 0 teeth 1..n, roller 1, ...), one
    note per comparison (empty, or why its difference may be large) and the patch data."""

    comparisons: list[Comparison]
    notes: list[str]
    patches: dict[str, Any]
    timings: dict[str, float]


def _designed_values(designed_gaps: Mapping[str, Any], side: str, flank: str, z: int, n: int) -> NDArray:
    """The (z * n,) designed gaps (mm) of ``side`` from a ``tooth_gaps``-shaped mapping."""
    g = np.asarray(designed_gaps[side][flank]["gap_mm"], dtype=np.float64)
    if g.shape != (z, n):
        raise ValueError(f"designed gaps of {side}/{flank} have shape {g.shape}, expected ({z}, {n})")
    return g.ravel()


def _off_band(part: PartFlanks, r: NDArray) -> NDArray:
    prof = part.profile
    return (r < prof.inner_radius - BAND_SLACK_MM) | (r > prof.outer_radius + BAND_SLACK_MM)


@dataclass(frozen=True)
class _Settled:
    """The analytic side of one side's check: the contacts at the nominal placement and with
    every roller settled (rigid axial ``shift`` per contact, mm, positive opens the flanks).

    ``d_nominal`` / ``distance``: signed common-normal distances (mm) at the nominal and
    the settled placement; ``q``: the settled nearest-point parameters (r, theta, rho, phi);
    ``point_a``, ``point_b``: those points (screw frame, mm); ``normal_z``: |n_z| of the
    nominal common normal; ``roller``, ``tooth``: each contact's roller and tooth.
    """

    batch: ContactBatch
    shift: NDArray[np.float64]
    d_nominal: NDArray[np.float64]
    distance: NDArray[np.float64]
    q: NDArray[np.float64]
    point_a: NDArray[np.float64]
    point_b: NDArray[np.float64]
    normal_z: NDArray[np.float64]
    roller: NDArray[np.int64]
    tooth: NDArray[np.int64]


def _settle(design: PRSDesign, side: str, flank: str, screw_profile: ThreadProfile | None) -> _Settled:
    """Solve every contact of ``side`` at the nominal placement, then settle each roller to
    ``VERIFY_CLEARANCE_MM`` at its closest tooth and solve again."""
    z, n = design.roller.count, design.thread.engaged_teeth
    batch, q0, info = tooth_contacts(design, side, flank, screw_profile=screw_profile)
    nominal = solve_collinear(batch, q0)
    d_nominal, q_nominal = euclidean_distance(batch, nominal.q)
    # the axial gap of the collinear solution changes by exactly the rigid shift
    shift = np.repeat(VERIFY_CLEARANCE_MM - nominal.gap.reshape(z, n).min(axis=1), n)
    settled = dataclasses.replace(batch, z_offset=-batch.xi_b * shift)
    dist, q = euclidean_distance(settled, solve_collinear(settled, nominal.q).q)
    pa, pb = settled.points(q)
    na, _ = batch.normals(q_nominal)
    return _Settled(batch=settled, shift=shift, d_nominal=d_nominal, distance=dist, q=q, point_a=pa,
                    point_b=pb, normal_z=np.abs(na[:, 2]), roller=info["roller"], tooth=info["tooth"])


def _off_flank_notes(side: str, settled: _Settled) -> list[list[str]]:
    """Per contact, the note that its analytic nearest point lies off the real flank (empty
    when it lies on it)."""
    ra, _, rb, _ = settled.q.T
    notes: list[list[str]] = [[] for _ in range(settled.batch.n)]
    for name, part, r in ((side, settled.batch.A, ra), ("roller", settled.batch.B, rb)):
        for i in np.flatnonzero(_off_band(part, r)):
            notes[i].append(f"{name} r = {r[i]:.4f} mm outside its flank {part.profile.inner_radius:.4f}-"
                            f"{part.profile.outer_radius:.4f} mm")
    return [["the analytic nearest point lies off the real flank (" + "; ".join(nt) + "): the analytic "
             "surfaces continue beyond root and crest, so this is an edge contact the analytic model "
             "does not describe"] if nt else [] for nt in notes]


@dataclass(frozen=True)
class _Placements:
    """Where each contact puts the two patches: part frame -> screw frame, rotations
    ``rot_*`` (N, 3, 3) and translations ``shift_*`` (N, 3, mm); ``ref_*``: the contact
    each patch is built at."""

    ref_a: int
    ref_b: int
    rot_a: NDArray[np.float64]
    shift_a: NDArray[np.float64]
    rot_b: NDArray[np.float64]
    shift_b: NDArray[np.float64]


def _placements(design: PRSDesign, settled: _Settled, perturb: NDArray[np.float64]) -> _Placements:
    """Rotate the reference nearest point's angle onto each contact's and shift by the helix
    between them; the roller patch then goes where the assembly puts roller k, plus the
    settling shift and the perturbation ``perturb`` (mm, per roller)."""
    b = settled.batch
    _, tha, _, phb = settled.q.T
    ref_a, ref_b = _reference(b.A, b.m_a, tha), _reference(b.B, b.m_b, phb)
    h_a = _helix_z(b.A, b.m_a, tha)
    h_b = _helix_z(b.B, b.m_b, phb)
    rot_a = np.ascontiguousarray(rotation_z(tha - tha[ref_a])[:, :3, :3])
    shift_a = np.zeros((b.n, 3))
    shift_a[:, 2] = h_a - h_a[ref_a]
    roller_frames = np.stack([roller_transform(design, k) for k in range(design.roller.count)])[settled.roller]
    rot_b = roller_frames[:, :3, :3] @ np.ascontiguousarray(rotation_z(phb - phb[ref_b])[:, :3, :3])
    shift_b = roller_frames[:, :3, 3].copy()
    shift_b[:, 2] += h_b - h_b[ref_b] + b.z_offset + perturb[settled.roller]
    return _Placements(ref_a=ref_a, ref_b=ref_b, rot_a=rot_a, shift_a=shift_a, rot_b=rot_b, shift_b=shift_b)


@dataclass(frozen=True)
class _Measured:
    """FCL's distances (mm) and nearest points (N, 2, 3; screw frame) at every contact, the
    patches of the last round and their margin ``half`` (mm), which contacts still had a
    nearest point on an artificial patch edge, and the time (s) spent building patches and in FCL."""

    distance: NDArray[np.float64]
    nearest: NDArray[np.float64]
    patch_a: _Patch
    patch_b: _Patch
    half: float
    on_edge: NDArray[np.bool_]
    patch_time: float
    fcl_time: float


def _fcl_distances(settled: _Settled, place: _Placements, tol: float) -> _Measured:
    """Build the two patches at the reference contacts and measure every placed pair with
    FCL; grow the patches (x2, at most ``MAX_PATCH_GROWTH`` times) while a nearest point
    lies on an artificial patch edge."""
    b = settled.batch
    ra, tha, rb, phb = settled.q.T
    ref_a, ref_b = place.ref_a, place.ref_b
    t_patch = t_fcl = 0.0
    half = PATCH_HALF_SIZE_MM
    req = fcl.DistanceRequest(enable_nearest_points=True)
    d_fcl = np.empty(b.n)
    near = np.empty((b.n, 2, 3))
    for growth in range(MAX_PATCH_GROWTH + 1):
        tp = time.perf_counter()
        pA = _build_patch(b.A, ra, ra[ref_a], tha[ref_a], b.m_a[ref_a], b.xi_a[ref_a], 0.5 * tol, half)
        pB = _build_patch(b.B, rb, rb[ref_b], phb[ref_b], b.m_b[ref_b], b.xi_b[ref_b], 0.5 * tol, half)
        tf = time.perf_counter()
        t_patch += tf - tp
        for i in range(b.n):
            pA.obj.setTransform(fcl.Transform(place.rot_a[i], place.shift_a[i]))
            pB.obj.setTransform(fcl.Transform(place.rot_b[i], place.shift_b[i]))
            res = fcl.DistanceResult()
            d_fcl[i] = fcl.distance(pA.obj, pB.obj, req, res)
            near[i] = res.nearest_points
        t_fcl += time.perf_counter() - tf
        # nearest points back into the patch frames (R^T (p - t)); touching or overlapping
        # patches have no meaningful nearest points
        loc_a = np.einsum("nji,nj->ni", place.rot_a, near[:, 0] - place.shift_a)
        loc_b = np.einsum("nji,nj->ni", place.rot_b, near[:, 1] - place.shift_b)
        on_edge = (d_fcl > 0) & (pA.on_artificial_edge(loc_a) | pB.on_artificial_edge(loc_b))
        if not on_edge.any() or growth == MAX_PATCH_GROWTH:
            break
        half *= 2.0
    return _Measured(distance=d_fcl, nearest=near, patch_a=pA, patch_b=pB, half=half, on_edge=on_edge,
                     patch_time=t_patch, fcl_time=t_fcl)


def verify_side(design: PRSDesign, side: str, tol: float, screw_profile: ThreadProfile | None = None,
                designed_gaps: Mapping[str, Any] | None = None,
                roller_offsets_mm: Sequence[float] | NDArray | None = None) -> SideResult:
    """FCL gaps against the designed gaps at every tooth of every roller on ``side``.

    Parameters
    ----------
    design : PRSDesign
        The design whose flanks are meshed and placed.
    side : str
        "screw" (screw-roller) or "nut" (roller-nut); the loaded flank (:data:`LOADED_FLANKS`).
    tol : float
        Chordal tolerance (mm) of the two patches together (each is built for tol / 2).
    screw_profile : ThreadProfile, optional
        The theoretical screw of the contact stage (the design's profile when None).
    designed_gaps : mapping, optional
        Designed gaps in the layout of ``ContactResult.tooth_gaps`` (mm); None: computed here
        from ``design`` (the same definition).
    roller_offsets_mm : sequence of float, optional
        Extra axial displacement (+z, mm) of each roller in the assembly being verified, not
        known to the analytic side: a perturbation the check must detect.
    """
    t0 = time.perf_counter()
    flank = LOADED_FLANKS[side]
    z, n = design.roller.count, design.thread.engaged_teeth
    settled = _settle(design, side, flank, screw_profile)
    designed = settled.d_nominal if designed_gaps is None else _designed_values(designed_gaps, side, flank, z, n)
    g_nr, g_rs = gap_terms(design)
    load_gap = np.tile(g_rs if side == "screw" else g_nr, z)
    perturb = np.zeros(z) if roller_offsets_mm is None else np.asarray(roller_offsets_mm, dtype=np.float64)
    if perturb.shape != (z,):
        raise ValueError(f"roller_offsets_mm must have one value per roller ({z}), got shape {perturb.shape}")
    notes = _off_flank_notes(side, settled)
    place = _placements(design, settled, perturb)
    t1 = time.perf_counter()
    fcl_run = _fcl_distances(settled, place, tol)
    for i in np.flatnonzero(fcl_run.on_edge):
        notes[i].append(f"FCL's nearest point lies on an edge of the {2 * fcl_run.half:.3g} mm patch")

    b, (_, tha, _, phb) = settled.batch, settled.q.T
    pA, pB = fcl_run.patch_a, fcl_run.patch_b
    e_tr = (transform_error(b.A, b.m_a, tha, place.ref_a, pA.half_angle)
            + transform_error(b.B, b.m_b, phb, place.ref_b, pB.half_angle))
    dist, d_fcl, near = settled.distance, fcl_run.distance, fcl_run.nearest
    fcl_gap = d_fcl - (dist - settled.d_nominal)
    pdiff = np.maximum(np.linalg.norm(near[:, 0] - settled.point_a, axis=1),
                       np.linalg.norm(near[:, 1] - settled.point_b, axis=1))
    comps = [Comparison(side=side, flank=flank, roller=int(settled.roller[i]), tooth=int(settled.tooth[i]),
                        analytic_distance_mm=float(dist[i]), fcl_distance_mm=float(d_fcl[i]),
                        point_difference_mm=float(pdiff[i]), designed_gap_mm=float(designed[i]),
                        fcl_gap_mm=float(fcl_gap[i]), normal_axial_component=float(settled.normal_z[i]),
                        load_model_gap_mm=float(load_gap[i])) for i in range(b.n)]
    patches = {
        "flank": flank,
        "patch_error_mm": max(pA.error, pB.error),
        "patch_triangles": pA.triangles + pB.triangles,
        "patch_half_size_mm": fcl_run.half,
        "axial_separation_mm": float(np.max(np.abs(settled.shift))),
        "settling_nonlinearity_mm": float(np.max(np.abs((dist - settled.d_nominal)
                                                        - settled.normal_z * settled.shift))),
        "transform_error_bound_mm": float(e_tr.max()),
    }
    timings = {"analytic": t1 - t0, "patches": fcl_run.patch_time, "fcl": fcl_run.fcl_time}
    return SideResult(comparisons=comps, notes=["; ".join(nt) for nt in notes], patches=patches, timings=timings)


def comparison_warning(c: Comparison, tolerance: float, note: str = "") -> str:
    """One line naming the comparison (side, roller, tooth), the FCL and designed gaps, their
    difference and the tolerance (um), and the distances behind the FCL gap (mm)."""
    msg = (f"{SIDE_NAMES[c.side]} contact, roller {c.roller}, tooth {c.tooth}: FCL gap "
           f"{c.fcl_gap_mm * 1e3:+.5f} um vs designed gap {c.designed_gap_mm * 1e3:+.5f} um, difference "
           f"{c.gap_difference_mm * 1e3:+.3g} um exceeds the tolerance {tolerance * 1e3:.3g} um "
           f"(FCL distance {c.fcl_distance_mm:.8f} mm, analytic distance {c.analytic_distance_mm:.8f} mm "
           f"at the settled position)")
    return msg + (f" ({note})" if note else "")


def check_comparisons(comps: Sequence[Comparison], tolerance: float,
                      notes: Sequence[str] | None = None) -> list[str]:
    """Warnings for every comparison whose |FCL gap - designed gap| exceeds ``tolerance`` (mm)
    or is not a number."""
    notes = notes or [""] * len(comps)
    return [comparison_warning(c, tolerance, nt) for c, nt in zip(comps, notes)
            if not abs(c.gap_difference_mm) <= tolerance]


def load_model_deviation(comps: Sequence[Comparison]) -> float:
    """Largest |(FCL gap_j - FCL gap_1) / n_z - load-model gap_j| (mm, axial) over the rollers
    and sides: how far the meshed geometry's tooth-to-tooth gaps are from the pitch lists'
    cumulative gaps (the phase effect of a graded warp)."""
    worst = 0.0
    first: dict[tuple[str, int], float] = {}
    for c in comps:
        if c.tooth == 1:
            first[(c.side, c.roller)] = c.fcl_gap_mm
    for c in comps:
        g1 = first.get((c.side, c.roller))
        if g1 is not None:
            worst = max(worst, abs((c.fcl_gap_mm - g1) / c.normal_axial_component - c.load_model_gap_mm))
    return worst


def verify_contacts(design: PRSDesign, tol: float = DEFAULT_TOL_MM,
                    screw_profile: ThreadProfile | None = None,
                    designed_gaps: Mapping[str, Any] | None = None,
                    roller_offsets_mm: Sequence[float] | NDArray | None = None) -> dict[str, Any]:
    """``checks.fcl`` of the report: the FCL gap of every tooth of every roller on both sides
    against the designed gap (module docstring).

    Parameters
    ----------
    design : PRSDesign
        The design (constant pitch or graded).
    tol : float
        Chordal tolerance (mm) of the two flank patches together (1e-5 mm = 0.01 um default).
    screw_profile : ThreadProfile, optional
        The theoretical screw of the contact stage (solved here when not given).
    designed_gaps : mapping, optional
        The designed gaps, ``ContactResult.tooth_gaps`` (mm; needs the loaded flanks: screw
        "upper", nut "lower"); None: computed here with the same definition.
    roller_offsets_mm : sequence of float, optional
        Axial displacement (+z, mm) of each roller in the verified assembly, unknown to the
        designed gaps (for testing that a misplaced roller is detected).

    Returns
    -------
    dict
        ``comparisons`` (2 z n: side "screw" first, then "nut"; roller-major), the verdict
        ``difference_tolerance_mm`` = ``tol`` + the larger transform error bound of the two
        sides, ``warnings`` (every comparison whose |FCL gap - designed gap| exceeds it),
        summary maxima, patch data and timings (s).
    """
    t0 = time.perf_counter()
    if screw_profile is None:
        screw_profile = theoretical_screw(design).profile
    t_screw = time.perf_counter() - t0
    sides = {side: verify_side(design, side, tol, screw_profile, designed_gaps, roller_offsets_mm)
             for side in ("screw", "nut")}
    comps = [c for s in sides.values() for c in s.comparisons]
    notes = [nt for s in sides.values() for nt in s.notes]
    tolerance = tol + max(s.patches["transform_error_bound_mm"] for s in sides.values())
    timings = {k: sum(s.timings[k] for s in sides.values()) for k in ("analytic", "patches", "fcl")}
    timings["analytic"] += t_screw
    return {
        "patch_chord_tolerance_mm": tol,
        "difference_tolerance_mm": tolerance,
        "designed_gaps_source": "computed" if designed_gaps is None else "given",
        "rollers_checked": design.roller.count,
        "teeth_checked": design.thread.engaged_teeth,
        "comparisons": [c.as_dict() for c in comps],
        "max_abs_difference_mm": float(max(abs(c.difference_mm) for c in comps)),
        "max_abs_gap_difference_um": float(max(abs(c.gap_difference_mm) for c in comps)) * 1e3,
        "max_point_difference_mm": float(max(c.point_difference_mm for c in comps)),
        "max_load_model_deviation_um": load_model_deviation(comps) * 1e3,
        "patches": {side: s.patches for side, s in sides.items()},
        "warnings": check_comparisons(comps, tolerance, notes),
        "timings_s": timings,
        "time_s": time.perf_counter() - t0,
    }
