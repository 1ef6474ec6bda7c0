"""Verification of the analytic contact distances with python-fcl (DOMAIN.md section 3).

For each side (screw-roller, roller-nut) a small, fine mesh patch of each flank is built
once around the analytic contact of a reference tooth, in the part's own frame, with its
own chordal tolerance. FCL's BVH of each patch is then *moved with transforms* to every
checked contact (several rollers and teeth): a rotation about the part axis plus an axial
shift taken from the analytic surface at the contact. For a constant-pitch part the moved
patch lies exactly on the surface; for a graded part the error is the change of warp slope
across the patch, ~|c'(m_i) - c'(m_0)| * patch half-length, below 1e-6 mm here and listed as
``transform_error_bound_mm``.

At the checked configuration the roller is shifted axially by a known amount so that every
contact has a clearance (FCL's distance is zero for touching or overlapping meshes). The
FCL distance and nearest points are compared with the analytic Euclidean distance (common
normal, :func:`prs_geom.contact.euclidean_distance`) and its points.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import fcl
import numpy as np
from numpy.typing import NDArray

from .contact import euclidean_distance, solve_collinear, theoretical_screw, tooth_contacts
from .design import PRSDesign

#: Axial clearance (mm) added on top of the largest interference so all checked contacts are open.
VERIFY_CLEARANCE_MM = 0.005
PATCH_HALF_SIZE_MM = 0.35


def _grid_mesh(u: NDArray, v: NDArray, fn) -> tuple[NDArray, NDArray]:
    """Triangulated parameter grid u x v mapped by fn(U, V) -> (n, 3)."""
    U, V = np.meshgrid(u, v, indexing="ij")
    P = fn(U.ravel(), V.ravel())
    nu, nv = len(u), len(v)
    idx = np.arange(nu * nv).reshape(nu, nv)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    F = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return P, F


def flank_patch(part, r_c: float, th_c: float, m: float, xi: float, tol: float,
                half: float = PATCH_HALF_SIZE_MM) -> tuple[NDArray, NDArray, float]:
    """Patch of Z(r, theta) around (r_c, th_c) in the part frame with chordal error <= tol.

    Grid step from the sagitta bound h^2 kappa / 8 <= tol / 2 (kappa a bound of the normal
    curvature); the achieved error is measured at the triangle centroids and returned.
    """
    prof = part.profile
    kappa = 2.0 / prof.inner_radius
    if prof.flank == "arc":
        kappa = max(kappa, 2.0 / (prof.arc_radius - prof.outer_radius))
    h = math.sqrt(4.0 * tol / kappa)
    r_lo = max(prof.inner_radius, r_c - half)
    r_hi = min(prof.outer_radius, r_c + half)
    nr = max(2, int(math.ceil((r_hi - r_lo) / h)) + 1)
    nt = max(2, int(math.ceil(2 * half / (h)) + 1))
    rr = np.linspace(r_lo, r_hi, nr)
    tt = th_c + np.linspace(-half, half, nt) / r_c

    def surf(r, th):
        Z = part.z_derivatives(r, th, np.full_like(r, m), np.full_like(r, xi))[0]
        return np.column_stack([r * np.cos(th), r * np.sin(th), Z])

    V, F = _grid_mesh(rr, tt, surf)
    # measured chordal error: centroid vs surface at the centroid's (r, theta)
    C = V[F].mean(axis=1)
    rc = np.hypot(C[:, 0], C[:, 1])
    tc = th_c + np.arctan2(-C[:, 0] * math.sin(th_c) + C[:, 1] * math.cos(th_c),
                           C[:, 0] * math.cos(th_c) + C[:, 1] * math.sin(th_c))
    Zs = part.z_derivatives(rc, tc, np.full_like(rc, m), np.full_like(rc, xi))[0]
    slope = np.abs(part.z_derivatives(rc, tc, np.full_like(rc, m), np.full_like(rc, xi))[1])
    err = float(np.max(np.abs(C[:, 2] - Zs) / np.sqrt(1 + slope ** 2)))
    return V, F, err


def bvh_model(V: NDArray, F: NDArray) -> fcl.BVHModel:
    """An FCL BVH of a triangle mesh (float64 vertices)."""
    g = fcl.BVHModel()
    g.beginModel(len(V), len(F))
    g.addSubModel(np.ascontiguousarray(V, dtype=np.float64), np.ascontiguousarray(F, dtype=np.int32))
    g.endModel()
    return g


def _rot_z(a: float) -> NDArray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@dataclass
class Comparison:
    side: str
    roller: int
    tooth: int
    analytic_distance_mm: float
    fcl_distance_mm: float
    point_difference_mm: float

    def as_dict(self) -> dict[str, Any]:
        d = dict(self.__dict__)
        d["difference_mm"] = self.fcl_distance_mm - self.analytic_distance_mm
        return d


def verify_side(design: PRSDesign, side: str, tol: float, rollers: NDArray, teeth: NDArray,
                screw_profile=None) -> tuple[list[Comparison], dict[str, float]]:
    """FCL vs analytic distances for one side (upper flank contacts)."""
    batch, q0, info = tooth_contacts(design, side, "upper", rollers, teeth, screw_profile)
    first = solve_collinear(batch, q0)
    shift = VERIFY_CLEARANCE_MM + max(0.0, -float(first.gap.min()))
    batch.z_offset[:] = -batch.xi_b * shift        # opens every gap by `shift`
    sol = solve_collinear(batch, first.q)
    dist, q = euclidean_distance(batch, sol.q)
    pa, pb = batch.points(q)
    # reference patches (contact 0), built once in the part frames
    r0, t0, rho0, ph0 = sol.q[0]
    VA, FA, errA = flank_patch(batch.A, r0, t0, batch.m_a[0], batch.xi_a[0], tol)
    VB, FB, errB = flank_patch(batch.B, rho0, ph0, batch.m_b[0], batch.xi_b[0], tol)
    objA = fcl.CollisionObject(bvh_model(VA, FA), fcl.Transform())
    objB = fcl.CollisionObject(bvh_model(VB, FB), fcl.Transform())
    ZA0 = batch.A.z_derivatives(sol.q[:1, 0], sol.q[:1, 1], batch.m_a[:1], batch.xi_a[:1])[0][0]
    ZB0 = batch.B.z_derivatives(sol.q[:1, 2], sol.q[:1, 3], batch.m_b[:1], batch.xi_b[:1])[0][0]
    out = []
    slope_err = 0.0
    for i in range(batch.n):
        r, th, rho, ph = sol.q[i]
        ZA = batch.A.z_derivatives(np.array([r]), np.array([th]), batch.m_a[i:i + 1], batch.xi_a[i:i + 1])[0][0]
        ZB = batch.B.z_derivatives(np.array([rho]), np.array([ph]), batch.m_b[i:i + 1], batch.xi_b[i:i + 1])[0][0]
        RA = _rot_z(th - t0)
        objA.setTransform(fcl.Transform(RA, [0.0, 0.0, ZA - ZA0]))
        RB = _rot_z(batch.alpha[i]) @ _rot_z(ph - ph0)
        objB.setTransform(fcl.Transform(RB, [batch.ox[i], batch.oy[i], ZB - ZB0 + batch.z_offset[i]]))
        req = fcl.DistanceRequest(enable_nearest_points=True)
        res = fcl.DistanceResult()
        d_fcl = fcl.distance(objA, objB, req, res)
        npts = np.array(res.nearest_points)
        pdiff = max(np.linalg.norm(npts[0] - pa[i]), np.linalg.norm(npts[1] - pb[i]))
        out.append(Comparison(side, int(info["roller"][i]), int(info["tooth"][i]), float(dist[i]),
                              float(d_fcl), float(pdiff)))
        for part, m_arr, th_i, th_ref in ((batch.A, batch.m_a, th, t0), (batch.B, batch.m_b, ph, ph0)):
            k = part.profile.lead / (2 * math.pi)
            s_i = part.warp.correction_slope(np.array([m_arr[i] + k * th_i]))[0]
            s_0 = part.warp.correction_slope(np.array([m_arr[0] + k * th_ref]))[0]
            slope_err = max(slope_err, abs(s_i - s_0) * k * PATCH_HALF_SIZE_MM / part.profile.inner_radius)
    meta = {"patch_error_mm": max(errA, errB), "patch_triangles": int(len(FA) + len(FB)),
            "axial_separation_mm": shift, "transform_error_bound_mm": slope_err}
    return out, meta


def verify_contacts(design: PRSDesign, tol: float = 0.001) -> dict[str, Any]:
    """``checks.fcl`` of the report: FCL vs analytic on both sides, corrected screw."""
    t0 = time.perf_counter()
    z, n = design.roller.count, design.thread.engaged_teeth
    rollers = np.unique([0, z // 3, (2 * z) // 3])
    teeth = np.unique([1, (n + 1) // 2, n])
    theo = theoretical_screw(design)
    comps, meta = [], {}
    for side in ("screw", "nut"):
        c, m = verify_side(design, side, tol, rollers, teeth, theo.profile)
        comps += c
        meta[side] = m
    diffs = [abs(c.fcl_distance_mm - c.analytic_distance_mm) for c in comps]
    return {
        "patch_chord_tolerance_mm": tol,
        "comparisons": [c.as_dict() for c in comps],
        "max_abs_difference_mm": float(max(diffs)),
        "max_point_difference_mm": float(max(c.point_difference_mm for c in comps)),
        "patches": meta,
        "time_s": time.perf_counter() - t0,
    }
